//! Spectral bins: the wavelength sampling of the `spectral` colour mode.
//!
//! A [`SpectralGrid`] splits [λ_min, λ_max] (vacuum wavelength, nm) into `count` equal bins; the default is the
//! thesis's 30 bins over 400–700 nm (10 nm each). A binned spectrum holds, per bin, the **mean** spectral
//! radiance over the bin (W·m⁻²·sr⁻¹·nm⁻¹), so that a line of total radiance L falling into a bin of width Δλ
//! is the value L/Δλ there (φ = 1/Δλ, P&P eq. 7) and keeps its energy when projected to XYZ with weights
//! integrated over the bins ([`crate::cie::bin_weights`]).

use crate::quadrature::gauss_legendre;
use crate::Error;

/// Equal-width bins over a vacuum-wavelength range, nm.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectralGrid {
    min_nm: f64,
    max_nm: f64,
    count: usize,
}

/// The accepted wavelength range for grids, nm (the physics is tested over 300–1000 nm).
pub const GRID_RANGE_NM: (f64, f64) = (200.0, 2000.0);
/// The largest accepted bin count.
pub const MAX_BINS: usize = 4096;

impl Default for SpectralGrid {
    /// 30 bins over 400–700 nm (Dorta-Perez 2015, section 4.3).
    fn default() -> Self {
        SpectralGrid {
            min_nm: 400.0,
            max_nm: 700.0,
            count: 30,
        }
    }
}

impl SpectralGrid {
    /// `count` bins over [`min_nm`, `max_nm`]; 1 ≤ count ≤ [`MAX_BINS`], bounds finite within
    /// [`GRID_RANGE_NM`] and min < max.
    pub fn new(min_nm: f64, max_nm: f64, count: usize) -> Result<Self, Error> {
        let (lo, hi) = GRID_RANGE_NM;
        for (name, v) in [("lambdamin", min_nm), ("lambdamax", max_nm)] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(Error::invalid(
                    "spectrum",
                    name,
                    v,
                    format!("a wavelength from {lo} to {hi} nm"),
                ));
            }
        }
        if min_nm >= max_nm {
            return Err(Error::invalid(
                "spectrum",
                "lambdamax",
                max_nm,
                format!("a wavelength above lambdamin = {min_nm} nm"),
            ));
        }
        if count == 0 || count > MAX_BINS {
            return Err(Error::invalid(
                "spectrum",
                "bins",
                count,
                format!("a bin count from 1 to {MAX_BINS}"),
            ));
        }
        Ok(SpectralGrid {
            min_nm,
            max_nm,
            count,
        })
    }

    /// Number of bins.
    pub fn count(&self) -> usize {
        self.count
    }
    /// Lower bound of the first bin, nm.
    pub fn min_nm(&self) -> f64 {
        self.min_nm
    }
    /// Upper bound of the last bin, nm.
    pub fn max_nm(&self) -> f64 {
        self.max_nm
    }
    /// Width of every bin, nm.
    pub fn width_nm(&self) -> f64 {
        (self.max_nm - self.min_nm) / self.count as f64
    }
    /// Edges [a, b) of bin `i`, nm. Consecutive bins share their edge exactly (no gaps from rounding).
    pub fn edges(&self, i: usize) -> (f64, f64) {
        (self.edge(i), self.edge(i + 1))
    }
    fn edge(&self, i: usize) -> f64 {
        if i >= self.count {
            self.max_nm
        } else {
            self.min_nm + i as f64 * self.width_nm()
        }
    }
    /// Centre of bin `i`, nm.
    pub fn centre(&self, i: usize) -> f64 {
        let (a, b) = self.edges(i);
        0.5 * (a + b)
    }
    /// Bin holding `lambda_nm` (bins are half-open [a, b); the last one also holds λ_max), or `None` outside.
    pub fn bin_of(&self, lambda_nm: f64) -> Option<usize> {
        if !(lambda_nm >= self.min_nm && lambda_nm <= self.max_nm) {
            return None;
        }
        let i = ((lambda_nm - self.min_nm) / self.width_nm()).floor() as usize;
        Some(i.min(self.count - 1))
    }
    /// The mean of `f(λ)` over each bin (4 Gauss–Legendre panels of 8 nodes per bin), e.g. the binned
    /// blackbody spectrum.
    pub fn bin_average(&self, f: impl Fn(f64) -> f64) -> Vec<f64> {
        (0..self.count)
            .map(|i| {
                let (a, b) = self.edges(i);
                gauss_legendre(&f, a, b, 4) / (b - a)
            })
            .collect()
    }
}

