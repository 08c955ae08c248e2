//! The chain driver shared by every Markov-chain integrator (MMLT, PSSMLT, tempered MMLT):
//! groups of walkers (MMLT and tempering: one group per path depth; PSSMLT: one group), each
//! group bootstrapped ([`super::bootstrap`]) for its normalisation `b` and its start states.
//! Mutations are allotted to groups in proportion to `b` (Hachisuka et al. 2014 §5), or to `b`
//! times the spread of the group's bootstrap values ([`Bootstrap::spread`]); a fixed
//! budget runs in one round, a time budget in rounds of about one mutation per pixel until the
//! deadline, re-allotted once by the groups' measured error where asked ([`super::adaptive`]).
//! Walkers are the unit of parallel work and splat into fixed-point buffers shared by the
//! threads, so the image is bit-identical at any thread count.
//!
//! A walker splats into one or more layers per group. Layer `l`'s splats are normalised by
//! `b_l / ρ_l`, where `b_l` is the mean of target `l` over the group's bootstrap and the large
//! steps of the walkers sampling it, and `ρ_l` the ratio the walker weighted them with; a single
//! layer is MMLT's `b_k` with `ρ_0 = 1`. Large steps are independent uniform samples, so the
//! refined `b` does not hinge on the bootstrap. A target with a lower-variance estimator of its
//! own `b` (MMLT's depths: [`super::all_strategies`]) has it combined with those samples. Each
//! group's image is scaled by
//! `N_pixels · b_l/ρ_l / M` (`M` the group's mutations). With [`ChainSettings::hybrid`], BDPT
//! samples drawn beside the chains in a fixed ratio are combined with them by multiple
//! importance sampling ([`super::hybrid`]).

