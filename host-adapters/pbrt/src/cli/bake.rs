//! `firemedium bake DATASET -o OUT.vdb`: the fire's coefficients as RGB grids, for a renderer that cannot load the
//! plugin (Blender's Cycles reads them through its Volume Coefficients node).
//!
//! The fire is built by the plugin from the dataset and `--param NAME=VALUE` (its parameters,
//! docs/reference/params.md) — the one read of its grids, within the memory budget — and asked through the C ABI
//! for the bricks its grids store and for σ_a, σ_s and the emission coefficient j in its channels at their voxel
//! centres (sparse in, sparse out — two blobs far apart bake as two leaves, not the box between them). They become
//! three vector grids in the renderer's linear working space (Rec.709/sRGB
//! primaries, D65), written as OpenVDB on the dataset's transform:
//!
//! - `emission` = the sRGB of j's XYZ (Σ_c j_c · XYZ_c, the plugin's own colour weights): per metre of path, in
//!   cd/m² — so a path tracer summing `emission · T ds` along a ray in metres gives the pixel `firemedium render`
//!   writes (its EXR is absolute: Y in cd/m²). A flame's colour lies outside Rec.709 (its blue is negative): the
//!   negative components are kept, so a linear renderer reproduces the flame's luminance and chromaticity (a
//!   compositor clipping them shifts both: how much is printed).
//! - `sigma_a`, `sigma_s` (per metre) = the coefficient spectrum averaged with the weight of each channel's light in
//!   that RGB component (its positive part): a colour renderer's three "wavelengths".
//!
//! - `velocity` (a dataset's velocity, `--velocity`, default the first of vel, v, velocity it holds): passed
//!   through as it is — the same lattice, the dataset's units — for the renderer's motion blur.
//!
//! What baking loses is printed with the result: atomic lines become their RGB, refraction's curved rays and embers
//! do not bake (refused), and the fire light becomes the renderer's own volume sampling.

use clap::Args;
use firemedium::render::scene::{load_plugin, typed_params};
use firemedium::Error;
use firemedium_core::cie::XYZ_TO_SRGB_ROWS;
use firemedium_dataset::{ChannelSource, Dataset, LoadOptions};
use firemedium_loader::{Context, Param};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Debug, Args)]
pub struct BakeArgs {
    /// The fire's dataset (OpenVDB, NanoVDB, or the thesis's formats), as the plugin's `filename` reads it.
    dataset: PathBuf,
    /// The baked OpenVDB file (vector grids `sigma_a`, `sigma_s`, `emission`).
    #[arg(short, long)]
    output: PathBuf,
    /// A fire parameter NAME=VALUE (repeatable; docs/reference/params.md, the dataset's and the volume's): `fuel=propane`,
    /// `temperaturescale=1000`, `source=houdini` ...
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    params: Vec<(String, String)>,
    /// The fire plugin library (default: FIREMEDIUM_PLUGIN, FIREMEDIUM_PLUGIN_PATH, or beside the executable).
    #[arg(long)]
    plugin: Option<PathBuf>,
    /// Frames A-B or A-B:STEP of a sequence: the dataset's and the output's names hold #### (the frame number).
    #[arg(long, value_name = "A-B", value_parser = crate::args::parse_frames)]
    frames: Option<crate::args::Frames>,
    /// The velocity passed through for Cycles' motion blur: a vector grid, or float grids NAME.x, NAME.y,
    /// NAME.z; `auto`: the first of vel, v, velocity the dataset holds; `none`: no velocity. Written as the vector
    /// grid `velocity` on the same lattice, in the dataset's units.
    #[arg(long, value_name = "NAME", default_value = "auto")]
    velocity: String,
    /// The memory budget in GB for the grids (default: half the machine's memory).
    #[arg(long, value_name = "GB", value_parser = crate::args::parse_gb)]
    max_memory: Option<f64>,
    /// Replace an output file that `firemedium bake` did not write (by default only its own bakes are replaced).
    #[arg(long)]
    force: bool,
    /// Print the result as JSON (one object per frame, a line each): the file, its voxels, the fire's luminance
    /// seen from its side and the view exposure that shows it.
    #[arg(long)]
    json: bool,
}

/// What a bake writes into its file's metadata as the `creator`: the files it may replace without `--force`.
const CREATOR: &str = "firemedium bake";

