//! The PLY reader (ASCII and binary) on arbitrary bytes.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = tempera_scene::ply::parse(data);
});
