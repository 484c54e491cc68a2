//! The spectral bins' own error: the luminance of a fire marched with N bins against the same march with many
//! more, for the plain per-bin CMF weights (`cie::bin_integrals`) and the weights of the spectrum rebuilt from
//! its bin means (`cie::bin_weights`, what the volume uses).
//!
//!     cargo run --release -p firemedium-plugin --example spectral_bins -- DATASET [PIXELS] [STEP] [BINS,BINS,…]
//!
//! Default: the committed campfire, 96 pixels, ½ voxel, 12,16,20,24,30,240 (the last is the reference). The
//! camera is the perf bench's pinhole. Last, what the default range (400–700 nm, DESIGN) leaves out: the
//! reference against the same march over ȳ's whole support, 380–780 nm, at the reference's bin width. Results
//! are in docs/results/log.md.

use firemedium_plugin::cie::{bin_integrals, bin_weights};
use firemedium_plugin::params::Param;
use firemedium_plugin::spectrum::SpectralGrid;
use firemedium_plugin::volume::FireVolume;
use glam::DVec3;

mod common;

/// The f64 march of `file` with `bins` bins over [lo, hi] nm and steps of `step` voxels.
fn volume(file: &str, bins: usize, step: f64, (lo, hi): (f64, f64)) -> FireVolume {
    FireVolume::new(&[
        Param::string("filename", file),
        Param::int("bins", bins as i64),
        Param::float("lambdamin", lo),
        Param::float("lambdamax", hi),
        Param::float("stepsize", step),
        Param::string("precision", "f64"),
    ])
    .unwrap_or_else(|e| panic!("{e}"))
}

/// Each pixel's radiance per bin (f64 march).
fn render(v: &FireVolume, size: usize) -> Vec<Vec<f64>> {
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    common::pinhole_rays(v, size)
        .map(|ray| {
            v.integrate(&ray, &mut l, &mut t);
            l.clone()
        })
        .collect()
}

/// Luminance of each pixel with per-bin weights `w`.
fn luminance(img: &[Vec<f64>], w: &[DVec3]) -> Vec<f64> {
    img.iter()
        .map(|l| l.iter().zip(w).map(|(a, b)| a * b.y).sum())
        .collect()
}

fn main() {
    let (args, file) = common::args_and_dataset();
    let size: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(96);
    let step: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.5);
    let bins: Vec<usize> = args
        .get(3)
        .map(|s| s.split(',').filter_map(|b| b.parse().ok()).collect())
        .unwrap_or_else(|| vec![12, 16, 20, 24, 30, 240]);
    let range = args
        .get(4)
        .and_then(|s| s.split_once('-'))
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((400.0, 700.0));
    let runs: Vec<(usize, Vec<Vec<f64>>)> = bins
        .iter()
        .map(|&n| (n, render(&volume(&file, n, step, range), size)))
        .collect();
    let grid = |n: usize| SpectralGrid::new(range.0, range.1, n).unwrap_or_else(|e| panic!("{e}"));
    let Some((n_ref, img_ref)) = runs.last() else {
        return;
    };
    let reference = luminance(img_ref, &bin_weights(&grid(*n_ref)));
    let norm: f64 = reference.iter().map(|y| y * y).sum::<f64>();
    let total: f64 = reference.iter().sum();
    println!("{file}, {size}² pixels, step {step} voxel, against {n_ref} bins (rebuilt weights)\n");
    println!(
        "| bins | plain weights: rel. RMSE | mean bias | rebuilt weights: rel. RMSE | mean bias |"
    );
    println!("|---|---|---|---|---|");
    for (n, img) in &runs {
        let stats = |w: &[DVec3]| {
            let y = luminance(img, w);
            let se: f64 = y.iter().zip(&reference).map(|(a, b)| (a - b).powi(2)).sum();
            ((se / norm).sqrt(), y.iter().sum::<f64>() / total - 1.0)
        };
        let (p, pb) = stats(&bin_integrals(&grid(*n)));
        let (r, rb) = stats(&bin_weights(&grid(*n)));
        println!("| {n} | {p:.3e} | {pb:+.3e} | {r:.3e} | {rb:+.3e} |");
    }
    // The range: the reference's bin width over 380–780 nm.
    let width = (range.1 - range.0) / *n_ref as f64;
    let n_wide = (400.0 / width).round() as usize;
    let wide = volume(&file, n_wide, step, (380.0, 780.0));
    let w = bin_weights(&SpectralGrid::new(380.0, 780.0, n_wide).unwrap_or_else(|e| panic!("{e}")));
    let y = luminance(&render(&wide, size), &w);
    let se: f64 = y.iter().zip(&reference).map(|(a, b)| (a - b).powi(2)).sum();
    let norm_wide: f64 = y.iter().map(|v| v * v).sum();
    println!(
        "\n{}–{} nm against 380–780 nm ({} bins): rel. RMSE {:.3e}, luminance {:+.3e}",
        range.0,
        range.1,
        n_wide,
        (se / norm_wide).sqrt(),
        total / y.iter().sum::<f64>() - 1.0
    );
}
