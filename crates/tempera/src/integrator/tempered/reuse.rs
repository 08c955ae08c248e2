//! All-replica reuse (`--reuse-replicas`): instead of replica 0 alone, every replica's current
//! state contributes after each sweep, weighted by the balance heuristic over the replicas'
//! normalised targets. Replica `j` samples `u` with density `f_j(u)/b_j`; with the same number
//! `N` of sweeps for every replica the multi-sample MIS estimator (Veach's balance heuristic)
//! of the image is
//!
//! `I = (1/N) Σ_j Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/b_l = (b_0/N) Σ_j Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/ρ_l`
//!
//! with `ρ_l = b_l/b_0`, so a state splats `C_0/Σ_l f_l/ρ_l` and the driver's usual scale
//! `b_0·N_pixels/M` (with the refined `b_0`) applies. The ratios are estimated per depth once
//! the depth's shared ladder is frozen, from the depth's bootstrap samples (the same uniform
//! primary samples that estimate `b_0`) evaluated again under replica 0's target and
//! cross-evaluated (no rays) under the others: `ρ_l = Σ_i f_l(u_i) / Σ_i f_0(u_i)`. A wrong
//! `ρ_l` scales replica `l`'s share of the estimate, which is why every bootstrap sample serves.

use crate::integrator::mmlt::{GroupContext, sampler_for};
use crate::mcmc::{Paths, Target, TemperedState, TemperedTarget};
use rayon::prelude::*;

/// The replicas' normalisation ratios `ρ_l = b_l/b_0` of one depth.
#[derive(Clone, Debug, PartialEq)]
pub struct Reuse {
    pub ratios: Vec<f64>,
}

impl Reuse {
    /// Estimates the ratios from the first `samples` bootstrap samples of the group; returns
    /// them with the rays traced. Sums are taken in sample order: the same at any thread count.
    pub(in crate::integrator) fn calibrate(
        targets: &[TemperedTarget],
        group: &GroupContext,
        samples: usize,
    ) -> (Reuse, u64) {
        let k = targets.len();
        let values: Vec<(Vec<f64>, u64)> = (0..samples)
            .into_par_iter()
            .map_init(
                || (TemperedState::default(), Paths::default()),
                |(state, paths), i| {
                    let mut sampler = sampler_for(group.seed, group.k, i, group.settings);
                    let mut rays = 0;
                    targets[0].evaluate(&mut sampler, paths, &mut rays, state);
                    // Every sample counts, also those replica 0 values at zero: a roughened
                    // lobe can give them value under the other targets.
                    (targets.iter().map(|t| f64::from(t.value_of(state))).collect(), rays)
                },
            )
            .collect();
        let mut sums = vec![0.0f64; k];
        let mut rays = 0;
        for (v, r) in &values {
            rays += r;
            for (sum, x) in sums.iter_mut().zip(v) {
                *sum += x;
            }
        }
        // Without light in the samples (or for a replica that saw none) the ratios stay 1: the
        // weights remain a partition of unity, only less well balanced.
        let ratios = sums.iter().map(|&s| if sums[0] > 0.0 && s > 0.0 { s / sums[0] } else { 1.0 }).collect();
        (Reuse { ratios }, rays)
    }

    /// The splat scale `1 / Σ_l f_l(u)/ρ_l` of `state` (0 where every target vanishes). The
    /// values are cached in the state (the ladder is frozen by now), so a state that stays
    /// (a rejected proposal) or moves to another replica is not evaluated again.
    pub fn scale(&self, targets: &[TemperedTarget], state: &mut TemperedState) -> f32 {
        if state.cross.len() != targets.len() {
            state.cross.clear();
            state.cross.resize(targets.len(), f32::NAN);
        }
        let mut sum = 0.0f64;
        for (l, (target, rho)) in targets.iter().zip(&self.ratios).enumerate() {
            let mut v = state.cross[l];
            if v.is_nan() {
                v = target.value_of(state);
                state.cross[l] = v;
            }
            sum += f64::from(v) / rho;
        }
        if sum > 0.0 && sum.is_finite() { (1.0 / sum) as f32 } else { 0.0 }
    }
}
