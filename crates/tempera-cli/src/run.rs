//! Running one render from the command line, for `tempera render`, an experiment's runs and
//! its references alike: a progress bar on a terminal, Ctrl-C to stop and keep what was
//! rendered, and snapshots for convergence curves.

use anyhow::Result;
use indicatif::{ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};
use tempera::integrator::{Budget, Integrator, RenderControl, RenderOutput, RenderSettings};
use tempera::scene::Scene;

/// Set by Ctrl-C: the render stops and keeps what it has.
pub static CANCEL: AtomicBool = AtomicBool::new(false);

/// True once Ctrl-C was pressed.
pub fn cancelled() -> bool {
    CANCEL.load(Ordering::Relaxed)
}

/// Ctrl-C asks the render to stop and write what it has; a second Ctrl-C exits at once.
pub fn install_interrupt_handler() {
    let installed = ctrlc::set_handler(|| {
        if CANCEL.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    if let Err(e) = installed {
        eprintln!("warning: Ctrl-C will not stop the render cleanly: {e}");
    }
}

/// A progress bar for a render of `pixels` pixels under `budget`, labelled `label` when given;
/// hidden when `quiet` or when standard error is not a terminal.
fn progress_bar(quiet: bool, budget: Budget, pixels: u64, label: Option<&str>) -> ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return ProgressBar::hidden();
    }
    let (len, template) = match budget {
        Budget::Samples(spp) => {
            (pixels * u64::from(spp), "{prefix}{elapsed_precise} [{wide_bar}] {percent}% (eta {eta})")
        }
        Budget::Time(d) => (d.as_millis() as u64, "{prefix}{elapsed_precise} [{wide_bar}] {msg}"),
    };
    let bar = ProgressBar::new(len);
    bar.set_style(ProgressStyle::with_template(template).expect("valid template").progress_chars("=> "));
    if let Some(label) = label {
        bar.set_prefix(format!("{label} "));
    }
    bar
}

/// One render to run.
pub struct Job<'a> {
    pub scene: &'a Scene,
    pub integrator: &'a dyn Integrator,
    pub settings: RenderSettings,
    /// No progress bar.
    pub quiet: bool,
    /// The progress bar's label.
    pub label: Option<&'a str>,
    /// Elapsed times at which `on_snapshot` receives the image so far (time budgets only).
    pub snapshots: &'a [Duration],
    pub on_snapshot: &'a (dyn Fn(usize, &RenderOutput) + Sync),
    /// The most memory the render may take (bytes); `None`: what the machine has available.
    pub max_memory: Option<u64>,
    /// The processes the render is shared among.
    pub cluster: &'a dyn tempera::cluster::Cluster,
}

fn no_snapshot(_: usize, _: &RenderOutput) {}

impl<'a> Job<'a> {
    pub fn new(scene: &'a Scene, integrator: &'a dyn Integrator, settings: RenderSettings, quiet: bool) -> Self {
        Self {
            scene,
            integrator,
            settings,
            quiet,
            label: None,
            snapshots: &[],
            on_snapshot: &no_snapshot,
            max_memory: None,
            cluster: &tempera::cluster::SOLO,
        }
    }

    /// Renders with a progress bar, stopping on Ctrl-C (the output then says `cancelled`).
    pub fn run(&self) -> Result<RenderOutput> {
        let film = &self.scene.film;
        let pixels = u64::from(film.width) * u64::from(film.height);
        let budget = self.settings.budget;
        let bar = progress_bar(self.quiet, budget, pixels, self.label);
        let start = Instant::now();
        let on_progress = |n: u64| match budget {
            Budget::Samples(_) => bar.inc(n),
            Budget::Time(_) => bar.set_position(start.elapsed().as_millis() as u64),
        };
        let control = RenderControl::new(&CANCEL, &on_progress)
            .with_snapshots(self.snapshots, self.on_snapshot)
            .with_max_memory(self.max_memory)
            .with_cluster(self.cluster);
        let out = self.integrator.render(self.scene, &self.settings, &control);
        bar.finish_and_clear();
        out.map_err(anyhow::Error::msg)
    }
}
