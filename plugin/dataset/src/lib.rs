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

pub mod alloc;
mod ascii;
mod compress;
pub mod convention;
mod cursor;
mod error;
mod files;
pub mod grid;
pub mod nanovdb;
mod options;
pub mod par;
pub mod particles;
pub mod raw;
mod sparse;
mod text;
pub mod vdb;

pub use sparse::{missing_grid, Transform};

use crate::grid::{Grid, GridStats, Interpolation};
use glam::DVec3;
use std::path::{Path, PathBuf};
use std::time::Instant;

use cursor::Bytes;
pub use error::{short, Error};
pub use files::{as_text, open_regular, read_file};
pub use files::{creator_of, format_of, frame_path, list_grids, GridEntry};
pub use options::{AxisOrder, ChannelSource, Format, LoadOptions, Mapping, Policy};

/// Every float grid `entries` lists for `path` (as [`list_grids`] gives them) loaded on one lattice — the union of
/// their bricks; `Ok(None)` when the file holds none (a file of vector grids only).
pub fn load_float_grids(
    path: &std::path::Path,
    entries: &[GridEntry],
    opts: &LoadOptions,
) -> Result<Option<Dataset>, Error> {
    let sources: Vec<ChannelSource> = entries
        .iter()
        .filter(|g| g.loadable)
        .map(|g| ChannelSource::new(&g.name, path))
        .collect();
    if sources.is_empty() {
        return Ok(None);
    }
    Dataset::load(&sources, opts).map(Some)
}

pub use convention::HOUDINI_KELVIN;
pub use raw::{RawCoords, RawValue};

