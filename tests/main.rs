//! The end-to-end tests, one crate with a module per concern. They drive what a user runs — the built
//! `firemedium` command, the built plugin cdylib through the loader and through C. A test target of the
//! `firemedium` package (so Cargo builds the command for them); the benchmarks' program has its own
//! (`tests/bench_cli.rs`, of `firemedium-bench`). Each crate's unit tests stay beside its code.

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
/// the documentation's commands), the farm, sparse and far-apart data, `gen`, `bake`, `tonemap` and `info`.
mod production {
    mod bake_cli;
    mod farm_cli;
    mod gen_cli;
    mod info_cli;
    mod noise_cli;
    mod render_cli;
    mod scene_cli;
    mod sparse_fire;
    mod tonemap_cli;
}

/// Bad input never crashes: mutated datasets, scenes, images and meshes.
mod robustness {
    mod mutated_inputs;
    mod round_four;
}

/// The code's shape: imports run one way between a crate's modules; no file past ~800 lines of code.
mod structure;

/// The C ABI: the loader over the built cdylib, and C programs compiled against the header.
mod abi {
    mod c_header;
    mod host_tracking;
    mod plugin_abi;
}
