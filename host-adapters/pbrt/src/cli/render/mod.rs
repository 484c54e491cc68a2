//! `firemedium render SCENE.pbrt [-o OUT.exr] [--spp N] [--threads N] [--seed S] [--fire-light W] [--stats]`.

use crate::args::{parse_frames, parse_resolution, Frames};
use clap::Args;
use firemedium::render::{self, scene};
use firemedium::tonemap;
use firemedium::Error;
use firemedium::{imageio, render::Image};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

mod stats;
use stats::stats;

#[derive(Debug, Args)]
// (Negative numbers are values: `--temperature -5` is refused by its range, not taken for a flag.)
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    /// The pbrt-v4 scene file.
    scene: PathBuf,
    /// Output EXR (default: the Film's filename, else SCENE.exr); a PNG preview is written beside it.
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Film resolution WxH instead of the scene's (say, 160x120 for a quick look).
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<(usize, usize)>,
    /// Render only this part of the film, x0 x1 y0 y1 in [0, 1] from the top left (pbrt-v4's --cropwindow);
    /// the EXR's data window lies inside the full display window.
    #[arg(long, num_args = 4, value_names = ["X0", "X1", "Y0", "Y1"], allow_negative_numbers = true)]
    cropwindow: Option<Vec<f64>>,
    /// Render only the pixels [x0, x1) × [y0, y1) (pbrt-v4's --pixelbounds).
    #[arg(long, num_args = 4, value_names = ["X0", "X1", "Y0", "Y1"], allow_negative_numbers = true)]
    pixelbounds: Option<Vec<f64>>,
    /// Samples per pixel (default: the Sampler's pixelsamples); with --noise-threshold or --time-limit, the most
    /// any pixel takes.
    #[arg(long)]
    spp: Option<usize>,
    /// Adaptive sampling to a relative error, e.g. 0.02: blocks of 8×8 pixels take samples where they lower the
    /// image's error most for their time, none left above twice this, until the image's estimated relative error
    /// (per pixel, as relMSE weighs it) is below it; the render ends there, or at --spp.
    #[arg(long, value_name = "T", value_parser = parse_noise_threshold)]
    noise_threshold: Option<f64>,
    /// Stop after the pass that ends past this many seconds of rendering (the image whole, each pixel with the
    /// samples it took; passes shorten as the limit nears).
    #[arg(long, value_name = "SECONDS", value_parser = parse_time_limit)]
    time_limit: Option<f64>,
    /// Worker threads, 1 to 1024 (default: all cores); no more are started than there are tiles.
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1024))]
    threads: Option<u16>,
    /// Seed of the pixel samples (same seed, same image, any thread count; default: the scene's
    /// `Option "integer seed"`, else 0).
    #[arg(long)]
    seed: Option<u64>,
    /// The fire plugin library (default: FIREMEDIUM_PLUGIN, FIREMEDIUM_PLUGIN_PATH, or beside the executable).
    #[arg(long)]
    plugin: Option<PathBuf>,
    /// How emitting media light the scene: a fire light sampling voxels by emitted `power`, `luminance`, or
    /// `escaping` (power times the share that leaves the fire); `off` leaves the fire's emission to paths that
    /// pass through it; `auto` (default): `power`, except for a fire that scatters much (albedo above 0.25),
    /// whose light costs more than it saves (measured; `--stats` says so).
    #[arg(long = "fire-light", value_name = "auto|power|luminance|escaping|off", default_value = "auto",
          value_parser = ["auto", "power", "luminance", "escaping", "off"])]
    fire_light: String,
    /// A parameter of the fire light, NAME=VALUE (repeatable; docs/reference/params.md, `light`): e.g. `cell=8` (the
    /// pdf's cells, voxels per side), `linestep=2` (the march step along a light sample's direction, voxels),
    /// `linecorrection=0.1`.
    #[arg(long = "fire-light-param", value_name = "NAME=VALUE", value_parser = parse_light_param)]
    fire_light_param: Vec<(String, String)>,
    /// Scattering events inside a fire sample that fire's light as well (by default only surfaces and scattering
    /// events elsewhere do: inside a scattering fire the phase function's own directions find its emission, and
    /// a light sample's line through the fire costs more than it saves there).
    #[arg(long = "fire-light-inside")]
    fire_light_inside: bool,
    /// Where the surfaces' paths go toward a fire that scatters and emits: `auto` (default: half of the directions
    /// leaving a diffuse or rough surface aim at the fire's box), `off` (the BSDF alone, pbrt-v4's way), or the
    /// share aimed at it (0 < P < 1). The same image up to noise either way.
    #[arg(long = "fire-guide", value_name = "auto|off|P", default_value = "auto",
          value_parser = parse_guide)]
    fire_guide: GuideArg,
    /// How the camera's rays (and their mirror images) gather a scattering fire's emission: `march` (the whole
    /// segment, deterministic, as for a fire that does not scatter; delta tracking then only picks where the path
    /// scatters), `track` (at delta tracking's tentative collisions, pbrt-v4's estimator: no march lattice), or
    /// `auto` (default): the march for a `fire`, pbrt-v4's tracking for pbrt-v4's grid media.
    #[arg(long = "camera-emission", value_name = "auto|march|track", default_value = "auto",
          value_parser = ["auto", "march", "track"])]
    camera_emission: String,
    /// Who tracks the fire's media: `plugin` (its whole-ray queries: the fast path) or `host` (the renderer,
    /// through the plugin's medium level — majorant grid and coefficients at points —, as pbrt-v4 or Mitsuba 3
    /// would; refused, naming the layer, for a fire with refraction, embers, lines, art direction, diffusion or
    /// motion). Both render the same image up to noise.
    #[arg(long, value_name = "WHO", default_value = "plugin", value_parser = ["plugin", "host"])]
    tracking: String,
    /// The PNG preview's display transform, as `firemedium tonemap --operator` (and its default): naka-rushton
    /// (the paper's cone responses), agx (Sobotka's AgX: the fire's core in a soft shoulder), aces, exposure or
    /// reinhard.
    #[arg(long, value_enum, default_value = "naka-rushton")]
    operator: PreviewOperator,
    /// The PNG preview's adaptation, as `firemedium tonemap --adapt`: image (default), night, indoor, day or a
    /// luminance in cd/m².
    #[arg(long, default_value = "image", value_parser = tonemap::parse_adapt, allow_negative_numbers = true)]
    adapt: tonemap::Adapt,
    /// The PNG preview's white, as `firemedium tonemap --white` (and its default): d65 (the display's white, as
    /// an observer whose surroundings are daylit or lamplit sees a fire: its colour kept), fire (the blackbody at
    /// the hottest temperature of the fires coloured by the physics: an eye adapted to the fire alone, which sees
    /// it nearly white), a temperature (1800K) or a chromaticity (x,y).
    #[arg(long, default_value = "d65", value_parser = tonemap::parse_white)]
    white: tonemap::WhiteArg,
    /// The memory budget in GB (default: half the machine's memory): the film, images read and each of the
    /// plugin's grids are checked against it before they are allocated.
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
    /// The EXR's colour space: srgb (linear Rec.709, D65: pbrt-v4's, the default — a flame's colour lies outside
    /// it, held as negative components, which the render says) or acescg (ACES AP1, the VFX convention: a
    /// flame's colour inside it, positive). Written as the EXR's chromaticities either way; AOV colours alike.
    #[arg(long, value_name = "SPACE", default_value = "srgb", value_parser = ["srgb", "acescg"])]
    colorspace: String,
    /// Print time, rays/s, and what the plugin built.
    #[arg(long)]
    stats: bool,
    /// Print where the paths' time and light go, by vertex kind: traversals, segments in media, scattering and
    /// surface vertices, light samples (a fire's and the others'), with each kind of light's share of the image's
    /// mean and of the pixels' variance. Reads the clock at every step: a profiled render runs a little slower
    /// (the same image).
    #[arg(long)]
    profile: bool,
    /// No warnings or progress.
    #[arg(long, short)]
    quiet: bool,
    /// Frames to render, A-B or A-B:STEP (inclusive): `####` or `%04d` in dataset names and in the output name
    /// take each frame's number; each frame has its own seed.
    #[arg(long, value_name = "A-B[:STEP]", value_parser = parse_frames, conflicts_with = "frame", allow_hyphen_values = true)]
    frames: Option<Frames>,
    /// One frame (as --frames N-N).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    frame: Option<i64>,
    /// With --frames or --frame: leave out frames whose output EXR exists.
    #[arg(long)]
    skip_existing: bool,
    /// Append one JSON object per event (start, progress, done, skipped, error) to FILE, a line each.
    #[arg(long, value_name = "FILE")]
    log_json: Option<PathBuf>,
    /// Output variables written as layers of the EXR beside R, G, B: a comma-separated list of fire (the media's
    /// emission seen from the camera), emission (lights seen from the camera), direct, indirect (these four sum
    /// to the beauty), alpha (the A channel), depth, albedo, normal, samples — or all.
    #[arg(long, value_name = "LIST", value_parser = parse_aovs)]
    aov: Option<Aovs>,
}

