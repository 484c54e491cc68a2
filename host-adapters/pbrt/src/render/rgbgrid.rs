//! pbrt-v4's `rgbgrid` medium (`RGBGridMedium`, `src/pbrt/media.h/.cpp`): per-voxel rgb σ_a, σ_s and Le over the box
//! [p0, p1] in the medium's space, rendered in the host (the plugin's grids are scalar).
//!
//! As pbrt-v4: each voxel's σ_a and σ_s are `RGBUnboundedSpectrum`s and its Le an `RGBIlluminantSpectrum` (the
//! sigmoid fit times the colour space's illuminant, D65 with ∫ D65 ȳ = ∫ ȳ: rgb (1, 1, 1) records
//! Y = ∫ ȳ dλ ≈ 106.857 on pbrt-v4's film — a grid's Le is *not* photometrically normalised, unlike a light's),
//! scaled by `scale` and `Lescale`; a missing σ grid is the constant 1 (× scale) inside the box. Lookups are
//! pbrt-v4's `SampledGrid::Lookup`: samples at voxel centres, trilinear between them, zero beyond the outermost
//! centres' neighbours (so values fade to zero over the box's outer half-voxel). Distances are the world's (the
//! σ's apply per unit length of the rendering space, as pbrt-v4 normalises the ray before transforming it).
//!
//! Tracking uses one majorant, the largest σ_t in any bin and voxel (pbrt-v4 uses a 16³ majorant grid: the same
//! estimate, more null collisions here): transmittance and emission by ratio tracking (at each tentative
//! collision sᵢ, emission T̂(sᵢ) σ_a Le / σ̄ with T̂ the running product of 1 − σ_t/σ̄ — unbiased, Novák et al.
//! 2014), scattering by delta tracking with the bins' mean σ's as event probabilities and spectral weights.

use super::spectrum::S;
use glam::{DAffine3, DVec3, Vec3A};

/// The grids of one `rgbgrid` medium, as bin spectra per voxel (x fastest).
#[derive(Debug)]
pub struct RgbGrid {
    pub n: [usize; 3],
    pub p0: DVec3,
    pub p1: DVec3,
    /// σ_a, σ_s per voxel (× scale), or the constant `scale` when the scene gave none.
    pub sa: Grid,
    pub ss: Grid,
    /// σ_a · Le per voxel is what emits: Le per voxel (× Lescale, in the film's units), if any.
    pub le: Option<Vec<S>>,
    /// The largest σ_t over bins and voxels.
    pub majorant: f32,
    pub to_medium: DAffine3,
    pub g: f64,
    /// The bins in use.
    pub bins: usize,
}

/// A σ grid: per-voxel spectra, or one constant spectrum everywhere in the box.
#[derive(Debug)]
pub enum Grid {
    Voxels(Vec<S>),
    Constant(Box<S>),
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

impl RgbGrid {
    /// Whether any voxel scatters (σ_s > 0 in some bin).
    pub fn scatters(&self) -> bool {
        match &self.ss {
            Grid::Voxels(v) => v.iter().any(|s| s.max() > 0.0),
            Grid::Constant(s) => s.max() > 0.0,
        }
    }
    fn lookup(&self, v: &[S], p: DVec3) -> S {
        // pbrt-v4's SampledGrid::Lookup: p ∈ [0, 1]³ of the box; samples at (i + ½)/n.
        let [nx, ny, nz] = self.n;
        let q = DVec3::new(
            p.x * nx as f64 - 0.5,
            p.y * ny as f64 - 0.5,
            p.z * nz as f64 - 0.5,
        );
        let i = q.floor();
        let f = q - i;
        let (ix, iy, iz) = (i.x as i64, i.y as i64, i.z as i64);
        let at = |x: i64, y: i64, z: i64| -> Option<&S> {
            if x < 0 || y < 0 || z < 0 || x >= nx as i64 || y >= ny as i64 || z >= nz as i64 {
                return None;
            }
            v.get(x as usize + nx * (y as usize + ny * z as usize))
        };
        let mut out = S::ZERO;
        for (dz, wz) in [(0, 1.0 - f.z), (1, f.z)] {
            for (dy, wy) in [(0, 1.0 - f.y), (1, f.y)] {
                for (dx, wx) in [(0, 1.0 - f.x), (1, f.x)] {
                    let w = (wx * wy * wz) as f32;
                    if w == 0.0 {
                        continue;
                    }
                    if let Some(s) = at(ix + dx, iy + dy, iz + dz) {
                        for c in 0..self.bins {
                            out.0[c] += w * s.0[c];
                        }
                    }
                }
            }
        }
        out
    }

