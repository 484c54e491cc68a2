//! `firemedium-bench` (run as `firemedium bench …`): the measurements behind docs/results/log.md, as commands anyone
//! can rerun. It links the plugin as a library to time its parts in process (the march kernel, the components'
//! build costs, the stability cases), and renders the user's path with the `firemedium` program beside it.

mod components;
mod error;
mod fire_light;
mod memory;
mod noise;
mod perf;
mod stability;
mod user_path;

use clap::{Args, Parser, Subcommand};
use std::io::Write;
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(
    name = "firemedium bench",
    bin_name = "firemedium bench",
    version,
    about = "firemedium's benchmarks"
)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, Subcommand)]
enum What {
    /// Stiff and extreme cases, expected vs measured; exits 1 if any fails.
    Stability,
    /// Pegoraro & Parker's workload (512², a 256³ fire, half-voxel steps) as a pbrt-v4 scene through
    /// `firemedium render` and the cdylib, per sampler, against an 8×8 sub-pixel reference and a naive march;
    /// `--kernel`: the march alone, in process (a micro-benchmark).
    Perf(PerfArgs),
    /// Error against render time of every estimator of the fire seen directly: march (spectral, rgb) at a
    /// ladder of steps, delta and ratio tracking at a ladder of samples; then the fire lighting surfaces, the fire
    /// light on and off, with every render's own error estimate beside its true error; CSV + log–log plot (SVG, PNG).
    ErrorVsTime(ErrorArgs),
    /// What the plugin builds for the same fire with and without species, refraction and the fire light:
    /// bytes and set-up time per component (unused parts cost nothing).
    Components(ComponentsArgs),
    /// The fire light's estimators against each other and against leaving it off, on the surfaces of a fire-lit
    /// room, with the campfire at several resolutions: error against time (CSV + log–log plot per resolution),
    /// error × time, and a light sample's cost beside a camera path.
    FireLight(FireLightArgs),
    /// Every render's own error estimate against its true error (the scene's sampler and independent samples,
    /// at a ladder of samples per pixel), and adaptive sampling (`--noise-threshold`) against uniform at equal
    /// true error, on the campfire scene and the fire-lit room (the campfire at 128³).
    Noise(noise::NoiseArgs),
    /// Peak RSS on the two rooms pbrt-v4's memory was measured on (a scattering fire, and an absorbing one lit by
    /// the fire light, as pbrt-v4's `nanovdb` medium) through `firemedium render`, beside pbrt-v4's figures, with
    /// the medium's default lattice and with the march's copy (`dense`), alternating rounds.
    Memory(memory::MemoryArgs),
    /// Redraws a ladder's plot (SVG, PNG) from its CSV, as `error-vs-time` and `fire-light` write it: the plots
    /// of committed measurements, without measuring again.
    Plot(PlotArgs),
}

#[derive(Debug, Args)]
pub struct PlotArgs {
    /// The ladder's CSV (estimator,setting,seconds,rel_rmse,rel_mse,medium_evaluations).
    csv: std::path::PathBuf,
    /// The plot's title.
    #[arg(long)]
    title: String,
    /// Output prefix: PREFIX.svg and PREFIX.png (default: the CSV's path without its extension).
    #[arg(short, long)]
    output: Option<std::path::PathBuf>,
}

