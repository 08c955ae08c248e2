//! One ensemble of replicas of a path depth: sweeps of one mutation per replica, each followed
//! (every `swap_every` sweeps) by a swap step of its kernel. Replica 0 holds the scene's BSDFs;
//! its mutations are the ensemble's mutations in budgets and statistics. Either replica 0 alone
//! splats (its proposals and current states with their expected weights, as an MMLT chain),
//! or, with all-replica reuse ([`super::reuse`]), every replica splats with its
//! balance-heuristic weight: its proposals and current states with their expected weights
//! (the default), or its current state after each swap step.
//!
//! The depth's ensembles are prepared together: the shared ladder is tuned ([`super::ladder`])
//! unless it is given; then the depth's bootstrap samples are valued under every replica's
//! target ([`super::calibration`]) and every replica of every ensemble restarts from them in
//! proportion to its own target, as MMLT's chains start: the ensembles then begin in their
//! stationary distribution, and no settling sweeps are needed. Statistics start afresh.

use super::calibration::Calibration;
use super::ladder::{Tuning, TuningMethod, candidate_temperatures, ladder_from_bootstrap, tune_together};
use super::mixture::MixtureTarget;
use super::replicas::Replicas;
use super::reuse::Reuse;
use super::{SwapKernel, swap_acceptance};
use crate::film::SharedSplats;
use crate::integrator::ReplicaSplats;
use crate::math::distribution::Distribution1D;
use crate::math::rng::Pcg32;
use crate::mcmc::stats::BridgeSums;
use crate::mcmc::{
    Chain, DepthStats, GroupContext, LadderBridge, Layers, Moments, State, SwapStats, Target, TemperedState,
    TemperedTarget, Walker, target_value,
};
use rayon::prelude::*;

/// How the ensembles of a depth are run and prepared.
#[derive(Clone, Debug)]
pub struct EnsembleSettings {
    /// Bootstrap samples that value the replicas' targets once the ladder is frozen (to
    /// restart the replicas and, with reuse, to calibrate their normalisations).
    pub calibration_samples: usize,
    /// Whether every replica is to contribute to the image.
    pub reuse_replicas: bool,
    /// With reuse: which of each replica's states splat.
    pub replica_splats: ReplicaSplats,
    /// A swap step after every `swap_every` sweeps.
    pub swap_every: u64,
    /// Replicas `1 … K−1` mutate every `hot_every` sweeps (replica 0 every sweep). Each
    /// mutation leaves its replica's target invariant, so any fixed schedule keeps the
    /// ensemble's product target; fewer hot mutations make an ensemble cheaper while its
    /// main chain keeps its pace.
    pub hot_every: u64,
    /// The large-step probability of replicas `1 … K−1` (`None`: replica 0's). Any fixed
    /// mixture of large and small steps leaves a replica's target invariant; hot targets are
    /// flatter, so independent proposals are accepted there more often.
    pub hot_large_step: Option<f32>,
    /// The ladder's burn-in, if it is to be tuned.
    pub tuning: Option<Tuning>,
    /// Run plain MMLT chains when the tuned ladder's neighbour acceptance stays above this.
    pub collapse_above: Option<f64>,
    /// Run plain MMLT chains when the tuned ladder's neighbour acceptance stays below this.
    pub collapse_below: Option<f64>,
    /// Sweeps of the pilot that decides whether the depth's ensembles pay for their replicas
    /// ([`ensembles_pay`]; 0: no pilot, ensembles everywhere).
    pub pilot: u64,
    /// One chain on the mixture of the replicas' targets instead of a chain per replica
    /// ([`super::mixture`]; implies reuse), with the hotter targets' weight.
    pub mixture: Option<f64>,
}

pub struct Ensemble<'a> {
    pub replicas: Replicas<'a>,
    pub kernel: SwapKernel,
    pub settings: EnsembleSettings,
    /// The swap steps' random numbers.
    pub rng: Pcg32,
    pub swaps: SwapStats,
    /// Storage for the cross-evaluations of one swap step, reused across sweeps.
    cross: Vec<Option<f64>>,
    /// Per target, the moments of its values over the large-step proposals of every replica
    /// (each an independent uniform sample): target 0's always, the others' with reuse.
    large: Vec<Moments>,
    /// Sweeps made since the render began.
    sweeps: u64,
    /// With reuse, the bridge sums of each neighbouring pair's ratio `b_j/b_{j+1}`.
    ladder_bridge: Vec<LadderBridge>,
}

