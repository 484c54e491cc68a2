//! Atomic lines across their profile (`lineshape "voigt"`, the default): the curve of growth.
//!
//! The paper bins a line with φ = 1/Δλ over a whole 10 nm bin. While the line is optically thin that is exact;
//! once its centre is thick, the light it sends out grows only with the width over which it is thick (the curve
//! of growth: linear, then √ln in the Doppler core, then √ in the collisional wings), and the box overstates it
//! up to a hundredfold (Na D at 1e20 m⁻³ over 1 m). A bin's radiance is not a function of its mean absorption,
//! so the fix cannot be a coefficient: it is line-by-line radiative transfer at wavelengths across the line.
//!
//! **Which lines.** A line is *thick-capable* when its centre optical depth (Voigt peak, at the species grid's
//! largest number density, over the fire's diagonal, at any temperature the grid holds) reaches [`THICK`]; the
//! others stay boxed (their error is below THICK/2). Thick-capable lines leave the volume's per-channel tables
//! (so every estimator — march, ratio, delta — sees the continuum and the thin lines) and are added back by the
//! correction below. `coefficients` still reports them as bin means (what a bin's coefficient is).
//!
//! **Groups and nodes.** The thick lines of one window — ±20 nm around each line, or wider where its collisional
//! wing is still thicker than [`WING_TAU`] (a dense flame's wings are thick tens of nm out), overlapping windows
//! merged — form a group. Each line owns the window up to the midpoints between its
//! neighbours; across it the nodes are a core node each side (offsets below δ₀ = 0.3 σ_D at 300 K) and
//! 3-point Gauss–Legendre panels, one per decade of offset, in u = ln δ (the integrand δ·g(δ) is a smooth bump
//! in u from the Doppler core to the Lorentz wings; 3.4e-3 against a 2e-5 nm grid, tested). Na D: 58 nodes.
//!
//! **Transfer.** Along the straight ray, in the volume's steps (midpoint samples, exact exponentials per step),
//! the continuum at the group's centre wavelength (soot σ_a, σ_s and κB there, times the same scales as the
//! tables) and each node's continuum + lines: with r_k = T_k/T⁰ (the line's own transmittance at node k) and
//! X_k = L_k − L⁰ (its excess radiance), a channel c gets
//!
//! - radiance  L_c += Σ_k P_c(λ_k) Δλ_k X_k,
//! - transmittance T_c += Σ_k Q_c(λ_k) Δλ_k T⁰ (r_k − 1),
//!
//! with P = Q = 1/bin width for the bin holding λ_k in spectral mode (so a line's wings reach the bins beside
//! it), and in rgb mode
//! P = K x̄ȳz̄_c(λ_k) (each node's light at its own wavelength's colour) and Q = x̄ȳz̄_c(λ_k)/∫x̄ȳz̄_c (a background
//! flat across the band). Steps without species change r_k by nothing and X_k by (r_k − 1)·ΔL⁰, folded in
//! lazily, so the continuum before, between and behind the lines costs one lookup per step.
//!
//! **Approximations** (documented, measured in the tests): the continuum is flat across a group's window (the
//! base channel's continuum is the bin mean, the nodes' the centre's); the colour ramp and the scatter colour
//! do not reach the nodes' continuum; light that enters a segment, and the scattered light at an event, is flat
//! across the window (a segment's own line self-absorption is exact, across segments it is not correlated);
//! refraction's bent rays get the correction along their straight chord.

use super::basis::Basis;
use super::tables::TTable;
use super::{ColorMode, FireVolume, Ray};
use crate::blackbody::spectral_radiance;
use crate::constants::BOLTZMANN;
use crate::dataset::Dataset;
use crate::species::profile::{
    atomic_mass_u, doppler_sigma_nm, line_profile_nm, lorentz_hwhm_nm, voigt_nm,
};
use crate::species::{line_cross_sections, Element, Line};
use crate::Error;
use glam::DVec3;

/// The centre optical depth (over the fire's diagonal, at its largest number density) from which a line is
/// integrated across its profile.
pub(super) const THICK: f64 = 0.01;

/// The least half width of the window across a line, nm: its wings beyond carry < 1 % of its light up to N·L =
/// 1e20 m⁻² (Na D) and stay out.
const HALF_WINDOW: f64 = 20.0;

