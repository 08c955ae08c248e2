//! A Markov chain in primary sample space with expected-value splatting (Veach 1997 §11.5;
//! pbrt-v4 §13.4.3): each proposal `y` from the current state `x` is accepted with
//! `a = min(1, f(y)/f(x))`, and both are splatted as `C/f` with weights `a` and `1 − a`. Values
//! that are NaN, infinite or negative count as zero. The chain keeps its state between calls, so
//! time-budgeted renders can advance all chains in rounds.

use super::lens::LensStep;
use super::{DepthStats, Evaluated, Moments, NormaliserMoments};
use crate::bidir::Paths;
use crate::film::SharedSplats;
use crate::math::rng::Pcg32;
use crate::sampler::PssSampler;

/// What a chain needs of an evaluated state.
pub trait State: Default {
    /// The target value `f` (0 for invalid states).
    fn value(&self) -> f32;
    /// Whether the evaluation met a NaN, infinite or negative value (which counts as zero).
    fn invalid(&self) -> bool;
    /// The bidirectional technique the state chose, for the technique-change statistics.
    fn technique(&self) -> usize;
    /// Adds the state's contributions, each times `scale`, to the film.
    fn splat(&self, splats: &SharedSplats, scale: f32);
    /// The luminance a splat of the state carries per unit of its target value: 1 where the
    /// target is the contribution's luminance, the inverse of the map's factor where a
    /// per-pixel map shapes it ([`super::importance`]).
    fn weight(&self) -> f32 {
        1.0
    }
    /// Clamps the target value at `c` (the contributions stay): only states of targets that
    /// are [`Target::clampable`] are ever clamped, so the others keep their value.
    fn clamp_value(&mut self, _c: f32) {}
    /// Whether the value does not depend on the state's film numbers, so that a film step
    /// ([`PssSampler::with_film_steps`]) would propose the state itself.
    fn film_unread(&self) -> bool {
        false
    }
}

/// What evaluating a primary-sample-space state needs: the sampler holding the state, subpath
/// storage reused from evaluation to evaluation, and the count of rays traced.
pub struct EvalContext {
    pub sampler: PssSampler,
    pub paths: Paths,
    pub rays: u64,
    /// The last evaluation of a target that leaves its path in [`Self::paths`] (MMLT's depth
    /// target), where it records it.
    pub last: Option<Evaluated>,
    /// The chain's current state's evaluation and subpaths, where [`Self::last`] was recorded
    /// for it: what a reversible jump ([`super::jump`]) starts from.
    pub held: Option<Evaluated>,
    pub held_paths: Paths,
}

impl EvalContext {
    pub fn new(sampler: PssSampler) -> Self {
        Self { sampler, paths: Paths::default(), rays: 0, last: None, held: None, held_paths: Paths::default() }
    }

    /// Keeps the last evaluation (the accepted proposal) as the current state's.
    fn hold(&mut self) {
        self.held = self.last.take();
        if self.held.is_some() {
            std::mem::swap(&mut self.paths, &mut self.held_paths);
        }
    }
}

