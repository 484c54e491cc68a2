//! `firemedium farm slurm SCENE --frames A-B --tiles N [--submit]`: a render cut into frames × tiles for a Slurm
//! cluster. It writes, in a job folder, an sbatch job array with one task per frame × tile (each `firemedium
//! render --frame F --pixelbounds 0 W y0 y1`: a horizontal band of the film's rows, the film's size read from the
//! scene by parsing alone), a merge job array with one task per
//! frame (`firemedium merge` of its tiles into the frame's EXR), and `submit.sh`, which submits the merge to
//! start after every render task succeeded (`--dependency=afterok`); `--submit` does what `submit.sh` does.
//!
//! Every task renders with the frame's own seed, and pixels carry their own seeds, so the merged frames equal a
//! local `firemedium render --frames` bit for bit. The job folder and the binary must be on a filesystem every
//! node sees (the scripts name them by absolute path).

use crate::args::{parse_frames, parse_resolution, Frames};
use clap::{Args, Subcommand};
use firemedium::Error;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
pub struct FarmArgs {
    #[command(subcommand)]
    scheduler: Scheduler,
}

#[derive(Debug, Subcommand)]
enum Scheduler {
    /// sbatch job arrays: one render task per frame × tile, then one merge task per frame.
    Slurm(SlurmArgs),
}

#[derive(Debug, Args)]
pub struct SlurmArgs {
    /// The pbrt-v4 scene file.
    scene: PathBuf,
    /// Frames to render, A-B or A-B:STEP (inclusive; `####` or `%04d` in dataset names take each frame).
    #[arg(long, value_name = "A-B[:STEP]", value_parser = parse_frames, allow_hyphen_values = true)]
    frames: Frames,
    /// Tiles per frame: horizontal bands of the film, each a task.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=4096))]
    tiles: u32,
    /// The Slurm partition (default: the cluster's default partition).
    #[arg(long)]
    partition: Option<String>,
    /// CPUs per task (`--cpus-per-task`, and the render's `--threads`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u16).range(1..=1024))]
    cpus: u16,
    /// The frames' EXRs, a name holding #### or %04d (default: beside the scene, SCENE.####.exr).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// The job folder for the scripts, tiles and logs (default: beside the scene, SCENE.farm).
    #[arg(long)]
    dir: Option<PathBuf>,
    /// Samples per pixel (default: the Sampler's).
    #[arg(long)]
    spp: Option<usize>,
    /// Adaptive sampling, as `render --noise-threshold` (each tile's blocks its own).
    #[arg(long, value_name = "T", value_parser = super::render::parse_noise_threshold)]
    noise_threshold: Option<f64>,
    /// As `render --time-limit`: each tile's render stops after the pass that crosses it.
    #[arg(long, value_name = "SECONDS", value_parser = super::render::parse_time_limit)]
    time_limit: Option<f64>,
    /// Seed of the pixel samples (each frame's seed follows from it, as for `render --frames`).
    #[arg(long)]
    seed: Option<u64>,
    /// Film resolution WxH instead of the scene's.
    #[arg(long, value_name = "WxH", value_parser = parse_resolution)]
    resolution: Option<(usize, usize)>,
    /// AOVs, as `render --aov` (merged with the tiles).
    #[arg(long, value_name = "LIST")]
    aov: Option<String>,
    /// Largest job array Slurm accepts (its `MaxArraySize` less one; 1000 by default).
    #[arg(long, default_value_t = 1000)]
    max_array: u64,
    /// Submit the jobs (with `sbatch` from PATH, or this one) instead of only writing them.
    #[arg(long)]
    submit: bool,
    /// The sbatch to submit with.
    #[arg(long, default_value = "sbatch", requires = "submit")]
    sbatch: PathBuf,
}

pub fn run(a: &FarmArgs) -> firemedium::Result<String> {
    match &a.scheduler {
        Scheduler::Slurm(s) => slurm(s),
    }
}

