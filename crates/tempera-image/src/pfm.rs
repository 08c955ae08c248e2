//! Portable Float Map (PFM) reading and writing: a text header `PF` (RGB) or `Pf` (grey),
//! `width height`, and a scale whose sign gives the byte order (negative = little-endian),
//! followed by 32-bit floats with the bottom row first.

use super::{ImageError, malformed};
use std::io::Write;
use std::path::Path;
use tempera::math::Rgb;
use tempera::texture::Image;

pub fn write(path: &Path, image: &Image) -> Result<(), ImageError> {
    let io = |e| ImageError::Io { path: path.to_owned(), source: e };
    let mut out = Vec::with_capacity(image.pixels.len() * 12 + 32);
    write!(out, "PF\n{} {}\n-1.0\n", image.width, image.height).map_err(io)?;
    for y in (0..image.height).rev() {
        for x in 0..image.width {
            for c in image.get(x, y).to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    std::fs::write(path, out).map_err(io)
}

/// Splits the next whitespace-delimited header token off `data`.
fn token<'a>(data: &mut &'a [u8]) -> Option<&'a str> {
    let start = data.iter().position(|b| !b.is_ascii_whitespace())?;
    let rest = &data[start..];
    let len = rest.iter().position(|b| b.is_ascii_whitespace()).unwrap_or(rest.len());
    let tok = std::str::from_utf8(&rest[..len]).ok()?;
    *data = &rest[len..];
    Some(tok)
}

pub fn read(path: &Path) -> Result<Image, ImageError> {
    let bytes = std::fs::read(path).map_err(|e| ImageError::Io { path: path.to_owned(), source: e })?;
    let mut data: &[u8] = &bytes;
    let channels = match token(&mut data) {
        Some("PF") => 3,
        Some("Pf") => 1,
        _ => return Err(malformed(path, "not a PFM file (expected header PF or Pf)")),
    };
    let mut number = |what: &str| -> Result<f64, ImageError> {
        token(&mut data)
            .and_then(|t| t.parse::<f64>().ok())
            .ok_or_else(|| malformed(path, format!("PFM header: expected {what}")))
    };
    let (w, h, scale) = (number("width")?, number("height")?, number("scale")?);
    if !(w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0) || w * h > 1e9 {
        return Err(malformed(path, format!("PFM header: invalid size {w} x {h}")));
    }
    let (w, h) = (w as usize, h as usize);
    // Exactly one whitespace byte separates the header from the data.
    let body = data.get(1..).unwrap_or(&[]);
    let need = w * h * channels * 4;
    if body.len() < need {
        return Err(malformed(path, format!("PFM data truncated: {} of {need} bytes", body.len())));
    }
    let little = scale < 0.0;
    let value = |i: usize| {
        let b = [body[4 * i], body[4 * i + 1], body[4 * i + 2], body[4 * i + 3]];
        if little { f32::from_le_bytes(b) } else { f32::from_be_bytes(b) }
    };
    let mut pixels = vec![Rgb::ZERO; w * h];
    for row in 0..h {
        let y = h - 1 - row;
        for x in 0..w {
            let i = (row * w + x) * channels;
            pixels[y * w + x] =
                if channels == 3 { Rgb::new(value(i), value(i + 1), value(i + 2)) } else { Rgb::splat(value(i)) };
        }
    }
    Ok(Image::new(w, h, pixels))
}
