//! Per-depth chain statistics, counted per chain and merged once (DESIGN §6.7).

use super::bridge::LadderBridge;
use crate::cluster::{Reader, Wire};

/// What the chains of one path depth did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepthStats {
    pub depth: usize,
    /// The row covers every path depth (PSSMLT's single set of chains); `depth` is then 0.
    pub all_depths: bool,
    /// Normalisation `b_k` (mean target value) and its relative standard error.
    pub b: f64,
    pub b_rel_se: f64,
    pub bootstrap_samples: u64,
    pub large_step_samples: u64,
    /// The spread of the bootstrap's non-zero values (see `Bootstrap::spread`).
    pub spread: f64,
    pub mutations: u64,
    pub large_steps_proposed: u64,
    pub large_steps_accepted: u64,
    pub small_steps_proposed: u64,
    pub small_steps_accepted: u64,
    /// Accepted proposals that changed the technique `s`.
    pub technique_changes: u64,
    /// Reversible jumps between techniques proposed and accepted ([`super::jump`]); the
    /// proposed ones count among `mutations`, not among the steps.
    pub jumps_proposed: u64,
    pub jumps_accepted: u64,
    /// Film steps proposed and accepted ([`crate::sampler::PssSampler::with_film_steps`]);
    /// they count among the small steps too.
    pub film_steps_proposed: u64,
    pub film_steps_accepted: u64,
    /// Lens steps proposed and accepted ([`super::lens`]; where a state has none, its step is
    /// a film step and counts among those); they count among the small steps too.
    pub lens_steps_proposed: u64,
    pub lens_steps_accepted: u64,
    /// Proposals whose value was NaN, infinite or negative (counted as zero).
    pub invalid: u64,
    /// The luminance the chains splatted per unit of target value, summed over their
    /// mutations with each splat's expected weight ([`super::State::weight`]): `mutations`
    /// where the target is the contribution's luminance; where a per-pixel map shapes it, the
    /// mutations weighted by the inverse of the map's factor where each splat landed.
    pub splat_weight: f64,
    /// Where a per-pixel map shapes the target: the unshaped normalisation from the
    /// normaliser's samples and its relative standard error
    /// ([`super::Bootstrap::plain_normalisation`]; 0: none), an estimate of the depth's total
    /// luminance independent of the chains', `b · splat_weight / mutations`. Set when the
    /// image is developed.
    pub b_plain: f64,
    pub b_plain_rel_se: f64,
    pub seconds: f64,
    /// Wall-clock time the group's preparation took before its first mutation (tempered MMLT:
    /// the ladder's burn-in and the calibration), shared by all threads.
    pub prepare_seconds: f64,
    /// Tempered MMLT: the replicas' roughening ladder (the mean over the depth's ensembles,
    /// `ladder_ensembles` of them) and what the swaps did.
    pub ladder: Vec<f32>,
    pub ladder_ensembles: u64,
    pub swaps: Option<SwapStats>,
    /// Tempered MMLT with all-replica reuse: the ratios `ρ_l ≈ b_l/b_0` the replicas' splats
    /// are weighted with (shared by the depth's ensembles); empty otherwise.
    pub replica_b_ratios: Vec<f32>,
    /// Tempered MMLT with all-replica reuse: each replica's normalisation `b_l` refined with
    /// its large steps (the first is `b`); empty otherwise.
    pub replica_b: Vec<f64>,
    /// Non-zero values among the bootstrap's samples.
    pub bootstrap_nonzero: u64,
    /// The large-step acceptance the bootstrap predicts for the depth's chains at equilibrium
    /// ([`super::acceptance::large_step_acceptance`]).
    pub large_step_estimate: f64,
    /// The depth was sampled independently instead of by chains (its bootstrap had too few
    /// non-zero values to start them apart; see [`super::independent`]): `mutations` counts
    /// the samples drawn in its share of the budget, each of which covers every strategy of
    /// every independently sampled depth.
    pub independent: bool,
    /// Samples of bidirectional path tracing combined with the chains ([`super::hybrid`]);
    /// each covers every depth, and all are counted in depth 0's row.
    pub hybrid_samples: u64,
    /// What one of the group's main-chain mutations is worth in independent samples of the
    /// chains' own density, as measured from the walkers' halves ([`super::efficiency`]; 0: not
    /// measured). Set when the image is developed.
    pub measured_efficiency: f64,
    /// The group's share of the mutations after they were re-allotted by the measured error
    /// ([`super::adaptive`]; 0: not re-allotted).
    pub reallotted_share: f64,
    /// The time and rays the render took before its first round (every group's bootstrap and
    /// preparation), in depth 0's row: the pilot of `--hybrid auto` measures the chains' work
    /// without them.
    pub setup_seconds: f64,
    pub setup_rays: u64,
    /// What the pilot of `--hybrid auto` measured and chose
    /// ([`crate::integrator::hybrid_pilot`]), in depth 0's row.
    pub hybrid_choice: Option<crate::integrator::hybrid_pilot::HybridChoice>,
    /// The bootstrap's independent acceptance ([`super::acceptance::independent_acceptance`])
    /// where tempered MMLT chose between its chains and BDPT by it, in depth 0's row.
    pub independent_acceptance: Option<f64>,
    /// What the pilot of `--importance-pilot` drew and chose
    /// ([`crate::integrator::importance_pilot`]), in depth 0's row.
    pub importance_pilot: Option<crate::integrator::importance_pilot::PilotChoice>,
    /// The sums of the bridge estimate of `b` ([`super::bridge`]) over the group's main chains.
    pub bridge: BridgeSums,
    /// `b` as the bridge estimate gives it from the bootstrap, the large steps and the chains'
    /// states (0: not estimated), and its relative standard error. Set when the image is
    /// developed.
    pub b_bridge: f64,
    pub b_bridge_rel_se: f64,
    /// Tempered MMLT with all-replica reuse: per neighbouring pair of replicas `(j, j + 1)`,
    /// the sums of the bridge estimate of `b_j/b_{j+1}` over the replicas' states
    /// ([`LadderBridge`]).
    pub ladder_bridge: Vec<LadderBridge>,
    /// `b` as the ladder gives it, the hottest replica's normalisation times the bridge ratios
    /// down the ladder (0: not estimated). Set when the image is developed.
    pub b_ladder: f64,
}

