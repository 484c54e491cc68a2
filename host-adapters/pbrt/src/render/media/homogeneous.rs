//! pbrt-v4's `homogeneous` medium: constant coefficients, its emission and transmittance in closed form, its
//! scattering distance sampled from the channels' mean extinction.

use super::{Emitted, MediumKind, Track};
use crate::render::paths::Integrator;
use crate::render::pixel::Samples;
use crate::render::scene::Homogeneous;
use crate::render::spectrum::S;
use glam::Vec3A;

impl MediumKind for Homogeneous {
    fn segment(
        &self,
        it: &Integrator<'_>,
        _: Vec3A,
        d: Vec3A,
        t_end: f32,
        _: &mut Samples,
        emission: bool,
        _: bool,
    ) -> (S, S, Option<(Vec3A, Vec3A)>) {
        let n = it.scene.bins.n();
        let len = if t_end.is_finite() {
            t_end * d.length()
        } else {
            f32::INFINITY
        };
        let (sa, le) = (self.sa, self.le);
        let st = sa + self.ss;
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

    fn track(
        &self,
        it: &Integrator<'_>,
        o: Vec3A,
        d: Vec3A,
        t_end: f32,
        rng: &mut Samples,
        _: bool,
    ) -> (Emitted, Track) {
        let n = it.scene.bins.n();
        let plain = |l: S| Emitted {
            l,
            fire_units: None,
        };
        // Emission over the whole segment in closed form; in-scattering by sampling a distance from the
        // channel-mean extinction σ̄ with spectral weights T_c(s) σ_s,c / p(s).
        let (le, tr, _) = self.segment(it, o, d, t_end, rng, true, false);
        let ss = self.ss;
        if ss.is_black() {
            let track = Track::Passed {
                weight: tr,
                bent: None,
            };
            return (plain(le), track);
        }
        let st = self.sa + ss;
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
            let track = Track::Scattered {
                t,
                weight: w,
                g: self.g as f32,
            };
            return (plain(le), track);
        }
        for c in 0..n {
            w.0[c] = if s_end.is_finite() {
                (-(st.0[c] - sbar) * s_end).exp()
            } else {
                0.0
            };
        }
        let track = Track::Passed {
            weight: w,
            bent: None,
        };
        (plain(le), track)
    }
}
