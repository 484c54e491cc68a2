//! `firemedium bench perf`, the user's path: Pegoraro & Parker's workload (a 512² image of a 256³ fire, half-voxel
//! steps, emission–absorption) as a pbrt-v4 scene rendered by `firemedium render` — a child process loading the
//! cdylib, as a user runs it — with each sampler a scene can ask for, against an 8 × 8 sub-pixel reference
//! rendered the same way, and against a naive march written here as the baseline (f64, no empty-space skipping,
//! a fixed half-voxel step from the box's entry, every coefficient evaluated at every step, 2 threads).

use firemedium::metrics::{errors, luminance};
use firemedium_plugin::params::Param;
use firemedium_plugin::volume::FireVolume;
use glam::DVec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

/// What one `firemedium render` reported and wrote.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// Scene load and plugin build, the render, and the child's wall time (process start to exit).
    pub load_s: f64,
    pub render_s: f64,
    pub wall_s: f64,
    pub rays: f64,
    pub peak_mb: f64,
    /// Luminance per pixel.
    pub y: Vec<f64>,
}

/// The medium type a workload scene names its fire with.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// `"string type" "fire"`: the paper's fire (soot, absolute Planck).
    Fire,
    /// `"string type" "nanovdb"`: pbrt-v4's own grid medium over the same file — σ_a = `scale` × density, grey,
    /// with `scale` the soot's σ_a per unit soot fraction at 550 nm (propane, 8.44e6 m⁻¹: 8.44 m⁻¹ at f_v = 1e-6,
    /// Dalzell & Sarofim), no scattering, `Lescale` 1 × the peak-normalised blackbody.
    NanoVdb,
}

impl Kind {
    /// The `MakeNamedMedium` parameters naming the fire's type and file.
    fn medium(self, dataset: &Path) -> String {
        match self {
            Kind::Fire => format!("\"string type\" \"fire\" \"string dataset\" \"{}\"", dataset.display()),
            Kind::NanoVdb => format!(
                "\"string type\" \"nanovdb\" \"string filename\" \"{}\" \"float scale\" 8.44e6 \"spectrum sigma_s\" [200 0 900 0]",
                dataset.display()
            ),
        }
    }
}

/// The workload's scene: `dataset` (whose medium-space box is `bounds`) as a `kind` medium with `medium`
/// parameters appended (pbrt syntax), seen by a pinhole 2.2 fire sizes in front (−y) with a 30° field of view, behind an `interface`
/// box, `volpath` maxdepth 1 (nothing but the fire), `sampler` (a pbrt `Sampler` directive), a box pixel filter
/// (so a pixel is the mean over its area: the reference's sub-pixels average it).
pub fn scene(
    kind: Kind,
    dataset: &Path,
    bounds: [DVec3; 2],
    size: usize,
    sampler: &str,
    medium: &str,
) -> String {
    let [b0, b1] = bounds;
    let c = 0.5 * (b0 + b1);
    let eye = c - DVec3::Y * (2.2 * (b1 - b0).max_element());
    let p = |x: f64, y: f64, z: f64| format!("{x} {y} {z}");
    let corners: Vec<String> = (0..8)
        .map(|k| {
            let q = |a: usize| if k >> a & 1 == 1 { b1[a] } else { b0[a] };
            p(q(0), q(1), q(2))
        })
        .collect();
    format!(
        "LookAt {}  {}  0 0 1\nCamera \"perspective\" \"float fov\" 30\nPixelFilter \"box\"\nFilm \"rgb\" \"integer xresolution\" {size} \"integer yresolution\" {size}\n{sampler}\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" {} {medium}\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" [ {} ] \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]\nAttributeEnd\n",
        p(eye.x, eye.y, eye.z),
        p(c.x, c.y, c.z),
        kind.medium(dataset),
        corners.join("  ")
    )
}

/// The `firemedium` program beside this one (the user's path: the renderer and the plugin it loads).
fn renderer() -> Result<std::path::PathBuf, String> {
    firemedium::program_beside("firemedium").map_err(|p| {
        format!(
            "{} is not there: the user's-path benchmarks render with it (build it with `cargo build --release -p firemedium`)",
            p.display()
        )
    })
}

