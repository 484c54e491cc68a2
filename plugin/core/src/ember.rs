//! Embers (Selle's marker particles, made physical): small grey spheres cooling by radiation alone.
//!
//! A sphere of radius r, density ρ, specific heat c and emissivity ε in surroundings at T_a loses
//! 4πr² εσ(T⁴ − T_a⁴) and holds (4/3)πr³ ρ c T, so (lumped: Biot number hr/k ≪ 1 for millimetre char)
//!
//!   dT/dt = −k (T⁴ − T_a⁴),   k = 3εσ / (ρ c r).
//!
//! Separating variables, k t = Φ(T) − Φ(T₀) with Φ(T) = ∫_T^∞ dT'/(T'⁴ − T_a⁴), which for T > T_a is
//!
//!   Φ(T) = [atanh(T_a/T) − atan(T_a/T)] / (2T_a³) = Σ_{m≥0} T_a^{4m} / ((4m + 3) T^{4m+3})
//!
//! (the series avoids the cancellation of the closed form when T_a ≪ T; with T_a = 0 it is 1/(3T³), so
//! T = T₀ (1 + 3k T₀³ t)^{−1/3}). T is found from Φ by Newton's method safeguarded by bisection.
//!
//! **Burning** ([`burn`]): a spark in air also oxidises its char, and the heat keeps it glowing while it flies.
//! Per unit of its surface, the char burns at J = 1 / (1/J_k + 1/J_d) kg/(m²·s) — the series of
//!
//! - the kinetics of wood char's oxidation (Anca-Couce, Zobel, Berger & Behrendt, *Combust. Flame* 159, 1708,
//!   2012): per kilogram of char k = A e^{−E/RT} Y_O2^0.68, A = 10^6.55 s⁻¹, E = 124 kJ/mol, over the ember's
//!   mass per area, J_k = k ρ r / 3;
//! - the diffusion of oxygen to the surface through the film around it (the one-film model of a burning carbon
//!   particle; Turns, *An Introduction to Combustion*, ch. 14): J_d = Sh ρ_g D / (2r) · Y_O2 / ν, Sh = 2 (the spark
//!   carried by the gas), ν = 2.664 kg of oxygen per kg of char;
//!
//! its carbon burning to CO₂ at the surface, releasing ΔH = 32.8 MJ per kg (12.3 MJ per kg of oxygen: the most any
//! carbon product gives — to CO, 6.9; the char's own heat of 37.7 MJ/kg with 2 kg of oxygen, Lautenberger &
//! Fernandez-Pello 2009, released 18.9 per kg of oxygen, more than chemistry allows), against its radiation
//! εσ(T⁴ − T_a⁴) and convection
//! h (T − T_a), h = Nu k_g / (2r), Nu = 2; air's k_g = 0.0263 (T_f/300)^0.8 W/(m·K), ρ_g = p M / (R T_f) and
//! D_O2 = 1.8e-5 (T_f/298)^1.75 m²/s at the film temperature T_f = (T + T_a)/2 (Incropera's tables of air, fitted).
//! The char burns away at constant density, r shrinking by J/ρ. A 1 mm spark settles near 1090 K (0.5 mm near
//! 1280 K: inside the 900–1300 K measured for glowing embers) and burns for about 34 s; a 3 mm one cannot stay lit
//! (its losses outrun the oxygen reaching it) and cools as above, as does any ember below the ~850 K where the
//! kinetics fall behind. The
//! two equations are integrated by classical RK4 in steps of at most half the ember's thermal time constant
//! (and 50 ms).
//!
//! Used by the plugin (an ember's temperature at the ray's time) and by `gen` (which ages the embers it emits),
//! so the two agree (by construction while an ember only cools; within 1e-7 while it burns: measured, one
//! integration over 3 s against 360 steps of a frame).

use crate::constants::STEFAN_BOLTZMANN;

/// Total emissivity of wood char (0.85–0.95; the plugin's `emberemissivity` default).
pub const CHAR_EMISSIVITY: f64 = 0.9;
/// Apparent density of softwood char, kg/m³ (200–300; `emberdensity`).
pub const CHAR_DENSITY: f64 = 250.0;
/// Specific heat of char at 600–1200 K, J/(kg·K) (1.0–1.5 k; Gupta, Yang & Kozinski 2003; `emberheatcapacity`).
pub const CHAR_HEAT_CAPACITY: f64 = 1200.0;