/// A chain's target: the value of the state the context's sampler holds.
pub trait Target {
    type State: State;
    /// Evaluates the state `cx.sampler` holds. `recycled` is a state that is no longer needed:
    /// the result may reuse its storage.
    fn evaluate(&self, cx: &mut EvalContext, recycled: Self::State) -> Self::State;
    /// An estimator of the target's mean (the normalisation `b`) with a lower variance than
    /// the target's own uniform samples, where the target has one: the moments of `samples`
    /// estimates seeded by `seed`, and the rays traced. `clamp` is the value at which the
    /// chains clamp a [`Self::clampable`] target (infinite for every other target): the
    /// estimate is then of the clamped target's mean.
    fn normaliser(&self, _seed: u64, _samples: usize, _clamp: f32) -> Option<(NormaliserMoments, u64)> {
        None
    }
    /// Whether the chains may clamp the target's values ([`super::ChainSettings::clamp`]):
    /// its states clamp their value and its normaliser (if any) estimates the clamped mean.
    fn clampable(&self) -> bool {
        false
    }
    /// The path depth `k ≥ 1` whose paths the target's values are, where the driver may
    /// sample it independently instead ([`super::independent`]); `None` for targets of another
    /// kind.
    fn independent_depth(&self) -> Option<usize> {
        None
    }
    /// The path depth `k` whose MMLT target (one strategy of the depth's `n`, valued
    /// `n·w_s·C_s`: [`super::strategy`]) this is, where the chains may be combined with
    /// bidirectional path tracing ([`super::hybrid`]); `None` for targets of another kind.
    fn hybrid_depth(&self) -> Option<usize> {
        None
    }
    /// Whether [`Self::value_groups`] values a state under the targets of several groups at
    /// once.
    fn values_groups_together(&self) -> bool {
        false
    }
    /// Values the state `cx.sampler` holds under the targets of groups `0..groups` at once,
    /// where they share work (MMLT's depths share subpaths): pushes per group the value and
    /// invalid flag its own target's evaluation gives and the rays that evaluation would
    /// trace, and returns the rays traced in all. Only where [`Self::values_groups_together`].
    fn value_groups(&self, _cx: &mut EvalContext, _groups: usize, _out: &mut Vec<GroupValue>) -> u64 {
        unreachable!("a target that does not value groups together")
    }
    /// Proposes a reversible jump of `current` (the state `cx.sampler` holds) to another
    /// technique of its path ([`super::jump`]), evaluated into `proposal`: returns the jump's
    /// Jacobian, or `None` where no jump was begun (the sampler unchanged). Targets that are
    /// not of one path depth propose none.
    fn jump(
        &self,
        _cx: &mut EvalContext,
        _rng: &mut Pcg32,
        _current: &Self::State,
        _proposal: &mut Self::State,
    ) -> Option<f32> {
        None
    }
    /// Proposes a lens step of `current` (the state `cx.sampler` holds, a lens step begun):
    /// moves its pixel and keeps the rest of its path ([`super::lens`]), evaluated into
    /// `proposal`. Targets that are not of one path depth have none: their states stay.
    fn lens_step(
        &self,
        _cx: &mut EvalContext,
        _rng: &mut Pcg32,
        _current: &Self::State,
        _proposal: &mut Self::State,
    ) -> LensStep {
        LensStep::Stay
    }
}

/// A sample's value under one group's target: what the target's evaluation gives for the
/// state's value and invalid flag, and the rays that evaluation traces.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GroupValue {
    pub value: f32,
    pub invalid: bool,
    pub rays: u64,
}

/// A target value as the chains use it: NaN, infinite, negative and zero values all count as
/// zero.
pub fn target_value(v: f32) -> f32 {
    if v.is_finite() && v > 0.0 { v } else { 0.0 }
}

pub struct Chain<S> {
    cx: EvalContext,
    rng: Pcg32,
    current: S,
    proposal: S,
    /// The value at which the target is clamped (infinite: none).
    clamp: f32,
    /// The level `h` of the independent samples' density in target units where the chain is
    /// combined with them by multiple importance sampling ([`super::hybrid`]): a state of
    /// value `f` splats with the balance-heuristic weight `f/(f + h)`, that is `C/(f + h)`
    /// instead of `C/f`. 0: the chain alone.
    mis_level: f32,
    /// The chain's statistics, with the bridge sums ([`super::bridge`]) and their level
    /// (`stats.bridge.level`; 0: the chain adds nothing to them).
    pub stats: DepthStats,
    /// The large-step proposals' values.
    pub large: Moments,
}

impl<S: State> Chain<S> {
    /// Starts from the state `sampler` holds (its first, large step), evaluated and accepted.
    pub fn start(target: &impl Target<State = S>, sampler: PssSampler, rng: Pcg32, depth: usize) -> Self {
        Self::start_clamped(target, sampler, rng, depth, f32::INFINITY)
    }

