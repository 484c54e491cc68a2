//! The coefficient tables of a fire volume, one builder per mode:
//! - [`physical`] — P&P: σ_a = f_v κ̂ (eq. 5) + Σ N_s σ̂_s(T) (eq. 7–12), j = intensity · (f_v κ̂B + Σ N_s ĵ_s),
//!   with f_v = sootscale · d; in rgb mode σ_a is the band's Planck mean at T, so it is a T table too;
//! - [`pbrt`] — pbrt-v4's grid media: σ_a = scale · sigma_a · d, j = σ_a · Lescale · B̃(T) for T > 100 K with B̃
//!   the peak-normalised blackbody (or a constant `Le`);
//!
//! and [`brick_majorants`], the largest σ_t of each majorant brick over its density and temperature ranges.

use super::basis::Basis;
use super::settings::SpectrumFn;
use super::tables::{RangeMax, SpeciesChannel, TTable};
use super::{ColorMode, Source, TableReport};
use crate::blackbody::{spectral_radiance, WIEN};
use crate::cie::cmf_table::CMF;
use crate::dataset::Dataset;
use crate::majorant::MajorantGrid;
use crate::soot::SootOptics;
use crate::species::Element;
use crate::Error;
use std::time::Instant;

/// Per-channel coefficients per unit density and the temperature tables.
pub(super) struct Coefficients {
    /// σ_a per unit density (rgb physical mode: see `a_t`).
    pub a: Vec<f64>,
    /// σ_a per unit density over T, where it depends on T (rgb physical mode).
    pub a_t: Option<TTable>,
    /// σ_s per unit density.
    pub s: Vec<f64>,
    /// Emission per unit density over T.
    pub j: TTable,
    /// Emission only above this temperature (pbrt's 100 K; 0 in physical mode).
    pub t_emit: f64,
    pub species: Vec<SpeciesChannel>,
    /// What the fire emits, for the light's full-spectrum power (physical mode).
    pub source: Option<Source>,
}

/// Soot and species tables (physical mode), up to the hottest voxel `t_max`.
#[allow(clippy::too_many_arguments)]
pub(super) fn physical(
    basis: &Basis,
    optics: &SootOptics,
    (alpha, sootscale, intensity): (f64, f64, f64),
    (smokescale, tint, ramp): (f64, Option<&SpectrumFn>, Option<&super::settings::Ramp>),
    species: &[(String, Element, f64)],
    sigma_s: Option<&SpectrumFn>,
    ds: &Dataset,
    t_max: f64,
    tables: &mut Vec<TableReport>,
) -> Coefficients {
    let c = basis.channels();
    let t0 = Instant::now();
    // κ(λ) is smooth between the optical constants' wavelengths (n, k linear there): the bin means of κ and
    // of κ·B are integrated piece by piece.
    let kinks: Vec<f64> = optics.rows().iter().map(|row| row[0]).collect();
    let kappa = {
        let optics = optics.clone();
        move |l: f64| optics.kappa(l, 1.0, alpha)
    };
    let kap = kappa.clone();
    let a = basis.absorb_split(&|l| smokescale * sootscale * kap(l), &kinks);
    let bb = basis.clone();
    let nodes = basis.nodes_split(&kinks);
    // The emission: the unscaled smoke's absorption (Kirchhoff's law, before art direction) times the tint.
    let g: Vec<f64> = nodes
        .lambda
        .iter()
        .map(|&l| intensity * sootscale * kappa(l) * tint.map_or(1.0, |f| f(l)))
        .collect();
    let art = Art::new(basis, ramp);
    let (a_t, j);
    if basis.mode() == ColorMode::Rgb {
        // The Planck-mean absorption per band and the emission, from one table build.
        let f: Vec<f64> = (0..CMF.len())
            .map(|i| smokescale * sootscale * kappa(380.0 + i as f64))
            .collect();
        let fallback = a.clone();
        let both = TTable::build(t_max, 2 * c, &move |t| {
            let mut rows = bb.soot_rgb_rows(&nodes, &g, &f, &fallback, t);
            let j = art.apply(t, &rows[c..]);
            rows.truncate(c);
            rows.extend(j);
            rows
        });
        let (ta, tj) = both.split(c);
        let seconds = t0.elapsed().as_secs_f64();
        tables.push(TableReport {
            name: "soot absorption (Planck-mean per band)".into(),
            bytes: ta.bytes(),
            seconds,
        });
        tables.push(TableReport {
            name: "soot emission".into(),
            bytes: tj.bytes(),
            seconds,
        });
        a_t = Some(ta);
        j = tj;
    } else {
        j = TTable::build(t_max, c, &move |t| {
            art.apply(t, &bb.emit_planck(&nodes, &g, t))
        });
        tables.push(TableReport {
            name: "soot emission".into(),
            bytes: j.bytes(),
            seconds: t0.elapsed().as_secs_f64(),
        });
        a_t = None;
    }
    let species_settings = species;
    let species = species_tables(species, ds, basis, t_max, intensity, tables);
    // (The fire light's full-spectrum power follows the physics: with a tint or a ramp, it reports its power over
    // the bins instead.)
    let physical_colour = tint.is_none() && ramp.is_none_or(|r| r.physical >= 1.0);
    let source = physical_colour.then(|| {
        let species = species_settings
            .iter()
            .zip(&species)
            .map(|((_, e, _), sp)| (e.clone(), sp.ch(), sp.scale()))
            .collect();
        Source::new(optics.clone(), alpha, (sootscale, intensity), species)
    });
    let s = match sigma_s {
        Some(f) => basis.absorb(&|l| smokescale * f(l)),
        None => vec![0.0; c],
    };
    Coefficients {
        a,
        a_t,
        s,
        j,
        t_emit: 0.0,
        species,
        source,
    }
}

