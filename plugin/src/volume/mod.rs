//! The fire volume component (the thesis's "fire volume shader"): voxels → spectral σ_a, σ_s and emission,
//! integrated along rays.
//!
//! ## Coefficients
//! With d the density channel, T the temperature (K, after the dataset's mapping) and N_s species number
//! densities (m⁻³), per channel c:
//! - **physical** mode: σ_a,c = f_v κ̂_c + Σ_s N_s σ̂_s,c(T), σ_s,c = sigma_s,c d, and the emission coefficient
//!   j_c = intensity · (f_v (κ̂B)_c(T) + Σ_s N_s ĵ_s,c(T)), with f_v = sootscale · d, κ̂ the soot absorption
//!   per unit volume fraction (eq. 5), B Planck's law (eq. 6) and σ̂, ĵ the line cross-sections (eq. 7–12).
//!   Kirchhoff holds per line and for soot: j = σ_a B.
//! - **pbrt** mode (pbrt-v4 `uniformgrid`/`nanovdb`): σ_a,c = scale · sigma_a,c · d, σ_s,c = scale ·
//!   sigma_s,c · d (both σ's default to 1, as pbrt-v4's), j_c = σ_a,c · Lescale · B̃_c(T) for T > 100 K with B̃
//!   the peak-normalised blackbody, not photometrically scaled (an optically thick 2000 K grid records Y = 5.2
//!   in pbrt-v4), or a constant `Le` spectrum scaled to luminance 1 (rgb: to its rgb's), Lescale possibly a
//!   grid. For NanoVDB files rays are clipped, as pbrt-v4 does, to
//!   NanoVDB's world box [T(i_min), T(i_max + 1)], and lookups fade toward the background over the half voxel
//!   beyond the last samples (NanoVDB's trilinear sampler).
//!
//! ## Channels
//! - `spectral`: `bins` equal bins over [lambdamin, lambdamax]; radiance in W·m⁻²·sr⁻¹·nm⁻¹ (bin means).
//! - `rgb`: three bands with the CIE 1931 x̄, ȳ, z̄ as weights over 380–780 nm: σ_c is the band's
//!   Planck-mean of σ(λ) at the local temperature (∫σ B w_c / ∫B w_c, so the optically thin limit j_c and the
//!   thick limit j_c/σ_c = the band's blackbody are both exact), j_c = K ∫ j(λ) w_c(λ) dλ with K = 683 lm/W, so radiance comes out as XYZ with Y in cd/m² (pbrt
//!   mode: K = 1: pbrt-v4's film records ∫ L ȳ dλ, not divided by ∫ȳ dλ). Non-negative weights keep every coefficient non-negative.
//!
//! Each channel's XYZ weights ([`FireVolume::channel_xyz`]) turn radiance into absolute XYZ.
//!
//! ## Tables
//! Everything that depends on T alone is tabulated once, in parallel, on a uniform grid of ≤ 0.5 K (at most
//! 65 536 rows up to the dataset's hottest voxel) and interpolated linearly; species tables exist only for
//! species present. The build report lists bytes and seconds per table.

mod basis;
mod bent;
mod build;
mod closed_form;
mod coefficients;
mod diffusion;
mod integrate;
mod kernel;
mod lanes;
mod lattice;
mod lines;
mod looks;
mod march;
mod mip;
mod motion;
mod notes;
pub mod params;
mod parts;
mod point;
mod query;
mod settings;
mod source;
mod subset;
mod tables;

pub use crate::dataset::params::{HostContext, Mode};
pub use closed_form::ClosedForm;
pub use integrate::evaluations_on_this_thread;
use integrate::EVALUATIONS;
pub(crate) use integrate::MAX_STEPS;
pub use integrate::{Event, Integrator, Ray};
use integrate::{Medium, Scratch};
pub(crate) use march::Stepper;
pub(crate) use mip::VoxelEmission;
pub use point::PointCoefficients;
pub use query::{Answer, Want};
use settings::{Emission, Settings};
pub(crate) use source::Source;
pub(crate) use subset::LineChannels;
use tables::SpeciesChannel;

use crate::dataset::{Dataset, Format};
use crate::majorant::MajorantGrid;
use crate::params::{Param, ParamReader};
use crate::spectrum::SpectralGrid;
use crate::Error;
use basis::Basis;
use glam::DVec3;
use std::time::Instant;

/// The largest optical depth a voxel may have: a bound on the work of tracking, far above any fire (the paper's
/// thickest soot is ~10 per voxel).
pub const MAX_OPTICAL_DEPTH_PER_VOXEL: f64 = 1e12;