fn parse_param(s: &str) -> Result<(String, String), Error> {
    s.split_once('=')
        .filter(|(n, v)| !n.is_empty() && !v.is_empty())
        .map(|(n, v)| (n.to_string(), v.to_string()))
        .ok_or_else(|| Error::value(format!("{s:?}: expected NAME=VALUE, e.g. fuel=propane")))
}

/// Features the grids cannot carry: baking them would silently drop them.
const REFUSED: [(u64, &str); 3] = [
    (
        firemedium_abi::FM_FEATURE_REFRACTION,
        "refraction (curved rays)",
    ),
    (firemedium_abi::FM_FEATURE_EMBERS, "embers (opaque spheres)"),
    (
        firemedium_abi::FM_FEATURE_DIFFUSION,
        "diffusion (multiple scattering read as emission)",
    ),
];

pub fn run(a: &BakeArgs) -> firemedium::Result<String> {
    let plugin = load_plugin(a.plugin.as_deref()).map_err(|e| Error::input(e.to_string()))?;
    let Some(frames) = &a.frames else {
        check_output(a, &a.dataset, &a.output)?;
        return bake(a, &plugin, None, &a.output);
    };
    if !a.output.to_string_lossy().contains('#') {
        return Err(Error::value(format!(
            "--frames needs an output name holding #### (the frame number): {}",
            a.output.display()
        )));
    }
    // Every frame's output checked before the first is baked.
    let mut outs = Vec::with_capacity(frames.0.len());
    for &f in &frames.0 {
        let out = firemedium_dataset::frame_path(&a.output, Some(f))
            .map_err(|e| Error::value(e.to_string()))?;
        let input = firemedium_dataset::frame_path(&a.dataset, Some(f))
            .map_err(|e| Error::value(e.to_string()))?;
        check_output(a, &input, &out)?;
        outs.push((f, out));
    }
    let mut report = String::new();
    for (f, out) in outs {
        report += &bake(a, &plugin, Some(f), &out)?;
    }
    Ok(report)
}

/// Refuses, before any work, an output that is the dataset itself, a folder, or a file `firemedium bake` did not
/// write (unless `--force`): a bake replaces only its own files.
fn check_output(a: &BakeArgs, dataset: &Path, out: &Path) -> firemedium::Result<()> {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    if abs(dataset) == abs(out) {
        return Err(Error::file(
            out.display(),
            "is the dataset itself: give the baked grids another name with -o",
        ));
    }
    if out.is_dir() {
        return Err(Error::file(
            out.display(),
            "is a folder: name a .vdb file with -o",
        ));
    }
    if out.exists() && !a.force {
        let creator = firemedium_dataset::creator_of(out).ok().flatten();
        if creator.as_deref() != Some(CREATOR) {
            return Err(Error::file(
                out.display(),
                "exists and is not a file firemedium bake wrote: give another name with -o, or --force to replace it",
            ));
        }
    }
    firemedium::imageio::check_writable(out)
}

/// The velocity `--velocity` asks for: its name in the dataset and its three components loaded (x, y, z), or
/// None (`none`, or `auto` in a dataset without one).
fn velocity_of(
    a: &BakeArgs,
    entries: &[firemedium_dataset::GridEntry],
    opts: &LoadOptions,
) -> firemedium::Result<Option<(String, Dataset)>> {
    let wanted = a.velocity.as_str();
    if wanted == "none" {
        return Ok(None);
    }
    let has = |n: &str| entries.iter().any(|g| g.name == n);
    let vector = |n: &str| {
        entries
            .iter()
            .any(|g| g.name == n && g.kind.starts_with("Tree_vec3s"))
    };
    let candidates: Vec<&str> = if wanted == "auto" {
        firemedium_dataset::vdb::VELOCITY_NAMES.to_vec()
    } else {
        vec![wanted]
    };
    let found = candidates
        .into_iter()
        .find(|b| vector(b) || ["x", "y", "z"].iter().all(|c| has(&format!("{b}.{c}"))));
    let Some(name) = found else {
        if wanted == "auto" {
            return Ok(None);
        }
        let names: Vec<&str> = entries.iter().map(|g| g.name.as_str()).collect();
        return Err(Error::value(format!(
            "--velocity {wanted}: {} has no vector grid {wanted} nor float grids {wanted}.x, .y, .z (its grids: {})",
            a.dataset.display(),
            names.join(", ")
        )));
    };
    let sources: Vec<ChannelSource> = ["x", "y", "z"]
        .iter()
        .map(|c| ChannelSource::new(&format!("{name}.{c}"), &a.dataset))
        .collect();
    let v = Dataset::load(&sources, opts).map_err(|e| Error::input(e.to_string()))?;
    Ok(Some((name.to_string(), v)))
}