#[derive(Debug, Args)]
pub struct FireLightArgs {
    /// The campfire's resolutions (voxels along its longest side), generated once into the temp directory.
    #[arg(long, value_delimiter = ',', default_value = "64,128,256",
          value_parser = clap::value_parser!(u32).range(16..=1024))]
    resolutions: Vec<u32>,
    /// Image width and height.
    #[arg(long, default_value = "160x120", value_parser = firemedium::args::parse_resolution)]
    image: (usize, usize),
    /// The light's samples-per-pixel ladder (the light off renders 4× each).
    #[arg(long, value_delimiter = ',', default_value = "4,16,64",
          value_parser = clap::value_parser!(u32).range(1..=65536))]
    spp: Vec<u32>,
    /// Samples per pixel of each resolution's reference (the fire light's pdf over bricks with the volume's own
    /// march), rendered in two halves whose difference takes the reference's own noise out of every error.
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=1048576))]
    reference_spp: u32,
    /// Rounds: every estimator renders its ladder once per round, the estimators in turn, and each rung's time
    /// is its median over the rounds (the images are the same every round: one seed per rung). The machine's
    /// speed drifts between runs by tens of per cent; alternating and the median keep one run's rows comparable.
    #[arg(long, default_value_t = 3, value_parser = clap::value_parser!(u32).range(1..=100))]
    repeats: u32,
    /// The estimators (comma-separated keys): off, voxel, brick, own, allbins, steps64, coarse, corrected, luminance,
    /// escaping, pbrt (pbrt-v4's own: ratio tracking and the light off; a nanovdb or uniformgrid fire only), inside
    /// (the default, with the light sampled from scattering events inside the fire too).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "off,voxel,brick,own,allbins,steps64,coarse,corrected,luminance,escaping"
    )]
    estimators: Vec<String>,
    /// The generated room's fire: `fire` (the paper's, propane soot) or `nanovdb` (pbrt-v4's own grid medium
    /// over the same file: σ_a = 8.44e6 × density, grey, the peak-normalised blackbody × `--lescale`).
    #[arg(long, default_value = "fire", value_parser = ["fire", "nanovdb"])]
    medium: String,
    /// With `--medium nanovdb`: the fire's single-scattering albedo σ_s / σ_t (isotropic; 0: it does not scatter).
    #[arg(long, default_value_t = 0.0)]
    albedo: f64,
    /// With `--medium nanovdb`: its `Lescale`.
    #[arg(long, default_value_t = 1.0)]
    lescale: f64,
    /// The generated room's `volpath` maxdepth.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u32).range(0..=1000))]
    maxdepth: u32,
    /// Output prefix: PREFIX-R.csv, PREFIX-R.svg and PREFIX-R.png per resolution R (PREFIX-NAME.* for a scene).
    #[arg(short, long, default_value = "fire-light")]
    output: std::path::PathBuf,
    /// A scene lit by a fire to measure instead of the generated room (e.g. scenes/mantaflow/scene.pbrt); the
    /// resolutions are then not used.
    #[arg(long)]
    scene: Option<std::path::PathBuf>,
}

#[derive(Debug, Args)]
pub struct ComponentsArgs {
    /// A dataset with a sodium grid; default: the repository's scenes/spectroscopy/torch.vdb (from the
    /// working directory if it holds one, else from the source tree this command was built from).
    #[arg(long)]
    dataset: Option<std::path::PathBuf>,
}

#[derive(Debug, Args)]
pub struct ErrorArgs {
    /// The fire (a dataset file); default: the campfire of scenes/campfire (generated into the temp directory
    /// when run elsewhere than the repository's root).
    #[arg(long)]
    dataset: Option<std::path::PathBuf>,
    /// Image width and height, pixels.
    #[arg(long, default_value_t = 128, value_parser = clap::value_parser!(u32).range(4..=4096))]
    image: u32,
    /// The largest samples per pixel of the tracking ladder (1, 2, 4, … up to it).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(1..=65536))]
    max_spp: u32,
    /// Output prefix: PREFIX.csv, PREFIX.svg, PREFIX.png, and PREFIX-surface.* for the surface scene.
    #[arg(short, long, default_value = "error-vs-time")]
    output: std::path::PathBuf,
    /// The second scene, the fire lighting surfaces (fire light on/off); default scenes/campfire/scene.pbrt
    /// when run from the repository's root; `none` to skip.
    #[arg(long)]
    surface: Option<String>,
    /// The surface scene's resolution.
    #[arg(long, default_value = "80x60", value_parser = firemedium::args::parse_resolution)]
    surface_resolution: (usize, usize),
    /// The surface ladder's largest samples per pixel (1, 2, 4, … up to it).
    #[arg(long, default_value_t = 64)]
    surface_max_spp: usize,
    /// Samples per pixel of the surface scene's reference render (the error's baseline).
    #[arg(long, default_value_t = 1024)]
    surface_reference_spp: usize,
}

#[derive(Debug, Args)]
pub struct PerfArgs {
    /// Voxels along the fire's longest side (the campfire dataset, generated once into the temp directory).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(8..=1024))]
    grid: u32,
    /// Image width and height, pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(8..=8192))]
    image: u32,
    /// A dataset file instead of the generated campfire.
    #[arg(long)]
    dataset: Option<std::path::PathBuf>,
    /// The reference's march step, voxels.
    #[arg(long, default_value_t = 0.0625)]
    reference_step: f64,
    /// The reference's spectral bins over 380–780 nm, the whole support of the CIE ȳ table (its correction from
    /// the default spectrum, made at ½ voxel).
    #[arg(long, default_value_t = 320, value_parser = clap::value_parser!(u32).range(30..=4096))]
    reference_bins: u32,
    /// Time each configuration this many times and report the fastest run, load + render (the machine's speed
    /// drifts by tens of percent between runs; the fastest is the least disturbed).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=100))]
    repeat: u32,
    /// The march alone, in process, with its own camera (a kernel micro-benchmark: no scene, no renderer, no
    /// ABI), against a reference at `--reference-step` with `--reference-bins`.
    #[arg(long)]
    kernel: bool,
    /// The user-path reference's sub-pixels per side (stratified, at their centres).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u32).range(1..=64))]
    reference_subpixels: u32,
    /// The user-path reference's march step, voxels.
    #[arg(long, default_value_t = 0.25)]
    reference_path_step: f64,
}

