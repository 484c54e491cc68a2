//! `firemedium-bench …` (what `firemedium bench …` runs) from the command line, at tiny sizes: each runs, writes
//! what it says, and its numbers are sane. (The measurements themselves are in docs/results/log.md; no timing is asserted here.)

use std::path::PathBuf;
use std::process::{Command, Output};

#[path = "common/mod.rs"]
mod common;
use common::scratch;

fn run(args: &[&str]) -> Output {
    Command::new(common::exe("firemedium-bench"))
        .args(args)
        .output()
        .unwrap()
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn scenes() -> PathBuf {
    common::root().join("scenes")
}

#[test]
fn stability_passes_every_case() {
    let text = ok(&run(&["stability"]));
    assert!(text.contains(" cases, 0 failed"), "{text}");
    assert!(!text.contains("FAIL"), "{text}");
    // `firemedium bench …` runs this program: the command beside it (a workspace build puts them together).
    let bench = common::exe("firemedium-bench");
    let firemedium = bench.with_file_name(format!("firemedium{}", std::env::consts::EXE_SUFFIX));
    assert!(
        firemedium.is_file(),
        "{} not built (cargo build --release -p firemedium)",
        firemedium.display()
    );
    let o = Command::new(&firemedium)
        .args(["bench", "stability"])
        .output()
        .unwrap();
    let forwarded = ok(&o);
    let cases = |t: &str| t.lines().filter(|l| l.ends_with("| pass |")).count();
    assert!(cases(&text) >= 40, "{text}");
    assert_eq!(cases(&forwarded), cases(&text), "{forwarded}");
    // Its errors are the program's, with the usage a user types.
    let o = Command::new(&firemedium)
        .args(["bench", "bogus"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("'bogus'") && e.contains("usage: firemedium bench <COMMAND>"),
        "{e}"
    );
}

#[test]
fn without_its_benchmark_program_firemedium_bench_says_where_it_looked() {
    let dir = scratch::Scratch::new("bench", "alone");
    let bench = common::exe("firemedium-bench");
    let firemedium = bench.with_file_name(format!("firemedium{}", std::env::consts::EXE_SUFFIX));
    let alone = dir.join(firemedium.file_name().unwrap());
    std::fs::copy(&firemedium, &alone).unwrap_or_else(|e| panic!("{}: {e}", firemedium.display()));
    let o = Command::new(&alone)
        .args(["bench", "stability"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains(&dir.join("firemedium-bench").display().to_string())
            && e.contains("cargo build --release -p firemedium-bench"),
        "{e}"
    );
}

#[test]
fn error_vs_time_writes_csv_svg_and_png() {
    let dir = scratch::Scratch::new("bench", "evt");
    let prefix = dir.join("evt");
    let vdb = scenes().join("campfire/campfire.vdb");
    let text = ok(&run(&[
        "error-vs-time",
        "--dataset",
        vdb.to_str().unwrap(),
        "--image",
        "12",
        "--max-spp",
        "2",
        "--surface",
        scenes().join("campfire/scene.pbrt").to_str().unwrap(),
        "--surface-resolution",
        "16x12",
        "--surface-max-spp",
        "2",
        "--surface-reference-spp",
        "8",
        "-o",
        prefix.to_str().unwrap(),
    ]));
    // The surface ladder: fire light on and off at 1 and 2 spp; for the light on, the whole image's true error
    // and the render's own estimate of it (2 spp: one pass, its halves).
    let surface = std::fs::read_to_string(dir.join("evt-surface.csv")).unwrap();
    assert_eq!(surface.lines().count(), 1 + 4 + 2, "{surface}");
    assert!(
        surface.contains("fire light on,1 spp") && surface.contains("fire light off,2 spp"),
        "{surface}"
    );
    let column = |estimator: &str| -> f64 {
        let line = surface
            .lines()
            .find(|l| l.starts_with(&format!("{estimator},2 spp,")))
            .unwrap_or_else(|| panic!("no {estimator} at 2 spp in\n{surface}"));
        line.split(',').nth(3).unwrap().parse().unwrap()
    };
    let (truth, estimate) = (
        column("fire light on: true error (whole image)"),
        column("fire light on: the render's own estimate"),
    );
    // (Loose: a 16×12 image at 2 spp against an 8-spp reference; the estimate's accuracy is measured in
    // `bench noise` and tests/production/noise_cli.rs.)
    assert!(
        truth > 0.0 && (0.25..4.0).contains(&(estimate / truth)),
        "{surface}"
    );
    assert!(text.contains("equal-time winner"), "{text}");
    // The reference is a quadrature no row computes; the finest march lands on it independently (1.2e-5 here).
    let agree: f64 = text
        .split("the march at 1/16 voxel differs from it by rel. RMSE ")
        .nth(1)
        .and_then(|t| t.split(',').next())
        .and_then(|t| t.parse().ok())
        .unwrap_or_else(|| panic!("no march-to-quadrature figure in\n{text}"));
    assert!(agree > 0.0 && agree < 2e-4, "{agree}");
    let csv = std::fs::read_to_string(dir.join("evt.csv")).unwrap();
    // Header, 5 march steps × 2 colour modes, 2 spp levels × 2 trackers.
    assert_eq!(csv.lines().count(), 1 + 10 + 4, "{csv}");
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let (secs, err): (f64, f64) = (f[2].parse().unwrap(), f[3].parse().unwrap());
        assert!(secs > 0.0 && err.is_finite() && err >= 0.0, "{line}");
    }
    // The march converges: its error falls from 2 to 1/8 voxel.
    let march: Vec<f64> = csv
        .lines()
        .filter(|l| l.starts_with("march spectral"))
        .map(|l| l.split(',').nth(3).unwrap().parse().unwrap())
        .collect();
    assert!(march[4] < march[0] / 4.0, "{march:?}");
    assert!(std::fs::read_to_string(dir.join("evt.svg"))
        .unwrap()
        .starts_with("<svg"));
    let dec = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.join("evt.png")).unwrap(),
    ));
    let info = dec.read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (760, 480));
}

