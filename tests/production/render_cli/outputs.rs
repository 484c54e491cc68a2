//! What a render leaves: frames, tiles that merge bit for bit, AOVs, the JSON log, finished and unfinished
//! frames, the EXR's colour space.

use super::*;

#[test]
fn skip_existing_renders_again_what_is_not_a_finished_frame() {
    // `--skip-existing` took any file under the name for a finished frame: truncated, empty and text EXRs, and
    // one an interrupted render wrote, were "left out". Now only an EXR that reads whole and whose record says
    // complete is; the others are rendered again, saying why.
    let dir = tmp("skip-broken");
    let scene = sky_scene(&dir, 8);
    let run = |frame: &str| {
        Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(&scene)
            .args(["--frame", frame, "--skip-existing", "-o"])
            .arg(dir.join("f.####.exr"))
            .output()
            .unwrap()
    };
    let o = run("1");
    assert!(o.status.success());
    let good = std::fs::read(dir.join("f.0001.exr")).unwrap();
    let o = run("1");
    assert!(String::from_utf8_lossy(&o.stdout).contains("exists, left out"));
    // A complete EXR whose record says interrupted, a truncated one, an empty one, a text file.
    let mut interrupted = good.clone();
    // (The record is one text attribute of key=value lines.)
    let at = interrupted
        .windows(b"complete=true".len())
        .position(|w| w == b"complete=true")
        .expect("the record's complete line");
    interrupted[at + 9..at + 13].copy_from_slice(b"nope");
    for (k, bytes) in [
        (2, interrupted),
        (3, good[..good.len() / 2].to_vec()),
        (4, Vec::new()),
        (5, b"not an exr".to_vec()),
    ] {
        let f = dir.join(format!("f.{k:04}.exr"));
        std::fs::write(&f, &bytes).unwrap();
        let o = run(&k.to_string());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.success()
                && err.contains("is not a finished frame")
                && err.contains("rendering it again"),
            "frame {k}: {err}"
        );
        assert!(
            std::fs::read(&f).unwrap().len() > 1000,
            "frame {k} rendered again"
        );
    }
}

#[test]
fn the_same_render_gives_the_same_pixels_and_cleans_up_after_killed_writers() {
    // Farms and caches compare renders: two renders of one scene on 2 threads must hold the same pixels and record
    // (the EXR's blocks were once written in completion order), their files differing in the render time alone. A temporary left by a killed writer (its PID gone) is removed
    // by the next write of the same file.
    let dir = tmp("bytes");
    let root = crate::common::root();
    let stale = dir.join("a.tmp-4194400.exr");
    std::fs::write(&stale, b"left by a killed render").unwrap();
    let mut files = Vec::new();
    for name in ["a.exr", "b.exr"] {
        let out = dir.join(name);
        let o = Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(root.join("scenes/campfire/scene.pbrt"))
            .args([
                "--resolution",
                "48x32",
                "--spp",
                "2",
                "--threads",
                "2",
                "-q",
                "-o",
            ])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        files.push(out);
    }
    assert!(
        same_render(&files[0], &files[1]),
        "two identical renders wrote different pixels or records"
    );
    // The bytes differ only in the render time: the files are the same length or the time's digits apart.
    let len = |p: &Path| std::fs::metadata(p).unwrap().len() as i64;
    assert!((len(&files[0]) - len(&files[1])).abs() <= 4);
    assert!(!stale.exists(), "the stale temporary is still there");
}

