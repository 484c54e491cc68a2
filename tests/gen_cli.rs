//! `firemedium gen` end to end: OpenVDB files of the blob fire model that the dataset reader loads, the same for
//! a seed, species grids that follow the flame, frame sequences, and one-line errors for bad arguments.

use std::path::PathBuf;
use std::process::{Command, Output};

fn run(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_firemedium"))
        .args(args)
        .output()
        .unwrap()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("firemedium-gen-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn ok(o: &Output) -> String {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn info(path: &str, grids: &[&str]) -> serde_json::Value {
    let mut args = vec!["info", path, "--json"];
    for g in grids {
        args.extend(["--grid", g]);
    }
    serde_json::from_str(&ok(&run(&args))).unwrap()
}

#[test]
fn every_kind_writes_a_loadable_physical_fire_and_a_seed_repeats() {
    let dir = tmp("kinds");
    for kind in ["campfire", "candle", "pool", "torch"] {
        let a = dir.join(format!("{kind}_a.vdb"));
        let b = dir.join(format!("{kind}_b.vdb"));
        let c = dir.join(format!("{kind}_c.vdb"));
        let text = ok(&run(&[
            "gen",
            kind,
            "--resolution",
            "32",
            "--frame",
            "24",
            "-o",
            a.to_str().unwrap(),
        ]));
        assert!(
            text.contains("frame 24, t = 1.000 s") && text.contains("active voxels"),
            "{text}"
        );
        ok(&run(&[
            "gen",
            kind,
            "--resolution",
            "32",
            "--frame",
            "24",
            "-o",
            b.to_str().unwrap(),
        ]));
        ok(&run(&[
            "gen",
            kind,
            "--resolution",
            "32",
            "--frame",
            "24",
            "--seed",
            "2",
            "-o",
            c.to_str().unwrap(),
        ]));
        let (fa, fb, fc) = (
            std::fs::read(&a).unwrap(),
            std::fs::read(&b).unwrap(),
            std::fs::read(&c).unwrap(),
        );
        assert!(fa == fb, "{kind}: the same seed gave different files");
        assert!(fa != fc, "{kind}: another seed gave the same file");
        // The dataset reader loads it: soot fractions of a flame, temperatures between ambient and ~2000 K.
        let v = info(a.to_str().unwrap(), &["density", "temperature"]);
        let ch = v["channels"].as_array().unwrap();
        let (d, t) = (&ch[0], &ch[1]);
        let (dmax, tmax) = (d["max"].as_f64().unwrap(), t["max"].as_f64().unwrap());
        eprintln!(
            "{kind}: soot fraction ≤ {dmax:.3e}, T ≤ {tmax:.0} K, dims {}",
            v["dims"]
        );
        assert!(dmax > 1e-8 && dmax < 1e-4, "{kind}: {dmax}");
        assert!(tmax > 1200.0 && tmax < 2600.0, "{kind}: {tmax}");
        assert!(d["min"].as_f64().unwrap() >= 0.0 && t["min"].as_f64().unwrap() >= 0.0);
    }
}

#[test]
fn species_follow_the_flame_and_frames_make_a_sequence() {
    let dir = tmp("species");
    let f = dir.join("torch.####.vdb");
    let text = ok(&run(&[
        "gen",
        "torch",
        "--resolution",
        "24",
        "--frames",
        "10-12",
        "--species",
        "Na:1e17",
        "--species",
        "Li:3e16",
        "-o",
        f.to_str().unwrap(),
    ]));
    assert_eq!(text.matches("wrote ").count(), 3, "{text}");
    for n in 10..=12 {
        let p = dir.join(format!("torch.{n:04}.vdb"));
        assert!(p.is_file(), "{}", p.display());
    }
    let p = dir.join("torch.0012.vdb");
    let v = info(p.to_str().unwrap(), &["Na", "Li", "temperature"]);
    let ch = v["channels"].as_array().unwrap();
    let na = ch[0]["max"].as_f64().unwrap();
    let li = ch[1]["max"].as_f64().unwrap();
    assert!(
        (na / 1e17 - 1.0).abs() < 1e-6 && (li / 3e16 - 1.0).abs() < 1e-6,
        "{na} {li}"
    );
    // Wherever there is sodium there is hot gas.
    assert!(
        ch[0]["active_fraction"].as_f64().unwrap()
            <= ch[2]["active_fraction"].as_f64().unwrap() + 1e-12
    );
}

#[test]
fn bad_arguments_exit_2_with_one_line() {
    let dir = tmp("bad");
    let out = dir.join("x.vdb");
    let out = out.to_str().unwrap();
    for (args, want) in [
        (
            vec!["gen", "bonfire", "-o", out],
            "campfire, candle, pool, torch",
        ),
        (
            vec!["gen", "torch", "-o", out, "--species", "Xx:1e17"],
            "Na, Li",
        ),
        (vec!["gen", "torch", "-o", out, "--species", "Na:-1"], "> 0"),
        (vec!["gen", "torch", "-o", out, "--frames", "5-3"], "A-B"),
        (vec!["gen", "torch", "-o", out, "--frames", "1-3"], "####"),
        (
            vec!["gen", "torch", "-o", out, "--resolution", "2"],
            "resolution",
        ),
    ] {
        let o = run(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {e}");
        assert!(e.lines().count() == 1 && e.contains(want), "{args:?}: {e}");
    }
    // Before the match catches there is nothing to write: exit 1, saying so.
    let o = run(&["gen", "campfire", "-o", out, "--frame", "0"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("no gas"), "{e}");
}

#[test]
fn the_committed_campfire_is_what_the_generator_makes() {
    // scenes/campfire/campfire.vdb was written by the command in its README; the generator is deterministic.
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenes/campfire");
    let out = tmp("campfire").join("campfire.vdb");
    ok(&run(&[
        "gen",
        "campfire",
        "--resolution",
        "96",
        "-o",
        out.to_str().unwrap(),
    ]));
    assert!(
        std::fs::read(&out).unwrap() == std::fs::read(root.join("campfire.vdb")).unwrap(),
        "regenerate it: firemedium gen campfire --resolution 96 -o scenes/campfire/campfire.vdb"
    );
}
