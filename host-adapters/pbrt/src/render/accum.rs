//! What a pixel's samples add up to beyond R, G, B: the sums behind the AOVs ([`super::aov`]) — each radiance
//! part through the beauty's own sensor transform, coverage, depth, the first surface's albedo and normal.

use super::aov::{Aov, Split, Visible};
use super::scene::Scene;
use super::spectrum::S;
use glam::DVec3;

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

    /// The pixel's channels for `aovs` ([`channel_names`]' order), given the weight of all its samples and their
    /// number.
    pub fn finish(&self, scene: &Scene, aovs: &[Aov], weights: f64, samples: u32) -> Vec<f32> {
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
                Aov::Samples => out.push(samples as f64),
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
