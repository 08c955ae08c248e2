//! Choosing a light with probability proportional to its emitted power (pbrt-v4 §12.6.2).

use crate::math::distribution::Distribution1D;

#[derive(Clone, Debug)]
pub struct LightSampler {
    distribution: Distribution1D,
    count: usize,
}

impl LightSampler {
    /// From per-light powers; all-zero powers fall back to uniform selection.
    pub fn new(powers: &[f32]) -> Self {
        Self { distribution: Distribution1D::new(powers), count: powers.len() }
    }

    /// Chooses a light: `(index, probability)`, or `None` when the scene has no lights.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.count == 0 {
            return None;
        }
        let (i, pmf, _) = self.distribution.sample_discrete(u);
        Some((i, pmf))
    }

    /// The interval of `u` in which [`Self::sample`] chooses light `light`.
    pub fn interval(&self, light: usize) -> (f32, f32) {
        self.distribution.cell_interval(light)
    }

    #[inline]
    pub fn pmf(&self, light: usize) -> f32 {
        if self.count == 0 { 0.0 } else { self.distribution.discrete_pdf(light) }
    }
}
