//! Multiplexed Metropolis light transport (Hachisuka, Kaplanyan & Dachsbacher 2014; pbrt-v4
//! §13.4): per path depth `k`, Markov chains in primary sample space whose states choose one
//! bidirectional strategy each, with target `f = luminance((k+2)·w·f/p)`
//! ([`crate::mcmc::strategy`]), run by the chain driver ([`crate::mcmc::driver`]): one group of
//! chains per depth, mutations allotted in proportion to `b_k`.

use super::{Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::math::rng::Pcg32;
use crate::mcmc::all_strategies::depth_normaliser;
use crate::mcmc::importance::ImportanceMap;
use crate::mcmc::lens::{self, LensStep};
use crate::mcmc::{
    ChainSettings, Contribution, EvalContext, NormaliserMoments, Single, Target, evaluate_connection, evaluate_depths,
};
use crate::scene::Scene;

#[derive(Clone, Copy, Debug)]
pub struct MmltIntegrator {
    pub max_depth: u32,
    /// Bootstrap samples per depth.
    pub bootstrap: usize,
    /// Independent chains per depth.
    pub chains: usize,
    pub sigma: f32,
    /// The probability that a chain proposes a reversible jump between the techniques of its
    /// path instead of a mutation ([`crate::mcmc::jump`]; 0: never).
    pub jumps: f32,
    /// The probability that a small step is a film step, which moves the film position alone
    /// ([`crate::sampler::PssSampler::with_film_steps`]; 0: never).
    pub film_steps: f32,
    /// The probability that a small step is a lens step ([`crate::mcmc::lens`]; 0: never).
    pub lens_steps: f32,
    pub large_step_probability: f32,
    /// Allot mutations by `b_k` times each depth's spread instead of `b_k` alone.
    pub spread_allocation: bool,
    /// Also produce one image per path depth (`depth0` … `depth{max_depth}`), which sum to the
    /// image.
    pub depth_images: bool,
    /// Depths `k ≥ 1` whose bootstrap has fewer non-zero values than this are sampled
    /// independently ([`crate::mcmc::independent`]); 0 (the default, MMLT as published): none.
    pub independent_below: usize,
    /// The share of the chains' rays spent on further samples of the depths' normalisers as
    /// the render goes on ([`crate::mcmc::normaliser`]; 0: the bootstrap's alone).
    pub normaliser_share: f64,
    /// Under a time budget, re-allot the mutations to the depths by their chains' measured
    /// error after this share of it ([`crate::mcmc::adaptive`]); 0 (the default, MMLT as
    /// published): by `b_k` throughout.
    pub reallot_at: f64,
    /// Clamps each depth's target (`k ≥ 1`) at this many times the mean of its bootstrap's
    /// non-zero values, splatting a clamped state's whole contribution over the clamped value
    /// ([`crate::mcmc::Chain::start_clamped`]); 0 (the default, MMLT as published): never.
    pub target_clamp: f64,
    /// Samples of bidirectional path tracing per main-chain mutation, combined with the chains
    /// by multiple importance sampling ([`crate::mcmc::hybrid`]); 0 (the default, MMLT as
    /// published): the chains alone.
    pub hybrid: f64,
    /// What a main-chain mutation counts as in the weights of [`Self::hybrid`]'s combination.
    pub chain_efficiency: f64,
    /// Instead of [`Self::chain_efficiency`], weights that give the BDPT samples this share of
    /// each depth's light ([`crate::mcmc::hybrid::HybridDepth::with_share`]).
    pub sample_share: Option<f64>,
    /// Choose by a pilot ([`crate::integrator::hybrid_pilot`]) between BDPT alone, the chains
    /// alone and their combination, and for a combination [`Self::hybrid`] and
    /// [`Self::chain_efficiency`]; a [`Self::sample_share`] given still sets its weights.
    pub hybrid_auto: bool,
    /// Measure each depth's chain efficiency from two halves of its chains, for the statistics
    /// ([`crate::mcmc::efficiency`]).
    pub measure_efficiency: bool,
    /// Scale each depth's image by the bridge estimate of its normalisation instead of `b` where
    /// [`crate::mcmc::bridge::prefer`] says so at this threshold (`None`: never).
    pub bridge_above: Option<f64>,
    /// Samples per pixel of the BDPT pilot whose image shapes the chains' targets per pixel
    /// ([`crate::mcmc::importance`]); 0 (the default, MMLT as published): no shaping.
    pub importance_pilot: u32,
    /// The shaping's floor `φ` as a fraction of the pilot image's mean.
    pub importance_floor: f64,
    /// The shaping's power `γ` ([`crate::mcmc::importance`]).
    pub importance_power: f64,
    /// The share of a time budget the shaping's pilot takes at most.
    pub importance_share: f64,
    /// The predicted relMSE ratio below which the pilot's map shapes the chains.
    pub importance_below: f64,
}

impl MmltIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self {
            max_depth,
            bootstrap: 20_000,
            chains: 64,
            sigma: 0.01,
            jumps: 0.0,
            film_steps: 0.0,
            lens_steps: 0.0,
            large_step_probability: 0.3,
            spread_allocation: false,
            depth_images: false,
            independent_below: 0,
            normaliser_share: crate::mcmc::normaliser::DEFAULT_SHARE,
            reallot_at: 0.0,
            target_clamp: 0.0,
            hybrid: 0.0,
            chain_efficiency: crate::mcmc::hybrid::DEFAULT_EFFICIENCY,
            sample_share: None,
            hybrid_auto: false,
            measure_efficiency: false,
            bridge_above: Some(crate::mcmc::bridge::DEFAULT_ABOVE),
            importance_pilot: 0,
            importance_floor: crate::mcmc::importance::DEFAULT_FLOOR,
            importance_power: crate::mcmc::importance::DEFAULT_POWER,
            importance_share: crate::integrator::importance_pilot::DEFAULT_SHARE,
            importance_below: crate::integrator::importance_pilot::DEFAULT_BELOW,
        }
    }
}

