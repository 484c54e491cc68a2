//! Refractive index of air (Ciddor 1996, *Refractive index of air: new equations for the visible and near
//! infrared*, Appl. Opt. 35(9), Appendix A), for P&P section 3.7 (hot air bends light).
//!
//! Inputs: vacuum wavelength λ (nm; σ = 1/λ in µm⁻¹), temperature T (K), pressure p (Pa), relative humidity h
//! (fraction 0–1), CO₂ mole fraction x_c (ppm). Output: n − 1 (dimensionless).
//!
//! The steps follow Ciddor's Appendix A (not the thesis's transcription, which drops the a₂t² term of the
//! compressibility, writes w₁ for w₂ in the water dispersion, and quotes Z_a at the wrong conditions): Davis's
//! saturation vapour pressure (T in K) and enhancement factor (t in °C) give the water mole fraction x_w; the
//! dry-air and water-vapour refractivities at their reference conditions are scaled by the densities of the
//! actual components (BIPM 1981/91 equation of state, compressibility Z).
//!
//! ## Outside the fitted range (flames)
//! Ciddor's fit covers −40…100 °C. Above 100 °C (and below −40 °C) the polynomial compressibility and Davis's
//! vapour pressure are not valid; the refractivity is evaluated at the nearest edge T_e of the range and
//! carried by the ideal-gas density scaling (n − 1)(T) = (n − 1)(T_e) · T_e / T at fixed p and composition
//! (Gladstone–Dale: refractivity ∝ density). So at 1500 K, n − 1 ≈ 5 × 10⁻⁵, (288/1500) of its 15 °C value.
//! The relative humidity is taken at T_e (at 100 °C saturation equals one atmosphere, so h is then roughly
//! the water mole fraction); use [`refractivity_mole_fraction`] to give x_w directly. T below 1 K is treated
//! as 1 K. Results are finite and positive for every input in the documented domains.

/// Ciddor's constant set (Appendix A). R is the 1996 value Ciddor used, kept so the published numbers
/// reproduce to the last digit.
mod k {
    pub const W: [f64; 4] = [295.235, 2.6422, -0.032380, 0.004028];
    pub const K0: f64 = 238.0185;
    pub const K1: f64 = 5_792_105.0;
    pub const K2: f64 = 57.362;
    pub const K3: f64 = 167_917.0;
    pub const A0: f64 = 1.58123e-6;
    pub const A1: f64 = -2.9331e-8;
    pub const A2: f64 = 1.1043e-10;
    pub const B0: f64 = 5.707e-6;
    pub const B1: f64 = -2.051e-8;
    pub const C0: f64 = 1.9898e-4;
    pub const C1: f64 = -2.376e-6;
    pub const D: f64 = 1.83e-11;
    pub const E: f64 = -0.765e-8;
    pub const P_R1: f64 = 101_325.0;
    pub const T_R1: f64 = 288.15;
    /// Compressibility of dry air at 15 °C, 101 325 Pa (eq. for Z with x_w = 0).
    pub const Z_A: f64 = 0.9995922115;
    /// Density of pure water vapour at 20 °C, 1333 Pa, kg/m³.
    pub const RHO_VS: f64 = 0.00985938;
    pub const R: f64 = 8.314510;
    pub const M_V: f64 = 0.018015;
    // Davis 1992 saturation vapour pressure, T in K.
    pub const SVP: [f64; 4] = [1.2378847e-5, -1.9121316e-2, 33.93711047, -6.3431645e3];
    // Enhancement factor f = α + β p + γ t², t in °C.
    pub const F: [f64; 3] = [1.00062, 3.14e-8, 5.6e-7];
}

/// Lower and upper temperature of Ciddor's fit, K (−40 °C, 100 °C).
pub const FIT_RANGE_K: (f64, f64) = (233.15, 373.15);

/// Air composition and state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Air {
    /// Temperature, K.
    pub temperature_k: f64,
    /// Total pressure, Pa.
    pub pressure_pa: f64,
    /// Relative humidity, fraction 0–1.
    pub relative_humidity: f64,
    /// CO₂ mole fraction, ppm.
    pub co2_ppm: f64,
}

impl Air {
    /// Standard air of the wavelength tables: 15 °C, 101 325 Pa, dry, 450 ppm CO₂.
    pub const STANDARD: Air = Air {
        temperature_k: 288.15,
        pressure_pa: 101_325.0,
        relative_humidity: 0.0,
        co2_ppm: 450.0,
    };
}

