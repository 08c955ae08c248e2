//! What every render loop shares, whether it renders tiles of pixel samples ([`super::tiles`])
//! or rounds of Markov-chain mutations ([`crate::mcmc::driver`]): the worker pool, the
//! budget's deadline, cancellation, snapshots under a time budget, and the final timing.

use super::{Budget, RenderControl, RenderOutput, RenderSettings, RenderStats};
use std::sync::atomic::Ordering;
use std::time::{Duration, Instant};

/// One render's pool, clock and control.
pub(crate) struct RenderLoop<'a> {
    pub start: Instant,
    /// When a time budget runs out.
    pub deadline: Option<Instant>,
    pub control: &'a RenderControl<'a>,
    pool: rayon::ThreadPool,
}

impl<'a> RenderLoop<'a> {
    /// Starts the clock and the worker pool (`settings.threads`; 0 uses every core).
    pub fn new(settings: &RenderSettings, control: &'a RenderControl<'a>) -> Self {
        let start = Instant::now();
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(settings.threads)
            .build()
            .expect("a rayon thread pool can be created");
        let deadline = match settings.budget {
            Budget::Time(d) => Some(start + d),
            Budget::Samples(_) => None,
        };
        Self { start, deadline, control, pool }
    }

    /// Runs `f` in the render's worker pool.
    pub fn install<R: Send>(&self, f: impl FnOnce() -> R + Send) -> R {
        self.pool.install(f)
    }

    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// True once the render was asked to stop (Ctrl-C).
    pub fn cancelled(&self) -> bool {
        self.control.cancel.load(Ordering::Relaxed)
    }

    /// True once the time budget is spent.
    pub fn past_deadline(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
    }

    /// True when the render should stop: cancelled or out of time.
    pub fn should_stop(&self) -> bool {
        self.cancelled() || self.past_deadline()
    }

    /// Reports `n` more pixel samples or mutations done.
    pub fn progress(&self, n: u64) {
        (self.control.on_progress)(n);
    }

    /// The snapshots this render takes (only under a time budget).
    pub fn snapshots(&self, budget: Budget) -> Snapshots<'a> {
        let times = if matches!(budget, Budget::Time(_)) { self.control.snapshots } else { &[] };
        Snapshots { start: self.start, times, next: 0 }
    }

    /// The final statistics' time and whether the render was cancelled.
    pub fn finish(&self, stats: &mut RenderStats) {
        stats.seconds = self.start.elapsed().as_secs_f64();
        stats.cancelled = self.cancelled();
    }
}

/// When the next snapshot of a time-budget render is due.
pub(crate) struct Snapshots<'a> {
    start: Instant,
    times: &'a [Duration],
    next: usize,
}

impl Snapshots<'_> {
    /// The instant the next snapshot is due, if any is left.
    pub fn next_due(&self) -> Option<Instant> {
        self.times.get(self.next).map(|&t| self.start + t)
    }

    /// True when a snapshot is due and the render is not cancelled.
    pub fn is_due(&self, render: &RenderLoop) -> bool {
        self.next_due().is_some_and(|d| Instant::now() >= d) && !render.cancelled()
    }

    /// When a snapshot is due and the render is not cancelled, develops the image so far
    /// (`develop` receives the seconds elapsed) and hands it to the control as every snapshot
    /// that is due now (several when one step of the render outlasted more than one requested
    /// time).
    pub fn take(&mut self, render: &RenderLoop, develop: impl FnOnce(f64) -> RenderOutput) {
        let due = self.next_due().is_some_and(|d| Instant::now() >= d);
        if !due || render.cancelled() {
            return;
        }
        let output = develop(self.start.elapsed().as_secs_f64());
        let elapsed = self.start.elapsed();
        while self.next < self.times.len() && self.times[self.next] <= elapsed {
            (render.control.on_snapshot)(self.next, &output);
            self.next += 1;
        }
    }
}