/// The MMLT target of one path depth.
#[derive(Clone, Copy)]
pub(crate) struct DepthTarget<'a> {
    pub scene: &'a Scene,
    pub depth: usize,
    /// The map shaping the target per pixel ([`crate::mcmc::importance`]; `None`: MMLT's).
    pub importance: Option<&'a ImportanceMap>,
}

impl Target for DepthTarget<'_> {
    type State = Contribution;

    /// Records the evaluation in `cx` (with its subpaths there) for chains that jump.
    fn evaluate(&self, cx: &mut EvalContext, _: Contribution) -> Contribution {
        let mut paths = std::mem::take(&mut cx.paths);
        let e = evaluate_connection(self.scene, self.depth, cx, &mut paths, self.importance);
        cx.paths = paths;
        // Recorded only for chains that jump or take lens steps: a copy per mutation otherwise
        // spent for nothing.
        if cx.sampler.jump_probability() > 0.0 || cx.sampler.lens_step_probability() > 0.0 {
            cx.last = Some(e);
        }
        e.untempered()
    }

    /// Depth 0 (emitters seen directly) from points on the emitters connected to the camera,
    /// deeper paths from every strategy of their depth at once.
    fn normaliser(&self, seed: u64, samples: usize, clamp: f32) -> Option<(NormaliserMoments, u64)> {
        depth_normaliser(self.scene, self.depth, seed, samples, (clamp, self.importance))
    }

    /// Depths `k ≥ 1`, whose all-strategy normaliser can value the clamped target.
    fn clampable(&self) -> bool {
        self.depth >= 1
    }

    fn independent_depth(&self) -> Option<usize> {
        (self.depth >= 1).then_some(self.depth)
    }

    fn hybrid_depth(&self) -> Option<usize> {
        Some(self.depth)
    }

    /// Every depth's bootstrap sample `i` is one primary-sample-space point, valued at all
    /// depths from one camera and one light subpath ([`evaluate_depths`]).
    fn values_groups_together(&self) -> bool {
        true
    }

    fn value_groups(&self, cx: &mut EvalContext, groups: usize, out: &mut Vec<crate::mcmc::GroupValue>) -> u64 {
        evaluate_depths(self.scene, groups, cx, out, self.importance)
    }

    /// The state's path is rebuilt by replaying its numbers ([`crate::mcmc::jump::propose`]).
    fn jump(
        &self,
        cx: &mut EvalContext,
        rng: &mut Pcg32,
        _: &Contribution,
        proposal: &mut Contribution,
    ) -> Option<f32> {
        let (e, jacobian) = crate::mcmc::jump::propose(self.scene, self.depth, cx, rng, self.importance)?;
        *proposal = e.untempered();
        Some(jacobian)
    }

    /// Planned from the state's evaluation held in `cx` ([`crate::mcmc::lens`]).
    fn lens_step(
        &self,
        cx: &mut EvalContext,
        rng: &mut Pcg32,
        current: &Contribution,
        proposal: &mut Contribution,
    ) -> LensStep {
        let plan = cx.held.as_ref().and_then(|e| lens::plan(self.scene, e, &cx.held_paths));
        match &plan {
            None if current.film_unread => return LensStep::Stay,
            Some(p) if !p.pin(self.scene, cx, rng) => return LensStep::Reject,
            _ => {}
        }
        *proposal = self.evaluate(cx, std::mem::take(proposal));
        let jacobian = lens::jacobian(self.scene, plan.as_ref(), cx.last.as_ref(), &cx.paths);
        LensStep::Proposed { jacobian, lens: plan.is_some() }
    }
}

