//! pbrt-v4 scene → render scene. Walks the parser's directives with pbrt's graphics state (CTM, attribute stack,
//! named materials/textures/media, object instances). Everything a fire scene needs is built; anything else is
//! reported by name: ignored with a warning when it cannot change the picture much, refused with an error when
//! it would be misread.

use super::pbrt_v4::{self, Kind};
use super::shapes::{Bvh, Geom, Prim};
use super::spectrum::{Bins, S};
use firemedium_core::spectrum::SpectralGrid;
use firemedium_loader::{Param as LParam, Plugin, Value, Volume};
use firemedium_pbrt_parser::{parse_file, Collect, Directive, Loc, Param, ParamDict};
use glam::{Affine3A, DAffine3, DMat3, DMat4, DVec3, Mat3A, Vec2, Vec3A};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A scene error: where and what.
pub type Error = String;

fn err(loc: &Loc, m: impl std::fmt::Display) -> Error {
    format!("{loc}: {m}")
}

/// A spectrum texture.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // constants are the common case; boxing them would cost a pointer chase per lookup
pub enum Tex {
    Const(S),
    Checker {
        a: Box<Tex>,
        b: Box<Tex>,
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

/// Surface materials.
#[derive(Debug, Clone)]
pub enum Material {
    Diffuse(Tex),
    /// Smooth mirror with this reflectance.
    Conductor(S),
    /// Smooth glass of this index.
    Dielectric(f32),
    /// Diffuse base under a smooth dielectric coat.
    CoatedDiffuse(Tex, f32),
}

/// Lights (area lights live on primitives).
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene
pub enum Light {
    Point {
        p: Vec3A,
        i: S,
    },
    Spot {
        p: Vec3A,
        dir: Vec3A,
        cos_total: f32,
        cos_falloff: f32,
        i: S,
    },
    Distant {
        to_light: Vec3A,
        l: S,
    },
    Infinite {
        l: S,
    },
    /// An environment map: world → light-space rotation, linear RGB × scale, equal-area square (pbrt-v4) or
    /// lat-long (2:1) parameterisation.
    InfiniteMap {
        img: std::sync::Arc<crate::imageio::RgbImage>,
        to_light: Mat3A,
        scale: f32,
        basis: [S; 3],
    },
    /// The fire light of plugin medium `medium` (importance-samples its emission).
    Fire {
        light: std::sync::Arc<firemedium_loader::Light>,
        medium: usize,
    },
    Area {
        prim: usize,
        l: S,
        twosided: bool,
    },
}

/// Participating media.
#[allow(clippy::large_enum_variant)] // a handful per scene
pub enum Medium {
    /// A fire (or pbrt grid medium) living in the plugin; `to_medium` maps world to medium space.
    Plugin {
        vol: Volume,
        to_medium: DAffine3,
        /// The inverse of `to_medium`.
        to_world: DAffine3,
        scatters: bool,
        g: f64,
        name: String,
    },
    /// pbrt's homogeneous medium.
    Homogeneous { sa: S, ss: S, le: S, g: f64 },
}

impl std::fmt::Debug for Medium {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Medium::Plugin { name, .. } => write!(f, "Plugin({name})"),
            Medium::Homogeneous { .. } => write!(f, "Homogeneous"),
        }
    }
}

/// Perspective camera.
#[derive(Debug, Clone)]
pub struct Camera {
    pub to_world: DAffine3,
    pub tan_half: f64,
    pub screen: [f64; 4],
    pub lens_radius: f64,
    pub focal_distance: f64,
    pub medium: Option<usize>,
}

/// What the plugin built for one medium.
#[derive(Debug, Clone)]
pub struct MediumReport {
    pub name: String,
    pub bytes: u64,
    pub seconds: f64,
    pub channels: u32,
    /// The fire light, when built: (emitting voxels, W, lm, bytes, seconds).
    pub light: Option<(u64, f64, f64, u64, f64)>,
}

/// A render-ready scene.
#[derive(Debug)]
pub struct Scene {
    pub bins: Bins,
    pub bvh: Bvh,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub media: Vec<Medium>,
    pub camera: Camera,
    pub res: (usize, usize),
    pub spp: usize,
    pub maxdepth: usize,
    pub film_name: Option<String>,
    pub eps: f32,
    pub warnings: Vec<String>,
    pub media_reports: Vec<MediumReport>,
}

impl Scene {
    /// The hottest temperature (K) of the scene's fire media, if any has a temperature grid.
    pub fn fire_temperature(&self) -> Option<f64> {
        self.media
            .iter()
            .filter_map(|m| match m {
                Medium::Plugin { vol, .. } => vol.temperature_range().ok().flatten(),
                _ => None,
            })
            .map(|[_, hi]| hi)
            .filter(|t| *t > 0.0)
            .reduce(f64::max)
    }
}

#[derive(Clone)]
struct State {
    ctm: DMat4,
    reverse: bool,
    material: Option<usize>,
    area: Option<(S, bool)>,
    inside: String,
    outside: String,
}

struct Builder {
    dir: PathBuf,
    bins: Bins,
    plugin_path: Option<PathBuf>,
    plugin: Option<Plugin>,
    st: State,
    stack: Vec<State>,
    named_coords: HashMap<String, DMat4>,
    named_materials: HashMap<String, usize>,
    textures: HashMap<String, Tex>,
    named_media: HashMap<String, usize>,
    materials: Vec<Material>,
    prims: Vec<Prim>,
    lights: Vec<Light>,
    media: Vec<Medium>,
    media_reports: Vec<MediumReport>,
    /// The Camera directive: parameters, camera-from-world, medium, position (built once the film is known).
    camera: Option<(Vec<Param>, DMat4, Option<usize>, Loc)>,
    res: (usize, usize),
    spp: usize,
    maxdepth: usize,
    film_name: Option<String>,
    warnings: Vec<String>,
    objects: HashMap<String, Vec<Prim>>,
    current_object: Option<(String, Vec<Prim>)>,
    bins_params: Vec<LParam>,
    /// Threads the plugin may use to build a medium (`Overrides::threads`).
    threads: Option<usize>,
    /// Whether the scene has a physical `fire` medium (its absolute units then set the film's).
    has_fire: bool,
    /// The film's XYZ weights per bin, from the plugin that renders the media (`volume_channel_xyz` of the
    /// first medium in the film's units), and that medium's name; every further medium is checked against it.
    film_xyz: Option<(String, Vec<DVec3>)>,
}

