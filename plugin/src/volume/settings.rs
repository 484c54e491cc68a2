//! The fire volume's parameters, read once into typed settings before anything is built (parse → settings →
//! build, as ripgrep's flags): every value is validated here, so the build cannot fail on a parameter. The
//! dataset's own parameters are read by [`crate::dataset::params`].

use super::basis::Basis;
use super::params::{
    self, ColourSpace, Fuel, Lattice, LineColour, LineShape, Precision, RefractionIntegrator,
    Scattering,
};
use super::{ColorMode, Integrator};
use crate::ciddor::Air;
use crate::cie::cmf_table::{CMF, CMF_START_NM};
use crate::dataset::params::{HostContext, Mode};
use crate::params::{Component, Param, ParamReader, ParamType, Values};
use crate::rgb_spectrum::{RgbSpectrum, RgbUse};
use crate::soot::SootOptics;
use crate::species::Element;
use crate::spectrum::SpectralGrid;
use crate::Error;

/// pbrt mode's largest optical depth of one march step (`steptau`'s default there): measured in
/// docs/reference/pbrt-compat.md.
pub(super) const PBRT_STEP_TAU: f64 = 0.1;

/// The largest optical depth of one march step when the smoke's light is diffusion's (`steptau`'s default
/// then): the scattered light is emission that rises over a diffusion length from the smoke's surface, and
/// the light that leaves comes from its first optical depth — a step sampling it once, deeper, is too bright
/// (+59 % at τ 105 across a metre, half-voxel steps of a 4-voxel grid; −8 % at this depth; docs/results/log.md).
pub(super) const DIFFUSION_STEP_TAU: f64 = 1.0;

/// Everything the volume's build reads from its parameters.
pub(super) struct Settings {
    pub mode: Mode,
    /// The channels and their photometric factor.
    pub basis: Basis,
    /// Where absorption and emission come from.
    pub emission: Emission,
    /// σ_s per unit density (pbrt mode: before `scale`), if given.
    pub sigma_s: Option<SpectrumFn>,
    /// σ_s per unit soot volume fraction (`sootscatter`): σ_s per unit density once the soot scale is known.
    pub sootscatter: Option<f64>,
    /// Majorant brick edge, voxels.
    pub brick: usize,
    /// `precision "f32"`: the march in f32 lanes where every product fits.
    f32_lanes: bool,
    /// `lattice`: auto, dense, bricks or off.
    pub lattice: Lattice,
    pub integrator: Integrator,
    /// March step, voxels.
    pub stepsize: f64,
    /// The largest optical depth of one march step before it is split (∞: never).
    pub step_tau: f64,
    pub cutoff: f64,
    pub g: f64,
    /// The fraction of the heat release the reaction zone emits as light (`chemiluminescence`).
    pub chemiluminescence: f64,
    /// Multiple scattering by diffusion at this many cells along the longest side (`multiplescattering`).
    pub diffusion: Option<usize>,
    /// Atomic lines by their Voigt profile where they can be thick (`lineshape`), else boxed over a bin.
    pub voigt: bool,
    /// Collisional FWHM at 2500 K, cm⁻¹ (`linebroadening`).
    pub linebroadening: f64,
    /// The index of air and the ray integrator, when `refraction` is on.
    pub refraction: Option<RefractionSettings>,
    /// The embers' char and the air around them.
    pub ember: crate::embers::Material,
    /// Whether `sootscale` was left unset: the build finds it from a file's density (`convention::soot_scale`).
    pub soot_auto: bool,
    #[cfg(test)]
    pub fault: String,
}

impl Settings {
    /// Whether the volume marches in f32 lanes (with diffusion the emission reads the coarse fluence grid: the
    /// f64 march).
    pub fn lanes_wanted(&self) -> bool {
        self.f32_lanes && self.integrator == Integrator::March && self.diffusion.is_none()
    }
}

