//! A complete Rust host of the fire, from the loader alone: load the plugin, create a fire from a dataset, look
//! through it along a fan of rays (radiance and transmittance per channel, turned into luminance with the
//! plugin's own colour weights), then build its fire light and estimate the light it sends to a point beside it.
//!
//! ```sh
//! cargo run --release -p firemedium-loader --example fire_pixel                 # the default scene's campfire
//! cargo run --release -p firemedium-loader --example fire_pixel -- fire.vdb     # any fire dataset
//! ```
//!
//! The plugin is the file `FIREMEDIUM_PLUGIN` names, or `libfiremedium_plugin.so` on `FIREMEDIUM_PLUGIN_PATH` or
//! in Cargo's `target/release` (one folder up from this example).

use firemedium_loader::{Param, Plugin, Ray};
use std::process::ExitCode;

fn main() -> ExitCode {
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("fire_pixel: {e}");
            ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let dataset = std::env::args().nth(1).unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenes/campfire/campfire.vdb"
        )
        .to_string()
    });
    // SAFETY: loading a library runs its initialisers; this is the firemedium plugin built with this example (or
    // the one the environment names).
    let plugin = unsafe { Plugin::from_env() }?;
    let (major, minor) = plugin.version();
    println!("plugin {} (ABI {major}.{minor})", plugin.path().display());

    // The fire: the dataset's density (a soot volume fraction) and temperature (K), propane soot. Every parameter
    // the plugin reads is in docs/reference/params.md (or `plugin.parameters()`).
    let fire = plugin.create_volume(&[
        Param::string("dataset", &dataset),
        Param::string("fuel", "propane"),
    ])?;
    let info = fire.info();
    let c = info.channels as usize;
    let (lo, hi) = (info.bounds_min, info.bounds_max);
    println!(
        "fire: {c} channels over {}–{} nm, box {lo:?} – {hi:?}",
        info.lambda_min, info.lambda_max
    );

    // A fan of rays across the box at half its height, in medium space; radiance and transmittance come back as
    // rays × channels, channel fastest.
    let z = lo[2] + 0.3 * (hi[2] - lo[2]);
    let rays: Vec<Ray> = (0..9)
        .map(|i| {
            let x = lo[0] + (hi[0] - lo[0]) * (i as f64 + 0.5) / 9.0;
            Ray {
                origin: [x, lo[1] - 1.0, z],
                direction: [0.0, 1.0, 0.0],
                tmin: 0.0,
                tmax: 1e30,
                seed: i,
            }
        })
        .collect();
    let (mut radiance, mut transmittance) =
        (vec![0f32; rays.len() * c], vec![0f32; rays.len() * c]);
    fire.integrate(&rays, &mut radiance, Some(&mut transmittance), None)?;
    // Luminance (cd/m²) from the plugin's colour weights: XYZ of unit radiance in each channel.
    let xyz = fire.channel_xyz()?;
    for (i, r) in rays.iter().enumerate() {
        let l = &radiance[i * c..(i + 1) * c];
        let y: f64 = l.iter().zip(&xyz).map(|(v, w)| *v as f64 * w[1]).sum();
        let t_mid = transmittance[i * c + c / 2];
        println!(
            "ray x = {:+.3}: Y {y:.4e} cd/m², transmittance {t_mid:.3} (middle channel)",
            r.origin[0]
        );
    }

    // The fire light: 256 points sampled by the fire's power (six uniform numbers each), and the light the fire
    // sends to a point beside it — its radiance along each sampled direction over that direction's density.
    let light = fire.create_light(None)?;
    let linfo = light.info();
    println!(
        "fire light: {:.4e} W, {:.4e} lm over {} voxels",
        linfo.power_w, linfo.power_lm, linfo.voxels
    );
    let n = 256;
    let mut rng = 0x2545_f491_4f6c_dd1du64;
    let mut uniform = || {
        rng ^= rng << 13;
        rng ^= rng >> 7;
        rng ^= rng << 17;
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let u: Vec<[f64; 6]> = (0..n).map(|_| [(); 6].map(|_| uniform())).collect();
    let (mut points, mut pdf) = (vec![[0.0; 3]; n], vec![0.0; n]);
    light.sample(&u, &mut points, &mut pdf, None)?;
    let at = [hi[0] + 1.0, 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])];
    let dirs: Vec<[f64; 3]> = points
        .iter()
        .map(|p| [p[0] - at[0], p[1] - at[1], p[2] - at[2]])
        .collect();
    let origins = vec![at; n];
    let mut pd = vec![0.0; n];
    light.pdf_direction(&origins, &dirs, &mut pd)?;
    let shots: Vec<Ray> = dirs
        .iter()
        .enumerate()
        .map(|(i, d)| Ray {
            origin: at,
            direction: *d,
            tmin: 0.0,
            tmax: 1e30,
            seed: 1000 + i as u64,
        })
        .collect();
    let mut l = vec![0f32; n * c];
    // The fire's emission along each direction as the light estimates it (its line estimate).
    light.integrate_at(&shots, None, &mut l, None)?;
    // ∫ L_Y dω over all directions at that point (its scalar illuminance, lm/m²): the mean of L_Y / pdf.
    let mut sum = 0.0;
    for i in 0..n {
        if pd[i] > 0.0 {
            let y: f64 = l[i * c..(i + 1) * c]
                .iter()
                .zip(&xyz)
                .map(|(v, w)| *v as f64 * w[1])
                .sum();
            sum += y / pd[i];
        }
    }
    println!(
        "scalar illuminance at {at:?}: {:.4e} lm/m² (the fire light's estimate from {n} samples)",
        sum / n as f64
    );
    Ok(())
}
