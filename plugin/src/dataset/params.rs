//! The voxel dataset's parameters (the `dataset` table, docs/reference/params.md) mapped to what it loads: a file (its
//! format, grid names, temperature mapping, the thesis formats' options, species grids) or pbrt-v4's inline
//! arrays, with the policies and the memory cap.

use super::{
    AxisOrder, ChannelSource, Dataset, Format, LoadOptions, Mapping, Policy, RawCoords, RawValue,
};
use crate::grid::Interpolation;
use crate::params::{choice, ParamReader};
use crate::Error;
use glam::DVec3;

/// Motion blur by the velocity grid (`velocitygrid`), when the shutter is open: the dataset's three velocity
/// channels and what turns a velocity and a time into a displacement.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Motion {
    /// Channels of the velocity's x, y and z.
    pub channels: [usize; 3],
    /// Medium units per frame per unit of the grid (`velocityscale / fps`).
    pub per_frame: f64,
    /// The shutter, in frames from the grids' time.
    pub shutter: [f64; 2],
}

/// The velocity channels' names in a dataset.
pub(super) const VELOCITY: [&str; 3] = ["velocity.x", "velocity.y", "velocity.z"];

use firemedium_dataset::convention;

/// `source`: the tool whose conventions the grids follow.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Tool {
    /// Found from the file's grid names and data (`firemedium_dataset::convention`); kelvin for inline grids and
    /// single-grid formats.
    Auto,
    /// Density and temperature in K (our gen, the thesis's files).
    Kelvin,
    /// pbrt-v4's nanovdb: as kelvin.
    Pbrt,
    /// A Mantaflow domain cache: the flame grid as Cycles maps it.
    Blender,
    /// Pyro: a relative temperature (× 5000 K, or less to hold its peak at 1500 K).
    Houdini,
    /// EmberGen: smoke and temperature in K.
    EmberGen,
}
choice!(Tool { Tool::Auto => "auto", Tool::Kelvin => "kelvin", Tool::Pbrt => "pbrt", Tool::Blender => "blender", Tool::Houdini => "houdini", Tool::EmberGen => "embergen" });
choice!(Option<Format> {
    None => "",
    Some(Format::AsciiDense) => "ascii",
    Some(Format::AsciiSparse) => "asciisparse",
    Some(Format::Raw) => "raw",
    Some(Format::Raw2) => "raw2",
    Some(Format::Vdb) => "vdb",
    Some(Format::NanoVdb) => "nvdb",
});

/// The names a tool writes a channel under, in the order tried (`source` presets): (density, temperature).
fn preset_names(source: Tool) -> Option<(&'static [&'static str], &'static [&'static str])> {
    match source {
        // Houdini's Pyro: density, temperature (older setups: heat).
        Tool::Houdini => Some((&["density"], &["temperature", "heat"])),
        // EmberGen: smoke, temperature (kelvin), flames, fuel, velocity.
        Tool::EmberGen => Some((&["smoke", "density"], &["temperature"])),
        Tool::Auto | Tool::Kelvin | Tool::Pbrt | Tool::Blender => None,
    }
}

impl Tool {
    pub(super) fn of(t: convention::Tool) -> Tool {
        match t {
            convention::Tool::Kelvin => Tool::Kelvin,
            convention::Tool::Pbrt => Tool::Pbrt,
            convention::Tool::Blender => Tool::Blender,
            convention::Tool::Houdini => Tool::Houdini,
            convention::Tool::EmberGen => Tool::EmberGen,
        }
    }
    pub(super) fn convention(self) -> convention::Tool {
        match self {
            Tool::Auto | Tool::Kelvin => convention::Tool::Kelvin,
            Tool::Pbrt => convention::Tool::Pbrt,
            Tool::Blender => convention::Tool::Blender,
            Tool::Houdini => convention::Tool::Houdini,
            Tool::EmberGen => convention::Tool::EmberGen,
        }
    }
}

/// Blender's flame grid as Cycles maps it: 1000 K · (ignition + flame · (maximum − ignition)) where flame > 0.
fn flame_mapping(ignition: f64, maximum: f64) -> Mapping {
    Mapping {
        scale: 1000.0 * (maximum - ignition),
        offset: 1000.0 * ignition,
        pbrt_offset: 0.0,
        zero_at_or_below: Some(0.0),
    }
}

