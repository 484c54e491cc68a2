//! The fire volume's march along curved rays (P&P §3.7): the index field baked once per volume
//! ([`Refraction::build`]), and [`integrate_exit`], which follows a ray through it — by default one Verlet step
//! per march step, with the medium sampled at the step's midpoint where the step looked up n and ∇n; with
//! `refractionintegrator "rk4"`, the RK4 reference path first, then the march along it at the volume's own step.

use super::{FireVolume, Ray, Stepper, MAX_STEPS};
use crate::ciddor::Air;
use crate::grid::Grid;
use crate::refraction::{trace, trace_verlet, IndexGrid, Steps};
use glam::DVec3;

/// The refraction state of a volume: the baked index field and how rays are stepped through it.
#[derive(Debug, Clone)]
pub(crate) struct Refraction {
    field: IndexGrid,
    steps: Steps,
    /// The RK4 reference integrator instead of the Verlet march.
    rk4: bool,
}

impl Refraction {
    /// Bytes the baked index field holds.
    pub(crate) fn bytes(&self) -> usize {
        self.field.bytes()
    }

    /// Bakes the index field of `air` heated to the `temperature` grid over `bounds`, at `wavelength` nm with
    /// (n − 1) exaggerated by `scale`, for a march of `step` over voxels of edge `voxel` (medium units), within
    /// `budget` bytes (else `Err` with the bytes the field would need).
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn build(
        temperature: &Grid,
        bounds: [DVec3; 2],
        air: &Air,
        (wavelength, scale): (f64, f64),
        rk4: bool,
        step: f64,
        voxel: f64,
        budget: u64,
    ) -> Result<Refraction, u64> {
        let [b0, b1] = bounds;
        let field =
            IndexGrid::from_temperature(temperature, b0, b1, wavelength, air, scale, budget)?;
        let steps = if rk4 {
            // RK steps of at most a voxel, each ending at the next plane of samples (one trilinear cell).
            Steps {
                h_max: step.min(voxel),
                h_min: 1e-6 * voxel,
                tol: 1e-6 * voxel,
                ..Default::default()
            }
        } else {
            // The march's steps (halved where the ray would turn by more than max_turn in one).
            Steps {
                h_max: step,
                h_min: 1e-6 * voxel,
                ..Default::default()
            }
        };
        Ok(Refraction { field, steps, rk4 })
    }
}

/// Radiance `l` and transmittance `t` along the curved ray, and where it leaves: (point, unit direction,
/// parameter = entry parameter + arc length / |d|). The ray curves inside the index field's box (the grid's, two
/// voxels wider).
pub(crate) fn integrate_exit(
    v: &FireVolume,
    rf: &Refraction,
    ray: &Ray,
    l: &mut [f64],
    t: &mut [f64],
) -> (DVec3, DVec3, f64) {
    let Refraction { field, steps, rk4 } = rf;
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
    let step = v.step_length();
    if *rk4 {
        // The curved path as a polyline of RK steps; then the march over it at the volume's own step (so the
        // coefficients are evaluated as often as along a straight ray, not once per RK step).
        let mut path: Vec<(DVec3, f64)> = vec![(ray.o + ray.d * a, 0.0)];
        let exit = trace(
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
        let ds = if total / step > MAX_STEPS {
            total / MAX_STEPS
        } else {
            step
        };
        let mut stepper = Stepper::new(v, false);
        let mut rng = ray.rng();
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
            if stepper.step(pa + (pb - pa) * f, s1 - s0, l, t) {
                break;
            }
            s0 = s1;
            next += ds;
        }
        return (exit.x, exit.dir, a + exit.s / speed);
    }
    // One Verlet step per march step: the medium is evaluated at the step's midpoint, where the step looked up
    // n and ∇n, so a curved ray costs one index lookup per sample more than a straight one.
    let diag = (c1 - c0).length();
    let ds = if diag / step > MAX_STEPS {
        diag / MAX_STEPS
    } else {
        step
    };
    let mut rng = ray.rng();
    let first = rng.next_f64() * ds;
    let mut opaque = false;
    let mut stepper = Stepper::new(v, true);
    let exit = trace_verlet(
        field,
        ray.o + ray.d * a,
        dir,
        (ray.t1 - a) * speed,
        ds,
        first,
        steps,
        |mid, h| {
            // (The padding around the grid bends rays but holds no medium; nor do empty bricks.)
            if !opaque && v.holds_medium(mid) {
                opaque = stepper.step(mid, h, l, t);
            }
        },
        |p| !inside(p),
    );
    stepper.finish(l, t);
    (exit.x, exit.dir, a + exit.s / speed)
}

#[cfg(test)]
mod tests {
    //! Curved rays through a fire volume: built only when asked, bent away from heat, shifted but not turned by
    //! a uniformly hot box, finite across extreme index jumps.
    use super::*;
    use crate::params::Param;

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
            first: None,
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
        // 16³ voxels, two ambient rings and a ring of zeros the lookup reads beyond them: δ and ∇δ per voxel
        // (dense: copies per brick would take more for a grid this full).
        assert_eq!(table.bytes, 22 * 22 * 22 * 16);
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
                    first: None,
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