/// Compressibility Z (BIPM equation of state) at T (K), p (Pa), water mole fraction x_w.
pub fn compressibility(t_k: f64, p: f64, xw: f64) -> f64 {
    let t = t_k - 273.15;
    let pt = p / t_k;
    1.0 - pt
        * (k::A0
            + k::A1 * t
            + k::A2 * t * t
            + (k::B0 + k::B1 * t) * xw
            + (k::C0 + k::C1 * t) * xw * xw)
        + pt * pt * (k::D + k::E * xw * xw)
}

/// Saturation vapour pressure of water over liquid (Davis 1992), Pa, at T (K) within the fit range.
pub fn saturation_vapour_pressure(t_k: f64) -> f64 {
    let [a, b, c, d] = k::SVP;
    (a * t_k * t_k + b * t_k + c + d / t_k).exp()
}

/// Water-vapour mole fraction x_w for relative humidity `h` (0–1) at T (K, within the fit range) and p (Pa).
pub fn water_mole_fraction(t_k: f64, p: f64, h: f64) -> f64 {
    let t = t_k - 273.15;
    let [alpha, beta, gamma] = k::F;
    let f = alpha + beta * p + gamma * t * t;
    f * h * saturation_vapour_pressure(t_k) / p
}

/// n − 1 of air by Ciddor's Appendix A, at vacuum wavelength `lambda_nm`, with the water given as a mole
/// fraction `xw`; T outside [`FIT_RANGE_K`] is carried by the ideal-gas scaling (module docs).
pub fn refractivity_mole_fraction(lambda_nm: f64, t_k: f64, p: f64, xw: f64, co2_ppm: f64) -> f64 {
    let t_k = if t_k >= 1.0 { t_k } else { 1.0 };
    let t_e = t_k.clamp(FIT_RANGE_K.0, FIT_RANGE_K.1);
    refractivity_in_range(lambda_nm, t_e, p, xw, co2_ppm) * (t_e / t_k)
}

fn refractivity_in_range(lambda_nm: f64, t_k: f64, p: f64, xw: f64, xc: f64) -> f64 {
    let sigma = 1e3 / lambda_nm; // µm⁻¹
    let s = sigma * sigma;
    // Standard dry air (15 °C, 101 325 Pa, 450 ppm CO₂) and standard water vapour refractivities.
    let n_as = 1e-8 * (k::K1 / (k::K0 - s) + k::K3 / (k::K2 - s));
    let [w0, w1, w2, w3] = k::W;
    let n_ws = 1.022e-8 * (w0 + w1 * s + w2 * s * s + w3 * s * s * s);
    let m_a = 1e-3 * (28.9635 + 12.011e-6 * (xc - 400.0));
    let n_axs = n_as * (1.0 + 0.534e-6 * (xc - 450.0));
    let z_m = compressibility(t_k, p, xw);
    let rho_axs = k::P_R1 * m_a / (k::Z_A * k::R * k::T_R1);
    let rho_v = xw * p * k::M_V / (z_m * k::R * t_k);
    let rho_a = (1.0 - xw) * p * m_a / (z_m * k::R * t_k);
    rho_a / rho_axs * n_axs + rho_v / k::RHO_VS * n_ws
}

/// n − 1 of air at vacuum wavelength `lambda_nm` (nm) for the given air (Ciddor 1996; module docs for flames).
pub fn refractivity(lambda_nm: f64, air: &Air) -> f64 {
    let t_e = air.temperature_k.clamp(FIT_RANGE_K.0, FIT_RANGE_K.1);
    let t_e = if t_e.is_nan() { FIT_RANGE_K.0 } else { t_e };
    let xw = water_mole_fraction(t_e, air.pressure_pa, air.relative_humidity).clamp(0.0, 1.0);
    refractivity_mole_fraction(
        lambda_nm,
        air.temperature_k,
        air.pressure_pa,
        xw,
        air.co2_ppm,
    )
}

/// The index n of air (1 + [`refractivity`]).
pub fn index(lambda_nm: f64, air: &Air) -> f64 {
    1.0 + refractivity(lambda_nm, air)
}

