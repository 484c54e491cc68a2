//! pbrt-v4 scene → render scene, in pbrt-v4's two steps: the directives are read with pbrt's graphics state into
//! a description whose entities carry their `file:line:col` (`description`; nothing built, no file but the
//! scene's opened), the command line's settings applied to it once, then the scene is built from it (`build`,
//! one `create` per kind). Everything a fire scene needs is built; anything else is reported by name: ignored
//! with a warning when it cannot change the picture much, refused with an error when it would be misread.

mod build;
mod builder;
mod create;
mod description;
mod kinds;
mod materials;
mod media;
pub use media::{load_plugin, typed_params};

use super::shapes::Bvh;
use super::spectrum::Bins;
use description::{Description, Reader};
use firemedium_pbrt_parser::{parse_file, Loc, ParamDict};
use glam::{DAffine3, Vec3A};
use std::path::{Path, PathBuf};

use crate::Error;

/// A statement at `loc` refused.
fn err(loc: &Loc, m: impl std::fmt::Display) -> Error {
    Error::at(loc, m)
}

pub use crate::render::material::{Material, Tex};

/// Lights (area lights live on primitives): each kind in its own file under `render/lights`, its answers to the
/// integrator there; the scene holds which kind each light is.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // a handful per scene
pub enum Light {
    Point(Point),
    Spot(Spot),
    Distant(Distant),
    /// A constant or mapped sky, behind a portal or not.
    Infinite(Infinite),
    /// The fire light of a plugin medium (importance-samples its emission).
    Fire(Fire),
    Area(Area),
}

pub use kinds::{Area, Distant, Fire, Infinite, Point, Sky, Spot};

/// Participating media: each kind in its own file under `render/media` (`rgbgrid` beside it), its answers to the
/// integrator there; the scene holds which kind each medium is.
#[allow(clippy::large_enum_variant)] // a handful per scene
pub enum Medium {
    /// A fire (or pbrt grid medium) living in the plugin.
    Plugin(Plugin),
    /// pbrt's homogeneous medium.
    Homogeneous(Homogeneous),
    /// pbrt-v4's rgbgrid medium, rendered by the host.
    RgbGrid(std::sync::Arc<crate::render::rgbgrid::RgbGrid>),
}

pub use kinds::{Homogeneous, Plugin};

impl std::fmt::Debug for Medium {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Medium::Plugin(p) => write!(f, "Plugin({})", p.name),
            Medium::Homogeneous(_) => write!(f, "Homogeneous"),
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
    /// Where a share of the surfaces' directions aims: the box of the fires that scatter and emit
    /// ([`crate::render::guide`]).
    pub guide: Option<crate::render::guide::Guide>,
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
                Medium::Plugin(p) => p.vol.white_temperature().ok().flatten(),
                _ => None,
            })
            .filter(|t| *t > 0.0)
            .reduce(f64::max)
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
    /// A fire light for every emitting medium, a scattering one's too (`--fire-light` given by name; `auto`
    /// leaves a scattering fire's out).
    pub fire_light_forced: bool,
    /// More of the fire lights' parameters, (name, value) as given (docs/reference/params.md, `light`: `cell`,
    /// `linestep`, …), typed by the plugin's table.
    pub fire_light_params: Vec<(String, String)>,
    /// Scattering events inside a fire sample its own light too ([`Scene::fire_light_inside`]).
    pub fire_light_inside: bool,
    /// The share of the surfaces' directions aimed at a scattering fire (`--fire-guide`; `None`: auto, 0: off).
    pub fire_guide: Option<f32>,
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
    /// How the camera gathers a scattering plugin medium's emission (`--camera-emission`; `None`: auto, the
    /// march for a `fire`, pbrt-v4's tracking for pbrt-v4's grids).
    pub camera_march: Option<bool>,
}

/// The film's resolution the scene at `path` asks for (pbrt-v4's 1280 × 720 when its Film does not say), read by
/// parsing alone — nothing is loaded or built (a farm cuts the film into tiles before any node renders it).
pub fn film_resolution(path: &Path) -> Result<(usize, usize), Error> {
    match read(path)?.film {
        Some(film) => create::film_resolution(&ParamDict::new(&film.params), &film.loc),
        None => Ok((1280, 720)),
    }
}

/// The scene at `path` as read: nothing built, no file but the scene's (and its includes) opened.
fn read(path: &Path) -> Result<Description, Error> {
    let mut reader = Reader::default();
    let parsed = parse_file(path, &mut reader);
    reader.finish(parsed)
}

/// Parses and builds the scene at `path`.
pub fn load(path: &Path, ov: &Overrides) -> Result<Scene, Error> {
    let mut desc = read(path)?;
    desc.apply(ov);
    let scene = build::build(path, &desc, ov)?;
    drop(desc);
    crate::heap::give_back_freed();
    Ok(scene)
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

    /// What reading and building found is reported in the scene's order, though media are built first.
    #[test]
    fn warnings_come_in_the_scenes_order() {
        let dir =
            std::env::temp_dir().join(format!("firemedium-scene-order-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("s.pbrt");
        std::fs::write(
            &scene,
            "Camera \"perspective\"\nFilm \"rgb\" \"integer xresolution\" 4 \"integer yresolution\" 4\nWorldBegin\nAttribute \"shape\" \"float radius\" 2\nMakeNamedMedium \"h\" \"string type\" \"homogeneous\" \"string preset\" \"nope\"\nColorSpace \"aces2065-1\"\n",
        )
        .unwrap();
        let sc = load(&scene, &Overrides::default()).unwrap();
        let lines: Vec<&str> = sc
            .warnings
            .iter()
            .map(|w| w.split(": warning").next().unwrap_or(""))
            .collect();
        assert_eq!(lines.len(), 3, "{:?}", sc.warnings);
        assert!(
            lines[0].ends_with(":4:1") && lines[1].ends_with(":5:1") && lines[2].ends_with(":6:1"),
            "{:?}",
            sc.warnings
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
