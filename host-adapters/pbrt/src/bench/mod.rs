//! `firemedium bench …`: the measurements behind docs/RESULTS.md, as commands anyone can rerun.

pub mod perf;
pub mod stability;

use clap::{Args, Subcommand};

#[derive(Debug, Args)]
pub struct BenchArgs {
    #[command(subcommand)]
    what: What,
}

#[derive(Debug, Subcommand)]
enum What {
    /// Stiff and extreme cases, expected vs measured; exits 1 if any fails.
    Stability,
    /// Pegoraro & Parker's workload: 512², 1 spp, a 256³ fire, half-voxel steps; time, rays/s, samples/s,
    /// memory, error against a converged reference; with refraction.
    Perf(PerfArgs),
}

#[derive(Debug, Args)]
pub struct PerfArgs {
    /// Voxels along the fire's longest side (the campfire dataset, generated once into the temp directory).
    #[arg(long, default_value_t = 256, value_parser = clap::value_parser!(u32).range(8..=1024))]
    grid: u32,
    /// Image width and height, pixels.
    #[arg(long, default_value_t = 512, value_parser = clap::value_parser!(u32).range(8..=8192))]
    image: u32,
    /// A dataset file instead of the generated campfire.
    #[arg(long)]
    dataset: Option<std::path::PathBuf>,
    /// The reference's march step, voxels.
    #[arg(long, default_value_t = 0.0625)]
    reference_step: f64,
}

pub fn run(a: &BenchArgs) -> Result<String, (u8, String)> {
    match &a.what {
        What::Perf(p) => perf_report(p).map_err(|e| (1, e)),
        What::Stability => {
            let start = std::time::Instant::now();
            let cases = stability::cases();
            let (table, ok) = stability::table(&cases);
            let failed = cases.iter().filter(|c| !c.pass).count();
            let summary = format!(
                "{} cases, {} failed, {:.2} s\n",
                cases.len(),
                failed,
                start.elapsed().as_secs_f64()
            );
            if ok {
                Ok(table + &summary)
            } else {
                print!("{table}");
                Err((
                    1,
                    format!("stability: {failed} of {} cases failed", cases.len()),
                ))
            }
        }
    }
}

fn perf_report(a: &PerfArgs) -> Result<String, String> {
    use firemedium_plugin::params::Param;
    let file = match &a.dataset {
        Some(f) => f.clone(),
        None => perf::dataset(&std::env::temp_dir(), a.grid as usize)?,
    };
    let size = a.image as usize;
    let cores = std::thread::available_parallelism().map_or(1, |n| n.get());
    let mut out = format!(
        "dataset {} ({}), image {size}×{size}, 1 ray per pixel, {cores} threads\n\n",
        file.display(),
        std::fs::metadata(&file)
            .map(|m| format!("{:.1} MB", m.len() as f64 / 1e6))
            .unwrap_or_default()
    );
    let reference = perf::run(&file, &[Param::float("stepsize", a.reference_step)], size)?;
    let reference_rgb = perf::run(
        &file,
        &[
            Param::float("stepsize", a.reference_step),
            Param::string("colormode", "rgb"),
        ],
        size,
    )?;
    out += &format!(
        "references: march at {} voxel, spectral {:.2} s, rgb {:.2} s; rgb vs spectral reference: rel. RMSE {:.2e}\n\n",
        a.reference_step,
        reference.render_s,
        reference_rgb.render_s,
        perf::rel_rmse(&reference_rgb.image, &reference.image)
    );
    out += "| configuration | load s | render s | total s | rays/s | steps/s | steps/s/core | rel. RMSE |\n|---|---|---|---|---|---|---|---|\n";
    let configs: Vec<(&str, Vec<Param>)> = vec![
        (
            "march ½ voxel, spectral (30 bins)",
            vec![Param::float("stepsize", 0.5)],
        ),
        (
            "march ½ voxel, rgb",
            vec![
                Param::float("stepsize", 0.5),
                Param::string("colormode", "rgb"),
            ],
        ),
        (
            "march ½ voxel, spectral, refraction",
            vec![
                Param::float("stepsize", 0.5),
                Param::bool("refraction", true),
            ],
        ),
    ];
    for (name, params) in configs {
        let r = perf::run(&file, &params, size)?;
        let total = r.load_s + r.render_s;
        // Each colour mode against its own reference (the step's error); refraction bends rays, so its error
        // against the straight reference is mostly the refraction itself.
        let rgb = params.iter().any(|p| p.name == "colormode");
        let err = perf::rel_rmse(&r.image, if rgb { &reference_rgb.image } else { &reference.image });
        out += &format!(
            "| {name} | {:.3} | {:.3} | {:.3} | {:.0} | {:.3e} | {:.3e} | {:.2e} |\n",
            r.load_s,
            r.render_s,
            total,
            r.rays as f64 / r.render_s,
            r.samples / r.render_s,
            r.samples / r.render_s / cores as f64,
            err
        );
    }
    if let Some(m) = perf::peak_rss() {
        out += &format!("\npeak memory (VmHWM) {:.0} MB\n", m as f64 / 1e6);
    }
    Ok(out)
}
