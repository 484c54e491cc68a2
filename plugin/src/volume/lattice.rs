//! The grids the march kernel reads, laid out for it.
//!
//! The dataset keeps each channel in 8³ bricks (`grid`). A trilinear lookup of density and temperature
//! there is sixteen scattered reads, and a cell on the grid's outer half voxel needs the general stencil,
//! where pbrt-v4's lookup fades to zero at the faces. Here the same values are stored again:
//!
//! - **interleaved**: density and temperature side by side, `[d, T]` per voxel, so the x-pair of both grids
//!   at one (y, z) corner of a cell is one 16-byte read and a cell is four;
//! - **padded** by one ring of zero voxels on every side, so every point inside the bounds — and up to one voxel
//!   beyond them, which covers pbrt-v4 nanovdb's half-voxel margin — has all eight corners in the array. The
//!   zeros make the plain trilinear lerp equal pbrt-v4's lookup there: half the edge sample on a face, zero
//!   half a voxel out (tested against `Grid::eval` at and across the faces).
//!
//! Further grids the march reads (Lescale, species) are padded the same way, one array each. Built only for
//! the f32 march of a trilinear dataset; 8 bytes per padded voxel, plus 4 per further grid.

use crate::grid::Grid;
use crate::majorant::{BrickRanges, Ranges};

/// The padded, interleaved copy of the grids a march samples.
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    /// Padded dims (the dataset's + 2 on each axis).
    dims: [usize; 3],
    /// `[d, T]` per padded voxel, x fastest (T = 0 when the volume has no temperature grid).
    pairs: Vec<f32>,
    /// Further grids, one value per padded voxel each.
    extra: Vec<Vec<f32>>,
}

