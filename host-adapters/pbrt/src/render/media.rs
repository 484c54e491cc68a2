//! The media as the integrator sees them. Each kind — pbrt-v4's `homogeneous` in closed form, its `rgbgrid`
//! tracked in the host ([`super::rgbgrid`]), a plugin medium through the ABI's whole-ray queries — answers the
//! same two questions here: what one segment of a path does ([`Integrator::track`]: scattered where, with what
//! weight and phase function; passed, with what transmittance, perhaps bent; absorbed — and the emission it
//! added), and what a segment transmits and emits ([`Integrator::medium_segment`], for shadow rays and light
//! walks). The integrator asks these and never which kind it holds; a new kind is one arm in each.

use super::paths::Integrator;
use super::pixel::Samples;
use super::scene::Medium;
use super::spectrum::S;
use super::tracker::{self, PluginMedium, Tracked};
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
        let Medium::Plugin {
            to_medium, units, ..
        } = &self.scene.media[m]
        else {
            return self.medium_segment(m, o, d, t_end, rng, true);
        };
        let n = self.scene.bins.n();
        let ray = plugin_ray(to_medium, o, d, t_end, rng.next_u64());
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
        (S(l) * *units, S(t))
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
        let n = self.scene.bins.n();
        if let Some(pm) = self.host_medium(m) {
            return self.host_segment(&pm, o, d, t_end, rng, emission);
        }
        match &self.scene.media[m] {
            Medium::Plugin {
                vol,
                to_medium,
                to_world,
                units,
                ..
            } => {
                let ray = plugin_ray(to_medium, o, d, t_end, rng.next_u64());
                let time = [rng.time];
                let (mut l, mut t) = (
                    [0f32; super::spectrum::MAX_CHANNELS],
                    [0f32; super::spectrum::MAX_CHANNELS],
                );
                let mut exit = [firemedium_loader::Exit::default()];
                let done = if emission {
                    vol.integrate_at(
                        std::slice::from_ref(&ray),
                        Some(&time),
                        &mut l[..n],
                        Some(&mut t[..n]),
                        want_exit.then_some(&mut exit[..]),
                    )
                } else {
                    vol.transmittance_at(std::slice::from_ref(&ray), Some(&time), &mut t[..n])
                };
                if self.failures.note(done).is_none() {
                    return (S::ZERO, S::ZERO, None);
                }
                let bent = (emission && want_exit).then(|| {
                    let de = DVec3::from(exit[0].direction);
                    let dn = DVec3::from(ray.direction).normalize_or_zero();
                    (de.is_finite() && de.dot(dn) < 1.0 - 1e-12).then(|| {
                        let p = to_world.transform_point3(DVec3::from(exit[0].point));
                        let w = to_world.transform_vector3(de).normalize_or_zero();
                        (Vec3A::from(p.as_vec3()), Vec3A::from(w.as_vec3()))
                    })
                });
                (S(l) * *units, S(t), bent.flatten())
            }
            Medium::Homogeneous { sa, ss, le, .. } => {
                let len = if t_end.is_finite() {
                    t_end * d.length()
                } else {
                    f32::INFINITY
                };
                let st = *sa + *ss;
                let mut tr = S::ZERO;
                let mut l = S::ZERO;
                for i in 0..n {
                    let tau = st.0[i] * len;
                    tr.0[i] = (-tau).exp();
                    if emission && st.0[i] > 0.0 {
                        l.0[i] = sa.0[i] * le.0[i] * -(-tau).exp_m1() / st.0[i];
                    }
                }
                (l, tr, None)
            }
            Medium::RgbGrid(grid) => self.host_segment(&**grid, o, d, t_end, rng, emission),
        }
    }

    /// Plugin medium `m` as the host tracks it (`--tracking host`), if it is one.
    fn host_medium(&self, m: usize) -> Option<PluginMedium<'_>> {
        match &self.scene.media[m] {
            Medium::Plugin {
                vol,
                to_medium,
                units,
                g,
                host: Some(grid),
                ..
            } => Some(PluginMedium {
                vol,
                grid,
                to_medium,
                units: *units,
                bins: self.scene.bins.n(),
                g: *g,
            }),
            _ => None,
        }
    }

    /// Transmittance and emission of a medium the host tracks, by ratio tracking (a failed query is counted and
    /// blocks the segment).
    fn host_segment(
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
    fn host_track(
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

    /// What medium `m` does to the path along o + t·d, t ∈ [0, t_end]: the emission it adds (at delta tracking's
    /// tentative collisions for a scattering plugin medium, as pbrt-v4's volpath; along the whole segment
    /// otherwise) and how the segment ends.
    #[inline]
    pub(super) fn track(
        &self,
        m: usize,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
    ) -> (Emitted, Track) {
        let sc = self.scene;
        let n = sc.bins.n();
        let plain = |l: S| Emitted {
            l,
            fire_units: None,
        };
        if let Some(pm) = self.host_medium(m) {
            return self.host_track(&pm, o, d, t_end, rng, Some(1.0));
        }
        match &sc.media[m] {
            Medium::Plugin {
                vol,
                to_medium,
                g,
                units,
                scatters: true,
                ..
            } => {
                let ray = plugin_ray(to_medium, o, d, t_end, rng.next_u64());
                let mut ev = [firemedium_loader::Scatter::default()];
                let (mut w, mut e) = (
                    [0f32; super::spectrum::MAX_CHANNELS],
                    [0f32; super::spectrum::MAX_CHANNELS],
                );
                // (Emission at the tentative collisions: marching it along every segment instead cost 7× the
                // time for no less error on a scattering fire — docs/results/log.md.)
                let tracked = vol.sample_scatter_at(
                    std::slice::from_ref(&ray),
                    Some(&[rng.time]),
                    &mut ev,
                    &mut w[..n],
                    Some(&mut e[..n]),
                );
                if self.failures.note(tracked).is_none() {
                    return (plain(S::ZERO), Track::Absorbed);
                }
                let emitted = Emitted {
                    l: S(e),
                    fire_units: Some(*units),
                };
                let track = match ev[0].event {
                    firemedium_abi::FM_EVENT_SCATTERED => Track::Scattered {
                        t: ev[0].t as f32,
                        weight: S(w),
                        g: *g as f32,
                    },
                    firemedium_abi::FM_EVENT_ABSORBED => Track::Absorbed,
                    _ => Track::Passed {
                        weight: S(w),
                        bent: None,
                    },
                };
                (emitted, track)
            }
            Medium::Plugin { .. } => {
                let (le, tr, bent) = self.medium_segment_exit(m, o, d, t_end, rng, true, true);
                let emitted = Emitted {
                    l: le,
                    fire_units: Some(1.0),
                };
                (emitted, Track::Passed { weight: tr, bent })
            }
            Medium::Homogeneous { sa, ss, g, .. } => {
                // Emission over the whole segment in closed form; in-scattering by sampling a distance from the
                // channel-mean extinction σ̄ with spectral weights T_c(s) σ_s,c / p(s).
                let (le, tr) = self.medium_segment(m, o, d, t_end, rng, true);
                if ss.is_black() {
                    return (
                        plain(le),
                        Track::Passed {
                            weight: tr,
                            bent: None,
                        },
                    );
                }
                let st = *sa + *ss;
                let sbar = st.0[..n].iter().sum::<f32>() / n as f32;
                let speed = d.length();
                let s_hit = -(1.0 - rng.next_f64() as f32).ln() / sbar;
                let s_end = t_end * speed;
                let mut w = S::ZERO;
                if s_hit < s_end {
                    for c in 0..n {
                        w.0[c] = (-(st.0[c] - sbar) * s_hit).exp() * ss.0[c] / sbar;
                    }
                    let t = s_hit / speed;
                    return (
                        plain(le),
                        Track::Scattered {
                            t,
                            weight: w,
                            g: *g as f32,
                        },
                    );
                }
                for c in 0..n {
                    w.0[c] = if s_end.is_finite() {
                        (-(st.0[c] - sbar) * s_end).exp()
                    } else {
                        0.0
                    };
                }
                (
                    plain(le),
                    Track::Passed {
                        weight: w,
                        bent: None,
                    },
                )
            }
            Medium::RgbGrid(grid) => self.host_track(&**grid, o, d, t_end, rng, None),
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