fn nums<'a>(p: &ParamDict<'a>, name: &str) -> Option<&'a [f64]> {
    p.numbers(name)
}
fn num(p: &ParamDict, name: &str, def: f64) -> f64 {
    p.float(name, def)
}
fn string<'a>(p: &ParamDict<'a>, name: &str) -> Option<&'a str> {
    p.string(name)
}

fn affine(m: &DMat4) -> DAffine3 {
    DAffine3::from_mat4(*m)
}

fn affine_f32(m: &DMat4) -> Affine3A {
    let a = DAffine3::from_mat4(*m);
    Affine3A {
        matrix3: Mat3A::from(a.matrix3.as_mat3()),
        translation: a.translation.as_vec3().into(),
    }
}

/// pbrt-v4's LookAt: the camera-from-world matrix (pbrt's left-handed camera space).
fn look_at(v: &[f64; 9]) -> DMat4 {
    let (pos, look, up) = (
        DVec3::new(v[0], v[1], v[2]),
        DVec3::new(v[3], v[4], v[5]),
        DVec3::new(v[6], v[7], v[8]),
    );
    let dir = (look - pos).normalize_or_zero();
    let right = up.normalize_or_zero().cross(dir).normalize_or_zero();
    let new_up = dir.cross(right);
    let world_from_camera = DMat4::from_cols(
        right.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        pos.extend(1.0),
    );
    world_from_camera.inverse()
}

impl Builder {
    /// A spectrum-valued parameter: rgb, spectrum (pairs or constant), blackbody; or a texture reference.
    fn spectrum(
        &self,
        params: &ParamDict,
        name: &str,
        def: Option<S>,
    ) -> Result<Option<Tex>, Error> {
        let Some(p) = params.get(name) else {
            return Ok(def.map(Tex::Const));
        };
        let s = match (p.ty.as_str(), &p.values) {
            ("rgb", _) => {
                let v = p.numbers().unwrap_or(&[]);
                self.bins.uplift_rgb([v[0], v[1], v[2]])
            }
            ("spectrum", firemedium_pbrt_parser::Values::Numbers(v)) => self.bins.pairs(v),
            ("blackbody", _) => self.bins.blackbody(p.numbers().unwrap_or(&[0.0])[0]),
            ("float", _) => S::splat(p.numbers().unwrap_or(&[0.0])[0] as f32) * self.bins.mask(),
            ("texture", _) => {
                let n = p.strings().and_then(|v| v.first()).cloned().unwrap_or_default();
                return self.textures.get(&n).cloned().map(Some).ok_or_else(|| err(&p.loc, format!("\"texture {name}\": no texture named \"{n}\"")));
            }
            (t, _) => return Err(err(&p.loc, format!("\"{t} {name}\": named spectra are not supported; give rgb, (λ, value) pairs or blackbody"))),
        };
        Ok(Some(Tex::Const(s)))
    }

    /// The bins' box-uplift basis for red, green and blue.
    fn rgb_basis(&self) -> [S; 3] {
        [
            self.bins.uplift_rgb([1.0, 0.0, 0.0]),
            self.bins.uplift_rgb([0.0, 1.0, 0.0]),
            self.bins.uplift_rgb([0.0, 0.0, 1.0]),
        ]
    }

    fn warn(&mut self, loc: &Loc, m: impl std::fmt::Display) {
        self.warnings.push(format!("{loc}: warning: {m}"));
    }

    /// Names every parameter of a directive that nothing read: a warning at the parameter when pbrt-v4 reads it
    /// (this renderer does not yet), an error with the closest name when pbrt-v4 does not know it either.
    fn finish(&mut self, kind: Kind, ty: &str, what: &str, p: &ParamDict) -> Result<(), Error> {
        let names = pbrt_v4::parameters(kind, ty).unwrap_or_default();
        for (loc, w) in p.report_unused(what, &names).map_err(|e| e.to_string())? {
            self.warn(&loc, w);
        }
        Ok(())
    }

    fn add_prim(&mut self, geom: Geom) {
        let light = self.st.area;
        let media = if self.st.inside.is_empty() && self.st.outside.is_empty() {
            None
        } else {
            let look = |n: &str| {
                if n.is_empty() {
                    None
                } else {
                    self.named_media.get(n).copied()
                }
            };
            Some((look(&self.st.inside), look(&self.st.outside)))
        };
        let mut prim = Prim {
            geom,
            material: self.st.material,
            area_light: None,
            media,
            reverse: self.st.reverse,
        };
        if let Some((_, objs)) = self.current_object.as_mut() {
            objs.push(prim);
            return;
        }
        if let Some((l, twosided)) = light {
            prim.area_light = Some(self.lights.len());
            self.lights.push(Light::Area {
                prim: self.prims.len(),
                l,
                twosided,
            });
        }
        self.prims.push(prim);
    }

    fn plugin(&mut self, loc: &Loc) -> Result<Plugin, Error> {
        if let Some(p) = &self.plugin {
            return Ok(p.clone());
        }
        let p = match &self.plugin_path {
            Some(path) => load_plugin(Some(path)),
            None => load_plugin(None),
        }
        .map_err(|e| err(loc, e))?;
        self.plugin = Some(p.clone());
        Ok(p)
    }

