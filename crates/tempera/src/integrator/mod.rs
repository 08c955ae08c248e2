//! Integrators and the render loop they share. An integrator is chosen once per render (the
//! [`Integrator`] trait object); per-pixel estimators such as the path tracer plug into the tile
//! driver in [`tiles`].

pub mod bdpt;
pub mod mmlt;
pub mod path;
pub mod pssmlt;
pub(crate) mod render_loop;
pub mod tempered;
pub mod tiles;

#[cfg(test)]
mod tests;

pub use bdpt::{BdptIntegrator, Strategies};
pub use mmlt::MmltIntegrator;
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

/// Interaction with a running render: a cancellation flag (Ctrl-C), a progress callback that
/// receives increments of completed pixel samples, and snapshots of the image so far.
pub struct RenderControl<'a> {
    pub cancel: &'a AtomicBool,
    pub on_progress: &'a (dyn Fn(u64) + Sync),
    /// Elapsed times, increasing, at which a render under a time budget hands `on_snapshot` the
    /// image it has so far (index into this list, output with the statistics so far). A
    /// snapshot is taken at the first point after its time where the render can develop an
    /// image (between passes or rows for per-pixel estimators, between rounds of about one
    /// mutation per pixel for Markov chains); `stats.seconds` says when. Times at or past the
    /// budget are never reached: the render's own output is the last picture.
    pub snapshots: &'a [Duration],
    pub on_snapshot: &'a (dyn Fn(usize, &RenderOutput) + Sync),
}

fn no_snapshot(_: usize, _: &RenderOutput) {}

impl<'a> RenderControl<'a> {
    /// A control without snapshots.
    pub fn new(cancel: &'a AtomicBool, on_progress: &'a (dyn Fn(u64) + Sync)) -> Self {
        Self { cancel, on_progress, snapshots: &[], on_snapshot: &no_snapshot }
    }

    /// The same control, also taking snapshots at `times` (see [`RenderControl::snapshots`]).
    pub fn with_snapshots(self, times: &'a [Duration], on_snapshot: &'a (dyn Fn(usize, &RenderOutput) + Sync)) -> Self {
        Self { snapshots: times, on_snapshot, ..self }
    }
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

#[derive(Clone)]
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
    /// Renders `scene`, or says why it cannot be rendered (for example an MCMC bootstrap in
    /// which no light path reaches the camera).
    fn render(&self, scene: &Scene, settings: &RenderSettings, control: &RenderControl)
    -> Result<RenderOutput, String>;
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
    pub roughen_mis: Option<bool>,
    /// Tempered MMLT: burn-in sweeps that tune the ladder and the acceptance they aim at
    /// (`None`: the integrator's defaults).
    pub burn_in: Option<u64>,
    pub swap_target: Option<f64>,
    /// Tempered MMLT: every replica contributes to the image (`None`: the default).
    pub reuse_replicas: Option<bool>,
    /// Tempered MMLT: sweeps between swap steps (`None`: the default).
    pub swap_every: Option<u64>,
}

/// The integrator called `name`.
pub fn create(name: &str, options: &IntegratorOptions) -> Option<Box<dyn Integrator>> {
    let d = options.max_depth;
    // Chain options: a count of 0 or an absent probability keeps the integrator's default.
    let count = |v: usize, default: usize| if v > 0 { v } else { default };
    let (bootstrap, chains, large_step) = (options.bootstrap, options.chains, options.large_step);
    match name {
        "path" => Some(Box::new(PathIntegrator::new(d))),
        "mmlt" => {
            let m = MmltIntegrator::new(d);
            Some(Box::new(MmltIntegrator {
                bootstrap: count(bootstrap, m.bootstrap),
                chains: count(chains, m.chains),
                large_step_probability: large_step.unwrap_or(m.large_step_probability),
                ..m
            }))
        }
        "tempered" => {
            let m = TemperedIntegrator::new(d);
            Some(Box::new(TemperedIntegrator {
                bootstrap: count(bootstrap, m.bootstrap),
                chains: count(chains, m.chains),
                large_step_probability: large_step.unwrap_or(m.large_step_probability),
                replicas: count(options.replicas, m.replicas),
                swap: options.swap,
                ladder: options.ladder.clone(),
                roughen_mis: options.roughen_mis.unwrap_or(m.roughen_mis),
                burn_in: options.burn_in.unwrap_or(m.burn_in),
                swap_target: options.swap_target.unwrap_or(m.swap_target),
                reuse_replicas: options.reuse_replicas.unwrap_or(m.reuse_replicas),
                swap_every: options.swap_every.unwrap_or(m.swap_every),
                ..m
            }))
        }
        "pssmlt" => {
            let m = PssmltIntegrator::new(d);
            Some(Box::new(PssmltIntegrator {
                bootstrap: count(bootstrap, m.bootstrap),
                chains: count(chains, m.chains),
                large_step_probability: large_step.unwrap_or(m.large_step_probability),
                ..m
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