/// The fire's features, refused when it holds one grids cannot carry.
fn bakeable(
    volume: &firemedium_loader::Volume,
    dataset: &std::path::Path,
) -> firemedium::Result<u64> {
    let features = volume.features().map_err(|e| Error::input(e.to_string()))?;
    let refused: Vec<&str> = REFUSED
        .iter()
        .filter(|(bit, _)| features & bit != 0)
        .map(|(_, name)| *name)
        .collect();
    if !refused.is_empty() {
        return Err(Error::input(format!(
                "{}: the fire holds {}, which grids cannot carry; render it with `firemedium render`, or leave those parameters out",
                dataset.display(),
                refused.join(", ")
            ),
        ));
    }
    Ok(features)
}

/// What a bake wrote and found, for its report.
struct Baked<'a> {
    out: &'a std::path::Path,
    frame: Option<i64>,
    dims: [usize; 3],
    bytes: usize,
    seconds: f64,
    /// The fire's luminance seen from its side (99th percentile), when it emits.
    seen: Option<f64>,
    /// Σ Y of the emission, and what clipping its negative components would change of it.
    luminance: f64,
    clipped: f64,
    /// It holds thick atomic lines.
    lines: bool,
    /// The velocity grid passed on, by name.
    velocity: Option<&'a str>,
    g: f64,
}

impl Baked<'_> {
    /// The report: a line of JSON, or the text a user reads.
    fn report(&self, json: bool) -> String {
        let Baked {
            out,
            frame,
            dims,
            bytes,
            seconds,
            seen,
            luminance,
            clipped,
            lines,
            velocity,
            g,
        } = *self;
        // (Clamping a negative component raises the luminance: the change is signed.)
        let change = if luminance > 0.0 {
            -100.0 * clipped / luminance
        } else {
            0.0
        };
        let passed = velocity.map_or(String::new(), |name| {
            format!("; velocity: the dataset's {name}, as it is (its units), for motion blur")
        });
        let exposure = seen.map(|l| (2.0 / l).log2());
        if json {
            return serde_json::json!({
                "output": out.display().to_string(),
                "frame": frame,
                "dims": dims,
                "bytes": bytes,
                "seconds": seconds,
                "luminance_p99": seen,
                "exposure": exposure,
                "out_of_gamut_change_percent": change,
            })
            .to_string()
                + "\n";
        }
        let seen_line = match (seen, exposure) {
            (Some(l), Some(e)) => format!("the fire seen from its side: {l:.4} cd/m² at its brightest (99th percentile of its lines of sight); a view exposure of {e:+.2} stops shows it (in AgX, that luminance at 2, a stop above diffuse white), as firemedium's own preview does\n"),
            _ => "the fire emits nothing visible from its side\n".to_string(),
        };
        format!(
            "wrote {} ({}×{}×{} voxels, grids sigma_a, sigma_s, emission: linear Rec.709/sRGB, per metre; emission in cd/m² per metre{passed}), {:.1} MB in {:.2} s\n\
             kept out of gamut: the emission's negative (out-of-Rec.709) components, which a compositor clipping them would change its luminance by {change:+.2} %; lost in baking: {}the fire light becomes the renderer's own volume sampling; the phase function's g = {} is the medium's\n{seen_line}",
            out.display(),
            dims[0],
            dims[1],
            dims[2],
            bytes as f64 / 1e6,
            seconds,
            if lines { "atomic lines become their RGB (thick across their profiles: the grids keep their colour, not their self-absorption); " } else { "" },
            g,
        )
    }
}

/// Marks a voxel active where a component is non-zero, and leaves out a leaf with none.
fn activate(leaves: &mut [Vec<firemedium_dataset::vdb::VdbLeaf>]) {
    for lv in leaves.iter_mut() {
        for (_, mask, vals) in lv.iter_mut() {
            for i in 0..512 {
                if vals[3 * i..3 * i + 3].iter().any(|&v| v != 0.0) {
                    mask[i / 64] |= 1 << (i % 64);
                }
            }
        }
        lv.retain(|(_, mask, _)| mask.iter().any(|&w| w != 0));
    }
}