impl Lattice {
    /// The lattice of `density`, `temperature` (if any) and the `extra` grids, all on one lattice; `None` when
    /// it would hold 2³² floats or more (the kernel's offsets are 32-bit; such a volume marches without it).
    /// With it, each grid's majorant brick ranges for bricks of `brick`³ voxels (`majorant::brick_ranges`'s
    /// values, in the order density, temperature, extra), gathered from the slabs as they are copied — while
    /// they are still in cache — rather than by another pass over the grids.
    ///
    /// It is an acceleration, so it is also `None` when its bytes would exceed `budget` or the allocator refuses
    /// them: the volume then marches without it (the same results, slower), never aborts.
    pub(crate) fn build(
        density: &Grid,
        temperature: Option<&Grid>,
        extra: &[&Grid],
        brick: usize,
        budget: u64,
    ) -> Option<(Lattice, Vec<Ranges>)> {
        let [nx, ny, nz] = density.dims();
        let dims = Lattice::padded(density.dims())?;
        let slab = dims[0] * dims[1];
        let total = slab * dims[2];
        let bytes = (total as u64).saturating_mul(4 * (2 + extra.len() as u64));
        if bytes > budget {
            return None;
        }
        let mut pairs = crate::alloc::filled(2 * total, 0f32)?;
        let mut extra_v: Vec<Vec<f32>> = extra
            .iter()
            .map(|_| crate::alloc::filled(total, 0f32))
            .collect::<Option<_>>()?;
        let threads = crate::par::threads(8);
        // Padded z-slabs 1..=nz hold data; split them over the threads.
        let per = nz.div_ceil(threads).max(1);
        let has_t = temperature.is_some();
        // The grids whose brick ranges are gathered, in the order returned.
        let grids: Vec<&Grid> = std::iter::once(density)
            .chain(temperature)
            .chain(extra.iter().copied())
            .collect();
        let grids = &grids;
        let mut ranges: Vec<BrickRanges> = grids
            .iter()
            .map(|_| BrickRanges::new([nx, ny, nz], brick, 0..nz))
            .collect();
        std::thread::scope(|s| {
            // Each thread takes whole padded slabs [1 + k·per, 1 + (k+1)·per).
            let mut rest: &mut [f32] = &mut pairs[2 * slab..];
            let mut rest_extra: Vec<&mut [f32]> =
                extra_v.iter_mut().map(|v| &mut v[slab..]).collect();
            let mut z0 = 0;
            let mut handles = Vec::new();
            while z0 < nz {
                let n = per.min(nz - z0);
                let (mine, tail) = rest.split_at_mut(2 * slab * n);
                rest = tail;
                let mut mine_extra = Vec::with_capacity(rest_extra.len());
                let mut tails = Vec::with_capacity(rest_extra.len());
                for r in rest_extra {
                    let (a, b) = r.split_at_mut(slab * n);
                    mine_extra.push(a);
                    tails.push(b);
                }
                rest_extra = tails;
                handles.push(s.spawn(move || {
                    let mut acc: Vec<BrickRanges> = grids
                        .iter()
                        .map(|_| BrickRanges::new([nx, ny, nz], brick, z0..z0 + n))
                        .collect();
                    // Each grid's current z-slab, dense (the grids store bricks): read once, copied and ranged.
                    let mut slabs: Vec<Vec<f32>> =
                        grids.iter().map(|_| vec![0f32; nx * ny]).collect();
                    for z in 0..n {
                        for (sl, g) in slabs.iter_mut().zip(grids) {
                            for y in 0..ny {
                                g.row(y, z0 + z, &mut sl[nx * y..nx * (y + 1)]);
                            }
                        }
                        let (d, t) = (&slabs[0], has_t.then(|| &slabs[1]));
                        let first_extra = 1 + has_t as usize;
                        for y in 0..ny {
                            let src = nx * y;
                            let dst = 1 + dims[0] * (y + 1) + slab * z;
                            let row = &mut mine[2 * dst..2 * (dst + nx)];
                            match t {
                                Some(t) => {
                                    for ((p, &dv), &tv) in row
                                        .chunks_exact_mut(2)
                                        .zip(&d[src..src + nx])
                                        .zip(&t[src..src + nx])
                                    {
                                        p[0] = dv;
                                        p[1] = tv;
                                    }
                                }
                                None => {
                                    for (p, &dv) in row.chunks_exact_mut(2).zip(&d[src..src + nx]) {
                                        p[0] = dv;
                                    }
                                }
                            }
                            for (dst_g, sl) in mine_extra.iter_mut().zip(&slabs[first_extra..]) {
                                dst_g[dst..dst + nx].copy_from_slice(&sl[src..src + nx]);
                            }
                        }
                        // The slab's brick ranges, from the values just read.
                        for (a, sl) in acc.iter_mut().zip(&slabs) {
                            a.add_slab(z0 + z, sl);
                        }
                    }
                    acc
                }));
                z0 += n;
            }
            for h in handles {
                let part = h.join().unwrap_or_else(|e| std::panic::resume_unwind(e));
                for (r, p) in ranges.iter_mut().zip(&part) {
                    r.merge(p);
                }
            }
        });
        Some((
            Lattice {
                dims,
                pairs,
                extra: extra_v,
            },
            ranges.into_iter().map(BrickRanges::finish).collect(),
        ))
    }

    /// The padded dims of a dataset of `dims`, if its `[d, T]` pairs stay below 2³² floats.
    pub(crate) fn padded(dims: [usize; 3]) -> Option<[usize; 3]> {
        let p = [
            dims[0].checked_add(2)?,
            dims[1].checked_add(2)?,
            dims[2].checked_add(2)?,
        ];
        let floats = p.iter().try_fold(2usize, |a, &n| a.checked_mul(n))?;
        (floats < u32::MAX as usize).then_some(p)
    }

    /// Padded dims.
    #[inline(always)]
    pub(crate) fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// `[d, T]` per padded voxel.
    #[inline(always)]
    pub(crate) fn pairs(&self) -> &[f32] {
        &self.pairs
    }
    /// The further grids, padded.
    #[inline(always)]
    pub(crate) fn extra(&self) -> &[Vec<f32>] {
        &self.extra
    }
    /// Bytes held.
    pub(crate) fn bytes(&self) -> usize {
        4 * (self.pairs.len() + self.extra.iter().map(Vec::len).sum::<usize>())
    }
}
