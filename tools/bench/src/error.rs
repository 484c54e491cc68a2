//! `firemedium bench error-vs-time`: the error of each estimator of the fire seen directly against the time it
//! takes — march at a ladder of steps (spectral and rgb), delta and ratio tracking at a ladder of samples per
//! pixel — against a reference none of them computes (quadrature of the point coefficients), as a CSV and a log–log
//! plot (SVG and PNG).

use firemedium::metrics::errors;
use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{evaluations_on_this_thread, FireVolume, Ray};
use rayon::prelude::*;
use std::path::Path;
use std::time::Instant;

/// One point of the plot.
#[derive(Debug, Clone, PartialEq)]
pub struct Point {
    pub estimator: String,
    pub setting: String,
    pub seconds: f64,
    pub rel_rmse: f64,
    pub rel_mse: f64,
    /// Medium evaluations, where counted (the rlib's volume; renders through the plugin library are not).
    pub evaluations: Option<u64>,
    /// The estimator's bias as the image shows it: its mean over the pixels against the reference's, less 1
    /// (the pixels' noise averages out of it; a deterministic estimator's whole error is bias). `None` where not
    /// measured (a CSV written before the column).
    pub level: Option<f64>,
}

/// The image's mean against the reference's, less 1 (see [`Point::level`]).
pub fn level(a: &[f64], r: &[f64]) -> f64 {
    let (sa, sr) = (a.iter().sum::<f64>(), r.iter().sum::<f64>());
    if sr > 0.0 {
        sa / sr - 1.0
    } else {
        0.0
    }
}

/// A luminance image (cd/m²) of the fire from a pinhole in front of it, `spp` rays per pixel; (image, seconds,
/// medium evaluations).
pub fn render(v: &FireVolume, size: usize, spp: usize, seed: u64) -> (Vec<f64>, f64, u64) {
    let (eye, dir) = super::perf::pinhole(v, size);
    let xyz = v.channel_xyz();
    let start = Instant::now();
    let rows: Vec<(Vec<f64>, u64)> = (0..size)
        .into_par_iter()
        .map(|j| {
            let before = evaluations_on_this_thread();
            let c = v.channels();
            let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
            let row = (0..size)
                .map(|i| {
                    let d = dir(i, j);
                    let mut y = 0.0;
                    for s in 0..spp {
                        let ray = Ray {
                            o: eye,
                            d,
                            t0: 0.0,
                            t1: 1e30,
                            seed: seed
                                .wrapping_mul(0x9E37_79B9_7F4A_7C15)
                                .wrapping_add(((j * size + i) * spp + s) as u64),
                            first: None,
                        };
                        v.integrate(&ray, &mut l, &mut t);
                        y += (0..c).map(|k| l[k] * xyz[k].y).sum::<f64>();
                    }
                    y / spp as f64
                })
                .collect();
            (row, evaluations_on_this_thread() - before)
        })
        .collect();
    let seconds = start.elapsed().as_secs_f64();
    let evals = rows.iter().map(|r| r.1).sum();
    (rows.into_iter().flat_map(|r| r.0).collect(), seconds, evals)
}

/// Gauss–Legendre nodes and weights on [0, 1], 4 points (exact for polynomials of degree 7).
const GL4: [(f64, f64); 4] = [
    (0.069_431_844_202_973_71, 0.173_927_422_568_726_93),
    (0.330_009_478_207_571_87, 0.326_072_577_431_273_07),
    (0.669_990_521_792_428_1, 0.326_072_577_431_273_07),
    (0.930_568_155_797_026_3, 0.173_927_422_568_726_93),
];

