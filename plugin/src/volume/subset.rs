//! The fire light's line in a few of the channels (issue 29): where a fire's light is its soot's alone, the
//! line's march computes `k` of the spectral bins (the nodes) and the others follow from them.
//!
//! - **Transmittance, exactly**: σ_c is the density times σ per unit density of channel c, so along any ray
//!   t_c = e^{−σ_c D} with D the column density, which the node of least σ gives. That node is also the
//!   channel whose transmittance stays highest, so the march of the nodes stops where the march of every
//!   channel stops: the nodes' radiance and transmittance are the whole set's bit for bit (tested).
//! - **Radiance, by interpolation**: between two nodes, linear in 1/λ, of the logarithm of the line's ratio to
//!   the fire's emission spectrum at one temperature (σ_a(λ)·B(λ, T), T the fire's hottest). Under Wien's law
//!   that logarithm is linear in 1/λ for emission at any one temperature, so a line through gas at one
//!   temperature follows exactly whichever T is the reference; a line through several is a mixture whose
//!   logarithm bends by the variance of 1/T along it (and the soot's absorption by a little more). What the
//!   interpolation misses is a bias, measured by the light when it is built and bounded there (`light.rs`,
//!   `CHANNEL_BIAS`).
//!
//! The march's cost is mostly per channel (the table rows, the step's exponential): 8 nodes of 32 bins march
//! in one lane of 8 instead of four.

use super::kernel::Tabs;
use super::lanes::{exp_neg, Lane, W};
use super::march::march_kernel;
use super::tables::TTable;
use super::{ColorMode, FireVolume, Ray};

/// The most nodes a subset marches (the kernel's four lanes of 8).
const MAX_NODES: usize = 32;

/// The channels a line marches and how the others follow from them.
#[derive(Debug, Clone)]
pub(crate) struct LineChannels {
    /// The marched channels (the volume's indices, increasing; the first and last channel among them).
    nodes: Vec<usize>,
    /// The nodes' emission columns and σ per unit density in lanes (the volume's own values).
    j: TTable,
    sigma: Vec<Lane>,
    /// σ per unit density of every channel, and the position among the nodes of the least.
    sig: Vec<f64>,
    least: usize,
    /// Per channel: the position i of the node at or below it (at most the last but one) and its place
    /// between nodes i and i + 1 (0 to 1, in 1/λ).
    below: Vec<usize>,
    frac: Vec<f32>,
    /// σ per unit density in f32, and the reference spectrum (all positive), per channel.
    sig32: Vec<f32>,
    reference: Vec<f32>,
}

impl LineChannels {
    /// How many channels the line marches.
    pub(crate) fn count(&self) -> usize {
        self.nodes.len()
    }
    /// The volume's channels the line marches.
    #[cfg(test)]
    pub(crate) fn nodes(&self) -> &[usize] {
        &self.nodes
    }
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        self.j.bytes() + self.sigma.len() * std::mem::size_of::<Lane>() + self.below.len() * 28
    }
}