use super::Target;
use super::bootstrap::Bootstrap;
use super::develop::{develop, gather_reports, local_reports, sum_buffers, sum_splats};
use super::hybrid::Hybrid;
use super::hybrid_plan::HybridPlan;
use super::independent::Independent;
use super::normaliser::Topup;
use super::walker::{GroupContext, Layers, StartContext, Walker};
use crate::film::{Footprint, SharedSplats};
use crate::integrator::render_loop::RenderLoop;
use crate::integrator::{Budget, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::math::distribution::Distribution1D;
use crate::math::rng::{Pcg32, hash};
use crate::scene::Scene;
use rayon::prelude::*;

/// What the chain driver needs to know.
#[derive(Clone, Copy, Debug)]
pub struct ChainSettings {
    /// Bootstrap samples per group.
    pub bootstrap: usize,
    /// Independent walkers per group.
    pub chains: usize,
    pub sigma: f32,
    pub large_step_probability: f32,
    /// Allot mutations in proportion to `b` times the spread of each group's values
    /// ([`Bootstrap::spread`]) instead of `b` alone: a group whose light is carried by a few
    /// rare paths (a caustic) mixes slowly and gets more.
    pub spread_allocation: bool,
    /// With [`Self::spread_allocation`], the spread counts only for the groups whose bootstrap
    /// holds fewer non-zero values than this; the others are allotted by `b` alone (0: every
    /// group by `b` times spread).
    pub spread_below: usize,
    /// Also develop one image per group (MMLT and tempering: per path depth) into
    /// [`RenderOutput::layers`]; they sum to the image.
    pub group_images: bool,
    /// A group of a depth target (MMLT's and tempering's depths `k ≥ 1`) whose bootstrap has
    /// fewer non-zero values than this is sampled independently instead of by chains
    /// ([`super::independent`]); 0: never.
    pub independent_below: usize,
    /// The share of the chains' rays spent on further samples of the groups' own normalisers
    /// as the render goes on ([`super::normaliser`]; 0: the bootstrap's alone).
    pub normaliser_share: f64,
    /// Clamps each group's target, where it is [`Target::clampable`], at this many times the
    /// mean of its bootstrap's non-zero values ([`super::Chain::start_clamped`]); 0: never.
    pub clamp: f64,
    /// Samples of bidirectional path tracing per main-chain mutation, combined with the chains
    /// by multiple importance sampling ([`super::hybrid`]); 0: the chains alone.
    pub hybrid: f64,
    /// What a main-chain mutation counts as in those weights, in independent samples at the
    /// same density: a chain's successive states are correlated.
    pub chain_efficiency: f64,
    /// Instead of weights from [`Self::chain_efficiency`], the share of each depth's light the
    /// independent samples carry ([`super::hybrid::HybridDepth::with_share`]).
    pub sample_share: Option<f64>,
    /// Measure each group's chain efficiency: its walkers of odd index splat into buffers of
    /// their own ([`Group::odd`]; [`super::efficiency`]), developed with the others.
    pub measure_efficiency: bool,
    /// Scale each group's main layer by the bridge estimate of its normalisation
    /// ([`super::bridge`]) instead of `b` where [`super::bridge::prefer`] says so at this
    /// threshold (`None`: never).
    pub bridge_above: Option<f64>,
    /// Under a time budget, re-allot the mutations by the error each group's chains measure
    /// after this share of the budget ([`super::adaptive`]; 0: by `b` throughout). Its walkers
    /// splat in halves for the measurement ([`Group::odd`]).
    pub reallot_at: f64,
    /// The probability that a chain proposes a reversible jump between the techniques of its
    /// path instead of a mutation ([`super::jump`]; 0: never).
    pub jumps: f32,
    /// The probability that a small step is a film step, which moves the state's film position
    /// alone ([`crate::sampler::PssSampler::with_film_steps`]; 0: never).
    pub film_steps: f32,
    /// The probability that a small step is a lens step: it moves the film position as a film
    /// step does and keeps the path's second camera vertex ([`super::lens`]; 0: never).
    pub lens_steps: f32,
}

/// Every group's bootstrap, made before the render ([`ChainSettings::bootstrap_groups`]),
/// and the rays it traced.
pub struct Bootstraps {
    pub boots: Vec<Bootstrap>,
    pub rays: u64,
}

/// One walker's place in the render.
#[derive(Clone, Copy, Debug)]
pub(super) struct Slot {
    /// Its group.
    pub group: usize,
    /// Its index in the group.
    pub index: usize,
    /// The group's walker count.
    pub walkers: u64,
    /// The group's mutations under a fixed budget.
    pub budget: Option<u64>,
}

impl Slot {
    /// This walker's share of its group's fixed budget.
    pub fn quota(&self) -> u64 {
        let m = self.budget.unwrap_or(0);
        m / self.walkers + u64::from((self.index as u64) < m % self.walkers)
    }
}

/// A prepared group: what its walkers share, its splat buffers (one per layer), and the time
/// its preparation took.
pub(super) struct Group<L> {
    pub shared: L,
    pub splats: Vec<SharedSplats>,
    /// Where the walkers of odd index splat instead, when the chain efficiency is measured
    /// ([`ChainSettings::measure_efficiency`]); empty otherwise.
    pub odd: Vec<SharedSplats>,
    pub seconds: f64,
}

/// Which groups' walkers splat in halves ([`Group::odd`]).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Halves {
    None,
    /// The groups with one layer (the re-allotment measures those alone).
    SingleLayer,
    /// Every group (the chain efficiency is measured for every one).
    Every,
}

/// Every group's preparation (`None`: a group without walkers); a group sampled
/// independently shares nothing (`shared` is `None`).
type Prepared<W> = Vec<Option<Group<Option<<W as Walker>::Group>>>>;

