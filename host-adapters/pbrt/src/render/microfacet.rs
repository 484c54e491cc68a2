//! Rough surfaces: the Trowbridge–Reitz (GGX) microfacet distribution, as pbrt-v4's
//! `TrowbridgeReitzDistribution` (`src/pbrt/util/scattering.h`), anisotropic, with Heitz's sampling of the
//! visible normals (*Sampling the GGX Distribution of Visible Normals*, JCGT 2018).
//!
//! In the local frame (z the shading normal), with e(m) = tan²θ_m (cos²φ_m/α_x² + sin²φ_m/α_y²):
//! D(m) = 1 / (π α_x α_y cos⁴θ_m (1 + e)²); Λ(w) = (√(1 + α(φ)² tan²θ) − 1) / 2 with
//! α(φ)² = α_x² cos²φ + α_y² sin²φ; G1 = 1 / (1 + Λ), G = 1 / (1 + Λ(wo) + Λ(wi)) (height-correlated).
//! The visible normals of w have the density D_w(m) = G1(w) max(0, w·m) D(m) / |cos θ_w|, which is what
//! [`TrowbridgeReitz::sample_wm`] draws from and [`TrowbridgeReitz::pdf`] returns. pbrt-v4 remaps a scene's
//! `roughness` r to α = √r (`remaproughness` true) and treats α < 10⁻³ as smooth. The BSDFs built on it are in
//! [`super::bsdf`].

use glam::Vec3A;
use std::f32::consts::PI;

/// A Trowbridge–Reitz distribution of widths `ax` (along the tangent) and `ay`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrowbridgeReitz {
    pub ax: f32,
    pub ay: f32,
}

fn cos2_theta(w: Vec3A) -> f32 {
    w.z * w.z
}

fn tan2_theta(w: Vec3A) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0) / cos2_theta(w)
}

/// (cos²φ, sin²φ) of a direction (φ = 0 on the pole).
fn cos2_sin2_phi(w: Vec3A) -> (f32, f32) {
    let sin = (1.0 - cos2_theta(w)).max(0.0).sqrt();
    if sin == 0.0 {
        return (1.0, 0.0);
    }
    let c = (w.x / sin).clamp(-1.0, 1.0);
    let s = (w.y / sin).clamp(-1.0, 1.0);
    (c * c, s * s)
}

impl TrowbridgeReitz {
    /// An isotropic distribution of width `alpha`.
    pub fn isotropic(alpha: f32) -> TrowbridgeReitz {
        TrowbridgeReitz {
            ax: alpha,
            ay: alpha,
        }
    }

    /// pbrt-v4's `RoughnessToAlpha` (α = √roughness) when `remap`, else the roughness as α; `u` along the
    /// tangent, `v` across it.
    pub fn from_roughness(u: f32, v: f32, remap: bool) -> TrowbridgeReitz {
        let a = |r: f32| {
            let r = r.max(0.0);
            if remap {
                r.sqrt()
            } else {
                r
            }
        };
        TrowbridgeReitz { ax: a(u), ay: a(v) }
    }

    /// Too narrow to tell from a mirror (pbrt-v4's `EffectivelySmooth`).
    pub fn smooth(&self) -> bool {
        self.ax.max(self.ay) < 1e-3
    }

    /// D(m) for a local microfacet normal m (z up).
    pub fn d(&self, m: Vec3A) -> f32 {
        let tan2 = tan2_theta(m);
        if !tan2.is_finite() {
            return 0.0;
        }
        let cos4 = cos2_theta(m) * cos2_theta(m);
        if cos4 < 1e-16 {
            return 0.0;
        }
        let (c2, s2) = cos2_sin2_phi(m);
        let e = tan2 * (c2 / (self.ax * self.ax) + s2 / (self.ay * self.ay));
        1.0 / (PI * self.ax * self.ay * cos4 * (1.0 + e) * (1.0 + e))
    }

    fn lambda(&self, w: Vec3A) -> f32 {
        let tan2 = tan2_theta(w);
        if !tan2.is_finite() {
            return 0.0;
        }
        let (c2, s2) = cos2_sin2_phi(w);
        let alpha2 = c2 * self.ax * self.ax + s2 * self.ay * self.ay;
        ((1.0 + alpha2 * tan2).sqrt() - 1.0) / 2.0
    }

