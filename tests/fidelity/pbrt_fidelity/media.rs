//! pbrt-v4's media at its pixel values: grids beside its lights, faces, its homogeneous preset, `rgbgrid`, `nanovdb`,
//! maxdepth counted as its volpath counts it, the march on its grids, the memory budget its media share.

use super::*;

/// The slab scene at temperature `t` (K), as a file in `dir`: `slab_const.pbrt` with its 2000 K replaced.
fn slab_at(dir: &Path, t: f64) -> PathBuf {
    let text = read_text(&data("pbrt-v4-measured/slab_const.pbrt"));
    let p = dir.join(format!("slab_{t}.pbrt"));
    std::fs::write(&p, text.replace(" 2000", &format!(" {t}"))).unwrap();
    p
}

/// pbrt-v4's Y of an optically thick grid at `t` with Lescale 1: ∫ ȳ(λ) B(λ, T) / B(λ_max, T) dλ, integrated
/// here at 1 nm from the CIE table in tests/data (independent of the renderer's bins).
fn thick_y(t: f64) -> f64 {
    let text = read_text(&data("cie1931_2deg_cmf_1nm.csv"));
    let b = |l: f64| firemedium_core::blackbody::spectral_radiance(t, l);
    let peak = b(firemedium_core::blackbody::WIEN / t * 1e9);
    text.lines()
        .filter_map(|line| {
            let v: Vec<f64> = line
                .split(',')
                .filter_map(|x| x.trim().parse().ok())
                .collect();
            (v.len() == 4).then(|| v[2] * b(v[0]) / peak)
        })
        .sum()
}

#[test]
fn a_thick_grid_beside_an_rgb_white_light_has_pbrt_v4s_pixel_ratio() {
    // Measured by pbrt-v4 itself on slab_const.pbrt (tests/data/pbrt-v4-measured, 1024 spp): the 2000 K box
    // records Y = 5.1809 ± 0.0005, RGB (13.060, 3.351, 0.106); the `rgb L [1 1 1]` light Y = 1, RGB (1, 1, 1.002).
    let dir = out_dir("slab");
    let img = render(
        &data("pbrt-v4-measured/slab_const.pbrt"),
        &dir.join("c.exr"),
        &["--spp", "16"],
    );
    let (f, l) = (
        mean_rgb(&img, BOX.0, BOX.1),
        mean_rgb(&img, LIGHT.0, LIGHT.1),
    );
    let ratio = y_of(f) / y_of(l);
    assert!(
        (ratio / 5.1809 - 1.0).abs() < 5e-3,
        "fire/light Y {ratio}, pbrt-v4 5.1809"
    );
    for (got, want) in f.iter().zip([13.060, 3.351, 0.106]) {
        assert!(
            (got / want - 1.0).abs() < 1e-2,
            "fire {f:?}, pbrt-v4 (13.060, 3.351, 0.106)"
        );
    }
    for (got, want) in l.iter().zip([1.0, 1.0, 1.002]) {
        assert!(
            (got / want - 1.0).abs() < 1e-2,
            "light {l:?}, pbrt-v4 (1, 1, 1.002)"
        );
    }
    // And against the closed form at 1500 and 2000 K (∫ȳ B̃: 0.3644 and 5.181; neither divided by ∫ȳ = 106.86).
    for t in [1500.0, 2000.0] {
        let img = render(
            &slab_at(&dir, t),
            &dir.join(format!("s{t}.exr")),
            &["--spp", "16"],
        );
        let ratio = y_of(mean_rgb(&img, BOX.0, BOX.1)) / y_of(mean_rgb(&img, LIGHT.0, LIGHT.1));
        let want = thick_y(t);
        assert!(
            (ratio / want - 1.0).abs() < 5e-3,
            "{t} K: fire/light Y {ratio}, closed form {want}"
        );
    }
}