/// `s` as one word of a POSIX shell command.
fn quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// Refuses a path that would leave its place in a job script: a control character (a newline ends the comment
/// or directive it stands in, and the next line runs as a command). Shell words are quoted ([`quote`]); paths
/// reach `#SBATCH` directives never (the logs go to `sbatch --output`, an argument).
fn plain(what: &str, s: &str) -> firemedium::Result<()> {
    match s.char_indices().find(|(_, c)| c.is_control()) {
        Some((i, c)) => Err(Error::value(format!(
                "{what} {s:?}: character {c:?} at byte {i}: expected no control character (it would end its line of the job script)"
            ),
        )),
        None => Ok(()),
    }
}

/// An absolute form of `p` (made from the working directory; the file need not exist yet).
fn absolute(p: &Path) -> firemedium::Result<PathBuf> {
    std::path::absolute(p).map_err(|e| Error::file(p.display(), e.to_string()))
}

/// The options every render task passes on to `firemedium render`.
fn passed_on(a: &SlurmArgs) -> String {
    let mut pass = format!("--threads {}", a.cpus);
    if let Some(n) = a.spp {
        write!(pass, " --spp {n}").ok();
    }
    if let Some(t) = a.noise_threshold {
        write!(pass, " --noise-threshold {t}").ok();
    }
    if let Some(t) = a.time_limit {
        write!(pass, " --time-limit {t}").ok();
    }
    if let Some(s) = a.seed {
        write!(pass, " --seed {s}").ok();
    }
    if let Some((w, h)) = a.resolution {
        write!(pass, " --resolution {w}x{h}").ok();
    }
    if let Some(l) = &a.aov {
        write!(pass, " --aov {}", quote(l)).ok();
    }
    pass
}

