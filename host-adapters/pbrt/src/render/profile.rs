//! Where a render's time and light go, by path vertex kind (`firemedium render --profile`): for every kind of
//! step a path takes — a traversal of the scene, a segment through a medium (the camera's first, or a later
//! one), a scattering vertex in a medium, a surface vertex, a light sample from either (a fire's light or the
//! others), the density a found emission's MIS weight asks of the fire light — how many and how long; and for
//! every kind of contribution a path adds — emission seen along the camera's segment or a later one, a light
//! sample from a medium or a surface vertex, a light a sampled direction finds — its share of the image's mean
//! and of the pixels' variance: each kind's variance over a pixel's paths, summed over the pixels plainly and
//! weighted as relMSE weighs them (over the pixel's squared mean, + 0.01). Kinds correlate within a path, so
//! the shares say where the variance is, not how it adds.
//!
//! Off unless asked: the integrator then reads no clock. On, each event costs two clock reads (tens of ns) and
//! each path one lock: a profiled render is a little slower than a plain one, its shares are what they measure.

use super::spectrum::S;
use std::time::Instant;

/// The kinds of step a path's time goes to (in [`STEPS`]'s order: a step's discriminant is its row).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Step {
    /// A traversal of the scene's shapes from a path vertex (the light samples' own are in theirs).
    Traverse,
    /// The camera ray's segment through a medium (emission added, tracked or marched).
    CameraSegment,
    /// A later segment through a medium.
    LaterSegment,
    /// The fire light's density of a direction a path found emission along (its MIS weight).
    EmissionMis,
    /// A scattering vertex in a medium: its light sample (in [`Step::MediumFireSample`] or
    /// [`Step::MediumLightSample`]) and the phase function's direction.
    MediumVertex,
    MediumFireSample,
    MediumLightSample,
    /// A surface vertex: its material, BSDF sample and evaluations, and the path's own bookkeeping — the path's
    /// time less every other step's (its light sample apart).
    SurfaceVertex,
    SurfaceFireSample,
    SurfaceLightSample,
    /// A fire-light sample's parts (from either vertex): the point it picks, the line's emission along the
    /// direction toward it (the walk through the shapes and the fire), that direction's density.
    FirePoint,
    FireLine,
    FireDensity,
}

const STEPS: [(Step, &str); 13] = [
    (Step::Traverse, "traversal of the shapes"),
    (Step::CameraSegment, "camera segment in a medium"),
    (Step::LaterSegment, "later segment in a medium"),
    (Step::EmissionMis, "found emission's MIS (fire light pdf)"),
    (Step::MediumVertex, "scattering vertex (phase, choice)"),
    (Step::MediumFireSample, "  its fire-light sample"),
    (Step::MediumLightSample, "  its other-light sample"),
    (
        Step::SurfaceVertex,
        "surface vertex (material, BSDF) and the rest",
    ),
    (Step::SurfaceFireSample, "  its fire-light sample"),
    (Step::SurfaceLightSample, "  its other-light sample"),
    (Step::FirePoint, "  a fire-light sample's point"),
    (Step::FireLine, "  a fire-light sample's line"),
    (Step::FireDensity, "  a fire-light sample's density"),
];

/// The kinds of contribution a path adds to its radiance (in [`GAINS`]'s order).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Gain {
    /// Emission along the camera ray's own segment.
    CameraEmission,
    /// Emission a later segment found after a surface vertex (its MIS weight against the fire light applied)...
    FoundEmission,
    /// ...and after a scattering vertex in a medium.
    ScatteredEmission,
    MediumFire,
    MediumLight,
    SurfaceFire,
    SurfaceLight,
    /// An area or infinite light a sampled direction (or the camera) found.
    FoundLight,
}

const GAINS: [(Gain, &str); 8] = [
    (Gain::CameraEmission, "emission on the camera segment"),
    (Gain::FoundEmission, "emission found from a surface vertex"),
    (
        Gain::ScatteredEmission,
        "emission found from a scattering vertex",
    ),
    (Gain::MediumFire, "fire-light sample at a scattering vertex"),
    (
        Gain::MediumLight,
        "other-light sample at a scattering vertex",
    ),
    (Gain::SurfaceFire, "fire-light sample at a surface vertex"),
    (Gain::SurfaceLight, "other-light sample at a surface vertex"),
    (Gain::FoundLight, "area / infinite light found"),
];

/// One path's tally, flushed into the render's [`Profile`] when the path ends.
#[derive(Debug, Clone, Default)]
pub(super) struct Tally {
    /// The path's pixel (any key unique to it).
    pixel: u64,
    ns: [u64; STEPS.len()],
    count: [u64; STEPS.len()],
    gain: [f64; GAINS.len()],
    /// The path's radiance (its mean over the bins) when a contribution was last credited.
    level: f64,
}

fn step_index(s: Step) -> usize {
    s as usize
}

fn gain_index(g: Gain) -> usize {
    g as usize
}

/// The clock's reading when the path is profiled (`tally` kept), else none: an unprofiled path reads no clock.
pub(super) fn clock(tally: &Option<Tally>) -> Option<Instant> {
    tally.as_ref().map(|_| Instant::now())
}

