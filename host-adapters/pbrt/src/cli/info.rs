//! `firemedium info FILE`: what a voxel dataset file holds, as the voxel dataset component loads it.
//!
//! Prints the format, dims, bounds, voxel size, the 8³ bricks stored, every channel with min/max/mean, non-zero ("active") fraction,
//! bytes and load time, the grids it could not load (vector grids, …), and with `--sample x,y,z` the trilinear
//! value of each channel at that medium-space point. A file the loader refuses prints its error on one line and
//! exits with status 1.

use clap::Args;
use firemedium::Error;
use firemedium_dataset::{
    self as dataset, AxisOrder, ChannelSource, Dataset, Format, LoadOptions, Policy, RawCoords,
    RawValue,
};
use glam::DVec3;
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

#[derive(Debug, Args)]
pub struct InfoArgs {
    /// The dataset file (.vdb, .nvdb, .raw, .raw2, .txt; or name the format).
    file: PathBuf,
    /// Format: ascii, asciisparse, raw, raw2, vdb, nvdb (default: from the extension).
    #[arg(long)]
    format: Option<String>,
    /// Grids to load (default: every float grid).
    #[arg(long = "grid", value_name = "NAME")]
    grids: Vec<String>,
    /// Dense ASCII value order: x (x fastest, default) or z (z fastest, the thesis's shader code).
    #[arg(long, default_value = "x")]
    order: String,
    /// Raw coordinates: thesis (1-based x z y, default) or xyz (0-based).
    #[arg(long, default_value = "thesis")]
    raw_coords: String,
    /// Raw value: red (r/256, default) or maxrgb (max(r,g,b)/256).
    #[arg(long, default_value = "red")]
    raw_value: String,
    /// NaN/infinite values: error (default) or zero.
    #[arg(long, default_value = "error")]
    nonfinite: String,
    /// Negative values: error (default) or zero.
    #[arg(long, default_value = "error")]
    negative: String,
    /// Frame number for a patterned file name (fire_####.vdb).
    #[arg(long)]
    frame: Option<i64>,
    /// Medium-space point x,y,z at which to sample every channel (trilinear).
    #[arg(
        long,
        value_name = "X,Y,Z",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    sample: Option<Vec<f64>>,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// The memory budget in GB for each grid (default: half the machine's memory).
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
}

#[derive(Debug, Serialize)]
struct Report {
    file: String,
    format: &'static str,
    dims: [usize; 3],
    bounds: [[f64; 3]; 2],
    voxel_size: [f64; 3],
    channels: Vec<ChannelInfo>,
    skipped_grids: Vec<Skipped>,
    /// 8³ bricks stored of those the box holds, and the bytes of their table.
    bricks: usize,
    /// Blocks of 512 values each grid stores for them (fewer than `bricks` when constant tiles share).
    blocks: usize,
    bricks_in_box: usize,
    brick_table_bytes: usize,
    bytes: usize,
    load_seconds: f64,
    /// The `source` the grids look like (kelvin, blender), and why; none when they look like neither.
    #[serde(skip_serializing_if = "Option::is_none")]
    source: Option<(String, String)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    sample: Option<SampleInfo>,
}

#[derive(Debug, Serialize)]
struct ChannelInfo {
    name: String,
    min: f64,
    max: f64,
    mean: f64,
    active_fraction: f64,
    bytes: usize,
    load_seconds: f64,
    replaced_nonfinite: usize,
    replaced_negative: usize,
}

#[derive(Debug, Serialize)]
struct Skipped {
    name: String,
    kind: String,
}

#[derive(Debug, Serialize)]
struct SampleInfo {
    point: [f64; 3],
    values: Vec<(String, f64)>,
}

/// Runs `info`: `Ok(text)`, or `Err((exit status, message))`.
/// How `args` asks the dataset to be read.
fn load_options(args: &InfoArgs) -> firemedium::Result<LoadOptions> {
    let bad_arg = Error::value;
    Ok(LoadOptions {
        format: args
            .format
            .as_deref()
            .map(Format::from_name)
            .transpose()
            .map_err(|e| bad_arg(format!("--format: {e}")))?,
        order: match args.order.as_str() {
            "x" => AxisOrder::XFastest,
            "z" => AxisOrder::ZFastest,
            o => return Err(bad_arg(format!("--order {o}: expected x or z"))),
        },
        raw_coords: match args.raw_coords.as_str() {
            "thesis" => RawCoords::Thesis,
            "xyz" => RawCoords::Xyz,
            o => return Err(bad_arg(format!("--raw-coords {o}: expected thesis or xyz"))),
        },
        raw_value: match args.raw_value.as_str() {
            "red" => RawValue::Red,
            "maxrgb" => RawValue::MaxRgb,
            o => return Err(bad_arg(format!("--raw-value {o}: expected red or maxrgb"))),
        },
        nonfinite: Policy::from_name("nonfinite", &args.nonfinite)
            .map_err(|e| bad_arg(format!("--nonfinite: {e}")))?,
        negative: Policy::from_name("negative", &args.negative)
            .map_err(|e| bad_arg(format!("--negative: {e}")))?,
        frame: args.frame,
        max_bytes: crate::args::budget(args.max_memory),
        ..LoadOptions::default()
    })
}

