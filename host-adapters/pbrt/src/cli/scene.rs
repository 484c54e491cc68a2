//! `firemedium scene DATASET`: a starter pbrt-v4 scene around a user's fire, so that their first render of their
//! own data is one command away. What the file means is read from its grids' names and its data
//! (`firemedium_dataset::convention`): which grid is the smoke, which the temperature and in what unit, which the
//! flame and the velocity, which way is up, and a soot scale that makes a simulator's density a flame in its smoke.
//! Each choice is printed, one line each with its reason, and written into the scene as an explicit parameter; the
//! camera frames the flame (where the light is); a sequence (`fire_####.vdb`) gets one scene whose box covers
//! every frame. The scene is parsed back before the command says it is done.

use clap::Args;
use firemedium::Error;
use firemedium_core::soot::SootOptics;
use firemedium_dataset::convention::{self, Reading, Unit, Up};
use firemedium_dataset::LoadOptions;
use glam::DVec3;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct SceneArgs {
    /// The fire's dataset (OpenVDB, NanoVDB, or the thesis's formats); `fire_####.vdb` (or `%04d`): a sequence,
    /// every frame on disk.
    dataset: PathBuf,
    /// The scene to write (default: the dataset's name with .pbrt, beside it; for a sequence, without its frame
    /// pattern).
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Replace the scene if it exists.
    #[arg(long)]
    force: bool,
    /// The fire's up axis: x, y, z, -x, -y or -z (default: found from the data — flames rise —, the tool's
    /// convention breaking a tie).
    #[arg(long, value_parser = parse_up, allow_hyphen_values = true)]
    up: Option<Up>,
}

/// Text from the input (a file's grid names, a path) made safe for the terminal.
fn shown(s: &str) -> String {
    firemedium::term::printable(s, firemedium::term::MAX_MESSAGE_CHARS)
}

fn parse_up(s: &str) -> Result<Up, String> {
    Up::parse(s).ok_or_else(|| format!("{}: expected x, y, z, -x, -y or -z", shown(s)))
}

/// A dataset name as a pbrt-v4 string holds it: quotes and backslashes escaped, control characters as escapes
/// (the parser reads `\n`, `\t`, `\r`, `\b`, `\f`); other control characters refused.
fn pbrt_string(s: &str) -> Result<String, String> {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            '\u{8}' => out.push_str("\\b"),
            '\u{c}' => out.push_str("\\f"),
            c if c.is_control() => {
                return Err(format!(
                    "holds the control character U+{:04X}, which a pbrt-v4 string cannot",
                    c as u32
                ))
            }
            c => out.push(c),
        }
    }
    out.push('"');
    Ok(out)
}

