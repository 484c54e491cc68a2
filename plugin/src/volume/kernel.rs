//! The straight march's kernel: the f32 lane march of [`super::lanes`] with its per-ray state in registers.
//!
//! The same steps at the same points as `integrate::march_steps` (eq. 3 of Pegoraro & Parker, a step exact for
//! constant coefficients, evaluated at the step's midpoint), written for speed:
//!
//! - **the ray in grid coordinates**: a sample's lattice position is one multiply–add per axis from the ray's
//!   start, and where all eight trilinear corners lie inside the grid (nearly every sample) the corners are read
//!   straight from the dense arrays, x pairs at a time; samples near the faces (and nearest-neighbour datasets)
//!   take the general stencil, which fades to zero outside;
//! - **the channels as `C` lanes** (a const generic: 1 for rgb, 4 for 30 spectral bins), so radiance,
//!   transmittance and σ per unit density stay in registers for the whole ray;
//! - **a thin step without the exponential**: when a bound on the sample's largest optical depth is below 0.1
//!   (almost every step of a flame), e^{−τ} = 1 − τ·g with g = (1 − e^{−τ})/τ from its series — one polynomial
//!   instead of the exponential, the series and a division; the full step otherwise;
//! - **empty bricks jumped over** in one step count, not stepped through;
//! - **fused multiply–adds** where the CPU has them (`F`, set by the AVX2 + FMA clone).
//!
//! Accuracy (tests, docs/RESULTS.md): the same image as the f64 march to the lanes' f32 rounding.

use super::integrate::{Medium, Span, MAX_STEPS};
use super::lanes::{Lane, LaneTables, MAX_SPECIES, W};
use super::{FireVolume, Ray, TTable, EVALUATIONS};
use crate::grid::Interpolation;

/// a·b + c, fused when `F` (inlined into the FMA clone, a single instruction; without FMA `mul_add` would be a
/// library call, so the plain product and sum).
#[inline(always)]
fn fma<const F: bool>(a: f32, b: f32, c: f32) -> f32 {
    if F {
        a.mul_add(b, c)
    } else {
        a * b + c
    }
}

/// ⌊x⌋ for the lattice coordinates the interior test has bounded: the rounding instruction when the clone has
/// SSE4.1 (the FMA clone), else [`crate::grid::floor`] (no libm call).
#[inline(always)]
fn floor<const F: bool>(x: f64) -> f64 {
    if F {
        x.floor()
    } else {
        crate::grid::floor(x)
    }
}

/// A non-negative integer-valued `x` below 2⁵² as usize, exactly, in three instructions: adding 2⁵² leaves the
/// integer in the low mantissa bits (a float→int cast costs a dozen, for its saturation and NaN handling).
#[inline(always)]
fn index(x: f64) -> usize {
    const TWO52: f64 = 4_503_599_627_370_496.0;
    ((x + TWO52).to_bits() - TWO52.to_bits()) as usize
}

/// a + t·(b − a).
#[inline(always)]
fn lerp<const F: bool>(t: f32, a: f32, b: f32) -> f32 {
    fma::<F>(t, b - a, a)
}

/// Where a sample's trilinear cell lies in the dense arrays: the lower corner's index, the y and z strides,
/// and the fractions toward the upper corner.
#[derive(Clone, Copy)]
struct Cell {
    i: usize,
    sy: usize,
    sz: usize,
    f: [f32; 3],
}

/// Trilinear interpolation of `data` in `cell` (all eight corners inside), in pbrt-v4's order (x, then y, then
/// z). `None` only if the index is out of range, which the interior test excludes. (Functions, not closures:
/// a closure would not inherit the FMA clone's target features.)
#[inline(always)]
fn trilinear<const F: bool>(data: &[f32], c: Cell) -> Option<f32> {
    let Cell { i, sy, sz, f } = c;
    // One range check for the cell's block; the eight reads below are then within it.
    let s = data.get(i..)?.get(..sz + sy + 2)?;
    let (a, b) = (sz, sz + sy);
    let y0 = lerp::<F>(
        f[1],
        lerp::<F>(f[0], s[0], s[1]),
        lerp::<F>(f[0], s[sy], s[sy + 1]),
    );
    let y1 = lerp::<F>(
        f[1],
        lerp::<F>(f[0], s[a], s[a + 1]),
        lerp::<F>(f[0], s[b], s[b + 1]),
    );
    Some(lerp::<F>(f[2], y0, y1))
}