/// The optical depth of a line's collisional wing at the edge of its window (at the species' largest number
/// density over the fire's diagonal, at the temperature where the line absorbs most): a denser fire's window
/// widens until its wing there is this thin, so the light its wings hold beyond stays under 1 % of B in any bin.
const WING_TAU: f64 = 0.01;

/// 3-point Gauss–Legendre nodes and weights on [−1, 1].
const GL3: [(f64, f64); 3] = [
    (-0.774_596_669_241_483_4, 0.555_555_555_555_555_6),
    (0.0, 0.888_888_888_888_888_9),
    (0.774_596_669_241_483_4, 0.555_555_555_555_555_6),
];

/// What the line model needs from the volume's build.
pub(super) struct Input<'a> {
    /// (symbol, element, m⁻³ per grid unit), the settings' species.
    pub species: &'a [(String, Element, f64)],
    pub ds: &'a Dataset,
    pub basis: &'a Basis,
    /// Collisional FWHM at 2500 K, cm⁻¹.
    pub broadening: f64,
    pub intensity: f64,
    /// The continuum per unit density at λ (nm): σ_a, σ_s, and the emission factor (× B(λ, T)).
    pub continuum: &'a dyn Fn(f64) -> [f64; 3],
    /// The temperature grid's range, K.
    pub t_range: [f64; 2],
    /// Bytes the tables may take.
    pub budget: u64,
}

/// A window's [λ₀, λ₁] (nm) and its lines (species index, line, the line's own half window).
type Window = ([f64; 2], Vec<(usize, Line, f64)>);

/// The line tables' temperature step: 2 K, or coarser for a hotter grid (at most 4096 rows; the populations
/// and widths change smoothly in T).
fn step(t_max: f64) -> f64 {
    (t_max / 4096.0).max(2.0)
}

/// The fire's diagonal, m: the longest path through it.
fn diagonal(inp: &Input) -> f64 {
    let [lo, hi] = inp.ds.bounds();
    (hi - lo).length()
}

/// Species `s`'s largest number density in the dataset, m⁻³.
fn largest_density(inp: &Input, s: usize) -> f64 {
    let (sym, _, scale) = &inp.species[s];
    inp.ds
        .channels()
        .iter()
        .find(|c| &c.name == sym)
        .map_or(0.0, |c| c.stats.max.max(0.0) as f64 * scale)
}

/// 33 temperatures spaced geometrically over the grid's range, where a line's strength is sampled.
fn temperatures(inp: &Input) -> Vec<f64> {
    let [t_lo, t_hi] = inp.t_range;
    let (t_lo, t_hi) = (t_lo.max(1.0), t_hi.max(1.0));
    (0..=32)
        .map(|i| t_lo * (t_hi / t_lo).powf(i as f64 / 32.0))
        .collect()
}

/// The thick-capable lines of each species (per line of its element).
pub(super) fn select(inp: &Input) -> Vec<Vec<bool>> {
    let length = diagonal(inp);
    let temps = temperatures(inp);
    inp.species
        .iter()
        .enumerate()
        .map(|(s, (_, e, _))| {
            let n_max = largest_density(inp, s);
            let mass = atomic_mass_u(e.symbol()).unwrap_or(1.0);
            e.lines()
                .iter()
                .map(|l| {
                    inside(inp.basis, l.lambda_nm)
                        && temps.iter().any(|&t| {
                            let kt = BOLTZMANN * t;
                            let phi = line_profile_nm(0.0, l.lambda_nm, t, mass, inp.broadening);
                            let (sa, _) =
                                line_cross_sections(l, kt, e.ln_partition_function(t), phi * 1e9);
                            n_max * sa * length >= THICK
                        })
                })
                .collect()
        })
        .collect()
}

/// A thick line's half window (nm): [`HALF_WINDOW`], or wider where its Lorentz wing, σ(Δλ) ≈ S γ / (π Δλ²), is
/// still thicker than [`WING_TAU`] there — Δλ = √(N_max L S γ / (π WING_TAU)) at the temperature (of `select`'s)
/// where S γ is largest.
fn half_window(inp: &Input, species: usize, line: &Line) -> f64 {
    let e = &inp.species[species].1;
    let (length, n_max) = (diagonal(inp), largest_density(inp, species));
    let widest = temperatures(inp)
        .into_iter()
        .map(|t| {
            // (The strength per unit of φ per nm, as the tables take it.)
            let strength =
                line_cross_sections(line, BOLTZMANN * t, e.ln_partition_function(t), 1e9).0;
            let gamma = lorentz_hwhm_nm(line.lambda_nm, t, inp.broadening);
            (n_max * length * strength * gamma / (std::f64::consts::PI * WING_TAU)).sqrt()
        })
        .fold(0.0, f64::max);
    if widest.is_finite() {
        widest.max(HALF_WINDOW)
    } else {
        HALF_WINDOW
    }
}

