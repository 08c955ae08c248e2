//! Bidirectional path tracing (Veach & Guibas 1995; Veach 1997 ch. 10; pbrt-v4 §13.3): a camera
//! and a light subpath per pixel sample, every strategy `(s, t)` up to `max_depth` combined by
//! MIS; light-tracing strategies (`t = 1`) are splatted onto the film. Subsets of strategies
//! without MIS (light tracing alone, or path tracing without light sampling) are available for
//! validation.

use super::tiles::{PixelEstimator, SampleCtx, render_tiles};
use super::{Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::bidir::{Heuristic, camera_subpath, connect, light_subpath};
use crate::geometry::Ray;
use crate::math::Rgb;
use crate::sampler::Sampler;
use crate::scene::Scene;

/// Which strategies contribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Strategies {
    /// Every strategy, MIS-weighted.
    #[default]
    All,
    /// Only light tracing (`t = 1`), unweighted: one strategy per path length.
    LightTracing,
    /// Only camera paths that hit emitters (`s = 0`, `t ≥ 3`), unweighted.
    PathTracing,
    /// One strategy `(s, t)`, unweighted.
    Only(usize, usize),
}

#[derive(Clone, Copy, Debug)]
pub struct BdptIntegrator {
    pub max_depth: u32,
    pub heuristic: Heuristic,
    pub strategies: Strategies,
    /// Also accumulate one image per strategy `(s, t)` with its weighted contribution (what
    /// pbrt calls `visualizestrategies`).
    pub strategy_images: bool,
}

/// Every strategy `(s, t)` up to `max_depth`, in the order of the strategy images.
pub fn strategy_list(max_depth: u32) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for depth in 0..=max_depth as usize {
        for s in 0..=depth + 1 {
            let t = depth + 2 - s;
            if !(s == 1 && t == 1) {
                out.push((s, t));
            }
        }
    }
    out
}

fn strategy_index(s: usize, t: usize) -> usize {
    // Depth d = s + t - 2 contributes d + 2 strategies (s = 0 … d + 1), minus (1, 1) at d = 0.
    let d = s + t - 2;
    let before: usize = (0..d).map(|k| k + 2).sum::<usize>() - usize::from(d > 0);
    before + s
}

impl BdptIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, heuristic: Heuristic::Power, strategies: Strategies::All, strategy_images: false }
    }

    fn included(&self, s: usize, t: usize) -> bool {
        match self.strategies {
            Strategies::All => true,
            Strategies::LightTracing => t == 1,
            Strategies::PathTracing => s == 0 && t >= 3,
            Strategies::Only(a, b) => (s, t) == (a, b),
        }
    }
}

impl PixelEstimator for BdptIntegrator {
    const SPLATS: bool = true;

    fn layers(&self) -> usize {
        if self.strategy_images { strategy_list(self.max_depth).len() } else { 0 }
    }

    fn li<S: Sampler>(&self, scene: &Scene, ray: Ray, sampler: &mut S, ctx: &mut SampleCtx) -> Rgb {
        let paths = &mut *ctx.paths;
        camera_subpath(scene, ray, sampler, self.max_depth, &mut paths.camera, &mut ctx.rays);
        light_subpath(scene, sampler, self.max_depth, &mut paths.light, &mut ctx.rays);
        let mut l = Rgb::ZERO;
        for t in 1..=paths.camera.len() {
            for s in 0..=paths.light.len() {
                let depth = (s + t) as i64 - 2;
                if (s == 1 && t == 1) || depth < 0 || depth > i64::from(self.max_depth) || !self.included(s, t) {
                    continue;
                }
                let Some(c) = connect(scene, paths.subpaths(), (s, t), sampler, self.heuristic, &mut ctx.rays) else {
                    continue;
                };
                let w = if self.strategies == Strategies::All { c.weight } else { 1.0 };
                let v = c.l * w;
                let raster = match (t, c.raster) {
                    (1, Some(raster)) => {
                        ctx.splats.add(raster, v);
                        raster
                    }
                    _ => {
                        l += v;
                        ctx.raster
                    }
                };
                if self.strategy_images {
                    ctx.layers[strategy_index(s, t)].add(raster, v);
                }
            }
        }
        l
    }
}

impl Integrator for BdptIntegrator {
    fn name(&self) -> &'static str {
        "bdpt"
    }

    fn layer_names(&self) -> Vec<String> {
        if !self.strategy_images {
            return Vec::new();
        }
        strategy_list(self.max_depth).into_iter().map(|(s, t)| format!("s{s}_t{t}")).collect()
    }

    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        let bytes = self.memory_estimate(scene, settings.threads);
        control.check_memory(bytes, "the film and a light-tracing splat buffer per thread")?;
        Ok(render_tiles(self, scene, settings, control))
    }

    fn memory_estimate(&self, scene: &Scene, threads: usize) -> u64 {
        use super::memory::{FILM_BYTES, SPLAT_BYTES, pixels};
        let threads = if threads == 0 { rayon::current_num_threads() } else { threads } as u64;
        let layers = 1 + self.layer_names().len() as u64;
        pixels(scene).saturating_mul(FILM_BYTES + (threads + 1) * layers * SPLAT_BYTES)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strategy_indices_follow_the_list() {
        for max_depth in 0..6 {
            for (i, (s, t)) in strategy_list(max_depth).into_iter().enumerate() {
                assert_eq!(strategy_index(s, t), i, "({s}, {t})");
            }
        }
        assert_eq!(strategy_list(1), vec![(0, 2), (0, 3), (1, 2), (2, 1)]);
    }
}