/// The coefficients' source, by mode.
pub(super) enum Emission {
    /// Pegoraro & Parker: soot (eq. 5) and atomic lines (eq. 7–12).
    Physical {
        optics: SootOptics,
        alpha: f64,
        sootscale: f64,
        intensity: f64,
        /// Art direction: the smoke's absorption and scattering times `smokescale` (emission kept), and the
        /// soot's emission times the `tint` spectrum.
        smokescale: f64,
        tint: Option<SpectrumFn>,
        /// A colour ramp over temperature and how much of the physical colour stays (`physical`).
        ramp: Option<Ramp>,
        /// (symbol, element, m⁻³ per unit of its grid).
        species: Vec<(String, Element, f64)>,
    },
    /// pbrt-v4's grid media.
    Pbrt {
        scale: f64,
        sigma_a: SpectrumFn,
        /// `Lescale` when one value (a per-voxel `Lescale` array is a dataset channel).
        le_scale: f64,
        /// A constant emission spectrum instead of the blackbody of a temperature grid.
        le: Option<SpectrumFn>,
    },
}

/// Refraction's parameters (P&P §3.7).
pub(super) struct RefractionSettings {
    pub air: Air,
    /// Wavelength of the index field, nm.
    pub wavelength: f64,
    pub scale: f64,
    /// The RK4 reference integrator instead of the Verlet march.
    pub rk4: bool,
}

/// The component tables a volume's parameter list is read against.
pub(super) fn components() -> Vec<&'static Component> {
    #[cfg(test)]
    return vec![&params::DATASET, &params::VOLUME, &params::FAULTS];
    #[cfg(not(test))]
    vec![&params::DATASET, &params::VOLUME]
}

impl Settings {
    /// Reads and validates the volume's parameters (`list` for the raw spectrum values).
    pub(super) fn read(
        r: &ParamReader,
        list: &[Param],
        ctx: &HostContext,
    ) -> Result<Settings, Error> {
        #[cfg(test)]
        let fault = r.string("faultinjection")?;
        #[cfg(test)]
        if fault == "create" {
            panic!("fault injection: panic during creation");
        }
        let mode = ctx.mode(r)?;
        let basis = read_basis(r, mode, ctx)?;
        // pbrt-v4's grid media scatter unless told otherwise (σ_s defaults to 1, as σ_a); the paper's fire does not.
        let sigma_s = match (spectrum_param(r, "sigma_s", list, RgbUse::Unbounded)?, mode) {
            (None, Mode::Pbrt) => Some(std::sync::Arc::new(|_: f64| 1.0) as SpectrumFn),
            (s, _) => s,
        };
        let sootscatter = r.opt_float("sootscatter")?;
        if sootscatter.is_some() && list.iter().any(|p| p.name == "sigma_s") {
            return Err(Error::invalid(
                "volume",
                "sootscatter",
                "given with sigma_s",
                "one of the two (sootscatter per unit soot, sigma_s per unit density)",
            ));
        }
        let emission = match mode {
            Mode::Physical => read_physical(r, list)?,
            Mode::Pbrt => read_pbrt(r, list)?,
        };
        let brick = r.int("brick")? as usize;
        let f32_lanes = r.choice::<Precision>("precision")? == Precision::F32;
        let lattice = r.choice("lattice")?;
        // Unset: the march, for the paper's fire and for pbrt-v4's grids alike (pbrt-v4's own estimator, ratio
        // tracking, is `integrator "ratio"`). In pbrt mode a step thicker than `steptau` is split, so the march
        // follows a voxel far denser than its step (a 1-voxel grid σ_a = 1000 has τ = 500 per half-voxel step,
        // where the midpoint's emission is 80× brighter than the surface layer pbrt-v4 sees); its bias against
        // pbrt-v4's expected image is measured in docs/reference/pbrt-compat.md.
        let integrator = r
            .choice::<Option<Integrator>>("integrator")?
            .unwrap_or(Integrator::March);
        let stepsize = r.float("stepsize")?;

        let cutoff = r.float("cutoff")?;
        let g = r.float("g")?;
        let chemiluminescence = r.float("chemiluminescence")?;
        let voigt = r.choice::<LineShape>("lineshape")? == LineShape::Voigt;
        let diffusion = (r.choice::<Scattering>("multiplescattering")? == Scattering::Diffusion)
            .then_some(r.int("diffusionresolution")? as usize);
        let linebroadening = r.float("linebroadening")?;
        let step_tau = r.opt_float("steptau")?.unwrap_or(match (mode, diffusion) {
            (Mode::Pbrt, _) => PBRT_STEP_TAU,
            (Mode::Physical, Some(_)) => DIFFUSION_STEP_TAU,
            (Mode::Physical, None) => f64::INFINITY,
        });
        // Refraction's parameters are validated whether or not it is on.
        let on = r.bool("refraction")?;
        let air = Air {
            temperature_k: r.float("ambienttemperature")?,
            pressure_pa: r.float("pressure")?,
            relative_humidity: r.float("humidity")?,
            co2_ppm: r.float("co2")?,
        };
        let refraction = RefractionSettings {
            air,
            wavelength: r.float("refractionwavelength")?,
            scale: r.float("refractionscale")?,
            rk4: r.choice::<RefractionIntegrator>("refractionintegrator")?
                == RefractionIntegrator::Rk4,
        };
        let ember = crate::embers::Material {
            emissivity: r.float("emberemissivity")?,
            density: r.float("emberdensity")?,
            heat_capacity: r.float("emberheatcapacity")?,
            ambient: r.float("ambienttemperature")?,
            oxygen: r.float("emberoxygen")?,
        };
        Ok(Settings {
            mode,
            basis,
            emission,
            sigma_s,
            sootscatter,
            brick,
            f32_lanes,
            lattice,
            integrator,
            stepsize,
            step_tau,
            cutoff,
            g,
            chemiluminescence,
            voigt,
            linebroadening,
            diffusion,
            refraction: on.then_some(refraction),
            ember,
            soot_auto: mode == Mode::Physical && r.opt_float("sootscale")?.is_none(),
            #[cfg(test)]
            fault,
        })
    }
}

