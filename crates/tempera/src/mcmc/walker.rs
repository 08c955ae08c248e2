//! What the chain driver ([`super::driver`]) runs: walkers (one chain, or one ensemble of
//! replicas) grouped per path depth, how a group's splat layers are normalised, and where each
//! walker starts.

use super::bootstrap::sampler_for;
use super::driver::ChainSettings;
use super::{Chain, DepthStats, Moments, Target};
use crate::film::SharedSplats;
use crate::math::distribution::Distribution1D;
use crate::math::rng::Pcg32;

/// How a group's splat layers are normalised, decided when the group is prepared.
pub trait Layers: Send + Sync {
    /// The layers each walker of the group splats into.
    fn count(&self) -> usize {
        1
    }
    /// For a layer `l ≥ 1`: the moments of its target over the group's bootstrap and the ratio
    /// `ρ_l` its splats were weighted with. (Layer 0 is the group's own target, `ρ_0 = 1`.)
    fn layer(&self, _l: usize) -> Option<(Moments, f64)> {
        None
    }
    /// The ratios `ρ_l` to report in the statistics (empty: a single layer).
    fn ratios(&self) -> &[f64] {
        &[]
    }
    /// Whether the group's single layer is splatted by chains on the mixture `Σ_l f_l/ρ_l` of
    /// targets `0 … valued − 1` (their moments and ratios from [`Self::layer`]): it is then
    /// normalised by `b_m = Σ_l b_l/ρ_l` instead of `b_0`.
    fn mixture(&self) -> bool {
        false
    }
    /// The targets whose moments over the large steps the walkers report ([`Walker::large`]):
    /// one per layer, or each target of the mixture.
    fn valued(&self) -> usize {
        self.count()
    }
}

/// A group with a single layer: MMLT's and PSSMLT's.
#[derive(Clone, Copy, Debug, Default)]
pub struct OneLayer;

impl Layers for OneLayer {}

/// A group's layers where it has walkers of its own kind; a single one where it is sampled
/// independently (`None`).
impl<L: Layers> Layers for Option<L> {
    fn count(&self) -> usize {
        self.as_ref().map_or(1, Layers::count)
    }
    fn layer(&self, l: usize) -> Option<(Moments, f64)> {
        self.as_ref().and_then(|g| g.layer(l))
    }
    fn ratios(&self) -> &[f64] {
        self.as_ref().map_or(&[], Layers::ratios)
    }
    fn mixture(&self) -> bool {
        self.as_ref().is_some_and(Layers::mixture)
    }
    fn valued(&self) -> usize {
        self.as_ref().map_or(1, Layers::valued)
    }
}

/// A unit of parallel work of the chain driver: one chain (MMLT, PSSMLT) or one ensemble of
/// replicas (tempered MMLT).
pub trait Walker: Send {
    /// What the walkers of a group share once it is prepared.
    type Group: Layers;
    /// Makes up to `mutations` mutations of the main chain, splatting into `splats` (one
    /// buffer per layer, shared with the group's other walkers); returns how many were made.
    fn run(&mut self, group: &Self::Group, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64;
    /// The main chain's statistics.
    fn stats(&self) -> DepthStats;
    /// The moments of `layer`'s target over the walker's large-step proposals.
    fn large(&self, layer: usize) -> Moments;
    fn rays(&self) -> u64;
    /// Prepares the walkers of one group together, before the first round; returns what they
    /// share and the rays traced.
    fn prepare_group(
        walkers: &mut [Self],
        group: &GroupContext,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (Self::Group, u64)
    where
        Self: Sized;
}

/// A group of walkers: its index, the render's seed, the driver's settings and, under a fixed
/// budget, the group's share of the mutations.
#[derive(Clone, Copy)]
pub struct GroupContext<'a> {
    pub k: usize,
    pub seed: u64,
    pub settings: &'a ChainSettings,
    pub budget: Option<u64>,
    /// The value the group's chains clamp its target at ([`Bootstrap::clamp`]).
    pub clamp: f32,
    /// The level of the independent samples the group's chains are combined with
    /// ([`super::hybrid`]; 0: none).
    pub mis_level: f32,
    /// The level of the bridge estimate of the group's normalisation its chains add to
    /// ([`super::bridge`]; 0: none).
    pub bridge_level: f32,
}

impl GroupContext<'_> {
    /// Starts a chain under `target` from the group's bootstrap sample that `u` picks from
    /// `starts` (a distribution over the samples), accepting with `rng`: every chain of every
    /// Markov-chain integrator starts so.
    pub fn start_chain<T: Target>(&self, target: &T, starts: &Distribution1D, u: f32, rng: Pcg32) -> Chain<T::State> {
        let (index, _, _) = starts.sample_discrete(u);
        let mut chain =
            Chain::start_clamped(target, sampler_for(self.seed, self.k, index, self.settings), rng, self.k, self.clamp);
        chain.set_mis_level(self.mis_level);
        chain.set_bridge_level(self.bridge_level);
        chain
    }
}

/// Where a walker starts: walker `c` of its group, with the group's bootstrap values and the
/// distribution of start states (in proportion to their value).
pub struct StartContext<'a> {
    pub group: GroupContext<'a>,
    pub c: usize,
    pub rng: Pcg32,
    pub starts: &'a Distribution1D,
    pub bootstrap: &'a [f32],
}

impl StartContext<'_> {
    /// Starts a chain under `target` from a bootstrap state drawn with `rng` in proportion to
    /// its value.
    pub fn start_chain<T: Target>(&self, target: &T, mut rng: Pcg32) -> Chain<T::State> {
        let u = rng.next_f32();
        self.group.start_chain(target, self.starts, u, rng)
    }
}

/// One chain with its target.
pub struct Single<T: Target> {
    pub chain: Chain<T::State>,
    pub target: T,
}

impl<T: Target> Single<T> {
    /// A chain under `target`, started as [`StartContext::start_chain`] does.
    pub fn start(cx: StartContext, target: T) -> Self {
        let chain = cx.start_chain(&target, cx.rng.clone());
        Single { chain, target }
    }
}

impl<T: Target + Send> Walker for Single<T>
where
    T::State: Send,
{
    type Group = OneLayer;

    fn run(&mut self, _: &OneLayer, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        self.chain.run(&self.target, mutations, Some(&splats[0]), stop)
    }

    fn stats(&self) -> DepthStats {
        self.chain.stats.clone()
    }

    fn large(&self, _layer: usize) -> Moments {
        self.chain.large
    }

    fn rays(&self) -> u64 {
        self.chain.rays()
    }

    fn prepare_group(_: &mut [Self], _: &GroupContext, _: &(dyn Fn() -> bool + Sync)) -> (OneLayer, u64) {
        (OneLayer, 0)
    }
}
