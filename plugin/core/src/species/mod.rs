//! Atomic emission and absorption lines (Pegoraro & Parker 2006, eq. 7–12), from NIST data, in LTE; and the molecular
//! bands the flame-colouring metals form ([`bands`]).
//!
//! For a line from an upper level k (energy E_k, weight g_k) to a lower level i (E_i) at vacuum wavelength λ,
//! with Einstein coefficient A_ki, number density N (m⁻³) of the element and line shape φ (m⁻¹):
//!
//! - Boltzmann populations (eq. 10): N_k / N = g_k e^{−E_k/kT} / Z(T).
//! - Emission (eq. 7): j = (h c₀ / (4π λ)) N_k A_ki φ, W·m⁻³·sr⁻¹ per metre of wavelength.
//! - Absorption (eq. 12, corrected for stimulated emission): σ_a = (λ⁴ A_ki φ / (8π c₀)) N_k (e^x − 1), with
//!   x = h c₀ / (λ k T). Eq. 12 multiplies an underflow (N_k at low T) by an overflow (eˣ); with
//!   E_i = E_k − h c₀/λ it is evaluated as (λ⁴ A_ki φ / (8π c₀)) · N g_k e^{−E_i/kT} (1 − e^{−x}) / Z, in log
//!   space, which never overflows.
//! - Kirchhoff: j = σ_a B_λ(T) holds identically (shared/data/README.md), to rounding.
//!
//! Lines are binned with φ = 1/Δλ of the bin holding the line's vacuum wavelength (the thesis's choice), right
//! while a line is optically thin; [`profile`] gives their true shape (Voigt), which the fire volume integrates
//! where a line can become thick.
//!
//! ## Partition function
//! Z(T) = Σ_j g_j e^{−E_j/kT} by a **direct sum over the levels this table ships**: the ground level plus every
//! upper level of a shipped line, plus each lower level whose weight is known. At flame temperatures
//! (1500–3000 K) this agrees with the de Galan polynomials to better than 1 % for Na, Li, K, Ca, Sr, Ba and Cu
//! (tested); it is exact in the low-T limit (Z → g₀) and finite at any T (bounded by Σ g_j), where polynomial
//! fits would leave their range. Above ≈ 5000 K neutral atoms ionise and the sum underestimates Z.
//!
//! ## Data
//! [`line_table`]: NIST ASD 5.5.6 neutral-atom lines, 300–1000 nm, below the first ionisation energy
//! (sources named in the file; regenerate with `tools/gen_tables.py`). Air wavelengths are converted to
//! vacuum with [`crate::ciddor::air_to_vacuum_nm`] (standard air).

pub mod bands;
pub mod line_table;
pub mod profile;

use crate::ciddor::air_to_vacuum_nm;
use crate::constants::{
    BOLTZMANN, ELEMENTARY_CHARGE, JOULES_PER_WAVENUMBER, PLANCK, SPEED_OF_LIGHT,
};
use crate::spectrum::SpectralGrid;
use crate::Error;
use std::f64::consts::PI;

/// A row of the shipped line table (see [`line_table`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TableLine {
    /// Element symbol.
    pub element: &'static str,
    /// Wavelength in standard air, nm.
    pub lambda_air_nm: f64,
    /// Einstein coefficient of spontaneous emission A_ki, s⁻¹.
    pub a_ki: f64,
    /// Upper-level energy E_k, eV.
    pub e_k_ev: f64,
    /// Upper-level statistical weight g_k.
    pub g_k: u32,
    /// Lower-level statistical weight g_i, 0 where the source does not give it.
    pub g_i: u32,
}

/// A spectral line ready for evaluation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Line {
    /// Vacuum wavelength, nm.
    pub lambda_nm: f64,
    /// A_ki, s⁻¹.
    pub a_ki: f64,
    /// Upper level energy, J.
    pub e_k: f64,
    /// Lower level energy E_k − h c₀/λ, J (snapped to 0 within 1 cm⁻¹ of the ground level).
    pub e_i: f64,
    /// Upper level weight.
    pub g_k: u32,
    /// Lower level weight (0 = unknown; not used by the line physics).
    pub g_i: u32,
}

