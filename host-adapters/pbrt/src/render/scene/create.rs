//! One small `create` per kind: what the scene's description ([`super::description`]) says, built — the film,
//! sampler, integrator and pixel filter, lights (sources and area lights), textures, object instances. Materials
//! are made in `materials`, shapes in `builder`, media in `media`; `load` calls them in pbrt-v4's order.

use super::builder::{affine_f32, num, nums, string, Builder, FilmParams};
use super::description::{Entity, Texture};
use super::{err, Error, Light, Tex};
use crate::render::pbrt_v4::Kind;
use crate::render::pixel::{Filter, Params as FilterParams, Sampler};
use crate::render::shapes::{Bvh, Geom, Prim};
use crate::render::spectrum::S;
use firemedium_core::rgb_spectrum::RgbUse;
use firemedium_pbrt_parser::v3;
use firemedium_pbrt_parser::{Loc, ParamDict};
use glam::{DMat3, DMat4, DVec3, Mat3A, Vec3A};
use std::sync::Arc;

/// The film's resolution (pbrt-v4's 1280 × 720 where it does not say): 1 to 65 536 pixels a side, as
/// --resolution (zero and negative were clamped to 1 silently, 1e9 allocated until the process aborted); the
/// film's bytes are checked against the budget in `build`. Read through the film's `p` (its parameters then
/// count as read), refused at the parameter or else at the film (`loc`).
pub(super) fn film_resolution(p: &ParamDict, loc: &Loc) -> Result<(usize, usize), Error> {
    let side = |name: &str, default: f64| -> Result<usize, Error> {
        let v = num(p, name, default);
        if v.fract() == 0.0 && (1.0..=65536.0).contains(&v) {
            Ok(v as usize)
        } else {
            let at = p.get(name).map_or(loc.clone(), |q| q.loc.clone());
            Err(err(
                &at,
                format!("film: \"integer {name}\" {v}: expected 1 to 65536 pixels"),
            ))
        }
    };
    Ok((side("xresolution", 1280.0)?, side("yresolution", 720.0)?))
}