/// The channels: spectral bins over [lambdamin, lambdamax], or XYZ bands; K = 683 lm/W (physical: Y in cd/m²)
/// or 1 (pbrt-v4's film records ∫ L ȳ dλ as it is, with an imaging ratio of 1).
fn read_basis(r: &ParamReader, mode: Mode, ctx: &HostContext) -> Result<Basis, Error> {
    let colormode: ColourSpace = r.choice("colormode")?;
    let [lo, hi] = ctx.wavelengths.map_or([None; 2], |w| w.map(Some));
    let bins = match ctx.bins {
        Some(n) if !r.list_has("bins") => n,
        _ => r.int("bins")? as usize,
    };
    let grid = SpectralGrid::new(
        HostContext::float(r, "lambdamin", lo)?,
        HostContext::float(r, "lambdamax", hi)?,
        bins,
    )
    .map_err(|e| match e {
        firemedium_core::Error::InvalidParameter {
            name,
            value,
            expected,
            ..
        } => Error::InvalidParameter {
            at: None,
            index: None,
            component: "volume",
            name,
            value,
            expected,
        },
    })?;
    let mode_c = if colormode == ColourSpace::Rgb {
        ColorMode::Rgb
    } else {
        ColorMode::Spectral(grid)
    };
    let k = if mode == Mode::Pbrt {
        1.0
    } else {
        crate::constants::LUMINOUS_EFFICACY
    };
    let line_split = r.choice::<LineColour>("linecolour")? == LineColour::OwnWavelength;
    Ok(Basis::new(mode_c, k, line_split))
}

/// Soot optics (a named fuel or a custom (λ, n, k) table), its scales, and the species.
fn read_physical(r: &ParamReader, list: &[Param]) -> Result<Emission, Error> {
    for name in ["sigma_a", "scale", "Lescale", "Le"] {
        if list.iter().any(|p| p.name == name) {
            return Err(Error::invalid("volume", name, "given", "mode \"pbrt\" (in physical mode the fire's absorption and emission come from soot and species)"));
        }
    }
    let optics = match r.choice::<Fuel>("fuel")? {
        Fuel::Custom => {
            let v = r.numbers("fuelnk")?.ok_or_else(|| {
                Error::invalid(
                    "volume",
                    "fuelnk",
                    "unset",
                    "(λ nm, n, k) triples for fuel \"custom\"",
                )
            })?;
            if v.len() % 3 != 0 {
                return Err(Error::invalid(
                    "volume",
                    "fuelnk",
                    format!("{} values", v.len()),
                    "(λ nm, n, k) triples",
                ));
            }
            let rows: Vec<[f64; 3]> = v.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
            SootOptics::from_table(&rows).map_err(|e| {
                Error::invalid("volume", "fuelnk", e.to_string(), "a valid (λ, n, k) table")
            })?
        }
        Fuel::Propane => SootOptics::propane(),
        Fuel::Acetylene => SootOptics::acetylene(),
    };
    let alpha = r.float("alpha")?;
    // Unset: 1 until the build reads the density (`Settings::soot_auto`).
    let sootscale = r.opt_float("sootscale")?.unwrap_or(1.0);
    // `firescale`: the compositing name of `intensity` (one of the two).
    let intensity = match (r.opt_float("intensity")?, r.opt_float("firescale")?) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                "volume",
                "firescale",
                "given with intensity",
                "one of the two (they are the same)",
            ))
        }
        (Some(v), None) | (None, Some(v)) => v,
        (None, None) => 1.0,
    };
    let smokescale = r.float("smokescale")?;
    let tint = spectrum_param(r, "tint", list, RgbUse::Unbounded)?;
    let ramp = Ramp::read(r)?;
    let syms: Vec<String> = r
        .strings("species")?
        .unwrap_or_default()
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    let scales = r.numbers("speciesscale")?.unwrap_or(vec![1.0]);
    if scales.len() != 1 && scales.len() != syms.len() {
        return Err(Error::invalid(
            "dataset",
            "speciesscale",
            format!("{} values", scales.len()),
            format!("one value or one per species ({})", syms.len()),
        ));
    }
    let mut species = Vec::with_capacity(syms.len());
    for (i, sym) in syms.into_iter().enumerate() {
        let e = Element::by_symbol(&sym)?;
        species.push((sym, e, scales.get(i).copied().unwrap_or(scales[0])));
    }
    Ok(Emission::Physical {
        optics,
        alpha,
        sootscale,
        intensity,
        smokescale,
        tint,
        ramp,
        species,
    })
}

