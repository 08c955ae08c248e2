//! The tempered MMLT integrator: MMLT's driver (bootstrap, budgets, `b_k` refinement,
//! determinism) with one replica ensemble per chain at the depths `k ≥ 1` that keep ensembles
//! ([`TemperedIntegrator::ensembles_below`]; 0: every depth `k ≥ 1`). Depth 0, whose only
//! strategy has no connection vertex, and the other depths run MMLT's chains
//! ([`super::walker`]). Before any chain runs, the bootstrap's independent acceptance
//! ([`independent_acceptance`]) decides whether chains can pay on the scene at all
//! ([`TemperedIntegrator::bdpt_above`]): where uniform samples land on the light about as
//! often as a chain's states would, the render is bidirectional path tracing alone.

use super::walker::TemperedWalker;
use super::{
    Ensemble, EnsembleSettings, EquiEnergy, Neighbor, Permutation, Replicas, SwapKernel, Tuning, TuningMethod,
};
use crate::bidir::{Heuristic, Tempering};
use crate::integrator::importance_pilot;
use crate::integrator::mmlt::DepthTarget;
use crate::integrator::{
    BdptIntegrator, Budget, Integrator, LadderTuning, RenderControl, RenderOutput, RenderSettings, ReplicaSplats, Swap,
};
use crate::math::rng::{Pcg32, hash};
use crate::mcmc::acceptance::independent_acceptance;
use crate::mcmc::bootstrap::count_nonzero;
use crate::mcmc::importance::ImportanceMap;
use crate::mcmc::{Bootstraps, ChainSettings, Flattening, Single, StartContext, TemperedTarget};
use crate::scene::Scene;
use std::time::Instant;

/// Rings of the equi-energy strategy.
const RINGS: usize = 8;