pub fn run(a: &BenchArgs) -> Result<String, (u8, String)> {
    match &a.what {
        What::Perf(p) => perf_report(p).map_err(|e| (1, e)),
        What::ErrorVsTime(e) => error_report(e).map_err(|m| (1, m)),
        What::Components(c) => components::report(c).map_err(|m| (1, m)),
        What::FireLight(f) => fire_light_report(f).map_err(|m| (1, m)),
        What::Plot(p) => plot_report(p).map_err(|m| (1, m)),
        What::Noise(n) => noise::report(n).map_err(|m| (1, m)),
        What::Memory(m) => memory::report(m).map_err(|e| (1, e)),
        What::Stability => {
            let start = std::time::Instant::now();
            let cases = stability::cases();
            let (table, ok) = stability::table(&cases);
            let failed = cases.iter().filter(|c| !c.pass).count();
            let summary = format!(
                "{} cases, {} failed, {:.2} s\n",
                cases.len(),
                failed,
                start.elapsed().as_secs_f64()
            );
            if ok {
                Ok(table + &summary)
            } else {
                print!("{table}");
                Err((
                    1,
                    format!("stability: {failed} of {} cases failed", cases.len()),
                ))
            }
        }
    }
}

fn perf_report(a: &PerfArgs) -> Result<String, String> {
    if !a.kernel {
        return user_path::report(a);
    }
    use firemedium_plugin::params::Param;
    let file = match &a.dataset {
        Some(f) => f.clone(),
        None => perf::dataset(&std::env::temp_dir(), a.grid as usize)?,
    };
    let size = a.image as usize;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut out = format!(
        "dataset {} ({}), image {size}×{size}, 1 ray per pixel, {cores} threads, fastest of {} run(s)\n\n",
        file.display(),
        std::fs::metadata(&file)
            .map(|m| format!("{:.1} MB", m.len() as f64 / 1e6))
            .unwrap_or_default(),
        a.repeat
    );
    // The reference, in f64 (so the error column holds the f32 lanes' rounding too), converged in each of the
    // workload's discretisations: the march at `reference_step` with the default spectrum, plus
    // the spectral correction at ½ voxel from those bins to `reference_bins` bins over 380–780 nm — the whole
    // of ȳ, whose tail past 700 nm carries a fire's red (the errors are nearly independent: the step's is O(h²),
    // the spectrum's O(1/N²) plus the range's, and the difference of two ½-voxel images carries the step error
    // only through its change with the spectrum).
    let f64_run = |extra: &[Param]| {
        let mut list = vec![Param::string("precision", "f64")];
        list.extend_from_slice(extra);
        perf::run(&file, &list, size)
    };
    let fine_step = f64_run(&[Param::float("stepsize", a.reference_step)])?;
    let half = f64_run(&[Param::float("stepsize", 0.5)])?;
    let half_fine = f64_run(&[
        Param::float("stepsize", 0.5),
        Param::int("bins", a.reference_bins as i64),
        Param::float("lambdamin", 380.0),
        Param::float("lambdamax", 780.0),
    ])?;
    let reference: Vec<f64> = fine_step
        .image
        .iter()
        .zip(half_fine.image.iter().zip(&half.image))
        .map(|(r, (f, h))| r + (f - h))
        .collect();
    out += &format!(
        "reference: march at {} voxel in f64 with the default spectrum ({:.1} s) + the correction to {} bins over 380–780 nm at ½ voxel ({:.1} s); at ½ voxel with the default spectrum (f64) the step alone is {:.2e} off it, the spectrum alone {:.2e} (the bins and the range; `spectral_bins` splits them)\n\n",
        a.reference_step,
        fine_step.render_s,
        a.reference_bins,
        half_fine.render_s + half.render_s,
        firemedium::metrics::errors(&half.image, &fine_step.image).0,
        firemedium::metrics::errors(&half.image, &half_fine.image).0,
    );
    out += "| configuration | load s | render s | total s | rays/s | steps/s | samples | samples/s/core | rel. RMSE |\n|---|---|---|---|---|---|---|---|---|\n";
    // Over 400–780 nm, the range that holds ȳ for a fire (380–400 nm adds 1.6e-7 here).
    let wide = |bins: i64| {
        vec![
            Param::float("stepsize", 0.5),
            Param::int("bins", bins),
            Param::float("lambdamin", 400.0),
            Param::float("lambdamax", 780.0),
        ]
    };
    let thesis = |extra: Vec<Param>| {
        let mut list = vec![
            Param::float("stepsize", 0.5),
            Param::int("bins", 30),
            Param::float("lambdamax", 700.0),
        ];
        list.extend(extra);
        list
    };
    let configs: Vec<(&str, Vec<Param>)> = vec![
        (
            "march ½ voxel, spectral (30 bins, 400–700 nm: the thesis's)",
            thesis(vec![]),
        ),
        (
            "march ½ voxel, spectral (32 bins, 400–780 nm: the default)",
            wide(32),
        ),
        ("march ½ voxel, spectral (16 bins, 400–780 nm)", wide(16)),
        (
            "march ½ voxel, spectral (30 bins, 400–700 nm), f64 (no lanes)",
            thesis(vec![Param::string("precision", "f64")]),
        ),
        (
            "march ½ voxel, rgb",
            vec![
                Param::float("stepsize", 0.5),
                Param::string("colormode", "rgb"),
            ],
        ),
        (
            "march ½ voxel, spectral (the default), refraction",
            vec![
                Param::float("stepsize", 0.5),
                Param::bool("refraction", true),
            ],
        ),
    ];
    for (name, params) in configs {
        // The fastest whole run (load + render: the workload's time, from loading the grid to the last ray).
        let mut r = perf::run(&file, &params, size)?;
        for _ in 1..a.repeat {
            let again = perf::run(&file, &params, size)?;
            if again.load_s + again.render_s < r.load_s + r.render_s {
                r = again;
            }
        }
        let total = r.load_s + r.render_s;
        // Every row against the one reference: rgb's error is then its bands' (it does not converge to the
        // spectral answer); refraction bends rays, so its error is mostly the refraction itself.
        let (err, _) = firemedium::metrics::errors(&r.image, &reference);
        out += &format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.0} | {:.3e} | {:.3e} | {:.3e} | {:.2e} |\n",
            r.load_s,
            r.render_s,
            total,
            r.rays as f64 / r.render_s,
            r.samples / r.render_s,
            r.evaluations as f64,
            r.evaluations as f64 / r.render_s / cores as f64,
            err
        );
    }
    if let Some(m) = firemedium::budget::peak_rss() {
        out += &format!("\npeak memory (VmHWM) {:.0} MB\n", m as f64 / 1e6);
    }
    Ok(out)
}