impl FireVolume {
    /// The line in `k` of this volume's spectral bins (2 ≤ k ≤ 32, fewer than it has): evenly spread from the
    /// first bin to the last, one of them the bin of least σ. `None` where the light is not the soot's alone
    /// ([`soot_only`](Self::soot_only): species' lines, T-dependent absorption, …), in rgb, or where σ per
    /// unit density vanishes in some channels and not in others (the transmittance would not follow).
    pub(crate) fn line_channels(&self, k: usize) -> Option<LineChannels> {
        let ColorMode::Spectral(grid) = self.model.basis().mode() else {
            return None;
        };
        let c = self.channels();
        if !self.soot_only() || !(2..=MAX_NODES).contains(&k) || k >= c {
            return None;
        }
        let full = self.estimator.lanes()?.sigma().as_flattened();
        let sig: Vec<f64> = (0..c)
            .map(|ch| self.model.a()[ch] + self.model.s()[ch])
            .collect();
        if full.len() < c || !sig.iter().all(|x| x.is_finite() && *x >= 0.0) {
            return None;
        }
        let least = (0..c).min_by(|&a, &b| sig[a].total_cmp(&sig[b]))?;
        if sig[least] == 0.0 && sig.iter().any(|&x| x > 0.0) {
            return None;
        }
        let mut nodes: Vec<usize> = (0..k)
            .map(|i| ((i * (c - 1)) as f64 / (k - 1) as f64).round() as usize)
            .collect();
        if !nodes.contains(&least) {
            // (The ends are nodes, so the least is inside: it takes the place of the nearest inner node.)
            let q = (1..k - 1).min_by_key(|&q| nodes[q].abs_diff(least))?;
            nodes[q] = least;
            nodes.sort_unstable();
        }
        let chunks = k.div_ceil(W);
        let rows = self.model.j().rows();
        let mut v = vec![[0f32; W]; rows * chunks];
        for r in 0..rows {
            for (q, &n) in nodes.iter().enumerate() {
                v[r * chunks + q / W][q % W] = self.model.j().value(r, n);
            }
        }
        let mut sigma = vec![[0f32; W]; chunks];
        for (q, &n) in nodes.iter().enumerate() {
            sigma[q / W][q % W] = full[n];
        }
        let u = |ch: usize| 1.0 / grid.centre(ch);
        let (mut below, mut frac) = (vec![0; c], vec![0f32; c]);
        for ch in 0..c {
            let i = (nodes.partition_point(|&n| n <= ch) - 1).min(k - 2);
            let (a, b) = (nodes[i], nodes[i + 1]);
            below[ch] = i;
            frac[ch] = ((u(ch) - u(a)) / (u(b) - u(a))) as f32;
        }
        // The reference: emission per unit density at the fire's hottest temperature (within the table).
        let hottest = self.temperature_range().map_or(0.0, |r| r[1]);
        let row = ((hottest * self.model.j().inv_dt()).round().max(0.0) as usize).min(rows - 1);
        let reference: Vec<f32> = (0..c).map(|ch| self.model.j().value(row, ch)).collect();
        if !reference.iter().all(|&x| x.is_finite() && x > 0.0) {
            return None;
        }
        let least = nodes.iter().position(|&n| n == least)?;
        Some(LineChannels {
            nodes,
            j: TTable::from_lanes(self.model.j().dt(), chunks, v),
            sigma,
            sig32: sig.iter().map(|&x| x as f32).collect(),
            sig,
            least,
            below,
            frac,
            reference,
        })
    }

