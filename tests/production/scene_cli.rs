//! `firemedium scene DATASET`: a starter scene a user's first render of their own fire needs nothing else for.

use crate::common::{exe, root, scratch::Scratch};
use std::path::Path;
use std::process::Command;

fn firemedium(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(exe("firemedium"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn a_starter_scene_frames_the_users_fire_and_renders_it() {
    let dir = Scratch::new("scene", "starter");
    for f in [
        "scenes/campfire/campfire.vdb",
        "tests/data/valid/vdb/mantaflow_fire_f060.vdb",
    ] {
        std::fs::copy(root().join(f), dir.join(Path::new(f).file_name().unwrap())).unwrap();
    }
    let o = firemedium(&dir, &["scene", "campfire.vdb"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("campfire.pbrt")).unwrap();
    // The dataset named beside the scene, its convention written out (a generic kelvin file, its density a soot
    // volume fraction already); the box is the data's.
    assert!(
        text.contains("\"string dataset\" \"campfire.vdb\"")
            && text.contains("\"string source\" \"kelvin\"")
            && text.contains("\"float sootscale\" 1\n"),
        "{text}"
    );
    assert!(
        text.contains("-0.6 -0.6 0.0349") && text.contains("0.566667 0.6 1.6 ]"),
        "{text}"
    );
    // It renders as written, with no warning (the camera outside the box, the box holding the data).
    let o = firemedium(
        &dir,
        &[
            "render",
            "campfire.pbrt",
            "--resolution",
            "64x36",
            "--spp",
            "4",
            "-o",
            "c.exr",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success() && !err.contains("warning"), "{err}");
    let img = firemedium::imageio::read(&dir.join("c.exr"), false).unwrap();
    // The fire lies in the frame: its brightest pixel well inside it.
    let (i, _) = img
        .px
        .iter()
        .enumerate()
        .map(|(i, p)| (i, p[0] + p[1] + p[2]))
        .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
    let (x, y) = (i % img.w, i / img.w);
    assert!(
        (8..56).contains(&x) && (4..34).contains(&y),
        "brightest at ({x}, {y})"
    );
    // A Mantaflow cache gets its convention.
    let o = firemedium(
        &dir,
        &["scene", "mantaflow_fire_f060.vdb", "-o", "smoke.pbrt"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("smoke.pbrt")).unwrap();
    assert!(
        text.contains("\"string source\" \"blender\"") && text.contains("smoke.exr"),
        "{text}"
    );
    // An existing scene is kept unless --force.
    let o = firemedium(&dir, &["scene", "campfire.vdb"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("campfire.pbrt: exists") && err.contains("--force"),
        "{err}"
    );
    assert!(firemedium(&dir, &["scene", "campfire.vdb", "--force"])
        .status
        .success());
}

#[test]
fn a_file_without_a_float_grid_is_not_a_fire() {
    let dir = Scratch::new("scene", "nogrid");
    let bytes = firemedium_dataset::vdb::write_with_vectors(
        &[],
        &[(
            "vel",
            [8, 8, 8],
            [&[1f32; 512][..], &[0f32; 512][..], &[0f32; 512][..]],
        )],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.1),
    );
    std::fs::write(dir.join("vel.vdb"), bytes).unwrap();
    let o = firemedium(&dir, &["scene", "vel.vdb"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("vel.vdb") && err.contains("no float grid"),
        "{err}"
    );
    assert!(!dir.join("vel.pbrt").exists());
}

/// A dataset in `dir` at `name` holding `grids` over an n³ lattice of 5 cm voxels (x fastest).
fn write_grids(dir: &Path, name: &str, n: usize, grids: &[(&str, Vec<f32>)]) {
    let list: Vec<(&str, [usize; 3], &[f32])> = grids
        .iter()
        .map(|(g, v)| (*g, [n, n, n], v.as_slice()))
        .collect();
    let bytes = firemedium_dataset::vdb::write(&list, glam::DVec3::ZERO, glam::DVec3::splat(0.05));
    std::fs::write(dir.join(name), bytes).unwrap();
}

#[test]
fn odd_files_are_said_plainly() {
    let dir = Scratch::new("scene", "odd");
    let n = 16;
    let at = |f: &dyn Fn(usize, usize, usize) -> f32| -> Vec<f32> {
        (0..n * n * n)
            .map(|i| f(i % n, (i / n) % n, i / (n * n)))
            .collect()
    };
    let cube = |i: usize, j: usize, k: usize| {
        if (4..12).contains(&i) && (4..12).contains(&j) && (4..12).contains(&k) {
            1.0
        } else {
            0.0
        }
    };
    // Smoke alone: no grid carries heat; refused, the file's grids listed, nothing written.
    write_grids(&dir, "smoke.vdb", n, &[("density", at(&cube))]);
    let o = firemedium(&dir, &["scene", "smoke.vdb"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("smoke.vdb") && err.contains("'density'") && err.contains("heat"),
        "{err}"
    );
    assert!(!dir.join("smoke.pbrt").exists());
    // Empty grids: refused, naming them.
    write_grids(
        &dir,
        "empty.vdb",
        n,
        &[
            ("density", vec![0.0; n * n * n]),
            ("temperature", vec![0.0; n * n * n]),
        ],
    );
    let o = firemedium(&dir, &["scene", "empty.vdb"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(1) && err.contains("empty.vdb") && err.contains("empty"),
        "{err}"
    );
    // A temperature peaking at 200: neither kelvin that glows nor a relative one — written, with a warning that
    // says how to map it.
    let warm = at(&|i, j, k| 200.0 * cube(i, j, k));
    write_grids(
        &dir,
        "cool.vdb",
        n,
        &[("density", at(&cube)), ("temperature", warm)],
    );
    let o = firemedium(&dir, &["scene", "cool.vdb"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("warning: the temperature grid 'temperature' peaks at 200")
            && out.contains("temperatureremap"),
        "{out}"
    );
    // A plume rising along the diagonal of y and z: two candidate up axes, said, the tool's convention taken.
    let rise = |j: usize, k: usize| (j + k) as f32 / (2 * n) as f32;
    let dens = at(&|i, j, k| {
        if (6..10).contains(&i) {
            rise(j, k)
        } else {
            0.0
        }
    });
    let temp = at(&|i, j, k| {
        if (6..10).contains(&i) && rise(j, k) < 0.25 {
            1500.0
        } else if (6..10).contains(&i) {
            400.0
        } else {
            0.0
        }
    });
    write_grids(
        &dir,
        "tilted.vdb",
        n,
        &[("density", dens), ("temperature", temp)],
    );
    let o = firemedium(&dir, &["scene", "tilted.vdb"]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        out.contains("warning: two candidate up axes, +y") && out.contains("+z taken"),
        "{out}"
    );
    // --up settles it; a scene named as the dataset is refused before anything is read.
    let o = firemedium(&dir, &["scene", "tilted.vdb", "--up", "y", "--force"]);
    assert!(o.status.success() && !String::from_utf8_lossy(&o.stdout).contains("warning"));
    let o = firemedium(
        &dir,
        &["scene", "tilted.vdb", "-o", "tilted.vdb", "--force"],
    );
    assert!(
        o.status.code() == Some(1)
            && String::from_utf8_lossy(&o.stderr).contains("is the dataset itself"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(firemedium_dataset::list_grids(
        &dir.join("tilted.vdb"),
        &firemedium_dataset::LoadOptions::default()
    )
    .is_ok());
}
