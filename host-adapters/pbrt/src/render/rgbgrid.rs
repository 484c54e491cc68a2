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
//! Tracked by the host's one tracker ([`super::tracker`]) with one majorant, the largest σ_t in any bin and voxel
//! (pbrt-v4 uses a 16³ majorant grid: the same estimate, more null collisions here).

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
        let lo = [0, 1, 2].map(|k| self.p0[k].min(self.p1[k]));
        let hi = [0, 1, 2].map(|k| self.p0[k].max(self.p1[k]));
        let (s0, s1) = super::tracker::slab(om, dm, lo, hi, s_max)?;
        Some((s0, s1, om, dm))
    }
}

impl super::tracker::Tracked for RgbGrid {
    /// The ray in the medium's space.
    type Ray = (DVec3, DVec3);

    fn bins(&self) -> usize {
        self.bins
    }

    fn g(&self) -> f64 {
        self.g
    }

    fn clip(&self, o: Vec3A, w: Vec3A, s_max: f32) -> Option<((DVec3, DVec3), f64, f64)> {
        RgbGrid::clip(self, o, w, s_max).map(|(s0, s1, om, dm)| ((om, dm), s0, s1))
    }

    /// One majorant over the whole box.
    fn majorant(&self, _: &(DVec3, DVec3), _: f64, s1: f64) -> (f32, f64) {
        (self.majorant, s1)
    }

    fn at(&self, (om, dm): &(DVec3, DVec3), s: f64) -> Result<(S, S, S), firemedium_loader::Error> {
        Ok(RgbGrid::at(self, *om + *dm * s))
    }
}