impl Builder {
    /// The film: its resolution, sensor, response, crop and outputs (pbrt-v4's `rgb`, `gbuffer`, `spectral`).
    pub(super) fn film(&mut self, e: &Entity) -> Result<(), Error> {
        let (ty, loc) = (&e.ty, &e.loc);
        let p = &ParamDict::new(&e.params);
        if !["rgb", "gbuffer", "spectral"].contains(&ty.as_str()) {
            return Err(err(
                loc,
                format!(
                    "film \"{ty}\" is not a pbrt-v4 film (rgb, gbuffer, spectral){}",
                    v3::type_hint("film", ty)
                ),
            ));
        }
        // pbrt-v4's gbuffer film: the visible surface's channels beside R, G, B, in camera or world space.
        self.gbuffer = None;
        if ty == "gbuffer" {
            let world = match string(p, "coordinatesystem").unwrap_or("camera") {
                "camera" => false,
                "world" => true,
                other => {
                    let at = p
                        .get("coordinatesystem")
                        .map_or(loc.clone(), |q| q.loc.clone());
                    return Err(err(&at, format!("film \"gbuffer\": \"string coordinatesystem\" \"{other}\": expected \"camera\" or \"world\"")));
                }
            };
            self.gbuffer = Some(crate::render::film::GBuffer { world });
        }
        self.res = film_resolution(p, loc)?;
        self.film_name = string(p, "filename").map(String::from);
        // pbrt-v4's spectral film: RGB plus `nbuckets` channels of spectral radiance over its range.
        self.spectral = None;
        if ty == "spectral" {
            let n = num(p, "nbuckets", 16.0);
            let (lo, hi) = (num(p, "lambdamin", 360.0), num(p, "lambdamax", 830.0));
            if !(n.fract() == 0.0
                && (1.0..=1024.0).contains(&n)
                && lo > 0.0
                && hi > lo
                && hi <= 1e5)
            {
                return Err(err(loc, format!("film \"spectral\": {n} buckets over {lo}–{hi} nm: expected 1 to 1024 buckets over 0 < lambdamin < lambdamax")));
            }
            self.spectral = Some(crate::render::film::Buckets {
                n: n as usize,
                lo,
                hi,
            });
        }
        // The sensor (pbrt-v4's PixelSensor): cie1931 is the CIE XYZ matching functions; a named camera
        // carried here is its measured curves and pbrt-v4's ColorChecker calibration; pbrt-v4's other
        // cameras render as cie1931 with their default 6500 K white, warned; any other name is an error.
        let sensor = string(p, "sensor").unwrap_or("cie1931");
        let mut camera = None;
        if sensor != "cie1931" {
            let at = p.get("sensor").map_or(loc.clone(), |q| q.loc.clone());
            const PBRT_V4: [&str; 17] = [
                "canon_eos_100d",
                "canon_eos_1dx_mkii",
                "canon_eos_200d",
                "canon_eos_200d_mkii",
                "canon_eos_5d",
                "canon_eos_5d_mkii",
                "canon_eos_5d_mkiii",
                "canon_eos_5d_mkiv",
                "canon_eos_5ds",
                "canon_eos_m",
                "hasselblad_l1d_20c",
                "nikon_d810",
                "nikon_d850",
                "sony_ilce_6400",
                "sony_ilce_7m3",
                "sony_ilce_7rm3",
                "sony_ilce_9",
            ];
            camera = crate::render::sensors::NAMES
                .iter()
                .copied()
                .find(|n| *n == sensor);
            if camera.is_none() {
                if !PBRT_V4.contains(&sensor) {
                    return Err(err(
                        &at,
                        format!(
                            "film: sensor \"{sensor}\" is not a pbrt-v4 sensor (cie1931, {})",
                            PBRT_V4.join(", ")
                        ),
                    ));
                }
                self.warn(&at, format!("film: sensor \"{sensor}\" is rendered with the cie1931 sensor (its measured curves are not carried here: {} are), white-balanced as pbrt-v4 does for it", crate::render::sensors::NAMES.join(", ")));
            }
        }
        let white = num(
            p,
            "whitebalance",
            if sensor == "cie1931" { 0.0 } else { 6500.0 },
        );
        let (iso, maxc) = (
            num(p, "iso", 100.0),
            num(p, "maxcomponentvalue", f64::INFINITY),
        );
        // (Cameras go to ISO 3.3 million; daylight's locus is defined to 25 000 K and clamped there.)
        let valid = iso > 0.0
            && iso <= 1e7
            && maxc > 0.0
            && (white == 0.0 || (white > 0.0 && white <= 1e6));
        if !valid {
            return Err(err(loc, format!("film: iso {iso}, maxcomponentvalue {maxc}, whitebalance {white}: expected 0 < iso <= 1e7, a positive maximum and 0 <= whitebalance <= 1e6 K")));
        }
        for (name, slot) in [
            ("cropwindow", &mut self.crop),
            ("pixelbounds", &mut self.pixel_bounds),
        ] {
            if let Some(q) = p.get(name) {
                let v = q.numbers().unwrap_or(&[]);
                if v.len() != 4 || v.iter().any(|x| !x.is_finite()) {
                    return Err(err(
                        &q.loc,
                        format!("film: \"{name}\" {v:?}: expected four finite values x0 x1 y0 y1"),
                    ));
                }
                *slot = Some(([v[0], v[1], v[2], v[3]], q.loc.clone()));
            }
        }
        self.film_response = FilmParams {
            iso,
            white_k: white,
            max_component: maxc,
            fp16: p.bool("savefp16", false),
            camera,
        };
        self.finish(Kind::Film, ty, "film", p)?;
        Ok(())
    }

