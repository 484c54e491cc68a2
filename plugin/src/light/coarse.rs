//! The fire at a coarser resolution, for the fire light's line estimate: a copy whose voxels are blocks of f³ of
//! the fire's (f = 2, 4 or 8), marched by the volume's kernel at the light's coarse step.
//!
//! At production resolutions the light's march reads the fire at scattered places (every light sample a different
//! direction: a cache miss per sample); the copy's few MB stay in the caches, so a light sample at 512³ costs what
//! it costs at 64³.
//!
//! A block's density is its voxels' mean (extinction is linear in density: the block holds the soot its voxels
//! hold), and its temperature the one whose emission per unit density, summed over the channels, is the block's
//! density-weighted mean: the block emits what its voxels emit, with the spectrum of one temperature. What that
//! costs in accuracy (the colour where a block spans the flame's sheet, the transmittance's nonlinearity) is the
//! line's bias against the volume's own march, measured in the tests and docs/results/log.md; the light's
//! `linecorrection` removes it. The blocks are made here; the volume makes the fire over them
//! ([`FireVolume::over`]).

use crate::dataset::{par_map, Dataset, LoadOptions};
use crate::grid::{Grid, Topology, BRICK};
use crate::volume::FireVolume;
use glam::DVec3;

/// Samples per brick.
const BV: usize = BRICK * BRICK * BRICK;

/// The most voxels the copy holds (128³, 16 bytes each with its lattice): it exists to fit in the caches.
const MAX_VOXELS: usize = 1 << 21;