/// What the ensembles of a depth share once prepared: with all-replica reuse, the ratios the
/// replicas' splats are weighted with, and each replica's splats form a layer of their own.
#[derive(Clone, Debug, Default)]
pub struct EnsembleGroup {
    pub reuse: Option<Reuse>,
    /// The ensembles' main chains sample the mixture of the targets ([`super::mixture`]).
    pub mixture: bool,
}

impl Layers for EnsembleGroup {
    fn count(&self) -> usize {
        if self.mixture { 1 } else { self.valued() }
    }

    fn valued(&self) -> usize {
        self.reuse.as_ref().map_or(1, |r| r.ratios.len())
    }

    fn mixture(&self) -> bool {
        self.mixture
    }

    fn layer(&self, l: usize) -> Option<(Moments, f64)> {
        self.reuse.as_ref().map(|r| (r.bootstrap[l], r.ratios[l]))
    }

    fn ratios(&self) -> &[f64] {
        self.reuse.as_ref().map_or(&[], |r| r.ratios.as_slice())
    }
}

impl<'a> Ensemble<'a> {
    pub fn new(replicas: Replicas<'a>, kernel: SwapKernel, settings: EnsembleSettings, rng: Pcg32) -> Self {
        let k = replicas.len();
        let mut replicas = replicas;
        if let Some(p) = settings.hot_large_step {
            for chain in replicas.chains.iter_mut().skip(1) {
                chain.set_large_step_probability(p);
            }
        }
        Self {
            replicas,
            kernel,
            settings,
            rng,
            swaps: SwapStats::new(k),
            cross: Vec::new(),
            large: vec![Moments::default(); k],
            sweeps: 0,
            ladder_bridge: vec![LadderBridge::default(); k.saturating_sub(1)],
        }
    }

    /// One swap step; replicas that receive another state re-value it under their target.
    pub(super) fn swap(&mut self) {
        if self.replicas.len() < 2 {
            return;
        }
        let mut cross = self.replicas.cross(&mut self.cross);
        if let Some(sigma) = self.kernel.step(&mut cross, &mut self.rng, &mut self.swaps) {
            self.replicas.permute(&sigma);
        }
    }

    /// One burn-in sweep: a mutation per replica (no splats); returns the probability of
    /// accepting an exchange of each neighbouring pair of the current states.
    pub(super) fn tuning_sweep(&mut self) -> Vec<f64> {
        self.replicas.sweep_without_splats();
        let k = self.replicas.len();
        let mut cross = self.replicas.cross(&mut self.cross);
        (1..k).map(|j| swap_acceptance(&mut cross, j - 1, j)).collect()
    }

    /// Draws every replica's state afresh from the depth's bootstrap in proportion to its own
    /// target (`starts[j]`, from `f_j` over the samples), as MMLT starts its chains: each
    /// replica then starts (up to the bootstrap's resolution) in its own stationary
    /// distribution, and so does the ensemble, whose invariant distribution is the product of
    /// the replicas' targets. Replicas started from replica 0's distribution instead sit where
    /// `f_0` is large while their flatter targets are still being explored, and a short render
    /// inherits that start-up bias: the hot replicas' states then over-represent replica 0's
    /// modes.
    fn restart(&mut self, starts: &[Option<Distribution1D>], group: &GroupContext) {
        for (j, start) in starts.iter().enumerate() {
            let Some(start) = start else { continue };
            let target = self.replicas.targets[j];
            self.restart_replica(j, &target, start, group);
        }
    }

    /// Restarts replica `j` under `target` from the depth's bootstrap sample that `start` (a
    /// distribution over the samples) picks with the ensemble's random numbers.
    fn restart_replica(
        &mut self,
        j: usize,
        target: &impl Target<State = TemperedState>,
        start: &Distribution1D,
        group: &GroupContext,
    ) {
        let u = self.rng.next_f32();
        let seed = (u64::from(self.rng.next_u32()) << 32) | u64::from(self.rng.next_u32());
        let fresh = group.start_chain(target, start, u, Pcg32::new(seed, j as u64));
        self.replicas.chains[j].restart(fresh);
    }

    /// Keeps replica 0 alone, as a plain MMLT chain (statistics start afresh).
    fn collapse(&mut self) {
        self.replicas.collapse();
        self.discard_statistics();
    }

