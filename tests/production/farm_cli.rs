//! `firemedium farm slurm` without a cluster: the job scripts it writes, run by bash as Slurm would run each array
//! task (`SLURM_ARRAY_TASK_ID`), render the tiles and merge them into frames equal to a local `render --frames`
//! bit for bit (`firemedium diff`); `--submit` hands the merge to sbatch with a dependency on the render array.
//! The same flow on a real one-node Slurm cluster is `tests/slurm-e2e.sh` (run by `.ci/run`).

use std::path::Path;
use std::process::Command;

use crate::common::scratch;

/// The test's scratch folder (removed when it passes).
fn tmp(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("farm", name)
}

fn run_in(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(crate::common::exe("firemedium"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn ok(o: &std::process::Output) -> String {
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    String::from_utf8_lossy(&o.stdout).into_owned()
}

const SCENE: &str = "LookAt 0 -3 0.6  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40 \"float shutteropen\" 0 \"float shutterclose\" 0.5\nFilm \"rgb\" \"integer xresolution\" 20 \"integer yresolution\" 15 \"string filename\" \"torch.####.exr\"\nSampler \"zsobol\" \"integer pixelsamples\" 2\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"torch.####.vdb\" \"string fuel\" \"propane\" \"string velocitygrid\" \"vel\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n";

/// A 16³ torch over `frames` with its velocity, and the scene rendering it, in `dir`.
fn torch(dir: &Path, frames: &str) {
    ok(&run_in(
        dir,
        &[
            "gen",
            "torch",
            "--resolution",
            "16",
            "--frames",
            frames,
            "--velocity",
            "-o",
            "torch.####.vdb",
        ],
    ));
    std::fs::write(dir.join("torch.pbrt"), SCENE).unwrap();
}

#[test]
fn farm_scripts_render_tiles_that_merge_into_the_local_frames() {
    let dir = tmp("scripts");
    torch(&dir, "30-31");
    let out = ok(&run_in(
        &dir,
        &[
            "farm",
            "slurm",
            "torch.pbrt",
            "--frames",
            "30-31",
            "--tiles",
            "15",
            "--aov",
            "fire,alpha",
            "--partition",
            "render",
        ],
    ));
    // As many bands as the film (20 × 15) has rows: one row each, none empty, none lost.
    assert!(
        out.contains("30 render tasks: 2 frames × 15 tiles"),
        "{out}"
    );
    let farm = dir.join("torch.farm");
    let render = std::fs::read_to_string(farm.join("render.sbatch")).unwrap();
    for line in [
        "#SBATCH --array=0-29",
        "--pixelbounds 0 20",
        "#SBATCH --partition=render",
        "--aov 'fire,alpha'",
    ] {
        assert!(render.contains(line), "{line} not in\n{render}");
    }
    // Each array task as Slurm would start it.
    let bash = |script: &str, task: usize| {
        let o = Command::new("bash")
            .arg(farm.join(script))
            .env("SLURM_ARRAY_TASK_ID", task.to_string())
            .output()
            .unwrap();
        ok(&o);
    };
    for task in 0..30 {
        bash("render.sbatch", task);
    }
    for task in 0..2 {
        bash("merge.sbatch", task);
    }
    ok(&run_in(
        &dir,
        &[
            "render",
            "torch.pbrt",
            "--frames",
            "30-31",
            "--aov",
            "fire,alpha",
            "-q",
            "-o",
            "local.####.exr",
        ],
    ));
    for f in ["0030", "0031"] {
        let o = run_in(
            &dir,
            &["diff", &format!("torch.{f}.exr"), &format!("local.{f}.exr")],
        );
        let text = ok(&o);
        assert!(
            text.contains("the same render") && text.contains("7 channels"),
            "{text}"
        );
    }
    // diff tells renders apart: another frame differs in its record, then in its pixels.
    let o = run_in(&dir, &["diff", "torch.0030.exr", "local.0031.exr"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("frame 30 vs 31"));
    // A task started outside an array says so.
    let o = Command::new("bash")
        .arg(farm.join("render.sbatch"))
        .env_remove("SLURM_ARRAY_TASK_ID")
        .output()
        .unwrap();
    assert!(
        !o.status.success()
            && String::from_utf8_lossy(&o.stderr).contains("run as a Slurm array task")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// An adaptive farm: the scripts carry the threshold and the time limit, each tile adapts on its own, and the
/// tiles merge into a frame whose record names the sampling.
#[test]
fn adaptive_farm_tiles_carry_their_sampling_and_merge() {
    let dir = tmp("adaptive");
    torch(&dir, "30-30");
    ok(&run_in(
        &dir,
        &[
            "farm",
            "slurm",
            "torch.pbrt",
            "--frames",
            "30-30",
            "--tiles",
            "3",
            "--spp",
            "64",
            "--noise-threshold",
            "0.5",
            "--time-limit",
            "600",
        ],
    ));
    let farm = dir.join("torch.farm");
    let render = std::fs::read_to_string(farm.join("render.sbatch")).unwrap();
    assert!(
        render.contains("--noise-threshold 0.5 --time-limit 600"),
        "{render}"
    );
    for (script, tasks) in [("render.sbatch", 3), ("merge.sbatch", 1)] {
        for task in 0..tasks {
            ok(&Command::new("bash")
                .arg(farm.join(script))
                .env("SLURM_ARRAY_TASK_ID", task.to_string())
                .output()
                .unwrap());
        }
    }
    // The merged frame's header records how it was sampled.
    let exr = std::fs::read(dir.join("torch.0030.exr")).unwrap();
    let needle = b"noise_threshold 0.5 time_limit 600";
    assert!(exr.windows(needle.len()).any(|w| w == needle));
}

#[test]
fn submit_makes_the_merge_wait_for_every_render_task() {
    let dir = tmp("submit");
    std::fs::write(dir.join("s.pbrt"), SCENE).unwrap();
    // A stand-in sbatch: records its arguments, answers a job id as `--parsable` does.
    let fake = dir.join("sbatch");
    std::fs::write(
        &fake,
        format!(
            "#!/bin/sh\necho \"$@\" >> '{}'\nn=$(wc -l < '{}')\necho \"$((100 + n));cluster\"\n",
            dir.join("calls").display(),
            dir.join("calls").display()
        ),
    )
    .unwrap();
    Command::new("chmod").arg("+x").arg(&fake).status().unwrap();
    let out = ok(&run_in(
        &dir,
        &[
            "farm",
            "slurm",
            "s.pbrt",
            "--frames",
            "1-4:3",
            "--tiles",
            "2",
            "--submit",
            "--sbatch",
            fake.to_str().unwrap(),
        ],
    ));
    assert!(
        out.contains("submitted render job 101 and merge job 102"),
        "{out}"
    );
    let calls = std::fs::read_to_string(dir.join("calls")).unwrap();
    let lines: Vec<&str> = calls.lines().collect();
    assert!(
        lines[0].starts_with("--parsable ") && lines[0].ends_with("render.sbatch"),
        "{calls}"
    );
    assert!(
        lines[1].contains("--dependency=afterok:101") && lines[1].ends_with("merge.sbatch"),
        "{calls}"
    );
    let merge = std::fs::read_to_string(dir.join("s.farm/merge.sbatch")).unwrap();
    assert!(
        merge.contains("FRAMES=(1 4)") && merge.contains("s.0004.exr"),
        "{merge}"
    );
    // Refused: more tasks than a job array holds, an output without a frame pattern, a failing sbatch.
    let o = run_in(
        &dir,
        &[
            "farm", "slurm", "s.pbrt", "--frames", "1-600", "--tiles", "2",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("1200 tasks"));
    let o = run_in(
        &dir,
        &[
            "farm", "slurm", "s.pbrt", "--frames", "1-2", "--tiles", "16",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("film's 15 rows"));
    let o = run_in(
        &dir,
        &[
            "farm", "slurm", "s.pbrt", "--frames", "1-2", "-o", "one.exr",
        ],
    );
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no #### or %04d"));
    let o = run_in(
        &dir,
        &[
            "farm",
            "slurm",
            "s.pbrt",
            "--frames",
            "1-2",
            "--submit",
            "--sbatch",
            "/bin/false",
        ],
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("/bin/false"));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn farm_scripts_run_nothing_a_file_name_or_partition_smuggles_in() {
    // A newline in the scene's file name ended the job script's comment line, and the name's next line ran when
    // the job ran; `--partition` likewise ended its `#SBATCH` line. Both are refused, naming the character; quotes,
    // `$` and backticks in a name stay inside its quoted word, and the scripts run nothing else.
    let dir = tmp("inject");
    let evil = "a\ntouch INJECTED_NL\n.pbrt";
    std::fs::write(dir.join(evil), SCENE).unwrap();
    let o = run_in(&dir, &["farm", "slurm", evil, "--frames", "1-1"]);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && msg.contains("'\\n' at byte"),
        "{msg}"
    );
    std::fs::write(dir.join("s.pbrt"), SCENE).unwrap();
    for partition in ["render\ntouch INJECTED_P", "a b", "$(touch INJECTED_S)", ""] {
        let o = run_in(
            &dir,
            &[
                "farm",
                "slurm",
                "s.pbrt",
                "--frames",
                "1-1",
                "--partition",
                partition,
            ],
        );
        let msg = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.code() == Some(2) && msg.contains("--partition"),
            "{partition:?}: {msg}"
        );
    }
    // Quotes, `$` and backticks in the name: the render script quotes it, so running the task passes the name
    // whole (its render then stops at the scene's missing dataset) and touches nothing.
    let odd = "it's $(touch INJECTED_D) `touch INJECTED_B`.pbrt";
    std::fs::write(dir.join(odd), SCENE).unwrap();
    ok(&run_in(
        &dir,
        &["farm", "slurm", odd, "--frames", "1-1", "--dir", "odd"],
    ));
    let script = dir.join("odd/render.sbatch");
    let text = std::fs::read_to_string(&script).unwrap();
    assert!(!text.contains("#SBATCH --output"), "{text}");
    let o = Command::new("bash")
        .arg(&script)
        .current_dir(&*dir)
        .env("SLURM_ARRAY_TASK_ID", "0")
        .output()
        .unwrap();
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(msg.contains(odd) && msg.contains("torch.0001.vdb"), "{msg}");
    for name in [
        "INJECTED_NL",
        "INJECTED_P",
        "INJECTED_S",
        "INJECTED_D",
        "INJECTED_B",
    ] {
        assert!(!dir.join(name).exists(), "{name} was created");
    }
}
