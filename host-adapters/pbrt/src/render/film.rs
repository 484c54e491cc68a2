//! The film's response, as pbrt-v4's `RGBFilm` with the `cie1931` sensor (`src/pbrt/film.cpp`): the imaging
//! ratio (exposure time × ISO / 100, with the exposure time the camera's shutter interval), an optional white
//! balance, each sample's largest RGB component clamped to `maxcomponentvalue`, and half- or full-float output.
//!
//! White balance (`whitebalance` T, in K): a von Kries adaptation in Bradford's LMS (pbrt-v4's `WhiteBalance`,
//! Lindbloom's matrices) from the white of CIE daylight at T to sRGB's D65. The daylight white is the CIE daylight
//! locus (CIE 15:2004 §3.1: x_D a cubic in 10³/T over 4000–7000 K and 7000–25 000 K, y_D = −3x_D² + 2.870x_D −
//! 0.275), which is the chromaticity of pbrt-v4's `Spectra::D(T)` by construction.

use glam::{DMat3, DVec3};

/// Bradford's cone responses from XYZ (rows), as pbrt-v4's `LMSFromXYZ`.
const BRADFORD: [[f64; 3]; 3] = [
    [0.8951, 0.2664, -0.1614],
    [-0.7502, 1.7135, 0.0367],
    [0.0389, -0.0685, 1.0296],
];

/// The sRGB (D65) white point, xy.
const D65_XY: [f64; 2] = [0.3127, 0.3290];

/// How the film turns samples into pixels.
#[derive(Debug, Clone, PartialEq)]
pub struct Response {
    /// exposure time × ISO / 100 (1: pbrt-v4's pass-through default).
    pub imaging_ratio: f64,
    /// XYZ → XYZ white balance, when asked for.
    pub white_balance: Option<DMat3>,
    /// The largest linear-sRGB component a sample may have (pbrt-v4's `maxcomponentvalue`; infinite by default).
    pub max_component: f64,
    /// Half-float EXR channels (`savefp16`).
    pub fp16: bool,
    /// A named camera sensor's per-bin XYZ weights (its curves through its calibration matrix), replacing the
    /// CMFs' (`render::sensors`).
    pub camera: Option<Vec<DVec3>>,
}

impl Default for Response {
    fn default() -> Response {
        Response {
            imaging_ratio: 1.0,
            white_balance: None,
            max_component: f64::INFINITY,
            fp16: false,
            camera: None,
        }
    }
}

/// The chromaticity of CIE daylight at correlated colour temperature `t` (4000–25 000 K; clamped).
pub fn daylight_xy(t: f64) -> [f64; 2] {
    let t = t.clamp(4000.0, 25_000.0);
    let (a, b) = (1e3 / t, 1e6 / (t * t));
    let c = 1e9 / (t * t * t);
    let x = if t <= 7000.0 {
        -4.6070 * c + 2.9678 * b + 0.09911 * a + 0.244063
    } else {
        -2.0064 * c + 1.9018 * b + 0.24748 * a + 0.237040
    };
    [x, -3.0 * x * x + 2.870 * x - 0.275]
}

/// The XYZ → XYZ von Kries adaptation (Bradford LMS) taking white `from` (xy) to white `to` (xy).
pub fn white_balance(from: [f64; 2], to: [f64; 2]) -> DMat3 {
    let m = DMat3::from_cols_array_2d(&BRADFORD).transpose();
    let xyz = |w: [f64; 2]| DVec3::new(w[0] / w[1], 1.0, (1.0 - w[0] - w[1]) / w[1]);
    let (src, dst) = (m * xyz(from), m * xyz(to));
    m.inverse() * DMat3::from_diagonal(dst / src) * m
}

impl Response {
    /// The response for a film's `iso`, `whitebalance` (K; 0: none) and `maxcomponentvalue`, and the camera's
    /// shutter interval.
    pub fn new(iso: f64, exposure: f64, white_k: f64, max_component: f64, fp16: bool) -> Response {
        Response {
            imaging_ratio: exposure * iso / 100.0,
            white_balance: (white_k > 0.0).then(|| white_balance(daylight_xy(white_k), D65_XY)),
            max_component,
            fp16,
            camera: None,
        }
    }

    /// A sample's XYZ as the sensor records it (before the imaging ratio): the bins' CIE weights, or a named
    /// camera's.
    pub fn sensor_xyz(
        &self,
        bins: &crate::render::spectrum::Bins,
        s: &crate::render::spectrum::S,
    ) -> DVec3 {
        match &self.camera {
            Some(w) => w.iter().zip(s.0.iter()).map(|(w, &v)| *w * v as f64).sum(),
            None => bins.to_xyz(s),
        }
    }

