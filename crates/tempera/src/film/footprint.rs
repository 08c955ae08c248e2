//! Where a contribution at an arbitrary raster position lands: the film's reconstruction
//! filter applied to splats (light tracing, Markov chains), so that a splatted image has the
//! same expectation as the film's weighted average of camera samples.
//!
//! The film develops a pixel `q` as `Σ w(q − pᵢ)·Lᵢ / Σ w(q − pᵢ)` over the camera samples
//! `pᵢ`, drawn uniformly over the film: in expectation `∫ L(p)·w(q − p) dp / ∫ w(q − p) dp`,
//! both integrals over the film. A splat at `p` therefore adds `L·w(q − p) / (I·m(q))` to each
//! pixel `q` the filter reaches: `I = ∫ w` over the plane and `m(q)` the share of it that lies
//! on the film (1 away from the borders), which is what the film's division by `Σ w` does at
//! the borders. The filter is separable and the film a rectangle, so both factor into a
//! column and a row term. pbrt-v4 splats through the filter with the same `1/I` (`RGBFilm`,
//! Pharr et al. 2023 §5.4.3); a box of radius ½ puts every splat on the one pixel containing
//! it with weight 1, as before filters applied to splats.

use super::{FilmDesc, Filter};
use crate::math::Vec2;
use std::sync::Arc;

/// A filter's splat weights over one film.
#[derive(Clone, Debug)]
pub struct Footprint {
    filter: Filter,
    /// The standard box: the containing pixel, weight 1.
    pixel: bool,
    width: usize,
    height: usize,
    /// `1 / (I_x·m_x)` per column and `1 / (I_y·m_y)` per row.
    columns: Vec<f32>,
    rows: Vec<f32>,
}

impl Footprint {
    /// The footprint of `filter` on a film of `width × height` pixels.
    pub fn new(width: u32, height: u32, filter: Filter) -> Self {
        let pixel = matches!(filter, Filter::Box { radius } if radius == 0.5);
        let norms = |n: u32| -> Vec<f32> {
            if pixel {
                return Vec::new();
            }
            let r = f64::from(filter.radius());
            let whole = integral(&filter, -r, r);
            (0..n)
                .map(|q| {
                    // ∫ over the film's [0, n) of w(c − u) du, c the pixel's centre: the whole
                    // integral unless the filter reaches past a border.
                    let c = q as f64 + 0.5;
                    let inside = c - r >= 0.0 && c + r <= f64::from(n);
                    let on_film = if inside { whole } else { integral(&filter, c - f64::from(n), c) };
                    (1.0 / on_film.max(whole * 1e-6)) as f32
                })
                .collect()
        };
        Self {
            filter,
            pixel,
            width: width as usize,
            height: height as usize,
            columns: norms(width),
            rows: norms(height),
        }
    }

    /// The footprint of `film`'s filter on it.
    pub fn of(film: &FilmDesc) -> Arc<Self> {
        Arc::new(Self::new(film.width, film.height, film.filter))
    }

    /// One pixel per splat with weight 1 (box reconstruction of radius ½).
    pub fn pixel(width: u32, height: u32) -> Self {
        Self::new(width, height, Filter::Box { radius: 0.5 })
    }

    /// The film's size in pixels.
    pub fn size(&self) -> (u32, u32) {
        (self.width as u32, self.height as u32)
    }