#[derive(Clone, Debug)]
pub struct TemperedIntegrator {
    pub max_depth: u32,
    pub bootstrap: usize,
    /// Ensembles per depth.
    pub chains: usize,
    pub sigma: f32,
    /// The probability that a chain proposes a reversible jump between the techniques of its
    /// path instead of a mutation ([`crate::mcmc::jump`]; 0: never).
    pub jumps: f32,
    /// The probability that a small step is a film step ([`crate::sampler::PssSampler::with_film_steps`]).
    pub film_steps: f32,
    /// The probability that a small step is a lens step ([`crate::mcmc::lens`]).
    pub lens_steps: f32,
    pub large_step_probability: f32,
    /// Allot mutations by `b_k` times each depth's spread instead of `b_k` alone.
    pub spread_allocation: bool,
    /// With [`Self::spread_allocation`] and [`Self::ensembles_below`], the spread counts only at
    /// the depths whose bootstrap is that sparse; the others are allotted by `b_k`, as MMLT
    /// allots them.
    pub spread_only_sparse: bool,
    /// Replicas per ensemble (1: plain MMLT).
    pub replicas: usize,
    pub swap: Swap,
    /// Temperatures of replicas `1 … K−1` (`τ_0 = 0`; up to 1 a roughening, beyond a power
    /// `1/τ` of the fully roughened target), fixed; empty: [`Self::default_ladder`], tuned as
    /// [`Self::tuning`] says.
    pub ladder: Vec<f32>,
    /// The highest temperature the tuning may reach (1: roughening only).
    pub max_temperature: f32,
    /// A depth whose tuned ladder still swaps neighbours more often than this runs plain MMLT
    /// chains instead of ensembles (its replicas barely differ); `None`: never.
    pub collapse_above: Option<f64>,
    /// A depth whose tuned ladder swaps neighbours less often than this runs plain MMLT chains
    /// (its hot replicas' targets are far from the main one: their reused samples and their
    /// swaps buy less than their rays cost); `None`: never.
    pub collapse_below: Option<f64>,
    /// Sweeps of the pilot that decides, per depth, whether its ensembles pay for their
    /// replicas (measured against plain MMLT chains; 0: ensembles at every depth).
    pub pilot: u64,
    /// Ensembles only at the depths whose bootstrap holds fewer than this many non-zero
    /// values; the others run plain MMLT chains (0: ensembles at every depth `k ≥ 1`). Where
    /// the bootstrap holds thousands of states with light, a depth's chains start spread over
    /// its modes and mix as they are; where it holds a few, they all start from those few,
    /// and a hot replica, which finds light more easily, is what moves them on.
    pub ensembles_below: usize,
    /// Recompute MIS weights from the roughened densities (default: keep the scene's, which
    /// measured better at equal time on the default scene; see the README).
    pub roughen_mis: bool,
    /// How each depth's shared ladder is tuned (without a fixed ladder).
    pub tuning: LadderTuning,
    /// Sweeps of the burn-in that tunes the ladder with [`LadderTuning::BurnIn`].
    pub burn_in: u64,
    /// Neighbour-swap acceptance the tuning aims at.
    pub swap_target: f64,
    /// Every replica contributes to the image (balance heuristic over the replicas' targets)
    /// instead of replica 0 alone (default: on, which measured better on every scene tried;
    /// see the README).
    pub reuse_replicas: bool,
    /// With reuse, which of each replica's states splat (default: proposals and current
    /// states with their expected weights; see the README).
    pub replica_splats: ReplicaSplats,
    /// How the hot replicas' targets are flattened (default: roughening, the paper's).
    pub flattening: Flattening,
    /// Sweeps between swap steps (1: a swap step after every sweep).
    pub swap_every: u64,
    /// Sweeps between mutations of replicas `1 … K−1` (1: every replica mutates every sweep).
    pub hot_every: u64,
    /// Large-step probability of replicas `1 … K−1` (`None`: [`Self::large_step_probability`]).
    pub hot_large_step: Option<f32>,
    /// With [`Swap::Mixture`], the weight `w` of the hotter targets in the mixture
    /// `f_0 + w Σ_{l ≥ 1} f_l/ρ_l` (1: every target's share equal).
    pub hot_weight: f64,
    /// Samples of bidirectional path tracing per main-chain mutation, combined with replica 0's
    /// splats by multiple importance sampling ([`crate::mcmc::hybrid`]; 0: none). Needs replica
    /// 0 alone writing the image.
    pub hybrid: f64,
    /// What a main-chain mutation counts as in [`Self::hybrid`]'s weights.
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
    /// Scale each depth's replica-0 layer by the bridge estimate of its normalisation instead
    /// of `b` where [`crate::mcmc::bridge::prefer`] says so at this threshold (`None`: never).
    pub bridge_above: Option<f64>,
    /// Also produce one image per path depth (`depth0` … `depth{max_depth}`), which sum to the
    /// image.
    pub depth_images: bool,
    /// Depths `k ≥ 1` whose bootstrap has fewer non-zero values than this are sampled
    /// independently ([`crate::mcmc::independent`]): their chains, all started from a few
    /// states, would not mix, with or without replicas. 0: none.
    pub independent_below: usize,
    /// The share of the chains' rays spent on further samples of the depths' normalisers as
    /// the render goes on ([`crate::mcmc::normaliser`]; 0: the bootstrap's alone).
    pub normaliser_share: f64,
    /// Under a time budget, re-allot the mutations to the depths by their measured error after
    /// this share of it, where the chains have made enough mutations by then to measure
    /// ([`crate::mcmc::adaptive`]; 0: never).
    pub reallot_at: f64,
    /// Render by bidirectional path tracing alone where the bootstrap's
    /// [`independent_acceptance`] exceeds this: the scene's light is found as well by
    /// independent samples as by chains, and BDPT, which values every strategy of every depth
    /// of each sample, then wins at equal time (`None`: never; nor with `hybrid`, per-depth
    /// images or the chains' efficiency measured, which are the chains' own).
    pub bdpt_above: Option<f64>,
    /// Samples per pixel of the BDPT pilot whose image shapes the chains' targets per pixel
    /// where the chains render ([`crate::mcmc::importance`]; 0: no shaping; 16 unless the
    /// render says otherwise).
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

/// [`TemperedIntegrator::bdpt_above`]'s default: between the scenes where the chains were
/// measured to win (the bootstrap's independent acceptance 0.006–0.011 on the twin caustics
/// and veach-ajar) and those where BDPT did (0.04–0.05 on the glossy lamp and veach-mis, 0.09
/// on coffee, 0.15 on the default scene). Classroom (0.013), where BDPT wins too, stays below
/// it: a threshold that low would sit within the twin caustics' seeds (README, "Where the
/// chains cannot pay").
pub const DEFAULT_BDPT_ABOVE: f64 = 0.03;

/// [`TemperedIntegrator::jumps`]' default: the probability of a reversible jump between the
/// techniques of a path in place of a mutation ([`crate::mcmc::jump`]), the one of those
/// screened (0.05, 0.1, 0.2) that lowered the error of both chain scenes, the twin caustics and
/// veach-ajar (README, "Jumps between the techniques of a path").
pub const DEFAULT_JUMPS: f32 = 0.05;

/// [`TemperedIntegrator::film_steps`]' default: the probability that a small step is a film
/// step (README, "Film steps").
pub const DEFAULT_FILM_STEPS: f32 = 0.3;

/// [`TemperedIntegrator::lens_steps`]' default: the probability that a small step is a lens
/// step, on top of the film steps' (README, "Lens steps").
pub const DEFAULT_LENS_STEPS: f32 = 0.3;

impl TemperedIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self {
            max_depth,
            bootstrap: 20_000,
            // Half MMLT's 64: measured against 4, 8, 16 and 64 (README, "Fewer chains").
            chains: 32,
            sigma: 0.01,
            jumps: DEFAULT_JUMPS,
            film_steps: DEFAULT_FILM_STEPS,
            lens_steps: DEFAULT_LENS_STEPS,
            large_step_probability: 0.3,
            // By b_k times spread at the depths with ensembles, by b_k (as MMLT) elsewhere:
            // measured against spread everywhere and b_k alone (README, "Allotted as MMLT
            // where the chains are MMLT's").
            spread_allocation: true,
            spread_only_sparse: true,
            // Two replicas measured better than five at equal time on every scene tried (see
            // the README); the paper's five are `paper()`.
            replicas: 2,
            swap: Swap::Neighbor,
            ladder: Vec::new(),
            max_temperature: 1.0,
            collapse_above: None,
            collapse_below: None,
            pilot: 0,
            // Chosen by measurement against ensembles at every depth and at 512 (README,
            // "Ensembles only where the bootstrap is sparse").
            ensembles_below: 128,
            roughen_mis: false,
            tuning: LadderTuning::Bootstrap,
            burn_in: 500,
            swap_target: 0.234,
            reuse_replicas: true,
            replica_splats: ReplicaSplats::Expected,
            flattening: Flattening::Roughen,
            swap_every: 1,
            hot_every: 1,
            hot_large_step: None,
            hot_weight: 1.0,
            hybrid: 0.0,
            chain_efficiency: crate::mcmc::hybrid::DEFAULT_EFFICIENCY,
            sample_share: None,
            hybrid_auto: false,
            measure_efficiency: false,
            bridge_above: Some(crate::mcmc::bridge::DEFAULT_ABOVE),
            depth_images: false,
            // The depths whose bootstrap found fewer than 40 paths with light: measured against
            // none and 20 (README, "Independent samples where the chains cannot start").
            independent_below: 40,
            normaliser_share: crate::mcmc::normaliser::DEFAULT_SHARE,
            // Measured against the allotment by b_k alone (README, "Re-allotted by the
            // measured error").
            reallot_at: 0.25,
            bdpt_above: Some(DEFAULT_BDPT_ABOVE),
            // Shaped where the pilot predicts a large gain: measured against none (README,
            // "A cheaper pilot, and a choice of where to shape").
            importance_pilot: 16,
            importance_floor: crate::mcmc::importance::DEFAULT_FLOOR,
            importance_power: crate::mcmc::importance::DEFAULT_POWER,
            importance_share: crate::integrator::importance_pilot::DEFAULT_SHARE,
            importance_below: crate::integrator::importance_pilot::DEFAULT_BELOW,
        }
    }

    /// The setup of Šik & Křivánek 2016: MMLT's allotment of mutations by `b_k`, five replicas
    /// at every depth, a roughness-only ladder
    /// tuned for a neighbour acceptance of 0.234 (adaptively, during a burn-in), replica 0
    /// alone writing the image; 64 ensembles per depth, MMLT's chains.
    pub fn paper(max_depth: u32) -> Self {
        Self {
            replicas: 5,
            tuning: LadderTuning::BurnIn,
            spread_allocation: false,
            spread_only_sparse: false,
            max_temperature: 1.0,
            flattening: Flattening::Roughen,
            collapse_above: None,
            collapse_below: None,
            pilot: 0,
            ensembles_below: 0,
            swap_target: 0.234,
            reuse_replicas: false,
            independent_below: 0,
            normaliser_share: 0.0,
            reallot_at: 0.0,
            bridge_above: None,
            bdpt_above: None,
            hybrid: 0.0,
            importance_pilot: 0,
            chains: 64,
            jumps: 0.0,
            film_steps: 0.0,
            lens_steps: 0.0,
            ..Self::new(max_depth)
        }
    }

    /// Geometric spacing from `a_1 = 0.02`, tripling: 0.02, 0.06, 0.18, 0.54, …
    pub fn default_ladder(replicas: usize) -> Vec<f32> {
        (1..replicas).map(|j| 0.02 * 3f32.powi(j as i32 - 1)).collect()
    }

    /// `τ_0 = 0` followed by the ladder: the fixed one (which then decides the number of
    /// replicas), else the default for [`Self::replicas`].
    pub fn ladder(&self) -> Vec<f32> {
        if !self.ladder.is_empty() {
            return std::iter::once(0.0).chain(self.ladder.iter().copied()).collect();
        }
        std::iter::once(0.0).chain(Self::default_ladder(self.replicas)).take(self.replicas.max(1)).collect()
    }
}

