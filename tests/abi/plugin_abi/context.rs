//! The host's context through the built library: what a renderer knows and the scene does not say — threads,
//! memory, frame, shutter, its thread pool, its scene's folder, what its medium type means and its spectral bins —
//! beside the scene's parameters, never among them.

use super::*;
use firemedium_loader::{Bins, Context, Kind};

#[test]
fn the_hosts_context_goes_beside_the_scenes_parameters() {
    // Threads, the memory budget, the frame and the shutter in the creation info, typed through the plugin to
    // the reads that use them (never turned into made-up parameters); a parameter the scene sets itself wins.
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
    // A context out of range is refused naming its field and the range, as a parameter would be.
    for (bad, says) in [
        (
            Context {
                threads: Some(5000),
                ..Default::default()
            },
            "threads 5000: expected 0 (every core) to 4096",
        ),
        (
            Context {
                frame: Some(i64::MIN),
                ..Default::default()
            },
            "frame -9223372036854775808",
        ),
        (
            Context {
                shutter: Some([0.5, f64::NAN]),
                ..Default::default()
            },
            "shutter [0.5, NaN]",
        ),
    ] {
        let e = p.create_volume_with(&fire_params(), &bad).unwrap_err();
        assert!(e.to_string().contains(says), "{e}");
    }
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

#[test]
fn the_host_says_what_its_medium_type_means_and_its_bins_beside_the_parameters() {
    // pbrt-v4's grid semantics and the render's bins as the context (ABI 1.4), not as parameters the host makes
    // up: the same volume, bit for bit, as the one given `mode`, `bins`, `lambdamin` and `lambdamax`.
    let p = plugin();
    let grid = [
        Param::string("filename", &fire_file()),
        Param::float("temperaturescale", 1000.0),
    ];
    let context = Context {
        kind: Some(Kind::Pbrt),
        bins: Some(Bins {
            count: 12,
            nm: [420.0, 700.0],
        }),
        ..Default::default()
    };
    let told = p.create_volume_with(&grid, &context).unwrap();
    let named = p
        .create_volume(
            &[
                grid.to_vec(),
                vec![
                    Param::string("mode", "pbrt"),
                    Param::int("bins", 12),
                    Param::float("lambdamin", 420.0),
                    Param::float("lambdamax", 700.0),
                ],
            ]
            .concat(),
        )
        .unwrap();
    let physical = p.create_volume(&grid).unwrap();
    let (a, b) = (told.info(), named.info());
    assert_eq!((a.channels, a.lambda_min, a.lambda_max), (12, 420.0, 700.0));
    assert_eq!((b.channels, b.lambda_min, b.lambda_max), (12, 420.0, 700.0));
    let integrate = |v: &firemedium_loader::Volume| {
        let rays = rays(16);
        let mut out = vec![0f32; rays.len() * v.info().channels as usize];
        v.integrate(&rays, &mut out, None, None).unwrap();
        out
    };
    let (l_told, l_named) = (integrate(&told), integrate(&named));
    assert!(l_told.iter().any(|&x| x > 0.0));
    assert_eq!(l_told, l_named);
    // Not the paper's fire, in its own default bins.
    assert_ne!(physical.info().channels, 12);
    // The scene's own parameters win over the context: its `mode` and its `bins`.
    let own = p
        .create_volume_with(
            &[
                grid.to_vec(),
                vec![Param::string("mode", "physical"), Param::int("bins", 8)],
            ]
            .concat(),
            &context,
        )
        .unwrap();
    assert_eq!((own.info().channels, own.info().lambda_min), (8, 420.0));
    // A context out of range is refused, naming it.
    for (bins, what) in [
        (
            Bins {
                count: 5000,
                nm: [420.0, 700.0],
            },
            "bins 5000",
        ),
        (
            Bins {
                count: 12,
                nm: [700.0, 420.0],
            },
            "wavelengths [700.0, 420.0]",
        ),
        (
            Bins {
                count: 12,
                nm: [100.0, 420.0],
            },
            "wavelengths [100.0, 420.0]",
        ),
    ] {
        let bad = Context {
            bins: Some(bins),
            ..Default::default()
        };
        let e = p.create_volume_with(&grid, &bad).unwrap_err().to_string();
        assert!(e.contains(what), "{e}");
    }
}
