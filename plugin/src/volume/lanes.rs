//! The march's per-sample work in `f32` lanes of [`W`] channels.
//!
//! The straight march (eq. 3) spends its time in two loops over the channels: the coefficients at the sample
//! (σ_t and j from the temperature tables) and the step (e^{−τ}, the emission weight, the transmittance). Here
//! both run over fixed-width arrays of `f32` with no branch per channel — the exponential is a polynomial, the
//! thin-step series a select — so the compiler turns each into vector instructions (8 channels per AVX2
//! instruction in `march_lanes`' AVX2 clone, 4 with the baseline SSE2).
//!
//! **Tables.** The lanes read the volume's own temperature tables ([`TTable`] stores its rows as lanes, padded to
//! a multiple of [`W`] channels), so the march holds no second copy. **Range.** [`LaneTables::build`] refuses
//! (and the volume marches in `f64`) when the largest density, emission scale or species density times the
//! largest coefficient could leave `f32`'s range. **Accuracy** (tested): one step is within 4e-7 relative of
//! the closed form for every τ from 1e-12 to 1e8; the campfire image within 1e-6 of the f64 march
//! (docs/results/log.md).

use super::tables::TTable;
pub(crate) use super::tables::{Lane, W};
use super::FireVolume;

/// The most species the lane march handles (the line data has seven elements).
pub(crate) const MAX_SPECIES: usize = 8;

/// What the lane march needs beyond the volume's tables: σ per unit density in lanes.
#[derive(Debug, Clone)]
pub(crate) struct LaneTables {
    chunks: usize,
    /// σ_a + σ_s per unit density (constant in T), or σ_s alone when σ_a depends on T (`a_t`, rgb physical mode).
    sigma: Vec<Lane>,
    /// The largest σ_t per unit density over channels and temperatures, and per unit number density of each
    /// species: with the sample's densities, a bound on its optical depth per unit length.
    sigma_max: f32,
    species_sigma_max: [f32; MAX_SPECIES],
}

/// The largest magnitude any per-sample product may reach (f32 holds 3.4e38; a step multiplies by a few more
/// factors below 1e6).
const LIMIT: f64 = 1e30;

/// A sample's soot: density, temperature, and the density times the emission scale (0 where it does not emit).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    d: f32,
    t: f32,
    dl: f32,
}

impl Sample {
    /// Density `d`, temperature `t` (K) and the emitting density `dl`.
    pub(crate) fn new(d: f32, t: f32, dl: f32) -> Sample {
        Sample { d, t, dl }
    }
}

impl LaneTables {
    /// The lane march's constants for volume `v` (its tables built, `c` channels), or `None` when a product
    /// could leave `f32`'s range: `dmax`, `dlmax` (the emitting density), `nmax` (per species) the largest values
    /// a lookup can give, `step` the march step.
    pub(crate) fn build(
        v: &FireVolume,
        dmax: f64,
        dlmax: f64,
        nmax: &[f64],
        step: f64,
    ) -> Option<LaneTables> {
        let c = v.model.a().len();
        let chunks = c.div_ceil(W);
        let mut sigma = vec![[0f32; W]; chunks];
        for ch in 0..c {
            let x = if v.model.a_t().is_some() {
                v.model.s()[ch]
            } else {
                v.model.a()[ch] + v.model.s()[ch]
            };
            sigma[ch / W][ch % W] = x as f32;
        }
        // Largest σ_t·step and emission·step per sample: inside the range, or the f64 march.
        let step = step.max(1.0);
        let smax = sigma.iter().flatten().fold(0f32, |m, &x| m.max(x)) as f64
            + v.model.a_t().map_or(0.0, TTable::max);
        let mut species_sigma_max = [0f32; MAX_SPECIES];
        let mut checks = vec![dmax * smax * step, dlmax * v.model.j().max() * step];
        for (sp, &n) in v.grids.species().iter().zip(nmax) {
            let n = n * sp.scale();
            checks.extend([n, n * sp.sigma().max() * step, n * sp.j().max() * step]);
        }
        for (m, sp) in species_sigma_max.iter_mut().zip(v.grids.species()) {
            // (Rounded up, so that the bound stays a bound in f32.)
            *m = (sp.sigma().max() * (1.0 + 1e-6)) as f32;
        }
        let ok = v.grids.species().len() <= MAX_SPECIES
            && checks.iter().all(|x| x.is_finite() && *x < LIMIT);
        ok.then_some(LaneTables {
            chunks,
            sigma,
            sigma_max: (smax * (1.0 + 1e-6)) as f32,
            species_sigma_max,
        })
    }

