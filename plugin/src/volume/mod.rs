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
//!   sigma_s,c · d, j_c = σ_a,c · Lescale · B̃_c(T) for T > 100 K with B̃ the peak-normalised blackbody (or a
//!   constant `Le` spectrum), Lescale possibly a grid. For NanoVDB files rays are clipped, as pbrt-v4 does, to
//!   NanoVDB's world box [T(i_min), T(i_max + 1)], and lookups fade toward the background over the half voxel
//!   beyond the last samples (NanoVDB's trilinear sampler).
//!
//! ## Channels
//! - `spectral`: `bins` equal bins over [lambdamin, lambdamax]; radiance in W·m⁻²·sr⁻¹·nm⁻¹ (bin means).
//! - `rgb`: three bands with the CIE 1931 x̄, ȳ, z̄ as weights over 380–780 nm: σ_c is the band's
//!   Planck-mean of σ(λ) at the local temperature (∫σ B w_c / ∫B w_c, so the optically thin limit j_c and the
//!   thick limit j_c/σ_c = the band's blackbody are both exact), j_c = K ∫ j(λ) w_c(λ) dλ with K = 683 lm/W, so radiance comes out as XYZ with Y in cd/m² (pbrt
//!   mode: K = 1/∫ȳ, pbrt's film normalisation). Non-negative weights keep every coefficient non-negative.
//!
//! Each channel's XYZ weights ([`FireVolume::channel_xyz`]) turn radiance into absolute XYZ.
//!
//! ## Tables
//! Everything that depends on T alone is tabulated once, in parallel, on a uniform grid of ≤ 0.5 K (at most
//! 65 536 rows up to the dataset's hottest voxel) and interpolated linearly; species tables exist only for
//! species present. The build report lists bytes and seconds per table.

mod integrate;
mod kernel;
mod lanes;
mod lattice;
pub mod params;

pub use integrate::{Event, Integrator, Ray};
use integrate::{Medium, Scratch};

use crate::blackbody::{spectral_radiance, WIEN};
use crate::cie::{self, cmf_table::CMF};
use crate::dataset::{
    ChannelSource, Dataset, Format, LoadOptions, Mapping, Policy, RawCoords, RawValue,
};
use crate::grid::Interpolation;
use crate::majorant::MajorantGrid;
use crate::params::{Param, ParamReader, Values};
use crate::soot::SootOptics;
use crate::species::Element;
use crate::spectrum::SpectralGrid;
use crate::Error;
use glam::DVec3;
use std::time::Instant;

pub use crate::cie::CIE_Y_INTEGRAL;

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

/// Channel basis: projections of spectral functions onto the channels.
#[derive(Debug, Clone)]
struct Basis {
    mode: ColorMode,
    /// Photometric factor: 683 lm/W (physical) or 1/∫ȳ (pbrt).
    k: f64,
}

impl Basis {
    fn channels(&self) -> usize {
        match self.mode {
            ColorMode::Spectral(g) => g.count(),
            ColorMode::Rgb => 3,
        }
    }
    /// Absorption-like: per channel mean of f (bin mean, or band-weighted mean).
    fn absorb(&self, f: &dyn Fn(f64) -> f64) -> Vec<f64> {
        match self.mode {
            ColorMode::Spectral(g) => g.bin_average(f),
            ColorMode::Rgb => {
                let (mut num, mut den) = ([0.0; 3], [0.0; 3]);
                for (i, w) in CMF.iter().enumerate() {
                    let v = f(380.0 + i as f64);
                    for c in 0..3 {
                        num[c] += v * w[c];
                        den[c] += w[c];
                    }
                }
                (0..3).map(|c| num[c] / den[c]).collect()
            }
        }
    }
    /// Emission-like: spectral bin means (W·m⁻³·sr⁻¹·nm⁻¹), or K ∫ f w_c dλ.
    fn emit(&self, f: &dyn Fn(f64) -> f64) -> Vec<f64> {
        match self.mode {
            ColorMode::Spectral(g) => g.bin_average(f),
            ColorMode::Rgb => {
                let mut out = vec![0.0; 3];
                for (i, w) in CMF.iter().enumerate() {
                    let v = f(380.0 + i as f64);
                    for c in 0..3 {
                        out[c] += self.k * v * w[c];
                    }
                }
                out
            }
        }
    }
    /// Wavelengths (nm) and (node, channel, weight) terms with emit(f)_c ≈ Σ weight·f(λ_node) over the
    /// channel's terms: the rgb bands' own 1 nm sums, and for spectral bins `emit`'s four 8-node Gauss–Legendre
    /// panels per bin. (Soot uses [`nodes_split`](Self::nodes_split): its n, k table is linear between its
    /// wavelengths, and one panel per smooth piece is exact where four panels across a kink are off by 5e-6.)
    fn nodes(&self) -> Nodes {
        match self.mode {
            ColorMode::Spectral(g) => {
                let n = g.bin_nodes(4);
                Nodes {
                    lambda: n.iter().map(|x| x.1).collect(),
                    terms: n.iter().enumerate().map(|(k, x)| (k, x.0, x.2)).collect(),
                }
            }
            ColorMode::Rgb => Nodes {
                lambda: (0..CMF.len()).map(|i| 380.0 + i as f64).collect(),
                terms: CMF
                    .iter()
                    .enumerate()
                    .flat_map(|(i, w)| (0..3).map(move |c| (i, c, w[c])))
                    .filter(|t| t.2 != 0.0)
                    .map(|(i, c, w)| (i, c, self.k * w))
                    .collect(),
            },
        }
    }
    /// [`absorb`](Self::absorb) of a spectrum smooth between the wavelengths `kinks`: spectral bins cut there,
    /// one 8-node Gauss–Legendre panel per piece (exact to rounding for such a spectrum, and a quarter of the
    /// four panels' nodes); the rgb bands as `absorb`.
    fn absorb_split(&self, f: &dyn Fn(f64) -> f64, kinks: &[f64]) -> Vec<f64> {
        match self.mode {
            ColorMode::Spectral(g) => g.bin_average_split(f, kinks, 1),
            ColorMode::Rgb => self.absorb(f),
        }
    }
    /// The nodes of [`absorb_split`](Self::absorb_split)'s rule (the rgb bands' as [`nodes`](Self::nodes)).
    fn nodes_split(&self, kinks: &[f64]) -> Nodes {
        match self.mode {
            ColorMode::Spectral(g) => {
                let n = g.bin_nodes_split(kinks, 1);
                Nodes {
                    lambda: n.iter().map(|x| x.1).collect(),
                    terms: n.iter().enumerate().map(|(k, x)| (k, x.0, x.2)).collect(),
                }
            }
            ColorMode::Rgb => self.nodes(),
        }
    }
    /// `emit(|λ| g(λ)·B(T, λ))` with g given at the nodes (so a temperature table evaluates g once, not per row;
    /// B once per node).
    fn emit_planck(&self, nodes: &Nodes, g: &[f64], t: f64) -> Vec<f64> {
        let b: Vec<f64> = nodes
            .lambda
            .iter()
            .zip(g)
            .map(|(&l, &g)| {
                if g != 0.0 {
                    g * spectral_radiance(t, l)
                } else {
                    0.0
                }
            })
            .collect();
        let mut out = vec![0.0; self.channels()];
        for &(n, c, w) in &nodes.terms {
            out[c] += w * b[n];
        }
        out
    }
    /// rgb soot at T, one Planck evaluation per wavelength for both rows (the CIE table's 1 nm wavelengths,
    /// 380, 381, … 780 nm, the `nodes` of this basis): the absorption per band, the band's Planck-mean
    /// σ_c = Σ f B w_c / Σ B w_c (f = σ per unit density at the nodes), so that both the thin (j_c) and the thick
    /// (j_c/σ_c → the band's blackbody) limits are exact, or `fallback` (the plain band means) where B vanishes;
    /// then the emission per band, as [`emit_planck`](Self::emit_planck) with `g` — each in its own order of
    /// operations, so the values are those of two separate passes (tested).
    fn soot_rgb_rows(
        &self,
        nodes: &Nodes,
        g: &[f64],
        f: &[f64],
        fallback: &[f64],
        t: f64,
    ) -> Vec<f64> {
        let b: Vec<f64> = nodes
            .lambda
            .iter()
            .map(|&l| spectral_radiance(t, l))
            .collect();
        let (mut num, mut den) = ([0.0; 3], [0.0; 3]);
        for ((w, &bi), &fi) in CMF.iter().zip(&b).zip(f) {
            for c in 0..3 {
                num[c] += fi * bi * w[c];
                den[c] += bi * w[c];
            }
        }
        let mut out: Vec<f64> = if den.iter().all(|&d| d > 0.0) {
            (0..3).map(|c| num[c] / den[c]).collect()
        } else {
            fallback.to_vec()
        };
        let mut e = [0.0; 3];
        for &(n, c, w) in &nodes.terms {
            e[c] += w * if g[n] != 0.0 { g[n] * b[n] } else { 0.0 };
        }
        out.extend(e);
        out
    }
    /// Per-unit-N line cross-sections of `e` at T: (σ̂ m², ĵ per channel).
    fn lines(
        &self,
        e: &Element,
        t: f64,
        fine: &SpectralGrid,
        fine_w: &[DVec3],
    ) -> (Vec<f64>, Vec<f64>) {
        match self.mode {
            ColorMode::Spectral(g) => {
                let (mut sa, mut j) = (vec![0.0; g.count()], vec![0.0; g.count()]);
                e.add_binned_cross_sections(t, &g, &mut sa, &mut j);
                (sa, j)
            }
            ColorMode::Rgb => {
                let n = fine.count();
                let (mut sa, mut j) = (vec![0.0; n], vec![0.0; n]);
                e.add_binned_cross_sections(t, fine, &mut sa, &mut j);
                // σ_c: the Planck-weighted band mean (as for soot), j_c: the band's energy.
                let (mut s3, mut j3, mut den, mut den0, mut s0) =
                    (vec![0.0; 3], vec![0.0; 3], [0.0; 3], [0.0; 3], [0.0; 3]);
                for i in 0..n {
                    let w = fine_w[i];
                    let b = spectral_radiance(t, fine.centre(i));
                    for c in 0..3 {
                        s3[c] += sa[i] * b * w[c];
                        den[c] += b * w[c];
                        s0[c] += sa[i] * w[c];
                        den0[c] += w[c];
                        j3[c] += self.k * j[i] * w[c];
                    }
                }
                for c in 0..3 {
                    s3[c] = if den[c] > 0.0 {
                        s3[c] / den[c]
                    } else {
                        s0[c] / den0[c]
                    };
                }
                (s3, j3)
            }
        }
    }
    /// XYZ per unit channel radiance.
    fn xyz(&self) -> Vec<DVec3> {
        match self.mode {
            ColorMode::Spectral(g) => cie::bin_weights(&g)
                .into_iter()
                .map(|w| w / crate::constants::LUMINOUS_EFFICACY * self.k)
                .collect(),
            ColorMode::Rgb => vec![DVec3::X, DVec3::Y, DVec3::Z],
        }
    }
}

/// Quadrature nodes of a basis (see [`Basis::nodes`]).
struct Nodes {
    lambda: Vec<f64>,
    terms: Vec<(usize, usize, f64)>,
}

/// A temperature table: `rows` × C values, row r at T = r·dt, each row stored as lanes of `lanes::W` channels
/// (zero-padded), which the f32 march reads directly.
#[derive(Debug, Clone, Default)]
struct TTable {
    dt: f64,
    /// 1 / dt (the kernel multiplies).
    inv_dt: f64,
    rows: usize,
    /// Lanes per row.
    chunks: usize,
    v: Vec<lanes::Lane>,
}

