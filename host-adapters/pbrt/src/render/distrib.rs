//! A piecewise-constant distribution over the cells of a 2D grid (pbrt-v4's `PiecewiseConstant2D`): a cell drawn
//! with probability proportional to its weight — the row by the marginal, the column by the row's conditional —
//! and a uniform position within it. Used for pixel filters and environment maps.

/// Cumulative weights: per row (nx + 1 entries each) and over the rows (ny + 1), each with its [`Guide`].
#[derive(Debug, Clone)]
pub struct Distribution2D {
    nx: usize,
    ny: usize,
    cond: Vec<f64>,
    marg: Vec<f64>,
    cond_guides: Vec<Guide>,
    marg_guide: Guide,
}

/// Where in a cumulative table the search for a value starts and ends, by which of the table's equal parts of
/// its total the value falls in (a guide table): a pixel filter's sample searched the whole table with a binary
/// search whose branches mispredict (docs/results/log.md, "The pixel filter's search guided"). The search inside
/// the guide's range is checked against the range's ends and falls back to the whole table, so it finds the
/// index the whole-table search finds, always.
#[derive(Debug, Clone)]
struct Guide {
    /// The parts per unit of the total (parts / total), and per part the first index whose value exceeds the
    /// part's start (one more entry: the table's length).
    scale: f64,
    first: Vec<u32>,
}

/// The most parts a [`Guide`] divides its table's total into.
const MAX_PARTS: usize = 64;

impl Guide {
    fn new(cdf: &[f64]) -> Guide {
        // As many parts as cells, up to 64: a filter's table is guided to the cell, an environment map's rows of
        // thousands to a few dozen entries (with guides a quarter of the table's own size at most).
        let parts = cdf.len().saturating_sub(1).clamp(1, MAX_PARTS);
        let total = cdf.last().copied().unwrap_or(0.0);
        if !(total > 0.0 && total.is_finite()) {
            return Guide {
                scale: 0.0,
                first: Vec::new(),
            };
        }
        let scale = parts as f64 / total;
        let mut first: Vec<u32> = (0..parts)
            .map(|b| cdf.partition_point(|&c| c <= b as f64 / scale) as u32)
            .collect();
        first.push(cdf.len() as u32);
        Guide { scale, first }
    }

    /// `cdf.partition_point(|&c| c <= t)` (`cdf` the table the guide was made for).
    #[inline]
    fn partition_point(&self, cdf: &[f64], t: f64) -> usize {
        let part = (t * self.scale) as usize;
        if part < self.first.len().saturating_sub(1) {
            let (lo, hi) = (self.first[part] as usize, self.first[part + 1] as usize);
            // The answer lies in [lo, hi] when the entry below lo is at most t and the one at hi above it.
            let below = lo == 0 || cdf[lo - 1] <= t;
            let above = hi >= cdf.len() || cdf[hi] > t;
            if below && above && lo <= hi {
                return lo + cdf[lo..hi].partition_point(|&c| c <= t);
            }
        }
        cdf.partition_point(|&c| c <= t)
    }
}

/// A drawn cell: its column and row, the position within it (each in [0, 1)) and its probability.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cell {
    pub x: usize,
    pub y: usize,
    pub fx: f64,
    pub fy: f64,
    pub p: f64,
}

impl Distribution2D {
    /// From `weights` (rows of `nx`, non-negative; `ny` = len / nx).
    pub fn new(weights: &[f64], nx: usize) -> Distribution2D {
        let nx = nx.max(1);
        let ny = (weights.len() / nx).max(1);
        let mut cond = Vec::with_capacity(ny * (nx + 1));
        let mut marg = vec![0.0];
        for y in 0..ny {
            let mut acc = 0.0;
            cond.push(0.0);
            for x in 0..nx {
                acc += weights.get(x + nx * y).copied().unwrap_or(0.0).max(0.0);
                cond.push(acc);
            }
            marg.push(marg[y] + acc);
        }
        let cond_guides = cond.chunks(nx + 1).map(Guide::new).collect();
        let marg_guide = Guide::new(&marg);
        Distribution2D {
            nx,
            ny,
            cond,
            marg,
            cond_guides,
            marg_guide,
        }
    }

    /// The sum of the weights.
    pub fn total(&self) -> f64 {
        self.marg[self.ny]
    }

    /// The probability of drawing cell (`x`, `y`) (0 outside the grid or when every weight is zero).
    pub fn prob(&self, x: usize, y: usize) -> f64 {
        let total = self.total();
        if !(total > 0.0) || x >= self.nx || y >= self.ny {
            return 0.0;
        }
        let row = &self.cond[y * (self.nx + 1)..(y + 1) * (self.nx + 1)];
        (row[x + 1] - row[x]) / total
    }

    /// The cell for `u` ∈ [0, 1)²; `None` when every weight is zero.
    pub fn sample(&self, u: [f64; 2]) -> Option<Cell> {
        let total = self.total();
        if !(total > 0.0) {
            return None;
        }
        let find = |cdf: &[f64], guide: &Guide, t: f64| -> (usize, f64) {
            let n = cdf.len() - 1;
            let k = guide.partition_point(cdf, t).clamp(1, n) - 1;
            let width = cdf[k + 1] - cdf[k];
            let f = if width > 0.0 {
                (t - cdf[k]) / width
            } else {
                0.5
            };
            (k, f.clamp(0.0, 1.0 - 1e-7))
        };
        let (y, fy) = find(&self.marg, &self.marg_guide, u[1] * total);
        let row = &self.cond[y * (self.nx + 1)..(y + 1) * (self.nx + 1)];
        let (x, fx) = find(row, &self.cond_guides[y], u[0] * row[self.nx]);
        Some(Cell {
            x,
            y,
            fx,
            fy,
            p: (row[x + 1] - row[x]) / total,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The guided search finds the whole table's index for every value: uniform ones, the table's own entries
    /// (where `<=` decides), just either side of them, beyond the total, and NaN.
    #[test]
    fn the_guide_finds_what_the_whole_search_finds() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let gaussian: Vec<f64> = (0..48)
            .map(|i| (-((i as f64 - 23.5) / 8.0).powi(2)).exp() - (-(24.0f64 / 8.0).powi(2)).exp())
            .collect();
        let spiky: Vec<f64> = (0..37)
            .map(|i| match i % 9 {
                0 => 1e6,
                4 => 0.0,
                _ => 1e-9 * i as f64,
            })
            .collect();
        let zeros_between = [0.0, 0.0, 3.0, 0.0, 0.0, 0.0, 1.0, 0.0];
        // (A row of an environment map: more cells than a guide has parts.)
        let long: Vec<f64> = (0..2048).map(|i| 1.0 + (i as f64 * 0.37).sin()).collect();
        for weights in [
            &gaussian[..],
            &spiky[..],
            &zeros_between[..],
            &[2.5][..],
            &long[..],
        ] {
            let mut cdf = vec![0.0];
            for w in weights {
                cdf.push(cdf[cdf.len() - 1] + w);
            }
            let guide = Guide::new(&cdf);
            let total = cdf[cdf.len() - 1];
            let mut values: Vec<f64> = (0..20_000).map(|_| next() * total).collect();
            for &c in &cdf {
                values.extend([c, c.next_down(), c.next_up()]);
            }
            values.extend([-1.0, total * 2.0, f64::NAN, f64::INFINITY]);
            for t in values {
                assert_eq!(
                    guide.partition_point(&cdf, t),
                    cdf.partition_point(|&c| c <= t),
                    "t = {t:e} over {cdf:?}"
                );
            }
        }
    }
}
