//! One tracker for every medium the host tracks itself — pbrt-v4's `SampleT_maj` over majorant segments, with
//! delta tracking for a path and ratio tracking for transmittance on top. A medium answers the two questions
//! pbrt-v4 and Mitsuba 3 ask ([`Tracked`]): a bound on σ_t from a point on (and how far it holds), and σ_a, σ_s,
//! σ_a·Le at a point. pbrt-v4's `rgbgrid` ([`super::rgbgrid`], one majorant over its box) and a plugin medium
//! through the ABI's medium level ([`PluginMedium`]: its majorant grid walked cell by cell, its coefficients in
//! the renderer's bins) are both tracked here.
//!
//! Estimators: emission at each tentative collision sᵢ as T̂(sᵢ) σ_a Le / σ̄ with T̂ the running product of
//! 1 − σ_t/σ̄ (ratio tracking, unbiased — Novák et al. 2014, as pbrt-v4's volpath), events with the bins' mean
//! σ's as probabilities and spectral weights. A majorant segment's end restarts the exponential step (free paths
//! are memoryless); a zero majorant skips its segment. Bounded: an absurd majorant over a long ray cannot hang a
//! render.

use super::spectrum::S;
use firemedium_loader::Error;
use glam::{DAffine3, DVec3, Vec3A};

/// A medium the host tracks: majorants along a ray and coefficients at its points. Distances are the world's
/// along a unit world direction.
pub(super) trait Tracked {
    /// The ray as the medium keeps it (its space, its clipping).
    type Ray;
    /// The bins in use.
    fn bins(&self) -> usize;
    /// The Henyey–Greenstein g of its phase function.
    fn g(&self) -> f64;
    /// The ray o + s·w, s ∈ [0, s_max], where it crosses the medium: (the ray, s₀, s₁), or None.
    fn clip(&self, o: Vec3A, w: Vec3A, s_max: f32) -> Option<(Self::Ray, f64, f64)>;
    /// A bound on σ_t over every bin from distance `s` on, and the distance (≤ `s1`, > `s` unless `s` = `s1`)
    /// up to which it holds.
    fn majorant(&self, ray: &Self::Ray, s: f64, s1: f64) -> (f32, f64);
    /// σ_a, σ_s and σ_a·Le at distance `s` (per world distance), or the plugin's error.
    fn at(&self, ray: &Self::Ray, s: f64) -> Result<(S, S, S), Error>;
}

/// What delta tracking found along a segment: scattered at distance s, or left it; each with the spectral
/// weight accumulated on the way (null collisions) and the emission it collected (relative to the path's
/// throughput at the segment's start).
#[derive(Debug)]
pub enum Track {
    Scattered { s: f32, weight: S, emitted: S },
    Passed { weight: S, emitted: S },
    Absorbed { emitted: S },
}

/// The tentative collisions along o + s·w, s ∈ [0, s_max], at each segment's majorant: `visit` gets each one's
/// distance, the majorant there, σ_a, σ_s and σ_a·Le (and the random numbers), until it returns a result, the ray
/// leaves the medium or a query fails.
fn collisions<M: Tracked, R>(
    m: &M,
    o: Vec3A,
    w: Vec3A,
    s_max: f32,
    u: &mut dyn FnMut() -> f64,
    mut visit: impl FnMut(f64, f32, S, S, S, &mut dyn FnMut() -> f64) -> Option<R>,
) -> Result<Option<R>, Error> {
    let Some((ray, s0, s1)) = m.clip(o, w, s_max) else {
        return Ok(None);
    };
    let mut s = s0;
    for _ in 0..1_000_000 {
        let (maj, end) = m.majorant(&ray, s, s1);
        if !(maj > 0.0) {
            s = end;
        } else {
            let step = -(1.0 - u()).ln() / maj as f64;
            if s + step >= end {
                s = end;
            } else {
                s += step;
                let (sa, ss, e) = m.at(&ray, s)?;
                if let Some(r) = visit(s, maj, sa, ss, e, u) {
                    return Ok(Some(r));
                }
                continue;
            }
        }
        if s >= s1 {
            break;
        }
    }
    Ok(None)
}

