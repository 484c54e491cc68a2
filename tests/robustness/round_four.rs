//! Hardening, round four: a host never dies through the plugin, a finished render is never lost, old hosts keep
//! working. One test per class of fault found; each failed on the code before its fix.

use crate::common::{exe, root, scratch::Scratch};
use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn firemedium(dir: &Path, args: &[&OsStr]) -> Output {
    Command::new(exe("firemedium"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

fn os(s: &str) -> &OsStr {
    OsStr::new(s)
}

/// A scene of the campfire in `dir`, named `name` (any bytes), its film 8×6.
fn campfire_scene(dir: &Path, name: &OsStr) -> PathBuf {
    std::fs::copy(
        root().join("scenes/campfire/campfire.vdb"),
        dir.join("campfire.vdb"),
    )
    .unwrap();
    let text = "LookAt 0 -3 0.8  0 0 0.8  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 6\nSampler \"independent\" \"integer pixelsamples\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"campfire.vdb\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.2\nAttributeEnd\n";
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Class A: text a format cannot hold. A scene whose name holds characters past U+00FF, or bytes that are not
/// UTF-8, renders to an EXR whose record holds the name (UTF-8 bytes), which `diff` and `merge` read back; it
/// panicked writing the EXR after the whole render ("exr::Text contains unsupported characters").
#[test]
fn a_scene_named_in_any_script_renders_and_its_record_reads_back() {
    let dir = Scratch::new("round4", "text");
    let mut names: Vec<PathBuf> = ["火焰€🔥.pbrt", "ünïcødé.pbrt"]
        .iter()
        .map(PathBuf::from)
        .collect();
    names.push(PathBuf::from(OsStr::from_bytes(b"bad\xff\xfe.pbrt")));
    for (i, name) in names.iter().enumerate() {
        let scene = campfire_scene(&dir, name.as_os_str());
        let out = dir.join(format!("out{i}.exr"));
        let o = firemedium(
            &dir,
            &[
                os("render"),
                scene.as_os_str(),
                os("-o"),
                out.as_os_str(),
                os("-q"),
                os("--log-json"),
                os("log.jsonl"),
            ],
        );
        assert!(
            o.status.success(),
            "{}: {}",
            name.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        let d = firemedium(&dir, &[os("diff"), out.as_os_str(), out.as_os_str()]);
        assert!(d.status.success(), "{}", String::from_utf8_lossy(&d.stderr));
    }
    let record = std::fs::read(dir.join("out0.exr")).unwrap();
    let want = "火焰€🔥.pbrt".as_bytes();
    assert!(
        record.windows(want.len()).any(|w| w == want),
        "the record holds the scene's name as UTF-8"
    );
}

/// Class E: `scene` writes names into pbrt unescaped. A dataset named with a quote, a backslash or a newline gives
/// a scene that parses back to the same name and renders; a name with a control character pbrt cannot hold is
/// refused, naming it.
#[test]
fn dataset_names_are_escaped_in_the_scene_or_refused() {
    let dir = Scratch::new("round4", "names");
    let src = root().join("scenes/campfire/campfire.vdb");
    for name in ["quo\"te.vdb", "back\\slash.vdb", "new\nline WorldBegin.vdb"] {
        std::fs::copy(&src, dir.join(name)).unwrap();
        let o = firemedium(
            &dir,
            &[os("scene"), os(name), os("-o"), os("s.pbrt"), os("--force")],
        );
        assert!(
            o.status.success(),
            "{name:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let text = std::fs::read_to_string(dir.join("s.pbrt")).unwrap();
        // One WorldBegin directive: the name's is inside a string and a comment.
        assert_eq!(
            text.lines().filter(|l| l.starts_with("WorldBegin")).count(),
            1,
            "{text}"
        );
        assert!(!text.lines().any(|l| l.starts_with("line")), "{text}");
        let o = firemedium(
            &dir,
            &[
                os("render"),
                os("s.pbrt"),
                os("--resolution"),
                os("8x6"),
                os("--spp"),
                os("1"),
                os("-q"),
            ],
        );
        assert!(
            o.status.success(),
            "{name:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    std::fs::copy(&src, dir.join("bell\u{7}.vdb")).unwrap();
    let o = firemedium(&dir, &[os("scene"), os("bell\u{7}.vdb")]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(1) && err.contains("U+0007") && !err.contains('\u{7}'),
        "{err}"
    );
}

/// Class G: work lost at the last step. A legal output name of 250 bytes: render, tonemap, merge, bake, gen and
/// scene finish and write it (their temporaries always fit); a name of 256 bytes is refused before any work,
/// naming why.
#[test]
fn long_output_names_are_written_or_refused_before_the_work() {
    let dir = Scratch::new("round4", "long");
    let scene = campfire_scene(&dir, os("s.pbrt"));
    let long = |ext: &str| format!("{}{ext}", "n".repeat(250 - ext.len()));
    let too_long = |ext: &str| format!("{}{ext}", "n".repeat(256 - ext.len()));
    let exr = long(".exr");
    let ok = |args: &[&str]| {
        let args: Vec<&OsStr> = args.iter().map(|a| os(a)).collect();
        let o = firemedium(&dir, &args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    ok(&["render", scene.to_str().unwrap(), "-o", &exr, "-q"]);
    assert!(dir.join(&exr).is_file() && dir.join(long(".png")).is_file());
    ok(&["tonemap", &exr, "-o", &long(".tm.png")]);
    ok(&[
        "render",
        "s.pbrt",
        "-o",
        "tile.exr",
        "-q",
        "--cropwindow",
        "0",
        "1",
        "0",
        "1",
    ]);
    ok(&["merge", "tile.exr", "-o", &long(".m.exr")]);
    ok(&["bake", "campfire.vdb", "-o", &long(".vdb")]);
    ok(&["scene", "campfire.vdb", "-o", &long(".pbrt")]);
    for args in [
        vec!["render", "s.pbrt", "-o", &too_long(".exr") as &str, "-q"],
        vec!["tonemap", &exr, "-o", &too_long(".png")],
        vec!["merge", "tile.exr", "-o", &too_long(".exr")],
        vec!["bake", "campfire.vdb", "-o", &too_long(".vdb")],
        vec!["gen", "candle", "-o", &too_long(".vdb")],
        vec!["scene", "campfire.vdb", "-o", &too_long(".pbrt")],
    ] {
        let args: Vec<&OsStr> = args.iter().map(|a| os(a)).collect();
        let start = std::time::Instant::now();
        let o = firemedium(&dir, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.code() == Some(1) && err.contains("longer than the 255"),
            "{args:?}: {err}"
        );
        // (Refused before the work: no render, no simulation.)
        assert!(start.elapsed().as_secs_f64() < 20.0, "{args:?}");
    }
}

/// A 16³ file with a fire at `t` K and sodium and potassium grids, in `dir`.
fn species_file(dir: &Path, name: &str, t: f32) {
    let n = 16;
    let v = |x: f32| vec![x; n * n * n];
    let grids: Vec<(&str, [usize; 3], Vec<f32>)> = vec![
        ("density", [n; 3], v(1e-7)),
        ("temperature", [n; 3], v(t)),
        ("Na", [n; 3], v(1e18)),
        ("K", [n; 3], v(1e18)),
    ];
    let list: Vec<(&str, [usize; 3], &[f32])> = grids
        .iter()
        .map(|(g, d, v)| (*g, *d, v.as_slice()))
        .collect();
    let bytes = firemedium_dataset::vdb::write(&list, glam::DVec3::ZERO, glam::DVec3::splat(0.01));
    std::fs::write(dir.join(name), bytes).unwrap();
}

/// Class B: memory the budget does not see. Two species and 4096 bins through the plugin, as a host builds them:
/// the temperature tables (each species' σ and j, and their range maxima) are counted against the budget before
/// one is built, and refused in well under 30 s naming them, their bytes and the budget — where the host was
/// killed (SIGABRT at 6–7 GB) after minutes.
#[test]
fn temperature_tables_past_the_budget_are_refused_before_they_are_built() {
    use firemedium_loader::{Context, Param, Plugin, Value};
    let dir = Scratch::new("round4", "tables");
    // SAFETY: the plugin this cargo invocation built.
    let plugin = unsafe { Plugin::load(crate::common::plugin_file()) }.unwrap();
    for (t, budget) in [(3300.0, Some(100_000_000u64)), (50_000.0, None)] {
        let file = dir.join(format!("na{t}.vdb"));
        species_file(&dir, file.file_name().unwrap().to_str().unwrap(), t);
        let params = vec![
            Param::string("filename", file.to_str().unwrap()),
            Param {
                name: "species".into(),
                value: Value::String(vec!["Na".into(), "K".into()]),
                at: None,
            },
            Param::int("bins", 4096),
            // (Boxed lines: the species' temperature tables themselves, not the thick lines' own, which were
            // already counted.)
            Param::string("lineshape", "box"),
        ];
        let context = Context {
            max_bytes: budget,
            ..Context::default()
        };
        let start = std::time::Instant::now();
        let err = plugin
            .create_volume_with(&params, &context)
            .map(|_| ())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("the temperature tables")
                && err.contains("4096 channels")
                && err.contains("bytes"),
            "{t} K: {err}"
        );
        assert!(
            start.elapsed().as_secs_f64() < 30.0,
            "{t} K: {:?}",
            start.elapsed()
        );
    }
}

/// A cube of soot at `t` K (8³ voxels of 10 cm) in `dir`.
fn hot_cube(dir: &Path, name: &str, t: f32) -> PathBuf {
    let n = 8;
    let (d, temp) = (vec![1e-6f32; n * n * n], vec![t; n * n * n]);
    let bytes = firemedium_dataset::vdb::write(
        &[("density", [n; 3], &d), ("temperature", [n; 3], &temp)],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.1),
    );
    std::fs::write(dir.join(name), bytes).unwrap();
    dir.join(name)
}

/// Class F: silent NaN or black for extreme but legal numbers. A fire at 1e9 K integrates finite; hotter is
/// refused naming its temperature and the range (at 1e30 K the radiance was NaN with FM_OK); a wavelength of
/// 1e-61 nm is refused naming it and the range (its emission was NaN), 1 nm and 1e6 nm answer finite; ray
/// directions of length 1e-201 or 1e301 are refused naming their length (they silently missed the fire), 1e-100
/// and 1e100 see what a unit direction sees.
#[test]
fn extreme_numbers_answer_finite_or_are_refused_by_name() {
    use firemedium_loader::{Param, Plugin, Point, Ray};
    let dir = Scratch::new("round4", "extremes");
    // SAFETY: the plugin this cargo invocation built.
    let plugin = unsafe { Plugin::load(crate::common::plugin_file()) }.unwrap();
    let volume = |t: f32| {
        let file = hot_cube(&dir, &format!("t{t:e}.vdb"), t);
        plugin.create_volume(&[
            Param::string("filename", file.to_str().unwrap()),
            Param::float("sootscale", 1.0),
        ])
    };
    let ray = |d: f64| Ray {
        origin: [0.4, -1.0, 0.4],
        direction: [0.0, d, 0.0],
        tmin: 0.0,
        tmax: f64::INFINITY,
        seed: 0,
    };
    let v = volume(1e9).unwrap();
    let c = v.info().channels as usize;
    let mut rad = vec![0f32; c];
    v.integrate(&[ray(1.0)], &mut rad, None, None).unwrap();
    assert!(
        rad.iter().all(|x| x.is_finite()) && rad.iter().any(|&x| x > 0.0),
        "{rad:?}"
    );
    let unit = rad.clone();
    for d in [1e-100, 1e100] {
        v.integrate(&[ray(d)], &mut rad, None, None).unwrap();
        for (a, b) in rad.iter().zip(&unit) {
            assert!((a / b - 1.0).abs() < 1e-4, "direction {d}: {a} against {b}");
        }
    }
    for d in [1e-201, 1e301, 0.0] {
        let e = v
            .integrate(&[ray(d)], &mut rad, None, None)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("ray 0") && e.contains("expected a length from 1e-150 to 1e150"),
            "{d}: {e}"
        );
    }
    let mut out = vec![Point::default(); 2];
    for (lambdas, ok) in [
        ([550.0, 1e-61], false),
        ([1.0, 1e6], true),
        ([550.0, 2e6], false),
    ] {
        let r = v.point(&[[0.4, 0.4, 0.4]], None, &lambdas, &mut out);
        match (r, ok) {
            (Ok(()), true) => assert!(
                out.iter().all(|p| [p.sigma_a, p.sigma_s, p.le, p.j]
                    .iter()
                    .all(|x| x.is_finite())),
                "{out:?}"
            ),
            (Err(e), false) => {
                let e = e.to_string();
                assert!(
                    e.contains("lambdas[1]") && e.contains("expected wavelengths from 1 nm"),
                    "{e}"
                );
            }
            (r, _) => panic!("{lambdas:?}: {r:?}"),
        }
    }
    for t in [1e19f32, 1e30] {
        let e = volume(t).map(|_| ()).unwrap_err().to_string();
        assert!(
            e.contains("K (its grid's hottest voxel") && e.contains("to 1e9 K"),
            "{t}: {e}"
        );
    }
}

/// Class I, the smaller ones: a value echoed back never carries a terminal escape sequence (clap quoted it raw);
/// `gen --species Na:1e300` is refused (it wrote a grid of NaN and exited 0); `bake` refuses a 17 KB file of
/// constant tiles whose grids would need 19 GB at once, from its header's bricks (it built the whole fire first,
/// 8–16 s).
#[test]
fn smaller_refusals_come_before_the_work_and_echo_no_escapes() {
    let dir = Scratch::new("round4", "smaller");
    let esc = "\u{1b}[2J\u{1b}]0;pwned\u{7}";
    for args in [
        vec!["render", "x.pbrt", "--spp", esc],
        vec!["gen", "candle", "--resolution", esc],
        vec!["scene", "x.vdb", "--up", esc],
        vec!["tonemap", "x.exr", "--operator", esc],
    ] {
        let args: Vec<&OsStr> = args.iter().map(|a| os(a)).collect();
        let o = firemedium(&dir, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {err}");
        assert!(
            !err.contains('\u{1b}') && !err.contains('\u{7}'),
            "{args:?}: {err:?}"
        );
        assert!(err.contains("\\u{1b}"), "{args:?}: {err:?}");
    }
    let o = firemedium(
        &dir,
        &[
            os("gen"),
            os("candle"),
            os("--species"),
            os("Na:1e300"),
            os("-o"),
            os("n.vdb"),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(2) && err.contains("PEAK ≤ 2.5e25"),
        "{err}"
    );
    assert!(!dir.join("n.vdb").exists());
    // 1024 × 1024 × 512 voxels of constant tiles, two grids: under 300 KB on disk (OpenVDB's own writer makes the
    // same 18 KB).
    let tiles: Vec<firemedium_dataset::vdb::VdbTile> = (0..8)
        .flat_map(|x| {
            (0..8).flat_map(move |y| (0..4).map(move |z| ([128 * x, 128 * y, 128 * z], 128, 0.0)))
        })
        .collect();
    let with = |v: f32| tiles.iter().map(|&(o, s, _)| (o, s, v)).collect::<Vec<_>>();
    let bytes = firemedium_dataset::vdb::write_tiled(
        &[
            ("density", vec![], with(1e-7)),
            ("temperature", vec![], with(1500.0)),
        ],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    assert!(bytes.len() < 300 * 1024, "{}", bytes.len());
    std::fs::write(dir.join("tiles.vdb"), bytes).unwrap();
    let o = firemedium(
        &dir,
        &[
            os("bake"),
            os("tiles.vdb"),
            os("-o"),
            os("t-firemedium.vdb"),
            os("--max-memory"),
            os("4"),
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(1)
            && err.contains("1048576 bricks")
            && err.contains("memory budget"),
        "{err}"
    );
    assert!(!dir.join("t-firemedium.vdb").exists());
}
