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
//! untempered contribution over its mixture value) with MMLT's expected-value weights and
//! scaling the depth's splats by `N_pixels · b_m / M` estimates the depth's image, for any
//! fixed `ρ` (a good one only lowers the variance). The chain driver ([`crate::mcmc::develop`])
//! computes `b_m` from the low-variance `b_0` and each `b_l`, refined like reuse's with the
//! chain's large steps (independent uniform samples valued under every target). The weight
//! `C_0/m ≤ ρ_0 C_0/f_0` is bounded by MMLT's, so hot components add no fireflies; where the
//! flattened targets carry light the real scene does not, the chain spends part of its time
//! there, splatting little.

use crate::film::SharedSplats;
use crate::mcmc::{
    Chain, EvalContext, Moments, NormaliserMoments, State, Target, TemperedState, TemperedTarget, target_value,
};

/// The mixture `Σ_l f_l/ρ_l` of a depth's tempered targets.
#[derive(Clone, Copy)]
pub struct MixtureTarget<'t, 'a> {
    pub targets: &'t [TemperedTarget<'a>],
    pub ratios: &'t [f64],
}

impl MixtureTarget<'_, '_> {
    /// The mixture value of `state` (evaluated under the main target), from its cached
    /// cross-evaluations.
    pub fn value_of(&self, state: &mut TemperedState) -> f32 {
        let mut sum = 0.0f64;
        for (l, rho) in self.ratios.iter().enumerate().take(self.targets.len()) {
            sum += f64::from(target_value(state.value_under(l, self.targets))) / rho;
        }
        if sum.is_finite() { sum as f32 } else { 0.0 }
    }

    /// The mixture values of bootstrap samples valued under every target (`values[i][l]`).
    pub fn values(&self, values: &[Vec<f32>]) -> Vec<f32> {
        values
            .iter()
            .map(|v| {
                let sum: f64 = v.iter().zip(self.ratios).map(|(&f, rho)| f64::from(f) / rho).sum();
                if sum.is_finite() { sum as f32 } else { 0.0 }
            })
            .collect()
    }
}

impl Target for MixtureTarget<'_, '_> {
    type State = TemperedState;

    /// Traces the state under the main target, then values it under the mixture. Its
    /// contribution stays the untempered one.
    fn evaluate(&self, cx: &mut EvalContext, recycled: TemperedState) -> TemperedState {
        let mut state = self.targets[0].evaluate(cx, recycled);
        state.value = self.value_of(&mut state);
        state
    }

    fn normaliser(&self, seed: u64, samples: usize) -> Option<(NormaliserMoments, u64)> {
        self.targets[0].normaliser(seed, samples)
    }
}

/// Makes up to `mutations` mutations of `chain` on the mixture, checking `stop` every 256;
/// each large-step proposal is valued under every target into `large`, the rest splats
/// `C_0/m` with its expected weight into `splats`. Returns the mutations made; the time
/// spent is added to the chain's statistics.
pub fn run(
    chain: &mut Chain<TemperedState>,
    target: &MixtureTarget,
    large: &mut [Moments],
    mutations: u64,
    splats: &SharedSplats,
    stop: &dyn Fn() -> bool,
) -> u64 {
    let start = std::time::Instant::now();
    let mut done = 0;
    while done < mutations {
        if done % 256 == 0 && stop() {
            break;
        }
        let observe = |proposal: &mut TemperedState| {
            for (l, m) in large.iter_mut().enumerate() {
                m.push(f64::from(target_value(proposal.value_under(l, target.targets))));
            }
        };
        chain.mutate_splatting(target, observe, |state, weight| {
            if weight > 0.0 && state.value() > 0.0 {
                state.splat(splats, weight / state.value());
            }
        });
        done += 1;
    }
    chain.stats.seconds += start.elapsed().as_secs_f64();
    done
}
