//! Integrators of the emission–absorption RTE along a ray (Pegoraro & Parker eq. 1–3), all reporting the same
//! quantities — emitted radiance L_c and transmittance T_c per channel — so their error and cost compare.
//!
//! - [`Integrator::March`]: fixed steps of the medium's step length with a jittered start; each step uses the
//!   exact solution for constant coefficients (eq. 3): L += T · (1 − e^{−σ_t Δ}) · j / σ_t with
//!   `−expm1(−σ_t Δ)`, which stays finite and accurate as σ_t → 0 (→ j Δ) and as σ_t Δ → ∞ (→ j / σ_t);
//!   T ·= e^{−σ_t Δ}; stops when every channel's T is below the cutoff (the bias is below cutoff · L_rest).
//! - [`Integrator::Ratio`]: ratio tracking over the majorant segments: tentative collisions at rate σ̄; at each,
//!   L += T · j / σ̄ and T ·= 1 − σ_t / σ̄. Unbiased; Russian roulette below T = 0.01.
//! - [`Integrator::Delta`]: delta tracking with spectral weights: at each tentative collision absorb, scatter or
//!   pass with probabilities from the channel-mean coefficients; absorption scores j / (σ̄ P_a) and stops;
//!   T is the track-length estimate (weight if the ray leaves, else 0). Unbiased.
//!
//! Scattering (σ_s) counts as extinction here; in-scattering is the host's job, through
//! [`sample_scatter`], which returns the first real scattering event with its weight and the emission collected
//! before it. Distances are |d| · Δt: ray parameters may use any direction length.

use crate::rng::Rng;
use glam::DVec3;

/// Which integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Integrator {
    /// Fixed-step march (eq. 3).
    March,
    /// Ratio tracking.
    Ratio,
    /// Delta tracking.
    Delta,
}

impl Integrator {
    /// From the parameter value.
    pub fn from_name(s: &str) -> Option<Integrator> {
        Some(match s {
            "march" => Integrator::March,
            "ratio" => Integrator::Ratio,
            "delta" => Integrator::Delta,
            _ => return None,
        })
    }
}

/// A ray segment in medium space: points o + t·d for t in [t0, t1]; `seed` drives its random numbers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// Origin.
    pub o: DVec3,
    /// Direction (any length; distances are |d|·Δt).
    pub d: DVec3,
    /// Start parameter.
    pub t0: f64,
    /// End parameter.
    pub t1: f64,
    /// Seed of the ray's random numbers.
    pub seed: u64,
    /// The first of them, when the host gives it (its sampler's stratified number): the march's offset along
    /// the ray, tracking's first free-flight distance.
    pub first: Option<f64>,
}

impl Ray {
    /// The ray's random numbers: `first`, if given, then the stream of `seed`.
    pub(crate) fn rng(&self) -> crate::rng::Rng {
        crate::rng::Rng::starting(self.seed, self.first)
    }
}

/// What integrators need from a medium.
pub(crate) trait Medium {
    /// The part of [t0, t1] inside the medium's support.
    fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)>;
    /// March step length, metres.
    fn step(&self) -> f64;
    /// σ_a, σ_s (m⁻¹) and the emission coefficient j = σ_a L_e per channel at `p`.
    fn eval(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]);
    /// Calls `f(ta, tb, σ̄)` for consecutive pieces of [t0, t1] with a scalar bound σ̄ ≥ σ_t of every channel;
    /// `f` returns false to stop.
    fn majorants(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    );
    /// March transmittance cutoff.
    fn cutoff(&self) -> f64;
    /// The largest optical depth one march step may take: a step whose midpoint's σ_t·Δ exceeds it is split
    /// into sub-steps of at most this depth (see [`split_step`]). Default: never split.
    fn step_tau(&self) -> f64 {
        f64::INFINITY
    }
    /// Calls `f(ta, tb)` for pieces of [t0, t1], in order, where the medium is known to be empty — no
    /// absorption, scattering or emission anywhere (the march skips its steps there). Default: none known.
    fn empty_spans(&self, _o: DVec3, _d: DVec3, _t0: f64, _t1: f64, _f: &mut dyn FnMut(f64, f64)) {}
    /// Told when a ray's tracking stopped at [`MAX_COLLISIONS`] (so the medium can count and report it).
    fn collision_cap_hit(&self) {}
}

