//! The Mitsuba 0.6 XML loader on arbitrary text; what loads is also built.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let options = tempera_scene::LoadOptions::default();
    if let Ok(loaded) = tempera_scene::load_mitsuba_str(&text, Path::new("fuzz/scene.xml"), &options) {
        let _ = loaded.builder.build();
    }
});
