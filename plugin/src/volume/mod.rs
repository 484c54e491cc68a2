//! The fire volume component (the thesis's "fire volume shader"): voxels → spectral σ_a, σ_s and emission,
//! integrated along rays.
//!
//! ## Coefficients
//! With d the density channel, T the temperature (K, after the dataset's mapping) and N_s species number
//! densities (m⁻³), per channel c:
//! - **physical** mode: σ_a,c = f_v κ̂_c + Σ_s N_s σ̂_s,c(T), σ_s,c = sigma_s,c d, and the emission coefficient
//!   j_c = intensity · (f_v (κ̂B)_c(T) + Σ_s N_s ĵ_s,c(T)), with f_v = sootscale · d, κ̂ the soot absorption
//!   per unit volume fraction (eq. 5), B Planck's law (eq. 6) and σ̂, ĵ the line cross-sections (eq. 7–12).
//!   Kirchhoff holds per line and for soot: j = σ_a B.
//! - **pbrt** mode (pbrt-v4 `uniformgrid`/`nanovdb`): σ_a,c = scale · sigma_a,c · d, σ_s,c = scale ·
//!   sigma_s,c · d (both σ's default to 1, as pbrt-v4's), j_c = σ_a,c · Lescale · B̃_c(T) for T > 100 K with B̃
//!   the peak-normalised blackbody, not photometrically scaled (an optically thick 2000 K grid records Y = 5.2
//!   in pbrt-v4), or a constant `Le` spectrum scaled to luminance 1 (rgb: to its rgb's), Lescale possibly a
//!   grid. For NanoVDB files rays are clipped, as pbrt-v4 does, to
//!   NanoVDB's world box [T(i_min), T(i_max + 1)], and lookups fade toward the background over the half voxel
//!   beyond the last samples (NanoVDB's trilinear sampler).
//!
//! ## Channels
//! - `spectral`: `bins` equal bins over [lambdamin, lambdamax]; radiance in W·m⁻²·sr⁻¹·nm⁻¹ (bin means).
//! - `rgb`: three bands with the CIE 1931 x̄, ȳ, z̄ as weights over 380–780 nm: σ_c is the band's
//!   Planck-mean of σ(λ) at the local temperature (∫σ B w_c / ∫B w_c, so the optically thin limit j_c and the
//!   thick limit j_c/σ_c = the band's blackbody are both exact), j_c = K ∫ j(λ) w_c(λ) dλ with K = 683 lm/W, so radiance comes out as XYZ with Y in cd/m² (pbrt
//!   mode: K = 1: pbrt-v4's film records ∫ L ȳ dλ, not divided by ∫ȳ dλ). Non-negative weights keep every coefficient non-negative.
//!
//! Each channel's XYZ weights ([`FireVolume::channel_xyz`]) turn radiance into absolute XYZ.
//!
//! ## Tables
//! Everything that depends on T alone is tabulated once, in parallel, on a uniform grid of ≤ 0.5 K (at most
//! 65 536 rows up to the dataset's hottest voxel) and interpolated linearly; species tables exist only for
//! species present. The build report lists bytes and seconds per table.

mod basis;
mod coefficients;
mod diffusion;
mod integrate;
mod kernel;
mod lanes;
mod lattice;
mod lines;
mod looks;
mod march;
mod mip;
mod motion;
pub mod params;
mod parts;
mod point;
mod settings;
mod subset;
mod tables;

pub(crate) use integrate::MAX_STEPS;
pub use integrate::{Event, Integrator, Ray};
use integrate::{Medium, Scratch};
pub use march::evaluations_on_this_thread;
pub(crate) use march::Stepper;
use march::EVALUATIONS;
pub use point::PointCoefficients;
use settings::{Emission, Settings};
pub(crate) use subset::LineChannels;
use tables::SpeciesChannel;

use crate::dataset::{Dataset, Format};
use crate::majorant::MajorantGrid;
use crate::params::{Param, ParamReader};
use crate::soot::SootOptics;
use crate::species::Element;
use crate::spectrum::SpectralGrid;
use crate::Error;
use basis::Basis;
use glam::DVec3;
use std::time::Instant;

/// The largest optical depth a voxel may have: a bound on the work of tracking, far above any fire (the paper's
/// thickest soot is ~10 per voxel).
pub const MAX_OPTICAL_DEPTH_PER_VOXEL: f64 = 1e12;

/// The colour space of a volume's channels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ColorMode {
    /// Spectral bins.
    Spectral(SpectralGrid),
    /// CIE XYZ bands.
    Rgb,
}

/// How the coefficients are defined.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Pegoraro & Parker's fire.
    Physical,
    /// pbrt-v4's grid media.
    Pbrt,
}

/// One table the build made.
#[derive(Debug, Clone, PartialEq)]
pub struct TableReport {
    /// What it holds.
    pub name: String,
    /// Bytes.
    pub bytes: usize,
    /// Seconds to build.
    pub seconds: f64,
}

/// What the fire emits, kept for the light's full-spectrum power (physical mode).
#[derive(Debug, Clone)]
pub(crate) struct Source {
    pub soot: SootOptics,
    pub alpha: f64,
    /// sootscale × intensity.
    pub soot_scale: f64,
    pub intensity: f64,
    /// (element, channel index, m⁻³ per unit).
    pub species: Vec<(Element, usize, f64)>,
}

/// What a volume holds beyond absorption ([`FireVolume::features`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Features {
    /// It emits (a temperature or emission grid that reaches emitting values).
    pub emits: bool,
    /// It scatters (σ_s > 0).
    pub scatters: bool,
    /// Its lookups move over the shutter (velocity motion blur).
    pub motion: bool,
    /// Rays bend in it (refraction).
    pub refraction: bool,
    /// It carries embers (opaque moving spheres, not a medium).
    pub embers: bool,
    /// Atomic lines integrated across their profiles (optically thick lines).
    pub thick_lines: bool,
    /// Its smoke's multiple scattering is read as emission (diffusion).
    pub diffusion: bool,
    /// It emits where it may not absorb (an emission grid): Le is undefined there, j is not.
    pub emits_without_absorption: bool,
}

/// A volume's majorant grid ([`FireVolume::majorant_cells`]).
#[derive(Debug, Clone, Copy)]
pub struct MajorantCells<'a> {
    /// The box the cells tile, medium space.
    pub bounds: [DVec3; 2],
    /// A cell's edge per axis (the last cell per axis may be cut by the box).
    pub cell: DVec3,
    /// Cells per axis.
    pub counts: [usize; 3],
    /// Per cell, x fastest, a bound on σ_t (medium units⁻¹).
    pub sigma_t: &'a [f64],
}

