//! Where a pixel's samples fall on the film and what they weigh: pbrt-v4's pixel samples (`independent`, and
//! `stratified` with its `jitter`) and its pixel filters by filter importance sampling (pbrt-v4
//! `src/pbrt/filters.h`, `samplers.h`).
//!
//! A sample u ∈ [0, 1)² of the pixel becomes a film offset p = F⁻¹(u) from the pixel's centre, drawn from the
//! filter f itself: `box` and `triangle` exactly (weight 1), `gaussian`, `mitchell` and `lanczos` from a
//! piecewise-constant table of |f| (32 cells per unit of radius, as pbrt-v4's `FilterSampler`) with weight
//! f(p) / pdf(p). The pixel's value is Σ w L / Σ w (pbrt-v4's `RGBFilm`). Stratified samples take the pixel's
//! strata in a per-pixel random order; without jitter they sit at the strata's centres, so
//! `"stratified" "bool jitter" false "integer xsamples" 1 "integer ysamples" 1` with a box filter traces each
//! pixel's centre.

/// How sample `s` of a pixel chooses its position in the pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Sampler {
    /// Uniform random positions (pbrt-v4's `independent`; the samplers this renderer does not have render so).
    Independent,
    /// `xs` × `ys` strata, visited in a per-pixel random order; jittered within the stratum or at its centre.
    Stratified { xs: usize, ys: usize, jitter: bool },
}

impl Sampler {
    /// The pixel sample of sample `s` in [0, 1)², from the pixel's own `order` hash and the sample's `rng` draws.
    pub fn pixel_sample(&self, s: usize, order: u64, draw: [f64; 2]) -> [f64; 2] {
        match *self {
            Sampler::Independent => draw,
            Sampler::Stratified { xs, ys, jitter } => {
                let n = (xs * ys).max(1);
                let k = permute(s % n, n, order);
                let (i, j) = (k % xs.max(1), k / xs.max(1));
                let (du, dv) = if jitter {
                    (draw[0], draw[1])
                } else {
                    (0.5, 0.5)
                };
                [(i as f64 + du) / xs as f64, (j as f64 + dv) / ys as f64]
            }
        }
    }
}

/// Element `i` of a random permutation of 0..n chosen by `seed` (a bijection: each stratum exactly once per n
/// samples). Cycle-walking over an invertible hash of the next power of two.
fn permute(i: usize, n: usize, seed: u64) -> usize {
    if n <= 1 {
        return 0;
    }
    let bits = usize::BITS - (n - 1).leading_zeros();
    let mask = (1u64 << bits) - 1;
    let mut x = i as u64;
    loop {
        // An invertible mix on `bits` bits: xor-shifts, odd multiplications and xors with the seed, all mod 2^bits.
        for round in 0..3u64 {
            x ^= (seed.rotate_left((round * 21) as u32)) & mask;
            x = x.wrapping_mul(0x9E37_79B9_7F4A_7C15 | 1) & mask;
            x ^= x >> (bits / 2).max(1);
        }
        if (x as usize) < n {
            return x as usize;
        }
    }
}

/// A pbrt-v4 pixel filter, ready to sample.
#[derive(Debug, Clone)]
pub enum Filter {
    /// Constant over [−r, r]² (pbrt-v4's default radius 0.5: the pixel).
    Box { radius: [f64; 2] },
    /// (r − |x|)(r − |y|) over [−r, r]².
    Triangle { radius: [f64; 2] },
    /// Gaussian, Mitchell–Netravali or Lanczos: sampled from a table of |f|.
    Tabulated(Table),
}

/// A filter tabulated for importance sampling: |f| on a grid over [−r, r]², its marginal and conditional CDFs.
#[derive(Debug, Clone)]
pub struct Table {
    radius: [f64; 2],
    f: fn(&Params, f64, f64) -> f64,
    params: Params,
    nx: usize,
    ny: usize,
    /// |f| per cell, rows of nx.
    cells: Vec<f64>,
    /// Per row: the CDF over its cells (nx + 1 entries each).
    cond: Vec<f64>,
    /// The CDF over the rows' sums (ny + 1 entries).
    marg: Vec<f64>,
    /// ∫ |f| over the domain.
    total: f64,
}

/// The parameters of the tabulated filters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Params {
    pub radius: [f64; 2],
    /// Gaussian σ.
    pub sigma: f64,
    /// Mitchell's B and C.
    pub b: f64,
    pub c: f64,
    /// Lanczos τ.
    pub tau: f64,
}

fn gaussian(p: &Params, x: f64, y: f64) -> f64 {
    let g = |x: f64, s: f64| {
        (-x * x / (2.0 * s * s)).exp() / (2.0 * std::f64::consts::PI * s * s).sqrt()
    };
    let s = p.sigma;
    (g(x, s) - g(p.radius[0], s)).max(0.0) * (g(y, s) - g(p.radius[1], s)).max(0.0)
}

