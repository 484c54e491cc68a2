//! The march on the lattice's brick copies and shared tiles, against the dense lattice.

use super::*;

/// The ray from `from` toward `to`, out to parameter `t1` (unit direction: metres), numbered `seed`.
fn between(from: DVec3, to: DVec3, t1: f64, seed: u64) -> Ray {
    Ray {
        o: from,
        d: (to - from).normalize(),
        t0: 0.0,
        t1,
        seed,
        first: None,
    }
}

#[test]
fn a_sparse_fire_marches_on_brick_copies_as_on_the_dense_lattice() {
    // Two fires of 3³ leaves with random soot and temperature, the second 120 voxels from the first on every
    // axis: the dense lattice over their 144³ box would cost 60 times what the grids store, so `auto` copies
    // the bricks. Rays through the first fire (and the empty box) give the dense lattice's answer to the bit, as
    // does the march without a lattice (reading the stored bricks in place).
    let mut rng = crate::rng::Rng::new(77);
    let mut leaves = |o: i32| {
        let (mut d, mut t) = (Vec::new(), Vec::new());
        for l in 0..27 {
            let origin = [o + 8 * (l % 3), o + 8 * ((l / 3) % 3), o + 8 * (l / 9)];
            let dv: Vec<f32> = (0..512).map(|_| (rng.next_f64() * 3e-6) as f32).collect();
            let tv: Vec<f32> = (0..512)
                .map(|_| (1200.0 + rng.next_f64() * 600.0) as f32)
                .collect();
            d.push((origin, [u64::MAX; 8], dv));
            t.push((origin, [u64::MAX; 8], tv));
        }
        (d, t)
    };
    let ((d0, t0), (d1, t1)) = (leaves(0), leaves(120));
    let bytes = crate::dataset::vdb::write_sparse(
        &[
            ("density", [d0, d1].concat()),
            ("temperature", [t0, t1].concat()),
        ],
        DVec3::ZERO,
        DVec3::splat(0.01),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-bricks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("two.vdb");
    std::fs::write(&file, bytes).unwrap();
    let build = |lattice: &str| {
        FireVolume::new(&[
            Param::string("filename", &file.display().to_string()),
            Param::string("lattice", lattice),
            Param::string("fuel", "propane"),
        ])
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let (auto, dense, off) = (build("auto"), build("dense"), build("off"));
    std::fs::remove_dir_all(&dir).unwrap();
    let (a, d) = (
        auto.estimator.lattice().built().unwrap(),
        dense.estimator.lattice().built().unwrap(),
    );
    assert!(
        a.bricks().is_some() && d.bricks().is_none() && off.estimator.lattice().built().is_none()
    );
    // 54 stored bricks: their copies and those below them, not the box.
    let copies = a.bricks().unwrap().active_bricks();
    assert!((54..=2 * 64).contains(&copies), "{copies} copies");
    assert!(
        a.bytes() * 20 < d.bytes(),
        "{} vs {} bytes",
        a.bytes(),
        d.bytes()
    );
    let mut rng = crate::rng::Rng::new(5);
    let mut lit = 0;
    for seed in 0..300 {
        // From a point around the first fire (0.24 m across) toward a point in it, some rays on to the second.
        let mut u = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let to = DVec3::splat(0.02) + u() * 0.2;
        let from = DVec3::splat(0.12) + (u() - DVec3::splat(0.5)).normalize_or(DVec3::X) * 0.5;
        let ray = between(from, to, 5.0, seed);
        let (la, ta) = run(&auto, &ray);
        let (ld, td) = run(&dense, &ray);
        let (lo, to) = run(&off, &ray);
        assert_eq!((&la, &ta), (&ld, &td), "ray {seed}: bricks vs dense");
        assert_eq!(
            (&lo, &to),
            (&ld, &td),
            "ray {seed}: the grids read in place vs dense"
        );
        lit += (la.iter().sum::<f64>() > 0.0) as usize;
    }
    assert!(lit > 100, "{lit} rays saw the fire");
}

/// A fog volume of OpenVDB tiles (one block of values shared by 4 096 bricks) marches as its dense copy does.
#[test]
fn shared_tile_blocks_march_as_the_dense_lattice() {
    let leaf = |o: [i32; 3], k: f32| -> crate::dataset::vdb::VdbLeaf {
        (
            o,
            [u64::MAX; 8],
            (0..512).map(|i| k * (1.0 + (i % 7) as f32)).collect(),
        )
    };
    let bytes = crate::dataset::vdb::write_tiled(
        &[
            (
                "density",
                vec![leaf([128, 0, 0], 2e-6)],
                vec![([0, 0, 0], 128, 1e-6), ([128, 8, 0], 8, 3e-6)],
            ),
            (
                "temperature",
                vec![leaf([128, 0, 0], 300.0)],
                vec![([0, 0, 0], 128, 1500.0), ([128, 8, 0], 8, 1900.0)],
            ),
        ],
        DVec3::ZERO,
        DVec3::splat(0.01),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-tiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("fog.vdb");
    std::fs::write(&file, bytes).unwrap();
    let build = |lattice: &str| {
        FireVolume::new(&[
            Param::string("filename", &file.display().to_string()),
            Param::string("lattice", lattice),
            Param::string("fuel", "propane"),
        ])
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let (bricks, dense, off) = (build("bricks"), build("dense"), build("off"));
    std::fs::remove_dir_all(&dir).unwrap();
    assert_eq!(dense.dataset().topology().blocks_stored(), 3);
    let mut rng = crate::rng::Rng::new(9);
    let mut lit = 0;
    for seed in 0..200 {
        let mut u = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
        let to = u() * DVec3::new(1.36, 1.28, 1.28);
        let from =
            DVec3::new(0.68, 0.64, 0.64) + (u() - DVec3::splat(0.5)).normalize_or(DVec3::X) * 3.0;
        let ray = between(from, to, 10.0, seed);
        let (lb, tb) = run(&bricks, &ray);
        let (ld, td) = run(&dense, &ray);
        let (lo, to) = run(&off, &ray);
        assert_eq!((&lb, &tb), (&ld, &td), "ray {seed}: bricks vs dense");
        assert_eq!(
            (&lo, &to),
            (&ld, &td),
            "ray {seed}: shared blocks read in place vs dense"
        );
        lit += (ld.iter().sum::<f64>() > 0.0) as usize;
    }
    assert!(lit > 150, "{lit} of 200 rays crossed the fog");
}

#[test]
fn without_a_lattice_the_march_reads_the_grids_in_place_to_the_bit() {
    // `lattice off` keeps no copy: the kernel reads each cell's eight samples from the dataset's stored bricks
    // (one brick, or up to eight where the cell straddles them; zero beyond the faces, where the lattice has its
    // padding) and lerps them as it lerps the lattice's. The same radiance and transmittance to the bit, on a
    // 40 × 36 × 44 box (no side whole bricks) with a Lescale grid (pbrt mode) or a species grid, for rays from
    // every side, some grazing the faces; a budget with no room for the copy marches the same way, and says so.
    // Under pbrt mode `auto` is `off`.
    for (extra, species) in [(vec![Param::string("mode", "pbrt")], false), (vec![], true)] {
        let build = |lattice: &str| {
            let mut e = extra.clone();
            e.push(Param::string("lattice", lattice));
            blob_volume(e, species)
        };
        let (dense, off) = (build("dense"), build("off"));
        assert!(dense.estimator.lattice().built().is_some() && !off.estimator.lattice().is_some());
        // `auto`: pbrt-v4's own media read their grids in place, as pbrt-v4 does; a `fire` keeps its copy.
        assert_eq!(
            build("auto").estimator.lattice().is_some(),
            species,
            "auto in {extra:?}"
        );
        // A budget that holds the grids and tables and a kilobyte more (with a Lescale grid; the species' tables
        // follow the budget), the copy asked for: no copy, the march on the grids, and a note saying so.
        let tight = (!species).then(|| {
            let mut e = extra.clone();
            e.push(Param::string("lattice", "dense"));
            e.push(Param::float(
                "maxbytes",
                (8_589_935_592 - off.spare_bytes()) as f64,
            ));
            blob_volume(e, species)
        });
        if let Some(tight) = &tight {
            assert!(!tight.estimator.lattice().is_some());
            assert!(
                tight
                    .notes()
                    .iter()
                    .any(|n| n.contains("the march's copy of the grids")
                        && n.contains("the march reads the grids in place")),
                "{:?}",
                tight.notes()
            );
        }
        assert!(off.notes().iter().all(|n| !n.contains("copy of the grids")));
        let mut rng = crate::rng::Rng::new(21);
        let (mut lit, mut crossed) = (0, 0);
        let size = DVec3::new(2.0, 1.8, 2.2);
        for seed in 0..400u64 {
            let mut u = || DVec3::new(rng.next_f64(), rng.next_f64(), rng.next_f64());
            let (mut to, side, jitter) = (u() * size, u(), u());
            // Every fourth ray toward a point on a face (within a fiftieth of a voxel), the rest into the box.
            if seed % 4 == 0 {
                let a = ((seed / 4) % 3) as usize;
                to[a] = if seed % 8 == 0 { 0.0 } else { size[a] } + (jitter.x - 0.5) * 1e-3;
            }
            let from = size * 0.5 + (side - DVec3::splat(0.5)).normalize_or(DVec3::X) * 4.0;
            let ray = between(from, to, 10.0, seed);
            let (ld, td) = run(&dense, &ray);
            let (lo, to_) = run(&off, &ray);
            assert_eq!((&lo, &to_), (&ld, &td), "ray {seed} (species {species})");
            if let Some(tight) = &tight {
                assert_eq!(
                    run(tight, &ray),
                    (ld.clone(), td.clone()),
                    "ray {seed}, budget"
                );
            }
            lit += (ld.iter().sum::<f64>() > 0.0) as usize;
            crossed += td.iter().any(|&t| t < 0.999) as usize;
        }
        assert!(
            lit > 200 && crossed > 100,
            "{lit} rays lit, {crossed} attenuated"
        );
    }
}

#[test]
fn a_scattering_fire_builds_its_lattice_when_a_ray_first_marches() {
    // A fire that scatters is tracked by its host, which may never march it: under `auto` its lattice waits
    // for the first march (none held after the build, its bytes kept from the fire light's budget), then is
    // the lattice `dense` builds with the volume — the same radiance to the bit.
    let mut rng = crate::rng::Rng::new(3);
    let (mut d, mut t) = (Vec::new(), Vec::new());
    for l in 0..8 {
        let origin = [8 * (l % 2), 8 * ((l / 2) % 2), 8 * (l / 4)];
        d.push((
            origin,
            [u64::MAX; 8],
            (0..512).map(|_| (rng.next_f64() * 3e-6) as f32).collect(),
        ));
        t.push((
            origin,
            [u64::MAX; 8],
            (0..512)
                .map(|_| (1200.0 + rng.next_f64() * 600.0) as f32)
                .collect(),
        ));
    }
    let bytes = crate::dataset::vdb::write_sparse(
        &[("density", d), ("temperature", t)],
        DVec3::ZERO,
        DVec3::splat(0.01),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-deferred-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("fire.vdb");
    std::fs::write(&file, bytes).unwrap();
    let build = |lattice: &str, sigma_s: f64| {
        FireVolume::new(&[
            Param::string("filename", &file.display().to_string()),
            Param::string("lattice", lattice),
            Param::string("fuel", "propane"),
            Param::floats("sigma_s", &[sigma_s]),
        ])
        .unwrap_or_else(|e| panic!("{e}"))
    };
    let (lazy, eager, absorbing) = (build("auto", 2e6), build("dense", 2e6), build("auto", 0.0));
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(lazy.estimator.lattice().built().is_none() && lazy.estimator.lattice().reserved() > 0);
    assert!(
        eager.estimator.lattice().built().is_some()
            && absorbing.estimator.lattice().built().is_some()
    );
    assert!(lazy.spare_bytes() < eager.spare_bytes() + 1);
    let ray = Ray {
        o: DVec3::new(-0.1, 0.07, 0.09),
        d: DVec3::X,
        t0: 0.0,
        t1: 1.0,
        seed: 1,
        first: None,
    };
    let (a, b) = (run(&lazy, &ray), run(&eager, &ray));
    assert!(a.0.iter().sum::<f64>() > 0.0);
    assert_eq!(a, b);
    assert_eq!(
        lazy.estimator.lattice().built().map(|l| l.bytes()),
        eager.estimator.lattice().built().map(|l| l.bytes())
    );
}
