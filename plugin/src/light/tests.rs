//! The fire light against closed forms: sampled and evaluated densities, power, the line estimate.

use super::*;
use crate::params::Param;
use crate::rng::Rng;
use build::escape_fractions;

fn sphere_fire(n: usize, r: f64, fv: f64, t: f64, extra: Vec<Param>) -> Arc<FireVolume> {
    // A uniform sphere of grey soot (alpha 0, constant n, k) in an n³ grid over [−1, 1]³, nearest lookup.
    let mut dens = Vec::with_capacity(n * n * n);
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                dens.push(if c(i).powi(2) + c(j).powi(2) + c(k).powi(2) < r * r {
                    fv
                } else {
                    0.0
                });
            }
        }
    }
    let mut list = vec![
        Param::floats("density", &dens),
        Param::floats("temperature", &vec![t; n * n * n]),
        Param::int("nx", n as i64),
        Param::int("ny", n as i64),
        Param::int("nz", n as i64),
        Param::point3("p0", [-1.0; 3]),
        Param::point3("p1", [1.0; 3]),
        Param::string("interpolation", "nearest"),
        Param::string("fuel", "custom"),
        Param::floats("fuelnk", &[500.0, 1.6, 0.5]),
        Param::float("alpha", 0.0),
    ];
    list.extend(extra);
    Arc::new(FireVolume::new(&list).unwrap())
}

#[test]
fn sampled_pdf_equals_evaluated_pdf() {
    for cell in [1, 2, 4, 8] {
        let light = FireLight::with_cell(
            sphere_fire(23, 0.8, 1e-6, 1500.0, vec![]),
            Weighting::Luminance,
            cell,
        )
        .unwrap();
        let mut rng = Rng::new(3);
        for _ in 0..20_000 {
            let u = [(); 6].map(|_| rng.next_f64());
            let s = light.sample(u);
            let p = light.pdf(s.point);
            assert!(
                s.pdf > 0.0 && ((p - s.pdf) / s.pdf).abs() < 1e-5,
                "cell {cell}: {} vs {p} at {}",
                s.pdf,
                s.point
            );
        }
    }
}