/// Per-call scratch: coefficient buffers sized to the channel count.
#[derive(Debug, Clone, Default)]
pub(crate) struct Scratch {
    sa: Vec<f64>,
    ss: Vec<f64>,
    j: Vec<f64>,
    /// Empty stretches of the current ray (march).
    empty: Vec<(f64, f64)>,
}

impl Scratch {
    pub fn new(c: usize) -> Scratch {
        Scratch {
            sa: vec![0.0; c],
            ss: vec![0.0; c],
            j: vec![0.0; c],
            empty: Vec::new(),
        }
    }

    /// One step of the f64 march ([`march_step`]) of length `h` at `p` of `m`, its coefficients in these buffers:
    /// the step's largest transmittance left.
    #[inline(always)]
    pub(crate) fn march_at(
        &mut self,
        m: &impl Medium,
        p: DVec3,
        h: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        m.eval(p, &mut self.sa, &mut self.ss, &mut self.j);
        march_step(&self.sa, &self.ss, &self.j, h, l, t)
    }

    /// `f` with this thread's scratch, as [`Scratch::new`] would make it for `c` channels (a fresh one when the
    /// thread's is in use): a query no longer allocates and frees its buffers (a tracked segment's three, which
    /// were 4 % of a scattering room's render in the allocator).
    pub(crate) fn with<R>(c: usize, f: impl FnOnce(&mut Scratch) -> R) -> R {
        thread_local! {
            static HELD: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
        }
        HELD.with(|held| match held.try_borrow_mut() {
            Ok(mut held) => {
                let sc = &mut *held;
                for v in [&mut sc.sa, &mut sc.ss, &mut sc.j] {
                    v.clear();
                    v.resize(c, 0.0);
                }
                sc.empty.clear();
                f(sc)
            }
            Err(_) => f(&mut Scratch::new(c)),
        })
    }
}

/// One march step of length `delta` through the coefficients in `sc` (eq. 3, exact for constant coefficients):
/// adds the step's emission to `l`, attenuates `t`; returns the largest transmittance left.
pub(crate) fn march_step(
    sa: &[f64],
    ss: &[f64],
    j: &[f64],
    delta: f64,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    let mut tmax = 0.0f64;
    for c in 0..t.len() {
        let st = sa[c] + ss[c];
        let tau = st * delta;
        // e^{−τ} and (1 − e^{−τ}) / σ_t, finite for σ_t → 0 and σ_t → ∞, with one exp at most: below τ = 0.01
        // (most steps of a fire) g = (1 − e^{−τ})/τ by its Taylor series to τ⁵, whose remainder τ⁶/5040 <
        // 2e-16 is below rounding; above, 1 − e^{−τ} loses at most 1e-14 relative to cancellation.
        let (e, fac) = if tau < 0.01 {
            let g = 1.0
                - tau
                    * (0.5
                        - tau
                            * (1.0 / 6.0 - tau * (1.0 / 24.0 - tau * (1.0 / 120.0 - tau / 720.0))));
            (1.0 - tau * g, delta * g)
        } else {
            let e = (-tau).exp();
            (e, (1.0 - e) / st)
        };
        l[c] += t[c] * j[c] * fac;
        t[c] *= e;
        tmax = tmax.max(t[c]);
    }
    tmax
}

/// The most sub-steps one march step is split into (a bound on the work of one step, whatever its optical depth:
/// past a few sub-steps of a thick step the transmittance is below any cutoff and the march ends).
pub(crate) const MAX_SPLIT: f64 = 4096.0;

/// How many sub-steps a step of optical depth `tau` (at its midpoint) takes under the limit `limit`.
#[inline]
pub(crate) fn split_count(tau: f64, limit: f64) -> usize {
    (tau / limit).ceil().clamp(1.0, MAX_SPLIT) as usize
}

