//! Faults a render survives: failing plugin calls, signals, files that lie about their size or never end,
//! logs and outputs that cannot be written, images past the memory.

use super::*;

#[test]
fn a_plugin_call_that_fails_inside_a_render_is_counted_and_reported() {
    // A plugin (C, through the header) that forwards to the real one but refuses one whole-ray query in five: the
    // render finishes and writes its image (the work is kept), but exits 1 naming how many calls failed and the
    // first one's message, and --stats counts them — never a silent black pixel.
    let dir = tmp("failing");
    let bin = crate::common::exe("firemedium");
    let (real, shim) = shim_plugin(&dir, "failing_plugin.c");
    let scene = small_fire_scene(4);
    std::fs::write(dir.join("f.pbrt"), scene).unwrap();
    let exr = dir.join("f.exr");
    let o = Command::new(&bin)
        .arg("render")
        .arg(dir.join("f.pbrt"))
        .args(["-o", exr.to_str().unwrap(), "--stats", "--plugin"])
        .arg(&shim)
        .env("FIREMEDIUM_REAL_PLUGIN", &real)
        .output()
        .unwrap();
    let (err, stats) = (
        String::from_utf8_lossy(&o.stderr),
        String::from_utf8_lossy(&o.stdout),
    );
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("plugin calls failed during the render")
            && err.contains("failing shim: this query is refused (a test)"),
        "{err}"
    );
    let counted: u64 = stats
        .lines()
        .find_map(|l| l.trim().strip_prefix("plugin calls that failed: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count in\n{stats}"));
    // 8 × 8 pixels × 4 samples, one camera ray each through the fire: about a fifth of them refused.
    assert!(
        (40..=90).contains(&counted),
        "{counted} failed calls\n{err}"
    );
    // Written beside the output, as an interrupted render's tiles are, its record saying it is not complete.
    let written = err
        .split(" so ")
        .nth(1)
        .and_then(|s| s.split(" and ").next())
        .map(PathBuf::from)
        .unwrap_or_else(|| panic!("no path in\n{err}"));
    assert!(written.is_file() && !exr.is_file(), "{}", written.display());
}

#[test]
fn ctrl_c_ends_a_long_render_inside_its_tiles() {
    // One 64×64 tile-sized render at 10⁶ samples per pixel would take hours: SIGINT must end it (Ctrl-C was
    // checked only between tiles, so a stuck tile ignored it), writing what is complete and exiting 130.
    let dir = tmp("interrupt");
    let out = dir.join("i.exr");
    let log = dir.join("i.jsonl");
    let root = crate::common::root();
    let child = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(root.join("scenes/campfire/scene.pbrt"))
        .args([
            "--resolution",
            "16x16",
            "--spp",
            "1000000",
            "--threads",
            "2",
            "-q",
            "--log-json",
        ])
        .arg(&log)
        .arg("-o")
        .arg(&out)
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let status = interrupt(child, &log, "INT");
    assert_eq!(status.code(), Some(130));
    // The finished tiles beside the output, never under its name (a complete frame from an earlier run would
    // be lost), their record saying the render is not complete.
    let partial = dir.join("i.partial.exr");
    assert!(
        partial.is_file() && !out.exists(),
        "the finished tiles are written beside the output"
    );
    let (_, meta) = firemedium::imageio::read_meta(&partial).unwrap();
    assert!(
        meta.iter().any(|(k, v)| k == "complete" && v == "false"),
        "{meta:?}"
    );
}

#[test]
fn an_image_claiming_a_huge_size_is_refused_before_it_is_read() {
    // A real 1×1 EXR whose data window is patched to claim 100 000² pixels (a few hundred bytes): as a light
    // map it must be an error naming the size against the memory budget, not a 120 GB allocation that aborts.
    let dir = tmp("bomb");
    exr_claiming(&dir.join("bomb.exr"), 100_000);
    let scene = "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nLightSource \"infinite\" \"string filename\" \"bomb.exr\"\n";
    std::fs::write(dir.join("b.pbrt"), scene).unwrap();
    let e = refused(&dir.join("b.pbrt"), &["--max-memory", "2"]);
    assert!(
        e.contains("b.pbrt:4:1: infinite light:")
            && e.contains("a 100000×100000 image needs 120000000000 bytes"),
        "{e}"
    );
}

