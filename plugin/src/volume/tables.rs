//! Temperature tables: per-channel functions of T alone (emission, T-dependent absorption, line
//! cross-sections), tabulated once on a uniform grid of ≤ 0.5 K (at most 65 536 rows up to the hottest voxel)
//! in lanes the f32 march reads directly, interpolated linearly; and [`RangeMax`], their maxima over any
//! temperature range in O(1), for the majorant bricks.

/// Channels per lane (the march's `f32` lanes, [`super::lanes`]).
pub(crate) const W: usize = 8;
/// One lane of channels.
pub(crate) type Lane = [f32; W];

/// The rows of a temperature table up to `t_max` K with rows at most `step` K apart.
fn rows_for(t_max: f64, step: f64) -> usize {
    ((t_max / step).ceil() as usize)
        .saturating_add(2)
        .clamp(2, 65_536)
}

/// The most bytes the temperature tables of a volume of `c` channels up to `t_max` K take while they are built,
/// counted before any is made (a table's size follows the input: the hottest voxel and the bins a scene asks for):
/// the soot's emission and absorption built together and split (four tables' worth), each of `species`' σ and j,
/// and the range maxima — a level per power of two of rows — over each temperature-dependent absorption table
/// (each species', and the soot's when `t_absorption`, rgb mode). Saturating.
pub(super) fn bytes_for(t_max: f64, c: usize, species: usize, t_absorption: bool) -> u64 {
    let rows = rows_for(t_max, 0.5) as u64;
    let lane = std::mem::size_of::<Lane>() as u64;
    let table = rows
        .saturating_mul(c.div_ceil(W).max(1) as u64)
        .saturating_mul(lane);
    let levels = u64::from(u64::BITS - rows.leading_zeros());
    let range_max = rows
        .saturating_mul(c as u64)
        .saturating_mul(4)
        .saturating_mul(levels);
    let maxed = species as u64 + u64::from(t_absorption);
    table
        .saturating_mul(4 + 2 * species as u64)
        .saturating_add(range_max.saturating_mul(maxed))
}

/// A temperature table: `rows` × C values, row r at T = r·dt, each row stored as lanes of `W` channels
/// (zero-padded), which the f32 march reads directly.
#[derive(Debug, Clone, Default)]
pub(super) struct TTable {
    dt: f64,
    /// 1 / dt (the kernel multiplies).
    inv_dt: f64,
    rows: usize,
    /// Lanes per row.
    chunks: usize,
    v: Vec<Lane>,
}

impl TTable {
    /// Tabulates `f(T) -> C values` for T in [0, t_max], in parallel.
    pub(super) fn build(t_max: f64, c: usize, f: &(dyn Fn(f64) -> Vec<f64> + Sync)) -> TTable {
        Self::build_step(t_max, 0.5, c, f)
    }
    /// As [`build`](Self::build) with rows at most `step` K apart.
    pub(super) fn build_step(
        t_max: f64,
        step: f64,
        c: usize,
        f: &(dyn Fn(f64) -> Vec<f64> + Sync),
    ) -> TTable {
        let rows = rows_for(t_max, step);
        let dt = if t_max > 0.0 {
            t_max / (rows - 2) as f64
        } else {
            1.0
        };
        let chunks = c.div_ceil(W).max(1);
        let mut v = vec![[0f32; W]; rows * chunks];
        let threads = crate::par::threads(8);
        let chunk = rows.div_ceil(threads);
        crate::par::scope(|s| {
            for (k, part) in v.chunks_mut(chunk * chunks).enumerate() {
                s.spawn(move || {
                    for (r, row) in part.chunks_mut(chunks).enumerate() {
                        for (ch, x) in f((k * chunk + r) as f64 * dt).into_iter().enumerate() {
                            row[ch / W][ch % W] = x as f32;
                        }
                    }
                });
            }
        });
        TTable {
            dt,
            inv_dt: 1.0 / dt,
            rows,
            chunks,
            v,
        }
    }
    /// The table of rows of `chunks` lanes each in `v`, `dt` K apart from 0 K (at least two rows).
    pub(super) fn from_lanes(dt: f64, chunks: usize, v: Vec<Lane>) -> TTable {
        TTable {
            dt,
            inv_dt: 1.0 / dt,
            rows: v.len() / chunks.max(1),
            chunks,
            v,
        }
    }
    /// The rows, ΔT between them (K) and 1/ΔT.
    pub(super) fn rows(&self) -> usize {
        self.rows
    }
    pub(super) fn dt(&self) -> f64 {
        self.dt
    }
    pub(super) fn inv_dt(&self) -> f64 {
        self.inv_dt
    }
    /// Lanes per row, and the rows' lanes one after another.
    pub(super) fn chunks(&self) -> usize {
        self.chunks
    }
    pub(super) fn lanes(&self) -> &[Lane] {
        &self.v
    }
    /// The two rows around T and the fraction between them, as lanes.
    #[inline(always)]
    pub(super) fn lane_rows(&self, t: f32) -> (&[Lane], &[Lane], f32) {
        let f = (t as f64 / self.dt).clamp(0.0, (self.rows - 1) as f64);
        let i = (f as usize).min(self.rows - 2);
        let a = &self.v[i * self.chunks..(i + 1) * self.chunks];
        let b = &self.v[(i + 1) * self.chunks..(i + 2) * self.chunks];
        (a, b, (f - i as f64) as f32)
    }
    /// The largest value in the table.
    pub(super) fn max(&self) -> f64 {
        self.v.iter().flatten().fold(0f32, |m, &x| m.max(x)) as f64
    }
    /// The table of channels 0..c and the table of the rest (one build that computes both, split).
    pub(super) fn split(&self, c: usize) -> (TTable, TTable) {
        let total = self.chunks * W;
        let part = |from: usize, to: usize| {
            let n = to - from;
            let chunks = n.div_ceil(W).max(1);
            let mut v = vec![[0f32; W]; self.rows * chunks];
            for r in 0..self.rows {
                for ch in 0..n {
                    v[r * chunks + ch / W][ch % W] = self.value(r, from + ch);
                }
            }
            TTable {
                dt: self.dt,
                inv_dt: self.inv_dt,
                rows: self.rows,
                chunks,
                v,
            }
        };
        (part(0, c.min(total)), part(c.min(total), total))
    }
    /// The same values at every temperature.
    pub(super) fn constant(row: &[f64]) -> TTable {
        TTable::build(0.0, row.len(), &|_| row.to_vec())
    }
    /// Row index and fraction of T.
    #[inline]
    pub(super) fn locate(&self, t: f64) -> (usize, f32) {
        let f = (t / self.dt).clamp(0.0, (self.rows - 1) as f64);
        let i = (f as usize).min(self.rows - 2);
        (i, (f - i as f64) as f32)
    }
    #[inline]
    pub(super) fn value(&self, r: usize, c: usize) -> f32 {
        self.v[r * self.chunks + c / W][c % W]
    }
    #[inline]
    pub(super) fn at(&self, (i, fr): (usize, f32), c: usize) -> f32 {
        let a = self.value(i, c);
        a + fr * (self.value(i + 1, c) - a)
    }
    pub(super) fn bytes(&self) -> usize {
        self.v.len() * std::mem::size_of::<Lane>()
    }
}

