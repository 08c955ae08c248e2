//! The pbrt-v4 tokenizer, parser and loader on arbitrary text; what loads is also built
//! (BVH, lights, camera), so counts and sizes read from the text reach the allocations.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let options = tempera_scene::LoadOptions::default();
    if let Ok(loaded) = tempera_scene::load_pbrt_str(&text, Path::new("fuzz/scene.pbrt"), &options) {
        let _ = loaded.builder.build();
    }
});