    /// The sampler and its samples per pixel.
    pub(super) fn sampler(&mut self, e: &Entity) -> Result<(), Error> {
        let (ty, loc) = (&e.ty, &e.loc);
        let p = &ParamDict::new(&e.params);
        if ty == "stratified" {
            let side = |name: &str| -> Result<usize, Error> {
                let v = num(p, name, 4.0);
                if !(1.0..=4096.0).contains(&v) || v.fract() != 0.0 {
                    return Err(err(
                        loc,
                        format!(
                            "sampler \"stratified\": \"integer {name}\" {v}: expected 1 to 4096"
                        ),
                    ));
                }
                Ok(v as usize)
            };
            let (xs, ys) = (side("xsamples")?, side("ysamples")?);
            self.sampler = Sampler::Stratified {
                xs,
                ys,
                jitter: p.bool("jitter", true),
            };
            self.spp = xs * ys;
        } else {
            self.sampler = match ty.as_str() {
                "independent" => Sampler::Independent,
                "halton" => Sampler::Halton,
                "zsobol" | "sobol" => {
                    if ty == "sobol" {
                        self.warn(loc, "sampler \"sobol\" is rendered as \"zsobol\" (one Owen-scrambled Sobol sequence over the film, pixels in Morton order: the same stratification within and across pixels)".to_string());
                    }
                    Sampler::ZSobol { log2_spp: 0, digits: 0, seed: 0 }
                }
                "paddedsobol" | "pmj02bn" => {
                    if ty == "pmj02bn" {
                        self.warn(loc, "sampler \"pmj02bn\" is rendered as \"paddedsobol\" (Owen-scrambled (0, 2)-sequence pairs per pixel: the same stratification within a pixel)".to_string());
                    }
                    Sampler::PaddedSobol
                }
                _ => return Err(err(loc, format!("sampler \"{ty}\" is not a pbrt-v4 sampler (zsobol, sobol, paddedsobol, halton, pmj02bn, stratified, independent)"))),
            };
            if let Some(r) = string(p, "randomization") {
                if !matches!(r, "fastowen" | "owen") {
                    self.warn(loc, format!("sampler \"{ty}\": randomization \"{r}\" is rendered with Owen scrambling"));
                }
            }
            self.spp = num(p, "pixelsamples", 16.0).max(1.0) as usize;
        }
        self.finish(Kind::Sampler, ty, &format!("sampler \"{ty}\""), p)?;
        Ok(())
    }

    /// The integrator (every pbrt-v4 integrator is rendered with volpath) and its depth.
    pub(super) fn integrator(&mut self, e: &Entity) -> Result<(), Error> {
        let (ty, loc) = (&e.ty, &e.loc);
        // pbrt-v4's integrators: all rendered with volpath (a warning); anything else is an error.
        const PBRT_V4: [&str; 10] = [
            "volpath",
            "path",
            "bdpt",
            "mlt",
            "sppm",
            "simplepath",
            "simplevolpath",
            "randomwalk",
            "lightpath",
            "ambientocclusion",
        ];
        if !PBRT_V4.contains(&ty.as_str()) {
            return Err(err(
                loc,
                format!(
                    "integrator \"{ty}\" is not a pbrt-v4 integrator ({}){}",
                    PBRT_V4.join(", "),
                    v3::type_hint("integrator", ty)
                ),
            ));
        }
        if ty != "volpath" && ty != "path" {
            self.warn(loc, format!("integrator \"{ty}\" is rendered with volpath"));
        }
        let p = &ParamDict::new(&e.params);
        self.maxdepth = num(p, "maxdepth", 5.0).max(0.0) as usize;
        self.finish(Kind::Integrator, ty, &format!("integrator \"{ty}\""), p)?;
        Ok(())
    }

