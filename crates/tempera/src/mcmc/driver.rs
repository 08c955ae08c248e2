//! The chain driver shared by every Markov-chain integrator (MMLT, PSSMLT, tempered MMLT):
//! groups of walkers (MMLT and tempering: one group per path depth; PSSMLT: one group), each
//! group bootstrapped ([`super::bootstrap`]) for its normalisation `b` and its start states.
//! Mutations are allotted to groups in proportion to `b` (Hachisuka et al. 2014 §5), or to `b`
//! times the spread of the group's bootstrap values ([`Bootstrap::spread`]); a fixed
//! budget runs in one round, a time budget in rounds of about one mutation per pixel until the
//! deadline. Walkers are the unit of parallel work and splat into fixed-point buffers shared
//! by the threads, so the image is bit-identical at any thread count.
//!
//! A walker splats into one or more layers per group. Layer `l`'s splats are normalised by
//! `b_l / ρ_l`, where `b_l` is the mean of target `l` over the group's bootstrap and the large
//! steps of the walkers sampling it, and `ρ_l` the ratio the walker weighted them with; a single
//! layer is MMLT's `b_k` with `ρ_0 = 1`. Large steps are independent uniform samples, so the
//! refined `b` does not hinge on the bootstrap. A target with a lower-variance estimator of its
//! own `b` (MMLT's depths: [`super::all_strategies`]) has it combined with those samples. Each
//! group's image is scaled by
//! `N_pixels · b_l/ρ_l / M` (`M` the group's mutations).

use super::bootstrap::{Bootstrap, sampler_for};
use super::{Chain, DepthStats, Moments, Target};
use crate::cluster::{Cluster, Reader, Wire};
use crate::film::SharedSplats;
use crate::integrator::render_loop::RenderLoop;
use crate::integrator::{Budget, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::math::distribution::Distribution1D;
use crate::math::rng::{Pcg32, hash};
use crate::scene::Scene;
use crate::texture::Image;
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
    /// Also develop one image per group (MMLT and tempering: per path depth) into
    /// [`RenderOutput::layers`]; they sum to the image.
    pub group_images: bool,
}

/// How a group's splat layers are normalised, decided when the group is prepared.
pub trait Layers: Send + Sync {
    /// The layers each walker of the group splats into.
    fn count(&self) -> usize {
        1
    }
    /// For a layer `l ≥ 1`: the moments of its target over the group's bootstrap and the ratio
    /// `ρ_l` its splats were weighted with. (Layer 0 is the group's own target, `ρ_0 = 1`.)
    fn layer(&self, _l: usize) -> Option<(Moments, f64)> {
        None
    }
    /// The ratios `ρ_l` to report in the statistics (empty: a single layer).
    fn ratios(&self) -> &[f64] {
        &[]
    }
}

/// A group with a single layer: MMLT's and PSSMLT's.
#[derive(Clone, Copy, Debug, Default)]
pub struct OneLayer;

impl Layers for OneLayer {}

/// A unit of parallel work of the chain driver: one chain (MMLT, PSSMLT) or one ensemble of
/// replicas (tempered MMLT).
pub trait Walker: Send {
    /// What the walkers of a group share once it is prepared.
    type Group: Layers;
    /// Makes up to `mutations` mutations of the main chain, splatting into `splats` (one
    /// buffer per layer, shared with the group's other walkers); returns how many were made.
    fn run(&mut self, group: &Self::Group, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64;
    /// The main chain's statistics.
    fn stats(&self) -> DepthStats;
    /// The moments of `layer`'s target over the walker's large-step proposals.
    fn large(&self, layer: usize) -> Moments;
    fn rays(&self) -> u64;
    /// Prepares the walkers of one group together, before the first round; returns what they
    /// share and the rays traced.
    fn prepare_group(
        walkers: &mut [Self],
        group: &GroupContext,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (Self::Group, u64)
    where
        Self: Sized;
}

/// A group of walkers: its index, the render's seed, the driver's settings and, under a fixed
/// budget, the group's share of the mutations.
#[derive(Clone, Copy)]
pub struct GroupContext<'a> {
    pub k: usize,
    pub seed: u64,
    pub settings: &'a ChainSettings,
    pub budget: Option<u64>,
}

impl GroupContext<'_> {
    /// Starts a chain under `target` from the group's bootstrap sample that `u` picks from
    /// `starts` (a distribution over the samples), accepting with `rng`: every chain of every
    /// Markov-chain integrator starts so.
    pub fn start_chain<T: Target>(&self, target: &T, starts: &Distribution1D, u: f32, rng: Pcg32) -> Chain<T::State> {
        let (index, _, _) = starts.sample_discrete(u);
        Chain::start(target, sampler_for(self.seed, self.k, index, self.settings), rng, self.k)
    }
}

