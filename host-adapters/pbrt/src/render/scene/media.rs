//! Scene building, media: `MakeNamedMedium` through the plugin (fire, pbrt-v4's grids, the procedural cloud baked
//! into one), pbrt-v4's `homogeneous` and `rgbgrid` in the host, the plugin's colour weights checked against the
//! film's, and what a medium needs when the renderer tracks it itself (`--tracking host`).

use super::builder::{affine, num, nums, string, Builder};
use super::{err, Camera, Error, Medium, MediumReport};
use crate::render::pbrt_v4::Kind;
use crate::render::shapes::Bvh;
use crate::render::spectrum::S;
use firemedium_core::rgb_spectrum::RgbUse;
use firemedium_loader::{Param as LParam, Plugin, Value, Volume};
use firemedium_pbrt_parser::{Loc, ParamDict};
use glam::DVec3;
use std::path::Path;

impl Builder {
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
            self.ctx.max_memory.saturating_sub(self.media_bytes),
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

    /// A named medium under its transform (`MakeNamedMedium`): each kind built by its own function.
    pub(super) fn medium(&mut self, m: &super::description::Medium) -> Result<(), Error> {
        let (name, loc) = (m.name.as_str(), &m.entity.loc);
        let params = &ParamDict::new(&m.entity.params);
        let ty = m.entity.ty.clone();
        let to_medium = affine(&m.ctm.inverse());
        let built = match ty.as_str() {
            "homogeneous" => self.homogeneous(name, params, loc)?,
            "rgbgrid" => Medium::RgbGrid(std::sync::Arc::new(self.rgbgrid(name, params, to_medium, loc)?)),
            "fire" | "uniformgrid" | "nanovdb" | "cloud" => self.plugin_medium(name, &ty, params, to_medium, loc)?,
            "" => return Err(err(loc, format!("MakeNamedMedium \"{name}\": missing \"string type\""))),
            other => return Err(err(loc, format!("MakeNamedMedium \"{name}\": medium type \"{other}\" is not supported (fire, uniformgrid, nanovdb, homogeneous, rgbgrid, cloud){}", firemedium_pbrt_parser::v3::type_hint("medium", other)))),
        };
        self.named_media.insert(name.to_string(), self.media.len());
        self.media.push(built);
        self.media_locs.push(loc.clone());
        let ty = string(params, "type").unwrap_or("");
        self.finish(Kind::Medium, ty, &format!("{ty} medium \"{name}\""), params)
    }

    /// pbrt-v4's `homogeneous` medium, in the host.
    fn homogeneous(&mut self, name: &str, params: &ParamDict, loc: &Loc) -> Result<Medium, Error> {
        let scale = num(params, "scale", 1.0) as f32;
        // pbrt-v4: a named preset (measured, mm⁻¹) replaces sigma_a and sigma_s; an unknown one warns.
        let preset = string(params, "preset").filter(|n| !n.is_empty());
        let found = preset.and_then(crate::render::media_presets::preset);
        if let (Some(n), None) = (preset, found) {
            self.warn(loc, format!("homogeneous medium \"{name}\": preset \"{n}\" not found (pbrt-v4's named media: Apple, Skin1, Wholemilk, Ketchup, …); sigma_a and sigma_s are used"));
        }
        let (sa, ss) = match found {
            Some((s, a)) => (
                self.bins.uplift(a, RgbUse::Unbounded),
                self.bins.uplift(s, RgbUse::Unbounded),
            ),
            None => (
                self.constant(params, "sigma_a", self.bins.mask(), RgbUse::Unbounded)?,
                self.constant(params, "sigma_s", self.bins.mask(), RgbUse::Unbounded)?,
            ),
        };
        let (sa, ss) = (sa * scale, ss * scale);
        let le = self.emitted(params, "Le", false, num(params, "Lescale", 1.0))?;
        Ok(Medium::Homogeneous(super::Homogeneous {
            sa,
            ss,
            le,
            g: num(params, "g", 0.0).clamp(-0.99, 0.99),
        }))
    }

