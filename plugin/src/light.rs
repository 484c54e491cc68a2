//! The fire light (the thesis's "fire light shader"): the fire as a light source its surroundings are lit by,
//! importance-sampled as in Selle's CS348B project — a piecewise-constant 3D pdf over voxels, proportional to
//! each voxel's emitted power, sampled by inversion of Pr(z), Pr(y | z), Pr(x | z, y), then a point uniform in
//! the chosen voxel. Only non-zero voxels are stored.
//!
//! ## Weights
//! A voxel's weight is its emission at the voxel centre, either `power` (∫ j dλ over the volume's bins, the
//! default: 0.4–0.7 % lower error on the default scene, docs/RESULTS.md) or `luminance` (Σ_c j_c Y_c). The light's total power
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

use crate::blackbody::spectral_radiance_si;
use crate::majorant::walk;
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
/// blocks, with no more error in the image (docs/RESULTS.md).
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

/// One brick's part of the light's build: its (W, lm, mean extinction) and its emitting voxels' (index, weight).
type BrickWeights = ((f64, f64, f64), Vec<(usize, f32)>);

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
        // volume's march on the light's own rays; the finest is taken unchecked if none does.
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
                let bias = light.line_sum(m, Some(light.line_step)) / f - 1.0;
                bias.abs() <= BLOCK_BIAS
            };
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
                        copies.push((f, v.mip(f, budget.saturating_sub(held))));
                        copies.len() - 1
                    }
                };
                let Some(m) = &copies[k].1 else { continue };
                if line.block == 0 && !within(&light, m) {
                    continue;
                }
                light.mip = copies.swap_remove(k).1.map(Box::new);
                break;
            }
            // No copy at this step: the fire's own voxels, checked unless this is the last step tried — where a
            // volume that bounds its march's bias (pbrt-v4's grids) takes its own march instead of an unchecked
            // line.
            let strict = auto && v.splits_thick_steps();
            if light.mip.is_some() || (last && !strict) || within(&light, v) {
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

    /// The bins the coarse line marches (`linechannels`; `None`: all of them).
    fn choose_channels(&self, asked: usize) -> Result<Option<crate::volume::LineChannels>, Error> {
        let c = self.vol.channels();
        if asked == 1 || (asked > 32 && asked < c) {
            return Err(Error::invalid(
                "light",
                "linechannels",
                asked.to_string(),
                "0 (chosen), 2 to 32 bins, or at least the volume's bins (all of them)",
            ));
        }
        // (At the volume's own step the line is the volume's march, every bin.)
        if !(self.line_step > self.vol.step_length()) || asked >= c {
            return Ok(None);
        }
        let target = self.mip.as_deref().unwrap_or(&self.vol);
        let k = if asked == 0 { LINE_CHANNELS } else { asked };
        let Some(lc) = target.line_channels(k) else {
            return Ok(None);
        };
        if asked == 0 && !(self.channel_bias(target, &lc) <= CHANNEL_BIAS) {
            return Ok(None);
        }
        Ok(Some(lc))
    }

    /// The largest relative difference in X, Y or Z between the line of `target` in the bins of `lc` and in all,
    /// in next-event estimation's sum over the light's check rays ([`check_rays`](Self::check_rays)).
    fn channel_bias(&self, target: &FireVolume, lc: &crate::volume::LineChannels) -> f64 {
        let c = target.channels();
        let xyz = target.channel_xyz();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let (mut few, mut all) = (DVec3::ZERO, DVec3::ZERO);
        let sum = |l: &[f64], p: f64| (0..c).map(|k| xyz[k] * (l[k] / p)).sum::<DVec3>();
        for (ray, p) in self.check_rays() {
            target.integrate_stepped_at(&ray, 0.0, self.line_step, &mut l, &mut t);
            all += sum(&l, p);
            if target
                .integrate_channels(lc, &ray, self.line_step, &mut l, &mut t)
                .is_none()
            {
                return f64::INFINITY;
            }
            few += sum(&l, p);
        }
        if all.min_element() > 0.0 {
            (few / all - 1.0).abs().max_element()
        } else {
            f64::INFINITY
        }
    }

    fn build(vol: Arc<FireVolume>, weighting: Weighting, cell: usize) -> Result<FireLight, Error> {
        let start = Instant::now();
        // Nothing to sample: refused before a weight per voxel is allocated (a 16-byte raw file claiming 600³
        // voxels and no temperature built a 3.4 GB light).
        if !vol.can_emit() && vol.embers().is_none_or(|e| e.len() == 0) {
            return Err(no_emission());
        }
        let ds = vol.dataset();
        let dims = ds.dims();
        let voxel = ds.voxel_size();
        let [p0, _] = ds.bounds();
        let c = vol.channels();
        let xyz = vol.channel_xyz();
        let widths: Vec<f64> = match vol.color_mode() {
            crate::volume::ColorMode::Spectral(g) => vec![g.width_nm(); g.count()],
            crate::volume::ColorMode::Rgb => vec![1.0; 3],
        };
        // Full-spectrum power per unit density over T (soot), and per unit N (lines), physical mode only.
        let src = vol.source().cloned();
        let soot_power = |t: f64| -> f64 {
            let Some(s) = &src else { return 0.0 };
            let (lo, hi) = (10e-9f64.ln(), 1e-3f64.ln());
            crate::quadrature::gauss_legendre(
                |u| {
                    let l = u.exp();
                    s.soot.kappa(l * 1e9, 1.0, s.alpha) * spectral_radiance_si(t, l) * l
                },
                lo,
                hi,
                60,
            )
        };
        // The bricks to weigh: the stored ones and their neighbours; all of them if a background emits (a
        // grid whose empty bricks read a non-zero value).
        let stored = ds.topology();
        let background_emits = ds.channels().iter().any(|ch| ch.grid.background() != 0.0);
        let topo = if background_emits {
            crate::grid::Topology::build_offset(dims, stored.offset(), |_| true)
        } else {
            stored
                .spread([0; 3], -1, 1)
                .and_then(|list| crate::grid::Topology::from_bricks(dims, stored.offset(), list))
        }
        .ok_or_else(no_emission)?;
        let topo = Arc::new(topo);
        // Two weights per covered voxel while building (the weights and their dilation), within what the
        // volume's budget (`maxbytes`) leaves after its grids and tables.
        let n = topo.values_len();
        let need = (n as u64).saturating_mul(8);
        if need > vol.spare_bytes() {
            return Err(Error::TooLarge {
                file: "fire light".into(),
                what: format!(
                    "the weights of {} bricks of 8³ voxels",
                    topo.active_bricks()
                ),
                bytes: need,
                cap: vol.spare_bytes(),
            });
        }
        let too_many = || {
            Error::invalid(
                "light",
                "fire",
                format!("{n} voxels"),
                "a fire whose per-voxel weights (8 bytes each) the allocator can hold",
            )
        };
        let mut w = crate::alloc::filled(n, 0f32).ok_or_else(too_many)?;
        let (mut pw, mut plm) = (0.0, 0.0);
        // (Soot power depends on T only: each worker memoises it per 0.5 K.)
        let dch = vol.density_channel();
        let tch = vol.temperature_channel();
        let mut bricks: Vec<[usize; 3]> = Vec::with_capacity(topo.active_bricks());
        let mut slot_bricks = vec![[0u32; 3]; topo.active_bricks() + 1];
        topo.for_each_slot(|b, slot| {
            bricks.push(b);
            slot_bricks[slot] = b.map(|v| v as u32);
        });
        // (Indices into the weights are u32.)
        if n > u32::MAX as usize {
            return Err(too_many());
        }
        // Per brick (independent: each writes its own slot of the weights), in parallel chunks of bricks under the
        // build's thread budget; the power sums are added brick by brick in the bricks' order, so the light is the
        // same on any number of threads.
        let brick_weights = |b: &[usize; 3],
                             memo: &mut std::collections::HashMap<i64, f64>,
                             sa: &mut [f64],
                             ss: &mut [f64],
                             j: &mut [f64],
                             out: &mut Vec<(usize, f32)>|
         -> (f64, f64, f64) {
            let (mut pw, mut plm, mut ext) = (0.0, 0.0, 0.0);
            let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
            for k in span[2].0..span[2].1 {
                for jy in span[1].0..span[1].1 {
                    for i in span[0].0..span[0].1 {
                        let p = p0 + (DVec3::new(i as f64, jy as f64, k as f64) + 0.5) * voxel;
                        vol.coefficients(p, sa, ss, j);
                        if weighting == Weighting::Escaping {
                            ext += (0..c).map(|q| (sa[q] + ss[q]) * widths[q]).sum::<f64>();
                        }
                        let lum: f64 = (0..c).map(|q| j[q] * xyz[q].y).sum();
                        let band: f64 = (0..c).map(|q| j[q] * widths[q]).sum();
                        if !(lum > 0.0 || band > 0.0) {
                            continue;
                        }
                        out.push((
                            topo.index(i, jy, k),
                            match weighting {
                                Weighting::Luminance => lum,
                                Weighting::Power | Weighting::Escaping => band,
                            } as f32,
                        ));
                        plm += lum;
                        pw += match &src {
                            None => band,
                            Some(s) => {
                                let chs = ds.channels();
                                let at = |q: usize| chs[q].grid.at(i as i64, jy as i64, k as i64);
                                let d = at(dch).max(0.0) as f64;
                                let t = tch.map(|q| at(q) as f64).unwrap_or(0.0);
                                let key = (t * 2.0).round() as i64;
                                let soot = *memo
                                    .entry(key)
                                    .or_insert_with(|| soot_power(key as f64 / 2.0));
                                let mut v = d * s.soot_scale * soot;
                                for (e, ch, scale) in &s.species {
                                    let nn = at(*ch).max(0.0) as f64 * scale;
                                    if nn > 0.0 {
                                        v += nn * s.intensity * line_power(e, t);
                                    }
                                }
                                v
                            }
                        };
                    }
                }
            }
            let n = span.iter().map(|s| s.1 - s.0).product::<usize>().max(1) as f64;
            (pw, plm, ext / (n * widths.iter().sum::<f64>()))
        };
        let workers = crate::par::threads(16).min(bricks.len().max(1));
        let chunk = bricks.len().div_ceil(workers).max(1);
        let run = |part: &[[usize; 3]]| {
            let mut memo = std::collections::HashMap::new();
            let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            part.iter()
                .map(|b| {
                    let mut out = Vec::new();
                    let sums = brick_weights(b, &mut memo, &mut sa, &mut ss, &mut j, &mut out);
                    (sums, out)
                })
                .collect::<Vec<_>>()
        };
        let parts: Vec<Vec<BrickWeights>> = if workers <= 1 {
            vec![run(&bricks)]
        } else {
            crate::par::scope(|sc| {
                let handles: Vec<_> = bricks
                    .chunks(chunk)
                    .map(|part| sc.spawn(move || run(part)))
                    .collect();
                handles
                    .into_iter()
                    .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
                    .collect()
            })
        };
        let mut extinction = Vec::with_capacity(bricks.len());
        for ((bpw, bplm, ext), out) in parts.into_iter().flatten() {
            pw += bpw;
            plm += bplm;
            extinction.push(ext);
            for (idx, v) in out {
                w[idx] = v;
            }
        }
        // With trilinear interpolation a voxel whose centre is dark still emits where it borders a bright one
        // (up to half the neighbour's value at the shared face, about 1/8 of it averaged over the voxel): the
        // pdf's support must cover that, or MIS would drop it. Such voxels get 1/8 of their brightest neighbour.
        if ds.interpolation() == crate::grid::Interpolation::Trilinear {
            w = dilate(&w, &topo, &bricks, 0.125).ok_or_else(too_many)?;
        }
        if weighting == Weighting::Escaping {
            let escape =
                escape_fractions(&topo, &bricks, &extinction, voxel * 8.0, vol.spare_bytes())
                    .ok_or_else(too_many)?;
            for (b, f) in bricks.iter().zip(escape) {
                let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
                let slot = topo.index(span[0].0, span[1].0, span[2].0) / 512;
                let keep = (ESCAPE_FLOOR + (1.0 - ESCAPE_FLOOR) * f) as f32;
                w[slot * 512..(slot + 1) * 512]
                    .iter_mut()
                    .for_each(|v| *v *= keep);
            }
        }
        let emitting = w.iter().filter(|&&v| v > 0.0).count();
        // The cells' weights: the voxels' summed per cell (in f64), brick by brick.
        let side = 8 / cell;
        let per = side * side * side;
        let w = if cell == 1 {
            w
        } else {
            let mut cw = crate::alloc::filled(n / 512 * per, 0f32).ok_or_else(too_many)?;
            for (slot, ws) in w.chunks_exact(512).enumerate() {
                let mut sums = [0f64; 512];
                for (l, &v) in ws.iter().enumerate() {
                    if v > 0.0 {
                        let c =
                            (l % 8) / cell + side * ((l / 8 % 8) / cell + side * ((l / 64) / cell));
                        sums[c] += v as f64;
                    }
                }
                for (c, &v) in sums[..per].iter().enumerate() {
                    cw[slot * per + c] = v as f32;
                }
            }
            cw
        };
        let vv = voxel.x * voxel.y * voxel.z;
        let power_w = 4.0 * std::f64::consts::PI * vv * pw;
        let power_lm = 4.0 * std::f64::consts::PI * vv * plm;
        // The bricks holding weight and their CDF (a cell's weights lie in its brick's slot, those outside the
        // grid's dims 0).
        let (mut brick_slots, mut cdf) = (Vec::new(), Vec::new());
        let mut total = 0.0;
        for b in &bricks {
            let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
            let slot = topo.index(span[0].0, span[1].0, span[2].0) / 512;
            let ws = &w[slot * per..(slot + 1) * per];
            let sum: f64 = ws.iter().map(|&v| v as f64).sum();
            if sum > 0.0 {
                total += sum;
                brick_slots.push(slot as u32);
                cdf.push(total);
            }
        }
        // The embers, by the same measure: an ember is a Lambertian sphere, π r² L per steradian on average, the
        // power j V of a voxel — in the voxels' units, divided by a voxel's volume.
        let fire_total = total;
        let (mut power_w, mut power_lm) = (power_w, power_lm);
        let (mut ember_w, mut ember_cdf) = (Vec::new(), Vec::new());
        if let Some(em) = vol.embers() {
            let n = em.len();
            ember_w = crate::alloc::filled(n, 0.0).ok_or_else(too_many)?;
            ember_cdf = crate::alloc::filled(n, 0.0).ok_or_else(too_many)?;
            let intensity = src.as_ref().map_or(1.0, |s| s.intensity);
            let eps = em.emissivity();
            let mut l = vec![0.0; c];
            for i in 0..n {
                em.radiance(i, 0.0, &mut l);
                let r = em.radius(i);
                let area = std::f64::consts::PI * r * r;
                let lum: f64 = (0..c).map(|q| l[q] * xyz[q].y).sum();
                let band: f64 = (0..c).map(|q| l[q] * widths[q]).sum();
                ember_w[i] =
                    area * match weighting {
                        Weighting::Luminance => lum,
                        Weighting::Power | Weighting::Escaping => band,
                    } / vv;
                total += ember_w[i];
                ember_cdf[i] = total;
                power_lm += 4.0 * std::f64::consts::PI * area * lum;
                power_w += intensity
                    * firemedium_core::ember::radiated_power(eps, r, em.temperature(i, 0.0));
            }
        }
        if !(total > 0.0) {
            return Err(no_emission());
        }
        let ember_p = ember_w.iter().map(|w| w / total).collect();
        Ok(FireLight {
            vol,
            weighting,
            dims,
            voxel,
            total,
            topo,
            cell,
            line_step: 0.0,
            correction: 0.0,
            mip: None,
            channels: None,
            brick_density: Vec::new(),
            weights: w,
            emitting,
            cdf,
            slot_bricks,
            brick_slots,
            fire_total,
            ember_p,
            ember_cdf,
            power_w,
            power_lm,
            build_seconds: start.elapsed().as_secs_f64(),
        })
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
    /// The table of [`brick_density`](Self::brick_density): each brick holding weight's density, as the walk of
    /// [`voxel_direction`](Self::voxel_direction) computes it.
    fn dense_bricks(&self) -> Vec<f64> {
        let off = self.topo.offset();
        let counts = [0, 1, 2].map(|a| (self.dims[a] + off[a]).div_ceil(crate::grid::BRICK));
        let n = counts.iter().try_fold(1usize, |a, &c| a.checked_mul(c));
        let Some(n) = n.filter(|&n| self.cell == crate::grid::BRICK && n <= DENSE_BRICKS) else {
            return Vec::new();
        };
        let mut table = vec![0.0; n];
        let density = self.density_of_cells();
        for &slot in &self.brick_slots {
            let q = self.slot_bricks[slot as usize].map(|v| v as usize);
            let w = self.cell_weight(q);
            if let Some(d) = table.get_mut(q[0] + counts[0] * (q[1] + counts[1] * q[2])) {
                *d = if w > 0.0 { density(q, w) } else { 0.0 };
            }
        }
        table
    }
    /// The pdf's density inside cell `q` (of the lattice shifted by the topology's offset) of weight `w`: a whole
    /// cell's is its weight times one factor; cells cut by the grid's edges hold theirs over less.
    fn density_of_cells(&self) -> impl Fn([usize; 3], f64) -> f64 + '_ {
        let off = self.topo.offset();
        let dims_v = [0, 1, 2].map(|a| self.dims[a] + off[a]);
        let c = self.cell as f64;
        let whole = 1.0 / (self.total * c * c * c * self.voxel.x * self.voxel.y * self.voxel.z);
        move |q, w| {
            let inside =
                (0..3).all(|a| q[a] * self.cell >= off[a] && (q[a] + 1) * self.cell <= dims_v[a]);
            if inside {
                w * whole
            } else {
                self.cell_density(w, self.cell_box(q).1)
            }
        }
    }
    /// The side of the blocks the line estimate marches through, voxels (1: the fire's own).
    pub fn line_block(&self) -> usize {
        self.mip.as_ref().map_or(1, |m| {
            (m.dataset().voxel_size().x / self.vol.dataset().voxel_size().x).round() as usize
        })
    }
    /// How many of the volume's channels the line marches (all of them, or the few the others follow from).
    pub fn line_channels(&self) -> usize {
        self.channels
            .as_ref()
            .map_or(self.vol.channels(), |c| c.count())
    }
    /// Seconds to build.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }

    /// Samples a point from six uniform numbers (the first chooses the voxel — or ember — by its weight, the
    /// last three place the point in it), at time 0.
    pub fn sample(&self, u: [f64; 6]) -> LightSample {
        self.sample_at(u, 0.0)
    }
    /// As [`sample`](Self::sample) at `time` (frames: where the embers are then; the voxels do not move).
    pub fn sample_at(&self, u: [f64; 6], time: f64) -> LightSample {
        let target = u[0] * self.total;
        if target >= self.fire_total && !self.ember_cdf.is_empty() {
            if let Some(em) = self.vol.embers() {
                let i = first_above(&self.ember_cdf, target);
                let point = em.sample_ball(i, [u[3], u[4], u[5]], time);
                return LightSample {
                    point,
                    pdf: self.pdf_at(point, time),
                };
            }
        }
        let target = target.min(self.fire_total * (1.0 - f64::EPSILON));
        let m = first_above(&self.cdf, target);
        let slot = self.brick_slots[m] as usize;
        // Within the brick: the first cell whose running weight passes what is left of the target (the last
        // weighted one if rounding leaves some over).
        let per = self.per_brick();
        let ws = &self.weights[slot * per..(slot + 1) * per];
        let mut rest = target - if m > 0 { self.cdf[m - 1] } else { 0.0 };
        let mut c = ws.iter().rposition(|&v| v > 0.0).unwrap_or(0);
        for (q, &v) in ws.iter().enumerate() {
            if v > 0.0 {
                if rest < v as f64 {
                    c = q;
                    break;
                }
                rest -= v as f64;
            }
        }
        let side = 8 / self.cell;
        let b = self.slot_bricks[slot];
        let q = [c % side, (c / side) % side, c / (side * side)];
        let (lo, n) = self.cell_box([0, 1, 2].map(|a| b[a] as usize * side + q[a]));
        let [p0, _] = self.vol.dataset().bounds();
        let u = DVec3::new(u[3], u[4], u[5]);
        let point = p0
            + (DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64)
                + u * DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64))
                * self.voxel;
        LightSample {
            point,
            pdf: self.cell_density(ws[c] as f64, n) + self.ember_density(point, time),
        }
    }

    /// Cells per brick.
    fn per_brick(&self) -> usize {
        let side = 8 / self.cell;
        side * side * side
    }

    /// The voxels of cell `q` (on the lattice of cells shifted by the topology's offset) inside the grid: its
    /// first voxel and its extent per axis (cells at the grid's edges are cut by it).
    fn cell_box(&self, q: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let off = self.topo.offset();
        let lo = [0, 1, 2].map(|a| (q[a] * self.cell).max(off[a]) - off[a]);
        let hi = [0, 1, 2].map(|a| ((q[a] + 1) * self.cell).min(self.dims[a] + off[a]) - off[a]);
        (lo, [0, 1, 2].map(|a| hi[a].saturating_sub(lo[a])))
    }

    /// The density per unit volume inside a cell of weight `w` and extent `n` voxels.
    fn cell_density(&self, w: f64, n: [usize; 3]) -> f64 {
        let cells = (n[0] * n[1] * n[2]) as f64;
        if !(w > 0.0 && cells > 0.0) {
            return 0.0;
        }
        w / (self.total * cells * self.voxel.x * self.voxel.y * self.voxel.z)
    }

    /// The weight of cell `q` (shifted lattice), 0 outside the stored bricks.
    fn cell_weight(&self, q: [usize; 3]) -> f64 {
        let side = 8 / self.cell;
        let slot = self.topo.slot(q.map(|v| v / side));
        let l = q[0] % side + side * (q[1] % side + side * (q[2] % side));
        self.weights
            .get(slot * self.per_brick() + l)
            .copied()
            .unwrap_or(0.0) as f64
    }

    /// The embers' part of the density per unit volume at `p` and `time`.
    fn ember_density(&self, p: DVec3, time: f64) -> f64 {
        let mut d = 0.0;
        if let Some(em) = self.vol.embers().filter(|_| !self.ember_p.is_empty()) {
            em.containing(p, time, &mut |i| {
                let r = em.radius(i);
                d += self.ember_p[i] / (4.0 / 3.0 * std::f64::consts::PI * r * r * r);
            });
        }
        d
    }

    /// Density of a medium-space point, per unit volume (embers at time 0).
    pub fn pdf(&self, p: DVec3) -> f64 {
        self.pdf_at(p, 0.0)
    }
    /// As [`pdf`](Self::pdf) at `time` (frames).
    pub fn pdf_at(&self, p: DVec3, time: f64) -> f64 {
        let embers = self.ember_density(p, time);
        let [p0, p1] = self.vol.dataset().bounds();
        if !(p.cmpge(p0).all() && p.cmplt(p1).all()) {
            return embers;
        }
        let f = ((p - p0) / self.voxel).floor();
        let off = self.topo.offset();
        let q = [0, 1, 2]
            .map(|a| ((f[a].max(0.0) as usize).min(self.dims[a] - 1) + off[a]) / self.cell);
        self.cell_density(self.cell_weight(q), self.cell_box(q).1) + embers
    }

    /// Solid-angle density of the direction `d` from `o`: ∫ pdf(o + s d̂) s² ds over s ≥ 0 (embers at time 0).
    pub fn pdf_direction(&self, o: DVec3, d: DVec3) -> f64 {
        self.pdf_direction_at(o, d, 0.0)
    }
    /// As [`pdf_direction`](Self::pdf_direction) at `time` (frames).
    pub fn pdf_direction_at(&self, o: DVec3, d: DVec3, time: f64) -> f64 {
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && o.is_finite()) {
            return 0.0;
        }
        let dn = d / len;
        let embers = match self.vol.embers().filter(|_| !self.ember_p.is_empty()) {
            Some(em) => em.chord_moment(o, dn, time, &self.ember_p),
            None => 0.0,
        };
        self.voxel_direction(o, dn) + embers
    }
    /// The line estimate's march step, metres.
    pub fn line_step(&self) -> f64 {
        self.line_step
    }

    /// The fire's emitted radiance `l` and transmittance `t` along `ray` at `time`, as next-event estimation
    /// takes them along a sampled direction: the volume's march at the light's coarser step, and with
    /// probability `linecorrection` also at the volume's own step, the difference over that probability added
    /// (the expectation is then the volume's own march: unbiased against what a camera ray sees). A light whose
    /// step is the volume's — or a volume that tracks — integrates as the volume does. Returns the exit
    /// parameter.
    pub fn integrate_at(
        &self,
        ray: &crate::volume::Ray,
        time: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        let v = &*self.vol;
        if !(self.line_step > v.step_length()) {
            return v.integrate_at(ray, time, l, t);
        }
        let target = self.mip.as_deref().unwrap_or(v);
        let few = self
            .channels
            .as_ref()
            .and_then(|lc| target.integrate_channels(lc, ray, self.line_step, l, t));
        let te =
            few.unwrap_or_else(|| target.integrate_stepped_at(ray, time, self.line_step, l, t));
        let q = self.correction;
        if q > 0.0 {
            // (Its own random number: the march's jitter comes from the ray's seed.)
            let u = crate::rng::Rng::new(ray.seed ^ 0x6c62_272e_07bb_0142).next_f64();
            if u < q {
                // (On the stack for up to 64 channels: no allocation per corrected sample.)
                let c = l.len();
                let (mut stack, mut heap) = ([0f64; 128], Vec::new());
                let fine = if 2 * c <= stack.len() {
                    &mut stack[..2 * c]
                } else {
                    heap.resize(2 * c, 0.0);
                    &mut heap[..]
                };
                let (lf, tf) = fine.split_at_mut(c);
                v.integrate_at(ray, time, lf, tf);
                for k in 0..c {
                    l[k] += (lf[k] - l[k]) / q;
                    t[k] += (tf[k] - t[k]) / q;
                }
            }
        }
        te
    }

    /// The relative difference between the line through the copy `m` and the volume's own march, in next-event
    /// estimation's sum over [`BLOCK_RAYS`] rays from a sphere around the fire toward points this light samples
    /// (each line over the density of its direction).
    #[cfg(test)]
    fn block_bias(&self, m: &FireVolume) -> f64 {
        self.line_sum(m, Some(self.line_step)) / self.line_sum(&self.vol, None) - 1.0
    }

    /// Next-event estimation's sum of the lines' radiance (every bin) over the densities of their directions, on
    /// the [`check_rays`](Self::check_rays): through `m` at `step`, or (None) the volume's own march. NaN or ∞
    /// where nothing is seen (no check passes).
    fn line_sum(&self, m: &FireVolume, step: Option<f64>) -> f64 {
        let c = m.channels();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let mut sum = 0.0;
        for (ray, p) in self.check_rays() {
            match step {
                Some(s) => m.integrate_stepped_at(&ray, 0.0, s, &mut l, &mut t),
                None => m.integrate_at(&ray, 0.0, &mut l, &mut t),
            };
            sum += l.iter().sum::<f64>() / p;
        }
        if step.is_none() && !(sum > 0.0) {
            return f64::NAN;
        }
        sum
    }

    /// The rays of the line's build-time checks and the density of each one's direction: [`BLOCK_RAYS`] from a
    /// sphere around the fire toward points this light samples (each line over its direction's density is what
    /// next-event estimation adds up, whose mean is the emission over all directions, however the light aims).
    fn check_rays(&self) -> impl Iterator<Item = (crate::volume::Ray, f64)> + '_ {
        let [p0, p1] = self.vol.bounds();
        let (centre, radius) = ((p0 + p1) * 0.5, 0.75 * (p1 - p0).length());
        let mut rng = crate::rng::Rng::new(0x5eed_b10c);
        (0..BLOCK_RAYS).filter_map(move |k| {
            let u = [(); 6].map(|_| rng.next_f64());
            let x = self.sample_at(u, 0.0).point;
            // A uniform direction from the centre places the origin on the sphere.
            let (z, phi) = (
                2.0 * rng.next_f64() - 1.0,
                std::f64::consts::TAU * rng.next_f64(),
            );
            let r = (1.0 - z * z).max(0.0).sqrt();
            let o = centre + DVec3::new(r * phi.cos(), r * phi.sin(), z) * radius;
            let ray = crate::volume::Ray {
                o,
                d: x - o,
                t0: 0.0,
                // (The origin is at least a quarter of the box's diagonal from x and at most 1.25 diagonals from
                // the box's far side: past it by t = 5.)
                t1: 8.0,
                seed: k,
                first: None,
            };
            let p = self.pdf_direction_at(o, ray.d, 0.0);
            (p > 0.0).then_some((ray, p))
        })
    }

    /// The voxels' part of [`pdf_direction`](Self::pdf_direction) along the unit direction `dn`: per cell the
    /// ray crosses, its density × (t₁³ − t₀³) / 3.
    fn voxel_direction(&self, o: DVec3, dn: DVec3) -> f64 {
        let ds = self.vol.dataset();
        let [p0, p1] = ds.bounds();
        // Only the part of the ray inside the grid (cells cut by its edges hold their density over their inside).
        let Some((ta, tb)) = crate::majorant::clip_box(o, dn, 0.0, f64::INFINITY, p0, p1) else {
            return 0.0;
        };
        let mut sum = 0.0;
        // On the lattice of cells and bricks shifted by the topology's offset (the walk's bricks are the
        // weights').
        let off = self.topo.offset();
        let shifted = [
            p0 - DVec3::new(off[0] as f64, off[1] as f64, off[2] as f64) * self.voxel,
            p1,
        ];
        let dims_v = [0, 1, 2].map(|a| self.dims[a] + off[a]);
        // Cells of a brick with the bricks' table: one number per brick.
        if !self.brick_density.is_empty() {
            // (Every brick's term, 0 where it holds no weight: no branch on the density, which changes along
            // the ray too irregularly to predict.)
            for seg in walk(shifted, dims_v, self.cell, o, dn, ta, tb) {
                let d = self.brick_density.get(seg.brick).copied().unwrap_or(0.0);
                sum += d * (seg.t1 * seg.t1 * seg.t1 - seg.t0 * seg.t0 * seg.t0);
            }
            return sum / 3.0;
        }
        let density = self.density_of_cells();
        let cells = |t0: f64, t1: f64, sum: &mut f64| {
            for seg in walk(shifted, dims_v, self.cell, o, dn, t0, t1) {
                let w = self.cell_weight(seg.cell);
                if w > 0.0 {
                    *sum += density(seg.cell, w) * (seg.t1.powi(3) - seg.t0.powi(3)) / 3.0;
                }
            }
        };
        // A fire that fills its box (the weights' bricks at least an eighth of the box's), or cells as large as
        // bricks: one walk over the cells. Otherwise brick by brick, cell by cell only inside bricks that hold
        // weights: a sparse fire in a big box costs its bricks along the ray, not the box's cells.
        let box_bricks = self.topo.bricks().iter().product::<usize>();
        if self.cell == crate::grid::BRICK
            || self.topo.active_bricks().saturating_mul(8) >= box_bricks
        {
            cells(ta, tb, &mut sum);
            return sum;
        }
        for bseg in walk(shifted, dims_v, crate::grid::BRICK, o, dn, ta, tb) {
            if self.topo.slot(bseg.cell) != 0 {
                cells(bseg.t0, bseg.t1, &mut sum);
            }
        }
        sum
    }
}

