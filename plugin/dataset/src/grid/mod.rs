//! Sparse scalar grids and their lookup, in pbrt-v4's convention.
//!
//! A [`Grid`] holds the samples of an nx × ny × nz lattice at the **cell centres** of a subdivision of the unit
//! cube: sample (i, j, k) sits at ((i, j, k) + 0.5) / (nx, ny, nz). Lookups take a point in [0, 1]³ (the dataset
//! maps medium space to it).
//!
//! **Storage follows the data.** The lattice is cut into bricks of 8³ samples (OpenVDB's and NanoVDB's leaf
//! size). A [`Topology`] — shared by every channel of a dataset — numbers the bricks that hold data (slots 1, 2,
//! …) in a table over all bricks, with 0 for the rest; a grid stores 512 values per slot, x fastest within the
//! brick, and in slot 0 its background, which every empty brick reads. A far-away second fire in the same box
//! costs its own bricks and four bytes per brick of the box, not the box. Dense inputs keep only the bricks
//! where some channel is non-zero, so every lookup gives the value the dense array gave, to the bit. Bricks
//! under an OpenVDB tile — one value throughout, in every channel — share one block of values per distinct
//! value ([`Topology::share`]): the brick table points them all at it.
//!
//! - [`Interpolation::Trilinear`] (default): pbrt-v4's `SampledGrid::Lookup` — the eight samples around
//!   p·n − 0.5, each sample outside the grid counting as **zero**. So within the last half voxel of every face
//!   the value fades linearly from the edge sample toward zero, reaching half the edge sample exactly on the
//!   bounds; beyond the bounds it is zero.
//! - [`Interpolation::Nearest`]: the sample whose cell holds p; zero outside [0, 1]³.

