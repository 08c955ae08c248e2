//! Primary-sample-space Metropolis light transport (Kelemen, Szirmay-Kalos, Antal & Csonka 2002)
//! over bidirectional path tracing: one set of chains over all path depths, each state a full
//! BDPT sample (every strategy, MIS-weighted) whose target is the summed luminance of its
//! contributions. The chain driver (bootstrap, start states in proportion to `f`, expected-value
//! splatting, `b` refined with large steps, budgets, determinism) is MMLT's with a single group;
//! the per-group statistics therefore have one row, covering every depth.

use super::mmlt::{ChainSettings, MmltReport};
use super::{Integrator, RenderControl, RenderOutput, RenderSettings, RenderStats};
use crate::mcmc::{FullContribution, Paths, Target, evaluate_full};
use crate::sampler::PssSampler;
use crate::scene::Scene;
use crate::texture::Image;

#[derive(Clone, Copy, Debug)]
pub struct PssmltIntegrator {
    pub max_depth: u32,
    /// Bootstrap samples.
    pub bootstrap: usize,
    /// Independent chains.
    pub chains: usize,
    pub sigma: f32,
    pub large_step_probability: f32,
}

impl PssmltIntegrator {
    pub fn new(max_depth: u32) -> Self {
        Self { max_depth, bootstrap: 100_000, chains: 64, sigma: 0.01, large_step_probability: 0.3 }
    }

    /// Renders and returns the chain statistics (one row) alongside the image.
    pub fn render_with_report(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<(RenderOutput, MmltReport), String> {
        let chain = ChainSettings {
            bootstrap: self.bootstrap,
            chains: self.chains,
            sigma: self.sigma,
            large_step_probability: self.large_step_probability,
        };
        let target = |_| FullTarget { scene, max_depth: self.max_depth };
        let (mut out, mut report) =
            chain.render(scene, settings, control, 1, target, |cx| chain.start_single(cx, target(0)))?;
        for d in out.chains.iter_mut().chain(&mut report.depths) {
            d.all_depths = true;
        }
        Ok((out, report))
    }
}

struct FullTarget<'a> {
    scene: &'a Scene,
    max_depth: u32,
}

impl Target for FullTarget<'_> {
    type State = FullContribution;

    fn evaluate(
        &self,
        sampler: &mut PssSampler,
        paths: &mut Paths,
        rays: &mut u64,
        out: &mut FullContribution,
    ) -> bool {
        evaluate_full(self.scene, self.max_depth, sampler, paths, rays, out)
    }
}

impl Integrator for PssmltIntegrator {
    fn name(&self) -> &'static str {
        "pssmlt"
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
        self.try_render(scene, settings, control).unwrap_or_else(|_| RenderOutput {
            image: Image::filled(scene.film.width as usize, scene.film.height as usize, crate::math::Rgb::ZERO),
            stats: RenderStats::default(),
            layers: Vec::new(),
            chains: Vec::new(),
        })
    }
}
