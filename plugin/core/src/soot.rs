//! Soot absorption (Pegoraro & Parker 2006, eq. 5, after Dalzell & Sarofim 1969).
//!
//! κ(λ) = 36π · n k / ((n² − k² + 2)² + 4 n² k²) · f_v / λ^α,   m⁻¹,
//!
//! with m = n − i k the complex refractive index of the soot and f_v the soot volume fraction (m³ of soot per m³
//! of gas, dimensionless). Units of λ:
//! - `alpha = 1` is the Rayleigh small-particle limit, dimensionally exact with λ in metres (κ in m⁻¹).
//! - `alpha = 1.39` (the default, Hottel's value recommended by P&P for the visible) is an empirical fit whose
//!   constant is calibrated with **λ in µm**, giving κ in µm⁻¹.
//!
//! Both are served by one formula: κ [m⁻¹] = 10⁶ · 36π E(m) f_v / (λ/µm)^α. For α = 1 this equals the
//! metre form exactly (the 10⁶ cancels), so the two conventions agree at α = 1 and the α = 1.39 result
//! is Hottel's. Check (shared/data): propane, 550 nm, f_v = 10⁻⁶, α = 1 → κ = 8.44 m⁻¹.
//!
//! The thesis writes the coefficient as 48 N π R³; substituting f_v = N·(4/3)πR³ into eq. 5 gives
//! 36π f_v = 48 π² N R³ (a factor π apart) — this module derives from eq. 5 and f_v
//! ([`volume_fraction`]).
//!
//! Optical constants: [`SootOptics::propane`] and [`SootOptics::acetylene`] (Dalzell & Sarofim 1969 at 435.8,
//! 450, 550, 650 and 806.5 nm), interpolated linearly in λ and held constant outside the table; or a user table.

use crate::Error;

/// Hottel's exponent for the visible (P&P section 3.4), used with λ in µm.
pub const HOTTEL_ALPHA: f64 = 1.39;
/// Mean soot particle radius of the thesis, m (Dalzell & Sarofim report 5–80 nm; the thesis takes 42.5 nm).
pub const DEFAULT_PARTICLE_RADIUS_M: f64 = 42.5e-9;

/// Complex refractive index of soot over wavelength: rows (λ nm, n, k), λ strictly increasing.
#[derive(Debug, Clone, PartialEq)]
pub struct SootOptics {
    rows: Vec<[f64; 3]>,
}

/// Dalzell & Sarofim 1969, propane soot: (λ nm, n, k). Via shared/data/README.md and the
/// Era-Dorta/fire-modeling `Propane.optconst` (which lacks the 806.5 nm row).
const PROPANE: [[f64; 3]; 5] = [
    [435.8, 1.57, 0.46],
    [450.0, 1.56, 0.50],
    [550.0, 1.57, 0.53],
    [650.0, 1.56, 0.52],
    [806.5, 1.57, 0.49],
];
/// Dalzell & Sarofim 1969, acetylene soot: (λ nm, n, k).
const ACETYLENE: [[f64; 3]; 5] = [
    [435.8, 1.56, 0.46],
    [450.0, 1.56, 0.48],
    [550.0, 1.56, 0.46],
    [650.0, 1.57, 0.44],
    [806.5, 1.57, 0.46],
];

/// The fuels with built-in soot optical constants, by the names a scene uses.
pub const FUELS: [&str; 2] = ["propane", "acetylene"];

impl SootOptics {
    /// Propane soot (Dalzell & Sarofim 1969).
    pub fn propane() -> Self {
        SootOptics {
            rows: PROPANE.to_vec(),
        }
    }

    /// Acetylene soot (Dalzell & Sarofim 1969).
    pub fn acetylene() -> Self {
        SootOptics {
            rows: ACETYLENE.to_vec(),
        }
    }

    /// Built-in optical constants by fuel name (`propane`, `acetylene`; case-insensitive).
    pub fn for_fuel(name: &str) -> Result<Self, Error> {
        match name.to_ascii_lowercase().as_str() {
            "propane" => Ok(Self::propane()),
            "acetylene" => Ok(Self::acetylene()),
            _ => Err(Error::invalid(
                "soot",
                "fuel",
                format!("'{name}'"),
                format!("one of {}", FUELS.join(", ")),
            )),
        }
    }

