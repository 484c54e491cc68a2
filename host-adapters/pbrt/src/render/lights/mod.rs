//! The lights as the integrator sees them. Each kind in its own file — pbrt-v4's delta lights ([`delta`]: point,
//! spot, distant), its infinite lights ([`infinite`]: constant or a map, behind a portal or not), area lights
//! ([`area`]) and a fire's own light through the plugin ([`fire`]); what each holds is the scene's — answers a sample toward a point, the density
//! of a direction and the radiance a path finds; here they meet in one-line dispatch: a sample
//! ([`Integrator::sample_light`]), the densities ([`Integrator::area_pdf`], [`env_pdf`], the fire light's inside
//! [`Integrator::emission_weight`]) and the radiance found ([`env`], [`Integrator::area_le`]). The integrator
//! weighs them by MIS in one place and never asks which kind it holds.

pub mod area;
pub mod delta;
pub mod fire;
pub mod infinite;

use super::paths::{Integrator, Spot};
use super::pixel::Samples;
use super::profile::Tally;
use super::scene::{Light, Medium};
use super::shapes::Hit;
use super::spectrum::S;
use glam::Vec3A;

/// A sample toward a point: (direction, distance to the light, radiance over the density, the solid-angle
/// density including the light's choice — 0 for a delta light, which no sampled direction finds).
type Incident = (Vec3A, f32, S, f32);

/// Radiance of an infinite light toward direction `-w` (seen looking along `w`); zero for other lights.
pub(super) fn env(light: &Light, w: Vec3A) -> S {
    match light {
        Light::Infinite(l) => l.le(w),
        _ => S::ZERO,
    }
}

/// The density (per steradian, before choosing among the scene's lights) with which next-event estimation from
/// `origin` picks world direction `w` toward an infinite light; 0 for other lights.
pub(super) fn env_pdf(light: &Light, origin: Vec3A, w: Vec3A) -> f32 {
    match light {
        Light::Infinite(l) => l.pdf(origin, w),
        _ => 0.0,
    }
}

impl Integrator<'_> {
    /// Radiance from one light toward `spot` (NEE), already divided by the light's selection probability:
    /// (incident radiance × visibility, direction, the light's solid-angle pdf of that direction including the
    /// selection probability — for MIS; 0 for delta lights, which paths cannot hit by themselves).
    /// `dark(wi)`: whether the vertex reflects nothing toward `wi` (a surface's BSDF is zero there), so a fire
    /// light sample in that direction skips the march along it.
    pub(super) fn sample_light(
        &self,
        li: usize,
        spot: &Spot,
        rng: &mut Samples,
        dark: &dyn Fn(Vec3A) -> bool,
        tally: &mut Option<Tally>,
    ) -> Option<(S, Vec3A, f32)> {
        let sc = self.scene;
        let u = Self::rng2(rng);
        let nl = sc.lights.len() as f32;
        let p = spot.p();
        let (wi, dist, le, pl) = match &sc.lights[li] {
            Light::Fire(f) => return self.sample_fire(f, spot, nl, rng, dark, tally),
            Light::Point(l) => l.toward(p),
            Light::Spot(l) => l.toward(p),
            Light::Distant(l) => l.toward(),
            Light::Infinite(l) => l.sample(p, u, nl)?,
            Light::Area(l) => l.sample(&sc.bvh, p, u, nl)?,
        };
        if le.max() <= 0.0 || !wi.is_finite() {
            return None;
        }
        let (o, medium) = spot.leave(wi);
        let t_max = if dist.is_finite() {
            (dist - (o - p).length()).max(0.0) * (1.0 - 1e-4)
        } else {
            1e30
        };
        let vis = self.walk_media(o, wi, t_max, medium, None, rng).0;
        let l = (le * vis * nl).finite_or_zero();
        (!l.is_black() && pl.is_finite()).then_some((l, wi, pl))
    }

    /// The solid-angle density with which next-event estimation picks the point `h` of area light `li` from
    /// `origin` (including the light's selection probability).
    pub(super) fn area_pdf(&self, li: usize, origin: Vec3A, h: &Hit) -> f32 {
        let sc = self.scene;
        let Light::Area(l) = &sc.lights[li] else {
            return 0.0;
        };
        let p = l.pdf(&sc.bvh, origin, h) / sc.lights.len() as f32;
        if p.is_finite() {
            p
        } else {
            0.0
        }
    }

    /// The MIS weight of emission that a path sampled with density `pdf_b` (solid angle) from `origin` along `d`
    /// collects in medium `m`: pdf_b / (pdf_b + the fire light's directional pdf), or 1 when `m` has no fire
    /// light or the path was not sampled by a BSDF/phase function (camera rays, specular bounces).
    /// `skipped`: the medium whose fire light the path's last vertex (a scattering event inside it) did not
    /// sample — its emission then has weight 1.
    pub(super) fn emission_weight(
        &self,
        m: usize,
        mis: Option<(Vec3A, f32)>,
        skipped: Option<usize>,
        d: Vec3A,
        time: f64,
    ) -> f32 {
        let Some((origin, pdf_b)) = mis else {
            return 1.0;
        };
        if skipped == Some(m) && !self.scene.fire_light_inside {
            return 1.0;
        }
        let sc = self.scene;
        let Medium::Plugin(p) = &sc.media[m] else {
            return 1.0;
        };
        let fire = sc.lights.iter().find_map(|l| match l {
            Light::Fire(f) if f.medium == m => Some(f),
            _ => None,
        });
        let Some(f) = fire else { return 1.0 };
        let pd = fire::pdf_direction(&f.light, &p.to_medium, origin, d, time);
        let Some(pd) = self.failures.note(pd) else {
            return 1.0;
        };
        let pl = pd as f32 / sc.lights.len() as f32;
        if pdf_b + pl > 0.0 {
            pdf_b / (pdf_b + pl)
        } else {
            1.0
        }
    }

    /// The radiance area light `li` sends from its point `h` back along `-d`: None when `li` is no area light
    /// or `h` is its back.
    pub(super) fn area_le(&self, li: usize, h: &Hit, d: Vec3A) -> Option<S> {
        match &self.scene.lights[li] {
            Light::Area(l) => l.le(h, d),
            _ => None,
        }
    }

    /// Whether light `li` counts for a path whose next segment is at `depth` (bounces so far): a fire light
    /// samples a medium's emission, which pbrt-v4's `VolPathIntegrator` adds only while `depth < maxdepth`
    /// (a real scattering event counts as a bounce); the other lights always count, as there.
    pub(super) fn light_counts(&self, li: usize, depth: usize) -> bool {
        depth < self.scene.maxdepth || !matches!(self.scene.lights[li], Light::Fire(_))
    }

    /// Whether a scattering event in `medium` leaves light `li` unsampled: the fire light of that very medium,
    /// unless the scene asks for it ([`super::scene::Scene::fire_light_inside`]). The emission the next segment
    /// finds in that medium then has MIS weight 1 ([`Self::emission_weight`]'s `skipped`).
    pub(super) fn skips_inside(&self, li: usize, medium: Option<usize>) -> bool {
        !self.scene.fire_light_inside
            && matches!(&self.scene.lights[li], Light::Fire(f) if Some(f.medium) == medium)
    }
}