/// Whether a line at λ lands in the basis's channels (a bin, or the CMFs' 380–780 nm).
fn inside(basis: &Basis, lambda: f64) -> bool {
    match basis.mode() {
        ColorMode::Spectral(g) => g.bin_of(lambda).is_some(),
        ColorMode::Rgb => (380.0..780.0).contains(&lambda),
    }
}

/// One species' lines in a group: its dataset channel, m⁻³ per unit, and a table over T of 2K values per
/// row — σ̂ at each node (m² per atom), then ĵ (W·sr⁻¹·nm⁻¹ per atom, × intensity).
#[derive(Clone)]
struct GroupSpecies {
    ch: usize,
    scale: f64,
    tab: TTable,
    /// The same rows contiguous (the node loop reads a whole row: a loop the compiler vectorises).
    rows: Vec<f32>,
}

impl GroupSpecies {
    fn new(ch: usize, scale: f64, tab: TTable, width: usize) -> GroupSpecies {
        let rows = (0..tab.rows())
            .flat_map(|r| (0..width).map(move |c| (r, c)))
            .map(|(r, c)| tab.value(r, c))
            .collect();
        GroupSpecies {
            ch,
            scale,
            tab,
            rows,
        }
    }
    /// Adds n × the row at T (linear between rows) to `out` (2K values).
    fn add_row(&self, t: f64, n: f64, out: &mut [f64]) {
        let w = out.len();
        let (i, f) = self.tab.locate(t);
        let (a, b) = (
            &self.rows[i * w..(i + 1) * w],
            &self.rows[(i + 1) * w..(i + 2) * w],
        );
        let (f, g) = (n * f as f64, n * (1.0 - f as f64));
        for ((o, &x), &y) in out.iter_mut().zip(a).zip(b) {
            *o += g * x as f64 + f * y as f64;
        }
    }
}

/// The thick lines of one window.
#[derive(Clone)]
struct Group {
    /// The continuum's wavelength (the window's centre line), nm.
    lambda_c: f64,
    /// Per unit density at `lambda_c`: σ_a, σ_s, emission factor.
    cont: [f64; 3],
    /// Node wavelengths, nm.
    lambda: Vec<f64>,
    /// (node, channel, P·Δλ, Q·Δλ).
    fold: Vec<(usize, usize, f64, f64)>,
    species: Vec<GroupSpecies>,
}

impl Group {
    fn k(&self) -> usize {
        self.lambda.len()
    }
}

/// The thick-capable lines of a volume, integrated across their profiles.
#[derive(Clone)]
pub(super) struct ThickLines {
    groups: Vec<Group>,
    /// The thick lines as bin means, per species: (dataset channel, scale, table of 2C: σ̂ then ĵ per channel),
    /// for `coefficients`.
    boxed: Vec<GroupSpecies>,
    channels: usize,
}

impl std::fmt::Debug for ThickLines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ThickLines")
            .field("groups", &self.groups.len())
            .field("nodes", &self.nodes())
            .finish()
    }
}

/// The nodes (λ, Δλ) across a window [w0, w1] holding the line centres `centres` (sorted), core half width δ₀,
/// with panels broken at the wavelengths `breaks` (bin edges: a node's light goes to its own bin).
fn window_nodes(
    w0: f64,
    w1: f64,
    centres: &[f64],
    d0: f64,
    breaks: &[f64],
) -> (Vec<f64>, Vec<f64>) {
    let (mut lam, mut wid) = (Vec::new(), Vec::new());
    for (i, &c) in centres.iter().enumerate() {
        let lo = if i == 0 {
            w0
        } else {
            0.5 * (centres[i - 1] + c)
        };
        let hi = if i + 1 == centres.len() {
            w1
        } else {
            0.5 * (c + centres[i + 1])
        };
        for (side, ext) in [(-1.0, c - lo), (1.0, hi - c)] {
            if !(ext > 0.0) {
                continue;
            }
            if ext <= 2.0 * d0 {
                lam.push(c + side * 0.5 * ext);
                wid.push(ext);
                continue;
            }
            lam.push(c + side * 0.5 * d0);
            wid.push(d0);
            // Pieces in u = ln δ between the breaks on this side, each in panels of at most a decade.
            let mut cuts: Vec<f64> = breaks
                .iter()
                .map(|&b| (b - c) * side)
                .filter(|&d| d > d0 && d < ext)
                .map(f64::ln)
                .collect();
            cuts.push(d0.ln());
            cuts.push(ext.ln());
            cuts.sort_by(f64::total_cmp);
            for piece in cuts.windows(2) {
                let (u0, u1) = (piece[0], piece[1]);
                let panels = ((u1 - u0) / std::f64::consts::LN_10).ceil().max(1.0) as usize;
                let h = (u1 - u0) / panels as f64;
                for p in 0..panels {
                    let mid = u0 + (p as f64 + 0.5) * h;
                    for (x, w) in GL3 {
                        let d = (mid + 0.5 * h * x).exp();
                        lam.push(c + side * d);
                        wid.push(w * 0.5 * h * d);
                    }
                }
            }
        }
    }
    (lam, wid)
}

