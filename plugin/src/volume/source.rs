//! What a physical fire emits over the whole spectrum, for its light's power in watts: the soot's (its absorption
//! times Planck's law, integrated from 10 nm to 1 mm), the atoms' lines and bands, the blue core's bands.

use crate::blackbody::spectral_radiance_si;
use crate::soot::SootOptics;
use crate::species::Element;

/// The fire's emitters, kept for the light's full-spectrum power (physical mode).
#[derive(Debug, Clone)]
pub(crate) struct Source {
    soot: SootOptics,
    alpha: f64,
    /// sootscale × intensity.
    soot_scale: f64,
    intensity: f64,
    /// (element, channel index, m⁻³ per unit).
    species: Vec<(Element, usize, f64)>,
    /// The blue core (a reaction grid): its channel and the power one unit of it emits per unit volume and
    /// solid angle, W m⁻³ sr⁻¹ — over the bins, which hold its CH* and C₂* bands whole.
    reaction: Option<(usize, f64)>,
}

impl Source {
    /// The soot of `soot` optics and dispersion exponent `alpha`, scaled by `sootscale` and `intensity` (the
    /// latter the lines' too), and the species (element, channel, m⁻³ per unit).
    pub(super) fn new(
        soot: SootOptics,
        alpha: f64,
        (sootscale, intensity): (f64, f64),
        species: Vec<(Element, usize, f64)>,
    ) -> Source {
        Source {
            soot,
            alpha,
            soot_scale: sootscale * intensity,
            intensity,
            species,
            reaction: None,
        }
    }
    /// The species' elements with all their lines (the coefficients may hold the visible ones alone).
    pub(super) fn set_elements(&mut self, full: impl IntoIterator<Item = Element>) {
        for ((e, _, _), f) in self.species.iter_mut().zip(full) {
            *e = f;
        }
    }
    /// The blue core's channel and its power per unit, W m⁻³ sr⁻¹.
    pub(super) fn set_reaction(&mut self, ch: usize, per_unit: f64) {
        self.reaction = Some((ch, per_unit));
    }
    /// The emission's scale (`intensity`): the embers' too.
    pub(crate) fn intensity(&self) -> f64 {
        self.intensity
    }

    /// The soot's full-spectrum power per unit density at `t` K, W sr⁻¹ (before `soot_scale`).
    pub(crate) fn soot_power(&self, t: f64) -> f64 {
        let (lo, hi) = (10e-9f64.ln(), 1e-3f64.ln());
        crate::quadrature::gauss_legendre(
            |u| {
                let l = u.exp();
                self.soot.kappa(l * 1e9, 1.0, self.alpha) * spectral_radiance_si(t, l) * l
            },
            lo,
            hi,
            60,
        )
    }

    /// A voxel's full-spectrum power per unit volume and solid angle: density `d` at `t` K, whose soot emits
    /// `soot` ([`soot_power`](Self::soot_power) at `t`), its grids' values by channel `at`.
    pub(crate) fn voxel_power(&self, d: f64, t: f64, soot: f64, at: impl Fn(usize) -> f32) -> f64 {
        let mut v = d * self.soot_scale * soot;
        for (e, ch, scale) in &self.species {
            let nn = at(*ch).max(0.0) as f64 * scale;
            if nn > 0.0 {
                v += nn * self.intensity * line_power(e, t);
            }
        }
        if let Some((ch, per_unit)) = self.reaction {
            v += at(ch).max(0.0) as f64 * per_unit;
        }
        v
    }
}

/// Full line and band emission per unit number density, W·sr⁻¹ (all shipped lines of `e`, and its molecular bands,
/// at T).
fn line_power(e: &Element, t: f64) -> f64 {
    use crate::constants::{BOLTZMANN, PLANCK, SPEED_OF_LIGHT};
    if !(t > 0.0) {
        return 0.0;
    }
    let kt = BOLTZMANN * t;
    let z = e.partition_function(t);
    e.bands().iter().map(|b| b.power(t)).sum::<f64>()
        + e.lines()
            .iter()
            .map(|l| {
                PLANCK * SPEED_OF_LIGHT / (4.0 * std::f64::consts::PI * l.lambda_nm * 1e-9)
                    * l.a_ki
                    * l.g_k as f64
                    * (-l.e_k / kt).exp()
                    / z
            })
            .sum::<f64>()
}
