//! `firemedium bench noise`: every render's own estimate of its error against its true error, and adaptive
//! against uniform sampling at equal true error, on the campfire scene and the fire-lit room.
//!
//! The true error is the whole image's, over luminance, against a reference rendered in two halves whose
//! difference takes the reference's own noise out ([`firemedium::metrics::errors_debiased`]): relative RMSE for
//! the estimate (what the estimate estimates), relMSE for adaptive sampling (what `--noise-threshold T` brings to
//! T²: the dark floor beside the fire counts as much as the flame).

use firemedium::metrics::errors_debiased;
use firemedium::render::{self, pixel::Sampler, scene as sc};
use std::fmt::Write as _;
use std::path::Path;

use clap::Args;

#[derive(Debug, Args)]
pub struct NoiseArgs {
    /// Image width and height.
    #[arg(long, default_value = "128x96", value_parser = firemedium::args::parse_resolution)]
    image: (usize, usize),
    /// The estimate's samples-per-pixel ladder.
    #[arg(long, value_delimiter = ',', default_value = "4,16,64,256")]
    spp: Vec<usize>,
    /// The references' samples per pixel (two halves).
    #[arg(long, default_value_t = 4096)]
    reference_spp: usize,
    /// The adaptive renders' noise thresholds.
    #[arg(long, value_delimiter = ',', default_value = "0.04,0.02,0.01")]
    thresholds: Vec<f64>,
    /// A scene to measure instead of the campfire and the fire-lit room (repeatable; e.g. each of scenes/).
    #[arg(long)]
    scene: Vec<std::path::PathBuf>,
    /// The estimate against the true error only (no adaptive renders, no uniform ladder).
    #[arg(long)]
    estimate_only: bool,
}

/// The luminance (cd/m²) of every pixel.
fn luminance(img: &render::Image) -> Vec<f64> {
    img.xyz.iter().map(|v| v.y).collect()
}

/// A workload: its name and the scene it loads at `res`, `spp` per pixel (`independent`: that sampler instead of
/// the scene's).
struct Workload<'a> {
    name: String,
    scene: &'a Path,
}

fn load(
    w: &Workload,
    res: (usize, usize),
    spp: usize,
    independent: bool,
) -> Result<sc::Scene, String> {
    let mut s = sc::load(
        w.scene,
        &sc::Overrides {
            spp: Some(spp),
            res: Some(res),
            ..Default::default()
        },
    )
    .map_err(|e| format!("{}: {e}", w.name))?;
    if independent {
        s.sampler = Sampler::Independent;
    }
    Ok(s)
}

