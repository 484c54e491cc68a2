//! Molecular bands of the flame-colouring metals (SrOH, CaOH, BaOH and BaO, CuOH and CuO), in LTE, per atom of the
//! element.
//!
//! A strontium flame is crimson and a calcium flame orange-red not from their atoms' lines (Sr I 460.7 nm, Ca I
//! 422.7 nm, violet) but from the bands of the hydroxides the metals form in a flame; barium's green and copper's
//! are molecular too. Per atom of the element (whatever share of it the flame holds as the molecule), at
//! temperature T and vacuum wavelength λ:
//!
//! - absorption σ_a(λ, T) = σ₀(λ) (1 − e^{−x}), x = h c₀ / (λ k T) (stimulated emission);
//! - emission j(λ, T) = σ_a(λ, T) B_λ(T) — Kirchhoff's law, by construction;
//! - σ₀(λ) = S · (e² / 4ε₀ m_e c₀) · g_ν, with g_ν = g_λ λ² / c₀ and g_λ = Σ_k w_k 𝒩(λ; λ_k, s), Σ w_k = 1: so
//!   ∫ σ₀ dν = S · π e² / (4π ε₀ m_e c₀), and **S is the band system's oscillator strength per free atom of the
//!   element**: the species grid holds free atoms, so S is the molecules per free atom (a flame holds most
//!   Sr, Ba as molecules: hence S of 9.9, 32, 42) times the molecule's f — not a share, which could not exceed 1.
//!   It is fixed, so the molecule/atom ratio does not follow M–OH ⇌ M + OH with temperature: the model holds
//!   near [`T_REF`].
//!
//! The shape σ₀ does not change with T: the bands absorb from the ground vibrational level's sequences (the
//! Franck–Condon factors of these hydroxides are near diagonal), so a hotter flame shifts their emission only
//! through e^{−x}. Each band is a Gaussian of standard deviation [`WIDTH_NM`] — the width of the SrOH bands in a
//! flame spectrum at 1.3 nm resolution, once the instrument is taken out; a flame's colour moves by < 0.005 in xy
//! between 1.5 and 4 nm (tested; BaOH's green, near the spectral locus, moves most).
//!
//! ## Data
//! - **Band positions and relative intensities**: Meyerriecks & Kosanke, *Color values and spectra of the principal
//!   emitters in colored flames*, J. Pyrotechnics 18 (2003) — the emitters isolated from salts aspirated into a
//!   propane flame, instrument corrected — as transcribed (air wavelengths to 1 nm, heights normalised to the
//!   strongest band) in the public repository TeoCaggia/Flame-test-simulator (`scripts/build_spectral_data.py`).
//!   The paper itself was not reachable from here; its SrOH table agrees with an independent flame spectrum to
//!   0.001 in xy (below). The weights are w_k ∝ I_k / (B_λ(λ_k, [`T_REF`]) λ_k²), so that the emission at T_REF has
//!   the published heights.
//! - **CaOH's pseudo-continuum.** Between its peaks the orange system (A²Π–X²Σ⁺) is a continuum of unresolved
//!   rotational lines, 607–628 nm, that M&K's table of peaks lacks: with their peaks alone calcium rendered at
//!   (0.572, 0.415), sodium's colour, against the measured flame's (0.612, 0.387). It is held as five more Gaussians
//!   at 3-nm spacing (607, 613, 616, 619, 622 nm; heights 2.6, 18.7, 4.6, 67.0, 34.2 where 625 nm is 100), fitted by
//!   non-negative least squares, with M&K's peaks scaled together, to the measured calcium spectrum over 545–635
//!   nm (`tests/data/flame-tests/Ca.csv`; the residual's RMS 11.8 counts with the peaks alone, 4.2 with them).
//! - **S**, calibrated against a measured flame-test spectrum (TeoCaggia/Flame-test-simulator,
//!   `files/spectral_sources/definitivo/`: salts in a gas flame, an Ocean Optics USB2000 at 1.3 nm FWHM, no
//!   response correction): S makes the ratio of one of the molecule's bands to the element's line, as peak heights
//!   at the instrument's resolution, what that spectrum shows, at [`T_REF`]. The spectrometer counts photons, so
//!   the counts' ratio is turned into the energies' by λ_line / λ_band (for Sr and Ca 0.68: read as energy, S
//!   would be 1.48× high). Band and line are both measured above zero or above the flat continuum the spectrum
//!   shows (not a band above its own wings, which reads the strontium and calcium bands 1.6× and 1.8× low): SrOH
//!   682 nm 705.5 and Sr I 36.4 counts from the recorded spectrum (background removed by the source), CaOH 625 nm
//!   67.7 above calcium's 5-count continuum (`tests/data/flame-tests/`, tested against the files), Ca I 6.5 (the
//!   source's `scelte.csv`); barium's heights are the source's (BaOH 512 nm, BaO "604" — M&K's 608, the nearest
//!   —, the line above the band forest it stands on), copper's read here above its 9-count continuum (CuOH 546, CuO
//!   492; the source's fit missed its broad bands). Each [`Molecule::calibration`] names the four numbers;
//!   `bands_are_calibrated_against_the_flame_spectrum` recomputes S from them. Barium's line (Ba I 553.5 nm) is
//!   clipped in that spectrum, so its S are upper bounds; copper's (Cu I 510.6 nm) sits on its bands' slope and
//!   its resonance lines (324.8, 327.4 nm) do not show at all, so copper's S are lower bounds — most of that
//!   flame's copper is molecules.
//!
//!   **S is uncertain by a factor of 2–3.** What is not corrected: the flame's temperature is not known (strontium's
//!   S would be ≈ 0.8 / 1.5 × at 1900 / 2200 K; barium's, whose line and bands lie close in energy, ≈ 0.9 / 1.1 ×),
//!   and the spectrometer's response differs between the band's and the line's wavelengths by an unknown factor
//!   (the source warns against comparing them).
//!
//! Not held: the monochlorides (SrCl, CaCl, BaCl, CuCl), which colour flames with a chlorine donor (pyrotechnic
//! reds, greens and copper's blue) — no table of theirs was reachable; the render notes it for Ba and Cu, whose
//! colours they change.

