//! A pixel's running sums and the image's error estimate from them: the halves, the twins and the sampler's gain
//! (see [`super`]).

use super::super::*;

/// A pixel's running sums.
/// (56 bytes, as pbrt-v4's RGBFilm pixel: a film is most of a render's memory beside the fire's grids.)
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Px {
    /// Σ w · sensor XYZ and Σ w (the pixel filter's weights).
    pub(super) sum: DVec3,
    pub(super) weights: f64,
    /// Σ w · Y and Σ w over the even samples (the odd ones': the totals less these).
    pub(super) even_y: f64,
    pub(super) even_w: f64,
    /// Samples taken, with [`DONE`] set once its block stopped (adaptive sampling).
    pub(super) n_done: u32,
    /// The seconds its samples took.
    pub(super) seconds: f32,
}

/// [`Px::n_done`]'s bit saying the pixel's block stopped.
pub(super) const DONE: u32 = 1 << 31;

/// A twinned pixel's twin (see the module), kept apart from the pixels (about 3 % of them have one): the pixel's
/// slot, Σ w · Y and Σ w under the other randomization, and the probability it was chosen with.
#[derive(Debug, Clone, Copy)]
pub(super) struct Twin {
    pub(super) slot: usize,
    pub(super) y: f64,
    pub(super) w: f64,
    pub(super) p: f64,
}

impl Twin {
    /// (M − M')²/2 of the twin and its pixel `px`, once both have samples.
    pub(super) fn estimate(&self, px: &Px) -> Option<f64> {
        (px.weights > 0.0 && self.w > 0.0)
            .then(|| (px.sum.y / px.weights - self.y / self.w).powi(2) / 2.0)
    }
}

impl Px {
    /// Samples taken.
    pub(super) fn n(&self) -> u32 {
        self.n_done & !DONE
    }

    /// Whether its block stopped.
    pub(super) fn done(&self) -> bool {
        self.n_done & DONE != 0
    }

    /// The pixel's luminance (sensor Y) and the estimate e of its mean's squared error, once it has two samples.
    pub(super) fn estimate(&self) -> Option<(f64, f64)> {
        let (odd_y, odd_w) = (self.sum.y - self.even_y, self.weights - self.even_w);
        let count = self.n();
        if count < 2 || self.even_w == 0.0 || odd_w == 0.0 || self.weights == 0.0 {
            return None;
        }
        let (a, b) = (self.even_y / self.even_w, odd_y / odd_w);
        let n = count as f64;
        let (na, nb) = ((count.div_ceil(2)) as f64, (count / 2) as f64);
        Some((
            self.sum.y / self.weights,
            (a - b).powi(2) * na * nb / (n * n),
        ))
    }
}

/// The image's sums after a pass: Σ e, Σ Y², Σ Y over the pixels with an estimate, how many, and whether all have.
pub(super) struct Sums {
    pub(super) e: f64,
    pub(super) y2: f64,
    pub(super) y: f64,
    pub(super) counted: usize,
    pub(super) all: bool,
}

pub(super) fn sums(px: &[Px], (w, h): (usize, usize), tw: usize) -> Sums {
    let mut s = Sums {
        e: 0.0,
        y2: 0.0,
        y: 0.0,
        counted: 0,
        all: true,
    };
    for cy in 0..h {
        for cx in 0..w {
            match px[slot_of(cx, cy, tw)].estimate() {
                Some((y, e)) => {
                    s.e += e;
                    s.y2 += y * y;
                    s.y += y;
                    s.counted += 1;
                }
                None => s.all = false,
            }
        }
    }
    s
}

/// Chooses the twins (see the module): each pixel with probability π = min(1, K (½ Y²/ΣY² + ½/N)), K =
/// max(256, N/32), by a uniform number of its own (the seed and the pixel's place in the render). (By its level,
/// not by its halves' e: the pixels whose first samples happened to differ most would be chosen, and their e,
/// which keeps those samples, would overstate them against their twins.)
pub(super) fn choose_twins(
    px: &[Px],
    (w, h): (usize, usize),
    tw: usize,
    seed: u64,
    sum_y2: f64,
) -> Vec<Twin> {
    let n = (w * h) as f64;
    let k = (n / 32.0).max(256.0).min(n);
    let mut twins = Vec::new();
    for cy in 0..h {
        for cx in 0..w {
            let slot = slot_of(cx, cy, tw);
            let Some((y, _)) = px[slot].estimate() else {
                continue;
            };
            let pi = (k * (0.5 * y * y / sum_y2 + 0.5 / n)).min(1.0);
            let u = (hash(seed, cx as u64, cy as u64, 0x7417) >> 11) as f64 / (1u64 << 53) as f64;
            if u < pi {
                twins.push(Twin {
                    slot,
                    y: 0.0,
                    w: 0.0,
                    p: pi,
                });
            }
        }
    }
    twins.sort_unstable_by_key(|t| t.slot);
    twins
}

/// The sampler's gain G = Σ d/π / Σ e/π over the twins (see the module); 1 without twins or while they say
/// nothing, and kept within [1/64, 4] (noisy twins must neither silence the estimate nor inflate it past what
/// independent samples would give by much). The floor errs high where a Sobol' sampler beats its halves by more
/// (the candle, emission alone: G ≈ 1/600 at 256 spp, the estimate 2.3× the true error); without it, twins among
/// the flame's pixels understate the surfaces' error (the art and blue-core scenes: 0.6× at 64–256 spp).
pub(super) fn gain(px: &[Px], twins: &[Twin]) -> f64 {
    gain_weighted(px, twins, |_| 1.0)
}

/// The sampler's gain for relMSE, each twin's errors weighed by 1 / (Y² + ε), ε = `floor` (see [`adapt`]): the
/// gain of the pixels that relMSE counts (surfaces, dark ones too) rather than of the bright ones that the image's
/// relative RMSE counts (a flame's, whose smooth light gains more from low discrepancy).
pub(super) fn gain_relative(px: &[Px], twins: &[Twin], floor: f64) -> f64 {
    gain_weighted(px, twins, |y| 1.0 / (y * y + floor))
}

/// G with each twin's d and e weighed by `weight(Y)` beside its 1/π (`twins` by slot: the sums' order is the
/// pixels').
pub(super) fn gain_weighted(px: &[Px], twins: &[Twin], weight: impl Fn(f64) -> f64) -> f64 {
    let (mut twin, mut halves) = (0.0, 0.0);
    for t in twins {
        let p = &px[t.slot];
        if let (Some(d), Some((y, e))) = (t.estimate(p), p.estimate()) {
            let w = weight(y) / t.p;
            twin += d * w;
            halves += e * w;
        }
    }
    if halves > 0.0 && twin > 0.0 {
        (twin / halves).clamp(1.0 / 64.0, 4.0)
    } else {
        1.0
    }
}

/// The slot of rendered pixel (cx, cy) in the tiles' runs.
pub(super) fn slot_of(cx: usize, cy: usize, tw: usize) -> usize {
    let t = (cy / TILE) * tw + cx / TILE;
    t * TILE * TILE + (cy % TILE) * TILE + (cx % TILE)
}