    /// [`Self::start`] for a chain whose target is clamped at `clamp` (infinite: none), the
    /// target of the clamped importance below. A chain on `g = min(f, c)` that splats `C/g`
    /// estimates the image as one on `f` does (the splats of a state are its contribution over
    /// the density it is visited with), normalised by `b_g = E[g]` instead of `E[f]` (Hoberock
    /// & Hart 2010, arbitrary importance functions for Metropolis light transport): a value far
    /// above `c` then weighs on its own pixels, as one bright sample of BDPT does, and not on
    /// the whole depth's normalisation.
    pub fn start_clamped(
        target: &impl Target<State = S>,
        sampler: PssSampler,
        rng: Pcg32,
        depth: usize,
        clamp: f32,
    ) -> Self {
        let mut cx = EvalContext::new(sampler);
        let mut current = target.evaluate(&mut cx, S::default());
        if clamp.is_finite() {
            current.clamp_value(clamp);
        }
        cx.sampler.accept();
        cx.hold();
        Self {
            cx,
            rng,
            current,
            proposal: S::default(),
            clamp,
            mis_level: 0.0,
            stats: DepthStats { depth, ..DepthStats::default() },
            large: Moments::default(),
        }
    }

    /// Rays traced since the chain started.
    pub fn rays(&self) -> u64 {
        self.cx.rays
    }

    /// Counts `rays` more as traced by this chain (those of chains it replaces).
    pub fn count_rays(&mut self, rays: u64) {
        self.cx.rays += rays;
    }

    /// Replaces this chain by `fresh`, keeping the count of rays traced by both, this chain's
    /// large-step probability, level of independent samples and bridge level (and `fresh`'s
    /// clamp).
    pub fn restart(&mut self, fresh: Chain<S>) {
        let (rays, p, h, bridge) =
            (self.cx.rays, self.large_step_probability(), self.mis_level, self.stats.bridge.level);
        *self = fresh;
        self.cx.rays += rays;
        self.set_large_step_probability(p);
        self.mis_level = h;
        self.stats.bridge.level = bridge;
    }

    /// Adds this chain's states and large steps to the bridge estimate of its target's
    /// normalisation at level `h` ([`super::bridge`]; 0: not).
    pub fn set_bridge_level(&mut self, h: f32) {
        self.stats.bridge.level = f64::from(h);
    }

    /// Combines this chain with independent samples of density level `h` in target units: a
    /// state of value `f` then splats with the weight `f/(f + h)` (0: the chain alone).
    pub fn set_mis_level(&mut self, h: f32) {
        self.mis_level = h;
    }

    /// The probability that this chain's proposals are large steps.
    pub fn large_step_probability(&self) -> f32 {
        self.cx.sampler.large_step_probability()
    }

    /// Sets the probability that this chain's proposals are large steps; it stays with the
    /// chain when states are exchanged or restarted.
    pub fn set_large_step_probability(&mut self, p: f32) {
        self.cx.sampler.set_large_step_probability(p);
    }

    /// The current state.
    pub fn state(&self) -> &S {
        &self.current
    }

    pub fn state_mut(&mut self) -> &mut S {
        &mut self.current
    }

    /// Exchanges the whole states (primary-sample vector with its stamps, and the evaluated
    /// state) of two chains; each keeps its random numbers for acceptance, its statistics and
    /// its large-step probability.
    pub fn exchange(&mut self, other: &mut Chain<S>) {
        let (p, q) = (self.large_step_probability(), other.large_step_probability());
        std::mem::swap(&mut self.cx.sampler, &mut other.cx.sampler);
        std::mem::swap(&mut self.current, &mut other.current);
        std::mem::swap(&mut self.cx.held, &mut other.cx.held);
        std::mem::swap(&mut self.cx.held_paths, &mut other.cx.held_paths);
        self.set_large_step_probability(p);
        other.set_large_step_probability(q);
    }

