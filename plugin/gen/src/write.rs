//! A frame as an OpenVDB file's bytes in a tool's conventions, and the embers as a PLY.

use super::*;

/// Writes one voxelised frame; returns (bytes written, active voxels, peak temperature, peak soot fraction).
/// Whose conventions a written file follows: grid names and temperature units as each tool writes them (so a
/// scene reads it with `"string source"` alone).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    /// density, temperature in K, `vel`: firemedium's own (and the thesis's, pbrt-v4's).
    Kelvin,
    /// Houdini's Pyro: density, temperature in units of 5000 K (its Pyro shader's blackbody default), flame
    /// (0–1), `vel`.
    Houdini,
    /// Blender's Mantaflow cache: density, flame as Cycles reads it (T = 1000 K · (1.5 + 1.5 · flame) where
    /// flame > 0: the domain's default ignition 1.5 and maximum 3.0; cooler gas has no flame), `velocity`.
    Blender,
    /// EmberGen: smoke, temperature in K, flames (0–1), `velocity`.
    Embergen,
}

impl Style {
    /// The styles by name.
    pub const NAMES: [&'static str; 4] = ["kelvin", "houdini", "blender", "embergen"];

    /// The style called `name`.
    pub fn from_name(name: &str) -> Option<Style> {
        Some(match name {
            "kelvin" => Style::Kelvin,
            "houdini" => Style::Houdini,
            "blender" => Style::Blender,
            "embergen" => Style::Embergen,
            _ => return None,
        })
    }
}

/// A frame as an OpenVDB file's bytes, with what it holds.
#[derive(Debug)]
pub struct Frame {
    /// The file.
    pub bytes: Vec<u8>,
    /// Voxels holding gas.
    pub active: usize,
    /// The hottest voxel, K.
    pub peak_temperature: f32,
    /// The highest soot volume fraction.
    pub peak_soot: f32,
}

/// Frame `sim` at resolution `res` in firemedium's own conventions (see [`frame_as`]).
pub fn frame(
    sim: &Sim,
    res: usize,
    species: &[(String, f64)],
    velocity: bool,
) -> Result<Frame, String> {
    frame_as(sim, res, species, (velocity, false), Style::Kelvin)
}

/// Frame `sim` at resolution `res` as OpenVDB in `style`'s conventions, with `species` grids following the
/// flame, and the velocity and the reaction's heat release rate (`reaction`, W/m³) when asked. A frame with no
/// gas (the fire not lit yet, or burnt out) is an error: a file of nothing is never what a user wants.
pub fn frame_as(
    sim: &Sim,
    res: usize,
    species: &[(String, f64)],
    (velocity, reaction): (bool, bool),
    style: Style,
) -> Result<Frame, String> {
    let f = voxelise(sim, res, velocity);
    let peak_flame = f
        .flame
        .iter()
        .copied()
        .fold(0f32, f32::max)
        .max(f32::MIN_POSITIVE);
    let species_data: Vec<(String, Vec<f32>)> = species
        .iter()
        .map(|(sym, n)| {
            let scale = (*n / peak_flame as f64) as f32;
            (sym.clone(), f.flame.iter().map(|v| v * scale).collect())
        })
        .collect();
    // The tool's temperature and flame (the flame normalised to its peak).
    let flame: Vec<f32> = f.flame.iter().map(|v| v / peak_flame).collect();
    let (ign, max) = (1.5f32, 3.0f32);
    let tool_t: Vec<f32> = match style {
        Style::Kelvin | Style::Embergen => Vec::new(),
        Style::Houdini => f
            .temperature
            .iter()
            .map(|t| t / firemedium_dataset::HOUDINI_KELVIN as f32)
            .collect(),
        Style::Blender => f
            .temperature
            .iter()
            .map(|t| ((t / 1000.0 - ign) / (max - ign)).max(0.0))
            .collect(),
    };
    let mut grids: Vec<(&str, [usize; 3], &[f32])> = match style {
        Style::Kelvin => vec![
            ("density", f.dims, &f.density),
            ("temperature", f.dims, &f.temperature),
        ],
        Style::Houdini => vec![
            ("density", f.dims, &f.density),
            ("temperature", f.dims, &tool_t),
            ("flame", f.dims, &flame),
        ],
        Style::Blender => vec![("density", f.dims, &f.density), ("flame", f.dims, &tool_t)],
        Style::Embergen => vec![
            ("smoke", f.dims, &f.density),
            ("temperature", f.dims, &f.temperature),
            ("flames", f.dims, &flame),
        ],
    };
    for (sym, data) in &species_data {
        grids.push((sym.as_str(), f.dims, data));
    }
    if reaction {
        grids.push(("reaction", f.dims, &f.reaction));
    }
    let active = f.density.iter().filter(|v| **v != 0.0).count();
    if active == 0 {
        return Err(format!(
            "the fire holds no gas at t = {:.3} s (not lit yet or burnt out); choose a later or earlier frame",
            sim.time
        ));
    }
    let [vx, vy, vz] = &f.velocity;
    let vectors: Vec<firemedium_dataset::vdb::VdbVector> = if velocity {
        let name = match style {
            Style::Kelvin | Style::Houdini => "vel",
            Style::Blender | Style::Embergen => "velocity",
        };
        vec![(name, f.dims, [vx, vy, vz])]
    } else {
        Vec::new()
    };
    let bytes = firemedium_dataset::vdb::write_with_vectors(
        &grids,
        &vectors,
        f.p0,
        glam::DVec3::splat(f.voxel),
    );
    let peak_temperature = f.temperature.iter().copied().fold(0f32, f32::max);
    let peak_soot = f.density.iter().copied().fold(0f32, f32::max);
    Ok(Frame {
        bytes,
        active,
        peak_temperature,
        peak_soot,
    })
}

/// The embers as a binary PLY (the plugin's `embers` file): x, y, z, radius (m), temperature (K, at birth),
/// vx, vy, vz (m/s) and age (s), one float each.
pub fn embers_ply(embers: &[Ember]) -> Vec<u8> {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\ncomment firemedium gen: embers (temperature at birth, cooled by the renderer over age)\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nproperty float radius\nproperty float temperature\nproperty float vx\nproperty float vy\nproperty float vz\nproperty float age\nend_header\n",
        embers.len()
    )
    .into_bytes();
    for e in embers {
        for v in [e.x.x, e.x.y, e.x.z, e.r, e.t0, e.v.x, e.v.y, e.v.z, e.age] {
            b.extend((v as f32).to_le_bytes());
        }
    }
    b
}