/// Per brick of `bricks` (whose mean extinctions, m⁻¹, are `ext`), the mean over the six axis directions of
/// e^{−τ} from its centre to the grid's edge, τ summed over the bricks on the way (half its own); bricks not
/// listed hold nothing. `size`: a brick's extent per axis. `None` when the bricks' box (4 bytes each) is larger
/// than `budget` or the allocator refuses it.
fn escape_fractions(
    topo: &crate::grid::Topology,
    bricks: &[[usize; 3]],
    ext: &[f64],
    size: DVec3,
    budget: u64,
) -> Option<Vec<f64>> {
    let nb = topo.bricks();
    let n = nb[0].checked_mul(nb[1])?.checked_mul(nb[2])?;
    if (n as u64).saturating_mul(8) > budget {
        return None;
    }
    let at = |b: [usize; 3]| b[0] + nb[0] * (b[1] + nb[1] * b[2]);
    let mut sigma = crate::alloc::filled(n, 0f32)?;
    for (b, &e) in bricks.iter().zip(ext) {
        sigma[at(*b)] = e as f32;
    }
    // Per axis, the optical depth from each brick's far face to the edge, both ways, by running sums along
    // each line of bricks; e^{−τ} of both directions accumulated per brick.
    let mut sum = crate::alloc::filled(n, 0f32)?;
    for a in 0..3 {
        let (u, v) = ((a + 1) % 3, (a + 2) % 3);
        for i in 0..nb[u] {
            for j in 0..nb[v] {
                let line = |k: usize| {
                    let mut b = [0; 3];
                    (b[a], b[u], b[v]) = (k, i, j);
                    at(b)
                };
                for forward in [true, false] {
                    let mut beyond = 0.0f64;
                    for step in 0..nb[a] {
                        let k = if forward { nb[a] - 1 - step } else { step };
                        let s = sigma[line(k)] as f64 * size[a];
                        sum[line(k)] += (-(beyond + 0.5 * s)).exp() as f32;
                        beyond += s;
                    }
                }
            }
        }
    }
    Some(bricks.iter().map(|b| sum[at(*b)] as f64 / 6.0).collect())
}

