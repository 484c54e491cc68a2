//! What the fire light's build holds beyond what it keeps, counted by this process's allocator (its own test
//! binary: one test, so no other thread allocates meanwhile).
//!
//! The build weighs every voxel and makes coarse copies of the fire for its line estimate. Its transient memory
//! once held a weight per voxel of the whole fire and, per worker, three f64 sums per block of each coarse copy
//! (on a 256-voxel production fire 26 MB and 55 MB beside a 37 MB fire): a renderer's peak memory is its
//! largest moment, so the build must hold a few layers of weights and each copy's own floats, no more.

use firemedium_plugin::light::{FireLight, Weighting};
use firemedium_plugin::params::Param;
use firemedium_plugin::volume::FireVolume;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::sync::Arc;

struct Counting;

static NOW: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is forwarded to the system allocator unchanged; the counters only observe sizes.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        // SAFETY: the caller's contract for `alloc` is the system allocator's.
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = NOW.fetch_add(layout.size(), Relaxed) + layout.size();
            PEAK.fetch_max(now, Relaxed);
        }
        p
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: `ptr` came from `alloc` above with this layout.
        unsafe { System.dealloc(ptr, layout) };
        NOW.fetch_sub(layout.size(), Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// A trilinear Gaussian ball of soot at 1000–1700 K in an n³ grid over [−1, 1]³.
fn ball(n: usize) -> FireVolume {
    let (mut d, mut t) = (Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                let w = (-(c(i).powi(2) + c(j).powi(2) + c(k).powi(2)) / 0.3).exp();
                d.push(2e-6 * w);
                t.push(1000.0 + 700.0 * w);
            }
        }
    }
    FireVolume::new(&[
        Param::floats("density", &d),
        Param::floats("temperature", &t),
        Param::int("nx", n as i64),
        Param::int("ny", n as i64),
        Param::int("nz", n as i64),
        Param::point3("p0", [-1.0; 3]),
        Param::point3("p1", [1.0; 3]),
    ])
    .expect("a ball of soot")
}

#[test]
fn the_lights_build_holds_a_few_layers_of_weights_not_the_fires() {
    let n = 128;
    let vol = Arc::new(ball(n));
    let before = NOW.load(Relaxed);
    PEAK.store(before, Relaxed);
    let light = FireLight::new(vol.clone(), Weighting::Power).expect("the ball's light");
    let (peak, kept) = (PEAK.load(Relaxed), NOW.load(Relaxed));
    let transient = peak - kept;
    // A weight per voxel of the fire: what the build once held whole (and the coarse copies' sums more).
    let weights = n * n * n * 4;
    eprintln!(
        "light kept {:.2} MB ({} reported), its build's transient {:.2} MB, the fire's weights {:.2} MB",
        (kept - before) as f64 / 1e6,
        light.bytes(),
        transient as f64 / 1e6,
        weights as f64 / 1e6
    );
    assert!(
        light.voxels() > n * n * n / 4,
        "the ball emits through most of its grid"
    );
    // What it holds now: three layers of weights (0.8 MB here), and the finest coarse copy's two f32 grids
    // (64³: 2.1 MB) while they become its dataset — 3.0 MB measured. Whole weights alone were 8.4 MB.
    assert!(
        transient < weights / 2,
        "the light's build held {transient} bytes beyond what it keeps; the fire's weights are {weights}"
    );
}
