//! Primary-sample-space Metropolis light transport (Kelemen, Szirmay-Kalos, Antal & Csonka 2002)
//! over bidirectional path tracing: one set of chains over all path depths, each state a full
//! BDPT sample (every strategy, MIS-weighted) whose target is the summed luminance of its
//! contributions. The chain driver (bootstrap, start states in proportion to `f`, expected-value
//! splatting, `b` refined with large steps, budgets, determinism) is MMLT's with a single group;
//! the per-group statistics therefore have one row, covering every depth.

use super::mmlt::{ChainSettings, MmltReport};
use super::{ChainIntegrator, RenderControl, RenderOutput, RenderSettings};
use crate::mcmc::{FullContribution, Paths, Target, evaluate_full};
use crate::sampler::PssSampler;
use crate::scene::Scene;

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

impl ChainIntegrator for PssmltIntegrator {
    fn name(&self) -> &'static str {
        "pssmlt"
    }

    /// Renders; the statistics have one row, covering every depth.
    fn render_with_report(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<(RenderOutput, MmltReport), String> {
        let chain = ChainSettings::new(self.bootstrap, self.chains, self.sigma, self.large_step_probability);
        let target = |_| FullTarget { scene, max_depth: self.max_depth };
        let (mut out, mut report) =
            chain.render(scene, settings, control, 1, target, |cx| chain.start_single(cx, target(0)))?;
        for d in out.chains.iter_mut().chain(&mut report.depths) {
            d.all_depths = true;
        }
        Ok((out, report))
    }
}
