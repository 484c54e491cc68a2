//! Bad input never panics and always says what is wrong: a replay of the invalid corpus in
//! tests/data/invalid (each file with the error it must give), and deterministic mutations of every valid file
//! (bit flips, overwrites, truncations, splices), each of which must load or fail with an error — never panic.

use firemedium_plugin::dataset::{ChannelSource, Dataset, Format, LoadOptions};
use std::path::PathBuf;

#[path = "../../tests/common/mutate.rs"]
mod mutate;
use mutate::{mutate, Rng};

fn path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(rel)
}

#[test]
fn invalid_corpus_gives_the_right_errors() {
    // (file, channel, format, substrings the one-line error must contain)
    let cases: &[(&str, &str, Option<Format>, &[&str])] = &[
        (
            "empty.vdb",
            "density",
            None,
            &[
                "empty.vdb: byte 0",
                "8 bytes of the OpenVDB magic",
                "truncated",
            ],
        ),
        (
            "bad_magic.vdb",
            "density",
            None,
            &["byte 0", "magic number 0x56444220"],
        ),
        (
            "bad_version.vdb",
            "density",
            None,
            &["unsupported", "OpenVDB file version 100"],
        ),
        (
            "truncated_header.vdb",
            "density",
            None,
            &["grid 'density' descriptor", "within the file of 300 bytes"],
        ),
        (
            "truncated_blocks.vdb",
            "density",
            None,
            &["truncated_blocks.vdb", "within the file of 12000 bytes"],
        ),
        (
            "corrupt_blosc.vdb",
            "density",
            None,
            &["corrupt_blosc.vdb: byte"],
        ),
        (
            "bad_magic.nvdb",
            "density",
            None,
            &["byte 0", "NanoVDB magic", "NanoVDB9"],
        ),
        (
            "truncated.nvdb",
            "density",
            None,
            &["truncated.nvdb", "grid 'density'", "truncated"],
        ),
        // Found by `cargo fuzz run nanovdb`: a zero-length read past the end used to panic.
        (
            "fuzz_nanovdb_record_past_end.nvdb",
            "density",
            None,
            &[
                "the grid name after its 176-byte record",
                "offset 192 past its end (191 bytes)",
            ],
        ),
        (
            "count_mismatch.raw2",
            "density",
            None,
            &["byte 12", "104 bytes for 2 voxels", "60 bytes"],
        ),
        (
            "coordinate_out_of_range.raw2",
            "density",
            None,
            &["byte 16 (voxel 1 of 1)", "within 4×4×4", "(1, 5, 1)"],
        ),
        (
            "huge_dims.raw2",
            "density",
            None,
            &["memory cap", "1073741824×1073741824×8"],
        ),
        (
            "negative_dims.raw2",
            "density",
            None,
            &["byte 4", "positive height", "-4"],
        ),
        (
            "overflow_dims.txt",
            "density",
            None,
            &["line 1, column 1", "width", "'4294967296'"],
        ),
        (
            "text_value.txt",
            "density",
            None,
            &["line 3, column 6", "value 4 of 4", "'abc'"],
        ),
        (
            "too_few_values.txt",
            "density",
            None,
            &["line 3, column 1", "value 6 of 8", "end of the file"],
        ),
        (
            "too_many_values.txt",
            "density",
            None,
            &[
                "line 2, column 5",
                "end of the file after the 2 values",
                "'3'",
            ],
        ),
        (
            "nan_density.txt",
            "density",
            None,
            &["channel 'density', voxel (1, 0, 0)", "finite value", "NaN"],
        ),
        (
            "inf_density.txt",
            "density",
            None,
            &["voxel (0, 0, 0)", "inf"],
        ),
        (
            "negative_density.txt",
            "density",
            None,
            &["voxel (1, 0, 0)", ">= 0", "-0.25"],
        ),
        ("binary.txt", "density", None, &["byte 7", "ASCII text"]),
        (
            "sparse_out_of_range.txt",
            "density",
            Some(Format::AsciiSparse),
            &[
                "line 4, column 5",
                "coordinate z of voxel 1 of 1 (0..3)",
                "'7'",
            ],
        ),
    ];
    let listed: Vec<&str> = cases.iter().map(|c| c.0).collect();
    let mut on_disk: Vec<String> = std::fs::read_dir(path("invalid"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    on_disk.sort();
    for f in &on_disk {
        assert!(
            listed.contains(&f.as_str()),
            "tests/data/invalid/{f} has no expected error in this table"
        );
    }
    for (file, channel, format, want) in cases {
        let opts = LoadOptions {
            format: *format,
            max_bytes: 1 << 30,
            ..LoadOptions::default()
        };
        let r = Dataset::load(
            &[ChannelSource::new(
                channel,
                path(&format!("invalid/{file}")),
            )],
            &opts,
        );
        let e = match r {
            Ok(_) => panic!("{file}: loaded, expected an error"),
            Err(e) => e.to_string(),
        };
        assert!(!e.contains('\n'), "{file}: multi-line error: {e}");
        for w in *want {
            assert!(e.contains(w), "{file}: error lacks '{w}': {e}");
        }
    }
}

#[test]
fn mutated_files_never_panic() {
    let raw2 = {
        let mut v = Vec::new();
        for d in [5i32, 4, 3] {
            v.extend_from_slice(&d.to_le_bytes());
        }
        v.extend_from_slice(&2i32.to_le_bytes());
        for (c, r) in [([1i32, 1, 1], 128.0), ([5, 3, 4], 64.0)] {
            for x in c {
                v.extend_from_slice(&x.to_le_bytes());
            }
            for x in [r, 0.0, 0.0, 1.0f64] {
                v.extend_from_slice(&x.to_le_bytes());
            }
        }
        v
    };
    let seeds: Vec<(Format, Vec<u8>, Vec<&str>)> = vec![
        (
            Format::Vdb,
            std::fs::read(path("valid/vdb/ramp_16.vdb")).unwrap(),
            vec!["density", "temperature"],
        ),
        (
            Format::Vdb,
            std::fs::read(path("valid/vdb/ramp_16_zip.vdb")).unwrap(),
            vec!["density"],
        ),
        (
            Format::Vdb,
            std::fs::read(path("valid/vdb/two_grids_half.vdb")).unwrap(),
            vec!["temperature"],
        ),
        (
            Format::NanoVdb,
            std::fs::read(path("valid/nvdb/ramp16_zip.nvdb")).unwrap(),
            vec!["density", "temperature"],
        ),
        (Format::Raw2, raw2, vec!["density"]),
        (
            Format::AsciiDense,
            b"3 2 2\n0 1 2 3 4 5\n6 7 8 9 10 11\n".to_vec(),
            vec!["density"],
        ),
        (
            Format::AsciiSparse,
            b"3 2 2\n2\n0.5\n0 0 0 7\n2 1 1 9\n".to_vec(),
            vec!["density"],
        ),
    ];
    // A small cap: mutated sizes must be refused before allocating, not allocate gigabytes.
    let opts = LoadOptions {
        max_bytes: 64 << 20,
        ..LoadOptions::default()
    };
    let mut rng = Rng::new(2026);
    let (mut ok, mut err) = (0, 0);
    for (format, seed, names) in &seeds {
        let n = if *format == Format::Vdb { 400 } else { 600 };
        for i in 0..n {
            let m = mutate(&mut rng, seed);
            let r = std::panic::catch_unwind(|| {
                Dataset::from_bytes(*format, "mutant", &m, names, &opts)
            });
            match r {
                Ok(Ok(_)) => ok += 1,
                Ok(Err(e)) => {
                    let s = e.to_string();
                    assert!(
                        s.starts_with("mutant") || s.starts_with("dataset:"),
                        "{format:?} #{i}: {s}"
                    );
                    err += 1;
                }
                Err(_) => panic!("{format:?} mutation #{i} panicked"),
            }
        }
    }
    eprintln!("mutations: {ok} loaded, {err} refused with an error, 0 panics");
    assert!(err > 1000 && ok > 100, "{ok} ok, {err} errors");
}

#[test]
fn grids_share_one_memory_cap() {
    // A mutant of the fuzz run (tools/mutants.py: a leaf moved far away) with every float grid asked for: their
    // active box makes four 2176×128×768 grids (855 MB each, dense). Each passed a 1 GB cap alone and the four
    // together took 3.2 GB; they share the cap, refused before anything is allocated.
    //
    // With sparse storage the far leaf costs its own brick, not the box: at 1 GB the four grids fit (and the
    // mutant's corrupt block is what the load then reports); under a cap their bricks together exceed but one
    // alone would not, they are still refused before anything is allocated.
    let file = path("fuzz/fuzz_vdb_grids_share_the_cap.vdb");
    // Every float grid of the file loaded under a cap: (grids asked for, the load's error).
    let load_all = |max_bytes: u64| {
        let opts = LoadOptions {
            max_bytes,
            ..LoadOptions::default()
        };
        let grids = firemedium_plugin::dataset::list_grids(&file, &opts).unwrap();
        let sources: Vec<ChannelSource> = grids
            .iter()
            .filter(|g| g.loadable)
            .map(|g| ChannelSource::new(&g.name, file.clone()))
            .collect();
        let e = Dataset::load(&sources, &opts).unwrap_err().to_string();
        (sources.len(), e)
    };
    let (_, e) = load_all(1_000_000_000);
    assert!(e.contains("expected a stored block of 1024 bytes"), "{e}");
    let (n, e) = load_all(2_000_000);
    assert_eq!(n, 4);
    // 768 bricks, those under the mutant's constant tiles sharing blocks: 279 blocks of 2 KB per grid (the
    // background's besides), 0.57 MB each where the dense box took 855 MB, and a two-level brick table: one grid
    // fits a 2 MB cap, the four together (2.3 MB) do not.
    assert!(
        e.contains("4 grids of 279 blocks")
            && e.contains("needs 2310552 bytes, above the memory cap of 2000000 bytes"),
        "{e}"
    );
}
