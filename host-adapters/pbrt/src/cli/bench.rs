//! `firemedium bench …`: the benchmarks are their own program, `firemedium-bench` (tools/bench), because they
//! time the plugin's parts in process and so link it as a library, which the renderer never does (it reaches the
//! fire through the loader and the C ABI only). This command runs that program, found beside this one.

use std::ffi::OsString;
use std::path::PathBuf;
use std::process::{Command, ExitCode};

/// The benchmark program's path: beside this executable.
fn program() -> Result<PathBuf, String> {
    firemedium::program_beside("firemedium-bench").map_err(|p| {
        format!(
            "bench: the benchmarks are the program {}, which is not there (build it with `cargo build --release -p firemedium-bench`, or install with tools/install.sh)",
            p.display()
        )
    })
}

/// Runs `firemedium-bench ARGS`, its output going straight to ours; its exit status is ours.
pub fn forward(args: &[OsString]) -> Result<ExitCode, (u8, String)> {
    let bench = program().map_err(|m| (2, m))?;
    let status = Command::new(&bench)
        .args(args)
        .status()
        .map_err(|e| (2, format!("bench: {}: {e}", bench.display())))?;
    Ok(match status.code() {
        Some(0) => ExitCode::SUCCESS,
        Some(c) => ExitCode::from(u8::try_from(c).unwrap_or(1)),
        // Killed by a signal: the shell's 128 + signal.
        None => ExitCode::from(signal_status(&status)),
    })
}

#[cfg(unix)]
fn signal_status(status: &std::process::ExitStatus) -> u8 {
    use std::os::unix::process::ExitStatusExt;
    status.signal().map_or(1, |s| 128u8.saturating_add(s as u8))
}

#[cfg(not(unix))]
fn signal_status(_: &std::process::ExitStatus) -> u8 {
    1
}
