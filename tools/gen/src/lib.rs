//! Fire datasets of our own: Stam & Fiume's (1995, §6) blob fire model, run over time and voxelised.
//!
//! **Fuel** lies on surfaces (logs, a pool, a wick, a torch head) as cells with a fuel load ρ_fuel (kg/m²) and
//! a temperature T_fuel. A cell heats by the radiation of the flames that reaches it and cools by its own
//! (§6: S_T,fuel = α_f F σ T_flame⁴, L_T,fuel = 2 α_f σ T⁴, per unit area, over a heat capacity per area) — an
//! implicit step, stable for any dt. "Striking a match" holds the ignition cells at `t_match` for the first
//! `match_seconds`. Fuel turns into flame by the Arrhenius rate k = ν_a exp(−T_a / T_fuel) (eq. 10), integrated
//! exactly over a step: the cell loses ρ_fuel (1 − e^{−k dt}) per area, and that mass leaves as a new **flame
//! blob** (production equals consumption to rounding).
//!
//! **Blobs** are Gaussian kernels (eq. 6–9 of §4) of flame mass m_f and smoke mass m_s at a temperature T. Each
//! moves with the wind — a buoyant updraft B √((T − T_amb)/T_amb) plus a divergence-free turbulent field (the curl
//! of a seeded noise potential, after Stam & Fiume 1993), by a midpoint step — and grows by diffusion,
//! σ² = σ₀² + 2κ·age. Flame turns into smoke at ν_b exp(−T / T_s) (§6), exactly over a step (the masses' sum
//! is kept); smoke decays at `smoke_decay`. A new blob starts at T_fuel + `release` (the heat of the reaction,
//! §6's S_T,flame); it cools by radiation, dT/dt = −K T⁴ with K = 4π α_flame σ / c (§6's L_T,flame per unit
//! heat capacity), integrated exactly — T(t + dt) = (T⁻³ + 3K dt)^(−1/3), never below ambient — so a stiff K
//! or a long step cannot overshoot; then mixing with entrained air relaxes T − T_amb by e^{−dt/τ} (our
//! addition: with radiation alone the smoke stays glowing-hot for metres). The radiation that cools the flames is what heats the fuel: the fuel sees
//! the flames' total radiant power from their power-weighted centre (one "blob cluster", as §6 shoots from a
//! couple), times the view factor `feedback`.
//!
//! **Voxelisation** sums the kernels: flame and smoke mass densities ρ (kg of fuel per m³) and the mass-weighted
//! temperature (§4: θ = Σ m θ W / Σ m W); it writes `density` = soot volume fraction Y_s (ρ_f + ρ_s) / ρ_soot,
//! `temperature` in K (0 where there is no mass, the file's background), and per `--species SYM:N` a number
//! density N · ρ_f / max ρ_f that follows the flame, as an OpenVDB file the dataset reader loads.
//!
//! **The radiative constants, against the fire light's convention.** An optically thin emitter of absorption
//! cross-section α per kg radiates 4·α·m·σT⁴ (its emission coefficient α ρ σT⁴/π over 4π sr: the fire light's
//! power). §6 writes 4π·α·σT⁴ — σT⁴ taken as a radiance — and the generator keeps the paper's form, so its
//! `alpha_flame` is an *effective* cross-section: the blobs radiate as thin emitters of cross-section π·α
//! (the campfire's `alpha_flame` of 30 m²/kg cools and heats as 94 m²/kg would in the fire light's convention). The fuel's loss
//! 2·α_f·σT⁴ per area is a surface's grey emission (α_f σT⁴ per side) from both sides, where §6 writes 2π — the
//! same slip the other way. Both are kept as written so that the committed datasets stay the generator's; a test
//! checks the blobs' energy bookkeeping against the effective constant.
//!
//! **Warped blobs** (§4, opt-in: `gen --warp`): the kernels are evaluated at points traced back through the
//! turbulent wind, so blobs stretch and curl with it instead of staying round ([`Warp`]).
//!
//! Not modelled (documented): fuel spread by conduction, oxygen depletion.

mod kinds;
mod sim;
mod voxel;
mod write;

use sim::Noise;
pub use sim::{implicit_fuel_temperature, radiative_cooling};
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
    /// Flame absorption cross-section per kg (m²/kg): a blob radiates 4π α m σ T⁴ (which cools it and heats
    /// the fuel).
    pub alpha_flame: f64,
    /// Fraction of the flames' radiant power density a fuel cell absorbs (view factor × absorptance).
    pub feedback: f64,
    /// Fuel heat capacity per area, J/(m² K).
    pub fuel_heat_capacity: f64,
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

impl Model {
    /// Radiative cooling constant K = 4π α σ / c, 1/(K³ s): dT/dt = −K T⁴ is the blob's radiated power
    /// 4π α m σ T⁴ over its heat capacity c m.
    pub fn k_rad(&self) -> f64 {
        4.0 * std::f64::consts::PI * self.alpha_flame * SIGMA / self.heat_capacity
    }
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