    /// The pixel filter.
    pub(super) fn filter(&mut self, e: &Entity) -> Result<(), Error> {
        let (ty, loc) = (&e.ty, &e.loc);
        let p = &ParamDict::new(&e.params);
        let r0 = Filter::default_radius(ty);
        let radius = [num(p, "xradius", r0), num(p, "yradius", r0)];
        if radius.iter().any(|r| !(*r > 0.0 && *r <= 64.0)) {
            return Err(err(
                loc,
                format!("pixel filter \"{ty}\": radius {radius:?}: expected 0 < r <= 64 pixels"),
            ));
        }
        let fp = FilterParams {
            radius,
            sigma: num(p, "sigma", 0.5),
            b: num(p, "B", 1.0 / 3.0),
            c: num(p, "C", 1.0 / 3.0),
            tau: num(p, "tau", 3.0),
        };
        if !(fp.sigma > 0.0 && fp.tau > 0.0 && fp.b.is_finite() && fp.c.is_finite()) {
            return Err(err(
                loc,
                format!(
                    "pixel filter \"{ty}\": sigma {}, tau {}: expected positive values",
                    fp.sigma, fp.tau
                ),
            ));
        }
        self.filter = Filter::new(ty, fp).ok_or_else(|| err(loc, format!("pixel filter \"{ty}\" is not a pbrt-v4 filter (box, gaussian, mitchell, sinc, triangle)")))?;
        self.finish(Kind::PixelFilter, ty, &format!("pixel filter \"{ty}\""), p)?;
        Ok(())
    }