impl SpectralGrid {
    /// Gauss–Legendre nodes for bin means, `panels` panels of 8 per bin: (bin, λ nm, weight), so that a bin's
    /// mean of f is Σ weight·f(λ) over its nodes ([`bin_average`](Self::bin_average)'s with 4 panels).
    pub fn bin_nodes(&self, panels: usize) -> Vec<(usize, f64, f64)> {
        self.bin_nodes_split(&[], panels)
    }

    /// As [`bin_nodes`](Self::bin_nodes), with each bin first cut at the `breaks` inside it (wavelengths, nm,
    /// where the integrand has a kink — a table linear between its rows, as soot's optical constants), then
    /// `panels` panels of 8 per piece: for an integrand smooth between the breaks, one panel per piece is
    /// exact to rounding where several panels across a kink are not (soot κ × Planck: 1e-14 against 5e-6
    /// for four panels; `volume` tests).
    pub fn bin_nodes_split(&self, breaks: &[f64], panels: usize) -> Vec<(usize, f64, f64)> {
        (0..self.count)
            .flat_map(|i| {
                let (a, b) = self.edges(i);
                let mut cuts = vec![a];
                let mut inside: Vec<f64> =
                    breaks.iter().copied().filter(|&x| x > a && x < b).collect();
                inside.sort_by(f64::total_cmp);
                cuts.extend(inside);
                cuts.push(b);
                let pieces: Vec<(f64, f64)> = cuts.windows(2).map(|w| (w[0], w[1])).collect();
                pieces.into_iter().flat_map(move |(p, q)| {
                    crate::quadrature::gauss_legendre_nodes(p, q, panels)
                        .into_iter()
                        .map(move |(x, w)| (i, x, w / (b - a)))
                })
            })
            .collect()
    }

    /// The mean of `f(λ)` over each bin by [`bin_nodes_split`](Self::bin_nodes_split)'s rule.
    pub fn bin_average_split(
        &self,
        f: impl Fn(f64) -> f64,
        breaks: &[f64],
        panels: usize,
    ) -> Vec<f64> {
        let mut out = vec![0.0; self.count];
        for (i, x, w) in self.bin_nodes_split(breaks, panels) {
            out[i] += w * f(x);
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_is_thirty_bins_over_400_700() {
        let g = SpectralGrid::default();
        assert_eq!(g.count(), 30);
        assert_eq!(g.width_nm(), 10.0);
        assert_eq!(g.edges(0), (400.0, 410.0));
        assert_eq!(g.edges(29), (690.0, 700.0));
        assert_eq!(g.centre(18), 585.0);
        assert_eq!(g.bin_of(589.0), Some(18));
        assert_eq!(g.bin_of(400.0), Some(0));
        assert_eq!(g.bin_of(700.0), Some(29));
        assert_eq!(g.bin_of(399.999), None);
        assert_eq!(g.bin_of(f64::NAN), None);
    }

    #[test]
    fn edges_tile_the_range() {
        let g = SpectralGrid::new(380.0, 780.0, 7).unwrap();
        let mut prev = 380.0;
        for i in 0..7 {
            let (a, b) = g.edges(i);
            assert_eq!(a, prev);
            prev = b;
        }
        assert_eq!(prev, 780.0);
    }

    #[test]
    fn bin_average_of_linear_is_centre_value() {
        let g = SpectralGrid::default();
        let v = g.bin_average(|l| 2.0 * l + 1.0);
        for (i, x) in v.iter().enumerate() {
            assert!((x - (2.0 * g.centre(i) + 1.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn invalid_grids_are_errors() {
        let e = SpectralGrid::new(700.0, 400.0, 30).unwrap_err().to_string();
        assert!(
            e.contains("lambdamax") && e.contains("400") && e.contains("700"),
            "{e}"
        );
        let e = SpectralGrid::new(400.0, 700.0, 0).unwrap_err().to_string();
        assert!(e.contains("bins") && e.contains("= 0"), "{e}");
        assert!(SpectralGrid::new(f64::NAN, 700.0, 3).is_err());
        assert!(SpectralGrid::new(100.0, 700.0, 3).is_err());
        assert!(SpectralGrid::new(400.0, 700.0, MAX_BINS + 1).is_err());
    }
}