use crate::blackbody::spectral_radiance;
use crate::ciddor::air_to_vacuum_nm;
use crate::constants::{BOLTZMANN, ELEMENTARY_CHARGE, PLANCK, SPEED_OF_LIGHT};
use crate::spectrum::SpectralGrid;

/// The flame temperature the band heights and strengths refer to, K (a gas flame's; see the module docs).
pub const T_REF: f64 = 2000.0;

/// Standard deviation of each band, nm.
pub const WIDTH_NM: f64 = 2.5;

/// Bands are summed out to this many standard deviations.
const REACH: f64 = 8.0;

/// e² / (4 ε₀ m_e c₀) = π e² / (4π ε₀ m_e c₀): the integrated absorption cross-section per unit oscillator
/// strength, m²·s⁻¹ (2.654 × 10⁻⁶).
const CLASSICAL: f64 = ELEMENTARY_CHARGE * ELEMENTARY_CHARGE
    / (4.0 * 8.854_187_812_8e-12 * 9.109_383_701_5e-31 * SPEED_OF_LIGHT);

/// A molecule's band system, per atom of its metal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Molecule {
    /// Formula.
    pub name: &'static str,
    /// The metal it carries.
    pub element: &'static str,
    /// (air wavelength nm, relative emission at [`T_REF`]) — Meyerriecks & Kosanke's table.
    pub bands: &'static [(f64, f64)],
    /// S, the band system's oscillator strength per atom of the element.
    pub strength: f64,
    /// What S was calibrated from, in the flame-test spectrum.
    pub calibration: Calibration,
}

/// A band's and its element's line's peak heights in a flame-test spectrum (counts above the local continuum, at the
/// spectrometer's 1.3 nm FWHM), which S reproduces at [`T_REF`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Calibration {
    /// The band's air wavelength (one of the molecule's), nm.
    pub band_nm: f64,
    /// Its height.
    pub band_height: f64,
    /// The element's line, air wavelength, nm.
    pub line_nm: f64,
    /// Its height.
    pub line_height: f64,
}

