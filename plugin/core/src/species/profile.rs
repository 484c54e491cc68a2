//! Line shapes: the Voigt profile of an atomic line in a flame — thermal Doppler broadening convolved with
//! collisional (pressure) broadening.
//!
//! - **Doppler** (Gaussian): standard deviation in wavelength σ_D = λ₀ √(kT / (m c₀²)) with m the atom's mass
//!   (FWHM 2√(2 ln 2) σ_D; Na D at 2000 K: 3.93 pm).
//! - **Collisional** (Lorentzian): half width at half maximum γ. Flame gases (N₂, H₂O, CO₂) broaden the
//!   resonance lines of the alkali and alkaline-earth metals by van der Waals collisions; impact theory gives a
//!   width ∝ p · T^{−0.7} (number density of perturbers ∝ p/T, relative speed^{3/5} ∝ T^{0.3}). firemedium takes
//!   a full width of [`LORENTZ_FWHM_CM1`] = 0.08 cm⁻¹ at 2500 K and 1 atm for every line — **a documented
//!   estimate**: it puts the Voigt damping a = √ln2 · γ_L/γ_D of Na D at 0.50 at 2500 K, inside the 0.4–0.8
//!   measured in atmospheric flames (Alkemade, Hollander, Snelleman & Zeegers, *Metal Vapours in Flames*, 1982,
//!   ch. 6), and a hosting scene can scale it (`linebroadening`).
//! - **Voigt**: φ(Δλ) = Re w(z) / (σ_D √(2π)), z = (Δλ + iγ) / (σ_D √2), with w the Faddeeva function by
//!   Humlíček's four-region rational approximation (J. Quant. Spectrosc. Radiat. Transfer 27, 437, 1982;
//!   relative error < 1e-4). φ is normalised: ∫ φ dλ = 1 (per nm here).
//!
//! Natural broadening (A_ki/4π: 1.6e-5 nm for Na D) is four hundred times below the collisional width and is
//! left out.

use crate::constants::{BOLTZMANN, SPEED_OF_LIGHT};

/// Atomic mass constant, kg (CODATA 2018).
pub const ATOMIC_MASS_UNIT: f64 = 1.660_539_066_60e-27;

/// Collisional full width at half maximum in wavenumbers at [`LORENTZ_T0`] and 1 atm (see the module notes).
pub const LORENTZ_FWHM_CM1: f64 = 0.08;
/// The temperature of [`LORENTZ_FWHM_CM1`], K.
pub const LORENTZ_T0: f64 = 2500.0;

/// Standard atomic weights (IUPAC 2021) of the elements with shipped lines, u.
pub fn atomic_mass_u(symbol: &str) -> Option<f64> {
    Some(match symbol {
        "Li" => 6.94,
        "Na" => 22.990,
        "K" => 39.098,
        "Ca" => 40.078,
        "Sr" => 87.62,
        "Ba" => 137.33,
        "Cu" => 63.546,
        _ => return None,
    })
}

/// Doppler standard deviation in wavelength (nm) of a line at `lambda_nm` from atoms of `mass_u` at `t_k`
/// (T below 1 K acts as 1 K).
pub fn doppler_sigma_nm(lambda_nm: f64, t_k: f64, mass_u: f64) -> f64 {
    let t = if t_k > 1.0 { t_k.min(1e7) } else { 1.0 };
    lambda_nm * (BOLTZMANN * t / (mass_u * ATOMIC_MASS_UNIT)).sqrt() / SPEED_OF_LIGHT
}

/// Collisional half width at half maximum (nm) of a line at `lambda_nm` and `t_k`, at 1 atm, with the full
/// width `fwhm_cm1` at [`LORENTZ_T0`]: γ = ½ λ² Δν̃ (T₀/T)^0.7 (T clamped to 300 K–10⁵ K, where the flame-gas
/// estimate stops meaning anything).
pub fn lorentz_hwhm_nm(lambda_nm: f64, t_k: f64, fwhm_cm1: f64) -> f64 {
    let t = if t_k > 300.0 { t_k.min(1e5) } else { 300.0 };
    0.5 * lambda_nm * lambda_nm * 1e-7 * fwhm_cm1.max(0.0) * (LORENTZ_T0 / t).powf(0.7)
}

