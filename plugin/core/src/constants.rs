//! Physical constants, CODATA 2018 (exact SI defining constants where they are defined).
//!
//! Every other module takes its constants from here, so that a change of convention happens in one place.

/// Planck constant h, J·s (exact, SI 2019).
pub const PLANCK: f64 = 6.626_070_15e-34;
/// Speed of light in vacuum c₀, m/s (exact).
pub const SPEED_OF_LIGHT: f64 = 299_792_458.0;
/// Boltzmann constant k_B, J/K (exact, SI 2019).
pub const BOLTZMANN: f64 = 1.380_649e-23;
/// Avogadro constant N_A, 1/mol (exact, SI 2019).
pub const AVOGADRO: f64 = 6.022_140_76e23;
/// Elementary charge e, C (exact): also joules per electronvolt.
pub const ELEMENTARY_CHARGE: f64 = 1.602_176_634e-19;
/// Stefan–Boltzmann constant σ = 2π⁵k⁴ / (15 h³ c₀²), W·m⁻²·K⁻⁴ (CODATA 2018: 5.670 374 419 × 10⁻⁸).
pub const STEFAN_BOLTZMANN: f64 = 5.670_374_419e-8;
/// Molar gas constant R = N_A k_B, J·mol⁻¹·K⁻¹.
pub const GAS_CONSTANT: f64 = AVOGADRO * BOLTZMANN;
/// Luminous efficacy of 540 THz radiation used to turn CIE-weighted radiance into luminance, lm/W.
/// With ȳ peaking at 1 near 555 nm this is the conventional 683 lm/W of the photometric definitions.
pub const LUMINOUS_EFFICACY: f64 = 683.0;
/// Energy of one wavenumber unit, J per cm⁻¹ (h c₀ · 100 m⁻¹).
pub const JOULES_PER_WAVENUMBER: f64 = PLANCK * SPEED_OF_LIGHT * 100.0;

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn stefan_boltzmann_follows_from_h_c_k() {
        // σ = 2π⁵k⁴ / (15 h³ c²): CODATA 2018 lists 5.670 374 419... × 10⁻⁸ as exact.
        let sigma =
            2.0 * PI.powi(5) * BOLTZMANN.powi(4) / (15.0 * PLANCK.powi(3) * SPEED_OF_LIGHT.powi(2));
        assert!((sigma / STEFAN_BOLTZMANN - 1.0).abs() < 1e-9, "{sigma}");
    }

    #[test]
    fn gas_constant_is_codata() {
        // CODATA 2018: R = 8.314 462 618... J/(mol K).
        assert!((GAS_CONSTANT - 8.314_462_618).abs() < 1e-8);
    }
}
