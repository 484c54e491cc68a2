//! The pbrt-v4 host: a volumetric path tracer for fire scenes. `scene` builds a render scene from a pbrt-v4 file
//! (media through the plugin), `integrator` is `volpath`, and [`render`] runs it over tiles in parallel into an
//! [`Image`] (linear sRGB and XYZ, absolute units), which [`Image::write_exr`] writes.

mod accum;
pub mod aov;
pub mod area;
pub mod bsdf;
pub mod cloud;
pub mod distrib;
pub mod envmap;
pub mod film;
pub mod guide;
pub mod integrator;
pub mod layered;
mod lights;
pub mod lobes;
pub mod material;
mod media;
pub mod media_presets;
pub mod microfacet;
pub mod named_spectra;
mod passes;
mod paths;
pub mod pbrt_v4;
pub mod pixel;
pub mod ply;
pub mod profile;
pub mod rgbgrid;
pub mod scene;
pub mod sensors;
pub mod shapes;
pub mod spectrum;
pub mod subdiv;
pub mod tracker;

use aov::Aov;
use firemedium_core::cie;
use firemedium_core::rng::Rng;
use glam::{DVec3, Vec3A};
pub use passes::{render_progressive, Pass, Progress, Progressive, Stop};
use pixel::Samples;
use rayon::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, LazyLock};

/// The signal that interrupted the render (SIGINT, SIGTERM or SIGHUP; 0 while none has): the tiles not finished
/// are left out and the finished ones are written. Shared with the signal handler, hence the `Arc`.
pub static INTERRUPTED: LazyLock<Arc<AtomicUsize>> = LazyLock::new(Default::default);

/// Whether a signal has asked the render to stop.
pub fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::Relaxed) != 0
}

/// A rendered image: linear sRGB (absolute: Y in cd/m² when the scene is absolute), row-major.
#[derive(Debug, Clone)]
pub struct Image {
    pub w: usize,
    pub h: usize,
    pub rgb: Vec<[f32; 3]>,
    pub xyz: Vec<DVec3>,
    pub complete: bool,
    /// Where the image's first pixel lies on the full film, and the full film's size (a crop window or pixel
    /// bounds render part of it: the EXR's data window inside its display window).
    pub origin: (usize, usize),
    pub full: (usize, usize),
    /// Channels beside R, G, B, their names and, per pixel, their values (pixel-major): the spectral film's
    /// buckets (`S0.<centre>nm`, mean spectral radiance) or the gbuffer film's channels.
    pub extra: Option<(Vec<String>, Vec<f32>)>,
    /// What the render was (scene, frame, spp, seed), written into the EXR ([`crate::imageio::RENDER_ATTRIBUTE`]):
    /// what `firemedium merge` checks its tiles against.
    pub meta: Vec<(String, String)>,
}

impl Image {
    /// Writes the linear, absolute image as an RGB float EXR, with the fire's hottest temperature (K), if any,
    /// as the [`crate::imageio::FIRE_TEMPERATURE_ATTRIBUTE`] attribute.
    pub fn write_exr(
        &self,
        path: &std::path::Path,
        fire_temperature: Option<f64>,
        fp16: bool,
    ) -> Result<(), crate::Error> {
        let window = crate::imageio::Window {
            origin: self.origin,
            full: self.full,
        };
        if let Some((names, values)) = &self.extra {
            return crate::imageio::write_channels_exr(
                path,
                self.w,
                self.h,
                &self.rgb,
                names,
                values,
                fire_temperature,
                fp16,
                window,
                &self.meta,
            );
        }
        crate::imageio::write_exr_as(
            path,
            self.w,
            self.h,
            &self.rgb,
            fire_temperature,
            fp16,
            window,
            &self.meta,
        )
    }
}

/// Render statistics.
#[derive(Debug, Clone, Default)]
pub struct Stats {
    pub seconds: f64,
    pub camera_rays: usize,
    /// Fire-light samples (next-event estimation toward fires).
    pub fire_light_samples: u64,
    /// Plugin calls that failed inside the render (their paths gave nothing from there on), and the first one's
    /// message.
    pub plugin_failures: (u64, Option<String>),
    /// Passes over the image, and the estimate of its relative RMSE after the last ([`passes`]).
    pub passes: usize,
    pub rel_rmse_estimate: Option<f64>,
    /// Why the render stopped sampling.
    pub stop: Stop,
    /// Camera samples the noise estimate's twins took (not in the image; see [`passes`]).
    pub twin_samples: u64,
    /// Where the paths' time and light went, when profiled (`--profile`): the printed table.
    pub profile: Option<String>,
}

const TILE: usize = 16;

fn hash(a: u64, b: u64, c: u64, d: u64) -> u64 {
    let mut h = a ^ 0x9E37_79B9_7F4A_7C15;
    for x in [b, c, d] {
        h = (h ^ x)
            .wrapping_mul(0x100_0000_01B3)
            .rotate_left(29)
            .wrapping_add(0x2545_F491_4F6C_DD1D);
    }
    h
}

/// Renders the scene with its samples per pixel in passes (see [`passes`]), no threshold or time limit;
/// `progress` is told of every tile finished.
pub fn render(
    scene: &scene::Scene,
    seed: u64,
    progress: &(dyn Fn(Progress) + Sync),
) -> (Image, Stats) {
    render_progressive(scene, seed, &Progressive::default(), progress)
}

/// The name of the spectral film's channel at `nm`: OpenEXR's spectral layout as pbrt-v4 writes it
/// (`S0.<centre>nm`, the decimal point as a comma).
fn spectral_channel_name(nm: f64) -> String {
    format!("S0.{nm:.3}nm")
        .replace('.', ",")
        .replacen(',', ".", 1)
}

