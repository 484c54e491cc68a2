//! pbrt-v4 fidelity, end to end: scenes written for pbrt-v4 render at pbrt-v4's own pixel values (its film,
//! its light normalisation, its grid media's peak-normalised blackbody), checked against numbers measured by
//! running pbrt-v4 itself (`../shared/data/pbrt-v4-measured/`) and against closed forms from its definitions.

#[path = "common/image.rs"]
mod image;

use image::read_exr;
use std::path::{Path, PathBuf};
use std::process::Command;

fn shared(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data").join(rel)
}

fn out_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("firemedium-pbrt-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Renders `scene` and returns its pixels (w, h, rgb).
fn render(scene: &Path, out: &Path, extra: &[&str]) -> (usize, usize, Vec<[f32; 3]>) {
    let o = Command::new(env!("CARGO_BIN_EXE_firemedium"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["-q", "--seed", "5"])
        .args(extra)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    read_exr(out)
}

/// Mean linear-sRGB colour over a pixel rectangle [x0, x1) × [y0, y1).
fn mean_rgb(img: &(usize, usize, Vec<[f32; 3]>), x: (usize, usize), y: (usize, usize)) -> [f64; 3] {
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

fn y_of(rgb: [f64; 3]) -> f64 {
    0.2126729 * rgb[0] + 0.7151522 * rgb[1] + 0.0721750 * rgb[2]
}

/// The slab scenes' two regions, inside their edges: the grid's box [0, 1] (x) × [0, 1] (z) and the light's
/// quad [1.2, 2.2] × [0, 1], seen from (1.1, −20, 0.5) looking along +y on a 64 × 32 film 4 × 2 units wide (16
/// pixels per unit; pbrt's camera space is left-handed, so world x grows to the left: pixel i is x = 3.1 − i/16).
const BOX: ((usize, usize), (usize, usize)) = ((36, 48), (10, 22));
const LIGHT: ((usize, usize), (usize, usize)) = ((16, 29), (10, 22));

#[test]
fn measure_slabs() {
    let dir = out_dir("slab");
    for name in ["slab_const", "slab"] {
        let img = render(
            &shared(&format!("pbrt-v4-measured/{name}.pbrt")),
            &dir.join(format!("{name}.exr")),
            &["--spp", "64"],
        );
        let f = mean_rgb(&img, BOX.0, BOX.1);
        let l = mean_rgb(&img, LIGHT.0, LIGHT.1);
        eprintln!("{name}: fire {f:?} Y {} light {l:?} Y {}", y_of(f), y_of(l));
    }
}
