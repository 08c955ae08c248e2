//! The tempered MMLT target (Šik & Křivánek 2016): replica `j` evaluates a state of depth `k`
//! exactly as MMLT does, then weighs it with the BSDFs at the connection vertices roughened by
//! `a_j` ([`crate::bidir::tempered`]). A state keeps its subpaths and connection, so its value
//! under any other replica's target (the cross-evaluations swaps need) costs no rays, and a
//! stored state re-evaluated under its own target reproduces its cached value exactly. The
//! contribution a state splats is always the untempered one (replica 0's).

use super::{Contribution, EvalContext, Evaluated, State, Target, evaluate_connection};
use crate::bidir::{Paths, TemperScratch, Tempering, tempered};
use crate::film::SharedSplats;
use crate::scene::Scene;

/// A state of one replica: its untempered contribution, its value under the target of the
/// replica that holds it, and the cached path.
#[derive(Default)]
pub struct TemperedState {
    pub contribution: Contribution,
    pub value: f32,
    pub evaluated: Option<Evaluated>,
    pub paths: Paths,
    /// Values of this state under the targets of its ensemble, by replica index (NaN: not
    /// computed yet); cleared whenever the state is evaluated afresh. Only valid while the
    /// ensemble's ladder is fixed.
    pub cross: Vec<f32>,
    scratch: TemperScratch,
}

impl TemperedState {
    /// This state's value under `targets[l]` (the targets of its ensemble, by replica index),
    /// computed once and cached in [`Self::cross`]: the swap step, the state's re-valuation
    /// after an exchange, the reuse weights and the large-step moments all ask for the same
    /// numbers, and a cached value is the fresh one bit for bit.
    pub fn value_under(&mut self, l: usize, targets: &[TemperedTarget]) -> f32 {
        if self.cross.len() != targets.len() {
            self.cross.clear();
            self.cross.resize(targets.len(), f32::NAN);
        }
        let mut v = self.cross[l];
        if v.is_nan() {
            v = targets[l].value_of(self);
            self.cross[l] = v;
        }
        v
    }

    /// Records that this state, held by replica `j` of an ensemble of `replicas`, has its own
    /// value there (what [`Self::value_under`] would compute for `j`).
    pub fn note_own_value(&mut self, j: usize, replicas: usize) {
        if self.cross.len() != replicas {
            self.cross.clear();
            self.cross.resize(replicas, f32::NAN);
        }
        self.cross[j] = self.value;
    }
}

impl State for TemperedState {
    fn value(&self) -> f32 {
        self.value
    }

    fn invalid(&self) -> bool {
        self.contribution.invalid
    }

    fn technique(&self) -> usize {
        self.contribution.technique
    }

    fn film_unread(&self) -> bool {
        self.contribution.film_unread
    }

    fn splat(&self, splats: &SharedSplats, scale: f32) {
        self.contribution.splat(splats, scale);
    }

    fn weight(&self) -> f32 {
        if self.value > 0.0 { crate::math::luminance(self.contribution.l) / self.value } else { 0.0 }
    }
}

/// How the targets of hot replicas are flattened.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Flattening {
    /// For `τ ≤ 1` the scene with the connection vertices roughened by `a = τ`; beyond, the
    /// fully roughened value raised to `β = 1/τ` (a flatter target where roughening alone
    /// saturates: every lobe at `α = 1`).
    #[default]
    Roughen,
    /// The scene's own value raised to `β = 1 − τ` (`τ ≤ 1`; at 1 the target is uniform over
    /// the paths that carry light): the classic tempered target of parallel tempering, which
    /// flattens every path, diffuse or glossy, and keeps its modes where they are.
    Power,
}

