//! `firemedium scene DATASET`: a starter pbrt-v4 scene around a user's fire, so that their first render of their
//! own data is one command away — the fire's boundary box fitted to the data, a camera framing it from the front,
//! a ground under it, and the `source` convention the grids look like (`firemedium info` says the same).

use clap::Args;
use firemedium::Error;
use firemedium_dataset::LoadOptions;
use glam::DVec3;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct SceneArgs {
    /// The fire's dataset (OpenVDB, NanoVDB, or the thesis's formats).
    dataset: PathBuf,
    /// The scene to write (default: the dataset's name with .pbrt, beside it).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace the scene if it exists.
    #[arg(long)]
    force: bool,
}

/// The scene's text for a dataset at `dataset` (as the scene names it) whose data spans `lo`..`hi`, up the axis
/// `up` (2: z, Blender's and the generator's; 1: y, Houdini's and EmberGen's), read with `source`.
fn scene_text(
    dataset: &str,
    lo: DVec3,
    hi: DVec3,
    up: usize,
    source: Option<&str>,
    image: &str,
) -> String {
    let size = hi - lo;
    let centre = 0.5 * (lo + hi);
    // The camera: in front (−y when z is up, +z when y is up), a little above the fire's middle, far enough that
    // the box fills about 80 % of the frame's height (fov 40° on the 16:9 film's shorter side) and its width.
    let (fov, aspect) = (40f64.to_radians(), 16.0 / 9.0);
    let height = size[up];
    // (x runs across the frame in both conventions; the other horizontal axis is the depth.)
    let width = size.x;
    let fit = (0.5 * height / 0.8).max(0.5 * width / (0.8 * aspect)) / (0.5 * fov).tan();
    let depth = if up == 2 { size[1] } else { size[2] };
    let distance = fit + 0.5 * depth;
    let (mut eye, mut up_v) = (centre, DVec3::ZERO);
    up_v[up] = 1.0;
    if up == 2 {
        eye.y -= distance;
    } else {
        eye.z += distance;
    }
    eye[up] += 0.15 * distance;
    let target = centre;
    // The box: the data's, its floor a hair above the ground (coplanar faces let rays slip between them).
    let gap = 1e-3 * size.max_element();
    let mut blo = lo;
    blo[up] += gap;
    let corners: Vec<String> = (0..8)
        .map(|c| {
            let p = DVec3::new(
                if c & 1 == 0 { blo.x } else { hi.x },
                if c & 2 == 0 { blo.y } else { hi.y },
                if c & 4 == 0 { blo.z } else { hi.z },
            );
            format!("{} {} {}", num(p.x), num(p.y), num(p.z))
        })
        .collect();
    // The ground: a square 20 times the fire's extent, at the data's bottom.
    let r = 10.0 * size.max_element();
    let g = lo[up];
    let ground: Vec<String> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(a, b)| {
            let mut p = centre;
            let (u, v) = if up == 2 { (0, 1) } else { (0, 2) };
            p[u] += a * r;
            p[v] += b * r;
            p[up] = g;
            format!("{} {} {}", num(p.x), num(p.y), num(p.z))
        })
        .collect();
    let source_line = source.map_or(String::new(), |s| format!("\n  \"string source\" \"{s}\""));
    format!(
        "# A starter scene for {dataset} (written by `firemedium scene`): the fire's boundary box fitted to its data, a\n\
         # camera framing it, a ground. Render it with `firemedium render` (docs/reference/params.md lists the fire's parameters:\n\
         # add them to the medium; \"float stepsize\" 1 renders faster, `--spp 16` for a first look).\n\
         LookAt {}   {}   {}\n\
         Camera \"perspective\" \"float fov\" 40\n\
         Film \"rgb\" \"integer xresolution\" 640 \"integer yresolution\" 360 \"string filename\" \"{image}\"\n\
         Sampler \"zsobol\" \"integer pixelsamples\" 64\n\
         Integrator \"volpath\" \"integer maxdepth\" 3\n\
         \n\
         WorldBegin\n\
         \n\
         MakeNamedMedium \"fire\" \"string type\" \"fire\"\n  \"string dataset\" \"{dataset}\"{source_line}\n\
         \n\
         AttributeBegin\n  MediumInterface \"fire\" \"\"\n  Material \"interface\"\n  Shape \"trianglemesh\" \"point3 P\" [ {} ]\n    \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]\nAttributeEnd\n\
         \n\
         AttributeBegin\n  Material \"diffuse\" \"rgb reflectance\" [ 0.3 0.28 0.25 ]\n  Shape \"trianglemesh\" \"point3 P\" [ {} ] \"integer indices\" [ 0 1 2 0 2 3 ]\nAttributeEnd\n",
        vec3(eye),
        vec3(target),
        vec3(up_v),
        corners.join("  "),
        ground.join("  "),
    )
}

