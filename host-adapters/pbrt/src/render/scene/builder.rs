//! The scene builder: what is built so far (materials, primitives, lights, media, the film's settings) and the
//! host's context (threads, memory budget, frame), with the helpers every `create` uses — spectra from
//! parameters, shapes' primitives, unread parameters reported (`finish`). The graphics state lives in the
//! reading (`description`); here each entity arrives with its own.

use super::description::Shape;
use super::{err, Error, Light, Material, Medium, MediumReport, Tex};
use crate::render::pbrt_v4::{self, Kind};
use crate::render::shapes::{Bvh, Geom, Prim};
use crate::render::spectrum::{Bins, S};
use firemedium_core::rgb_spectrum::RgbUse;
use firemedium_loader::Plugin;
use firemedium_pbrt_parser::{Loc, ParamDict};
use glam::{Affine3A, DAffine3, DMat3, DMat4, DVec3, Mat3A, Vec2, Vec3A};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

/// Where a shape's primitives go and what they are given: its material (built), area light, media (inside,
/// outside; built) and orientation.
#[derive(Clone, Copy)]
pub(super) struct Placement {
    pub(super) material: Option<usize>,
    /// The area light of its primitives: (L, two-sided, the `power` in W each shape emits, or 0).
    pub(super) area: Option<(S, bool, f32)>,
    pub(super) media: Option<(Option<usize>, Option<usize>)>,
    pub(super) reverse: bool,
}

/// What the `Film` directive says of the sensor and the output (the camera's shutter completes it in `load`).
#[derive(Debug, Clone, Copy)]
pub(super) struct FilmParams {
    pub(super) iso: f64,
    /// White balance temperature in K (0: none).
    pub(super) white_k: f64,
    pub(super) max_component: f64,
    pub(super) fp16: bool,
    /// A named camera sensor carried here (`render::sensors`); None: cie1931.
    pub(super) camera: Option<&'static str>,
}

impl Default for FilmParams {
    fn default() -> FilmParams {
        FilmParams {
            iso: 100.0,
            white_k: 0.0,
            max_component: f64::INFINITY,
            fp16: false,
            camera: None,
        }
    }
}

/// What a scene is built within, read by every statement and changed by none: the command line's settings.
pub(super) struct Context {
    /// The scene file's folder (relative names in it are read from there).
    pub(super) dir: PathBuf,
    /// Threads the plugin may use to build a medium (`Overrides::threads`).
    pub(super) threads: Option<usize>,
    /// The frame for every plugin medium (`--frames`), unless the scene sets one.
    pub(super) frame: Option<i64>,
    /// Plugin media tracked by the renderer through the medium level (`Overrides::host_tracking`).
    pub(super) host_tracking: bool,
    /// How the camera gathers a scattering plugin medium's emission (`Overrides::camera_march`).
    pub(super) camera_march: Option<bool>,
    /// The memory budget, bytes: each plugin grid's `maxbytes` unless the scene sets it.
    pub(super) max_memory: u64,
}

/// What building reports beside the scene: warnings, with the place in the scene's order of the statement each
/// is about, and what the plugin built for each medium.
#[derive(Default)]
pub(super) struct Reports {
    pub(super) warnings: Vec<(usize, String)>,
    pub(super) media: Vec<MediumReport>,
}

