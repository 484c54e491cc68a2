//! The fire at a coarser resolution, for the fire light's line estimate (issue 29): a copy whose voxels are
//! blocks of f³ of the fire's (f = 2, 4 or 8), marched by the same kernel at the light's coarse step.
//!
//! At production resolutions the light's march reads a lattice of hundreds of MB at scattered places (every
//! light sample a different direction: a cache miss per sample); the copy's few MB stay in the caches, so a
//! light sample at 512³ costs what it costs at 64³.
//!
//! A block's density is its voxels' mean (extinction is linear in density: the block holds the soot its voxels
//! hold), and its temperature the one whose emission per unit density, summed over the channels, is the
//! block's density-weighted mean: the block emits what its voxels emit, with the spectrum of one temperature.
//! What that costs in accuracy (the colour where a block spans the flame's sheet, the transmittance's
//! nonlinearity) is the line's bias against the volume's own march, measured in the tests and
//! docs/results/log.md; the light's `linecorrection` removes it.

use super::parts;
use super::{lanes, lattice, CapCounter, FireVolume, Integrator};
use crate::dataset::{par_map, Dataset, LoadOptions};
use crate::grid::{Interpolation, BRICK};
use crate::majorant::MajorantGrid;
use glam::DVec3;

/// The most voxels the copy holds (128³, 16 bytes each with its lattice): it exists to fit in the caches.
const MAX_VOXELS: usize = 1 << 21;

