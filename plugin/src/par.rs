//! The plugin's parallel build work under one thread budget. A volume's build runs inside
//! [`with_budget`] with its `threads` parameter (a host passes its own thread count, as `firemedium render
//! --threads` does; 0 means every core), and every fan-out of the build asks [`threads`] how many threads it may
//! use. Results never depend on the count: each fan-out splits independent work (table rows, z-slabs, grids,
//! file parts) and joins it in order.

use std::cell::Cell;

thread_local! {
    /// The budget of the build running on this thread (0: every core).
    static BUDGET: Cell<usize> = const { Cell::new(0) };
}

/// Runs `f` (a build) on this thread with at most `threads` threads for its fan-outs (0: every core).
pub(crate) fn with_budget<R>(threads: usize, f: impl FnOnce() -> R) -> R {
    let before = BUDGET.with(|b| b.replace(threads));
    let r = f();
    BUDGET.with(|b| b.set(before));
    r
}

/// How many threads a fan-out may use: the budget (or every core), at most `cap`, at least 1.
pub(crate) fn threads(cap: usize) -> usize {
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