fn mitchell(p: &Params, x: f64, y: f64) -> f64 {
    let (b, c) = (p.b, p.c);
    let m = |x: f64| {
        let x = x.abs();
        if x <= 1.0 {
            ((12.0 - 9.0 * b - 6.0 * c) * x.powi(3)
                + (-18.0 + 12.0 * b + 6.0 * c) * x * x
                + (6.0 - 2.0 * b))
                / 6.0
        } else if x <= 2.0 {
            ((-b - 6.0 * c) * x.powi(3)
                + (6.0 * b + 30.0 * c) * x * x
                + (-12.0 * b - 48.0 * c) * x
                + (8.0 * b + 24.0 * c))
                / 6.0
        } else {
            0.0
        }
    };
    m(2.0 * x / p.radius[0]) * m(2.0 * y / p.radius[1])
}

fn lanczos(p: &Params, x: f64, y: f64) -> f64 {
    let sinc = |x: f64| {
        if x.abs() < 1e-5 {
            1.0
        } else {
            (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
        }
    };
    let w = |x: f64, r: f64| {
        if x.abs() > r {
            0.0
        } else {
            sinc(x) * sinc(x / p.tau)
        }
    };
    w(x, p.radius[0]) * w(y, p.radius[1])
}

impl Filter {
    /// The filter pbrt-v4 names `ty`, or `None` for a name it does not have.
    pub fn new(ty: &str, p: Params) -> Option<Filter> {
        let f: fn(&Params, f64, f64) -> f64 = match ty {
            "box" => return Some(Filter::Box { radius: p.radius }),
            "triangle" => return Some(Filter::Triangle { radius: p.radius }),
            "gaussian" => gaussian,
            "mitchell" => mitchell,
            "sinc" | "lanczos" => lanczos,
            _ => return None,
        };
        Some(Filter::Tabulated(Table::new(f, p)))
    }

    /// pbrt-v4's default radius of filter `ty` (per axis).
    pub fn default_radius(ty: &str) -> f64 {
        match ty {
            "gaussian" => 1.5,
            "mitchell" | "triangle" => 2.0,
            "sinc" | "lanczos" => 4.0,
            _ => 0.5,
        }
    }

    /// The film offset from the pixel centre for pixel sample `u`, and the sample's weight.
    pub fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        match self {
            Filter::Box { radius } => (
                [
                    (2.0 * u[0] - 1.0) * radius[0],
                    (2.0 * u[1] - 1.0) * radius[1],
                ],
                1.0,
            ),
            Filter::Triangle { radius } => {
                // The tent's inverse CDF on [−1, 1].
                let tent = |u: f64| {
                    if u < 0.5 {
                        -1.0 + (2.0 * u).sqrt()
                    } else {
                        1.0 - (2.0 - 2.0 * u).sqrt()
                    }
                };
                ([tent(u[0]) * radius[0], tent(u[1]) * radius[1]], 1.0)
            }
            Filter::Tabulated(t) => t.sample(u),
        }
    }
}