    /// A user table of (λ nm, n, k) rows: at least one row, λ finite, positive and strictly increasing,
    /// n > 0 and k ≥ 0 finite.
    pub fn from_table(rows: &[[f64; 3]]) -> Result<Self, Error> {
        if rows.is_empty() {
            return Err(Error::invalid(
                "soot",
                "optics",
                "an empty table",
                "at least one (λ nm, n, k) row",
            ));
        }
        for (i, &[l, n, k]) in rows.iter().enumerate() {
            if !(l.is_finite() && l > 0.0) {
                return Err(Error::invalid(
                    "soot",
                    format!("optics row {i} wavelength"),
                    l,
                    "a finite wavelength > 0 nm",
                ));
            }
            if !(n.is_finite() && n > 0.0) {
                return Err(Error::invalid(
                    "soot",
                    format!("optics row {i} n"),
                    n,
                    "a finite real index n > 0",
                ));
            }
            if !(k.is_finite() && k >= 0.0) {
                return Err(Error::invalid(
                    "soot",
                    format!("optics row {i} k"),
                    k,
                    "a finite absorption index k >= 0",
                ));
            }
            if i > 0 && l <= rows[i - 1][0] {
                return Err(Error::invalid(
                    "soot",
                    format!("optics row {i} wavelength"),
                    l,
                    format!(
                        "a wavelength above the previous row's {} nm (rows sorted, no repeats)",
                        rows[i - 1][0]
                    ),
                ));
            }
        }
        Ok(SootOptics {
            rows: rows.to_vec(),
        })
    }

    /// The table rows (λ nm, n, k).
    pub fn rows(&self) -> &[[f64; 3]] {
        &self.rows
    }

    /// (n, k) at `lambda_nm`: linear in λ between rows, constant beyond the first and last row.
    pub fn nk(&self, lambda_nm: f64) -> (f64, f64) {
        let r = &self.rows;
        let first = r[0];
        let last = r[r.len() - 1];
        if !(lambda_nm > first[0]) {
            return (first[1], first[2]);
        }
        if lambda_nm >= last[0] {
            return (last[1], last[2]);
        }
        // r.len() ≥ 2 here; find the interval [r[i], r[i+1]] holding λ.
        let i = r.partition_point(|row| row[0] <= lambda_nm) - 1;
        let (a, b) = (r[i], r[i + 1]);
        let s = (lambda_nm - a[0]) / (b[0] - a[0]);
        (a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2]))
    }

    /// 36π E(m) with E(m) = n k / ((n² − k² + 2)² + 4n²k²) = Im((m² − 1)/(m² + 2)) / 6 (dimensionless).
    pub fn absorption_function(&self, lambda_nm: f64) -> f64 {
        let (n, k) = self.nk(lambda_nm);
        let a = n * n - k * k + 2.0;
        36.0 * std::f64::consts::PI * n * k / (a * a + 4.0 * n * n * k * k)
    }

    /// Absorption coefficient κ, m⁻¹, at vacuum wavelength `lambda_nm` for soot volume fraction `f_v`
    /// (dimensionless) and exponent `alpha` (see the module docs for units). f_v ≤ 0 or NaN gives 0.
    pub fn kappa(&self, lambda_nm: f64, f_v: f64, alpha: f64) -> f64 {
        if !(f_v > 0.0) {
            return 0.0;
        }
        let lambda_um = lambda_nm * 1e-3;
        1e6 * self.absorption_function(lambda_nm) * f_v / lambda_um.powf(alpha)
    }
}