/// A thick march step split in `n` equal sub-steps, each evaluated at its own midpoint and integrated as eq. 3
/// ([`march_step`]): the step of length `delta` around `mid` (arc length; `dir` the unit direction). A fixed step
/// through a thick, varying medium sees the coefficients at its midpoint only, where the light that leaves it
/// comes from its first optical depth (a one-voxel pbrt-v4 grid with σ_a = 1000 per voxel is 80× too bright
/// at half-voxel steps); its sub-steps of depth ≤ the medium's `step_tau` follow the variation. Returns the
/// largest transmittance left (stopping early below the cutoff).
#[cold]
#[allow(clippy::too_many_arguments)]
pub(crate) fn split_step(
    m: &dyn Medium,
    mid: DVec3,
    dir: DVec3,
    delta: f64,
    n: usize,
    (sa, ss, j): (&mut [f64], &mut [f64], &mut [f64]),
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    let h = delta / n as f64;
    let cutoff = m.cutoff();
    let mut tmax = 0.0;
    for i in 0..n {
        let p = mid + dir * (((i as f64 + 0.5) / n as f64 - 0.5) * delta);
        m.eval(p, sa, ss, j);
        tmax = march_step(sa, ss, j, h, l, t);
        if tmax < cutoff {
            break;
        }
    }
    tmax
}

/// A ray clipped to a medium: parameters [a, b] inside it, and |d| (arc length per unit of parameter).
pub(crate) struct Span<'a> {
    m: &'a dyn Medium,
    ray: &'a Ray,
    a: f64,
    b: f64,
    speed: f64,
}

impl<'a> Span<'a> {
    /// The part of `ray` inside `m`; `None` when it misses, or its direction is zero or not finite.
    pub(crate) fn new(m: &'a dyn Medium, ray: &'a Ray) -> Option<Span<'a>> {
        let (a, b) = m.clip(ray.o, ray.d, ray.t0, ray.t1)?;
        let speed = ray.d.length();
        (speed > 0.0 && speed.is_finite()).then_some(Span {
            m,
            ray,
            a,
            b,
            speed,
        })
    }
    /// The ray's parameter where it enters the medium.
    #[inline(always)]
    pub(crate) fn a(&self) -> f64 {
        self.a
    }
    /// The ray's parameter where it leaves the medium.
    #[inline(always)]
    pub(crate) fn b(&self) -> f64 {
        self.b
    }
    /// Arc length per unit of the ray's parameter (|d|).
    #[inline(always)]
    pub(crate) fn speed(&self) -> f64 {
        self.speed
    }
}

/// The most steps one ray may take (a guard against absurd step sizes): ~1.7e7 at up to 32 channels.
pub(crate) const MAX_STEPS: f64 = (1u64 << 24) as f64;

/// The most steps one ray of `channels` channels may take: [`MAX_STEPS`], fewer in proportion past 32 channels,
/// so that one call's work stays bounded (a ray at 4 096 bins and the smallest step through a 256³ grid was
/// 10¹⁰ channel evaluations); the steps then lengthen, never the work.
pub(crate) fn max_steps(channels: usize) -> f64 {
    MAX_STEPS * 32.0 / channels.max(32) as f64
}

/// The most tentative collisions one ray's tracking may take: 2²⁰ ≈ 10⁶, tens of milliseconds. A ray that
/// reaches it (a majorant far above the data, or an optical depth of 10⁶ along the ray) stops there as if
/// absorbed — a bias towards dark, so the medium counts it ([`Medium::collision_cap_hit`]) and the host reports
/// it. The march needs no cap: its steps are bounded by [`MAX_STEPS`].
pub(crate) const MAX_COLLISIONS: u64 = 1 << 20;

/// The most channel evaluations one ray's tracking may take: [`MAX_COLLISIONS`] at 32 channels. With more
/// channels (up to 4 096 bins) the collision cap shrinks in proportion, so one call's work stays bounded (a ray
/// at 4 096 bins through one dense voxel took 44 s).
pub(crate) const MAX_TRACKING_WORK: u64 = MAX_COLLISIONS * 32;