/// Art direction: a colour ramp over temperature (`colorramp`: keys T r g b) that replaces the blackbody's
/// chromaticity and keeps its luminance, blended with the physical colour by `physical` (1: physical, 0: the ramp).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Ramp {
    /// (T in K, linear sRGB), T increasing.
    pub(super) keys: Vec<(f64, [f64; 3])>,
    pub(super) physical: f64,
}

impl Ramp {
    fn read(r: &ParamReader) -> Result<Option<Ramp>, Error> {
        let physical = r.opt_float("physical")?;
        let Some(v) = r.numbers("colorramp")? else {
            if physical.is_some() {
                return Err(Error::invalid(
                    "volume",
                    "physical",
                    "given without a colorramp",
                    "a colorramp to blend the physical colour with",
                ));
            }
            return Ok(None);
        };
        let keys: Vec<(f64, [f64; 3])> = v
            .chunks_exact(4)
            .map(|k| (k[0], [k[1], k[2], k[3]]))
            .collect();
        // (At most 1024 keys: each is a spectrum fitted to its colour.)
        let ok = v.len() % 4 == 0
            && !keys.is_empty()
            && keys.len() <= 1024
            && v.iter().all(|x| x.is_finite())
            && keys
                .iter()
                .all(|(t, c)| *t >= 0.0 && c.iter().all(|x| *x >= 0.0))
            && keys.windows(2).all(|w| w[0].0 < w[1].0);
        if !ok {
            return Err(Error::invalid(
                "volume",
                "colorramp",
                format!("{} values", v.len()),
                "1 to 1024 keys of four numbers: a temperature in K (increasing) and a linear sRGB colour (≥ 0)",
            ));
        }
        Ok(Some(Ramp {
            keys,
            physical: physical.unwrap_or(0.0),
        }))
    }
}

/// pbrt-v4's σ_a, scale, Lescale and Le.
fn read_pbrt(r: &ParamReader, list: &[Param]) -> Result<Emission, Error> {
    for name in [
        "fuel",
        "fuelnk",
        "alpha",
        "sootscale",
        "sootscatter",
        "species",
        "smokescale",
        "firescale",
        "tint",
        "colorramp",
        "physical",
    ] {
        if list.iter().any(|p| p.name == name) {
            return Err(Error::invalid(
                "volume",
                name,
                "given",
                "mode \"physical\" (pbrt mode takes sigma_a, sigma_s, scale, Lescale, Le)",
            ));
        }
    }
    let scale = r.float("scale")?;
    let sigma_a = spectrum_param(r, "sigma_a", list, RgbUse::Unbounded)?
        .unwrap_or_else(|| std::sync::Arc::new(|_| 1.0));
    // A per-voxel Lescale array is a dataset channel (inline grids); then the scalar factor is 1.
    let per_voxel = crate::dataset::params::lescale_is_grid(r)?;
    let le_scale = if per_voxel { 1.0 } else { r.float("Lescale")? };
    let le = spectrum_param(r, "Le", list, RgbUse::Illuminant)?;
    // pbrt-v4 (GridMedium::Create) scales a constant `Le` to luminance 1 ("equivalent to 1 nit"): an rgb one
    // already is (to the luminance of its rgb); pairs and constants are divided by ∫ Le ȳ dλ here. An `Le` that
    // is zero everywhere emits nothing.
    let le = match le {
        Some(f)
            if !list
                .iter()
                .any(|p| p.name == "Le" && p.ty == ParamType::Rgb) =>
        {
            let y: f64 = CMF
                .iter()
                .enumerate()
                .map(|(i, c)| c[1] * f(CMF_START_NM + i as f64))
                .sum();
            (y > 0.0).then(|| std::sync::Arc::new(move |l| f(l) / y) as SpectrumFn)
        }
        le => le,
    };
    Ok(Emission::Pbrt {
        scale,
        sigma_a,
        le_scale,
        le,
    })
}

