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
//! T = T₀ (1 + 3k T₀³ t)^{−1/3}). T is found from Φ by Newton's method safeguarded by bisection. Convection and
//! the heat of the char's own oxidation are left out: an ember here only cools.
//!
//! Used by the plugin (an ember's temperature at the ray's time) and by `gen` (which ages the embers it emits),
//! so the two agree by construction.

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
}
