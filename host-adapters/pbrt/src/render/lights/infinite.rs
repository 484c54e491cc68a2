//! pbrt-v4's infinite lights: a constant radiance or an environment map (equal-area square or lat-long), each
//! optionally seen only through a portal. Found by paths that escape ([`Infinite::le`]) and sampled by next-event
//! estimation — uniformly, by the map's luminance, or through the portal.

use super::Incident;
use crate::render::scene::{Infinite, Sky};
use crate::render::spectrum::S;
use glam::Vec3A;
use std::f32::consts::PI;

fn uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

impl Infinite {
    /// Radiance toward direction `-w` (seen looking along `w`).
    pub(super) fn le(&self, w: Vec3A) -> S {
        if let Some(portal) = &self.portal {
            if !(w.dot(portal.n) > 0.0) {
                return S::ZERO;
            }
        }
        match &self.sky {
            Sky::Constant(l) => *l,
            Sky::Map {
                img,
                to_light,
                scale,
                basis,
                ..
            } => {
                let d = (*to_light * w).normalize_or_zero();
                let [u, v] = if img.w == img.h {
                    crate::render::envmap::equal_area_sphere_to_square(d.to_array())
                } else {
                    [
                        0.5 + d.y.atan2(d.x) / (2.0 * PI),
                        d.z.clamp(-1.0, 1.0).acos() / PI,
                    ]
                };
                let c = img.bilerp(u, v, crate::imageio::Wrap::Clamp);
                (basis[0] * c[0] + basis[1] * c[1] + basis[2] * c[2]) * *scale
            }
        }
    }

    /// The density (per steradian, before choosing among the scene's lights) with which next-event estimation
    /// from `origin` picks world direction `w`.
    pub(super) fn pdf(&self, origin: Vec3A, w: Vec3A) -> f32 {
        match (&self.portal, &self.sky) {
            (Some(portal), _) => portal.pdf(origin, w),
            (None, Sky::Constant(_)) => 1.0 / (4.0 * PI),
            (None, Sky::Map { to_light, dist, .. }) => {
                dist.pdf((*to_light * w).normalize_or_zero().to_array())
            }
        }
    }

    /// A direction from `p`, chosen among `nl` lights.
    pub(super) fn sample(&self, p: Vec3A, u: [f32; 2], nl: f32) -> Option<Incident> {
        match (&self.portal, &self.sky) {
            (Some(portal), _) => {
                let (w, _, pdf) = portal.sample(p, u)?;
                Some((w, f32::INFINITY, self.le(w) / pdf, pdf / nl))
            }
            (None, Sky::Constant(l)) => {
                let w = uniform_sphere(u);
                Some((w, f32::INFINITY, *l * (4.0 * PI), 1.0 / (4.0 * PI * nl)))
            }
            (None, Sky::Map { to_light, dist, .. }) => {
                // A direction by the map's luminance, taken from the map's space to the world's.
                let (dl, pdf) = dist.sample(u);
                if !(pdf > 0.0) {
                    return None;
                }
                let w = (to_light.inverse() * Vec3A::from(dl)).normalize_or_zero();
                Some((w, f32::INFINITY, self.le(w) / pdf, pdf / nl))
            }
        }
    }
}
