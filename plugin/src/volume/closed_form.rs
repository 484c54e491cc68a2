//! The volume's coefficients in closed form over its fields, for a host that textures the fire (Dr.Jit, a GPU):
//! three fields on the dataset's lattice — soot density d, temperature T and the Lescale or emission grid's value
//! les — and tables over T per channel, so that at any point
//!
//! - σ_a = d · A(T), σ_s = d · S, j = e · J(T) where T > t_emit (else 0), e = d · les (or les with an emission
//!   grid),
//! - d, T, les the voxels' values interpolated trilinearly, zero past the outer samples (a zero layer around the
//!   lattice), nothing outside the volume's bounds,
//! - A and J linear between rows T_r = r · dt, r = clamp(T / dt, 0, rows − 1) —
//!
//! which is how the volume itself evaluates them ([`FireVolume::coefficients`]): a host that interpolates the
//! fields, not the coefficients, sees the fire the plugin renders. (Interpolating j between voxel centres instead
//! of T brightens a flame: Planck's law is convex in T — 0.8 % on the campfire's brightest line of sight, and
//! baked bins add their own bias at a host's wavelengths.)
//!
//! What is not this form is refused, naming it: atomic lines and the blue core, a scatter colour grid, diffusion,
//! refraction, embers, motion blur, a dataset interpolated other than trilinearly.

use super::FireVolume;
use crate::grid::Interpolation;
use crate::Error;
use glam::DVec3;

/// The tables of [`FireVolume::closed_form`], read from the volume's own (no copy).
#[derive(Debug, Clone, Copy)]
pub struct ClosedForm<'a> {
    /// The volume's channels.
    pub channels: usize,
    /// Rows of the T tables.
    pub rows: usize,
    /// Kelvin between rows (row r holds T = r · dt).
    pub dt: f64,
    /// The fire emits where T > t_emit (pbrt mode's 100 K; −∞ without a temperature grid, 0 otherwise).
    pub t_emit: f64,
    /// e = les (an emission grid) rather than d · les.
    pub emission_grid: bool,
    model: &'a super::parts::Model,
}

impl ClosedForm<'_> {
    /// σ_a per unit density at row `r`, channel `k`.
    pub fn absorption(&self, r: usize, k: usize) -> f32 {
        match self.model.a_t() {
            // (The rgb mode's table has the emission's rows: one build of both.)
            Some(tab) => tab.value(r.min(tab.rows() - 1), k),
            None => self.model.a()[k] as f32,
        }
    }
    /// σ_s per unit density, channel `k`.
    pub fn scattering(&self, k: usize) -> f32 {
        self.model.s()[k] as f32
    }
    /// j per unit of e at row `r`, channel `k`.
    pub fn emission(&self, r: usize, k: usize) -> f32 {
        self.model.j().value(r, k)
    }
}

