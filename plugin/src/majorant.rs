//! Majorant grid and DDA: coarse bricks bounding every channel from above and below, walked along rays.
//!
//! The dataset's lattice is cut into bricks of `brick`³ voxels (8 by default; the last brick on an axis may
//! be partial). Each brick stores, per channel, the max and min of the voxels it covers **widened by one
//! voxel** on every side: a trilinear lookup anywhere inside the brick blends only those voxels, so the bound
//! holds under interpolation; where the widened range leaves the grid, the zero that trilinear lookups use
//! outside is included. [`MajorantGrid::segments`] walks a ray through the bricks (Amanatides & Woo) and yields
//! (t₀, t₁, brick) pieces that exactly tile the ray's overlap with the bounds. A brick whose `density` max is
//! zero is empty space ([`MajorantGrid::is_empty`]).

use crate::dataset::Dataset;
use glam::DVec3;

/// The part [a, b] of the ray o + t·d, t ∈ [t0, t1], inside the box [p0, p1] (slab test); `None` when it
/// misses, and for non-finite rays (`f64::max` would silently skip a NaN).
pub fn clip_box(o: DVec3, d: DVec3, t0: f64, t1: f64, p0: DVec3, p1: DVec3) -> Option<(f64, f64)> {
    if !(o.is_finite() && d.is_finite()) {
        return None;
    }
    let (mut a, mut b) = (t0, t1);
    for k in 0..3 {
        if d[k] == 0.0 {
            if !(o[k] >= p0[k] && o[k] <= p1[k]) {
                return None;
            }
        } else {
            let (ta, tb) = ((p0[k] - o[k]) / d[k], (p1[k] - o[k]) / d[k]);
            a = a.max(ta.min(tb));
            b = b.min(ta.max(tb));
        }
    }
    (a < b).then_some((a, b))
}

/// Per-brick channel bounds over a dataset's lattice.
#[derive(Debug, Clone, PartialEq)]
pub struct MajorantGrid {
    brick: usize,
    counts: [usize; 3],
    dims: [usize; 3],
    bounds: [DVec3; 2],
    channels: usize,
    /// `[brick][channel]` → (min, max).
    ranges: Vec<(f32, f32)>,
}

/// One piece of a ray inside one brick.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Entry parameter.
    pub t0: f64,
    /// Exit parameter.
    pub t1: f64,
    /// Linear brick index (x fastest), for [`MajorantGrid::max`] and [`MajorantGrid::min`].
    pub brick: usize,
    /// The brick's coordinates (its linear index, decoded without divisions).
    pub cell: [usize; 3],
}

impl MajorantGrid {
    /// Builds the bricks of `brick`³ voxels (`brick` ≥ 1) over every channel of `ds`.
    pub fn build(ds: &Dataset, brick: usize) -> MajorantGrid {
        MajorantGrid::with_ranges(ds, brick, vec![None; ds.channels().len()])
    }

    /// As [`MajorantGrid::build`], with the ranges of some channels already gathered (`known[c]`, in
    /// [`brick_ranges`]'s layout — the march lattice gathers its grids' as it copies them); the rest are
    /// computed here.
    pub(crate) fn with_ranges(
        ds: &Dataset,
        brick: usize,
        mut known: Vec<Option<Ranges>>,
    ) -> MajorantGrid {
        let brick = brick.max(1);
        let dims = ds.dims();
        let counts = dims.map(|n| n.div_ceil(brick));
        let channels = ds.channels().len();
        let nb = counts[0] * counts[1] * counts[2];
        // Per channel (in parallel), per brick: the range over the brick's voxels and the ring around it that
        // trilinear lookups inside it reach (and 0 where that reaches past the grid).
        known.resize(channels, None);
        let work: Vec<_> = ds.channels().iter().zip(known).collect();
        let per_channel = crate::dataset::par_map(work, |(ch, known)| match known {
            Some(r) if r.len() == nb => r,
            _ => grid_brick_ranges(&ch.grid, brick),
        });
        let mut ranges = vec![(0.0, 0.0); nb * channels];
        for (c, r) in per_channel.iter().enumerate() {
            for (i, &v) in r.iter().enumerate() {
                ranges[i * channels + c] = v;
            }
        }
        MajorantGrid {
            brick,
            counts,
            dims,
            bounds: ds.bounds(),
            channels,
            ranges,
        }
    }

