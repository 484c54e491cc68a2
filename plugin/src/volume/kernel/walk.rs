//! Where the march's samples fall along a ray: its steps, less the empty stretches the brick walk finds.

use super::BATCH;
use crate::volume::integrate::{Span, MAX_STEPS};
use crate::volume::{FireVolume, Ray};

/// A ray's empty stretches (arc length from its entry into the medium): the bricks `empty_spans` reports,
/// pulled from the brick walk as the march reaches them, adjacent ones merged — no list per ray, and no walk
/// past where the march stops.
struct Gaps<'a> {
    segs: std::iter::Peekable<crate::majorant::Segments>,
    empty: &'a [bool],
    /// The ray's entry parameter and |d| (arc length per unit of parameter).
    a: f64,
    speed: f64,
}

impl Gaps<'_> {
    /// The next empty stretch, (∞, ∞) when none is left.
    #[inline]
    fn next(&mut self) -> (f64, f64) {
        let empty = |g: &Gaps, b: usize| g.empty.get(b).copied().unwrap_or(false);
        while let Some(seg) = self.segs.next() {
            if !empty(self, seg.brick) {
                continue;
            }
            let start = (seg.t0 - self.a) * self.speed;
            let mut end = (seg.t1 - self.a) * self.speed;
            // (The walk's pieces tile the ray: the next starts exactly where this one ends.)
            while let Some(&next) = self.segs.peek() {
                if !empty(self, next.brick) || (next.t0 - self.a) * self.speed != end {
                    break;
                }
                end = (next.t1 - self.a) * self.speed;
                self.segs.next();
            }
            return (start, end);
        }
        (f64::INFINITY, f64::INFINITY)
    }
}

/// The march's steps along a ray (arc length from its entry): step k spans [first + (k − 1)·ds, first + k·ds] ∩
/// [0, len] (k counted in f64: exact below 2⁵³; a step's end is the next one's start, as computed here), those
/// whose midpoints fall in an empty stretch skipped.
pub(super) struct Walk<'a> {
    gaps: Gaps<'a>,
    first: f64,
    ds: f64,
    len: f64,
    k: f64,
    s0: f64,
    /// The next empty stretch (infinitely far when there is none left).
    gap: (f64, f64),
}

impl<'a> Walk<'a> {
    /// The march of `ray` over `span` through `v` in steps of `step` (at most MAX_STEPS over the span), the
    /// first a random fraction of a step from the entry.
    #[inline(always)]
    pub(super) fn along(v: &'a FireVolume, ray: &Ray, span: &Span, step: f64) -> Walk<'a> {
        let len = (span.b() - span.a()) * span.speed();
        let mut ds = step;
        if !(ds > 0.0) || len / ds > MAX_STEPS {
            ds = len / MAX_STEPS;
        }
        let mut rng = ray.rng();
        let mut first = rng.next_f64() * ds;
        if first <= 0.0 {
            first = ds;
        }
        // Empty stretches (arc length from the entry), pulled from the brick walk as the march reaches them.
        let gaps = Gaps {
            segs: v
                .bounds
                .majorant()
                .segments(ray.o, ray.d, span.a(), span.b())
                .peekable(),
            empty: v.bounds.brick_empty(),
            a: span.a(),
            speed: span.speed(),
        };
        Walk::new(gaps, first, ds, len)
    }

    /// The steps of `ds` from `first` to `len`, skipping the stretches `gaps` gives.
    #[inline(always)]
    fn new(mut gaps: Gaps<'a>, first: f64, ds: f64, len: f64) -> Walk<'a> {
        let gap = gaps.next();
        Walk {
            gaps,
            first,
            ds,
            len,
            k: 0.0,
            s0: 0.0,
            gap,
        }
    }

    /// The next BATCH steps outside empty stretches: their midpoints and lengths in `mids` and `deltas`; how many
    /// there are, and whether the ray ends after them.
    #[inline(always)]
    pub(super) fn next_batch(
        &mut self,
        mids: &mut [f64; BATCH],
        deltas: &mut [f32; BATCH],
    ) -> (usize, bool) {
        let (first, ds, len) = (self.first, self.ds, self.len);
        let (mut k, mut s0, mut gap) = (self.k, self.s0, self.gap);
        let mut m = 0;
        let mut end = false;
        // The common case at once: all BATCH steps whole and before the next empty stretch (the ends are
        // increasing, so the last step decides), with the loop's arithmetic, bit for bit.
        let mut ends = [0f64; BATCH + 1];
        ends[0] = s0;
        for b in 0..BATCH {
            ends[b + 1] = first + (k + b as f64) * ds;
        }
        if ends[BATCH] < len && 0.5 * (ends[BATCH - 1] + ends[BATCH]) < gap.0 {
            for b in 0..BATCH {
                mids[b] = 0.5 * (ends[b] + ends[b + 1]);
                deltas[b] = (ends[b + 1] - ends[b]) as f32;
            }
            k += BATCH as f64;
            s0 = ends[BATCH];
            m = BATCH;
        }
        while m < BATCH {
            if !(s0 < len) {
                end = true;
                break;
            }
            let s1 = first + k * ds;
            let s1 = if s1 < len { s1 } else { len };
            let mid = 0.5 * (s0 + s1);
            if mid >= gap.0 {
                if mid < gap.1 {
                    // The first step whose midpoint (first + (k − ½)·ds for a whole step) is past the stretch.
                    let past = ((gap.1 - first) / ds + 0.5).ceil();
                    k = if past > k + 1.0 { past } else { k + 1.0 };
                    s0 = first + (k - 1.0) * ds;
                } else {
                    gap = self.gaps.next();
                }
                continue;
            }
            k += 1.0;
            mids[m] = mid;
            deltas[m] = (s1 - s0) as f32;
            m += 1;
            s0 = s1;
        }
        (self.k, self.s0, self.gap) = (k, s0, gap);
        (m, end)
    }
}
