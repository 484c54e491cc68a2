//! End-to-end: `firemedium info` on real dataset files — the numbers, the JSON fields, `--sample`, and a
//! refused file exiting 1 with one line (never 101, a panic).

use serde_json::Value;
use std::process::{Command, Output};

fn data(rel: &str) -> String {
    crate::common::root()
        .join("tests/data")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

fn firemedium(args: &[&str]) -> Output {
    Command::new(crate::common::exe("firemedium"))
        .args(args)
        .output()
        .expect("firemedium runs")
}

#[test]
fn info_json_on_the_mantaflow_fire() {
    let f = data("valid/vdb/mantaflow_fire_f060.vdb");
    let out = firemedium(&[
        "info",
        &f,
        "--json",
        "--grid",
        "density",
        "--grid",
        "temperature",
        "--sample",
        "1,1,0.5",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["format"], "vdb");
    // Union of the active boxes [1, 62] × [1, 62] × [2, 94] → 62 × 62 × 93, voxel 1/32.
    assert_eq!(v["dims"], serde_json::json!([62, 62, 93]));
    assert_eq!(v["voxel_size"][0], 0.03125);
    assert_eq!(v["bounds"][0][2], (2.0 - 0.5) / 32.0);
    let ch = v["channels"].as_array().unwrap();
    assert_eq!(ch[0]["name"], "density");
    assert_eq!(ch[0]["max"], 1.0439453125); // the sidecar's max_active
    assert_eq!(ch[1]["max"], 2.974609375);
    // Stored as 8³ bricks aligned as the file's leaves (the box starts at (1, 1, 2)): the 459 of the box's
    // 8 × 8 × 12 that hold a leaf (Mantaflow leaves the rest to inactive background tiles), and the background's
    // brick — 0.66× the dense box's 62 · 62 · 93 · 4 bytes.
    assert_eq!(v["bricks"], 459);
    assert_eq!(v["bricks_in_box"], 768);
    assert_eq!(ch[0]["bytes"], 460 * 512 * 4);
    assert!(ch[0]["load_seconds"].as_f64().unwrap() >= 0.0);
    // 121 969 non-zero density voxels of 62·62·93.
    let frac = ch[0]["active_fraction"].as_f64().unwrap();
    assert!(
        (frac - 121_969.0 / (62.0 * 62.0 * 93.0)).abs() < 1e-12,
        "{frac}"
    );
    let skipped: Vec<&str> = v["skipped_grids"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["name"].as_str().unwrap())
        .collect();
    assert_eq!(skipped, ["velocity", "shadow", "flame"]);
    // Blender's cache says where it comes from: its flame grid is the fire's temperature (`source "blender"`).
    assert_eq!(v["source"][0], "blender");
    let s = &v["sample"]["values"];
    assert_eq!(s[0][0], "density");
    assert!(s[0][1].as_f64().unwrap() > 0.5, "{s}");
}

#[test]
fn info_text_and_sample_on_the_ramp() {
    let out = firemedium(&[
        "info",
        &data("valid/vdb/ramp_16_zip.vdb"),
        "--sample=0.6,-1,2",
    ]);
    assert!(out.status.success());
    let t = String::from_utf8(out.stdout).unwrap();
    assert!(t.contains("dims      16 × 16 × 16"), "{t}");
    // Index (1, 0, 0) sits at (0.6, −1, 2): density 1, temperature 300.
    assert!(
        t.contains("sample at (0.6, -1, 2): density = 1 temperature = 300"),
        "{t}"
    );
}

#[test]
fn refused_files_exit_1_with_one_line() {
    for (f, want) in [
        (data("invalid/truncated_blocks.vdb"), "truncated_blocks.vdb"),
        (data("invalid/nan_density.txt"), "NaN"),
        ("/no/such/fire.vdb".to_string(), "cannot read"),
    ] {
        let out = firemedium(&["info", &f]);
        assert_eq!(out.status.code(), Some(1), "{f}");
        let e = String::from_utf8_lossy(&out.stderr);
        assert_eq!(e.trim_end().lines().count(), 1, "{e}");
        assert!(e.contains(want), "{e}");
    }
    // The NaN policy as a flag turns the refusal into a report.
    let out = firemedium(&[
        "info",
        &data("invalid/nan_density.txt"),
        "--nonfinite",
        "zero",
        "--json",
    ]);
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["channels"][0]["replaced_nonfinite"], 1);
    // Bad flags exit 2.
    let out = firemedium(&["info", &data("valid/vdb/ramp_16.vdb"), "--sample", "1,2"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn a_file_of_vector_grids_is_described_by_their_components() {
    // A bake's output (sigma_a, sigma_s, emission) and a velocity cache hold vector grids only: `info` describes
    // their components instead of refusing the file.
    let dir = crate::common::scratch::Scratch::new("info", "vectors");
    let n = 8 * 8 * 8;
    let (up, zero) = (vec![2.5f32; n], vec![0f32; n]);
    let bytes = firemedium_dataset::vdb::write_with_vectors(
        &[],
        &[("vel", [8, 8, 8], [&zero[..], &zero[..], &up[..]])],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.1),
    );
    let file = dir.join("vel.vdb");
    std::fs::write(&file, bytes).unwrap();
    let o = std::process::Command::new(crate::common::exe("firemedium"))
        .arg("info")
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let row = |name: &str| {
        text.lines()
            .find(|l| l.starts_with(name))
            .unwrap_or_else(|| panic!("no {name} row: {text}"))
            .split_whitespace()
            .skip(1)
            .take(3)
            .map(|v| v.parse::<f64>().unwrap())
            .collect::<Vec<_>>()
    };
    assert_eq!(row("vel.z"), [2.5, 2.5, 2.5]);
    assert_eq!(row("vel.x"), [0.0, 0.0, 0.0]);
    assert!(!text.contains("skipped"), "{text}");
}
