//! Image input and output for Tempera: OpenEXR (32-bit float, via the `exr` crate), PFM
//! (Portable Float Map, written by hand), and 8-bit PNG/JPEG/TGA (via the `image` crate) with
//! sRGB transfer functions. Formats are chosen by file extension.

mod color;
pub mod flip;
pub mod metrics;
mod pfm;

pub use color::{ColorEncoding, linear_to_srgb, srgb_to_linear};

use std::path::{Path, PathBuf};
use tempera::math::Rgb;
use tempera::texture::Image;

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: unsupported image format (expected .exr, .pfm, .png, .jpg, .jpeg or .tga)")]
    UnsupportedFormat { path: PathBuf },
    #[error("{path}: {message}")]
    Malformed { path: PathBuf, message: String },
}

/// The file formats Tempera reads and writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    Exr,
    Pfm,
    Png,
    Jpeg,
    Tga,
}

impl Format {
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "exr" => Some(Format::Exr),
            "pfm" => Some(Format::Pfm),
            "png" => Some(Format::Png),
            "jpg" | "jpeg" => Some(Format::Jpeg),
            "tga" => Some(Format::Tga),
            _ => None,
        }
    }

    /// True for formats that store linear floating-point values.
    pub fn is_float(self) -> bool {
        matches!(self, Format::Exr | Format::Pfm)
    }
}

/// Options for writing low-dynamic-range files.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WriteOptions {
    /// Exposure in stops applied before sRGB encoding (PNG only).
    pub exposure: f32,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self { exposure: 0.0 }
    }
}

fn malformed(path: &Path, message: impl ToString) -> ImageError {
    ImageError::Malformed { path: path.to_owned(), message: message.to_string() }
}

/// A sibling of `path` to write into before renaming it into place: the same folder and
/// extension (which names the format), hidden, with this process's id.
fn partial_path(path: &Path) -> std::path::PathBuf {
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let ext = path.extension().map(|e| format!(".{}", e.to_string_lossy())).unwrap_or_default();
    path.with_file_name(format!(".{name}.partial-{}{ext}", std::process::id()))
}

