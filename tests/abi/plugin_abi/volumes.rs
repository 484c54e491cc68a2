//! Volumes through the built library: creation, descriptions, notes, the closed form, threads, typed errors, lifetimes,
//! ray times, art direction against D65, the host's first numbers and step (its context: `context.rs`).

use super::*;

#[test]
fn loads_describes_and_integrates() {
    let p = plugin();
    assert_eq!(p.version(), (1, 4));
    let params = p.parameters();
    let names: Vec<&str> = params.iter().map(|r| r.name.as_str()).collect();
    for n in [
        "filename",
        "stepsize",
        "colormode",
        "temperaturescale",
        "species",
        "Lescale",
    ] {
        assert!(names.contains(&n), "{n} missing from the self-description");
    }
    let step = params.iter().find(|r| r.name == "stepsize").unwrap();
    assert_eq!(
        (
            step.component.as_str(),
            step.ty.as_str(),
            step.default.as_str(),
            step.unit.as_str()
        ),
        ("volume", "float", "0.5", "voxels")
    );

    let v = p.create_volume(&fire_params()).unwrap();
    let info = v.info();
    // The default spectrum: 32 bins over 400–780 nm (11.875 nm wide).
    assert_eq!(info.channels, 32);
    // (1.2) The dataset's lattice: the Mantaflow frame's 62 × 62 × 93 samples of 3.125 cm.
    assert_eq!(info.dims, [62, 62, 93]);
    for a in 0..3 {
        let voxel = (info.lattice_max[a] - info.lattice_min[a]) / info.dims[a] as f64;
        assert!((voxel - 0.03125).abs() < 1e-9, "axis {a}: {voxel}");
    }
    assert_eq!(info.channel_space, firemedium_abi::FM_SPACE_SPECTRAL);
    assert!(info.bytes > 1_000_000 && info.build_seconds > 0.0);
    let xyz = v.channel_xyz().unwrap();
    assert!(
        (xyz[13][1] - 683.0 * 11.875 * 0.995).abs() < 683.0 * 11.875 * 0.02,
        "{:?}",
        xyz[13]
    ); // ȳ ≈ 0.995 at the bin's centre, 560.3 nm
       // The temperature range (ABI 0.3): the Mantaflow frame's 0 … 2.974609 × temperaturescale 1000.
    let [lo, hi] = v.temperature_range().unwrap().expect("a temperature grid");
    assert!(lo == 0.0 && (hi - 2974.609).abs() < 1e-3, "{lo} {hi}");

    // Same rays through the rlib, in process: the cdylib gives the same numbers.
    let rs = rays(64);
    let c = 32;
    let (mut l, mut t) = (vec![0f32; 64 * c], vec![0f32; 64 * c]);
    let mut exits = vec![Default::default(); 64];
    v.integrate(&rs, &mut l, Some(&mut t), Some(&mut exits))
        .unwrap();
    let list = vec![
        firemedium_plugin::params::Param::string("filename", &fire_file()),
        firemedium_plugin::params::Param::float("temperaturescale", 1000.0),
        firemedium_plugin::params::Param::float("sootscale", 1e-6),
    ];
    let local = firemedium_plugin::volume::FireVolume::new(&list).unwrap();
    let (mut ll, mut lt) = (vec![0.0; c], vec![0.0; c]);
    let mut lit = 0;
    for (i, r) in rs.iter().enumerate() {
        let ray = firemedium_plugin::volume::Ray {
            o: r.origin.into(),
            d: r.direction.into(),
            t0: r.tmin,
            t1: r.tmax,
            seed: r.seed,
            first: None,
        };
        local.integrate(&ray, &mut ll, &mut lt);
        for k in 0..c {
            assert_eq!(l[i * c + k], ll[k] as f32);
            assert_eq!(t[i * c + k], lt[k] as f32);
            assert!((0.0..=1.0).contains(&t[i * c + k]) && l[i * c + k].is_finite());
        }
        lit += (l[i * c + 29] > 0.0) as usize;
        assert!(exits[i].t <= r.tmax);
    }
    assert!(lit > 10, "only {lit} of 64 rays saw the fire");
}

