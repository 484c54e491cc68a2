//! End-to-end through the C ABI: load the **built** plugin library (not the rlib) with the loader, create fire
//! volumes, integrate from four threads at once, and check errors and lifetimes (that a panic inside the plugin
//! comes back as a status is the plugin's own test, `export::tests`: test-only code never enters the shipped build).
//!
//! Declared as a test of `firemedium-loader`, whose dev-dependency on the plugin makes Cargo build the plugin's
//! cdylib (the shipped build) into the same target directory.

use firemedium_loader::{library_file_name, Error, Param, Plugin, Ray, Value};
use std::path::PathBuf;

fn plugin() -> Plugin {
    // The test executable lives in target/<profile>/deps, beside the cdylib Cargo built for this run.
    let deps = std::env::current_exe()
        .unwrap()
        .parent()
        .unwrap()
        .to_path_buf();
    let dirs = [deps.clone(), deps.parent().unwrap().to_path_buf()];
    // SAFETY: the plugin this cargo invocation built.
    unsafe { Plugin::find(&dirs) }.unwrap_or_else(|e| {
        panic!(
            "{e} — the plugin cdylib ({}) should be built by `cargo test`",
            library_file_name()
        )
    })
}

fn fire_file() -> String {
    crate::common::root()
        .join("tests/data/valid/vdb/mantaflow_fire_f060.vdb")
        .to_string_lossy()
        .into_owned()
}

fn fire_params() -> Vec<Param> {
    vec![
        Param::string("filename", &fire_file()),
        Param::float("temperaturescale", 1000.0),
        Param::float("sootscale", 1e-6),
    ]
}

fn rays(n: usize) -> Vec<Ray> {
    // A fan of rays through the fire (medium space: the Mantaflow grid spans about [0, 2]² × [0, 3] m).
    (0..n)
        .map(|i| {
            let f = i as f64 / n as f64;
            Ray {
                origin: [
                    0.2 + 1.6 * f,
                    -1.0,
                    0.3 + 2.0 * ((i * 7) % n) as f64 / n as f64,
                ],
                direction: [0.05 * (f - 0.5), 1.0, 0.1 * (0.5 - f)],
                tmin: 0.0,
                tmax: 5.0,
                seed: i as u64,
            }
        })
        .collect()
}

