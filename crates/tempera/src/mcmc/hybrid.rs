//! Markov chains combined with bidirectional path tracing by multiple importance sampling.
//!
//! MMLT's depth-`k` chains visit a point `x = (u, s)` of primary sample space (the strategy
//! `s` included) with density `p_m(x) = f(x)/b_k`, where `f` is the chain's target and
//! `C(x) = n·w_s·C_s` its contribution (`n` strategies: [`super::strategy`]). One sample of
//! bidirectional path tracing values every strategy of every depth from one camera and one
//! light subpath ([`super::all_strategies::each_strategy_of`]): for depth `k` it is `n`
//! points `(u, s)`, each of density 1, whose contributions `C(x)/n = w_s·C_s` are what BDPT
//! adds to the image. With `N_m` mutations at depth `k` and `N_b` such samples, the balance
//! heuristic (Veach 1997 §9.2) weighs a point by
//!
//! ```text
//! w_m(x) = e N_m p_m(x) / (e N_m p_m(x) + n N_b) = f/(f + h),   w_b(x) = h/(f + h),
//! h = n · b_k · N_b / (e N_m),
//! ```
//!
//! the level of the independent samples' density in the chain's target units, where a mutation
//! counts as `e` independent samples at the same density (`chain_efficiency`; small steps keep
//! a chain's successive states close, so `e` is well below 1). A chain state
//! then splats `C/(f + h)` instead of MMLT's `C/f` (developed with `b_k/N_m` as before), and
//! an independent sample's strategy `w_s·C_s·h/(f + h)` (developed as BDPT's samples are: the
//! pixels take their samples in turn, each pixel's camera-ray contributions are averaged over
//! its own samples and light tracing's are scaled by the pixels over the samples drawn). The
//! weights sum to one at every point for any `h`, so the combination is unbiased whatever the counts
//! the weights assume; the render fixes them before its first mutation (the rounds' shares, or
//! the fixed budget's), with `b_k` from the bootstrap, and develops with the counts made.
//!
//! Instead of from the counts and `e`, the level may be set from the share `π` of each depth's
//! light the samples are to carry ([`HybridDepth::with_share`]): a point of value `f` carries
//! light in proportion to `f`, so over the bootstrap's uniform points the samples' share at
//! level `h` is `Σ f·h/(f + h) / Σ f`, which grows from 0 to 1 with `h`. Those weights do not
//! depend on the counts, so the split of the work between samples and chains is then a choice
//! of its own.
//!
//! Kelemen et al. 2002 weigh a chain's own large steps against its states so; here the
//! independent samples are whole BDPT samples, which serve every depth at once: where the
//! chains' density is low (dim parts of the image, which MMLT, allotting mutations by
//! brightness, visits rarely) the independent samples carry the estimate as BDPT does; where a
//! bright, hard-to-find path family holds the chains, they carry it. In parallel tempering's
//! terms the independent samples are a replica at inverse temperature 0 sampled exactly (Syed
//! et al. 2022), kept apart from the swaps.
//!
//! Where the chains' target is clamped at `c` ([`super::ChainSettings::clamp`]), `f` is the
//! clamped value, as the chains' density is.

use super::all_strategies::each_strategy_from;
use super::strategy::raster_position;
use super::target_value;
use crate::bidir::Paths;
use crate::film::SharedSplats;
use crate::math::rng::hash;
use crate::math::{Rgb, Vec2, luminance};
use crate::sampler::{IndependentSampler, Sampler, Stream};
use crate::scene::Scene;
use crate::texture::Image;

/// What a main-chain mutation counts as, in independent samples at the same density, unless
/// the render says otherwise: a hundredth. Small steps keep a chain's states near each other
/// for many mutations, so its samples are worth far fewer independent ones than their
/// number; the README gives the measurements this value was chosen by.
pub const DEFAULT_EFFICIENCY: f64 = 0.01;

/// The strategies of depth `k`: 1 at depth 0 (emitters seen directly), `k + 2` beyond.
fn strategies(k: usize) -> f32 {
    if k == 0 { 1.0 } else { (k + 2) as f32 }
}

/// How one depth's share of an independent sample is weighted.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HybridDepth {
    pub k: usize,
    /// The depth's strategies `n` (1 at depth 0, `k + 2` beyond).
    pub strategies: f32,
    /// The level `h` of the independent samples' density in the chains' target units
    /// (infinite: the depth has no chains, and its independent samples weigh 1).
    pub level: f32,
    /// The value the depth's chains clamp their target at (infinite: none).
    pub clamp: f32,
}

impl HybridDepth {
    /// Depth `k` of a render with `chains` mutations and `samples` independent samples (or
    /// their rates), whose chains' target has mean `b` and is clamped at `clamp`; a mutation
    /// counts as `efficiency` independent points at the same density.
    pub fn new(k: usize, b: f64, (chains, efficiency): (u64, f64), samples: u64, clamp: f32) -> Self {
        let n = f64::from(strategies(k));
        let chains = chains as f64 * efficiency;
        let level = if chains > 0.0 && b > 0.0 { n * b * samples as f64 / chains } else { f64::INFINITY };
        Self { k, strategies: n as f32, level: level as f32, clamp }
    }