/// The reference independent of every estimator on the ladder: the emission–absorption integral
/// L = ∫ j(s) e^{−τ(s)} ds along each pixel's ray, by Gauss–Legendre quadrature of the volume's point coefficients
/// ([`FireVolume::coefficients`], what every estimator samples) over each piece on which the trilinear fields
/// are polynomial (the ray cut at every plane through voxel centres, where the interpolation kinks), the optical
/// depth to each node by the same quadrature nested; (image, seconds). No step, no random number: what the
/// march and the trackers estimate, to the quadrature's error.
pub fn quadrature(v: &FireVolume, size: usize) -> (Vec<f64>, f64) {
    let (eye, dir) = super::perf::pinhole(v, size);
    let xyz = v.channel_xyz();
    let ds = v.dataset();
    let ([b0, b1], vs, dims) = (ds.bounds(), ds.voxel_size(), ds.dims());
    // Beyond the lattice's outer centres the fields fall to the zero layer half a voxel further.
    let (lo, hi) = (b0 - vs, b1 + vs);
    let c = v.channels();
    let start = Instant::now();
    let img: Vec<f64> = (0..size * size)
        .into_par_iter()
        .map(|px| {
            let d = dir(px % size, px / size);
            let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
            for a in 0..3 {
                let (n0, n1) = ((lo[a] - eye[a]) / d[a], (hi[a] - eye[a]) / d[a]);
                t0 = t0.max(n0.min(n1));
                t1 = t1.min(n0.max(n1));
            }
            if t0 >= t1 {
                return 0.0;
            }
            let mut cuts = vec![t0, t1];
            for a in 0..3 {
                if d[a] == 0.0 {
                    continue;
                }
                for i in -1..=dims[a] as i64 {
                    let t = (b0[a] + (i as f64 + 0.5) * vs[a] - eye[a]) / d[a];
                    if t > t0 && t < t1 {
                        cuts.push(t);
                    }
                }
            }
            cuts.sort_by(f64::total_cmp);
            let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            let mut sigma_t = |t: f64, out: &mut [f64], emit: Option<&mut [f64]>| {
                v.coefficients(eye + d * t, &mut sa, &mut ss, &mut j);
                for k in 0..c {
                    out[k] = sa[k] + ss[k];
                }
                if let Some(e) = emit {
                    e.copy_from_slice(&j);
                }
            };
            let (mut tau, mut l) = (vec![0.0; c], vec![0.0; c]);
            let (mut st, mut jt, mut inner) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            for w in cuts.windows(2) {
                let (a, b) = (w[0], w[1]);
                let h = b - a;
                if h <= 0.0 {
                    continue;
                }
                for &(x, wx) in &GL4 {
                    let s = a + h * x;
                    sigma_t(s, &mut st, Some(&mut jt));
                    // τ from a to s, nested.
                    let mut part = vec![0.0; c];
                    for &(y, wy) in &GL4 {
                        sigma_t(a + (s - a) * y, &mut inner, None);
                        for k in 0..c {
                            part[k] += wy * (s - a) * inner[k];
                        }
                    }
                    for k in 0..c {
                        l[k] += wx * h * jt[k] * (-(tau[k] + part[k])).exp();
                    }
                }
                for &(x, wx) in &GL4 {
                    sigma_t(a + h * x, &mut st, None);
                    for k in 0..c {
                        tau[k] += wx * h * st[k];
                    }
                }
            }
            (0..c).map(|k| l[k] * xyz[k].y).sum::<f64>()
        })
        .collect();
    (img, start.elapsed().as_secs_f64())
}

/// The whole ladder on `file`; returns the points and a description of the reference.
pub fn ladder(file: &Path, size: usize, max_spp: usize) -> Result<(Vec<Point>, String), String> {
    let build = |extra: &[Param]| {
        let mut list = vec![Param::string("filename", &file.to_string_lossy())];
        list.extend_from_slice(extra);
        FireVolume::new(&list).map_err(|e| e.to_string())
    };
    // The reference: quadrature, no estimator of the ladder; the march at 1/16 voxel measured against it.
    let (reference, ref_s) = quadrature(&build(&[])?, size);
    let fine = build(&[Param::float("stepsize", 1.0 / 16.0)])?;
    let (finest, _, _) = render(&fine, size, 1, 1);
    let (ref_err, _) = errors(&finest, &reference);

    let mut points = Vec::new();
    let mut push =
        |estimator: &str, setting: String, img: &[f64], seconds: f64, evaluations: u64| {
            let (rel_rmse, rel_mse) = errors(img, &reference);
            points.push(Point {
                estimator: estimator.to_string(),
                setting,
                seconds,
                rel_rmse,
                rel_mse,
                evaluations: Some(evaluations),
                level: Some(level(img, &reference)),
            });
        };
    for (estimator, extra) in [
        ("march spectral", None),
        ("march rgb", Some(Param::string("colormode", "rgb"))),
    ] {
        for step in [2.0, 1.0, 0.5, 0.25, 0.125] {
            let mut params = vec![Param::float("stepsize", step)];
            params.extend(extra.clone());
            let v = build(&params)?;
            let (img, s, n) = render(&v, size, 1, 3);
            push(estimator, format!("step {step} voxel"), &img, s, n);
        }
    }
    for estimator in ["delta", "ratio"] {
        let v = build(&[Param::string("integrator", estimator)])?;
        let mut spp = 1;
        while spp <= max_spp {
            let (img, s, n) = render(&v, size, spp, 4);
            push(
                &format!("{estimator} tracking"),
                format!("{spp} spp"),
                &img,
                s,
                n,
            );
            spp *= 2;
        }
    }
    // How the march converges towards the reference: its error's fall per halving of the step.
    let err_at = |setting: &str| {
        points
            .iter()
            .find(|p| p.estimator == "march spectral" && p.setting == setting)
            .map(|p| p.rel_rmse)
    };
    let r = match (err_at("step 0.25 voxel"), err_at("step 0.125 voxel")) {
        (Some(a), Some(b)) if b > 0.0 => a / b,
        _ => f64::NAN,
    };
    let about = format!(
        "reference: Gauss–Legendre quadrature of the point coefficients over every trilinear piece of each ray (4 nodes, the optical depth nested; no estimator of the ladder), spectral, {size}×{size} pixels, {ref_s:.1} s; the march at 1/16 voxel differs from it by rel. RMSE {ref_err:.2e}, its error falling {r:.2}× per halving of the step between 1/4 and 1/8 voxel. Each row: that estimator's error against the quadrature (bias and noise together; the trackers are unbiased, the march's error is its bias)"
    );
    Ok((points, about))
}