impl TemperedIntegrator {
    /// How the ensembles are run and prepared.
    fn ensemble_settings(&self, replicas: usize) -> EnsembleSettings {
        let method = match self.tuning {
            LadderTuning::Bootstrap => Some(TuningMethod::Bootstrap),
            LadderTuning::BurnIn if self.burn_in > 0 => Some(TuningMethod::BurnIn(self.burn_in)),
            _ => None,
        };
        let tune = self.ladder.is_empty() && replicas > 1;
        EnsembleSettings {
            calibration_samples: self.bootstrap,
            reuse_replicas: self.reuse_replicas,
            replica_splats: self.replica_splats,
            swap_every: self.swap_every.max(1),
            hot_every: self.hot_every.max(1),
            hot_large_step: self.hot_large_step,
            tuning: method.filter(|_| tune).map(|method| Tuning {
                method,
                target: self.swap_target,
                max_temperature: self.max_temperature,
                flattening: self.flattening,
            }),
            collapse_above: self.collapse_above,
            collapse_below: self.collapse_below,
            pilot: self.pilot,
            mixture: (self.swap == Swap::Mixture).then_some(self.hot_weight),
        }
    }

    /// Walker `cx.c` of depth `cx.k`: at a plain depth ([`Self::ensembles_below`]) MMLT's
    /// chain, else an ensemble.
    fn start_walker<'a>(
        &self,
        (scene, importance): (&'a Scene, Option<&'a ImportanceMap>),
        ladder: &[f32],
        cx: StartContext,
    ) -> TemperedWalker<'a> {
        let k = cx.group.k;
        if k == 0 || self.plain_depth(cx.bootstrap) {
            return TemperedWalker::Plain(Box::new(Single::start(cx, DepthTarget { scene, depth: k, importance })));
        }
        TemperedWalker::Ensemble(Box::new(self.start_ensemble((scene, importance), ladder, cx)))
    }

    /// Ensemble `cx.c` of depth `cx.k`: replica 0 starts exactly as an MMLT chain, the others
    /// draw their own start states (until the depth's preparation restarts them all).
    fn start_ensemble<'a>(
        &self,
        (scene, importance): (&'a Scene, Option<&'a ImportanceMap>),
        ladder: &[f32],
        cx: StartContext,
    ) -> Ensemble<'a> {
        let (k, c, seed) = (cx.group.k, cx.c, cx.group.seed);
        let kernel = match self.swap {
            // The mixture's chains never swap.
            Swap::Neighbor | Swap::Mixture => SwapKernel::Neighbor(Neighbor),
            Swap::EquiEnergy => SwapKernel::EquiEnergy(EquiEnergy::from_samples(cx.bootstrap, RINGS)),
            Swap::Permutation => SwapKernel::Permutation(Permutation::new(ladder.len())),
        };
        let mut replicas = Replicas { chains: Vec::with_capacity(ladder.len()), targets: Vec::new() };
        for (j, &a) in ladder.iter().enumerate() {
            let target =
                TemperedTarget::flattened(scene, k, self.tempering(), a, self.flattening).with_importance(importance);
            let rng =
                if j == 0 { cx.rng.clone() } else { Pcg32::new(hash(&[seed, 0x7e4b, k as u64, c as u64]), j as u64) };
            let mut chain = cx.start_chain(&target, rng);
            if j > 0 {
                // Only replica 0's statistics are reported: the hotter ones add nothing to the
                // bridge estimate of b.
                chain.set_bridge_level(0.0);
            }
            replicas.chains.push(chain);
            replicas.targets.push(target);
        }
        let rng = Pcg32::new(hash(&[seed, 0x5a4b, k as u64, c as u64]), 11);
        Ensemble::new(replicas, kernel, self.ensemble_settings(ladder.len()), rng)
    }

    /// Whether a depth `k ≥ 1` whose bootstrap values are `bootstrap` runs plain MMLT chains
    /// ([`Self::ensembles_below`]).
    fn plain_depth(&self, bootstrap: &[f32]) -> bool {
        self.ensembles_below > 0 && count_nonzero(bootstrap) >= self.ensembles_below as u64
    }

    fn tempering(&self) -> Tempering {
        Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: self.roughen_mis }
    }
}

