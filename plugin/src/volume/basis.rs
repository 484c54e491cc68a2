//! The channel basis: how spectral functions become a volume's channels — bin means over spectral bins (8-node
//! Gauss–Legendre panels, optionally split at the soot table's kinks), or XYZ bands with the CIE 1931 CMFs as
//! weights (absorption as the band's Planck mean at T, emission with K = 683 lm/W, or 1/∫ȳ in pbrt mode), and
//! each channel's XYZ weights.

use super::ColorMode;
use crate::blackbody::spectral_radiance;
use crate::cie::{self, cmf_table::CMF, LineSplit};
use crate::species::Element;
use crate::spectrum::SpectralGrid;
use glam::DVec3;

/// Channel basis: projections of spectral functions onto the channels.
#[derive(Debug, Clone)]
pub(super) struct Basis {
    mode: ColorMode,
    /// Photometric factor: 683 lm/W (physical) or 1/∫ȳ (pbrt).
    k: f64,
    /// Spectral bins share each atomic line with a neighbour so the film sees its own wavelength's luminance
    /// (`linecolour "ownwavelength"`, [`LineSplit`]).
    line_split: bool,
}

impl Basis {
    pub(super) fn new(mode: ColorMode, k: f64, line_split: bool) -> Basis {
        Basis {
            mode,
            k,
            line_split,
        }
    }
    pub(super) fn mode(&self) -> ColorMode {
        self.mode
    }
    /// Photometric factor: 683 lm/W (physical) or 1/∫ȳ (pbrt).
    pub(super) fn k(&self) -> f64 {
        self.k
    }
    /// Whether spectral bins share each atomic line with a neighbour (`linecolour "ownwavelength"`).
    pub(super) fn line_split(&self) -> bool {
        self.line_split
    }
    pub(super) fn channels(&self) -> usize {
        match self.mode {
            ColorMode::Spectral(g) => g.count(),
            ColorMode::Rgb => 3,
        }
    }
    /// Absorption-like: per channel mean of f (bin mean, or band-weighted mean).
    pub(super) fn absorb(&self, f: &dyn Fn(f64) -> f64) -> Vec<f64> {
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
    pub(super) fn emit(&self, f: &dyn Fn(f64) -> f64) -> Vec<f64> {
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
    pub(super) fn nodes(&self) -> Nodes {
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
    pub(super) fn absorb_split(&self, f: &dyn Fn(f64) -> f64, kinks: &[f64]) -> Vec<f64> {
        match self.mode {
            ColorMode::Spectral(g) => g.bin_average_split(f, kinks, 1),
            ColorMode::Rgb => self.absorb(f),
        }
    }
    /// The nodes of [`absorb_split`](Self::absorb_split)'s rule (the rgb bands' as [`nodes`](Self::nodes)).
    pub(super) fn nodes_split(&self, kinks: &[f64]) -> Nodes {
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
    pub(super) fn emit_planck(&self, nodes: &Nodes, g: &[f64], t: f64) -> Vec<f64> {
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
    pub(super) fn soot_rgb_rows(
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
    /// What [`lines`](Self::lines) needs besides the element: the rgb bands' fine grid and its CMF weights, and
    /// the spectral bins' line split.
    pub(super) fn line_aux(&self) -> LineAux {
        let (fine, fine_w) = fine_cmf();
        let split = match self.mode {
            ColorMode::Spectral(g) if self.line_split => Some(LineSplit::new(&g)),
            _ => None,
        };
        LineAux {
            fine,
            fine_w,
            split,
        }
    }
    /// Per-unit-N line cross-sections of `e` at T: (σ̂ m², ĵ per channel). Spectral bins take each line's box
    /// shared between two bins so that the film sees it at its own wavelength's luminance ([`LineSplit`]).
    pub(super) fn lines(&self, e: &Element, t: f64, aux: &LineAux) -> (Vec<f64>, Vec<f64>) {
        let (fine, fine_w) = (&aux.fine, &aux.fine_w);
        match self.mode {
            ColorMode::Spectral(g) => {
                let (mut sa, mut j) = (vec![0.0; g.count()], vec![0.0; g.count()]);
                match &aux.split {
                    Some(split) => e.add_split_cross_sections(t, &g, split, &mut sa, &mut j),
                    None => e.add_binned_cross_sections(t, &g, &mut sa, &mut j),
                }
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
    pub(super) fn xyz(&self) -> Vec<DVec3> {
        match self.mode {
            ColorMode::Spectral(g) => cie::bin_weights(&g)
                .into_iter()
                .map(|w| w / crate::constants::LUMINOUS_EFFICACY * self.k)
                .collect(),
            ColorMode::Rgb => vec![DVec3::X, DVec3::Y, DVec3::Z],
        }
    }
}

/// What [`Basis::lines`] reads besides an element (built once per volume: the split integrates the CMFs).
#[derive(Debug, Clone)]
pub(super) struct LineAux {
    fine: SpectralGrid,
    fine_w: Vec<DVec3>,
    split: Option<LineSplit>,
}

/// Quadrature nodes of a basis (see [`Basis::nodes`]).
pub(super) struct Nodes {
    pub(super) lambda: Vec<f64>,
    terms: Vec<(usize, usize, f64)>,
}

/// The 1 nm grid over the CMFs that rgb mode bins lines on, and each bin's ∫ x̄ȳz̄.
pub(super) fn fine_cmf() -> (SpectralGrid, Vec<DVec3>) {
    let fine = SpectralGrid::new(380.0, 780.0, 400).unwrap_or_default();
    let w = (0..400)
        .map(|i| cie::cmf_integral(380.0 + i as f64, 381.0 + i as f64))
        .collect();
    (fine, w)
}
