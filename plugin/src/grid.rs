//! Dense scalar grids and their lookup, in pbrt-v4's convention.
//!
//! A [`Grid`] holds nx·ny·nz `f32` samples, x fastest (`x + nx·(y + ny·z)`), at the **cell centres** of an
//! nx × ny × nz subdivision of the unit cube: sample (i, j, k) sits at ((i, j, k) + 0.5) / (nx, ny, nz).
//! Lookups take a point in [0, 1]³ (the dataset maps medium space to it).
//!
//! - [`Interpolation::Trilinear`] (default): pbrt-v4's `SampledGrid::Lookup` — the eight samples around
//!   p·n − 0.5, each sample outside the grid counting as **zero**. So within the last half voxel of every face
//!   the value fades linearly from the edge sample toward zero, reaching half the edge sample exactly on the
//!   bounds; beyond the bounds it is zero.
//! - [`Interpolation::Nearest`]: the sample whose cell holds p; zero outside [0, 1]³.

/// ⌊x⌋ without the libm call `f64::floor` makes on baseline x86-64 (no rounding instruction before SSE4.1),
/// exact for |x| < 2⁶³ — grid coordinates, which lookups have checked to lie within a few voxels of the grid.
#[inline(always)]
pub(crate) fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x {
        t - 1.0
    } else {
        t
    }
}

/// How a grid is sampled between its samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Trilinear between cell centres, zero outside (pbrt-v4).
    #[default]
    Trilinear,
    /// Value of the cell holding the point.
    Nearest,
}

/// Summary statistics of a grid's samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct GridStats {
    /// Smallest sample.
    pub min: f32,
    /// Largest sample.
    pub max: f32,
    /// Mean over all samples (f64 accumulation).
    pub mean: f64,
    /// Fraction of samples that are non-zero.
    pub nonzero_fraction: f64,
}

/// Up to eight samples and weights that interpolate any grid of the same dims at one point (all channels of a
/// dataset share their lattice, so the weights are computed once per point).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Stencil {
    idx: [usize; 8],
    w: [f32; 8],
    n: usize,
}

impl Stencil {
    /// The stencil of `p` in [0, 1]³ on a grid of `dims`; `None` outside the bounds (value zero).
    pub fn new(dims: [usize; 3], p: [f64; 3], interp: Interpolation) -> Option<Stencil> {
        Stencil::with_margin(dims, p, interp, 0.0)
    }

    /// As [`Stencil::new`], but trilinear lookups continue `margin` voxels beyond the bounds, fading toward the
    /// zero outside (NanoVDB's sampler does this up to the next voxel centre).
    #[inline(always)]
    pub fn with_margin(
        dims: [usize; 3],
        p: [f64; 3],
        interp: Interpolation,
        margin: f64,
    ) -> Option<Stencil> {
        for a in 0..3 {
            let m = margin / dims[a] as f64;
            if !(p[a] >= -m && p[a] <= 1.0 + m) {
                return None;
            }
        }
        if interp == Interpolation::Trilinear {
            let (base, frac) = Stencil::cell(dims, p);
            // Inside (all eight samples in the grid, the common case): the weights and indices directly, in
            // the same corner order and products as the general path (so the same sums, bit for bit: the zero
            // weights it leaves out add +0).
            if (0..3).all(|a| base[a] >= 0 && base[a] + 1 < dims[a] as i64) {
                let [nx, ny, _] = dims;
                let [fx, fy, fz] = frac;
                let [gx, gy, gz] = frac.map(|f| 1.0 - f);
                let i0 = base[0] as usize + nx * (base[1] as usize + ny * base[2] as usize);
                let (sy, sz) = (nx, nx * ny);
                return Some(Stencil {
                    idx: [
                        i0,
                        i0 + 1,
                        i0 + sy,
                        i0 + sy + 1,
                        i0 + sz,
                        i0 + sz + 1,
                        i0 + sz + sy,
                        i0 + sz + sy + 1,
                    ],
                    w: [
                        gx * gy * gz,
                        fx * gy * gz,
                        gx * fy * gz,
                        fx * fy * gz,
                        gx * gy * fz,
                        fx * gy * fz,
                        gx * fy * fz,
                        fx * fy * fz,
                    ],
                    n: 8,
                });
            }
        }
        Some(Stencil::general(dims, p, interp))
    }