/// An energy level (for the partition function).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Level {
    /// Energy above the ground level, J.
    pub energy: f64,
    /// Statistical weight 2J + 1.
    pub g: u32,
}

/// One element's lines and levels.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    symbol: &'static str,
    lines: Vec<Line>,
    levels: Vec<Level>,
    /// The bands of the molecules the element forms in a flame ([`bands`]).
    bands: Vec<bands::Bands>,
}

/// Symbols of the elements with shipped line data.
pub fn symbols() -> impl Iterator<Item = &'static str> {
    line_table::ELEMENTS.iter().map(|e| e.0)
}

/// Temperatures below this are evaluated at it (the T → 0 limit is reached: only the ground level is populated).
const T_MIN: f64 = 1e-3;

impl Element {
    /// The element with symbol `symbol` (`Na`, `Li`, `K`, `Ca`, `Sr`, `Ba`, `Cu`; case-sensitive like chemistry).
    pub fn by_symbol(symbol: &str) -> Result<Element, Error> {
        let Some(&(sym, g0, _ion)) = line_table::ELEMENTS.iter().find(|e| e.0 == symbol) else {
            let known: Vec<&str> = symbols().collect();
            return Err(Error::invalid(
                "species",
                "element",
                format!("'{symbol}'"),
                format!("one of {}", known.join(", ")),
            ));
        };
        let lines: Vec<Line> = line_table::LINES
            .iter()
            .filter(|l| l.element == sym)
            .map(|l| {
                let lambda_nm = air_to_vacuum_nm(l.lambda_air_nm);
                let e_k = l.e_k_ev * ELEMENTARY_CHARGE;
                let photon = PLANCK * SPEED_OF_LIGHT / (lambda_nm * 1e-9);
                let e_i = e_k - photon;
                let e_i = if e_i.abs() < JOULES_PER_WAVENUMBER {
                    0.0
                } else {
                    e_i.max(0.0)
                };
                // E_k − E_i = h c₀/λ exactly, so that Kirchhoff's law holds to rounding (the snap moves E_k by
                // less than 1 cm⁻¹).
                Line {
                    lambda_nm,
                    a_ki: l.a_ki,
                    e_k: e_i + photon,
                    e_i,
                    g_k: l.g_k,
                    g_i: l.g_i,
                }
            })
            .collect();
        let mut levels = vec![Level { energy: 0.0, g: g0 }];
        for l in &lines {
            levels.push(Level {
                energy: l.e_k,
                g: l.g_k,
            });
            if l.g_i > 0 && l.e_i > 0.0 {
                levels.push(Level {
                    energy: l.e_i,
                    g: l.g_i,
                });
            }
        }
        // One entry per level: the same level reached from several lines agrees to the table's precision
        // (≲ 0.1 cm⁻¹); distinct fine-structure levels differ in energy by more or in weight.
        levels.sort_by(|a, b| a.energy.total_cmp(&b.energy));
        let tol = 0.2 * JOULES_PER_WAVENUMBER;
        let mut unique: Vec<Level> = Vec::with_capacity(levels.len());
        for l in levels {
            if !unique
                .iter()
                .rev()
                .take_while(|u| l.energy - u.energy < tol)
                .any(|u| u.g == l.g)
            {
                unique.push(l);
            }
        }
        Ok(Element {
            symbol: sym,
            lines,
            levels: unique,
            bands: bands::molecules_of(sym)
                .map(|m| bands::Bands::new(m, bands::WIDTH_NM))
                .collect(),
        })
    }