/// `max(w, f · max of the 26 neighbours)` per voxel of `bricks` (a separable 3×3×3 max filter over the
/// topology's storage; voxels outside it count as 0, and every voxel a stored weight's dilation reaches is
/// inside it, the bricks around the data being covered). `None` when the allocator refuses the copies.
fn dilate(
    w: &[f32],
    topo: &crate::grid::Topology,
    bricks: &[[usize; 3]],
    f: f32,
) -> Option<Vec<f32>> {
    let dims = topo.dims();
    let mut m = crate::alloc::filled(w.len(), 0f32)?;
    m.copy_from_slice(w);
    let mut src = crate::alloc::filled(w.len(), 0f32)?;
    for axis in 0..3 {
        src.copy_from_slice(&m);
        for b in bricks {
            let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
            for k in span[2].0..span[2].1 {
                for jy in span[1].0..span[1].1 {
                    for i in span[0].0..span[0].1 {
                        let v = [i, jy, k];
                        let idx = topo.index(i, jy, k);
                        let mut out = m[idx];
                        if v[axis] > 0 {
                            let mut q = v;
                            q[axis] -= 1;
                            out = out.max(src[topo.index(q[0], q[1], q[2])]);
                        }
                        if v[axis] + 1 < dims[axis] {
                            let mut q = v;
                            q[axis] += 1;
                            out = out.max(src[topo.index(q[0], q[1], q[2])]);
                        }
                        m[idx] = out;
                    }
                }
            }
        }
    }
    Some(w.iter().zip(&m).map(|(&a, &b)| a.max(f * b)).collect())
}