impl ChainSettings {
    /// Renders with `groups` independent sets of walkers (MMLT: one per path depth; PSSMLT:
    /// one), group `k` bootstrapped under `targets(k)` (or taken from `bootstraps`, made by
    /// [`Self::bootstrap_groups`] under the same seed and targets: the same image without
    /// bootstrapping again) and its walkers started by `start_walker`. The statistics carry one
    /// row per group. An error when no light path reaches the camera.
    #[allow(clippy::too_many_arguments)]
    pub fn render<T, W>(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        groups: usize,
        targets: impl Fn(usize) -> T + Sync,
        start_walker: impl Fn(StartContext) -> W + Sync,
        bootstraps: Option<Bootstraps>,
    ) -> Result<RenderOutput, String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let render = RenderLoop::new(settings, control);
        render.install(|| self.render_in_pool(&render, scene, settings, groups, &targets, &start_walker, bootstraps))
    }

    /// Bootstraps every group as [`Self::render`] does (the same samples, so the same values),
    /// on the render's threads, for a caller that decides from them how to render; an error
    /// when no light path reaches the camera.
    pub fn bootstrap_groups<T: Target + Sync>(
        &self,
        settings: &RenderSettings,
        control: &RenderControl,
        groups: usize,
        targets: impl Fn(usize) -> T + Sync,
    ) -> Result<Bootstraps, String> {
        let render = RenderLoop::new(settings, control);
        render
            .install(|| self.bootstrap(settings.seed, groups, &targets))
            .map(|(boots, rays)| Bootstraps { boots, rays })
    }

    /// Bootstraps every group; an error when all of them saw no light.
    fn bootstrap<T: Target + Sync>(
        &self,
        seed: u64,
        groups: usize,
        targets: &(impl Fn(usize) -> T + Sync),
    ) -> Result<(Vec<Bootstrap>, u64), String> {
        let (boots, rays) = if groups > 1 && targets(0).values_groups_together() {
            Bootstrap::run_groups(targets, self, seed, groups)
        } else {
            let mut rays = 0;
            let boots: Vec<Bootstrap> = (0..groups)
                .map(|k| {
                    let (b, r) = Bootstrap::run(&targets(k), self, seed, k);
                    rays += r;
                    b
                })
                .collect();
            (boots, rays)
        };
        let b_total: f64 = boots.iter().map(Bootstrap::b).sum();
        if b_total.is_nan() || b_total <= 0.0 {
            return Err("no light path reaches the camera (every bootstrap sample was zero)".into());
        }
        Ok((boots, rays))
    }

    /// A group's weight in the allotment of mutations: its normalisation `b` (Hachisuka et al.
    /// 2014), times the spread of its values with [`Self::spread_allocation`].
    fn weight(&self, boot: &Bootstrap) -> f64 {
        let b = boot.b();
        let sparse = self.spread_below == 0 || (boot.nonzero() as usize) < self.spread_below;
        if self.spread_allocation && sparse { b * boot.spread() } else { b }
    }

    /// The walkers of every group with light: under a fixed budget each group's share of the
    /// mutations in proportion to its weight, and no more walkers than mutations.
    /// A group whose bootstrap holds no light has no state to start from: it gets no walkers,
    /// unless it is sampled independently (`independent[k]`) and its normaliser saw light.
    fn plan(&self, boots: &[Bootstrap], independent: &[bool], budget: Option<u64>) -> Vec<Slot> {
        let total: f64 = boots.iter().map(|b| self.weight(b)).sum();
        let mut plan = Vec::new();
        for (k, b) in boots.iter().enumerate() {
            if b.b() <= 0.0 || (b.mean <= 0.0 && !independent[k]) {
                continue;
            }
            let m_k = budget.map(|m| (self.weight(b) / total * m as f64).round() as u64);
            if m_k == Some(0) {
                continue;
            }
            let walkers = m_k.map_or(self.chains as u64, |m| (self.chains as u64).min(m)).max(1);
            for c in 0..walkers {
                plan.push(Slot { group: k, index: c as usize, walkers, budget: m_k });
            }
        }
        plan
    }

    #[allow(clippy::too_many_arguments)]
    fn render_in_pool<T, W>(
        &self,
        render: &RenderLoop,
        scene: &Scene,
        settings: &RenderSettings,
        groups: usize,
        targets: &(impl Fn(usize) -> T + Sync),
        start_walker: &(impl Fn(StartContext) -> W + Sync),
        bootstraps: Option<Bootstraps>,
    ) -> Result<RenderOutput, String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let seed = settings.seed;
        let (w, h) = (scene.film.width, scene.film.height);
        let pixels = u64::from(w) * u64::from(h);
        let started = std::time::Instant::now();
        let (mut boots, mut total_rays) = match bootstraps {
            Some(Bootstraps { boots, rays }) => (boots, rays),
            None => self.bootstrap(seed, groups, targets)?,
        };
        let total: f64 = boots.iter().map(|b| self.weight(b)).sum();
        let shares: Vec<f64> = boots.iter().map(|b| self.weight(b) / total).collect();
        let mut topup = Topup::new(&boots, &shares, self.normaliser_share);
        let budget = match settings.budget {
            Budget::Samples(mpp) => Some(u64::from(mpp) * pixels),
            Budget::Time(_) => None,
        };
        let independent: Vec<bool> = (0..groups).map(|k| self.independent(&boots[k], &targets(k))).collect();
        let (iplan, plan): (Vec<Slot>, Vec<Slot>) =
            self.plan(&boots, &independent, budget).into_iter().partition(|slot| independent[slot.group]);
        let mut independents: Vec<Independent> =
            iplan.iter().map(|slot| Independent::new(slot.group, seed, slot.index)).collect();
        // Every independent walker's samples cover all the independently sampled depths.
        let independent_depths: Vec<usize> =
            (0..groups).filter(|&k| independent[k] && iplan.iter().any(|s| s.group == k)).collect();
        // A time budget's rounds of about one mutation per pixel, shared as the fixed budget is.
        let quota_at = |shares: &[f64], slot: &Slot| {
            ((shares[slot.group] * pixels as f64 / slot.walkers as f64).round() as u64).max(1)
        };
        let round_quota = |slot: &Slot| quota_at(&shares, slot);
        // One footprint of the film's filter for every splat buffer.
        let footprint = Footprint::of(&scene.film);
        let kappa = super::efficiency::filter_energy(&footprint);
        let hybrid = HybridPlan::new(self, &boots, (&plan, &independent), budget.is_some(), &round_quota, &footprint);
        if !hybrid.depths.is_empty() && (0..groups).any(|k| targets(k).hybrid_depth() != Some(k)) {
            return Err("combining chains with bidirectional path tracing needs MMLT's per-depth targets".into());
        }
        let mut hybrids: Vec<Hybrid> =
            hybrid.plan.iter().map(|slot| Hybrid::new(seed, slot.index, hybrid.plan.len())).collect();
        let levels = hybrid.levels(groups);
        // When the mutations are re-allotted by the groups' measured error ([`super::adaptive`]).
        let mut reallot_after = match settings.budget {
            Budget::Time(t) if self.reallot_at > 0.0 && hybrid.depths.is_empty() => {
                Some(t.mul_f64(self.reallot_at.min(1.0)))
            }
            _ => None,
        };
        // The bridge estimates' levels: each group's bootstrap mean.
        let bridges: Vec<f32> = boots.iter().map(|b| b.b() as f32).collect();
        // Walkers start from bootstrap states drawn in proportion to their value.
        let starts: Vec<Distribution1D> = boots.iter().map(Bootstrap::starts).collect();
        let mut walkers: Vec<W> = plan
            .par_iter()
            .map(|slot| {
                let (k, c) = (slot.group, slot.index);
                let rng = Pcg32::new(hash(&[seed, 0xc4a1, k as u64, c as u64]), 7);
                let bootstrap = &boots[k].values;
                let group = GroupContext {
                    k,
                    seed,
                    settings: self,
                    budget: slot.budget,
                    clamp: boots[k].clamp,
                    mis_level: levels[k],
                    bridge_level: bridges[k],
                };
                start_walker(StartContext { group, c, rng, starts: &starts[k], bootstrap })
            })
            .collect();
        let stop = || render.should_stop();
        let clamps: Vec<f32> = boots.iter().map(|b| b.clamp).collect();
        let (mut prepared, rays) = self.prepare(
            &plan,
            &mut walkers,
            seed,
            (
                &clamps,
                &levels,
                &bridges,
                match (self.measure_efficiency, reallot_after.is_some()) {
                    (true, _) => Halves::Every,
                    (false, true) => Halves::SingleLayer,
                    (false, false) => Halves::None,
                },
            ),
            &footprint,
            &stop,
        );
        total_rays += rays;
        let setup = (started.elapsed().as_secs_f64(), total_rays);
        for slot in &iplan {
            prepared[slot.group].get_or_insert_with(|| Group {
                shared: None,
                splats: vec![SharedSplats::filtered(&footprint)],
                odd: Vec::new(),
                seconds: 0.0,
            });
        }
        // Every rank prepares every group alike; each runs the walkers dealt to it (the
        // independent ones numbered after the chains, the hybrid samples' after those).
        let cluster = render.control.cluster;
        let slots: Vec<Slot> = plan.iter().chain(&iplan).chain(&hybrid.plan).copied().collect();
        let independent_splats: Vec<&SharedSplats> = independent_depths
            .iter()
            .map(|&k| &prepared[k].as_ref().expect("every planned group is prepared").splats[0])
            .collect();
        let hybrid_ks: Vec<usize> = hybrid.depths.iter().map(|d| d.k).collect();
        let run_round = |walkers: &mut [W],
                         independents: &mut [Independent],
                         hybrids: &mut [Hybrid],
                         quota: &(dyn Fn(&Slot) -> u64 + Sync)| {
            // One walker per job: walkers differ in cost by orders of magnitude (the plan is
            // ordered by group, and the shallow depths hold most of the mutations), and rayon's
            // adaptive splitting would otherwise leave one thread a quarter of the plan to run
            // alone once the others have finished theirs.
            walkers.par_iter_mut().with_max_len(1).zip(&plan).enumerate().filter(|(i, _)| cluster.owns(*i)).for_each(
                |(_, (walker, slot))| {
                    let group = prepared[slot.group].as_ref().expect("every planned group is prepared");
                    let shared = group.shared.as_ref().expect("a group of walkers has their shared state");
                    let splats = if slot.index % 2 == 1 && !group.odd.is_empty() { &group.odd } else { &group.splats };
                    let done = walker.run(shared, quota(slot), splats, &stop);
                    render.progress(done);
                },
            );
            independents
                .par_iter_mut()
                .with_max_len(1)
                .zip(&iplan)
                .enumerate()
                .filter(|(i, _)| cluster.owns(plan.len() + *i))
                .for_each(|(_, (walker, slot))| {
                    let done = walker.run(scene, &independent_depths, quota(slot), &independent_splats, &stop);
                    render.progress(done);
                });
            // The independent samples combined with the chains: the same share of every round
            // (the weights assume it), or of the fixed budget.
            let first = plan.len() + iplan.len();
            hybrids
                .par_iter_mut()
                .with_max_len(1)
                .zip(&hybrid.plan)
                .enumerate()
                .filter(|(i, _)| cluster.owns(first + *i))
                .for_each(|(_, (walker, slot))| {
                    walker.run(scene, &hybrid.depths, &hybrid_ks, &hybrid.film, slot.quota(), &stop);
                });
        };
        // The image so far (at rank 0, from every rank's walkers), its statistics taken
        // `seconds` after the start.
        // `extra` counts the normalisers' rays since the bootstrap.
        let developed = |boots: &[Bootstrap],
                         extra: u64,
                         walkers: &[W],
                         independents: &[Independent],
                         hybrids: &[Hybrid],
                         seconds: f64| {
            let local = local_reports(cluster, (walkers, independents, hybrids), &plan, &prepared);
            let reports = gather_reports(cluster, local);
            let summed = cluster.is_distributed().then(|| sum_splats(cluster, &prepared));
            let hybrid_summed =
                cluster.is_distributed().then(|| hybrid.film.with_buffers(sum_buffers(cluster, &hybrid.film.buffers)));
            let independent_image = (!hybrid.depths.is_empty())
                .then(|| (hybrid.depths.as_slice(), hybrid_summed.as_ref().unwrap_or(&hybrid.film)));
            let mut out = develop(
                boots,
                &reports,
                &slots,
                &prepared,
                (summed.as_deref(), independent_image),
                (w, h),
                (self.group_images, kappa, self.bridge_above),
            );
            if let Some(first) = out.chains.first_mut() {
                (first.setup_seconds, first.setup_rays) = setup;
            }
            RenderOutput {
                stats: RenderStats { rays: out.stats.rays + total_rays + extra, seconds, ..out.stats },
                ..out
            }
        };
        // The shares after the mutations were re-allotted, where they were.
        let mut reallotted: Option<Vec<f64>> = None;
        match budget {
            // A fixed budget: one round, each walker its share of its group's mutations.
            Some(m) => {
                run_round(&mut walkers, &mut independents, &mut hybrids, &Slot::quota);
                topup.run(&mut boots, targets, seed, m, &stop);
            }
            // A time budget: rounds of about one mutation per pixel, shared in proportion to
            // b_k, until the deadline (rank 0's). Snapshots (if asked for) are developed
            // between rounds.
            None => {
                let mut snapshots = render.snapshots(settings.budget);
                // The shares the rounds run at, and the main-chain mutations a whole round makes,
                // on every rank together.
                let mut now = shares.clone();
                let mut per_round: u64 = plan.iter().map(round_quota).sum();
                let mut made = 0u64;
                while !cluster.broadcast(stop()) {
                    run_round(&mut walkers, &mut independents, &mut hybrids, &|slot: &Slot| quota_at(&now, slot));
                    // The normalisers keep pace with the rounds finished on every rank.
                    if !cluster.broadcast(stop()) {
                        made += per_round;
                        topup.run(&mut boots, targets, seed, made, &|| false);
                    }
                    if reallot_after.is_some_and(|at| cluster.broadcast(started.elapsed() >= at)) {
                        reallot_after = None;
                        let out = developed(&boots, topup.rays, &walkers, &independents, &hybrids, 0.0);
                        let summed = cluster.is_distributed().then(|| sum_splats(cluster, &prepared));
                        if let Some(new) =
                            super::adaptive::reallot(cluster, &out, &prepared, summed.as_deref(), &plan, &now)
                        {
                            now = new;
                            per_round = plan.iter().map(|slot| quota_at(&now, slot)).sum();
                            reallotted = Some(now.clone());
                        }
                    }
                    if cluster.broadcast(snapshots.is_due(render)) {
                        let out = developed(&boots, topup.rays, &walkers, &independents, &hybrids, 0.0);
                        snapshots.take(render, |seconds| RenderOutput {
                            stats: RenderStats { seconds, ..out.stats.clone() },
                            ..out
                        });
                    }
                }
            }
        }
        let mut out = developed(&boots, topup.rays, &walkers, &independents, &hybrids, 0.0);
        for (d, &share) in out.chains.iter_mut().zip(reallotted.iter().flatten()) {
            d.reallotted_share = share;
        }
        render.finish(&mut out.stats);
        Ok(out)
    }

    /// Prepares each group's walkers (contiguous in the plan), all groups at once (each
    /// group's result does not depend on the others'), and allocates the group's splat
    /// buffers, one per layer, shared by the threads.
    #[allow(clippy::too_many_arguments)]
    fn prepare<W: Walker>(
        &self,
        plan: &[Slot],
        walkers: &mut [W],
        seed: u64,
        (clamps, levels, bridges, halves): (&[f32], &[f32], &[f32], Halves),
        footprint: &std::sync::Arc<Footprint>,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (Prepared<W>, u64) {
        let mut slices: Vec<(usize, Option<u64>, &mut [W])> = Vec::new();
        let (mut rest, mut first) = (walkers, 0);
        while !rest.is_empty() {
            let k = plan[first].group;
            let n = plan[first..].iter().take_while(|p| p.group == k).count();
            let (group, tail) = rest.split_at_mut(n);
            slices.push((k, plan[first].budget, group));
            (rest, first) = (tail, first + n);
        }
        let results: Vec<(usize, W::Group, u64, f64)> = slices
            .into_par_iter()
            .with_max_len(1)
            .map(|(k, budget, group)| {
                let start = std::time::Instant::now();
                let cx = GroupContext {
                    k,
                    seed,
                    settings: self,
                    budget,
                    clamp: clamps[k],
                    mis_level: levels[k],
                    bridge_level: bridges[k],
                };
                let (shared, rays) = W::prepare_group(group, &cx, stop);
                (k, shared, rays, start.elapsed().as_secs_f64())
            })
            .collect();
        let mut prepared: Prepared<W> = (0..clamps.len()).map(|_| None).collect();
        let mut rays = 0;
        for (k, shared, r, seconds) in results {
            rays += r;
            let splats = (0..shared.count()).map(|_| SharedSplats::filtered(footprint)).collect();
            // Halves need a walker in each.
            let split = halves == Halves::Every || (halves == Halves::SingleLayer && shared.count() == 1);
            let odd = if split && plan.iter().any(|s| s.group == k && s.index == 1) {
                (0..shared.count()).map(|_| SharedSplats::filtered(footprint)).collect()
            } else {
                Vec::new()
            };
            prepared[k] = Some(Group { shared: Some(shared), splats, odd, seconds });
        }
        (prepared, rays)
    }
}