    /// Bricks per axis.
    pub fn counts(&self) -> [usize; 3] {
        self.counts
    }
    /// The box the bricks tile (the dataset's bounds).
    pub fn bounds(&self) -> [DVec3; 2] {
        self.bounds
    }
    /// The edge of a brick in medium units, per axis (the last brick on an axis may be cut by the box).
    pub fn cell(&self) -> DVec3 {
        let dims = DVec3::new(
            self.dims[0] as f64,
            self.dims[1] as f64,
            self.dims[2] as f64,
        );
        (self.bounds[1] - self.bounds[0]) / dims * self.brick as f64
    }
    /// Voxels per brick edge.
    pub fn brick(&self) -> usize {
        self.brick
    }
    /// Largest value of `channel` that a lookup inside `brick` can return.
    pub fn max(&self, brick: usize, channel: usize) -> f32 {
        self.ranges[brick * self.channels + channel].1
    }
    /// Smallest value of `channel` that a lookup inside `brick` can return.
    pub fn min(&self, brick: usize, channel: usize) -> f32 {
        self.ranges[brick * self.channels + channel].0
    }
    /// Whether `channel` is zero throughout `brick` (empty space to skip).
    pub fn is_empty(&self, brick: usize, channel: usize) -> bool {
        self.max(brick, channel) <= 0.0 && self.min(brick, channel) >= 0.0
    }
    /// Bytes held.
    pub fn bytes(&self) -> usize {
        self.ranges.len() * std::mem::size_of::<(f32, f32)>()
    }

    /// The brick holding medium-space point `p`, if inside the bounds.
    pub fn brick_at(&self, p: DVec3) -> Option<usize> {
        let u = (p - self.bounds[0]) / (self.bounds[1] - self.bounds[0]);
        if !(u.cmpge(DVec3::ZERO).all() && u.cmple(DVec3::ONE).all()) {
            return None;
        }
        let c = [0, 1, 2].map(|a| {
            (((u[a] * self.dims[a] as f64) as usize) / self.brick).min(self.counts[a] - 1)
        });
        Some(c[0] + self.counts[0] * (c[1] + self.counts[1] * c[2]))
    }