/// Full line emission per unit number density, W·sr⁻¹ (all shipped lines of `e` at T).
fn line_power(e: &crate::species::Element, t: f64) -> f64 {
    use crate::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT};
    if !(t > 0.0) {
        return 0.0;
    }
    let kt = BOLTZMANN * t;
    let z = e.partition_function(t);
    e.lines()
        .iter()
        .map(|l| {
            PLANCK * SPEED_OF_LIGHT / (4.0 * std::f64::consts::PI * l.lambda_nm * 1e-9)
                * l.a_ki
                * l.g_k as f64
                * (-l.e_k / kt).exp()
                / z
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;
    use crate::rng::Rng;

    fn sphere_fire(n: usize, r: f64, fv: f64, t: f64, extra: Vec<Param>) -> Arc<FireVolume> {
        // A uniform sphere of grey soot (alpha 0, constant n, k) in an n³ grid over [−1, 1]³, nearest lookup.
        let mut dens = Vec::with_capacity(n * n * n);
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                    dens.push(if c(i).powi(2) + c(j).powi(2) + c(k).powi(2) < r * r {
                        fv
                    } else {
                        0.0
                    });
                }
            }
        }
        let mut list = vec![
            Param::floats("density", &dens),
            Param::floats("temperature", &vec![t; n * n * n]),
            Param::int("nx", n as i64),
            Param::int("ny", n as i64),
            Param::int("nz", n as i64),
            Param::point3("p0", [-1.0; 3]),
            Param::point3("p1", [1.0; 3]),
            Param::string("interpolation", "nearest"),
            Param::string("fuel", "custom"),
            Param::floats("fuelnk", &[500.0, 1.6, 0.5]),
            Param::float("alpha", 0.0),
        ];
        list.extend(extra);
        Arc::new(FireVolume::new(&list).unwrap())
    }

    #[test]
    fn sampled_pdf_equals_evaluated_pdf() {
        for cell in [1, 2, 4, 8] {
            let light = FireLight::with_cell(
                sphere_fire(23, 0.8, 1e-6, 1500.0, vec![]),
                Weighting::Luminance,
                cell,
            )
            .unwrap();
            let mut rng = Rng::new(3);
            for _ in 0..20_000 {
                let u = [(); 6].map(|_| rng.next_f64());
                let s = light.sample(u);
                let p = light.pdf(s.point);
                assert!(
                    s.pdf > 0.0 && ((p - s.pdf) / s.pdf).abs() < 1e-5,
                    "cell {cell}: {} vs {p} at {}",
                    s.pdf,
                    s.point
                );
            }
        }
    }

    #[test]
    fn cells_are_sampled_in_proportion_to_their_weights() {
        // The brick CDF then the scan inside the brick: 400 000 samples of a 24³ sphere fire, per cell size;
        // every cell with an expected count of 50 or more is drawn within 5σ of it, none without weight is.
        for cell in [1, 4] {
            let light = FireLight::with_cell(
                sphere_fire(24, 0.8, 1e-6, 1500.0, vec![]),
                Weighting::Power,
                cell,
            )
            .unwrap();
            let n = 400_000;
            let off = light.topo.offset();
            let mut counts = std::collections::HashMap::new();
            let mut rng = Rng::new(11);
            for _ in 0..n {
                let s = light.sample([(); 6].map(|_| rng.next_f64()));
                let v = ((s.point - DVec3::splat(-1.0)) / light.voxel).floor();
                let q = [v.x, v.y, v.z].map(|x| x as usize);
                *counts
                    .entry([0, 1, 2].map(|a| (q[a] + off[a]) / cell))
                    .or_insert(0usize) += 1;
            }
            let mut checked = 0;
            let m = (24 + 8) / cell;
            for k in 0..m {
                for j in 0..m {
                    for i in 0..m {
                        let p = light.cell_weight([i, j, k]) / light.total;
                        let want = p * n as f64;
                        let got = counts.get(&[i, j, k]).copied().unwrap_or(0) as f64;
                        if p == 0.0 {
                            assert_eq!(got, 0.0, "cell {i} {j} {k} has no weight");
                        } else if want >= 50.0 {
                            let sigma = (want * (1.0 - p)).sqrt();
                            assert!(
                                (got - want).abs() < 5.0 * sigma,
                                "cell size {cell}, cell {i} {j} {k}: {got} vs {want}"
                            );
                            checked += 1;
                        }
                    }
                }
            }
            let total: usize = counts.values().sum();
            assert_eq!(total, n);
            assert!(checked > 1000 / (cell * cell * cell), "{checked}");
        }
    }

    #[test]
    fn the_parameter_table_states_the_lights_defaults() {
        let default = |name: &str| {
            crate::volume::params::LIGHT
                .params
                .iter()
                .find(|p| p.name == name)
                .map(|p| p.default)
        };
        assert_eq!(default("cell"), Some(DEFAULT_CELL.to_string().as_str()));
        let line = LineEstimate::default();
        assert_eq!(
            default("linestep"),
            Some(line.step_voxels.to_string().as_str())
        );
        assert_eq!(
            default("linecorrection"),
            Some(line.correction.to_string().as_str())
        );
    }

    #[test]
    fn the_escape_fraction_is_e_to_the_minus_tau_along_the_axes() {
        // A row of four bricks along x (1 m each) with extinctions 0, 1, 2, 0 m⁻¹, one brick thick in y and z:
        // brick 1 sees τ = 0.5 toward −x (its own half), 0.5 + 2 toward +x, 0.5 up, down and sideways.
        let topo = crate::grid::Topology::build_offset([32, 8, 8], [0; 3], |_| true).unwrap();
        let bricks = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]];
        let f =
            escape_fractions(&topo, &bricks, &[0.0, 1.0, 2.0, 0.0], DVec3::ONE, 1 << 20).unwrap();
        let e = |t: f64| (-t).exp();
        let want = [
            (1.0 * 5.0 + e(3.0)) / 6.0,
            (e(0.5) * 5.0 + e(2.5)) / 6.0,
            (e(1.0) * 4.0 + e(2.0) + e(1.0)) / 6.0,
            (5.0 + e(3.0)) / 6.0,
        ];
        for k in 0..4 {
            assert!(
                (f[k] - want[k]).abs() < 1e-6,
                "brick {k}: {} vs {}",
                f[k],
                want[k]
            );
        }
        // A box of bricks larger than the budget is refused, not allocated.
        assert!(escape_fractions(&topo, &bricks, &[0.0; 4], DVec3::ONE, 16).is_none());
    }

    #[test]
    fn escaping_weights_favour_the_voxels_whose_light_leaves() {
        // A thick soot ball (κ ≈ 2.6 m⁻¹, τ ≈ 1.3 per brick of ½ m): the escaping weights, over the power weights, are lower at the
        // centre than near the rim (bricks of 8³ voxels: the rim brick is an outer one on two axes); in a thin ball they are the power weights to within the escape (e^{−τ} ≈ 1).
        let ratio = |fv: f64, v: [usize; 3]| {
            let vol = sphere_fire(32, 0.9, fv, 1500.0, vec![]);
            let p = FireLight::with_cell(vol.clone(), Weighting::Power, 1).unwrap();
            let e = FireLight::with_cell(vol, Weighting::Escaping, 1).unwrap();
            let off = p.topo.offset();
            let q = [0, 1, 2].map(|a| v[a] + off[a]);
            (
                e.cell_weight(q) / p.cell_weight(q),
                e.power_w() / p.power_w(),
            )
        };
        let (centre, same_power) = ratio(3e-7, [16, 16, 16]);
        let (rim, _) = ratio(3e-7, [6, 6, 16]);
        assert_eq!(same_power, 1.0, "the light's power is what it emits");
        assert!(centre < 0.75 * rim, "centre {centre}, rim {rim}");
        assert!(centre >= ESCAPE_FLOOR * 0.999, "{centre}");
        let (thin, _) = ratio(1e-10, [16, 16, 16]);
        assert!((thin - 1.0).abs() < 1e-3, "{thin}");
    }

    #[test]
    fn the_light_is_the_same_on_one_thread_and_on_four() {
        // The weights are built brick by brick in parallel chunks under the volume's `threads`: one thread and
        // four give the same weights, CDF and powers, bit for bit.
        let build = |threads: i64| {
            let vol = sphere_fire(40, 0.9, 1e-6, 1700.0, vec![Param::int("threads", threads)]);
            FireLight::new(vol, Weighting::Power).unwrap()
        };
        let (one, four) = (build(1), build(4));
        assert!(one.voxels() > 20_000);
        assert_eq!(one.weights, four.weights);
        assert_eq!(one.cdf, four.cdf);
        assert_eq!(one.brick_slots, four.brick_slots);
        assert_eq!(
            (one.power_w.to_bits(), one.power_lm.to_bits()),
            (four.power_w.to_bits(), four.power_lm.to_bits())
        );
    }

    #[test]
    fn thin_grey_sphere_radiates_four_kappa_sigma_t4_v() {
        // Optically thin uniform emitter: P = 4 κ σ T⁴ V (shared/data), V the voxelised sphere's volume.
        let (n, fv, t) = (32, 1e-9, 1500.0);
        let vol = sphere_fire(n, 0.8, fv, t, vec![]);
        let light = FireLight::new(vol.clone(), Weighting::Power).unwrap();
        let kappa = vol_kappa(&vol);
        let v = light.voxels() as f64 * (2.0 / n as f64).powi(3);
        let want = 4.0 * kappa * crate::constants::STEFAN_BOLTZMANN * t.powi(4) * v;
        assert!(
            (light.power_w() / want - 1.0).abs() < 0.005,
            "{} W vs 4κσT⁴V = {want} W",
            light.power_w()
        );
    }

    fn vol_kappa(vol: &FireVolume) -> f64 {
        let c = vol.channels();
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        vol.coefficients(DVec3::ZERO, &mut a, &mut s, &mut j);
        a[0]
    }

    #[test]
    fn monte_carlo_power_equals_the_computed_power() {
        // E[L_v(x)/pdf(x)] = Σ_v w_v V: the luminous power from samples within 3σ of the tabulated one.
        // Per cell size: the estimator is unbiased whatever the cells.
        for cell in [1, 8] {
            let vol = sphere_fire(20, 0.9, 1e-7, 1800.0, vec![]);
            let light = FireLight::with_cell(vol.clone(), Weighting::Power, cell).unwrap();
            let xyz = vol.channel_xyz();
            let c = vol.channels();
            let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            let mut rng = Rng::new(9);
            let n = 40_000;
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let smp = light.sample([(); 6].map(|_| rng.next_f64()));
                vol.coefficients(smp.point, &mut a, &mut s, &mut j);
                let lum: f64 =
                    (0..c).map(|q| j[q] * xyz[q].y).sum::<f64>() * 4.0 * std::f64::consts::PI;
                let x = lum / smp.pdf;
                sum += x;
                sum2 += x * x;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            assert!(
                (mean - light.power_lm()).abs() <= 3.0 * se + 1e-9 * mean,
                "{mean} ± {se} vs {}",
                light.power_lm()
            );
        }
    }

    #[test]
    fn the_brick_walk_gives_the_voxel_walks_direction_pdf_on_a_sparse_fire() {
        // A ball of soot written as an OpenVDB file whose active box starts at index 11 (a leaf's voxel 3), so
        // the weights' bricks are offset from the lattice, with a second ball 120 voxels away (empty bricks
        // between them). The direction pdf walked brick by brick equals the plain voxel walk's.
        let ball = |c: i32| -> (
            Vec<crate::dataset::vdb::VdbLeaf>,
            Vec<crate::dataset::vdb::VdbLeaf>,
        ) {
            let (mut d, mut t) = (Vec::new(), Vec::new());
            for l in 0..27 {
                let o = [8 + 8 * (l % 3), 8 + 8 * ((l / 3) % 3), 8 + 8 * (l / 9)].map(|v| v + c);
                let (mut dv, mut tv, mut mask) = (vec![0f32; 512], vec![0f32; 512], [0u64; 8]);
                for i in 0..512 {
                    let p = [
                        o[0] + (i as i32 >> 6),
                        o[1] + ((i as i32 >> 3) & 7),
                        o[2] + (i as i32 & 7),
                    ];
                    let r2: i32 = p.iter().map(|&x| (x - 20 - c) * (x - 20 - c)).sum();
                    if r2 < 81 {
                        (dv[i], tv[i]) = (4e-6, 1600.0);
                        mask[i / 64] |= 1 << (i % 64);
                    }
                }
                d.push((o, mask, dv));
                t.push((o, mask, tv));
            }
            (d, t)
        };
        // Two balls (the weights' bricks an eighth of the box's or fewer: the brick walk) and the first alone
        // (a fire filling its box: one voxel walk).
        for far in [true, false] {
            let (d0, t0) = ball(0);
            let (d1, t1) = if far { ball(120) } else { (vec![], vec![]) };
            let bytes = crate::dataset::vdb::write_sparse(
                &[
                    ("density", [d0, d1].concat()),
                    ("temperature", [t0, t1].concat()),
                ],
                DVec3::ZERO,
                DVec3::splat(0.01),
            );
            let file = std::env::temp_dir()
                .join(format!("firemedium-light-walk-{}.vdb", std::process::id()));
            std::fs::write(&file, bytes).unwrap();
            let vol = Arc::new(
                FireVolume::new(&[
                    Param::string("dataset", &file.to_string_lossy()),
                    Param::string("fuel", "propane"),
                ])
                .unwrap(),
            );
            let _ = std::fs::remove_file(&file);
            for cell in [1, 2, 8] {
                let light = FireLight::with_cell(vol.clone(), Weighting::Power, cell).unwrap();
                assert_ne!(light.topo.offset(), [0, 0, 0]);
                let box_bricks: usize = light.topo.bricks().iter().product();
                assert_eq!(light.topo.active_bricks() * 8 >= box_bricks, !far);
                let ds = light.vol.dataset();
                let [p0, p1] = ds.bounds();
                let mut rng = crate::rng::Rng::new(4);
                let mut checked = 0;
                for _ in 0..300 {
                    let o = p0
                        + (p1 - p0)
                            * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64())
                            * 1.4
                        - (p1 - p0) * 0.2;
                    // Toward one of the balls (centres near 0.205 m and 1.405 m on every axis), within its radius.
                    let c = if far && rng.next_f64() < 0.5 {
                        1.405
                    } else {
                        0.205
                    };
                    let j = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
                    let d = DVec3::splat(c) + j * 0.12 - o;
                    let dn = d.normalize();
                    let mut want = 0.0;
                    // Voxel by voxel, the density at each piece's middle (constant over a voxel for any cell size).
                    for seg in walk(ds.bounds(), light.dims, 1, o, dn, 0.0, f64::INFINITY) {
                        let w = light.pdf(o + dn * (0.5 * (seg.t0 + seg.t1)));
                        want += w * (seg.t1.powi(3) - seg.t0.powi(3)) / 3.0;
                    }
                    let got = light.pdf_direction(o, d);
                    checked += (want > 0.0) as usize;
                    assert!(
                        (got - want).abs() <= 1e-9 * want.max(1e-300),
                        "cell {cell}: {got} vs {want}"
                    );
                }
                assert!(checked > 200, "{checked} rays met the fire");
            }
        }
    }

    #[test]
    fn direction_pdf_integrates_to_one_over_the_sphere() {
        // ∫ pdf_direction dω = 1 for a point outside the fire (all the pdf is seen from there), per cell size.
        for cell in [1, 4] {
            let light = FireLight::with_cell(
                sphere_fire(16, 0.7, 1e-6, 1600.0, vec![]),
                Weighting::Luminance,
                cell,
            )
            .unwrap();
            let o = DVec3::new(0.3, -3.0, 0.2);
            let mut rng = Rng::new(5);
            let n = 200_000;
            let mut sum = 0.0;
            for _ in 0..n {
                let z = 1.0 - 2.0 * rng.next_f64();
                let r = (1.0 - z * z).max(0.0).sqrt();
                let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
                sum += light.pdf_direction(o, DVec3::new(r * phi.cos(), r * phi.sin(), z))
                    * 4.0
                    * std::f64::consts::PI;
            }
            let mean = sum / n as f64;
            assert!((mean - 1.0).abs() < 0.03, "cell {cell}: ∫ pdf dω = {mean}");
            // And it is consistent with point sampling: pdf_direction ≥ pdf(x) s² ds piece for the sampled direction.
            let s = light.sample([0.5; 6]);
            assert!(light.pdf_direction(o, s.point - o) > 0.0);
        }
    }

    #[test]
    fn irradiance_beside_a_fire_equals_brute_force_quadrature() {
        // E_Y(p) = ∫ T(p, x) j_Y(x) cosθ / |x − p|² dV over a smooth, trilinear, optically thick-ish fire
        // (τ ≈ 1 across): the light's estimator against a midpoint quadrature on 4³ points per voxel.
        let n = 10;
        let (mut dens, mut temp) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                    let r2 = c(i).powi(2) + c(j).powi(2) + (c(k) + 0.2).powi(2);
                    dens.push((1.0 - r2 / 0.8).max(0.0) * 2e-7);
                    temp.push(1200.0 + 800.0 * (1.0 - r2 / 2.0).max(0.0));
                }
            }
        }
        let vol = cube_fire(
            n,
            &dens,
            &temp,
            &[
                Param::string("fuel", "propane"),
                Param::float("stepsize", 0.25),
            ],
        );
        let light = FireLight::new(vol.clone(), Weighting::Luminance).unwrap();
        let xyz = vol.channel_xyz();
        let c = vol.channels();
        let p = DVec3::new(1.7, 0.3, -0.4);
        let nrm = DVec3::new(-1.0, 0.0, 0.3).normalize();
        let (mut a, mut s, mut j, mut t) = (vec![0.0; c], vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let mut tau_max = 0.0f64;
        let mut f = |x: DVec3| -> f64 {
            let v = x - p;
            let r2 = v.length_squared();
            let cos = nrm.dot(v) / r2.sqrt();
            if cos <= 0.0 {
                return 0.0;
            }
            vol.coefficients(x, &mut a, &mut s, &mut j);
            if j.iter().all(|&q| q == 0.0) {
                return 0.0;
            }
            let ray = crate::volume::Ray {
                o: p,
                d: v,
                t0: 0.0,
                t1: 1.0,
                seed: 1,
                first: None,
            };
            vol.transmittance(&ray, &mut t);
            tau_max = tau_max.max(-t[c / 2].ln());
            (0..c).map(|q| j[q] * t[q] * xyz[q].y).sum::<f64>() * cos / r2
        };
        // Brute force.
        let m = 4 * n;
        let h = 2.0 / m as f64;
        let mut quad = 0.0;
        for k in 0..m {
            for jy in 0..m {
                for i in 0..m {
                    let x = DVec3::new(i as f64 + 0.5, jy as f64 + 0.5, k as f64 + 0.5) * h - 1.0;
                    quad += f(x) * h * h * h;
                }
            }
        }
        // The light.
        let mut rng = Rng::new(21);
        let ns = 40_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..ns {
            let smp = light.sample([(); 6].map(|_| rng.next_f64()));
            let x = f(smp.point) / smp.pdf;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / ns as f64;
        let se = ((sum2 / ns as f64 - mean * mean).max(0.0) / ns as f64).sqrt();
        assert!(
            tau_max > 0.3,
            "the test fire should shadow itself (τ_max = {tau_max})"
        );
        assert!(
            (mean - quad).abs() <= 3.0 * se,
            "fire light {mean} ± {se} vs quadrature {quad} (rel. σ {})",
            se / mean
        );
    }

    #[test]
    fn a_fire_that_cannot_emit_is_refused_before_its_voxels_are_weighed() {
        // No temperature grid: nothing emits. Refused up front (a 600³ grid of this kind built a 3.4 GB light).
        let vol = FireVolume::new(&[
            Param::floats("density", &[1.0; 8]),
            Param::int("nx", 2),
            Param::int("ny", 2),
            Param::int("nz", 2),
        ])
        .unwrap();
        assert!(!vol.can_emit());
        let e = FireLight::new(Arc::new(vol), Weighting::Power)
            .unwrap_err()
            .to_string();
        assert!(e.contains("no emitting voxel"), "{e}");
        assert!(sphere_fire(8, 0.8, 1e-6, 1500.0, vec![]).can_emit());
    }

    /// A Gaussian ball of soot in a 48³ trilinear grid over [−1, 1]³, thin or thick by `fv`: at 1550 K, or
    /// (`steep`) from 1000 K at its edge to 1700 K at its centre.
    fn ball(fv: f64, steep: bool) -> Arc<FireVolume> {
        let n = 48;
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                    let w = (-(c(i).powi(2) + c(j).powi(2) + c(k).powi(2)) / 0.15).exp();
                    d.push(fv * w);
                    t.push(if steep { 1000.0 + 700.0 * w } else { 1550.0 });
                }
            }
        }
        cube_fire(n, &d, &t, &[])
    }

    /// A trilinear fire over [−1, 1]³ from n³ densities and temperatures (x fastest), with `extra` parameters.
    fn cube_fire(n: usize, d: &[f64], t: &[f64], extra: &[Param]) -> Arc<FireVolume> {
        let mut list = vec![
            Param::floats("density", d),
            Param::floats("temperature", t),
            Param::int("nx", n as i64),
            Param::int("ny", n as i64),
            Param::int("nz", n as i64),
            Param::point3("p0", [-1.0; 3]),
            Param::point3("p1", [1.0; 3]),
        ];
        list.extend_from_slice(extra);
        Arc::new(FireVolume::new(&list).unwrap())
    }

    #[test]
    fn the_line_marches_a_copy_only_where_it_keeps_to_the_fire() {
        // `lineblock` 0 with a 2-voxel step: the copy of 2³ blocks is checked against the volume's march on the
        // light's rays and kept within 0.5 % — on a fire at one temperature, thin or thick; where the temperature
        // falls 700 K across the ball, a block's one temperature, interpolated between blocks, emits less than
        // its voxels did (emission is convex in T), so the line marches the fire's own voxels. Asked for, the
        // copy is used regardless.
        let line = |block: usize| LineEstimate {
            step_voxels: 2.0,
            correction: 0.0,
            block,
            channels: 0,
        };
        let thin = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(0)).unwrap();
        assert_eq!(thin.line_block(), 2);
        let bias = thin.block_bias(thin.mip.as_deref().unwrap());
        assert!(bias.abs() <= BLOCK_BIAS, "{bias}");
        let thick = FireLight::with(ball(1e-7, false), Weighting::Power, 8, line(0)).unwrap();
        assert_eq!(thick.line_block(), 2);
        let c = thick.vol.channels();
        let (mut l, mut tr) = (vec![0.0; c], vec![0.0; c]);
        let centre = crate::volume::Ray {
            o: DVec3::new(-2.0, 0.0, 0.0),
            d: DVec3::X,
            t0: 0.0,
            t1: 4.0,
            seed: 1,
            first: None,
        };
        thick.vol.integrate_at(&centre, 0.0, &mut l, &mut tr);
        assert!(tr[c / 2] < 0.7, "the thick ball lets {} through", tr[c / 2]);
        let steep = FireLight::with(ball(1e-9, true), Weighting::Power, 8, line(0)).unwrap();
        assert_eq!(steep.line_block(), 1);
        let forced = FireLight::with(ball(1e-9, true), Weighting::Power, 8, line(2)).unwrap();
        assert_eq!(forced.line_block(), 2);
        let bias = forced.block_bias(forced.mip.as_deref().unwrap());
        assert!(bias < -BLOCK_BIAS, "the steep fire's copy strays: {bias}");
        // The light's memory counts the copy.
        assert!(forced.bytes() > steep.bytes() + forced.mip.as_ref().unwrap().mip_bytes() / 2);
        // The volume's own voxels when asked, and no block size but 0, 1, 2, 4 and 8.
        let own = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(1)).unwrap();
        assert_eq!(own.line_block(), 1);
        let e = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(3))
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("lineblock") && e.contains('3'), "{e}");
    }

    #[test]
    fn the_line_takes_the_coarsest_step_that_keeps_to_the_fire() {
        // `linestep` and `lineblock` 0: 16, 32 or 64 steps across the fire, the coarsest whose line stays within
        // 0.5 % of the volume's march on the light's rays; the finest unchecked where none does. Given a block,
        // 64 steps as before.
        let steps = |l: &FireLight| {
            let longest = 2.0;
            (longest / l.line_step()).round() as usize
        };
        // (A thin ball at one temperature: a copy of 4³ blocks at 16 steps; falling 700 K to its rim, the copy
        // strays and the fire's own voxels at 16 steps do not; a thick ball as well: only 64 steps.)
        for (fv, steep, want) in [
            (1e-9, false, (16, 4)),
            (1e-9, true, (16, 1)),
            (1e-7, false, (16, 2)),
            (3e-6, true, (64, 1)),
        ] {
            let l = FireLight::with(
                ball(fv, steep),
                Weighting::Power,
                8,
                LineEstimate::default(),
            )
            .unwrap();
            let bias = l.block_bias(l.mip.as_deref().unwrap_or(&l.vol));
            assert_eq!((steps(&l), l.line_block()), want, "{fv} {steep}");
            assert!(bias.abs() <= BLOCK_BIAS, "{fv} {steep}: {bias}");
        }
        // The thick, steep ball's own voxels at 16 and 32 steps (3 and 1.5 voxels) stray: why 64 were taken.
        for step_voxels in [3.0, 1.5] {
            let coarse = LineEstimate {
                step_voxels,
                block: 1,
                ..LineEstimate::default()
            };
            let l = FireLight::with(ball(3e-6, true), Weighting::Power, 8, coarse).unwrap();
            let bias = l.block_bias(&l.vol);
            assert!(bias.abs() > BLOCK_BIAS, "{step_voxels}: {bias}");
        }
        let given = LineEstimate {
            block: 2,
            ..LineEstimate::default()
        };
        let l = FireLight::with(ball(1e-9, false), Weighting::Power, 8, given).unwrap();
        assert_eq!((steps(&l), l.line_block()), (64, 2));
    }

    #[test]
    fn the_line_marches_a_few_bins_only_where_the_colour_allows() {
        // `linechannels` 0: 8 of the 32 bins where the line's X, Y and Z stay within 0.2 % of every bin's on the
        // light's rays. A ball at one temperature follows exactly (Wien: the logarithm of its ratio to the slab at
        // any temperature is linear in 1/λ), thin or thick; one falling 700 K to its rim mixes temperatures
        // along each line and strays by a few 1e-4; made thick as well (optical depths of ten), by 0.8 %,
        // refused. Asked for, the few bins are marched regardless; 1 is not a count; at least the volume's
        // bins, all of them.
        let line = |channels: usize| LineEstimate {
            step_voxels: 2.0,
            correction: 0.0,
            block: 1,
            channels,
        };
        let bias = |l: &FireLight| l.channel_bias(&l.vol, l.channels.as_ref().unwrap());
        for (fv, steep, most) in [
            (1e-9, false, 1e-6),
            (1e-7, false, 1e-6),
            (1e-9, true, CHANNEL_BIAS),
        ] {
            let l = FireLight::with(ball(fv, steep), Weighting::Power, 8, line(0)).unwrap();
            assert_eq!(l.line_channels(), LINE_CHANNELS, "{fv} {steep}");
            let b = bias(&l);
            assert!(b <= most, "{fv} {steep}: {b}");
        }
        let thick = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(0)).unwrap();
        assert_eq!(thick.line_channels(), 32);
        let forced = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(8)).unwrap();
        assert_eq!(forced.line_channels(), 8);
        assert!(bias(&forced) > CHANNEL_BIAS, "{}", bias(&forced));
        let sixteen = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(16)).unwrap();
        assert_eq!(sixteen.line_channels(), 16);
        assert_eq!(
            FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(64))
                .unwrap()
                .line_channels(),
            32
        );
        let Err(e) = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(1)) else {
            panic!("1 is not a count");
        };
        let e = e.to_string();
        assert!(e.contains("linechannels") && e.contains("2 to 32"), "{e}");
    }
}