/// The largest value of each of a temperature table's first `c` channels over any range of rows, in O(1): a
/// sparse table (level k holds the maxima over 2ᵏ rows from each row), so the majorant bricks' temperature
/// ranges cost two reads each instead of a scan of their rows (the rgb volume's bricks: 60 → 25 ms at 256³).
/// The same values as a scan of the rows, bit for bit (tested).
pub(super) struct RangeMax {
    dt: f64,
    rows: usize,
    c: usize,
    levels: Vec<Vec<f32>>,
}

impl RangeMax {
    pub(super) fn new(tab: &TTable, c: usize) -> RangeMax {
        let rows = tab.rows;
        let mut levels = vec![(0..rows * c)
            .map(|i| tab.value(i / c, i % c))
            .collect::<Vec<f32>>()];
        let mut k = 1;
        while (1usize << k) <= rows {
            let (half, prev) = (1usize << (k - 1), &levels[k - 1]);
            let n = rows + 1 - (1usize << k);
            let next: Vec<f32> = (0..n * c)
                .map(|i| prev[i].max(prev[i + half * c]))
                .collect();
            levels.push(next);
            k += 1;
        }
        RangeMax {
            dt: tab.dt,
            rows,
            c,
            levels,
        }
    }
    /// The largest value of channel `ch` over T in [lo, hi] (rows rounded outward), ≥ 0.
    pub(super) fn max_over(&self, lo: f64, hi: f64, ch: usize) -> f32 {
        let last = (self.rows - 1) as f64;
        let a = (lo / self.dt).floor().clamp(0.0, last) as usize;
        let b = (hi / self.dt).ceil().clamp(0.0, last) as usize;
        if b < a || ch >= self.c {
            return 0.0;
        }
        let k = (usize::BITS - 1 - (b - a + 1).leading_zeros()) as usize;
        let level = &self.levels[k];
        level[a * self.c + ch]
            .max(level[(b + 1 - (1usize << k)) * self.c + ch])
            .max(0.0)
    }
}

#[derive(Debug, Clone)]
pub(super) struct SpeciesChannel {
    ch: usize,
    scale: f64,
    sigma: TTable,
    j: TTable,
}

impl SpeciesChannel {
    /// A species read from grid channel `ch`, its values times `scale` its number density (m⁻³), with its
    /// cross-section and emission per unit number density over T.
    pub(super) fn new(ch: usize, scale: f64, sigma: TTable, j: TTable) -> SpeciesChannel {
        SpeciesChannel {
            ch,
            scale,
            sigma,
            j,
        }
    }
    /// Its grid channel, and the scale from the grid's values to number density.
    pub(super) fn ch(&self) -> usize {
        self.ch
    }
    pub(super) fn scale(&self) -> f64 {
        self.scale
    }
    /// Its cross-section and emission per unit number density over T.
    pub(super) fn sigma(&self) -> &TTable {
        &self.sigma
    }
    pub(super) fn j(&self) -> &TTable {
        &self.j
    }
}
