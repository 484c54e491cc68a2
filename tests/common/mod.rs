//! What the end-to-end tests share: where the repository and the built programs are, scratch folders, EXR
//! reading, renders through the built command, the byte mutator, a hang guard.
#![allow(dead_code)]

pub mod guard;
pub mod image;
pub mod mutate;
pub mod render;
pub mod scratch;

use std::path::PathBuf;

/// The repository's root (the packages whose tests these are lie two folders down).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The build's output folder (`target/<profile>`): this test executable lives in its `deps/`.
fn build_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test executable's path");
    exe.parent()
        .and_then(|deps| deps.parent())
        .expect("the test executable lives in target/<profile>/deps")
        .to_path_buf()
}

/// A program the workspace builds (`firemedium`, `firemedium-bench`), in this build's output folder: Cargo builds
/// a package's programs for its own test targets, so `cargo test --workspace --release` (what the README and CI
/// run) builds both, and a test of one package can run the other's.
pub fn exe(name: &str) -> PathBuf {
    let p = build_dir().join(format!("{name}{}", std::env::consts::EXE_SUFFIX));
    assert!(
        p.is_file(),
        "{} is not built: run the tests with `cargo test --workspace --release`, or build it first",
        p.display()
    );
    p
}

/// The plugin cdylib this build made (in `deps/`, beside the test executable, after `cargo test`; also in the
/// output folder after `cargo build`).
pub fn plugin_file() -> PathBuf {
    let name = firemedium_loader::library_file_name();
    let dir = build_dir();
    let p = dir.join("deps").join(&name);
    if p.is_file() {
        return p;
    }
    let p = dir.join(&name);
    assert!(p.is_file(), "{} is not built", p.display());
    p
}