/// Emitted radiance `l` and transmittance `t` of the ray; returns the parameter where the ray left the medium
/// (or t1).
pub(crate) fn integrate(
    m: &dyn Medium,
    ray: &Ray,
    how: Integrator,
    sc: &mut Scratch,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    l.iter_mut().for_each(|v| *v = 0.0);
    t.iter_mut().for_each(|v| *v = 1.0);
    let Some(span) = Span::new(m, ray) else {
        return ray.t1;
    };
    let mut rng = ray.rng();
    match how {
        Integrator::March => {
            let cutoff = m.cutoff();
            let limit = m.step_tau();
            let dir = ray.d / span.speed;
            let Scratch { sa, ss, j, empty } = sc;
            march_steps(&span, &mut rng, empty, sa.len(), |p, delta| {
                m.eval(p, sa, ss, j);
                let tau = sa
                    .iter()
                    .zip(ss.iter())
                    .fold(0.0f64, |x, (a, s)| x.max((a + s) * delta));
                if tau > limit {
                    split_step(m, p, dir, delta, split_count(tau, limit), (sa, ss, j), l, t)
                        >= cutoff
                } else {
                    march_step(sa, ss, j, delta, l, t) >= cutoff
                }
            });
        }
        Integrator::Ratio => ratio(&span, &mut rng, sc, l, t),
        Integrator::Delta => {
            delta(&span, &mut rng, sc, l, t, false);
        }
    };
    span.b
}

/// Transmittance only (shadow rays): march's e^{−Σσ_tΔ}, or a ratio-tracking estimate for the tracking
/// integrators.
pub(crate) fn transmittance(
    m: &dyn Medium,
    ray: &Ray,
    how: Integrator,
    sc: &mut Scratch,
    t: &mut [f64],
) {
    let mut l = vec![0.0; t.len()];
    let how = if how == Integrator::Delta {
        Integrator::Ratio
    } else {
        how
    };
    integrate(m, ray, how, sc, &mut l, t);
}

/// The march's steps along [a, b] (arc length `m.step()`, the first one a random fraction of it): calls
/// `f(midpoint, length)` for each step until it returns false, skipping the steps whose midpoint lies in one of
/// the medium's empty stretches (collected in `empty`).
#[inline(always)]
pub(crate) fn march_steps(
    span: &Span,
    rng: &mut Rng,
    empty: &mut Vec<(f64, f64)>,
    channels: usize,
    mut f: impl FnMut(DVec3, f64) -> bool,
) {
    let &Span {
        m,
        ray,
        a,
        b,
        speed,
    } = span;
    let len = (b - a) * speed;
    let mut ds = m.step();
    let most = max_steps(channels);
    if !(ds > 0.0) || len / ds > most {
        ds = len / most;
    }
    // Empty stretches (arc length from a): a step whose midpoint falls in one adds nothing (σ = j = 0 there, so
    // L += 0 and T *= e⁰ = 1 exactly), so it is skipped without evaluating the medium — bit for bit the same.
    empty.clear();
    m.empty_spans(ray.o, ray.d, a, b, &mut |ta, tb| {
        empty.push(((ta - a) * speed, (tb - a) * speed))
    });
    let mut e = 0;
    let mut s = 0.0;
    let mut next = rng.next_f64() * ds;
    if next <= 0.0 {
        next = ds;
    }
    while s < len {
        let end = next.min(len);
        let delta = end - s;
        let mid = 0.5 * (s + end);
        while e < empty.len() && empty[e].1 <= mid {
            e += 1;
        }
        if e < empty.len() && empty[e].0 <= mid {
            s = end;
            next += ds;
            continue;
        }
        let p = ray.o + ray.d * (a + mid / speed);
        if !f(p, delta) {
            break;
        }
        s = end;
        next += ds;
    }
}

