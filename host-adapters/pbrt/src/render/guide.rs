//! Directions toward a scattering fire from the surfaces it lights: a second way to pick where a path leaves a
//! surface, mixed with the BSDF's (one-sample MIS with the balance heuristic: the path's weight is f·cos over the
//! mixture's density, so the estimate is the same in expectation whichever way a direction was drawn).
//!
//! A fire that scatters much lights its room twice: the emission that leaves it unscattered, and the emission its
//! soot scatters out. The second is found only by paths that reach the fire and scatter in it; from a wall a few
//! metres away the fire is a small part of the BSDF's hemisphere, so few paths do, each with a large weight: the
//! speckles of a scattering room. Here a share `prob` of the directions aims at a point drawn uniformly in the
//! fire's box (world space), whose density per solid angle from `p` along `w` is the box's chord taken as a cone:
//! (t₁³ − t₀³) / 3V, t₀ and t₁ where the ray enters and leaves it (closed form, so any direction's density is
//! known, the BSDF's samples' too). Only BxDFs that reflect, have no specular lobe and know their own density
//! take it ([`Bxdf::guidable`](super::bsdf::Bxdf::guidable)).

use glam::Vec3A;

/// The box a share of the surfaces' directions aims at.
#[derive(Debug, Clone, Copy)]
pub struct Guide {
    lo: Vec3A,
    hi: Vec3A,
    volume: f64,
    /// The share of the directions aimed at the box (0 < prob < 1: the BSDF keeps the rest).
    prob: f32,
}

impl Guide {
    /// Aims a share `prob` of the directions at the box [`lo`, `hi`]; `None` for an empty box or a share outside
    /// (0, 1).
    pub fn new(lo: Vec3A, hi: Vec3A, prob: f32) -> Option<Guide> {
        let e = (hi - lo).as_dvec3();
        let volume = e.x * e.y * e.z;
        (volume > 0.0 && volume.is_finite() && prob > 0.0 && prob < 1.0).then_some(Guide {
            lo,
            hi,
            volume,
            prob,
        })
    }

    /// The share of the directions aimed at the box.
    pub fn prob(&self) -> f32 {
        self.prob
    }

    /// The box, corners low and high.
    pub fn bounds(&self) -> [Vec3A; 2] {
        [self.lo, self.hi]
    }

    /// A unit direction from `p` toward a point drawn uniformly in the box by `u`; `None` when the point is `p`.
    pub fn sample(&self, p: Vec3A, u: [f32; 3]) -> Option<Vec3A> {
        let q = self.lo + (self.hi - self.lo) * Vec3A::from_array(u);
        let w = (q - p).normalize_or_zero();
        (w != Vec3A::ZERO).then_some(w)
    }

    /// The density per solid angle with which [`sample`](Self::sample) from `p` draws the unit direction `w`:
    /// ∫ t² dt / V over the ray's chord through the box, (t₁³ − t₀³) / 3V (0 when it misses).
    pub fn pdf(&self, p: Vec3A, w: Vec3A) -> f32 {
        let inv = w.recip();
        let (a, b) = ((self.lo - p) * inv, (self.hi - p) * inv);
        let (near, far) = (a.min(b), a.max(b));
        // (NaN from a zero component times an infinite reciprocal on a face is dropped by max/min.)
        let t0 = near.max_element().max(0.0);
        let t1 = far.min_element();
        if !(t1 > t0) {
            return 0.0;
        }
        let (t0, t1) = (f64::from(t0), f64::from(t1));
        ((t1 * t1 * t1 - t0 * t0 * t0) / (3.0 * self.volume)) as f32
    }

    /// The mixture's density of `w` from `p`, given the BSDF's `pb`.
    pub fn mixed(&self, p: Vec3A, w: Vec3A, pb: f32) -> f32 {
        self.prob * self.pdf(p, w) + (1.0 - self.prob) * pb
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The solid-angle density integrates to 1 over the sphere of directions, from outside the box and inside
    /// it, and matches a histogram of the sampled directions.
    #[test]
    fn the_density_is_the_samples_density() {
        let g = Guide::new(Vec3A::new(-0.6, -0.5, 0.0), Vec3A::new(0.6, 0.7, 1.6), 0.5).unwrap();
        check(&g);
    }

    fn check(g: &Guide) {
        let mut state = 0x9e3779b97f4a7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        for p in [Vec3A::new(2.0, -3.0, 0.5), Vec3A::new(0.1, 0.2, 0.3)] {
            // ∫ pdf dω by a Fibonacci lattice of directions.
            let n = 400_000;
            let mut integral = 0f64;
            for i in 0..n {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
                let r = (1.0 - z * z).sqrt();
                let w = Vec3A::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
                integral += f64::from(g.pdf(p, w));
            }
            integral *= 4.0 * std::f64::consts::PI / n as f64;
            assert!((integral - 1.0).abs() < 2e-3, "{p}: ∫ pdf dω = {integral}");
            // The share of samples in cones around the box's centre and toward a corner's cell against ∫ pdf
            // over each cone.
            let m = 200_000;
            let samples: Vec<Vec3A> = (0..m)
                .filter_map(|_| g.sample(p, [next(), next(), next()]))
                .collect();
            for (towards, cos_max) in [
                ((g.lo + g.hi) * 0.5, 0.995f32),
                (g.lo * 0.8 + g.hi * 0.2, 0.998),
            ] {
                let axis = (towards - p).normalize();
                let inside =
                    samples.iter().filter(|w| w.dot(axis) > cos_max).count() as f64 / m as f64;
                let expected = integral_over_cone(g, p, axis, cos_max);
                assert!(
                    expected > 1e-3 && (inside - expected).abs() < 4.0 * (expected / m as f64).sqrt() + 1e-4,
                    "{p}: {inside} of the samples in the cone toward {towards}, ∫ pdf over it {expected}"
                );
            }
        }
        // A ray that misses has no density.
        assert_eq!(g.pdf(Vec3A::new(5.0, 5.0, 5.0), Vec3A::X), 0.0);
    }

    /// ∫ pdf dω over the cone of directions within acos(`cos_max`) of `axis`, by a polar grid.
    fn integral_over_cone(g: &Guide, p: Vec3A, axis: Vec3A, cos_max: f32) -> f64 {
        let (t, b) = crate::render::lobes::frame(axis);
        let (nc, np) = (400, 400);
        let mut s = 0f64;
        for i in 0..nc {
            let c = 1.0 - (1.0 - f64::from(cos_max)) * (i as f64 + 0.5) / nc as f64;
            let r = (1.0 - c * c).sqrt();
            for j in 0..np {
                let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / np as f64;
                let w = t * (r * phi.cos()) as f32 + b * (r * phi.sin()) as f32 + axis * c as f32;
                s += f64::from(g.pdf(p, w.normalize()));
            }
        }
        s * 2.0 * std::f64::consts::PI * (1.0 - f64::from(cos_max)) / (nc * np) as f64
    }
}
