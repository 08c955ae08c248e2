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
//! each pixel's value averaged over the smallest square around it that holds
//! [`WINDOW_SAMPLES`] of the pilot's samples (the pixel alone at 16 samples per pixel, 3×3 at
//! 2–15, 5×5 at one), then per pixel the largest value of its 3×3 neighbourhood, averaged over
//! the 3×3 neighbourhood again. `φ` is `floor` times the pilot's mean. The map errs towards
//! bright: a pixel the pilot overestimates gets fewer mutations than it should, and only its
//! own noise grows; one it underestimates (a glint the pilot missed) gets a target far above
//! its neighbours', where the chains that find it stay and pile up its light, and the depth's
//! normalisation, a mean of `g`, gets the heavier tail. Depth 0 (the emitters seen directly)
//! keeps MMLT's target: each depth's chains and normalisation are their own, so every depth
//! may have its own positive target.
//!
//! The model's variance, `Ī_p²/n_p`, is that of independent samples. A chain's states are not:
//! where a depth's light comes from a few narrow paths (a caustic seen through glass) the
//! chains that find one stay on it for many mutations, and the full shape, which gives a
//! moderately lit pixel nearly the brightest pixels' share, raises such paths' share of the
//! chains' time with it. A power `γ` softens the shape: `g = f/ψ^γ`, so that
//! `n_p ∝ Ī_p/ψ_p^γ`: `γ = 1` is the shape above, `γ = 0` MMLT's target, and between them
//! bright pixels keep part of MMLT's share (README, "A softer shape").

use crate::math::Vec2;

/// The floor `φ` over the pilot image's mean unless the render says otherwise.
pub const DEFAULT_FLOOR: f64 = 0.5;

/// The power `γ` of the shape `ψ^γ` unless the render says otherwise.
pub const DEFAULT_POWER: f64 = 0.75;

/// The pilot's samples each pixel's value is first averaged over, at least: its own where the
/// pilot took this many per pixel, its neighbours' too where it took fewer.
pub const WINDOW_SAMPLES: u32 = 16;

/// The `ε` of relMSE, `(I − R)²/(R² + ε)`, in the model of [`ImportanceMap::predicted_ratio`].
pub const RELMSE_EPSILON: f64 = 0.01;

/// The factor `1/ψ(p)` a depth `k ≥ 1` state's value is multiplied by, per pixel.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportanceMap {
    width: usize,
    height: usize,
    factor: Vec<f32>,
    /// [`Self::predicted_ratio`].
    predicted: f64,
}

impl ImportanceMap {
    /// The map for a pilot image's pixel luminances (`width × height`, row by row) from `spp`
    /// samples per pixel, with the floor `φ = floor · mean` and the factors `1/ψ^power`; `None`
    /// if the pilot saw no light (or `floor` is not positive, or `power` not finite and
    /// positive, or a factor would not be a finite positive `f32`).
    pub fn from_pilot(
        width: usize,
        height: usize,
        luminance: &[f32],
        spp: u32,
        floor: f64,
        power: f64,
    ) -> Option<Self> {
        let bad = |v: f64| !(v > 0.0 && v.is_finite());
        if width == 0 || height == 0 || luminance.len() != width * height || bad(floor) || bad(power) {
            return None;
        }
        let clean: Vec<f32> = luminance.iter().map(|&y| if y.is_finite() && y > 0.0 { y } else { 0.0 }).collect();
        let mean = |v: &mut Vec<f32>| v.iter().sum::<f32>() / v.len() as f32;
        let radius = window_radius(spp);
        let denoised = if radius == 0 { clean } else { neighbourhood(width, height, &clean, radius, mean) };
        let largest = neighbourhood(width, height, &denoised, 1, |v| v.iter().copied().fold(0.0, f32::max));
        let smooth = neighbourhood(width, height, &largest, 1, mean);
        let mean = smooth.iter().map(|&y| f64::from(y)).sum::<f64>() / smooth.len() as f64;
        let phi = floor * mean;
        if !(phi > 0.0 && phi.is_finite()) {
            return None;
        }
        let psi = |y: f32| (f64::from(y).powi(2) + phi * phi).sqrt();
        let full: Vec<f32> = smooth.iter().map(|&y| (1.0 / psi(y)) as f32).collect();
        let predicted = predicted_ratio(&smooth, &full);
        let factor = if power == 1.0 { full } else { smooth.iter().map(|&y| psi(y).powf(-power) as f32).collect() };
        // A very dim image's factors may leave `f32`'s range (above all for `γ > 1`): no map.
        if !factor.iter().all(|&f| f.is_finite() && f > 0.0) {
            return None;
        }
        Some(Self { width, height, factor, predicted })
    }

