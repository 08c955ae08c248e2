//! The texture and reference readers (PFM, EXR, PNG, TGA, JPEG) on arbitrary bytes: the first
//! byte picks the format, the rest is the file.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else { return };
    let ext = ["pfm", "exr", "png", "tga", "jpg"][pick as usize % 5];
    let path = std::env::temp_dir().join(format!("tempera-fuzz-{}.{ext}", std::process::id()));
    if std::fs::write(&path, body).is_ok() {
        let _ = tempera_image::read_image(&path, tempera_image::ColorEncoding::Srgb);
    }
});