    /// The pieces of the ray o + t·d, t ∈ [t0, t1], inside the bounds, one per brick crossed, in order; they
    /// tile [max(t0, t_enter), min(t1, t_exit)] exactly (each piece starts where the previous ended).
    pub fn segments(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Segments {
        walk(self.bounds, self.dims, self.brick, o, d, t0, t1)
    }
}

/// Per brick (x fastest), the (min, max) of one grid: [`brick_ranges`]'s layout.
pub(crate) type Ranges = Vec<(f32, f32)>;

/// [`brick_ranges`] of a sparse grid. A grid storing most of its bricks is read slab by slab (the vectorised
/// pass); a sparse one brick by brick: a brick whose widened range reaches only empty storage bricks takes their
/// background (and 0 where it leaves the grid) without reading a voxel, the others are read voxel by voxel. The
/// values are the same either way (tested against the dense pass).
pub(crate) fn grid_brick_ranges(g: &crate::grid::Grid, brick: usize) -> Ranges {
    let dims = g.dims();
    let topo = g.topology();
    let stored: usize = topo.bricks().iter().product();
    if topo.active_bricks().saturating_mul(4) >= stored {
        let [nx, ny, nz] = dims;
        let mut acc = BrickRanges::new(dims, brick, 0..nz);
        let mut slab = vec![0f32; nx * ny];
        for z in 0..nz {
            for y in 0..ny {
                g.row(y, z, &mut slab[nx * y..nx * (y + 1)]);
            }
            acc.add_slab(z, &slab);
        }
        return acc.finish();
    }
    let brick = brick.max(1);
    let counts = dims.map(|n| n.div_ceil(brick));
    let bg = g.background();
    let cell = |c: [usize; 3]| c[0] + counts[0] * (c[1] + counts[1] * c[2]);
    // The widened voxel range [lo, hi] of range brick `c` on each axis, inside the grid, and whether it
    // leaves the grid.
    let widened = |c: [usize; 3]| {
        let (mut lo, mut hi, mut outside) = ([0usize; 3], [0usize; 3], false);
        for a in 0..3 {
            let (l, h) = ((c[a] * brick) as i64 - 1, ((c[a] + 1) * brick) as i64);
            outside |= l < 0 || h >= dims[a] as i64;
            lo[a] = l.max(0) as usize;
            hi[a] = (h.min(dims[a] as i64 - 1)) as usize;
        }
        (lo, hi, outside)
    };
    // Per range brick that stored voxels reach: their (min, max) and count. Visited from the stored bricks,
    // so time follows the data, not the box (two far leaves cost two leaves).
    let mut reached: std::collections::HashMap<usize, (f32, f32, u64)> = Default::default();
    topo.for_each_slot(|b, _| {
        let span = [0, 1, 2].map(|a| topo.brick_span(b[a], a));
        // The range bricks whose widened range [c·brick − 1, (c + 1)·brick] meets the span [s0, s1).
        let first = span.map(|(s0, _)| s0.div_ceil(brick).saturating_sub(1));
        let last = [0, 1, 2].map(|a| (span[a].1 / brick).min(counts[a] - 1));
        for cz in first[2]..=last[2] {
            for cy in first[1]..=last[1] {
                for cx in first[0]..=last[0] {
                    let c = [cx, cy, cz];
                    let (lo, hi, _) = widened(c);
                    let a = [0, 1, 2].map(|k| lo[k].max(span[k].0));
                    let z = [0, 1, 2].map(|k| (hi[k] + 1).min(span[k].1));
                    if (0..3).any(|k| a[k] >= z[k]) {
                        continue;
                    }
                    let e = reached
                        .entry(cell(c))
                        .or_insert((f32::INFINITY, f32::NEG_INFINITY, 0));
                    for k in a[2]..z[2] {
                        for j in a[1]..z[1] {
                            for i in a[0]..z[0] {
                                let v = g.at(i as i64, j as i64, k as i64);
                                e.0 = if v < e.0 { v } else { e.0 };
                                e.1 = if v > e.1 { v } else { e.1 };
                            }
                        }
                    }
                    e.2 += ((z[0] - a[0]) * (z[1] - a[1]) * (z[2] - a[2])) as u64;
                }
            }
        }
    });
    let mut out = Vec::with_capacity(counts.iter().product());
    for cz in 0..counts[2] {
        for cy in 0..counts[1] {
            for cx in 0..counts[0] {
                let c = [cx, cy, cz];
                let (lo, hi, outside) = widened(c);
                let (mut mn, mut mx) = if outside {
                    (0.0f32, 0.0f32)
                } else {
                    (f32::INFINITY, f32::NEG_INFINITY)
                };
                let mut fold = |v: f32| {
                    mn = if v < mn { v } else { mn };
                    mx = if v > mx { v } else { mx };
                };
                let voxels = (0..3).map(|k| (hi[k] - lo[k] + 1) as u64).product::<u64>();
                match reached.get(&cell(c)) {
                    Some(&(a, b, n)) => {
                        fold(a);
                        fold(b);
                        // Voxels of the range in empty bricks read the background.
                        if n < voxels {
                            fold(bg);
                        }
                    }
                    None => fold(bg),
                }
                out.push((mn, mx));
            }
        }
    }
    out
}

/// The (min, max) of `g` (x fastest, `dims`) over each brick of `brick`³ voxels widened by one voxel on every side,
/// with 0 taken in where the widened brick reaches past the grid, bricks x fastest (see [`BrickRanges`]). Min and
/// max are exact, so the values are the brute force's (tested).
#[cfg(test)]
pub(crate) fn brick_ranges(g: &[f32], dims: [usize; 3], brick: usize) -> Ranges {
    let mut acc = BrickRanges::new(dims, brick, 0..dims[2]);
    for (z, slab) in g.chunks_exact(dims[0] * dims[1]).enumerate() {
        acc.add_slab(z, slab);
    }
    acc.finish()
}

/// The bricks' ranges of one grid, gathered a z-slab at a time (so that a pass which reads the slabs anyway —
/// the march lattice's build — gathers them without reading the grid again), separably: along y, row against
/// row, into the slab's (y-brick, x) ranges; those along z into the (z-brick, y-brick, x) ranges of the
/// z-bricks the slab belongs to; last, in [`BrickRanges::finish`], along x. The first two are elementwise over
/// whole rows, which vectorises. Slabs may come in any order and from several accumulators, merged.
pub(crate) struct BrickRanges {
    dims: [usize; 3],
    brick: usize,
    /// Bricks per axis.
    c: [usize; 3],
    /// The z-bricks held: `bz0..bz0 + (zlo.len() / (c[1]·nx))`.
    bz0: usize,
    /// Per held z-brick, per y-brick, per x: min and max so far.
    zlo: Vec<f32>,
    zhi: Vec<f32>,
    /// The current slab's per y-brick, per x range (scratch).
    ylo: Vec<f32>,
    yhi: Vec<f32>,
}

/// Elementwise running min of `lo` with `vlo` and max of `hi` with `vhi` (NaN skipped, as `f32::min` does).
#[inline]
fn fold_rows(lo: &mut [f32], hi: &mut [f32], vlo: &[f32], vhi: &[f32]) {
    for (((l, h), &a), &b) in lo.iter_mut().zip(hi.iter_mut()).zip(vlo).zip(vhi) {
        *l = if a < *l { a } else { *l };
        *h = if b > *h { b } else { *h };
    }
}

impl BrickRanges {
    /// An accumulator for the slabs `zs` (the z-bricks they reach are the ones held).
    pub(crate) fn new(dims: [usize; 3], brick: usize, zs: std::ops::Range<usize>) -> BrickRanges {
        let brick = brick.max(1);
        let c = dims.map(|n| n.div_ceil(brick));
        let bz0 = zs.start.saturating_sub(1) / brick;
        let bz1 = (zs.end / brick + 1).min(c[2]);
        let n = bz1.saturating_sub(bz0) * c[1] * dims[0];
        let (inf, ninf) = (f32::INFINITY, f32::NEG_INFINITY);
        BrickRanges {
            dims,
            brick,
            c,
            bz0,
            zlo: vec![inf; n],
            zhi: vec![ninf; n],
            ylo: vec![inf; c[1] * dims[0]],
            yhi: vec![ninf; c[1] * dims[0]],
        }
    }

