//! Surface scattering: pbrt-v4's BxDFs (`src/pbrt/bxdfs.h`, `bxdfs.cpp`) over the render bins, in the local
//! shading frame (z the shading normal, which points to the shape's outside: a dielectric's inside is z < 0).
//!
//! - `diffuse`: f = R/π on either side (Lambert).
//! - `diffusetransmission`: R/π on wo's side, T/π on the other, each lobe sampled by its largest channel.
//! - `conductor`: a mirror or a Trowbridge–Reitz microfacet BRDF f = D G F / (4 |cos θo cos θi|) with the
//!   conductor's Fresnel reflectance for a complex index η + ik (Born & Wolf; pbrt-v4's `FrComplex`).
//! - `dielectric`: the Fresnel-weighted choice between reflection and refraction (Snell), smooth, or rough by
//!   Walter et al.'s microfacet transmission (*Microfacet Models for Refraction through Rough Surfaces*, EGSR
//!   2007) with the generalized half vector; radiance crossing into a denser medium is scaled by 1/η² (pbrt's
//!   `TransportMode::Radiance`).
//! - `thindielectric`: a thin slab — reflection R + T²R/(1 − R²), the rest passes straight through.
//! - `coateddiffuse` and `coatedconductor` are the layered BSDF of [`super::layered`].
//!
//! Every call is total: a direction on the horizon, a zero pdf or a NaN gives no sample or zero, never a panic.

use super::layered::{Interface, Layered};
pub use super::lobes::{same_hemisphere, Flags, Lobes, Mode, Sample};
use super::microfacet::TrowbridgeReitz;
use super::spectrum::S;
use glam::Vec3A;
use std::f32::consts::{FRAC_1_PI, PI};

/// One BxDF, evaluated in the local shading frame.
#[derive(Debug, Clone)]
pub enum Bxdf {
    Diffuse {
        r: S,
    },
    DiffuseTransmission {
        r: S,
        t: S,
    },
    /// A conductor of complex index η + ik per bin; smooth when `distrib` is.
    Conductor {
        eta: S,
        k: S,
        distrib: TrowbridgeReitz,
    },
    /// A dielectric interface of relative index η (inside over outside), smooth when `distrib` is.
    Dielectric {
        eta: f32,
        distrib: TrowbridgeReitz,
    },
    ThinDielectric {
        eta: f32,
    },
    Layered(Box<Layered<Bxdf>>),
}

/// A cosine-distributed direction in the upper hemisphere (Malley's method on a concentric disk).
pub(crate) fn cosine_hemisphere(u: [f32; 2]) -> Vec3A {
    let (x, y) = (2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    let (r, theta) = if x == 0.0 && y == 0.0 {
        (0.0, 0.0)
    } else if x.abs() > y.abs() {
        (x, PI / 4.0 * (y / x))
    } else {
        (y, PI / 2.0 - PI / 4.0 * (x / y))
    };
    let (dx, dy) = (r * theta.cos(), r * theta.sin());
    Vec3A::new(dx, dy, (1.0 - dx * dx - dy * dy).max(0.0).sqrt())
}

/// The Fresnel reflectance of a dielectric interface of relative index `eta` for a direction at `cos_i` to the
/// normal (negative: arriving from inside).
pub fn fr_dielectric(cos_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_t = (1.0 - cos_i * cos_i) / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (r_parl * r_parl + r_perp * r_perp) / 2.0
}

#[derive(Debug, Clone, Copy)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    fn new(re: f32, im: f32) -> Complex {
        Complex { re, im }
    }
    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }
    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }
    fn mul(self, o: Complex) -> Complex {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }
    fn div(self, o: Complex) -> Complex {
        let d = o.re * o.re + o.im * o.im;
        Complex::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }
    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }
    /// The principal square root.
    fn sqrt(self) -> Complex {
        let n = self.norm().sqrt();
        if n == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 {
            Complex::new(t1, t2)
        } else {
            Complex::new(t2.abs(), t1.copysign(self.im))
        }
    }
}