/// The shipped band systems.
#[rustfmt::skip]
pub const MOLECULES: [Molecule; 6] = [
    Molecule {
        name: "SrOH", element: "Sr", strength: 9.857,
        bands: &[(606.0, 59.0), (620.0, 2.0), (626.0, 2.0), (649.0, 13.0), (659.0, 33.0), (671.0, 70.0), (682.0, 100.0), (707.0, 9.0), (722.0, 1.0)],
        calibration: Calibration { band_nm: 682.0, band_height: 705.5, line_nm: 460.7331, line_height: 36.4 },
    },
    Molecule {
        name: "CaOH", element: "Ca", strength: 2.629,
        // M&K's peaks, then (607–622 nm) the orange system's pseudo-continuum (see the module docs).
        bands: &[(555.0, 45.0), (572.0, 1.0), (594.0, 7.0), (600.0, 11.0), (604.0, 14.0), (625.0, 100.0), (645.0, 10.0), (665.0, 1.0),
                 (607.0, 2.6), (613.0, 18.7), (616.0, 4.6), (619.0, 67.0), (622.0, 34.2)],
        calibration: Calibration { band_nm: 625.0, band_height: 67.7, line_nm: 422.673, line_height: 6.5 },
    },
    Molecule {
        name: "BaOH", element: "Ba", strength: 32.34,
        bands: &[(488.0, 72.0), (502.0, 30.0), (513.0, 100.0), (524.0, 86.0), (745.0, 47.0)],
        calibration: Calibration { band_nm: 513.0, band_height: 86.8, line_nm: 553.5481, line_height: 161.0 },
    },
    Molecule {
        name: "BaO", element: "Ba", strength: 41.73,
        bands: &[(485.0, 72.0), (497.0, 100.0), (514.0, 87.0), (526.0, 97.0), (533.0, 100.0), (535.0, 90.0), (546.0, 16.0), (551.0, 68.0), (567.0, 51.0), (574.0, 36.0), (583.0, 32.0), (589.0, 93.0), (608.0, 88.0), (612.0, 59.0), (617.0, 34.0), (623.0, 32.0), (626.0, 29.0), (632.0, 79.0), (642.0, 26.0), (653.0, 71.0), (656.0, 57.0), (663.0, 39.0), (682.0, 56.0), (686.0, 33.0), (693.0, 26.0), (701.0, 10.0), (710.0, 50.0), (718.0, 46.0), (725.0, 14.0), (734.0, 32.0), (744.0, 16.0), (752.0, 26.0), (761.0, 41.0)],
        calibration: Calibration { band_nm: 608.0, band_height: 61.7, line_nm: 553.5481, line_height: 161.0 },
    },
    Molecule {
        name: "CuOH", element: "Cu", strength: 1.472e-3,
        bands: &[(505.0, 46.0), (512.0, 44.0), (524.0, 75.0), (533.0, 84.0), (546.0, 100.0), (605.0, 10.0)],
        calibration: Calibration { band_nm: 546.0, band_height: 89.0, line_nm: 510.5541, line_height: 3.3 },
    },
    Molecule {
        name: "CuO", element: "Cu", strength: 1.664e-3,
        bands: &[(450.0, 25.0), (453.0, 27.0), (458.0, 33.0), (467.0, 52.0), (471.0, 53.0), (477.0, 57.0), (480.0, 66.0), (486.0, 69.0), (488.0, 83.0), (492.0, 100.0), (606.0, 42.0), (616.0, 59.0), (632.0, 47.0)],
        calibration: Calibration { band_nm: 492.0, band_height: 23.0, line_nm: 510.5541, line_height: 3.3 },
    },
];

/// The band systems carried by element `symbol`.
pub fn molecules_of(symbol: &str) -> impl Iterator<Item = &'static Molecule> + '_ {
    MOLECULES.iter().filter(move |m| m.element == symbol)
}

/// A molecule's bands ready for evaluation: vacuum centres (nm) and weights w_k (Σ = 1), with S.
#[derive(Debug, Clone, PartialEq)]
pub struct Bands {
    molecule: &'static Molecule,
    centres: Vec<(f64, f64)>,
    width: f64,
}

