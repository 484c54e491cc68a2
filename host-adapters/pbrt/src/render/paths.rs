//! What every part of the path tracer shares, below the integrator, the media and the lights: the integrator's
//! state ([`Integrator`]: the scene, the plugin calls that failed), where next-event estimation leaves from
//! ([`Spot`]). `media`, `lights` and `integrator` each add their own methods to [`Integrator`]; the arrows run
//! integrator → lights → media → here, never back.

use super::pixel::Samples;
use super::scene::Scene;
use super::spectrum::S;
use glam::Vec3A;

/// Where next-event estimation leaves from: a surface point (the side a direction leaves by picks the offset
/// and the medium) or a point inside a medium.
#[derive(Debug, Clone, Copy)]
pub(super) enum Spot {
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
    pub(super) fn p(&self) -> Vec3A {
        match self {
            Spot::Surface { p, .. } | Spot::Medium { p, .. } => *p,
        }
    }
    /// The origin and medium of a ray leaving along `w`.
    pub(super) fn leave(&self, w: Vec3A) -> (Vec3A, Option<usize>) {
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
    /// Where the paths' time and light go, when the render is profiled ([`super::profile`]).
    pub profile: Option<super::profile::Profile>,
}

impl Integrator<'_> {
    pub(super) fn rng2(rng: &mut Samples) -> [f32; 2] {
        [rng.next_f64() as f32, rng.next_f64() as f32]
    }
}