/// The grid values the march reads at a sample (after the clamps of `FireVolume::lane_step`).
#[derive(Clone, Copy, Default)]
struct Values {
    d: f32,
    t: f32,
    les: f32,
    n: [f32; MAX_SPECIES],
}

/// Where a sample's values came from.
#[derive(PartialEq)]
enum Lookup {
    /// Read (into the `Values`).
    Found,
    /// Outside the grid (or an index out of range, which the interior test excludes): no medium.
    Outside,
    /// Not in the interior: the general stencil decides.
    General,
}

/// The sample at lattice position `g` (pbrt-v4's p·n − 0.5) into `x`, when its cell lies inside the grid
/// (`lim` = n − 1 per axis, or −1 to refuse every point). (The values are written in place: returning them
/// by value cost a store-forwarding stall per sample.)
#[inline(always)]
fn interior<const F: bool>(v: &FireVolume, g: [f64; 3], lim: [f64; 3], x: &mut Values) -> Lookup {
    let inside = g[0] >= 0.0
        && g[0] < lim[0]
        && g[1] >= 0.0
        && g[1] < lim[1]
        && g[2] >= 0.0
        && g[2] < lim[2];
    if !inside {
        return Lookup::General;
    }
    let ch = v.ds.channels();
    let [nx, ny, _] = v.ds.dims();
    let c = [floor::<F>(g[0]), floor::<F>(g[1]), floor::<F>(g[2])];
    // The index in f64 (exact below 2⁵²; the interior test bounds it by the grid's size) and one conversion.
    let (fx, fy) = (nx as f64, (nx * ny) as f64);
    let cell = Cell {
        i: index(c[0] + fx * c[1] + fy * c[2]),
        sy: nx,
        sz: nx * ny,
        f: [
            (g[0] - c[0]) as f32,
            (g[1] - c[1]) as f32,
            (g[2] - c[2]) as f32,
        ],
    };
    let Some(d) = trilinear::<F>(ch[v.density].grid.data(), cell) else {
        return Lookup::Outside;
    };
    x.d = d.max(0.0);
    x.t = 0.0;
    if let Some(k) = v.temperature {
        let Some(t) = trilinear::<F>(ch[k].grid.data(), cell) else {
            return Lookup::Outside;
        };
        x.t = t;
    }
    x.les = 1.0;
    if let Some(k) = v.lescale {
        let Some(les) = trilinear::<F>(ch[k].grid.data(), cell) else {
            return Lookup::Outside;
        };
        x.les = les.max(0.0);
    }
    for (s, sp) in v.species.iter().enumerate() {
        let Some(n) = trilinear::<F>(ch[sp.ch].grid.data(), cell) else {
            return Lookup::Outside;
        };
        x.n[s] = (n.max(0.0) as f64 * sp.scale) as f32;
    }
    Lookup::Found
}

/// The sample at medium-space point `p` into `x` by the general stencil (near the faces, where it fades to
/// zero, and for nearest lookups).
#[inline(never)]
fn general(v: &FireVolume, p: glam::DVec3, x: &mut Values) -> Lookup {
    let Some(st) = v.ds.stencil_with_margin(p, v.margin) else {
        return Lookup::Outside;
    };
    let ch = v.ds.channels();
    let at = |k: usize| ch[k].grid.eval(&st);
    for (k, sp) in v.species.iter().enumerate() {
        x.n[k] = (at(sp.ch).max(0.0) as f64 * sp.scale) as f32;
    }
    x.d = at(v.density).max(0.0);
    x.t = v.temperature.map_or(0.0, at);
    x.les = v.lescale.map_or(1.0, |k| at(k).max(0.0));
    Lookup::Found
}

