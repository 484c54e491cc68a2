//! Production-scale sparse fires (issue 23): memory follows the active voxels, not the box.
//!
//! A small fire (a 24³ blob of soot at 1400–1700 K) written as an OpenVDB file alone, and again with a second
//! copy 2040 voxels away on every axis (a 2060³ active box: dense storage of its two grids would take 70 GB). Rendered
//! through `firemedium render` and the cdylib under a 1 GB memory budget, the far file must load and render,
//! and the first copy's pixels must be the single fire's.

use crate::common::image;

use image::read_exr;
use std::path::Path;
use std::process::Command;

use crate::common::scratch;

use crate::common::guard;
use guard::finishes;

/// The test's scratch folder (removed when it passes).
fn out_dir(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("sparse", name)
}

/// The blob's leaves (density, temperature) with origin `o` (index space, multiples of 8): 3³ leaves.
fn blob(
    o: [i32; 3],
) -> (
    Vec<firemedium_dataset::vdb::VdbLeaf>,
    Vec<firemedium_dataset::vdb::VdbLeaf>,
) {
    let (mut d, mut t) = (Vec::new(), Vec::new());
    for lz in 0..3 {
        for ly in 0..3 {
            for lx in 0..3 {
                let origin = [o[0] + 8 * lx, o[1] + 8 * ly, o[2] + 8 * lz];
                let (mut dv, mut tv) = (vec![0f32; 512], vec![0f32; 512]);
                let mut mask = [0u64; 8];
                for i in 0..512 {
                    // Leaf voxel i: x = i >> 6, y = (i >> 3) & 7, z = i & 7 (z fastest).
                    let p = [
                        8 * lx + (i as i32 >> 6),
                        8 * ly + ((i as i32 >> 3) & 7),
                        8 * lz + (i as i32 & 7),
                    ];
                    let r = p
                        .iter()
                        .map(|&c| (c as f64 + 0.5 - 12.0).powi(2))
                        .sum::<f64>()
                        .sqrt()
                        / 10.0;
                    if r < 1.0 {
                        dv[i] = (4e-6 * (1.0 - r)) as f32;
                        tv[i] = (1400.0 + 300.0 * (1.0 - r)) as f32;
                        mask[i / 64] |= 1 << (i % 64);
                    }
                }
                d.push((origin, mask, dv));
                t.push((origin, mask, tv));
            }
        }
    }
    (d, t)
}

fn render(scene: &Path, out: &Path) -> std::process::Output {
    Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args([
            "-q",
            "--seed",
            "3",
            "--fire-light",
            "off",
            "--max-memory",
            "1",
        ])
        .output()
        .unwrap()
}