/// The fire lighting surfaces: `scene` rendered at `res` with the fire light on and off at 1, 2, 4, … `max_spp`
/// samples per pixel, against the fire light sampled by luminance at `ref_spp` (another estimator than the rows');
/// errors over the pixels that see a diffuse surface.
pub fn surface_ladder(
    scene: &Path,
    res: (usize, usize),
    max_spp: usize,
    ref_spp: usize,
) -> Result<(Vec<Point>, String), String> {
    use firemedium::render::{self, scene as sc, surface_mask};
    let load_weighted = |spp: usize, light: bool, weighting: Option<&str>| {
        sc::load(
            scene,
            &sc::Overrides {
                spp: Some(spp),
                plugin: None,
                no_fire_light: !light,
                fire_light_weighting: weighting.map(str::to_string),
                res: Some(res),
                threads: None,
                max_memory: None,
                ..Default::default()
            },
        )
    };
    let load = |spp: usize, light: bool| load_weighted(spp, light, None);
    // The reference samples the fire light by its voxels' luminance, not by their power as the rows do: another
    // estimator (unbiased both), so the rows are not compared with a longer run of themselves.
    let reference_scene =
        load_weighted(ref_spp, true, Some("luminance")).map_err(|e| e.to_string())?;
    let mut rng = firemedium_core::rng::Rng::new(0);
    let mask = surface_mask(&reference_scene, &mut rng);
    let (reference, st) = render::render(&reference_scene, 99, &|_| {});
    let reference_m = surface_luminance(&reference, &mask);
    let reference_all: Vec<f64> = reference.xyz.iter().map(|v| v.y).collect();
    // The reference's own error: half its samples against the other half, scaled to the full count.
    let about = format!(
        "reference: the fire light sampling voxels by luminance (the rows: by power, the default), {ref_spp} spp, {}×{} pixels ({} see a diffuse surface), {:.1} s; each row's error is against it, its own noise included",
        res.0,
        res.1,
        reference_m.len(),
        st.seconds
    );
    let mut points = Vec::new();
    for light in [true, false] {
        let mut spp = 1;
        while spp <= max_spp {
            let s = load(spp, light).map_err(|e| e.to_string())?;
            let (img, st) = render::render(&s, 7 + spp as u64, &|_| {});
            let surface = surface_luminance(&img, &mask);
            let (rel_rmse, rel_mse) = errors(&surface, &reference_m);
            points.push(Point {
                estimator: if light {
                    "fire light on"
                } else {
                    "fire light off"
                }
                .into(),
                setting: format!("{spp} spp"),
                seconds: st.seconds,
                rel_rmse,
                rel_mse,
                // (The renderer reaches the fire through the plugin library, whose counter is its own.)
                evaluations: None,
                level: Some(level(&surface, &reference_m)),
            });
            // Every render's own estimate of its error beside its true error, both over the whole image.
            if let (true, Some(estimate)) = (light, st.rel_rmse_estimate) {
                let all: Vec<f64> = img.xyz.iter().map(|v| v.y).collect();
                let (true_rmse, true_mse) = errors(&all, &reference_all);
                for (estimator, rel_rmse, rel_mse, lvl) in [
                    (
                        TRUE_WHOLE,
                        true_rmse,
                        true_mse,
                        Some(level(&all, &reference_all)),
                    ),
                    (ESTIMATE_WHOLE, estimate, f64::NAN, None),
                ] {
                    points.push(Point {
                        estimator: estimator.into(),
                        setting: format!("{spp} spp"),
                        seconds: st.seconds,
                        rel_rmse,
                        rel_mse,
                        evaluations: None,
                        level: lvl,
                    });
                }
            }
            spp *= 2;
        }
    }
    Ok((points, about))
}

