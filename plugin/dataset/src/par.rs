//! The plugin's parallel build work under one thread budget, on the host's threads when it lends them. A
//! volume's build runs inside [`with_budget`] with its `threads` parameter (a host passes its own thread count, as
//! `firemedium render --threads` does; 0 means every core), and every fan-out of the build asks [`threads`] how
//! many parts to cut and runs them in a [`scope`]. Results never depend on the count: each fan-out splits
//! independent work (table rows, z-slabs, grids, file parts) and joins it in order.
//!
//! A host with a thread pool of its own (TBB, Dr.Jit, rayon) lends it through the ABI's `FmCreateInfo`: inside
//! [`with_pool`] a scope's parts run as the pool's tasks instead of threads the plugin starts, so a build does
//! not oversubscribe the host's cores.

use std::cell::{Cell, RefCell};
use std::panic::{catch_unwind, resume_unwind, AssertUnwindSafe};
use std::sync::{Arc, Mutex};

/// A host's thread pool: `pool(n, task)` runs `task(i)` for every i in 0..n on its threads, as it likes, and
/// returns when every one has returned.
pub type Pool = Arc<dyn Fn(usize, &(dyn Fn(usize) + Sync)) + Send + Sync>;

thread_local! {
    /// The budget of the build running on this thread (0: every core).
    static BUDGET: Cell<usize> = const { Cell::new(0) };
    /// The host's pool the build running on this thread may use.
    static POOL: RefCell<Option<Pool>> = const { RefCell::new(None) };
}

/// Runs `f` (a build) on this thread with at most `threads` threads for its fan-outs (0: every core).
pub fn with_budget<R>(threads: usize, f: impl FnOnce() -> R) -> R {
    let before = BUDGET.with(|b| b.replace(threads));
    let r = f();
    BUDGET.with(|b| b.set(before));
    r
}

/// Runs `f` (a build) on this thread with `pool` running its fan-outs (`None`: threads of the plugin's own).
pub fn with_pool<R>(pool: Option<Pool>, f: impl FnOnce() -> R) -> R {
    let before = POOL.with(|p| p.replace(pool));
    let r = f();
    POOL.with(|p| *p.borrow_mut() = before);
    r
}

/// A job of a [`scope`], boxed; it borrows from outside the scope ('env).
type Job<'env> = Box<dyn FnOnce() + Send + 'env>;

/// A fan-out's parts, as [`std::thread::Scope`] has them: [`spawn`](Scope::spawn) each, and every part has run
/// when [`scope`] returns (or when a handle is joined). The parts run together when the first handle is joined
/// or the scope ends — on the host's pool inside [`with_pool`], else one thread each.
pub struct Scope<'env> {
    jobs: Mutex<Vec<Job<'env>>>,
    /// The payload of a part that panicked and whose handle nobody joined: re-raised when the scope ends.
    panicked: Arc<Mutex<Option<Payload>>>,
}

/// A panic's payload.
type Payload = Box<dyn std::any::Any + Send>;

/// What a handle needs of its scope.
trait Parts {
    /// Runs every part added so far.
    fn flush(&self);
    /// Keeps the payload of an unjoined part's panic for the scope's end.
    fn keep(&self, payload: Payload);
}

impl Parts for Scope<'_> {
    fn flush(&self) {
        Scope::flush(self)
    }
    fn keep(&self, payload: Payload) {
        *self.panicked.lock().unwrap_or_else(|e| e.into_inner()) = Some(payload);
    }
}

/// A part's result, as [`std::thread::ScopedJoinHandle`].
pub struct Handle<'scope, R> {
    slot: Arc<Mutex<Option<std::thread::Result<R>>>>,
    scope: &'scope dyn Parts,
}

impl std::fmt::Debug for Scope<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Scope").finish_non_exhaustive()
    }
}

impl<R> std::fmt::Debug for Handle<'_, R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Handle").finish_non_exhaustive()
    }
}

impl<'env> Scope<'env> {
    /// Adds a part (which may borrow from outside the scope).
    pub fn spawn<R: Send + 'env>(&self, f: impl FnOnce() -> R + Send + 'env) -> Handle<'_, R> {
        let slot = Arc::new(Mutex::new(None));
        let out = slot.clone();
        let (budget, pool) = (BUDGET.with(Cell::get), POOL.with(|p| p.borrow().clone()));
        let panicked = Arc::clone(&self.panicked);
        self.lock_jobs().push(Box::new(move || {
            // The part's own nested fan-outs keep the build's budget and pool, on whichever thread it runs.
            let r = catch_unwind(AssertUnwindSafe(|| {
                with_budget(budget, || with_pool(pool, f))
            }));
            match r {
                // Nobody holds the handle (dropped unjoined, on the thread now waiting for this part): the
                // scope re-raises the panic when it ends.
                Err(payload) if Arc::strong_count(&out) == 1 => {
                    *panicked.lock().unwrap_or_else(|e| e.into_inner()) = Some(payload)
                }
                r => *out.lock().unwrap_or_else(|e| e.into_inner()) = Some(r),
            }
        }));
        Handle { slot, scope: self }
    }

    fn lock_jobs(&self) -> std::sync::MutexGuard<'_, Vec<Job<'env>>> {
        self.jobs.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Runs every part added so far, all at once, and returns when they have run.
    fn flush(&self) {
        let jobs = std::mem::take(&mut *self.lock_jobs());
        if jobs.is_empty() {
            return;
        }
        match POOL.with(|p| p.borrow().clone()) {
            Some(pool) => {
                let slots: Vec<Mutex<Option<Job<'env>>>> =
                    jobs.into_iter().map(|j| Mutex::new(Some(j))).collect();
                let take = |i: usize| {
                    slots
                        .get(i)
                        .and_then(|s| s.lock().unwrap_or_else(|e| e.into_inner()).take())
                };
                // (A part catches its own panic; the pool's tasks never unwind into the host.)
                pool(slots.len(), &|i| {
                    if let Some(job) = take(i) {
                        job()
                    }
                });
                // A pool that skipped a task leaves it here: it runs on this thread, never lost.
                for i in 0..slots.len() {
                    if let Some(job) = take(i) {
                        job()
                    }
                }
            }
            None => std::thread::scope(|s| {
                for job in jobs {
                    s.spawn(job);
                }
            }),
        }
    }
}