/// The two rows of `tab` around T and the fraction between them (as `TTable::lane_rows`, with one multiply
/// and one float→int conversion); `None` only if the table has not `C` lanes per row.
#[inline(always)]
fn rows<const C: usize, const F: bool>(
    tab: &TTable,
    t: f32,
) -> Option<(&[Lane; C], &[Lane; C], f32)> {
    let last = (tab.rows - 1) as f64;
    let f = (t as f64 * tab.inv_dt).max(0.0).min(last);
    let i = floor::<F>(f).min(last - 1.0);
    let at = index(i) * C;
    let (a, b) = tab.v.get(at..at + 2 * C)?.split_at(C);
    Some((a.try_into().ok()?, b.try_into().ok()?, (f - i) as f32))
}

/// Samples whose grid values are read before they are stepped through.
const BATCH: usize = 8;

/// A step's optical depth below which the thin step (no exponential) is taken.
const THIN: f32 = 0.1;

/// The straight march of `ray` through `v` in `C` lanes (`C` = `lt.chunks()`, checked by the caller; any other
/// count returns `None`). Fills `l` and `t`; returns the exit parameter.
#[inline(always)]
pub(super) fn march<const C: usize, const F: bool>(
    v: &FireVolume,
    lt: &LaneTables,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> Option<f64> {
    if C > 4 {
        return None; // (the lanes below are written out for up to four)
    }
    let sigma: &[Lane; C] = lt.sigma().try_into().ok()?;
    l.fill(0.0);
    t.fill(1.0);
    let Some(span) = Span::new(v, ray) else {
        return Some(ray.t1);
    };
    let len = (span.b - span.a) * span.speed;
    let mut ds = v.step;
    if !(ds > 0.0) || len / ds > MAX_STEPS {
        ds = len / MAX_STEPS;
    }
    let mut rng = crate::rng::Rng::new(ray.seed);
    let mut first = rng.next_f64() * ds;
    if first <= 0.0 {
        first = ds;
    }
    // Empty stretches (arc length from the entry), as `march_steps` finds them.
    let mut empty: Vec<(f64, f64)> = Vec::new();
    v.empty_spans(ray.o, ray.d, span.a, span.b, &mut |ta, tb| {
        empty.push(((ta - span.a) * span.speed, (tb - span.a) * span.speed))
    });
    // The ray in lattice coordinates g = unit·n − 0.5 as a function of arc length s: g0 + s·gd.
    let dims = v.ds.dims().map(|n| n as f64);
    let [b0, b1] = v.ds.bounds();
    let size = b1 - b0;
    let entry = ray.o + ray.d * span.a;
    let dir = ray.d / span.speed;
    let g0 = [0, 1, 2].map(|a| (entry[a] - b0[a]) / size[a] * dims[a] - 0.5);
    let gd = [0, 1, 2].map(|a| dir[a] / size[a] * dims[a]);
    let lim = if v.ds.interpolation() == Interpolation::Trilinear {
        dims.map(|n| n - 1.0)
    } else {
        [-1.0; 3]
    };
    let c = l.len();
    let mut lk = [[0f32; W]; C];
    // (Padding lanes hold transmittance 0, so they never keep the early termination from stopping.)
    let mut tk = [[0f32; W]; C];
    for ch in 0..c {
        tk[ch / W][ch % W] = 1.0;
    }
    let cutoff = v.cutoff as f32;
    let sp_max = lt.species_sigma_max();
    let sigma_max = lt.sigma_max();
    let ns = v.species.len().min(MAX_SPECIES);
    let no_temperature = v.temperature.is_none();
    let mut samples = 0u64;
    let (mut k, mut e) = (0u64, 0usize);
    let mut batch = [(Values::default(), 0f32); BATCH];
    'ray: loop {
        // Gather the grid values of the next BATCH samples that hold something (their lookups are
        // independent, so the CPU overlaps their loads), then step through them in order.
        let mut nb = 0;
        let mut end = false;
        while nb < BATCH {
            let s0 = if k == 0 {
                0.0
            } else {
                first + (k - 1) as f64 * ds
            };
            if !(s0 < len) {
                end = true;
                break;
            }
            let s1 = (first + k as f64 * ds).min(len);
            let mid = 0.5 * (s0 + s1);
            while e < empty.len() && empty[e].1 <= mid {
                e += 1;
            }
            if e < empty.len() && empty[e].0 <= mid {
                // The first step whose midpoint (first + (k − ½)·ds for a whole step) is past this stretch.
                let past = ((empty[e].1 - first) / ds + 0.5).ceil();
                k = (k + 1).max(if past < MAX_STEPS {
                    past as u64
                } else {
                    u64::MAX
                });
                continue;
            }
            k += 1;
            let g = [
                g0[0] + mid * gd[0],
                g0[1] + mid * gd[1],
                g0[2] + mid * gd[2],
            ];
            let (x, delta) = &mut batch[nb];
            let mut found = interior::<F>(v, g, lim, x);
            if found == Lookup::General {
                found = general(v, ray.o + ray.d * (span.a + mid / span.speed), x);
            }
            if found == Lookup::Outside {
                continue;
            }
            samples += 1;
            // No soot and no species: σ = j = 0, the step would add +0 and multiply by 1 (skipped, bit for
            // bit).
            let mut nothing = x.d == 0.0;
            for s in 0..ns {
                nothing &= x.n[s] == 0.0;
            }
            if !nothing {
                *delta = (s1 - s0) as f32;
                nb += 1;
            }
        }
        for (x, delta) in batch.iter().take(nb) {
            let delta = *delta;
            let emits = no_temperature || x.t as f64 > v.t_emit;
            let dl = if emits { x.d * x.les } else { 0.0 };
            // The table rows at the sample's temperature (as `LaneTables::coefficients`) and a bound on its optical
            // depth, which picks the step.
            let (j0, j1, fr) = rows::<C, F>(&v.j, x.t)?;
            let mut at: Option<(&[Lane; C], &[Lane; C], f32)> = None;
            if let Some(tab) = &v.a_t {
                at = Some(rows::<C, F>(tab, x.t)?);
            }
            let mut bound = x.d * sigma_max;
            let mut sp_rows: [Option<SpeciesRows<C>>; MAX_SPECIES] = [None; MAX_SPECIES];
            for s in 0..ns {
                let n = x.n[s];
                if n > 0.0 {
                    let sp = &v.species[s];
                    bound += n * sp_max[s];
                    let (s0, s1, f) = rows::<C, F>(&sp.sigma, x.t)?;
                    let (e0, e1, _) = rows::<C, F>(&sp.j, x.t)?;
                    sp_rows[s] = Some(SpeciesRows {
                        n,
                        f,
                        s0,
                        s1,
                        e0,
                        e1,
                    });
                }
            }
            let thin = bound * delta < THIN;
            let co = Coefficients {
                d: x.d,
                dl,
                sigma,
                j: (j0, j1, fr),
                at,
                species: &sp_rows[..ns],
                delta,
                thin,
            };
            let mut tmax = [0f32; W];
            // Lane by lane, each written out (a loop over q kept the lanes in memory; with constant indices
            // radiance and transmittance stay in registers).
            macro_rules! lane {
                ($q:literal) => {
                    if $q < C {
                        if let (Some(l), Some(t)) = (lk.get_mut($q), tk.get_mut($q)) {
                            co.step::<F>($q, l, t, &mut tmax);
                        }
                    }
                };
            }
            lane!(0);
            lane!(1);
            lane!(2);
            lane!(3);
            if horizontal_max(tmax) < cutoff {
                break 'ray;
            }
        }
        if end {
            break;
        }
    }
    EVALUATIONS.with(|n| n.set(n.get() + samples));
    for ch in 0..c {
        l[ch] = lk[ch / W][ch % W] as f64;
        t[ch] = tk[ch / W][ch % W] as f64;
    }
    Some(span.b)
}