#[test]
fn a_one_voxel_grid_fades_to_its_faces_as_pbrt_v4s() {
    // slab.pbrt: one voxel over [0, 1]³; pbrt-v4's lookup interpolates between voxel centres with zero outside,
    // so on the face the camera sees, density, temperature and Lescale are 0.5·tx·tz of their centre values
    // (tx = 1 − |x − ½|), rising inward. The face-centre pixel against the RTE integrated along its rays here
    // (σ_a = 1000 d, S = Lescale · B̃(T), L = ∫ σ_a S e^{−τ} dy), over the pixel's footprint.
    let dir = out_dir("tent");
    let img = render(
        &data("pbrt-v4-measured/slab.pbrt"),
        &dir.join("t.exr"),
        &["--spp", "1024"],
    );
    let got = y_of(mean_rgb(&img, (41, 42), (15, 17)));
    // The whole face (pixels 34–49 × rows 8–23): pbrt-v4 measured 5.7e-6 ± 1.8e-6 over the box's pixels.
    let face = y_of(mean_rgb(&img, (34, 50), (8, 24)));
    eprintln!("face mean Y {face} (pbrt-v4: 5.7e-6 ± 1.8e-6)");
    assert!(
        (face - 5.7e-6).abs() < 3.0 * 1.8e-6,
        "face mean Y {face}, pbrt-v4 5.7e-6 ± 1.8e-6"
    );
    let cmf: Vec<[f64; 2]> = read_text(&data("cie1931_2deg_cmf_1nm.csv"))
        .lines()
        .filter_map(|line| {
            let v: Vec<f64> = line
                .split(',')
                .filter_map(|x| x.trim().parse().ok())
                .collect();
            (v.len() == 4).then(|| [v[0], v[2]])
        })
        .collect();
    let y_bb = |t: f64| {
        if t <= 100.0 {
            return 0.0;
        }
        let b = |l: f64| firemedium_core::blackbody::spectral_radiance(t, l);
        let peak = b(firemedium_core::blackbody::WIEN / t * 1e9);
        cmf.iter().map(|c| c[1] * b(c[0]) / peak).sum::<f64>()
    };
    let tent = |u: f64| 1.0 - (u - 0.5).abs();
    let mut sum = 0.0;
    let n = 8;
    for i in 0..n {
        for k in 0..n {
            // Pixel 41 spans x ∈ [3.1 − 42/16, 3.1 − 41/16]; rows 15–16 span z ∈ [0.4375, 0.5625].
            let x = 3.1 - 42.0 / 16.0 + (i as f64 + 0.5) / n as f64 / 16.0;
            let z = 0.4375 + (k as f64 + 0.5) / n as f64 * 0.125;
            let w = tent(x) * tent(z);
            let (mut tau, mut l, dy) = (0.0f64, 0.0f64, 2e-6);
            for j in 0..20_000 {
                let f = w * tent((j as f64 + 0.5) * dy);
                let sa = 1000.0 * f;
                l += sa * f * y_bb(2000.0 * f) * (-tau).exp() * dy;
                tau += sa * dy;
            }
            sum += l;
        }
    }
    let want = sum / (n * n) as f64;
    eprintln!("face centre Y {got}, closed form {want}");
    assert!(
        (got / want - 1.0).abs() < 0.03,
        "face centre Y {got}, closed form {want}"
    );
}

#[test]
fn a_homogeneous_preset_is_pbrt_v4s_measured_medium() {
    // "Ketchup" (Jensen et al. 2001, as pbrt-v4 lists it): σ'_s (0.18, 0.07, 0.03), σ_a (0.061, 0.97, 1.45) mm⁻¹,
    // as unbounded rgb spectra. The spectra's own colours (as reflectances under D65, scaled back) give the rgb.
    let dir = out_dir("preset");
    let f = dir.join("p.pbrt");
    std::fs::write(&f, "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nMakeNamedMedium \"k\" \"string type\" \"homogeneous\" \"string preset\" \"Ketchup\" \"float scale\" 2\n").unwrap();
    let sc = firemedium::render::scene::load(&f, &Default::default()).unwrap();
    let firemedium::render::scene::Medium::Homogeneous(firemedium::render::scene::Homogeneous {
        sa,
        ss,
        ..
    }) = &sc.media[0]
    else {
        panic!("not a homogeneous medium")
    };
    let n = sc.bins.n();
    let rgb_of = |s: &firemedium::render::spectrum::S| {
        // The colour of a spectrum (bin means) seen as a reflectance under D65: ∫ s D65 x̄ȳz̄ / ∫ D65 ȳ → sRGB.
        let d65 = sc.bins.d65();
        let mut lit = *s;
        for i in 0..n {
            lit.0[i] *= d65.0[i];
        }
        let xyz = sc.bins.to_xyz(&lit) / sc.bins.luminance(&d65);
        firemedium_core::cie::xyz_to_linear_srgb(xyz).to_array()
    };
    for (s, want) in [(ss, [0.18, 0.07, 0.03]), (sa, [0.061, 0.97, 1.45])] {
        let got = rgb_of(s);
        for c in 0..3 {
            let w = 2.0 * want[c];
            assert!(
                (got[c] - w).abs() < 0.02 * (w + 0.1 * 2.9),
                "{got:?} vs 2 × {want:?}"
            );
        }
    }
}

