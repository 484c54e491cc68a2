//! Extremes, parameter errors, pbrt-v4 nanovdb's clipping, a real simulation's grids, the tracking caps and the memory budget.

use super::*;

#[test]
fn extremes_are_finite() {
    // (Densities up to the optical-depth bound, ~1e11 per voxel here; beyond it a volume is refused when built.)
    for (d, t) in [
        (0.0, 0.0),
        (1e-30, 1.0),
        (5e4, 1e6),
        (1.0, 1e6),
        (1e-3, 0.0),
        (5e4, 300.0),
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
                    first: None,
                }, // starts inside
                Ray {
                    o: DVec3::new(-1.0, 0.0, 0.0),
                    d: DVec3::X,
                    t0: 0.0,
                    t1: 10.0,
                    seed: 2,
                    first: None,
                }, // along an edge
                Ray {
                    o: DVec3::new(-1.0, 0.5, 1.0),
                    d: DVec3::X,
                    t0: 0.0,
                    t1: 10.0,
                    seed: 3,
                    first: None,
                }, // in a face
                Ray {
                    o: DVec3::new(-1.0, 2.0, 0.5),
                    d: DVec3::X,
                    t0: 0.0,
                    t1: 10.0,
                    seed: 4,
                    first: None,
                }, // misses
                Ray {
                    o: DVec3::new(0.5, 0.5, 0.5),
                    d: DVec3::new(1e-300, 0.0, 0.0),
                    t0: 0.0,
                    t1: 1.0,
                    seed: 5,
                    first: None,
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
    let v = slab_volume(5e4, 1e6, vec![]);
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
    assert_eq!(
        FireVolume::new(&l).unwrap_err().to_string(),
        "volume: unknown parameter 'stepsise' (did you mean 'stepsize'?)"
    );
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
fn parameters_are_checked_before_a_file_is_opened() {
    // A mistake in the parameters is reported without reading the dataset: here the file does not exist, and
    // each error names the parameter, not the file (a preset's grid, looked up in the file, included).
    let missing = std::env::temp_dir().join("firemedium-no-such-dir/fire.vdb");
    let file = missing.display().to_string();
    let cases = [
        (vec![Param::int("nx", 4)], "'nx'"),
        (
            vec![
                Param::string("embers", "sparks.ply"),
                Param::float("fps", -1.0),
            ],
            "fps",
        ),
        (
            vec![Param::string("source", "houdini"), Param::int("nx", 4)],
            "'nx'",
        ),
    ];
    for (extra, want) in cases {
        let mut l = vec![Param::string("filename", &file)];
        l.extend(extra);
        let e = FireVolume::new(&l).unwrap_err().to_string();
        assert!(
            e.contains(want) && !e.contains("firemedium-no-such-dir"),
            "{e}"
        );
    }
    // With the parameters right, the file is what is wrong, and the error names it.
    let e = FireVolume::new(&[Param::string("filename", &file)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("firemedium-no-such-dir"), "{e}");
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
        Param::spectrum("sigma_s", &[0.0]),
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
        first: None,
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
            first: None,
        },
    );
    assert!(
        l.iter().all(|x| x.is_finite() && *x >= 0.0) && l[29] > 0.0,
        "{l:?}"
    );
    assert!(t.iter().all(|x| (0.0..1.0).contains(x)));
}

#[test]
fn tracking_stops_at_the_collision_cap_and_counts_it() {
    // One voxel of dense soot (f_v = 1e4 · sootscale) in a brick of thin smoke: the brick's majorant is that
    // voxel's, ~1e10 m⁻¹, so a ray through the thin part meets ~1e10 null collisions per metre. It stops at
    // MAX_COLLISIONS (2^20) as if absorbed, and the volume counts the ray for the host to report.
    let v = dense_voxel_in_smoke(&[Param::string("integrator", "ratio")]);
    assert_eq!(v.capped_rays(), 0);
    let (_, t) = run(&v, &ray_x(1));
    assert!(t.iter().all(|&x| x == 0.0), "{t:?}");
    assert_eq!(v.capped_rays(), 1);
    // A ray that misses the volume is not counted.
    let miss = Ray {
        o: DVec3::new(-0.5, 5.0, 0.5),
        ..ray_x(2)
    };
    run(&v, &miss);
    assert_eq!(v.capped_rays(), 1);
}

#[test]
fn tracking_in_4096_bins_stops_within_the_same_work() {
    // The reproducer, in process: one scattering ray at 4 096 bins through a brick whose majorant is one
    // dense voxel's took 44.5 s (2^20 null collisions × 4 096 channels). The collision cap shrinks with the
    // channels (2^25 channel evaluations a ray): the ray stops as absorbed and is counted.
    let v = dense_voxel_in_smoke(&[Param::int("bins", 4096), Param::float("sigma_s", 1e-3)]);
    let c = v.channels();
    assert_eq!(c, 4096);
    let (mut l, mut w) = (vec![0.0; c], vec![0.0; c]);
    let evals = super::integrate::EVALUATIONS.with(|n| n.get());
    v.sample_scatter(&ray_x(1), &mut l, &mut w);
    let taken = super::integrate::EVALUATIONS.with(|n| n.get()) - evals;
    assert_eq!(v.capped_rays(), 1, "{taken} collisions");
    assert!(
        taken <= super::integrate::MAX_TRACKING_WORK / 4096 + 1,
        "{taken} collisions"
    );
}

#[test]
fn a_march_at_4096_bins_takes_at_most_its_share_of_the_steps() {
    // The smallest step (1e-4 voxels) along 64 voxels: 640 000 steps, each 4 096 channels — 2.6e9 channel
    // evaluations in one ABI call (10¹⁰ through a 256³ grid). The step cap shrinks past 32 channels, as the
    // collision cap does: the steps lengthen, the work stays 2^29 channel steps a ray.
    let v = FireVolume::new(&[
        Param::floats("density", &[1e-6; 64]),
        Param::floats("temperature", &[1500.0; 64]),
        Param::int("nx", 64),
        Param::int("ny", 1),
        Param::int("nz", 1),
        Param::int("bins", 4096),
        Param::float("stepsize", 1e-4),
    ])
    .unwrap();
    let c = v.channels();
    let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
    let before = super::integrate::EVALUATIONS.with(|n| n.get());
    v.integrate(&ray_x(1), &mut l, &mut t);
    let steps = super::integrate::EVALUATIONS.with(|n| n.get()) - before;
    let most = super::integrate::max_steps(4096);
    assert_eq!(most, 131_072.0);
    assert!(
        steps > 100_000 && steps as f64 <= most + 2.0,
        "{steps} steps"
    );
    // The medium is seen: a little light, a little absorbed.
    assert!(
        l.iter().any(|&x| x > 0.0) && t.iter().all(|&x| x < 1.0 && x > 0.0),
        "{:?}",
        &t[..4]
    );
}

#[test]
fn an_optical_depth_beyond_any_fire_is_an_error_naming_where() {
    // One voxel of 1e30 (an outlier in a simulation's output) would make tracking collide ~1e30 times per
    // voxel: refused when the volume is built, naming the brick and the depth.
    let mut d = vec![1.0; 64];
    d[21] = 1e30;
    let e = FireVolume::new(&[
        Param::floats("density", &d),
        Param::floats("temperature", &[1500.0; 64]),
        Param::int("nx", 4),
        Param::int("ny", 4),
        Param::int("nz", 4),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("parameter 'extinction'")
            && e.contains("optical depth")
            && e.contains("at most 1e12"),
        "{e}"
    );
    // A step below 1e-4 voxel would run every ray into the step cap: refused by its range.
    let e = FireVolume::new(&[
        Param::floats("density", &[1.0; 8]),
        Param::int("nx", 2),
        Param::int("ny", 2),
        Param::int("nz", 2),
        Param::float("stepsize", 1e-320),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("'stepsize' = 1e-320: expected a finite number 1e-4 to 1e9"),
        "{e}"
    );
}

#[test]
fn the_budget_covers_what_the_volume_derives() {
    // A 4³ trilinear fire whose grids (2 × 256 bytes) fit `maxbytes` but whose march lattice (6³ padded voxels
    // × 8 bytes) does not: it marches without the lattice — the same answer within f32 rounding — and its fire
    // light, which would not fit either, is refused naming the budget.
    let build = |maxbytes: f64| {
        FireVolume::new(&[
            Param::floats("density", &[1e-6; 64]),
            Param::floats("temperature", &[1500.0; 64]),
            Param::int("nx", 4),
            Param::int("ny", 4),
            Param::int("nz", 4),
            Param::float("maxbytes", maxbytes),
        ])
        .unwrap()
    };
    // (The budget's first share goes to the temperature tables, their bound counted before they are built: a
    // budget below it is refused naming them.)
    let tables = super::super::tables::bytes_for(1500.0, 32, 0, false) as f64;
    let e = FireVolume::new(&[
        Param::floats("density", &[1e-6; 64]),
        Param::floats("temperature", &[1500.0; 64]),
        Param::int("nx", 4),
        Param::int("ny", 4),
        Param::int("nz", 4),
        Param::float("maxbytes", 600.0),
    ])
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("the temperature tables") && e.contains("cap of"),
        "{e}"
    );
    let roomy = build(1e9);
    let tight = build(roomy.grids.ds().bytes() as f64 + tables + 600.0);
    assert!(
        tight.estimator.lattice().built().is_none() && roomy.estimator.lattice().built().is_some()
    );
    let (a, b) = (run(&tight, &ray_x(3)).0, run(&roomy, &ray_x(3)).0);
    for k in 0..a.len() {
        assert!(
            (a[k] / b[k] - 1.0).abs() < 1e-5,
            "ch {k}: {} vs {}",
            a[k],
            b[k]
        );
    }
    let e =
        crate::light::FireLight::new(std::sync::Arc::new(tight), crate::light::Weighting::Power)
            .unwrap_err()
            .to_string();
    assert!(e.contains("fire light") && e.contains("memory cap"), "{e}");
    assert!(crate::light::FireLight::new(
        std::sync::Arc::new(roomy),
        crate::light::Weighting::Power
    )
    .is_ok());
}
