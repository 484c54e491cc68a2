//! The renderer's colour: every quantity is a spectrum over the same bins as the fire volumes (so radiance,
//! reflectance and transmittance multiply bin by bin), converted to absolute XYZ only at the film.
//!
//! Scene spectra become bins as follows: `spectrum` (λ, value) pairs and `blackbody` are averaged over each bin
//! exactly; constant `rgb` values become pbrt-v4's spectra of their use (core's `rgb_spectrum`: sigmoid
//! polynomials as reflectances, unbounded σ's, or illuminants times D65); image textures, whose texels mix
//! linearly, use a box basis (blue below 490 nm, green to 580 nm, red above: white stays flat, saturated colours
//! are approximate), times D65 for emitted maps.

use firemedium_core::blackbody::{spectral_radiance, WIEN};
use firemedium_core::cie;
use firemedium_core::quadrature::gauss_legendre;
use firemedium_core::rgb_spectrum::{d65, d65_luminance, RgbSpectrum, RgbUse};
use firemedium_core::spectrum::SpectralGrid;
use glam::DVec3;

/// Largest channel count the renderer supports.
pub const MAX_CHANNELS: usize = 64;

/// A spectrum over the render bins (unused channels are zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct S(pub [f32; MAX_CHANNELS]);

impl Default for S {
    fn default() -> S {
        S::ZERO
    }
}

impl S {
    pub const ZERO: S = S([0.0; MAX_CHANNELS]);
    #[inline]
    pub fn splat(v: f32) -> S {
        S([v; MAX_CHANNELS])
    }
    #[inline]
    pub fn max(&self) -> f32 {
        self.0.iter().copied().fold(0.0, f32::max)
    }
    #[inline]
    pub fn is_black(&self) -> bool {
        self.0.iter().all(|&v| v == 0.0)
    }
    #[inline]
    pub fn finite_or_zero(self) -> S {
        S(self.0.map(|v| if v.is_finite() { v } else { 0.0 }))
    }
}

macro_rules! op {
    ($t:ident, $f:ident, $op:tt) => {
        impl std::ops::$t for S {
            type Output = S;
            #[inline]
            fn $f(self, o: S) -> S {
                let mut r = self;
                for i in 0..MAX_CHANNELS {
                    r.0[i] = self.0[i] $op o.0[i];
                }
                r
            }
        }
        impl std::ops::$t<f32> for S {
            type Output = S;
            #[inline]
            fn $f(self, o: f32) -> S {
                S(self.0.map(|v| v $op o))
            }
        }
    };
}
op!(Add, add, +);
op!(Mul, mul, *);
op!(Sub, sub, -);
op!(Div, div, /);

impl std::ops::AddAssign for S {
    #[inline]
    fn add_assign(&mut self, o: S) {
        *self = *self + o;
    }
}
impl std::ops::MulAssign for S {
    #[inline]
    fn mul_assign(&mut self, o: S) {
        *self = *self * o;
    }
}

/// The render bins and their XYZ weights.
#[derive(Debug, Clone)]
pub struct Bins {
    pub grid: SpectralGrid,
    /// XYZ per unit radiance in each bin: K times the plugin's bin weights (`cie::bin_weights`: the CMFs
    /// integrated against the spectrum rebuilt from its bin means, as the fire volume's channels use), K = 683
    /// lm/W (absolute) or 1/∫ȳ (pbrt's relative units).
    pub xyz: Vec<DVec3>,
}