/// The surface ladder's series of the fire light on over the whole image: the true error, and the render's own
/// estimate of it (its relMSE column empty). Measures of the estimate, not estimators: never a ladder's winner.
pub const TRUE_WHOLE: &str = "fire light on: true error (whole image)";
pub const ESTIMATE_WHOLE: &str = "fire light on: the render's own estimate";

/// The luminance of the pixels `mask` marks (those that see a surface), in pixel order.
pub fn surface_luminance(img: &firemedium::render::Image, mask: &[bool]) -> Vec<f64> {
    img.xyz
        .iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(v, _)| v.y)
        .collect()
}

/// The equal-time winner: among the points no slower than the paper's setting (march, ½ voxel, spectral), the
/// one with the lowest error.
pub fn winner(points: &[Point]) -> Option<usize> {
    // (Without a march point — the surface scene — the budget is the fastest estimator's slowest point.)
    let budget = match points
        .iter()
        .find(|p| p.estimator == "march spectral" && p.setting == "step 0.5 voxel")
    {
        Some(p) => p.seconds,
        None => estimators(points)
            .iter()
            .map(|e| {
                points
                    .iter()
                    .filter(|p| &p.estimator == e)
                    .map(|p| p.seconds)
                    .fold(0.0, f64::max)
            })
            .fold(f64::INFINITY, f64::min),
    };
    (0..points.len())
        .filter(|&i| points[i].seconds <= budget * 1.0001)
        .filter(|&i| ![TRUE_WHOLE, ESTIMATE_WHOLE].contains(&points[i].estimator.as_str()))
        .min_by(|&a, &b| points[a].rel_rmse.total_cmp(&points[b].rel_rmse))
}

/// The points of a CSV [`csv`] wrote: an error naming the line, the column and what it expected.
/// The CSV's columns before `level`.
const HEADER: &str = "estimator,setting,seconds,rel_rmse,rel_mse,medium_evaluations";

pub fn parse_csv(text: &str) -> Result<Vec<Point>, String> {
    let mut lines = text.lines().enumerate();
    // (The level column came later: a CSV without it still reads.)
    let fields = match lines.next() {
        Some((_, h)) if h.trim() == HEADER => 6,
        Some((_, h)) if h.trim() == format!("{HEADER},level") => 7,
        _ => return Err(format!("line 1: expected the header {HEADER}[,level]")),
    };
    let mut points = Vec::new();
    for (i, line) in lines.filter(|(_, l)| !l.trim().is_empty()) {
        let f = split_csv_line(line);
        if f.len() != fields {
            return Err(format!(
                "line {}: {} fields, expected {fields}",
                i + 1,
                f.len()
            ));
        }
        let num = |k: usize, what: &str| -> Result<f64, String> {
            f[k].trim()
                .parse::<f64>()
                .map_err(|_| format!("line {}: {what} {:?}: expected a number", i + 1, f[k]))
        };
        let evaluations = match f[5].trim() {
            "" => None,
            v => Some(v.parse::<u64>().map_err(|_| {
                format!(
                    "line {}: medium_evaluations {v:?}: expected a count or nothing",
                    i + 1
                )
            })?),
        };
        let level = match f.get(6).map(|v| v.trim()) {
            None | Some("") => None,
            Some(_) => Some(num(6, "level")?),
        };
        points.push(Point {
            estimator: f[0].clone(),
            setting: f[1].clone(),
            seconds: num(2, "seconds")?,
            rel_rmse: num(3, "rel_rmse")?,
            rel_mse: num(4, "rel_mse")?,
            evaluations,
            level,
        });
    }
    if points.is_empty() {
        return Err("no points".into());
    }
    Ok(points)
}

