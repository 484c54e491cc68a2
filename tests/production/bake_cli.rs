//! `firemedium bake`: the fire's coefficients as RGB grids on the dataset's lattice, which a renderer without the
//! plugin integrates to the fire's own luminance.

use crate::common::{exe, root, scratch::Scratch};
use firemedium_dataset::{ChannelSource, Dataset, LoadOptions};
use firemedium_loader::{Param, Plugin};
use glam::DVec3;
use std::process::Command;

fn plugin() -> Plugin {
    // SAFETY: the plugin this test run built.
    unsafe { Plugin::load(crate::common::plugin_file()) }.unwrap()
}

#[test]
fn baked_grids_integrate_to_the_fires_luminance() {
    let dir = Scratch::new("bake", "campfire");
    let campfire = root().join("scenes/campfire/campfire.vdb");
    let out = dir.join("baked.vdb");
    let o = Command::new(exe("firemedium"))
        .args(["bake"])
        .arg(&campfire)
        .arg("-o")
        .arg(&out)
        .args(["--param", "fuel=propane"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(
        text.contains("70×72×94 voxels") && text.contains("lost in baking"),
        "{text}"
    );
    // The grids, on the dataset's lattice and transform.
    let names = [
        "sigma_a.x",
        "sigma_a.y",
        "sigma_a.z",
        "emission.x",
        "emission.y",
        "emission.z",
    ];
    let sources: Vec<ChannelSource> = names.iter().map(|n| ChannelSource::new(n, &out)).collect();
    let baked = Dataset::load(&sources, &LoadOptions::default()).unwrap();
    let fire = Dataset::load(
        &[ChannelSource::new("density", &campfire)],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(baked.dims(), fire.dims());
    for k in 0..2 {
        assert!((baked.bounds()[k] - fire.bounds()[k]).abs().max_element() < 1e-9);
    }
    // Along rays through the flame, a colour renderer's integral over the baked grids (1 mm steps: T per RGB
    // component from sigma_a, emission summed) against the plugin's own march, both as luminance in cd/m².
    let volume = plugin()
        .create_volume(&[
            Param::string("filename", &campfire.to_string_lossy()),
            Param::string("fuel", "propane"),
        ])
        .unwrap();
    let y: Vec<f64> = volume.channel_xyz().unwrap().iter().map(|c| c[1]).collect();
    let c = volume.info().channels as usize;
    for (origin, z) in [
        ([0.0, -3.0, 0.3], 0.3),
        ([0.1, -3.0, 0.5], 0.5),
        ([-0.05, -3.0, 0.8], 0.8),
    ] {
        let ray = firemedium_loader::Ray {
            origin,
            direction: [0.0, 1.0, 0.0],
            tmin: 0.0,
            tmax: 1e30,
            seed: 1,
        };
        let mut rad = vec![0f32; c];
        volume.integrate(&[ray], &mut rad, None, None).unwrap();
        let want: f64 = rad.iter().zip(&y).map(|(l, w)| *l as f64 * w).sum();
        let (mut l, mut tau) = ([0.0f64; 3], [0.0f64; 3]);
        let ds = 0.001;
        for i in 0..6000 {
            let p = DVec3::new(origin[0], origin[1] + (i as f64 + 0.5) * ds, z);
            for k in 0..3 {
                let sa = baked.sample(k, p) as f64;
                l[k] += (-tau[k] - 0.5 * sa * ds).exp() * baked.sample(3 + k, p) as f64 * ds;
                tau[k] += sa * ds;
            }
        }
        let got = 0.2126 * l[0] + 0.7152 * l[1] + 0.0722 * l[2];
        println!("bake: ray at z = {z}: {got:.2} cd/m² from the grids, {want:.2} from the plugin's march");
        assert!((got / want - 1.0).abs() < 0.05, "{got} against {want}");
    }
}

#[test]
fn what_grids_cannot_carry_is_refused_by_name() {
    let dir = Scratch::new("bake", "refused");
    let o = Command::new(exe("firemedium"))
        .arg("bake")
        .arg(root().join("scenes/campfire/campfire.vdb"))
        .arg("-o")
        .arg(dir.join("x.vdb"))
        .args(["--param", "refraction=true"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("refraction") && e.contains("firemedium render"),
        "{e}"
    );
    assert!(!dir.join("x.vdb").exists());
    // A parameter the fire does not have: named, with the ones it has.
    let o = Command::new(exe("firemedium"))
        .arg("bake")
        .arg(root().join("scenes/campfire/campfire.vdb"))
        .arg("-o")
        .arg(dir.join("x.vdb"))
        .args(["--param", "fule=propane"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("has no parameter \"fule\""));
}

#[test]
fn a_sequence_bakes_frame_by_frame() {
    let dir = Scratch::new("bake", "frames");
    let run = |args: &[&str]| {
        let o = Command::new(exe("firemedium"))
            .current_dir(&*dir)
            .args(args)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    run(&[
        "gen",
        "torch",
        "--resolution",
        "24",
        "--frames",
        "30-31",
        "-o",
        "torch_####.vdb",
    ]);
    let text = run(&[
        "bake",
        "torch_####.vdb",
        "--frames",
        "30-31",
        "-o",
        "baked_####.vdb",
    ]);
    assert_eq!(text.matches("wrote baked_00").count(), 2, "{text}");
    let (a, b) = (
        std::fs::read(dir.join("baked_0030.vdb")).unwrap(),
        std::fs::read(dir.join("baked_0031.vdb")).unwrap(),
    );
    assert!(a.len() > 1000 && a != b, "two frames, two fires");
    // An output name without #### cannot hold a sequence.
    let o = Command::new(exe("firemedium"))
        .current_dir(&*dir)
        .args([
            "bake",
            "torch_####.vdb",
            "--frames",
            "30-31",
            "-o",
            "one.vdb",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("####"));
}

#[test]
fn a_datasets_velocity_is_passed_through_for_motion_blur() {
    // Mantaflow's cache holds a half-float vector grid `velocity`: baked as the vector grid `velocity` on the
    // coefficients' lattice, each voxel's value the dataset's there (as it is, its units); `--velocity none`
    // leaves it out; a name the file does not hold is refused, listing the grids it has.
    let dir = Scratch::new("bake", "velocity");
    let cache = root().join("tests/data/valid/vdb/mantaflow_fire_f060.vdb");
    let bake = |out: &str, extra: &[&str]| {
        Command::new(exe("firemedium"))
            .arg("bake")
            .arg(&cache)
            .arg("-o")
            .arg(dir.join(out))
            .args(["--param", "source=blender"])
            .args(extra)
            .output()
            .unwrap()
    };
    let o = bake("with.vdb", &[]);
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(text.contains("velocity: the dataset's velocity"), "{text}");
    let opts = LoadOptions::default();
    let load = |file: &std::path::Path, names: &[&str]| {
        let sources: Vec<ChannelSource> =
            names.iter().map(|n| ChannelSource::new(n, file)).collect();
        Dataset::load(&sources, &opts).unwrap()
    };
    let axes = ["velocity.x", "velocity.y", "velocity.z"];
    let baked = load(&dir.join("with.vdb"), &axes);
    let source = load(&cache, &axes);
    let density = load(&cache, &["density"]);
    assert_eq!(baked.dims(), density.dims());
    // Every voxel centre of the lattice: the baked value is the source's there.
    let (dims, [l0, _], step) = (density.dims(), density.bounds(), density.voxel_size());
    let (mut moving, mut worst) = (0usize, 0f32);
    for z in 0..dims[2] {
        for y in 0..dims[1] {
            for x in 0..dims[0] {
                let p = l0 + DVec3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * step;
                for k in 0..3 {
                    let (b, s) = (baked.sample(k, p), source.sample(k, p));
                    worst = worst.max((b - s).abs());
                    moving += usize::from(s != 0.0 && k == 2);
                }
            }
        }
    }
    assert!(moving > 1000, "only {moving} voxels move upward");
    assert!(worst <= 1e-6, "largest difference {worst}");

    let o = bake("without.vdb", &["--velocity", "none"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let names: Vec<String> = firemedium_dataset::list_grids(&dir.join("without.vdb"), &opts)
        .unwrap()
        .into_iter()
        .map(|g| g.name)
        .collect();
    assert_eq!(names, ["sigma_a", "sigma_s", "emission"]);

    let o = bake("bad.vdb", &["--velocity", "wind"]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("--velocity wind") && err.contains("density, shadow"),
        "{err}"
    );
    assert!(!dir.join("bad.vdb").exists());
}

#[test]
fn a_small_file_standing_for_many_voxels_is_refused_within_the_budget() {
    // One active tile of 128³ voxels of constant soot and temperature: a fire of one shared block of values,
    // whose bake would write 4 096 leaves per grid (75 MB). Within 0.05 GB the bake refuses it by name — the
    // bricks, the bytes, the budget — before allocating them, and writes nothing.
    let dir = Scratch::new("bake", "tiles");
    let bytes = firemedium_dataset::vdb::write_tiled(
        &[
            ("density", vec![], vec![([0, 0, 0], 128, 1e-6)]),
            ("temperature", vec![], vec![([0, 0, 0], 128, 1600.0)]),
        ],
        DVec3::ZERO,
        DVec3::splat(0.01),
    );
    let input = dir.join("tile.vdb");
    std::fs::write(&input, &bytes).unwrap();
    let out = dir.join("baked.vdb");
    let o = Command::new(exe("firemedium"))
        .arg("bake")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--max-memory", "0.05", "--param", "fuel=propane"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success(),
        "{}",
        String::from_utf8_lossy(&o.stdout)
    );
    assert!(
        err.contains("tile.vdb")
            && err.contains("4096 bricks")
            && err.contains("75497472 bytes")
            && err.contains("50000000")
            && err.contains("--max-memory"),
        "{err}"
    );
    assert!(!out.exists());
}

#[test]
fn a_sparse_dataset_bakes_sparse() {
    // Two 8³ blobs of hot soot 8 000 voxels apart on each axis: a box of 5·10¹¹ voxels, two bricks of data. The bake
    // visits the two bricks only (within a 0.1 GB budget) and writes two leaves per grid, far apart as they were.
    let dir = Scratch::new("bake", "sparse");
    let leaf = |origin: [i32; 3], v: f32| (origin, [u64::MAX; 8], vec![v; 512]);
    let far = [8000, 8000, 8000];
    let bytes = firemedium_dataset::vdb::write_sparse(
        &[
            ("density", vec![leaf([0, 0, 0], 1.0), leaf(far, 1.0)]),
            (
                "temperature",
                vec![leaf([0, 0, 0], 1600.0), leaf(far, 1600.0)],
            ),
        ],
        DVec3::ZERO,
        DVec3::splat(0.01),
    );
    let input = dir.join("two.vdb");
    std::fs::write(&input, bytes).unwrap();
    let out = dir.join("baked.vdb");
    let o = Command::new(exe("firemedium"))
        .arg("bake")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .args(["--max-memory", "0.1"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let baked = Dataset::load(
        &[ChannelSource::new("emission.x", &out)],
        &LoadOptions::default(),
    )
    .unwrap();
    assert_eq!(baked.topology().active_bricks(), 2);
    assert_eq!(baked.dims(), [8008, 8008, 8008]);
    // Each blob glows, at the same level: the same soot at the same temperature.
    let at = |v: [f64; 3]| baked.sample(0, DVec3::from_array(v));
    let (near, far) = (at([0.04, 0.04, 0.04]), at([80.04, 80.04, 80.04]));
    assert!(
        near > 0.0 && (far / near - 1.0).abs() < 1e-6,
        "{near} {far}"
    );
    let size = std::fs::metadata(&out).unwrap().len();
    // (Each far leaf costs its own path of internal nodes, whose tables OpenVDB stores whole: 1.8 MB, not the
    // box's terabytes.)
    assert!(size < 4_000_000, "{size} bytes");
}
