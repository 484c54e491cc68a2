//! The straight march's one entry point, [`integrate`]: the lane kernel ([`super::kernel`]) where the volume has
//! f32 lanes, trilinear grids (its lattice, or the grids read in place) and at most 32 channels, else the lane march over the dataset ([`march_lanes`]), else
//! the f64 estimators of [`super::integrate`] (march, ratio, delta). All three take the same steps at the same
//! points and stop by the same rule (tested), so the choice changes only rounding.
//!
//! [`Stepper`] is the march's per-step work for paths the volume does not trace itself: refraction's curved
//! rays.

use super::integrate::{self, Medium, Scratch, EVALUATIONS};
use super::{kernel, lanes, FireVolume, Ray};
use glam::DVec3;

/// Radiance `l` and transmittance `t` along `ray` by the volume's fastest exact path; returns the exit parameter.
pub(super) fn integrate(v: &FireVolume, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> f64 {
    if let Some(lt) = v.estimator.lanes() {
        if let Some(b) = march_kernel(v, lt, None, ray, v.estimator.step(), l, t) {
            return b;
        }
        // (The lane march over the dataset does not split thick steps: a volume that splits them takes f64.)
        if v.estimator.step_tau().is_infinite() {
            return march_lanes(v, lt, ray, l, t);
        }
    }
    Scratch::with(v.channels(), |sc| {
        integrate::integrate(v, ray, v.estimator.integrator(), sc, l, t)
    })
}

/// As [`integrate`] with the march's step `step` (metres) instead of the volume's, for a volume that marches
/// (`m`: the volume itself, or as motion blur displaces it).
pub(super) fn integrate_stepped(
    v: &FireVolume,
    m: &dyn Medium,
    mapped: Option<&dyn Fn(DVec3) -> DVec3>,
    ray: &Ray,
    step: f64,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    let stepped = Stepped { m, step };
    match (v.estimator.lanes(), mapped) {
        // (The fire light's line: an estimate checked against the volume's own march, its steps not split.)
        (Some(lt), None) => {
            let own = kernel::Tabs::own(v, lt, false);
            march_kernel(v, lt, Some(own), ray, step, l, t)
                .unwrap_or_else(|| march_lanes_mapped(v, lt, &stepped, |p| p, ray, l, t))
        }
        (Some(lt), Some(f)) => march_lanes_mapped(v, lt, &stepped, f, ray, l, t),
        (None, _) => Scratch::with(v.channels(), |sc| {
            integrate::integrate(&stepped, ray, integrate::Integrator::March, sc, l, t)
        }),
    }
}

/// A medium marched with another step: everything but the step is `m`'s.
struct Stepped<'a> {
    m: &'a dyn Medium,
    step: f64,
}

impl Medium for Stepped<'_> {
    fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        self.m.clip(o, d, t0, t1)
    }
    fn step(&self) -> f64 {
        self.step
    }
    fn eval(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        self.m.eval(p, sa, ss, j)
    }
    fn majorants(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) {
        self.m.majorants(o, d, t0, t1, f)
    }
    fn cutoff(&self) -> f64 {
        self.m.cutoff()
    }
    fn step_tau(&self) -> f64 {
        // (The fire light's line at its own step: not split, as in the kernel.)
        f64::INFINITY
    }
    fn empty_spans(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, f: &mut dyn FnMut(f64, f64)) {
        self.m.empty_spans(o, d, t0, t1, f)
    }
    fn collision_cap_hit(&self) {
        self.m.collision_cap_hit()
    }
}

