//! The end-to-end tests, one crate with a module per concern. They drive what a user runs — the built
//! `firemedium` command and `firemedium-bench`, the built plugin cdylib through the loader and through C — so they
//! are their own package (`firemedium-tests`), built beside the programs by `cargo test --workspace --release`.
//! Each crate's own unit tests stay beside its code.

mod common;

/// The physics core's quantities through the command, against published references.
mod physics {
    mod physics_cli;
}

/// pbrt-v4 fidelity: scenes written for pbrt-v4 at pbrt-v4's pixel values; its materials' furnaces and metals.
mod fidelity {
    mod materials;
    mod pbrt_fidelity;
}

/// What production use needs: renders end to end (closed forms, the default scene, frames, AOVs, faults,
/// the documentation's commands), the farm, sparse and far-apart data, `gen`, `tonemap`, `info` and the benchmarks.
mod production {
    mod bench_cli;
    mod farm_cli;
    mod gen_cli;
    mod info_cli;
    mod render_cli;
    mod sparse_fire;
    mod tonemap_cli;
}

/// Bad input never crashes: mutated datasets, scenes, images and meshes.
mod robustness {
    mod mutated_inputs;
}

/// The C ABI: the loader over the built cdylib, and C programs compiled against the header.
mod abi {
    mod c_header;
    mod plugin_abi;
}
