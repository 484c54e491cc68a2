//! The march's cost per medium sample, and what f32 lanes change: one thread, the rays of a square pinhole
//! image through a fire, each configuration timed in interleaved rounds (fastest and median reported, as the
//! machine's speed drifts), and the f32 image compared with the f64 one pixel by pixel.
//!
//!     cargo run --release -p firemedium-plugin --example march_cost -- [DATASET.vdb] [PIXELS] [ROUNDS] [CONFIGURATION SUBSTRING] [BRICK] [LATTICES]
//!
//! Default: the committed campfire (scenes/campfire/campfire.vdb), 96 pixels, 5 rounds. LATTICES is a comma list
//! of the volume's `lattice` values (auto, dense, bricks, off), each configuration run with each, interleaved;
//! its f32 rows are compared with the f64 row of the same lattice. Results are in docs/results/log.md.

use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{evaluations_on_this_thread, FireVolume};
use std::time::Instant;

mod common;

/// Luminance of every pixel, seconds, evaluations.
fn render(v: &FireVolume, size: usize) -> (Vec<f64>, f64, u64) {
    let xyz = v.channel_xyz();
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    let mut img = Vec::with_capacity(size * size);
    let e0 = evaluations_on_this_thread();
    let start = Instant::now();
    for ray in common::pinhole_rays(v, size) {
        v.integrate(&ray, &mut l, &mut t);
        img.push((0..c).map(|k| l[k] * xyz[k].y).sum());
    }
    (
        img,
        start.elapsed().as_secs_f64(),
        evaluations_on_this_thread() - e0,
    )
}

fn main() {
    let (args, file) = common::args_and_dataset();
    let size: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(96);
    let rounds: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let only = args.get(3).cloned().unwrap_or_default();
    let configs: Vec<_> = [
        ("spectral f64", "spectral", "f64", 30),
        ("spectral f32", "spectral", "f32", 30),
        ("rgb f64", "rgb", "f64", 3),
        ("rgb f32", "rgb", "f32", 3),
        ("spectral16 f64", "spectral", "f64", 16),
        ("spectral16 f32", "spectral", "f32", 16),
        ("spectral24 f32", "spectral", "f32", 24),
    ]
    .into_iter()
    .filter(|c| c.0.contains(only.as_str()))
    .collect();
    let lattices: Vec<String> = args
        .get(5)
        .map_or("auto", String::as_str)
        .split(',')
        .map(str::to_string)
        .collect();
    // Every configuration with every lattice, f64 and f32 rows of one configuration side by side.
    let configs: Vec<(String, &str, &str, i64, &str)> = configs
        .iter()
        .flat_map(|c| lattices.iter().map(move |l| (c, l)))
        .map(|((name, mode, precision, bins), l)| {
            (
                format!("{name}, lattice {l}"),
                *mode,
                *precision,
                *bins,
                l.as_str(),
            )
        })
        .collect();
    let volumes: Vec<FireVolume> = configs
        .iter()
        .map(|(_, mode, precision, bins, lattice)| {
            let mut list = vec![
                Param::string("filename", &file),
                Param::string("colormode", mode),
                Param::string("precision", precision),
                Param::int("bins", *bins),
                Param::string("lattice", lattice),
            ];
            if let Some(b) = args.get(4).and_then(|s| s.parse().ok()) {
                list.push(Param::int("brick", b));
            }
            FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"))
        })
        .collect();
    let mut times = vec![Vec::new(); configs.len()];
    let mut images = vec![Vec::new(); configs.len()];
    let mut evals = vec![0; configs.len()];
    for _ in 0..rounds {
        for (k, v) in volumes.iter().enumerate() {
            let (img, s, n) = render(v, size);
            times[k].push(s);
            images[k] = img;
            evals[k] = n;
        }
    }
    println!("{file}, {size}² rays, one thread, {rounds} rounds");
    println!("| configuration | fastest s | median s | samples | ns per sample (fastest) | vs f64: max rel. diff | rel. RMS diff |");
    println!("|---|---|---|---|---|---|---|");
    let n_lat = lattices.len();
    for (k, (name, ..)) in configs.iter().enumerate() {
        let mut ts = times[k].clone();
        ts.sort_by(f64::total_cmp);
        // (The f64 row of the same configuration pair and lattice.)
        let reference = &images[((k / n_lat) & !1) * n_lat + k % n_lat];
        let peak = reference.iter().fold(0f64, |m, &x| m.max(x));
        let (mut worst, mut sq, mut n) = (0f64, 0.0, 0usize);
        for (a, b) in images[k].iter().zip(reference) {
            // Pixels above 1e-3 of the peak (relative differences of black pixels say nothing).
            if *b > 1e-3 * peak {
                worst = worst.max((a - b).abs() / b);
                sq += ((a - b) / b).powi(2);
                n += 1;
            }
        }
        println!(
            "| {name} | {:.3} | {:.3} | {} | {:.1} | {:.2e} | {:.2e} |",
            ts[0],
            ts[ts.len() / 2],
            evals[k],
            ts[0] / evals[k].max(1) as f64 * 1e9,
            worst,
            (sq / n.max(1) as f64).sqrt()
        );
    }
}