#[test]
fn cells_are_sampled_in_proportion_to_their_weights() {
    // The brick CDF then the scan inside the brick: 400 000 samples of a 24³ sphere fire, per cell size;
    // every cell with an expected count of 50 or more is drawn within 5σ of it, none without weight is.
    for cell in [1, 4] {
        let light = FireLight::with_cell(
            sphere_fire(24, 0.8, 1e-6, 1500.0, vec![]),
            Weighting::Power,
            cell,
        )
        .unwrap();
        let n = 400_000;
        let off = light.topo.offset();
        let mut counts = std::collections::HashMap::new();
        let mut rng = Rng::new(11);
        for _ in 0..n {
            let s = light.sample([(); 6].map(|_| rng.next_f64()));
            let v = ((s.point - DVec3::splat(-1.0)) / light.voxel).floor();
            let q = [v.x, v.y, v.z].map(|x| x as usize);
            *counts
                .entry([0, 1, 2].map(|a| (q[a] + off[a]) / cell))
                .or_insert(0usize) += 1;
        }
        let mut checked = 0;
        let m = (24 + 8) / cell;
        for k in 0..m {
            for j in 0..m {
                for i in 0..m {
                    let p = light.cell_weight([i, j, k]) / light.total;
                    let want = p * n as f64;
                    let got = counts.get(&[i, j, k]).copied().unwrap_or(0) as f64;
                    if p == 0.0 {
                        assert_eq!(got, 0.0, "cell {i} {j} {k} has no weight");
                    } else if want >= 50.0 {
                        let sigma = (want * (1.0 - p)).sqrt();
                        assert!(
                            (got - want).abs() < 5.0 * sigma,
                            "cell size {cell}, cell {i} {j} {k}: {got} vs {want}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        let total: usize = counts.values().sum();
        assert_eq!(total, n);
        assert!(checked > 1000 / (cell * cell * cell), "{checked}");
    }
}

#[test]
fn the_parameter_table_states_the_lights_defaults() {
    let default = |name: &str| {
        crate::light::params::LIGHT
            .params
            .iter()
            .find(|p| p.name == name)
            .map(|p| p.default)
    };
    assert_eq!(default("cell"), Some(DEFAULT_CELL.to_string().as_str()));
    let line = LineEstimate::default();
    assert_eq!(
        default("linestep"),
        Some(line.step_voxels.to_string().as_str())
    );
    assert_eq!(
        default("linecorrection"),
        Some(line.correction.to_string().as_str())
    );
}

#[test]
fn the_escape_fraction_is_e_to_the_minus_tau_along_the_axes() {
    // A row of four bricks along x (1 m each) with extinctions 0, 1, 2, 0 m⁻¹, one brick thick in y and z:
    // brick 1 sees τ = 0.5 toward −x (its own half), 0.5 + 2 toward +x, 0.5 up, down and sideways.
    let topo = crate::grid::Topology::build_offset([32, 8, 8], [0; 3], |_| true).unwrap();
    let bricks = [[0, 0, 0], [1, 0, 0], [2, 0, 0], [3, 0, 0]];
    let f = escape_fractions(&topo, &bricks, &[0.0, 1.0, 2.0, 0.0], DVec3::ONE, 1 << 20).unwrap();
    let e = |t: f64| (-t).exp();
    let want = [
        (1.0 * 5.0 + e(3.0)) / 6.0,
        (e(0.5) * 5.0 + e(2.5)) / 6.0,
        (e(1.0) * 4.0 + e(2.0) + e(1.0)) / 6.0,
        (5.0 + e(3.0)) / 6.0,
    ];
    for k in 0..4 {
        assert!(
            (f[k] - want[k]).abs() < 1e-6,
            "brick {k}: {} vs {}",
            f[k],
            want[k]
        );
    }
    // A box of bricks larger than the budget is refused, not allocated.
    assert!(escape_fractions(&topo, &bricks, &[0.0; 4], DVec3::ONE, 16).is_none());
}

#[test]
fn escaping_weights_favour_the_voxels_whose_light_leaves() {
    // A thick soot ball (κ ≈ 2.6 m⁻¹, τ ≈ 1.3 per brick of ½ m): the escaping weights, over the power weights, are lower at the
    // centre than near the rim (bricks of 8³ voxels: the rim brick is an outer one on two axes); in a thin ball they are the power weights to within the escape (e^{−τ} ≈ 1).
    let ratio = |fv: f64, v: [usize; 3]| {
        let vol = sphere_fire(32, 0.9, fv, 1500.0, vec![]);
        let p = FireLight::with_cell(vol.clone(), Weighting::Power, 1).unwrap();
        let e = FireLight::with_cell(vol, Weighting::Escaping, 1).unwrap();
        let off = p.topo.offset();
        let q = [0, 1, 2].map(|a| v[a] + off[a]);
        (
            e.cell_weight(q) / p.cell_weight(q),
            e.power_w() / p.power_w(),
        )
    };
    let (centre, same_power) = ratio(3e-7, [16, 16, 16]);
    let (rim, _) = ratio(3e-7, [6, 6, 16]);
    assert_eq!(same_power, 1.0, "the light's power is what it emits");
    assert!(centre < 0.75 * rim, "centre {centre}, rim {rim}");
    assert!(centre >= ESCAPE_FLOOR * 0.999, "{centre}");
    let (thin, _) = ratio(1e-10, [16, 16, 16]);
    assert!((thin - 1.0).abs() < 1e-3, "{thin}");
}

#[test]
fn the_light_is_the_same_on_one_thread_and_on_four() {
    // The weights are built brick by brick in parallel chunks under the volume's `threads`: one thread and
    // four give the same weights, CDF and powers, bit for bit.
    let build = |threads: i64| {
        let vol = sphere_fire(40, 0.9, 1e-6, 1700.0, vec![Param::int("threads", threads)]);
        FireLight::new(vol, Weighting::Power).unwrap()
    };
    let (one, four) = (build(1), build(4));
    assert!(one.voxels() > 20_000);
    assert_eq!(one.weights, four.weights);
    assert_eq!(one.cdf, four.cdf);
    assert_eq!(one.brick_slots, four.brick_slots);
    assert_eq!(
        (one.power_w.to_bits(), one.power_lm.to_bits()),
        (four.power_w.to_bits(), four.power_lm.to_bits())
    );
}

#[test]
fn thin_grey_sphere_radiates_four_kappa_sigma_t4_v() {
    // Optically thin uniform emitter: P = 4 κ σ T⁴ V (shared/data), V the voxelised sphere's volume.
    let (n, fv, t) = (32, 1e-9, 1500.0);
    let vol = sphere_fire(n, 0.8, fv, t, vec![]);
    let light = FireLight::new(vol.clone(), Weighting::Power).unwrap();
    let kappa = vol_kappa(&vol);
    let v = light.voxels() as f64 * (2.0 / n as f64).powi(3);
    let want = 4.0 * kappa * crate::constants::STEFAN_BOLTZMANN * t.powi(4) * v;
    assert!(
        (light.power_w() / want - 1.0).abs() < 0.005,
        "{} W vs 4κσT⁴V = {want} W",
        light.power_w()
    );
}

#[test]
fn the_blue_core_adds_its_chemiluminescence_to_the_full_spectrum_power() {
    // Soot at 1500 K and a reaction zone releasing 1e7 W/m³ in a 16³ box: with the blue core, the light's power
    // is the soot's full-spectrum power plus the chemiluminescent fraction (1e-4) of the heat released — never
    // the power over the bins alone (it was: 9 kW of soot read as 65 W).
    let n = 16usize;
    let h = 0.01;
    let dens = vec![1e-7f32; n * n * n];
    let temp = vec![1500f32; n * n * n];
    let mut react = vec![0f32; n * n * n];
    for (i, r) in react.iter_mut().enumerate() {
        if (i % n) < 8 {
            *r = 1e7;
        }
    }
    let bytes = crate::dataset::vdb::write(
        &[
            ("density", [n; 3], &dens),
            ("temperature", [n; 3], &temp),
            ("reaction", [n; 3], &react),
        ],
        glam::DVec3::ZERO,
        glam::DVec3::splat(h),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-corepower-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("core.vdb");
    std::fs::write(&file, bytes).unwrap();
    let power = |core: bool| {
        let mut list = vec![
            Param::string("filename", &file.display().to_string()),
            Param::string("interpolation", "nearest"),
        ];
        if core {
            list.push(Param::string("reactiongrid", "reaction"));
            list.push(Param::float("chemiluminescence", 1e-4));
        }
        let vol = Arc::new(FireVolume::new(&list).unwrap_or_else(|e| panic!("{e}")));
        FireLight::new(vol, Weighting::Power).unwrap().power_w()
    };
    let (soot, both) = (power(false), power(true));
    std::fs::remove_dir_all(&dir).unwrap();
    let released = 1e7 * (n * n * n / 2) as f64 * h * h * h;
    let want = soot + 1e-4 * released;
    assert!(soot > 1e-4 * released, "{soot} W of soot");
    assert!(
        (both / want - 1.0).abs() < 1e-9,
        "{both} W with the core, want {soot} + {} W",
        1e-4 * released
    );
}

fn vol_kappa(vol: &FireVolume) -> f64 {
    let c = vol.channels();
    let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
    vol.coefficients(DVec3::ZERO, &mut a, &mut s, &mut j);
    a[0]
}

#[test]
fn monte_carlo_power_equals_the_computed_power() {
    // E[L_v(x)/pdf(x)] = Σ_v w_v V: the luminous power from samples within 3σ of the tabulated one.
    // Per cell size: the estimator is unbiased whatever the cells.
    for cell in [1, 8] {
        let vol = sphere_fire(20, 0.9, 1e-7, 1800.0, vec![]);
        let light = FireLight::with_cell(vol.clone(), Weighting::Power, cell).unwrap();
        let xyz = vol.channel_xyz();
        let c = vol.channels();
        let (mut a, mut s, mut j) = (vec![0.0; c], vec![0.0; c], vec![0.0; c]);
        let mut rng = Rng::new(9);
        let n = 40_000;
        let (mut sum, mut sum2) = (0.0, 0.0);
        for _ in 0..n {
            let smp = light.sample([(); 6].map(|_| rng.next_f64()));
            vol.coefficients(smp.point, &mut a, &mut s, &mut j);
            let lum: f64 =
                (0..c).map(|q| j[q] * xyz[q].y).sum::<f64>() * 4.0 * std::f64::consts::PI;
            let x = lum / smp.pdf;
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / n as f64;
        let se = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
        assert!(
            (mean - light.power_lm()).abs() <= 3.0 * se + 1e-9 * mean,
            "{mean} ± {se} vs {}",
            light.power_lm()
        );
    }
}

#[test]
fn the_brick_walk_gives_the_voxel_walks_direction_pdf_on_a_sparse_fire() {
    // A ball of soot written as an OpenVDB file whose active box starts at index 11 (a leaf's voxel 3), so
    // the weights' bricks are offset from the lattice, with a second ball 120 voxels away (empty bricks
    // between them). The direction pdf walked brick by brick equals the plain voxel walk's.
    let ball = |c: i32| -> (
        Vec<crate::dataset::vdb::VdbLeaf>,
        Vec<crate::dataset::vdb::VdbLeaf>,
    ) {
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for l in 0..27 {
            let o = [8 + 8 * (l % 3), 8 + 8 * ((l / 3) % 3), 8 + 8 * (l / 9)].map(|v| v + c);
            let (mut dv, mut tv, mut mask) = (vec![0f32; 512], vec![0f32; 512], [0u64; 8]);
            for i in 0..512 {
                let p = [
                    o[0] + (i as i32 >> 6),
                    o[1] + ((i as i32 >> 3) & 7),
                    o[2] + (i as i32 & 7),
                ];
                let r2: i32 = p.iter().map(|&x| (x - 20 - c) * (x - 20 - c)).sum();
                if r2 < 81 {
                    (dv[i], tv[i]) = (4e-6, 1600.0);
                    mask[i / 64] |= 1 << (i % 64);
                }
            }
            d.push((o, mask, dv));
            t.push((o, mask, tv));
        }
        (d, t)
    };
    // Two balls (the weights' bricks an eighth of the box's or fewer: the brick walk) and the first alone
    // (a fire filling its box: one voxel walk).
    for far in [true, false] {
        let (d0, t0) = ball(0);
        let (d1, t1) = if far { ball(120) } else { (vec![], vec![]) };
        let bytes = crate::dataset::vdb::write_sparse(
            &[
                ("density", [d0, d1].concat()),
                ("temperature", [t0, t1].concat()),
            ],
            DVec3::ZERO,
            DVec3::splat(0.01),
        );
        let file =
            std::env::temp_dir().join(format!("firemedium-light-walk-{}.vdb", std::process::id()));
        std::fs::write(&file, bytes).unwrap();
        let vol = Arc::new(
            FireVolume::new(&[
                Param::string("dataset", &file.to_string_lossy()),
                Param::string("fuel", "propane"),
            ])
            .unwrap(),
        );
        let _ = std::fs::remove_file(&file);
        for cell in [1, 2, 8] {
            let light = FireLight::with_cell(vol.clone(), Weighting::Power, cell).unwrap();
            assert_ne!(light.topo.offset(), [0, 0, 0]);
            let box_bricks: usize = light.topo.bricks().iter().product();
            assert_eq!(light.topo.active_bricks() * 8 >= box_bricks, !far);
            let ds = light.vol.dataset();
            let [p0, p1] = ds.bounds();
            let mut rng = crate::rng::Rng::new(4);
            let mut checked = 0;
            for _ in 0..300 {
                let o = p0
                    + (p1 - p0) * DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) * 1.4
                    - (p1 - p0) * 0.2;
                // Toward one of the balls (centres near 0.205 m and 1.405 m on every axis), within its radius.
                let c = if far && rng.next_f64() < 0.5 {
                    1.405
                } else {
                    0.205
                };
                let j = DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64()) - 0.5;
                let d = DVec3::splat(c) + j * 0.12 - o;
                let dn = d.normalize();
                let mut want = 0.0;
                // Voxel by voxel, the density at each piece's middle (constant over a voxel for any cell size).
                for seg in walk(ds.bounds(), light.dims, 1, o, dn, 0.0, f64::INFINITY) {
                    let w = light.pdf(o + dn * (0.5 * (seg.t0 + seg.t1)));
                    want += w * (seg.t1.powi(3) - seg.t0.powi(3)) / 3.0;
                }
                let got = light.pdf_direction(o, d);
                checked += (want > 0.0) as usize;
                assert!(
                    (got - want).abs() <= 1e-9 * want.max(1e-300),
                    "cell {cell}: {got} vs {want}"
                );
            }
            assert!(checked > 200, "{checked} rays met the fire");
        }
    }
}

#[test]
fn direction_pdf_integrates_to_one_over_the_sphere() {
    // ∫ pdf_direction dω = 1 for a point outside the fire (all the pdf is seen from there), per cell size.
    for cell in [1, 4] {
        let light = FireLight::with_cell(
            sphere_fire(16, 0.7, 1e-6, 1600.0, vec![]),
            Weighting::Luminance,
            cell,
        )
        .unwrap();
        let o = DVec3::new(0.3, -3.0, 0.2);
        let mut rng = Rng::new(5);
        let n = 200_000;
        let mut sum = 0.0;
        for _ in 0..n {
            let z = 1.0 - 2.0 * rng.next_f64();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
            sum += light.pdf_direction(o, DVec3::new(r * phi.cos(), r * phi.sin(), z))
                * 4.0
                * std::f64::consts::PI;
        }
        let mean = sum / n as f64;
        assert!((mean - 1.0).abs() < 0.03, "cell {cell}: ∫ pdf dω = {mean}");
        // And it is consistent with point sampling: pdf_direction ≥ pdf(x) s² ds piece for the sampled direction.
        let s = light.sample([0.5; 6]);
        assert!(light.pdf_direction(o, s.point - o) > 0.0);
    }
}

#[test]
fn irradiance_beside_a_fire_equals_brute_force_quadrature() {
    // E_Y(p) = ∫ T(p, x) j_Y(x) cosθ / |x − p|² dV over a smooth, trilinear, optically thick-ish fire
    // (τ ≈ 1 across): the light's estimator against a midpoint quadrature on 4³ points per voxel.
    let n = 10;
    let (mut dens, mut temp) = (Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                let r2 = c(i).powi(2) + c(j).powi(2) + (c(k) + 0.2).powi(2);
                dens.push((1.0 - r2 / 0.8).max(0.0) * 2e-7);
                temp.push(1200.0 + 800.0 * (1.0 - r2 / 2.0).max(0.0));
            }
        }
    }
    let vol = cube_fire(
        n,
        &dens,
        &temp,
        &[
            Param::string("fuel", "propane"),
            Param::float("stepsize", 0.25),
        ],
    );
    let light = FireLight::new(vol.clone(), Weighting::Luminance).unwrap();
    let xyz = vol.channel_xyz();
    let c = vol.channels();
    let p = DVec3::new(1.7, 0.3, -0.4);
    let nrm = DVec3::new(-1.0, 0.0, 0.3).normalize();
    let (mut a, mut s, mut j, mut t) = (vec![0.0; c], vec![0.0; c], vec![0.0; c], vec![0.0; c]);
    let mut tau_max = 0.0f64;
    let mut f = |x: DVec3| -> f64 {
        let v = x - p;
        let r2 = v.length_squared();
        let cos = nrm.dot(v) / r2.sqrt();
        if cos <= 0.0 {
            return 0.0;
        }
        vol.coefficients(x, &mut a, &mut s, &mut j);
        if j.iter().all(|&q| q == 0.0) {
            return 0.0;
        }
        let ray = crate::volume::Ray {
            o: p,
            d: v,
            t0: 0.0,
            t1: 1.0,
            seed: 1,
            first: None,
        };
        vol.transmittance(&ray, &mut t);
        tau_max = tau_max.max(-t[c / 2].ln());
        (0..c).map(|q| j[q] * t[q] * xyz[q].y).sum::<f64>() * cos / r2
    };
    // Brute force.
    let m = 4 * n;
    let h = 2.0 / m as f64;
    let mut quad = 0.0;
    for k in 0..m {
        for jy in 0..m {
            for i in 0..m {
                let x = DVec3::new(i as f64 + 0.5, jy as f64 + 0.5, k as f64 + 0.5) * h - 1.0;
                quad += f(x) * h * h * h;
            }
        }
    }
    // The light.
    let mut rng = Rng::new(21);
    let ns = 40_000;
    let (mut sum, mut sum2) = (0.0, 0.0);
    for _ in 0..ns {
        let smp = light.sample([(); 6].map(|_| rng.next_f64()));
        let x = f(smp.point) / smp.pdf;
        sum += x;
        sum2 += x * x;
    }
    let mean = sum / ns as f64;
    let se = ((sum2 / ns as f64 - mean * mean).max(0.0) / ns as f64).sqrt();
    assert!(
        tau_max > 0.3,
        "the test fire should shadow itself (τ_max = {tau_max})"
    );
    assert!(
        (mean - quad).abs() <= 3.0 * se,
        "fire light {mean} ± {se} vs quadrature {quad} (rel. σ {})",
        se / mean
    );
}

#[test]
fn a_fire_that_cannot_emit_is_refused_before_its_voxels_are_weighed() {
    // No temperature grid: nothing emits. Refused up front (a 600³ grid of this kind built a 3.4 GB light).
    let vol = FireVolume::new(&[
        Param::floats("density", &[1.0; 8]),
        Param::int("nx", 2),
        Param::int("ny", 2),
        Param::int("nz", 2),
    ])
    .unwrap();
    assert!(!vol.can_emit());
    let e = FireLight::new(Arc::new(vol), Weighting::Power)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no emitting voxel"), "{e}");
    assert!(sphere_fire(8, 0.8, 1e-6, 1500.0, vec![]).can_emit());
}

/// A Gaussian ball of soot in a 48³ trilinear grid over [−1, 1]³, thin or thick by `fv`: at 1550 K, or
/// (`steep`) from 1000 K at its edge to 1700 K at its centre.
fn ball(fv: f64, steep: bool) -> Arc<FireVolume> {
    ball_of(fv, steep, 0.15)
}

/// [`ball`] of Gaussian width² `w2` (e^{−r²/w2}): a wider ball's blocks average its curvature away.
fn ball_of(fv: f64, steep: bool, w2: f64) -> Arc<FireVolume> {
    let n = 48;
    let (mut d, mut t) = (Vec::new(), Vec::new());
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let c = |q: usize| -1.0 + (q as f64 + 0.5) * 2.0 / n as f64;
                let w = (-(c(i).powi(2) + c(j).powi(2) + c(k).powi(2)) / w2).exp();
                d.push(fv * w);
                t.push(if steep { 1000.0 + 700.0 * w } else { 1550.0 });
            }
        }
    }
    cube_fire(n, &d, &t, &[])
}