    /// A medium the plugin builds: a fire, pbrt-v4's `uniformgrid` and `nanovdb`, or pbrt-v4's procedural cloud
    /// baked into a grid. Its parameters pass to the plugin unchanged, but for the type, the plugin file (read by
    /// `load`'s pre-scan, which loaded the plugin), and relative paths; the renderer's context beside them.
    fn plugin_medium(
        &mut self,
        name: &str,
        ty: &str,
        params: &ParamDict,
        to_medium: glam::DAffine3,
        loc: &Loc,
    ) -> Result<Medium, Error> {
        let plugin = self.plugin(loc)?;
        // The plugin reads and checks every parameter itself, reporting any it does not use.
        params.mark_all_used();
        // The parameters in the plugin's list, and beside them where each was given: an error about one comes
        // back with its index in the list (not with a location to match as text).
        let (mut list, mut origins) = plugin_params(params);
        if ty == "cloud" {
            self.bake_cloud(name, &mut list, &mut origins, loc)?;
        }
        // The renderer's context goes beside the scene's parameters, not among them (a parameter the scene
        // sets itself wins in the plugin): what the medium's type means, the scene's bins, threads, frame.
        let mut context = firemedium_loader::Context {
            threads: self.ctx.threads.map(|n| n as u32),
            frame: self.ctx.frame,
            directory: Some(self.ctx.dir.clone()),
            kind: Some(if ty == "fire" {
                firemedium_loader::Kind::Fire
            } else {
                firemedium_loader::Kind::Pbrt
            }),
            bins: Some(self.plugin_bins),
            ..Default::default()
        };
        // Motion blur: every plugin medium gets the camera's shutter (one that does not move ignores it);
        // once the built volume says it moves — by its velocity, or by its embers' own — the camera draws a
        // time per sample, the plugin holding each in the medium's own shutter. (The host reads none of the
        // fire's parameter names for this: the volume's features say it.)
        let camera = self.camera_shutter;
        context.shutter = Some(camera);
        // The budget is shared: each medium may use what the media built before it left.
        context.max_bytes = Some(self.ctx.max_memory.saturating_sub(self.media_bytes).max(1));
        let vol = plugin.create_volume_with(&list, &context).map_err(|e| {
            // An error about one parameter carries its index in the list (the plugin's error detail):
            // report it where that parameter was given, else at the medium.
            let at = match &e {
                firemedium_loader::Error::Status { detail, .. } => {
                    detail.index.and_then(|i| origins.get(i).copied())
                }
                _ => None,
            };
            err(at.unwrap_or(loc), format!("medium \"{name}\" ({ty}): {e}"))
        })?;
        let info = vol.info();
        if info.channel_space != firemedium_abi::FM_SPACE_SPECTRAL
            || info.channels as usize != self.bins.n()
        {
            return Err(err(loc, format!("medium \"{name}\": {} channels in space {}, but the renderer uses {} spectral bins (all media share the scene's bins; colormode rgb is for other hosts)", info.channels, info.channel_space, self.bins.n())));
        }
        let units = self.check_colour(name, ty == "fire", &vol, loc)?;
        // What the plugin's build found a user should hear (species' lines outside the bins, flame colours
        // the model cannot give).
        for m in vol
            .notes()
            .map_err(|e| err(loc, format!("medium \"{name}\": {e}")))?
        {
            self.warn(loc, format!("medium \"{name}\": {m}"));
        }
        // A temperature grid that is not in kelvin (a tool's relative units read as kelvin) leaves the
        // fire black: say so, with the presets that read each tool's units.
        if let (true, Ok(Some([_, hi]))) = (ty == "fire", vol.temperature_range()) {
            if hi > 0.0 && hi < 500.0 {
                self.warn(loc, format!("medium \"{name}\": its temperature peaks at {hi:.3} K, too cool to glow visibly (below 500 K): if the grid is not in kelvin, set \"string source\" (\"houdini\": × 5000 K; \"blender\": a Mantaflow flame grid) or \"float temperatureremap\" [a b ka kb]"));
            }
        }
        let moves = firemedium_abi::FM_FEATURE_MOTION | firemedium_abi::FM_FEATURE_EMBERS;
        if camera[1] > camera[0]
            && vol
                .features()
                .map_err(|e| err(loc, format!("medium \"{name}\": {e}")))?
                & moves
                != 0
        {
            self.shutter = Some(camera);
        }
        self.media_bytes = self.media_bytes.saturating_add(info.bytes);
        self.reports.media.push(MediumReport {
            name: name.to_string(),
            bytes: info.bytes,
            seconds: info.build_seconds,
            channels: info.channels,
            light: None,
            light_left_out: None,
        });
        let host = if self.ctx.host_tracking {
            Some(host_majorants(&vol, name, loc)?)
        } else {
            None
        };
        // The camera's view of a scattering fire by the march: its pixels' variance falls 10-30-fold for
        // 2-6× their time (docs/results); for pbrt-v4's grids pbrt-v4's own estimator unless asked (where the
        // surfaces hold the error the march's time is not repaid: the scattering room's surfaces lose 1.2-1.3×).
        let camera_march = info.scatters != 0 && self.ctx.camera_march.unwrap_or(ty == "fire");
        Ok(Medium::Plugin(super::Plugin {
            vol,
            to_medium,
            to_world: to_medium.inverse(),
            scatters: info.scatters != 0,
            g: info.g,
            name: name.to_string(),
            units,
            host,
            camera_march,
        }))
    }

