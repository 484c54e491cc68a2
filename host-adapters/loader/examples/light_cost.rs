//! What a fire-light sample costs inside the plugin, call by call through the ABI: `light_sample` (a point),
//! `light_pdf_direction` (its direction's density) and `light_integrate` (the fire's emission along it),
//! one entry per call as a renderer makes them, one thread, for each light configuration in interleaved rounds
//! (the machine's speed drifts between rounds; compare the rows of one round).
//!
//!     cargo run --release -p firemedium-loader --example light_cost -- PLUGIN FIRE.vdb [CONFIG ...]
//!
//! FIRE.vdb: the room's fire of `firemedium bench fire-light` (e.g. `firemedium gen campfire --resolution 256`).
//! A CONFIG is `name=value,name=value` of light parameters (`lineblock=1,linechannels=4096`; a value with a
//! point is a float, `linestep=16.0`); none: the default. `LC_N` sets the calls per round (default 20 000; more
//! for a profiler, whose samples then fall mostly outside the light's build).
//! The rays start on the room's floor and back wall and aim at points the light samples. Results in
//! docs/results/log.md.
use firemedium_loader::{Param, Plugin, Ray};
use std::time::Instant;

/// xorshift64: uniform numbers in [0, 1), the same sequence every run.
struct Rng(u64);

impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    if a.len() < 3 {
        eprintln!("usage: light_cost PLUGIN FIRE.vdb [name=value,... ...]");
        std::process::exit(2);
    }
    // SAFETY: the plugin named on the command line is this project's cdylib; its ABI version is checked by
    // `load`.
    let plugin = unsafe { Plugin::load(&a[1]) }.unwrap_or_else(|e| panic!("{e}"));
    let v = plugin
        .create_volume(&[
            Param::string("dataset", &a[2]),
            Param::string("fuel", "propane"),
            Param::float("stepsize", 1.0),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
    let c = v.info().channels as usize;
    let configs: Vec<String> = if a.len() > 3 {
        a[3..].to_vec()
    } else {
        vec![String::new()]
    };
    let lights: Vec<_> = configs
        .iter()
        .map(|cfg| {
            let list: Vec<Param> = cfg
                .split(',')
                .filter(|s| !s.is_empty())
                .map(|kv| {
                    let (k, val) = kv.split_once('=').expect("name=value");
                    match val.parse::<i64>() {
                        Ok(i) => Param::int(k, i),
                        Err(_) => Param::float(k, val.parse().expect("a number")),
                    }
                })
                .collect();
            let l = v.create_light_with(&list).unwrap_or_else(|e| panic!("{e}"));
            let channels = l.line_channels().unwrap_or_else(|e| panic!("{e}"));
            println!(
                "{cfg:?}: line through blocks of {} voxels in {channels} of {c} channels",
                l.info().line_block
            );
            l
        })
        .collect();
    let n: usize = std::env::var("LC_N")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(20_000);
    let mut rng = Rng(0x1234_5678_9abc_def0);
    for round in 0..5 {
        for (cfg, light) in configs.iter().zip(&lights) {
            let us: Vec<[f64; 6]> = (0..n).map(|_| [(); 6].map(|_| rng.next())).collect();
            let (mut pts, mut pdf) = (vec![[0.0; 3]; n], vec![0.0; n]);
            let start = Instant::now();
            for k in 0..n {
                light
                    .sample_at(
                        &us[k..k + 1],
                        None,
                        &mut pts[k..k + 1],
                        &mut pdf[k..k + 1],
                        None,
                    )
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            let ts = start.elapsed().as_secs_f64() / n as f64;
            // Origins: two thirds on the floor around the fire's box, a third on the back wall.
            let origins: Vec<[f64; 3]> = (0..n)
                .map(|k| {
                    if k % 3 == 2 {
                        [-5.0 + 10.0 * rng.next(), 2.5, 4.0 * rng.next()]
                    } else {
                        loop {
                            let p = [-3.0 + 6.0 * rng.next(), -4.0 + 6.5 * rng.next(), 0.0];
                            if p[0].abs() > 0.6 || p[1].abs() > 0.6 {
                                break p;
                            }
                        }
                    }
                })
                .collect();
            let dirs: Vec<[f64; 3]> = (0..n)
                .map(|k| [0, 1, 2].map(|i| pts[k][i] - origins[k][i]))
                .collect();
            let mut pd = [0.0];
            let start = Instant::now();
            for k in 0..n {
                light
                    .pdf_direction_at(&origins[k..k + 1], &dirs[k..k + 1], None, &mut pd)
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            let tp = start.elapsed().as_secs_f64() / n as f64;
            let rays: Vec<Ray> = (0..n)
                .map(|k| Ray {
                    origin: origins[k],
                    direction: dirs[k],
                    tmin: 0.0,
                    tmax: 1e30,
                    seed: k as u64,
                })
                .collect();
            let (mut l, mut t) = (vec![0f32; c], vec![0f32; c]);
            let start = Instant::now();
            for r in &rays {
                light
                    .integrate_at(std::slice::from_ref(r), None, &mut l, Some(&mut t))
                    .unwrap_or_else(|e| panic!("{e}"));
            }
            let ti = start.elapsed().as_secs_f64() / n as f64;
            println!(
                "round {round} {cfg:?}: sample {:.0} ns, direction's density {:.0} ns, line {:.0} ns",
                ts * 1e9,
                tp * 1e9,
                ti * 1e9
            );
        }
    }
}