fn error_report(a: &ErrorArgs) -> Result<String, String> {
    let file = match &a.dataset {
        Some(f) => f.clone(),
        None => {
            let local = repository_file("scenes/campfire/campfire.vdb");
            if local.is_file() {
                local
            } else {
                perf::dataset(&std::env::temp_dir(), 96)?
            }
        }
    };
    let (points, about) = error::ladder(&file, a.image as usize, a.max_spp as usize)?;
    let title = format!(
        "the fire seen directly ({}): error vs time",
        file.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default()
    );
    let mut out = write_ladder(
        &a.output,
        "",
        &points,
        &about,
        &title,
        error::winner(&points),
    )?;
    let surface = match a.surface.as_deref() {
        Some("none") => None,
        Some(s) => Some(std::path::PathBuf::from(s)),
        None => Some(repository_file("scenes/campfire/scene.pbrt")).filter(|p| p.is_file()),
    };
    if let Some(scene) = surface {
        let (points, about) = error::surface_ladder(
            &scene,
            a.surface_resolution,
            a.surface_max_spp,
            a.surface_reference_spp,
        )?;
        out += "\n";
        out += &write_ladder(
            &a.output,
            "-surface",
            &points,
            &about,
            "the fire lighting surfaces: error vs time",
            error::winner(&points),
        )?;
    }
    Ok(out)
}