    /// σ_a, σ_s and σ_a · Le at medium-space point `pm` (inside the box).
    fn at(&self, pm: DVec3) -> (S, S, S) {
        let u = (pm - self.p0) / (self.p1 - self.p0);
        let grid = |g: &Grid| match g {
            Grid::Voxels(v) => self.lookup(v, u),
            Grid::Constant(s) => **s,
        };
        let (sa, ss) = (grid(&self.sa), grid(&self.ss));
        let mut e = S::ZERO;
        if let Some(le) = &self.le {
            let le = self.lookup(le, u);
            for c in 0..self.bins {
                e.0[c] = sa.0[c] * le.0[c];
            }
        }
        (sa, ss, e)
    }

    /// The world-distance interval [s0, s1] ⊂ [0, s_max] of the ray o + s·w (w a unit world direction) inside the
    /// box, with the ray in medium space.
    fn clip(&self, o: Vec3A, w: Vec3A, s_max: f32) -> Option<(f64, f64, DVec3, DVec3)> {
        let om = self.to_medium.transform_point3(o.as_dvec3());
        let dm = self.to_medium.transform_vector3(w.as_dvec3());
        let (mut s0, mut s1) = (0.0f64, s_max as f64);
        for k in 0..3 {
            let (lo, hi) = (self.p0[k].min(self.p1[k]), self.p0[k].max(self.p1[k]));
            if dm[k] == 0.0 {
                if om[k] < lo || om[k] > hi {
                    return None;
                }
                continue;
            }
            let (a, b) = ((lo - om[k]) / dm[k], (hi - om[k]) / dm[k]);
            s0 = s0.max(a.min(b));
            s1 = s1.min(a.max(b));
        }
        (s0 < s1 && s0.is_finite()).then_some((s0, s1, om, dm))
    }

    /// The tentative collisions along o + s·w, s ∈ [0, s_max] (world distances), at the majorant's rate: `visit`
    /// gets each one's distance, σ_a, σ_s and σ_a·Le (and the random numbers), until it returns a result or the
    /// ray leaves the box. Bounded: an absurd majorant over a long box cannot hang a render.
    fn collisions<R>(
        &self,
        o: Vec3A,
        w: Vec3A,
        s_max: f32,
        u: &mut dyn FnMut() -> f64,
        mut visit: impl FnMut(f64, S, S, S, &mut dyn FnMut() -> f64) -> Option<R>,
    ) -> Option<R> {
        let (s0, s1, om, dm) = self.clip(o, w, s_max)?;
        let maj = self.majorant as f64;
        if !(maj > 0.0) {
            return None;
        }
        let mut s = s0;
        for _ in 0..1_000_000 {
            s += -(1.0 - u()).ln() / maj;
            if s >= s1 {
                break;
            }
            let (sa, ss, e) = self.at(om + dm * s);
            if let Some(r) = visit(s, sa, ss, e, u) {
                return Some(r);
            }
        }
        None
    }

    /// Transmittance and (with `emission`) emitted radiance along o + s·w, s ∈ [0, s_max] (world distances), by
    /// ratio tracking.
    pub fn segment(
        &self,
        o: Vec3A,
        w: Vec3A,
        s_max: f32,
        mut u: impl FnMut() -> f64,
        emission: bool,
    ) -> (S, S) {
        let mut tr = S::splat(1.0);
        let mut l = S::ZERO;
        let maj = self.majorant;
        self.collisions(o, w, s_max, &mut u, |_, sa, ss, e, _| {
            for c in 0..self.bins {
                if emission {
                    l.0[c] += tr.0[c] * e.0[c] / maj;
                }
                tr.0[c] *= 1.0 - (sa.0[c] + ss.0[c]) / maj;
            }
            (tr.max() <= 0.0).then_some(())
        });
        (l, tr)
    }

    /// Delta tracking along o + s·w, s ∈ [0, s_max]: where the path scatters, if it does.
    pub fn track(&self, o: Vec3A, w: Vec3A, s_max: f32, mut u: impl FnMut() -> f64) -> Track {
        let mut weight = S::splat(1.0);
        let mut emitted = S::ZERO;
        let (maj, bins) = (self.majorant, self.bins);
        let n = bins.max(1) as f32;
        let event = self.collisions(o, w, s_max, &mut u, |s, sa, ss, e, u| {
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
        event.unwrap_or(Track::Passed { weight, emitted })
    }
}
