//! # firemedium plugin
//!
//! The fire of Pegoraro & Parker, *Physically-Based Realistic Fire Rendering* (2006), packaged as a medium a
//! path tracer loads at run time, in the three components of Dorta-Perez's thesis (voxel dataset, fire volume,
//! fire light).
//!
//! This crate is built twice: as a `cdylib` (the loadable plugin) and as an `rlib` (so tests and tools can call
//! the pure physics directly). Today it holds the spectral physics core:
//!
//! | module | what | source |
//! |---|---|---|
//! | [`constants`] | CODATA 2018 constants | CODATA 2018 |
//! | [`blackbody`] | absolute Planck spectral radiance | P&P eq. 6 |
//! | [`soot`] | soot absorption coefficient | P&P eq. 5, Dalzell & Sarofim 1969 |
//! | [`species`] | atomic line absorption and emission | P&P eq. 7–12, NIST ASD |
//! | [`ciddor`] | refractive index of air | Ciddor 1996 |
//! | [`cie`] | CIE 1931 colour matching, XYZ, sRGB, LMS | CIE 1931, IEC 61966-2-1, Hunt–Pointer–Estévez |
//! | [`spectrum`] | spectral bins | the thesis: 30 bins over 400–700 nm |
//!
//! Invariants: physics modules are pure (no I/O, no `unsafe`, no `Result` in per-sample code); SI units inside,
//! wavelengths in nm at the API; every public quantity documents its unit.

pub use firemedium_core::{
    blackbody, ciddor, cie, constants, quadrature, rng, soot, species, spectrum,
};

pub mod dataset;
pub mod error;
pub mod export;
pub mod grid;
pub mod light;
pub mod majorant;
pub mod params;
pub mod refraction;
pub mod volume;

pub use error::Error;