impl Integrator for TemperedIntegrator {
    fn name(&self) -> &'static str {
        "tempered"
    }

    fn layer_names(&self) -> Vec<String> {
        crate::integrator::mmlt::depth_image_names(self.depth_images, self.max_depth)
    }

    /// Renders; the statistics carry ladders and swap statistics.
    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        importance_pilot::check(self.importance_pilot, self.hybrid > 0.0 || self.hybrid_auto, self.measure_efficiency)?;
        if self.hybrid_auto {
            if self.swap == Swap::Mixture {
                return Err("--hybrid auto needs replica 0 alone writing the image: no mixture chains".into());
            }
            // Replica 0 alone writes the image the samples are combined with.
            let chains = Self { hybrid_auto: false, hybrid: 0.0, reuse_replicas: false, ..self.clone() };
            return super::super::hybrid_pilot::render(
                &chains,
                self.max_depth,
                scene,
                settings,
                control,
                |c, s, cx| {
                    if c.chains_alone() {
                        // The chains alone, with replica reuse as the integrator has it.
                        Self { hybrid_auto: false, hybrid: 0.0, ..self.clone() }.render(scene, s, cx)
                    } else {
                        Self { hybrid: c.ratio, chain_efficiency: c.efficiency, ..chains.clone() }.render(scene, s, cx)
                    }
                },
            );
        }
        if self.hybrid > 0.0 && (self.reuse_replicas || self.swap == Swap::Mixture) {
            return Err("combining the chains with bidirectional path tracing (hybrid) needs replica 0 \
                        alone writing the image: no replica reuse, no mixture chains"
                .into());
        }
        let bytes = self.memory_estimate(scene, settings.threads);
        control.check_memory(bytes, "a splat buffer per path depth and contributing replica")?;
        let chains = self.chain_settings();
        let ladder = self.ladder();
        let depths = self.max_depth as usize + 1;
        let main = |depth| TemperedTarget::flattened(scene, depth, self.tempering(), 0.0, self.flattening);
        // The chains, shaped per pixel by a pilot where asked (their bootstrap then drawn anew
        // under the shaped targets).
        let shaping = self.shaping();
        let render_chains = |rest: &RenderSettings, control: &RenderControl, boots: Option<Bootstraps>| {
            importance_pilot::render(shaping, self.max_depth, scene, rest, control, |importance, s, c| {
                let main = |depth| main(depth).with_importance(importance);
                let start = |cx: StartContext| self.start_walker((scene, importance), &ladder, cx);
                // A bootstrap drawn under the unshaped targets serves unshaped chains only.
                let boots = boots.filter(|_| importance.is_none());
                chains.render(scene, s, c, depths, main, start, boots)
            })
        };
        // Per-depth images and the chains' measured efficiency are the chains' own.
        let choose = self.hybrid == 0.0 && !self.depth_images && !self.measure_efficiency;
        let Some(above) = self.bdpt_above.filter(|_| choose) else {
            return render_chains(settings, control, None);
        };
        // The bootstrap first, to choose by; the render then gets the rest of a time budget
        // (its snapshots as much earlier), and the chains reuse the bootstrap.
        let started = Instant::now();
        let bootstraps = chains.bootstrap_groups(settings, control, depths, main)?;
        let acceptance = independent_acceptance(&bootstraps.boots);
        let spent = started.elapsed();
        let snapshots = crate::integrator::snapshots_after(control.snapshots, spent);
        let control = RenderControl { snapshots: &snapshots, ..*control };
        let budget = match settings.budget {
            Budget::Time(t) => Budget::Time(t.saturating_sub(spent)),
            fixed => fixed,
        };
        let rest = RenderSettings { budget, ..*settings };
        let bootstrap_rays = bootstraps.rays;
        let mut out = if acceptance > above {
            let mut out = self.render_bdpt(scene, &rest, &control, &bootstraps)?;
            out.stats.rays += bootstrap_rays;
            out
        } else {
            render_chains(&rest, &control, Some(bootstraps))?
        };
        out.stats.seconds += spent.as_secs_f64();
        if let Some(first) = out.chains.first_mut() {
            first.independent_acceptance = Some(acceptance);
        }
        Ok(out)
    }

    fn memory_estimate(&self, scene: &Scene, _threads: usize) -> u64 {
        use crate::integrator::memory::{SHARED_SPLAT_BYTES, pixels};
        let layers = if self.reuse_replicas && self.swap != Swap::Mixture { self.replicas.max(1) } else { 1 } as u64;
        let images = if self.depth_images { 12 * (u64::from(self.max_depth) + 1) } else { 0 };
        let depths = u64::from(self.max_depth) + 1;
        let hybrid = crate::mcmc::hybrid::film_buffers(self.hybrid, self.depth_images, depths);
        // With the efficiency measured, the odd walkers' buffers of every depth's layers; with
        // the mutations re-allotted, of every depth's single layer.
        let halves = if self.measure_efficiency {
            depths * layers
        } else if self.reallot_at > 0.0 {
            depths
        } else {
            0
        };
        pixels(scene)
            .saturating_mul(12 + images + (depths * layers + halves + hybrid) * SHARED_SPLAT_BYTES)
            .saturating_add(crate::mcmc::shared_bootstrap_bytes(self.bootstrap, depths as usize))
    }
}