    /// A `LightSource` under its transform.
    pub(super) fn light_source(&mut self, e: &Entity, ctm: DMat4) -> Result<(), Error> {
        let (ty, loc) = (&e.ty, &e.loc);
        let p = &ParamDict::new(&e.params);
        let scale = num(p, "scale", 1.0);
        let m = ctm;
        let pt = |v: Option<&[f64]>, def: [f64; 3]| {
            Vec3A::from(
                m.transform_point3(DVec3::from(v.map(|v| [v[0], v[1], v[2]]).unwrap_or(def)))
                    .as_vec3(),
            )
        };
        let l = match ty.as_str() {
            "point" => {
                // pbrt-v4: I in nits-equivalent ("scale /= SpectrumToPhotometric(I)"), `power` in W over 4π.
                let power = num(p, "power", -1.0);
                let k = if power > 0.0 { power / (4.0 * std::f64::consts::PI) } else { 1.0 };
                Light::Point(super::Point { p: pt(nums(p, "from"), [0.0; 3]), i: self.emitted(p, "I", true, scale * k)? })
            }
            "spot" => {
                let (from, to) = (pt(nums(p, "from"), [0.0; 3]), pt(nums(p, "to"), [0.0, 0.0, 1.0]));
                let cone = num(p, "coneangle", 30.0);
                let (cos_total, cos_falloff) = (cone.to_radians().cos(), (cone - num(p, "conedeltaangle", 5.0)).to_radians().cos());
                // pbrt-v4's `power`: over the cone, its smooth falloff counted at half.
                let power = num(p, "power", -1.0);
                let k_e = 2.0 * std::f64::consts::PI * ((1.0 - cos_falloff) + (cos_falloff - cos_total) / 2.0);
                let k = if power > 0.0 && k_e > 0.0 { power / k_e } else { 1.0 };
                Light::Spot(super::Spot {
                    p: from,
                    dir: (to - from).normalize_or_zero(),
                    cos_total: cos_total as f32,
                    cos_falloff: cos_falloff as f32,
                    i: self.emitted(p, "I", true, scale * k)?,
                })
            }
            "distant" => {
                let (from, to) = (pt(nums(p, "from"), [0.0; 3]), pt(nums(p, "to"), [0.0, 0.0, 1.0]));
                // `illuminance` in lux on a surface facing the light.
                let e = num(p, "illuminance", -1.0);
                Light::Distant(super::Distant { to_light: (from - to).normalize_or_zero(), l: self.emitted(p, "L", true, scale * if e > 0.0 { e } else { 1.0 })? })
            }
            "infinite" => {
                // pbrt-v4's portal: four corners in the light's space, to the world by the light's transform.
                let portal = match nums(p, "portal") {
                    None => None,
                    Some(v) => {
                        let at = p.get("portal").map_or(loc.clone(), |q| q.loc.clone());
                        if v.len() != 12 {
                            return Err(err(&at, format!("infinite light: \"point3 portal\" has {} values: expected 4 points (12 values)", v.len())));
                        }
                        let m = ctm;
                        let c = |i: usize| Vec3A::from(m.transform_point3(DVec3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2])).as_vec3());
                        Some(super::Portal::new([c(0), c(1), c(2), c(3)]).map_err(|e| err(&at, format!("infinite light: {e}")))?)
                    }
                };
                match string(p, "filename") {
                    Some(f) => {
                        if p.has("L") {
                            return Err(err(loc, "infinite light: give \"L\" or \"filename\", not both (as pbrt-v4)"));
                        }
                        // (Within what the scene's budget — `--max-memory` — leaves, not half the machine.)
                        let left = self.ctx.max_memory.saturating_sub(self.media_bytes);
                        let img = crate::imageio::read_within(&self.ctx.dir.join(f), false, left).map_err(|e| err(loc, format!("infinite light: {e}")))?;
                        if !(img.w == img.h || img.w == 2 * img.h) {
                            return Err(err(loc, format!("infinite light: a {}×{} map; expected a square equal-area map (pbrt-v4) or a 2:1 lat-long one", img.w, img.h)));
                        }
                        let to_light = Mat3A::from(DMat3::from_mat4(ctm).inverse().as_mat3());
                        // pbrt-v4: each texel is an illuminant rgb (× D65), the map scaled by 1 / the luminance of D65, so a
                        // texel (1, 1, 1) records Y = 1.
                        let white = self.bins.d65();
                        let basis = self.rgb_basis().map(|b| b * white * (1.0 / self.bins.luminance(&white)) as f32);
                        let dist = std::sync::Arc::new(crate::render::envmap::EnvSampler::new(&img));
                        // `illuminance` in lux on a patch facing the map's +z: the map scaled to give it.
                        let e_v = num(p, "illuminance", -1.0);
                        let k = if e_v > 0.0 {
                            let e = crate::render::envmap::upper_illuminance(&img);
                            if !(e > 0.0) {
                                return Err(err(loc, format!("infinite light: \"illuminance\" {e_v} asked of a map that is black above its horizon")));
                            }
                            e_v / e
                        } else {
                            1.0
                        };
                        let sky = super::Sky::Map { img: std::sync::Arc::new(img), to_light, scale: (scale * k) as f32, basis, dist };
                        Light::Infinite(super::Infinite { sky, portal })
                    }
                    None => {
                        // `illuminance` in lux on an upward-facing patch under the uniform sky: π L.
                        let e = num(p, "illuminance", -1.0);
                        let l = self.emitted(p, "L", true, scale * if e > 0.0 { e / std::f64::consts::PI } else { 1.0 })?;
                        Light::Infinite(super::Infinite { sky: super::Sky::Constant(l), portal })
                    }
                }
            }
            other => return Err(err(loc, format!("light \"{other}\" is not supported (point, spot, distant, infinite, and area diffuse)"))),
        };
        self.lights.push(l);
        self.finish(Kind::Light, ty, &format!("{ty} light"), p)?;
        Ok(())
    }

    /// A texture, under its name (textures made before it are named by its parameters).
    pub(super) fn texture(&mut self, t: &Texture) -> Result<(), Error> {
        let (class, loc, name) = (&t.entity.ty, &t.entity.loc, t.name.clone());
        let p = &ParamDict::new(&t.entity.params);
        let t = match class.as_str() {
            "checkerboard" => {
                let a = self
                    .spectrum(p, "tex1", Some(self.bins.mask()), RgbUse::Albedo)?
                    .unwrap_or(Tex::Const(S::ZERO));
                let b = self
                    .spectrum(p, "tex2", Some(S::ZERO), RgbUse::Albedo)?
                    .unwrap_or(Tex::Const(S::ZERO));
                Tex::Checker {
                    a: std::sync::Arc::new(a),
                    b: std::sync::Arc::new(b),
                    su: num(p, "uscale", 1.0) as f32,
                    sv: num(p, "vscale", 1.0) as f32,
                }
            }
            "constant" => self
                .spectrum(p, "value", Some(self.bins.mask()), RgbUse::Albedo)?
                .unwrap_or(Tex::Const(S::ZERO)),
            "imagemap" => {
                let f = string(p, "filename")
                    .ok_or_else(|| err(loc, "imagemap: missing \"string filename\""))?;
                let srgb = match string(p, "encoding").unwrap_or("sRGB") {
                    "sRGB" => true,
                    "linear" => false,
                    e => {
                        return Err(err(
                            loc,
                            format!("imagemap: encoding \"{e}\" is not supported (sRGB, linear)"),
                        ))
                    }
                };
                let wrap = match string(p, "wrap").unwrap_or("repeat") {
                    "repeat" => crate::imageio::Wrap::Repeat,
                    "clamp" => crate::imageio::Wrap::Clamp,
                    "black" => crate::imageio::Wrap::Black,
                    w => {
                        return Err(err(
                            loc,
                            format!("imagemap: wrap \"{w}\" is not one of repeat, clamp, black"),
                        ))
                    }
                };
                let left = self.ctx.max_memory.saturating_sub(self.media_bytes);
                let img = crate::imageio::read_within(&self.ctx.dir.join(f), srgb, left)
                    .map_err(|e| err(loc, format!("imagemap: {e}")))?;
                let invert = p.bool("invert", false);
                Tex::Image {
                    img: std::sync::Arc::new(img),
                    scale: num(p, "scale", 1.0) as f32,
                    invert,
                    wrap,
                    basis: self.rgb_basis(),
                }
            }
            other => {
                return Err(err(
                    loc,
                    format!(
                    "texture class \"{other}\" is not supported (checkerboard, constant, imagemap)"
                ),
                ))
            }
        };
        self.finish(
            Kind::Texture,
            class,
            &format!("{class} texture \"{name}\""),
            p,
        )?;
        self.textures.insert(name, t);
        Ok(())
    }

    /// An instance of an object built before it, under its transform.
    pub(super) fn instance(
        &mut self,
        object: &Arc<Bvh>,
        n: &str,
        ctm: &DMat4,
        loc: &Loc,
    ) -> Result<(), Error> {
        if object.prims.is_empty() {
            return Ok(());
        }
        self.room_for_prims(1, &format!("ObjectInstance \"{n}\""), loc)?;
        let first = self.prims.len();
        let to_world = affine_f32(ctm);
        self.prims.push(Prim {
            geom: Geom::Instance {
                to_world,
                to_obj: to_world.inverse(),
                object: object.clone(),
            },
            material: None,
            area_light: None,
            media: None,
            reverse: false,
        });
        self.check_bounds(first, &format!("ObjectInstance \"{n}\""), loc)?;
        Ok(())
    }

    /// An area light: what each shape given it emits (L, two-sided, the `power` in W each shape emits, or 0).
    pub(super) fn area_light(&mut self, e: &Entity) -> Result<(S, bool, f32), Error> {
        let p = &ParamDict::new(&e.params);
        if e.ty != "diffuse" {
            return Err(err(
                &e.loc,
                format!("area light \"{}\" is not supported (diffuse)", e.ty),
            ));
        }
        let l = self.emitted(p, "L", true, num(p, "scale", 1.0))?;
        let two = p.bool("twosided", false);
        let power = num(p, "power", -1.0).max(0.0) as f32;
        self.finish(Kind::AreaLight, &e.ty, "diffuse area light", p)?;
        Ok((l, two, power))
    }
}