impl ThickLines {
    /// The groups of the lines `thick` marks (see [`select`]); `None` when there are none.
    pub(super) fn new(
        inp: &Input,
        thick: &[Vec<bool>],
        t_max: f64,
    ) -> Result<Option<ThickLines>, Error> {
        // (species index, line) of every thick line.
        let mut all: Vec<(usize, Line)> = Vec::new();
        for (s, ((_, e, _), marks)) in inp.species.iter().zip(thick).enumerate() {
            for (l, &m) in e.lines().iter().zip(marks) {
                if m {
                    all.push((s, *l));
                }
            }
        }
        if all.is_empty() {
            return Ok(None);
        }
        all.sort_by(|a, b| a.1.lambda_nm.total_cmp(&b.1.lambda_nm));
        // Windows: each line's own half window around it (clipped to the channels' range: nodes beyond reach no
        // channel), overlapping ones merged.
        let [lo, hi] = match inp.basis.mode() {
            ColorMode::Spectral(g) => [g.min_nm(), g.max_nm()],
            ColorMode::Rgb => [380.0, 780.0],
        };
        let mut windows: Vec<Window> = Vec::new();
        for (s, l) in all {
            let hw = half_window(inp, s, &l);
            let w = [
                (l.lambda_nm - hw).max(lo.min(l.lambda_nm)),
                (l.lambda_nm + hw).min(hi.max(l.lambda_nm)),
            ];
            match windows.last_mut() {
                Some((last, members)) if w[0] < last[1] => {
                    last[1] = last[1].max(w[1]);
                    last[0] = last[0].min(w[0]);
                    members.push((s, l, hw));
                }
                _ => windows.push((w, vec![(s, l, hw)])),
            }
            // (A wide window may reach back over the one before: merged, their lines stay in order.)
            while windows.len() > 1
                && windows[windows.len() - 1].0[0] < windows[windows.len() - 2].0[1]
            {
                let (w, members) = windows.pop().unwrap_or_default();
                if let Some((last, m)) = windows.last_mut() {
                    *last = [last[0].min(w[0]), last[1].max(w[1])];
                    m.extend(members);
                }
            }
        }
        // The tables' bytes before they are built: two values a node per row for each species with lines in the
        // window, twice (the lanes and the contiguous rows), and the bins' means.
        let rows = (t_max / step(t_max)).ceil() + 2.0;
        let per_row: f64 = windows
            .iter()
            .map(|(w, members)| {
                let mut species: Vec<usize> = members.iter().map(|m| m.0).collect();
                species.sort_unstable();
                species.dedup();
                2.0 * Self::window_of(inp, *w, members).0.len() as f64 * species.len() as f64
            })
            .sum();
        let lines = windows.iter().map(|w| w.1.len()).sum::<usize>();
        let need =
            rows * 8.0 * (per_row + 2.0 * inp.basis.channels() as f64 * inp.species.len() as f64);
        if need > inp.budget as f64 {
            return Err(Error::invalid(
                "volume",
                "lineshape",
                format!(
                    "\"voigt\" for {lines} optically thick lines up to {t_max:.0} K ({:.0} MB of tables)",
                    need / 1e6
                ),
                format!(
                    "tables within the memory budget's {:.0} MB left (lineshape \"box\", or a smaller maxbytes use)",
                    inp.budget as f64 / 1e6
                ),
            ));
        }
        let c = inp.basis.channels();
        let groups = windows
            .into_iter()
            .map(|(w, members)| Self::group(inp, w, &members, t_max))
            .collect();
        // The thick lines as the bins' means (for `coefficients`).
        let boxed = inp
            .species
            .iter()
            .zip(thick)
            .filter(|(_, marks)| marks.iter().any(|&m| m))
            .map(|((sym, e, scale), marks)| {
                // The thick lines alone: the bands stay with the thin rest.
                let only = e
                    .with_lines(&|l| {
                        e.lines()
                            .iter()
                            .zip(marks)
                            .any(|(x, &m)| m && x.lambda_nm == l.lambda_nm)
                    })
                    .without_bands();
                let (basis, intensity) = (inp.basis.clone(), inp.intensity);
                let aux = basis.line_aux();
                let tab = TTable::build_step(t_max, step(t_max), 2 * c, &move |t| {
                    let (mut s, j) = basis.lines(&only, t, &aux);
                    s.extend(j.into_iter().map(|v| v * intensity));
                    s
                });
                GroupSpecies::new(channel(inp.ds, sym), *scale, tab, 0)
            })
            .collect();
        Ok(Some(ThickLines {
            groups,
            boxed,
            channels: c,
        }))
    }