/// Soot volume fraction f_v = N · (4/3)π R³ from a particle number density `n_per_m3` (m⁻³) and particle
/// radius `radius_m` (m): dimensionless.
pub fn volume_fraction(n_per_m3: f64, radius_m: f64) -> f64 {
    n_per_m3 * 4.0 / 3.0 * std::f64::consts::PI * radius_m.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn propane_550nm_rayleigh_is_8_44_per_metre() {
        // shared/data/README.md: κ = 36π n k / ((n²−k²+2)² + 4n²k²) · f_v / λ, λ in m → 8.44 m⁻¹.
        let k = SootOptics::propane().kappa(550.0, 1e-6, 1.0);
        assert!((k / 8.44 - 1.0).abs() < 0.005, "{k}");
        // Same number from the metre form written out.
        let (n, kk) = (1.57f64, 0.53f64);
        let a = n * n - kk * kk + 2.0;
        let direct =
            36.0 * std::f64::consts::PI * n * kk / (a * a + 4.0 * n * n * kk * kk) * 1e-6 / 550e-9;
        assert!((k / direct - 1.0).abs() < 1e-12);
    }

    #[test]
    fn hottel_exponent_uses_micrometres() {
        // α = 1.39 with λ in µm: κ = 10⁶ · 36πE · f_v / 0.55^1.39 — 10.66 m⁻¹ for propane at 550 nm,
        // the same order as the Rayleigh 8.44 m⁻¹ (a λ in metres would give 10⁹ × too much).
        let k = SootOptics::propane().kappa(550.0, 1e-6, HOTTEL_ALPHA);
        let want =
            1e6 * SootOptics::propane().absorption_function(550.0) * 1e-6 / 0.55f64.powf(1.39);
        assert!((k / want - 1.0).abs() < 1e-12);
        assert!((k - 10.66).abs() < 0.01, "{k}");
    }

    #[test]
    fn interpolates_linearly_and_clamps() {
        let p = SootOptics::propane();
        assert_eq!(p.nk(550.0), (1.57, 0.53));
        let (n, k) = p.nk(500.0); // halfway 450 → 550
        assert!((n - 1.565).abs() < 1e-12 && (k - 0.515).abs() < 1e-12);
        assert_eq!(p.nk(300.0), (1.57, 0.46));
        assert_eq!(p.nk(1000.0), (1.57, 0.49));
        let a = SootOptics::acetylene();
        assert_eq!(a.nk(806.5), (1.57, 0.46));
        assert_eq!(a.nk(f64::NAN), (1.56, 0.46));
    }

    #[test]
    fn kappa_is_linear_in_volume_fraction_and_zero_for_none() {
        let p = SootOptics::propane();
        let k1 = p.kappa(600.0, 1e-7, 1.0);
        assert!((p.kappa(600.0, 3e-7, 1.0) / k1 - 3.0).abs() < 1e-12);
        assert_eq!(p.kappa(600.0, 0.0, 1.0), 0.0);
        assert_eq!(p.kappa(600.0, -1.0, 1.0), 0.0);
        assert_eq!(p.kappa(600.0, f64::NAN, 1.0), 0.0);
    }

    #[test]
    fn number_density_to_volume_fraction() {
        // f_v = N (4/3)π R³: 10¹⁶ m⁻³ particles of 42.5 nm → 3.2155e-6.
        let fv = volume_fraction(1e16, DEFAULT_PARTICLE_RADIUS_M);
        assert!((fv - 1e16 * 4.0 / 3.0 * std::f64::consts::PI * 42.5e-9f64.powi(3)).abs() < 1e-20);
        assert!((fv - 3.2155e-6).abs() < 1e-9, "{fv}");
    }

    #[test]
    fn user_tables_are_validated() {
        assert!(SootOptics::from_table(&[[500.0, 1.6, 0.6]]).is_ok());
        let one = SootOptics::from_table(&[[500.0, 1.6, 0.6]]).unwrap();
        assert_eq!(one.nk(100.0), (1.6, 0.6));
        let e = SootOptics::from_table(&[]).unwrap_err().to_string();
        assert!(e.contains("empty"), "{e}");
        let e = SootOptics::from_table(&[[500.0, 1.6, 0.6], [450.0, 1.6, 0.6]])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("row 1 wavelength") && e.contains("450") && e.contains("500"),
            "{e}"
        );
        let e = SootOptics::from_table(&[[500.0, f64::NAN, 0.6]])
            .unwrap_err()
            .to_string();
        assert!(e.contains("row 0 n") && e.contains("NaN"), "{e}");
        let e = SootOptics::from_table(&[[500.0, 1.5, -0.1]])
            .unwrap_err()
            .to_string();
        assert!(e.contains("row 0 k"), "{e}");
        let e = SootOptics::for_fuel("methane").unwrap_err().to_string();
        assert!(
            e.contains("'methane'") && e.contains("propane, acetylene"),
            "{e}"
        );
        assert_eq!(
            SootOptics::for_fuel("Propane").unwrap(),
            SootOptics::propane()
        );
    }
}