/// Counts `step`, begun at `t0`, in a profiled path.
pub(super) fn took(tally: &mut Option<Tally>, step: Step, t0: Option<Instant>) {
    if let (Some(t), Some(t0)) = (tally.as_mut(), t0) {
        t.step(step, t0);
    }
}

/// [`took`], and the clock's reading for the step that follows.
pub(super) fn lap(tally: &mut Option<Tally>, step: Step, t0: Option<Instant>) -> Option<Instant> {
    took(tally, step, t0);
    clock(tally)
}

/// Credits what the path's radiance `l` (its first `n` bins) gained since the last credit to `gain`, in a
/// profiled path (every addition to the radiance is credited as it is made).
pub(super) fn credit(tally: &mut Option<Tally>, gain: Gain, l: &S, n: usize) {
    if let Some(t) = tally.as_mut() {
        let level = l.0[..n].iter().map(|&v| f64::from(v)).sum::<f64>() / n.max(1) as f64;
        t.gain(gain, level - t.level);
        t.level = level;
    }
}

impl Tally {
    /// An empty tally of a path in `pixel`.
    pub(super) fn new(pixel: u64) -> Tally {
        Tally {
            pixel,
            ..Tally::default()
        }
    }

    /// Counts one `step` begun at `start`.
    pub(super) fn step(&mut self, step: Step, start: Instant) {
        let i = step_index(step);
        self.ns[i] += start.elapsed().as_nanos() as u64;
        self.count[i] += 1;
    }

    /// Counts one `step` whose time is taken apart ([`Tally::finish`]).
    pub(super) fn count(&mut self, step: Step) {
        self.count[step_index(step)] += 1;
    }

    /// Adds `y` (a contribution's mean over the bins) to the path's `gain`.
    pub(super) fn gain(&mut self, gain: Gain, y: f64) {
        self.gain[gain_index(gain)] += y;
    }

    /// Ends the path begun at `start`: what its steps did not take goes to [`Step::SurfaceVertex`].
    pub(super) fn finish(&mut self, start: Instant) {
        let path = start.elapsed().as_nanos() as u64;
        let taken: u64 = STEPS
            .iter()
            .zip(&self.ns)
            .filter(|((k, name), _)| !name.starts_with(' ') && *k != Step::SurfaceVertex)
            .map(|(_, ns)| ns)
            .sum();
        self.ns[step_index(Step::SurfaceVertex)] = path.saturating_sub(taken);
    }
}

/// A profiled render's sums over its paths.
#[derive(Debug, Default)]
pub struct Profile {
    sums: std::sync::Mutex<Sums>,
}

#[derive(Debug, Clone, Default)]
struct Sums {
    paths: u64,
    ns: [u64; STEPS.len()],
    count: [u64; STEPS.len()],
    y: [f64; GAINS.len()],
    pixels: std::collections::HashMap<u64, Pixel>,
}

/// A pixel's paths: their count, each kind's sum and sum of squares, the sum of the paths' totals.
#[derive(Debug, Clone, Copy, Default)]
struct Pixel {
    n: u64,
    y: [f64; GAINS.len()],
    y2: [f64; GAINS.len()],
    total: f64,
}

/// relMSE's floor under a pixel's squared mean.
const REL_FLOOR: f64 = 0.01;

impl Profile {
    pub(super) fn add(&self, t: &Tally) {
        let Ok(mut s) = self.sums.lock() else { return };
        s.paths += 1;
        for i in 0..STEPS.len() {
            s.ns[i] += t.ns[i];
            s.count[i] += t.count[i];
        }
        let px = s.pixels.entry(t.pixel).or_default();
        px.n += 1;
        px.total += t.gain.iter().sum::<f64>();
        for i in 0..GAINS.len() {
            px.y[i] += t.gain[i];
            px.y2[i] += t.gain[i] * t.gain[i];
        }
        for i in 0..GAINS.len() {
            s.y[i] += t.gain[i];
        }
    }

    /// Each kind's variance summed over the pixels with two paths or more: plainly, and weighted as relMSE.
    fn variances(s: &Sums) -> ([f64; GAINS.len()], [f64; GAINS.len()]) {
        let (mut plain, mut rel) = ([0.0; GAINS.len()], [0.0; GAINS.len()]);
        for px in s.pixels.values().filter(|p| p.n >= 2) {
            let n = px.n as f64;
            let mean = px.total / n;
            for i in 0..GAINS.len() {
                let var = ((px.y2[i] - px.y[i] * px.y[i] / n) / (n - 1.0)).max(0.0);
                plain[i] += var;
                rel[i] += var / (mean * mean + REL_FLOOR);
            }
        }
        (plain, rel)
    }