    /// Makes up to `mutations` mutations, checking `stop` every 256, splatting into `splats`
    /// when given; returns how many were made. The time spent is added to the statistics.
    pub fn run(
        &mut self,
        target: &impl Target<State = S>,
        mutations: u64,
        splats: Option<&SharedSplats>,
        stop: &dyn Fn() -> bool,
    ) -> u64 {
        self.run_observed(target, mutations, splats, stop, |_| {})
    }

    /// [`Self::run`], showing each large-step proposal to `observe` ([`Self::mutate_observed`]).
    pub fn run_observed(
        &mut self,
        target: &impl Target<State = S>,
        mutations: u64,
        splats: Option<&SharedSplats>,
        stop: &dyn Fn() -> bool,
        mut observe: impl FnMut(&mut S),
    ) -> u64 {
        let start = std::time::Instant::now();
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            self.mutate_observed(target, splats, &mut observe);
            done += 1;
        }
        self.stats.seconds += start.elapsed().as_secs_f64();
        done
    }

    /// One mutation: propose, splat proposal and current state with their expected weights
    /// (when `splats` is given), accept or reject. Not timed: callers that interleave chains
    /// (replica ensembles) time whole sweeps.
    pub fn mutate(&mut self, target: &impl Target<State = S>, splats: Option<&SharedSplats>) {
        self.mutate_observed(target, splats, |_| {});
    }

    /// [`Self::mutate`], showing each large-step proposal, once evaluated, to `observe`: a
    /// large step is an independent uniform sample, which replica ensembles also value under
    /// their other targets to refine those targets' normalisations.
    pub fn mutate_observed(
        &mut self,
        target: &impl Target<State = S>,
        splats: Option<&SharedSplats>,
        observe: impl FnMut(&mut S),
    ) {
        let h = self.mis_level;
        self.mutate_splatting(target, observe, |c, weight| {
            if let Some(splats) = splats
                && weight > 0.0
                && c.value() > 0.0
            {
                c.splat(splats, weight / (c.value() + h));
            }
        });
    }

    /// [`Self::mutate_observed`] with the splatting left to `splat`, which is shown the
    /// proposal with its acceptance probability `a`, then the current state with `1 − a`
    /// (expected-value splatting with weights of the caller's choosing: replica ensembles
    /// that reuse every replica weight each state by the balance heuristic over their targets).
    pub fn mutate_splatting(
        &mut self,
        target: &impl Target<State = S>,
        mut observe: impl FnMut(&mut S),
        mut splat: impl FnMut(&mut S, f32),
    ) {
        let jumps = self.cx.sampler.jump_probability();
        if jumps > 0.0 && self.rng.next_f32() < jumps {
            return self.jump(target, splat);
        }
        self.cx.sampler.start_iteration();
        if self.cx.sampler.is_lens_step() {
            return self.lens(target, splat);
        }
        let large = self.cx.sampler.is_large_step();
        let film = self.cx.sampler.is_film_step();
        if film && self.current.film_unread() {
            // The proposal is the state itself, accepted: no evaluation needed.
            self.cx.sampler.reject();
            let s = &mut self.stats;
            s.mutations += 1;
            s.small_steps_proposed += 1;
            s.small_steps_accepted += 1;
            s.film_steps_proposed += 1;
            s.film_steps_accepted += 1;
            return self.stay(&mut splat);
        }
        self.proposal = target.evaluate(&mut self.cx, std::mem::take(&mut self.proposal));
        if self.clamp.is_finite() {
            self.proposal.clamp_value(self.clamp);
        }
        if large {
            observe(&mut self.proposal);
        }
        let s = &mut self.stats;
        s.invalid += u64::from(self.proposal.invalid());
        if large {
            self.large.push(f64::from(self.proposal.value()));
            s.large_steps_proposed += 1;
        } else {
            s.small_steps_proposed += 1;
            s.film_steps_proposed += u64::from(film);
        }
        let (pv, cv) = (self.proposal.value(), self.current.value());
        let a = if cv > 0.0 { (pv / cv).min(1.0) } else { 1.0 };
        let h = s.bridge.level;
        if h > 0.0 && large {
            s.bridge.uniform.push(f64::from(pv) / (f64::from(pv) + h));
        }
        s.mutations += 1;
        let changed = self.proposal.technique() != self.current.technique();
        if self.settle(a, &mut splat) {
            let s = &mut self.stats;
            s.technique_changes += u64::from(changed);
            if large {
                s.large_steps_accepted += 1;
            } else {
                s.small_steps_accepted += 1;
                s.film_steps_accepted += u64::from(film);
            }
        }
    }

    /// A step that keeps the state without evaluating a proposal (a film step of a state that
    /// does not read its film numbers, or a jump that found no path to propose): the state
    /// splats alone and adds itself to the bridge sums. The caller counts the step.
    fn stay(&mut self, splat: &mut impl FnMut(&mut S, f32)) {
        let h = self.stats.bridge.level;
        if h > 0.0 {
            self.stats.bridge.states.push(1.0 / (f64::from(self.current.value()) + h));
        }
        self.stats.splat_weight += f64::from(self.current.weight());
        splat(&mut self.current, 1.0);
    }

    /// Settles the evaluated proposal, accepted with probability `a`: adds the step to the
    /// bridge sums, splats proposal and current state with their expected weights, and accepts
    /// (keeping the proposal's held evaluation) or rejects. Returns whether it accepted.
    fn settle(&mut self, a: f32, splat: &mut impl FnMut(&mut S, f32)) -> bool {
        let h = self.stats.bridge.level;
        if h > 0.0 {
            let (pv, cv, a) = (f64::from(self.proposal.value()), f64::from(self.current.value()), f64::from(a));
            self.stats.bridge.states.push(a / (pv + h) + (1.0 - a) / (cv + h));
        }
        self.stats.splat_weight += f64::from(a * self.proposal.weight() + (1.0 - a) * self.current.weight());
        splat(&mut self.proposal, a);
        splat(&mut self.current, 1.0 - a);
        let accepted = self.rng.next_f32() < a;
        if accepted {
            std::mem::swap(&mut self.current, &mut self.proposal);
            self.cx.sampler.accept();
            self.cx.hold();
        } else {
            self.cx.sampler.reject();
        }
        accepted
    }
}

