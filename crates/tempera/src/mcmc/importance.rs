//! A per-pixel shape for the chains' target: each depth `k ≥ 1` samples
//! `g(x) = f(x) / ψ(p(x))` instead of `f(x)`, where `p(x)` is the pixel the state's
//! contribution lands on and `ψ` a smooth estimate of that pixel's brightness.
//!
//! MMLT's target `f` sends mutations to a pixel in proportion to its brightness, which suits the
//! image's absolute error: a pixel a hundred times dimmer than a caustic gets a hundredth of its
//! mutations, and so about ten times its relative error. Judged by relative error (relMSE,
//! FLIP, the eye), the dim parts of the image then carry most of the error. Any positive target
//! gives the same image in expectation (Hoberock & Hart 2010, arbitrary importance functions
//! for Metropolis light transport): a state splats `C/g` and the depth is normalised by
//! `b_k = E[g]` over uniform points, both estimated with `g` where MMLT uses `f`. With
//! `ψ(p) = sqrt(Ī_p² + φ²)` each pixel brighter than `φ` gets about as many mutations as any
//! other, so its relative error is about the same, and pixels darker than `φ` get fewer, in
//! proportion to their brightness over `φ`. For an estimator whose per-pixel variance is its
//! brightness squared over its samples, `n_p ∝ Ī_p/ψ_p` is the allocation that minimises the
//! sum of `Var_p/(Ī_p² + φ²)`, relMSE with `φ²` as its `ε`.
//!
//! `Ī` comes from a short bidirectional path tracing pilot ([`ImportanceMap::from_pilot`]):
//! per pixel the largest value of its 3×3 neighbourhood, averaged over the 3×3 neighbourhood
//! again. `φ` is `floor` times the pilot's mean. The map errs towards bright: a pixel the pilot
//! overestimates gets fewer mutations than it should, and only its own noise grows; one it
//! underestimates (a glint the pilot missed) gets a target far above its neighbours', where
//! the chains that find it stay and pile up its light, and the depth's normalisation, a mean of
//! `g`, gets the heavier tail. Depth 0 (the emitters seen directly) keeps MMLT's
//! target: each depth's chains and normalisation are their own, so every depth may have its own
//! positive target.

use crate::math::Vec2;

/// The floor `φ` over the pilot image's mean unless the render says otherwise.
pub const DEFAULT_FLOOR: f64 = 0.5;

/// The factor `1/ψ(p)` a depth `k ≥ 1` state's value is multiplied by, per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportanceMap {
    width: usize,
    height: usize,
    factor: Vec<f32>,
}

impl ImportanceMap {
    /// The map for a pilot image's pixel luminances (`width × height`, row by row) with the
    /// floor `φ = floor · mean`; `None` if the pilot saw no light (or `floor` is not positive).
    pub fn from_pilot(width: usize, height: usize, luminance: &[f32], floor: f64) -> Option<Self> {
        if width == 0 || height == 0 || luminance.len() != width * height || floor.is_nan() || floor <= 0.0 {
            return None;
        }
        let clean: Vec<f32> = luminance.iter().map(|&y| if y.is_finite() && y > 0.0 { y } else { 0.0 }).collect();
        let largest = neighbourhood(width, height, &clean, |v| v.iter().copied().fold(0.0, f32::max));
        let smooth = neighbourhood(width, height, &largest, |v| v.iter().sum::<f32>() / v.len() as f32);
        let mean = smooth.iter().map(|&y| f64::from(y)).sum::<f64>() / smooth.len() as f64;
        let phi = floor * mean;
        if !(phi > 0.0 && phi.is_finite()) {
            return None;
        }
        let factor = smooth.iter().map(|&y| (1.0 / (f64::from(y).powi(2) + phi * phi).sqrt()) as f32).collect();
        Some(Self { width, height, factor })
    }

