//! Per-call overhead of the ABI: the same camera rays through the cdylib one per call and in batches of 16 and
//! 256, through the fire and missing it (the call's own cost), three rounds.
//!
//!     cargo run --release -p firemedium-loader --example abi_overhead -- target/release/libfiremedium_plugin.so FIRE.vdb
//!
//! FIRE.vdb: `firemedium gen campfire --resolution 256` (the bench's box is assumed for the camera). Results in
//! docs/results/log.md.
use firemedium_loader::{Param, Plugin, Ray};
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 3 {
        eprintln!("usage: abi_overhead PLUGIN FIRE.vdb");
        std::process::exit(2);
    }
    // SAFETY: the plugin named on the command line is this project's cdylib; its ABI version is checked by
    // `load`.
    let plugin = unsafe { Plugin::load(&a[1]) }.unwrap();
    let v = plugin
        .create_volume(&[
            Param::string("filename", &a[2]),
            Param::float("stepsize", 0.5),
        ])
        .unwrap();
    let c = v.info().channels as usize;
    let size = 256usize;
    // A pinhole at the bench's place for the 256³ campfire box.
    let (b0, b1) = ([-0.6, -0.56875, 0.03125], [0.6, 0.6, 1.6]);
    let cen = [0.0, 0.5 * (b0[1] + b1[1]), 0.5 * (b0[2] + b1[2])];
    let eye = [cen[0], cen[1] - 2.2 * 1.56875, cen[2]];
    let half = 15f64.to_radians().tan();
    let rays: Vec<Ray> = (0..size * size)
        .map(|p| {
            let (i, j) = (p % size, p / size);
            let u = (1.0 - (i as f64 + 0.5) / size as f64 * 2.0) * half;
            let w = (1.0 - (j as f64 + 0.5) / size as f64 * 2.0) * half;
            Ray {
                origin: eye,
                direction: [u, 1.0, w],
                tmin: 0.0,
                tmax: 1e30,
                seed: p as u64,
            }
        })
        .collect();
    // Rays that miss the box too (the call's own cost): a second set pointing away.
    let away: Vec<Ray> = rays
        .iter()
        .map(|r| Ray {
            direction: [r.direction[0], -1.0, r.direction[2]],
            ..*r
        })
        .collect();
    for round in 0..3 {
        for (name, set) in [("through the fire", &rays), ("missing it", &away)] {
            for batch in [1usize, 16, 256] {
                let mut l = vec![0f32; batch * c];
                let mut t = vec![0f32; batch * c];
                let start = Instant::now();
                for chunk in set.chunks(batch) {
                    let n = chunk.len();
                    v.integrate(chunk, &mut l[..n * c], Some(&mut t[..n * c]), None)
                        .unwrap();
                }
                let s = start.elapsed().as_secs_f64();
                println!(
                    "round {round} {name}: batch {batch}: {:.1} ns per ray",
                    s / set.len() as f64 * 1e9
                );
            }
        }
    }
}