    /// The nodes (λ, Δλ) across window `w` of `members`' lines.
    fn window_of(inp: &Input, w: [f64; 2], members: &[(usize, Line, f64)]) -> (Vec<f64>, Vec<f64>) {
        let mut centres: Vec<f64> = Vec::new();
        let mut d0 = f64::INFINITY;
        for (s, l, _) in members {
            let mass = atomic_mass_u(inp.species[*s].1.symbol()).unwrap_or(1.0);
            d0 = d0.min(0.3 * doppler_sigma_nm(l.lambda_nm, 300.0, mass));
            if centres.last().is_none_or(|&c| l.lambda_nm - c > 1e-3) {
                centres.push(l.lambda_nm);
            }
        }
        let breaks: Vec<f64> = match inp.basis.mode() {
            ColorMode::Spectral(g) => (0..=g.count())
                .map(|i| g.min_nm() + i as f64 * g.width_nm())
                .collect(),
            ColorMode::Rgb => Vec::new(),
        };
        window_nodes(w[0], w[1], &centres, d0, &breaks)
    }

    fn group(inp: &Input, w: [f64; 2], members: &[(usize, Line, f64)], t_max: f64) -> Group {
        let (lambda, width) = Self::window_of(inp, w, members);
        // The continuum's wavelength: the lines' mean (within a bin, or 10 nm, of each of them).
        let lambda_c =
            members.iter().map(|(_, l, _)| l.lambda_nm).sum::<f64>() / members.len() as f64;
        let cont = (inp.continuum)(lambda_c);
        let mut fold = Vec::new();
        match inp.basis.mode() {
            ColorMode::Spectral(g) => {
                // Each node's light shared as a line at its wavelength would be (`LineSplit`: the film sees its
                // own luminance), its transmittance in its own bin.
                let split = inp
                    .basis
                    .line_split()
                    .then(|| crate::cie::LineSplit::new(&g));
                for (k, (&l, &dw)) in lambda.iter().zip(&width).enumerate() {
                    let Some(b) = g.bin_of(l) else { continue };
                    let parts = match &split {
                        Some(s) => s.split(l).unwrap_or([(b, 1.0), (b, 0.0)]),
                        None => [(b, 1.0), (b, 0.0)],
                    };
                    {
                        // (The transmittance once, in the node's bin.)
                        let mut q_left = dw / g.width_nm();
                        for (bin, f) in parts {
                            let q = if bin == b {
                                std::mem::take(&mut q_left)
                            } else {
                                0.0
                            };
                            if f > 0.0 || q > 0.0 {
                                fold.push((k, bin, f * dw / g.width_nm(), q));
                            }
                        }
                    }
                }
            }
            ColorMode::Rgb => {
                let total = crate::cie::cmf_integral(360.0, 830.0);
                for (k, (&l, &dw)) in lambda.iter().zip(&width).enumerate() {
                    let w = crate::cie::cmf(l);
                    for ch in 0..3 {
                        fold.push((k, ch, inp.basis.k() * w[ch] * dw, w[ch] * dw / total[ch]));
                    }
                }
            }
        }
        let mut species = Vec::new();
        for (s, (sym, e, scale)) in inp.species.iter().enumerate() {
            let lines: Vec<(Line, f64)> = members
                .iter()
                .filter(|m| m.0 == s)
                .map(|m| (m.1, m.2))
                .collect();
            if lines.is_empty() {
                continue;
            }
            let (e, lam, intensity) = (e.clone(), lambda.clone(), inp.intensity);
            let mass = atomic_mass_u(e.symbol()).unwrap_or(1.0);
            let broadening = inp.broadening;
            let k = lam.len();
            let tab = TTable::build_step(t_max, step(t_max), 2 * k, &move |t| {
                let mut row = vec![0.0; 2 * k];
                if !(t > 0.0) {
                    return row;
                }
                let (kt, ln_z) = (BOLTZMANN * t, e.ln_partition_function(t));
                for (line, hw) in &lines {
                    // σ is linear in the profile: the line's strength (its cross-section per unit of φ, per
                    // nm) and its widths once per row, the Voigt profile per node.
                    let strength = line_cross_sections(line, kt, ln_z, 1e9).0;
                    let sigma = doppler_sigma_nm(line.lambda_nm, t, mass);
                    let gamma = lorentz_hwhm_nm(line.lambda_nm, t, broadening);
                    // (Out to the line's own window: its wings beyond are thinner than WING_TAU — as the
                    // windows were drawn — and a merged window of many lines would otherwise cost lines × nodes.)
                    for (n, &l) in lam.iter().enumerate() {
                        let offset = l - line.lambda_nm;
                        if offset.abs() <= *hw {
                            row[n] += strength * voigt_nm(offset, sigma, gamma);
                        }
                    }
                }
                // Kirchhoff at each node's own wavelength (a wing 10 nm out sees Planck 12 % off the centre's).
                for (n, &l) in lam.iter().enumerate() {
                    row[k + n] = row[n] * spectral_radiance(t, l) * intensity;
                }
                row
            });
            species.push(GroupSpecies::new(channel(inp.ds, sym), *scale, tab, 2 * k));
        }
        Group {
            lambda_c,
            cont,
            lambda,
            fold,
            species,
        }
    }