/// A trilinear fire over [−1, 1]³ from n³ densities and temperatures (x fastest), with `extra` parameters.
fn cube_fire(n: usize, d: &[f64], t: &[f64], extra: &[Param]) -> Arc<FireVolume> {
    let mut list = vec![
        Param::floats("density", d),
        Param::floats("temperature", t),
        Param::int("nx", n as i64),
        Param::int("ny", n as i64),
        Param::int("nz", n as i64),
        Param::point3("p0", [-1.0; 3]),
        Param::point3("p1", [1.0; 3]),
    ];
    list.extend_from_slice(extra);
    Arc::new(FireVolume::new(&list).unwrap())
}

#[test]
fn the_line_marches_a_copy_only_where_it_keeps_to_the_fire() {
    // `lineblock` 0 with a 2-voxel step: the copy of 2³ blocks is checked against the volume's march on the
    // light's rays and kept within 0.5 % — on a fire at one temperature, thin or thick; where the temperature
    // falls 700 K across the ball, a block's one temperature, interpolated between blocks, emits less than
    // its voxels did (emission is convex in T), so the line marches the fire's own voxels. Asked for, the
    // copy is used regardless.
    let line = |block: usize| LineEstimate {
        step_voxels: 2.0,
        correction: 0.0,
        block,
        channels: 0,
    };
    let thin = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(0)).unwrap();
    assert_eq!(thin.line_block(), 2);
    let bias = thin.block_bias_alone(thin.mip.as_deref().unwrap());
    assert!(bias.abs() <= BLOCK_BIAS, "{bias}");
    let thick = FireLight::with(ball(1e-7, false), Weighting::Power, 8, line(0)).unwrap();
    assert_eq!(thick.line_block(), 2);
    let c = thick.vol.channels();
    let (mut l, mut tr) = (vec![0.0; c], vec![0.0; c]);
    let centre = crate::volume::Ray {
        o: DVec3::new(-2.0, 0.0, 0.0),
        d: DVec3::X,
        t0: 0.0,
        t1: 4.0,
        seed: 1,
        first: None,
    };
    thick.vol.integrate_at(&centre, 0.0, &mut l, &mut tr);
    assert!(tr[c / 2] < 0.7, "the thick ball lets {} through", tr[c / 2]);
    let steep = FireLight::with(ball(1e-9, true), Weighting::Power, 8, line(0)).unwrap();
    assert_eq!(steep.line_block(), 1);
    let forced = FireLight::with(ball(1e-9, true), Weighting::Power, 8, line(2)).unwrap();
    assert_eq!(forced.line_block(), 2);
    let bias = forced.block_bias_alone(forced.mip.as_deref().unwrap());
    assert!(bias < -BLOCK_BIAS, "the steep fire's copy strays: {bias}");
    // The light's memory counts the copy.
    assert!(forced.bytes() > steep.bytes() + forced.mip.as_ref().unwrap().mip_bytes() / 2);
    // The volume's own voxels when asked, and no block size but 0, 1, 2, 4 and 8.
    let own = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(1)).unwrap();
    assert_eq!(own.line_block(), 1);
    let e = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(3))
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("lineblock") && e.contains('3'), "{e}");
}

