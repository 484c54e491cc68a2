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
    ds: Dataset,
    density: usize,
    temperature: Option<usize>,
    lescale: Option<usize>,
    /// The `lescale` channel is an emission grid: emission follows it, not the density (j = e · J(T)).
    emission_grid: bool,
    species: Vec<SpeciesChannel>,
}

impl Grids {
    /// The dataset and its channels: the density's, the temperature's, Lescale's (an emission grid when
    /// `emission_grid`), and the species'.
    pub(super) fn new(
        ds: Dataset,
        (density, temperature, lescale): (usize, Option<usize>, Option<usize>),
        emission_grid: bool,
        species: Vec<SpeciesChannel>,
    ) -> Grids {
        Grids {
            ds,
            density,
            temperature,
            lescale,
            emission_grid,
            species,
        }
    }
    /// A dataset of a density and a temperature alone (the light's coarse copy).
    pub(super) fn density_and_temperature(ds: Dataset) -> Grids {
        Grids::new(ds, (0, Some(1), None), false, Vec::new())
    }
    pub(super) fn ds(&self) -> &Dataset {
        &self.ds
    }
    pub(super) fn density(&self) -> usize {
        self.density
    }
    pub(super) fn temperature(&self) -> Option<usize> {
        self.temperature
    }
    pub(super) fn lescale(&self) -> Option<usize> {
        self.lescale
    }
    /// Whether the `lescale` channel is an emission grid (j = e · J(T)).
    pub(super) fn emission_grid(&self) -> bool {
        self.emission_grid
    }
    pub(super) fn species(&self) -> &[SpeciesChannel] {
        &self.species
    }
}

/// The coefficient model: σ and j per unit density over temperature, in the volume's channels.
#[derive(Debug, Clone)]
pub(super) struct Model {
    basis: Basis,
    mode: Mode,
    /// σ_a and σ_s per unit density, per channel (rgb physical mode: σ_a depends on T, `a_t`).
    a: Vec<f64>,
    a_t: Option<TTable>,
    s: Vec<f64>,
    /// Emission per unit density over T.
    j: TTable,
    /// pbrt's 100 K emission threshold (0 in physical mode).
    t_emit: f64,
    /// The fire's colour is the physics' (no tint, no colour ramp short of `physical` 1).
    physical_colour: bool,
    /// The scatter colour grid's channels and, per channel, the weights of its r, g, b.
    scatter_color: Option<ScatterColor>,
    /// Henyey–Greenstein g.
    g: f64,
    /// What the point query evaluates at any wavelength (or why it is refused).
    point_model: point::PointModel,
}

/// A scatter colour grid's channels and, per volume channel, the weights of its r, g, b.
pub(super) type ScatterColor = ([usize; 3], Vec<[f64; 3]>);

/// σ_a, σ_a over T (where it depends on T), σ_s, j over T, and the temperature emission starts above.
pub(super) type PerDensity = (Vec<f64>, Option<TTable>, Vec<f64>, TTable, f64);

impl Model {
    /// The model in `basis` under `mode`: the coefficients per unit density, whether the colour is the
    /// physics' and the scatter colour grid, Henyey–Greenstein g, and what the point query evaluates.
    pub(super) fn new(
        (basis, mode): (Basis, Mode),
        (a, a_t, s, j, t_emit): PerDensity,
        (physical_colour, scatter_color): (bool, Option<ScatterColor>),
        g: f64,
        point_model: point::PointModel,
    ) -> Model {
        Model {
            basis,
            mode,
            a,
            a_t,
            s,
            j,
            t_emit,
            physical_colour,
            scatter_color,
            g,
            point_model,
        }
    }
    /// The model of a copy of the volume's soot alone (the light's coarse copy): σ_a constant in T, no scatter
    /// colour grid.
    pub(super) fn soot_copy(&self) -> Model {
        Model {
            basis: self.basis.clone(),
            mode: self.mode,
            a: self.a.clone(),
            a_t: None,
            s: self.s.clone(),
            j: self.j.clone(),
            t_emit: self.t_emit,
            physical_colour: self.physical_colour,
            scatter_color: None,
            g: self.g,
            point_model: self.point_model.clone(),
        }
    }
    pub(super) fn basis(&self) -> &Basis {
        &self.basis
    }
    pub(super) fn mode(&self) -> Mode {
        self.mode
    }
    /// σ_a per unit density, per channel.
    pub(super) fn a(&self) -> &[f64] {
        &self.a
    }
    /// σ_a per unit density over T, where it depends on T (rgb physical mode).
    pub(super) fn a_t(&self) -> Option<&TTable> {
        self.a_t.as_ref()
    }
    /// σ_s per unit density, per channel.
    pub(super) fn s(&self) -> &[f64] {
        &self.s
    }
    /// Emission per unit density over T.
    pub(super) fn j(&self) -> &TTable {
        &self.j
    }
    pub(super) fn t_emit(&self) -> f64 {
        self.t_emit
    }
    pub(super) fn physical_colour(&self) -> bool {
        self.physical_colour
    }
    pub(super) fn scatter_color(&self) -> Option<&ScatterColor> {
        self.scatter_color.as_ref()
    }
    pub(super) fn g(&self) -> f64 {
        self.g
    }
    pub(super) fn point_model(&self) -> &point::PointModel {
        &self.point_model
    }
}

