//! Multiplexed Metropolis light transport (Hachisuka, Kaplanyan & Dachsbacher 2014; pbrt-v4
//! §13.4): per path depth `k`, Markov chains in primary sample space whose states choose one
//! bidirectional strategy each; target `f = luminance((k+2)·w·f/p)`. A bootstrap of independent
//! states gives the normalisation `b_k` and the chains' start states (drawn in proportion to
//! `f`, which removes start-up bias); mutations are allotted to depths in proportion to `b_k`;
//! proposals and current states are splatted with expected values (`a` and `1 − a`, as `C/f`).
//! `b_k` is refined with the large-step proposals, which are independent uniform samples, so the
//! image brightness does not hinge on the bootstrap. Chains are the unit of parallel work and
//! splat into per-thread fixed-point buffers: the image is bit-identical at any thread count.

use super::{Budget, Integrator, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::film::SplatBuffer;
use crate::math::distribution::Distribution1D;
use crate::math::rng::{Pcg32, hash};
use crate::mcmc::{Contribution, DepthStats, Paths, evaluate};
use crate::sampler::PssSampler;
use crate::scene::Scene;
use crate::texture::Image;
use rayon::prelude::*;
use std::sync::Mutex;
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

fn sampler_for(seed: u64, k: usize, i: usize, m: &MmltIntegrator) -> PssSampler {
    PssSampler::new(bootstrap_seed(seed, k, i), k as u64, m.sigma, m.large_step_probability)
}

/// What every chain of a render shares.
struct ChainContext<'a> {
    scene: &'a Scene,
    seed: u64,
    /// Per depth, the bootstrap distribution that start states are drawn from.
    starts: Vec<Distribution1D>,
    deadline: Option<Instant>,
    control: &'a RenderControl<'a>,
}

/// One chain's work.
struct ChainJob {
    depth: usize,
    index: usize,
    mutations: u64,
}

struct ChainResult {
    depth: usize,
    stats: DepthStats,
    large_sum: f64,
    large_sum2: f64,
    large_count: u64,
    rays: u64,
}

/// The result of the bootstrap of one depth: target values and their mean.
struct Bootstrap {
    values: Vec<f32>,
    mean: f64,
    sum2: f64,
    invalid: u64,
}

impl MmltIntegrator {
    fn bootstrap(&self, scene: &Scene, seed: u64, k: usize) -> (Bootstrap, u64) {
        let results: Vec<(f32, bool, u64)> = (0..self.bootstrap)
            .into_par_iter()
            .map_init(Paths::default, |paths, i| {
                let mut sampler = sampler_for(seed, k, i, self);
                let mut rays = 0;
                let (c, invalid) = evaluate(scene, k, &mut sampler, paths, &mut rays);
                (c.f, invalid, rays)
            })
            .collect();
        let values: Vec<f32> = results.iter().map(|r| r.0).collect();
        let n = values.len().max(1) as f64;
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let sum2 = values.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>();
        let invalid = results.iter().filter(|r| r.1).count() as u64;
        let rays = results.iter().map(|r| r.2).sum();
        (Bootstrap { values, mean, sum2, invalid }, rays)
    }

    /// Runs one chain, splatting `C/f`-weighted contributions into `splats`.
    fn run_chain(&self, ctx: &ChainContext, job: &ChainJob, splats: &mut SplatBuffer) -> ChainResult {
        let ChainContext { scene, seed, deadline, control, .. } = *ctx;
        let starts = &ctx.starts[job.depth];
        let k = job.depth;
        let start_time = Instant::now();
        let mut rng = Pcg32::new(hash(&[seed, 0xc4a1, k as u64, job.index as u64]), 7);
        let (start, _, _) = starts.sample_discrete(rng.next_f32());
        let mut sampler = sampler_for(seed, k, start, self);
        let mut paths = Paths::default();
        let mut rays = 0;
        let (mut current, _) = evaluate(scene, k, &mut sampler, &mut paths, &mut rays);
        sampler.accept();
        let mut stats = DepthStats { depth: k, ..DepthStats::default() };
        let (mut large_sum, mut large_sum2, mut large_count) = (0.0f64, 0.0f64, 0u64);
        let splat = |splats: &mut SplatBuffer, c: &Contribution, weight: f32| {
            if weight > 0.0 && c.f > 0.0 {
                splats.add(c.raster, c.l * (weight / c.f));
            }
        };
        for m in 0..job.mutations {
            if m % 256 == 0 && (control.cancel.load(Ordering::Relaxed) || deadline.is_some_and(|d| Instant::now() >= d))
            {
                break;
            }
            sampler.start_iteration();
            let large = sampler.is_large_step();
            let (proposal, invalid) = evaluate(scene, k, &mut sampler, &mut paths, &mut rays);
            stats.invalid += u64::from(invalid);
            if large {
                large_sum += f64::from(proposal.f);
                large_sum2 += f64::from(proposal.f).powi(2);
                large_count += 1;
            }
            let a = if current.f > 0.0 { (proposal.f / current.f).min(1.0) } else { 1.0 };
            splat(splats, &proposal, a);
            splat(splats, &current, 1.0 - a);
            stats.mutations += 1;
            if large {
                stats.large_steps_proposed += 1;
            } else {
                stats.small_steps_proposed += 1;
            }
            if rng.next_f32() < a {
                if proposal.technique != current.technique {
                    stats.technique_changes += 1;
                }
                if large {
                    stats.large_steps_accepted += 1;
                } else {
                    stats.small_steps_accepted += 1;
                }
                current = proposal;
                sampler.accept();
            } else {
                sampler.reject();
            }
        }
        stats.seconds = start_time.elapsed().as_secs_f64();
        ChainResult { depth: k, stats, large_sum, large_sum2, large_count, rays }
    }

