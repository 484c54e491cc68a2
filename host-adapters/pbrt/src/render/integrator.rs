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

use super::aov::{Split, Visible};
use super::bsdf::{Bxdf, Lobes, Mode};
use super::lights;
use super::lobes::{around, frame, henyey_greenstein as hg, sample_henyey_greenstein_cos};
use super::material;
use super::media::Track;
use super::paths::Spot;
pub use super::paths::{Failures, Integrator};
use super::pixel::Samples;
use super::profile::{clock, credit, took, Gain, Step, Tally};
use super::scene::Light;
use super::shapes::Hit;
use super::spectrum::S;
use glam::Vec3A;
use std::time::Instant;

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

/// The MIS weight of a light a path found by a direction it sampled (density `pb` from `origin`) against
/// next-event estimation's density of that direction, `pl(origin)`: the balance heuristic; 1 for camera rays and
/// specular bounces (`mis` None), which next-event estimation cannot take.
fn found_weight(mis: Option<(Vec3A, f32)>, pl: impl FnOnce(Vec3A) -> f32) -> f32 {
    mis.map_or(1.0, |(origin, pb)| {
        let pl = pl(origin);
        if pb + pl > 0.0 {
            pb / (pb + pl)
        } else {
            1.0
        }
    })
}

/// Adds a light the path found to its radiance, and — seen from the camera — to the AOVs' emission part.
fn seen(l: &mut S, split: &mut Option<&mut Split>, depth: usize, contribution: S) {
    *l += contribution;
    if depth == 0 {
        if let Some(sp) = split.as_deref_mut() {
            sp.emission += contribution;
        }
    }
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

/// The surface a camera ray sees first at `h` (pbrt-v4's `VisibleSurface`), its albedo ρ(wo) = ∫ f |cos| dωi
/// estimated by one sample of `bxdf` per camera sample (the pixel's mean over its samples is pbrt-v4's `rho` by
/// Monte Carlo).
fn visible_surface(h: &Hit, bxdf: &Bxdf, wo_l: Vec3A, seed: u64, rng: &mut Samples) -> Visible {
    let (uc, u) = (rng.next_f64() as f32, Integrator::rng2(rng));
    let albedo = bxdf
        .sample_f(wo_l, uc, u, Mode::Radiance, Lobes::ALL, seed)
        .filter(|bs| bs.pdf > 0.0)
        .map_or(S::ZERO, |bs| {
            (bs.f * (bs.wi.z.abs() / bs.pdf)).finite_or_zero()
        });
    Visible {
        p: h.p,
        ng: h.ng,
        ns: h.ns,
        albedo,
    }
}

/// A direction from `bxdf` at a surface (shading normal `ns`, `wo_l` in its frame): the world direction and the
/// sample, or None when the sample failed.
#[inline]
fn sample_bsdf(
    bxdf: &Bxdf,
    wo_l: Vec3A,
    ns: Vec3A,
    seed: u64,
    rng: &mut Samples,
) -> Option<(Vec3A, super::bsdf::Sample)> {
    let uc = rng.next_f64() as f32;
    let u = Integrator::rng2(rng);
    let bs = bxdf.sample_f(wo_l, uc, u, Mode::Radiance, Lobes::ALL, seed)?;
    let wi = from_local(ns, bs.wi);
    (wi.is_finite() && wi != Vec3A::ZERO).then_some((wi, bs))
}

/// A direction from a surface whose BxDF can be [guided](super::guide): the guide's with its share, else the
/// BSDF's; the world direction, the path's gain f·|cos| over the mixture's density, and that density (for MIS).
#[inline]
fn sample_guided(
    bxdf: &Bxdf,
    guide: &super::guide::Guide,
    (p, ns, wo_l): (Vec3A, Vec3A, Vec3A),
    seed: u64,
    rng: &mut Samples,
) -> Option<(Vec3A, S, f32)> {
    let wi = if (rng.next_f64() as f32) < guide.prob() {
        let u = [0; 3].map(|_| rng.next_f64() as f32);
        guide.sample(p, u)?
    } else {
        sample_bsdf(bxdf, wo_l, ns, seed, rng)?.0
    };
    let wi_l = to_local(ns, wi);
    let f = bxdf.f(wo_l, wi_l, Mode::Radiance, seed);
    let pdf = guide.mixed(
        p,
        wi,
        bxdf.pdf(wo_l, wi_l, Mode::Radiance, Lobes::ALL, seed),
    );
    (pdf > 0.0 && !f.is_black()).then(|| (wi, f * (wi_l.z.abs() / pdf), pdf))
}

/// How a path leaves a surface: its direction, the gain f·|cos|/pdf, the origin and pdf for MIS (None after a
/// specular bounce) and the η² a refraction crossed (1 for a reflection).
struct Left {
    wi: Vec3A,
    gain: S,
    mis: Option<(Vec3A, f32)>,
    eta2: f32,
}

/// The direction a path leaves a surface by (world point `p`, shading normal `ns`, `wo_l` in its frame): the
/// BSDF's sample, or — where the BxDF can be guided — the mixture's with `guide`; None when sampling failed.
#[inline]
fn leave(
    bxdf: &Bxdf,
    guide: Option<&super::guide::Guide>,
    (p, ns, wo_l): (Vec3A, Vec3A, Vec3A),
    seed: u64,
    rng: &mut Samples,
) -> Option<Left> {
    if let Some(g) = guide {
        let (wi, gain, pdf) = sample_guided(bxdf, g, (p, ns, wo_l), seed, rng)?;
        return Some(Left {
            wi,
            gain,
            mis: Some((p, pdf)),
            eta2: 1.0,
        });
    }
    let (wi, bs) = sample_bsdf(bxdf, wo_l, ns, seed, rng)?;
    Some(Left {
        wi,
        gain: bs.f * (bs.wi.z.abs() / bs.pdf),
        mis: (!bs.specular).then(|| (p, mis_pdf(bxdf, wo_l, &bs, seed))),
        eta2: if bs.reflection {
            1.0
        } else {
            bs.etap * bs.etap
        },
    })
}

/// A non-specular BSDF sample's solid-angle pdf for MIS (the BSDF's own when the sample's is only proportional).
#[inline]
fn mis_pdf(bxdf: &Bxdf, wo_l: Vec3A, bs: &super::bsdf::Sample, seed: u64) -> f32 {
    if bs.proportional {
        bxdf.pdf(wo_l, bs.wi, Mode::Radiance, Lobes::ALL, seed)
    } else {
        bs.pdf
    }
}

/// Russian roulette (after three bounces), on the throughput without the radiance scaling refraction applies
/// (pbrt-v4's etaScale): whether the path goes on, its gain `beta` then divided by the odds it had.
#[inline]
fn survives(beta: &mut S, eta_scale: f32, rng: &mut Samples) -> bool {
    let q = (*beta * eta_scale).max().min(0.95);
    if (rng.next_f64() as f32) > q {
        return false;
    }
    *beta = *beta / q;
    true
}

/// Counts a light sample from a surface vertex (`surface`) or a scattering one, begun at `t0`, and credits what
/// it added to the radiance `l`, by whether `light` is a fire's, in a profiled path.
fn light_sampled(
    tally: &mut Option<Tally>,
    surface: bool,
    light: &Light,
    t0: Option<Instant>,
    l: &S,
    n: usize,
) {
    let (step, gain) = match (surface, matches!(light, Light::Fire(_))) {
        (true, true) => (Step::SurfaceFireSample, Gain::SurfaceFire),
        (true, false) => (Step::SurfaceLightSample, Gain::SurfaceLight),
        (false, true) => (Step::MediumFireSample, Gain::MediumFire),
        (false, false) => (Step::MediumLightSample, Gain::MediumLight),
    };
    took(tally, step, t0);
    credit(tally, gain, l, n);
}

/// Keeps one of `n` bins of the path's gain `beta`, uniformly chosen, weighted by `n`; which.
fn keep_one_bin(beta: &mut S, n: usize, rng: &mut Samples) -> usize {
    let c = ((rng.next_f64() * n as f64) as usize).min(n.max(1) - 1);
    let mut keep = S::ZERO;
    keep.0[c] = n as f32;
    *beta *= keep;
    c
}

/// Samples HG around the propagation direction `d`.
fn sample_hg(d: Vec3A, g: f32, u: [f32; 2]) -> Vec3A {
    around(d, sample_henyey_greenstein_cos(g, u[0]), u[1])
}

impl Integrator<'_> {
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
        tally: &mut Option<Tally>,
    ) -> (Vec3A, f32) {
        let lights = &self.scene.lights;
        if !lights.is_empty() {
            let li = (rng.next_f64() * lights.len() as f64) as usize % lights.len();
            let spot = Spot::Medium { p, medium };
            if self.light_counts(li, depth + 1) && !self.skips_inside(li, medium) {
                let t0 = clock(tally);
                if let Some((le, wi, pl)) = self.sample_light(li, &spot, rng, &|_| false, tally) {
                    let ph = hg((-d).dot(wi), g);
                    *l += beta * le * (ph * light_mis_weight(pl, ph));
                }
                if tally.is_some() {
                    let n = self.scene.bins.n();
                    light_sampled(tally, false, &lights[li], t0, l, n);
                }
            }
        }
        let wi = sample_hg(d, g, Self::rng2(rng));
        (wi, hg((-d).dot(wi), g))
    }

    /// A path that escaped along `d` with gain `beta` after `depth` bounces: the infinite lights, weighted
    /// against their next-event estimation when the direction was sampled by a BSDF or phase function (`mis`);
    /// an escaping camera ray's coverage (what the media it crossed took) into the AOVs.
    fn escaped(
        &self,
        d: Vec3A,
        beta: S,
        mis: Option<(Vec3A, f32)>,
        depth: usize,
        l: &mut S,
        split: &mut Option<&mut Split>,
    ) {
        let sc = self.scene;
        for light in &sc.lights {
            let le = lights::env(light, d);
            if !le.is_black() {
                let w = found_weight(mis, |origin| {
                    lights::env_pdf(light, origin, d) / sc.lights.len() as f32
                });
                seen(l, split, depth, beta * le * w);
            }
        }
        if depth == 0 {
            if let Some(sp) = split.as_deref_mut() {
                let n = sc.bins.n().max(1) as f32;
                let t = beta.0[..sc.bins.n()].iter().sum::<f32>() / n;
                sp.alpha = Some((1.0 - t).clamp(0.0, 1.0));
            }
        }
    }

    /// The segment `at` = (o, d, t_end, bounces so far) of a path through medium `m`: the emission it adds to
    /// `l` (below the maximum depth; a fire's weighted by MIS against its light when the direction was sampled,
    /// `mis`, unless the last vertex `skipped` that light) and how the segment ends.
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &self,
        m: usize,
        at: (Vec3A, Vec3A, f32, usize),
        mis: Option<(Vec3A, f32)>,
        skipped: Option<usize>,
        beta: S,
        l: &mut S,
        rng: &mut Samples,
        tally: &mut Option<Tally>,
    ) -> Track {
        let (o, d, t_end, depth) = at;
        let t0 = clock(tally);
        let (emitted, track) = self.track(m, o, d, t_end, rng, mis.is_none());
        let (step, gain) = match (depth, skipped) {
            (0, _) => (Step::CameraSegment, Gain::CameraEmission),
            (_, None) => (Step::LaterSegment, Gain::FoundEmission),
            (_, Some(_)) => (Step::LaterSegment, Gain::ScatteredEmission),
        };
        took(tally, step, t0);
        if depth < self.scene.maxdepth {
            match emitted.fire_units {
                // (MIS's density only for light that is there: a dark segment needs no walk.)
                Some(units) if !emitted.l.is_black() => {
                    let t0 = clock(tally);
                    let w = self.emission_weight(m, mis, skipped, d, rng.time);
                    took(tally, Step::EmissionMis, t0);
                    *l += beta * emitted.l * (units * w);
                }
                Some(_) => {}
                None => *l += beta * emitted.l,
            }
        }
        credit(tally, gain, l, self.scene.bins.n());
        track
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
        let n_bins = sc.bins.n();
        // A profiled render's tally of this path (`--profile`).
        let start = self.profile.as_ref().map(|_| Instant::now());
        let mut tally = start.map(|_| Tally::new(rng.pixel_key()));
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
            let t0 = clock(&tally);
            let hit = sc.bvh.intersect(o, d, sc.eps, f32::INFINITY);
            took(&mut tally, Step::Traverse, t0);
            let t_end = hit.map(|h| h.t).unwrap_or(f32::INFINITY);
            if let Some(m) = medium {
                let at = (o, d, t_end, depth);
                let track = self.segment(m, at, mis, skipped, beta, &mut l, rng, &mut tally);
                match track {
                    Track::Scattered { t, weight, g } => {
                        beta *= weight;
                        if depth >= sc.maxdepth {
                            break;
                        }
                        let p = o + d * t;
                        Split::mark(&mut split, depth, l);
                        let t0 = clock(&tally);
                        let (wi, pdf) = self
                            .scatter_vertex(p, d, g, medium, depth, beta, &mut l, rng, &mut tally);
                        took(&mut tally, Step::MediumVertex, t0);
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
                self.escaped(d, beta, mis, depth, &mut l, &mut split);
                credit(&mut tally, Gain::FoundLight, &l, n_bins);
                break;
            };
            let prim = sc.bvh.prim(&h);
            if let Some((li, le)) = prim
                .area_light
                .and_then(|li| Some((li, self.area_le(li, &h, d)?)))
            {
                let w = found_weight(mis, |origin| self.area_pdf(li, origin, &h));
                seen(&mut l, &mut split, depth, beta * le * w);
                credit(&mut tally, Gain::FoundLight, &l, n_bins);
            }
            let wo = -d;
            // Where the path leaves the surface from (the side a direction leaves by picks the offset and the
            // medium), for next-event estimation and the path's next segment alike.
            let spot = Spot::Surface {
                p: h.p,
                ng: h.ng,
                eps: sc.eps,
                media: prim.media,
                medium,
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
            if let Some(t) = tally.as_mut() {
                t.count(Step::SurfaceVertex);
            }
            let mat = &sc.materials[mi];
            let n = sc.bins.n();
            // A dispersive index: the path keeps one bin (uniformly chosen; its weight × the bin count).
            if channel.is_none() && mat.eta().is_some_and(|e| e.dispersive(n)) {
                channel = Some(keep_one_bin(&mut beta, n, rng));
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
                    *v = Some(visible_surface(&h, &bxdf, wo_l, seed, rng));
                }
            }
            if depth >= sc.maxdepth {
                break;
            }
            Split::mark(&mut split, depth, l);
            // Where a share of the directions aims at a scattering fire ([`super::guide`]).
            let guide = sc.guide.as_ref().filter(|_| bxdf.guidable());
            // Next-event estimation through the BSDF, weighted against BSDF sampling for lights paths can hit.
            if bxdf.flags().non_specular() && !sc.lights.is_empty() {
                let li = (rng.next_f64() * sc.lights.len() as f64) as usize % sc.lights.len();
                let t0 = clock(&tally);
                // (A direction the BSDF does not reflect: no march along it. The BSDF's value there is kept, so a
                // fire-light sample evaluates it once.)
                let seen = std::cell::Cell::new(None);
                let dark = |wi: Vec3A| {
                    let f = bxdf.f(wo_l, to_local(h.ns, wi), Mode::Radiance, seed);
                    seen.set(Some((wi, f)));
                    f.is_black()
                };
                let found = match self.light_counts(li, depth + 1) {
                    true => self.sample_light(li, &spot, rng, &dark, &mut tally),
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
                            let pb = bxdf.pdf(wo_l, wi_l, Mode::Radiance, Lobes::ALL, seed);
                            guide.map_or(pb, |g| g.mixed(h.p, wi, pb))
                        } else {
                            0.0
                        };
                        l += beta * f * le * light_mis_weight(pl, pb);
                    }
                }
                if tally.is_some() {
                    light_sampled(&mut tally, true, &sc.lights[li], t0, &l, n_bins);
                }
            }
            let Some(left) = leave(&bxdf, guide, (h.p, h.ns, wo_l), seed, rng) else {
                break;
            };
            beta *= left.gain;
            if !beta.max().is_finite() {
                break;
            }
            (mis, eta_scale) = (left.mis, eta_scale * left.eta2);
            let wi = left.wi;
            (o, medium) = spot.leave(wi);
            skipped = None;
            d = wi;
            depth += 1;
            if depth > 3 && !survives(&mut beta, eta_scale, rng) {
                break;
            }
        }
        if let (Some(mut t), Some(p), Some(s)) = (tally, self.profile.as_ref(), start) {
            t.finish(s);
            p.add(&t);
        }
        l.finite_or_zero()
    }
}