/// The Fresnel reflectance of a conductor of complex index η + ik at `cos_i` (clamped to [0, 1]).
pub fn fr_complex(cos_i: f32, eta: f32, k: f32) -> f32 {
    if eta == 0.0 && k == 0.0 {
        return 0.0;
    }
    let cos_i = cos_i.clamp(0.0, 1.0);
    let e = Complex::new(eta, k);
    let ci = Complex::new(cos_i, 0.0);
    let sin2_i = Complex::new(1.0 - cos_i * cos_i, 0.0);
    let sin2_t = sin2_i.div(e.mul(e));
    let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
    let r_parl = e.mul(ci).sub(cos_t).div(e.mul(ci).add(cos_t));
    let r_perp = ci.sub(e.mul(cos_t)).div(ci.add(e.mul(cos_t)));
    let r = (r_parl.norm() + r_perp.norm()) / 2.0;
    if r.is_finite() {
        r.clamp(0.0, 1.0)
    } else {
        0.0
    }
}

/// [`fr_complex`] per bin.
fn fr_complex_s(cos_i: f32, eta: &S, k: &S) -> S {
    let mut r = S::ZERO;
    for i in 0..r.0.len() {
        r.0[i] = fr_complex(cos_i, eta.0[i], k.0[i]);
    }
    r
}

/// Snell's refraction of `wi` about normal `n` (either side) for relative index `eta`: the refracted direction
/// and the index actually crossed; `None` under total internal reflection.
pub(crate) fn refract(wi: Vec3A, n: Vec3A, eta: f32) -> Option<(Vec3A, f32)> {
    let (mut cos_i, mut n, mut eta) = (n.dot(wi), n, eta);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    Some((-wi / eta + n * (cos_i / eta - cos_t), eta))
}

fn reflect(wo: Vec3A, n: Vec3A) -> Vec3A {
    -wo + n * (2.0 * wo.dot(n))
}

impl Bxdf {
    pub fn flags(&self) -> Flags {
        match self {
            Bxdf::Diffuse { r } => Flags {
                reflection: !r.is_black(),
                diffuse: !r.is_black(),
                ..Flags::default()
            },
            Bxdf::DiffuseTransmission { r, t } => Flags {
                reflection: !r.is_black(),
                transmission: !t.is_black(),
                diffuse: !(r.is_black() && t.is_black()),
                ..Flags::default()
            },
            Bxdf::Conductor { distrib, .. } => Flags {
                reflection: true,
                specular: distrib.smooth(),
                glossy: !distrib.smooth(),
                ..Flags::default()
            },
            Bxdf::Dielectric { eta, distrib } => Flags {
                reflection: *eta != 1.0,
                transmission: true,
                specular: distrib.smooth(),
                glossy: !distrib.smooth(),
                ..Flags::default()
            },
            Bxdf::ThinDielectric { .. } => Flags {
                reflection: true,
                transmission: true,
                specular: true,
                ..Flags::default()
            },
            Bxdf::Layered(l) => l.flags(),
        }
    }

    /// Whether a path may leave this BxDF by a direction it did not sample ([`super::guide`]): it reflects only,
    /// has no specular lobe, and its `pdf` and `f` are exact (not the layered BSDF's random-walk estimates).
    pub fn guidable(&self) -> bool {
        let fl = self.flags();
        !matches!(self, Bxdf::Layered(_))
            && fl.reflection
            && !fl.transmission
            && !fl.specular
            && fl.non_specular()
    }