fn fire_light_report(a: &FireLightArgs) -> Result<String, String> {
    let chosen: Vec<&fire_light::Estimator> = a
        .estimators
        .iter()
        .map(|k| {
            fire_light::ESTIMATORS
                .iter()
                .find(|e| e.key == k)
                .ok_or_else(|| {
                    let keys: Vec<&str> = fire_light::ESTIMATORS.iter().map(|e| e.key).collect();
                    format!(
                        "--estimators: no estimator {k:?} (there are {})",
                        keys.join(", ")
                    )
                })
        })
        .collect::<Result<_, _>>()?;
    let spp: Vec<usize> = a.spp.iter().map(|&n| n as usize).collect();
    let dir = std::env::temp_dir();
    let baseline = match chosen.iter().any(|e| e.ratio) {
        true => "pbrt-v4's estimator (ratio tracking, the light off)",
        false => "the light off",
    };
    let mut out = format!(
        "{}\ngains against {baseline}; bias: the surfaces' mean against the reference's, less 1, at the largest rung (what does not average out; the reference's own noise, about its rel. RMSE over √pixels, bounds what shows)\n\n| fire | estimator | rel. RMSE² × s | baseline / it | relMSE × s | baseline / it | bias | a light sample, in camera paths |\n|---|---|---|---|---|---|---|---|\n",
        machine()
    );
    // (label, scene, title, whether the bench wrote the scene)
    let mut cases = Vec::new();
    match &a.scene {
        Some(s) => {
            // Its folder and file name (scenes/mantaflow/scene.pbrt: `mantaflow-scene`).
            let part = |p: Option<&std::ffi::OsStr>| {
                p.map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default()
            };
            let folder = part(s.parent().and_then(|p| p.file_name()));
            let stem = part(s.file_stem());
            let name = if folder.is_empty() {
                stem
            } else {
                format!("{folder}-{stem}")
            };
            let title = format!("{name}: surface error vs time");
            cases.push((name, s.clone(), title, false));
        }
        None => {
            for &r in &a.resolutions {
                let dataset = perf::dataset(&dir, r as usize)?;
                let scene = dir.join(format!(
                    "firemedium-bench-room-{r}-{}.pbrt",
                    std::process::id()
                ));
                let fire = match a.medium.as_str() {
                    "nanovdb" => fire_light::Fire::NanoVdb {
                        albedo: a.albedo,
                        lescale: a.lescale,
                    },
                    _ => fire_light::Fire::Fire,
                };
                if !((0.0..1.0).contains(&a.albedo) && a.lescale >= 0.0 && a.lescale.is_finite()) {
                    return Err(format!(
                        "--albedo {} --lescale {}: expected an albedo in [0, 1) and a finite Lescale ≥ 0",
                        a.albedo, a.lescale
                    ));
                }
                std::fs::write(&scene, fire_light::room_scene(&dataset, fire, a.maxdepth))
                    .map_err(|e| format!("{}: {e}", scene.display()))?;
                let title = format!("fire-lit room, campfire {r}: error vs time");
                cases.push((format!("{r}"), scene, title, true));
            }
        }
    }
    for (label, scene, title, written) in cases {
        let r = if written {
            format!("{label}³")
        } else {
            label.clone()
        };
        let result = fire_light::ladder(
            &scene,
            &r,
            a.image,
            &spp,
            a.reference_spp as usize,
            a.repeats as usize,
            &chosen,
            &|line| eprintln!("{line}"),
        );
        if written {
            let _ = std::fs::remove_file(&scene);
        }
        let (runs, about) = result?;
        let prefix = fire_light::output(&a.output, &label, "");
        // (No winner circled: the rungs of different estimators do not meet at one time.)
        write_ladder(
            &prefix,
            "",
            &fire_light::points(&runs),
            &about,
            &title,
            None,
        )?;
        for l in fire_light::summary(&runs) {
            out += &format!(
                "| {r} | {} | {:.3e} | {:.1}× | {:.3e} | {:.1}× | {:+.2e} | {} |\n",
                l.estimator,
                l.rmse2_s,
                l.gain_rmse2,
                l.relmse_s,
                l.gain_relmse,
                l.level,
                l.sample_cost
                    .map_or_else(|| "—".to_string(), |c| format!("{c:.2}"))
            );
        }
    }
    Ok(out)
}

