//! The dataset component against small files it writes itself: every format, policies, mappings, frames.

use super::*;
use vdb::VdbLeaf;

#[test]
fn a_large_file_read_in_parts_is_the_file() {
    // Above the parallel threshold, with a length that does not split evenly: every byte where it was.
    let n = (9 << 20) + 12_345;
    let bytes: Vec<u8> = (0..n).map(|i| (i * 7 + i / 251) as u8).collect();
    let path = tmp("large.bin", &bytes);
    assert_eq!(read_file(&path).expect("readable"), bytes);
    let e = read_file(&path.with_extension("missing"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("large.missing"), "{e}");
}

fn tmp(name: &str, content: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("firemedium-ds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, content).unwrap();
    p
}

#[test]
fn frame_patterns() {
    let p = |s: &str, f| frame_path(Path::new(s), f).map(|p| p.display().to_string());
    assert_eq!(p("fire_####.vdb", Some(7)).unwrap(), "fire_0007.vdb");
    assert_eq!(p("fire_##.vdb", Some(123)).unwrap(), "fire_123.vdb");
    assert_eq!(p("fire_%04d.vdb", Some(42)).unwrap(), "fire_0042.vdb");
    assert_eq!(p("fire_%d.vdb", Some(42)).unwrap(), "fire_42.vdb");
    assert_eq!(p("fire.vdb", Some(42)).unwrap(), "fire.vdb");
    assert_eq!(p("100%.vdb", Some(1)).unwrap(), "100%.vdb");
    assert!(p("fire_####.vdb", None)
        .unwrap_err()
        .to_string()
        .contains("frame"));
}

#[test]
fn frame_sequence_loads_the_right_file() {
    tmp("seq_0001.txt", b"1 1 1\n1.5\n");
    let p2 = tmp("seq_0002.txt", b"1 1 1\n2.5\n");
    let pattern = p2.parent().unwrap().join("seq_####.txt");
    for (f, want) in [(1, 1.5), (2, 2.5)] {
        let ds = Dataset::load(
            &[ChannelSource::new("density", &pattern)],
            &LoadOptions {
                frame: Some(f),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(ds.channels()[0].grid.to_dense(), &[want]);
        assert!(ds.channels()[0]
            .report
            .file
            .ends_with(&format!("seq_000{f}.txt")));
    }
    let e = Dataset::load(
        &[ChannelSource::new("density", &pattern)],
        &LoadOptions {
            frame: Some(3),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("seq_0003.txt: cannot read"), "{e}");
}

#[test]
fn two_ascii_channels_share_a_grid_and_map() {
    let d = tmp("d.txt", b"2 1 1\n0.5 1\n");
    let t = tmp("t.txt", b"2 1 1\n1.5 2\n");
    let mut temp = ChannelSource::new("temperature", &t);
    temp.mapping = Mapping {
        scale: 1000.0,
        offset: 0.0,
        pbrt_offset: 0.5,
        zero_at_or_below: None,
    };
    let opts = LoadOptions {
        bounds: Some([DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 1.0)]),
        ..Default::default()
    };
    let ds = Dataset::load(&[ChannelSource::new("density", &d), temp], &opts).unwrap();
    assert_eq!(ds.dims(), [2, 1, 1]);
    assert_eq!(
        ds.channel("temperature").unwrap().grid.to_dense(),
        &[1000.0, 1500.0]
    );
    // The centre of voxel 1 is at x = 0.5 in medium space.
    assert_eq!(ds.sample(0, DVec3::new(0.5, 0.5, 0.5)), 1.0);
    assert_eq!(ds.sample(1, DVec3::new(-0.5, 0.5, 0.5)), 1000.0);
    assert_eq!(ds.sample(0, DVec3::new(2.0, 0.5, 0.5)), 0.0);
    let r = &ds.channels()[0].report;
    // Storage is by 8³ bricks: the one brick holding the two voxels, and the background's.
    assert_eq!(r.bytes, 2 * 512 * 4);
    assert!(r.load_seconds >= 0.0);
    // Mismatched dims are an error naming both.
    let t3 = tmp("t3.txt", b"3 1 1\n1 2 3\n");
    let e = Dataset::load(
        &[
            ChannelSource::new("density", &d),
            ChannelSource::new("temperature", &t3),
        ],
        &opts,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("3×1×1") && e.contains("2×1×1") && e.contains("'density'"),
        "{e}"
    );
}

#[test]
fn nan_and_negative_policies() {
    let f = tmp("nan.txt", b"2 1 1\nnan -3\n");
    let e = Dataset::load(
        &[ChannelSource::new("density", &f)],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("nan.txt") && e.contains("voxel (0, 0, 0)") && e.contains("NaN"),
        "{e}"
    );
    let opts = LoadOptions {
        nonfinite: Policy::Zero,
        ..Default::default()
    };
    let e = Dataset::load(&[ChannelSource::new("density", &f)], &opts)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("voxel (1, 0, 0)") && e.contains("-3") && e.contains(">= 0"),
        "{e}"
    );
    let opts = LoadOptions {
        nonfinite: Policy::Zero,
        negative: Policy::Zero,
        ..Default::default()
    };
    let ds = Dataset::load(&[ChannelSource::new("density", &f)], &opts).unwrap();
    assert_eq!(ds.channels()[0].grid.to_dense(), &[0.0, 0.0]);
    assert_eq!(
        (
            ds.channels()[0].report.replaced_nonfinite,
            ds.channels()[0].report.replaced_negative
        ),
        (1, 1)
    );
    let inf = tmp("inf.txt", b"1 1 1\ninf\n");
    assert!(Dataset::load(
        &[ChannelSource::new("density", &inf)],
        &LoadOptions::default()
    )
    .unwrap_err()
    .to_string()
    .contains("inf"));
}

#[test]
fn inline_arrays_like_pbrt() {
    let dens = [0.0f32, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
    let ds = Dataset::from_inline(
        [2, 2, 2],
        DVec3::splat(-1.0),
        DVec3::splat(1.0),
        &[("density", &dens)],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(ds.format(), Format::Inline);
    assert_eq!(ds.sample(0, DVec3::new(0.5, 0.5, 0.5)), 7.0);
    assert_eq!(ds.sample(0, DVec3::new(-0.5, -0.5, -0.5)), 0.0);
    assert_eq!(ds.sample(0, DVec3::ZERO), 3.5);
    let e = Dataset::from_inline(
        [2, 2, 3],
        DVec3::ZERO,
        DVec3::ONE,
        &[("density", &dens)],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("8 values") && e.contains("2·2·3 = 12"), "{e}");
    let e = Dataset::from_inline(
        [2, 2, 2],
        DVec3::ONE,
        DVec3::ZERO,
        &[("density", &dens)],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("p0 < p1"), "{e}");
}

#[test]
fn raw_files_through_the_public_loader() {
    // raw2: dims 4×3×2; voxel (3, 2, 1) 0-based is stored 1-based x, z, y = (4, 2, 3).
    let f = tmp(
        "fire.raw2",
        &raw::encode(Some([4, 3, 2]), &[([4, 2, 3], [64.0, 200.0, 0.0, 1.0])]),
    );
    let ds = Dataset::load(
        &[ChannelSource::new("density", &f)],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!((ds.format(), ds.dims()), (Format::Raw2, [4, 3, 2]));
    assert_eq!(ds.channels()[0].grid.at(3, 2, 1), 0.25);
    let opts = LoadOptions {
        raw_value: RawValue::MaxRgb,
        ..Default::default()
    };
    assert_eq!(
        Dataset::load(&[ChannelSource::new("density", &f)], &opts)
            .unwrap()
            .channels()[0]
            .grid
            .at(3, 2, 1),
        200.0 / 256.0
    );
    // Headerless raw: the grid is raw_dims (256³ by default).
    let f = tmp(
        "fire.raw",
        &raw::encode(None, &[([1, 1, 1], [256.0, 0.0, 0.0, 1.0])]),
    );
    let opts = LoadOptions {
        raw_dims: [8, 8, 8],
        ..Default::default()
    };
    let ds = Dataset::load(&[ChannelSource::new("density", &f)], &opts).unwrap();
    assert_eq!(
        (ds.dims(), ds.channels()[0].grid.at(0, 0, 0)),
        ([8, 8, 8], 1.0)
    );
    let ds = Dataset::load(
        &[ChannelSource::new("density", &f)],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(ds.dims(), [256, 256, 256]);
    // Two channels from one single-grid file is an error.
    let e = Dataset::load(
        &[
            ChannelSource::new("density", &f),
            ChannelSource::new("temperature", &f),
        ],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("one channel per raw file"), "{e}");
}

#[test]
fn missing_file_unknown_extension_and_binary_as_text() {
    let e = Dataset::load(
        &[ChannelSource::new("density", "/no/such/file.vdb")],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("/no/such/file.vdb: cannot read"), "{e}");
    let e = Dataset::load(
        &[ChannelSource::new("density", "fire.xyz")],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("format") && e.contains("fire.xyz"), "{e}");
    let b = tmp("bin.txt", &[b'1', b' ', 0xff, 0xfe]);
    let e = Dataset::load(
        &[ChannelSource::new("density", &b)],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("byte 2") && e.contains("not text"), "{e}");
    assert!(Format::from_name("obj")
        .unwrap_err()
        .to_string()
        .contains("ascii, asciisparse"));
}

#[test]
fn sparse_files_are_streamed_by_offset_as_they_decode_from_memory() {
    // Three grids over 2 MB each (the read window is 1 MB: it refills mid-grid); the scene names two.
    let dims = [96, 80, 72];
    let n = dims[0] * dims[1] * dims[2];
    let wave = |k: f32| -> Vec<f32> {
        (0..n)
            .map(|i| {
                let v = ((i as f32) * 0.001 * k).sin();
                if v > 0.2 {
                    v
                } else {
                    0.0
                }
            })
            .collect()
    };
    let (d, t, junk) = (wave(1.0), wave(1.7), wave(2.3));
    let bytes = vdb::write(
        &[
            ("junk", dims, &junk),
            ("density", dims, &d),
            ("temperature", dims, &t),
        ],
        DVec3::ZERO,
        DVec3::splat(0.1),
    );
    assert!(bytes.len() > 6 << 20, "{}", bytes.len());
    let path = tmp("streamed.vdb", &bytes);
    let names = ["temperature", "density"];
    let sources: Vec<ChannelSource> = names.iter().map(|n| ChannelSource::new(n, &path)).collect();
    let opts = LoadOptions::default();
    let from_file = Dataset::load(&sources, &opts).expect("loads from the file");
    let from_memory = Dataset::from_bytes(Format::Vdb, "m.vdb", &bytes, &names, &opts).unwrap();
    for (a, b) in from_file.channels().iter().zip(from_memory.channels()) {
        assert_eq!(a.grid.to_dense(), b.grid.to_dense(), "{}", a.name);
    }
    assert_eq!(
        from_file.channels()[1].grid.to_dense().iter().sum::<f32>(),
        d.iter().sum::<f32>()
    );
    // Cut inside the density's leaf values: the same error from the file as from memory (file, byte, what).
    let cut = &bytes[..bytes.len() * 5 / 9];
    let path = tmp("streamed-cut.vdb", cut);
    let e_file = Dataset::load(&[ChannelSource::new("density", &path)], &opts)
        .unwrap_err()
        .to_string();
    let e_mem = Dataset::from_bytes(
        Format::Vdb,
        &path.display().to_string(),
        cut,
        &["density"],
        &opts,
    )
    .unwrap_err()
    .to_string();
    assert_eq!(e_file, e_mem);
    assert!(
        e_file.contains("streamed-cut.vdb") && e_file.contains("byte "),
        "{e_file}"
    );
    // NanoVDB alike: the grids named are read by offset (its density and temperature, each alone).
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/data/valid/nvdb/plume48.nvdb");
    let nano = std::fs::read(&path).unwrap();
    for name in ["density", "temperature"] {
        let a = Dataset::load(&[ChannelSource::new(name, &path)], &opts).unwrap();
        let b = Dataset::from_bytes(Format::NanoVdb, "m.nvdb", &nano, &[name], &opts).unwrap();
        assert_eq!(
            a.channels()[0].grid.to_dense(),
            b.channels()[0].grid.to_dense()
        );
        assert!(a.channels()[0].grid.to_dense().iter().any(|&v| v > 0.0));
    }
}

#[test]
fn constant_tiles_share_one_block_per_value() {
    // A fog volume as OpenVDB's prune leaves it: a 128³ tile (density 0.5, temperature 1500 K), an 8³ tile of
    // density beside it over a leaf of temperature, and a leaf of density beyond.
    let ramp = |o: [i32; 3], k: f32| -> VdbLeaf {
        let vals: Vec<f32> = (0..512).map(|i| k + i as f32).collect();
        (o, [u64::MAX; 8], vals)
    };
    let bytes = vdb::write_tiled(
        &[
            (
                "density",
                vec![ramp([136, 0, 0], 1.0)],
                vec![([0, 0, 0], 128, 0.5), ([128, 0, 0], 8, 0.25)],
            ),
            (
                "temperature",
                vec![ramp([128, 0, 0], 1000.0)],
                vec![([0, 0, 0], 128, 1500.0)],
            ),
        ],
        DVec3::ZERO,
        DVec3::splat(0.1),
    );
    assert!(bytes.len() < 400_000, "{}", bytes.len()); // (mostly the nodes' tables of tile values)
    let ds = Dataset::from_bytes(
        Format::Vdb,
        "fog.vdb",
        &bytes,
        &["density", "temperature"],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(ds.dims(), [144, 128, 128]);
    let leaf = |i: i64, j: i64, k: i64, o: i64, base: f32| base + (64 * (i - o) + 8 * j + k) as f32;
    let want_d = |i: i64, j: i64, k: i64| match i {
        _ if i < 128 => 0.5,
        _ if j >= 8 || k >= 8 => 0.0,
        _ if i < 136 => 0.25,
        _ => leaf(i, j, k, 136, 1.0),
    };
    let want_t = |i: i64, j: i64, k: i64| match i {
        _ if i < 128 => 1500.0,
        _ if j >= 8 || k >= 8 || i >= 136 => 0.0,
        _ => leaf(i, j, k, 128, 1000.0),
    };
    let (d, t) = (&ds.channels()[0].grid, &ds.channels()[1].grid);
    for k in 0..128 {
        for j in 0..128 {
            for i in 0..144 {
                assert_eq!(d.at(i, j, k), want_d(i, j, k), "density ({i}, {j}, {k})");
                assert_eq!(
                    t.at(i, j, k),
                    want_t(i, j, k),
                    "temperature ({i}, {j}, {k})"
                );
            }
        }
    }
    // 4 096 bricks under the big tile share one block; the two bricks a leaf touches have their own.
    let topo = d.topology();
    assert_eq!(topo.active_bricks(), 4096 + 2);
    assert_eq!(topo.blocks_stored(), 3);
    assert_eq!(d.bytes(), 4 * 512 * 4);
    // Interpolation across a shared block's faces reads the neighbours' values (a dense copy agrees).
    let dense = Grid::new(ds.dims(), d.to_dense()).unwrap();
    for p in [
        [0.5, 0.5, 0.5],
        [0.886, 0.03, 0.02],
        [0.89, 0.031, 0.031],
        [0.999, 0.01, 0.01],
    ] {
        assert_eq!(
            d.lookup(p, Interpolation::Trilinear),
            dense.lookup(p, Interpolation::Trilinear),
            "{p:?}"
        );
    }
    let s = d.stats();
    assert_eq!(s.max, leaf(143, 7, 7, 136, 1.0));
}

#[test]
fn an_ascii_grid_on_one_long_line_loads_and_errors_name_the_column() {
    // 40³ values on one line (the column of every token was counted from the line's start: quadratic, and a
    // 160³ grid on one line never finished loading); a bad value at the end is reported at its column.
    let n = 40;
    let mut vals: Vec<String> = (0..n * n * n)
        .map(|i| {
            if i % 97 == 0 {
                "0.5".into()
            } else {
                "0".into()
            }
        })
        .collect();
    let text = format!("{n} {n} {n}\n{}\n", vals.join(" "));
    let path = tmp("long-line.txt", text.as_bytes());
    let ds = Dataset::load(
        &[ChannelSource::new("density", &path)],
        &LoadOptions::default(),
    )
    .unwrap();
    let g = &ds.channels()[0].grid;
    assert_eq!(g.at(0, 0, 0), 0.5);
    assert_eq!(g.at(97 % 40, 97 / 40, 0), 0.5);
    assert_eq!(g.at(1, 0, 0), 0.0);
    // Stored as bricks where the values are, never dense.
    assert!(g.topology().active_bricks() <= 125);
    let last = vals.len() - 1;
    vals[last] = "x".into();
    let text = format!("{n} {n} {n}\n{}\n", vals.join(" "));
    let col = text.lines().nth(1).unwrap().len();
    let path = tmp("long-line-bad.txt", text.as_bytes());
    let e = Dataset::load(
        &[ChannelSource::new("density", &path)],
        &LoadOptions::default(),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains(&format!("line 2, column {col}")) && e.contains("'x'"),
        "{e}"
    );
}