/// The cooling constant k = 3εσ/(ρ c r) (K⁻³ s⁻¹) of a sphere of radius `r` (m), emissivity `eps`, density
/// `rho` (kg/m³) and specific heat `c` (J/(kg·K)). 0 when any input is not positive and finite.
pub fn cooling_constant(eps: f64, rho: f64, c: f64, r: f64) -> f64 {
    let k = 3.0 * eps * STEFAN_BOLTZMANN / (rho * c * r);
    if eps > 0.0 && k.is_finite() && k > 0.0 {
        k
    } else {
        0.0
    }
}

/// Φ(T) = ∫_T^∞ dT'/(T'⁴ − a⁴) for T > a ≥ 0 (K⁻³).
fn phi(t: f64, a: f64) -> f64 {
    let x = a / t;
    if x < 0.5 {
        // Σ x^{4m}/(4m + 3) / T³: the ratio x⁴ ≤ 1/16, 14 terms reach 1e-17.
        let (x4, mut term, mut sum) = (x.powi(4), 1.0, 0.0);
        for m in 0..14 {
            sum += term / (4 * m + 3) as f64;
            term *= x4;
        }
        sum / t.powi(3)
    } else {
        (x.atanh() - x.atan()) / (2.0 * a.powi(3))
    }
}

/// The temperature (K) of an ember at `t0` (K) after `seconds` of cooling with constant `k`
/// ([`cooling_constant`]) in surroundings at `ambient` (K). A negative time runs the cooling backwards (the
/// temperature it had then), capped at 1e6 K. An ember at or below ambient keeps its temperature (it would warm
/// towards ambient, where it emits almost nothing visible). Non-finite inputs give `t0` (or 0 if that is not
/// finite either).
pub fn cooled_temperature(t0: f64, seconds: f64, k: f64, ambient: f64) -> f64 {
    const T_CAP: f64 = 1e6;
    if !t0.is_finite() || t0 <= 0.0 {
        return if t0.is_finite() { t0.max(0.0) } else { 0.0 };
    }
    let a = if ambient.is_finite() {
        ambient.max(0.0)
    } else {
        0.0
    };
    if !(seconds.is_finite() && k.is_finite() && k > 0.0) || seconds == 0.0 || t0 <= a {
        return t0;
    }
    let target = phi(t0, a) + k * seconds;
    if target <= phi(T_CAP, a) {
        return T_CAP;
    }
    // Φ decreases from +∞ at T = a to 0 at ∞; the root lies in (a, t0] when cooling, (t0, cap] when warming
    // backwards. Start from the T_a = 0 solution clamped into the bracket.
    let (mut lo, mut hi) = if seconds > 0.0 { (a, t0) } else { (t0, T_CAP) };
    let mut t = (1.0 / (3.0 * target)).cbrt().clamp(lo, hi);
    if t <= lo {
        t = 0.5 * (lo + hi);
    }
    for _ in 0..200 {
        let f = phi(t, a) - target;
        // Φ is decreasing: f > 0 means t is below the root.
        if f > 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        let slope = -1.0 / (t.powi(4) - a.powi(4));
        let newton = t - f / slope;
        let next = if newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() <= 1e-13 * t {
            return next;
        }
        t = next;
    }
    t
}