impl FireVolume {
    /// The tables of the closed form (see the module), or why the volume is not of that form.
    pub fn closed_form(&self) -> Result<ClosedForm<'_>, Error> {
        let species = (
            !self.grids.species().is_empty(),
            "atomic lines or the blue core",
        );
        let rest = [
            (
                self.model.scatter_color().is_some(),
                "a scatter colour grid",
            ),
            (
                self.grids.ds().interpolation() != Interpolation::Trilinear,
                "a dataset interpolated other than trilinearly",
            ),
        ];
        let mut refused = std::iter::once(species)
            .chain(self.layers.present())
            .chain(rest);
        if let Some((_, what)) = refused.find(|(on, _)| *on) {
            return Err(Error::Unsupported {
                file: "volume".into(),
                what: format!("the closed form of a volume with {what}"),
                hint: "its coefficients at points (volume_coefficients) or its whole-ray queries render it"
                    .into(),
            });
        }
        Ok(ClosedForm {
            channels: self.channels(),
            rows: self.model.j().rows(),
            dt: self.model.j().dt(),
            t_emit: if self.grids.temperature().is_none() {
                f64::NEG_INFINITY
            } else {
                self.model.t_emit()
            },
            emission_grid: self.grids.emission_grid(),
            model: &self.model,
        })
    }

    /// The fields the closed form reads at medium-space point `p`: [d, T, les] as the volume interpolates them
    /// (d and les clamped at 0, les 1 without a grid); zeros outside. At a voxel centre, the voxel's own values.
    pub fn fields(&self, p: DVec3) -> [f64; 3] {
        match self.lookup(p) {
            Some((_, l)) => [l.d, l.t, l.les],
            None => [0.0; 3],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::tests::blob_volume;
    use super::*;
    use crate::params::Param;

    /// σ_a, σ_s and j from the closed form at `p`, as a host evaluates it from interpolated fields.
    fn from_closed_form(v: &FireVolume, cf: &ClosedForm<'_>, p: DVec3) -> Vec<[f64; 3]> {
        let [d, t, les] = v.fields(p);
        let f = (t / cf.dt).clamp(0.0, (cf.rows - 1) as f64);
        let r = (f as usize).min(cf.rows - 2);
        let fr = f - r as f64;
        let lerp = |tab: &dyn Fn(usize, usize) -> f32, k: usize| {
            let a = tab(r, k) as f64;
            a + fr * (tab(r + 1, k) as f64 - a)
        };
        let e = if cf.emission_grid { les } else { d * les };
        (0..cf.channels)
            .map(|k| {
                [
                    d * lerp(&|r, k| cf.absorption(r, k), k),
                    d * cf.scattering(k) as f64,
                    if t > cf.t_emit {
                        e * lerp(&|r, k| cf.emission(r, k), k)
                    } else {
                        0.0
                    },
                ]
            })
            .collect()
    }

    fn agrees(v: &FireVolume, what: &str) {
        let cf = v.closed_form().unwrap_or_else(|e| panic!("{what}: {e}"));
        let c = v.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let mut rng = firemedium_core::rng::Rng::new(7);
        let mut emitting = 0;
        for _ in 0..2000 {
            // Points over the box (2 × 1.8 × 2.2) and a little past it.
            let p = DVec3::new(
                rng.next_f64() * 2.1 - 0.05,
                rng.next_f64() * 1.9 - 0.05,
                rng.next_f64() * 2.3 - 0.05,
            );
            v.coefficients(p, &mut sa, &mut ss, &mut j);
            let got = from_closed_form(v, &cf, p);
            emitting += usize::from(j.iter().any(|&x| x > 0.0));
            for k in 0..c {
                for (name, g, w) in [
                    ("sigma_a", got[k][0], sa[k]),
                    ("sigma_s", got[k][1], ss[k]),
                    ("j", got[k][2], j[k]),
                ] {
                    assert!(
                        (g - w).abs() <= 1e-5 * w.abs() + 1e-30,
                        "{what}, {p}, channel {k}, {name}: {g} from the closed form, {w} from the volume"
                    );
                }
            }
        }
        assert!(emitting > 500, "{what}: {emitting} of 2000 points emit");
    }

    #[test]
    fn the_closed_form_is_the_volumes_coefficients_at_every_point() {
        // Soot in spectral bins, in the rgb bands (σ_a over T), pbrt-v4's grid with a Lescale grid, and
        // scattering.
        agrees(&blob_volume(vec![], false), "physical");
        agrees(
            &blob_volume(vec![Param::string("colormode", "rgb")], false),
            "rgb",
        );
        agrees(
            &blob_volume(vec![Param::string("mode", "pbrt")], false),
            "pbrt",
        );
        agrees(
            &blob_volume(
                vec![Param::floats("sigma_s", &[400.0, 1e4, 700.0, 3e4])],
                false,
            ),
            "scattering",
        );
        // A voxel centre's fields are the voxel's values (the lattice a host textures).
        let v = blob_volume(vec![], false);
        let [d, t, _] = v.fields(DVec3::new(
            2.0 * 30.5 / 40.0,
            1.8 * 10.5 / 36.0,
            2.2 * 5.5 / 44.0,
        ));
        assert!(
            (d - 1e-6).abs() < 1e-12 && (t - 1500.0).abs() < 1e-3,
            "{d} {t}"
        );
    }

    #[test]
    fn what_is_not_the_closed_form_is_refused_by_name() {
        let e = blob_volume(vec![], true)
            .closed_form()
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("atomic lines") && e.contains("volume_coefficients"),
            "{e}"
        );
        let e = blob_volume(vec![Param::string("interpolation", "nearest")], false)
            .closed_form()
            .unwrap_err()
            .to_string();
        assert!(e.contains("trilinearly"), "{e}");
    }
}
