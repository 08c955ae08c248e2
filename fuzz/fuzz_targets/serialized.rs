//! Mitsuba's `.serialized` mesh reader on arbitrary bytes, for the first and a later shape.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = tempera_scene::serialized::parse(data, 0);
    let _ = tempera_scene::serialized::parse(data, 3);
});
