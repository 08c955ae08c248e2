//! Integrators and the render loop they share. An integrator is chosen once per render (the
//! [`Integrator`] trait object); per-pixel estimators such as the path tracer plug into the tile
//! driver in [`tiles`].

pub mod bdpt;
pub mod mmlt;
pub mod path;
pub mod pssmlt;
pub mod tempered;
pub mod tiles;

#[cfg(test)]
mod tests;

pub use bdpt::{BdptIntegrator, Strategies};
pub use mmlt::{MmltIntegrator, MmltReport};
pub use path::PathIntegrator;
pub use pssmlt::PssmltIntegrator;
pub use tempered::{Swap, TemperedIntegrator};

use crate::scene::Scene;
use crate::texture::Image;
use std::sync::atomic::AtomicBool;
use std::time::Duration;

/// How much work a render does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Budget {
    /// A fixed number of samples per pixel: deterministic for a given seed.
    Samples(u32),
    /// Wall-clock time: as many samples as fit.
    Time(Duration),
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderSettings {
    pub budget: Budget,
    pub seed: u64,
    /// Worker threads; 0 uses every core.
    pub threads: usize,
}

/// Interaction with a running render: a cancellation flag (Ctrl-C) and a progress callback that
/// receives increments of completed pixel samples.
pub struct RenderControl<'a> {
    pub cancel: &'a AtomicBool,
    pub on_progress: &'a (dyn Fn(u64) + Sync),
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderStats {
    /// Samples per pixel that every pixel received.
    pub spp_completed: u32,
    pub pixel_samples: u64,
    pub rays: u64,
    /// Samples whose value was NaN, infinite or negative (recorded as black).
    pub invalid_samples: u64,
    pub seconds: f64,
    /// True when the render stopped early on request.
    pub cancelled: bool,
}

pub struct RenderOutput {
    pub image: Image,
    pub stats: RenderStats,
    /// Extra images an integrator produces on request (BDPT's per-strategy images), with names.
    pub layers: Vec<Image>,
    /// Per-depth Markov-chain statistics (MCMC integrators only).
    pub chains: Vec<crate::mcmc::DepthStats>,
}

/// A light-transport algorithm.
pub trait Integrator: Send + Sync {
    fn name(&self) -> &'static str;
    /// Names of the extra layers in [`RenderOutput::layers`], in order.
    fn layer_names(&self) -> Vec<String> {
        Vec::new()
    }
    fn render(&self, scene: &Scene, settings: &RenderSettings, control: &RenderControl) -> RenderOutput;
    /// Like [`Self::render`], but reports why a render could not be made (for example an MCMC
    /// bootstrap in which no light path reaches the camera).
    fn try_render(
        &self,
        scene: &Scene,
        settings: &RenderSettings,
        control: &RenderControl,
    ) -> Result<RenderOutput, String> {
        Ok(self.render(scene, settings, control))
    }
}

/// Names accepted by [`create`].
pub const INTEGRATORS: &[&str] = &["path", "bdpt", "mmlt", "pssmlt", "tempered"];

/// Options shared by the integrators [`create`] makes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct IntegratorOptions {
    /// Maximum number of scattering events per path (pbrt's `maxdepth`).
    pub max_depth: u32,
    /// BDPT: also produce one image per strategy.
    pub strategy_images: bool,
    /// BDPT: the MIS heuristic.
    pub heuristic: crate::bidir::Heuristic,
    /// MMLT and PSSMLT: bootstrap samples and chains (per depth for MMLT) and the large-step
    /// probability (`None` or 0 samples and chains keep the integrator's defaults).
    pub bootstrap: usize,
    pub chains: usize,
    pub large_step: Option<f32>,
    /// Tempered MMLT: replicas per ensemble (0: the default), swap strategy, fixed ladder
    /// `a_1 … a_{K−1}` (empty: the default) and whether MIS weights use the roughened densities.
    pub replicas: usize,
    pub swap: Swap,
    pub ladder: Vec<f32>,
    pub keep_mis: bool,
    /// Tempered MMLT: burn-in sweeps that tune the ladder and the acceptance they aim at
    /// (`None`: the integrator's defaults).
    pub burn_in: Option<u64>,
    pub swap_target: Option<f64>,
}

/// The integrator called `name`.
pub fn create(name: &str, options: &IntegratorOptions) -> Option<Box<dyn Integrator>> {
    let d = options.max_depth;
    match name {
        "path" => Some(Box::new(PathIntegrator::new(d))),
        "mmlt" => {
            let defaults = MmltIntegrator::new(d);
            Some(Box::new(MmltIntegrator {
                bootstrap: if options.bootstrap > 0 { options.bootstrap } else { defaults.bootstrap },
                chains: if options.chains > 0 { options.chains } else { defaults.chains },
                large_step_probability: options.large_step.unwrap_or(defaults.large_step_probability),
                ..defaults
            }))
        }
        "tempered" => {
            let defaults = TemperedIntegrator::new(d);
            Some(Box::new(TemperedIntegrator {
                bootstrap: if options.bootstrap > 0 { options.bootstrap } else { defaults.bootstrap },
                chains: if options.chains > 0 { options.chains } else { defaults.chains },
                large_step_probability: options.large_step.unwrap_or(defaults.large_step_probability),
                replicas: if options.replicas > 0 { options.replicas } else { defaults.replicas },
                swap: options.swap,
                ladder: options.ladder.clone(),
                roughen_mis: !options.keep_mis,
                burn_in: options.burn_in.unwrap_or(defaults.burn_in),
                swap_target: options.swap_target.unwrap_or(defaults.swap_target),
                ..defaults
            }))
        }
        "pssmlt" => {
            let defaults = PssmltIntegrator::new(d);
            Some(Box::new(PssmltIntegrator {
                bootstrap: if options.bootstrap > 0 { options.bootstrap } else { defaults.bootstrap },
                chains: if options.chains > 0 { options.chains } else { defaults.chains },
                large_step_probability: options.large_step.unwrap_or(defaults.large_step_probability),
                ..defaults
            }))
        }
        "bdpt" => Some(Box::new(BdptIntegrator {
            strategy_images: options.strategy_images,
            heuristic: options.heuristic,
            ..BdptIntegrator::new(d)
        })),
        _ => None,
    }
}
