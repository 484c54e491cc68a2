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
//!
//! Two layouts, one read:
//!
//! - **dense**: one padded array over the dataset's box ((n + 2)³ voxels);
//! - **bricks**: a padded copy per brick whose cells touch data — 9³ voxels, the brick's 8³ and the first
//!   voxel of the next on each axis, so that every cell (the 8 samples around a point) whose lower corner is in
//!   the brick lies in its copy and the kernel reads it with the same four 16-byte loads, strides 9 and 81.
//!   The copies are numbered by a [`Topology`] over the cells' lower corners (the samples shifted by one, so the
//!   half-voxel margin below sample 0 has its bricks): the data's bricks and those just below them on each
//!   axis. A cell in no copy has all eight corners in empty bricks and reads copy 0, the background. Memory
//!   follows the data: a fire far from its copy in a 2048³ box costs its bricks, not the box; copies of a
//!   constant tile's interior (or the background's, along the box's faces) share one copy, as the dataset's
//!   bricks share one block.
//!
//! The volume builds the dense layout while it costs at most four times what its grids store, else the bricks; a
//! fire that scatters builds it when a ray first marches ([`Slot`])
//! (`lattice` parameter; docs/results/log.md has both measured on the same fires). Without a lattice (`off`, or
//! one the budget refuses) the kernel reads the dataset's bricks in place: the same values, lerped alike, so the
//! same image to the bit — the copy buys speed only.

use crate::grid::{Grid, Topology, BRICK};
use crate::majorant::{BrickRanges, Ranges};

/// The lattice a volume marches: built with the volume, or — for a fire that scatters, which its host tracks and
/// may never march (a scattering room with the fire light off asks only for scattering events) — when a ray first
/// marches, once, on the plugin's own threads (another query waits for it; a host's pool may be busy running the
/// very queries that wait). The same lattice either way: the images do not depend on when it was built.
#[derive(Debug, Clone, Default)]
pub(crate) struct Slot {
    built: std::sync::OnceLock<Option<Lattice>>,
    plan: Option<Plan>,
}

/// What a deferred lattice is built from: the dataset's channels it interleaves, its layout, and the budget and
/// threads the volume's build had.
#[derive(Debug, Clone)]
pub(crate) struct Plan {
    dense: bool,
    density: usize,
    temperature: Option<usize>,
    extra: Vec<usize>,
    brick: usize,
    budget: u64,
    threads: usize,
    /// What it will hold (for bricks, an estimate: a copy per stored brick), kept from the budget the volume
    /// leaves to its fire light.
    bytes: u64,
}

impl Plan {
    /// The plan of a `dense` or bricked lattice of `ds`'s channels (density, temperature, the further grids),
    /// majorant bricks of `brick` samples, within `budget` bytes, on the build's threads.
    pub(crate) fn new(
        dense: bool,
        (density, temperature, extra): (usize, Option<usize>, Vec<usize>),
        ds: &crate::dataset::Dataset,
        brick: usize,
        budget: u64,
    ) -> Plan {
        let fields = 4 * (2 + extra.len() as u64);
        let bytes = if dense {
            Lattice::padded(ds.dims())
                .map_or(u64::MAX, |p| p.iter().map(|&n| n as u64).product::<u64>())
                .saturating_mul(fields)
        } else {
            (ds.topology().blocks_stored() as u64 + 1).saturating_mul(PADDED_VOXELS as u64 * fields)
        };
        Plan {
            dense,
            density,
            temperature,
            extra,
            brick,
            budget,
            threads: crate::par::threads(usize::MAX),
            bytes,
        }
    }

    /// The bytes the lattice will hold (for bricks, an estimate; `u64::MAX` for a dense box past any memory).
    pub(crate) fn bytes(&self) -> u64 {
        self.bytes
    }

    /// What the build reports of it.
    pub(crate) fn describe(&self) -> String {
        let layout = if self.dense {
            "dense"
        } else {
            "a padded copy per brick"
        };
        format!("march lattice ({layout}, built when a ray first marches: the host tracks this scattering fire)")
    }
}

impl Slot {
    /// A lattice built with the volume.
    pub(crate) fn ready(lattice: Lattice) -> Slot {
        Slot {
            built: std::sync::OnceLock::from(Some(lattice)),
            plan: None,
        }
    }