    /// f(wo, wi), local directions; the layered BSDF's is an unbiased random-walk estimate drawn with `seed`.
    pub fn f(&self, wo: Vec3A, wi: Vec3A, mode: Mode, seed: u64) -> S {
        match self {
            Bxdf::Diffuse { r } => {
                if same_hemisphere(wo, wi) {
                    *r * FRAC_1_PI
                } else {
                    S::ZERO
                }
            }
            Bxdf::DiffuseTransmission { r, t } => {
                if same_hemisphere(wo, wi) {
                    *r * FRAC_1_PI
                } else {
                    *t * FRAC_1_PI
                }
            }
            Bxdf::Conductor { eta, k, distrib } => {
                if !same_hemisphere(wo, wi) || distrib.smooth() {
                    return S::ZERO;
                }
                let (co, ci) = (wo.z.abs(), wi.z.abs());
                if ci == 0.0 || co == 0.0 {
                    return S::ZERO;
                }
                let wm = (wi + wo).normalize_or_zero();
                if wm == Vec3A::ZERO {
                    return S::ZERO;
                }
                let fr = fr_complex_s(wo.dot(wm).abs(), eta, k);
                fr * (distrib.d(wm) * distrib.g(wo, wi) / (4.0 * ci * co))
            }
            Bxdf::Dielectric { eta, distrib } => dielectric_f(*eta, distrib, wo, wi, mode),
            Bxdf::ThinDielectric { .. } => S::ZERO,
            Bxdf::Layered(l) => l.f(wo, wi, mode, seed),
        }
    }

    /// A direction for `wo` from the lobes allowed, with `uc` choosing the lobe and `u` the direction.
    pub fn sample_f(
        &self,
        wo: Vec3A,
        uc: f32,
        u: [f32; 2],
        mode: Mode,
        lobes: Lobes,
        seed: u64,
    ) -> Option<Sample> {
        let s = match self {
            Bxdf::Diffuse { r } => {
                if !lobes.reflection {
                    return None;
                }
                let mut wi = cosine_hemisphere(u);
                if wo.z < 0.0 {
                    wi.z = -wi.z;
                }
                Sample {
                    f: *r * FRAC_1_PI,
                    wi,
                    pdf: wi.z.abs() * FRAC_1_PI,
                    specular: false,
                    reflection: true,
                    etap: 1.0,
                    proportional: false,
                }
            }
            Bxdf::DiffuseTransmission { r, t } => {
                let mut pr = if lobes.reflection { r.max() } else { 0.0 };
                let mut pt = if lobes.transmission { t.max() } else { 0.0 };
                if !(pr + pt > 0.0) {
                    return None;
                }
                (pr, pt) = (pr / (pr + pt), pt / (pr + pt));
                let mut wi = cosine_hemisphere(u);
                let reflect = uc < pr;
                // Reflection stays on wo's side, transmission crosses.
                if (wo.z < 0.0) == reflect {
                    wi.z = -wi.z;
                }
                Sample {
                    f: if reflect { *r } else { *t } * FRAC_1_PI,
                    wi,
                    pdf: wi.z.abs() * FRAC_1_PI * if reflect { pr } else { pt },
                    specular: false,
                    reflection: reflect,
                    etap: 1.0,
                    proportional: false,
                }
            }
            Bxdf::Conductor { eta, k, distrib } => {
                if !lobes.reflection {
                    return None;
                }
                if distrib.smooth() {
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    let c = wi.z.abs();
                    Sample {
                        f: fr_complex_s(c, eta, k) * (1.0 / c),
                        wi,
                        pdf: 1.0,
                        specular: true,
                        reflection: true,
                        etap: 1.0,
                        proportional: false,
                    }
                } else {
                    if wo.z == 0.0 {
                        return None;
                    }
                    let wm = distrib.sample_wm(wo, u);
                    let wi = reflect(wo, wm);
                    if !same_hemisphere(wo, wi) {
                        return None;
                    }
                    let pdf = distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
                    let (co, ci) = (wo.z.abs(), wi.z.abs());
                    if ci == 0.0 || co == 0.0 {
                        return None;
                    }
                    let fr = fr_complex_s(wo.dot(wm).abs(), eta, k);
                    Sample {
                        f: fr * (distrib.d(wm) * distrib.g(wo, wi) / (4.0 * ci * co)),
                        wi,
                        pdf,
                        specular: false,
                        reflection: true,
                        etap: 1.0,
                        proportional: false,
                    }
                }
            }
            Bxdf::Dielectric { eta, distrib } => {
                return dielectric_sample(*eta, distrib, wo, uc, u, mode, lobes)
            }
            Bxdf::ThinDielectric { eta } => {
                let mut r = fr_dielectric(wo.z.abs(), *eta);
                let mut t = 1.0 - r;
                // Light bouncing between the two faces: R + T²R / (1 − R²) leaves on wo's side.
                if r < 1.0 {
                    r += t * t * r / (1.0 - r * r);
                    t = 1.0 - r;
                }
                let pr = if lobes.reflection { r } else { 0.0 };
                let pt = if lobes.transmission { t } else { 0.0 };
                if !(pr + pt > 0.0) {
                    return None;
                }
                if uc < pr / (pr + pt) {
                    let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
                    Sample {
                        f: S::splat(r / wi.z.abs()),
                        wi,
                        pdf: pr / (pr + pt),
                        specular: true,
                        reflection: true,
                        etap: 1.0,
                        proportional: false,
                    }
                } else {
                    let wi = -wo;
                    Sample {
                        f: S::splat(t / wi.z.abs()),
                        wi,
                        pdf: pt / (pr + pt),
                        specular: true,
                        reflection: false,
                        etap: 1.0,
                        proportional: false,
                    }
                }
            }
            Bxdf::Layered(l) => return l.sample_f(wo, uc, u, mode, seed),
        };
        (s.pdf > 0.0 && s.pdf.is_finite() && s.wi.z != 0.0 && !s.f.is_black()).then_some(s)
    }

