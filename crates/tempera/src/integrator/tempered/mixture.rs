//! The mixture target (`--swap mixture`): instead of `K` chains, one per replica, exchanging
//! states, one chain samples the mixture of the replicas' normalised targets
//!
//! `m(u) = Σ_l f_l(u)/ρ_l`,
//!
//! with the ratios `ρ_l ≈ b_l/b_0` of all-replica reuse ([`super::reuse`]). This is serial
//! (simulated) tempering (Marinari & Parisi 1992; Geyer & Thompson 1995) with the temperature
//! index summed out of the state: a chain on `(u, l)` with target `f_l(u)/ρ_l` whose marginal
//! over `u` is `m`. Where the main target `f_0` has a valley that a flattened `f_l` fills, `m`
//! has none, so the chain crosses between the main target's modes as a hot replica does, and
//! every proposal costs one path evaluation: `f_l(u)` for `l ≥ 1` reuses the proposal's
//! subpaths and connection (no rays).
//!
//! The chain's states follow `m/b_m`, `b_m = ∫ m = Σ_l b_l/ρ_l`, so splatting `C_0/m` (its
//! untempered contribution over its mixture value, as any [`crate::mcmc::Chain`] on the target
//! `m` splats) with MMLT's expected-value weights and
//! scaling the depth's splats by `N_pixels · b_m / M` estimates the depth's image, for any
//! fixed `ρ` (a good one only lowers the variance). The chain driver ([`crate::mcmc::develop`])
//! computes `b_m` from the low-variance `b_0` and each `b_l`, refined like reuse's with the
//! chain's large steps (independent uniform samples valued under every target). The weight
//! `C_0/m ≤ ρ_0 C_0/f_0` is bounded by MMLT's, so hot components add no fireflies; where the
//! flattened targets carry light the real scene does not, the chain spends part of its time
//! there, splatting little.

use super::Reuse;
use crate::mcmc::{EvalContext, NormaliserMoments, Target, TemperedState, TemperedTarget};

/// The mixture `Σ_l f_l/ρ_l` of a depth's tempered targets, with the ratios of `reuse`.
#[derive(Clone, Copy)]
pub struct MixtureTarget<'t, 'a> {
    pub targets: &'t [TemperedTarget<'a>],
    pub reuse: &'t Reuse,
}

impl MixtureTarget<'_, '_> {
    /// The mixture values of bootstrap samples valued under every target (`values[i][l]`).
    pub fn values(&self, values: &[Vec<f32>]) -> Vec<f32> {
        values
            .iter()
            .map(|v| finite(v.iter().zip(&self.reuse.ratios).map(|(&f, rho)| f64::from(f) / rho).sum()))
            .collect()
    }
}

/// A mixture value as a target value: 0 where the sum overflowed.
fn finite(sum: f64) -> f32 {
    if sum.is_finite() { sum as f32 } else { 0.0 }
}

impl Target for MixtureTarget<'_, '_> {
    type State = TemperedState;

    /// Traces the state under the main target, then values it under the mixture (from its
    /// cached cross-evaluations). Its contribution stays the untempered one.
    fn evaluate(&self, cx: &mut EvalContext, recycled: TemperedState) -> TemperedState {
        let mut state = self.targets[0].evaluate(cx, recycled);
        state.value = finite(self.reuse.mixture(self.targets, &mut state));
        state
    }

    fn normaliser(&self, seed: u64, samples: usize, clamp: f32) -> Option<(NormaliserMoments, u64)> {
        self.targets[0].normaliser(seed, samples, clamp)
    }
}
