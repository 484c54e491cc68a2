//! `volpath`: unidirectional path tracing with next-event estimation to the scene's lights, media crossed at
//! MediumInterface boundaries (and `interface` materials), emission–absorption of plugin media through the
//! plugin's `integrate` call (or its scattering-event sampling when σ_s > 0, with Henyey–Greenstein phase
//! sampling and NEE at the scattering point), and homogeneous media in closed form.
//!
//! Surfaces scatter through pbrt-v4's BxDFs ([`super::bsdf`]) in the shading frame. Every light a path can hit
//! by itself — area lights, environment maps, the fire — is reached both ways and weighted by the balance
//! heuristic: next-event estimation at every non-specular vertex (surface or medium), and BSDF/phase sampling
//! that finds it; delta lights (point, spot, distant) by next-event estimation only. A path that meets a
//! dispersive dielectric keeps one bin from there on ([`super::material::Eta`]).

use super::bsdf::{Lobes, Mode};
use super::material;
use super::media::{to_space, Track};
use super::pixel::Samples;
use super::scene::{Light, Medium, Scene};
use super::shapes::{sample_area, Hit};
use super::spectrum::S;
use glam::{DAffine3, DVec3, Vec3A};
use std::f32::consts::PI;

/// The surface a camera ray sees first (pbrt-v4's `VisibleSurface`), for the `gbuffer` film: world-space point,
/// geometric and shading normals, and the material's directional albedo ρ(wo) (one-sample estimate).
#[derive(Debug, Clone, Copy)]
pub struct Visible {
    pub p: Vec3A,
    pub ng: Vec3A,
    pub ns: Vec3A,
    pub albedo: S,
}

/// Where a camera sample's light came from, for the AOVs: the radiance the path had gathered when it reached
/// its first and its second scattering vertex (all of it so far was seen from the camera, then the first vertex's
/// direct light), the lights it saw directly, and the coverage of its camera ray. Contributions come in that
/// order along a path, so two marks split it: seen = first mark, direct = second − first, indirect = the rest.
#[derive(Debug, Clone, Copy, Default)]
pub struct Split {
    /// The path's radiance at its first and second scattering vertex (none: the path ended before).
    pub marks: [Option<S>; 2],
    /// Lights (area, infinite) seen from the camera: the rest of what was seen is the media's emission.
    pub emission: S,
    /// 1 − the camera ray's transmittance when it escaped (none: a surface or a medium stopped it: 1).
    pub alpha: Option<f32>,
}

impl Split {
    /// Marks the radiance `l` gathered when the path reaches a scattering vertex at `depth`.
    fn mark(split: &mut Option<&mut Split>, depth: usize, l: S) {
        if let Some(sp) = split.as_deref_mut() {
            if depth < 2 && sp.marks[depth].is_none() {
                sp.marks[depth] = Some(l);
            }
        }
    }
    /// The path's radiance `l` in four parts: media emission seen from the camera, lights seen from the camera,
    /// direct and indirect light (they sum to `l`, to rounding).
    pub fn parts(&self, l: S) -> [S; 4] {
        let first = self.marks[0].unwrap_or(l);
        let second = self.marks[1].unwrap_or(l);
        [
            first - self.emission,
            self.emission,
            second - first,
            l - second,
        ]
    }
}

fn frame(n: Vec3A) -> (Vec3A, Vec3A) {
    let s = if n.z < 0.0 { -1.0 } else { 1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        Vec3A::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vec3A::new(b, s + n.y * n.y * a, -n.y),
    )
}

/// `w` in the frame whose z is `n` (the microfacet models' local space)...
fn to_local(n: Vec3A, w: Vec3A) -> Vec3A {
    let (t, b) = frame(n);
    Vec3A::new(w.dot(t), w.dot(b), w.dot(n))
}

/// ...and back.
fn from_local(n: Vec3A, w: Vec3A) -> Vec3A {
    let (t, b) = frame(n);
    (t * w.x + b * w.y + n * w.z).normalize_or_zero()
}

fn uniform_sphere(u: [f32; 2]) -> Vec3A {
    let z = 1.0 - 2.0 * u[0];
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    Vec3A::new(r * phi.cos(), r * phi.sin(), z)
}