    /// The density with which [`sample_f`](Self::sample_f) picks `wi` for `wo` (0 for specular lobes); the
    /// layered BSDF's is a stochastic estimate.
    pub fn pdf(&self, wo: Vec3A, wi: Vec3A, mode: Mode, lobes: Lobes, seed: u64) -> f32 {
        match self {
            Bxdf::Diffuse { .. } => {
                if lobes.reflection && same_hemisphere(wo, wi) {
                    wi.z.abs() * FRAC_1_PI
                } else {
                    0.0
                }
            }
            Bxdf::DiffuseTransmission { r, t } => {
                let pr = if lobes.reflection { r.max() } else { 0.0 };
                let pt = if lobes.transmission { t.max() } else { 0.0 };
                if !(pr + pt > 0.0) {
                    return 0.0;
                }
                let share = if same_hemisphere(wo, wi) { pr } else { pt };
                share / (pr + pt) * wi.z.abs() * FRAC_1_PI
            }
            Bxdf::Conductor { distrib, .. } => {
                if !lobes.reflection || !same_hemisphere(wo, wi) || distrib.smooth() {
                    return 0.0;
                }
                let mut wm = (wo + wi).normalize_or_zero();
                if wm == Vec3A::ZERO {
                    return 0.0;
                }
                if wm.z < 0.0 {
                    wm = -wm;
                }
                distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
            }
            Bxdf::Dielectric { eta, distrib } => dielectric_pdf(*eta, distrib, wo, wi, mode, lobes),
            Bxdf::ThinDielectric { .. } => 0.0,
            Bxdf::Layered(l) => l.pdf(wo, wi, mode, seed),
        }
    }
}