/// σ_a = scale · sigma_a, σ_s = scale · sigma_s per unit density, and j = σ_a · Lescale · B̃(T) (T > 100 K) or
/// σ_a · Lescale · Le (pbrt mode); `temperature` says whether the dataset has a temperature grid.
#[allow(clippy::too_many_arguments)]
pub(super) fn pbrt(
    basis: &Basis,
    scale: f64,
    sigma_a: &SpectrumFn,
    le_scale: f64,
    le: Option<&SpectrumFn>,
    sigma_s: Option<&SpectrumFn>,
    temperature: bool,
    t_max: f64,
    tables: &mut Vec<TableReport>,
) -> Result<Coefficients, Error> {
    let c = basis.channels();
    let t0 = Instant::now();
    let a = basis.absorb(&|l| scale * sigma_a(l));
    let s = match sigma_s {
        Some(f) => basis.absorb(&|l| scale * f(l)),
        None => vec![0.0; c],
    };
    let bb = basis.clone();
    let a2 = a.clone();
    let j = match (le, temperature) {
        (Some(_), true) => {
            return Err(Error::invalid(
                "volume",
                "Le",
                "given with a temperature grid",
                "one of Le or temperature (as pbrt-v4)",
            ))
        }
        (Some(le), false) => {
            // j = σ_a Le: per channel σ_a,c times the channel value of Le.
            let lec = basis.emit(&|l| le(l));
            let row: Vec<f64> = (0..c).map(|i| a2[i] * le_scale * lec[i]).collect();
            TTable::constant(&row)
        }
        (None, _) => {
            let nodes = basis.nodes();
            let ones = vec![1.0; nodes.lambda.len()];
            TTable::build(t_max, c, &move |t| {
                if t <= 100.0 {
                    return vec![0.0; a2.len()];
                }
                let peak = spectral_radiance(t, WIEN / t * 1e9);
                let e = bb.emit_planck(&nodes, &ones, t);
                (0..a2.len())
                    .map(|i| a2[i] * le_scale * e[i] / peak)
                    .collect()
            })
        }
    };
    tables.push(TableReport {
        name: "blackbody (peak-normalised)".into(),
        bytes: j.bytes(),
        seconds: t0.elapsed().as_secs_f64(),
    });
    Ok(Coefficients {
        a,
        a_t: None,
        s,
        j,
        t_emit: 100.0,
        species: Vec::new(),
        source: None,
    })
}

/// The line tables of each species (σ̂ and ĵ over T, per channel), in the settings' order.
fn species_tables(
    species: &[(String, Element, f64)],
    ds: &Dataset,
    basis: &Basis,
    t_max: f64,
    intensity: f64,
    tables: &mut Vec<TableReport>,
) -> Vec<SpeciesChannel> {
    let aux = basis.line_aux();
    let mut out = Vec::new();
    for (sym, e, scale) in species {
        let ch = ds
            .channels()
            .iter()
            .position(|c| &c.name == sym)
            .unwrap_or(0);
        let t0 = Instant::now();
        let c = basis.channels();
        let (e1, b1, a1) = (e.clone(), basis.clone(), aux.clone());
        let sigma = TTable::build(t_max, c, &move |t| b1.lines(&e1, t, &a1).0);
        let (e2, b2, a2) = (e.clone(), basis.clone(), aux.clone());
        let j = TTable::build(t_max, c, &move |t| {
            b2.lines(&e2, t, &a2)
                .1
                .into_iter()
                .map(|v| v * intensity)
                .collect()
        });
        tables.push(TableReport {
            name: format!("species {sym} (lines)"),
            bytes: sigma.bytes() + j.bytes(),
            seconds: t0.elapsed().as_secs_f64(),
        });
        out.push(SpeciesChannel::new(ch, *scale, sigma, j));
    }
    out
}