impl FireVolume {
    /// One march step in lanes at `p`: the coefficients there, then the step; returns the largest transmittance.
    /// (Inlined always, so that `march_lanes`' AVX2 clone holds it.)
    #[inline(always)]
    pub(super) fn lane_step(
        &self,
        lt: &lanes::LaneTables,
        p: DVec3,
        delta: f64,
        ls: &mut LaneScratch,
    ) -> f32 {
        let Some(st) = self.grids.ds().stencil_with_margin(p, self.bounds.margin()) else {
            return 1.0;
        };
        let ch = self.grids.ds().channels();
        let d = ch[self.grids.density()].grid.eval(&st).max(0.0);
        let mut n = [0f32; lanes::MAX_SPECIES];
        for (k, sp) in self.grids.species().iter().enumerate() {
            n[k] = (ch[sp.ch()].grid.eval(&st).max(0.0) as f64 * sp.scale()) as f32;
        }
        let les = self
            .grids
            .lescale()
            .map_or(1.0, |i| ch[i].grid.eval(&st).max(0.0));
        // No soot, no species and no emission grid here: σ = j = 0, the step would add +0 and multiply by e⁰ = 1
        // exactly, so it is skipped (bit for bit the same; the transmittance is unchanged, so the march goes on).
        if d == 0.0 && n.iter().all(|&x| x == 0.0) && !(self.grids.emission_grid() && les > 0.0) {
            return 1.0;
        }
        let t = self
            .grids
            .temperature()
            .map_or(0.0, |i| ch[i].grid.eval(&st));
        let emits = t as f64 > self.model.t_emit() || self.grids.temperature().is_none();
        let LaneScratch { sig, jj, l, t: tr } = ls;
        let dl = if emits { self.emitting(d, les) } else { 0.0 };
        lt.coefficients(self, lanes::Sample::new(d, t, dl), &n, sig, jj);
        lanes::step(sig, jj, delta as f32, l, tr)
    }
}

/// One march step at a time at points the caller chooses (refraction's curved rays): in f32 lanes where the
/// volume has them and the caller asks for them, else in f64 (radiance and transmittance accumulate straight
/// into the caller's arrays).
pub(crate) struct Stepper<'a> {
    v: &'a FireVolume,
    lanes: Option<(&'a lanes::LaneTables, LaneScratch)>,
    sc: Scratch,
}

impl<'a> Stepper<'a> {
    /// A stepper over `v`; `lanes`: use the volume's f32 lanes if it has them.
    pub(crate) fn new(v: &'a FireVolume, lanes: bool) -> Stepper<'a> {
        Stepper {
            v,
            lanes: v
                .estimator
                .lanes()
                .filter(|_| lanes)
                .map(|lt| (lt, LaneScratch::new(lt.chunks()))),
            sc: Scratch::new(v.channels()),
        }
    }
    /// Adds the step of length `h` whose coefficients are taken at `p`; returns whether the ray is now opaque
    /// (its largest transmittance under the volume's cutoff).
    #[inline(always)]
    pub(crate) fn step(&mut self, p: DVec3, h: f64, l: &mut [f64], t: &mut [f64]) -> bool {
        let v = self.v;
        match &mut self.lanes {
            Some((lt, ls)) => {
                EVALUATIONS.with(|n| n.set(n.get() + 1));
                v.lane_step(lt, p, h, ls) < v.estimator.cutoff() as f32
            }
            None => self.sc.march_at(v, p, h, l, t) < v.estimator.cutoff(),
        }
    }
    /// Writes the lanes' radiance and transmittance to `l` and `t` (the f64 path wrote them as it went).
    pub(crate) fn finish(&self, l: &mut [f64], t: &mut [f64]) {
        if let Some((_, ls)) = &self.lanes {
            ls.finish(l, t);
        }
    }
}

/// The straight march in f32 lanes (the same steps, at the same points, as the f64 march of `integrate`); compiled
/// twice, for baseline x86-64 and for AVX2 + FMA (8 channels per instruction), chosen once at run time.
pub(super) fn march_lanes(
    v: &FireVolume,
    lt: &lanes::LaneTables,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    march_lanes_mapped(v, lt, v, |p| p, ray, l, t)
}

/// As [`march_lanes`], with the ray clipped and its empty stretches skipped by `m`, and each step's coefficients
/// taken at `map(p)` (motion blur's displaced lookups; the identity otherwise).
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
pub(super) fn march_lanes_mapped<M: Fn(DVec3) -> DVec3>(
    v: &FireVolume,
    lt: &lanes::LaneTables,
    m: &dyn Medium,
    map: M,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    l.iter_mut().for_each(|v| *v = 0.0);
    t.iter_mut().for_each(|v| *v = 1.0);
    let Some(span) = integrate::Span::new(m, ray) else {
        return ray.t1;
    };
    let mut rng = ray.rng();
    let mut ls = LaneScratch::new(lt.chunks());
    let mut empty = Vec::new();
    let cutoff = v.estimator.cutoff() as f32;
    let mut samples = 0;
    integrate::march_steps(&span, &mut rng, &mut empty, l.len(), |p, delta| {
        samples += 1;
        v.lane_step(lt, map(p), delta, &mut ls) >= cutoff
    });
    EVALUATIONS.with(|n| n.set(n.get() + samples));
    ls.finish(l, t);
    span.b()
}

/// The straight march's kernel (`kernel::march`) for 1–4 lanes of channels (`None` for more: `march_lanes`
/// takes them); compiled for baseline x86-64, for AVX2 + FMA and for AVX-512, chosen at run time — AVX-512 only
/// where [`simd`] allows it (`FIREMEDIUM_SIMD=avx2` caps the kernel at what an AVX2 machine runs). `tabs`: the
/// channels to march, the volume's own when `None` (`l` and `t` hold as many as the tables have columns).
pub(super) fn march_kernel(
    v: &FireVolume,
    lt: &lanes::LaneTables,
    tabs: Option<kernel::Tabs>,
    ray: &Ray,
    step: f64,
    l: &mut [f64],
    t: &mut [f64],
) -> Option<f64> {
    if simd() == Simd::Avx2 {
        march_kernel_avx2(v, lt, tabs, ray, step, l, t)
    } else {
        march_kernel_any(v, lt, tabs, ray, step, l, t)
    }
}

/// The instruction sets the march kernel may use: the best this CPU has, or at most AVX2.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Simd {
    Native,
    Avx2,
}

