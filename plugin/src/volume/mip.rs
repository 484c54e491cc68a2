//! The volume's side of the fire light's coarse copy (`light/coarse.rs`): the same soot model over coarser grids,
//! and whether this volume's light can be carried by one.

use super::parts;
use super::{lanes, lattice, CapCounter, FireVolume, Integrator};
use crate::dataset::Dataset;
use crate::grid::{Interpolation, BRICK};
use crate::majorant::MajorantGrid;

impl FireVolume {
    /// This volume's soot model over other grids `ds` (density, then temperature: a coarser copy of its own, the
    /// fire light's), its step `f` times its own, reading its grids in place (whatever this volume's `lattice`) until
    /// it is given a lattice of its own ([`with_lattice`](Self::with_lattice)). `None` when the lanes cannot be
    /// built.
    pub(crate) fn over(&self, ds: Dataset, f: f64) -> Option<FireVolume> {
        // (No lattice yet: a copy is built, checked against the fire and perhaps dropped, and its lattice — the
        // same values, marched alike — is built only for the copy kept, [`with_lattice`](Self::with_lattice).)
        let majorant = MajorantGrid::with_ranges(&ds, BRICK, vec![None; 2]);
        let nb = majorant.counts().iter().product::<usize>();
        let sigma = self
            .model
            .a()
            .iter()
            .zip(self.model.s())
            .map(|(a, s)| a + s)
            .fold(0.0, f64::max);
        let brick_sigma: Vec<f64> = (0..nb).map(|b| majorant.max(b, 0) as f64 * sigma).collect();
        let brick_empty: Vec<bool> = (0..nb).map(|b| majorant.max(b, 0) <= 0.0).collect();
        let dmax = (0..nb).map(|b| majorant.max(b, 0)).fold(0f32, f32::max) as f64;
        let step = self.estimator.step() * f;
        let clip_box = ds.bounds();
        let mut v = FireVolume {
            grids: parts::Grids::density_and_temperature(ds),
            model: self.model.soot_copy(),
            bounds: parts::Bounds::new(majorant, (brick_sigma, brick_empty), clip_box, 0.0),
            layers: parts::Layers::default(),
            estimator: parts::Estimator::new(
                Integrator::March,
                step,
                self.estimator.step_tau(),
                self.estimator.cutoff(),
            ),
            report: parts::Report::of_copy(self.report.threads()),
            capped: CapCounter::default(),
            #[cfg(test)]
            fault: self.fault.clone(),
        };
        v.estimator
            .set_lanes(Some(lanes::LaneTables::build(&v, dmax, dmax, &[], step)?));
        Some(v)
    }

    /// A coarse copy ([`over`](Self::over)) with its march lattice, within `budget` bytes (without one if the
    /// budget or the allocator refuses: the same line, slower). The copy is made to fit in the caches, at most
    /// 128³ blocks: its lattice is a few MB, and the light's line marches it at every sample (without it the
    /// fire-lit room's render took 1.3× as long).
    pub(crate) fn with_lattice(mut self, budget: u64) -> FireVolume {
        let ch = self.grids.ds().channels();
        if let Some((lat, _)) =
            lattice::Lattice::build(&ch[0].grid, Some(&ch[1].grid), &[], BRICK, budget)
        {
            self.estimator.set_lattice(lattice::Slot::ready(lat));
        }
        self
    }

    /// Whether a coarse copy carries this volume's light: its soot's alone ([`soot_only`](Self::soot_only)),
    /// trilinear, its grids reading 0 where they store nothing.
    pub(crate) fn coarse_copyable(&self) -> bool {
        self.soot_only()
            && self.grids.ds().interpolation() == Interpolation::Trilinear
            && self
                .grids
                .ds()
                .channels()
                .iter()
                .all(|c| c.grid.background() == 0.0)
    }