/// Where the medium is and how thick: the majorant bricks and the box rays are clipped to.
#[derive(Debug, Clone)]
pub(super) struct Bounds {
    majorant: MajorantGrid,
    brick_sigma: Vec<f64>,
    /// Bricks holding no density and no species anywhere in their interpolation footprint: no σ, no j.
    brick_empty: Vec<bool>,
    /// Where rays are clipped: the dataset bounds, or pbrt-v4 nanovdb's world box [T(i_min), T(i_max + 1)]
    /// (shifted half a voxel up), with lookups fading over the half voxel beyond the last samples.
    clip_box: [DVec3; 2],
    margin: f64,
}

impl Bounds {
    /// The majorant bricks, each brick's largest σ_t over its channels and whether it is empty, the box rays are
    /// clipped to and how far lookups fade beyond the last samples.
    pub(super) fn new(
        majorant: MajorantGrid,
        (brick_sigma, brick_empty): (Vec<f64>, Vec<bool>),
        clip_box: [DVec3; 2],
        margin: f64,
    ) -> Bounds {
        Bounds {
            majorant,
            brick_sigma,
            brick_empty,
            clip_box,
            margin,
        }
    }
    pub(super) fn majorant(&self) -> &MajorantGrid {
        &self.majorant
    }
    /// Each majorant brick's bound on σ_t over every channel.
    pub(super) fn brick_sigma(&self) -> &[f64] {
        &self.brick_sigma
    }
    /// Per majorant brick: whether it holds nothing (no σ, no j).
    pub(super) fn brick_empty(&self) -> &[bool] {
        &self.brick_empty
    }
    pub(super) fn clip_box(&self) -> [DVec3; 2] {
        self.clip_box
    }
    /// How far beyond the last samples lookups fade (pbrt-v4's nanovdb: half a voxel; else 0).
    pub(super) fn margin(&self) -> f64 {
        self.margin
    }
    /// Bytes held.
    pub(super) fn bytes(&self) -> usize {
        self.majorant.bytes() + self.brick_sigma.len() * 9
    }
}

/// The optional layers, each built only when the scene asks for it; what the volume's modules read of them goes
/// through the methods below.
#[derive(Debug, Clone, Default)]
pub(super) struct Layers {
    /// Velocity motion blur (a velocity grid and an open shutter).
    blur: Option<motion::Blur>,
    /// The `embers` particles: opaque grey spheres (see [`crate::embers`]).
    embers: Option<crate::embers::Embers>,
    /// The index field and step control, only when `refraction` is on.
    refraction: Option<super::bent::Refraction>,
    /// The fire's light in its smoke by diffusion (`multiplescattering "diffusion"`): read as emission.
    diffusion: Option<diffusion::Diffusion>,
    /// Atomic lines that can be optically thick, integrated across their profiles (`lineshape "voigt"`).
    lines: Option<lines::ThickLines>,
}