/// A comment's text on one line (whatever a reason quotes, no newline starts a directive).
fn comment(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// A parameter's value: 5 significant digits (an exponent for a soot scale's 1e-7).
fn sig(v: f64) -> String {
    if v != 0.0 && (v.abs() < 1e-3 || v.abs() >= 1e6) {
        format!("{v:.4e}")
    } else {
        num((v * 1e4).round() / 1e4)
    }
}

/// A coordinate as a scene gives it: 6 decimals, trailing zeros dropped.
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

/// The axes across the frame and along the camera's line of sight for a fire `up`: the camera looks along the
/// larger-numbered horizontal axis (y when z is up, z when y is up), from its negative side when z is up (the
/// generator's and Blender's front), else from its positive side.
fn view_axes(up: Up) -> (usize, usize, f64) {
    let horizontal: Vec<usize> = (0..3).filter(|&a| a != up.axis).collect();
    let (across, depth) = (horizontal[0], horizontal[1]);
    (across, depth, if up.axis == 2 { -1.0 } else { 1.0 })
}

/// The scene's text for `dataset` (a pbrt-v4 string, quoted) as `reading` reads it.
fn scene_text(dataset: &str, name: &str, r: &Reading, image: &str, sequence: bool) -> String {
    let up = r.up.value;
    let u = up.axis;
    let (across, depth_axis, side) = view_axes(up);
    let [lo, hi] = r.bounds;
    let size = hi - lo;
    // What the camera frames: the glowing gas (where the light is) with a quarter as much again above it and a
    // tenth beside it, inside the data's box; the whole box when nothing glows.
    let [mut flo, mut fhi] = r.flame.unwrap_or(r.bounds);
    let fsize = fhi - flo;
    for a in 0..3 {
        let grow = if a == u { 0.0 } else { 0.1 * fsize[a] };
        flo[a] -= grow;
        fhi[a] += grow;
    }
    if up.down {
        flo[u] -= 0.25 * fsize[u];
    } else {
        fhi[u] += 0.25 * fsize[u];
    }
    let flo = flo.max(lo);
    let fhi = fhi.min(hi);
    let fsize = fhi - flo;
    let centre = 0.5 * (flo + fhi);
    // Far enough that the framed region fills about 80 % of the frame's height (fov 40° on the 16:9 film's
    // shorter side) and of its width; the eye a little above the framed region's middle.
    let (fov, aspect) = (40f64.to_radians(), 16.0 / 9.0);
    let fit = (0.5 * fsize[u] / 0.8).max(0.5 * fsize[across] / (0.8 * aspect)) / (0.5 * fov).tan();
    // From the framed region's centre to the data box's face on the camera's side, then the fit beyond it.
    let to_face = if side < 0.0 {
        centre[depth_axis] - lo[depth_axis]
    } else {
        hi[depth_axis] - centre[depth_axis]
    };
    let distance = fit + to_face.max(0.5 * fsize[depth_axis]);
    let upv = up.vector();
    let mut eye = centre;
    eye[depth_axis] += side * distance;
    eye += 0.15 * distance * upv;
    // The data's bottom along up, and the box's floor a hair above the ground (coplanar faces let rays slip
    // between them).
    let bottom = if up.down { hi[u] } else { lo[u] };
    let gap = 1e-3 * size.max_element();
    let (mut blo, mut bhi) = (lo, hi);
    if up.down {
        bhi[u] -= gap;
    } else {
        blo[u] += gap;
    }
    let corners: Vec<String> = (0..8)
        .map(|c| {
            vec3(DVec3::new(
                if c & 1 == 0 { blo.x } else { bhi.x },
                if c & 2 == 0 { blo.y } else { bhi.y },
                if c & 4 == 0 { blo.z } else { bhi.z },
            ))
        })
        .collect();
    // The ground: a square 20 times the fire's extent, at the data's bottom, facing up.
    let reach = 10.0 * size.max_element();
    let mid = 0.5 * (lo + hi);
    let ground: Vec<String> = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(a, b)| {
            let mut p = mid;
            p[across] += a * reach;
            p[depth_axis] += b * reach;
            p[u] = bottom;
            vec3(p)
        })
        .collect();
    let n = &r.names;
    // One parameter a line, its reason in a comment under it; what is said but not written, a comment alone.
    let mut lines: Vec<(Option<String>, &str)> = vec![
        (
            Some(format!("\"string source\" \"{}\"", n.tool.value.name())),
            &n.tool.why,
        ),
        (
            Some(format!("\"string densitygrid\" \"{}\"", n.smoke.value)),
            &n.smoke.why,
        ),
        (
            Some(format!("\"string temperaturegrid\" \"{}\"", n.heat.value.0)),
            &n.heat.why,
        ),
    ];
    let scale = match r.unit.value {
        Unit::Relative { kelvin_per_unit } => Some(format!(
            "\"float temperaturescale\" {}",
            sig(kelvin_per_unit)
        )),
        Unit::Flame => Some(format!(
            "\"float flameignition\" {} \"float flamemax\" {}",
            num(convention::FLAME_RANGE.0),
            num(convention::FLAME_RANGE.1)
        )),
        Unit::Kelvin => None,
    };
    lines.push((scale, &r.unit.why));
    lines.push((
        Some(format!("\"float sootscale\" {}", sig(r.soot.value))),
        &r.soot.why,
    ));
    let velocity_why;
    if let Some(v) = &n.velocity {
        velocity_why = format!("{}; for a 180° shutter add \"float shutterclose\" 0.5 (frames), and \"float velocityscale\" for the grid's units per metre per second", v.why);
        lines.push((
            Some(format!("\"string velocitygrid\" \"{}\"", v.value)),
            &velocity_why,
        ));
    }
    if let Some(f) = &n.flame {
        lines.push((None, &f.why));
    }
    let mut medium = String::new();
    for (line, why) in lines {
        match line {
            Some(l) => {
                let _ = writeln!(medium, "  {l}\n    # {}", comment(why));
            }
            None => {
                let _ = writeln!(medium, "  # {}", comment(why));
            }
        }
    }
    let frames_note = if sequence {
        "\n# A sequence: render it with --frames A-B (the box covers every frame on disk)."
    } else {
        ""
    };
    format!(
        "# A starter scene for {name} (written by `firemedium scene`): the fire's box fitted to its data, a camera\n\
         # framing its flame, a ground; {up} is up ({why}). docs/reference/params.md lists the fire's parameters;\n\
         # \"float stepsize\" 1 renders faster, `--spp 16` for a first look.{frames_note}\n\
         LookAt {}   {}   {}\n\
         Camera \"perspective\" \"float fov\" 40\n\
         Film \"rgb\" \"integer xresolution\" 640 \"integer yresolution\" 360 \"string filename\" {image}\n\
         Sampler \"zsobol\" \"integer pixelsamples\" 64\n\
         Integrator \"volpath\" \"integer maxdepth\" 3\n\
         \n\
         WorldBegin\n\
         \n\
         MakeNamedMedium \"fire\" \"string type\" \"fire\"\n  \"string dataset\" {dataset}\n{medium}\
         \n\
         AttributeBegin\n  MediumInterface \"fire\" \"\"\n  Material \"interface\"\n  Shape \"trianglemesh\" \"point3 P\" [ {} ]\n    \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]\nAttributeEnd\n\
         \n\
         AttributeBegin\n  Material \"diffuse\" \"rgb reflectance\" [ 0.3 0.28 0.25 ]\n  Shape \"trianglemesh\" \"point3 P\" [ {} ] \"integer indices\" [ {} ]\nAttributeEnd\n",
        vec3(eye),
        vec3(centre),
        vec3(upv),
        corners.join("  "),
        ground.join("  "),
        // Wound so the ground's normal points up (either sign of the axis).
        if ground_faces_up(up) { "0 1 2 0 2 3" } else { "0 2 1 0 3 2" },
        name = comment(name),
        up = up.name(),
        why = comment(&r.up.why),
    )
}

