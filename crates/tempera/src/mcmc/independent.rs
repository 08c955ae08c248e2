//! Independent samples of the path depths where chains would not mix: bidirectional path
//! tracing restricted to those depths ([`super::all_strategies::each_strategy_of`]), each
//! sample splatting every strategy of every such depth.
//!
//! A depth whose light lies on a sliver of primary sample space (paths of many bounces in an
//! open scene: almost every one escapes) gives its bootstrap only a handful of non-zero
//! values. The depth's chains all start from those few states, and a small step from them
//! rarely finds light again, so each chain stays where it started and the depth's whole share
//! of the image lands on a few pixels: fireflies worth the depth's `b_k` times the film's size,
//! unbiased over seeds but not within one. Independent samples spread it out as BDPT does, and
//! one sample serves all such depths at once (one camera and one light subpath, long enough
//! for the deepest), so each depth gets the samples of all of them. A sample splats its
//! contributions `L` as they are; the driver scales each such depth's buffer by
//! `N_pixels / N`, `N` the samples drawn by all the independent walkers.

use super::DepthStats;
use super::all_strategies::each_strategy_of;
use crate::bidir::Paths;
use crate::film::SharedSplats;
use crate::math::rng::hash;
use crate::sampler::IndependentSampler;
use crate::scene::Scene;

/// One walker of the independently sampled depths: each of its samples covers all of them.
pub struct Independent {
    k: usize,
    seed: u64,
    index: usize,
    paths: Paths,
    rays: u64,
    /// The statistics of the depth whose share of the budget the walker draws; its samples
    /// are counted there.
    pub stats: DepthStats,
}

impl Independent {
    /// Walker `index` of depth `k ≥ 1`, one of the independently sampled depths.
    pub fn new(k: usize, seed: u64, index: usize) -> Self {
        let stats = DepthStats { depth: k, independent: true, ..DepthStats::default() };
        Self { k, seed, index, paths: Paths::default(), rays: 0, stats }
    }

    /// Draws up to `samples` more samples of all of `depths` (every independently sampled
    /// depth), splatting depth `depths[i]`'s contributions into `splats[i]`; returns how many
    /// were drawn. Sample `i` of this walker always has the same seed, so the image does not
    /// depend on how the samples are dealt to rounds or threads.
    pub fn run(
        &mut self,
        scene: &Scene,
        depths: &[usize],
        samples: u64,
        splats: &[&SharedSplats],
        stop: &dyn Fn() -> bool,
    ) -> u64 {
        let start = std::time::Instant::now();
        let mut done = 0;
        while done < samples {
            if done % 256 == 0 && stop() {
                break;
            }
            let i = self.stats.mutations;
            let seed = hash(&[self.seed, 0x1d5a, self.k as u64, self.index as u64, i]);
            let mut sampler = IndependentSampler::new(seed, self.k as u64);
            self.rays += each_strategy_of(scene, depths, &mut sampler, &mut self.paths, |d, p, l| splats[d].add(p, l));
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