/// What a chain adds to the bridge estimate of its target's normalisation ([`super::bridge`])
/// at level `h`: `1/(f + h)` over its states (in expectation over each mutation's outcome)
/// and `f/(f + h)` over its large-step proposals (independent uniform samples).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct BridgeSums {
    /// The level `h` (0: none); the same for every chain of a group.
    pub level: f64,
    pub states: Moments,
    pub uniform: Moments,
}

impl BridgeSums {
    pub fn merge(&mut self, o: &BridgeSums) {
        if self.level == 0.0 {
            self.level = o.level;
        }
        self.states.merge(&o.states);
        self.uniform.merge(&o.uniform);
    }
}

impl DepthStats {
    /// Every field, bit for bit, for another process ([`crate::cluster`]).
    pub fn encode(&self, w: &mut Wire) {
        w.u64(self.depth as u64).u64(u64::from(self.all_depths)).f64(self.b).f64(self.b_rel_se);
        w.u64(self.bootstrap_samples).u64(self.large_step_samples).f64(self.spread).u64(self.mutations);
        w.u64(self.large_steps_proposed).u64(self.large_steps_accepted);
        w.u64(self.small_steps_proposed).u64(self.small_steps_accepted).u64(self.technique_changes);
        w.u64(self.jumps_proposed).u64(self.jumps_accepted);
        w.u64(self.film_steps_proposed).u64(self.film_steps_accepted);
        w.u64(self.lens_steps_proposed).u64(self.lens_steps_accepted);
        w.u64(self.invalid).f64(self.seconds).f64(self.prepare_seconds);
        w.u64(self.ladder.len() as u64);
        for &a in &self.ladder {
            w.f64(f64::from(a));
        }
        w.u64(self.ladder_ensembles);
        match &self.swaps {
            None => {
                w.u64(0);
            }
            Some(sw) => {
                w.u64(1).u64(sw.replicas as u64).u64(sw.attempts.len() as u64);
                for (&a, &b) in sw.attempts.iter().zip(&sw.accepted) {
                    w.u64(a).u64(b);
                }
                w.u64(sw.steps).u64(sw.no_pair).u64(sw.non_identity).u64(sw.main_changed);
            }
        }
        w.u64(self.replica_b_ratios.len() as u64);
        for &r in &self.replica_b_ratios {
            w.f64(f64::from(r));
        }
        w.u64(self.replica_b.len() as u64);
        for &b in &self.replica_b {
            w.f64(b);
        }
        w.u64(self.bootstrap_nonzero).u64(u64::from(self.independent)).f64(self.large_step_estimate);
        w.u64(self.hybrid_samples);
        w.f64(self.bridge.level);
        for m in [&self.bridge.states, &self.bridge.uniform] {
            w.f64(m.sum).f64(m.sum2).u64(m.n);
        }
        w.u64(self.ladder_bridge.len() as u64);
        for &x in self.ladder_bridge.iter().flat_map(|p| p.upper.iter().chain(&p.lower)) {
            w.f64(x);
        }
        w.f64(self.splat_weight);
    }