/// `vol` at 1/`f` of its resolution per axis (`f` = 2, 4 or 8), for the fire light's coarse line; its box is the
/// fire's rounded up to whole blocks. `None` when the volume holds what the copy would not carry
/// ([`FireVolume::coarse_copyable`]), has no temperature, or when the copy would exceed `budget` bytes: the light
/// then marches the volume itself.
pub(super) fn coarse(vol: &FireVolume, f: usize, budget: u64) -> Option<FireVolume> {
    if !vol.coarse_copyable() || !matches!(f, 2 | 4 | 8) {
        return None;
    }
    let tch = vol.temperature_channel()?;
    // Emission per unit density summed over the channels, per row of the table: it must grow with T (the
    // block's temperature is found by inverting it).
    let (jsum, inv_dt, dt) = vol.emission_per_density();
    if jsum.len() < 2 || jsum.windows(2).any(|w| !(w[1] >= w[0])) {
        return None;
    }
    let ds = vol.dataset();
    let dims = ds.dims();
    let cd = dims.map(|n| n.div_ceil(f));
    let n = cd[0] * cd[1] * cd[2];
    // Two f32 grids per block, the lattice's two padded floats, and no more: each worker fills its own rows.
    let need = (n as u64) * (8 + 16);
    if n > MAX_VOXELS || need > budget {
        return None;
    }

    // Per block, from the stored bricks (empty ones read 0): Σ d, Σ d·J(T) and Σ T over its voxels, in
    // place, then its density (the mean) and temperature.
    let jt = &jsum;
    let emission = |t: f32| -> f64 {
        let x = (t as f64 * inv_dt).clamp(0.0, (jt.len() - 1) as f64);
        let i = (x as usize).min(jt.len() - 2);
        jt[i] + (x - i as f64) * (jt[i + 1] - jt[i])
    };
    let topo = ds.topology();
    let grids = ds.channels();
    let (dg, tg) = (&grids[vol.density_channel()].grid, &grids[tch].grid);
    let volume = (f * f * f) as f64;
    let block = |q: [usize; 3]| -> (f32, f32) {
        let lo = q.map(|v| v * f);
        let hi = [0, 1, 2].map(|a| (lo[a] + f).min(dims[a]));
        let (b0, b1) = (topo.brick_of(lo), topo.brick_of(hi.map(|v| v - 1)));
        let stored = (b0[2]..=b1[2])
            .any(|z| (b0[1]..=b1[1]).any(|y| (b0[0]..=b1[0]).any(|x| topo.slot([x, y, z]) != 0)));
        if !stored {
            return (0.0, 0.0);
        }
        let mut s = [0f64; 3];
        // Row by row, each row's brick found once where the row lies in one brick of each grid (f divides the
        // bricks' side: unless the grids' bricks are offset in x), else voxel by voxel: the same values in the
        // same order either way.
        let row_start = |g: &Grid, j: usize, k: usize| -> Option<(usize, usize)> {
            let t = g.topology();
            let o = t.offset();
            let (x0, x1) = (lo[0] + o[0], hi[0] - 1 + o[0]);
            let (y, z) = (j + o[1], k + o[2]);
            (x0 / BRICK == x1 / BRICK).then(|| {
                let slot = t.slot([x0 / BRICK, y / BRICK, z / BRICK]);
                (
                    slot * BV + BRICK * ((y % BRICK) + BRICK * (z % BRICK)),
                    o[0],
                )
            })
        };
        let (dv, tv) = (dg.values(), tg.values());
        for k in lo[2]..hi[2] {
            for j in lo[1]..hi[1] {
                match row_start(dg, j, k).zip(row_start(tg, j, k)) {
                    Some(((db, dx), (tb, tx))) => {
                        for i in lo[0]..hi[0] {
                            let d = dv[db + (i + dx) % BRICK].max(0.0);
                            let t = tv[tb + (i + tx) % BRICK];
                            s[0] += d as f64;
                            s[1] += d as f64 * emission(t);
                            s[2] += t as f64;
                        }
                    }
                    None => {
                        for i in lo[0]..hi[0] {
                            let (ii, jj, kk) = (i as i64, j as i64, k as i64);
                            let d = dg.at(ii, jj, kk).max(0.0);
                            let t = tg.at(ii, jj, kk);
                            s[0] += d as f64;
                            s[1] += d as f64 * emission(t);
                            s[2] += t as f64;
                        }
                    }
                }
            }
        }
        let temperature = if s[0] > 0.0 {
            // The temperature whose emission per unit density is the block's mean: between the table's
            // rows r − 1 and r where the sum first reaches it.
            let y = s[1] / s[0];
            let r = jt.partition_point(|&x| x < y);
            if r == 0 {
                0.0
            } else if r >= jt.len() {
                ((jt.len() - 1) as f64 * dt) as f32
            } else {
                let span = jt[r] - jt[r - 1];
                let fr = if span > 0.0 {
                    (y - jt[r - 1]) / span
                } else {
                    0.0
                };
                ((r - 1) as f64 * dt + fr * dt) as f32
            }
        } else {
            // No soot: the gas's mean temperature (what interpolation toward a neighbour blends with).
            (s[2] / volume) as f32
        };
        ((s[0] / volume) as f32, temperature)
    };
    // (pbrt-v4's nanovdb box is the dataset's moved by half a voxel, its samples at the voxels' corners: the
    // blocks move with it.)
    let p0 = ds.bounds()[0] + (vol.bounds()[0] - ds.bounds()[0]);
    let voxel = ds.voxel_size() * f as f64;
    let p1 = p0 + DVec3::new(cd[0] as f64, cd[1] as f64, cd[2] as f64) * voxel;
    let coarse = Dataset::from_grids(p0, p1, bricked(cd, block)?, &LoadOptions::default()).ok()?;
    vol.over(coarse, f as f64)
}