/// The process id in a name `partial_path` made, if `name` is one.
fn partial_owner(name: &str) -> Option<u32> {
    let rest = name.strip_prefix('.')?;
    let (_, after) = rest.rsplit_once(".partial-")?;
    let digits: String = after.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// Whether process `pid` is running (where that cannot be known, only this process counts).
fn process_alive(pid: u32) -> bool {
    if pid == std::process::id() {
        return true;
    }
    cfg!(target_os = "linux") && Path::new("/proc").join(pid.to_string()).exists()
}

/// Removes, under `dir` (recursively), the temporary files that writes of processes no
/// longer running left behind (a `kill -9` between writing and renaming); returns how many.
/// Files of running processes are left alone.
pub fn remove_stale_partials(dir: &Path) -> usize {
    let mut removed = 0;
    for entry in std::fs::read_dir(dir).into_iter().flatten().flatten() {
        let path = entry.path();
        let Ok(kind) = entry.file_type() else { continue };
        if kind.is_dir() {
            removed += remove_stale_partials(&path);
        } else if let Some(pid) = partial_owner(&entry.file_name().to_string_lossy())
            && !process_alive(pid)
            && std::fs::remove_file(&path).is_ok()
        {
            removed += 1;
        }
    }
    removed
}

/// Writes `contents` to `path` through a temporary sibling renamed into place, so that a
/// process killed at any moment leaves either the old file or the new one, never a part.
pub fn write_file_atomically(path: &Path, contents: &[u8]) -> std::io::Result<()> {
    let partial = partial_path(path);
    std::fs::write(&partial, contents).and_then(|()| std::fs::rename(&partial, path)).inspect_err(|_| {
        let _ = std::fs::remove_file(&partial);
    })
}

/// Writes `image` in the format given by `path`'s extension. EXR and PFM are linear float;
/// PNG is sRGB-encoded 8-bit after applying the exposure. The file appears whole or not at
/// all (written to a temporary sibling, then renamed).
pub fn write_image(path: &Path, image: &Image, options: &WriteOptions) -> Result<(), ImageError> {
    Format::from_path(path).ok_or_else(|| ImageError::UnsupportedFormat { path: path.to_owned() })?;
    let partial = partial_path(path);
    let written = write_image_to(&partial, image, options).and_then(|()| {
        std::fs::rename(&partial, path).map_err(|e| malformed(path, format!("cannot rename into place: {e}")))
    });
    if written.is_err() {
        let _ = std::fs::remove_file(&partial);
    }
    written.map_err(|e| match e {
        ImageError::Malformed { message, .. } => malformed(path, message),
        ImageError::Io { source, .. } => ImageError::Io { path: path.to_owned(), source },
        other => other,
    })
}

fn write_image_to(path: &Path, image: &Image, options: &WriteOptions) -> Result<(), ImageError> {
    let format = Format::from_path(path).ok_or_else(|| ImageError::UnsupportedFormat { path: path.to_owned() })?;
    match format {
        Format::Exr => exr::prelude::write_rgb_file(path, image.width, image.height, |x, y| {
            let p = image.get(x, y);
            (p.x, p.y, p.z)
        })
        .map_err(|e| malformed(path, e)),
        Format::Pfm => pfm::write(path, image),
        Format::Png | Format::Jpeg | Format::Tga => {
            let scale = options.exposure.exp2();
            let bytes: Vec<u8> = image
                .pixels
                .iter()
                .flat_map(|p| (*p * scale).to_array())
                .map(|v| (linear_to_srgb(if v.is_finite() { v } else { 0.0 }) * 255.0 + 0.5).clamp(0.0, 255.0) as u8)
                .collect();
            let buffer = image::RgbImage::from_raw(image.width as u32, image.height as u32, bytes)
                .ok_or_else(|| malformed(path, "image size overflow"))?;
            buffer.save(path).map_err(|e| malformed(path, e))
        }
    }
}

/// Reads an image as linear RGB. `encoding` applies to 8-bit formats (float formats are linear).
pub fn read_image(path: &Path, encoding: ColorEncoding) -> Result<Image, ImageError> {
    let format = Format::from_path(path).ok_or_else(|| ImageError::UnsupportedFormat { path: path.to_owned() })?;
    if !path.exists() {
        return Err(ImageError::Io { path: path.to_owned(), source: std::io::ErrorKind::NotFound.into() });
    }
    match format {
        Format::Pfm => pfm::read(path),
        Format::Exr => read_exr(path),
        Format::Png | Format::Jpeg | Format::Tga => {
            let dynamic = image::open(path).map_err(|e| malformed(path, e))?;
            let rgb = dynamic.to_rgb32f();
            let (w, h) = (rgb.width() as usize, rgb.height() as usize);
            let pixels = rgb
                .pixels()
                .map(|p| Rgb::new(encoding.decode(p[0]), encoding.decode(p[1]), encoding.decode(p[2])))
                .collect();
            Ok(Image::new(w, h, pixels))
        }
    }
}

/// The most pixels an image file may declare (2^27, e.g. 16384×8192: 1.5 GiB as linear
/// RGB), checked before anything is allocated for them; compressed formats can declare far
/// more pixels than their size suggests.
pub const MAX_PIXELS: u64 = 1 << 27;

fn read_exr(path: &Path) -> Result<Image, ImageError> {
    let meta = exr::meta::MetaData::read_from_file(path, false).map_err(|e| malformed(path, e))?;
    for header in &meta.headers {
        let size = header.layer_size;
        let pixels = size.width() as u64 * size.height() as u64;
        if pixels > MAX_PIXELS {
            return Err(malformed(
                path,
                format!(
                    "declares {}x{} pixels, more than the {MAX_PIXELS} an image may have",
                    size.width(),
                    size.height()
                ),
            ));
        }
    }
    let image = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |resolution, _| Image::filled(resolution.width(), resolution.height(), Rgb::ZERO),
        |img: &mut Image, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
            let w = img.width;
            img.pixels[pos.y() * w + pos.x()] = Rgb::new(r, g, b);
        },
    )
    .map_err(|e| malformed(path, e))?;
    Ok(image.layer_data.channel_data.pixels)
}