#[test]
fn loads_describes_and_integrates() {
    let p = plugin();
    assert_eq!(p.version(), (1, 2));
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
            // ABI 0.12: the parameter at fault as a field, not only in the text.
            assert_eq!(detail.parameter.as_deref(), Some("stepsise"));
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
        (detail.parameter.as_deref(), detail.location.as_deref()),
        (Some("stepsize"), Some("scene.pbrt:12:5"))
    );
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
fn the_fire_light_samples_through_the_abi() {
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let light = v.create_light(None).unwrap();
    let lum = v.create_light(Some("luminance")).unwrap();
    // The volume handle may go first: the light holds its own reference.
    drop(v);
    let info = light.info();
    assert_eq!(info.weighting, firemedium_abi::FM_WEIGHTING_POWER);
    assert_eq!(lum.info().weighting, firemedium_abi::FM_WEIGHTING_LUMINANCE);
    assert!(info.voxels > 1000 && info.power_w > 0.0 && info.power_lm > 0.0);
    // Both weightings describe the same fire: the same total power.
    assert_eq!(info.power_w, lum.info().power_w);

    let n = 2000;
    let mut rng = firemedium_plugin::rng::Rng::new(7);
    let u: Vec<[f64; 6]> = (0..n).map(|_| [(); 6].map(|_| rng.next_f64())).collect();
    let (mut pts, mut pdf, mut em) = (vec![[0.0; 3]; n], vec![0.0; n], vec![0f32; n * 32]);
    light.sample(&u, &mut pts, &mut pdf, Some(&mut em)).unwrap();
    let mut again = vec![0.0; n];
    light.pdf(&pts, &mut again).unwrap();
    for i in 0..n {
        assert!(
            pdf[i] > 0.0 && (again[i] / pdf[i] - 1.0).abs() < 1e-5,
            "{} vs {}",
            pdf[i],
            again[i]
        );
        assert!(
            pts[i].iter().all(|c| (-0.01..3.01).contains(c)),
            "{:?}",
            pts[i]
        );
        assert!(em[i * 32..(i + 1) * 32]
            .iter()
            .all(|e| e.is_finite() && *e >= 0.0));
    }
    // Seen from beside the fire, the direction of a sampled point has positive density; away from it, zero.
    let o = [[1.0, -2.0, 1.0]];
    let toward = [[pts[0][0] - 1.0, pts[0][1] + 2.0, pts[0][2] - 1.0]];
    let mut pd = [0.0];
    light.pdf_direction(&o, &toward, &mut pd).unwrap();
    assert!(pd[0] > 0.0);
    light
        .pdf_direction(&o, &[[0.0, -1.0, 0.0]], &mut pd)
        .unwrap();
    assert_eq!(pd[0], 0.0);

    let e = p
        .create_volume(&fire_params())
        .unwrap()
        .create_light(Some("brightest"))
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("weighting") && e.contains("brightest") && e.contains("power"),
        "{e}"
    );
    let mut short = vec![0.0; 1];
    assert!(matches!(
        light.sample(&u[..2], &mut pts[..2], &mut short, None),
        Err(Error::Buffer(_))
    ));
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
fn the_fire_lights_line_estimate_through_the_abi() {
    // `light_integrate_at`: at the volume's own step, the volume's march bit for bit; with a coarse step, the
    // same fire to within the march's discretisation; with the correction always taken (probability 1), the
    // volume's march again (coarse + (fine − coarse) / 1); bad parameters named.
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let c = v.info().channels as usize;
    let rs = rays(64);
    let (mut lv, mut tv) = (vec![0f32; rs.len() * c], vec![0f32; rs.len() * c]);
    v.integrate_at(&rs, None, &mut lv, Some(&mut tv), None)
        .unwrap();
    let light_with = |extra: &[Param]| {
        let mut list = vec![Param::string("weighting", "power")];
        list.extend_from_slice(extra);
        v.create_light_with(&list)
    };
    let run = |light: &firemedium_loader::Light| {
        let (mut l, mut t) = (vec![0f32; rs.len() * c], vec![0f32; rs.len() * c]);
        light.integrate_at(&rs, None, &mut l, Some(&mut t)).unwrap();
        (l, t)
    };
    // The volume's step (the default stepsize, ½ voxel) is below this fire's longest side / 64 (96 voxels:
    // 1.5): `linestep` 0.5 is the volume's own march.
    let same = light_with(&[Param::float("linestep", 0.5)]).unwrap();
    assert_eq!(run(&same), (lv.clone(), tv.clone()));
    let total = |l: &[f32]| l.iter().map(|&x| x as f64).sum::<f64>();
    let coarse = light_with(&[]).unwrap();
    let (lc, tc) = run(&coarse);
    assert_ne!(
        lc, lv,
        "the default step (longest side / 64) is coarser here"
    );
    assert!(tc.iter().all(|t| (0.0..=1.0).contains(t)));
    // Its expectation (each ray with 64 seeds: the march's jitter averaged out) against the volume's march's.
    let mean = |light: Option<&firemedium_loader::Light>| {
        let mut sum = 0.0;
        for k in 0..64u64 {
            let rk: Vec<Ray> = rs
                .iter()
                .map(|r| Ray {
                    seed: r.seed.wrapping_mul(7919).wrapping_add(k),
                    ..*r
                })
                .collect();
            let mut l = vec![0f32; rk.len() * c];
            match light {
                Some(lt) => lt.integrate_at(&rk, None, &mut l, None).unwrap(),
                None => v.integrate_at(&rk, None, &mut l, None, None).unwrap(),
            }
            sum += total(&l);
        }
        sum
    };
    let rel = mean(Some(&coarse)) / mean(None) - 1.0;
    eprintln!("coarse line estimate against the volume's march: {rel:+.3e}");
    assert!(rel.abs() < 0.01, "coarse line estimate off by {rel}");
    // This thick fire's copy of 2³ blocks strays (its build-time check refuses it): the default line marches
    // the fire's own voxels, as `lineblock` 1 asks; `lineblock` 2 forces the copy, several per cent off.
    let own = light_with(&[Param::int("lineblock", 1)]).unwrap();
    assert_eq!(run(&own), (lc.clone(), tc.clone()));
    let copy = light_with(&[Param::int("lineblock", 2)]).unwrap();
    let rel_copy = mean(Some(&copy)) / mean(None) - 1.0;
    eprintln!("through the copy of 2³ blocks: {rel_copy:+.3e}");
    assert!(rel_copy < -0.02, "{rel_copy}");
    // The light says which (ABI 0.9: `FmLightInfo::line_block`).
    let blocks = |l: &firemedium_loader::Light| l.info().line_block;
    assert_eq!((blocks(&coarse), blocks(&own), blocks(&copy)), (1, 1, 2));
    // And in how many of the volume's channels (ABI 0.10): this thick fire's line in every bin (its build-time
    // check refuses the line in 8, whose X, Y or Z strays by more than 0.2 % on its rays); in 8 when asked, its
    // luminance then within 0.2 % of every bin's on these rays.
    let few = light_with(&[Param::int("linechannels", 8)]).unwrap();
    assert_eq!(coarse.line_channels().unwrap() as usize, c);
    assert_eq!(few.line_channels().unwrap(), 8);
    let (la, _) = run(&few);
    let y = |l: &[f32]| {
        let xyz = v.channel_xyz().unwrap();
        l.chunks(c)
            .map(|r| (0..c).map(|k| r[k] as f64 * xyz[k][1]).sum::<f64>())
            .sum::<f64>()
    };
    let rel_y = y(&la) / y(&lc) - 1.0;
    eprintln!("the line in 8 bins against every bin, Y: {rel_y:+.3e}");
    assert!(rel_y.abs() < 2e-3 && la != lc, "{rel_y}");
    let corrected = light_with(&[Param::float("linecorrection", 1.0)]).unwrap();
    let (lq, tq) = run(&corrected);
    for k in 0..lq.len() {
        assert!(
            (lq[k] - lv[k]).abs() <= 1e-5 * lv[k].abs() + 1e-30,
            "{k}: {} vs {}",
            lq[k],
            lv[k]
        );
        assert!((tq[k] - tv[k]).abs() <= 1e-6, "{k}");
    }
    for (name, value, want) in [
        ("linecorrection", 1.5, "linecorrection"),
        ("linestep", -1.0, "linestep"),
        ("cell", 3.0, "cell"),
        ("lineblock", 3.0, "lineblock"),
    ] {
        let param = if name == "cell" || name == "lineblock" {
            Param::int(name, value as i64)
        } else {
            Param::float(name, value)
        };
        let e = light_with(&[param]).unwrap_err().to_string();
        assert!(e.contains(want), "{name} = {value}: {e}");
    }
    let mut short = vec![0f32; 3];
    assert!(matches!(
        coarse.integrate_at(&rs, None, &mut short, None),
        Err(Error::Buffer(_))
    ));
}

