//! What to load and how: the formats, the thesis formats' options, the bad-data policies, the per-channel
//! mapping, the channel sources and the load options (with the memory cap).

use super::{RawCoords, RawValue};
use crate::Error;
use glam::DVec3;
use std::path::{Path, PathBuf};

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
    /// Values at or below this map to 0, whatever the rest does (Blender's flame: no flame, no fire).
    pub zero_at_or_below: Option<f64>,
}

impl Default for Mapping {
    fn default() -> Self {
        Mapping {
            scale: 1.0,
            offset: 0.0,
            pbrt_offset: 0.0,
            zero_at_or_below: None,
        }
    }
}

impl Mapping {
    pub(super) fn is_identity(&self) -> bool {
        *self == Mapping::default()
    }
    pub(super) fn apply(&self, v: f32) -> f32 {
        if self.zero_at_or_below.is_some_and(|z| v as f64 <= z) {
            return 0.0;
        }
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
    pub(super) fn grid_name(&self) -> &str {
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