#[test]
fn files_that_never_end_are_refused_not_read() {
    // /dev/zero never ends and a FIFO blocks its reader forever: as a dataset, an Include or a mesh each must
    // be an error naming it, promptly (bounded waits: a hang fails the test instead of stalling it).
    let dir = tmp("endless");
    let fifo = dir.join("fifo.vdb");
    let made = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(made.success());
    let cases = [
        ("dataset", "Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"string dataset\" \"/dev/zero\" \"string format\" \"vdb\"\n".to_string()),
        ("fifo", format!("Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"string dataset\" \"{}\"\n", fifo.display())),
        ("include", "Camera \"perspective\"\nWorldBegin\nInclude \"/dev/zero\"\n".to_string()),
        ("plymesh", "Camera \"perspective\"\nWorldBegin\nShape \"plymesh\" \"string filename\" \"/dev/zero\"\n".to_string()),
    ];
    for (name, text) in cases {
        let path = dir.join(format!("{name}.pbrt"));
        std::fs::write(&path, text).unwrap();
        let mut child = Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(&path)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let mut waited = 0;
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            if waited > 300 {
                let _ = child.kill();
                panic!("{name}: still reading after 30 s");
            }
            std::thread::sleep(std::time::Duration::from_millis(100));
            waited += 1;
        };
        let mut e = String::new();
        std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut e).unwrap();
        assert_eq!(status.code(), Some(1), "{name}: {e}");
        assert!(e.contains("not a regular file"), "{name}: {e}");
    }
}