#[test]
fn a_host_tracks_the_fire_itself_through_its_majorant_grid_and_point_coefficients() {
    // ABI 0.11, the medium level's first part: what the volume holds (features) and its majorant grid, beside
    // the point coefficients. A host's own ratio tracking — its own DDA over the exported cells, the plugin
    // asked only for σ at its tentative collisions — gives the transmittance the plugin's own march gives.
    let p = plugin();
    let with = |extra: &[Param]| {
        let mut list = fire_params();
        list.extend_from_slice(extra);
        p.create_volume(&list).unwrap()
    };
    use firemedium_loader::{
        FM_FEATURE_EMITS, FM_FEATURE_EMITS_WITHOUT_ABSORPTION, FM_FEATURE_MOTION,
        FM_FEATURE_SCATTERS,
    };
    let v = with(&[]);
    assert_eq!(v.features().unwrap(), FM_FEATURE_EMITS);
    let blur = [
        Param::string("velocitygrid", "velocity"),
        Param::float("velocityscale", 0.05),
        Param::float("shutterclose", 0.5),
    ];
    assert_eq!(
        with(&blur).features().unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_MOTION
    );
    assert_eq!(
        with(&[Param::float("sigma_s", 1.0)]).features().unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_SCATTERS
    );
    assert_eq!(
        with(&[Param::string("emissiongrid", "flame")])
            .features()
            .unwrap(),
        FM_FEATURE_EMITS | FM_FEATURE_EMITS_WITHOUT_ABSORPTION
    );
    let grid = v.majorant_grid().unwrap();
    let cells = grid.counts.iter().product::<usize>();
    // With motion blur every cell's bound covers the shutter: at least the still fire's, more somewhere.
    let moving = with(&blur);
    let widened = moving.majorant_grid().unwrap();
    assert_eq!(widened.counts, grid.counts);
    assert!(widened
        .sigma_t
        .iter()
        .zip(grid.sigma_t)
        .all(|(w, s)| w >= s));
    assert!(widened.sigma_t.iter().zip(grid.sigma_t).any(|(w, s)| w > s));
    assert_eq!(grid.sigma_t.len(), cells);
    assert!(grid.sigma_t.iter().any(|&s| s > 0.0) && grid.sigma_t.iter().all(|&s| s >= 0.0));
    // The bound holds at every point, in every channel (2 000 points, the box and a margin around it).
    let c = v.info().channels as usize;
    let mut rng = 1u64;
    let mut u = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    let points: Vec<[f64; 3]> = (0..2000)
        .map(|_| [0, 1, 2].map(|a| grid.lo[a] - 0.01 + (grid.hi[a] - grid.lo[a] + 0.02) * u()))
        .collect();
    let (mut sa, mut ss, mut j) = (
        vec![0f32; points.len() * c],
        vec![0f32; points.len() * c],
        vec![0f32; points.len() * c],
    );
    v.coefficients(&points, &mut sa, &mut ss, &mut j).unwrap();
    for (i, p) in points.iter().enumerate() {
        let most = (0..c)
            .map(|k| sa[i * c + k] as f64 + ss[i * c + k] as f64)
            .fold(0.0, f64::max);
        assert!(
            most <= grid.at(*p) * (1.0 + 1e-5),
            "{p:?}: σ_t {most} over the bound {}",
            grid.at(*p)
        );
    }
    // Ratio tracking by the host, cell by cell, against the plugin's march, in channel 16: first with the
    // plugin's bins (`coefficients`), then pbrt-v4's and Mitsuba's way, each path at a wavelength of its own
    // drawn across that bin (`point`: the closed forms at λ).
    let k = 16;
    let rs = rays(8);
    let mut plugin_t = vec![0f32; rs.len() * c];
    v.transmittance(&rs, &mut plugin_t).unwrap();
    let info = v.info();
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    for at_wavelengths in [false, true] {
        let n = 400;
        for (r, ray) in rs.iter().enumerate() {
            let mut u = u; // (a copy: both passes draw the same numbers)
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let lambda = info.lambda_min + width * (k as f64 + u());
                let (tr, _) = host_path(&grid, ray, &mut u, &mut |x| {
                    if at_wavelengths {
                        let mut o = [firemedium_loader::Point::default()];
                        v.point(&[x], None, &[lambda], &mut o).unwrap();
                        (o[0].sigma_a + o[0].sigma_s, o[0].j)
                    } else {
                        let (mut a1, mut s1, mut j1) =
                            (vec![0f32; c], vec![0f32; c], vec![0f32; c]);
                        v.coefficients(&[x], &mut a1, &mut s1, &mut j1).unwrap();
                        (a1[k] as f64 + s1[k] as f64, j1[k] as f64)
                    }
                });
                sum += tr;
                sum2 += tr * tr;
            }
            let mean = sum / n as f64;
            let sd = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            let want = plugin_t[r * c + k] as f64;
            assert!(
                (mean - want).abs() <= 4.0 * sd + 2e-3,
                "ray {r} (wavelengths: {at_wavelengths}): the host's ratio tracking {mean} ± {sd}, the plugin's march {want}"
            );
            eprintln!("ray {r} (wavelengths: {at_wavelengths}): host {mean:.5} ± {sd:.5}, plugin {want:.5}");
        }
    }
    // The point query at a time: the blurred fire's lookups move (somewhere along the fan), and at time 0 it is
    // the still fire's.
    let pts: Vec<[f64; 3]> = (0..200)
        .map(|i| {
            [
                0.3 + 1.4 * (i % 20) as f64 / 20.0,
                1.0,
                0.3 + 0.2 * (i / 20) as f64,
            ]
        })
        .collect();
    let lambdas = vec![550.0; pts.len()];
    let query = |vol: &firemedium_loader::Volume, t: f64| {
        let mut o = vec![firemedium_loader::Point::default(); pts.len()];
        vol.point(&pts, Some(&vec![t; pts.len()]), &lambdas, &mut o)
            .unwrap();
        o
    };
    assert_eq!(query(&moving, 0.0), query(&v, 0.0));
    assert_ne!(query(&moving, 0.4), query(&v, 0.0));
    // A layer the closed forms cannot express is refused by name.
    let tinted = with(&[Param {
        name: "tint".into(),
        value: firemedium_loader::Value::Rgb(vec![1.0, 0.5, 0.2]),
        at: None,
    }]);
    let e = tinted
        .point(
            &pts[..1],
            None,
            &lambdas[..1],
            &mut [firemedium_loader::Point::default()],
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("art direction"), "{e}");
}

