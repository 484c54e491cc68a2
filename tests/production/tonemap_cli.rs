//! `firemedium tonemap` end to end: the default scene rendered once (its EXR records the fire's hottest
//! temperature), then tone-mapped for night and for daylight adaptation; the flame is closer to white at night.

use std::path::Path;
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(crate::common::exe("firemedium"))
}

fn run(args: &[&str]) -> Output {
    bin().args(args).output().unwrap()
}

use crate::common::scratch;

/// The test's scratch folder (removed when it passes).
fn tmp(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("tonemap", name)
}

/// 8-bit RGB PNG pixels in [0, 1] (sRGB-encoded).
fn read_png(path: &Path) -> (usize, usize, Vec<[f64; 3]>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0u8; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let px = buf[..info.buffer_size()]
        .chunks(3)
        .map(|c| {
            [
                c[0] as f64 / 255.0,
                c[1] as f64 / 255.0,
                c[2] as f64 / 255.0,
            ]
        })
        .collect();
    (info.width as usize, info.height as usize, px)
}

/// Linear-sRGB EXR pixels (cd/m² scale).
fn read_exr(path: &Path) -> Vec<[f32; 3]> {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.x() + *w * pos.y()] = [r, g, b],
    )
    .unwrap();
    img.layer_data.channel_data.pixels.1
}

/// HSV saturation (max − min) / max of a display pixel.
/// The largest difference of one channel between two images' pixels.
fn max_difference(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(p, q)| (0..3).map(move |k| (p[k] - q[k]).abs()))
        .fold(0.0, f64::max)
}

fn saturation(p: [f64; 3]) -> f64 {
    let (hi, lo) = (p[0].max(p[1]).max(p[2]), p[0].min(p[1]).min(p[2]));
    if hi > 0.0 {
        (hi - lo) / hi
    } else {
        0.0
    }
}

