//! A hang guard for tests of inputs that once took minutes or hours.

use std::process::Command;

/// Runs `cmd`, killing it after `limit` seconds: a guard far above what the command takes (a second or less),
/// not a timing — the inputs these tests run took minutes to hours before their fixes.
pub fn finishes(cmd: &mut Command, limit: u64) -> std::process::Output {
    let mut child = cmd
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed().as_secs() > limit {
            child.kill().unwrap();
            panic!("{cmd:?} still running after {limit} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    child.wait_with_output().unwrap()
}