/// One CSV line's fields, quoted ones unquoted (RFC 4180: a doubled quote inside is one quote).
fn split_csv_line(line: &str) -> Vec<String> {
    let (mut fields, mut cur, mut quoted) = (Vec::new(), String::new(), false);
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match (c, quoted) {
            ('"', true) if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            ('"', _) => quoted = !quoted,
            (',', false) => fields.push(std::mem::take(&mut cur)),
            _ => cur.push(c),
        }
    }
    fields.push(cur);
    fields
}

pub fn csv(points: &[Point]) -> String {
    // (A text field holding a comma or a quote is quoted, its quotes doubled: RFC 4180.)
    let field = |t: &str| {
        if t.contains([',', '"', '\n']) {
            format!("\"{}\"", t.replace('"', "\"\""))
        } else {
            t.to_string()
        }
    };
    let mut s = format!("{HEADER},level\n");
    for p in points {
        s += &format!(
            "{},{},{:.6},{:.6e},{:.6e},{},{}\n",
            field(&p.estimator),
            field(&p.setting),
            p.seconds,
            p.rel_rmse,
            p.rel_mse,
            p.evaluations.map(|n| n.to_string()).unwrap_or_default(),
            p.level.map(|l| format!("{l:.6e}")).unwrap_or_default()
        );
    }
    s
}

const COLOURS: [(u8, u8, u8); 8] = [
    (214, 39, 40),
    (255, 127, 14),
    (31, 119, 180),
    (44, 160, 44),
    (148, 103, 189),
    (23, 190, 207),
    (140, 86, 75),
    (127, 127, 127),
];

/// The plot's geometry: log-log axes over the points' range, in a `w`×`h` canvas.
struct Axes {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    w: f64,
    h: f64,
}

impl Axes {
    const LEFT: f64 = 70.0;
    const RIGHT: f64 = 190.0;
    const TOP: f64 = 30.0;
    const BOTTOM: f64 = 50.0;
    fn new(points: &[Point], w: f64, h: f64) -> Axes {
        let xs = points.iter().map(|p| p.seconds.max(1e-6).log10());
        let ys = points.iter().map(|p| p.rel_rmse.max(1e-9).log10());
        let (x0, x1) = xs.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
        let (y0, y1) = ys.fold((f64::MAX, f64::MIN), |(a, b), v| (a.min(v), b.max(v)));
        Axes {
            x0: x0.floor(),
            x1: x1.ceil().max(x0.floor() + 1.0),
            y0: y0.floor(),
            y1: y1.ceil().max(y0.floor() + 1.0),
            w,
            h,
        }
    }
    fn px(&self, seconds: f64) -> f64 {
        let u = (seconds.max(1e-6).log10() - self.x0) / (self.x1 - self.x0);
        Self::LEFT + u * (self.w - Self::LEFT - Self::RIGHT)
    }
    fn py(&self, err: f64) -> f64 {
        let u = (err.max(1e-9).log10() - self.y0) / (self.y1 - self.y0);
        self.h - Self::BOTTOM - u * (self.h - Self::TOP - Self::BOTTOM)
    }
}

fn estimators(points: &[Point]) -> Vec<String> {
    let mut names: Vec<String> = Vec::new();
    for p in points {
        if !names.contains(&p.estimator) {
            names.push(p.estimator.clone());
        }
    }
    names
}

