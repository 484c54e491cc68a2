//! pbrt-v4's materials, end to end: white furnaces (a lossless object under a uniform sky must vanish, which
//! holds only if every BSDF conserves energy and every MIS weight sums to one) and measured metals against the
//! closed form of their Fresnel reflectance.

use crate::common::render;

use render::{data, mean_rgb, out_dir, read_text, render, y_of};

/// A unit sphere of `material` (after `preamble`) inside a uniform sky of luminance 1, seen from 5 units away.
fn furnace(name: &str, preamble: &str, material: &str) -> [f64; 3] {
    let dir = out_dir("furnace");
    let scene = format!(
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 30\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24\nSampler \"paddedsobol\" \"integer pixelsamples\" 128\nIntegrator \"volpath\" \"integer maxdepth\" 100\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n{preamble}\n{material}\nShape \"sphere\" \"float radius\" 1\n"
    );
    let f = dir.join(format!("{name}.pbrt"));
    std::fs::write(&f, scene).unwrap();
    let img = render(&f, &dir.join(format!("{name}.exr")), &[]);
    // The central 8 × 8 pixels all see the sphere (±0.45 units of its radius 1).
    mean_rgb(&img, (8, 16), (8, 16))
}

#[test]
fn lossless_materials_vanish_in_a_white_furnace() {
    let cases: [(&str, &str, &str, f64); 9] = [
        ("glass", "", "Material \"dielectric\" \"float eta\" 1.5", 0.01),
        // A narrow rough lobe loses little to the microfacets' single scattering.
        (
            "rough-glass",
            "",
            "Material \"dielectric\" \"float eta\" 1.5 \"float roughness\" 0.005",
            0.02,
        ),
        ("thin-glass", "", "Material \"thindielectric\" \"float eta\" 1.5", 0.01),
        (
            "diffuse-transmission",
            "",
            "Material \"diffusetransmission\" \"rgb reflectance\" [0.5 0.5 0.5] \"rgb transmittance\" [0.5 0.5 0.5]",
            0.015,
        ),
        // A white base under a thin clear coat, with walks long enough to let everything out.
        (
            "coated-diffuse",
            "",
            "Material \"coateddiffuse\" \"rgb reflectance\" [1 1 1] \"float thickness\" 1e-5 \"integer maxdepth\" 200",
            0.015,
        ),
        (
            "coated-conductor",
            "",
            "Material \"coatedconductor\" \"rgb reflectance\" [1 1 1] \"float thickness\" 1e-5 \"integer maxdepth\" 200",
            0.015,
        ),
        // (Both chosen materials keep radiance unscaled: a mix of thick glass with anything else would enter
        // with 1/η² and leave without its η², in pbrt-v4 as here.)
        (
            "mix",
            "MakeNamedMaterial \"a\" \"string type\" \"diffusetransmission\" \"rgb reflectance\" [0.3 0.3 0.3] \"rgb transmittance\" [0.7 0.7 0.7]\nMakeNamedMaterial \"b\" \"string type\" \"thindielectric\"",
            "Material \"mix\" \"string materials\" [\"a\" \"b\"] \"float amount\" 0.4",
            0.01,
        ),
        // Dispersion: each path keeps one wavelength bin through the glass; the sum over bins is the sky's.
        (
            "dispersive-glass",
            "",
            "Material \"dielectric\" \"spectrum eta\" \"glass-F11\"",
            0.02,
        ),
        (
            "interface-in-a-mix",
            "MakeNamedMaterial \"a\" \"string type\" \"interface\"\nMakeNamedMaterial \"b\" \"string type\" \"thindielectric\"",
            "Material \"mix\" \"string materials\" [\"a\" \"b\"] \"float amount\" 0.5",
            0.01,
        ),
    ];
    for (name, pre, mat, tol) in cases {
        let rgb = furnace(name, pre, mat);
        let y = y_of(rgb);
        assert!(
            (y - 1.0).abs() < tol,
            "{name}: Y {y} (rgb {rgb:?}), expected 1 ± {tol}"
        );
        for c in rgb {
            assert!(
                (c - 1.0).abs() < 2.0 * tol,
                "{name}: rgb {rgb:?} is not the sky's white"
            );
        }
    }
}

