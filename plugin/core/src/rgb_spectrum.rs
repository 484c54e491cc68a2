//! RGB → spectrum, as pbrt-v4 turns a scene's `rgb` values into spectra: the sigmoid-polynomial spectra of
//! Jakob & Hanika, *A Low-Dimensional Function Space for Efficient Spectral Upsampling* (EGSR 2019), and
//! pbrt-v4's three uses of them (`RGBAlbedoSpectrum`, `RGBUnboundedSpectrum`, `RGBIlluminantSpectrum`,
//! `src/pbrt/util/spectrum.h`).
//!
//! A spectrum s(λ) = S(c₀t² + c₁t + c₂), S(x) = ½ + x / (2√(1 + x²)), with t = (λ − 380 nm)/400 nm (a
//! reparametrisation of pbrt's polynomial in λ: the same function space, better conditioned). Its colour is
//! that of a reflectance under the colour space's illuminant (D65 for sRGB):
//! rgb(s) = M_XYZ→sRGB ∫ s(λ) D65(λ) x̄ȳz̄(λ) dλ / ∫ D65(λ) ȳ(λ) dλ,
//! so s ≡ 1 is white (1, 1, 1). [`Sigmoid::fit`] finds the coefficients whose colour is a given rgb by damped
//! Gauss–Newton, walking from the grey of the same mean along the straight line to the target (Jakob & Hanika
//! fill their table the same way, from the grey axis outward). Where pbrt-v4 interpolates a precomputed 64³ table
//! of such fits, this fits each distinct rgb exactly; colours on the gamut's boundary (a channel of 0 or 1 with
//! others apart) cannot be reached by a sigmoid and end at the least-squares spectrum in rgb (pbrt minimises in
//! CIELAB: the two differ only there).
//!
//! D65 is CIE 15:2004 Table T.1 (relative spectral power, 5 nm, 380–780 nm), linear between samples and zero
//! outside, as the CMFs of [`crate::cie`].

use crate::cie::{self, cmf_table::CMF, cmf_table::CMF_START_NM};
use glam::{DMat3, DVec3};

/// CIE standard illuminant D65, relative spectral power at 380, 385, …, 780 nm (CIE 15:2004 Table T.1;
/// 100 at 560 nm).
pub const D65_5NM: [f64; 81] = [
    49.9755, 52.3118, 54.6482, 68.7015, 82.7549, 87.1204, 91.4860, 92.4589, 93.4318, 90.0570,
    86.6823, 95.7736, 104.8650, 110.9360, 117.0080, 117.4100, 117.8120, 116.3360, 114.8610,
    115.3920, 115.9230, 112.3670, 108.8110, 109.0820, 109.3540, 108.5780, 107.8020, 106.2960,
    104.7900, 106.2390, 107.6890, 106.0470, 104.4050, 104.2250, 104.0460, 102.0230, 100.0000,
    98.1671, 96.3342, 96.0611, 95.7880, 92.2368, 88.6856, 89.3459, 90.0062, 89.8026, 89.5991,
    88.6489, 87.6987, 85.4936, 83.2886, 83.4939, 83.6992, 81.8630, 80.0268, 80.1207, 80.2146,
    81.2462, 82.2778, 80.2810, 78.2842, 74.0027, 69.7213, 70.6652, 71.6091, 72.9790, 74.3490,
    67.9765, 61.6040, 65.7448, 69.8856, 72.4863, 75.0870, 69.3398, 63.5927, 55.0054, 46.4182,
    56.6118, 66.8054, 65.0941, 63.3828,
];

/// D65 at `lambda_nm` (relative, 100 at 560 nm); zero outside 380–780 nm.
pub fn d65(lambda_nm: f64) -> f64 {
    let x = (lambda_nm - 380.0) / 5.0;
    if !(0.0..=80.0).contains(&x) {
        return 0.0;
    }
    let i = (x as usize).min(79);
    let f = x - i as f64;
    D65_5NM[i] * (1.0 - f) + D65_5NM[i + 1] * f
}

