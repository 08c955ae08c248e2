//! Image comparison metrics and a false-colour error map.
//!
//! - MSE and RMSE: over all pixels and the three RGB channels.
//! - relMSE: `mean((I − R)² / (R² + ε))` on luminance (Rec. 709 weights), `ε = 0.01`, the
//!   convention of Rousselle et al. and later MCMC rendering papers.
//! - SMAPE: `mean(|I − R| / (|I| + |R| + ε))` over pixels and channels, `ε = 0.01`, in `[0, 1]`.
//! - FLIP: mean LDR-FLIP error after clamping and sRGB encoding (see [`crate::flip`]).
//! - The mean ratio: mean luminance of `I` over mean luminance of `R`.
//!
//! The relMSE error map shows the per-pixel relMSE term on a logarithmic scale from 10⁻⁴ to
//! 10⁰ with a viridis-like colour map, and a colour bar with decade labels beneath the image;
//! the FLIP error map shows the FLIP map in FLIP's magma colours with a bar from 0 to 1.

use crate::check_sizes;
use tempera::math::{Rgb, luminance};
use tempera::texture::Image;

/// ε of relMSE and SMAPE.
pub const EPSILON: f64 = 0.01;

/// The metrics [`compare`] computes, by name.
pub const METRICS: &[&str] = &["mse", "rmse", "relmse", "smape", "flip"];

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Comparison {
    pub mse: f64,
    pub rmse: f64,
    pub relmse: f64,
    pub smape: f64,
    pub flip: f64,
    pub mean_ratio: f64,
}

impl Comparison {
    pub fn get(&self, name: &str) -> Option<f64> {
        match name {
            "mse" => Some(self.mse),
            "rmse" => Some(self.rmse),
            "relmse" => Some(self.relmse),
            "smape" => Some(self.smape),
            "flip" => Some(self.flip),
            _ => None,
        }
    }
}

fn lum(c: Rgb) -> f64 {
    f64::from(luminance(c))
}

/// The relMSE term of one pixel.
pub fn rel_se(i: Rgb, r: Rgb) -> f64 {
    let (i, r) = (lum(i), lum(r));
    (i - r).powi(2) / (r * r + EPSILON)
}

/// Compares `image` with `reference`; they must have the same size.
pub fn compare(image: &Image, reference: &Image) -> Result<Comparison, String> {
    check_sizes(image, reference)?;
    let n = image.pixels.len().max(1) as f64;
    let (mut se, mut rel, mut smape, mut sum_i, mut sum_r) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (&i, &r) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let (a, b) = (f64::from(i[c]), f64::from(r[c]));
            se += (a - b).powi(2);
            smape += (a - b).abs() / (a.abs() + b.abs() + EPSILON);
        }
        rel += rel_se(i, r);
        sum_i += lum(i);
        sum_r += lum(r);
    }
    let mse = se / (3.0 * n);
    Ok(Comparison {
        mse,
        rmse: mse.sqrt(),
        relmse: rel / n,
        smape: smape / (3.0 * n),
        flip: crate::flip::flip(image, reference)?.0,
        mean_ratio: if sum_r != 0.0 { sum_i / sum_r } else { f64::NAN },
    })
}

/// A viridis-like colour map on `[0, 1]` (linear RGB).
fn colour(t: f64) -> Rgb {
    const STOPS: [[f32; 3]; 5] = [
        [0.267, 0.005, 0.329],
        [0.229, 0.322, 0.546],
        [0.128, 0.567, 0.551],
        [0.369, 0.789, 0.383],
        [0.993, 0.906, 0.144],
    ];
    let x = t.clamp(0.0, 1.0) * 4.0;
    let i = (x as usize).min(3);
    let f = (x - i as f64) as f32;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let srgb = Rgb::new(a[0] + (b[0] - a[0]) * f, a[1] + (b[1] - a[1]) * f, a[2] + (b[2] - a[2]) * f);
    Rgb::new(crate::srgb_to_linear(srgb.x), crate::srgb_to_linear(srgb.y), crate::srgb_to_linear(srgb.z))
}

/// Decades the error map spans: 10^LOW … 10^HIGH.
const LOW: f64 = -4.0;
const HIGH: f64 = 0.0;

/// 3×5 bitmap glyphs for the legend labels, one row per `u8` (bit 2 is the left column).
fn glyph(c: char) -> [u8; 5] {
    match c {
        '0' => [7, 5, 5, 5, 7],
        '1' => [2, 6, 2, 2, 7],
        '2' => [7, 1, 7, 4, 7],
        '3' => [7, 1, 7, 1, 7],
        '4' => [5, 5, 7, 1, 1],
        '5' => [7, 4, 7, 1, 7],
        '.' => [0, 0, 0, 0, 2],
        'e' => [0, 7, 7, 4, 7],
        '-' => [0, 0, 7, 0, 0],
        _ => [0; 5],
    }
}