/// The preview's display transform (`--operator`).
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
enum PreviewOperator {
    Agx,
    Aces,
    NakaRushton,
    Exposure,
    Reinhard,
}

impl PreviewOperator {
    fn operator(self) -> tonemap::Operator {
        match self {
            PreviewOperator::Agx => tonemap::Operator::Agx,
            PreviewOperator::Aces => tonemap::Operator::Aces,
            PreviewOperator::NakaRushton => tonemap::Operator::NakaRushton,
            PreviewOperator::Exposure => tonemap::Operator::Exposure,
            PreviewOperator::Reinhard => tonemap::Operator::Reinhard,
        }
    }
}

/// `--aov`'s list (a type of its own: clap would take a `Vec` for repeated flags).
#[derive(Debug, Clone)]
struct Aovs(Vec<firemedium::render::aov::Aov>);

fn parse_aovs(s: &str) -> firemedium::Result<Aovs> {
    firemedium::render::aov::Aov::parse_list(s).map(Aovs)
}

/// `--log-json`: events as JSON lines appended to a file (a farm's scheduler reads them while the render runs).
/// A write that fails (a full disk) is said once on stderr, with the file and the error: the render goes on.
struct JsonLog(
    Option<std::sync::Mutex<std::fs::File>>,
    std::path::PathBuf,
    std::sync::atomic::AtomicBool,
);