/// The grid names `velocitygrid` gives (empty: none): one name is a vector grid or its components' float grids
/// (`name.x` …, which the OpenVDB reader resolves either way); three are float grids.
fn velocity_grids(r: &ParamReader) -> Result<Option<[String; 3]>, Error> {
    let names: Vec<String> = r
        .strings("velocitygrid")?
        .unwrap_or_default()
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    match names.as_slice() {
        [] => Ok(None),
        [one] => Ok(Some(["x", "y", "z"].map(|a| format!("{one}.{a}")))),
        [x, y, z] => Ok(Some([x.clone(), y.clone(), z.clone()])),
        _ => Err(Error::invalid(
            "dataset",
            "velocitygrid",
            format!("{} names", names.len()),
            "one name (a vector grid) or three (float grids x, y, z)",
        )),
    }
}

/// The grid the scene names for a channel: by our parameter `ours` or by pbrt-v4's nanovdb name `theirs`
/// (`gridname`, `temperaturename`); `None` when neither is given; an error when both are.
fn grid_name(r: &ParamReader, ours: &str, theirs: &str) -> Result<Option<String>, Error> {
    match (r.list_has(ours), r.list_has(theirs)) {
        (true, true) => Err(Error::invalid(
            "dataset",
            theirs,
            format!("\"{theirs}\" and \"{ours}\" both given"),
            format!("one name for the grid (pbrt-v4 reads \"{theirs}\")"),
        )),
        (true, false) => r.string(ours).map(Some),
        (false, true) => r.string(theirs).map(Some),
        (false, false) => Ok(None),
    }
}

/// What [`Request::load`] gives a volume.
pub(crate) struct Loaded {
    pub ds: Dataset,
    /// The channel that scales emission per voxel: pbrt-v4's inline `Lescale`, or the `emissiongrid`.
    pub lescale: Option<usize>,
    /// Whether that channel is an emission grid: the fire's emission follows it instead of the density
    /// (j = e · J(T), not d · J(T)).
    pub emission_grid: bool,
    /// Motion blur (velocity is read only while the shutter is open).
    pub motion: Option<Motion>,
    /// The scatter colour's r, g, b channels (`scattercolorgrid`: Houdini's `Cd`).
    pub scatter_color: Option<[usize; 3]>,
    /// The reaction zone's heat release rate (`reactiongrid`, W/m³): the blue core's chemiluminescence.
    pub reaction: Option<usize>,
    /// The `embers` particle file, read.
    pub embers: Option<EmberFile>,
    /// The tool whose conventions the grids were read in (`source`, or what `auto` found).
    pub tool: convention::Tool,
    /// What `source "auto"` chose and what the temperature's unit was found to be, a sentence each (the
    /// volume's notes).
    pub chosen: Vec<String>,
}

/// An `embers` file's particles, and the shutter and frame rate they move in.
pub(crate) struct EmberFile {
    pub file: String,
    pub particles: Vec<super::particles::Particle>,
    /// Frames from the grids' time.
    pub shutter: [f64; 2],
    pub fps: f64,
}

/// The dataset's channels of the scatter colour (`scattercolorgrid`).
pub(crate) const SCATTER_COLOR: [&str; 3] = ["scattercolor.r", "scattercolor.g", "scattercolor.b"];

/// What the dataset's parameters ask for, read and checked without opening a file ([`read`]); [`Request::load`]
/// then reads the files. A mistake in the parameters is reported before a large file is read.
pub(crate) struct Request {
    pub(super) opts: LoadOptions,
    pub(super) interp: Interpolation,
    pub(super) grids: Grids,
    /// Medium units per frame per unit of velocity, and the shutter in frames.
    pub(super) per_frame: f64,
    pub(super) shutter: [f64; 2],
    /// The `embers` file and the frame rate its particles move at.
    pub(super) embers: Option<(String, f64)>,
    /// The tool the parameters name.
    pub(super) tool: Tool,
    /// Whether the temperature's unit is found from its peak once read (`auto` and `houdini` without a mapping
    /// of the scene's own).
    pub(super) find_unit: bool,
    /// Whether the scene named the density and the temperature grid (`auto` leaves those alone).
    pub(super) named: [bool; 2],
    /// Blender's flame mapping (`flameignition`, `flamemax`), for a Mantaflow cache `auto` finds.
    pub(super) flame: Mapping,
}

