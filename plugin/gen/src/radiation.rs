//! The flames' radiation, derived from the renderer's own soot: what a blob radiates is what the plugin would
//! render it emitting, so the heat the flames lose and the heat the fuel receives are the picture's.
//!
//! A blob holds Y_s kg of soot per kg of fuel (`soot_yield`), at the density of soot ρ_s: the voxeliser writes
//! its soot volume fraction f_v = Y_s ρ / ρ_s, and the plugin renders σ_a(λ) = f_v κ(λ) (propane's optical
//! constants, Hottel's α: `SootOptics::propane`, the plugin's default fuel). Optically thin, a volume V
//! radiates 4π ∫ σ_a B_λ(T) dλ V = 4 f_v κ̂_P(T) σT⁴ V, with κ̂_P(T) = ∫ κ B_λ dλ / ∫ B_λ dλ the Planck mean per
//! unit volume fraction. Per kg of fuel in the blob, over the heat capacity c of the gas it heats:
//!
//!   dT/dt = −K(T) T⁴,   K(T) = 4 σ κ̂_P(T) Y_s / (ρ_s c),
//!
//! one constant, derived (Stam & Fiume's L_T,flame = 4π ρ α_flame σT⁴ with their α_flame the Planck mean: their
//! 4π counts σT⁴ as a radiance, π too much, which the derivation here does not repeat). κ̂_P grows about
//! linearly with T (Rayleigh soot), so the cooling is steeper than T⁴; it is integrated exactly over a step
//! through the table of F(T) = ∫_T^∞ dT' / (K(T') T'⁴): F(T(t + dt)) = F(T(t)) + dt, never below ambient.

use super::{RHO_SOOT, SIGMA, T_AMB};
use firemedium_core::blackbody::spectral_radiance;
use firemedium_core::soot::{SootOptics, HOTTEL_ALPHA};

/// Nodes of the tables, log-spaced in T from ambient to [`T_TOP`].
const NODES: usize = 1024;
/// The tables' top (K): above it K(T) is extrapolated as ∝ T (Rayleigh soot).
const T_TOP: f64 = 2.0e4;

/// κ̂_P(T): soot's Planck-mean absorption coefficient per unit volume fraction (1/m), the renderer's soot
/// (propane, Hottel's α), by quadrature over 100 nm–100 µm (log steps of 1 %: 690 nodes; the midpoint rule's error there is below 1e-5).
pub fn planck_mean_per_fraction(t: f64) -> f64 {
    let soot = SootOptics::propane();
    let (mut num, mut den) = (0.0, 0.0);
    let mut l = 100.0;
    while l < 1.0e5 {
        let dl = l * 1e-2;
        let b = spectral_radiance(t, l + 0.5 * dl);
        num += soot.kappa(l + 0.5 * dl, 1.0, HOTTEL_ALPHA) * b * dl;
        den += b * dl;
        l += dl;
    }
    num / den
}

/// The blobs' radiative cooling, dT/dt = −K(T) T⁴ (see the module's text), integrated exactly.
#[derive(Debug, Clone)]
pub struct Cooling {
    /// ln T at the nodes.
    ln_t: Vec<f64>,
    /// K(T) at the nodes, 1/(K³ s).
    k: Vec<f64>,
    /// F(T) = ∫_T^∞ dT' / (K T'⁴) at the nodes, s (decreasing).
    f: Vec<f64>,
}

impl Cooling {
    /// The cooling of a gas holding `soot_yield` kg of soot per kg of fuel, of heat capacity `heat_capacity`
    /// J/(kg K) per kg of fuel.
    pub fn new(soot_yield: f64, heat_capacity: f64) -> Cooling {
        let (lo, hi) = (T_AMB.ln(), T_TOP.ln());
        let ln_t: Vec<f64> = (0..NODES)
            .map(|i| lo + (hi - lo) * i as f64 / (NODES - 1) as f64)
            .collect();
        let scale = 4.0 * SIGMA * soot_yield / (RHO_SOOT * heat_capacity);
        let k: Vec<f64> = ln_t
            .iter()
            .map(|&x| scale * planck_mean_per_fraction(x.exp()))
            .collect();
        // F from the top down: the tail above T_TOP in closed form (K ∝ T there: ∫ dT / (K_top/T_top · T⁵) =
        // T_top / (4 K_top T_top⁴)), then Simpson per interval in ln T (dT = T d ln T).
        let g = |x: f64, kx: f64| 1.0 / (kx * x.exp().powi(3));
        let mut f = vec![0.0; NODES];
        f[NODES - 1] = 1.0 / (4.0 * k[NODES - 1] * T_TOP.powi(3));
        for i in (0..NODES - 1).rev() {
            let (a, b) = (ln_t[i], ln_t[i + 1]);
            let m = 0.5 * (a + b);
            let km = scale * planck_mean_per_fraction(m.exp());
            f[i] = f[i + 1] + (b - a) / 6.0 * (g(a, k[i]) + 4.0 * g(m, km) + g(b, k[i + 1]));
        }
        Cooling { ln_t, k, f }
    }

    /// Node interval and fraction of `ln T` (clamped to the table).
    fn locate(&self, x: f64) -> (usize, f64) {
        let (lo, hi) = (self.ln_t[0], self.ln_t[NODES - 1]);
        let u = ((x - lo) / (hi - lo) * (NODES - 1) as f64).clamp(0.0, (NODES - 1) as f64);
        let i = (u as usize).min(NODES - 2);
        (i, u - i as f64)
    }

    /// K(T), 1/(K³ s).
    pub fn k(&self, t: f64) -> f64 {
        if t >= T_TOP {
            return self.k[NODES - 1] * t / T_TOP;
        }
        let (i, w) = self.locate(t.max(T_AMB).ln());
        self.k[i] + w * (self.k[i + 1] - self.k[i])
    }

    /// The power a blob of `mass` kg of fuel radiates at `t`, W (c m K(T) T⁴: what its cooling removes).
    pub fn power(&self, t: f64, mass: f64, heat_capacity: f64) -> f64 {
        heat_capacity * mass * self.k(t) * t.powi(4)
    }

    /// F(T): log-linear between the nodes (F ∝ T⁻⁴ locally, so ln F is near linear in ln T).
    fn f_of(&self, t: f64) -> f64 {
        if t >= T_TOP {
            return self.f[NODES - 1] * (T_TOP / t).powi(4);
        }
        let (i, w) = self.locate(t.ln());
        (self.f[i].ln() + w * (self.f[i + 1].ln() - self.f[i].ln())).exp()
    }

    /// The temperature after `dt` s of cooling from `t` (ambient once F(T) + dt passes F(ambient)).
    pub fn step(&self, t: f64, dt: f64) -> f64 {
        if !(t > T_AMB) {
            return T_AMB;
        }
        let target = self.f_of(t) + dt.max(0.0);
        if target >= self.f[0] {
            return T_AMB;
        }
        // F decreases with T: the node interval holding `target`, then ln F linear within it.
        let (mut a, mut b) = (0, NODES - 1);
        if target < self.f[NODES - 1] {
            // Above the table: the closed-form tail.
            return T_TOP * (self.f[NODES - 1] / target).powf(0.25);
        }
        while b - a > 1 {
            let m = (a + b) / 2;
            if self.f[m] >= target {
                a = m;
            } else {
                b = m;
            }
        }
        let (fa, fb) = (self.f[a].ln(), self.f[b].ln());
        let w = if fb != fa {
            (target.ln() - fa) / (fb - fa)
        } else {
            0.0
        };
        (self.ln_t[a] + w * (self.ln_t[b] - self.ln_t[a])).exp()
    }
}