impl Table {
    fn new(f: fn(&Params, f64, f64) -> f64, params: Params) -> Table {
        let radius = params.radius;
        let nx = ((32.0 * radius[0]).ceil() as usize).clamp(1, 4096);
        let ny = ((32.0 * radius[1]).ceil() as usize).clamp(1, 4096);
        let (cw, ch) = (2.0 * radius[0] / nx as f64, 2.0 * radius[1] / ny as f64);
        let mut cells = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let (x, y) = (
                    -radius[0] + (i as f64 + 0.5) * cw,
                    -radius[1] + (j as f64 + 0.5) * ch,
                );
                cells.push(f(&params, x, y).abs() * cw * ch);
            }
        }
        let mut cond = Vec::with_capacity(ny * (nx + 1));
        let mut marg = vec![0.0];
        for j in 0..ny {
            let mut acc = 0.0;
            cond.push(0.0);
            for i in 0..nx {
                acc += cells[j * nx + i];
                cond.push(acc);
            }
            marg.push(marg[j] + acc);
        }
        let total = marg[ny];
        Table {
            radius,
            f,
            params,
            nx,
            ny,
            cells,
            cond,
            marg,
            total,
        }
    }

    fn sample(&self, u: [f64; 2]) -> ([f64; 2], f64) {
        if !(self.total > 0.0) {
            return ([0.0, 0.0], 1.0);
        }
        // Row by the marginal, then the cell in it, then uniformly within the cell.
        let find = |cdf: &[f64], t: f64| -> (usize, f64) {
            let n = cdf.len() - 1;
            let k = cdf.partition_point(|&c| c <= t).clamp(1, n) - 1;
            let w = cdf[k + 1] - cdf[k];
            (
                k,
                if w > 0.0 {
                    ((t - cdf[k]) / w).clamp(0.0, 1.0)
                } else {
                    0.5
                },
            )
        };
        let (j, fy) = find(&self.marg, u[1] * self.total);
        let row = &self.cond[j * (self.nx + 1)..(j + 1) * (self.nx + 1)];
        let (i, fx) = find(row, u[0] * row[self.nx]);
        let (cw, ch) = (
            2.0 * self.radius[0] / self.nx as f64,
            2.0 * self.radius[1] / self.ny as f64,
        );
        let p = [
            -self.radius[0] + (i as f64 + fx) * cw,
            -self.radius[1] + (j as f64 + fy) * ch,
        ];
        // pdf(p) = |f|(cell) / (∫|f| · cell area); weight f(p) / pdf(p), up to the constant ∫|f| that Σw L / Σw
        // divides out.
        let pdf = self.cells[j * self.nx + i] / (self.total * cw * ch);
        let w = (self.f)(&self.params, p[0], p[1]) / (pdf * self.total).max(1e-300);
        (p, if w.is_finite() { w } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(r: f64) -> Params {
        Params {
            radius: [r, r],
            sigma: 0.5,
            b: 1.0 / 3.0,
            c: 1.0 / 3.0,
            tau: 3.0,
        }
    }

    #[test]
    fn stratified_samples_cover_each_stratum_once() {
        let s = Sampler::Stratified {
            xs: 3,
            ys: 2,
            jitter: false,
        };
        let mut seen: Vec<[f64; 2]> = (0..6).map(|k| s.pixel_sample(k, 77, [0.9, 0.1])).collect();
        seen.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let want = [0.25, 0.75];
        let mut all = Vec::new();
        for i in 0..3 {
            for j in want {
                all.push([(i as f64 + 0.5) / 3.0, j]);
            }
        }
        assert_eq!(seen, all);
        // One unjittered sample is the pixel centre.
        let c = Sampler::Stratified {
            xs: 1,
            ys: 1,
            jitter: false,
        };
        assert_eq!(c.pixel_sample(0, 5, [0.3, 0.8]), [0.5, 0.5]);
        for n in [1, 2, 5, 16, 100] {
            let mut p: Vec<usize> = (0..n).map(|i| permute(i, n, 12345)).collect();
            p.sort();
            assert_eq!(p, (0..n).collect::<Vec<_>>());
        }
    }

    #[test]
    fn filter_samples_have_the_filters_mean_and_variance() {
        // E[w · x²] / E[w] over evenly spread u is the filter's second moment: box r = 0.5 → 1/12; triangle r = 2 →
        // r²/6 = 2/3; gaussian σ = 0.5 truncated at 1.5 → 0.2454 (of the truncated, shifted Gaussian); the
        // Mitchell filter's weights are negative in its lobes, and its mean weight is positive.
        // The filters are separable: along u₀ with u₁ fixed, the x offsets follow the x marginal.
        let n = 20_000;
        let moment = |f: &Filter| {
            let (mut sw, mut sx2, mut sx) = (0.0, 0.0, 0.0);
            for a in 0..n {
                let (p, w) = f.sample([(a as f64 + 0.5) / n as f64, 0.3]);
                sw += w;
                sx2 += w * p[0] * p[0];
                sx += w * p[0];
            }
            (sx2 / sw, sx / sw)
        };
        let cases: [(&str, f64, f64); 3] = [
            ("box", 0.5, 1.0 / 12.0),
            ("triangle", 2.0, 2.0 / 3.0),
            ("gaussian", 1.5, 0.0),
        ];
        for (ty, r, want) in cases {
            let f = Filter::new(ty, params(r)).unwrap();
            let (m2, m1) = moment(&f);
            assert!(m1.abs() < 1e-3, "{ty}: mean {m1}");
            let want = if ty == "gaussian" {
                // ∫ x² g̃ / ∫ g̃ with g̃ = max(0, g(x) − g(1.5)), by quadrature.
                let g = |x: f64| (-2.0 * x * x).exp() - (-2.0 * 2.25f64).exp();
                let k = 20_000;
                let (mut a, mut b) = (0.0, 0.0);
                for i in 0..k {
                    let x = -1.5 + 3.0 * (i as f64 + 0.5) / k as f64;
                    a += x * x * g(x);
                    b += g(x);
                }
                a / b
            } else {
                want
            };
            assert!(
                (m2 / want - 1.0).abs() < 2e-3,
                "{ty}: second moment {m2}, expected {want}"
            );
        }
        let m = Filter::new("mitchell", params(2.0)).unwrap();
        let ws: Vec<f64> = (0..n)
            .map(|a| m.sample([(a as f64 + 0.5) / n as f64, 0.5]).1)
            .collect();
        assert!(ws.iter().any(|&w| w < 0.0) && ws.iter().sum::<f64>() > 0.0);
        assert!(
            Filter::new("lanczos", params(4.0)).is_some()
                && Filter::new("cubic", params(1.0)).is_none()
        );
    }
}