/// A spectrum as a function of wavelength (nm).
pub(super) type SpectrumFn = std::sync::Arc<dyn Fn(f64) -> f64 + Send + Sync>;

/// A spectrum parameter as a function of λ (nm): one constant, or (λ, value) pairs linear between, zero
/// outside (pbrt-v4's piecewise-linear spectrum), or an `rgb` value as pbrt-v4 makes it a spectrum of its use
/// (core's `rgb_spectrum`: σ's are unbounded spectra; an emission `Le` is an illuminant, the sigmoid times D65
/// scaled to the luminance of its rgb — pbrt-v4 divides a grid's `Le` by its photometric value, and for an rgb
/// spectrum that is its illuminant's alone).
fn spectrum_param(
    r: &ParamReader,
    name: &str,
    list: &[Param],
    usage: RgbUse,
) -> Result<Option<SpectrumFn>, Error> {
    if let Some(p) = list.iter().find(|p| p.name == name) {
        if let Values::Strings(v) = &p.values {
            return Err(Error::invalid(
                "volume",
                name,
                format!("the named spectrum \"{}\"", v.join(" ")),
                "a constant or (λ nm, value) pairs",
            ));
        }
        if p.ty == crate::params::ParamType::Rgb {
            // (Read through the reader too: type-checked and marked used.)
            r.numbers(name)?;
            if let Values::Numbers(v) = &p.values {
                if v.len() != 3 || v.iter().any(|x| !x.is_finite() || *x < 0.0) {
                    return Err(Error::invalid(
                        "volume",
                        name,
                        format!("rgb {v:?}"),
                        "three finite values >= 0",
                    ));
                }
                let s = RgbSpectrum::new([v[0], v[1], v[2]], usage);
                return Ok(Some(std::sync::Arc::new(move |l| s.eval(l))));
            }
        }
    }
    let Some(v) = r.numbers(name)? else {
        return Ok(None);
    };
    if v.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            "volume",
            name,
            format!("{v:?}"),
            "finite values",
        ));
    }
    if v.len() == 1 {
        let c = v[0];
        if c < 0.0 {
            return Err(Error::invalid("volume", name, c, "a value >= 0"));
        }
        return Ok(Some(std::sync::Arc::new(move |_| c)));
    }
    if v.len() % 2 != 0 || v.len() < 4 {
        return Err(Error::invalid(
            "volume",
            name,
            format!("{} values", v.len()),
            "one constant or (λ nm, value) pairs",
        ));
    }
    let pairs: Vec<(f64, f64)> = v.chunks(2).map(|c| (c[0], c[1])).collect();
    for w in pairs.windows(2) {
        if w[1].0 <= w[0].0 {
            return Err(Error::invalid(
                "volume",
                name,
                format!("wavelength {} after {}", w[1].0, w[0].0),
                "increasing wavelengths",
            ));
        }
    }
    if pairs.iter().any(|p| p.1 < 0.0) {
        return Err(Error::invalid(
            "volume",
            name,
            "a negative value",
            "values >= 0",
        ));
    }
    Ok(Some(std::sync::Arc::new(move |l| {
        if l < pairs[0].0 || l > pairs[pairs.len() - 1].0 {
            return 0.0;
        }
        let i = pairs
            .partition_point(|p| p.0 <= l)
            .clamp(1, pairs.len() - 1);
        let (a, b) = (pairs[i - 1], pairs[i]);
        a.1 + (l - a.0) / (b.0 - a.0) * (b.1 - a.1)
    })))
}