#[test]
fn perf_and_components_run_small() {
    let vdb = scenes().join("campfire/campfire.vdb");
    let text = ok(&run(&[
        "perf",
        "--dataset",
        vdb.to_str().unwrap(),
        "--image",
        "16",
        "--reference-step",
        "0.25",
        "--kernel",
    ]));
    assert_eq!(text.matches("| march ½ voxel").count(), 6, "{text}");
    // The f32 lanes and the f64 march make the same image to f32 rounding: equal errors against the reference.
    let err = |row: &str| -> f64 {
        let line = text.lines().find(|l| l.starts_with(row)).unwrap();
        line.trim_end_matches('|')
            .rsplit('|')
            .next()
            .unwrap()
            .trim()
            .parse()
            .unwrap()
    };
    let (lanes, f64_) = (
        err("| march ½ voxel, spectral (30 bins, 400–700 nm: the thesis's) |"),
        err("| march ½ voxel, spectral (30 bins, 400–700 nm), f64"),
    );
    // Against the reference converged in the step, the bins and the range (380–780 nm), the thesis's range
    // leaves out the fire's red tail past 700 nm (the campfire at 16²: 4.37e-3); 32 bins over 400–780 nm, the
    // default, are 7.80e-4 off, 16 bins 1.92e-3. The reference line gives the step's and the spectrum's parts.
    let (wide32, wide16) = (
        err("| march ½ voxel, spectral (32 bins, 400–780 nm: the default) |"),
        err("| march ½ voxel, spectral (16 bins, 400–780 nm) |"),
    );
    assert!(
        lanes > 3e-3 && wide32 < 0.25 * lanes && wide16 > 1.5 * wide32 && wide16 < 2e-3,
        "{lanes} {wide32} {wide16}\n{text}"
    );
    // The default spectrum's own error (at ½ voxel, against 320 bins over 380–780 nm): 4.54e-4 here, a tenth
    // of the thesis's range's.
    let alone: f64 = text
        .split("the spectrum alone ")
        .nth(1)
        .and_then(|t| t.split_whitespace().next())
        .and_then(|w| w.parse().ok())
        .unwrap_or(f64::NAN);
    assert!(alone < 1e-3 && alone < 0.2 * lanes, "{alone}\n{text}");
    // (Printed to three digits: equal up to one unit of the last, as f32 rounding moves the error by ~1e-7.)
    assert!(
        lanes.is_finite() && (lanes - f64_).abs() <= 0.011 * f64_.abs(),
        "{lanes} vs {f64_}\n{text}"
    );
    assert!(text.contains("peak memory"), "{text}");
    // The user's path: the same workload as a scene through `firemedium render`, per sampler, and the naive
    // march. The naive march and the render at pixel centres are the same estimator through the same camera:
    // their errors against the sub-pixel reference agree (a mirrored camera would not); 16 zsobol samples
    // per pixel are closer to it than one at the centre.
    let text = ok(&run(&[
        "perf",
        "--dataset",
        vdb.to_str().unwrap(),
        "--image",
        "16",
        "--reference-subpixels",
        "4",
    ]));
    let err = |row: &str| -> f64 {
        let line = text.lines().find(|l| l.starts_with(row)).unwrap();
        line.split('|').nth(7).unwrap().trim().parse().unwrap()
    };
    let (naive, centres, zsobol) = (
        err("| naive march"),
        err("| pixel centres (stratified 1×1"),
        err("| zsobol, 16 spp"),
    );
    assert!(
        (naive / centres - 1.0).abs() < 0.05 && zsobol < 0.5 * centres,
        "{naive} {centres} {zsobol}\n{text}"
    );
    assert!(text.contains("two threads against one"), "{text}");
    let torch = scenes().join("spectroscopy/torch.vdb");
    let text = ok(&run(&["components", "--dataset", torch.to_str().unwrap()]));
    assert_eq!(text.matches("**total**").count(), 4, "{text}");
}

