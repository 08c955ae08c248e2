//! A Markov chain in primary sample space with expected-value splatting (Veach 1997 §11.5;
//! pbrt-v4 §13.4.3): each proposal `y` from the current state `x` is accepted with
//! `a = min(1, f(y)/f(x))`, and both are splatted as `C/f` with weights `a` and `1 − a`. Values
//! that are NaN, infinite or negative count as zero. The chain keeps its state between calls, so
//! time-budgeted renders can advance all chains in rounds.

use super::{DepthStats, Moments, Paths};
use crate::film::SharedSplats;
use crate::math::rng::Pcg32;
use crate::sampler::PssSampler;

/// What a chain needs of an evaluated state.
pub trait State: Default {
    /// The target value `f` (0 for invalid states).
    fn value(&self) -> f32;
    /// The bidirectional technique the state chose, for the technique-change statistics.
    fn technique(&self) -> usize;
    /// Adds the state's contributions, each times `scale`, to the film.
    fn splat(&self, splats: &SharedSplats, scale: f32);
}

/// Evaluates the sampler's current state into `out`; returns whether its value was invalid
/// (NaN, infinite or negative, counted as zero).
pub trait Target {
    type State: State;
    fn evaluate(&self, sampler: &mut PssSampler, paths: &mut Paths, rays: &mut u64, out: &mut Self::State) -> bool;
}

pub struct Chain<S> {
    sampler: PssSampler,
    rng: Pcg32,
    current: S,
    proposal: S,
    paths: Paths,
    pub stats: DepthStats,
    /// The large-step proposals' values.
    pub large: Moments,
    pub rays: u64,
}

impl<S: State> Chain<S> {
    /// Starts from the state `sampler` holds (its first, large step), evaluated and accepted.
    pub fn start(target: &impl Target<State = S>, mut sampler: PssSampler, rng: Pcg32, depth: usize) -> Self {
        let mut paths = Paths::default();
        let mut rays = 0;
        let mut current = S::default();
        target.evaluate(&mut sampler, &mut paths, &mut rays, &mut current);
        sampler.accept();
        Self {
            sampler,
            rng,
            current,
            proposal: S::default(),
            paths,
            stats: DepthStats { depth, ..DepthStats::default() },
            large: Moments::default(),
            rays,
        }
    }

    /// The current state.
    pub fn state(&self) -> &S {
        &self.current
    }

    pub fn state_mut(&mut self) -> &mut S {
        &mut self.current
    }

    /// Exchanges the whole states (primary-sample vector with its stamps, and the evaluated
    /// state) of two chains; each keeps its random numbers for acceptance and its statistics.
    pub fn exchange(&mut self, other: &mut Chain<S>) {
        std::mem::swap(&mut self.sampler, &mut other.sampler);
        std::mem::swap(&mut self.current, &mut other.current);
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
        let start = std::time::Instant::now();
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            self.mutate(target, splats);
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
        mut observe: impl FnMut(&mut S),
    ) {
        self.sampler.start_iteration();
        let large = self.sampler.is_large_step();
        let invalid = target.evaluate(&mut self.sampler, &mut self.paths, &mut self.rays, &mut self.proposal);
        if large {
            observe(&mut self.proposal);
        }
        let (proposal, current) = (&self.proposal, &self.current);
        let s = &mut self.stats;
        s.invalid += u64::from(invalid);
        if large {
            self.large.push(f64::from(proposal.value()));
            s.large_steps_proposed += 1;
        } else {
            s.small_steps_proposed += 1;
        }
        let a = if current.value() > 0.0 { (proposal.value() / current.value()).min(1.0) } else { 1.0 };
        if let Some(splats) = splats {
            for (c, weight) in [(proposal, a), (current, 1.0 - a)] {
                if weight > 0.0 && c.value() > 0.0 {
                    c.splat(splats, weight / c.value());
                }
            }
        }
        s.mutations += 1;
        if self.rng.next_f32() < a {
            if proposal.technique() != current.technique() {
                s.technique_changes += 1;
            }
            if large {
                s.large_steps_accepted += 1;
            } else {
                s.small_steps_accepted += 1;
            }
            std::mem::swap(&mut self.current, &mut self.proposal);
            self.sampler.accept();
        } else {
            self.sampler.reject();
        }
    }
}