    /// Element symbol.
    pub fn symbol(&self) -> &'static str {
        self.symbol
    }
    /// The element's lines (vacuum wavelengths).
    pub fn lines(&self) -> &[Line] {
        &self.lines
    }
    /// The same element with only the lines `keep` accepts (the levels, and so Z(T), and the bands unchanged).
    pub fn with_lines(&self, keep: &dyn Fn(&Line) -> bool) -> Element {
        Element {
            symbol: self.symbol,
            lines: self.lines.iter().copied().filter(|l| keep(l)).collect(),
            levels: self.levels.clone(),
            bands: self.bands.clone(),
        }
    }
    /// The same element without its molecular bands (its lines alone).
    pub fn without_bands(&self) -> Element {
        Element {
            bands: Vec::new(),
            ..self.clone()
        }
    }
    /// The molecular bands it colours a flame with.
    pub fn bands(&self) -> &[bands::Bands] {
        &self.bands
    }
    /// The levels summed in the partition function.
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// ln Z(T), by log-sum-exp over [`Element::levels`]; finite for every T (T < 1 mK and NaN act as 1 mK).
    pub fn ln_partition_function(&self, t_k: f64) -> f64 {
        let kt = BOLTZMANN * t_k.max(T_MIN);
        let terms = self
            .levels
            .iter()
            .map(|l| (l.g as f64).ln() - l.energy / kt);
        let m = terms.clone().fold(f64::NEG_INFINITY, f64::max);
        m + terms.map(|x| (x - m).exp()).sum::<f64>().ln()
    }

    /// Z(T) = Σ g_j e^{−E_j/kT} (dimensionless).
    pub fn partition_function(&self, t_k: f64) -> f64 {
        self.ln_partition_function(t_k).exp()
    }

    /// Adds this element's lines to binned coefficients **per unit number density** of the element:
    /// `absorption[i] += σ_a/N` (m², a cross-section) and `emission[i] += j/N` (W·sr⁻¹·nm⁻¹ per atom: the
    /// emission coefficient in W·m⁻³·sr⁻¹·nm⁻¹ divided by N in m⁻³), at temperature `t_k`, each line in the
    /// bin of `grid` holding its vacuum wavelength with φ = 1/Δλ, and its molecular bands' bin means
    /// ([`bands::Bands::add_binned`]). Multiply by N (m⁻³): both are exactly linear in N. T < 1 mK acts as 1 mK
    /// (only ground-level absorption remains, emission is 0).
    pub fn add_binned_cross_sections(
        &self,
        t_k: f64,
        grid: &SpectralGrid,
        absorption: &mut [f64],
        emission: &mut [f64],
    ) {
        self.add_placed(
            t_k,
            grid,
            &|l| grid.bin_of(l).map(|b| [(b, 1.0), (b, 0.0)]),
            absorption,
            emission,
        );
    }

    /// As [`add_binned_cross_sections`](Self::add_binned_cross_sections), each line's box shared between two
    /// bins as `split` says (absorption and emission alike: Kirchhoff holds in each bin, and the film sees the
    /// line at its own wavelength's luminance — [`crate::cie::LineSplit`]).
    pub fn add_split_cross_sections(
        &self,
        t_k: f64,
        grid: &SpectralGrid,
        split: &crate::cie::LineSplit,
        absorption: &mut [f64],
        emission: &mut [f64],
    ) {
        self.add_placed(t_k, grid, &|l| split.split(l), absorption, emission);
    }

    /// Each line's box (φ = 1/Δλ of `grid`) added to the bins `place` gives its wavelength, with their fractions.
    fn add_placed(
        &self,
        t_k: f64,
        grid: &SpectralGrid,
        place: &dyn Fn(f64) -> Option<[(usize, f64); 2]>,
        absorption: &mut [f64],
        emission: &mut [f64],
    ) {
        let t = t_k.max(T_MIN);
        let kt = BOLTZMANN * t;
        let ln_z = self.ln_partition_function(t);
        let phi = 1.0 / (grid.width_nm() * 1e-9); // m⁻¹
        for line in &self.lines {
            let Some(parts) = place(line.lambda_nm) else {
                continue;
            };
            let (sa, j) = line_cross_sections(line, kt, ln_z, phi);
            for (bin, f) in parts {
                if f > 0.0 {
                    absorption[bin] += sa * f;
                    emission[bin] += j * f;
                }
            }
        }
        for b in &self.bands {
            b.add_binned(t, grid, absorption, emission);
        }
    }
}