#[test]
fn night_makes_the_flame_whiter_than_day() {
    let scene = crate::common::root().join("scenes/mantaflow/scene.pbrt");
    let dir = tmp("adapt");
    let exr = dir.join("room.exr");
    let o = bin()
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&exr)
        .args(["--spp", "2", "--resolution", "80x60", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let hdr = read_exr(&exr);
    let y =
        |p: [f32; 3]| 0.2126729 * p[0] as f64 + 0.7151522 * p[1] as f64 + 0.0721750 * p[2] as f64;
    // The flame's pixels: above the floor's horizon (the upper half of the view; the room is black there) and
    // brighter than 1e3 cd/m² (its core reaches ~2e7; the fire-lit floor below is 1e4–4e4 cd/m²).
    let flame: Vec<usize> = (0..hdr.len() / 2).filter(|&i| y(hdr[i]) > 1e3).collect();
    assert!(flame.len() > 20, "{} flame pixels", flame.len());
    let mut sat = Vec::new();
    for adapt in ["night", "day"] {
        let png = dir.join(format!("{adapt}.png"));
        let o = run(&[
            "tonemap",
            exr.to_str().unwrap(),
            "-o",
            png.to_str().unwrap(),
            "--adapt",
            adapt,
            "--white",
            "fire",
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = String::from_utf8_lossy(&o.stdout);
        // The white is the render's fire: the Mantaflow frame's 2.9746 × 1000 K.
        assert!(
            text.contains("white blackbody 2975 K (the render's fire)"),
            "{text}"
        );
        let (w, h, px) = read_png(&png);
        assert_eq!((w, h), (80, 60));
        sat.push(flame.iter().map(|&i| saturation(px[i])).sum::<f64>() / flame.len() as f64);
    }
    eprintln!(
        "flame saturation: night {:.3}, day {:.3} ({} pixels)",
        sat[0],
        sat[1],
        flame.len()
    );
    assert!(sat[0] + 0.05 < sat[1], "night {} vs day {}", sat[0], sat[1]);
    // `render --adapt night --operator naka-rushton` writes the same preview as `tonemap --adapt night` of its EXR (within one 8-bit
    // level: the EXR holds f32 RGB, the render its f64 XYZ).
    let night_render = dir.join("room_night.exr");
    let o = bin()
        .arg("render")
        .arg(&scene)
        .arg("-o")
        .arg(&night_render)
        .args([
            "--spp",
            "2",
            "--resolution",
            "80x60",
            "--quiet",
            "--adapt",
            "night",
            "--operator",
            "naka-rushton",
            "--white",
            "fire",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, a) = read_png(&night_render.with_extension("png"));
    let (_, _, b) = read_png(&dir.join("night.png"));
    let worst = max_difference(&a, &b);
    assert!(
        worst <= 1.0 / 255.0 + 1e-9,
        "render's night preview differs by {worst}"
    );
    // 16-bit output, the other operators, an explicit white.
    for extra in [
        &["--bits", "16"][..],
        &["--operator", "exposure", "--exposure", "-1"],
        &["--operator", "reinhard", "--white", "d65"],
        &["--white", "0.3127,0.3290", "--adapt", "250"],
    ] {
        let png = dir.join("extra.png");
        let o = bin()
            .args([
                "tonemap",
                exr.to_str().unwrap(),
                "-o",
                png.to_str().unwrap(),
            ])
            .args(extra)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{extra:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let dec = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(dir.join("extra.png")).unwrap(),
    ));
    assert_eq!(
        dec.read_info().unwrap().info().bit_depth,
        png::BitDepth::Eight
    );
}

#[test]
fn bad_arguments_exit_2_and_bad_files_exit_1() {
    let dir = tmp("bad");
    let out = dir.join("o.png");
    let out = out.to_str().unwrap();
    for (args, want) in [
        (vec!["x.exr", "-o", out, "--adapt", "-3"], "cd/m²"),
        (vec!["x.exr", "-o", out, "--adapt", "dusk"], "night"),
        (vec!["x.exr", "-o", out, "--white", "5K"], "300–100000"),
        (vec!["x.exr", "-o", out, "--bits", "12"], "bits"),
        (vec!["x.exr", "-o", out, "--operator", "filmic"], "'filmic'"),
    ] {
        let o = run(&[&["tonemap"][..], &args].concat());
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.lines().count() == 1 && e.contains(want), "{args:?}: {e}");
    }
    // A file that is not an EXR: exit 1, naming it.
    let fake = dir.join("fake.exr");
    std::fs::write(&fake, b"not an exr").unwrap();
    let o = run(&["tonemap", fake.to_str().unwrap(), "-o", out]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("fake.exr") && e.contains("EXR"), "{e}");
}

#[test]
fn the_renders_preview_is_tonemaps_default_and_keeps_the_fires_colour() {
    // `render` and `tonemap` share one default (Naka–Rushton adapted to the image, a D65 white): re-tonemapping a
    // render's EXR with no option gives its preview. With that white the flame keeps its colour — orange, red
    // above blue — where the fire's own white (`--white fire`) turns its core neutral.
    let dir = tmp("one-default");
    let exr = dir.join("campfire.exr");
    let o = run(&[
        "render",
        crate::common::root()
            .join("scenes/campfire/scene.pbrt")
            .to_str()
            .unwrap(),
        "-o",
        exr.to_str().unwrap(),
        "--resolution",
        "96x54",
        "--spp",
        "8",
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let again = dir.join("again.png");
    let o = run(&[
        "tonemap",
        exr.to_str().unwrap(),
        "-o",
        again.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, a) = read_png(&exr.with_extension("png"));
    let (_, _, b) = read_png(&again);
    let worst = max_difference(&a, &b);
    assert!(
        worst <= 1.0 / 255.0 + 1e-9,
        "preview and tonemap differ by {worst}"
    );
    // The flame's pixels (the brightest tenth in the EXR): their mean colour in the preview is warm and
    // saturated; with the fire's white it is near grey.
    let hdr = read_exr(&exr);
    let y = |p: &[f32; 3]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let mut ys: Vec<f64> = hdr.iter().map(y).collect();
    ys.sort_by(f64::total_cmp);
    let cut = ys[ys.len() * 9 / 10];
    let flame: Vec<usize> = (0..hdr.len()).filter(|&i| y(&hdr[i]) > cut).collect();
    let mean = |px: &[[f64; 3]]| {
        let mut m = [0.0; 3];
        for &i in &flame {
            for k in 0..3 {
                m[k] += px[i][k] / flame.len() as f64;
            }
        }
        m
    };
    let fire_white = dir.join("fire-white.png");
    let o = run(&[
        "tonemap",
        exr.to_str().unwrap(),
        "-o",
        fire_white.to_str().unwrap(),
        "--white",
        "fire",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, c) = read_png(&fire_white);
    let (warm, neutral) = (mean(&a), mean(&c));
    assert!(
        warm[0] > warm[1] && warm[1] > warm[2] && saturation(warm) > 0.4,
        "default {warm:?}"
    );
    assert!(
        saturation(neutral) < saturation(warm) / 2.0,
        "fire white {neutral:?} against {warm:?}"
    );
}
