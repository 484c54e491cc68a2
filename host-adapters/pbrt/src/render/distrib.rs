//! A piecewise-constant distribution over the cells of a 2D grid (pbrt-v4's `PiecewiseConstant2D`): a cell drawn
//! with probability proportional to its weight — the row by the marginal, the column by the row's conditional —
//! and a uniform position within it. Used for pixel filters and environment maps.

/// Cumulative weights: per row (nx + 1 entries each) and over the rows (ny + 1).
#[derive(Debug, Clone)]
pub struct Distribution2D {
    nx: usize,
    ny: usize,
    cond: Vec<f64>,
    marg: Vec<f64>,
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
        Distribution2D { nx, ny, cond, marg }
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
        let find = |cdf: &[f64], t: f64| -> (usize, f64) {
            let n = cdf.len() - 1;
            let k = cdf.partition_point(|&c| c <= t).clamp(1, n) - 1;
            let width = cdf[k + 1] - cdf[k];
            let f = if width > 0.0 {
                (t - cdf[k]) / width
            } else {
                0.5
            };
            (k, f.clamp(0.0, 1.0 - 1e-7))
        };
        let (y, fy) = find(&self.marg, u[1] * total);
        let row = &self.cond[y * (self.nx + 1)..(y + 1) * (self.nx + 1)];
        let (x, fx) = find(row, u[0] * row[self.nx]);
        Some(Cell {
            x,
            y,
            fx,
            fy,
            p: (row[x + 1] - row[x]) / total,
        })
    }
}
