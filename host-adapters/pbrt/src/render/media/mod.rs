//! The media as the integrator sees them. Each kind, in its own file — pbrt-v4's `homogeneous` in closed form
//! ([`homogeneous`]), its `rgbgrid` tracked in the host (`rgbgrid`), a plugin medium through the ABI's
//! whole-ray queries ([`plugin`]); what each holds is the scene's — answers the same two questions ([`MediumKind`]): what one segment of a path
//! does (`track`: scattered where, with what weight and phase function; passed, with what transmittance,
//! perhaps bent; absorbed — and the emission it added), and what a segment transmits and emits (`segment`, for
//! shadow rays and light walks). The integrator asks these through [`Integrator::track`] and
//! [`Integrator::medium_segment`] and never which kind it holds; a new kind is a file and one arm in each.

pub mod homogeneous;
pub mod plugin;
mod rgbgrid;

use super::paths::Integrator;
use super::pixel::Samples;
use super::scene::Medium;
use super::spectrum::S;
use super::tracker::{self, Tracked};
use firemedium_loader::Ray as FRay;
use glam::{DAffine3, DVec3, Vec3A};

/// What a medium did to a path along one segment.
#[derive(Debug, Clone, Copy)]
pub(super) enum Track {
    /// Scattered at o + t·d: the path's weight there (transmittance × σ_s / pdf) and the phase function's g.
    Scattered { t: f32, weight: S, g: f32 },
    /// Crossed the segment: its weight; a refracting medium bent the ray (world point and unit direction where
    /// it leaves).
    Passed {
        weight: S,
        bent: Option<(Vec3A, Vec3A)>,
    },
    /// Absorbed (or a plugin call failed, counted): the path ends.
    Absorbed,
}

/// The emission a segment added, before the path's weight.
#[derive(Debug, Clone, Copy)]
pub(super) struct Emitted {
    pub l: S,
    /// A fire medium's emission, which its fire light also samples: weighted by MIS, scaled by these units
    /// (None: nothing else samples it, added as it is).
    pub fire_units: Option<f32>,
}

/// What a kind of medium answers the integrator (pbrt-v4's `Medium` interface, answered per segment).
pub(super) trait MediumKind {
    /// Transmittance of the medium along o + t·d, t ∈ [0, t_end], the emission it adds (with `emission`), and —
    /// with `want_exit` — where the ray leaves if the medium bent it (world point, unit direction; None when it
    /// went straight).
    #[allow(clippy::too_many_arguments)]
    fn segment(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
        want_exit: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>);

    /// What the medium does to a path along o + t·d, t ∈ [0, t_end]: the emission it adds and how the segment
    /// ends; `seen`: the segment is the camera's or a mirror image of it (no light sample could take it).
    fn track(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        seen: bool,
    ) -> (Emitted, Track);
}

/// World point `o` and direction `d` in the space `xf` maps to.
pub(super) fn to_space(xf: &DAffine3, o: Vec3A, d: Vec3A) -> (DVec3, DVec3) {
    let f = |v: Vec3A| DVec3::from(v.to_array().map(f64::from));
    (xf.transform_point3(f(o)), xf.transform_vector3(f(d)))
}

/// The plugin ray of the world segment o + t·d, t ∈ [0, t_end] (unbounded: 1e30), in medium space.
pub(super) fn plugin_ray(to_medium: &DAffine3, o: Vec3A, d: Vec3A, t_end: f32, seed: u64) -> FRay {
    let (om, dm) = to_space(to_medium, o, d);
    FRay {
        origin: om.to_array(),
        direction: dm.to_array(),
        tmin: 0.0,
        tmax: if t_end.is_finite() {
            t_end as f64
        } else {
            1e30
        },
        seed,
    }
}

