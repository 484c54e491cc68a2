//! # firemedium, the pbrt-v4 host
//!
//! A library that renders pbrt-v4 scenes whose media are fires loaded from the firemedium plugin (through its C
//! ABI, with `firemedium-loader`), and the pieces around it; the `firemedium` command line (`src/cli/`) is a thin
//! layer of commands over it.
//!
//! | module | what |
//! |---|---|
//! | [`render`] | scene building from a pbrt-v4 file, the `volpath` integrator, tiles on rayon → an absolute [`render::Image`] |
//! | [`imageio`] | EXR/PNG in (textures, light maps, references) and out (the film, previews), written atomically |
//! | [`tonemap`] | visual adaptation (P&P §3.8): XYZ in cd/m² → display sRGB (von Kries + Naka–Rushton) |
//! | [`metrics`] | DESIGN's error metrics (relative RMSE, relMSE) and luminance |
//! | [`budget`] | the memory budget, checked before allocating what input sizes |
//! | [`heap`] | the allocator's policy: glibc's thresholds held, a build's freed memory given back |
//! | [`Error`] | the one error type: a scene statement's `file:line:col`, a file, the budget, the plugin, a value; its exit status |
//!
//! Arrows point one way: `render` → `imageio`; `imageio`, `tonemap`, `metrics` depend on no other module here but
//! [`Error`];
//! colour comes from `firemedium-core` and, for media, from the plugin the scene loaded.

// `unsafe` calls, allowed where they are made: loading the plugin (`render::scene`) and the allocator's policy
// (`heap`).
#![deny(unsafe_code)]

pub mod args;
pub mod budget;
mod error;
pub mod heap;
pub mod imageio;
pub mod metrics;
pub mod render;
pub mod term;
pub mod tonemap;

pub use error::{Error, Result};

/// The program `name` beside the running executable (`firemedium` and `firemedium-bench` find each other so,
/// in a build's output folder and in an installed `bin/`): its path, or the path where it was looked for.
pub fn program_beside(name: &str) -> Result<std::path::PathBuf, std::path::PathBuf> {
    let exe = std::env::current_exe().unwrap_or_default();
    let p = exe.with_file_name(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    if p.is_file() {
        Ok(p)
    } else {
        Err(p)
    }
}
