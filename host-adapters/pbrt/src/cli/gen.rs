//! `firemedium gen KIND -o OUT.vdb`: a fire dataset from the blob model (the firemedium-gen crate), written as OpenVDB.

use clap::Args;
use firemedium::Error;
use firemedium_gen::{frame_as, Kind, Sim, Style};
use std::path::PathBuf;

#[derive(Debug, Args)]
pub struct GenArgs {
    /// campfire, candle, pool or torch.
    kind: String,
    /// The OpenVDB file to write; with --frames, a name holding #### (the frame number, zero-padded).
    #[arg(short, long)]
    output: PathBuf,
    /// Voxels along the domain's longest side.
    #[arg(long, default_value_t = 96, value_parser = clap::value_parser!(u32).range(4..=1024))]
    resolution: u32,
    /// Random seed (the same seed gives the same grids).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The frame to write (24 frames per second from ignition).
    #[arg(long, default_value_t = 48, value_parser = clap::value_parser!(u32).range(0..=100_000))]
    frame: u32,
    /// A frame sequence A-B (inclusive) instead of one frame.
    #[arg(long, value_name = "A-B")]
    frames: Option<String>,
    /// A species grid following the flame, SYMBOL:PEAK (number density in m⁻³), e.g. Na:1e17; repeatable.
    #[arg(long, value_name = "SYM:N")]
    species: Vec<String>,
    /// Also write the gas's velocity (m/s) as the vector grid `vel`, as Houdini does (for motion blur:
    /// `"string velocitygrid" "vel"`).
    #[arg(long)]
    velocity: bool,
    /// Also write the reaction's heat release rate (W/m³) as the grid `reaction`: the blue core's source
    /// (`"string reactiongrid" "reaction"`).
    #[arg(long)]
    reaction: bool,
    /// Warped blobs (Stam & Fiume §4): evaluate each blob's kernel at points traced back through the turbulent
    /// wind for SECONDS, so blobs stretch and curl with the wind instead of staying round (0 < SECONDS ≤ 10;
    /// ~0.1–0.5 s at the fires' scales).
    #[arg(long, value_name = "SECONDS", value_parser = parse_warp)]
    warp: Option<f64>,
    /// With --warp: the warped kernel's σ is σ − η·SECONDS (η in m/s, ≥ 0; at least half of σ), the paper's
    /// allowance for the spread the advection itself causes.
    #[arg(long, value_name = "ETA", default_value_t = 0.0, requires = "warp", value_parser = parse_spread)]
    warp_spread: f64,
    /// Embers thrown from the burning fuel, RATE per second on average (0 < RATE ≤ 100000): carried by drag
    /// and gravity, cooling by radiation; written beside the grids as a binary PLY (OUT with `.vdb` replaced by
    /// `.embers.ply`) for the fire's `"string embers"`.
    #[arg(long, value_name = "RATE", value_parser = parse_rate)]
    embers: Option<f64>,
    /// Write the grids as a tool does, to be read with `"string source"` alone: kelvin (density, temperature in
    /// K), houdini (density, temperature in units of 5000 K, flame), blender (density, flame as Cycles maps it to
    /// kelvin), embergen (smoke, temperature in K, flames).
    #[arg(long, default_value = "kelvin", value_parser = clap::builder::PossibleValuesParser::new(Style::NAMES))]
    style: String,
}

const SPECIES: [&str; 7] = ["Na", "Li", "K", "Ca", "Sr", "Ba", "Cu"];

/// The most atoms of a species a flame's gas holds per m³: all of it (p/kT, 1 atm at 300 K). The grids are f32,
/// so a number past this (1e300) would not even be stored: it became infinite, then NaN, and was written.
const MAX_SPECIES_DENSITY: f64 = 2.5e25;

fn parse_species(s: &str) -> Result<(String, f64), Error> {
    let bad = || {
        Error::value(format!("--species '{s}': expected SYMBOL:PEAK with SYMBOL one of {} and PEAK a number density in m⁻³, 0 < PEAK ≤ {MAX_SPECIES_DENSITY:e} (the gas itself at 1 atm), e.g. Na:1e17", SPECIES.join(", ")))
    };
    let (sym, n) = s.split_once(':').ok_or_else(bad)?;
    let n: f64 = n.parse().map_err(|_| bad())?;
    if !(SPECIES.contains(&sym) && n > 0.0 && n <= MAX_SPECIES_DENSITY) {
        return Err(bad());
    }
    Ok((sym.to_string(), n))
}

fn parse_warp(s: &str) -> Result<f64, Error> {
    match s.parse::<f64>() {
        Ok(t) if t > 0.0 && t <= 10.0 => Ok(t),
        _ => Err(Error::value(format!(
            "--warp '{s}': expected a back-trace time in seconds, 0 < t ≤ 10, e.g. 0.25"
        ))),
    }
}