/// A fire volume, from parts: the grids it reads, its coefficient model, its majorants, the optional layers the
/// scene asked for, its estimator, and what its build reports.
#[derive(Debug, Clone)]
pub struct FireVolume {
    grids: parts::Grids,
    model: parts::Model,
    bounds: parts::Bounds,
    layers: parts::Layers,
    estimator: parts::Estimator,
    report: parts::Report,
    /// Rays whose tracking stopped at the collision cap (see `integrate::MAX_COLLISIONS`).
    capped: CapCounter,
    #[cfg(test)]
    fault: String,
}

/// A count that clones as its current value (a volume is cloned whole in tests and tools).
#[derive(Debug, Default)]
struct CapCounter(std::sync::atomic::AtomicU64);

impl Clone for CapCounter {
    fn clone(&self) -> Self {
        CapCounter(std::sync::atomic::AtomicU64::new(
            self.0.load(std::sync::atomic::Ordering::Relaxed),
        ))
    }
}

impl FireVolume {
    /// Builds a fire volume from a parameter list (the `dataset` and `volume` tables, docs/params.md): the
    /// parameters are read and checked first ([`Settings`]), then the dataset is loaded, then the coefficient
    /// tables, the march lattice, the majorant bricks and (if asked for) the refraction field are built.
    pub fn new(list: &[Param]) -> Result<FireVolume, Error> {
        Self::new_unlocated(list).map_err(|e| e.located(list))
    }

    fn new_unlocated(list: &[Param]) -> Result<FireVolume, Error> {
        let start = Instant::now();
        let list = &*looks::expand(list);
        let comps = settings::components();
        let r = ParamReader::new("volume", list, &comps);
        r.check_names()?;
        march::check_simd()?;
        // (The look was expanded into the list above; reading it checks its name.)
        r.string("look")?;
        let set = Settings::read(&r, list)?;
        let threads = r.int("threads")? as usize;
        let budget = r.float("maxbytes")? as u64;
        crate::par::with_budget(threads, || {
            let loaded = crate::dataset::params::load(&r, set.mode == Mode::Pbrt)?;
            r.finish()?;
            let mut v = Self::build(set, loaded, budget, start)?;
            v.report.threads = threads;
            Ok(v)
        })
    }

    /// `budget`: the volume's memory budget (`maxbytes`); what it derives beyond its grids must fit in what the
    /// grids leave of it.
    fn build(
        set: Settings,
        loaded: crate::dataset::params::Loaded,
        budget: u64,
        start: Instant,
    ) -> Result<FireVolume, Error> {
        let crate::dataset::params::Loaded {
            ds,
            lescale,
            emission_grid,
            motion,
            scatter_color,
            reaction,
            embers,
        } = loaded;
        let spare = budget.saturating_sub(ds.bytes() as u64);
        let channel = |name: &str| ds.channels().iter().position(|c| c.name == name);
        let density = channel("density").unwrap_or(0);
        let temperature = channel("temperature");
        let basis = set.basis;
        let c = basis.channels();

        // ---- coefficients
        let t_max = temperature
            .map(|i| ds.channels()[i].stats.max as f64)
            .unwrap_or(0.0)
            .max(0.0);
        let mut tables = Vec::new();
        let mut thick = None;
        let mut co = match &set.emission {
            Emission::Physical {
                optics,
                alpha,
                sootscale,
                intensity,
                smokescale,
                tint,
                ramp,
                species,
            } => {
                // Lines that can be thick leave the tables for the line model (`lines`).
                let mut thin = species.clone();
                if set.voigt && !species.is_empty() {
                    let t0 = Instant::now();
                    let sigma_s = set.sigma_s.as_ref();
                    let continuum = |l: f64| {
                        let k = optics.kappa(l, 1.0, *alpha) * sootscale;
                        [
                            smokescale * k,
                            smokescale * sigma_s.map_or(0.0, |f| f(l)),
                            intensity * k * tint.as_ref().map_or(1.0, |f| f(l)),
                        ]
                    };
                    let t_range = temperature
                        .map(|i| {
                            let st = &ds.channels()[i].stats;
                            [st.min as f64, st.max as f64]
                        })
                        .unwrap_or([0.0, 0.0]);
                    let inp = lines::Input {
                        species,
                        ds: &ds,
                        basis: &basis,
                        broadening: set.linebroadening,
                        intensity: *intensity,
                        continuum: &continuum,
                        t_range,
                        budget: spare,
                    };
                    let marks = lines::select(&inp);
                    thick = lines::ThickLines::new(&inp, &marks, t_max)?;
                    for ((_, e, _), m) in thin.iter_mut().zip(&marks) {
                        let keep: Vec<bool> = m.iter().map(|x| !x).collect();
                        let lines = e.lines().to_vec();
                        *e = e.with_lines(&|l| {
                            lines
                                .iter()
                                .zip(&keep)
                                .any(|(x, &k)| k && x.lambda_nm == l.lambda_nm)
                        });
                    }
                    if let Some(tl) = &thick {
                        tables.push(TableReport {
                            name: format!("thick lines ({} wavelengths across them)", tl.nodes()),
                            bytes: tl.bytes(),
                            seconds: t0.elapsed().as_secs_f64(),
                        });
                    }
                }
                let mut co = coefficients::physical(
                    &basis,
                    optics,
                    (*alpha, *sootscale, *intensity),
                    (*smokescale, tint.as_ref(), ramp.as_ref()),
                    &thin,
                    set.sigma_s.as_ref(),
                    &ds,
                    t_max,
                    &mut tables,
                );
                // (The light's power counts every line.)
                if let Some(src) = &mut co.source {
                    for ((e, _, _), (_, full, _)) in src.species.iter_mut().zip(species) {
                        *e = full.clone();
                    }
                }
                co
            }
            Emission::Pbrt {
                scale,
                sigma_a,
                le_scale,
                le,
            } => coefficients::pbrt(
                &basis,
                *scale,
                sigma_a,
                *le_scale,
                le.as_ref(),
                set.sigma_s.as_ref(),
                temperature.is_some(),
                t_max,
                &mut tables,
            )?,
        };
        // (The fire light's full-spectrum power assumes emission follows the soot: with an emission grid it reports
        // its power over the bins.)
        if emission_grid {
            co.source = None;
        }
        // The blue core: the reaction zone's chemiluminescence, a channel that emits (yield · heat release / 4π
        // times the CH*/C₂* band spectrum, per channel) and absorbs nothing — the species' machinery, with
        // tables that do not depend on temperature.
        if let Some(ch) = reaction {
            let shape = basis.emit(&firemedium_core::chemiluminescence::spectrum);
            let zeros = vec![0.0; c];
            co.species.push(SpeciesChannel {
                ch,
                scale: set.chemiluminescence / (4.0 * std::f64::consts::PI),
                sigma: tables::TTable::build(0.0, c, &|_| zeros.clone()),
                j: tables::TTable::build(0.0, c, &|_| shape.clone()),
            });
            // (The light's full-spectrum power follows the soot and atoms: with the blue core, over the bins.)
            co.source = None;
        }
        if co.a.iter().chain(&co.s).any(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::invalid(
                "volume",
                "sigma_a/sigma_s",
                format!("{:?} {:?}", co.a, co.s),
                "finite, non-negative coefficients",
            ));
        }

