//! How many independent samples a group's chain mutations are worth, measured while the render
//! runs ([`super::driver::ChainSettings::measure_efficiency`]): the ratio of the variance that
//! independent samples of the chains' own density would give to the variance the chains give,
//! the Markov-chain analogue of an effective sample size per sample.
//!
//! A depth's walkers are split in two halves (even and odd indices) that splat into separate
//! buffers. Scaled as the whole image is (`N_pixels · b / M`, `M` the depth's mutations), the
//! halves' sums `E` and `O` are independent, and with `M_e` and `M_o` mutations
//! `E' = E·M/(2M_e)` and `O' = O·M/(2M_o)` both have mean `J/2`, `J = E + O` the depth's image.
//! A chain's variance grows in proportion to its mutations, so their difference estimates the
//! variance of `J` without any assumption on how the chains mix (independent replications):
//!
//! ```text
//! V_chain = Σ_p (E'_p − O'_p)² / ((M/4)·(1/M_e + 1/M_o))
//! ```
//!
//! summed over the pixels, in luminance (the divisor is 1 for halves of equal size). `M` independent samples of the chains' own density
//! `f/b` would splat `N_pixels · b · g(x) / M` through the filter, with `g = lum C/(f + h)`
//! (`g = 1` for MMLT alone, `C` the contribution and `f` its luminance; `h` the level of the
//! independent samples, [`super::hybrid::HybridDepth`]); their variance summed over the pixels is
//!
//! ```text
//! V_iid = (N_pixels² · b² · E_{f/b}[g²] · κ − Σ_p J_p²) / M,
//! ```
//!
//! `κ = E[Σ_q w_q²]` the filter's splat weights' squared sum averaged over a pixel's positions
//! (1 for a box of one pixel), and `Σ_p J_p²` corrected by `V_chain` for the noise in `J`. The
//! expectation under `f/b` comes from the bootstrap, whose samples are uniform:
//! `E_{f/b}[g²] = E[f·g²]/E[f]`. A mutation counts as `e = V_iid / V_chain` independent samples.

use crate::film::{Footprint, SharedSplats};
use crate::math::{Vec2, luminance};

/// The smallest and largest efficiency a measurement may give: a measurement from two halves
/// is noisy, and chains that have not yet met most of their depth's light can look better
/// mixed than they are.
pub const RANGE: (f64, f64) = (1e-4, 1.0);

/// The mean over a pixel's positions (16 × 16 stratified) of the squared splat weights of a
/// splat there, summed over the pixels it reaches, taken at the film's centre.
pub fn filter_energy(footprint: &Footprint) -> f64 {
    let (w, h) = footprint.size();
    let centre = Vec2::new((w / 2) as f32, (h / 2) as f32);
    let n = 16;
    let mut sum = 0.0;
    for i in 0..n * n {
        let at = centre + Vec2::new(((i % n) as f32 + 0.5) / n as f32, ((i / n) as f32 + 0.5) / n as f32);
        footprint.each(at, |_, weight| sum += f64::from(weight) * f64::from(weight));
    }
    sum / (n * n) as f64
}

/// `E_{f/b}[g²]` over the bootstrap's `values` of the target `f`, for chains combined with
/// independent samples at level `level` (0: none), `g = f/(f + h)`. Where the target is
/// clamped, the bootstrap holds the clamped values, and the contributions above the clamp,
/// which splat more than `g`, are counted as `g`: the independent samples' variance comes out
/// low, and with it the efficiency.
pub fn second_moment(values: &[f32], level: f32) -> f64 {
    let (mut fg2, mut sum) = (0.0, 0.0);
    for &v in values.iter().filter(|&&v| v > 0.0) {
        let f = f64::from(v);
        let g = f / (f + f64::from(level));
        fg2 += f * g * g;
        sum += f;
    }
    if sum > 0.0 { fg2 / sum } else { 0.0 }
}

/// One depth's measurement from its halves' buffers (`even`, `odd`: one layer each) and the
/// mutations each half made.
pub struct Halves<'a> {
    pub even: &'a SharedSplats,
    pub odd: &'a SharedSplats,
    pub mutations: (u64, u64),
}