    /// Statistics [`Self::encode`] wrote.
    pub fn decode(r: &mut Reader) -> Self {
        let mut d = DepthStats {
            depth: r.u64() as usize,
            all_depths: r.u64() != 0,
            b: r.f64(),
            b_rel_se: r.f64(),
            bootstrap_samples: r.u64(),
            large_step_samples: r.u64(),
            spread: r.f64(),
            mutations: r.u64(),
            large_steps_proposed: r.u64(),
            large_steps_accepted: r.u64(),
            small_steps_proposed: r.u64(),
            small_steps_accepted: r.u64(),
            technique_changes: r.u64(),
            jumps_proposed: r.u64(),
            jumps_accepted: r.u64(),
            film_steps_proposed: r.u64(),
            film_steps_accepted: r.u64(),
            lens_steps_proposed: r.u64(),
            lens_steps_accepted: r.u64(),
            invalid: r.u64(),
            seconds: r.f64(),
            prepare_seconds: r.f64(),
            ..DepthStats::default()
        };
        d.ladder = (0..r.u64()).map(|_| r.f64() as f32).collect();
        d.ladder_ensembles = r.u64();
        if r.u64() == 1 {
            let replicas = r.u64() as usize;
            let n = r.u64() as usize;
            let (mut attempts, mut accepted) = (Vec::with_capacity(n), Vec::with_capacity(n));
            for _ in 0..n {
                attempts.push(r.u64());
                accepted.push(r.u64());
            }
            d.swaps = Some(SwapStats {
                replicas,
                attempts,
                accepted,
                steps: r.u64(),
                no_pair: r.u64(),
                non_identity: r.u64(),
                main_changed: r.u64(),
            });
        }
        d.replica_b_ratios = (0..r.u64()).map(|_| r.f64() as f32).collect();
        d.replica_b = (0..r.u64()).map(|_| r.f64()).collect();
        d.bootstrap_nonzero = r.u64();
        d.independent = r.u64() != 0;
        d.large_step_estimate = r.f64();
        d.hybrid_samples = r.u64();
        d.bridge.level = r.f64();
        for m in [&mut d.bridge.states, &mut d.bridge.uniform] {
            *m = Moments { sum: r.f64(), sum2: r.f64(), n: r.u64() };
        }
        d.ladder_bridge = vec![LadderBridge::default(); r.u64() as usize];
        for x in d.ladder_bridge.iter_mut().flat_map(|p| p.upper.iter_mut().chain(&mut p.lower)) {
            *x = r.f64();
        }
        d.splat_weight = r.f64();
        d
    }