impl JsonLog {
    fn open(path: Option<&Path>) -> firemedium::Result<JsonLog> {
        let Some(path) = path else {
            return Ok(JsonLog(None, Default::default(), Default::default()));
        };
        let f = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(|e| Error::value(format!("--log-json {}: {e}", path.display())))?;
        Ok(JsonLog(
            Some(std::sync::Mutex::new(f)),
            path.to_path_buf(),
            Default::default(),
        ))
    }
    fn on(&self) -> bool {
        self.0.is_some()
    }
    fn event(&self, v: serde_json::Value) {
        if let Some(Ok(mut f)) = self.0.as_ref().map(|m| m.lock()) {
            // (One write per line: appends of a line from several processes do not interleave.)
            let r = std::io::Write::write_all(&mut *f, format!("{v}\n").as_bytes());
            if let Err(e) = r {
                if !self.2.swap(true, std::sync::atomic::Ordering::Relaxed) {
                    eprintln!(
                        "firemedium: --log-json {}: cannot write: {e} (this and later events are lost; the render goes on)",
                        self.1.display()
                    );
                }
            }
        }
    }
}

/// The EXR record's attribute saying whether every tile was rendered ("true") or the render was interrupted.
const COMPLETE: &str = "complete";

/// `path` with `.partial` before its extension: where an interrupted render writes what it finished. A stem too
/// long for the name to fit a file system's 255 bytes is shortened (at a character) so that it always does.
fn partial(path: &Path) -> PathBuf {
    let mut stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    let room = firemedium::imageio::NAME_MAX.saturating_sub(".partial".len() + ext.len());
    while stem.len() > room {
        stem.pop();
    }
    path.with_file_name(format!("{stem}.partial{ext}"))
}

/// An error unless the image can be written at `path` (imageio::check_writable: its name fits, its folder takes a
/// file), said before the scene is loaded or rendered.
fn writable(path: &Path) -> firemedium::Result<()> {
    firemedium::imageio::check_writable(path)
}

/// Whether the EXR at `path` is a finished frame: it reads whole (every pixel), and its record does not say it
/// is incomplete (renders before the record said so are taken as complete when they read whole).
fn finished(path: &Path) -> firemedium::Result<()> {
    imageio::read(path, false)?;
    let (_, meta) = imageio::read_meta(path)?;
    match meta.iter().find(|(k, _)| k == COMPLETE) {
        Some((_, v)) if v != "true" => Err(Error::file(
            path.display(),
            "its record says the render was interrupted",
        )),
        _ => Ok(()),
    }
}

/// The seed of frame `f` from the render's seed: the same seed for the same frame, another for each frame.
/// From here on Ctrl-C, SIGTERM and SIGHUP (what Slurm sends at a time limit or preemption) end the render
/// between pixels and bounces, writing its finished tiles; once per process (every frame shares the handlers).
fn handle_signals() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        #[cfg(unix)]
        let signals = [
            signal_hook::consts::SIGINT,
            signal_hook::consts::SIGTERM,
            signal_hook::consts::SIGHUP,
        ];
        #[cfg(not(unix))]
        let signals = [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM];
        for s in signals {
            // A signal we cannot handle keeps its default action (the process ends, writing nothing): say so.
            if let Err(e) =
                signal_hook::flag::register_usize(s, std::sync::Arc::clone(&render::INTERRUPTED), s as usize)
            {
                eprintln!("warning: signal {s} not handled ({e}): it will end the render without its tiles");
            }
        }
    });
}

fn frame_seed(seed: u64, f: i64) -> u64 {
    seed ^ (f as u64)
        .wrapping_add(1)
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
}

/// Four values clap counted (`num_args = 4`).
fn four(v: &Option<Vec<f64>>) -> Option<[f64; 4]> {
    v.as_deref().and_then(|v| v.try_into().ok())
}