impl FireVolume {
    /// This volume at 1/`f` of its resolution per axis (`f` = 2, 4 or 8), for the fire light's coarse line; its
    /// box is the fire's rounded up to whole blocks. `None` when the volume holds what the copy would not carry
    /// (species, an emission or `Lescale` grid, T-dependent absorption, motion blur, refraction, diffusion,
    /// thick lines, embers, a non-zero background, pbrt-v4's shifted nanovdb box), marches without lanes or a
    /// lattice, has no temperature, or when the copy would exceed `budget` bytes: the light then marches the
    /// volume itself.
    pub(crate) fn mip(&self, f: usize, budget: u64) -> Option<FireVolume> {
        let carried = self.soot_only()
            && self.bounds.margin == 0.0
            && self.grids.ds.interpolation() == Interpolation::Trilinear
            && self
                .grids
                .ds
                .channels()
                .iter()
                .all(|c| c.grid.background() == 0.0);
        let tch = self.grids.temperature?;
        if !carried || !matches!(f, 2 | 4 | 8) {
            return None;
        }
        // Emission per unit density summed over the channels, per row of the table: it must grow with T (the
        // block's temperature is found by inverting it).
        let c = self.channels();
        let jsum: Vec<f64> = (0..self.model.j.rows)
            .map(|r| (0..c).map(|ch| self.model.j.value(r, ch) as f64).sum())
            .collect();
        if jsum.len() < 2 || jsum.windows(2).any(|w| !(w[1] >= w[0])) {
            return None;
        }
        let dims = self.grids.ds.dims();
        let cd = dims.map(|n| n.div_ceil(f));
        let n = cd[0] * cd[1] * cd[2];
        // Two f32 grids per block, the lattice's two padded floats, and no more: each worker fills its own rows.
        let need = (n as u64) * (8 + 16);
        if n > MAX_VOXELS || need > budget {
            return None;
        }

        // Per block, from the stored bricks (empty ones read 0): Σ d, Σ d·J(T) and Σ T over its voxels, in
        // place, then its density (the mean) and temperature.
        let (jt, inv_dt, dt) = (&jsum, self.model.j.inv_dt, self.model.j.dt);
        let emission = |t: f32| -> f64 {
            let x = (t as f64 * inv_dt).clamp(0.0, (jt.len() - 1) as f64);
            let i = (x as usize).min(jt.len() - 2);
            jt[i] + (x - i as f64) * (jt[i + 1] - jt[i])
        };
        let topo = self.grids.ds.topology();
        let grids = self.grids.ds.channels();
        let (dg, tg) = (&grids[self.grids.density].grid, &grids[tch].grid);
        let volume = (f * f * f) as f64;
        let block = |q: [usize; 3]| -> (f32, f32) {
            let lo = q.map(|v| v * f);
            let hi = [0, 1, 2].map(|a| (lo[a] + f).min(dims[a]));
            let (b0, b1) = (topo.brick_of(lo), topo.brick_of(hi.map(|v| v - 1)));
            let stored = (b0[2]..=b1[2]).any(|z| {
                (b0[1]..=b1[1]).any(|y| (b0[0]..=b1[0]).any(|x| topo.slot([x, y, z]) != 0))
            });
            if !stored {
                return (0.0, 0.0);
            }
            let mut s = [0f64; 3];
            for k in lo[2]..hi[2] {
                for j in lo[1]..hi[1] {
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
        let mut density = vec![0f32; n];
        let mut temperature = vec![0f32; n];
        // Rows of blocks, a few parts per worker (a fire fills its box unevenly).
        let plane = cd[0] * cd[1];
        let part = plane * cd[2].div_ceil(4 * crate::par::threads(4)).max(1);
        let parts: Vec<_> = density
            .chunks_mut(part)
            .zip(temperature.chunks_mut(part))
            .enumerate()
            .collect();
        par_map(parts, |(p, (ds, ts))| {
            for (o, (d, t)) in ds.iter_mut().zip(ts.iter_mut()).enumerate() {
                let q = p * part + o;
                (*d, *t) = block([q % cd[0], (q / cd[0]) % cd[1], q / plane]);
            }
        });
        let [p0, _] = self.grids.ds.bounds();
        let voxel = self.grids.ds.voxel_size() * f as f64;
        let p1 = p0 + DVec3::new(cd[0] as f64, cd[1] as f64, cd[2] as f64) * voxel;
        let ds = Dataset::from_inline(
            cd,
            p0,
            p1,
            &[("density", &density), ("temperature", &temperature)],
            &LoadOptions::default(),
        )
        .ok()?;
        drop((density, temperature));

        // Its own march lattice when the volume has one (else its march too reads its grids in place).
        let ch = ds.channels();
        let (lat, ranges) = if self.estimator.lattice.is_some() {
            let (lat, ranges) =
                lattice::Lattice::build(&ch[0].grid, Some(&ch[1].grid), &[], BRICK, budget)?;
            (Some(lat), ranges.into_iter().map(Some).collect())
        } else {
            (None, vec![None; 2])
        };
        let majorant = MajorantGrid::with_ranges(&ds, BRICK, ranges);
        let nb = majorant.counts().iter().product::<usize>();
        let sigma = self
            .model
            .a
            .iter()
            .zip(&self.model.s)
            .map(|(a, s)| a + s)
            .fold(0.0, f64::max);
        let brick_sigma: Vec<f64> = (0..nb).map(|b| majorant.max(b, 0) as f64 * sigma).collect();
        let brick_empty: Vec<bool> = (0..nb).map(|b| majorant.max(b, 0) <= 0.0).collect();
        let dmax = (0..nb).map(|b| majorant.max(b, 0)).fold(0f32, f32::max) as f64;
        let step = self.estimator.step * f as f64;
        let clip_box = ds.bounds();
        let mut v = FireVolume {
            grids: parts::Grids {
                ds,
                density: 0,
                temperature: Some(1),
                lescale: None,
                emission_grid: false,
                species: Vec::new(),
            },
            model: parts::Model {
                basis: self.model.basis.clone(),
                mode: self.model.mode,
                a: self.model.a.clone(),
                a_t: None,
                s: self.model.s.clone(),
                j: self.model.j.clone(),
                t_emit: self.model.t_emit,
                physical_colour: self.model.physical_colour,
                scatter_color: None,
                g: self.model.g,
                point_model: self.model.point_model.clone(),
            },
            bounds: parts::Bounds {
                majorant,
                brick_sigma,
                brick_empty,
                clip_box,
                margin: 0.0,
            },
            layers: parts::Layers::default(),
            estimator: parts::Estimator {
                integrator: Integrator::March,
                step,
                step_tau: self.estimator.step_tau,
                cutoff: self.estimator.cutoff,
                lanes: None,
                lattice: Default::default(),
            },
            report: parts::Report {
                tables: Vec::new(),
                build_seconds: 0.0,
                source: None,
                spare: 0,
                threads: self.report.threads,
                notes: Vec::new(),
            },
            capped: CapCounter::default(),
            #[cfg(test)]
            fault: self.fault.clone(),
        };
        v.estimator.lanes = Some(lanes::LaneTables::build(&v, dmax, dmax, &[], step)?);
        if let Some(lat) = lat {
            v.estimator.lattice = lattice::Slot::ready(lat);
        }
        Some(v)
    }

    /// Whether this volume's light is its soot's alone, marched by the lane kernel: no species, emission or
    /// `Lescale` grid, T-dependent absorption, motion blur, refraction, diffusion, thick lines or embers.
    pub(super) fn soot_only(&self) -> bool {
        self.estimator.lanes.is_some()
            && (self.estimator.lattice.is_some()
                || self.grids.ds.interpolation() == crate::grid::Interpolation::Trilinear)
            && self.estimator.integrator == Integrator::March
            && self.grids.species.is_empty()
            && self.grids.lescale.is_none()
            && !self.grids.emission_grid
            && self.model.a_t.is_none()
            && self.layers.blur.is_none()
            && self.layers.refraction.is_none()
            && self.layers.diffusion.is_none()
            && self.layers.lines.is_none()
            && self.layers.embers.is_none()
    }

    /// Bytes the copy of [`mip`](Self::mip) holds: its grids, lattice and majorants.
    pub(crate) fn mip_bytes(&self) -> usize {
        self.grids.ds.bytes()
            + self.estimator.lattice.built().map_or(0, |l| l.bytes())
            + self.bounds.majorant.bytes()
            + self.bounds.brick_sigma.len() * 9
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;

    /// Emission per unit density summed over the channels at `t` (the table's rows, interpolated).
    fn jsum(v: &FireVolume, t: f64) -> f64 {
        let c = v.channels();
        let x = (t * v.model.j.inv_dt).clamp(0.0, (v.model.j.rows - 1) as f64);
        let i = (x as usize).min(v.model.j.rows - 2);
        let at = |r: usize| (0..c).map(|ch| v.model.j.value(r, ch) as f64).sum::<f64>();
        at(i) + (x - i as f64) * (at(i + 1) - at(i))
    }

    /// A 22 × 20 × 26 fire (dims no block size divides), soot at 1500–1600 K.
    fn fire() -> FireVolume {
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
        FireVolume::new(&[
            Param::point3("p0", [0.0, 0.0, 0.0]),
            Param::point3("p1", [2.2, 2.0, 2.6]),
            Param::floats("density", &d),
            Param::floats("temperature", &t),
            Param::int("nx", nx as i64),
            Param::int("ny", ny as i64),
            Param::int("nz", nz as i64),
        ])
        .unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn a_block_holds_its_voxels_soot_and_emits_what_they_emit() {
        // Per block of 2³ and 4³ voxels (the last ones cut by the grid's edge): its density the voxels' mean
        // (the soot kept to f32 rounding), and its temperature one at which it emits their mean emission (to the
        // table's interpolation); the copy's box starts at the fire's and its voxels are f times the fire's.
        let v = fire();
        assert!(
            v.mip(3, u64::MAX).is_none(),
            "blocks of 2, 4 or 8 voxels only"
        );
        assert!(v.mip(2, 1000).is_none(), "within the budget only");
        for f in [2usize, 4] {
            let m = v.mip(f, u64::MAX).expect("a copy");
            let (dims, cd) = (v.grids.ds.dims(), m.grids.ds.dims());
            assert_eq!(cd, dims.map(|n| n.div_ceil(f)));
            assert_eq!(m.grids.ds.bounds()[0], v.grids.ds.bounds()[0]);
            assert!(
                (m.grids.ds.voxel_size() - v.grids.ds.voxel_size() * f as f64)
                    .abs()
                    .max_element()
                    < 1e-12
            );
            let (fd, ft) = (
                &v.grids.ds.channels()[v.grids.density].grid,
                &v.grids.ds.channels()[v.grids.temperature.unwrap()].grid,
            );
            let (md, mt) = (
                &m.grids.ds.channels()[0].grid,
                &m.grids.ds.channels()[1].grid,
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
        assert!(with_species.mip(2, u64::MAX).is_none());
    }
}