/// The Faddeeva function's real part Re w(x + iy) for y ≥ 0 (Humlíček 1982, region by region).
pub fn faddeeva_re(x: f64, y: f64) -> f64 {
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    impl C {
        fn add(self, o: C) -> C {
            C(self.0 + o.0, self.1 + o.1)
        }
        fn mul(self, o: C) -> C {
            C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
        }
        fn div(self, o: C) -> C {
            let d = o.0 * o.0 + o.1 * o.1;
            C(
                (self.0 * o.0 + self.1 * o.1) / d,
                (self.1 * o.0 - self.0 * o.1) / d,
            )
        }
        fn r(v: f64) -> C {
            C(v, 0.0)
        }
        /// A polynomial Σ c_i uⁱ (coefficients from the constant term up), by Horner.
        fn poly(u: C, c: &[f64]) -> C {
            c.iter()
                .rev()
                .fold(C::r(0.0), |acc, &k| acc.mul(u).add(C::r(k)))
        }
    }
    if !(x.is_finite() && y.is_finite()) {
        return 0.0;
    }
    let y = y.max(0.0);
    let t = C(y, -x);
    let s = x.abs() + y;
    let w = if s >= 15.0 {
        t.mul(C::r(0.564_189_6)).div(C::r(0.5).add(t.mul(t)))
    } else if s >= 5.5 {
        let u = t.mul(t);
        t.mul(C::poly(u, &[1.410_474, 0.564_189_6]))
            .div(C::poly(u, &[0.75, 3.0, 1.0]))
    } else if y >= 0.195 * x.abs() - 0.176 {
        C::poly(t, &[16.4955, 20.20933, 11.96482, 3.778987, 0.564_223_6]).div(C::poly(
            t,
            &[16.4955, 38.82363, 39.27121, 21.69274, 6.699398, 1.0],
        ))
    } else {
        let u = t.mul(t);
        let e = u.0.exp();
        let ex = C(e * u.1.cos(), e * u.1.sin());
        let num = C::poly(
            u,
            &[
                36183.31, -3321.9905, 1540.787, -219.0313, 35.76683, -1.320522, 0.56419,
            ],
        );
        let den = C::poly(
            u,
            &[
                32066.6, -24322.84, 9022.228, -2186.181, 364.2191, -61.57037, 1.841439, -1.0,
            ],
        );
        let q = t.mul(num).div(den);
        C(ex.0 - q.0, ex.1 - q.1)
    };
    w.0.max(0.0)
}

/// The Voigt profile (per nm; ∫ φ dλ = 1) at `offset_nm` from the line centre, for Doppler standard deviation
/// `sigma_nm` and collisional half width `gamma_nm`. A pure Gaussian for γ = 0, a pure Lorentzian for σ → 0.
pub fn voigt_nm(offset_nm: f64, sigma_nm: f64, gamma_nm: f64) -> f64 {
    let g = gamma_nm.max(0.0);
    if !(sigma_nm > 1e-12 * g.max(1e-300)) {
        return g / (std::f64::consts::PI * (offset_nm * offset_nm + g * g)).max(1e-300);
    }
    let k = sigma_nm * std::f64::consts::SQRT_2;
    faddeeva_re(offset_nm / k, g / k) / (sigma_nm * (2.0 * std::f64::consts::PI).sqrt())
}

