//! What weighs a fire's voxels for its light: each voxel's luminance or power in the bins (the light's weights),
//! and the sums its power, luminous flux and mean extinction take from them.

use super::Weighting;
use crate::volume::{FireVolume, VoxelEmission};
use glam::DVec3;
use std::sync::atomic::{AtomicU64, Ordering::Relaxed};

/// What weighs a brick's voxels for the light: each voxel's luminance or power in the bins, and the sums the
/// light's power (W: the soot's over the whole spectrum, the lines', the reaction's), luminous flux and, for
/// `escaping`, mean extinction take from them.
pub(super) struct Weigher<'a> {
    vol: &'a FireVolume,
    topo: &'a crate::grid::Topology,
    weighting: Weighting,
    /// The lattice's corner and voxel size.
    p0: DVec3,
    voxel: DVec3,
    /// Per channel its XYZ per unit radiance and its width (nm, or 1 per band).
    xyz: &'a [DVec3],
    widths: &'a [f64],
    /// The physical fire's emitters (none in pbrt-v4's mode: the power is the bins').
    src: Option<&'a crate::volume::Source>,
    density: usize,
    temperature: Option<usize>,
    /// The soot's power depends on T only (an integral over the spectrum): found once per 0.5 K for the whole
    /// build, in a table to 10 000 K that the workers fill as they meet a temperature (a race computes the same
    /// value twice; [`EMPTY`] until then), in a shared map beyond it.
    known: Vec<AtomicU64>,
    beyond: std::sync::Mutex<std::collections::HashMap<i64, f64>>,
    /// Where the fire's emission is its soot's alone (and the weighting needs no extinction): a voxel's
    /// luminance and power in the bins from its density and temperature, without its coefficients per bin.
    soot: Option<VoxelEmission>,
}

/// A [`Weigher::known`] entry not found yet.
const EMPTY: u64 = u64::MAX;