/// The environment variable that caps the march kernel's instruction set.
pub const SIMD_VAR: &str = "FIREMEDIUM_SIMD";

/// `FIREMEDIUM_SIMD` read: unset, empty or `native` — the best this CPU has; `avx2` — no AVX-512 (what AVX2
/// machines run, to measure them on a newer CPU or to render a farm's frames alike). Anything else is an error.
pub fn simd_setting(value: Option<&str>) -> Result<Simd, crate::Error> {
    match value.map(str::trim) {
        None | Some("") => Ok(Simd::Native),
        Some(v) if v.eq_ignore_ascii_case("native") => Ok(Simd::Native),
        Some(v) if v.eq_ignore_ascii_case("avx2") => Ok(Simd::Avx2),
        Some(v) => Err(crate::Error::invalid(
            "volume",
            SIMD_VAR,
            format!("{v:?}"),
            "native or avx2 (the environment variable capping the march kernel's instruction set)",
        )),
    }
}

/// The cap from the environment, read once per process (an unreadable value: no cap here — volumes refuse to
/// be built with it, [`check_simd`]).
pub fn simd() -> Simd {
    static CAP: std::sync::OnceLock<Simd> = std::sync::OnceLock::new();
    *CAP.get_or_init(|| simd_from_env().unwrap_or(Simd::Native))
}

/// Refuses a `FIREMEDIUM_SIMD` the march cannot honour (a volume's build calls it).
pub fn check_simd() -> Result<(), crate::Error> {
    simd_from_env().map(|_| ())
}

fn simd_from_env() -> Result<Simd, crate::Error> {
    let v = std::env::var_os(SIMD_VAR).map(|v| v.to_string_lossy().into_owned());
    simd_setting(v.as_deref())
}

/// `kernel::march` in `cv` lanes of `v` channels for spectral bins (with or without species; T-dependent absorption
/// is rgb's alone).
macro_rules! lanes {
    ($cv:literal, $v:literal, $s:expr, $a:expr, $f:ident, ($($arg:expr),*)) => {
        match ($s, $a) {
            (false, false) => kernel::march::<$cv, $v, false, false, $f>($($arg),*),
            (true, false) => kernel::march::<$cv, $v, true, false, $f>($($arg),*),
            _ => None,
        }
    };
}