/// The colour space of a volume's channels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColorMode {
    /// Spectral bins.
    Spectral(SpectralGrid),
    /// CIE XYZ bands.
    Rgb,
}

/// One table the build made.
#[derive(Debug, Clone, PartialEq)]
pub struct TableReport {
    /// What it holds.
    pub name: String,
    /// Bytes.
    pub bytes: usize,
    /// Seconds to build.
    pub seconds: f64,
}

/// What a volume holds beyond absorption ([`FireVolume::features`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Features {
    /// It emits (a temperature or emission grid that reaches emitting values).
    pub emits: bool,
    /// It scatters (σ_s > 0).
    pub scatters: bool,
    /// Its lookups move over the shutter (velocity motion blur).
    pub motion: bool,
    /// Rays bend in it (refraction).
    pub refraction: bool,
    /// It carries embers (opaque moving spheres, not a medium).
    pub embers: bool,
    /// Atomic lines integrated across their profiles (optically thick lines).
    pub thick_lines: bool,
    /// Its smoke's multiple scattering is read as emission (diffusion).
    pub diffusion: bool,
    /// It emits where it may not absorb (an emission grid): Le is undefined there, j is not.
    pub emits_without_absorption: bool,
}

/// A volume's majorant grid ([`FireVolume::majorant_cells`]).
#[derive(Debug, Clone, Copy)]
pub struct MajorantCells<'a> {
    /// The box the cells tile, medium space.
    pub bounds: [DVec3; 2],
    /// A cell's edge per axis (the last cell per axis may be cut by the box).
    pub cell: DVec3,
    /// Cells per axis.
    pub counts: [usize; 3],
    /// Per cell, x fastest, a bound on σ_t (medium units⁻¹).
    pub sigma_t: &'a [f64],
}

/// A fire volume, from parts: the grids it reads, its coefficient model, its majorants, the optional layers the
/// scene asked for, its estimator, and what its build reports.
#[derive(Debug, Clone)]
pub struct FireVolume {
    grids: parts::Grids,
    model: parts::Model,
    bounds: parts::Bounds,
    layers: parts::Layers,
    estimator: parts::Estimator,
    report: parts::Report,
    /// Rays whose tracking stopped at the collision cap (see `integrate::MAX_COLLISIONS`).
    capped: CapCounter,
    #[cfg(test)]
    fault: String,
}

/// A count that clones as its current value (a volume is cloned whole in tests and tools).
#[derive(Debug, Default)]
struct CapCounter(std::sync::atomic::AtomicU64);

impl Clone for CapCounter {
    fn clone(&self) -> Self {
        CapCounter(std::sync::atomic::AtomicU64::new(
            self.0.load(std::sync::atomic::Ordering::Relaxed),
        ))
    }
}

