//! What every BxDF shares, below the BxDFs themselves (`bsdf`) and the layered BSDF built from them (`layered`):
//! the quantity transported, the lobes a query may use, what a BxDF can do, a sampled direction; and the
//! Henyey–Greenstein phase function, evaluated and sampled (the layered BSDF's medium and the integrator's media
//! use the same), and the orthonormal frame around a direction.

use super::spectrum::S;
use glam::Vec3A;

/// Which quantity flows along the path: radiance (camera paths) or importance (the adjoint, used inside the
/// layered BSDF): they differ only in the 1/η² of refraction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    Radiance,
    Importance,
}

impl Mode {
    pub fn flip(self) -> Mode {
        match self {
            Mode::Radiance => Mode::Importance,
            Mode::Importance => Mode::Radiance,
        }
    }
}

/// Which lobes a sample or a pdf may use (pbrt-v4's `BxDFReflTransFlags`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Lobes {
    pub reflection: bool,
    pub transmission: bool,
}

impl Lobes {
    pub const ALL: Lobes = Lobes {
        reflection: true,
        transmission: true,
    };
    pub const REFLECTION: Lobes = Lobes {
        reflection: true,
        transmission: false,
    };
    pub const TRANSMISSION: Lobes = Lobes {
        reflection: false,
        transmission: true,
    };
}

/// What a BxDF can do (pbrt-v4's `BxDFFlags`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Flags {
    pub reflection: bool,
    pub transmission: bool,
    pub diffuse: bool,
    pub glossy: bool,
    pub specular: bool,
}

impl Flags {
    /// Has a lobe that next-event estimation can evaluate (diffuse or glossy).
    pub fn non_specular(&self) -> bool {
        self.diffuse || self.glossy
    }
}

/// A sampled direction: f (not multiplied by the cosine), wi, its pdf, and what kind of scattering it was.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    pub f: S,
    pub wi: Vec3A,
    pub pdf: f32,
    pub specular: bool,
    pub reflection: bool,
    /// The relative index crossed (η for refraction into the medium below, 1 for reflection).
    pub etap: f32,
    /// The pdf is only proportional to the true density (the layered BSDF's random walk): MIS must ask
    /// `Bxdf::pdf` for the direction instead.
    pub proportional: bool,
}

/// Whether `a` and `b` lie on the same side of the shading plane.
pub fn same_hemisphere(a: Vec3A, b: Vec3A) -> bool {
    a.z * b.z > 0.0
}

/// Henyey–Greenstein's phase function (P&P eq. 4) for the cosine `cos` between the two directions as pbrt-v4 takes
/// them (the propagation direction reversed, and the scattered one), asymmetry `g`: what a medium's scattering and
/// the layered BSDF's medium between its interfaces both evaluate.
pub fn henyey_greenstein(cos: f32, g: f32) -> f32 {
    let d = 1.0 + g * g + 2.0 * g * cos;
    (1.0 - g * g) / (4.0 * std::f32::consts::PI * d * d.max(1e-12).sqrt())
}

/// The cosine between the propagation direction and the scattered one, drawn from Henyey–Greenstein with asymmetry
/// `g` by inverting its cdf at `u` (pbrt-v4's `SampleHenyeyGreenstein`; uniform below |g| = 10⁻³, where the
/// inversion loses its digits).
pub fn sample_henyey_greenstein_cos(g: f32, u: f32) -> f32 {
    if g.abs() < 1e-3 {
        1.0 - 2.0 * u
    } else {
        let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    }
}

/// Two unit tangents completing `n` (unit) to an orthonormal frame, continuous but at n.z = 0's sign change (Duff
/// et al. 2017, *Building an Orthonormal Basis, Revisited*).
pub fn frame(n: Vec3A) -> (Vec3A, Vec3A) {
    let s = if n.z < 0.0 { -1.0 } else { 1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (
        Vec3A::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x),
        Vec3A::new(b, s + n.y * n.y * a, -n.y),
    )
}

/// The unit direction at cosine `cos` to `axis` (unit), at azimuth 2π·`u` in [`frame`]`(axis)`.
pub fn around(axis: Vec3A, cos: f32, u: f32) -> Vec3A {
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * std::f32::consts::PI * u;
    let (t, b) = frame(axis);
    (t * (sin * phi.cos()) + b * (sin * phi.sin()) + axis * cos).normalize_or_zero()
}