/// The tentative collisions of tracking along [a, b]: in every majorant piece with σ̄ > 0, exponential free
/// flights at rate σ̄; at each, the medium's coefficients are put in `sc` and `at(t, σ̄, sc, rng)` says whether
/// to go on. Returns true when the ray stopped at [`MAX_COLLISIONS`] (the medium was told).
fn collisions(
    span: &Span,
    rng: &mut Rng,
    sc: &mut Scratch,
    at: &mut dyn FnMut(f64, f64, &Scratch, &mut Rng) -> bool,
) -> bool {
    let &Span {
        m,
        ray,
        a,
        b,
        speed,
    } = span;
    let mut count = 0u64;
    let mut capped = false;
    let cap = (MAX_TRACKING_WORK / sc.sa.len().max(1) as u64).clamp(1 << 10, MAX_COLLISIONS);
    m.majorants(ray.o, ray.d, a, b, &mut |ta, tb, smaj| {
        if !(smaj > 0.0) {
            return true;
        }
        let mut tt = ta;
        loop {
            tt += -(1.0 - rng.next_f64()).ln() / (smaj * speed);
            if !(tt < tb) {
                return true;
            }
            count += 1;
            if count > cap {
                capped = true;
                return false;
            }
            m.eval(ray.o + ray.d * tt, &mut sc.sa, &mut sc.ss, &mut sc.j);
            if !at(tt, smaj, sc, rng) {
                return false;
            }
        }
    });
    if capped {
        m.collision_cap_hit();
    }
    capped
}

fn ratio(span: &Span, rng: &mut Rng, sc: &mut Scratch, l: &mut [f64], t: &mut [f64]) {
    let capped = collisions(span, rng, sc, &mut |_, smaj, sc, rng| {
        let mut tmax = 0.0f64;
        for c in 0..t.len() {
            l[c] += t[c] * sc.j[c] / smaj;
            t[c] *= (1.0 - (sc.sa[c] + sc.ss[c]) / smaj).max(0.0);
            tmax = tmax.max(t[c]);
        }
        if tmax < 0.01 {
            // Russian roulette: survive with probability 1/2, doubled weight.
            if rng.next_f64() < 0.5 {
                t.iter_mut().for_each(|v| *v *= 2.0);
            } else {
                t.iter_mut().for_each(|v| *v = 0.0);
                return false;
            }
        }
        true
    });
    if capped {
        t.iter_mut().for_each(|v| *v = 0.0);
    }
}

/// The outcome of [`sample_scatter`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Event {
    /// The ray left [t0, t1] (or the medium); the weights are its transmittance estimate.
    Escaped,
    /// A real scattering event at parameter t; the weights multiply the in-scattered radiance there.
    Scattered(f64),
    /// Absorbed: nothing continues.
    Absorbed,
}

/// Delta tracking; with `scatter_mode`, returns at the first scattering event (for [`sample_scatter`]).
fn delta(
    span: &Span,
    rng: &mut Rng,
    sc: &mut Scratch,
    l: &mut [f64],
    w: &mut [f64],
    scatter_mode: bool,
) -> Event {
    let n = w.len() as f64;
    let mut event = Event::Escaped;
    let capped = collisions(span, rng, sc, &mut |tt, smaj, sc, rng| {
        let pa = sc.sa.iter().sum::<f64>() / (n * smaj);
        let ps = sc.ss.iter().sum::<f64>() / (n * smaj);
        if scatter_mode {
            // Emission collected at every tentative collision (ratio-style), then the event.
            for c in 0..w.len() {
                l[c] += w[c] * sc.j[c] / smaj;
            }
        }
        let xi = rng.next_f64();
        if xi < pa {
            if !scatter_mode {
                for c in 0..w.len() {
                    l[c] += w[c] * sc.j[c] / (smaj * pa);
                }
            }
            w.iter_mut().for_each(|v| *v = 0.0);
            event = Event::Absorbed;
            false
        } else if xi < pa + ps {
            if scatter_mode {
                for c in 0..w.len() {
                    w[c] *= sc.ss[c] / (smaj * ps);
                }
                event = Event::Scattered(tt);
            } else {
                w.iter_mut().for_each(|v| *v = 0.0);
                event = Event::Absorbed;
            }
            false
        } else {
            let pn = 1.0 - pa - ps;
            for c in 0..w.len() {
                let sn = (smaj - sc.sa[c] - sc.ss[c]).max(0.0);
                w[c] *= sn / (smaj * pn);
            }
            true
        }
    });
    if capped {
        w.iter_mut().for_each(|v| *v = 0.0);
        event = Event::Absorbed;
    }
    event
}

