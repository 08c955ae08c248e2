//! One ensemble of replicas of a path depth: sweeps of one mutation per replica, each followed
//! by a swap step. Replica 0 holds the scene's BSDFs; its mutations are the ensemble's
//! mutations in budgets and statistics. Either replica 0 alone splats (its proposals and
//! current states with their expected weights, as an MMLT chain), or, with all-replica reuse
//! ([`super::reuse`]), every replica's current state splats after each sweep with its
//! balance-heuristic weight.
//!
//! Ladder tuning, one shared ladder per depth: during a burn-in of `sweeps` sweeps, in which
//! the depth's first [`TUNING_ENSEMBLES`] ensembles sweep in lockstep (splats discarded), the
//! gaps `a_j − a_{j−1}` follow a Robbins–Monro recursion on their logarithm,
//! `ln g_j += γ_n (ᾱ_j − α*)` with `γ_n = (1 + n/10)^−0.6`, where `ᾱ_j` is the probability of
//! exchanging replicas `j − 1` and `j` (whatever the swap strategy) averaged over those
//! ensembles and `α*` the target (0.234). A shared ladder lets one calibration from the
//! depth's bootstrap serve all-replica reuse, and averages out the noise of single ensembles.
//! Wider gaps lower the acceptance, so the recursion settles where the neighbour acceptance
//! averages `α*`; the ladder is then frozen. Gaps are capped at `1/(K−1)`: beyond `a = 1`
//! roughening changes nothing, and on scenes whose connections are mostly diffuse the
//! acceptance stays above `α*` even at the cap.
//!
//! Once the ladder is frozen (tuned or given), the depth's bootstrap samples are valued under
//! every replica's target and every replica of every ensemble restarts from them in
//! proportion to its own target, as MMLT's chains start: the ensembles then begin in their
//! stationary distribution, and no settling sweeps are needed. Statistics start afresh.

use super::calibration::Calibration;
use super::reuse::Reuse;
use super::{CrossValues, SwapStrategy, swap_acceptance};
use crate::film::SharedSplats;
use crate::integrator::mmlt::{GroupContext, Walker, sampler_for};
use crate::math::distribution::Distribution1D;
use crate::math::rng::Pcg32;
use crate::mcmc::{Chain, DepthStats, Moments, State, SwapStats, TemperedState, TemperedTarget};
use rayon::prelude::*;

pub struct Ensemble<'a> {
    pub replicas: Vec<Chain<TemperedState>>,
    pub targets: Vec<TemperedTarget<'a>>,
    pub strategy: Box<dyn SwapStrategy>,
    pub rng: Pcg32,
    pub swaps: SwapStats,
    /// Ladder tuning still to do, if any.
    pub tuning: Option<Tuning>,
    /// Storage for the cross-evaluations of one swap step, reused across sweeps.
    pub(super) cross_cache: Vec<Option<f64>>,
    /// Bootstrap samples that value the replicas' targets once the ladder is frozen (to
    /// restart the replicas and, with reuse, to calibrate their normalisations).
    pub calibration_samples: usize,
    /// Whether every replica is to contribute to the image.
    pub reuse_replicas: bool,
    /// All-replica reuse, once calibrated: the ratios every replica's splats are weighted with.
    pub reuse: Option<Reuse>,
    /// Per target, the moments of its values over the large-step proposals of every replica
    /// (each an independent uniform sample): target 0's always, the others' with reuse.
    pub large: Vec<Moments>,
    /// A swap step after every `swap_every` sweeps; sweeps made since the render began.
    pub swap_every: u64,
    pub sweeps: u64,
}

/// Ensembles of a depth that tune its ladder in lockstep; the others wait for the result.
const TUNING_ENSEMBLES: usize = 8;

/// The state of the ladder's burn-in.
#[derive(Clone, Debug)]
pub struct Tuning {
    /// Burn-in sweeps left.
    pub sweeps: u64,
    /// Target neighbour acceptance.
    pub target: f64,
    /// Sweeps done.
    pub n: u64,
}