    /// The march at `step` (the volume's own where that is longer) of `ray` in the channels of `lc` (made by
    /// this volume), the others following from them: radiance `l` and transmittance `t` for every channel, and
    /// the exit parameter. `None` where the kernel does not take the ray (the caller marches every channel).
    pub(crate) fn integrate_channels(
        &self,
        lc: &LineChannels,
        ray: &Ray,
        step: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> Option<f64> {
        let lt = self.estimator.lanes()?;
        let (c, k) = (lc.below.len(), lc.nodes.len());
        if l.len() != c || t.len() != c {
            return None;
        }
        self.fault_check();
        let step = if step > self.estimator.step() {
            step
        } else {
            self.estimator.step()
        };
        let (mut lk, mut tk) = ([0f64; MAX_NODES], [1f64; MAX_NODES]);
        let tabs = Tabs::subset(&lc.j, &lc.sigma);
        let te = march_kernel(self, lt, Some(tabs), ray, step, &mut lk[..k], &mut tk[..k])?;
        // The column density from the node of least σ; where its light is gone (every σ > 0 then), one at
        // which the least σ's optical depth is 88, past which e^{−τ} is 0 in f32 and the slab opaque.
        let (sl, tl) = (lc.sig[lc.nodes[lc.least]], tk[lc.least]);
        let column = match (sl > 0.0, tl > 0.0) {
            (false, _) => 0.0,
            (true, true) => (-tl.ln() / sl).min(88.0 / sl),
            (true, false) => 88.0 / sl,
        } as f32;
        expand(lc, &lk[..k], column, l, t);
        for (q, &n) in lc.nodes.iter().enumerate() {
            (l[n], t[n]) = (lk[q], tk[q]);
        }
        Some(te)
    }
}

/// Every channel's radiance `l` and transmittance `t` from the nodes' radiance `lk` and the ray's column of
/// soot (`column`, in units of 1/σ): compiled for baseline x86-64 and for AVX2 + FMA (eight channels per
/// instruction), chosen once at run time.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn expand(lc: &LineChannels, lk: &[f64], column: f32, l: &mut [f64], t: &mut [f64]) {
    let c = l
        .len()
        .min(t.len())
        .min(lc.sig32.len())
        .min(lc.reference.len());
    // Per channel: its transmittance e^{−σD}, and in `l` for now the reference along this ray — a uniform slab
    // holding the ray's column of soot at the reference temperature, j/σ·(1 − e^{−σD}), here over D (which the
    // ratios below do not depend on): j where thin, j/(σD) where opaque.
    for ch in 0..c {
        let x = lc.sig32[ch] * column;
        let e = exp_neg(-x);
        // (1 − e^{−x})/x: its series below 0.1 (remainder x⁵/720 < 2e-8), else the quotient.
        let series = 1.0 - x * (0.5 - x * (1.0 / 6.0 - x * (1.0 / 24.0 - x * (1.0 / 120.0))));
        let g = if x < 0.1 { series } else { (1.0 - e) / x };
        t[ch] = e as f64;
        l[ch] = (lc.reference[ch] * g) as f64;
    }
    // Each node's ratio to the slab, and the logarithm of the next one's over it (NaN where either is dark).
    let k = lk.len().min(MAX_NODES);
    let (mut q, mut up) = ([0f32; MAX_NODES], [0f32; MAX_NODES]);
    for p in 0..k {
        let slab = lc
            .nodes
            .get(p)
            .and_then(|&n| l.get(n))
            .copied()
            .unwrap_or(0.0);
        q[p] = if slab > 0.0 {
            (lk[p] / slab) as f32
        } else {
            0.0
        };
    }
    for p in 0..k.saturating_sub(1) {
        up[p] = if q[p] > 0.0 && q[p + 1] > 0.0 {
            (q[p + 1] / q[p]).ln().clamp(-80.0, 80.0)
        } else {
            f32::NAN
        };
    }
    // Between nodes i and i + 1 at place f: the ratio q_i·(q_{i+1}/q_i)^f, or linear where a node is dark.
    for ch in 0..c {
        let i = lc.below[ch].min(MAX_NODES - 2);
        let (qi, qn, d, f) = (q[i], q[i + 1], up[i], lc.frac[ch]);
        let r = if d.is_nan() {
            qi + f * (qn - qi)
        } else {
            qi * exp_neg(f * d)
        };
        l[ch] *= r as f64;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;
    use crate::volume::tests::blob_pair;

    fn rays() -> Vec<Ray> {
        crate::volume::tests::blob_rays(60, 700)
    }

    /// Every channel's line along `rays()` through `v` at twice its step: by the march of all, and by the march
    /// of `lc`'s nodes.
    #[allow(clippy::type_complexity)]
    fn lines(
        v: &FireVolume,
        lc: &LineChannels,
    ) -> Vec<((Vec<f64>, Vec<f64>), (Vec<f64>, Vec<f64>))> {
        let (c, step) = (v.channels(), 2.0 * v.step_length());
        rays()
            .iter()
            .map(|r| {
                let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                let te = v.integrate_stepped_at(r, 0.0, step, &mut l, &mut t);
                let (mut lf, mut tf) = (vec![0.0; c], vec![0.0; c]);
                let tef = v
                    .integrate_channels(lc, r, step, &mut lf, &mut tf)
                    .expect("the kernel takes it");
                assert_eq!(te, tef);
                ((l, t), (lf, tf))
            })
            .collect()
    }

    #[test]
    fn the_nodes_are_the_whole_march_and_the_rest_follow() {
        // 8 of 32 bins on the soot blob (a 2000 K ball beside a 1500 K slab) at twice its step. Thick (as built:
        // optical depths of several) or thin (a fiftieth of the soot): the nodes' radiance and transmittance are
        // the march of every channel bit for bit, and every channel's transmittance follows from the column of
        // soot to f32 rounding. Thin, every other channel's radiance is within 1 % ray by ray and its sum over
        // the rays within 0.2 %; thick, the blue bins where the soot's absorption has a kink (its n, k table) are
        // off by 2–4 % — the light's check refuses the few there (light.rs).
        for (scale, thin) in [(0.02, true), (1.0, false)] {
            let (v, _) = blob_pair(
                &[Param::int("bins", 32), Param::float("sootscale", scale)],
                false,
            );
            let c = v.channels();
            let lc = v.line_channels(8).expect("a soot fire in 32 bins");
            assert_eq!(lc.count(), 8);
            assert_eq!((lc.nodes()[0], lc.nodes()[7]), (0, 31));
            let (mut sums, mut sums_all) = (vec![0.0; c], vec![0.0; c]);
            let mut lit = 0;
            for ((l, t), (lf, tf)) in lines(&v, &lc) {
                for &n in lc.nodes() {
                    assert_eq!((lf[n], tf[n]), (l[n], t[n]), "node {n}");
                }
                let peak = l.iter().fold(0f64, |m, &x| m.max(x));
                lit += (peak > 0.0) as usize;
                for ch in 0..c {
                    assert!(
                        (tf[ch] - t[ch]).abs() < 2e-6,
                        "ch {ch}: {} vs {}",
                        tf[ch],
                        t[ch]
                    );
                    if thin && l[ch] > 1e-3 * peak {
                        let e = lf[ch] / l[ch] - 1.0;
                        assert!(
                            e.abs() < 0.01,
                            "ch {ch}: {} vs {} ({e:+.2e})",
                            lf[ch],
                            l[ch]
                        );
                    }
                    sums[ch] += lf[ch];
                    sums_all[ch] += l[ch];
                }
            }
            assert!(lit > 20, "{lit}");
            let worst = (0..c)
                .map(|ch| (sums[ch] / sums_all[ch] - 1.0).abs())
                .fold(0.0, f64::max);
            if thin {
                assert!(worst < 2e-3, "{worst}");
            } else {
                assert!(worst > 0.02, "{worst}");
            }
        }
    }

    #[test]
    fn only_a_soot_fires_bins_march_in_part() {
        let (v, _) = blob_pair(&[Param::int("bins", 32)], false);
        assert!(v.line_channels(1).is_none() && v.line_channels(33).is_none());
        assert!(v.line_channels(16).is_some());
        let (rgb, _) = blob_pair(&[Param::string("colormode", "rgb")], false);
        assert!(rgb.line_channels(2).is_none(), "rgb");
        let (sodium, _) = blob_pair(&[Param::int("bins", 32)], true);
        assert!(sodium.line_channels(8).is_none(), "an atomic line");
        let (few, _) = blob_pair(&[Param::int("bins", 8)], false);
        assert!(few.line_channels(8).is_none(), "no fewer than its bins");
        // 64 bins: more than the kernel's four lanes hold, but 8 of them are one lane (the others follow, and
        // the nodes are the lane march's, which takes the whole set, to its f32 rounding).
        let (many, _) = blob_pair(
            &[Param::int("bins", 64), Param::float("sootscale", 0.02)],
            false,
        );
        let lc = many.line_channels(8).expect("8 of 64 bins");
        let (step, c) = (2.0 * many.step_length(), 64);
        let mut lit = 0;
        for r in rays() {
            let (mut l, mut t, mut lf, mut tf) =
                (vec![0.0; c], vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            many.integrate_stepped_at(&r, 0.0, step, &mut l, &mut t);
            many.integrate_channels(&lc, &r, step, &mut lf, &mut tf)
                .expect("the kernel takes 8 of 64");
            let peak = l.iter().fold(0f64, |m, &x| m.max(x));
            lit += (peak > 0.0) as usize;
            for ch in 0..c {
                assert!((tf[ch] - t[ch]).abs() < 1e-5, "ch {ch}");
                if l[ch] > 1e-3 * peak {
                    assert!(
                        (lf[ch] / l[ch] - 1.0).abs() < 0.01,
                        "ch {ch}: {} vs {}",
                        lf[ch],
                        l[ch]
                    );
                }
            }
        }
        assert!(lit > 20, "{lit}");
    }
}
