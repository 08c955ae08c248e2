//! The chain driver's settings ([`ChainSettings`]): their defaults and builders.

use super::Target;
use super::bootstrap::Bootstrap;
use super::driver::ChainSettings;

impl ChainSettings {
    pub fn new(bootstrap: usize, chains: usize, sigma: f32, large_step_probability: f32) -> Self {
        Self {
            bootstrap,
            chains,
            sigma,
            large_step_probability,
            spread_allocation: false,
            spread_below: 0,
            group_images: false,
            independent_below: 0,
            normaliser_share: super::normaliser::DEFAULT_SHARE,
            clamp: 0.0,
            hybrid: 0.0,
            chain_efficiency: super::hybrid::DEFAULT_EFFICIENCY,
            sample_share: None,
            measure_efficiency: false,
            bridge_above: None,
            reallot_at: 0.0,
            jumps: 0.0,
            film_steps: 0.0,
            lens_steps: 0.0,
        }
    }

    /// These settings with `ratio` samples of bidirectional path tracing per main-chain
    /// mutation combined with the chains ([`super::hybrid`]; 0: none). Only for targets that
    /// are MMLT's depths ([`Target::hybrid_depth`]).
    pub fn with_hybrid(self, ratio: f64) -> Self {
        Self { hybrid: ratio, ..self }
    }

    /// These settings with reversible jumps proposed with probability `p` ([`super::jump`]).
    pub fn with_jumps(self, p: f32) -> Self {
        Self { jumps: p, ..self }
    }

    /// These settings with film steps in place of small steps with probability `p`
    /// ([`Self::film_steps`]).
    pub fn with_film_steps(self, p: f32) -> Self {
        Self { film_steps: p, ..self }
    }

    /// These settings with lens steps in place of small steps with probability `p`
    /// ([`Self::lens_steps`]).
    pub fn with_lens_steps(self, p: f32) -> Self {
        Self { lens_steps: p, ..self }
    }

    /// These settings with a main-chain mutation counting as `efficiency` independent samples
    /// in the weights of [`Self::with_hybrid`].
    pub fn with_chain_efficiency(self, efficiency: f64) -> Self {
        Self { chain_efficiency: efficiency, ..self }
    }

    /// These settings with the independent samples of [`Self::with_hybrid`] weighted to carry
    /// `share` of each depth's light (`None`: weights from the chain efficiency).
    pub fn with_sample_share(self, share: Option<f64>) -> Self {
        Self { sample_share: share, ..self }
    }

    /// These settings with each group's chain efficiency measured when `on` is set
    /// ([`Self::measure_efficiency`]).
    pub fn with_measured_efficiency(self, on: bool) -> Self {
        Self { measure_efficiency: on, ..self }
    }

    /// These settings with each group's main layer scaled by its bridge estimate where `b`'s
    /// relative error exceeds `above` ([`Self::bridge_above`]).
    pub fn with_bridge_above(self, above: Option<f64>) -> Self {
        Self { bridge_above: above, ..self }
    }

    /// These settings with clampable targets clamped at `clamp` times the mean of their
    /// bootstrap's non-zero values (0: none).
    pub fn with_clamp(self, clamp: f64) -> Self {
        Self { clamp, ..self }
    }

    /// These settings with the depths whose bootstrap has fewer than `n` non-zero values
    /// sampled independently (0: none).
    pub fn with_independent_below(self, n: usize) -> Self {
        Self { independent_below: n, ..self }
    }

    /// Whether group `boot` of `target` is sampled independently.
    pub(super) fn independent<T: Target>(&self, boot: &Bootstrap, target: &T) -> bool {
        target.independent_depth().is_some() && (boot.nonzero() as usize) < self.independent_below
    }

    /// These settings with `share` of the chains' rays spent on further normaliser samples.
    pub fn with_normaliser_share(self, share: f64) -> Self {
        Self { normaliser_share: share, ..self }
    }

    /// These settings with one image per group developed beside the image when `on` is set.
    pub fn with_group_images(self, on: bool) -> Self {
        Self { group_images: on, ..self }
    }

    /// These settings with the spread counting only for the groups whose bootstrap holds fewer
    /// than `n` non-zero values (0: for every group).
    pub fn with_spread_below(self, n: usize) -> Self {
        Self { spread_below: n, ..self }
    }

    /// These settings with mutations allotted by `b` times spread when `spread` is set.
    pub fn with_spread_allocation(self, spread: bool) -> Self {
        Self { spread_allocation: spread, ..self }
    }

    /// These settings with a time budget's mutations re-allotted by the groups' measured error
    /// after `share` of it ([`Self::reallot_at`]; 0: never).
    pub fn with_reallot_at(self, share: f64) -> Self {
        Self { reallot_at: share, ..self }
    }
}