    /// Depth `k` with the level at which the independent samples carry `share` of the depth's
    /// light (`share` in `(0, 1)`): the level `h` where `Σ f·h/(f + h) = share·Σ f` over the
    /// depth's bootstrap `values` (its target's values at uniform points, each point's
    /// contribution being its value over `n`), found by bisection on `log h`. A depth without
    /// light gets an infinite level (its samples weigh 1).
    pub fn with_share(k: usize, values: &[f32], share: f64, clamp: f32) -> Self {
        let n = strategies(k);
        let values: Vec<f64> = values.iter().map(|&f| f64::from(f.min(clamp))).collect();
        let light = |h: f64| values.iter().map(|&f| f * h / (f + h)).sum::<f64>();
        let total: f64 = values.iter().sum();
        if !(total > 0.0 && total.is_finite()) {
            return Self { k, strategies: n, level: f32::INFINITY, clamp };
        }
        let target = share.clamp(1e-6, 1.0 - 1e-6) * total;
        let (mut lo, mut hi) = (-60.0f64, 60.0f64);
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if light(mid.exp2()) < target { lo = mid } else { hi = mid }
        }
        Self { k, strategies: n, level: (0.5 * (lo + hi)).exp2() as f32, clamp }
    }

    /// The balance-heuristic weight of an independent sample's strategy with MIS-weighted
    /// contribution luminance `y` (`y·n` is the chains' value of the same point).
    pub fn weight(&self, y: f32) -> f32 {
        if self.level.is_infinite() {
            return 1.0;
        }
        let f = target_value(y * self.strategies).min(self.clamp);
        self.level / (f + self.level)
    }
}

/// Where the independent samples splat: as a film does, the camera rays' contributions
/// summed with the filter's weights and divided by the weights' sum per pixel (so a pixel's
/// estimate is the mean of its own samples), and light tracing's (`t = 1`) summed and scaled
/// by the pixels over the samples drawn. One layer, or one per depth covered when the render
/// develops per-depth images.
pub struct HybridFilm {
    /// The filter weights' sums, then per layer the camera rays' and light tracing's sums.
    pub buffers: Vec<SharedSplats>,
    /// What contributions are multiplied by before they are splatted, so that the
    /// fixed-point sums keep their precision (about one over the image's mean luminance).
    pub scale: f32,
}

impl HybridFilm {
    /// A film of `layers` layers whose buffers splat through `footprint`, for an image of
    /// mean luminance about `mean`.
    pub fn new(layers: usize, footprint: &std::sync::Arc<crate::film::Footprint>, mean: f64) -> Self {
        let scale = if mean > 0.0 && mean.is_finite() { (1.0 / mean) as f32 } else { 1.0 };
        Self { buffers: (0..1 + 2 * layers).map(|_| SharedSplats::filtered(footprint)).collect(), scale }
    }

    pub fn layers(&self) -> usize {
        self.buffers.len() / 2
    }

    fn weights(&self) -> &SharedSplats {
        &self.buffers[0]
    }

    fn camera(&self, layer: usize) -> &SharedSplats {
        &self.buffers[1 + 2 * layer]
    }

    fn light(&self, layer: usize) -> &SharedSplats {
        &self.buffers[2 + 2 * layer]
    }

    /// The same film with other buffers (the sums over the ranks).
    pub fn with_buffers(&self, buffers: Vec<SharedSplats>) -> Self {
        Self { buffers, scale: self.scale }
    }

    /// Layer `layer`'s image from `samples` independent samples, and the splats dropped as
    /// invalid in all of the film's buffers.
    pub fn image(&self, layer: usize, samples: u64) -> Image {
        let weights = self.weights().image(1.0);
        let (w, h) = (self.weights().width as usize, self.weights().height as usize);
        let camera = self.camera(layer).image(1.0 / f64::from(self.scale));
        let light = self.light(layer).image((w * h) as f64 / (samples.max(1) as f64 * f64::from(self.scale)));
        let pixels = camera
            .pixels
            .iter()
            .zip(&light.pixels)
            .zip(&weights.pixels)
            .map(|((&c, &l), wt)| if wt.x > 0.0 { c / wt.x + l } else { l })
            .collect();
        Image::new(w, h, pixels)
    }

    pub fn invalid(&self) -> u64 {
        self.buffers.iter().map(SharedSplats::invalid).sum()
    }
}

/// The splat buffers a render's [`HybridFilm`] holds: none without independent samples
/// (`ratio` 0), else the weights' and two per layer (one layer, or one per depth of `depths`
/// with per-depth images).
pub fn film_buffers(ratio: f64, per_depth: bool, depths: u64) -> u64 {
    if ratio > 0.0 { 1 + 2 * if per_depth { depths } else { 1 } } else { 0 }
}

