//! pbrt-v4's `rgbgrid` medium ([`crate::render::rgbgrid`]), tracked by the renderer: its segments by ratio
//! tracking, its paths by delta tracking, over its own majorant grid.

use super::{Emitted, MediumKind, Track};
use crate::render::paths::Integrator;
use crate::render::pixel::Samples;
use crate::render::rgbgrid::RgbGrid;
use crate::render::spectrum::S;
use glam::Vec3A;

impl MediumKind for RgbGrid {
    fn segment(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
        _: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>) {
        it.host_segment(self, o, d, t_end, rng, emission)
    }

    fn track(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        _: bool,
    ) -> (Emitted, Track) {
        it.host_track(self, o, d, t_end, rng, None)
    }
}
