//! The ABI's medium level carries a fire as its whole-ray queries do: the renderer tracking a scattering,
//! emitting plume itself (`--tracking host`: the plugin's majorant grid walked cell by cell, its coefficients at
//! each tentative collision — what pbrt-v4 or Mitsuba 3 do with a medium) renders the image the plugin's own
//! tracking carries along every camera ray, up to noise; a fire with a layer the medium level cannot carry is
//! refused, naming it.

use crate::common::scratch::Scratch;
use firemedium::render::{integrator::Integrator, pixel::Samples, scene};
use std::path::Path;
use std::process::Command;

/// An emitting plume (scattering with `sigma_s` > 0) inside an interface sphere above a grey floor, under a dim
/// sky.
fn plume_scene(dir: &Path, sigma_s: f64, extra: &str) -> std::path::PathBuf {
    let nvdb = crate::common::root().join("tests/data/valid/nvdb/plume48.nvdb");
    let scene = dir.join("plume.pbrt");
    std::fs::write(
        &scene,
        format!(
            "LookAt 0 -3 0.2  0 0 -0.2  0 0 1\nCamera \"perspective\" \"float fov\" 50\nFilm \"rgb\" \"integer xresolution\" 24 \"integer yresolution\" 18\nSampler \"independent\" \"integer pixelsamples\" 8\nIntegrator \"volpath\" \"integer maxdepth\" 4\nWorldBegin\nLightSource \"infinite\" \"rgb L\" [0.05 0.05 0.06]\nMakeNamedMedium \"plume\" \"string type\" \"nanovdb\" \"string filename\" \"{}\" \"spectrum sigma_a\" [200 10 900 10] \"spectrum sigma_s\" [200 {sigma_s} 900 {sigma_s}] \"float Lescale\" 5 \"float temperaturecutoff\" 1 \"float temperaturescale\" 1.5 {extra}\nAttributeBegin\nMediumInterface \"plume\" \"\"\nMaterial \"interface\"\nShape \"sphere\" \"float radius\" 1\nAttributeEnd\nAttributeBegin\nMaterial \"diffuse\" \"rgb reflectance\" [0.5 0.5 0.5]\nShape \"trianglemesh\" \"point3 P\" [-20 -20 -1.05  20 -20 -1.05  20 20 -1.05  -20 20 -1.05] \"integer indices\" [0 1 2 0 2 3]\nAttributeEnd\n",
            nvdb.display()
        ),
    )
    .unwrap();
    scene
}

fn render(dir: &Path, scene: &Path, args: &[&str]) -> std::process::Output {
    Command::new(crate::common::exe("firemedium"))
        .current_dir(dir)
        .arg("render")
        .arg(scene)
        .args(["-q", "--plugin"])
        .arg(crate::common::plugin_file())
        .args(args)
        .output()
        .unwrap()
}

/// The radiance along one camera ray of `scene`, summed over the bins, by `n` paths: mean and standard error.
fn estimate(sc: &scene::Scene, pixel: (f64, f64), n: usize) -> (f64, f64) {
    let integ = Integrator {
        scene: sc,
        mask: sc.bins.mask(),
        fire_samples: Default::default(),
        failures: Default::default(),
        profile: None,
    };
    let mut rng = Samples::random(firemedium_core::rng::Rng::new(7));
    let (o, d) = firemedium::render::camera_ray(sc, pixel.0, pixel.1, &mut rng);
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let l = integ.li(o, d, &mut rng);
        let y: f64 = l.0[..sc.bins.n()].iter().map(|&v| v as f64).sum();
        sum += y;
        sum2 += y * y;
    }
    assert_eq!(integ.failures.into_report().0, 0, "plugin calls failed");
    let mean = sum / n as f64;
    (
        mean,
        ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt(),
    )
}

#[test]
fn host_tracking_through_the_medium_level_gives_the_plugins_radiance() {
    // Camera rays through the plume's hot base and its body, and one that misses it (the sky alone): the radiance
    // each carries, by the plugin's tracking and by the host's, agree within their noise (σ of each estimate from
    // its own samples) — emission alone (the host's delta tracking against the plugin's march), then with
    // scattering (both delta tracking; the sky and the floor through the bounces).
    let dir = Scratch::new("host-tracking", "plume");
    for (sigma_s, paths, pixels) in [
        (0.0, 100_000, &[(12.5, 6.5), (10.5, 8.5), (13.5, 4.5)][..]),
        (5.0, 150_000, &[(12.5, 6.5)][..]),
    ] {
        let scene_file = plume_scene(&dir, sigma_s, "");
        let load = |host: bool| {
            let ov = scene::Overrides {
                plugin: Some(crate::common::plugin_file()),
                host_tracking: host,
                ..Default::default()
            };
            scene::load(&scene_file, &ov).unwrap()
        };
        let (plugin, host) = (load(false), load(true));
        for &pixel in pixels {
            let (p, sp) = estimate(&plugin, pixel, paths);
            let (h, sh) = estimate(&host, pixel, paths);
            let sigma = (sp * sp + sh * sh).sqrt();
            let what = format!(
                "σ_s {sigma_s}, pixel {pixel:?}: host {h:.5e} ± {sh:.1e} vs plugin {p:.5e} ± {sp:.1e} ({:+.2} %)",
                100.0 * (h / p - 1.0)
            );
            assert!(
                p > 0.0 && sigma < 0.02 * p,
                "{what}: black or too noisy to tell"
            );
            assert!((h - p).abs() <= 4.0 * sigma + 0.005 * p, "{what}");
        }
    }
}

#[test]
fn host_tracking_refuses_what_the_medium_level_cannot_carry() {
    let dir = Scratch::new("host-tracking", "refused");
    // Refraction bends rays: no point query can say so.
    let scene = plume_scene(&dir, 5.0, "\"bool refraction\" true");
    let o = render(&dir, &scene, &["--tracking", "host", "--spp", "1"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("plume.pbrt:")
            && err.contains("medium \"plume\": --tracking host:")
            && err.contains("--tracking plugin"),
        "{err}"
    );
    // The same scene renders through the plugin's whole-ray queries.
    let o = render(&dir, &scene, &["--spp", "1"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}
