//! pbrt-v4 scene → render scene. Walks the parser's directives with pbrt's graphics state (CTM, attribute stack,
//! named materials/textures/media, object instances). Everything a fire scene needs is built; anything else is
//! reported by name: ignored with a warning when it cannot change the picture much, refused with an error when
//! it would be misread.

mod builder;
mod directives;
mod materials;
mod media;
use media::{boundary_warnings, light_params};
pub use media::{load_plugin, typed_params};

use super::pbrt_v4::Kind;
use super::shapes::Bvh;
use super::spectrum::{Bins, S};
use builder::{affine, num, nums, string, Builder, State};
use firemedium_core::spectrum::SpectralGrid;
use firemedium_loader::{Param as LParam, Value, Volume};
use firemedium_pbrt_parser::{parse_file, Collect, Directive, Loc, ParamDict};
use glam::{DAffine3, DMat4, Mat3A, Vec3A};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use crate::Error;

/// A statement at `loc` refused.
fn err(loc: &Loc, m: impl std::fmt::Display) -> Error {
    Error::at(loc, m)
}

pub use crate::render::material::{Material, Tex};

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
        portal: Option<Portal>,
    },
    /// An environment map: world → light-space rotation, linear RGB × scale, equal-area square (pbrt-v4) or
    /// lat-long (2:1) parameterisation.
    InfiniteMap {
        img: std::sync::Arc<crate::imageio::RgbImage>,
        to_light: Mat3A,
        scale: f32,
        basis: [S; 3],
        /// Directions drawn by the map's luminance (pbrt-v4 importance-samples its image lights).
        dist: std::sync::Arc<crate::render::envmap::EnvSampler>,
        portal: Option<Portal>,
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
        /// The medium's majorant grid when the renderer tracks it itself (`--tracking host`; None: the
        /// plugin's whole-ray queries).
        host: Option<crate::render::tracker::Majorants>,
        /// The factor that takes the medium's radiance to the film's units: 1, or 1/683 for a pbrt grid (its
        /// radiance in pbrt-v4's units, Y = ∫ L ȳ) in a scene whose film is absolute (a fire's, Y = 683 ∫ L ȳ).
        units: f32,
    },
    /// pbrt's homogeneous medium.
    Homogeneous { sa: S, ss: S, le: S, g: f64 },
    /// pbrt-v4's rgbgrid medium, rendered by the host.
    RgbGrid(std::sync::Arc<crate::render::rgbgrid::RgbGrid>),
}

impl std::fmt::Debug for Medium {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Medium::Plugin { name, .. } => write!(f, "Plugin({name})"),
            Medium::Homogeneous { .. } => write!(f, "Homogeneous"),
            Medium::RgbGrid(g) => write!(f, "RgbGrid({:?})", g.n),
        }
    }
}

/// pbrt-v4's perspective or orthographic camera (camera space: x right, y up, z forward).
#[derive(Debug, Clone)]
pub struct Camera {
    pub to_world: DAffine3,
    pub tan_half: f64,
    pub screen: [f64; 4],
    pub lens_radius: f64,
    pub focal_distance: f64,
    pub medium: Option<usize>,
    /// Parallel rays from the screen window (in camera-space units) instead of rays through a pinhole.
    pub orthographic: bool,
}

/// pbrt-v4's infinite-light `portal`: a rectangle (world space) through which the light enters the scene.
/// The light shines only into the half-space the portal faces (directions w with w · n > 0, n = e₂ × e₁ from the
/// edges p₀p₃ and p₀p₁, as pbrt-v4's `PortalImageInfiniteLight` frame), and next-event estimation samples
/// points on the portal uniformly by area (pbrt-v4 samples its image over the portal: the same integral, another
/// variance); directions that miss the portal are left to BSDF sampling, whose MIS weight is 1 there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Portal {
    pub p0: Vec3A,
    pub e1: Vec3A,
    pub e2: Vec3A,
    pub n: Vec3A,
    pub area: f32,
}

