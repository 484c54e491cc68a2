//! # firemedium plugin
//!
//! The fire of Pegoraro & Parker, *Physically-Based Realistic Fire Rendering* (2006), packaged as a medium a
//! path tracer loads at run time, in the three components of Dorta-Perez's thesis (voxel dataset, fire volume,
//! fire light).
//!
//! This crate is built twice: as a `cdylib` (the loadable plugin, whose one entry point is
//! [`export::firemedium_plugin_entry`]) and as an `rlib` (for the tests, the benchmarks and the host's `info` and
//! `gen`). The physics it computes with is `firemedium-core`'s, re-exported here under the same names.
//!
//! | module | component | what |
//! |---|---|---|
//! | [`dataset`] | voxel dataset | files (OpenVDB, NanoVDB, the thesis's ASCII and raw formats, pbrt inline arrays) → validated grids; its parameter mapping |
//! | [`grid`], [`majorant`] | voxel dataset | cell-centred grids with pbrt-v4's lookup; majorant bricks and their DDA |
//! | [`volume`] | fire volume | settings → coefficient tables → march lattice and majorants → the RTE along rays (march, ratio, delta) |
//! | [`refraction`] | fire volume | the index of hot air (Ciddor) baked to a field; curved rays through it |
//! | [`light`] | fire light | Selle's piecewise-constant 3D pdf over emitting voxels; samples, pdfs, power |
//! | [`params`] | all | one table per component drives parsing, validation, docs/reference/params.md and the ABI's self-description |
//! | [`export`] | all | the C ABI: the crate's only `unsafe`, every entry checked and guarded against panics |
//!
//! Invariants: components are immutable once built and `Send + Sync`; per-sample code cannot fail (values are
//! validated when a component is built); SI units inside, wavelengths in nm at the API.

#![deny(unsafe_code)]
pub use firemedium_core::{
    blackbody, ciddor, cie, constants, quadrature, rgb_spectrum, rng, soot, species, spectrum,
};

use firemedium_dataset::alloc;
pub mod dataset;
mod embers;
#[allow(unsafe_code)]
// The C ABI: the plugin's one module with `unsafe`, every block with a `// SAFETY:` line.
pub mod export;
pub use firemedium_dataset::grid;
pub mod light;
pub mod majorant;
use firemedium_dataset::par;
pub mod params;
pub mod refraction;
pub mod volume;

pub use firemedium_dataset::Error;
