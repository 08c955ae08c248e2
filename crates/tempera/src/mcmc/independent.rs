//! Independent samples of one path depth, where chains would not mix: bidirectional path
//! tracing restricted to depth `k` ([`super::all_strategies::each_strategy`]), each sample
//! splatting every strategy's MIS-weighted contribution.
//!
//! A depth whose light lies on a sliver of primary sample space (paths of many bounces in an
//! open scene: almost every one escapes) gives its bootstrap only a handful of non-zero
//! values. The depth's chains all start from those few states, and a small step from them
//! rarely finds light again, so each chain stays where it started and the depth's whole share
//! of the image lands on a few pixels: fireflies worth the depth's `b_k` times the film's size,
//! unbiased over seeds but not within one. Independent samples spread it out as BDPT does.
//! They splat `L / b` into the group's buffer, which the driver scales by
//! `N_pixels · b / N` as it scales a chain's splats by `N_pixels · b / M`: so the image of the
//! depth is `N_pixels / N · Σ L`, whatever `b` is.

use super::DepthStats;
use super::all_strategies::each_strategy;
use crate::bidir::Paths;
use crate::film::SharedSplats;
use crate::math::rng::hash;
use crate::sampler::IndependentSampler;
use crate::scene::Scene;

/// One walker of an independently sampled depth.
pub struct Independent {
    k: usize,
    seed: u64,
    index: usize,
    /// `1 / b`: see the module documentation.
    inv_b: f64,
    paths: Paths,
    rays: u64,
    pub stats: DepthStats,
}

impl Independent {
    /// Walker `index` of depth `k ≥ 1`, whose normalisation the driver develops with is `b`.
    pub fn new(k: usize, seed: u64, index: usize, b: f64) -> Self {
        let stats = DepthStats { depth: k, independent: true, ..DepthStats::default() };
        Self { k, seed, index, inv_b: if b > 0.0 { 1.0 / b } else { 0.0 }, paths: Paths::default(), rays: 0, stats }
    }

    /// Draws up to `samples` more samples, splatting into `splats`; returns how many were drawn.
    /// Sample `i` of this walker always has the same seed, so the image does not depend on how
    /// the samples are dealt to rounds or threads.
    pub fn run(&mut self, scene: &Scene, samples: u64, splats: &SharedSplats, stop: &dyn Fn() -> bool) -> u64 {
        let start = std::time::Instant::now();
        let scale = self.inv_b as f32;
        let mut done = 0;
        while done < samples {
            if done % 256 == 0 && stop() {
                break;
            }
            let i = self.stats.mutations;
            let mut sampler =
                IndependentSampler::new(hash(&[self.seed, 0x1d5a, self.k as u64, self.index as u64, i]), self.k as u64);
            self.rays += each_strategy(scene, self.k, &mut sampler, &mut self.paths, |p, l| splats.add(p, l * scale));
            self.stats.mutations += 1;
            done += 1;
        }
        self.stats.seconds += start.elapsed().as_secs_f64();
        done
    }

    pub fn rays(&self) -> u64 {
        self.rays
    }
}
