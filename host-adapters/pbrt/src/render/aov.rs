//! Arbitrary output variables: what a compositor splits a fire render into, written as `layer.channel`
//! channels of the render's EXR beside R, G, B (and A).
//!
//! - `fire`: the media's emission seen from the camera (before any scattering vertex);
//! - `emission`: lights (area, infinite) seen from the camera;
//! - `direct`: light arriving at the first scattering vertex (surface or medium) straight from its source —
//!   next-event estimation there, and emission found by the bounce ray;
//! - `indirect`: everything after the second vertex.
//!
//! These four sum to the beauty image (to rounding: each is the beauty's own sensor transform, clamp factor
//! and filter weight applied to its part of every sample). Then `alpha` (the main part's A: 1 where a surface or
//! a scattering event stops the camera ray, else 1 − its transmittance through the media), `depth` (camera-space
//! z of the nearest surface among the pixel's samples, +∞ where none), `albedo` and `normal` (the first surface's
//! directional albedo as linear sRGB and its world-space shading normal — a denoiser's guides) and `samples`
//! (samples taken per pixel).

use super::integrator::{Split, Visible};
use super::scene::Scene;
use super::spectrum::S;
use glam::DVec3;

/// One output variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Aov {
    Fire,
    Emission,
    Direct,
    Indirect,
    Alpha,
    Depth,
    Albedo,
    Normal,
    Samples,
}

impl Aov {
    /// Every variable, in the order channels are written.
    pub const ALL: [Aov; 9] = [
        Aov::Fire,
        Aov::Emission,
        Aov::Direct,
        Aov::Indirect,
        Aov::Alpha,
        Aov::Depth,
        Aov::Albedo,
        Aov::Normal,
        Aov::Samples,
    ];

    /// The name `--aov` takes.
    pub fn name(self) -> &'static str {
        match self {
            Aov::Fire => "fire",
            Aov::Emission => "emission",
            Aov::Direct => "direct",
            Aov::Indirect => "indirect",
            Aov::Alpha => "alpha",
            Aov::Depth => "depth",
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Samples => "samples",
        }
    }

    /// Its EXR channels.
    pub fn channels(self) -> &'static [&'static str] {
        match self {
            Aov::Fire => &["fire.R", "fire.G", "fire.B"],
            Aov::Emission => &["emission.R", "emission.G", "emission.B"],
            Aov::Direct => &["direct.R", "direct.G", "direct.B"],
            Aov::Indirect => &["indirect.R", "indirect.G", "indirect.B"],
            Aov::Alpha => &["A"],
            Aov::Depth => &["depth.Z"],
            Aov::Albedo => &["albedo.R", "albedo.G", "albedo.B"],
            Aov::Normal => &["normal.X", "normal.Y", "normal.Z"],
            Aov::Samples => &["samples.Y"],
        }
    }

    /// A comma-separated list (`all` for every one); each named once, in the order written.
    pub fn parse_list(s: &str) -> Result<Vec<Aov>, crate::Error> {
        let mut want = Vec::new();
        for name in s.split(',').map(str::trim).filter(|n| !n.is_empty()) {
            if name == "all" {
                want.extend(Aov::ALL);
                continue;
            }
            let Some(a) = Aov::ALL.iter().find(|a| a.name() == name) else {
                let names: Vec<&str> = Aov::ALL.iter().map(|a| a.name()).collect();
                return Err(crate::Error::value(format!(
                    "'{name}': unknown AOV; expected a comma-separated list of {} (or all)",
                    names.join(", ")
                )));
            };
            want.push(*a);
        }
        if want.is_empty() {
            return Err(crate::Error::value(format!(
                "'{s}': expected at least one AOV"
            )));
        }
        Ok(Aov::ALL.into_iter().filter(|a| want.contains(a)).collect())
    }
}

/// The channel names of `aovs`, in order.
pub fn channel_names(aovs: &[Aov]) -> Vec<String> {
    aovs.iter()
        .flat_map(|a| a.channels().iter().map(|c| c.to_string()))
        .collect()
}