#[test]
fn the_memory_budget_is_shared_by_a_scenes_media() {
    // Three procedural clouds, each baked into 128³ samples (25 MB while baked, 8.5 MB once built): under a 30 MB
    // budget the first fits and the second does not, and the error names it (before, each medium had the whole
    // budget to itself, so a few lines could build gigabytes).
    let dir = out_dir("shared-budget");
    let mut scene = String::from("Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\n");
    for i in 0..3 {
        scene += &format!("MakeNamedMedium \"c{i}\" \"string type\" \"cloud\"\n");
    }
    std::fs::write(dir.join("c.pbrt"), scene).unwrap();
    let o = run_render(
        &dir.join("c.pbrt"),
        &dir.join("c.exr"),
        &["--max-memory", "0.03", "-q"],
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("c.pbrt:5:1")
            && e.contains("cloud medium \"c1\"")
            && e.contains("memory budget"),
        "{e}"
    );
}

#[test]
fn an_rgbgrid_emits_and_attenuates_as_pbrt_v4_defines_it() {
    // pbrt-v4's rgbgrid on [0, 1]³, 64 × 4 × 4 voxels of σ_a = 5 (rgb 5 5 5: a flat unbounded spectrum), σ_s = 0,
    // Le = (1, 1, 1) (an illuminant spectrum: D65 with ∫ D65 ȳ = ∫ ȳ, not photometrically scaled), seen
    // orthographically along +x through its middle (y, z ∈ [0.4, 0.6], where the trilinear lookup is flat in y
    // and z). Along x the lookup fades over the outer half-voxels: w(x) = min(1, ½ + 64 x, ½ + 64 (1 − x)), σ_a =
    // 5w and Le = w, so L = ∫₀¹ e^{−∫₀ˣ 5w} 5 w² dx · (1, 1, 1)'s Le, and the film records Y = ∫ȳ · that.
    let dir = out_dir("rgbgrid");
    let n = 64 * 4 * 4;
    let rgb = |v: f64| vec![format!("{v} {v} {v}"); n].join(" ");
    let grid = |extra: &str| {
        format!("MakeNamedMedium \"g\" \"string type\" \"rgbgrid\" \"integer nx\" 64 \"integer ny\" 4 \"integer nz\" 4 {extra}\n")
    };
    let view = "LookAt -5 0.5 0.5  0 0.5 0.5  0 0 1\nCamera \"orthographic\" \"float screenwindow\" [-0.1 0.1 -0.1 0.1]\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"zsobol\" \"integer pixelsamples\" 256\nPixelFilter \"box\"\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\n";
    let boxed = "AttributeBegin\nMediumInterface \"g\" \"\"\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 1 1 0 0 1 0 0 0 1 1 0 1 1 1 1 0 1 1] \"integer indices\" [0 2 1 0 3 2 4 5 6 4 6 7 0 1 5 0 5 4 3 7 6 3 6 2 0 4 7 0 7 3 1 2 6 1 6 5]\nAttributeEnd\n";
    let emitter = format!(
        "{view}{}{boxed}",
        grid(&format!(
            "\"rgb sigma_a\" [{}] \"rgb sigma_s\" [{}] \"rgb Le\" [{}]",
            rgb(5.0),
            rgb(0.0),
            rgb(1.0)
        ))
    );
    let f = dir.join("emit.pbrt");
    std::fs::write(&f, emitter).unwrap();
    let y = y_of(mean_rgb(
        &render(&f, &dir.join("emit.exr"), &[]),
        (0, 8),
        (0, 8),
    ));
    let steps = 200_000;
    let (mut tau, mut sum) = (0.0f64, 0.0f64);
    for i in 0..steps {
        let x = (i as f64 + 0.5) / steps as f64;
        let w = (0.5 + 64.0 * x).min(0.5 + 64.0 * (1.0 - x)).min(1.0);
        let dx = 1.0 / steps as f64;
        sum += (-(tau + 0.5 * 5.0 * w * dx)).exp() * 5.0 * w * w * dx;
        tau += 5.0 * w * dx;
    }
    let y_integral: f64 = firemedium_core::cie::cmf_table::CMF
        .iter()
        .map(|c| c[1])
        .sum();
    let want = y_integral * sum;
    eprintln!("rgbgrid: Y {y}, pbrt-v4's definition {want} (∫ȳ {y_integral} × {sum})");
    assert!(
        (y / want - 1.0).abs() < 0.01,
        "emitting rgbgrid: Y {y}, expected {want}"
    );
    // Without "sigma_a" pbrt-v4's σ_a is 1 in the whole box (no fade): a backlit box (an area light of Y = 1
    // behind it) transmits e^{−1}; with "float scale" 2, e^{−2}.
    for (scale, want) in [(1.0f64, (-1.0f64).exp()), (2.0, (-2.0f64).exp())] {
        let light = "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\nShape \"trianglemesh\" \"point3 P\" [3 -5 -5 3 5 -5 3 5 5 3 -5 5] \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n";
        let text = format!(
            "{view}{}{boxed}{light}",
            grid(&format!(
                "\"rgb sigma_s\" [{}] \"float scale\" {scale}",
                rgb(0.0)
            ))
        );
        let f = dir.join(format!("absorb{scale}.pbrt"));
        std::fs::write(&f, text).unwrap();
        let y = y_of(mean_rgb(
            &render(&f, &dir.join(format!("absorb{scale}.exr")), &[]),
            (0, 8),
            (0, 8),
        ));
        assert!(
            (y / want - 1.0).abs() < 0.01,
            "scale {scale}: transmitted Y {y}, expected {want}"
        );
    }
    // A grid whose size disagrees with nx·ny·nz is an error naming the counts.
    let f = dir.join("bad.pbrt");
    std::fs::write(
        &f,
        format!("{view}{}{boxed}", grid("\"rgb sigma_a\" [1 1 1]")),
    )
    .unwrap();
    let o = run_render(&f, &dir.join("bad.exr"), &["-q"]);
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && msg.contains("3072"), "{msg}");
}