    /// Calls `add(index, weight)` for every pixel of the film that a splat at raster position
    /// `p` reaches with a non-zero weight (`index = y·width + x`).
    #[inline]
    pub fn each(&self, p: Vec2, mut add: impl FnMut(usize, f32)) {
        if self.pixel {
            let (x, y) = (p.x.floor(), p.y.floor());
            if x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32 {
                add(y as usize * self.width + x as usize, 1.0);
            }
            return;
        }
        if !(p.x.is_finite() && p.y.is_finite()) {
            return;
        }
        let r = self.filter.radius();
        let span = |v: f32, n: usize| {
            let lo = (v - 0.5 - r).ceil().max(0.0) as usize;
            let hi = ((v - 0.5 + r).floor().min(n as f32 - 1.0)).max(-1.0);
            (lo, (hi + 1.0) as usize)
        };
        let (x0, x1) = span(p.x, self.width);
        let (y0, y1) = span(p.y, self.height);
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        const MAX: usize = 16;
        let mut wx = [0.0f32; MAX];
        let cached = x1 - x0 <= MAX;
        if cached {
            for (x, w) in (x0..x1).zip(wx.iter_mut()) {
                *w = self.filter.eval_1d(x as f32 + 0.5 - p.x) * self.columns[x];
            }
        }
        for y in y0..y1 {
            let wy = self.filter.eval_1d(y as f32 + 0.5 - p.y) * self.rows[y];
            if wy == 0.0 {
                continue;
            }
            for x in x0..x1 {
                let w = if cached { wx[x - x0] } else { self.filter.eval_1d(x as f32 + 0.5 - p.x) * self.columns[x] };
                if w != 0.0 {
                    add(y * self.width + x, wy * w);
                }
            }
        }
    }
}

