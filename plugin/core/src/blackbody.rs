//! Planck's law: absolute blackbody spectral radiance (Pegoraro & Parker 2006, eq. 6).
//!
//! B_λ(T) = 2 h c₀² / λ⁵ · 1 / (e^{h c₀ / (λ k T)} − 1), in W·m⁻²·sr⁻¹·nm⁻¹ at the API (W·m⁻³·sr⁻¹ in SI).
//! This is **absolute** radiance, not pbrt-v4's peak-normalised blackbody: a 1500 K blackbody has
//! ∫B_λ dλ = σT⁴/π = 9.137 × 10⁴ W·m⁻²·sr⁻¹.
//!
//! ## Stable evaluation
//! With x = h c₀ / (λ k T), 1/(eˣ − 1) is written e^{−x} / (−expm1(−x)): no overflow for large x (low T or
//! short λ), full precision for small x (high T or long λ). For x > [`X_CUTOFF`] the radiance is below
//! 10⁻²⁰⁰ W·m⁻²·sr⁻¹·nm⁻¹ and exactly 0 is returned, so no subnormal numbers reach the integrators.
//! T ≤ 0 (and NaN) gives exactly 0.
//!
//! ## Radiance in a medium of index n (the n² subtlety)
//! Pegoraro & Parker write eq. 6 with c = c₀/n. Read literally with λ the wavelength *in the medium* and the
//! radiance per unit in-medium wavelength, that is correct. Throughout this project spectra are indexed by the
//! **vacuum** wavelength (so that spectral bins do not move with n), and per unit vacuum wavelength the
//! equilibrium radiance in a medium is n² times the vacuum value: [`spectral_radiance_in_medium`].
//! Radiance divided by n² ("basic radiance") is what stays constant along a ray across index changes, so a
//! camera in air sees B_λ(T) of a hot gas in air up to n² ≈ 1 + 10⁻⁴. Flames have n − 1 < 3 × 10⁻⁴.

use crate::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT, STEFAN_BOLTZMANN};

/// First radiation constant for radiance, c₁ = 2 h c₀², W·m²·sr⁻¹.
pub const C1: f64 = 2.0 * PLANCK * SPEED_OF_LIGHT * SPEED_OF_LIGHT;
/// Second radiation constant, c₂ = h c₀ / k, m·K.
pub const C2: f64 = PLANCK * SPEED_OF_LIGHT / BOLTZMANN;
/// Wien's displacement constant b, m·K (CODATA 2018: 2.897 771 955 × 10⁻³).
pub const WIEN: f64 = 2.897_771_955e-3;
/// Above this x = c₂/(λT) the radiance is treated as exactly zero (e^{−500} ≈ 7 × 10⁻²¹⁸).
pub const X_CUTOFF: f64 = 500.0;

/// 1/(eˣ − 1) evaluated stably for x ≥ 0; 0 beyond [`X_CUTOFF`], +∞ at x = 0.
#[inline]
pub fn bose_einstein(x: f64) -> f64 {
    if x > X_CUTOFF {
        0.0
    } else if x >= 0.5 {
        // 1 − e^{−x} ≥ 0.39 here, so the subtraction loses under 1.3 ulp: one exponential, not two.
        let e = (-x).exp();
        e / (1.0 - e)
    } else {
        (-x).exp() / -(-x).exp_m1()
    }
}

/// Spectral radiance in SI units, W·m⁻³·sr⁻¹ (per metre of vacuum wavelength), at vacuum wavelength
/// `lambda_m` (m) and temperature `t_k` (K), in vacuum (n = 1).
#[inline]
pub fn spectral_radiance_si(t_k: f64, lambda_m: f64) -> f64 {
    // `!(t > 0)` also catches NaN.
    if !(t_k > 0.0) || !(lambda_m > 0.0) {
        return 0.0;
    }
    let x = C2 / (lambda_m * t_k);
    let b = bose_einstein(x);
    // (Far short of the peak e^−x underflows to 0 while λ⁵ may too: the radiance is 0, not 0 / 0.)
    if b == 0.0 {
        return 0.0;
    }
    let l5 = lambda_m * lambda_m * lambda_m * lambda_m * lambda_m;
    C1 / l5 * b
}

/// Spectral radiance B_λ(T), W·m⁻²·sr⁻¹·nm⁻¹, at vacuum wavelength `lambda_nm` (nm), in vacuum (n = 1).
#[inline]
pub fn spectral_radiance(t_k: f64, lambda_nm: f64) -> f64 {
    spectral_radiance_si(t_k, lambda_nm * 1e-9) * 1e-9
}

/// Equilibrium spectral radiance in a medium of refractive index `n`, per unit **vacuum** wavelength:
/// n² · B_λ(T), W·m⁻²·sr⁻¹·nm⁻¹. See the module documentation.
#[inline]
pub fn spectral_radiance_in_medium(t_k: f64, lambda_nm: f64, n: f64) -> f64 {
    n * n * spectral_radiance(t_k, lambda_nm)
}