impl Layers {
    /// The layers built with the volume's grids (diffusion comes later, from the built volume:
    /// [`set_diffusion`](Self::set_diffusion)).
    pub(super) fn new(
        blur: Option<motion::Blur>,
        embers: Option<crate::embers::Embers>,
        refraction: Option<super::bent::Refraction>,
        lines: Option<lines::ThickLines>,
    ) -> Layers {
        Layers {
            blur,
            embers,
            refraction,
            diffusion: None,
            lines,
        }
    }
    pub(super) fn set_diffusion(&mut self, df: diffusion::Diffusion) {
        self.diffusion = Some(df);
    }
    pub(super) fn blur(&self) -> Option<&motion::Blur> {
        self.blur.as_ref()
    }
    pub(super) fn embers(&self) -> Option<&crate::embers::Embers> {
        self.embers.as_ref()
    }
    pub(super) fn refraction(&self) -> Option<&super::bent::Refraction> {
        self.refraction.as_ref()
    }
    pub(super) fn diffusion(&self) -> Option<&diffusion::Diffusion> {
        self.diffusion.as_ref()
    }
    pub(super) fn lines(&self) -> Option<&lines::ThickLines> {
        self.lines.as_ref()
    }
    /// Each layer, whether the volume has it, and its name in a sentence (what a query that cannot take it
    /// refuses).
    pub(super) fn present(&self) -> [(bool, &'static str); 5] {
        [
            (self.lines.is_some(), "optically thick atomic lines"),
            (self.diffusion.is_some(), "diffusion"),
            (self.refraction.is_some(), "refraction"),
            (self.embers.is_some(), "embers"),
            (self.blur.is_some(), "motion blur"),
        ]
    }
    /// Whether the volume has none of them.
    pub(super) fn none(&self) -> bool {
        self.present().iter().all(|(on, _)| !on)
    }
}

/// The estimator: which integrator, its step and cutoffs, and the march's accelerator.
#[derive(Debug, Clone)]
pub(super) struct Estimator {
    integrator: Integrator,
    step: f64,
    /// The largest optical depth of one march step before it is split (`steptau`; ∞: never).
    step_tau: f64,
    cutoff: f64,
    /// The march's tables in f32 lanes (`precision "f32"`, the march, and every product inside f32's range).
    lanes: Option<lanes::LaneTables>,
    /// The grids laid out for the lane march's kernel (with the lanes, for trilinear datasets), built with the
    /// volume or when a ray first marches ([`lattice::Slot`]).
    lattice: lattice::Slot,
}

impl Estimator {
    /// The integrator with its step, the optical depth at which a march step is split and the transmittance
    /// cutoff; the lanes and the lattice follow once the volume is built.
    pub(super) fn new(integrator: Integrator, step: f64, step_tau: f64, cutoff: f64) -> Estimator {
        Estimator {
            integrator,
            step,
            step_tau,
            cutoff,
            lanes: None,
            lattice: lattice::Slot::default(),
        }
    }
    pub(super) fn set_lanes(&mut self, lanes: Option<lanes::LaneTables>) {
        self.lanes = lanes;
    }
    pub(super) fn set_lattice(&mut self, lattice: lattice::Slot) {
        self.lattice = lattice;
    }
    /// The step no longer than `most`.
    pub(super) fn shorten_step(&mut self, most: f64) {
        self.step = self.step.min(most);
    }
    pub(super) fn integrator(&self) -> Integrator {
        self.integrator
    }
    pub(super) fn step(&self) -> f64 {
        self.step
    }
    pub(super) fn step_tau(&self) -> f64 {
        self.step_tau
    }
    pub(super) fn cutoff(&self) -> f64 {
        self.cutoff
    }
    pub(super) fn lanes(&self) -> Option<&lanes::LaneTables> {
        self.lanes.as_ref()
    }
    pub(super) fn lattice(&self) -> &lattice::Slot {
        &self.lattice
    }
}

/// What the build reports, and leaves for what is derived from the volume later.
#[derive(Debug, Clone, Default)]
pub(super) struct Report {
    tables: Vec<TableReport>,
    build_seconds: f64,
    source: Option<Source>,
    /// Bytes the budget (`maxbytes`) leaves for what is derived from the volume later (its fire light).
    spare: u64,
    /// The build's thread budget (`threads`), which the fire light's build keeps to as well.
    threads: usize,
    /// What the build found that a user should hear ([`super::notes`]).
    notes: Vec<String>,
}

impl Report {
    /// The report of a volume built from its settings: its tables so far, what it emits, its notes.
    pub(super) fn new(
        tables: Vec<TableReport>,
        source: Option<Source>,
        notes: Vec<String>,
    ) -> Report {
        Report {
            tables,
            source,
            notes,
            ..Report::default()
        }
    }
    /// The report of a copy of a volume (the light's coarse copy): nothing built, the same thread budget.
    pub(super) fn of_copy(threads: usize) -> Report {
        Report {
            threads,
            ..Report::default()
        }
    }
    pub(super) fn set_threads(&mut self, threads: usize) {
        self.threads = threads;
    }
    /// A table built after the volume's first tables (lanes, lattice, diffusion).
    pub(super) fn push(&mut self, table: TableReport) {
        self.tables.push(table);
    }
    /// The bytes of the tables built so far.
    pub(super) fn table_bytes(&self) -> u64 {
        self.tables.iter().map(|t| t.bytes as u64).sum()
    }
    /// The build done: what `budget` leaves after the tables and `reserved` bytes, and the build's seconds.
    pub(super) fn finish(&mut self, budget: u64, reserved: u64, seconds: f64) {
        self.spare = budget
            .saturating_sub(self.table_bytes())
            .saturating_sub(reserved);
        self.build_seconds = seconds;
    }
    pub(super) fn tables(&self) -> &[TableReport] {
        &self.tables
    }
    pub(super) fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
    pub(super) fn source(&self) -> Option<&Source> {
        self.source.as_ref()
    }
    pub(super) fn notes(&self) -> &[String] {
        &self.notes
    }
    pub(super) fn threads(&self) -> usize {
        self.threads
    }
    pub(super) fn spare(&self) -> u64 {
        self.spare
    }
}
