//! The medium level's point query: σ_a, σ_s, the emitted radiance Le and the emission coefficient j = σ_a Le at
//! a point, at the host's wavelengths and time — the closed forms at λ (soot's κ(λ) times Planck's B(λ, T);
//! pbrt-v4's spectra and its peak-normalised blackbody), not the volume's bins, so that a host sampling its own
//! wavelengths (pbrt-v4's and Mitsuba 3's four per path) sees the fire the bins integrate.
//!
//! What the closed forms cannot say is refused, naming it: atomic lines and the blue core (narrow lines between a
//! host's sampled wavelengths want their own treatment), art direction (a tint, a colour ramp), a scatter colour
//! grid, diffusion, refraction and embers (the features a host learns first, `FireVolume::features`).

use super::settings::{Emission, SpectrumFn};
use super::FireVolume;
use crate::blackbody::{spectral_radiance, WIEN};
use crate::soot::SootOptics;
use crate::Error;
use glam::DVec3;

/// What the point query evaluates, per unit density, at any wavelength.
#[derive(Clone)]
pub(super) enum PointModel {
    /// Pegoraro & Parker's soot: σ_a = smokescale·sootscale·κ(λ)·d, σ_s = smokescale·sigma_s(λ)·d,
    /// j = intensity·sootscale·κ(λ)·B(λ, T)·d.
    Physical {
        optics: SootOptics,
        alpha: f64,
        sootscale: f64,
        smokescale: f64,
        intensity: f64,
        sigma_s: Option<SpectrumFn>,
    },
    /// pbrt-v4's grid media: σ_a = scale·sigma_a(λ)·d, σ_s = scale·sigma_s(λ)·d, Le = Lescale·B(λ, T)/B(λ_max, T)
    /// above 100 K (or Lescale·Le(λ) without a temperature grid).
    Pbrt {
        scale: f64,
        sigma_a: SpectrumFn,
        sigma_s: Option<SpectrumFn>,
        le_scale: f64,
        le: Option<SpectrumFn>,
    },
    /// The point query is refused: why.
    Refused(String),
}

impl std::fmt::Debug for PointModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PointModel::Physical { .. } => write!(f, "PointModel::Physical"),
            PointModel::Pbrt { .. } => write!(f, "PointModel::Pbrt"),
            PointModel::Refused(why) => write!(f, "PointModel::Refused({why})"),
        }
    }
}

impl PointModel {
    /// The model of a volume built from `set`; `refused` names what the volume holds that it cannot express.
    pub(super) fn new(
        emission: &Emission,
        sigma_s: Option<&SpectrumFn>,
        refused: Option<String>,
    ) -> PointModel {
        if let Some(why) = refused {
            return PointModel::Refused(why);
        }
        match emission {
            Emission::Physical {
                optics,
                alpha,
                sootscale,
                intensity,
                smokescale,
                ..
            } => PointModel::Physical {
                optics: optics.clone(),
                alpha: *alpha,
                sootscale: *sootscale,
                smokescale: *smokescale,
                intensity: *intensity,
                sigma_s: sigma_s.cloned(),
            },
            Emission::Pbrt {
                scale,
                sigma_a,
                le_scale,
                le,
            } => PointModel::Pbrt {
                scale: *scale,
                sigma_a: sigma_a.clone(),
                sigma_s: sigma_s.cloned(),
                le_scale: *le_scale,
                le: le.clone(),
            },
        }
    }
}

/// The coefficients at one point and wavelength ([`FireVolume::point`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PointCoefficients {
    /// σ_a, medium units⁻¹.
    pub sigma_a: f64,
    /// σ_s, medium units⁻¹.
    pub sigma_s: f64,
    /// The emitted radiance Le (j/σ_a; with an emission grid where σ_a = 0, 0 — j still emits).
    pub le: f64,
    /// The emission coefficient j (radiance per unit length).
    pub j: f64,
}