    pub fn merge(&mut self, o: &DepthStats) {
        self.mutations += o.mutations;
        self.large_steps_proposed += o.large_steps_proposed;
        self.large_steps_accepted += o.large_steps_accepted;
        self.small_steps_proposed += o.small_steps_proposed;
        self.small_steps_accepted += o.small_steps_accepted;
        self.technique_changes += o.technique_changes;
        self.jumps_proposed += o.jumps_proposed;
        self.jumps_accepted += o.jumps_accepted;
        self.film_steps_proposed += o.film_steps_proposed;
        self.film_steps_accepted += o.film_steps_accepted;
        self.lens_steps_proposed += o.lens_steps_proposed;
        self.lens_steps_accepted += o.lens_steps_accepted;
        self.invalid += o.invalid;
        self.splat_weight += o.splat_weight;
        self.seconds += o.seconds;
        self.independent |= o.independent;
        self.hybrid_samples += o.hybrid_samples;
        self.bridge.merge(&o.bridge);
        if self.ladder_bridge.len() < o.ladder_bridge.len() {
            self.ladder_bridge.resize(o.ladder_bridge.len(), LadderBridge::default());
        }
        for (a, b) in self.ladder_bridge.iter_mut().zip(&o.ladder_bridge) {
            a.merge(b);
        }
        if let Some(o) = &o.swaps {
            self.swaps.get_or_insert_with(|| SwapStats::new(o.replicas)).merge(o);
        }
        if !o.ladder.is_empty() {
            if self.ladder.len() != o.ladder.len() {
                self.ladder = vec![0.0; o.ladder.len()];
                self.ladder_ensembles = 0;
            }
            let (n, m) = (self.ladder_ensembles as f64, o.ladder_ensembles.max(1) as f64);
            for (a, b) in self.ladder.iter_mut().zip(&o.ladder) {
                *a = ((f64::from(*a) * n + f64::from(*b) * m) / (n + m)) as f32;
            }
            self.ladder_ensembles += o.ladder_ensembles.max(1);
        }
    }

    pub fn acceptance(&self) -> f64 {
        let proposed = self.large_steps_proposed + self.small_steps_proposed;
        if proposed == 0 {
            0.0
        } else {
            (self.large_steps_accepted + self.small_steps_accepted) as f64 / proposed as f64
        }
    }
}

/// A target's normaliser samples ([`super::Target::normaliser`]): the moments of its
/// estimates and, where the target's own value is one of an estimate's terms picked at random
/// (MMLT's depth `k ≥ 1`: one strategy of the `n` whose MIS-weighted sum the estimate is,
/// scaled by `n`), the sum over the samples of that value's second moment given the sample,
/// `n · Σ_s Y_s²`. By the law of total variance the target's own per-sample variance is then
/// `E[n Σ_s Y_s²] − b²`, measured on the normaliser's samples, which see every strategy of
/// each path and so the rare bright paths one strategy finds far more often than the
/// target's own samples do.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NormaliserMoments {
    pub moments: Moments,
    pub one_sample_sum2: Option<f64>,
    /// Where a per-pixel map shapes the target ([`super::importance`]): the moments of the
    /// same samples' unshaped estimates, whose mean is the depth's total luminance.
    pub plain: Option<Moments>,
}

impl NormaliserMoments {
    pub fn merge(&mut self, o: &NormaliserMoments) {
        self.moments.merge(&o.moments);
        self.one_sample_sum2 = self.one_sample_sum2.zip(o.one_sample_sum2).map(|(a, b)| a + b);
        self.plain = match (self.plain, o.plain) {
            (Some(mut a), Some(b)) => {
                a.merge(&b);
                Some(a)
            }
            (a, b) => a.or(b),
        };
    }

