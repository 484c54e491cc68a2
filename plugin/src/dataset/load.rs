//! Loading what the dataset's parameters asked for ([`super::params::read`]'s `Request`): the files read (or the
//! inline arrays taken) into the dataset, `source "auto"`'s grids chosen by their names, the temperature's unit
//! found from its peak, the velocity and the embers read.

use super::params::{EmberFile, Grids, Loaded, Motion, Request, Tool, SCATTER_COLOR, VELOCITY};
use super::{frame_path, ChannelSource, Dataset, Format, LoadOptions, Mapping};
use crate::Error;
use firemedium_dataset::convention;

impl Request {
    /// Reads the files the parameters name (or takes the inline arrays) into the dataset.
    pub(crate) fn load(self) -> Result<Loaded, Error> {
        let Request {
            opts,
            interp,
            grids,
            per_frame,
            shutter,
            embers,
            tool,
            find_unit,
            named,
            flame,
        } = self;
        let mut chosen = Vec::new();
        let mut resolved = tool;
        let (ds, lescale, emission_grid, motion, scatter_color, reaction) = match grids {
            Grids::Inline {
                dims,
                bounds: [b0, b1],
                arrays,
                lescale,
            } => {
                let arrays: Vec<(&str, &[f32])> =
                    arrays.iter().map(|(n, v)| (*n, v.as_slice())).collect();
                let ds = Dataset::from_inline(dims, b0, b1, &arrays, &opts)?;
                let li = lescale.then_some(arrays.len() - 1);
                (ds, li, false, None, None, None)
            }
            Grids::Files {
                mut sources,
                presets,
                emission,
                reaction,
            } => {
                for (at, names) in presets {
                    sources[at].grid = Some(preset_grid(names, &sources[at].file, &opts)?);
                }
                let heat = if tool == Tool::Auto {
                    auto_grids(
                        &mut sources,
                        named,
                        find_unit.then_some(flame),
                        &opts,
                        &mut resolved,
                        &mut chosen,
                    )?
                } else {
                    None
                };
                let mut ds = Dataset::load(&sources, &opts)?;
                let temperature = (sources.len() > 1 && sources[1].name == "temperature")
                    .then(|| ds.channels().iter().position(|c| c.name == "temperature"))
                    .flatten();
                if let (true, Some(t), false) = (
                    find_unit,
                    temperature,
                    heat == Some(convention::HeatKind::Flame),
                ) {
                    let grid = sources[1].grid.clone().unwrap_or_default();
                    let peak = convention::peak(&ds.channels()[t].grid);
                    let (unit, warning) =
                        convention::unit(&grid, convention::HeatKind::Temperature, peak);
                    if let convention::Unit::Relative { kelvin_per_unit } = unit.value {
                        ds.scale_channel(t, kelvin_per_unit as f32).ok_or_else(|| {
                            Error::invalid(
                                "dataset",
                                "temperaturegrid",
                                format!("'{grid}' × {kelvin_per_unit}"),
                                "a temperature the memory allows to scale",
                            )
                        })?;
                    }
                    if unit.value != convention::Unit::Kelvin {
                        chosen.push(format!("temperature unit: {}", unit.why));
                    }
                    chosen.extend(warning);
                }
                let at = |n: &str| ds.channels().iter().position(|c| c.name == n);
                let emission = at("emission").filter(|_| emission);
                let motion = match VELOCITY.map(at) {
                    [Some(x), Some(y), Some(z)] => Some(Motion {
                        channels: [x, y, z],
                        per_frame,
                        shutter,
                    }),
                    _ => None,
                };
                let scatter = match SCATTER_COLOR.map(at) {
                    [Some(r), Some(g), Some(b)] => Some([r, g, b]),
                    _ => None,
                };
                let reaction = at("reaction").filter(|_| reaction);
                (ds, emission, emission.is_some(), motion, scatter, reaction)
            }
        };
        let embers = match embers {
            Some((name, fps)) => Some(read_embers(&name, &opts, shutter, fps)?),
            None => None,
        };
        Ok(Loaded {
            ds: ds.with_interpolation(interp),
            lescale,
            emission_grid,
            motion,
            scatter_color,
            reaction,
            embers,
            tool: resolved.convention(),
            chosen,
        })
    }
}

