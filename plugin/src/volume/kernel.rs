//! The straight march's kernel: the f32 lane march of [`super::lanes`] with its per-ray state in registers.
//!
//! The same steps at the same points as `integrate::march_steps` (eq. 3 of Pegoraro & Parker, a step exact for
//! constant coefficients, evaluated at the step's midpoint), written for speed:
//!
//! - **the ray in grid coordinates, eight samples at a time**: the next eight steps outside empty bricks are
//!   looked up together — lattice positions (one multiply–add per axis from the ray's entry), cells, weights
//!   and the trilinear interpolation in vector arithmetic across the eight, the corner reads straight from the
//!   dense arrays, and the loads of eight independent samples overlapped by the CPU; samples whose cell is not
//!   inside the grid (near the faces, where pbrt-v4's lookup fades to zero) and nearest-neighbour datasets take
//!   the general stencil;
//! - **the channels as `C` lanes** (a const generic: 1 for rgb, 4 for 30 spectral bins), so radiance,
//!   transmittance and σ per unit density stay in registers for the whole ray;
//! - **a thin step without the exponential**: when a bound on the sample's largest optical depth is below 0.1
//!   (almost every step of a flame), e^{−τ} = 1 − τ·g with g = (1 − e^{−τ})/τ from its series — one polynomial
//!   instead of the exponential, the series and a division; the full step otherwise;
//! - **empty bricks jumped over** in one step count, not stepped through;
//! - **fused multiply–adds** where the CPU has them (`F`, set by the AVX2 + FMA clone).
//!
//! Accuracy (tests, docs/RESULTS.md): the same image as the f64 march to the lanes' f32 rounding.

use super::integrate::{Span, MAX_STEPS};
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

/// ⌊x⌋ of a lattice coordinate: the rounding instruction when the clone has SSE4.1 (the FMA clone), else
/// [`crate::grid::floor`] (no libm call).
#[inline(always)]
fn floor<const F: bool>(x: f64) -> f64 {
    if F {
        x.floor()
    } else {
        crate::grid::floor(x)
    }
}

/// A non-negative integer-valued `x` below 2⁵² as usize, exactly, in three instructions: adding 2⁵² leaves the
/// integer in the low mantissa bits (a float→int cast costs a dozen, for its saturation and NaN handling). Any
/// other `x` gives a meaningless index (never a panic), which callers do not use.
#[inline(always)]
fn index(x: f64) -> usize {
    const TWO52: f64 = 4_503_599_627_370_496.0;
    (x + TWO52).to_bits().wrapping_sub(TWO52.to_bits()) as usize
}

/// a + t·(b − a).
#[inline(always)]
fn lerp<const F: bool>(t: f32, a: f32, b: f32) -> f32 {
    fma::<F>(t, b - a, a)
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
    /// Outside the grid: no medium.
    Outside,
}

/// The most grids a sample reads: density, temperature, Lescale and the species.
const MAX_GRIDS: usize = 3 + MAX_SPECIES;

/// The grids the kernel reads, in the order density, temperature, Lescale, species (those the volume has).
struct Grids<'a> {
    data: [&'a [f32]; MAX_GRIDS],
    n: usize,
    temperature: Option<usize>,
    lescale: Option<usize>,
    species: usize,
}

impl<'a> Grids<'a> {
    fn new(v: &'a FireVolume) -> Grids<'a> {
        let ch = v.ds.channels();
        let mut g = Grids {
            data: [&[]; MAX_GRIDS],
            n: 0,
            temperature: None,
            lescale: None,
            species: 0,
        };
        let push = |g: &mut Grids<'a>, k: usize| {
            g.data[g.n] = ch[k].grid.data();
            g.n += 1;
            g.n - 1
        };
        push(&mut g, v.density);
        if let Some(k) = v.temperature {
            g.temperature = Some(push(&mut g, k));
        }
        if let Some(k) = v.lescale {
            g.lescale = Some(push(&mut g, k));
        }
        g.species = g.n;
        for sp in v.species.iter().take(MAX_SPECIES) {
            push(&mut g, sp.ch);
        }
        g
    }
}

