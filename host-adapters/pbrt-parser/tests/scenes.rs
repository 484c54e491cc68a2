//! The parser on real pbrt-v4 scene files (tests/data/pbrt), Includes, cycles, and mutated input.

use firemedium_pbrt_parser::{parse_file, parse_str, Collect, Directive};
use std::path::{Path, PathBuf};

fn scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/data/pbrt")
        .join(name)
}

fn parse(name: &str) -> Result<Collect, firemedium_pbrt_parser::ParseError> {
    let mut c = Collect::default();
    parse_file(&scene(name), &mut c).map(|_| c)
}

#[test]
fn explosion_fire_scene() {
    let c = parse("explosion.pbrt").unwrap();
    let d: Vec<&Directive> = c.0.iter().map(|x| &x.0).collect();
    assert!(matches!(d[0], Directive::LookAt(v) if v[1] == 120.0 && v[3] == -0.5));
    assert!(d.iter().any(|x| matches!(x, Directive::Integrator(t, p) if t == "volpath" && p[0].numbers() == Some(&[5.0][..]))));
    let medium = d
        .iter()
        .find_map(|x| match x {
            Directive::MakeNamedMedium(n, p) => Some((n, p)),
            _ => None,
        })
        .unwrap();
    assert_eq!(medium.0, "kaboom");
    let names: Vec<&str> = medium.1.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "type",
            "filename",
            "sigma_s",
            "sigma_a",
            "LeScale",
            "temperaturecutoff",
            "temperaturescale"
        ]
    );
    assert_eq!(medium.1[2].numbers(), Some(&[200.0, 10.0, 900.0, 10.0][..]));
    assert!(d
        .iter()
        .any(|x| matches!(x, Directive::MediumInterface(i, o) if i == "kaboom" && o.is_empty())));
    assert!(d
        .iter()
        .any(|x| matches!(x, Directive::Material(t, _) if t == "interface")));
    // Positions: the medium is on line 29.
    let loc =
        &c.0.iter()
            .find(|x| matches!(x.0, Directive::MakeNamedMedium(..)))
            .unwrap()
            .1;
    assert_eq!((loc.line, loc.col), (29, 1));
}

#[test]
fn the_other_shared_scenes() {
    for name in ["bunny-cloud.pbrt", "clouds.pbrt"] {
        let c = parse(name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            c.0.iter()
                .any(|x| matches!(&x.0, Directive::MakeNamedMedium(..))),
            "{name}"
        );
        assert!(
            c.0.iter().any(|x| matches!(&x.0, Directive::WorldBegin)),
            "{name}"
        );
    }
    // clouds.pbrt has `Material ""`.
    let c = parse("clouds.pbrt").unwrap();
    assert!(c
        .0
        .iter()
        .any(|x| matches!(&x.0, Directive::Material(t, _) if t.is_empty())));
}

#[test]
fn a_missing_include_names_file_and_line() {
    let e = parse("killeroo-simple.pbrt").unwrap_err();
    assert_eq!((e.loc.line, e.loc.col), (55, 5));
    let s = e.to_string();
    assert!(
        s.contains("killeroo-simple.pbrt:55:5: Include \"geometry/killeroo.pbrt\": cannot read")
            && s.contains("geometry/killeroo.pbrt"),
        "{s}"
    );
}

