//! The cost of refraction: rays/s of the fire volume's integration along straight rays and along curved ones
//! (physical index, and ×100), one thread, the Mantaflow fire at one voxel per march step.
//!
//!     cargo run --release -p firemedium-plugin --example refraction_cost
//!
//! Results are in docs/results/log.md.

use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{FireVolume, Ray};
use glam::DVec3;
fn main() {
    let f = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../tests/data/valid/vdb/mantaflow_fire_f060.vdb"
    );
    let mut rows: Vec<(String, Vec<f64>, f64, f64)> = Vec::new();
    let mut exits: Vec<Vec<DVec3>> = Vec::new();
    for round in 0..5 {
        for (k, (name, extra)) in [
            ("off", vec![]),
            ("on", vec![Param::bool("refraction", true)]),
            (
                "on x100",
                vec![
                    Param::bool("refraction", true),
                    Param::float("refractionscale", 100.0),
                ],
            ),
            (
                "on rk4",
                vec![
                    Param::bool("refraction", true),
                    Param::string("refractionintegrator", "rk4"),
                ],
            ),
            (
                "on x100 rk4",
                vec![
                    Param::bool("refraction", true),
                    Param::float("refractionscale", 100.0),
                    Param::string("refractionintegrator", "rk4"),
                ],
            ),
        ]
        .into_iter()
        .enumerate()
        {
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
            let mut dirs = Vec::with_capacity(n);
            for i in 0..n {
                let fx = (i % 64) as f64 / 64.0;
                let fz = (i / 64) as f64 / (n / 64) as f64;
                let ray = Ray {
                    o: DVec3::new(0.2 + 1.6 * fx, -1.0, 0.1 + 2.8 * fz),
                    d: DVec3::Y,
                    t0: 0.0,
                    t1: 5.0,
                    seed: i as u64,
                    first: None,
                };
                let (_, d, _) = v.integrate_exit(&ray, &mut l, &mut t);
                sum += l[15];
                bend = bend.max(d.dot(DVec3::Y).clamp(-1.0, 1.0).acos());
                dirs.push(d);
            }
            let s = start.elapsed().as_secs_f64();
            if round == 0 {
                rows.push((name.to_string(), Vec::new(), sum / n as f64, bend));
                exits.push(dirs);
            }
            rows[k].1.push(n as f64 / s);
        }
    }
    // Five interleaved rounds; the best and median rate of each (the machine's speed drifts; the best is the least disturbed).
    // Exit directions of the Verlet march against the RK4 reference (rows 1, 2 vs 3, 4).
    for (a, b) in [(1, 3), (2, 4)] {
        let (mut e2, mut d2, mut emax) = (0.0, 0.0, 0.0f64);
        for (u, w) in exits[a].iter().zip(&exits[b]) {
            let e = u.dot(*w).clamp(-1.0, 1.0).acos();
            let d = w.dot(DVec3::Y).clamp(-1.0, 1.0).acos();
            e2 += e * e;
            d2 += d * d;
            emax = emax.max(e);
        }
        println!(
            "{} vs {}: direction error rms {:.3e} rad, max {emax:.3e} rad; rms deflection {:.3e} rad",
            rows[a].0,
            rows[b].0,
            (e2 / exits[a].len() as f64).sqrt(),
            (d2 / exits[a].len() as f64).sqrt()
        );
    }
    for (name, mut rates, mean, bend) in rows {
        rates.sort_by(f64::total_cmp);
        println!(
            "{name}: best {:.0} rays/s, median {:.0}, mean L[15] {mean:.6e}, max deflection {bend:.3e} rad",
            rates[rates.len() - 1],
            rates[rates.len() / 2]
        );
    }
}