/// Each channel's linear sRGB per unit radiance (from its XYZ), and the sums of their positive parts: the weight
/// of a channel's light in each RGB component.
fn channel_weights(xyz: &[[f64; 3]]) -> (Vec<[f64; 3]>, [f64; 3]) {
    let rgb_of = |x: &[f64; 3]| XYZ_TO_SRGB_ROWS.map(|r| r[0] * x[0] + r[1] * x[1] + r[2] * x[2]);
    let channel_rgb: Vec<[f64; 3]> = xyz.iter().map(rgb_of).collect();
    let weight_sum: [f64; 3] = [0, 1, 2].map(|k| {
        channel_rgb
            .iter()
            .map(|c| c[k].max(0.0))
            .sum::<f64>()
            .max(f64::MIN_POSITIVE)
    });
    (channel_rgb, weight_sum)
}

/// One frame (`None`: the dataset as named) baked into `out`.
fn bake(
    a: &BakeArgs,
    plugin: &firemedium_loader::Plugin,
    frame: Option<i64>,
    out: &std::path::Path,
) -> firemedium::Result<String> {
    let start = Instant::now();
    let budget = crate::args::budget(a.max_memory);
    let opts = LoadOptions {
        max_bytes: budget,
        frame,
        ..LoadOptions::default()
    };
    let entries = firemedium_dataset::list_grids(&a.dataset, &opts)
        .map_err(|e| Error::input(e.to_string()))?;
    // The fire, through the plugin: it reads the dataset once, within the budget, and says which bricks its grids
    // hold.
    let mut params = vec![Param::string("filename", &a.dataset.to_string_lossy())];
    params.extend(
        typed_params(
            plugin,
            &["dataset", "volume"],
            "the fire",
            "--param",
            &a.params,
        )
        .map_err(Error::value)?,
    );
    let context = Context {
        max_bytes: Some(budget),
        frame,
        ..Context::default()
    };
    let volume = plugin
        .create_volume_with(&params, &context)
        .map_err(|e| Error::input(e.to_string()))?;
    let features = bakeable(&volume, &a.dataset)?;
    let info = volume.info();
    let dims = info.dims.map(|n| n as usize);
    // Only the bricks the fire's grids hold are baked (sparse in, sparse out): per brick, a leaf of each grid.
    let firsts = volume.bricks().map_err(|e| Error::input(e.to_string()))?;
    // The baked grids' bytes, refused before they are allocated or the velocity read (a small file of constant
    // tiles can stand for billions of voxels), within what the fire left of the budget.
    let has = |n: &str| {
        entries
            .iter()
            .any(|g| g.name == n || g.name == format!("{n}.x"))
    };
    let velocity_named = match a.velocity.as_str() {
        "none" => false,
        "auto" => firemedium_dataset::vdb::VELOCITY_NAMES
            .iter()
            .any(|n| has(n)),
        _ => true,
    };
    let grid_count: u64 = if velocity_named { 4 } else { 3 };
    let left = budget.saturating_sub(info.bytes);
    let bytes = (firsts.len() as u64).saturating_mul(grid_count * 3 * 512 * 4);
    if bytes > left {
        return Err(Error::input(format!(
            "{}: the baked grids' {} bricks of 8³ voxels need {bytes} bytes, above the memory budget of {budget} less the fire's {} (raise --max-memory)",
            a.dataset.display(),
            firsts.len(),
            info.bytes
        )));
    }
    let velocity_opts = LoadOptions {
        max_bytes: left - bytes,
        frame,
        ..LoadOptions::default()
    };
    let velocity = velocity_of(a, &entries, &velocity_opts)?;
    let channels = info.channels as usize;
    let xyz = volume
        .channel_xyz()
        .map_err(|e| Error::input(e.to_string()))?;
    let (channel_rgb, weight_sum) = channel_weights(&xyz);
    // The output's index space keeps the bricks whole: lattice sample i at i + off, each brick's first sample at
    // a multiple of 8 (where the lattice starts inside a brick, its first sample's index is below 0).
    let off = firsts
        .first()
        .map_or([0; 3], |f| f.map(|v| (-v).rem_euclid(8) as usize));
    let mut bricks: Vec<[usize; 3]> = firsts
        .iter()
        .map(|f| [0, 1, 2].map(|a| ((f[a] + off[a] as i64) / 8) as usize))
        .collect();
    bricks.sort_by_key(|b| (b[2], b[1], b[0]));
    let grid_count: u64 = if velocity.is_some() { 4 } else { 3 };
    // The lattice's voxel centres, in the dataset's space — the medium space the plugin builds the fire in.
    let b0 = info.lattice_min;
    let voxel = [0, 1, 2].map(|a| (info.lattice_max[a] - info.lattice_min[a]) / dims[a] as f64);
    let (mut luminance, mut clipped) = (0.0f64, 0.0f64);
    // Per grid, its leaves: origin (output index space, sample i at i + off), active mask, 3 × 512 values.
    let mut leaves: Vec<Vec<firemedium_dataset::vdb::VdbLeaf>> =
        vec![Vec::new(); grid_count as usize];
    // Bricks in batches of a fixed number of voxels per call (the buffers' size does not follow the input's).
    const BATCH: usize = 32;
    let mut points = Vec::with_capacity(BATCH * 512);
    let mut places: Vec<(usize, usize)> = Vec::with_capacity(BATCH * 512);
    let cap = BATCH * 512 * channels;
    let (mut sa, mut ss, mut j) = (vec![0f32; cap], vec![0f32; cap], vec![0f32; cap]);
    for batch in bricks.chunks(BATCH) {
        let first_leaf = leaves[0].len();
        points.clear();
        places.clear();
        for (bi, b) in batch.iter().enumerate() {
            for lv in leaves.iter_mut() {
                lv.push((b.map(|c| 8 * c as i32), [0u64; 8], vec![0f32; 3 * 512]));
            }
            for i in 0..512 {
                // (The writer's order: z fastest.)
                let l = [i >> 6, (i >> 3) & 7, i & 7];
                let v = [0, 1, 2].map(|a| (8 * b[a] + l[a]).checked_sub(off[a]));
                let [Some(x), Some(y), Some(z)] = v else {
                    continue;
                };
                if x >= dims[0] || y >= dims[1] || z >= dims[2] {
                    continue;
                }
                let centre = [
                    b0[0] + (x as f64 + 0.5) * voxel[0],
                    b0[1] + (y as f64 + 0.5) * voxel[1],
                    b0[2] + (z as f64 + 0.5) * voxel[2],
                ];
                points.push(centre);
                places.push((first_leaf + bi, i));
                if let Some((_, vel)) = &velocity {
                    let p = glam::DVec3::from_array(centre);
                    let leaf = &mut leaves[3][first_leaf + bi];
                    for k in 0..3 {
                        leaf.2[3 * i + k] = vel.sample(k, p);
                    }
                }
            }
        }
        let (m, c) = (points.len(), points.len() * channels);
        volume
            .coefficients(&points, &mut sa[..c], &mut ss[..c], &mut j[..c])
            .map_err(|e| Error::input(e.to_string()))?;
        for q in 0..m {
            let (leaf, i) = places[q];
            let row = &j[q * channels..(q + 1) * channels];
            let mut e = [0.0f64; 3];
            let mut y_lum = 0.0;
            for (c, v) in row.iter().enumerate() {
                for k in 0..3 {
                    e[k] += *v as f64 * channel_rgb[c][k];
                }
                y_lum += *v as f64 * xyz[c][1];
            }
            let clipped_y: f64 =
                0.2126 * e[0].max(0.0) + 0.7152 * e[1].max(0.0) + 0.0722 * e[2].max(0.0);
            luminance += y_lum;
            clipped += y_lum - clipped_y;
            for k in 0..3 {
                leaves[2][leaf].2[3 * i + k] = e[k] as f32;
                for (g, src) in [(0, &sa), (1, &ss)] {
                    let row = &src[q * channels..(q + 1) * channels];
                    let s: f64 = row
                        .iter()
                        .zip(&channel_rgb)
                        .map(|(v, c)| *v as f64 * c[k].max(0.0))
                        .sum();
                    leaves[g][leaf].2[3 * i + k] = (s / weight_sum[k]) as f32;
                }
            }
        }
    }
    // The fire seen from its side (before empty leaves are dropped: `leaves` line up with `bricks`).
    let seen = side_luminance(&bricks, &leaves, voxel, side_axes(a, &opts));
    activate(&mut leaves);
    let names = ["sigma_a", "sigma_s", "emission", "velocity"];
    let grids: Vec<(&str, Vec<firemedium_dataset::vdb::VdbLeaf>)> =
        names.iter().copied().zip(leaves).collect();
    let origin = [0, 1, 2].map(|k| b0[k] - off[k] as f64 * voxel[k]);
    let bytes = firemedium_dataset::vdb::write_sparse_vectors_by(
        Some(CREATOR),
        &grids,
        glam::DVec3::from_array(origin),
        glam::DVec3::from_array(voxel),
    );
    firemedium::imageio::write_atomic(out, |tmp| {
        std::fs::write(tmp, &bytes)
            .map_err(|e| Error::file(out.display(), format!("cannot write: {e}")))
    })?;
    Ok(Baked {
        out,
        frame,
        dims,
        bytes: bytes.len(),
        seconds: start.elapsed().as_secs_f64(),
        seen,
        luminance,
        clipped,
        lines: features & firemedium_abi::FM_FEATURE_THICK_LINES != 0,
        velocity: velocity.as_ref().map(|(name, _)| name.as_str()),
        g: info.g,
    }
    .report(a.json))
}

