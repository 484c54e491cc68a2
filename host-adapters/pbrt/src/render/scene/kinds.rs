//! What each kind of light and medium holds, as the scene builds it; what each does for the integrator is in its
//! own file under `render/lights` and `render/media` (this side imports neither: the arrows run from them to
//! the scene).

use crate::render::scene::Portal;
use crate::render::spectrum::S;
use crate::render::tracker::Majorants;
use firemedium_loader::Volume;
use glam::{DAffine3, Mat3A, Vec3A};

/// A plugin medium placed in the scene; `to_medium` maps world to medium space.
pub struct Plugin {
    pub vol: Volume,
    pub to_medium: DAffine3,
    /// The inverse of `to_medium`.
    pub to_world: DAffine3,
    pub scatters: bool,
    pub g: f64,
    pub name: String,
    /// The medium's majorant grid when the renderer tracks it itself (`--tracking host`; None: the plugin's
    /// whole-ray queries).
    pub host: Option<Majorants>,
    /// The factor that takes the medium's radiance to the film's units: 1, or 1/683 for a pbrt grid (its
    /// radiance in pbrt-v4's units, Y = ∫ L ȳ) in a scene whose film is absolute (a fire's, Y = 683 ∫ L ȳ).
    pub units: f32,
    /// A scattering medium whose emission the camera gathers by the plugin's march along the whole segment
    /// (deterministic), delta tracking then only choosing where the path scatters; otherwise at delta
    /// tracking's tentative collisions, as pbrt-v4 (`--camera-emission`).
    pub camera_march: bool,
}

impl Plugin {
    /// The data's box in the world: its medium-space bounds' corners placed (low and high corners).
    pub fn world_box(&self) -> [glam::DVec3; 2] {
        let info = self.vol.info();
        let (a, c) = (info.bounds_min, info.bounds_max);
        let mut b = [glam::DVec3::INFINITY, glam::DVec3::NEG_INFINITY];
        for k in 0..8 {
            let corner = glam::DVec3::new(
                if k & 1 == 0 { a[0] } else { c[0] },
                if k & 2 == 0 { a[1] } else { c[1] },
                if k & 4 == 0 { a[2] } else { c[2] },
            );
            let w = self.to_world.transform_point3(corner);
            b = [b[0].min(w), b[1].max(w)];
        }
        b
    }
}

/// Constant σ_a, σ_s, Le per bin and the phase function's g.
#[derive(Debug, Clone)]
pub struct Homogeneous {
    pub sa: S,
    pub ss: S,
    pub le: S,
    pub g: f64,
}

/// A point light: intensity `i` at `p`.
#[derive(Debug, Clone)]
pub struct Point {
    pub p: Vec3A,
    pub i: S,
}

/// A spot light: intensity `i` at `p` along `dir`, falling off (smoothstep⁴) between the cone's cosines.
#[derive(Debug, Clone)]
pub struct Spot {
    pub p: Vec3A,
    pub dir: Vec3A,
    pub cos_total: f32,
    pub cos_falloff: f32,
    pub i: S,
}

/// A distant light: radiance `l` arriving from direction `to_light`.
#[derive(Debug, Clone)]
pub struct Distant {
    pub to_light: Vec3A,
    pub l: S,
}

/// What an infinite light sends: a constant radiance, or a map.
#[derive(Debug, Clone)]
#[allow(clippy::large_enum_variant)] // one per infinite light
pub enum Sky {
    Constant(S),
    /// An environment map: world → light-space rotation, linear RGB × scale, equal-area square (pbrt-v4) or
    /// lat-long (2:1) parameterisation.
    Map {
        img: std::sync::Arc<crate::imageio::RgbImage>,
        to_light: Mat3A,
        scale: f32,
        basis: [S; 3],
        /// Directions drawn by the map's luminance (pbrt-v4 importance-samples its image lights).
        dist: std::sync::Arc<crate::render::envmap::EnvSampler>,
    },
}

/// An infinite light, seen through `portal` only when it has one.
#[derive(Debug, Clone)]
pub struct Infinite {
    pub sky: Sky,
    pub portal: Option<Portal>,
}

/// Radiance `l` from primitive `prim`'s front, or both sides.
#[derive(Debug, Clone)]
pub struct Area {
    pub prim: usize,
    pub l: S,
    pub twosided: bool,
}

/// The fire light of plugin medium `medium`.
#[derive(Debug, Clone)]
pub struct Fire {
    pub light: std::sync::Arc<firemedium_loader::Light>,
    pub medium: usize,
}

impl std::fmt::Debug for Plugin {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Plugin")
            .field("name", &self.name)
            .field("scatters", &self.scatters)
            .field("host_tracked", &self.host.is_some())
            .field("camera_march", &self.camera_march)
            .finish()
    }
}