/// A walker of independent samples: each covers every depth of the render.
pub struct Hybrid {
    seed: u64,
    index: usize,
    /// The walkers drawing samples together: walker `index`'s sample `i` is the render's
    /// `i·walkers + index`-th, at pixel `(i·walkers + index) mod N_pixels`, so that the pixels
    /// get their samples in turn.
    walkers: usize,
    paths: Paths,
    rays: u64,
    /// Samples drawn.
    pub samples: u64,
}

impl Hybrid {
    /// Walker `index` of `walkers` of a render seeded with `seed`.
    pub fn new(seed: u64, index: usize, walkers: usize) -> Self {
        Self { seed, index, walkers, paths: Paths::default(), rays: 0, samples: 0 }
    }

    /// Draws up to `samples` more samples of every depth in `depths` (with `ks` their depths),
    /// splatting depth `depths[i]`'s weighted contributions into `film`'s layer `i` (or its
    /// only layer); returns how many were drawn. Sample `i` of this walker always has the
    /// same seed and pixel, so the image does not depend on how the samples are dealt to rounds
    /// or threads.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &mut self,
        scene: &Scene,
        depths: &[HybridDepth],
        ks: &[usize],
        film: &HybridFilm,
        samples: u64,
        stop: &dyn Fn() -> bool,
    ) -> u64 {
        let (w, h) = (scene.film.width, scene.film.height);
        let pixels = u64::from(w) * u64::from(h);
        let per_depth = film.layers() > 1;
        let mut done = 0;
        while done < samples {
            if done % 256 == 0 && stop() {
                break;
            }
            let pixel = (self.samples * self.walkers as u64 + self.index as u64) % pixels.max(1);
            let (x, y) = ((pixel % u64::from(w)) as f32, (pixel / u64::from(w)) as f32);
            let seed = hash(&[self.seed, 0x4b1d, self.index as u64, self.samples]);
            let mut sampler = IndependentSampler::new(seed, 0);
            sampler.start_stream(Stream::Camera);
            let jitter = sampler.next_2d();
            let at = Vec2::new((x + jitter.x) / w as f32, (y + jitter.y) / h as f32);
            film.weights().add(raster_position(scene, at), Rgb::new(1.0, 0.0, 0.0));
            self.rays += each_strategy_from(scene, ks, at, &mut sampler, &mut self.paths, |i, p, l, light| {
                let layer = if per_depth { i } else { 0 };
                let v = l * (depths[i].weight(luminance(l)) * film.scale);
                if light { film.light(layer).add(p, v) } else { film.camera(layer).add(p, v) }
            });
            self.samples += 1;
            done += 1;
        }
        done
    }

    pub fn rays(&self) -> u64 {
        self.rays
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The chain's weight `f/(f + h)` and the independent samples' `h/(f + h)` sum to one at
    /// every value, clamped or not, and the level follows the counts.
    #[test]
    fn the_weights_sum_to_one() {
        let d = HybridDepth::new(3, 0.2, (1000, 0.5), 100, 4.0);
        assert_eq!(d.strategies, 5.0);
        assert!((d.level - 5.0 * 0.2 * 0.2).abs() < 1e-6);
        for y in [0.0f32, 1e-6, 0.01, 0.1, 0.5, 0.79, 0.81, 3.0, 1e6] {
            let f = target_value(y * 5.0).min(4.0);
            let chain = if f > 0.0 { f / (f + d.level) } else { 0.0 };
            assert!((chain + d.weight(y) - 1.0).abs() < 1e-6, "{y}");
        }
        let alone = HybridDepth::new(0, 0.2, (0, 0.5), 100, f32::INFINITY);
        assert_eq!((alone.strategies, alone.weight(0.3)), (1.0, 1.0));
    }

    /// The level that gives the samples a share of the light: `h = f` halves every value's
    /// light, the share found is the one asked for over mixed values (clamped ones at the
    /// clamp), it grows with the share, and a depth without light weighs its samples 1.
    #[test]
    fn the_level_gives_the_samples_their_share_of_the_light() {
        let even = HybridDepth::with_share(2, &[0.5; 10], 0.5, f32::INFINITY);
        assert!((even.level - 0.5).abs() < 1e-5, "{}", even.level);
        assert_eq!(even.strategies, 4.0);
        let values = [0.0, 1e-3, 0.01, 0.2, 1.0, 3.0, 50.0, 0.0];
        let mut last = 0.0;
        for share in [0.01, 0.3, 0.7, 0.99] {
            let d = HybridDepth::with_share(3, &values, share, 10.0);
            let h = f64::from(d.level);
            let f = |v: f32| f64::from(v.min(10.0));
            let light: f64 = values.iter().map(|&v| f(v) * h / (f(v) + h)).sum();
            let total: f64 = values.iter().map(|&v| f(v)).sum();
            assert!((light / total - share).abs() < 1e-4, "{share}: {}", light / total);
            assert!(h > last, "{share}");
            last = h;
        }
        let dark = HybridDepth::with_share(1, &[0.0; 4], 0.5, f32::INFINITY);
        assert!(dark.level.is_infinite() && dark.weight(0.0) == 1.0);
    }
}
