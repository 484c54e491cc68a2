//! A batch of the march's samples: the ray in the lattice's coordinates, the samples' grid values (from the
//! lattice or the dataset's stored bricks), the species' rows at a sample, and the lanes the steps are taken in.

use super::stored::{self, Memo, Stored};
use super::{floor, general, march_cells, read, Extras, Layout, Rows, SpeciesRows, BATCH};
use crate::volume::integrate::Span;
use crate::volume::lanes::{LaneTables, MAX_SPECIES};
use crate::volume::{FireVolume, Ray};

/// A ray as the march reads it: its parameters, its span through the medium and, as a function of arc length s
/// from the entry, its lattice coordinates g0 + s·gd.
pub(super) struct OnRay<'r> {
    ray: &'r Ray,
    span: &'r Span<'r>,
    g0: [f64; 3],
    gd: [f64; 3],
}

impl<'r> OnRay<'r> {
    /// `ray` over `span` in `v`'s lattice coordinates g = unit·n − 0.5.
    #[inline(always)]
    pub(super) fn new(v: &FireVolume, ray: &'r Ray, span: &'r Span<'r>) -> OnRay<'r> {
        let dims = v.grids.ds().dims().map(|n| n as f64);
        let [b0, b1] = v.grids.ds().bounds();
        let size = b1 - b0;
        let entry = ray.o + ray.d * span.a();
        let dir = ray.d / span.speed();
        OnRay {
            ray,
            span,
            g0: [0, 1, 2].map(|a| (entry[a] - b0[a]) / size[a] * dims[a] - 0.5),
            gd: [0, 1, 2].map(|a| dir[a] / size[a] * dims[a]),
        }
    }
}

/// The grid values of a batch's `m` samples at arc lengths `mids` into `dt` and `x`: from the lattice (the cells
/// and fractions first, then the reads) or from the dataset's stored bricks (each in turn); a sample neither
/// answers through the general stencil. `None` when the volume has neither.
#[inline(always)]
pub(super) fn read_batch<const F: bool>(
    v: &FireVolume,
    (lay, stored): (&Option<Layout>, &Option<Stored>),
    on: &OnRay,
    (mids, m): (&[f64; BATCH], usize),
    scales: &[f64],
    dt: &mut [[f32; 2]; BATCH],
    x: &mut Extras,
) -> Option<()> {
    let (ray, span, g0, gd) = (on.ray, on.span, on.g0, on.gd);
    let mut ci = [0usize; BATCH];
    let mut fx = [[0f32; BATCH]; 3];
    match (lay, stored) {
        (None, Some(st)) => {
            // The cells' lower corners and fractions at once (a loop that vectorises), then the reads.
            let mut cf = [[0f64; BATCH]; 3];
            for b in 0..BATCH {
                for a in 0..3 {
                    let g = g0[a] + mids[b] * gd[a];
                    cf[a][b] = floor::<F>(g);
                    fx[a][b] = (g - cf[a][b]) as f32;
                }
            }
            let mut memo = Memo::new();
            for b in 0..m {
                let (c, f) = (
                    [cf[0][b], cf[1][b], cf[2][b]],
                    [fx[0][b], fx[1][b], fx[2][b]],
                );
                if !stored::read_stored::<F>(st, &mut memo, c, f, scales, b, dt, x) {
                    let p = ray.o + ray.d * (span.a() + mids[b] / span.speed());
                    general(v, p, b, dt, x);
                }
            }
        }
        (Some(lay), _) => march_cells::<F>(lay, g0, gd, mids, m, &mut ci, &mut fx),
        (None, None) => return None,
    }
    if let Some(lay) = lay {
        for b in 0..m {
            let f = [fx[0][b], fx[1][b], fx[2][b]];
            if !read::<F>(lay, ci[b], f, scales, b, dt, x) {
                let p = ray.o + ray.d * (span.a() + mids[b] / span.speed());
                general(v, p, b, dt, x);
            }
        }
    }
    Some(())
}

/// Each species' σ and j tables (the same temperature rows) and its largest σ per unit number density (none
/// without species: `S` false).
pub(super) type SpeciesTables<'a, const CV: usize, const V: usize> =
    [Option<(Rows<'a, CV, V>, Rows<'a, CV, V>, f32)>; MAX_SPECIES];

#[inline(always)]
pub(super) fn species_tables<'a, const CV: usize, const V: usize, const S: bool>(
    v: &'a FireVolume,
    lt: &LaneTables,
) -> Option<SpeciesTables<'a, CV, V>> {
    let mut sp_tabs: SpeciesTables<'a, CV, V> = [None; MAX_SPECIES];
    if S {
        for (tab, sp) in sp_tabs.iter_mut().zip(v.grids.species()) {
            *tab = Some((Rows::new(sp.sigma())?, Rows::new(sp.j())?, 0.0));
        }
        for (tab, m) in sp_tabs.iter_mut().zip(lt.species_sigma_max()) {
            if let Some(t) = tab {
                t.2 = m;
            }
        }
    }
    Some(sp_tabs)
}

/// A sample's rows of each species present (number density `n` above 0) at its temperature `t`, into `sp`, and
/// the bound on its step's optical depth (`delta` long) with theirs added to `bound`; whether any is present.
#[inline(always)]
pub(super) fn species_rows<'a, const CV: usize, const V: usize, const F: bool>(
    tabs: &[Option<(Rows<'a, CV, V>, Rows<'a, CV, V>, f32)>],
    n: &[f32; MAX_SPECIES],
    (t, delta): (f32, f32),
    mut bound: f32,
    sp: &mut [Option<SpeciesRows<'a>>; MAX_SPECIES],
) -> (bool, f32) {
    let mut any = false;
    for (s, tab) in tabs.iter().enumerate() {
        let n = n[s];
        if let (true, Some((st, et, smax))) = (n > 0.0, tab) {
            any = true;
            bound += n * smax * delta;
            let (r, f) = st.locate::<F, 1>(&[t]);
            if let (Some(sr), Some(jr)) = (st.pair(r[0]), et.pair(r[0])) {
                sp[s] = Some(SpeciesRows {
                    n,
                    f: f[0],
                    s: sr,
                    j: jr,
                });
            }
        }
    }
    (any, bound)
}

/// `values` in `CV` lanes of `V`, in order (the lanes past them zero).
#[inline(always)]
pub(super) fn in_lanes<const CV: usize, const V: usize>(
    values: impl Iterator<Item = f32>,
) -> [[f32; V]; CV] {
    let mut lanes = [[0f32; V]; CV];
    for (ch, x) in values.enumerate().take(CV * V) {
        lanes[ch / V][ch % V] = x;
    }
    lanes
}
