//! End-to-end: the built `firemedium` binary's `physics` subcommand (the README's first command) prints the
//! documented JSON with values that match the published references, and bad arguments exit 2 with one line.

use serde_json::Value;
use std::process::{Command, Output};

fn firemedium(args: &[&str]) -> Output {
    Command::new(crate::common::exe("firemedium"))
        .args(args)
        .output()
        .expect("the firemedium binary runs")
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

#[test]
fn readme_physics_command_prints_the_documented_json() {
    let out = firemedium(&[
        "physics",
        "--temperature",
        "1500",
        "--wavelengths",
        "450,550,650",
        "--fuel",
        "propane",
        "--soot-fraction",
        "1e-6",
        "--alpha",
        "1",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).expect("stdout is JSON");
    assert_eq!(v["temperature_k"], 1500.0);
    assert_eq!(v["fuel"], "propane");
    let w = v["wavelengths"].as_array().expect("wavelengths is a list");
    assert_eq!(w.len(), 3);
    // Planck at 1500 K (shared/data/README.md, W·m⁻³·sr⁻¹ → per nm), 4 significant figures.
    for (i, (nm, b_si)) in [(450.0, 3.571e6), (550.0, 6.312e7), (650.0, 4.005e8)]
        .into_iter()
        .enumerate()
    {
        assert_eq!(w[i]["wavelength_nm"], nm);
        let b = w[i]["blackbody"].as_f64().unwrap();
        assert!(rel(b, b_si / 1e9) < 5e-4, "{nm} nm: {b}");
        let k = w[i]["soot_kappa"].as_f64().unwrap();
        let n1 = w[i]["air_index_minus_one"].as_f64().unwrap();
        // n − 1 of 1500 K air is ≈ 288/1500 of its 15 °C value ≈ 2.78e-4 → 5.3e-5.
        assert!(n1 > 5.0e-5 && n1 < 5.6e-5, "{nm} nm: n-1 = {n1}");
        assert!(k > 0.0);
    }
    // Propane soot at 550 nm, f_v = 1e-6, α = 1: 8.44 m⁻¹ (shared/data/README.md).
    assert!(rel(w[1]["soot_kappa"].as_f64().unwrap(), 8.44) < 0.005);
    // Blackbody colour: on the Planckian locus at 1500 K (0.5857, 0.3931); Y > 0 in cd/m².
    let (x, y) = (
        v["blackbody_chromaticity"]["x"].as_f64().unwrap(),
        v["blackbody_chromaticity"]["y"].as_f64().unwrap(),
    );
    assert!(
        (x - 0.5857).abs() < 1e-3 && (y - 0.3931).abs() < 1e-3,
        "({x}, {y})"
    );
    // Luminance against an independent value: the 1948 candela — a full radiator at the freezing point of
    // platinum (2042 K) has 60 cd/cm², 6.0e5 cd/m² (today's K_m = 683 lm/W and the CIE 1931 ȳ agree to 0.3 %).
    let hot = firemedium(&["physics", "--temperature", "2042", "--json"]);
    let h: Value = serde_json::from_slice(&hot.stdout).expect("stdout is JSON");
    let y_pt = h["blackbody_xyz"]["Y"].as_f64().unwrap();
    assert!(rel(y_pt, 6.0e5) < 0.01, "Y at 2042 K: {y_pt} cd/m²");
    // And colour: a 1500 K radiator is red-dominated in linear sRGB; one at 6504 K (D65's correlated colour
    // temperature) is close to neutral — a little magenta, as the Planckian locus at 6504 K, (0.3135, 0.3236),
    // lies 0.005 below D65's (0.3127, 0.3290).
    let rgb = &v["blackbody_srgb_linear"];
    let (r, g) = (rgb["r"].as_f64().unwrap(), rgb["g"].as_f64().unwrap());
    assert!(r > 2.0 * g, "1500 K: r {r}, g {g}");
    let d65 = firemedium(&["physics", "--temperature", "6504", "--json"]);
    let d: Value = serde_json::from_slice(&d65.stdout).expect("stdout is JSON");
    let c = &d["blackbody_srgb_linear"];
    let (r, g, b) = (
        c["r"].as_f64().unwrap(),
        c["g"].as_f64().unwrap(),
        c["b"].as_f64().unwrap(),
    );
    assert!(
        (r / g - 1.0).abs() < 0.08 && (b / g - 1.0).abs() < 0.08 && r > g && b > g,
        "6504 K: ({r}, {g}, {b})"
    );
}

#[test]
fn bad_arguments_exit_2_with_one_line() {
    for args in [
        &["physics", "--temperature", "abc"][..],
        &["physics", "--temperature=-3"],
        &["physics", "--temperature", "NaN"],
        &["physics", "--fuel", "methane"],
        &["physics", "--wavelengths", "450,,650"],
        &["physics", "--wavelengths", "50"],
        &["physics", "--humidity", "1.5"],
        &["physics", "--no-such-flag"],
        &[],
    ] {
        let out = firemedium(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: {err}");
        assert!(err.starts_with("firemedium: "), "{err}");
        assert!(out.stdout.is_empty(), "{args:?}");
    }
    let err =
        String::from_utf8_lossy(&firemedium(&["physics", "--fuel", "methane"]).stderr).to_string();
    assert!(err.contains("methane") && err.contains("propane"), "{err}");
    let err =
        String::from_utf8_lossy(&firemedium(&["physics", "--temperature=-3"]).stderr).to_string();
    assert!(err.contains("--temperature") && err.contains("-3"), "{err}");
    // A negative number after a space is a value too, refused by its range (not "unexpected argument").
    let err = String::from_utf8_lossy(&firemedium(&["physics", "--temperature", "-5"]).stderr)
        .to_string();
    assert!(
        err.contains("--temperature -5: expected a temperature in K"),
        "{err}"
    );
    // Missing arguments are named, with the usage.
    let out = firemedium(&["compare"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        err.contains("<SCENE>")
            && err.contains("usage: firemedium compare")
            && err.lines().count() == 1,
        "{err}"
    );
    // A scene that cannot be read: its name, without a position it does not have.
    let out = firemedium(&["render", "/no/such/scene.pbrt"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        err.contains("cannot read /no/such/scene.pbrt") && !err.contains(":0:0"),
        "{err}"
    );
}

#[test]
fn table_output_and_help() {
    let out = firemedium(&["physics", "--temperature", "2000"]);
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("T = 2000 K") && text.contains("kappa (1/m)"),
        "{text}"
    );
    let help = firemedium(&["physics", "--help"]);
    assert!(help.status.success());
    assert!(String::from_utf8_lossy(&help.stdout).contains("--soot-fraction"));
}