/// Lazily computed cross-evaluations `f_i(u_j)` of an ensemble.
struct Cross<'e, 'a> {
    ensemble: &'e mut Ensemble<'a>,
    cache: Vec<Option<f64>>,
}

impl CrossValues for Cross<'_, '_> {
    fn replicas(&self) -> usize {
        self.ensemble.replicas.len()
    }

    fn f(&mut self, i: usize, j: usize) -> f64 {
        let k = self.replicas();
        if let Some(v) = self.cache[i * k + j] {
            return v;
        }
        let e = &mut *self.ensemble;
        let v = if i == j {
            f64::from(e.replicas[j].state().value)
        } else {
            f64::from(e.targets[i].value_of(e.replicas[j].state_mut()))
        };
        self.cache[i * k + j] = Some(v);
        v
    }
}

/// Applies `sigma` in place: afterwards `items[i]` holds what `items[sigma[i]]` held.
pub fn apply_permutation<T>(items: &mut [T], sigma: &[usize], exchange: impl Fn(&mut [T], usize, usize)) {
    for i in 0..sigma.len() {
        let mut j = sigma[i];
        while j < i {
            j = sigma[j];
        }
        if j != i {
            exchange(items, i, j);
        }
    }
}

impl<'a> Ensemble<'a> {
    /// Cross-evaluations of the current states, computed on demand, in the reused storage.
    fn cross(&mut self) -> Cross<'_, 'a> {
        let k = self.replicas.len();
        let mut cache = std::mem::take(&mut self.cross_cache);
        cache.clear();
        cache.resize(k * k, None);
        Cross { ensemble: self, cache }
    }

    /// One swap step; replicas that receive another state re-value it under their target.
    fn swap(&mut self) {
        let k = self.replicas.len();
        if k < 2 {
            return;
        }
        let mut rng = self.rng.clone();
        let mut swaps = std::mem::take(&mut self.swaps);
        // The strategy is moved out while the cross-evaluations borrow the ensemble.
        let strategy = std::mem::replace(&mut self.strategy, Box::new(super::Neighbor));
        let sigma = {
            let mut cross = self.cross();
            let sigma = strategy.step(&mut cross, &mut rng, &mut swaps);
            cross.ensemble.cross_cache = cross.cache;
            sigma
        };
        self.strategy = strategy;
        self.rng = rng;
        self.swaps = swaps;
        let Some(sigma) = sigma else { return };
        apply_permutation(&mut self.replicas, &sigma, |r, i, j| {
            let (lo, hi) = r.split_at_mut(j.max(i));
            lo[i.min(j)].exchange(&mut hi[0]);
        });
        for (i, &from) in sigma.iter().enumerate() {
            if from != i {
                let value = self.targets[i].value_of(self.replicas[i].state_mut());
                self.replicas[i].state_mut().value = value;
            }
        }
    }
}