impl Portal {
    /// The portal through corners p₀…p₃ (in order), or why it is not one: pbrt-v4 asks for a planar rectangle.
    pub fn new(p: [Vec3A; 4]) -> Result<Portal, Error> {
        let (e1, e2) = (p[1] - p[0], p[3] - p[0]);
        let n = e2.cross(e1);
        let area = n.length();
        let planar = (p[2] - (p[0] + e1 + e2)).length() <= 1e-3 * e1.length().max(e2.length());
        let square = e1.normalize_or_zero().dot(e2.normalize_or_zero()).abs() < 1e-3;
        if !(area > 0.0 && area.is_finite() && planar && square) {
            return Err(Error::value(format!(
                "\"point3 portal\" {:?}: expected the four corners of a rectangle, in order (as pbrt-v4)",
                p.map(|v| v.to_array())
            )));
        }
        Ok(Portal {
            p0: p[0],
            e1,
            e2,
            n: n / area,
            area,
        })
    }

    /// A point on the portal seen from `p`: direction, distance and solid-angle pdf; None behind it.
    pub fn sample(&self, p: Vec3A, u: [f32; 2]) -> Option<(Vec3A, f32, f32)> {
        let q = self.p0 + self.e1 * u[0] + self.e2 * u[1];
        let v = q - p;
        let d2 = v.length_squared();
        let w = v / d2.sqrt();
        let cos = w.dot(self.n);
        (cos > 0.0 && d2 > 0.0).then(|| (w, d2.sqrt(), d2 / (self.area * cos)))
    }

    /// The solid-angle pdf with which [`Portal::sample`] from `p` draws direction `w`: 0 when `w` misses it.
    pub fn pdf(&self, p: Vec3A, w: Vec3A) -> f32 {
        let cos = w.dot(self.n);
        if !(cos > 0.0) {
            return 0.0;
        }
        let t = (self.p0 - p).dot(self.n) / cos;
        if !(t > 0.0) {
            return 0.0;
        }
        let r = p + w * t - self.p0;
        let (a, b) = (
            r.dot(self.e1) / self.e1.length_squared(),
            r.dot(self.e2) / self.e2.length_squared(),
        );
        if (0.0..=1.0).contains(&a) && (0.0..=1.0).contains(&b) {
            t * t / (self.area * cos)
        } else {
            0.0
        }
    }
}

/// Why no path of the scene can ask a light for a sample, if none can: `volpath` samples the lights (next-event
/// estimation) only at a surface hit with a non-specular lobe or at a scattering event in a medium, and only
/// below `maxdepth`. Then a fire light would be built for nothing (the fire's emission still reaches every path
/// that crosses it).
fn no_light_sampling(b: &builder::Builder) -> Option<String> {
    if b.maxdepth <= 1 {
        // (pbrt-v4 counts a medium's emission only before the maxdepth-th bounce: what a fire light samples from
        // a vertex lies past it.)
        return Some(format!(
            "maxdepth {}: no path vertex samples a fire's light below the maximum depth",
            b.maxdepth
        ));
    }
    let scatters = b.media.iter().any(|m| match m {
        Medium::Plugin { scatters, .. } => *scatters,
        Medium::Homogeneous { ss, .. } => ss.max() > 0.0,
        Medium::RgbGrid(g) => g.scatters(),
    });
    let surfaces = b.prims.iter().any(|p| {
        p.material
            .and_then(|m| b.materials.get(m))
            .is_some_and(|m| m.may_be_non_specular(&b.materials))
    });
    (!scatters && !surfaces).then(|| {
        "no surface with a non-specular lobe and no scattering medium: no path samples a light"
            .into()
    })
}

/// A fire light as the plugin built it.
#[derive(Debug, Clone, Copy)]
pub struct LightReport {
    pub info: firemedium_loader::LightInfo,
    /// How many of the volume's channels its line marches.
    pub line_channels: u32,
}

/// What the plugin built for one medium.
#[derive(Debug, Clone)]
pub struct MediumReport {
    pub name: String,
    pub bytes: u64,
    pub seconds: f64,
    pub channels: u32,
    /// The fire light, when built.
    pub light: Option<LightReport>,
    /// Why the fire light was left out, when it was.
    pub light_left_out: Option<String>,
}

