//! `firemedium bench fire-light`: the fire light's estimators against each other and against leaving it off,
//! on the surfaces of a fire-lit room, at several resolutions of the same fire (issue 29): per resolution,
//! surface error against render time at a ladder of samples per pixel (CSV and a log–log plot), and a table of
//! error × time and of what a light sample costs beside a camera path.

use super::error::Point;
use firemedium::metrics::{errors, errors_debiased};
use firemedium::render::{self, scene as sc, surface_mask};
use std::path::{Path, PathBuf};

/// One estimator: its name and how the renderer is told (`None`: the fire light off).
pub struct Estimator {
    /// Short name (`--estimators`).
    pub key: &'static str,
    pub name: &'static str,
    pub light: Option<(&'static str, &'static [(&'static str, &'static str)])>,
    /// The scene's pbrt-v4 grid media take pbrt-v4's own estimator (`"string integrator" "ratio"`).
    pub ratio: bool,
    /// Scattering events inside the fire sample its light too (`--fire-light-inside`).
    pub inside: bool,
}

/// The estimators measured: the light before issue 29 (`voxel, full`: a pdf over voxels, the volume's own march
/// along each sampled direction), each change alone (`brick`: cells of 8³ voxels; `own`: the line's march at
/// 64 steps across the fire, through its own voxels; `allbins`: the same through the copy of the fire in blocks
/// that the light's build-time check keeps, in every bin; `coarse`: that in the 8 bins the check allows, the
/// default — at the coarsest of 16, 32 or 64 steps across the fire that the check allows; `steps64`: at 64 steps
/// through the 2³ copy, the default before that on the room at 256³; `corrected`: toward the volume's march with
/// probability 0.25), the weightings (power unless named: luminance, escaping), and the light off (emission found
/// only by paths that pass through the fire). With a scattering fire every one but `pbrt` (pbrt-v4's estimator,
/// the BSDF's directions alone) aims half of the surfaces' directions at it, as the renderer does by default.
pub const ESTIMATORS: &[Estimator] = &[
    Estimator {
        key: "off",
        name: "off",
        light: None,
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "voxel",
        name: "voxel, full (before)",
        light: Some(("power", &[("cell", "1"), ("linestep", "1e-9")])),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "brick",
        name: "brick, full",
        light: Some(("power", &[("cell", "8"), ("linestep", "1e-9")])),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "own",
        name: "brick, coarse, own voxels",
        light: Some((
            "power",
            &[("cell", "8"), ("linestep", "0"), ("lineblock", "1")],
        )),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "allbins",
        name: "blocks, every bin",
        light: Some((
            "power",
            &[
                ("cell", "8"),
                ("linestep", "0"),
                ("lineblock", "0"),
                ("linechannels", "4096"),
            ],
        )),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "steps64",
        name: "64 steps, 2³ blocks, 8 bins",
        light: Some((
            "power",
            &[
                ("cell", "8"),
                ("linestep", "0"),
                ("lineblock", "2"),
                ("linechannels", "0"),
            ],
        )),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "coarse",
        name: "blocks, 8 bins (default)",
        light: Some(("power", DEFAULT_LINE)),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "corrected",
        name: "brick, coarse, corrected",
        light: Some((
            "power",
            &[("cell", "8"), ("linestep", "0"), ("linecorrection", "0.25")],
        )),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "luminance",
        name: "lum., brick, coarse",
        light: Some(("luminance", &[("cell", "8"), ("linestep", "0")])),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "escaping",
        name: "escaping, brick, coarse",
        light: Some(("escaping", &[("cell", "8"), ("linestep", "0")])),
        ratio: false,
        inside: false,
    },
    Estimator {
        key: "pbrt",
        name: PBRT,
        light: None,
        ratio: true,
        inside: false,
    },
    Estimator {
        key: "inside",
        name: "blocks, 8 bins, sampled inside the fire too",
        light: Some(("power", DEFAULT_LINE)),
        ratio: false,
        inside: true,
    },
];

