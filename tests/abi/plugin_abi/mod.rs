//! End-to-end through the C ABI: load the **built** plugin library (not the rlib) with the loader, create fire
//! volumes, integrate from four threads at once, and check errors and lifetimes (that a panic inside the plugin
//! comes back as a status is the plugin's own test, `export::tests`: test-only code never enters the shipped build).
//! A file per concern: volumes, the host's context, the fire light, the medium level.
//!
//! The end-to-end crate's dev-dependency on the plugin makes Cargo build the plugin's cdylib (the shipped build)
//! into the same target directory.

use firemedium_loader::{library_file_name, Error, Param, Plugin, Ray, Value};
use std::path::PathBuf;

mod context;
mod light;
mod medium_level;
mod volumes;

fn plugin() -> Plugin {
    // The test executable lives in target/<profile>/deps, beside the cdylib Cargo built for this run.
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let dirs = [deps.clone(), deps.parent().unwrap().to_path_buf()];
    // SAFETY: the plugin this cargo invocation built.
    unsafe { Plugin::find(&dirs) }.unwrap_or_else(|e| {
        panic!(
            "{e} — the plugin cdylib ({}) should be built by `cargo test`",
            library_file_name()
        )
    })
}

fn fire_file() -> String {
    crate::common::root()
        .join("tests/data/valid/vdb/mantaflow_fire_f060.vdb")
        .to_string_lossy()
        .into_owned()
}

fn fire_params() -> Vec<Param> {
    vec![
        Param::string("filename", &fire_file()),
        Param::float("temperaturescale", 1000.0),
        Param::float("sootscale", 1e-6),
    ]
}

fn rays(n: usize) -> Vec<Ray> {
    // A fan of rays through the fire (medium space: the Mantaflow grid spans about [0, 2]² × [0, 3] m).
    (0..n)
        .map(|i| {
            let f = i as f64 / n as f64;
            Ray {
                origin: [
                    0.2 + 1.6 * f,
                    -1.0,
                    0.3 + 2.0 * ((i * 7) % n) as f64 / n as f64,
                ],
                direction: [0.05 * (f - 0.5), 1.0, 0.1 * (0.5 - f)],
                tmin: 0.0,
                tmax: 5.0,
                seed: i as u64,
            }
        })
        .collect()
}