/// ⌊x⌋ without the libm call `f64::floor` makes on baseline x86-64 (no rounding instruction before SSE4.1),
/// exact for |x| < 2⁶³ — grid coordinates, which lookups have checked to lie within a few voxels of the grid.
#[inline(always)]
pub fn floor(x: f64) -> f64 {
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
    /// The stencil of `p` in [0, 1]³ on the grids of `topo`; `None` outside the bounds (value zero).
    pub fn new(topo: &Topology, p: [f64; 3], interp: Interpolation) -> Option<Stencil> {
        Stencil::with_margin(topo, p, interp, 0.0)
    }

    /// As [`Stencil::new`], but trilinear lookups continue `margin` voxels beyond the bounds, fading toward the
    /// zero outside (NanoVDB's sampler does this up to the next voxel centre).
    #[inline(always)]
    pub fn with_margin(
        topo: &Topology,
        p: [f64; 3],
        interp: Interpolation,
        margin: f64,
    ) -> Option<Stencil> {
        let dims = topo.dims;
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
                let [fx, fy, fz] = frac;
                let [gx, gy, gz] = frac.map(|f| 1.0 - f);
                let [i, j, k] = base.map(|v| v as usize);
                let at = |a: usize, b: usize, c: usize| topo.index(i + a, j + b, k + c);
                return Some(Stencil {
                    idx: [
                        at(0, 0, 0),
                        at(1, 0, 0),
                        at(0, 1, 0),
                        at(1, 1, 0),
                        at(0, 0, 1),
                        at(1, 0, 1),
                        at(0, 1, 1),
                        at(1, 1, 1),
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
        Some(Stencil::general(topo, p, interp))
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
    fn general(topo: &Topology, p: [f64; 3], interp: Interpolation) -> Stencil {
        let p = if interp == Interpolation::Nearest {
            p.map(|x| x.clamp(0.0, 1.0))
        } else {
            p
        };
        let dims = topo.dims;
        let [nx, ny, nz] = dims;
        let mut st = Stencil::default();
        match interp {
            Interpolation::Nearest => {
                let i = [0, 1, 2].map(|a| ((p[a] * dims[a] as f64) as usize).min(dims[a] - 1));
                st.idx[0] = topo.index(i[0], i[1], i[2]);
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
                        st.idx[st.n] = topo.index(q[0] as usize, q[1] as usize, q[2] as usize);
                        st.w[st.n] = w;
                        st.n += 1;
                    }
                }
            }
        }
        st
    }
}

/// Samples per brick edge (OpenVDB's leaf), and per brick.
pub const BRICK: usize = 8;
const BRICK_VOXELS: usize = BRICK * BRICK * BRICK;
/// Bricks per region edge of the top table, and per region.
const REGION: usize = 16;
const REGION_BRICKS: usize = REGION * REGION * REGION;

/// Which 8³ bricks of an nx × ny × nz lattice hold data: their slots (1, 2, …), 0 for the empty ones, in a
/// two-level table — a top table over regions of 16³ bricks (128³ samples, OpenVDB's internal node) whose
/// entries point to a block of 4096 slots for a region holding data and are 0 for an empty one — so the table
/// too follows the data (a 2048³ box with two fires: a 16 KB top table and a block per region they touch).
/// Shared by the grids of one dataset, so one [`Stencil`] indexes them all.
#[derive(Debug, Clone, PartialEq)]
pub struct Topology {
    dims: [usize; 3],
    /// Where sample 0 sits in its brick on each axis (0–7): a sparse file's leaves, aligned to multiples of 8
    /// in its own index space, stay whole bricks when the lattice starts elsewhere.
    off: [usize; 3],
    /// Bricks per axis.
    nb: [usize; 3],
    /// Regions of 16³ bricks per axis.
    nr: [usize; 3],
    /// Per region (x fastest), 1 + its block's index in `blocks`; 0: every brick empty.
    top: Vec<u32>,
    /// Per region with data, 4096 slots (its bricks, x fastest); 0: empty (reads the grid's background).
    blocks: Vec<u32>,
    /// Bricks with a slot.
    active: usize,
    /// Blocks of values a grid stores, the background's aside.
    blocks_stored: usize,
}

impl Topology {
    /// The topology of `dims` whose bricks are those `present` says hold data (called once per brick with its
    /// brick coordinates). `None` when the table or the slot count does not fit (2³² − 1 slots; the table's
    /// bytes are the caller's to check against its budget first, with [`Topology::table_bytes`]).
    pub fn build(dims: [usize; 3], present: impl FnMut([usize; 3]) -> bool) -> Option<Topology> {
        Topology::build_offset(dims, [0; 3], present)
    }

    /// As [`Topology::build`], sample 0 at `off` (each 0–7) within its brick: brick b covers samples
    /// 8b − off … 8b − off + 7.
    pub fn build_offset(
        dims: [usize; 3],
        off: [usize; 3],
        mut present: impl FnMut([usize; 3]) -> bool,
    ) -> Option<Topology> {
        if off.iter().any(|&o| o >= BRICK) || dims.contains(&0) {
            return None;
        }
        let nb = [0, 1, 2].map(|a| (dims[a] + off[a]).div_ceil(BRICK));
        // (The brick count must fit: the slots are numbered in u32, the brick coordinates in usize.)
        nb.iter().try_fold(1usize, |a, &b| a.checked_mul(b))?;
        // The bricks `present` names, listed (grown fallibly) for `from_bricks`, which numbers them.
        let mut list: Vec<[usize; 3]> = Vec::new();
        for z in 0..nb[2] {
            for y in 0..nb[1] {
                for x in 0..nb[0] {
                    if present([x, y, z]) {
                        if list.len() == list.capacity() {
                            list.try_reserve(list.len().max(64)).ok()?;
                        }
                        list.push([x, y, z]);
                    }
                }
            }
        }
        Topology::from_bricks(dims, off, list)
    }

    /// As [`Topology::build_offset`], from the list of the bricks holding data (any order, repeats allowed;
    /// those outside the lattice ignored): the same topology, in time and memory that follow the list rather
    /// than the box.
    pub fn from_bricks(
        dims: [usize; 3],
        off: [usize; 3],
        mut bricks: Vec<[usize; 3]>,
    ) -> Option<Topology> {
        if off.iter().any(|&o| o >= BRICK) || dims.contains(&0) {
            return None;
        }
        let nb = [0, 1, 2].map(|a| (dims[a] + off[a]).div_ceil(BRICK));
        nb.iter().try_fold(1usize, |a, &b| a.checked_mul(b))?;
        let nr = nb.map(|n| n.div_ceil(REGION));
        let regions = nr.iter().try_fold(1usize, |a, &b| a.checked_mul(b))?;
        bricks.retain(|b| (0..3).all(|a| b[a] < nb[a]));
        // Slots numbered as `build_offset` numbers them: regions x fastest, bricks x fastest within.
        let key = |b: &[usize; 3]| {
            let r = [b[0] / REGION, b[1] / REGION, b[2] / REGION];
            let l = (b[0] % REGION) + REGION * ((b[1] % REGION) + REGION * (b[2] % REGION));
            (r[0] + nr[0] * (r[1] + nr[1] * r[2]), l)
        };
        bricks.sort_unstable_by_key(key);
        bricks.dedup();
        let mut top = crate::alloc::filled(regions, 0u32)?;
        let mut blocks: Vec<u32> = Vec::new();
        for (n, b) in bricks.iter().enumerate() {
            let (r, l) = key(b);
            if top[r] == 0 {
                blocks.try_reserve(REGION_BRICKS).ok()?;
                blocks.resize(blocks.len() + REGION_BRICKS, 0);
                top[r] = u32::try_from(blocks.len() / REGION_BRICKS).ok()?;
            }
            blocks[(top[r] as usize - 1) * REGION_BRICKS + l] = u32::try_from(n + 1).ok()?;
        }
        Some(Topology {
            dims,
            off,
            nb,
            nr,
            top,
            blocks,
            active: bricks.len(),
            blocks_stored: bricks.len(),
        })
    }

    /// This topology with the bricks `class` puts in a class (a constant brick: the same value throughout in
    /// every grid, as an OpenVDB tile) sharing one block of values per class: a tile costs its table entries,
    /// not 2 KB per brick per grid. The table then holds blocks, not one slot per brick — lookups stay one table
    /// read — so [`for_each_slot`](Self::for_each_slot) gives a shared block for each of its bricks: structures
    /// kept per brick (the march's copies, the fire light's weights) are built over their own topologies, made
    /// from the brick list, as they are; and a shared block must be written with its class's value alone.
    /// `None` when the allocator refuses the map.
    pub fn share(mut self, mut class: impl FnMut([usize; 3]) -> Option<u32>) -> Option<Topology> {
        let mut store = crate::alloc::filled(self.active + 1, 0u32)?;
        let mut class_block: std::collections::HashMap<u32, u32> = Default::default();
        let mut next = 0u32;
        let mut shared = false;
        self.for_each_slot(|b, s| {
            store[s] = match class(b) {
                Some(c) => *class_block.entry(c).or_insert_with(|| {
                    next += 1;
                    next
                }),
                None => {
                    next += 1;
                    next
                }
            };
            shared |= store[s] as usize != s;
        });
        if shared {
            self.blocks_stored = next as usize;
            for e in self.blocks.iter_mut().filter(|e| **e != 0) {
                *e = store[*e as usize];
            }
        }
        Some(self)
    }

    /// The bricks b + `shift` + d of every stored brick b, for every offset d with each component in
    /// `lo..=hi` (those below 0 left out): the list of a dilated topology for [`Topology::from_bricks`].
    /// `None` when the allocator refuses it.
    pub fn spread(&self, shift: [usize; 3], lo: i64, hi: i64) -> Option<Vec<[usize; 3]>> {
        let side = (hi - lo + 1).max(0) as usize;
        let mut list = Vec::new();
        list.try_reserve(self.active.checked_mul(side * side * side)?)
            .ok()?;
        self.for_each_slot(|b, _| {
            for z in lo..=hi {
                for y in lo..=hi {
                    for x in lo..=hi {
                        let c = [x, y, z];
                        let c = [0, 1, 2].map(|a| (b[a] + shift[a]) as i64 + c[a]);
                        if c.iter().all(|&v| v >= 0) {
                            list.push(c.map(|v| v as usize));
                        }
                    }
                }
            }
        });
        Some(list)
    }

    /// Every brick present (small dense grids: tests, generated grids).
    pub fn full(dims: [usize; 3]) -> Option<Topology> {
        Topology::build(dims, |_| true)
    }

    /// Bytes of the top table of a `dims` lattice (4 per region of 16³ bricks, one more per axis for an
    /// offset), `None` beyond `u64`; the blocks follow the data (16 KB per region holding some).
    pub fn table_bytes(dims: [usize; 3]) -> Option<u64> {
        dims.iter().try_fold(4u64, |a, &n| {
            a.checked_mul(n.div_ceil(BRICK * REGION) as u64 + 1)
        })
    }
    /// Sample 0's place within its brick, per axis.
    pub fn offset(&self) -> [usize; 3] {
        self.off
    }

    /// (nx, ny, nz).
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// Bricks holding data.
    pub fn active_bricks(&self) -> usize {
        self.active
    }
    /// Bricks per axis.
    pub fn bricks(&self) -> [usize; 3] {
        self.nb
    }
    /// Bytes of the table.
    pub fn bytes(&self) -> usize {
        (self.top.len() + self.blocks.len()) * std::mem::size_of::<u32>()
    }
    /// Blocks of 512 values a grid stores besides its background's: one per stored brick, less what constant
    /// bricks share ([`Topology::share`]).
    pub fn blocks_stored(&self) -> usize {
        self.blocks_stored
    }
    /// The slot of brick `b` (0: empty).
    #[inline(always)]
    pub fn slot(&self, b: [usize; 3]) -> usize {
        let r = [b[0] / REGION, b[1] / REGION, b[2] / REGION];
        let block = self.top[r[0] + self.nr[0] * (r[1] + self.nr[1] * r[2])] as usize;
        if block == 0 {
            return 0;
        }
        let l = (b[0] % REGION) + REGION * ((b[1] % REGION) + REGION * (b[2] % REGION));
        self.blocks[(block - 1) * REGION_BRICKS + l] as usize
    }
    /// Where sample (i, j, k) (inside the lattice) is stored in a grid of this topology.
    #[inline(always)]
    pub fn index(&self, i: usize, j: usize, k: usize) -> usize {
        let (i, j, k) = (i + self.off[0], j + self.off[1], k + self.off[2]);
        let slot = self.slot([i / BRICK, j / BRICK, k / BRICK]);
        slot * BRICK_VOXELS + (i % BRICK) + BRICK * ((j % BRICK) + BRICK * (k % BRICK))
    }
    /// The brick holding sample (i, j, k).
    #[inline(always)]
    pub fn brick_of(&self, v: [usize; 3]) -> [usize; 3] {
        [0, 1, 2].map(|a| (v[a] + self.off[a]) / BRICK)
    }
    /// The samples [lo, hi) of brick `b` along axis `a`, inside the lattice.
    #[inline]
    pub fn brick_span(&self, b: usize, a: usize) -> (usize, usize) {
        let lo = (b * BRICK).saturating_sub(self.off[a]);
        let hi = ((b + 1) * BRICK - self.off[a]).min(self.dims[a]);
        (lo, hi.max(lo))
    }
    /// The sample stored at `n` in a grid's values ([`Grid::values_mut`]), or `None` for the background and padding.
    pub fn voxel_of(&self, n: usize) -> Option<[usize; 3]> {
        let block = n / BRICK_VOXELS;
        if block == 0 {
            return None;
        }
        // (A shared block: the first brick stored in it.)
        let mut brick = None;
        self.for_each_slot(|b, s| {
            if brick.is_none() && s == block {
                brick = Some(b);
            }
        });
        let brick = brick?;
        let l = n % BRICK_VOXELS;
        let v = [
            brick[0] * BRICK + l % BRICK,
            brick[1] * BRICK + (l / BRICK) % BRICK,
            brick[2] * BRICK + l / (BRICK * BRICK),
        ];
        let v = [0, 1, 2].map(|a| v[a].checked_sub(self.off[a]));
        let v = [v[0]?, v[1]?, v[2]?];
        (0..3).all(|a| v[a] < self.dims[a]).then_some(v)
    }
    /// Row (·, j, k) cut at brick boundaries: for each piece its samples [x0, x1) and where the first is
    /// stored (below 512: an empty brick, the background).
    #[inline]
    fn row_pieces(&self, j: usize, k: usize, mut f: impl FnMut(usize, usize, usize)) {
        let (jj, kk) = (j + self.off[1], k + self.off[2]);
        let within = BRICK * ((jj % BRICK) + BRICK * (kk % BRICK));
        let mut x0 = 0;
        while x0 < self.dims[0] {
            let xx = x0 + self.off[0];
            let x1 = ((xx / BRICK + 1) * BRICK - self.off[0]).min(self.dims[0]);
            let slot = self.slot([xx / BRICK, jj / BRICK, kk / BRICK]);
            f(
                x0,
                x1,
                if slot == 0 {
                    0
                } else {
                    slot * BRICK_VOXELS + within + xx % BRICK
                },
            );
            x0 = x1;
        }
    }

    /// Calls `f` with every stored brick and its slot.
    pub fn for_each_slot(&self, mut f: impl FnMut([usize; 3], usize)) {
        for (r, &block) in self.top.iter().enumerate() {
            if block == 0 {
                continue;
            }
            let r = [
                r % self.nr[0],
                (r / self.nr[0]) % self.nr[1],
                r / (self.nr[0] * self.nr[1]),
            ];
            let slots =
                &self.blocks[(block as usize - 1) * REGION_BRICKS..block as usize * REGION_BRICKS];
            for (l, &s) in slots.iter().enumerate() {
                if s != 0 {
                    let b = [
                        r[0] * REGION + l % REGION,
                        r[1] * REGION + (l / REGION) % REGION,
                        r[2] * REGION + l / (REGION * REGION),
                    ];
                    f(b, s as usize);
                }
            }
        }
    }

    /// Calls `f` with every sample of the lattice a stored brick holds and where a grid of this topology stores it
    /// (bricks that share a constant block are each visited; the background's empty bricks are not).
    pub fn for_each_stored_voxel(&self, mut f: impl FnMut([usize; 3], usize)) {
        self.for_each_slot(|b, slot| {
            let span = [0, 1, 2].map(|a| self.brick_span(b[a], a));
            for k in span[2].0..span[2].1 {
                for j in span[1].0..span[1].1 {
                    let row = slot * BRICK_VOXELS
                        + BRICK * ((j + self.off[1]) % BRICK + BRICK * ((k + self.off[2]) % BRICK));
                    for i in span[0].0..span[0].1 {
                        f([i, j, k], row + (i + self.off[0]) % BRICK);
                    }
                }
            }
        });
    }

    /// The values a grid of this topology stores: 512 per block, the background's included.
    pub fn values_len(&self) -> usize {
        (self.blocks_stored + 1) * BRICK_VOXELS
    }
}

/// A scalar grid, cell-centred, stored by bricks (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid {
    topo: std::sync::Arc<Topology>,
    /// 512 values per slot, x fastest within the brick; slot 0 holds the background.
    values: Vec<f32>,
}

impl Grid {
    /// A grid of `dims` from dense samples `data` (x fastest; its length must equal the product), every brick
    /// stored. `None` on a mismatch or when the allocator refuses.
    pub fn new(dims: [usize; 3], data: Vec<f32>) -> Option<Grid> {
        let n = dims.iter().try_fold(1usize, |a, &d| a.checked_mul(d))?;
        if n != data.len() || n == 0 {
            return None;
        }
        let topo = std::sync::Arc::new(Topology::full(dims)?);
        Grid::from_dense(topo, &data, 0.0)
    }

    /// A grid of topology `topo` from dense samples `data` (x fastest, over `topo`'s dims): the bricks `topo`
    /// holds are copied, the rest read `background`. `None` on a length mismatch or a refused allocation.
    pub fn from_dense(
        topo: std::sync::Arc<Topology>,
        data: &[f32],
        background: f32,
    ) -> Option<Grid> {
        let [nx, ny, nz] = topo.dims;
        if data.len() != nx.checked_mul(ny)?.checked_mul(nz)? {
            return None;
        }
        let mut g = Grid::filled(topo, background)?;
        for k in 0..nz {
            for j in 0..ny {
                let row = &data[nx * (j + ny * k)..nx * (j + ny * k + 1)];
                g.set_row(j, k, row);
            }
        }
        Some(g)
    }

    /// A grid of topology `topo` with every sample `value` (stored bricks included), to be filled.
    pub fn filled(topo: std::sync::Arc<Topology>, value: f32) -> Option<Grid> {
        let values = crate::alloc::filled(topo.values_len(), value)?;
        Some(Grid { topo, values })
    }

    /// Writes row (·, j, k) from `row` (nx values) into the bricks that hold it (the rest are left alone).
    pub fn set_row(&mut self, j: usize, k: usize, row: &[f32]) {
        let topo = self.topo.clone();
        topo.row_pieces(j, k, |x0, x1, start| {
            if start >= BRICK_VOXELS {
                self.values[start..start + (x1 - x0)].copy_from_slice(&row[x0..x1]);
            }
        });
    }

    /// Sample (i, j, k) ← `v`, if its brick is stored; returns whether it was.
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, k: usize, v: f32) -> bool {
        let idx = self.topo.index(i, j, k);
        if idx < BRICK_VOXELS {
            return false;
        }
        self.values[idx] = v;
        true
    }

    /// The 512 stored values (x fastest) of the brick whose first sample is (i, j, k), when that sample starts
    /// a stored brick.
    pub fn brick_mut(&mut self, v: [usize; 3]) -> Option<&mut [f32]> {
        let t = &self.topo;
        if (0..3).any(|a| (v[a] + t.off[a]) % BRICK != 0 || v[a] >= t.dims[a]) {
            return None;
        }
        let b = t.slot(t.brick_of(v));
        (b != 0).then(|| &mut self.values[b * BRICK_VOXELS..(b + 1) * BRICK_VOXELS])
    }

    /// The 512 stored values of brick `b` (brick coordinates; a shared block for a constant brick), when stored.
    pub fn brick_values_mut(&mut self, b: [usize; 3]) -> Option<&mut [f32]> {
        if (0..3).any(|a| b[a] >= self.topo.nb[a]) {
            return None;
        }
        let k = self.topo.slot(b);
        (k != 0).then(|| &mut self.values[k * BRICK_VOXELS..(k + 1) * BRICK_VOXELS])
    }

    /// Copies row (·, j, k) into `out` (nx values).
    pub fn row(&self, j: usize, k: usize, out: &mut [f32]) {
        self.topo.row_pieces(j, k, |x0, x1, start| {
            if start < BRICK_VOXELS {
                out[x0..x1].fill(self.values[0]);
            } else {
                out[x0..x1].copy_from_slice(&self.values[start..start + (x1 - x0)]);
            }
        });
    }

    /// (nx, ny, nz).
    pub fn dims(&self) -> [usize; 3] {
        self.topo.dims
    }
    /// The bricks this grid (and its dataset's other grids) stores.
    pub fn topology(&self) -> &std::sync::Arc<Topology> {
        &self.topo
    }
    /// The value every empty brick reads.
    pub fn background(&self) -> f32 {
        self.values[0]
    }
    /// Bytes held by the samples (the brick table is its topology's, shared).
    pub fn bytes(&self) -> usize {
        self.values.len() * std::mem::size_of::<f32>()
    }
    /// A grid of the same topology holding `f` of every stored value (the background's too); `None` when the
    /// allocator refuses.
    pub fn map(&self, f: impl FnMut(f32) -> f32) -> Option<Grid> {
        let mut values = crate::alloc::with_capacity(self.values.len())?;
        values.extend(self.values.iter().copied().map(f));
        Some(Grid {
            topo: self.topo.clone(),
            values,
        })
    }
    /// Whether slot `s` stores only `v` (512 values; slot 0 is the background).
    pub fn slot_is(&self, s: usize, v: f32) -> bool {
        self.values
            .get(s * BRICK_VOXELS..(s + 1) * BRICK_VOXELS)
            .is_some_and(|b| b.iter().all(|&x| x == v))
    }
    /// The stored values (slot 0 first: the background), as [`Topology::for_each_stored_voxel`] indexes them.
    pub fn values(&self) -> &[f32] {
        &self.values
    }
    /// The stored values (slot 0 first: the background), for load-time policies.
    pub fn values_mut(&mut self) -> &mut [f32] {
        &mut self.values
    }
    /// This grid in topology `topo` (which holds at least this grid's bricks), or `None` when it does not or the
    /// allocator refuses.
    pub fn rehome(&self, topo: std::sync::Arc<Topology>) -> Option<Grid> {
        if topo.dims != self.topo.dims {
            return None;
        }
        let mut g = Grid::filled(topo, self.background())?;
        if g.topo.off != self.topo.off {
            // Bricks that do not line up: row by row.
            let [nx, ny, nz] = self.topo.dims;
            let mut row = vec![0f32; nx];
            for k in 0..nz {
                for j in 0..ny {
                    self.row(j, k, &mut row);
                    g.set_row(j, k, &row);
                }
            }
            return Some(g);
        }
        let mut ok = true;
        let (from_topo, to_topo) = (self.topo.clone(), g.topo.clone());
        from_topo.for_each_slot(|b, from| {
            let to = to_topo.slot(b);
            if to == 0 {
                ok = false;
                return;
            }
            let (from, to) = (from * BRICK_VOXELS, to * BRICK_VOXELS);
            g.values[to..to + BRICK_VOXELS]
                .copy_from_slice(&self.values[from..from + BRICK_VOXELS]);
        });
        ok.then_some(g)
    }
    /// The dense samples, x fastest (tests and small grids: nx·ny·nz values).
    pub fn to_dense(&self) -> Vec<f32> {
        let [nx, ny, nz] = self.topo.dims;
        let mut out = vec![0f32; nx * ny * nz];
        for k in 0..nz {
            for j in 0..ny {
                self.row(j, k, &mut out[nx * (j + ny * k)..nx * (j + ny * k + 1)]);
            }
        }
        out
    }

    /// Sample (i, j, k) with signed indices; zero outside the grid.
    #[inline]
    pub fn at(&self, i: i64, j: i64, k: i64) -> f32 {
        let [nx, ny, nz] = self.topo.dims;
        if i < 0 || j < 0 || k < 0 || i >= nx as i64 || j >= ny as i64 || k >= nz as i64 {
            return 0.0;
        }
        self.values[self.topo.index(i as usize, j as usize, k as usize)]
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
        let dims = self.topo.dims;
        let idx = |a: usize| ((p[a] * dims[a] as f64) as i64).min(dims[a] as i64 - 1);
        self.at(idx(0), idx(1), idx(2))
    }

    fn trilinear(&self, p: [f64; 3]) -> f32 {
        // Continuous sample coordinates; NaN or far-away points are outside.
        let dims = self.topo.dims;
        let mut base = [0i64; 3];
        let mut frac = [0f32; 3];
        for a in 0..3 {
            // Outside the bounds (and NaN): zero, as pbrt's rays are clipped to the medium's box.
            if !(0.0..=1.0).contains(&p[a]) {
                return 0.0;
            }
            let s = p[a] * dims[a] as f64 - 0.5;
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

    /// The value a [`Stencil`] computed for this grid's topology interpolates.
    #[inline(always)]
    pub fn eval(&self, st: &Stencil) -> f32 {
        if st.n == 8 {
            // (The same sum, in the same order, unrolled.)
            let mut v = 0.0f32;
            for k in 0..8 {
                v += st.w[k] * self.values[st.idx[k]];
            }
            return v;
        }
        (0..st.n).map(|k| st.w[k] * self.values[st.idx[k]]).sum()
    }

    /// Min, max, mean and non-zero fraction of the nx·ny·nz samples (empty bricks count as their voxels of
    /// background).
    pub fn stats(&self) -> GridStats {
        let mut acc = StatsAcc::new();
        let mut stored = 0u64;
        let mut row = [0f32; BRICK];
        let t = &self.topo;
        // The stored bricks only (time follows the data: two far leaves cost two leaves, not their box).
        t.for_each_slot(|[bx, by, bz], slot| {
            let (sx, sy, sz) = (
                t.brick_span(bx, 0),
                t.brick_span(by, 1),
                t.brick_span(bz, 2),
            );
            let (w, h, d) = (sx.1 - sx.0, sy.1 - sy.0, sz.1 - sz.0);
            stored += (w * h * d) as u64;
            // The span's first sample within the brick, per axis.
            let o = [
                sx.0 + t.off[0] - bx * BRICK,
                sy.0 + t.off[1] - by * BRICK,
                sz.0 + t.off[2] - bz * BRICK,
            ];
            for z in 0..d {
                for y in 0..h {
                    let start =
                        slot * BRICK_VOXELS + o[0] + BRICK * (o[1] + y + BRICK * (o[2] + z));
                    row[..w].copy_from_slice(&self.values[start..start + w]);
                    if w == BRICK {
                        acc.add_lanes(&row);
                    } else {
                        row[..w].iter().for_each(|&v| acc.add(v));
                    }
                }
            }
        });
        let all = t.dims.iter().map(|&n| n as u64).product::<u64>();
        let empty = all - stored;
        if empty > 0 {
            acc.add_repeated(self.values[0], empty);
        }
        acc.finish()
    }
}

/// Lanes of [`StatsAcc`].
pub const STATS_LANES: usize = 8;

/// Running grid statistics in eight lanes (running minima, maxima, sums and counts, so that a loop over groups
/// of eight vectorises; min and max skip NaN, as `f32::min` does: a comparison with NaN is false).
#[derive(Debug)]
pub struct StatsAcc {
    lo: [f32; STATS_LANES],
    hi: [f32; STATS_LANES],
    sums: [f64; STATS_LANES],
    counts: [u64; STATS_LANES],
    n: u64,
}

impl Default for StatsAcc {
    fn default() -> Self {
        Self::new()
    }
}

impl StatsAcc {
    pub fn new() -> StatsAcc {
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
    pub fn add_lanes(&mut self, c: &[f32; STATS_LANES]) {
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
    pub fn add(&mut self, v: f32) {
        self.lo[0] = if v < self.lo[0] { v } else { self.lo[0] };
        self.hi[0] = if v > self.hi[0] { v } else { self.hi[0] };
        self.sums[0] += v as f64;
        self.counts[0] += (v != 0.0) as u64;
        self.n += 1;
    }
    /// `n` samples of value `v`.
    pub fn add_repeated(&mut self, v: f32, n: u64) {
        self.lo[0] = if v < self.lo[0] { v } else { self.lo[0] };
        self.hi[0] = if v > self.hi[0] { v } else { self.hi[0] };
        self.sums[0] += v as f64 * n as f64;
        self.counts[0] += (v != 0.0) as u64 * n;
        self.n += n;
    }
    pub fn finish(&self) -> GridStats {
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
mod tests;