impl<S: State> Chain<S> {
    /// A lens step ([`super::lens`]), begun by the sampler (a film step where the state has
    /// none), accepted with `min(1, f(y)/f(x) · J)`.
    fn lens(&mut self, target: &impl Target<State = S>, mut splat: impl FnMut(&mut S, f32)) {
        let s = &mut self.stats;
        s.mutations += 1;
        s.small_steps_proposed += 1;
        let (jacobian, lens) = match target.lens_step(&mut self.cx, &mut self.rng, &self.current, &mut self.proposal) {
            LensStep::Stay => {
                self.cx.sampler.reject();
                self.stats.small_steps_accepted += 1;
                return self.stay(&mut splat);
            }
            LensStep::Reject => {
                self.cx.sampler.reject();
                self.stats.lens_steps_proposed += 1;
                return self.stay(&mut splat);
            }
            LensStep::Proposed { jacobian, lens } => (jacobian, lens),
        };
        if self.clamp.is_finite() {
            self.proposal.clamp_value(self.clamp);
        }
        let s = &mut self.stats;
        s.lens_steps_proposed += u64::from(lens);
        s.film_steps_proposed += u64::from(!lens);
        s.invalid += u64::from(self.proposal.invalid());
        let (pv, cv) = (self.proposal.value(), self.current.value());
        let a = if cv > 0.0 && jacobian > 0.0 { (pv / cv * jacobian).min(1.0) } else { 0.0 };
        if self.settle(if a.is_finite() { a } else { 0.0 }, &mut splat) {
            let s = &mut self.stats;
            s.small_steps_accepted += 1;
            s.lens_steps_accepted += u64::from(lens);
            s.film_steps_accepted += u64::from(!lens);
        }
    }

