//! MCMC photon tracing with replica exchange (Hachisuka & Jensen 2011, "Robust adaptive photon
//! tracing using photon path visibility"). A photon path is a point `u` of primary sample space
//! (the numbers its light sample, BSDF samples and Russian roulette draw); its *visibility*
//! `V(u)` is 1 when the path reaches any visible point within that point's radius, else 0.
//!
//! Each Markov chain samples `u` in proportion to `V(u)`. A step of a chain:
//!
//! 1. **Exchange with the uniform replica.** A fresh uniform `u'` (the state of a replica whose
//!    target is the uniform distribution and which draws an independent state every step) is
//!    offered in exchange for the chain's state; the exchange's acceptance
//!    `min(1, V(u')·1 / (V(u)·1))` is `V(u')` for a visible chain: the chain jumps to every
//!    visible uniform photon. The uniform photons' visible fraction `V̄` estimates `∫V`.
//! 2. **Mutation.** A Kelemen perturbation of width `σ` (in [`PssSampler`]); accepted when the
//!    mutated path is visible (the Metropolis ratio `V(u'')/V(u)`). `σ` adapts towards an
//!    acceptance of 0.234 by `σ ← σ + (a − 0.234)/i` after the chain's `i`-th mutation, with
//!    `a` 1 for an accepted and 0 for a rejected one (a diminishing adaptation).
//! 3. **Recording.** The chain's current state deposits its photon.
//!
//! Over `N` recorded steps the chains' deposits estimate `∫c(u)du = ∫V·(c/V)du ≈ V̄·(1/N)·Σ
//! c(u_i)` for the chain states `u_i` (all visible, and `c = 0` where `V = 0`): scaled by
//! `P·V̄/N`, what `P` uniform photons would deposit. When the visible points move (a new SPPM
//! iteration), a chain first re-traces its state; a state that is invisible under the new points
//! accepts any proposal, and the chain's steps are not recorded until it is visible again (a
//! burn-in: counting them would darken the estimate).

use super::{PhotonSums, Targets, trace_photon};
use crate::math::Rgb;
use crate::sampler::PssSampler;
use crate::scene::Scene;
use rayon::prelude::*;

/// The acceptance the mutation size adapts towards.
const TARGET_ACCEPTANCE: f64 = 0.234;

/// A photon path's deposits: the pixel of each visible point it reached and `β·f` there.
pub type Deposits = Vec<(u32, Rgb)>;

/// One Markov chain over photon paths.
#[derive(Clone, Debug)]
pub struct PhotonChain {
    sampler: PssSampler,
    deposits: Deposits,
    /// Whether the current state reaches a visible point.
    pub visible: bool,
    /// The mutation size.
    pub sigma: f32,
    pub mutations: u64,
    pub accepted: u64,
    /// Uniform photons offered, and taken.
    pub offered: u64,
    pub exchanged: u64,
}

/// What one step of a chain found.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StepOutcome {
    pub rays: u64,
    /// Whether the uniform photon was visible.
    pub uniform_visible: bool,
}

impl PhotonChain {
    pub fn new(seed: u64, chain: u64) -> Self {
        Self {
            sampler: PssSampler::new(seed ^ 0x9407_c4a1, chain, 0.1, 0.0),
            deposits: Vec::new(),
            visible: false,
            sigma: 0.1,
            mutations: 0,
            accepted: 0,
            offered: 0,
            exchanged: 0,
        }
    }

    /// The current state's deposits.
    pub fn deposits(&self) -> &Deposits {
        &self.deposits
    }