/// The light's default cells and line (each choice made by its build-time check).
const DEFAULT_LINE: &[(&str, &str)] = &[
    ("cell", "8"),
    ("linestep", "0"),
    ("lineblock", "0"),
    ("linechannels", "0"),
];

/// The `pbrt` estimator's name: pbrt-v4's own strategy for its grid media (ratio tracking, no light).
pub const PBRT: &str = "pbrt-v4's (ratio tracking, light off)";

/// The room's fire: the paper's (`fire`, propane soot), or pbrt-v4's own `nanovdb` medium over the same file —
/// σ_a = 8.44e6 × density (propane soot's σ_a at 550 nm per unit soot fraction, Dalzell & Sarofim), grey, with
/// σ_s = σ_a · albedo / (1 − albedo) (isotropic) and `Lescale` × the peak-normalised blackbody.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fire {
    Fire,
    NanoVdb { albedo: f64, lescale: f64 },
}

/// The room: the fire (its box [−0.6, 0.6]² × [0, 1.6] m) on a floor before a back wall, with three diffuse
/// spheres; `volpath` to depth 5; the fire is the only light.
pub fn room_scene(dataset: &Path, fire: Fire, maxdepth: u32) -> String {
    let box_mesh = "\"point3 P\" [ -0.6 -0.6 0.002 0.6 -0.6 0.002 -0.6 0.6 0.002 0.6 0.6 0.002 -0.6 -0.6 1.6 0.6 -0.6 1.6 -0.6 0.6 1.6 0.6 0.6 1.6 ] \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]";
    format!(
        r#"# the fire-lit room of `firemedium bench fire-light`
LookAt 0 -4.6 1.5   0 0 0.7   0 0 1
Camera "perspective" "float fov" 48
Film "rgb" "integer xresolution" 320 "integer yresolution" 240 "string filename" "room.exr"
Sampler "independent" "integer pixelsamples" 16
Integrator "volpath" "integer maxdepth" {maxdepth}
WorldBegin
{medium}
AttributeBegin
  MediumInterface "fire" ""
  Material "interface"
  Shape "trianglemesh" {box_mesh}
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.45 0.42 0.38 ]
  Shape "trianglemesh" "point3 P" [ -5 -6 0  5 -6 0  5 2.5 0  -5 2.5 0 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
  Shape "trianglemesh" "point3 P" [ -5 2.5 0  5 2.5 0  5 2.5 4  -5 2.5 4 ] "integer indices" [ 0 1 2 0 2 3 ]
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.6 0.6 0.6 ]
  Translate -1.7 -0.5 0.5
  Shape "sphere" "float radius" 0.5
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.15 0.25 0.6 ]
  Translate 1.6 -0.8 0.35
  Shape "sphere" "float radius" 0.35
AttributeEnd
AttributeBegin
  Material "diffuse" "rgb reflectance" [ 0.6 0.3 0.2 ]
  Translate 0.5 1.5 0.4
  Shape "sphere" "float radius" 0.4
AttributeEnd
"#,
        medium = match fire {
            Fire::Fire => format!(
                "MakeNamedMedium \"fire\" \"string type\" \"fire\"\n  \"string dataset\" \"{}\"\n  \"string fuel\" \"propane\"\n  \"float stepsize\" 1",
                dataset.display()
            ),
            Fire::NanoVdb { albedo, lescale } => format!(
                "MakeNamedMedium \"fire\" \"string type\" \"nanovdb\"\n  \"string filename\" \"{}\"\n  \"float scale\" 8.44e6 \"spectrum sigma_a\" [200 1 900 1]\n  \"spectrum sigma_s\" [200 {s} 900 {s}] \"float Lescale\" {lescale}",
                dataset.display(),
                s = albedo / (1.0 - albedo)
            ),
        }
    )
}

/// A file removed when dropped.
#[derive(Debug)]
pub struct TempFile(pub PathBuf);

impl Drop for TempFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.0);
    }
}