/// The scene being built, statement by statement, within its [`Context`], with its [`Reports`].
pub(super) struct Builder {
    pub(super) ctx: Context,
    pub(super) reports: Reports,
    pub(super) bins: Bins,
    pub(super) plugin: Option<Plugin>,
    /// The place in the scene's order of the statement being built (its warnings are reported in that order).
    pub(super) order: usize,
    pub(super) named_materials: HashMap<String, usize>,
    pub(super) textures: HashMap<String, Tex>,
    pub(super) named_media: HashMap<String, usize>,
    pub(super) materials: Vec<Material>,
    pub(super) prims: Vec<Prim>,
    pub(super) lights: Vec<Light>,
    pub(super) media: Vec<Medium>,
    /// Where each medium was defined (for what is found about it once the scene is built).
    pub(super) media_locs: Vec<Loc>,
    /// The camera's `shutteropen` and `shutterclose` (pbrt-v4's 0 and 1 when not given).
    pub(super) camera_shutter: [f64; 2],
    pub(super) res: (usize, usize),
    pub(super) spp: usize,
    pub(super) sampler: crate::render::pixel::Sampler,
    pub(super) filter: crate::render::pixel::Filter,
    pub(super) film_response: FilmParams,
    pub(super) spectral: Option<crate::render::film::Buckets>,
    pub(super) gbuffer: Option<crate::render::film::GBuffer>,
    /// The film's `cropwindow` (x0, x1, y0, y1 in [0, 1]) or `pixelbounds` (pixels), with where each was given.
    pub(super) crop: Option<([f64; 4], Loc)>,
    pub(super) pixel_bounds: Option<([f64; 4], Loc)>,
    pub(super) maxdepth: usize,
    pub(super) film_name: Option<String>,
    /// The objects' BVHs, in the description's order.
    pub(super) objects: Vec<Arc<Bvh>>,
    /// Primitives held by the objects defined so far (each once, however often it is instanced).
    pub(super) object_prims: usize,
    pub(super) current_object: Option<(String, Vec<Prim>)>,
    /// The scene's spectral bins, as the plugin's media are told them.
    pub(super) plugin_bins: firemedium_loader::Bins,
    /// The camera's shutter (frames) once a medium blurs by its velocity: each camera sample then draws a
    /// time in it.
    pub(super) shutter: Option<[f64; 2]>,
    /// Bytes the plugin media built so far hold (each new medium's `maxbytes` is what the budget has left).
    pub(super) media_bytes: u64,
    /// Whether the scene has a physical `fire` medium (its absolute units then set the film's).
    pub(super) has_fire: bool,
    /// The film's XYZ weights per bin, from the plugin that renders the media (`volume_channel_xyz` of the
    /// first medium in the film's units), and that medium's name; every further medium is checked against it.
    pub(super) film_xyz: Option<(String, Vec<DVec3>)>,
}

pub(super) fn nums<'a>(p: &ParamDict<'a>, name: &str) -> Option<&'a [f64]> {
    p.numbers(name)
}
pub(super) fn num(p: &ParamDict, name: &str, def: f64) -> f64 {
    p.float(name, def)
}
pub(super) fn string<'a>(p: &ParamDict<'a>, name: &str) -> Option<&'a str> {
    p.string(name)
}

pub(super) fn affine(m: &DMat4) -> DAffine3 {
    DAffine3::from_mat4(*m)
}

pub(super) fn affine_f32(m: &DMat4) -> Affine3A {
    let a = DAffine3::from_mat4(*m);
    Affine3A {
        matrix3: Mat3A::from(a.matrix3.as_mat3()),
        translation: a.translation.as_vec3().into(),
    }
}