    /// A lattice built when a ray first marches.
    pub(crate) fn deferred(plan: Plan) -> Slot {
        Slot {
            built: std::sync::OnceLock::new(),
            plan: Some(plan),
        }
    }

    /// The lattice, built now if it was deferred (`None`: none, or the budget or the allocator refused it).
    pub(crate) fn get(&self, ds: &crate::dataset::Dataset) -> Option<&Lattice> {
        match &self.plan {
            None => self.built.get()?.as_ref(),
            Some(p) => self
                .built
                .get_or_init(|| {
                    let ch = ds.channels();
                    let extra: Vec<&Grid> = p.extra.iter().map(|&k| &ch[k].grid).collect();
                    let (d, t) = (&ch[p.density].grid, p.temperature.map(|k| &ch[k].grid));
                    crate::par::with_pool(None, || {
                        crate::par::with_budget(p.threads, || {
                            if p.dense {
                                Lattice::build(d, t, &extra, p.brick, p.budget).map(|(l, _)| l)
                            } else {
                                Lattice::build_bricks(d, t, &extra, p.budget)
                            }
                        })
                    })
                })
                .as_ref(),
        }
    }

    /// Whether the volume marches on a lattice (built, or to be built).
    pub(crate) fn is_some(&self) -> bool {
        self.plan.is_some() || self.built().is_some()
    }

    /// The bytes a deferred lattice will hold (0 for one built with the volume, or none).
    pub(crate) fn reserved(&self) -> u64 {
        self.plan.as_ref().map_or(0, |p| p.bytes)
    }

    /// The lattice, if it has been built.
    pub(crate) fn built(&self) -> Option<&Lattice> {
        self.built.get()?.as_ref()
    }
}

/// Samples per side of a padded brick.
pub(crate) const PADDED: usize = BRICK + 1;
/// Samples of a padded brick.
pub(crate) const PADDED_VOXELS: usize = PADDED * PADDED * PADDED;

/// The padded, interleaved copy of the grids a march samples.
#[derive(Debug, Clone)]
pub(crate) struct Lattice {
    /// Padded dims (the dataset's + 2 on each axis).
    dims: [usize; 3],
    /// `[d, T]` per padded voxel, x fastest (T = 0 when the volume has no temperature grid); for the bricks,
    /// `PADDED_VOXELS` per copy, copy 0 first.
    pairs: Vec<f32>,
    /// Further grids, one value per padded voxel each.
    extra: Vec<Vec<f32>>,
    /// The bricks' table, for the brick layout.
    bricks: Option<Topology>,
}

