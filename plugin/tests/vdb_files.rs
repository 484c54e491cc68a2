//! OpenVDB and NanoVDB readers against real files written by OpenVDB 12 / NanoVDB (tests/data/valid, copied
//! from shared/data with their JSON sidecars): every value the sidecars give must be reproduced.

use firemedium_plugin::dataset::{ChannelSource, Dataset, LoadOptions};
use glam::DVec3;
use serde_json::Value;
use std::path::PathBuf;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data/valid")
        .join(rel)
}

fn sidecar(rel: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(data(rel)).unwrap()).unwrap()
}

fn load(rel: &str, names: &[&str]) -> Dataset {
    let sources: Vec<ChannelSource> = names
        .iter()
        .map(|n| ChannelSource::new(n, data(rel)))
        .collect();
    Dataset::load(&sources, &LoadOptions::default()).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

fn v3(v: &Value) -> DVec3 {
    DVec3::new(
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    )
}

fn sum(ds: &Dataset, ch: usize) -> f64 {
    ds.channels()[ch]
        .grid
        .to_dense()
        .iter()
        .map(|&v| v as f64)
        .sum()
}

/// Checks every sidecar sample: the value at the voxel's medium-space centre (trilinear at a centre is the
/// sample itself) and at its index.
fn check_samples(ds: &Dataset, side: &Value, names: &[&str], index_min: [i64; 3], tol: f64) {
    let samples = side["samples"].as_array().unwrap();
    assert!(samples.len() >= 10);
    for s in samples {
        let ijk: Vec<i64> = s["ijk"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_i64().unwrap())
            .collect();
        let world = v3(&s["world_xyz"]);
        for (c, name) in names.iter().enumerate() {
            let want = s[*name].as_f64().unwrap();
            let got = ds.sample(c, world) as f64;
            let q = [0, 1, 2].map(|k| ijk[k] - index_min[k]);
            let inside = (0..3).all(|k| q[k] >= 0 && (q[k] as usize) < ds.dims()[k]);
            if inside {
                let at = ds.channels()[c].grid.at(q[0], q[1], q[2]) as f64;
                // The sidecars print f32 values through f64; compare in f32 when exact.
                let same = if tol == 0.0 {
                    at as f32 == want as f32
                } else {
                    (at - want).abs() <= tol * want.abs().max(1.0)
                };
                assert!(same, "{name} at {ijk:?}: {at} vs {want}");
                assert!(
                    (got - want).abs() <= 1e-6 * want.abs().max(1.0),
                    "{name} at {world}: {got} vs {want}"
                );
            } else {
                // Outside the active box the dataset is zero (its background is zero here).
                assert_eq!(want, 0.0, "{name} at {ijk:?} outside the active box");
            }
        }
    }
}

#[test]
fn ramp_16_in_every_compression() {
    for (file, side) in [
        ("vdb/ramp_16.vdb", "vdb/ramp_16.json"),
        ("vdb/ramp_16_zip.vdb", "vdb/ramp_16_zip.json"),
        ("vdb/ramp_16_nocomp.vdb", "vdb/ramp_16_nocomp.json"),
    ] {
        let ds = load(file, &["density", "temperature"]);
        let side = sidecar(side);
        assert_eq!(ds.dims(), [16, 16, 16], "{file}");
        // Index i ↦ 0.1 i + (0.5, −1, 2); the box spans half a voxel beyond the outer centres.
        let [p0, p1] = ds.bounds();
        assert!(
            (p0 - DVec3::new(0.45, -1.05, 1.95)).abs().max_element() < 1e-12,
            "{p0}"
        );
        assert!(
            (p1 - DVec3::new(2.05, 0.55, 3.55)).abs().max_element() < 1e-12,
            "{p1}"
        );
        let g = &ds.channels()[0].grid;
        let t = &ds.channels()[1].grid;
        for k in 0..16 {
            for j in 0..16 {
                for i in 0..16 {
                    assert_eq!(
                        g.at(i, j, k),
                        (i + 16 * j + 256 * k) as f32,
                        "{file} density ({i},{j},{k})"
                    );
                    assert_eq!(t.at(i, j, k), (300 + 100 * k) as f32, "{file} temperature");
                }
            }
        }
        assert_eq!(
            sum(&ds, 0),
            side["value_sums_float64"]["density"].as_f64().unwrap()
        );
        assert_eq!(
            sum(&ds, 1),
            side["value_sums_float64"]["temperature"].as_f64().unwrap()
        );
        check_samples(&ds, &side, &["density", "temperature"], [0, 0, 0], 0.0);
        // 16³ voxels in eight 8³ bricks, and the background's brick.
        assert_eq!(ds.channels()[0].report.bytes, (16 * 16 * 16 + 512) * 4);
    }
}

#[test]
fn half_floats_round_to_nearest_even() {
    let ds = load("vdb/two_grids_half.vdb", &["density", "temperature"]);
    let side = sidecar("vdb/two_grids_half.json");
    check_samples(&ds, &side, &["density", "temperature"], [0, 0, 0], 0.0);
    assert_eq!(
        sum(&ds, 0),
        side["value_sums_float64"]["density"].as_f64().unwrap()
    );
    assert_eq!(
        sum(&ds, 1),
        side["value_sums_float64"]["temperature"].as_f64().unwrap()
    );
    assert_eq!(ds.channels()[0].stats.max, 4096.0);
    // 1024 odd values above 2048 changed: 4095 → 4096, 2931 → 2932, 2457 → 2456.
    let g = &ds.channels()[0].grid;
    let dense = g.to_dense();
    let changed = (0..4096).filter(|&n| dense[n] != n as f32).count();
    assert_eq!(
        changed as u64,
        side["half_rounded_value_count"]["density"]
            .as_u64()
            .unwrap()
    );
    assert_eq!(g.at(15, 15, 15), 4096.0);
    assert_eq!(g.at(3, 7, 11), 2932.0);
}

#[test]
fn sparse_blob_tree_with_partial_leaves() {
    let ds = load("vdb/sparse_blob.vdb", &["density", "temperature"]);
    let side = sidecar("vdb/sparse_blob.json");
    // Active index box [12, 51]³ → 40³ voxels; world = (i − 31.5)/32.
    assert_eq!(ds.dims(), [40, 40, 40]);
    let [p0, p1] = ds.bounds();
    assert!(
        (p0 - DVec3::splat((11.5 - 31.5) / 32.0))
            .abs()
            .max_element()
            < 1e-12,
        "{p0}"
    );
    assert!(
        (p1 - DVec3::splat((51.5 - 31.5) / 32.0))
            .abs()
            .max_element()
            < 1e-12,
        "{p1}"
    );
    check_samples(&ds, &side, &["density", "temperature"], [12, 12, 12], 0.0);
    for (c, name) in ["density", "temperature"].iter().enumerate() {
        let want = side["value_sums_float64_active"][name].as_f64().unwrap();
        assert!(
            (sum(&ds, c) / want - 1.0).abs() < 1e-9,
            "{name}: {} vs {want}",
            sum(&ds, c)
        );
        let mm = &side["min_max_active"][name];
        assert_eq!(ds.channels()[c].stats.max as f64, mm[1].as_f64().unwrap());
        let nonzero = ds.channels()[c]
            .grid
            .to_dense()
            .iter()
            .filter(|&&v| v != 0.0)
            .count();
        assert_eq!(
            nonzero as u64,
            side["active_voxel_count_per_grid"].as_u64().unwrap()
        );
    }
}

#[test]
fn mantaflow_fire_frames() {
    let side = sidecar("vdb/mantaflow_fire.json");
    for frame in ["mantaflow_fire_f030.vdb", "mantaflow_fire_f060.vdb"] {
        let ds = load(
            &format!("vdb/{frame}"),
            &["density", "temperature", "flame"],
        );
        let grids = side["files"][frame]["grids"].as_array().unwrap();
        for (c, name) in ["density", "temperature", "flame"].iter().enumerate() {
            let g = grids.iter().find(|g| g["name"] == *name).unwrap();
            let st = &ds.channels()[c].stats;
            assert_eq!(
                st.max as f64,
                g["max_active"].as_f64().unwrap(),
                "{frame} {name} max"
            );
            let nonzero = ds.channels()[c]
                .grid
                .to_dense()
                .iter()
                .filter(|&&v| v != 0.0)
                .count() as u64;
            assert_eq!(
                nonzero,
                g["dense_stats"]["nonzero_count"].as_u64().unwrap(),
                "{frame} {name}"
            );
            // dense_stats' mean is over the grid's own active box; all its non-zero voxels lie in ours.
            let bb = &g["active_index_bbox"];
            let cells: f64 = (0..3)
                .map(|k| (bb[1][k].as_i64().unwrap() - bb[0][k].as_i64().unwrap() + 1) as f64)
                .product();
            let want = g["dense_stats"]["mean"].as_f64().unwrap() * cells;
            assert!(
                (sum(&ds, c) / want - 1.0).abs() < 1e-6,
                "{frame} {name}: sum {} vs {want}",
                sum(&ds, c)
            );
        }
        // Transform: UniformScaleMap 1/32, no translation.
        let bb = &grids.iter().find(|g| g["name"] == "density").unwrap()["active_index_bbox"];
        let lo = bb[0][0].as_f64().unwrap();
        assert!((ds.bounds()[0].x - (lo - 0.5) / 32.0).abs() < 1e-12);
    }
}

/// Mantaflow's half-precision `velocity` (Tree_vec3s_5_4_3_HalfFloat) read as three components (`velocity.x`,
/// `.y`, `.z`): each component's extremes over the active voxels and the largest and mean magnitude are the
/// sidecar's (OpenVDB's own statistics of the same file).
#[test]
fn mantaflow_velocity_vector_grid() {
    let side = sidecar("vdb/mantaflow_fire.json");
    for frame in ["mantaflow_fire_f030.vdb", "mantaflow_fire_f060.vdb"] {
        let ds = load(
            &format!("vdb/{frame}"),
            &["velocity.x", "velocity.y", "velocity.z", "density"],
        );
        let grids = side["files"][frame]["grids"].as_array().unwrap();
        let g = grids.iter().find(|g| g["name"] == "velocity").unwrap();
        let st = &g["dense_stats"];
        let dense: Vec<Vec<f32>> = (0..3).map(|c| ds.channels()[c].grid.to_dense()).collect();
        for c in 0..3 {
            // Every extreme has the sign that makes the grid's zeros irrelevant to it.
            let lo = dense[c].iter().copied().fold(f32::MAX, f32::min) as f64;
            let hi = dense[c].iter().copied().fold(f32::MIN, f32::max) as f64;
            assert_eq!(
                lo,
                st["component_min_active"][c].as_f64().unwrap(),
                "{frame} {c} min"
            );
            assert_eq!(
                hi,
                st["component_max_active"][c].as_f64().unwrap(),
                "{frame} {c} max"
            );
        }
        // Active voxels are the density's (the sidecar: the same count); their magnitudes.
        let active = g["active_voxel_count"].as_u64().unwrap() as f64;
        let dens = ds.channels()[3].grid.to_dense();
        let (mut max, mut sum) = (0f64, 0f64);
        for i in 0..dens.len() {
            let m = (0..3)
                .map(|c| (dense[c][i] as f64).powi(2))
                .sum::<f64>()
                .sqrt();
            max = max.max(m);
            if dens[i] != 0.0 {
                sum += m;
            }
        }
        assert!(
            (max / st["max_magnitude"].as_f64().unwrap() - 1.0).abs() < 1e-6,
            "{frame} {max}"
        );
        let mean = st["mean_magnitude_active"].as_f64().unwrap();
        // (The mean over the density's non-zero voxels: the velocity's active set, less voxels where the
        // density is active at exactly zero — none here, as the counts agree.)
        assert!(
            (sum / active / mean - 1.0).abs() < 1e-3,
            "{frame} mean {} vs {mean}",
            sum / active
        );
    }
    // `auto` finds Mantaflow's `velocity` (the names tried: vel, v, velocity), value for value.
    let named = load(
        "vdb/mantaflow_fire_f030.vdb",
        &["velocity.x", "velocity.y", "velocity.z"],
    );
    let auto = load(
        "vdb/mantaflow_fire_f030.vdb",
        &["auto.x", "auto.y", "auto.z"],
    );
    for c in 0..3 {
        assert!(named.channels()[c].grid.to_dense() == auto.channels()[c].grid.to_dense());
    }
    let none = Dataset::load(
        &[ChannelSource::new("auto.x", data("vdb/ramp_16.vdb"))],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(none.contains("'vel' or 'v' or 'velocity'"), "{none}");
    // A component of a float grid, or an axis that is not x, y, z, is a missing grid naming those present.
    let err = Dataset::load(
        &[ChannelSource::new(
            "density.x",
            data("vdb/mantaflow_fire_f030.vdb"),
        )],
        &LoadOptions::default(),
    );
    assert!(err.is_err());
}

#[test]
fn nanovdb_ramp_plain_and_zip() {
    let side = sidecar("nvdb/ramp16.json");
    for file in ["nvdb/ramp16.nvdb", "nvdb/ramp16_zip.nvdb"] {
        let ds = load(file, &["density", "temperature"]);
        assert_eq!(ds.dims(), [16, 16, 16], "{file}");
        let [p0, p1] = ds.bounds();
        assert!(
            (p0 + DVec3::splat(0.5)).abs().max_element() < 1e-12
                && (p1 - DVec3::splat(0.5)).abs().max_element() < 1e-12,
            "{p0} {p1}"
        );
        for s in side["samples"].as_array().unwrap() {
            let ijk: Vec<i64> = s["ijk"]
                .as_array()
                .unwrap()
                .iter()
                .map(|v| v.as_i64().unwrap())
                .collect();
            let w = v3(&s["world_center"]);
            for (c, name) in ["density", "temperature"].iter().enumerate() {
                let want = s[*name].as_f64().unwrap() as f32;
                assert_eq!(
                    ds.channels()[c].grid.at(ijk[0], ijk[1], ijk[2]),
                    want,
                    "{file} {name} {ijk:?}"
                );
                assert_eq!(ds.sample(c, w), want, "{file} {name} at {w}");
            }
        }
        let g = &ds.channels()[0].grid;
        assert!((0..16)
            .all(|k| (0..16)
                .all(|j| (0..16).all(|i| g.at(i, j, k) == (i + 16 * j + 256 * k) as f32))));
    }
}

fn npy_f32(rel: &str) -> Vec<f32> {
    // NumPy .npy v1: magic, version, u16 header length, header, little-endian f32 data.
    let b = std::fs::read(data(rel)).unwrap();
    assert_eq!(&b[..6], b"\x93NUMPY");
    let hlen = u16::from_le_bytes([b[8], b[9]]) as usize;
    let header = std::str::from_utf8(&b[10..10 + hlen]).unwrap();
    assert!(
        header.contains("'<f4'") && header.contains("'fortran_order': False"),
        "{header}"
    );
    b[10 + hlen..]
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

#[test]
fn nanovdb_plume_matches_its_arrays() {
    let ds = load("nvdb/plume48.nvdb", &["density", "temperature"]);
    for (c, name) in ["density", "temperature"].iter().enumerate() {
        let arr = npy_f32(&format!("nvdb/plume48_{name}.npy"));
        assert_eq!(arr.len(), 48 * 48 * 48);
        // Our grid covers the active box; every array value outside it is zero.
        let lo = (0..3)
            .map(|k| ((ds.bounds()[0][k] + 0.5) * 48.0).round() as i64)
            .collect::<Vec<_>>();
        let g = &ds.channels()[c].grid;
        let mut checked = 0;
        for i in 0..48i64 {
            for j in 0..48i64 {
                for k in 0..48i64 {
                    let want = arr[((i * 48 + j) * 48 + k) as usize];
                    let got = g.at(i - lo[0], j - lo[1], k - lo[2]);
                    assert_eq!(got, want, "{name} ({i},{j},{k})");
                    checked += (want != 0.0) as usize;
                }
            }
        }
        assert!(checked > 1000);
    }
}

#[test]
fn missing_grid_names_the_ones_present() {
    let e = Dataset::load(
        &[ChannelSource::new("heat", data("vdb/ramp_16.vdb"))],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("a grid named 'heat'") && e.contains("'density', 'temperature'"),
        "{e}"
    );
    let e = Dataset::load(
        &[ChannelSource::new(
            "velocity",
            data("vdb/mantaflow_fire_f030.vdb"),
        )],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("unsupported") && e.contains("vec3s"), "{e}");
    let e = Dataset::load(
        &[ChannelSource::new("heat", data("nvdb/ramp16.nvdb"))],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("'density', 'temperature'"), "{e}");
}

/// `source "blender"` on Blender's own cache: the fire's temperature is its flame grid as Cycles maps it,
/// 1000 K · (1.5 + 1.5 · flame) where flame > 0 (Blender's default ignition and maximum), 0 elsewhere — the
/// hottest voxel from the sidecar's flame maximum; the file's own `temperature` grid (Mantaflow's heat, 0–3) is
/// not read.
#[test]
fn the_blender_source_reads_the_flame_as_cycles_does() {
    use firemedium_plugin::params::Param;
    use firemedium_plugin::volume::FireVolume;
    let side = sidecar("vdb/mantaflow_fire.json");
    let file = data("vdb/mantaflow_fire_f060.vdb");
    let grids = side["files"]["mantaflow_fire_f060.vdb"]["grids"]
        .as_array()
        .unwrap();
    let flame_max = grids.iter().find(|g| g["name"] == "flame").unwrap()["max_active"]
        .as_f64()
        .unwrap();
    let build = |extra: Vec<Param>| {
        let mut list = vec![
            Param::string("filename", &file.display().to_string()),
            Param::float("sootscale", 1e-6),
        ];
        list.extend(extra);
        FireVolume::new(&list)
    };
    let v = build(vec![Param::string("source", "blender")]).unwrap();
    let [lo, hi] = v.temperature_range().unwrap();
    let want = 1000.0 * (1.5 + 1.5 * flame_max);
    assert!(
        lo == 0.0 && (hi / want - 1.0).abs() < 1e-6,
        "{lo} {hi} vs {want}"
    );
    let names: Vec<&str> = v
        .dataset()
        .channels()
        .iter()
        .map(|c| c.name.as_str())
        .collect();
    assert_eq!(names, ["density", "temperature"]);
    // The domain's own settings.
    let v = build(vec![
        Param::string("source", "blender"),
        Param::float("flameignition", 1.0),
        Param::float("flamemax", 2.0),
    ])
    .unwrap();
    let hi = v.temperature_range().unwrap()[1];
    assert!(
        (hi / (1000.0 * (1.0 + flame_max)) - 1.0).abs() < 1e-6,
        "{hi}"
    );
    // Its mapping is its own; the flame settings belong to it.
    for (extra, name) in [
        (
            vec![
                Param::string("source", "blender"),
                Param::float("temperaturescale", 1000.0),
            ],
            "temperaturescale",
        ),
        (
            vec![
                Param::string("source", "kelvin"),
                Param::float("flamemax", 2.0),
            ],
            "flamemax",
        ),
        (
            vec![
                Param::string("source", "blender"),
                Param::float("flameignition", 2.0),
                Param::float("flamemax", 2.0),
            ],
            "flamemax",
        ),
    ] {
        let e = build(extra).unwrap_err().to_string();
        assert!(e.contains(name), "{e}");
    }
}
