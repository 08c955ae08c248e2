//! All-replica reuse (`--reuse-replicas`): instead of replica 0 alone, every replica's current
//! state contributes after each sweep, weighted by the balance heuristic over the replicas'
//! normalised targets. Replica `j` samples `u` with density `f_j(u)/b_j`; with the same number
//! `N` of sweeps for every replica the multi-sample MIS estimator (Veach's balance heuristic)
//! of the image is
//!
//! `I = (1/N) Σ_j Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/b_l`.
//!
//! The weights need only ratios: with any fixed `ρ_l > 0` standing in for `b_l/b_0`,
//! `w_j = (f_j/ρ_j) / Σ_l f_l/ρ_l` still sums to one over the replicas, and
//!
//! `I = Σ_j (b_j/ρ_j) · (1/N) Σ_n C_0(u_jn) / Σ_l f_l(u_jn)/ρ_l`
//!
//! is unbiased whatever `ρ` is; a good `ρ` only lowers the variance. So a state of replica `j`
//! splats `C_0/Σ_l f_l/ρ_l` into layer `j` of its depth, and the driver scales layer `j` by
//! `b_j/ρ_j · N_pixels/M`, with `b_j` refined like MMLT's `b_k`: the mean of `f_j` over the
//! depth's bootstrap and replica `j`'s large-step proposals (uniform samples, whichever
//! replica slot they are made in). Each `b_j` enters the image linearly, so its estimation
//! error averages out instead of biasing the image, as MMLT's `b_k` does. (Scaling every layer
//! by the refined `b_0`, with the ratios from the bootstrap alone, makes the image depend on
//! the bootstrap's `Σ f_l / Σ f_0` through the weights' normalisation, a bias that does not
//! shrink with the render's length.)
//!
//! The estimator also assumes each replica's states follow its own target. Replicas that
//! started from replica 0's distribution did not yet at short budgets, which biased short
//! renders bright (see the README); every replica now restarts from the bootstrap in proportion to
//! its own target once the ladder is frozen (see `Ensemble::restart`).
//!
//! The ratios are estimated per depth once the depth's shared ladder is frozen, from the
//! depth's bootstrap samples (the same uniform primary samples that estimate `b_0`) evaluated
//! again under replica 0's target and cross-evaluated (no rays) under the others:
//! `ρ_l = Σ_i f_l(u_i) / Σ_i f_0(u_i)`; the same sums start the `b_l`.

use super::calibration::Calibration;
use crate::mcmc::{Moments, TemperedState, TemperedTarget};

/// The replicas' normalisation ratios `ρ_l ≈ b_l/b_0` of one depth (the weights), and the
/// moments of each replica's target over the depth's bootstrap.
#[derive(Clone, Debug, PartialEq)]
pub struct Reuse {
    pub ratios: Vec<f64>,
    pub bootstrap: Vec<Moments>,
}

impl Reuse {
    /// The ratios and bootstrap moments from the depth's calibration. Sums are taken in sample
    /// order: the same at any thread count.
    pub fn new(calibration: &Calibration, replicas: usize) -> Reuse {
        let mut bootstrap = vec![Moments::default(); replicas];
        for v in &calibration.values {
            // Every sample counts, also those replica 0 values at zero: a roughened lobe can
            // give them value under the other targets.
            for (m, &x) in bootstrap.iter_mut().zip(v) {
                m.push(f64::from(x));
            }
        }
        // Without light in the samples (or for a replica that saw none) the ratios stay 1: the
        // weights remain a partition of unity, only less well balanced.
        let s0 = bootstrap[0].sum;
        let ratios = bootstrap.iter().map(|m| if s0 > 0.0 && m.sum > 0.0 { m.sum / s0 } else { 1.0 }).collect();
        Reuse { ratios, bootstrap }
    }

    /// The splat scale `1 / Σ_l f_l(u)/ρ_l` of `state` (0 where every target vanishes). The
    /// values are cached in the state (the ladder is frozen by now), so a state that stays
    /// (a rejected proposal) or moves to another replica is not evaluated again.
    pub fn scale(&self, targets: &[TemperedTarget], state: &mut TemperedState) -> f32 {
        let sum = self.mixture(targets, state);
        if sum > 0.0 && sum.is_finite() { (1.0 / sum) as f32 } else { 0.0 }
    }

    /// `Σ_l f_l(u)/ρ_l` at `state`: the balance heuristic's denominator, and the target of a
    /// mixture chain ([`super::mixture`]).
    pub fn mixture(&self, targets: &[TemperedTarget], state: &mut TemperedState) -> f64 {
        let mut sum = 0.0f64;
        for (l, rho) in self.ratios.iter().enumerate().take(targets.len()) {
            sum += f64::from(state.value_under(l, targets)) / rho;
        }
        sum
    }
}
