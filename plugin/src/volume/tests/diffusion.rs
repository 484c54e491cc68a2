//! Diffusion against a path-traced smoke.

use super::*;

#[test]
fn diffusion_approaches_the_path_traced_smoke() {
    // A glowing, strongly scattering cube (1 m, 1500 K soot, albedo 0.9; a 4-voxel grid, so half-voxel steps of
    // 12.5 cm): the radiance through its centre with `multiplescattering "diffusion"` (the march, the scattered
    // light as emission) against the same cube path traced (scattering events, isotropic; 3000 paths, seeded),
    // and against no in-scattering at all. Measured (the 555 nm bin), optical thickness 1.1 / 10.5 / 32 / 105:
    // diffusion −7.7 / −2.2 / −2.2 / −7.9 %, none −36 / −82 / −83 / −83 %. Before the march sampled the
    // scattered light per diffusion cell and per optical depth, and before the grid's faces held Marshak's
    // value: −7.7 / +1.2 / +21 / +59 % (the light that leaves a thick smoke comes from its first optical depth,
    // which one sample 6 cm deep, or the first cell's centre value held out to the face, overstates).
    for fv in [1e-8, 1e-7, 3e-7, 1e-6] {
        let base = slab_volume(fv, 1500.0, vec![]);
        let c = base.channels();
        let (mut sa, mut ss, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        base.coefficients(DVec3::splat(0.5), &mut sa, &mut ss, &mut j);
        // σ_s per unit density so that σ_s = 9 σ_a in the middle bin.
        let sigma_s = 9.0 * sa[15] / fv;
        let with = |ms: &str| {
            let mut e = vec![
                Param::float("sigma_s", sigma_s),
                Param::string("multiplescattering", ms),
            ];
            if ms == "pathtraced" {
                e.push(Param::string("integrator", "delta"));
            }
            slab_volume(fv, 1500.0, e)
        };
        let (traced, diffused) = (with("pathtraced"), with("diffusion"));
        assert!(traced.scatters() && !diffused.scatters());
        let ray = ray_x(1);
        let mc = random_walk_radiance(&traced, &ray, 3000);
        let (ld, _) = run(&diffused, &ray);
        let (lm, _) = run(
            &slab_volume(fv, 1500.0, vec![Param::float("sigma_s", sigma_s)]),
            &ray,
        );
        let ch = 15;
        let (e_d, e_none) = (ld[ch] / mc[ch] - 1.0, lm[ch] / mc[ch] - 1.0);
        assert!(
            e_d.abs() < 0.1 && e_none < -0.3,
            "τ {:.1}: path traced {}, diffusion {e_d:+.3}, none {e_none:+.3}",
            10.0 * sa[ch],
            mc[ch]
        );
    }
}
