//! `firemedium compare SCENE.pbrt REFERENCE.exr IMAGE.exr…`: the error of renders against a reference, over the
//! pixels where the camera sees a diffuse surface (so the fire seen directly or in a mirror — the same in every
//! render — does not drown the lighting error). Used for the fire light's equal-time comparison
//! (docs/results/log.md).

use crate::args::parse_resolution;
use clap::Args;
use firemedium::imageio::{self as image, RgbImage};
use firemedium::metrics::{errors, luminance};
use firemedium::render::{scene, surface_mask};
use firemedium::Error;
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct CompareArgs {
    /// The scene the images were rendered from (for the surface mask).
    scene: PathBuf,
    /// The reference image (EXR).
    reference: PathBuf,
    /// Images to compare (EXR, same resolution).
    #[arg(required = true)]
    images: Vec<PathBuf>,
    /// The film resolution the images were rendered at, if not the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<(usize, usize)>,
    /// The fire plugin library (default: as for `render`).
    #[arg(long)]
    plugin: Option<PathBuf>,
}

pub fn run(a: &CompareArgs) -> firemedium::Result<String> {
    let ov = scene::Overrides {
        spp: None,
        plugin: a.plugin.clone(),
        no_fire_light: true,
        fire_light_weighting: None,
        res: a.resolution,
        threads: None,
        max_memory: None,
        ..Default::default()
    };
    let sc = scene::load(&a.scene, &ov)?;
    let (w, h) = sc.res;
    let reference = image::read(&a.reference, false)?;
    let check = |img: &RgbImage, p: &PathBuf| {
        if (img.w, img.h) == (w, h) {
            Ok(())
        } else {
            Err(Error::input(format!(
                    "{} is {}×{} pixels where the scene renders {w}×{h}: compare images of one size, and give \
                     --resolution {}x{} if they were rendered at that size",
                    p.display(),
                    img.w,
                    img.h,
                    img.w,
                    img.h
                ),
            ))
        }
    };
    check(&reference, &a.reference)?;
    let mut rng = firemedium_core::rng::Rng::new(0);
    let mask = surface_mask(&sc, &mut rng);
    let count = mask.iter().filter(|&&m| m).count();
    if count == 0 {
        return Err(Error::input(format!(
            "{}: no pixel sees a surface",
            a.scene.display()
        )));
    }
    let mean_ref = (0..w * h)
        .filter(|&i| mask[i])
        .map(|i| luminance(reference.px[i]))
        .sum::<f64>()
        / count as f64;
    let mut out = format!(
        "{count} surface pixels of {}; reference mean luminance {mean_ref:.6e}\n",
        w * h
    );
    let mut first = None;
    for p in &a.images {
        let img = image::read(p, false)?;
        check(&img, p)?;
        let mut se: Vec<f64> = (0..w * h)
            .filter(|&i| mask[i])
            .map(|i| (luminance(img.px[i]) - luminance(reference.px[i])).powi(2))
            .collect();
        let mse = se.iter().sum::<f64>() / count as f64;
        se.sort_by(|a, b| b.total_cmp(a));
        let top = se[..count.div_ceil(100)].iter().sum::<f64>() / (mse * count as f64).max(1e-300);
        let mean = (0..w * h)
            .filter(|&i| mask[i])
            .map(|i| luminance(img.px[i]))
            .sum::<f64>()
            / count as f64;
        let masked = |img: &RgbImage| -> Vec<f64> {
            (0..w * h)
                .filter(|&i| mask[i])
                .map(|i| luminance(img.px[i]))
                .collect()
        };
        let (_, rel_mse) = errors(&masked(&img), &masked(&reference));
        let base = *first.get_or_insert(mse);
        out += &format!(
            "{}: MSE {mse:.6e}, relative {:.6e}, relMSE {rel_mse:.6e}, {:.3}× the first; mean {:+.4} % off the reference's; the worst 1 % of pixels hold {:.1} % of the error\n",
            p.display(),
            mse / (mean_ref * mean_ref).max(1e-300),
            mse / base.max(1e-300),
            100.0 * (mean / mean_ref - 1.0),
            100.0 * top
        );
    }
    Ok(out)
}