/// Where the grids come from.
pub(super) enum Grids {
    /// pbrt-v4's inline arrays: (name, values), the last `Lescale` when `lescale`.
    Inline {
        dims: [usize; 3],
        bounds: [DVec3; 2],
        arrays: Vec<(&'static str, Vec<f32>)>,
        lescale: bool,
    },
    /// Files: each channel's source; `presets` — (source, names) — name the grids a `source` preset tries in
    /// its file, the first found taken; whether an emission and a reaction grid were asked for.
    Files {
        sources: Vec<ChannelSource>,
        presets: Vec<(usize, &'static [&'static str])>,
        emission: bool,
        reaction: bool,
    },
}

/// How the coefficients are defined: the `mode` parameter, or the kind of medium a host's scene named.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Pegoraro & Parker's fire.
    Physical,
    /// pbrt-v4's grid media.
    Pbrt,
}
choice!(Mode { Mode::Physical => "physical", Mode::Pbrt => "pbrt" });

/// What a host says of its render (the ABI's `FmCreateInfo`), typed end to end: each stands where the scene
/// does not set the parameter of the same meaning itself (`threads`, `maxbytes`, `frame`, `shutteropen`,
/// `shutterclose`, `mode`, `bins`, `lambdamin`, `lambdamax`), which wins.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct HostContext {
    /// The host's thread count (0 or none: the parameter's default, every core).
    pub threads: Option<usize>,
    /// The host's memory budget for the volume, bytes.
    pub max_bytes: Option<u64>,
    /// The frame being rendered (patterned file names take it).
    pub frame: Option<i64>,
    /// The camera's shutter, open and close, in frames from the grids' time.
    pub shutter: Option<[f64; 2]>,
    /// What the medium type the scene named means (pbrt-v4's `nanovdb` and `uniformgrid`: [`Mode::Pbrt`]).
    pub mode: Option<Mode>,
    /// The render's spectral bins.
    pub bins: Option<usize>,
    /// The bins' span, nm.
    pub wavelengths: Option<[f64; 2]>,
}

impl HostContext {
    /// `name`'s value: the scene's if it sets it, else the host's (`host`), else the table's default.
    pub(crate) fn float(r: &ParamReader, name: &str, host: Option<f64>) -> Result<f64, Error> {
        match host {
            Some(v) if !r.list_has(name) => Ok(v),
            _ => r.float(name),
        }
    }

    /// The medium's mode: the scene's `mode` if it sets it, else the host's, else the paper's fire.
    pub(crate) fn mode(&self, r: &ParamReader) -> Result<Mode, Error> {
        match self.mode {
            Some(m) if !r.list_has("mode") => Ok(m),
            _ => r.choice("mode"),
        }
    }
}

/// Reads the dataset's parameters (pbrt-v4's grid media when `pbrt`) beside the host's context, touching no file.
/// How the dataset's files are read (format, a raw file's layout, what replaces non-finite and negative values, the
/// memory budget, the frame — the scene's, else the host's), and the box the scene gives it, if any.
fn load_options(
    r: &ParamReader,
    ctx: &HostContext,
) -> Result<(LoadOptions, Option<[DVec3; 2]>), Error> {
    let pol = |name: &str| -> Result<Policy, Error> { r.choice(name) };
    let format: Option<Format> = r.choice("format")?;
    let rawdims = r.ints("rawdims")?.unwrap_or(vec![256, 256, 256]);
    if rawdims.len() != 3 {
        return Err(Error::invalid(
            "dataset",
            "rawdims",
            format!("{} values", rawdims.len()),
            "three integers",
        ));
    }
    let (p0, p1) = (r.point3("p0")?, r.point3("p1")?);
    let bounds = match (p0, p1) {
        (None, None) => None,
        (a, b) => Some([
            DVec3::from(a.unwrap_or([0.0; 3])),
            DVec3::from(b.unwrap_or([1.0; 3])),
        ]),
    };
    let opts = LoadOptions {
        format,
        order: r.choice("order")?,
        raw_coords: r.choice("rawcoords")?,
        raw_value: r.choice("rawvalue")?,
        raw_dims: [
            rawdims[0] as usize,
            rawdims[1] as usize,
            rawdims[2] as usize,
        ],
        nonfinite: pol("nonfinite")?,
        negative: pol("negative")?,
        max_bytes: HostContext::float(r, "maxbytes", ctx.max_bytes.map(|b| b as f64))? as u64,
        frame: match r.ints("frame")?.and_then(|v| v.first().copied()) {
            None => ctx.frame,
            f => f,
        },
        bounds,
    };
    Ok((opts, bounds))
}