/// `scene` with its pbrt-v4 grid media on pbrt-v4's estimator (`"string integrator" "ratio"`), written beside it
/// (relative paths stay valid).
pub fn ratio_scene(scene: &Path) -> Result<TempFile, String> {
    let text = std::fs::read_to_string(scene).map_err(|e| format!("{}: {e}", scene.display()))?;
    let mut out = text.clone();
    for ty in ["nanovdb", "uniformgrid"] {
        let from = format!("\"string type\" \"{ty}\"");
        out = out.replace(&from, &format!("{from} \"string integrator\" \"ratio\""));
    }
    if out == text {
        return Err(format!(
            "{}: the `pbrt` estimator needs a nanovdb or uniformgrid medium (a `fire` medium has no pbrt-v4 estimator)",
            scene.display()
        ));
    }
    let mut name = scene.as_os_str().to_owned();
    name.push(format!(".ratio-{}.pbrt", std::process::id()));
    let path = PathBuf::from(name);
    std::fs::write(&path, out).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(TempFile(path))
}

/// One render of the ladder.
#[derive(Debug, Clone)]
pub struct Run {
    pub estimator: &'static str,
    pub spp: usize,
    pub seconds: f64,
    /// Against the reference with its own noise taken out ([`firemedium::metrics::errors_debiased`]).
    pub rel_mse: f64,
    pub rel_rmse: f64,
    /// Against the reference as it is.
    pub raw: (f64, f64),
    /// The surfaces' mean against the reference's, less 1: the estimator's bias as far as the reference's noise
    /// lets it show ([`super::error::level`]).
    pub level: f64,
    pub camera_rays: usize,
    pub light_samples: u64,
}