impl TTable {
    /// Tabulates `f(T) -> C values` for T in [0, t_max], in parallel.
    fn build(t_max: f64, c: usize, f: &(dyn Fn(f64) -> Vec<f64> + Sync)) -> TTable {
        let rows = ((t_max / 0.5).ceil() as usize + 2).clamp(2, 65_536);
        let dt = if t_max > 0.0 {
            t_max / (rows - 2) as f64
        } else {
            1.0
        };
        let chunks = c.div_ceil(lanes::W).max(1);
        let mut v = vec![[0f32; lanes::W]; rows * chunks];
        let threads = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .min(8);
        let chunk = rows.div_ceil(threads);
        std::thread::scope(|s| {
            for (k, part) in v.chunks_mut(chunk * chunks).enumerate() {
                s.spawn(move || {
                    for (r, row) in part.chunks_mut(chunks).enumerate() {
                        for (ch, x) in f((k * chunk + r) as f64 * dt).into_iter().enumerate() {
                            row[ch / lanes::W][ch % lanes::W] = x as f32;
                        }
                    }
                });
            }
        });
        TTable {
            dt,
            inv_dt: 1.0 / dt,
            rows,
            chunks,
            v,
        }
    }
    /// The table of channels 0..c and the table of the rest (one build that computes both, split).
    fn split(&self, c: usize) -> (TTable, TTable) {
        let total = self.chunks * lanes::W;
        let part = |from: usize, to: usize| {
            let n = to - from;
            let chunks = n.div_ceil(lanes::W).max(1);
            let mut v = vec![[0f32; lanes::W]; self.rows * chunks];
            for r in 0..self.rows {
                for ch in 0..n {
                    v[r * chunks + ch / lanes::W][ch % lanes::W] = self.value(r, from + ch);
                }
            }
            TTable {
                dt: self.dt,
                inv_dt: self.inv_dt,
                rows: self.rows,
                chunks,
                v,
            }
        };
        (part(0, c.min(total)), part(c.min(total), total))
    }
    /// The same values at every temperature.
    fn constant(row: &[f64]) -> TTable {
        TTable::build(0.0, row.len(), &|_| row.to_vec())
    }
    /// Row index and fraction of T.
    #[inline]
    fn locate(&self, t: f64) -> (usize, f32) {
        let f = (t / self.dt).clamp(0.0, (self.rows - 1) as f64);
        let i = (f as usize).min(self.rows - 2);
        (i, (f - i as f64) as f32)
    }
    #[inline]
    fn value(&self, r: usize, c: usize) -> f32 {
        self.v[r * self.chunks + c / lanes::W][c % lanes::W]
    }
    #[inline]
    fn at(&self, (i, fr): (usize, f32), c: usize) -> f32 {
        let a = self.value(i, c);
        a + fr * (self.value(i + 1, c) - a)
    }
    fn bytes(&self) -> usize {
        self.v.len() * std::mem::size_of::<lanes::Lane>()
    }
}

/// The largest value of each of a temperature table's first `c` channels over any range of rows, in O(1): a
/// sparse table (level k holds the maxima over 2ᵏ rows from each row), so the majorant bricks' temperature
/// ranges cost two reads each instead of a scan of their rows (the rgb volume's bricks: 60 → 25 ms at 256³).
/// The same values as a scan of the rows, bit for bit (tested).
struct RangeMax {
    dt: f64,
    rows: usize,
    c: usize,
    levels: Vec<Vec<f32>>,
}

