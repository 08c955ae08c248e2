//! The film: per-tile accumulation of filtered samples in `f64`, merged into the full image in a
//! fixed order (so the result does not depend on thread scheduling), and development into a
//! linear RGB image.

pub mod filter;
pub mod footprint;
pub mod splat;

pub use filter::Filter;
pub use footprint::Footprint;
pub use splat::{SharedSplats, SplatBuffer};

use crate::math::{Rgb, Vec2, is_valid_radiance};
use crate::texture::Image;

/// Film size and filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmDesc {
    pub width: u32,
    pub height: u32,
    pub filter: Filter,
}

impl Default for FilmDesc {
    fn default() -> Self {
        Self { width: 512, height: 512, filter: Filter::default() }
    }
}

/// A rectangle of pixels `[x0, x1) × [y0, y1)`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Tile {
    pub x0: u32,
    pub y0: u32,
    pub x1: u32,
    pub y1: u32,
}

impl FilmDesc {
    /// The film cut into square tiles in scanline order.
    pub fn tiles(&self, size: u32) -> Vec<Tile> {
        let mut tiles = Vec::new();
        for y0 in (0..self.height).step_by(size as usize) {
            for x0 in (0..self.width).step_by(size as usize) {
                tiles.push(Tile { x0, y0, x1: (x0 + size).min(self.width), y1: (y0 + size).min(self.height) });
            }
        }
        tiles
    }
}

/// Weighted sums `(Σ w·r, Σ w·g, Σ w·b, Σ w)` of one pixel.
type PixelSum = [f64; 4];

/// Accumulates the samples of one tile, including the apron its filter reaches into.
#[derive(Clone, Debug)]
pub struct TileBuffer {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    sums: Vec<PixelSum>,
    filter: Filter,
    /// Samples whose value was NaN, infinite or negative (recorded as black).
    pub invalid_samples: u64,
}

impl TileBuffer {
    pub fn new(film: &FilmDesc, tile: Tile) -> Self {
        let r = film.filter.radius().ceil() as i64;
        let x0 = (i64::from(tile.x0) - r).max(0);
        let y0 = (i64::from(tile.y0) - r).max(0);
        let x1 = (i64::from(tile.x1) + r).min(i64::from(film.width));
        let y1 = (i64::from(tile.y1) + r).min(i64::from(film.height));
        let (width, height) = (x1 - x0, y1 - y0);
        Self {
            x0,
            y0,
            width,
            height,
            sums: vec![[0.0; 4]; width as usize * height as usize],
            filter: film.filter,
            invalid_samples: 0,
        }
    }

    /// Adds a radiance sample at raster position `p`. Invalid values count as black.
    #[inline]
    pub fn add_sample(&mut self, p: Vec2, l: Rgb) {
        let l = if is_valid_radiance(l) {
            l
        } else {
            self.invalid_samples += 1;
            Rgb::ZERO
        };
        let r = self.filter.radius();
        let lo_x = ((p.x - 0.5 - r).ceil() as i64).max(self.x0);
        let hi_x = ((p.x - 0.5 + r).floor() as i64).min(self.x0 + self.width - 1);
        let lo_y = ((p.y - 0.5 - r).ceil() as i64).max(self.y0);
        let hi_y = ((p.y - 0.5 + r).floor() as i64).min(self.y0 + self.height - 1);
        for y in lo_y..=hi_y {
            for x in lo_x..=hi_x {
                let w = self.filter.eval(p.x - (x as f32 + 0.5), p.y - (y as f32 + 0.5));
                if w == 0.0 {
                    continue;
                }
                let s = &mut self.sums[((y - self.y0) * self.width + (x - self.x0)) as usize];
                let w = f64::from(w);
                s[0] += w * f64::from(l.x);
                s[1] += w * f64::from(l.y);
                s[2] += w * f64::from(l.z);
                s[3] += w;
            }
        }
    }
}

