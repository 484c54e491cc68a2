//! `firemedium`: the command line over the host library (`firemedium::`), one module per command:
//! `render` (a pbrt-v4 scene through the plugin to EXR + PNG), `tonemap` (visual adaptation of an EXR),
//! `compare` (error against a reference over surface pixels), `gen` (blob-model fire datasets), `info` (a
//! dataset file), `physics` (the physics core's quantities) and `bench` (stability, error-vs-time, perf,
//! components). A command depends only on the library and on `args` (shared value parsers), never on another
//! command.
//!
//! Exit status: 0 on success, 1 when a file or scene is refused, 2 on bad arguments, 128 + the signal when
//! interrupted (130 Ctrl-C, 143 SIGTERM, 129 SIGHUP); one line on stderr, never a panic.

#![forbid(unsafe_code)]
use firemedium::args;
mod bake;
mod bench;
mod compare;
mod diff;
mod farm;
mod gen;
mod info;
mod merge;
mod physics;
mod render;
mod scene;
mod tonemap;

use clap::{Parser, Subcommand};
use std::io::Write;
use std::process::ExitCode;

#[derive(Debug, Parser)]
#[command(
    name = "firemedium",
    version,
    about = "A physically based fire medium (Pegoraro & Parker 2006) for path tracers"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
#[allow(clippy::large_enum_variant)] // parsed once per process
enum Command {
    /// Print blackbody radiance, soot absorption, the index of air and the blackbody's colour.
    Physics(physics::PhysicsArgs),
    /// Describe a voxel dataset file: dims, bounds, channels with statistics, bytes, load time.
    Info(info::InfoArgs),
    /// Render a pbrt-v4 scene (fire media through the plugin) to EXR and a PNG preview.
    Render(render::RenderArgs),
    /// A starter pbrt-v4 scene around a fire dataset: its box fitted to the data, a camera framing it, a ground.
    Scene(scene::SceneArgs),
    /// Error of renders against a reference over the pixels that see a surface (luminance MSE).
    Compare(compare::CompareArgs),
    /// Assemble the tiles of one render (`render --cropwindow`/`--pixelbounds`) into the full frame.
    Merge(merge::MergeArgs),
    /// Whether two EXRs hold the same render: every channel bit for bit, and the same render record.
    Diff(diff::DiffArgs),
    /// Render on a cluster: job scripts (and their submission) for frames × tiles, then their merge.
    Farm(farm::FarmArgs),
    /// What an observer sees of an absolute EXR: visual adaptation (von Kries + Naka–Rushton) to a PNG.
    Tonemap(tonemap::TonemapArgs),
    /// A fire dataset (OpenVDB) from Stam & Fiume's blob fire model: campfire, candle, pool, torch.
    Gen(gen::GenArgs),
    /// The fire's coefficients as RGB grids (OpenVDB) for a renderer without the plugin (Cycles' Volume
    /// Coefficients node): sigma_a, sigma_s and emission per metre, linear Rec.709.
    Bake(bake::BakeArgs),
    /// Benchmarks: stability (stiff and extreme cases), error-vs-time, perf (the paper's workload), components,
    /// fire-light — the program firemedium-bench beside this one (`firemedium bench --help` lists them).
    #[command(disable_help_flag = true)]
    Bench {
        /// The benchmark and its arguments, passed to firemedium-bench.
        #[arg(trailing_var_arg = true, allow_hyphen_values = true)]
        args: Vec<std::ffi::OsString>,
    },
}

fn main() -> ExitCode {
    firemedium::heap::hold_thresholds();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => {
            use clap::error::ErrorKind;
            if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) {
                print!("{e}");
                return ExitCode::SUCCESS;
            }
            if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
                eprintln!(
                    "firemedium: a subcommand is required (render, scene, merge, diff, farm, tonemap, compare, gen, bake, info, physics, bench); see 'firemedium --help'"
                );
                return ExitCode::from(2);
            }
            eprintln!(
                "firemedium: {}",
                firemedium::term::one_line(&e.render().to_string())
            );
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Physics(args) => physics::run(&args),
        Command::Info(args) => info::run(&args),
        Command::Render(args) => render::run(&args),
        Command::Scene(args) => scene::run(&args),
        Command::Compare(args) => compare::run(&args),
        Command::Merge(args) => merge::run(&args),
        Command::Diff(args) => diff::run(&args),
        Command::Farm(args) => farm::run(&args),
        Command::Tonemap(args) => tonemap::run(&args),
        Command::Gen(args) => gen::run(&args),
        Command::Bake(args) => bake::run(&args),
        Command::Bench { args } => {
            return bench::forward(&args).unwrap_or_else(|(status, msg)| {
                eprintln!(
                    "firemedium: {}",
                    firemedium::term::printable(&msg, firemedium::term::MAX_MESSAGE_CHARS)
                );
                ExitCode::from(status)
            })
        }
    };
    match result {
        Ok(text) => {
            let mut out = std::io::stdout().lock();
            // A closed pipe (`| head`) is not an error worth a panic.
            let _ = out.write_all(firemedium::term::printable(&text, usize::MAX).as_bytes());
            ExitCode::SUCCESS
        }
        Err(e) => {
            // One line, whatever the message holds.
            // (Input quoted in it made printable: no escape sequence from a file reaches the terminal.)
            let msg =
                firemedium::term::printable(&e.to_string(), firemedium::term::MAX_MESSAGE_CHARS);
            eprintln!("firemedium: {}", msg.replace('\n', " "));
            ExitCode::from(e.exit_status())
        }
    }
}