pub fn run(args: &InfoArgs) -> firemedium::Result<String> {
    let bad_arg = Error::value;
    let bad_file = Error::input;
    let opts = load_options(args)?;
    if let Some(s) = &args.sample {
        if s.len() != 3 || s.iter().any(|v| !v.is_finite()) {
            return Err(bad_arg(format!(
                "--sample: expected three finite coordinates x,y,z, found {s:?}"
            )));
        }
    }
    let start = Instant::now();
    let entries = dataset::list_grids(&args.file, &opts).map_err(bad_file)?;
    let names: Vec<String> = if args.grids.is_empty() {
        let floats: Vec<String> = entries
            .iter()
            .filter(|g| g.loadable)
            .map(|g| g.name.clone())
            .collect();
        if floats.is_empty() {
            // A file of vector grids only (a bake's sigma_a, sigma_s, emission; a velocity): their components.
            entries
                .iter()
                .filter(|g| g.kind.starts_with("Tree_vec3s"))
                .flat_map(|g| ["x", "y", "z"].map(|c| format!("{}.{c}", g.name)))
                .collect()
        } else {
            floats
        }
    } else {
        args.grids.clone()
    };
    if names.is_empty() {
        return Err(Error::input(format!(
            "{}: no float grid to load (grids: {})",
            args.file.display(),
            entries
                .iter()
                .map(|g| format!("{} {}", g.name, g.kind))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let sources: Vec<ChannelSource> = names
        .iter()
        .map(|n| ChannelSource::new(n, &args.file))
        .collect();
    let ds = Dataset::load(&sources, &opts).map_err(bad_file)?;
    let load_seconds = start.elapsed().as_secs_f64();
    let [p0, p1] = ds.bounds();
    let dims = ds.dims();
    let voxel = (p1 - p0) / DVec3::new(dims[0] as f64, dims[1] as f64, dims[2] as f64);
    let sample = args.sample.as_ref().map(|s| {
        let p = DVec3::new(s[0], s[1], s[2]);
        SampleInfo {
            point: p.to_array(),
            values: ds
                .channels()
                .iter()
                .enumerate()
                .map(|(i, c)| (c.name.clone(), ds.sample(i, p) as f64))
                .collect(),
        }
    });
    let report = Report {
        file: ds.channels()[0].report.file.clone(),
        format: ds.format().name(),
        dims,
        bounds: [p0.to_array(), p1.to_array()],
        voxel_size: voxel.to_array(),
        channels: ds
            .channels()
            .iter()
            .map(|c| ChannelInfo {
                name: c.name.clone(),
                min: c.stats.min as f64,
                max: c.stats.max as f64,
                mean: c.stats.mean,
                active_fraction: c.stats.nonzero_fraction,
                bytes: c.report.bytes,
                load_seconds: c.report.load_seconds,
                replaced_nonfinite: c.report.replaced_nonfinite,
                replaced_negative: c.report.replaced_negative,
            })
            .collect(),
        skipped_grids: entries
            .iter()
            .filter(|g| {
                !names
                    .iter()
                    .any(|n| *n == g.name || n.strip_suffix(".x") == Some(&g.name))
            })
            .map(|g| Skipped {
                name: g.name.clone(),
                kind: g.kind.clone(),
            })
            .collect(),
        bricks: ds.topology().active_bricks(),
        blocks: ds.topology().blocks_stored(),
        bricks_in_box: ds.topology().bricks().iter().product(),
        brick_table_bytes: ds.topology().bytes(),
        bytes: ds.bytes(),
        load_seconds,
        source: source_of(
            &args.file.display().to_string(),
            &entries,
            &ds,
            ds.format() == Format::NanoVdb,
        ),
        sample,
    };
    if args.json {
        return serde_json::to_string_pretty(&report)
            .map(|s| s + "\n")
            .map_err(|e| Error::input(format!("JSON output failed: {e}")));
    }
    Ok(text(&report))
}

/// The report as the command prints it.
/// A channel's statistic in a column of 12: six decimals where they show it (a temperature, a density of order
/// one), else six significant digits (a soot volume fraction of 1e-7 would read 0.000000).
fn value(x: f64) -> String {
    if x == 0.0 || (x.abs() >= 1e-3 && x.abs() < 1e6) {
        format!("{x:.6}")
    } else {
        format!("{x:.5e}")
    }
}

fn text(report: &Report) -> String {
    let [p0, p1] = report.bounds.map(DVec3::from);
    let dims = report.dims;
    let voxel = DVec3::from(report.voxel_size);
    let mut s = format!("{} ({})\n", report.file, report.format);
    s += &format!("dims      {} × {} × {}\n", dims[0], dims[1], dims[2]);
    s += &format!(
        "bounds    ({:.6}, {:.6}, {:.6}) .. ({:.6}, {:.6}, {:.6})\n",
        p0.x, p0.y, p0.z, p1.x, p1.y, p1.z
    );
    s += &format!(
        "voxel     {:.6} × {:.6} × {:.6}\n",
        voxel.x, voxel.y, voxel.z
    );
    s += &format!(
        "{:<14} {:>12} {:>12} {:>12} {:>8} {:>12} {:>9}\n",
        "channel", "min", "max", "mean", "active", "bytes", "load (s)"
    );
    for c in &report.channels {
        s += &format!(
            "{:<14} {:>12} {:>12} {:>12} {:>7.2}% {:>12} {:>9.4}\n",
            c.name,
            value(c.min),
            value(c.max),
            value(c.mean),
            100.0 * c.active_fraction,
            c.bytes,
            c.load_seconds
        );
        if c.replaced_nonfinite + c.replaced_negative > 0 {
            s += &format!(
                "{:<14} replaced {} non-finite and {} negative values by 0\n",
                "", c.replaced_nonfinite, c.replaced_negative
            );
        }
    }
    for g in &report.skipped_grids {
        if g.kind.starts_with("Tree_vec3s") {
            s += &format!(
                "skipped   {} ({}: a vector grid, e.g. a velocity for motion blur: \"string velocitygrid\" \"{}\")\n",
                g.name, g.kind, g.name
            );
        } else {
            s += &format!("skipped   {} ({})\n", g.name, g.kind);
        }
    }
    s += &format!(
        "storage   {} of the box's {} bricks of 8³ ({:.1} %){}, their table {} bytes\n",
        report.bricks,
        report.bricks_in_box,
        100.0 * report.bricks as f64 / report.bricks_in_box.max(1) as f64,
        if report.blocks < report.bricks {
            format!(
                " in {} blocks of values (constant tiles share one per value)",
                report.blocks
            )
        } else {
            String::new()
        },
        report.brick_table_bytes
    );
    s += &format!(
        "total     {} bytes, loaded in {:.4} s\n",
        report.bytes, report.load_seconds
    );
    if let Some((name, why)) = &report.source {
        s += &format!("source    {name}: {why}\n");
    }
    if let Some(smp) = &report.sample {
        s += &format!(
            "sample at ({}, {}, {}):",
            smp.point[0], smp.point[1], smp.point[2]
        );
        for (n, v) in &smp.values {
            s += &format!(" {n} = {v}");
        }
        s += "\n";
    }
    s
}

/// The `source` convention the grids follow and why (`firemedium_dataset::convention`: the names, and the
/// temperature's unit from its peak); `None` when no grid can be the smoke or carry the heat.
fn source_of(
    file: &str,
    entries: &[firemedium_dataset::GridEntry],
    ds: &Dataset,
    nanovdb: bool,
) -> Option<(String, String)> {
    use firemedium_dataset::convention;
    let n = convention::names(file, entries, nanovdb).ok()?;
    let (grid, kind) = &n.heat.value;
    let unit = ds.channel(grid).map(|c| {
        convention::unit(grid, *kind, convention::peak(&c.grid))
            .0
            .why
    });
    let why = match unit {
        Some(u) => format!("{}; {u}", n.tool.why),
        None => n.tool.why.clone(),
    };
    Some((n.tool.value.name().to_string(), why))
}

#[cfg(test)]
mod tests {
    use super::value;

    /// Small and large statistics keep their digits; the usual ones read as before.
    #[test]
    fn a_statistic_keeps_six_significant_digits() {
        assert_eq!(value(3.25e-7), "3.25000e-7");
        assert_eq!(value(1390.72998), "1390.729980");
        assert_eq!(value(0.0), "0.000000");
        assert_eq!(value(-2.5e9), "-2.50000e9");
        assert_eq!(value(0.5), "0.500000");
    }
}
