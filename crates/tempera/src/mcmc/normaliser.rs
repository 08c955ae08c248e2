//! More samples of each group's own normaliser ([`super::Target::normaliser`]) as the render
//! goes on, so that the normalisations `b_k` converge with the render instead of stopping at
//! the bootstrap's fixed count. A group's `b_k` scales its whole share of the image, so a
//! depth whose normaliser is heavy-tailed (glossy paths that every strategy samples poorly)
//! leaves each seed's image brighter or darker by its error whatever the chains do, and a few
//! thousand samples beside the bootstrap leave errors of several percent there.
//!
//! The normalisers get a fixed share of the chains' rays: after `M` main-chain mutations,
//! `share · M · r̄` rays, with `r̄` the bootstrap's rays per sample averaged over the groups in
//! proportion to their allotment (a stand-in for a mutation's rays, known before the first
//! mutation), split evenly over the groups with a normaliser, chunk by chunk to the group
//! whose chunks have traced the fewest rays (by its measured rays per sample). Even, not by
//! each group's measured variance: the depths that need the samples are those whose rare
//! bright paths the bootstrap's normaliser samples have not seen yet, and their measured
//! variance is then small (splitting by the variance each combination would have, measured on
//! those samples, left seed 3's image on the default scene at `--mpp 512` 1.9 % bright, as
//! without further samples; split evenly 1.45 %). Chunks are seeded by their index and chunk
//! `i` of a group joins fold `i mod FOLDS` of its cross-fitted normalisation; the schedule
//! depends on the seed and the number of mutations only, so the result is the same at any
//! thread count and at any rank count (every rank draws every chunk).

use super::bootstrap::{Bootstrap, FOLDS};
use super::{Moments, NormaliserMoments, Target};
use crate::math::rng::hash;
use rayon::prelude::*;

/// Normaliser samples per chunk.
const CHUNK: usize = 64;

/// The normalisers' share of the chains' rays.
pub const DEFAULT_SHARE: f64 = 0.1;

/// The schedule of the groups' further normaliser samples.
pub struct Topup {
    /// Normaliser rays per main-chain mutation.
    rays_per_mutation: f64,
    /// Per group, its normaliser's rays per sample (`None`: no normaliser, or one whose
    /// samples all had one value).
    groups: Vec<Option<f64>>,
    /// Chunks drawn so far, per group.
    chunks: Vec<u64>,
    /// The rays they traced.
    pub rays: u64,
}

impl Topup {
    /// The schedule for groups `boots` allotted mutations in proportion to `allotment` (a
    /// partition of one), the normalisers taking `share` of the chains' rays.
    pub fn new(boots: &[Bootstrap], allotment: &[f64], share: f64) -> Self {
        let rays_per_sample = |b: &Bootstrap| b.rays as f64 / b.values.len().max(1) as f64;
        let r_bar: f64 = boots.iter().zip(allotment).map(|(b, &a)| a * rays_per_sample(b)).sum();
        let groups = boots
            .iter()
            .map(|b| {
                let mut all = Moments::default();
                b.normaliser.as_ref()?.iter().for_each(|f| all.merge(&f.moments));
                let (mean, rel) = all.mean_and_rel_se();
                let cost = b.normaliser_rays as f64 / all.n.max(1) as f64;
                (mean * rel > 0.0 && cost > 0.0).then_some(cost)
            })
            .collect();
        Self { rays_per_mutation: share * r_bar, groups, chunks: vec![0; boots.len()], rays: 0 }
    }