/// Henyey–Greenstein phase function value (eq. 4) for cosθ between wo-reversed and wi (pbrt's convention).
fn hg(cos: f32, g: f32) -> f32 {
    let d = 1.0 + g * g + 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * PI * d * d.max(1e-12).sqrt())
}

/// The balance-heuristic weight of a light sample whose solid-angle pdf is `pl` against the BSDF/phase pdf `pb`
/// of the same direction; 1 when the light cannot be reached by BSDF sampling (`pl` = 0 marks those lights).
fn light_mis_weight(pl: f32, pb: f32) -> f32 {
    if pl > 0.0 {
        pl / (pl + pb)
    } else {
        1.0
    }
}

/// Samples HG around the propagation direction `d`.
fn sample_hg(d: Vec3A, g: f32, u: [f32; 2]) -> Vec3A {
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u[0]
    } else {
        let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u[0]);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u[1];
    let (t, b) = frame(d);
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + d * cos).normalize_or_zero()
}

/// Radiance of an infinite light toward direction `-w` (seen looking along `w`); zero for other lights.
fn env(light: &Light, w: Vec3A) -> S {
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
                crate::imageio::equal_area_sphere_to_square(d.to_array())
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
fn env_pdf(light: &Light, origin: Vec3A, w: Vec3A) -> f32 {
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

/// Where next-event estimation leaves from: a surface point (the side a direction leaves by picks the offset
/// and the medium) or a point inside a medium.
#[derive(Debug, Clone, Copy)]
enum Spot {
    Surface {
        p: Vec3A,
        ng: Vec3A,
        eps: f32,
        /// The shape's (inside, outside) media, or the medium the path is in when the shape has none.
        media: Option<(Option<usize>, Option<usize>)>,
        medium: Option<usize>,
    },
    Medium {
        p: Vec3A,
        medium: Option<usize>,
    },
}

impl Spot {
    fn p(&self) -> Vec3A {
        match self {
            Spot::Surface { p, .. } | Spot::Medium { p, .. } => *p,
        }
    }
    /// The origin and medium of a ray leaving along `w`.
    fn leave(&self, w: Vec3A) -> (Vec3A, Option<usize>) {
        match *self {
            Spot::Medium { p, medium } => (p, medium),
            Spot::Surface {
                p,
                ng,
                eps,
                media,
                medium,
            } => {
                let out = w.dot(ng) > 0.0;
                let m = match media {
                    Some((inside, outside)) => {
                        if out {
                            outside
                        } else {
                            inside
                        }
                    }
                    None => medium,
                };
                (p + if out { ng } else { -ng } * eps, m)
            }
        }
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

/// Plugin calls that failed inside the render: counted, the first one's message kept, for the render's report
/// (a path whose call failed contributes nothing from there on — never silently).
#[derive(Debug, Default)]
pub struct Failures {
    count: std::sync::atomic::AtomicU64,
    first: std::sync::OnceLock<String>,
}

impl Failures {
    /// `r`'s value, or `None` with the failure counted.
    pub fn note<T>(&self, r: Result<T, firemedium_loader::Error>) -> Option<T> {
        match r {
            Ok(v) => Some(v),
            Err(e) => {
                self.count
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                let _ = self.first.set(e.to_string());
                None
            }
        }
    }

    /// How many failed, and the first one's message.
    pub fn into_report(self) -> (u64, Option<String>) {
        (self.count.into_inner(), self.first.into_inner())
    }
}

/// Renders radiance along camera rays.
#[derive(Debug)]
pub struct Integrator<'a> {
    pub scene: &'a Scene,
    pub mask: S,
    /// Fire-light samples taken (next-event estimation toward a fire), for the render's statistics.
    pub fire_samples: std::sync::atomic::AtomicU64,
    /// Plugin calls that failed inside the render.
    pub failures: Failures,
}

impl Integrator<'_> {
    fn rng2(rng: &mut Samples) -> [f32; 2] {
        [rng.next_f64() as f32, rng.next_f64() as f32]
    }

    /// Walks from `o` along `d` for distance parameter `t_max` through surfaces that are only medium boundaries:
    /// (transmittance — zero if an opaque surface is in the way —, the emission of medium `fire` seen along
    /// the way, attenuated by every medium in front of it, as its fire light estimates it). With `fire` the walk
    /// ends where the fire's shapes can no longer be reached, its transmittance then only that far (a light
    /// sample wants the emission alone).
    fn walk_media(
        &self,
        mut o: Vec3A,
        d: Vec3A,
        mut t_max: f32,
        mut medium: Option<usize>,
        fire: Option<(usize, &firemedium_loader::Light)>,
        rng: &mut Samples,
    ) -> (S, S) {
        let eps = self.scene.eps;
        let mut tr = self.mask;
        let mut l = S::ZERO;
        for _ in 0..64 {
            let hit = self.scene.bvh.intersect(o, d, eps, t_max - eps);
            let seg = hit.map(|h| h.t).unwrap_or(t_max);
            if let Some(m) = medium {
                let light = fire.filter(|f| f.0 == m).map(|f| f.1);
                let (le, t) = match light {
                    Some(light) => self.light_segment(light, m, o, d, seg, rng),
                    None => self.medium_segment(m, o, d, seg, rng, false),
                };
                if light.is_some() {
                    l += tr * le;
                }
                tr *= t;
                if tr.max() <= 0.0 {
                    return (S::ZERO, l);
                }
            }
            let Some(h) = hit else { return (tr, l) };
            let prim = self.scene.bvh.prim(&h);
            if prim.material.is_some() {
                return (S::ZERO, l);
            }
            if let Some((inside, outside)) = prim.media {
                medium = if d.dot(h.ng) > 0.0 { outside } else { inside };
            }
            o = h.p;
            t_max -= h.t;
            // A light's walk outside its fire that cannot reach a shape bounding the fire's medium again has
            // gathered all the fire's light it will (its transmittance from here on is not wanted): the rest of
            // the walk — a traversal to the wall behind — is skipped.
            if let Some((f, _)) = fire {
                if medium != Some(f) && !self.reaches(f, o, d, t_max) {
                    return (tr, l);
                }
            }
        }
        (tr, l)
    }

    /// Whether o + t·d, t ∈ (eps / 2, t_max), meets the box of the shapes bounding medium `m` (the slab test).
    fn reaches(&self, m: usize, o: Vec3A, d: Vec3A, t_max: f32) -> bool {
        let Some(Some(b)) = self.scene.media_boxes.get(m) else {
            return false;
        };
        let inv = d.recip();
        let (t0, t1) = ((b.min - o) * inv, (b.max - o) * inv);
        let (near, far) = (t0.min(t1).max_element(), t0.max(t1).min_element());
        // (The walk's next traversal starts at t = eps — from a point on the box's face, `far` is 0 up to
        // rounding —, so a box that ends before eps / 2 holds nothing it could hit. NaN from 0 × ∞ on a face's
        // plane: counted as reaching, the walk goes on as before.)
        !(near > far || far < 0.5 * self.scene.eps || near > t_max)
    }

    /// Radiance from one light toward `spot` (NEE), already divided by the light's selection probability:
    /// (incident radiance × visibility, direction, the light's solid-angle pdf of that direction including the
    /// selection probability — for MIS; 0 for delta lights, which paths cannot hit by themselves).
    /// `dark(wi)`: whether the vertex reflects nothing toward `wi` (a surface's BSDF is zero there), so a fire
    /// light sample in that direction skips the march along it.
    fn sample_light(
        &self,
        li: usize,
        spot: &Spot,
        rng: &mut Samples,
        dark: &dyn Fn(Vec3A) -> bool,
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
                // The fire's emission along wi, up to the first opaque surface.
                let le = self
                    .walk_media(o, wi, f32::INFINITY, medium, Some((*fm, light)), rng)
                    .1;
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
    fn area_pdf(&self, li: usize, origin: Vec3A, h: &Hit) -> f32 {
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
    fn emission_weight(
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

    /// A real scattering event in a medium at `p`: NEE with the Henyey–Greenstein phase function (MIS-weighted
    /// against phase sampling for the fire light), then the next direction sampled from it (weight 1) and its
    /// solid-angle pdf.
    #[allow(clippy::too_many_arguments)]
    fn scatter_vertex(
        &self,
        p: Vec3A,
        d: Vec3A,
        g: f32,
        medium: Option<usize>,
        depth: usize,
        beta: S,
        l: &mut S,
        rng: &mut Samples,
    ) -> (Vec3A, f32) {
        let lights = &self.scene.lights;
        if !lights.is_empty() {
            let li = (rng.next_f64() * lights.len() as f64) as usize % lights.len();
            let spot = Spot::Medium { p, medium };
            if self.light_counts(li, depth + 1) && !self.skips_inside(li, medium) {
                if let Some((le, wi, pl)) = self.sample_light(li, &spot, rng, &|_| false) {
                    let ph = hg((-d).dot(wi), g);
                    *l += beta * le * (ph * light_mis_weight(pl, ph));
                }
            }
        }
        let wi = sample_hg(d, g, Self::rng2(rng));
        (wi, hg((-d).dot(wi), g))
    }

    /// Whether light `li` counts for a path whose next segment is at `depth` (bounces so far): a fire light
    /// samples a medium's emission, which pbrt-v4's `VolPathIntegrator` adds only while `depth < maxdepth`
    /// (a real scattering event counts as a bounce); the other lights always count, as there.
    fn light_counts(&self, li: usize, depth: usize) -> bool {
        depth < self.scene.maxdepth || !matches!(self.scene.lights[li], Light::Fire { .. })
    }

    /// Whether a scattering event in `medium` leaves light `li` unsampled: the fire light of that very medium,
    /// unless the scene asks for it ([`super::scene::Scene::fire_light_inside`]). The emission the next segment
    /// finds in that medium then has MIS weight 1 ([`Self::emission_weight`]'s `skipped`).
    fn skips_inside(&self, li: usize, medium: Option<usize>) -> bool {
        !self.scene.fire_light_inside
            && matches!(self.scene.lights[li], Light::Fire { medium: fm, .. } if Some(fm) == medium)
    }

    /// Radiance along a camera ray.
    pub fn li(&self, o: Vec3A, d: Vec3A, rng: &mut Samples) -> S {
        self.li_visible(o, d, rng, None, None)
    }

    /// Radiance along a camera ray and, when `visible` is given, the surface the ray sees first (pbrt-v4's
    /// `VisibleSurface`: the first hit with a material, before any scattering; none when a medium scattered the
    /// path first or the ray escaped).
    /// With `split`, where the radiance came from (the AOVs, [`Split`]).
    pub fn li_visible(
        &self,
        mut o: Vec3A,
        mut d: Vec3A,
        rng: &mut Samples,
        mut visible: Option<&mut Option<Visible>>,
        mut split: Option<&mut Split>,
    ) -> S {
        let sc = self.scene;
        let mut l = S::ZERO;
        let mut beta = self.mask;
        let mut medium = sc.camera.medium;
        let mut depth = 0;
        // The bin a dispersive dielectric made the path keep, and the product of the η² crossed (which scales
        // radiance, not what the path carries, so Russian roulette undoes it).
        let mut channel: Option<usize> = None;
        let mut eta_scale = 1.0f32;
        // Origin and solid-angle pdf of the current direction when it was sampled from a BSDF or phase function
        // (for MIS against the lights it may find); None for camera rays and specular bounces.
        let mut mis: Option<(Vec3A, f32)> = None;
        // The medium of the last vertex when it was a scattering event (whose own fire light it did not sample).
        let mut skipped: Option<usize> = None;
        for _ in 0..(4 * sc.maxdepth + 64) {
            // Ctrl-C or SIGTERM within a path too (a maxdepth of 1e8 in an albedo-1 medium is one long path): its
            // tile is then left out, never written half-done.
            if super::interrupted() {
                break;
            }
            let hit = sc.bvh.intersect(o, d, sc.eps, f32::INFINITY);
            let t_end = hit.map(|h| h.t).unwrap_or(f32::INFINITY);
            if let Some(m) = medium {
                let (emitted, track) = self.track(m, o, d, t_end, rng);
                if depth < sc.maxdepth {
                    match emitted.fire_units {
                        // (MIS's density only for light that is there: a dark segment needs no walk.)
                        Some(units) if !emitted.l.is_black() => {
                            l += beta
                                * emitted.l
                                * (units * self.emission_weight(m, mis, skipped, d, rng.time));
                        }
                        Some(_) => {}
                        None => l += beta * emitted.l,
                    }
                }
                match track {
                    Track::Scattered { t, weight, g } => {
                        beta *= weight;
                        if depth >= sc.maxdepth {
                            break;
                        }
                        let p = o + d * t;
                        Split::mark(&mut split, depth, l);
                        let (wi, pdf) =
                            self.scatter_vertex(p, d, g, medium, depth, beta, &mut l, rng);
                        (o, d, mis, skipped) = (p, wi, Some((p, pdf)), medium);
                        depth += 1;
                        continue;
                    }
                    Track::Passed { weight, bent } => {
                        beta *= weight;
                        // A refracting fire bent the ray: continue from where it left, in its new direction
                        // (the surface hit found along the straight line no longer applies).
                        if let Some((p, w)) = bent {
                            if beta.max() <= 0.0 {
                                break;
                            }
                            (o, d) = (p, w);
                            continue;
                        }
                    }
                    Track::Absorbed => break,
                }
                if beta.max() <= 0.0 {
                    break;
                }
            }
            let Some(h) = hit else {
                // Escaped: the infinite lights, weighted against their next-event estimation when the
                // direction was sampled by a BSDF or phase function.
                for light in &sc.lights {
                    let le = env(light, d);
                    if !le.is_black() {
                        let w = mis.map_or(1.0, |(origin, pb)| {
                            let pl = env_pdf(light, origin, d) / sc.lights.len() as f32;
                            if pb + pl > 0.0 {
                                pb / (pb + pl)
                            } else {
                                1.0
                            }
                        });
                        l += beta * le * w;
                        if depth == 0 {
                            if let Some(sp) = split.as_deref_mut() {
                                sp.emission += beta * le * w;
                            }
                        }
                    }
                }
                // The camera ray escaped: its coverage is what the media it crossed took.
                if depth == 0 {
                    if let Some(sp) = split.as_deref_mut() {
                        let n = sc.bins.n().max(1) as f32;
                        let t = beta.0[..sc.bins.n()].iter().sum::<f32>() / n;
                        sp.alpha = Some((1.0 - t).clamp(0.0, 1.0));
                    }
                }
                break;
            };
            let prim = sc.bvh.prim(&h);
            if let Some(li) = prim.area_light {
                if let Light::Area {
                    l: le, twosided, ..
                } = &sc.lights[li]
                {
                    if *twosided || h.ng.dot(-d) > 0.0 {
                        let w = mis.map_or(1.0, |(origin, pb)| {
                            let pl = self.area_pdf(li, origin, &h);
                            if pb + pl > 0.0 {
                                pb / (pb + pl)
                            } else {
                                1.0
                            }
                        });
                        l += beta * *le * w;
                        if depth == 0 {
                            if let Some(sp) = split.as_deref_mut() {
                                sp.emission += beta * *le * w;
                            }
                        }
                    }
                }
            }
            let wo = -d;
            let side_medium = |w: Vec3A| match prim.media {
                Some((inside, outside)) => {
                    if w.dot(h.ng) > 0.0 {
                        outside
                    } else {
                        inside
                    }
                }
                None => medium,
            };
            let Some(mi) = material::resolve(&sc.materials, prim.material, h.p, wo, h.uv) else {
                // Only a medium boundary (or a `mix` that chose `interface`): pass through.
                if let Some((inside, outside)) = prim.media {
                    medium = if d.dot(h.ng) > 0.0 { outside } else { inside };
                }
                o = h.p;
                continue;
            };
            // pbrt-v4 records the visible surface before it ends a path at its maximum depth.
            let record = depth == 0 && visible.is_some();
            if depth >= sc.maxdepth && !record {
                break;
            }
            let mat = &sc.materials[mi];
            let n = sc.bins.n();
            // A dispersive index: the path keeps one bin (uniformly chosen; its weight × the bin count).
            if channel.is_none() && mat.eta().is_some_and(|e| e.dispersive(n)) {
                let c = ((rng.next_f64() * n as f64) as usize).min(n.max(1) - 1);
                let mut keep = S::ZERO;
                keep.0[c] = n as f32;
                beta *= keep;
                channel = Some(c);
            }
            let Some(bxdf) = mat.bxdf(h.uv, channel, n) else {
                break;
            };
            let seed = rng.next_u64();
            let wo_l = to_local(h.ns, wo);
            if wo_l.z == 0.0 {
                break;
            }
            if depth == 0 {
                if let Some(v) = visible.take() {
                    // The albedo ρ(wo) = ∫ f |cos| dωi, estimated by one BSDF sample per camera sample (the
                    // pixel's mean over its samples is pbrt-v4's `rho` by Monte Carlo).
                    let (uc, u) = (rng.next_f64() as f32, Self::rng2(rng));
                    let albedo = bxdf
                        .sample_f(wo_l, uc, u, Mode::Radiance, Lobes::ALL, seed)
                        .filter(|bs| bs.pdf > 0.0)
                        .map_or(S::ZERO, |bs| {
                            (bs.f * (bs.wi.z.abs() / bs.pdf)).finite_or_zero()
                        });
                    *v = Some(Visible {
                        p: h.p,
                        ng: h.ng,
                        ns: h.ns,
                        albedo,
                    });
                }
            }
            if depth >= sc.maxdepth {
                break;
            }
            Split::mark(&mut split, depth, l);
            // Next-event estimation through the BSDF, weighted against BSDF sampling for lights paths can hit.
            if bxdf.flags().non_specular() && !sc.lights.is_empty() {
                let li = (rng.next_f64() * sc.lights.len() as f64) as usize % sc.lights.len();
                let spot = Spot::Surface {
                    p: h.p,
                    ng: h.ng,
                    eps: sc.eps,
                    media: prim.media,
                    medium,
                };
                // (A direction the BSDF does not reflect: no march along it. The BSDF's value there is kept, so a
                // fire-light sample evaluates it once.)
                let seen = std::cell::Cell::new(None);
                let dark = |wi: Vec3A| {
                    let f = bxdf.f(wo_l, to_local(h.ns, wi), Mode::Radiance, seed);
                    seen.set(Some((wi, f)));
                    f.is_black()
                };
                let found = match self.light_counts(li, depth + 1) {
                    true => self.sample_light(li, &spot, rng, &dark),
                    false => None,
                };
                if let Some((le, wi, pl)) = found {
                    let wi_l = to_local(h.ns, wi);
                    let f = match seen.get() {
                        Some((w, f)) if w == wi => f,
                        _ => bxdf.f(wo_l, wi_l, Mode::Radiance, seed),
                    } * wi_l.z.abs();
                    if !f.is_black() {
                        let pb = if pl > 0.0 {
                            bxdf.pdf(wo_l, wi_l, Mode::Radiance, Lobes::ALL, seed)
                        } else {
                            0.0
                        };
                        l += beta * f * le * light_mis_weight(pl, pb);
                    }
                }
            }
            // Sample the BSDF.
            let uc = rng.next_f64() as f32;
            let u = Self::rng2(rng);
            let Some(bs) = bxdf.sample_f(wo_l, uc, u, Mode::Radiance, Lobes::ALL, seed) else {
                break;
            };
            let wi = from_local(h.ns, bs.wi);
            if !wi.is_finite() || wi == Vec3A::ZERO {
                break;
            }
            beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
            if !beta.max().is_finite() {
                break;
            }
            mis = (!bs.specular).then(|| {
                let pdf = if bs.proportional {
                    bxdf.pdf(wo_l, bs.wi, Mode::Radiance, Lobes::ALL, seed)
                } else {
                    bs.pdf
                };
                (h.p, pdf)
            });
            if !bs.reflection {
                eta_scale *= bs.etap * bs.etap;
            }
            medium = side_medium(wi);
            skipped = None;
            o = h.p + if wi.dot(h.ng) > 0.0 { h.ng } else { -h.ng } * sc.eps;
            d = wi;
            depth += 1;
            // Russian roulette after three bounces, on the throughput without the radiance scaling that
            // refraction applies (pbrt-v4's etaScale).
            if depth > 3 {
                let q = (beta * eta_scale).max().min(0.95);
                if (rng.next_f64() as f32) > q {
                    break;
                }
                beta = beta / q;
            }
        }
        l.finite_or_zero()
    }
}