fn slurm(a: &SlurmArgs) -> firemedium::Result<String> {
    if !a.scene.is_file() {
        return Err(Error::value(format!(
            "{}: no such scene file",
            a.scene.display()
        )));
    }
    let scene = absolute(&a.scene)?;
    plain("the scene's path", &scene.display().to_string())?;
    if let Some(p) = &a.partition {
        if p.is_empty()
            || !p
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_.,-".contains(c))
        {
            return Err(Error::value(format!("--partition {p:?}: expected partition names of letters, digits and _ . , - (Slurm's)"),
            ));
        }
    }
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    let beside = scene.parent().unwrap_or(Path::new("/")).to_path_buf();
    let dir = absolute(
        &a.dir
            .clone()
            .unwrap_or_else(|| beside.join(format!("{stem}.farm"))),
    )?;
    let output = absolute(
        &a.output
            .clone()
            .unwrap_or_else(|| beside.join(format!("{stem}.####.exr"))),
    )?;
    plain("--dir", &dir.display().to_string())?;
    plain("-o", &output.display().to_string())?;
    let frames = &a.frames.0;
    let outs: Vec<PathBuf> = frames
        .iter()
        .map(|&f| firemedium_dataset::frame_path(&output, Some(f)))
        .collect::<Result<_, _>>()
        .map_err(|e| Error::value(e.to_string()))?;
    if frames.len() > 1 && outs[0] == output {
        return Err(Error::value(format!(
                "-o {}: the name holds no #### or %04d for the frame number: every frame would overwrite it",
                output.display()
            ),
        ));
    }
    // Bands of whole rows: no more tiles than the film has rows (an empty band would fail its task).
    let (cols, rows) = match a.resolution {
        Some(r) => r,
        None => firemedium::render::scene::film_resolution(&scene)?,
    };
    if a.tiles as usize > rows {
        return Err(Error::value(format!(
                "--tiles {}: more bands than the film's {rows} rows (each tile is a band of whole rows)",
                a.tiles
            ),
        ));
    }
    let tiles = a.tiles as u64;
    let tasks = frames.len() as u64 * tiles;
    if tasks > a.max_array {
        return Err(Error::value(format!(
                "{} frames × {tiles} tiles = {tasks} tasks: more than the job array's {} (Slurm's MaxArraySize less one; \
                 split --frames, or raise --max-array to your cluster's)",
                frames.len(),
                a.max_array
            ),
        ));
    }
    let exe = std::env::current_exe()
        .map_err(|e| Error::input(format!("cannot find the firemedium executable: {e}")))?;
    for sub in ["tiles", "logs"] {
        std::fs::create_dir_all(dir.join(sub)).map_err(|e| {
            Error::input(format!("{}: cannot create: {e}", dir.join(sub).display()))
        })?;
    }
    let q = |p: &Path| quote(&p.display().to_string());
    let pass = passed_on(a);
    let list = |v: &[String]| v.join(" ");
    let frame_list = list(&frames.iter().map(|f| f.to_string()).collect::<Vec<_>>());
    // Band k of the film: rows ⌊k·H/T⌋ to ⌊(k+1)·H/T⌋ (pixel bounds: whole numbers, so neighbours meet exactly
    // — crop-window fractions would go through ⌈H·y⌉ and its rounding — and none is empty while T ≤ H).
    let band = |k: u64| (k * rows as u64 / tiles).to_string();
    let y0 = list(&(0..tiles).map(band).collect::<Vec<_>>());
    let y1 = list(&(1..=tiles).map(band).collect::<Vec<_>>());
    let partition = a
        .partition
        .as_ref()
        .map(|p| format!("#SBATCH --partition={p}\n"))
        .unwrap_or_default();
    let tile_name = r#""$(printf 'f%s.t%03d.exr' "$F" "$K")""#;
    let render = format!(
        "#!/bin/bash\n\
         # firemedium farm: {scene}, frames {first}..{last} ({nf}), {tiles} tiles each: one task per frame × tile.\n\
         #SBATCH --job-name=firemedium-render\n\
         #SBATCH --array=0-{last_task}\n\
         #SBATCH --cpus-per-task={cpus}\n\
         {partition}\
         set -eu\n\
         FRAMES=({frame_list})\n\
         Y0=({y0})\n\
         Y1=({y1})\n\
         TASK=${{SLURM_ARRAY_TASK_ID:?run as a Slurm array task, or set SLURM_ARRAY_TASK_ID}}\n\
         F=${{FRAMES[$((TASK / {tiles}))]}}\n\
         K=$((TASK % {tiles}))\n\
         exec {exe} render {qscene} --frame \"$F\" --pixelbounds 0 {cols} \"${{Y0[$K]}}\" \"${{Y1[$K]}}\" {pass} -q \\\n\
         \x20   --log-json {qlog} -o {qtiles}/{tile_name}\n",
        scene = scene.display(),
        first = frames[0],
        last = frames[frames.len() - 1],
        nf = frames.len(),
        last_task = tasks - 1,
        cpus = a.cpus,
        exe = q(&exe),
        qscene = q(&scene),
        qlog = q(&dir.join("logs/render.jsonl")),
        qtiles = q(&dir.join("tiles")),
    );
    let outs_list = list(&outs.iter().map(|o| q(o)).collect::<Vec<_>>());
    let merge = format!(
        "#!/bin/bash\n\
         # firemedium farm: each frame's {tiles} tiles merged into its EXR (after every render task succeeded).\n\
         #SBATCH --job-name=firemedium-merge\n\
         #SBATCH --array=0-{last_frame}\n\
         {partition}\
         set -eu\n\
         FRAMES=({frame_list})\n\
         OUT=({outs_list})\n\
         TASK=${{SLURM_ARRAY_TASK_ID:?run as a Slurm array task, or set SLURM_ARRAY_TASK_ID}}\n\
         F=${{FRAMES[$TASK]}}\n\
         TILES=()\n\
         for ((K = 0; K < {tiles}; K++)); do TILES+=({qtiles}/{tile_name}); done\n\
         exec {exe} merge \"${{TILES[@]}}\" -o \"${{OUT[$TASK]}}\"\n",
        last_frame = frames.len() - 1,
        qtiles = q(&dir.join("tiles")),
        exe = q(&exe),
    );
    let (render_path, merge_path) = (dir.join("render.sbatch"), dir.join("merge.sbatch"));
    // The tasks' logs (Slurm's %A job and %a task): `sbatch --output`, an argument, not a directive in the
    // script (Slurm splits a directive at white space).
    let (render_log, merge_log) = (
        dir.join("logs/render-%A_%a.log"),
        dir.join("logs/merge-%A_%a.log"),
    );
    let submit = format!(
        "#!/bin/bash\n\
         # Submits the render array, then the merge array to start when every render task succeeded.\n\
         set -eu\n\
         R=$(sbatch --parsable --output={rlog} {render})\n\
         M=$(sbatch --parsable --output={mlog} --dependency=afterok:${{R%%;*}} {merge})\n\
         echo \"render job $R, merge job $M\"\n",
        render = q(&render_path),
        merge = q(&merge_path),
        rlog = q(&render_log),
        mlog = q(&merge_log),
    );
    let submit_path = dir.join("submit.sh");
    for (path, text) in [
        (&render_path, &render),
        (&merge_path, &merge),
        (&submit_path, &submit),
    ] {
        write_script(path, text)?;
    }
    let mut out = format!(
        "wrote {} ({tasks} render tasks: {} frames × {tiles} tiles), {} ({} merge tasks) and {}\n",
        render_path.display(),
        frames.len(),
        merge_path.display(),
        frames.len(),
        submit_path.display()
    );
    if a.submit {
        let output = |p: &Path| format!("--output={}", p.display());
        let render_id = sbatch(&a.sbatch, &[&output(&render_log)], &render_path)?;
        let dep = format!("--dependency=afterok:{render_id}");
        let merge_id = sbatch(&a.sbatch, &[&output(&merge_log), &dep], &merge_path)?;
        writeln!(
            out,
            "submitted render job {render_id} and merge job {merge_id} (frames: {})",
            outs.first()
                .map_or(String::new(), |o| o.display().to_string())
                + if outs.len() > 1 { " …" } else { "" }
        )
        .ok();
    } else {
        writeln!(out, "submit with: {}", submit_path.display()).ok();
    }
    Ok(out)
}

