//! pbrt-v4's materials (`src/pbrt/materials.h`): what a scene's `Material` says, and the BxDF it becomes at a
//! hit ([`Material::bxdf`]). Parameters keep pbrt-v4's names and defaults (the builder reads them); roughness
//! and `mix`'s `amount` may be float textures, reflectances spectrum textures.
//!
//! An index that varies with wavelength (`"spectrum eta" "glass-BK7"`) refracts each wavelength its own way:
//! as pbrt-v4 terminates the secondary wavelengths, a path that meets one keeps a single bin (chosen uniformly,
//! its weight multiplied by the bin count) — [`Eta::dispersive`]. `mix` chooses one of its two materials per hit
//! by a hash of the point and the direction (pbrt-v4's `MixMaterial::ChooseMaterial`), so a pixel's samples
//! blend them by `amount`.

use super::bsdf::Bxdf;
use super::layered::Layered;
use super::microfacet::TrowbridgeReitz;
use super::spectrum::S;
use glam::{Vec2, Vec3A};

/// A spectrum texture.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // constants are the common case; boxing them would cost a pointer chase per lookup
pub enum Tex {
    Const(S),
    /// (Its two textures shared, not copied: a texture naming another twice at each of 20 levels is 20 nodes,
    /// not 2²⁰ — it took 4.9 GB.)
    Checker {
        a: std::sync::Arc<Tex>,
        b: std::sync::Arc<Tex>,
        su: f32,
        sv: f32,
    },
    /// An image: linear RGB × scale (1 − it when inverted), uplifted with the bins' box basis.
    Image {
        img: std::sync::Arc<crate::imageio::RgbImage>,
        scale: f32,
        invert: bool,
        wrap: crate::imageio::Wrap,
        basis: [S; 3],
    },
}

impl Tex {
    pub fn eval(&self, uv: Vec2) -> S {
        match self {
            Tex::Const(s) => *s,
            Tex::Checker { a, b, su, sv } => {
                if ((uv.x * su).floor() as i64 + (uv.y * sv).floor() as i64) % 2 == 0 {
                    a.eval(uv)
                } else {
                    b.eval(uv)
                }
            }
            Tex::Image {
                img,
                scale,
                invert,
                wrap,
                basis,
            } => {
                // pbrt-v4 flips t: row 0 of the image is v = 1.
                let c = img.bilerp(uv.x, 1.0 - uv.y, *wrap).map(|x| {
                    if *invert {
                        (1.0 - x * *scale).max(0.0)
                    } else {
                        x * *scale
                    }
                });
                basis[0] * c[0] + basis[1] * c[1] + basis[2] * c[2]
            }
        }
    }
}

/// A float parameter: a constant or a texture (its mean over the active bins).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene, read in place at each hit
pub enum FloatTex {
    Const(f32),
    Tex(Tex, usize),
}

impl FloatTex {
    pub fn eval(&self, uv: Vec2) -> f32 {
        match self {
            FloatTex::Const(v) => *v,
            FloatTex::Tex(t, n) => {
                let s = t.eval(uv);
                let n = (*n).max(1);
                s.0[..n].iter().sum::<f32>() / n as f32
            }
        }
    }
}

/// pbrt-v4's `uroughness`/`vroughness` (defaulting to `roughness`) and `remaproughness`.
#[derive(Debug, Clone)]
pub struct Roughness {
    pub u: FloatTex,
    pub v: FloatTex,
    pub remap: bool,
}

impl Roughness {
    pub fn smooth() -> Roughness {
        Roughness {
            u: FloatTex::Const(0.0),
            v: FloatTex::Const(0.0),
            remap: true,
        }
    }
    fn at(&self, uv: Vec2) -> TrowbridgeReitz {
        TrowbridgeReitz::from_roughness(self.u.eval(uv), self.v.eval(uv), self.remap)
    }
    /// Whether every hit is smooth: a constant roughness whose α is below 10⁻³ (a perfect mirror or glass).
    pub fn always_smooth(&self) -> bool {
        match (&self.u, &self.v) {
            (FloatTex::Const(u), FloatTex::Const(v)) => {
                TrowbridgeReitz::from_roughness(*u, *v, self.remap).smooth()
            }
            _ => false,
        }
    }
}

/// A dielectric's index: one value, or one per bin (dispersive).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene, read in place at each hit
pub enum Eta {
    Const(f32),
    Spectral(S),
}

impl Eta {
    /// Whether the index differs between the bins (the path must then keep one bin).
    pub fn dispersive(&self, n: usize) -> bool {
        match self {
            Eta::Const(_) => false,
            Eta::Spectral(s) => s.0[..n].iter().any(|v| *v != s.0[0]),
        }
    }
    /// The index for bin `channel` (or bin 0 when the path has not chosen one); pbrt-v4 treats 0 as 1.
    fn at(&self, channel: Option<usize>) -> f32 {
        let v = match self {
            Eta::Const(v) => *v,
            Eta::Spectral(s) => s.0[channel.unwrap_or(0)],
        };
        if v == 0.0 || !v.is_finite() {
            1.0
        } else {
            v
        }
    }
}