    /// A sample's XYZ with its largest sRGB component clamped (pbrt-v4 clamps before filtering).
    pub fn clamp_sample(&self, xyz: DVec3) -> DVec3 {
        if !self.max_component.is_finite() {
            return xyz;
        }
        let m = firemedium_core::cie::xyz_to_linear_srgb(xyz).max_element();
        if m > self.max_component {
            xyz * (self.max_component / m)
        } else {
            xyz
        }
    }

    /// A pixel's final XYZ from its filtered XYZ.
    pub fn finish(&self, xyz: DVec3) -> DVec3 {
        let xyz = xyz * self.imaging_ratio;
        match &self.white_balance {
            Some(m) => *m * xyz,
            None => xyz,
        }
    }
}

/// pbrt-v4's `spectral` film: `n` equal buckets over [lambdamin, lambdamax] nm, each pixel's mean spectral
/// radiance in each (× the imaging ratio), written as EXR channels `S0.<centre>nm` beside R, G, B (the OpenEXR
/// spectral layout, the decimal point as a comma). The renderer's bins are resampled into the buckets by overlap;
/// where the buckets reach beyond the bins (pbrt-v4's default 360–830 nm against 380–780), the radiance is 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Buckets {
    pub n: usize,
    pub lo: f64,
    pub hi: f64,
}

impl Buckets {
    /// The buckets' centre wavelengths.
    pub fn centres(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| self.lo + (i as f64 + 0.5) / self.n as f64 * (self.hi - self.lo))
            .collect()
    }

    /// The mean of the bins' piecewise-constant spectrum `s` over each bucket.
    pub fn resample(&self, bins: &crate::render::spectrum::Bins, s: &[f64]) -> Vec<f32> {
        let width = (self.hi - self.lo) / self.n as f64;
        (0..self.n)
            .map(|k| {
                let (a, b) = (self.lo + k as f64 * width, self.lo + (k + 1) as f64 * width);
                let covered: f64 = (0..bins.n())
                    .map(|i| {
                        let (c, d) = bins.grid.edges(i);
                        (b.min(d) - a.max(c)).max(0.0) * s[i]
                    })
                    .sum();
                (covered / width) as f32
            })
            .collect()
    }
}

/// pbrt-v4's `gbuffer` film: beside R, G, B, per pixel the first visible surface's filter-weighted mean albedo,
/// position, depth slopes and normals, in camera space (`"string coordinatesystem" "camera"`, the default) or
/// world space, and the variance of the sensor values of the samples that saw a surface — the channels and the
/// normalisation of pbrt-v4's `GBufferFilm::GetImage` (sums over samples with a surface divided by the weight of
/// all samples; normals renormalised; |dz/dx|, |dz/dy|).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GBuffer {
    /// World space instead of camera space.
    pub world: bool,
}

/// The gbuffer film's channels after R, G, B, in pbrt-v4's order.
pub const GBUFFER_CHANNELS: [&str; 20] = [
    "Albedo.R",
    "Albedo.G",
    "Albedo.B",
    "Px",
    "Py",
    "Pz",
    "dzdx",
    "dzdy",
    "Nx",
    "Ny",
    "Nz",
    "Nsx",
    "Nsy",
    "Nsz",
    "Variance.R",
    "Variance.G",
    "Variance.B",
    "RelativeVariance.R",
    "RelativeVariance.G",
    "RelativeVariance.B",
];

/// One sample's visible surface, in the gbuffer's space.
#[derive(Debug, Clone, Copy, Default)]
pub struct GSample {
    pub albedo_rgb: DVec3,
    pub p: DVec3,
    pub n: DVec3,
    pub ns: DVec3,
    pub dzdx: f64,
    pub dzdy: f64,
}

/// A pixel's gbuffer sums.
#[derive(Debug, Clone, Default)]
pub struct GPixel {
    sum: GSample,
    /// Welford's running mean and sum of squared deviations of the sensor values, per component.
    n: f64,
    mean: DVec3,
    m2: DVec3,
}

impl GPixel {
    /// Adds a sample of filter weight `w` that saw `v`, its sensor value `sensor`.
    pub fn add(&mut self, w: f64, v: &GSample, sensor: DVec3) {
        let s = &mut self.sum;
        s.albedo_rgb += w * v.albedo_rgb;
        s.p += w * v.p;
        s.n += w * v.n;
        s.ns += w * v.ns;
        s.dzdx += w * v.dzdx;
        s.dzdy += w * v.dzdy;
        self.n += 1.0;
        let delta = sensor - self.mean;
        self.mean += delta / self.n;
        self.m2 += delta * (sensor - self.mean);
    }