/// The largest of a lane's values, as a tree of halves (vector shuffles, not eight scalar steps).
#[inline(always)]
fn horizontal_max(x: Lane) -> f32 {
    let mut h = x;
    let mut n = W / 2;
    while n > 0 {
        for w in 0..n {
            h[w] = if h[w + n] > h[w] { h[w + n] } else { h[w] };
        }
        n /= 2;
    }
    h[0]
}

/// A sample's coefficients, ready for each lane's step.
struct Coefficients<'a, const C: usize> {
    d: f32,
    /// Density times the emission scale (0 where it does not emit).
    dl: f32,
    sigma: &'a [Lane; C],
    /// Emission rows and the fraction between them.
    j: (&'a [Lane; C], &'a [Lane; C], f32),
    /// σ_a rows where σ_a depends on T.
    at: Option<(&'a [Lane; C], &'a [Lane; C], f32)>,
    species: &'a [Option<SpeciesRows<'a, C>>],
    delta: f32,
    thin: bool,
}

impl<const C: usize> Coefficients<'_, C> {
    /// σ_t and j in lane `q`, then its step; `tmax` keeps the largest transmittance per lane position.
    #[inline(always)]
    fn step<const F: bool>(&self, q: usize, l: &mut Lane, t: &mut Lane, tmax: &mut Lane) {
        let (j0, j1, fr) = self.j;
        let mut sg = [0f32; W];
        let mut jq = [0f32; W];
        for w in 0..W {
            sg[w] = self.d * self.sigma[q][w];
            jq[w] = self.dl * lerp::<F>(fr, j0[q][w], j1[q][w]);
        }
        if let Some((a0, a1, fa)) = self.at {
            for w in 0..W {
                sg[w] = fma::<F>(self.d, lerp::<F>(fa, a0[q][w], a1[q][w]), sg[w]);
            }
        }
        for r in self.species.iter().flatten() {
            for w in 0..W {
                sg[w] = fma::<F>(r.n, lerp::<F>(r.f, r.s0[q][w], r.s1[q][w]), sg[w]);
                jq[w] = fma::<F>(r.n, lerp::<F>(r.f, r.e0[q][w], r.e1[q][w]), jq[w]);
            }
        }
        if self.thin {
            thin_step::<F>(&sg, &jq, self.delta, l, t);
        } else {
            full_step::<F>(&sg, &jq, self.delta, l, t);
        }
        for w in 0..W {
            tmax[w] = if t[w] > tmax[w] { t[w] } else { tmax[w] };
        }
    }
}