/// The log–log plot as SVG.
/// `mark`: the point to circle as the equal-time winner, if any.
pub fn svg(points: &[Point], title: &str, mark: Option<usize>) -> String {
    let (w, h) = (760.0, 480.0);
    let ax = Axes::new(points, w, h);
    let mut s = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n<text x=\"{}\" y=\"18\" font-size=\"14\">{title}</text>\n",
        Axes::LEFT
    );
    // Decade grid and labels.
    for e in (ax.x0 as i32)..=(ax.x1 as i32) {
        let x = ax.px(10f64.powi(e));
        s += &format!(
            "<line x1=\"{x:.1}\" y1=\"{}\" x2=\"{x:.1}\" y2=\"{}\" stroke=\"#ddd\"/><text x=\"{x:.1}\" y=\"{}\" text-anchor=\"middle\">1e{e}</text>\n",
            Axes::TOP,
            h - Axes::BOTTOM,
            h - Axes::BOTTOM + 16.0
        );
    }
    for e in (ax.y0 as i32)..=(ax.y1 as i32) {
        let y = ax.py(10f64.powi(e));
        s += &format!(
            "<line x1=\"{}\" y1=\"{y:.1}\" x2=\"{}\" y2=\"{y:.1}\" stroke=\"#ddd\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{e}</text>\n",
            Axes::LEFT,
            w - Axes::RIGHT,
            Axes::LEFT - 6.0,
            y + 4.0
        );
    }
    s += &format!(
        "<text x=\"{:.1}\" y=\"{}\" text-anchor=\"middle\">render time, s</text>\n<text x=\"16\" y=\"{:.1}\" transform=\"rotate(-90 16 {:.1})\" text-anchor=\"middle\">relative RMSE</text>\n",
        0.5 * (Axes::LEFT + w - Axes::RIGHT),
        h - 10.0,
        0.5 * h,
        0.5 * h
    );
    for (k, name) in estimators(points).iter().enumerate() {
        let (r, g, b) = COLOURS[k % COLOURS.len()];
        let pts: Vec<String> = points
            .iter()
            .filter(|p| &p.estimator == name)
            .map(|p| format!("{:.1},{:.1}", ax.px(p.seconds), ax.py(p.rel_rmse)))
            .collect();
        s += &format!(
            "<polyline fill=\"none\" stroke=\"rgb({r},{g},{b})\" stroke-width=\"2\" points=\"{}\"/>\n",
            pts.join(" ")
        );
        for p in pts {
            let (x, y) = p.split_once(',').unwrap_or(("0", "0"));
            s += &format!("<circle cx=\"{x}\" cy=\"{y}\" r=\"3\" fill=\"rgb({r},{g},{b})\"/>\n");
        }
        let ly = Axes::TOP + 20.0 * k as f64 + 10.0;
        let lx = w - Axes::RIGHT + 14.0;
        s += &format!(
            "<line x1=\"{lx}\" y1=\"{ly}\" x2=\"{}\" y2=\"{ly}\" stroke=\"rgb({r},{g},{b})\" stroke-width=\"3\"/><text x=\"{}\" y=\"{}\">{name}</text>\n",
            lx + 22.0,
            lx + 28.0,
            ly + 4.0
        );
    }
    if let Some(i) = mark {
        let p = &points[i];
        let (x, y) = (ax.px(p.seconds), ax.py(p.rel_rmse));
        s += &format!(
            "<circle cx=\"{x:.1}\" cy=\"{y:.1}\" r=\"9\" fill=\"none\" stroke=\"black\" stroke-width=\"2\"/><text x=\"{:.1}\" y=\"{:.1}\">equal-time winner: {} ({})</text>\n",
            x + 12.0,
            y - 10.0,
            p.estimator,
            p.setting
        );
    }
    s + "</svg>\n"
}

/// Where the PNG's labels find a TrueType font: `FIREMEDIUM_FONT`, else the usual places of DejaVu Sans
/// (Debian's `fonts-dejavu-core`) and of the system's sans serif on macOS and Windows.
const FONT_PATHS: [&str; 6] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu-sans-fonts/DejaVuSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
    "C:\\Windows\\Fonts\\arial.ttf",
];

/// The font the PNG's labels are drawn in, registered with plotters once per process: its path, or why there
/// is none (no file found, one too large, or not a font plotters reads).
fn plot_font() -> Result<&'static str, String> {
    static FONT: std::sync::OnceLock<Result<String, String>> = std::sync::OnceLock::new();
    FONT.get_or_init(|| {
        let named = std::env::var("FIREMEDIUM_FONT").ok();
        let path = match &named {
            Some(p) => p.clone(),
            None => FONT_PATHS
                .iter()
                .find(|p| std::path::Path::new(p).is_file())
                .map(|p| p.to_string())
                .ok_or_else(|| {
                    format!(
                        "no TrueType font in {} (set FIREMEDIUM_FONT, or install fonts-dejavu-core)",
                        FONT_PATHS.join(", ")
                    )
                })?,
        };
        // (A font is a few hundred kB; a file far larger is not one.)
        let size = std::fs::metadata(&path).map_err(|e| format!("{path}: {e}"))?.len();
        if size > 64 << 20 {
            return Err(format!("{path}: {size} bytes, expected a TrueType font under 64 MB"));
        }
        let bytes = std::fs::read(&path).map_err(|e| format!("{path}: {e}"))?;
        // (Registered once for the process's life: plotters keeps fonts as 'static bytes.)
        let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
        plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, bytes)
            .map_err(|_| format!("{path}: not a TrueType font plotters can read"))?;
        Ok(path)
    })
    .as_deref()
    .map_err(|e| e.clone())
}