/// The target of one replica of depth `depth` at temperature `τ`, flattened as
/// [`Flattening`] says.
#[derive(Clone, Copy)]
pub struct TemperedTarget<'a> {
    pub scene: &'a Scene,
    pub depth: usize,
    /// The roughening `a` and how the roughened weights are computed.
    pub temper: Tempering,
    /// The temperature `τ` (0: the scene itself).
    tau: f32,
    /// The map shaping the target per pixel ([`super::importance`]; `None`: MMLT's).
    pub importance: Option<&'a super::importance::ImportanceMap>,
    flattening: Flattening,
}

impl<'a> TemperedTarget<'a> {
    /// The target of depth `depth` at temperature `tau`.
    pub fn new(scene: &'a Scene, depth: usize, temper: Tempering, tau: f32) -> Self {
        Self::flattened(scene, depth, temper, tau, Flattening::Roughen)
    }

    /// The target of depth `depth` at temperature `tau`, flattened as `flattening` says.
    pub fn flattened(scene: &'a Scene, depth: usize, temper: Tempering, tau: f32, flattening: Flattening) -> Self {
        let mut target = Self { scene, depth, temper, tau: 0.0, flattening, importance: None };
        target.set_temperature(tau);
        target
    }

    /// The target shaped by `importance` per pixel ([`super::importance`]).
    pub fn with_importance(self, importance: Option<&'a super::importance::ImportanceMap>) -> Self {
        Self { importance, ..self }
    }

    pub fn temperature(&self) -> f32 {
        self.tau
    }

    pub fn set_temperature(&mut self, tau: f32) {
        self.tau = tau;
        self.temper.a = match self.flattening {
            Flattening::Roughen => tau.min(1.0),
            Flattening::Power => 0.0,
        };
    }

    /// The value of `state` (evaluated under any replica's target) under this target; no rays.
    pub fn value_of(&self, state: &mut TemperedState) -> f32 {
        if self.flattening == Flattening::Power && self.tau > 0.0 {
            let f = state.contribution.f;
            return if f > 0.0 { f.powf(1.0 - self.tau.min(1.0)) } else { 0.0 };
        }
        if self.temper.a <= 0.0 {
            return state.contribution.f;
        }
        // By reference: an evaluated state holds its connection's sampled vertex.
        let Some(e) = &state.evaluated else { return 0.0 };
        let Some(c) = &e.connection else { return 0.0 };
        let (l, w) = tempered(self.scene, state.paths.subpaths(), (e.s, e.t), c, &self.temper, &mut state.scratch);
        // An invalid value has a zero contribution.
        let f = e.contribution(l, w).f;
        if self.tau > 1.0 && f > 0.0 { f.powf(1.0 / self.tau) } else { f }
    }
}