#[test]
fn the_line_takes_the_coarsest_step_that_keeps_to_the_fire() {
    // `linestep` and `lineblock` 0: 16, 32 or 64 steps across the fire, the coarsest whose line stays within
    // 0.5 % of the volume's march on the light's rays; the finest unchecked where none does. Given a block,
    // 64 steps as before.
    let steps = |l: &FireLight| {
        let longest = 2.0;
        (longest / l.line_step()).round() as usize
    };
    // (A thin ball at one temperature: a copy of 2³ blocks at 16 steps — its 4³ copy holds the light's weighted
    // sum but not the plain one; falling 700 K to its rim, the copy
    // strays and the fire's own voxels at 16 steps do not; a thick ball as well: only 64 steps.)
    for (fv, steep, want) in [
        (1e-9, false, (16, 2)),
        (1e-9, true, (16, 1)),
        (1e-7, false, (16, 2)),
        (3e-6, true, (64, 1)),
    ] {
        let l = FireLight::with(
            ball(fv, steep),
            Weighting::Power,
            8,
            LineEstimate::default(),
        )
        .unwrap();
        let bias = l.block_bias_alone(l.mip.as_deref().unwrap_or(&l.vol));
        assert_eq!((steps(&l), l.line_block()), want, "{fv} {steep}");
        assert!(bias.abs() <= BLOCK_BIAS, "{fv} {steep}: {bias}");
    }
    // The thick, steep ball's own voxels at 16 and 32 steps (3 and 1.5 voxels) stray: why 64 were taken.
    for step_voxels in [3.0, 1.5] {
        let coarse = LineEstimate {
            step_voxels,
            block: 1,
            ..LineEstimate::default()
        };
        let l = FireLight::with(ball(3e-6, true), Weighting::Power, 8, coarse).unwrap();
        let bias = l.block_bias_alone(&l.vol);
        assert!(bias.abs() > BLOCK_BIAS, "{step_voxels}: {bias}");
    }
    let given = LineEstimate {
        block: 2,
        ..LineEstimate::default()
    };
    let l = FireLight::with(ball(1e-9, false), Weighting::Power, 8, given).unwrap();
    assert_eq!((steps(&l), l.line_block()), (64, 2));
}