/// The grids given inline (`float density` with `nx ny nz`; a temperature mapped by `tmap`, an `Lescale` array),
/// over `bounds` or the unit box. Refused with a velocity or a grid only a file holds.
fn inline_grids(
    r: &ParamReader,
    dens: &[f64],
    tmap: Mapping,
    lescale_values: Option<Vec<f64>>,
    velocity: bool,
    bounds: Option<[DVec3; 2]>,
) -> Result<Grids, Error> {
    let dims = [
        r.int("nx")? as usize,
        r.int("ny")? as usize,
        r.int("nz")? as usize,
    ];
    let to32 = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
    let dens = to32(dens);
    let mut temp = r.numbers("temperature")?.map(|v| to32(&v));
    if let Some(t) = temp.as_mut() {
        for v in t.iter_mut() {
            *v = ((*v as f64 - tmap.pbrt_offset) * tmap.scale) as f32;
        }
    }
    let les = lescale_values
        .filter(|v| v.len() > 1 || dims == [1, 1, 1])
        .map(|v| to32(&v));
    let lescale = les.is_some();
    let mut arrays = vec![("density", dens)];
    if let Some(t) = temp {
        arrays.push(("temperature", t));
    }
    if let Some(l) = les {
        arrays.push(("Lescale", l));
    }
    if velocity {
        return Err(Error::invalid(
            "dataset",
            "velocitygrid",
            "given for an inline grid",
            "a dataset file holding the velocity grid",
        ));
    }
    for name in ["emissiongrid", "scattercolorgrid", "reactiongrid"] {
        if r.list_has(name) {
            return Err(Error::invalid(
                "dataset",
                name,
                "given for an inline grid",
                "a dataset file holding the grid",
            ));
        }
    }
    Ok(Grids::Inline {
        dims,
        bounds: bounds.unwrap_or([DVec3::ZERO, DVec3::ONE]),
        arrays,
        lescale,
    })
}

