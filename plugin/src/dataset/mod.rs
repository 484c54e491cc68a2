//! The voxel dataset component (the thesis's "voxel dataset shader"): files → named scalar grids on one
//! lattice, validated, mapped, and sampled in medium space.
//!
//! ## Channels
//! A [`Dataset`] holds named channels on one nx × ny × nz grid over the medium-space box `p0..p1` (x fastest,
//! cell-centred, pbrt's convention; see [`crate::grid`]):
//! - `density`: soot volume fraction f_v, or a normalised density the fire volume maps to f_v by a scale;
//! - `temperature`: kelvin after the mapping;
//! - species (`Na`, `Li`, …): **number densities in m⁻³** after the mapping (a mole fraction x converts with
//!   N = x·p/(k_B T), which the fire volume does when told the channel holds mole fractions);
//! - anything else a file holds, under its own name.
//!
//! Only the channels a scene asks for are loaded ([`ChannelSource`]); each is converted to `f32` (half-float
//! files decode exactly into `f32`) and reported with its bytes and load time.
//!
//! ## Mapping
//! Per channel, at load time: v' = (v − `pbrt_offset`) · `scale` + `offset`. `scale`/`offset` are the
//! Maya/Arnold-style artist controls; `pbrt_offset` with `scale` is pbrt-v4's `temperatureoffset` /
//! `temperaturescale` meaning T' = (T − offset) · scale.
//!
//! ## Bad data
//! NaN or infinite values in any channel, and negative values in the physical channels (`density`,
//! `temperature`, species) as the file holds them, are errors naming the file, channel, voxel and value unless
//! the [`Policy`] says `Zero`, which replaces them with 0 and counts them in the report. Other channels keep
//! negative values. Physical values that the mapping moves below zero (an offset used as a cutoff, as pbrt-v4's
//! `temperaturecutoff`) are clamped to 0. Dims whose product
//! overflows or whose grid would exceed `max_bytes` are refused before anything is allocated.

mod ascii;
mod compress;
mod cursor;
pub mod nanovdb;
pub(crate) mod params;
pub mod raw;
mod sparse;
mod text;
pub mod vdb;

pub use sparse::Transform;

use crate::grid::{Grid, GridStats, Interpolation};
use crate::Error;
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

pub use raw::{RawCoords, RawValue};

/// A file format of the voxel dataset component.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Thesis ASCII dense: `w h d` then w·h·d values.
    AsciiDense,
    /// Uintah ASCII sparse: `w h d`, count, background, `x y z value` lines.
    AsciiSparse,
    /// Thesis binary sparse without dims (256³).
    Raw,
    /// Thesis binary sparse with three int32 dims.
    Raw2,
    /// OpenVDB.
    Vdb,
    /// NanoVDB.
    NanoVdb,
    /// pbrt-v4 inline arrays (`uniformgrid` medium parameters).
    Inline,
}

impl Format {
    /// Every format's parameter name.
    pub const NAMES: [&'static str; 6] = ["ascii", "asciisparse", "raw", "raw2", "vdb", "nvdb"];

    /// The format with parameter name `name`.
    pub fn from_name(name: &str) -> Result<Format, Error> {
        Ok(match name {
            "ascii" => Format::AsciiDense,
            "asciisparse" => Format::AsciiSparse,
            "raw" => Format::Raw,
            "raw2" => Format::Raw2,
            "vdb" => Format::Vdb,
            "nvdb" | "nanovdb" => Format::NanoVdb,
            _ => {
                return Err(Error::invalid(
                    "dataset",
                    "format",
                    format!("'{name}'"),
                    format!("one of {}", Format::NAMES.join(", ")),
                ))
            }
        })
    }

    /// The parameter name of this format.
    pub fn name(self) -> &'static str {
        match self {
            Format::AsciiDense => "ascii",
            Format::AsciiSparse => "asciisparse",
            Format::Raw => "raw",
            Format::Raw2 => "raw2",
            Format::Vdb => "vdb",
            Format::NanoVdb => "nvdb",
            Format::Inline => "inline",
        }
    }

    /// The format a file's extension implies: `.vdb`, `.nvdb`, `.raw`, `.raw2`; `.txt`/`.ascii`/`.dat` are
    /// dense ASCII (sparse ASCII must be named with `format "asciisparse"`).
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "vdb" => Format::Vdb,
            "nvdb" => Format::NanoVdb,
            "raw" => Format::Raw,
            "raw2" => Format::Raw2,
            "txt" | "ascii" | "dat" => Format::AsciiDense,
            _ => return None,
        })
    }
}

/// Axis order of the values in a dense ASCII file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AxisOrder {
    /// x varies fastest (the thesis's text; the default).
    #[default]
    XFastest,
    /// z varies fastest (the thesis's shader code).
    ZFastest,
}

/// What to do with NaN/infinite or negative values.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Policy {
    /// Refuse the file with an error naming the voxel.
    #[default]
    Error,
    /// Replace with 0 and count it in the report.
    Zero,
}