    /// Renders and returns the per-depth statistics alongside the image.
    pub fn render_with_report(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<(RenderOutput, MmltReport), String> {
        let start = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .expect("a rayon thread pool can be created");
        pool.install(|| self.render_in_pool(scene, settings, control, start))
    }

    fn render_in_pool(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
        start: Instant,
    ) -> Result<(RenderOutput, MmltReport), String> {
        let seed = settings.seed;
        let depths = self.max_depth as usize + 1;
        let (w, h) = (scene.film.width, scene.film.height);
        let pixels = u64::from(w) * u64::from(h);
        let mut total_rays = 0;
        let boots: Vec<Bootstrap> = (0..depths)
            .map(|k| {
                let (b, rays) = self.bootstrap(scene, seed, k);
                total_rays += rays;
                b
            })
            .collect();
        let b_total: f64 = boots.iter().map(|b| b.mean).sum();
        if b_total.is_nan() || b_total <= 0.0 {
            return Err("no light path reaches the camera (every bootstrap sample was zero)".into());
        }
        // Mutations per depth in proportion to b_k; a time budget sets a large cap and stops at
        // the deadline.
        let (total_mutations, deadline) = match settings.budget {
            Budget::Samples(mpp) => (u64::from(mpp) * pixels, None),
            Budget::Time(d) => (u64::MAX / 4, Some(start + d)),
        };
        let mut jobs = Vec::new();
        for (k, b) in boots.iter().enumerate() {
            let m_k = ((b.mean / b_total) * total_mutations as f64).round() as u64;
            if m_k == 0 || b.mean <= 0.0 {
                continue;
            }
            let chains = (self.chains as u64).min(m_k).max(1);
            for c in 0..chains {
                let mutations = m_k / chains + u64::from(c < m_k % chains);
                jobs.push(ChainJob { depth: k, index: c as usize, mutations });
            }
        }
        let ctx = ChainContext {
            scene,
            seed,
            starts: boots.iter().map(|b| Distribution1D::new(&b.values)).collect(),
            deadline,
            control,
        };
        let threads = rayon::current_num_threads().max(1);
        let buffers: Vec<Mutex<Vec<SplatBuffer>>> =
            (0..threads).map(|_| Mutex::new((0..depths).map(|_| SplatBuffer::new(w, h)).collect())).collect();
        let results: Vec<ChainResult> = jobs
            .par_iter()
            .map(|job| {
                let index = rayon::current_thread_index().unwrap_or(0) % buffers.len();
                let mut guard = buffers[index].lock().unwrap_or_else(std::sync::PoisonError::into_inner);
                self.run_chain(&ctx, job, &mut guard[job.depth])
            })
            .collect();
        // Merge statistics in job order; refine b_k with the large-step proposals.
        let mut report =
            MmltReport { depths: (0..depths).map(|k| DepthStats { depth: k, ..DepthStats::default() }).collect() };
        let mut large: Vec<(f64, f64, u64)> = vec![(0.0, 0.0, 0); depths];
        for r in &results {
            report.depths[r.depth].merge(&r.stats);
            large[r.depth].0 += r.large_sum;
            large[r.depth].1 += r.large_sum2;
            large[r.depth].2 += r.large_count;
            total_rays += r.rays;
        }
        let mut per_depth = vec![SplatBuffer::new(w, h); depths];
        for buffer in buffers {
            let buffer = buffer.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner);
            for (total, b) in per_depth.iter_mut().zip(&buffer) {
                total.merge(b);
            }
        }
        let mut image = Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO);
        let mut invalid = 0;
        for (k, d) in report.depths.iter_mut().enumerate() {
            let boot = &boots[k];
            let n = boot.values.len() as u64 + large[k].2;
            let sum = boot.mean * boot.values.len() as f64 + large[k].0;
            let sum2 = boot.sum2 + large[k].1;
            d.b = if n > 0 { sum / n as f64 } else { 0.0 };
            let var = if n > 1 { (sum2 / n as f64 - d.b * d.b).max(0.0) * n as f64 / (n - 1) as f64 } else { 0.0 };
            d.b_rel_se = if d.b > 0.0 { (var / n as f64).sqrt() / d.b } else { 0.0 };
            d.bootstrap_samples = boot.values.len() as u64;
            d.large_step_samples = large[k].2;
            d.invalid += boot.invalid;
            invalid += d.invalid + per_depth[k].invalid;
            if d.mutations == 0 {
                continue;
            }
            let layer = per_depth[k].image(d.b * pixels as f64 / d.mutations as f64);
            for (p, q) in image.pixels.iter_mut().zip(&layer.pixels) {
                *p += *q;
            }
        }
        let mutations: u64 = report.depths.iter().map(|d| d.mutations).sum();
        let stats = RenderStats {
            spp_completed: (mutations / pixels.max(1)) as u32,
            pixel_samples: mutations,
            rays: total_rays,
            invalid_samples: invalid,
            seconds: start.elapsed().as_secs_f64(),
            cancelled: control.cancel.load(Ordering::Relaxed),
        };
        Ok((RenderOutput { image, stats, layers: Vec::new() }, report))
    }
}

impl Integrator for MmltIntegrator {
    fn name(&self) -> &'static str {
        "mmlt"
    }

    fn try_render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        self.render_with_report(scene, settings, control).map(|(out, _)| out)
    }

    fn render(&self, scene: &Scene, settings: &RenderSettings, control: &RenderControl) -> RenderOutput {
        match self.render_with_report(scene, settings, control) {
            Ok((out, _)) => out,
            Err(_) => RenderOutput {
                image: Image::filled(scene.film.width as usize, scene.film.height as usize, crate::math::Rgb::ZERO),
                stats: RenderStats::default(),
                layers: Vec::new(),
            },
        }
    }
}