/// An error naming both sizes unless `image` and `reference` have the same size.
pub fn check_sizes(image: &Image, reference: &Image) -> Result<(), String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "image is {}x{} but the reference is {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_image() -> Image {
        let pixels = (0..12).map(|i| Rgb::new(i as f32 * 0.25, 1.0 / (i as f32 + 1.0), 3.5)).collect();
        Image::new(4, 3, pixels)
    }

    #[test]
    fn float_formats_round_trip_exactly() {
        let dir = std::env::temp_dir().join(format!("tempera-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let img = sample_image();
        for name in ["a.exr", "a.pfm"] {
            let path = dir.join(name);
            write_image(&path, &img, &WriteOptions::default()).unwrap();
            let back = read_image(&path, ColorEncoding::Linear).unwrap();
            assert_eq!(back, img, "{name} round trip");
        }
    }

    #[test]
    fn png_is_srgb_encoded_and_decoded_to_linear() {
        let dir = std::env::temp_dir().join(format!("tempera-png-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("a.png");
        let img = Image::new(2, 1, vec![Rgb::splat(0.2158), Rgb::new(1.0, 0.0, 0.5)]);
        write_image(&path, &img, &WriteOptions::default()).unwrap();
        let raw = image::open(&path).unwrap().to_rgb8();
        assert_eq!(raw.get_pixel(0, 0)[0], 128, "linear 0.2158 encodes to sRGB 128");
        let back = read_image(&path, ColorEncoding::Srgb).unwrap();
        for (a, b) in back.pixels.iter().zip(&img.pixels) {
            assert!((*a - *b).abs().max_element() < 0.005, "{a} vs {b}");
        }
        // One stop of exposure doubles the linear value before encoding.
        write_image(&path, &Image::new(1, 1, vec![Rgb::splat(0.1079)]), &WriteOptions { exposure: 1.0 }).unwrap();
        assert_eq!(image::open(&path).unwrap().to_rgb8().get_pixel(0, 0)[0], 128);
    }

    #[test]
    fn eight_bit_textures_decode_to_linear() {
        let dir = std::env::temp_dir().join(format!("tempera-ldr-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let raw =
            image::RgbImage::from_fn(
                8,
                8,
                |x, _| {
                    if x < 4 { image::Rgb([128, 128, 128]) } else { image::Rgb([255, 0, 64]) }
                },
            );
        for name in ["t.tga", "t.jpg", "t.png"] {
            let path = dir.join(name);
            raw.save(&path).unwrap();
            let srgb = read_image(&path, ColorEncoding::Srgb).unwrap();
            let linear = read_image(&path, ColorEncoding::Linear).unwrap();
            // JPEG is lossy: compare the flat left half's centre with a tolerance.
            let tol = if name.ends_with("jpg") { 0.02 } else { 1e-4 };
            assert!(
                (srgb.get(1, 4).x - 0.2158).abs() < tol,
                "{name}: sRGB 128 decodes to 0.2158, got {}",
                srgb.get(1, 4).x
            );
            assert!((linear.get(1, 4).x - 128.0 / 255.0).abs() < tol, "{name}: linear keeps the code value");
            assert!((srgb.get(6, 4).x - 1.0).abs() < tol * 5.0, "{name}");
        }
        let gamma = ColorEncoding::Gamma(2.2).decode(0.5);
        assert!((gamma - 0.5f32.powf(2.2)).abs() < 1e-6);
    }

    /// Files appear whole: written beside the target and renamed over it, leaving no partial
    /// file behind, also when the write fails (an unwritable folder names the target).
    #[test]
    fn writes_replace_files_whole_and_leave_nothing_behind() {
        let dir = std::env::temp_dir().join(format!("tempera-atomic-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let text = dir.join("results.csv");
        write_file_atomically(&text, b"old").unwrap();
        write_file_atomically(&text, b"new contents").unwrap();
        assert_eq!(std::fs::read(&text).unwrap(), b"new contents");
        for name in ["a.exr", "a.pfm", "a.png"] {
            write_image(&dir.join(name), &sample_image(), &WriteOptions::default()).unwrap();
            write_image(&dir.join(name), &sample_image(), &WriteOptions::default()).unwrap();
        }
        let names: Vec<String> =
            std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
        assert!(names.iter().all(|n| !n.contains("partial")), "{names:?}");
        assert_eq!(names.len(), 4, "{names:?}");
        let missing = dir.join("no-such-folder").join("b.exr");
        let e = write_image(&missing, &sample_image(), &WriteOptions::default()).unwrap_err().to_string();
        assert!(e.contains("no-such-folder/b.exr") && !e.contains("partial"), "{e}");
    }

    /// Temporary files of dead processes go; those of running ones and ordinary files stay.
    #[test]
    fn stale_partial_files_are_removed() {
        let dir = std::env::temp_dir().join(format!("tempera-stale-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let own = format!(".a.exr.partial-{}.exr", std::process::id());
        let names =
            [".b.json.partial-4294967294.json", "sub/.c.png.partial-4294967293.png", &own, "d.exr", "e.partial-1"];
        for name in names {
            std::fs::write(dir.join(name), b"x").unwrap();
        }
        assert_eq!(partial_owner(".x.partial-12.exr"), Some(12));
        assert_eq!(partial_owner("x.partial-12.exr"), None, "only hidden files");
        assert_eq!(remove_stale_partials(&dir), 2);
        assert!(!dir.join(names[0]).exists() && !dir.join(names[1]).exists());
        assert!(names[2..].iter().all(|n| dir.join(n).exists()));
        let _ = std::fs::remove_dir_all(&dir);
    }

    /// Inputs found by fuzzing (`fuzz/`): each is an error naming the file, not an abort.
    #[test]
    fn fuzzed_images_are_errors() {
        // An EXR whose data window declares billions of pixels in 34 KB: the image was
        // allocated from the header before any pixel was read.
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fuzz-huge-data-window.exr");
        let e = read_image(&path, ColorEncoding::Linear).unwrap_err().to_string();
        assert!(e.contains("fuzz-huge-data-window.exr"), "{e}");
    }

    #[test]
    fn malformed_pfm_is_an_error_naming_the_file() {
        let dir = std::env::temp_dir().join(format!("tempera-badpfm-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for (name, bytes) in
            [("a.pfm", &b"P6\n1 1\n-1\n"[..]), ("b.pfm", b"PF\n2 2\n-1.0\n\0\0"), ("c.pfm", b"PF\n-2 x\n")]
        {
            let path = dir.join(name);
            std::fs::write(&path, bytes).unwrap();
            let err = read_image(&path, ColorEncoding::Linear).unwrap_err().to_string();
            assert!(err.contains(name), "{err}");
        }
    }

    #[test]
    fn errors_name_the_file() {
        let err = read_image(Path::new("/nonexistent/x.exr"), ColorEncoding::Linear).unwrap_err();
        assert!(err.to_string().contains("/nonexistent/x.exr"));
        let err = write_image(Path::new("out.bmp"), &sample_image(), &WriteOptions::default()).unwrap_err();
        assert!(err.to_string().contains("unsupported"));
    }
}
