//! Fire datasets of our own: Stam & Fiume's (1995, §6) blob fire model, run over time and voxelised.
//!
//! **Fuel** lies on surfaces (logs, a pool, a wick, a torch head) as cells with a fuel load ρ_fuel (kg/m²) and
//! a temperature T_fuel. Each cell's surface balances, per area, over a heat capacity per area (`fuel`):
//!
//!   C dT/dt = a (E_flames + E_fuel) + h (T_gas − T) + Q_cond / A − a σ (T⁴ − T_amb⁴) − L ṁ(T),
//!
//! - E_flames: the flames' radiation arriving at the cell — every blob a point source of its radiated power
//!   (below), through the cosine at the cell and the inverse square (§6's S_T,fuel, shot from each blob near the
//!   cell and from each 15 cm cube's power centre farther away, where §6 shoots from "a couple of blob
//!   clusters");
//! - E_fuel: the other cells' surfaces facing it (glowing logs keep each other burning: a small-patch view
//!   factor, no occlusion); `a` the surface's absorptance, which is also its emissivity (char, 0.9);
//! - h (T_gas − T): the flame gas touching it (its temperature from the blobs' kernels there; h = 20 W/(m² K),
//!   fires' flames 10–30);
//! - Q_cond: conduction from its neighbours along the fuel (wood's 0.12 W/(m K) through the layer whose heat
//!   capacity C is) — §6.1's diffusion over the fuel map; tiny against radiation at these scales, as it is;
//! - L ṁ(T): the heat its wood takes to gasify (1.8 MJ/kg) at the Arrhenius rate ṁ = ρ_fuel ν_a e^{−T_a/T}
//!   (eq. 10): the sink that holds a burning surface near 600–700 K and its burning rate near wood's 5–20
//!   g/(m² s).
//!
//! The step is implicit in T (one monotone equation: stable for any dt). **Striking a match** holds the
//! cells within `match_radius` of `match_at` at `t_match` for the first `match_seconds` (the campfire's
//! kindling under the logs' raised tips); the rest of the fire catches from their flames and burns on
//! without them. The fuel a step gasifies, ρ_fuel (1 − e^{−k dt}) per area, leaves as a new **flame blob**
//! (production equals consumption to rounding). **A liquid** (the pool's heptane, `boiling`) does not gasify by
//! Arrhenius: its surface stays at its boiling point and what heat reaches it beyond what holds it there
//! evaporates fuel at its heat of gasification (the pool then burns at large heptane pools' 0.06–0.07 kg/(m² s));
//! its match is a pilot flame over it.
//!
//! **Blobs** are Gaussian kernels (eq. 6–9 of §4) of flame mass m_f and smoke mass m_s at a temperature T. Each
//! moves with the wind — a buoyant updraft B √((T − T_amb)/T_amb) plus a divergence-free turbulent field (the curl
//! of a seeded noise potential, after Stam & Fiume 1993), by a midpoint step — and grows by diffusion,
//! σ² = σ₀² + 2κ·age. Flame turns into smoke at ν_b exp(−T / T_s) (§6), exactly over a step (the masses' sum
//! is kept); smoke decays at `smoke_decay`. A new blob starts at T_fuel + `release` (the heat of the reaction,
//! §6's S_T,flame). It **radiates what the renderer renders its soot emitting** ([`radiation`]): the blob's
//! soot, Y_s kg per kg of fuel, at the plugin's soot optics (propane), radiates 4 f_v κ̂_P(T) σT⁴ per volume, so
//! dT/dt = −K(T) T⁴ with K = 4σ κ̂_P(T) Y_s / (ρ_s c) — one constant, derived (§6's 4π α_flame form counts σT⁴
//! as a radiance, π too much) — integrated exactly over a step, never below ambient; then mixing with
//! entrained air relaxes T − T_amb by e^{−dt/τ} (our addition: with radiation alone the smoke stays glowing-hot
//! for metres). The same power heats the fuel.
//!
//! **Voxelisation** sums the kernels: flame and smoke mass densities ρ (kg of fuel per m³) and the mass-weighted
//! temperature (§4: θ = Σ m θ W / Σ m W); it writes `density` = soot volume fraction Y_s (ρ_f + ρ_s) / ρ_soot,
//! `temperature` in K (0 where there is no mass, the file's background), and per `--species SYM:N` a number
//! density N · ρ_f / max ρ_f that follows the flame, as an OpenVDB file the dataset reader loads.
//!
//! **Warped blobs** (§4, opt-in: `gen --warp`): the kernels are evaluated at points traced back through the
//! turbulent wind, so blobs stretch and curl with it instead of staying round ([`Warp`]).
//!
//! Not modelled (documented): oxygen depletion, the fuel's change of shape as it burns, occlusion between
//! fuel surfaces, and the liquid pool's surface held at its boiling point (its cells burn as a solid's).