impl Halves<'_> {
    /// The efficiency `e = V_iid / V_chain` of the mutations of a depth with mean `b`,
    /// `E_{f/b}[g²]` `g2` and filter energy `kappa`, within [`RANGE`]; `None` where a half made
    /// no mutations, the halves do not differ or the independent samples' variance comes out
    /// non-positive.
    pub fn efficiency(&self, b: f64, g2: f64, kappa: f64) -> Option<f64> {
        let (chain, squares) = self.difference(b, None)?;
        let (w, h) = (self.even.width, self.even.height);
        let pixels = f64::from(w) * f64::from(h);
        let m = (self.mutations.0 + self.mutations.1) as f64;
        let iid = (pixels * pixels * b * b * g2 * kappa - squares + chain) / m;
        if !(chain > 0.0 && iid > 0.0 && iid.is_finite()) {
            return None;
        }
        Some((iid / chain).clamp(RANGE.0, RANGE.1))
    }

    /// The variance of the depth's image (normalisation `b`) summed over its pixels, each
    /// weighted by `weights` (row by row), as the halves' difference estimates it; `None` where
    /// a half made no mutations or the weights do not fit the image.
    pub fn weighted_variance(&self, b: f64, weights: &[f64]) -> Option<f64> {
        if weights.len() != self.even.width as usize * self.even.height as usize {
            return None;
        }
        self.difference(b, Some(weights)).map(|(chain, _)| chain)
    }

    /// `V_chain` (with each pixel's term weighted by `weights`, if given) and `Σ_p J_p²`.
    fn difference(&self, b: f64, weights: Option<&[f64]>) -> Option<(f64, f64)> {
        let (me, mo) = (self.mutations.0 as f64, self.mutations.1 as f64);
        if me == 0.0 || mo == 0.0 {
            return None;
        }
        let m = me + mo;
        let (w, h) = (self.even.width, self.even.height);
        let pixels = f64::from(w) * f64::from(h);
        let scale = pixels * b / m;
        let (even, odd) = (self.even.image(scale), self.odd.image(scale));
        let (mut chain, mut squares) = (0.0, 0.0);
        for (i, (e, o)) in even.pixels.iter().zip(&odd.pixels).enumerate() {
            let (e, o) = (f64::from(luminance(*e)), f64::from(luminance(*o)));
            let d = e * m / (2.0 * me) - o * m / (2.0 * mo);
            chain += d * d * weights.map_or(1.0, |w| w[i]);
            squares += (e + o) * (e + o);
        }
        chain /= m / 4.0 * (1.0 / me + 1.0 / mo);
        Some((chain, squares))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::film::Filter;
    use crate::math::Rgb;
    use crate::math::rng::Pcg32;

    /// A box of one pixel has energy 1; a wider filter spreads a splat, so less.
    #[test]
    fn filter_energy_of_box_and_gaussian() {
        assert!((filter_energy(&Footprint::pixel(16, 16)) - 1.0).abs() < 1e-9);
        let gaussian = Footprint::new(16, 16, Filter::Gaussian { radius: 1.5, sigma: 0.5 });
        let k = filter_energy(&gaussian);
        assert!(k > 0.1 && k < 0.9, "{k}");
    }

    /// Without a level or clamp, `g = 1`; a level shrinks the values it weighs.
    #[test]
    fn second_moment_follows_the_weights() {
        let values = [0.0, 1.0, 2.0, 4.0];
        assert!((second_moment(&values, 0.0) - 1.0).abs() < 1e-12);
        let with = second_moment(&values, 2.0);
        let expect = (1.0 / 9.0 + 2.0 * 0.25 + 4.0 * (4.0 / 9.0)) / 7.0;
        assert!((with - expect).abs() < 1e-12, "{with} {expect}");
    }

    /// Independent uniform splats of luminance `b` weighted as an iid sampler's are measured at
    /// an efficiency near 1; the same splats repeated in runs of 10 (a chain that moves every
    /// tenth mutation) near 0.1.
    #[test]
    fn independent_splats_measure_one_and_runs_of_ten_a_tenth() {
        let (w, h) = (32u32, 32u32);
        let footprint = std::sync::Arc::new(Footprint::pixel(w, h));
        let measure = |run: usize| {
            let (even, odd) = (SharedSplats::filtered(&footprint), SharedSplats::filtered(&footprint));
            let mut rng = Pcg32::new(7, 1);
            let mutations = 200_000u64;
            // Eight walkers, each `mutations / 8` splats of value 1.
            for walker in 0..8 {
                let buffer = if walker % 2 == 0 { &even } else { &odd };
                let mut at = Vec2::ZERO;
                for i in 0..mutations / 8 {
                    if i.is_multiple_of(run as u64) {
                        at = Vec2::new(rng.next_f32() * w as f32, rng.next_f32() * h as f32);
                    }
                    buffer.add(at, Rgb::new(1.0, 1.0, 1.0));
                }
            }
            let half = mutations / 2;
            Halves { even: &even, odd: &odd, mutations: (half, half) }.efficiency(1.0, 1.0, 1.0).expect("a measurement")
        };
        let one = measure(1);
        assert!((0.7..=1.0).contains(&one), "{one}");
        let tenth = measure(10);
        assert!((0.07..0.14).contains(&tenth), "{tenth}");
    }
}
