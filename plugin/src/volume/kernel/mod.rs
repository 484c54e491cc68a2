//! The straight march's kernel: the f32 lane march of [`super::lanes`] with its per-ray state in registers.
//!
//! The same steps at the same points as `integrate::march_steps` (eq. 3 of Pegoraro & Parker, a step exact for
//! constant coefficients, evaluated at the step's midpoint), written for speed:
//!
//! - **24 samples at a time, in phases** (`BATCH`): the next 24 steps outside empty bricks (their
//!   midpoints; all at once when they are whole and before the next empty stretch), their cells and fractions (at once,
//!   in vector registers), then their grid values, read together from the [`Lattice`] (density and temperature interleaved and padded: a
//!   cell is four 16-byte reads under one range check, and the padding gives pbrt-v4's fade at the faces, so no
//!   sample inside the bounds needs the general stencil) — or, for a volume that keeps no lattice, from the
//!   dataset's own bricks in place ([`Stored`]: the same values in the same lerps, bit for bit) — then their table rows (located once for emission and
//!   T-dependent absorption), then the steps in order — independent reads first, which the CPU overlaps;
//! - **the channels as `C` lanes** (a const generic: 1 for rgb, 4 for 30 spectral bins), so radiance,
//!   transmittance and σ per unit density stay in registers for the whole ray;
//! - **a thin step without the exponential**: when a bound on the sample's largest optical depth is below 0.1
//!   (almost every step of a flame), e^{−τ} = 1 − τ·g with g = (1 − e^{−τ})/τ from its series — one polynomial
//!   instead of the exponential, the series and a division; the full step otherwise;
//! - **empty bricks jumped over** in one step count, not stepped through;
//! - **no code for what the volume lacks**: species (`S`) and T-dependent absorption (`A`) are const generics;
//! - **fused multiply–adds** where the CPU has them (`F`, set by the AVX2 + FMA and AVX-512 clones).
//!
//! Accuracy (tests, docs/results/log.md): the same image as the f64 march to the lanes' f32 rounding.

use super::integrate::{Span, EVALUATIONS};
use super::lanes::{Lane, LaneTables, MAX_SPECIES, W};
use super::lattice::Lattice;
use super::tables::TTable;
use super::{FireVolume, Ray};
use batch::{in_lanes, read_batch, species_rows, species_tables, OnRay};
use stored::Stored;
use walk::Walk;

mod batch;
mod stored;
mod walk;

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

/// The values of the further grids (Lescale, species) at a batch of samples (after the clamps of
/// `FireVolume::lane_step`; Lescale 1 where the volume has none).
struct Extras {
    les: [f32; BATCH],
    n: [[f32; BATCH]; MAX_SPECIES],
}

/// The lattice as one sample's lookup needs it: the arrays, the strides in floats between the x-pairs of a
/// cell's corners, and what the further grids hold.
struct Layout<'a> {
    pairs: &'a [f32],
    extra: &'a [Vec<f32>],
    /// Padded voxel strides along y and z.
    sy: usize,
    sz: usize,
    /// The padded linear index of cell (cx, cy, cz) is `off + cx + fy·cy + fz·cz` (fy, fz: the strides).
    off: f64,
    fy: f64,
    fz: f64,
    /// Largest linear index whose cell has all eight corners in the arrays (exclusive).
    cells: usize,
    /// Whether the first further grid is Lescale (the species follow it).
    lescale: bool,
    /// The brick layout's table, the offset of its bricks and the largest lower corner w = c + 1 (the
    /// dataset's dims) per axis.
    bricks: Option<(&'a crate::grid::Topology, [f64; 3], [f64; 3])>,
}

