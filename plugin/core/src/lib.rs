//! # firemedium-core: the fire's physics
//!
//! Pure functions of temperature, wavelength and composition that the plugin's components call per voxel or per
//! sample, and that the host uses for its own colorimetry and tone mapping without linking the plugin.
//!
//! | module | what | source |
//! |---|---|---|
//! | [`constants`] | CODATA 2018 constants | CODATA 2018 |
//! | [`blackbody`] | absolute Planck spectral radiance | P&P eq. 6 |
//! | [`chemiluminescence`] | the blue core: CH* and C₂* band emission of the reaction zone | Selle; Pearse & Gaydon 1976 |
//! | [`ember`] | embers: grey spheres cooling by radiation (Stefan–Boltzmann) | Selle; lumped heat balance |
//! | [`soot`] | soot absorption coefficient | P&P eq. 5, Dalzell & Sarofim 1969 |
//! | [`species`] | atomic line absorption and emission | P&P eq. 7–12, NIST ASD |
//! | [`ciddor`] | refractive index of air | Ciddor 1996 |
//! | [`cie`] | CIE 1931 colour matching, XYZ, sRGB, LMS | CIE 1931, IEC 61966-2-1, Hunt–Pointer–Estévez |
//! | [`spectrum`] | spectral bins | the thesis: equal bins over a range |
//! | [`quadrature`] | Gauss–Legendre | — |
//! | [`rgb_spectrum`] | rgb → spectrum (albedo, unbounded, illuminant), D65 | Jakob & Hanika 2019, pbrt-v4, CIE 15:2004 |
//! | [`rng`] | SplitMix64 | Steele, Lea & Flood 2014 |
//!
//! Invariants: no I/O, no `unsafe`, no `Result` in per-sample code (inputs outside a function's domain map to
//! documented finite values; validation happens when a table is constructed); SI units inside, wavelengths in
//! nm at the API; every public quantity documents its unit.

#![forbid(unsafe_code)]

pub mod blackbody;
pub mod chemiluminescence;
pub mod ciddor;
pub mod cie;
pub mod constants;
pub mod ember;
pub mod error;
pub mod quadrature;
pub mod rgb_spectrum;
pub mod rng;
pub mod soot;
pub mod species;
pub mod spectrum;

pub use error::Error;