/// Writes the ladder's CSV, SVG and PNG; `mark`: the point the plots circle (and the text names) as the equal-time
/// winner, if any.
/// `bench plot`: a ladder's CSV read back (every row checked) and drawn as the bench draws it.
fn plot_report(a: &PlotArgs) -> Result<String, String> {
    let name = a.csv.display();
    let text = std::fs::read_to_string(&a.csv).map_err(|e| format!("{name}: cannot read: {e}"))?;
    let points = error::parse_csv(&text).map_err(|m| format!("{name}: {m}"))?;
    let prefix = a.output.clone().unwrap_or_else(|| a.csv.with_extension(""));
    let (svg_path, png_path) = (prefix.with_extension("svg"), prefix.with_extension("png"));
    let mark = error::winner(&points);
    let write = |path: &std::path::Path, bytes: &[u8]| {
        firemedium::imageio::write_atomic(path, |tmp| {
            std::fs::write(tmp, bytes)
                .map_err(|e| firemedium::Error::file(path.display(), format!("cannot write: {e}")))
        })
        .map_err(|e| e.to_string())
    };
    write(&svg_path, error::svg(&points, &a.title, mark).as_bytes())?;
    let (w, h, rgb, why) = error::png(&points, &a.title, mark);
    if let Some(why) = why {
        eprintln!("firemedium: {}: {why}", png_path.display());
    }
    firemedium::imageio::write_png_bytes(&png_path, w, h, &rgb, false)
        .map_err(|e| e.to_string())?;
    Ok(format!(
        "{} points from {name}: wrote {} and {}\n",
        points.len(),
        svg_path.display(),
        png_path.display()
    ))
}

fn write_ladder(
    prefix: &std::path::Path,
    suffix: &str,
    points: &[error::Point],
    about: &str,
    title: &str,
    mark: Option<usize>,
) -> Result<String, String> {
    let with = |ext: &str| {
        let mut p = prefix.as_os_str().to_owned();
        p.push(suffix);
        p.push(ext);
        std::path::PathBuf::from(p)
    };
    let (csv_path, svg_path, png_path) = (with(".csv"), with(".svg"), with(".png"));
    let write = |path: &std::path::Path, bytes: &[u8]| {
        firemedium::imageio::write_atomic(path, |tmp| {
            std::fs::write(tmp, bytes)
                .map_err(|e| firemedium::Error::file(path.display(), format!("cannot write: {e}")))
        })
    };
    write(&csv_path, error::csv(points).as_bytes()).map_err(|e| e.to_string())?;
    write(&svg_path, error::svg(points, title, mark).as_bytes()).map_err(|e| e.to_string())?;
    let (w, h, rgb, why) = error::png(points, title, mark);
    if let Some(why) = why {
        eprintln!("firemedium: {}: {why}", png_path.display());
    }
    firemedium::imageio::write_png_bytes(&png_path, w, h, &rgb, false)
        .map_err(|e| e.to_string())?;
    let mut out = format!("{}\n{about}\n\nbias: the image's mean against the reference's, less 1 — the error that does not average out over the pixels (noise does), beside the rel. RMSE of bias and noise together\n\n| estimator | setting | seconds | rel. RMSE | relMSE | bias | medium evaluations |\n|---|---|---|---|---|---|---|\n", machine());
    for p in points {
        out += &format!(
            "| {} | {} | {:.3} | {:.3e} | {} | {} | {} |\n",
            p.estimator,
            p.setting,
            p.seconds,
            p.rel_rmse,
            match p.rel_mse.is_nan() {
                true => "—".to_string(),
                false => format!("{:.3e}", p.rel_mse),
            },
            p.level
                .map_or_else(|| "—".to_string(), |l| format!("{l:+.2e}")),
            p.evaluations
                .map(|n| n.to_string())
                .unwrap_or_else(|| "—".into())
        );
    }
    if let Some(i) = mark {
        out += &format!(
            "\nequal-time winner: {} ({}), rel. RMSE {:.3e}\n",
            points[i].estimator, points[i].setting, points[i].rel_rmse
        );
    }
    out += &format!(
        "wrote {}, {}, {}\n",
        csv_path.display(),
        svg_path.display(),
        png_path.display()
    );
    Ok(out)
}

/// A file of the repository, `rel` from its root: from the working directory when it holds it (a clone's
/// root), else from the source tree this binary was built from, else `rel` as it is (its absence is then the
/// error the caller reports, naming it).
pub(crate) fn repository_file(rel: &str) -> std::path::PathBuf {
    let here = std::path::PathBuf::from(rel);
    if here.exists() {
        return here;
    }
    let built = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    if built.exists() {
        built
    } else {
        here
    }
}