impl<'a> Layout<'a> {
    fn new(lat: &'a Lattice, lescale: bool, dims: [usize; 3]) -> Layout<'a> {
        let [px, py, pz] = lat.dims();
        let (sy, sz) = (px, px * py);
        let bricks = lat
            .bricks()
            .map(|t| (t, t.offset().map(|o| o as f64), dims.map(|n| n as f64)));
        Layout {
            pairs: lat.pairs(),
            extra: lat.extra(),
            sy,
            sz,
            off: (1 + sy + sz) as f64,
            fy: sy as f64,
            fz: sz as f64,
            cells: match bricks {
                Some(_) => lat.pairs().len() / 2,
                None => (px * py * pz).saturating_sub(sy + sz + 1),
            },
            lescale,
            bricks,
        }
    }
}

/// a + t·(b − a) on four values at once (written out: a closure, as in `array::map`, would not inherit the
/// clone's target features).
#[inline(always)]
fn lerp4<const F: bool>(t: f32, a: &[f32; 4], b: &[f32; 4]) -> [f32; 4] {
    [
        lerp::<F>(t, a[0], b[0]),
        lerp::<F>(t, a[1], b[1]),
        lerp::<F>(t, a[2], b[2]),
        lerp::<F>(t, a[3], b[3]),
    ]
}

/// Four values of `s` from `o` (`None` past its end: the caller takes the general stencil).
#[inline(always)]
fn quad(s: &[f32], o: usize) -> Option<&[f32; 4]> {
    s.get(o..o + 4)?.try_into().ok()
}

/// The trilinear value of one further grid `a` at cell `i` (strides `sy`, `sz`), fractions `f`.
#[inline(always)]
fn trilinear<const F: bool>(a: &[f32], i: usize, sy: usize, sz: usize, f: [f32; 3]) -> f32 {
    let Some(s) = a.get(i..i + sy + sz + 2) else {
        return 0.0;
    };
    let (z, zy) = (sz, sz + sy);
    let v = lerp4::<F>(
        f[0],
        &[s[0], s[sy], s[z], s[zy]],
        &[s[1], s[sy + 1], s[z + 1], s[zy + 1]],
    );
    lerp::<F>(
        f[2],
        lerp::<F>(f[1], v[0], v[1]),
        lerp::<F>(f[1], v[2], v[3]),
    )
}

/// The cell of lattice point `g` (the dataset's lattice coordinates: voxel centres at integers, the bounds at
/// −½ and n − ½): its lower corner's padded index (at least `lay.cells`, or meaningless, when the cell is not in
/// the lattice) and the fractions within it.
#[inline(always)]
fn cell<const F: bool>(lay: &Layout, g: [f64; 3]) -> (usize, [f32; 3]) {
    let c = [floor::<F>(g[0]), floor::<F>(g[1]), floor::<F>(g[2])];
    let i = index(lay.off + c[0] + lay.fy * c[1] + lay.fz * c[2]);
    (
        i,
        [
            (g[0] - c[0]) as f32,
            (g[1] - c[1]) as f32,
            (g[2] - c[2]) as f32,
        ],
    )
}

/// [`cell`] for the brick layout: the cell's lower corner c, as w = c + 1 ∈ [0, n], locates its copy in the
/// table (copy 0, the background, when its bricks are empty) and its place in the copy; `usize::MAX` when the
/// cell is beyond the lattice's margin (or `g` is NaN).
#[inline(always)]
fn cell_in_bricks<const F: bool>(
    topo: &crate::grid::Topology,
    off: [f64; 3],
    n: [f64; 3],
    g: [f64; 3],
) -> (usize, [f32; 3]) {
    use super::lattice::{PADDED, PADDED_VOXELS};
    let c = [floor::<F>(g[0]), floor::<F>(g[1]), floor::<F>(g[2])];
    let f = [
        (g[0] - c[0]) as f32,
        (g[1] - c[1]) as f32,
        (g[2] - c[2]) as f32,
    ];
    let w = [c[0] + 1.0, c[1] + 1.0, c[2] + 1.0];
    let inside = (0..3).all(|a| w[a] >= 0.0 && w[a] <= n[a]);
    if !inside {
        return (usize::MAX, f);
    }
    let u = [
        index(w[0] + off[0]),
        index(w[1] + off[1]),
        index(w[2] + off[2]),
    ];
    let b = [
        u[0] / crate::grid::BRICK,
        u[1] / crate::grid::BRICK,
        u[2] / crate::grid::BRICK,
    ];
    let l = (u[0] % crate::grid::BRICK)
        + PADDED * ((u[1] % crate::grid::BRICK) + PADDED * (u[2] % crate::grid::BRICK));
    (topo.slot(b) * PADDED_VOXELS + l, f)
}

/// The cells and fractions of a batch's `m` samples at arc lengths `mids` along the ray g0 + s·gd (lattice
/// coordinates) into `ci` and `fx`: for the dense layout all `BATCH` at once, a loop without exits that
/// vectorises (those past `m` are not read).
#[inline(always)]
fn march_cells<const F: bool>(
    lay: &Layout,
    g0: [f64; 3],
    gd: [f64; 3],
    mids: &[f64; BATCH],
    m: usize,
    ci: &mut [usize; BATCH],
    fx: &mut [[f32; BATCH]; 3],
) {
    match lay.bricks {
        None => {
            for b in 0..BATCH {
                let g = [
                    g0[0] + mids[b] * gd[0],
                    g0[1] + mids[b] * gd[1],
                    g0[2] + mids[b] * gd[2],
                ];
                let (i, f) = cell::<F>(lay, g);
                ci[b] = i;
                fx[0][b] = f[0];
                fx[1][b] = f[1];
                fx[2][b] = f[2];
            }
        }
        Some((topo, off, n)) => {
            for b in 0..m {
                let g = [
                    g0[0] + mids[b] * gd[0],
                    g0[1] + mids[b] * gd[1],
                    g0[2] + mids[b] * gd[2],
                ];
                let (i, f) = cell_in_bricks::<F>(topo, off, n, g);
                ci[b] = i;
                fx[0][b] = f[0];
                fx[1][b] = f[1];
                fx[2][b] = f[2];
            }
        }
    }
}

/// Sample `b` of a batch in cell `i` at fractions `f` (from [`cell`]) into `d`, `t` and `x`, trilinearly from
/// the padded lattice; false when the cell is not in the lattice (the general stencil takes it). Species values
/// are scaled by `scales`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn read<const F: bool>(
    lay: &Layout,
    i: usize,
    f: [f32; 3],
    scales: &[f64],
    b: usize,
    dt: &mut [[f32; 2]; BATCH],
    x: &mut Extras,
) -> bool {
    if i >= lay.cells {
        return false;
    }
    // Offsets in floats, each below 2³² (the lattice holds fewer floats, `Lattice::build`), so that their sums
    // cannot wrap and one range check covers the four reads.
    let (o, oy, oz) = (
        2 * (i as u32 as usize),
        2 * (lay.sy as u32 as usize),
        2 * (lay.sz as u32 as usize),
    );
    let Some(s) = lay.pairs.get(o..o + oy + oz + 4) else {
        return false;
    };
    // [d, T] at x and x + 1, at the cell's four (y, z) corners: four 16-byte reads.
    let (Some(q00), Some(q10), Some(q01), Some(q11)) =
        (quad(s, 0), quad(s, oy), quad(s, oz), quad(s, oy + oz))
    else {
        return false;
    };
    let z0 = lerp4::<F>(f[1], q00, q10);
    let z1 = lerp4::<F>(f[1], q01, q11);
    let v = lerp4::<F>(f[2], &z0, &z1);
    // Along x, [d, T] toward the x + 1 pair, still four wide (the swapped half is not used).
    let r = lerp4::<F>(f[0], &v, &[v[2], v[3], v[0], v[1]]);
    // (Stored side by side and unclamped: the vectoriser builds the lerps above from this pair of stores.)
    dt[b] = [r[0], r[1]];
    if !lay.extra.is_empty() {
        let mut e = 0;
        if lay.lescale {
            x.les[b] = trilinear::<F>(&lay.extra[0], i, lay.sy, lay.sz, f).max(0.0);
            e = 1;
        }
        for (k, (a, &scale)) in lay.extra[e..].iter().zip(scales).enumerate() {
            x.n[k][b] = (trilinear::<F>(a, i, lay.sy, lay.sz, f).max(0.0) as f64 * scale) as f32;
        }
    }
    true
}