#[test]
fn a_fire_with_a_far_away_copy_renders_in_the_memory_of_two_fires() {
    let dir = out_dir("far");
    let voxel = glam::DVec3::splat(0.01);
    let (d0, t0) = blob([0, 0, 0]);
    let (d1, t1) = blob([2040, 2040, 2040]);
    let single = firemedium_dataset::vdb::write_sparse(
        &[("density", d0.clone()), ("temperature", t0.clone())],
        glam::DVec3::ZERO,
        voxel,
    );
    let far = firemedium_dataset::vdb::write_sparse(
        &[
            ("density", [d0, d1].concat()),
            ("temperature", [t0, t1].concat()),
        ],
        glam::DVec3::ZERO,
        voxel,
    );
    std::fs::write(dir.join("single.vdb"), &single).unwrap();
    std::fs::write(dir.join("far.vdb"), &far).unwrap();
    assert!(far.len() < 1_000_000, "a small file: {} bytes", far.len());
    // Seen along +z from below, orthographic over the first blob; the medium's boundary is the first blob's
    // box (rays enter both datasets at the same face, so their samples are the same points).
    let scene = |file: &str| {
        format!(
            "LookAt 0.12 0.12 -1  0.12 0.12 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-0.12 0.12 -0.12 0.12]\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nSampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" false\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"{file}\" \"string fuel\" \"propane\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 0.24 0 0 0 0.24 0 0.24 0.24 0 0 0 0.24 0.24 0 0.24 0 0.24 0.24 0.24 0.24 0.24] \"integer indices\" [0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5]\nAttributeEnd\n"
        )
    };
    let mut images = Vec::new();
    for name in ["single", "far"] {
        let f = dir.join(format!("{name}.pbrt"));
        std::fs::write(&f, scene(&format!("{name}.vdb"))).unwrap();
        let out = dir.join(format!("{name}.exr"));
        let o = render(&f, &out);
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        images.push(read_exr(&out));
    }
    // The fire is there (the blob's centre is bright) and the far copy changes none of its pixels.
    let (a, b) = (&images[0].2, &images[1].2);
    let centre = a[8 + 16 * 8];
    assert!(centre[0] > 1.0, "the fire is visible: {centre:?}");
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-4 * p[c].abs().max(1e-3),
                "pixel {i}: {p:?} vs {q:?}"
            );
        }
    }
    // With the fire light (the default) the far fire renders too: the light weighs the stored bricks and
    // their neighbours only, so it follows the data as the grids do (no warning, within the 1 GB budget).
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(dir.join("far.pbrt"))
        .arg("-o")
        .arg(dir.join("far-light.exr"))
        .args(["--seed", "3", "--max-memory", "1"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    // (The box bounds the near fire only, on purpose: the far copy's data lies beyond it, which is said.)
    let others = e
        .lines()
        .filter(|l| l.contains("warning") && !l.contains("beyond the shapes that bound it"))
        .count();
    assert!(o.status.success() && others == 0, "{e}");
    // What the plugin says it stored: the two blobs' bricks, not the box.
    let info = Command::new(crate::common::exe("firemedium"))
        .args(["info", "--json"])
        .arg(dir.join("far.vdb"))
        .output()
        .unwrap();
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    // The active box: voxels 2 … 2061 on each axis (the blobs' spheres of radius 10 around 12 and 2052).
    assert_eq!(v["dims"], serde_json::json!([2060, 2060, 2060]));
    eprintln!(
        "far fire: {} bricks of {}, {} bytes",
        v["bricks"], v["bricks_in_box"], v["bytes"]
    );
    assert_eq!(v["bricks"], 2 * 27);
    assert!(v["bytes"].as_u64().unwrap() < 100_000_000, "{}", v["bytes"]);
}

#[test]
fn two_far_leaves_cost_what_two_leaves_cost() {
    // Two 8³ leaves 32 768 voxels apart on every axis: a box of 4096³ bricks, two of them stored. The grid's
    // statistics (`info`) and the majorant ranges (`render`) walked every brick of the box: 10.7 s at 16 384
    // apart, 85 s here (render: 37 s at 24 576), growing as the box. They now walk the stored bricks (0.02 s and 0.7 s).
    let dir = out_dir("two-far-leaves");
    let far = 32_768;
    let leaf = |o: [i32; 3], v: f32| (o, [u64::MAX; 8], vec![v; 512]);
    let file = firemedium_dataset::vdb::write_sparse(
        &[
            ("density", vec![leaf([0; 3], 1e-3), leaf([far; 3], 1e-3)]),
            (
                "temperature",
                vec![leaf([0; 3], 1500.0), leaf([far; 3], 1500.0)],
            ),
        ],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    std::fs::write(dir.join("far.vdb"), &file).unwrap();
    let info = finishes(
        Command::new(crate::common::exe("firemedium"))
            .args(["info", "--json"])
            .arg(dir.join("far.vdb")),
        60,
    );
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(v["dims"], serde_json::json!([far + 8, far + 8, far + 8]));
    assert_eq!(v["bricks"], 2);
    // Seen from below through the first leaf's column, with a floor the fire light shines on.
    std::fs::write(
        dir.join("far.pbrt"),
        "LookAt 0.04 0.3 -1  0.04 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-0.1 0.1 -0.1 0.1]\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nSampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" false\nIntegrator \"volpath\" \"integer maxdepth\" 5\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"far.vdb\" \"string fuel\" \"propane\" \"float sootscale\" 1\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 0.08 0 0 0 0.08 0 0.08 0.08 0 0 0 0.08 0.08 0 0.08 0 0.08 0.08 0.08 0.08 0.08] \"integer indices\" [0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5]\nAttributeEnd\nMaterial \"diffuse\"\nShape \"trianglemesh\" \"point3 P\" [-1 -0.05 -1  1 -0.05 -1  1 -0.05 1  -1 -0.05 1] \"integer indices\" [0 1 2 0 2 3]\n",
    )
    .unwrap();
    let o = finishes(
        Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(dir.join("far.pbrt"))
            .arg("-o")
            .arg(dir.join("far.exr"))
            .args(["--stats", "--fire-light", "power", "--max-memory", "2"]),
        60,
    );
    let e = String::from_utf8_lossy(&o.stderr);
    // (The box bounds the near fire only, on purpose: the far copy's data lies beyond it, which is said.)
    let others = e
        .lines()
        .filter(|l| l.contains("warning") && !l.contains("beyond the shapes that bound it"))
        .count();
    assert!(o.status.success() && others == 0, "{e}");
    // (`--stats` reports on stdout.) Each leaf and the fringe its trilinear lookups reach: 2 × 9³ voxels.
    let stats = String::from_utf8_lossy(&o.stdout);
    assert!(
        stats.contains("fire light: 1458 emitting voxels"),
        "{stats}"
    );
    let (_, _, px) = read_exr(&dir.join("far.exr"));
    assert!(px.iter().any(|p| p[0] > 1.0), "the fire is seen");
}

/// The megabytes `firemedium render --stats` says the plugin built for the scene's one medium.
fn plugin_built_mb(stats: &str) -> f64 {
    let line = stats
        .lines()
        .find(|l| l.contains("plugin built"))
        .unwrap_or_else(|| panic!("no \"plugin built\" line in {stats}"));
    let after = &line[line.find("plugin built ").unwrap() + "plugin built ".len()..];
    after.split(' ').next().unwrap().parse().unwrap()
}

/// Renders `dataset` (named relative to `dir`, with `params` on the medium) as a fire filling the box seen
/// orthographically over `window` against a grey sky, with and without the march lattice (`lattice` "off": the same
/// grids read by the general stencil); returns the plugin's megabytes with the lattice and both images.
fn with_and_without_lattice(
    dir: &Path,
    dataset: &str,
    params: &str,
    window: f64,
) -> (f64, Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let mut out = Vec::new();
    let mut mb = 0.0;
    for lattice in ["auto", "off"] {
        let scene = dir.join(format!("{lattice}.pbrt"));
        std::fs::write(
            &scene,
            format!("LookAt 0.5 0.5 -200  0.5 0.5 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-{window} {window} -{window} {window}]\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nSampler \"stratified\" \"integer xsamples\" 1 \"integer ysamples\" 1 \"bool jitter\" false\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.5 0.5 0.5]\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"{dataset}\" {params} \"string lattice\" \"{lattice}\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 100\nAttributeEnd\n"),
        )
        .unwrap();
        let exr = dir.join(format!("{lattice}.exr"));
        let o = Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&exr)
            .args(["--stats", "--max-memory", "2"])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.success() && !e.contains("warning"),
            "{lattice}: {e}"
        );
        if lattice == "auto" {
            mb = plugin_built_mb(&String::from_utf8_lossy(&o.stdout));
        }
        out.push(read_exr(&exr).2);
    }
    let off = out.pop().unwrap();
    (mb, out.pop().unwrap(), off)
}