/// Vacuum wavelength (nm) of a line tabulated at air wavelength `lambda_air_nm` in standard air
/// (NIST ASD lists air wavelengths between 200 and 2000 nm).
pub fn air_to_vacuum_nm(lambda_air_nm: f64) -> f64 {
    // n depends on λ_vac only weakly (dn/dλ ≈ 3e-8 per nm): one fixed-point step is exact to < 1e-12 nm.
    let first = lambda_air_nm * index(lambda_air_nm, &Air::STANDARD);
    lambda_air_nm * index(first, &Air::STANDARD)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn air(t_c: f64, rh: f64) -> Air {
        Air {
            temperature_k: t_c + 273.15,
            pressure_pa: 101_325.0,
            relative_humidity: rh,
            co2_ppm: 450.0,
        }
    }

    #[test]
    fn ciddor_reference_values() {
        // shared/data/README.md (Ciddor 1996 Appendix A values), to 1e-9 absolute in n − 1.
        for (l, t, rh, want) in [
            (633.0, 20.0, 0.0, 2.717998e-4),
            (633.0, 20.0, 0.5, 2.713727e-4),
            (589.0, 20.0, 0.0, 2.724110e-4),
            (632.8, 15.0, 0.0, 2.765327e-4),
        ] {
            let got = refractivity(l, &air(t, rh));
            assert!(
                (got - want).abs() < 1e-9,
                "λ={l} t={t} RH={rh}: {got:e} vs {want:e}"
            );
        }
    }

    #[test]
    fn ciddor_intermediates() {
        // Z_a and ρ_vs follow from the compressibility formula (Ciddor: 0.9995922115, 0.00985938 kg/m³).
        assert!((compressibility(288.15, 101_325.0, 0.0) - 0.9995922115).abs() < 1e-10);
        let rho_vs = 1333.0 * k::M_V / (compressibility(293.15, 1333.0, 1.0) * k::R * 293.15);
        assert!((rho_vs - 0.00985938).abs() < 1e-8, "{rho_vs}");
    }

    #[test]
    fn decreases_with_temperature_and_stays_finite() {
        let mut prev = f64::INFINITY;
        let mut t = 250.0;
        while t <= 4000.0 {
            let a = Air {
                temperature_k: t,
                ..Air::STANDARD
            };
            let r = refractivity(550.0, &a);
            assert!(
                r.is_finite() && r > 0.0 && r < prev,
                "T={t}: {r} (prev {prev})"
            );
            prev = r;
            t += 5.0;
        }
        // And with humidity too.
        let mut prev = f64::INFINITY;
        for i in 0..=300 {
            let a = Air {
                temperature_k: 250.0 + 12.5 * i as f64,
                relative_humidity: 0.5,
                ..Air::STANDARD
            };
            let r = refractivity(550.0, &a);
            assert!(r.is_finite() && r > 0.0 && r < prev, "{a:?}: {r}");
            prev = r;
        }
    }

    #[test]
    fn flame_temperature_is_ideal_gas_scaled() {
        // n − 1 at 1500 K ≈ (288/1500) of its 288 K value (ideal gas); the compressibility at 288 K and the
        // carry from 373 K differ from the pure ratio by less than 1e-3 relative.
        let cold = refractivity(550.0, &Air::STANDARD);
        let hot = refractivity(
            550.0,
            &Air {
                temperature_k: 1500.0,
                ..Air::STANDARD
            },
        );
        let ratio = hot / cold;
        assert!((ratio / (288.15 / 1500.0) - 1.0).abs() < 1e-3, "{ratio}");
        assert!((hot - 5.3e-5).abs() < 0.3e-5, "{hot:e}");
        // Continuous at the fit edge.
        let below = refractivity(
            550.0,
            &Air {
                temperature_k: 373.15 - 1e-9,
                ..Air::STANDARD
            },
        );
        let above = refractivity(
            550.0,
            &Air {
                temperature_k: 373.15 + 1e-9,
                ..Air::STANDARD
            },
        );
        // d(n−1)/dT ≈ −7e-7 K⁻¹, so 2e-9 K apart the values differ by ~1.5e-15.
        assert!((below - above).abs() < 1e-13);
    }

    #[test]
    fn degenerate_inputs_are_finite() {
        for t in [0.0, -5.0, f64::NAN, 1e-9, 1e6] {
            let r = refractivity(
                550.0,
                &Air {
                    temperature_k: t,
                    ..Air::STANDARD
                },
            );
            assert!(r.is_finite() && r > 0.0, "T={t}: {r}");
        }
    }

    #[test]
    fn air_to_vacuum_sodium_d() {
        // NIST: Na D2 588.995 nm air ↔ 589.158 nm vacuum.
        let v = air_to_vacuum_nm(588.995);
        assert!((v - 589.158).abs() < 1e-3, "{v}");
    }
}