pub fn run(a: &RenderArgs) -> firemedium::Result<String> {
    if a.spp == Some(0) {
        return Err(Error::value("--spp must be at least 1"));
    }
    let log = JsonLog::open(a.log_json.as_deref())?;
    let logged = |r: firemedium::Result<Frame>, frame: Option<i64>| {
        if let Err(e) = &r {
            log.event(serde_json::json!({"event": "error", "frame": frame, "code": e.exit_status(), "message": e.to_string()}));
        }
        r
    };
    let frames: Option<Vec<i64>> = a.frames.clone().map(|f| f.0).or(a.frame.map(|f| vec![f]));
    let Some(frames) = frames else {
        if a.skip_existing {
            return Err(Error::value("--skip-existing needs --frames or --frame"))
                .inspect_err(|e| log.event(serde_json::json!({"event": "error", "frame": null, "code": e.exit_status(), "message": e.to_string()})));
        }
        return logged(render_frame(a, None, &log), None).map(Frame::into_text);
    };
    let mut out = String::new();
    for &f in &frames {
        let start = std::time::Instant::now();
        match logged(render_frame(a, Some(f), &log), Some(f)) {
            Ok(Frame::Rendered(text)) => {
                out += &text;
                // One line per finished frame, as it finishes (a farm's log follows the sequence).
                if !a.quiet {
                    eprintln!(
                        "firemedium: frame {f} done in {:.2} s",
                        start.elapsed().as_secs_f64()
                    );
                }
            }
            Ok(Frame::Skipped(line)) => out += &line,
            Err(e) => return Err(e),
        }
    }
    Ok(out)
}

/// What became of one frame.
enum Frame {
    /// Rendered and written: the report.
    Rendered(String),
    /// Left out by `--skip-existing`: the line saying so.
    Skipped(String),
}

impl Frame {
    fn into_text(self) -> String {
        match self {
            Frame::Rendered(t) | Frame::Skipped(t) => t,
        }
    }
}

/// What the command line changes of the scene, for `frame`.
fn overrides(a: &RenderArgs, frame: Option<i64>) -> scene::Overrides {
    scene::Overrides {
        frame,
        spp: a.spp,
        plugin: a.plugin.clone(),
        no_fire_light: a.fire_light == "off",
        fire_light_weighting: (!matches!(a.fire_light.as_str(), "off" | "auto"))
            .then(|| a.fire_light.clone()),
        fire_light_forced: a.fire_light != "auto",
        fire_light_params: a.fire_light_param.clone(),
        fire_light_inside: a.fire_light_inside,
        fire_guide: match a.fire_guide {
            GuideArg::Auto => None,
            GuideArg::Share(p) => Some(p),
        },
        host_tracking: a.tracking == "host",
        camera_march: match a.camera_emission.as_str() {
            "march" => Some(true),
            "track" => Some(false),
            _ => None,
        },
        res: a.resolution,
        crop: four(&a.cropwindow),
        pixel_bounds: four(&a.pixelbounds),
        threads: a.threads.map(usize::from),
        max_memory: a.max_memory.map(|gb| (gb * 1e9) as u64),
        aovs: a.aov.clone().map(|l| l.0).unwrap_or_default(),
    }
}

/// The image's record: the scene, seed, samples and how they were spent, the camera (its matrix and
/// projection), frame, shutter, AOVs, the fire light, the plugin's ABI, and the render's seconds.
fn metadata(
    a: &RenderArgs,
    sc: &scene::Scene,
    (seed, frame): (u64, Option<i64>),
    seconds: f64,
) -> Vec<(String, String)> {
    vec![
        (
            "scene".to_string(),
            std::fs::canonicalize(&a.scene)
                .unwrap_or_else(|_| a.scene.clone())
                .display()
                .to_string(),
        ),
        ("seed".to_string(), seed.to_string()),
        ("spp".to_string(), sc.spp.to_string()),
        (
            // How the samples were spent (adaptive sampling, a time limit): what `merge` checks tiles against.
            "sampling".to_string(),
            format!(
                "noise_threshold {} time_limit {}",
                a.noise_threshold
                    .map_or("none".to_string(), |t| t.to_string()),
                a.time_limit.map_or("none".to_string(), |t| t.to_string())
            ),
        ),
        (
            // pbrt's camera-to-world matrix, row by row (3 × 4), for a compositor matching the render.
            "camera_to_world".to_string(),
            {
                let m = sc.camera.to_world;
                let (c, t) = (m.matrix3, m.translation);
                (0..3)
                    .map(|r| format!("{} {} {} {}", c.x_axis[r], c.y_axis[r], c.z_axis[r], t[r]))
                    .collect::<Vec<_>>()
                    .join("  ")
            },
        ),
        (
            // The projection: with camera_to_world, what a compositor needs to place 3D elements in the render.
            "camera".to_string(),
            {
                let c = &sc.camera;
                let [x0, x1, y0, y1] = c.screen;
                if c.orthographic {
                    format!("orthographic screenwindow {x0} {x1} {y0} {y1}")
                } else {
                    format!(
                    "perspective fov {} screenwindow {x0} {x1} {y0} {y1} lensradius {} focaldistance {}",
                    2.0 * c.tan_half.atan().to_degrees(),
                    c.lens_radius,
                    c.focal_distance
                )
                }
            },
        ),
        (
            "frame".to_string(),
            frame.map_or_else(|| "none".to_string(), |f| f.to_string()),
        ),
        (
            "shutter".to_string(),
            match sc.shutter {
                Some([o, c]) => format!("{o} {c}"),
                None => "closed".to_string(),
            },
        ),
        (
            "aovs".to_string(),
            sc.aovs
                .iter()
                .map(|a| a.name())
                .collect::<Vec<_>>()
                .join(","),
        ),
        (
            // How the fire lit the scene: `off`, or the weighting and the light parameters given.
            "fire_light".to_string(),
            std::iter::once(a.fire_light.clone())
                .chain(a.fire_light_param.iter().map(|(n, v)| format!("{n}={v}")))
                .collect::<Vec<_>>()
                .join(" "),
        ),
        (
            // Where the surfaces' paths aimed: `off`, or the share aimed at the box of the scattering fires.
            "fire_guide".to_string(),
            sc.guide
                .as_ref()
                .map_or_else(|| "off".to_string(), |g| format!("{}", g.prob())),
        ),
        (
            // The C ABI of the plugin that rendered the media (none without plugin media).
            "plugin_abi".to_string(),
            sc.media
                .iter()
                .find_map(|m| match m {
                    scene::Medium::Plugin(scene::Plugin { vol, .. }) => {
                        let (major, minor) = vol.abi_version();
                        Some(format!("{major}.{minor}"))
                    }
                    _ => None,
                })
                .unwrap_or_else(|| "none".to_string()),
        ),
        (
            imageio::RENDER_SECONDS.to_string(),
            format!("{:.6}", seconds),
        ),
    ]
}

