//! Fuzz target: the pbrt-v4 tokenizer and parser must return Ok or Err for any text, never panic.
#![no_main]

use firemedium_pbrt_parser::{parse_str, Collect};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_str("fuzz.pbrt", text, std::path::Path::new("/nonexistent"), &mut Collect::default());
    }
});