impl RangeMax {
    fn new(tab: &TTable, c: usize) -> RangeMax {
        let rows = tab.rows;
        let mut levels = vec![(0..rows * c)
            .map(|i| tab.value(i / c, i % c))
            .collect::<Vec<f32>>()];
        let mut k = 1;
        while (1usize << k) <= rows {
            let (half, prev) = (1usize << (k - 1), &levels[k - 1]);
            let n = rows + 1 - (1usize << k);
            let next: Vec<f32> = (0..n * c)
                .map(|i| prev[i].max(prev[i + half * c]))
                .collect();
            levels.push(next);
            k += 1;
        }
        RangeMax {
            dt: tab.dt,
            rows,
            c,
            levels,
        }
    }
    /// The largest value of channel `ch` over T in [lo, hi] (rows rounded outward), ≥ 0.
    fn max_over(&self, lo: f64, hi: f64, ch: usize) -> f32 {
        let last = (self.rows - 1) as f64;
        let a = (lo / self.dt).floor().clamp(0.0, last) as usize;
        let b = (hi / self.dt).ceil().clamp(0.0, last) as usize;
        if b < a || ch >= self.c {
            return 0.0;
        }
        let k = (usize::BITS - 1 - (b - a + 1).leading_zeros()) as usize;
        let level = &self.levels[k];
        level[a * self.c + ch]
            .max(level[(b + 1 - (1usize << k)) * self.c + ch])
            .max(0.0)
    }
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

#[derive(Debug, Clone)]
struct SpeciesChannel {
    ch: usize,
    scale: f64,
    sigma: TTable,
    j: TTable,
}

/// A fire volume: a dataset, its coefficient tables and majorants, and an integrator.
#[derive(Debug, Clone)]
pub struct FireVolume {
    ds: Dataset,
    density: usize,
    temperature: Option<usize>,
    lescale: Option<usize>,
    species: Vec<SpeciesChannel>,
    basis: Basis,
    mode: Mode,
    /// σ_a and σ_s per unit density, per channel (rgb physical mode: σ_a depends on T, `a_t`).
    a: Vec<f64>,
    a_t: Option<TTable>,
    s: Vec<f64>,
    /// Emission per unit density over T.
    j: TTable,
    /// pbrt's 100 K emission threshold (0 in physical mode).
    t_emit: f64,
    majorant: MajorantGrid,
    brick_sigma: Vec<f64>,
    /// Bricks holding no density and no species anywhere in their interpolation footprint: no σ, no j.
    brick_empty: Vec<bool>,
    /// Where rays are clipped: the dataset bounds, or pbrt-v4 nanovdb's world box [T(i_min), T(i_max + 1)]
    /// (shifted half a voxel up), with lookups fading over the half voxel beyond the last samples.
    clip_box: [DVec3; 2],
    margin: f64,
    step: f64,
    integrator: Integrator,
    cutoff: f64,
    g: f64,
    tables: Vec<TableReport>,
    build_seconds: f64,
    source: Option<Source>,
    /// The index field and step control, only when `refraction` is on.
    refraction: Option<Refraction>,
    /// The march's tables in f32 lanes (`precision "f32"`, the march, and every product inside f32's range).
    lanes: Option<lanes::LaneTables>,
    /// The grids laid out for the lane march's kernel (with the lanes, for trilinear datasets).
    lattice: Option<lattice::Lattice>,
    #[cfg(test)]
    fault: String,
}

/// A spectrum parameter as a function of λ (nm): one constant, or (λ, value) pairs linear between, zero
/// outside (pbrt-v4's piecewise-linear spectrum). Gray `rgb` values are constants.
/// A spectrum as a function of wavelength (nm).
type SpectrumFn = Box<dyn Fn(f64) -> f64 + Send + Sync>;

fn spectrum_param(
    r: &ParamReader,
    name: &str,
    list: &[Param],
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
            if let Values::Numbers(v) = &p.values {
                if v.len() != 3 || v[0] != v[1] || v[1] != v[2] {
                    return Err(Error::invalid("volume", name, format!("rgb {v:?}"), "a gray rgb (r = g = b) or a spectrum; coloured rgb needs a spectral uplift this plugin does not do"));
                }
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
    if v.len() == 1 || (v.len() == 3 && v[0] == v[1] && v[1] == v[2]) {
        let c = v[0];
        if c < 0.0 {
            return Err(Error::invalid("volume", name, c, "a value >= 0"));
        }
        return Ok(Some(Box::new(move |_| c)));
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
    Ok(Some(Box::new(move |l| {
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

impl FireVolume {
    /// Builds a fire volume from a parameter list (the `dataset` and `volume` tables, docs/params.md).
    pub fn new(list: &[Param]) -> Result<FireVolume, Error> {
        let start = Instant::now();
        #[cfg(test)]
        let comps: Vec<&'static crate::params::Component> =
            vec![&params::DATASET, &params::VOLUME, &params::FAULTS];
        #[cfg(not(test))]
        let comps: Vec<&'static crate::params::Component> = vec![&params::DATASET, &params::VOLUME];
        let r = ParamReader::new("volume", list, &comps);
        r.check_names()?;
        #[cfg(test)]
        let fault = r.string("faultinjection")?;
        #[cfg(test)]
        if fault == "create" {
            panic!("fault injection: panic during creation");
        }
        let mode = if r.string("mode")? == "pbrt" {
            Mode::Pbrt
        } else {
            Mode::Physical
        };

        // ---- dataset
        let (ds, lescale) = load_dataset(&r, mode)?;
        let density = ds
            .channels()
            .iter()
            .position(|c| c.name == "density")
            .unwrap_or(0);
        let temperature = ds.channel("temperature").map(|_| {
            ds.channels()
                .iter()
                .position(|c| c.name == "temperature")
                .unwrap_or(0)
        });

        // ---- channel basis
        let colormode = r.string("colormode")?;
        let grid = SpectralGrid::new(
            r.float("lambdamin")?,
            r.float("lambdamax")?,
            r.int("bins")? as usize,
        )
        .map_err(|e| match e {
            firemedium_core::Error::InvalidParameter {
                name,
                value,
                expected,
                ..
            } => Error::InvalidParameter {
                component: "volume",
                name,
                value,
                expected,
            },
        })?;
        let cmode = if colormode == "rgb" {
            ColorMode::Rgb
        } else {
            ColorMode::Spectral(grid)
        };
        let k = if mode == Mode::Pbrt {
            1.0 / CIE_Y_INTEGRAL
        } else {
            crate::constants::LUMINOUS_EFFICACY
        };
        let basis = Basis { mode: cmode, k };
        let c = basis.channels();

        // ---- coefficients
        let t_max = temperature
            .map(|i| ds.channels()[i].stats.max as f64)
            .unwrap_or(0.0)
            .max(0.0);
        let mut tables = Vec::new();
        let sigma_s = spectrum_param(&r, "sigma_s", list)?;
        let (a, s, j, t_emit, species);
        let mut a_t = None;
        let mut source = None;
        let t0 = Instant::now();
        match mode {
            Mode::Physical => {
                for name in ["sigma_a", "scale", "Lescale", "Le"] {
                    if list.iter().any(|p| p.name == name) {
                        return Err(Error::invalid("volume", name, "given", "mode \"pbrt\" (in physical mode the fire's absorption and emission come from soot and species)"));
                    }
                }
                let optics = match r.string("fuel")?.as_str() {
                    "custom" => {
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
                            Error::invalid(
                                "volume",
                                "fuelnk",
                                e.to_string(),
                                "a valid (λ, n, k) table",
                            )
                        })?
                    }
                    f => SootOptics::for_fuel(f)?,
                };
                let alpha = r.float("alpha")?;
                let sootscale = r.float("sootscale")?;
                let intensity = r.float("intensity")?;
                // κ(λ) is smooth between the optical constants' wavelengths (n, k linear there): the bin means
                // of κ and of κ·B are integrated piece by piece.
                let kinks: Vec<f64> = optics.rows().iter().map(|row| row[0]).collect();
                let optics_kept = optics.clone();
                let kappa = move |l: f64| optics.kappa(l, 1.0, alpha);
                let kap = kappa.clone();
                a = basis.absorb_split(&|l| sootscale * kap(l), &kinks);
                let bb = basis.clone();
                let nodes = basis.nodes_split(&kinks);
                let g: Vec<f64> = nodes
                    .lambda
                    .iter()
                    .map(|&l| intensity * sootscale * kappa(l))
                    .collect();
                if basis.mode == ColorMode::Rgb {
                    // The Planck-mean absorption per band and the emission, from one table build.
                    let f: Vec<f64> = (0..CMF.len())
                        .map(|i| sootscale * kappa(380.0 + i as f64))
                        .collect();
                    let fallback = a.clone();
                    let both = TTable::build(t_max, 2 * c, &move |t| {
                        bb.soot_rgb_rows(&nodes, &g, &f, &fallback, t)
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
                    j = TTable::build(t_max, c, &move |t| bb.emit_planck(&nodes, &g, t));
                    tables.push(TableReport {
                        name: "soot emission".into(),
                        bytes: j.bytes(),
                        seconds: t0.elapsed().as_secs_f64(),
                    });
                }
                t_emit = 0.0;
                species = build_species(&r, &ds, &basis, t_max, intensity, &mut tables)?;
                let mut sp = Vec::new();
                for sym in r
                    .strings("species")?
                    .unwrap_or_default()
                    .into_iter()
                    .filter(|s| !s.is_empty())
                {
                    let ch = ds
                        .channels()
                        .iter()
                        .position(|c| c.name == sym)
                        .unwrap_or(0);
                    let scale = species
                        .iter()
                        .find(|x| x.ch == ch)
                        .map(|x| x.scale)
                        .unwrap_or(1.0);
                    sp.push((Element::by_symbol(&sym)?, ch, scale));
                }
                source = Some(Source {
                    soot: optics_kept,
                    alpha,
                    soot_scale: sootscale * intensity,
                    intensity,
                    species: sp,
                });
                s = match &sigma_s {
                    Some(f) => basis.absorb(&|l| f(l)),
                    None => vec![0.0; c],
                };
            }
            Mode::Pbrt => {
                for name in ["fuel", "fuelnk", "alpha", "sootscale", "species"] {
                    if list.iter().any(|p| p.name == name) {
                        return Err(Error::invalid("volume", name, "given", "mode \"physical\" (pbrt mode takes sigma_a, sigma_s, scale, Lescale, Le)"));
                    }
                }
                let scale = r.float("scale")?;
                let sa = spectrum_param(&r, "sigma_a", list)?.unwrap_or_else(|| Box::new(|_| 1.0));
                a = basis.absorb(&|l| scale * sa(l));
                s = match &sigma_s {
                    Some(f) => basis.absorb(&|l| scale * f(l)),
                    None => vec![0.0; c],
                };
                let le_scale = if lescale.is_some() {
                    1.0
                } else {
                    r.float("Lescale")?
                };
                let le = spectrum_param(&r, "Le", list)?;
                let bb = basis.clone();
                let a2 = a.clone();
                match (le, temperature) {
                    (Some(_), Some(_)) => {
                        return Err(Error::invalid(
                            "volume",
                            "Le",
                            "given with a temperature grid",
                            "one of Le or temperature (as pbrt-v4)",
                        ))
                    }
                    (Some(le), None) => {
                        // j = σ_a Le: per channel σ_a,c times the channel value of Le.
                        let lec = basis.emit(&|l| le(l));
                        let row: Vec<f64> = (0..c).map(|i| a2[i] * le_scale * lec[i]).collect();
                        j = TTable::constant(&row);
                    }
                    (None, _) => {
                        let nodes = basis.nodes();
                        let ones = vec![1.0; nodes.lambda.len()];
                        j = TTable::build(t_max, c, &move |t| {
                            if t <= 100.0 {
                                return vec![0.0; a2.len()];
                            }
                            let peak = spectral_radiance(t, WIEN / t * 1e9);
                            let e = bb.emit_planck(&nodes, &ones, t);
                            (0..a2.len())
                                .map(|i| a2[i] * le_scale * e[i] / peak)
                                .collect()
                        });
                    }
                }
                tables.push(TableReport {
                    name: "blackbody (peak-normalised)".into(),
                    bytes: j.bytes(),
                    seconds: t0.elapsed().as_secs_f64(),
                });
                t_emit = 100.0;
                species = Vec::new();
            }
        }
        if a.iter().chain(&s).any(|v| !v.is_finite() || *v < 0.0) {
            return Err(Error::invalid(
                "volume",
                "sigma_a/sigma_s",
                format!("{a:?} {s:?}"),
                "finite, non-negative coefficients",
            ));
        }

        // ---- majorants
        let brick = r.int("brick")? as usize;
        let precision = r.string("precision")?;
        let integrator =
            Integrator::from_name(&r.string("integrator")?).unwrap_or(Integrator::March);
        // The march lattice, for a volume that marches in f32 lanes over a trilinear dataset (kept below only
        // if the lanes are built): made first, because it gathers its grids' brick ranges as it copies them.
        let mut lattice = None;
        let mut known = vec![None; ds.channels().len()];
        if precision == "f32"
            && integrator == Integrator::March
            && ds.interpolation() == crate::grid::Interpolation::Trilinear
        {
            let t4 = Instant::now();
            let ch = ds.channels();
            let extra: Vec<usize> = lescale
                .iter()
                .copied()
                .chain(species.iter().map(|sp| sp.ch))
                .collect();
            let grids: Vec<&crate::grid::Grid> = extra.iter().map(|&k| &ch[k].grid).collect();
            if let Some((lat, ranges)) = lattice::Lattice::build(
                &ch[density].grid,
                temperature.map(|k| &ch[k].grid),
                &grids,
                brick,
            ) {
                let order = std::iter::once(density).chain(temperature).chain(extra);
                for (k, r) in order.zip(ranges) {
                    if known[k].is_none() {
                        known[k] = Some(r);
                    }
                }
                lattice = Some((lat, t4.elapsed().as_secs_f64()));
            }
        }
        let t1 = Instant::now();
        let majorant = MajorantGrid::with_ranges(&ds, brick, known);
        let counts = majorant.counts();
        let nb = counts[0] * counts[1] * counts[2];
        let a_max = a_t.as_ref().map(|tab| RangeMax::new(tab, c));
        let sp_max: Vec<RangeMax> = species
            .iter()
            .map(|sp| RangeMax::new(&sp.sigma, c))
            .collect();
        let brick_sigma: Vec<f64> = (0..nb)
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
                            v += majorant.max(b, sp.ch).max(0.0) as f64
                                * sp.scale
                                * m.max_over(tlo, thi, ch) as f64;
                        }
                        v
                    })
                    .fold(0.0, f64::max)
                    * (1.0 + 1e-6)
            })
            .collect();
        let brick_empty: Vec<bool> = (0..nb)
            .map(|b| {
                majorant.max(b, density) <= 0.0
                    && species.iter().all(|sp| majorant.max(b, sp.ch) <= 0.0)
            })
            .collect();
        tables.push(TableReport {
            name: format!("majorant bricks ({brick}³ voxels)"),
            bytes: majorant.bytes() + brick_sigma.len() * 8,
            seconds: t1.elapsed().as_secs_f64(),
        });

        let stepsize = r.float("stepsize")?;
        let cutoff = r.float("cutoff")?;
        let g = r.float("g")?;
        let step = stepsize * ds.voxel_size().min_element();
        let refraction = if r.bool("refraction")? {
            let t_ch = temperature.ok_or_else(|| {
                Error::invalid(
                    "volume",
                    "refraction",
                    "true without a temperature grid",
                    "a temperature grid (the index of air follows from it)",
                )
            })?;
            let t2 = Instant::now();
            let air = crate::ciddor::Air {
                temperature_k: r.float("ambienttemperature")?,
                pressure_pa: r.float("pressure")?,
                relative_humidity: r.float("humidity")?,
                co2_ppm: r.float("co2")?,
            };
            let [b0, b1] = ds.bounds();
            let field = crate::refraction::IndexGrid::from_temperature(
                &ds.channels()[t_ch].grid,
                b0,
                b1,
                r.float("refractionwavelength")?,
                &air,
                r.float("refractionscale")?,
            );
            tables.push(TableReport {
                name: "refraction index field".into(),
                bytes: field.bytes(),
                seconds: t2.elapsed().as_secs_f64(),
            });
            let voxel = ds.voxel_size().min_element();
            let rk4 = r.string("refractionintegrator")? == "rk4";
            let steps = if rk4 {
                // RK steps of at most a voxel, each ending at the next plane of samples (one trilinear cell).
                crate::refraction::Steps {
                    h_max: step.min(voxel),
                    h_min: 1e-6 * voxel,
                    tol: 1e-6 * voxel,
                    ..Default::default()
                }
            } else {
                // The march's steps (halved where the ray would turn by more than max_turn in one).
                crate::refraction::Steps {
                    h_max: step,
                    h_min: 1e-6 * voxel,
                    ..Default::default()
                }
            };
            Some(Refraction { field, steps, rk4 })
        } else {
            r.string("refractionintegrator")?;
            for name in [
                "refractionscale",
                "refractionwavelength",
                "ambienttemperature",
                "pressure",
                "humidity",
                "co2",
            ] {
                r.float(name)?;
            }
            None
        };
        r.finish()?;
        // The largest value a lookup can return, from the bricks' ranges (for the lane march's range check).
        let max = |ch: usize| (0..nb).map(|b| majorant.max(b, ch)).fold(0f32, f32::max) as f64;
        let (dmax, lesmax) = (max(density), lescale.map_or(1.0, max));
        let nmax: Vec<f64> = species.iter().map(|sp| max(sp.ch)).collect();
        let [b0, b1] = ds.bounds();
        let (clip_box, margin) = if mode == Mode::Pbrt && ds.format() == Format::NanoVdb {
            let half = ds.voxel_size() * 0.5;
            ([b0 + half, b1 + half], 0.5)
        } else {
            ([b0, b1], 0.0)
        };
        let mut vol = FireVolume {
            ds,
            density,
            temperature,
            lescale,
            species,
            basis,
            mode,
            a,
            a_t,
            s,
            j,
            t_emit,
            majorant,
            brick_sigma,
            brick_empty,
            clip_box,
            margin,
            step,
            integrator,
            cutoff,
            g,
            tables,
            build_seconds: start.elapsed().as_secs_f64(),
            source,
            refraction,
            lanes: None,
            lattice: None,
            #[cfg(test)]
            fault,
        };
        if precision == "f32" && integrator == Integrator::March {
            let t3 = Instant::now();
            vol.lanes = lanes::LaneTables::build(&vol, dmax, lesmax, &nmax, step);
            if let Some(lt) = &vol.lanes {
                vol.tables.push(TableReport {
                    name: "march lanes (σ per unit density; the tables are shared)".into(),
                    bytes: lt.bytes(),
                    seconds: t3.elapsed().as_secs_f64(),
                });
                if let Some((lat, seconds)) = lattice {
                    vol.tables.push(TableReport {
                        name: "march lattice (grids interleaved and padded; their brick ranges)"
                            .into(),
                        bytes: lat.bytes(),
                        seconds,
                    });
                    vol.lattice = Some(lat);
                }
            }
        }
        vol.build_seconds = start.elapsed().as_secs_f64();
        Ok(vol)
    }

    /// The dataset.
    pub fn dataset(&self) -> &Dataset {
        &self.ds
    }
    /// Medium-space bounds rays are clipped to (the dataset's, or pbrt-v4 nanovdb's world box in pbrt mode).
    pub fn bounds(&self) -> [DVec3; 2] {
        self.clip_box
    }
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.basis.channels()
    }
    /// The colour mode.
    pub fn color_mode(&self) -> ColorMode {
        self.basis.mode
    }
    /// The coefficient mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }
    /// XYZ (Y in cd/m², or pbrt's relative units in pbrt mode) per unit radiance in each channel.
    pub fn channel_xyz(&self) -> Vec<DVec3> {
        self.basis.xyz()
    }
    /// The integrator in use.
    pub fn integrator(&self) -> Integrator {
        self.integrator
    }
    /// Henyey–Greenstein g.
    pub fn g(&self) -> f64 {
        self.g
    }
    /// Whether any scattering is configured.
    pub fn scatters(&self) -> bool {
        self.s.iter().any(|&v| v > 0.0)
    }
    /// March step length, medium units.
    pub fn step_length(&self) -> f64 {
        self.step
    }
    /// The tables built (name, bytes, seconds).
    pub fn tables(&self) -> &[TableReport] {
        &self.tables
    }
    /// Bytes held by the dataset and tables.
    pub fn bytes(&self) -> usize {
        // (The species line tables are among `tables`, reported as "species X (lines)".)
        self.ds.bytes() + self.tables.iter().map(|t| t.bytes).sum::<usize>()
    }
    /// Seconds spent building.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
    pub(crate) fn source(&self) -> Option<&Source> {
        self.source.as_ref()
    }
    pub(crate) fn density_channel(&self) -> usize {
        self.density
    }
    pub(crate) fn temperature_channel(&self) -> Option<usize> {
        self.temperature
    }
    /// The lowest and highest temperature of the grid (K, after the mapping), if it has one.
    pub fn temperature_range(&self) -> Option<[f64; 2]> {
        let s = self.ds.channels()[self.temperature?].grid.stats();
        Some([s.min as f64, s.max as f64])
    }

    #[cfg(test)]
    fn fault_check(&self) {
        if self.fault == "integrate" {
            panic!("fault injection: panic during integration");
        }
    }
    #[cfg(not(test))]
    fn fault_check(&self) {}

    /// Emitted radiance `l` and transmittance `t` (per channel) along `ray`; returns the exit parameter.
    pub fn integrate(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> f64 {
        self.fault_check();
        if let Some(lt) = &self.lanes {
            return march_kernel(self, lt, ray, l, t)
                .unwrap_or_else(|| march_lanes(self, lt, ray, l, t));
        }
        let mut sc = Scratch::new(self.channels());
        integrate::integrate(self, ray, self.integrator, &mut sc, l, t)
    }

    /// One march step in lanes at `p`: the coefficients there, then the step; returns the largest transmittance.
    /// (Inlined always, so that `march_lanes`' AVX2 clone holds it.)
    #[inline(always)]
    fn lane_step(&self, lt: &lanes::LaneTables, p: DVec3, delta: f64, ls: &mut LaneScratch) -> f32 {
        let Some(st) = self.ds.stencil_with_margin(p, self.margin) else {
            return 1.0;
        };
        let ch = self.ds.channels();
        let d = ch[self.density].grid.eval(&st).max(0.0);
        let mut n = [0f32; lanes::MAX_SPECIES];
        for (k, sp) in self.species.iter().enumerate() {
            n[k] = (ch[sp.ch].grid.eval(&st).max(0.0) as f64 * sp.scale) as f32;
        }
        // No soot and no species here: σ = j = 0, the step would add +0 and multiply by e⁰ = 1 exactly, so it
        // is skipped (bit for bit the same; the transmittance is unchanged, so the march goes on).
        if d == 0.0 && n.iter().all(|&x| x == 0.0) {
            return 1.0;
        }
        let t = self.temperature.map_or(0.0, |i| ch[i].grid.eval(&st));
        let les = self.lescale.map_or(1.0, |i| ch[i].grid.eval(&st).max(0.0));
        let emits = t as f64 > self.t_emit || self.temperature.is_none();
        let LaneScratch { sig, jj, l, t: tr } = ls;
        let dl = if emits { d * les } else { 0.0 };
        lt.coefficients(self, lanes::Sample { d, t, dl }, &n, sig, jj);
        lanes::step(sig, jj, delta as f32, l, tr)
    }
    /// As [`integrate`](Self::integrate), and where the ray leaves: (point, unit direction, parameter). With
    /// refraction on, the ray curves inside the index field's box (the grid's, two voxels wider; its march follows
    /// the curved path in Verlet steps of the march's length) and leaves bent; the parameter is then the entry
    /// parameter plus arc length / |d|.
    pub fn integrate_exit(&self, ray: &Ray, l: &mut [f64], t: &mut [f64]) -> (DVec3, DVec3, f64) {
        let Some(Refraction { field, steps, rk4 }) = &self.refraction else {
            let te = self.integrate(ray, l, t);
            return (ray.o + ray.d * te, ray.d.normalize_or_zero(), te);
        };
        self.fault_check();
        l.iter_mut().for_each(|v| *v = 0.0);
        t.iter_mut().for_each(|v| *v = 1.0);
        let speed = ray.d.length();
        let dir = ray.d / speed;
        // The curved path starts where the ray enters the index field's box (two voxels wider than the grid).
        let [c0, c1] = field.bounds();
        let clip = crate::majorant::clip_box(ray.o, ray.d, ray.t0, ray.t1, c0, c1);
        let (Some((a, _)), true) = (clip, speed > 0.0 && speed.is_finite()) else {
            return (ray.o + ray.d * ray.t1, dir, ray.t1);
        };
        let slack = 1e-9 * (c1 - c0).max_element();
        let inside = |p: DVec3| p.cmpge(c0 - slack).all() && p.cmple(c1 + slack).all();
        let mut sc = Scratch::new(self.channels());
        if *rk4 {
            // The curved path as a polyline of RK steps; then the march over it at the volume's own step (so the
            // coefficients are evaluated as often as along a straight ray, not once per RK step).
            let mut path: Vec<(DVec3, f64)> = vec![(ray.o + ray.d * a, 0.0)];
            let exit = crate::refraction::trace(
                field,
                ray.o + ray.d * a,
                dir,
                (ray.t1 - a) * speed,
                steps,
                |_, x1, h| {
                    let s_prev = path.last().map(|v| v.1).unwrap_or(0.0);
                    path.push((x1, s_prev + h));
                },
                |p| !inside(p),
            );
            let total = exit.s;
            let ds = if total / self.step > integrate::MAX_STEPS {
                total / integrate::MAX_STEPS
            } else {
                self.step
            };
            let mut rng = crate::rng::Rng::new(ray.seed);
            let (mut s0, mut next) = (0.0, rng.next_f64() * ds);
            if next <= 0.0 {
                next = ds;
            }
            let mut seg = 0;
            while s0 < total && ds > 0.0 {
                let s1 = next.min(total);
                let mid = 0.5 * (s0 + s1);
                while seg + 2 < path.len() && path[seg + 1].1 < mid {
                    seg += 1;
                }
                let (pa, sa_) = path[seg];
                let (pb, sb_) = path[(seg + 1).min(path.len() - 1)];
                let f = if sb_ > sa_ {
                    ((mid - sa_) / (sb_ - sa_)).clamp(0.0, 1.0)
                } else {
                    0.0
                };
                Medium::eval(self, pa + (pb - pa) * f, &mut sc.sa, &mut sc.ss, &mut sc.j);
                if integrate::march_step(&sc.sa, &sc.ss, &sc.j, s1 - s0, l, t) < self.cutoff {
                    break;
                }
                s0 = s1;
                next += ds;
            }
            return (exit.x, exit.dir, a + exit.s / speed);
        }
        // One Verlet step per march step: the medium is evaluated at the step's midpoint, where the step looked
        // up n and ∇n, so a curved ray costs one index lookup per sample more than a straight one.
        let diag = (c1 - c0).length();
        let ds = if diag / self.step > integrate::MAX_STEPS {
            diag / integrate::MAX_STEPS
        } else {
            self.step
        };
        let mut rng = crate::rng::Rng::new(ray.seed);
        let first = rng.next_f64() * ds;
        let mut opaque = false;
        let mut ls = self.lanes.as_ref().map(|lt| LaneScratch::new(lt.chunks()));
        let exit = crate::refraction::trace_verlet(
            field,
            ray.o + ray.d * a,
            dir,
            (ray.t1 - a) * speed,
            ds,
            first,
            steps,
            |mid, h| {
                // (The padding around the grid bends rays but holds no medium; nor do empty bricks.)
                let [m0, m1] = self.clip_box;
                let empty = self
                    .majorant
                    .brick_at(mid)
                    .is_some_and(|b| self.brick_empty[b]);
                if !opaque && !empty && mid.cmpge(m0).all() && mid.cmple(m1).all() {
                    opaque = match (&self.lanes, &mut ls) {
                        (Some(lt), Some(ls)) => {
                            EVALUATIONS.with(|n| n.set(n.get() + 1));
                            self.lane_step(lt, mid, h, ls) < self.cutoff as f32
                        }
                        _ => {
                            Medium::eval(self, mid, &mut sc.sa, &mut sc.ss, &mut sc.j);
                            integrate::march_step(&sc.sa, &sc.ss, &sc.j, h, l, t) < self.cutoff
                        }
                    };
                }
            },
            |p| !inside(p),
        );
        if let Some(ls) = &ls {
            ls.finish(l, t);
        }
        (exit.x, exit.dir, a + exit.s / speed)
    }
    /// Transmittance only (along the straight ray, also with refraction on: shadow rays do not bend).
    pub fn transmittance(&self, ray: &Ray, t: &mut [f64]) {
        let mut sc = Scratch::new(self.channels());
        integrate::transmittance(self, ray, self.integrator, &mut sc, t)
    }
    /// The first real scattering event (see [`Event`]); `l` gets the emission before it, `w` its weights.
    pub fn sample_scatter(&self, ray: &Ray, l: &mut [f64], w: &mut [f64]) -> Event {
        let mut sc = Scratch::new(self.channels());
        integrate::sample_scatter(self, ray, &mut sc, l, w)
    }
    /// σ_a, σ_s and j per channel at medium-space point `p` (zeros outside).
    pub fn coefficients(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        Medium::eval(self, p, sa, ss, j)
    }
}

/// The straight march in f32 lanes (the same steps, at the same points, as the f64 march of `integrate`); compiled
/// twice, for baseline x86-64 and for AVX2 + FMA (8 channels per instruction), chosen once at run time.
#[multiversion::multiversion(targets("x86_64+avx2+fma"))]
fn march_lanes(
    v: &FireVolume,
    lt: &lanes::LaneTables,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> f64 {
    l.iter_mut().for_each(|v| *v = 0.0);
    t.iter_mut().for_each(|v| *v = 1.0);
    let Some(span) = integrate::Span::new(v, ray) else {
        return ray.t1;
    };
    let mut rng = crate::rng::Rng::new(ray.seed);
    let mut ls = LaneScratch::new(lt.chunks());
    let mut empty = Vec::new();
    let cutoff = v.cutoff as f32;
    let mut samples = 0;
    integrate::march_steps(&span, &mut rng, &mut empty, |p, delta| {
        samples += 1;
        v.lane_step(lt, p, delta, &mut ls) >= cutoff
    });
    EVALUATIONS.with(|n| n.set(n.get() + samples));
    ls.finish(l, t);
    span.b
}

/// The straight march's kernel (`kernel::march`) for 1–4 lanes of channels (`None` for more: `march_lanes`
/// takes them); compiled for baseline x86-64 and for AVX2 + FMA, chosen once at run time.
#[multiversion::multiversion(targets(
    "x86_64+avx512f+avx512vl+avx512bw+avx512dq+avx2+fma",
    "x86_64+avx2+fma"
))]
fn march_kernel(
    v: &FireVolume,
    lt: &lanes::LaneTables,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> Option<f64> {
    const F: bool = multiversion::target::target_cfg_f!(target_feature = "fma");
    // The lanes' shape from the channel count: rgb in one lane of 4 (a 128-bit register, no padding work),
    // spectral bins in lanes of 16 where the clone has AVX-512, else of 8. σ_a depends on T only in rgb
    // physical mode (3 channels).
    const WIDE: bool = multiversion::target::target_cfg_f!(target_feature = "avx512f");
    let (s, a) = (!v.species.is_empty(), v.a_t.is_some());
    macro_rules! lanes {
        ($cv:literal, $v:literal) => {
            match (s, a) {
                (false, false) => kernel::march::<$cv, $v, false, false, F>(v, lt, ray, l, t),
                (true, false) => kernel::march::<$cv, $v, true, false, F>(v, lt, ray, l, t),
                _ => None,
            }
        };
    }
    match v.channels() {
        0..=4 => match (s, a) {
            (false, false) => kernel::march::<1, 4, false, false, F>(v, lt, ray, l, t),
            (false, true) => kernel::march::<1, 4, false, true, F>(v, lt, ray, l, t),
            (true, false) => kernel::march::<1, 4, true, false, F>(v, lt, ray, l, t),
            (true, true) => kernel::march::<1, 4, true, true, F>(v, lt, ray, l, t),
        },
        5..=8 => lanes!(1, 8),
        9..=16 if WIDE => lanes!(1, 16),
        9..=16 => lanes!(2, 8),
        17..=24 => lanes!(3, 8),
        25..=32 if WIDE => lanes!(2, 16),
        25..=32 => lanes!(4, 8),
        _ => None,
    }
}

/// Per-ray state of the lane march: coefficients at the sample, radiance and transmittance.
struct LaneScratch {
    sig: Vec<lanes::Lane>,
    jj: Vec<lanes::Lane>,
    l: Vec<lanes::Lane>,
    t: Vec<lanes::Lane>,
}

impl LaneScratch {
    fn new(chunks: usize) -> LaneScratch {
        let zero = vec![[0f32; lanes::W]; chunks];
        LaneScratch {
            sig: zero.clone(),
            jj: zero.clone(),
            l: zero,
            t: vec![[1f32; lanes::W]; chunks],
        }
    }
    /// The ray's radiance and transmittance per channel.
    fn finish(&self, l: &mut [f64], t: &mut [f64]) {
        for c in 0..l.len() {
            l[c] = self.l[c / lanes::W][c % lanes::W] as f64;
            t[c] = self.t[c / lanes::W][c % lanes::W] as f64;
        }
    }
}

thread_local! {
    static EVALUATIONS: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// How many times any fire volume evaluated its coefficients on this thread (a counter for benchmarks: read it
/// before and after the work, on the same thread).
pub fn evaluations_on_this_thread() -> u64 {
    EVALUATIONS.with(|n| n.get())
}

/// The refraction state of a volume: the baked index field and how rays are stepped through it.
#[derive(Debug, Clone)]
struct Refraction {
    field: crate::refraction::IndexGrid,
    steps: crate::refraction::Steps,
    /// The RK4 reference integrator instead of the Verlet march.
    rk4: bool,
}

impl Medium for FireVolume {
    fn clip(&self, o: DVec3, d: DVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        crate::majorant::clip_box(o, d, t0, t1, self.clip_box[0], self.clip_box[1])
    }
    fn step(&self) -> f64 {
        self.step
    }
    fn cutoff(&self) -> f64 {
        self.cutoff
    }
    fn eval(&self, p: DVec3, sa: &mut [f64], ss: &mut [f64], j: &mut [f64]) {
        EVALUATIONS.with(|n| n.set(n.get() + 1));
        let Some(st) = self.ds.stencil_with_margin(p, self.margin) else {
            sa.iter_mut()
                .chain(ss.iter_mut())
                .chain(j.iter_mut())
                .for_each(|v| *v = 0.0);
            return;
        };
        let ch = self.ds.channels();
        let d = ch[self.density].grid.eval(&st).max(0.0) as f64;
        let t = self
            .temperature
            .map(|i| ch[i].grid.eval(&st) as f64)
            .unwrap_or(0.0);
        let les = self
            .lescale
            .map(|i| ch[i].grid.eval(&st).max(0.0) as f64)
            .unwrap_or(1.0);
        let emits = t > self.t_emit || self.temperature.is_none();
        let loc = self.j.locate(t);
        let at = self.a_t.as_ref().map(|tab| (tab, tab.locate(t)));
        for c in 0..sa.len() {
            sa[c] = d * at.map(|(tab, l)| tab.at(l, c) as f64).unwrap_or(self.a[c]);
            ss[c] = d * self.s[c];
            j[c] = if emits {
                d * les * self.j.at(loc, c) as f64
            } else {
                0.0
            };
        }
        for sp in &self.species {
            let n = ch[sp.ch].grid.eval(&st).max(0.0) as f64 * sp.scale;
            if n > 0.0 {
                let l = sp.sigma.locate(t);
                for c in 0..sa.len() {
                    sa[c] += n * sp.sigma.at(l, c) as f64;
                    j[c] += n * sp.j.at(l, c) as f64;
                }
            }
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
        for seg in self.majorant.segments(o, d, t0, t1) {
            if !f(seg.t0, seg.t1, self.brick_sigma[seg.brick]) {
                return;
            }
        }
    }
    fn empty_spans(&self, o: DVec3, d: DVec3, t0: f64, t1: f64, f: &mut dyn FnMut(f64, f64)) {
        // (Lescale multiplies the soot emission, which is zero where the density is: no need to look at it.)
        for seg in self.majorant.segments(o, d, t0, t1) {
            if self.brick_empty[seg.brick] {
                f(seg.t0, seg.t1);
            }
        }
    }
}

/// Loads the dataset the parameters describe; returns it and the index of a per-voxel Lescale channel.
fn load_dataset(r: &ParamReader, mode: Mode) -> Result<(Dataset, Option<usize>), Error> {
    let pol = |name: &str| -> Result<Policy, Error> { Policy::from_name(name, &r.string(name)?) };
    let format = match r.string("format")?.as_str() {
        "" => None,
        f => Some(Format::from_name(f)?),
    };
    let rawdims = r.ints("rawdims")?.unwrap_or(vec![256, 256, 256]);
    if rawdims.len() != 3 {
        return Err(Error::invalid(
            "dataset",
            "rawdims",
            format!("{} values", rawdims.len()),
            "three integers",
        ));
    }
    let (p0, p1) = (r.point3("p0")?, r.point3("p1")?);
    let bounds = match (p0, p1) {
        (None, None) => None,
        (a, b) => Some([
            DVec3::from(a.unwrap_or([0.0; 3])),
            DVec3::from(b.unwrap_or([1.0; 3])),
        ]),
    };
    let opts = LoadOptions {
        format,
        order: if r.string("order")? == "z" {
            crate::dataset::AxisOrder::ZFastest
        } else {
            crate::dataset::AxisOrder::XFastest
        },
        raw_coords: if r.string("rawcoords")? == "xyz" {
            RawCoords::Xyz
        } else {
            RawCoords::Thesis
        },
        raw_value: if r.string("rawvalue")? == "maxrgb" {
            RawValue::MaxRgb
        } else {
            RawValue::Red
        },
        raw_dims: [
            rawdims[0] as usize,
            rawdims[1] as usize,
            rawdims[2] as usize,
        ],
        nonfinite: pol("nonfinite")?,
        negative: pol("negative")?,
        max_bytes: r.float("maxbytes")? as u64,
        frame: r.ints("frame")?.and_then(|v| v.first().copied()),
        bounds,
    };
    let offset = match (
        r.opt_float("temperatureoffset")?,
        r.opt_float("temperaturecutoff")?,
    ) {
        (Some(_), Some(_)) => {
            return Err(Error::invalid(
                "dataset",
                "temperaturecutoff",
                "given with temperatureoffset",
                "one of the two (they are the same)",
            ))
        }
        (Some(o), None) | (None, Some(o)) => o,
        (None, None) => 0.0,
    };
    let tmap = Mapping {
        scale: r.float("temperaturescale")?,
        offset: 0.0,
        pbrt_offset: offset,
    };
    let interp = if r.string("interpolation")? == "nearest" {
        Interpolation::Nearest
    } else {
        Interpolation::Trilinear
    };
    let species: Vec<String> = r
        .strings("species")?
        .unwrap_or_default()
        .into_iter()
        .filter(|s| !s.is_empty())
        .collect();
    if mode == Mode::Pbrt && !species.is_empty() {
        return Err(Error::invalid(
            "volume",
            "species",
            "given",
            "mode \"physical\"",
        ));
    }
    let inline_density = r.numbers("density")?;
    let lescale_values = r.numbers("Lescale")?;
    let (mut ds, lescale) = if let Some(dens) = inline_density {
        let dims = [
            r.int("nx")? as usize,
            r.int("ny")? as usize,
            r.int("nz")? as usize,
        ];
        let to32 = |v: &[f64]| v.iter().map(|&x| x as f32).collect::<Vec<f32>>();
        let dens = to32(&dens);
        let mut temp = r.numbers("temperature")?.map(|v| to32(&v));
        if let Some(t) = temp.as_mut() {
            for v in t.iter_mut() {
                *v = ((*v as f64 - tmap.pbrt_offset) * tmap.scale) as f32;
            }
        }
        let les = lescale_values.filter(|v| v.len() > 1).map(|v| to32(&v));
        let mut arrays: Vec<(&str, &[f32])> = vec![("density", &dens)];
        if let Some(t) = &temp {
            arrays.push(("temperature", t));
        }
        if let Some(l) = &les {
            arrays.push(("Lescale", l));
        }
        let [b0, b1] = bounds.unwrap_or([DVec3::ZERO, DVec3::ONE]);
        let ds = Dataset::from_inline(dims, b0, b1, &arrays, &opts)?;
        let li = les.as_ref().map(|_| arrays.len() - 1);
        (ds, li)
    } else {
        let filename = match (r.string("filename")?, r.string("dataset")?) {
            (f, d) if !f.is_empty() && !d.is_empty() => {
                return Err(Error::invalid(
                    "dataset",
                    "dataset",
                    format!("\"{d}\" with filename \"{f}\""),
                    "one of filename or dataset",
                ))
            }
            (f, d) => {
                if f.is_empty() {
                    d
                } else {
                    f
                }
            }
        };
        let densityfile = r.string("densityfile")?;
        let temperaturefile = r.string("temperaturefile")?;
        let dfile = if !densityfile.is_empty() {
            densityfile
        } else {
            filename.clone()
        };
        if dfile.is_empty() {
            return Err(Error::invalid("dataset", "filename", "unset", "a dataset file (filename or densityfile), or inline \"float density\" with nx ny nz"));
        }
        let mut sources = vec![ChannelSource {
            name: "density".into(),
            file: dfile.clone().into(),
            grid: Some(r.string("densitygrid")?),
            mapping: Mapping::default(),
        }];
        let tgrid = r.string("temperaturegrid")?;
        let tfile = if !temperaturefile.is_empty() {
            temperaturefile
        } else {
            filename.clone()
        };
        let single = matches!(
            opts.format
                .or_else(|| Format::from_extension(std::path::Path::new(&tfile))),
            Some(Format::AsciiDense | Format::AsciiSparse | Format::Raw | Format::Raw2)
        );
        // A single-grid file cannot hold temperature too: without a temperature file there is none.
        let no_temperature = tgrid.is_empty() || (single && tfile == dfile);
        if !no_temperature {
            sources.push(ChannelSource {
                name: "temperature".into(),
                file: tfile.into(),
                grid: Some(tgrid),
                mapping: tmap,
            });
        }
        let sfiles = r.strings("speciesfiles")?.unwrap_or_default();
        for (i, sym) in species.iter().enumerate() {
            let file = sfiles.get(i).cloned().unwrap_or_else(|| filename.clone());
            sources.push(ChannelSource {
                name: sym.clone(),
                file: file.into(),
                grid: Some(sym.clone()),
                mapping: Mapping::default(),
            });
        }
        if lescale_values.as_ref().is_some_and(|v| v.len() > 1) {
            return Err(Error::invalid(
                "volume",
                "Lescale",
                "an array",
                "one value for file datasets (arrays are for inline grids)",
            ));
        }
        (Dataset::load(&sources, &opts)?, None)
    };
    ds = ds.with_interpolation(interp);
    Ok((ds, lescale))
}

fn build_species(
    r: &ParamReader,
    ds: &Dataset,
    basis: &Basis,
    t_max: f64,
    intensity: f64,
    tables: &mut Vec<TableReport>,
) -> Result<Vec<SpeciesChannel>, Error> {
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
    let fine = SpectralGrid::new(380.0, 780.0, 400).unwrap_or_default();
    let fine_w: Vec<DVec3> = (0..400)
        .map(|i| cie::cmf_integral(380.0 + i as f64, 381.0 + i as f64))
        .collect();
    let mut out = Vec::new();
    for (i, sym) in syms.iter().enumerate() {
        let e = Element::by_symbol(sym)?;
        let ch = ds
            .channels()
            .iter()
            .position(|c| &c.name == sym)
            .unwrap_or(0);
        let t0 = Instant::now();
        let c = basis.channels();
        let (e1, b1, fw1) = (e.clone(), basis.clone(), fine_w.clone());
        let sigma = TTable::build(t_max, c, &move |t| b1.lines(&e1, t, &fine, &fw1).0);
        let (e2, b2, fw2) = (e.clone(), basis.clone(), fine_w.clone());
        let j = TTable::build(t_max, c, &move |t| {
            b2.lines(&e2, t, &fine, &fw2)
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
        out.push(SpeciesChannel {
            ch,
            scale: scales.get(i).copied().unwrap_or(scales[0]),
            sigma,
            j,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::params::Param;

    fn slab_volume(d: f64, t: f64, extra: Vec<Param>) -> FireVolume {
        // A 4×4×4 constant grid over [0, 1]³, nearest lookup: exactly homogeneous inside the box.
        let n = 64;
        let mut list = vec![
            Param::floats("density", &vec![d; n]),
            Param::floats("temperature", &vec![t; n]),
            Param::int("nx", 4),
            Param::int("ny", 4),
            Param::int("nz", 4),
            Param::string("interpolation", "nearest"),
        ];
        list.extend(extra);
        FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"))
    }

    fn ray_x(seed: u64) -> Ray {
        Ray {
            o: DVec3::new(-0.5, 0.5, 0.5),
            d: DVec3::X,
            t0: 0.0,
            t1: 3.0,
            seed,
        }
    }

    fn run(v: &FireVolume, ray: &Ray) -> (Vec<f64>, Vec<f64>) {
        let c = v.channels();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        v.integrate(ray, &mut l, &mut t);
        (l, t)
    }

    #[test]
    fn voxel_slab_matches_closed_form_across_optical_depth() {
        // Through 1 m of homogeneous soot at 1800 K: L_c = (j_c/σ_c)(1 − e^{−σ_c}), τ from ~1e-4 to ~50; the
        // transmittance to 1e-9 in f64, to f32's 2e-7 in lanes.
        for (fv, precision) in [1e-11, 1e-9, 1e-7, 3e-6, 5e-6]
            .into_iter()
            .flat_map(|fv| [(fv, "f64"), (fv, "f32")])
        {
            let extra = vec![
                Param::float("alpha", 1.0),
                Param::string("precision", precision),
            ];
            let v = slab_volume(fv, 1800.0, extra);
            assert_eq!(v.lanes.is_some(), precision == "f32");
            let ttol = if precision == "f32" { 4e-7 } else { 1e-9 };
            let c = v.channels();
            let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
            v.coefficients(DVec3::splat(0.5), &mut sa, &mut ss, &mut j);
            let (l, t) = run(&v, &ray_x(1));
            for k in 0..c {
                let tau = sa[k];
                let want = j[k] / sa[k] * -(-tau).exp_m1();
                assert!(
                    ((l[k] - want) / want).abs() < 1e-3,
                    "fv={fv} ch {k}: {} vs {want} (τ={tau})",
                    l[k]
                );
                // The march stops once every channel is below the 1e-6 cutoff.
                let tw = (-tau).exp();
                assert!(
                    (t[k] - tw).abs() < ttol * tw || (t[k] <= 1e-6 && tw < 1e-6),
                    "ch {k}: T {} vs {tw}",
                    t[k]
                );
                // Kirchhoff per bin: j/σ is the bin's blackbody radiance (to the variation of κ over 10 nm).
                let lam = 405.0 + 10.0 * k as f64;
                let b = crate::blackbody::spectral_radiance(1800.0, lam);
                assert!(
                    ((j[k] / sa[k]) / b - 1.0).abs() < 5e-3,
                    "ch {k}: {} vs B {b}",
                    j[k] / sa[k]
                );
            }
            let tau550 = sa[15];
            assert!(tau550 > 0.5e-4 && tau550 < 60.0);
        }
    }

    #[test]
    fn rgb_soot_rows_in_one_pass_equal_two() {
        // The absorption (Planck-mean per band) and emission rows from one Planck evaluation per wavelength,
        // against each formula evaluated on its own, bit for bit; and the split table holds each.
        let basis = Basis {
            mode: ColorMode::Rgb,
            k: 683.0,
        };
        let optics = SootOptics::propane();
        let nodes = basis.nodes();
        let f: Vec<f64> = (0..CMF.len())
            .map(|i| 3e-7 * optics.kappa(380.0 + i as f64, 1.0, 1.39))
            .collect();
        let g: Vec<f64> = nodes
            .lambda
            .iter()
            .map(|&l| 2.0 * 3e-7 * optics.kappa(l, 1.0, 1.39))
            .collect();
        let fallback = [1.0, 2.0, 3.0];
        for t in [0.0, 1.0, 300.0, 900.0, 1675.0, 3000.0, 1e5] {
            let row = basis.soot_rgb_rows(&nodes, &g, &f, &fallback, t);
            let (mut num, mut den) = ([0.0; 3], [0.0; 3]);
            for (i, w) in CMF.iter().enumerate() {
                let b = spectral_radiance(t, 380.0 + i as f64);
                for c in 0..3 {
                    num[c] += f[i] * b * w[c];
                    den[c] += b * w[c];
                }
            }
            let absorb: Vec<f64> = if den.iter().all(|&d| d > 0.0) {
                (0..3).map(|c| num[c] / den[c]).collect()
            } else {
                fallback.to_vec()
            };
            let emit = basis.emit_planck(&nodes, &g, t);
            assert_eq!(&row[..3], &absorb[..], "absorption at {t} K");
            assert_eq!(&row[3..], &emit[..], "emission at {t} K");
        }
        let both = TTable::build(2000.0, 6, &|t| {
            basis.soot_rgb_rows(&nodes, &g, &f, &fallback, t)
        });
        let (a, j) = both.split(3);
        for r in [0, 1, 1000, both.rows - 1] {
            for c in 0..3 {
                assert_eq!(a.value(r, c), both.value(r, c));
                assert_eq!(j.value(r, c), both.value(r, c + 3));
            }
        }
    }

    #[test]
    fn range_maxima_equal_the_row_scan() {
        // The sparse table against a scan of the rows (what the bricks did before): random and edge ranges, inside and past the table,
        // empty (lo > hi) and NaN ranges, every channel — the same f32 bit for bit.
        let tab = TTable::build(2000.0, 5, &|t| {
            (0..5)
                .map(|c| ((t * 0.01 + c as f64).sin() + 1.0) * (1.0 + t / 500.0))
                .collect()
        });
        let m = RangeMax::new(&tab, 5);
        let mut rng = crate::rng::Rng::new(3);
        let mut ranges = vec![
            (0.0, 0.0),
            (0.0, 2000.0),
            (-50.0, 3000.0),
            (1999.9, 2000.0),
            (700.0, 700.0),
            (800.0, 700.0),
            (f64::NAN, 900.0),
        ];
        for _ in 0..2000 {
            let (x, y) = (
                rng.next_f64() * 2200.0 - 100.0,
                rng.next_f64() * 2200.0 - 100.0,
            );
            ranges.push((x.min(y), x.max(y)));
        }
        let scan = |lo: f64, hi: f64, c: usize| {
            let a = (lo / tab.dt).floor().clamp(0.0, (tab.rows - 1) as f64) as usize;
            let b = (hi / tab.dt).ceil().clamp(0.0, (tab.rows - 1) as f64) as usize;
            (a..=b).map(|r| tab.value(r, c)).fold(0.0, f32::max)
        };
        for (lo, hi) in ranges {
            for ch in 0..5 {
                assert_eq!(
                    m.max_over(lo, hi, ch).to_bits(),
                    scan(lo, hi, ch).to_bits(),
                    "[{lo}, {hi}] ch {ch}"
                );
            }
        }
    }

    #[test]
    fn soot_bin_means_are_split_at_the_optical_constants_kinks() {
        // κ(λ) of soot is smooth between the Dalzell & Sarofim wavelengths (n, k linear there; kinks at 435.8,
        // 450, 550, 650 nm). Bin means of κ·B by one 8-node panel per smooth piece against 64 panels per piece:
        // equal to rounding, while four panels across the 435.8 nm kink (bin 430–440 nm) are off by more than
        // 1e-6 — the rule the soot tables use, with a quarter of the nodes (the emission table's build time).
        let grid = SpectralGrid::default();
        let basis = Basis {
            mode: ColorMode::Spectral(grid),
            k: 683.0,
        };
        for optics in [SootOptics::propane(), SootOptics::acetylene()] {
            let kinks: Vec<f64> = optics.rows().iter().map(|r| r[0]).collect();
            let nodes = basis.nodes_split(&kinks);
            assert_eq!(nodes.lambda.len(), 30 * 8 + 8, "one bin cut in two");
            let kap: Vec<f64> = nodes
                .lambda
                .iter()
                .map(|&l| optics.kappa(l, 1.0, 1.39))
                .collect();
            let mut four_worst = 0f64;
            for t in [300.0, 1000.0, 1800.0, 3000.0, 1e5] {
                let f = |l: f64| optics.kappa(l, 1.0, 1.39) * spectral_radiance(t, l);
                let fast = basis.emit_planck(&nodes, &kap, t);
                let reference = grid.bin_average_split(f, &kinks, 64);
                let four = grid.bin_average(f);
                assert_bins_agree(&fast, &reference, &format!("T {t}"));
                for c in 0..30 {
                    four_worst = four_worst.max((four[c] / reference[c] - 1.0).abs());
                }
                let a = basis.absorb_split(&|l| optics.kappa(l, 1.0, 1.39), &kinks);
                let a_ref = grid.bin_average_split(|l| optics.kappa(l, 1.0, 1.39), &kinks, 64);
                assert_bins_agree(&a, &a_ref, "κ");
            }
            assert!(
                four_worst > 1e-6,
                "four panels across the kink: {four_worst:e}"
            );
        }
    }

    /// Every channel of `got` within 1e-12 (relative) of `want`, the same number of channels.
    fn assert_bins_agree(got: &[f64], want: &[f64], what: &str) {
        assert_eq!(got.len(), want.len(), "{what}");
        for (c, (g, w)) in got.iter().zip(want).enumerate() {
            let e = (g / w - 1.0).abs();
            assert!(e < 1e-12, "{what}, bin {c}: {g} vs {w} ({e:e})");
        }
    }

    #[test]
    fn table_nodes_match_the_bin_means() {
        // The tables' node sums against emit's bin means, for soot κ × Planck from 300 K to 1e5 K, 30 and 5 bins.
        for bins in [30, 5, 0] {
            let mode = match bins {
                0 => ColorMode::Rgb,
                n => ColorMode::Spectral(SpectralGrid::new(400.0, 750.0, n).unwrap()),
            };
            let basis = Basis { mode, k: 683.0 };
            let bins = basis.channels();
            let nodes = basis.nodes();
            let optics = SootOptics::propane();
            let kap: Vec<f64> = nodes
                .lambda
                .iter()
                .map(|&l| optics.kappa(l, 1.0, 1.39))
                .collect();
            for t in [300.0, 1000.0, 1800.0, 3000.0, 1e5] {
                let fast = basis.emit_planck(&nodes, &kap, t);
                let slow = basis.emit(&|l| optics.kappa(l, 1.0, 1.39) * spectral_radiance(t, l));
                assert_bins_agree(&fast, &slow, &format!("{bins} bins, T {t}"));
            }
        }
    }

    #[test]
    fn f32_lanes_only_where_every_product_fits() {
        // An everyday fire marches in lanes; a density of 1e35 (σ·step ≈ 1e41, past f32's 3.4e38) and the
        // tracking integrators do not — and the opaque slab still gives L = B.
        assert!(slab_volume(1e-6, 1500.0, vec![]).lanes.is_some());
        let huge = slab_volume(1e35, 1500.0, vec![Param::float("sootscale", 1.0)]);
        assert!(huge.lanes.is_none());
        let (l, t) = run(&huge, &ray_x(1));
        let b = crate::blackbody::spectral_radiance(1500.0, 555.0);
        assert!(
            (l[15] / b - 1.0).abs() < 5e-3 && t[15] == 0.0,
            "{} vs {b}",
            l[15]
        );
        let ratio = slab_volume(1e-6, 1500.0, vec![Param::string("integrator", "ratio")]);
        assert!(ratio.lanes.is_none());
        let f64_asked = slab_volume(1e-6, 1500.0, vec![Param::string("precision", "f64")]);
        assert!(f64_asked.lanes.is_none());
        // A 1e12 × intensity fire at 3000 K (emission per unit density ~1e23) still marches in lanes, 1e12 × the f64 one.
        let bright = slab_volume(
            1e-6,
            3000.0,
            vec![
                Param::float("intensity", 1e12),
                Param::string("precision", "f32"),
            ],
        );
        assert!(bright.lanes.is_some());
        let dim = slab_volume(1e-6, 3000.0, vec![Param::string("precision", "f64")]);
        let (lb, _) = run(&bright, &ray_x(1));
        let (ld, _) = run(&dim, &ray_x(1));
        for k in 0..lb.len() {
            assert!(
                (lb[k] / (ld[k] * 1e12) - 1.0).abs() < 1e-5,
                "ch {k}: {} vs {}",
                lb[k],
                ld[k] * 1e12
            );
        }
    }

    #[test]
    fn tracking_agrees_with_march_within_three_sigma() {
        for fv in [1e-8, 1e-6] {
            let march = slab_volume(fv, 1600.0, vec![]);
            let (lm, tm) = run(&march, &ray_x(0));
            for how in ["ratio", "delta"] {
                let v = slab_volume(fv, 1600.0, vec![Param::string("integrator", how)]);
                let n = 3000;
                let c = 15; // 550–560 nm
                let (mut s, mut s2, mut st, mut st2) = (0.0, 0.0, 0.0, 0.0);
                for seed in 0..n {
                    let (l, t) = run(&v, &ray_x(seed));
                    s += l[c];
                    s2 += l[c] * l[c];
                    st += t[c];
                    st2 += t[c] * t[c];
                }
                let nf = n as f64;
                let (m, mt) = (s / nf, st / nf);
                let se = ((s2 / nf - m * m).max(0.0) / nf).sqrt();
                // Delta's transmittance is 0 or a weight per sample: at least the Bernoulli σ.
                let set = ((st2 / nf - mt * mt).max(0.0) / nf)
                    .sqrt()
                    .max((tm[c] * (1.0 - tm[c]) / nf).sqrt());
                assert!(
                    (m - lm[c]).abs() <= 3.0 * se + 1e-9 * lm[c],
                    "{how} fv={fv}: {m} ± {se} vs {}",
                    lm[c]
                );
                assert!(
                    (mt - tm[c]).abs() <= 3.0 * set + 1e-9,
                    "{how} fv={fv}: T {mt} ± {set} vs {}",
                    tm[c]
                );
            }
        }
    }

    #[test]
    fn spectral_and_rgb_agree_on_luminance_and_differ_documentedly() {
        // The same 1 m of soot at 1700 K in both modes, compared in XYZ.
        let to_xyz = |v: &FireVolume, l: &[f64]| {
            v.channel_xyz()
                .iter()
                .zip(l)
                .map(|(w, x)| *w * *x)
                .sum::<DVec3>()
        };
        for fv in [1e-8, 1e-6, 5e-6] {
            let sp = slab_volume(
                fv,
                1700.0,
                vec![
                    Param::float("lambdamin", 380.0),
                    Param::float("lambdamax", 780.0),
                    Param::int("bins", 40),
                ],
            );
            let rgb = slab_volume(fv, 1700.0, vec![Param::string("colormode", "rgb")]);
            let (a, b) = (
                to_xyz(&sp, &run(&sp, &ray_x(0)).0),
                to_xyz(&rgb, &run(&rgb, &ray_x(0)).0),
            );
            let rel = (a - b).abs() / a;
            // Measured (docs/RESULTS.md): ≤ 4.9e-3 in every channel, thin to opaque, with the rgb bands'
            // Planck-mean absorption (a plain band mean gave 9.3e-2 in X when opaque).
            assert!(
                rel.is_finite() && rel.max_element() < 1e-2,
                "fv={fv}: spectral {a} rgb {b} ({rel})"
            );
            eprintln!(
                "spectral vs rgb, f_v = {fv:e}: XYZ relative difference ({:.2e}, {:.2e}, {:.2e})",
                rel.x, rel.y, rel.z
            );
        }
    }

    #[test]
    fn pbrt_mode_is_sigma_times_density_and_normalised_blackbody() {
        let v = slab_volume(
            2.0,
            1500.0,
            vec![
                Param::string("mode", "pbrt"),
                Param::spectrum("sigma_a", &[0.5]),
                Param::float("scale", 0.75),
                Param::float("Lescale", 3.0),
            ],
        );
        let (l, t) = run(&v, &ray_x(0));
        let tau: f64 = 2.0 * 0.5 * 0.75;
        let peak = crate::blackbody::spectral_radiance(1500.0, WIEN / 1500.0 * 1e9);
        for k in [0, 15, 29] {
            let lam0 = 400.0 + 10.0 * k as f64;
            let bn = crate::quadrature::gauss_legendre(
                |x| crate::blackbody::spectral_radiance(1500.0, x) / peak,
                lam0,
                lam0 + 10.0,
                4,
            ) / 10.0;
            let want = 3.0 * bn * -(-tau).exp_m1();
            assert!(
                ((l[k] - want) / want).abs() < 1e-4,
                "ch {k}: {} vs {want}",
                l[k]
            );
            assert!((t[k] - (-tau).exp()).abs() < 1e-6);
        }
        // Below 100 K pbrt emits nothing.
        let cold = slab_volume(2.0, 90.0, vec![Param::string("mode", "pbrt")]);
        assert!(run(&cold, &ray_x(0)).0.iter().all(|&x| x == 0.0));
        // A pbrt-style spectrum of pairs: [200 10 900 10] is the constant 10.
        let v = slab_volume(
            1.0,
            0.0,
            vec![
                Param::string("mode", "pbrt"),
                Param::spectrum("sigma_a", &[200.0, 10.0, 900.0, 10.0]),
            ],
        );
        assert!((run(&v, &ray_x(0)).1[3] - (-10.0f64).exp()).abs() < 1e-9);
    }

    /// A trilinear 40×36×44 grid over [0, 2] × [0, 1.8] × [0, 2.2] with a hot blob in one corner and a slab on
    /// the far x side (so many bricks are empty) and `extra` parameters (pbrt mode adds a Lescale grid); `species` adds a sodium grid
    /// (files: species grids are not inline parameters).
    /// The blob volume with `extra` parameters in the lanes' precision (the default) and in f64.
    fn blob_pair(extra: &[Param], species: bool) -> (FireVolume, FireVolume) {
        let mut e64 = extra.to_vec();
        e64.push(Param::string("precision", "f64"));
        (
            blob_volume(extra.to_vec(), species),
            blob_volume(e64, species),
        )
    }

    fn blob_volume(extra: Vec<Param>, species: bool) -> FireVolume {
        let [nx, ny, nz] = [40usize, 36, 44];
        let (mut d, mut t, mut les, mut na) = (vec![], vec![], vec![], vec![]);
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let p = DVec3::new(
                        i as f64 / nx as f64,
                        j as f64 / ny as f64,
                        k as f64 / nz as f64,
                    );
                    let r2 = (p - DVec3::new(0.3, 0.35, 0.25)).length_squared() / 0.04;
                    let w = if r2 < 1.0 { (1.0 - r2).powi(2) } else { 0.0 };
                    // And a hot slab with a sharp face, right after empty bricks along x.
                    let slab = if i >= 27 { 1.0 } else { 0.0 };
                    d.push(3e-6 * w + 1e-6 * slab);
                    t.push(300.0 + 1700.0 * w + 1200.0 * slab);
                    les.push(0.5 + p.x);
                    na.push(w * (1.0 - p.z));
                }
            }
        }
        let mut list = vec![
            Param::point3("p0", [0.0, 0.0, 0.0]),
            Param::point3("p1", [2.0, 1.8, 2.2]),
        ];
        if species {
            let dir =
                std::env::temp_dir().join(format!("firemedium-kernel-{}", std::process::id()));
            std::fs::create_dir_all(&dir).unwrap();
            let f = |name: &str, v: &[f64]| {
                let p = dir.join(name);
                let body: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                std::fs::write(&p, format!("{nx} {ny} {nz}\n{}\n", body.join(" "))).unwrap();
                p.display().to_string()
            };
            list.extend([
                Param::string("densityfile", &f("d.txt", &d)),
                Param::string("temperaturefile", &f("t.txt", &t)),
                Param::strings("species", &["Na"]),
                Param::strings("speciesfiles", &[&f("na.txt", &na)]),
                Param::float("speciesscale", 1e15),
            ]);
        } else {
            if extra.iter().any(|p| p.name == "mode") {
                // (pbrt mode: σ_a per unit density, and a per-voxel emission scale.)
                list.extend([
                    Param::floats("Lescale", &les),
                    Param::spectrum("sigma_a", &[200.0, 2e5, 900.0, 3e5]),
                ]);
            }
            list.extend([
                Param::floats("density", &d),
                Param::floats("temperature", &t),
                Param::int("nx", nx as i64),
                Param::int("ny", ny as i64),
                Param::int("nz", nz as i64),
            ]);
        }
        list.extend(extra);
        FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"))
    }

    #[test]
    fn kernel_matches_the_lane_and_f64_marches() {
        // The kernel (`integrate` with lanes) against the lane march it replaces (same f32 arithmetic, per
        // sample) and the f64 march: random rays from outside and inside, along axes, through faces and
        // edges, and through the empty bricks the kernel jumps; rgb and spectral; with Lescale, with species.
        let mut rng = crate::rng::Rng::new(7);
        let mut rays = vec![
            Ray {
                o: DVec3::new(-1.0, 0.63, 0.55),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 1,
            },
            Ray {
                o: DVec3::new(0.6, 0.63, -1.0),
                d: DVec3::Z,
                t0: 0.0,
                t1: 9.0,
                seed: 2,
            },
            Ray {
                o: DVec3::new(0.6, 0.63, 0.55),
                d: DVec3::new(0.3, -1.0, 0.2),
                t0: 0.0,
                t1: 9.0,
                seed: 3,
            },
            Ray {
                o: DVec3::new(-1.0, 0.0, 0.5),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 4,
            }, // in a face
            Ray {
                o: DVec3::new(-1.0, 0.0, 0.0),
                d: DVec3::X,
                t0: 0.0,
                t1: 9.0,
                seed: 5,
            }, // along an edge
            Ray {
                o: DVec3::new(3.0, 0.6, 0.5),
                d: DVec3::new(-2.0, 0.0, 0.0),
                t0: 0.0,
                t1: 9.0,
                seed: 6,
            },
        ];
        for seed in 0..150 {
            let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 1.0;
            let target = DVec3::new(0.6, 0.63, 0.55)
                + (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5) * 1.2;
            rays.push(Ray {
                o,
                d: target - o,
                t0: 0.0,
                t1: 5.0,
                seed: 100 + seed,
            });
        }
        for (extra, species) in [
            (vec![], false),
            (vec![Param::string("colormode", "rgb")], false),
            (
                vec![
                    Param::string("mode", "pbrt"),
                    Param::float("stepsize", 3.0),
                    Param::int("brick", 4),
                ],
                false,
            ),
            (vec![Param::float("stepsize", 0.37)], true),
        ] {
            let (v, v64) = blob_pair(&extra, species);
            let lt = v.lanes.as_ref().expect("the blob marches in lanes");
            let c = v.channels();
            let (mut worst, mut lit) = (0f64, 0);
            for ray in &rays {
                let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                let (mut l2, mut t2) = (vec![0.0; c], vec![0.0; c]);
                let (mut l3, mut t3) = (vec![0.0; c], vec![0.0; c]);
                let te = v.integrate(ray, &mut l, &mut t);
                let te2 = march_lanes(&v, lt, ray, &mut l2, &mut t2);
                let te3 = v64.integrate(ray, &mut l3, &mut t3);
                assert_eq!(te, te2);
                assert_eq!(te, te3);
                let peak = l3.iter().fold(0f64, |m, &x| m.max(x));
                if peak > 0.0 {
                    lit += 1;
                }
                for k in 0..c {
                    for (a, what) in [(l[k], "lane march"), (l3[k], "f64 march")] {
                        // Relative to the ray's brightest channel (dim channels carry f32's absolute rounding).
                        let e = (l[k] - a).abs() / peak.max(1e-300);
                        worst = worst.max(e);
                        assert!(e < 2e-5, "{ray:?} ch {k}: kernel {} vs {what} {a}", l[k]);
                    }
                    assert!((t[k] - t2[k]).abs() < 1e-5 && (t[k] - t3[k]).abs() < 1e-5);
                }
            }
            assert!(lit > 50, "only {lit} rays saw the fire");
            assert!(
                worst > 0.0,
                "f32 and f64 cannot agree to the bit everywhere"
            );
        }
    }

    #[test]
    fn every_lane_shape_matches_the_f64_march() {
        // The dispatch picks one lane shape per channel count and CPU (this machine's clone runs only some):
        // each shape called directly, with and without FMA, against the f64 march — rgb in one lane of 4,
        // 6/12/20/30 bins in lanes of 8 and of 16, with sodium where it applies.
        let rays: Vec<Ray> = (0..40)
            .map(|k| {
                let mut rng = crate::rng::Rng::new(900 + k);
                let o = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 4.0 - 1.0;
                let target = DVec3::new(0.6, 0.63, 0.55)
                    + (DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5);
                Ray {
                    o,
                    d: target - o,
                    t0: 0.0,
                    t1: 5.0,
                    seed: k,
                }
            })
            .collect();
        type Kernel =
            fn(&FireVolume, &lanes::LaneTables, &Ray, &mut [f64], &mut [f64]) -> Option<f64>;
        // (The volume's extra parameters, with sodium, and the shapes to run on it.)
        type Case = (Vec<Param>, bool, Vec<(&'static str, Kernel)>);
        let cases: Vec<Case> = vec![
            (
                vec![Param::string("colormode", "rgb")],
                false,
                vec![
                    ("1×4", kernel::march::<1, 4, false, true, false>),
                    ("1×4 fma", kernel::march::<1, 4, false, true, true>),
                ],
            ),
            (
                vec![Param::string("colormode", "rgb")],
                true,
                vec![("1×4 Na", kernel::march::<1, 4, true, true, true>)],
            ),
            (
                vec![Param::int("bins", 6)],
                false,
                vec![("1×8", kernel::march::<1, 8, false, false, true>)],
            ),
            (
                vec![Param::int("bins", 12)],
                false,
                vec![
                    ("2×8", kernel::march::<2, 8, false, false, true>),
                    ("1×16", kernel::march::<1, 16, false, false, true>),
                ],
            ),
            (
                vec![Param::int("bins", 20)],
                false,
                vec![("3×8", kernel::march::<3, 8, false, false, false>)],
            ),
            (
                vec![],
                false,
                vec![
                    ("4×8", kernel::march::<4, 8, false, false, true>),
                    ("4×8 no fma", kernel::march::<4, 8, false, false, false>),
                    ("2×16", kernel::march::<2, 16, false, false, true>),
                ],
            ),
            (
                vec![],
                true,
                vec![
                    ("4×8 Na", kernel::march::<4, 8, true, false, true>),
                    ("2×16 Na", kernel::march::<2, 16, true, false, true>),
                ],
            ),
        ];
        for (extra, species, kernels) in cases {
            let (v, v64) = blob_pair(&extra, species);
            let lt = v.lanes.as_ref().expect("the blob marches in lanes");
            let c = v.channels();
            for (name, kernel) in kernels {
                let mut lit = 0;
                for ray in &rays {
                    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                    let (mut l3, mut t3) = (vec![0.0; c], vec![0.0; c]);
                    let te = kernel(&v, lt, ray, &mut l, &mut t).expect("this shape fits");
                    let te3 = v64.integrate(ray, &mut l3, &mut t3);
                    assert_eq!(te, te3, "{name}");
                    let peak = l3.iter().fold(0f64, |m, &x| m.max(x));
                    lit += (peak > 0.0) as usize;
                    for k in 0..c {
                        let e = (l[k] - l3[k]).abs() / peak.max(1e-300);
                        assert!(e < 2e-5, "{name}, {ray:?} ch {k}: {} vs {}", l[k], l3[k]);
                        assert!((t[k] - t3[k]).abs() < 1e-5, "{name} ch {k}");
                    }
                }
                assert!(lit > 10, "{name}: only {lit} rays saw the fire");
            }
        }
    }

    #[test]
    fn sodium_flame_glows_at_589() {
        let n = 64;
        let list = vec![
            Param::floats("density", &vec![0.0; n]),
            Param::floats("temperature", &vec![2000.0; n]),
            Param::int("nx", 4),
            Param::int("ny", 4),
            Param::int("nz", 4),
            Param::string("interpolation", "nearest"),
            Param::strings("species", &["Na"]),
        ];
        // Species grids come from files or the dataset; inline species are not a pbrt concept, so use a file.
        let dir = std::env::temp_dir().join(format!("firemedium-vol-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let f = |name: &str, v: f64| {
            let p = dir.join(name);
            let body: Vec<String> = (0..n).map(|_| v.to_string()).collect();
            std::fs::write(&p, format!("4 4 4\n{}\n", body.join(" "))).unwrap();
            p.display().to_string()
        };
        let list2 = vec![
            Param::string("densityfile", &f("d.txt", 0.0)),
            Param::string("temperaturefile", &f("t.txt", 2000.0)),
            Param::strings("species", &["Na"]),
            Param::strings("speciesfiles", &[&f("na.txt", 1.0)]),
            Param::float("speciesscale", 1e16),
            Param::string("interpolation", "nearest"),
        ];
        let _ = list;
        let v = FireVolume::new(&list2).unwrap_or_else(|e| panic!("{e}"));
        let (l, t) = run(&v, &ray_x(0));
        let brightest = (0..30).max_by(|&a, &b| l[a].total_cmp(&l[b])).unwrap();
        assert_eq!(brightest, 18, "{l:?}");
        assert!(l[18] > 0.0 && t[18] < 1.0 && t[0] == 1.0);
        // Kirchhoff in the 589 bin: L ≤ B(2000 K, 589 nm) and → B as N grows.
        let b = crate::blackbody::spectral_radiance(2000.0, 589.0);
        assert!(l[18] < b);
    }

    #[test]
    fn extremes_are_finite() {
        for (d, t) in [
            (0.0, 0.0),
            (1e-30, 1.0),
            (1e30, 1e6),
            (1.0, 1e6),
            (1e-3, 0.0),
            (3e38, 300.0),
        ] {
            for how in ["march", "ratio", "delta"] {
                let v = slab_volume(d, t, vec![Param::string("integrator", how)]);
                for ray in [
                    ray_x(5),
                    Ray {
                        o: DVec3::new(0.5, 0.5, 0.5),
                        d: DVec3::Z,
                        t0: 0.0,
                        t1: 10.0,
                        seed: 1,
                    }, // starts inside
                    Ray {
                        o: DVec3::new(-1.0, 0.0, 0.0),
                        d: DVec3::X,
                        t0: 0.0,
                        t1: 10.0,
                        seed: 2,
                    }, // along an edge
                    Ray {
                        o: DVec3::new(-1.0, 0.5, 1.0),
                        d: DVec3::X,
                        t0: 0.0,
                        t1: 10.0,
                        seed: 3,
                    }, // in a face
                    Ray {
                        o: DVec3::new(-1.0, 2.0, 0.5),
                        d: DVec3::X,
                        t0: 0.0,
                        t1: 10.0,
                        seed: 4,
                    }, // misses
                    Ray {
                        o: DVec3::new(0.5, 0.5, 0.5),
                        d: DVec3::new(1e-300, 0.0, 0.0),
                        t0: 0.0,
                        t1: 1.0,
                        seed: 5,
                    },
                ] {
                    let (l, tr) = run(&v, &ray);
                    assert!(
                        l.iter().all(|x| x.is_finite() && *x >= 0.0),
                        "d={d} T={t} {how} {ray:?}: {l:?}"
                    );
                    assert!(
                        tr.iter().all(|x| (0.0..=1.0).contains(x)),
                        "d={d} T={t} {how}: {tr:?}"
                    );
                }
            }
        }
        // Opaque at 1e6 K: radiance → the blackbody's bin mean.
        let v = slab_volume(1e30, 1e6, vec![]);
        let (l, _) = run(&v, &ray_x(0));
        let b = crate::blackbody::spectral_radiance(1e6, 555.0);
        assert!((l[15] / b - 1.0).abs() < 1e-2, "{} vs {b}", l[15]);
    }

    #[test]
    fn parameter_errors_suggest_and_explain() {
        let base = || {
            vec![
                Param::floats("density", &[1.0]),
                Param::floats("temperature", &[1000.0]),
            ]
        };
        let mut l = base();
        l.push(Param::float("stepsise", 0.5));
        assert_eq!(FireVolume::new(&l).unwrap_err().to_string(), "volume: parameter 'stepsise' = unknown: expected a known parameter (did you mean 'stepsize'?)");
        let mut l = base();
        l.push(Param::spectrum("sigma_a", &[1.0]));
        assert!(FireVolume::new(&l)
            .unwrap_err()
            .to_string()
            .contains("mode \"pbrt\""));
        let mut l = base();
        l.push(Param::string("colormode", "hsv"));
        assert!(FireVolume::new(&l)
            .unwrap_err()
            .to_string()
            .contains("one of spectral, rgb"));
        let mut l = base();
        l.push(Param::float("lambdamax", 300.0));
        assert!(FireVolume::new(&l)
            .unwrap_err()
            .to_string()
            .contains("lambdamax"));
        assert!(FireVolume::new(&[])
            .unwrap_err()
            .to_string()
            .contains("filename"));
    }

    #[test]
    fn pbrt_nanovdb_clips_to_nanovdbs_world_box() {
        // ramp16.nvdb: NanoVDB's world box is [-0.46875, 0.53125]³ (index 0 → its centre, index 16 → +1 voxel).
        let f = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/valid/nvdb/ramp16.nvdb"
        );
        let v = FireVolume::new(&[
            Param::string("filename", f),
            Param::string("mode", "pbrt"),
            Param::spectrum("sigma_a", &[1e-4]),
        ])
        .unwrap();
        let [p0, p1] = v.bounds();
        assert!(
            (p0 - DVec3::splat(-0.46875)).abs().max_element() < 1e-12
                && (p1 - DVec3::splat(0.53125)).abs().max_element() < 1e-12,
            "{p0} {p1}"
        );
        let c = v.channels();
        let (mut a, mut s2, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        // A quarter voxel beyond the last centre along x (index 15.25): trilinear toward the background 0.
        let x = -0.46875 + 15.25 / 16.0;
        let y = -0.46875 + 3.0 / 16.0;
        v.coefficients(DVec3::new(x, y, y), &mut a, &mut s2, &mut j);
        let want = 1e-4 * 0.75 * (15.0 + 16.0 * 3.0 + 256.0 * 3.0);
        assert!((a[0] - want).abs() < 1e-9, "{} vs {want}", a[0]);
        // Outside NanoVDB's box: nothing.
        v.coefficients(DVec3::new(0.6, y, y), &mut a, &mut s2, &mut j);
        assert_eq!(a[0], 0.0);
        // A ray through the whole box matches a march over the same coefficients (tracking agrees too).
        let ray = Ray {
            o: DVec3::new(-1.0, y, y),
            d: DVec3::X,
            t0: 0.0,
            t1: 3.0,
            seed: 4,
        };
        let (l, t) = run(&v, &ray);
        assert!(l.iter().all(|x| x.is_finite()) && t[0] < 1.0 && t[0] > 0.0);
    }

    #[test]
    fn builds_from_the_mantaflow_fire() {
        let f = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../tests/data/valid/vdb/mantaflow_fire_f060.vdb"
        );
        let v = FireVolume::new(&[
            Param::string("filename", f),
            Param::float("temperaturescale", 1000.0),
            Param::float("sootscale", 1e-6),
        ])
        .unwrap();
        assert_eq!(v.dataset().channels().len(), 2);
        assert!(v
            .tables()
            .iter()
            .any(|t| t.name == "soot emission" && t.bytes > 0));
        // A ray up the middle of the fire: finite, positive, some absorption.
        let [p0, p1] = v.bounds();
        let mid = (p0 + p1) * 0.5;
        let (l, t) = run(
            &v,
            &Ray {
                o: DVec3::new(mid.x, p0.y - 1.0, 0.5),
                d: DVec3::Y,
                t0: 0.0,
                t1: 10.0,
                seed: 9,
            },
        );
        assert!(
            l.iter().all(|x| x.is_finite() && *x >= 0.0) && l[29] > 0.0,
            "{l:?}"
        );
        assert!(t.iter().all(|x| (0.0..1.0).contains(x)));
    }

    fn field_volume(n: usize, f: impl Fn(DVec3) -> (f64, f64), extra: Vec<Param>) -> FireVolume {
        // n³ voxels over [0, 1]³, trilinear; f gives (density, temperature) at each voxel centre.
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let c = (DVec3::new(i as f64, j as f64, k as f64) + 0.5) / n as f64;
                    let (dv, tv) = f(c);
                    d.push(dv);
                    t.push(tv);
                }
            }
        }
        let mut list = vec![
            Param::floats("density", &d),
            Param::floats("temperature", &t),
            Param::int("nx", n as i64),
            Param::int("ny", n as i64),
            Param::int("nz", n as i64),
        ];
        list.extend(extra);
        FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}"))
    }

    fn exit(v: &FireVolume, o: DVec3, d: DVec3) -> (Vec<f64>, Vec<f64>, DVec3, DVec3, f64) {
        let c = v.channels();
        let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
        let ray = Ray {
            o,
            d,
            t0: 0.0,
            t1: 10.0,
            seed: 3,
        };
        let (p, dir, te) = v.integrate_exit(&ray, &mut l, &mut t);
        (l, t, p, dir, te)
    }

    #[test]
    fn refraction_is_built_only_when_asked_and_bends_rays_away_from_heat() {
        let hot = |c: DVec3| {
            let r2 = (c - DVec3::splat(0.5)).length_squared();
            (
                1e-8 * (-r2 / 0.05).exp(),
                300.0 + 1500.0 * (-r2 / 0.05).exp(),
            )
        };
        let off = field_volume(16, hot, vec![]);
        assert!(off.tables().iter().all(|t| !t.name.contains("refraction")));
        let on = field_volume(
            16,
            hot,
            vec![
                Param::bool("refraction", true),
                Param::float("refractionscale", 100.0),
            ],
        );
        let table = on
            .tables()
            .iter()
            .find(|t| t.name.contains("refraction"))
            .expect("index field");
        // 16³ voxels and two ambient rings, δ and ∇δ per voxel.
        assert_eq!(table.bytes, 20 * 20 * 20 * 16);
        // Off: the exit is the straight ray's.
        let (o, d) = (DVec3::new(-0.5, 0.62, 0.5), DVec3::new(2.0, 0.0, 0.0));
        let (l0, _, p0, d0, _) = exit(&off, o, d);
        assert_eq!(d0, DVec3::X);
        assert!((p0 - DVec3::new(1.0, 0.62, 0.5)).length() < 1e-9, "{p0}");
        // On: a ray passing above the hot core bends up, away from the heat (hot air has the lower index).
        let (l1, _, p1, d1, _) = exit(&on, o, d);
        assert!((d1.length() - 1.0).abs() < 1e-12);
        assert!(d1.y > 1e-4 && p1.y > 0.62, "{d1} at {p1}");
        // At scale 100 the path is pushed out of the core (less emission); at the physical scale the curved march
        // integrates the same fire as the straight one: radiance and transmittance within 0.5 %.
        assert!(l1[15] < l0[15], "{} vs {}", l1[15], l0[15]);
        // (Both at a tenth of a voxel per step: the bluest bins' emission, ∝ T¹⁵, is sharply peaked.)
        let fine = field_volume(16, hot, vec![Param::float("stepsize", 0.1)]);
        let (l0, t0, _, _, _) = exit(&fine, o, d);
        let on1 = field_volume(
            16,
            hot,
            vec![
                Param::bool("refraction", true),
                Param::float("stepsize", 0.1),
            ],
        );
        let (l2, t2, _, _, _) = exit(&on1, o, d);
        for k in 0..l0.len() {
            assert!(
                (l2[k] / l0[k] - 1.0).abs() < 0.005 && (t2[k] / t0[k] - 1.0).abs() < 0.005,
                "{k}: {} vs {}",
                l2[k],
                l0[k]
            );
        }
        // The deflection scales with refractionscale (small angles): ×10 scale, ×10 angle within 5 %.
        let on10 = field_volume(
            16,
            hot,
            vec![
                Param::bool("refraction", true),
                Param::float("refractionscale", 10.0),
            ],
        );
        let (_, _, _, d10, _) = exit(&on10, o, d);
        assert!(
            (d1.y / d10.y / 10.0 - 1.0).abs() < 0.05,
            "{} vs {}",
            d1.y,
            d10.y
        );
    }

    #[test]
    fn a_uniformly_hot_box_shifts_but_does_not_turn_rays() {
        // Entering and leaving through parallel faces: the direction comes out as it went in (the index fades to
        // ambient over the padding, so both crossings are smooth and cancel). RK4 (the reference) keeps it to
        // 1e-6; the Verlet march to a small fraction of the bend inside, which is ~δ/n of the box: physical
        // δ ≈ 2e-4, ×1000 δ ≈ 0.2 (n 1.29 → 1.06 within two voxels).
        // (Clear of the y faces, where the index varies in y too.)
        let d = DVec3::new(1.0, 0.25, 0.0).normalize();
        let o = DVec3::new(-0.3, 0.3, 0.5);
        for (integrator, scale, tol) in [
            ("rk4", 1000.0, 1e-6),
            ("verlet", 1.0, 1e-6),
            ("verlet", 1000.0, 2e-3),
        ] {
            let v = field_volume(
                8,
                |_| (1e-9, 1500.0),
                vec![
                    Param::bool("refraction", true),
                    Param::float("refractionscale", scale),
                    Param::string("refractionintegrator", integrator),
                ],
            );
            let mut worst = 0.0f64;
            for seed in 0..16 {
                let ray = Ray {
                    o,
                    d,
                    t0: 0.0,
                    t1: 10.0,
                    seed,
                };
                let c = v.channels();
                let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
                let (p, dir, _) = v.integrate_exit(&ray, &mut l, &mut t);
                worst = worst.max((dir - d).length());
                // ... but it moved: n_hot < n_amb, so inside the ray runs steeper and exits higher than straight.
                let straight = o + d * ((1.0 + 0.3) / d.x);
                if scale > 1.0 {
                    assert!(
                        p.x > 1.0 - 1e-9 && p.y > straight.y + 1e-3,
                        "{p} vs {straight}"
                    );
                }
            }
            eprintln!("uniform box, {integrator} ×{scale}: exit direction off by {worst:.3e}");
            assert!(worst < tol, "{integrator} ×{scale}: {worst} ≥ {tol}");
        }
    }

    #[test]
    fn extreme_index_jumps_stay_finite() {
        // Temperature jumping 300 K → 3000 K between neighbouring voxels, (n − 1) × 10⁴: no NaN, unit directions,
        // transmittance in [0, 1], for rays in many directions (some turn back by total internal reflection).
        let v = field_volume(
            8,
            |c| (1e-7, if c.x > 0.5 { 3000.0 } else { 300.0 }),
            vec![
                Param::bool("refraction", true),
                Param::float("refractionscale", 1e4),
            ],
        );
        let mut rng = crate::rng::Rng::new(8);
        for _ in 0..200 {
            let d = DVec3::new(
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
                rng.next_f64() - 0.5,
            );
            let o = DVec3::splat(0.5) - d.normalize() * 1.5;
            let (l, t, p, dir, te) = exit(&v, o, d);
            assert!(
                p.is_finite() && te.is_finite() && (dir.length() - 1.0).abs() < 1e-9,
                "{p} {dir}"
            );
            assert!(
                l.iter().all(|x| x.is_finite() && *x >= 0.0)
                    && t.iter().all(|x| (0.0..=1.0).contains(x))
            );
        }
    }
}