/// Sample `b` at medium-space point `p` by the general stencil (any point whose cell is not in the lattice);
/// d = −1 where `p` is outside the medium.
#[cold]
#[inline(never)]
fn general(v: &FireVolume, p: glam::DVec3, b: usize, dt: &mut [[f32; 2]; BATCH], x: &mut Extras) {
    let Some(st) = v.grids.ds().stencil_with_margin(p, v.bounds.margin()) else {
        dt[b] = [OUTSIDE, 0.0];
        return;
    };
    let ch = v.grids.ds().channels();
    let at = |k: usize| ch[k].grid.eval(&st);
    for (k, sp) in v.grids.species().iter().take(MAX_SPECIES).enumerate() {
        x.n[k][b] = (at(sp.ch()).max(0.0) as f64 * sp.scale()) as f32;
    }
    dt[b] = [at(v.grids.density()), v.grids.temperature().map_or(0.0, at)];
    x.les[b] = v.grids.lescale().map_or(1.0, |k| at(k).max(0.0));
}

/// The density that marks a sample outside the medium (not counted; real densities are ≥ 0, or a rounding
/// below it).
const OUTSIDE: f32 = -1.0;

/// Samples whose grid values are read before they are stepped through: more reads in flight, less per-batch
/// bookkeeping per sample. Measured (docs/results/log.md, session 8): 8 → 16 took a sample from 17.2 to 14.0 ns at 16
/// bins (rgb 17.8 → 14.4, 30 bins 21.8 → 18.3); 24 is a further 5–10 % below 16; 32 is slower than 24.
const BATCH: usize = 24;