/// What a photograph of a flame coloured by `symbol` shows that this model does not render, and why — `None` where
/// the model holds its colour: lithium's and sodium's lines, strontium's and calcium's hydroxide bands (their
/// monochlorides, with a chlorine donor, colour alike: red and orange).
///
/// - Barium and copper: their bands here are the hydroxide's and oxide's, the yellow-green and green of a gas flame
///   without chlorine; with a chlorine donor (a pyrotechnic green or blue) BaCl (507–532 nm) and CuCl (430–500 nm)
///   take over, which no table reachable here held.
/// - Potassium: a photograph shows lilac — the gas flame's blue through potassium's weak visible light (its
///   766/770 nm doublet, where the CIE observer sees almost nothing, and 404 nm), and a camera's red channel
///   reaching the doublet.
pub fn colour_note(symbol: &str) -> Option<&'static str> {
    Some(match symbol {
        "Ba" => "its bands here are BaOH's and BaO's, the yellow-green of a flame without chlorine; with a chlorine donor its flame photographs green, from BaCl bands at 507–532 nm, which the model does not hold",
        "Cu" => "its bands here are CuOH's and CuO's, the green of a flame without chlorine; with a chlorine donor its flame photographs blue, from CuCl bands at 430–500 nm, which the model does not hold",
        "K" => "its flame photographs lilac: the gas flame's own blue showing through its weak visible light (give the fire a reaction grid's chemiluminescence), and a camera's red channel reaching its 766/770 nm doublet, which the CIE observer barely sees; alone it renders red",
        _ => return None,
    })
}