/// [`march_kernel`]'s body, compiled for the targets given (the AVX-512 clone's lanes are 16 wide).
macro_rules! march_kernel_for {
    ($name:ident, $($target:literal),+) => {
        #[multiversion::multiversion(targets($($target),+))]
        fn $name(
            v: &FireVolume,
            lt: &lanes::LaneTables,
            tabs: Option<kernel::Tabs>,
            ray: &Ray,
            step: f64,
            l: &mut [f64],
            t: &mut [f64],
        ) -> Option<f64> {
            const F: bool = multiversion::target::target_cfg_f!(target_feature = "fma");
            // The lanes' shape from the channel count: rgb in one lane of 4 (a 128-bit register, no padding
            // work), spectral bins in lanes of 16 where the clone has AVX-512, else of 8. σ_a depends on T only
            // in rgb physical mode (3 channels).
            const WIDE: bool = multiversion::target::target_cfg_f!(target_feature = "avx512f");
            let (s, a) = (!v.grids.species().is_empty(), v.model.a_t().is_some());
            let tb = tabs.unwrap_or_else(|| kernel::Tabs::own(v, lt, true));
            match l.len() {
                0..=4 => match (s, a) {
                    (false, false) => kernel::march::<1, 4, false, false, F>(v, lt, tb, ray, step, l, t),
                    (false, true) => kernel::march::<1, 4, false, true, F>(v, lt, tb, ray, step, l, t),
                    (true, false) => kernel::march::<1, 4, true, false, F>(v, lt, tb, ray, step, l, t),
                    (true, true) => kernel::march::<1, 4, true, true, F>(v, lt, tb, ray, step, l, t),
                },
                5..=8 => lanes!(1, 8, s, a, F, (v, lt, tb, ray, step, l, t)),
                9..=16 if WIDE => lanes!(1, 16, s, a, F, (v, lt, tb, ray, step, l, t)),
                9..=16 => lanes!(2, 8, s, a, F, (v, lt, tb, ray, step, l, t)),
                17..=24 => lanes!(3, 8, s, a, F, (v, lt, tb, ray, step, l, t)),
                25..=32 if WIDE => lanes!(2, 16, s, a, F, (v, lt, tb, ray, step, l, t)),
                25..=32 => lanes!(4, 8, s, a, F, (v, lt, tb, ray, step, l, t)),
                _ => None,
            }
        }
    };
}
march_kernel_for!(
    march_kernel_any,
    "x86_64+avx512f+avx512vl+avx512bw+avx512dq+avx2+fma",
    "x86_64+avx2+fma"
);
march_kernel_for!(march_kernel_avx2, "x86_64+avx2+fma");

/// Per-ray state of the lane march: coefficients at the sample, radiance and transmittance.
pub(super) struct LaneScratch {
    sig: Vec<lanes::Lane>,
    jj: Vec<lanes::Lane>,
    l: Vec<lanes::Lane>,
    t: Vec<lanes::Lane>,
}

impl LaneScratch {
    fn new(chunks: usize) -> LaneScratch {
        let zero = vec![[0f32; lanes::W]; chunks];
        LaneScratch {
            sig: zero.clone(),
            jj: zero.clone(),
            l: zero,
            t: vec![[1f32; lanes::W]; chunks],
        }
    }
    /// The ray's radiance and transmittance per channel.
    fn finish(&self, l: &mut [f64], t: &mut [f64]) {
        for c in 0..l.len() {
            l[c] = self.l[c / lanes::W][c % lanes::W] as f64;
            t[c] = self.t[c / lanes::W][c % lanes::W] as f64;
        }
    }
}

#[cfg(test)]
mod tests {
    //! The three marches agree: the kernel, the lane march and the f64 march take the same steps.
    use super::*;
    use crate::params::Param;
    use crate::volume::tests::{blob_pair, ray_x, run, slab_volume};