/// A step's optical depth below which the thin step (no exponential) is taken.
const THIN: f32 = 0.1;

/// The channels a march computes: the emission table's columns and σ per unit density — the volume's own
/// (`LaneTables`), or a few of them (the fire light's line in fewer channels, [`super::subset`]).
#[derive(Clone, Copy)]
pub(super) struct Tabs<'a> {
    j: &'a TTable,
    sigma: &'a [Lane],
    /// A step thicker than this is split ([`super::integrate::split_step`]): the volume's `steptau` for its own
    /// march, ∞ for estimates checked against it (the fire light's line, its channel subsets).
    split_tau: f32,
}

impl<'a> Tabs<'a> {
    /// A few of the channels (`j`'s columns and their σ per unit density), their steps never split: an estimate
    /// checked against the volume's own march (the fire light's line in a subset of the bins).
    pub(super) fn subset(j: &'a TTable, sigma: &'a [Lane]) -> Tabs<'a> {
        Tabs {
            j,
            sigma,
            split_tau: f32::INFINITY,
        }
    }

    /// The volume's own channels; `split`: its thick steps split as its own march splits them.
    pub(super) fn own(v: &'a FireVolume, lt: &'a LaneTables, split: bool) -> Tabs<'a> {
        Tabs {
            j: v.model.j(),
            sigma: lt.sigma(),
            split_tau: if split {
                v.estimator.step_tau() as f32
            } else {
                f32::INFINITY
            },
        }
    }
}

/// The straight march of `ray` through `v` in `CV` lanes of `V` channels (at most 4 lanes holding the `l.len()`
/// channels of `tabs`; else, or for a volume without a lattice, `None`). `S`: the volume has species (their rows
/// are looked up per sample; without, that code is not compiled in); `A`: σ_a depends on T (`a_t`, rgb physical
/// mode). `step`: the march's step, metres (the volume's own, or the fire light's coarser one). Fills `l` and `t`;
/// returns the exit parameter. (The thin-step test bounds the optical depth by the volume's largest σ whichever
/// channels are marched, so a subset's channels take the very steps the whole set takes.)
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub(super) fn march<
    const CV: usize,
    const V: usize,
    const S: bool,
    const A: bool,
    const F: bool,