    /// pbrt-v4's procedural cloud, baked into a grid the plugin renders as a pbrt grid medium: its own parameters
    /// taken from the list, the grid put in their place (located at the medium).
    fn bake_cloud<'a>(
        &self,
        name: &str,
        list: &mut Vec<LParam>,
        origins: &mut Vec<&'a Loc>,
        loc: &'a Loc,
    ) -> Result<(), Error> {
        let mut take = |param: &str, def: f64| -> f64 {
            let Some(i) = list.iter().position(|p| p.name == param) else {
                return def;
            };
            origins.remove(i);
            match list.remove(i).value {
                Value::Float(v) => v.first().copied().unwrap_or(def),
                _ => def,
            }
        };
        let (dens, wisp, freq) = (
            take("density", 1.0),
            take("wispiness", 1.0),
            take("frequency", 5.0),
        );
        if ![dens, wisp, freq]
            .iter()
            .all(|v| v.is_finite() && *v >= 0.0 && *v <= 1e6)
        {
            return Err(err(loc, format!("cloud medium \"{name}\": density {dens}, wispiness {wisp}, frequency {freq}: expected values from 0 to 1e6")));
        }
        let corner = |param: &str, def: f64| {
            list.iter()
                .find(|p| p.name == param)
                .and_then(|p| match &p.value {
                    Value::Point3(v) if v.len() == 3 => Some(DVec3::new(v[0], v[1], v[2])),
                    _ => None,
                })
                .unwrap_or(DVec3::splat(def))
        };
        let (p0, p1) = (corner("p0", 0.0), corner("p1", 1.0));
        let n = crate::render::cloud::BAKE as i64;
        // The bake (f64 here, f32 in the plugin) must fit in what the media built so far left.
        crate::budget::check(
            &format!("cloud medium \"{name}\": its {n}³ baked grid"),
            (n * n * n) as u64,
            12,
            self.ctx.max_memory.saturating_sub(self.media_bytes),
        )
        .map_err(|e| err(loc, e))?;
        for axis in ["nx", "ny", "nz"] {
            list.push(LParam::int(axis, n));
            origins.push(loc);
        }
        list.push(LParam {
            name: "density".into(),
            value: Value::Float(crate::render::cloud::bake(p0, p1, dens, wisp, freq)),
            at: None,
        });
        origins.push(loc);
        Ok(())
    }
}