/// Tracking that stopped at the plugin's per-ray collision cap biases towards dark: says so, per medium (unless
/// `quiet`).
fn capped_rays(sc: &scene::Scene, quiet: bool) -> firemedium::Result<()> {
    for m in &sc.media {
        if let scene::Medium::Plugin(scene::Plugin { vol, name, .. }) = m {
            match vol.capped_rays() {
                Ok(0) => {}
                Ok(n) if !quiet => eprintln!("firemedium: warning: medium \"{name}\": {n} rays stopped at the per-ray collision cap (2^20 tentative collisions) and were cut short as if absorbed; the medium's majorant is far above its data (an outlier voxel?) or it is optically very thick: the image is darker there than it should be"),
                Ok(_) => {}
                Err(e) => return Err(Error::input(format!("medium \"{name}\": {e}"))),
            }
        }
    }
    Ok(())
}

/// `--skip-existing`: a frame is done when its EXR reads whole and its record says it is complete; a truncated,
/// unreadable or interrupted one is rendered again, saying why.
fn skip_existing(a: &RenderArgs, frame: Option<i64>, log: &JsonLog, exr: &Path) -> Option<Frame> {
    if !(a.skip_existing && exr.is_file()) {
        return None;
    }
    let why = match finished(exr) {
        Ok(()) => {
            log.event(serde_json::json!({"event": "skipped", "frame": frame, "exr": exr.display().to_string()}));
            return Some(Frame::Skipped(format!(
                "frame {}: {} exists, left out\n",
                frame.unwrap_or(0),
                exr.display()
            )));
        }
        Err(why) => why,
    };
    if !a.quiet {
        eprintln!(
            "firemedium: frame {}: {} is not a finished frame ({}): rendering it again",
            frame.unwrap_or(0),
            exr.display(),
            firemedium::term::printable(&why.to_string(), firemedium::term::MAX_MESSAGE_CHARS)
        );
    }
    None
}

/// The preview's tone mapping: the tonemap command's defaults (Naka–Rushton adapted to the image, a D65 white, or
/// the fire's hottest blackbody with `--white fire`) unless asked.
fn preview_tone(a: &RenderArgs, fire_t: Option<f64>) -> tonemap::Options {
    tonemap::Options {
        white: match a.white {
            tonemap::WhiteArg::Fire => {
                fire_t.map_or(tonemap::White::D65, tonemap::White::Blackbody)
            }
            tonemap::WhiteArg::Given(w) => w,
        },
        adapt: a.adapt,
        operator: a.operator.operator(),
        stops: 0.0,
    }
}

/// The line a render ends with: what it wrote, the samples taken (the scene's per pixel, or their mean and why
/// sampling stopped early), the estimated noise, and the share of pixels outside sRGB (`outside` of them).
fn wrote(
    a: &RenderArgs,
    (img, outside): (&render::Image, usize),
    (sc, st): (&scene::Scene, &render::Stats),
    (exr, png): (&Path, &Path),
) -> String {
    let gamut = if outside > 0 && a.colorspace == "srgb" {
        format!(
            "; {:.1} % of its pixels hold colour outside sRGB as negative components (kept, linear; --colorspace acescg holds a flame's colour positive)",
            100.0 * outside as f64 / img.rgb.len().max(1) as f64
        )
    } else {
        String::new()
    };
    // The samples taken: the scene's per pixel, or, where sampling stopped early, their mean and why.
    let pixels = (img.w * img.h).max(1);
    let spp = if st.camera_rays == pixels * sc.spp {
        format!("{} spp", sc.spp)
    } else {
        format!(
            "{:.1} spp on average of at most {}, {}",
            st.camera_rays as f64 / pixels as f64,
            sc.spp,
            st.stop.describe()
        )
    };
    let noise = st.rel_rmse_estimate.map_or(String::new(), |e| {
        format!(", rel. RMSE ≈ {:.2} % (estimated)", 100.0 * e)
    });
    format!(
        "wrote {} and {} ({}×{}, {spp}{noise}{gamut})\n",
        exr.display(),
        png.display(),
        img.w,
        img.h,
    )
}