>(
    v: &FireVolume,
    lt: &LaneTables,
    tabs: Tabs,
    ray: &Ray,
    step: f64,
    l: &mut [f64],
    t: &mut [f64],
) -> Option<f64> {
    let c = l.len();
    if CV > 4 || CV * V < c || S == v.grids.species().is_empty() || A != v.model.a_t().is_some() {
        return None; // (the lanes below are written out for up to four)
    }
    // The lattice, else the dataset's grids themselves (the same values, read in place).
    let lat = v.estimator.lattice().get(v.grids.ds());
    let stored = match lat {
        Some(_) => None,
        None => Some(Stored::new(v)?),
    };
    // σ per unit density in the kernel's lanes (channels past `c` are zero).
    let sigma = in_lanes::<CV, V>(tabs.sigma.as_flattened().iter().copied().take(c));
    l.fill(0.0);
    t.fill(1.0);
    let Some(span) = Span::new(v, ray) else {
        return Some(ray.t1);
    };
    let mut walk = Walk::along(v, ray, &span, step);
    let on_ray = OnRay::new(v, ray, &span);
    let dir = ray.d / span.speed();
    let mut lk = [[0f32; V]; CV];
    // (Padding lanes hold transmittance 0, so they never keep the early termination from stopping.)
    let mut tk = in_lanes::<CV, V>(std::iter::repeat_n(1.0, c));
    let cutoff = v.estimator.cutoff() as f32;
    let split_tau = tabs.split_tau;
    let sigma_max = lt.sigma_max();
    let ns = v.grids.species().len().min(MAX_SPECIES);
    let mut scales = [0f64; MAX_SPECIES];
    for (s, sp) in scales.iter_mut().zip(v.grids.species()) {
        *s = sp.scale();
    }
    let all = v.grids.temperature().is_none();
    let t_emit = v.model.t_emit() as f32;
    let lay = lat.map(|lat| Layout::new(lat, v.grids.lescale().is_some(), v.grids.ds().dims()));
    let jt = Rows::<CV, V>::new(tabs.j)?;
    // σ_a(T) rows where they exist (else the emission rows, never read); located with the emission rows when
    // both tables share their temperatures (as every volume builds them).
    let at = match v.model.a_t() {
        Some(tab) => Rows::<CV, V>::new(tab)?,
        None => jt,
    };
    let shared = at.inv_dt == jt.inv_dt && at.last == jt.last;
    let sp_tabs = species_tables::<CV, V, S>(v, lt)?;
    let mut samples = 0u64;
    let mut x = Extras {
        les: [1.0; BATCH],
        n: [[0.0; BATCH]; MAX_SPECIES],
    };
    'ray: loop {
        // 1. The next BATCH steps outside empty stretches.
        let mut mids = [0f64; BATCH];
        let mut deltas = [0f32; BATCH];
        let (m, end) = walk.next_batch(&mut mids, &mut deltas);
        // 2. Their grid values, read before any is stepped through (independent reads, which the CPU
        // overlaps). A sample outside the medium gets d = −1 (skipped below, not counted).
        let mut dt = [[0f32; 2]; BATCH];
        read_batch::<F>(
            v,
            (&lay, &stored),
            &on_ray,
            (&mids, m),
            &scales[..ns],
            &mut dt,
            &mut x,
        )?;
        // 3. For all of them at once: the table rows at T, the emitting density, the thin-step test (a bound on
        // the optical depth: the largest σ per unit density times d, plus the species').
        let Batch {
            d,
            tt,
            inside,
            dl,
            thin,
        } = Batch::new(v, &dt, &x, &deltas, (all, t_emit, sigma_max));
        let (jr, jf) = jt.locate::<F, BATCH>(&tt);
        let (ar, af) = if A && !shared {
            at.locate::<F, BATCH>(&tt)
        } else {
            (jr, jf)
        };
        // 4. The steps, in order.
        for b in 0..m {
            // Whether the sample steps at all, and whether its step is thin; with species, their rows.
            let mut sp: [Option<SpeciesRows>; MAX_SPECIES] = [None; MAX_SPECIES];
            let (thin_b, bound) = if S {
                if !inside[b] {
                    continue;
                }
                samples += 1;
                let soot = d[b] > 0.0 || dl[b] > 0.0;
                let bound = d[b] * sigma_max * deltas[b];
                let n = x.n.map(|n| n[b]);
                let (any, bound) = species_rows::<CV, V, F>(
                    &sp_tabs[..ns],
                    &n,
                    (tt[b], deltas[b]),
                    bound,
                    &mut sp,
                );
                // (No soot and no species: σ = j = 0, as below.)
                if !(soot || any) {
                    continue;
                }
                (bound < THIN, bound)
            } else {
                // No soot: σ = j = 0, the step would add +0 and multiply by 1 (skipped, bit for bit); a sample
                // outside (d = −1) is not counted.
                samples += inside[b] as u64;
                if !(d[b] > 0.0 || dl[b] > 0.0) {
                    continue;
                }
                (thin[b], d[b] * sigma_max * deltas[b])
            };
            // A step thicker than the volume's `step_tau` (pbrt-v4's grids: a voxel far denser than the step),
            // in sub-steps through the f64 path (never for the fire light's channel subsets, whose columns are
            // not the volume's).
            if bound > split_tau && c == v.channels() {
                let p = ray.o + ray.d * (span.a() + mids[b] / span.speed());
                let tmax = split(
                    v,
                    p,
                    dir,
                    deltas[b] as f64,
                    bound as f64,
                    &mut lk.as_flattened_mut()[..c],
                    &mut tk.as_flattened_mut()[..c],
                );
                // (Its sub-steps' evaluations count themselves.)
                samples -= 1;
                if !(tmax >= cutoff) {
                    break 'ray;
                }
                continue;
            }
            // (A constant empty slice without species, so the array above is not even built.)
            let species: &[Option<SpeciesRows>] = if S { &sp[..ns] } else { &[] };
            let step = Step {
                d: d[b],
                dl: dl[b],
                delta: deltas[b],
            };
            let Some(jp) = jt.pair(jr[b]) else { continue };
            let j = (jp, jf[b]);
            let a = if A {
                match at.pair(ar[b]) {
                    Some(p) => (p, af[b]),
                    None => continue,
                }
            } else {
                j
            };
            let mut tmax = [0f32; V];
            // Lane by lane, each written out (a loop over q kept the lanes in memory; with constant indices
            // radiance and transmittance stay in registers).
            macro_rules! lane {
                ($q:literal) => {
                    if $q < CV {
                        if let (Some(l), Some(t)) = (lk.get_mut($q), tk.get_mut($q)) {
                            step.lane::<CV, V, A, F>(
                                $q, &sigma, j, a, species, thin_b, l, t, &mut tmax,
                            );
                        }
                    }
                };
            }
            lane!(0);
            lane!(1);
            lane!(2);
            lane!(3);
            if !any_at_least(&tmax, cutoff) {
                break 'ray;
            }
        }
        if end {
            break;
        }
    }
    EVALUATIONS.with(|n| n.set(n.get() + samples));
    for ch in 0..c {
        l[ch] = lk[ch / V][ch % V] as f64;
        t[ch] = tk[ch / V][ch % V] as f64;
    }
    Some(span.b())
}

