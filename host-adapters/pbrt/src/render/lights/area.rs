//! pbrt-v4's `diffuse` area light on a shape: sampled by area, its density of a direction the area's over the
//! cosine at the light, its radiance found by paths that hit its front (or either side, two-sided).

use super::Incident;
use crate::render::area::sample_area;
use crate::render::scene::Area;
use crate::render::shapes::{Bvh, Hit};
use crate::render::spectrum::S;
use glam::Vec3A;

impl Area {
    /// A point of it seen from `p`, chosen among `nl` lights.
    pub(super) fn sample(&self, bvh: &Bvh, p: Vec3A, u: [f32; 2], nl: f32) -> Option<Incident> {
        let (q, n, pdf_a) = sample_area(&bvh.prims[self.prim], u);
        let v = q - p;
        let d2 = v.length_squared();
        let w = v.normalize_or_zero();
        let cos_l = n.dot(-w);
        if cos_l <= 0.0 && !self.twosided {
            return None;
        }
        let pdf_w = pdf_a * d2 / cos_l.abs();
        Some((w, d2.sqrt(), self.l / pdf_w, pdf_w / nl))
    }

    /// The solid-angle density with which a sample from `origin` picks the point `h` (before the light's
    /// selection).
    pub(super) fn pdf(&self, bvh: &Bvh, origin: Vec3A, h: &Hit) -> f32 {
        let pdf_a = sample_area(&bvh.prims[self.prim], [0.5, 0.5]).2;
        let v = h.p - origin;
        let d = v.normalize_or_zero();
        let cos_l = h.ng.dot(-d).abs();
        if cos_l == 0.0 {
            return 0.0;
        }
        pdf_a * v.length_squared() / cos_l
    }

    /// The radiance it sends from its point `h` back along `-d`: None from its back.
    pub(super) fn le(&self, h: &Hit, d: Vec3A) -> Option<S> {
        (self.twosided || h.ng.dot(-d) > 0.0).then_some(self.l)
    }
}