        // ---- the march lattice, for a volume that marches in f32 lanes over a trilinear dataset (kept below
        // only if the lanes are built): made before the majorants, because it gathers its grids' brick ranges
        // as it copies them.
        let brick = majorant_brick(set.brick, ds.topology());
        // (With diffusion the emission reads the coarse fluence grid: the f64 march.)
        let lanes_wanted =
            set.f32_lanes && set.integrator == Integrator::March && set.diffusion.is_none();
        let mut lattice = None;
        let mut known = vec![None; ds.channels().len()];
        if lanes_wanted && ds.interpolation() == crate::grid::Interpolation::Trilinear {
            let t4 = Instant::now();
            let ch = ds.channels();
            let extra: Vec<usize> = lescale
                .iter()
                .copied()
                .chain(co.species.iter().map(|sp| sp.ch))
                .collect();
            let grids: Vec<&crate::grid::Grid> = extra.iter().map(|&k| &ch[k].grid).collect();
            // Dense over the box while it costs at most four times what its grids store (512 values per block:
            // constant tiles share blocks, as the brick layout's copies of their interiors do), else a copy per
            // brick holding data (a fire far from its copy in a big box, a file of constant tiles).
            let per_grid = (ds.topology().blocks_stored() as u64 + 1) * 4 * 512;
            let copied = per_grid * (2 + grids.len() as u64 - temperature.is_none() as u64);
            let dense_fits = lattice::Lattice::padded(ds.dims()).is_some_and(|p| {
                let voxels = p.iter().map(|&n| n as u64).product::<u64>();
                voxels.saturating_mul(4 * (2 + grids.len() as u64)) <= copied.saturating_mul(4)
            });
            let dense = match set.lattice.as_str() {
                "dense" => Some(true),
                "bricks" => Some(false),
                "off" => None,
                _ => Some(dense_fits),
            };
            let (d, t) = (&ch[density].grid, temperature.map(|k| &ch[k].grid));
            match dense {
                Some(true) => {
                    if let Some((lat, ranges)) = lattice::Lattice::build(d, t, &grids, brick, spare)
                    {
                        let order = std::iter::once(density).chain(temperature).chain(extra);
                        for (k, r) in order.zip(ranges) {
                            if known[k].is_none() {
                                known[k] = Some(r);
                            }
                        }
                        lattice = Some((lat, t4.elapsed().as_secs_f64()));
                    }
                }
                Some(false) => {
                    lattice = lattice::Lattice::build_bricks(d, t, &grids, spare)
                        .map(|lat| (lat, t4.elapsed().as_secs_f64()));
                }
                None => {}
            }
        }

        // ---- majorants
        let t1 = Instant::now();
        let majorant = MajorantGrid::with_ranges(&ds, brick, known);
        let mut brick_sigma =
            coefficients::brick_majorants(&majorant, &co, density, temperature, c);
        // An emission grid emits where there may be no smoke: tracking's estimators add j/σ̄ at tentative
        // collisions, so σ̄ must not be 0 where j is not — a floor of one collision per voxel there.
        if let Some(e) = lescale.filter(|_| emission_grid) {
            let floor = 1.0 / ds.voxel_size().min_element();
            for (b, s) in brick_sigma.iter_mut().enumerate() {
                if majorant.max(b, e) > 0.0 {
                    *s = s.max(floor);
                }
            }
        }
        let nb = brick_sigma.len();
        // An optical depth above 1e12 per voxel is no fire: a voxel value far outside the data's range, or a
        // scale far too large. Tracking through it would take ~1e12 collisions per voxel.
        let voxel = ds.voxel_size().max_element();
        if let Some((b, &sigma)) = brick_sigma
            .iter()
            .enumerate()
            .max_by(|x, y| x.1.total_cmp(y.1))
            .filter(|(_, &s)| !(s * voxel <= MAX_OPTICAL_DEPTH_PER_VOXEL))
        {
            let [cx, cy, _] = majorant.counts();
            let (i, j, k) = (b % cx, (b / cx) % cy, b / (cx * cy));
            return Err(Error::invalid(
                "volume",
                "extinction",
                format!("{sigma:.3e} m⁻¹ in brick ({i}, {j}, {k}) of {brick}³ voxels, an optical depth of {:.3e} per voxel", sigma * voxel),
                format!("at most {MAX_OPTICAL_DEPTH_PER_VOXEL:e} per voxel (a voxel value far outside the data's range, or sootscale, scale, sigma_a or sigma_s far too large?)"),
            ));
        }
        let emitter = lescale.filter(|_| emission_grid);
        let brick_empty: Vec<bool> = (0..nb)
            .map(|b| {
                majorant.max(b, density) <= 0.0
                    && co.species.iter().all(|sp| majorant.max(b, sp.ch) <= 0.0)
                    && emitter.is_none_or(|e| majorant.max(b, e) <= 0.0)
            })
            .collect();
        tables.push(TableReport {
            name: format!("majorant bricks ({brick}³ voxels)"),
            bytes: majorant.bytes() + brick_sigma.len() * 8,
            seconds: t1.elapsed().as_secs_f64(),
        });
        let blur = motion.map(|m| {
            let t5 = Instant::now();
            let b = motion::Blur::new(m, &ds, &majorant, &brick_sigma, &brick_empty);
            tables.push(TableReport {
                name: format!(
                    "motion blur (majorants widened by {:.4} medium units)",
                    b.reach()
                ),
                bytes: b.bytes(),
                seconds: t5.elapsed().as_secs_f64(),
            });
            b
        });

        // ---- embers
        let embers = match embers {
            None => None,
            Some(ef) => {
                let Emission::Physical { intensity, .. } = &set.emission else {
                    return Err(Error::invalid(
                        "dataset",
                        "embers",
                        format!("\"{}\" for a pbrt-v4 medium", ef.file),
                        "a fire (\"string type\" \"fire\"): embers glow by their temperature",
                    ));
                };
                let t6 = Instant::now();
                let nodes = basis.nodes();
                let g = vec![set.ember.emissivity * intensity; nodes.lambda.len()];
                let left = spare.saturating_sub(tables.iter().map(|t| t.bytes as u64).sum());
                let em = crate::embers::Embers::new(
                    &ef.file,
                    &ef.particles,
                    set.ember,
                    ef.shutter,
                    ef.fps,
                    &|t| basis.emit_planck(&nodes, &g, t),
                    left,
                )?;
                tables.push(TableReport {
                    name: format!("embers ({} particles and their grid)", em.len()),
                    bytes: em.bytes(),
                    seconds: t6.elapsed().as_secs_f64(),
                });
                Some(em)
            }
        };