impl Builder {
    /// A spectrum-valued parameter: rgb (as pbrt-v4 makes it a spectrum of its `usage`), spectrum (pairs or
    /// constant), blackbody; or a texture reference.
    pub(super) fn spectrum(
        &self,
        params: &ParamDict,
        name: &str,
        def: Option<S>,
        usage: RgbUse,
    ) -> Result<Option<Tex>, Error> {
        let Some(p) = params.get(name) else {
            return Ok(def.map(Tex::Const));
        };
        let s = match (p.ty.as_str(), &p.values) {
            ("rgb", _) => {
                let v = p.numbers().unwrap_or(&[]);
                self.bins.uplift([v[0], v[1], v[2]], usage)
            }
            ("spectrum", firemedium_pbrt_parser::Values::Numbers(v)) => self.bins.pairs(v),
            ("spectrum", firemedium_pbrt_parser::Values::Strings(v)) => {
                let n = v.first().map(String::as_str).unwrap_or("");
                let pairs = crate::render::named_spectra::lookup(n).ok_or_else(|| {
                    let near = firemedium_pbrt_parser::closest(n, crate::render::named_spectra::NAMES)
                        .map(|c| format!(" (did you mean \"{c}\"?)"))
                        .unwrap_or_default();
                    err(&p.loc, format!("\"spectrum {name}\" \"{n}\": no such named spectrum{near}; the named spectra are {}", crate::render::named_spectra::NAMES.join(", ")))
                })?;
                self.bins.pairs(&pairs)
            }
            ("blackbody", _) => self.bins.blackbody(p.numbers().unwrap_or(&[0.0])[0]),
            ("float", _) => S::splat(p.numbers().unwrap_or(&[0.0])[0] as f32) * self.bins.mask(),
            ("texture", _) => {
                let n = p.strings().and_then(|v| v.first()).cloned().unwrap_or_default();
                return self.textures.get(&n).cloned().map(Some).ok_or_else(|| err(&p.loc, format!("\"texture {name}\": no texture named \"{n}\"")));
            }
            (t, _) => return Err(err(&p.loc, format!("\"{t} {name}\": expected rgb, spectrum ((λ, value) pairs or a name), blackbody, float or texture"))),
        };
        Ok(Some(Tex::Const(s)))
    }

    /// A constant spectrum of the parameter `name`.
    pub(super) fn constant(
        &self,
        params: &ParamDict,
        name: &str,
        def: S,
        usage: RgbUse,
    ) -> Result<S, Error> {
        Ok(self
            .spectrum(params, name, Some(def), usage)?
            .map(|t| t.eval(Vec2::ZERO))
            .unwrap_or(S::ZERO))
    }

    /// An emitted spectrum as pbrt-v4 scales it "to be equivalent to 1 nit" (`SpectrumToPhotometric`): a light's
    /// `L`/`I` (default: the colour space's illuminant, D65) or a homogeneous medium's `Le` (default: none),
    /// divided by its luminance — for an rgb value, by its illuminant's alone, so `rgb L [1 1 1]` records Y = 1
    /// and `[1 0 0]` the luminance of red — and multiplied by `scale`. Luminances are the film's own (its bins
    /// and weights), so a normalised light records exactly that.
    pub(super) fn emitted(
        &self,
        params: &ParamDict,
        name: &str,
        default_d65: bool,
        scale: f64,
    ) -> Result<S, Error> {
        let white = self.bins.d65();
        let def = if default_d65 { white } else { S::ZERO };
        let s = self.constant(params, name, def, RgbUse::Illuminant)?;
        let rgb = params.get(name).is_some_and(|p| p.ty == "rgb");
        let y = self.bins.luminance(if rgb { &white } else { &s });
        if !(y > 0.0) || s.is_black() {
            return Ok(S::ZERO);
        }
        Ok(s * (scale / y) as f32)
    }

    /// The bins' box-uplift basis for red, green and blue.
    pub(super) fn rgb_basis(&self) -> [S; 3] {
        [
            self.bins.uplift_rgb([1.0, 0.0, 0.0]),
            self.bins.uplift_rgb([0.0, 1.0, 0.0]),
            self.bins.uplift_rgb([0.0, 0.0, 1.0]),
        ]
    }

    pub(super) fn warn(&mut self, loc: &Loc, m: impl std::fmt::Display) {
        self.reports
            .warnings
            .push((self.order, format!("{loc}: warning: {m}")));
    }

    /// Names every parameter of a directive that nothing read: a warning at the parameter when pbrt-v4 reads it
    /// (this renderer does not yet), an error with the closest name when pbrt-v4 does not know it either.
    pub(super) fn finish(
        &mut self,
        kind: Kind,
        ty: &str,
        what: &str,
        p: &ParamDict,
    ) -> Result<(), Error> {
        let names = pbrt_v4::parameters(kind, ty).unwrap_or_default();
        for (loc, w) in p.report_unused(what, &names)? {
            self.warn(&loc, w);
        }
        Ok(())
    }