    /// The pixel's channels ([`GBUFFER_CHANNELS`]) given the weight of all its samples.
    pub fn finish(&self, weights: f64) -> [f32; 20] {
        let k = if weights != 0.0 { 1.0 / weights } else { 1.0 };
        let s = &self.sum;
        let (a, p) = (s.albedo_rgb * k, s.p * k);
        let (n, ns) = (s.n.normalize_or_zero(), s.ns.normalize_or_zero());
        let var = if self.n > 1.0 {
            self.m2 / (self.n - 1.0)
        } else {
            DVec3::ZERO
        };
        let rel = |c: usize| {
            if self.n < 1.0 || self.mean[c] == 0.0 {
                0.0
            } else {
                var[c] / self.mean[c]
            }
        };
        [
            a.x,
            a.y,
            a.z,
            p.x,
            p.y,
            p.z,
            (s.dzdx * k).abs(),
            (s.dzdy * k).abs(),
            n.x,
            n.y,
            n.z,
            ns.x,
            ns.y,
            ns.z,
            var.x,
            var.y,
            var.z,
            rel(0),
            rel(1),
            rel(2),
        ]
        .map(|v| if v.is_finite() { v as f32 } else { 0.0 })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn daylight_and_white_balance() {
        // CIE 15:2004 Table T.3: D65 (6504 K) at (0.31272, 0.32903), D50 (5003 K) at (0.34567, 0.35851).
        for (t, want) in [(6504.0, [0.31272, 0.32903]), (5003.0, [0.34567, 0.35851])] {
            let xy = daylight_xy(t);
            assert!(
                (xy[0] - want[0]).abs() < 2e-4 && (xy[1] - want[1]).abs() < 2e-4,
                "{t}: {xy:?}"
            );
        }
        // Balancing for D50 takes D50's white to D65's and leaves luminance alone.
        let d50 = daylight_xy(5003.0);
        let m = white_balance(d50, D65_XY);
        let w = m * DVec3::new(d50[0] / d50[1], 1.0, (1.0 - d50[0] - d50[1]) / d50[1]);
        let s = w.x + w.y + w.z;
        assert!(
            (w.x / s - 0.3127).abs() < 1e-9 && (w.y / s - 0.3290).abs() < 1e-9,
            "{w}"
        );
        assert!((w.y - 1.0).abs() < 0.02, "{w}");
        // The imaging ratio: ISO 400 for 1/4 s is 1.
        assert_eq!(
            Response::new(400.0, 0.25, 0.0, f64::INFINITY, false).imaging_ratio,
            1.0
        );
        // Clamping keeps the chromaticity.
        let r = Response::new(100.0, 1.0, 0.0, 2.0, false);
        let xyz = DVec3::new(9.5, 10.0, 10.9);
        let c = r.clamp_sample(xyz);
        assert!((firemedium_core::cie::xyz_to_linear_srgb(c).max_element() - 2.0).abs() < 1e-9);
        assert!((c / c.y - xyz / xyz.y).abs().max_element() < 1e-12);
    }

    #[test]
    fn a_gbuffer_pixel_is_pbrt_v4s_weighted_means_and_variance() {
        // Samples of weight 1, 1, 2 seeing surfaces; a fourth (weight 4) seeing nothing only adds to the weights.
        let mut g = GPixel::default();
        for (w, x, z) in [(1.0, 1.0, 2.0), (1.0, 2.0, 4.0), (2.0, 3.0, 6.0)] {
            let v = GSample {
                albedo_rgb: DVec3::splat(0.5),
                p: DVec3::new(x, 0.0, z),
                n: DVec3::new(0.0, 0.0, -2.0),
                ns: DVec3::new(0.0, 1.0, -1.0),
                dzdx: -0.25,
                dzdy: 0.5,
            };
            g.add(w, &v, DVec3::new(x, 2.0 * x, 0.0));
        }
        let c = g.finish(8.0);
        // Σ w v / Σ w over all samples (8): albedo 0.5·4/8, Px (1 + 2 + 6)/8, Pz (2 + 4 + 12)/8.
        assert_eq!(&c[..3], &[0.25; 3]);
        assert_eq!((c[3], c[5]), (9.0 / 8.0, 18.0 / 8.0));
        assert_eq!((c[6], c[7]), (0.125, 0.25));
        // Normals renormalised.
        assert_eq!(&c[8..11], &[0.0, 0.0, -1.0]);
        assert!((c[12] - 0.5f32.sqrt()).abs() < 1e-6);
        // Sensor values 1, 2, 3 (unweighted, as pbrt-v4's VarianceEstimator): variance 1, relative variance
        // variance / mean = ½; twice that in G; 0 where the mean is 0.
        assert_eq!(&c[14..17], &[1.0, 4.0, 0.0]);
        assert_eq!(&c[17..20], &[0.5, 1.0, 0.0]);
    }
}