#[test]
fn escape_sequences_and_huge_tokens_from_a_scene_never_reach_the_terminal_raw() {
    // A scene string holding ESC[2J ESC[31m was printed raw on stderr (clearing the terminal), and a 5 MB token
    // echoed whole: both are escaped or cut in the error.
    let dir = tmp("term");
    let scene = dir.join("t.pbrt");
    std::fs::write(
        &scene,
        "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"\u{1b}[2J\u{1b}[31mbogus\"\n",
    )
    .unwrap();
    let o = Command::new(crate::common::exe("firemedium"))
        .args(["render", "-o"])
        .arg(dir.join("t.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && !err.contains('\u{1b}') && err.contains("\\u{1b}[2J"),
        "{err:?}"
    );
    std::fs::write(
        &scene,
        format!("WorldBegin\nShape \"{}\"\n", "x".repeat(5_000_000)),
    )
    .unwrap();
    let o = Command::new(crate::common::exe("firemedium"))
        .args(["render", "-o"])
        .arg(dir.join("t.exr"))
        .arg(&scene)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.len() < 10_000 && err.contains("more characters"),
        "{} bytes: {}",
        err.len(),
        &err[..err.len().min(300)]
    );
}

#[test]
fn ctrl_c_ends_a_path_that_would_bounce_for_hours() {
    // maxdepth 1e8 in an albedo-1 medium 10⁴ mean free paths deep: one path scatters ~10⁸ times (Russian roulette
    // acts at surfaces only). SIGINT is checked at every bounce, so the render stops with exit 130 instead of
    // finishing the path (it ran on 44 s after SIGINT before). SIGTERM (what Slurm sends at a time limit) and
    // SIGHUP too (they ended the render writing nothing), each exiting as the shell reports that signal: 128 + it.
    for (signal, code) in [("INT", 130), ("TERM", 143), ("HUP", 129)] {
        interrupt_a_long_path(signal, code);
    }
}

#[test]
fn a_log_that_cannot_be_written_is_said_once_and_the_render_goes_on() {
    // `--log-json /dev/full`: every event was lost without a word.
    let dir = tmp("log-full");
    let scene = sky_scene(&dir, 4);
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(&scene)
        .args(["-q", "--log-json", "/dev/full", "-o"])
        .arg(dir.join("s.exr"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert_eq!(
        err.matches("--log-json /dev/full: cannot write").count(),
        1,
        "{err}"
    );
    assert!(dir.join("s.exr").is_file());
}

#[test]
fn an_image_within_the_budget_but_past_the_memory_is_an_error_not_an_abort() {
    // A 1×1 EXR patched to claim 30 000² pixels (10.8 GB of f32 RGB): within a budget of half a large machine,
    // it aborted `tonemap` (SIGABRT) when its pixels were allocated infallibly. Under an address-space limit
    // that cannot hold them, the allocation fails and says so.
    let dir = tmp("bomb-within");
    exr_claiming(&dir.join("bomb.exr"), 30_000);
    let o = Command::new("bash")
        .arg("-c")
        .arg(format!(
            "ulimit -v 4000000 && exec '{}' tonemap bomb.exr -o bomb.png",
            crate::common::exe("firemedium").display()
        ))
        .current_dir(&*dir)
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("bomb.exr") && e.contains("more than this machine can give"),
        "{e}"
    );
    // `--max-memory` holds every command that reads images to the user's budget (they were held to half the
    // machine whatever the flag): refused from the header, naming the file and the bytes.
    for args in [
        &["tonemap", "bomb.exr", "-o", "bomb.png"][..],
        &["merge", "bomb.exr", "-o", "merged.exr"],
        &["diff", "bomb.exr", "bomb.exr"],
    ] {
        let o = firemedium_in(&dir, &[args, &["--max-memory", "1"]].concat());
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(
            e.contains("bomb.exr")
                && e.contains("30000×30000")
                && e.contains("above the memory budget of 1000000000 bytes"),
            "{args:?}: {e}"
        );
    }
}

#[test]
fn scene_images_are_held_to_the_renders_memory_budget() {
    // A PNG of 4 000² zero pixels (a few kilobytes) as an infinite light's map: its 192 MB of pixels were checked
    // against half the machine, not `--max-memory` (a 16 000² one took 7 GB with `--max-memory 1`).
    let dir = tmp("image-budget");
    {
        let f = std::fs::File::create(dir.join("sky.png")).unwrap();
        let mut enc = png::Encoder::new(std::io::BufWriter::new(f), 4000, 4000);
        enc.set_color(png::ColorType::Grayscale);
        enc.set_depth(png::BitDepth::Eight);
        let mut w = enc.write_header().unwrap();
        w.write_image_data(&vec![0u8; 4000 * 4000]).unwrap();
    }
    assert!(std::fs::metadata(dir.join("sky.png")).unwrap().len() < 1_000_000);
    let scene = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nLightSource \"infinite\" \"string filename\" \"sky.png\"\n";
    std::fs::write(dir.join("s.pbrt"), scene).unwrap();
    let e = refused(&dir.join("s.pbrt"), &["--max-memory", "0.1"]);
    assert!(
        e.contains("s.pbrt:5:1: infinite light:")
            && e.contains("a 4000×4000 image needs 192000000 bytes"),
        "{e}"
    );
}

#[test]
fn an_output_that_cannot_be_written_fails_before_the_scene_is_loaded() {
    // A missing folder, a folder named as the image, a "folder" that is a file: each refused at once, naming the
    // path, before any loading or rendering — the scene here would take minutes, and its dataset does not even
    // exist, so only an early check can give this message.
    let dir = tmp("unwritable");
    std::fs::write(dir.join("plain.txt"), "not a folder").unwrap();
    std::fs::write(
        dir.join("slow.pbrt"),
        "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4000 \"integer yresolution\" 4000\nSampler \"independent\" \"integer pixelsamples\" 100000\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"string dataset\" \"missing.vdb\"\n",
    )
    .unwrap();
    for (out, says) in [
        ("nowhere/fire.exr", "does not exist"),
        (".", "is a folder"),
        ("plain.txt/fire.exr", "does not exist"),
    ] {
        let o = firemedium_in(&dir, &["render", "slow.pbrt", "-q", "-o", out]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{out}: {err}");
        assert!(
            err.contains(out.trim_end_matches("/fire.exr")) && err.contains(says),
            "{out}: {err}"
        );
        assert!(
            !err.contains("missing.vdb"),
            "{out}: the scene was loaded first: {err}"
        );
    }
    // Without -o, the film's own name is checked after the scene is read and before the render.
    std::fs::write(
        dir.join("film.pbrt"),
        "Camera \"perspective\"\nFilm \"rgb\" \"string filename\" \"gone/out.exr\" \"integer xresolution\" 4000 \"integer yresolution\" 4000\nSampler \"independent\" \"integer pixelsamples\" 100000\nWorldBegin\nLightSource \"infinite\"\n",
    )
    .unwrap();
    let o = firemedium_in(&dir, &["render", "film.pbrt", "-q"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("gone/out.exr") && err.contains("does not exist"),
        "{err}"
    );
}

/// Waits (bounded: 120 s) for a render started with `--log-json log` to say it is loaded and handles its
/// signals (its "rendering" event; a fixed delay lost the race on a loaded machine), sends it `SIG{signal}`, and
/// waits (bounded: 60 s, a hang guard, not a timing assertion) for its exit status.
fn interrupt(mut child: std::process::Child, log: &Path, signal: &str) -> std::process::ExitStatus {
    let mut waited = 0;
    while !std::fs::read_to_string(log).is_ok_and(|t| t.contains("\"rendering\"")) {
        assert!(
            waited < 1200 && child.try_wait().unwrap().is_none(),
            "no \"rendering\" event in {} within 120 s",
            log.display()
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
        waited += 1;
    }
    std::thread::sleep(std::time::Duration::from_millis(200));
    assert!(Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap()
        .success());
    let mut waited = 0;
    loop {
        if let Some(s) = child.try_wait().unwrap() {
            return s;
        }
        assert!(
            waited < 600,
            "the render did not stop within 60 s of SIG{signal}"
        );
        std::thread::sleep(std::time::Duration::from_millis(100));
        waited += 1;
    }
}

/// `firemedium render scene args…` (writing beside the scene), which must fail with exit 1: its stderr.
fn refused(scene: &Path, args: &[&str]) -> String {
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(scene)
        .args(args)
        .arg("-o")
        .arg(scene.with_extension("exr"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{e}");
    e
}

/// A real 1×1 EXR at `path` whose data and display windows are patched to claim `side`² pixels.
fn exr_claiming(path: &Path, side: i32) {
    write_exr_map(path, 1, 1, |_, _| 1.0);
    let mut bytes = std::fs::read(path).unwrap();
    for name in [&b"dataWindow\0box2i\0"[..], &b"displayWindow\0box2i\0"[..]] {
        let at = bytes.windows(name.len()).position(|w| w == name).unwrap() + name.len() + 4;
        // box2i: xMin, yMin, xMax, yMax (i32, little-endian).
        bytes[at + 8..at + 12].copy_from_slice(&(side - 1).to_le_bytes());
        bytes[at + 12..at + 16].copy_from_slice(&(side - 1).to_le_bytes());
    }
    std::fs::write(path, &bytes).unwrap();
}

fn interrupt_a_long_path(signal: &str, code: i32) {
    let dir = tmp(&format!("long-path-{signal}"));
    let scene = dir.join("p.pbrt");
    std::fs::write(
        &scene,
        "LookAt 0 0 -2000  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 1\nFilm \"rgb\" \"integer xresolution\" 2 \"integer yresolution\" 2\nSampler \"independent\" \"integer pixelsamples\" 16\nIntegrator \"volpath\" \"integer maxdepth\" 100000000\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"spectrum sigma_a\" [200 0 900 0] \"spectrum sigma_s\" [200 10 900 10]\nAttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1000\nAttributeEnd\n",
    )
    .unwrap();
    let log = dir.join("p.jsonl");
    let child = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(&scene)
        .args(["--threads", "2", "-q", "--log-json"])
        .arg(&log)
        .arg("-o")
        .arg(dir.join("p.exr"))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let status = interrupt(child, &log, signal);
    assert_eq!(status.code(), Some(code), "SIG{signal}");
    assert!(
        dir.join("p.partial.exr").is_file(),
        "SIG{signal}: the finished tiles"
    );
}
