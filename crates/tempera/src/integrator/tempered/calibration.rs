//! A depth's bootstrap valued under every replica's target once its ladder is frozen: the
//! replicas restart from it in proportion to their own targets, and all-replica reuse takes
//! its ratios `ρ_l` and the bootstrap part of each `b_l` from it. The samples are the ones
//! that estimated `b_0` (the same seeds), traced again under replica 0's target and
//! cross-evaluated, without rays, under the others.

use crate::mcmc::bootstrap::Scratch;
use crate::mcmc::{GroupContext, TemperedTarget, sampler_for, target_value};
use rayon::prelude::*;

/// The depth's bootstrap samples valued under every replica's target once the ladder is
/// frozen: `values[i][l] = f_l(u_i)`.
pub struct Calibration {
    pub values: Vec<Vec<f32>>,
}

impl Calibration {
    /// Evaluates the first `samples` bootstrap samples of the group under replica 0's target
    /// and cross-evaluates them (no rays) under the others; returns them with the rays traced.
    pub fn new(targets: &[TemperedTarget], group: &GroupContext, samples: usize) -> (Self, u64) {
        let evaluated: Vec<(Vec<f32>, u64)> = (0..samples)
            .into_par_iter()
            .map_init(Scratch::default, |scratch, i| {
                let sampler = sampler_for(group.seed, group.k, i, group.settings);
                let (state, rays) = scratch.evaluate(&targets[0], sampler);
                (targets.iter().map(|t| target_value(t.value_of(state))).collect(), rays)
            })
            .collect();
        let rays = evaluated.iter().map(|e| e.1).sum();
        (Self { values: evaluated.into_iter().map(|e| e.0).collect() }, rays)
    }

    /// The values under the targets `targets` (indices) only, in that order.
    pub fn select(&self, targets: &[usize]) -> Calibration {
        Calibration { values: self.values.iter().map(|v| targets.iter().map(|&l| v[l]).collect()).collect() }
    }

    /// Replica `l`'s values over the samples.
    pub fn of(&self, l: usize) -> Vec<f32> {
        self.values.iter().map(|v| v[l]).collect()
    }
}
