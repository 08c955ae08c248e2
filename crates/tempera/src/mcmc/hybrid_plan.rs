//! The independent samples a render combines with its chains ([`super::hybrid`]): how many,
//! their walkers, their film and their weights.

use super::Bootstrap;
use super::driver::{ChainSettings, Slot};
use super::hybrid::{HybridDepth, HybridFilm};
use crate::film::Footprint;
use std::sync::Arc;

/// The independent samples a render combines with its chains.
pub(super) struct HybridPlan {
    /// The depths they cover, with their weights.
    pub depths: Vec<HybridDepth>,
    /// Their walkers, each with its share of the samples (of a round, under a time budget).
    pub plan: Vec<Slot>,
    /// Where they splat.
    pub film: HybridFilm,
}

impl Default for HybridPlan {
    fn default() -> Self {
        Self { depths: Vec::new(), plan: Vec::new(), film: HybridFilm { buffers: Vec::new(), scale: 1.0 } }
    }
}

impl HybridPlan {
    /// The independent samples of `settings` ([`ChainSettings::hybrid`]; none without): that
    /// ratio of the main-chain mutations of `plan` (a fixed budget's, or a round's:
    /// `round_quota`), dealt to as many walkers as a group has chains, covering every depth not
    /// sampled `independent`ly instead of by chains.
    pub fn new(
        settings: &ChainSettings,
        boots: &[Bootstrap],
        (plan, independent): (&[Slot], &[bool]),
        fixed: bool,
        round_quota: &dyn Fn(&Slot) -> u64,
        footprint: &Arc<Footprint>,
    ) -> Self {
        let mut mutations = vec![0u64; boots.len()];
        for slot in plan {
            mutations[slot.group] += if fixed { slot.quota() } else { round_quota(slot) };
        }
        let total: u64 = mutations.iter().sum();
        if settings.hybrid <= 0.0 || total == 0 {
            return Self::default();
        }
        let samples = ((settings.hybrid * total as f64).round() as u64).max(1);
        let efficiency = settings.chain_efficiency;
        let depths: Vec<HybridDepth> = (0..boots.len())
            .filter(|&k| !independent[k])
            .map(|k| match settings.sample_share {
                Some(share) => HybridDepth::with_share(k, &boots[k].values, share, boots[k].clamp),
                None => HybridDepth::new(k, boots[k].b(), (mutations[k], efficiency), samples, boots[k].clamp),
            })
            .collect();
        let walkers = (settings.chains as u64).min(samples).max(1);
        let plan = (0..walkers)
            .map(|index| Slot { group: 0, index: index as usize, walkers, budget: Some(samples) })
            .collect();
        let layers = if settings.group_images { depths.len() } else { 1 };
        let mean: f64 = boots.iter().map(Bootstrap::b).sum();
        let film = HybridFilm::new(layers, footprint, mean);
        Self { depths, plan, film }
    }

    /// Each group's chains' level ([`super::walker::GroupContext::mis_level`]).
    pub fn levels(&self, groups: usize) -> Vec<f32> {
        let mut levels = vec![0.0; groups];
        for d in self.depths.iter().filter(|d| d.level.is_finite()) {
            levels[d.k] = d.level;
        }
        levels
    }
}
