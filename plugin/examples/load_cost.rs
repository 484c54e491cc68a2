//! What loading a fire costs, stage by stage: the volume built `ROUNDS` times from one file (spectral, f32
//! march, as `bench perf` loads it), the fastest build and each table's time in that build.
//!
//!     cargo run --release -p firemedium-plugin --example load_cost -- DATASET.vdb [ROUNDS] [COLORMODE]

use firemedium_plugin::params::Param;
use firemedium_plugin::volume::FireVolume;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(file) = args.first() else {
        eprintln!("usage: load_cost DATASET [ROUNDS] [COLORMODE]");
        std::process::exit(2);
    };
    let rounds: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(10);
    let mode = args.get(2).map_or("spectral", |s| s.as_str());
    let mut best: Option<(f64, FireVolume)> = None;
    let mut all = Vec::new();
    for _ in 0..rounds {
        let t = Instant::now();
        let v = match FireVolume::new(&[
            Param::string("filename", file),
            Param::string("colormode", mode),
        ]) {
            Ok(v) => v,
            Err(e) => {
                eprintln!("{e}");
                std::process::exit(1);
            }
        };
        let s = t.elapsed().as_secs_f64();
        all.push(s);
        if best.as_ref().is_none_or(|b| s < b.0) {
            best = Some((s, v));
        }
    }
    all.sort_by(f64::total_cmp);
    let Some((s, v)) = best else { return };
    println!(
        "{file}, {mode}: fastest {:.1} ms, median {:.1} ms of {rounds}",
        s * 1e3,
        all[all.len() / 2] * 1e3
    );
    for c in v.dataset().channels() {
        println!(
            "  channel {:<12} {:>7.1} ms  {:>6.1} MB",
            c.name,
            c.report.load_seconds * 1e3,
            c.report.bytes as f64 / 1e6
        );
    }
    for t in v.tables() {
        println!(
            "  {:<60} {:>7.1} ms  {:>6.1} MB",
            t.name,
            t.seconds * 1e3,
            t.bytes as f64 / 1e6
        );
    }
}