/// The axes the fire is seen along from its side: the two other than its up axis (`firemedium_dataset::convention`
/// from the dataset's grids; z up when they do not say).
fn side_axes(a: &BakeArgs, opts: &LoadOptions) -> [usize; 2] {
    let up =
        firemedium_dataset::convention::survey(std::slice::from_ref(&a.dataset), opts, None, 1.0)
            .map_or(2, |r| r.up.value.axis);
    match up {
        0 => [1, 2],
        1 => [0, 2],
        _ => [0, 1],
    }
}

/// The 99th percentile of the luminance (cd/m²) along the lattice's lines of sight through the baked grids, along
/// `axes` (orthographic views of the fire from its side, front to back: L = Σ T · Y(emission) ds, T = e^(−τ) with
/// τ from the luminance-weighted σ_a + σ_s), over the lines that see any; `None` when none does. `leaves[g][i]` is
/// brick `bricks[i]`'s leaf of grid g (0 σ_a, 1 σ_s, 2 emission), values z fastest.
fn side_luminance(
    bricks: &[[usize; 3]],
    leaves: &[Vec<firemedium_dataset::vdb::VdbLeaf>],
    voxel: [f64; 3],
    axes: [usize; 2],
) -> Option<f64> {
    let y = |v: &[f32]| 0.2126 * v[0] as f64 + 0.7152 * v[1] as f64 + 0.0722 * v[2] as f64;
    // Luminance in log bins of 1/100 decade from 1e-12 to 1e12 cd/m².
    const BINS: usize = 2400;
    let mut hist = vec![0u64; BINS];
    for along in axes {
        let (u, w) = match along {
            0 => (1, 2),
            1 => (0, 2),
            _ => (0, 1),
        };
        // The bricks in the order a line of sight along `along` crosses them, row by row.
        let mut order: Vec<usize> = (0..bricks.len()).collect();
        order.sort_by_key(|&i| (bricks[i][w], bricks[i][u], bricks[i][along]));
        let ds = voxel[along];
        let mut k = 0;
        while k < order.len() {
            let row = (bricks[order[k]][w], bricks[order[k]][u]);
            let (mut l, mut t) = ([0f64; 64], [1f64; 64]);
            while k < order.len() && (bricks[order[k]][w], bricks[order[k]][u]) == row {
                let b = order[k];
                for s in 0..8 {
                    for line in 0..64 {
                        let mut p = [0usize; 3];
                        p[along] = s;
                        p[u] = line % 8;
                        p[w] = line / 8;
                        // (The leaves' order: z fastest.)
                        let i = 3 * (p[0] * 64 + p[1] * 8 + p[2]);
                        let e = y(&leaves[2][b].2[i..i + 3]);
                        let st = y(&leaves[0][b].2[i..i + 3]) + y(&leaves[1][b].2[i..i + 3]);
                        l[line] += t[line] * e.max(0.0) * ds;
                        t[line] *= (-st.max(0.0) * ds).exp();
                    }
                }
                k += 1;
            }
            for v in l {
                if v > 0.0 {
                    let bin = ((v.log10() + 12.0) * 100.0).clamp(0.0, (BINS - 1) as f64) as usize;
                    hist[bin] += 1;
                }
            }
        }
    }
    let total: u64 = hist.iter().sum();
    if total == 0 {
        return None;
    }
    let want = (total as f64 * 0.99).ceil() as u64;
    let mut seen = 0;
    for (b, &c) in hist.iter().enumerate() {
        seen += c;
        if seen >= want {
            return Some(10f64.powf((b as f64 + 0.5) / 100.0 - 12.0));
        }
    }
    None
}