/// Renders `scene` with `firemedium render` (the program beside this one) and `extra` arguments into `dir`.
pub fn render(dir: &Path, name: &str, scene: &str, extra: &[&str]) -> Result<Rendered, String> {
    let file = dir.join(format!("{name}.pbrt"));
    std::fs::write(&file, scene).map_err(|e| format!("{}: {e}", file.display()))?;
    let out = dir.join(format!("{name}.exr"));
    let exe = renderer()?;
    let start = Instant::now();
    let o = Command::new(exe)
        .arg("render")
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .args(["--quiet", "--stats"])
        .args(extra)
        .output()
        .map_err(|e| format!("firemedium render: {e}"))?;
    let wall_s = start.elapsed().as_secs_f64();
    if !o.status.success() {
        return Err(format!(
            "firemedium render {}: {}",
            file.display(),
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&o.stdout);
    // "scene: X s to load …", "render: X s on N threads, R camera rays, …", "peak memory: X MB".
    let number = |prefix: &str, k: usize| -> Result<f64, String> {
        text.lines()
            .find_map(|l| l.strip_prefix(prefix))
            .and_then(|l| l.split_whitespace().nth(k))
            .and_then(|w| w.parse().ok())
            .ok_or_else(|| format!("firemedium render --stats: no '{prefix}' line in:\n{text}"))
    };
    let img = firemedium::imageio::read(&out, false).map_err(|e| e.to_string())?;
    Ok(Rendered {
        load_s: number("scene: ", 0)?,
        render_s: number("render: ", 0)?,
        wall_s,
        rays: number("render: ", 5)?,
        peak_mb: number("peak memory: ", 0)?,
        y: img.px.iter().map(|&p| luminance(p)).collect(),
    })
}

/// The naive baseline at pixel centres: (load s, render s, luminance per pixel). The same camera as [`scene`]
/// (pbrt-v4's: raster x grows toward −x of the world here, as its `LookAt` with z up gives), one ray per pixel
/// on 2 threads, a half-voxel step from where the ray enters the box to where it leaves it, each step's
/// coefficients evaluated at its midpoint in f64 (`FireVolume::coefficients`: the trilinear lookup and the
/// tables) and integrated exactly for constant coefficients (the paper's eq. 3), no early termination.
pub fn naive(dataset: &Path, size: usize) -> Result<(f64, f64, Vec<f64>), String> {
    let t0 = Instant::now();
    let v = FireVolume::new(&[
        Param::string("filename", &dataset.to_string_lossy()),
        Param::string("precision", "f64"),
        Param::float("stepsize", 0.5),
    ])
    .map_err(|e| e.to_string())?;
    let load_s = t0.elapsed().as_secs_f64();
    let [b0, b1] = v.bounds();
    let c = 0.5 * (b0 + b1);
    let eye = c - DVec3::Y * (2.2 * (b1 - b0).max_element());
    let half = 15f64.to_radians().tan();
    let xyz = v.channel_xyz();
    let n = v.channels();
    let h = v.step_length();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .map_err(|e| e.to_string())?;
    let t1 = Instant::now();
    let y: Vec<f64> = pool.install(|| {
        (0..size * size)
            .into_par_iter()
            .map(|p| {
                let (i, j) = (p % size, p / size);
                let u = (1.0 - (i as f64 + 0.5) / size as f64 * 2.0) * half;
                let w = (1.0 - (j as f64 + 0.5) / size as f64 * 2.0) * half;
                let d = DVec3::new(u, 1.0, w).normalize();
                let Some((a, b)) = firemedium_plugin::majorant::clip_box(eye, d, 0.0, 1e30, b0, b1)
                else {
                    return 0.0;
                };
                let (mut sa, mut ss, mut jj) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
                let (mut l, mut t) = (vec![0.0; n], vec![1.0; n]);
                let mut s = a;
                while s < b {
                    let s1 = (s + h).min(b);
                    v.coefficients(eye + d * (0.5 * (s + s1)), &mut sa, &mut ss, &mut jj);
                    for k in 0..n {
                        let st = sa[k] + ss[k];
                        let tau = st * (s1 - s);
                        if st > 0.0 {
                            let e = (-tau).exp();
                            l[k] += t[k] * jj[k] / st * (1.0 - e);
                            t[k] *= e;
                        }
                    }
                    s = s1;
                }
                (0..n).map(|k| l[k] * xyz[k].y).sum()
            })
            .collect()
    });
    Ok((load_s, t1.elapsed().as_secs_f64(), y))
}

/// Relative RMSE of `a` against `r` (over all pixels: √(Σ(a − r)²/Σr²)).
pub fn rel_rmse(a: &[f64], r: &[f64]) -> f64 {
    errors(a, r).0
}

/// A temporary directory for the bench's scenes and images, removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(name: &str) -> Result<Scratch, String> {
        let d =
            std::env::temp_dir().join(format!("firemedium-bench-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).map_err(|e| format!("{}: {e}", d.display()))?;
        Ok(Scratch(d))
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// The workload through `firemedium render` (this module).
pub fn report(a: &crate::PerfArgs) -> Result<String, String> {
    let file = match &a.dataset {
        Some(f) => f.clone(),
        None => crate::perf::dataset(&std::env::temp_dir(), a.grid as usize)?,
    };
    let file = file
        .canonicalize()
        .map_err(|e| format!("{}: {e}", file.display()))?;
    let size = a.image as usize;
    let bounds =
        firemedium_plugin::volume::FireVolume::new(&[firemedium_plugin::params::Param::string(
            "filename",
            &file.to_string_lossy(),
        )])
        .map_err(|e| e.to_string())?
        .bounds();
    let dir = Scratch::new("perf")?;
    let stratified = |n: u32| {
        format!("Sampler \"stratified\" \"integer xsamples\" {n} \"integer ysamples\" {n} \"bool jitter\" false")
    };
    let centres = stratified(1);
    let step = |h: f64| format!("\"float stepsize\" {h}");
    let half = step(0.5);
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut out = format!(
        "dataset {} ({:.1} MB), {size}×{size} pixels, `firemedium render` (a child process, the cdylib) on {cores} threads unless said; fastest of {} alternating round(s)\n\n",
        file.display(),
        std::fs::metadata(&file).map_or(0.0, |m| m.len() as f64 / 1e6),
        a.repeat
    );
    // The references, one per medium type (the same data, another emission): sub-pixel centres, a finer step;
    // the fire's own step error from pixel-centre renders at its step and half of it.
    let (r, rs) = (a.reference_subpixels, a.reference_path_step);
    let mut references = Vec::new();
    for kind in [Kind::Fire, Kind::NanoVdb] {
        let name = format!("reference-{kind:?}");
        let sc = scene(kind, &file, bounds, size, &stratified(r), &step(rs));
        references.push(render(&dir.0, &name, &sc, &[])?);
    }
    let at = |h: f64, name: &str| {
        render(
            &dir.0,
            name,
            &scene(Kind::Fire, &file, bounds, size, &centres, &step(h)),
            &[],
        )
    };
    let (coarse, fine) = (
        at(rs, "centres-ref-step")?,
        at(0.5 * rs, "centres-half-ref-step")?,
    );
    let (subpix, ref_step) = (
        rel_rmse(&coarse.y, &references[0].y),
        rel_rmse(&coarse.y, &fine.y),
    );
    out += &format!(
        "references: {r}×{r} sub-pixel centres at a {rs}-voxel step, default spectrum ({:.1} s the fire, {:.1} s the nanovdb medium); the fire's step error ≈ {ref_step:.2e} (pixel centres at {rs} against {} voxel); pixel centres differ from it by {subpix:.2e} at {rs} voxel. The nanovdb medium is pbrt-v4's own type over the same file (σ_a = 8.44e6 × density, grey, the peak-normalised blackbody; its default estimator)\n\n",
        references[0].render_s,
        references[1].render_s,
        0.5 * rs
    );
    let configs: Vec<(&str, Kind, String, String, Vec<&str>)> = vec![
        (
            "pixel centres (stratified 1×1, no jitter), ½ voxel: the paper's workload",
            Kind::Fire,
            centres.clone(),
            half.clone(),
            vec![],
        ),
        (
            "the same as a pbrt-v4 `nanovdb` medium",
            Kind::NanoVdb,
            centres.clone(),
            String::new(),
            vec![],
        ),
        (
            "the same on 1 thread",
            Kind::Fire,
            centres.clone(),
            half.clone(),
            vec!["--threads", "1"],
        ),
        (
            "pixel centres, ½ voxel, 16 bins over 400–780 nm",
            Kind::Fire,
            centres.clone(),
            format!("{half} \"integer bins\" 16 \"float lambdamin\" 400 \"float lambdamax\" 780"),
            vec![],
        ),
        (
            "zsobol, 16 spp, ½ voxel",
            Kind::Fire,
            "Sampler \"zsobol\" \"integer pixelsamples\" 16".into(),
            half.clone(),
            vec![],
        ),
        (
            "zsobol, 16 spp, a `nanovdb` medium",
            Kind::NanoVdb,
            "Sampler \"zsobol\" \"integer pixelsamples\" 16".into(),
            String::new(),
            vec![],
        ),
        (
            "independent, 16 spp, ½ voxel",
            Kind::Fire,
            "Sampler \"independent\" \"integer pixelsamples\" 16".into(),
            half.clone(),
            vec![],
        ),
        (
            "pixel centres, a `nanovdb` medium with pbrt-v4's estimator (`integrator \"ratio\"`)",
            Kind::NanoVdb,
            centres.clone(),
            "\"string integrator\" \"ratio\"".into(),
            vec![],
        ),
    ];
    let mut best: Vec<Option<Rendered>> = vec![None; configs.len()];
    let mut base: Option<(f64, f64, Vec<f64>)> = None;
    for _ in 0..a.repeat {
        // Alternating: the baseline, then every configuration, each round.
        let n = naive(&file, size)?;
        if base.as_ref().is_none_or(|b| n.0 + n.1 < b.0 + b.1) {
            base = Some(n);
        }
        for (k, (name, kind, sampler, medium, extra)) in configs.iter().enumerate() {
            let r = render(
                &dir.0,
                &format!("config{k}"),
                &scene(*kind, &file, bounds, size, sampler, medium),
                extra,
            )
            .map_err(|e| format!("{name}: {e}"))?;
            if best[k].as_ref().is_none_or(|b| r.wall_s < b.wall_s) {
                best[k] = Some(r);
            }
        }
    }
    let Some((nl, nr, ny)) = base else {
        return Err("no round ran".into());
    };
    let naive_total = nl + nr;
    out += "| configuration | load s | render s | total s (process) | rays/s | peak MB | rel. RMSE vs reference | total / naive |\n|---|---|---|---|---|---|---|---|\n";
    out += &format!(
        "| naive march (f64, no skipping, every coefficient at every step, 2 threads, in process) | {nl:.3} | {nr:.3} | {naive_total:.3} | {:.0} | — | {:.2e} | 1 |\n",
        (size * size) as f64 / nr,
        rel_rmse(&ny, &references[0].y)
    );
    for ((name, kind, ..), r) in configs.iter().zip(&best) {
        let Some(r) = r else { continue };
        let reference = &references[(*kind == Kind::NanoVdb) as usize];
        out += &format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.0} | {:.0} | {:.2e} | {:.2} |\n",
            r.load_s,
            r.render_s,
            r.wall_s,
            r.rays / r.render_s,
            r.peak_mb,
            rel_rmse(&r.y, &reference.y),
            r.wall_s / naive_total
        );
    }
    if let (Some(fire), Some(nvdb)) = (&best[0], &best[1]) {
        out += &format!(
            "\nthe `nanovdb` medium against the fire (whole process): {:.2}×\n",
            nvdb.wall_s / fire.wall_s
        );
    }
    if let (Some(two), Some(one)) = (&best[0], &best[2]) {
        out += &format!(
            "\ntwo threads against one (render phase): {:.2}×\n",
            one.render_s / two.render_s
        );
    }
    Ok(out)
}