    /// How many wavelength nodes the groups hold.
    pub(super) fn nodes(&self) -> usize {
        self.groups.iter().map(Group::k).sum()
    }
    /// Bytes of the tables.
    pub(super) fn bytes(&self) -> usize {
        self.groups
            .iter()
            .flat_map(|g| &g.species)
            .chain(&self.boxed)
            .map(|s| s.tab.bytes())
            .sum()
    }

    /// Adds the thick lines' bin means to σ_a and j at a sample (T, and each species' grid value by `value`).
    pub(super) fn add_boxed(
        &self,
        t: f64,
        value: &dyn Fn(usize) -> f64,
        sa: &mut [f64],
        j: &mut [f64],
    ) {
        for b in &self.boxed {
            let n = value(b.ch).max(0.0) * b.scale;
            if n > 0.0 {
                let loc = b.tab.locate(t);
                for c in 0..self.channels.min(sa.len()) {
                    sa[c] += n * b.tab.at(loc, c) as f64;
                    j[c] += n * b.tab.at(loc, self.channels + c) as f64;
                }
            }
        }
    }

    /// The lines' part along `ray` up to parameter `end` (the exit, or a scattering event), in the medium seen
    /// through `at` (the identity when `still`, or motion blur's displacement): adds their radiance to `l`, and
    /// to `t` their transmittance (`Fold::Add`) or multiplies `t` by it (`Fold::Scale`, a scattering event's
    /// weights). Still, it steps only through the majorant bricks that hold anything, and returns at once from
    /// a ray that meets no brick holding its species.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn apply(
        &self,
        v: &FireVolume,
        ray: &Ray,
        end: f64,
        still: bool,
        at: &dyn Fn(DVec3) -> DVec3,
        l: Option<&mut [f64]>,
        t: &mut [f64],
        fold: Fold,
    ) {
        let speed = ray.d.length();
        let Some((a, b)) = super::Medium::clip(v, ray.o, ray.d, ray.t0, end.min(ray.t1)) else {
            return;
        };
        if !(speed > 0.0 && speed.is_finite()) {
            return;
        }
        // The spans to step through: the majorant bricks that hold anything (and whether any of this model's
        // species is there); with motion blur (`still` false) the whole clipped ray, as the lookups move.
        let spans: Vec<(f64, f64, bool)> = if still {
            let species: Vec<usize> = self
                .groups
                .iter()
                .flat_map(|g| g.species.iter().map(|sp| sp.ch))
                .collect();
            v.bounds
                .majorant()
                .segments(ray.o, ray.d, a, b)
                .filter(|sg| !v.bounds.brick_empty()[sg.brick])
                .map(|sg| {
                    let lines = species
                        .iter()
                        .any(|&c| v.bounds.majorant().max(sg.brick, c) > 0.0);
                    (sg.t0, sg.t1, lines)
                })
                .collect()
        } else {
            vec![(a, b, true)]
        };
        if !spans.iter().any(|s| s.2) {
            return;
        }
        let chs = v.grids.ds().channels();
        let mut state: Vec<State> = self.groups.iter().map(|g| State::new(g.k())).collect();
        let (mut row, mut ns) = (Vec::new(), Vec::new());
        let mut budget = super::MAX_STEPS as usize;
        for (s0, s1, lines_here) in spans {
            let n = (((s1 - s0) * speed / v.estimator.step()).ceil().max(1.0) as usize).min(budget);
            budget -= n;
            let dt = (s1 - s0) / n as f64;
            let ds = dt * speed;
            for i in 0..n {
                let p = at(ray.o + ray.d * (s0 + (i as f64 + 0.5) * dt));
                let Some(st) = v.grids.ds().stencil_with_margin(p, v.bounds.margin()) else {
                    continue;
                };
                let value = |k: usize| chs[k].grid.eval(&st) as f64;
                let d = value(v.grids.density()).max(0.0);
                let temp = v.grids.temperature().map_or(0.0, value);
                let les = v.grids.lescale().map_or(1.0, |k| value(k).max(0.0));
                let emits = temp > v.model.t_emit() || v.grids.temperature().is_none();
                for (g, s) in self.groups.iter().zip(&mut state) {
                    let sc = d * (g.cont[0] + g.cont[1]);
                    let jc = if emits && g.cont[2] > 0.0 {
                        v.emitting(d, les) * g.cont[2] * spectral_radiance(temp, g.lambda_c)
                    } else {
                        0.0
                    };
                    ns.clear();
                    if lines_here {
                        for (q, sp) in g.species.iter().enumerate() {
                            let nq = value(sp.ch).max(0.0) * sp.scale;
                            if nq > 0.0 {
                                ns.push((q, nq));
                            }
                        }
                    }
                    if ns.is_empty() {
                        s.continuum(sc, jc, ds);
                        continue;
                    }
                    let k = g.k();
                    row.clear();
                    row.resize(2 * k, 0.0);
                    for &(q, nq) in &ns {
                        g.species[q].add_row(temp, nq, &mut row);
                    }
                    let (sig, jj) = row.split_at(k);
                    s.lines(sc, jc, sig, jj, ds);
                }
            }
        }
        // Per channel: Σ P Δλ X_k, and Σ Q Δλ (r_k − 1) (times T⁰ for a transmittance).
        let mut add_l = vec![0.0; t.len()];
        let mut add_t = vec![0.0; t.len()];
        for (g, s) in self.groups.iter().zip(&mut state) {
            s.settle();
            for &(k, c, pw, qw) in &g.fold {
                if c < t.len() {
                    add_l[c] += pw * s.x[k];
                    add_t[c] += qw
                        * (s.r[k] - 1.0)
                        * match fold {
                            Fold::Add => s.t0,
                            Fold::Scale => 1.0,
                        };
                }
            }
        }
        for c in 0..t.len() {
            t[c] = match fold {
                Fold::Add => t[c] + add_t[c],
                Fold::Scale => t[c] * (1.0 + add_t[c]),
            }
            .max(0.0);
        }
        if let Some(l) = l {
            for (v, a) in l.iter_mut().zip(&add_l) {
                *v = (*v + a).max(0.0);
            }
        }
    }
}