    /// The voxel range [lo, hi] of brick `b` along an axis of `n` voxels, and whether it reaches past the grid.
    fn span(&self, b: usize, n: usize) -> (usize, usize, bool) {
        let lo = (b * self.brick) as i64 - 1;
        let hi = ((b + 1) * self.brick) as i64;
        let past = lo < 0 || hi >= n as i64;
        (lo.max(0) as usize, (hi.min(n as i64 - 1)) as usize, past)
    }

    /// Slab `z` of the grid (its nx·ny values, x fastest), which must lie in the range given to `new`.
    pub(crate) fn add_slab(&mut self, z: usize, slab: &[f32]) {
        let [nx, ny, nz] = self.dims;
        let n = self.c[1] * nx;
        self.ylo.fill(f32::INFINITY);
        self.yhi.fill(f32::NEG_INFINITY);
        for by in 0..self.c[1] {
            let (a, b, _) = self.span(by, ny);
            let (lo, hi) = (
                &mut self.ylo[by * nx..][..nx],
                &mut self.yhi[by * nx..][..nx],
            );
            for row in slab[a * nx..(b + 1) * nx].chunks_exact(nx) {
                fold_rows(lo, hi, row, row);
            }
        }
        // The z-bricks whose widened range holds slab z: its own, and a neighbour when z is on a boundary.
        let own = z / self.brick;
        for bz in own.saturating_sub(1)..=(own + 1).min(self.c[2] - 1) {
            let (a, b, _) = self.span(bz, nz);
            let Some(k) = bz.checked_sub(self.bz0) else {
                continue;
            };
            if (a..=b).contains(&z) && (k + 1) * n <= self.zlo.len() {
                let at = k * n;
                fold_rows(
                    &mut self.zlo[at..][..n],
                    &mut self.zhi[at..][..n],
                    &self.ylo,
                    &self.yhi,
                );
            }
        }
    }

    /// Takes in another accumulator's slabs (of the same grid).
    pub(crate) fn merge(&mut self, other: &BrickRanges) {
        let n = self.c[1] * self.dims[0];
        let held = |r: &BrickRanges| r.bz0..r.bz0 + r.zlo.len() / n.max(1);
        for bz in held(other) {
            if let (Some(k), Some(ko)) = (bz.checked_sub(self.bz0), bz.checked_sub(other.bz0)) {
                if (k + 1) * n <= self.zlo.len() {
                    let (at, ao) = (k * n, ko * n);
                    fold_rows(
                        &mut self.zlo[at..][..n],
                        &mut self.zhi[at..][..n],
                        &other.zlo[ao..][..n],
                        &other.zhi[ao..][..n],
                    );
                }
            }
        }
    }

