//! What the examples share: the benchmarks' pinhole camera (as `firemedium bench perf`'s).

use firemedium_plugin::volume::{FireVolume, Ray};
use glam::DVec3;

/// The rays of a `size`² pinhole image 2.2 fire-sizes in front of `v` (−y), looking at its centre with a 30°
/// field of view, row by row from the top.
pub fn pinhole_rays(v: &FireVolume, size: usize) -> impl Iterator<Item = Ray> {
    let [b0, b1] = v.bounds();
    let eye = 0.5 * (b0 + b1) - DVec3::Y * (2.2 * (b1 - b0).max_element());
    let half = 15f64.to_radians().tan();
    (0..size * size).map(move |p| {
        let (i, j) = (p % size, p / size);
        let u = ((i as f64 + 0.5) / size as f64 * 2.0 - 1.0) * half;
        let w = (1.0 - (j as f64 + 0.5) / size as f64 * 2.0) * half;
        Ray {
            o: eye,
            d: DVec3::new(u, 1.0, w).normalize(),
            t0: 0.0,
            t1: f64::INFINITY,
            seed: p as u64,
            first: None,
        }
    })
}

/// The command line's arguments and its first, the dataset (default: the committed campfire).
pub fn args_and_dataset() -> (Vec<String>, String) {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let file = args.first().cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../scenes/campfire/campfire.vdb"
        )
        .to_string()
    });
    (args, file)
}