#[test]
fn a_volumes_notes_cross_the_abi() {
    // ABI 1.1: what the build found a user should hear, read by count and index (the length asked first, then the
    // text): a barium flame with a chlorine donor photographs in BaCl's green, which the model does not hold; a
    // sodium flame's colour is its lines, and there is nothing to say.
    let p = plugin();
    let torch = crate::common::root().join("scenes/spectroscopy/torch.vdb");
    let fire = |sym: &str| {
        p.create_volume(&[
            Param::string("filename", torch.to_str().unwrap()),
            Param::string("species", sym),
            Param::float("sootscale", 1e-6),
        ])
        .unwrap()
    };
    let notes = fire("Ba").notes().unwrap();
    assert_eq!(notes.len(), 1, "{notes:?}");
    assert!(
        notes[0].starts_with("species Ba: its bands here are BaOH's and BaO's")
            && notes[0].contains("from BaCl bands at 507–532 nm"),
        "{notes:?}"
    );
    assert!(fire("Na").notes().unwrap().is_empty());
}

#[test]
fn the_closed_form_crosses_the_abi_and_is_the_volumes_coefficients() {
    // ABI 1.2: the campfire's fields on its lattice and its tables over T give, at points between voxel centres,
    // the coefficients the volume gives there; a sodium flame (atomic lines) is not of that form, and says so.
    let p = plugin();
    let campfire = crate::common::root().join("scenes/campfire/campfire.vdb");
    let v = p
        .create_volume(&[Param::string("filename", campfire.to_str().unwrap())])
        .unwrap();
    let t = v.tables().unwrap();
    let c = t.channels;
    assert!(
        t.rows > 1000 && c == 32 && !t.emission_grid,
        "{} rows, {c}",
        t.rows
    );
    let pts: Vec<[f64; 3]> = (0..400)
        .map(|i| {
            let f = i as f64 / 400.0;
            [
                0.31 * (f * 17.0).sin(),
                0.27 * (f * 11.0).cos(),
                0.05 + 0.9 * f,
            ]
        })
        .collect();
    let mut fields = vec![[0f32; 3]; pts.len()];
    v.fields(&pts, &mut fields).unwrap();
    let (mut sa, mut ss, mut j) = (
        vec![0f32; pts.len() * c],
        vec![0f32; pts.len() * c],
        vec![0f32; pts.len() * c],
    );
    v.coefficients(&pts, &mut sa, &mut ss, &mut j).unwrap();
    let mut emitting = 0;
    for (i, [d, temp, les]) in fields.iter().map(|f| f.map(f64::from)).enumerate() {
        let r = (temp / t.dt).clamp(0.0, (t.rows - 1) as f64);
        let r0 = (r as usize).min(t.rows - 2);
        let fr = r - r0 as f64;
        let lerp = |tab: &[f32], k: usize| {
            let a = tab[r0 * c + k] as f64;
            a + fr * (tab[(r0 + 1) * c + k] as f64 - a)
        };
        for k in 0..c {
            let want = [sa[i * c + k], j[i * c + k]].map(f64::from);
            let got = [
                d * lerp(&t.absorption, k),
                if temp > t.t_emit {
                    d * les * lerp(&t.emission, k)
                } else {
                    0.0
                },
            ];
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g - w).abs() <= 1e-5 * w.abs() + 1e-30,
                    "point {i}, channel {k}: {g} against {w}"
                );
            }
        }
        emitting += usize::from(j[i * c + 20] > 0.0);
    }
    assert!(emitting > 100, "{emitting} of 400 points emit");
    let torch = crate::common::root().join("scenes/spectroscopy/torch.vdb");
    let na = p
        .create_volume(&[
            Param::string("filename", torch.to_str().unwrap()),
            Param::string("species", "Na"),
            Param::string("lineshape", "box"),
        ])
        .unwrap();
    let e = na.tables().unwrap_err().to_string();
    assert!(
        e.contains("atomic lines") && e.contains("volume_coefficients"),
        "{e}"
    );
}