/// Renders `scene` with every estimator at its ladder (the light on: `spp`; off: 4× each, the same
/// budget in camera paths as the light's light samples cost at most) against a reference of `ref_spp` with
/// the light's pdf over bricks and the volume's own march (unbiased against it), rendered in two independent
/// halves so that its own noise can be taken out of every error; returns the runs and a line about the
/// reference. In `repeats` rounds, the estimators in turn (each loaded afresh: the build is not timed), every
/// rung's time the median of its rounds.
#[allow(clippy::too_many_arguments)]
pub fn ladder(
    scene: &Path,
    label: &str,
    res: (usize, usize),
    spp: &[usize],
    ref_spp: usize,
    repeats: usize,
    estimators: &[&Estimator],
    log: &dyn Fn(&str),
) -> Result<(Vec<Run>, String), String> {
    // (Removed when the ladder ends, however it ends.)
    let ratio = match estimators.iter().any(|e| e.ratio) {
        true => Some(ratio_scene(scene)?),
        false => None,
    };
    let load = |spp: usize, e: &Estimator| {
        sc::load(
            match (e.ratio, &ratio) {
                (true, Some(r)) => &r.0,
                _ => scene,
            },
            &sc::Overrides {
                spp: Some(spp),
                no_fire_light: e.light.is_none(),
                fire_light_weighting: e.light.map(|l| l.0.to_string()),
                fire_light_params: e
                    .light
                    .map(|l| {
                        l.1.iter()
                            .map(|(n, v)| (n.to_string(), v.to_string()))
                            .collect()
                    })
                    .unwrap_or_default(),
                fire_light_inside: e.inside,
                fire_light_forced: true,
                // (pbrt-v4's estimator: its BSDF's directions alone, none aimed at a scattering fire.)
                fire_guide: e.ratio.then_some(0.0),
                res: Some(res),
                ..Default::default()
            },
        )
    };
    let by = ESTIMATORS
        .iter()
        .find(|e| e.key == "brick")
        .ok_or("no reference estimator")?;
    let reference_scene = load(ref_spp.div_ceil(2), by).map_err(|e| e.to_string())?;
    let mut rng = firemedium_core::rng::Rng::new(0);
    let mask = surface_mask(&reference_scene, &mut rng);
    let mut seconds = 0.0;
    let halves = [99, 100].map(|seed| {
        let (img, st) = render::render(&reference_scene, seed, &|_| {});
        seconds += st.seconds;
        super::error::surface_luminance(&img, &mask)
    });
    drop(reference_scene);
    let reference: Vec<f64> = halves[0]
        .iter()
        .zip(&halves[1])
        .map(|(a, b)| 0.5 * (a + b))
        .collect();
    // The reference's own rel. RMSE (its halves' difference over 2 estimates its noise).
    let own = firemedium::metrics::errors(&halves[0], &halves[1]).0 / 2.0;
    let about = format!(
        "{label}: reference {} spp in two halves ({}; its own noise, rel. RMSE {own:.4}, taken out of every \
         error), {}×{} pixels ({} see a surface), {:.1} s",
        2 * ref_spp.div_ceil(2),
        by.name,
        res.0,
        res.1,
        reference.len(),
        seconds
    );
    log(&about);
    let mut runs: Vec<Run> = Vec::new();
    let mut times: Vec<Vec<f64>> = Vec::new();
    for round in 0..repeats.max(1) {
        for (k, e) in estimators.iter().enumerate() {
            // One load per estimator and round (the fire and its light built once), its samples per pixel set per
            // rung.
            let mut s = load(1, e).map_err(|e| e.to_string())?;
            for (q, &n) in spp.iter().enumerate() {
                let n = if e.light.is_none() { 4 * n } else { n };
                s.spp = n;
                let (img, st) = render::render(&s, 7 + n as u64, &|_| {});
                let at = k * spp.len() + q;
                if round > 0 {
                    if let Some(t) = times.get_mut(at) {
                        t.push(st.seconds);
                    }
                    log(&format!(
                        "{label} {}: {n} spp, round {}, {:.3} s",
                        e.name,
                        round + 1,
                        st.seconds
                    ));
                    continue;
                }
                let lum = super::error::surface_luminance(&img, &mask);
                let (rel_rmse, rel_mse) =
                    errors_debiased(&lum, &reference, [&halves[0], &halves[1]]);
                let raw = errors(&lum, &reference);
                let run = Run {
                    level: super::error::level(&lum, &reference),
                    estimator: e.name,
                    spp: n,
                    seconds: st.seconds,
                    rel_mse,
                    rel_rmse,
                    raw,
                    camera_rays: st.camera_rays,
                    light_samples: st.fire_light_samples,
                };
                log(&format!(
                    "{label} {}: {n} spp, {:.3} s, relMSE {:.4e} (against the reference as it is {:.4e})",
                    e.name, run.seconds, run.rel_mse, run.raw.1
                ));
                runs.push(run);
                times.push(vec![st.seconds]);
            }
        }
    }
    for (run, t) in runs.iter_mut().zip(&times) {
        run.seconds = median(t);
    }
    Ok((runs, about))
}