/// The output's names (EXR, PNG): `-o` or the film's, with the frame's number in its pattern (refused without
/// one when several frames render).
fn output_names(
    a: &RenderArgs,
    frame: Option<i64>,
    film: Option<&str>,
) -> firemedium::Result<(PathBuf, PathBuf)> {
    let (exr, _) = outputs(&a.scene, film, a.output.as_deref());
    let Some(f) = frame else {
        return Ok(outputs(&a.scene, film, Some(&exr)));
    };
    let patterned =
        firemedium_dataset::frame_path(&exr, Some(f)).map_err(|e| Error::value(e.to_string()))?;
    if patterned == exr && a.frames.as_ref().is_some_and(|v| v.0.len() > 1) {
        return Err(Error::value(format!(
                "--frames: the output name {} holds no #### or %04d for the frame number: every frame would overwrite it (-o fire.####.exr)",
                exr.display()
            ),
        ));
    }
    Ok(outputs(&a.scene, None, Some(&patterned)))
}

/// Renders one frame (`None`: the scene as written) and writes its EXR and PNG, or leaves it out
/// (`--skip-existing`).
fn render_frame(a: &RenderArgs, frame: Option<i64>, log: &JsonLog) -> firemedium::Result<Frame> {
    log.event(serde_json::json!({"event": "start", "frame": frame, "scene": a.scene.display().to_string()}));
    let frame_start = std::time::Instant::now();
    let ov = overrides(a, frame);
    let named = |film: Option<&str>| output_names(a, frame, film);
    let exists = |exr: &Path| skip_existing(a, frame, log, exr);
    // (With `-o`, a frame left out is not even loaded, and an output that cannot be written is said before the
    // scene is.)
    if let Some(o) = a.output.as_deref().filter(|o| o.is_dir()) {
        return Err(Error::file(
            o.display(),
            "is a folder: -o takes the image's file name (say, renders/fire.exr)",
        ));
    }
    if a.output.is_some() {
        let (exr, png) = named(None)?;
        if let Some(skipped) = exists(&exr) {
            return Ok(skipped);
        }
        writable(&exr)?;
        writable(&png)?;
    }
    let load_start = std::time::Instant::now();
    let sc = scene::load(&a.scene, &ov)?;
    let (exr, png) = named(sc.film_name.as_deref())?;
    if let Some(skipped) = exists(&exr) {
        return Ok(skipped);
    }
    // (Before the render: an hour of work must not end in "cannot write".)
    writable(&exr)?;
    writable(&png)?;
    let seed = a.seed.unwrap_or(sc.seed);
    let seed = frame.map_or(seed, |f| frame_seed(seed, f));
    let load_seconds = load_start.elapsed().as_secs_f64();
    if !a.quiet {
        for w in &sc.warnings {
            eprintln!(
                "{}",
                firemedium::term::printable(w, firemedium::term::MAX_MESSAGE_CHARS)
            );
        }
    }
    handle_signals();
    let [x0, x1, y0, y1] = sc.bounds;
    let tiles = (x1 - x0).div_ceil(16) * (y1 - y0).div_ceil(16);
    // (Loaded, Ctrl-C handled from here on: a farm's scheduler, or a test, may interrupt the render now.)
    log.event(serde_json::json!({"event": "rendering", "frame": frame, "tiles": tiles}));
    let bar = ProgressBar::new(1000);
    let terminal = std::io::stderr().is_terminal() && std::env::var_os("CI").is_none();
    let show = !a.quiet && terminal;
    // Off a terminal (a farm's log), progress as plain lines at every tenth of the samples.
    let lines = !a.quiet && !terminal;
    let report = lines || log.on();
    let label = frame.map_or(String::new(), |f| format!("frame {f} "));
    let tenth = std::sync::atomic::AtomicUsize::new(0);
    bar.set_draw_target(if show {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    });
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {percent:>3} % {msg} {elapsed}/{eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let pool = rayon::ThreadPoolBuilder::new()
        // (5000 threads for an 8×8 image spent 30 s starting them.)
        .num_threads(a.threads.map_or(0, usize::from).min(tiles))
        .build()
        .map_err(|e| Error::input(format!("threads: {e}")))?;
    // After each pass: its error estimate in the log (error against run time, for any scene) and on the bar.
    let on_pass = |p: &render::Pass| {
        if let Some(e) = p.rel_rmse_estimate {
            bar.set_message(format!("pass {}, rel. RMSE ≈ {:.2} %", p.index, 100.0 * e));
        }
        log.event(serde_json::json!({
            "event": "pass",
            "frame": frame,
            "pass": p.index,
            "seconds": p.seconds,
            "samples": p.samples,
            "spp": p.spp,
            "rel_rmse_estimate": p.rel_rmse_estimate,
            "active_pixels": p.active_pixels,
        }));
    };
    let opts = render::Progressive {
        noise_threshold: a.noise_threshold,
        time_limit: a.time_limit,
        on_pass: Some(&on_pass),
        profile: a.profile,
    };
    let (img, st) = pool.install(|| {
        render::render_progressive(&sc, seed, &opts, &|p: render::Progress| {
            bar.set_position((p.fraction * 1000.0) as u64);
            let t = (p.fraction * 10.0) as usize;
            if report && t < 10 && t > tenth.fetch_max(t, std::sync::atomic::Ordering::Relaxed) {
                if lines {
                    eprintln!("firemedium: {label}{} % (pass {}, {}/{} tiles)", t * 10, p.pass, p.tiles_done, p.tiles);
                }
                log.event(serde_json::json!({"event": "progress", "frame": frame, "percent": t * 10, "pass": p.pass, "tiles_done": p.tiles_done, "tiles": p.tiles}));
            }
        })
    });
    bar.finish_and_clear();
    capped_rays(&sc, a.quiet)?;
    // The preview: the tonemap command's defaults (Naka–Rushton adapted to the image, a D65 white) unless asked.
    let fire_t = sc.fire_temperature();
    let tone = preview_tone(a, fire_t);
    // What the image is a render of (for `firemedium merge` and compositors), and how long it took (the one
    // line two renders of the same scene differ in).
    let mut img = img;
    img.meta = metadata(a, &sc, (seed, frame), st.seconds);
    // An interrupted render writes its finished tiles beside the output, never over it (a complete frame from
    // an earlier run stays), and its record says it is not complete; so does a render in which plugin calls
    // failed (its paths lost light there: `--skip-existing` renders it again).
    let whole = img.complete && st.plugin_failures.0 == 0;
    let (exr, png) = if whole {
        (exr, png)
    } else {
        (partial(&exr), partial(&png))
    };
    img.meta.push((COMPLETE.to_string(), whole.to_string()));
    // Out of the EXR's gamut: the pixels with a negative component (sRGB), counted before any conversion.
    let outside = img
        .rgb
        .iter()
        .filter(|p| p.iter().any(|&c| c < 0.0))
        .count();
    if a.colorspace == "acescg" {
        to_acescg(&mut img);
        img.meta
            .push((imageio::COLORSPACE_KEY.to_string(), "acescg".to_string()));
    }
    if st.plugin_failures.0 > 0 {
        img.meta.push((
            "plugin_failures".to_string(),
            st.plugin_failures.0.to_string(),
        ));
    }
    img.write_exr(&exr, fire_t, sc.response.fp16)?;
    write_preview(&img, &png, &tone)?;
    let pixels = (img.w * img.h).max(1);
    let mut out = wrote(a, (&img, outside), (&sc, &st), (&exr, &png));
    if a.stats {
        out += &stats(&sc, &st, load_seconds, pool.current_num_threads());
    }
    if let Some(table) = &st.profile {
        out += table;
    }
    if !img.complete {
        // The shell's convention, as a farm's scheduler reads it: 128 + the signal (130 Ctrl-C, 143 SIGTERM).
        let signal = render::INTERRUPTED.load(std::sync::atomic::Ordering::Relaxed);
        return Err(Error::Interrupted {
            signal: i32::try_from(signal).unwrap_or(2),
            message: format!(
                "interrupted: wrote the image as it stood ({:.1} samples per pixel on average, each pixel its own) to {} and {}",
                st.camera_rays as f64 / pixels as f64,
                exr.display(),
                png.display()
            ),
        });
    }
    // A plugin call that failed inside the render left its path without the rest of its light: the image is
    // darker there than the scene. It is written (the work is kept), and the render fails saying so.
    if let (n @ 1.., first) = &st.plugin_failures {
        log.event(serde_json::json!({
            "event": "plugin_failures",
            "frame": frame,
            "count": n,
            "first": first,
        }));
        // (The statistics, which say the same, before the error.)
        print!("{out}");
        return Err(Error::input(format!(
                "{n} plugin calls failed during the render (first: {}); the paths that made them gave nothing from there on, so {} and {} are darker than the scene",
                first.as_deref().unwrap_or("no message"),
                exr.display(),
                png.display()
            ),
        ));
    }
    log.event(serde_json::json!({
        "event": "done",
        "frame": frame,
        "exr": exr.display().to_string(),
        "png": png.display().to_string(),
        "width": img.w,
        "height": img.h,
        "spp": sc.spp,
        "samples": st.camera_rays,
        "passes": st.passes,
        "stop": format!("{:?}", st.stop).to_lowercase(),
        "rel_rmse_estimate": st.rel_rmse_estimate,
        "seed": seed,
        "render_seconds": st.seconds,
        "seconds": frame_start.elapsed().as_secs_f64(),
    }));
    Ok(Frame::Rendered(out))
}

/// The image's colours (the beauty and every AOV triplet `NAME.R`, `.G`, `.B`) from linear Rec.709 to ACEScg.
fn to_acescg(img: &mut Image) {
    let m = imageio::SRGB_TO_ACESCG;
    let apply = |p: [f32; 3]| [0, 1, 2].map(|r| m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2]);
    for p in img.rgb.iter_mut() {
        *p = apply(*p);
    }
    if let Some((names, values)) = &mut img.extra {
        let n = names.len();
        let triplets: Vec<[usize; 3]> = names
            .iter()
            .enumerate()
            .filter_map(|(i, name)| {
                let base = name.strip_suffix(".R")?;
                let at = |c: &str| names.iter().position(|x| *x == format!("{base}.{c}"));
                Some([i, at("G")?, at("B")?])
            })
            .collect();
        for px in values.chunks_mut(n.max(1)) {
            for t in &triplets {
                let c = apply([px[t[0]], px[t[1]], px[t[2]]]);
                for k in 0..3 {
                    px[t[k]] = c[k];
                }
            }
        }
    }
}

