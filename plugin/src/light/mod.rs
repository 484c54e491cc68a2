//! The fire light (the thesis's "fire light shader"): the fire as a light source its surroundings are lit by,
//! importance-sampled as in Selle's CS348B project — a piecewise-constant 3D pdf over voxels, proportional to
//! each voxel's emitted power, sampled by inversion of Pr(z), Pr(y | z), Pr(x | z, y), then a point uniform in
//! the chosen voxel. Only non-zero voxels are stored.
//!
//! ## Weights
//! A voxel's weight is its emission at the voxel centre, either `power` (∫ j dλ over the volume's bins, the
//! default: 0.4–0.7 % lower error on the default scene, docs/results/log.md) or `luminance` (Σ_c j_c Y_c). The light's total power
//! is 4π V Σ ∫ j dλ over the **whole** spectrum (W) — soot ∫ κ(λ) B(T, λ) dλ over 10 nm–1 mm, lines summed —
//! and 4π V Σ_c j_c Y_c over the bins (lm). Medium units are taken as metres.
//!
//! ## Densities and their use
//! - `pdf(x)`: per unit medium-space volume, w_v / (W V_voxel) in the voxel holding x.
//! - `pdf_direction(o, ω)`: the solid-angle density of the sampled point's direction seen from o,
//!   ∫ pdf(o + s ω̂) s² ds along the whole ray (a per-voxel walk: exact for the piecewise-constant pdf).
//! - A host estimates the fire's light at a point p by T(x, p) j(x) G / pdf(x), with G = cosθ_p / |x − p|²
//!   (medium-space distance; the medium transform must be a similarity), and combines it with paths that reach
//!   the fire by themselves through MIS on directions: weight pdf_direction / (pdf_direction + pdf_bsdf) for the
//!   light sample and pdf_bsdf / (pdf_bsdf + pdf_direction) for the emission those paths collect.

use crate::majorant::walk;
use crate::params::choice;
use crate::volume::FireVolume;
use crate::Error;
use glam::DVec3;
use std::sync::Arc;
use std::time::Instant;

/// Voxels per side of the pdf's cells unless a host asks otherwise.
pub const DEFAULT_CELL: usize = 8;

/// How far (relative) the radiance of the line through a copy of the fire may stray from the volume's own
/// march, on the light's rays, for `lineblock` 0 to choose the copy.
pub const BLOCK_BIAS: f64 = 0.005;

/// How far (relative) the X, Y or Z of the line in [`LINE_CHANNELS`] of the bins may stray from the line in all
/// of them, on the light's rays, for `linechannels` 0 to march the few.
pub const CHANNEL_BIAS: f64 = 0.002;

/// The bins the line marches for `linechannels` 0 (one lane of the kernel), where the check allows.
pub const LINE_CHANNELS: usize = 8;

/// The most bricks whose densities the light keeps in a table over the box (16 MB).
const DENSE_BRICKS: usize = 1 << 21;

/// Rays on which a copy's line is checked: from around the fire toward points the light samples.
const BLOCK_RAYS: u64 = 1024;

/// The line estimate's steps across the fire's longest side when `lineblock` is given and `linestep` is 0 (the
/// longest side over this, or the volume's own step if that is longer), and the finest [`LINE_STEPS_TRIED`].
pub const LINE_STEPS: f64 = 64.0;

/// The steps across the fire's longest side `linestep` 0 and `lineblock` 0 try, coarsest first: the first whose
/// line stays within [`BLOCK_BIAS`] of the volume's march on the light's rays is taken (the last unchecked). On
/// issue 29's room at 256³ the 16 steps' line through the copy of 8³ blocks costs half the 64 steps' through 2³
/// blocks, with no more error in the image (docs/results/log.md).
pub const LINE_STEPS_TRIED: [f64; 3] = [16.0, 32.0, LINE_STEPS];