/// `source "auto"` on a file: the grids its names choose (convention::names) for the density and the
/// temperature the scene did not name, the flame mapping for a Mantaflow cache's flame; the tool found goes to
/// `resolved` and what was chosen, a sentence each, to `chosen`; `flame`: the mapping of a flame grid (`None`: the
/// scene gave a mapping of its own). Returns what the heat grid holds (`None`: the
/// names chose nothing — inline, a single-grid format, or names no convention knows — and the defaults stand).
fn auto_grids(
    sources: &mut [ChannelSource],
    named: [bool; 2],
    flame: Option<Mapping>,
    opts: &LoadOptions,
    resolved: &mut Tool,
    chosen: &mut Vec<String>,
) -> Result<Option<convention::HeatKind>, Error> {
    *resolved = Tool::Kelvin;
    let file = sources[0].file.clone();
    let format = super::format_of(&file, opts)?;
    if !matches!(format, Format::Vdb | Format::NanoVdb) {
        return Ok(None);
    }
    let entries = super::list_grids(&file, opts)?;
    let label = file.display().to_string();
    let Ok(n) = convention::names(&label, &entries, format == Format::NanoVdb) else {
        return Ok(None);
    };
    *resolved = Tool::of(n.tool.value);
    // A generic density + temperature file is what `kelvin` always read: nothing to say.
    let plain = matches!(
        n.tool.value,
        convention::Tool::Kelvin | convention::Tool::Pbrt
    );
    let mut say = |s: String| {
        if !plain {
            chosen.push(s);
        }
    };
    say(format!("source \"auto\": {}", n.tool.why));
    if !named[0] {
        sources[0].grid = Some(n.smoke.value.clone());
        say(format!("density: {}", n.smoke.why));
    }
    let has_temperature = sources.len() > 1 && sources[1].name == "temperature";
    let (grid, kind) = n.heat.value.clone();
    // A flame grid stands for the temperature only with auto's own mapping: a mapping the scene gives is for the
    // grid it names, 'temperature' by default.
    if !named[1]
        && has_temperature
        && (kind == convention::HeatKind::Temperature || flame.is_some())
    {
        sources[1].grid = Some(grid);
        if let (convention::HeatKind::Flame, Some(m)) = (kind, flame) {
            sources[1].mapping = m;
            chosen.push(format!("temperature: {}", n.heat.why));
            chosen.push(format!(
                "temperature unit: {}",
                convention::unit(&n.heat.value.0, kind, 1.0).0.why
            ));
        } else {
            say(format!("temperature: {}", n.heat.why));
        }
        return Ok(Some(kind));
    }
    Ok(has_temperature.then_some(convention::HeatKind::Temperature))
}

/// The grid a preset reads: the first of `names` the file holds (an error listing them and the file's grids
/// when it holds none).
fn preset_grid(
    names: &[&str],
    file: &std::path::Path,
    opts: &LoadOptions,
) -> Result<String, Error> {
    let grids = super::list_grids(file, opts)?;
    match names.iter().find(|n| grids.iter().any(|g| g.name == **n)) {
        Some(n) => Ok(n.to_string()),
        None => Err(super::missing_grid(
            &file.display().to_string(),
            &names.join("' or '"),
            grids.iter().map(|g| g.name.as_str()),
        )),
    }
}

/// The `embers` file (frame-substituted), read and checked.
fn read_embers(
    name: &str,
    opts: &LoadOptions,
    shutter: [f64; 2],
    fps: f64,
) -> Result<EmberFile, Error> {
    let path = frame_path(std::path::Path::new(name), opts.frame)?;
    let file = path.display().to_string();
    let (_, len) = crate::dataset::open_regular(&path)?;
    if len > opts.max_bytes {
        return Err(Error::TooLarge {
            file,
            what: "the embers file".into(),
            bytes: len,
            cap: opts.max_bytes,
        });
    }
    let bytes = crate::dataset::read_file(&path)?;
    let particles = super::particles::parse(&file, &bytes, opts.max_bytes)?;
    Ok(EmberFile {
        file,
        particles,
        shutter,
        fps,
    })
}