fn assert_same_pixels(a: &[[f32; 3]], b: &[[f32; 3]], what: &str) {
    assert!(a.iter().any(|p| p[0] > 0.0), "{what}: a black image");
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        for c in 0..3 {
            assert!(
                (p[c] - q[c]).abs() <= 1e-4 * p[c].abs().max(1e-3),
                "{what}: pixel {i}: {p:?} with the lattice, {q:?} without"
            );
        }
    }
}

#[test]
fn constant_tiles_stay_shared_in_the_march_lattice() {
    // 256 active constant tiles of 128³ per grid (a 1024×1024×512 box, 1 M bricks, in a few hundred KB): the
    // dataset stores one block per value, but the march lattice copied every brick the tiles cover — "plugin
    // built 4358 MB", 4.6 GB resident. Its copies of a tile's interior (and of each face's) now share one copy,
    // as the dataset's bricks do: 36.6 MB, the same image.
    let dir = out_dir("tiles");
    let (mut d, mut t) = (Vec::new(), Vec::new());
    for k in 0..4 {
        for j in 0..8 {
            for i in 0..8 {
                d.push(([128 * i, 128 * j, 128 * k], 128, 1e-4f32));
                t.push(([128 * i, 128 * j, 128 * k], 128, 1500f32));
            }
        }
    }
    let file = firemedium_dataset::vdb::write_tiled(
        &[("density", vec![], d), ("temperature", vec![], t)],
        glam::DVec3::ZERO,
        glam::DVec3::splat(1.0 / 1024.0),
    );
    assert!(file.len() < 400_000, "{} bytes", file.len());
    std::fs::write(dir.join("tiles.vdb"), &file).unwrap();
    let (mb, with, without) =
        with_and_without_lattice(&dir, "tiles.vdb", "\"string fuel\" \"propane\"", 0.6);
    assert!(mb < 100.0, "the plugin built {mb} MB for 2 values");
    assert_same_pixels(&with, &without, "tiles");
}