    #[test]
    fn f32_lanes_only_where_every_product_fits() {
        // An everyday fire marches in lanes; the tracking integrators do not. (Densities whose σ·step passed
        // f32's 3.4e38 took the f64 march; an optical depth above 1e12 per voxel is now refused when the volume
        // is built, `an_optical_depth_beyond_any_fire_is_an_error_naming_where`.) The thickest slab allowed,
        // ~1e11 per voxel, is opaque: L = B.
        assert!(slab_volume(1e-6, 1500.0, vec![])
            .estimator
            .lanes()
            .is_some());
        let huge = slab_volume(5e4, 1500.0, vec![Param::float("sootscale", 1.0)]);
        let (l, t) = run(&huge, &ray_x(1));
        let b = crate::blackbody::spectral_radiance(1500.0, 555.0);
        assert!(
            (l[15] / b - 1.0).abs() < 5e-3 && t[15] == 0.0,
            "{} vs {b}",
            l[15]
        );
        let ratio = slab_volume(1e-6, 1500.0, vec![Param::string("integrator", "ratio")]);
        assert!(ratio.estimator.lanes().is_none());
        let f64_asked = slab_volume(1e-6, 1500.0, vec![Param::string("precision", "f64")]);
        assert!(f64_asked.estimator.lanes().is_none());
        // A 1e12 × intensity fire at 3000 K (emission per unit density ~1e23) still marches in lanes, 1e12 × the f64 one.
        let bright = slab_volume(
            1e-6,
            3000.0,
            vec![
                Param::float("intensity", 1e12),
                Param::string("precision", "f32"),
            ],
        );
        assert!(bright.estimator.lanes().is_some());
        let dim = slab_volume(1e-6, 3000.0, vec![Param::string("precision", "f64")]);
        let (lb, _) = run(&bright, &ray_x(1));
        let (ld, _) = run(&dim, &ray_x(1));
        for k in 0..lb.len() {
            assert!(
                (lb[k] / (ld[k] * 1e12) - 1.0).abs() < 1e-5,
                "ch {k}: {} vs {}",
                lb[k],
                ld[k] * 1e12
            );
        }
    }

