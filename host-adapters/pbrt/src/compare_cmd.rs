//! `firemedium compare SCENE.pbrt REFERENCE.exr IMAGE.exr…`: the error of renders against a reference, over the
//! pixels where the camera sees a diffuse surface (so the fire seen directly or in a mirror — the same in every
//! render — does not drown the lighting error). Used for the fire light's equal-time comparison
//! (docs/RESULTS.md).

use crate::render::{self, image, scene};
use clap::Args;
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
    #[arg(long, value_name = "WxH", value_parser = crate::render_cmd::parse_resolution)]
    resolution: Option<(usize, usize)>,
    /// The fire plugin library (default: as for `render`).
    #[arg(long)]
    plugin: Option<PathBuf>,
}

/// Rec. 709 luminance of linear sRGB.
fn luminance(p: [f32; 3]) -> f64 {
    0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64
}

/// The pixels whose centre and four corners all see a diffuse surface first: no fire, no mirror or coating
/// reflecting it, inside the pixel's footprint.
pub fn surface_mask(sc: &scene::Scene, rng: &mut firemedium_core::rng::Rng) -> Vec<bool> {
    let (w, h) = sc.res;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .all(|&(u, v)| {
                    let (o, d) = render::camera_ray(sc, x + u, y + v, rng);
                    sc.bvh
                        .intersect(o, d, sc.eps, f32::INFINITY)
                        .and_then(|hit| sc.bvh.prims[hit.prim].material)
                        .is_some_and(|m| matches!(sc.materials[m], scene::Material::Diffuse(_)))
                })
        })
        .collect()
}

pub fn run(a: &CompareArgs) -> Result<String, (u8, String)> {
    let ov = scene::Overrides {
        spp: None,
        plugin: a.plugin.clone(),
        no_fire_light: true,
        fire_light_weighting: None,
        res: a.resolution,
    };
    let sc = scene::load(&a.scene, &ov).map_err(|e| (1, e))?;
    let (w, h) = sc.res;
    let reference = image::read(&a.reference, false).map_err(|e| (1, e))?;
    let check = |img: &image::RgbImage, p: &PathBuf| {
        if (img.w, img.h) == (w, h) {
            Ok(())
        } else {
            Err((
                1,
                format!(
                    "{}: {}×{} pixels, the scene (and the reference) are {w}×{h}",
                    p.display(),
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
        return Err((1, format!("{}: no pixel sees a surface", a.scene.display())));
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
        let img = image::read(p, false).map_err(|e| (1, e))?;
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
        // relMSE as DESIGN.md defines it: mean((a − r)² / (r² + 0.01·mean(r)²)).
        let rel_mse = (0..w * h)
            .filter(|&i| mask[i])
            .map(|i| {
                let (a, r) = (luminance(img.px[i]), luminance(reference.px[i]));
                (a - r).powi(2) / (r * r + 0.01 * mean_ref * mean_ref).max(1e-300)
            })
            .sum::<f64>()
            / count as f64;
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
