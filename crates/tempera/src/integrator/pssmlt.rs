//! Primary-sample-space Metropolis light transport (Kelemen, Szirmay-Kalos, Antal & Csonka 2002)
//! over bidirectional path tracing: one set of chains over all path depths, each state a full
//! BDPT sample (every strategy, MIS-weighted) whose target is the summed luminance of its
//! contributions. The chain driver (bootstrap, start states in proportion to `f`, expected-value
//! splatting, `b` refined with large steps, budgets, determinism) is MMLT's with a single group;
//! the per-group statistics therefore have one row, covering every depth.

use super::{Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::mcmc::{ChainSettings, EvalContext, FullContribution, Single, Target, evaluate_full};
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

    fn evaluate(&self, cx: &mut EvalContext, recycled: FullContribution) -> FullContribution {
        evaluate_full(self.scene, self.max_depth, cx, recycled)
    }
}

impl Integrator for PssmltIntegrator {
    fn name(&self) -> &'static str {
        "pssmlt"
    }

    /// Renders; the statistics have one row, covering every depth.
    fn render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        control.check_memory(self.memory_estimate(scene, settings.threads), "the splat buffer")?;
        let chain = ChainSettings::new(self.bootstrap, self.chains, self.sigma, self.large_step_probability);
        let target = |_| FullTarget { scene, max_depth: self.max_depth };
        let mut out = chain.render(scene, settings, control, 1, target, |cx| Single::start(cx, target(0)), None)?;
        for d in &mut out.chains {
            d.all_depths = true;
        }
        Ok(out)
    }

    fn memory_estimate(&self, scene: &Scene, _threads: usize) -> u64 {
        use crate::integrator::memory::{SHARED_SPLAT_BYTES, pixels};
        pixels(scene).saturating_mul(12 + SHARED_SPLAT_BYTES)
    }
}
