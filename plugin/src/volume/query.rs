//! The fire volume's whole-ray queries: integrate (straight, or bent by refraction, with where the ray leaves),
//! transmittance and scattering events, at a time (motion blur, moving embers) and at a coarser step (the
//! light's line); the embers cut the ray, thick lines fold in beside the march.

use super::*;

impl FireVolume {
    /// The one whole-ray query: what `want` asks along `ray`, at `time` (frames from the grids' time: with motion
    /// blur the fire is looked up where its velocity carried it from, and embers are where theirs carried them;
    /// `None`: the grids as they are, embers at time 0). `l` gets the emitted radiance (before the event, for
    /// [`Want::Scatter`]), `t` the transmittance (the event's weights). Every `integrate*`, `transmittance*` and
    /// `sample_scatter*` below is this.
    pub fn query(
        &self,
        ray: &Ray,
        time: Option<f64>,
        want: Want,
        l: &mut [f64],
        t: &mut [f64],
    ) -> Answer {
        let at = time.unwrap_or(0.0);
        let (cut, hit) = self.ember_cut(ray, at);
        // The fire as it stands at `time` (motion blur), looked up once for the whole query.
        let adv = time.and_then(|time| self.advected(time));
        let adv = adv.as_ref();
        match want {
            Want::Radiance { step } => {
                let te = match step {
                    Some(s)
                        if self.estimator.integrator() == Integrator::March
                            && s > self.estimator.step() =>
                    {
                        self.stepped_fire(adv, &cut, s, l, t)
                    }
                    _ => self.integrate_fire(adv, &cut, l, t),
                };
                Answer::Ends(self.ember_seen(hit, at, Some(l), t).unwrap_or(te))
            }
            Want::Exit => {
                let exit = self.integrate_exit_fire(adv, &cut, l, t);
                Answer::Exits(match self.ember_seen(hit, at, Some(l), t) {
                    Some(th) => (ray.o + ray.d * th, exit.1, th),
                    None => exit,
                })
            }
            Want::Transmittance => {
                self.transmittance_fire(adv, &cut, t);
                self.ember_seen(hit, at, None, t);
                Answer::Transmitted
            }
            Want::Scatter => {
                let ev = self.sample_scatter_fire(adv, &cut, l, t);
                Answer::Event(self.ember_event(ev, hit, at, l, t))
            }
        }
    }
    /// Emitted radiance `l` and transmittance `t` (per channel) along `ray`; returns the exit parameter (where
    /// an ember stopped the ray, if one did).
    pub fn integrate(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> f64 {
        self.query(ray, None, Want::Radiance { step: None }, l, t)
            .end(ray)
    }
    /// As [`integrate`](Self::integrate), and where the ray leaves: (point, unit direction, parameter). With
    /// refraction on, the ray curves through the index field and leaves bent (`volume/bent.rs`); the parameter
    /// is then the entry parameter plus arc length / |d|. (Embers are met along the straight chord.)
    pub fn integrate_exit(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> (DVec3, DVec3, f64) {
        self.query(ray, None, Want::Exit, l, t).exit(ray)
    }
    /// Transmittance only (along the straight ray, also with refraction on: shadow rays do not bend).
    pub fn transmittance(&self, ray: &Ray, t: &mut [f64]) {
        self.query(ray, None, Want::Transmittance, &mut [], t);
    }
    /// The first real scattering event (see [`Event`]); `l` gets the emission before it, `w` its weights. A ray
    /// that reaches an ember collects its radiance and ends there ([`Event::Absorbed`]).
    pub fn sample_scatter(&self, ray: &Ray, l: &mut [f64], w: &mut [f64]) -> Event {
        self.query(ray, None, Want::Scatter, l, w).event()
    }
    /// As [`integrate`](Self::integrate) at time `time` (frames from the grids' time): with motion blur the
    /// fire is looked up where the velocity carried it from (`motion`), and embers are where their velocity
    /// carried them. Without motion blur or embers, or at time 0, the same as `integrate`.
    pub fn integrate_at(&self, ray: &Ray, time: f64, l: &mut [f64], t: &mut [f64]) -> f64 {
        self.query(ray, Some(time), Want::Radiance { step: None }, l, t)
            .end(ray)
    }
    /// As [`integrate_at`](Self::integrate_at) with the march's step `step` (metres) instead of the volume's —
    /// the fire light's coarse line estimate. A volume that tracks (ratio, delta) or whose own step is as long
    /// integrates as `integrate_at` does.
    pub fn integrate_stepped_at(
        &self,
        ray: &Ray,
        time: f64,
        step: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        self.query(ray, Some(time), Want::Radiance { step: Some(step) }, l, t)
            .end(ray)
    }
    /// As [`integrate_exit`](Self::integrate_exit) at time `time`. (Refraction's curved march follows the
    /// grids' time: a refracting volume ignores `time` here but for its embers.)
    pub fn integrate_exit_at(
        &self,
        ray: &Ray,
        time: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> (DVec3, DVec3, f64) {
        self.query(ray, Some(time), Want::Exit, l, t).exit(ray)
    }
    /// As [`transmittance`](Self::transmittance) at time `time`.
    pub fn transmittance_at(&self, ray: &Ray, time: f64, t: &mut [f64]) {
        self.query(ray, Some(time), Want::Transmittance, &mut [], t);
    }
    /// As [`sample_scatter`](Self::sample_scatter) at time `time`.
    pub fn sample_scatter_at(&self, ray: &Ray, time: f64, l: &mut [f64], w: &mut [f64]) -> Event {
        self.query(ray, Some(time), Want::Scatter, l, w).event()
    }
    /// The march at `step` along a cut ray in the fire as `adv` has moved it, thick lines folded in.
    fn stepped_fire(
        &self,
        adv: Option<&motion::Advected>,
        cut: &Ray,
        step: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        self.fault_check();
        let te = match adv {
            Some(a) => {
                let map = |p: DVec3| a.displaced(p);
                march::integrate_stepped(self, a, Some(&map), cut, step, l, t)
            }
            None => march::integrate_stepped(self, self, None, cut, step, l, t),
        };
        self.thick_lines(adv, cut, cut.t1, Some(l), t, lines::Fold::Add);
        te
    }
    /// `ray` up to the first ember it meets at `time`, and that ember's (parameter, index).
    pub(super) fn ember_cut(&self, ray: &Ray, time: f64) -> (Ray, Option<(f64, usize)>) {
        let hit = self
            .layers
            .embers()
            .and_then(|e| e.hit(ray.o, ray.d, ray.t0, ray.t1, time));
        let mut cut = *ray;
        if let Some((th, _)) = hit {
            cut.t1 = th.max(ray.t0);
        }
        (cut, hit)
    }
    /// An ember met at the end of a cut ray: its radiance seen through `t` added to `l`, and nothing passes
    /// it; returns where it was met.
    pub(super) fn ember_seen(
        &self,
        hit: Option<(f64, usize)>,
        time: f64,
        l: Option<&mut [f64]>,
        t: &mut [f64],
    ) -> Option<f64> {
        let (Some((th, i)), Some(em)) = (hit, self.layers.embers()) else {
            return None;
        };
        if let Some(l) = l {
            let mut e = vec![0.0; t.len()];
            em.radiance(i, time, &mut e);
            for c in 0..t.len() {
                l[c] += t[c] * e[c];
            }
        }
        t.iter_mut().for_each(|v| *v = 0.0);
        Some(th)
    }
    /// A scattering event on a cut ray: one that reached the ember collects its radiance and ends there.
    pub(super) fn ember_event(
        &self,
        ev: Event,
        hit: Option<(f64, usize)>,
        time: f64,
        l: &mut [f64],
        w: &mut [f64],
    ) -> Event {
        match ev {
            Event::Escaped if hit.is_some() => {
                self.ember_seen(hit, time, Some(l), w);
                Event::Absorbed
            }
            _ => ev,
        }
    }
    /// Emitted radiance `l` and transmittance `t` (per channel) along `ray`, in the fire as `adv` has moved it
    /// (`None`: as the grids are); returns the exit parameter.
    fn integrate_fire(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        self.fault_check();
        let te = match adv {
            Some(a) => a.integrate(ray, l, t),
            None => march::integrate(self, ray, l, t),
        };
        self.thick_lines(adv, ray, ray.t1, Some(l), t, lines::Fold::Add);
        te
    }
    /// The thick lines' part of a result along `ray` up to `end` (see [`lines`]), in the medium as `adv` sees it.
    pub(super) fn thick_lines(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        end: f64,
        l: Option<&mut [f64]>,
        t: &mut [f64],
        fold: lines::Fold,
    ) {
        if let Some(tl) = self.layers.lines() {
            match adv {
                Some(a) => tl.apply(self, ray, end, false, &|p| a.displaced(p), l, t, fold),
                None => tl.apply(self, ray, end, true, &|p| p, l, t, fold),
            }
        }
    }
    /// `sample_scatter`'s event with the thick lines folded in (emission before the event, their mean
    /// transmittance on the weights).
    pub(super) fn scatter_lines(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        ev: Event,
        l: &mut [f64],
        w: &mut [f64],
    ) -> Event {
        let end = match ev {
            Event::Scattered(t) => t,
            Event::Escaped => ray.t1,
            Event::Absorbed => return ev,
        };
        self.thick_lines(adv, ray, end, Some(l), w, lines::Fold::Scale);
        ev
    }
    /// As [`integrate_fire`](Self::integrate_fire), and where the ray leaves: (point, unit direction,
    /// parameter). With refraction on, the ray curves through the index field and leaves bent
    /// (`volume/bent.rs`), the parameter then the entry parameter plus arc length / |d| — along the grids as they
    /// are: refraction's curved march ignores motion.
    fn integrate_exit_fire(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        l: &mut [f64],
        t: &mut [f64],
    ) -> (DVec3, DVec3, f64) {
        let Some(rf) = self.layers.refraction() else {
            let te = self.integrate_fire(adv, ray, l, t);
            return (ray.o + ray.d * te, ray.d.normalize_or_zero(), te);
        };
        self.fault_check();
        let exit = super::bent::integrate_exit(self, rf, ray, l, t);
        // (Along the straight chord: the bend is a fraction of a degree.)
        self.thick_lines(None, ray, ray.t1, Some(l), t, lines::Fold::Add);
        exit
    }
    /// Transmittance only (along the straight ray, also with refraction on: shadow rays do not bend), in the fire
    /// as `adv` has moved it.
    fn transmittance_fire(&self, adv: Option<&motion::Advected>, ray: &Ray, t: &mut [f64]) {
        match adv {
            Some(a) => a.transmittance(ray, t),
            None => {
                Scratch::with(self.channels(), |sc| {
                    integrate::transmittance(self, ray, self.estimator.integrator(), sc, t)
                });
            }
        }
        self.thick_lines(adv, ray, ray.t1, None, t, lines::Fold::Add);
    }
    /// The first real scattering event (see [`Event`]) in the fire as `adv` has moved it; `l` gets the emission
    /// before it, `w` its weights.
    fn sample_scatter_fire(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        l: &mut [f64],
        w: &mut [f64],
    ) -> Event {
        let ev = match adv {
            Some(a) => a.sample_scatter(ray, l, w),
            None => Scratch::with(self.channels(), |sc| {
                integrate::sample_scatter(self, ray, sc, l, w)
            }),
        };
        self.scatter_lines(adv, ray, ev, l, w)
    }
    pub(super) fn advected(&self, time: f64) -> Option<motion::Advected<'_>> {
        self.layers.blur().and_then(|b| b.at(self, time))
    }
}

/// What a whole-ray [`FireVolume::query`] asks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Want {
    /// Emitted radiance and transmittance along the straight ray; with a `step` longer than the volume's, a march
    /// at that step (a coarse estimate: the fire light's line).
    Radiance { step: Option<f64> },
    /// The same following the ray where it bends (refraction), and where it leaves.
    Exit,
    /// Transmittance only (shadow rays; straight).
    Transmittance,
    /// The first real scattering event.
    Scatter,
}

/// What a [`FireVolume::query`] found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Answer {
    /// The ray's parameter where it ended (its end, or an ember).
    Ends(f64),
    /// Where it left: point, unit direction, parameter.
    Exits((DVec3, DVec3, f64)),
    /// Transmittance only.
    Transmitted,
    /// A scattering query's event.
    Event(Event),
}

impl Answer {
    /// The end parameter (the ray's own end for an answer without one).
    pub fn end(self, ray: &Ray) -> f64 {
        match self {
            Answer::Ends(t) | Answer::Exits((_, _, t)) => t,
            Answer::Event(Event::Scattered(t)) => t,
            _ => ray.t1,
        }
    }
    /// The exit (the straight ray's end for an answer without one).
    pub fn exit(self, ray: &Ray) -> (DVec3, DVec3, f64) {
        match self {
            Answer::Exits(e) => e,
            a => {
                let t = a.end(ray);
                (ray.o + ray.d * t, ray.d.normalize_or_zero(), t)
            }
        }
    }
    /// The event (escaped for an answer without one).
    pub fn event(self) -> Event {
        match self {
            Answer::Event(e) => e,
            _ => Event::Escaped,
        }
    }
}