#[test]
fn pbrt_v4s_default_coat_absorbs_what_its_layer_and_walks_leave_out() {
    // The same white coated base with pbrt-v4's defaults (thickness 0.01 of unit extinction, 10 events per
    // walk) is visibly darker than the sky: both losses are pbrt-v4's model, not noise.
    let rgb = furnace(
        "coated-default",
        "",
        "Material \"coateddiffuse\" \"rgb reflectance\" [1 1 1]",
    );
    let y = y_of(rgb);
    assert!(y > 0.75 && y < 0.95, "Y {y}");
}

/// ∫ R(λ) D65(λ) ȳ(λ) dλ / ∫ D65 ȳ at 1 nm from tests/data's CIE table: the luminance a mirror of normal
/// reflectance R shows under a white (D65, luminance 1) sky.
fn luminance_under_d65(r: impl Fn(f64) -> f64) -> f64 {
    let text = read_text(&data("cie1931_2deg_cmf_1nm.csv"));
    let (mut num, mut den) = (0.0, 0.0);
    for line in text.lines() {
        let v: Vec<f64> = line
            .split(',')
            .filter_map(|x| x.trim().parse().ok())
            .collect();
        if v.len() == 4 {
            let w = firemedium_core::rgb_spectrum::d65(v[0]) * v[2];
            num += r(v[0]) * w;
            den += w;
        }
    }
    num / den
}

/// A named spectrum's value at λ (linear between its samples).
fn named(name: &str, l: f64) -> f64 {
    let v = firemedium::render::named_spectra::lookup(name).unwrap();
    let p: Vec<(f64, f64)> = v.chunks(2).map(|c| (c[0], c[1])).collect();
    let i = p.partition_point(|q| q.0 <= l).clamp(1, p.len() - 1);
    let (a, b) = (p[i - 1], p[i]);
    a.1 + (l - a.0) / (b.0 - a.0) * (b.1 - a.1)
}

#[test]
fn measured_metals_reflect_their_fresnel_reflectance() {
    // A smooth conductor seen straight on under a white sky, direct light only: each wavelength reflects
    // ((η − 1)² + k²)/((η + 1)² + k²) of the sky. Copper is pbrt-v4's default conductor.
    let dir = out_dir("metals");
    for (name, params, metal) in [
        (
            "gold",
            "\"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"",
            "Au",
        ),
        ("copper", "", "Cu"),
        (
            "silver",
            "\"spectrum eta\" \"metal-Ag-eta\" \"spectrum k\" \"metal-Ag-k\"",
            "Ag",
        ),
    ] {
        let scene = format!("LookAt 0 0 10  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"paddedsobol\" \"integer pixelsamples\" 4\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nMaterial \"conductor\" {params}\nShape \"trianglemesh\" \"point3 P\" [-5 -5 0 5 -5 0 5 5 0 -5 5 0] \"integer indices\" [0 1 2 0 2 3]\n");
        let f = dir.join(format!("{name}.pbrt"));
        std::fs::write(&f, scene).unwrap();
        let rgb = mean_rgb(
            &render(&f, &dir.join(format!("{name}.exr")), &[]),
            (0, 8),
            (0, 8),
        );
        let want = luminance_under_d65(|l| {
            let (e, k) = (
                named(&format!("metal-{metal}-eta"), l),
                named(&format!("metal-{metal}-k"), l),
            );
            ((e - 1.0).powi(2) + k * k) / ((e + 1.0).powi(2) + k * k)
        });
        let y = y_of(rgb);
        assert!(
            (y / want - 1.0).abs() < 0.01,
            "{name}: Y {y}, closed form {want}"
        );
        if metal != "Ag" {
            assert!(
                rgb[0] > rgb[1] && rgb[1] > rgb[2],
                "{name} is not warm: {rgb:?}"
            );
        }
    }
}

#[test]
fn an_unknown_named_spectrum_is_an_error_naming_the_closest() {
    let dir = out_dir("named");
    let f = dir.join("typo.pbrt");
    std::fs::write(&f, "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\nMaterial \"conductor\" \"spectrum eta\" \"metal-Au-eat\"\nShape \"sphere\"\n").unwrap();
    let o = render::run_render(&f, &dir.join("typo.exr"), &["-q"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && e.contains("typo.pbrt:4:") && e.contains("metal-Au-eta"),
        "{e}"
    );
}