    /// The table the render prints: per step kind its count per path, its time per path and share of the
    /// steps' time; per contribution kind its share of the mean and of the second moment.
    pub fn report(&self) -> String {
        let s = match self.sums.lock() {
            Ok(s) => s.clone(),
            Err(p) => p.into_inner().clone(),
        };
        let paths = s.paths.max(1) as f64;
        // The top-level steps (the light samples are inside their vertices).
        let total: u64 = STEPS
            .iter()
            .zip(&s.ns)
            .filter(|((_, name), _)| !name.starts_with(' '))
            .map(|(_, ns)| ns)
            .sum();
        let mut out = format!(
            "profile over {} paths (camera samples and their twins), {:.3} s of steps per thread-path sum:\n",
            s.paths,
            total as f64 * 1e-9
        );
        out += &format!(
            "  {:<46} {:>10} {:>12} {:>8}\n",
            "step", "per path", "µs per path", "share"
        );
        for (i, (_, name)) in STEPS.iter().enumerate() {
            out += &format!(
                "  {:<46} {:>10.3} {:>12.3} {:>7.1}%\n",
                name,
                s.count[i] as f64 / paths,
                s.ns[i] as f64 * 1e-3 / paths,
                100.0 * s.ns[i] as f64 / total.max(1) as f64
            );
        }
        let ysum = s.y.iter().sum::<f64>();
        let (plain, rel) = Self::variances(&s);
        let share = |v: f64, of: &[f64]| {
            let sum: f64 = of.iter().sum();
            100.0 * v / if sum > 0.0 { sum } else { 1.0 }
        };
        out += &format!(
            "  {:<46} {:>10} {:>12} {:>8}\n",
            "contribution", "of mean", "of variance", "relMSE"
        );
        for (i, (_, name)) in GAINS.iter().enumerate() {
            out += &format!(
                "  {:<46} {:>9.1}% {:>11.1}% {:>7.1}%\n",
                name,
                100.0 * s.y[i] / if ysum != 0.0 { ysum } else { 1.0 },
                share(plain[i], &plain),
                share(rel[i], &rel)
            );
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tables_rows_follow_the_kinds_order() {
        for (i, (k, _)) in STEPS.iter().enumerate() {
            assert_eq!(*k as usize, i, "{k:?}");
        }
        for (i, (k, _)) in GAINS.iter().enumerate() {
            assert_eq!(*k as usize, i, "{k:?}");
        }
    }

    #[test]
    fn credits_follow_the_radiance() {
        let mut t = Some(Tally::new(0));
        let mut l = S::ZERO;
        l.0[..2].copy_from_slice(&[1.0, 3.0]);
        credit(&mut t, Gain::CameraEmission, &l, 2);
        l.0[0] += 4.0;
        credit(&mut t, Gain::SurfaceFire, &l, 2);
        let t = t.unwrap();
        assert_eq!(t.gain[gain_index(Gain::CameraEmission)], 2.0);
        assert_eq!(t.gain[gain_index(Gain::SurfaceFire)], 2.0);
    }

    #[test]
    fn a_path_s_tally_adds_its_steps_and_each_kind_s_variance_per_pixel() {
        let p = Profile::default();
        let mut t = Tally::default();
        t.step(Step::Traverse, Instant::now());
        t.step(Step::Traverse, Instant::now());
        // Pixel 1: the surface's fire sample gives 1 + 2 = 3 on one path (a path's sum, not each addition), 1 on
        // the other (variance 2); the found light 1 on both (variance 0).
        t.gain(Gain::SurfaceFire, 1.0);
        t.gain(Gain::SurfaceFire, 2.0);
        t.gain(Gain::FoundLight, 1.0);
        t.pixel = 1;
        p.add(&t);
        let mut u = Tally {
            pixel: 1,
            ..Tally::default()
        };
        u.gain(Gain::SurfaceFire, 1.0);
        u.gain(Gain::FoundLight, 1.0);
        p.add(&u);
        // Pixel 2: one path only — no variance counted; a mean.
        let mut v = Tally {
            pixel: 2,
            ..Tally::default()
        };
        v.gain(Gain::CameraEmission, 2.0);
        p.add(&v);
        let s = p.sums.lock().unwrap().clone();
        assert_eq!(s.paths, 3);
        assert_eq!(s.count[step_index(Step::Traverse)], 2);
        let (plain, rel) = Profile::variances(&s);
        assert_eq!(plain[gain_index(Gain::SurfaceFire)], 2.0);
        assert_eq!(plain[gain_index(Gain::FoundLight)], 0.0);
        // Over the pixel's mean squared ((4 + 2) / 2 = 3) and the floor.
        assert!((rel[gain_index(Gain::SurfaceFire)] - 2.0 / 9.01).abs() < 1e-12);
        let r = p.report();
        let row = |name: &str| -> Vec<String> {
            let line = r
                .lines()
                .find(|l| l.trim_start().starts_with(name))
                .unwrap();
            line[2 + 46..]
                .split_whitespace()
                .map(String::from)
                .collect()
        };
        // The mean's shares: 4 of 8, 2 of 8, 2 of 8; the variance all the fire sample's.
        assert_eq!(
            row("fire-light sample at a surface"),
            ["50.0%", "100.0%", "100.0%"],
            "{r}"
        );
        assert_eq!(
            row("area / infinite light found"),
            ["25.0%", "0.0%", "0.0%"],
            "{r}"
        );
        assert_eq!(
            row("emission on the camera"),
            ["25.0%", "0.0%", "0.0%"],
            "{r}"
        );
    }
}