    /// Burn-in statistics are discarded with its splats.
    fn discard_statistics(&mut self) {
        for chain in &mut self.replicas.chains {
            // The bridge sums start afresh at the chain's level.
            let bridge = BridgeSums { level: chain.stats.bridge.level, ..BridgeSums::default() };
            chain.stats = DepthStats { depth: chain.stats.depth, bridge, ..DepthStats::default() };
            chain.large = Moments::default();
        }
        self.swaps = SwapStats::new(self.replicas.len());
        self.large = vec![Moments::default(); self.replicas.len()];
        self.ladder_bridge = vec![LadderBridge::default(); self.replicas.len().saturating_sub(1)];
    }

    /// One sweep: a mutation per replica, each large-step proposal valued under the first
    /// `valued` targets for their normalisations. Without reuse replica 0 splats as an MMLT
    /// chain does. With reuse and [`ReplicaSplats::Expected`] every replica splats its proposal
    /// and its current state with their expected weights (`a` and `1 − a`), each times its
    /// balance-heuristic scale, into the replica's own layer; with [`ReplicaSplats::States`]
    /// the current states splat after the swap step instead ([`Walker::run`]).
    fn sweep(&mut self, splats: &[SharedSplats], reuse: Option<&Reuse>) {
        let expected = reuse.filter(|_| self.settings.replica_splats == ReplicaSplats::Expected);
        let Replicas { chains, targets } = &mut self.replicas;
        let targets: &[TemperedTarget] = targets;
        let large = &mut self.large;
        let bridge = &mut self.ladder_bridge;
        let valued = if reuse.is_some() { targets.len() } else { 1 };
        let hot = self.sweeps.is_multiple_of(self.settings.hot_every);
        for (j, (chain, target)) in chains.iter_mut().zip(targets).enumerate() {
            if j > 0 && !hot {
                // A replica that sits this sweep out keeps its state, which counts as this
                // sweep's sample of its target.
                if let Some(reuse) = expected {
                    splat_reused(reuse, targets, chain.state_mut(), j, 1.0, &splats[j]);
                    bridge_state(bridge, reuse, targets, chain.state_mut(), j, 1.0);
                }
                continue;
            }
            let observe = |proposal: &mut TemperedState| {
                for (l, m) in large.iter_mut().take(valued).enumerate() {
                    let v = if l == j { proposal.value() } else { proposal.value_under(l, targets) };
                    m.push(f64::from(target_value(v)));
                }
            };
            match expected {
                Some(reuse) => chain.mutate_splatting(target, observe, |state, weight| {
                    splat_reused(reuse, targets, state, j, weight, &splats[j]);
                    bridge_state(bridge, reuse, targets, state, j, weight);
                }),
                None => chain.mutate_observed(target, (j == 0 && reuse.is_none()).then(|| &splats[0]), observe),
            }
        }
    }
}

/// Adds `state`, a state of replica `j` weighted `weight` as it splats, to the bridge sums of
/// the pairs `(j − 1, j)` and `(j, j + 1)`, each at the level `ρ_j/ρ_{j+1}` of the reuse's
/// ratios (its calibrated `b_j/b_{j+1}`). Needs no evaluation the splat has not made.
fn bridge_state(
    bridge: &mut [LadderBridge],
    reuse: &Reuse,
    targets: &[TemperedTarget],
    state: &mut TemperedState,
    j: usize,
    weight: f32,
) {
    if weight <= 0.0 {
        return;
    }
    state.note_own_value(j, targets.len());
    let mut f = |l: usize| f64::from(target_value(state.value_under(l, targets)));
    let level = |p: usize| reuse.ratios[p] / reuse.ratios[p + 1];
    if j >= 1 {
        let values = (f(j - 1), f(j));
        bridge[j - 1].add(true, values, f64::from(weight), level(j - 1));
    }
    if j + 1 < targets.len() {
        let values = (f(j), f(j + 1));
        bridge[j].add(false, values, f64::from(weight), level(j));
    }
}

/// Splats `state`, a state of replica `j` (its proposal or its current state), with `weight`
/// times its balance-heuristic scale into `layer`.
fn splat_reused(
    reuse: &Reuse,
    targets: &[TemperedTarget],
    state: &mut TemperedState,
    j: usize,
    weight: f32,
    layer: &SharedSplats,
) {
    if weight <= 0.0 {
        return;
    }
    state.note_own_value(j, targets.len());
    let scale = reuse.scale(targets, state);
    if scale > 0.0 {
        state.splat(layer, weight * scale);
    }
}