impl<'a> Weigher<'a> {
    /// The weigher of `vol`'s voxels over the bricks of `topo` by `weighting`, with each channel's XYZ per unit
    /// radiance and width, and the physical fire's emitters `src`.
    pub(super) fn new(
        vol: &'a FireVolume,
        topo: &'a crate::grid::Topology,
        weighting: Weighting,
        (xyz, widths): (&'a [DVec3], &'a [f64]),
        src: Option<&'a crate::volume::Source>,
    ) -> Weigher<'a> {
        let ybar: Vec<f64> = xyz.iter().map(|v| v.y).collect();
        Weigher {
            vol,
            topo,
            weighting,
            p0: vol.dataset().bounds()[0],
            voxel: vol.dataset().voxel_size(),
            xyz,
            widths,
            src,
            density: vol.density_channel(),
            temperature: vol.temperature_channel(),
            known: (0..=20_000).map(|_| AtomicU64::new(EMPTY)).collect(),
            beyond: std::sync::Mutex::new(std::collections::HashMap::new()),
            // (The extinction `escaping` weighs by is the coefficients'.)
            soot: (weighting != Weighting::Escaping)
                .then(|| vol.voxel_emission(&ybar, widths))
                .flatten(),
        }
    }

    /// The soot's full-spectrum power per unit density at `t`.
    fn soot_power(&self, t: f64) -> f64 {
        self.src.map_or(0.0, |s| s.soot_power(t))
    }

    /// Brick `b`'s voxel weights into `out` (allocated when one emits; `sa`, `ss`, `j` a channel's scratch), and
    /// its sums: power, luminance, mean extinction over the bins' widths.
    pub(super) fn brick(
        &self,
        b: &[usize; 3],
        sa: &mut [f64],
        ss: &mut [f64],
        j: &mut [f64],
        out: &mut Option<Box<[f32; 512]>>,
    ) -> (f64, f64, f64) {
        let (mut pw, mut plm, mut ext) = (0.0, 0.0, 0.0);
        let span = [0, 1, 2].map(|a| self.topo.brick_span(b[a], a));
        if let Some(soot) = &self.soot {
            let chs = self.vol.dataset().channels();
            let (dg, tg) = (
                &chs[self.density].grid,
                self.temperature.map(|q| &chs[q].grid),
            );
            // (A brick the density does not store holds no soot: nothing emits there.)
            let topo = dg.topology();
            if topo.slot(topo.brick_of([span[0].0, span[1].0, span[2].0])) == 0
                && !(dg.background() > 0.0)
            {
                return (0.0, 0.0, 0.0);
            }
            for k in span[2].0..span[2].1 {
                for jy in span[1].0..span[1].1 {
                    for i in span[0].0..span[0].1 {
                        let (ii, jj, kk) = (i as i64, jy as i64, k as i64);
                        let d = dg.at(ii, jj, kk).max(0.0) as f64;
                        let t = tg.map_or(0.0, |g| g.at(ii, jj, kk) as f64);
                        let [lum, band] = soot.at(d, t);
                        self.add([i, jy, k], (lum, band), out, (&mut pw, &mut plm));
                    }
                }
            }
            return (pw, plm, 0.0);
        }
        for k in span[2].0..span[2].1 {
            for jy in span[1].0..span[1].1 {
                for i in span[0].0..span[0].1 {
                    let p =
                        self.p0 + (DVec3::new(i as f64, jy as f64, k as f64) + 0.5) * self.voxel;
                    self.vol.coefficients(p, sa, ss, j);
                    if self.weighting == Weighting::Escaping {
                        ext += (0..self.widths.len())
                            .map(|q| (sa[q] + ss[q]) * self.widths[q])
                            .sum::<f64>();
                    }
                    let lum: f64 = (0..self.widths.len()).map(|q| j[q] * self.xyz[q].y).sum();
                    let band: f64 = (0..self.widths.len()).map(|q| j[q] * self.widths[q]).sum();
                    self.add([i, jy, k], (lum, band), out, (&mut pw, &mut plm));
                }
            }
        }
        let n = span.iter().map(|s| s.1 - s.0).product::<usize>().max(1) as f64;
        (pw, plm, ext / (n * self.widths.iter().sum::<f64>()))
    }

    /// Voxel (i, j, k)'s luminance and power in the bins `(lum, band)` as its weight (none when both are 0),
    /// added to the brick's sums: its power (W, from the physical fire's emitters; the bins' in pbrt-v4's mode)
    /// and luminance.
    fn add(
        &self,
        [i, jy, k]: [usize; 3],
        (lum, band): (f64, f64),
        out: &mut Option<Box<[f32; 512]>>,
        (pw, plm): (&mut f64, &mut f64),
    ) {
        if !(lum > 0.0 || band > 0.0) {
            return;
        }
        out.get_or_insert_with(|| Box::new([0.0; 512]))[self.topo.index(i, jy, k) % 512] =
            match self.weighting {
                Weighting::Luminance => lum,
                Weighting::Power | Weighting::Escaping => band,
            } as f32;
        *plm += lum;
        *pw += match self.src {
            None => band,
            Some(s) => {
                let chs = self.vol.dataset().channels();
                let at = |q: usize| chs[q].grid.at(i as i64, jy as i64, k as i64);
                let d = at(self.density).max(0.0) as f64;
                let t = self.temperature.map(|q| at(q) as f64).unwrap_or(0.0);
                let key = (t * 2.0).round() as i64;
                let soot = match usize::try_from(key).ok().and_then(|k| self.known.get(k)) {
                    Some(slot) => match slot.load(Relaxed) {
                        EMPTY => {
                            let p = self.soot_power(key as f64 / 2.0);
                            slot.store(p.to_bits(), Relaxed);
                            p
                        }
                        bits => f64::from_bits(bits),
                    },
                    None => *self
                        .beyond
                        .lock()
                        .unwrap_or_else(|e| e.into_inner())
                        .entry(key)
                        .or_insert_with(|| self.soot_power(key as f64 / 2.0)),
                };
                s.voxel_power(d, t, soot, at)
            }
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;

    #[test]
    fn a_voxels_weight_from_its_soots_weighed_rows_is_its_coefficients_weighed() {
        // A 19 × 12 × 10 fire of soot from 600 K to 2 100 K (its table's rows interpolated; its coolest voxels
        // below the emission threshold), weighed by luminance and by power: every voxel's weight and every
        // brick's sums from the emission table's weighed rows as from the voxel's coefficients per bin, to
        // rounding.
        let [nx, ny, nz] = [19usize, 12, 10];
        let (mut d, mut t) = (vec![], vec![]);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let r2 = [(i, nx), (j, ny), (k, nz)]
                        .map(|(v, n)| (v as f64 / n as f64 - 0.5).powi(2))
                        .iter()
                        .sum::<f64>();
                    let w = (1.0 - r2 / 0.2).max(0.0);
                    d.push(2e-9 * w + 1e-10 * (i % 3) as f64);
                    t.push(600.0 + 1500.0 * w + 7.3 * (j % 4) as f64);
                }
            }
        }
        let vol = FireVolume::new(&[
            Param::point3("p0", [0.0, 0.0, 0.0]),
            Param::point3("p1", [1.9, 1.2, 1.0]),
            Param::floats("density", &d),
            Param::floats("temperature", &t),
            Param::int("nx", nx as i64),
            Param::int("ny", ny as i64),
            Param::int("nz", nz as i64),
        ])
        .unwrap_or_else(|e| panic!("{e}"));
        let crate::volume::ColorMode::Spectral(g) = vol.color_mode() else {
            panic!("a spectral fire")
        };
        let (xyz, widths) = (vol.channel_xyz(), vec![g.width_nm(); g.count()]);
        let topo = vol.dataset().topology();
        let c = vol.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.abs().max(b.abs());
        for weighting in [Weighting::Luminance, Weighting::Power] {
            let fast = Weigher::new(&vol, topo, weighting, (&xyz, &widths), vol.source());
            assert!(fast.soot.is_some(), "a soot fire weighed from its rows");
            let mut slow = Weigher::new(&vol, topo, weighting, (&xyz, &widths), vol.source());
            slow.soot = None;
            let mut weighed = 0;
            topo.for_each_slot(|b, _| {
                let (mut wf, mut ws) = (None, None);
                let sf = fast.brick(&b, &mut sa, &mut ss, &mut j, &mut wf);
                let s = slow.brick(&b, &mut sa, &mut ss, &mut j, &mut ws);
                assert!(
                    close(sf.0, s.0) && close(sf.1, s.1),
                    "{weighting:?} {b:?}: {sf:?} {s:?}"
                );
                let (wf, ws) = (wf.expect("weights"), ws.expect("weights"));
                // (To rounding of the brick's brightest: a dark voxel's coefficients, sampled at its centre,
                // may catch 1e-16 of a neighbour's.)
                let top = ws.iter().fold(0f32, |m, &v| m.max(v)) as f64;
                for (x, y) in wf.iter().zip(ws.iter()) {
                    let (x, y) = (*x as f64, *y as f64);
                    assert!(
                        close(x, y) || (x - y).abs() <= 1e-9 * top,
                        "{weighting:?} {b:?}: {x} {y}"
                    );
                    weighed += (y > 1e-9 * top) as usize;
                }
            });
            // (Some voxels do not emit: below the threshold, or beyond the dims in a brick.)
            assert!(weighed > 500 && weighed < nx * ny * nz, "{weighed}");
        }
    }
}