/// The generator's torch, `gen` = (voxels, frames A-B, stem), written into `dir` as `stem.####.vdb`, and a scene
/// over the sequence, `scene` = (its file name, the Film's parameters, samples per pixel): the fire in a sphere,
/// `####` in its dataset's name.
fn torch_sequence(dir: &Path, gen: (&str, &str, &str), scene: (&str, &str, usize)) {
    let ((res, frames, stem), (name, film, spp)) = (gen, scene);
    let vdb = format!("{stem}.####.vdb");
    let args = [
        "gen",
        "torch",
        "--resolution",
        res,
        "--frames",
        frames,
        "-o",
        &vdb,
    ];
    let o = firemedium_in(dir, &args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(
        dir.join(name),
        format!("LookAt 0 -3 0.6  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" {film}\nSampler \"independent\" \"integer pixelsamples\" {spp}\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"{vdb}\" \"string fuel\" \"propane\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n"),
    )
    .unwrap();
}

#[test]
fn frames_render_a_sequence_one_seed_per_frame() {
    // Three frames of the generator's torch; `####` in the dataset and output names takes each frame.
    let dir = tmp("frames");
    let run = |args: &[&str]| firemedium_in(&dir, args);
    let film = "\"integer xresolution\" 24 \"integer yresolution\" 24 \"string filename\" \"seq.####.exr\"";
    torch_sequence(&dir, ("16", "30-32", "torch"), ("seq.pbrt", film, 2));
    let o = run(&["render", "seq.pbrt", "--frames", "30-32"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // Off a terminal: progress and each finished frame as plain lines.
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("firemedium: frame 31 done in") && err.contains("% ("),
        "{err}"
    );
    let frames: Vec<PathBuf> = (30..=32)
        .map(|f| dir.join(format!("seq.00{f}.exr")))
        .collect();
    assert!(
        read_exr(&frames[0]) != read_exr(&frames[1])
            && read_exr(&frames[1]) != read_exr(&frames[2])
    );
    // A frame rendered alone is the sequence's frame, byte for byte (its seed follows from the frame).
    let o = run(&[
        "render",
        "seq.pbrt",
        "--frame",
        "31",
        "-o",
        "alone.exr",
        "-q",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(same_render(&dir.join("alone.exr"), &frames[1]));
    // Existing outputs are left out, saying so; a name without a pattern would overwrite itself.
    let o = run(&[
        "render",
        "seq.pbrt",
        "--frames",
        "30-32:2",
        "--skip-existing",
        "-q",
    ]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success() && out.matches("exists, left out").count() == 2,
        "{out}"
    );
    let o = run(&["render", "seq.pbrt", "--frames", "30-32", "-o", "one.exr"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("holds no #### or %04d"));
    let o = run(&["render", "seq.pbrt", "--frames", "32-30"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("expected A-B or A-B:STEP"));
}

#[test]
fn tiles_merge_into_the_full_frame_bit_for_bit() {
    // Four crop-window tiles of a small fire scene merge into the full render's pixels exactly; overlapping
    // tiles, a tile of another seed and a missing tile are refused, naming the file.
    let dir = tmp("merge");
    let nvdb = crate::common::root().join("tests/data/valid/nvdb/plume48.nvdb");
    std::fs::write(
        dir.join("fire.pbrt"),
        format!(
            "LookAt 0 -3 0.3  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 16\nSampler \"independent\" \"integer pixelsamples\" 2\nIntegrator \"volpath\" \"integer maxdepth\" 2\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.05 0.05 0.06]\nMakeNamedMedium \"kaboom\" \"string type\" \"nanovdb\" \"string filename\" \"{}\" \"spectrum sigma_a\" [200 10 900 10] \"spectrum sigma_s\" [200 5 900 5] \"float Lescale\" 5 \"float temperaturecutoff\" 1 \"float temperaturescale\" 1.5\nAttributeBegin\nMediumInterface \"kaboom\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
            nvdb.display()
        ),
    )
    .unwrap();
    let run = |args: &[&str]| firemedium_in(&dir, args);
    let ok = |o: std::process::Output| {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    ok(run(&[
        "render",
        "fire.pbrt",
        "-q",
        "--seed",
        "5",
        "-o",
        "full.exr",
    ]));
    let quads = [
        ("0", "0.5", "0", "0.5"),
        ("0.5", "1", "0", "0.5"),
        ("0", "0.5", "0.5", "1"),
        ("0.5", "1", "0.5", "1"),
    ];
    let mut tiles = Vec::new();
    for (k, (x0, x1, y0, y1)) in quads.iter().enumerate() {
        let name = format!("tile{k}.exr");
        ok(run(&[
            "render",
            "fire.pbrt",
            "-q",
            "--seed",
            "5",
            "--cropwindow",
            x0,
            x1,
            y0,
            y1,
            "-o",
            &name,
        ]));
        tiles.push(name);
    }
    let mut args = vec!["merge"];
    args.extend(tiles.iter().rev().map(String::as_str));
    args.extend(["-o", "merged.exr"]);
    ok(run(&args));
    let (full, merged) = (
        read_exr(&dir.join("full.exr")),
        read_exr(&dir.join("merged.exr")),
    );
    assert_eq!((merged.0, merged.1), (24, 16));
    assert!(
        full.2 == merged.2,
        "the merged frame must equal the full render"
    );
    assert!(full.2.iter().any(|p| p[0] > 0.0));
    // Refused: an overlap, another seed's tile, a gap.
    let o = run(&[
        "merge", &tiles[0], &tiles[0], &tiles[1], &tiles[2], &tiles[3], "-o", "x.exr",
    ]);
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("overlaps"));
    ok(run(&[
        "render",
        "fire.pbrt",
        "-q",
        "--seed",
        "6",
        "--cropwindow",
        "0.5",
        "1",
        "0.5",
        "1",
        "-o",
        "other.exr",
    ]));
    let o = run(&[
        "merge",
        &tiles[0],
        &tiles[1],
        &tiles[2],
        "other.exr",
        "-o",
        "x.exr",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("other.exr") && e.contains("seed 5 vs 6"),
        "{e}"
    );
    let o = run(&["merge", &tiles[0], &tiles[1], &tiles[2], "-o", "x.exr"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("leave pixel (12, 8)"),
        "{e}"
    );
    // A tile whose record says its render was interrupted (as an interrupted render writes it).
    let mut bytes = std::fs::read(dir.join(&tiles[3])).unwrap();
    let at = bytes
        .windows(b"complete=true".len())
        .position(|w| w == b"complete=true")
        .expect("the record's complete line");
    bytes[at + 9..at + 13].copy_from_slice(b"nope");
    std::fs::write(dir.join("cut.exr"), &bytes).unwrap();
    let o = run(&[
        "merge", &tiles[0], &tiles[1], &tiles[2], "cut.exr", "-o", "x.exr",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("cut.exr") && e.contains("interrupted"),
        "{e}"
    );
    // One flipped byte in a tile's pixels (the last block's last value's high byte): merged silently before, one
    // pixel −1.2e15; now an error (the checksum in its record, or the file unreadable).
    let mut bytes = std::fs::read(dir.join(&tiles[3])).unwrap();
    let last = bytes.len() - 1;
    bytes[last] ^= 0x80;
    std::fs::write(dir.join("flipped.exr"), &bytes).unwrap();
    let o = run(&[
        "merge",
        &tiles[0],
        &tiles[1],
        &tiles[2],
        "flipped.exr",
        "-o",
        "x.exr",
    ]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("flipped.exr") && !dir.join("x.exr").exists(),
        "{e}"
    );
    eprintln!("one flipped byte: {e}");
    // The record the EXRs carry (read back with the `exr` crate): what the render was.
    let (win, meta) = firemedium::imageio::read_meta(&dir.join("merged.exr")).unwrap();
    assert_eq!((win.origin, win.full), ((0, 0), (24, 16)));
    let get = |k: &str| {
        meta.iter()
            .find(|m| m.0 == k)
            .map(|m| m.1.clone())
            .unwrap_or_default()
    };
    assert_eq!(
        (get("seed"), get("spp"), get("frame")),
        ("5".into(), "2".into(), "none".into())
    );
    assert!(get("scene").ends_with("fire.pbrt"));
    assert_eq!(get("camera_to_world").split_whitespace().count(), 12);
    assert_eq!(
        get("plugin_abi"),
        format!(
            "{}.{}",
            firemedium_abi::ABI_MAJOR,
            firemedium_abi::ABI_MINOR
        )
    );
    assert!(
        get("camera").starts_with("perspective fov 40")
            && get("camera").contains("screenwindow -1.5 1.5 -1 1"),
        "{}",
        get("camera")
    );
    assert!(get("render_seconds").parse::<f64>().unwrap() > 0.0);
}

#[test]
fn aovs_split_the_beauty_and_merge_with_the_tiles() {
    // A scattering, emitting plume above a grey floor under a dim sky: the fire's emission, the sky seen
    // directly, and direct and indirect light all appear; the four sum to R, G, B. Alpha is 1 on the floor,
    // 0 on the empty sky, between through the plume; depth, normal and albedo are the floor's.
    let dir = tmp("aovs");
    let nvdb = crate::common::root().join("tests/data/valid/nvdb/plume48.nvdb");
    std::fs::write(
        dir.join("aov.pbrt"),
        format!(
            "LookAt 0 -3 0.2  0 0 -0.2  0 0 1\nCamera \"perspective\" \"float fov\" 50\nFilm \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24 \"string filename\" \"aov.exr\"\nSampler \"zsobol\" \"integer pixelsamples\" 8\nIntegrator \"volpath\" \"integer maxdepth\" 3\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.05 0.05 0.06]\nMakeNamedMedium \"kaboom\" \"string type\" \"nanovdb\" \"string filename\" \"{}\" \"spectrum sigma_a\" [200 10 900 10] \"spectrum sigma_s\" [200 5 900 5] \"float Lescale\" 5 \"float temperaturecutoff\" 1 \"float temperaturescale\" 1.5\nAttributeBegin\nMediumInterface \"kaboom\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\nAttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\nShape \"trianglemesh\" \"point3 P\" [-20 -20 -1.05  20 -20 -1.05  20 20 -1.05  -20 20 -1.05] \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n",
            nvdb.display()
        ),
    )
    .unwrap();
    let run = |args: &[&str]| firemedium_in(&dir, args);
    let o = run(&["render", "aov.pbrt", "-q", "--aov", "all"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (w, h, ch) = exr_channels(&dir.join("aov.exr"));
    for name in [
        "R",
        "G",
        "B",
        "A",
        "fire.R",
        "emission.G",
        "direct.B",
        "indirect.R",
        "depth.Z",
        "albedo.G",
        "normal.Z",
        "samples.Y",
    ] {
        assert!(ch.contains_key(name), "no channel {name}: {:?}", ch.keys());
    }
    let c = |n: &str| &ch[n];
    // The four parts sum to the beauty, channel by channel.
    let peak = c("R").iter().cloned().fold(0f32, f32::max);
    for k in ["R", "G", "B"] {
        for i in 0..w * h {
            let sum: f32 = ["fire", "emission", "direct", "indirect"]
                .iter()
                .map(|p| c(&format!("{p}.{k}"))[i])
                .sum();
            let beauty = c(k)[i];
            assert!(
                (sum - beauty).abs() <= 1e-5 * peak + 1e-4 * beauty.abs(),
                "pixel {i} {k}: parts {sum} vs beauty {beauty}"
            );
        }
        for p in ["fire", "emission", "direct", "indirect"] {
            let total: f32 = c(&format!("{p}.{k}")).iter().sum();
            assert!(total > 0.0, "{p}.{k} is black");
        }
    }
    // Floor pixels (the bottom row), sky pixels (the top corners: no plume there).
    let floor = w / 2 + w * (h - 1);
    let sky = 0;
    assert_eq!(c("A")[floor], 1.0);
    assert_eq!(c("A")[sky], 0.0);
    let plume = w / 2 + w * (h / 3);
    assert!(
        c("A")[plume] > 0.0 && c("A")[plume] <= 1.0,
        "{}",
        c("A")[plume]
    );
    assert!(c("depth.Z")[floor].is_finite() && c("depth.Z")[floor] > 1.0);
    assert!(c("depth.Z")[sky].is_infinite());
    assert!(c("normal.Z")[floor] > 0.999, "{}", c("normal.Z")[floor]);
    for k in ["R", "G", "B"] {
        let a = c(&format!("albedo.{k}"))[floor];
        assert!((a - 0.5).abs() < 0.02, "albedo.{k} {a}");
    }
    assert!(c("samples.Y").iter().all(|&n| n == 8.0));
    // Two crop-window tiles with their AOVs merge into the full frame's channels, bit for bit.
    for (name, y0, y1) in [("top.exr", "0", "0.5"), ("bottom.exr", "0.5", "1")] {
        let o = run(&[
            "render",
            "aov.pbrt",
            "-q",
            "--aov",
            "all",
            "--cropwindow",
            "0",
            "1",
            y0,
            y1,
            "-o",
            name,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let o = run(&["merge", "top.exr", "bottom.exr", "-o", "merged.exr"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (_, _, merged) = exr_channels(&dir.join("merged.exr"));
    assert_eq!(merged.len(), ch.len());
    for (name, v) in &ch {
        let m = &merged[name];
        assert!(
            v.iter().zip(m).all(|(a, b)| a.to_bits() == b.to_bits()),
            "merged {name} differs"
        );
    }
    // A tile without the AOVs is refused.
    let o = run(&[
        "render",
        "aov.pbrt",
        "-q",
        "--cropwindow",
        "0",
        "1",
        "0.5",
        "1",
        "-o",
        "plain.exr",
    ]);
    assert!(o.status.success());
    let o = run(&["merge", "top.exr", "plain.exr", "-o", "x.exr"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && e.contains("plain.exr"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn log_json_records_each_event_as_a_line() {
    // A farm reads `--log-json`: start, progress and done per frame, skipped frames, and the error that ends a
    // render (here frame 33, whose dataset does not exist), one JSON object per line, appended.
    let dir = tmp("logjson");
    let run = |args: &[&str]| firemedium_in(&dir, args);
    let film = "\"integer xresolution\" 40 \"integer yresolution\" 40";
    torch_sequence(&dir, ("12", "31-32", "t"), ("s.pbrt", film, 1));
    let o = run(&[
        "render",
        "s.pbrt",
        "--frames",
        "31-32",
        "-o",
        "s.####.exr",
        "-q",
        "--log-json",
        "log.jsonl",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "render",
        "s.pbrt",
        "--frames",
        "31-33",
        "-o",
        "s.####.exr",
        "-q",
        "--skip-existing",
        "--log-json",
        "log.jsonl",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let text = std::fs::read_to_string(dir.join("log.jsonl")).unwrap();
    let events: Vec<serde_json::Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    let of = |kind: &str| -> Vec<&serde_json::Value> {
        events.iter().filter(|e| e["event"] == kind).collect()
    };
    let done: Vec<i64> = of("done")
        .iter()
        .map(|e| e["frame"].as_i64().unwrap())
        .collect();
    assert_eq!(done, vec![31, 32], "{text}");
    assert!(of("done")
        .iter()
        .all(|e| e["width"] == 40 && e["spp"] == 1 && e["seconds"].as_f64().unwrap() > 0.0));
    // 40×40 pixels are 9 tiles: progress at most every tenth, some of them reported.
    assert!(
        of("progress")
            .iter()
            .any(|e| e["frame"] == 32 && e["tiles"] == 9),
        "{text}"
    );
    let skipped: Vec<i64> = of("skipped")
        .iter()
        .map(|e| e["frame"].as_i64().unwrap())
        .collect();
    assert_eq!(skipped, vec![31, 32], "{text}");
    let errors = of("error");
    assert!(
        errors.len() == 1
            && errors[0]["code"] == 1
            && errors[0]["frame"] == 33
            && errors[0]["message"]
                .as_str()
                .unwrap()
                .contains("t.0033.vdb"),
        "{text}"
    );
    assert_eq!(of("start").len(), 5, "{text}");
}

#[test]
fn the_exr_names_its_colour_space_and_acescg_holds_the_flame_positive() {
    // A flame's colour lies outside sRGB: the default EXR (linear Rec.709, pbrt-v4's) holds it as negative
    // components and the render says how much; `--colorspace acescg` writes ACES AP1, where it is positive. Both
    // files carry their chromaticities; `tonemap` reads the ACEScg one back to the same preview.
    let dir = tmp("colorspace");
    let scene = crate::common::root().join("scenes/campfire/scene.pbrt");
    let render = |out: &str, extra: &[&str]| {
        let mut args = vec![
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "48x27",
            "--spp",
            "4",
            "-o",
            out,
        ];
        args.extend_from_slice(extra);
        let o = firemedium_in(&dir, &args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let said = render("srgb.exr", &[]);
    assert!(
        said.contains("% of its pixels hold colour outside sRGB as negative components"),
        "{said}"
    );
    let said = render("aces.exr", &["--colorspace", "acescg"]);
    assert!(!said.contains("outside sRGB"), "{said}");
    let chroma = |f: &str| {
        let meta = exr::meta::MetaData::read_from_file(dir.join(f), false).unwrap();
        let c = meta.headers[0]
            .shared_attributes
            .chromaticities
            .expect("chromaticities");
        (c.red.0, c.green.1, c.white.0)
    };
    assert_eq!(chroma("srgb.exr"), (0.64, 0.60, 0.3127));
    assert_eq!(chroma("aces.exr"), (0.713, 0.830, 0.32168));
    let negative = |f: &str| {
        let img = firemedium::imageio::read(&dir.join(f), false).unwrap();
        img.px.iter().filter(|p| p.iter().any(|&c| c < 0.0)).count() as f64 / img.px.len() as f64
    };
    let (s, a) = (negative("srgb.exr"), negative("aces.exr"));
    // (A few dim pixels stay outside AP1 too: noise in the bins of light barely there.)
    assert!(
        s > 0.3 && a < 0.1 * s,
        "negative pixels: sRGB {s}, ACEScg {a}"
    );
    for (exr, png) in [("srgb.exr", "s.png"), ("aces.exr", "a.png")] {
        let o = firemedium_in(&dir, &["tonemap", exr, "-o", png]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let (pa, pb) = (
        std::fs::read(dir.join("s.png")).unwrap(),
        std::fs::read(dir.join("a.png")).unwrap(),
    );
    assert!(pa == pb, "the ACEScg EXR tone-maps to another picture");
}

/// Every channel of an EXR's first part by name (the `exr` crate, as a compositor reads it), its size, and its
/// attributes' names.
fn exr_channels(path: &Path) -> (usize, usize, std::collections::HashMap<String, Vec<f32>>) {
    use exr::prelude::*;
    let img = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .unwrap();
    let size = img.layer_data.size;
    let map = img
        .layer_data
        .channel_data
        .list
        .iter()
        .map(|c| (c.name.to_string(), c.sample_data.values_as_f32().collect()))
        .collect();
    (size.width(), size.height(), map)
}