        // ---- refraction
        let step = set.stepsize * ds.voxel_size().min_element();
        let refraction = match &set.refraction {
            None => None,
            Some(rs) => {
                let t_ch = temperature.ok_or_else(|| {
                    Error::invalid(
                        "volume",
                        "refraction",
                        "true without a temperature grid",
                        "a temperature grid (the index of air follows from it)",
                    )
                })?;
                let t2 = Instant::now();
                // What the budget leaves after the grids, the tables and the lattice.
                let left = spare
                    .saturating_sub(tables.iter().map(|t| t.bytes as u64).sum())
                    .saturating_sub(lattice.as_ref().map_or(0, |(l, _)| l.bytes() as u64));
                let rf = crate::refraction::march::Refraction::build(
                    &ds.channels()[t_ch].grid,
                    ds.bounds(),
                    &rs.air,
                    (rs.wavelength, rs.scale),
                    rs.rk4,
                    step,
                    ds.voxel_size().min_element(),
                    left,
                )
                .map_err(|bytes| Error::TooLarge {
                    file: "refraction".into(),
                    what:
                        "the index field (16 bytes per voxel around the voxels hotter than ambient)"
                            .into(),
                    bytes,
                    cap: left,
                })?;
                tables.push(TableReport {
                    name: "refraction index field".into(),
                    bytes: rf.field.bytes(),
                    seconds: t2.elapsed().as_secs_f64(),
                });
                Some(rf)
            }
        };

