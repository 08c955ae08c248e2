//! Integrators and the render loop they share. An integrator is chosen once per render (the
//! [`Integrator`] trait object); per-pixel estimators such as the path tracer plug into the tile
//! driver in [`tiles`].

pub mod bdpt;
pub mod hybrid_pilot;
pub mod importance_pilot;
pub mod memory;
pub mod mmlt;
pub mod path;
pub mod pssmlt;
pub(crate) mod render_loop;
pub mod run_stats;
pub mod settings;
pub mod sppm;
pub mod tempered;
pub mod tiles;

#[cfg(test)]
mod clamp_tests;
#[cfg(test)]
mod efficiency_tests;
#[cfg(test)]
mod hybrid_tests;
#[cfg(test)]
mod importance_tests;
#[cfg(test)]
mod layer_tests;
#[cfg(test)]
mod markov_chain_tests;
#[cfg(test)]
mod media_tests;
#[cfg(test)]
mod settings_tests;
#[cfg(test)]
mod tests;

pub use bdpt::{BdptIntegrator, Strategies};
pub use mmlt::MmltIntegrator;
pub use path::PathIntegrator;
pub use pssmlt::PssmltIntegrator;
pub use run_stats::RunStats;
pub use settings::{
    Allocation, Flattening, Hybrid, IntegratorKind, IntegratorSettings, LadderTuning, ReplicaSplats, Swap, TemperedMis,
    create,
};
pub use sppm::{PhotonSampler, SppmIntegrator};
pub use tempered::TemperedIntegrator;

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

impl Budget {
    /// What a render gets once a pilot has taken `spent` of it: the rest of a time budget, but
    /// at least half of it (a pilot that overran its share makes the render late, not empty);
    /// a fixed budget whole.
    pub fn after_pilot(self, spent: Duration) -> Self {
        match self {
            Budget::Time(t) => Budget::Time(t.saturating_sub(spent).max(t / 2)),
            fixed => fixed,
        }
    }
}

/// Snapshot times `spent` earlier: those of a render that follows a preliminary of that length
/// (a pilot, a bootstrap) and counts its own time from there.
pub(crate) fn snapshots_after(snapshots: &[Duration], spent: Duration) -> Vec<Duration> {
    snapshots.iter().map(|t| t.saturating_sub(spent)).collect()
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
#[derive(Clone, Copy)]
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
    /// The most memory a render may take, in bytes; `None`: what the machine has available.
    pub max_memory: Option<u64>,
    /// The processes the render is shared among ([`crate::cluster::Solo`]: this one alone).
    pub cluster: &'a dyn crate::cluster::Cluster,
}

fn no_snapshot(_: usize, _: &RenderOutput) {}

impl<'a> RenderControl<'a> {
    /// A control without snapshots.
    pub fn new(cancel: &'a AtomicBool, on_progress: &'a (dyn Fn(u64) + Sync)) -> Self {
        Self {
            cancel,
            on_progress,
            snapshots: &[],
            on_snapshot: &no_snapshot,
            max_memory: None,
            cluster: &crate::cluster::SOLO,
        }
    }

    /// The same control for a render shared among the processes of `cluster`.
    pub fn with_cluster(self, cluster: &'a dyn crate::cluster::Cluster) -> Self {
        Self { cluster, ..self }
    }

    /// The same control with a memory limit of `bytes` instead of the available memory.
    pub fn with_max_memory(self, bytes: Option<u64>) -> Self {
        Self { max_memory: bytes, ..self }
    }

    /// Refuses a render that would need more than `bytes` (see [`memory::check`]).
    pub fn check_memory(&self, bytes: u64, what: &str) -> Result<(), String> {
        memory::check(bytes, self.max_memory, what)
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
    /// A conservative estimate of the bytes the render allocates, checked before it starts
    /// ([`RenderControl::check_memory`]).
    fn memory_estimate(&self, scene: &Scene, threads: usize) -> u64;
}
