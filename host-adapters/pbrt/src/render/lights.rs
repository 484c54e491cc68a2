//! The lights as the integrator sees them: for every kind — point, spot, distant, infinite (constant or a map,
//! behind a portal or not), area, and a fire's own light through the plugin — a sample toward a point
//! ([`Integrator::sample_light`]), the density of a direction ([`Integrator::area_pdf`], [`env_pdf`], the fire
//! light's inside [`Integrator::emission_weight`]) and the radiance a path finds ([`env`],
//! [`Integrator::area_le`]). The integrator weighs them by MIS in one place and never asks which kind it holds.

use super::area::sample_area;
use super::media::to_space;
use super::paths::{Integrator, Spot};
use super::pixel::Samples;
use super::profile::{Step, Tally};
use super::scene::{Light, Medium};
use super::shapes::Hit;
use super::spectrum::S;
use glam::{DAffine3, DVec3, Vec3A};
use std::f32::consts::PI;
use std::time::Instant;

/// Counts `s`, begun at `t0`, in a profiled path, and starts the next step's clock.
fn step(tally: &mut Option<Tally>, s: Step, t0: Option<Instant>) -> Option<Instant> {
    let (t, t0) = (tally.as_mut()?, t0?);
    t.step(s, t0);
    Some(Instant::now())
}

fn uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Radiance of an infinite light toward direction `-w` (seen looking along `w`); zero for other lights.
pub(super) fn env(light: &Light, w: Vec3A) -> S {
    match light {
        Light::Infinite {
            portal: Some(portal),
            ..
        }
        | Light::InfiniteMap {
            portal: Some(portal),
            ..
        } if !(w.dot(portal.n) > 0.0) => S::ZERO,
        Light::Infinite { l, .. } => *l,
        Light::InfiniteMap {
            img,
            to_light,
            scale,
            basis,
            ..
        } => {
            let d = (*to_light * w).normalize_or_zero();
            let [u, v] = if img.w == img.h {
                super::envmap::equal_area_sphere_to_square(d.to_array())
            } else {
                [
                    0.5 + d.y.atan2(d.x) / (2.0 * PI),
                    d.z.clamp(-1.0, 1.0).acos() / PI,
                ]
            };
            let c = img.bilerp(u, v, crate::imageio::Wrap::Clamp);
            (basis[0] * c[0] + basis[1] * c[1] + basis[2] * c[2]) * *scale
        }
        _ => S::ZERO,
    }
}

/// The density (per steradian, before choosing among the scene's lights) with which next-event estimation from
/// `origin` picks world direction `w` toward an infinite light; 0 for other lights.
pub(super) fn env_pdf(light: &Light, origin: Vec3A, w: Vec3A) -> f32 {
    match light {
        Light::Infinite {
            portal: Some(portal),
            ..
        }
        | Light::InfiniteMap {
            portal: Some(portal),
            ..
        } => portal.pdf(origin, w),
        Light::Infinite { .. } => 1.0 / (4.0 * PI),
        Light::InfiniteMap { to_light, dist, .. } => {
            dist.pdf((*to_light * w).normalize_or_zero().to_array())
        }
        _ => 0.0,
    }
}

