//! The build step: a scene's description ([`super::description`]) made into a render-ready [`Scene`] — the
//! plugin and the spectral bins from the media, then each kind's entities through its `create`, in pbrt-v4's
//! order (film and sampler, media, textures, materials, objects, then the world's shapes, instances and lights in
//! file order), the camera once the film is known, and a fire light per emitting medium that a path can sample.

use super::builder::{affine, num, nums, string, Builder, Context, Placement, Reports};
use super::description::{self, Description, MaterialRef, World};
use super::media::{boundary_warnings, light_params, load_plugin};
use super::{err, Camera, Error, Light, LightReport, Material, Medium, Overrides, Scene, Tex};
use crate::render::pbrt_v4::Kind;
use crate::render::shapes::Bvh;
use crate::render::spectrum::Bins;
use firemedium_core::spectrum::SpectralGrid;
use firemedium_pbrt_parser::{Loc, ParamDict};
use std::collections::HashMap;
use std::path::Path;

/// Why no path of the scene can ask a light for a sample, if none can: `volpath` samples the lights (next-event
/// estimation) only at a surface hit with a non-specular lobe or at a scattering event in a medium, and only
/// below `maxdepth`. Then a fire light would be built for nothing (the fire's emission still reaches every path
/// that crosses it).
fn no_light_sampling(b: &Builder) -> Option<String> {
    if b.maxdepth <= 1 {
        // (pbrt-v4 counts a medium's emission only before the maxdepth-th bounce: what a fire light samples from
        // a vertex lies past it.)
        return Some(format!(
            "maxdepth {}: no path vertex samples a fire's light below the maximum depth",
            b.maxdepth
        ));
    }
    let scatters = b.media.iter().any(|m| match m {
        Medium::Plugin(p) => p.scatters,
        Medium::Homogeneous(h) => h.ss.max() > 0.0,
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

/// The albedo above which a scattering fire's light is left out by default: its light estimates the emission
/// that leaves the fire unscattered, and past this the paths' own tracking finds the scattered rest for less
/// (measured: the fire-lit room at albedo 0.8 0.4× as efficient with the light, at 0.3 0.9×; the smoky looks at
/// 0.16-0.17, their grounds lit by the fire, far smoother with it: docs/results/log.md).
const LIGHT_ALBEDO: f64 = 0.25;

/// What a scattering fire's light meets: its single-scattering albedo, Σ σ_s / Σ σ_t over every channel at the
/// centres of a 24³ lattice over its box (its extinction-weighted albedo; 0 where nothing is there), and whether
/// it emits at any of them. Asked a plane of the lattice at a time: the whole lattice's coefficients in 32 channels
/// would be 5 MB on top of the fire's grids.
#[derive(Debug, Clone, Copy)]
struct Look {
    albedo: f64,
    emits: bool,
}

fn look(vol: &firemedium_loader::Volume) -> Result<Look, firemedium_loader::Error> {
    const N: usize = 24;
    let info = vol.info();
    let (lo, hi) = (info.bounds_min, info.bounds_max);
    let k = N * N * info.channels as usize;
    let (mut sa, mut ss, mut j) = (vec![0f32; k], vec![0f32; k], vec![0f32; k]);
    let (mut s, mut a, mut emits) = (0f64, 0f64, false);
    for z in 0..N {
        let points: Vec<[f64; 3]> = (0..N * N)
            .map(|i| {
                let c = [i % N, i / N, z];
                [0, 1, 2].map(|a| lo[a] + (hi[a] - lo[a]) * (c[a] as f64 + 0.5) / N as f64)
            })
            .collect();
        vol.coefficients(&points, &mut sa, &mut ss, &mut j)?;
        s = ss.iter().fold(s, |acc, &v| acc + f64::from(v));
        a = sa.iter().fold(a, |acc, &v| acc + f64::from(v));
        emits |= j.iter().any(|&v| v > 0.0);
    }
    let t = s + a;
    Ok(Look {
        albedo: if t > 0.0 { s / t } else { 0.0 },
        emits,
    })
}

/// The film's pixel bounds (pbrt-v4's `FilmBaseParameters`): a crop window (the command line's, else the scene's)
/// covers the pixels [⌈W x0⌉, ⌈W x1⌉) × [⌈H y0⌉, ⌈H y1⌉); else pixel bounds, clamped to the film; else the film.
fn pixel_bounds(
    b: &Builder,
    ov: &description::CommandLine,
    path: &Path,
) -> Result<[usize; 4], Error> {
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

/// Fire lights: every plugin medium that emits gets one, unless switched off, no path can sample it, or it
/// scatters much ([`LIGHT_ALBEDO`]); each medium's report says what its light built or why it was left out.
/// Returns the media that scatter and emit.
fn fire_lights(b: &mut Builder, ov: &Overrides, path: &Path) -> Result<Vec<usize>, Error> {
    // Every scattering plugin medium's look (what its light would meet, whether it emits).
    let mut looks = vec![None; b.media.len()];
    for (mi, m) in b.media.iter().enumerate() {
        if let Medium::Plugin(crate::render::scene::Plugin {
            vol,
            scatters: true,
            ..
        }) = m
        {
            looks[mi] = Some(look(vol).map_err(|e| {
                Error::file(path.display(), format!("medium {mi}: its albedo: {e}"))
            })?);
        }
    }
    // Fire lights: every plugin medium that emits gets one, unless switched off or no path can sample it.
    let left_out = if ov.no_fire_light {
        Some("--fire-light off".to_string())
    } else {
        no_light_sampling(b)
    };
    if let Some(why) = &left_out {
        for rep in &mut b.reports.media {
            rep.light_left_out = Some(why.clone());
        }
    } else {
        let mut report = 0;
        for (mi, m) in b.media.iter().enumerate() {
            if let Medium::Plugin(crate::render::scene::Plugin { vol, .. }) = m {
                let r = report;
                report += 1;
                // A fire that scatters much: its light is left out unless asked for by name ([`LIGHT_ALBEDO`]).
                if let (Some(Look { albedo, .. }), false) = (looks[mi], ov.fire_light_forced) {
                    if albedo > LIGHT_ALBEDO {
                        if let Some(rep) = b.reports.media.get_mut(r) {
                            rep.light_left_out = Some(format!(
                            "the fire scatters, albedo {albedo:.2} (above {LIGHT_ALBEDO}): its light \
                             costs more than it saves there (measured; `--fire-light power` builds it)"
                        ));
                        }
                        continue;
                    }
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
                        if let Some(rep) = b.reports.media.get_mut(r) {
                            rep.light = Some(LightReport {
                                info: light.info(),
                                line_channels: light.line_channels()?,
                            });
                        }
                        b.lights.push(Light::Fire(crate::render::scene::Fire {
                            light: std::sync::Arc::new(light),
                            medium: mi,
                        }));
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
    Ok((looks.iter().enumerate())
        .filter(|(_, l)| l.is_some_and(|l| l.emits))
        .map(|(mi, _)| mi)
        .collect())
}

/// The share of the surfaces' directions aimed at a scattering fire's box by default (measured on the scattering
/// room and the smoky campfire look: docs/results/log.md, "Surfaces aiming at a scattering fire").
const GUIDE_SHARE: f32 = 0.5;

/// Where a share of the surfaces' directions aims ([`crate::render::guide`]): the world box around the fires that
/// scatter and emit, each fire's own box (its medium-space bounds in world space) within the shapes that name it.
fn fire_guide(
    media: &[Medium],
    ov: &Overrides,
    fires: &[usize],
    boxes: &[Option<obvhs::aabb::Aabb>],
) -> Option<crate::render::guide::Guide> {
    let share = ov.fire_guide.unwrap_or(GUIDE_SHARE);
    let mut lo = glam::Vec3A::splat(f32::INFINITY);
    let mut hi = -lo;
    for &mi in fires {
        let Medium::Plugin(p) = &media[mi] else {
            continue;
        };
        let [flo, fhi] = p.world_box().map(|v| v.as_vec3a());
        let (flo, fhi) = match boxes.get(mi) {
            Some(Some(s)) => (flo.max(s.min), fhi.min(s.max)),
            _ => (flo, fhi),
        };
        (lo, hi) = (lo.min(flo), hi.max(fhi));
    }
    // (Uniformly over the box: cells weighted by the fire's extinction, its square root or its presence
    // all measured less efficient on the scattering room, their paths deeper in the fire for no less noise. No
    // fire, or a share of 0: an empty box or share, no guide.)
    crate::render::guide::Guide::new(lo, hi, share)
}

/// The plugin the scene's plugin media need (from `--plugin`, the first such medium's `"string plugin"` — relative
/// to the scene's folder `dir` — or the environment), loaded; none without such a medium. With whether the scene
/// holds a `fire` (its film then records absolute radiance).
fn scene_plugin(
    dir: &Path,
    desc: &Description,
    ov: &Overrides,
) -> Result<(Option<firemedium_loader::Plugin>, bool), Error> {
    let mut fire = false;
    let mut plugin_path = ov.plugin.clone();
    let mut first_medium: Option<&Loc> = None;
    for m in &desc.media {
        let loc = &m.entity.loc;
        {
            let p = &ParamDict::new(&m.entity.params);
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
    Ok((plugin, fire))
}

/// The builder before the scene's statements: the renderer's context, pbrt-v4's defaults.
fn new_builder(
    ov: &Overrides,
    desc: &Description,
    (dir, plugin, fire): (std::path::PathBuf, Option<firemedium_loader::Plugin>, bool),
    (bins, plugin_bins): (Bins, firemedium_loader::Bins),
) -> Builder {
    Builder {
        ctx: Context {
            dir,
            threads: ov.threads,
            frame: ov.frame,
            host_tracking: ov.host_tracking,
            camera_march: ov.camera_march,
            max_memory: ov.max_memory.unwrap_or_else(crate::budget::default_bytes),
        },
        reports: Reports::default(),
        bins,
        plugin,
        order: 0,
        named_materials: HashMap::new(),
        textures: HashMap::new(),
        named_media: HashMap::new(),
        materials: Vec::new(),
        prims: Vec::new(),
        lights: Vec::new(),
        media: Vec::new(),
        media_locs: Vec::new(),
        camera_shutter: desc.camera.as_ref().map_or([0.0, 1.0], |c| {
            let cp = ParamDict::new(&c.entity.params);
            [num(&cp, "shutteropen", 0.0), num(&cp, "shutterclose", 1.0)]
        }),
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
        objects: Vec::new(),
        object_prims: 0,
        current_object: None,
        plugin_bins,
        has_fire: fire,
        film_xyz: None,
    }
}

/// The scene's camera (with the command line's resolution), its pixel bounds, checked against the memory budget
/// with the film they need, and its shutter's interval (s: pbrt-v4's imaging ratio takes it).
fn camera(
    b: &mut Builder,
    (desc, camera_desc, cp): (&Description, &description::Camera, &ParamDict),
    ov: &Overrides,
    path: &Path,
) -> Result<(Camera, [usize; 4], f64), Error> {
    let (camera_type, camera_from_world) = (&camera_desc.entity.ty, camera_desc.camera_from_world);
    let medium = b.named_media.get(&camera_desc.medium).copied();
    b.order = camera_desc.entity.order;
    if let Some(r) = desc.command_line.res {
        b.res = r;
    }
    let bounds = pixel_bounds(b, &desc.command_line, path)?;
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
    Ok((camera, bounds, exposure))
}

/// The film's response: its ISO, white balance and format, over the shutter's `exposure`; a named camera's sensor
/// curves in place of the CMFs.
fn film_response(
    b: &Builder,
    exposure: f64,
    bins: &Bins,
    path: &Path,
) -> Result<crate::render::film::Response, Error> {
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
    Ok(response)
}

/// The scene's spectral bins: with a plugin medium (a fire, or pbrt-v4's grids), the plugin's measured default,
/// which its march kernel holds in vector lanes; without one, the whole CIE table (380–780 nm, 10 nm bins), as
/// pbrt-v4 samples wavelengths over the visible range (400–700 nm would leave out 0.5 % of a 2000 K grid's
/// luminance; 380–400 nm holds 0.004 % of ∫ȳ). A medium's own `bins`, `lambdamin`, `lambdamax` set them for all.
fn scene_bins(
    path: &Path,
    desc: &Description,
    plugin: Option<&firemedium_loader::Plugin>,
) -> Result<(f64, f64, usize), Error> {
    let (mut lo, mut hi, mut n) = (380.0, 780.0, 40);
    if let Some(p) = plugin {
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
    // The media's own bins: every plugin medium shares the scene's (a second that disagrees is an error).
    let mut given: Vec<(&str, f64)> = Vec::new();
    for m in &desc.media {
        let loc = &m.entity.loc;
        let p = &ParamDict::new(&m.entity.params);
        for (k, v) in [("lambdamin", &mut lo), ("lambdamax", &mut hi)] {
            if let Some(x) = nums(p, k).and_then(|v| v.first()) {
                if given.iter().any(|&(g, y)| g == k && y != *x) {
                    return Err(err(
                        loc,
                        format!(
                            "media disagree on \"{k}\": all media share the scene's spectral bins"
                        ),
                    ));
                }
                *v = *x;
                given.push((k, *x));
            }
        }
        if let Some(x) = nums(p, "bins").and_then(|v| v.first()) {
            n = *x as usize;
        }
    }
    if n > crate::render::spectrum::MAX_CHANNELS {
        return Err(Error::file(
            path.display(),
            format!(
                "{n} spectral bins; the renderer supports at most {}",
                crate::render::spectrum::MAX_CHANNELS
            ),
        ));
    }
    Ok((lo, hi, n))
}

/// Builds the scene described: the plugin and the spectral bins first (from the media), then the film, sampler,
/// filter and integrator, the media, textures, area lights and materials, the objects, the world's shapes,
/// instances and lights in file order, the camera, and the fire lights.
pub(super) fn build(path: &Path, desc: &Description, ov: &Overrides) -> Result<Scene, Error> {
    // Pre-scan: the plugin and the render bins (from the media, or the defaults of the plugin that renders them)
    // and the photometric scale.
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let (plugin, fire) = scene_plugin(&dir, desc, ov)?;
    let (lo, hi, n) = scene_bins(path, desc, plugin.as_ref())?;
    let grid = SpectralGrid::new(lo, hi, n).map_err(|e| Error::file(path.display(), e))?;
    // The film records Y in cd/m² (nits) either way. With a fire, radiance is absolute (683 lm/W); without one it
    // is in pbrt-v4's units, whose film records ∫ L ȳ dλ as it is (K = 1): a pbrt scene's numbers are pbrt-v4's.
    // Lights are normalised to their luminance in both (`Builder::emitted`), and a pbrt grid in a fire's scene is
    // brought to the film's units by its weights' ratio (`Builder::check_colour`).
    let k = if fire { 683.0 } else { 1.0 };
    let bins = Bins::new(grid, k);
    // The plugin's media take the scene's bins beside their parameters (the context), not among them.
    let plugin_bins = firemedium_loader::Bins {
        count: n as u32,
        nm: [lo, hi],
    };
    let mut b = new_builder(ov, desc, (dir, plugin, fire), (bins.clone(), plugin_bins));
    // pbrt's default material: diffuse 0.5.
    b.materials
        .push(Material::Diffuse(Tex::Const(bins.mask() * 0.5)));
    // The scene-wide statements (the last of each kind; pbrt-v4's defaults where none).
    type Create = fn(&mut Builder, &description::Entity) -> Result<(), Error>;
    let settings: [(&Option<description::Entity>, Create); 4] = [
        (&desc.film, Builder::film),
        (&desc.sampler, Builder::sampler),
        (&desc.filter, Builder::filter),
        (&desc.integrator, Builder::integrator),
    ];
    for (e, create) in settings {
        if let Some(e) = e {
            b.order = e.order;
            create(&mut b, e)?;
        }
    }
    for m in &desc.media {
        b.order = m.entity.order;
        b.medium(m)?;
    }
    for t in &desc.textures {
        b.order = t.entity.order;
        b.texture(t)?;
    }
    let mut areas = Vec::with_capacity(desc.area_lights.len());
    for e in &desc.area_lights {
        b.order = e.order;
        areas.push(b.area_light(e)?);
    }
    // Materials in file order: a mix names those made before it.
    let mut materials = Vec::with_capacity(desc.materials.len());
    for m in &desc.materials {
        let (ty, loc, p) = (
            &m.entity.ty,
            &m.entity.loc,
            &ParamDict::new(&m.entity.params),
        );
        b.order = m.entity.order;
        let built = b.material(ty, p, loc)?;
        match &m.name {
            None => b.finish(Kind::Material, ty, &format!("{ty} material"), p)?,
            Some(name) => {
                b.finish(Kind::Material, ty, &format!("{ty} material \"{name}\""), p)?;
                // Interface named materials are stored as usize::MAX.
                b.named_materials
                    .insert(name.clone(), built.unwrap_or(usize::MAX));
            }
        }
        materials.push(built);
    }
    let place = |b: &Builder, s: &description::Shape| Placement {
        material: match s.material {
            MaterialRef::Default => Some(0),
            MaterialRef::Entity(i) => materials[i],
        },
        area: s.area.map(|a| areas[a]),
        media: (!(s.inside.is_empty() && s.outside.is_empty())).then(|| {
            let look = |n: &str| b.named_media.get(n).copied();
            (look(&s.inside), look(&s.outside))
        }),
        reverse: s.reverse,
    };
    // Objects (one BVH each, built once and shared by every instance of it), then the world in file order.
    for object in &desc.objects {
        b.current_object = Some((object.name.clone(), Vec::new()));
        for s in &object.shapes {
            b.order = s.entity.order;
            let at = place(&b, s);
            b.shape(s, &at)?;
        }
        let prims = b.current_object.take().map(|(_, p)| p).unwrap_or_default();
        b.object_prims += prims.len();
        b.objects.push(std::sync::Arc::new(Bvh::new(prims)));
    }
    for w in &desc.world {
        match w {
            World::Shape(s) => {
                b.order = s.entity.order;
                let at = place(&b, s);
                b.shape(s, &at)?;
            }
            World::Instance {
                object,
                name,
                ctm,
                loc,
                order,
            } => {
                b.order = *order;
                let object = b.objects[*object].clone();
                b.instance(&object, name, ctm, loc)?;
            }
            World::Light { entity, ctm } => {
                b.order = entity.order;
                b.light_source(entity, *ctm)?;
            }
        }
    }
    // The camera, now that the film resolution is known (pbrt allows Film after Camera).
    let camera_desc = desc
        .camera
        .as_ref()
        .ok_or_else(|| Error::file(path.display(), "no Camera directive"))?;
    // (One dictionary: the camera's build marks what it read, and `finish` warns of the rest.)
    let cp = &ParamDict::new(&camera_desc.entity.params);
    let (camera, bounds, exposure) = camera(&mut b, (desc, camera_desc, cp), ov, path)?;
    let response = film_response(&b, exposure, &bins, path)?;
    let camera_type = &camera_desc.entity.ty;
    b.finish(
        Kind::Camera,
        camera_type,
        &format!("{camera_type} camera"),
        cp,
    )?;
    let fires = fire_lights(&mut b, ov, path)?;
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
    let mut spp = desc.command_line.spp.unwrap_or(b.spp);
    if matches!(b.sampler, crate::render::pixel::Sampler::ZSobol { .. }) && !spp.is_power_of_two() {
        b.reports.warnings.push((usize::MAX, format!(
            "sampler \"zsobol\": {spp} samples per pixel rounded up to {} (a power of two, as pbrt-v4)",
            spp.next_power_of_two()
        )));
        spp = spp.next_power_of_two();
    }
    // What reading and building found, in the scene's order (what is found of the whole scene last).
    let mut warnings = desc.warnings.clone();
    warnings.append(&mut b.reports.warnings);
    warnings.sort_by_key(|(order, _)| *order);
    let mut warnings: Vec<String> = warnings.into_iter().map(|(_, w)| w).collect();
    let bvh = Bvh::new(b.prims);
    let media_boxes: Vec<_> = (0..b.media.len()).map(|m| bvh.media_box(m)).collect();
    let guide = fire_guide(&b.media, ov, &fires, &media_boxes);
    for (m, (medium, loc)) in b.media.iter().zip(&b.media_locs).enumerate() {
        for w in boundary_warnings(medium, &bvh, m, media_boxes[m].as_ref(), &camera) {
            warnings.push(format!("{loc}: warning: {w}"));
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
        seed: desc.seed,
        pixel_jitter: desc.pixel_jitter,
        shutter: b.shutter,
        aovs: ov.aovs.clone(),
        maxdepth: b.maxdepth,
        fire_light_inside: ov.fire_light_inside,
        guide,
        film_name: b.film_name,
        eps: (extent * 1e-5).max(1e-6),
        warnings,
        media_reports: b.reports.media,
    })
}