/// ∫ D65(λ) ȳ(λ) dλ over the 1 nm CMF table: the luminance of [`d65`] before normalisation.
pub fn d65_luminance() -> f64 {
    CMF.iter()
        .enumerate()
        .map(|(i, c)| d65(CMF_START_NM + i as f64) * c[1])
        .sum()
}

/// The sigmoid S(x) = ½ + x / (2√(1 + x²)), finite for every x (±∞ → 1 or 0).
fn sigmoid(x: f64) -> f64 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// A sigmoid-polynomial spectrum, values in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sigmoid {
    /// c₀, c₁, c₂ of the polynomial in t = (λ − 380)/400.
    pub c: [f64; 3],
}

/// D65-weighted CMFs per nm over the table, normalised so a spectrum of 1 has Y = 1, then taken to linear sRGB:
/// rgb(s) = Σ s(λᵢ) w(λᵢ).
fn rgb_weights() -> &'static [DVec3; 401] {
    static W: std::sync::OnceLock<[DVec3; 401]> = std::sync::OnceLock::new();
    W.get_or_init(|| {
        let m: DMat3 = cie::xyz_to_srgb_matrix();
        let norm = 1.0 / d65_luminance();
        let mut w = [DVec3::ZERO; 401];
        for (i, c) in CMF.iter().enumerate() {
            w[i] = m * (DVec3::from_array(*c) * d65(CMF_START_NM + i as f64) * norm);
        }
        w
    })
}

impl Sigmoid {
    /// The constant spectrum `v` (clamped to [0, 1]): pbrt-v4's grey case, exact.
    pub fn constant(v: f64) -> Sigmoid {
        let v = v.clamp(0.0, 1.0);
        let c2 = if v <= 0.0 {
            f64::NEG_INFINITY
        } else if v >= 1.0 {
            f64::INFINITY
        } else {
            (v - 0.5) / (v * (1.0 - v)).sqrt()
        };
        Sigmoid { c: [0.0, 0.0, c2] }
    }

    /// The value at `lambda_nm`.
    pub fn eval(&self, lambda_nm: f64) -> f64 {
        let t = (lambda_nm - 380.0) / 400.0;
        if self.c[0] == 0.0 && self.c[1] == 0.0 {
            return sigmoid(self.c[2]);
        }
        sigmoid((self.c[0] * t + self.c[1]) * t + self.c[2])
    }

    /// Its colour as a reflectance under D65 (linear sRGB; s ≡ 1 is (1, 1, 1)).
    pub fn rgb(&self) -> DVec3 {
        rgb_weights()
            .iter()
            .enumerate()
            .map(|(i, w)| *w * self.eval(CMF_START_NM + i as f64))
            .sum()
    }

    /// The spectrum whose [`Sigmoid::rgb`] is `rgb` (times white's rgb), each channel clamped to [0, 1] (an
    /// albedo); greys exactly, other colours to within 1e-6 where a sigmoid reaches them, else the nearest in rgb.
    pub fn fit(rgb: [f64; 3]) -> Sigmoid {
        let target = DVec3::from_array(rgb.map(|v| {
            if v.is_finite() {
                v.clamp(0.0, 1.0)
            } else {
                0.0
            }
        }));
        if target.x == target.y && target.y == target.z {
            return Sigmoid::constant(target.x);
        }
        // Start on the grey axis (its mean), kept off 0 and 1 where the constant needs infinite coefficients.
        let grey = ((target.x + target.y + target.z) / 3.0).clamp(0.02, 0.98);
        let mut s = Sigmoid::constant(grey);
        // Colours are matched relative to white's own (D65 through the rounded sRGB matrix is white to 2e-3), so
        // that fits stay continuous across the grey axis, where constants are exact.
        let white = Sigmoid::constant(1.0).rgb();
        let (start, target) = (white * grey, white * target);
        const STEPS: usize = 16;
        for k in 1..=STEPS {
            let goal = start.lerp(target, k as f64 / STEPS as f64);
            s = s.newton(goal, if k == STEPS { 40 } else { 6 });
        }
        s
    }