/// A number as a scene gives it: 6 significant digits, no exponent for ordinary sizes.
fn num(v: f64) -> String {
    let s = format!("{:.6}", v);
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

fn vec3(v: DVec3) -> String {
    format!("{} {} {}", num(v.x), num(v.y), num(v.z))
}

pub fn run(a: &SceneArgs) -> firemedium::Result<String> {
    let out = a
        .output
        .clone()
        .unwrap_or_else(|| a.dataset.with_extension("pbrt"));
    if out.exists() && !a.force {
        return Err(Error::file(
            out.display(),
            "exists: give another name with -o, or --force to replace it",
        ));
    }
    let opts = LoadOptions::default();
    let entries = firemedium_dataset::list_grids(&a.dataset, &opts)
        .map_err(|e| Error::input(e.to_string()))?;
    let ds = firemedium_dataset::load_float_grids(&a.dataset, &entries, &opts)
        .map_err(|e| Error::input(e.to_string()))?
        .ok_or_else(|| {
            Error::input(format!(
                "{}: no float grid (density, temperature, …): not a fire dataset",
                a.dataset.display()
            ))
        })?;
    let [lo, hi] = ds.bounds();
    let source = firemedium_dataset::looks_like(&entries, &ds);
    let name = source.as_ref().map(|s| s.0.as_str());
    // Houdini's and EmberGen's worlds are y-up; Blender's, the generator's and the thesis's z-up.
    let up = if matches!(name, Some("houdini" | "embergen")) {
        1
    } else {
        2
    };
    // The dataset as the scene names it: relative to the scene's folder when it lies within it.
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let dataset = relative(&a.dataset, dir);
    let image = out
        .with_extension("exr")
        .file_name()
        .map_or("fire.exr".into(), |f| f.to_string_lossy().into_owned());
    let text = scene_text(
        &dataset,
        lo,
        hi,
        up,
        name.filter(|n| *n != "kelvin"),
        &image,
    );
    firemedium::imageio::write_atomic(&out, |tmp| {
        std::fs::write(tmp, &text)
            .map_err(|e| Error::file(out.display(), format!("cannot write: {e}")))
    })?;
    let why = source.map_or(
        "no tool's conventions recognised: read as density and temperature in kelvin".to_string(),
        |(_, why)| why,
    );
    Ok(format!(
        "wrote {} (the fire's box ({}) … ({}), {} up; {why})\nrender it: firemedium render {}\n",
        out.display(),
        vec3(lo),
        vec3(hi),
        if up == 2 { "z" } else { "y" },
        out.display()
    ))
}

/// `path` as seen from `dir`: relative when `path` lies under `dir` (both made absolute), else absolute.
fn relative(path: &Path, dir: &Path) -> String {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, d) = (abs(path), abs(dir));
    p.strip_prefix(&d)
        .map(|r| r.display().to_string())
        .unwrap_or_else(|_| p.display().to_string())
}