    /// Takes the film's colour from the plugin: the medium's bins must be the renderer's, and the first medium in
    /// the film's units (a `fire` when the scene has one, else any) gives the XYZ weights of every bin. A further
    /// medium must agree with them up to its units' scale, so a plugin built from another commit, or media that
    /// project their bins differently, are refused instead of rendering a silently wrong colour.
    fn check_colour(
        &mut self,
        name: &str,
        fire: bool,
        vol: &Volume,
        loc: &Loc,
    ) -> Result<(), Error> {
        let info = vol.info();
        let (lo, hi) = (self.bins.grid.min_nm(), self.bins.grid.max_nm());
        if (info.lambda_min - lo).abs() > 1e-9 * hi || (info.lambda_max - hi).abs() > 1e-9 * hi {
            return Err(err(loc, format!("medium \"{name}\": the plugin's bins span {}–{} nm, the renderer's {lo}–{hi} nm (all media share the scene's bins)", info.lambda_min, info.lambda_max)));
        }
        let xyz: Vec<DVec3> = vol
            .channel_xyz()
            .map_err(|e| err(loc, format!("medium \"{name}\": {e}")))?
            .into_iter()
            .map(DVec3::from_array)
            .collect();
        match &self.film_xyz {
            None if fire || !self.has_fire => {
                self.film_xyz = Some((name.to_string(), xyz));
                Ok(())
            }
            None => Ok(()),
            Some((first, want)) => {
                // The same projection up to one scale (physical and pbrt units differ by a constant).
                let y = |w: &[DVec3]| w.iter().map(|v| v.y).sum::<f64>();
                let k = y(want) / y(&xyz);
                let worst = want
                    .iter()
                    .zip(&xyz)
                    .map(|(a, b)| {
                        (*a - *b * k).abs().max_element() / a.abs().max_element().max(1e-300)
                    })
                    .fold(0.0, f64::max);
                if worst.is_finite() && worst < 1e-6 {
                    Ok(())
                } else {
                    Err(err(loc, format!("medium \"{name}\": its bins project to XYZ differently from medium \"{first}\"'s (largest relative difference {worst:.3e}); are both from the same plugin?")))
                }
            }
        }
    }