impl Ensemble<'_> {
    /// One mutation per replica, splatting nothing.
    fn sweep_without_splats(&mut self) {
        for (chain, target) in self.replicas.iter_mut().zip(&self.targets) {
            chain.mutate(target, None);
        }
    }

    /// One burn-in sweep: a mutation per replica (no splats); returns the probability of
    /// accepting an exchange of each neighbouring pair of the current states.
    fn tuning_sweep(&mut self) -> Vec<f64> {
        self.sweep_without_splats();
        let k = self.replicas.len();
        let mut cross = self.cross();
        let alphas = (1..k).map(|j| swap_acceptance(&mut cross, j - 1, j)).collect();
        cross.ensemble.cross_cache = cross.cache;
        alphas
    }

    /// Sets the roughening of replicas `1 …` to `ladder` and re-values their states.
    fn set_ladder(&mut self, ladder: &[f32]) {
        for (j, &a) in ladder.iter().enumerate() {
            self.targets[j + 1].temper.a = a;
            let value = self.targets[j + 1].value_of(self.replicas[j + 1].state_mut());
            self.replicas[j + 1].state_mut().value = value;
        }
    }

    /// The burn-in of one depth: all its ensembles sweep in lockstep under one shared ladder,
    /// whose log gaps follow the Robbins–Monro recursion on the neighbour acceptance averaged
    /// over the ensembles; the ladder is then frozen. Returns false when stopped early.
    fn tune_together(all: &mut [Self], mut tuning: Tuning, stop: &(dyn Fn() -> bool + Sync)) -> bool {
        let k = all[0].replicas.len();
        // The first few ensembles tune the ladder; the others take it when it is frozen.
        let (ensembles, rest) = all.split_at_mut(all.len().min(TUNING_ENSEMBLES));
        let targets = &ensembles[0].targets;
        let mut log_gaps: Vec<f64> =
            (1..k).map(|j| f64::from(targets[j].temper.a - targets[j - 1].temper.a).max(1e-6).ln()).collect();
        // Roughening saturates at α = 1 (a = 1 flattens every lobe completely), so gaps stay
        // below 1/(K−1) and the ladder within (0, 1].
        let max_gap = (1.0 / (k - 1) as f64).ln();
        let mut finished = true;
        while tuning.sweeps > 0 {
            if stop() {
                finished = false;
                break;
            }
            // One sweep of every tuning ensemble, then one step of the recursion with their
            // mean acceptance. (Stepping once per batch of sweeps synchronises the threads less
            // often, but the ladder lags behind: 0.05 below the target on the tuning test.)
            let alphas: Vec<Vec<f64>> = ensembles
                .par_iter_mut()
                .map(|e| {
                    let alphas = e.tuning_sweep();
                    e.swap();
                    alphas
                })
                .collect();
            let gamma = (1.0 + tuning.n as f64 / 10.0).powf(-0.6);
            for (j, g) in log_gaps.iter_mut().enumerate() {
                let mean = alphas.iter().map(|a| a[j]).sum::<f64>() / alphas.len() as f64;
                *g = (*g + gamma * (mean - tuning.target)).clamp(1e-5f64.ln(), max_gap);
            }
            let mut a = 0.0f64;
            let ladder: Vec<f32> = log_gaps
                .iter()
                .map(|g| {
                    a += g.exp();
                    a as f32
                })
                .collect();
            ensembles.par_iter_mut().for_each(|e| e.set_ladder(&ladder));
            tuning.sweeps -= 1;
            tuning.n += 1;
        }
        let ladder: Vec<f32> = ensembles[0].targets[1..].iter().map(|t| t.temper.a).collect();
        rest.par_iter_mut().for_each(|e| e.set_ladder(&ladder));
        finished
    }

    /// Draws every replica's state afresh from the depth's bootstrap in proportion to its own
    /// target (`values[i][j] = f_j(u_i)`), as MMLT starts its chains: each replica then starts
    /// (up to the bootstrap's resolution) in its own stationary distribution, and so does the
    /// ensemble, whose invariant distribution is the product of the replicas' targets.
    /// Replicas started from replica 0's distribution instead sit where `f_0` is large while
    /// their flatter targets are still being explored, and a short render inherits that
    /// start-up bias: the hot replicas' states then over-represent replica 0's modes.
    fn restart(&mut self, starts: &[Option<Distribution1D>], group: &GroupContext) {
        for (j, start) in starts.iter().enumerate() {
            let Some(start) = start else { continue };
            let (index, _, _) = start.sample_discrete(self.rng.next_f32());
            let seed = (u64::from(self.rng.next_u32()) << 32) | u64::from(self.rng.next_u32());
            let sampler = sampler_for(group.seed, group.k, index, group.settings);
            let fresh = Chain::start(&self.targets[j], sampler, Pcg32::new(seed, j as u64), group.k);
            let rays = self.replicas[j].rays;
            self.replicas[j] = fresh;
            self.replicas[j].rays += rays;
        }
    }

    /// Burn-in statistics are discarded with its splats.
    fn discard_statistics(&mut self) {
        for chain in &mut self.replicas {
            chain.stats = DepthStats { depth: chain.stats.depth, ..DepthStats::default() };
            chain.large = Moments::default();
        }
        self.swaps = SwapStats::new(self.replicas.len());
        self.large = vec![Moments::default(); self.replicas.len()];
    }
}