    /// Smith's masking of one direction.
    pub fn g1(&self, w: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Smith's height-correlated masking–shadowing.
    pub fn g(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// The density of visible normal `wm` seen from `w`: G1(w) |w·m| D(m) / |cos θ_w| (per solid angle of m).
    pub fn pdf(&self, w: Vec3A, wm: Vec3A) -> f32 {
        if w.z == 0.0 {
            return 0.0;
        }
        self.g1(w) / w.z.abs() * self.d(wm) * w.dot(wm).abs()
    }

    /// A visible normal of `w` (either hemisphere: drawn for w's mirror image above the surface when below),
    /// always in the upper hemisphere.
    pub fn sample_wm(&self, w: Vec3A, u: [f32; 2]) -> Vec3A {
        // Stretch to the hemisphere configuration, sample the projected disk, unstretch (Heitz 2018).
        let mut wh = Vec3A::new(self.ax * w.x, self.ay * w.y, w.z).normalize_or_zero();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3A::Z.cross(wh).normalize_or_zero()
        } else {
            Vec3A::X
        };
        let t2 = wh.cross(t1);
        let r = u[0].sqrt();
        let phi = 2.0 * PI * u[1];
        let (p1, p2) = (r * phi.cos(), r * phi.sin());
        let h = (1.0 - p1 * p1).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        let p2 = (1.0 - s) * h + s * p2;
        let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
        let nh = t1 * p1 + t2 * p2 + wh * p3;
        Vec3A::new(self.ax * nh.x, self.ay * nh.y, nh.z.max(1e-6)).normalize_or_zero()
    }

    /// The reflection BRDF of a white conductor (Fresnel 1) for local wo, wi: D G / (4 |cos θo cos θi|).
    pub fn brdf(&self, wo: Vec3A, wi: Vec3A) -> f32 {
        if wo.z * wi.z <= 0.0 {
            return 0.0;
        }
        let m = (wo + wi).normalize_or_zero();
        if m == Vec3A::ZERO {
            return 0.0;
        }
        self.d(m) * self.g(wo, wi) / (4.0 * (wo.z * wi.z).abs())
    }

    /// The directional albedo ∫ f cos θi dωi of a white conductor seen from local `wo`, by a midpoint rule of
    /// `q` × `q` cells in (cos θi, φ) — the reference the BSDFs and the renderer are tested against.
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
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn dir(theta: f32, phi: f32) -> Vec3A {
        Vec3A::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    #[test]
    fn d_is_normalised_and_the_visible_normals_are_a_density() {
        for (ax, ay) in [(0.05f32, 0.05f32), (0.3, 0.3), (0.8, 0.8), (0.1, 0.6)] {
            let tr = TrowbridgeReitz { ax, ay };
            // ∫ D(m) cos θ_m dω = 1 (projected microfacet area), by a midpoint rule in (θ, φ).
            let (nt, np) = (4000, 256);
            let mut s = 0.0f64;
            for i in 0..nt {
                let theta = (i as f64 + 0.5) / nt as f64 * std::f64::consts::FRAC_PI_2;
                for j in 0..np {
                    let phi = (j as f64 + 0.5) / np as f64 * 2.0 * std::f64::consts::PI;
                    let m = dir(theta as f32, phi as f32);
                    s += tr.d(m) as f64 * theta.cos() * theta.sin();
                }
            }
            s *= std::f64::consts::FRAC_PI_2 / nt as f64 * 2.0 * std::f64::consts::PI / np as f64;
            assert!((s - 1.0).abs() < 3e-3, "α ({ax}, {ay}): ∫D cos = {s}");
            // The visible normals of a direction integrate to 1 over the hemisphere of m, and the sampler
            // draws from them: E[1 / pdf(m)] over its samples is the hemisphere's 2π.
            let wo = dir(0.7, 0.3);
            let k = 300;
            let mut inv = 0.0f64;
            for a in 0..k {
                for b in 0..k {
                    let u = [(a as f32 + 0.5) / k as f32, (b as f32 + 0.5) / k as f32];
                    let m = tr.sample_wm(wo, u);
                    let p = tr.pdf(wo, m);
                    assert!(
                        m.z > 0.0 && p > 0.0 && p.is_finite(),
                        "α ({ax}, {ay}): pdf {p}"
                    );
                    // Only the normals facing wo are drawn; 1/pdf over them estimates their solid angle.
                    inv += 1.0 / p as f64;
                }
            }
            inv /= (k * k) as f64;
            // The solid angle of {m : m·wo > 0, m.z > 0}: the hemisphere less a lune of angle θo.
            let want = 2.0 * std::f64::consts::PI - 2.0 * 0.7;
            // (A narrow lobe leaves most of that set unsampled: the estimate is then loose, so only the
            // wide lobes check it.)
            if ax.min(ay) >= 0.3 {
                assert!(
                    (inv / want - 1.0).abs() < 0.05,
                    "α ({ax}, {ay}): E[1/pdf] = {inv}, want {want}"
                );
            }
        }
    }

    #[test]
    fn the_white_conductor_brdf_is_reciprocal_and_isotropic_when_widths_agree() {
        let tr = TrowbridgeReitz::isotropic(0.4);
        for (a, b) in [((0.3, 0.1), (1.1, 2.0)), ((0.9, 4.0), (0.2, 1.0))] {
            let (wo, wi) = (dir(a.0, a.1), dir(b.0, b.1));
            assert!((tr.brdf(wo, wi) - tr.brdf(wi, wo)).abs() < 1e-6);
            // Rotating both directions about the normal leaves an isotropic BRDF unchanged.
            let (wo2, wi2) = (dir(a.0, a.1 + 0.7), dir(b.0, b.1 + 0.7));
            assert!((tr.brdf(wo, wi) - tr.brdf(wo2, wi2)).abs() < 1e-4 * tr.brdf(wo, wi));
        }
        let aniso = TrowbridgeReitz { ax: 0.1, ay: 0.6 };
        // Anisotropic: microfacets tilt more across the tangent (y, α 0.6) than along it (x, α 0.1). A
        // reflection turned 0.3 rad in azimuth off the mirror direction needs its half vector tilted
        // perpendicular to the plane of incidence: toward y when that plane is xz (likely), toward x when it
        // is yz (unlikely).
        let wo = dir(0.5, 0.0);
        let tilt_y = aniso.brdf(wo, dir(0.5, std::f32::consts::PI - 0.3));
        let tilt_x = aniso.brdf(
            dir(0.5, std::f32::consts::FRAC_PI_2),
            dir(0.5, -std::f32::consts::FRAC_PI_2 + 0.3),
        );
        assert!(tilt_y > 2.0 * tilt_x, "{tilt_y} vs {tilt_x}");
    }
}
