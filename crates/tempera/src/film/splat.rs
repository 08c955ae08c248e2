//! Splat buffers for contributions that land on arbitrary pixels. Values are accumulated in
//! fixed point: integer addition is associative and commutative, so the image does not depend
//! on the order in which threads add to it.
//!
//! - [`SplatBuffer`] (light tracing): 64.64 fixed point (`i128`), one buffer per thread, merged;
//!   any radiance fits.
//! - [`SharedSplats`] (Markov chains): 40.24 fixed point in `AtomicI64`, one buffer that every
//!   thread adds to, so memory does not grow with the thread count (the chain driver keeps one
//!   buffer per path depth and, with all-replica reuse, per replica). Chain splats are bounded:
//!   a state of value `f = luminance(C)` splats `C/f` times a weight of at most 1, at most
//!   `1/0.0722` per channel, so the range of ±5.5·10¹¹ per pixel and channel holds more than
//!   10¹⁰ splats on one pixel, and a resolution of 6·10⁻⁸ per splat is far below what the f32
//!   image keeps.

use super::Footprint;
use crate::math::{Rgb, Vec2, is_valid_radiance};
use crate::texture::Image;
use std::sync::Arc;
use std::sync::atomic::{AtomicI64, AtomicU64, Ordering};

const SCALE: f64 = 18_446_744_073_709_551_616.0; // 2^64

#[derive(Clone, Debug)]
pub struct SplatBuffer {
    pub width: u32,
    pub height: u32,
    sums: Vec<[i128; 3]>,
    /// Splats whose value was NaN, infinite or negative (dropped).
    pub invalid: u64,
    footprint: Arc<Footprint>,
}

#[inline]
fn fixed(v: f32) -> i128 {
    (f64::from(v) * SCALE).round() as i128
}

impl SplatBuffer {
    /// A buffer whose splats each land on the pixel containing them (box reconstruction).
    pub fn new(width: u32, height: u32) -> Self {
        Self::with_footprint(Arc::new(Footprint::pixel(width, height)), width, height)
    }

    /// A buffer whose splats go through a film's filter ([`Footprint::of`]), of that film's size.
    pub fn filtered(footprint: &Arc<Footprint>) -> Self {
        let (width, height) = footprint.size();
        Self::with_footprint(footprint.clone(), width, height)
    }

    fn with_footprint(footprint: Arc<Footprint>, width: u32, height: u32) -> Self {
        Self { width, height, sums: vec![[0; 3]; width as usize * height as usize], invalid: 0, footprint }
    }

    /// An empty buffer of the same size and footprint.
    pub fn cleared(&self) -> Self {
        Self::with_footprint(self.footprint.clone(), self.width, self.height)
    }

    /// Adds `l` at raster position `p`, spread over the pixels of the buffer's footprint.
    #[inline]
    pub fn add(&mut self, p: Vec2, l: Rgb) {
        if !is_valid_radiance(l) {
            self.invalid += 1;
            return;
        }
        let sums = &mut self.sums;
        self.footprint.each(p, |i, w| {
            let s = &mut sums[i];
            s[0] += fixed(l.x * w);
            s[1] += fixed(l.y * w);
            s[2] += fixed(l.z * w);
        });
    }

    pub fn merge(&mut self, other: &SplatBuffer) {
        for (a, b) in self.sums.iter_mut().zip(&other.sums) {
            for c in 0..3 {
                a[c] += b[c];
            }
        }
        self.invalid += other.invalid;
    }

    /// The sums, for another process ([`crate::cluster`]).
    pub fn encode(&self, w: &mut crate::cluster::Wire) {
        w.u64(self.invalid);
        for s in &self.sums {
            for v in s {
                w.i128(*v);
            }
        }
    }