impl FireVolume {
    /// σ_a, σ_s, Le and j at medium-space point `p` at `time` (frames from the grids' time; motion blur
    /// displaces the lookups), at each of `lambdas` (nm) into `out` — the closed forms at λ, not the bins. An
    /// error when the volume holds what they cannot express (`PointModel`'s refusals).
    pub fn point(
        &self,
        p: DVec3,
        time: f64,
        lambdas: &[f64],
        out: &mut [PointCoefficients],
    ) -> Result<(), Error> {
        let refuse = |what: String| Error::Unsupported {
            file: "volume".into(),
            what: format!("point coefficients of a volume with {what}"),
            hint: "its whole-ray queries (integrate, transmittance, sample_scatter) render it"
                .into(),
        };
        let model = match self.model.point_model() {
            PointModel::Refused(why) => return Err(refuse(why.clone())),
            m => m,
        };
        let q = self.advected(time).map_or(p, |a| a.displaced(p));
        out.iter_mut()
            .for_each(|o| *o = PointCoefficients::default());
        let Some((_, super::Lookup { d, t, les, emits })) = self.lookup(q) else {
            return Ok(());
        };
        let e = self.emitting(d, les);
        for (o, &l) in out.iter_mut().zip(lambdas) {
            let (sa, ss, j) = match model {
                PointModel::Physical {
                    optics,
                    alpha,
                    sootscale,
                    smokescale,
                    intensity,
                    sigma_s,
                } => {
                    let k = optics.kappa(l, 1.0, *alpha) * sootscale;
                    let j = if emits && t > 0.0 {
                        e * intensity * k * spectral_radiance(t, l)
                    } else {
                        0.0
                    };
                    (
                        d * smokescale * k,
                        d * smokescale * sigma_s.as_ref().map_or(0.0, |f| f(l)),
                        j,
                    )
                }
                PointModel::Pbrt {
                    scale,
                    sigma_a,
                    sigma_s,
                    le_scale,
                    le,
                } => {
                    let a = scale * sigma_a(l);
                    let le_l = match le {
                        Some(f) => le_scale * f(l),
                        None if t > 100.0 => {
                            le_scale * spectral_radiance(t, l)
                                / spectral_radiance(t, WIEN / t * 1e9)
                        }
                        None => 0.0,
                    };
                    (
                        d * a,
                        d * scale * sigma_s.as_ref().map_or(0.0, |f| f(l)),
                        if emits { e * a * le_l } else { 0.0 },
                    )
                }
                PointModel::Refused(_) => (0.0, 0.0, 0.0),
            };
            *o = PointCoefficients {
                sigma_a: sa,
                sigma_s: ss,
                le: if sa > 0.0 { j / sa } else { 0.0 },
                j,
            };
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::slab_volume;
    use super::*;
    use crate::params::Param;

    /// The point query's mean over each 10 nm bin (400 wavelengths across it) against the volume's bin value.
    fn bins_agree(v: &FireVolume, what: &str) {
        let p = DVec3::new(0.4, 0.6, 0.5);
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        v.coefficients(p, &mut sa, &mut ss, &mut j);
        let n = 400;
        for k in 0..c {
            let lambdas: Vec<f64> = (0..n)
                .map(|i| 400.0 + 10.0 * k as f64 + 10.0 * (i as f64 + 0.5) / n as f64)
                .collect();
            let mut out = vec![PointCoefficients::default(); n];
            v.point(p, 0.0, &lambdas, &mut out).unwrap();
            let mean =
                |f: &dyn Fn(&PointCoefficients) -> f64| out.iter().map(f).sum::<f64>() / n as f64;
            // (pbrt-v4's j is σ_a(λ)·Le(λ) at each wavelength; its bins hold the product of the bin means, which
            // differs by their covariance over the bin — 5e-4 here — so there the product is compared.)
            let j_mean = if what == "pbrt" {
                mean(&|o| o.sigma_a) * mean(&|o| o.le)
            } else {
                mean(&|o| o.j)
            };
            for (name, got, want) in [
                ("sigma_a", mean(&|o| o.sigma_a), sa[k]),
                ("sigma_s", mean(&|o| o.sigma_s), ss[k]),
                ("j", j_mean, j[k]),
            ] {
                assert!(
                    (got - want).abs() <= 1e-4 * want.abs() + 1e-300,
                    "{what}, bin {k}, {name}: {got} at the wavelengths, {want} in the bin"
                );
            }
            // Le is j/σ_a at each wavelength: soot at T is a blackbody's emitter (Kirchhoff).
            for (o, &l) in out.iter().zip(&lambdas) {
                assert!((o.le * o.sigma_a - o.j).abs() <= 1e-12 * o.j.abs());
                if what == "physical" {
                    let b = spectral_radiance(1800.0, l);
                    assert!(
                        (o.le - b).abs() <= 1e-9 * b,
                        "{l} nm: Le {} against B {b}",
                        o.le
                    );
                }
            }
        }
    }

    #[test]
    fn point_coefficients_at_the_hosts_wavelengths_average_to_the_bins() {
        // Soot at 1800 K (σ_s from a spectrum), and pbrt-v4's grid with its peak-normalised blackbody: the
        // closed forms at λ, averaged over each bin, are the bins' values; the soot's Le is Planck's B(λ, T).
        let physical = slab_volume(
            1e-6,
            1800.0,
            vec![Param::floats("sigma_s", &[400.0, 1e4, 700.0, 3e4])],
        );
        bins_agree(&physical, "physical");
        let pbrt = slab_volume(
            0.5,
            1800.0,
            vec![
                Param::string("mode", "pbrt"),
                Param::floats("sigma_a", &[400.0, 2.0, 700.0, 1.0]),
                Param::float("Lescale", 3.0),
            ],
        );
        bins_agree(&pbrt, "pbrt");
    }

    #[test]
    fn what_the_closed_forms_cannot_say_is_refused_by_name() {
        let v = slab_volume(1e-6, 1800.0, vec![Param::rgb("tint", [1.0, 0.5, 0.2])]);
        let mut out = [PointCoefficients::default(); 1];
        let e = v
            .point(DVec3::splat(0.5), 0.0, &[589.0], &mut out)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("art direction") && e.contains("whole-ray queries"),
            "{e}"
        );
    }
}
