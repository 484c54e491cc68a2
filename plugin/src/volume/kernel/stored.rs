//! The kernel's reads from the dataset's own grids, for a volume that keeps no lattice: the stored 8³ bricks read
//! in place, each cell's eight samples lerped as the lattice's are — the same values in the same order, so the
//! same image to the bit, without the copy (slower: docs/results/log.md, "The march without its copy").

use super::{index, lerp, lerp4, Extras, BATCH};
use crate::volume::lanes::MAX_SPECIES;
use crate::volume::FireVolume;

/// The dataset's own grids as the kernel reads them when the volume keeps no [`Lattice`] (`lattice off`, or one
/// refused by the budget): each cell's eight samples from the stored 8³ bricks — the slots of a brick and of its
/// seven neighbours beyond it looked up once, when the march enters the brick, for the cells that straddle them —
/// and zero beyond the bounds, where the lattice has its padding. The same eight values per grid as the lattice holds, in the same lerps: the same
/// result, bit for bit, without the copy.
pub(super) struct Stored<'a> {
    topo: &'a crate::grid::Topology,
    d: &'a [f32],
    t: Option<&'a [f32]>,
    /// Lescale (when the volume has it), then the species: the lattice's further grids, in its order.
    extra: [&'a [f32]; 1 + MAX_SPECIES],
    n_extra: usize,
    lescale: bool,
    /// Sample 0's place in its brick, the dims, and the largest lower corner a cell in the lattice has (n − 1).
    off: [usize; 3],
    dims: [usize; 3],
    last: [f64; 3],
}

impl<'a> Stored<'a> {
    /// `None` for a dataset that is not trilinear (the kernel's lerps are its lookup only then).
    pub(super) fn new(v: &'a FireVolume) -> Option<Stored<'a>> {
        let ds = v.grids.ds();
        if ds.interpolation() != crate::grid::Interpolation::Trilinear {
            return None;
        }
        let ch = ds.channels();
        let values = |k: usize| ch[k].grid.values();
        let mut extra: [&[f32]; 1 + MAX_SPECIES] = [&[]; 1 + MAX_SPECIES];
        let mut n_extra = 0;
        let further = v
            .grids
            .lescale()
            .into_iter()
            .chain(v.grids.species().iter().map(|sp| sp.ch()));
        for (slot, k) in extra.iter_mut().zip(further) {
            *slot = values(k);
            n_extra += 1;
        }
        let topo: &crate::grid::Topology = ds.topology();
        let dims = ds.dims();
        Some(Stored {
            topo,
            d: values(v.grids.density()),
            t: v.grids.temperature().map(values),
            extra,
            n_extra,
            lescale: v.grids.lescale().is_some(),
            off: topo.offset(),
            dims,
            last: dims.map(|n| n as f64 - 1.0),
        })
    }

    /// The start of brick `b`'s values and of its neighbours' beyond it on each axis (by the axes, x = 1, y = 2,
    /// z = 4), from `memo` when `b` is the brick asked for last: a march's consecutive samples mostly share a
    /// brick, and the table is two dependent reads per brick.
    #[inline(always)]
    fn starts<'m>(&self, b: [usize; 3], memo: &'m mut BrickMemo) -> &'m [usize; 8] {
        // (Compared field by field: an array compare loaded them as one vector just after they were stored
        // one by one, a store-forwarding stall measured at 7 % of the kernel.)
        if (memo.brick[0] ^ b[0]) | (memo.brick[1] ^ b[1]) | (memo.brick[2] ^ b[2]) != 0 {
            const BV: usize = crate::grid::BRICK * crate::grid::BRICK * crate::grid::BRICK;
            let nb = self.topo.bricks();
            let own = self.topo.slot(b) * BV;
            memo.brick = b;
            memo.starts[0] = own;
            for (next, s) in memo.starts.iter_mut().enumerate().skip(1) {
                let n = [
                    b[0] + (next & 1),
                    b[1] + ((next >> 1) & 1),
                    b[2] + (next >> 2),
                ];
                // (A brick past the last is never read: no cell inside the bounds reaches it.)
                *s = if (n[0] < nb[0]) & (n[1] < nb[1]) & (n[2] < nb[2]) {
                    self.topo.slot(n) * BV
                } else {
                    own
                };
            }
        }
        &memo.starts
    }

    /// Where the eight samples of the cell with lower corner c = w − 1 (w ∈ [0, n] on each axis) are stored, x
    /// fastest, then y, then z: without branches on where the cell lies in its brick (a third of the cells
    /// reach into the next brick; a branch on it mispredicted often enough to cost a tenth of the kernel).
    /// (Written out, without array `map`s or iterator closures: they would not inherit the kernel clone's
    /// target features.)
    #[inline(always)]
    fn corners(&self, w: [usize; 3], memo: &mut BrickMemo) -> [usize; 8] {
        const B: usize = crate::grid::BRICK;
        let inside = |a: usize| w[a] >= 1 && w[a] < self.dims[a];
        if !(inside(0) & inside(1) & inside(2)) {
            return self.on_bounds([w[0] as i64 - 1, w[1] as i64 - 1, w[2] as i64 - 1]);
        }
        let u = [
            w[0] - 1 + self.off[0],
            w[1] - 1 + self.off[1],
            w[2] - 1 + self.off[2],
        ];
        let b = [u[0] / B, u[1] / B, u[2] / B];
        let l = [u[0] % B, u[1] % B, u[2] % B];
        let starts = self.starts(b, memo);
        // The axes on which the cell reaches into the next brick.
        let cross = (l[0] == B - 1) as usize
            | ((l[1] == B - 1) as usize) << 1
            | ((l[2] == B - 1) as usize) << 2;
        let mut at = [0usize; 8];
        for (k, a) in at.iter_mut().enumerate() {
            let w0 = (l[0] + (k & 1)) % B;
            let w1 = (l[1] + ((k >> 1) & 1)) % B;
            let w2 = (l[2] + (k >> 2)) % B;
            *a = starts[k & cross] + w0 + B * (w1 + B * w2);
        }
        at
    }

    /// [`corners`](Self::corners) of a cell on the bounds: each corner inside them looked up, those beyond read
    /// as zero.
    #[cold]
    #[inline(never)]
    fn on_bounds(&self, c: [i64; 3]) -> [usize; 8] {
        let mut at = [usize::MAX; 8];
        for (k, a) in at.iter_mut().enumerate() {
            let p = [
                c[0] + (k & 1) as i64,
                c[1] + ((k >> 1) & 1) as i64,
                c[2] + (k >> 2) as i64,
            ];
            if (0..3).all(|i| p[i] >= 0 && (p[i] as usize) < self.dims[i]) {
                *a = self.topo.index(p[0] as usize, p[1] as usize, p[2] as usize);
            }
        }
        at
    }
}