/// A host's own free-flight sampling along `ray` over a volume's majorant grid (its own DDA, one cell at a
/// time): `collide(x, σ̄)` at each tentative collision, which says whether to go on. Returns whether the ray left
/// the cells (rather than being stopped).
fn walk(
    grid: &firemedium_loader::MajorantGrid,
    ray: &Ray,
    u: &mut impl FnMut() -> f64,
    collide: &mut dyn FnMut([f64; 3], f64) -> bool,
) -> bool {
    let at = |t: f64| [0, 1, 2].map(|a| ray.origin[a] + t * ray.direction[a]);
    let speed = ray.direction.iter().map(|d| d * d).sum::<f64>().sqrt();
    // The ray's part inside the cells' box.
    let (mut t0, mut t1) = (ray.tmin, ray.tmax);
    for a in 0..3 {
        let (lo, hi) = (
            (grid.lo[a] - ray.origin[a]) / ray.direction[a],
            (grid.hi[a] - ray.origin[a]) / ray.direction[a],
        );
        t0 = t0.max(lo.min(hi));
        t1 = t1.min(lo.max(hi));
    }
    let mut t = t0;
    while t < t1 {
        // The cell at t and where the ray leaves it.
        let cell = grid.cell_of(at(t + 1e-9));
        let mut exit = t1;
        for a in 0..3 {
            if ray.direction[a] != 0.0 {
                let side = cell[a] + (ray.direction[a] > 0.0) as usize;
                let te =
                    (grid.lo[a] + side as f64 * grid.cell[a] - ray.origin[a]) / ray.direction[a];
                if te > t {
                    exit = exit.min(te);
                }
            }
        }
        let bound = grid.sigma_t[cell[0] + grid.counts[0] * (cell[1] + grid.counts[1] * cell[2])];
        let step = if bound > 0.0 {
            -(1.0 - u()).ln() / (bound * speed)
        } else {
            f64::INFINITY
        };
        if t + step >= exit {
            t = exit;
            continue;
        }
        t += step;
        if !collide(at(t), bound) {
            return false;
        }
    }
    true
}