    /// A reversible jump ([`Target::jump`]) in place of a mutation, accepted with
    /// `min(1, f(y)/f(x) · J)`; where none is begun the current state stays and splats alone.
    fn jump(&mut self, target: &impl Target<State = S>, mut splat: impl FnMut(&mut S, f32)) {
        self.stats.mutations += 1;
        self.stats.jumps_proposed += 1;
        let Some(jacobian) = target.jump(&mut self.cx, &mut self.rng, &self.current, &mut self.proposal) else {
            return self.stay(&mut splat);
        };
        if self.clamp.is_finite() {
            self.proposal.clamp_value(self.clamp);
        }
        self.stats.invalid += u64::from(self.proposal.invalid());
        let (pv, cv) = (self.proposal.value(), self.current.value());
        let a = if cv > 0.0 && jacobian > 0.0 { (pv / cv * jacobian).min(1.0) } else { 0.0 };
        if self.settle(if a.is_finite() { a } else { 0.0 }, &mut splat) {
            self.stats.jumps_accepted += 1;
            self.stats.technique_changes += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::{Heuristic, Tempering};
    use crate::mcmc::TemperedTarget;
    use crate::sampler::PssSampler;

    /// Exchanging two chains' states moves the primary-sample vectors and evaluated states but
    /// leaves each chain its large-step probability (a property of the replica's slot), and a
    /// restarted chain keeps it too.
    #[test]
    fn exchanged_and_restarted_chains_keep_their_large_step_probability() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(16, 16);
        let target =
            TemperedTarget::new(&scene, 2, Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: false }, 0.0);
        let start = |seed| {
            let mut seed = seed;
            loop {
                let chain = Chain::start(&target, PssSampler::new(seed, 0, 0.01, 0.3), Pcg32::new(seed, 1), 2);
                if chain.state().value() > 0.0 {
                    return chain;
                }
                seed += 100;
            }
        };
        let (mut a, mut b) = (start(1), start(2));
        b.set_large_step_probability(1.0);
        let (va, vb) = (a.state().value(), b.state().value());
        assert_ne!(va, vb);
        a.exchange(&mut b);
        assert_eq!((a.state().value(), b.state().value()), (vb, va));
        assert_eq!((a.large_step_probability(), b.large_step_probability()), (0.3, 1.0));
        b.restart(start(3));
        assert_eq!(b.large_step_probability(), 1.0);
        // Every proposal of a chain with probability 1 is a large step.
        for _ in 0..50 {
            b.mutate(&target, None);
        }
        assert_eq!(b.stats.large_steps_proposed, 50);
    }

    /// A film step of a state that does not read its film numbers (light tracing, `t = 1`)
    /// proposes the state itself: the state stays and no ray is traced. Every other state's
    /// film step is evaluated.
    #[test]
    fn film_steps_of_states_that_do_not_read_the_film_trace_nothing() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(16, 16);
        let target =
            TemperedTarget::new(&scene, 2, Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: false }, 0.0);
        let (mut unread, mut read) = (0, 0);
        for seed in 0..200 {
            let sampler = PssSampler::new(seed, 0, 0.01, 0.0).with_film_steps(1.0, 0.02);
            let mut chain = Chain::start(&target, sampler, Pcg32::new(seed, 1), 2);
            for _ in 0..5 {
                let (rays, value) = (chain.rays(), chain.state().value());
                if chain.state().film_unread() {
                    unread += 1;
                    chain.mutate(&target, None);
                    assert_eq!((chain.rays(), chain.state().value()), (rays, value));
                } else {
                    read += 1;
                    chain.mutate(&target, None);
                    assert!(chain.rays() > rays);
                }
            }
            assert_eq!((chain.stats.film_steps_proposed, chain.stats.small_steps_proposed), (5, 5));
        }
        assert!(unread > 100 && read > 300, "{unread} states without film numbers, {read} with");
    }
}