impl TemperedIntegrator {
    /// How the chains' targets are shaped per pixel.
    fn shaping(&self) -> importance_pilot::Shaping {
        importance_pilot::Shaping {
            spp: self.importance_pilot,
            floor: self.importance_floor,
            power: self.importance_power,
            share: self.importance_share,
            below: self.importance_below,
        }
    }

    /// The chains' driver settings.
    fn chain_settings(&self) -> ChainSettings {
        ChainSettings::new(self.bootstrap, self.chains, self.sigma, self.large_step_probability)
            .with_jumps(self.jumps)
            .with_film_steps(self.film_steps)
            .with_lens_steps(self.lens_steps)
            .with_spread_allocation(self.spread_allocation)
            .with_spread_below(if self.spread_only_sparse { self.ensembles_below } else { 0 })
            .with_group_images(self.depth_images)
            .with_independent_below(self.independent_below)
            .with_normaliser_share(self.normaliser_share)
            .with_reallot_at(self.reallot_at)
            .with_hybrid(self.hybrid)
            .with_chain_efficiency(self.chain_efficiency)
            .with_sample_share(self.sample_share)
            .with_measured_efficiency(self.measure_efficiency)
            .with_bridge_above(self.bridge_above)
    }

    /// BDPT alone, for the budget that was the chains'. A fixed budget of `m` mutations per
    /// pixel becomes the samples per pixel that trace the rays `m` mutations would: a
    /// mutation of depth `k` traces what depth `k`'s bootstrap evaluations traced on average,
    /// the depths in the shares of `b_k` the chains would make, and a BDPT sample what a
    /// one-sample-per-pixel render of it traces (a pilot whose image is not kept). So the
    /// choice changes neither the work nor, at a fixed budget, the image's independence of
    /// the machine and the thread count.
    fn render_bdpt(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        bootstraps: &Bootstraps,
    ) -> Result<RenderOutput, String> {
        let bdpt = BdptIntegrator::new(self.max_depth);
        let budget = match settings.budget {
            Budget::Samples(mpp) => {
                // Every rank measures the same sample alone, so all choose the same budget.
                let quiet = |_: u64| {};
                let solo = &crate::cluster::SOLO;
                let pilot_control = RenderControl { on_progress: &quiet, snapshots: &[], cluster: solo, ..*control };
                let pilot =
                    bdpt.render(scene, &RenderSettings { budget: Budget::Samples(1), ..*settings }, &pilot_control)?;
                let pixels = f64::from(scene.film.width) * f64::from(scene.film.height);
                let per_sample = pilot.stats.rays as f64 / pixels;
                let spp = f64::from(mpp) * rays_per_mutation(&bootstraps.boots) / per_sample.max(1.0);
                Budget::Samples(spp.round().clamp(1.0, f64::from(u32::MAX)) as u32)
            }
            time => time,
        };
        let mut out = bdpt.render(scene, &RenderSettings { budget, ..*settings }, control)?;
        // BDPT has no chains: the choice gets a row of its own.
        out.chains = vec![crate::mcmc::DepthStats::default()];
        Ok(out)
    }
}

/// The rays a mutation traces on average: each depth's bootstrap evaluations' rays per
/// sample (its normaliser's left out), weighted by the depth's `b_k`.
fn rays_per_mutation(boots: &[crate::mcmc::bootstrap::Bootstrap]) -> f64 {
    let (mut rays, mut total) = (0.0, 0.0);
    for boot in boots {
        let b = boot.b();
        if b.is_finite() && b > 0.0 && !boot.values.is_empty() {
            rays += b * boot.rays.saturating_sub(boot.normaliser_rays) as f64 / boot.values.len() as f64;
            total += b;
        }
    }
    if total > 0.0 { rays / total } else { 1.0 }
}
