//! Image data and bilinear image textures with wrap modes (pbrt-v4 §10.4.3). Images are stored
//! top row first; texture space has `v = 0` at the bottom row, as in pbrt and Mitsuba.

use super::UvMapping;
use crate::math::{Rgb, Vec2};
use std::sync::Arc;

/// A linear-RGB floating-point image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<Rgb>,
}

impl Image {
    pub fn new(width: usize, height: usize, pixels: Vec<Rgb>) -> Self {
        assert_eq!(pixels.len(), width * height, "pixel count must match the image size");
        Self { width, height, pixels }
    }

    pub fn filled(width: usize, height: usize, value: Rgb) -> Self {
        Self::new(width, height, vec![value; width * height])
    }

    #[inline]
    pub fn get(&self, x: usize, y: usize) -> Rgb {
        self.pixels[y * self.width + x]
    }

    /// The image reduced by an integer `factor` in both axes, each output pixel the mean of a
    /// `factor × factor` block (what a box-filtered render at the lower resolution estimates);
    /// `None` when the size is not a multiple of `factor`.
    pub fn downsample(&self, factor: usize) -> Option<Image> {
        if factor == 0 || !self.width.is_multiple_of(factor) || !self.height.is_multiple_of(factor) {
            return None;
        }
        let (w, h) = (self.width / factor, self.height / factor);
        let n = (factor * factor) as f64;
        let mut pixels = Vec::with_capacity(w * h);
        for y in 0..h {
            for x in 0..w {
                let mut sum = [0f64; 3];
                for dy in 0..factor {
                    for dx in 0..factor {
                        let p = self.get(x * factor + dx, y * factor + dy);
                        for c in 0..3 {
                            sum[c] += f64::from(p[c]);
                        }
                    }
                }
                pixels.push(Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32));
            }
        }
        Some(Image::new(w, h, pixels))
    }

    pub fn mean(&self) -> Rgb {
        let sum = self
            .pixels
            .iter()
            .fold([0f64; 3], |acc, p| [acc[0] + f64::from(p.x), acc[1] + f64::from(p.y), acc[2] + f64::from(p.z)]);
        let n = self.pixels.len().max(1) as f64;
        Rgb::new((sum[0] / n) as f32, (sum[1] / n) as f32, (sum[2] / n) as f32)
    }
}

/// What a lookup outside `[0, 1)` sees.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    #[default]
    Repeat,
    Clamp,
    Black,
}

impl WrapMode {
    /// Maps an integer texel coordinate into range, or `None` for black.
    #[inline]
    fn apply(self, i: i64, n: usize) -> Option<usize> {
        let n = n as i64;
        match self {
            WrapMode::Repeat => Some(i.rem_euclid(n) as usize),
            WrapMode::Clamp => Some(i.clamp(0, n - 1) as usize),
            WrapMode::Black => (0..n).contains(&i).then_some(i as usize),
        }
    }
}

/// A bilinearly filtered image lookup.
#[derive(Clone, Debug)]
pub struct ImageTexture {
    pub image: Arc<Image>,
    pub wrap: WrapMode,
    pub mapping: UvMapping,
    pub scale: f32,
    pub invert: bool,
}

impl ImageTexture {
    pub fn new(image: Arc<Image>) -> Self {
        Self { image, wrap: WrapMode::Repeat, mapping: UvMapping::default(), scale: 1.0, invert: false }
    }

    fn texel(&self, x: i64, y: i64) -> Rgb {
        match (self.wrap.apply(x, self.image.width), self.wrap.apply(y, self.image.height)) {
            (Some(x), Some(y)) => self.image.get(x, y),
            _ => Rgb::ZERO,
        }
    }

    /// Bilinear lookup at texture coordinates `uv`.
    pub fn bilinear(&self, uv: Vec2) -> Rgb {
        let st = self.mapping.map(uv);
        let x = st.x * self.image.width as f32 - 0.5;
        let y = (1.0 - st.y) * self.image.height as f32 - 0.5;
        if !x.is_finite() || !y.is_finite() {
            return Rgb::ZERO;
        }
        let (x0, y0) = (x.floor(), y.floor());
        let (dx, dy) = (x - x0, y - y0);
        let (xi, yi) = (x0 as i64, y0 as i64);
        let v = (1.0 - dx) * (1.0 - dy) * self.texel(xi, yi)
            + dx * (1.0 - dy) * self.texel(xi + 1, yi)
            + (1.0 - dx) * dy * self.texel(xi, yi + 1)
            + dx * dy * self.texel(xi + 1, yi + 1);
        let v = v * self.scale;
        if self.invert { (Rgb::ONE - v).max(Rgb::ZERO) } else { v }
    }
}

#[cfg(test)]
mod downsample_tests {
    use super::*;

    #[test]
    fn downsampling_averages_blocks_and_refuses_other_sizes() {
        let pixels = (0..16).map(|i| Rgb::splat(i as f32)).collect();
        let img = Image::new(4, 4, pixels);
        let half = img.downsample(2).unwrap();
        assert_eq!((half.width, half.height), (2, 2));
        // Top-left block: 0, 1, 4, 5.
        assert_eq!(half.get(0, 0), Rgb::splat(2.5));
        assert_eq!(half.get(1, 1), Rgb::splat(12.5));
        assert_eq!(half.mean(), img.mean());
        assert!(img.downsample(3).is_none() && img.downsample(0).is_none());
    }
}