/// How [`ThickLines::apply`] folds the lines' transmittance into a channel's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Fold {
    /// A transmittance: T_c + Σ Q Δλ T⁰ (r_k − 1).
    Add,
    /// A weight: w_c · (1 + Σ Q Δλ (r_k − 1)), the lines' mean transmittance over the window.
    Scale,
}

/// A group's transfer along a ray: the continuum's radiance and transmittance, the nodes' r_k = T_k/T⁰ and
/// X_k = L_k − L⁰, and the continuum's radiance gathered since the last line sample (folded in as X_k +=
/// (r_k − 1)·pending).
struct State {
    l0: f64,
    t0: f64,
    r: Vec<f64>,
    x: Vec<f64>,
    pending: f64,
    lines_seen: bool,
}

/// (1 − e^{−σ s})/σ, → s as σ → 0.
fn path(sigma: f64, s: f64) -> f64 {
    let tau = sigma * s;
    if tau < 1e-8 {
        s
    } else {
        -(-tau).exp_m1() / sigma
    }
}

impl State {
    fn new(k: usize) -> State {
        State {
            l0: 0.0,
            t0: 1.0,
            r: vec![1.0; k],
            x: vec![0.0; k],
            pending: 0.0,
            lines_seen: false,
        }
    }
    fn continuum(&mut self, sc: f64, jc: f64, ds: f64) {
        let dl = self.t0 * jc * path(sc, ds);
        self.l0 += dl;
        if self.lines_seen {
            self.pending += dl;
        }
        self.t0 *= (-sc * ds).exp();
    }
    fn settle(&mut self) {
        if self.pending != 0.0 {
            for (x, r) in self.x.iter_mut().zip(&self.r) {
                *x += (r - 1.0) * self.pending;
            }
            self.pending = 0.0;
        }
    }
    fn lines(&mut self, sc: f64, jc: f64, sig: &[f64], jl: &[f64], ds: f64) {
        self.settle();
        self.lines_seen = true;
        let base = jc * path(sc, ds);
        let ec = (-sc * ds).exp();
        let thin_c = sc * ds < 1e-4;
        for m in 0..sig.len() {
            // At most one exponential per node — none in the thin wings, where most nodes lie (series to
            // τ³, below 1e-16 relative at τ < 1e-4).
            let tl = sig[m] * ds;
            let st = sc + sig[m];
            let (el, p) = if tl < 1e-4 && thin_c {
                let tt = st * ds;
                (
                    1.0 - tl * (1.0 - 0.5 * tl),
                    ds * (1.0 - tt * (0.5 - tt / 6.0)),
                )
            } else {
                let el = (-tl).exp();
                let p = if st * ds < 1e-3 {
                    path(st, ds)
                } else {
                    (1.0 - el * ec) / st
                };
                (el, p)
            };
            self.x[m] += self.t0 * (self.r[m] * (jc + jl[m]) * p - base);
            self.r[m] *= el;
        }
        self.l0 += self.t0 * base;
        self.t0 *= ec;
    }
}