/// `pairs` (two floats per voxel) and each of `extra` (one per voxel) cut, in order, into runs of `counts[k]`
/// units of `unit` voxels: one (pairs, extras) per run, for one thread each.
fn runs<'a>(
    mut pairs: &'a mut [f32],
    mut extra: Vec<&'a mut [f32]>,
    unit: usize,
    counts: &[usize],
) -> Vec<(&'a mut [f32], Vec<&'a mut [f32]>)> {
    let mut out = Vec::with_capacity(counts.len());
    for &n in counts {
        let (mine, tail) = std::mem::take(&mut pairs).split_at_mut(2 * unit * n);
        pairs = tail;
        let (mut mine_extra, mut tails) = (Vec::new(), Vec::new());
        for r in extra {
            let (a, b) = r.split_at_mut(unit * n);
            mine_extra.push(a);
            tails.push(b);
        }
        extra = tails;
        out.push((mine, mine_extra));
    }
    out
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
        crate::par::scope(|s| {
            // Each thread takes whole padded slabs [1 + k·per, 1 + (k+1)·per).
            let counts: Vec<usize> = (0..nz).step_by(per).map(|z0| per.min(nz - z0)).collect();
            let parts = runs(
                &mut pairs[2 * slab..],
                extra_v.iter_mut().map(|v| &mut v[slab..]).collect(),
                slab,
                &counts,
            );
            let mut handles = Vec::new();
            for (k, (mine, mut mine_extra)) in parts.into_iter().enumerate() {
                let (z0, n) = (k * per, counts[k]);
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
                bricks: None,
            },
            ranges.into_iter().map(BrickRanges::finish).collect(),
        ))
    }

    /// The brick layout of the same grids (see the module docs); `None` when its table or bytes would exceed
    /// `budget`, or the allocator refuses them (the volume then marches without it: the same results, slower).
    pub(crate) fn build_bricks(
        density: &Grid,
        temperature: Option<&Grid>,
        extra: &[&Grid],
        budget: u64,
    ) -> Option<Lattice> {
        let data = density.topology();
        let n = density.dims();
        // Cell lower corners c ∈ [−1, n − 1] are numbered w = c + 1 ∈ [0, n]; the copies' bricks sit where the
        // data's do (a data brick's cells are one copy), so w-brick b starts at sample 8b − off − 1.
        let off = data.offset().map(|o| (o + BRICK - 1) % BRICK);
        let grids: Vec<&Grid> = std::iter::once(density)
            .chain(temperature)
            .chain(extra.iter().copied())
            .collect();
        // A background other than 0 fills the box, and a copy on the box's faces must fade it to 0 outside.
        let faces = grids.iter().any(|g| g.background() != 0.0);
        let present = |b: [usize; 3]| {
            // The samples this copy holds, [lo, lo + 8] per axis, within the lattice.
            let mut span = [(0usize, 0usize); 3];
            let mut face = false;
            for a in 0..3 {
                let lo = (BRICK * b[a]) as i64 - off[a] as i64 - 1;
                let hi = lo + BRICK as i64;
                face |= lo < 0 || hi >= n[a] as i64;
                let (lo, hi) = (lo.max(0), hi.min(n[a] as i64 - 1));
                if lo > hi {
                    return false;
                }
                span[a] = (lo as usize, hi as usize);
            }
            if face && faces {
                return true;
            }
            // The data bricks of its first and last sample on each axis (at most two per axis).
            let lo = data.brick_of([span[0].0, span[1].0, span[2].0]);
            let hi = data.brick_of([span[0].1, span[1].1, span[2].1]);
            (lo[2]..=hi[2]).any(|z| {
                (lo[1]..=hi[1]).any(|y| (lo[0]..=hi[0]).any(|x| data.slot([x, y, z]) != 0))
            })
        };
        let dims = [0, 1, 2].map(|a| n[a] + 1);
        let table = Topology::table_bytes(dims)?;
        if table > budget {
            return None;
        }
        let topo = if faces {
            Topology::build_offset(dims, off, present)?
        } else {
            // The copies holding a stored brick's cells: its own (data brick b is copy b + s, s = 1 when the
            // data's bricks start at sample 0) and those one below on any axis — from the list, not the box.
            let s = data.offset().map(|o| (o == 0) as usize);
            Topology::from_bricks(dims, off, data.spread(s, -1, 0)?)?
        };
        // A copy whose data bricks (two per axis) are all one shared block — a constant tile's interior, the same
        // values in every grid — holds that block's value throughout, save the zeros past the box where it
        // crosses a face: such copies share one copy per block and face (below, inside or above the box on
        // each axis), so a file of constant tiles costs its tiles here too, not 5.8 KB per brick covered.
        let one_topology = grids
            .iter()
            .all(|g| std::sync::Arc::ptr_eq(g.topology(), data));
        let mut classes: std::collections::HashMap<(usize, [i8; 3]), u32> = Default::default();
        let constant = |b: [usize; 3]| {
            if !one_topology {
                return None;
            }
            // The copy's samples inside the lattice, [lo, hi] per axis, and where it crosses a face.
            let (mut lo, mut hi, mut face) = ([0usize; 3], [0usize; 3], [0i8; 3]);
            for a in 0..3 {
                let l = (BRICK * b[a]) as i64 - off[a] as i64 - 1;
                let h = l + BRICK as i64;
                face[a] = if l < 0 {
                    -1
                } else if h >= n[a] as i64 {
                    1
                } else {
                    0
                };
                let (l, h) = (l.max(0), h.min(n[a] as i64 - 1));
                if l > h {
                    return None;
                }
                (lo[a], hi[a]) = (l as usize, h as usize);
            }
            let (first, last) = (data.brick_of(lo), data.brick_of(hi));
            let slot = data.slot(first);
            let same = (first[2]..=last[2]).all(|z| {
                (first[1]..=last[1])
                    .all(|y| (first[0]..=last[0]).all(|x| data.slot([x, y, z]) == slot))
            });
            // (Within the box the copy's nine samples per axis span two data bricks, so one slot for all is a
            // shared block, or the background's; a copy within one stored brick — at a face — is not shared.)
            if !same || (slot != 0 && first == last) {
                return None;
            }
            let next = classes.len() as u32;
            Some(*classes.entry((slot, face)).or_insert(next))
        };
        let topo = topo.share(constant)?;
        let copies = topo.blocks_stored() + 1;
        let voxels = copies.checked_mul(PADDED_VOXELS)?;
        // (The kernel's offsets are 32-bit, as for the dense layout.)
        if voxels.checked_mul(2)? >= u32::MAX as usize {
            return None;
        }
        let bytes = (voxels as u64).saturating_mul(4 * (2 + extra.len() as u64));
        if bytes.saturating_add(topo.bytes() as u64) > budget {
            return None;
        }
        let mut pairs = crate::alloc::filled(2 * voxels, 0f32)?;
        let mut extra_v: Vec<Vec<f32>> = extra
            .iter()
            .map(|_| crate::alloc::filled(voxels, 0f32))
            .collect::<Option<_>>()?;
        // Copy 0: the background of each grid (cells in no copy are inside the box, among empty bricks).
        let bg: Vec<f32> = grids.iter().map(|g| g.background()).collect();
        let first_extra = 1 + temperature.is_some() as usize;
        for p in pairs[..2 * PADDED_VOXELS].chunks_exact_mut(2) {
            p[0] = bg[0];
            p[1] = if temperature.is_some() { bg[1] } else { 0.0 };
        }
        for (v, &b) in extra_v.iter_mut().zip(&bg[first_extra..]) {
            v[..PADDED_VOXELS].fill(b);
        }
        // Each copy's brick, by copy number.
        let mut of = crate::alloc::filled(copies, [0usize; 3])?;
        topo.for_each_slot(|b, s| of[s] = b);
        let fill = |b: [usize; 3], pairs: &mut [f32], extra: &mut [&mut [f32]]| {
            let lo = [0, 1, 2].map(|a| (BRICK * b[a]) as i64 - off[a] as i64 - 1);
            for z in 0..PADDED {
                for y in 0..PADDED {
                    for x in 0..PADDED {
                        let (i, j, k) = (lo[0] + x as i64, lo[1] + y as i64, lo[2] + z as i64);
                        let l = x + PADDED * (y + PADDED * z);
                        pairs[2 * l] = density.at(i, j, k);
                        if let Some(t) = temperature {
                            pairs[2 * l + 1] = t.at(i, j, k);
                        }
                        for (e, g) in extra.iter_mut().zip(&grids[first_extra..]) {
                            e[l] = g.at(i, j, k);
                        }
                    }
                }
            }
        };
        // Copies split over the threads in contiguous runs.
        let threads = crate::par::threads(8);
        let per = (copies - 1).div_ceil(threads).max(1);
        crate::par::scope(|s| {
            let counts: Vec<usize> = (1..copies)
                .step_by(per)
                .map(|c| per.min(copies - c))
                .collect();
            let parts = runs(
                &mut pairs[2 * PADDED_VOXELS..],
                extra_v
                    .iter_mut()
                    .map(|v| &mut v[PADDED_VOXELS..])
                    .collect(),
                PADDED_VOXELS,
                &counts,
            );
            for (k, (mine, mut mine_extra)) in parts.into_iter().enumerate() {
                let (first, m) = (1 + k * per, counts[k]);
                let (of, fill) = (&of, &fill);
                s.spawn(move || {
                    for c in 0..m {
                        let mut e: Vec<&mut [f32]> = mine_extra
                            .iter_mut()
                            .map(|v| &mut v[PADDED_VOXELS * c..PADDED_VOXELS * (c + 1)])
                            .collect();
                        fill(
                            of[first + c],
                            &mut mine[2 * PADDED_VOXELS * c..2 * PADDED_VOXELS * (c + 1)],
                            &mut e,
                        );
                    }
                });
            }
        });
        Some(Lattice {
            dims: [PADDED; 3],
            pairs,
            extra: extra_v,
            bricks: Some(topo),
        })
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

    /// Padded dims (of one copy, for the bricks).
    #[inline(always)]
    pub(crate) fn dims(&self) -> [usize; 3] {
        self.dims
    }
    /// The copies' table, for the brick layout.
    #[inline(always)]
    pub(crate) fn bricks(&self) -> Option<&Topology> {
        self.bricks.as_ref()
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
            + self.bricks.as_ref().map_or(0, Topology::bytes)
    }
}