mod fuel;
mod kinds;
pub mod radiation;
mod sim;
mod voxel;
mod write;

pub use fuel::Link;
pub use radiation::Cooling;
use sim::Noise;
pub use sim::{implicit_fuel_temperature, liquid_fuel_step, FuelBalance};
pub use voxel::{voxelise, Fields, HEAT_OF_COMBUSTION, REACTION_TIME};
pub use write::{embers_ply, frame, frame_as, Frame, Style};

use firemedium_core::constants::STEFAN_BOLTZMANN as SIGMA;
use firemedium_core::rng::Rng;
use glam::DVec3;
use rayon::prelude::*;

/// The fires the generator knows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Campfire,
    Candle,
    Pool,
    Torch,
}

impl Kind {
    pub const ALL: [Kind; 4] = [Kind::Campfire, Kind::Candle, Kind::Pool, Kind::Torch];
    pub fn name(self) -> &'static str {
        match self {
            Kind::Campfire => "campfire",
            Kind::Candle => "candle",
            Kind::Pool => "pool",
            Kind::Torch => "torch",
        }
    }
    pub fn from_name(s: &str) -> Option<Kind> {
        Kind::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// Ambient air temperature, K.
pub const T_AMB: f64 = 293.15;
/// Density of soot, kg/m³.
const RHO_SOOT: f64 = 1800.0;

/// The model's constants for one kind of fire (SI units).
#[derive(Debug, Clone)]
pub struct Model {
    /// Domain: x, y in [−half_width, half_width], z in [0, height] (m), z up.
    pub half_width: f64,
    pub height: f64,
    /// Fuel load, kg/m².
    pub fuel_load: f64,
    /// Arrhenius frequency ν_a (1/s) and activation temperature T_a (K).
    pub nu_a: f64,
    pub t_a: f64,
    /// Temperature rise of the reaction: a new flame blob starts at T_fuel + release (K).
    pub release: f64,
    /// Heat capacity of the flame gas per kg of fuel (the products and the air they carry), J/(kg K): with
    /// `alpha_flame` it sets the radiative cooling K = 4π α σ / c ([`Model::k_rad`]).
    pub heat_capacity: f64,
    /// Cooling by mixing with the entrained air: T − T_amb decays by e^{−dt/τ} (s; not in §6, whose flames
    /// cool by radiation only and so stay hot as smoke far too long).
    pub mixing_time: f64,
    /// The fuel surface's absorptance, which is its emissivity (char: 0.9).
    pub fuel_absorptance: f64,
    /// Heat transfer from the flame gas touching the fuel, W/(m² K) (fires' flames: 10–30).
    pub flame_contact: f64,
    /// The fuel layer's conductivity × thickness, W/K (wood, 0.12 W/(m K) × the layer whose heat capacity is
    /// `fuel_heat_capacity`): conduction between neighbouring cells.
    pub fuel_conduction: f64,
    /// The heat the fuel takes to gasify, J/kg (wood: 1.8 MJ/kg, Drysdale, *An Introduction to Fire Dynamics*,
    /// after Tewarson): the sink that holds a burning surface near 650–700 K.
    pub gasification: f64,
    /// Fuel heat capacity per area, J/(m² K).
    pub fuel_heat_capacity: f64,
    /// A liquid fuel's boiling point, K (0: a solid, gasifying at the Arrhenius rate). A liquid's surface never
    /// passes it: what heat reaches the surface beyond what holds it there evaporates fuel at `gasification`
    /// J/kg, and a match is a pilot flame over it (the gas touching it at `t_match`), not a hot surface.
    pub boiling: f64,
    /// Smoke: ν_b (1/s), T_s (K), decay (1/s).
    pub nu_b: f64,
    pub t_s: f64,
    pub smoke_decay: f64,
    /// Blob size at birth (m) and diffusion coefficient κ (m²/s).
    pub sigma0: f64,
    pub kappa: f64,
    /// Buoyant speed scale B (m/s), turbulence speed (m/s) and length scale (m).
    pub buoyancy: f64,
    pub turbulence: f64,
    pub turbulence_scale: f64,
    /// Soot yield: kg of soot per kg of fuel in the flame.
    pub soot_yield: f64,
    /// Ignition: the cells within `match_radius` of `match_at` are held at `t_match` for `match_seconds`.
    pub match_at: DVec3,
    pub match_radius: f64,
    pub t_match: f64,
    pub match_seconds: f64,
    /// Time step, s.
    pub dt: f64,
}

/// A patch of fuel surface.
#[derive(Debug, Clone, Copy)]
pub struct Cell {
    pub p: DVec3,
    pub normal: DVec3,
    pub area: f64,
    pub load: f64,
    pub t: f64,
}

/// A blob of flame and smoke.
#[derive(Debug, Clone, Copy)]
pub struct Blob {
    pub x: DVec3,
    pub m_flame: f64,
    pub m_smoke: f64,
    pub t: f64,
    pub age: f64,
    pub sigma0: f64,
}

impl Blob {
    pub fn sigma(&self, kappa: f64) -> f64 {
        (self.sigma0 * self.sigma0 + 2.0 * kappa * self.age).sqrt()
    }
    /// Its kernel's weight at `x` (unnormalised, 1 at its centre) given its σ `s`: none beyond 3σ.
    pub fn weight_at(&self, x: DVec3, s: f64) -> Option<f64> {
        let d2 = (x - self.x).length_squared();
        (d2 < 9.0 * s * s).then(|| (-0.5 * d2 / (s * s)).exp())
    }
}

/// What one step did to the masses (kg), for bookkeeping.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepLedger {
    pub fuel_consumed: f64,
    pub flame_produced: f64,
    pub smoke_produced: f64,
    pub flame_to_smoke: f64,
    pub smoke_decayed: f64,
    pub removed: f64,
}

