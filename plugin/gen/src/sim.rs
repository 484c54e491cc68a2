//! The model run over time: fuel heated by the flames' radiation, blobs born, moved by the wind, cooled, turned to smoke.

use super::*;

/// A seeded, smooth 3D value noise (trilinear over a hashed lattice with a quintic fade); three independent
/// components give a vector potential whose curl is the turbulent wind.
#[derive(Debug)]
pub(crate) struct Noise {
    pub(crate) seed: u64,
}

impl Noise {
    pub(crate) fn hash(&self, i: i64, j: i64, k: i64, c: u64) -> f64 {
        let mut h = self.seed ^ c.wrapping_mul(0x9E37_79B9_7F4A_7C15);
        for v in [i, j, k] {
            h ^= (v as u64)
                .wrapping_add(0x9E37_79B9_7F4A_7C15)
                .wrapping_add(h << 6)
                .wrapping_add(h >> 2);
            h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
            h ^= h >> 31;
        }
        (h >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
    pub(crate) fn value(&self, p: DVec3, c: u64) -> f64 {
        let f = p.floor();
        let t = p - f;
        let s = t * t * t * (t * (t * 6.0 - 15.0) + 10.0);
        let (i, j, k) = (f.x as i64, f.y as i64, f.z as i64);
        let mut acc = 0.0;
        for dz in 0..2 {
            for dy in 0..2 {
                for dx in 0..2 {
                    let w = (if dx == 1 { s.x } else { 1.0 - s.x })
                        * (if dy == 1 { s.y } else { 1.0 - s.y })
                        * (if dz == 1 { s.z } else { 1.0 - s.z });
                    acc += w * self.hash(i + dx, j + dy, k + dz, c);
                }
            }
        }
        acc
    }
    /// Curl of the potential (ψ₀, ψ₁, ψ₂)(p) by central differences: divergence-free to rounding.
    pub(crate) fn curl(&self, p: DVec3) -> DVec3 {
        let h = 1e-3;
        let d = |c: u64, axis: DVec3| {
            (self.value(p + axis * h, c) - self.value(p - axis * h, c)) / (2.0 * h)
        };
        DVec3::new(
            d(2, DVec3::Y) - d(1, DVec3::Z),
            d(0, DVec3::Z) - d(2, DVec3::X),
            d(1, DVec3::X) - d(0, DVec3::Y),
        )
    }
}

impl Sim {
    pub fn new(kind: Kind, seed: u64) -> Sim {
        let (model, mut cells, links) = kind.setup();
        for c in &mut cells {
            c.load = model.fuel_load;
        }
        Sim {
            cooling: Cooling::new(model.soot_yield, model.heat_capacity),
            model,
            cells,
            links,
            blobs: Vec::new(),
            time: 0.0,
            warp: None,
            ember_rate: None,
            ember_char: crate::EMBER_CHAR,
            embers: Vec::new(),
            embers_born: 0,
            rng: Rng::new(seed ^ 0x5EED_F1AE),
            ember_rng: Rng::new(seed ^ 0xE3BE_25F1),
            noise: Noise { seed },
        }
    }

    /// The wind at `x` for a blob at temperature `t`.
    pub(crate) fn wind(&self, x: DVec3, t: f64) -> DVec3 {
        let m = &self.model;
        let lift = m.buoyancy * ((t - T_AMB).max(0.0) / T_AMB).sqrt();
        DVec3::Z * lift + self.turbulence(x, self.time)
    }
    /// The turbulent part of the wind at `x` and time `time` (divergence-free; the buoyant lift is uniform for
    /// a blob, so it moves blobs without deforming them).
    pub(crate) fn turbulence(&self, x: DVec3, time: f64) -> DVec3 {
        let m = &self.model;
        // The turbulence drifts upwards with the plume and evolves slowly.
        let q = (x - DVec3::Z * (0.5 * m.buoyancy * time)) / m.turbulence_scale
            + DVec3::splat(0.37 * time);
        self.noise.curl(q) * (m.turbulence * 0.5)
    }

    /// One step of dt; returns the mass bookkeeping.
    pub fn step(&mut self) -> StepLedger {
        let m = self.model.clone();
        let dt = m.dt;
        let mut ledger = StepLedger::default();
        // Fuel cells: heat (implicit in T), burn (exact in the load), emit a flame blob. Each cell is heated by
        // what reaches it: the flames' radiation (each blob a point source near it, far ones by hash cell) and
        // the flame gas touching it; it conducts to its neighbours along the fuel and loses its own radiation.
        let matching = self.time < m.match_seconds;
        let heating = if m.fuel_absorptance > 0.0 || m.flame_contact > 0.0 {
            self.fuel_heating()
        } else {
            vec![(0.0, T_AMB); self.cells.len()]
        };
        let conduction = self.conduction();
        let exchange = self.fuel_exchange();
        let mut born = Vec::new();
        for (i, c) in self.cells.iter_mut().enumerate() {
            let (radiation, t_gas) = heating[i];
            let lit = matching && (c.p - m.match_at).length() < m.match_radius;
            let liquid = m.boiling > 0.0;
            // A liquid's match is a pilot flame over it.
            let t_gas = if liquid && lit {
                t_gas.max(m.t_match)
            } else {
                t_gas
            };
            let balance = FuelBalance {
                flux: m.fuel_absorptance * (radiation + exchange[i]) + conduction[i] / c.area,
                h: m.flame_contact,
                t_gas,
                emissivity: m.fuel_absorptance,
                heat_capacity: m.fuel_heat_capacity,
                load: c.load,
                nu_a: m.nu_a,
                t_a: m.t_a,
                gasification: m.gasification,
            };
            let burnt = if liquid {
                // Lit, its surface layer is at its boiling point (heptane's flash point is below the room's: it
                // burns at once, its surface within a second at boiling).
                let t0 = if lit { c.t.max(m.boiling) } else { c.t };
                let (t, burnt) = liquid_fuel_step(t0, &balance, m.boiling, dt);
                c.t = t;
                burnt
            } else {
                c.t = implicit_fuel_temperature(c.t, &balance, dt);
                if lit {
                    c.t = c.t.max(m.t_match);
                }
                balance.burnt(c.t, dt)
            };
            let mass = burnt * c.area;
            if !(mass > 1e-15) {
                continue;
            }
            c.load -= burnt;
            ledger.fuel_consumed += mass;
            ledger.flame_produced += mass;
            let jitter = DVec3::new(
                self.rng.next_f64(),
                self.rng.next_f64(),
                self.rng.next_f64(),
            ) - 0.5;
            born.push(Blob {
                x: c.p + c.normal * m.sigma0 + jitter * (c.area.sqrt()),
                m_flame: mass,
                m_smoke: 0.0,
                t: (c.t + m.release).max(T_AMB),
                age: 0.0,
                sigma0: m.sigma0,
            });
        }
        // Blobs: move (midpoint), cool (exact), smoke (exact), decay, grow.
        let moved: Vec<(DVec3, f64)> = self
            .blobs
            .par_iter()
            .map(|b| {
                let v0 = self.wind(b.x, b.t);
                let mid = b.x + v0 * (0.5 * dt);
                (b.x + self.wind(mid, b.t) * dt, 0.0)
            })
            .collect();
        let mut kept = Vec::with_capacity(self.blobs.len() + born.len());
        let lo = DVec3::new(-m.half_width, -m.half_width, 0.0) * 1.5 - DVec3::splat(0.1 * m.height);
        let hi = DVec3::new(m.half_width * 1.5, m.half_width * 1.5, m.height * 1.1);
        for (b, (x, _)) in self.blobs.iter().zip(moved) {
            let mut b = *b;
            b.x = x;
            b.t = self.cooling.step(b.t, dt);
            b.t = T_AMB + (b.t - T_AMB) * (-dt / m.mixing_time).exp();
            let to_smoke = b.m_flame * -(-m.nu_b * (-b.t / m.t_s).exp() * dt).exp_m1();
            b.m_flame -= to_smoke;
            b.m_smoke += to_smoke;
            ledger.flame_to_smoke += to_smoke;
            let decayed = b.m_smoke * -(-m.smoke_decay * dt).exp_m1();
            b.m_smoke -= decayed;
            ledger.smoke_decayed += decayed;
            b.age += dt;
            let inside = b.x.cmpge(lo).all() && b.x.cmple(hi).all();
            if inside && b.m_flame + b.m_smoke > 1e-12 {
                kept.push(b);
            } else {
                ledger.removed += b.m_flame + b.m_smoke;
            }
        }
        ledger.smoke_produced = ledger.flame_to_smoke;
        if let Some(rate) = self.ember_rate {
            self.step_embers(rate, &born);
        }
        kept.extend(born);
        self.blobs = kept;
        self.time += dt;
        ledger
    }

    /// The gas's temperature at `x` from the blobs `which` (ascending indices; every blob whose kernel reaches `x`
    /// among them — [`BlobCells`]): their temperatures weighted by their kernels, fading to ambient outside them
    /// (weights summing below 1 keep that share of ambient).
    fn gas_temperature_of(&self, x: DVec3, which: impl IntoIterator<Item = usize>) -> f64 {
        let kappa = self.model.kappa;
        let (mut w, mut wt) = (0.0, 0.0);
        for i in which {
            let b = &self.blobs[i];
            if let Some(k) = b.weight_at(x, b.sigma(kappa)) {
                w += k;
                wt += k * (b.t - T_AMB);
            }
        }
        T_AMB + wt / w.max(1.0)
    }

    /// One step of the embers: new ones thrown from the cells that burnt this step (`born`: their flame
    /// blobs, by mass), then each moved by gravity and quadratic drag (C_d 0.47, air at the gas's temperature:
    /// ρ = 353 K·kg/m³ / T) towards the wind, and aged; those that land, leave the domain or cool below
    /// [`EMBER_DEAD_K`] are dropped.
    pub(crate) fn step_embers(&mut self, rate: f64, born: &[Blob]) {
        use firemedium_core::ember::CHAR_DENSITY;
        let m = self.model.clone();
        let dt = m.dt;
        let total: f64 = born.iter().map(|b| b.m_flame).sum();
        if total > 0.0 {
            // Expected rate·dt embers this step, shared by the cells by the mass they burnt.
            let mut carry = self.ember_rng.next_f64();
            for b in born {
                carry += rate * dt * b.m_flame / total;
                while carry >= 1.0 {
                    carry -= 1.0;
                    let g = &mut self.ember_rng;
                    let r = 0.5e-3 * (3.0f64 / 0.5).powf(g.next_f64());
                    let a = 2.0 * std::f64::consts::PI * g.next_f64();
                    // A pop throws it up at 2–5 m/s and out at up to 1.5 m/s.
                    let out = DVec3::new(a.cos(), a.sin(), 0.0) * (0.5 + g.next_f64());
                    let v = out + DVec3::Z * (2.0 + 3.0 * g.next_f64());
                    // Born at the gas's temperature where the fuel burns (a millimetre of char reaches it in the
                    // flame within a fraction of a second), then burning in the air once thrown.
                    let t0 = b.t;
                    self.embers_born += 1;
                    self.embers.push(Ember {
                        x: b.x,
                        v,
                        r,
                        t0,
                        age: 0.0,
                        now: (t0, r),
                    });
                }
            }
        }
        let lo = DVec3::new(-m.half_width, -m.half_width, 0.0);
        let hi = DVec3::new(m.half_width, m.half_width, m.height);
        // The blobs by the cells their kernels reach: an ember's gas temperature sums only the blobs of its cell,
        // in the same order — the same number as over every blob, in time that follows the blobs near it (10 000
        // embers a second over thousands of blobs took minutes).
        let near = BlobCells::new(&self.blobs, m.kappa);
        let moved: Vec<Ember> = self
            .embers
            .par_iter()
            .map(|e| {
                let accel = |x: DVec3, v: DVec3| {
                    let tg = self.gas_temperature_of(x, near.at(x).iter().map(|&i| i as usize));
                    let rho_air = 353.0 / tg;
                    let w = v - self.wind(x, tg);
                    -DVec3::Z * 9.81 * (1.0 - rho_air / CHAR_DENSITY)
                        - w * (w.length() * 3.0 * 0.47 * rho_air / (8.0 * CHAR_DENSITY * e.now.1))
                };
                // Midpoint in (x, v).
                let a0 = accel(e.x, e.v);
                let (xm, vm) = (e.x + e.v * (0.5 * dt), e.v + a0 * (0.5 * dt));
                let am = accel(xm, vm);
                Ember {
                    x: e.x + vm * dt,
                    v: e.v + am * dt,
                    age: e.age + dt,
                    now: firemedium_core::ember::burn(e.now.0, e.now.1, dt, &self.ember_char),
                    ..*e
                }
            })
            .collect();
        self.embers = moved
            .into_iter()
            .filter(|e| {
                e.x.cmpge(lo).all()
                    && e.x.cmple(hi).all()
                    && e.now.1 > 0.0
                    && e.temperature() > EMBER_DEAD_K
            })
            .collect();
    }

    /// The fuel: (cells burning — above 500 K, a liquid at its boiling point —, cells, their mean temperature,
    /// fraction of the fuel left).
    pub fn fuel_summary(&self) -> (usize, usize, f64, f64) {
        let burning = if self.model.boiling > 0.0 {
            self.model.boiling
        } else {
            500.0
        };
        let hot: Vec<f64> = self
            .cells
            .iter()
            .map(|c| c.t)
            .filter(|t| *t >= burning)
            .collect();
        let total: f64 = self
            .cells
            .iter()
            .map(|c| c.area * self.model.fuel_load)
            .sum();
        let left: f64 = self.cells.iter().map(|c| c.area * c.load).sum();
        let mean = if hot.is_empty() {
            0.0
        } else {
            hot.iter().sum::<f64>() / hot.len() as f64
        };
        (hot.len(), self.cells.len(), mean, left / total)
    }

    /// Runs until `t` (s).
    pub fn run_to(&mut self, t: f64) {
        while self.time + 0.5 * self.model.dt < t {
            self.step();
        }
    }
}

/// What a fuel cell's surface exchanges over a step: the flux it absorbs from outside (W/m², radiation and
/// conduction), the flame gas touching it (`h` W/(m² K) at `t_gas`), its own radiation (grey, `emissivity`), and
/// the heat its fuel takes to gasify (`gasification` J/kg, at the Arrhenius rate of its `load` kg/m²: ν_a, T_a).
#[derive(Debug, Clone, Copy)]
pub struct FuelBalance {
    pub flux: f64,
    pub h: f64,
    pub t_gas: f64,
    pub emissivity: f64,
    /// Heat capacity per area, J/(m² K).
    pub heat_capacity: f64,
    pub load: f64,
    pub nu_a: f64,
    pub t_a: f64,
    pub gasification: f64,
}

impl FuelBalance {
    /// The mass gasified over dt at the surface temperature t, kg/m² (exact in the load: ρ (1 − e^{−k dt})).
    pub fn burnt(&self, t: f64, dt: f64) -> f64 {
        let k = self.nu_a * (-self.t_a / t).exp();
        self.load * -(-k * dt).exp_m1()
    }
}

/// A liquid fuel's step (boiling at `t_b` K): below its boiling point it heats as a solid that does not gasify;
/// at it, the surface stays there and the heat beyond what holds it — the flux, the flame gas, less its own
/// radiation and what warming it to `t_b` took — evaporates fuel at `gasification` J/kg. Returns (T₁, the mass
/// evaporated over dt, kg/m², at most the load).
pub fn liquid_fuel_step(t0: f64, s: &FuelBalance, t_b: f64, dt: f64) -> (f64, f64) {
    let dry = FuelBalance {
        gasification: 0.0,
        ..*s
    };
    let t1 = implicit_fuel_temperature(t0, &dry, dt);
    if t1 <= t_b {
        return (t1, 0.0);
    }
    let net = s.flux + s.h * (s.t_gas - t_b) - s.emissivity * SIGMA * (t_b.powi(4) - T_AMB.powi(4));
    let heat = net * dt - s.heat_capacity * (t_b - t0);
    (t_b, (heat / s.gasification).clamp(0.0, s.load))
}

/// The fuel temperature after dt: C (T₁ − T₀)/dt = flux + h (T_gas − T₁) − ε σ (T₁⁴ − T_amb⁴) − L ṁ(T₁), with ṁ(T₁)
/// the mass gasified over the step at T₁ per dt — solved for T₁. Every term is monotone in T₁, so the equation
/// has one root: Newton from above safeguarded by bisection, stable for any dt and flux (the gasification's
/// Arrhenius stiffness included).
pub fn implicit_fuel_temperature(t0: f64, s: &FuelBalance, dt: f64) -> f64 {
    let c = s.heat_capacity;
    let f = |t: f64| {
        c * (t - t0) / dt - s.flux - s.h * (s.t_gas - t)
            + s.emissivity * SIGMA * (t.powi(4) - T_AMB.powi(4))
            + s.gasification * s.burnt(t, dt) / dt
    };
    let gain = s.flux.max(0.0) + s.h * s.t_gas.max(0.0);
    let (mut lo, mut hi) = (0.0f64, t0.max(T_AMB).max(s.t_gas) + gain * dt / c + 1.0);
    // f(lo) < 0 < f(hi) whenever the gains are ≥ 0; widen hi if not.
    while f(hi) < 0.0 && hi < 1e7 {
        hi *= 2.0;
    }
    let mut t = hi;
    for _ in 0..200 {
        let ft = f(t);
        if ft.abs() < 1e-12 * c || hi - lo < 1e-12 * hi {
            break;
        }
        if ft > 0.0 {
            hi = t;
        } else {
            lo = t;
        }
        let k = s.nu_a * (-s.t_a / t).exp();
        let dburn = s.gasification * s.load * k * s.t_a / (t * t) * (-k * dt).exp();
        let d = c / dt + s.h + 4.0 * s.emissivity * SIGMA * t.powi(3) + dburn;
        let next = t - ft / d;
        t = if next > lo && next < hi {
            next
        } else {
            0.5 * (lo + hi)
        };
    }
    t
}

/// Blobs binned by the cubes their kernels reach (3σ), the cube's edge the largest kernel's reach: every blob whose
/// kernel reaches a point is in that point's cube's list, in ascending order.
struct BlobCells {
    edge: f64,
    cells: std::collections::HashMap<[i64; 3], Vec<u32>>,
}

impl BlobCells {
    fn new(blobs: &[crate::Blob], kappa: f64) -> BlobCells {
        let reach: Vec<f64> = blobs.iter().map(|b| 3.0 * b.sigma(kappa)).collect();
        let edge = reach.iter().copied().fold(0.0, f64::max).max(1e-6);
        let mut cells: std::collections::HashMap<[i64; 3], Vec<u32>> = Default::default();
        let cell = |v: f64| (v / edge).floor() as i64;
        for (i, (b, r)) in blobs.iter().zip(&reach).enumerate() {
            // (A hair wider than the kernel: a point its test keeps is never on the far side of a cube edge.)
            let pad = r * (1.0 + 1e-9) + 1e-12;
            let (lo, hi) = (b.x - DVec3::splat(pad), b.x + DVec3::splat(pad));
            for z in cell(lo.z)..=cell(hi.z) {
                for y in cell(lo.y)..=cell(hi.y) {
                    for x in cell(lo.x)..=cell(hi.x) {
                        cells.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        BlobCells { edge, cells }
    }

    /// The blobs whose kernels may reach `p`, ascending.
    fn at(&self, p: DVec3) -> &[u32] {
        let c = [p.x, p.y, p.z].map(|v| (v / self.edge).floor() as i64);
        self.cells.get(&c).map_or(&[], Vec::as_slice)
    }
}
