//! The bootstrap of a group of chains (MMLT: one path depth; Veach 1997 §11.3.1, pbrt-v4
//! §13.4.4): independent uniform samples of the group's target. Their mean is the
//! normalisation `b`, and chains start from them in proportion to their value, which removes
//! start-up bias. Sample `i` of group `k` always has the same seed, so whoever needs the same
//! samples again (tempering's calibration) evaluates them again.

use super::driver::ChainSettings;
use super::{EvalContext, Moments, State, Target};
use crate::bidir::Paths;
use crate::math::distribution::Distribution1D;
use crate::math::rng::hash;
use crate::sampler::PssSampler;
use rayon::prelude::*;

/// Seed of bootstrap sample `i` of group `k`.
fn bootstrap_seed(seed: u64, k: usize, i: usize) -> u64 {
    hash(&[seed, 0xb007, k as u64, i as u64])
}

/// The sampler holding bootstrap sample `i` of group `k` (a chain started from it mutates it).
pub fn sampler_for(seed: u64, k: usize, i: usize, settings: &ChainSettings) -> PssSampler {
    PssSampler::new(bootstrap_seed(seed, k, i), k as u64, settings.sigma, settings.large_step_probability)
}

/// Per-thread storage for evaluating independent samples one after the other.
pub struct Scratch<S> {
    paths: Paths,
    state: S,
}

impl<S: State> Default for Scratch<S> {
    fn default() -> Self {
        Self { paths: Paths::default(), state: S::default() }
    }
}

impl<S: State> Scratch<S> {
    /// Evaluates the state `sampler` holds under `target`; returns it and the rays traced.
    pub fn evaluate(&mut self, target: &impl Target<State = S>, sampler: PssSampler) -> (&mut S, u64) {
        let mut cx = EvalContext { sampler, paths: std::mem::take(&mut self.paths), rays: 0 };
        self.state = target.evaluate(&mut cx, std::mem::take(&mut self.state));
        self.paths = cx.paths;
        (&mut self.state, cx.rays)
    }
}

/// Samples of a target's own normaliser beside `bootstrap` bootstrap samples: a quarter as
/// many. Its estimates have far less variance than the target's values (that is its point),
/// and at depth `k` each costs about twice the rays of a bootstrap sample.
pub fn normaliser_samples(bootstrap: usize) -> usize {
    bootstrap.div_ceil(4)
}

/// The bootstrap of one group: its samples' target values and their moments.
pub struct Bootstrap {
    pub values: Vec<f32>,
    /// The mean of the values: the group's normalisation before the large steps refine it.
    pub mean: f64,
    pub sum2: f64,
    /// Samples whose value was NaN, infinite or negative.
    pub invalid: u64,
    /// The target's own lower-variance estimator of `b` ([`Target::normaliser`]), combined
    /// with the values' ([`Self::normalisation`]).
    pub normaliser: Option<Moments>,
}

impl Bootstrap {
    /// Evaluates `settings.bootstrap` samples of group `k` in parallel; returns them with the
    /// rays traced.
    pub fn run<T: Target + Sync>(target: &T, settings: &ChainSettings, seed: u64, k: usize) -> (Self, u64) {
        let results: Vec<(f32, bool, u64)> = (0..settings.bootstrap)
            .into_par_iter()
            .map_init(Scratch::default, |scratch, i| {
                let (state, rays) = scratch.evaluate(target, sampler_for(seed, k, i, settings));
                (state.value(), state.invalid(), rays)
            })
            .collect();
        let values: Vec<f32> = results.iter().map(|r| r.0).collect();
        let n = values.len().max(1) as f64;
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let sum2 = values.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>();
        let invalid = results.iter().filter(|r| r.1).count() as u64;
        let mut rays = results.iter().map(|r| r.2).sum();
        let normaliser = target.normaliser(seed, normaliser_samples(settings.bootstrap)).map(|(m, r)| {
            rays += r;
            m
        });
        (Bootstrap { values, mean, sum2, invalid, normaliser }, rays)
    }

    /// The group's normalisation as far as the bootstrap knows it.
    pub fn b(&self) -> f64 {
        self.normalisation(&Moments::default()).0
    }

    /// The group's normalisation `b` and its relative standard error, from the bootstrap and
    /// the large steps' values (`large`), independent uniform samples of the target. Where the
    /// target has its own normaliser, the two independent estimates are combined with weights
    /// inversely proportional to their variances; the values' variance is taken from the
    /// bootstrap alone, so that the weights do not depend on the large steps they weight.
    pub fn normalisation(&self, large: &Moments) -> (f64, f64) {
        let mut plain = self.moments();
        plain.merge(large);
        let Some(normaliser) = self.normaliser else { return plain.mean_and_rel_se() };
        let (a, rel_a) = normaliser.mean_and_rel_se();
        let var_a = (a * rel_a).powi(2);
        let (b, _) = plain.mean_and_rel_se();
        let (boot, rel_boot) = self.moments().mean_and_rel_se();
        // The per-sample variance of the values, over the samples of the plain estimate.
        let var_b = (boot * rel_boot).powi(2) * self.values.len() as f64 / plain.n.max(1) as f64;
        let (mean, var) = if a <= 0.0 {
            // The normaliser saw no light where the values did: theirs is the estimate.
            return plain.mean_and_rel_se();
        } else if b <= 0.0 || var_a == 0.0 {
            return normaliser.mean_and_rel_se();
        } else if var_b == 0.0 {
            (b, 0.0)
        } else {
            ((a * var_b + b * var_a) / (var_a + var_b), var_a * var_b / (var_a + var_b))
        };
        (mean, var.sqrt() / mean)
    }

    /// How unevenly the group's light is spread over the paths that carry it:
    /// `sqrt(E[f²] / E[f]²)` over the bootstrap's non-zero values, from 1 (all equal) up to a
    /// cap of 8. Zeros are left out: a target that is zero on most of primary sample space (a
    /// small light seen directly) is easy for a chain once found.
    pub fn spread(&self) -> f64 {
        let (mut n, mut sum, mut sum2) = (0u64, 0.0f64, 0.0f64);
        for &v in self.values.iter().filter(|&&v| v > 0.0) {
            n += 1;
            sum += f64::from(v);
            sum2 += f64::from(v).powi(2);
        }
        if n == 0 || sum <= 0.0 {
            return 1.0;
        }
        (sum2 * n as f64 / (sum * sum)).sqrt().clamp(1.0, 8.0)
    }

    /// The moments of the values, to be refined with the large steps'.
    pub fn moments(&self) -> Moments {
        let n = self.values.len() as u64;
        Moments { sum: self.mean * n as f64, sum2: self.sum2, n }
    }

    /// The distribution chains draw their start states from: in proportion to the values.
    pub fn starts(&self) -> Distribution1D {
        Distribution1D::new(&self.values)
    }
}