/// `map` (`w × h` pixels) with a colour bar of `colour` over `[0, 1]` beneath it and white
/// `labels` at their positions along the bar (0 = left end, 1 = right end).
fn with_legend(map: Vec<Rgb>, w: usize, h: usize, colour: impl Fn(f64) -> Rgb, labels: &[(f64, String)]) -> Image {
    let (bar, label_rows) = (12, 9);
    let height = h + 4 + bar + label_rows;
    let mut out = Image::new(w, height, vec![Rgb::ZERO; w * height]);
    out.pixels[..w * h].copy_from_slice(&map);
    for x in 0..w {
        let c = colour(x as f64 / (w.max(2) - 1) as f64);
        for y in h + 4..h + 4 + bar {
            out.pixels[y * w + x] = c;
        }
    }
    for (position, text) in labels {
        let width = text.len() * 4;
        let centre = (position.clamp(0.0, 1.0) * (w.max(1) - 1) as f64).round() as usize;
        let x0 = centre.saturating_sub(width / 2).min(w.saturating_sub(width));
        for (k, ch) in text.chars().enumerate() {
            for (row, bits) in glyph(ch).iter().enumerate() {
                for col in 0..3 {
                    let (x, y) = (x0 + k * 4 + col, h + 4 + bar + 2 + row);
                    if bits & (4 >> col) != 0 && x < w && y < height {
                        out.pixels[y * w + x] = Rgb::ONE;
                    }
                }
            }
        }
    }
    out
}

/// The false-colour map of the per-pixel relMSE terms, with a colour bar and labels
/// (`1e-4` … `1e0`) beneath; linear RGB, ready for any writer.
pub fn error_map(image: &Image, reference: &Image) -> Result<Image, String> {
    check_sizes(image, reference)?;
    let values: Vec<f64> = image.pixels.iter().zip(&reference.pixels).map(|(&i, &r)| rel_se(i, r)).collect();
    Ok(value_map(&values, image.width, image.height))
}

/// Per-pixel values (such as relative variances) in the relMSE map's colours and log scale
/// (10⁻⁴ … 10⁰), with the same legend; `values` has `width × height` entries.
pub fn value_map(values: &[f64], width: usize, height: usize) -> Image {
    let map = values.iter().map(|&v| colour((v.max(1e-30).log10() - LOW) / (HIGH - LOW))).collect();
    let decades = (HIGH - LOW) as usize;
    let labels: Vec<(f64, String)> =
        (0..=decades).map(|d| (d as f64 / decades as f64, format!("1e{}", LOW as i32 + d as i32))).collect();
    with_legend(map, width, height, colour, &labels)
}

/// The FLIP error map in FLIP's magma colours with a colour bar from 0 to 1 beneath.
pub fn flip_error_map(image: &Image, reference: &Image) -> Result<Image, String> {
    let (_, values) = crate::flip::flip(image, reference)?;
    let (w, h) = (image.width, image.height);
    let map = crate::flip::flip_colours(&values, w, h).pixels;
    let ramp: Vec<f32> = (0..256).map(|i| i as f32 / 255.0).collect();
    let ramp = crate::flip::flip_colours(&ramp, 256, 1).pixels;
    let colour = |t: f64| ramp[(t.clamp(0.0, 1.0) * 255.0).round() as usize];
    let labels = [(0.0, "0".to_owned()), (0.5, "0.5".to_owned()), (1.0, "1".to_owned())];
    Ok(with_legend(map, w, h, colour, &labels))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn image(values: &[f32]) -> Image {
        Image::new(values.len(), 1, values.iter().map(|&v| Rgb::splat(v)).collect())
    }

    #[test]
    fn metrics_match_hand_computed_values() {
        let (i, r) = (image(&[1.0, 0.5]), image(&[1.0, 1.0]));
        let c = compare(&i, &r).unwrap();
        assert!((c.mse - 0.125).abs() < 1e-9, "{c:?}");
        assert!((c.rmse - 0.125f64.sqrt()).abs() < 1e-9);
        // Luminance of grey v is v (weights sum to 1, up to f32 rounding).
        assert!((c.relmse - 0.5 * 0.25 / 1.01).abs() < 1e-6, "{c:?}");
        assert!((c.smape - 0.5 * 0.5 / 1.51).abs() < 1e-6, "{c:?}");
        assert!((c.mean_ratio - 0.75).abs() < 1e-6);
        let same = compare(&r, &r).unwrap();
        assert_eq!((same.mse, same.relmse, same.smape), (0.0, 0.0, 0.0));
        assert!(compare(&image(&[1.0]), &r).is_err(), "sizes must match");
    }

    #[test]
    fn error_map_has_a_legend_and_orders_errors_by_colour() {
        let i = image(&[
            1.0, 1.1, 2.0, 10.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0,
        ]);
        let r = image(&[1.0; 20]);
        let map = error_map(&i, &r).unwrap();
        assert_eq!((map.width, map.height), (20, 1 + 4 + 12 + 9));
        // Larger errors map further along the colour map (the last stop is the brightest).
        let l: Vec<f32> = map.pixels[..4].iter().map(|&p| luminance(p)).collect();
        assert!(l[0] < l[1] && l[1] < l[2] && l[2] <= l[3], "{l:?}");
        // The bar runs from dark to bright, and labels put white pixels beneath it.
        let bar_row = &map.pixels[5 * 20..6 * 20];
        assert!(luminance(bar_row[0]) < luminance(bar_row[19]));
        assert!(map.pixels[(1 + 4 + 12) * 20..].contains(&Rgb::ONE));
    }

    #[test]
    fn flip_is_reported_and_mapped_with_a_legend() {
        let r = Image::new(16, 16, vec![Rgb::splat(0.5); 256]);
        let mut i = r.clone();
        i.pixels[0] = Rgb::ONE;
        let c = compare(&i, &r).unwrap();
        assert!(c.flip > 0.0 && c.flip < 0.1, "{c:?}");
        assert_eq!(c.get("flip"), Some(c.flip));
        let map = flip_error_map(&i, &r).unwrap();
        assert_eq!((map.width, map.height), (16, 16 + 4 + 12 + 9));
        // The differing pixel is brighter in the map than the untouched far corner.
        assert!(luminance(map.pixels[0]) > luminance(map.pixels[255]));
    }
}