#[test]
fn a_background_is_one_block_not_a_dense_grid() {
    // A Uintah sparse grid of 20 bytes: 1000³, no voxels, background 1. Every brick was stored (4 GB), and its
    // lattice 12.3 GB resident, 35 s. Empty bricks read the background: 4 KB, a 5 MB lattice, the same image.
    let dir = out_dir("background");
    std::fs::write(dir.join("u.txt"), "1000 1000 1000\n0\n1\n").unwrap();
    let info = Command::new(crate::common::exe("firemedium"))
        .args(["info", "--json", "--format", "asciisparse"])
        .arg(dir.join("u.txt"))
        .output()
        .unwrap();
    assert!(
        info.status.success(),
        "{}",
        String::from_utf8_lossy(&info.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    assert_eq!(v["dims"], serde_json::json!([1000, 1000, 1000]));
    assert!(v["bytes"].as_u64().unwrap() < 100_000, "{}", v["bytes"]);
    // (pbrt-v4's semantics: σa = 0.7 per unit density, no scattering, seen against a sky: a transmittance of
    // e^−0.7.)
    let params = "\"string format\" \"asciisparse\" \"string mode\" \"pbrt\" \"spectrum sigma_a\" [400 0.7 800 0.7] \"spectrum sigma_s\" [400 0 800 0]";
    let (mb, with, without) = with_and_without_lattice(&dir, "u.txt", params, 0.6);
    assert!(mb < 50.0, "the plugin built {mb} MB for a background");
    assert_same_pixels(&with, &without, "background");
    // Through the unit box: the sky beside it (pixel 0 of the row) times e^−0.7.
    let (centre, sky) = (with[8 + 16 * 8], with[16 * 8]);
    for c in 0..3 {
        let want = sky[c] * (-0.7f32).exp();
        assert!(
            (centre[c] - want).abs() < 1e-3 * want,
            "{centre:?} vs {want}"
        );
    }
}

#[test]
fn a_file_of_many_nodes_reads_in_time_that_follows_its_nodes() {
    // 216 root nodes, each with one leaf and twenty active 8³ tiles: every node's empty slot is a tile of the
    // background (7 M of them), and each was matched against every valued tile (4 320) to see whether it
    // overrides one — 3·10¹⁰ comparisons, found by the structure-aware mutator as an 11 MB file running for
    // minutes. Matched through the cells the valued tiles cover, the file reads in a second.
    let dir = out_dir("many-nodes");
    let (mut d, mut tiles) = (Vec::new(), Vec::new());
    for k in 0..6 {
        for j in 0..6 {
            for i in 0..6 {
                let o = [4096 * i, 4096 * j, 4096 * k];
                d.push((o, [u64::MAX; 8], vec![1e-4f32; 512]));
                for t in 0..20 {
                    tiles.push(([o[0] + 512 + 8 * t, o[1] + 512, o[2] + 512], 8, 2e-4f32));
                }
            }
        }
    }
    let file = firemedium_dataset::vdb::write_tiled(
        &[("density", d, tiles)],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    std::fs::write(dir.join("nodes.vdb"), &file).unwrap();
    let o = finishes(
        Command::new(crate::common::exe("firemedium"))
            .args(["info", "--json"])
            .arg(dir.join("nodes.vdb")),
        60,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The 216 leaves and 4 320 tiles' bricks, and the valued tiles' value among the leaves'.
    assert_eq!(v["bricks"], 216 + 4320, "{v}");
    let max = v["channels"][0]["max"].as_f64().unwrap();
    assert!((max - 2e-4).abs() < 1e-9, "{v}");
}