/// The dataset channel of a species (0 if absent: validated by the settings).
fn channel(ds: &Dataset, sym: &str) -> usize {
    ds.channels()
        .iter()
        .position(|c| c.name == sym)
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodes_integrate_a_thick_doublet() {
        // The equivalent width ∫(1 − e^{−κ(λ)}) dλ of Na D at 2000 K over 585–595 nm, N·L 1e14–1e20 m⁻²: the
        // window's nodes against a 2e-5 nm grid, within 5e-3 (measured: 3.4e-3 at most with 58 nodes; 4-point
        // panels, 76 nodes, gave 4e-4).
        let sigma = crate::volume::tests::sodium_d_kappa(2000.0);
        let kappa = |lam: f64, n: f64| n * sigma(lam);
        let na = Element::by_symbol("Na").unwrap();
        let d: Vec<Line> = na
            .lines()
            .iter()
            .filter(|l| (585.0..595.0).contains(&l.lambda_nm))
            .copied()
            .collect();
        let centres: Vec<f64> = d.iter().map(|l| l.lambda_nm).collect();
        let d0 = 0.3 * doppler_sigma_nm(588.995, 300.0, 22.99);
        let (lam, wid) = window_nodes(585.0, 595.0, &centres, d0, &[]);
        let total: f64 = wid.iter().sum();
        assert!((total - 10.0).abs() < 1e-3, "{total}");
        for n in [1e14, 1e16, 1e18, 1e20] {
            let q: f64 = lam
                .iter()
                .zip(&wid)
                .map(|(&l, &w)| w * (1.0 - (-kappa(l, n)).exp()))
                .sum();
            let steps = 500_000;
            let h = 10.0 / steps as f64;
            let f: f64 = (0..steps)
                .map(|i| h * (1.0 - (-kappa(585.0 + (i as f64 + 0.5) * h, n)).exp()))
                .sum();
            assert!((q / f - 1.0).abs() < 5e-3, "N·L {n:e}: nodes {q} vs {f}");
        }
    }
}
