//! Bidirectional path tracing (Veach & Guibas 1995; Veach 1997 ch. 10; pbrt-v4 §13.3): a camera
//! and a light subpath per pixel sample, every strategy `(s, t)` up to `max_depth` combined by
//! MIS; light-tracing strategies (`t = 1`) are splatted onto the film. Subsets of strategies
//! without MIS (light tracing alone, or path tracing without light sampling) are available for
//! validation.

use super::tiles::{PixelEstimator, SampleCtx, render_tiles};
use super::{Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::bidir::{Heuristic, Subpaths, Vertex, camera_subpath, connect, light_subpath};
use crate::geometry::Ray;
use crate::math::Rgb;
use crate::sampler::Sampler;
use crate::scene::Scene;
use std::cell::RefCell;

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
}

impl BdptIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, heuristic: Heuristic::Power, strategies: Strategies::All }
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

thread_local! {
    /// Reused subpath storage, one pair per worker thread.
    static PATHS: RefCell<(Vec<Vertex>, Vec<Vertex>)> = const { RefCell::new((Vec::new(), Vec::new())) };
}

impl PixelEstimator for BdptIntegrator {
    const SPLATS: bool = true;

    fn li<S: Sampler>(&self, scene: &Scene, ray: Ray, sampler: &mut S, ctx: &mut SampleCtx) -> Rgb {
        PATHS.with_borrow_mut(|(camera, light)| {
            camera_subpath(scene, ray, sampler, self.max_depth, camera, &mut ctx.rays);
            light_subpath(scene, sampler, self.max_depth, light, &mut ctx.rays);
            let mut l = Rgb::ZERO;
            for t in 1..=camera.len() {
                for s in 0..=light.len() {
                    let depth = (s + t) as i64 - 2;
                    if (s == 1 && t == 1) || depth < 0 || depth > i64::from(self.max_depth) || !self.included(s, t) {
                        continue;
                    }
                    let paths = Subpaths { light, camera };
                    let Some(c) = connect(scene, paths, (s, t), sampler, self.heuristic, &mut ctx.rays) else {
                        continue;
                    };
                    let w = if self.strategies == Strategies::All { c.weight } else { 1.0 };
                    let v = c.l * w;
                    match (t, c.raster) {
                        (1, Some(raster)) => ctx.splats.add(raster, v),
                        _ => l += v,
                    }
                }
            }
            l
        })
    }
}

impl Integrator for BdptIntegrator {
    fn name(&self) -> &'static str {
        "bdpt"
    }

    fn render(&self, scene: &Scene, settings: &RenderSettings, control: &RenderControl) -> RenderOutput {
        render_tiles(self, scene, settings, control)
    }
}