impl Walker for Ensemble<'_> {
    fn run(&mut self, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        if self.replicas.len() == 1 {
            return self.replicas[0].run(&self.targets[0], mutations, Some(&splats[0]), stop);
        }
        let start = std::time::Instant::now();
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            let reuse = self.reuse.is_some();
            let (targets, large) = (&self.targets, &mut self.large);
            let valued = if reuse { targets.len() } else { 1 };
            for (j, (chain, target)) in self.replicas.iter_mut().zip(targets).enumerate() {
                let splats = if j == 0 && !reuse { Some(&splats[0]) } else { None };
                chain.mutate_observed(target, splats, |proposal| {
                    for (l, (m, t)) in large.iter_mut().zip(targets).take(valued).enumerate() {
                        let v = if l == j { proposal.value() } else { t.value_of(proposal) };
                        // Invalid values count as zero, as in the chains themselves.
                        m.push(if v.is_finite() && v > 0.0 { f64::from(v) } else { 0.0 });
                    }
                });
            }
            self.sweeps += 1;
            if self.sweeps.is_multiple_of(self.swap_every) {
                self.swap();
            }
            if let Some(reuse) = &self.reuse {
                // Every replica's current state, weighted by the balance heuristic, into the
                // replica's own layer (normalised by its own b_l).
                for (chain, layer) in self.replicas.iter_mut().zip(splats) {
                    let scale = reuse.scale(&self.targets, chain.state_mut());
                    if scale > 0.0 {
                        chain.state().splat(layer, scale);
                    }
                }
            }
            done += 1;
        }
        // The ensemble's time is its main chain's.
        self.replicas[0].stats.seconds += start.elapsed().as_secs_f64();
        done
    }

    fn stats(&self) -> DepthStats {
        let mut stats = self.replicas[0].stats.clone();
        stats.ladder = self.targets.iter().map(|t| t.temper.a).collect();
        stats.ladder_ensembles = 1;
        stats.swaps = (self.replicas.len() > 1).then(|| self.swaps.clone());
        stats
    }

    fn layers(&self) -> usize {
        if self.reuse.is_some() { self.replicas.len() } else { 1 }
    }

    fn large(&self, layer: usize) -> Moments {
        if self.replicas.len() == 1 { self.replicas[0].large } else { self.large[layer] }
    }

    fn calibration(&self) -> Option<(&[Moments], &[f64])> {
        self.reuse.as_ref().map(|r| (r.bootstrap.as_slice(), r.ratios.as_slice()))
    }

    fn rays(&self) -> u64 {
        self.replicas.iter().map(|r| r.rays).sum()
    }

    /// Tunes the depth's shared ladder, values the depth's bootstrap under the frozen ladder,
    /// restarts every replica from it in proportion to its own target and (with reuse)
    /// calibrates the replicas' normalisations.
    fn prepare_group(ensembles: &mut [Self], group: &GroupContext, stop: &(dyn Fn() -> bool + Sync)) -> u64 {
        if ensembles.is_empty() || ensembles[0].replicas.len() < 2 {
            return 0;
        }
        if let Some(tuning) = ensembles[0].tuning.clone()
            && !Self::tune_together(ensembles, tuning, stop)
        {
            // Stopped during the burn-in: nothing of it may show in the statistics.
            for e in ensembles.iter_mut() {
                e.tuning = None;
                e.discard_statistics();
            }
            return 0;
        }
        let k = ensembles[0].replicas.len();
        let (calibration, rays) = Calibration::new(&ensembles[0].targets, group, ensembles[0].calibration_samples);
        let starts: Vec<Option<Distribution1D>> = (0..k)
            .map(|l| {
                let values = calibration.of(l);
                values.iter().any(|&v| v > 0.0).then(|| Distribution1D::new(&values))
            })
            .collect();
        let reuse = ensembles[0].reuse_replicas.then(|| Reuse::new(&calibration, k));
        ensembles.par_iter_mut().for_each(|e| {
            e.restart(&starts, group);
            e.tuning = None;
            e.discard_statistics();
            e.reuse.clone_from(&reuse);
        });
        rays
    }
}