    /// The target's own per-sample variance as the normaliser's samples measure it (`None`:
    /// not measurable, or no light seen).
    pub fn target_variance(&self) -> Option<f64> {
        let n = self.moments.n as f64;
        let mean = self.moments.sum / n;
        let v = self.one_sample_sum2? / n - mean * mean;
        (self.moments.n > 1 && mean > 0.0 && v.is_finite()).then_some(v.max(0.0) * n / (n - 1.0))
    }
}

/// Running sums of a target's values over independent uniform samples (the bootstrap, large
/// steps): its mean is a normalisation `b`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Moments {
    pub sum: f64,
    pub sum2: f64,
    pub n: u64,
}

impl Moments {
    pub fn push(&mut self, v: f64) {
        self.sum += v;
        self.sum2 += v * v;
        self.n += 1;
    }

    pub fn merge(&mut self, o: &Moments) {
        self.sum += o.sum;
        self.sum2 += o.sum2;
        self.n += o.n;
    }

    /// The mean and its relative standard error (0 where undefined).
    pub fn mean_and_rel_se(&self) -> (f64, f64) {
        let n = self.n;
        let b = if n > 0 { self.sum / n as f64 } else { 0.0 };
        let var = if n > 1 { (self.sum2 / n as f64 - b * b).max(0.0) * n as f64 / (n - 1) as f64 } else { 0.0 };
        (b, if b > 0.0 { (var / n as f64).sqrt() / b } else { 0.0 })
    }
}

/// What the swap steps did, per ensemble (merged per depth).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SwapStats {
    /// Replicas in the ensemble.
    pub replicas: usize,
    /// Attempts and acceptances per replica pair `(i, j)`, `i < j`, at index `i·K + j`.
    pub attempts: Vec<u64>,
    pub accepted: Vec<u64>,
    /// Swap steps taken.
    pub steps: u64,
    /// Equi-energy steps in which no ring held two replicas.
    pub no_pair: u64,
    /// Permutation steps that drew a permutation other than the identity, and that gave
    /// replica 0 another state.
    pub non_identity: u64,
    pub main_changed: u64,
}

impl SwapStats {
    pub fn new(replicas: usize) -> Self {
        Self {
            replicas,
            attempts: vec![0; replicas * replicas],
            accepted: vec![0; replicas * replicas],
            ..Self::default()
        }
    }

    pub fn record(&mut self, i: usize, j: usize, accepted: bool) {
        let (i, j) = (i.min(j), i.max(j));
        self.attempts[i * self.replicas + j] += 1;
        self.accepted[i * self.replicas + j] += u64::from(accepted);
    }

    pub fn merge(&mut self, o: &SwapStats) {
        if self.replicas == 0 {
            *self = SwapStats::new(o.replicas);
        }
        for (a, b) in self.attempts.iter_mut().zip(&o.attempts) {
            *a += b;
        }
        for (a, b) in self.accepted.iter_mut().zip(&o.accepted) {
            *a += b;
        }
        self.steps += o.steps;
        self.no_pair += o.no_pair;
        self.non_identity += o.non_identity;
        self.main_changed += o.main_changed;
    }

    /// Attempted and accepted exchanges between neighbours `(i, i + 1)`, over all pairs.
    pub fn neighbor_counts(&self) -> (u64, u64) {
        let k = self.replicas;
        (0..k.saturating_sub(1))
            .map(|i| (self.attempts[i * k + i + 1], self.accepted[i * k + i + 1]))
            .fold((0, 0), |(a, b), (x, y)| (a + x, b + y))
    }

    /// Acceptance rate of exchanges between neighbours `(i, i + 1)` over all their attempts.
    pub fn neighbor_acceptance(&self) -> f64 {
        let (attempts, accepted) = self.neighbor_counts();
        if attempts == 0 { 0.0 } else { accepted as f64 / attempts as f64 }
    }
}
