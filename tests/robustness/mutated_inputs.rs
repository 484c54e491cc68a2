//! The host's own readers under deterministic mutation: EXR and PNG images (environment maps, image textures,
//! `compare` and `tonemap` inputs) and PLY meshes, plain and gzipped. Every mutant must give an image/mesh or a one-line error that
//! names the file — never a panic, and never pixels allocated past the budget their header is checked against.
//! (The dataset readers have their own mutation test in the plugin; the built binary is fuzzed by
//! tools/mutants.py; fuzz/ holds cargo-fuzz targets over the same entry points.)

use crate::common::mutate;

use firemedium::imageio::{decode, write_exr, write_png_bytes, ImageKind};
use firemedium::render::ply;
use mutate::{mutate, Rng};

const BUDGET: u64 = 64 << 20;

/// A file in this test's own folder (tests run in parallel, and writers clean up each other's temporaries).
fn tmp(test: &str, name: &str) -> std::path::PathBuf {
    let d = folder(test);
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// This test's folder (the caller removes it when done with its files).
fn folder(test: &str) -> std::path::PathBuf {
    std::env::temp_dir().join(format!("firemedium-mutated-{}-{test}", std::process::id()))
}

/// Valid files to mutate: (name, bytes, what reads them).
fn seeds(test: &str) -> Vec<(&'static str, Vec<u8>, Option<ImageKind>)> {
    let (w, h) = (7, 5);
    let rgb: Vec<[f32; 3]> = (0..w * h)
        .map(|i| [i as f32, 0.5, 1.0 / (1.0 + i as f32)])
        .collect();
    let exr = tmp(test, "seed.exr");
    write_exr(&exr, w, h, &rgb, Some(1500.0)).unwrap();
    let png8 = tmp(test, "seed8.png");
    let bytes: Vec<u8> = (0..w * h * 3).map(|i| (i * 7) as u8).collect();
    write_png_bytes(&png8, w, h, &bytes, false).unwrap();
    let png16 = tmp(test, "seed16.png");
    let bytes: Vec<u8> = (0..w * h * 6).map(|i| (i * 13) as u8).collect();
    write_png_bytes(&png16, w, h, &bytes, true).unwrap();
    let header = "ply\nformat {F} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n";
    let mut ascii = header.replace("{F}", "ascii");
    let mut binary = header.replace("{F}", "binary_little_endian").into_bytes();
    for v in 0..4 {
        let (x, y) = ((v & 1) as f32, (v >> 1) as f32);
        let vals = [x, y, 0.0, 0.0, 0.0, 1.0, x, y];
        ascii += &format!("{}\n", vals.map(|f| f.to_string()).join(" "));
        for f in vals {
            binary.extend_from_slice(&f.to_le_bytes());
        }
    }
    ascii += "3 0 1 2\n4 0 1 3 2\n";
    binary.push(3);
    for k in [0i32, 1, 2] {
        binary.extend_from_slice(&k.to_le_bytes());
    }
    binary.push(4);
    for k in [0i32, 1, 3, 2] {
        binary.extend_from_slice(&k.to_le_bytes());
    }
    let seeds = vec![
        ("m.exr", std::fs::read(exr).unwrap(), Some(ImageKind::Exr)),
        ("m8.png", std::fs::read(png8).unwrap(), Some(ImageKind::Png)),
        (
            "m16.png",
            std::fs::read(png16).unwrap(),
            Some(ImageKind::Png),
        ),
        ("ascii.ply", ascii.into_bytes(), None),
        ("binary.ply", binary, None),
    ];
    // (Read into memory: the files are not needed any more.)
    let _ = std::fs::remove_dir_all(folder(test));
    seeds
}

fn read(name: &str, bytes: &[u8], kind: Option<ImageKind>) -> Result<usize, firemedium::Error> {
    match kind {
        Some(k) => decode(name, bytes, k, true, BUDGET).map(|img| img.w * img.h),
        None => ply::parse(name, bytes).map(|m| m.1.len()),
    }
}

#[test]
fn the_seeds_read_back() {
    for (name, bytes, kind) in seeds("seeds") {
        let n = read(name, &bytes, kind).unwrap_or_else(|e| panic!("{e}"));
        // 35 pixels, or 3 + 6 triangle indices (the quad split in two).
        assert_eq!(n, if kind.is_some() { 35 } else { 9 }, "{name}");
    }
}

#[test]
fn mutated_images_and_meshes_never_panic() {
    let mut rng = Rng::new(2027);
    let (mut ok, mut err) = (0, 0);
    for (name, bytes, kind) in seeds("mutants") {
        for i in 0..1200 {
            let m = mutate(&mut rng, &bytes);
            match std::panic::catch_unwind(|| read(name, &m, kind)) {
                Ok(Ok(_)) => ok += 1,
                Ok(Err(e)) => {
                    assert!(
                        e.to_string().starts_with(name) && !e.to_string().contains('\n'),
                        "{name} mutation #{i}: {e}"
                    );
                    err += 1;
                }
                Err(_) => panic!("{name} mutation #{i} panicked"),
            }
        }
    }
    // Gzipped meshes (`.ply.gz`): the gzip member and the mesh inside, inflated within a 1 MB budget.
    let ascii = &seeds("mutants")[3].1;
    let mut gz = vec![0x1f, 0x8b, 8, 8, 0, 0, 0, 0, 0, 0xff, b'm', 0];
    gz.extend(miniz_oxide::deflate::compress_to_vec(ascii, 9));
    gz.extend([0u8; 4]);
    gz.extend((ascii.len() as u32).to_le_bytes());
    for i in 0..1200 {
        let m = mutate(&mut rng, &gz);
        let r = std::panic::catch_unwind(|| {
            ply::gunzip("m.ply.gz", &m, 1 << 20).and_then(|b| ply::parse("m.ply.gz", &b))
        });
        match r {
            Ok(Ok(_)) => ok += 1,
            Ok(Err(e)) => {
                assert!(
                    e.to_string().starts_with("m.ply.gz") && !e.to_string().contains('\n'),
                    "gz mutation #{i}: {e}"
                );
                err += 1;
            }
            Err(_) => panic!("gz mutation #{i} panicked"),
        }
    }
    eprintln!("image and mesh mutations: {ok} read, {err} refused with an error, 0 panics");
    assert!(ok > 100 && err > 1000, "{ok} read, {err} refused");
}

#[test]
fn an_image_header_claiming_more_than_the_budget_is_refused_before_its_pixels() {
    // A PNG whose IHDR claims 60 000 × 60 000 pixels (43 GB as f32 RGB) in 57 bytes.
    let png8 = tmp("huge", "huge.png");
    write_png_bytes(&png8, 1, 1, &[1, 2, 3], false).unwrap();
    let mut b = std::fs::read(&png8).unwrap();
    let _ = std::fs::remove_dir_all(folder("huge"));
    b[16..20].copy_from_slice(&60_000u32.to_be_bytes());
    b[20..24].copy_from_slice(&60_000u32.to_be_bytes());
    // The chunk's CRC-32 (ISO 3309, as the PNG specification defines it) over its type and data.
    let crc = !b[12..29].iter().fold(!0u32, |c, &x| {
        (0..8).fold(c ^ x as u32, |c, _| {
            if c & 1 == 1 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            }
        })
    });
    b[29..33].copy_from_slice(&crc.to_be_bytes());
    let e = decode("huge.png", &b, ImageKind::Png, true, BUDGET)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("huge.png") && e.contains("60000×60000") && e.contains("budget"),
        "{e}"
    );
}