/// The same plot as a PNG, drawn by plotters: log–log axes over the points' decades, a line and markers per
/// estimator, the legend, and the equal-time winner circled. The labels need a TrueType font
/// ([`plot_font`]); without one the plot is drawn unlabelled and the reason is returned beside it (the SVG
/// carries the labels either way).
pub fn png(
    points: &[Point],
    title: &str,
    mark: Option<usize>,
) -> (usize, usize, Vec<u8>, Option<String>) {
    use plotters::prelude::*;
    let (w, h) = (760usize, 480usize);
    let mut img = vec![255u8; w * h * 3];
    let font = plot_font();
    let labels = font.is_ok();
    // (Points without a finite time and error stay in the CSV; an axis cannot hold them.)
    let plotted = |p: &&Point| p.seconds.is_finite() && p.rel_rmse.is_finite();
    let shown: Vec<Point> = points.iter().filter(plotted).cloned().collect();
    if shown.is_empty() {
        return (
            w,
            h,
            img,
            Some("no point with a finite time and error to plot".into()),
        );
    }
    let ax = Axes::new(&shown, w as f64, h as f64);
    let x = 10f64.powf(ax.x0)..10f64.powf(ax.x1);
    let y = 10f64.powf(ax.y0)..10f64.powf(ax.y1);
    let drawn = (|| -> Result<(), Box<dyn std::error::Error + '_>> {
        let root = BitMapBackend::with_buffer(&mut img, (w as u32, h as u32)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut builder = ChartBuilder::on(&root);
        builder
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64);
        if labels {
            builder.caption(title, ("sans-serif", 18));
        }
        let mut chart = builder.build_cartesian_2d(x.clone().log_scale(), y.clone().log_scale())?;
        if labels {
            chart
                .configure_mesh()
                .x_desc("render time, s")
                .y_desc("relative RMSE")
                .draw()?;
        } else {
            // (plotters' mesh draws its labels' text even when asked for none: the decades by hand.)
            let grey = RGBColor(221, 221, 221);
            for e in (ax.x0 as i32)..=(ax.x1 as i32) {
                let v = 10f64.powi(e);
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(v, y.start), (v, y.end)],
                    grey,
                )))?;
            }
            for e in (ax.y0 as i32)..=(ax.y1 as i32) {
                let v = 10f64.powi(e);
                chart.draw_series(std::iter::once(PathElement::new(
                    vec![(x.start, v), (x.end, v)],
                    grey,
                )))?;
            }
        }
        for (k, name) in estimators(points).iter().enumerate() {
            let (r, g, b) = COLOURS[k % COLOURS.len()];
            let c = RGBColor(r, g, b);
            let pts: Vec<(f64, f64)> = shown
                .iter()
                .filter(|p| &p.estimator == name)
                .map(|p| (p.seconds.max(1e-6), p.rel_rmse.max(1e-9)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), c.stroke_width(2)))?
                .label(name.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(3))
                });
            chart.draw_series(pts.iter().map(|&p| Circle::new(p, 4, c.filled())))?;
        }
        if let Some(p) = mark.and_then(|i| points.get(i)).filter(plotted) {
            let at = (p.seconds.max(1e-6), p.rel_rmse.max(1e-9));
            chart.draw_series(std::iter::once(Circle::new(at, 10, BLACK.stroke_width(2))))?;
            if labels {
                let text = format!("equal-time winner: {} ({})", p.estimator, p.setting);
                chart.draw_series(std::iter::once(
                    EmptyElement::at(at) + Text::new(text, (14, -22), ("sans-serif", 13)),
                ))?;
            }
        }
        if labels {
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperRight)
                .draw()?;
        }
        root.present()?;
        Ok(())
    })();
    let why = match (drawn, font) {
        (Err(e), _) => Some(format!("the PNG's plot: {e}")),
        (Ok(()), Err(e)) => Some(format!("the PNG has no labels: {e}")),
        (Ok(()), Ok(_)) => None,
    };
    (w, h, img, why)
}
