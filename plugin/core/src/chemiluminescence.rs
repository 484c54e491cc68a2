//! The blue core: chemiluminescence of a hydrocarbon flame's reaction zone (Selle, *Rendering the Blue Core*,
//! rendered it as an emissive shell; here it is the light the excited radicals CH* and C₂* emit where the fuel
//! reacts, in proportion to the heat release rate).
//!
//! The spectrum is a sum of four bands, each normalised to unit area and weighted by its share of the emitted
//! power:
//!
//! | band | head (nm) | shape | share |
//! |---|---|---|---|
//! | CH* A²Δ → X²Π (0,0) | 431.4 | Gaussian, σ = 1.5 nm (its rotational envelope at flame temperatures, 425–437 nm) | 0.50 |
//! | C₂* Swan d³Π → a³Π, Δv = +1 | 473.7 | shaded to the violet: e^(−(head − λ)/w) below the head, w = 5 nm | 0.12 |
//! | C₂* Swan, Δv = 0 | 516.5 | the same | 0.30 |
//! | C₂* Swan, Δv = −1 | 563.6 | the same | 0.08 |
//!
//! Band heads from Pearse & Gaydon, *The Identification of Molecular Spectra* (4th ed., 1976); the Swan bands
//! are degraded to the violet (Gaydon, *The Spectroscopy of Flames*, 2nd ed., 1974, ch. 6). The shares are an
//! estimate for a near-stoichiometric methane–air flame (a C₂*/CH* band ratio near 1: Kojima, Ikeda & Nakajima,
//! *Combust. Flame* 140, 2005, measured 0.5–1.5 over the equivalence ratios that burn blue); leaner flames have
//! less C₂*. The emitted power is a fraction of the heat release rate (the chemiluminescence yield, ~1e-5–1e-4
//! for CH*: Hardalupas & Orain, *Combust. Flame* 139, 2004), a parameter of the volume.

use std::f64::consts::PI;

/// (head nm, share) of the three Swan sequences (Δv = +1, 0, −1).
const SWAN: [(f64, f64); 3] = [(473.7, 0.12), (516.5, 0.30), (563.6, 0.08)];
/// CH*'s band: centre, σ (nm), share.
const CH: (f64, f64, f64) = (431.4, 1.5, 0.50);
/// The Swan bands' violet shading length, nm.
const SWAN_W: f64 = 5.0;

/// The normalised spectrum of the reaction zone's light, nm⁻¹: ∫ S(λ) dλ = 1 over all wavelengths.
pub fn spectrum(lambda_nm: f64) -> f64 {
    if !lambda_nm.is_finite() {
        return 0.0;
    }
    let (c, s, share) = CH;
    let ch = share * (-0.5 * ((lambda_nm - c) / s).powi(2)).exp() / (s * (2.0 * PI).sqrt());
    let swan: f64 = SWAN
        .iter()
        .filter(|(head, _)| lambda_nm <= *head)
        .map(|(head, share)| share * (-(head - lambda_nm) / SWAN_W).exp() / SWAN_W)
        .sum();
    ch + swan
}

/// The bands' shares, for reports: (name, head nm, share of the power).
pub fn bands() -> [(&'static str, f64, f64); 4] {
    [
        ("CH* (0,0)", CH.0, CH.2),
        ("C2* Swan +1", SWAN[0].0, SWAN[0].1),
        ("C2* Swan 0", SWAN[1].0, SWAN[1].1),
        ("C2* Swan -1", SWAN[2].0, SWAN[2].1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_spectrum_has_unit_area_and_its_bands_where_the_tables_put_them() {
        // Midpoints by 0.01 nm over 300–700 nm: the whole area, and each band's share around its head.
        let area = |a: f64, b: f64| {
            let n = ((b - a) / 0.01) as usize;
            (0..n)
                .map(|i| spectrum(a + (i as f64 + 0.5) * 0.01))
                .sum::<f64>()
                * 0.01
        };
        assert!(
            (area(300.0, 700.0) - 1.0).abs() < 1e-6,
            "{}",
            area(300.0, 700.0)
        );
        assert!((area(420.0, 443.0) - 0.50).abs() < 1e-3);
        assert!((area(440.0, 473.7) - 0.12).abs() < 1e-3);
        assert!((area(474.0, 516.5) - 0.30).abs() < 2e-3);
        assert!((area(517.0, 563.6) - 0.08).abs() < 1e-3);
        // The peaks: CH* at its centre, each Swan band at its head and nothing just above it (degraded to the
        // violet).
        assert!(spectrum(431.4) > spectrum(429.0) && spectrum(431.4) > spectrum(433.5));
        assert!(spectrum(516.5) > 10.0 * spectrum(516.6));
        assert_eq!(spectrum(f64::NAN), 0.0);
        let sum: f64 = bands().iter().map(|b| b.2).sum();
        assert!((sum - 1.0).abs() < 1e-12);
    }
}