/// A render-ready scene.
#[derive(Debug)]
pub struct Scene {
    pub bins: Bins,
    pub bvh: Bvh,
    /// Per medium, the box around the shapes whose interface names it (None: none does) — a ray that misses it
    /// neither enters nor leaves the medium.
    pub media_boxes: Vec<Option<obvhs::aabb::Aabb>>,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub media: Vec<Medium>,
    pub camera: Camera,
    pub res: (usize, usize),
    pub spp: usize,
    /// Where a pixel's samples fall, and the pixel filter that places and weighs them.
    pub sampler: crate::render::pixel::Sampler,
    pub filter: crate::render::pixel::Filter,
    /// The film's response: imaging ratio, white balance, sample clamp, half floats.
    pub response: crate::render::film::Response,
    /// pbrt-v4's `spectral` film: its buckets.
    pub spectral: Option<crate::render::film::Buckets>,
    /// pbrt-v4's `gbuffer` film.
    pub gbuffer: Option<crate::render::film::GBuffer>,
    /// The pixels rendered, [x0, x1) × [y0, y1) of the `res` film (pbrt-v4's pixel bounds; all of it by default).
    pub bounds: [usize; 4],
    /// The scene's seed (`Option "integer seed"`; the command line's `--seed` wins) and whether pixel samples
    /// spread over the pixel (`Option "bool disablepixeljitter" true`: all at its centre).
    pub seed: u64,
    pub pixel_jitter: bool,
    /// The shutter (frames) when a medium blurs by its velocity: each camera sample draws its time in it (and
    /// none is drawn otherwise, so a scene without motion blur samples as before).
    pub shutter: Option<[f64; 2]>,
    /// Output variables written beside the beauty (`--aov`), in channel order.
    pub aovs: Vec<crate::render::aov::Aov>,
    pub maxdepth: usize,
    /// Whether a scattering event inside a fire samples that fire's own light (`--fire-light-inside`); by
    /// default only surfaces and the events in other media do (docs/results/log.md measures both).
    pub fire_light_inside: bool,
    pub film_name: Option<String>,
    pub eps: f32,
    pub warnings: Vec<String>,
    pub media_reports: Vec<MediumReport>,
}

impl Scene {
    /// The hottest temperature (K) of the scene's fire media whose colour is the physics' (a tint or a colour
    /// ramp is meant to be seen against D65), if any has a temperature grid.
    pub fn fire_temperature(&self) -> Option<f64> {
        self.media
            .iter()
            .filter_map(|m| match m {
                Medium::Plugin { vol, .. } => vol.white_temperature().ok().flatten(),
                _ => None,
            })
            .filter(|t| *t > 0.0)
            .reduce(f64::max)
    }
}

