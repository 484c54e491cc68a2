//! End-to-end renders through the built `firemedium` binary and the built plugin cdylib, a file per concern:
//! renders against closed forms and their twins, scenes as users write them, what a render leaves, the faults it
//! survives, and what the documentation promises. The helpers more than one of them uses live here.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::image;
use image::{luminance, mean_y, read_exr};

use crate::common::scratch;

use crate::common::guard;

mod closed_forms;
mod docs;
mod faults;
mod outputs;
mod scenes;

/// The test's scratch folder (removed when it passes).
fn tmp(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("render", name)
}

/// `dir/s.pbrt`: a white sky seen by a `px`² film at 1 spp — the smallest scene that renders.
fn sky_scene(dir: &Path, px: u32) -> PathBuf {
    let scene = dir.join("s.pbrt");
    std::fs::write(
        &scene,
        format!("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" {px} \"integer yresolution\" {px}\nSampler \"independent\" \"integer pixelsamples\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"),
    )
    .unwrap();
    scene
}

/// `firemedium ARGS` run in `dir`.
fn firemedium_in(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(crate::common::exe("firemedium"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// Whether two EXRs hold the same render: the same pixels, bit for bit, and the same record but for the render
/// time (the one line two renders of a scene differ in).
fn same_render(a: &Path, b: &Path) -> bool {
    let record = |p: &Path| firemedium::imageio::read_meta(p).unwrap();
    let ((wa, ma), (wb, mb)) = (record(a), record(b));
    read_exr(a) == read_exr(b)
        && wa == wb
        && firemedium::imageio::record_differences(&ma, &mb).is_none()
}

fn render(scene: &Path, extra: &[&str]) -> PathBuf {
    let out = scene.with_extension("exr");
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(&out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "render {}: {}\n{}",
        scene.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

fn inline_grid(n: usize, density: f64, temperature: f64) -> String {
    let d = vec![format!("{density}"); n * n * n].join(" ");
    let t = vec![format!("{temperature}"); n * n * n].join(" ");
    format!("\"integer nx\" {n} \"integer ny\" {n} \"integer nz\" {n} \"float density\" [{d}] \"float temperature\" [{t}]")
}

/// The plugin this test run built, and a C shim plugin (`tests/c/SRC`, built against the header) that forwards to it
/// through `FIREMEDIUM_REAL_PLUGIN`: (real, shim).
fn shim_plugin(dir: &Path, src: &str) -> (PathBuf, PathBuf) {
    let root = crate::common::root();
    let bin = crate::common::exe("firemedium");
    let real = bin.parent().unwrap().join("deps").join(format!(
        "{}firemedium_plugin{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    assert!(real.is_file(), "{} not built", real.display());
    let shim = dir.join(format!("lib{}", src.replace(".c", ".so")));
    let cc = Command::new("gcc")
        .args(["-std=c11", "-Wall", "-Werror", "-shared", "-fPIC", "-I"])
        .arg(root.join("plugin/abi/include"))
        .arg(root.join("tests/c").join(src))
        .arg("-o")
        .arg(&shim)
        .arg("-ldl")
        .output()
        .unwrap();
    assert!(
        cc.status.success(),
        "{}",
        String::from_utf8_lossy(&cc.stderr)
    );
    (real, shim)
}

/// An 8 × 8 film looking at a 4³ soot fire at 1600 K inside a sphere, `spp` samples a pixel.
fn small_fire_scene(spp: usize) -> String {
    format!(
        "LookAt 0 -3 0.5  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" {spp}\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"float sootscale\" 1e-6\nAttributeBegin\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 2\nAttributeEnd\n",
        inline_grid(4, 1.0, 1600.0)
    )
}

fn write_exr_map(path: &Path, w: usize, h: usize, f: impl Fn(f32, f32) -> f32 + Sync) {
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let v = f((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        (v, v, v)
    })
    .unwrap();
}