    /// The trilinear cell of `p`: the lower corner's sample index and the fractions toward the upper one.
    #[inline(always)]
    fn cell(dims: [usize; 3], p: [f64; 3]) -> ([i64; 3], [f32; 3]) {
        let mut base = [0i64; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            let s = p[a] * dims[a] as f64 - 0.5;
            let f = floor(s);
            base[a] = f as i64;
            frac[a] = (s - f) as f32;
        }
        (base, frac)
    }

    /// The stencil near the grid's faces (samples outside count as zero) and for nearest lookups.
    #[inline(never)]
    fn general(dims: [usize; 3], p: [f64; 3], interp: Interpolation) -> Stencil {
        let p = if interp == Interpolation::Nearest {
            p.map(|x| x.clamp(0.0, 1.0))
        } else {
            p
        };
        let [nx, ny, nz] = dims;
        let mut st = Stencil::default();
        match interp {
            Interpolation::Nearest => {
                let i = [0, 1, 2].map(|a| ((p[a] * dims[a] as f64) as usize).min(dims[a] - 1));
                st.idx[0] = i[0] + nx * (i[1] + ny * i[2]);
                st.w[0] = 1.0;
                st.n = 1;
            }
            Interpolation::Trilinear => {
                let (base, frac) = Stencil::cell(dims, p);
                for corner in 0..8 {
                    let o = [corner & 1, (corner >> 1) & 1, corner >> 2];
                    let q = [0, 1, 2].map(|a| base[a] + o[a] as i64);
                    let w = (0..3)
                        .map(|a| if o[a] == 1 { frac[a] } else { 1.0 - frac[a] })
                        .product::<f32>();
                    if w != 0.0
                        && q[0] >= 0
                        && q[1] >= 0
                        && q[2] >= 0
                        && q[0] < nx as i64
                        && q[1] < ny as i64
                        && q[2] < nz as i64
                    {
                        st.idx[st.n] = q[0] as usize + nx * (q[1] as usize + ny * q[2] as usize);
                        st.w[st.n] = w;
                        st.n += 1;
                    }
                }
            }
        }
        st
    }
}

/// A dense scalar grid, x fastest, cell-centred.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    dims: [usize; 3],
    data: Vec<f32>,
}

impl Grid {
    /// A grid of `dims` from `data` (len must equal the product; the caller validated it, so a mismatch is a
    /// logic error and returns `None`).
    pub fn new(dims: [usize; 3], data: Vec<f32>) -> Option<Grid> {
        let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d))?;
        (n == data.len() && n > 0).then_some(Grid { dims, data })
    }

    /// (nx, ny, nz).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// The samples, x fastest.
    pub fn data(&self) -> &[f32] {
        &self.data
    }
    /// Mutable samples (for policies and mappings applied at load time).
    pub(crate) fn data_mut(&mut self) -> &mut [f32] {
        &mut self.data
    }
    /// Bytes held by the samples.
    pub fn bytes(&self) -> usize {
        self.data.len() * std::mem::size_of::<f32>()
    }

    /// Sample (i, j, k) with signed indices; zero outside the grid.
    #[inline]
    pub fn at(&self, i: i64, j: i64, k: i64) -> f32 {
        let [nx, ny, nz] = self.dims;
        if i < 0 || j < 0 || k < 0 || i >= nx as i64 || j >= ny as i64 || k >= nz as i64 {
            return 0.0;
        }
        self.data[i as usize + nx * (j as usize + ny * k as usize)]
    }

    /// Value at `p` in [0, 1]³ (see the module docs for the convention at the bounds).
    #[inline]
    pub fn lookup(&self, p: [f64; 3], interp: Interpolation) -> f32 {
        match interp {
            Interpolation::Trilinear => self.trilinear(p),
            Interpolation::Nearest => self.nearest(p),
        }
    }

    fn nearest(&self, p: [f64; 3]) -> f32 {
        if !(0.0..=1.0).contains(&p[0])
            || !(0.0..=1.0).contains(&p[1])
            || !(0.0..=1.0).contains(&p[2])
        {
            return 0.0;
        }
        let idx = |a: usize| ((p[a] * self.dims[a] as f64) as i64).min(self.dims[a] as i64 - 1);
        self.at(idx(0), idx(1), idx(2))
    }

    fn trilinear(&self, p: [f64; 3]) -> f32 {
        // Continuous sample coordinates; NaN or far-away points are outside.
        let mut base = [0i64; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            // Outside the bounds (and NaN): zero, as pbrt's rays are clipped to the medium's box.
            if !(0.0..=1.0).contains(&p[a]) {
                return 0.0;
            }
            let s = p[a] * self.dims[a] as f64 - 0.5;
            let f = floor(s);
            base[a] = f as i64;
            frac[a] = (s - f) as f32;
        }
        let [i, j, k] = base;
        let [fx, fy, fz] = frac;
        let lerp = |a: f32, b: f32, t: f32| a + t * (b - a);
        let c00 = lerp(self.at(i, j, k), self.at(i + 1, j, k), fx);
        let c10 = lerp(self.at(i, j + 1, k), self.at(i + 1, j + 1, k), fx);
        let c01 = lerp(self.at(i, j, k + 1), self.at(i + 1, j, k + 1), fx);
        let c11 = lerp(self.at(i, j + 1, k + 1), self.at(i + 1, j + 1, k + 1), fx);
        lerp(lerp(c00, c10, fy), lerp(c01, c11, fy), fz)
    }

    /// The value a [`Stencil`] computed for this grid's dims interpolates.
    #[inline(always)]
    pub fn eval(&self, st: &Stencil) -> f32 {
        if st.n == 8 {
            // (The same sum, in the same order, unrolled.)
            let mut v = 0.0f32;
            for k in 0..8 {
                v += st.w[k] * self.data[st.idx[k]];
            }
            return v;
        }
        (0..st.n).map(|k| st.w[k] * self.data[st.idx[k]]).sum()
    }

    /// Min, max, mean and non-zero fraction of the samples.
    pub fn stats(&self) -> GridStats {
        let mut acc = StatsAcc::new();
        let chunks = self.data.chunks_exact(STATS_LANES);
        let rest = chunks.remainder();
        for c in chunks {
            if let Ok(c) = c.try_into() {
                acc.add_lanes(c);
            }
        }
        for &v in rest {
            acc.add(v);
        }
        acc.finish()
    }
}

