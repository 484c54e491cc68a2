//! Adaptive sampling's stopping rule (see [`super`]): blocks of pixels by their noise over the root of their cost.

use super::sums::{slot_of, Px, DONE};

/// The adaptive blocks' edge, pixels, and the samples a pixel takes before its block may stop.
pub(super) const BLOCK: usize = 8;
pub(super) const MIN_ADAPTIVE_SPP: u32 = 8;
/// A block of [`BLOCK`]² pixels (on the full film) as the stopping rule sees it.
pub(super) struct Block {
    /// Its pixels' ranges in the rendered pixels.
    xs: std::ops::Range<usize>,
    ys: std::ops::Range<usize>,
    /// Its pixels, and their mean samples.
    pixels: f64,
    n: f64,
    /// The relative variance of one sample, r = n · g mean(e / (Y² + ε)): its estimated relMSE is r / n.
    r: f64,
    /// Seconds per pixel sample.
    cost: f64,
    done: bool,
}

/// The stopping rule (see the module): marks done every block that has its share of the samples that bring the
/// image's relMSE to `threshold`² at the least time, no block's above (2 · threshold)². `gain` the sampler's
/// (see [`gain`]), `spp` the most a pixel takes, `mean_y` the image's mean luminance. No block stops before
/// every pixel has [`MIN_ADAPTIVE_SPP`] samples.
pub(super) fn adapt(
    px: &mut [Px],
    (w, h): (usize, usize),
    (x0, y0): (usize, usize),
    tw: usize,
    (threshold, gain, spp): (f64, f64, usize),
    mean_y: f64,
) {
    let slot_of = |cx: usize, cy: usize| slot_of(cx, cy, tw);
    // Blocks on the full film: those that overlap the rendered pixels.
    let (bx0, bx1) = (x0 / BLOCK, (x0 + w).div_ceil(BLOCK));
    let (by0, by1) = (y0 / BLOCK, (y0 + h).div_ceil(BLOCK));
    let floor = 0.01 * mean_y * mean_y;
    let mut blocks = Vec::with_capacity((bx1 - bx0) * (by1 - by0));
    for by in by0..by1 {
        for bx in bx0..bx1 {
            let xs = (bx * BLOCK).max(x0) - x0..((bx + 1) * BLOCK).min(x0 + w) - x0;
            let ys = (by * BLOCK).max(y0) - y0..((by + 1) * BLOCK).min(y0 + h) - y0;
            let (mut rel, mut n, mut secs, mut count) = (0.0, 0.0, 0.0, 0.0);
            for cy in ys.clone() {
                for cx in xs.clone() {
                    let p = &px[slot_of(cx, cy)];
                    match p.estimate() {
                        Some((y, e)) if p.n() >= MIN_ADAPTIVE_SPP => {
                            rel += e / (y * y + floor);
                            n += p.n() as f64;
                            secs += p.seconds as f64;
                            count += 1.0;
                        }
                        // (Every pixel samples until it has the least: no block stops before.)
                        _ => return,
                    }
                }
            }
            let n_mean = n / count;
            blocks.push(Block {
                pixels: count,
                n: n_mean,
                // (A block whose estimate is not a number does not steer the others: as one without noise.)
                r: Some(n_mean * gain * rel / count)
                    .filter(|r| floor > 0.0 && r.is_finite())
                    .unwrap_or(0.0),
                cost: (secs / n).max(1e-12),
                done: px[slot_of(xs.start, ys.start)].done(),
                xs,
                ys,
            });
        }
    }
    let t2 = threshold * threshold;
    let pixels: f64 = blocks.iter().map(|b| b.pixels).sum();
    // A block's samples at multiplier k: k √(r / c) (the least time to a given relMSE: Lagrange), at least what
    // brings it to (2T)², never fewer than it has nor more than the most.
    let want = |b: &Block, k: f64| {
        if b.done {
            b.n
        } else {
            (k * (b.r / b.cost).sqrt())
                .max(b.r / (4.0 * t2))
                .clamp(b.n, spp as f64)
        }
    };
    let rel_mse = |k: f64| {
        blocks
            .iter()
            .map(|b| b.pixels * b.r / want(b, k).max(1.0))
            .sum::<f64>()
            / pixels
    };
    // The multiplier that meets T² (bisection on ln k; relMSE falls as k grows); none if even the most samples
    // everywhere would not.
    let (mut lo, mut hi) = (-80f64, 80f64);
    if rel_mse(hi.exp()) > t2 {
        return;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if rel_mse(mid.exp()) > t2 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let k = hi.exp();
    for b in blocks.iter().filter(|b| !b.done && want(b, k) <= b.n) {
        for cy in b.ys.clone() {
            for cx in b.xs.clone() {
                px[slot_of(cx, cy)].n_done |= DONE;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::TILE;
    use super::*;
    use glam::DVec3;

    /// A render one block high, a block per entry of `blocks` across (δ, cost): every pixel of luminance 1 with
    /// `n` samples whose halves differ by 2δ (so e = δ², and r = n δ² / 1.01 with the image's mean 1) and which
    /// took `cost` seconds per sample. The pixels, the render's size and its tiles across.
    fn film(n: u32, blocks: &[(f64, f64)]) -> (Vec<Px>, (usize, usize), usize) {
        let (w, h) = (BLOCK * blocks.len(), BLOCK);
        let tw = w.div_ceil(TILE);
        let mut px = vec![Px::default(); tw * TILE * TILE];
        for cy in 0..h {
            for cx in 0..w {
                let (delta, cost) = blocks[cx / BLOCK];
                let half = n as f64 / 2.0;
                px[slot_of(cx, cy, tw)] = Px {
                    sum: DVec3::new(0.0, n as f64, 0.0),
                    weights: n as f64,
                    even_y: (1.0 + delta) * half,
                    even_w: half,
                    n_done: n,
                    seconds: (cost * n as f64) as f32,
                };
            }
        }
        (px, (w, h), tw)
    }

    /// δ for a block's r at n samples.
    fn delta(r: f64, n: u32) -> f64 {
        (r * 1.01 / n as f64).sqrt()
    }

    /// Which blocks stop at threshold `t`, gain `gain`, after `n` samples of `blocks`.
    fn stops(n: u32, blocks: &[(f64, f64)], t: f64, gain: f64) -> Vec<bool> {
        let (mut px, (w, h), tw) = film(n, blocks);
        adapt(&mut px, (w, h), (0, 0), tw, (t, gain, 1 << 20), 1.0);
        (0..blocks.len())
            .map(|b| px[slot_of(b * BLOCK, 0, tw)].done())
            .collect()
    }

    #[test]
    fn a_block_takes_samples_by_its_noise_over_the_root_of_its_cost() {
        // Both blocks r = 0.08; B's samples cost 4× A's. The least time to relMSE T² = 0.008 gives n ∝ √(r / c):
        // n_A = 2 n_B. With both at 8 samples, B's are its share (the optimum's 7.5) and A needs (0.08/8 +
        // 0.08/n_A)/2 = 0.008: n_A = 13.3 — A goes on.
        let t = 0.008f64.sqrt();
        let d = delta(0.08, 8);
        assert_eq!(stops(8, &[(d, 1.0), (d, 4.0)], t, 1.0), [false, true]);
        // Equal costs: each needs 10 (0.08/n = 0.008); at 8 neither has its share, at 12 both have.
        assert_eq!(stops(8, &[(d, 1.0), (d, 1.0)], t, 1.0), [false, false]);
        let d = delta(0.08, 12);
        assert_eq!(stops(12, &[(d, 1.0), (d, 1.0)], t, 1.0), [true, true]);
        // The sampler's gain scales r: at gain 2 the 12 samples are not enough (each needs 20).
        assert_eq!(stops(12, &[(d, 1.0), (d, 1.0)], t, 2.0), [false, false]);
    }

    #[test]
    fn a_noisy_block_is_never_left_above_twice_the_threshold() {
        // Seven quiet cheap blocks (r = 0.001) and one noisy block (r = 0.5) whose samples cost 10⁴× more: the
        // optimum would give the noisy one almost nothing, but its error at 8 samples, 0.5/8, is above (2T)² =
        // 0.032, so it goes on whatever it costs; the quiet ones stop.
        let t = 0.008f64.sqrt();
        let mut blocks = vec![(delta(0.001, 8), 1.0); 7];
        blocks.push((delta(0.5, 8), 1e4));
        let want: Vec<bool> = (0..8).map(|b| b < 7).collect();
        assert_eq!(stops(8, &blocks, t, 1.0), want);
        // A block without noise (the sky) stops at the least samples; before them nothing stops.
        assert!(stops(8, &[(0.0, 1.0), (delta(0.08, 8), 1.0)], 0.1, 1.0)[0]);
        assert_eq!(
            stops(4, &[(0.0, 1.0), (0.0, 1.0)], 0.1, 1.0),
            [false, false]
        );
        // A block whose estimate is not a number counts as one without noise and does not stop the others
        // early: seven blocks of r = 0.08 at 8 samples need 8.75 each to bring the mean to 0.008.
        let mut blocks = vec![(delta(0.08, 8), 1.0); 7];
        blocks.push((f64::NAN, 1.0));
        let want: Vec<bool> = (0..8).map(|b| b == 7).collect();
        assert_eq!(stops(8, &blocks, t, 1.0), want);
    }
}