    pub(super) fn add_prim(&mut self, geom: Geom, at: &Placement) {
        let mut prim = Prim {
            geom,
            material: at.material,
            area_light: None,
            media: at.media,
            reverse: at.reverse,
        };
        if let Some((_, objs)) = self.current_object.as_mut() {
            // An object's primitives are no area lights (pbrt-v4 leaves them out too; the reading warns).
            objs.push(prim);
            return;
        }
        if let Some((mut l, twosided, power)) = at.area {
            // pbrt-v4 makes an area light per shape (per triangle of a mesh): `power` is each one's, over its
            // area A and both sides when two-sided: L · (sides · A · π) = power.
            if power > 0.0 {
                let area = 1.0 / crate::render::area::sample_area(&prim, [0.5, 0.5]).2;
                let k = if twosided { 2.0 } else { 1.0 } * area * std::f32::consts::PI;
                if k > 0.0 && k.is_finite() {
                    l = l * (power / k);
                }
            }
            prim.area_light = Some(self.lights.len());
            self.lights.push(Light::Area(super::Area {
                prim: self.prims.len(),
                l,
                twosided,
            }));
        }
        self.prims.push(prim);
    }

    /// An error unless `n` more primitives (with their BVH nodes) fit in the memory budget beside the scene's:
    /// checked before they are made (a mesh by its face count; an instance is one primitive over its object's
    /// shared BVH).
    /// pbrt-v4's `loopsubdiv`: the control mesh `P`, `indices` subdivided `levels` times (default 3) and pushed
    /// to the limit surface, as a triangle mesh with smooth normals.
    #[allow(clippy::type_complexity)]
    fn loop_subdivide(
        &self,
        p: &ParamDict,
        pos: Vec<f64>,
        idx: Vec<usize>,
        loc: &Loc,
    ) -> Result<(Vec<f64>, Vec<usize>, Option<Vec<f64>>, Option<Vec<f64>>), Error> {
        use crate::render::subdiv;
        let levels = num(p, "levels", 3.0);
        if !(0.0..=subdiv::MAX_LEVELS as f64).contains(&levels) || levels.fract() != 0.0 {
            return Err(err(
                loc,
                format!(
                    "loopsubdiv: \"integer levels\" {levels}: expected 0 to {}",
                    subdiv::MAX_LEVELS
                ),
            ));
        }
        let levels = levels as u32;
        let nv = pos.len() / 3;
        if pos.len() % 3 != 0 || idx.len() % 3 != 0 || idx.iter().any(|&i| i >= nv) {
            return Err(err(
                loc,
                format!("loopsubdiv: indices must come in 3s and be below the {nv} vertices"),
            ));
        }
        // Its final triangles, and the same again for the subdivision's working copies (edges, rings).
        let tris = ((idx.len() / 3) as u64).saturating_mul(1u64 << (2 * levels));
        self.room_for_prims(
            usize::try_from(tris.saturating_mul(2)).unwrap_or(usize::MAX),
            "loopsubdiv",
            loc,
        )?;
        let control = subdiv::Mesh {
            p: pos.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            tris: idx
                .chunks(3)
                .map(|c| [c[0] as u32, c[1] as u32, c[2] as u32])
                .collect(),
        };
        let m = subdiv::subdivide(&control, levels);
        let n = subdiv::normals(&m);
        Ok((
            m.p.concat(),
            m.tris.iter().flatten().map(|&i| i as usize).collect(),
            Some(n.concat()),
            None,
        ))
    }