/// One species' table rows at a sample: its number density, the fraction between the rows, σ and j rows.
#[derive(Clone, Copy)]
struct SpeciesRows<'a, const C: usize> {
    n: f32,
    f: f32,
    s0: &'a [Lane; C],
    s1: &'a [Lane; C],
    e0: &'a [Lane; C],
    e1: &'a [Lane; C],
}

/// One step of one lane where every τ = σ·δ < 0.1: g = (1 − e^{−τ})/τ by its series to τ⁴ (remainder
/// τ⁵/720 < 1.4e-8) and e^{−τ} = 1 − τ·g (within 1.4e-9 plus rounding).
#[inline(always)]
fn thin_step<const F: bool>(sig: &Lane, jj: &Lane, delta: f32, l: &mut Lane, t: &mut Lane) {
    for w in 0..W {
        let tau = sig[w] * delta;
        // 1 − τ(½ − τ(⅙ − τ(1/24 − τ/120))), the signs folded into −τ.
        let g = fma::<F>(-tau, 1.0 / 120.0, 1.0 / 24.0);
        let g = fma::<F>(-tau, g, 1.0 / 6.0);
        let g = fma::<F>(-tau, g, 0.5);
        let g = fma::<F>(-tau, g, 1.0);
        l[w] = fma::<F>(t[w] * jj[w], delta * g, l[w]);
        t[w] *= fma::<F>(-tau, g, 1.0);
    }
}

/// One step of one lane for any τ (as [`super::lanes::step`]).
#[inline(always)]
fn full_step<const F: bool>(sig: &Lane, jj: &Lane, delta: f32, l: &mut Lane, t: &mut Lane) {
    for w in 0..W {
        let tau = sig[w] * delta;
        let e = super::lanes::exp_neg(-tau);
        let series = 1.0
            - tau
                * (0.5
                    - tau * (1.0 / 6.0 - tau * (1.0 / 24.0 - tau * (1.0 / 120.0 - tau / 720.0))));
        let quot = (1.0 - e) / tau.max(THIN);
        let thin = 0u32.wrapping_sub((tau < THIN) as u32);
        let g = f32::from_bits((series.to_bits() & thin) | (quot.to_bits() & !thin));
        l[w] = fma::<F>(t[w] * jj[w], delta * g, l[w]);
        t[w] *= e;
    }
}