/// The blocks of a `cd` copy as two grids (density, temperature) in 8³ bricks, `block` giving each block's
/// values: a brick is stored where a value in it is not zero — the bricks an inline grid of the same samples
/// would store — and the blocks are written into their bricks, with no dense copy beside them. `None` when the
/// allocator refuses.
fn bricked(
    cd: [usize; 3],
    block: impl Fn([usize; 3]) -> (f32, f32) + Sync,
) -> Option<Vec<(&'static str, Grid)>> {
    let nb = cd.map(|n| n.div_ceil(BRICK));
    // A slab of bricks per task (a fire fills its box unevenly); each keeps its bricks that hold data.
    let slabs: Vec<usize> = (0..nb[2]).collect();
    let kept = par_map(slabs, |z| {
        let mut kept: Vec<([usize; 3], Vec<f32>)> = Vec::new();
        for y in 0..nb[1] {
            for x in 0..nb[0] {
                let b = [x, y, z];
                let lo = b.map(|v| v * BRICK);
                let hi = [0, 1, 2].map(|a| (lo[a] + BRICK).min(cd[a]));
                let mut values = Vec::new();
                values.try_reserve_exact(2 * BV).ok()?;
                values.resize(2 * BV, 0f32);
                let mut any = false;
                for k in lo[2]..hi[2] {
                    for j in lo[1]..hi[1] {
                        for i in lo[0]..hi[0] {
                            let (d, t) = block([i, j, k]);
                            let at = (i - lo[0]) + BRICK * ((j - lo[1]) + BRICK * (k - lo[2]));
                            (values[at], values[BV + at]) = (d, t);
                            any |= d != 0.0 || t != 0.0;
                        }
                    }
                }
                if any {
                    kept.try_reserve(1).ok()?;
                    kept.push((b, values));
                }
            }
        }
        Some(kept)
    });
    let kept: Vec<_> = kept
        .into_iter()
        .collect::<Option<Vec<_>>>()?
        .into_iter()
        .flatten()
        .collect();
    let list = kept.iter().map(|(b, _)| *b).collect();
    let topo = std::sync::Arc::new(Topology::from_bricks(cd, [0; 3], list)?);
    let mut density = Grid::filled(topo.clone(), 0.0)?;
    let mut temperature = Grid::filled(topo, 0.0)?;
    for (b, values) in kept {
        let first = b.map(|v| v * BRICK);
        density.brick_mut(first)?.copy_from_slice(&values[..BV]);
        temperature.brick_mut(first)?.copy_from_slice(&values[BV..]);
    }
    Some(vec![("density", density), ("temperature", temperature)])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;

    /// Emission per unit density summed over the channels at `t` (the table's rows, interpolated).
    fn jsum(v: &FireVolume, t: f64) -> f64 {
        let (rows, inv_dt, _) = v.emission_per_density();
        let x = (t * inv_dt).clamp(0.0, (rows.len() - 1) as f64);
        let i = (x as usize).min(rows.len() - 2);
        rows[i] + (x - i as f64) * (rows[i + 1] - rows[i])
    }

    /// A 22 × 20 × 26 fire (dims no block size divides), soot at 1500–1600 K.
    fn fire() -> FireVolume {
        fire_with(&[])
    }

    /// [`fire`] with further parameters.
    fn fire_with(more: &[Param]) -> FireVolume {
        let [nx, ny, nz] = [22usize, 20, 26];
        let (mut d, mut t) = (vec![], vec![]);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = [
                        i as f64 / nx as f64,
                        j as f64 / ny as f64,
                        k as f64 / nz as f64,
                    ];
                    let w = (1.0
                        - ((p[0] - 0.5).powi(2) + (p[1] - 0.5).powi(2) + (p[2] - 0.4).powi(2))
                            / 0.12)
                        .max(0.0);
                    d.push(1e-9 * w);
                    t.push(1500.0 + 100.0 * w);
                }
            }
        }
        let mut list = vec![
            Param::point3("p0", [0.0, 0.0, 0.0]),
            Param::point3("p1", [2.2, 2.0, 2.6]),
            Param::floats("density", &d),
            Param::floats("temperature", &t),
            Param::int("nx", nx as i64),
            Param::int("ny", ny as i64),
            Param::int("nz", nz as i64),
        ];
        list.extend_from_slice(more);
        FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn the_copy_marches_a_lattice_of_its_own_whatever_the_fire_reads() {
        // A fire that reads its grids in place (`lattice off`) and one with its dense copy: their light's copies
        // are the same, and the one kept gets a dense lattice — the 10 × 11 × 13 blocks padded by one, 8 bytes
        // each — while a copy only checked holds none.
        let lattice = |v: &str| coarse(&fire_with(&[Param::string("lattice", v)]), 2, u64::MAX);
        let (off, dense) = (
            lattice("off").expect("a copy"),
            lattice("dense").expect("a copy"),
        );
        let padded = 13 * 12 * 15 * 8;
        let grids = off.dataset().bytes();
        assert_eq!(off.mip_bytes(), dense.mip_bytes());
        assert!(
            off.mip_bytes() < grids + padded,
            "{} held before it is kept",
            off.mip_bytes()
        );
        let (off, dense) = (off.with_lattice(u64::MAX), dense.with_lattice(u64::MAX));
        assert_eq!(off.mip_bytes(), dense.mip_bytes());
        assert!(
            off.mip_bytes() >= grids + padded,
            "{} < {grids} + {padded}",
            off.mip_bytes()
        );
    }

    #[test]
    fn the_bricked_copy_holds_what_an_inline_grid_of_its_blocks_holds() {
        // Blocks over 19 × 9 × 17 (bricks cut by every edge), zero outside a ball and on one plane of it (−0.0
        // there: zero as the inline grid's rule reads it), temperature alone in the far corner's brick: the same
        // samples everywhere and the same bricks stored as `Dataset::from_inline` of the dense arrays.
        let cd = [19usize, 9, 17];
        let block = |[i, j, k]: [usize; 3]| -> (f32, f32) {
            let r2 = (i as f32 - 9.0).powi(2) + (j as f32 - 4.0).powi(2) + (k as f32 - 8.0).powi(2);
            if [i, j, k] == [18, 8, 16] {
                return (0.0, 300.0);
            }
            if r2 > 36.0 || k == 8 {
                return (-0.0, 0.0);
            }
            (1e-9 * (37.0 - r2), 1200.0 + r2)
        };
        let grids = bricked(cd, block).expect("bricked");
        let (p0, p1) = (DVec3::ZERO, DVec3::new(1.9, 0.9, 1.7));
        let ours = Dataset::from_grids(p0, p1, grids, &LoadOptions::default()).expect("a dataset");
        let mut dense = [Vec::new(), Vec::new()];
        for k in 0..cd[2] {
            for j in 0..cd[1] {
                for i in 0..cd[0] {
                    let (d, t) = block([i, j, k]);
                    dense[0].push(d);
                    dense[1].push(t);
                }
            }
        }
        let inline = Dataset::from_inline(
            cd,
            p0,
            p1,
            &[("density", &dense[0]), ("temperature", &dense[1])],
            &LoadOptions::default(),
        )
        .expect("a dataset");
        assert_eq!(ours.dims(), inline.dims());
        assert_eq!(ours.bounds(), inline.bounds());
        let (a, b) = (ours.topology(), inline.topology());
        assert_eq!(a.active_bricks(), b.active_bricks());
        assert_eq!(a.active_bricks(), 9, "the ball's 8 bricks and the corner's");
        for (ca, cb) in ours.channels().iter().zip(inline.channels()) {
            assert_eq!(ca.name, cb.name);
            for k in -1..=cd[2] as i64 {
                for j in -1..=cd[1] as i64 {
                    for i in -1..=cd[0] as i64 {
                        let (x, y) = (ca.grid.at(i, j, k), cb.grid.at(i, j, k));
                        assert_eq!(x.to_bits(), y.to_bits(), "{} at ({i}, {j}, {k})", ca.name);
                    }
                }
            }
        }
        // Grids on two topologies are refused, naming the channel.
        let mut two = bricked(cd, block).expect("bricked");
        two[1].1 = bricked(cd, |_| (1.0, 1.0)).expect("bricked").remove(1).1;
        let e = Dataset::from_grids(p0, p1, two, &LoadOptions::default()).unwrap_err();
        assert!(e.to_string().contains("temperature"), "{e}");
    }

    #[test]
    fn pbrt_v4s_shifted_nanovdb_box_has_its_copy_shifted_alike() {
        // pbrt-v4's nanovdb medium puts its samples at the voxels' corners: its box is the dataset's moved by half
        // a voxel. The copy's blocks move with it (their box starts at the fire's; left in the dataset's box the
        // 2³ copy of this 48-voxel plume measured 4.8 % from the fire's march at half a voxel, moved 3.4 %).
        let f = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/valid/nvdb/plume48.nvdb"
        );
        let v = FireVolume::new(&[
            Param::string("filename", f),
            Param::string("mode", "pbrt"),
            Param::spectrum("sigma_a", &[40.0]),
            Param::spectrum("sigma_s", &[0.0]),
            Param::float("Lescale", 1.0),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
        let half = v.dataset().voxel_size() * 0.5;
        assert!(
            (v.bounds()[0] - (v.dataset().bounds()[0] + half))
                .abs()
                .max_element()
                < 1e-12
        );
        let m = coarse(&v, 2, u64::MAX).expect("a copy of the shifted fire");
        let (mb, vb) = (m.bounds()[0], v.bounds()[0]);
        let light =
            crate::light::FireLight::new(std::sync::Arc::new(v), crate::light::Weighting::Power)
                .unwrap_or_else(|e| panic!("{e}"));
        let bias = light.block_bias_alone(&m);
        assert!((mb - vb).abs().max_element() < 1e-12, "{} {}", mb, vb);
        assert!(
            bias.abs() < 0.04,
            "the copy's line {bias:+.4} from the fire's own march"
        );
    }

    #[test]
    fn a_block_holds_its_voxels_soot_and_emits_what_they_emit() {
        // Per block of 2³ and 4³ voxels (the last ones cut by the grid's edge): its density the voxels' mean
        // (the soot kept to f32 rounding), and its temperature one at which it emits their mean emission (to the
        // table's interpolation); the copy's box starts at the fire's and its voxels are f times the fire's.
        let v = fire();
        assert!(
            coarse(&v, 3, u64::MAX).is_none(),
            "blocks of 2, 4 or 8 voxels only"
        );
        assert!(coarse(&v, 2, 1000).is_none(), "within the budget only");
        for f in [2usize, 4] {
            let m = coarse(&v, f, u64::MAX).expect("a copy");
            let (dims, cd) = (v.dataset().dims(), m.dataset().dims());
            assert_eq!(cd, dims.map(|n| n.div_ceil(f)));
            assert_eq!(m.dataset().bounds()[0], v.dataset().bounds()[0]);
            assert!(
                (m.dataset().voxel_size() - v.dataset().voxel_size() * f as f64)
                    .abs()
                    .max_element()
                    < 1e-12
            );
            let (fd, ft) = (
                &v.dataset().channels()[v.density_channel()].grid,
                &v.dataset().channels()[v.temperature_channel().unwrap()].grid,
            );
            let (md, mt) = (
                &m.dataset().channels()[0].grid,
                &m.dataset().channels()[1].grid,
            );
            let (mut soot, mut soot_copy) = (0.0, 0.0);
            for bz in 0..cd[2] {
                for by in 0..cd[1] {
                    for bx in 0..cd[0] {
                        let (mut sd, mut se) = (0.0, 0.0);
                        for k in bz * f..(bz * f + f).min(dims[2]) {
                            for j in by * f..(by * f + f).min(dims[1]) {
                                for i in bx * f..(bx * f + f).min(dims[0]) {
                                    let (d, t) = (
                                        fd.at(i as i64, j as i64, k as i64) as f64,
                                        ft.at(i as i64, j as i64, k as i64) as f64,
                                    );
                                    sd += d;
                                    se += d * jsum(&v, t);
                                }
                            }
                        }
                        let (d, t) = (
                            md.at(bx as i64, by as i64, bz as i64) as f64,
                            mt.at(bx as i64, by as i64, bz as i64) as f64,
                        );
                        let volume = (f * f * f) as f64;
                        assert!(
                            (d - sd / volume).abs() <= 1e-6 * sd / volume + 1e-30,
                            "block {bx} {by} {bz}: {d} vs {}",
                            sd / volume
                        );
                        if sd > 0.0 {
                            let e = d * jsum(&v, t);
                            assert!(
                                (e / (se / volume) - 1.0).abs() < 1e-3,
                                "block {bx} {by} {bz}: emits {e} vs {}",
                                se / volume
                            );
                        }
                        soot += sd;
                        soot_copy += d * volume;
                    }
                }
            }
            assert!((soot_copy / soot - 1.0).abs() < 1e-6);
        }
        // A volume with what the copy does not carry (a species' grid) has none.
        let (with_species, _) = crate::volume::tests::blob_pair(&[], true);
        assert!(coarse(&with_species, 2, u64::MAX).is_none());
    }
}