impl Walker for Ensemble<'_> {
    type Group = EnsembleGroup;

    fn run(&mut self, group: &EnsembleGroup, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        if group.mixture
            && let Some(reuse) = &group.reuse
        {
            // Each large-step proposal valued under every target, for their b_l.
            let Replicas { chains, targets } = &mut self.replicas;
            let target = MixtureTarget { targets, reuse };
            let large = &mut self.large;
            let observe = |proposal: &mut TemperedState| {
                for (l, m) in large.iter_mut().enumerate() {
                    m.push(f64::from(target_value(proposal.value_under(l, targets))));
                }
            };
            return chains[0].run_observed(&target, mutations, Some(&splats[0]), stop, observe);
        }
        if self.replicas.len() == 1 {
            return self.replicas.chains[0].run(&self.replicas.targets[0], mutations, Some(&splats[0]), stop);
        }
        let start = std::time::Instant::now();
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            self.sweep(splats, group.reuse.as_ref());
            self.sweeps += 1;
            if self.sweeps.is_multiple_of(self.settings.swap_every) {
                self.swap();
            }
            if let Some(reuse) = &group.reuse
                && self.settings.replica_splats == ReplicaSplats::States
            {
                // Every replica's current state, weighted by the balance heuristic, into the
                // replica's own layer (normalised by its own b_l).
                let Replicas { chains, targets } = &mut self.replicas;
                for (j, (chain, layer)) in chains.iter_mut().zip(splats).enumerate() {
                    splat_reused(reuse, targets, chain.state_mut(), j, 1.0, layer);
                }
            }
            done += 1;
        }
        // The ensemble's time is its main chain's.
        self.replicas.chains[0].stats.seconds += start.elapsed().as_secs_f64();
        done
    }

    fn stats(&self) -> DepthStats {
        let mut stats = self.replicas.chains[0].stats.clone();
        stats.ladder = self.replicas.ladder();
        stats.ladder_ensembles = 1;
        stats.ladder_bridge = self.ladder_bridge.clone();
        // A mixture chain does not swap.
        stats.swaps = (self.replicas.len() > 1 && self.settings.mixture.is_none()).then(|| self.swaps.clone());
        stats
    }

    fn large(&self, layer: usize) -> Moments {
        if self.replicas.len() == 1 { self.replicas.chains[0].large } else { self.large[layer] }
    }

    fn rays(&self) -> u64 {
        self.replicas.chains.iter().map(Chain::rays).sum()
    }

    /// [`prepare_ensembles`].
    fn prepare_group(
        ensembles: &mut [Self],
        group: &GroupContext,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (EnsembleGroup, u64) {
        let mut ensembles: Vec<&mut Ensemble> = ensembles.iter_mut().collect();
        prepare_ensembles(&mut ensembles, group, stop)
    }
}

