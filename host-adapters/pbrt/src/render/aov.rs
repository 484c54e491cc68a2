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

use super::spectrum::S;
use glam::Vec3A;

/// The surface a camera ray sees first (pbrt-v4's `VisibleSurface`), for the `gbuffer` film: world-space point,
/// geometric and shading normals, and the material's directional albedo ρ(wo) (one-sample estimate).
#[derive(Debug, Clone, Copy)]
pub struct Visible {
    pub p: Vec3A,
    pub ng: Vec3A,
    pub ns: Vec3A,
    pub albedo: S,
}

/// Where a camera sample's light came from, for the AOVs: the radiance the path had gathered when it reached
/// its first and its second scattering vertex (all of it so far was seen from the camera, then the first vertex's
/// direct light), the lights it saw directly, and the coverage of its camera ray. Contributions come in that
/// order along a path, so two marks split it: seen = first mark, direct = second − first, indirect = the rest.
#[derive(Debug, Clone, Copy, Default)]
pub struct Split {
    /// The path's radiance at its first and second scattering vertex (none: the path ended before).
    pub marks: [Option<S>; 2],
    /// Lights (area, infinite) seen from the camera: the rest of what was seen is the media's emission.
    pub emission: S,
    /// 1 − the camera ray's transmittance when it escaped (none: a surface or a medium stopped it: 1).
    pub alpha: Option<f32>,
}

impl Split {
    /// Marks the radiance `l` gathered when the path reaches a scattering vertex at `depth`.
    pub(super) fn mark(split: &mut Option<&mut Split>, depth: usize, l: S) {
        if let Some(sp) = split.as_deref_mut() {
            if depth < 2 && sp.marks[depth].is_none() {
                sp.marks[depth] = Some(l);
            }
        }
    }
    /// The path's radiance `l` in four parts: media emission seen from the camera, lights seen from the camera,
    /// direct and indirect light (they sum to `l`, to rounding).
    pub fn parts(&self, l: S) -> [S; 4] {
        let first = self.marks[0].unwrap_or(l);
        let second = self.marks[1].unwrap_or(l);
        [
            first - self.emission,
            self.emission,
            second - first,
            l - second,
        ]
    }
}

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
