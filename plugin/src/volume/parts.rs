//! The parts a [`FireVolume`](super::FireVolume) is built from, each built once by the volume's constructor:
//! the grids it reads, its coefficient model, its majorants, the optional layers a scene asks for, its
//! estimator with the march's accelerator, and what the build reports.

use super::basis::Basis;
use super::tables::TTable;
use super::Mode;
use super::{diffusion, lanes, lattice, lines, motion, point, Integrator, SpeciesChannel};
use super::{Source, TableReport};
use crate::dataset::Dataset;
use crate::majorant::MajorantGrid;
use glam::DVec3;

/// The grids the volume reads: the dataset and which of its channels are what.
#[derive(Debug, Clone)]
pub(super) struct Grids {
    pub(super) ds: Dataset,
    pub(super) density: usize,
    pub(super) temperature: Option<usize>,
    pub(super) lescale: Option<usize>,
    /// The `lescale` channel is an emission grid: emission follows it, not the density (j = e · J(T)).
    pub(super) emission_grid: bool,
    pub(super) species: Vec<SpeciesChannel>,
}

/// The coefficient model: σ and j per unit density over temperature, in the volume's channels.
#[derive(Debug, Clone)]
pub(super) struct Model {
    pub(super) basis: Basis,
    pub(super) mode: Mode,
    /// σ_a and σ_s per unit density, per channel (rgb physical mode: σ_a depends on T, `a_t`).
    pub(super) a: Vec<f64>,
    pub(super) a_t: Option<TTable>,
    pub(super) s: Vec<f64>,
    /// Emission per unit density over T.
    pub(super) j: TTable,
    /// pbrt's 100 K emission threshold (0 in physical mode).
    pub(super) t_emit: f64,
    /// The fire's colour is the physics' (no tint, no colour ramp short of `physical` 1).
    pub(super) physical_colour: bool,
    /// The scatter colour grid's channels and, per channel, the weights of its r, g, b.
    pub(super) scatter_color: Option<([usize; 3], Vec<[f64; 3]>)>,
    /// Henyey–Greenstein g.
    pub(super) g: f64,
    /// What the point query evaluates at any wavelength (or why it is refused).
    pub(super) point_model: point::PointModel,
}

/// Where the medium is and how thick: the majorant bricks and the box rays are clipped to.
#[derive(Debug, Clone)]
pub(super) struct Bounds {
    pub(super) majorant: MajorantGrid,
    pub(super) brick_sigma: Vec<f64>,
    /// Bricks holding no density and no species anywhere in their interpolation footprint: no σ, no j.
    pub(super) brick_empty: Vec<bool>,
    /// Where rays are clipped: the dataset bounds, or pbrt-v4 nanovdb's world box [T(i_min), T(i_max + 1)]
    /// (shifted half a voxel up), with lookups fading over the half voxel beyond the last samples.
    pub(super) clip_box: [DVec3; 2],
    pub(super) margin: f64,
}

/// The optional layers, each built only when the scene asks for it.
#[derive(Debug, Clone, Default)]
pub(super) struct Layers {
    /// Velocity motion blur (a velocity grid and an open shutter).
    pub(super) blur: Option<motion::Blur>,
    /// The `embers` particles: opaque grey spheres (see [`crate::embers`]).
    pub(super) embers: Option<crate::embers::Embers>,
    /// The index field and step control, only when `refraction` is on.
    pub(super) refraction: Option<super::bent::Refraction>,
    /// The fire's light in its smoke by diffusion (`multiplescattering "diffusion"`): read as emission.
    pub(super) diffusion: Option<diffusion::Diffusion>,
    /// Atomic lines that can be optically thick, integrated across their profiles (`lineshape "voigt"`).
    pub(super) lines: Option<lines::ThickLines>,
}

/// The estimator: which integrator, its step and cutoffs, and the march's accelerator.
#[derive(Debug, Clone)]
pub(super) struct Estimator {
    pub(super) integrator: Integrator,
    pub(super) step: f64,
    /// The largest optical depth of one march step before it is split (`steptau`; ∞: never).
    pub(super) step_tau: f64,
    pub(super) cutoff: f64,
    /// The march's tables in f32 lanes (`precision "f32"`, the march, and every product inside f32's range).
    pub(super) lanes: Option<lanes::LaneTables>,
    /// The grids laid out for the lane march's kernel (with the lanes, for trilinear datasets), built with the
    /// volume or when a ray first marches ([`lattice::Slot`]).
    pub(super) lattice: lattice::Slot,
}

/// What the build reports, and leaves for what is derived from the volume later.
#[derive(Debug, Clone)]
pub(super) struct Report {
    pub(super) tables: Vec<TableReport>,
    pub(super) build_seconds: f64,
    pub(super) source: Option<Source>,
    /// Bytes the budget (`maxbytes`) leaves for what is derived from the volume later (its fire light).
    pub(super) spare: u64,
    /// The build's thread budget (`threads`), which the fire light's build keeps to as well.
    pub(super) threads: usize,
    /// What the build found that a user should hear ([`super::notes`]).
    pub(super) notes: Vec<String>,
}