impl Policy {
    /// `error` or `zero`.
    pub fn from_name(param: &str, name: &str) -> Result<Policy, Error> {
        match name {
            "error" => Ok(Policy::Error),
            "zero" => Ok(Policy::Zero),
            _ => Err(Error::invalid(
                "dataset",
                param,
                format!("'{name}'"),
                "error or zero",
            )),
        }
    }
}

/// Per-channel artist mapping v' = (v − pbrt_offset) · scale + offset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mapping {
    /// Multiplier.
    pub scale: f64,
    /// Added after scaling (Maya/Arnold offset).
    pub offset: f64,
    /// Subtracted before scaling (pbrt's `temperatureoffset`).
    pub pbrt_offset: f64,
}

impl Default for Mapping {
    fn default() -> Self {
        Mapping {
            scale: 1.0,
            offset: 0.0,
            pbrt_offset: 0.0,
        }
    }
}

impl Mapping {
    fn is_identity(&self) -> bool {
        *self == Mapping::default()
    }
    fn apply(&self, v: f32) -> f32 {
        ((v as f64 - self.pbrt_offset) * self.scale + self.offset) as f32
    }
}

/// Where one channel comes from.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelSource {
    /// The channel's name in the dataset (`density`, `temperature`, `Na`, …).
    pub name: String,
    /// The file (may hold a frame pattern, `fire_####.vdb`).
    pub file: PathBuf,
    /// The grid inside a VDB/NanoVDB file; defaults to `name`.
    pub grid: Option<String>,
    /// The artist mapping.
    pub mapping: Mapping,
}

impl ChannelSource {
    /// A channel `name` read from `file` (grid of the same name), unmapped.
    pub fn new(name: &str, file: impl Into<PathBuf>) -> Self {
        ChannelSource {
            name: name.to_string(),
            file: file.into(),
            grid: None,
            mapping: Mapping::default(),
        }
    }
    fn grid_name(&self) -> &str {
        self.grid.as_deref().unwrap_or(&self.name)
    }
}

/// How files are read.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadOptions {
    /// The format; `None` guesses from the extension.
    pub format: Option<Format>,
    /// Dense ASCII value order.
    pub order: AxisOrder,
    /// Raw coordinate convention.
    pub raw_coords: RawCoords,
    /// Raw value channel.
    pub raw_value: RawValue,
    /// Dims of a headerless raw file.
    pub raw_dims: [usize; 3],
    /// NaN/infinity policy.
    pub nonfinite: Policy,
    /// Negative-value policy.
    pub negative: Policy,
    /// Refuse grids larger than this many bytes (per channel).
    pub max_bytes: u64,
    /// Frame number for patterned file names.
    pub frame: Option<i64>,
    /// Medium-space bounds for formats without a transform (ASCII, raw); pbrt's default is the unit cube.
    pub bounds: Option<[DVec3; 2]>,
}

impl Default for LoadOptions {
    fn default() -> Self {
        LoadOptions {
            format: None,
            order: AxisOrder::XFastest,
            raw_coords: RawCoords::Thesis,
            raw_value: RawValue::Red,
            raw_dims: [256; 3],
            nonfinite: Policy::Error,
            negative: Policy::Error,
            max_bytes: 8 << 30,
            frame: None,
            bounds: None,
        }
    }
}

/// `f` over `items`, one thread per item (a dataset has a handful of grids; each is independent work of tens
/// of milliseconds or more), results in order; one after the other when the build's budget is one thread.
pub(crate) fn par_map<T: Send, R: Send>(items: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
    if items.len() <= 1 || crate::par::threads(2) == 1 {
        return items.into_iter().map(f).collect();
    }
    let f = &f;
    std::thread::scope(|s| {
        let handles: Vec<_> = items.into_iter().map(|x| s.spawn(move || f(x))).collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// What a reader hands back for one grid, before policies and mapping.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Loaded {
    pub dims: [usize; 3],
    pub data: Vec<f32>,
    /// Medium-space bounds from the file's own transform, if it has one.
    pub bounds: Option<[DVec3; 2]>,
}

/// Allocates an nx·ny·nz grid filled with `fill`, refusing overflowing or over-cap sizes first.
pub(crate) fn alloc_grid(
    file: &str,
    dims: [usize; 3],
    max_bytes: u64,
    fill: f32,
) -> Result<Vec<f32>, Error> {
    let n = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d as u64));
    let bytes = n.and_then(|n| n.checked_mul(4));
    match bytes {
        Some(b) if b <= max_bytes && b > 0 => Ok(vec![fill; n.unwrap_or(0) as usize]),
        _ => Err(Error::TooLarge {
            file: file.to_string(),
            what: format!("a {}×{}×{} grid of f32", dims[0], dims[1], dims[2]),
            bytes: bytes.unwrap_or(u64::MAX),
            cap: max_bytes,
        }),
    }
}