    /// Damped Gauss–Newton toward `goal` (3 equations, 3 unknowns; the step halves until the residual falls).
    fn newton(mut self, goal: DVec3, iterations: usize) -> Sigmoid {
        let mut r = self.rgb() - goal;
        for _ in 0..iterations {
            if r.length() < 1e-9 {
                break;
            }
            let h = 1e-5;
            let mut cols = [DVec3::ZERO; 3];
            for (j, col) in cols.iter_mut().enumerate() {
                let mut p = self;
                p.c[j] += h;
                *col = (p.rgb() - goal - r) / h;
            }
            let jac = DMat3::from_cols(cols[0], cols[1], cols[2]);
            // Levenberg–Marquardt's normal equations: never singular, and a plain Newton step near the solution.
            let jt = jac.transpose();
            let jtj = jt * jac;
            let damp = 1e-9 * (jtj.x_axis.x + jtj.y_axis.y + jtj.z_axis.z).max(1e-12);
            let a = jtj + DMat3::from_diagonal(DVec3::splat(damp));
            if a.determinant().abs() < 1e-300 {
                break;
            }
            let step = a.inverse() * (jt * -r);
            let mut t = 1.0;
            let mut improved = false;
            for _ in 0..20 {
                let mut p = self;
                for j in 0..3 {
                    p.c[j] += t * step[j];
                }
                let rp = p.rgb() - goal;
                if rp.is_finite() && rp.length() < r.length() {
                    self = p;
                    r = rp;
                    improved = true;
                    break;
                }
                t *= 0.5;
            }
            if !improved {
                break;
            }
        }
        self
    }
}

/// How a scene uses an rgb value (pbrt-v4's `SpectrumType`), and so which spectrum it becomes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RgbUse {
    /// A reflectance or transmittance: the fit of rgb clamped to [0, 1] (`RGBAlbedoSpectrum`).
    Albedo,
    /// Any non-negative quantity (σ_a, σ_s): 2m · fit(rgb / 2m), m = max(rgb) (`RGBUnboundedSpectrum`).
    Unbounded,
    /// An emitter: 2m · fit(rgb / 2m) · D65(λ) / ∫D65 ȳ, so rgb (1, 1, 1) is D65 of luminance 1
    /// (`RGBIlluminantSpectrum` with pbrt's normalised illuminant and the light's photometric scale).
    Illuminant,
}

/// The spectrum of a scene's rgb value, as a function of λ (nm). Negative and non-finite channels count as 0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RgbSpectrum {
    scale: f64,
    sigmoid: Sigmoid,
    illuminant: bool,
}