/// The oxygen mass fraction of air (`emberoxygen`'s default).
pub const AIR_OXYGEN: f64 = 0.233;
/// Wood char's oxidation: ln(A/s⁻¹)/ln 10, E/R (K), the oxygen exponent (Anca-Couce et al. 2012).
const CHAR_KINETICS: (f64, f64, f64) = (6.55, 124.0e3 / 8.314_462_618, 0.68);
/// The char's carbon burning to CO₂ at its surface, C + O₂ → CO₂: the heat released per kg of carbon (ΔH_f of CO₂,
/// 393.5 kJ/mol, over carbon's 12.011 g/mol) and the kg of oxygen it takes (31.998 / 12.011) — 12.3 MJ per kg of
/// oxygen, the most any carbon product gives (to CO, 9.2 MJ per kg of carbon and 1.33 kg of oxygen: 6.9 MJ per kg
/// of oxygen). Lautenberger & Fernandez-Pello's 37.7 MJ with 2 kg of oxygen (18.9 MJ per kg of oxygen) released
/// more heat per kilogram of oxygen than chemistry allows.
pub const CHAR_HEAT: f64 = 393.5e3 / 12.011e-3;
/// Kilograms of oxygen per kilogram of carbon burnt to CO₂.
pub const CHAR_OXYGEN_RATIO: f64 = 31.998 / 12.011;
/// Nusselt and Sherwood numbers of a sphere carried by the gas.
const SPHERE_NU: f64 = 2.0;

/// An ember's char and the air it flies in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Char {
    pub emissivity: f64,
    /// kg/m³.
    pub density: f64,
    /// J/(kg·K).
    pub heat_capacity: f64,
    /// The air's temperature, K.
    pub ambient: f64,
    /// The air's oxygen mass fraction (0: the char does not burn, and [`burn`] is [`cooled_temperature`]).
    pub oxygen: f64,
}

/// The rates of an ember at `t` (K), radius `r` (m): (dT/dt in K/s, dr/dt in m/s).
fn rates(t: f64, r: f64, c: &Char) -> (f64, f64) {
    let a = c.ambient.max(0.0);
    let film = 0.5 * (t + a).max(2.0);
    let k_gas = 0.0263 * (film / 300.0).powf(0.8);
    let rho_d = 101_325.0 * 0.028_97 / (8.314_462_618 * film) * 1.8e-5 * (film / 298.0).powf(1.75);
    let (log_a, t_a, n) = CHAR_KINETICS;
    let burn = if c.oxygen > 0.0 && t > 0.0 {
        let j_kin = 10f64.powf(log_a) * (-t_a / t).exp() * c.oxygen.powf(n) * c.density * r / 3.0;
        let j_dif = SPHERE_NU * rho_d / (2.0 * r) * c.oxygen / CHAR_OXYGEN_RATIO;
        if j_kin > 0.0 && j_dif > 0.0 {
            1.0 / (1.0 / j_kin + 1.0 / j_dif)
        } else {
            0.0
        }
    } else {
        0.0
    };
    let loss = c.emissivity * STEFAN_BOLTZMANN * (t.powi(4) - a.powi(4))
        + SPHERE_NU * k_gas / (2.0 * r) * (t - a);
    // Per unit area over the heat held per unit area, ρ c r / 3.
    let dtdt = (burn * CHAR_HEAT - loss) / (c.density * c.heat_capacity * r / 3.0);
    (dtdt, -burn / c.density)
}

/// An ember's temperature (K) and radius (m) after `seconds` (≥ 0) from `t0`, `r0`, burning in air as the
/// module says; without oxygen, [`cooled_temperature`] (radiation alone) and the radius kept. An ember whose
/// char is gone (radius below 1 µm) returns radius 0 at the ambient temperature. Non-finite or non-positive
/// inputs give (t0, r0) back.
pub fn burn(t0: f64, r0: f64, seconds: f64, c: &Char) -> (f64, f64) {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if !(ok(t0)
        && ok(r0)
        && seconds.is_finite()
        && seconds > 0.0
        && ok(c.density)
        && ok(c.heat_capacity))
    {
        return (t0, r0);
    }
    if !(c.oxygen > 0.0) {
        let k = cooling_constant(c.emissivity, c.density, c.heat_capacity, r0);
        return (cooled_temperature(t0, seconds, k, c.ambient), r0);
    }
    let (mut t, mut r, mut left) = (t0, r0, seconds);
    const GONE: f64 = 1e-6;
    while left > 0.0 {
        if r < GONE {
            return (c.ambient.max(0.0), 0.0);
        }
        // Half the thermal time constant ρ c r / 3 over the losses' conductance (radiation's 4εσT³ and
        // convection's h), and 50 ms (RK4 is stable to 2.8 of them; at a half its error is ~3e-4 per step).
        let g = 4.0 * c.emissivity.max(0.0) * STEFAN_BOLTZMANN * t.max(c.ambient).powi(3)
            + SPHERE_NU * 0.0263 * (t.max(300.0) / 300.0).powf(0.8) / (2.0 * r);
        let tau = c.density * c.heat_capacity * r / 3.0 / g.max(1e-12);
        let h = (0.5 * tau).clamp(1e-6, 0.05).min(left);
        let f = |t: f64, r: f64| rates(t.max(1.0), r.max(0.5 * GONE), c);
        let (a1, b1) = f(t, r);
        let (a2, b2) = f(t + 0.5 * h * a1, r + 0.5 * h * b1);
        let (a3, b3) = f(t + 0.5 * h * a2, r + 0.5 * h * b2);
        let (a4, b4) = f(t + h * a3, r + h * b3);
        t += h / 6.0 * (a1 + 2.0 * a2 + 2.0 * a3 + a4);
        r += h / 6.0 * (b1 + 2.0 * b2 + 2.0 * b3 + b4);
        t = t.clamp(1.0, 1e5);
        left -= h;
    }
    if r < GONE {
        return (c.ambient.max(0.0), 0.0);
    }
    (t, r)
}

