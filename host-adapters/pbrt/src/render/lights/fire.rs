//! A fire's own light, through the plugin: a point drawn by the fire's emission chooses a direction, and the
//! estimate is the fire's whole emission along it (Σ T·L_e up to the first opaque surface) over that direction's
//! density — no 1/r² singularity next to the fire. Its density of a direction also weighs the emission paths find
//! by themselves ([`Integrator::emission_weight`]).

use crate::render::media::to_space;
use crate::render::paths::{Integrator, Spot};
use crate::render::pixel::Samples;
use crate::render::profile::{clock, lap, Step, Tally};
use crate::render::scene::{Fire, Medium};
use crate::render::spectrum::S;
use glam::{DAffine3, DVec3, Vec3A};

/// The solid-angle density with which `light` (of a medium placed by `to_medium`) picks world direction `d`
/// from `o` at `time` (frames: the embers move).
pub(super) fn pdf_direction(
    light: &firemedium_loader::Light,
    to_medium: &DAffine3,
    o: Vec3A,
    d: Vec3A,
    time: f64,
) -> Result<f64, firemedium_loader::Error> {
    let (om, dm) = to_space(to_medium, o, d);
    let mut pd = [0.0f64];
    light.pdf_direction_at(&[om.to_array()], &[dm.to_array()], Some(&[time]), &mut pd)?;
    Ok(pd[0])
}

impl Integrator<'_> {
    /// A sample of fire light `f` toward `spot`, chosen among `nl` lights: (radiance over the direction's
    /// density, direction, density including the choice), as [`Integrator::sample_light`] answers.
    pub(super) fn sample_fire(
        &self,
        f: &Fire,
        spot: &Spot,
        nl: f32,
        rng: &mut Samples,
        dark: &dyn Fn(Vec3A) -> bool,
        tally: &mut Option<Tally>,
    ) -> Option<(S, Vec3A, f32)> {
        let Medium::Plugin(m) = &self.scene.media[f.medium] else {
            return None;
        };
        let (light, p) = (&*f.light, spot.p());
        let t0 = clock(tally);
        let uu = [(); 6].map(|_| rng.next_f64());
        let (mut pt, mut pdf) = ([[0.0f64; 3]], [0.0f64]);
        let sampled = light.sample_at(&[uu], Some(&[rng.time]), &mut pt, &mut pdf, None);
        self.failures.note(sampled)?;
        if !(pdf[0] > 0.0) {
            return None;
        }
        self.fire_samples
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let xw = m.to_world.transform_point3(DVec3::from(pt[0]));
        let wi = (Vec3A::from(xw.as_vec3()) - p).normalize_or_zero();
        if wi == Vec3A::ZERO || !wi.is_finite() || dark(wi) {
            return None;
        }
        let (o, medium) = spot.leave(wi);
        let t0 = lap(tally, Step::FirePoint, t0);
        // The fire's emission along wi, up to the first opaque surface.
        let fire = Some((f.medium, light));
        let le = self.walk_media(o, wi, f32::INFINITY, medium, fire, rng).1;
        let t0 = lap(tally, Step::FireLine, t0);
        // (A line that brings no light — the fire hidden behind a surface — needs no density: the walk over the
        // pdf's bricks comes after it.)
        if le.is_black() {
            return None;
        }
        // Solid angle in medium space equals world solid angle for a similarity transform.
        let pd = pdf_direction(light, &m.to_medium, p, wi, rng.time);
        let pdf_dir = self.failures.note(pd)? as f32 / nl;
        lap(tally, Step::FireDensity, t0);
        if !(pdf_dir > 0.0) {
            return None;
        }
        let l = (le / pdf_dir).finite_or_zero();
        (!l.is_black()).then_some((l, wi, pdf_dir))
    }
}
