//! `firemedium bench perf`: Pegoraro & Parker's workload — a 512×512 image, one ray per pixel, through a 256³
//! fire, a march step of half a voxel, soot + blackbody, emission–absorption only (their 40–80 s on a dual 3 GHz
//! Xeon in 2006) — timed from loading the grid to the last ray, with the error against a converged reference.

use firemedium_gen::{frame, Kind, Sim};
use firemedium_plugin::params::Param;
use firemedium_plugin::volume::{FireVolume, Ray};
use glam::DVec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// One timed configuration.
#[derive(Debug, Clone)]
pub struct Run {
    pub load_s: f64,
    pub render_s: f64,
    pub rays: usize,
    /// March steps along the clipped rays (early termination not subtracted): an upper bound of medium samples.
    pub samples: f64,
    /// Medium samples the volume actually evaluated (its per-thread counter, read around each row on the thread
    /// that rendered it): the steps minus those skipped in empty bricks or after early termination.
    pub evaluations: u64,
    /// Luminance image (Y, cd/m²).
    pub image: Vec<f64>,
}

/// The dataset: the campfire 30 s after its kindling (the default scene's moment: burning on its own) at `res`
/// voxels along its longest side, generated once into `dir` under a name keyed
/// by what makes it — this build's version and generator source (FNV-1a of the firemedium-gen crate's files) — so a file another build
/// or tool left there under the plain name is never taken for it. Written atomically: a killed run leaves none.
pub fn dataset(dir: &Path, res: usize) -> Result<PathBuf, String> {
    let key = [
        include_str!("../../../plugin/gen/src/lib.rs"),
        include_str!("../../../plugin/gen/src/kinds.rs"),
        include_str!("../../../plugin/gen/src/sim.rs"),
        include_str!("../../../plugin/gen/src/fuel.rs"),
        include_str!("../../../plugin/gen/src/radiation.rs"),
        include_str!("../../../plugin/gen/src/voxel.rs"),
        include_str!("../../../plugin/gen/src/write.rs"),
    ]
    .into_iter()
    .flat_map(str::bytes)
    .chain(env!("CARGO_PKG_VERSION").bytes())
    .fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    });
    let path = dir.join(format!("firemedium-bench-campfire-{res}-{key:016x}.vdb"));
    if !path.is_file() {
        let mut sim = Sim::new(Kind::Campfire, 1);
        sim.run_to(30.0);
        let f = frame(&sim, res, &[], false).map_err(|e| format!("{}: {e}", path.display()))?;
        firemedium::imageio::write_atomic(&path, |tmp| {
            std::fs::write(tmp, &f.bytes)
                .map_err(|e| firemedium::Error::file(path.display(), format!("cannot write: {e}")))
        })
        .map_err(|e| e.to_string())?;
    }
    Ok(path)
}

/// The benchmarks' camera: a pinhole 2.2 fire-sizes in front of the volume (−y), looking at its centre with a
/// 30° field of view, so the fire fills the frame; (eye, unit direction of pixel (i, j) of `size`²).
pub fn pinhole(v: &FireVolume, size: usize) -> (DVec3, impl Fn(usize, usize) -> DVec3 + Sync) {
    let [b0, b1] = v.bounds();
    let eye = 0.5 * (b0 + b1) - DVec3::Y * (2.2 * (b1 - b0).max_element());
    let half = 15f64.to_radians().tan();
    let dir = move |i: usize, j: usize| {
        let u = ((i as f64 + 0.5) / size as f64 * 2.0 - 1.0) * half;
        let w = (1.0 - (j as f64 + 0.5) / size as f64 * 2.0) * half;
        DVec3::new(u, 1.0, w).normalize()
    };
    (eye, dir)
}

/// Renders the workload with `params` added to the dataset's; `size` pixels square.
pub fn run(file: &Path, params: &[Param], size: usize) -> Result<Run, String> {
    let t0 = Instant::now();
    let mut list = vec![Param::string("filename", &file.to_string_lossy())];
    list.extend_from_slice(params);
    let v = FireVolume::new(&list).map_err(|e| e.to_string())?;
    let load_s = t0.elapsed().as_secs_f64();
    let [b0, b1] = v.bounds();
    let (eye, dir) = pinhole(&v, size);
    let xyz = v.channel_xyz();
    let step = v.step_length();
    let t1 = Instant::now();
    let rows: Vec<(Vec<f64>, u64)> = (0..size)
        .into_par_iter()
        .map(|j| {
            let c = v.channels();
            let (mut l, mut t) = (vec![0.0; c], vec![0.0; c]);
            let mut row = Vec::with_capacity(size);
            let e0 = firemedium_plugin::volume::evaluations_on_this_thread();
            for i in 0..size {
                let ray = Ray {
                    o: eye,
                    d: dir(i, j),
                    t0: 0.0,
                    t1: 1e30,
                    seed: (j * size + i) as u64,
                    first: None,
                };
                // (integrate_exit: the curved march when refraction is on, the straight one otherwise.)
                v.integrate_exit(&ray, &mut l, &mut t);
                row.push((0..c).map(|k| l[k] * xyz[k].y).sum::<f64>());
            }
            let evaluations = firemedium_plugin::volume::evaluations_on_this_thread() - e0;
            (row, evaluations)
        })
        .collect();
    let render_s = t1.elapsed().as_secs_f64();
    // The steps along the clipped rays, counted after the clock stops (a statistic, not part of the render).
    let samples = (0..size * size)
        .map(|p| {
            let d = dir(p % size, p / size);
            firemedium_plugin::majorant::clip_box(eye, d, 0.0, 1e30, b0, b1)
                .map_or(0.0, |(a, b)| ((b - a) / step).ceil())
        })
        .sum();
    let evaluations = rows.iter().map(|r| r.1).sum();
    Ok(Run {
        load_s,
        render_s,
        rays: size * size,
        samples,
        evaluations,
        image: rows.into_iter().flat_map(|r| r.0).collect(),
    })
}