    pub(super) fn room_for_prims(&self, n: usize, what: &str, loc: &Loc) -> Result<(), Error> {
        // A primitive, its BVH leaf reference and its share of the nodes: about 2.5 × its own size.
        let each = (std::mem::size_of::<Prim>() as u64) * 5 / 2;
        let open = self.current_object.as_ref().map_or(0, |(_, o)| o.len());
        let total = [self.prims.len(), self.object_prims, open, n]
            .iter()
            .fold(0u64, |a, &k| a.saturating_add(k as u64));
        crate::budget::check(
            &format!("{what}: {total} primitives"),
            total,
            each,
            self.ctx.max_memory,
        )
        .map_err(|e| err(loc, e))
    }

    /// Primitives built so far where new ones go (the open object's, or the scene's).
    fn prim_count(&self) -> usize {
        match &self.current_object {
            Some((_, objs)) => objs.len(),
            None => self.prims.len(),
        }
    }

    /// The primitives a shape added since `first` must have finite bounds in f32: a radius of 1e39, or a
    /// `Scale 1e300`, overflows them, and the BVH build would panic on it.
    pub(super) fn check_bounds(
        &mut self,
        first: usize,
        what: &str,
        loc: &Loc,
    ) -> Result<(), Error> {
        let prims = match &self.current_object {
            Some((_, objs)) => &objs[first..],
            None => &self.prims[first..],
        };
        if let Some(prim) = prims.iter().find(|pr| {
            let b = obvhs::Boundable::aabb(*pr);
            !(b.min.is_finite() && b.max.is_finite())
        }) {
            let b = obvhs::Boundable::aabb(prim);
            return Err(err(
                loc,
                format!(
                    "{what}: its bounds {:?}–{:?} do not fit in f32 (±3.4e38): expected finite geometry (a huge radius, coordinate or scale?)",
                    b.min.to_array(),
                    b.max.to_array()
                ),
            ));
        }
        Ok(())
    }