/// The profile of a line of an atom of `mass_u` at `lambda_nm` and `t_k`, at `offset_nm` (per nm), with the
/// collisional width `fwhm_cm1` at [`LORENTZ_T0`].
pub fn line_profile_nm(
    offset_nm: f64,
    lambda_nm: f64,
    t_k: f64,
    mass_u: f64,
    fwhm_cm1: f64,
) -> f64 {
    voigt_nm(
        offset_nm,
        doppler_sigma_nm(lambda_nm, t_k, mass_u),
        lorentz_hwhm_nm(lambda_nm, t_k, fwhm_cm1),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn faddeeva_limits_match_closed_forms() {
        // y = 0: Re w(x) = e^{−x²} (the Gaussian), every region.
        for x in [0.0, 0.3, 1.0, 2.0, 3.5, 5.0, 8.0] {
            let w = faddeeva_re(x, 0.0);
            let want = (-x * x).exp();
            assert!(
                (w - want).abs() < 2e-4 * want.max(1e-3),
                "x {x}: {w} vs {want}"
            );
        }
        // x = 0: Re w(iy) = e^{y²} erfc(y) — tabulated values (Abramowitz & Stegun 7.1).
        for (y, want) in [(0.5, 0.615_690_1), (1.0, 0.427_583_9), (2.0, 0.255_395_7)] {
            let w = faddeeva_re(0.0, y);
            assert!((w / want - 1.0).abs() < 1e-4, "y {y}: {w} vs {want}");
        }
        // Far wing: Re w → y / (√π (x² + y²)) (the Lorentzian).
        let (x, y) = (40.0, 0.5);
        let want = y / (PI.sqrt() * (x * x + y * y));
        assert!((faddeeva_re(x, y) / want - 1.0).abs() < 1e-3);
    }

    #[test]
    fn voigt_is_normalised_and_has_the_right_widths() {
        // Na D2 at 2000 K: Doppler FWHM 3.93 pm (2√(2 ln 2) σ).
        let s = doppler_sigma_nm(589.158, 2000.0, 22.990);
        assert!(
            (2.0 * (2.0 * 2f64.ln()).sqrt() * s / 3.93e-3 - 1.0).abs() < 0.01,
            "{s}"
        );
        // The damping of Na D at 2500 K: a = √ln2 γ_L / γ_D ≈ 0.50.
        let (sd, g) = (
            doppler_sigma_nm(589.158, 2500.0, 22.990),
            lorentz_hwhm_nm(589.158, 2500.0, LORENTZ_FWHM_CM1),
        );
        let a = 2f64.ln().sqrt() * g / ((2.0 * 2f64.ln()).sqrt() * sd);
        assert!((a - 0.50).abs() < 0.03, "a = {a}");
        // ∫ φ dλ = 1, on a log grid out to 1e4 widths plus the Lorentzian tail beyond (2γ/πX).
        let x_max = 1e4 * (sd + g);
        let n = 200_000;
        let (lo, hi) = ((1e-4 * sd).ln(), x_max.ln());
        let mut sum = voigt_nm(0.0, sd, g) * 1e-4 * sd;
        for i in 0..n {
            let u = lo + (i as f64 + 0.5) * (hi - lo) / n as f64;
            let x = u.exp();
            sum += voigt_nm(x, sd, g) * x * (hi - lo) / n as f64;
        }
        let total = 2.0 * sum - voigt_nm(0.0, sd, g) * 1e-4 * sd + 2.0 * g / (PI * x_max);
        assert!((total - 1.0).abs() < 1e-3, "∫φ = {total}");
        // The peak of a pure Doppler line: 1/(σ√(2π)).
        assert!((voigt_nm(0.0, sd, 0.0) * sd * (2.0 * PI).sqrt() - 1.0).abs() < 1e-4);
        // Pure Lorentzian: 1/(πγ).
        assert!((voigt_nm(0.0, 0.0, g) * PI * g - 1.0).abs() < 1e-12);
    }

    #[test]
    fn widths_are_finite_at_any_temperature() {
        for t in [f64::NAN, -5.0, 0.0, 1.0, 300.0, 1e5, 1e9, f64::INFINITY] {
            let s = doppler_sigma_nm(589.0, t, 22.99);
            let g = lorentz_hwhm_nm(589.0, t, LORENTZ_FWHM_CM1);
            let p = line_profile_nm(0.01, 589.0, t, 22.99, LORENTZ_FWHM_CM1);
            assert!(
                s > 0.0 && s.is_finite() && g > 0.0 && g.is_finite() && p.is_finite(),
                "T {t}"
            );
        }
    }
}