/// What loading one channel cost and changed.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelReport {
    /// The file it came from (after frame substitution).
    pub file: String,
    /// Bytes of the loaded samples.
    pub bytes: usize,
    /// Wall time to read, decode and validate it, seconds (shared equally by channels of one file).
    pub load_seconds: f64,
    /// NaN/infinite values replaced by 0 under `nonfinite zero`.
    pub replaced_nonfinite: usize,
    /// Negative values replaced by 0 under `negative zero`.
    pub replaced_negative: usize,
}

/// One named channel.
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Its name.
    pub name: String,
    /// Its samples.
    pub grid: Grid,
    /// Statistics after mapping.
    pub stats: GridStats,
    /// Load report.
    pub report: ChannelReport,
}

/// Named channels on one grid over a medium-space box.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    format: Format,
    dims: [usize; 3],
    bounds: [DVec3; 2],
    channels: Vec<Channel>,
    interpolation: Interpolation,
}

/// Replaces the first run of `#` (`fire_####.vdb`) or a `%0Nd` with the zero-padded frame number.
pub fn frame_path(path: &Path, frame: Option<i64>) -> Result<PathBuf, Error> {
    let s = path.to_string_lossy();
    let (start, len, width) = if let Some(start) = s.find('#') {
        let len = s[start..].chars().take_while(|&c| c == '#').count();
        (start, len, len)
    } else if let Some(start) = s.find('%') {
        let rest = &s[start + 1..];
        let digits: String = rest.chars().take_while(|c| c.is_ascii_digit()).collect();
        if rest[digits.len()..].starts_with('d') {
            (
                start,
                digits.len() + 2,
                digits.trim_start_matches('0').parse().unwrap_or(0),
            )
        } else {
            return Ok(path.to_path_buf());
        }
    } else {
        return Ok(path.to_path_buf());
    };
    let Some(frame) = frame else {
        return Err(Error::invalid(
            "dataset",
            "frame",
            "unset",
            format!("a frame number for the pattern in '{s}'"),
        ));
    };
    let num = if frame < 0 {
        format!("-{:0width$}", -frame, width = width)
    } else {
        format!("{frame:0width$}")
    };
    Ok(PathBuf::from(format!(
        "{}{}{}",
        &s[..start],
        num,
        &s[start + len..]
    )))
}

/// The bytes of `path`. A large file is read in parallel, one part per thread at its offset (the copy out of
/// the page cache is bound by one core's memory copy: 27.6 → 20.1 ms, medians of 10, for the 42.5 MB of the 256³
/// campfire on 2 cores).
fn read_file(path: &Path) -> Result<Vec<u8>, Error> {
    let io = |e: std::io::Error| Error::Io {
        file: path.display().to_string(),
        message: e.to_string(),
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileExt;
        /// Below this a single read is as fast.
        const PARALLEL_BYTES: u64 = 8 << 20;
        let f = std::fs::File::open(path).map_err(io)?;
        let len = f.metadata().map_err(io)?.len();
        let threads = crate::par::threads(4);
        if len >= PARALLEL_BYTES && threads > 1 {
            let len = usize::try_from(len).map_err(|_| Error::Io {
                file: path.display().to_string(),
                message: format!("{len} bytes: larger than this machine can address"),
            })?;
            let mut buf = vec![0u8; len];
            let part = len.div_ceil(threads);
            let f = &f;
            let done: Vec<std::io::Result<()>> = std::thread::scope(|s| {
                let jobs: Vec<_> = buf
                    .chunks_mut(part)
                    .enumerate()
                    .map(|(k, chunk)| s.spawn(move || f.read_exact_at(chunk, (k * part) as u64)))
                    .collect();
                jobs.into_iter()
                    .map(|j| {
                        j.join().unwrap_or_else(|_| {
                            Err(std::io::Error::other("a reading thread stopped"))
                        })
                    })
                    .collect()
            });
            for r in done {
                r.map_err(io)?;
            }
            return Ok(buf);
        }
    }
    std::fs::read(path).map_err(io)
}

fn as_text<'a>(file: &str, bytes: &'a [u8]) -> Result<&'a str, Error> {
    std::str::from_utf8(bytes).map_err(|e| {
        Error::format(
            file,
            format!("byte {}", e.valid_up_to()),
            "ASCII text",
            "a byte that is not text (a binary file?)",
        )
    })
}

/// A grid inside a file, as listed by [`list_grids`].
#[derive(Debug, Clone, PartialEq)]
pub struct GridEntry {
    /// Its name (single-grid formats: `density`).
    pub name: String,
    /// Its value type as the file names it.
    pub kind: String,
    /// Whether this component can load it (float grids).
    pub loadable: bool,
}

/// The format `opts` or the extension gives `path`.
pub fn format_of(path: &Path, opts: &LoadOptions) -> Result<Format, Error> {
    opts.format
        .or_else(|| Format::from_extension(path))
        .ok_or_else(|| {
            Error::invalid(
                "dataset",
                "format",
                format!("unset for '{}'", path.display()),
                format!(
                    "a known extension (.vdb .nvdb .raw .raw2 .txt) or 'format' one of {}",
                    Format::NAMES.join(", ")
                ),
            )
        })
}