/// A conductor's optics: a complex index per bin, or pbrt-v4's `reflectance` (η = 1, k = 2√r/√(1 − r), so r
/// is the reflectance at normal incidence).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene, read in place at each hit
pub enum Metal {
    Index { eta: S, k: S },
    Reflectance(Tex),
}

impl Metal {
    fn at(&self, uv: Vec2, n: usize) -> (S, S) {
        match self {
            Metal::Index { eta, k } => (*eta, *k),
            Metal::Reflectance(t) => {
                let r = t.eval(uv);
                let (mut eta, mut k) = (S::ZERO, S::ZERO);
                for i in 0..n {
                    let r = r.0[i].clamp(0.0, 0.9999);
                    eta.0[i] = 1.0;
                    k.0[i] = 2.0 * r.sqrt() / (1.0 - r).max(0.0).sqrt();
                }
                (eta, k)
            }
        }
    }
}

/// The medium between a coat and its base (pbrt-v4's `thickness`, `albedo`, `g`) and the walks' limits.
#[derive(Debug, Clone)]
pub struct Layer {
    pub thickness: f32,
    pub albedo: S,
    pub g: f32,
    pub max_depth: u32,
    pub n_samples: u32,
}

/// Surface materials.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene, read in place at each hit
pub enum Material {
    Diffuse(Tex),
    DiffuseTransmission {
        r: Tex,
        t: Tex,
        scale: f32,
    },
    Conductor {
        metal: Metal,
        rough: Roughness,
    },
    Dielectric {
        eta: Eta,
        rough: Roughness,
    },
    ThinDielectric {
        eta: Eta,
    },
    CoatedDiffuse {
        r: Tex,
        eta: Eta,
        rough: Roughness,
        layer: Layer,
    },
    CoatedConductor {
        eta: Eta,
        rough: Roughness,
        metal: Metal,
        metal_rough: Roughness,
        layer: Layer,
    },
    /// Two materials (`None`: `interface`) chosen per hit with probability 1 − amount and amount.
    Mix {
        a: Option<usize>,
        b: Option<usize>,
        amount: FloatTex,
    },
}

impl Material {
    /// Whether a hit on this material can have a non-specular lobe, where next-event estimation samples the
    /// lights (`all`: the scene's materials, which `mix` refers to; `interface`, `None` in a mix, never does).
    pub fn may_be_non_specular(&self, all: &[Material]) -> bool {
        self.non_specular_within(all, 0)
    }
    fn non_specular_within(&self, all: &[Material], depth: usize) -> bool {
        match self {
            Material::Conductor { rough, .. } | Material::Dielectric { rough, .. } => {
                !rough.always_smooth()
            }
            Material::ThinDielectric { .. } => false,
            // (A chain of mixes deeper than any scene writes is taken to reach a diffuse one.)
            Material::Mix { a, b, .. } => {
                depth > 32
                    || [a, b].iter().any(|m| {
                        m.and_then(|i| all.get(i))
                            .is_some_and(|m| m.non_specular_within(all, depth + 1))
                    })
            }
            _ => true,
        }
    }
}

/// A hash of a hit's point and outgoing direction to [0, 1) (`mix`'s choice, fixed per point and view).
fn hash_unit(p: Vec3A, wo: Vec3A, a: usize, b: usize) -> f32 {
    let mut h = 0x243F_6A88_85A3_08D3u64 ^ ((a as u64) << 32) ^ b as u64;
    for v in [p.x, p.y, p.z, wo.x, wo.y, wo.z] {
        h = (h ^ v.to_bits() as u64).wrapping_mul(0x100_0000_01B3);
        h ^= h >> 29;
        h = h.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h ^= h >> 32;
    }
    (h >> 40) as f32 / (1u64 << 24) as f32
}

/// The material that applies at a hit: `mix`es resolved (to `None` when they choose `interface`), at most
/// 16 deep (a longer chain of mixes is a loop the builder refuses; the bound keeps a hit finite regardless).
pub fn resolve(
    materials: &[Material],
    mut m: Option<usize>,
    p: Vec3A,
    wo: Vec3A,
    uv: Vec2,
) -> Option<usize> {
    for _ in 0..16 {
        match m.and_then(|i| materials.get(i)) {
            Some(Material::Mix { a, b, amount }) => {
                let amt = amount.eval(uv);
                m = if amt <= 0.0 {
                    *a
                } else if amt >= 1.0 {
                    *b
                } else if amt < hash_unit(p, wo, a.unwrap_or(usize::MAX), b.unwrap_or(usize::MAX)) {
                    *a
                } else {
                    *b
                };
            }
            _ => return m,
        }
    }
    m
}