/// The film's pixel bounds (pbrt-v4's `FilmBaseParameters`): a crop window (the command line's, else the scene's)
/// covers the pixels [⌈W x0⌉, ⌈W x1⌉) × [⌈H y0⌉, ⌈H y1⌉); else pixel bounds, clamped to the film; else the film.
fn pixel_bounds(b: &Builder, ov: &Overrides, path: &Path) -> Result<[usize; 4], Error> {
    let (w, h) = (b.res.0 as f64, b.res.1 as f64);
    // Where a window was given: its statement, or the command line (named after the scene).
    let refuse = |loc: Option<&Loc>, m: String| match loc {
        Some(l) => Error::at(l, m),
        None => Error::file(path.display(), format!("command line: {m}")),
    };
    let crop = ov
        .crop
        .map(|c| (c, None))
        .or(b.crop.as_ref().map(|(c, l)| (*c, Some(l))));
    let bounds = if let Some((c, _)) = crop {
        let (cx0, cx1) = (
            c[0].min(c[1]).clamp(0.0, 1.0),
            c[0].max(c[1]).clamp(0.0, 1.0),
        );
        let (cy0, cy1) = (
            c[2].min(c[3]).clamp(0.0, 1.0),
            c[2].max(c[3]).clamp(0.0, 1.0),
        );
        [
            (w * cx0).ceil(),
            (w * cx1).ceil(),
            (h * cy0).ceil(),
            (h * cy1).ceil(),
        ]
        .map(|v| v as usize)
    } else if let Some((p, loc)) = ov
        .pixel_bounds
        .map(|p| (p, None))
        .or(b.pixel_bounds.as_ref().map(|(p, l)| (*p, Some(l))))
    {
        let clamp = |v: f64, n: f64| v.clamp(0.0, n) as usize;
        let r = [
            clamp(p[0], w),
            clamp(p[1], w),
            clamp(p[2], h),
            clamp(p[3], h),
        ];
        if r[1] <= r[0] || r[3] <= r[2] {
            return Err(refuse(loc, format!("pixel bounds {p:?} leave no pixel of the {}×{} film: expected x0 < x1, y0 < y1 inside it", b.res.0, b.res.1)));
        }
        r
    } else {
        [0, b.res.0, 0, b.res.1]
    };
    if bounds[1] <= bounds[0] || bounds[3] <= bounds[2] {
        return Err(refuse(
            crop.and_then(|c| c.1),
            format!(
                "the crop window leaves no pixel of the {}×{} film",
                b.res.0, b.res.1
            ),
        ));
    }
    Ok(bounds)
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
    /// A fire light for every emitting medium, a scattering one's too (`--fire-light` given by name; `auto`
    /// leaves a scattering fire's out).
    pub fire_light_forced: bool,
    /// More of the fire lights' parameters, (name, value) as given (docs/reference/params.md, `light`: `cell`,
    /// `linestep`, …), typed by the plugin's table.
    pub fire_light_params: Vec<(String, String)>,
    /// Scattering events inside a fire sample its own light too ([`Scene::fire_light_inside`]).
    pub fire_light_inside: bool,
    /// Film resolution instead of the scene's.
    pub res: Option<(usize, usize)>,
    /// pbrt-v4's `--cropwindow x0 x1 y0 y1` and `--pixelbounds x0 x1 y0 y1`, instead of the film's.
    pub crop: Option<[f64; 4]>,
    pub pixel_bounds: Option<[f64; 4]>,
    /// Threads the plugin may use to build each medium (the render's own; `None`: every core).
    pub threads: Option<usize>,
    /// The memory budget in bytes (`None`: half the machine's memory, [`crate::budget::default_bytes`]): the
    /// film is checked against it, and each plugin grid (`maxbytes`, unless the scene sets it).
    pub max_memory: Option<u64>,
    /// The frame number every plugin medium's dataset name takes (`####`, `%04d`), unless the scene sets one.
    pub frame: Option<i64>,
    /// Output variables written beside the beauty (`--aov`).
    pub aovs: Vec<crate::render::aov::Aov>,
    /// Plugin media tracked by the renderer through the ABI's medium level (majorant grid and point
    /// coefficients), as pbrt-v4 or Mitsuba 3 would, instead of the plugin's whole-ray queries (`--tracking host`).
    pub host_tracking: bool,
}

/// The film's resolution the scene at `path` asks for (pbrt-v4's 1280 × 720 when its Film does not say), read by
/// parsing alone — nothing is loaded or built (a farm cuts the film into tiles before any node renders it).
pub fn film_resolution(path: &Path) -> Result<(usize, usize), Error> {
    let mut c = Collect::default();
    parse_file(path, &mut c)?;
    let mut res = (1280, 720);
    for (d, loc) in &c.0 {
        if let Directive::Film(_, params) = d {
            let p = ParamDict::new(params);
            let side = |name: &str, default: f64| -> Result<usize, Error> {
                let v = p.float(name, default);
                if v.fract() == 0.0 && (1.0..=65536.0).contains(&v) {
                    Ok(v as usize)
                } else {
                    Err(err(
                        loc,
                        format!("film: \"integer {name}\" {v}: expected 1 to 65536 pixels"),
                    ))
                }
            };
            res = (side("xresolution", 1280.0)?, side("yresolution", 720.0)?);
        }
    }
    Ok(res)
}