    /// The emission per unit density summed over the channels, per row of the temperature table, with the
    /// table's 1/ΔT and ΔT (K).
    pub(crate) fn emission_per_density(&self) -> (Vec<f64>, f64, f64) {
        let j = self.model.j();
        let sum = (0..j.rows()).map(|r| self.weighed_row(r, None)).collect();
        (sum, j.inv_dt(), j.dt())
    }

    /// Row `r` of the emission table summed over the channels, each weighed by `w` (1 without).
    fn weighed_row(&self, r: usize, w: Option<&[f64]>) -> f64 {
        let j = self.model.j();
        (0..self.channels())
            .map(|ch| j.value(r, ch) as f64 * w.map_or(1.0, |w| w[ch]))
            .sum()
    }

    /// A voxel's emission weighed per channel twice over (`a`, `b`: the fire light's ȳ and the bins' widths),
    /// as one table lookup per voxel, where this volume's emission is its soot's alone
    /// ([`soot_only`](Self::soot_only)): the density times the emission table's rows, weighed once. `None`
    /// elsewhere (species, lines, a `Lescale` or emission grid, diffusion: the point's coefficients then).
    pub(crate) fn voxel_emission(&self, a: &[f64], b: &[f64]) -> Option<VoxelEmission> {
        let c = self.channels();
        if !self.soot_only() || a.len() < c || b.len() < c {
            return None;
        }
        let j = self.model.j();
        let rows = (0..j.rows())
            .map(|r| [self.weighed_row(r, Some(a)), self.weighed_row(r, Some(b))])
            .collect();
        Some(VoxelEmission {
            rows,
            inv_dt: j.inv_dt(),
            t_emit: self.model.t_emit(),
            has_temperature: self.grids.temperature().is_some(),
        })
    }

    /// Whether this volume's light is its soot's alone, marched by the lane kernel: no species, emission or
    /// `Lescale` grid, T-dependent absorption, motion blur, refraction, diffusion, thick lines or embers.
    pub(super) fn soot_only(&self) -> bool {
        self.estimator.lanes().is_some()
            && (self.estimator.lattice().is_some()
                || self.grids.ds().interpolation() == crate::grid::Interpolation::Trilinear)
            && self.estimator.integrator() == Integrator::March
            && self.grids.species().is_empty()
            && self.grids.lescale().is_none()
            && !self.grids.emission_grid()
            && self.model.a_t().is_none()
            && self.layers.none()
    }

    /// Bytes the copy of [`mip`](Self::mip) holds: its grids, lattice and majorants.
    pub(crate) fn mip_bytes(&self) -> usize {
        self.grids.ds().bytes()
            + self.estimator.lattice().built().map_or(0, |l| l.bytes())
            + self.bounds.bytes()
    }
}

/// A voxel's weighed emission from its density and temperature ([`FireVolume::voxel_emission`]).
pub(crate) struct VoxelEmission {
    /// Per row of the emission table (ΔT apart from 0 K): its channels weighed by the two weights.
    rows: Vec<[f64; 2]>,
    inv_dt: f64,
    /// The temperature at and below which the gas does not emit, and whether there is a temperature grid.
    t_emit: f64,
    has_temperature: bool,
}

impl VoxelEmission {
    /// The two weighed sums of the emission of density `d` at temperature `t` (K): the point's coefficients'
    /// `j` summed against the weights, to rounding (the rows interpolated linearly in T, as each channel is).
    #[inline]
    pub(crate) fn at(&self, d: f64, t: f64) -> [f64; 2] {
        // (As the point's: a NaN temperature does not emit.)
        let emits = t > self.t_emit || !self.has_temperature;
        if !emits {
            return [0.0; 2];
        }
        let x = (t * self.inv_dt).clamp(0.0, (self.rows.len() - 1) as f64);
        let i = (x as usize).min(self.rows.len() - 2);
        let (r0, r1, f) = (self.rows[i], self.rows[i + 1], x - i as f64);
        [0, 1].map(|k| d * (r0[k] + f * (r1[k] - r0[k])))
    }
}