/// `f` over `items`, one thread per item (a dataset has a handful of grids; each is independent work of tens
/// of milliseconds or more), results in order; one after the other when the build's budget is one thread.
pub fn par_map<T: Send, R: Send>(items: Vec<T>, f: impl Fn(T) -> R + Sync) -> Vec<R> {
    if items.len() <= 1 || crate::par::threads(2) == 1 {
        return items.into_iter().map(f).collect();
    }
    let f = &f;
    crate::par::scope(|s| {
        let handles: Vec<_> = items.into_iter().map(|x| s.spawn(move || f(x))).collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// What a reader hands back for one grid, before policies and mapping.
#[derive(Debug, Clone, PartialEq)]
pub struct Loaded {
    pub dims: [usize; 3],
    /// Dense samples, x fastest (empty when `bricks` holds them).
    pub data: Vec<f32>,
    /// The samples as bricks (sparse formats), sharing one topology with the file's other grids.
    pub bricks: Option<Grid>,
    /// Medium-space bounds from the file's own transform, if it has one.
    pub bounds: Option<[DVec3; 2]>,
}

/// Allocates an nx·ny·nz grid filled with `fill`, refusing overflowing or over-cap sizes first.
pub fn alloc_grid(
    file: &str,
    dims: [usize; 3],
    max_bytes: u64,
    fill: f32,
) -> Result<Vec<f32>, Error> {
    let n = dims.iter().try_fold(1u64, |a, &d| a.checked_mul(d as u64));
    let bytes = n.and_then(|n| n.checked_mul(4));
    match bytes {
        Some(b) if b <= max_bytes && b > 0 => {
            // Fallible: a grid within the cap that the allocator still refuses is an error, not an abort of the
            // host that loaded the plugin.
            crate::alloc::filled(n.unwrap_or(0) as usize, fill).ok_or_else(|| Error::TooLarge {
                file: file.to_string(),
                what: format!(
                    "a {}×{}×{} grid of f32 (the allocator refused it)",
                    dims[0], dims[1], dims[2]
                ),
                bytes: b,
                cap: max_bytes,
            })
        }
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
    /// The bricks the channels store (shared by all).
    topology: std::sync::Arc<crate::grid::Topology>,
    bounds: [DVec3; 2],
    channels: Vec<Channel>,
    interpolation: Interpolation,
}

/// Decodes `src` of `format` into the grids `names` (single-grid formats: exactly one name).
fn decode(
    format: Format,
    file: &str,
    src: Bytes,
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
        Format::Vdb => vdb::read(file, src, names, opts.max_bytes)?,
        Format::NanoVdb => nanovdb::read(file, src, names, opts.max_bytes)?,
        Format::AsciiDense => vec![ascii::read_dense(
            file,
            as_text(file, &src.all(file)?)?,
            opts.order,
            opts.max_bytes,
        )?],
        Format::AsciiSparse => vec![ascii::read_sparse(
            file,
            as_text(file, &src.all(file)?)?,
            opts.max_bytes,
        )?],
        Format::Raw | Format::Raw2 => vec![raw::read(
            file,
            &src.all(file)?,
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
        let grids = decode(format, label, Bytes::Slice(bytes), names, opts)?;
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
            // Sparse files are read by offset, only the grids named; the others whole, in parallel parts.
            let names: Vec<&str> = group.iter().map(|&j| sources[j].grid_name()).collect();
            let grids = if let Format::Vdb | Format::NanoVdb = format {
                let (f, len) = files::open_regular(&path)?;
                decode(format, &file, Bytes::File { file: &f, len }, &names, opts)?
            } else {
                let bytes = read_file(&path)?;
                decode(format, &file, Bytes::Slice(&bytes), &names, opts)?
            };
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
            // (Dense, then bricked with the other channels: the array already lives in the host's parameters,
            // and a small grid is smaller dense than as 2 KB bricks.)
            let data = alloc_grid("inline", dims, opts.max_bytes, 0.0).map(|_| values.to_vec())?;
            loaded.push((
                i,
                Loaded {
                    dims,
                    data,
                    bricks: None,
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

    /// A dataset from grids already in bricks (`grids`: each channel's name and grid, every grid on one
    /// topology), over the box `p0`–`p1`: the samples are checked as a file's are, and nothing is copied.
    pub fn from_grids(
        p0: DVec3,
        p1: DVec3,
        grids: Vec<(&str, Grid)>,
        opts: &LoadOptions,
    ) -> Result<Dataset, Error> {
        let mut loaded = Vec::new();
        let mut sources = Vec::new();
        let first = grids.first().map(|(_, g)| g.topology().clone());
        for (i, (name, grid)) in grids.into_iter().enumerate() {
            if !first
                .as_ref()
                .is_some_and(|t| std::sync::Arc::ptr_eq(t, grid.topology()))
            {
                return Err(Error::invalid(
                    "dataset",
                    name,
                    "a grid on a topology of its own",
                    "the first channel's topology (all channels share one)",
                ));
            }
            loaded.push((
                i,
                Loaded {
                    dims: grid.dims(),
                    data: Vec::new(),
                    bricks: Some(grid),
                    bounds: Some([p0, p1]),
                },
                "inline".to_string(),
                0.0,
                Format::Inline,
            ));
            sources.push(ChannelSource::new(name, "inline"));
        }
        if loaded.is_empty() {
            return Err(Error::invalid(
                "dataset",
                "channels",
                "none",
                "at least one grid",
            ));
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
            let v = |p: DVec3| {
                let c = p.to_array().map(crate::short);
                format!("({}, {}, {})", c[0], c[1], c[2])
            };
            let shown = format!("{} to {}", v(bounds[0]), v(bounds[1]));
            // From the file's own transform (a voxel size of 0, 1e300, NaN…): name the file.
            if opts.bounds.is_none() && first.1.bounds.is_some() && first.4 != Format::Inline {
                return Err(Error::format(
                    &first.2,
                    "the grid's transform (voxel size and offset)",
                    "a box with finite corners and a positive size on every axis",
                    shown,
                ));
            }
            return Err(Error::invalid(
                "dataset",
                "p0 p1",
                shown,
                "finite corners with p0 < p1 on every axis",
            ));
        }
        let (first_idx, first_bounds, format) = (first.0, first.1.bounds, first.4);
        // Checks and policies per channel, in parallel, on the samples as loaded (dense or bricks).
        let checked = par_map(loaded, |(idx, mut l, file, seconds, _)| {
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
            let (nonfinite, negative, stats) = match &mut l.bricks {
                Some(g) => {
                    let topo = g.topology().clone();
                    let voxel = |n: usize| match topo.voxel_of(n) {
                        Some([i, j, k]) => format!("channel '{}', voxel ({i}, {j}, {k})", src.name),
                        None => format!("channel '{}', its background", src.name),
                    };
                    let (a, b, _) = apply_policies(
                        g.values_mut(),
                        &voxel,
                        &src.name,
                        &file,
                        &src.mapping,
                        opts,
                    )?;
                    (a, b, None)
                }
                None => {
                    if l.data.is_empty() {
                        return Err(Error::invalid(
                            "dataset",
                            &src.name,
                            "an empty grid",
                            "at least one voxel",
                        ));
                    }
                    let voxel = |n: usize| {
                        let (i, rest) = (n % dims[0], n / dims[0]);
                        format!(
                            "channel '{}', voxel ({}, {}, {})",
                            src.name,
                            i,
                            rest % dims[1],
                            rest / dims[1]
                        )
                    };
                    let (a, b, st) =
                        apply_policies(&mut l.data, &voxel, &src.name, &file, &src.mapping, opts)?;
                    (a, b, Some(st))
                }
            };
            Ok((idx, l, file, seconds, nonfinite, negative, stats))
        })
        .into_iter()
        .collect::<Result<Vec<_>, Error>>()?;
        let topology = union_topology(
            &checked.iter().map(|c| &c.1).collect::<Vec<_>>(),
            dims,
            opts.max_bytes,
        )?;
        // The grids on the shared topology (dense samples copied brick by brick, bricks re-homed when their
        // file's topology is not the union), with their statistics.
        let channels = par_map(
            checked,
            |(idx, l, file, seconds, nonfinite, negative, stats)| {
                let src = &sources[idx];
                let refused = || Error::TooLarge {
                    file: file.clone(),
                    what: format!(
                        "channel '{}': {} bricks of 8³ f32",
                        src.name,
                        topology.active_bricks()
                    ),
                    bytes: topology.values_len() as u64 * 4,
                    cap: opts.max_bytes,
                };
                let grid = match l.bricks {
                    Some(g) if std::sync::Arc::ptr_eq(g.topology(), &topology) => g,
                    Some(g) => g.rehome(topology.clone()).ok_or_else(refused)?,
                    None => Grid::from_dense(topology.clone(), &l.data, 0.0).ok_or_else(refused)?,
                };
                let stats = stats.unwrap_or_else(|| grid.stats());
                let bytes = grid.bytes();
                Ok(Channel {
                    name: src.name.clone(),
                    grid,
                    stats,
                    report: ChannelReport {
                        file,
                        bytes,
                        load_seconds: seconds,
                        replaced_nonfinite: nonfinite,
                        replaced_negative: negative,
                    },
                })
            },
        )
        .into_iter()
        .collect::<Result<Vec<_>, Error>>()?;
        Ok(Dataset {
            format,
            dims,
            topology,
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
    /// Multiplies channel `index`'s values by `k` in place and updates its statistics (a unit found once the
    /// grid was read); `None` when there is no such channel.
    pub fn scale_channel(&mut self, index: usize, k: f32) -> Option<()> {
        let c = self.channels.get_mut(index)?;
        c.grid.values_mut().iter_mut().for_each(|v| *v *= k);
        c.stats = c.grid.stats();
        Some(())
    }
    /// Sets the interpolation used by [`Dataset::sample`].
    pub fn with_interpolation(mut self, interp: Interpolation) -> Self {
        self.interpolation = interp;
        self
    }
    /// Bytes of all loaded samples and their brick table.
    pub fn bytes(&self) -> usize {
        self.channels.iter().map(|c| c.report.bytes).sum::<usize>() + self.topology.bytes()
    }
    /// The bricks the channels store.
    pub fn topology(&self) -> &std::sync::Arc<crate::grid::Topology> {
        &self.topology
    }

    /// The unit-cube coordinates of medium-space point `p`.
    #[inline]
    pub fn to_unit(&self, p: DVec3) -> [f64; 3] {
        ((p - self.bounds[0]) / (self.bounds[1] - self.bounds[0])).to_array()
    }

    /// The interpolation stencil of medium-space point `p`, shared by every channel (`None` outside).
    #[inline]
    pub fn stencil(&self, p: DVec3) -> Option<crate::grid::Stencil> {
        crate::grid::Stencil::new(&self.topology, self.to_unit(p), self.interpolation)
    }
    /// The stencil of `p`, continuing `margin` voxels beyond the bounds (see [`crate::grid::Stencil::with_margin`]).
    #[inline]
    pub fn stencil_with_margin(&self, p: DVec3, margin: f64) -> Option<crate::grid::Stencil> {
        crate::grid::Stencil::with_margin(
            &self.topology,
            self.to_unit(p),
            self.interpolation,
            margin,
        )
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

/// The bricks any channel holds: a dense channel's where it is non-zero, a sparse one's where its file stored
/// them (one file's grids share theirs, which is then the union as it is). The table is checked against the
/// cap first.
fn union_topology(
    loaded: &[&Loaded],
    dims: [usize; 3],
    max_bytes: u64,
) -> Result<std::sync::Arc<crate::grid::Topology>, Error> {
    use crate::grid::Topology;
    let sparse: Vec<&Grid> = loaded.iter().filter_map(|l| l.bricks.as_ref()).collect();
    if sparse.len() == loaded.len()
        && sparse
            .iter()
            .all(|g| std::sync::Arc::ptr_eq(g.topology(), sparse[0].topology()))
    {
        return Ok(sparse[0].topology().clone());
    }
    let table = Topology::table_bytes(dims).unwrap_or(u64::MAX);
    let too_large = || Error::TooLarge {
        file: "dataset".to_string(),
        what: format!(
            "the brick table of a {}×{}×{} grid",
            dims[0], dims[1], dims[2]
        ),
        bytes: table,
        cap: max_bytes,
    };
    if table > max_bytes {
        return Err(too_large());
    }
    // Bricks aligned as the first sparse grid's are (its file's leaves), else at sample 0.
    let off = sparse.first().map_or([0; 3], |g| g.topology().offset());
    let probe = Topology::build_offset(dims, off, |_| false).ok_or_else(too_large)?;
    let [nx, ny, _] = dims;
    Topology::build_offset(dims, off, |b| {
        // The union brick's samples [lo, hi) per axis.
        let span = [0, 1, 2].map(|a| probe.brick_span(b[a], a));
        if (0..3).any(|a| span[a].0 >= span[a].1) {
            return false;
        }
        loaded.iter().any(|l| match &l.bricks {
            Some(g) => {
                let t = g.topology();
                let (blo, bhi) = (
                    t.brick_of([span[0].0, span[1].0, span[2].0]),
                    t.brick_of([span[0].1 - 1, span[1].1 - 1, span[2].1 - 1]),
                );
                (blo[2]..=bhi[2]).any(|z| {
                    (blo[1]..=bhi[1]).any(|y| (blo[0]..=bhi[0]).any(|x| t.slot([x, y, z]) != 0))
                })
            }
            None => (span[2].0..span[2].1).any(|k| {
                (span[1].0..span[1].1).any(|j| {
                    let row = nx * (j + ny * k);
                    l.data[row + span[0].0..row + span[0].1]
                        .iter()
                        .any(|&v| v != 0.0)
                })
            }),
        })
    })
    .map(std::sync::Arc::new)
    .ok_or_else(too_large)
}

/// Applies the mapping and the NaN/negative policies to `values` (`voxel` names the sample at an index);
/// returns the replacement counts and the statistics of the result (gathered in the same pass).
fn apply_policies(
    values: &mut [f32],
    voxel: &dyn Fn(usize) -> String,
    name: &str,
    file: &str,
    mapping: &Mapping,
    opts: &LoadOptions,
) -> Result<(usize, usize, crate::grid::GridStats), Error> {
    let identity = mapping.is_identity();
    // Negative values are refused only where they are unphysical; other grids (Mantaflow's `shadow` is −1
    // everywhere) keep what the file says.
    let physical = name == "density"
        || name == "temperature"
        || firemedium_core::species::symbols().any(|s| s == name);
    let (mut nonfinite, mut negative) = (0, 0);
    // Eight voxels at a time are tested at once (a loop the compiler vectorises); only a group holding a
    // non-finite or negative value, or any group under a mapping, goes through the voxel-by-voxel rules.
    const L: usize = crate::grid::STATS_LANES;
    let mut stats = crate::grid::StatsAcc::new();
    for (g, group) in values.chunks_mut(L).enumerate() {
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
mod tests;
