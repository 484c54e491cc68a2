//! Area sampling of shapes, for area lights: a point uniform by area on a triangle, sphere (or its part), disk or
//! cylinder in its object space, with its normal and density.

use super::shapes::{normal_to_world, Geom, Prim};
use glam::{Affine3A, Vec3A};

/// A uniformly sampled point on the shape (by area), its normal, and the area pdf.
pub fn sample_area(pr: &Prim, u: [f32; 2]) -> (Vec3A, Vec3A, f32) {
    let flip = |n: Vec3A| if pr.reverse { -n } else { n };
    match &pr.geom {
        Geom::Triangle { p, .. } => {
            let su = u[0].sqrt();
            let (b0, b1) = (1.0 - su, u[1] * su);
            let q = p[0] * b0 + p[1] * b1 + p[2] * (1.0 - b0 - b1);
            let c = (p[1] - p[0]).cross(p[2] - p[0]);
            (q, flip(c.normalize_or_zero()), 2.0 / c.length().max(1e-30))
        }
        Geom::Sphere {
            to_world,
            to_obj,
            r,
            zmin,
            zmax,
            phimax,
        } => {
            // Archimedes: z uniform is area-uniform on a sphere, on a zone too.
            let (z0, z1) = (zmin.max(-r) / r, zmax.min(*r) / r);
            let z = z0 + (z1 - z0) * u[0];
            let rr = (1.0 - z * z).max(0.0).sqrt();
            let phi = phimax * u[1];
            let q = Vec3A::new(rr * phi.cos(), rr * phi.sin(), z) * *r;
            let area = phimax * r * r * (z1 - z0) * area_scale(to_world);
            (
                to_world.transform_point3a(q),
                flip(normal_to_world(to_obj, q)),
                1.0 / area,
            )
        }
        Geom::Disk {
            to_world,
            to_obj,
            h,
            r,
            ri,
            phimax,
        } => {
            let rr = (ri * ri + u[0] * (r * r - ri * ri)).sqrt();
            let phi = phimax * u[1];
            let q = Vec3A::new(rr * phi.cos(), rr * phi.sin(), *h);
            let area = 0.5 * phimax * (r * r - ri * ri) * area_scale(to_world);
            (
                to_world.transform_point3a(q),
                flip(normal_to_world(to_obj, Vec3A::Z)),
                1.0 / area,
            )
        }
        Geom::Cylinder {
            to_world,
            to_obj,
            r,
            zmin,
            zmax,
            phimax,
        } => {
            let phi = phimax * u[1];
            let q = Vec3A::new(r * phi.cos(), r * phi.sin(), zmin + u[0] * (zmax - zmin));
            let area = phimax * r * (zmax - zmin) * area_scale(to_world);
            (
                to_world.transform_point3a(q),
                flip(normal_to_world(to_obj, Vec3A::new(q.x, q.y, 0.0))),
                1.0 / area,
            )
        }
        // Instances are never area lights (the builder warns and leaves the light out, as pbrt-v4 does): an
        // infinite pdf is a sample that contributes nothing.
        Geom::Instance { to_world, .. } => (to_world.translation, Vec3A::Z, f32::INFINITY),
    }
}

/// Area scale of a transform (exact for uniform scales; documented approximation otherwise).
fn area_scale(m: &Affine3A) -> f32 {
    m.matrix3.determinant().abs().powf(2.0 / 3.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::shapes::tests::sphere;

    #[test]
    fn area_sampling_pdf_integrates_to_one() {
        let s = sphere(2.0, Vec3A::ZERO);
        let (_, _, pdf) = sample_area(&s, [0.3, 0.7]);
        assert!((pdf * 4.0 * std::f32::consts::PI * 4.0 - 1.0).abs() < 1e-5);
    }
}