/// The generalized half vector of a rough dielectric for wo, wi (facing +z), with the relative index crossed;
/// `None` for grazing directions and back-facing microfacets.
fn half_vector(eta: f32, wo: Vec3A, wi: Vec3A) -> Option<(Vec3A, f32, bool)> {
    let (co, ci) = (wo.z, wi.z);
    let reflect = co * ci > 0.0;
    let etap = if reflect {
        1.0
    } else if co > 0.0 {
        eta
    } else {
        1.0 / eta
    };
    let wm = wi * etap + wo;
    if ci == 0.0 || co == 0.0 || wm.length_squared() == 0.0 {
        return None;
    }
    let mut wm = wm.normalize();
    if wm.z < 0.0 {
        wm = -wm;
    }
    // Microfacets that face away from either direction do not contribute.
    if wm.dot(wi) * ci < 0.0 || wm.dot(wo) * co < 0.0 {
        return None;
    }
    Some((wm, etap, reflect))
}

fn dielectric_f(eta: f32, distrib: &TrowbridgeReitz, wo: Vec3A, wi: Vec3A, mode: Mode) -> S {
    if eta == 1.0 || distrib.smooth() {
        return S::ZERO;
    }
    let Some((wm, etap, reflect)) = half_vector(eta, wo, wi) else {
        return S::ZERO;
    };
    let f = fr_dielectric(wo.dot(wm), eta);
    let v = if reflect {
        distrib.d(wm) * distrib.g(wo, wi) * f / (4.0 * wi.z * wo.z).abs()
    } else {
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
        let mut ft =
            distrib.d(wm) * (1.0 - f) * distrib.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
        if mode == Mode::Radiance {
            ft /= etap * etap;
        }
        ft
    };
    if v.is_finite() {
        S::splat(v)
    } else {
        S::ZERO
    }
}

fn dielectric_pdf(
    eta: f32,
    distrib: &TrowbridgeReitz,
    wo: Vec3A,
    wi: Vec3A,
    _mode: Mode,
    lobes: Lobes,
) -> f32 {
    if eta == 1.0 || distrib.smooth() {
        return 0.0;
    }
    let Some((wm, etap, reflect)) = half_vector(eta, wo, wi) else {
        return 0.0;
    };
    let r = fr_dielectric(wo.dot(wm), eta);
    let pr = if lobes.reflection { r } else { 0.0 };
    let pt = if lobes.transmission { 1.0 - r } else { 0.0 };
    if !(pr + pt > 0.0) {
        return 0.0;
    }
    let p = if reflect {
        distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt)
    } else {
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
        distrib.pdf(wo, wm) * wi.dot(wm).abs() / denom * pt / (pr + pt)
    };
    if p.is_finite() {
        p
    } else {
        0.0
    }
}