/// The grid values at a block of samples (lattice positions g0 + mids·gd), each grid interpolated for all
/// of them at once (positions, cells and the trilinear weights in vector arithmetic; the eight corner reads
/// per sample and grid stay scalar). `inside[b]` is false where sample b's cell is not in the interior
/// (`lim`), or its index out of range: the general stencil takes those.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn lookup_block<const F: bool>(
    grids: &Grids,
    dims: [usize; 3],
    mids: &[f64; BATCH],
    g0: [f64; 3],
    gd: [f64; 3],
    lim: [f64; 3],
    vals: &mut [[f32; BATCH]; MAX_GRIDS],
    inside: &mut [bool; BATCH],
) {
    let (sy, sz) = (dims[0], dims[0] * dims[1]);
    let (fy, fz) = (sy as f64, sz as f64);
    let mut idx = [0usize; BATCH];
    let mut f = [[0f32; BATCH]; 3];
    for b in 0..BATCH {
        let g = [
            g0[0] + mids[b] * gd[0],
            g0[1] + mids[b] * gd[1],
            g0[2] + mids[b] * gd[2],
        ];
        inside[b] = (g[0] >= 0.0)
            & (g[0] < lim[0])
            & (g[1] >= 0.0)
            & (g[1] < lim[1])
            & (g[2] >= 0.0)
            & (g[2] < lim[2]);
        let c = [floor::<F>(g[0]), floor::<F>(g[1]), floor::<F>(g[2])];
        // (Outside the interior the index is meaningless, and unused.)
        idx[b] = index(c[0] + fy * c[1] + fz * c[2]);
        for a in 0..3 {
            f[a][b] = (g[a] - c[a]) as f32;
        }
    }
    for (k, data) in grids.data.iter().take(grids.n).enumerate() {
        let mut c = [[0f32; BATCH]; 8];
        for b in 0..BATCH {
            if !inside[b] {
                continue;
            }
            let Some(s) = data.get(idx[b]..).and_then(|s| s.get(..sz + sy + 2)) else {
                inside[b] = false;
                continue;
            };
            let (y, z, yz) = (sy, sz, sz + sy);
            [c[0][b], c[1][b], c[2][b], c[3][b]] = [s[0], s[1], s[y], s[y + 1]];
            [c[4][b], c[5][b], c[6][b], c[7][b]] = [s[z], s[z + 1], s[yz], s[yz + 1]];
        }
        for b in 0..BATCH {
            let [fx, fy, fz] = [f[0][b], f[1][b], f[2][b]];
            let y0 = lerp::<F>(
                fy,
                lerp::<F>(fx, c[0][b], c[1][b]),
                lerp::<F>(fx, c[2][b], c[3][b]),
            );
            let y1 = lerp::<F>(
                fy,
                lerp::<F>(fx, c[4][b], c[5][b]),
                lerp::<F>(fx, c[6][b], c[7][b]),
            );
            vals[k][b] = lerp::<F>(fz, y0, y1);
        }
    }
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
    // Empty stretches (arc length from the entry): the bricks `empty_spans` reports, walked here directly and
    // adjacent ones merged (fewer stretches to test, no call per brick).
    let mut empty: Vec<(f64, f64)> = Vec::new();
    for seg in v.majorant.segments(ray.o, ray.d, span.a, span.b) {
        if !v.brick_empty[seg.brick] {
            continue;
        }
        let (a, b) = ((seg.t0 - span.a) * span.speed, (seg.t1 - span.a) * span.speed);
        match empty.last_mut() {
            Some(last) if last.1 == a => last.1 = b,
            _ => empty.push((a, b)),
        }
    }
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
    let grids = Grids::new(v);
    let dims_n = v.ds.dims();
    let (mut k, mut e) = (0u64, 0usize);
    let mut batch = [(Values::default(), 0f32); BATCH];
    'ray: loop {
        // Gather the grid values of the next BATCH samples that hold something (their lookups are
        // independent, so the CPU overlaps their loads), then step through them in order.
        let mut m = 0;
        let mut end = false;
        let mut mids = [0f64; BATCH];
        let mut deltas = [0f32; BATCH];
        while m < BATCH {
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
            mids[m] = mid;
            deltas[m] = (s1 - s0) as f32;
            m += 1;
        }
        let mut vals = [[0f32; BATCH]; MAX_GRIDS];
        let mut inside = [false; BATCH];
        lookup_block::<F>(&grids, dims_n, &mids, g0, gd, lim, &mut vals, &mut inside);
        let mut nb = 0;
        for b in 0..m {
            let x = &mut batch[nb].0;
            if inside[b] {
                x.d = vals[0][b].max(0.0);
                x.t = grids.temperature.map_or(0.0, |k| vals[k][b]);
                x.les = grids.lescale.map_or(1.0, |k| vals[k][b].max(0.0));
                for (s, sp) in v.species.iter().take(ns).enumerate() {
                    x.n[s] = (vals[grids.species + s][b].max(0.0) as f64 * sp.scale) as f32;
                }
            } else {
                let p = ray.o + ray.d * (span.a + mids[b] / span.speed);
                if general(v, p, x) == Lookup::Outside {
                    continue;
                }
            }
            samples += 1;
            // No soot and no species: σ = j = 0, the step would add +0 and multiply by 1 (skipped, bit for
            // bit).
            let mut nothing = x.d == 0.0;
            for s in 0..ns {
                nothing &= x.n[s] == 0.0;
            }
            if !nothing {
                batch[nb].1 = deltas[b];
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