/// A constant 2000 K grid filling the unit box (σ_a = σ_s = 1, albedo ½, isotropic), seen face-on and filling a
/// 16 × 16 film, with no other light, rendered at `maxdepth` with `extra` parameters for the medium.
fn scattering_box(dir: &Path, maxdepth: usize, medium: &str) -> PathBuf {
    let text = format!(
        r#"LookAt 0.5 -20 0.5   0.5 0 0.5   0 0 1
Camera "perspective" "float fov" 2.8624
Film "rgb" "integer xresolution" 16 "integer yresolution" 16 "string filename" "d.exr"
Sampler "independent" "integer pixelsamples" 64
PixelFilter "box"
Integrator "volpath" "integer maxdepth" {maxdepth}
WorldBegin
{}"#,
        unit_box(
            "box",
            1.0,
            r#""point3 p0" [ -1 -1 -1 ] "point3 p1" [ 2 2 2 ]"#,
            medium
        )
    );
    let p = dir.join(format!("box{maxdepth}{}.pbrt", medium.len()));
    std::fs::write(&p, text).unwrap();
    p
}

/// A 3³ `uniformgrid` medium `name` of density 1 at 2000 K (σ_a 1, σ_s `sigma_s` per metre, its grid's box `at`,
/// `more` parameters) inside the unit cube's `interface` mesh.
fn unit_box(name: &str, sigma_s: f64, at: &str, more: &str) -> String {
    let ones = ["1"; 27].join(" ");
    let temps = ["2000"; 27].join(" ");
    format!(
        r#"MakeNamedMedium "{name}" "string type" "uniformgrid" "integer nx" 3 "integer ny" 3 "integer nz" 3
  "float density" [ {ones} ] "float temperature" [ {temps} ]
  "spectrum sigma_a" [200 1 900 1] "spectrum sigma_s" [200 {sigma_s} 900 {sigma_s}]
  {at} {more}
AttributeBegin
  MediumInterface "{name}" ""
  Material "interface"
  Shape "trianglemesh" "point3 P" [ 0 0 0  1 0 0  0 1 0  1 1 0  0 0 1  1 0 1  0 1 1  1 1 1 ]
    "integer indices" [ 0 2 3 0 3 1  4 5 7 4 7 6  0 1 5 0 5 4  2 6 7 2 7 3  0 4 6 0 6 2  1 3 7 1 7 5 ]
AttributeEnd
"#
    )
}