/// The scene's parameters of a plugin medium as the plugin's list (but `type` and `plugin`), typed as the scene
/// wrote them, and where each was given.
fn plugin_params<'a>(params: &'a ParamDict) -> (Vec<LParam>, Vec<&'a Loc>) {
    let mut list: Vec<LParam> = Vec::new();
    let mut origins: Vec<&Loc> = Vec::new();
    for p in params.params() {
        if p.name == "type" || p.name == "plugin" {
            continue;
        }
        let value = match (&p.values, p.ty.as_str()) {
            // (File names as the scene wrote them: the plugin resolves its own against the scene's
            // folder, `Context::directory`.)
            (firemedium_pbrt_parser::Values::Strings(v), _) => Value::String(v.clone()),
            (firemedium_pbrt_parser::Values::Bools(v), _) => Value::Bool(v.clone()),
            (firemedium_pbrt_parser::Values::Numbers(v), "integer") => {
                Value::Integer(v.iter().map(|&x| x as i64).collect())
            }
            (firemedium_pbrt_parser::Values::Numbers(v), "point3") => Value::Point3(v.clone()),
            (firemedium_pbrt_parser::Values::Numbers(v), "vector3") => Value::Vector3(v.clone()),
            (firemedium_pbrt_parser::Values::Numbers(v), "rgb") => Value::Rgb(v.clone()),
            (firemedium_pbrt_parser::Values::Numbers(v), "spectrum") => Value::Spectrum(v.clone()),
            // pbrt-v4's `BlackbodySpectrum(T)`, peak-normalised, as 1 nm (λ, value) pairs over 360–830.
            (firemedium_pbrt_parser::Values::Numbers(v), "blackbody") => {
                let t = v.first().copied().unwrap_or(0.0);
                let peak = firemedium_core::blackbody::spectral_radiance(
                    t,
                    firemedium_core::blackbody::WIEN / t * 1e9,
                );
                Value::Spectrum(
                    (360..=830)
                        .flat_map(|l| {
                            [
                                l as f64,
                                if t > 0.0 && peak > 0.0 {
                                    firemedium_core::blackbody::spectral_radiance(t, l as f64)
                                        / peak
                                } else {
                                    0.0
                                },
                            ]
                        })
                        .collect(),
                )
            }
            (firemedium_pbrt_parser::Values::Numbers(v), _) => Value::Float(v.clone()),
        };
        list.push(LParam {
            name: p.name.clone(),
            value,
            at: None,
        });
        origins.push(&p.loc);
    }
    (list, origins)
}

/// The command line's `NAME=VALUE` light parameters typed as the plugin's table declares them (the light's own
/// or the volume's).
pub(super) fn light_params(
    plugin: &Plugin,
    given: &[(String, String)],
) -> Result<Vec<LParam>, Error> {
    typed_params(
        plugin,
        &["light"],
        "the fire light",
        "--fire-light-param",
        given,
    )
}

/// `NAME=VALUE` parameters from a command line (`flag`) typed as the plugin's table declares them for
/// `components` (`what` names them in an error, which lists the parameters they have).
pub fn typed_params(
    plugin: &Plugin,
    components: &[&str],
    what: &str,
    flag: &str,
    given: &[(String, String)],
) -> Result<Vec<LParam>, Error> {
    let table = plugin.parameters();
    given
        .iter()
        .map(|(name, value)| {
            let info = table
                .iter()
                .find(|p| components.contains(&p.component.as_str()) && &p.name == name)
                .ok_or_else(|| {
                    let names: Vec<&str> = table
                        .iter()
                        .filter(|p| components.contains(&p.component.as_str()))
                        .map(|p| p.name.as_str())
                        .collect();
                    Error::value(format!(
                        "{flag} {name}={value}: {what} has no parameter \"{name}\" (it has {})",
                        names.join(", ")
                    ))
                })?;
            let bad = |kind: &str| {
                Error::value(format!("{flag} {name}={value}: \"{value}\" is not {kind}"))
            };
            Ok(match info.ty.as_str() {
                "integer" => LParam::int(name, value.parse().map_err(|_| bad("an integer"))?),
                "float" => LParam::float(name, value.parse().map_err(|_| bad("a number"))?),
                "bool" => LParam::bool(name, value.parse().map_err(|_| bad("true or false"))?),
                _ => LParam::string(name, value),
            })
        })
        .collect()
}