/// Total (all-wavelength) radiance σT⁴/π, W·m⁻²·sr⁻¹.
pub fn total_radiance(t_k: f64) -> f64 {
    if !(t_k > 0.0) {
        return 0.0;
    }
    STEFAN_BOLTZMANN * t_k.powi(4) / std::f64::consts::PI
}

/// Wavelength of peak spectral radiance per unit wavelength, b/T, nm (Wien's displacement law).
pub fn wien_peak_nm(t_k: f64) -> f64 {
    WIEN / t_k * 1e9
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::gauss_legendre;
    use std::f64::consts::PI;

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn one_exponential_above_half_agrees_with_the_expm1_form() {
        // 1/(eˣ − 1) as e^{−x}/(1 − e^{−x}) for x ≥ 0.5 against e^{−x}/(−expm1(−x)) everywhere, across the
        // switch and up to the cutoff: within 4 ulp.
        let mut x = 1e-3;
        while x < X_CUTOFF {
            let half = 0.5f64.to_bits();
            for y in [x, f64::from_bits(half - 1), 0.5, f64::from_bits(half + 1)] {
                let want = (-y).exp() / -(-y).exp_m1();
                assert!(rel(bose_einstein(y), want) < 4.0 * f64::EPSILON, "x = {y}");
            }
            x *= 1.01;
        }
    }

    #[test]
    fn reference_values_from_shared_data() {
        // shared/data/README.md, W·m⁻³·sr⁻¹ (CODATA constants), quoted to 4 significant figures:
        // the comparison is at the quoted precision (half a unit in the last place ≤ 6e-4 relative)
        // and at 1e-4 where the quote carries 4 digits.
        let table = [
            (1000.0, [8.40e1, 1.031e4, 2.502e5]),
            (1500.0, [3.571e6, 6.312e7, 4.005e8]),
            (2000.0, [7.363e8, 4.939e9, 1.603e10]),
        ];
        for (t, row) in table {
            for (lambda_nm, want) in [450.0, 550.0, 650.0].into_iter().zip(row) {
                let got = spectral_radiance_si(t, lambda_nm * 1e-9);
                // Round the computed value to the quoted number of significant digits, then compare to 1e-4.
                let digits = if want == 8.40e1 { 3 } else { 4 };
                let scale = 10f64.powi(got.log10().floor() as i32 - (digits - 1));
                let rounded = (got / scale).round() * scale;
                assert!(
                    rel(rounded, want) < 1e-4,
                    "T={t} λ={lambda_nm}: {got:e} (rounded {rounded:e}) vs {want:e}"
                );
                assert!(
                    rel(got, want) < 0.5 * scale / want + 1e-12,
                    "T={t} λ={lambda_nm}: {got:e} vs {want:e}"
                );
            }
        }
        // Per-nm API is the SI value / 1e9.
        assert!(rel(spectral_radiance(1500.0, 550.0), 6.312e7 / 1e9) < 1e-3);
    }

    /// Fraction of σT⁴/π emitted at wavelengths above `lambda_m` — an independent closed form, from the
    /// series of t³/(eᵗ − 1) = t² − t³/2 + t⁴/12 − t⁶/720 + t⁸/30240 − … (valid for x = c₂/λT < 2π).
    fn long_tail_fraction(lambda_m: f64, t: f64) -> f64 {
        let x = C2 / (lambda_m * t);
        assert!(x < 1.0);
        let s = x.powi(3) / 3.0 - x.powi(4) / 8.0 + x.powi(5) / 60.0 - x.powi(7) / 5040.0
            + x.powi(9) / 272_160.0;
        15.0 / PI.powi(4) * s
    }

    /// Fraction emitted below `lambda_m`: (15/π⁴) Σₙ e^{−nx}/n (x³ + 3x²/n + 6x/n² + 6/n³), x large.
    fn short_tail_fraction(lambda_m: f64, t: f64) -> f64 {
        let x = C2 / (lambda_m * t);
        let mut s = 0.0;
        for n in 1..=50 {
            let n = n as f64;
            s += (-n * x).exp() / n
                * (x.powi(3) + 3.0 * x * x / n + 6.0 * x / (n * n) + 6.0 / n.powi(3));
        }
        15.0 / PI.powi(4) * s
    }

    #[test]
    fn integral_over_10nm_to_1mm_is_stefan_boltzmann() {
        // ∫B_λ dλ = σT⁴/π. The band 10 nm–1 mm misses a long-wave tail of (15/π⁴)(x³/3 − …) with
        // x = c₂/(1 mm · T): 1.21e-6 of the total at 500 K, 4.9e-8 at 1500 K. The quadrature over the band is
        // compared to σT⁴/π less both analytic tails, to 1e-6 relative; and to σT⁴/π itself to 1e-6 where the
        // tail allows (1500 K, 6000 K) and to 1.3e-6 at 500 K.
        for t in [500.0, 1500.0, 6000.0] {
            let (lo, hi) = (10e-9f64, 1e-3f64);
            // Substitute u = ln λ: ∫ B dλ = ∫ B(e^u) e^u du, 600 panels over 11.5 e-folds.
            let band = gauss_legendre(
                |u| {
                    let l = u.exp();
                    spectral_radiance_si(t, l) * l
                },
                lo.ln(),
                hi.ln(),
                600,
            );
            let total = total_radiance(t);
            let expected_band =
                total * (1.0 - long_tail_fraction(hi, t) - short_tail_fraction(lo, t));
            assert!(
                rel(band, expected_band) < 1e-6,
                "T={t}: band {band} vs {expected_band}"
            );
            let tol = if t == 500.0 { 1.3e-6 } else { 1e-6 };
            assert!(
                rel(band, total) < tol,
                "T={t}: band {band} vs σT⁴/π {total}"
            );
        }
        // The quoted value at 1500 K.
        assert!(rel(total_radiance(1500.0), 9.137490e4) < 1e-6);
    }

    #[test]
    fn wien_peak() {
        for t in [800.0, 1500.0, 3000.0, 6000.0] {
            // Golden-section search for the maximum of B_λ.
            let (mut a, mut b) = (0.5 * wien_peak_nm(t), 2.0 * wien_peak_nm(t));
            let g = (5f64.sqrt() - 1.0) / 2.0;
            for _ in 0..200 {
                let c = b - g * (b - a);
                let d = a + g * (b - a);
                if spectral_radiance(t, c) > spectral_radiance(t, d) {
                    b = d;
                } else {
                    a = c;
                }
            }
            let peak = 0.5 * (a + b);
            let want = 2.897772e-3 / t * 1e9;
            assert!(rel(peak, want) < 1e-3, "T={t}: {peak} nm vs {want} nm");
        }
    }

    #[test]
    fn stable_at_extremes() {
        assert_eq!(spectral_radiance(0.0, 550.0), 0.0);
        assert_eq!(spectral_radiance(-10.0, 550.0), 0.0);
        assert_eq!(spectral_radiance(f64::NAN, 550.0), 0.0);
        for t in [
            1e-300, 1e-3, 1.0, 10.0, 100.0, 300.0, 1e3, 1e4, 1e5, 1e6, 1e9,
        ] {
            for l in [300.0, 380.0, 550.0, 780.0, 1000.0] {
                let b = spectral_radiance(t, l);
                assert!(b.is_finite() && b >= 0.0, "T={t} λ={l}: {b}");
                // Either exactly zero or a normal number: no subnormal storms downstream.
                assert!(b == 0.0 || b.is_normal(), "T={t} λ={l}: subnormal {b:e}");
            }
        }
        // Rayleigh–Jeans limit at high T: B → 2 c k T / λ⁴ (x = 1.4e-5 at 1e9 K, 1000 nm).
        let (t, l) = (1e9f64, 1000e-9f64);
        let rj = 2.0 * SPEED_OF_LIGHT * BOLTZMANN * t / l.powi(4);
        assert!(rel(spectral_radiance_si(t, l), rj) < 1e-4);
        // Monotone in T at fixed λ.
        let mut prev = 0.0;
        for i in 0..2000 {
            let b = spectral_radiance(1.0 + i as f64 * 5.0, 450.0);
            assert!(b >= prev);
            prev = b;
        }
    }

    #[test]
    fn medium_index_scales_by_n_squared() {
        // Planck's law written inside the medium — light speed c/n, the wavelength there λ/n, per unit of that
        // wavelength — then carried to a density per unit vacuum wavelength (dλ = n dλ_medium): derived from the
        // constants here, not from the function under test. n = 1.5 (glass) makes the factor unmistakable.
        use crate::constants::{BOLTZMANN as K, PLANCK as H, SPEED_OF_LIGHT as C};
        for (t, l_nm, n) in [
            (1800.0, 600.0, 1.0003),
            (2500.0, 450.0, 1.5),
            (900.0, 1000.0, 1.33),
        ] {
            let (cm, lm) = (C / n, l_nm * 1e-9 / n);
            let per_medium_m =
                2.0 * H * cm * cm / lm.powi(5) / ((H * cm / (lm * K * t)).exp() - 1.0);
            let per_vacuum_nm = per_medium_m / n * 1e-9;
            let got = spectral_radiance_in_medium(t, l_nm, n);
            assert!(
                rel(got, per_vacuum_nm) < 1e-12,
                "T {t} λ {l_nm} n {n}: {got} vs {per_vacuum_nm}"
            );
        }
        assert_eq!(
            spectral_radiance_in_medium(1800.0, 600.0, 1.0),
            spectral_radiance(1800.0, 600.0)
        );
    }
}