impl Bins {
    pub fn new(grid: SpectralGrid, k: f64) -> Bins {
        let xyz = cie::bin_weights(&grid)
            .into_iter()
            .map(|w| w / firemedium_core::constants::LUMINOUS_EFFICACY * k)
            .collect();
        Bins { grid, xyz }
    }
    pub fn n(&self) -> usize {
        self.grid.count()
    }
    /// Bin means of a function of λ (nm).
    pub fn bin_means(&self, f: impl Fn(f64) -> f64) -> S {
        let mut s = S::ZERO;
        for i in 0..self.n() {
            let (a, b) = self.grid.edges(i);
            s.0[i] = (gauss_legendre(&f, a, b, 2) / (b - a)) as f32;
        }
        s
    }
    /// pbrt-v4's spectrum of an rgb value used as `usage` (illuminants: D65 of luminance 1 for rgb (1, 1, 1)).
    pub fn uplift(&self, rgb: [f64; 3], usage: RgbUse) -> S {
        let s = RgbSpectrum::new(rgb, usage);
        self.bin_means(|l| s.eval(l))
    }
    /// CIE D65 scaled to luminance 1 (the default spectrum of pbrt-v4's lights: the colour space's illuminant).
    pub fn d65(&self) -> S {
        let y = d65_luminance();
        self.bin_means(|l| d65(l) / y)
    }
    /// The film's luminance of a spectrum (what pbrt-v4's photometric light normalisation divides by, taken over
    /// the film's own bins so that a normalised light records exactly its luminance).
    pub fn luminance(&self, s: &S) -> f64 {
        self.to_xyz(s).y
    }
    /// The box uplift of an RGB triple.
    pub fn uplift_rgb(&self, rgb: [f64; 3]) -> S {
        let mut s = S::ZERO;
        for i in 0..self.n() {
            let c = self.grid.centre(i);
            s.0[i] = if c < 490.0 {
                rgb[2]
            } else if c < 580.0 {
                rgb[1]
            } else {
                rgb[0]
            } as f32;
        }
        s
    }
    /// pbrt-v4's blackbody: Planck at T normalised to 1 at its peak.
    pub fn blackbody(&self, t: f64) -> S {
        if !(t > 0.0) {
            return S::ZERO;
        }
        let peak = spectral_radiance(t, WIEN / t * 1e9);
        self.bin_means(|l| spectral_radiance(t, l) / peak)
    }
    /// (λ, value) pairs, linear between, zero outside; or one constant.
    pub fn pairs(&self, v: &[f64]) -> S {
        if v.len() == 1 {
            return S::splat(v[0] as f32) * self.mask();
        }
        let pairs: Vec<(f64, f64)> = v.chunks(2).map(|c| (c[0], c[1])).collect();
        self.bin_means(|l| {
            if pairs.is_empty() || l < pairs[0].0 || l > pairs[pairs.len() - 1].0 {
                return 0.0;
            }
            let i = pairs
                .partition_point(|p| p.0 <= l)
                .clamp(1, pairs.len().max(2) - 1);
            let (a, b) = (pairs[i - 1], pairs[i.min(pairs.len() - 1)]);
            if b.0 == a.0 {
                a.1
            } else {
                a.1 + (l - a.0) / (b.0 - a.0) * (b.1 - a.1)
            }
        })
    }
    /// 1 in the active channels.
    pub fn mask(&self) -> S {
        let mut s = S::ZERO;
        s.0[..self.n()].iter_mut().for_each(|v| *v = 1.0);
        s
    }
    /// Absolute XYZ of a spectrum.
    pub fn to_xyz(&self, s: &S) -> DVec3 {
        self.xyz
            .iter()
            .zip(s.0.iter())
            .map(|(w, &v)| *w * v as f64)
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_and_blackbody_colours() {
        let b = Bins::new(SpectralGrid::new(380.0, 780.0, 40).unwrap(), 683.0);
        // A flat 1 W m⁻² sr⁻¹ nm⁻¹: Y = 683 ∫ȳ ≈ 72 983 cd/m².
        assert!((b.to_xyz(&b.mask()).y / 72_983.0 - 1.0).abs() < 1e-3);
        let w = b.uplift_rgb([1.0, 1.0, 1.0]);
        assert_eq!(w, b.mask());
        // A 2000 K blackbody sits near the Planckian locus (0.5267, 0.4133).
        let xyz = b.to_xyz(&b.blackbody(2000.0));
        let (x, y) = (
            xyz.x / (xyz.x + xyz.y + xyz.z),
            xyz.y / (xyz.x + xyz.y + xyz.z),
        );
        assert!(
            (x - 0.5267).abs() < 3e-3 && (y - 0.4133).abs() < 3e-3,
            "({x}, {y})"
        );
        let p = b.pairs(&[200.0, 10.0, 900.0, 10.0]);
        assert!((p.0[5] - 10.0).abs() < 1e-4 && p.0[45] == 0.0);
    }
}