/// Writes an executable script.
fn write_script(path: &Path, text: &str) -> firemedium::Result<()> {
    firemedium::imageio::write_atomic(path, |tmp| {
        std::fs::write(tmp, text)
            .map_err(|e| Error::file(path.display(), format!("cannot write: {e}")))?;
        #[cfg(unix)]
        {
            use std::os::unix::fs::PermissionsExt;
            std::fs::set_permissions(tmp, std::fs::Permissions::from_mode(0o755))
                .map_err(|e| Error::file(path.display(), e.to_string()))?;
        }
        Ok(())
    })
}

/// Submits `script` with `sbatch --parsable ARGS`; its job id.
fn sbatch(sbatch: &Path, args: &[&str], script: &Path) -> firemedium::Result<String> {
    let o = std::process::Command::new(sbatch)
        .arg("--parsable")
        .args(args)
        .arg(script)
        .output()
        .map_err(|e| Error::file(sbatch.display(), format!("cannot run: {e}")))?;
    let text = String::from_utf8_lossy(&o.stdout);
    // `--parsable` prints "id" or "id;cluster".
    let id = text.trim().split(';').next().unwrap_or("").to_string();
    if !o.status.success() || id.is_empty() || !id.bytes().all(|b| b.is_ascii_digit()) {
        return Err(Error::input(format!(
            "{} {}: {} {}",
            sbatch.display(),
            script.display(),
            o.status,
            String::from_utf8_lossy(&o.stderr).trim()
        )));
    }
    Ok(id)
}

#[cfg(test)]
mod tests {
    use super::quote;

    #[test]
    fn words_are_quoted_for_the_shell() {
        assert_eq!(quote("a b"), "'a b'");
        assert_eq!(quote("it's"), r"'it'\''s'");
    }
}