    /// The relMSE of chains under the full shape (`γ = 1`, whatever the map's power) over that
    /// of MMLT's chains, as the model of the module's documentation predicts it from the map's
    /// own brightness `Ī`, a measure of how uneven the image is: with `n_p ∝ Ī_p/ψ_p`
    /// mutations (MMLT: `n_p ∝ Ī_p`) and per-pixel variance `Ī_p²/n_p`, relMSE is proportional to
    /// `Σ_p (Ī_p/ψ_p) · Σ_p Ī_p ψ_p/(Ī_p² + ε)` (MMLT: `Σ_p Ī_p · Σ_p Ī_p/(Ī_p² + ε)`), `ε` being
    /// relMSE's [`RELMSE_EPSILON`] in the image's units. Near 1 where the image's brightness is
    /// even (the shaping has little to move), small where most pixels are far dimmer than a few.
    pub fn predicted_ratio(&self) -> f64 {
        self.predicted
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

/// [`ImportanceMap::predicted_ratio`] for the smoothed brightness `bright` and the factors
/// `1/ψ`; 1 (no gain) where the image is black.
fn predicted_ratio(bright: &[f32], factor: &[f32]) -> f64 {
    let (mut shaped_n, mut shaped_v, mut plain_n, mut plain_v) = (0.0, 0.0, 0.0, 0.0);
    for (&y, &f) in bright.iter().zip(factor) {
        let (y, psi) = (f64::from(y), 1.0 / f64::from(f));
        let weight = y / (y * y + RELMSE_EPSILON);
        shaped_n += y / psi;
        shaped_v += weight * psi;
        plain_n += y;
        plain_v += weight;
    }
    let ratio = shaped_n * shaped_v / (plain_n * plain_v);
    if ratio.is_finite() && ratio > 0.0 { ratio } else { 1.0 }
}

/// The radius of the square window whose pixels hold [`WINDOW_SAMPLES`] of a pilot's `spp`
/// samples per pixel.
fn window_radius(spp: u32) -> usize {
    (0..)
        .find(|&r: &usize| ((2 * r + 1).pow(2) as u64) * u64::from(spp.max(1)) >= u64::from(WINDOW_SAMPLES))
        .unwrap_or(0)
}

/// Each pixel's `reduce` over its `(2·radius + 1)²` neighbourhood (cut at the film's edges),
/// row by row.
pub(crate) fn neighbourhood(
    width: usize,
    height: usize,
    v: &[f32],
    radius: usize,
    reduce: impl Fn(&mut Vec<f32>) -> f32,
) -> Vec<f32> {
    let mut window = Vec::with_capacity((2 * radius + 1).pow(2));
    (0..width * height)
        .map(|j| {
            let (x, y) = (j % width, j / width);
            window.clear();
            for yy in y.saturating_sub(radius)..(y + radius + 1).min(height) {
                for xx in x.saturating_sub(radius)..(x + radius + 1).min(width) {
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
        let map = ImportanceMap::from_pilot(w, h, &lum, 16, 1e-4, 1.0).unwrap();
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
        let floored = ImportanceMap::from_pilot(w, h, &lum, 16, 0.05, 1.0).unwrap();
        let f = |x: usize, y: usize| floored.factor(Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        assert!(f(0, 9) > f(8, 6) && f(8, 6) < at(8, 6) && f(0, 9) < 1.0, "{} {}", f(0, 9), f(8, 6));
        // Positions outside the film clamp to its edge.
        assert_eq!(map.factor(Vec2::new(-3.0, 100.0)), at(0, h - 1));
        assert_eq!(ImportanceMap::of(Some(&map), 0, Vec2::new(10.5, 4.5)), 1.0);
        assert_eq!(ImportanceMap::of(None, 3, Vec2::new(10.5, 4.5)), 1.0);
        assert_eq!(ImportanceMap::of(Some(&map), 3, Vec2::new(10.5, 4.5)), at(10, 4));
        // No light, a wrong size or no floor: no map.
        assert!(ImportanceMap::from_pilot(w, h, &vec![0.0; w * h], 16, 0.1, 1.0).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum[1..], 16, 0.1, 1.0).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum, 16, 0.0, 1.0).is_none());
        assert!(ImportanceMap::from_pilot(w, h, &lum, 16, f64::NAN, 1.0).is_none());
        for power in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(ImportanceMap::from_pilot(w, h, &lum, 16, 0.1, power).is_none(), "{power}");
        }
    }

    /// A power `γ` takes the `γ`-th power of every factor, so a factor ten times another's is
    /// about three times it at `γ = 1/2`; the prediction, the full shape's, does not change; a
    /// pilot so dim that its factors would leave `f32`'s range gives no map.
    #[test]
    fn a_power_softens_the_map() {
        let (w, h) = (40, 30);
        let lum: Vec<f32> = (0..w * h).map(|j| if j % w < 4 { 100.0 } else { 1.0 + (j % 7) as f32 }).collect();
        let full = ImportanceMap::from_pilot(w, h, &lum, 16, 0.05, 1.0).unwrap();
        let soft = ImportanceMap::from_pilot(w, h, &lum, 16, 0.05, 0.5).unwrap();
        assert_eq!(full.predicted_ratio(), soft.predicted_ratio());
        for (x, y) in [(0, 0), (2, 10), (4, 4), (5, 29), (20, 15), (39, 3)] {
            let p = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let (f, s) = (full.factor(p), soft.factor(p));
            assert!((s / f.sqrt() - 1.0).abs() < 1e-5, "({x}, {y}): {s} vs sqrt {f}");
        }
        let (bright, dim) = (Vec2::new(1.5, 12.5), Vec2::new(30.5, 12.5));
        let ratio = |m: &ImportanceMap| m.factor(dim) / m.factor(bright);
        assert!(ratio(&full) > 10.0 && ratio(&soft) > 3.0 && ratio(&soft) < 0.5 * ratio(&full));
        let dim: Vec<f32> = lum.iter().map(|&y| y * 1e-30).collect();
        assert!(ImportanceMap::from_pilot(w, h, &dim, 16, 1e-3, 1.0).is_some());
        assert!(ImportanceMap::from_pilot(w, h, &dim, 16, 1e-3, 2.0).is_none());
    }

    /// A pilot of fewer samples per pixel is averaged over neighbours first: a lone bright
    /// pixel of a one-sample pilot (a firefly as likely as a glint) lowers the map around it by
    /// far less than the same pixel of a sixteen-sample pilot.
    #[test]
    fn sparse_pilots_are_averaged_first() {
        assert_eq!([16, 40, 15, 4, 2, 1, 0].map(window_radius), [0, 0, 1, 1, 1, 2, 2]);
        let (w, h) = (16, 10);
        let mut lum = vec![1.0f32; w * h];
        lum[4 * w + 8] = 1000.0;
        let dense = ImportanceMap::from_pilot(w, h, &lum, 16, 1e-4, 1.0).unwrap();
        let sparse = ImportanceMap::from_pilot(w, h, &lum, 1, 1e-4, 1.0).unwrap();
        let at = |m: &ImportanceMap| m.factor(Vec2::new(8.5, 4.5));
        assert!(at(&dense) < 0.0011, "{}", at(&dense));
        // 5×5 mean (1000 + 24)/25 ≈ 41, its largest neighbour and their mean: about 1/41.
        assert!(at(&sparse) > 0.02 && at(&sparse) < 0.03, "{}", at(&sparse));
        // Far from it both maps are the background's.
        let far = Vec2::new(0.5, 9.5);
        assert!((dense.factor(far) - 1.0).abs() < 1e-3 && (sparse.factor(far) - 1.0).abs() < 1e-3);
    }

    /// The predicted gain: none on an evenly lit image; large where a few pixels are far
    /// brighter than the rest (the model's ratio for a tenth of the pixels 100 times brighter
    /// and a floor far below both levels is about 0.10); a brighter floor predicts less.
    #[test]
    fn the_prediction_follows_the_dynamic_range() {
        let (w, h) = (40, 30);
        let even = ImportanceMap::from_pilot(w, h, &vec![0.7; w * h], 16, 0.5, 1.0).unwrap();
        assert!((even.predicted_ratio() - 1.0).abs() < 1e-6, "{}", even.predicted_ratio());
        let lum: Vec<f32> = (0..w * h).map(|j| if j % w < 4 { 100.0 } else { 1.0 }).collect();
        let steep = ImportanceMap::from_pilot(w, h, &lum, 16, 1e-3, 1.0).unwrap();
        let (b, d) = (100.0f64, 1.0f64);
        let (nb, nd) = (0.1, 0.9);
        let weight = |y: f64| y / (y * y + RELMSE_EPSILON);
        let model = (nb + nd) * (nb * b * weight(b) + nd * d * weight(d))
            / ((nb * b + nd * d) * (nb * weight(b) + nd * weight(d)));
        // The 3×3 maximum widens the bright columns by one, which predicts a little more gain.
        assert!((0.10..0.11).contains(&model), "{model}");
        let ratio = steep.predicted_ratio();
        assert!(ratio > 0.6 * model && ratio < 1.05 * model, "{ratio} vs {model}");
        let floored = ImportanceMap::from_pilot(w, h, &lum, 16, 0.5, 1.0).unwrap();
        assert!(floored.predicted_ratio() > steep.predicted_ratio() && floored.predicted_ratio() < 1.0);
    }
}