        // The largest value a lookup can return, from the bricks' ranges (for the lane march's range check).
        let max = |ch: usize| (0..nb).map(|b| majorant.max(b, ch)).fold(0f32, f32::max) as f64;
        let (dmax, lesmax) = (max(density), lescale.map_or(1.0, max));
        // The largest emitting density: d · Lescale, or the emission grid itself.
        let dlmax = if emission_grid { lesmax } else { dmax * lesmax };
        let nmax: Vec<f64> = co.species.iter().map(|sp| max(sp.ch)).collect();
        let [b0, b1] = ds.bounds();
        let (clip_box, margin) = if set.mode == Mode::Pbrt && ds.format() == Format::NanoVdb {
            let half = ds.voxel_size() * 0.5;
            ([b0 + half, b1 + half], 0.5)
        } else {
            ([b0, b1], 0.0)
        };
        let scatter_color = scatter_color.map(|k| (k, scatter_weights(&basis)));
        let physical_colour = match &set.emission {
            Emission::Physical { tint, ramp, .. } => {
                tint.is_none() && ramp.as_ref().is_none_or(|r| r.physical >= 1.0)
            }
            _ => true,
        };
        // What the point query's closed forms cannot express (the first such layer names the refusal).
        let refused = [
            (!co.species.is_empty(), "atomic lines or the blue core"),
            (thick.is_some(), "optically thick atomic lines"),
            (scatter_color.is_some(), "a scatter colour grid"),
            (set.diffusion.is_some(), "diffusion"),
            (refraction.is_some(), "refraction"),
            (embers.is_some(), "embers"),
            (!physical_colour, "art direction (a tint or a colour ramp)"),
        ]
        .iter()
        .find(|(on, _)| *on)
        .map(|(_, why)| why.to_string());
        let point_model = point::PointModel::new(&set.emission, set.sigma_s.as_ref(), refused);
        let mut vol = FireVolume {
            grids: parts::Grids {
                ds,
                density,
                temperature,
                lescale,
                emission_grid,
                species: co.species,
            },
            model: parts::Model {
                basis,
                mode: set.mode,
                a: co.a,
                a_t: co.a_t,
                s: co.s,
                j: co.j,
                t_emit: co.t_emit,
                physical_colour,
                scatter_color,
                g: set.g,
                point_model,
            },
            bounds: parts::Bounds {
                majorant,
                brick_sigma,
                brick_empty,
                clip_box,
                margin,
            },
            layers: parts::Layers {
                blur,
                embers,
                refraction,
                diffusion: None,
                lines: thick,
            },
            estimator: parts::Estimator {
                integrator: set.integrator,
                step,
                step_tau: set.step_tau,
                cutoff: set.cutoff,
                lanes: None,
                lattice: None,
            },
            report: parts::Report {
                tables,
                build_seconds: 0.0,
                source: co.source,
                spare: 0,
                threads: 0,
            },
            capped: CapCounter::default(),
            #[cfg(test)]
            fault: set.fault,
        };
        if lanes_wanted {
            let t3 = Instant::now();
            vol.estimator.lanes = lanes::LaneTables::build(&vol, dmax, dlmax, &nmax, step);
            if let Some(lt) = &vol.estimator.lanes {
                vol.report.tables.push(TableReport {
                    name: "march lanes (σ per unit density; the tables are shared)".into(),
                    bytes: lt.bytes(),
                    seconds: t3.elapsed().as_secs_f64(),
                });
                if let Some((lat, seconds)) = lattice {
                    vol.report.tables.push(TableReport {
                        name: match lat.bricks() {
                            None => {
                                "march lattice (grids interleaved and padded; their brick ranges)"
                                    .into()
                            }
                            Some(t) => format!(
                                "march lattice (grids interleaved, a padded copy per brick: {} copies)",
                                t.active_bricks()
                            ),
                        },
                        bytes: lat.bytes(),
                        seconds,
                    });
                    vol.estimator.lattice = Some(lat);
                }
            }
        }
        if let Some(res) = set
            .diffusion
            .filter(|_| vol.model.s.iter().any(|&v| v > 0.0))
        {
            let t5 = Instant::now();
            // The solve's peak: three cell arrays per channel, five per solving thread.
            let cells = {
                let size = vol.bounds.clip_box[1] - vol.bounds.clip_box[0];
                let h = size.max_element() / res.clamp(1, diffusion::MAX_RESOLUTION) as f64;
                [0, 1, 2]
                    .map(|k| ((size[k] / h).ceil() as u64).max(1))
                    .iter()
                    .product::<u64>()
            };
            let need = cells * (vol.channels() as u64 * 28 + 40 * crate::par::threads(16) as u64);
            let left = spare.saturating_sub(vol.report.tables.iter().map(|t| t.bytes as u64).sum());
            if need > left {
                return Err(Error::invalid(
                    "volume",
                    "diffusionresolution",
                    format!("{res} ({cells} cells, {need} bytes to solve)"),
                    format!("a grid within the memory budget's {left} bytes left"),
                ));
            }
            let df = diffusion::Diffusion::build(&vol, res, vol.model.g)?;
            vol.report.tables.push(TableReport {
                name: format!("diffusion ({} iterations)", df.iterations),
                bytes: df.bytes(),
                seconds: t5.elapsed().as_secs_f64(),
            });
            vol.layers.diffusion = Some(df);
        }
        vol.report.spare =
            spare.saturating_sub(vol.report.tables.iter().map(|t| t.bytes as u64).sum());
        vol.report.build_seconds = start.elapsed().as_secs_f64();
        Ok(vol)
    }

    /// The dataset.
    pub fn dataset(&self) -> &Dataset {
        &self.grids.ds
    }
    /// Medium-space bounds rays are clipped to (the dataset's, or pbrt-v4 nanovdb's world box in pbrt mode).
    pub fn bounds(&self) -> [DVec3; 2] {
        self.bounds.clip_box
    }
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.model.basis.channels()
    }
    /// The colour mode.
    pub fn color_mode(&self) -> ColorMode {
        self.model.basis.mode
    }
    /// The coefficient mode.
    pub fn mode(&self) -> Mode {
        self.model.mode
    }
    /// XYZ (Y in cd/m², or pbrt's relative units in pbrt mode) per unit radiance in each channel.
    pub fn channel_xyz(&self) -> Vec<DVec3> {
        self.model.basis.xyz()
    }
    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.estimator.integrator
    }
    /// Henyey–Greenstein g.
    pub fn g(&self) -> f64 {
        self.model.g
    }
    /// Whether the host should sample scattering events: scattering is configured and not resolved by
    /// diffusion (where the smoke's scattered light is emission).
    pub fn scatters(&self) -> bool {
        self.layers.diffusion.is_none() && self.model.s.iter().any(|&v| v > 0.0)
    }
    /// March step length, medium units.
    pub fn step_length(&self) -> f64 {
        self.estimator.step
    }
    /// The tables built (name, bytes, seconds).
    pub fn tables(&self) -> &[TableReport] {
        &self.report.tables
    }
    /// Bytes held by the dataset and tables.
    pub fn bytes(&self) -> usize {
        // (The species line tables are among `tables`, reported as "species X (lines)".)
        self.grids.ds.bytes() + self.report.tables.iter().map(|t| t.bytes).sum::<usize>()
    }
    /// Seconds spent building.
    pub fn build_seconds(&self) -> f64 {
        self.report.build_seconds
    }
    pub(crate) fn source(&self) -> Option<&Source> {
        self.report.source.as_ref()
    }
    pub(crate) fn density_channel(&self) -> usize {
        self.grids.density
    }
    pub(crate) fn temperature_channel(&self) -> Option<usize> {
        self.grids.temperature
    }
    /// The lowest and highest temperature of the grid (K, after the mapping), if it has one.
    pub fn temperature_range(&self) -> Option<[f64; 2]> {
        let s = self.grids.ds.channels()[self.grids.temperature?]
            .grid
            .stats();
        Some([s.min as f64, s.max as f64])
    }

    /// The build's thread budget (`threads`; 0: every core).
    pub(crate) fn threads(&self) -> usize {
        self.report.threads
    }
    /// Bytes of the volume's memory budget (`maxbytes`) left after its grids and tables: what a fire light built
    /// from it may take.
    pub fn spare_bytes(&self) -> u64 {
        self.report.spare
    }
    /// Whether anything in the volume can emit: some temperature (or constant `Le`) with a non-zero emission
    /// table, or species. A fire light of a volume that cannot emit is refused before it allocates per voxel.
    pub fn can_emit(&self) -> bool {
        !self.grids.species.is_empty()
            || self
                .model
                .j
                .v
                .iter()
                .any(|lane| lane.iter().any(|&x| x > 0.0))
    }
    /// How many rays' tracking stopped at the collision cap so far (each a ray cut short as if absorbed: a bias
    /// a host should report).
    pub fn capped_rays(&self) -> u64 {
        self.capped.0.load(std::sync::atomic::Ordering::Relaxed)
    }
    /// [`Medium::majorants`] over the volume's bricks with the bounds `sigma` (one per brick).
    pub(super) fn majorants_over(
        &self,
        sigma: &[f64],
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) {
        for seg in self.bounds.majorant.segments(o, d, t0, t1) {
            if !f(seg.t0, seg.t1, sigma[seg.brick]) {
                return;
            }
        }
    }
    /// [`Medium::empty_spans`] over the volume's bricks, `empty` saying which hold nothing (σ = j = 0).
    pub(super) fn empty_spans_over(
        &self,
        empty: &[bool],
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64),
    ) {
        for seg in self.bounds.majorant.segments(o, d, t0, t1) {
            if empty[seg.brick] {
                f(seg.t0, seg.t1);
            }
        }
    }
    /// The density that emits at a sample of soot density `d` and Lescale (or emission grid) value `les`.
    #[inline(always)]
    pub(super) fn emitting<T: std::ops::Mul<Output = T>>(&self, d: T, les: T) -> T {
        if self.grids.emission_grid {
            les
        } else {
            d * les
        }
    }
    /// Whether `p` can hold medium: inside the clip box and not in an empty brick.
    #[inline]
    pub(crate) fn holds_medium(&self, p: DVec3) -> bool {
        let [m0, m1] = self.bounds.clip_box;
        let empty = self
            .bounds
            .majorant
            .brick_at(p)
            .is_some_and(|b| self.bounds.brick_empty[b]);
        !empty && p.cmpge(m0).all() && p.cmple(m1).all()
    }

    #[cfg(test)]
    fn fault_check(&self) {
        if self.fault == "integrate" {
            panic!("fault injection: panic during integration");
        }
    }
    #[cfg(not(test))]
    fn fault_check(&self) {}

    /// Emitted radiance `l` and transmittance `t` (per channel) along `ray`; returns the exit parameter (where
    /// an ember stopped the ray, if one did).
    pub fn integrate(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> f64 {
        let (cut, hit) = self.ember_cut(ray, 0.0);
        let te = self.integrate_fire(&cut, l, t);
        self.ember_seen(hit, 0.0, Some(l), t).unwrap_or(te)
    }
    /// As [`integrate`](Self::integrate), and where the ray leaves: (point, unit direction, parameter). With
    /// refraction on, the ray curves through the index field and leaves bent ([`crate::refraction::march`]); the
    /// parameter is then the entry parameter plus arc length / |d|. (Embers are met along the straight chord.)
    pub fn integrate_exit(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> (DVec3, DVec3, f64) {
        let (cut, hit) = self.ember_cut(ray, 0.0);
        let exit = self.integrate_exit_fire(&cut, l, t);
        match self.ember_seen(hit, 0.0, Some(l), t) {
            Some(th) => (ray.o + ray.d * th, exit.1, th),
            None => exit,
        }
    }
    /// Transmittance only (along the straight ray, also with refraction on: shadow rays do not bend).
    pub fn transmittance(&self, ray: &Ray, t: &mut [f64]) {
        let (cut, hit) = self.ember_cut(ray, 0.0);
        self.transmittance_fire(&cut, t);
        self.ember_seen(hit, 0.0, None, t);
    }
    /// The first real scattering event (see [`Event`]); `l` gets the emission before it, `w` its weights. A ray
    /// that reaches an ember collects its radiance and ends there ([`Event::Absorbed`]).
    pub fn sample_scatter(&self, ray: &Ray, l: &mut [f64], w: &mut [f64]) -> Event {
        let (cut, hit) = self.ember_cut(ray, 0.0);
        let ev = self.sample_scatter_fire(&cut, l, w);
        self.ember_event(ev, hit, 0.0, l, w)
    }
    /// As [`integrate`](Self::integrate) at time `time` (frames from the grids' time): with motion blur the
    /// fire is looked up where the velocity carried it from (`motion`), and embers are where their velocity
    /// carried them. Without motion blur or embers, or at time 0, the same as `integrate`.
    pub fn integrate_at(&self, ray: &Ray, time: f64, l: &mut [f64], t: &mut [f64]) -> f64 {
        let (cut, hit) = self.ember_cut(ray, time);
        let te = self.integrate_at_fire(&cut, time, l, t);
        self.ember_seen(hit, time, Some(l), t).unwrap_or(te)
    }
    /// As [`integrate_at`](Self::integrate_at) with the march's step `step` (metres) instead of the volume's —
    /// the fire light's coarse line estimate. A volume that tracks (ratio, delta) or whose own step is as long
    /// integrates as `integrate_at` does.
    pub fn integrate_stepped_at(
        &self,
        ray: &Ray,
        time: f64,
        step: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> f64 {
        if self.estimator.integrator != Integrator::March || !(step > self.estimator.step) {
            return self.integrate_at(ray, time, l, t);
        }
        let (cut, hit) = self.ember_cut(ray, time);
        self.fault_check();
        let te = match self.advected(time) {
            Some(a) => {
                let map = |p: DVec3| a.displaced(p);
                let te = march::integrate_stepped(self, &a, Some(&map), &cut, step, l, t);
                self.thick_lines(Some(&a), &cut, cut.t1, Some(l), t, lines::Fold::Add);
                te
            }
            None => {
                let te = march::integrate_stepped(self, self, None, &cut, step, l, t);
                self.thick_lines(None, &cut, cut.t1, Some(l), t, lines::Fold::Add);
                te
            }
        };
        self.ember_seen(hit, time, Some(l), t).unwrap_or(te)
    }
    /// As [`integrate_exit`](Self::integrate_exit) at time `time`. (Refraction's curved march follows the
    /// grids' time: a refracting volume ignores `time` here but for its embers.)
    pub fn integrate_exit_at(
        &self,
        ray: &Ray,
        time: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> (DVec3, DVec3, f64) {
        let (cut, hit) = self.ember_cut(ray, time);
        let exit = self.integrate_exit_at_fire(&cut, time, l, t);
        match self.ember_seen(hit, time, Some(l), t) {
            Some(th) => (ray.o + ray.d * th, exit.1, th),
            None => exit,
        }
    }
    /// As [`transmittance`](Self::transmittance) at time `time`.
    pub fn transmittance_at(&self, ray: &Ray, time: f64, t: &mut [f64]) {
        let (cut, hit) = self.ember_cut(ray, time);
        self.transmittance_at_fire(&cut, time, t);
        self.ember_seen(hit, time, None, t);
    }
    /// As [`sample_scatter`](Self::sample_scatter) at time `time`.
    pub fn sample_scatter_at(&self, ray: &Ray, time: f64, l: &mut [f64], w: &mut [f64]) -> Event {
        let (cut, hit) = self.ember_cut(ray, time);
        let ev = self.sample_scatter_at_fire(&cut, time, l, w);
        self.ember_event(ev, hit, time, l, w)
    }
    /// `ray` up to the first ember it meets at `time`, and that ember's (parameter, index).
    fn ember_cut(&self, ray: &Ray, time: f64) -> (Ray, Option<(f64, usize)>) {
        let hit = self
            .layers
            .embers
            .as_ref()
            .and_then(|e| e.hit(ray.o, ray.d, ray.t0, ray.t1, time));
        let mut cut = *ray;
        if let Some((th, _)) = hit {
            cut.t1 = th.max(ray.t0);
        }
        (cut, hit)
    }
    /// An ember met at the end of a cut ray: its radiance seen through `t` added to `l`, and nothing passes
    /// it; returns where it was met.
    fn ember_seen(
        &self,
        hit: Option<(f64, usize)>,
        time: f64,
        l: Option<&mut [f64]>,
        t: &mut [f64],
    ) -> Option<f64> {
        let (Some((th, i)), Some(em)) = (hit, &self.layers.embers) else {
            return None;
        };
        if let Some(l) = l {
            let mut e = vec![0.0; t.len()];
            em.radiance(i, time, &mut e);
            for c in 0..t.len() {
                l[c] += t[c] * e[c];
            }
        }
        t.iter_mut().for_each(|v| *v = 0.0);
        Some(th)
    }
    /// A scattering event on a cut ray: one that reached the ember collects its radiance and ends there.
    fn ember_event(
        &self,
        ev: Event,
        hit: Option<(f64, usize)>,
        time: f64,
        l: &mut [f64],
        w: &mut [f64],
    ) -> Event {
        match ev {
            Event::Escaped if hit.is_some() => {
                self.ember_seen(hit, time, Some(l), w);
                Event::Absorbed
            }
            _ => ev,
        }
    }
    /// The volume's embers, if it has any.
    pub(crate) fn embers(&self) -> Option<&crate::embers::Embers> {
        self.layers.embers.as_ref()
    }
    /// Emitted radiance `l` and transmittance `t` (per channel) along `ray`; returns the exit parameter.
    fn integrate_fire(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> f64 {
        self.fault_check();
        let te = march::integrate(self, ray, l, t);
        self.thick_lines(None, ray, ray.t1, Some(l), t, lines::Fold::Add);
        te
    }
    /// The thick lines' part of a result along `ray` up to `end` (see [`lines`]), in the medium as `adv` sees it.
    fn thick_lines(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        end: f64,
        l: Option<&mut [f64]>,
        t: &mut [f64],
        fold: lines::Fold,
    ) {
        if let Some(tl) = &self.layers.lines {
            match adv {
                Some(a) => tl.apply(self, ray, end, false, &|p| a.displaced(p), l, t, fold),
                None => tl.apply(self, ray, end, true, &|p| p, l, t, fold),
            }
        }
    }
    /// `sample_scatter`'s event with the thick lines folded in (emission before the event, their mean
    /// transmittance on the weights).
    fn scatter_lines(
        &self,
        adv: Option<&motion::Advected>,
        ray: &Ray,
        ev: Event,
        l: &mut [f64],
        w: &mut [f64],
    ) -> Event {
        let end = match ev {
            Event::Scattered(t) => t,
            Event::Escaped => ray.t1,
            Event::Absorbed => return ev,
        };
        self.thick_lines(adv, ray, end, Some(l), w, lines::Fold::Scale);
        ev
    }
    /// As [`integrate`](Self::integrate), and where the ray leaves: (point, unit direction, parameter). With
    /// refraction on, the ray curves through the index field and leaves bent ([`crate::refraction::march`]); the
    /// parameter is then the entry parameter plus arc length / |d|.
    fn integrate_exit_fire(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> (DVec3, DVec3, f64) {
        let Some(rf) = &self.layers.refraction else {
            let te = self.integrate_fire(ray, l, t);
            return (ray.o + ray.d * te, ray.d.normalize_or_zero(), te);
        };
        self.fault_check();
        let exit = crate::refraction::march::integrate_exit(self, rf, ray, l, t);
        // (Along the straight chord: the bend is a fraction of a degree.)
        self.thick_lines(None, ray, ray.t1, Some(l), t, lines::Fold::Add);
        exit
    }

    /// Transmittance only (along the straight ray, also with refraction on: shadow rays do not bend).
    fn transmittance_fire(&self, ray: &Ray, t: &mut [f64]) {
        let mut sc = Scratch::new(self.channels());
        integrate::transmittance(self, ray, self.estimator.integrator, &mut sc, t);
        self.thick_lines(None, ray, ray.t1, None, t, lines::Fold::Add);
    }
    /// The first real scattering event (see [`Event`]); `l` gets the emission before it, `w` its weights.
    fn sample_scatter_fire(&self, ray: &Ray, l: &mut [f64], w: &mut [f64]) -> Event {
        let mut sc = Scratch::new(self.channels());
        let ev = integrate::sample_scatter(self, ray, &mut sc, l, w);
        self.scatter_lines(None, ray, ev, l, w)
    }

    /// The temperature (K) whose blackbody a viewer adapts to: the hottest when the colour is the physics',
    /// `None` when it is art-directed (a tint or a colour ramp: meant for a D65 white) or there is no temperature.
    pub fn white_temperature(&self) -> Option<f64> {
        self.temperature_range()
            .map(|[_, hi]| hi)
            .filter(|&t| self.model.physical_colour && t > 0.0)
    }

    /// What the volume holds beyond absorption — what a host that tracks the medium itself (from its point
    /// coefficients and majorant grid) must handle or refuse.
    pub fn features(&self) -> Features {
        Features {
            emits: self.can_emit(),
            scatters: self.scatters(),
            motion: self.layers.blur.is_some(),
            refraction: self.layers.refraction.is_some(),
            embers: self.layers.embers.is_some(),
            thick_lines: self.layers.lines.is_some(),
            diffusion: self.layers.diffusion.is_some(),
            emits_without_absorption: self.grids.emission_grid,
        }
    }
    /// The majorant grid a host walks with its own DDA: the box its cells tile, a cell's edge, the cells per
    /// axis and per cell (x fastest) a bound on σ_t over every channel and every point of the cell (and, with
    /// motion blur, over the shutter). A point of the volume's bounds outside the box (pbrt mode's half voxel)
    /// takes the nearest cell's bound.
    pub fn majorant_cells(&self) -> MajorantCells<'_> {
        MajorantCells {
            bounds: self.bounds.majorant.bounds(),
            cell: self.bounds.majorant.cell(),
            counts: self.bounds.majorant.counts(),
            sigma_t: self
                .layers
                .blur
                .as_ref()
                .map_or(&self.bounds.brick_sigma[..], |b| b.brick_sigma()),
        }
    }
    /// The volume's motion blur: the shutter (frames) and the largest displacement (medium units); `None`
    /// without a velocity grid or with the shutter closed.
    pub fn motion_blur(&self) -> Option<([f64; 2], f64)> {
        self.layers.blur.as_ref().map(|b| (b.shutter(), b.reach()))
    }
    /// As [`integrate`](Self::integrate) at time `time` (frames from the grids' time): with motion blur the
    /// fire is looked up where the velocity carried it from (`motion`). Without motion blur, or at time 0, the
    /// same as `integrate`.
    fn integrate_at_fire(&self, ray: &Ray, time: f64, l: &mut [f64], t: &mut [f64]) -> f64 {
        match self.advected(time) {
            Some(a) => {
                self.fault_check();
                let te = a.integrate(ray, l, t);
                self.thick_lines(Some(&a), ray, ray.t1, Some(l), t, lines::Fold::Add);
                te
            }
            None => self.integrate_fire(ray, l, t),
        }
    }
    /// As [`integrate_exit`](Self::integrate_exit) at time `time`. (Refraction's curved march follows the
    /// grids' time: a refracting volume ignores `time` here.)
    fn integrate_exit_at_fire(
        &self,
        ray: &Ray,
        time: f64,
        l: &mut [f64],
        t: &mut [f64],
    ) -> (DVec3, DVec3, f64) {
        match self.advected(time) {
            Some(a) if self.layers.refraction.is_none() => {
                self.fault_check();
                let te = a.integrate(ray, l, t);
                self.thick_lines(Some(&a), ray, ray.t1, Some(l), t, lines::Fold::Add);
                (ray.o + ray.d * te, ray.d.normalize_or_zero(), te)
            }
            _ => self.integrate_exit_fire(ray, l, t),
        }
    }
    /// As [`transmittance`](Self::transmittance) at time `time`.
    fn transmittance_at_fire(&self, ray: &Ray, time: f64, t: &mut [f64]) {
        match self.advected(time) {
            Some(a) => {
                a.transmittance(ray, t);
                self.thick_lines(Some(&a), ray, ray.t1, None, t, lines::Fold::Add);
            }
            None => self.transmittance_fire(ray, t),
        }
    }
    /// As [`sample_scatter`](Self::sample_scatter) at time `time`.
    fn sample_scatter_at_fire(&self, ray: &Ray, time: f64, l: &mut [f64], w: &mut [f64]) -> Event {
        match self.advected(time) {
            Some(a) => {
                let ev = a.sample_scatter(ray, l, w);
                self.scatter_lines(Some(&a), ray, ev, l, w)
            }
            None => self.sample_scatter_fire(ray, l, w),
        }
    }
    fn advected(&self, time: f64) -> Option<motion::Advected<'_>> {
        self.layers.blur.as_ref().and_then(|b| b.at(self, time))
    }
    /// σ_a, σ_s and j per channel at medium-space point `p` (zeros outside).
    /// (Atomic lines as their bins' means, thick or not: what a channel's coefficient is.)
    pub fn coefficients(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        Medium::eval(self, p, sa, ss, j);
        if let Some(tl) = &self.layers.lines {
            if let Some(st) = self.grids.ds.stencil_with_margin(p, self.bounds.margin) {
                let ch = self.grids.ds.channels();
                let value = |k: usize| ch[k].grid.eval(&st) as f64;
                let t = self.grids.temperature.map_or(0.0, value);
                tl.add_boxed(t, &value, sa, j);
            }
        }
    }
}

/// The grids at a point ([`FireVolume::lookup`]).
pub(super) struct Lookup {
    /// Soot density (clamped at 0).
    pub d: f64,
    /// Temperature, K (0 without a temperature grid).
    pub t: f64,
    /// The Lescale or emission grid's value (1 without one).
    pub les: f64,
    /// Whether it emits there (above pbrt mode's 100 K, or any temperature in physical mode).
    pub emits: bool,
}

impl FireVolume {
    /// The grids' values at medium-space point `p` (trilinear or as the dataset interpolates) and the stencil
    /// that read them (for further grids), `None` outside the volume and its margin: what both the bins'
    /// coefficients and the point query read.
    #[inline(always)]
    pub(super) fn lookup(&self, p: DVec3) -> Option<(crate::grid::Stencil, Lookup)> {
        let st = self.grids.ds.stencil_with_margin(p, self.bounds.margin)?;
        let ch = self.grids.ds.channels();
        let d = ch[self.grids.density].grid.eval(&st).max(0.0) as f64;
        let t = self
            .grids
            .temperature
            .map(|i| ch[i].grid.eval(&st) as f64)
            .unwrap_or(0.0);
        let les = self
            .grids
            .lescale
            .map(|i| ch[i].grid.eval(&st).max(0.0) as f64)
            .unwrap_or(1.0);
        let emits = t > self.model.t_emit || self.grids.temperature.is_none();
        Some((st, Lookup { d, t, les, emits }))
    }
    /// Whether the march splits steps thicker than `steptau` (pbrt mode): its bias is bounded, and estimates
    /// made from it (the fire light's line) must stay within it.
    pub(crate) fn splits_thick_steps(&self) -> bool {
        self.estimator.step_tau.is_finite()
    }
}

impl Medium for FireVolume {
    fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        crate::majorant::clip_box(
            o,
            d,
            t0,
            t1,
            self.bounds.clip_box[0],
            self.bounds.clip_box[1],
        )
    }
    fn step(&self) -> f64 {
        self.estimator.step
    }
    fn cutoff(&self) -> f64 {
        self.estimator.cutoff
    }
    fn step_tau(&self) -> f64 {
        self.estimator.step_tau
    }
    fn eval(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        EVALUATIONS.with(|n| n.set(n.get() + 1));
        let Some((st, Lookup { d, t, les, emits })) = self.lookup(p) else {
            sa.iter_mut()
                .chain(ss.iter_mut())
                .chain(j.iter_mut())
                .for_each(|v| *v = 0.0);
            return;
        };
        let ch = self.grids.ds.channels();
        let loc = self.model.j.locate(t);
        let at = self.model.a_t.as_ref().map(|tab| (tab, tab.locate(t)));
        for c in 0..sa.len() {
            sa[c] = d * at
                .map(|(tab, l)| tab.at(l, c) as f64)
                .unwrap_or(self.model.a[c]);
            ss[c] = d * self.model.s[c];
            j[c] = if emits {
                self.emitting(d, les) * self.model.j.at(loc, c) as f64
            } else {
                0.0
            };
        }
        // The scatter colour: what it does not scatter is absorbed (σ_t kept, so the majorants and the march
        // stand).
        if let Some((k, w)) = &self.model.scatter_color {
            let rgb = k.map(|i| (ch[i].grid.eval(&st) as f64).clamp(0.0, 1.0));
            for c in 0..sa.len() {
                let albedo = w[c][0] * rgb[0] + w[c][1] * rgb[1] + w[c][2] * rgb[2];
                sa[c] += ss[c] * (1.0 - albedo);
                ss[c] *= albedo;
            }
        }
        for sp in &self.grids.species {
            let n = ch[sp.ch].grid.eval(&st).max(0.0) as f64 * sp.scale;
            if n > 0.0 {
                let l = sp.sigma.locate(t);
                for c in 0..sa.len() {
                    sa[c] += n * sp.sigma.at(l, c) as f64;
                    j[c] += n * sp.j.at(l, c) as f64;
                }
            }
        }
        if let Some(df) = &self.layers.diffusion {
            df.add(p, ss, j);
        }
    }
    fn majorants(
        &self,
        o: DVec3,
        d: DVec3,
        t0: f64,
        t1: f64,
        f: &mut dyn FnMut(f64, f64, f64) -> bool,
    ) {
        self.majorants_over(&self.bounds.brick_sigma, o, d, t0, t1, f)
    }
    fn collision_cap_hit(&self) {
        self.capped
            .0
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    }
    fn empty_spans(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, f: &mut dyn FnMut(f64, f64)) {
        self.empty_spans_over(&self.bounds.brick_empty, o, d, t0, t1, f)
    }
}

/// Per channel, the weights of a scatter colour's r, g, b: the channel itself in rgb mode; in spectral bins the
/// bin means of the smooth rgb→spectrum fits of the three primaries (albedo fits, pbrt-v4's), normalised to sum
/// to 1 at every wavelength — so white is 1 in every bin and any colour in [0, 1]³ an albedo in [0, 1].
fn scatter_weights(basis: &Basis) -> Vec<[f64; 3]> {
    use firemedium_core::rgb_spectrum::{RgbSpectrum, RgbUse};
    if basis.mode == ColorMode::Rgb {
        return vec![[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let prim = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        .map(|rgb| RgbSpectrum::new(rgb, RgbUse::Albedo));
    let part = |k: usize, l: f64| {
        let v = prim.map(|p| p.eval(l).max(1e-12));
        v[k] / (v[0] + v[1] + v[2])
    };
    let per: Vec<Vec<f64>> = (0..3).map(|k| basis.absorb(&|l| part(k, l))).collect();
    (0..basis.channels())
        .map(|c| [per[0][c], per[1][c], per[2][c]])
        .collect()
}

/// The majorant bricks' edge for a dataset: `configured` (8 by default), doubled (up to 256) while the box
/// would hold more than 16 majorant bricks per 8³ brick the dataset stores — a sparse fire in a big box keeps
/// its majorant structures in proportion to its data; a dense one keeps the configured bricks (and so the same
/// results, bit for bit).
fn majorant_brick(configured: usize, topo: &crate::grid::Topology) -> usize {
    let dims = topo.dims();
    let active = topo.active_bricks().max(1);
    let mut b = configured.max(1);
    while b < 256 && dims.iter().map(|n| n.div_ceil(b)).product::<usize>() > 16 * active {
        b *= 2;
    }
    b
}

#[cfg(test)]
pub(crate) mod tests;