    /// Evaluates the proposal `start` begins with `eval` (which traces the path from the
    /// sampler's numbers, filling `scratch` with its deposits); keeps it when `keep(visible)`.
    fn propose(
        &mut self,
        eval: &mut dyn FnMut(&mut PssSampler, &mut Deposits) -> (u64, bool),
        scratch: &mut Deposits,
        keep: impl Fn(bool, bool) -> bool,
    ) -> (u64, bool, bool) {
        scratch.clear();
        let (rays, visible) = eval(&mut self.sampler, scratch);
        let kept = keep(visible, self.visible);
        if kept {
            self.sampler.accept();
            std::mem::swap(&mut self.deposits, scratch);
            self.visible = visible;
        } else {
            self.sampler.reject();
        }
        (rays, visible, kept)
    }

    /// Re-traces the current state under new visible points.
    pub fn refresh(&mut self, eval: &mut dyn FnMut(&mut PssSampler, &mut Deposits) -> (u64, bool)) -> u64 {
        let mut scratch = Deposits::new();
        self.sampler.set_sigma(0.0);
        self.sampler.start_iteration_as(false);
        self.propose(eval, &mut scratch, |_, _| true).0
    }

    /// One step: the exchange with a uniform photon, then a mutation; the current state's
    /// deposits are then [`Self::deposits`].
    pub fn step(
        &mut self,
        eval: &mut dyn FnMut(&mut PssSampler, &mut Deposits) -> (u64, bool),
        scratch: &mut Deposits,
    ) -> StepOutcome {
        // A state of zero target (invisible) takes any proposal.
        let keep = |proposal: bool, current: bool| proposal || !current;
        self.sampler.start_iteration_as(true);
        let (uniform_rays, uniform_visible, taken) = self.propose(eval, scratch, keep);
        self.offered += 1;
        self.exchanged += u64::from(taken);
        let was_visible = self.visible;
        self.sampler.set_sigma(self.sigma);
        self.sampler.start_iteration_as(false);
        let (mutation_rays, _, kept) = self.propose(eval, scratch, keep);
        if was_visible {
            self.mutations += 1;
            self.accepted += u64::from(kept);
            let a = if kept { 1.0 } else { 0.0 };
            let sigma = f64::from(self.sigma) + (a - TARGET_ACCEPTANCE) / self.mutations as f64;
            self.sigma = sigma.clamp(1e-5, 0.5) as f32;
        }
        StepOutcome { rays: uniform_rays + mutation_rays, uniform_visible }
    }
}

/// The chains of an SPPM render, kept from iteration to iteration.
pub struct PhotonChains {
    pub chains: Vec<PhotonChain>,
}

impl PhotonChains {
    pub fn new(seed: u64, chains: usize) -> Self {
        Self { chains: (0..chains.max(1)).map(|c| PhotonChain::new(seed, c as u64)).collect() }
    }

    /// `photons` steps in all, shared among the chains (those `owns` says this process runs),
    /// each chain's current photon added to `sums` after every step at which it is visible.
    /// Returns the rays traced, how many of the uniform photons were visible and how many steps
    /// were recorded: `visible / recorded` scales the sums to an estimate of `photons` uniform
    /// photons' sums (`photons·V̄` over the recorded steps).
    pub fn run(
        &mut self,
        scene: &Scene,
        max_depth: u32,
        (targets, sums): (&Targets, &PhotonSums),
        photons: u64,
        owns: &(dyn Fn(usize) -> bool + Sync),
    ) -> (u64, u64, u64) {
        let c = self.chains.len() as u64;
        self.chains
            .par_iter_mut()
            .enumerate()
            .filter(|(j, _)| owns(*j))
            .map(|(j, chain)| {
                let steps = photons / c + u64::from((j as u64) < photons % c);
                let mut eval = |sampler: &mut PssSampler, out: &mut Deposits| {
                    trace_photon(scene, max_depth, targets, sampler, &mut |i, v| out.push((i as u32, v)))
                };
                let mut rays = chain.refresh(&mut eval);
                let (mut visible, mut recorded) = (0u64, 0u64);
                let mut scratch = Deposits::new();
                for _ in 0..steps {
                    let outcome = chain.step(&mut eval, &mut scratch);
                    rays += outcome.rays;
                    visible += u64::from(outcome.uniform_visible);
                    // A chain whose state is not visible (it has not found the new visible
                    // points yet) is still burning in: its steps are not recorded.
                    if chain.visible {
                        recorded += 1;
                        for &(i, v) in chain.deposits() {
                            sums.add(i as usize, v);
                        }
                    }
                }
                (rays, visible, recorded)
            })
            .reduce(|| (0, 0, 0), |a, b| (a.0 + b.0, a.1 + b.1, a.2 + b.2))
    }

