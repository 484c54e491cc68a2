//! The C header `plugin/abi/include/firemedium.h`: a C program compiled against it (gcc, -Wall -Werror) loads
//! the built plugin, checks every struct size against the Rust layout, and integrates a ray; a fake plugin
//! claiming ABI 99.0 is refused by the loader with both versions named.

use firemedium_loader::{library_file_name, Param, Plugin, Ray};
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    crate::common::root()
}

fn plugin_path() -> PathBuf {
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let p = deps.join(library_file_name());
    assert!(p.is_file(), "{} not built", p.display());
    p
}

fn gcc(args: &[&str]) {
    let out = Command::new("gcc")
        .args(args)
        .output()
        .expect("gcc runs (the project's machines have it)");
    assert!(
        out.status.success(),
        "gcc {args:?}:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Compiles the C host `src` (relative to the repository) against the header into the executable `name`, as a user
/// would (`-std=c99 -Wall -Wextra -Werror`, linked with libdl and libm).
fn c_host(name: &str, src: &str) -> PathBuf {
    c_host_with(name, src, "plugin/abi/include")
}

/// As [`c_host`], against the header in `include` (relative to the repository).
fn c_host_with(name: &str, src: &str, include: &str) -> PathBuf {
    let include = root().join(include);
    let exe = tmp(name);
    gcc(&[
        "-std=c99",
        "-Wall",
        "-Wextra",
        "-Werror",
        "-I",
        include.to_str().unwrap(),
        root().join(src).to_str().unwrap(),
        "-o",
        exe.to_str().unwrap(),
        "-ldl",
        "-lm",
    ]);
    exe
}

/// Compiles the C file `src` (relative to the repository) against the header into a shared library named
/// `name`, with extra compiler flags.
fn c_plugin(name: &str, src: &str, flags: &[&str]) -> PathBuf {
    let include = root().join("plugin/abi/include");
    let so = tmp(&format!(
        "{}{name}{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    let mut args = vec!["-std=c99", "-Wall", "-Werror", "-shared", "-fPIC"];
    args.extend_from_slice(flags);
    let (inc, file, out) = (
        include.to_str().unwrap().to_string(),
        root().join(src).to_str().unwrap().to_string(),
        so.to_str().unwrap().to_string(),
    );
    args.extend_from_slice(&["-I", &inc, &file, "-o", &out]);
    gcc(&args);
    so
}

/// `name` in a folder of its own (`firemedium-c-PID-NAME`), removed by [`done`] when the test has passed.
fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("firemedium-c-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// Removes the folder [`tmp`] made for `file`.
fn done(file: &Path) {
    if let Some(d) = file.parent().filter(|d| {
        d.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with("firemedium-c-"))
    }) {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn a_c_host_loads_the_plugin_through_the_header() {
    let exe = c_host("smoke", "tests/c/smoke.c");
    let fire = root().join("tests/data/valid/vdb/mantaflow_fire_f060.vdb");
    let out = Command::new(&exe)
        .arg(plugin_path())
        .arg(&fire)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let get = |k: &str| -> String {
        text.lines()
            .find_map(|l| l.strip_prefix(&format!("{k} ")))
            .unwrap_or_else(|| panic!("{k} missing in\n{text}"))
            .to_string()
    };
    use firemedium_abi::*;
    for (k, n) in [
        ("sizeof_FmRay", std::mem::size_of::<FmRay>()),
        ("sizeof_FmExit", std::mem::size_of::<FmExit>()),
        ("sizeof_FmScatter", std::mem::size_of::<FmScatter>()),
        ("sizeof_FmVolumeInfo", std::mem::size_of::<FmVolumeInfo>()),
        ("sizeof_FmParam", std::mem::size_of::<FmParam>()),
        ("sizeof_FmParamInfo", std::mem::size_of::<FmParamInfo>()),
        ("sizeof_FmApi", std::mem::size_of::<FmApi>()),
        ("sizeof_FmLightInfo", std::mem::size_of::<FmLightInfo>()),
        (
            "sizeof_FmMajorantGrid",
            std::mem::size_of::<FmMajorantGrid>(),
        ),
        ("sizeof_FmPointQuery", std::mem::size_of::<FmPointQuery>()),
        ("sizeof_FmErrorDetail", std::mem::size_of::<FmErrorDetail>()),
        ("sizeof_FmCreateInfo", std::mem::size_of::<FmCreateInfo>()),
        ("sizeof_FmRayQuery", std::mem::size_of::<FmRayQuery>()),
        ("sizeof_FmTables", std::mem::size_of::<FmTables>()),
    ] {
        assert_eq!(
            get(k).parse::<usize>().unwrap(),
            n,
            "{k}: C and Rust layouts differ"
        );
    }
    // The header's version is the Rust contract's (it said 0.2 while the plugin spoke 0.3), and so is the
    // plugin's.
    let version = format!("{ABI_MAJOR}.{ABI_MINOR}");
    assert_eq!(
        get("header_abi"),
        version,
        "firemedium.h's FM_ABI_MAJOR/MINOR"
    );
    assert_eq!(get("abi"), version);
    // The volume's build ran its parallel parts as the C host's pool's tasks.
    assert!(get("pool_tasks").parse::<usize>().unwrap() >= 2);
    let (p1, p2): (f64, f64) = (
        get("light_pdf").parse().unwrap(),
        get("light_pdf_again").parse().unwrap(),
    );
    assert!(
        p1 > 0.0 && (p1 / p2 - 1.0).abs() < 1e-9,
        "light pdf {p1} vs {p2}"
    );
    assert!(
        get("light_power_w").parse::<f64>().unwrap() > 0.0
            && get("light_voxels").parse::<u64>().unwrap() > 1000
    );
    assert_eq!(get("channels"), "32");
    // From C: the Mantaflow frame's temperature range, 0 … 2.974609 × temperaturescale 1000 K.
    assert_eq!(get("temperature_status"), "0");
    assert_eq!(get("temperature_min"), "0");
    let tmax: f64 = get("temperature_max").parse().unwrap();
    assert!((tmax - 2974.609).abs() < 1e-3, "{tmax}");
    assert_eq!(get("integrate_status"), "0");
    // From C, the closed form: j from the fields and the tables is volume_coefficients' j at the same point.
    assert_eq!(get("tables_status"), "0 0 0");
    assert!(get("tables_rows").parse::<u32>().unwrap() > 1000);
    let (jc, jv): (f64, f64) = (
        get("closed_form_j29").parse().unwrap(),
        get("coefficients_j29").parse().unwrap(),
    );
    assert!(
        jv > 0.0 && (jc / jv - 1.0).abs() < 1e-5,
        "{jc} against {jv}"
    );
    // The same ray through the Rust loader gives the same numbers.
    // SAFETY: the plugin this cargo invocation built.
    let p = unsafe { Plugin::load(plugin_path()) }.unwrap();
    let v = p
        .create_volume(&[
            Param::string("filename", fire.to_str().unwrap()),
            Param::float("temperaturescale", 1000.0),
            Param::float("sootscale", 1e-6),
        ])
        .unwrap();
    let (mut l, mut t) = (vec![0f32; 32], vec![0f32; 32]);
    v.integrate(
        &[Ray {
            origin: [1.0, -1.0, 0.5],
            direction: [0.0, 1.0, 0.0],
            tmin: 0.0,
            tmax: 10.0,
            seed: 7,
        }],
        &mut l,
        Some(&mut t),
        None,
    )
    .unwrap();
    let c_l: f32 = get("radiance_29").parse().unwrap();
    let c_t: f32 = get("transmittance_29").parse().unwrap();
    assert_eq!((c_l, c_t), (l[29], t[29]));
    assert!(
        c_l > 0.0 && c_t < 1.0,
        "the ray should cross the fire: L {c_l}, T {c_t}"
    );
    // The medium level from C: what the fire holds (it emits) and its majorant grid; the point query at 650 nm
    // gives the soot's absorption there and its emitted radiance.
    assert_eq!(get("features_status"), "0");
    assert_eq!(get("features"), FM_FEATURE_EMITS.to_string());
    assert_eq!(get("majorant_status"), "0");
    assert!(get("majorant_first").parse::<f64>().unwrap() >= 0.0);
    assert_eq!(get("point_status"), "0");
    let sa: f64 = get("point_sigma_a_650").parse().unwrap();
    let le: f64 = get("point_le_650").parse().unwrap();
    assert!(sa > 0.0 && le > 0.0, "σ_a {sa}, Le {le}");
    assert_eq!(get("bad_status"), "2");
    // The same error's parts as fields.
    assert_eq!(get("detail_status"), "0 2");
    assert_eq!(get("detail_parameter"), "stepsise");
    // The parameter's index in the list the call was given (its only one), and a 1.0-1.3 host's smaller struct
    // written as far as it goes, not a byte past it.
    assert_eq!(get("detail_index"), "0");
    assert_eq!(get("detail_1_0"), "0 1");
    assert!(get("bad_message").contains("did you mean 'stepsize'"));
    done(&exe);
}

#[test]
fn an_abi_mismatch_names_both_versions() {
    let so = c_plugin("fake", "tests/c/fake_plugin.c", &[]);
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let e = unsafe { Plugin::load(&so) }.unwrap_err().to_string();
    let needs = format!(
        "speaks firemedium ABI 99.0, this host needs {}.{}",
        firemedium_abi::ABI_MAJOR,
        firemedium_abi::ABI_MINOR
    );
    assert!(e.contains(&needs), "{e}");
    // A stale library of another ABI earlier on the search path does not shadow a compatible one after it;
    // alone, it is the error.
    let stale = so.parent().unwrap().join("stale");
    std::fs::create_dir_all(&stale).unwrap();
    std::fs::copy(&so, stale.join(library_file_name())).unwrap();
    let good = plugin_path().parent().unwrap().to_path_buf();
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let p = unsafe { Plugin::find(&[stale.clone(), good]) }.unwrap();
    assert_eq!(
        p.version(),
        (firemedium_abi::ABI_MAJOR, firemedium_abi::ABI_MINOR)
    );
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let e = unsafe { Plugin::find(&[stale]) }.unwrap_err().to_string();
    assert!(e.contains("speaks firemedium ABI 99.0"), "{e}");
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let e = unsafe { Plugin::load(Path::new("/etc/hostname")) }
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot load"), "{e}");
    done(&so);
    // A plugin of the last 0.x ABI (0.13, before the 1.0 cut) and this 1.0 host: refused, both versions named.
    let old = c_plugin(
        "fake013",
        "tests/c/fake_plugin.c",
        &["-DFAKE_MAJOR=0u", "-DFAKE_MINOR=13u"],
    );
    // SAFETY: a library this test made.
    let e = unsafe { Plugin::load(&old) }.unwrap_err().to_string();
    assert!(
        e.contains(&format!(
            "speaks firemedium ABI 0.13, this host needs {}.{}",
            firemedium_abi::ABI_MAJOR,
            firemedium_abi::ABI_MINOR
        )),
        "{e}"
    );
    done(&old);
}

#[test]
fn a_broken_plugin_is_refused_saying_what_is_wrong() {
    // The right version, but no table, a short table, or null entries: each is an error naming the fault, never a
    // crash of the host that loaded it.
    for (kind, want) in [
        (1, "its firemedium_plugin_entry returned no table (null)"),
        (2, "table declares 16 bytes"),
        (3, "its entry 'last_error' is null"),
    ] {
        let so = c_plugin(
            &format!("broken{kind}"),
            "tests/c/broken_plugin.c",
            &[&format!("-DBROKEN={kind}")],
        );
        // SAFETY: a library this test built; the loader reads its table and must refuse it before any call.
        let e = unsafe { Plugin::load(&so) }.unwrap_err().to_string();
        assert!(
            e.contains("is a broken firemedium plugin") && e.contains(want),
            "{kind}: {e}"
        );
        done(&so);
    }
}

#[test]
fn every_entry_refuses_bad_arguments_from_c() {
    // A C host calling every entry with null handles and buffers, absurd counts, NaN numbers and unknown type
    // codes: each call fails with a status other than FM_PANIC and a message, and the plugin goes on working.
    let exe = c_host("abi_abuse", "tests/c/abi_abuse.c");
    let out = Command::new(&exe).arg(plugin_path()).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{text}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.lines().count() >= 60 && text.contains("failures 0"),
        "{text}"
    );
    done(&exe);
}

/// An ABI 1.0 host keeps working with every 1.x plugin: the example host as it was at 1.0, compiled against the
/// 1.0 header (tests/c/abi-1.0, from the commit that declared 1.0: its FmCreateInfo ends before `directory`, 88
/// bytes), renders the campfire through today's plugin — which refused every volume_create it made ("struct_size
/// 88, expected at least 96") — to the same brightest ray as the current example.
#[test]
fn an_abi_1_0_host_renders_with_todays_plugin() {
    let fire = root().join("scenes/campfire/campfire.vdb");
    let run = |exe: &PathBuf| {
        let out = Command::new(exe)
            .arg(plugin_path())
            .arg(&fire)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    let old = c_host_with(
        "fire_pixel_1_0",
        "tests/c/abi-1.0/fire_pixel.c",
        "tests/c/abi-1.0",
    );
    let new = c_host("fire_pixel_now", "plugin/abi/examples/fire_pixel.c");
    let brightest = |text: &str| -> String {
        text.lines()
            .find(|l| l.starts_with("brightest"))
            .unwrap_or_else(|| panic!("no brightest ray in\n{text}"))
            .to_string()
    };
    let (a, b) = (run(&old), run(&new));
    assert_eq!(brightest(&a), brightest(&b), "{a}\n{b}");
    // The 1.0 struct is smaller than today's, and today's plugin reads it as far as it goes.
    assert!(
        firemedium_abi::FM_CREATE_INFO_SIZE_1_0
            < std::mem::size_of::<firemedium_abi::FmCreateInfo>()
    );
    done(&old);
    done(&new);
}

#[test]
fn the_c_example_host_renders_the_campfire() {
    // plugin/abi/examples/fire_pixel.c, compiled as a user would (-Wall -Wextra -Werror), run on the default
    // scene's fire: its brightest ray is the loader's, to the digit it prints, and its fire-light estimate is
    // positive and finite.
    let exe = c_host("fire_pixel", "plugin/abi/examples/fire_pixel.c");
    let fire = root().join("scenes/campfire/campfire.vdb");
    let out = Command::new(&exe)
        .arg(plugin_path())
        .arg(&fire)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    let value = |key: &str| -> f64 {
        text.lines()
            .find_map(|l| l.strip_prefix(key).map(|v| v.trim().parse().unwrap()))
            .unwrap_or_else(|| panic!("no {key} in\n{text}"))
    };
    // The same fan through the loader: the brightest of its nine rays.
    // SAFETY: the plugin built for this test.
    let plugin = unsafe { Plugin::load(plugin_path()) }.unwrap();
    let v = plugin
        .create_volume(&[
            Param::string("dataset", fire.to_str().unwrap()),
            Param::string("fuel", "propane"),
        ])
        .unwrap();
    let info = v.info();
    let c = info.channels as usize;
    let xyz = v.channel_xyz().unwrap();
    let (lo, hi) = (info.bounds_min, info.bounds_max);
    let z = lo[2] + 0.3 * (hi[2] - lo[2]);
    let rays: Vec<Ray> = (0..9)
        .map(|i| Ray {
            origin: [
                lo[0] + (hi[0] - lo[0]) * (i as f64 + 0.5) / 9.0,
                lo[1] - 1.0,
                z,
            ],
            direction: [0.0, 1.0, 0.0],
            tmin: 0.0,
            tmax: 1e30,
            seed: i,
        })
        .collect();
    let mut l = vec![0f32; 9 * c];
    v.integrate(&rays, &mut l, None, None).unwrap();
    let brightest = (0..9)
        .map(|i| (0..c).map(|k| l[i * c + k] as f64 * xyz[k][1]).sum::<f64>())
        .fold(0.0, f64::max);
    assert!(brightest > 0.0 && (value("brightest ") / brightest - 1.0).abs() < 1e-6);
    let e = value("scalar_illuminance ");
    assert!(e.is_finite() && e > 0.0, "{e}");
    done(&exe);
}

/// docs/reference/abi.md from the header: its opening (how a host loads the plugin), the status codes, the
/// constants a host sets or reads, the table's conventions and each entry with its comment — so the reference and
/// the header cannot disagree.
fn abi_reference(header: &str) -> String {
    // A C comment's text, one paragraph: the leading '*' of each line and the delimiters gone.
    let comment = |c: &str| -> String {
        c.trim()
            .trim_start_matches("/*")
            .trim_end_matches("*/")
            .lines()
            .map(|l| l.trim().trim_start_matches('*').trim())
            .filter(|l| !l.is_empty())
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut out = String::from(
        "# The C ABI\n\n<!-- Generated from plugin/abi/include/firemedium.h by tests/abi/c_header.rs.\n     Regenerate: FIREMEDIUM_BLESS=1 cargo test --release -p firemedium --test end_to_end abi_reference -->\n\n",
    );
    let opening = header.split("*/").next().unwrap_or("");
    out += &comment(opening);
    out += "\n\n## Constants\n\n| name | value | meaning |\n|---|---|---|\n";
    for line in header.lines().filter(|l| l.starts_with("#define FM_")) {
        let (def, note) = match line.split_once("/*") {
            Some((d, n)) => (d, comment(&format!("/*{n}"))),
            None => (line, String::new()),
        };
        let mut parts = def.trim_start_matches("#define ").split_whitespace();
        let (name, value) = (
            parts.next().unwrap_or(""),
            parts.collect::<Vec<_>>().join(" "),
        );
        out += &format!("| `{name}` | `{value}` | {note} |\n");
    }
    // The structs a host fills or reads, as the header declares them (the table's own comes last).
    out += "\n## Structs\n\n";
    let mut from = 0;
    while let Some(i) = header[from..].find("typedef struct Fm") {
        let at = from + i;
        let name: String = header[at + 15..]
            .chars()
            .take_while(|c| c.is_alphanumeric())
            .collect();
        let Some(end) = header[at..].find(&format!("}} {name};")) else {
            break;
        };
        let decl = &header[at..at + end + name.len() + 3];
        from = at + end;
        if name == "FmApi" || !decl.contains('{') {
            continue;
        }
        out += &format!("### `{name}`\n\n```c\n{decl}\n```\n\n");
    }
    // The table: its conventions (the comment before it), then each entry with the comment before it (an
    // entry without one shares the previous comment's group).
    let start = header.find("typedef struct FmApi").unwrap_or(0);
    let before = &header[..start];
    let conventions = before
        .rfind("/*")
        .map(|i| {
            comment(&before[i..])
                .replace(" - ", "\n- ")
                .replacen(":\n- ", ":\n\n- ", 1)
        })
        .unwrap_or_default();
    out += &format!("## The function table, `FmApi`\n\n{conventions}\n\n| entry | signature | what it does |\n|---|---|---|\n");
    let body = &header[start
        ..header[start..]
            .find("} FmApi;")
            .map_or(header.len(), |e| start + e)];
    let mut pending = String::new();
    // (The last comment, and the entry it came with.)
    let mut group = (String::new(), String::new());
    let mut rest = body;
    while !rest.is_empty() {
        let c = rest.find("/*");
        let f = rest.find("(*");
        match (c, f) {
            (Some(ci), fi) if fi.is_none_or(|fi| ci < fi) => {
                let end = rest[ci..].find("*/").map_or(rest.len(), |e| ci + e + 2);
                pending = comment(&rest[ci..end]);
                rest = &rest[end..];
            }
            (_, Some(fi)) => {
                let line_start = rest[..fi].rfind(['\n', ';']).map_or(0, |i| i + 1);
                let end = rest[fi..].find(';').map_or(rest.len(), |e| fi + e + 1);
                let decl = rest[line_start..end]
                    .split_whitespace()
                    .collect::<Vec<_>>()
                    .join(" ");
                let name = decl[decl.find("(*").unwrap_or(0) + 2..]
                    .split(')')
                    .next()
                    .unwrap_or("")
                    .to_string();
                // An entry without a comment of its own that the last comment names is described there.
                let what = if !pending.is_empty() {
                    group = (pending.clone(), name.clone());
                    pending.clone()
                } else if group.0.contains(name.as_str()) {
                    format!("With `{}`, above.", group.1)
                } else {
                    String::new()
                };
                out += &format!(
                    "| `{name}` | `{}` | {} |\n",
                    decl.replace('|', "\\|"),
                    what.replace('|', "\\|")
                );
                pending.clear();
                rest = &rest[end..];
            }
            _ => break,
        }
    }
    out
}

#[test]
fn abi_reference_is_current() {
    // docs/reference/abi.md is generated from the header; regenerate with FIREMEDIUM_BLESS=1.
    let header = std::fs::read_to_string(root().join("plugin/abi/include/firemedium.h")).unwrap();
    let want = abi_reference(&header);
    let path = root().join("docs/reference/abi.md");
    if std::env::var_os("FIREMEDIUM_BLESS").is_some() {
        std::fs::write(&path, &want).unwrap();
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        have == want,
        "docs/reference/abi.md is stale: run FIREMEDIUM_BLESS=1 cargo test --release -p firemedium --test end_to_end abi_reference"
    );
    // Every entry of the table is there, with its words.
    for entry in [
        "volume_create",
        "volume_point",
        "volume_majorant_grid",
        "volume_query",
        "light_sample",
        "light_pdf_direction",
    ] {
        assert!(want.contains(&format!("| `{entry}` |")), "{entry} missing");
    }
    assert!(want.contains("| `FM_FEATURE_MOTION` |"));
}
