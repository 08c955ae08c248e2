//! Pixel reconstruction filters (pbrt-v4 §8.8): box, triangle (tent) and truncated Gaussian,
//! applied as weighted averages `Σ w·L / Σ w` per pixel.

/// A separable reconstruction filter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    Box { radius: f32 },
    Triangle { radius: f32 },
    Gaussian { radius: f32, sigma: f32 },
}

impl Default for Filter {
    fn default() -> Self {
        Filter::Box { radius: 0.5 }
    }
}

fn gaussian(x: f32, sigma: f32) -> f32 {
    (-x * x / (2.0 * sigma * sigma)).exp()
}

impl Filter {
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box { radius } | Filter::Triangle { radius } | Filter::Gaussian { radius, .. } => radius,
        }
    }

    /// The separable profile: the weight at offset `x` along one axis.
    pub fn eval_1d(&self, x: f32) -> f32 {
        match *self {
            Filter::Box { radius } => {
                if x.abs() <= radius {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Triangle { radius } => (radius - x.abs()).max(0.0),
            Filter::Gaussian { radius, sigma } => (gaussian(x, sigma) - gaussian(radius, sigma)).max(0.0),
        }
    }

    /// Weight of a sample at offset `(dx, dy)` from a pixel centre.
    #[inline]
    pub fn eval(&self, dx: f32, dy: f32) -> f32 {
        self.eval_1d(dx) * self.eval_1d(dy)
    }
}