impl Target for TemperedTarget<'_> {
    type State = TemperedState;

    /// Evaluates the state (its subpaths kept in the state itself, for the cross-evaluations).
    fn evaluate(&self, cx: &mut EvalContext, recycled: TemperedState) -> TemperedState {
        let mut out = recycled;
        let e = evaluate_connection(self.scene, self.depth, cx, &mut out.paths, self.importance);
        out.contribution = e.untempered();
        out.evaluated = Some(e);
        out.cross.clear();
        out.value = self.value_of(&mut out);
        out
    }

    /// As MMLT normalises the depth: replica 0's target is MMLT's.
    fn normaliser(&self, seed: u64, samples: usize, clamp: f32) -> Option<(super::NormaliserMoments, u64)> {
        super::all_strategies::depth_normaliser(self.scene, self.depth, seed, samples, (clamp, self.importance))
    }

    /// The main target's depth: the scene's own paths, unflattened.
    fn independent_depth(&self) -> Option<usize> {
        (self.depth >= 1 && self.tau == 0.0).then_some(self.depth)
    }

    /// The main target is MMLT's.
    fn hybrid_depth(&self) -> Option<usize> {
        (self.tau == 0.0).then_some(self.depth)
    }

    /// The main target values a state as MMLT does at every depth, so its bootstraps are
    /// MMLT's, valued at all depths together.
    fn values_groups_together(&self) -> bool {
        self.tau == 0.0
    }

    fn value_groups(&self, cx: &mut EvalContext, groups: usize, out: &mut Vec<crate::mcmc::GroupValue>) -> u64 {
        super::evaluate_depths(self.scene, groups, cx, out, self.importance)
    }

    /// A state keeps its path, so the jump is planned from it.
    fn jump(
        &self,
        cx: &mut EvalContext,
        rng: &mut crate::math::rng::Pcg32,
        current: &TemperedState,
        proposal: &mut TemperedState,
    ) -> Option<f32> {
        let e = current.evaluated.as_ref()?;
        let plan = super::jump::plan(self.scene, self.depth, e, &current.paths, rng)?;
        plan.apply(&mut cx.sampler);
        *proposal = self.evaluate(cx, std::mem::take(proposal));
        Some(proposal.evaluated.as_ref().map_or(0.0, |n| plan.jacobian(e, n, &proposal.paths)))
    }

    /// A state keeps its path, so the lens step is planned from it.
    fn lens_step(
        &self,
        cx: &mut EvalContext,
        rng: &mut crate::math::rng::Pcg32,
        current: &TemperedState,
        proposal: &mut TemperedState,
    ) -> super::lens::LensStep {
        use super::lens::{LensStep, jacobian, plan};
        let plan = current.evaluated.as_ref().and_then(|e| plan(self.scene, e, &current.paths));
        match &plan {
            None if current.film_unread() => return LensStep::Stay,
            Some(p) if !p.pin(self.scene, cx, rng) => return LensStep::Reject,
            _ => {}
        }
        *proposal = self.evaluate(cx, std::mem::take(proposal));
        let jacobian = jacobian(self.scene, plan.as_ref(), proposal.evaluated.as_ref(), &proposal.paths);
        LensStep::Proposed { jacobian, lens: plan.is_some() }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::Heuristic;
    use crate::mcmc::evaluate;
    use crate::sampler::PssSampler;

    #[test]
    fn cached_states_re_evaluate_exactly_and_cross_evaluations_match_fresh_ones() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(32, 32);
        let ladder = [0.0, 0.05, 0.2, 0.6, 1.0, 4.0];
        let (mut nonzero, mut differs) = (0, 0);
        for (roughen_mis, flattening) in
            [(true, Flattening::Roughen), (false, Flattening::Roughen), (false, Flattening::Power)]
        {
            let target = |depth, a: f32| {
                let temper = Tempering { a, heuristic: Heuristic::Power, roughen_mis };
                TemperedTarget::flattened(&scene, depth, temper, a.min(1.0), flattening)
            };
            for i in 0..4000u64 {
                let depth = 1 + (i % 4) as usize;
                let j = (i / 4 % 6) as usize;
                let fresh = || EvalContext::new(PssSampler::new(i, 0, 0.01, 0.3));
                let mut state = target(depth, ladder[j]).evaluate(&mut fresh(), TemperedState::default());
                // Replica 0's view is MMLT's target, bit for bit.
                let mmlt = evaluate(&scene, depth, &mut fresh(), None);
                assert_eq!(state.contribution, mmlt);
                // Re-evaluating the cached state under its own target reproduces its value.
                let cached = state.value;
                assert_eq!(target(depth, ladder[j]).value_of(&mut state).to_bits(), cached.to_bits());
                // Cross-evaluations equal fresh evaluations under the other targets.
                for &a in &ladder {
                    let other = target(depth, a).evaluate(&mut fresh(), TemperedState::default());
                    let cross = target(depth, a).value_of(&mut state);
                    assert_eq!(cross.to_bits(), other.value.to_bits(), "state {i}, a = {a}");
                    nonzero += usize::from(cross > 0.0);
                    differs += usize::from(cross != state.contribution.f);
                }
            }
        }
        assert!(nonzero > 1000 && differs > 500, "{nonzero} nonzero, {differs} changed by tempering");
    }
}
