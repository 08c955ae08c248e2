//! Parallel tempering for MMLT (Šik & Křivánek 2016): per path depth an ensemble of replicas
//! whose targets are flattened by roughening the BSDFs at the connection vertices
//! ([`crate::bidir::tempered`]), exchanging states by one of three swap strategies. This module
//! holds the strategies, which only see the ensemble through its cross-evaluations
//! `f_i(u_j)` (target of replica `i` at the state replica `j` holds); each leaves every
//! replica's target invariant:
//!
//! - [`Neighbor`]: propose exchanging replicas `i` and `i + 1` (uniform `i`), accepted with
//!   `min(1, f_i(u_j) f_j(u_i) / (f_i(u_i) f_j(u_j)))`;
//! - [`EquiEnergy`] (Baragatti, Grimaud & Pommeret 2012): states fall into log-spaced rings of
//!   the main target `f_0`; two replicas in a ring holding at least two are proposed, with the
//!   same acceptance. The ring is a function of the state alone, so an exchange leaves the ring
//!   occupancy, and thereby the proposal probability, unchanged;
//! - [`Permutation`]: a Gibbs step over all `K!` assignments of states to replicas, drawn with
//!   probability proportional to `Π_i f_i(u_σ(i))` (always accepted).
//!
//! Or, without swaps, [`mixture`]: one chain per ensemble on the mixture of the replicas'
//! normalised targets.

mod calibration;
mod ensemble;
mod equi_energy;
mod integrator;
mod ladder;
pub mod mixture;
mod neighbor;
mod permutation;
mod replicas;
mod reuse;
mod walker;

#[cfg(test)]
mod tests;

pub use ensemble::{Ensemble, EnsembleGroup, EnsembleSettings};
pub use equi_energy::EquiEnergy;
pub use integrator::{DEFAULT_BDPT_ABOVE, TemperedIntegrator};
pub use ladder::{Ladder, Tuning, TuningMethod};
pub use neighbor::Neighbor;
pub use permutation::Permutation;
pub use replicas::{Replicas, apply_permutation};
pub use reuse::Reuse;

use crate::math::rng::Pcg32;
pub use crate::mcmc::SwapStats;

/// Cross-evaluations of an ensemble: `f(i, j)` is replica `i`'s target at the state replica `j`
/// holds. Implementations may compute entries lazily; strategies ask only for what they need.
pub trait CrossValues {
    fn replicas(&self) -> usize;
    fn f(&mut self, i: usize, j: usize) -> f64;
}

/// A swap strategy. `step` returns the new assignment `σ` (replica `i` takes the state of
/// replica `σ[i]`), or `None` when the states stay where they are.
pub trait SwapStrategy: Send + Sync {
    fn name(&self) -> &'static str;
    fn step(&self, values: &mut dyn CrossValues, rng: &mut Pcg32, stats: &mut SwapStats) -> Option<Vec<usize>>;
}

/// The swap kernel of an ensemble: one of the strategies, each in a file of its own.
#[derive(Clone, Debug)]
pub enum SwapKernel {
    Neighbor(Neighbor),
    EquiEnergy(EquiEnergy),
    Permutation(Permutation),
}

impl SwapKernel {
    /// One swap step of the kernel (see [`SwapStrategy::step`]).
    pub fn step(&self, values: &mut dyn CrossValues, rng: &mut Pcg32, stats: &mut SwapStats) -> Option<Vec<usize>> {
        match self {
            SwapKernel::Neighbor(s) => s.step(values, rng, stats),
            SwapKernel::EquiEnergy(s) => s.step(values, rng, stats),
            SwapKernel::Permutation(s) => s.step(values, rng, stats),
        }
    }
}

/// The Metropolis acceptance of exchanging the states of replicas `i` and `j`, in `f64`.
/// A pair whose current product is zero (a replica that has not found light yet) is exchanged
/// whenever the exchanged product is positive.
pub fn swap_acceptance(values: &mut dyn CrossValues, i: usize, j: usize) -> f64 {
    let current = values.f(i, i) * values.f(j, j);
    let exchanged = values.f(i, j) * values.f(j, i);
    if !exchanged.is_finite() || exchanged <= 0.0 {
        return 0.0;
    }
    if current.is_nan() || current <= 0.0 { 1.0 } else { (exchanged / current).min(1.0) }
}

/// Proposes exchanging `i` and `j`; returns the assignment when accepted.
fn try_exchange(
    values: &mut dyn CrossValues,
    i: usize,
    j: usize,
    rng: &mut Pcg32,
    stats: &mut SwapStats,
) -> Option<Vec<usize>> {
    let a = swap_acceptance(values, i, j);
    let accepted = rng.next_f64() < a;
    stats.record(i, j, accepted);
    accepted.then(|| {
        let mut sigma: Vec<usize> = (0..values.replicas()).collect();
        sigma.swap(i, j);
        sigma
    })
}
