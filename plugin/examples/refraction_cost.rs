//! The cost of refraction: rays/s of the fire volume's integration along straight rays and along curved ones
//! (physical index, and ×100), one thread, the Mantaflow fire at one voxel per march step.
//!
//!     cargo run --release -p firemedium-plugin --example refraction_cost
//!
//! Results are in docs/RESULTS.md.

use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{FireVolume, Ray};
use glam::DVec3;
fn main() {
    let f = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/valid/vdb/mantaflow_fire_f060.vdb"
    );
    for (name, extra) in [
        ("off", vec![]),
        ("on", vec![Param::bool("refraction", true)]),
        (
            "on x100",
            vec![
                Param::bool("refraction", true),
                Param::float("refractionscale", 100.0),
            ],
        ),
    ] {
        let mut list = vec![
            Param::string("filename", f),
            Param::float("temperaturescale", 1000.0),
            Param::float("sootscale", 3e-7),
            Param::float("stepsize", 1.0),
        ];
        list.extend(extra);
        let v = FireVolume::new(&list).unwrap();
        let c = v.channels();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let n = 4000;
        let start = std::time::Instant::now();
        let mut sum = 0.0;
        let mut bend = 0.0f64;
        for i in 0..n {
            let fx = (i % 64) as f64 / 64.0;
            let fz = (i / 64) as f64 / (n / 64) as f64;
            let ray = Ray {
                o: DVec3::new(0.2 + 1.6 * fx, -1.0, 0.1 + 2.8 * fz),
                d: DVec3::Y,
                t0: 0.0,
                t1: 5.0,
                seed: i as u64,
            };
            let (_, d, _) = v.integrate_exit(&ray, &mut l, &mut t);
            sum += l[15];
            bend = bend.max(d.dot(DVec3::Y).clamp(-1.0, 1.0).acos());
        }
        let s = start.elapsed().as_secs_f64();
        println!(
            "{name}: {:.0} rays/s, mean L[15] {:.6e}, max deflection {:.3e} rad",
            n as f64 / s,
            sum / n as f64,
            bend
        );
    }
}
