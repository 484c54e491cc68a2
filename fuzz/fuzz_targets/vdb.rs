//! Fuzz target: the vdb reader must return Ok or Err for any bytes, never panic or allocate past the cap.
#![no_main]

use firemedium_dataset::{Dataset, Format, LoadOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let opts = LoadOptions { max_bytes: 64 << 20, ..LoadOptions::default() };
    let _ = Dataset::from_bytes(Format::Vdb, "fuzz", data, &["density", "temperature"], &opts);
});