impl Integrator for MmltIntegrator {
    fn name(&self) -> &'static str {
        "mmlt"
    }

    fn layer_names(&self) -> Vec<String> {
        depth_image_names(self.depth_images, self.max_depth)
    }

    /// Renders; the statistics have one row per path depth.
    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        super::importance_pilot::check(
            self.importance_pilot,
            self.hybrid > 0.0 || self.hybrid_auto,
            self.measure_efficiency,
        )?;
        if self.hybrid_auto {
            let chains = Self { hybrid_auto: false, hybrid: 0.0, ..*self };
            return super::hybrid_pilot::render(&chains, self.max_depth, scene, settings, control, |c, s, cx| {
                Self { hybrid: c.ratio, chain_efficiency: c.efficiency, ..chains }.render(scene, s, cx)
            });
        }
        control.check_memory(self.memory_estimate(scene, settings.threads), "a splat buffer per path depth")?;
        let depths = self.max_depth as usize + 1;
        let chains = ChainSettings::new(self.bootstrap, self.chains, self.sigma, self.large_step_probability)
            .with_jumps(self.jumps)
            .with_film_steps(self.film_steps)
            .with_lens_steps(self.lens_steps)
            .with_spread_allocation(self.spread_allocation)
            .with_group_images(self.depth_images)
            .with_independent_below(self.independent_below)
            .with_normaliser_share(self.normaliser_share)
            .with_reallot_at(self.reallot_at)
            .with_clamp(self.target_clamp)
            .with_hybrid(self.hybrid)
            .with_chain_efficiency(self.chain_efficiency)
            .with_sample_share(self.sample_share)
            .with_measured_efficiency(self.measure_efficiency)
            .with_bridge_above(self.bridge_above);
        let shaping = self.shaping();
        super::importance_pilot::render(shaping, self.max_depth, scene, settings, control, |importance, s, c| {
            let target = |depth| DepthTarget { scene, depth, importance };
            let start = |cx: crate::mcmc::StartContext| {
                let k = cx.group.k;
                Single::start(cx, target(k))
            };
            chains.render(scene, s, c, depths, target, start, None)
        })
    }

    fn memory_estimate(&self, scene: &Scene, _threads: usize) -> u64 {
        use crate::integrator::memory::{SHARED_SPLAT_BYTES, pixels};
        let images = if self.depth_images { 12 * (u64::from(self.max_depth) + 1) } else { 0 };
        let depths = u64::from(self.max_depth) + 1;
        let hybrid = crate::mcmc::hybrid::film_buffers(self.hybrid, self.depth_images, depths);
        // With the efficiency measured or the mutations re-allotted, the odd walkers' buffers
        // of every depth.
        let halves = if self.measure_efficiency || self.reallot_at > 0.0 { 2 } else { 1 };
        pixels(scene)
            .saturating_mul(12 + images + (halves * depths + hybrid) * SHARED_SPLAT_BYTES)
            .saturating_add(crate::mcmc::shared_bootstrap_bytes(self.bootstrap, depths as usize))
    }
}

impl MmltIntegrator {
    /// How the chains' targets are shaped per pixel.
    fn shaping(&self) -> super::importance_pilot::Shaping {
        super::importance_pilot::Shaping {
            spp: self.importance_pilot,
            floor: self.importance_floor,
            power: self.importance_power,
            share: self.importance_share,
            below: self.importance_below,
        }
    }
}

/// The names of the per-depth images of a Markov-chain render (none unless asked for).
pub(crate) fn depth_image_names(wanted: bool, max_depth: u32) -> Vec<String> {
    if wanted { (0..=max_depth).map(|k| format!("depth{k}")).collect() } else { Vec::new() }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The estimate counts the table of every bootstrap sample's value at every depth, which
    /// the depths' shared bootstrap holds at once (here far more than the 1×1 film's buffers).
    #[test]
    fn the_memory_estimate_counts_the_shared_bootstrap() {
        let mut scene = crate::scenes::default_scene().build().unwrap();
        scene.set_resolution(1, 1);
        let mmlt = MmltIntegrator { bootstrap: 1_000_000, ..MmltIntegrator::new(999) };
        let table = 1_000_000 * 1000 * std::mem::size_of::<crate::mcmc::GroupValue>() as u64;
        assert!(mmlt.memory_estimate(&scene, 1) >= table);
        let tempered = crate::integrator::TemperedIntegrator {
            bootstrap: 1_000_000,
            ..crate::integrator::TemperedIntegrator::new(999)
        };
        assert!(tempered.memory_estimate(&scene, 1) >= table);
    }
}