/// The noise benchmark over `scenes` (name, scene file): estimate against truth at `spps`, then adaptive at
/// `thresholds` against a uniform ladder, every render at `res`, the references at `reference_spp` (two halves).
pub fn run(
    scenes: &[(String, std::path::PathBuf)],
    res: (usize, usize),
    spps: &[usize],
    reference_spp: usize,
    thresholds: &[f64],
    adaptive: bool,
) -> Result<String, String> {
    let mut out = format!("{}\n\n", crate::machine());
    for (name, path) in scenes {
        let w = Workload {
            name: name.clone(),
            scene: path,
        };
        // The reference: two halves, different seeds.
        let half = (reference_spp / 2).max(1);
        let mut halves = Vec::new();
        let mut ref_seconds = 0.0;
        for seed in [1001, 1002] {
            let s = load(&w, res, half, false)?;
            let (img, st) = render::render(&s, seed, &|_| {});
            ref_seconds += st.seconds;
            halves.push(luminance(&img));
        }
        let r: Vec<f64> = halves[0]
            .iter()
            .zip(&halves[1])
            .map(|(a, b)| (a + b) / 2.0)
            .collect();
        let truth = |a: &[f64]| errors_debiased(a, &r, [&halves[0], &halves[1]]);
        writeln!(
            out,
            "## {name}: {}×{}, reference {reference_spp} spp in two halves ({ref_seconds:.1} s)\n",
            res.0, res.1
        )
        .ok();
        writeln!(out, "| sampler | spp | estimated rel. RMSE | true rel. RMSE | estimate / true | seconds | twin samples |").ok();
        writeln!(out, "|---|---|---|---|---|---|---|").ok();
        // (A scene that samples independently already: its rows once.)
        let own_independent = matches!(load(&w, res, 1, false)?.sampler, Sampler::Independent);
        for independent in [false, true] {
            if independent && own_independent {
                continue;
            }
            for &spp in spps {
                let s = load(&w, res, spp, independent)?;
                let sampler = if independent {
                    "independent".to_string()
                } else {
                    format!("{:?}", s.sampler)
                        .split([' ', '{'])
                        .next()
                        .unwrap_or("the scene's")
                        .to_lowercase()
                };
                let (img, st) = render::render(&s, 7 + spp as u64, &|_| {});
                let (t, _) = truth(&luminance(&img));
                let e = st.rel_rmse_estimate;
                writeln!(
                    out,
                    "| {sampler} | {spp} | {} | {t:.4} | {} | {:.2} | {:.1} % |",
                    e.map_or("—".into(), |e| format!("{e:.4}")),
                    e.map_or("—".into(), |e| format!("{:.2}", e / t)),
                    st.seconds,
                    100.0 * st.twin_samples as f64 / st.camera_rays.max(1) as f64
                )
                .ok();
            }
        }
        if !adaptive {
            out.push('\n');
            continue;
        }
        // Adaptive against uniform, at equal relMSE: the uniform ladder's time interpolated (log–log) at each
        // adaptive render's relMSE.
        let mut ladder = Vec::new();
        for spp in [16usize, 32, 64, 128, 256, 512, 1024] {
            let s = load(&w, res, spp, false)?;
            let (img, st) = render::render(&s, 11, &|_| {});
            let y = luminance(&img);
            ladder.push((spp, st.seconds, truth(&y).1, mean(&y)));
        }
        writeln!(
            out,
            "\n| uniform spp | seconds | relMSE | mean Y / reference |"
        )
        .ok();
        writeln!(out, "|---|---|---|---|").ok();
        let level = mean(&r);
        for (spp, secs, m, y) in &ladder {
            writeln!(out, "| {spp} | {secs:.2} | {m:.3e} | {:.4} |", y / level).ok();
        }
        writeln!(out, "\n| threshold | mean spp | seconds | relMSE | uniform's seconds at that relMSE | speed-up | mean Y / reference | estimated rel. RMSE |").ok();
        writeln!(out, "|---|---|---|---|---|---|---|---|").ok();
        for &t in thresholds {
            let s = load(&w, res, 4096, false)?;
            let opts = render::Progressive {
                noise_threshold: Some(t),
                ..Default::default()
            };
            let (img, st) = render::render_progressive(&s, 11, &opts, &|_| {});
            let y = luminance(&img);
            let m = truth(&y).1;
            let uniform = interpolate(&ladder, m);
            writeln!(
                out,
                "| {t} | {:.1} | {:.2} | {m:.3e} | {} | {} | {:.4} | {} |",
                st.camera_rays as f64 / (res.0 * res.1) as f64,
                st.seconds,
                uniform.map_or("beyond the ladder".into(), |u| format!("{u:.2}")),
                uniform.map_or("—".into(), |u| format!("{:.2}×", u / st.seconds)),
                mean(&y) / level,
                st.rel_rmse_estimate
                    .map_or("—".into(), |e| format!("{e:.4}"))
            )
            .ok();
        }
        out.push('\n');
    }
    Ok(out)
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// The uniform ladder's time at relMSE `m`, log–log between the two rungs around it (`None` outside).
fn interpolate(ladder: &[(usize, f64, f64, f64)], m: f64) -> Option<f64> {
    ladder.windows(2).find_map(|p| {
        let ((_, t0, m0, _), (_, t1, m1, _)) = (p[0], p[1]);
        (m <= m0 && m >= m1 && m0 > m1).then(|| {
            let f = (m0.ln() - m.ln()) / (m0.ln() - m1.ln());
            (t0.ln() + f * (t1.ln() - t0.ln())).exp()
        })
    })
}

/// The report of `bench noise`: the campfire scene and a fire-lit room over a 128³ generated fire, or the scenes
/// `--scene` names.
pub fn report(a: &NoiseArgs) -> Result<String, String> {
    let measure = |scenes: &[(String, std::path::PathBuf)]| {
        run(
            scenes,
            a.image,
            &a.spp,
            a.reference_spp,
            &a.thresholds,
            !a.estimate_only,
        )
    };
    if !a.scene.is_empty() {
        let scenes: Vec<_> = a
            .scene
            .iter()
            .map(|p| (p.display().to_string(), p.clone()))
            .collect();
        return measure(&scenes);
    }
    let dir = std::env::temp_dir();
    let dataset = crate::perf::dataset(&dir, 128)?;
    let room = dir.join(format!(
        "firemedium-bench-noise-room-{}.pbrt",
        std::process::id()
    ));
    std::fs::write(
        &room,
        crate::fire_light::room_scene(&dataset, crate::fire_light::Fire::Fire, 5),
    )
    .map_err(|e| format!("{}: {e}", room.display()))?;
    let out = measure(&[
        (
            "the campfire scene".to_string(),
            crate::repository_file("scenes/campfire/scene.pbrt"),
        ),
        ("the fire-lit room".to_string(), room.clone()),
    ]);
    let _ = std::fs::remove_file(&room);
    out
}
