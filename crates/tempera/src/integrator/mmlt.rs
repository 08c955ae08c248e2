//! Multiplexed Metropolis light transport (Hachisuka, Kaplanyan & Dachsbacher 2014; pbrt-v4
//! §13.4): per path depth `k`, Markov chains in primary sample space whose states choose one
//! bidirectional strategy each; target `f = luminance((k+2)·w·f/p)`. A bootstrap of independent
//! states gives the normalisation `b_k` and the chains' start states (drawn in proportion to
//! `f`, which removes start-up bias); mutations are allotted to depths in proportion to `b_k`;
//! proposals and current states are splatted with expected values (`a` and `1 − a`, as `C/f`).
//! `b_k` is refined with the large-step proposals, which are independent uniform samples, so the
//! image brightness does not hinge on the bootstrap. Chains are the unit of parallel work and
//! splat into fixed-point buffers shared by the threads (one per depth, and per replica when
//! tempered replicas are reused): the image is bit-identical at any thread count.

use super::{Budget, ChainIntegrator, RenderControl, RenderOutput, RenderSettings, RenderStats, SnapshotClock};
use crate::film::SharedSplats;
use crate::math::distribution::Distribution1D;
use crate::math::rng::{Pcg32, hash};
use crate::mcmc::{Chain, Contribution, DepthStats, Moments, Paths, State, Target, evaluate};
use crate::sampler::PssSampler;
use crate::scene::Scene;
use crate::texture::Image;
use rayon::prelude::*;
use std::sync::atomic::Ordering;
use std::time::Instant;

#[derive(Clone, Copy, Debug)]
pub struct MmltIntegrator {
    pub max_depth: u32,
    /// Bootstrap samples per depth.
    pub bootstrap: usize,
    /// Independent chains per depth.
    pub chains: usize,
    pub sigma: f32,
    pub large_step_probability: f32,
}

impl MmltIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, bootstrap: 20_000, chains: 64, sigma: 0.01, large_step_probability: 0.3 }
    }
}

/// Everything a render reports beyond the image.
#[derive(Clone, Debug, Default)]
pub struct MmltReport {
    pub depths: Vec<DepthStats>,
}

/// Seed of bootstrap sample `i` of depth `k`.
fn bootstrap_seed(seed: u64, k: usize, i: usize) -> u64 {
    hash(&[seed, 0xb007, k as u64, i as u64])
}

pub(super) fn sampler_for(seed: u64, k: usize, i: usize, m: &ChainSettings) -> PssSampler {
    PssSampler::new(bootstrap_seed(seed, k, i), k as u64, m.sigma, m.large_step_probability)
}

/// What the chain driver shared by MMLT and PSSMLT needs to know.
#[derive(Clone, Copy, Debug)]
pub(super) struct ChainSettings {
    /// Bootstrap samples per group.
    pub bootstrap: usize,
    /// Independent chains per group.
    pub chains: usize,
    pub sigma: f32,
    pub large_step_probability: f32,
}

/// A unit of parallel work of the chain driver: one chain (MMLT, PSSMLT) or one ensemble of
/// replicas (tempered MMLT).
///
/// A walker splats into one or more layers per group. Layer `l`'s splats are normalised by
/// `b_l / ρ_l`, where `b_l` is the mean of target `l` over the group's bootstrap and the large
/// steps of the chains sampling it, and `ρ_l` the ratio the walker weighted them with; a single
/// layer is MMLT's `b_k` with `ρ_0 = 1`.
pub(super) trait Walker: Send {
    /// Makes up to `mutations` mutations of the main chain, splatting into `splats` (one
    /// buffer per layer, shared with the group's other walkers); returns how many were made.
    fn run(&mut self, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64;
    /// The main chain's statistics (with swap statistics for ensembles).
    fn stats(&self) -> DepthStats;
    /// The layers this walker splats into (fixed once its group is prepared).
    fn layers(&self) -> usize {
        1
    }
    /// The moments of `layer`'s target over the walker's large-step proposals (independent
    /// uniform samples; an ensemble values every replica's under the layer's target).
    fn large(&self, layer: usize) -> Moments;
    /// With several layers: per layer, the moments of its target over the group's bootstrap
    /// (shared by the group's walkers) and the ratio `ρ_l` its splats were weighted with.
    fn calibration(&self) -> Option<(&[Moments], &[f64])> {
        None
    }
    fn rays(&self) -> u64;
    /// Prepares the walkers of one group together, before the first round (tempered MMLT
    /// tunes one ladder per depth and calibrates the replicas' normalisations here); returns
    /// the rays it traced.
    fn prepare_group(_walkers: &mut [Self], _group: &GroupContext, _stop: &(dyn Fn() -> bool + Sync)) -> u64
    where
        Self: Sized,
    {
        0
    }
}

/// What [`Walker::prepare_group`] knows of its group.
pub(super) struct GroupContext<'a> {
    pub k: usize,
    pub seed: u64,
    pub settings: &'a ChainSettings,
}