/// Whether the ground's corners, in the order `scene_text` lists them (across, depth: −−, +−, ++, −+), wind
/// counter-clockwise seen from above.
fn ground_faces_up(up: Up) -> bool {
    let (across, depth, _) = view_axes(up);
    let (mut a, mut d) = (DVec3::ZERO, DVec3::ZERO);
    a[across] = 1.0;
    d[depth] = 1.0;
    (a.cross(d).dot(up.vector())) > 0.0
}

/// The frames of a sequence `pattern` (`####` or `%0Nd`) on disk, in order; `None` when it is not a pattern.
fn sequence_frames(pattern: &Path) -> Result<Option<Vec<(i64, PathBuf)>>, Error> {
    let probe = |f: i64| firemedium_dataset::frame_path(pattern, Some(f));
    let base = probe(0).map_err(|e| Error::input(e.to_string()))?;
    if base == pattern {
        return Ok(None);
    }
    let dir = pattern
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let entries = std::fs::read_dir(dir).map_err(|e| {
        Error::file(
            dir.display(),
            format!("cannot list the sequence's folder: {e}"),
        )
    })?;
    let mut frames = Vec::new();
    for e in entries.flatten() {
        let path = dir.join(e.file_name());
        let name = e.file_name().to_string_lossy().into_owned();
        // A frame's name is the pattern's with a number in place of the pattern: try the number the name holds
        // where the pattern's run starts.
        let pat = pattern
            .file_name()
            .map(|p| p.to_string_lossy().into_owned())
            .unwrap_or_default();
        let start = pat.find(['#', '%']).unwrap_or(0);
        if name.len() <= start || !name.is_char_boundary(start) {
            continue;
        }
        let digits: String = name[start..]
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == '-')
            .collect();
        let Ok(f) = digits.parse::<i64>() else {
            continue;
        };
        if probe(f)
            .ok()
            .and_then(|p| p.file_name().map(|n| n.to_os_string()))
            == Some(e.file_name())
        {
            frames.push((f, path));
        }
    }
    frames.sort();
    if frames.is_empty() {
        return Err(Error::file(
            pattern.display(),
            format!(
                "no frame of the sequence on disk (looked in {})",
                dir.display()
            ),
        ));
    }
    Ok(Some(frames))
}