/// How the light estimates the fire's emission along a sampled direction (next-event estimation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LineEstimate {
    /// The coarse march's step, voxels (0: the fire's longest side over [`LINE_STEPS`]); a step no longer than
    /// the volume's own is the volume's march.
    pub step_voxels: f64,
    /// The probability of the correction: with it, the volume's own march too, and the difference divided by
    /// it added (unbiased against the volume's march); 0: the coarse march alone.
    pub correction: f64,
    /// The side of the blocks of the fire's copy the coarse line marches through ([`FireVolume::mip`]): 2, 4 or
    /// 8 voxels; 1, the fire's own voxels; 0, the coarsest copy no coarser than the step whose line stays
    /// within [`BLOCK_BIAS`] of the volume's march on the light's own rays (checked when the light is built).
    pub block: usize,
    /// How many of the spectral bins the coarse line marches, the others following from them
    /// ([`FireVolume::line_channels`]): 2 to 32; at least the volume's bins, all; 0, [`LINE_CHANNELS`] where
    /// the line's X, Y and Z stay within [`CHANNEL_BIAS`] of every bin's on the light's own rays, else all.
    pub channels: usize,
}

impl Default for LineEstimate {
    fn default() -> Self {
        LineEstimate {
            step_voxels: 0.0,
            correction: 0.0,
            block: 0,
            channels: 0,
        }
    }
}

/// One brick's part of the light's build: its (W, lm, mean extinction) and its voxels' weights, if any emits.
type BrickWeights = ((f64, f64, f64), Option<Box<[f32; 512]>>);

/// The share of a voxel's weight the `escaping` weighting keeps however deep it lies (the pdf's support stays
/// the emission's: a voxel the coarse estimate calls opaque is still sampled, rarely).
const ESCAPE_FLOOR: f64 = 0.05;

/// How voxels are weighted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Weighting {
    /// Σ_c j_c Y_c (luminance of the emission).
    Luminance,
    /// ∫ j dλ over the bins.
    Power,
    /// ∫ j dλ times the share of it that leaves the fire: the mean over the six axis directions of e^{−τ} to
    /// the grid's edge, τ from the bricks' mean extinction (a coarse estimate), floored at [`ESCAPE_FLOOR`].
    Escaping,
}

choice!(Weighting { Weighting::Power => "power", Weighting::Luminance => "luminance", Weighting::Escaping => "escaping" });

/// A sampled point of the fire.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightSample {
    /// Medium-space point.
    pub point: DVec3,
    /// Density per unit medium-space volume.
    pub pdf: f64,
}

/// The fire light of one volume.
#[derive(Debug)]
pub struct FireLight {
    vol: Arc<FireVolume>,
    weighting: Weighting,
    dims: [usize; 3],
    voxel: DVec3,
    total: f64,
    /// The bricks the weights cover: the dataset's stored bricks and their neighbours (trilinear emission
    /// reaches a voxel beyond a brick, and the dilation one more), or every brick when a background emits.
    topo: Arc<crate::grid::Topology>,
    /// Voxels per side of the pdf's cells (1, 2, 4 or 8: a brick holds (8 / cell)³ of them).
    cell: usize,
    /// The line estimate's march step (metres; not longer than the volume's: the volume's march) and the
    /// probability of its correction.
    line_step: f64,
    correction: f64,
    /// The fire at the line's resolution, when the line is coarse enough and the volume can be copied so.
    mip: Option<Box<FireVolume>>,
    /// The bins the coarse line marches, when fewer than all (made by the volume it marches: `mip` or `vol`).
    channels: Option<crate::volume::LineChannels>,
    /// With cells of a brick, the pdf's density in each brick of the box (the walk's lattice, x fastest; 0
    /// without weight), so that a direction's density reads one number per brick; empty for smaller cells or
    /// more than [`DENSE_BRICKS`] bricks (the walk then looks the weights up).
    brick_density: Vec<f64>,
    /// Per cell of those bricks, its weight (the sum of its voxels' dilated weights), brick by brick in the
    /// topology's slots ((8 / cell)³ per slot, slot 0: zeros), a brick's cells in x-fastest order.
    weights: Vec<f32>,
    /// The slots of the bricks holding weight, and the running sum of their weights: the pdf's inverse CDF picks
    /// a brick, then a scan of its cells' weights the cell (12 bytes per brick, not per emitting voxel).
    brick_slots: Vec<u32>,
    cdf: Vec<f64>,
    /// How many voxels have weight.
    emitting: usize,
    /// Per slot of `topo`, its brick (so an index in `weights` gives its voxel).
    slot_bricks: Vec<[u32; 3]>,
    /// The voxels' share of `total` (the embers', if any, follow it).
    fire_total: f64,
    /// Per ember, the probability of picking it, and the running sum of the embers' weights from `fire_total`.
    ember_p: Vec<f64>,
    ember_cdf: Vec<f64>,
    power_w: f64,
    power_lm: f64,
    build_seconds: f64,
}