    /// Lanes per channel set.
    pub(crate) fn chunks(&self) -> usize {
        self.chunks
    }

    /// σ per unit density, in lanes.
    pub(crate) fn sigma(&self) -> &[Lane] {
        &self.sigma
    }
    /// The largest σ_t per unit density (a bound).
    pub(crate) fn sigma_max(&self) -> f32 {
        self.sigma_max
    }
    /// The largest σ per unit number density of each species (bounds).
    pub(crate) fn species_sigma_max(&self) -> [f32; MAX_SPECIES] {
        self.species_sigma_max
    }

    /// Bytes held (the tables are the volume's).
    pub(crate) fn bytes(&self) -> usize {
        self.sigma.len() * std::mem::size_of::<Lane>()
    }

    /// σ_t and j at a sample of volume `v`, with species number densities `n` (m⁻³, one per species).
    #[inline(always)]
    pub(crate) fn coefficients(
        &self,
        v: &FireVolume,
        x: Sample,
        n: &[f32],
        sig: &mut [Lane],
        jj: &mut [Lane],
    ) {
        let Sample { d, t, dl } = x;
        let (j0, j1, fr) = v.model.j().lane_rows(t);
        for k in 0..self.chunks {
            let (s, a, b) = (&self.sigma[k], &j0[k], &j1[k]);
            for w in 0..W {
                sig[k][w] = d * s[w];
                jj[k][w] = dl * (a[w] + fr * (b[w] - a[w]));
            }
        }
        if let Some(tab) = v.model.a_t() {
            let (a0, a1, fr) = tab.lane_rows(t);
            for k in 0..self.chunks {
                for w in 0..W {
                    sig[k][w] += d * (a0[k][w] + fr * (a1[k][w] - a0[k][w]));
                }
            }
        }
        for (sp, &n) in v.grids.species().iter().zip(n) {
            if n > 0.0 {
                let (s0, s1, fr) = sp.sigma().lane_rows(t);
                let (e0, e1, _) = sp.j().lane_rows(t);
                for k in 0..self.chunks {
                    for w in 0..W {
                        sig[k][w] += n * (s0[k][w] + fr * (s1[k][w] - s0[k][w]));
                        jj[k][w] += n * (e0[k][w] + fr * (e1[k][w] - e0[k][w]));
                    }
                }
            }
        }
    }
}

/// e^{x} for x ≤ 0 (Cephes' `expf`: x = n ln 2 + r, |r| ≤ ln2/2, a degree-6 polynomial, 2ⁿ by the exponent
/// bits), within 2 ulp; 0 below −87 (where e^{x} leaves f32's normal range), and for x = −∞. Branch-free and
/// without float→int casts (whose saturation blocks vectorisation): n is rounded by adding 1.5·2²³, which
/// leaves n in the low mantissa bits.
#[inline(always)]
pub(crate) fn exp_neg(x: f32) -> f32 {
    const LOG2E: f32 = std::f32::consts::LOG2_E;
    const C1: f32 = 0.693_359_4;
    const C2: f32 = -2.121_944_4e-4;
    const MAGIC: f32 = 12_582_912.0; // 1.5·2²³: bits 0x4b40_0000 + n for |n| < 2²²
    let xc = x.max(-87.0);
    let big = xc * LOG2E + MAGIC;
    let nf = big - MAGIC;
    let r = xc - nf * C1 - nf * C2;
    let p = ((((1.987_569_1e-4 * r + 1.398_2e-3) * r + 8.333_452e-3) * r + 4.166_579_6e-2) * r
        + 1.666_666_5e-1)
        * r
        + 5.000_000_1e-1;
    let y = p * r * r + r + 1.0;
    // 2ⁿ: (n + 127) << 23, with n = bits(big) − 0x4b40_0000 (n ≥ −126 here, so the exponent is ≥ 1).
    let two_n = f32::from_bits(big.to_bits().wrapping_sub(0x4b40_0000 - 127) << 23);
    // Zero where x < −87 (and −∞), by masking the bits.
    let keep = 0u32.wrapping_sub((x >= -87.0) as u32);
    f32::from_bits((y * two_n).to_bits() & keep)
}