    /// The chains' statistics as one row: steps as mutations, uniform photons offered and
    /// taken as large steps, mutations proposed and accepted as small steps, and `b` the
    /// uniform photons' visible fraction over the render.
    pub fn stats(&self, visible_fraction: f64) -> crate::mcmc::DepthStats {
        let mut d = crate::mcmc::DepthStats { all_depths: true, b: visible_fraction, ..Default::default() };
        for c in &self.chains {
            d.mutations += c.offered;
            d.large_steps_proposed += c.offered;
            d.large_steps_accepted += c.exchanged;
            d.small_steps_proposed += c.mutations;
            d.small_steps_accepted += c.accepted;
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampler::{Sampler, Stream};

    /// A toy visibility over two numbers: `u0` in [0.2, 0.25) or [0.7, 0.85) and `u1 < 0.5`,
    /// measure 0.1. The chains' states must be uniform over that set (their target `V`): each
    /// of its ten 0.025-wide bins of `u0` holds a tenth of the states; no state is invisible
    /// once the chains have found the set; the uniform photons' visible fraction is its
    /// measure; the mutation size settles where a quarter of the mutations are accepted.
    #[test]
    fn chains_sample_the_visible_set_uniformly_and_estimate_its_measure() {
        let visible = |u0: f32, u1: f32| ((0.2..0.25).contains(&u0) || (0.7..0.85).contains(&u0)) && u1 < 0.5;
        let mut eval = |s: &mut PssSampler, out: &mut Deposits| {
            s.start_stream(Stream::Light);
            let (u0, u1) = (s.next_1d(), s.next_1d());
            let v = visible(u0, u1);
            if v {
                out.push(((u0 / 0.025) as u32, Rgb::ONE));
            }
            (2, v)
        };
        let mut bins = [0u64; 40];
        let (mut states, mut uniform_visible, mut offered) = (0u64, 0u64, 0u64);
        let mut chains = PhotonChains::new(7, 32);
        for chain in &mut chains.chains {
            let mut scratch = Deposits::new();
            for step in 0..20_000 {
                let outcome = chain.step(&mut eval, &mut scratch);
                uniform_visible += u64::from(outcome.uniform_visible);
                offered += 1;
                if step < 100 {
                    continue;
                }
                assert_eq!(chain.deposits().len(), 1, "the chain stays in the visible set");
                bins[chain.deposits()[0].0 as usize] += 1;
                states += 1;
            }
        }
        let expected_bins = [8usize, 9, 28, 29, 30, 31, 32, 33];
        for (b, &n) in bins.iter().enumerate() {
            let share = n as f64 / states as f64;
            // Bin 8 is [0.2, 0.225), 9 is [0.225, 0.25), 28–33 cover [0.7, 0.85).
            let want = if expected_bins.contains(&b) { 0.125 } else { 0.0 };
            assert!((share - want).abs() < 0.01, "bin {b}: {share} of the states, expected {want}");
        }
        let measure = uniform_visible as f64 / offered as f64;
        assert!((measure - 0.1).abs() < 0.003, "visible fraction {measure}");
        let stats = chains.stats(measure);
        let acceptance = stats.small_steps_accepted as f64 / stats.small_steps_proposed as f64;
        assert!((acceptance - TARGET_ACCEPTANCE).abs() < 0.03, "mutation acceptance {acceptance}");
        assert_eq!(stats.large_steps_proposed, offered);
    }
}