impl RgbSpectrum {
    pub fn new(rgb: [f64; 3], usage: RgbUse) -> RgbSpectrum {
        let rgb = rgb.map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 });
        match usage {
            RgbUse::Albedo => RgbSpectrum {
                scale: 1.0,
                sigmoid: Sigmoid::fit(rgb),
                illuminant: false,
            },
            RgbUse::Unbounded | RgbUse::Illuminant => {
                let m = rgb[0].max(rgb[1]).max(rgb[2]);
                let (scale, sigmoid) = if m > 0.0 {
                    (2.0 * m, Sigmoid::fit(rgb.map(|v| v / (2.0 * m))))
                } else {
                    (0.0, Sigmoid::constant(0.0))
                };
                RgbSpectrum {
                    scale,
                    sigmoid,
                    illuminant: usage == RgbUse::Illuminant,
                }
            }
        }
    }

    /// The value at `lambda_nm`.
    pub fn eval(&self, lambda_nm: f64) -> f64 {
        let s = self.scale * self.sigmoid.eval(lambda_nm);
        if self.illuminant {
            s * d65(lambda_nm) / d65_luminance()
        } else {
            s
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn xyz_of(f: impl Fn(f64) -> f64) -> DVec3 {
        CMF.iter()
            .enumerate()
            .map(|(i, c)| DVec3::from_array(*c) * f(CMF_START_NM + i as f64))
            .sum()
    }

    #[test]
    fn d65_is_the_srgb_white_point() {
        // D65's chromaticity (CIE 15:2004: x = 0.31272, y = 0.32903 for the 1931 observer).
        let (x, y) = cie::chromaticity(xyz_of(d65));
        assert!(
            (x - 0.31272).abs() < 2e-4 && (y - 0.32903).abs() < 2e-4,
            "({x}, {y})"
        );
        // ∫ D65 ȳ over 380–780 at 1 nm: 10 567 (D65 at 100 for 560 nm).
        assert!(
            (d65_luminance() / 10_567.0 - 1.0).abs() < 2e-3,
            "{}",
            d65_luminance()
        );
    }

    #[test]
    fn greys_are_constants_and_white_is_white() {
        for v in [0.0, 0.18, 0.5, 0.9, 1.0] {
            let s = Sigmoid::fit([v, v, v]);
            for l in [380.0, 500.0, 780.0] {
                assert!((s.eval(l) - v).abs() < 1e-12, "{v} at {l}: {}", s.eval(l));
            }
        }
        let w = Sigmoid::constant(1.0).rgb();
        assert!((w - DVec3::ONE).abs().max_element() < 2e-3, "{w}");
    }

    #[test]
    fn fits_reproduce_reachable_colours() {
        for rgb in [
            [0.8, 0.3, 0.2],
            [0.2, 0.5, 0.7],
            [0.05, 0.05, 0.6],
            [0.45, 0.4, 0.05],
            [0.5, 0.25, 0.0625],
        ] {
            let s = Sigmoid::fit(rgb);
            let back = s.rgb();
            // Relative to white's own rounding (D65 through the sRGB matrix is white to 2e-3).
            let white = Sigmoid::constant(1.0).rgb();
            let want = DVec3::from_array(rgb) * white;
            assert!((back - want).abs().max_element() < 1e-6, "{rgb:?} → {back}");
            for l in (380..=780).step_by(10) {
                let v = s.eval(l as f64);
                assert!((0.0..=1.0).contains(&v));
            }
        }
    }

    #[test]
    fn saturated_colours_end_near_the_target() {
        // Not reachable by a sigmoid: the least-squares spectrum, still a valid reflectance.
        let s = Sigmoid::fit([1.0, 0.0, 0.0]);
        let back = s.rgb();
        assert!(back.x > 0.8 && back.y < 0.1 && back.z < 0.1, "{back}");
    }

    #[test]
    fn illuminants_have_the_luminance_of_their_rgb() {
        // pbrt-v4: an `rgb L [1 1 1]` light records Y = 1 and rgb (1, 1, 1); [2 2 2] twice that; a coloured light
        // the luminance of its rgb.
        for (rgb, y) in [
            ([1.0, 1.0, 1.0], 1.0),
            ([2.0, 2.0, 2.0], 2.0),
            (
                [1.0, 0.5, 0.25],
                0.2126729 + 0.7151522 * 0.5 + 0.0721750 * 0.25,
            ),
        ] {
            let s = RgbSpectrum::new(rgb, RgbUse::Illuminant);
            let got = xyz_of(|l| s.eval(l)).y;
            assert!((got - y).abs() < 3e-3 * y, "{rgb:?}: Y {got}, expected {y}");
        }
        let s = RgbSpectrum::new([3.0, 3.0, 3.0], RgbUse::Unbounded);
        assert!((s.eval(550.0) - 3.0).abs() < 1e-12);
        assert_eq!(
            RgbSpectrum::new([0.0; 3], RgbUse::Illuminant).eval(550.0),
            0.0
        );
        assert_eq!(
            RgbSpectrum::new([f64::NAN, -1.0, 0.0], RgbUse::Albedo).eval(550.0),
            0.0
        );
    }
}
