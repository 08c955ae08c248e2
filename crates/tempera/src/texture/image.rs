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