/// The temperature (K) at which an ember of radius `r` (m) burns steadily — its char's heat release equal to its
/// losses — searched from 600 K to 5000 K; `None` when it cannot burn there (too little oxygen, too large to
/// stay lit).
pub fn burning_temperature(r: f64, c: &Char) -> Option<f64> {
    let net = |t: f64| rates(t, r, c).0;
    // The upper root of the balance (the stable, burning branch): from hot down, the first sign change.
    let (mut hi, mut lo) = (5000.0, 5000.0);
    while lo > 600.0 {
        lo -= 10.0;
        if net(lo) > 0.0 {
            break;
        }
        hi = lo;
    }
    if !(net(lo) > 0.0) {
        return None;
    }
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if net(mid) > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The total power (W) a grey sphere of radius `r` (m), emissivity `eps`, at `t` (K) radiates: 4πr²εσT⁴.
pub fn radiated_power(eps: f64, r: f64, t: f64) -> f64 {
    4.0 * std::f64::consts::PI * r * r * eps * STEFAN_BOLTZMANN * t.powi(4)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn without_surroundings_the_closed_form() {
        // T = T0 (1 + 3 k T0³ t)^(-1/3), independent of this module's series and Newton.
        let k = cooling_constant(0.9, 200.0, 1000.0, 1e-3);
        assert!((k - 3.0 * 0.9 * 5.670_374_419e-8 / 200.0).abs() < 1e-20);
        for (t0, s) in [(1200.0, 0.01), (1200.0, 1.0), (900.0, 10.0), (3000.0, 0.3)] {
            let exact = t0 * (1.0 + 3.0 * k * t0 * t0 * t0 * s).powf(-1.0 / 3.0);
            let got = cooled_temperature(t0, s, k, 0.0);
            assert!(
                (got / exact - 1.0).abs() < 1e-12,
                "{t0} K, {s} s: {got} vs {exact}"
            );
        }
    }

    /// dT/dt = −k (T⁴ − a⁴) by classical RK4 with small steps: an independent integration.
    fn rk4(t0: f64, s: f64, k: f64, a: f64) -> f64 {
        let n = 20_000;
        let h = s / n as f64;
        let f = |t: f64| -k * (t.powi(4) - a.powi(4));
        let mut t = t0;
        for _ in 0..n {
            let k1 = f(t);
            let k2 = f(t + 0.5 * h * k1);
            let k3 = f(t + 0.5 * h * k2);
            let k4 = f(t + h * k3);
            t += h / 6.0 * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
        }
        t
    }

    #[test]
    fn with_surroundings_it_follows_the_ode() {
        let k = cooling_constant(0.9, 300.0, 1100.0, 0.5e-3);
        for (t0, s, a) in [
            (1200.0, 0.2, 293.15),
            (1200.0, 5.0, 293.15),
            (700.0, 20.0, 600.0),
            (350.0, 50.0, 300.0),
            (1500.0, 2.0, 1000.0),
        ] {
            let want = rk4(t0, s, k, a);
            let got = cooled_temperature(t0, s, k, a);
            assert!(
                (got - want).abs() < 1e-6 * want,
                "{t0} K, {s} s, {a} K: {got} vs {want}"
            );
            assert!(got < t0 && got > a);
        }
    }

    #[test]
    fn backwards_returns_the_earlier_temperature() {
        let k = cooling_constant(0.9, 200.0, 1000.0, 1e-3);
        let later = cooled_temperature(1300.0, 0.4, k, 293.15);
        let back = cooled_temperature(later, -0.4, k, 293.15);
        assert!((back - 1300.0).abs() < 1e-8, "{back}");
    }

    #[test]
    fn energy_radiated_is_the_heat_lost() {
        // ρ c V (T0 − T(t)) = ∫ 4πr² εσ (T⁴ − a⁴) dt, the integral by Simpson over the cooled curve.
        let (eps, rho, c, r, a) = (0.85, 250.0, 1200.0, 2e-3, 293.15);
        let k = cooling_constant(eps, rho, c, r);
        let (t0, s, n) = (1250.0, 3.0, 3000);
        let h = s / n as f64;
        let q = |i: usize| {
            let t = cooled_temperature(t0, i as f64 * h, k, a);
            radiated_power(eps, r, t) - radiated_power(eps, r, a)
        };
        let mut e = q(0) + q(n);
        for i in 1..n {
            e += q(i) * if i % 2 == 1 { 4.0 } else { 2.0 };
        }
        e *= h / 3.0;
        let heat = rho * c * 4.0 / 3.0
            * std::f64::consts::PI
            * r.powi(3)
            * (t0 - cooled_temperature(t0, s, k, a));
        assert!(
            (e / heat - 1.0).abs() < 1e-6,
            "{e} J radiated, {heat} J lost"
        );
    }

    #[test]
    fn degenerate_inputs_stay_finite() {
        let k = 1e-9;
        assert_eq!(cooled_temperature(f64::NAN, 1.0, k, 300.0), 0.0);
        assert_eq!(cooled_temperature(1000.0, f64::NAN, k, 300.0), 1000.0);
        assert_eq!(cooled_temperature(1000.0, 1.0, 0.0, 300.0), 1000.0);
        assert_eq!(cooled_temperature(250.0, 1.0, k, 300.0), 250.0);
        assert_eq!(cooled_temperature(1000.0, -1e9, k, 0.0), 1e6);
        let t = cooled_temperature(1000.0, 1e30, k, 300.0);
        assert!((300.0..300.001).contains(&t), "{t}");
        assert_eq!(cooling_constant(0.9, 0.0, 1000.0, 1e-3), 0.0);
        assert_eq!(cooling_constant(0.0, 200.0, 1000.0, 1e-3), 0.0);
    }

    const SPARK: Char = Char {
        emissivity: CHAR_EMISSIVITY,
        density: CHAR_DENSITY,
        heat_capacity: CHAR_HEAT_CAPACITY,
        ambient: 293.15,
        oxygen: AIR_OXYGEN,
    };

    #[test]
    fn a_burning_spark_settles_where_oxidation_meets_its_losses() {
        // The steady burning temperature, written out independently from the published constants: in the
        // diffusion limit the oxygen reaching the surface, Sh ρD / (2r) · Y, releases q per kilogram — carbon
        // to CO₂, 393.5 kJ/mol over 31.998 g of O₂ per mol: 12.30 MJ/kg —, against εσ(T⁴ − T_a⁴) + Nu k / (2r)
        // (T − T_a), air's properties at the film temperature; the kinetics (10^6.55 e^{−124 kJ/mol / RT}) are
        // fast there, so the series rate is within a few % of the diffusion limit, and the root with them within
        // tens of kelvin. Steady temperatures inside the 900–1300 K measured for glowing embers at 0.5 and 1 mm;
        // a 3 mm ember's losses outrun its oxygen supply: it cannot stay lit.
        let q = 393.5e3 / 31.998e-3;
        let balance = |t: f64, r: f64| {
            let (a, f): (f64, f64) = (293.15, 0.5 * (t + 293.15));
            let rho_d =
                101_325.0 * 0.028_97 / (8.314_462_618 * f) * 1.8e-5 * (f / 298.0).powf(1.75);
            let k = 0.0263 * (f / 300.0).powf(0.8);
            q * 2.0 * rho_d / (2.0 * r) * 0.233
                - 0.9 * STEFAN_BOLTZMANN * (t.powi(4) - a.powi(4))
                - 2.0 * k / (2.0 * r) * (t - a)
        };
        assert_eq!(burning_temperature(3e-3, &SPARK), None);
        for (r, lo, hi) in [(0.5e-3, 1200.0, 1350.0), (1e-3, 1000.0, 1150.0)] {
            let (mut a, mut b) = (700.0, 4000.0);
            for _ in 0..80 {
                let m = 0.5 * (a + b);
                if balance(m, r) > 0.0 {
                    a = m
                } else {
                    b = m
                }
            }
            let diffusion_limit = 0.5 * (a + b);
            let steady = burning_temperature(r, &SPARK).expect("a spark in air burns");
            assert!(
                steady < diffusion_limit
                    && diffusion_limit - steady < 60.0
                    && (lo..hi).contains(&steady),
                "r {r}: {steady} K, diffusion limit {diffusion_limit} K"
            );
            // Thrown at 1650 K, within a few of its thermal time constants (ρ c r / 3 over its losses'
            // conductance: 0.2 s at 1 mm) it burns at the steady temperature of the radius it has then
            // (quasi-steady: its char burns away far slower than it heats or cools).
            let (t, rr) = burn(1650.0, r, 3000.0 * r, &SPARK);
            let now = burning_temperature(rr, &SPARK).unwrap();
            assert!(
                (t / now - 1.0).abs() < 0.01,
                "r {r} → {rr}: {t} K vs {now} K"
            );
            assert!(rr > 0.8 * r, "r {r} → {rr}");
        }
    }

    #[test]
    fn a_spark_burns_away_by_the_d_squared_law_and_a_cold_one_goes_out() {
        // In the diffusion limit r² falls at the constant rate Sh ρD Y / (ν ρ_c) (at its film temperature): a
        // 1 mm spark shrinks to 0.3 mm in (1 − 0.3²) r₀² ρ_c ν / (Sh ρD Y). Measured against that at its steady
        // temperature, within 25 % (it burns hotter, and faster, as it shrinks; smaller still, its kinetics fall
        // behind and it goes out).
        let r0 = 1e-3;
        let steady = burning_temperature(r0, &SPARK).unwrap();
        let f = 0.5 * (steady + 293.15);
        let rho_d = 101_325.0 * 0.028_97 / (8.314_462_618 * f) * 1.8e-5 * (f / 298.0).powf(1.75);
        let d2 = (1.0 - 0.09) * r0 * r0 * CHAR_DENSITY * (31.998 / 12.011) / (2.0 * rho_d * 0.233);
        let mut alive = 0.0;
        let (mut t, mut r) = (1650.0, r0);
        while r > 0.3 * r0 && alive < 100.0 {
            (t, r) = burn(t, r, 0.05, &SPARK);
            alive += 0.05;
        }
        assert!(
            (alive / d2 - 1.0).abs() < 0.25,
            "down to 0.3 mm in {alive} s, the d² law {d2} s (at {t} K)"
        );
        // A spark already below where its char can keep up (700 K) cools as radiation and convection say,
        // never rising; without oxygen, burn is the radiative cooling, bit for bit.
        let mut prev = 700.0;
        for s in [0.1, 0.5, 1.0, 3.0] {
            let (t, _) = burn(700.0, r0, s, &SPARK);
            assert!(t < prev, "{s} s: {t} K");
            prev = t;
        }
        let inert = Char {
            oxygen: 0.0,
            ..SPARK
        };
        let k = cooling_constant(inert.emissivity, inert.density, inert.heat_capacity, r0);
        assert_eq!(
            burn(1500.0, r0, 0.7, &inert),
            (cooled_temperature(1500.0, 0.7, k, 293.15), r0)
        );
    }
}