/// Prepares the ensembles of one depth together ([`Walker::prepare_group`]): tunes the depth's
/// shared ladder, values the depth's bootstrap under the frozen ladder, restarts every replica
/// from it in proportion to its own target and (with reuse) calibrates the replicas'
/// normalisations. Returns what they share and the rays traced.
pub fn prepare_ensembles(
    ensembles: &mut [&mut Ensemble],
    group: &GroupContext,
    stop: &(dyn Fn() -> bool + Sync),
) -> (EnsembleGroup, u64) {
    if ensembles.is_empty() || ensembles[0].replicas.len() < 2 {
        return (EnsembleGroup::default(), 0);
    }
    let (k, main) = (ensembles[0].replicas.len(), ensembles[0].replicas.targets[0]);
    let EnsembleSettings { calibration_samples: samples, tuning, collapse_above, collapse_below, .. } =
        ensembles[0].settings;
    let collapses = |acceptance: f64| {
        collapse_above.is_some_and(|limit| acceptance > limit) || collapse_below.is_some_and(|limit| acceptance < limit)
    };
    let (calibration, rays) = match tuning.map(|t| (t, t.method)) {
        Some((tuning, TuningMethod::Bootstrap)) => {
            // The bootstrap valued under every candidate temperature; the ladder chosen
            // from it keeps the columns of its rungs.
            let grid = candidate_temperatures(tuning.max_temperature, tuning.flattening);
            let candidates: Vec<TemperedTarget> = grid
                .iter()
                .map(|&tau| {
                    let mut t = main;
                    t.set_temperature(tau);
                    t
                })
                .collect();
            let (all, rays) = Calibration::new(&candidates, group, samples);
            let columns: Vec<Vec<f32>> = (0..grid.len()).map(|g| all.of(g)).collect();
            match ladder_from_bootstrap(&columns, &grid, k, tuning) {
                Some((rungs, acceptance)) => {
                    if collapses(acceptance) {
                        return collapse(ensembles, rays);
                    }
                    let ladder: Vec<f32> = rungs[1..].iter().map(|&g| grid[g]).collect();
                    ensembles.par_iter_mut().for_each(|e| e.replicas.set_ladder(&ladder));
                    (all.select(&rungs), rays)
                }
                // No light in the bootstrap, or too many replicas for the grid: the ladder
                // stays as given.
                None => Calibration::new(&ensembles[0].replicas.targets, group, samples),
            }
        }
        Some((tuning, TuningMethod::BurnIn(sweeps))) => {
            let Some(acceptance) = tune_together(ensembles, sweeps, tuning, stop) else {
                // Stopped during the burn-in: nothing of it may show in the statistics.
                for e in ensembles.iter_mut() {
                    e.discard_statistics();
                }
                return (EnsembleGroup::default(), 0);
            };
            if collapses(acceptance) {
                return collapse(ensembles, 0);
            }
            Calibration::new(&ensembles[0].replicas.targets, group, samples)
        }
        None => Calibration::new(&ensembles[0].replicas.targets, group, samples),
    };
    if let Some(weight) = ensembles[0].settings.mixture {
        // The main chains alone mutate, on the mixture: they restart in proportion to it.
        // A weight w of the hotter targets is a ratio ρ_l/w (any ratio keeps the estimate
        // unbiased).
        let mut reuse = Reuse::new(&calibration, k);
        for rho in reuse.ratios.iter_mut().skip(1) {
            *rho /= weight;
        }
        let targets = &ensembles[0].replicas.targets.clone();
        let target = MixtureTarget { targets, reuse: &reuse };
        let values = target.values(&calibration.values);
        if values.iter().any(|&v| v > 0.0) {
            let start = Distribution1D::new(&values);
            ensembles.par_iter_mut().for_each(|e| e.restart_replica(0, &target, &start, group));
        }
        ensembles.par_iter_mut().for_each(|e| e.discard_statistics());
        return (EnsembleGroup { reuse: Some(reuse), mixture: true }, rays);
    }
    let starts: Vec<Option<Distribution1D>> = (0..k)
        .map(|l| {
            let values = calibration.of(l);
            values.iter().any(|&v| v > 0.0).then(|| Distribution1D::new(&values))
        })
        .collect();
    let reuse = ensembles[0].settings.reuse_replicas.then(|| Reuse::new(&calibration, k));
    ensembles.par_iter_mut().for_each(|e| {
        e.restart(&starts, group);
        e.discard_statistics();
    });
    let shared = EnsembleGroup { reuse, mixture: false };
    let values = calibration.of(0);
    let b0 = values.iter().map(|&v| f64::from(v)).sum::<f64>() / values.len().max(1) as f64;
    if ensembles_pay(ensembles, &shared, b0, group, stop) == Some(false) {
        return collapse(ensembles, rays);
    }
    // The pilot's statistics are not the render's.
    ensembles.par_iter_mut().for_each(|e| e.discard_statistics());
    (shared, rays)
}

/// Pilot walkers per kind, at most.
const PILOT_WALKERS: usize = 32;
/// The shortest pilot that decides anything, in sweeps.
const MIN_PILOT: u64 = 64;