/// A batch's samples as its steps take them: the density clamped at 0 (an interpolation of non-negative data may
/// round below it), the temperature, whether the sample is inside the medium (to count), the emitting density and
/// whether the step is thin by the soot's bound on its optical depth.
struct Batch {
    d: [f32; BATCH],
    tt: [f32; BATCH],
    inside: [bool; BATCH],
    dl: [f32; BATCH],
    thin: [bool; BATCH],
}

impl Batch {
    /// From the grid values `dt` and `x` of steps `deltas` long; `all`: every temperature emits, else those
    /// above `t_emit`; `sigma_max`: the largest σ per unit density.
    #[inline(always)]
    fn new(
        v: &FireVolume,
        dt: &[[f32; 2]; BATCH],
        x: &Extras,
        deltas: &[f32; BATCH],
        (all, t_emit, sigma_max): (bool, f32, f32),
    ) -> Batch {
        let mut d = [0f32; BATCH];
        let mut tt = [0f32; BATCH];
        let mut inside = [false; BATCH];
        for b in 0..BATCH {
            inside[b] = dt[b][0] > 0.5 * OUTSIDE;
            d[b] = dt[b][0].max(0.0);
            tt[b] = dt[b][1];
        }
        let mut dl = [0f32; BATCH];
        let mut thin = [false; BATCH];
        for b in 0..BATCH {
            let emits = all | (tt[b] > t_emit);
            dl[b] = if emits && inside[b] {
                v.emitting(d[b], x.les[b])
            } else {
                0.0
            };
            thin[b] = d[b] * sigma_max * deltas[b] < THIN;
        }
        Batch {
            d,
            tt,
            inside,
            dl,
            thin,
        }
    }
}