fn dielectric_sample(
    eta: f32,
    distrib: &TrowbridgeReitz,
    wo: Vec3A,
    uc: f32,
    u: [f32; 2],
    mode: Mode,
    lobes: Lobes,
) -> Option<Sample> {
    let radiance = |etap: f32| {
        if mode == Mode::Radiance {
            1.0 / (etap * etap)
        } else {
            1.0
        }
    };
    if eta == 1.0 || distrib.smooth() {
        let r = fr_dielectric(wo.z, eta);
        let pr = if lobes.reflection { r } else { 0.0 };
        let pt = if lobes.transmission { 1.0 - r } else { 0.0 };
        if !(pr + pt > 0.0) {
            return None;
        }
        if uc < pr / (pr + pt) {
            let wi = Vec3A::new(-wo.x, -wo.y, wo.z);
            return Some(Sample {
                f: S::splat(r / wi.z.abs()),
                wi,
                pdf: pr / (pr + pt),
                specular: true,
                reflection: true,
                etap: 1.0,
                proportional: false,
            });
        }
        let (wi, etap) = refract(wo, Vec3A::Z, eta)?;
        if wi.z == 0.0 {
            return None;
        }
        return Some(Sample {
            f: S::splat((1.0 - r) / wi.z.abs() * radiance(etap)),
            wi,
            pdf: pt / (pr + pt),
            specular: true,
            reflection: false,
            etap,
            proportional: false,
        });
    }
    let wm = distrib.sample_wm(wo, u);
    let r = fr_dielectric(wo.dot(wm), eta);
    let pr = if lobes.reflection { r } else { 0.0 };
    let pt = if lobes.transmission { 1.0 - r } else { 0.0 };
    if !(pr + pt > 0.0) {
        return None;
    }
    let s = if uc < pr / (pr + pt) {
        let wi = reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        let pdf = distrib.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt);
        Sample {
            f: S::splat(distrib.d(wm) * distrib.g(wo, wi) * r / (4.0 * wi.z * wo.z).abs()),
            wi,
            pdf,
            specular: false,
            reflection: true,
            etap: 1.0,
            proportional: false,
        }
    } else {
        let (wi, etap) = refract(wo, wm, eta)?;
        if same_hemisphere(wo, wi) || wi.z == 0.0 {
            return None;
        }
        let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
        let dwm_dwi = wi.dot(wm).abs() / denom;
        let pdf = distrib.pdf(wo, wm) * dwm_dwi * pt / (pr + pt);
        let ft = (1.0 - r)
            * distrib.d(wm)
            * distrib.g(wo, wi)
            * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs()
            * radiance(etap);
        Sample {
            f: S::splat(ft),
            wi,
            pdf,
            specular: false,
            reflection: false,
            etap,
            proportional: false,
        }
    };
    (s.pdf > 0.0 && s.pdf.is_finite() && s.f.0[0].is_finite()).then_some(s)
}