impl FireVolume {
    /// The dataset.
    pub fn dataset(&self) -> &Dataset {
        self.grids.ds()
    }
    /// Calls `f` with the first sample (lattice indices, below 0 where the lattice starts inside the brick) of
    /// each 8³ brick the dataset's grids store, in the table's order.
    pub fn for_each_stored_brick(&self, mut f: impl FnMut([i64; 3])) {
        let topo = self.grids.ds().topology();
        let off = topo.offset();
        topo.for_each_slot(|b, _| {
            f([0, 1, 2].map(|a| (crate::grid::BRICK * b[a]) as i64 - off[a] as i64))
        });
    }
    /// Medium-space bounds rays are clipped to (the dataset's, or pbrt-v4 nanovdb's world box in pbrt mode).
    pub fn bounds(&self) -> [DVec3; 2] {
        self.bounds.clip_box()
    }
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.model.basis().channels()
    }
    /// The colour mode.
    pub fn color_mode(&self) -> ColorMode {
        self.model.basis().mode()
    }
    /// The coefficient mode.
    pub fn mode(&self) -> Mode {
        self.model.mode()
    }
    /// XYZ (Y in cd/m², or pbrt's relative units in pbrt mode) per unit radiance in each channel.
    pub fn channel_xyz(&self) -> Vec<DVec3> {
        self.model.basis().xyz()
    }
    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.estimator.integrator()
    }
    /// Henyey–Greenstein g.
    pub fn g(&self) -> f64 {
        self.model.g()
    }
    /// Whether the host should sample scattering events: scattering is configured and not resolved by
    /// diffusion (where the smoke's scattered light is emission).
    pub fn scatters(&self) -> bool {
        self.layers.diffusion().is_none() && self.model.s().iter().any(|&v| v > 0.0)
    }
    /// March step length, medium units.
    pub fn step_length(&self) -> f64 {
        self.estimator.step()
    }
    /// The tables built (name, bytes, seconds).
    pub fn tables(&self) -> &[TableReport] {
        self.report.tables()
    }
    /// Bytes held by the dataset and tables.
    pub fn bytes(&self) -> usize {
        // (The species line tables are among `tables`, reported as "species X (lines)".)
        self.grids.ds().bytes() + self.report.tables().iter().map(|t| t.bytes).sum::<usize>()
    }
    /// Seconds spent building.
    pub fn build_seconds(&self) -> f64 {
        self.report.build_seconds()
    }
    pub(crate) fn source(&self) -> Option<&Source> {
        self.report.source()
    }
    pub(crate) fn density_channel(&self) -> usize {
        self.grids.density()
    }
    pub(crate) fn temperature_channel(&self) -> Option<usize> {
        self.grids.temperature()
    }
    /// The lowest and highest temperature of the grid (K, after the mapping), if it has one.
    pub fn temperature_range(&self) -> Option<[f64; 2]> {
        let s = self.grids.ds().channels()[self.grids.temperature()?]
            .grid
            .stats();
        Some([s.min as f64, s.max as f64])
    }

    /// What the build found that a user should hear (species whose lines fall outside the channels, flame colours
    /// the model cannot give), one line each.
    pub fn notes(&self) -> &[String] {
        self.report.notes()
    }

    /// The build's thread budget (`threads`; 0: every core).
    pub(crate) fn threads(&self) -> usize {
        self.report.threads()
    }
    /// Bytes of the volume's memory budget (`maxbytes`) left after its grids and tables: what a fire light built
    /// from it may take.
    pub fn spare_bytes(&self) -> u64 {
        self.report.spare()
    }
    /// Whether anything in the volume can emit: some temperature (or constant `Le`) with a non-zero emission
    /// table, or species. A fire light of a volume that cannot emit is refused before it allocates per voxel.
    pub fn can_emit(&self) -> bool {
        !self.grids.species().is_empty()
            || self
                .model
                .j()
                .lanes()
                .iter()
                .any(|lane| lane.iter().any(|&x| x > 0.0))
    }
    /// How many rays' tracking stopped at the collision cap so far (each a ray cut short as if absorbed: a bias
    /// a host should report).
    pub fn capped_rays(&self) -> u64 {
        self.capped.0.load(std::sync::atomic::Ordering::Relaxed)
    }
    /// [`Medium::majorants`] over the volume's bricks with the bounds `sigma` (one per brick).
    pub(super) fn majorants_over(
        &self,
        sigma: &[f64],
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) {
        for seg in self.bounds.majorant().segments(o, d, t0, t1) {
            if !f(seg.t0, seg.t1, sigma[seg.brick]) {
                return;
            }
        }
    }
    /// [`Medium::empty_spans`] over the volume's bricks, `empty` saying which hold nothing (σ = j = 0).
    pub(super) fn empty_spans_over(
        &self,
        empty: &[bool],
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64),
    ) {
        for seg in self.bounds.majorant().segments(o, d, t0, t1) {
            if empty[seg.brick] {
                f(seg.t0, seg.t1);
            }
        }
    }
    /// The density that emits at a sample of soot density `d` and Lescale (or emission grid) value `les`.
    #[inline(always)]
    pub(super) fn emitting<T: std::ops::Mul<Output = T>>(&self, d: T, les: T) -> T {
        if self.grids.emission_grid() {
            les
        } else {
            d * les
        }
    }
    /// Whether `p` can hold medium: inside the clip box and not in an empty brick.
    #[inline]
    pub(crate) fn holds_medium(&self, p: DVec3) -> bool {
        let [m0, m1] = self.bounds.clip_box();
        let empty = self
            .bounds
            .majorant()
            .brick_at(p)
            .is_some_and(|b| self.bounds.brick_empty()[b]);
        !empty && p.cmpge(m0).all() && p.cmple(m1).all()
    }

    #[cfg(test)]
    fn fault_check(&self) {
        if self.fault == "integrate" {
            panic!("fault injection: panic during integration");
        }
    }
    #[cfg(not(test))]
    fn fault_check(&self) {}

    /// The volume's embers, if it has any.
    pub(crate) fn embers(&self) -> Option<&crate::embers::Embers> {
        self.layers.embers()
    }
    /// The temperature (K) whose blackbody a viewer adapts to: the hottest when the colour is the physics',
    /// `None` when it is art-directed (a tint or a colour ramp: meant for a D65 white) or there is no temperature.
    pub fn white_temperature(&self) -> Option<f64> {
        self.temperature_range()
            .map(|[_, hi]| hi)
            .filter(|&t| self.model.physical_colour() && t > 0.0)
    }

    /// What the volume holds beyond absorption — what a host that tracks the medium itself (from its point
    /// coefficients and majorant grid) must handle or refuse.
    pub fn features(&self) -> Features {
        Features {
            emits: self.can_emit(),
            scatters: self.scatters(),
            motion: self.layers.blur().is_some(),
            refraction: self.layers.refraction().is_some(),
            embers: self.layers.embers().is_some(),
            thick_lines: self.layers.lines().is_some(),
            diffusion: self.layers.diffusion().is_some(),
            emits_without_absorption: self.grids.emission_grid(),
        }
    }
    /// The majorant grid a host walks with its own DDA: the box its cells tile, a cell's edge, the cells per
    /// axis and per cell (x fastest) a bound on σ_t over every channel and every point of the cell (and, with
    /// motion blur, over the shutter). A point of the volume's bounds outside the box (pbrt mode's half voxel)
    /// takes the nearest cell's bound.
    pub fn majorant_cells(&self) -> MajorantCells<'_> {
        MajorantCells {
            bounds: self.bounds.majorant().bounds(),
            cell: self.bounds.majorant().cell(),
            counts: self.bounds.majorant().counts(),
            sigma_t: self
                .layers
                .blur()
                .map_or(self.bounds.brick_sigma(), |b| b.brick_sigma()),
        }
    }
    /// The volume's motion blur: the shutter (frames) and the largest displacement (medium units); `None`
    /// without a velocity grid or with the shutter closed.
    pub fn motion_blur(&self) -> Option<([f64; 2], f64)> {
        self.layers.blur().map(|b| (b.shutter(), b.reach()))
    }
    /// σ_a, σ_s and j per channel at medium-space point `p` (zeros outside).
    /// (Atomic lines as their bins' means, thick or not: what a channel's coefficient is.)
    pub fn coefficients(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        Medium::eval(self, p, sa, ss, j);
        if let Some(tl) = self.layers.lines() {
            if let Some(st) = self.grids.ds().stencil_with_margin(p, self.bounds.margin()) {
                let ch = self.grids.ds().channels();
                let value = |k: usize| ch[k].grid.eval(&st) as f64;
                let t = self.grids.temperature().map_or(0.0, value);
                tl.add_boxed(t, &value, sa, j);
            }
        }
    }
}

