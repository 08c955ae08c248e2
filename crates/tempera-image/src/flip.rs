//! LDR-FLIP (Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", HPG 2020)
//! through NVIDIA's reference implementation (the `nv-flip` crate).
//!
//! FLIP compares images as a person flipping between them would see them, so linear radiance
//! is first tone mapped the way `tempera render -o image.png` writes it: clamped to `[0, 1]`
//! and sRGB-encoded to 8 bits, with no exposure change. The observer sees
//! [`PIXELS_PER_DEGREE`] pixels per degree of visual angle (FLIP's default: a 0.7 m wide 4K
//! monitor seen from 0.7 m). The score is the mean of the per-pixel FLIP map, in `[0, 1]`
//! (0: no visible difference).

use tempera::math::Rgb;
use tempera::texture::Image;

/// Pixels per degree of visual angle of the assumed observer.
pub const PIXELS_PER_DEGREE: f32 = nv_flip::DEFAULT_PIXELS_PER_DEGREE;

fn ldr(image: &Image) -> nv_flip::FlipImageRgb8 {
    let data: Vec<u8> = image
        .pixels
        .iter()
        .flat_map(|p| p.to_array())
        .map(|v| {
            let v = if v.is_finite() { v } else { 0.0 };
            (crate::linear_to_srgb(v) * 255.0 + 0.5) as u8
        })
        .collect();
    nv_flip::FlipImageRgb8::with_data(image.width as u32, image.height as u32, &data)
}

/// The per-pixel FLIP error of `image` against `reference` (same size, else an error) and its mean.
pub fn flip(image: &Image, reference: &Image) -> Result<(f64, Vec<f32>), String> {
    crate::check_sizes(image, reference)?;
    if image.pixels.is_empty() {
        return Ok((0.0, Vec::new()));
    }
    let map = nv_flip::flip(ldr(reference), ldr(image), PIXELS_PER_DEGREE);
    let mean = f64::from(nv_flip::FlipPool::from_image(&map).mean());
    Ok((mean, map.to_vec()))
}

/// The FLIP map in FLIP's magma colour map (linear RGB, for any writer), without a legend.
pub fn flip_colours(values: &[f32], width: usize, height: usize) -> Image {
    let map = nv_flip::FlipImageFloat::with_data(width as u32, height as u32, values);
    let rgb = map.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    let pixels = rgb
        .chunks_exact(3)
        .map(|c| {
            let f = |v: u8| crate::srgb_to_linear(f32::from(v) / 255.0);
            Rgb::new(f(c[0]), f(c[1]), f(c[2]))
        })
        .collect();
    Image::new(width, height, pixels)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(w: usize, h: usize, f: impl Fn(usize, usize) -> f32) -> Image {
        let pixels = (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(|(x, y)| Rgb::splat(f(x, y))).collect();
        Image::new(w, h, pixels)
    }

    #[test]
    fn identical_images_score_zero_and_opposites_score_high() {
        let a = grey(32, 32, |x, y| ((x + y) % 7) as f32 / 7.0);
        assert_eq!(flip(&a, &a).unwrap().0, 0.0);
        let (black, white) = (grey(32, 32, |_, _| 0.0), grey(32, 32, |_, _| 1.0));
        let (score, map) = flip(&black, &white).unwrap();
        assert_eq!(map.len(), 32 * 32);
        // Black against white is the largest colour difference FLIP knows.
        assert!(score > 0.9 && score <= 1.0, "{score}");
        assert!(flip(&grey(2, 2, |_, _| 0.0), &white).is_err());
    }

    #[test]
    fn more_noise_scores_higher() {
        let reference = grey(48, 48, |_, _| 0.3);
        let noisy = |amplitude: f32| {
            grey(48, 48, |x, y| {
                let h = (x * 7919 + y * 104_729) % 1000;
                0.3 + amplitude * (h as f32 / 1000.0 - 0.5)
            })
        };
        let scores: Vec<f64> = [0.02, 0.1, 0.4].iter().map(|&a| flip(&noisy(a), &reference).unwrap().0).collect();
        assert!(scores[0] < scores[1] && scores[1] < scores[2], "{scores:?}");
        // Values above 1 tone map to white: an overexposed difference is invisible.
        assert_eq!(flip(&grey(8, 8, |_, _| 2.0), &grey(8, 8, |_, _| 5.0)).unwrap().0, 0.0);
    }
}
