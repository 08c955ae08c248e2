//! All-replica reuse (`--reuse-replicas`): instead of replica 0 alone, every replica's current
//! state contributes after each sweep, weighted by the balance heuristic over the replicas'
//! normalised targets. Replica `j` samples `u` with density `f_j(u)/b_j`; with the same number
//! `N` of sweeps for every replica the multi-sample MIS estimator (Veach's balance heuristic)
//! of the image is
//!
//! `I = (1/N) Σ_j Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/b_l = (b_0/N) Σ_j Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/ρ_l`
//!
//! with `ρ_l = b_l/b_0`, so a state splats `C_0/Σ_l f_l/ρ_l` and the driver's usual scale
//! `b_0·N_pixels/M` (with the refined `b_0`) applies. The ratios are estimated per ensemble
//! once its ladder is frozen, from fresh uniform primary samples evaluated under replica 0's
//! target and cross-evaluated (no rays) under the others: `ρ_l = Σ_i f_l(u_i) / Σ_i f_0(u_i)`.
//! A wrong `ρ_l` scales replica `l`'s share of the estimate, so the calibration needs enough
//! samples (by default as many per ensemble as the bootstrap spends per chain).

use crate::math::rng::hash;
use crate::mcmc::{Paths, Target, TemperedState, TemperedTarget};
use crate::sampler::PssSampler;

/// The replicas' normalisation ratios `ρ_l = b_l/b_0` of one ensemble.
#[derive(Clone, Debug, PartialEq)]
pub struct Reuse {
    pub ratios: Vec<f64>,
}

/// What a calibration needs to draw its samples.
#[derive(Clone, Copy, Debug)]
pub struct Calibration {
    pub seed: u64,
    pub depth: usize,
    pub ensemble: usize,
    pub samples: usize,
    pub sigma: f32,
    pub large_step_probability: f32,
}

impl Reuse {
    /// Estimates the ratios from `plan.samples` uniform states; returns them with the rays traced.
    pub fn calibrate(targets: &[TemperedTarget], plan: &Calibration) -> (Reuse, u64) {
        let k = targets.len();
        let mut sums = vec![0.0f64; k];
        let (mut state, mut paths, mut rays) = (TemperedState::default(), Paths::default(), 0);
        for i in 0..plan.samples {
            let seed = hash(&[plan.seed, 0xca1b, plan.depth as u64, plan.ensemble as u64, i as u64]);
            let mut sampler = PssSampler::new(seed, plan.depth as u64, plan.sigma, plan.large_step_probability);
            targets[0].evaluate(&mut sampler, &mut paths, &mut rays, &mut state);
            if state.value <= 0.0 {
                continue;
            }
            for (sum, target) in sums.iter_mut().zip(targets) {
                *sum += f64::from(target.value_of(&mut state));
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