/// One march step of length `delta` through `sig`/`jj` (eq. 3, exact for constant coefficients, as
/// `integrate::march_step`): adds the step's emission to `l`, attenuates `t`; returns the largest transmittance.
#[inline(always)]
pub(crate) fn step(sig: &[Lane], jj: &[Lane], delta: f32, l: &mut [Lane], t: &mut [Lane]) -> f32 {
    let mut tmax = [0f32; W];
    for k in 0..sig.len() {
        let (s, j, lk, tk) = (&sig[k], &jj[k], &mut l[k], &mut t[k]);
        for w in 0..W {
            let tau = s[w] * delta;
            let e = exp_neg(-tau);
            // (1 − e^{−τ})/τ: its series to τ⁵ below τ = 0.1 (remainder τ⁶/5040 < 2e-10), else the quotient
            // (whose cancellation costs at most 6e-7 relative at τ = 0.1); chosen by a bit mask, no branch.
            let series = 1.0
                - tau
                    * (0.5
                        - tau
                            * (1.0 / 6.0 - tau * (1.0 / 24.0 - tau * (1.0 / 120.0 - tau / 720.0))));
            let quot = (1.0 - e) / tau.max(0.1);
            let thin = 0u32.wrapping_sub((tau < 0.1) as u32);
            let g = f32::from_bits((series.to_bits() & thin) | (quot.to_bits() & !thin));
            lk[w] += tk[w] * j[w] * (delta * g);
            tk[w] *= e;
            tmax[w] = if tk[w] > tmax[w] { tk[w] } else { tmax[w] };
        }
    }
    tmax.iter().fold(0f32, |m, &x| if x > m { x } else { m })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_neg_is_within_two_ulp_and_zero_far_out() {
        let mut worst = 0f64;
        let mut x = 0.0f32;
        while x > -87.0 {
            let want = (x as f64).exp();
            let got = exp_neg(x) as f64;
            worst = worst.max((got - want).abs() / want);
            x -= 0.000_37;
        }
        assert!(worst < 2.5e-7, "worst relative error {worst:e}");
        for x in [-87.5f32, -1e8, f32::NEG_INFINITY] {
            assert_eq!(exp_neg(x), 0.0, "x = {x}");
        }
        assert_eq!(exp_neg(0.0), 1.0);
        assert_eq!(exp_neg(-0.0), 1.0);
    }

    #[test]
    fn a_step_matches_the_f64_step_for_every_optical_depth() {
        // One channel per lane slot, τ from 1e-12 to 1e8; the f64 reference is the closed form of a uniform step.
        let taus: Vec<f64> = (-12..=8)
            .flat_map(|e| [1.0, 3.0].map(|m| m * 10f64.powi(e)))
            .collect();
        let chunks = taus.len().div_ceil(W);
        let mut sig = vec![[0f32; W]; chunks];
        let mut jj = vec![[0f32; W]; chunks];
        let delta = 0.37f64;
        for (i, tau) in taus.iter().enumerate() {
            sig[i / W][i % W] = (tau / delta) as f32;
            jj[i / W][i % W] = 0.8;
        }
        let mut l = vec![[0f32; W]; chunks];
        let mut t = vec![[0.5f32; W]; chunks];
        step(&sig, &jj, delta as f32, &mut l, &mut t);
        for i in 0..taus.len() {
            let tau = (sig[i / W][i % W] * delta as f32) as f64;
            let e = (-tau).exp();
            let g = if tau > 0.0 {
                -(-tau).exp_m1() / tau
            } else {
                1.0
            };
            let want_l = 0.5 * 0.8f32 as f64 * delta as f32 as f64 * g;
            let want_t = 0.5 * e;
            let (gl, gt) = (l[i / W][i % W] as f64, t[i / W][i % W] as f64);
            assert!(
                (gl - want_l).abs() <= 4e-7 * want_l,
                "τ {tau:e}: L {gl:e} vs {want_l:e}"
            );
            let tol = if tau < 80.0 { 4e-7 * want_t } else { 1e-37 };
            assert!(
                (gt - want_t).abs() <= tol,
                "τ {tau:e}: T {gt:e} vs {want_t:e}"
            );
        }
    }
}
