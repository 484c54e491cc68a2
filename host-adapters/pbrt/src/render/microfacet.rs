//! Rough conductors: the Trowbridge–Reitz (GGX) microfacet distribution, as pbrt-v4's
//! `TrowbridgeReitzDistribution` (`src/pbrt/util/scattering.h`) — isotropic here — with Heitz's sampling of the
//! visible normals (*Sampling the GGX Distribution of Visible Normals*, JCGT 2018).
//!
//! In the local frame (z the shading normal): D(m) = 1 / (π α² cos⁴θ_m (1 + tan²θ_m / α²)²),
//! Λ(w) = (√(1 + α² tan²θ) − 1) / 2, G1 = 1 / (1 + Λ), G = 1 / (1 + Λ(wo) + Λ(wi)); the BRDF
//! f = D(m) G F / (4 cos θo cos θi) with m the half vector; sampling m from D_wo(m) = G1(wo) max(0, wo·m) D(m) / cos θo
//! and reflecting wo about it gives pdf(wi) = D_wo(m) / (4 wo·m) and the weight f cos θi / pdf = F G / G1(wo).
//! pbrt-v4 remaps a scene's `roughness` r to α = √r (`remaproughness` true), and treats α < 10⁻³ as smooth.

use glam::Vec3A;
use std::f32::consts::PI;

/// An isotropic Trowbridge–Reitz distribution of width `alpha`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrowbridgeReitz {
    pub alpha: f32,
}

impl TrowbridgeReitz {
    /// pbrt-v4's `RoughnessToAlpha`: α = √roughness.
    pub fn from_roughness(r: f32, remap: bool) -> TrowbridgeReitz {
        let r = r.max(0.0);
        TrowbridgeReitz {
            alpha: if remap { r.sqrt() } else { r },
        }
    }

    /// Too narrow to tell from a mirror (pbrt-v4's `EffectivelySmooth`).
    pub fn smooth(&self) -> bool {
        self.alpha < 1e-3
    }

    /// D(m) for a local microfacet normal m (z up).
    pub fn d(&self, m: Vec3A) -> f32 {
        let cos2 = m.z * m.z;
        if cos2 <= 0.0 {
            return 0.0;
        }
        let tan2 = (1.0 - cos2).max(0.0) / cos2;
        let a2 = self.alpha * self.alpha;
        let e = 1.0 + tan2 / a2;
        1.0 / (PI * a2 * cos2 * cos2 * e * e)
    }

    fn lambda(&self, w: Vec3A) -> f32 {
        let cos2 = w.z * w.z;
        if cos2 <= 0.0 {
            return f32::INFINITY;
        }
        let tan2 = (1.0 - cos2).max(0.0) / cos2;
        ((1.0 + self.alpha * self.alpha * tan2).sqrt() - 1.0) / 2.0
    }