/// A thick step (optical depth bound `tau`) through `v`'s own channels in sub-steps
/// ([`super::integrate::split_step`], f64), the radiance `l` and transmittance `t` carried in and out of the
/// kernel's lanes; returns the largest transmittance left.
#[cold]
#[inline(never)]
fn split(
    v: &FireVolume,
    mid: glam::DVec3,
    dir: glam::DVec3,
    delta: f64,
    tau: f64,
    l: &mut [f32],
    t: &mut [f32],
) -> f32 {
    const MAX: usize = 64;
    let c = l.len().min(MAX);
    let [mut sa, mut ss, mut j, mut ll, mut tt] = [[0f64; MAX]; 5];
    for ch in 0..c {
        (ll[ch], tt[ch]) = (l[ch] as f64, t[ch] as f64);
    }
    let n = super::integrate::split_count(tau, v.estimator.step_tau());
    super::integrate::split_step(
        v,
        mid,
        dir,
        delta,
        n,
        (&mut sa[..c], &mut ss[..c], &mut j[..c]),
        &mut ll[..c],
        &mut tt[..c],
    );
    let mut tmax = 0f32;
    for ch in 0..c {
        (l[ch], t[ch]) = (ll[ch] as f32, tt[ch] as f32);
        tmax = tmax.max(t[ch]);
    }
    tmax
}

/// A temperature table as the kernel reads it: rows of the table's 8-channel lanes, of which the kernel's `CV`
/// lanes of `V` channels take the first CV·V.
#[derive(Clone, Copy)]
struct Rows<'a, const CV: usize, const V: usize> {
    v: &'a [Lane],
    /// Lanes per row in the table.
    chunks: usize,
    inv_dt: f64,
    /// rows − 1 and rows − 2, as floats (the clamps).
    last: f64,
    below: f64,
}

impl<'a, const CV: usize, const V: usize> Rows<'a, CV, V> {
    /// The table's lanes that hold the kernel's CV·V channels (a constant for each kernel).
    const LANES: usize = (CV * V).div_ceil(W);

    /// `None` if the table's rows hold fewer than CV·V channels.
    #[inline(always)]
    fn new(tab: &'a TTable) -> Option<Rows<'a, CV, V>> {
        let (v, chunks, rows) = (tab.lanes(), tab.chunks(), tab.rows());
        let ok = chunks >= Self::LANES && rows >= 2 && v.len() == rows * chunks;
        ok.then_some(Rows {
            v,
            chunks,
            inv_dt: tab.inv_dt(),
            last: (rows - 1) as f64,
            below: (rows - 2) as f64,
        })
    }
    /// The lower row index and the fraction toward the next of each temperature (as `TTable::lane_rows`, one
    /// multiply and one exact float→int conversion each, across the batch at once).
    #[inline(always)]
    fn locate<const F: bool, const N: usize>(&self, t: &[f32; N]) -> ([usize; N], [f32; N]) {
        let mut r = [0usize; N];
        let mut fr = [0f32; N];
        for b in 0..N {
            let f = (t[b] as f64 * self.inv_dt).max(0.0).min(self.last);
            let i = floor::<F>(f).min(self.below);
            r[b] = index(i);
            fr[b] = (f - i) as f32;
        }
        (r, fr)
    }
    /// Rows i and i + 1, their first `LANES` lanes (`locate`'s clamps keep i + 1 in the table, so never `None`
    /// from there).
    #[inline(always)]
    fn pair(&self, i: usize) -> Option<(&'a [Lane], &'a [Lane])> {
        let k = Self::LANES;
        let at = i.checked_mul(self.chunks)?;
        let next = at + self.chunks;
        Some((self.v.get(at..at + k)?, self.v.get(next..next + k)?))
    }
}

/// Lane `q` of `V` channels of a row's lanes (`None` past them: never, for the rows of [`Rows::pair`]).
#[inline(always)]
fn view<const V: usize>(row: &[Lane], q: usize) -> Option<&[f32; V]> {
    row.as_flattened().get(q * V..q * V + V)?.try_into().ok()
}

/// What a sample's step needs beyond its table rows.
struct Step {
    d: f32,
    /// Density times the emission scale (0 where it does not emit).
    dl: f32,
    delta: f32,
}

/// Two table rows and the fraction between them.
type RowPair<'a> = ((&'a [Lane], &'a [Lane]), f32);

impl Step {
    /// σ_t and j in lane `q` (from σ per unit density, the emission rows `j`, the T-dependent absorption rows
    /// `a` when `A`, and the species'), then its step; `tmax` keeps the largest transmittance per lane
    /// position.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn lane<const CV: usize, const V: usize, const A: bool, const F: bool>(
        &self,
        q: usize,
        sigma: &[[f32; V]; CV],
        j: RowPair,
        a: RowPair,
        species: &[Option<SpeciesRows>],
        thin: bool,
        l: &mut [f32; V],
        t: &mut [f32; V],
        tmax: &mut [f32; V],
    ) {
        let ((j0, j1), fr) = j;
        let (Some(j0), Some(j1), Some(sig)) = (view::<V>(j0, q), view::<V>(j1, q), sigma.get(q))
        else {
            return;
        };
        let mut sg = [0f32; V];
        let mut jq = [0f32; V];
        for w in 0..V {
            sg[w] = self.d * sig[w];
            jq[w] = self.dl * lerp::<F>(fr, j0[w], j1[w]);
        }
        if A {
            let ((a0, a1), fa) = a;
            if let (Some(a0), Some(a1)) = (view::<V>(a0, q), view::<V>(a1, q)) {
                for w in 0..V {
                    sg[w] = fma::<F>(self.d, lerp::<F>(fa, a0[w], a1[w]), sg[w]);
                }
            }
        }
        for r in species.iter().flatten() {
            let ((s0, s1), (e0, e1)) = (r.s, r.j);
            if let (Some(s0), Some(s1), Some(e0), Some(e1)) = (
                view::<V>(s0, q),
                view::<V>(s1, q),
                view::<V>(e0, q),
                view::<V>(e1, q),
            ) {
                for w in 0..V {
                    sg[w] = fma::<F>(r.n, lerp::<F>(r.f, s0[w], s1[w]), sg[w]);
                    jq[w] = fma::<F>(r.n, lerp::<F>(r.f, e0[w], e1[w]), jq[w]);
                }
            }
        }
        if thin {
            thin_step::<V, F>(&sg, &jq, self.delta, l, t);
        } else {
            full_step::<V, F>(&sg, &jq, self.delta, l, t);
        }
        for w in 0..V {
            tmax[w] = if t[w] > tmax[w] { t[w] } else { tmax[w] };
        }
    }
}