    /// A shape's primitives, placed by `at` (built from the shape's state by `load`).
    pub(super) fn shape(&mut self, shape: &Shape, at: &Placement) -> Result<(), Error> {
        let (ty, loc) = (shape.entity.ty.as_str(), &shape.entity.loc);
        let p = &ParamDict::new(&shape.entity.params);
        let to_world = affine_f32(&shape.ctm);
        let to_obj = to_world.inverse();
        let first = self.prim_count();
        match ty {
            "sphere" => {
                let r = num(p, "radius", 1.0);
                if !r.is_finite() {
                    return Err(err(loc, format!("sphere: radius {r}: expected a finite number")));
                }
                // pbrt-v4: z clamped to [−r, r] and ordered (a negative radius is the same sphere); φmax clamped
                // to [0°, 360°].
                let ra = r.abs();
                let (z0, z1) = (num(p, "zmin", -ra).clamp(-ra, ra), num(p, "zmax", ra).clamp(-ra, ra));
                let phimax = num(p, "phimax", 360.0).clamp(0.0, 360.0).to_radians();
                self.add_prim(Geom::Sphere {
                    to_world,
                    to_obj,
                    r: r as f32,
                    zmin: z0.min(z1) as f32,
                    zmax: z0.max(z1) as f32,
                    phimax: phimax as f32,
                }, at);
            }
            "disk" => {
                let phimax = num(p, "phimax", 360.0).clamp(0.0, 360.0).to_radians() as f32;
                self.add_prim(Geom::Disk { to_world, to_obj, h: num(p, "height", 0.0) as f32, r: num(p, "radius", 1.0) as f32, ri: num(p, "innerradius", 0.0) as f32, phimax }, at);
            }
            "cylinder" => {
                let phimax = num(p, "phimax", 360.0).clamp(0.0, 360.0).to_radians() as f32;
                let (z0, z1) = (num(p, "zmin", -1.0), num(p, "zmax", 1.0));
                self.add_prim(Geom::Cylinder { to_world, to_obj, r: num(p, "radius", 1.0) as f32, zmin: z0.min(z1) as f32, zmax: z0.max(z1) as f32, phimax }, at);
            }
            "trianglemesh" | "bilinearmesh" | "plymesh" | "loopsubdiv" => {
                let (pos, idx, normals, uvs) = if ty == "plymesh" {
                    let f = string(p, "filename").ok_or_else(|| err(loc, "plymesh: missing \"string filename\""))?;
                    crate::render::ply::read(&self.ctx.dir.join(f), self.ctx.max_memory).map_err(|e| err(loc, e))?
                } else {
                    let pos = nums(p, "P").ok_or_else(|| err(loc, format!("{ty}: missing \"point3 P\"")))?.to_vec();
                    let idx: Vec<usize> = match nums(p, "indices") {
                        Some(v) => {
                            // (A cast would turn -1 into vertex 0 silently.)
                            if let Some((k, x)) = v.iter().enumerate().find(|(_, x)| !(**x >= 0.0 && x.fract() == 0.0 && **x <= u32::MAX as f64)) {
                                return Err(err(loc, format!("{ty}: \"integer indices\" [{k}] = {x}: expected a vertex number from 0")));
                            }
                            v.iter().map(|&x| x as usize).collect()
                        }
                        None if ty == "trianglemesh" && pos.len() == 9 => vec![0, 1, 2],
                        None if ty == "bilinearmesh" && pos.len() == 12 => vec![0, 1, 2, 3],
                        None => return Err(err(loc, format!("{ty}: missing \"integer indices\""))),
                    };
                    if ty == "loopsubdiv" {
                        self.loop_subdivide(p, pos, idx, loc)?
                    } else {
                        (pos, idx, nums(p, "N").map(|v| v.to_vec()), nums(p, "uv").map(|v| v.to_vec()))
                    }
                };
                let nv = pos.len() / 3;
                let per = if ty == "bilinearmesh" { 4 } else { 3 };
                self.room_for_prims(idx.len() / per * (per - 2), ty, loc)?;
                if idx.len() % per != 0 || idx.iter().any(|&i| i >= nv) {
                    return Err(err(loc, format!("{ty}: indices must come in {per}s and be below the {nv} vertices")));
                }
                let m = shape.ctm;
                let vp = |i: usize| Vec3A::from(m.transform_point3(DVec3::new(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2])).as_vec3());
                let nm = DMat3::from_mat4(m).inverse().transpose();
                let vn = |i: usize| normals.as_ref().filter(|n| n.len() == pos.len()).map(|n| Vec3A::from((nm * DVec3::new(n[3 * i], n[3 * i + 1], n[3 * i + 2])).normalize_or_zero().as_vec3()));
                let vt = |i: usize| uvs.as_ref().filter(|u| u.len() == 2 * nv).map(|u| Vec2::new(u[2 * i] as f32, u[2 * i + 1] as f32)).unwrap_or(Vec2::ZERO);
                let tri = |b: &mut Builder, a: usize, c: usize, d: usize| {
                    let n = match (vn(a), vn(c), vn(d)) {
                        (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                        _ => None,
                    };
                    b.add_prim(Geom::Triangle { p: [vp(a), vp(c), vp(d)], n, uv: [vt(a), vt(c), vt(d)] }, at);
                };
                for f in idx.chunks(per) {
                    if per == 4 {
                        // pbrt's bilinear patch vertex order: p00 p10 p01 p11 → two triangles.
                        tri(self, f[0], f[1], f[3]);
                        tri(self, f[0], f[3], f[2]);
                    } else {
                        tri(self, f[0], f[1], f[2]);
                    }
                }
            }
            other => return Err(err(loc, format!("shape \"{other}\" is not supported (sphere, disk, cylinder, trianglemesh, bilinearmesh, plymesh, loopsubdiv)"))),
        }
        self.check_bounds(first, ty, loc)?;
        self.finish(Kind::Shape, ty, ty, p)
    }
}