/// Where a walker starts: walker `c` of its group, with the group's bootstrap values and the
/// distribution of start states (in proportion to their value).
pub struct StartContext<'a> {
    pub group: GroupContext<'a>,
    pub c: usize,
    pub rng: Pcg32,
    pub starts: &'a Distribution1D,
    pub bootstrap: &'a [f32],
}

impl StartContext<'_> {
    /// Starts a chain under `target` from a bootstrap state drawn with `rng` in proportion to
    /// its value.
    pub fn start_chain<T: Target>(&self, target: &T, mut rng: Pcg32) -> Chain<T::State> {
        let u = rng.next_f32();
        self.group.start_chain(target, self.starts, u, rng)
    }
}

/// One chain with its target.
pub struct Single<T: Target> {
    pub chain: Chain<T::State>,
    pub target: T,
}

impl<T: Target> Single<T> {
    /// A chain under `target`, started as [`StartContext::start_chain`] does.
    pub fn start(cx: StartContext, target: T) -> Self {
        let chain = cx.start_chain(&target, cx.rng.clone());
        Single { chain, target }
    }
}

impl<T: Target + Send> Walker for Single<T>
where
    T::State: Send,
{
    type Group = OneLayer;

    fn run(&mut self, _: &OneLayer, mutations: u64, splats: &[SharedSplats], stop: &dyn Fn() -> bool) -> u64 {
        self.chain.run(&self.target, mutations, Some(&splats[0]), stop)
    }

    fn stats(&self) -> DepthStats {
        self.chain.stats.clone()
    }

    fn large(&self, _layer: usize) -> Moments {
        self.chain.large
    }

    fn rays(&self) -> u64 {
        self.chain.rays()
    }

    fn prepare_group(_: &mut [Self], _: &GroupContext, _: &(dyn Fn() -> bool + Sync)) -> (OneLayer, u64) {
        (OneLayer, 0)
    }
}

/// One walker's place in the render.
#[derive(Clone, Copy, Debug)]
struct Slot {
    /// Its group.
    group: usize,
    /// Its index in the group.
    index: usize,
    /// The group's walker count.
    walkers: u64,
    /// The group's mutations under a fixed budget.
    budget: Option<u64>,
}

impl Slot {
    /// This walker's share of its group's fixed budget.
    fn quota(&self) -> u64 {
        let m = self.budget.unwrap_or(0);
        m / self.walkers + u64::from((self.index as u64) < m % self.walkers)
    }
}

/// A prepared group: what its walkers share, its splat buffers (one per layer), and the time
/// its preparation took.
struct Group<L> {
    shared: L,
    splats: Vec<SharedSplats>,
    seconds: f64,
}

impl ChainSettings {
    pub fn new(bootstrap: usize, chains: usize, sigma: f32, large_step_probability: f32) -> Self {
        Self { bootstrap, chains, sigma, large_step_probability, spread_allocation: false, group_images: false }
    }

    /// These settings with one image per group developed beside the image when `on` is set.
    pub fn with_group_images(self, on: bool) -> Self {
        Self { group_images: on, ..self }
    }

    /// These settings with mutations allotted by `b` times spread when `spread` is set.
    pub fn with_spread_allocation(self, spread: bool) -> Self {
        Self { spread_allocation: spread, ..self }
    }