/// The grids at a point ([`FireVolume::lookup`]).
pub(super) struct Lookup {
    /// Soot density (clamped at 0).
    pub d: f64,
    /// Temperature, K (0 without a temperature grid).
    pub t: f64,
    /// The Lescale or emission grid's value (1 without one).
    pub les: f64,
    /// Whether it emits there (above pbrt mode's 100 K, or any temperature in physical mode).
    pub emits: bool,
}

impl FireVolume {
    /// The grids' values at medium-space point `p` (trilinear or as the dataset interpolates) and the stencil
    /// that read them (for further grids), `None` outside the volume and its margin: what both the bins'
    /// coefficients and the point query read.
    #[inline(always)]
    pub(super) fn lookup(&self, p: DVec3) -> Option<(crate::grid::Stencil, Lookup)> {
        let st = self
            .grids
            .ds()
            .stencil_with_margin(p, self.bounds.margin())?;
        let ch = self.grids.ds().channels();
        let d = ch[self.grids.density()].grid.eval(&st).max(0.0) as f64;
        let t = self
            .grids
            .temperature()
            .map(|i| ch[i].grid.eval(&st) as f64)
            .unwrap_or(0.0);
        let les = self
            .grids
            .lescale()
            .map(|i| ch[i].grid.eval(&st).max(0.0) as f64)
            .unwrap_or(1.0);
        let emits = t > self.model.t_emit() || self.grids.temperature().is_none();
        Some((st, Lookup { d, t, les, emits }))
    }
    /// Whether the march splits steps thicker than `steptau` (pbrt mode): its bias is bounded, and estimates
    /// made from it (the fire light's line) must stay within it.
    pub(crate) fn splits_thick_steps(&self) -> bool {
        self.estimator.step_tau().is_finite()
    }
}