/// Whether any of `x` is at least `cutoff` (the march goes on while a channel's transmittance is): compares
/// reduced by `|`, a mask compare and a test (a tree of maxima went through memory for lanes of 16).
#[inline(always)]
fn any_at_least<const V: usize>(x: &[f32; V], cutoff: f32) -> bool {
    let mut any = false;
    for &v in x {
        any |= v >= cutoff;
    }
    any
}

/// One species' table rows at a sample: its number density, the fraction between the rows, σ and j rows.
#[derive(Clone, Copy)]
struct SpeciesRows<'a> {
    n: f32,
    f: f32,
    s: (&'a [Lane], &'a [Lane]),
    j: (&'a [Lane], &'a [Lane]),
}

/// One step of one lane where every τ = σ·δ < 0.1: g = (1 − e^{−τ})/τ by its series to τ⁴ (remainder
/// τ⁵/720 < 1.4e-8) and e^{−τ} = 1 − τ·g (within 1.4e-9 plus rounding).
#[inline(always)]
fn thin_step<const V: usize, const F: bool>(
    sig: &[f32; V],
    jj: &[f32; V],
    delta: f32,
    l: &mut [f32; V],
    t: &mut [f32; V],
) {
    for w in 0..V {
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

/// One step of one lane for any τ (as [`super::lanes::step`]). (Kept apart from [`thin_step`]: one function
/// with a const switch between the two measured rgb 17.9 → 21.2 ns per sample, docs/results/log.md.)
#[inline(always)]
fn full_step<const V: usize, const F: bool>(
    sig: &[f32; V],
    jj: &[f32; V],
    delta: f32,
    l: &mut [f32; V],
    t: &mut [f32; V],
) {
    for w in 0..V {
        let tau = sig[w] * delta;
        let e = super::lanes::exp_neg(-tau);
        let series = 1.0
            - tau
                * (0.5
                    - tau
                        * (1.0 / 6.0
                            - tau * (1.0 / 24.0 - tau * (1.0 / 120.0 - tau * (1.0 / 720.0)))));
        let quot = (1.0 - e) / tau.max(THIN);
        let thin = 0u32.wrapping_sub((tau < THIN) as u32);
        let g = f32::from_bits((series.to_bits() & thin) | (quot.to_bits() & !thin));
        l[w] = fma::<F>(t[w] * jj[w], delta * g, l[w]);
        t[w] *= e;
    }
}

#[cfg(test)]
mod tests;