/// Where a walker starts: chain `c` of group `k`, with the group's bootstrap values and the
/// distribution of start states (in proportion to their value).
pub(super) struct StartContext<'a> {
    pub k: usize,
    pub c: usize,
    pub seed: u64,
    pub rng: Pcg32,
    pub starts: &'a Distribution1D,
    pub bootstrap: &'a [f32],
}

/// One chain with its target.
pub(super) struct Single<T: Target> {
    pub chain: Chain<T::State>,
    pub target: T,
}

impl<T: Target + Send> Walker for Single<T>
where
    T::State: Send,
{
    fn run(&mut self, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        self.chain.run(&self.target, mutations, Some(&splats[0]), stop)
    }

    fn stats(&self) -> DepthStats {
        self.chain.stats.clone()
    }

    fn large(&self, _layer: usize) -> Moments {
        self.chain.large
    }

    fn rays(&self) -> u64 {
        self.chain.rays
    }
}

impl ChainSettings {
    pub fn new(bootstrap: usize, chains: usize, sigma: f32, large_step_probability: f32) -> Self {
        Self { bootstrap, chains, sigma, large_step_probability }
    }

    /// Starts a single chain from a bootstrap state drawn in proportion to its value.
    pub(super) fn start_single<T: Target>(&self, cx: StartContext, target: T) -> Single<T> {
        let mut rng = cx.rng;
        let (index, _, _) = cx.starts.sample_discrete(rng.next_f32());
        let chain = Chain::start(&target, sampler_for(cx.seed, cx.k, index, self), rng, cx.k);
        Single { chain, target }
    }
}

/// The MMLT target of one path depth.
struct DepthTarget<'a> {
    scene: &'a Scene,
    depth: usize,
}

impl Target for DepthTarget<'_> {
    type State = Contribution;

    fn evaluate(&self, sampler: &mut PssSampler, paths: &mut Paths, rays: &mut u64, out: &mut Contribution) -> bool {
        let (c, invalid) = evaluate(self.scene, self.depth, sampler, paths, rays);
        *out = c;
        invalid
    }
}

/// The result of the bootstrap of one depth: target values and their mean.
struct Bootstrap {
    values: Vec<f32>,
    mean: f64,
    sum2: f64,
    invalid: u64,
}

impl ChainSettings {
    fn bootstrap<T: Target + Sync>(&self, target: &T, seed: u64, k: usize) -> (Bootstrap, u64) {
        let results: Vec<(f32, bool, u64)> = (0..self.bootstrap)
            .into_par_iter()
            .map_init(
                || (Paths::default(), T::State::default()),
                |(paths, state), i| {
                    let mut sampler = sampler_for(seed, k, i, self);
                    let mut rays = 0;
                    let invalid = target.evaluate(&mut sampler, paths, &mut rays, state);
                    (state.value(), invalid, rays)
                },
            )
            .collect();
        let values: Vec<f32> = results.iter().map(|r| r.0).collect();
        let n = values.len().max(1) as f64;
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let sum2 = values.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>();
        let invalid = results.iter().filter(|r| r.1).count() as u64;
        let rays = results.iter().map(|r| r.2).sum();
        (Bootstrap { values, mean, sum2, invalid }, rays)
    }