/// Transmittance and (with `emission`) emitted radiance along o + s·w, s ∈ [0, s_max], by ratio tracking, or
/// the error of a query that failed.
pub(super) fn segment<M: Tracked>(
    m: &M,
    o: Vec3A,
    w: Vec3A,
    s_max: f32,
    mut u: impl FnMut() -> f64,
    emission: bool,
) -> Result<(S, S), Error> {
    let mut tr = S::splat(1.0);
    let mut l = S::ZERO;
    let bins = m.bins();
    collisions(m, o, w, s_max, &mut u, |_, maj, sa, ss, e, _| {
        for c in 0..bins {
            if emission {
                l.0[c] += tr.0[c] * e.0[c] / maj;
            }
            tr.0[c] *= 1.0 - (sa.0[c] + ss.0[c]) / maj;
        }
        (tr.max() <= 0.0).then_some(())
    })?;
    Ok((l, tr))
}

/// Delta tracking along o + s·w, s ∈ [0, s_max]: where the path scatters, if it does, or the error of a query
/// that failed.
pub(super) fn track<M: Tracked>(
    m: &M,
    o: Vec3A,
    w: Vec3A,
    s_max: f32,
    mut u: impl FnMut() -> f64,
) -> Result<Track, Error> {
    let mut weight = S::splat(1.0);
    let mut emitted = S::ZERO;
    let bins = m.bins();
    let n = bins.max(1) as f32;
    let event = collisions(m, o, w, s_max, &mut u, |s, maj, sa, ss, e, u| {
        for c in 0..bins {
            emitted.0[c] += weight.0[c] * e.0[c] / maj;
        }
        // Event probabilities from the bins' means (they sum to 1: σ_a + σ_s + σ_n = σ̄ in every bin).
        let mean = |x: &S| x.0[..bins].iter().sum::<f32>() / n;
        let (pa, ps) = (mean(&sa) / maj, mean(&ss) / maj);
        let x = u() as f32;
        if x < pa {
            return Some(Track::Absorbed { emitted });
        }
        if x < pa + ps {
            for c in 0..bins {
                weight.0[c] *= ss.0[c] / (maj * ps);
            }
            return Some(Track::Scattered {
                s: s as f32,
                weight,
                emitted,
            });
        }
        let pn = 1.0 - pa - ps;
        if !(pn > 0.0) {
            return Some(Track::Absorbed { emitted });
        }
        for c in 0..bins {
            weight.0[c] *= (maj - sa.0[c] - ss.0[c]) / (maj * pn);
        }
        None
    });
    Ok(event?.unwrap_or(Track::Passed { weight, emitted }))
}

/// The interval [s₀, s₁] ⊂ [0, s_max] of the ray o + s·d inside the box [lo, hi] (the slab test), or None.
pub(super) fn slab(
    o: DVec3,
    d: DVec3,
    lo: [f64; 3],
    hi: [f64; 3],
    s_max: f32,
) -> Option<(f64, f64)> {
    let (mut s0, mut s1) = (0.0f64, s_max as f64);
    for k in 0..3 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
        s0 = s0.max(a.min(b));
        s1 = s1.min(a.max(b));
    }
    (s0 < s1 && s0.is_finite()).then_some((s0, s1))
}

/// A plugin medium's majorant grid, owned by the scene: cells tiling a box in the medium's space, a bound on σ_t
/// per cell (medium units⁻¹), x fastest; and the volume's bounds, which may reach beyond the cells (pbrt mode's
/// half-voxel margin, where the nearest cell's bound holds — the ABI's contract).
#[derive(Debug, Clone)]
pub struct Majorants {
    /// Where the volume may be non-zero: its bounds and the cells' box together.
    pub clip: [[f64; 3]; 2],
    pub lo: [f64; 3],
    pub cell: [f64; 3],
    pub counts: [usize; 3],
    pub sigma_t: Vec<f64>,
}