impl Material {
    /// The index whose dispersion makes a path keep one bin, if this material has one.
    pub fn eta(&self) -> Option<&Eta> {
        match self {
            Material::Dielectric { eta, .. }
            | Material::ThinDielectric { eta }
            | Material::CoatedDiffuse { eta, .. }
            | Material::CoatedConductor { eta, .. } => Some(eta),
            _ => None,
        }
    }

    /// The BxDF at texture coordinates `uv` for a path that keeps bin `channel` (if it chose one), over `n`
    /// active bins. `Mix` must be resolved first ([`resolve`]); it gives `None`.
    pub fn bxdf(&self, uv: Vec2, channel: Option<usize>, n: usize) -> Option<Bxdf> {
        let dielectric = |eta: &Eta, rough: &Roughness| Bxdf::Dielectric {
            eta: eta.at(channel),
            distrib: rough.at(uv),
        };
        let conductor = |metal: &Metal, rough: &Roughness| {
            let (eta, k) = metal.at(uv, n);
            Bxdf::Conductor {
                eta,
                k,
                distrib: rough.at(uv),
            }
        };
        let layered = |top: Bxdf, bottom: Bxdf, l: &Layer| {
            Bxdf::Layered(Box::new(Layered {
                top,
                bottom,
                thickness: l.thickness.max(f32::MIN_POSITIVE),
                albedo: l.albedo,
                g: l.g,
                max_depth: l.max_depth,
                n_samples: l.n_samples,
            }))
        };
        Some(match self {
            Material::Diffuse(t) => Bxdf::Diffuse {
                r: clamp01(t.eval(uv)),
            },
            Material::DiffuseTransmission { r, t, scale } => Bxdf::DiffuseTransmission {
                r: clamp01(r.eval(uv) * *scale),
                t: clamp01(t.eval(uv) * *scale),
            },
            Material::Conductor { metal, rough } => conductor(metal, rough),
            Material::Dielectric { eta, rough } => dielectric(eta, rough),
            Material::ThinDielectric { eta } => Bxdf::ThinDielectric {
                eta: eta.at(channel),
            },
            Material::CoatedDiffuse {
                r,
                eta,
                rough,
                layer,
            } => layered(
                dielectric(eta, rough),
                Bxdf::Diffuse {
                    r: clamp01(r.eval(uv)),
                },
                layer,
            ),
            Material::CoatedConductor {
                eta,
                rough,
                metal,
                metal_rough,
                layer,
            } => {
                // The conductor's index is relative to the coat above it (pbrt-v4 divides by the coat's η).
                let e = eta.at(channel);
                let (ce, ck) = metal.at(uv, n);
                layered(
                    dielectric(eta, rough),
                    Bxdf::Conductor {
                        eta: ce / e,
                        k: ck / e,
                        distrib: metal_rough.at(uv),
                    },
                    layer,
                )
            }
            Material::Mix { .. } => return None,
        })
    }
}

/// Reflectances as pbrt-v4 clamps them: to [0, 1].
fn clamp01(s: S) -> S {
    S(s.0.map(|v| {
        if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        }
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mix_chooses_by_amount() {
        let mats = vec![
            Material::Diffuse(Tex::Const(S::splat(0.1))),
            Material::Diffuse(Tex::Const(S::splat(0.9))),
            Material::Mix {
                a: Some(0),
                b: Some(1),
                amount: FloatTex::Const(0.3),
            },
        ];
        let n = 100_000;
        let picked_b = (0..n)
            .filter(|i| {
                let p = Vec3A::new(*i as f32 * 0.37, (*i as f32).sin(), 1.0);
                resolve(&mats, Some(2), p, Vec3A::Z, Vec2::ZERO) == Some(1)
            })
            .count();
        // P(b) = amount (pbrt-v4: amount < u picks a); 5σ of a binomial is 0.7 %.
        assert!(
            (picked_b as f64 / n as f64 - 0.3).abs() < 0.007,
            "{picked_b}"
        );
        // Fixed per point and view.
        let p = Vec3A::new(0.3, 0.2, 0.1);
        let first = resolve(&mats, Some(2), p, Vec3A::Z, Vec2::ZERO);
        assert!((0..10).all(|_| resolve(&mats, Some(2), p, Vec3A::Z, Vec2::ZERO) == first));
    }

    #[test]
    fn a_reflectance_conductor_reflects_its_reflectance_head_on() {
        let m = Metal::Reflectance(Tex::Const(S::splat(0.6)));
        let (eta, k) = m.at(Vec2::ZERO, 4);
        let r = crate::render::bsdf::fr_complex(1.0, eta.0[2], k.0[2]);
        assert!((r - 0.6).abs() < 1e-5, "{r}");
        assert_eq!(eta.0[5], 0.0);
    }
}