/// The grids a file holds (after frame substitution). Single-grid formats hold one grid, `density`.
pub fn list_grids(path: &Path, opts: &LoadOptions) -> Result<Vec<GridEntry>, Error> {
    let path = frame_path(path, opts.frame)?;
    let file = path.display().to_string();
    Ok(match format_of(&path, opts)? {
        Format::Vdb => vdb::read_header(&file, &read_file(&path)?)?
            .grids
            .into_iter()
            .map(|g| GridEntry {
                loadable: g.tree_type == "Tree_float_5_4_3" && g.instance_parent_is_empty(),
                kind: g.tree_type.clone() + if g.half { " (half)" } else { "" },
                name: g.name,
            })
            .collect(),
        Format::NanoVdb => nanovdb::grid_names(&file, &read_file(&path)?)?
            .into_iter()
            .map(|(name, float)| GridEntry {
                name,
                kind: if float {
                    "float".into()
                } else {
                    "other".into()
                },
                loadable: float,
            })
            .collect(),
        _ => {
            read_file(&path)?;
            vec![GridEntry {
                name: "density".into(),
                kind: "float".into(),
                loadable: true,
            }]
        }
    })
}

/// Decodes `bytes` of `format` into the grids `names` (single-grid formats: exactly one name).
fn decode(
    format: Format,
    file: &str,
    bytes: &[u8],
    names: &[&str],
    opts: &LoadOptions,
) -> Result<Vec<Loaded>, Error> {
    if !matches!(format, Format::Vdb | Format::NanoVdb) && names.len() != 1 {
        return Err(Error::invalid(
            "dataset",
            "channels",
            format!("{} channels from '{file}'", names.len()),
            format!(
                "one channel per {} file (it holds a single grid)",
                format.name()
            ),
        ));
    }
    Ok(match format {
        Format::Vdb => vdb::read(file, bytes, names, opts.max_bytes)?,
        Format::NanoVdb => nanovdb::read(file, bytes, names, opts.max_bytes)?,
        Format::AsciiDense => vec![ascii::read_dense(
            file,
            as_text(file, bytes)?,
            opts.order,
            opts.max_bytes,
        )?],
        Format::AsciiSparse => vec![ascii::read_sparse(
            file,
            as_text(file, bytes)?,
            opts.max_bytes,
        )?],
        Format::Raw | Format::Raw2 => vec![raw::read(
            file,
            bytes,
            format == Format::Raw2,
            opts.raw_dims,
            opts.raw_coords,
            opts.raw_value,
            opts.max_bytes,
        )?],
        Format::Inline => {
            return Err(Error::invalid(
                "dataset",
                "format",
                "inline",
                "a file format (inline grids come from Dataset::from_inline)",
            ))
        }
    })
}

impl Dataset {
    /// Decodes a file already in memory: channels `names` (grid names, also the channel names) of `format`;
    /// `label` names the data in errors. Hosts that hold files in memory, and the fuzz targets, use this.
    pub fn from_bytes(
        format: Format,
        label: &str,
        bytes: &[u8],
        names: &[&str],
        opts: &LoadOptions,
    ) -> Result<Dataset, Error> {
        if names.is_empty() {
            return Err(Error::invalid(
                "dataset",
                "channels",
                "none",
                "at least one channel to load",
            ));
        }
        let start = Instant::now();
        let grids = decode(format, label, bytes, names, opts)?;
        let seconds = start.elapsed().as_secs_f64() / names.len() as f64;
        let sources: Vec<ChannelSource> =
            names.iter().map(|n| ChannelSource::new(n, label)).collect();
        let loaded = grids
            .into_iter()
            .enumerate()
            .map(|(i, g)| (i, g, label.to_string(), seconds, format))
            .collect();
        Self::assemble(&sources, loaded, opts)
    }

    /// Loads the channels of `sources` (files grouped so each is read once).
    pub fn load(sources: &[ChannelSource], opts: &LoadOptions) -> Result<Dataset, Error> {
        if sources.is_empty() {
            return Err(Error::invalid(
                "dataset",
                "channels",
                "none",
                "at least one channel to load",
            ));
        }
        let mut loaded: Vec<(usize, Loaded, String, f64, Format)> = Vec::new();
        let mut done = vec![false; sources.len()];
        for (i, src) in sources.iter().enumerate() {
            if done[i] {
                continue;
            }
            let path = frame_path(&src.file, opts.frame)?;
            let file = path.display().to_string();
            let format = format_of(&path, opts)?;
            // All channels from this same file.
            let group: Vec<usize> = (i..sources.len())
                .filter(|&j| !done[j] && sources[j].file == src.file)
                .collect();
            let start = Instant::now();
            let bytes = read_file(&path)?;
            let names: Vec<&str> = group.iter().map(|&j| sources[j].grid_name()).collect();
            let grids = decode(format, &file, &bytes, &names, opts)?;
            let seconds = start.elapsed().as_secs_f64() / group.len() as f64;
            for (j, g) in group.into_iter().zip(grids) {
                done[j] = true;
                loaded.push((j, g, file.clone(), seconds, format));
            }
        }
        loaded.sort_by_key(|l| l.0);
        Self::assemble(sources, loaded, opts)
    }

