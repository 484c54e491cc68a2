//! A medium living in the plugin — a fire, or one of pbrt-v4's grid media the plugin renders — answered through
//! the ABI's whole-ray queries (`integrate`, `transmittance`, `sample_scatter`), or, tracked by the renderer
//! (`--tracking host`), through its medium level ([`crate::render::tracker`]).

use super::{plugin_ray, Emitted, MediumKind, Track};
use crate::render::paths::Integrator;
use crate::render::pixel::Samples;
use crate::render::scene::Plugin;
use crate::render::spectrum::{MAX_CHANNELS, S};
use crate::render::tracker::PluginMedium;
use glam::{DVec3, Vec3A};

impl Plugin {
    /// The medium as the host tracks it (`--tracking host`), if it does.
    fn tracked(&self, bins: usize) -> Option<PluginMedium<'_>> {
        let grid = self.host.as_ref()?;
        Some(PluginMedium {
            vol: &self.vol,
            grid,
            to_medium: &self.to_medium,
            units: self.units,
            bins,
            g: self.g,
        })
    }
}

impl MediumKind for Plugin {
    fn segment(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        emission: bool,
        want_exit: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>) {
        let n = it.scene.bins.n();
        if let Some(pm) = self.tracked(n) {
            return it.host_segment(&pm, o, d, t_end, rng, emission);
        }
        let ray = plugin_ray(&self.to_medium, o, d, t_end, rng.next_u64());
        let time = [rng.time];
        let (mut l, mut t) = ([0f32; MAX_CHANNELS], [0f32; MAX_CHANNELS]);
        let mut exit = [firemedium_loader::Exit::default()];
        let done = if emission {
            self.vol.integrate_at(
                std::slice::from_ref(&ray),
                Some(&time),
                &mut l[..n],
                Some(&mut t[..n]),
                want_exit.then_some(&mut exit[..]),
            )
        } else {
            self.vol
                .transmittance_at(std::slice::from_ref(&ray), Some(&time), &mut t[..n])
        };
        if it.failures.note(done).is_none() {
            return (S::ZERO, S::ZERO, None);
        }
        let bent = (emission && want_exit).then(|| {
            let de = DVec3::from(exit[0].direction);
            let dn = DVec3::from(ray.direction).normalize_or_zero();
            (de.is_finite() && de.dot(dn) < 1.0 - 1e-12).then(|| {
                let p = self.to_world.transform_point3(DVec3::from(exit[0].point));
                let w = self.to_world.transform_vector3(de).normalize_or_zero();
                (Vec3A::from(p.as_vec3()), Vec3A::from(w.as_vec3()))
            })
        });
        (S(l) * self.units, S(t), bent.flatten())
    }

    fn track(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        seen: bool,
    ) -> (Emitted, Track) {
        let n = it.scene.bins.n();
        if let Some(pm) = self.tracked(n) {
            return it.host_track(&pm, o, d, t_end, rng, Some(1.0));
        }
        if !self.scatters {
            let (le, tr, bent) = self.segment(it, o, d, t_end, rng, true, true);
            let emitted = Emitted {
                l: le,
                fire_units: Some(1.0),
            };
            return (emitted, Track::Passed { weight: tr, bent });
        }
        let absorbed = || {
            let l = S::ZERO;
            (
                Emitted {
                    l,
                    fire_units: None,
                },
                Track::Absorbed,
            )
        };
        let ray = plugin_ray(&self.to_medium, o, d, t_end, rng.next_u64());
        let mut ev = [firemedium_loader::Scatter::default()];
        let (mut w, mut e) = ([0f32; MAX_CHANNELS], [0f32; MAX_CHANNELS]);
        // What the camera sees of the fire marched, the whole segment's emission at once, and tracking only
        // choosing where the path scatters. (Its transmittance is asked for too, though not wanted: without it the
        // smoky look measured 2.76 / 2.66 s against 2.50 / 2.46 s, alternating.) (Emission at the tentative collisions elsewhere: marching it along every segment cost 7× the
        // time for no less error on a scattering fire's surfaces — docs/results/log.md.)
        let march = seen && self.camera_march;
        if march {
            let mut t = [0f32; MAX_CHANNELS];
            let marched = self.vol.integrate_at(
                std::slice::from_ref(&ray),
                Some(&[rng.time]),
                &mut e[..n],
                Some(&mut t[..n]),
                None,
            );
            if it.failures.note(marched).is_none() {
                return absorbed();
            }
        }
        let tracked = self.vol.sample_scatter_at(
            std::slice::from_ref(&ray),
            Some(&[rng.time]),
            &mut ev,
            &mut w[..n],
            (!march).then_some(&mut e[..n]),
        );
        if it.failures.note(tracked).is_none() {
            return absorbed();
        }
        let emitted = Emitted {
            l: S(e),
            fire_units: Some(self.units),
        };
        let track = match ev[0].event {
            firemedium_abi::FM_EVENT_SCATTERED => Track::Scattered {
                t: ev[0].t as f32,
                weight: S(w),
                g: self.g as f32,
            },
            firemedium_abi::FM_EVENT_ABSORBED => Track::Absorbed,
            _ => Track::Passed {
                weight: S(w),
                bent: None,
            },
        };
        (emitted, track)
    }
}