impl TileBuffer {
    /// The buffer, bit for bit, for another process ([`crate::cluster`]).
    pub fn encode(&self, w: &mut crate::cluster::Wire) {
        w.u64(self.x0 as u64).u64(self.y0 as u64).u64(self.width as u64).u64(self.height as u64);
        w.u64(self.invalid_samples);
        for s in &self.sums {
            for v in s {
                w.f64(*v);
            }
        }
    }

    /// A buffer [`Self::encode`] wrote, on the film `film`.
    pub fn decode(film: &FilmDesc, r: &mut crate::cluster::Reader) -> Self {
        let (x0, y0, width, height) = (r.u64() as i64, r.u64() as i64, r.u64() as i64, r.u64() as i64);
        let invalid_samples = r.u64();
        let sums = (0..width * height).map(|_| [r.f64(), r.f64(), r.f64(), r.f64()]).collect();
        Self { x0, y0, width, height, sums, filter: film.filter, invalid_samples }
    }
}

/// The whole film's weighted sums.
#[derive(Clone, Debug)]
pub struct Film {
    pub desc: FilmDesc,
    sums: Vec<PixelSum>,
    pub invalid_samples: u64,
}

impl Film {
    pub fn new(desc: FilmDesc) -> Self {
        Self { desc, sums: vec![[0.0; 4]; (desc.width * desc.height) as usize], invalid_samples: 0 }
    }

    /// Adds a tile's sums. Merging tiles in a fixed order makes the result deterministic.
    pub fn merge(&mut self, tile: &TileBuffer) {
        for y in 0..tile.height {
            for x in 0..tile.width {
                let src = &tile.sums[(y * tile.width + x) as usize];
                let dst = &mut self.sums[((tile.y0 + y) * i64::from(self.desc.width) + tile.x0 + x) as usize];
                for c in 0..4 {
                    dst[c] += src[c];
                }
            }
        }
        self.invalid_samples += tile.invalid_samples;
    }

    /// The filtered image `Σ w·L / Σ w`; pixels without samples are black.
    pub fn develop(&self) -> Image {
        let pixels = self
            .sums
            .iter()
            .map(|s| {
                if s[3] > 0.0 {
                    Rgb::new((s[0] / s[3]) as f32, (s[1] / s[3]) as f32, (s[2] / s[3]) as f32)
                } else {
                    Rgb::ZERO
                }
            })
            .collect();
        Image::new(self.desc.width as usize, self.desc.height as usize, pixels)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_filter_averages_within_the_pixel() {
        let desc = FilmDesc { width: 4, height: 2, filter: Filter::default() };
        let mut film = Film::new(desc);
        for tile in desc.tiles(2) {
            let mut buf = TileBuffer::new(&desc, tile);
            for y in tile.y0..tile.y1 {
                for x in tile.x0..tile.x1 {
                    buf.add_sample(Vec2::new(x as f32 + 0.25, y as f32 + 0.5), Rgb::splat(x as f32));
                    buf.add_sample(Vec2::new(x as f32 + 0.75, y as f32 + 0.5), Rgb::splat(x as f32 + 1.0));
                }
            }
            film.merge(&buf);
        }
        let img = film.develop();
        assert_eq!(img.get(2, 1), Rgb::splat(2.5));
        assert_eq!(img.get(0, 0), Rgb::splat(0.5));
    }

    #[test]
    fn wide_filters_reach_neighbours_across_tiles_and_invalid_samples_are_black() {
        let desc = FilmDesc { width: 4, height: 4, filter: Filter::Gaussian { radius: 1.5, sigma: 0.5 } };
        let mut film = Film::new(desc);
        let tiles = desc.tiles(2);
        let mut buf = TileBuffer::new(&desc, tiles[0]);
        buf.add_sample(Vec2::new(1.9, 1.9), Rgb::ONE);
        buf.add_sample(Vec2::new(0.5, 0.5), Rgb::new(f32::NAN, 0.0, 0.0));
        film.merge(&buf);
        let img = film.develop();
        assert_eq!(img.get(2, 2), Rgb::ONE, "sample reaches the next tile's pixel");
        assert!(img.get(0, 0).is_finite());
        assert_eq!(film.invalid_samples, 1);
    }
}