/// One path of a host's own ratio tracking along `ray` ([`walk`]): the transmittance, and the emission collected
/// pbrt-v4's way — T·j/σ̄ at each tentative collision — with `sigma(x)` giving (σ_t, j) at a collision.
fn host_path(
    grid: &firemedium_loader::MajorantGrid,
    ray: &Ray,
    u: &mut impl FnMut() -> f64,
    sigma: &mut dyn FnMut([f64; 3]) -> (f64, f64),
) -> (f64, f64) {
    let (mut tr, mut l) = (1.0f64, 0.0f64);
    walk(grid, ray, u, &mut |x, bound| {
        let (sigma_t, j) = sigma(x);
        l += tr * j / bound;
        tr *= 1.0 - sigma_t / bound;
        tr > 0.0
    });
    (tr, l)
}

/// A unit direction uniform on the sphere (the isotropic phase function's sample).
fn isotropic(u: &mut impl FnMut() -> f64) -> [f64; 3] {
    let z = 1.0 - 2.0 * u();
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u();
    [r * phi.cos(), r * phi.sin(), z]
}

#[test]
fn a_host_collects_the_fires_emission_at_its_own_wavelengths_and_times() {
    // The medium level alone renders the fire's expected radiance: a host's ratio tracking at one wavelength per
    // path across bin 16, emission collected at its tentative collisions (T·j/σ̄, pbrt-v4's way), against the
    // plugin's whole-ray march — the still fire, and the motion-blurred one at a time in its shutter (the
    // point query's lookups displaced, the cells' bounds widened over the shutter).
    let p = plugin();
    let blur = [
        Param::string("velocitygrid", "velocity"),
        Param::float("velocityscale", 0.05),
        Param::float("shutterclose", 0.5),
    ];
    let make = |extra: &[Param]| {
        let mut list = fire_params();
        list.extend_from_slice(extra);
        p.create_volume(&list).unwrap()
    };
    let (still, moving) = (make(&[]), make(&blur));
    // The expected radiance from the plugin: its march at a tenth of the default step (0.05 voxels), over 32
    // seeds (one march's random offset on this spiky emission moves a ray's value by tens of per cent).
    let fine = |extra: &[Param]| make(&[extra, &[Param::float("stepsize", 0.05)]].concat());
    let (still_fine, moving_fine) = (fine(&[]), fine(&blur));
    let rs = rays(16);
    let c = still.info().channels as usize;
    let k = 16;
    let info = still.info();
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    let mut rng = 7u64;
    let mut u = move || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (rng >> 11) as f64 / (1u64 << 53) as f64
    };
    for (v, reference, time) in [(&still, &still_fine, 0.0), (&moving, &moving_fine, 0.4)] {
        let grid = v.majorant_grid().unwrap();
        let times = vec![time; rs.len()];
        let mut pl = vec![0f64; rs.len() * c];
        let seeds = 32;
        for s in 0..seeds {
            let rs: Vec<Ray> = rs
                .iter()
                .map(|r| Ray {
                    seed: 100 + s,
                    ..*r
                })
                .collect();
            let mut l = vec![0f32; rs.len() * c];
            reference
                .integrate_at(&rs, Some(&times), &mut l, None, None)
                .unwrap();
            for (a, b) in pl.iter_mut().zip(&l) {
                *a += *b as f64 / seeds as f64;
            }
        }
        let n = 2000;
        let mut seen = 0;
        for (r, ray) in rs.iter().enumerate() {
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let lambda = info.lambda_min + width * (k as f64 + u());
                let (_, l) = host_path(&grid, ray, &mut u, &mut |x| {
                    let mut o = [firemedium_loader::Point::default()];
                    v.point(&[x], Some(&[time]), &[lambda], &mut o).unwrap();
                    (o[0].sigma_a + o[0].sigma_s, o[0].j)
                });
                sum += l;
                sum2 += l * l;
            }
            let mean = sum / n as f64;
            let sd = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            let want = pl[r * c + k];
            eprintln!("time {time}, ray {r}: host {mean:.6e} ± {sd:.2e}, plugin {want:.6e}");
            assert!(
                (mean - want).abs() <= 4.0 * sd + 0.01 * want,
                "time {time}, ray {r}: the host's radiance {mean} ± {sd}, the plugin's march {want}"
            );
            seen += (want > 0.0) as usize;
        }
        assert!(seen >= 4, "the fan crosses the fire: {seen} rays see it");
    }
}

