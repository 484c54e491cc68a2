//! The scene builder's state (pbrt-v4's graphics state and the named things a scene declares) and what it
//! builds per directive: media (through the plugin), shapes, materials, spectra from parameters; every
//! directive's parameters are read through a `ParamDict` and the rest reported (`finish`).

use super::{err, Error, Light, Material, Medium, MediumReport, Tex};
use crate::render::pbrt_v4::{self, Kind};
use crate::render::shapes::{Bvh, Geom, Prim};
use crate::render::spectrum::{Bins, S};
use firemedium_core::rgb_spectrum::RgbUse;
use firemedium_loader::{Param as LParam, Plugin, Value, Volume};
use firemedium_pbrt_parser::{Loc, Param, ParamDict};
use glam::{Affine3A, DAffine3, DMat3, DMat4, DVec3, Mat3A, Vec2, Vec3A};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

#[derive(Clone)]
pub(super) struct State {
    pub(super) ctm: DMat4,
    pub(super) reverse: bool,
    pub(super) material: Option<usize>,
    /// The area light of the shapes that follow: (L, two-sided, the `power` in W each shape emits, or 0).
    pub(super) area: Option<(S, bool, f32)>,
    pub(super) inside: String,
    pub(super) outside: String,
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

/// A `Camera` directive as given: its type, parameters, camera-from-world, medium and place (read once the film
/// is known).
pub(super) type CameraDirective = (String, Vec<Param>, DMat4, Option<usize>, Loc);

pub(super) struct Builder {
    pub(super) dir: PathBuf,
    pub(super) bins: Bins,
    pub(super) plugin: Option<Plugin>,
    pub(super) st: State,
    /// Saved states, with where each was saved (AttributeBegin, TransformBegin, ObjectBegin).
    pub(super) stack: Vec<(State, Loc)>,
    pub(super) named_coords: HashMap<String, DMat4>,
    pub(super) named_materials: HashMap<String, usize>,
    pub(super) textures: HashMap<String, Tex>,
    pub(super) named_media: HashMap<String, usize>,
    pub(super) materials: Vec<Material>,
    pub(super) prims: Vec<Prim>,
    pub(super) lights: Vec<Light>,
    pub(super) media: Vec<Medium>,
    pub(super) media_reports: Vec<MediumReport>,
    /// The Camera directive: parameters, camera-from-world, medium, position (built once the film is known).
    pub(super) camera: Option<CameraDirective>,
    pub(super) res: (usize, usize),
    pub(super) spp: usize,
    pub(super) sampler: crate::render::pixel::Sampler,
    pub(super) filter: crate::render::pixel::Filter,
    pub(super) film_response: FilmParams,
    pub(super) spectral: Option<crate::render::film::Buckets>,
    pub(super) gbuffer: Option<crate::render::film::GBuffer>,
    /// `Option "integer seed"` and `Option "bool disablepixeljitter"`.
    pub(super) seed: u64,
    pub(super) pixel_jitter: bool,
    /// The film's `cropwindow` (x0, x1, y0, y1 in [0, 1]) or `pixelbounds` (pixels), with where each was given.
    pub(super) crop: Option<([f64; 4], Loc)>,
    pub(super) pixel_bounds: Option<([f64; 4], Loc)>,
    pub(super) maxdepth: usize,
    pub(super) film_name: Option<String>,
    pub(super) warnings: Vec<String>,
    pub(super) objects: HashMap<String, Arc<Bvh>>,
    /// Primitives held by the objects defined so far (each once, however often it is instanced).
    pub(super) object_prims: usize,
    pub(super) current_object: Option<(String, Vec<Prim>)>,
    pub(super) bins_params: Vec<LParam>,
    /// Threads the plugin may use to build a medium (`Overrides::threads`).
    pub(super) threads: Option<usize>,
    /// The frame for every plugin medium (`--frames`), unless the scene sets one.
    pub(super) frame: Option<i64>,
    /// Plugin media tracked by the renderer through the medium level (`Overrides::host_tracking`).
    pub(super) host_tracking: bool,
    /// The camera's shutter (frames) once a medium blurs by its velocity: each camera sample then draws a
    /// time in it.
    pub(super) shutter: Option<[f64; 2]>,
    /// Bytes the plugin media built so far hold (each new medium's `maxbytes` is what the budget has left).
    pub(super) media_bytes: u64,
    /// The memory budget, bytes: each plugin grid's `maxbytes` unless the scene sets it.
    pub(super) max_memory: u64,
    /// Whether the scene has a physical `fire` medium (its absolute units then set the film's).
    pub(super) has_fire: bool,
    /// The film's XYZ weights per bin, from the plugin that renders the media (`volume_channel_xyz` of the
    /// first medium in the film's units), and that medium's name; every further medium is checked against it.
    pub(super) film_xyz: Option<(String, Vec<DVec3>)>,
}

impl Builder {
    /// The Camera directive's `shutteropen` and `shutterclose` (pbrt-v4's 0 and 1 when not given, or before
    /// the camera).
    fn camera_shutter(&self) -> [f64; 2] {
        let Some((_, cp, ..)) = &self.camera else {
            return [0.0, 1.0];
        };
        let cp = ParamDict::new(cp);
        [num(&cp, "shutteropen", 0.0), num(&cp, "shutterclose", 1.0)]
    }
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

/// pbrt-v4's LookAt: the camera-from-world matrix (pbrt's left-handed camera space).
pub(super) fn look_at(v: &[f64; 9]) -> DMat4 {
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
        self.warnings.push(format!("{loc}: warning: {m}"));
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

    pub(super) fn add_prim(&mut self, geom: Geom) {
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
            // An object's primitives are no area lights (pbrt-v4 leaves them out too; `shape` warns).
            objs.push(prim);
            return;
        }
        if let Some((mut l, twosided, power)) = light {
            // pbrt-v4 makes an area light per shape (per triangle of a mesh): `power` is each one's, over its
            // area A and both sides when two-sided: L · (sides · A · π) = power.
            if power > 0.0 {
                let area = 1.0 / crate::render::shapes::sample_area(&prim, [0.5, 0.5]).2;
                let k = if twosided { 2.0 } else { 1.0 } * area * std::f32::consts::PI;
                if k > 0.0 && k.is_finite() {
                    l = l * (power / k);
                }
            }
            prim.area_light = Some(self.lights.len());
            self.lights.push(Light::Area {
                prim: self.prims.len(),
                l,
                twosided,
            });
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
            self.max_memory,
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

    /// The plugin `load` found for the scene's plugin media (from `--plugin`, the first such medium's
    /// `"string plugin"`, or the environment).
    pub(super) fn plugin(&self, loc: &Loc) -> Result<Plugin, Error> {
        self.plugin
            .clone()
            .ok_or_else(|| err(loc, "no firemedium plugin was loaded for this medium"))
    }

    /// Takes the film's colour from the plugin: the medium's bins must be the renderer's, and the first medium in
    /// the film's units (a `fire` when the scene has one, else any) gives the XYZ weights of every bin. A further
    /// medium must agree with them up to its units' scale, so a plugin built from another commit, or media that
    /// project their bins differently, are refused instead of rendering a silently wrong colour. Returns the
    /// factor that takes the medium's radiance to the film's units (its weights' luminance over the film's:
    /// 1 in its own units, 1/683 for a pbrt grid beside a fire).
    pub(super) fn check_colour(
        &mut self,
        name: &str,
        fire: bool,
        vol: &Volume,
        loc: &Loc,
    ) -> Result<f32, Error> {
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
        let y = |w: &[DVec3]| w.iter().map(|v| v.y).sum::<f64>();
        // The film's weights are the renderer's own until the first medium in its units replaces them.
        let film = match &self.film_xyz {
            Some((_, want)) => y(want),
            None => y(&self.bins.xyz),
        };
        let units = y(&xyz) / film;
        let units = if (units - 1.0).abs() < 1e-6 {
            1.0
        } else {
            units as f32
        };
        if !(units > 0.0 && units.is_finite()) {
            return Err(err(loc, format!("medium \"{name}\": its bins' colour weights have luminance {}; expected a positive one", y(&xyz))));
        }
        match &self.film_xyz {
            // The medium that sets the film's weights is in the film's units by definition.
            None if fire || !self.has_fire => {
                self.film_xyz = Some((name.to_string(), xyz));
                Ok(1.0)
            }
            None => Ok(units),
            Some((first, want)) => {
                // The same projection up to one scale (physical and pbrt units differ by a constant).
                let k = y(want) / y(&xyz);
                let worst = want
                    .iter()
                    .zip(&xyz)
                    .map(|(a, b)| {
                        (*a - *b * k).abs().max_element() / a.abs().max_element().max(1e-300)
                    })
                    .fold(0.0, f64::max);
                if worst.is_finite() && worst < 1e-6 {
                    Ok(units)
                } else {
                    Err(err(loc, format!("medium \"{name}\": its bins project to XYZ differently from medium \"{first}\"'s (largest relative difference {worst:.3e}); are both from the same plugin?")))
                }
            }
        }
    }

    /// pbrt-v4's `rgbgrid` medium (see [`crate::render::rgbgrid`]), its rgb grids made bin spectra per voxel.
    fn rgbgrid(
        &mut self,
        name: &str,
        params: &ParamDict,
        to_medium: glam::DAffine3,
        loc: &Loc,
    ) -> Result<crate::render::rgbgrid::RgbGrid, Error> {
        use crate::render::rgbgrid::{Grid, RgbGrid};
        let what = format!("rgbgrid medium \"{name}\"");
        let dims: Vec<usize> = ["nx", "ny", "nz"]
            .iter()
            .map(|k| {
                let v = num(params, k, 1.0);
                if v.fract() == 0.0 && (1.0..=1e6).contains(&v) {
                    Ok(v as usize)
                } else {
                    Err(err(
                        loc,
                        format!("{what}: \"integer {k}\" {v}: expected 1 to 1000000"),
                    ))
                }
            })
            .collect::<Result<_, _>>()?;
        let count = dims
            .iter()
            .try_fold(1usize, |a, &b| a.checked_mul(b))
            .unwrap_or(usize::MAX);
        // Three grids of bin spectra at most.
        crate::budget::check(
            &format!("{what}: {count} voxels"),
            count as u64,
            3 * std::mem::size_of::<S>() as u64,
            self.max_memory.saturating_sub(self.media_bytes),
        )
        .map_err(|e| err(loc, e))?;
        let rgbs = |key: &str| -> Result<Option<&[f64]>, Error> {
            let Some(p) = params.get(key) else {
                return Ok(None);
            };
            let firemedium_pbrt_parser::Values::Numbers(v) = &p.values else {
                return Err(err(
                    &p.loc,
                    format!("{what}: \"{key}\": expected \"rgb {key}\" values"),
                ));
            };
            if p.ty != "rgb" {
                return Err(err(&p.loc, format!("{what}: \"{} {key}\": pbrt-v4's rgbgrid takes \"rgb {key}\" (one rgb per voxel)", p.ty)));
            }
            if v.len() != 3 * count {
                return Err(err(
                    &p.loc,
                    format!(
                        "{what}: \"rgb {key}\" has {} values: expected 3 × nx·ny·nz = {}",
                        v.len(),
                        3 * count
                    ),
                ));
            }
            if let Some((i, x)) = v
                .iter()
                .enumerate()
                .find(|(_, x)| !(x.is_finite() && **x >= 0.0))
            {
                return Err(err(
                    &p.loc,
                    format!("{what}: \"rgb {key}\" [{i}] = {x}: expected a finite value >= 0"),
                ));
            }
            Ok(Some(v.as_slice()))
        };
        let (sa, ss, le) = (rgbs("sigma_a")?, rgbs("sigma_s")?, rgbs("Le")?);
        if sa.is_none() && ss.is_none() {
            return Err(err(
                loc,
                format!("{what}: give \"rgb sigma_a\" and/or \"rgb sigma_s\" (as pbrt-v4)"),
            ));
        }
        if le.is_some() && sa.is_none() {
            return Err(err(
                loc,
                format!("{what}: \"rgb Le\" needs \"rgb sigma_a\" (as pbrt-v4)"),
            ));
        }
        let scale = num(params, "scale", 1.0) as f32;
        // pbrt-v4's RGBIlluminantSpectrum: the fit times D65 with ∫ D65 ȳ = ∫ ȳ (the uplift gives ∫ s ȳ = 1 for
        // white), not photometrically normalised; in the film's units (÷ its K: 683 beside a fire).
        let y_integral: f64 = firemedium_core::cie::cmf_table::CMF
            .iter()
            .map(|c| c[1])
            .sum::<f64>()
            * firemedium_core::cie::cmf_table::CMF_STEP_NM;
        let k = if self.has_fire {
            firemedium_core::constants::LUMINOUS_EFFICACY
        } else {
            1.0
        };
        let le_scale = (num(params, "Lescale", 1.0) * y_integral / k) as f32;
        let mut cache: std::collections::HashMap<([u64; 3], bool), S> =
            std::collections::HashMap::new();
        let mut spectra = |v: &[f64], illuminant: bool, k: f32| -> Vec<S> {
            v.chunks(3)
                .map(|c| {
                    let key = ([c[0].to_bits(), c[1].to_bits(), c[2].to_bits()], illuminant);
                    *cache.entry(key).or_insert_with(|| {
                        let usage = if illuminant {
                            RgbUse::Illuminant
                        } else {
                            RgbUse::Unbounded
                        };
                        self.bins.uplift([c[0], c[1], c[2]], usage) * k
                    })
                })
                .collect()
        };
        let grid = |g: Option<Vec<S>>| match g {
            Some(v) => Grid::Voxels(v),
            None => Grid::Constant(Box::new(self.bins.mask() * scale)),
        };
        let sa = grid(sa.map(|v| spectra(v, false, scale)));
        let ss = grid(ss.map(|v| spectra(v, false, scale)));
        let le = le.map(|v| spectra(v, true, le_scale));
        let n = self.bins.n();
        let max = |g: &Grid| match g {
            Grid::Voxels(v) => v
                .iter()
                .flat_map(|s| s.0[..n].iter().copied())
                .fold(0.0f32, f32::max),
            Grid::Constant(s) => s.max(),
        };
        let majorant = max(&sa) + max(&ss);
        if !majorant.is_finite() {
            return Err(err(
                loc,
                format!("{what}: σ_t reaches {majorant}: expected finite values (check \"scale\")"),
            ));
        }
        let pt = |key: &str, def: [f64; 3]| {
            nums(params, key)
                .filter(|v| v.len() == 3)
                .map_or(DVec3::from_array(def), |v| DVec3::new(v[0], v[1], v[2]))
        };
        let (p0, p1) = (pt("p0", [0.0; 3]), pt("p1", [1.0; 3]));
        if !(p0.is_finite() && p1.is_finite() && (p1 - p0).abs().min_element() > 0.0) {
            return Err(err(
                loc,
                format!("{what}: p0 {p0} and p1 {p1}: expected a box of positive size"),
            ));
        }
        self.media_bytes = self
            .media_bytes
            .saturating_add((count * 3 * std::mem::size_of::<S>()) as u64);
        Ok(RgbGrid {
            n: [dims[0], dims[1], dims[2]],
            p0,
            p1,
            sa,
            ss,
            le,
            majorant,
            to_medium,
            g: num(params, "g", 0.0).clamp(-0.99, 0.99),
            bins: n,
        })
    }

    pub(super) fn medium(
        &mut self,
        name: &str,
        params: &ParamDict,
        loc: &Loc,
    ) -> Result<(), Error> {
        let ty = string(params, "type").unwrap_or("").to_string();
        let to_medium = affine(&self.st.ctm.inverse());
        let m = match ty.as_str() {
            "homogeneous" => {
                let scale = num(params, "scale", 1.0) as f32;
                // pbrt-v4: a named preset (measured, mm⁻¹) replaces sigma_a and sigma_s; an unknown one warns.
                let preset = string(params, "preset").filter(|n| !n.is_empty());
                let found = preset.and_then(crate::render::media_presets::preset);
                if let (Some(n), None) = (preset, found) {
                    self.warn(loc, format!("homogeneous medium \"{name}\": preset \"{n}\" not found (pbrt-v4's named media: Apple, Skin1, Wholemilk, Ketchup, …); sigma_a and sigma_s are used"));
                }
                let (sa, ss) = match found {
                    Some((s, a)) => (self.bins.uplift(a, RgbUse::Unbounded), self.bins.uplift(s, RgbUse::Unbounded)),
                    None => (
                        self.constant(params, "sigma_a", self.bins.mask(), RgbUse::Unbounded)?,
                        self.constant(params, "sigma_s", self.bins.mask(), RgbUse::Unbounded)?,
                    ),
                };
                let (sa, ss) = (sa * scale, ss * scale);
                let le = self.emitted(params, "Le", false, num(params, "Lescale", 1.0))?;
                Medium::Homogeneous { sa, ss, le, g: num(params, "g", 0.0).clamp(-0.99, 0.99) }
            }
            "rgbgrid" => Medium::RgbGrid(std::sync::Arc::new(self.rgbgrid(name, params, to_medium, loc)?)),
            "fire" | "uniformgrid" | "nanovdb" | "cloud" => {
                // Parameters pass to the plugin unchanged, but for the type, the plugin file (read by `load`'s
                // pre-scan, which loaded the plugin), and relative paths.
                let plugin = self.plugin(loc)?;
                // The plugin reads and checks every parameter itself, reporting any it does not use.
                params.mark_all_used();
                let mut list: Vec<LParam> = Vec::new();
                for p in params.params() {
                    if p.name == "type" || p.name == "plugin" {
                        continue;
                    }
                    // pbrt-v4's `nanovdb` names its grids `gridname` (default "density") and `temperaturename`
                    // (default "temperature"): the plugin's `densitygrid` and `temperaturegrid`.
                    let key = match (ty.as_str(), p.name.as_str()) {
                        ("nanovdb", "gridname") => "densitygrid",
                        ("nanovdb", "temperaturename") => "temperaturegrid",
                        (_, n) => n,
                    };
                    if key != p.name && params.params().iter().any(|q| q.name == key) {
                        return Err(err(&p.loc, format!("nanovdb medium \"{name}\": \"{}\" and \"{key}\" both name a grid: give one (pbrt-v4 reads \"{}\")", p.name, p.name)));
                    }
                    let value = match (&p.values, p.ty.as_str()) {
                        // (File names as the scene wrote them: the plugin resolves its own against the scene's
                        // folder, `Context::directory`.)
                        (firemedium_pbrt_parser::Values::Strings(v), _) => Value::String(v.clone()),
                        (firemedium_pbrt_parser::Values::Bools(v), _) => Value::Bool(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "integer") => Value::Integer(v.iter().map(|&x| x as i64).collect()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "point3") => Value::Point3(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "vector3") => Value::Vector3(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "rgb") => Value::Rgb(v.clone()),
                        (firemedium_pbrt_parser::Values::Numbers(v), "spectrum") => Value::Spectrum(v.clone()),
                        // pbrt-v4's `BlackbodySpectrum(T)`, peak-normalised, as 1 nm (λ, value) pairs over 360–830.
                        (firemedium_pbrt_parser::Values::Numbers(v), "blackbody") => {
                            let t = v.first().copied().unwrap_or(0.0);
                            let peak = firemedium_core::blackbody::spectral_radiance(t, firemedium_core::blackbody::WIEN / t * 1e9);
                            Value::Spectrum((360..=830).flat_map(|l| [l as f64, if t > 0.0 && peak > 0.0 { firemedium_core::blackbody::spectral_radiance(t, l as f64) / peak } else { 0.0 }]).collect())
                        }
                        (firemedium_pbrt_parser::Values::Numbers(v), _) => Value::Float(v.clone()),
                    };
                    list.push(LParam { name: key.to_string(), value, at: Some(p.loc.to_string()) });
                }
                if ty == "cloud" {
                    // pbrt-v4's procedural cloud, baked into a grid the plugin renders as a pbrt grid medium.
                    let take = |list: &mut Vec<LParam>, name: &str, def: f64| -> f64 {
                        match list.iter().position(|p| p.name == name) {
                            Some(i) => match list.remove(i).value {
                                Value::Float(v) => v.first().copied().unwrap_or(def),
                                _ => def,
                            },
                            None => def,
                        }
                    };
                    let (dens, wisp, freq) = (take(&mut list, "density", 1.0), take(&mut list, "wispiness", 1.0), take(&mut list, "frequency", 5.0));
                    if ![dens, wisp, freq].iter().all(|v| v.is_finite() && *v >= 0.0 && *v <= 1e6) {
                        return Err(err(loc, format!("cloud medium \"{name}\": density {dens}, wispiness {wisp}, frequency {freq}: expected values from 0 to 1e6")));
                    }
                    let corner = |name: &str, def: f64| {
                        list.iter()
                            .find(|p| p.name == name)
                            .and_then(|p| match &p.value { Value::Point3(v) if v.len() == 3 => Some(DVec3::new(v[0], v[1], v[2])), _ => None })
                            .unwrap_or(DVec3::splat(def))
                    };
                    let (p0, p1) = (corner("p0", 0.0), corner("p1", 1.0));
                    let n = crate::render::cloud::BAKE as i64;
                    // The bake (f64 here, f32 in the plugin) must fit in what the media built so far left.
                    crate::budget::check(
                        &format!("cloud medium \"{name}\": its {n}³ baked grid"),
                        (n * n * n) as u64,
                        12,
                        self.max_memory.saturating_sub(self.media_bytes),
                    )
                    .map_err(|e| err(loc, e))?;
                    for axis in ["nx", "ny", "nz"] {
                        list.push(LParam::int(axis, n));
                    }
                    list.push(LParam { name: "density".into(), value: Value::Float(crate::render::cloud::bake(p0, p1, dens, wisp, freq)), at: Some(loc.to_string()) });
                }
                if ty != "fire" {
                    list.push(LParam::string("mode", "pbrt"));
                }
                for b in &self.bins_params {
                    if !list.iter().any(|p| p.name == b.name) {
                        list.push(b.clone());
                    }
                }
                // The renderer's context goes beside the scene's parameters, not among them (a parameter the scene
                // sets itself wins in the plugin).
                let mut context = firemedium_loader::Context {
                    threads: self.threads.map(|n| n as u32),
                    frame: self.frame,
                    directory: Some(self.dir.clone()),
                    ..Default::default()
                };
                // Motion blur: a velocity grid or embers (which move by their own velocities) see the camera's
                // shutter (unless the medium sets its own), and the camera then draws a time per sample.
                let velocity = list.iter().any(|p| {
                    (p.name == "velocitygrid" || p.name == "embers")
                        && matches!(&p.value, Value::String(v) if v.iter().any(|s| !s.is_empty()))
                });
                if velocity {
                    let camera = self.camera_shutter();
                    let mut shutter = camera;
                    for (k, n) in ["shutteropen", "shutterclose"].into_iter().enumerate() {
                        if let Some(Value::Float(v)) = list.iter().find(|p| p.name == n).map(|p| &p.value) {
                            if v.len() == 1 {
                                shutter[k] = v[0];
                            }
                        }
                    }
                    context.shutter = Some(camera);
                    // The camera draws its times in its own shutter; the plugin holds each in the medium's.
                    if shutter[1] > shutter[0] {
                        self.shutter = Some(camera);
                    }
                }
                // The budget is shared: each medium may use what the media built before it left.
                context.max_bytes = Some(self.max_memory.saturating_sub(self.media_bytes).max(1));
                let vol = plugin.create_volume_with(&list, &context).map_err(|e| {
                    // An error about one parameter carries where it was given (the plugin's error detail, not its
                    // text): report it there, the message without that prefix.
                    let text = e.to_string();
                    let given = match &e {
                        firemedium_loader::Error::Status { detail, .. } => detail.location.clone(),
                        _ => None,
                    };
                    let at = given.and_then(|g| params.params().iter().find(|p| p.loc.to_string() == g)).map(|p| {
                        let prefix = format!("{}: ", p.loc);
                        (&p.loc, text.strip_prefix(&prefix).unwrap_or(&text))
                    });
                    match at {
                        Some((ploc, rest)) => err(ploc, format!("medium \"{name}\" ({ty}): {rest}")),
                        None => err(loc, format!("medium \"{name}\" ({ty}): {text}")),
                    }
                })?;
                let info = vol.info();
                if info.channel_space != firemedium_abi::FM_SPACE_SPECTRAL || info.channels as usize != self.bins.n() {
                    return Err(err(loc, format!("medium \"{name}\": {} channels in space {}, but the renderer uses {} spectral bins (all media share the scene's bins; colormode rgb is for other hosts)", info.channels, info.channel_space, self.bins.n())));
                }
                let units = self.check_colour(name, ty == "fire", &vol, loc)?;
                // Species whose strong lines lie outside the render's bins emit nothing there: say so.
                if ty == "fire" {
                    let hot = vol.temperature_range().ok().flatten().map_or(2000.0, |[_, hi]| hi.max(1000.0));
                    let species = list.iter().filter(|p| p.name == "species").flat_map(|p| match &p.value {
                        Value::String(v) => v.clone(),
                        _ => Vec::new(),
                    });
                    for sym in species {
                        if let Some(m) = lines_outside(&sym, hot, (info.lambda_min, info.lambda_max)) {
                            self.warn(loc, format!("medium \"{name}\": {m}"));
                        }
                    }
                }
                // A temperature grid that is not in kelvin (a tool's relative units read as kelvin) leaves the
                // fire black: say so, with the presets that read each tool's units.
                if let (true, Ok(Some([_, hi]))) = (ty == "fire", vol.temperature_range()) {
                    if hi > 0.0 && hi < 500.0 {
                        self.warn(loc, format!("medium \"{name}\": its temperature peaks at {hi:.3} K, too cool to glow visibly (below 500 K): if the grid is not in kelvin, set \"string source\" (\"houdini\": × 5000 K; \"blender\": a Mantaflow flame grid) or \"float temperatureremap\" [a b ka kb]"));
                    }
                }
                self.media_bytes = self.media_bytes.saturating_add(info.bytes);
                self.media_reports.push(MediumReport { name: name.to_string(), bytes: info.bytes, seconds: info.build_seconds, channels: info.channels, light: None, light_left_out: None });
                let host = if self.host_tracking { Some(host_majorants(&vol).map_err(|m| err(loc, format!("medium \"{name}\": --tracking host: {m}")))?) } else { None };
                Medium::Plugin { vol, to_medium, to_world: to_medium.inverse(), scatters: info.scatters != 0, g: info.g, name: name.to_string(), units, host }
            }
            "" => return Err(err(loc, format!("MakeNamedMedium \"{name}\": missing \"string type\""))),
            other => return Err(err(loc, format!("MakeNamedMedium \"{name}\": medium type \"{other}\" is not supported (fire, uniformgrid, nanovdb, homogeneous)"))),
        };
        self.named_media.insert(name.to_string(), self.media.len());
        self.media.push(m);
        Ok(())
    }

    pub(super) fn shape(&mut self, ty: &str, p: &ParamDict, loc: &Loc) -> Result<(), Error> {
        if let (Some(_), Some((object, _))) = (self.st.area, &self.current_object) {
            let m = format!("{ty} in object \"{object}\": area lights are not supported with object instancing (as pbrt-v4): the shape is kept, its emission left out");
            self.warn(loc, m);
        }
        let to_world = affine_f32(&self.st.ctm);
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
                });
            }
            "disk" => {
                let phimax = num(p, "phimax", 360.0).clamp(0.0, 360.0).to_radians() as f32;
                self.add_prim(Geom::Disk { to_world, to_obj, h: num(p, "height", 0.0) as f32, r: num(p, "radius", 1.0) as f32, ri: num(p, "innerradius", 0.0) as f32, phimax });
            }
            "cylinder" => {
                let phimax = num(p, "phimax", 360.0).clamp(0.0, 360.0).to_radians() as f32;
                let (z0, z1) = (num(p, "zmin", -1.0), num(p, "zmax", 1.0));
                self.add_prim(Geom::Cylinder { to_world, to_obj, r: num(p, "radius", 1.0) as f32, zmin: z0.min(z1) as f32, zmax: z0.max(z1) as f32, phimax });
            }
            "trianglemesh" | "bilinearmesh" | "plymesh" | "loopsubdiv" => {
                let (pos, idx, normals, uvs) = if ty == "plymesh" {
                    let f = string(p, "filename").ok_or_else(|| err(loc, "plymesh: missing \"string filename\""))?;
                    crate::render::ply::read(&self.dir.join(f), self.max_memory).map_err(|e| err(loc, e))?
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
            other => return Err(err(loc, format!("shape \"{other}\" is not supported (sphere, disk, cylinder, trianglemesh, bilinearmesh, plymesh, loopsubdiv)"))),
        }
        self.check_bounds(first, ty, loc)?;
        Ok(())
    }
}

/// When species `sym`'s lines outside the bins `lo`–`hi` nm carry more than a tenth of its visible line emission
/// at `t` K (each line's power g_k A_ki e^(−E_k/kT) hc/λ, weighted by the eye's ȳ): what is lost, and how to keep it.
pub(crate) fn lines_outside(sym: &str, t: f64, (lo, hi): (f64, f64)) -> Option<String> {
    use firemedium_core::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT};
    let e = firemedium_core::species::Element::by_symbol(sym).ok()?;
    let lum = |l: &firemedium_core::species::Line| {
        let power =
            l.g_k as f64 * l.a_ki * (-l.e_k / (BOLTZMANN * t)).exp() * PLANCK * SPEED_OF_LIGHT
                / (l.lambda_nm * 1e-9);
        power * firemedium_core::cie::cmf(l.lambda_nm).y
    };
    let total: f64 = e.lines().iter().map(lum).sum();
    let out: Vec<&firemedium_core::species::Line> = e
        .lines()
        .iter()
        .filter(|l| (l.lambda_nm < lo || l.lambda_nm > hi) && lum(l) > 0.0)
        .collect();
    let lost: f64 = out.iter().map(|l| lum(l)).sum();
    if !(total > 0.0 && lost > 0.1 * total) {
        return None;
    }
    let mut strongest = out.clone();
    strongest.sort_by(|a, b| lum(b).total_cmp(&lum(a)));
    let names: Vec<String> = strongest
        .iter()
        .take(3)
        .map(|l| format!("{:.1}", l.lambda_nm))
        .collect();
    Some(format!(
        "species {sym}: its lines at {} nm carry {:.0} % of its visible line emission (luminance-weighted at {t:.0} K) and lie outside the render's bins, {lo:.0}–{hi:.0} nm: they are left out (widen the bins with \"float lambdamin\" / \"float lambdamax\", up to 380–780 nm)",
        names.join(", "),
        100.0 * lost / total
    ))
}

