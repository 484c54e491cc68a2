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
    // The dataset named beside the scene; kelvin is the default, so no source line; the box is the data's.
    assert!(
        text.contains("\"string dataset\" \"campfire.vdb\"") && !text.contains("string source"),
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