    /// Adds the sums [`Self::encode`] wrote for a buffer of the same size.
    pub fn merge_encoded(&mut self, r: &mut crate::cluster::Reader) {
        self.invalid += r.u64();
        for s in &mut self.sums {
            for v in s.iter_mut() {
                *v += r.i128();
            }
        }
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

const SHARED_SCALE: f64 = 16_777_216.0; // 2^24

/// Largest value one splat may add per channel; larger ones are dropped as invalid (they
/// cannot come from a chain, and could overflow the sums).
const SHARED_MAX: f32 = 1.0e9;

/// A splat buffer that threads add to concurrently (see the module documentation).
#[derive(Debug)]
pub struct SharedSplats {
    /// The film's size in pixels.
    pub width: u32,
    pub height: u32,
    /// Each sum covers a square of `2^shift` pixels on a side (0: one pixel).
    shift: u32,
    /// Sums per row.
    row: usize,
    sums: Vec<[AtomicI64; 3]>,
    invalid: AtomicU64,
    footprint: Arc<Footprint>,
}

impl SharedSplats {
    pub fn new(width: u32, height: u32) -> Self {
        Self::coarse(width, height, 0)
    }

    /// A buffer for a film of `width × height` pixels whose sums each cover a square of
    /// `2^shift` pixels on a side: a coarse image of where a chain's splats went.
    pub fn coarse(width: u32, height: u32, shift: u32) -> Self {
        let footprint = Arc::new(Footprint::pixel(width, height));
        Self::with_footprint(width, height, shift, footprint)
    }

    /// A buffer whose splats go through a film's filter ([`Footprint::of`]), of that film's size.
    pub fn filtered(footprint: &Arc<Footprint>) -> Self {
        let (width, height) = footprint.size();
        Self::with_footprint(width, height, 0, footprint.clone())
    }

    fn with_footprint(width: u32, height: u32, shift: u32, footprint: Arc<Footprint>) -> Self {
        let cells = |n: u32| (n as usize).div_ceil(1 << shift);
        let (row, rows) = (cells(width), cells(height));
        let sums = (0..row * rows).map(|_| Default::default()).collect();
        Self { width, height, shift, row, sums, invalid: AtomicU64::new(0), footprint }
    }

    /// An empty buffer of the same size and footprint.
    pub fn cleared(&self) -> Self {
        Self::with_footprint(self.width, self.height, self.shift, self.footprint.clone())
    }

    /// Adds `l` at raster position `p`: spread over the pixels of the buffer's footprint, or
    /// for a coarse buffer on the sum containing `p`.
    #[inline]
    pub fn add(&self, p: Vec2, l: Rgb) {
        if !is_valid_radiance(l) || l.x > SHARED_MAX || l.y > SHARED_MAX || l.z > SHARED_MAX {
            self.invalid.fetch_add(1, Ordering::Relaxed);
            return;
        }
        if self.shift == 0 {
            self.footprint.each(p, |i, w| {
                for (sum, v) in self.sums[i].iter().zip([l.x, l.y, l.z]) {
                    let v = (f64::from(v * w) * SHARED_SCALE).round() as i64;
                    if v != 0 {
                        sum.fetch_add(v, Ordering::Relaxed);
                    }
                }
            });
            return;
        }
        let (x, y) = (p.x.floor(), p.y.floor());
        if x < 0.0 || y < 0.0 || x >= self.width as f32 || y >= self.height as f32 {
            return;
        }
        let s = &self.sums[(y as usize >> self.shift) * self.row + (x as usize >> self.shift)];
        for (sum, v) in s.iter().zip([l.x, l.y, l.z]) {
            let v = (f64::from(v) * SHARED_SCALE).round() as i64;
            if v != 0 {
                sum.fetch_add(v, Ordering::Relaxed);
            }
        }
    }

    /// Splats dropped because their value was NaN, infinite, negative or out of range.
    pub fn invalid(&self) -> u64 {
        self.invalid.load(Ordering::Relaxed)
    }

    /// The fixed-point sums (three per pixel) and the dropped count, last.
    pub fn values(&self) -> Vec<i64> {
        let mut v: Vec<i64> = self.sums.iter().flat_map(|s| s.iter().map(|a| a.load(Ordering::Relaxed))).collect();
        v.push(self.invalid() as i64);
        v
    }

    /// A buffer holding `values` as [`Self::values`] gives them.
    pub fn from_values(width: u32, height: u32, values: &[i64]) -> Self {
        let b = Self::new(width, height);
        for (s, v) in b.sums.iter().zip(values.chunks_exact(3)) {
            for (a, &x) in s.iter().zip(v) {
                a.store(x, Ordering::Relaxed);
            }
        }
        b.invalid.store(values.last().copied().unwrap_or(0) as u64, Ordering::Relaxed);
        b
    }

    /// The accumulated image multiplied by `scale` (consistent once the adding threads have
    /// finished, as between the chain driver's rounds), one pixel per sum.
    pub fn image(&self, scale: f64) -> Image {
        let pixels = self
            .sums
            .iter()
            .map(|s| {
                let c = |i: usize| (s[i].load(Ordering::Relaxed) as f64 / SHARED_SCALE * scale) as f32;
                Rgb::new(c(0), c(1), c(2))
            })
            .collect();
        Image::new(self.row, self.sums.len() / self.row.max(1), pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_splats_from_many_threads_are_bit_identical_to_one() {
        let values: Vec<(Vec2, Rgb)> = (0..20_000)
            .map(|i| {
                (Vec2::new((i % 7) as f32 + 0.5, (i % 3) as f32 + 0.5), Rgb::new(1.0, 0.5, 13.0) / (i as f32 + 1.0))
            })
            .collect();
        let one = SharedSplats::new(7, 3);
        values.iter().for_each(|&(p, l)| one.add(p, l));
        let shared = SharedSplats::new(7, 3);
        std::thread::scope(|scope| {
            for part in values.chunks(1_000) {
                let shared = &shared;
                scope.spawn(move || part.iter().rev().for_each(|&(p, l)| shared.add(p, l)));
            }
        });
        assert_eq!(one.image(1.0).pixels, shared.image(1.0).pixels);
        let total: f64 = one.image(1.0).pixels.iter().map(|p| f64::from(p.z)).sum();
        let want: f64 = values.iter().map(|v| f64::from(v.1.z)).sum();
        assert!((total - want).abs() < 1e-5 * want, "{total} vs {want}");
        one.add(Vec2::new(0.5, 0.5), Rgb::new(f32::NAN, 0.0, 0.0));
        one.add(Vec2::new(0.5, 0.5), Rgb::new(0.0, 2e9, 0.0));
        assert_eq!(one.invalid(), 2);
        assert_eq!(one.image(1.0).pixels, shared.image(1.0).pixels, "dropped splats leave no trace");
    }

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
