//! Importance sampling of environment maps (pbrt-v4's `ImageInfiniteLight`): directions drawn from a
//! piecewise-constant density over the map's texels, proportional to their luminance times the solid angle a
//! texel covers (uniform for pbrt-v4's equal-area square, ∝ sin θ for a lat-long map).
//!
//! Each texel's weight is the largest luminance over it and its eight neighbours, since the bilinear lookup of
//! a point in one texel reads its neighbours too: the density is positive wherever the map's radiance is, so the
//! estimate stays unbiased; a small floor (1e-4 of the mean) keeps it so for maps with negative-clamped texels.

use super::distrib::Distribution2D;
use crate::imageio::RgbImage;
use std::f32::consts::PI;

/// The sampling density of one map.
#[derive(Debug)]
pub struct EnvSampler {
    w: usize,
    h: usize,
    equal_area: bool,
    cells: Distribution2D,
}

impl EnvSampler {
    /// The density for `img` (an equal-area square when `w == h`, else lat-long with θ down the rows).
    pub fn new(img: &RgbImage) -> EnvSampler {
        let (w, h) = (img.w.max(1), img.h.max(1));
        let equal_area = img.w == img.h;
        let lum = |x: i64, y: i64| -> f64 {
            let (x, y) = (x.clamp(0, w as i64 - 1), y.clamp(0, h as i64 - 1));
            let c = img
                .px
                .get(x as usize + w * y as usize)
                .copied()
                .unwrap_or([0.0; 3]);
            (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]).max(0.0) as f64
        };
        let mut weight = vec![0.0f64; w * h];
        for y in 0..h {
            // Solid angle per texel: uniform (equal-area) or sin θ at the row's centre (lat-long).
            let jac = if equal_area {
                1.0
            } else {
                (std::f64::consts::PI * (y as f64 + 0.5) / h as f64).sin()
            };
            for x in 0..w {
                let mut m = 0.0f64;
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        m = m.max(lum(x as i64 + dx, y as i64 + dy));
                    }
                }
                weight[x + w * y] = m * jac;
            }
        }
        let mean = weight.iter().sum::<f64>() / (w * h) as f64;
        let floor = if mean > 0.0 { 1e-4 * mean } else { 1.0 };
        weight.iter_mut().for_each(|v| *v += floor);
        EnvSampler {
            w,
            h,
            equal_area,
            cells: Distribution2D::new(&weight, w),
        }
    }

    /// A direction in the map's space and its density per steradian.
    pub fn sample(&self, u: [f32; 2]) -> ([f32; 3], f32) {
        let Some(c) = self.cells.sample([u[0] as f64, u[1] as f64]) else {
            return ([0.0, 0.0, 1.0], 0.0);
        };
        // Density in (s, t) ∈ [0, 1]²: the texel's share over its area 1/(w h).
        let p_st = (c.p * (self.w * self.h) as f64) as f32;
        let (s, t) = (
            ((c.x as f64 + c.fx) / self.w as f64) as f32,
            ((c.y as f64 + c.fy) / self.h as f64) as f32,
        );
        if self.equal_area {
            (equal_area_square_to_sphere([s, t]), p_st / (4.0 * PI))
        } else {
            // The lookup's parameterisation: s = ½ + φ/2π, t = θ/π.
            let (phi, theta) = ((s - 0.5) * 2.0 * PI, t * PI);
            let st = theta.sin();
            let d = [st * phi.cos(), st * phi.sin(), theta.cos()];
            (
                d,
                if st > 0.0 {
                    p_st / (2.0 * PI * PI * st)
                } else {
                    0.0
                },
            )
        }
    }
}

impl EnvSampler {
    /// The density per steradian with which [`sample`](Self::sample) picks the map-space direction `d`
    /// (unit length).
    pub fn pdf(&self, d: [f32; 3]) -> f32 {
        let [s, t] = if self.equal_area {
            equal_area_sphere_to_square(d)
        } else {
            [
                0.5 + d[1].atan2(d[0]) / (2.0 * PI),
                d[2].clamp(-1.0, 1.0).acos() / PI,
            ]
        };
        let x = ((s * self.w as f32) as usize).min(self.w - 1);
        let y = ((t * self.h as f32) as usize).min(self.h - 1);
        let p_st = (self.cells.prob(x, y) * (self.w * self.h) as f64) as f32;
        if self.equal_area {
            p_st / (4.0 * PI)
        } else {
            let st = (1.0 - d[2] * d[2]).max(0.0).sqrt();
            if st > 0.0 {
                p_st / (2.0 * PI * PI * st)
            } else {
                0.0
            }
        }
    }
}

