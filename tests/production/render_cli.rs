//! End-to-end renders through the built `firemedium` binary and the built plugin cdylib: a furnace, a sphere
//! of uniform fire against its closed form, a pbrt-v4 `uniformgrid` pixel against an integration of that ray
//! written from pbrt-v4's definitions, and the default scene's EXR (finite everywhere, lit by the fire).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::image;
use image::{luminance, mean_y, read_exr};

use crate::common::scratch;

use crate::common::guard;

/// The test's scratch folder (removed when it passes).
fn tmp(name: &str) -> scratch::Scratch {
    scratch::Scratch::new("render", name)
}

/// `dir/s.pbrt`: a white sky seen by a `px`² film at 1 spp — the smallest scene that renders.
fn sky_scene(dir: &Path, px: u32) -> PathBuf {
    let scene = dir.join("s.pbrt");
    std::fs::write(
        &scene,
        format!("LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" {px} \"integer yresolution\" {px}\nSampler \"independent\" \"integer pixelsamples\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n"),
    )
    .unwrap();
    scene
}

/// `firemedium ARGS` run in `dir`.
fn firemedium_in(dir: &Path, args: &[&str]) -> std::process::Output {
    Command::new(crate::common::exe("firemedium"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// Whether two EXRs hold the same render: the same pixels, bit for bit, and the same record but for the render
/// time (the one line two renders of a scene differ in).
fn same_render(a: &Path, b: &Path) -> bool {
    let record = |p: &Path| firemedium::imageio::read_meta(p).unwrap();
    let ((wa, ma), (wb, mb)) = (record(a), record(b));
    read_exr(a) == read_exr(b)
        && wa == wb
        && firemedium::imageio::record_differences(&ma, &mb).is_none()
}

fn render(scene: &Path, extra: &[&str]) -> PathBuf {
    let out = scene.with_extension("exr");
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(&out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "render {}: {}\n{}",
        scene.display(),
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    out
}

#[test]
fn furnace_closed_diffuse_sphere() {
    // Inside a closed sphere that both emits L and reflects diffusely with ρ, every direction sees
    // L (1 + ρ + ρ² + …) = L / (1 − ρ). Compared against the same sphere with ρ = 0.
    let dir = tmp("furnace");
    let scene = |rho: f64| {
        format!(
            "LookAt 0 0 0  0 1 0  0 0 1\nCamera \"perspective\" \"float fov\" 60\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nSampler \"independent\" \"integer pixelsamples\" 64\nIntegrator \"volpath\" \"integer maxdepth\" 200\nWorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"bool twosided\" true\nMaterial \"diffuse\" \"rgb reflectance\" [{rho} {rho} {rho}]\nShape \"sphere\" \"float radius\" 3\nAttributeEnd\n"
        )
    };
    std::fs::write(dir.join("f0.pbrt"), scene(0.0)).unwrap();
    std::fs::write(dir.join("f5.pbrt"), scene(0.5)).unwrap();
    let (_, _, p0) = read_exr(&render(&dir.join("f0.pbrt"), &[]));
    let (_, _, p5) = read_exr(&render(&dir.join("f5.pbrt"), &[]));
    let (y0, y5) = (mean_y(&p0), mean_y(&p5));
    assert!(y0 > 0.0);
    // Emission only: every pixel is exactly L.
    assert!(p0.iter().all(|p| (luminance(*p) / y0 - 1.0).abs() < 1e-5));
    let ratio = y5 / y0;
    eprintln!("furnace: L(ρ=0.5)/L(ρ=0) = {ratio:.5} (closed form 2)");
    assert!(
        (ratio - 2.0).abs() < 0.02,
        "furnace: L(ρ=0.5)/L(ρ=0) = {ratio}, expected 2"
    );
}

fn inline_grid(n: usize, density: f64, temperature: f64) -> String {
    let d = vec![format!("{density}"); n * n * n].join(" ");
    let t = vec![format!("{temperature}"); n * n * n].join(" ");
    format!("\"integer nx\" {n} \"integer ny\" {n} \"integer nz\" {n} \"float density\" [{d}] \"float temperature\" [{t}]")
}

#[test]
fn a_sphere_of_uniform_fire_matches_the_closed_form() {
    // Soot at 1600 K filling a sphere of radius R: the centre pixel sees L = Σ_c (j_c/σ_c)(1 − e^{−2σ_c R}).
    let dir = tmp("sphere");
    let (r, fv, t) = (0.5, 2e-7, 1600.0);
    let scene = format!(
        "LookAt 0 -20 0  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 0.5\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 4\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1] \"string interpolation\" \"nearest\" \"float alpha\" 1\nAttributeBegin\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" {r}\nAttributeEnd\n",
        inline_grid(4, fv, t)
    );
    std::fs::write(dir.join("s.pbrt"), &scene).unwrap();
    let (w, h, px) = read_exr(&render(&dir.join("s.pbrt"), &[]));
    let centre = luminance(px[w / 2 + w * (h / 2)]);
    // The closed form, from the plugin's own coefficients (rlib) and the same bins.
    use firemedium_plugin::params::Param;
    let v = firemedium_plugin::volume::FireVolume::new(&[
        Param::floats("density", &vec![fv; 64]),
        Param::floats("temperature", &vec![t; 64]),
        Param::int("nx", 4),
        Param::int("ny", 4),
        Param::int("nz", 4),
        Param::string("interpolation", "nearest"),
        Param::float("alpha", 1.0),
    ])
    .unwrap();
    let (mut sa, mut ss, mut j) = (vec![0.0; 30], vec![0.0; 30], vec![0.0; 30]);
    v.coefficients(glam::DVec3::splat(0.5), &mut sa, &mut ss, &mut j);
    let xyz = v.channel_xyz();
    // The camera is 20 m away with a 0.5° field: rays within ±0.002 of the centre chord.
    let want: f64 = (0..30)
        .map(|c| xyz[c].y * j[c] / sa[c] * -(-2.0 * sa[c] * r).exp_m1())
        .sum();
    eprintln!(
        "fire sphere: centre pixel Y {centre:.6e} vs closed form {want:.6e} ({:+.2e})",
        centre / want - 1.0
    );
    assert!(
        (centre / want - 1.0).abs() < 0.01,
        "centre pixel Y {centre} vs closed form {want}"
    );
}

#[test]
fn a_pbrt_uniformgrid_pixel_matches_pbrts_definitions() {
    // pbrt-v4 uniformgrid with a temperature field: the centre pixel against an integration written from
    // pbrt-v4's definitions in this test (not the plugin's march, which renders the pixel).
    let dir = tmp("grid");
    let n = 6;
    let dens: Vec<String> = (0..n * n * n)
        .map(|i| format!("{}", 0.5 + 0.4 * ((i * 7 % 11) as f64 / 11.0)))
        .collect();
    let temp: Vec<String> = (0..n * n * n)
        .map(|i| format!("{}", 1200.0 + 600.0 * ((i * 5 % 13) as f64 / 13.0)))
        .collect();
    let scene = format!(
        "LookAt 0 -30 0  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 0.05\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nSampler \"independent\" \"integer pixelsamples\" 16\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"g\" \"string type\" \"uniformgrid\" \"integer nx\" {n} \"integer ny\" {n} \"integer nz\" {n} \"float density\" [{}] \"float temperature\" [{}] \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1] \"spectrum sigma_a\" [0.8] \"spectrum sigma_s\" [0] \"string integrator\" \"march\" \"float Lescale\" 2\nAttributeBegin\nMediumInterface \"g\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.7\nAttributeEnd\n",
        dens.join(" "),
        temp.join(" ")
    );
    std::fs::write(dir.join("g.pbrt"), &scene).unwrap();
    let (w, h, px) = read_exr(&render(&dir.join("g.pbrt"), &[]));
    let got = luminance(px[w / 2 + w * (h / 2)]);
    // The reference, written here from pbrt-v4's definitions rather than taken from the plugin: the central ray
    // (x = z = 0) crosses the grid between samples 2 and 3 of x and z; pbrt's trilinear lookup at cell centres
    // (i + ½)/n; σ_a = 0.8 · density; Le = Lescale · the blackbody normalised to its peak (pbrt-v4's
    // BlackbodySpectrum); L = ∫ σ_a Le e^(−∫σ_a) ds, by midpoints of 1e-4; the film's Y = ∫ L ȳ dλ over
    // 380–780 nm by 1 nm (Le is unitless: no 683 lm/W).
    let to_f = |v: &[String]| {
        v.iter()
            .map(|s| s.parse::<f64>().unwrap())
            .collect::<Vec<_>>()
    };
    let (d, tk) = (to_f(&dens), to_f(&temp));
    let at = |g: &[f64], y: f64| {
        // Trilinear at (x, y, z) = (0, y, 0): equal weights on samples 2 and 3 of x and z.
        let s = (y + 1.0) / 2.0 * n as f64 - 0.5;
        let (j0, f) = (s.floor(), s - s.floor());
        let row = |j: f64| {
            if j < 0.0 || j >= n as f64 {
                return 0.0;
            }
            let j = j as usize;
            [(2, 2), (3, 2), (2, 3), (3, 3)]
                .iter()
                .map(|&(i, k)| g[i + n * (j + n * k)])
                .sum::<f64>()
                / 4.0
        };
        (1.0 - f) * row(j0) + f * row(j0 + 1.0)
    };
    let planck = |t: f64, l_nm: f64| {
        let l = l_nm * 1e-9;
        let (h, c, k) = (6.62607015e-34, 299792458.0, 1.380649e-23);
        2.0 * h * c * c / l.powi(5) / ((h * c / (l * k * t)).exp() - 1.0)
    };
    let ds = 1e-4;
    let want: f64 = (380..780)
        .map(|li| {
            let l_nm = li as f64 + 0.5;
            let (mut tau, mut rad) = (0.0, 0.0);
            let mut y = -1.0 + 0.5 * ds;
            while y < 1.0 {
                let sa = 0.8 * at(&d, y);
                let t = at(&tk, y);
                let peak = planck(t, 2.8977721e-3 / t * 1e9);
                let le = 2.0 * planck(t, l_nm) / peak;
                rad += sa * le * (-tau - 0.5 * sa * ds).exp() * ds;
                tau += sa * ds;
                y += ds;
            }
            rad * firemedium_core::cie::cmf(l_nm).y
        })
        .sum();
    assert!(want > 0.0);
    eprintln!(
        "uniformgrid: pixel Y {got:.6e} vs the reference {want:.6e} ({:+.2e})",
        got / want - 1.0
    );
    // (The render's 10 nm bins against the reference's 1 nm: 0.8 % measured.)
    assert!(
        (got / want - 1.0).abs() < 0.015,
        "pixel Y {got} vs reference {want}"
    );
}

#[test]
fn the_mantaflow_scene_renders_finite_and_lit() {
    let scene = crate::common::root().join("scenes/mantaflow/scene.pbrt");
    let dir = tmp("default");
    let out = dir.join("room.exr");
    let o = Command::new(crate::common::exe("firemedium"))
        .args(["render"])
        .arg(&scene)
        .arg("-o")
        .arg(&out)
        .args(["--spp", "2", "--stats", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("medium \"flame\": plugin built") && text.contains("camera rays/s"),
        "{text}"
    );
    // The fire is the scene's light (issue 6).
    assert!(
        text.contains("1 lights")
            && text.contains("fire light:")
            && text.contains("emitting voxels"),
        "{text}"
    );
    let (w, h, px) = read_exr(&out);
    assert_eq!((w, h), (320, 240));
    assert!(
        px.iter().all(|p| p.iter().all(|c| c.is_finite())),
        "NaN or infinity in the image"
    );
    // The fire's core is bright; the corners of the dark room are dim; the PNG preview exists.
    let fire = luminance(px[160 + w * 150]);
    let corner = luminance(px[5 + w * 5]);
    eprintln!("mantaflow scene: fire core Y {fire:.1} cd/m², corner {corner:.3e}");
    assert!(
        fire > 100.0 && fire > 1000.0 * corner.max(1e-9),
        "fire {fire} cd/m², corner {corner}"
    );
    assert!(out.with_extension("png").is_file());
}

#[test]
fn bad_scenes_exit_1_with_file_line_col() {
    let dir = tmp("bad");
    for (name, text, want) in [
        ("typo.pbrt", "WorldBegin\nShpe \"sphere\"\n", "typo.pbrt:2:1: unknown directive 'Shpe'"),
        ("medium.pbrt", "Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"string dataset\" \"nope.vdb\"\n", "medium.pbrt:3:1: medium \"f\" (fire)"),
        ("light.pbrt", "Camera \"perspective\"\nWorldBegin\nLightSource \"goniometric\"\n", "light.pbrt:3:1: light \"goniometric\" is not supported"),
        // A plugin parameter's error points at the parameter itself (the plugin gets each one's location), not
        // at the directive: here a negative sootscale on line 4, and fuelnk that nothing reads with fuel propane.
        ("sootscale.pbrt", "Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\"\n  \"integer nx\" 1 \"float density\" [1] \"float sootscale\" -1\n", "sootscale.pbrt:4:38: medium \"f\" (fire): volume: parameter 'sootscale' = -1"),
        // Hardening: geometry that overflows f32 (the BVH build panicked), negative indices (became vertex 0),
        // an unbalanced AttributeBegin (passed silently), an instance inside an object's definition.
        ("huge.pbrt", "Camera \"perspective\"\nWorldBegin\nShape \"sphere\" \"float radius\" 1e39\n", "huge.pbrt:3:1: sphere: its bounds"),
        ("scaled.pbrt", "Camera \"perspective\"\nWorldBegin\nScale 1e300 1 1\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\n", "scaled.pbrt:4:1: trianglemesh: its bounds"),
        ("negative.pbrt", "Camera \"perspective\"\nWorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 -1 2]\n", "negative.pbrt:3:1: trianglemesh: \"integer indices\" [1] = -1: expected a vertex number from 0"),
        ("unbalanced.pbrt", "Camera \"perspective\"\nWorldBegin\nAttributeBegin\nShape \"sphere\"\n", "unbalanced.pbrt:3:1: AttributeBegin (or TransformBegin, ObjectBegin) without its End"),
        ("nested.pbrt", "Camera \"perspective\"\nWorldBegin\nObjectBegin \"a\"\nShape \"sphere\"\nObjectEnd\nObjectBegin \"b\"\nObjectInstance \"a\"\nObjectEnd\n", "nested.pbrt:7:1: ObjectInstance \"a\" inside object \"b\""),
        // A film of 1e9 pixels a side allocated until the process aborted; 0 was clamped to 1 silently.
        ("film.pbrt", "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 1000000000\nWorldBegin\n", "film.pbrt:2:12: film: \"integer xresolution\" 1000000000: expected 1 to 65536 pixels"),
        ("film0.pbrt", "Camera \"perspective\"\nFilm \"rgb\" \"integer yresolution\" 0\nWorldBegin\n", "film0.pbrt:2:12: film: \"integer yresolution\" 0: expected 1 to 65536 pixels"),
        // A typo in a pbrt-v4 parameter: at the parameter, with the closest name.
        ("radus.pbrt", "Camera \"perspective\"\nWorldBegin\nShape \"sphere\" \"float radus\" 2\n", "radus.pbrt:3:16: sphere: unknown parameter \"float radus\" (did you mean \"radius\"?)"),
        ("unread.pbrt", "Camera \"perspective\"\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"float density\" [1]\n  \"float fuelnk\" [500 1.5 0.5]\n", "unread.pbrt:4:3: medium \"f\" (fire): volume: parameter 'fuelnk' = given, but nothing in this configuration reads it"),
    ] {
        std::fs::write(dir.join(name), text).unwrap();
        let o = Command::new(crate::common::exe("firemedium")).arg("render").arg(dir.join(name)).output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{name}");
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(e.contains(want) && e.trim_end().lines().count() == 1, "{name}: {e}");
    }
}

#[test]
fn firemedium_simd_caps_the_kernel_and_refuses_what_it_cannot_honour() {
    // `FIREMEDIUM_SIMD=avx2` runs the march's AVX2 clone on a CPU with AVX-512 (on an AVX2 machine it is the one
    // clone there is): the same image bit for bit. A value it cannot honour is refused, named, before any work.
    let dir = tmp("simd");
    let grid: String = (0..216)
        .map(|k| format!("{} ", 1e-7 * (1.0 + (k % 7) as f64)))
        .collect();
    let temps: String = (0..216)
        .map(|k| format!("{} ", 1200.0 + 60.0 * (k % 11) as f64))
        .collect();
    let scene = format!(
        "LookAt 0 -4 0  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 12\nSampler \"independent\" \"integer pixelsamples\" 4\nIntegrator \"volpath\" \"integer maxdepth\" 2\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" \"integer nx\" 6 \"integer ny\" 6 \"integer nz\" 6 \"float density\" [{grid}] \"float temperature\" [{temps}] \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1]\nAttributeBegin\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n"
    );
    std::fs::write(dir.join("s.pbrt"), &scene).unwrap();
    let run = |simd: &str, out: &str| {
        Command::new(crate::common::exe("firemedium"))
            .env("FIREMEDIUM_SIMD", simd)
            .arg("render")
            .arg(dir.join("s.pbrt"))
            .arg("-o")
            .arg(dir.join(out))
            .arg("--quiet")
            .output()
            .unwrap()
    };
    let (native, avx2) = (run("native", "native.exr"), run("avx2", "avx2.exr"));
    assert!(
        native.status.success() && avx2.status.success(),
        "{native:?}\n{avx2:?}"
    );
    assert!(mean_y(&read_exr(&dir.join("native.exr")).2) > 0.0);
    assert!(same_render(&dir.join("native.exr"), &dir.join("avx2.exr")));
    let o = run("avx1024", "bad.exr");
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("FIREMEDIUM_SIMD") && e.contains("\"avx1024\"") && e.contains("native or avx2"),
        "{e}"
    );
}

#[test]
fn the_command_holds_none_of_the_plugins_code() {
    // The renderer reaches the fire through the loader and the C ABI only: the plugin's code is in the plugin,
    // not linked into the command (the readers `info` and `gen` share with it are the dataset crate's). Rust's
    // mangled symbols carry their crate's name with its length first, so a function of the plugin's crate linked
    // in would leave "17firemedium_plugin" in the symbol table (the entry point's name "firemedium_plugin_entry",
    // which the loader looks up, is not mangled).
    let exe = crate::common::exe("firemedium");
    let bytes = std::fs::read(&exe).unwrap_or_else(|e| panic!("{}: {e}", exe.display()));
    let has = |s: &[u8]| bytes.windows(s.len()).any(|w| w == s);
    assert!(
        has(b"18firemedium_dataset") && has(b"15firemedium_core"),
        "{}: no mangled symbols of the crates it does link (stripped?)",
        exe.display()
    );
    assert!(
        !has(b"17firemedium_plugin"),
        "{} links the plugin's crate",
        exe.display()
    );
}

/// The plugin this test run built, and a C shim plugin (`tests/c/SRC`, built against the header) that forwards to it
/// through `FIREMEDIUM_REAL_PLUGIN`: (real, shim).
fn shim_plugin(dir: &Path, src: &str) -> (PathBuf, PathBuf) {
    let root = crate::common::root();
    let bin = crate::common::exe("firemedium");
    let real = bin.parent().unwrap().join("deps").join(format!(
        "{}firemedium_plugin{}",
        std::env::consts::DLL_PREFIX,
        std::env::consts::DLL_SUFFIX
    ));
    assert!(real.is_file(), "{} not built", real.display());
    let shim = dir.join(format!("lib{}", src.replace(".c", ".so")));
    let cc = Command::new("gcc")
        .args(["-std=c11", "-Wall", "-Werror", "-shared", "-fPIC", "-I"])
        .arg(root.join("plugin/abi/include"))
        .arg(root.join("tests/c").join(src))
        .arg("-o")
        .arg(&shim)
        .arg("-ldl")
        .output()
        .unwrap();
    assert!(
        cc.status.success(),
        "{}",
        String::from_utf8_lossy(&cc.stderr)
    );
    (real, shim)
}

/// An 8 × 8 film looking at a 4³ soot fire at 1600 K inside a sphere, `spp` samples a pixel.
fn small_fire_scene(spp: usize) -> String {
    format!(
        "LookAt 0 -3 0.5  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" {spp}\nWorldBegin\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"float sootscale\" 1e-6\nAttributeBegin\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 2\nAttributeEnd\n",
        inline_grid(4, 1.0, 1600.0)
    )
}

#[test]
fn the_film_takes_its_colour_from_the_plugin_it_loaded() {
    // A plugin (C, through the header) that forwards to the real one but reports every channel's XYZ weights
    // doubled: the renderer must render exactly twice as bright through it. (It computed its own weights from a
    // linked copy of the plugin's code before, so a plugin from another commit rendered silently wrong.)
    let dir = tmp("colour");
    let bin = crate::common::exe("firemedium");
    let (real, shim) = shim_plugin(&dir, "doubled_colour_plugin.c");
    let scene = small_fire_scene(2);
    std::fs::write(dir.join("c.pbrt"), scene).unwrap();
    let plain = read_exr(&render(
        &dir.join("c.pbrt"),
        &["--plugin", real.to_str().unwrap()],
    ))
    .2;
    let o = Command::new(&bin)
        .arg("render")
        .arg(dir.join("c.pbrt"))
        .args([
            "-o",
            dir.join("d.exr").to_str().unwrap(),
            "--quiet",
            "--plugin",
        ])
        .arg(&shim)
        .env("FIREMEDIUM_REAL_PLUGIN", &real)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let doubled = read_exr(&dir.join("d.exr")).2;
    let (mut lit, mut worst) = (0, 0f64);
    for (a, b) in plain.iter().zip(&doubled) {
        for c in 0..3 {
            if a[c] != 0.0 {
                lit += 1;
                worst = worst.max((b[c] as f64 / a[c] as f64 - 2.0).abs());
            }
        }
    }
    assert!(lit > 0, "the fire is not in view");
    assert!(
        worst < 1e-6,
        "doubled weights give {worst} away from twice the image"
    );
}

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
fn unsupported_pbrt_parameters_are_named_where_they_stand() {
    // pbrt-v4 reads an integrator's "regularize" and a shape's "alpha"; this renderer does not yet: each is a
    // warning at its own position, never dropped silently (pbrt-v4's ReportUnused).
    let dir = tmp("unsupported");
    let scene = "Camera \"perspective\" \"float fov\" 30\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nIntegrator \"volpath\" \"bool regularize\" true\nWorldBegin\nShape \"sphere\" \"float alpha\" 0.5\n";
    std::fs::write(dir.join("u.pbrt"), scene).unwrap();
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(dir.join("u.pbrt"))
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{e}");
    for want in [
        "u.pbrt:3:22: warning: integrator \"volpath\": \"bool regularize\" is read by pbrt-v4 but not supported",
        "u.pbrt:5:16: warning: sphere: \"float alpha\" is read by pbrt-v4 but not supported",
    ] {
        assert!(e.contains(want), "{want}\nin\n{e}");
    }
}

fn write_exr_map(path: &Path, w: usize, h: usize, f: impl Fn(f32, f32) -> f32 + Sync) {
    exr::prelude::write_rgb_file(path, w, h, |x, y| {
        let v = f((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
        (v, v, v)
    })
    .unwrap();
}

#[test]
fn environment_maps_light_the_right_directions() {
    // Upper hemisphere bright, lower dark: lat-long (2:1, top rows = +z) and pbrt-v4's equal-area square
    // (+z hemisphere = the inner diamond |2u−1| + |2v−1| ≤ 1).
    let dir = tmp("env");
    write_exr_map(
        &dir.join("ll.exr"),
        64,
        32,
        |_, v| if v < 0.5 { 2.0 } else { 0.0 },
    );
    write_exr_map(&dir.join("ea.exr"), 64, 64, |u, v| {
        if (2.0 * u - 1.0).abs() + (2.0 * v - 1.0).abs() < 1.0 {
            2.0
        } else {
            0.0
        }
    });
    for map in ["ll.exr", "ea.exr"] {
        for (look, want_bright) in [("0 0 1", true), ("0 0 -1", false)] {
            let up = "0 1 0";
            let scene = format!("LookAt 0 0 0  {look}  {up}\nCamera \"perspective\" \"float fov\" 10\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nSampler \"independent\" \"integer pixelsamples\" 4\nWorldBegin\nLightSource \"infinite\" \"string filename\" \"{map}\"\n");
            let f = dir.join(format!("{map}-{}.pbrt", want_bright));
            std::fs::write(&f, scene).unwrap();
            let (_, _, px) = read_exr(&render(&f, &[]));
            let y = mean_y(&px);
            if want_bright {
                // pbrt-v4: a texel (2, 2, 2) is twice the colour space's illuminant scaled to 1 nit: Y = 2.
                assert!((y / 2.0 - 1.0).abs() < 1e-3, "{map} looking {look}: Y {y}");
            } else {
                assert!(y < 1e-6, "{map} looking {look}: Y {y}");
            }
        }
    }
}

#[test]
fn an_srgb_imagemap_on_a_diffuse_floor_under_a_uniform_sky() {
    // A floor whose reflectance is a grey PNG (sRGB 128 → linear 0.2158) under a uniform sky L: radiance ρL.
    let dir = tmp("imagemap");
    {
        let f = std::fs::File::create(dir.join("grey.png")).unwrap();
        let mut e = png::Encoder::new(std::io::BufWriter::new(f), 4, 4);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.write_header()
            .unwrap()
            .write_image_data(&[128u8; 48])
            .unwrap();
    }
    let scene = "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 20\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 256\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nTexture \"g\" \"spectrum\" \"imagemap\" \"string filename\" \"grey.png\"\nMaterial \"diffuse\" \"texture reflectance\" \"g\"\nShape \"trianglemesh\" \"point3 P\" [-50 -50 0 50 -50 0 50 50 0 -50 50 0] \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n";
    std::fs::write(dir.join("floor.pbrt"), scene).unwrap();
    let sky = "LookAt 0 0 5  0 0 10  0 1 0\nCamera \"perspective\" \"float fov\" 20\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 4\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n";
    std::fs::write(dir.join("sky.pbrt"), sky).unwrap();
    let floor = mean_y(&read_exr(&render(&dir.join("floor.pbrt"), &[])).2);
    let l = mean_y(&read_exr(&render(&dir.join("sky.pbrt"), &[])).2);
    let rho = ((128.0f64 / 255.0 + 0.055) / 1.055).powf(2.4);
    eprintln!("imagemap floor: Y/L = {:.4} (ρ = {rho:.4})", floor / l);
    assert!(
        (floor / l / rho - 1.0).abs() < 0.03,
        "floor/sky {} vs ρ {rho}",
        floor / l
    );
}

#[test]
fn a_thick_scattering_emitting_medium_is_in_equilibrium() {
    // Deep inside a homogeneous medium that emits L_e (σ_a L_e) and scatters with albedo ½, L = L_e: in-scattering
    // restores what out-scattering removes. (Counting scattering as extinction would give ½ L_e.)
    let dir = tmp("equilibrium");
    for (name, ss) in [("absorbing", 0.0), ("scattering", 1.0)] {
        // The camera sits in the medium: pbrt's camera medium is the outside medium at the Camera directive.
        let scene = format!(
            "LookAt 0 0 0  0 1 0  0 0 1\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 128\nIntegrator \"volpath\" \"integer maxdepth\" 400\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\" \"spectrum sigma_a\" [1] \"spectrum sigma_s\" [{ss}] \"spectrum Le\" [1] \"float g\" 0.3\nMediumInterface \"\" \"m\"\nCamera \"perspective\" \"float fov\" 30\nWorldBegin\nAttributeBegin\nMediumInterface \"m\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 40\nAttributeEnd\n"
        );
        let f = dir.join(format!("{name}.pbrt"));
        std::fs::write(&f, scene).unwrap();
        let y = mean_y(&read_exr(&render(&f, &[])).2);
        // pbrt-v4 scales a homogeneous medium's Le to luminance 1 ("equivalent to 1 nit") times Lescale: Y = 1.
        let want = 1.0;
        eprintln!("equilibrium ({name}): Y/Y(L_e) = {:.4}", y / want);
        assert!((y / want - 1.0).abs() < 0.02, "{name}: {y} vs {want}");
    }
}

#[test]
fn a_pbrt_nanovdb_scene_like_explosion_pbrt_renders() {
    // The parameters of pbrt-v4's explosion.pbrt (spelled as pbrt-v4 reads them), on the shipped plume48.nvdb:
    // a scattering, emitting nanovdb medium behind an interface sphere, lit by a sky.
    let dir = tmp("nanovdb");
    let nvdb = crate::common::root().join("tests/data/valid/nvdb/plume48.nvdb");
    let scene = format!(
        "LookAt 0 -3 0  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 30\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24\nSampler \"independent\" \"integer pixelsamples\" 8\nIntegrator \"volpath\" \"integer maxdepth\" 5\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.02 0.02 0.03]\nMakeNamedMedium \"kaboom\" \"string type\" \"nanovdb\" \"string filename\" \"{}\" \"spectrum sigma_s\" [200 10 900 10] \"spectrum sigma_a\" [200 10 900 10] \"float Lescale\" 5 \"float temperaturecutoff\" 1 \"float temperaturescale\" 1.5\nAttributeBegin\nMediumInterface \"kaboom\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n",
        nvdb.display()
    );
    std::fs::write(dir.join("kaboom.pbrt"), scene).unwrap();
    let (w, h, px) = read_exr(&render(&dir.join("kaboom.pbrt"), &["--stats"]));
    let bad: Vec<_> = px
        .iter()
        // (A hot fire's colour lies outside sRGB: blue a little below zero, relative to red.)
        .filter(|p| {
            !p.iter()
                .all(|c| c.is_finite() && *c >= -0.05 * p[0].max(1e-3))
        })
        .collect();
    assert!(bad.is_empty(), "non-finite pixels: {bad:?}");
    let centre = luminance(px[w / 2 + w * (h / 2)]);
    let corner = luminance(px[0]);
    eprintln!("nanovdb plume: centre Y {centre:.4e}, corner (sky) Y {corner:.4e}");
    // Albedo ½, τ ≈ 14 across and maxdepth 5 (explosion.pbrt's settings): little of the hot core's light gets
    // out; measured 3× the sky at the centre when the grid was divided by ∫ȳ = 106.86, pbrt-v4's level is 106.86× that.
    assert!(
        centre > 2.0 * corner && corner > 0.0,
        "the plume should glow against the sky: {centre} vs {corner}"
    );
}

#[test]
fn the_fire_light_and_paths_that_find_the_fire_agree() {
    // A floor lit only by a fire outside the camera's view, direct light only (maxdepth 2: pbrt-v4 counts a
    // medium's emission on the segments before the maxdepth-th bounce, and the floor's is the first). Without the fire light, paths
    // find the fire by BSDF sampling alone; with it, NEE and those paths share the work by MIS. Both must give
    // the same image on average (light counted once, nothing lost) — here with the fire grid larger than its
    // spherical boundary, so the light also samples points where the medium is absent.
    // Both on a diffuse floor and on a rough conductor one (its microfacet BRDF in NEE and in MIS).
    for (name, floor) in [
        (
            "diffuse",
            r#"Material "diffuse" "rgb reflectance" [0.5 0.5 0.5]"#,
        ),
        (
            "rough",
            r#"Material "conductor" "rgb reflectance" [0.8 0.8 0.8] "float roughness" 0.3"#,
        ),
    ] {
        let dir = tmp(&format!("firelight-{name}"));
        let scene = format!(
        "LookAt 3 -3 4  2 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 20\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24\nSampler \"independent\" \"integer pixelsamples\" 96\nIntegrator \"volpath\" \"integer maxdepth\" 2\nWorldBegin\nAttributeBegin\nTranslate 0 0 1.2\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1]\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 0.7\nAttributeEnd\n{}\nShape \"trianglemesh\" \"point3 P\" [-10 -10 0 10 -10 0 10 10 0 -10 10 0] \"integer indices\" [0 1 2 0 2 3]\n",
        inline_grid(6, 3e-7, 1700.0),
        floor
    );
        std::fs::write(dir.join("o.pbrt"), &scene).unwrap();
        let (_, _, without) = read_exr(&render(
            &dir.join("o.pbrt"),
            &["--fire-light", "off", "--spp", "384"],
        ));
        // The light's estimators (issue 29): the default (brick cells, a coarse line march), the voxel pdf with
        // the volume's own march, the escaping weighting, and the coarse march corrected half the time.
        for (how, extra) in [
            ("default", vec![]),
            (
                "voxel pdf, full march",
                vec![
                    "--fire-light-param",
                    "cell=1",
                    "--fire-light-param",
                    "linestep=1e-9",
                ],
            ),
            ("escaping", vec!["--fire-light", "escaping"]),
            (
                "corrected",
                vec!["--fire-light-param", "linecorrection=0.5"],
            ),
        ] {
            std::fs::write(dir.join("l.pbrt"), &scene).unwrap();
            let path = dir.join("l.pbrt");
            let mut args = vec!["--stats"];
            args.extend(&extra);
            let (_, _, with) = read_exr(&render(&path, &args));
            let (a, b) = (mean_y(&with), mean_y(&without));
            // Noise of the mean without the light: from the pixel-to-pixel spread of (without − with), which is
            // dominated by the light-less render's noise.
            let n = with.len() as f64;
            let d: Vec<f64> = with
                .iter()
                .zip(&without)
                .map(|(p, q)| luminance(*q) - luminance(*p))
                .collect();
            let md = d.iter().sum::<f64>() / n;
            let sd =
                (d.iter().map(|x| (x - md).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / n.sqrt();
            eprintln!(
            "fire light ({name}, {how}): mean Y {a:.6e} with, {b:.6e} without ({:+.3e}, σ {:.2e})",
            b / a - 1.0,
            sd / a
        );
            assert!(
                a > 0.0 && with.iter().all(|p| luminance(*p) > 0.0),
                "the floor is lit everywhere"
            );
            assert!(
                (b - a).abs() < 4.0 * sd + 1e-3 * a,
                "with {a}, without {b}, σ {sd}"
            );
            assert!(
                sd / a < 0.02,
                "the comparison should be sharp (σ {:.3})",
                sd / a
            );
        }
    }
}

#[test]
fn refraction_moves_the_wall_behind_the_fire_and_nothing_else() {
    // The refraction scene with the fire's emission off (only the bending differs), refraction on and off.
    let root = crate::common::root().join("scenes");
    let text = std::fs::read_to_string(root.join("refraction/scene.pbrt")).unwrap();
    let vdb = root.join("mantaflow/fire_f060.vdb");
    let dir = tmp("refraction");
    let mut images = Vec::new();
    for on in [true, false] {
        let scene = text
            .replace("../mantaflow/fire_f060.vdb", vdb.to_str().unwrap())
            .replace(
                "\"bool refraction\" true",
                &format!("\"bool refraction\" {on} \"float intensity\" 0"),
            );
        let path = dir.join(format!("wall_{on}.pbrt"));
        std::fs::write(&path, scene).unwrap();
        let out = render(&path, &["--resolution", "96x96", "--spp", "4"]);
        images.push(read_exr(&out));
    }
    let (w, h, on) = &images[0];
    let off = &images[1].2;
    // Mean |ΔY| / mean Y over a band of columns: the plume's (the middle fifth) and the margins' (outside the
    // medium's box, which spans about the middle 45 % of the view).
    let band = |x0: usize, x1: usize| {
        let (mut d, mut y) = (0.0, 0.0);
        for j in 0..*h {
            for i in x0..x1 {
                let (a, b) = (luminance(on[i + w * j]), luminance(off[i + w * j]));
                d += (a - b).abs();
                y += b;
            }
        }
        d / y
    };
    let plume = band(2 * w / 5, 3 * w / 5);
    let margins = band(0, w / 5).max(band(4 * w / 5, *w));
    eprintln!("refraction on vs off: mean |ΔY|/Y {plume:.4} behind the plume, {margins:.4} in the margins");
    assert!(plume > 0.02, "{plume}");
    assert!(margins < 0.01 * plume, "{margins} vs {plume}");
}

#[test]
fn every_scene_renders_at_a_tiny_resolution() {
    // Each scene of the gallery (every .pbrt of every scene folder) parses, loads its datasets and renders
    // finite, with its fire visible.
    let root = crate::common::root().join("scenes");
    let dir = tmp("gallery");
    let pbrt_files = |d: &std::path::Path| -> Vec<PathBuf> {
        let mut v: Vec<PathBuf> = std::fs::read_dir(d)
            .map(|r| r.filter_map(|e| e.ok()).map(|e| e.path()).collect())
            .unwrap_or_default();
        // (Not hidden files: tools/mutants.py writes its mutants beside the scenes for a moment.)
        v.retain(|p| {
            p.extension().is_some_and(|x| x == "pbrt")
                && !p
                    .file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        });
        v.sort();
        v
    };
    let mut names: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| !pbrt_files(&e.path()).is_empty())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "adaptation",
            "art",
            "bluecore",
            "campfire",
            "diffusion",
            "fuels",
            "looks",
            "mantaflow",
            "refraction",
            "spectroscopy"
        ]
    );
    let scenes = names.iter().flat_map(|n| pbrt_files(&root.join(n)));
    for scene in scenes {
        let name = format!(
            "{}/{}",
            scene
                .parent()
                .unwrap()
                .file_name()
                .unwrap()
                .to_string_lossy(),
            scene.file_stem().unwrap().to_string_lossy()
        );
        let out = dir.join(format!("{}.exr", name.replace('/', "-")));
        let o = Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(&scene)
            .arg("-o")
            .arg(&out)
            .args(["--resolution", "40x30", "--spp", "1", "--quiet"])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let (w, h, px) = read_exr(&out);
        assert_eq!((w, h), (40, 30));
        assert!(
            px.iter().all(|p| p.iter().all(|c| c.is_finite())),
            "{name}: NaN"
        );
        let brightest = px.iter().map(|p| luminance(*p)).fold(0.0, f64::max);
        eprintln!("{name}: brightest pixel {brightest:.3e} cd/m²");
        assert!(brightest > 1.0, "{name}: brightest {brightest}");
    }
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

#[test]
fn instances_share_their_objects_geometry() {
    // An object of 2 000 triangles instanced 1 000 times: copied, 2 million primitives (hundreds of MB; a 253 KB
    // scene of instances grew to 1.7 GB). Shared, it is 2 000 primitives and 1 000 instances, well inside 0.1 GB.
    let dir = tmp("instances");
    let mut p = Vec::new();
    let mut idx = Vec::new();
    for i in 0..2000 {
        let x = i as f64 * 0.001;
        p.extend([format!("{x} 0 0"), format!("{x} 1 0"), format!("{x} 0 1")]);
        idx.push(format!("{} {} {}", 3 * i, 3 * i + 1, 3 * i + 2));
    }
    let mut scene = format!(
        "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nObjectBegin \"a\"\nShape \"trianglemesh\" \"point3 P\" [{}] \"integer indices\" [{}]\nObjectEnd\n",
        p.join(" "),
        idx.join(" ")
    );
    for i in 0..1000 {
        scene +=
            &format!("AttributeBegin\nTranslate {i} 0 0\nObjectInstance \"a\"\nAttributeEnd\n");
    }
    std::fs::write(dir.join("i.pbrt"), &scene).unwrap();
    render(&dir.join("i.pbrt"), &["--max-memory", "0.1"]);
    // The budget still counts each object's primitives once: 0.001 GB does not hold the 2 000 triangles.
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(dir.join("i.pbrt"))
        .args(["--max-memory", "0.001", "-q"])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("trianglemesh: ")
            && e.contains("primitives needs")
            && e.contains("memory budget"),
        "{e}"
    );
}

#[test]
fn an_instance_renders_as_its_object_written_out_in_place() {
    // The same lit scene twice: a sphere, a disk and a two-triangle quad, once written in world space under
    // rotated, scaled and translated transforms, once as an object instanced under those transforms. The
    // images agree to f32 rounding (the instance intersects in object space), materials and media included.
    let dir = tmp("instance-equal");
    let head = "LookAt 0 -6 2  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 48 \"integer yresolution\" 32\nSampler \"independent\" \"integer pixelsamples\" 4\nWorldBegin\nLightSource \"distant\" \"point3 from\" [1 -2 3] \"point3 to\" [0 0 0]\nLightSource \"infinite\" \"rgb L\" [0.2 0.2 0.25]\n";
    let body = "Material \"diffuse\" \"rgb reflectance\" [0.7 0.3 0.2]\nShape \"sphere\" \"float radius\" 0.6\nMaterial \"conductor\"\nShape \"disk\" \"float radius\" 1.2 \"float height\" -0.5\nMaterial \"diffuse\"\nShape \"trianglemesh\" \"point3 P\" [-1 1 -0.5  1 1 -0.5  1 1 1  -1 1 1] \"integer indices\" [0 1 2 0 2 3]\n";
    let places = [
        "Translate -1.5 0 0 Rotate 30 0 0 1 Scale 0.8 0.8 0.8",
        "Translate 1.5 0.5 0.2 Rotate -45 1 1 0",
    ];
    let mut written = head.to_string();
    let mut instanced = format!("{head}ObjectBegin \"o\"\n{body}ObjectEnd\n");
    for t in places {
        written += &format!("AttributeBegin\n{t}\n{body}AttributeEnd\n");
        instanced += &format!("AttributeBegin\n{t}\nObjectInstance \"o\"\nAttributeEnd\n");
    }
    std::fs::write(dir.join("written.pbrt"), written).unwrap();
    std::fs::write(dir.join("instanced.pbrt"), instanced).unwrap();
    let (_, _, a) = read_exr(&render(&dir.join("written.pbrt"), &["--seed", "3"]));
    let (_, _, b) = read_exr(&render(&dir.join("instanced.pbrt"), &["--seed", "3"]));
    let lit = mean_y(&a);
    assert!(lit > 0.01, "the scene is dark: mean Y {lit}");
    // Per pixel: equal unless an edge moved by rounding (a few pixels at most).
    let differ = a
        .iter()
        .zip(&b)
        .filter(|(p, q)| (luminance(**p) - luminance(**q)).abs() > 1e-3 * (1.0 + luminance(**p)))
        .count();
    assert!(
        differ <= a.len() / 100,
        "{differ} of {} pixels differ",
        a.len()
    );
    assert!(
        (mean_y(&b) / lit - 1.0).abs() < 2e-3,
        "{} vs {lit}",
        mean_y(&b)
    );
}

#[test]
fn the_fire_light_is_built_only_where_a_path_can_sample_it() {
    // The plume behind its interface sphere, maxdepth 1: alone, or above a mirror floor, no path vertex samples
    // a light (the mirror has no non-specular lobe), so the fire light is left out — saying why — and the image
    // is that of `--fire-light off` to the bit; above a diffuse floor at maxdepth 1 or 0 too (pbrt-v4 counts a
    // medium's emission only before the maxdepth-th bounce, where a light sample from the floor would land); at
    // maxdepth 2 the floor samples it.
    let dir = tmp("leave-out");
    let nvdb = crate::common::root().join("tests/data/valid/nvdb/plume48.nvdb");
    let scene = |floor: &str, depth: u32| {
        format!(
            "LookAt 0 -3 0.4  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nSampler \"independent\" \"integer pixelsamples\" 2\nIntegrator \"volpath\" \"integer maxdepth\" {depth}\nWorldBegin\nMakeNamedMedium \"kaboom\" \"string type\" \"nanovdb\" \"string filename\" \"{}\" \"spectrum sigma_a\" [200 10 900 10] \"spectrum sigma_s\" [200 0 900 0] \"float Lescale\" 5 \"float temperaturecutoff\" 1 \"float temperaturescale\" 1.5\nAttributeBegin\nMediumInterface \"kaboom\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\n{floor}",
            nvdb.display()
        )
    };
    let quad = "Shape \"trianglemesh\" \"point3 P\" [-5 -5 -1.1  5 -5 -1.1  5 5 -1.1  -5 5 -1.1] \"integer indices\" [0 1 2 0 2 3]\n";
    let mirror = format!("Material \"conductor\" \"float roughness\" 0\n{quad}");
    let diffuse = format!("Material \"diffuse\"\n{quad}");
    let stats = |name: &str, text: String, extra: &[&str]| {
        let f = dir.join(format!("{name}.pbrt"));
        std::fs::write(&f, text).unwrap();
        let out = dir.join(format!("{name}{}.exr", extra.len()));
        let o = Command::new(crate::common::exe("firemedium"))
            .arg("render")
            .arg(&f)
            .arg("-o")
            .arg(&out)
            .args(["--quiet", "--stats", "--seed", "4"])
            .args(extra)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        (
            String::from_utf8_lossy(&o.stdout).into_owned(),
            read_exr(&out),
        )
    };
    for (name, text) in [
        ("alone", scene("", 1)),
        ("mirror", scene(&mirror, 1)),
        ("depth0", scene(&diffuse, 0)),
        ("depth1", scene(&diffuse, 1)),
    ] {
        let (s, img) = stats(name, text.clone(), &[]);
        assert!(
            s.contains("0 lights")
                && s.contains("fire light: left out (")
                && !s.contains("emitting voxels"),
            "{name}: {s}"
        );
        let (_, off) = stats(name, text, &["--fire-light", "off"]);
        assert!(img == off, "{name}: the image must not change");
    }
    let (s, _) = stats("diffuse", scene(&diffuse, 2), &[]);
    assert!(
        s.contains("1 lights") && s.contains("emitting voxels") && !s.contains("left out"),
        "{s}"
    );
}

#[test]
fn frames_render_a_sequence_one_seed_per_frame() {
    // Three frames of the generator's torch; `####` in the dataset and output names takes each frame.
    let dir = tmp("frames");
    let run = |args: &[&str]| firemedium_in(&dir, args);
    let o = run(&[
        "gen",
        "torch",
        "--resolution",
        "16",
        "--frames",
        "30-32",
        "-o",
        "torch.####.vdb",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(
        dir.join("seq.pbrt"),
        "LookAt 0 -3 0.6  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 24 \"string filename\" \"seq.####.exr\"\nSampler \"independent\" \"integer pixelsamples\" 2\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"torch.####.vdb\" \"string fuel\" \"propane\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n",
    )
    .unwrap();
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
    let o = run(&[
        "gen",
        "torch",
        "--resolution",
        "12",
        "--frames",
        "31-32",
        "-o",
        "t.####.vdb",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::write(
        dir.join("s.pbrt"),
        "LookAt 0 -3 0.6  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 40 \"integer yresolution\" 40\nSampler \"independent\" \"integer pixelsamples\" 1\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"t.####.vdb\" \"string fuel\" \"propane\"\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1.5\nAttributeEnd\n",
    )
    .unwrap();
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

/// A thin Gaussian blob of fire (σ = 0.05 m, 1500 K) centred at (0.32, 0.24, 0.32) in a 32³ grid of 2 cm voxels,
/// moving along +y at 4.8 m/s (0.2 m per frame at 24 fps): `vel` written as an OpenVDB vector grid.
fn moving_blob(dir: &Path) {
    let n = 32usize;
    let (mut d, mut t) = (vec![0f32; n * n * n], vec![0f32; n * n * n]);
    for i in 0..n * n * n {
        let c = [i % n, (i / n) % n, i / (n * n)].map(|k| (k as f64 + 0.5) * 0.02);
        let r2 = (c[0] - 0.32).powi(2) + (c[1] - 0.24).powi(2) + (c[2] - 0.32).powi(2);
        let v = 1e-9 * (-r2 / (2.0 * 0.05f64.powi(2))).exp();
        if v > 1e-15 {
            d[i] = v as f32;
            t[i] = 1500.0;
        }
    }
    let (zero, vy) = (vec![0f32; n * n * n], vec![4.8f32; n * n * n]);
    let bytes = firemedium_dataset::vdb::write_with_vectors(
        &[("density", [n; 3], &d), ("temperature", [n; 3], &t)],
        &[("vel", [n; 3], [&zero, &vy, &zero])],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.02),
    );
    std::fs::write(dir.join("blob.vdb"), bytes).unwrap();
}

/// An orthographic view along +x of the blob's box; `medium` is the MakeNamedMedium's extra text, `shift` the
/// fire's translation along y.
fn blob_scene(medium: &str, shift: f64) -> String {
    format!(
        "LookAt -1 0.32 0.32  0 0.32 0.32  0 0 1\nCamera \"orthographic\" \"float screenwindow\" [-0.32 0.32 -0.32 0.32] \"float shutteropen\" 0 \"float shutterclose\" 1\nFilm \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 32 \"string filename\" \"x.exr\"\nSampler \"zsobol\" \"integer pixelsamples\" 64\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nAttributeBegin\nTranslate 0 {shift} 0\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"blob.vdb\" \"string fuel\" \"propane\" \"float stepsize\" 0.25 {medium}\nAttributeEnd\nAttributeBegin\nMediumInterface \"fire\" \"\"\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" [ 0 -0.2 0  0.64 -0.2 0  0 0.84 0  0.64 0.84 0  0 -0.2 0.64  0.64 -0.2 0.64  0 0.84 0.64  0.64 0.84 0.64 ] \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]\nAttributeEnd\n"
    )
}

#[test]
fn velocity_motion_blur_averages_the_moving_fire_over_the_shutter() {
    // A blob moving at constant velocity, rendered with the camera's shutter open over one frame, against the
    // average of 16 still renders of the blob moved to the middle of each sixteenth of the shutter; with the
    // medium's shutter closed the image is the still one's, bit for bit.
    let dir = tmp("motionblur");
    moving_blob(&dir);
    let render_scene = |name: &str, text: String| {
        let scene = dir.join(format!("{name}.pbrt"));
        std::fs::write(&scene, text).unwrap();
        read_exr(&render(&scene, &[]))
    };
    let (w, h, blur) = render_scene("blur", blob_scene("\"string velocitygrid\" \"vel\"", 0.0));
    let k = 16;
    let mut avg = vec![[0f32; 3]; w * h];
    for i in 0..k {
        let shift = 0.2 * (i as f64 + 0.5) / k as f64;
        let (_, _, px) = render_scene(&format!("still{i}"), blob_scene("", shift));
        for (a, p) in avg.iter_mut().zip(px) {
            for c in 0..3 {
                a[c] += p[c] / k as f32;
            }
        }
    }
    // Profiles across the motion (sums of columns and of rows, whichever way the camera maps y), within 3 %
    // of the peak: the time samples' noise and the 16-point average's.
    let profile = |px: &[[f32; 3]], by_col: bool| -> Vec<f64> {
        let mut v = vec![0.0; if by_col { w } else { h }];
        for y in 0..h {
            for x in 0..w {
                v[if by_col { x } else { y }] += luminance(px[x + w * y]);
            }
        }
        v
    };
    for by_col in [true, false] {
        let (a, b) = (profile(&blur, by_col), profile(&avg, by_col));
        let peak = b.iter().cloned().fold(0.0, f64::max);
        assert!(peak > 0.0);
        let worst = a
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max)
            / peak;
        eprintln!(
            "motion blur profile (columns {by_col}): largest difference {worst:.4} of the peak"
        );
        assert!(worst < 0.03, "profile {by_col}: {worst}\n{a:?}\n{b:?}");
    }
    // The blur is there: the still blob at its start differs from the average by far more.
    let (_, _, start) = render_scene("start", blob_scene("", 0.0));
    let d = |p: &[[f32; 3]]| {
        p.iter()
            .zip(&avg)
            .map(|(a, b)| (luminance(*a) - luminance(*b)).abs())
            .sum::<f64>()
    };
    assert!(d(&start) > 5.0 * d(&blur), "{} vs {}", d(&start), d(&blur));
    // The medium's own shutter closed: the velocity is not read and the camera draws no time.
    let (_, _, closed) = render_scene(
        "closed",
        blob_scene(
            "\"string velocitygrid\" \"vel\" \"float shutteropen\" 0 \"float shutterclose\" 0",
            0.0,
        ),
    );
    assert!(closed == start, "a closed shutter changes the image");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_ember_lights_the_floor_as_a_glowing_sphere_does() {
    // One ember (radius r, 1500 K) a height h above a grey floor, in an empty fire: the floor point below it
    // receives E = π L (r/h)², so it looks ρ L (r/h)² bright — with the fire light sampling the ember (NEE, MIS)
    // and without it (paths find the ember by BSDF sampling alone). The shutter is closed: over the camera's
    // default frame (0 to 1) this ember would cool by 1.1 K, 0.6 % of its luminance, as the renderer does.
    // (Measured at 16384 spp: +0.07 % with the fire light, −0.13 % without; σ ≈ 0.1 % and 0.7 %.)
    let dir = tmp("ember-floor");
    let (r, h, rho) = (0.1, 1.0, 0.5);
    std::fs::write(
        dir.join("e.csv"),
        format!("x,y,z,radius,temperature\n0,0,0,{r},1500\n"),
    )
    .unwrap();
    let scene = format!(
        "LookAt 3 0 1  0 0 0  0 0 1\nCamera \"perspective\" \"float fov\" 0.2\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 64\nIntegrator \"volpath\" \"integer maxdepth\" 2\nWorldBegin\nAttributeBegin\nTranslate 0 0 {h}\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1] \"string embers\" \"e.csv\" \"float shutterclose\" 0\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\nMaterial \"diffuse\" \"spectrum reflectance\" [300 {rho} 900 {rho}]\nShape \"trianglemesh\" \"point3 P\" [-10 -10 0 10 -10 0 10 10 0 -10 10 0] \"integer indices\" [0 1 2 0 2 3]\n",
        inline_grid(2, 0.0, 0.0)
    );
    std::fs::write(dir.join("s.pbrt"), &scene).unwrap();
    // The ember's radiance per channel from the plugin's rlib (a ray through its centre), and the film's weights.
    use firemedium_plugin::params::Param;
    let f = dir.join("e.csv").to_string_lossy().into_owned();
    let v = firemedium_plugin::volume::FireVolume::new(&[
        Param::floats("density", &[0.0; 8]),
        Param::floats("temperature", &[0.0; 8]),
        Param::int("nx", 2),
        Param::int("ny", 2),
        Param::int("nz", 2),
        Param::point3("p0", [-1.0; 3]),
        Param::point3("p1", [1.0; 3]),
        Param::string("embers", &f),
    ])
    .unwrap();
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    let ray = firemedium_plugin::volume::Ray {
        o: glam::DVec3::new(-0.9, 0.0, 0.0),
        d: glam::DVec3::X,
        t0: 0.0,
        t1: 2.0,
        seed: 1,
        first: None,
    };
    v.integrate(&ray, &mut l, &mut t);
    let xyz = v.channel_xyz();
    let le: f64 = (0..c).map(|k| xyz[k].y * l[k]).sum();
    let want = rho * le * (r / h) * (r / h);
    for (extra, tol) in [
        (vec!["--spp", "1024"], 0.012),
        (vec!["--fire-light", "off", "--spp", "4096"], 0.04),
    ] {
        let (_, _, px) = read_exr(&render(&dir.join("s.pbrt"), &extra));
        let got = mean_y(&px);
        eprintln!(
            "ember over a floor {extra:?}: Y {got:.5e} vs ρ L (r/h)² {want:.5e} ({:+.2e})",
            got / want - 1.0
        );
        assert!((got / want - 1.0).abs() < tol, "{got} vs {want}");
    }
}

#[test]
fn the_diffusion_scene_agrees_with_its_path_traced_twin() {
    // scenes/diffusion: a glowing cube of smoke (albedo 0.9, optical thickness ~3) by the diffusion equation and
    // path traced. The cube's face (the central pixels) and the floor it lights (the bottom rows) agree within the
    // diffusion approximation's error at this depth: measured against 2048 spp, −8.9 % and −7.9 %
    // (docs/results/log.md, "Multiple scattering by diffusion").
    let root = crate::common::root().join("scenes/diffusion");
    let mean = |name: &str, extra: &[&str]| {
        let mut args = vec!["--resolution", "64x48"];
        args.extend(extra);
        let (w, h, px) = read_exr(&render(&root.join(name), &args));
        let region = |x0: usize, x1: usize, y0: usize, y1: usize| {
            let mut s = 0.0;
            for y in y0..y1 {
                for x in x0..x1 {
                    s += luminance(px[x + w * y]);
                }
            }
            s / ((x1 - x0) * (y1 - y0)) as f64
        };
        (region(26, 38, 16, 28), region(4, 60, h - 6, h))
    };
    let (face_d, floor_d) = mean("scene.pbrt", &["--spp", "16"]);
    let (face_p, floor_p) = mean("pathtraced.pbrt", &["--spp", "256"]);
    eprintln!(
        "diffusion scene: face {face_d:.4e} vs path traced {face_p:.4e} ({:+.3}); floor {floor_d:.4e} vs {floor_p:.4e} ({:+.3})",
        face_d / face_p - 1.0,
        floor_d / floor_p - 1.0
    );
    assert!(
        (face_d / face_p - 1.0).abs() < 0.1,
        "face {face_d} vs {face_p}"
    );
    assert!(
        (floor_d / floor_p - 1.0).abs() < 0.15,
        "floor {floor_d} vs {floor_p}"
    );
}

#[test]
fn an_installed_firemedium_finds_its_plugin_from_any_directory() {
    // tools/install.sh's layout — PREFIX/bin/firemedium, PREFIX/lib/firemedium/<plugin> — copied from the build,
    // run from an unrelated directory with no plugin variables: it finds its plugin relative to itself, renders
    // the default scene, and writes where it is told.
    let dir = tmp("install");
    let exe = crate::common::exe("firemedium");
    let lib = firemedium_loader::library_file_name();
    // (Beside the binary after `cargo build`, in `deps` after `cargo test` alone.)
    let plugin = [
        exe.parent().unwrap().join(&lib),
        exe.parent().unwrap().join("deps").join(&lib),
    ]
    .into_iter()
    .find(|p| p.is_file())
    .expect("the plugin is built");
    std::fs::create_dir_all(dir.join("prefix/bin")).unwrap();
    std::fs::create_dir_all(dir.join("prefix/lib/firemedium")).unwrap();
    std::fs::create_dir_all(dir.join("elsewhere")).unwrap();
    let installed = dir.join("prefix/bin").join(exe.file_name().unwrap());
    std::fs::copy(&exe, &installed).unwrap();
    std::fs::copy(&plugin, dir.join("prefix/lib/firemedium").join(&lib)).unwrap();
    let scene = crate::common::root().join("scenes/campfire/scene.pbrt");
    let o = Command::new(&installed)
        .current_dir(dir.join("elsewhere"))
        .env_remove("FIREMEDIUM_PLUGIN")
        .env_remove("FIREMEDIUM_PLUGIN_PATH")
        .args([
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "32x18",
            "--spp",
            "1",
        ])
        .args(["-o", "here.exr", "--quiet"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("elsewhere/here.exr").is_file() && dir.join("elsewhere/here.png").is_file());
    // Every gallery scene, from there, by its absolute path.
    let gallery = crate::common::root().join("scenes");
    let mut scenes: Vec<PathBuf> = std::fs::read_dir(&gallery)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .flat_map(|d| {
            std::fs::read_dir(d)
                .unwrap()
                .filter_map(|e| e.ok().map(|e| e.path()))
        })
        .filter(|p| p.extension().is_some_and(|x| x == "pbrt"))
        .collect();
    scenes.sort();
    assert!(scenes.len() >= 15, "{scenes:?}");
    for s in &scenes {
        let o = Command::new(&installed)
            .current_dir(dir.join("elsewhere"))
            .env_remove("FIREMEDIUM_PLUGIN")
            .env_remove("FIREMEDIUM_PLUGIN_PATH")
            .arg("render")
            .arg(s.canonicalize().unwrap())
            .args([
                "--resolution",
                "8x6",
                "--spp",
                "1",
                "-o",
                "g.exr",
                "--quiet",
            ])
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{}: {}",
            s.display(),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    // Without the plugin beside it, the message says where it looked.
    std::fs::remove_file(dir.join("prefix/lib/firemedium").join(&lib)).unwrap();
    let o = Command::new(&installed)
        .current_dir(dir.join("elsewhere"))
        .env_remove("FIREMEDIUM_PLUGIN")
        .env_remove("FIREMEDIUM_PLUGIN_PATH")
        .args([
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "32x18",
            "--spp",
            "1",
        ])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success()
            && e.contains("no firemedium plugin found")
            && e.contains("lib/firemedium"),
        "{e}"
    );
}

#[test]
fn scene_readmes_quote_what_render_stats_prints() {
    // A scene README's numbers from `render --stats` are quoted verbatim in backticks — a span holding
    // "plugin built", "fire light:" or ending in a number of lm or W — with "…" for what is left out; each piece
    // must appear in the stats of one of the folder's scenes (rendered at 8×6, 1 spp: the plugin's build and the
    // fire light do not depend on the film). A number that drifts fails here, not in a reader's hands.
    let root = crate::common::root().join("scenes");
    let dir = tmp("readme-stats");
    let mut checked = 0;
    let mut folders: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.join("README.md").is_file())
        .collect();
    folders.sort();
    for folder in folders {
        let readme = std::fs::read_to_string(folder.join("README.md")).unwrap();
        let quotes: Vec<&str> = readme
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|q| {
                q.contains("plugin built")
                    || q.contains("fire light:")
                    || ((q.ends_with(" lm") || q.ends_with(" W"))
                        && q.chars().next().is_some_and(|c| c.is_ascii_digit()))
            })
            .collect();
        if quotes.is_empty() {
            continue;
        }
        let mut stats = String::new();
        let mut scenes: Vec<PathBuf> = std::fs::read_dir(&folder)
            .unwrap()
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|x| x == "pbrt"))
            .collect();
        scenes.sort();
        for scene in scenes {
            let out = dir.join("s.exr");
            let o = Command::new(crate::common::exe("firemedium"))
                .arg("render")
                .arg(&scene)
                .args([
                    "--resolution",
                    "8x6",
                    "--spp",
                    "1",
                    "--stats",
                    "--quiet",
                    "-o",
                ])
                .arg(&out)
                .output()
                .unwrap();
            assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
            stats += &String::from_utf8_lossy(&o.stdout);
            stats += &String::from_utf8_lossy(&o.stderr);
        }
        for q in quotes {
            for piece in q.split('…').map(str::trim).filter(|p| !p.is_empty()) {
                assert!(
                    stats.contains(piece),
                    "{}: `{q}` — '{piece}' is not in what render --stats prints:\n{stats}",
                    folder.join("README.md").display()
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 15, "{checked} quotes checked");
}

/// Copies the folder `from` into `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap().filter_map(|e| e.ok()) {
        let (src, dst) = (e.path(), to.join(e.file_name()));
        if src.is_dir() {
            copy_dir(&src, &dst);
        } else {
            std::fs::copy(&src, &dst).unwrap();
        }
    }
}

#[test]
fn the_readmes_quick_commands_run_as_written() {
    // Every `firemedium …` (or `target/release/firemedium …`) line of the README's sh blocks whose
    // command is quick — physics, info, tonemap, the quick gens and benches, the adaptation scene's render —
    // runs as written (this build's binary standing for `firemedium`) in a copy of the repository's scenes and
    // test data, in the README's order, and succeeds.
    let root = crate::common::root();
    let dir = tmp("readme");
    copy_dir(&root.join("scenes"), &dir.join("scenes"));
    copy_dir(&root.join("tests/data"), &dir.join("tests/data"));
    // (The README's first steps, then the rendering guide its commands moved to.)
    let readme = ["README.md", "docs/guide/rendering.md"]
        .iter()
        .map(|f| std::fs::read_to_string(root.join(f)).unwrap_or_else(|e| panic!("{f}: {e}")))
        .collect::<Vec<_>>()
        .join("\n");
    let mut in_sh = false;
    let mut commands: Vec<Vec<String>> = Vec::new();
    for line in readme.lines() {
        if line.starts_with("```") {
            in_sh = line == "```sh" && !in_sh;
            continue;
        }
        if !in_sh {
            continue;
        }
        // (A comment starts at " # "; `pool.####.vdb` is not one.)
        let cmd = line.split(" # ").next().unwrap_or("").trim();
        let rest = cmd
            .strip_prefix("target/release/firemedium ")
            .or_else(|| cmd.strip_prefix("firemedium "));
        let Some(rest) = rest else { continue };
        let args: Vec<String> = rest.split_whitespace().map(String::from).collect();
        let quick = match args.first().map(String::as_str) {
            Some("physics" | "info" | "tonemap") => true,
            Some("bench") => matches!(
                args.get(1).map(String::as_str),
                Some("stability" | "components")
            ),
            Some("gen") => args.iter().any(|a| a == "torch" || a == "--embers"),
            Some("render") => args
                .get(1)
                .is_some_and(|s| s == "scenes/adaptation/scene.pbrt"),
            _ => false,
        };
        if quick {
            commands.push(args);
        }
    }
    let names: Vec<String> = commands
        .iter()
        .map(|a| a[..2.min(a.len())].join(" "))
        .collect();
    for want in [
        "physics --temperature",
        "info tests/data/valid/vdb/mantaflow_fire_f060.vdb",
        "tonemap scenes/adaptation/adaptation.exr",
        "bench stability",
        "bench components",
        "gen torch",
        "gen campfire",
        "render scenes/adaptation/scene.pbrt",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "the README and the rendering guide no longer show `firemedium {want} …`: {names:?}"
        );
    }
    for args in &commands {
        let o = firemedium_in(&dir, &args.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(
            o.status.success(),
            "firemedium {}: {}",
            args.join(" "),
            String::from_utf8_lossy(&o.stderr)
        );
    }
    for f in [
        "night.png",
        "day.png",
        "torch.vdb",
        "campfire.vdb",
        "campfire.embers.ply",
    ] {
        assert!(dir.join(f).is_file(), "{f} was not written");
    }
}

#[test]
fn the_fire_lights_parameters_are_checked_and_its_samples_counted() {
    // `--fire-light-param NAME=VALUE` reaches the plugin typed by its table; a wrong name, type or value is named;
    // `--stats` counts the light's samples, and the EXR records how the fire lit the scene.
    let dir = tmp("light-params");
    let scene = format!(
        "LookAt 3 -3 4  0 0 0.5  0 0 1\nCamera \"perspective\" \"float fov\" 40\nFilm \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 12\nSampler \"independent\" \"integer pixelsamples\" 4\nIntegrator \"volpath\" \"integer maxdepth\" 2\nWorldBegin\nAttributeBegin\nTranslate 0 0 1.2\nMakeNamedMedium \"f\" \"string type\" \"fire\" {} \"point3 p0\" [-1 -1 -1] \"point3 p1\" [1 1 1]\nMediumInterface \"f\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 0.7\nAttributeEnd\nMaterial \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\nShape \"trianglemesh\" \"point3 P\" [-10 -10 0 10 -10 0 10 10 0 -10 10 0] \"integer indices\" [0 1 2 0 2 3]\n",
        inline_grid(16, 3e-7, 1700.0)
    );
    std::fs::write(dir.join("s.pbrt"), &scene).unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec!["render", "s.pbrt", "-o", "s.exr"];
        args.extend(extra);
        let o = firemedium_in(&dir, &args);
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned(),
            String::from_utf8_lossy(&o.stderr).into_owned(),
        )
    };
    for (extra, want) in [
        (
            vec!["--fire-light-param", "nosuch=1"],
            vec!["no parameter \"nosuch\"", "cell", "linestep"],
        ),
        (
            vec!["--fire-light-param", "cell=two"],
            vec!["cell=two", "not an integer"],
        ),
        (
            vec!["--fire-light-param", "cell=3"],
            vec!["cell", "1, 2, 4 or 8"],
        ),
        (
            vec!["--fire-light-param", "linecorrection=2"],
            vec!["linecorrection", "2"],
        ),
        (
            vec!["--fire-light-param", "cell"],
            vec!["expected NAME=VALUE"],
        ),
    ] {
        let (ok, _, err) = run(&extra);
        assert!(!ok, "{extra:?} should fail");
        for w in want {
            assert!(err.contains(w), "{extra:?}: {err}");
        }
    }
    let (ok, out, err) = run(&["--stats", "--fire-light-param", "cell=2"]);
    assert!(ok, "{err}");
    let line = out
        .lines()
        .find(|l| l.contains("samples,") && l.contains("per camera ray"))
        .unwrap_or_else(|| panic!("no light sample count in {out}"));
    let n: u64 = line
        .split_whitespace()
        .nth(2)
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("{line}"));
    // 16 × 12 pixels × 4 samples, each path sampling the light at its diffuse vertices (up to 2).
    assert!(n > 100 && n <= 2 * 16 * 12 * 4, "{line}");
    let (_, meta) = firemedium::imageio::read_meta(&dir.join("s.exr")).unwrap();
    let light = meta
        .iter()
        .find(|m| m.0 == "fire_light")
        .map(|m| m.1.clone());
    assert_eq!(light.as_deref(), Some("auto cell=2"));
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
fn a_texture_naming_another_twice_at_every_level_is_built_once_per_node() {
    // 40 checkerboards each using the previous one twice (3.5 KB of scene): every level copied its two
    // textures, 2⁴⁰ nodes (4.9 GB at 20 levels, an abort at 40). Shared now: the render runs in little memory and
    // the checker of two equal textures is that texture (albedo 0.5 under a white sky: a grey of 0.5).
    let dir = tmp("texture-dag");
    let mut scene = String::from("LookAt 0 0 5  0 0 0  0 1 0\nCamera \"orthographic\" \"float screenwindow\" [-1 1 -1 1]\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nSampler \"independent\" \"integer pixelsamples\" 64\nIntegrator \"volpath\" \"integer maxdepth\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\nTexture \"t0\" \"spectrum\" \"constant\" \"rgb value\" [0.5 0.5 0.5]\n");
    for i in 1..=40 {
        scene += &format!(
            "Texture \"t{i}\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"t{}\" \"texture tex2\" \"t{}\" \"float uscale\" 8\n",
            i - 1,
            i - 1
        );
    }
    scene += "Material \"diffuse\" \"texture reflectance\" \"t40\"\nShape \"trianglemesh\" \"point3 P\" [-5 -5 0 5 -5 0 5 5 0 -5 5 0] \"integer indices\" [0 1 2 0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\n";
    std::fs::write(dir.join("d.pbrt"), scene).unwrap();
    let o = Command::new(crate::common::exe("firemedium"))
        .arg("render")
        .arg(dir.join("d.pbrt"))
        .args(["--max-memory", "1", "--stats", "--seed", "1", "-o"])
        .arg(dir.join("d.exr"))
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let peak: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("peak memory: "))
        .and_then(|l| l.split_whitespace().next())
        .and_then(|w| w.parse().ok())
        .unwrap_or_else(|| panic!("no peak memory in {out}"));
    assert!(peak < 200.0, "peak memory {peak} MB");
    let (_, _, px) = read_exr(&dir.join("d.exr"));
    let y = mean_y(&px);
    assert!((y - 0.5).abs() < 0.03, "mean Y {y}");
}

#[test]
fn degenerate_geometry_builds_in_n_log_n() {
    // 32 000 coincident triangles took 26.8 s in "load and build", 100 000 instances of one sphere 262 s and
    // 32 000 nested triangles, each wider than the last, 26.4 s: the BVH builder's nearest-neighbour merging
    // went quadratic (at the 64 000 here, about 100 s each). Primitives whose boxes are equal bit for bit are one
    // BVH entry (0.08 s, 0.07 s); a chain of nested boxes is built by median splits (0.13 s); the nearest
    // primitive is still the one hit.
    let dir = tmp("shared-boxes");
    let head = "Camera \"perspective\" \"float fov\" 30\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 1\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [1 1 1]\n";
    let n = 64_000;
    let p = "-1 -1 0 1 -1 0 0 1 0 ".repeat(n);
    let idx: Vec<String> = (0..3 * n).map(|i| i.to_string()).collect();
    std::fs::write(
        dir.join("tris.pbrt"),
        format!(
            "LookAt 0 0 -5  0 0 0  0 1 0\n{head}Material \"diffuse\" \"rgb reflectance\" [0 0 0]\nShape \"trianglemesh\" \"point3 P\" [{p}] \"integer indices\" [{}]\n",
            idx.join(" ")
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("instances.pbrt"),
        format!(
            "LookAt 0 0 -5  0 0 0  0 1 0\n{head}ObjectBegin \"s\"\nMaterial \"diffuse\" \"rgb reflectance\" [0 0 0]\nShape \"sphere\" \"float radius\" 1\nObjectEnd\n{}",
            "ObjectInstance \"s\"\n".repeat(100_000)
        ),
    )
    .unwrap();
    let p: String = (0..n)
        .map(|i| {
            let w = 1.0 + i as f64 * 5e-4;
            format!("-1 -1 0 {} -1 0 -1 {} 0 ", w - 1.0, w - 1.0)
        })
        .collect();
    std::fs::write(
        dir.join("nested.pbrt"),
        format!(
            "LookAt 0 0 -5  0 0 0  0 1 0\n{head}Material \"diffuse\" \"rgb reflectance\" [0 0 0]\nShape \"trianglemesh\" \"point3 P\" [{p}] \"integer indices\" [{}]\n",
            idx.join(" ")
        ),
    )
    .unwrap();
    for name in ["tris", "instances", "nested"] {
        let o = guard::finishes(
            Command::new(crate::common::exe("firemedium"))
                .arg("render")
                .arg(dir.join(format!("{name}.pbrt")))
                .arg("-o")
                .arg(dir.join(format!("{name}.exr")))
                .args(["--stats", "--threads", "2"]),
            60,
        );
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{name}: {e}");
        // A black shape against a white sky: the centre pixel is the shape, a corner the sky.
        let (w, h, px) = read_exr(&dir.join(format!("{name}.exr")));
        let (centre, corner) = (px[w / 2 + w * (h / 2)], px[0]);
        assert!(
            centre == [0.0; 3] && corner[1] > 0.5,
            "{name}: {centre:?} {corner:?}"
        );
    }
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

#[test]
fn unknown_types_and_pbrt_v3_names_are_refused_with_what_pbrt_v4_calls_them() {
    // Each of these rendered (exit 0, no message) or stopped at the first of many v3 names without a word on
    // what pbrt-v4 calls it: now an error at the statement, naming pbrt-v4's name where pbrt-v3 had another.
    let dir = tmp("v3");
    let cases = [
        ("Film \"image\"\nWorldBegin\n", "2:1", "pbrt-v3's film \"image\" is pbrt-v4's \"rgb\""),
        ("Film \"bogusfilm\"\nWorldBegin\n", "2:1", "not a pbrt-v4 film (rgb, gbuffer, spectral)"),
        ("Integrator \"bogus\"\nWorldBegin\n", "2:1", "not a pbrt-v4 integrator"),
        ("Integrator \"directlighting\"\nWorldBegin\n", "2:1", "pbrt-v4's \"volpath\" with \"integer maxdepth\" 1"),
        ("WorldBegin\nMaterial \"matte\"\nShape \"sphere\"\n", "3:1", "pbrt-v3's material \"matte\" is pbrt-v4's \"diffuse\""),
        ("WorldBegin\nMaterial \"diffuse\" \"color Kd\" [.5 .5 .5]\nShape \"sphere\"\n", "3:20", "pbrt-v3's \"Kd\" is pbrt-v4's \"reflectance\""),
        ("WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"heterogeneous\"\n", "3:1", "pbrt-v4's \"uniformgrid\""),
        (
            "WorldBegin\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\"\nMakeNamedMedium \"m\" \"string type\" \"homogeneous\"\n",
            "4:1",
            "a medium of that name is already defined",
        ),
    ];
    for (body, at, says) in cases {
        std::fs::write(
            dir.join("s.pbrt"),
            format!("Camera \"perspective\"\n{body}"),
        )
        .unwrap();
        let o = firemedium_in(&dir, &["render", "s.pbrt", "-q"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{body}: {err}");
        assert!(
            err.contains(&format!("s.pbrt:{at}: ")) && err.contains(says),
            "{body}: {err}"
        );
    }
}

#[test]
fn a_species_whose_flame_colour_is_molecular_is_warned_about() {
    // The spectroscopy scene's flames: barium and copper photograph, with a chlorine donor, in their chlorides'
    // colours, which the model does not hold, and potassium in a camera's lilac, each warned about at its medium;
    // lithium, sodium, calcium and strontium, whose colours are their lines and bands, not.
    let dir = tmp("molecular");
    let scene = crate::common::root().join("scenes/spectroscopy/scene.pbrt");
    let o = firemedium_in(
        &dir,
        &[
            "render",
            scene.to_str().unwrap(),
            "--resolution",
            "20x10",
            "--spp",
            "1",
            "-o",
            "s.exr",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    let warned: Vec<&str> = err
        .lines()
        .filter(|l| l.contains("warning") && l.contains("photographs"))
        .collect();
    assert_eq!(warned.len(), 3, "{warned:?}");
    for (sym, says) in [
        (
            "Ba",
            "with a chlorine donor its flame photographs green, from BaCl",
        ),
        (
            "Cu",
            "with a chlorine donor its flame photographs blue, from CuCl",
        ),
        ("K", "its flame photographs lilac"),
    ] {
        assert!(
            warned
                .iter()
                .any(|w| w.contains(&format!("species {sym}: ")) && w.contains(says)),
            "{sym}: {warned:?}"
        );
    }
}

#[test]
fn a_fire_clipped_swapped_or_behind_the_camera_is_warned_about() {
    // Three scenes that render without an error but not the fire they mean, each warned about at its medium's
    // statement: shapes that cut the data, a MediumInterface with inside and outside swapped, and a camera inside
    // the fire's shapes without being in the medium (pbrt-v4's semantics: its rays never enter it). The scene as
    // meant says nothing.
    let dir = tmp("boundary");
    let dataset = crate::common::root().join("scenes/campfire/campfire.vdb");
    let scene = |eye: &str, interface: &str, top: f64| {
        let box_ = format!(
            "[ -0.6 -0.6 0.005 0.6 -0.6 0.005 -0.6 0.6 0.005 0.6 0.6 0.005 -0.6 -0.6 {top} 0.6 -0.6 {top} -0.6 0.6 {top} 0.6 0.6 {top} ]"
        );
        format!(
            "LookAt {eye}  0 0 0.8  0 0 1\nCamera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 8 \"integer yresolution\" 8\nSampler \"independent\" \"integer pixelsamples\" 1\nWorldBegin\nMakeNamedMedium \"fire\" \"string type\" \"fire\" \"string dataset\" \"{}\"\nAttributeBegin\nMediumInterface {interface}\nMaterial \"interface\"\nShape \"trianglemesh\" \"point3 P\" {box_} \"integer indices\" [ 0 2 3 0 3 1 4 5 7 4 7 6 0 1 5 0 5 4 2 6 7 2 7 3 0 4 6 0 6 2 1 3 7 1 7 5 ]\nAttributeEnd\n",
            dataset.display()
        )
    };
    let cases = [
        (scene("0 -4 0.8", "\"fire\" \"\"", 1.6), None),
        (
            scene("0 -4 0.8", "\"fire\" \"\"", 1.0),
            Some("beyond the shapes that bound it"),
        ),
        (
            scene("0 -4 0.8", "\"\" \"fire\"", 1.6),
            Some("MediumInterface takes the inside medium first"),
        ),
        (
            scene("0 -0.2 0.8", "\"fire\" \"\"", 1.6),
            Some("the camera is inside the shapes bounding medium \"fire\""),
        ),
    ];
    for (text, says) in cases {
        std::fs::write(dir.join("s.pbrt"), &text).unwrap();
        let o = firemedium_in(&dir, &["render", "s.pbrt", "-o", "s.exr"]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(o.status.success(), "{err}");
        let warnings: Vec<&str> = err.lines().filter(|l| l.contains("warning")).collect();
        match says {
            None => assert!(warnings.is_empty(), "{warnings:?}"),
            Some(s) => assert!(
                warnings.len() == 1
                    && warnings[0].starts_with("s.pbrt:6:1: warning: ")
                    && warnings[0].contains(s),
                "{s}: {warnings:?}"
            ),
        }
    }
}

#[test]
fn the_readme_is_short_and_its_links_lead_somewhere() {
    // The README is the newcomer's page: what it is, the two commands, a first scene, where to go next — at most
    // about 8 KB; every relative link in it and in the guides names a file that exists.
    let root = crate::common::root();
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    assert!(
        readme.len() <= 8 * 1024,
        "README.md is {} bytes",
        readme.len()
    );
    for want in [
        "cargo build --release && target/release/firemedium render scenes/campfire/scene.pbrt",
        "cargo test --workspace --release",
        "firemedium scene fire.vdb",
    ] {
        assert!(readme.contains(want), "the README lost `{want}`");
    }
    let mut files = vec![root.join("README.md")];
    for e in std::fs::read_dir(root.join("docs/guide")).unwrap() {
        files.push(e.unwrap().path());
    }
    let mut broken = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        for (i, _) in text.match_indices("](") {
            let link: String = text[i + 2..]
                .chars()
                .take_while(|&c| c != ')' && c != '#' && c != ' ')
                .collect();
            if link.is_empty() || link.starts_with("http") {
                continue;
            }
            if !f.parent().unwrap().join(&link).exists() {
                broken.push(format!("{}: {link}", f.display()));
            }
        }
    }
    assert!(broken.is_empty(), "links to nothing: {broken:?}");
}

#[test]
fn the_results_page_gives_each_figure_a_command_and_a_log_entry_that_exists() {
    // docs/results/README.md: one row per topic — the current figure, the command that reproduces it, and a link
    // to the log entry that measured it, whose heading must still exist (GitHub's anchor: lower case, spaces to
    // hyphens, punctuation dropped). No internal issue numbers in it.
    let dir = crate::common::root().join("docs/results");
    let page = std::fs::read_to_string(dir.join("README.md")).unwrap();
    let log = std::fs::read_to_string(dir.join("log.md")).unwrap();
    let anchors: Vec<String> = log
        .lines()
        .filter_map(|l| l.strip_prefix("## "))
        .map(|h| {
            h.trim()
                .to_lowercase()
                .chars()
                .filter(|c| c.is_alphanumeric() || *c == '-' || *c == '_' || *c == ' ')
                .map(|c| if c == ' ' { '-' } else { c })
                .collect()
        })
        .collect();
    let rows: Vec<&str> = page
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| topic"))
        .collect();
    assert!(rows.len() >= 10, "{} rows", rows.len());
    for row in rows {
        let cells: Vec<&str> = row.split(" | ").collect();
        assert!(cells.len() >= 4, "{row}");
        assert!(cells[2].contains('`'), "no command: {row}");
        let anchor = row
            .split("(log.md#")
            .nth(1)
            .and_then(|r| r.split(')').next())
            .unwrap_or_else(|| panic!("no log entry: {row}"));
        assert!(
            anchors.iter().any(|a| a == anchor),
            "no log heading for #{anchor}"
        );
    }
    assert!(
        !page.to_lowercase().contains("issue "),
        "an issue number in the results page"
    );
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