fn first_above(cdf: &[f64], target: f64) -> usize {
    cdf.partition_point(|&c| c <= target)
        .min(cdf.len().saturating_sub(1))
}

/// The error for a fire with nothing to sample.
fn no_emission() -> Error {
    Error::invalid(
        "light",
        "fire",
        "no emitting voxel",
        "a fire with some emission (temperature above 0 K and density or species)",
    )
}

impl FireLight {
    /// Builds the light of `vol` (the light's own parameter, `weighting`, is `luminance` or `power`), with
    /// cells of [`DEFAULT_CELL`] voxels per side.
    pub fn new(vol: Arc<FireVolume>, weighting: Weighting) -> Result<FireLight, Error> {
        Self::with_cell(vol, weighting, DEFAULT_CELL)
    }

    /// As [`new`](Self::new), the pdf piecewise constant over cells of `cell`³ voxels (1, 2, 4 or 8).
    pub fn with_cell(
        vol: Arc<FireVolume>,
        weighting: Weighting,
        cell: usize,
    ) -> Result<FireLight, Error> {
        Self::with(vol, weighting, cell, LineEstimate::default())
    }

    /// As [`with_cell`](Self::with_cell), with the line estimate's settings.
    pub fn with(
        vol: Arc<FireVolume>,
        weighting: Weighting,
        cell: usize,
        line: LineEstimate,
    ) -> Result<FireLight, Error> {
        if !(line.step_voxels >= 0.0 && line.step_voxels.is_finite()) {
            return Err(Error::invalid(
                "light",
                "linestep",
                line.step_voxels.to_string(),
                "a step ≥ 0 voxels (0: the fire's longest side over 16, 32 or 64 steps, checked)",
            ));
        }
        if !(0.0..=1.0).contains(&line.correction) {
            return Err(Error::invalid(
                "light",
                "linecorrection",
                line.correction.to_string(),
                "a probability in [0, 1]",
            ));
        }
        if !matches!(cell, 1 | 2 | 4 | 8) {
            return Err(Error::invalid(
                "light",
                "cell",
                cell.to_string(),
                "1, 2, 4 or 8 voxels per side (a divisor of the 8-voxel brick)",
            ));
        }
        // Built under the volume's thread budget (a host's `--threads` bounds the light's build too).
        let mut light =
            crate::par::with_budget(vol.threads(), || Self::build(vol, weighting, cell))?;
        let v = &light.vol;
        let voxel = v.dataset().voxel_size();
        let longest = (0..3)
            .map(|a| light.dims[a] as f64 * voxel[a])
            .fold(0.0, f64::max);
        light.correction = line.correction;
        light.brick_density = light.dense_bricks();
        if !matches!(line.block, 0 | 1 | 2 | 4 | 8) {
            return Err(Error::invalid(
                "light",
                "lineblock",
                line.block.to_string(),
                "0 (chosen), 1 (the fire's voxels), 2, 4 or 8 voxels per side",
            ));
        }
        let start = Instant::now();
        // The step and the copy: given, or (both 0) the coarsest of the tried steps whose line — through a copy
        // of blocks no larger than about the step, or the fire's own voxels — stays within BLOCK_BIAS of the
        // volume's march on the light's own rays (a step where the fire's own voxels are not tries no copy); the
        // finest is taken unchecked if none does.
        let auto = line.step_voxels == 0.0 && line.block == 0;
        let tried: &[f64] = if auto {
            &LINE_STEPS_TRIED
        } else {
            &[LINE_STEPS]
        };
        let budget = v.spare_bytes().saturating_sub(light.bytes() as u64);
        let mut fine = None;
        // (Each copy built once, whichever steps try it.)
        let mut copies: Vec<(usize, Option<FireVolume>)> = Vec::new();
        for (k, &n) in tried.iter().enumerate() {
            let step = if line.step_voxels > 0.0 {
                line.step_voxels * voxel.min_element()
            } else {
                longest / n
            };
            light.line_step = step.max(v.step_length());
            // (A step no longer than the volume's own: the volume's march, nothing to check.)
            if !(light.line_step > v.step_length()) {
                break;
            }
            let last = k + 1 == tried.len();
            let ratio = light.line_step / voxel.min_element();
            let sizes: &[usize] = match line.block {
                0 => &[8, 4, 2],
                1 => &[],
                f => &[f][..],
            };
            let mut within = |light: &FireLight, m: &FireVolume| {
                let f = *fine.get_or_insert_with(|| light.line_sum(&light.vol, None));
                light.block_bias(m, f).abs() <= BLOCK_BIAS
            };
            // A copy is not asked to do better than the fire's own voxels at the same step: where those are
            // already beyond the bound (the step's own bias), no copy is built or checked at it (but at the last,
            // where one may be taken unchecked).
            let own = (line.block == 0 && !last).then(|| within(&light, v));
            if own == Some(false) {
                continue;
            }
            for &f in sizes {
                if line.block == 0 && (f as f64 > ratio * std::f64::consts::SQRT_2) {
                    continue;
                }
                let k = match copies.iter().position(|c| c.0 == f) {
                    Some(k) => k,
                    None => {
                        // (Within the budget less the copies held.)
                        let held: u64 = copies
                            .iter()
                            .filter_map(|c| c.1.as_ref())
                            .map(|m| m.mip_bytes() as u64)
                            .sum();
                        copies.push((f, coarse::coarse(v, f, budget.saturating_sub(held))));
                        copies.len() - 1
                    }
                };
                let Some(m) = &copies[k].1 else { continue };
                if line.block == 0 && !within(&light, m) {
                    continue;
                }
                // (Its lattice now, for the copy kept: a copy dropped never held one.)
                light.mip = copies.swap_remove(k).1.map(|m| {
                    let held = m.mip_bytes() as u64;
                    Box::new(m.with_lattice(budget.saturating_sub(held)))
                });
                break;
            }
            // No copy at this step: the fire's own voxels, checked unless this is the last step tried — where a
            // volume that bounds its march's bias (pbrt-v4's grids) takes its own march instead of an unchecked
            // line.
            let strict = auto && v.splits_thick_steps();
            if light.mip.is_some() || (last && !strict) || own.unwrap_or_else(|| within(&light, v))
            {
                break;
            }
            if last {
                light.line_step = v.step_length();
            }
        }
        light.channels = light.choose_channels(line.channels)?;
        light.build_seconds += start.elapsed().as_secs_f64();
        Ok(light)
    }

    /// The volume the light belongs to.
    pub fn volume(&self) -> &FireVolume {
        &self.vol
    }
    /// The weighting.
    pub fn weighting(&self) -> Weighting {
        self.weighting
    }
    /// Total emitted power over the whole spectrum, W (pbrt mode: over the bins, relative units).
    pub fn power_w(&self) -> f64 {
        self.power_w
    }
    /// Luminous power over the bins, lm.
    pub fn power_lm(&self) -> f64 {
        self.power_lm
    }
    /// Emitting voxels.
    pub fn voxels(&self) -> usize {
        self.emitting
    }
    /// Bytes held by the distribution.
    pub fn bytes(&self) -> usize {
        self.weights.len() * 4
            + self.brick_slots.len() * 4
            + self.cdf.len() * 8
            + self.slot_bricks.len() * 12
            + self.topo.bytes()
            + self.mip.as_ref().map_or(0, |m| m.mip_bytes())
            + self.channels.as_ref().map_or(0, |c| c.bytes())
            + self.brick_density.len() * 8
    }
    /// Seconds to build.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
}

mod build;
mod coarse;
mod line;
pub mod params;
mod pdf;
#[cfg(test)]
mod tests;
mod weigh;