fn parse_spread(s: &str) -> Result<f64, Error> {
    match s.parse::<f64>() {
        Ok(e) if (0.0..=1e3).contains(&e) => Ok(e),
        _ => Err(Error::value(format!(
            "--warp-spread '{s}': expected η in m/s, 0 ≤ η ≤ 1000, e.g. 0.05"
        ))),
    }
}

fn parse_rate(s: &str) -> Result<f64, Error> {
    match s.parse::<f64>() {
        Ok(r) if r > 0.0 && r <= 1e5 => Ok(r),
        _ => Err(Error::value(format!(
            "--embers '{s}': expected embers per second, 0 < RATE ≤ 100000, e.g. 40"
        ))),
    }
}

/// Where the embers of the grids at `path` go: `.vdb` replaced by `.embers.ply` (appended if absent).
pub fn embers_path(path: &std::path::Path) -> PathBuf {
    let s = path.to_string_lossy();
    PathBuf::from(match s.strip_suffix(".vdb") {
        Some(stem) => format!("{stem}.embers.ply"),
        None => format!("{s}.embers.ply"),
    })
}

fn parse_frames(s: &str) -> Result<(u32, u32), Error> {
    let bad = || {
        Error::value(format!(
            "--frames '{s}': expected A-B with 0 ≤ A ≤ B ≤ 100000, e.g. 24-48"
        ))
    };
    let (a, b) = s.split_once('-').ok_or_else(bad)?;
    let (a, b): (u32, u32) = (a.parse().map_err(|_| bad())?, b.parse().map_err(|_| bad())?);
    if a > b || b > 100_000 {
        return Err(bad());
    }
    Ok((a, b))
}

pub fn run(a: &GenArgs) -> firemedium::Result<String> {
    let kind = Kind::from_name(&a.kind).ok_or_else(|| {
        Error::value(format!(
            "'{}': unknown fire; expected one of campfire, candle, pool, torch",
            a.kind
        ))
    })?;
    let species: Vec<(String, f64)> = a
        .species
        .iter()
        .map(|s| parse_species(s))
        .collect::<Result<_, _>>()
        .map_err(Error::value)?;
    let (first, last) = match &a.frames {
        Some(s) => {
            let r = parse_frames(s).map_err(Error::value)?;
            if !a.output.to_string_lossy().contains("####") {
                return Err(Error::value(format!(
                    "--frames needs an output name holding #### (the frame number): {}",
                    a.output.display()
                )));
            }
            r
        }
        None => (a.frame, a.frame),
    };
    let style = Style::from_name(&a.style).unwrap_or(Style::Kelvin);
    // Every frame's outputs (and its embers') checked before the simulation runs.
    for frame in first..=last {
        let path = PathBuf::from(
            a.output
                .to_string_lossy()
                .replace("####", &format!("{frame:04}")),
        );
        firemedium::imageio::check_writable(&path)?;
        if a.embers.is_some() {
            firemedium::imageio::check_writable(&embers_path(&path))?;
        }
    }
    let start = std::time::Instant::now();
    let mut sim = Sim::new(kind, a.seed);
    sim.warp = a.warp.map(|t| (t, a.warp_spread));
    sim.ember_rate = a.embers;
    let mut out = String::new();
    for frame in first..=last {
        sim.run_to(frame as f64 / 24.0);
        let path = PathBuf::from(
            a.output
                .to_string_lossy()
                .replace("####", &format!("{frame:04}")),
        );
        let f = frame_as(
            &sim,
            a.resolution as usize,
            &species,
            (a.velocity, a.reaction),
            style,
        )
        .map_err(|e| Error::file(path.display(), e.to_string()))?;
        firemedium::imageio::write_atomic(&path, |tmp| {
            std::fs::write(tmp, &f.bytes)
                .map_err(|e| Error::file(path.display(), format!("cannot write: {e}")))
        })?;
        let (active, tmax, fmax) = (f.active, f.peak_temperature, f.peak_soot);
        let embers = match a.embers {
            Some(_) => {
                let ep = embers_path(&path);
                let bytes = firemedium_gen::embers_ply(&sim.embers);
                firemedium::imageio::write_atomic(&ep, |tmp| {
                    std::fs::write(tmp, &bytes)
                        .map_err(|e| Error::file(ep.display(), format!("cannot write: {e}")))
                })?;
                format!("; {} embers in {}", sim.embers.len(), ep.display())
            }
            None => String::new(),
        };
        let (hot, cells, t_fuel, left) = sim.fuel_summary();
        out += &format!(
            "wrote {} ({} frame {frame}, t = {:.3} s): {} blobs, {active} active voxels, peak {tmax:.0} K, peak soot fraction {fmax:.3e}, {:.1} MB; fuel: {hot}/{cells} cells burning at {t_fuel:.0} K mean, {:.1} % left{embers}\n",
            path.display(),
            kind.name(),
            sim.time,
            sim.blobs.len(),
            f.bytes.len() as f64 / 1e6,
            100.0 * left
        );
    }
    out += &format!("{:.2} s\n", start.elapsed().as_secs_f64());
    Ok(out)
}
