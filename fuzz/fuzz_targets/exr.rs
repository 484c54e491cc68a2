//! Fuzz target: the host's EXR decoder (environment maps, image textures, `compare`/`tonemap` inputs) must return
//! an image or an error for any bytes, never panic or allocate past the budget its header is checked against.
#![no_main]

use firemedium::imageio::{decode, ImageKind};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = decode("fuzz.exr", data, ImageKind::Exr, false, 64 << 20);
});