impl Majorants {
    /// A copy of the volume's grid (the scene keeps it beside the volume), `bounds` the volume's.
    pub fn of(g: &firemedium_loader::MajorantGrid<'_>, bounds: [[f64; 3]; 2]) -> Majorants {
        Majorants {
            clip: [
                [0, 1, 2].map(|a| g.lo[a].min(bounds[0][a])),
                [0, 1, 2].map(|a| g.hi[a].max(bounds[1][a])),
            ],
            lo: g.lo,
            cell: g.cell,
            counts: g.counts,
            sigma_t: g.sigma_t.to_vec(),
        }
    }
}

/// A plugin medium tracked by the host through the ABI's medium level: its majorant grid walked cell by cell
/// (a cell's bound × the medium's length per world length), its coefficients (`volume_coefficients`, in the
/// renderer's bins) at each tentative collision — what pbrt-v4 or Mitsuba 3 would do with it.
pub(super) struct PluginMedium<'a> {
    pub vol: &'a firemedium_loader::Volume,
    pub grid: &'a Majorants,
    pub to_medium: &'a DAffine3,
    /// The film's units per the medium's radiance unit.
    pub units: f32,
    pub bins: usize,
    pub g: f64,
}

/// A ray in a plugin medium's space: origin, direction per world distance, and its length per world length.
#[derive(Debug, Clone, Copy)]
pub(super) struct MediumRay {
    o: DVec3,
    d: DVec3,
    stretch: f64,
}

impl Tracked for PluginMedium<'_> {
    type Ray = MediumRay;

    fn bins(&self) -> usize {
        self.bins
    }

    fn g(&self) -> f64 {
        self.g
    }

    fn clip(&self, o: Vec3A, w: Vec3A, s_max: f32) -> Option<(MediumRay, f64, f64)> {
        let om = self.to_medium.transform_point3(o.as_dvec3());
        let dm = self.to_medium.transform_vector3(w.as_dvec3());
        let (s0, s1) = slab(om, dm, self.grid.clip[0], self.grid.clip[1], s_max)?;
        let ray = MediumRay {
            o: om,
            d: dm,
            stretch: dm.length(),
        };
        Some((ray, s0, s1))
    }

    fn majorant(&self, ray: &MediumRay, s: f64, s1: f64) -> (f32, f64) {
        let g = self.grid;
        let p = ray.o + ray.d * s;
        let mut end = s1;
        let mut idx = [0usize; 3];
        for a in 0..3 {
            // The cell the ray is in just after `s`, and where it leaves it. On a face — or a rounding away from
            // it, the face then behind `s` — the ray is in the cell beyond. Outside the cells (the margin), the
            // nearest cell's bound holds up to the first face.
            let t = (p[a] - g.lo[a]) / g.cell[a];
            let mut c = if ray.d[a] < 0.0 {
                t.ceil() - 1.0
            } else {
                t.floor()
            };
            if ray.d[a] != 0.0 {
                let step = ray.d[a].signum();
                let exit = |c: f64| {
                    let face = g.lo[a] + (c + if step > 0.0 { 1.0 } else { 0.0 }) * g.cell[a];
                    s + (face - p[a]) / ray.d[a]
                };
                let mut e = exit(c);
                if e <= s {
                    c += step;
                    e = exit(c);
                }
                if e > s {
                    end = end.min(e);
                }
            }
            idx[a] = c.clamp(0.0, (g.counts[a] - 1) as f64) as usize;
        }
        let k = idx[0] + g.counts[0] * (idx[1] + g.counts[1] * idx[2]);
        let maj = g.sigma_t.get(k).copied().unwrap_or(0.0) * ray.stretch;
        (maj as f32, end)
    }

    fn at(&self, ray: &MediumRay, s: f64) -> Result<(S, S, S), Error> {
        let n = self.bins;
        let p = ray.o + ray.d * s;
        let (mut sa, mut ss, mut e) = (S::ZERO, S::ZERO, S::ZERO);
        self.vol.coefficients(
            &[p.to_array()],
            &mut sa.0[..n],
            &mut ss.0[..n],
            &mut e.0[..n],
        )?;
        let k = ray.stretch as f32;
        for c in 0..n {
            sa.0[c] *= k;
            ss.0[c] *= k;
            e.0[c] *= k * self.units;
        }
        Ok((sa, ss, e))
    }
}