#[test]
fn the_bricks_a_volume_stores_cross_the_abi() {
    // ABI 1.3: a sparse file's leaves, two active from x = 3 on (so the lattice starts inside its brick),
    // and one far away, come back as the bricks the volume stores, each by its first sample's lattice index — not
    // the box between them. (The raw calls' refusals: tests/c/abi_abuse.c.)
    // (Values in writer's order, z fastest: voxel i at x = i / 64; the inactive ones hold the background, 0.)
    let leaf = |o: [i32; 3], mask: [u64; 8], v: f32| -> firemedium_dataset::vdb::VdbLeaf {
        let on = |i: usize| mask[i / 64] >> (i % 64) & 1 == 1;
        (
            o,
            mask,
            (0..512).map(|i| if on(i) { v } else { 0.0 }).collect(),
        )
    };
    let from_x3 = [0, 0, 0, u64::MAX, u64::MAX, u64::MAX, u64::MAX, u64::MAX];
    let all = [u64::MAX; 8];
    let leaves = |v: f32| {
        vec![
            leaf([8, 16, 0], from_x3, v),
            leaf([8, 16, 8], from_x3, v),
            leaf([200, 8, 64], all, v),
        ]
    };
    let bytes = firemedium_dataset::vdb::write_sparse(
        &[("density", leaves(2e-6)), ("temperature", leaves(1600.0))],
        glam::DVec3::ZERO,
        glam::DVec3::splat(0.01),
    );
    let dir = std::env::temp_dir().join(format!("firemedium-abi-bricks-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("sparse.vdb");
    std::fs::write(&file, bytes).unwrap();
    let v = plugin()
        .create_volume(&[
            Param::string("filename", file.to_str().unwrap()),
            Param::string("fuel", "propane"),
        ])
        .unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
    // The lattice starts at the first active sample (11, 8, 0) of index space.
    assert_eq!(v.info().dims, [200 + 8 - 11, 16 + 8 - 8, 64 + 8]);
    let mut got = v.bricks().unwrap();
    got.sort();
    assert_eq!(got, vec![[-3, 8, 0], [-3, 8, 8], [189, 0, 64]]);
}

#[test]
fn four_threads_give_the_single_thread_results() {
    let p = plugin();
    let v = p
        .create_volume(&[fire_params(), vec![Param::string("integrator", "ratio")]].concat())
        .unwrap();
    let c = v.info().channels as usize;
    let rs = rays(2000);
    let mut single = vec![0f32; rs.len() * c];
    v.integrate(&rs, &mut single, None, None).unwrap();
    let chunks: Vec<&[Ray]> = rs.chunks(500).collect();
    let results: Vec<Vec<f32>> = std::thread::scope(|s| {
        let handles: Vec<_> = chunks
            .iter()
            .map(|chunk| {
                let v = &v;
                s.spawn(move || {
                    let mut out = vec![0f32; chunk.len() * c];
                    v.integrate(chunk, &mut out, None, None).unwrap();
                    out
                })
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(
        results.concat(),
        single,
        "threaded results differ from single-threaded ones"
    );
}

#[test]
fn errors_come_back_typed() {
    let p = plugin();
    match p.create_volume(&[fire_params(), vec![Param::float("stepsise", 0.25)]].concat()) {
        Err(Error::Status {
            code,
            message,
            detail,
        }) => {
            assert_eq!(code, firemedium_abi::FM_INVALID_PARAMETER);
            assert!(message.contains("did you mean 'stepsize'"), "{message}");
            // ABI 0.12: the parameter at fault as a field, not only in the text; 1.4: its index in the list.
            assert_eq!(detail.parameter.as_deref(), Some("stepsise"));
            assert_eq!(detail.index, Some(fire_params().len()));
        }
        other => panic!("expected a parameter error, got {other:?}"),
    }
    match p.create_volume(&[Param::string("filename", "/no/such/fire.vdb")]) {
        Err(Error::Status {
            code,
            message,
            detail,
        }) => {
            assert_eq!(code, firemedium_abi::FM_DATASET);
            assert_eq!(detail.file.as_deref(), Some("/no/such/fire.vdb"));
            assert_eq!(detail.index, None, "a file's error names no parameter");
            assert!(
                message.contains("/no/such/fire.vdb: cannot read"),
                "{message}"
            );
        }
        other => panic!("expected a dataset error, got {other:?}"),
    }
    let wrong_type = Param {
        name: "stepsize".into(),
        value: Value::String(vec!["fast".into()]),
        at: Some("scene.pbrt:12:5".into()),
    };
    let err = p
        .create_volume(&[fire_params(), vec![wrong_type]].concat())
        .unwrap_err();
    let e = err.to_string();
    // The error names the parameter, what it is and what was expected, from where the host said it was given —
    // in the text, and (ABI 0.12) as fields a host reads without parsing it.
    assert!(
        e.starts_with("scene.pbrt:12:5: volume: parameter 'stepsize'") && e.contains("float"),
        "{e}"
    );
    let Error::Status { detail, .. } = err else {
        panic!("{err:?}")
    };
    assert_eq!(
        (
            detail.parameter.as_deref(),
            detail.location.as_deref(),
            detail.index
        ),
        (
            Some("stepsize"),
            Some("scene.pbrt:12:5"),
            Some(fire_params().len())
        )
    );
    // A host that keeps its parameters' places passes none: the message begins with the plugin's component,
    // and the index says which parameter.
    let typo = [
        Param::float("sootscale", 1e-6),
        Param::string("filename", &fire_file()),
        Param::float("temperaturscale", 1000.0),
    ];
    let err = p.create_volume(&typo).unwrap_err();
    let Error::Status { detail, .. } = &err else {
        panic!("{err:?}")
    };
    assert!(err.to_string().starts_with("volume: "), "{err}");
    assert_eq!((detail.index, detail.location.as_deref()), (Some(2), None));
    // A file's content at fault: the file and the position in it.
    let dir = std::env::temp_dir().join(format!("firemedium-abi-detail-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let broken = dir.join("broken.vdb");
    std::fs::write(&broken, b"not an OpenVDB file at all").unwrap();
    let err = p
        .create_volume(&[Param::string("filename", broken.to_str().unwrap())])
        .unwrap_err();
    std::fs::remove_dir_all(&dir).unwrap();
    let Error::Status { detail, .. } = &err else {
        panic!("{err:?}")
    };
    assert_eq!(detail.file.as_deref(), broken.to_str());
    assert_eq!(detail.position.as_deref(), Some("byte 0"), "{err}");
    let v = p.create_volume(&fire_params()).unwrap();
    let mut small = vec![0f32; 10];
    assert!(matches!(
        v.integrate(&rays(2), &mut small, None, None),
        Err(Error::Buffer(_))
    ));
}

#[test]
fn volumes_keep_the_library_alive() {
    let v = {
        let p = plugin();
        p.create_volume(&fire_params()).unwrap()
    }; // the Plugin is dropped here; the volume holds the library.
    let c = v.info().channels as usize;
    let mut t = vec![0f32; 3 * c];
    v.transmittance(&rays(3), &mut t).unwrap();
    assert!(t.iter().all(|x| (0.0..=1.0).contains(x)));
}

#[test]
fn not_found_and_not_a_plugin() {
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let e = unsafe { Plugin::find(&[PathBuf::from("/nonexistent-dir")]) }
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("no firemedium plugin found") && e.contains("/nonexistent-dir"),
        "{e}"
    );
    // SAFETY: files this test made or chose (a firemedium build, a stale or fake library, or no library at all).
    let e = unsafe { Plugin::load("/nonexistent-dir/libfoo.so") }
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot load the firemedium plugin /nonexistent-dir/libfoo.so"),
        "{e}"
    );
}

#[test]
fn ray_times_blur_a_volume_with_velocity_and_nothing_else() {
    // ABI 0.5: Mantaflow's own `velocity` vector grid (solver units, scaled down), the shutter over half a frame.
    let p = plugin();
    let with = |extra: &[Param]| {
        let mut list = fire_params();
        list.extend_from_slice(extra);
        p.create_volume(&list).unwrap()
    };
    let blur = [
        Param::string("velocitygrid", "velocity"),
        Param::float("velocityscale", 0.05),
        Param::float("shutterclose", 0.5),
    ];
    let moving = with(&blur);
    let still = with(&[]);
    let mut closed_params = blur.to_vec();
    closed_params[2] = Param::float("shutterclose", 0.0);
    let closed = with(&closed_params);
    let rs = rays(64);
    let c = 32;
    let run = |v: &firemedium_loader::Volume, times: Option<&[f64]>| {
        let (mut l, mut t) = (vec![0f32; 64 * c], vec![0f32; 64 * c]);
        v.integrate_at(&rs, times, &mut l, Some(&mut t), None)
            .unwrap();
        let mut tr = vec![0f32; 64 * c];
        v.transmittance_at(&rs, times, &mut tr).unwrap();
        let mut ev = vec![Default::default(); 64];
        let mut w = vec![0f32; 64 * c];
        v.sample_scatter_at(&rs, times, &mut ev, &mut w, None)
            .unwrap();
        (l, t, tr)
    };
    let (zero, late) = (vec![0.0; 64], vec![0.4; 64]);
    let base = run(&still, None);
    // At time 0 every volume is the still one, bit for bit; without a velocity grid, or with the shutter
    // closed, times change nothing.
    assert!(run(&moving, Some(&zero)) == base);
    assert!(run(&still, Some(&late)) == base);
    assert!(run(&closed, Some(&late)) == base);
    // At 0.4 frames the fire has moved (its rays see other radiance), and stays finite and physical.
    let (l, t, tr) = run(&moving, Some(&late));
    let changed = (0..64)
        .filter(|&i| l[i * c + 29] != base.0[i * c + 29])
        .count();
    assert!(changed > 10, "only {changed} of 64 rays changed");
    assert!(l.iter().all(|x| x.is_finite() && *x >= 0.0));
    assert!(t.iter().chain(&tr).all(|x| (0.0..=1.0).contains(x)));
    // Times are checked: one per ray, finite.
    let mut l = vec![0f32; 64 * c];
    let e = moving.integrate_at(&rs, Some(&late[..3]), &mut l, None, None);
    assert!(matches!(e, Err(Error::Buffer(_))), "{e:?}");
    let mut nan = late.clone();
    nan[7] = f64::NAN;
    let e = moving
        .integrate_at(&rs, Some(&nan), &mut l, None, None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("times[7] = NaN"), "{e}");
}

#[test]
fn an_art_directed_colour_is_seen_against_d65() {
    // ABI 0.6: the white a viewer adapts to — the hottest temperature of a physically coloured fire; none for a
    // fire coloured by a ramp (the artist's colours are meant for a D65 display), nor without temperature.
    let p = plugin();
    let make = |extra: Vec<Param>| {
        let mut list = vec![
            Param::int("nx", 2),
            Param::int("ny", 1),
            Param::int("nz", 1),
            Param {
                name: "density".into(),
                value: Value::Float(vec![1e-6, 1e-6]),
                at: None,
            },
            Param {
                name: "temperature".into(),
                value: Value::Float(vec![1200.0, 1800.0]),
                at: None,
            },
        ];
        list.extend(extra);
        p.create_volume(&list).unwrap()
    };
    assert_eq!(make(vec![]).white_temperature().unwrap(), Some(1800.0));
    let ramp = Param {
        name: "colorramp".into(),
        value: Value::Float(vec![1000.0, 0.0, 0.5, 1.0]),
        at: None,
    };
    assert_eq!(make(vec![ramp.clone()]).white_temperature().unwrap(), None);
    let physical = Param::float("physical", 1.0);
    assert_eq!(
        make(vec![ramp, physical]).white_temperature().unwrap(),
        Some(1800.0)
    );
    assert_eq!(
        make(vec![Param::string("look", "gasburner")])
            .white_temperature()
            .unwrap(),
        None
    );
}

#[test]
fn the_whole_ray_query_takes_the_hosts_first_number_and_step() {
    // ABI 1.0's one whole-ray query: a host's own first uniform number per ray (its sampler's, stratified)
    // replaces the first number of the ray's stream — the march's offset, tracking's first free flight — and a
    // step of the host's makes a coarser march.
    use firemedium_abi::FM_EVENT_SCATTERED;
    use firemedium_loader::{Sampling, Scatter};
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let c = v.info().channels as usize;
    let ray = rays(9)[4];
    // The march draws one number a ray: with the host's, the seed no longer matters.
    let seeded: Vec<Ray> = (0..4).map(|s| Ray { seed: s, ..ray }).collect();
    let mut own = vec![0f32; 4 * c];
    v.integrate(&seeded, &mut own, None, None).unwrap();
    assert!(
        own[..c] != own[c..2 * c],
        "the seeds give different offsets"
    );
    let u = [0.3; 4];
    let given = Sampling {
        u: Some(&u),
        ..Sampling::default()
    };
    let mut with_u = vec![0f32; 4 * c];
    v.integrate_with(&seeded, &given, &mut with_u, None, None)
        .unwrap();
    assert!(with_u[29] > 0.0);
    for s in 1..4 {
        assert_eq!(with_u[..c], with_u[s * c..(s + 1) * c], "seed {s}");
    }
    // Stratified offsets average to the seeds' mean: 64 numbers (k + ½)/64 against 256 seeds.
    let fan: Vec<Ray> = (0..256).map(|s| Ray { seed: s, ..ray }).collect();
    let mut l = vec![0f32; 256 * c];
    v.integrate(&fan, &mut l, None, None).unwrap();
    let mean = |l: &[f32], n: usize| (0..n).map(|i| l[i * c + 29] as f64).sum::<f64>() / n as f64;
    let seeds_mean = mean(&l, 256);
    let strata: Vec<f64> = (0..64).map(|k| (k as f64 + 0.5) / 64.0).collect();
    let mut ls = vec![0f32; 64 * c];
    let s = Sampling {
        u: Some(&strata),
        ..Sampling::default()
    };
    v.integrate_with(&fan[..64], &s, &mut ls, None, None)
        .unwrap();
    let strata_mean = mean(&ls, 64);
    assert!(
        (strata_mean / seeds_mean - 1.0).abs() < 2e-3,
        "{strata_mean} vs {seeds_mean}"
    );
    // A number outside [0, 1) is refused, naming the ray.
    let bad = [0.5, 1.0];
    let e = v
        .integrate_with(
            &seeded[..2],
            &Sampling {
                u: Some(&bad),
                ..Sampling::default()
            },
            &mut with_u[..2 * c],
            None,
            None,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("u[1] = 1: expected a number in [0, 1)"), "{e}");

    // The step: 0 is the volume's own, bit for bit; four times the volume's is a coarser march of the same fire —
    // each ray's estimate differs, their mean over 256 seeds agrees within a per cent (the offset is jittered).
    let own_step = v.info().step;
    let mut b = vec![0f32; 256 * c];
    v.integrate_with(&fan, &Sampling::default(), &mut b, None, None)
        .unwrap();
    assert_eq!(l, b);
    let coarse = Sampling {
        step: 4.0 * own_step,
        ..Sampling::default()
    };
    v.integrate_with(&fan, &coarse, &mut b, None, None).unwrap();
    assert!(l != b, "a coarser march");
    let coarse_mean = mean(&b, 256);
    assert!(
        (coarse_mean / seeds_mean - 1.0).abs() < 0.01,
        "{coarse_mean} vs {seeds_mean}"
    );
    let fan9 = rays(9);
    let mut b = vec![0f32; 9 * c];
    // A step of its own is for straight rays: with exits it is refused.
    let mut exits = vec![Default::default(); 9];
    let e = v
        .integrate_with(&fan9, &coarse, &mut b, None, Some(&mut exits))
        .unwrap_err()
        .to_string();
    assert!(e.contains("exits must be null"), "{e}");

    // Delta tracking's first free flight is the host's number: in a constant scattering slab (2³ voxels of soot
    // at 1500 K, f_v 1e-9: σ_a ≈ 0.01 m⁻¹ beside σ_s 20 m⁻¹, so that the first tentative collision is a real one), two numbers u₁ < u₂ put
    // their events ln((1 − u₁)/(1 − u₂)) / σ̄ apart, σ̄ the majorant there, whatever the seeds.
    let grid = |name: &str, x: f64| Param {
        name: name.into(),
        value: Value::Float(vec![x; 8]),
        at: None,
    };
    let sv = p
        .create_volume(&[
            grid("density", 1.0),
            grid("temperature", 1500.0),
            Param::int("nx", 2),
            Param::int("ny", 2),
            Param::int("nz", 2),
            Param::float("sootscale", 1e-9),
            Param::float("sigma_s", 20.0),
        ])
        .unwrap();
    let g = sv.majorant_grid().unwrap();
    let r = Ray {
        origin: [-1.0, 0.5, 0.5],
        direction: [1.0, 0.0, 0.0],
        tmin: 0.0,
        tmax: 10.0,
        seed: 5,
    };
    let twice = [r, Ray { seed: 77, ..r }];
    let us = [0.02, 0.05];
    let mut ev = [Scatter::default(); 2];
    let mut w = vec![0f32; 2 * c];
    sv.sample_scatter_with(
        &twice,
        &Sampling {
            u: Some(&us),
            ..Sampling::default()
        },
        &mut ev,
        &mut w,
        None,
    )
    .unwrap();
    assert!(ev.iter().all(|e| e.event == FM_EVENT_SCATTERED), "{ev:?}");
    let sigma = g.at(ev[0].point);
    assert_eq!(g.cell_of(ev[0].point), g.cell_of(ev[1].point));
    let want = ((1.0 - us[0]) / (1.0 - us[1])).ln() / sigma;
    assert!(
        ((ev[1].t - ev[0].t) / want - 1.0).abs() < 1e-9,
        "{} vs {want}",
        ev[1].t - ev[0].t
    );
}