/// Lanes of [`StatsAcc`].
pub(crate) const STATS_LANES: usize = 8;

/// Running grid statistics in eight lanes (running minima, maxima, sums and counts, so that a loop over groups
/// of eight vectorises; min and max skip NaN, as `f32::min` does: a comparison with NaN is false).
pub(crate) struct StatsAcc {
    lo: [f32; STATS_LANES],
    hi: [f32; STATS_LANES],
    sums: [f64; STATS_LANES],
    counts: [u64; STATS_LANES],
    n: u64,
}

impl StatsAcc {
    pub(crate) fn new() -> StatsAcc {
        StatsAcc {
            lo: [f32::INFINITY; STATS_LANES],
            hi: [f32::NEG_INFINITY; STATS_LANES],
            sums: [0.0; STATS_LANES],
            counts: [0; STATS_LANES],
            n: 0,
        }
    }
    /// Eight samples.
    #[inline]
    pub(crate) fn add_lanes(&mut self, c: &[f32; STATS_LANES]) {
        for k in 0..STATS_LANES {
            let v = c[k];
            self.lo[k] = if v < self.lo[k] { v } else { self.lo[k] };
            self.hi[k] = if v > self.hi[k] { v } else { self.hi[k] };
            self.sums[k] += v as f64;
            self.counts[k] += (v != 0.0) as u64;
        }
        self.n += STATS_LANES as u64;
    }
    /// One sample.
    #[inline]
    pub(crate) fn add(&mut self, v: f32) {
        self.lo[0] = if v < self.lo[0] { v } else { self.lo[0] };
        self.hi[0] = if v > self.hi[0] { v } else { self.hi[0] };
        self.sums[0] += v as f64;
        self.counts[0] += (v != 0.0) as u64;
        self.n += 1;
    }
    pub(crate) fn finish(&self) -> GridStats {
        let n = self.n.max(1) as f64;
        GridStats {
            min: self.lo.iter().fold(f32::INFINITY, |m, &v| m.min(v)),
            max: self.hi.iter().fold(f32::NEG_INFINITY, |m, &v| m.max(v)),
            mean: self.sums.iter().sum::<f64>() / n,
            nonzero_fraction: self.counts.iter().sum::<u64>() as f64 / n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_matches_libm() {
        for x in [
            -3.5,
            -3.0,
            -2.9999999,
            -0.5,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.5,
            1.0,
            2.9999999,
            3.0,
            1e15 + 0.5,
        ] {
            assert_eq!(floor(x), f64::floor(x), "x = {x}");
        }
    }

    fn ramp() -> Grid {
        // v = i + 10 j + 100 k on 4×3×2.
        let mut d = Vec::new();
        for k in 0..2 {
            for j in 0..3 {
                for i in 0..4 {
                    d.push((i + 10 * j + 100 * k) as f32);
                }
            }
        }
        Grid::new([4, 3, 2], d).unwrap()
    }

    #[test]
    fn x_fastest_layout() {
        let g = ramp();
        assert_eq!(g.at(3, 0, 0), 3.0);
        assert_eq!(g.at(0, 2, 0), 20.0);
        assert_eq!(g.at(1, 1, 1), 111.0);
        assert_eq!(g.at(4, 0, 0), 0.0);
        assert_eq!(g.at(-1, 0, 0), 0.0);
        assert!(Grid::new([2, 2, 2], vec![0.0; 7]).is_none());
        assert!(Grid::new([usize::MAX, 2, 2], vec![]).is_none());
    }

    #[test]
    fn trilinear_reproduces_samples_and_linear_fields() {
        let g = ramp();
        // At cell centres the sample itself.
        let c = |i: f64, j: f64, k: f64| [(i + 0.5) / 4.0, (j + 0.5) / 3.0, (k + 0.5) / 2.0];
        assert_eq!(g.lookup(c(2.0, 1.0, 1.0), Interpolation::Trilinear), 112.0);
        // Between centres, exactly linear (the field is linear).
        let v = g.lookup(c(1.25, 0.5, 0.5), Interpolation::Trilinear);
        assert!((v - (1.25 + 5.0 + 50.0)).abs() < 1e-4, "{v}");
    }

    #[test]
    fn last_half_voxel_fades_to_half_at_the_bounds() {
        // pbrt convention: on the face the value is half the edge sample; outside, zero.
        let g = Grid::new([2, 1, 1], vec![4.0, 8.0]).unwrap();
        let y = 0.5;
        let z = 0.5;
        // y, z at the single centre: the x profile.
        assert_eq!(g.lookup([1.0, y, z], Interpolation::Trilinear), 4.0);
        assert_eq!(g.lookup([0.0, y, z], Interpolation::Trilinear), 2.0);
        assert_eq!(g.lookup([0.75, y, z], Interpolation::Trilinear), 8.0);
        assert_eq!(g.lookup([1.0001, y, z], Interpolation::Trilinear), 0.0);
        assert_eq!(g.lookup([f64::NAN, y, z], Interpolation::Trilinear), 0.0);
        // Along y (one sample): at the centre 4, at the face 2 (x at sample 0's centre).
        assert_eq!(g.lookup([0.25, 0.0, 0.5], Interpolation::Trilinear), 2.0);
    }

    #[test]
    fn nearest_picks_the_cell() {
        let g = ramp();
        assert_eq!(g.lookup([0.99, 0.99, 0.99], Interpolation::Nearest), 123.0);
        assert_eq!(g.lookup([1.0, 1.0, 1.0], Interpolation::Nearest), 123.0);
        assert_eq!(g.lookup([0.0, 0.0, 0.0], Interpolation::Nearest), 0.0);
        assert_eq!(g.lookup([0.26, 0.0, 0.0], Interpolation::Nearest), 1.0);
        assert_eq!(g.lookup([1.1, 0.0, 0.0], Interpolation::Nearest), 0.0);
    }

    #[test]
    fn stencil_agrees_with_lookup() {
        let g = ramp();
        let mut x = 0.013;
        for _ in 0..2000 {
            x = (x * 3.7 + 0.123) % 1.0;
            let p = [x, (x * 7.1) % 1.0, (x * 13.3) % 1.0];
            for interp in [Interpolation::Trilinear, Interpolation::Nearest] {
                let st = Stencil::new(g.dims(), p, interp).unwrap();
                assert!((g.eval(&st) - g.lookup(p, interp)).abs() < 1e-4, "{p:?}");
            }
        }
        assert!(Stencil::new(g.dims(), [1.5, 0.5, 0.5], Interpolation::Trilinear).is_none());
    }

    #[test]
    fn stats() {
        let s = ramp().stats();
        assert_eq!((s.min, s.max), (0.0, 123.0));
        assert!((s.mean - 61.5).abs() < 1e-12);
        assert!((s.nonzero_fraction - 23.0 / 24.0).abs() < 1e-12);
    }
}