/// Whether a depth's ensembles pay for their replicas, measured by a pilot (`None`: not
/// measured — no pilot asked for, fewer than eight walkers, too small a budget, or stopped).
/// The first half of the depth's walkers (at most [`PILOT_WALKERS`]) make
/// [`EnsembleSettings::pilot`] sweeps as ensembles, just as in the render; as many others make
/// as many mutations of replica 0 alone, a plain MMLT chain. Each splats into a coarse image
/// of its own (blocks of about an eighth of the film's longer side), scaled as the render
/// scales it (normalisation `b0`). The walkers started independently in their stationary
/// distributions, so the spread of their images over walkers is the error of a render of that
/// many mutations, slow mixing included. The ensembles pay when that spread (per block,
/// relative to the block's squared mean plus relMSE's `ε = 0.01`, summed over the blocks)
/// times their rays per main-chain mutation is below the plain chains'. Rays, not seconds,
/// measure the cost, so the decision is the same on every machine, thread count and rank.
/// Under a fixed budget the pilot takes at most a quarter of the depth's mutations.
fn ensembles_pay(
    ensembles: &mut [&mut Ensemble],
    shared: &EnsembleGroup,
    b0: f64,
    group: &GroupContext,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<bool> {
    let n = (ensembles.len() / 2).min(PILOT_WALKERS);
    let sweeps = ensembles.first()?.settings.pilot;
    let sweeps = group.budget.map_or(sweeps, |b| sweeps.min(b / (8 * n as u64).max(1)));
    if n < 4 || sweeps < MIN_PILOT || b0 <= 0.0 {
        return None;
    }
    let film = &ensembles[0].replicas.targets[0].scene.film;
    let (w, h) = (film.width, film.height);
    let shift = w.max(h).div_ceil(8).max(1).next_power_of_two().trailing_zeros();
    let scale = b0 * f64::from(w) * f64::from(h) / f64::from(1u32 << (2 * shift));
    // Each walker's block luminances and rays per main-chain mutation, running as `run` says
    // into `layers` coarse buffers of its own.
    let measure =
        |walkers: &mut [&mut Ensemble], layers: usize, run: &(dyn Fn(&mut Ensemble, &[SharedSplats]) -> u64 + Sync)| {
            walkers
                .par_iter_mut()
                .map(|e| {
                    let buffers: Vec<SharedSplats> = (0..layers).map(|_| SharedSplats::coarse(w, h, shift)).collect();
                    let rays = e.rays();
                    let done = run(e, &buffers);
                    (blocks(&buffers, scale, done), (e.rays() - rays) as f64 / done.max(1) as f64)
                })
                .collect::<Vec<(Vec<f64>, f64)>>()
        };
    let (head, tail) = ensembles.split_at_mut(n);
    let tempered = measure(head, shared.count(), &|e, buffers| e.run(shared, sweeps, buffers, stop));
    let plain = measure(&mut tail[..n], 1, &|e, buffers| {
        e.replicas.chains[0].run(&e.replicas.targets[0], sweeps, Some(&buffers[0]), stop)
    });
    if stop() {
        return None;
    }
    let cells = tempered[0].0.len();
    let mean: Vec<f64> =
        (0..cells).map(|c| tempered.iter().chain(&plain).map(|r| r.0[c]).sum::<f64>() / (2 * n) as f64).collect();
    // The error per ray of a kind's walkers.
    let cost = |runs: &[(Vec<f64>, f64)]| {
        let n = runs.len() as f64;
        let spread: f64 = (0..cells)
            .map(|c| {
                let m = runs.iter().map(|r| r.0[c]).sum::<f64>() / n;
                let var = runs.iter().map(|r| (r.0[c] - m).powi(2)).sum::<f64>() / (n - 1.0);
                var / (mean[c] * mean[c] + 0.01)
            })
            .sum();
        spread * runs.iter().map(|r| r.1).sum::<f64>() / n
    };
    Some(cost(&tempered) < cost(&plain))
}

/// Block luminances of a pilot walker's coarse images (summed over its layers) as the render
/// would scale them after `mutations` main-chain mutations.
fn blocks(buffers: &[SharedSplats], scale: f64, mutations: u64) -> Vec<f64> {
    let scale = scale / mutations.max(1) as f64;
    let mut sums: Vec<f64> = Vec::new();
    for b in buffers {
        let image = b.image(1.0);
        sums.resize(image.pixels.len(), 0.0);
        for (s, p) in sums.iter_mut().zip(&image.pixels) {
            *s += f64::from(crate::math::luminance(*p)) * scale;
        }
    }
    sums
}

/// Every ensemble of a depth keeps replica 0 alone, as a plain MMLT chain: the replicas barely
/// differ even at the hottest ladder allowed, and plain chains, continuing from replica 0's
/// state, cost a K-th.
fn collapse(ensembles: &mut [&mut Ensemble], rays: u64) -> (EnsembleGroup, u64) {
    for e in ensembles.iter_mut() {
        e.collapse();
    }
    (EnsembleGroup::default(), rays)
}