/// Writes the PNG preview: the visual-adaptation tone mapping with `options`.
pub fn write_preview(
    img: &Image,
    path: &Path,
    options: &tonemap::Options,
) -> firemedium::Result<()> {
    let f = tonemap::mapper(&img.xyz, options);
    imageio::write_png(path, img.w, img.h, img.xyz.iter().map(|&p| f(p)), false)
}

/// The output paths: `-o` or the film's filename (relative to the scene), and the PNG beside it.
pub fn outputs(scene_path: &Path, film: Option<&str>, out: Option<&Path>) -> (PathBuf, PathBuf) {
    let exr = match (out, film) {
        (Some(o), _) => o.to_path_buf(),
        (None, Some(f)) => scene_path.parent().unwrap_or(Path::new(".")).join(f),
        (None, None) => scene_path.with_extension("exr"),
    };
    let exr = if exr.extension().is_some_and(|e| e == "exr") {
        exr
    } else {
        exr.with_extension("exr")
    };
    let png = exr.with_extension("png");
    (exr, png)
}

/// `NAME=VALUE` (the plugin's table types the value when the light is built).
pub(crate) fn parse_noise_threshold(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t > 0.0 && t < 1e3 => Ok(t),
        Ok(t) => Err(format!(
            "{t}: expected a relative error above 0 (0.01 is 1 %)"
        )),
        Err(e) => Err(format!("{s:?}: {e}")),
    }
}