/// The state of a simulation.
#[derive(Debug)]
pub struct Sim {
    pub model: Model,
    pub cells: Vec<Cell>,
    /// Neighbouring fuel cells, for conduction.
    pub links: Vec<Link>,
    /// The flames' radiative cooling, from the renderer's soot.
    pub cooling: Cooling,
    pub blobs: Vec<Blob>,
    pub time: f64,
    /// Warped blobs (§4) when voxelising: the back-trace time t₀ (s) and the spread η (m/s) — `None`: round
    /// kernels.
    pub warp: Option<(f64, f64)>,
    /// Embers thrown from the burning fuel, per second (`None`: none, and no random number is drawn for them).
    pub ember_rate: Option<f64>,
    /// The embers' char and the air they burn in ([`EMBER_CHAR`], the plugin's defaults).
    pub ember_char: firemedium_core::ember::Char,
    pub embers: Vec<Ember>,
    /// Embers thrown so far.
    pub embers_born: usize,
    rng: Rng,
    ember_rng: Rng,
    noise: Noise,
}

/// An ember in flight: thrown from a burning fuel cell, carried by drag towards the gas's velocity, falling,
/// burning its char in the air and cooling by radiation and convection (`firemedium_core::ember::burn`, the
/// plugin's defaults for char and air).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ember {
    pub x: DVec3,
    pub v: DVec3,
    /// Radius at birth, m (what the particle file holds: the plugin burns it down from there).
    pub r: f64,
    /// Temperature at birth, K.
    pub t0: f64,
    /// Seconds since birth.
    pub age: f64,
    /// Its temperature (K) and radius (m) now.
    pub now: (f64, f64),
}

/// The char of the embers and the air they burn in (the plugin's defaults).
pub const EMBER_CHAR: firemedium_core::ember::Char = firemedium_core::ember::Char {
    emissivity: firemedium_core::ember::CHAR_EMISSIVITY,
    density: firemedium_core::ember::CHAR_DENSITY,
    heat_capacity: firemedium_core::ember::CHAR_HEAT_CAPACITY,
    ambient: T_AMB,
    oxygen: firemedium_core::ember::AIR_OXYGEN,
};

impl Ember {
    /// Its temperature now (K).
    pub fn temperature(&self) -> f64 {
        self.now.0
    }
}

/// Embers cooler than this are dropped (below the Draper point, 798 K, a dull red at most).
pub const EMBER_DEAD_K: f64 = 700.0;

#[cfg(test)]
mod tests;