/// The median of `t` (the mean of the middle two for an even count; 0 for none).
fn median(t: &[f64]) -> f64 {
    let mut v = t.to_vec();
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => 0.0,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// The plot's points of one resolution.
pub fn points(runs: &[Run]) -> Vec<Point> {
    runs.iter()
        .map(|r| Point {
            estimator: r.estimator.to_string(),
            setting: format!("{} spp", r.spp),
            seconds: r.seconds,
            rel_rmse: r.rel_rmse,
            rel_mse: r.rel_mse,
            evaluations: None,
            level: Some(r.level),
        })
        .collect()
}

/// One estimator's line of the summary.
#[derive(Debug, Clone)]
pub struct Summary {
    pub estimator: String,
    /// rel. RMSE² × seconds and relMSE × seconds at its largest rung (lower is better).
    pub rmse2_s: f64,
    pub relmse_s: f64,
    /// The light off's over it.
    pub gain_rmse2: f64,
    pub gain_relmse: f64,
    /// Its largest rung's [`Run::level`].
    pub level: f64,
    /// What a light sample costs in camera paths without one: the time a render spends beyond the light off's
    /// at the same samples per pixel, per light sample, over the light off's time per camera ray.
    pub sample_cost: Option<f64>,
}

/// Per estimator of one resolution, its [`Summary`]; its gains against pbrt-v4's estimator where it ran, else
/// against the light off ([`baseline`]).
pub fn summary(runs: &[Run]) -> Vec<Summary> {
    let last = |name: &str| runs.iter().rfind(|r| r.estimator == name);
    let Some(base) = last(baseline(runs)) else {
        return Vec::new();
    };
    let off = last("off").unwrap_or(base);
    let path_cost = off.seconds / off.camera_rays.max(1) as f64;
    let mut names: Vec<&str> = Vec::new();
    for r in runs {
        if !names.contains(&r.estimator) {
            names.push(r.estimator);
        }
    }
    names
        .into_iter()
        .filter_map(|name| {
            let r = last(name)?;
            // The light off at the same samples per pixel (its ladder is 4× the light's: a rung below).
            let same = runs.iter().find(|o| o.estimator == "off" && o.spp == r.spp);
            let sample_cost = same
                .filter(|_| r.light_samples > 0)
                .map(|o| (r.seconds - o.seconds).max(0.0) / r.light_samples as f64 / path_cost);
            let (rmse2_s, relmse_s) = (r.rel_rmse * r.rel_rmse * r.seconds, r.rel_mse * r.seconds);
            Some(Summary {
                estimator: name.to_string(),
                rmse2_s,
                relmse_s,
                gain_rmse2: base.rel_rmse * base.rel_rmse * base.seconds / rmse2_s,
                gain_relmse: base.rel_mse * base.seconds / relmse_s,
                level: r.level,
                sample_cost,
            })
        })
        .collect()
}

/// The estimator the summary's gains are against: pbrt-v4's where it ran, else the light off.
pub fn baseline(runs: &[Run]) -> &'static str {
    match runs.iter().any(|r| r.estimator == PBRT) {
        true => PBRT,
        false => "off",
    }
}

/// Where the bench writes: PREFIX-LABEL.csv/svg/png per case.
pub fn output(prefix: &Path, label: &str, ext: &str) -> PathBuf {
    let mut p = prefix.as_os_str().to_owned();
    p.push(format!("-{label}{ext}"));
    PathBuf::from(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rungs_time_is_the_median_of_its_rounds() {
        assert_eq!(median(&[3.0]), 3.0);
        assert_eq!(median(&[5.0, 1.0, 4.0]), 4.0);
        assert_eq!(median(&[4.0, 1.0, 2.0, 10.0]), 3.0);
        assert_eq!(median(&[]), 0.0);
    }

    #[test]
    fn the_summary_weighs_error_by_time_against_the_light_off() {
        // The light off at 4 and 16 spp, a light at 4: the light's gains are the light off's error² × time at its
        // largest rung over the light's, and its sample's cost the time beyond the light off's at 4 spp per light
        // sample, in the light off's camera paths.
        let run = |estimator: &'static str, spp, seconds, rel: f64, light_samples| Run {
            estimator,
            spp,
            seconds,
            rel_mse: rel * rel,
            rel_rmse: rel,
            raw: (rel, rel * rel),
            level: 0.0,
            camera_rays: 1000 * spp,
            light_samples,
        };
        let runs = [
            run("off", 4, 1.0, 1.0, 0),
            run("off", 16, 4.0, 0.5, 0),
            run("light", 4, 3.0, 0.2, 2000),
        ];
        let s = summary(&runs);
        assert_eq!(s.len(), 2);
        let l = &s[1];
        assert_eq!(l.estimator, "light");
        // off: 0.25 × 4 = 1; light: 0.04 × 3 = 0.12.
        assert!((l.gain_rmse2 - 1.0 / 0.12).abs() < 1e-9, "{}", l.gain_rmse2);
        // (3 − 1) s over 2000 samples, per (4 s / 16 000 rays).
        let cost = l.sample_cost.unwrap();
        assert!(
            (cost - 2.0 / 2000.0 / (4.0 / 16000.0)).abs() < 1e-9,
            "{cost}"
        );
    }
}