/// The mean Y over the film's central 8 × 8 pixels and its standard error (from the pixels' spread).
fn centre_y(img: &(usize, usize, Vec<[f32; 3]>)) -> (f64, f64) {
    let ys: Vec<f64> = (4..12)
        .flat_map(|j| (4..12).map(move |i| (i, j)))
        .map(|(i, j)| y_of(mean_rgb(img, (i, i + 1), (j, j + 1))))
        .collect();
    let n = ys.len() as f64;
    let mean = ys.iter().sum::<f64>() / n;
    let var = ys.iter().map(|y| (y - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

#[test]
fn maxdepth_counts_a_real_scattering_event_as_pbrt_v4s_volpath() {
    // pbrt-v4's VolPathIntegrator adds a medium's emission only while depth < maxdepth and counts each real
    // scattering event as a bounce (`if (depth++ >= maxDepth)`): at maxdepth 1 a path sees the emission in front of
    // its first scattering event and nothing after, Y = Ỹ(T) · σ_a/σ_t · (1 − e^{−σ_t·1}) for this unit box
    // (Ỹ = ∫ȳ B̃ at 2000 K: 5.181; σ_a/σ_t = ½, σ_t = 2).
    let dir = out_dir("maxdepth");
    let want = thick_y(2000.0) * 0.5 * (1.0 - (-2.0f64).exp());
    let mut levels = Vec::new();
    for maxdepth in 1..=3 {
        // The default estimators (the fire light's samples and the medium's own), and pbrt-v4's: ratio tracking,
        // no fire light. Both have pbrt-v4's expected image.
        let ours = render(
            &scattering_box(&dir, maxdepth, ""),
            &dir.join(format!("o{maxdepth}.exr")),
            &["--spp", "1024"],
        );
        let theirs = render(
            &scattering_box(&dir, maxdepth, r#""string integrator" "ratio""#),
            &dir.join(format!("p{maxdepth}.exr")),
            &["--spp", "1024", "--fire-light", "off"],
        );
        // The fire light (left out of a scattering fire by default) built by name, and also sampled from the
        // scattering events inside its own fire (MIS with the phase function's directions there).
        let light = |extra: &[&str], tag: &str| {
            let img = render(
                &scattering_box(&dir, maxdepth, ""),
                &dir.join(format!("{tag}{maxdepth}.exr")),
                &[&["--spp", "1024", "--fire-light", "power"], extra].concat(),
            );
            centre_y(&img)
        };
        let ((a, sa), (b, sb)) = (centre_y(&ours), centre_y(&theirs));
        let ((c, sc), (e, se)) = (light(&[], "l"), light(&["--fire-light-inside"], "i"));
        eprintln!("maxdepth {maxdepth}: default {a:.4} ± {sa:.4}, pbrt-v4's estimator {b:.4} ± {sb:.4}, the light {c:.4} ± {sc:.4}, the light inside too {e:.4} ± {se:.4}");
        for (x, s, what) in [
            (a, sa, "default"),
            (c, sc, "the light"),
            (e, se, "the light inside too"),
        ] {
            assert!(
                (x - b).abs() < 4.0 * (s * s + sb * sb).sqrt(),
                "maxdepth {maxdepth}: {what} {x} ± {s}, pbrt-v4's estimator {b} ± {sb}"
            );
        }
        if maxdepth == 1 {
            for (got, s) in [(a, sa), (b, sb)] {
                assert!(
                    (got - want).abs() < 4.0 * s + 2e-3 * want,
                    "maxdepth 1: Y {got} ± {s}, closed form {want}"
                );
            }
        }
        levels.push(a);
    }
    // Each bounce adds the light scattered once more (albedo ½: a few per cent of the level and more).
    assert!(
        levels[1] > levels[0] * 1.03 && levels[2] > levels[1] * 1.005,
        "levels by maxdepth {levels:?}"
    );
}

#[test]
fn a_nanovdb_medium_names_its_grids_as_pbrt_v4s() {
    // pbrt-v4's NanoVDBMedium::Create reads "gridname" (default "density") and "temperaturename" (default
    // "temperature"). Naming the defaults renders the same image bit for bit; a name the file lacks is an error
    // that lists the file's grids; naming a grid both ways is refused.
    let dir = out_dir("gridname");
    std::fs::copy(data("valid/nvdb/plume48.nvdb"), dir.join("plume.nvdb")).unwrap();
    let scene = |extra: &str| {
        let p = dir.join(format!("g{}.pbrt", extra.len()));
        std::fs::write(
            &p,
            format!(
                r#"LookAt 0 -3 0  0 0 0  0 0 1
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 12 "integer yresolution" 12
Sampler "independent" "integer pixelsamples" 4
WorldBegin
MakeNamedMedium "plume" "string type" "nanovdb" "string filename" "plume.nvdb" "float Lescale" 2 {extra}
AttributeBegin
  MediumInterface "plume" ""
  Material "interface"
  Shape "sphere" "float radius" 0.9
AttributeEnd
"#
            ),
        )
        .unwrap();
        p
    };
    let plain = render(&scene(""), &dir.join("a.exr"), &[]);
    let named = render(
        &scene(r#""string gridname" "density" "string temperaturename" "temperature""#),
        &dir.join("b.exr"),
        &[],
    );
    assert!(plain.2.iter().any(|p| p[1] > 0.0), "the plume emits");
    assert_eq!(
        plain.2, named.2,
        "naming the default grids changed the image"
    );
    let o = run_render(
        &scene(r#""string temperaturename" "heat""#),
        &dir.join("c.exr"),
        &["-q"],
    );
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && msg.contains("'heat'") && msg.contains("'density', 'temperature'"),
        "{msg}"
    );
    let o = run_render(
        &scene(r#""string gridname" "density" "string densitygrid" "density""#),
        &dir.join("d.exr"),
        &["-q"],
    );
    let msg = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && msg.contains("\"gridname\" and \"densitygrid\""),
        "{msg}"
    );
}

/// The march's bias on pbrt-v4's grids: per pixel (those of `region` above 5 % of its brightest), |default −
/// reference| / reference, with the reference the march at a sixteenth of a voxel and sub-steps of optical depth ≤ 0.005
/// (converged: halving both moves no pixel by 1e-5). Returns (the largest, the mean image's).
fn march_bias(
    dir: &Path,
    name: &str,
    scene: &str,
    spp: &str,
    region: ((usize, usize), (usize, usize)),
) -> (f64, f64) {
    let at = |extra: &str, tag: &str| {
        let p = dir.join(format!("{name}-{tag}.pbrt"));
        std::fs::write(&p, scene.replace("EXTRA", extra)).unwrap();
        render(&p, &dir.join(format!("{name}-{tag}.exr")), &["--spp", spp])
    };
    let got = at("", "default");
    let want = at(
        r#""float stepsize" 0.0625 "float steptau" 0.005"#,
        "reference",
    );
    let ((x0, x1), (y0, y1)) = region;
    let y = |img: &(usize, usize, Vec<[f32; 3]>)| -> Vec<f64> {
        (y0..y1)
            .flat_map(|j| (x0..x1).map(move |i| (i, j)))
            .map(|(i, j)| luminance(img.2[i + img.0 * j]))
            .collect()
    };
    let (a, r) = (y(&got), y(&want));
    let top = r.iter().cloned().fold(0.0, f64::max);
    assert!(top > 0.0, "{name}: the reference is black");
    let worst = a
        .iter()
        .zip(&r)
        .filter(|(_, r)| **r > 0.05 * top)
        .map(|(a, r)| (a - r).abs() / r)
        .fold(0.0, f64::max);
    let mean = a.iter().sum::<f64>() / r.iter().sum::<f64>() - 1.0;
    eprintln!("{name}: largest pixel bias {worst:.2e}, mean {mean:+.2e}");
    (worst, mean)
}

#[test]
fn the_march_on_pbrt_v4s_grids_is_within_a_tenth_of_a_percent_of_their_integral() {
    // pbrt-v4's grid media take the march by default (pbrt-v4's ratio tracking is `integrator "ratio"`): its
    // bias against the exact integral, which is pbrt-v4's expected image, below 0.1 % of every pixel on the
    // pbrt-fidelity cases: a 32³ `uniformgrid` blob at 64 spp, the NanoVDB plume thin (σ_t·voxel ≤ 0.04) and
    // thick (≤ 0.8), the one-voxel tent at σ_a = 1000 (τ = 500 per half-voxel step, split), the constant slab.
    let dir = out_dir("march-bias");
    std::fs::copy(data("valid/nvdb/plume48.nvdb"), dir.join("plume.nvdb")).unwrap();
    let plume = |scale: f64| {
        format!(
            r#"LookAt 0 -3 0  0 0 0  0 0 1
Camera "perspective" "float fov" 30
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "stratified" "integer xsamples" 2 "integer ysamples" 2 "bool jitter" false
PixelFilter "box"
Integrator "volpath" "integer maxdepth" 1
WorldBegin
MakeNamedMedium "plume" "string type" "nanovdb" "string filename" "plume.nvdb"
  "spectrum sigma_s" [200 0 900 0] "float scale" {scale} EXTRA
AttributeBegin
  MediumInterface "plume" ""
  Material "interface"
  Shape "sphere" "float radius" 0.9
AttributeEnd
"#
        )
    };
    let slab = |file: &str| {
        read_text(&data(file)).replace(r#""float scale" 1"#, r#""float scale" 1 EXTRA"#)
    };
    // A 32³ `uniformgrid` blob (a Gaussian of density and temperature), inline, under pixel-area sampling.
    let blob = {
        let n = 32;
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |a: usize| (a as f64 + 0.5) / n as f64 - 0.5;
                    let g = (-(c(i).powi(2) + c(j).powi(2) + c(k).powi(2)) / 0.03).exp();
                    d.push(format!("{:.5}", 3.0 * g));
                    t.push(format!("{:.1}", 300.0 + 1600.0 * g));
                }
            }
        }
        format!(
            r#"LookAt 0 -4 0  0 0 0  0 0 1
Camera "perspective" "float fov" 20
Film "rgb" "integer xresolution" 32 "integer yresolution" 32
Sampler "independent" "integer pixelsamples" 64
Integrator "volpath" "integer maxdepth" 1
WorldBegin
MakeNamedMedium "blob" "string type" "uniformgrid" "integer nx" {n} "integer ny" {n} "integer nz" {n}
  "float density" [ {} ] "float temperature" [ {} ]
  "point3 p0" [ -0.5 -0.5 -0.5 ] "point3 p1" [ 0.5 0.5 0.5 ] "spectrum sigma_s" [200 0 900 0] "float scale" 4 EXTRA
AttributeBegin
  MediumInterface "blob" ""
  Material "interface"
  Shape "sphere" "float radius" 0.87
AttributeEnd
"#,
            d.join(" "),
            t.join(" ")
        )
    };
    let all = ((0, 32), (0, 32));
    for (name, scene, spp, region) in [
        ("blob", blob, "64", all),
        ("plume-thin", plume(1.0), "16", all),
        ("plume-thick", plume(20.0), "16", all),
        ("tent", slab("pbrt-v4-measured/slab.pbrt"), "64", BOX),
        ("slab", slab("pbrt-v4-measured/slab_const.pbrt"), "16", BOX),
    ] {
        assert!(scene.contains("EXTRA"), "{name}");
        let (worst, mean) = march_bias(&dir, name, &scene, spp, region);
        assert!(
            worst < 1e-3 && mean.abs() < 1e-3,
            "{name}: largest pixel bias {worst:.2e}, mean {mean:+.2e}: expected below 1e-3"
        );
    }
}

#[test]
fn a_scattering_fire_lights_a_floor_alike_whether_its_paths_aim_at_it_or_not() {
    // A floor 2–3 m from a scattering (albedo 0.8), emitting unit box, seen from above with the fire out of view:
    // the light on it is the fire's, unscattered and scattered out. Aiming a share of the floor's directions at the
    // fire's box (by default for every fire that scatters) weighs each path by the mixture's density, and the fire
    // light's samples (left out of this fire by default, built by name) by MIS against it: the same mean as the
    // BSDF's directions alone, and less noise.
    let dir = out_dir("guide");
    let text = format!(
        r#"LookAt 3 0.5 4   3 0.5 0   0 1 0
Camera "perspective" "float fov" 14
Film "rgb" "integer xresolution" 16 "integer yresolution" 16 "string filename" "g.exr"
Sampler "independent" "integer pixelsamples" 64
PixelFilter "box"
Integrator "volpath" "integer maxdepth" 5
WorldBegin
{}Material "diffuse" "rgb reflectance" [ 0.5 0.5 0.5 ]
Shape "trianglemesh" "point3 P" [ -5 -5 -0.001  8 -5 -0.001  8 6 -0.001  -5 6 -0.001 ] "integer indices" [ 0 1 2 0 2 3 ]
"#,
        unit_box(
            "fire",
            4.0,
            r#""point3 p0" [ 0 0 0 ] "point3 p1" [ 1 1 1 ]"#,
            ""
        )
    );
    let scene = dir.join("floor.pbrt");
    std::fs::write(&scene, text).unwrap();
    // Per pixel Y, and the render's own estimate of its relative RMSE (two interleaved halves of each pixel's
    // samples).
    let floor = |guide: &str, light: &str, spp: &str| {
        let out = dir.join(format!("{guide}-{light}.exr"));
        let args = [
            "--spp",
            spp,
            "--seed",
            "5",
            "--stats",
            "--fire-guide",
            guide,
            "--fire-light",
            light,
        ];
        let o = run_render(&scene, &out, &args);
        let log =
            String::from_utf8_lossy(&o.stdout).to_string() + &String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{log}");
        let rmse: f64 = log
            .split("estimated relative RMSE ")
            .nth(1)
            .and_then(|r| r.split_whitespace().next())
            .and_then(|r| r.parse().ok())
            .unwrap_or_else(|| panic!("no estimated error in {log}"));
        let img = read_exr(&out);
        let ys: Vec<f64> = (0..16 * 16)
            .map(|k| y_of(mean_rgb(&img, (k % 16, k % 16 + 1), (k / 16, k / 16 + 1))))
            .collect();
        (ys, rmse)
    };
    let (off, e_off) = floor("off", "auto", "8192");
    let mean = off.iter().sum::<f64>() / off.len() as f64;
    assert!(mean > 0.0, "the fire lights the floor");
    // (The light's samples cost most: a quarter of the samples, their error scaled to the others'.)
    for (guide, light, spp) in [
        ("auto", "auto", 8192),
        ("0.9", "auto", 8192),
        ("auto", "power", 2048),
    ] {
        // The pixels' differences from the BSDF's alone (the floor's own gradient cancels): their mean and its
        // standard error.
        let (ys, e) = floor(guide, light, &spp.to_string());
        let e = e * (spp as f64 / 8192.0).sqrt();
        let d: Vec<f64> = ys.iter().zip(&off).map(|(a, b)| a - b).collect();
        let n = d.len() as f64;
        let dm = d.iter().sum::<f64>() / n;
        let se = (d.iter().map(|x| (x - dm).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt();
        eprintln!("{guide}, light {light}: floor Y {mean:.5e}, aimed − BSDF alone {dm:.3e} ± {se:.2e}; estimated rel. RMSE {e:.4} (BSDF alone {e_off:.4})");
        assert!(
            dm.abs() < 4.0 * se + 1e-3 * mean,
            "{guide}, light {light}: the floor's mean moved by {dm} ± {se} of {mean}"
        );
        // The aimed paths reach the fire more often: less noise.
        assert!(
            e < 0.8 * e_off,
            "{guide}, light {light}: estimated rel. RMSE {e}, BSDF alone {e_off}"
        );
    }
}