    /// Draws the chunks due after `mutations` main-chain mutations in all and adds them to
    /// the groups' normalisers, counting their rays. Stops between chunks when `stop` says so.
    pub fn run<T: Target + Sync>(
        &mut self,
        boots: &mut [Bootstrap],
        targets: &(impl Fn(usize) -> T + Sync),
        seed: u64,
        mutations: u64,
        stop: &(dyn Fn() -> bool + Sync),
    ) {
        let budget = self.rays_per_mutation * mutations as f64;
        let mut due = self.chunks.clone();
        // The rays the chunks drawn so far are expected to trace (by the groups' costs), which
        // the budget bounds.
        let mut planned: f64 =
            self.groups.iter().zip(&due).filter_map(|(cost, &n)| cost.map(|c| n as f64 * c * CHUNK as f64)).sum();
        // Chunk by chunk to the group whose chunks have traced the fewest rays.
        loop {
            let next = self
                .groups
                .iter()
                .enumerate()
                .filter_map(|(k, cost)| cost.map(|c| (k, due[k] as f64 * c, c * CHUNK as f64)))
                .fold(None, |best: Option<(usize, f64, f64)>, g| match best {
                    Some(b) if b.1 <= g.1 => Some(b),
                    _ => Some(g),
                });
            let Some((k, _, rays)) = next else { break };
            if planned + rays > budget {
                break;
            }
            planned += rays;
            due[k] += 1;
        }
        // The chunks due, group by group in index order, drawn in parallel (a chunk at a deep
        // depth costs many times one at a shallow one, so each is a job of its own) and merged
        // in that order, so the sums are the same at any thread count.
        let jobs: Vec<(usize, u64)> = due
            .iter()
            .enumerate()
            .filter(|(k, _)| boots[*k].normaliser.is_some())
            .flat_map(|(k, &due)| (self.chunks[k]..due).map(move |c| (k, c)))
            .collect();
        let drawn: Vec<Option<Option<(NormaliserMoments, u64)>>> = {
            let boots = &*boots;
            jobs.par_iter()
                .with_max_len(1)
                .map(|&(k, c)| {
                    (!stop()).then(|| targets(k).normaliser(hash(&[seed, 0x70b0, k as u64, c]), CHUNK, boots[k].clamp))
                })
                .collect()
        };
        let mut rays = 0;
        // Merged up to the first chunk not drawn (the render was stopped), so that each
        // group's chunks stay consecutive.
        for (&(k, c), drawn) in jobs.iter().zip(drawn) {
            let Some(drawn) = drawn else { break };
            if let Some((m, r)) = drawn {
                let folds = boots[k].normaliser.as_mut().expect("only groups with a normaliser have jobs");
                folds[c as usize % FOLDS].merge(&m);
                boots[k].normaliser_rays += r;
                rays += r;
            }
            self.chunks[k] = c + 1;
        }
        self.rays += rays;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bidir::{Heuristic, Tempering};
    use crate::mcmc::{ChainSettings, TemperedTarget};

    /// On a Cornell box's depths 0–3, after 400,000 mutations the further samples trace their
    /// share of the rays (within 10 %), each group within 10 % and a chunk of the groups'
    /// mean, and every depth's normalisation still has the chains' expectation: it agrees with
    /// the mean of MMLT's own target over 200,000 independent samples.
    #[test]
    fn further_normaliser_samples_take_their_share_evenly_and_keep_the_expectation() {
        let mut scene = crate::scenes::cornell_box(16, 16).build().unwrap();
        scene.set_resolution(16, 16);
        let settings = ChainSettings::new(2000, 4, 0.01, 0.3);
        let temper = Tempering { a: 0.0, heuristic: Heuristic::Power, roughen_mis: false };
        let targets = |k| TemperedTarget::new(&scene, k, temper, 0.0);
        let mut boots: Vec<Bootstrap> = (0..4).map(|k| Bootstrap::run(&targets(k), &settings, 5, k).0).collect();
        let samples = |b: &Bootstrap| b.normaliser.as_ref().unwrap().iter().map(|f| f.moments.n).sum::<u64>();
        let before: Vec<u64> = boots.iter().map(|b| b.normaliser_rays).collect();
        // A chunk's rays at each depth, by the bootstrap's normaliser samples.
        let chunk: Vec<f64> =
            boots.iter().map(|b| b.normaliser_rays as f64 / samples(b) as f64 * CHUNK as f64).collect();
        let allotment = [0.25; 4];
        let mut topup = Topup::new(&boots, &allotment, 0.1);
        let mutations = 400_000;
        topup.run(&mut boots, &targets, 5, mutations, &|| false);
        let r_bar: f64 = boots.iter().map(|b| 0.25 * b.rays as f64 / b.values.len() as f64).sum();
        let budget = 0.1 * r_bar * mutations as f64;
        let spent: Vec<f64> = boots.iter().zip(&before).map(|(b, &r)| (b.normaliser_rays - r) as f64).collect();
        let total: f64 = spent.iter().sum();
        assert_eq!(total as u64, topup.rays);
        assert!((total - budget).abs() < 0.1 * budget, "{total} rays of {budget}");
        let mean = total / 4.0;
        for (k, s) in spent.iter().enumerate() {
            assert!((s - mean).abs() < 0.1 * mean + chunk[k], "depth {k}: {s} rays of {spent:?}");
        }
        for (k, boot) in boots.iter().enumerate().skip(1) {
            let (b, rel) = boot.normalisation(&Moments::default());
            let (m, rel_m) = crate::testing::mmlt_target_moments(&scene, k, 9, 200_000).mean_and_rel_se();
            let sigma = ((b * rel).powi(2) + (m * rel_m).powi(2)).sqrt();
            assert!((b - m).abs() < 4.0 * sigma, "depth {k}: {b} ± {rel} vs {m} ± {rel_m}");
        }
    }
}