#[test]
fn the_hosts_context_goes_beside_the_scenes_parameters() {
    // ABI 0.13: threads, the memory budget, the frame and the shutter in the creation info, not made-up
    // parameters; a parameter the scene sets itself wins.
    use firemedium_loader::{Context, FM_FEATURE_MOTION};
    let p = plugin();
    let tight = Context {
        max_bytes: Some(1000),
        threads: Some(1),
        ..Default::default()
    };
    let e = p.create_volume_with(&fire_params(), &tight).unwrap_err();
    assert!(
        e.to_string().contains("above the memory cap of 1000 bytes"),
        "{e}"
    );
    let own = [fire_params(), vec![Param::float("maxbytes", 1e9)]].concat();
    assert!(p.create_volume_with(&own, &tight).is_ok());
    // The shutter: a velocity grid blurs over the context's shutter, and not without one.
    let moving = [
        fire_params(),
        vec![Param::string("velocitygrid", "velocity")],
    ]
    .concat();
    let open = Context {
        shutter: Some([0.0, 0.5]),
        ..Default::default()
    };
    let blurred = p.create_volume_with(&moving, &open).unwrap();
    assert_eq!(
        blurred.features().unwrap() & FM_FEATURE_MOTION,
        FM_FEATURE_MOTION
    );
    let still = p.create_volume_with(&moving, &Context::default()).unwrap();
    assert_eq!(still.features().unwrap() & FM_FEATURE_MOTION, 0);
    // The same volume either way: the context as parameters gives the same numbers.
    let as_params = [
        moving.clone(),
        vec![
            Param::float("shutteropen", 0.0),
            Param::float("shutterclose", 0.5),
        ],
    ]
    .concat();
    let by_params = p.create_volume(&as_params).unwrap();
    let rs = rays(16);
    let c = blurred.info().channels as usize;
    let (mut a, mut b) = (vec![0f32; rs.len() * c], vec![0f32; rs.len() * c]);
    let times = vec![0.3; rs.len()];
    blurred
        .integrate_at(&rs, Some(&times), &mut a, None, None)
        .unwrap();
    by_params
        .integrate_at(&rs, Some(&times), &mut b, None, None)
        .unwrap();
    assert_eq!(a, b);
    assert!(a.iter().any(|&v| v > 0.0));
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

#[test]
fn a_host_tracks_a_scattering_fire_through_the_medium_level_alone() {
    // A scattering fire (σ_s = 8 m⁻¹ per unit density beside soot's σ_a ≈ 8: albedo about ½, isotropic) rendered
    // twice by a host's own volumetric path tracer: once through the medium level alone — delta tracking over the
    // exported majorant grid with the point coefficients at one wavelength per path across bin 16, emission
    // collected pbrt-v4's way (j/σ̄ at every tentative collision), absorption, scattering or a null collision
    // chosen by σ_a/σ̄ and σ_s/σ̄ — and once through the fast path (the plugin's scattering events and their
    // weights, the host sampling the phase function). The same expected radiance along each ray, within the
    // noise of both.
    use firemedium_loader::{Point, Scatter, FM_FEATURE_SCATTERS};
    let p = plugin();
    let mut list = fire_params();
    list.push(Param::float("sigma_s", 8.0));
    let v = p.create_volume(&list).unwrap();
    assert_ne!(v.features().unwrap() & FM_FEATURE_SCATTERS, 0);
    let info = v.info();
    assert_eq!(info.g, 0.0, "isotropic");
    let grid = v.majorant_grid().unwrap();
    let c = info.channels as usize;
    let k = 16;
    let width = (info.lambda_max - info.lambda_min) / c as f64;
    // (One stream, shared by the free flights and the collisions' choices: a copyable closure over a cell.)
    let rng = std::cell::Cell::new(11u64);
    let u = || {
        rng.set(
            rng.get()
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407),
        );
        (rng.get() >> 11) as f64 / (1u64 << 53) as f64
    };
    const DEPTH: usize = 64;
    let (n, rs) = (8000, rays(16));
    let (mut scattered, mut seen) = (0usize, 0);
    for (r, ray) in rs.iter().enumerate() {
        let (mut host, mut fast) = ((0.0, 0.0), (0.0, 0.0));
        for i in 0..n {
            // The medium level alone.
            let lambda = info.lambda_min + width * (k as f64 + u());
            let (mut l, mut path) = (0.0, *ray);
            for _ in 0..DEPTH {
                let mut next = None;
                let escaped = walk(&grid, &path, &mut { u }, &mut |x, bound| {
                    let mut o = [Point::default()];
                    v.point(&[x], None, &[lambda], &mut o).unwrap();
                    l += o[0].j / bound;
                    let xi = u();
                    if xi < o[0].sigma_a / bound {
                        return false;
                    }
                    if xi < (o[0].sigma_a + o[0].sigma_s) / bound {
                        next = Some(x);
                        return false;
                    }
                    true
                });
                match next {
                    Some(x) if !escaped => {
                        scattered += 1;
                        path = Ray {
                            origin: x,
                            direction: isotropic(&mut { u }),
                            tmin: 0.0,
                            tmax: f64::INFINITY,
                            ..path
                        };
                    }
                    _ => break,
                }
            }
            host.0 += l;
            host.1 += l * l;
            // The fast path: the plugin's events, the host's phase function.
            let (mut l, mut beta, mut path) = (0.0, 1.0, *ray);
            for d in 0..DEPTH {
                path.seed = (i * DEPTH + d) as u64 * 977 + r as u64;
                let mut ev = [Scatter::default()];
                let (mut w, mut e) = (vec![0f32; c], vec![0f32; c]);
                v.sample_scatter(std::slice::from_ref(&path), &mut ev, &mut w, Some(&mut e))
                    .unwrap();
                l += beta * e[k] as f64;
                if ev[0].event != firemedium_abi::FM_EVENT_SCATTERED {
                    break;
                }
                beta *= w[k] as f64;
                path = Ray {
                    origin: ev[0].point,
                    direction: isotropic(&mut { u }),
                    tmin: 0.0,
                    tmax: f64::INFINITY,
                    ..path
                };
            }
            fast.0 += l;
            fast.1 += l * l;
        }
        let stats = |(s, s2): (f64, f64)| {
            let m = s / n as f64;
            (m, ((s2 / n as f64 - m * m).max(0.0) / n as f64).sqrt())
        };
        let ((hm, hs), (fm, fs)) = (stats(host), stats(fast));
        let sd = (hs * hs + fs * fs).sqrt();
        eprintln!("ray {r}: medium level {hm:.6e} ± {hs:.1e}, fast path {fm:.6e} ± {fs:.1e}");
        assert!(
            (hm - fm).abs() <= 4.0 * sd + 0.01 * fm,
            "ray {r}: through the medium level {hm} ± {hs}, through the fast path {fm} ± {fs}"
        );
        seen += (fm > 0.0) as usize;
    }
    assert!(seen >= 4, "the fan crosses the fire: {seen} rays see it");
    assert!(
        scattered > n,
        "paths scatter in the fire: {scattered} events"
    );
}