pub fn run(a: &SceneArgs) -> firemedium::Result<String> {
    let frames = sequence_frames(&a.dataset)?;
    let out = a.output.clone().unwrap_or_else(|| {
        let stem = a.dataset.with_extension("pbrt");
        match &frames {
            // fire_####.vdb → fire.pbrt
            Some(_) => {
                let s = stem.to_string_lossy();
                let cut = s.find(['#', '%']).unwrap_or(s.len());
                let head = s[..cut].trim_end_matches(['_', '.', '-']);
                PathBuf::from(format!("{head}.pbrt"))
            }
            None => stem,
        }
    });
    let same = |p: &Path, q: &Path| {
        let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
        abs(p) == abs(q)
    };
    let files: Vec<PathBuf> = match &frames {
        Some(f) => f.iter().map(|(_, p)| p.clone()).collect(),
        None => vec![a.dataset.clone()],
    };
    if files.iter().any(|f| same(f, &out)) {
        return Err(Error::file(
            out.display(),
            "is the dataset itself: give the scene another name with -o",
        ));
    }
    if out.exists() && !a.force {
        return Err(Error::file(
            out.display(),
            "exists: give another name with -o, or --force to replace it",
        ));
    }
    firemedium::imageio::check_writable(&out)?;
    // The dataset as the scene names it: relative to the scene's folder when it lies within it.
    let dir = out
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let dataset = relative(&a.dataset, dir).ok_or_else(|| {
        Error::file(
            a.dataset.display(),
            "is not valid UTF-8: a scene file cannot name it (rename the file)",
        )
    })?;
    let quoted = pbrt_string(&dataset)
        .map_err(|why| Error::file(a.dataset.display(), format!("its name {why}")))?;
    let image_name = out.with_extension("exr");
    let image_name = image_name
        .file_name()
        .map_or("fire.exr".into(), |f| f.to_string_lossy().into_owned());
    let image_name = match &frames {
        Some(_) if !image_name.contains('#') => image_name.replacen(".exr", ".####.exr", 1),
        _ => image_name,
    };
    let image = pbrt_string(&image_name)
        .map_err(|why| Error::file(out.display(), format!("its name {why}")))?;
    let kappa = SootOptics::propane().kappa(550.0, 1.0, 1.39);
    let reading = convention::survey(&files, &LoadOptions::default(), a.up, kappa)
        .map_err(|e| Error::input(e.to_string()))?;
    let text = scene_text(
        &quoted,
        &a.dataset.display().to_string(),
        &reading,
        &image,
        frames.is_some(),
    );
    // The scene parsed back: it is one MakeNamedMedium naming the dataset as written, or the command failed.
    let mut parsed = firemedium_pbrt_parser::Collect::default();
    firemedium_pbrt_parser::parse_str(&out.display().to_string(), &text, dir, &mut parsed)
        .map_err(|e| {
            Error::input(format!(
                "the scene written for {} does not parse back ({e}): a bug, please report it",
                a.dataset.display()
            ))
        })?;
    let names_dataset = parsed.0.iter().any(|(d, _)| match d {
        firemedium_pbrt_parser::Directive::MakeNamedMedium(_, params) => params
            .iter()
            .any(|p| p.name == "dataset" && p.strings() == Some(std::slice::from_ref(&dataset))),
        _ => false,
    });
    if !names_dataset {
        return Err(Error::input(format!(
            "the scene written for {} does not name it when parsed back: a bug, please report it",
            a.dataset.display()
        )));
    }
    firemedium::imageio::write_atomic(&out, |tmp| {
        std::fs::write(tmp, &text)
            .map_err(|e| Error::file(out.display(), format!("cannot write: {e}")))
    })?;
    let n = &reading.names;
    let mut said = format!(
        "wrote {} (the fire's box ({}) … ({}){})\n",
        out.display(),
        vec3(reading.bounds[0]),
        vec3(reading.bounds[1]),
        frames
            .as_ref()
            .map_or(String::new(), |f| format!(", {} frames", f.len()))
    );
    let mut line = |what: &str, why: &str| {
        let _ = writeln!(said, "  {what:<12} {}", shown(why));
    };
    line("source", &n.tool.why);
    line("smoke", &n.smoke.why);
    line("temperature", &n.heat.why);
    line("unit", &reading.unit.why);
    line("up", &reading.up.why);
    line("sootscale", &reading.soot.why);
    if let Some(f) = &n.flame {
        line("flame", &f.why);
    }
    if let Some(v) = &n.velocity {
        line("velocity", &v.why);
    }
    for w in &reading.warnings {
        let _ = writeln!(said, "warning: {}", shown(w));
    }
    let _ = writeln!(
        said,
        "render it: firemedium render {}{}",
        shown(&out.display().to_string()),
        frames.as_ref().map_or(String::new(), |f| format!(
            " --frames {}-{}",
            f[0].0,
            f[f.len() - 1].0
        ))
    );
    Ok(said)
}

/// `path` as seen from `dir`: relative when `path` lies under `dir` (both made absolute), else absolute; `None`
/// when it is not valid UTF-8.
fn relative(path: &Path, dir: &Path) -> Option<String> {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let (p, d) = (abs(path), abs(dir));
    let shown = p.strip_prefix(&d).map(Path::to_path_buf).unwrap_or(p);
    shown.to_str().map(str::to_string)
}
