//! Piecewise-constant 1D and 2D distributions for importance sampling tabulated functions
//! (pbrt-v4 §A.4.1–A.4.2): light selection by power and environment-map sampling.

use super::Vec2;

/// A piecewise-constant density on `[0, 1)` (or a discrete distribution over its cells).
#[derive(Clone, Debug)]
pub struct Distribution1D {
    func: Vec<f32>,
    cdf: Vec<f64>,
    integral: f64,
}

impl Distribution1D {
    /// Builds from non-negative cell values. All-zero (or empty) input gives a uniform density.
    pub fn new(values: &[f32]) -> Self {
        let func: Vec<f32> = if values.is_empty() {
            vec![1.0]
        } else {
            values.iter().map(|&v| if v.is_finite() { v.max(0.0) } else { 0.0 }).collect()
        };
        let n = func.len();
        let mut cdf = Vec::with_capacity(n + 1);
        cdf.push(0.0);
        for (i, &f) in func.iter().enumerate() {
            cdf.push(cdf[i] + f64::from(f) / n as f64);
        }
        let mut integral = cdf[n];
        let func = if integral > 0.0 {
            func
        } else {
            for (i, c) in cdf.iter_mut().enumerate() {
                *c = i as f64 / n as f64;
            }
            integral = 1.0;
            vec![1.0; n]
        };
        for c in cdf.iter_mut() {
            *c /= integral;
        }
        cdf[n] = 1.0;
        Self { func, cdf, integral }
    }

    pub fn len(&self) -> usize {
        self.func.len()
    }

    pub fn is_empty(&self) -> bool {
        self.func.is_empty()
    }

    /// Integral of the input function over `[0, 1)`.
    pub fn integral(&self) -> f64 {
        self.integral
    }

    fn find_cell(&self, u: f64) -> usize {
        let idx = self.cdf.partition_point(|&c| c <= u);
        idx.saturating_sub(1).min(self.func.len() - 1)
    }

    /// Samples a cell index; returns `(index, probability, u remapped to [0,1) within the cell)`.
    pub fn sample_discrete(&self, u: f32) -> (usize, f32, f32) {
        let u = f64::from(u);
        let i = self.find_cell(u);
        let width = self.cdf[i + 1] - self.cdf[i];
        let remapped = if width > 0.0 { ((u - self.cdf[i]) / width) as f32 } else { 0.0 };
        (i, width as f32, remapped.clamp(0.0, 1.0 - f32::EPSILON))
    }

    /// The interval of `u` in which [`Self::sample_discrete`] chooses cell `i`.
    pub fn cell_interval(&self, i: usize) -> (f32, f32) {
        (self.cdf[i] as f32, self.cdf[i + 1] as f32)
    }

    /// Probability of choosing cell `i` in [`Self::sample_discrete`].
    pub fn discrete_pdf(&self, i: usize) -> f32 {
        (self.cdf[i + 1] - self.cdf[i]) as f32
    }

    /// Samples a continuous position in `[0, 1)`; returns `(x, density, cell index)`.
    pub fn sample_continuous(&self, u: f32) -> (f32, f32, usize) {
        let (i, _, du) = self.sample_discrete(u);
        let n = self.func.len();
        let x = ((i as f32 + du) / n as f32).min(1.0 - f32::EPSILON);
        let pdf = (f64::from(self.func[i]) / self.integral) as f32;
        (x, pdf, i)
    }

    /// Density at `x ∈ [0, 1)` of [`Self::sample_continuous`].
    pub fn pdf(&self, x: f32) -> f32 {
        let n = self.func.len();
        let i = ((x * n as f32) as usize).min(n - 1);
        (f64::from(self.func[i]) / self.integral) as f32
    }
}

/// A piecewise-constant density on `[0,1)²`, stored row-major (`v` selects the row).
#[derive(Clone, Debug)]
pub struct Distribution2D {
    conditionals: Vec<Distribution1D>,
    marginal: Distribution1D,
}

impl Distribution2D {
    pub fn new(values: &[f32], width: usize, height: usize) -> Self {
        assert_eq!(values.len(), width * height, "distribution size mismatch");
        let conditionals: Vec<_> = values.chunks(width).map(Distribution1D::new).collect();
        let row_integrals: Vec<f32> = conditionals
            .iter()
            .zip(values.chunks(width))
            .map(|(c, row)| if row.iter().any(|&v| v > 0.0) { c.integral() as f32 } else { 0.0 })
            .collect();
        let marginal = Distribution1D::new(&row_integrals);
        Self { conditionals, marginal }
    }

    /// Samples `(u, v)` in the unit square and returns it with its density.
    pub fn sample(&self, u: Vec2) -> (Vec2, f32) {
        let (v, pdf_v, row) = self.marginal.sample_continuous(u.y);
        let (x, pdf_u, _) = self.conditionals[row].sample_continuous(u.x);
        (Vec2::new(x, v), pdf_u * pdf_v)
    }

    pub fn pdf(&self, p: Vec2) -> f32 {
        let h = self.conditionals.len();
        let row = ((p.y * h as f32) as usize).min(h - 1);
        self.marginal.pdf(p.y) * self.conditionals[row].pdf(p.x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    #[test]
    fn discrete_frequencies_match_values() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0, 4.0]);
        let mut counts = [0usize; 4];
        let mut rng = Pcg32::new(5, 1);
        let n = 80_000;
        for _ in 0..n {
            let (i, p, r) = d.sample_discrete(rng.next_f32());
            assert!((0.0..1.0).contains(&r));
            assert!((p - d.discrete_pdf(i)).abs() < 1e-6);
            counts[i] += 1;
        }
        assert_eq!(counts[1], 0);
        for (i, want) in [(0, 0.125), (2, 0.375), (3, 0.5)] {
            let got = counts[i] as f64 / f64::from(n);
            assert!((got - want).abs() < 0.01, "cell {i}: {got} vs {want}");
        }
    }

    #[test]
    fn continuous_pdf_integrates_to_one_and_matches_sampling() {
        let d = Distribution2D::new(&[1.0, 2.0, 0.0, 5.0, 1.0, 1.0], 3, 2);
        let mut rng = Pcg32::new(9, 2);
        for _ in 0..1000 {
            let (p, pdf) = d.sample(Vec2::new(rng.next_f32(), rng.next_f32()));
            assert!(pdf > 0.0);
            assert!((d.pdf(p) - pdf).abs() < 1e-4 * pdf);
        }
        let mut integral = 0.0;
        let n = 300;
        for i in 0..n {
            for j in 0..n {
                let p = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                integral += d.pdf(p) as f64;
            }
        }
        assert!((integral / f64::from(n * n) - 1.0).abs() < 1e-3);
    }

    #[test]
    fn all_zero_input_is_uniform() {
        let d = Distribution1D::new(&[0.0, 0.0]);
        assert_eq!(d.discrete_pdf(0), 0.5);
    }
}