impl<R> Handle<'_, R> {
    /// The part's result, once it has run (`Err` with its panic's payload if it panicked).
    pub fn join(self) -> std::thread::Result<R> {
        let taken = || self.slot.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(r) = taken() {
            return r;
        }
        self.scope.flush();
        taken().unwrap_or_else(|| Err(Box::new("a part of the build did not run")))
    }
}

impl<R> Drop for Handle<'_, R> {
    fn drop(&mut self) {
        // An unjoined part that panicked: its payload goes to the scope, which re-raises it at its end.
        let r = self.slot.lock().unwrap_or_else(|e| e.into_inner()).take();
        if let Some(Err(payload)) = r {
            self.scope.keep(payload);
        }
    }
}

/// Runs `f` with a [`Scope`] for its parts, and every part before it returns — the plugin's
/// [`std::thread::scope`]. A part that panicked and was not joined panics here.
pub fn scope<'env, R>(f: impl for<'s> FnOnce(&'s Scope<'env>) -> R) -> R {
    let s = Scope {
        jobs: Mutex::new(Vec::new()),
        panicked: Arc::new(Mutex::new(None)),
    };
    let r = f(&s);
    s.flush();
    if let Some(payload) = s.panicked.lock().unwrap_or_else(|e| e.into_inner()).take() {
        resume_unwind(payload);
    }
    r
}

/// How many threads a fan-out may use: the budget (or every core), at most `cap`, at least 1.
pub fn threads(cap: usize) -> usize {
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    match BUDGET.with(Cell::get) {
        0 => cores,
        n => n,
    }
    .clamp(1, cap.max(1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scope_runs_its_parts_on_the_hosts_pool_or_its_own_threads() {
        // Both ways give the same results in order; on a pool every part is the pool's task, and a pool that
        // skips tasks loses none (they run on the caller's thread).
        let data: Vec<u64> = (0..1000).collect();
        let sums = || {
            scope(|s| {
                let hs: Vec<_> = data
                    .chunks(100)
                    .map(|c| s.spawn(move || c.iter().sum::<u64>()))
                    .collect();
                hs.into_iter()
                    .map(|h| h.join().unwrap())
                    .collect::<Vec<_>>()
            })
        };
        let own = sums();
        let ran = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let counter = ran.clone();
        let pool: Pool = Arc::new(move |n, task| {
            std::thread::scope(|s| {
                for i in 0..n {
                    let counter = &counter;
                    s.spawn(move || {
                        counter.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        task(i)
                    });
                }
            })
        });
        assert_eq!(with_pool(Some(pool), sums), own);
        assert_eq!(ran.load(std::sync::atomic::Ordering::Relaxed), 10);
        let lazy: Pool = Arc::new(|n, task| (0..n).step_by(2).for_each(task));
        assert_eq!(with_pool(Some(lazy), sums), own);
        // Nested fan-outs inside a part keep the pool.
        let nested = Arc::new(std::sync::atomic::AtomicUsize::new(0));
        let count = nested.clone();
        let pool: Pool = Arc::new(move |n, task| {
            count.fetch_add(n, std::sync::atomic::Ordering::Relaxed);
            (0..n).for_each(task)
        });
        with_pool(Some(pool), || {
            scope(|s| {
                s.spawn(|| scope(|t| t.spawn(|| 1).join().unwrap()));
            })
        });
        assert_eq!(nested.load(std::sync::atomic::Ordering::Relaxed), 2);
    }

    #[test]
    fn a_part_that_panics_panics_its_join_or_its_scope() {
        let joined = scope(|s| s.spawn(|| panic!("joined")).join());
        assert!(joined.is_err());
        let unjoined = catch_unwind(|| {
            scope(|s| {
                s.spawn(|| panic!("unjoined"));
            })
        });
        let msg = unjoined.unwrap_err();
        assert_eq!(msg.downcast_ref::<&str>(), Some(&"unjoined"));
    }

    #[test]
    fn the_budget_bounds_every_fan_out_and_is_restored() {
        let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
        assert_eq!(threads(usize::MAX), cores);
        with_budget(1, || {
            assert_eq!(threads(8), 1);
            with_budget(3, || assert_eq!(threads(2), 2));
            assert_eq!(threads(8), 1);
        });
        assert_eq!(threads(4), cores.min(4));
    }
}