#[test]
fn the_hosts_thread_pool_runs_the_builds_parallel_parts() {
    // A host lending its pool (FmCreateInfo::parallel_for): the volume's and its light's build run their
    // parallel parts (table rows, lattice slabs, the light's bricks) as the pool's tasks, on the pool's threads,
    // and build the same fire as the plugin's own threads do.
    use firemedium_loader::{Context, ThreadPool};
    use std::sync::atomic::{AtomicUsize, Ordering};
    use std::sync::{Arc, Mutex};
    let p = plugin();
    let tasks = Arc::new(AtomicUsize::new(0));
    let names = Arc::new(Mutex::new(std::collections::BTreeSet::new()));
    let (count, seen) = (tasks.clone(), names.clone());
    let pool: ThreadPool = Arc::new(move |n, task| {
        // Three workers of the host's, each taking every third task.
        std::thread::scope(|s| {
            for w in 0..3 {
                let (count, seen) = (&count, &seen);
                std::thread::Builder::new()
                    .name(format!("host-pool-{w}"))
                    .spawn_scoped(s, move || {
                        for i in (w..n).step_by(3) {
                            count.fetch_add(1, Ordering::Relaxed);
                            let me = std::thread::current().name().unwrap_or("").to_string();
                            seen.lock().unwrap().insert(me);
                            task(i);
                        }
                    })
                    .unwrap();
            }
        })
    });
    let context = Context {
        threads: Some(4),
        pool: Some(pool),
        ..Context::default()
    };
    let pooled = p.create_volume_with(&fire_params(), &context).unwrap();
    let after_volume = tasks.load(Ordering::Relaxed);
    assert!(after_volume >= 4, "{after_volume} tasks");
    let light = pooled.create_light(None).unwrap();
    assert!(
        tasks.load(Ordering::Relaxed) > after_volume,
        "the light's build used the pool too"
    );
    let names = names.lock().unwrap().clone();
    assert!(
        !names.is_empty() && names.iter().all(|n| n.starts_with("host-pool-")),
        "{names:?}"
    );
    // The same fire as with the plugin's own threads.
    let own = p
        .create_volume_with(
            &fire_params(),
            &Context {
                threads: Some(4),
                ..Context::default()
            },
        )
        .unwrap();
    let c = own.info().channels as usize;
    let rs = rays(32);
    let (mut a, mut b) = (vec![0f32; 32 * c], vec![0f32; 32 * c]);
    own.integrate(&rs, &mut a, None, None).unwrap();
    pooled.integrate(&rs, &mut b, None, None).unwrap();
    assert_eq!(a, b);
    let own_light = own.create_light(None).unwrap();
    assert_eq!(light.info().power_w, own_light.info().power_w);
    // A pool that runs no task at all: the plugin runs its parts itself.
    let idle: ThreadPool = Arc::new(|_, _| {});
    let lazy = p
        .create_volume_with(
            &fire_params(),
            &Context {
                pool: Some(idle),
                ..Context::default()
            },
        )
        .unwrap();
    lazy.integrate(&rs, &mut b, None, None).unwrap();
    assert_eq!(a, b);
}