    /// Smith's masking of one direction.
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Smith's height-correlated masking–shadowing.
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// The BRDF of a conductor of reflectance `f` (its Fresnel term) for local wo, wi, without f: D G / (4 cos cos).
    pub fn brdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize_or_zero();
        if m == Vec3A::ZERO {
            return 0.0;
        }
        self.d(m) * self.g(wo, wi) / (4.0 * wo.z * wi.z)
    }

    /// The solid-angle pdf of sampling wi from wo (visible normals, reflected).
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize_or_zero();
        let dot = wo.dot(m);
        if m == Vec3A::ZERO || dot <= 0.0 {
            return 0.0;
        }
        let d_wo = self.g1(wo) * dot * self.d(m) / wo.z;
        d_wo / (4.0 * dot)
    }

    /// The directional albedo ∫ f cos θi dωi of a white conductor seen from local `wo`, by a midpoint rule of
    /// `q` × `q` cells in (cos θi, φ) — the reference the sampler and the renderer are tested against.
    pub fn albedo_by_quadrature(&self, wo: Vec3A, q: usize) -> f64 {
        let mut sum = 0.0f64;
        for i in 0..q {
            for j in 0..q {
                let (ct, phi) = (
                    (i as f32 + 0.5) / q as f32,
                    (j as f32 + 0.5) / q as f32 * 2.0 * PI,
                );
                let st = (1.0 - ct * ct).sqrt();
                let wi = Vec3A::new(st * phi.cos(), st * phi.sin(), ct);
                sum += (self.brdf(wo, wi) * ct) as f64;
            }
        }
        sum * 2.0 * std::f64::consts::PI / (q * q) as f64
    }

    /// A reflected direction for local wo (z > 0) from the visible normals, or `None` below the surface.
    pub fn sample(&self, wo: Vec3A, u: [f32; 2]) -> Option<Vec3A> {
        // Stretch to the hemisphere configuration, sample the projected disk, unstretch (Heitz 2018).
        let a = self.alpha;
        let wh = Vec3A::new(a * wo.x, a * wo.y, wo.z).normalize_or_zero();
        let t1 = if wh.z < 0.99999 {
            Vec3A::Z.cross(wh).normalize_or_zero()
        } else {
            Vec3A::X
        };
        let t2 = wh.cross(t1);
        let r = u[0].sqrt();
        let phi = 2.0 * PI * u[1];
        let (mut p1, p2) = (r * phi.cos(), r * phi.sin());
        let s = 0.5 * (1.0 + wh.z);
        let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * p2;
        p1 = p1.clamp(-1.0, 1.0);
        let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        let nh = t1 * p1 + t2 * p2 + wh * p3;
        let m = Vec3A::new(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize_or_zero();
        let wi = m * (2.0 * wo.dot(m)) - wo;
        (wi.z > 0.0).then_some(wi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(theta: f32, phi: f32) -> Vec3A {
        Vec3A::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    #[test]
    fn d_is_normalised_and_the_pdf_matches_the_sampler() {
        for alpha in [0.05f32, 0.3, 0.8] {
            let tr = TrowbridgeReitz { alpha };
            // ∫ D(m) cos θ_m dω = 1 (projected microfacet area), by quadrature in θ with the substitution that
            // follows narrow lobes.
            let n = 20_000;
            let mut s = 0.0f64;
            for i in 0..n {
                let theta = (i as f64 + 0.5) / n as f64 * std::f64::consts::FRAC_PI_2;
                let m = dir(theta as f32, 0.0);
                s += tr.d(m) as f64 * theta.cos() * theta.sin() * 2.0 * std::f64::consts::PI;
            }
            s *= std::f64::consts::FRAC_PI_2 / n as f64;
            assert!((s - 1.0).abs() < 2e-3, "α {alpha}: ∫D cos = {s}");
            // E[g(wi) / pdf(wi)] over samples = ∫ g dω for g = 1 on the hemisphere: the sampler's density is pdf.
            let wo = dir(0.7, 0.3);
            let (mut sum, mut count) = (0.0f64, 0);
            let k = 400;
            for a in 0..k {
                for b in 0..k {
                    let u = [(a as f32 + 0.5) / k as f32, (b as f32 + 0.5) / k as f32];
                    if let Some(wi) = tr.sample(wo, u) {
                        let p = tr.pdf(wo, wi);
                        assert!(p > 0.0 && p.is_finite(), "α {alpha}: pdf {p}");
                        // Weight f cos / pdf = G / G1 (with F = 1), checked against the formula.
                        let w = tr.brdf(wo, wi) * wi.z / p;
                        let want = tr.g(wo, wi) / tr.g1(wo);
                        assert!(
                            (w - want).abs() < 1e-3 * want.max(1e-3),
                            "α {alpha}: {w} vs {want}"
                        );
                        sum += (w as f64).min(1.0);
                        count += 1;
                    }
                }
            }
            // The directional albedo of a white rough mirror, sampled, against ∫ f cos θi dωi by quadrature.
            let albedo = sum / (k * k) as f64;
            let want = tr.albedo_by_quadrature(wo, 1000);
            assert!(
                albedo <= 1.0 && (albedo / want - 1.0).abs() < 0.02,
                "α {alpha}: albedo {albedo} sampled ({count} samples), {want} by quadrature"
            );
        }
    }

    #[test]
    fn the_brdf_is_reciprocal() {
        let tr = TrowbridgeReitz { alpha: 0.4 };
        for (a, b) in [((0.3, 0.1), (1.1, 2.0)), ((0.9, 4.0), (0.2, 1.0))] {
            let (wo, wi) = (dir(a.0, a.1), dir(b.0, b.1));
            assert!((tr.brdf(wo, wi) - tr.brdf(wi, wo)).abs() < 1e-6);
        }
    }
}