    /// A dataset from pbrt-v4 inline arrays (`uniformgrid`: `nx ny nz`, `p0`, `p1`, and float arrays such as
    /// `density`, `temperature`, `Lescale`), each of length nx·ny·nz, x fastest.
    pub fn from_inline(
        dims: [usize; 3],
        p0: DVec3,
        p1: DVec3,
        arrays: &[(&str, &[f32])],
        opts: &LoadOptions,
    ) -> Result<Dataset, Error> {
        let n = dims
            .iter()
            .try_fold(1usize, |a, &d| a.checked_mul(d))
            .filter(|&n| n > 0);
        let Some(n) = n else {
            return Err(Error::invalid(
                "dataset",
                "nx ny nz",
                format!("{} {} {}", dims[0], dims[1], dims[2]),
                "positive counts whose product fits in memory",
            ));
        };
        let mut loaded = Vec::new();
        let mut sources = Vec::new();
        for (i, (name, values)) in arrays.iter().enumerate() {
            if values.len() != n {
                return Err(Error::invalid(
                    "dataset",
                    *name,
                    format!("{} values", values.len()),
                    format!(
                        "nx·ny·nz = {}·{}·{} = {n} values",
                        dims[0], dims[1], dims[2]
                    ),
                ));
            }
            let data = alloc_grid("inline", dims, opts.max_bytes, 0.0).map(|_| values.to_vec())?;
            loaded.push((
                i,
                Loaded {
                    dims,
                    data,
                    bounds: Some([p0, p1]),
                },
                "inline".to_string(),
                0.0,
                Format::Inline,
            ));
            sources.push(ChannelSource::new(name, "inline"));
        }
        Self::assemble(&sources, loaded, opts)
    }

    fn assemble(
        sources: &[ChannelSource],
        loaded: Vec<(usize, Loaded, String, f64, Format)>,
        opts: &LoadOptions,
    ) -> Result<Dataset, Error> {
        let first = &loaded[0];
        let dims = first.1.dims;
        let bounds = opts
            .bounds
            .or(first.1.bounds)
            .unwrap_or([DVec3::ZERO, DVec3::ONE]);
        if !(bounds[0].is_finite() && bounds[1].is_finite() && bounds[0].cmplt(bounds[1]).all()) {
            return Err(Error::invalid(
                "dataset",
                "p0 p1",
                format!("{} {}", bounds[0], bounds[1]),
                "finite corners with p0 < p1 on every axis",
            ));
        }
        let (first_idx, first_bounds, format) = (first.0, first.1.bounds, first.4);
        // Checks, policies and statistics per channel, in parallel.
        let channels = par_map(loaded, |(idx, l, file, seconds, _)| {
            let src = &sources[idx];
            if l.dims != dims {
                return Err(Error::invalid(
                    "dataset",
                    format!("{} dims", src.name),
                    format!("{}×{}×{} in {file}", l.dims[0], l.dims[1], l.dims[2]),
                    format!(
                        "the {}×{}×{} of channel '{}' (all channels share one grid)",
                        dims[0], dims[1], dims[2], sources[first_idx].name
                    ),
                ));
            }
            if opts.bounds.is_none() && l.bounds.is_some() && l.bounds != first_bounds {
                return Err(Error::invalid(
                    "dataset",
                    format!("{} bounds", src.name),
                    format!("{:?} in {file}", l.bounds.unwrap_or_default()),
                    format!(
                        "the bounds {bounds:?} of channel '{}' (all channels share one grid)",
                        sources[first_idx].name
                    ),
                ));
            }
            let mut grid = Grid::new(l.dims, l.data).ok_or_else(|| {
                Error::invalid("dataset", &src.name, "an empty grid", "at least one voxel")
            })?;
            let (replaced_nonfinite, replaced_negative, stats) =
                apply_policies(&mut grid, &src.name, &file, &src.mapping, opts)?;
            let bytes = grid.bytes();
            Ok(Channel {
                name: src.name.clone(),
                grid,
                stats,
                report: ChannelReport {
                    file,
                    bytes,
                    load_seconds: seconds,
                    replaced_nonfinite,
                    replaced_negative,
                },
            })
        })
        .into_iter()
        .collect::<Result<Vec<_>, Error>>()?;
        Ok(Dataset {
            format,
            dims,
            bounds,
            channels,
            interpolation: Interpolation::Trilinear,
        })
    }

