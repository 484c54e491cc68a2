//! Fuzz target: the host's PNG decoder must return an image or an error for any bytes, never panic or allocate
//! past the budget its header is checked against.
#![no_main]

use firemedium::imageio::{decode, ImageKind};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = decode("fuzz.png", data, ImageKind::Png, true, 64 << 20);
});