    /// Renders with `groups` independent sets of walkers (MMLT: one per path depth; PSSMLT:
    /// one), group `k` bootstrapped under `targets(k)` and its walkers started by
    /// `start_walker`. The statistics carry one row per group. An error when no light path
    /// reaches the camera.
    pub fn render<T, W>(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        groups: usize,
        targets: impl Fn(usize) -> T + Sync,
        start_walker: impl Fn(StartContext) -> W + Sync,
    ) -> Result<RenderOutput, String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let render = RenderLoop::new(settings, control);
        render.install(|| self.render_in_pool(&render, scene, settings, groups, &targets, &start_walker))
    }

    /// Bootstraps every group; an error when all of them saw no light.
    fn bootstrap<T: Target + Sync>(
        &self,
        seed: u64,
        groups: usize,
        targets: &(impl Fn(usize) -> T + Sync),
    ) -> Result<(Vec<Bootstrap>, u64), String> {
        let mut rays = 0;
        let boots: Vec<Bootstrap> = (0..groups)
            .map(|k| {
                let (b, r) = Bootstrap::run(&targets(k), self, seed, k);
                rays += r;
                b
            })
            .collect();
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
        if self.spread_allocation { b * boot.spread() } else { b }
    }

    /// The walkers of every group with light: under a fixed budget each group's share of the
    /// mutations in proportion to its weight, and no more walkers than mutations.
    /// A group whose bootstrap holds no light has no state to start from: it gets no walkers.
    fn plan(&self, boots: &[Bootstrap], budget: Option<u64>) -> Vec<Slot> {
        let total: f64 = boots.iter().map(|b| self.weight(b)).sum();
        let mut plan = Vec::new();
        for (k, b) in boots.iter().enumerate() {
            if b.mean <= 0.0 || b.b() <= 0.0 {
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

    fn render_in_pool<T, W>(
        &self,
        render: &RenderLoop,
        scene: &Scene,
        settings: &RenderSettings,
        groups: usize,
        targets: &(impl Fn(usize) -> T + Sync),
        start_walker: &(impl Fn(StartContext) -> W + Sync),
    ) -> Result<RenderOutput, String>
    where
        T: Target + Sync,
        W: Walker,
    {
        let seed = settings.seed;
        let (w, h) = (scene.film.width, scene.film.height);
        let pixels = u64::from(w) * u64::from(h);
        let (boots, mut total_rays) = self.bootstrap(seed, groups, targets)?;
        let total: f64 = boots.iter().map(|b| self.weight(b)).sum();
        let share = |k: usize| self.weight(&boots[k]) / total;
        let budget = match settings.budget {
            Budget::Samples(mpp) => Some(u64::from(mpp) * pixels),
            Budget::Time(_) => None,
        };
        let plan = self.plan(&boots, budget);
        // Walkers start from bootstrap states drawn in proportion to their value.
        let starts: Vec<Distribution1D> = boots.iter().map(Bootstrap::starts).collect();
        let mut walkers: Vec<W> = plan
            .par_iter()
            .map(|slot| {
                let (k, c) = (slot.group, slot.index);
                let rng = Pcg32::new(hash(&[seed, 0xc4a1, k as u64, c as u64]), 7);
                let bootstrap = &boots[k].values;
                let group = GroupContext { k, seed, settings: self, budget: slot.budget };
                start_walker(StartContext { group, c, rng, starts: &starts[k], bootstrap })
            })
            .collect();
        let stop = || render.should_stop();
        let (prepared, rays) = self.prepare(&plan, &mut walkers, seed, groups, w, h, &stop);
        total_rays += rays;
        // Every rank prepares every group alike; each runs the walkers dealt to it.
        let cluster = render.control.cluster;
        let run_round = |walkers: &mut [W], quota: &(dyn Fn(&Slot) -> u64 + Sync)| {
            walkers.par_iter_mut().zip(&plan).enumerate().filter(|(i, _)| cluster.owns(*i)).for_each(
                |(_, (walker, slot))| {
                    let group = prepared[slot.group].as_ref().expect("every planned group is prepared");
                    let done = walker.run(&group.shared, quota(slot), &group.splats, &stop);
                    render.progress(done);
                },
            );
        };
        // The image so far (at rank 0, from every rank's walkers), its statistics taken
        // `seconds` after the start.
        let developed = |walkers: &[W], seconds: f64| {
            let reports = gather_reports(cluster, walkers, &plan, &prepared);
            let summed = cluster.is_distributed().then(|| sum_splats(cluster, &prepared));
            let out = develop(&boots, &reports, &plan, &prepared, summed.as_deref(), (w, h), self.group_images);
            RenderOutput { stats: RenderStats { rays: out.stats.rays + total_rays, seconds, ..out.stats }, ..out }
        };
        match budget {
            // A fixed budget: one round, each walker its share of its group's mutations.
            Some(_) => run_round(&mut walkers, &Slot::quota),
            // A time budget: rounds of about one mutation per pixel, shared in proportion to
            // b_k, until the deadline (rank 0's). Snapshots (if asked for) are developed
            // between rounds.
            None => {
                let mut snapshots = render.snapshots(settings.budget);
                while !cluster.broadcast(stop()) {
                    run_round(&mut walkers, &|slot| {
                        ((share(slot.group) * pixels as f64 / slot.walkers as f64).round() as u64).max(1)
                    });
                    if cluster.broadcast(snapshots.is_due(render)) {
                        let out = developed(&walkers, 0.0);
                        snapshots.take(render, |seconds| RenderOutput {
                            stats: RenderStats { seconds, ..out.stats.clone() },
                            ..out
                        });
                    }
                }
            }
        }
        let mut out = developed(&walkers, 0.0);
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
        groups: usize,
        w: u32,
        h: u32,
        stop: &(dyn Fn() -> bool + Sync),
    ) -> (Vec<Option<Group<W::Group>>>, u64) {
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
            .map(|(k, budget, group)| {
                let start = std::time::Instant::now();
                let cx = GroupContext { k, seed, settings: self, budget };
                let (shared, rays) = W::prepare_group(group, &cx, stop);
                (k, shared, rays, start.elapsed().as_secs_f64())
            })
            .collect();
        let mut prepared: Vec<Option<Group<W::Group>>> = (0..groups).map(|_| None).collect();
        let mut rays = 0;
        for (k, shared, r, seconds) in results {
            rays += r;
            let splats = (0..shared.count()).map(|_| SharedSplats::new(w, h)).collect();
            prepared[k] = Some(Group { shared, splats, seconds });
        }
        (prepared, rays)
    }
}

/// What developing the image needs of one walker.
#[derive(Clone, Debug, Default)]
struct Report {
    stats: DepthStats,
    /// Per layer, the moments of its target over the walker's large steps.
    large: Vec<Moments>,
    rays: u64,
}

impl Report {
    fn of<W: Walker>(walker: &W, layers: usize) -> Self {
        Report { stats: walker.stats(), large: (0..layers).map(|l| walker.large(l)).collect(), rays: walker.rays() }
    }
}

/// Every walker's report, at rank 0 (each from the rank that runs it); the other ranks get
/// their own walkers' reports and defaults elsewhere.
fn gather_reports<W: Walker>(
    cluster: &dyn Cluster,
    walkers: &[W],
    plan: &[Slot],
    groups: &[Option<Group<W::Group>>],
) -> Vec<Report> {
    let layers = |k: usize| groups[k].as_ref().map_or(1, |g| g.splats.len());
    let mut reports: Vec<Report> = walkers
        .iter()
        .zip(plan)
        .enumerate()
        .map(
            |(i, (walker, slot))| {
                if cluster.owns(i) { Report::of(walker, layers(slot.group)) } else { Report::default() }
            },
        )
        .collect();
    if !cluster.is_distributed() {
        return reports;
    }
    let mut w = Wire::default();
    for (i, r) in reports.iter().enumerate().filter(|(i, _)| cluster.owns(*i)) {
        w.u64(i as u64).u64(r.rays).u64(r.large.len() as u64);
        for m in &r.large {
            w.f64(m.sum).f64(m.sum2).u64(m.n);
        }
        r.stats.encode(&mut w);
    }
    for bytes in cluster.gather(w.bytes).iter().skip(1) {
        let mut r = Reader::new(bytes);
        while !r.is_empty() {
            let (i, rays) = (r.u64() as usize, r.u64());
            let large = (0..r.u64()).map(|_| Moments { sum: r.f64(), sum2: r.f64(), n: r.u64() }).collect();
            reports[i] = Report { stats: DepthStats::decode(&mut r), large, rays };
        }
    }
    reports
}

/// Every prepared group's splat buffers summed over the ranks (integer sums, exact).
fn sum_splats<L>(cluster: &dyn Cluster, groups: &[Option<Group<L>>]) -> Vec<Vec<SharedSplats>> {
    groups
        .iter()
        .map(|g| {
            let Some(g) = g else { return Vec::new() };
            g.splats
                .iter()
                .map(|b| {
                    let mut values = b.values();
                    cluster.sum(&mut values);
                    SharedSplats::from_values(b.width, b.height, &values)
                })
                .collect()
        })
        .collect()
}

/// The image and per-group statistics of the walkers' `reports` so far: statistics merged in
/// walker order, each layer's normalisation `b_l` refined with the large-step proposals, each
/// layer's splats (`summed` over the ranks, else the groups' own) scaled to estimate its share
/// of the image per mutation. Rays count the walkers' rays only. With `group_images`, each
/// group's share of the image (its layers summed) is also returned, in group order.
#[allow(clippy::too_many_arguments)]
fn develop<L: Layers>(
    boots: &[Bootstrap],
    reports: &[Report],
    plan: &[Slot],
    groups: &[Option<Group<L>>],
    summed: Option<&[Vec<SharedSplats>]>,
    (w, h): (u32, u32),
    group_images: bool,
) -> RenderOutput {
    let pixels = u64::from(w) * u64::from(h);
    let layers = |k: usize| groups[k].as_ref().map_or(1, |g| g.splats.len());
    let mut stats: Vec<DepthStats> =
        (0..boots.len()).map(|k| DepthStats { depth: k, ..DepthStats::default() }).collect();
    let mut large: Vec<Vec<Moments>> = (0..boots.len()).map(|k| vec![Moments::default(); layers(k)]).collect();
    let mut rays = 0;
    for (report, slot) in reports.iter().zip(plan) {
        let k = slot.group;
        stats[k].merge(&report.stats);
        for (sums, m) in large[k].iter_mut().zip(&report.large) {
            sums.merge(m);
        }
        rays += report.rays;
    }
    let mut image = Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO);
    let mut per_group: Vec<Image> = Vec::new();
    let mut invalid = 0;
    for (k, d) in stats.iter_mut().enumerate() {
        if group_images {
            per_group.push(Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO));
        }
        let boot = &boots[k];
        // A target's mean over its bootstrap and large-step samples.
        let refine = |mut prior: Moments, large: &Moments| {
            prior.merge(large);
            prior.mean_and_rel_se()
        };
        (d.b, d.b_rel_se) = boot.normalisation(&large[k][0]);
        d.bootstrap_samples = boot.values.len() as u64;
        d.spread = boot.spread();
        d.large_step_samples = large[k][0].n;
        d.invalid += boot.invalid;
        let Some(group) = &groups[k] else {
            invalid += d.invalid;
            continue;
        };
        let buffers = summed.map_or(group.splats.as_slice(), |s| s[k].as_slice());
        invalid += d.invalid + buffers.iter().map(SharedSplats::invalid).sum::<u64>();
        d.replica_b_ratios = group.shared.ratios().iter().map(|&r| r as f32).collect();
        d.prepare_seconds = group.seconds;
        if d.mutations == 0 {
            continue;
        }
        // Layer l estimates its share of the group's image per mutation: N_pixels · b_l/ρ_l / M_k
        // (MMLT's N_pixels · b_k / M_k for one layer).
        let mut layer_b = Vec::with_capacity(group.splats.len());
        for (l, buffer) in buffers.iter().enumerate() {
            let (b, ratio) = match (l, group.shared.layer(l)) {
                (0, _) => (d.b, 1.0),
                (_, Some((moments, ratio))) => (refine(moments, &large[k][l]).0, ratio),
                (_, None) => continue,
            };
            layer_b.push(b);
            let layer = buffer.image(b / ratio * pixels as f64 / d.mutations as f64);
            for (p, q) in image.pixels.iter_mut().zip(&layer.pixels) {
                *p += *q;
            }
            if let Some(own) = per_group.last_mut() {
                for (p, q) in own.pixels.iter_mut().zip(&layer.pixels) {
                    *p += *q;
                }
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
    RenderOutput { image, stats: stats_total, layers: per_group, chains: stats }
}