/// (σ_a/N in m², j/N in W·sr⁻¹·nm⁻¹) of one line with line shape `phi` (m⁻¹), at kT (J), given ln Z.
pub fn line_cross_sections(line: &Line, kt: f64, ln_z: f64, phi: f64) -> (f64, f64) {
    let lambda = line.lambda_nm * 1e-9;
    let x = PLANCK * SPEED_OF_LIGHT / (lambda * kt);
    let ln_g = (line.g_k as f64).ln();
    // ln[(λ⁴ A φ / 8πc) g_k e^{−E_i/kT} (1 − e^{−x}) / Z]; ln(−expm1(−x)) → 0 for large x, ln x for small.
    let ln_sa = (lambda.powi(4) * line.a_ki * phi / (8.0 * PI * SPEED_OF_LIGHT)).ln() + ln_g
        - line.e_i / kt
        + (-(-x).exp_m1()).ln()
        - ln_z;
    // ln[(h c / 4πλ) A φ g_k e^{−E_k/kT} / Z], per metre of wavelength; × 1e-9 per nm.
    let ln_j = (PLANCK * SPEED_OF_LIGHT / (4.0 * PI * lambda) * line.a_ki * phi * 1e-9).ln() + ln_g
        - line.e_k / kt
        - ln_z;
    (ln_sa.exp(), ln_j.exp())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blackbody::spectral_radiance;

    const ALL: [&str; 7] = ["Na", "Li", "K", "Ca", "Sr", "Ba", "Cu"];

    /// de Galan polynomial U = Σ aᵢ (T/1000)ⁱ (shared/data/aesCoeff.csv), valid 1500–7000 K.
    fn de_galan(sym: &str, t: f64) -> f64 {
        let a: &[f64] = match sym {
            "Li" => &[2.081, -0.068926, 0.014081],
            "Na" => &[2.0078, 0.0023147, -0.0063878, 0.0015002],
            "K" => &[1.9909, 0.023169, -0.017423, 0.0040938],
            "Ca" => &[1.0007, 0.02054, -0.019616, 0.004442],
            "Sr" => &[0.87127, 0.20148, -0.10746, 0.021424, -0.0010231],
            "Ba" => &[1.2869, -0.27064, 0.029301, 0.021825, -0.0014227],
            "Cu" => &[2.1905, -0.1938, 0.051491, -0.0014419],
            _ => unreachable!(),
        };
        let u = t / 1000.0;
        a.iter()
            .enumerate()
            .map(|(i, c)| c * u.powi(i as i32))
            .sum()
    }

    #[test]
    fn partition_function_sodium_lithium_2000k() {
        // shared/data/README.md: Li, Na ≈ 2.00 near flame temperatures.
        for s in ["Na", "Li"] {
            let z = Element::by_symbol(s).unwrap().partition_function(2000.0);
            assert!((z / 2.0 - 1.0).abs() < 0.01, "{s}: Z(2000 K) = {z}");
        }
    }

    #[test]
    fn partition_function_matches_de_galan_at_flame_temperatures() {
        // 1 % from 2000 to 3000 K. At 1500 K, the edge of de Galan's range, the fits themselves disagree for Ba
        // (de Galan 1.0133, Irwin 1.0004; the direct sum gives 1.0021 from the ³D levels at 9034–9597 cm⁻¹),
        // so there the bound is the fits' 1.5 % spread.
        for s in ALL {
            let e = Element::by_symbol(s).unwrap();
            for (t, tol) in [
                (1500.0, 0.015),
                (2000.0, 0.01),
                (2500.0, 0.01),
                (3000.0, 0.01),
            ] {
                let (z, want) = (e.partition_function(t), de_galan(s, t));
                assert!(
                    (z / want - 1.0).abs() < tol,
                    "{s} T={t}: Z = {z}, de Galan {want}"
                );
            }
        }
        // Ba: 1.21 at 3000 K (shared/data/README.md). At 2000 K the README rounds to 1.01; the sum over NIST's
        // levels is 1.0203 (³D₁,₂,₃ contribute 0.0181), the fits 1.0147: inside the 1 % check above.
        let ba = Element::by_symbol("Ba").unwrap();
        assert!((ba.partition_function(3000.0) - 1.21).abs() < 0.01);
        assert!((ba.partition_function(2000.0) - 1.0203).abs() < 1e-4);
    }

    #[test]
    fn partition_function_low_and_high_limits() {
        for s in ALL {
            let e = Element::by_symbol(s).unwrap();
            let g0 = e.levels()[0].g as f64;
            assert_eq!(e.levels()[0].energy, 0.0);
            for t in [0.0, 1e-9, 1.0, 10.0, 300.0] {
                assert!((e.partition_function(t) - g0).abs() < 1e-12, "{s} T={t}");
            }
            let bound: f64 = e.levels().iter().map(|l| l.g as f64).sum();
            for t in [1e4, 1e5, 1e9, f64::INFINITY] {
                let z = e.partition_function(t);
                assert!(
                    z.is_finite() && z > g0 && z <= bound * (1.0 + 1e-12),
                    "{s} T={t}: {z}"
                );
            }
        }
    }

    #[test]
    fn sodium_d_lines_land_in_the_589_bin() {
        let na = Element::by_symbol("Na").unwrap();
        let grid = SpectralGrid::default();
        let (mut sa, mut j) = (vec![0.0; 30], vec![0.0; 30]);
        na.add_binned_cross_sections(2000.0, &grid, &mut sa, &mut j);
        let bin = grid.bin_of(589.0).unwrap();
        let brightest = (0..30).max_by(|&a, &b| j[a].total_cmp(&j[b])).unwrap();
        assert_eq!(brightest, bin);
        // The D doublet dominates: > 99 % of the visible line emission at 2000 K.
        let total: f64 = j.iter().sum();
        assert!(j[bin] / total > 0.99, "{}", j[bin] / total);
        let d: Vec<&Line> = na
            .lines()
            .iter()
            .filter(|l| (l.lambda_nm - 589.4).abs() < 0.5)
            .collect();
        assert_eq!(d.len(), 2);
        assert!(d
            .iter()
            .all(|l| l.e_i == 0.0 && grid.bin_of(l.lambda_nm) == Some(bin)));
    }

    #[test]
    fn kirchhoff_holds_for_every_line_and_temperature() {
        // j = σ_a B_λ(T) wherever σ_a > 0, to 1e-6 relative, T from 1 K to 1e5 K.
        let phi = 1.0 / 10e-9;
        for s in ALL {
            let e = Element::by_symbol(s).unwrap();
            for t in [
                1.0, 10.0, 100.0, 300.0, 1000.0, 1500.0, 2000.0, 3000.0, 1e4, 1e5,
            ] {
                let kt = BOLTZMANN * t;
                let ln_z = e.ln_partition_function(t);
                for line in e.lines() {
                    let (sa, j) = line_cross_sections(line, kt, ln_z, phi);
                    assert!(
                        sa.is_finite() && j.is_finite() && sa >= 0.0 && j >= 0.0,
                        "{s} T={t} {line:?}"
                    );
                    let b = spectral_radiance(t, line.lambda_nm);
                    if sa > 0.0 && b > 0.0 && j > 0.0 {
                        let rel = (j / (sa * b) - 1.0).abs();
                        assert!(
                            rel < 1e-6,
                            "{s} T={t} λ={}: j={j:e} σB={:e}",
                            line.lambda_nm,
                            sa * b
                        );
                    } else {
                        // Underflow: either both sides are below f64's range or σ_a B is.
                        assert!(
                            j < 1e-290 || sa * b < 1e-290,
                            "{s} T={t}: j={j:e} σ={sa:e} B={b:e}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn extreme_temperatures_and_densities_stay_finite() {
        let grid = SpectralGrid::new(300.0, 1000.0, 70).unwrap();
        for s in ALL {
            let e = Element::by_symbol(s).unwrap();
            for t in [0.0, -1.0, f64::NAN, 1.0, 1e5, 1e6, f64::INFINITY] {
                let (mut sa, mut j) = (vec![0.0; 70], vec![0.0; 70]);
                e.add_binned_cross_sections(t, &grid, &mut sa, &mut j);
                for n in [0.0, 1e-30, 1.0, 1e20, 1e30] {
                    assert!(
                        sa.iter()
                            .chain(&j)
                            .all(|v| (v * n).is_finite() && *v >= 0.0),
                        "{s} T={t} N={n}"
                    );
                }
                if !(t > 1.0) {
                    // At (or below) 1 K no upper level is populated; ground-level absorption remains.
                    assert!(j.iter().all(|&v| v == 0.0), "{s} T={t}");
                }
            }
        }
        // T → 0: the resonance line absorbs with the ground population N g_k/g₀ … (1 − e^{−x}) → 1.
        let na = Element::by_symbol("Na").unwrap();
        let d2 = na
            .lines()
            .iter()
            .find(|l| l.g_k == 4 && l.e_i == 0.0 && (l.lambda_nm - 589.158).abs() < 0.01)
            .unwrap();
        let (sa, j) = line_cross_sections(d2, BOLTZMANN * 1e-3, na.ln_partition_function(0.0), 1e8);
        let lam = d2.lambda_nm * 1e-9;
        let want = lam.powi(4) * d2.a_ki * 1e8 / (8.0 * PI * SPEED_OF_LIGHT) * 4.0 / 2.0;
        assert!((sa / want - 1.0).abs() < 1e-12 && j == 0.0);
    }

    #[test]
    fn a_line_in_equilibrium_emits_planck_over_its_absorption() {
        // Kirchhoff in LTE: for each line, emission over absorption (stimulated emission included) is Planck's
        // law at the line's wavelength — checked against the blackbody module, an independent formula, for the
        // lithium doublet's bin at 2200 K and 1500 K.
        let li = Element::by_symbol("Li").unwrap();
        let grid = SpectralGrid::default();
        let bin = grid.bin_of(670.8).unwrap();
        for t in [1500.0, 2200.0] {
            let (mut sa, mut j) = (vec![0.0; 30], vec![0.0; 30]);
            li.add_binned_cross_sections(t, &grid, &mut sa, &mut j);
            assert!(j[bin] > 0.0 && sa[bin] > 0.0);
            // (The doublet's vacuum wavelengths, 670.96 and 670.98 nm, as the table holds them.)
            let lam = li
                .lines()
                .iter()
                .find(|l| grid.bin_of(l.lambda_nm) == Some(bin))
                .map(|l| l.lambda_nm)
                .unwrap();
            let b = crate::blackbody::spectral_radiance(t, lam);
            assert!(
                (j[bin] / sa[bin] / b - 1.0).abs() < 2e-4, // (B differs by 2e-4 across the doublet)
                "T {t}: j/σ {} vs B {b}",
                j[bin] / sa[bin]
            );
        }
        // And the absolute size (eq. 7): N = 1e17 m⁻³ Li at 2200 K, both 670.8 nm components in a 10 nm bin.
        let (mut sa, mut j) = (vec![0.0; 30], vec![0.0; 30]);
        li.add_binned_cross_sections(2200.0, &grid, &mut sa, &mut j);
        let kt = BOLTZMANN * 2200.0;
        let z = li.partition_function(2200.0);
        let manual: f64 = li
            .lines()
            .iter()
            .filter(|l| grid.bin_of(l.lambda_nm) == Some(bin))
            .map(|l| {
                let lam = l.lambda_nm * 1e-9;
                let nk = 1e17 * l.g_k as f64 * (-l.e_k / kt).exp() / z;
                PLANCK * SPEED_OF_LIGHT / (4.0 * PI * lam) * nk * l.a_ki / 10e-9 * 1e-9
            })
            .sum();
        assert!(
            (j[bin] * 1e17 / manual - 1.0).abs() < 1e-12,
            "{} vs {manual}",
            j[bin] * 1e17
        );
    }

    #[test]
    fn every_element_has_its_resonance_line() {
        // The lines of shared/data/README.md (air wavelengths) are present with their A_ki.
        for (s, lair, a) in [
            ("Na", 588.995, 6.16e7),
            ("Na", 589.592, 6.14e7),
            ("Li", 670.776, 3.689e7),
            ("K", 766.490, 3.779e7),
            ("K", 769.896, 3.734e7),
            ("Ca", 422.673, 2.18e8),
            ("Sr", 460.733, 2.01e8),
            ("Ba", 553.548, 1.19e8),
            ("Cu", 510.554, 2.0e6),
            ("Cu", 515.324, 6.0e7),
            ("Cu", 521.820, 7.5e7),
        ] {
            let found = line_table::LINES.iter().any(|l| {
                l.element == s
                    && (l.lambda_air_nm - lair).abs() < 2e-3
                    && (l.a_ki / a - 1.0).abs() < 0.01
            });
            assert!(found, "{s} {lair} nm");
        }
        // Cu 510.554 nm: lower level 3d⁹4s² ²D₅/₂ at 11202.62 cm⁻¹.
        let cu = Element::by_symbol("Cu").unwrap();
        let l = cu
            .lines()
            .iter()
            .find(|l| (l.lambda_nm - 510.696).abs() < 0.01)
            .unwrap();
        assert!(
            (l.e_i / JOULES_PER_WAVENUMBER - 11202.62).abs() < 0.5,
            "{}",
            l.e_i / JOULES_PER_WAVENUMBER
        );
    }

    #[test]
    fn unknown_element_is_an_error_naming_the_choices() {
        let e = Element::by_symbol("Xx").unwrap_err().to_string();
        assert!(
            e.contains("'Xx'") && e.contains("Na") && e.contains("Cu"),
            "{e}"
        );
    }
}