/// The illuminance (lux, per unit of the map's luminance scale) a map gives a patch facing the map's +z: Σ over
/// texels above the horizon of luminance × cos θ × the texel's solid angle. pbrt-v4 (`lights.cpp`) weights each
/// texel of its equal-area map by 2π/(W H); the texels' solid angle is 4π/(W H), used here.
pub fn upper_illuminance(img: &RgbImage) -> f64 {
    let (w, h) = (img.w.max(1), img.h.max(1));
    let mut e = 0.0;
    for y in 0..h {
        for x in 0..w {
            let (s, t) = ((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
            let (z, d_omega) = if img.w == img.h {
                (
                    equal_area_square_to_sphere([s, t])[2] as f64,
                    4.0 * std::f64::consts::PI / (w * h) as f64,
                )
            } else {
                let theta = t as f64 * std::f64::consts::PI;
                (
                    theta.cos(),
                    2.0 * std::f64::consts::PI * std::f64::consts::PI * theta.sin()
                        / (w * h) as f64,
                )
            };
            if z > 0.0 {
                let c = img.px.get(x + w * y).copied().unwrap_or([0.0; 3]);
                let lum = (0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]).max(0.0) as f64;
                e += lum * z * d_omega;
            }
        }
    }
    e
}

/// The inverse of [`equal_area_sphere_to_square`]: (u, v) in [0, 1]² → a unit direction.
pub fn equal_area_square_to_sphere(p: [f32; 2]) -> [f32; 3] {
    let (u, v) = (2.0 * p[0] - 1.0, 2.0 * p[1] - 1.0);
    let (up, vp) = (u.abs(), v.abs());
    let signed = 1.0 - (up + vp);
    let r = 1.0 - signed.abs();
    let phi = if r == 0.0 { 1.0 } else { (vp - up) / r + 1.0 } * std::f32::consts::FRAC_PI_4;
    let z = (1.0 - r * r).copysign(signed);
    let s = r * (2.0 - r * r).max(0.0).sqrt();
    [phi.cos().copysign(u) * s, phi.sin().copysign(v) * s, z]
}

/// pbrt-v4's equal-area octahedral map (Clarberg 2008): a unit direction → (u, v) in [0, 1]².
pub fn equal_area_sphere_to_square(d: [f32; 3]) -> [f32; 2] {
    let (x, y, z) = (d[0].abs(), d[1].abs(), d[2].abs());
    let r = (1.0 - z).max(0.0).sqrt();
    let (a, b) = (x.max(y), x.min(y));
    let b = if a == 0.0 { 0.0 } else { b / a };
    let mut phi = b.atan() * std::f32::consts::FRAC_2_PI;
    if x < y {
        phi = 1.0 - phi;
    }
    let mut v = phi * r;
    let mut u = r - v;
    if d[2] < 0.0 {
        std::mem::swap(&mut u, &mut v);
        u = 1.0 - u;
        v = 1.0 - v;
    }
    u = u.copysign(d[0]);
    v = v.copysign(d[1]);
    [0.5 * (u + 1.0), 0.5 * (v + 1.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn equal_area_map_corners_and_poles() {
        // +z maps to the centre; −z to the corners; ±x, ±y to the edge midpoints.
        assert_eq!(equal_area_sphere_to_square([0.0, 0.0, 1.0]), [0.5, 0.5]);
        let c = equal_area_sphere_to_square([0.0, 0.0, -1.0]);
        assert!(
            (c[0] - 0.5).abs() == 0.5 && (c[1] - 0.5).abs() == 0.5,
            "{c:?}"
        );
        let e = equal_area_sphere_to_square([1.0, 0.0, 0.0]);
        assert!(
            (e[0] - 1.0).abs() < 1e-6 && (e[1] - 0.5).abs() < 1e-6,
            "{e:?}"
        );
        // Equal area: uniform directions fill the square uniformly (4×4 cells within 4σ).
        let mut cells = [0u32; 16];
        let n = 64_000;
        let mut s = 1u64;
        for _ in 0..n {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u1 = (s >> 40) as f32 / (1u64 << 24) as f32;
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let u2 = (s >> 40) as f32 / (1u64 << 24) as f32;
            let z = 1.0 - 2.0 * u1;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u2;
            let [u, v] = equal_area_sphere_to_square([r * phi.cos(), r * phi.sin(), z]);
            cells[((u * 4.0).min(3.0) as usize) + 4 * ((v * 4.0).min(3.0) as usize)] += 1;
        }
        let mean = n as f64 / 16.0;
        for c in cells {
            assert!((c as f64 - mean).abs() < 4.0 * mean.sqrt(), "{cells:?}");
        }
    }

    #[test]
    fn the_density_integrates_to_one_and_follows_the_map() {
        // A map dim everywhere but for a bright patch (400×): E[1/pdf] over samples is the sphere's 4π, and
        // most samples land on the patch (density above 5× the uniform 1/4π).
        let (w, h) = (64, 32);
        let mut px = vec![[1.0f32; 3]; w * h];
        for y in 8..12 {
            for x in 20..28 {
                px[x + w * y] = [400.0; 3];
            }
        }
        for img in [
            RgbImage {
                w,
                h,
                px: px.clone(),
            },
            RgbImage {
                w: 32,
                h: 32,
                px: px[..1024].to_vec(),
            },
        ] {
            let s = EnvSampler::new(&img);
            // Random u (a lattice aliases against texels whose share is below its spacing); σ of the mean ≈ 0.2 %.
            let n = 1000;
            let mut rng = firemedium_core::rng::Rng::new(9);
            let (mut inv, mut bright, mut mismatched) = (0.0f64, 0, 0);
            for _ in 0..n {
                for _ in 0..n {
                    let u = [rng.next_f64() as f32, rng.next_f64() as f32];
                    let (d, pdf) = s.sample(u);
                    let len = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
                    assert!((len - 1.0).abs() < 1e-4, "{d:?}");
                    if pdf > 0.0 {
                        inv += 1.0 / pdf as f64;
                        // The density of a sampled direction, looked up, is the one it was drawn with
                        // (texel edges aside, where the lookup may fall in the neighbour).
                        let q = s.pdf(d);
                        let edge = {
                            let [a, b] = if img.w == img.h {
                                equal_area_sphere_to_square(d)
                            } else {
                                [
                                    0.5 + d[1].atan2(d[0]) / (2.0 * PI),
                                    d[2].clamp(-1.0, 1.0).acos() / PI,
                                ]
                            };
                            let f = |v: f32, n: usize| (v * n as f32).fract();
                            let near = |x: f32| !(1e-3..=1.0 - 1e-3).contains(&x);
                            near(f(a, img.w)) || near(f(b, img.h))
                        };
                        if !edge && (q / pdf - 1.0).abs() > 1e-3 {
                            mismatched += 1;
                        }
                    }
                    if pdf > 5.0 / (4.0 * PI) {
                        bright += 1;
                    }
                }
            }
            let sphere = inv / (n * n) as f64;
            assert!(
                (sphere / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
                "{} × {}: {sphere}",
                img.w,
                img.h
            );
            assert!(bright > n * n / 2, "{bright}");
            // (f32 round trips near the equal-area map's corners land a few samples in the next texel.)
            assert!(
                mismatched < n * n / 1000,
                "{mismatched} lookups differ from their samples' density"
            );
        }
    }

    #[test]
    fn the_equal_area_map_round_trips() {
        for p in [[0.1f32, 0.2], [0.7, 0.9], [0.5, 0.5], [0.95, 0.05]] {
            let d = equal_area_square_to_sphere(p);
            let q = equal_area_sphere_to_square(d);
            assert!(
                (q[0] - p[0]).abs() < 1e-5 && (q[1] - p[1]).abs() < 1e-5,
                "{p:?} → {d:?} → {q:?}"
            );
        }
    }
}
