//! pbrt-v4's delta lights — `point`, `spot`, `distant` — which only next-event estimation reaches (their density
//! of a direction is 0: no sampled direction finds them).

use super::Incident;
use crate::render::scene::{Distant, Point, Spot};
use glam::Vec3A;

impl Point {
    pub(super) fn toward(&self, p: Vec3A) -> Incident {
        let v = self.p - p;
        let d2 = v.length_squared();
        (v.normalize_or_zero(), d2.sqrt(), self.i / d2, 0.0)
    }
}

impl Spot {
    pub(super) fn toward(&self, p: Vec3A) -> Incident {
        let v = self.p - p;
        let d2 = v.length_squared();
        let w = v.normalize_or_zero();
        let c = (-w).dot(self.dir);
        let (cos_total, cos_falloff) = (self.cos_total, self.cos_falloff);
        let f = if c < cos_total {
            0.0
        } else if c >= cos_falloff {
            1.0
        } else {
            ((c - cos_total) / (cos_falloff - cos_total)).powi(4)
        };
        (w, d2.sqrt(), self.i * (f / d2), 0.0)
    }
}

impl Distant {
    pub(super) fn toward(&self) -> Incident {
        (self.to_light, f32::INFINITY, self.l, 0.0)
    }
}