/// `∫_a^b w(x) dx` of the filter's 1D profile, exactly for the box and the triangle, by
/// composite Simpson quadrature for the (smooth inside its support) Gaussian.
fn integral(filter: &Filter, a: f64, b: f64) -> f64 {
    let r = f64::from(filter.radius());
    let (a, b) = (a.max(-r), b.min(r));
    if a >= b {
        return 0.0;
    }
    match *filter {
        Filter::Box { .. } => b - a,
        Filter::Triangle { .. } => {
            // Antiderivative of r − |x| on [−r, r], zero at −r.
            let f = |x: f64| if x <= 0.0 { (x + r) * (x + r) / 2.0 } else { r * r - (r - x) * (r - x) / 2.0 };
            f(b) - f(a)
        }
        Filter::Gaussian { .. } => {
            let n = 2048;
            let h = (b - a) / n as f64;
            let w = |x: f64| f64::from(filter.eval_1d(x as f32));
            let mut sum = w(a) + w(b);
            for i in 1..n {
                sum += w(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 };
            }
            sum * h / 3.0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn weights(f: &Footprint, p: Vec2) -> Vec<(usize, f32)> {
        let mut v = Vec::new();
        f.each(p, |i, w| v.push((i, w)));
        v
    }

    /// The standard box puts a splat on its pixel with weight 1, and nothing off the film.
    #[test]
    fn the_box_of_radius_one_half_is_one_pixel() {
        let f = Footprint::pixel(4, 3);
        assert_eq!(weights(&f, Vec2::new(2.7, 1.2)), vec![(6, 1.0)]);
        assert_eq!(weights(&f, Vec2::new(2.0, 1.0)), vec![(6, 1.0)]);
        assert!(weights(&f, Vec2::new(4.0, 1.0)).is_empty());
        assert!(weights(&f, Vec2::new(-0.1, 1.0)).is_empty());
    }

    /// Away from the borders a splat's weights sum to about 1 (exactly for integer-radius
    /// boxes and triangles) and follow the filter; at a border,
    /// each pixel's weights, integrated over the splat positions on the film, are 1 (the
    /// film's division by its total weight), so a uniform image stays uniform.
    #[test]
    fn weights_integrate_to_one_per_pixel_for_every_filter() {
        for filter in [
            Filter::Triangle { radius: 2.0 },
            Filter::Gaussian { radius: 1.5, sigma: 0.5 },
            Filter::Box { radius: 1.0 },
            Filter::Triangle { radius: 9.0 },
        ] {
            let (w, h) = (24u32, 20u32);
            let f = Footprint::new(w, h, filter);
            let inner: f32 = weights(&f, Vec2::new(12.3, 9.8)).iter().map(|x| x.1).sum();
            assert!(filter.radius() > 5.0 || (inner - 1.0).abs() < 1e-2, "{filter:?}: {inner}");
            let splat = weights(&f, Vec2::new(12.3, 9.8));
            let at = |x: usize, y: usize| splat.iter().find(|e| e.0 == y * 24 + x).map_or(0.0, |e| e.1);
            let expected = filter.eval(12.5 - 12.3, 10.5 - 9.8) / filter.eval(12.5 - 12.3, 9.5 - 9.8);
            assert!((at(12, 10) / at(12, 9) - expected).abs() < 1e-4, "{filter:?}");
            // Integrate every pixel's weight over splat positions on a fine grid of the film.
            let n = 16;
            let mut total = vec![0.0f64; (w * h) as usize];
            for j in 0..h * n {
                for i in 0..w * n {
                    let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    f.each(p, |q, wt| total[q] += f64::from(wt) / f64::from(n * n));
                }
            }
            for (q, t) in total.iter().enumerate() {
                assert!((t - 1.0).abs() < 0.02, "{filter:?}: pixel {q} integrates to {t}");
            }
        }
    }

    /// Splats of samples drawn uniformly over the film, scaled by `N_pixels / N`, develop
    /// into the image the film's weighted average of stratified camera samples gives, pixel by
    /// pixel, edges and borders included; splatting each on its pixel alone would not.
    #[test]
    fn filtered_splats_develop_into_the_films_image() {
        use crate::film::{Film, FilmDesc, SharedSplats, SplatBuffer, TileBuffer};
        use crate::math::Rgb;
        use crate::math::rng::Pcg32;
        // A diagonal edge and a bright square: sharp features that any filter blurs.
        let radiance = |p: Vec2| {
            let v = if p.x + 0.6 * p.y < 7.3 { 1.0 } else { 0.1 }
                + if (3.0..5.0).contains(&p.x) && p.y > 6.5 { 4.0 } else { 0.0 };
            Rgb::splat(v)
        };
        for filter in [Filter::Triangle { radius: 2.0 }, Filter::Gaussian { radius: 1.5, sigma: 0.5 }] {
            let desc = FilmDesc { width: 12, height: 9, filter };
            let n = 32; // samples per pixel along each axis
            let mut film = Film::new(desc);
            for tile in desc.tiles(4) {
                let mut buf = TileBuffer::new(&desc, tile);
                for y in tile.y0..tile.y1 {
                    for x in tile.x0..tile.x1 {
                        for j in 0..n {
                            for i in 0..n {
                                let p = Vec2::new(
                                    x as f32 + (i as f32 + 0.5) / n as f32,
                                    y as f32 + (j as f32 + 0.5) / n as f32,
                                );
                                buf.add_sample(p, radiance(p));
                            }
                        }
                    }
                }
                film.merge(&buf);
            }
            let expected = film.develop();
            let (mut mine, shared, mut boxed) = (
                SplatBuffer::filtered(&Footprint::of(&desc)),
                SharedSplats::filtered(&Footprint::of(&desc)),
                SplatBuffer::new(12, 9),
            );
            let mut rng = Pcg32::new(7, 1);
            let samples = 12 * 9 * 4096;
            for _ in 0..samples {
                let p = Vec2::new(rng.next_f32() * 12.0, rng.next_f32() * 9.0);
                mine.add(p, radiance(p));
                shared.add(p, radiance(p));
                boxed.add(p, radiance(p));
            }
            let scale = 108.0 / samples as f64;
            let worst = |img: &crate::texture::Image| {
                img.pixels.iter().zip(&expected.pixels).map(|(a, b)| (a.x - b.x).abs() / b.x).fold(0.0f32, f32::max)
            };
            let (a, b, c) = (worst(&mine.image(scale)), worst(&shared.image(scale)), worst(&boxed.image(scale)));
            assert!(a < 0.06 && b < 0.06, "{filter:?}: filtered splats differ from the film by up to {a} and {b}");
            assert!(c > 0.2, "{filter:?}: box splats would differ by {c}");
        }
    }
}