/// Parses and builds the scene at `path`.
pub fn load(path: &Path, ov: &Overrides) -> Result<Scene, Error> {
    let mut c = Collect::default();
    parse_file(path, &mut c)?;
    // Pre-scan: the render bins (from the media, or the defaults of the plugin that renders them) and the
    // photometric scale.
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut fire = false;
    let mut plugin_path = ov.plugin.clone();
    let mut first_medium: Option<&Loc> = None;
    for (d, loc) in &c.0 {
        if let Directive::MakeNamedMedium(_, p) = d {
            let p = &ParamDict::new(p);
            match string(p, "type") {
                Some("fire") => fire = true,
                Some("uniformgrid" | "nanovdb" | "cloud") => {}
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
    // The bins: with a plugin medium (a fire, or pbrt-v4's grids), the plugin's measured default, which its march
    // kernel holds in vector lanes; without one, the whole CIE table (380–780 nm, 10 nm bins), as pbrt-v4 samples
    // wavelengths over the visible range (400–700 nm would leave out 0.5 % of a 2000 K grid's luminance; 380–400
    // nm holds 0.004 % of ∫ȳ).
    let (mut lo, mut hi, mut n) = (380.0, 780.0, 40);
    if let Some(p) = &plugin {
        let default = SpectralGrid::default();
        (lo, hi, n) = (default.min_nm(), default.max_nm(), default.count());
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
        return Err(Error::file(
            path.display(),
            format!(
                "{n} spectral bins; the renderer supports at most {}",
                super::spectrum::MAX_CHANNELS
            ),
        ));
    }
    let grid = SpectralGrid::new(lo, hi, n).map_err(|e| Error::file(path.display(), e))?;
    // The film records Y in cd/m² (nits) either way. With a fire, radiance is absolute (683 lm/W); without one it
    // is in pbrt-v4's units, whose film records ∫ L ȳ dλ as it is (K = 1): a pbrt scene's numbers are pbrt-v4's.
    // Lights are normalised to their luminance in both (`Builder::emitted`), and a pbrt grid in a fire's scene is
    // brought to the film's units by its weights' ratio (`Builder::check_colour`).
    let k = if fire { 683.0 } else { 1.0 };
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
        media_locs: Vec::new(),
        media_reports: Vec::new(),
        camera: None,
        res: (1280, 720),
        spp: 16,
        // pbrt-v4's defaults: zsobol and a Gaussian of radius 1.5, σ 0.5.
        sampler: crate::render::pixel::Sampler::ZSobol {
            log2_spp: 0,
            digits: 0,
            seed: 0,
        },
        film_response: Default::default(),
        spectral: None,
        gbuffer: None,
        media_bytes: 0,
        shutter: None,
        seed: 0,
        pixel_jitter: true,
        crop: None,
        pixel_bounds: None,
        filter: crate::render::pixel::Filter::new(
            "gaussian",
            crate::render::pixel::Params {
                radius: [1.5, 1.5],
                sigma: 0.5,
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                tau: 3.0,
            },
        )
        .unwrap_or(crate::render::pixel::Filter::Box { radius: [0.5, 0.5] }),
        maxdepth: 5,
        film_name: None,
        warnings: Vec::new(),
        objects: HashMap::new(),
        object_prims: 0,
        current_object: None,
        bins_params,
        has_fire: fire,
        film_xyz: None,
        threads: ov.threads,
        frame: ov.frame,
        host_tracking: ov.host_tracking,
        max_memory: ov.max_memory.unwrap_or_else(crate::budget::default_bytes),
    };
    // pbrt's default material: diffuse 0.5.
    b.materials
        .push(Material::Diffuse(Tex::Const(bins.mask() * 0.5)));
    b.st.material = Some(0);
    for (d, loc) in c.0 {
        b.directive(d, &loc)?;
    }
    if let Some((_, open)) = b.stack.last() {
        return Err(err(open, "AttributeBegin (or TransformBegin, ObjectBegin) without its End: the scene ends inside it"));
    }
    // The camera, now that the film resolution is known (pbrt allows Film after Camera).
    let (camera_type, cp, camera_from_world, medium, _) = b
        .camera
        .take()
        .ok_or_else(|| Error::file(path.display(), "no Camera directive"))?;
    let cp = &ParamDict::new(&cp);
    if let Some(r) = ov.res {
        b.res = r;
    }
    let bounds = pixel_bounds(&b, ov, path)?;
    // The film: per pixel its XYZ and RGB and the tile's result on the way (64 bytes, with room), and a spectral
    // film's buckets (twice: the tiles' and the image's).
    let bucket_bytes = b.spectral.as_ref().map_or(0, |s| 8 * s.n as u64)
        + b.gbuffer.map_or(0, |_| {
            (8 + 4) * crate::render::film::GBUFFER_CHANNELS.len() as u64
        });
    crate::budget::check(
        &format!(
            "{}: the film of {}×{} pixels",
            path.display(),
            b.res.0,
            b.res.1
        ),
        (b.res.0 as u64) * (b.res.1 as u64),
        64 + bucket_bytes,
        ov.max_memory.unwrap_or_else(crate::budget::default_bytes),
    )?;
    let (w, h) = (b.res.0 as f64, b.res.1 as f64);
    let aspect = num(cp, "frameaspectratio", w / h);
    let screen = match nums(cp, "screenwindow") {
        Some(s) if s.len() == 4 => [s[0], s[1], s[2], s[3]],
        _ if aspect > 1.0 => [-aspect, aspect, -1.0, 1.0],
        _ => [-1.0, 1.0, -1.0 / aspect, 1.0 / aspect],
    };
    let orthographic = camera_type == "orthographic";
    let camera = Camera {
        to_world: affine(&camera_from_world.inverse()),
        tan_half: if orthographic {
            1.0
        } else {
            (num(cp, "fov", 90.0).to_radians() / 2.0).tan()
        },
        screen,
        lens_radius: num(cp, "lensradius", 0.0),
        focal_distance: num(cp, "focaldistance", 1e6),
        medium,
        orthographic,
    };
    // pbrt-v4's imaging ratio: the shutter interval × ISO / 100 (1 by default).
    let exposure = num(cp, "shutterclose", 1.0) - num(cp, "shutteropen", 0.0);
    if !(exposure > 0.0 && exposure <= 1e6) {
        return Err(Error::file(
            path.display(),
            format!(
                "camera: the shutter is open from {} to {}: expected an interval of up to 1e6 s",
                num(cp, "shutteropen", 0.0),
                num(cp, "shutterclose", 1.0)
            ),
        ));
    }
    let f = b.film_response;
    let mut response =
        crate::render::film::Response::new(f.iso, exposure, f.white_k, f.max_component, f.fp16);
    if let Some(name) = f.camera {
        // A named camera: its curves through pbrt-v4's calibration matrix, per bin and in the film's units (K:
        // the film's ȳ weights over the CIE ones), replace the CMFs; the calibration white-balances.
        let m = crate::render::sensors::xyz_from_sensor(name, f.white_k).ok_or_else(|| {
            Error::file(
                path.display(),
                format!("film: sensor \"{name}\": its calibration failed"),
            )
        })?;
        let curves = crate::render::sensors::curves(name).ok_or_else(|| {
            Error::file(path.display(), format!("film: sensor \"{name}\" unknown"))
        })?;
        let cie = firemedium_core::cie::bin_weights_of(&bins.grid, firemedium_core::cie::cmf, 1.0);
        let k = bins.xyz.iter().map(|w| w.y).sum::<f64>() / cie.iter().map(|w| w.y).sum::<f64>();
        response.white_balance = None;
        response.camera = Some(firemedium_core::cie::bin_weights_of(
            &bins.grid,
            |l| m * curves(l),
            k,
        ));
    }
    b.finish(
        Kind::Camera,
        &camera_type,
        &format!("{camera_type} camera"),
        cp,
    )?;
    // Fire lights: every plugin medium that emits gets one, unless switched off or no path can sample it.
    let left_out = if ov.no_fire_light {
        Some("--fire-light off".to_string())
    } else {
        no_light_sampling(&b)
    };
    if let Some(why) = &left_out {
        for rep in &mut b.media_reports {
            rep.light_left_out = Some(why.clone());
        }
    } else {
        let mut report = 0;
        for (mi, m) in b.media.iter().enumerate() {
            if let Medium::Plugin { vol, scatters, .. } = m {
                let r = report;
                report += 1;
                // A fire that scatters: its light is left out unless asked for by name (measured: the light's
                // line estimates the emission that leaves the fire unscattered, while the paths' delta tracking
                // is cheap and finds the scattered rest — on a fire-lit room at albedo 0.8 the light made the
                // render 0.4× as efficient, at albedo 0.3 0.9×: docs/results/log.md).
                if *scatters && !ov.fire_light_forced {
                    if let Some(rep) = b.media_reports.get_mut(r) {
                        rep.light_left_out = Some(
                            "the fire scatters: its light costs more than it saves there (measured; \
                             `--fire-light power` builds it)"
                                .into(),
                        );
                    }
                    continue;
                }
                let mut lp = Vec::new();
                if let Some(w) = &ov.fire_light_weighting {
                    lp.push(firemedium_loader::Param::string("weighting", w));
                }
                if let Some(plugin) = &b.plugin {
                    lp.extend(light_params(plugin, &ov.fire_light_params)?);
                }
                match vol.create_light_with(&lp) {
                    Ok(light) => {
                        if let Some(rep) = b.media_reports.get_mut(r) {
                            rep.light = Some(LightReport {
                                info: light.info(),
                                line_channels: light.line_channels()?,
                            });
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
                        return Err(Error::file(
                            path.display(),
                            format!("fire light of medium {mi}: {e}"),
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
    // pbrt-v4's zsobol takes a power of two samples per pixel, rounding up with a warning.
    let mut spp = ov.spp.unwrap_or(b.spp);
    if matches!(b.sampler, crate::render::pixel::Sampler::ZSobol { .. }) && !spp.is_power_of_two() {
        b.warnings.push(format!(
            "sampler \"zsobol\": {spp} samples per pixel rounded up to {} (a power of two, as pbrt-v4)",
            spp.next_power_of_two()
        ));
        spp = spp.next_power_of_two();
    }
    let bvh = Bvh::new(b.prims);
    let media_boxes: Vec<_> = (0..b.media.len()).map(|m| bvh.media_box(m)).collect();
    for (m, (medium, loc)) in b.media.iter().zip(&b.media_locs).enumerate() {
        for w in boundary_warnings(medium, &bvh, m, media_boxes[m].as_ref(), &camera) {
            b.warnings.push(format!("{loc}: warning: {w}"));
        }
    }
    Ok(Scene {
        bins,
        bvh,
        media_boxes,
        materials: b.materials,
        lights: b.lights,
        media: b.media,
        camera,
        res: b.res,
        spp,
        sampler: b.sampler,
        filter: b.filter,
        response,
        spectral: b.spectral,
        gbuffer: b.gbuffer,
        bounds,
        seed: b.seed,
        pixel_jitter: b.pixel_jitter,
        shutter: b.shutter,
        aovs: ov.aovs.clone(),
        maxdepth: b.maxdepth,
        fire_light_inside: ov.fire_light_inside,
        film_name: b.film_name,
        eps: (extent * 1e-5).max(1e-6),
        warnings: b.warnings,
        media_reports: b.media_reports,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A refused statement comes back as data: its file, line and column, not a message to re-parse; a scene
    /// that cannot be read is a parse error, a missing camera the file's own.
    #[test]
    fn a_refused_statement_carries_its_location() {
        let dir = std::env::temp_dir().join(format!("firemedium-scene-err-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("bad.pbrt");
        std::fs::write(
            &scene,
            "Camera \"perspective\"\nWorldBegin\n  Material \"diffuse\"\n    Shape \"sphere\" \"float radius\" [ -1 ]\n    PixelFilter \"bogus\"\n",
        )
        .unwrap();
        let e = load(&scene, &Overrides::default()).unwrap_err();
        let loc = e.loc().expect("a statement's location");
        assert_eq!((loc.line, loc.col), (5, 5), "{e}");
        assert!(matches!(e, Error::Scene { .. }), "{e:?}");
        assert_eq!(e.exit_status(), 1);

        std::fs::write(&scene, "WorldBegin\n").unwrap();
        let e = load(&scene, &Overrides::default()).unwrap_err();
        assert!(
            matches!(&e, Error::File { message, .. } if message == "no Camera directive"),
            "{e:?}"
        );

        let e = load(&dir.join("missing.pbrt"), &Overrides::default()).unwrap_err();
        assert!(matches!(e, Error::Parse(_)), "{e:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
