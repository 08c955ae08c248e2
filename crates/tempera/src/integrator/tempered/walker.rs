//! The walkers of tempered MMLT: an ensemble of replicas at the depths that keep one, and
//! MMLT's own chain on MMLT's depth target at the depths that run plain
//! ([`super::TemperedIntegrator::ensembles_below`]). The plain chain makes the same mutations
//! and splats as a one-replica ensemble, bit for bit, without the tempered state's cached
//! subpaths and cross-values, which only swaps and reuse need.

use super::ensemble::{Ensemble, EnsembleGroup, prepare_ensembles};
use crate::film::SharedSplats;
use crate::integrator::mmlt::DepthTarget;
use crate::mcmc::{DepthStats, GroupContext, Moments, OneLayer, Single, Walker};

/// One walker of tempered MMLT (boxed: a chain holds its states inline, an ensemble its
/// settings and statistics, and the two differ in size by hundreds of bytes).
pub enum TemperedWalker<'a> {
    /// MMLT's chain, at a depth without ensembles.
    Plain(Box<Single<DepthTarget<'a>>>),
    /// An ensemble of replicas.
    Ensemble(Box<Ensemble<'a>>),
}

impl Walker for TemperedWalker<'_> {
    type Group = EnsembleGroup;

    fn run(&mut self, group: &EnsembleGroup, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        match self {
            Self::Plain(single) => single.run(&OneLayer, mutations, splats, stop),
            Self::Ensemble(e) => e.run(group, mutations, splats, stop),
        }
    }

    /// A plain depth reports the one-rung ladder of a one-replica ensemble.
    fn stats(&self) -> DepthStats {
        match self {
            Self::Plain(single) => DepthStats { ladder: vec![0.0], ladder_ensembles: 1, ..single.stats() },
            Self::Ensemble(e) => e.stats(),
        }
    }

    fn large(&self, layer: usize) -> Moments {
        match self {
            Self::Plain(single) => single.large(layer),
            Self::Ensemble(e) => e.large(layer),
        }
    }

    fn rays(&self) -> u64 {
        match self {
            Self::Plain(single) => single.rays(),
            Self::Ensemble(e) => e.rays(),
        }
    }

    /// A depth's walkers are all plain or all ensembles; plain ones need no preparation.
    fn prepare_group(
        walkers: &mut [Self],
        group: &GroupContext,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (EnsembleGroup, u64) {
        let mut ensembles: Vec<&mut Ensemble> = walkers
            .iter_mut()
            .filter_map(|w| match w {
                Self::Ensemble(e) => Some(&mut **e),
                Self::Plain(_) => None,
            })
            .collect();
        prepare_ensembles(&mut ensembles, group, stop)
    }
}