    /// Renders with `groups` independent sets of chains (MMLT: one per path depth; PSSMLT: one),
    /// group `k` sampling `targets(k)`, and returns the per-group statistics alongside the image.
    pub(super) fn render<T, W>(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        depths: usize,
        targets: impl Fn(usize) -> T + Sync,
        start_walker: impl Fn(StartContext) -> W + Sync,
    ) -> Result<(RenderOutput, MmltReport), String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let start = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .expect("a rayon thread pool can be created");
        pool.install(|| self.render_in_pool(scene, settings, control, start, depths, (&targets, &start_walker)))
    }

    fn render_in_pool<T, W>(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        start: Instant,
        depths: usize,
        (targets, start_walker): (&(impl Fn(usize) -> T + Sync), &(impl Fn(StartContext) -> W + Sync)),
    ) -> Result<(RenderOutput, MmltReport), String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let seed = settings.seed;
        let (w, h) = (scene.film.width, scene.film.height);
        let pixels = u64::from(w) * u64::from(h);
        let mut total_rays = 0;
        let boots: Vec<Bootstrap> = (0..depths)
            .map(|k| {
                let (b, rays) = self.bootstrap(&targets(k), seed, k);
                total_rays += rays;
                b
            })
            .collect();
        let b_total: f64 = boots.iter().map(|b| b.mean).sum();
        if b_total.is_nan() || b_total <= 0.0 {
            return Err("no light path reaches the camera (every bootstrap sample was zero)".into());
        }
        let share = |k: usize| boots[k].mean / b_total;
        // Chains per depth, started from bootstrap states drawn in proportion to their value.
        let mpp_total = match settings.budget {
            Budget::Samples(mpp) => Some(u64::from(mpp) * pixels),
            Budget::Time(_) => None,
        };
        let deadline = match settings.budget {
            Budget::Time(d) => Some(start + d),
            Budget::Samples(_) => None,
        };
        let mut plan = Vec::new();
        for (k, b) in boots.iter().enumerate() {
            if b.mean <= 0.0 {
                continue;
            }
            let m_k = mpp_total.map(|m| (share(k) * m as f64).round() as u64);
            if m_k == Some(0) {
                continue;
            }
            let chains = m_k.map_or(self.chains as u64, |m| (self.chains as u64).min(m)).max(1);
            for c in 0..chains {
                plan.push((k, c as usize, chains, m_k));
            }
        }
        let starts: Vec<Distribution1D> = boots.iter().map(|b| Distribution1D::new(&b.values)).collect();
        let mut chains: Vec<W> = plan
            .par_iter()
            .map(|&(k, c, _, _)| {
                let rng = Pcg32::new(hash(&[seed, 0xc4a1, k as u64, c as u64]), 7);
                start_walker(StartContext { k, c, seed, rng, starts: &starts[k], bootstrap: &boots[k].values })
            })
            .collect();
        let stop = || control.cancel.load(Ordering::Relaxed) || deadline.is_some_and(|d| Instant::now() >= d);
        // Walkers of a group are contiguous in the plan; groups are prepared independently of
        // each other, all at once (each group's result does not depend on the others').
        let mut groups: Vec<(usize, &mut [W])> = Vec::new();
        let (mut rest, mut first) = (chains.as_mut_slice(), 0);
        while !rest.is_empty() {
            let k = plan[first].0;
            let n = plan[first..].iter().take_while(|p| p.0 == k).count();
            let (group, tail) = rest.split_at_mut(n);
            groups.push((k, group));
            (rest, first) = (tail, first + n);
        }
        total_rays += groups
            .into_par_iter()
            .map(|(k, group)| W::prepare_group(group, &GroupContext { k, seed, settings: self }, &stop))
            .sum::<u64>();
        let mut layers = vec![1; depths];
        for (chain, &(k, ..)) in chains.iter().zip(&plan) {
            layers[k] = layers[k].max(chain.layers());
        }
        // One buffer per layer of each group, shared by the threads.
        let splats: Vec<Vec<SharedSplats>> =
            layers.iter().map(|&n| (0..n).map(|_| SharedSplats::new(w, h)).collect()).collect();
        let run_round = |chains: &mut [W], quota: &(dyn Fn(usize) -> u64 + Sync)| {
            chains.par_iter_mut().enumerate().for_each(|(i, chain)| {
                let (k, ..) = plan[i];
                let n = quota(i);
                let done = chain.run(n, &splats[k], &stop);
                (control.on_progress)(done);
            });
        };
        match mpp_total {
            // A fixed budget: one round, each chain its share of its depth's mutations.
            Some(_) => run_round(&mut chains, &|i| {
                let (_, c, n, m_k) = plan[i];
                let m_k = m_k.unwrap_or(0);
                m_k / n + u64::from((c as u64) < m_k % n)
            }),
            // A time budget: rounds of about one mutation per pixel, shared in proportion to b_k,
            // until the deadline.
            // Snapshots (if asked for) are developed between rounds.
            None => {
                let mut clock = SnapshotClock::new(start, control, settings.budget);
                while !stop() {
                    run_round(&mut chains, &|i| {
                        let (k, _, n, _) = plan[i];
                        ((share(k) * pixels as f64 / n as f64).round() as u64).max(1)
                    });
                    if clock.due() && !control.cancel.load(Ordering::Relaxed) {
                        let out = develop(&boots, &chains, &plan, &splats, pixels);
                        let seconds = start.elapsed().as_secs_f64();
                        let out = RenderOutput {
                            stats: RenderStats { rays: out.stats.rays + total_rays, seconds, ..out.stats },
                            ..out
                        };
                        clock.deliver(control, &out);
                    }
                }
            }
        }
        let out = develop(&boots, &chains, &plan, &splats, pixels);
        let out = RenderOutput {
            stats: RenderStats {
                rays: out.stats.rays + total_rays,
                seconds: start.elapsed().as_secs_f64(),
                cancelled: control.cancel.load(Ordering::Relaxed),
                ..out.stats
            },
            ..out
        };
        let report = MmltReport { depths: out.chains.clone() };
        Ok((out, report))
    }
}