/// The largest σ_t of each majorant brick over all channels: its largest density times the largest σ_a + σ_s
/// per unit density over its temperature range (T-dependent tables through [`RangeMax`]), plus each species'
/// largest number density times its largest line cross-section; widened by 1e-6 so that rounding never puts
/// it under the data.
pub(super) fn brick_majorants(
    majorant: &MajorantGrid,
    co: &Coefficients,
    density: usize,
    temperature: Option<usize>,
    c: usize,
) -> Vec<f64> {
    let counts = majorant.counts();
    let nb = counts[0] * counts[1] * counts[2];
    let (a, s, species) = (&co.a, &co.s, &co.species);
    let a_max = co.a_t.as_ref().map(|tab| RangeMax::new(tab, c));
    let sp_max: Vec<RangeMax> = species
        .iter()
        .map(|sp| RangeMax::new(sp.sigma(), c))
        .collect();
    (0..nb)
        .map(|b| {
            let dmax = majorant.max(b, density).max(0.0) as f64;
            let (tlo, thi) = temperature
                .map(|t| (majorant.min(b, t) as f64, majorant.max(b, t) as f64))
                .unwrap_or((0.0, 0.0));
            (0..c)
                .map(|ch| {
                    let ach = a_max
                        .as_ref()
                        .map(|m| m.max_over(tlo, thi, ch) as f64)
                        .unwrap_or(a[ch]);
                    let mut v = dmax * (ach + s[ch]);
                    for (sp, m) in species.iter().zip(&sp_max) {
                        v += majorant.max(b, sp.ch()).max(0.0) as f64
                            * sp.scale()
                            * m.max_over(tlo, thi, ch) as f64;
                    }
                    v
                })
                .fold(0.0, f64::max)
                * (1.0 + 1e-6)
        })
        .collect()
}

/// The colour ramp applied to an emission row (`colorramp`, `physical`): the ramp's colour at T, in the render's
/// channels, scaled to the row's luminance, blended with the row. Without a ramp, or at `physical` 1, the row
/// itself (bit for bit).
struct Art {
    /// (T, the key's colour in the channels, its luminance), and the channels' luminance weights.
    keys: Vec<(f64, Vec<f64>, f64)>,
    y: Vec<f64>,
    physical: f64,
}

impl Art {
    fn new(basis: &Basis, ramp: Option<&super::settings::Ramp>) -> Art {
        let y: Vec<f64> = basis.xyz().iter().map(|w| w.y).collect();
        let Some(ramp) = ramp.filter(|r| r.physical < 1.0) else {
            return Art {
                keys: Vec::new(),
                y,
                physical: 1.0,
            };
        };
        let keys = ramp
            .keys
            .iter()
            .map(|&(t, rgb)| {
                // An emitter's colour (pbrt-v4's RGBIlluminantSpectrum: the fit times D65, so white is D65's
                // white); the fit alone is a reflectance's, whose violet end reads purple in emission.
                let s = crate::rgb_spectrum::RgbSpectrum::new(
                    rgb,
                    crate::rgb_spectrum::RgbUse::Illuminant,
                );
                let ch = basis.emit(&|l| s.eval(l));
                let lum = ch.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>();
                (t, ch, lum)
            })
            .collect();
        Art {
            keys,
            y,
            physical: ramp.physical,
        }
    }

    fn apply(&self, t: f64, row: &[f64]) -> Vec<f64> {
        if self.keys.is_empty() {
            return row.to_vec();
        }
        // The ramp's colour at t: linear between keys, the end keys' beyond.
        let k = self.keys.partition_point(|(kt, _, _)| *kt <= t);
        let (colour, lum): (Vec<f64>, f64) = if k == 0 || k == self.keys.len() {
            let (_, c, l) = &self.keys[if k == 0 { 0 } else { k - 1 }];
            (c.clone(), *l)
        } else {
            let ((t0, c0, l0), (t1, c1, l1)) = (&self.keys[k - 1], &self.keys[k]);
            let f = (t - t0) / (t1 - t0);
            (
                c0.iter().zip(c1).map(|(a, b)| a + f * (b - a)).collect(),
                l0 + f * (l1 - l0),
            )
        };
        let y_row: f64 = row.iter().zip(&self.y).map(|(a, b)| a * b).sum();
        let scale = if lum > 0.0 { y_row / lum } else { 0.0 };
        row.iter()
            .zip(&colour)
            .map(|(&p, &c)| self.physical * p + (1.0 - self.physical) * c * scale)
            .collect()
    }
}