/// The solid-angle density with which `light` (of a medium placed by `to_medium`) picks world direction `d`
/// from `o` at `time` (frames: the embers move).
fn fire_pdf_direction(
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
            Light::Fire { light, medium: fm } => {
                let Medium::Plugin {
                    to_medium,
                    to_world,
                    ..
                } = &sc.media[*fm]
                else {
                    return None;
                };
                // The sampled point only chooses the direction (density pdf_direction); the estimate is the
                // fire's whole emission along it, Σ T·L_e up to the first opaque surface, divided by that
                // density. Unlike a point estimate j T G / pdf(x), it has no 1/r² singularity next to the fire.
                let t0 = tally.as_ref().map(|_| Instant::now());
                let uu = [(); 6].map(|_| rng.next_f64());
                let (mut pt, mut pdf) = ([[0.0f64; 3]], [0.0f64]);
                self.failures.note(light.sample_at(
                    &[uu],
                    Some(&[rng.time]),
                    &mut pt,
                    &mut pdf,
                    None,
                ))?;
                if !(pdf[0] > 0.0) {
                    return None;
                }
                self.fire_samples
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let xw = to_world.transform_point3(DVec3::from(pt[0]));
                let wi = (Vec3A::from(xw.as_vec3()) - p).normalize_or_zero();
                if wi == Vec3A::ZERO || !wi.is_finite() || dark(wi) {
                    return None;
                }
                let (o, medium) = spot.leave(wi);
                let t0 = step(tally, Step::FirePoint, t0);
                // The fire's emission along wi, up to the first opaque surface.
                let le = self
                    .walk_media(o, wi, f32::INFINITY, medium, Some((*fm, light)), rng)
                    .1;
                let t0 = step(tally, Step::FireLine, t0);
                // (A line that brings no light — the fire hidden behind a surface — needs no density: the walk
                // over the pdf's bricks comes after it.)
                if le.is_black() {
                    return None;
                }
                // Solid angle in medium space equals world solid angle for a similarity transform.
                let pdf_dir = self
                    .failures
                    .note(fire_pdf_direction(light, to_medium, p, wi, rng.time))?
                    as f32
                    / nl;
                step(tally, Step::FireDensity, t0);
                if !(pdf_dir > 0.0) {
                    return None;
                }
                let l = (le / pdf_dir).finite_or_zero();
                return (!l.is_black()).then_some((l, wi, pdf_dir));
            }
            Light::Point { p: lp, i } => {
                let v = *lp - p;
                let d2 = v.length_squared();
                (v.normalize_or_zero(), d2.sqrt(), *i / d2, 0.0)
            }
            Light::Spot {
                p: lp,
                dir,
                cos_total,
                cos_falloff,
                i,
            } => {
                let v = *lp - p;
                let d2 = v.length_squared();
                let w = v.normalize_or_zero();
                let c = (-w).dot(*dir);
                let f = if c < *cos_total {
                    0.0
                } else if c >= *cos_falloff {
                    1.0
                } else {
                    ((c - cos_total) / (cos_falloff - cos_total)).powi(4)
                };
                (w, d2.sqrt(), *i * (f / d2), 0.0)
            }
            Light::Distant { to_light, l } => (*to_light, f32::INFINITY, *l, 0.0),
            Light::Infinite {
                portal: Some(portal),
                ..
            }
            | Light::InfiniteMap {
                portal: Some(portal),
                ..
            } => {
                let (w, _, pdf) = portal.sample(p, u)?;
                (w, f32::INFINITY, env(&sc.lights[li], w) / pdf, pdf / nl)
            }
            Light::Infinite { l, .. } => {
                let w = uniform_sphere(u);
                (w, f32::INFINITY, *l * (4.0 * PI), 1.0 / (4.0 * PI * nl))
            }
            Light::InfiniteMap { to_light, dist, .. } => {
                // A direction by the map's luminance, taken from the map's space to the world's.
                let (dl, pdf) = dist.sample(u);
                if !(pdf > 0.0) {
                    return None;
                }
                let w = (to_light.inverse() * Vec3A::from(dl)).normalize_or_zero();
                (w, f32::INFINITY, env(&sc.lights[li], w) / pdf, pdf / nl)
            }
            Light::Area { prim, l, twosided } => {
                let (q, n, pdf_a) = sample_area(&sc.bvh.prims[*prim], u);
                let v = q - p;
                let d2 = v.length_squared();
                let w = v.normalize_or_zero();
                let cos_l = n.dot(-w);
                if cos_l <= 0.0 && !twosided {
                    return None;
                }
                let pdf_w = pdf_a * d2 / cos_l.abs();
                (w, d2.sqrt(), *l / pdf_w, pdf_w / nl)
            }
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
        let Light::Area { prim, .. } = &sc.lights[li] else {
            return 0.0;
        };
        let pdf_a = sample_area(&sc.bvh.prims[*prim], [0.5, 0.5]).2;
        let v = h.p - origin;
        let d = v.normalize_or_zero();
        let cos_l = h.ng.dot(-d).abs();
        if cos_l == 0.0 {
            return 0.0;
        }
        let p = pdf_a * v.length_squared() / cos_l / sc.lights.len() as f32;
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
        let Medium::Plugin { to_medium, .. } = &sc.media[m] else {
            return 1.0;
        };
        for l in &sc.lights {
            if let Light::Fire { light, medium } = l {
                if *medium == m {
                    let Some(pd) = self
                        .failures
                        .note(fire_pdf_direction(light, to_medium, origin, d, time))
                    else {
                        return 1.0;
                    };
                    let pl = pd as f32 / sc.lights.len() as f32;
                    return if pdf_b + pl > 0.0 {
                        pdf_b / (pdf_b + pl)
                    } else {
                        1.0
                    };
                }
            }
        }
        1.0
    }

    /// The radiance area light `li` sends from its point `h` back along `-d`: None when `li` is no area light
    /// or `h` is its back.
    pub(super) fn area_le(&self, li: usize, h: &Hit, d: Vec3A) -> Option<S> {
        match &self.scene.lights[li] {
            Light::Area { l, twosided, .. } if *twosided || h.ng.dot(-d) > 0.0 => Some(*l),
            _ => None,
        }
    }

    /// Whether light `li` counts for a path whose next segment is at `depth` (bounces so far): a fire light
    /// samples a medium's emission, which pbrt-v4's `VolPathIntegrator` adds only while `depth < maxdepth`
    /// (a real scattering event counts as a bounce); the other lights always count, as there.
    pub(super) fn light_counts(&self, li: usize, depth: usize) -> bool {
        depth < self.scene.maxdepth || !matches!(self.scene.lights[li], Light::Fire { .. })
    }

    /// Whether a scattering event in `medium` leaves light `li` unsampled: the fire light of that very medium,
    /// unless the scene asks for it ([`super::scene::Scene::fire_light_inside`]). The emission the next segment
    /// finds in that medium then has MIS weight 1 ([`Self::emission_weight`]'s `skipped`).
    pub(super) fn skips_inside(&self, li: usize, medium: Option<usize>) -> bool {
        !self.scene.fire_light_inside
            && matches!(self.scene.lights[li], Light::Fire { medium: fm, .. } if Some(fm) == medium)
    }
}