impl Medium for FireVolume {
    fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        crate::majorant::clip_box(
            o,
            d,
            t0,
            t1,
            self.bounds.clip_box()[0],
            self.bounds.clip_box()[1],
        )
    }
    fn step(&self) -> f64 {
        self.estimator.step()
    }
    fn cutoff(&self) -> f64 {
        self.estimator.cutoff()
    }
    fn step_tau(&self) -> f64 {
        self.estimator.step_tau()
    }
    fn eval(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        EVALUATIONS.with(|n| n.set(n.get() + 1));
        let Some((st, Lookup { d, t, les, emits })) = self.lookup(p) else {
            sa.iter_mut()
                .chain(ss.iter_mut())
                .chain(j.iter_mut())
                .for_each(|v| *v = 0.0);
            return;
        };
        let ch = self.grids.ds().channels();
        let loc = self.model.j().locate(t);
        let at = self.model.a_t().map(|tab| (tab, tab.locate(t)));
        for c in 0..sa.len() {
            sa[c] = d * at
                .map(|(tab, l)| tab.at(l, c) as f64)
                .unwrap_or(self.model.a()[c]);
            ss[c] = d * self.model.s()[c];
            j[c] = if emits {
                self.emitting(d, les) * self.model.j().at(loc, c) as f64
            } else {
                0.0
            };
        }
        // The scatter colour: what it does not scatter is absorbed (σ_t kept, so the majorants and the march
        // stand).
        if let Some((k, w)) = self.model.scatter_color() {
            let rgb = k.map(|i| (ch[i].grid.eval(&st) as f64).clamp(0.0, 1.0));
            for c in 0..sa.len() {
                let albedo = w[c][0] * rgb[0] + w[c][1] * rgb[1] + w[c][2] * rgb[2];
                sa[c] += ss[c] * (1.0 - albedo);
                ss[c] *= albedo;
            }
        }
        for sp in self.grids.species() {
            let n = ch[sp.ch()].grid.eval(&st).max(0.0) as f64 * sp.scale();
            if n > 0.0 {
                let l = sp.sigma().locate(t);
                for c in 0..sa.len() {
                    sa[c] += n * sp.sigma().at(l, c) as f64;
                    j[c] += n * sp.j().at(l, c) as f64;
                }
            }
        }
        if let Some(df) = self.layers.diffusion() {
            df.add(p, ss, j);
        }
    }
    fn majorants(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) {
        self.majorants_over(self.bounds.brick_sigma(), o, d, t0, t1, f)
    }
    fn collision_cap_hit(&self) {
        self.capped
            .0
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
    fn empty_spans(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, f: &mut dyn FnMut(f64, f64)) {
        self.empty_spans_over(self.bounds.brick_empty(), o, d, t0, t1, f)
    }
}

/// Per channel, the weights of a scatter colour's r, g, b: the channel itself in rgb mode; in spectral bins the
/// bin means of the smooth rgb→spectrum fits of the three primaries (albedo fits, pbrt-v4's), normalised to sum
/// to 1 at every wavelength — so white is 1 in every bin and any colour in [0, 1]³ an albedo in [0, 1].
fn scatter_weights(basis: &Basis) -> Vec<[f64; 3]> {
    use firemedium_core::rgb_spectrum::{RgbSpectrum, RgbUse};
    if basis.mode() == ColorMode::Rgb {
        return vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let prim = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .map(|rgb| RgbSpectrum::new(rgb, RgbUse::Albedo));
    let part = |k: usize, l: f64| {
        let v = prim.map(|p| p.eval(l).max(1e-12));
        v[k] / (v[0] + v[1] + v[2])
    };
    let per: Vec<Vec<f64>> = (0..3).map(|k| basis.absorb(&|l| part(k, l))).collect();
    (0..basis.channels())
        .map(|c| [per[0][c], per[1][c], per[2][c]])
        .collect()
}

/// The majorant bricks' edge for a dataset: `configured` (8 by default), doubled (up to 256) while the box
/// would hold more than 16 majorant bricks per 8³ brick the dataset stores — a sparse fire in a big box keeps
/// its majorant structures in proportion to its data; a dense one keeps the configured bricks (and so the same
/// results, bit for bit).
fn majorant_brick(configured: usize, topo: &crate::grid::Topology) -> usize {
    let dims = topo.dims();
    let active = topo.active_bricks().max(1);
    let mut b = configured.max(1);
    while b < 256 && dims.iter().map(|n| n.div_ceil(b)).product::<usize>() > 16 * active {
        b *= 2;
    }
    b
}

#[cfg(test)]
pub(crate) mod tests;