/// A pixel's AOV sums over its samples.
#[derive(Debug, Clone, Default)]
pub struct Pixel {
    /// The four parts' sensor XYZ, weighted (fire, emission, direct, indirect).
    parts: [DVec3; 4],
    alpha: f64,
    albedo: DVec3,
    normal: DVec3,
    /// Camera-space z of the nearest surface seen.
    depth: Option<f64>,
    seen: f64,
}

impl Pixel {
    /// Adds one sample of weight `w`: its radiance `l` split by `split`, the sensor transform of the beauty
    /// (`xyz` of a spectrum) with the beauty's clamp factor `clamp`, and the surface it saw.
    pub fn add(
        &mut self,
        scene: &Scene,
        w: f64,
        l: S,
        split: &Split,
        clamp: f64,
        visible: Option<&Visible>,
    ) {
        for (sum, part) in self.parts.iter_mut().zip(split.parts(l)) {
            *sum += scene.response.sensor_xyz(&scene.bins, &part) * (clamp * w);
        }
        self.alpha += split.alpha.map_or(1.0, f64::from) * w;
        if let Some(v) = visible {
            let z = scene
                .camera
                .to_world
                .inverse()
                .transform_point3(v.p.as_dvec3())
                .z;
            self.depth = Some(self.depth.map_or(z, |d| d.min(z)));
            self.normal += v.ns.as_dvec3() * w;
            self.albedo += albedo_rgb(scene, &v.albedo) * w;
            self.seen += w;
        }
    }

    /// The pixel's channels for `aovs` ([`channel_names`]' order), given the weight of all its samples.
    pub fn finish(&self, scene: &Scene, aovs: &[Aov], weights: f64) -> Vec<f32> {
        let k = if weights != 0.0 { 1.0 / weights } else { 0.0 };
        let rgb = |xyz: DVec3| {
            firemedium_core::cie::xyz_to_linear_srgb(scene.response.finish(xyz * k)).to_array()
        };
        let mut out = Vec::new();
        for a in aovs {
            match a {
                Aov::Fire => out.extend(rgb(self.parts[0])),
                Aov::Emission => out.extend(rgb(self.parts[1])),
                Aov::Direct => out.extend(rgb(self.parts[2])),
                Aov::Indirect => out.extend(rgb(self.parts[3])),
                Aov::Alpha => out.push(self.alpha * k),
                Aov::Depth => out.push(self.depth.unwrap_or(f64::INFINITY)),
                Aov::Albedo => {
                    let a = if self.seen > 0.0 {
                        self.albedo / self.seen
                    } else {
                        DVec3::ZERO
                    };
                    out.extend(a.to_array());
                }
                Aov::Normal => out.extend(self.normal.normalize_or_zero().to_array()),
                Aov::Samples => out.push(scene.spp as f64),
            }
        }
        out.into_iter().map(|v| v as f32).collect()
    }
}

/// A directional albedo (a reflectance spectrum) as linear sRGB under D65 (white stays white).
pub(super) fn albedo_rgb(scene: &Scene, albedo: &S) -> DVec3 {
    let d65 = scene.bins.d65();
    let mut lit = *albedo;
    for (a, e) in lit.0.iter_mut().zip(d65.0) {
        *a *= e;
    }
    let white = scene.bins.luminance(&d65);
    let xyz = scene.bins.to_xyz(&lit) / if white > 0.0 { white } else { 1.0 };
    firemedium_core::cie::xyz_to_linear_srgb(xyz)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_parse_in_channel_order() {
        assert_eq!(
            Aov::parse_list("depth, fire,alpha").unwrap(),
            vec![Aov::Fire, Aov::Alpha, Aov::Depth]
        );
        assert_eq!(Aov::parse_list("all").unwrap(), Aov::ALL.to_vec());
        let e = Aov::parse_list("fire,glow").unwrap_err().to_string();
        assert!(e.contains("'glow'") && e.contains("indirect"), "{e}");
        assert_eq!(
            channel_names(&[Aov::Alpha, Aov::Normal]),
            ["A", "normal.X", "normal.Y", "normal.Z"]
        );
    }
}