    #[test]
    fn kernel_matches_the_lane_and_f64_marches() {
        // The kernel (`integrate` with lanes) against the lane march it replaces (same f32 arithmetic, per
        // sample) and the f64 march: random rays from outside and inside, along axes, through faces and
        // edges, and through the empty bricks the kernel jumps; rgb and spectral; with Lescale, with species.
        // pbrt mode's thick steps split in sub-steps (`steptau`): the kernel and the f64 march split alike, the
        // lane march over the dataset does not (a splitting volume never takes it), so it is compared unsplit.
        let mut rng = crate::rng::Rng::new(7);
        let mut rays = vec![
            Ray {
                o: DVec3::new(-1.0, 0.63, 0.55),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 1,
                first: None,
            },
            Ray {
                o: DVec3::new(0.6, 0.63, -1.0),
                d: DVec3::Z,
                t0: 0.0,
                t1: 9.0,
                seed: 2,
                first: None,
            },
            Ray {
                o: DVec3::new(0.6, 0.63, 0.55),
                d: DVec3::new(0.3, -1.0, 0.2),
                t0: 0.0,
                t1: 9.0,
                seed: 3,
                first: None,
            },
            Ray {
                o: DVec3::new(-1.0, 0.0, 0.5),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 4,
                first: None,
            }, // in a face
            Ray {
                o: DVec3::new(-1.0, 0.0, 0.0),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 5,
                first: None,
            }, // along an edge
            Ray {
                o: DVec3::new(3.0, 0.6, 0.5),
                d: DVec3::new(-2.0, 0.0, 0.0),
                t0: 0.0,
                t1: 9.0,
                seed: 6,
                first: None,
            },
        ];
        for seed in 0..150 {
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 1.0;
            let target = DVec3::new(0.6, 0.63, 0.55)
                + (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 1.2;
            rays.push(Ray {
                o,
                d: target - o,
                t0: 0.0,
                t1: 5.0,
                seed: 100 + seed,
                first: None,
            });
        }
        let pbrt = |steptau: f64| {
            vec![
                Param::string("mode", "pbrt"),
                Param::string("integrator", "march"),
                Param::float("stepsize", 3.0),
                Param::int("brick", 4),
                Param::float("steptau", steptau),
            ]
        };
        for (extra, species) in [
            (vec![], false),
            (vec![Param::string("colormode", "rgb")], false),
            (pbrt(1e30), false),
            (pbrt(0.02), false),
            (vec![Param::float("stepsize", 0.37)], true),
        ] {
            let split = extra.iter().any(|p| {
                p.name == "steptau" && p.values == crate::params::Values::Numbers(vec![0.02])
            });
            let (v, v64) = blob_pair(&extra, species);
            let lt = v.estimator.lanes().expect("the blob marches in lanes");
            let c = v.channels();
            let (mut worst, mut lit) = (0f64, 0);
            for ray in &rays {
                let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                let (mut l2, mut t2) = (vec![0.0; c], vec![0.0; c]);
                let (mut l3, mut t3) = (vec![0.0; c], vec![0.0; c]);
                let te = v.integrate(ray, &mut l, &mut t);
                let te2 = march_lanes(&v, lt, ray, &mut l2, &mut t2);
                let te3 = v64.integrate(ray, &mut l3, &mut t3);
                assert_eq!(te, te2);
                assert_eq!(te, te3);
                let peak = l3.iter().fold(0f64, |m, &x| m.max(x));
                if peak > 0.0 {
                    lit += 1;
                }
                for k in 0..c {
                    let (l2k, t2k) = if split { (l[k], t[k]) } else { (l2[k], t2[k]) };
                    for (a, what) in [(l2k, "lane march"), (l3[k], "f64 march")] {
                        // Relative to the ray's brightest channel (dim channels carry f32's absolute rounding).
                        let e = (l[k] - a).abs() / peak.max(1e-300);
                        worst = worst.max(e);
                        assert!(e < 2e-5, "{ray:?} ch {k}: kernel {} vs {what} {a}", l[k]);
                    }
                    assert!((t[k] - t2k).abs() < 1e-5 && (t[k] - t3[k]).abs() < 1e-5);
                }
            }
            assert!(lit > 50, "only {lit} rays saw the fire");
            assert!(
                worst > 0.0,
                "f32 and f64 cannot agree to the bit everywhere"
            );
        }
    }

    #[test]
    fn the_avx2_cap_marches_as_the_best_kernel_does() {
        // `FIREMEDIUM_SIMD=avx2` runs the AVX2 clone where the CPU has AVX-512 (30 bins: lanes of 8, not 16);
        // per channel the same arithmetic, so the same numbers (on an AVX2 machine both are the AVX2 clone).
        let rays = crate::volume::tests::blob_rays(40, 900);
        for (extra, species) in [
            (vec![], false),
            (vec![], true),
            (vec![Param::int("bins", 12)], false),
        ] {
            let (v, _) = blob_pair(&extra, species);
            let lt = v.estimator.lanes().expect("the blob marches in lanes");
            let c = v.channels();
            let mut lit = 0;
            for ray in &rays {
                let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                let (mut l2, mut t2) = (vec![0.0; c], vec![0.0; c]);
                let te = march_kernel_any(&v, lt, None, ray, v.estimator.step(), &mut l, &mut t);
                let te2 =
                    march_kernel_avx2(&v, lt, None, ray, v.estimator.step(), &mut l2, &mut t2);
                assert!(te.is_some() && te == te2, "{ray:?}: {te:?} vs {te2:?}");
                let peak = l.iter().fold(0f64, |m, &x| m.max(x));
                lit += (peak > 0.0) as usize;
                for k in 0..c {
                    assert!(
                        (l[k] - l2[k]).abs() <= 1e-6 * peak,
                        "ch {k}: {} vs {}",
                        l[k],
                        l2[k]
                    );
                    assert!(
                        (t[k] - t2[k]).abs() <= 1e-6,
                        "ch {k}: {} vs {}",
                        t[k],
                        t2[k]
                    );
                }
            }
            assert!(lit > 10, "only {lit} rays saw the fire");
        }
        // The variable's values: unset, empty and `native` leave the choice to the CPU; `avx2` caps it; anything
        // else is refused, naming the variable and the value.
        assert_eq!(simd_setting(None), Ok(Simd::Native));
        assert_eq!(simd_setting(Some(" ")), Ok(Simd::Native));
        assert_eq!(simd_setting(Some("Native")), Ok(Simd::Native));
        assert_eq!(simd_setting(Some("avx2")), Ok(Simd::Avx2));
        let e = simd_setting(Some("avx1024")).unwrap_err().to_string();
        assert!(
            e.contains("FIREMEDIUM_SIMD") && e.contains("avx1024") && e.contains("avx2"),
            "{e}"
        );
    }

    #[test]
    fn every_lane_shape_matches_the_f64_march() {
        // The dispatch picks one lane shape per channel count and CPU (this machine's clone runs only some):
        // each shape called directly, with and without FMA, against the f64 march — rgb in one lane of 4,
        // 6/12/20/30 bins in lanes of 8 and of 16, with sodium where it applies.
        let rays = crate::volume::tests::blob_rays(40, 900);
        type Kernel = fn(
            &FireVolume,
            &lanes::LaneTables,
            kernel::Tabs,
            &Ray,
            f64,
            &mut [f64],
            &mut [f64],
        ) -> Option<f64>;
        // (The volume's extra parameters, with sodium, and the shapes to run on it.)
        type Case = (Vec<Param>, bool, Vec<(&'static str, Kernel)>);
        let cases: Vec<Case> = vec![
            (
                vec![Param::string("colormode", "rgb")],
                false,
                vec![
                    ("1×4", kernel::march::<1, 4, false, true, false>),
                    ("1×4 fma", kernel::march::<1, 4, false, true, true>),
                ],
            ),
            (
                vec![Param::string("colormode", "rgb")],
                true,
                vec![("1×4 Na", kernel::march::<1, 4, true, true, true>)],
            ),
            (
                vec![Param::int("bins", 6)],
                false,
                vec![("1×8", kernel::march::<1, 8, false, false, true>)],
            ),
            (
                vec![Param::int("bins", 12)],
                false,
                vec![
                    ("2×8", kernel::march::<2, 8, false, false, true>),
                    ("1×16", kernel::march::<1, 16, false, false, true>),
                ],
            ),
            (
                vec![Param::int("bins", 20)],
                false,
                vec![("3×8", kernel::march::<3, 8, false, false, false>)],
            ),
            (
                vec![],
                false,
                vec![
                    ("4×8", kernel::march::<4, 8, false, false, true>),
                    ("4×8 no fma", kernel::march::<4, 8, false, false, false>),
                    ("2×16", kernel::march::<2, 16, false, false, true>),
                ],
            ),
            (
                vec![],
                true,
                vec![
                    ("4×8 Na", kernel::march::<4, 8, true, false, true>),
                    ("2×16 Na", kernel::march::<2, 16, true, false, true>),
                ],
            ),
        ];
        for (extra, species, kernels) in cases {
            let (v, v64) = blob_pair(&extra, species);
            let lt = v.estimator.lanes().expect("the blob marches in lanes");
            let c = v.channels();
            for (name, kernel) in kernels {
                let mut lit = 0;
                for ray in &rays {
                    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                    let (mut l3, mut t3) = (vec![0.0; c], vec![0.0; c]);
                    let tabs = kernel::Tabs::own(&v, lt, true);
                    let te = kernel(&v, lt, tabs, ray, v.estimator.step(), &mut l, &mut t)
                        .expect("this shape fits");
                    let te3 = v64.integrate(ray, &mut l3, &mut t3);
                    assert_eq!(te, te3, "{name}");
                    let peak = l3.iter().fold(0f64, |m, &x| m.max(x));
                    lit += (peak > 0.0) as usize;
                    for k in 0..c {
                        let e = (l[k] - l3[k]).abs() / peak.max(1e-300);
                        assert!(e < 2e-5, "{name}, {ray:?} ch {k}: {} vs {}", l[k], l3[k]);
                        assert!((t[k] - t3[k]).abs() < 1e-5, "{name} ch {k}");
                    }
                }
                assert!(lit > 10, "{name}: only {lit} rays saw the fire");
            }
        }
    }
}