#[test]
fn the_medium_handle_carries_what_the_medium_level_can_and_refuses_the_rest() {
    // Volume::medium: the majorants and point coefficients of a plain fire (the same as the volume's own
    // answers), and an error naming the layer for a volume whose layers they cannot carry.
    use firemedium_loader::{Point, FM_FEATURE_EMITS};
    let p = plugin();
    let v = p.create_volume(&fire_params()).unwrap();
    let m = v.medium().unwrap();
    assert_eq!(m.features(), FM_FEATURE_EMITS);
    assert_eq!(m.g(), 0.0);
    let grid = v.majorant_grid().unwrap();
    assert_eq!(m.majorant_grid().sigma_t, grid.sigma_t);
    let x = [1.0, 1.0, 0.6];
    assert_eq!(m.majorant(x), grid.at(x));
    let (mut a, mut b) = ([Point::default(); 2], [Point::default(); 2]);
    m.point(&[x], None, &[450.0, 650.0], &mut a).unwrap();
    v.point(&[x], None, &[450.0, 650.0], &mut b).unwrap();
    assert_eq!(a, b);
    assert!(a[1].sigma_a > 0.0 && a[1].sigma_a <= m.majorant(x));
    for (extra, layer) in [
        (
            Param {
                name: "tint".into(),
                value: Value::Rgb(vec![1.0, 0.5, 0.2]),
                at: None,
            },
            "art direction",
        ),
        (Param::bool("refraction", true), "refraction"),
    ] {
        let mut list = fire_params();
        list.push(extra);
        let e = p
            .create_volume(&list)
            .unwrap()
            .medium()
            .unwrap_err()
            .to_string();
        assert!(e.contains(layer), "{e}");
    }
}

#[test]
fn the_plugin_resolves_its_own_file_names_against_the_hosts_folder() {
    // FmCreateInfo::directory: a relative `filename` is the scene's folder's, so a host passes the fire's
    // parameters as the scene wrote them, knowing none of their names; without the folder it is the working
    // directory's, and a file not there is an error naming it.
    use firemedium_loader::Context;
    let p = plugin();
    let file = PathBuf::from(fire_file());
    let (dir, name) = (
        file.parent().unwrap().to_path_buf(),
        file.file_name().unwrap().to_str().unwrap().to_string(),
    );
    let mut list = fire_params();
    list[0] = Param::string("filename", &name);
    let there = Context {
        directory: Some(dir.clone()),
        ..Context::default()
    };
    let v = p.create_volume_with(&list, &there).unwrap();
    let absolute = p.create_volume(&fire_params()).unwrap();
    assert_eq!(v.info().bounds_min, absolute.info().bounds_min);
    let e = p.create_volume(&list).unwrap_err().to_string();
    assert!(e.contains(&name), "{e}");
    // An absolute name stays as it is.
    let v = p.create_volume_with(&fire_params(), &there).unwrap();
    assert_eq!(v.info().bounds_max, absolute.info().bounds_max);
}