/// Samples the first real scattering event along the ray (delta tracking with spectral weights), collecting
/// the emission before it in `l`. `w` gets the event's throughput weights.
pub(crate) fn sample_scatter(
    m: &dyn Medium,
    ray: &Ray,
    sc: &mut Scratch,
    l: &mut [f64],
    w: &mut [f64],
) -> Event {
    l.iter_mut().for_each(|v| *v = 0.0);
    w.iter_mut().for_each(|v| *v = 1.0);
    let Some(span) = Span::new(m, ray) else {
        return Event::Escaped;
    };
    let mut rng = ray.rng();
    delta(&span, &mut rng, sc, l, w, true)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A homogeneous medium inside a box or sphere, for closed-form checks.
    pub struct Uniform {
        pub sa: Vec<f64>,
        pub ss: Vec<f64>,
        pub j: Vec<f64>,
        sphere: Option<f64>,
        pub step: f64,
        /// Majorant floor, so tracking sees null collisions even in thin media.
        maj: f64,
    }

    impl Medium for Uniform {
        fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
            match self.sphere {
                Some(r) => {
                    // |o + t d|² = r²
                    let (a, b, c) = (d.dot(d), 2.0 * o.dot(d), o.dot(o) - r * r);
                    let disc = b * b - 4.0 * a * c;
                    if disc <= 0.0 {
                        return None;
                    }
                    let q = disc.sqrt();
                    let (ta, tb) = ((-b - q) / (2.0 * a), (-b + q) / (2.0 * a));
                    let (lo, hi) = (ta.max(t0), tb.min(t1));
                    (lo < hi).then_some((lo, hi))
                }
                // The slab 0 ≤ x ≤ 1.
                None => {
                    let (ta, tb) = if d.x != 0.0 {
                        ((0.0 - o.x) / d.x, (1.0 - o.x) / d.x)
                    } else {
                        (f64::NEG_INFINITY, f64::INFINITY)
                    };
                    let (lo, hi) = (ta.min(tb).max(t0), ta.max(tb).min(t1));
                    (lo < hi).then_some((lo, hi))
                }
            }
        }
        fn step(&self) -> f64 {
            self.step
        }
        fn eval(&self, _p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
            sa.copy_from_slice(&self.sa);
            ss.copy_from_slice(&self.ss);
            j.copy_from_slice(&self.j);
        }
        fn majorants(
            &self,
            o: DVec3,
            d: DVec3,
            t0: f64,
            t1: f64,
            f: &mut dyn FnMut(f64, f64, f64) -> bool,
        ) {
            let smaj = self
                .sa
                .iter()
                .zip(&self.ss)
                .map(|(a, s)| a + s)
                .fold(self.maj, f64::max);
            if let Some((a, b)) = self.clip(o, d, t0, t1) {
                f(a, b, smaj);
            }
        }
        fn cutoff(&self) -> f64 {
            0.0
        }
    }

    fn slab(kappa: f64, b: f64) -> Uniform {
        Uniform {
            sa: vec![kappa],
            ss: vec![0.0],
            j: vec![kappa * b],
            sphere: None,
            step: 0.05,
            maj: 0.0,
        }
    }

    fn run(m: &Uniform, ray: &Ray, how: Integrator) -> (f64, f64) {
        let mut sc = Scratch::new(1);
        let (mut l, mut t) = ([0.0], [0.0]);
        integrate(m, ray, how, &mut sc, &mut l, &mut t);
        (l[0], t[0])
    }

    #[test]
    fn march_matches_the_slab_closed_form_for_every_optical_depth() {
        // L = B (1 − e^{−τ}) through a unit slab (shared/data), τ from 1e-12 to 1e8, relative 1e-3 or better.
        let b = 7.5;
        for tau in [1e-12, 1e-8, 1e-4, 1e-2, 0.1, 1.0, 5.0, 20.0, 50.0, 1e3, 1e8] {
            let m = slab(tau, b);
            let ray = Ray {
                o: DVec3::new(-1.0, 0.3, 0.2),
                d: DVec3::new(2.0, 0.0, 0.0),
                t0: 0.0,
                t1: 10.0,
                seed: 3,
                first: None,
            };
            let (l, t) = run(&m, &ray, Integrator::March);
            let want = b * -(-tau).exp_m1();
            assert!(((l - want) / want).abs() < 1e-9, "τ={tau}: {l} vs {want}");
            assert!(
                (t - (-tau).exp()).abs() <= 1e-12 * (-tau).exp().max(1e-300),
                "τ={tau}: T={t}"
            );
            assert!(l.is_finite() && (0.0..=1.0).contains(&t));
        }
    }

    #[test]
    fn sphere_chords_match_the_closed_form() {
        // L(b) = B (1 − e^{−2κ√(R²−b²)}) (shared/data), τ across the centre from 1e-4 to 50.
        for tau_c in [1e-4, 1e-2, 1.0, 10.0, 50.0] {
            let (r, bb) = (0.8, 3.0);
            let kappa = tau_c / (2.0 * r);
            let m = Uniform {
                sa: vec![kappa],
                ss: vec![0.0],
                j: vec![kappa * bb],
                sphere: Some(r),
                step: r / 40.0,
                maj: 0.0,
            };
            for imp in [0.0, 0.3, 0.6, 0.79] {
                let ray = Ray {
                    o: DVec3::new(imp, -5.0, 0.0),
                    d: DVec3::Y,
                    t0: 0.0,
                    t1: 100.0,
                    seed: 11,
                    first: None,
                };
                let (l, _) = run(&m, &ray, Integrator::March);
                let want = bb * -(-2.0 * kappa * (r * r - imp * imp).sqrt()).exp_m1();
                assert!(
                    ((l - want) / want).abs() < 1e-3,
                    "τc={tau_c} b={imp}: {l} vs {want}"
                );
            }
        }
    }

    #[test]
    fn tracking_estimators_agree_within_three_sigma() {
        // Ratio and delta tracking: the mean over N seeds within 3σ (σ from the sample) of the closed form.
        for tau in [1e-4, 0.5, 3.0, 50.0] {
            let mut m = slab(tau, 2.0);
            // A majorant above σ_t (as over a real grid), so null collisions happen even when τ is tiny.
            m.maj = 4.0;
            let want_l = 2.0 * -(-tau).exp_m1();
            let want_t = (-tau).exp();
            for how in [Integrator::Ratio, Integrator::Delta] {
                let n = 4000;
                let (mut sl, mut sl2, mut st, mut st2) = (0.0, 0.0, 0.0, 0.0);
                for s in 0..n {
                    let ray = Ray {
                        o: DVec3::new(-1.0, 0.0, 0.0),
                        d: DVec3::X,
                        t0: 0.0,
                        t1: 5.0,
                        seed: s,
                        first: None,
                    };
                    let (l, t) = run(&m, &ray, how);
                    assert!(l.is_finite() && (0.0..=1.0).contains(&t));
                    sl += l;
                    sl2 += l * l;
                    st += t;
                    st2 += t * t;
                }
                let nf = n as f64;
                let (ml, mt) = (sl / nf, st / nf);
                // Delta's absorption score (B = 2 per event) is rare at small τ: at least its Bernoulli σ.
                let sel = ((sl2 / nf - ml * ml).max(0.0) / nf)
                    .sqrt()
                    .max((want_l * 2.0 / nf).sqrt());
                // Delta's transmittance is 0 or 1 per sample: its σ is at least the Bernoulli one.
                let set = ((st2 / nf - mt * mt).max(0.0) / nf)
                    .sqrt()
                    .max((want_t * (1.0 - want_t) / nf).sqrt());
                assert!(
                    (ml - want_l).abs() <= 3.0 * sel + 1e-12 * want_l,
                    "{how:?} τ={tau}: L {ml} ± {sel} vs {want_l}"
                );
                assert!(
                    (mt - want_t).abs() <= 3.0 * set + 1e-12,
                    "{how:?} τ={tau}: T {mt} ± {set} vs {want_t}"
                );
            }
        }
    }

    #[test]
    fn scatter_sampling_weights_average_to_transmittance() {
        // With σ_s = σ_t (pure scatterer), P(scatter before x) = 1 − e^{−σ x}; escaped weight = 1.
        let m = Uniform {
            sa: vec![0.0],
            ss: vec![2.0],
            j: vec![0.0],
            sphere: None,
            step: 0.1,
            maj: 0.0,
        };
        let mut sc = Scratch::new(1);
        let n = 20_000;
        let mut escaped = 0;
        for s in 0..n {
            let ray = Ray {
                o: DVec3::new(0.0, 0.0, 0.0),
                d: DVec3::X,
                t0: 0.0,
                t1: 1.0,
                seed: s,
                first: None,
            };
            let (mut l, mut w) = ([0.0], [0.0]);
            match sample_scatter(&m, &ray, &mut sc, &mut l, &mut w) {
                Event::Escaped => escaped += 1,
                Event::Scattered(t) => {
                    assert!((0.0..1.0).contains(&t) && (w[0] - 1.0).abs() < 1e-12)
                }
                Event::Absorbed => panic!("no absorption in a pure scatterer"),
            }
        }
        let p = escaped as f64 / n as f64;
        let want = (-2.0f64).exp();
        let sigma = (want * (1.0 - want) / n as f64).sqrt();
        assert!((p - want).abs() < 3.0 * sigma, "{p} vs {want}");
    }

    #[test]
    fn degenerate_rays_are_harmless() {
        let m = slab(1.0, 1.0);
        for ray in [
            Ray {
                o: DVec3::ZERO,
                d: DVec3::ZERO,
                t0: 0.0,
                t1: 1.0,
                seed: 0,
                first: None,
            },
            Ray {
                o: DVec3::NAN,
                d: DVec3::X,
                t0: 0.0,
                t1: 1.0,
                seed: 0,
                first: None,
            },
            Ray {
                o: DVec3::new(2.0, 0.0, 0.0),
                d: DVec3::X,
                t0: 0.0,
                t1: 1.0,
                seed: 0,
                first: None,
            },
            Ray {
                o: DVec3::new(0.5, 0.0, 0.0),
                d: DVec3::Y,
                t0: 0.0,
                t1: 1.0,
                seed: 0,
                first: None,
            },
        ] {
            for how in [Integrator::March, Integrator::Ratio, Integrator::Delta] {
                let (l, t) = run(&m, &ray, how);
                assert!(
                    l.is_finite() && (0.0..=1.0).contains(&t),
                    "{ray:?} {how:?}: {l} {t}"
                );
            }
        }
        // Starting inside the slab, lying in its plane: the parallel ray inside integrates its full length.
        let (l, t) = run(
            &m,
            &Ray {
                o: DVec3::new(0.5, 0.0, 0.0),
                d: DVec3::Y,
                t0: 0.0,
                t1: 2.0,
                seed: 0,
                first: None,
            },
            Integrator::March,
        );
        assert!(
            ((l - -(-2.0f64).exp_m1()) / l).abs() < 1e-9 && (t - (-2.0f64).exp()).abs() < 1e-12
        );
    }
}

thread_local! {
    pub(super) static EVALUATIONS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// How many times any fire volume evaluated its coefficients on this thread (a counter for benchmarks: read it
/// before and after the work, on the same thread).
pub fn evaluations_on_this_thread() -> u64 {
    EVALUATIONS.with(|n| n.get())
}