pub(crate) fn parse_time_limit(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(t) if t > 0.0 && t <= 1e9 => Ok(t),
        Ok(t) => Err(format!("{t}: expected seconds above 0, at most 1e9")),
        Err(e) => Err(format!("{s:?}: {e}")),
    }
}

/// `--fire-guide`: `auto`, or the share of the surfaces' directions aimed at a scattering fire (`off`: 0).
#[derive(Debug, Clone, Copy)]
enum GuideArg {
    Auto,
    Share(f32),
}

fn parse_guide(s: &str) -> Result<GuideArg, Error> {
    match s {
        "auto" => Ok(GuideArg::Auto),
        "off" => Ok(GuideArg::Share(0.0)),
        _ => s
            .parse::<f32>()
            .ok()
            .filter(|p| (0.0..1.0).contains(p))
            .map(GuideArg::Share)
            .ok_or_else(|| {
                Error::value(format!(
                    "{s:?}: expected auto, off or a share of the directions in [0, 1), e.g. 0.5"
                ))
            }),
    }
}

fn parse_light_param(s: &str) -> Result<(String, String), Error> {
    s.split_once('=')
        .filter(|(n, v)| !n.is_empty() && !v.is_empty())
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .ok_or_else(|| Error::value(format!("{s:?}: expected NAME=VALUE, e.g. cell=8")))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_ranges_parse_with_steps_and_negative_numbers() {
        let f = |s: &str| parse_frames(s).map(|f| f.0).map_err(|e| e.to_string());
        assert_eq!(f("1-5"), Ok(vec![1, 2, 3, 4, 5]));
        assert_eq!(f("1-240:100"), Ok(vec![1, 101, 201]));
        assert_eq!(f("7-7"), Ok(vec![7]));
        assert_eq!(f("-5--3"), Ok(vec![-5, -4, -3]));
        assert_eq!(f("-2-1:2"), Ok(vec![-2, 0]));
        for bad in [
            "5-3",
            "1-5:0",
            "1-5:-1",
            "x-3",
            "3",
            "1-",
            "-",
            "1-2000000000",
        ] {
            assert!(f(bad).is_err(), "{bad}");
        }
        assert!(f("0-2000000").unwrap_err().contains("at most 1 000 000"));
        // Every frame its own seed, the same for the same frame.
        assert_ne!(frame_seed(7, 1), frame_seed(7, 2));
        assert_eq!(frame_seed(7, 2), frame_seed(7, 2));
        assert_ne!(frame_seed(7, -1), frame_seed(7, 0));
    }
}