impl Integrator<'_> {
    /// Transmittance of medium `m` along o + t·d, t ∈ [0, t_end], and (optionally) the emission it adds.
    pub(super) fn medium_segment(
        &self,
        m: usize,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
    ) -> (S, S) {
        let (l, t, _) = self.medium_segment_exit(m, o, d, t_end, rng, emission, false);
        (l, t)
    }

    /// The emission and transmittance of plugin medium `m` along o + t·d, t ∈ [0, t_end], as its fire light
    /// estimates them for a light sample's direction (`light_integrate`: a coarser march on a large fire).
    pub(super) fn light_segment(
        &self,
        light: &firemedium_loader::Light,
        m: usize,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
    ) -> (S, S) {
        let Medium::Plugin(p) = &self.scene.media[m] else {
            return self.medium_segment(m, o, d, t_end, rng, true);
        };
        let n = self.scene.bins.n();
        let ray = plugin_ray(&p.to_medium, o, d, t_end, rng.next_u64());
        let (mut l, mut t) = (
            [0f32; super::spectrum::MAX_CHANNELS],
            [0f32; super::spectrum::MAX_CHANNELS],
        );
        let estimated = light.integrate_at(
            std::slice::from_ref(&ray),
            Some(&[rng.time]),
            &mut l[..n],
            Some(&mut t[..n]),
        );
        if self.failures.note(estimated).is_none() {
            return (S::ZERO, S::ZERO);
        }
        (S(l) * p.units, S(t))
    }

    /// As [`medium_segment`](Self::medium_segment), and — when `want_exit` — where the ray leaves if a
    /// refracting plugin medium bent it (world space: point, unit direction); None when it went straight.
    /// Without `want_exit` the plugin integrates the straight ray (NEE and light paths).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn medium_segment_exit(
        &self,
        m: usize,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
        want_exit: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>) {
        let (e, x) = (emission, want_exit);
        match &self.scene.media[m] {
            Medium::Plugin(p) => p.segment(self, o, d, t_end, rng, e, x),
            Medium::Homogeneous(h) => h.segment(self, o, d, t_end, rng, e, x),
            Medium::RgbGrid(g) => g.segment(self, o, d, t_end, rng, e, x),
        }
    }

    /// What medium `m` does to the path along o + t·d, t ∈ [0, t_end]: the emission it adds (at delta tracking's
    /// tentative collisions for a scattering plugin medium, as pbrt-v4's volpath, unless the segment is `seen` —
    /// the camera's or a mirror image of it — and the medium marches what the camera sees; along the whole
    /// segment otherwise) and how the segment ends.
    #[inline]
    pub(super) fn track(
        &self,
        m: usize,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        seen: bool,
    ) -> (Emitted, Track) {
        match &self.scene.media[m] {
            Medium::Plugin(p) => p.track(self, o, d, t_end, rng, seen),
            Medium::Homogeneous(h) => h.track(self, o, d, t_end, rng, seen),
            Medium::RgbGrid(g) => g.track(self, o, d, t_end, rng, seen),
        }
    }

    /// Transmittance and emission of a medium the host tracks, by ratio tracking (a failed query is counted and
    /// blocks the segment).
    pub(super) fn host_segment(
        &self,
        medium: &impl Tracked,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>) {
        let speed = d.length();
        if !(speed > 0.0) {
            return (S::ZERO, S::splat(1.0), None);
        }
        let r = tracker::segment(
            medium,
            o,
            d / speed,
            t_end * speed,
            || rng.next_f64(),
            emission,
        );
        match self.failures.note(r) {
            Some((l, tr)) => (l, tr, None),
            None => (S::ZERO, S::ZERO, None),
        }
    }

    /// Delta tracking through a medium the host tracks, as [`Self::track`] answers it; `fire_units`: the
    /// emission's MIS with a fire light (Some(1): a plugin medium's, already in the film's units).
    pub(super) fn host_track(
        &self,
        medium: &impl Tracked,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        fire_units: Option<f32>,
    ) -> (Emitted, Track) {
        let speed = d.length();
        let r = tracker::track(medium, o, d / speed, t_end * speed, || rng.next_f64());
        let Some(t) = self.failures.note(r) else {
            let l = S::ZERO;
            return (Emitted { l, fire_units }, Track::Absorbed);
        };
        let emitted = |l: S| Emitted { l, fire_units };
        match t {
            tracker::Track::Scattered {
                s,
                weight,
                emitted: l,
            } => (
                emitted(l),
                Track::Scattered {
                    t: s / speed,
                    weight,
                    g: medium.g() as f32,
                },
            ),
            tracker::Track::Passed { weight, emitted: l } => {
                (emitted(l), Track::Passed { weight, bent: None })
            }
            tracker::Track::Absorbed { emitted: l } => (emitted(l), Track::Absorbed),
        }
    }

    /// Walks from `o` along `d` for distance parameter `t_max` through surfaces that are only medium boundaries:
    /// (transmittance — zero if an opaque surface is in the way —, the emission of medium `fire` seen along
    /// the way, attenuated by every medium in front of it, as its fire light estimates it). With `fire` the walk
    /// ends where the fire's shapes can no longer be reached, its transmittance then only that far (a light
    /// sample wants the emission alone).
    pub(super) fn walk_media(
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
    pub(super) fn reaches(&self, m: usize, o: Vec3A, d: Vec3A, t_max: f32) -> bool {
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
}
