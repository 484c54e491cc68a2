//! `Material` and `MakeNamedMaterial`: pbrt-v4's materials read with its parameter names and defaults
//! (`src/pbrt/materials.cpp`), each value checked where it is given.

use super::builder::{num, Builder};
use super::{err, Error, Material, Tex};
use crate::render::material::{Eta, FloatTex, Layer, Metal, Roughness};
use crate::render::spectrum::S;
use firemedium_core::rgb_spectrum::RgbUse;
use firemedium_pbrt_parser::{Loc, ParamDict, Values};

/// Bounds on the layered BSDF's random walks: each hit costs up to `nsamples` × `maxdepth` interface events.
const MAX_WALK: f64 = 1000.0;

impl Builder {
    /// A reflectance (an albedo spectrum or texture) with pbrt-v4's default.
    fn reflectance(&self, p: &ParamDict, name: &str, def: f32) -> Result<Tex, Error> {
        Ok(self
            .spectrum(p, name, Some(self.bins.mask() * def), RgbUse::Albedo)?
            .unwrap_or(Tex::Const(S::ZERO)))
    }

    /// A float parameter that may name a texture; finite and within `lo..=hi`.
    fn float_tex(
        &self,
        p: &ParamDict,
        name: &str,
        def: f64,
        (lo, hi): (f64, f64),
        loc: &Loc,
    ) -> Result<FloatTex, Error> {
        if let Some(q) = p.get(name) {
            if q.ty == "texture" {
                let t = q
                    .strings()
                    .and_then(|v| v.first())
                    .cloned()
                    .unwrap_or_default();
                return self
                    .textures
                    .get(&t)
                    .cloned()
                    .map(|tex| FloatTex::Tex(tex, self.bins.n()))
                    .ok_or_else(|| {
                        err(
                            &q.loc,
                            format!("\"texture {name}\": no texture named \"{t}\""),
                        )
                    });
            }
        }
        let v = num(p, name, def);
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            let at = p.get(name).map_or(loc, |q| &q.loc);
            return Err(err(
                at,
                format!("\"{name}\" {v}: expected a number from {lo} to {hi}"),
            ));
        }
        Ok(FloatTex::Const(v as f32))
    }

    /// pbrt-v4's roughness parameters under `prefix` (`""`, `"interface."`, `"conductor."`): `uroughness` and
    /// `vroughness` default to `roughness` (default 0); `remaproughness` (shared, default true).
    fn roughness(&self, p: &ParamDict, prefix: &str, loc: &Loc) -> Result<Roughness, Error> {
        let range = (0.0, 1e6);
        let name = |s: &str| format!("{prefix}{s}");
        let base = self.float_tex(p, &name("roughness"), 0.0, range, loc)?;
        let u = if p.has(&name("uroughness")) {
            self.float_tex(p, &name("uroughness"), 0.0, range, loc)?
        } else {
            base.clone()
        };
        let v = if p.has(&name("vroughness")) {
            self.float_tex(p, &name("vroughness"), 0.0, range, loc)?
        } else {
            base
        };
        Ok(Roughness {
            u,
            v,
            remap: p.bool("remaproughness", true),
        })
    }

    /// A dielectric's index `name`: `"float"` or a `"spectrum"` (named, or (λ, value) pairs); default 1.5.
    fn eta(&self, p: &ParamDict, name: &str) -> Result<Eta, Error> {
        let Some(q) = p.get(name) else {
            return Ok(Eta::Const(1.5));
        };
        let v = match (q.ty.as_str(), &q.values) {
            ("float", Values::Numbers(v)) => v.first().copied().unwrap_or(1.5),
            ("spectrum", _) => {
                let s = self.constant(p, name, S::ZERO, RgbUse::Unbounded)?;
                let n = self.bins.n();
                if let Some(bad) = s.0[..n].iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                    return Err(err(
                        &q.loc,
                        format!("\"spectrum {name}\": index {bad}: expected finite values >= 0"),
                    ));
                }
                // A flat spectrum is a constant index; a varying one disperses.
                if s.0[..n].iter().all(|v| *v == s.0[0]) {
                    s.0[0] as f64
                } else {
                    return Ok(Eta::Spectral(s));
                }
            }
            (t, _) => {
                return Err(err(
                    &q.loc,
                    format!("\"{t} {name}\": expected \"float {name}\" or \"spectrum {name}\""),
                ))
            }
        };
        if !(v.is_finite() && (0.0..=1e3).contains(&v)) {
            return Err(err(&q.loc, format!("\"{name}\" {v}: expected an index from 0 to 1000 (0 is taken as 1, as pbrt-v4 does)")));
        }
        Ok(Eta::Const(v as f32))
    }

    /// A conductor: `reflectance` (as pbrt-v4: η = 1, k from it) if given, else the complex index
    /// `eta_name` + i `k_name` (default: copper, pbrt-v4's `metal-Cu-eta`/`metal-Cu-k`).
    fn metal(&self, p: &ParamDict, eta_name: &str, k_name: &str) -> Result<Metal, Error> {
        if p.has("reflectance") {
            return Ok(Metal::Reflectance(self.reflectance(
                p,
                "reflectance",
                0.0,
            )?));
        }
        let named = |n: &str| {
            crate::render::named_spectra::lookup(n)
                .map(|v| self.bins.pairs(&v))
                .unwrap_or(S::ZERO)
        };
        let eta = self.constant(p, eta_name, named("metal-Cu-eta"), RgbUse::Unbounded)?;
        let k = self.constant(p, k_name, named("metal-Cu-k"), RgbUse::Unbounded)?;
        let n = self.bins.n();
        for (name, s) in [(eta_name, &eta), (k_name, &k)] {
            if let Some(bad) = s.0[..n].iter().find(|v| !(v.is_finite() && **v >= 0.0)) {
                let m = format!("\"{name}\": {bad}: expected finite values >= 0");
                return Err(match p.get(name) {
                    Some(q) => err(&q.loc, m),
                    None => Error::value(m),
                });
            }
        }
        Ok(Metal::Index { eta, k })
    }

    /// The layer between a coat and its base: `thickness` (0.01), `albedo` (0), `g` (0), `maxdepth` (10),
    /// `nsamples` (1).
    fn layer(&self, p: &ParamDict, loc: &Loc) -> Result<Layer, Error> {
        let f = |name: &str, def: f64, lo: f64, hi: f64| -> Result<f64, Error> {
            let v = num(p, name, def);
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                let at = p.get(name).map_or(loc, |q| &q.loc);
                Err(err(
                    at,
                    format!("\"{name}\" {v}: expected a number from {lo} to {hi}"),
                ))
            }
        };
        let albedo = self.constant(p, "albedo", S::ZERO, RgbUse::Albedo)?;
        Ok(Layer {
            thickness: f("thickness", 0.01, 1e-30, 1e30)? as f32,
            albedo: S(albedo.0.map(|v| v.clamp(0.0, 1.0))),
            g: f("g", 0.0, -0.999, 0.999)? as f32,
            max_depth: f("maxdepth", 10.0, 1.0, MAX_WALK)? as u32,
            n_samples: f("nsamples", 1.0, 1.0, MAX_WALK)? as u32,
        })
    }

    pub(super) fn material(
        &mut self,
        ty: &str,
        p: &ParamDict,
        loc: &Loc,
    ) -> Result<Option<usize>, Error> {
        let m = match ty {
            "interface" | "" => return Ok(None),
            "diffuse" => Material::Diffuse(self.reflectance(p, "reflectance", 0.5)?),
            "diffusetransmission" => {
                let scale = num(p, "scale", 1.0);
                if !(scale.is_finite() && scale >= 0.0) {
                    return Err(err(
                        loc,
                        format!(
                            "diffusetransmission: \"scale\" {scale}: expected a finite number >= 0"
                        ),
                    ));
                }
                Material::DiffuseTransmission {
                    r: self.reflectance(p, "reflectance", 0.25)?,
                    t: self.reflectance(p, "transmittance", 0.25)?,
                    scale: scale as f32,
                }
            }
            "conductor" => Material::Conductor {
                metal: self.metal(p, "eta", "k")?,
                rough: self.roughness(p, "", loc)?,
            },
            "dielectric" => Material::Dielectric {
                eta: self.eta(p, "eta")?,
                rough: self.roughness(p, "", loc)?,
            },
            "thindielectric" => Material::ThinDielectric {
                eta: self.eta(p, "eta")?,
            },
            "coateddiffuse" => Material::CoatedDiffuse {
                r: self.reflectance(p, "reflectance", 0.5)?,
                eta: self.eta(p, "eta")?,
                rough: self.roughness(p, "", loc)?,
                layer: self.layer(p, loc)?,
            },
            "coatedconductor" => Material::CoatedConductor {
                eta: self.eta(p, "interface.eta")?,
                rough: self.roughness(p, "interface.", loc)?,
                metal: self.metal(p, "conductor.eta", "conductor.k")?,
                metal_rough: self.roughness(p, "conductor.", loc)?,
                layer: self.layer(p, loc)?,
            },
            "mix" => {
                let names = p
                    .get("materials")
                    .and_then(|q| q.strings())
                    .ok_or_else(|| {
                        err(
                            loc,
                            "mix: missing \"string materials\" (two named materials)",
                        )
                    })?;
                if names.len() != 2 {
                    return Err(err(
                        loc,
                        format!(
                            "mix: \"string materials\" has {} names: expected two named materials",
                            names.len()
                        ),
                    ));
                }
                let mut pick = [None, None];
                for (slot, n) in pick.iter_mut().zip(names) {
                    let m = *self.named_materials.get(n).ok_or_else(|| {
                        err(loc, format!("mix: no material named \"{n}\" (MakeNamedMaterial must come first)"))
                    })?;
                    // `interface` is stored as usize::MAX: the mix then passes through where it chooses it.
                    *slot = (m != usize::MAX).then_some(m);
                }
                Material::Mix {
                    a: pick[0],
                    b: pick[1],
                    amount: self.float_tex(
                        p,
                        "amount",
                        0.5,
                        (f64::NEG_INFINITY, f64::INFINITY),
                        loc,
                    )?,
                }
            }
            other => {
                return Err(err(loc, format!("material \"{other}\" is not supported (diffuse, coateddiffuse, coatedconductor, conductor, dielectric, thindielectric, diffusetransmission, mix, interface){}", firemedium_pbrt_parser::v3::type_hint("material", other))));
            }
        };
        self.materials.push(m);
        Ok(Some(self.materials.len() - 1))
    }
}