/// Where the gbuffer film's values live: the transform from world to its space (camera or world) and its normal
/// matrix, and the scale pbrt-v4 puts on a pixel's footprint (`Camera::Approximate_dp_dxy`: max(⅛, 1/√spp), 1
/// without pixel jitter).
struct GSpace {
    from_world: glam::DAffine3,
    normals: glam::DMat3,
    footprint: f64,
}

impl GSpace {
    fn new(scene: &scene::Scene, world: bool) -> GSpace {
        let from_world = if world {
            glam::DAffine3::IDENTITY
        } else {
            scene.camera.to_world.inverse()
        };
        GSpace {
            from_world,
            normals: from_world.matrix3.inverse().transpose(),
            footprint: if scene.pixel_jitter {
                (1.0 / (scene.spp as f64).sqrt()).max(0.125)
            } else {
                1.0
            },
        }
    }

    /// One camera sample's visible surface in the gbuffer's space: the albedo as an rgb reflectance under D65
    /// (pbrt-v4 multiplies it by the colour space's illuminant), and dz/dx, dz/dy from where the pinhole rays
    /// one pixel over meet the surface's tangent plane.
    fn sample(&self, scene: &scene::Scene, fx: f64, fy: f64, v: &aov::Visible) -> film::GSample {
        let p = v.p.as_dvec3();
        let ng = v.ng.as_dvec3();
        let dz = |fx: f64, fy: f64| {
            let (o, d) = pinhole_ray(scene, fx, fy);
            let den = ng.dot(d);
            if den.abs() < 1e-12 {
                return 0.0;
            }
            let q = o + d * (ng.dot(p - o) / den);
            self.from_world
                .transform_vector3((q - p) * self.footprint)
                .z
        };
        film::GSample {
            albedo_rgb: accum::albedo_rgb(scene, &v.albedo),
            p: self.from_world.transform_point3(p),
            n: (self.normals * ng).normalize_or_zero(),
            ns: (self.normals * v.ns.as_dvec3()).normalize_or_zero(),
            dzdx: dz(fx + 1.0, fy),
            dzdy: dz(fx, fy + 1.0),
        }
    }
}

/// The camera ray through film position (`fx`, `fy`) without a lens, in world space (f64).
fn pinhole_ray(scene: &scene::Scene, fx: f64, fy: f64) -> (DVec3, DVec3) {
    let (org, dir) = camera_space_ray(scene, fx, fy);
    let cam = &scene.camera;
    (
        cam.to_world.transform_point3(org),
        cam.to_world.transform_vector3(dir).normalize(),
    )
}

/// The pinhole (or orthographic) ray through film position (`fx`, `fy`) in camera space: origin, direction.
fn camera_space_ray(scene: &scene::Scene, fx: f64, fy: f64) -> (DVec3, DVec3) {
    let cam = &scene.camera;
    let (w, h) = (scene.res.0 as f64, scene.res.1 as f64);
    let sx = cam.screen[0] + fx / w * (cam.screen[1] - cam.screen[0]);
    let sy = cam.screen[3] - fy / h * (cam.screen[3] - cam.screen[2]);
    // Perspective: through the pinhole toward the screen at z = 1; orthographic: parallel, from the screen.
    if cam.orthographic {
        (DVec3::new(sx, sy, 0.0), DVec3::Z)
    } else {
        (
            DVec3::ZERO,
            DVec3::new(sx * cam.tan_half, sy * cam.tan_half, 1.0),
        )
    }
}

/// The camera ray through film position (`fx`, `fy`) in pixels (origin top left), its lens sample from `rng`
/// when the camera has a lens.
pub fn camera_ray(scene: &scene::Scene, fx: f64, fy: f64, rng: &mut Samples) -> (Vec3A, Vec3A) {
    let cam = &scene.camera;
    let (mut org, mut dir) = camera_space_ray(scene, fx, fy);
    if cam.lens_radius > 0.0 {
        let (r, phi) = (
            rng.next_f64().sqrt() * cam.lens_radius,
            2.0 * std::f64::consts::PI * rng.next_f64(),
        );
        // The point in focus along the pinhole ray, seen from the lens sample (pbrt-v4's thin lens).
        let focus = org + dir * (cam.focal_distance / dir.z);
        org += DVec3::new(r * phi.cos(), r * phi.sin(), 0.0);
        dir = focus - org;
    }
    let o = cam.to_world.transform_point3(org);
    let d = cam.to_world.transform_vector3(dir).normalize();
    (Vec3A::from(o.as_vec3()), Vec3A::from(d.as_vec3()))
}

/// The pixels whose centre and four corners all see a diffuse surface first: no fire, no mirror or coating
/// reflecting it, inside the pixel's footprint.
pub fn surface_mask(sc: &scene::Scene, rng: &mut Rng) -> Vec<bool> {
    let mut rng = Samples::random(rng.clone());
    let (w, h) = sc.res;
    (0..w * h)
        .map(|i| {
            let (x, y) = ((i % w) as f64, (i / w) as f64);
            [(0.5, 0.5), (0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .all(|&(u, v)| {
                    let (o, d) = camera_ray(sc, x + u, y + v, &mut rng);
                    sc.bvh
                        .intersect(o, d, sc.eps, f32::INFINITY)
                        .and_then(|hit| sc.bvh.prim(&hit).material)
                        .is_some_and(|m| matches!(sc.materials[m], scene::Material::Diffuse(_)))
                })
        })
        .collect()
}