fn main() -> ExitCode {
    let args = match BenchArgs::try_parse() {
        Ok(args) => args,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(
                e.kind(),
                ErrorKind::DisplayHelp
                    | ErrorKind::DisplayVersion
                    | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
            ) {
                print!("{e}");
                return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
            }
            eprintln!(
                "firemedium bench: {}",
                firemedium::term::one_line(&e.render().to_string())
            );
            return ExitCode::from(2);
        }
    };
    match run(&args) {
        Ok(text) => {
            // A closed pipe (`| head`) is not an error worth a panic.
            let _ = std::io::stdout().lock().write_all(text.as_bytes());
            ExitCode::SUCCESS
        }
        Err((status, msg)) => {
            let msg = firemedium::term::printable(&msg, firemedium::term::MAX_MESSAGE_CHARS);
            eprintln!("firemedium bench: {}", msg.replace('\n', " "));
            ExitCode::from(status)
        }
    }
}

/// The machine a measurement ran on and its load, for every table's heading: the processor, the cores this
/// process may use, the SIMD level the march was asked for, and the load average (1, 5, 15 minutes) when the
/// measurement began — a benchmark beside another job reads slower, and says so.
pub(crate) fn machine() -> String {
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| std::env::consts::ARCH.to_string());
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let load = std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|t| t.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|| "unknown".into());
    let simd =
        std::env::var("FIREMEDIUM_SIMD").unwrap_or_else(|_| "the best the processor has".into());
    format!("machine: {cpu}, {cores} cores, SIMD {simd}; load average {load} at the start")
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_png_plot_draws_each_estimator_in_its_colour_where_its_points_are() {
        // Two estimators over two decades of time and error; each one's colour must appear near its markers,
        // the winner's ring in black, whether or not the machine has a font for the labels.
        let point = |estimator: &str, seconds: f64, rel_rmse: f64| super::error::Point {
            estimator: estimator.into(),
            setting: "spp".into(),
            seconds,
            rel_rmse,
            rel_mse: rel_rmse * rel_rmse,
            evaluations: None,
            level: None,
        };
        let points = [
            point("off", 0.5, 2.0),
            point("off", 5.0, 0.6),
            point(
                "a light with a name longer than the old legend held",
                0.6,
                0.5,
            ),
            point(
                "a light with a name longer than the old legend held",
                6.0,
                0.15,
            ),
        ];
        let (w, h, rgb, why) = super::error::png(&points, "test", Some(3));
        assert_eq!((w, h, rgb.len()), (760, 480, 760 * 480 * 3));
        if let Some(why) = &why {
            assert!(why.starts_with("the PNG has no labels"), "{why}");
        }
        let count = |c: [u8; 3]| rgb.chunks_exact(3).filter(|p| *p == c).count();
        // COLOURS[0] and [1]: the first and second estimator's lines and markers.
        let (first, second) = (count([214, 39, 40]), count([255, 127, 14]));
        assert!(first > 200 && second > 200, "{first} {second}");
        assert!(count([0, 0, 0]) > 50);
        // A point without a finite error (a dark reference) is left off the axes, not drawn at infinity; with
        // none left, a blank plot and the reason.
        let mut odd = points.to_vec();
        odd.push(point("off", f64::INFINITY, f64::NAN));
        let (_, _, same, _) = super::error::png(&odd, "test", Some(3));
        assert_eq!(same, rgb);
        let (_, _, blank, why) = super::error::png(&odd[4..], "test", None);
        assert!(blank.iter().all(|&b| b == 255));
        assert_eq!(
            why.as_deref(),
            Some("no point with a finite time and error to plot")
        );
    }

    #[test]
    fn the_csv_quotes_names_holding_commas() {
        let p = super::error::Point {
            estimator: "brick pdf, coarse \"march\"".into(),
            setting: "4 spp".into(),
            seconds: 1.5,
            rel_rmse: 0.25,
            rel_mse: 0.5,
            evaluations: None,
            level: None,
        };
        let text = super::error::csv(&[p]);
        assert_eq!(
            text.lines().nth(1),
            Some("\"brick pdf, coarse \"\"march\"\"\",4 spp,1.500000,2.500000e-1,5.000000e-1,,")
        );
    }

    #[test]
    fn a_ladders_csv_reads_back_as_its_points_and_bad_rows_say_where() {
        let points = vec![
            super::error::Point {
                estimator: "brick pdf, coarse \"march\"".into(),
                setting: "4 spp".into(),
                seconds: 1.5,
                rel_rmse: 0.25,
                rel_mse: 0.0625,
                evaluations: None,
                level: Some(-2.5e-3),
            },
            super::error::Point {
                estimator: "march spectral".into(),
                setting: "step 1 voxel".into(),
                seconds: 0.009696,
                rel_rmse: 2.057536e-3,
                rel_mse: 3.422771e-6,
                evaluations: Some(503258),
                level: None,
            },
        ];
        let back = super::error::parse_csv(&super::error::csv(&points)).unwrap();
        assert_eq!(back, points);
        let head = "estimator,setting,seconds,rel_rmse,rel_mse,medium_evaluations\n";
        for (body, says) in [
            (
                "march,step 1,fast,0.1,0.01,\n",
                "line 2: seconds \"fast\": expected a number",
            ),
            ("march,step 1,0.1\n", "line 2: 3 fields, expected 6"),
            ("", "no points"),
        ] {
            let e = super::error::parse_csv(&format!("{head}{body}")).unwrap_err();
            assert_eq!(e, says);
        }
        // With the level column, a level that is not a number is named.
        let e = super::error::parse_csv(
            "estimator,setting,seconds,rel_rmse,rel_mse,medium_evaluations,level\nmarch,step 1,0.1,0.1,0.01,,high\n",
        )
        .unwrap_err();
        assert_eq!(e, "line 2: level \"high\": expected a number");
        assert!(super::error::parse_csv("a,b\n")
            .unwrap_err()
            .starts_with("line 1:"));
    }

    #[test]
    fn the_fire_light_summary_compares_with_the_light_off_at_the_same_samples() {
        // Off: 16 and 64 spp; the light: 16 spp, 4 s, rel. RMSE 0.5 with 1000 light samples. The light off's
        // 64-spp rung is the baseline: rel. RMSE² × s 1 × 2 = 2; the light's 0.25 × 4 = 1 (2× better); a camera
        // path costs 2 s / 1000 rays, a light sample (4 − 1) s / 1000 = 1.5 paths.
        use super::fire_light::{summary, Run};
        let run = |estimator, spp, seconds, rel_rmse, light_samples| Run {
            estimator,
            spp,
            seconds,
            rel_mse: rel_rmse * rel_rmse,
            rel_rmse,
            raw: (rel_rmse, rel_rmse * rel_rmse),
            level: 0.0,
            camera_rays: 1000,
            light_samples,
        };
        let s = summary(&[
            run("off", 16, 1.0, 2.0, 0),
            run("off", 64, 2.0, 1.0, 0),
            run("light", 16, 4.0, 0.5, 1000),
        ]);
        assert_eq!(s.len(), 2);
        assert_eq!((s[0].gain_rmse2, s[0].sample_cost), (1.0, None));
        assert!((s[1].gain_rmse2 - 2.0).abs() < 1e-12, "{:?}", s[1]);
        assert!(
            (s[1].sample_cost.unwrap() - 1.5).abs() < 1e-12,
            "{:?}",
            s[1]
        );
    }

    #[test]
    fn unused_components_cost_nothing_and_used_ones_are_counted_once() {
        let file = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenes/spectroscopy/torch.vdb");
        let c = super::components::components(&file.to_string_lossy()).unwrap();
        let get = |k: usize, name: &str| -> usize {
            c[k].1
                .iter()
                .find(|r| r.0.contains(name))
                .map(|r| r.1)
                .unwrap_or(0)
        };
        // The sum of the components is the total: nothing counted twice, nothing left out.
        for (name, rows, total) in &c {
            assert_eq!(rows.iter().map(|r| r.1).sum::<usize>(), *total, "{name}");
        }
        // Each option adds what it builds and nothing else: sodium one more grid on the dataset's bricks (each
        // of the two others' size; the brick table, a top table and 16 KB per region of 16³ bricks, is shared) and its line tables; refraction
        // its index field; the light its CDFs.
        let grids = |k| get(k, "dataset grids");
        let (one, table) = (grids(1) - grids(0), grids(0) - 2 * (grids(1) - grids(0)));
        assert!(
            one % 2048 == 0 && table % 4 == 0 && table < one,
            "{one} {table}"
        );
        assert!(get(0, "species Na") == 0 && get(1, "species Na (lines)") > 0);
        assert_eq!(get(1, "refraction"), 0);
        assert_eq!(c[2].2 - c[1].2, get(2, "refraction index field"));
        assert_eq!(c[3].2 - c[2].2, get(3, "fire light"));
        assert!(get(2, "fire light") == 0);
    }
}