impl Bands {
    /// `m`'s bands, each a Gaussian of standard deviation `width` nm.
    pub fn new(m: &'static Molecule, width: f64) -> Bands {
        let raw: Vec<(f64, f64)> = m
            .bands
            .iter()
            .map(|&(air, i)| {
                let l = air_to_vacuum_nm(air);
                (l, i / (spectral_radiance(T_REF, l) * l * l))
            })
            .collect();
        let sum: f64 = raw.iter().map(|c| c.1).sum();
        Bands {
            molecule: m,
            centres: raw.into_iter().map(|(l, w)| (l, w / sum)).collect(),
            width,
        }
    }
    /// The molecule these bands are of.
    pub fn molecule(&self) -> &'static Molecule {
        self.molecule
    }
    /// (σ₀ at λ per unit g_λ in nm⁻¹): S · (e²/4ε₀m_ec) · λ²/c · 10⁹, m² per (nm⁻¹).
    fn scale(&self, lambda_nm: f64) -> f64 {
        let l = lambda_nm * 1e-9;
        self.molecule.strength * CLASSICAL * l * l / SPEED_OF_LIGHT * 1e9
    }
    /// g_λ(λ), nm⁻¹ (the normalised sum of Gaussians) for bands of standard deviation `s`.
    fn shape(&self, lambda_nm: f64, s: f64) -> f64 {
        let norm = 1.0 / (s * (2.0 * std::f64::consts::PI).sqrt());
        self.centres
            .iter()
            .filter(|c| (lambda_nm - c.0).abs() < REACH * s)
            .map(|&(c, w)| w * norm * (-0.5 * ((lambda_nm - c) / s).powi(2)).exp())
            .sum()
    }
    /// σ₀(λ), m² per atom of the element.
    pub fn sigma0(&self, lambda_nm: f64) -> f64 {
        self.scale(lambda_nm) * self.shape(lambda_nm, self.width)
    }
    /// σ₀(λ) seen through an instrument of Gaussian standard deviation `s_inst` nm.
    pub fn sigma0_seen(&self, lambda_nm: f64, s_inst: f64) -> f64 {
        let s = self.width.hypot(s_inst);
        self.scale(lambda_nm) * self.shape(lambda_nm, s)
    }
    /// (σ_a m², j W·sr⁻¹·nm⁻¹) per atom of the element at λ and T.
    pub fn at(&self, lambda_nm: f64, t_k: f64) -> (f64, f64) {
        let s0 = self.sigma0(lambda_nm);
        (
            s0 * stimulated(lambda_nm, t_k),
            s0 * emitted(lambda_nm, t_k),
        )
    }
    /// Adds the bands' bin means of σ_a (m²) and j = σ_a B_λ (W·sr⁻¹·nm⁻¹) per atom, at T, over `grid`: each band's
    /// Gaussian integrated over each bin exactly (through erf), λ²/c₀, e^{−x} and B_λ at the bin's centre, so that
    /// Kirchhoff's law holds in every bin.
    pub fn add_binned(
        &self,
        t_k: f64,
        grid: &SpectralGrid,
        absorption: &mut [f64],
        emission: &mut [f64],
    ) {
        let (w, s) = (grid.width_nm(), self.width);
        let mut g = vec![0.0; grid.count()];
        for &(c, wk) in &self.centres {
            let (Some(lo), Some(hi)) = (
                grid.bin_of((c - REACH * s).max(grid.min_nm())),
                grid.bin_of((c + REACH * s).min(grid.max_nm())),
            ) else {
                continue;
            };
            for (i, gi) in g.iter_mut().enumerate().take(hi + 1).skip(lo) {
                let (a, b) = grid.edges(i);
                *gi += wk * (normal_cdf((b - c) / s) - normal_cdf((a - c) / s)) / w;
            }
        }
        for (i, gi) in g.into_iter().enumerate() {
            if gi > 0.0 {
                let l = grid.centre(i);
                let s0 = self.scale(l) * gi;
                absorption[i] += s0 * stimulated(l, t_k);
                emission[i] += s0 * emitted(l, t_k);
            }
        }
    }
    /// ∫ j dλ per atom over the whole spectrum at T, W·sr⁻¹: each band's weight times λ²/c₀ · e^{−x} 2hc²/λ⁵ by
    /// three-point Gauss–Hermite quadrature over its Gaussian (nodes c, c ± √3 s; weights 2/3, 1/6, 1/6 — exact
    /// for quintics; within 1e-4 of the integral from 1000 to 3000 K, tested) — cheap enough for the fire light to
    /// call per voxel.
    pub fn power(&self, t_k: f64) -> f64 {
        let d = 3f64.sqrt() * self.width;
        let f = |l: f64| self.scale(l) * emitted(l, t_k);
        self.centres
            .iter()
            .map(|&(c, wk)| wk * (2.0 / 3.0 * f(c) + (f(c - d) + f(c + d)) / 6.0))
            .sum()
    }
}

/// x = hc/λkT (T below 1 mK, and NaN, act as 1 mK).
fn x_of(lambda_nm: f64, t_k: f64) -> f64 {
    PLANCK * SPEED_OF_LIGHT / (lambda_nm * 1e-9 * BOLTZMANN * t_k.max(1e-3))
}

