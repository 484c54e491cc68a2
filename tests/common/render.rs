//! Rendering scenes with the built binary, for the end-to-end tests: where fixtures and outputs live, one
//! quiet render, means over pixel rectangles. Included by `#[path]` (with `image.rs`).

use super::image::read_exr;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A file of the repository's test data (`tests/data`, each copied from the project's reference data with its
/// source named in `tests/data/README.md`).
pub fn data(rel: &str) -> PathBuf {
    super::root().join("tests/data").join(rel)
}

/// The text of a test-data file; a failure names the path.
pub fn read_text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

pub use super::scratch;

/// The test's scratch folder (removed when it passes).
pub fn out_dir(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("test", name)
}

/// Runs `firemedium render scene -o out args…` and returns what it did (status, stderr).
pub fn run_render(scene: &Path, out: &Path, args: &[&str]) -> std::process::Output {
    Command::new(super::exe("firemedium"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(args)
        .output()
        .unwrap()
}

/// Renders `scene` quietly with seed 5 (and `extra`), which must succeed, and returns its pixels (w, h, rgb).
pub fn render(scene: &Path, out: &Path, extra: &[&str]) -> (usize, usize, Vec<[f32; 3]>) {
    let o = run_render(scene, out, &[&["-q", "--seed", "5"], extra].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    read_exr(out)
}

/// Mean linear-sRGB colour over a pixel rectangle [x0, x1) × [y0, y1).
pub fn mean_rgb(
    img: &(usize, usize, Vec<[f32; 3]>),
    x: (usize, usize),
    y: (usize, usize),
) -> [f64; 3] {
    let mut s = [0.0; 3];
    let mut n = 0.0;
    for j in y.0..y.1 {
        for i in x.0..x.1 {
            let p = img.2[i + img.0 * j];
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
            n += 1.0;
        }
    }
    s.map(|v| v / n)
}

pub fn y_of(rgb: [f64; 3]) -> f64 {
    0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2]
}