/// The grids the dataset's files hold: density and temperature (named by the scene, by pbrt-v4's names, or by
/// the `source` tool's preset, found when the files are read), the species', an emission, reaction, scatter colour
/// or velocity grid. With which of density and temperature the scene named.
fn file_grids(
    r: &ParamReader,
    (tool, pbrt, tmap): (Tool, bool, Mapping),
    species: &[String],
    format: Option<Format>,
    lescale_values: Option<Vec<f64>>,
    velocity: Option<&[String; 3]>,
) -> Result<(Grids, [bool; 2]), Error> {
    let blender = tool == Tool::Blender;
    let filename = match (r.string("filename")?, r.string("dataset")?) {
        (f, d) if !f.is_empty() && !d.is_empty() => {
            return Err(Error::invalid(
                "dataset",
                "dataset",
                format!("\"{d}\" with filename \"{f}\""),
                "one of filename or dataset",
            ))
        }
        (f, d) => {
            if f.is_empty() {
                d
            } else {
                f
            }
        }
    };
    let densityfile = r.string("densityfile")?;
    let temperaturefile = r.string("temperaturefile")?;
    let dfile = if !densityfile.is_empty() {
        densityfile
    } else {
        filename.clone()
    };
    if dfile.is_empty() {
        return Err(Error::invalid(
            "dataset",
            "filename",
            "unset",
            "a dataset file (filename or densityfile), or inline \"float density\" with nx ny nz",
        ));
    }
    let tfile = if !temperaturefile.is_empty() {
        temperaturefile
    } else {
        filename.clone()
    };
    // The grids the scene names, by our names or pbrt-v4's nanovdb ones.
    let dg = grid_name(r, "densitygrid", "gridname")?;
    let tg = grid_name(r, "temperaturegrid", "temperaturename")?;
    let named = [dg.is_some(), tg.is_some()];
    // A preset's grid is found in its file when the files are read (`presets`); its name here stands for it.
    let mut presets = Vec::new();
    let (dgrid, tgrid) = match preset_names(tool) {
        Some((d, t)) => {
            let mut named = |given: Option<String>, names: &'static [&'static str], at: usize| {
                given.unwrap_or_else(|| {
                    presets.push((at, names));
                    names[0].to_string()
                })
            };
            (named(dg, d, 0), named(tg, t, 1))
        }
        None => (
            dg.map_or_else(|| r.string("densitygrid"), Ok)?,
            match tg {
                Some(t) => t,
                None if blender => "flame".to_string(),
                None => r.string("temperaturegrid")?,
            },
        ),
    };
    let mut sources = vec![ChannelSource {
        name: "density".into(),
        file: dfile.clone().into(),
        grid: Some(dgrid),
        mapping: Mapping::default(),
    }];
    let single = matches!(
        format.or_else(|| Format::from_extension(std::path::Path::new(&tfile))),
        Some(Format::AsciiDense | Format::AsciiSparse | Format::Raw | Format::Raw2)
    );
    // A single-grid file cannot hold temperature too: without a temperature file there is none.
    let no_temperature = tgrid.is_empty() || (single && tfile == dfile);
    if no_temperature {
        presets.retain(|&(at, _)| at != 1);
    } else {
        sources.push(ChannelSource {
            name: "temperature".into(),
            file: tfile.into(),
            grid: Some(tgrid),
            mapping: tmap,
        });
    }
    let sfiles = r.strings("speciesfiles")?.unwrap_or_default();
    for (i, sym) in species.iter().enumerate() {
        let file = sfiles.get(i).cloned().unwrap_or_else(|| filename.clone());
        sources.push(ChannelSource {
            name: sym.clone(),
            file: file.into(),
            grid: Some(sym.clone()),
            mapping: Mapping::default(),
        });
    }
    if lescale_values.as_ref().is_some_and(|v| v.len() > 1) {
        return Err(Error::invalid(
            "volume",
            "Lescale",
            "an array",
            "one value for file datasets (arrays are for inline grids)",
        ));
    }
    let vfile = if filename.is_empty() {
        &dfile
    } else {
        &filename
    };
    // A grid the physical model alone reads, named by `param`, as the channel `channel` (refused in pbrt mode,
    // saying what it takes there).
    let mut physical_grid = |param: &str, channel: &str, instead: &str| -> Result<bool, Error> {
        let grid = r.string(param)?;
        if grid.is_empty() {
            return Ok(false);
        }
        if pbrt {
            return Err(Error::invalid("volume", param, "given", instead));
        }
        sources.push(ChannelSource {
            name: channel.into(),
            file: vfile.into(),
            grid: Some(grid),
            mapping: Mapping::default(),
        });
        Ok(true)
    };
    // An emission grid (Houdini's or Blender's `flame`, `heat`, `burn`): the fire's emission follows it.
    let emission = physical_grid(
        "emissiongrid",
        "emission",
        "mode \"physical\" (pbrt mode takes Lescale)",
    )?;
    // The heat release rate of the reaction zone (the blue core).
    let reaction = physical_grid(
        "reactiongrid",
        "reaction",
        "mode \"physical\" (the blue core is the physical model's)",
    )?;
    // The scatter colour (Houdini's `Cd`, a vector grid, or its components as float grids).
    let cd = r.string("scattercolorgrid")?;
    if !cd.is_empty() {
        for (name, axis) in SCATTER_COLOR.iter().zip(["x", "y", "z"]) {
            sources.push(ChannelSource {
                name: name.to_string(),
                file: vfile.into(),
                grid: Some(format!("{cd}.{axis}")),
                mapping: Mapping::default(),
            });
        }
    }
    for (name, grid) in VELOCITY.iter().zip(velocity.into_iter().flatten()) {
        sources.push(ChannelSource {
            name: name.to_string(),
            file: vfile.into(),
            grid: Some(grid.clone()),
            mapping: Mapping::default(),
        });
    }
    Ok((
        Grids::Files {
            sources,
            presets,
            emission,
            reaction,
        },
        named,
    ))
}