    fn medium(&mut self, name: &str, params: &ParamDict, loc: &Loc) -> Result<(), Error> {
        let ty = string(params, "type").unwrap_or("").to_string();
        let to_medium = affine(&self.st.ctm.inverse());
        let m = match ty.as_str() {
            "homogeneous" => {
                let scale = num(params, "scale", 1.0) as f32;
                let sa = self.spectrum(params, "sigma_a", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale;
                let ss = self.spectrum(params, "sigma_s", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale;
                let le = self.spectrum(params, "Le", Some(S::ZERO))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * num(params, "Lescale", 1.0) as f32;
                Medium::Homogeneous { sa, ss, le, g: num(params, "g", 0.0).clamp(-0.99, 0.99) }
            }
            "fire" | "uniformgrid" | "nanovdb" => {
                // Parameters pass to the plugin unchanged, but for the type, the plugin file, and relative paths.
                if let Some(p) = string(params, "plugin") {
                    self.plugin_path = Some(self.dir.join(p));
                }
                let plugin = self.plugin(loc)?;
                // The plugin reads and checks every parameter itself, reporting any it does not use.
                params.mark_all_used();
                let mut list: Vec<LParam> = Vec::new();
                for p in params.params() {
                    if p.name == "type" || p.name == "plugin" {
                        continue;
                    }
                    let value = match (&p.values, p.ty.as_str()) {
                        (firemedium_pbrt_parser::Values::Strings(v), _) => {
                            let files = ["filename", "dataset", "densityfile", "temperaturefile", "speciesfiles"];
                            Value::String(v.iter().map(|s| if files.contains(&p.name.as_str()) && !Path::new(s).is_absolute() { self.dir.join(s).display().to_string() } else { s.clone() }).collect())
                        }
                        (firemedium_pbrt_parser::Values::Bools(v), _) => Value::Bool(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "integer") => Value::Integer(v.iter().map(|&x| x as i64).collect()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "point3") => Value::Point3(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "vector3") => Value::Vector3(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "rgb") => Value::Rgb(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "spectrum") => Value::Spectrum(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), _) => Value::Float(v.clone()),
                    };
                    list.push(LParam { name: p.name.clone(), value, at: Some(p.loc.to_string()) });
                }
                if ty != "fire" {
                    list.push(LParam::string("mode", "pbrt"));
                }
                for b in &self.bins_params {
                    if !list.iter().any(|p| p.name == b.name) {
                        list.push(b.clone());
                    }
                }
                if let Some(n) = self.threads {
                    if !list.iter().any(|p| p.name == "threads") {
                        list.push(LParam::int("threads", n as i64));
                    }
                }
                let vol = plugin.create_volume(&list).map_err(|e| {
                    // An error about one parameter begins with where it was given: report it there.
                    let text = e.to_string();
                    let at = params.params().iter().find_map(|p| text.strip_prefix(&format!("{}: ", p.loc)).map(|rest| (&p.loc, rest)));
                    match at {
                        Some((ploc, rest)) => err(ploc, format!("medium \"{name}\" ({ty}): {rest}")),
                        None => err(loc, format!("medium \"{name}\" ({ty}): {text}")),
                    }
                })?;
                let info = vol.info();
                if info.channel_space != firemedium_abi::FM_SPACE_SPECTRAL || info.channels as usize != self.bins.n() {
                    return Err(err(loc, format!("medium \"{name}\": {} channels in space {}, but the renderer uses {} spectral bins (all media share the scene's bins; colormode rgb is for other hosts)", info.channels, info.channel_space, self.bins.n())));
                }
                self.check_colour(name, ty == "fire", &vol, loc)?;
                self.media_reports.push(MediumReport { name: name.to_string(), bytes: info.bytes, seconds: info.build_seconds, channels: info.channels, light: None });
                Medium::Plugin { vol, to_medium, to_world: to_medium.inverse(), scatters: info.scatters != 0, g: info.g, name: name.to_string() }
            }
            "" => return Err(err(loc, format!("MakeNamedMedium \"{name}\": missing \"string type\""))),
            other => return Err(err(loc, format!("MakeNamedMedium \"{name}\": medium type \"{other}\" is not supported (fire, uniformgrid, nanovdb, homogeneous)"))),
        };
        self.named_media.insert(name.to_string(), self.media.len());
        self.media.push(m);
        Ok(())
    }

    fn shape(&mut self, ty: &str, p: &ParamDict, loc: &Loc) -> Result<(), Error> {
        let to_world = affine_f32(&self.st.ctm);
        let to_obj = to_world.inverse();
        match ty {
            "sphere" => {
                let r = num(p, "radius", 1.0) as f32;
                if nums(p, "zmin").is_some() || nums(p, "zmax").is_some() || nums(p, "phimax").is_some() {
                    self.warn(loc, "sphere: partial spheres (zmin, zmax, phimax) are rendered whole");
                }
                self.add_prim(Geom::Sphere { to_world, to_obj, r });
            }
            "disk" => {
                self.add_prim(Geom::Disk { to_world, to_obj, h: num(p, "height", 0.0) as f32, r: num(p, "radius", 1.0) as f32, ri: num(p, "innerradius", 0.0) as f32 });
            }
            "cylinder" => {
                self.add_prim(Geom::Cylinder { to_world, to_obj, r: num(p, "radius", 1.0) as f32, zmin: num(p, "zmin", -1.0) as f32, zmax: num(p, "zmax", 1.0) as f32 });
            }
            "trianglemesh" | "bilinearmesh" | "plymesh" => {
                let (pos, idx, normals, uvs) = if ty == "plymesh" {
                    let f = string(p, "filename").ok_or_else(|| err(loc, "plymesh: missing \"string filename\""))?;
                    super::ply::read(&self.dir.join(f)).map_err(|e| err(loc, e))?
                } else {
                    let pos = nums(p, "P").ok_or_else(|| err(loc, format!("{ty}: missing \"point3 P\"")))?.to_vec();
                    let idx: Vec<usize> = match nums(p, "indices") {
                        Some(v) => v.iter().map(|&x| x as usize).collect(),
                        None if ty == "trianglemesh" && pos.len() == 9 => vec![0, 1, 2],
                        None if ty == "bilinearmesh" && pos.len() == 12 => vec![0, 1, 2, 3],
                        None => return Err(err(loc, format!("{ty}: missing \"integer indices\""))),
                    };
                    (pos, idx, nums(p, "N").map(|v| v.to_vec()), nums(p, "uv").map(|v| v.to_vec()))
                };
                let nv = pos.len() / 3;
                let per = if ty == "bilinearmesh" { 4 } else { 3 };
                if idx.len() % per != 0 || idx.iter().any(|&i| i >= nv) {
                    return Err(err(loc, format!("{ty}: indices must come in {per}s and be below the {nv} vertices")));
                }
                let m = self.st.ctm;
                let vp = |i: usize| Vec3A::from(m.transform_point3(DVec3::new(pos[3 * i], pos[3 * i + 1], pos[3 * i + 2])).as_vec3());
                let nm = DMat3::from_mat4(m).inverse().transpose();
                let vn = |i: usize| normals.as_ref().filter(|n| n.len() == pos.len()).map(|n| Vec3A::from((nm * DVec3::new(n[3 * i], n[3 * i + 1], n[3 * i + 2])).normalize_or_zero().as_vec3()));
                let vt = |i: usize| uvs.as_ref().filter(|u| u.len() == 2 * nv).map(|u| Vec2::new(u[2 * i] as f32, u[2 * i + 1] as f32)).unwrap_or(Vec2::ZERO);
                let tri = |b: &mut Builder, a: usize, c: usize, d: usize| {
                    let n = match (vn(a), vn(c), vn(d)) {
                        (Some(x), Some(y), Some(z)) => Some([x, y, z]),
                        _ => None,
                    };
                    b.add_prim(Geom::Triangle { p: [vp(a), vp(c), vp(d)], n, uv: [vt(a), vt(c), vt(d)] });
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
            other => return Err(err(loc, format!("shape \"{other}\" is not supported (sphere, disk, cylinder, trianglemesh, bilinearmesh, plymesh)"))),
        }
        Ok(())
    }

    fn material(&mut self, ty: &str, p: &ParamDict, loc: &Loc) -> Result<Option<usize>, Error> {
        let m = match ty {
            "interface" | "" => return Ok(None),
            "diffuse" => {
                Material::Diffuse(self.spectrum(p, "reflectance", Some(self.bins.mask() * 0.5))?.unwrap_or(Tex::Const(S::ZERO)))
            }
            "coateddiffuse" => {
                Material::CoatedDiffuse(self.spectrum(p, "reflectance", Some(self.bins.mask() * 0.5))?.unwrap_or(Tex::Const(S::ZERO)), num(p, "eta", 1.5) as f32)
            }
            "conductor" => {
                let r = self.spectrum(p, "reflectance", Some(self.bins.mask() * 0.9))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO);
                Material::Conductor(r)
            }
            "dielectric" | "thindielectric" => {
                Material::Dielectric(num(p, "eta", 1.5) as f32)
            }
            other => return Err(err(loc, format!("material \"{other}\" is not supported (diffuse, coateddiffuse, conductor, dielectric, interface)"))),
        };
        self.materials.push(m);
        Ok(Some(self.materials.len() - 1))
    }

    fn directive(&mut self, d: Directive, loc: &Loc) -> Result<(), Error> {
        let ctm = &mut self.st.ctm;
        match d {
            Directive::Identity => *ctm = DMat4::IDENTITY,
            Directive::Translate(v) => *ctm *= DMat4::from_translation(DVec3::from(v)),
            Directive::Scale(v) => *ctm *= DMat4::from_scale(DVec3::from(v)),
            Directive::Rotate(a, axis) => {
                *ctm *=
                    DMat4::from_axis_angle(DVec3::from(axis).normalize_or_zero(), a.to_radians())
            }
            Directive::LookAt(v) => *ctm *= look_at(&v),
            Directive::Transform(m) => *ctm = DMat4::from_cols_array(&m),
            Directive::ConcatTransform(m) => *ctm *= DMat4::from_cols_array(&m),
            Directive::CoordinateSystem(n) => {
                self.named_coords.insert(n, *ctm);
            }
            Directive::CoordSysTransform(n) => match self.named_coords.get(&n) {
                Some(m) => *ctm = *m,
                None => {
                    return Err(err(
                        loc,
                        format!("CoordSysTransform \"{n}\": no such coordinate system"),
                    ))
                }
            },
            Directive::TransformTimes(..) | Directive::ActiveTransform(_) => {
                self.warn(loc, "motion blur transforms are ignored (one shutter time)")
            }
            Directive::ReverseOrientation => self.st.reverse = !self.st.reverse,
            Directive::AttributeBegin | Directive::TransformBegin => {
                self.stack.push(self.st.clone())
            }
            Directive::AttributeEnd | Directive::TransformEnd => match self.stack.pop() {
                Some(s) => self.st = s,
                None => return Err(err(loc, "AttributeEnd without AttributeBegin")),
            },
            Directive::Attribute(..) => self.warn(loc, "Attribute defaults are ignored"),
            Directive::ObjectBegin(n) => {
                self.stack.push(self.st.clone());
                self.current_object = Some((n, Vec::new()));
            }
            Directive::ObjectEnd => {
                if let Some((n, prims)) = self.current_object.take() {
                    self.objects.insert(n, prims);
                }
                if let Some(s) = self.stack.pop() {
                    self.st = s;
                }
            }
            Directive::ObjectInstance(n) => {
                let prims =
                    self.objects.get(&n).cloned().ok_or_else(|| {
                        err(loc, format!("ObjectInstance \"{n}\": no such object"))
                    })?;
                let m = affine_f32(&self.st.ctm);
                for mut p in prims {
                    p.geom = match p.geom {
                        Geom::Triangle { p: v, n, uv } => Geom::Triangle {
                            p: v.map(|x| m.transform_point3a(x)),
                            n: n.map(|n| n.map(|x| m.transform_vector3a(x).normalize_or_zero())),
                            uv,
                        },
                        Geom::Sphere { to_world, r, .. } => Geom::Sphere {
                            to_world: m * to_world,
                            to_obj: (m * to_world).inverse(),
                            r,
                        },
                        Geom::Disk {
                            to_world, h, r, ri, ..
                        } => Geom::Disk {
                            to_world: m * to_world,
                            to_obj: (m * to_world).inverse(),
                            h,
                            r,
                            ri,
                        },
                        Geom::Cylinder {
                            to_world,
                            r,
                            zmin,
                            zmax,
                            ..
                        } => Geom::Cylinder {
                            to_world: m * to_world,
                            to_obj: (m * to_world).inverse(),
                            r,
                            zmin,
                            zmax,
                        },
                    };
                    self.prims.push(p);
                }
            }
            Directive::Option(p) => self.warn(loc, format!("Option \"{}\" is ignored", p.name)),
            Directive::ColorSpace(n) => {
                if n != "srgb" {
                    self.warn(
                        loc,
                        format!("ColorSpace \"{n}\": rgb values are read as sRGB"),
                    );
                }
            }
            Directive::Camera(ty, p) => {
                if ty != "perspective" {
                    return Err(err(
                        loc,
                        format!("camera \"{ty}\" is not supported (perspective)"),
                    ));
                }
                let medium = if self.st.outside.is_empty() {
                    None
                } else {
                    self.named_media.get(&self.st.outside).copied()
                };
                // (Its parameters are read, and the rest reported, once the film is known: `load`.)
                self.named_coords
                    .insert("camera".into(), self.st.ctm.inverse());
                self.camera = Some((p, self.st.ctm, medium, loc.clone()));
            }
            Directive::Film(ty, params) => {
                let p = &ParamDict::new(&params);
                if ty != "rgb" && ty != "gbuffer" {
                    self.warn(loc, format!("film \"{ty}\" is written as an rgb film"));
                }
                self.res = (
                    num(p, "xresolution", 1280.0).max(1.0) as usize,
                    num(p, "yresolution", 720.0).max(1.0) as usize,
                );
                self.film_name = string(p, "filename").map(String::from);
                self.finish(Kind::Film, &ty, "film", p)?;
            }
            Directive::Sampler(ty, params) => {
                let p = &ParamDict::new(&params);
                self.spp = num(p, "pixelsamples", 16.0).max(1.0) as usize;
                self.finish(Kind::Sampler, &ty, &format!("sampler \"{ty}\""), p)?;
            }
            Directive::Integrator(ty, params) => {
                if ty != "volpath" && ty != "path" {
                    self.warn(loc, format!("integrator \"{ty}\" is rendered with volpath"));
                }
                let p = &ParamDict::new(&params);
                self.maxdepth = num(p, "maxdepth", 5.0).max(0.0) as usize;
                self.finish(Kind::Integrator, &ty, &format!("integrator \"{ty}\""), p)?;
            }
            Directive::PixelFilter(ty, params) => {
                if ty != "box" {
                    self.warn(
                        loc,
                        format!("pixel filter \"{ty}\" is rendered as a box filter"),
                    );
                }
                let p = &ParamDict::new(&params);
                self.finish(Kind::PixelFilter, &ty, &format!("pixel filter \"{ty}\""), p)?;
            }
            Directive::Accelerator(..) => {}
            Directive::WorldBegin => {
                self.st.ctm = DMat4::IDENTITY;
                self.named_coords.insert("world".into(), DMat4::IDENTITY);
            }
            Directive::LightSource(ty, params) => {
                let p = &ParamDict::new(&params);
                let scale = num(p, "scale", 1.0) as f32;
                let m = self.st.ctm;
                let pt = |v: Option<&[f64]>, def: [f64; 3]| {
                    Vec3A::from(
                        m.transform_point3(DVec3::from(
                            v.map(|v| [v[0], v[1], v[2]]).unwrap_or(def),
                        ))
                        .as_vec3(),
                    )
                };
                let l = match ty.as_str() {
                    "point" => {
                        Light::Point { p: pt(nums(p, "from"), [0.0; 3]), i: self.spectrum(p, "I", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale }
                    }
                    "spot" => {
                        let (from, to) = (pt(nums(p, "from"), [0.0; 3]), pt(nums(p, "to"), [0.0, 0.0, 1.0]));
                        let cone = num(p, "coneangle", 30.0);
                        Light::Spot {
                            p: from,
                            dir: (to - from).normalize_or_zero(),
                            cos_total: cone.to_radians().cos() as f32,
                            cos_falloff: (cone - num(p, "conedelta", 5.0)).to_radians().cos() as f32,
                            i: self.spectrum(p, "I", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale,
                        }
                    }
                    "distant" => {
                        let (from, to) = (pt(nums(p, "from"), [0.0; 3]), pt(nums(p, "to"), [0.0, 0.0, 1.0]));
                        Light::Distant { to_light: (from - to).normalize_or_zero(), l: self.spectrum(p, "L", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale }
                    }
                    "infinite" => {
                        match string(p, "filename") {
                            Some(f) => {
                                if p.has("L") {
                                    return Err(err(loc, "infinite light: give \"L\" or \"filename\", not both (as pbrt-v4)"));
                                }
                                let img = crate::imageio::read(&self.dir.join(f), false).map_err(|e| err(loc, format!("infinite light: {e}")))?;
                                if !(img.w == img.h || img.w == 2 * img.h) {
                                    return Err(err(loc, format!("infinite light: a {}×{} map; expected a square equal-area map (pbrt-v4) or a 2:1 lat-long one", img.w, img.h)));
                                }
                                let to_light = Mat3A::from(DMat3::from_mat4(self.st.ctm).inverse().as_mat3());
                                Light::InfiniteMap { img: std::sync::Arc::new(img), to_light, scale, basis: self.rgb_basis() }
                            }
                            None => Light::Infinite { l: self.spectrum(p, "L", Some(self.bins.mask()))?.map(|t| t.eval(Vec2::ZERO)).unwrap_or(S::ZERO) * scale },
                        }
                    }
                    other => return Err(err(loc, format!("light \"{other}\" is not supported (point, spot, distant, infinite, and area diffuse)"))),
                };
                self.lights.push(l);
                self.finish(Kind::Light, &ty, &format!("{ty} light"), p)?;
            }
            Directive::AreaLightSource(ty, params) => {
                let p = &ParamDict::new(&params);
                if ty != "diffuse" {
                    return Err(err(
                        loc,
                        format!("area light \"{ty}\" is not supported (diffuse)"),
                    ));
                }
                let l = self
                    .spectrum(p, "L", Some(self.bins.mask()))?
                    .map(|t| t.eval(Vec2::ZERO))
                    .unwrap_or(S::ZERO)
                    * num(p, "scale", 1.0) as f32;
                let two = p.bool("twosided", false);
                self.st.area = Some((l, two));
                self.finish(Kind::AreaLight, &ty, "diffuse area light", p)?;
            }
            Directive::Material(ty, params) => {
                let p = &ParamDict::new(&params);
                self.st.material = self.material(&ty, p, loc)?;
                self.finish(Kind::Material, &ty, &format!("{ty} material"), p)?;
            }
            Directive::MakeNamedMaterial(name, params) => {
                let p = &ParamDict::new(&params);
                let ty = string(p, "type").unwrap_or("").to_string();
                if ty.is_empty() {
                    return Err(err(
                        loc,
                        format!("MakeNamedMaterial \"{name}\": missing \"string type\""),
                    ));
                }
                let m = self.material(&ty, p, loc)?;
                self.finish(Kind::Material, &ty, &format!("{ty} material \"{name}\""), p)?;
                // Interface named materials are stored as usize::MAX.
                self.named_materials.insert(name, m.unwrap_or(usize::MAX));
            }
            Directive::NamedMaterial(name) => match self.named_materials.get(&name) {
                Some(&m) => self.st.material = (m != usize::MAX).then_some(m),
                None => {
                    return Err(err(
                        loc,
                        format!("NamedMaterial \"{name}\": no such material"),
                    ))
                }
            },
            Directive::Texture(name, _ty, class, params) => {
                let p = &ParamDict::new(&params);
                let t = match class.as_str() {
                    "checkerboard" => {
                        let a = self
                            .spectrum(p, "tex1", Some(self.bins.mask()))?
                            .unwrap_or(Tex::Const(S::ZERO));
                        let b = self
                            .spectrum(p, "tex2", Some(S::ZERO))?
                            .unwrap_or(Tex::Const(S::ZERO));
                        Tex::Checker {
                            a: Box::new(a),
                            b: Box::new(b),
                            su: num(p, "uscale", 1.0) as f32,
                            sv: num(p, "vscale", 1.0) as f32,
                        }
                    }
                    "constant" => self
                        .spectrum(p, "value", Some(self.bins.mask()))?
                        .unwrap_or(Tex::Const(S::ZERO)),
                    "imagemap" => {
                        let f = string(p, "filename").ok_or_else(|| err(loc, "imagemap: missing \"string filename\""))?;
                        let srgb = match string(p, "encoding").unwrap_or("sRGB") {
                            "sRGB" => true,
                            "linear" => false,
                            e => return Err(err(loc, format!("imagemap: encoding \"{e}\" is not supported (sRGB, linear)"))),
                        };
                        let wrap = match string(p, "wrap").unwrap_or("repeat") {
                            "repeat" => crate::imageio::Wrap::Repeat,
                            "clamp" => crate::imageio::Wrap::Clamp,
                            "black" => crate::imageio::Wrap::Black,
                            w => return Err(err(loc, format!("imagemap: wrap \"{w}\" is not one of repeat, clamp, black"))),
                        };
                        let img = crate::imageio::read(&self.dir.join(f), srgb).map_err(|e| err(loc, format!("imagemap: {e}")))?;
                        let invert = p.bool("invert", false);
                        Tex::Image { img: std::sync::Arc::new(img), scale: num(p, "scale", 1.0) as f32, invert, wrap, basis: self.rgb_basis() }
                    }
                    other => return Err(err(
                        loc,
                        format!(
                            "texture class \"{other}\" is not supported (checkerboard, constant, imagemap)"
                        ),
                    )),
                };
                self.finish(
                    Kind::Texture,
                    &class,
                    &format!("{class} texture \"{name}\""),
                    p,
                )?;
                self.textures.insert(name, t);
            }
            Directive::Shape(ty, params) => {
                let p = &ParamDict::new(&params);
                self.shape(&ty, p, loc)?;
                self.finish(Kind::Shape, &ty, &ty, p)?;
            }
            Directive::MakeNamedMedium(name, params) => {
                let p = &ParamDict::new(&params);
                self.medium(&name, p, loc)?;
                let ty = string(p, "type").unwrap_or("");
                self.finish(Kind::Medium, ty, &format!("{ty} medium \"{name}\""), p)?;
            }
            Directive::MediumInterface(i, o) => {
                for n in [&i, &o] {
                    if !n.is_empty() && !self.named_media.contains_key(n) {
                        return Err(err(
                            loc,
                            format!("MediumInterface: no medium named \"{n}\""),
                        ));
                    }
                }
                self.st.inside = i;
                self.st.outside = o;
            }
        }
        Ok(())
    }
}

/// Loads the fire plugin from `path`, or as [`Plugin::from_env`] finds it. The host's one `unsafe`: loading a
/// library runs its initialisers, so the renderer loads only the file the user named (`--plugin`, a medium's
/// `"string plugin"`, `FIREMEDIUM_PLUGIN`, `FIREMEDIUM_PLUGIN_PATH`) or the one built beside it.
#[allow(unsafe_code)]
fn load_plugin(path: Option<&Path>) -> Result<Plugin, firemedium_loader::Error> {
    match path {
        // SAFETY: a plugin file the user named; the loader checks its ABI version, size and entries.
        Some(p) => unsafe { Plugin::load(p) },
        // SAFETY: the file the user's environment names, or the plugin built beside this executable.
        None => unsafe { Plugin::from_env() },
    }
}

/// Settings the command line can override.
#[derive(Debug, Clone, Default)]
pub struct Overrides {
    pub spp: Option<usize>,
    pub plugin: Option<PathBuf>,
    /// Do not build fire lights (paths find the fire's emission only by chance).
    pub no_fire_light: bool,
    /// The fire lights' voxel weighting (`power`, the plugin's default, or `luminance`).
    pub fire_light_weighting: Option<String>,
    /// Film resolution instead of the scene's.
    pub res: Option<(usize, usize)>,
    /// Threads the plugin may use to build each medium (the render's own; `None`: every core).
    pub threads: Option<usize>,
}

/// Parses and builds the scene at `path`.
pub fn load(path: &Path, ov: &Overrides) -> Result<Scene, Error> {
    let mut c = Collect::default();
    parse_file(path, &mut c).map_err(|e| e.to_string())?;
    // Pre-scan: the render bins (from the media, or the defaults of the plugin that renders them) and the
    // photometric scale.
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (mut fire, mut pbrt_media) = (false, false);
    let mut plugin_path = ov.plugin.clone();
    let mut first_medium: Option<&Loc> = None;
    for (d, loc) in &c.0 {
        if let Directive::MakeNamedMedium(_, p) = d {
            let p = &ParamDict::new(p);
            match string(p, "type") {
                Some("fire") => fire = true,
                Some("uniformgrid" | "nanovdb") => pbrt_media = true,
                _ => continue,
            }
            first_medium.get_or_insert(loc);
            if let (None, Some(file)) = (&plugin_path, string(p, "plugin")) {
                plugin_path = Some(dir.join(file));
            }
        }
    }
    let plugin = match first_medium {
        Some(loc) => Some(
            match &plugin_path {
                Some(file) => load_plugin(Some(file)),
                None => load_plugin(None),
            }
            .map_err(|e| err(loc, e))?,
        ),
        None => None,
    };
    let default = SpectralGrid::default();
    let (mut lo, mut hi, mut n) = (default.min_nm(), default.max_nm(), default.count());
    if let Some(p) = &plugin {
        for row in p.parameters() {
            let x = row.default.trim().parse::<f64>();
            match (row.name.as_str(), x) {
                ("lambdamin", Ok(x)) => lo = x,
                ("lambdamax", Ok(x)) => hi = x,
                ("bins", Ok(x)) if x >= 1.0 => n = x as usize,
                _ => {}
            }
        }
    }
    let mut bins_params: Vec<LParam> = Vec::new();
    for (d, loc) in &c.0 {
        if let Directive::MakeNamedMedium(_, p) = d {
            let p = &ParamDict::new(p);
            for (k, v) in [("lambdamin", &mut lo), ("lambdamax", &mut hi)] {
                if let Some(x) = nums(p, k).and_then(|v| v.first()) {
                    if bins_params
                        .iter()
                        .any(|b| b.name == k && b.value != Value::Float(vec![*x]))
                    {
                        return Err(err(loc, format!("media disagree on \"{k}\": all media share the scene's spectral bins")));
                    }
                    *v = *x;
                    bins_params.push(LParam::float(k, *x));
                }
            }
            if let Some(x) = nums(p, "bins").and_then(|v| v.first()) {
                n = *x as usize;
                bins_params.push(LParam::int("bins", *x as i64));
            }
        }
    }
    if n > super::spectrum::MAX_CHANNELS {
        return Err(format!(
            "{}: {n} spectral bins; the renderer supports at most {}",
            path.display(),
            super::spectrum::MAX_CHANNELS
        ));
    }
    let grid = SpectralGrid::new(lo, hi, n).map_err(|e| format!("{}: {e}", path.display()))?;
    // Absolute units (683 lm/W) with a fire; pbrt's relative units for scenes of pbrt grid media only.
    let k = if pbrt_media && !fire {
        1.0 / firemedium_core::cie::CIE_Y_INTEGRAL
    } else {
        683.0
    };
    let bins = Bins::new(grid, k);
    bins_params.dedup_by(|a, b| a.name == b.name);
    for (name, v) in [("bins", n as f64), ("lambdamin", lo), ("lambdamax", hi)] {
        if !bins_params.iter().any(|p| p.name == name) {
            bins_params.push(if name == "bins" {
                LParam::int(name, v as i64)
            } else {
                LParam::float(name, v)
            });
        }
    }
    let mut b = Builder {
        dir,
        bins: bins.clone(),
        plugin_path,
        plugin,
        st: State {
            ctm: DMat4::IDENTITY,
            reverse: false,
            material: None,
            area: None,
            inside: String::new(),
            outside: String::new(),
        },
        stack: Vec::new(),
        named_coords: HashMap::new(),
        named_materials: HashMap::new(),
        textures: HashMap::new(),
        named_media: HashMap::new(),
        materials: Vec::new(),
        prims: Vec::new(),
        lights: Vec::new(),
        media: Vec::new(),
        media_reports: Vec::new(),
        camera: None,
        res: (1280, 720),
        spp: 16,
        maxdepth: 5,
        film_name: None,
        warnings: Vec::new(),
        objects: HashMap::new(),
        current_object: None,
        bins_params,
        has_fire: fire,
        film_xyz: None,
        threads: ov.threads,
    };
    // pbrt's default material: diffuse 0.5.
    b.materials
        .push(Material::Diffuse(Tex::Const(bins.mask() * 0.5)));
    b.st.material = Some(0);
    for (d, loc) in c.0 {
        b.directive(d, &loc)?;
    }
    // The camera, now that the film resolution is known (pbrt allows Film after Camera).
    let (cp, camera_from_world, medium, _) = b
        .camera
        .take()
        .ok_or_else(|| format!("{}: no Camera directive", path.display()))?;
    let cp = &ParamDict::new(&cp);
    if let Some(r) = ov.res {
        b.res = r;
    }
    let (w, h) = (b.res.0 as f64, b.res.1 as f64);
    let aspect = num(cp, "frameaspectratio", w / h);
    let screen = match nums(cp, "screenwindow") {
        Some(s) if s.len() == 4 => [s[0], s[1], s[2], s[3]],
        _ if aspect > 1.0 => [-aspect, aspect, -1.0, 1.0],
        _ => [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect],
    };
    let camera = Camera {
        to_world: affine(&camera_from_world.inverse()),
        tan_half: (num(cp, "fov", 90.0).to_radians() / 2.0).tan(),
        screen,
        lens_radius: num(cp, "lensradius", 0.0),
        focal_distance: num(cp, "focaldistance", 1e6),
        medium,
    };
    b.finish(Kind::Camera, "perspective", "perspective camera", cp)?;
    // Fire lights: every plugin medium that emits gets one (unless switched off).
    if !ov.no_fire_light {
        let mut report = 0;
        for (mi, m) in b.media.iter().enumerate() {
            if let Medium::Plugin { vol, .. } = m {
                let r = report;
                report += 1;
                match vol.create_light(ov.fire_light_weighting.as_deref()) {
                    Ok(light) => {
                        let li = light.info();
                        if let Some(rep) = b.media_reports.get_mut(r) {
                            rep.light = Some((
                                li.voxels,
                                li.power_w,
                                li.power_lm,
                                li.bytes,
                                li.build_seconds,
                            ));
                        }
                        b.lights.push(Light::Fire {
                            light: std::sync::Arc::new(light),
                            medium: mi,
                        });
                    }
                    // A medium that does not emit is no light.
                    Err(firemedium_loader::Error::Status { message, .. })
                        if message.contains("no emitting voxel") => {}
                    Err(e) => {
                        return Err(format!(
                            "{}: fire light of medium {mi}: {e}",
                            path.display()
                        ))
                    }
                }
            }
        }
    }
    let scale = b.prims.iter().map(|p| {
        let bb = obvhs::Boundable::aabb(p);
        (bb.max - bb.min).max_element().abs()
    });
    let extent = scale.fold(1.0f32, f32::max);
    // The film's colour is the plugin's projection of its bins (scenes without plugin media: the core's).
    let mut bins = bins;
    if let Some((_, xyz)) = b.film_xyz.take() {
        bins.xyz = xyz;
    }
    Ok(Scene {
        bins,
        bvh: Bvh::new(b.prims),
        materials: b.materials,
        lights: b.lights,
        media: b.media,
        camera,
        res: b.res,
        spp: ov.spp.unwrap_or(b.spp),
        maxdepth: b.maxdepth,
        film_name: b.film_name,
        eps: (extent * 1e-5).max(1e-6),
        warnings: b.warnings,
        media_reports: b.media_reports,
    })
}