/// Loads the fire plugin from `path`, or as [`Plugin::from_env`] finds it. One of the host's two `unsafe` calls (the
/// other gives the build's freed memory back, `scene::load`): loading a
/// library runs its initialisers, so the renderer loads only the file the user named (`--plugin`, a medium's
/// `"string plugin"`, `FIREMEDIUM_PLUGIN`, `FIREMEDIUM_PLUGIN_PATH`) or the one built beside it.
#[allow(unsafe_code)]
pub fn load_plugin(path: Option<&Path>) -> Result<Plugin, firemedium_loader::Error> {
    match path {
        // SAFETY: a plugin file the user named; the loader checks its ABI version, size and entries.
        Some(p) => unsafe { Plugin::load(p) },
        // SAFETY: the file the user's environment names, or the plugin built beside this executable.
        None => unsafe { Plugin::from_env() },
    }
}

/// What a built scene shows about a plugin medium that its statements could not: the camera inside its shapes
/// without being in the medium (pbrt-v4's semantics: the fire is not seen from there), shapes smaller than its
/// data (the fire clipped), and the medium only ever outside its shapes while its data lies inside them (the
/// MediumInterface's inside and outside swapped).
pub(super) fn boundary_warnings(
    medium: &Medium,
    bvh: &Bvh,
    m: usize,
    shapes: Option<&obvhs::aabb::Aabb>,
    camera: &Camera,
) -> Vec<String> {
    let (Medium::Plugin(plugin), Some(shapes)) = (medium, shapes) else {
        return Vec::new();
    };
    let name = &plugin.name;
    // The data's box in the world.
    let [lo, hi] = plugin.world_box();
    let (slo, shi) = (shapes.min.as_dvec3(), shapes.max.as_dvec3());
    let mut out = Vec::new();
    let (inside, outside) =
        bvh.prims
            .iter()
            .filter_map(|p| p.media)
            .fold((0, 0), |(i, o), (pi, po)| {
                (
                    i + usize::from(pi == Some(m)),
                    o + usize::from(po == Some(m)),
                )
            });
    let centre = 0.5 * (lo + hi);
    let holds = |p: DVec3| (0..3).all(|a| p[a] > slo[a] && p[a] < shi[a]);
    if inside == 0 && outside > 0 && holds(centre) {
        out.push(format!("medium \"{name}\" is only ever the outside of the shapes that name it, while its data lies inside them: MediumInterface takes the inside medium first (MediumInterface \"{name}\" \"\")"));
    }
    let tolerance = 0.01 * (hi - lo).max_element();
    if inside > 0 && (0..3).any(|a| lo[a] < slo[a] - tolerance || hi[a] > shi[a] + tolerance) {
        out.push(format!(
            "medium \"{name}\": its data reaches ({:.3}, {:.3}, {:.3}) … ({:.3}, {:.3}, {:.3}), beyond the shapes that bound it ({:.3}, {:.3}, {:.3}) … ({:.3}, {:.3}, {:.3}): the fire is cut where they end",
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z, slo.x, slo.y, slo.z, shi.x, shi.y, shi.z
        ));
    }
    let eye = camera.to_world.translation;
    if camera.medium != Some(m)
        && inside > 0
        && holds(eye)
        && (0..3).all(|a| eye[a] > lo[a] && eye[a] < hi[a])
    {
        out.push(format!("the camera is inside the shapes bounding medium \"{name}\" but not in the medium: its rays start outside it and cross no boundary into it, so the fire is missing from where it stands (a MediumInterface \"\" \"{name}\" before Camera puts the camera in it)"));
    }
    out
}

/// The majorant grid of the volume of medium `name` (defined at `loc`) that the renderer will track itself, or
/// why it cannot: a layer the medium level cannot carry (named by the plugin), or motion (its per-bin
/// coefficients have no time).
fn host_majorants(
    vol: &Volume,
    name: &str,
    loc: &Loc,
) -> Result<crate::render::tracker::Majorants, Error> {
    let refuse = |why: &dyn std::fmt::Display| {
        err(
            loc,
            format!("medium \"{name}\": --tracking host: {why}; render it with --tracking plugin"),
        )
    };
    let m = vol.medium().map_err(|e| refuse(&e))?;
    if m.features() & firemedium_abi::FM_FEATURE_MOTION != 0 {
        return Err(refuse(
            &"it moves (motion blur), and the medium level's coefficients in bins have no time",
        ));
    }
    let info = vol.info();
    Ok(crate::render::tracker::Majorants::of(
        m.majorant_grid(),
        [info.bounds_min, info.bounds_max],
    ))
}