/// The eight values of `a` at `at` ([`Stored::corners`]; `usize::MAX`: beyond the bounds, zero).
#[inline(always)]
fn eight(a: &[f32], at: &[usize; 8]) -> [f32; 8] {
    let v = |k: usize| a.get(at[k]).copied().unwrap_or(0.0);
    [v(0), v(1), v(2), v(3), v(4), v(5), v(6), v(7)]
}

/// The start of the last brick [`Stored::starts`] was asked for, and of its neighbours'.
struct BrickMemo {
    brick: [usize; 3],
    starts: [usize; 8],
}

/// What [`read_stored`] keeps from one sample to the next along a ray: the last brick's slot, and the last
/// cell's lower corner and its eight values of each grid.
pub(super) struct Memo {
    brick: BrickMemo,
    cell: [f64; 3],
    d: [f32; 8],
    t: [f32; 8],
    /// The further grids' (Lescale's, the species').
    extra: [[f32; 8]; 1 + MAX_SPECIES],
}

impl Memo {
    pub(super) fn new() -> Memo {
        Memo {
            brick: BrickMemo {
                brick: [usize::MAX; 3],
                starts: [0; 8],
            },
            // (NaN: no cell equals it.)
            cell: [f64::NAN; 3],
            d: [0.0; 8],
            t: [0.0; 8],
            extra: [[0.0; 8]; 1 + MAX_SPECIES],
        }
    }
}

/// [`read`] from the dataset's grids: sample `b` in the cell with lower corner `c` (⌊g⌋ of its lattice point
/// g) at fractions `f`, the same lerps on the same values; false when the cell is beyond the lattice's margin
/// (or g is NaN: the general stencil takes it).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn read_stored<const F: bool>(
    st: &Stored,
    memo: &mut Memo,
    c: [f64; 3],
    f: [f32; 3],
    scales: &[f64],
    b: usize,
    dt: &mut [[f32; 2]; BATCH],
    x: &mut Extras,
) -> bool {
    let cell = |a: usize| c[a] >= -1.0 && c[a] <= st.last[a];
    if !(cell(0) & cell(1) & cell(2)) {
        return false;
    }
    // (Steps of half a voxel or less visit each cell about twice: the last cell's values are kept. Where they
    // are stored is not: keeping it, a copy of the enum stalled on its stores, 7 % of the kernel.)
    if c != memo.cell {
        let at = st.corners(
            [index(c[0] + 1.0), index(c[1] + 1.0), index(c[2] + 1.0)],
            &mut memo.brick,
        );
        memo.cell = c;
        memo.d = eight(st.d, &at);
        memo.t = match st.t {
            Some(t) => eight(t, &at),
            None => [0.0; 8],
        };
        for (e, a) in memo.extra.iter_mut().zip(&st.extra[..st.n_extra]) {
            *e = eight(a, &at);
        }
    }
    let (d, t) = (&memo.d, &memo.t);
    // As `read`: [d, T] at x and x + 1 at the four (y, z) corners, lerped in y, z, then x.
    let q = |k: usize| [d[k], t[k], d[k + 1], t[k + 1]];
    let z0 = lerp4::<F>(f[1], &q(0), &q(2));
    let z1 = lerp4::<F>(f[1], &q(4), &q(6));
    let v = lerp4::<F>(f[2], &z0, &z1);
    let r = lerp4::<F>(f[0], &v, &[v[2], v[3], v[0], v[1]]);
    dt[b] = [r[0], r[1]];
    if st.n_extra > 0 {
        // As `trilinear`: x first, then y, then z.
        let tri = |e: &[f32; 8]| {
            let v = lerp4::<F>(f[0], &[e[0], e[2], e[4], e[6]], &[e[1], e[3], e[5], e[7]]);
            lerp::<F>(
                f[2],
                lerp::<F>(f[1], v[0], v[1]),
                lerp::<F>(f[1], v[2], v[3]),
            )
        };
        let mut e = 0;
        if st.lescale {
            x.les[b] = tri(&memo.extra[0]).max(0.0);
            e = 1;
        }
        for (k, (a, &scale)) in memo.extra[e..st.n_extra].iter().zip(scales).enumerate() {
            x.n[k][b] = (tri(a).max(0.0) as f64 * scale) as f32;
        }
    }
    true
}