/// The layered BSDF's interfaces are BxDFs.
impl Interface for Bxdf {
    fn flags(&self) -> Flags {
        Bxdf::flags(self)
    }
    fn f(&self, wo: Vec3A, wi: Vec3A, mode: Mode, seed: u64) -> S {
        Bxdf::f(self, wo, wi, mode, seed)
    }
    fn sample_f(
        &self,
        wo: Vec3A,
        uc: f32,
        u: [f32; 2],
        mode: Mode,
        lobes: Lobes,
        seed: u64,
    ) -> Option<Sample> {
        Bxdf::sample_f(self, wo, uc, u, mode, lobes, seed)
    }
    fn pdf(&self, wo: Vec3A, wi: Vec3A, mode: Mode, lobes: Lobes, seed: u64) -> f32 {
        Bxdf::pdf(self, wo, wi, mode, lobes, seed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use firemedium_core::rng::Rng;

    fn dir(theta: f32, phi: f32) -> Vec3A {
        Vec3A::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// ∫ f |cos θi| dωi over the sphere by a midpoint rule in (cos θ, φ) on both hemispheres.
    pub(crate) fn albedo_quadrature(b: &Bxdf, wo: Vec3A, q: usize, mode: Mode) -> f64 {
        let mut sum = 0.0f64;
        for hemi in [1.0f32, -1.0] {
            for i in 0..q {
                for j in 0..q {
                    let ct = (i as f32 + 0.5) / q as f32;
                    let phi = (j as f32 + 0.5) / q as f32 * 2.0 * PI;
                    let st = (1.0 - ct * ct).sqrt();
                    let wi = Vec3A::new(st * phi.cos(), st * phi.sin(), ct * hemi);
                    sum += (b.f(wo, wi, mode, 0).0[0] * ct) as f64;
                }
            }
        }
        sum * 2.0 * std::f64::consts::PI / (q * q) as f64
    }

    /// The sampler's estimate of the albedo (E[f |cos| / pdf]) and its consistency with `pdf` and `f`.
    pub(crate) fn albedo_sampled(b: &Bxdf, wo: Vec3A, n: usize, check: bool, mode: Mode) -> f64 {
        let mut rng = Rng::new(7);
        let mut sum = 0.0f64;
        for _ in 0..n {
            let uc = rng.next_f64() as f32;
            let u = [rng.next_f64() as f32, rng.next_f64() as f32];
            if let Some(s) = b.sample_f(wo, uc, u, mode, Lobes::ALL, 0) {
                let w = s.f.0[0] * s.wi.z.abs() / s.pdf;
                assert!(w.is_finite() && w >= 0.0, "{b:?}: weight {w}");
                if check && !s.specular {
                    let (p, f) = (
                        b.pdf(wo, s.wi, mode, Lobes::ALL, 0),
                        b.f(wo, s.wi, mode, 0).0[0],
                    );
                    assert!(
                        (p - s.pdf).abs() <= 2e-3 * s.pdf.max(1e-3),
                        "{b:?}: sampled pdf {} vs pdf() {p}",
                        s.pdf
                    );
                    assert!(
                        (f - s.f.0[0]).abs() <= 2e-3 * f.max(1e-3),
                        "{b:?}: sampled f {} vs f() {f}",
                        s.f.0[0]
                    );
                }
                sum += w as f64;
            }
        }
        sum / n as f64
    }

    #[test]
    fn a_conductors_fresnel_reflectance_is_the_complex_index_formula() {
        // Normal incidence: R = ((η − 1)² + k²) / ((η + 1)² + k²). Copper at 551 nm (η 0.950, k 2.577 in
        // pbrt-v4's table) reflects 0.636.
        let (eta, k) = (0.950375f32, 2.5765f32);
        let want = ((eta - 1.0).powi(2) + k * k) / ((eta + 1.0).powi(2) + k * k);
        assert!((fr_complex(1.0, eta, k) - want).abs() < 1e-6);
        assert!((want - 0.636).abs() < 1e-3, "{want}");
        // k = 0 is the dielectric formula; grazing light is always reflected.
        for c in [0.1f32, 0.5, 0.9] {
            assert!((fr_complex(c, 1.5, 0.0) - fr_dielectric(c, 1.5)).abs() < 1e-5);
        }
        assert!((fr_complex(0.0, 0.2, 3.0) - 1.0).abs() < 1e-5);
        // pbrt-v4's "reflectance" conductor: η = 1, k = 2√r/√(1 − r) reflects r at normal incidence.
        let r = 0.3f32;
        assert!((fr_complex(1.0, 1.0, 2.0 * r.sqrt() / (1.0 - r).sqrt()) - r).abs() < 1e-5);
    }

    #[test]
    fn every_bsdf_conserves_energy_and_samples_its_own_pdf() {
        let white = S::splat(1.0);
        let tr = |a: f32| TrowbridgeReitz::isotropic(a);
        let cases: Vec<(Bxdf, f64)> = vec![
            // (BSDF, its albedo from straight above when known in closed form; NaN: only ≤ 1)
            (Bxdf::Diffuse { r: white * 0.5 }, 0.5),
            (
                Bxdf::DiffuseTransmission {
                    r: white * 0.3,
                    t: white * 0.6,
                },
                0.9,
            ),
            (
                Bxdf::Conductor {
                    eta: white,
                    k: white * 1e3,
                    distrib: tr(0.4),
                },
                f64::NAN,
            ),
            (
                Bxdf::Dielectric {
                    eta: 1.5,
                    distrib: tr(0.3),
                },
                f64::NAN,
            ),
            (
                Bxdf::Dielectric {
                    eta: 1.5,
                    distrib: tr(0.0),
                },
                f64::NAN,
            ),
            (Bxdf::ThinDielectric { eta: 1.5 }, 1.0),
        ];
        for (b, want) in &cases {
            for theta in [0.0f32, 0.6, 1.2] {
                for side in [1.0f32, -1.0] {
                    let mut wo = dir(theta, 0.4);
                    wo.z *= side;
                    // Energy: importance mode (radiance mode scales what crosses an interface by 1/η²).
                    let sampled = albedo_sampled(b, wo, 40_000, true, Mode::Importance);
                    assert!(sampled <= 1.0 + 2e-2, "{b:?} θ {theta}: albedo {sampled}");
                    if theta == 0.0 && want.is_finite() {
                        assert!((sampled - want).abs() < 1e-2, "{b:?}: {sampled} vs {want}");
                    }
                    // Rough lobes: the sampler's estimate equals the quadrature of f.
                    if b.flags().glossy || b.flags().diffuse {
                        let quad = albedo_quadrature(b, wo, 600, Mode::Importance);
                        let radiance = albedo_sampled(b, wo, 40_000, true, Mode::Radiance);
                        let quad_r = albedo_quadrature(b, wo, 600, Mode::Radiance);
                        assert!(
                            (radiance - quad_r).abs() < 0.02 * quad_r.max(0.05),
                            "{b:?} θ {theta} side {side}: radiance sampled {radiance} vs quadrature {quad_r}"
                        );
                        assert!(
                            (sampled - quad).abs() < 0.02 * quad.max(0.05),
                            "{b:?} θ {theta} side {side}: sampled {sampled} vs quadrature {quad}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_smooth_dielectric_splits_light_by_fresnel_and_conserves_it() {
        // Normal incidence on glass: R = ((η − 1)/(η + 1))² = 0.04; what enters carries radiance × 1/η².
        let b = Bxdf::Dielectric {
            eta: 1.5,
            distrib: TrowbridgeReitz::isotropic(0.0),
        };
        let wo = Vec3A::Z;
        let (mut r, mut t) = (0.0f64, 0.0f64);
        let n = 20_000;
        for i in 0..n {
            let uc = (i as f32 + 0.5) / n as f32;
            let s = b
                .sample_f(wo, uc, [0.5, 0.5], Mode::Radiance, Lobes::ALL, 0)
                .unwrap();
            let w = (s.f.0[0] * s.wi.z.abs() / s.pdf) as f64;
            if s.reflection {
                r += w;
                assert_eq!(s.wi, Vec3A::Z);
            } else {
                t += w;
                assert!((s.wi + Vec3A::Z).length() < 1e-6 && s.etap == 1.5);
            }
        }
        let (r, t) = (r / n as f64, t / n as f64);
        assert!((r - 0.04).abs() < 1e-4, "R {r}");
        assert!((t - 0.96 / 2.25).abs() < 1e-3, "T {t}");
        // Total internal reflection from inside beyond the critical angle (41.8°).
        let inside = dir(std::f32::consts::PI - 0.9, 0.0);
        let s = b
            .sample_f(inside, 0.99, [0.5, 0.5], Mode::Radiance, Lobes::ALL, 0)
            .unwrap();
        assert!(s.reflection && (s.f.0[0] * s.wi.z.abs() / s.pdf - 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_rough_dielectric_is_reciprocal_up_to_the_index() {
        // Walter et al.: f(wo → wi)/η_i² = f(wi → wo)/η_o² for transmission in radiance mode, and plain
        // reciprocity for reflection.
        let b = Bxdf::Dielectric {
            eta: 1.5,
            distrib: TrowbridgeReitz::isotropic(0.3),
        };
        let (wo, wi) = (dir(0.4, 0.2), dir(std::f32::consts::PI - 0.7, 3.0));
        let a = b.f(wo, wi, Mode::Radiance, 0).0[0];
        let c = b.f(wi, wo, Mode::Radiance, 0).0[0];
        assert!(a > 0.0 && c > 0.0);
        assert!((a * 1.5f32.powi(2) / c - 1.0).abs() < 1e-3, "{a} vs {c}");
        let (wo, wi) = (dir(0.4, 0.2), dir(0.9, 2.5));
        let (a, c) = (
            b.f(wo, wi, Mode::Radiance, 0).0[0],
            b.f(wi, wo, Mode::Radiance, 0).0[0],
        );
        assert!((a - c).abs() < 1e-5 * a);
    }
}