/// The majorant grid of a volume the renderer will track itself, or why it cannot: a layer the medium level
/// cannot carry (named by the plugin), or motion (its per-bin coefficients have no time).
fn host_majorants(vol: &Volume) -> Result<crate::render::tracker::Majorants, String> {
    let m = vol
        .medium()
        .map_err(|e| format!("{e}; render it with --tracking plugin"))?;
    if m.features() & firemedium_abi::FM_FEATURE_MOTION != 0 {
        return Err("it moves (motion blur), and the medium level's coefficients in bins have no time; render it with --tracking plugin".into());
    }
    let info = vol.info();
    Ok(crate::render::tracker::Majorants::of(
        m.majorant_grid(),
        [info.bounds_min, info.bounds_max],
    ))
}

#[cfg(test)]
mod tests {
    #[test]
    fn species_lines_outside_the_bins_are_reported() {
        // Potassium's resonance doublet (766.7, 770.1 nm) outside 400–700 nm: nearly all its visible light.
        let m = super::lines_outside("K", 2000.0, (400.0, 700.0)).expect("a warning");
        let pct: f64 = m
            .split(" carry ")
            .nth(1)
            .and_then(|r| r.split(" %").next())
            .and_then(|v| v.parse().ok())
            .unwrap();
        assert!(
            m.contains("766.") && m.contains("770.") && pct > 90.0,
            "{m}"
        );
        // Inside the default 400–780 nm, and sodium's D lines inside 400–700: nothing to say.
        assert!(super::lines_outside("K", 2000.0, (400.0, 780.0)).is_none());
        assert!(super::lines_outside("Na", 2000.0, (400.0, 700.0)).is_none());
    }
}