/// What the chain driver plans: per walker its group, index, the group's walker count and the
/// group's mutation budget (`None` under a time budget).
type Plan = [(usize, usize, u64, Option<u64>)];

/// The image and per-group statistics of `chains` so far: statistics merged in chain order,
/// each layer's normalisation `b_l` refined with the large-step proposals, each layer's splats
/// scaled to estimate its share of the image per mutation. Rays count the chains' rays only.
fn develop<W: Walker>(
    boots: &[Bootstrap],
    chains: &[W],
    plan: &Plan,
    per_group: &[Vec<SharedSplats>],
    pixels: u64,
) -> RenderOutput {
    let depths = boots.len();
    let mut stats: Vec<DepthStats> = (0..depths).map(|k| DepthStats { depth: k, ..DepthStats::default() }).collect();
    let mut large: Vec<Vec<Moments>> = per_group.iter().map(|g| vec![Moments::default(); g.len()]).collect();
    // Shared by a group's walkers: the first one's serves.
    let mut calibration: Vec<Option<(&[Moments], &[f64])>> = vec![None; depths];
    let mut rays = 0;
    for (chain, &(k, ..)) in chains.iter().zip(plan) {
        stats[k].merge(&chain.stats());
        for (l, sums) in large[k].iter_mut().enumerate() {
            sums.merge(&chain.large(l));
        }
        if calibration[k].is_none() {
            calibration[k] = chain.calibration();
        }
        rays += chain.rays();
    }
    let (w, h) = per_group.first().and_then(|g| g.first()).map_or((0, 0), |b| (b.width, b.height));
    let mut image = Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO);
    let mut invalid = 0;
    for (k, d) in stats.iter_mut().enumerate() {
        let boot = &boots[k];
        let n_boot = boot.values.len() as u64;
        // A target's mean over its bootstrap and large-step samples.
        let refine = |mut prior: Moments, large: &Moments| {
            prior.merge(large);
            prior.mean_and_rel_se()
        };
        let layer0 = Moments { sum: boot.mean * n_boot as f64, sum2: boot.sum2, n: n_boot };
        (d.b, d.b_rel_se) = refine(layer0, &large[k][0]);
        d.bootstrap_samples = n_boot;
        d.large_step_samples = large[k][0].n;
        d.invalid += boot.invalid;
        invalid += d.invalid + per_group[k].iter().map(SharedSplats::invalid).sum::<u64>();
        if let Some((_, ratios)) = calibration[k] {
            d.replica_b_ratios = ratios.iter().map(|&r| r as f32).collect();
        }
        if d.mutations == 0 {
            continue;
        }
        // Layer l estimates its share of the depth's image per mutation: N_pixels · b_l/ρ_l / M_k
        // (MMLT's N_pixels · b_k / M_k for one layer).
        let mut layer_b = Vec::with_capacity(per_group[k].len());
        for (l, buffer) in per_group[k].iter().enumerate() {
            let (b, ratio) = match (calibration[k], l) {
                (_, 0) => (d.b, 1.0),
                (Some((moments, ratios)), l) => (refine(moments[l], &large[k][l]).0, ratios[l]),
                (None, _) => continue,
            };
            layer_b.push(b);
            let layer = buffer.image(b / ratio * pixels as f64 / d.mutations as f64);
            for (p, q) in image.pixels.iter_mut().zip(&layer.pixels) {
                *p += *q;
            }
        }
        if layer_b.len() > 1 {
            d.replica_b = layer_b;
        }
    }
    let mutations: u64 = stats.iter().map(|d| d.mutations).sum();
    let stats_total = RenderStats {
        spp_completed: (mutations / pixels.max(1)) as u32,
        pixel_samples: mutations,
        rays,
        invalid_samples: invalid,
        seconds: 0.0,
        cancelled: false,
    };
    RenderOutput { image, stats: stats_total, layers: Vec::new(), chains: stats }
}

impl ChainIntegrator for MmltIntegrator {
    fn name(&self) -> &'static str {
        "mmlt"
    }

    /// Renders and returns the per-depth statistics alongside the image.
    fn render_with_report(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<(RenderOutput, MmltReport), String> {
        let depths = self.max_depth as usize + 1;
        let chains = ChainSettings::new(self.bootstrap, self.chains, self.sigma, self.large_step_probability);
        let target = |depth| DepthTarget { scene, depth };
        chains.render(scene, settings, control, depths, target, |cx| {
            let k = cx.k;
            chains.start_single(cx, target(k))
        })
    }
}