#[test]
fn includes_resolve_relative_to_the_including_file_and_cycles_stop() {
    let dir = std::env::temp_dir().join(format!("firemedium-pbrt-{}-include", std::process::id()));
    std::fs::create_dir_all(dir.join("sub")).unwrap();
    std::fs::write(
        dir.join("main.pbrt"),
        "WorldBegin\nInclude \"sub/a.pbrt\"\nShape \"sphere\"\n",
    )
    .unwrap();
    std::fs::write(dir.join("sub/a.pbrt"), "Import \"b.pbrt\"\n").unwrap();
    std::fs::write(
        dir.join("sub/b.pbrt"),
        "Shape \"disk\" \"float radius\" 2\n",
    )
    .unwrap();
    let mut c = Collect::default();
    parse_file(&dir.join("main.pbrt"), &mut c).unwrap();
    assert_eq!(c.0.len(), 3);
    assert!(matches!(&c.0[1].0, Directive::Shape(t, _) if t == "disk"));
    assert!(c.0[1].1.file.ends_with("sub/b.pbrt"));
    // A cycle is an error at the Include that closes it.
    std::fs::write(dir.join("sub/b.pbrt"), "Include \"a.pbrt\"\n").unwrap();
    let e = parse_file(&dir.join("main.pbrt"), &mut Collect::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("b.pbrt:1:1") && e.contains("an Include cycle"),
        "{e}"
    );
    // Invalid UTF-8 names the byte.
    std::fs::write(dir.join("bad.pbrt"), b"Shape \"sph\xffere\"").unwrap();
    let e = parse_file(&dir.join("bad.pbrt"), &mut Collect::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.pbrt:1:11: byte 10: not UTF-8"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The next 64 random bits of the physics core's generator.
fn rng(s: &mut firemedium_core::rng::Rng) -> u64 {
    s.next_u64()
}

#[test]
fn mutated_scenes_never_panic() {
    let pieces = [
        "\"",
        "[",
        "]",
        "#",
        "\n",
        "\\",
        "é",
        "\u{0}",
        "1e400",
        "-",
        "\"float x\"",
        "Include",
        "Translate",
        "\"bool b\"",
        "nan",
        " ",
    ];
    let mut s = firemedium_core::rng::Rng::new(7);
    let (mut ok, mut err) = (0, 0);
    for name in [
        "explosion.pbrt",
        "bunny-cloud.pbrt",
        "clouds.pbrt",
        "killeroo-simple.pbrt",
    ] {
        let text = std::fs::read_to_string(scene(name)).unwrap();
        let chars: Vec<char> = text.chars().collect();
        for _ in 0..1500 {
            let mut c = chars.clone();
            for _ in 0..1 + rng(&mut s) % 4 {
                let i = (rng(&mut s) % (c.len() as u64 + 1)) as usize;
                match rng(&mut s) % 3 {
                    0 if i < c.len() => {
                        c.remove(i);
                    }
                    1 => c.truncate(i),
                    _ => {
                        let p = pieces[(rng(&mut s) % pieces.len() as u64) as usize];
                        for (k, ch) in p.chars().enumerate() {
                            c.insert((i + k).min(c.len()), ch);
                        }
                    }
                }
            }
            let m: String = c.into_iter().collect();
            let r = std::panic::catch_unwind(|| {
                parse_str(
                    "m.pbrt",
                    &m,
                    Path::new("/nonexistent"),
                    &mut Collect::default(),
                )
            });
            match r {
                Ok(Ok(())) => ok += 1,
                Ok(Err(e)) => {
                    assert!(
                        e.to_string().starts_with("m.pbrt:")
                            || e.to_string().contains("/nonexistent"),
                        "{e}"
                    );
                    err += 1;
                }
                Err(_) => panic!("the parser panicked on a mutation of {name}:\n{m}"),
            }
        }
    }
    eprintln!("parser mutations: {ok} parsed, {err} errors, 0 panics");
    assert!(ok > 100 && err > 1000, "{ok} {err}");
}

#[test]
fn a_diamond_of_includes_is_refused_in_bounded_time() {
    // 41 files of ~30 bytes, each including the next twice: no cycle, 41 deep, 2⁴⁰ parses. Refused at the
    // 65 537th Include, naming the file and the bound; a file included twice legitimately still is.
    let dir = std::env::temp_dir().join(format!("firemedium-pbrt-{}-diamond", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for i in 0..40 {
        let next = format!("f{}.pbrt", i + 1);
        std::fs::write(
            dir.join(format!("f{i}.pbrt")),
            format!("Include \"{next}\"\nInclude \"{next}\"\n"),
        )
        .unwrap();
    }
    std::fs::write(dir.join("f40.pbrt"), "Shape \"sphere\"\n").unwrap();
    let e = parse_file(&dir.join("f0.pbrt"), &mut Collect::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("Include number 65537") && e.contains("expected at most 65536"),
        "{e}"
    );
    // Three levels of the same diamond: 2³ spheres, as pbrt-v4 would include them.
    let mut c = Collect::default();
    parse_file(&dir.join("f37.pbrt"), &mut c).unwrap();
    assert_eq!(c.0.len(), 8);
    std::fs::remove_dir_all(&dir).ok();
}