#[test]
fn the_line_marches_a_few_bins_only_where_the_colour_allows() {
    // `linechannels` 0: 8 of the 32 bins where the line's X, Y and Z stay within 0.2 % of every bin's on the
    // light's rays. A ball at one temperature follows exactly (Wien: the logarithm of its ratio to the slab at
    // any temperature is linear in 1/λ), thin or thick; one falling 700 K to its rim mixes temperatures
    // along each line and strays by a few 1e-4; made thick as well (optical depths of ten), by 0.8 %,
    // refused. Asked for, the few bins are marched regardless; 1 is not a count; at least the volume's
    // bins, all of them.
    let line = |channels: usize| LineEstimate {
        step_voxels: 2.0,
        correction: 0.0,
        block: 1,
        channels,
    };
    let bias = |l: &FireLight| l.channel_bias(&l.vol, l.channels.as_ref().unwrap());
    for (fv, steep, most) in [
        (1e-9, false, 1e-6),
        (1e-7, false, 1e-6),
        (1e-9, true, CHANNEL_BIAS),
    ] {
        let l = FireLight::with(ball(fv, steep), Weighting::Power, 8, line(0)).unwrap();
        assert_eq!(l.line_channels(), LINE_CHANNELS, "{fv} {steep}");
        let b = bias(&l);
        assert!(b <= most, "{fv} {steep}: {b}");
    }
    let thick = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(0)).unwrap();
    assert_eq!(thick.line_channels(), 32);
    let forced = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(8)).unwrap();
    assert_eq!(forced.line_channels(), 8);
    assert!(bias(&forced) > CHANNEL_BIAS, "{}", bias(&forced));
    let sixteen = FireLight::with(ball(1e-6, true), Weighting::Power, 8, line(16)).unwrap();
    assert_eq!(sixteen.line_channels(), 16);
    assert_eq!(
        FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(64))
            .unwrap()
            .line_channels(),
        32
    );
    let Err(e) = FireLight::with(ball(1e-9, false), Weighting::Power, 8, line(1)) else {
        panic!("1 is not a count");
    };
    let e = e.to_string();
    assert!(e.contains("linechannels") && e.contains("2 to 32"), "{e}");
}