pub(crate) fn read(r: &ParamReader, pbrt: bool, ctx: &HostContext) -> Result<Request, Error> {
    let shutter = [
        HostContext::float(r, "shutteropen", ctx.shutter.map(|s| s[0]))?,
        HostContext::float(r, "shutterclose", ctx.shutter.map(|s| s[1]))?,
    ];
    if shutter[1] < shutter[0] {
        return Err(Error::invalid(
            "dataset",
            "shutterclose",
            format!("{} (shutteropen {})", shutter[1], shutter[0]),
            "a time at or after shutteropen",
        ));
    }
    let velocity = velocity_grids(r)?.filter(|_| shutter[1] > shutter[0]);
    let per_frame = r.float("velocityscale")? / r.float("fps")?;
    let (opts, bounds) = load_options(r, ctx)?;
    let offset = match (
        r.opt_float("temperatureoffset")?,
        r.opt_float("temperaturecutoff")?,
    ) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                "dataset",
                "temperaturecutoff",
                "given with temperatureoffset",
                "one of the two (they are the same)",
            ))
        }
        (Some(o), None) | (None, Some(o)) => o,
        (None, None) => 0.0,
    };
    let mut tmap = Mapping {
        scale: r.float("temperaturescale")?,
        offset: 0.0,
        pbrt_offset: offset,
        zero_at_or_below: None,
    };
    // Where the grids come from: Blender's fluid cache gives the fire's temperature as its flame grid, which
    // Cycles maps to 1000 K · (ignition + flame · (maximum − ignition)) where there is flame (Blender's defaults:
    // ignition 1.5, maximum 3.0).
    let tool: Tool = r.choice("source")?;
    let source = crate::params::name_of(tool);
    let blender = tool == Tool::Blender;
    // Houdini's Pyro shader maps its relative temperature linearly onto kelvin, 1 → its blackbody's "temperature
    // high", 5000 K by default (SideFX, Pyro Shader / Blackbody COP docs) — unless that puts the flame above a
    // sooty flame's 2000 K (convention::unit, once the grid is read); EmberGen's grids hold kelvin, under their
    // own names. A mapping of the scene's own replaces the preset's.
    let mapping_given = [
        "temperaturescale",
        "temperatureoffset",
        "temperaturecutoff",
        "temperatureremap",
    ]
    .into_iter()
    .find(|n| r.list_has(n));
    if blender {
        if let Some(n) = mapping_given {
            return Err(Error::invalid(
                "dataset",
                n,
                format!("given with source \"{source}\""),
                "the blender source's own mapping (set flameignition and flamemax to the domain's)",
            ));
        }
    }
    let (ign, max) = (r.float("flameignition")?, r.float("flamemax")?);
    if !(max > ign) {
        return Err(Error::invalid(
            "dataset",
            "flamemax",
            format!("{max} (flameignition {ign})"),
            "a maximum above the ignition temperature",
        ));
    }
    if blender {
        tmap = flame_mapping(ign, max);
    } else if tool != Tool::Auto && (r.list_has("flameignition") || r.list_has("flamemax")) {
        return Err(Error::invalid(
            "dataset",
            if r.list_has("flameignition") {
                "flameignition"
            } else {
                "flamemax"
            },
            format!("given with source \"{source}\""),
            "source \"blender\" or \"auto\" (they are a Mantaflow domain's flame settings)",
        ));
    }
    if tool == Tool::Houdini && mapping_given.is_none() {
        tmap.scale = convention::HOUDINI_KELVIN;
    }
    // `auto` finds the unit from the grid's peak once it is read (convention::unit), unless the scene maps it.
    let find_unit = tool == Tool::Auto && mapping_given.is_none() && !pbrt;
    // Art direction: the grid's range [a, b] onto kelvin [ka, kb], linearly — the same map as a scale and an
    // offset, T = (t − (a − ka/s)) · s with s = (kb − ka)/(b − a).
    if let Some(v) = r.numbers("temperatureremap")? {
        let given = ["temperaturescale", "temperatureoffset", "temperaturecutoff"]
            .into_iter()
            .find(|n| r.opt_float(n).ok().flatten().is_some());
        if let Some(n) = given {
            return Err(Error::invalid(
                "dataset",
                "temperatureremap",
                format!("given with {n}"),
                "one way to map temperatures (the remap is a scale and an offset)",
            ));
        }
        let ok = v.len() == 4 && v.iter().all(|x| x.is_finite()) && v[1] != v[0];
        let s = if ok {
            (v[3] - v[2]) / (v[1] - v[0])
        } else {
            f64::NAN
        };
        if !(s.is_finite() && s > 0.0 && s <= 1e9) {
            return Err(Error::invalid(
                "dataset",
                "temperatureremap",
                format!("{v:?}"),
                "four numbers: the grid's range a b (a ≠ b) and the kelvin range ka < kb it maps onto, increasing together",
            ));
        }
        tmap.scale = s;
        tmap.pbrt_offset = v[0] - v[2] / s;
    }
    let interp: Interpolation = r.choice("interpolation")?;
    let species: Vec<String> = r
        .strings("species")?
        .unwrap_or_default()
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    if pbrt && !species.is_empty() {
        return Err(Error::invalid(
            "volume",
            "species",
            "given",
            "mode \"physical\"",
        ));
    }
    let inline_density = r.numbers("density")?;
    let mut named = [true, true];
    let lescale_values = r.numbers("Lescale")?;
    let grids = match inline_density {
        Some(dens) => inline_grids(r, &dens, tmap, lescale_values, velocity.is_some(), bounds)?,
        None => {
            let (grids, given) = file_grids(
                r,
                (tool, pbrt, tmap),
                &species,
                opts.format,
                lescale_values,
                velocity.as_ref(),
            )?;
            named = given;
            grids
        }
    };
    let embers = r.string("embers")?;
    let embers = if embers.is_empty() {
        None
    } else {
        Some((embers, r.float("fps")?))
    };
    Ok(Request {
        opts,
        interp,
        grids,
        per_frame,
        shutter,
        embers,
        tool,
        find_unit,
        named,
        // `auto`'s flame grid: a fire's luminous soot's temperatures unless the scene gives Blender's.
        flame: if r.list_has("flameignition") || r.list_has("flamemax") {
            flame_mapping(ign, max)
        } else {
            let (a, b) = convention::FLAME_RANGE;
            flame_mapping(a, b)
        },
    })
}

/// Whether `Lescale` is a per-voxel grid (pbrt-v4: any `Lescale` array of an inline grid is one, a single value
/// included when the grid is one voxel — it then fades to its faces as the density does) rather than one factor.
pub(crate) fn lescale_is_grid(r: &ParamReader) -> Result<bool, Error> {
    let Some(v) = r.numbers("Lescale")? else {
        return Ok(false);
    };
    let one_voxel =
        r.numbers("density")?.is_some() && [r.int("nx")?, r.int("ny")?, r.int("nz")?] == [1, 1, 1];
    Ok(v.len() > 1 || one_voxel)
}

choice!(AxisOrder { AxisOrder::XFastest => "x", AxisOrder::ZFastest => "z" });
choice!(RawCoords { RawCoords::Thesis => "thesis", RawCoords::Xyz => "xyz" });
choice!(RawValue { RawValue::Red => "red", RawValue::MaxRgb => "maxrgb" });
choice!(Policy { Policy::Error => "error", Policy::Zero => "zero" });
choice!(Interpolation { Interpolation::Trilinear => "trilinear", Interpolation::Nearest => "nearest" });
