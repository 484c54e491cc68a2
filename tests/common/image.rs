//! Reading the renders the end-to-end tests write: EXR pixels, luminance, means. Included by `#[path]`.
#![allow(dead_code)]

use std::path::Path;

/// (width, height, linear sRGB pixels).
pub fn read_exr(path: &Path) -> (usize, usize, Vec<[f32; 3]>) {
    use exr::prelude::*;
    let img = read_first_rgba_layer_from_file(
        path,
        |res, _| {
            (
                res.width(),
                res.height(),
                vec![[0f32; 3]; res.width() * res.height()],
            )
        },
        |(w, _, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            px[pos.x() + *w * pos.y()] = [r, g, b]
        },
    )
    .unwrap();
    img.layer_data.channel_data.pixels
}

pub fn luminance(p: [f32; 3]) -> f64 {
    // Y row of sRGB → XYZ (D65).
    0.2126729 * p[0] as f64 + 0.7151522 * p[1] as f64 + 0.0721750 * p[2] as f64
}

pub fn mean_y(px: &[[f32; 3]]) -> f64 {
    px.iter().map(|p| luminance(*p)).sum::<f64>() / px.len() as f64
}
