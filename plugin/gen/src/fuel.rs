//! What heats the fuel: the flames' radiation reaching each cell, the flame gas touching it, and conduction
//! along the fuel between neighbouring cells (Stam & Fiume §6's S_T,fuel, shot from every blob rather than from
//! a couple of blob clusters, and the fuel map's diffusion).

use super::*;
use std::collections::HashMap;

/// Two neighbouring fuel cells and the conductance between them, W/K: k·d·w/Δx for a fuel layer of
/// conductivity × thickness k·d (W/K) sharing an edge of length w at centres Δx apart.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    pub a: usize,
    pub b: usize,
    pub conductance: f64,
}

/// The blobs binned in cubes of side `h`: each cube's blobs, and its radiant power and power-weighted centre.
struct Bins {
    h: f64,
    cubes: HashMap<[i64; 3], (Vec<usize>, f64, DVec3)>,
}

impl Bins {
    fn key(&self, x: DVec3) -> [i64; 3] {
        let q = (x / self.h).floor();
        [q.x as i64, q.y as i64, q.z as i64]
    }
}

impl Sim {
    /// The power blob `b` radiates, W (what its cooling removes: the renderer's soot at its temperature).
    pub fn blob_power(&self, b: &Blob) -> f64 {
        self.cooling
            .power(b.t, b.m_flame + b.m_smoke, self.model.heat_capacity)
    }

    /// Per fuel cell: the flames' radiation arriving on its outer face, W/m², and the temperature of the gas
    /// touching it (K). Blobs in the cubes around the cell count one by one — a point source at its centre, no
    /// nearer than twice its σ, through the cosine at the cell; the gas temperature from their kernels as
    /// [`Sim::gas_temperature_of`] weighs them — and farther cubes by their total power from their power-weighted
    /// centre (their contribution is a few per cent of a cell's: measured, docs/results/log.md).
    pub fn fuel_heating(&self) -> Vec<(f64, f64)> {
        let m = &self.model;
        let mut bins = Bins {
            h: 10.0 * m.sigma0,
            cubes: HashMap::new(),
        };
        // (Each blob's power once per step: the cells near it read it again.)
        let power: Vec<f64> = self.blobs.iter().map(|b| self.blob_power(b)).collect();
        for (i, (b, &p)) in self.blobs.iter().zip(&power).enumerate() {
            let key = bins.key(b.x);
            let e = bins
                .cubes
                .entry(key)
                .or_insert((Vec::new(), 0.0, DVec3::ZERO));
            e.0.push(i);
            e.1 += p;
            e.2 += b.x * p;
        }
        // (In key order: the sums are the same from run to run, whatever the map's order.)
        let mut far: Vec<([i64; 3], f64, DVec3)> = bins
            .cubes
            .iter()
            .filter(|(_, (_, p, _))| *p > 0.0)
            .map(|(k, (_, p, c))| (*k, *p, *c / *p))
            .collect();
        far.sort_unstable_by_key(|f| f.0);
        let point = |from: DVec3, power: f64, floor2: f64, cell: &Cell| {
            let d = from - cell.p;
            let r2 = d.length_squared().max(floor2);
            let cos = (d.dot(cell.normal) / r2.sqrt()).max(0.0);
            power * cos / (4.0 * std::f64::consts::PI * r2)
        };
        self.cells
            .par_iter()
            .map(|c| {
                let at = c.p + c.normal * m.sigma0;
                let k0 = bins.key(at);
                let near = |k: &[i64; 3]| (0..3).all(|a| (k[a] - k0[a]).abs() <= 1);
                let (mut e, mut w, mut wt) = (0.0, 0.0, 0.0);
                for (k, p, centre) in &far {
                    if !near(k) {
                        e += point(*centre, *p, 0.0, c);
                    }
                }
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let Some((ids, ..)) =
                                bins.cubes.get(&[k0[0] + dx, k0[1] + dy, k0[2] + dz])
                            else {
                                continue;
                            };
                            for &i in ids {
                                let b = &self.blobs[i];
                                let s = b.sigma(m.kappa);
                                e += point(b.x, power[i], 4.0 * s * s, c);
                                if let Some(k) = b.weight_at(at, s) {
                                    w += k;
                                    wt += k * (b.t - T_AMB);
                                }
                            }
                        }
                    }
                }
                (e, T_AMB + wt / w.max(1.0))
            })
            .collect()
    }

    /// Per fuel cell: what the other cells' surfaces radiate onto it above ambient, W/m² — glowing logs facing
    /// each other keep each other burning. Two small patches i, j exchange ε σ (T_j⁴ − T_amb⁴) cos θ_i cos θ_j
    /// A_j / (π r²) (their view factor), r² no smaller than the patch's area; on one convex surface the cosines
    /// leave out every pair; a third surface between two is not seen (no occlusion).
    pub fn fuel_exchange(&self) -> Vec<f64> {
        let eps = self.model.fuel_absorptance;
        let cells = &self.cells;
        cells
            .par_iter()
            .enumerate()
            .map(|(i, c)| {
                let mut q = 0.0;
                for (j, o) in cells.iter().enumerate() {
                    if i == j || o.t <= T_AMB {
                        continue;
                    }
                    let d = o.p - c.p;
                    let r2 = d.length_squared().max(o.area);
                    let r = r2.sqrt();
                    let (ci, cj) = (c.normal.dot(d) / r, -o.normal.dot(d) / r);
                    if ci > 0.0 && cj > 0.0 {
                        q += eps * SIGMA * (o.t.powi(4) - T_AMB.powi(4)) * ci * cj * o.area
                            / (std::f64::consts::PI * r2);
                    }
                }
                q
            })
            .collect()
    }

    /// Per fuel cell: the heat conducted into it from its neighbours, W.
    pub(crate) fn conduction(&self) -> Vec<f64> {
        let mut q = vec![0.0; self.cells.len()];
        for l in &self.links {
            let flow = l.conductance * (self.cells[l.b].t - self.cells[l.a].t);
            q[l.a] += flow;
            q[l.b] -= flow;
        }
        q
    }
}
