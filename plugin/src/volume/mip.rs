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
        let c = self.channels();
        let j = self.model.j();
        let sum = (0..j.rows)
            .map(|r| (0..c).map(|ch| j.value(r, ch) as f64).sum())
            .collect();
        (sum, j.inv_dt, j.dt)
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