    /// The format the first channel came from.
    pub fn format(&self) -> Format {
        self.format
    }
    /// Grid resolution (nx, ny, nz).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// Medium-space bounds [p0, p1].
    pub fn bounds(&self) -> [DVec3; 2] {
        self.bounds
    }
    /// The channels, in the order asked for.
    pub fn channels(&self) -> &[Channel] {
        &self.channels
    }
    /// The channel named `name`.
    pub fn channel(&self, name: &str) -> Option<&Channel> {
        self.channels.iter().find(|c| c.name == name)
    }
    /// Sets the interpolation used by [`Dataset::sample`].
    pub fn with_interpolation(mut self, interp: Interpolation) -> Self {
        self.interpolation = interp;
        self
    }
    /// Bytes of all loaded samples.
    pub fn bytes(&self) -> usize {
        self.channels.iter().map(|c| c.report.bytes).sum()
    }

    /// The unit-cube coordinates of medium-space point `p`.
    #[inline]
    pub fn to_unit(&self, p: DVec3) -> [f64; 3] {
        ((p - self.bounds[0]) / (self.bounds[1] - self.bounds[0])).to_array()
    }

    /// The interpolation stencil of medium-space point `p`, shared by every channel (`None` outside).
    #[inline]
    pub fn stencil(&self, p: DVec3) -> Option<crate::grid::Stencil> {
        crate::grid::Stencil::new(self.dims, self.to_unit(p), self.interpolation)
    }
    /// The stencil of `p`, continuing `margin` voxels beyond the bounds (see [`crate::grid::Stencil::with_margin`]).
    #[inline]
    pub fn stencil_with_margin(&self, p: DVec3, margin: f64) -> Option<crate::grid::Stencil> {
        crate::grid::Stencil::with_margin(self.dims, self.to_unit(p), self.interpolation, margin)
    }
    /// The interpolation used by [`Dataset::sample`].
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }
    /// Medium-space size of one voxel on each axis.
    pub fn voxel_size(&self) -> DVec3 {
        (self.bounds[1] - self.bounds[0])
            / DVec3::new(
                self.dims[0] as f64,
                self.dims[1] as f64,
                self.dims[2] as f64,
            )
    }

    /// Channel `index` at medium-space point `p` (zero outside the bounds).
    #[inline]
    pub fn sample(&self, index: usize, p: DVec3) -> f32 {
        self.channels[index]
            .grid
            .lookup(self.to_unit(p), self.interpolation)
    }
}