#[test]
fn memory_renders_pbrt_v4s_rooms_beside_its_figures() {
    // The two rooms over the campfire as pbrt-v4's `nanovdb` medium, at a tiny film: every room with the medium's
    // default (no copy for pbrt-v4's media) and with the march's dense copy, each row's ratio its peak over
    // pbrt-v4's figure, and the copy costing what it holds (62 × 68 × 98 padded voxels of 8 bytes: 3.3 MB).
    let vdb = scenes().join("campfire/campfire.vdb");
    let text = ok(&run(&[
        "memory",
        "--dataset",
        vdb.to_str().unwrap(),
        "--spp",
        "1",
        "--rounds",
        "1",
        "--resolution",
        "16x9",
    ]));
    let rows: Vec<Vec<&str>> = text
        .lines()
        .filter(|l| l.starts_with("| a") && l.contains("fire"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    assert_eq!(rows.len(), 4, "{text}");
    let mut peaks = Vec::new();
    for (k, r) in rows.iter().enumerate() {
        let num = |i: usize| -> f64 { r[i].trim_end_matches('×').parse().unwrap() };
        let (peak, pbrt, ratio) = (num(3), num(4), num(5));
        assert_eq!(pbrt, if k < 2 { 43.0 } else { 45.1 }, "{text}");
        assert!(peak > 1.0 && peak < 1000.0, "{text}");
        assert!((ratio - peak / pbrt).abs() < 0.006, "{text}");
        assert_eq!(r[2] == "dense", k % 2 == 1, "{text}");
        peaks.push(peak);
    }
    for room in [0, 2] {
        let copy = peaks[room + 1] - peaks[room];
        assert!((2.0..8.0).contains(&copy), "the copy: {copy} MB\n{text}");
    }
}