/// 1 − e^{−x} (1 at T → 0, 0 at T = ∞).
fn stimulated(lambda_nm: f64, t_k: f64) -> f64 {
    -(-x_of(lambda_nm, t_k)).exp_m1()
}

/// (1 − e^{−x}) B_λ(T) = (2hc²/λ⁵) e^{−x}, W·m⁻²·sr⁻¹·nm⁻¹: what σ₀ multiplies for the emission — finite at every
/// T, where (1 − e^{−x}) · B_λ would be 0 · ∞ at T = ∞.
fn emitted(lambda_nm: f64, t_k: f64) -> f64 {
    let l = lambda_nm * 1e-9;
    crate::blackbody::C1 / l.powi(5) * (-x_of(lambda_nm, t_k)).exp() * 1e-9
}

/// Φ(z), the standard normal distribution. erfc's 1.5e-7 absolute error is enough: a band's bins telescope, so
/// their sum is Φ(b_last) − Φ(a_first) whatever the error inside.
fn normal_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// erfc(x), absolute error < 1.5e-7 (Abramowitz & Stegun 7.1.26, with erfc(−x) = 2 − erfc(x)).
fn erfc(x: f64) -> f64 {
    let ax = x.abs();
    let t = 1.0 / (1.0 + 0.327_591_1 * ax);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let e = poly * (-ax * ax).exp();
    if x >= 0.0 {
        e
    } else {
        2.0 - e
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::species::{line_cross_sections, Element};

    fn grid() -> SpectralGrid {
        SpectralGrid::new(380.0, 780.0, 40).unwrap()
    }

    #[test]
    fn kirchhoff_holds_in_every_bin() {
        for m in &MOLECULES {
            let b = Bands::new(m, WIDTH_NM);
            for t in [300.0, 1500.0, 2000.0, 3000.0, 1e5] {
                let (mut sa, mut j) = (vec![0.0; 40], vec![0.0; 40]);
                b.add_binned(t, &grid(), &mut sa, &mut j);
                assert!(sa.iter().any(|&s| s > 0.0), "{}", m.name);
                for i in 0..40 {
                    let want = sa[i] * spectral_radiance(t, grid().centre(i));
                    assert!(
                        (j[i] - want).abs() <= 1e-12 * want,
                        "{} {t} K bin {i}",
                        m.name
                    );
                }
            }
        }
    }

    /// ∫ σ₀ dν = S e²/(4ε₀ m_e c₀), by quadrature of σ₀(λ) c₀/λ² dλ; and the bins' means carry the same total.
    #[test]
    fn the_bands_integrate_to_their_oscillator_strength() {
        // e²/(4 ε₀ m_e c₀) = π r_e c₀ with the classical electron radius r_e = 2.8179403262e-15 m (CODATA 2018).
        let classical = std::f64::consts::PI * 2.817_940_326_2e-15 * SPEED_OF_LIGHT;
        assert!((CLASSICAL / classical - 1.0).abs() < 1e-9);
        for m in &MOLECULES {
            let b = Bands::new(m, WIDTH_NM);
            let f = |l: f64| b.sigma0(l) * SPEED_OF_LIGHT / (l * l * 1e-18) * 1e-9;
            let total = crate::quadrature::gauss_legendre(f, 300.0, 900.0, 600);
            let want = m.strength * classical;
            assert!(
                (total / want - 1.0).abs() < 1e-6,
                "{}: {total} vs {want}",
                m.name
            );
            // The bins (at T → 0, where σ_a = σ₀): Σ σ̄₀ Δλ c₀/λ_c².
            let g = SpectralGrid::new(300.0, 900.0, 600).unwrap();
            let (mut sa, mut j) = (vec![0.0; 600], vec![0.0; 600]);
            b.add_binned(1.0, &g, &mut sa, &mut j);
            let binned: f64 = (0..600)
                .map(|i| sa[i] * SPEED_OF_LIGHT / (g.centre(i) * 1e-9).powi(2) * 1e-9)
                .sum();
            assert!(
                (binned / want - 1.0).abs() < 1e-4,
                "{}: {binned} vs {want}",
                m.name
            );
        }
    }

    /// At T_REF the emission has the published heights: at each band's centre, j over the sum of the table's
    /// Gaussians (I_k 𝒩(λ; λ_k, s)) is the same for every band — within 6 % (B_λ λ² varies across a band, and bands 2–4 nm apart overlap).
    #[test]
    fn emission_at_the_reference_temperature_has_the_published_heights() {
        for m in &MOLECULES {
            let b = Bands::new(m, WIDTH_NM);
            let ratios: Vec<f64> = m
                .bands
                .iter()
                .map(|&(air, _)| {
                    let l = air_to_vacuum_nm(air);
                    let table: f64 = m
                        .bands
                        .iter()
                        .map(|&(a, i)| {
                            let z = (l - air_to_vacuum_nm(a)) / WIDTH_NM;
                            i * (-0.5 * z * z).exp()
                        })
                        .sum();
                    b.at(l, T_REF).1 / table
                })
                .collect();
            let (lo, hi) = ratios
                .iter()
                .fold((f64::MAX, 0.0f64), |(a, c), &r| (a.min(r), c.max(r)));
            assert!(hi / lo < 1.06, "{}: {ratios:?}", m.name);
        }
    }

    #[test]
    fn the_power_at_band_centres_is_the_integral() {
        for m in &MOLECULES {
            let b = Bands::new(m, WIDTH_NM);
            for t in [1000.0, 2000.0, 3000.0] {
                let exact = crate::quadrature::gauss_legendre(|l| b.at(l, t).1, 300.0, 900.0, 600);
                let fast = b.power(t);
                assert!(
                    (fast / exact - 1.0).abs() < 1e-4,
                    "{} {t} K: {fast} vs {exact}",
                    m.name
                );
            }
        }
    }

    fn chromaticity(b: &Bands, t: f64) -> (f64, f64) {
        crate::cie::chromaticity(crate::cie::spectrum_to_xyz(|l| b.at(l, t).1))
    }

    #[test]
    fn a_flames_colour_hardly_depends_on_the_band_width() {
        for m in &MOLECULES {
            let (narrow, wide) = (Bands::new(m, 1.5), Bands::new(m, 4.0));
            let (a, c) = (chromaticity(&narrow, T_REF), chromaticity(&wide, T_REF));
            let d = (a.0 - c.0).hypot(a.1 - c.1);
            assert!(d < 0.005, "{}: {a:?} vs {c:?}", m.name);
        }
    }

    /// S reproduces the flame spectrum's ratio of the strongest band to the element's line, as peak heights at the
    /// spectrometer's resolution (1.3 nm FWHM) at T_REF: the line's J = (hc/4πλ) A g_k e^{−E_k/kT}/Z spread over
    /// the instrument's Gaussian, the band's σ₀ broadened by it, times (1 − e^{−x}) B_λ.
    #[test]
    fn bands_are_calibrated_against_the_flame_spectrum() {
        let s_inst = 1.3 / (8.0 * std::f64::consts::LN_2).sqrt();
        for m in &MOLECULES {
            let Calibration {
                band_nm,
                band_height: band_h,
                line_nm,
                line_height: line_h,
            } = m.calibration;
            let e = Element::by_symbol(m.element).unwrap();
            let line_vac = air_to_vacuum_nm(line_nm);
            let line = e
                .lines()
                .iter()
                .min_by(|a, b| {
                    (a.lambda_nm - line_vac)
                        .abs()
                        .total_cmp(&(b.lambda_nm - line_vac).abs())
                })
                .unwrap();
            assert!(
                (line.lambda_nm - line_vac).abs() < 0.01,
                "{}: {}",
                m.name,
                line.lambda_nm
            );
            let kt = BOLTZMANN * T_REF;
            let j_line = line_cross_sections(line, kt, e.ln_partition_function(T_REF), 1e9).1;
            let line_peak = j_line / (s_inst * (2.0 * std::f64::consts::PI).sqrt());
            let b = Bands::new(m, WIDTH_NM);
            let l = air_to_vacuum_nm(band_nm);
            let band_peak =
                b.sigma0_seen(l, s_inst) * stimulated(l, T_REF) * spectral_radiance(T_REF, l);
            let ratio = band_peak / line_peak;
            // Counts are photons: energy per photon h c / λ, so the energies' ratio is the counts' times
            // λ_line / λ_band.
            let want = band_h / line_h * line_nm / band_nm;
            eprintln!("{}: S should be {:.4e}", m.name, m.strength * want / ratio);
            assert!(
                (ratio / want - 1.0).abs() < 0.005,
                "{}: S {} gives {ratio}, the spectrum {want}: S should be {}",
                m.name,
                m.strength,
                m.strength * want / ratio
            );
        }
    }
}
