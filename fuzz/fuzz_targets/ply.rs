//! Fuzz target: the PLY reader (`plymesh`) must return a mesh or an error for any bytes, never panic.
#![no_main]

use firemedium::render::ply;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = ply::parse("fuzz.ply", data);
});