    /// The bricks' (min, max), bricks x fastest: along x, and 0 where the widened brick reaches past the grid
    /// on any axis. (An accumulator that holds every z-brick: made for all slabs, or merged into.)
    pub(crate) fn finish(self) -> Ranges {
        let [nx, ny, nz] = self.dims;
        let c = self.c;
        let mut out = vec![(f32::INFINITY, f32::NEG_INFINITY); c[2] * c[1] * c[0]];
        for bz in 0..c[2] {
            let past_z = self.span(bz, nz).2;
            for by in 0..c[1] {
                let past_y = self.span(by, ny).2;
                let dst = &mut out[(bz * c[1] + by) * c[0]..][..c[0]];
                let at = (bz.wrapping_sub(self.bz0) * c[1] + by) * nx;
                let (Some(lo), Some(hi)) = (self.zlo.get(at..at + nx), self.zhi.get(at..at + nx))
                else {
                    continue;
                };
                for (bx, o) in dst.iter_mut().enumerate() {
                    let (a, b, past_x) = self.span(bx, nx);
                    if past_z || past_y || past_x {
                        *o = (0.0, 0.0);
                    }
                    for x in a..=b {
                        o.0 = if lo[x] < o.0 { lo[x] } else { o.0 };
                        o.1 = if hi[x] > o.1 { hi[x] } else { o.1 };
                    }
                }
            }
        }
        out
    }
}

/// The cells of `brick`³ voxels (the last one per axis may be partial) that the ray o + t·d, t ∈ [t0, t1],
/// crosses inside the box of a `dims` lattice, in order (Amanatides & Woo); the pieces tile the clipped ray
/// exactly. `brick` = 1 walks single voxels.
pub fn walk(
    bounds: [DVec3; 2],
    dims: [usize; 3],
    brick: usize,
    o: DVec3,
    d: DVec3,
    t0: f64,
    t1: f64,
) -> Segments {
    let [p0, p1] = bounds;
    let brick = brick.max(1);
    let counts = dims.map(|n| n.div_ceil(brick));
    let (tmin, tmax) = clip_box(o, d, t0, t1, p0, p1).unwrap_or((0.0, f64::NEG_INFINITY));
    let mut s = Segments {
        t: tmin,
        tmax,
        cell: [0; 3],
        step: [0; 3],
        next: [f64::INFINITY; 3],
        delta: [0.0; 3],
        counts,
        done: !(tmin < tmax),
    };
    if s.done {
        return s;
    }
    // Cell coordinates: cells per medium unit on each axis.
    let scale = [0, 1, 2].map(|a| dims[a] as f64 / brick as f64 / (p1[a] - p0[a]));
    for a in 0..3 {
        let ob = (o[a] - p0[a]) * scale[a];
        let db = d[a] * scale[a];
        let pos = ob + db * tmin;
        s.cell[a] = (pos.floor().max(0.0) as i64).min(counts[a] as i64 - 1);
        if db > 0.0 {
            s.step[a] = 1;
            s.next[a] = (s.cell[a] as f64 + 1.0 - ob) / db;
            s.delta[a] = 1.0 / db;
        } else if db < 0.0 {
            s.step[a] = -1;
            s.next[a] = (s.cell[a] as f64 - ob) / db;
            s.delta[a] = -1.0 / db;
        }
    }
    s
}

/// Iterator over a ray's bricks (see [`MajorantGrid::segments`]).
#[derive(Debug, Clone)]
pub struct Segments {
    t: f64,
    tmax: f64,
    cell: [i64; 3],
    step: [i64; 3],
    next: [f64; 3],
    delta: [f64; 3],
    counts: [usize; 3],
    done: bool,
}

impl Iterator for Segments {
    type Item = Segment;
    fn next(&mut self) -> Option<Segment> {
        while !self.done {
            // The axis whose boundary comes first (ties to the later axis, as before), by selects rather than
            // branches: along a ray the axis changes at nearly every brick, too irregularly to predict.
            let [n0, n1, n2] = self.next;
            let b1 = n1 <= n0;
            let (m, am) = if b1 { (n1, 1) } else { (n0, 0) };
            let a = if n2 <= m { 2 } else { am };
            let cell = self.cell.map(|c| c as usize);
            let brick = cell[0] + self.counts[0] * (cell[1] + self.counts[1] * cell[2]);
            let mut t_end = self.next[a].min(self.tmax);
            let stepped = self.cell[a] + self.step[a];
            let leaves = stepped < 0 || stepped >= self.counts[a] as i64;
            if t_end >= self.tmax || leaves {
                // Last brick: it runs to the exit, so the pieces tile the clipped ray exactly.
                t_end = self.tmax;
                self.done = true;
            } else {
                self.cell[a] = stepped;
                self.next[a] += self.delta[a];
            }
            let t0 = self.t;
            self.t = t_end;
            if t_end > t0 {
                return Some(Segment {
                    t0,
                    t1: t_end,
                    brick,
                    cell,
                });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dataset::{Dataset, LoadOptions};

    #[test]
    fn sparse_majorants_bound_the_data_as_the_dense_pass_does() {
        // The brick-by-brick ranges of a sparse grid equal the dense slab pass's, brick for brick, at several
        // majorant brick sizes; so every majorant is ≥ the data (the dense pass is tested against brute force).
        use crate::grid::{Grid, Topology};
        for (t, (dims, off)) in [([37usize, 41, 39], [5, 2, 6]), ([9, 64, 45], [5, 2, 6])]
            .into_iter()
            .enumerate()
        {
            // One storage brick in ten kept (few enough to take the brick-by-brick path), random values in them.
            let mut rng = Rng::new(7 + t as u64);
            let probe = Topology::build_offset(dims, off, |_| false).unwrap();
            let nb = probe.bricks();
            let keep: Vec<bool> = (0..nb.iter().product::<usize>())
                .map(|_| rng.next() < 0.1)
                .collect();
            let kept = |b: [usize; 3]| keep[b[0] + nb[0] * (b[1] + nb[1] * b[2])];
            let mut d = vec![0f32; dims.iter().product()];
            for k in 0..dims[2] {
                for j in 0..dims[1] {
                    for i in 0..dims[0] {
                        if kept(probe.brick_of([i, j, k])) {
                            d[i + dims[0] * (j + dims[1] * k)] = rng.range(0.0, 3.0) as f32;
                        }
                    }
                }
            }
            let topo = Topology::build_offset(dims, off, kept).unwrap();
            let sparse = Grid::from_dense(std::sync::Arc::new(topo), &d, 0.0).unwrap();
            let stored: usize = sparse.topology().bricks().iter().product();
            assert!(sparse.topology().active_bricks() * 4 < stored);
            for brick in [1, 4, 8, 16] {
                let want = brick_ranges(&d, dims, brick);
                let got = grid_brick_ranges(&sparse, brick);
                assert_eq!(got, want, "dims {dims:?} brick {brick}");
            }
        }
    }

    /// The crate's generator with a uniform range, for property tests.
    struct Rng(crate::rng::Rng);
    impl Rng {
        fn new(seed: u64) -> Rng {
            Rng(crate::rng::Rng::new(seed))
        }
        fn next(&mut self) -> f64 {
            self.0.next_f64()
        }
        fn range(&mut self, a: f64, b: f64) -> f64 {
            a + (b - a) * self.next()
        }
    }

    fn blob(dims: [usize; 3]) -> Dataset {
        // A bumpy field with sharp jumps, so widening matters.
        let mut v = Vec::new();
        for k in 0..dims[2] {
            for j in 0..dims[1] {
                for i in 0..dims[0] {
                    let x = (i as f32 * 0.37).sin() * (j as f32 * 0.21).cos()
                        + ((k * 7 + i * 3) % 11) as f32 * 0.1;
                    v.push(if (i + j + k) % 13 == 0 {
                        5.0
                    } else {
                        x.max(0.0)
                    });
                }
            }
        }
        let dens = v.clone();
        let temp: Vec<f32> = v.iter().map(|x| 300.0 + 500.0 * x).collect();
        Dataset::from_inline(
            dims,
            DVec3::new(-1.0, 0.0, 2.0),
            DVec3::new(1.0, 1.5, 3.0),
            &[("density", &dens), ("temperature", &temp)],
            &LoadOptions::default(),
        )
        .unwrap()
    }

    #[test]
    fn separable_brick_ranges_equal_the_brute_force() {
        // Each brick's 10³ neighbourhood read directly (the build before session 5) against the separable passes
        // (whole, and split between accumulators):
        // odd sizes, a brick larger than the grid, 1-voxel and 1 × 1 × N grids, zeros and negative values.
        let mut rng = crate::rng::Rng::new(5);
        for (dims, brick) in [
            ([13usize, 9, 11], 4usize),
            ([13, 9, 11], 8),
            ([13, 9, 11], 3),
            ([5, 6, 7], 16),
            ([1, 1, 1], 8),
            ([1, 1, 30], 4),
            ([17, 1, 2], 1),
        ] {
            let n = dims[0] * dims[1] * dims[2];
            let g: Vec<f32> = (0..n)
                .map(|_| {
                    let u = rng.next_f64();
                    if u < 0.3 {
                        0.0
                    } else {
                        (u as f32 - 0.4) * 7.0
                    }
                })
                .collect();
            let c = dims.map(|d| d.div_ceil(brick));
            let mut brute = Vec::new();
            for bz in 0..c[2] {
                for by in 0..c[1] {
                    for bx in 0..c[0] {
                        let b = [bx, by, bz];
                        let lo = b.map(|v| (v * brick) as i64 - 1);
                        let hi = [0, 1, 2].map(|a| ((b[a] + 1) * brick) as i64);
                        let (mut mn, mut mx) = (f32::INFINITY, f32::NEG_INFINITY);
                        if (0..3).any(|a| lo[a] < 0 || hi[a] >= dims[a] as i64) {
                            (mn, mx) = (0.0, 0.0);
                        }
                        for z in lo[2].max(0)..=hi[2].min(dims[2] as i64 - 1) {
                            for y in lo[1].max(0)..=hi[1].min(dims[1] as i64 - 1) {
                                for x in lo[0].max(0)..=hi[0].min(dims[0] as i64 - 1) {
                                    let v = g[x as usize
                                        + dims[0] * (y as usize + dims[1] * z as usize)];
                                    mn = mn.min(v);
                                    mx = mx.max(v);
                                }
                            }
                        }
                        brute.push((mn, mx));
                    }
                }
            }
            assert_eq!(
                brick_ranges(&g, dims, brick),
                brute,
                "{dims:?}, brick {brick}"
            );
            // The slabs split between accumulators at every cut (as the lattice's threads do), then merged.
            let slab = dims[0] * dims[1];
            for cut in 0..=dims[2] {
                let mut a = BrickRanges::new(dims, brick, 0..cut);
                let mut b = BrickRanges::new(dims, brick, cut..dims[2]);
                for z in (0..dims[2]).rev() {
                    let acc = if z < cut { &mut a } else { &mut b };
                    acc.add_slab(z, &g[z * slab..][..slab]);
                }
                let mut all = BrickRanges::new(dims, brick, 0..dims[2]);
                all.merge(&b);
                all.merge(&a);
                assert_eq!(all.finish(), brute, "{dims:?}, brick {brick}, cut {cut}");
            }
        }
    }

    #[test]
    fn majorant_bounds_every_trilinear_sample() {
        // 1e5 random points: min ≤ sample ≤ max of the brick holding the point (shared/data: property test).
        let ds = blob([37, 20, 29]);
        for brick in [1, 4, 16] {
            let m = MajorantGrid::build(&ds, brick);
            let mut rng = Rng::new(brick as u64);
            let [p0, p1] = ds.bounds();
            for _ in 0..100_000 / 3 {
                let p = DVec3::new(
                    rng.range(p0.x, p1.x),
                    rng.range(p0.y, p1.y),
                    rng.range(p0.z, p1.z),
                );
                let b = m.brick_at(p).unwrap();
                for c in 0..2 {
                    let v = ds.sample(c, p);
                    assert!(
                        v <= m.max(b, c) && v >= m.min(b, c),
                        "brick {brick}: {v} not in [{}, {}] at {p}",
                        m.min(b, c),
                        m.max(b, c)
                    );
                }
            }
        }
    }

    #[test]
    fn segments_tile_the_clipped_ray_exactly() {
        let ds = blob([37, 20, 29]);
        let m = MajorantGrid::build(&ds, 8);
        let [p0, p1] = ds.bounds();
        let mut rng = Rng::new(7);
        let mut crossed = 0;
        for n in 0..20_000 {
            let o = DVec3::new(
                rng.range(-3.0, 3.0),
                rng.range(-1.0, 2.5),
                rng.range(1.0, 4.0),
            );
            let mut d = DVec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            // Some rays parallel to axes or planes.
            if n % 7 == 0 {
                d.x = 0.0;
            }
            if n % 11 == 0 {
                d.y = 0.0;
                d.z = 0.0;
                d.x = if d.x == 0.0 { 1.0 } else { d.x };
            }
            let (t0, t1) = (rng.range(-1.0, 1.0), rng.range(1.0, 10.0));
            let segs: Vec<Segment> = m.segments(o, d, t0, t1).collect();
            // The analytic clip.
            let (mut a, mut b) = (t0, t1);
            for k in 0..3 {
                if d[k] == 0.0 {
                    if !(o[k] >= p0[k] && o[k] <= p1[k]) {
                        b = f64::NEG_INFINITY;
                    }
                } else {
                    let (ta, tb) = ((p0[k] - o[k]) / d[k], (p1[k] - o[k]) / d[k]);
                    a = a.max(ta.min(tb));
                    b = b.min(ta.max(tb));
                }
            }
            if !(a < b) {
                assert!(segs.is_empty());
                continue;
            }
            crossed += 1;
            assert_eq!(segs.first().unwrap().t0, a);
            assert_eq!(segs.last().unwrap().t1, b);
            for w in segs.windows(2) {
                assert_eq!(w[0].t1, w[1].t0);
                assert_ne!(w[0].brick, w[1].brick);
            }
            for s in &segs {
                assert!(s.t1 > s.t0);
                // The midpoint lies in the claimed brick (or on its boundary within rounding).
                let mid = o + d * (0.5 * (s.t0 + s.t1));
                let b = m.brick_at(mid.clamp(p0, p1)).unwrap();
                if b != s.brick {
                    let len = (s.t1 - s.t0) * d.length();
                    assert!(
                        len < 1e-9,
                        "ray {n}: midpoint in brick {b}, segment says {} (len {len})",
                        s.brick
                    );
                }
            }
        }
        assert!(crossed > 2000, "{crossed}");
    }

    #[test]
    fn rays_inside_grazing_and_missing() {
        let ds = blob([16, 16, 16]);
        let m = MajorantGrid::build(&ds, 4);
        // Starting inside, along +x: from t = 0 to the far face.
        let segs: Vec<Segment> = m
            .segments(DVec3::new(0.0, 0.75, 2.5), DVec3::X, 0.0, 100.0)
            .collect();
        assert_eq!(segs.first().unwrap().t0, 0.0);
        assert_eq!(segs.last().unwrap().t1, 1.0);
        assert_eq!(segs.len(), 2);
        // Missing entirely.
        assert_eq!(
            m.segments(DVec3::new(5.0, 5.0, 5.0), DVec3::X, 0.0, 100.0)
                .count(),
            0
        );
        // Grazing the face y = 0 along x.
        let g: Vec<Segment> = m
            .segments(DVec3::new(-2.0, 0.0, 2.5), DVec3::X, 0.0, 100.0)
            .collect();
        assert_eq!((g.first().unwrap().t0, g.last().unwrap().t1), (1.0, 3.0));
        // Along an edge.
        assert_eq!(
            m.segments(DVec3::new(-2.0, 0.0, 2.0), DVec3::X, 0.0, 100.0)
                .count(),
            4
        );
        // Zero direction, NaN direction: nothing, no panic.
        assert_eq!(
            m.segments(DVec3::new(0.0, 0.5, 2.5), DVec3::ZERO, 0.0, 1.0)
                .count(),
            1
        );
        assert_eq!(
            m.segments(DVec3::new(0.0, 0.5, 2.5), DVec3::NAN, 0.0, 1.0)
                .count(),
            0
        );
    }

    #[test]
    fn empty_bricks_and_one_voxel_grids() {
        let mut v = vec![0.0f32; 32 * 32 * 32];
        v[5 + 32 * (5 + 32 * 5)] = 1.0;
        let ds = Dataset::from_inline(
            [32, 32, 32],
            DVec3::ZERO,
            DVec3::ONE,
            &[("density", &v)],
            &LoadOptions::default(),
        )
        .unwrap();
        let m = MajorantGrid::build(&ds, 16);
        assert_eq!(m.counts(), [2, 2, 2]);
        assert!(!m.is_empty(0, 0));
        assert!((1..8).all(|b| m.is_empty(b, 0)));
        let one = Dataset::from_inline(
            [1, 1, 1],
            DVec3::ZERO,
            DVec3::ONE,
            &[("density", &[2.0])],
            &LoadOptions::default(),
        )
        .unwrap();
        let m = MajorantGrid::build(&one, 16);
        assert_eq!((m.min(0, 0), m.max(0, 0)), (0.0, 2.0));
        assert_eq!(
            m.segments(DVec3::new(0.5, 0.5, -1.0), DVec3::Z, 0.0, 10.0)
                .count(),
            1
        );
        let thin = Dataset::from_inline(
            [1, 1, 40],
            DVec3::ZERO,
            DVec3::ONE,
            &[("density", &[1.0; 40])],
            &LoadOptions::default(),
        )
        .unwrap();
        let m = MajorantGrid::build(&thin, 16);
        assert_eq!(m.counts(), [1, 1, 3]);
        let s: Vec<Segment> = m
            .segments(DVec3::new(0.5, 0.5, -1.0), DVec3::Z, 0.0, 10.0)
            .collect();
        assert_eq!(s.len(), 3);
        assert!((s[0].t1 - (1.0 + 16.0 / 40.0)).abs() < 1e-12);
    }
}
