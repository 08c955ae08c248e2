//! Splat buffers for contributions that land on arbitrary pixels (light tracing, MCMC). Values
//! are accumulated in 64.64 fixed point (`i128`): integer addition is associative, so buffers
//! filled by any number of threads in any order merge to a bit-identical image.

use crate::math::{Rgb, Vec2, is_valid_radiance};
use crate::texture::Image;

const SCALE: f64 = 18_446_744_073_709_551_616.0; // 2^64

#[derive(Clone, Debug)]
pub struct SplatBuffer {
    pub width: u32,
    pub height: u32,
    sums: Vec<[i128; 3]>,
    /// Splats whose value was NaN, infinite or negative (dropped).
    pub invalid: u64,
}

#[inline]
fn fixed(v: f32) -> i128 {
    (f64::from(v) * SCALE).round() as i128
}

impl SplatBuffer {
    pub fn new(width: u32, height: u32) -> Self {
        Self { width, height, sums: vec![[0; 3]; (width * height) as usize], invalid: 0 }
    }

    /// Adds `l` to the pixel containing raster position `p` (box reconstruction).
    #[inline]
    pub fn add(&mut self, p: Vec2, l: Rgb) {
        if !is_valid_radiance(l) {
            self.invalid += 1;
            return;
        }
        let (x, y) = (p.x.floor(), p.y.floor());
        if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
            return;
        }
        let s = &mut self.sums[y as usize * self.width as usize + x as usize];
        s[0] += fixed(l.x);
        s[1] += fixed(l.y);
        s[2] += fixed(l.z);
    }

    pub fn merge(&mut self, other: &SplatBuffer) {
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.invalid += other.invalid;
    }

    /// The accumulated image multiplied by `scale`.
    pub fn image(&self, scale: f64) -> Image {
        let pixels = self
            .sums
            .iter()
            .map(|s| {
                Rgb::new(
                    (s[0] as f64 / SCALE * scale) as f32,
                    (s[1] as f64 / SCALE * scale) as f32,
                    (s[2] as f64 / SCALE * scale) as f32,
                )
            })
            .collect();
        Image::new(self.width as usize, self.height as usize, pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn merging_in_any_order_is_bit_identical() {
        let values: Vec<(Vec2, Rgb)> = (0..1000)
            .map(|i| (Vec2::new((i % 4) as f32 + 0.5, 0.5), Rgb::splat(1.0 / (i as f32 + 1.0)) * 1e3))
            .collect();
        let mut a = SplatBuffer::new(4, 1);
        values.iter().for_each(|&(p, l)| a.add(p, l));
        let mut parts = [SplatBuffer::new(4, 1), SplatBuffer::new(4, 1), SplatBuffer::new(4, 1)];
        for (i, &(p, l)) in values.iter().rev().enumerate() {
            parts[i % 3].add(p, l);
        }
        let mut b = SplatBuffer::new(4, 1);
        for part in parts.iter().rev() {
            b.merge(part);
        }
        assert_eq!(a.image(1.0).pixels, b.image(1.0).pixels);
        let total: f32 = a.image(1.0).pixels.iter().map(|p| p.x).sum();
        let want: f32 = values.iter().map(|v| v.1.x).sum();
        assert!((total - want).abs() < 1e-3 * want);
        a.add(Vec2::new(0.5, 0.5), Rgb::new(f32::NAN, 0.0, 0.0));
        assert_eq!(a.invalid, 1);
    }
}