/// Applies the mapping and the NaN/negative policies; returns the replacement counts and the statistics of
/// the result (gathered in the same pass over the grid).
fn apply_policies(
    grid: &mut Grid,
    name: &str,
    file: &str,
    mapping: &Mapping,
    opts: &LoadOptions,
) -> Result<(usize, usize, crate::grid::GridStats), Error> {
    let dims = grid.dims();
    let voxel = |n: usize| {
        let (i, rest) = (n % dims[0], n / dims[0]);
        format!(
            "channel '{name}', voxel ({}, {}, {})",
            i,
            rest % dims[1],
            rest / dims[1]
        )
    };
    let identity = mapping.is_identity();
    // Negative values are refused only where they are unphysical; other grids (Mantaflow's `shadow` is −1
    // everywhere) keep what the file says.
    let physical =
        name == "density" || name == "temperature" || crate::species::symbols().any(|s| s == name);
    let (mut nonfinite, mut negative) = (0, 0);
    // Eight voxels at a time are tested at once (a loop the compiler vectorises); only a group holding a
    // non-finite or negative value, or any group under a mapping, goes through the voxel-by-voxel rules.
    const L: usize = crate::grid::STATS_LANES;
    let mut stats = crate::grid::StatsAcc::new();
    for (g, group) in grid.data_mut().chunks_mut(L).enumerate() {
        if let (true, Ok(whole)) = (identity, <&[f32; L]>::try_from(&*group)) {
            let mut clean = true;
            for v in whole.iter() {
                clean &= v.is_finite() & (*v >= 0.0 || !physical);
            }
            if clean {
                stats.add_lanes(whole);
                continue;
            }
        }
        for (k, v) in group.iter_mut().enumerate() {
            let n = g * L + k;
            if !v.is_finite() {
                match opts.nonfinite {
                    Policy::Error => {
                        return Err(Error::format(
                            file,
                            voxel(n),
                            "a finite value (or 'nonfinite' \"zero\")",
                            *v,
                        ));
                    }
                    Policy::Zero => {
                        *v = 0.0;
                        nonfinite += 1;
                    }
                }
            }
            // The policy judges the data as the file has it…
            if *v < 0.0 && physical {
                match opts.negative {
                    Policy::Error => {
                        return Err(Error::format(
                            file,
                            voxel(n),
                            "a value >= 0 (or 'negative' \"zero\")",
                            *v,
                        ));
                    }
                    Policy::Zero => {
                        *v = 0.0;
                        negative += 1;
                    }
                }
            }
            if !identity {
                *v = mapping.apply(*v);
                if !v.is_finite() {
                    return Err(Error::format(
                        file,
                        voxel(n),
                        "a finite value after the mapping (scale/offset)",
                        *v,
                    ));
                }
                // …while values the mapping moves below zero are a cutoff doing its job (pbrt-v4's
                // `temperaturecutoff`: colder voxels do not emit), clamped to 0.
                if *v < 0.0 && physical {
                    *v = 0.0;
                }
            }
            stats.add(*v);
        }
    }
    Ok((nonfinite, negative, stats.finish()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_file_read_in_parts_is_the_file() {
        // Above the parallel threshold, with a length that does not split evenly: every byte where it was.
        let n = (9 << 20) + 12_345;
        let bytes: Vec<u8> = (0..n).map(|i| (i * 7 + i / 251) as u8).collect();
        let path = tmp("large.bin", &bytes);
        assert_eq!(read_file(&path).expect("readable"), bytes);
        let e = read_file(&path.with_extension("missing"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("large.missing"), "{e}");
    }

    fn tmp(name: &str, content: &[u8]) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("firemedium-ds-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, content).unwrap();
        p
    }

    #[test]
    fn frame_patterns() {
        let p = |s: &str, f| frame_path(Path::new(s), f).map(|p| p.display().to_string());
        assert_eq!(p("fire_####.vdb", Some(7)).unwrap(), "fire_0007.vdb");
        assert_eq!(p("fire_##.vdb", Some(123)).unwrap(), "fire_123.vdb");
        assert_eq!(p("fire_%04d.vdb", Some(42)).unwrap(), "fire_0042.vdb");
        assert_eq!(p("fire_%d.vdb", Some(42)).unwrap(), "fire_42.vdb");
        assert_eq!(p("fire.vdb", Some(42)).unwrap(), "fire.vdb");
        assert_eq!(p("100%.vdb", Some(1)).unwrap(), "100%.vdb");
        assert!(p("fire_####.vdb", None)
            .unwrap_err()
            .to_string()
            .contains("frame"));
    }

    #[test]
    fn frame_sequence_loads_the_right_file() {
        tmp("seq_0001.txt", b"1 1 1\n1.5\n");
        let p2 = tmp("seq_0002.txt", b"1 1 1\n2.5\n");
        let pattern = p2.parent().unwrap().join("seq_####.txt");
        for (f, want) in [(1, 1.5), (2, 2.5)] {
            let ds = Dataset::load(
                &[ChannelSource::new("density", &pattern)],
                &LoadOptions {
                    frame: Some(f),
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(ds.channels()[0].grid.data(), &[want]);
            assert!(ds.channels()[0]
                .report
                .file
                .ends_with(&format!("seq_000{f}.txt")));
        }
        let e = Dataset::load(
            &[ChannelSource::new("density", &pattern)],
            &LoadOptions {
                frame: Some(3),
                ..Default::default()
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("seq_0003.txt: cannot read"), "{e}");
    }

    #[test]
    fn two_ascii_channels_share_a_grid_and_map() {
        let d = tmp("d.txt", b"2 1 1\n0.5 1\n");
        let t = tmp("t.txt", b"2 1 1\n1.5 2\n");
        let mut temp = ChannelSource::new("temperature", &t);
        temp.mapping = Mapping {
            scale: 1000.0,
            offset: 0.0,
            pbrt_offset: 0.5,
        };
        let opts = LoadOptions {
            bounds: Some([DVec3::new(-1.0, 0.0, 0.0), DVec3::new(1.0, 1.0, 1.0)]),
            ..Default::default()
        };
        let ds = Dataset::load(&[ChannelSource::new("density", &d), temp], &opts).unwrap();
        assert_eq!(ds.dims(), [2, 1, 1]);
        assert_eq!(
            ds.channel("temperature").unwrap().grid.data(),
            &[1000.0, 1500.0]
        );
        // The centre of voxel 1 is at x = 0.5 in medium space.
        assert_eq!(ds.sample(0, DVec3::new(0.5, 0.5, 0.5)), 1.0);
        assert_eq!(ds.sample(1, DVec3::new(-0.5, 0.5, 0.5)), 1000.0);
        assert_eq!(ds.sample(0, DVec3::new(2.0, 0.5, 0.5)), 0.0);
        let r = &ds.channels()[0].report;
        assert_eq!(r.bytes, 8);
        assert!(r.load_seconds >= 0.0);
        // Mismatched dims are an error naming both.
        let t3 = tmp("t3.txt", b"3 1 1\n1 2 3\n");
        let e = Dataset::load(
            &[
                ChannelSource::new("density", &d),
                ChannelSource::new("temperature", &t3),
            ],
            &opts,
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("3×1×1") && e.contains("2×1×1") && e.contains("'density'"),
            "{e}"
        );
    }

    #[test]
    fn nan_and_negative_policies() {
        let f = tmp("nan.txt", b"2 1 1\nnan -3\n");
        let e = Dataset::load(
            &[ChannelSource::new("density", &f)],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("nan.txt") && e.contains("voxel (0, 0, 0)") && e.contains("NaN"),
            "{e}"
        );
        let opts = LoadOptions {
            nonfinite: Policy::Zero,
            ..Default::default()
        };
        let e = Dataset::load(&[ChannelSource::new("density", &f)], &opts)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("voxel (1, 0, 0)") && e.contains("-3") && e.contains(">= 0"),
            "{e}"
        );
        let opts = LoadOptions {
            nonfinite: Policy::Zero,
            negative: Policy::Zero,
            ..Default::default()
        };
        let ds = Dataset::load(&[ChannelSource::new("density", &f)], &opts).unwrap();
        assert_eq!(ds.channels()[0].grid.data(), &[0.0, 0.0]);
        assert_eq!(
            (
                ds.channels()[0].report.replaced_nonfinite,
                ds.channels()[0].report.replaced_negative
            ),
            (1, 1)
        );
        let inf = tmp("inf.txt", b"1 1 1\ninf\n");
        assert!(Dataset::load(
            &[ChannelSource::new("density", &inf)],
            &LoadOptions::default()
        )
        .unwrap_err()
        .to_string()
        .contains("inf"));
    }

    #[test]
    fn inline_arrays_like_pbrt() {
        let dens = [0.0f32, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0];
        let ds = Dataset::from_inline(
            [2, 2, 2],
            DVec3::splat(-1.0),
            DVec3::splat(1.0),
            &[("density", &dens)],
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(ds.format(), Format::Inline);
        assert_eq!(ds.sample(0, DVec3::new(0.5, 0.5, 0.5)), 7.0);
        assert_eq!(ds.sample(0, DVec3::new(-0.5, -0.5, -0.5)), 0.0);
        assert_eq!(ds.sample(0, DVec3::ZERO), 3.5);
        let e = Dataset::from_inline(
            [2, 2, 3],
            DVec3::ZERO,
            DVec3::ONE,
            &[("density", &dens)],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("8 values") && e.contains("2·2·3 = 12"), "{e}");
        let e = Dataset::from_inline(
            [2, 2, 2],
            DVec3::ONE,
            DVec3::ZERO,
            &[("density", &dens)],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("p0 < p1"), "{e}");
    }

    #[test]
    fn raw_files_through_the_public_loader() {
        // raw2: dims 4×3×2; voxel (3, 2, 1) 0-based is stored 1-based x, z, y = (4, 2, 3).
        let f = tmp(
            "fire.raw2",
            &raw::encode(Some([4, 3, 2]), &[([4, 2, 3], [64.0, 200.0, 0.0, 1.0])]),
        );
        let ds = Dataset::load(
            &[ChannelSource::new("density", &f)],
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!((ds.format(), ds.dims()), (Format::Raw2, [4, 3, 2]));
        assert_eq!(ds.channels()[0].grid.at(3, 2, 1), 0.25);
        let opts = LoadOptions {
            raw_value: RawValue::MaxRgb,
            ..Default::default()
        };
        assert_eq!(
            Dataset::load(&[ChannelSource::new("density", &f)], &opts)
                .unwrap()
                .channels()[0]
                .grid
                .at(3, 2, 1),
            200.0 / 256.0
        );
        // Headerless raw: the grid is raw_dims (256³ by default).
        let f = tmp(
            "fire.raw",
            &raw::encode(None, &[([1, 1, 1], [256.0, 0.0, 0.0, 1.0])]),
        );
        let opts = LoadOptions {
            raw_dims: [8, 8, 8],
            ..Default::default()
        };
        let ds = Dataset::load(&[ChannelSource::new("density", &f)], &opts).unwrap();
        assert_eq!(
            (ds.dims(), ds.channels()[0].grid.at(0, 0, 0)),
            ([8, 8, 8], 1.0)
        );
        let ds = Dataset::load(
            &[ChannelSource::new("density", &f)],
            &LoadOptions::default(),
        )
        .unwrap();
        assert_eq!(ds.dims(), [256, 256, 256]);
        // Two channels from one single-grid file is an error.
        let e = Dataset::load(
            &[
                ChannelSource::new("density", &f),
                ChannelSource::new("temperature", &f),
            ],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("one channel per raw file"), "{e}");
    }

    #[test]
    fn missing_file_unknown_extension_and_binary_as_text() {
        let e = Dataset::load(
            &[ChannelSource::new("density", "/no/such/file.vdb")],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("/no/such/file.vdb: cannot read"), "{e}");
        let e = Dataset::load(
            &[ChannelSource::new("density", "fire.xyz")],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("format") && e.contains("fire.xyz"), "{e}");
        let b = tmp("bin.txt", &[b'1', b' ', 0xff, 0xfe]);
        let e = Dataset::load(
            &[ChannelSource::new("density", &b)],
            &LoadOptions::default(),
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("byte 2") && e.contains("not text"), "{e}");
        assert!(Format::from_name("obj")
            .unwrap_err()
            .to_string()
            .contains("ascii, asciisparse"));
    }
}