    /// The factor at raster position `raster` (clamped to the film).
    pub fn factor(&self, raster: Vec2) -> f32 {
        let x = (raster.x.max(0.0) as usize).min(self.width - 1);
        let y = (raster.y.max(0.0) as usize).min(self.height - 1);
        self.factor[y * self.width + x]
    }

    /// The factor of a depth-`k` state whose contribution lands at `raster`: 1 at depth 0 or
    /// without a map.
    pub fn of(map: Option<&Self>, k: usize, raster: Vec2) -> f32 {
        match map {
            Some(m) if k >= 1 => m.factor(raster),
            _ => 1.0,
        }
    }
}

/// Each pixel's `reduce` over its 3×3 neighbourhood (cut at the film's edges), row by row.
pub(crate) fn neighbourhood(width: usize, height: usize, v: &[f32], reduce: impl Fn(&mut Vec<f32>) -> f32) -> Vec<f32> {
    let mut window = Vec::with_capacity(9);
    (0..width * height)
        .map(|j| {
            let (x, y) = (j % width, j / width);
            window.clear();
            for yy in y.saturating_sub(1)..(y + 2).min(height) {
                for xx in x.saturating_sub(1)..(x + 2).min(width) {
                    window.push(v[yy * width + xx]);
                }
            }
            reduce(&mut window)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bright region lowers the map to the inverse of its brightness, and a lone bright pixel
    /// (a glint, or a firefly) lowers it two pixels around; dark pixels get the floor's
    /// factor; depth 0 is left alone.
    #[test]
    fn the_map_follows_bright_regions_and_pixels() {
        let (w, h) = (16, 10);
        let mut lum = vec![1.0f32; w * h];
        lum[w + 5] = 1000.0;
        for y in 0..h {
            for x in 0..w {
                if x >= 12 {
                    lum[y * w + x] = 10.0;
                } else if x < 4 && y >= 5 {
                    lum[y * w + x] = 0.0;
                }
            }
        }
        let map = ImportanceMap::from_pilot(w, h, &lum, 1e-4).unwrap();
        let at = |x: usize, y: usize| map.factor(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        // The floor is far below every lit level here.
        assert!((at(8, 6) - 1.0).abs() < 1e-3, "{}", at(8, 6));
        assert!((at(14, 5) - 0.1).abs() < 1e-3, "{}", at(14, 5));
        // The bright pixel, and a ninth of it two pixels away; three away, nothing.
        assert!(at(5, 1) < 0.0011, "{}", at(5, 1));
        assert!((at(7, 3) * (1008.0 / 9.0) - 1.0).abs() < 1e-3, "{}", at(7, 3));
        assert!((at(8, 4) - 1.0).abs() < 1e-3, "{}", at(8, 4));
        // Dark pixels two from any light: the floor's factor, finite and the largest.
        assert!(at(0, 9).is_finite() && at(0, 9) > 100.0, "{}", at(0, 9));
        let floored = ImportanceMap::from_pilot(w, h, &lum, 0.05).unwrap();
        let f = |x: usize, y: usize| floored.factor(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        assert!(f(0, 9) > f(8, 6) && f(8, 6) < at(8, 6) && f(0, 9) < 1.0, "{} {}", f(0, 9), f(8, 6));
        // Positions outside the film clamp to its edge.
        assert_eq!(map.factor(Vec2::new(-3.0, 100.0)), at(0, h - 1));
        assert_eq!(ImportanceMap::of(Some(&map), 0, Vec2::new(10.5, 4.5)), 1.0);
        assert_eq!(ImportanceMap::of(None, 3, Vec2::new(10.5, 4.5)), 1.0);
        assert_eq!(ImportanceMap::of(Some(&map), 3, Vec2::new(10.5, 4.5)), at(10, 4));
        // No light, a wrong size or no floor: no map.
        assert!(ImportanceMap::from_pilot(w, h, &vec![0.0; w * h], 0.1).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum[1..], 0.1).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum, 0.0).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum, f64::NAN).is_none());
    }
}
