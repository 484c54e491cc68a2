//! Sampling the light and its densities: a point by the CDF over bricks and a scan of the brick's cells (or an
//! ember by power), its density per volume, and a direction's density by a walk over cells.

use super::*;

impl FireLight {
    /// The table of [`brick_density`](Self::brick_density): each brick holding weight's density, as the walk of
    /// [`voxel_direction`](Self::voxel_direction) computes it.
    pub(super) fn dense_bricks(&self) -> Vec<f64> {
        let off = self.topo.offset();
        let counts = [0, 1, 2].map(|a| (self.dims[a] + off[a]).div_ceil(crate::grid::BRICK));
        let n = counts.iter().try_fold(1usize, |a, &c| a.checked_mul(c));
        let Some(n) = n.filter(|&n| self.cell == crate::grid::BRICK && n <= DENSE_BRICKS) else {
            return Vec::new();
        };
        let mut table = vec![0.0; n];
        let density = self.density_of_cells();
        for &slot in &self.brick_slots {
            let q = self.slot_bricks[slot as usize].map(|v| v as usize);
            let w = self.cell_weight(q);
            if let Some(d) = table.get_mut(q[0] + counts[0] * (q[1] + counts[1] * q[2])) {
                *d = if w > 0.0 { density(q, w) } else { 0.0 };
            }
        }
        table
    }
    /// The pdf's density inside cell `q` (of the lattice shifted by the topology's offset) of weight `w`: a whole
    /// cell's is its weight times one factor; cells cut by the grid's edges hold theirs over less.
    pub(super) fn density_of_cells(&self) -> impl Fn([usize; 3], f64) -> f64 + '_ {
        let off = self.topo.offset();
        let dims_v = [0, 1, 2].map(|a| self.dims[a] + off[a]);
        let c = self.cell as f64;
        let whole = 1.0 / (self.total * c * c * c * self.voxel.x * self.voxel.y * self.voxel.z);
        move |q, w| {
            let inside =
                (0..3).all(|a| q[a] * self.cell >= off[a] && (q[a] + 1) * self.cell <= dims_v[a]);
            if inside {
                w * whole
            } else {
                self.cell_density(w, self.cell_box(q).1)
            }
        }
    }
    /// Samples a point from six uniform numbers (the first chooses the voxel — or ember — by its weight, the
    /// last three place the point in it), at time 0.
    pub fn sample(&self, u: [f64; 6]) -> LightSample {
        self.sample_at(u, 0.0)
    }
    /// As [`sample`](Self::sample) at `time` (frames: where the embers are then; the voxels do not move).
    pub fn sample_at(&self, u: [f64; 6], time: f64) -> LightSample {
        let target = u[0] * self.total;
        if target >= self.fire_total && !self.ember_cdf.is_empty() {
            if let Some(em) = self.vol.embers() {
                let i = first_above(&self.ember_cdf, target);
                let point = em.sample_ball(i, [u[3], u[4], u[5]], time);
                return LightSample {
                    point,
                    pdf: self.pdf_at(point, time),
                };
            }
        }
        let target = target.min(self.fire_total * (1.0 - f64::EPSILON));
        let m = first_above(&self.cdf, target);
        let slot = self.brick_slots[m] as usize;
        // Within the brick: the first cell whose running weight passes what is left of the target (the last
        // weighted one if rounding leaves some over).
        let per = self.per_brick();
        let ws = &self.weights[slot * per..(slot + 1) * per];
        let mut rest = target - if m > 0 { self.cdf[m - 1] } else { 0.0 };
        let mut c = ws.iter().rposition(|&v| v > 0.0).unwrap_or(0);
        for (q, &v) in ws.iter().enumerate() {
            if v > 0.0 {
                if rest < v as f64 {
                    c = q;
                    break;
                }
                rest -= v as f64;
            }
        }
        let side = 8 / self.cell;
        let b = self.slot_bricks[slot];
        let q = [c % side, (c / side) % side, c / (side * side)];
        let (lo, n) = self.cell_box([0, 1, 2].map(|a| b[a] as usize * side + q[a]));
        let [p0, _] = self.vol.dataset().bounds();
        let u = DVec3::new(u[3], u[4], u[5]);
        let point = p0
            + (DVec3::new(lo[0] as f64, lo[1] as f64, lo[2] as f64)
                + u * DVec3::new(n[0] as f64, n[1] as f64, n[2] as f64))
                * self.voxel;
        LightSample {
            point,
            pdf: self.cell_density(ws[c] as f64, n) + self.ember_density(point, time),
        }
    }

    /// Cells per brick.
    pub(super) fn per_brick(&self) -> usize {
        let side = 8 / self.cell;
        side * side * side
    }

    /// The voxels of cell `q` (on the lattice of cells shifted by the topology's offset) inside the grid: its
    /// first voxel and its extent per axis (cells at the grid's edges are cut by it).
    pub(super) fn cell_box(&self, q: [usize; 3]) -> ([usize; 3], [usize; 3]) {
        let off = self.topo.offset();
        let lo = [0, 1, 2].map(|a| (q[a] * self.cell).max(off[a]) - off[a]);
        let hi = [0, 1, 2].map(|a| ((q[a] + 1) * self.cell).min(self.dims[a] + off[a]) - off[a]);
        (lo, [0, 1, 2].map(|a| hi[a].saturating_sub(lo[a])))
    }

    /// The density per unit volume inside a cell of weight `w` and extent `n` voxels.
    pub(super) fn cell_density(&self, w: f64, n: [usize; 3]) -> f64 {
        let cells = (n[0] * n[1] * n[2]) as f64;
        if !(w > 0.0 && cells > 0.0) {
            return 0.0;
        }
        w / (self.total * cells * self.voxel.x * self.voxel.y * self.voxel.z)
    }

    /// The weight of cell `q` (shifted lattice), 0 outside the stored bricks.
    pub(super) fn cell_weight(&self, q: [usize; 3]) -> f64 {
        let side = 8 / self.cell;
        let slot = self.topo.slot(q.map(|v| v / side));
        let l = q[0] % side + side * (q[1] % side + side * (q[2] % side));
        self.weights
            .get(slot * self.per_brick() + l)
            .copied()
            .unwrap_or(0.0) as f64
    }

    /// The embers' part of the density per unit volume at `p` and `time`.
    pub(super) fn ember_density(&self, p: DVec3, time: f64) -> f64 {
        let mut d = 0.0;
        if let Some(em) = self.vol.embers().filter(|_| !self.ember_p.is_empty()) {
            em.containing(p, time, &mut |i| {
                let r = em.radius(i);
                d += self.ember_p[i] / (4.0 / 3.0 * std::f64::consts::PI * r * r * r);
            });
        }
        d
    }

    /// Density of a medium-space point, per unit volume (embers at time 0).
    pub fn pdf(&self, p: DVec3) -> f64 {
        self.pdf_at(p, 0.0)
    }
    /// As [`pdf`](Self::pdf) at `time` (frames).
    pub fn pdf_at(&self, p: DVec3, time: f64) -> f64 {
        let embers = self.ember_density(p, time);
        let [p0, p1] = self.vol.dataset().bounds();
        if !(p.cmpge(p0).all() && p.cmplt(p1).all()) {
            return embers;
        }
        let f = ((p - p0) / self.voxel).floor();
        let off = self.topo.offset();
        let q = [0, 1, 2]
            .map(|a| ((f[a].max(0.0) as usize).min(self.dims[a] - 1) + off[a]) / self.cell);
        self.cell_density(self.cell_weight(q), self.cell_box(q).1) + embers
    }

    /// Solid-angle density of the direction `d` from `o`: ∫ pdf(o + s d̂) s² ds over s ≥ 0 (embers at time 0).
    pub fn pdf_direction(&self, o: DVec3, d: DVec3) -> f64 {
        self.pdf_direction_at(o, d, 0.0)
    }
    /// As [`pdf_direction`](Self::pdf_direction) at `time` (frames).
    pub fn pdf_direction_at(&self, o: DVec3, d: DVec3, time: f64) -> f64 {
        let len = d.length();
        if !(len > 0.0 && len.is_finite() && o.is_finite()) {
            return 0.0;
        }
        let dn = d / len;
        let embers = match self.vol.embers().filter(|_| !self.ember_p.is_empty()) {
            Some(em) => em.chord_moment(o, dn, time, &self.ember_p),
            None => 0.0,
        };
        self.voxel_direction(o, dn) + embers
    }
    /// The voxels' part of [`pdf_direction`](Self::pdf_direction) along the unit direction `dn`: per cell the
    /// ray crosses, its density × (t₁³ − t₀³) / 3.
    pub(super) fn voxel_direction(&self, o: DVec3, dn: DVec3) -> f64 {
        let ds = self.vol.dataset();
        let [p0, p1] = ds.bounds();
        // Only the part of the ray inside the grid (cells cut by its edges hold their density over their inside).
        let Some((ta, tb)) = crate::majorant::clip_box(o, dn, 0.0, f64::INFINITY, p0, p1) else {
            return 0.0;
        };
        let mut sum = 0.0;
        // On the lattice of cells and bricks shifted by the topology's offset (the walk's bricks are the
        // weights').
        let off = self.topo.offset();
        let shifted = [
            p0 - DVec3::new(off[0] as f64, off[1] as f64, off[2] as f64) * self.voxel,
            p1,
        ];
        let dims_v = [0, 1, 2].map(|a| self.dims[a] + off[a]);
        // Cells of a brick with the bricks' table: one number per brick.
        if !self.brick_density.is_empty() {
            // (Every brick's term, 0 where it holds no weight: no branch on the density, which changes along
            // the ray too irregularly to predict.)
            for seg in walk(shifted, dims_v, self.cell, o, dn, ta, tb) {
                let d = self.brick_density.get(seg.brick).copied().unwrap_or(0.0);
                sum += d * (seg.t1 * seg.t1 * seg.t1 - seg.t0 * seg.t0 * seg.t0);
            }
            return sum / 3.0;
        }
        let density = self.density_of_cells();
        let cells = |t0: f64, t1: f64, sum: &mut f64| {
            for seg in walk(shifted, dims_v, self.cell, o, dn, t0, t1) {
                let w = self.cell_weight(seg.cell);
                if w > 0.0 {
                    *sum += density(seg.cell, w) * (seg.t1.powi(3) - seg.t0.powi(3)) / 3.0;
                }
            }
        };
        // A fire that fills its box (the weights' bricks at least an eighth of the box's), or cells as large as
        // bricks: one walk over the cells. Otherwise brick by brick, cell by cell only inside bricks that hold
        // weights: a sparse fire in a big box costs its bricks along the ray, not the box's cells.
        let box_bricks = self.topo.bricks().iter().product::<usize>();
        if self.cell == crate::grid::BRICK
            || self.topo.active_bricks().saturating_mul(8) >= box_bricks
        {
            cells(ta, tb, &mut sum);
            return sum;
        }
        for bseg in walk(shifted, dims_v, crate::grid::BRICK, o, dn, ta, tb) {
            if self.topo.slot(bseg.cell) != 0 {
                cells(bseg.t0, bseg.t1, &mut sum);
            }
        }
        sum
    }
}
