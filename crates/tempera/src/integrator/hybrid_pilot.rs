//! How a render that combines Markov chains with bidirectional path tracing (`--hybrid auto`)
//! splits its work between them and weighs them: a short pilot renders the scene twice by BDPT
//! alone and twice by the render's own chains alone (different seeds), and each pair's
//! difference measures that method's relative variance per unit of work.
//!
//! With `V_b` and `V_m` those variances (relMSE's terms, `ε = 0.01`, against the median of the
//! four images smoothed over 3×3 pixels, so that a firefly does not sit in its own
//! denominator) and `ρ = V_b/V_m`, the render is BDPT alone where `ρ < 0.7`, the chains alone
//! (the integrator's own setup, replica reuse included) where `ρ > 1.5`, and between them a
//! combination in which the samples get the share `s = 1/(1 + ρ⁴)` of the work, clamped to
//! `[0.05, 0.9]`. A combination whose chains get a tenth of the work or less was measured
//! worse than BDPT alone on every scene where the pilot chose it (few mutations per chain mix
//! poorly, and the weights take them for better than they are), and one whose samples get a
//! twentieth worse than the chains alone; the thresholds are the README's. Under a fixed
//! budget BDPT alone draws as many samples per pixel as the pilot measured it to make in the
//! rays of the budget's mutations. A linear model of the two estimators' precisions would put
//! all of the work on the better one; the exponent, chosen by the README's screens, leaves the
//! combination room where both are close. The weights are variance-aware (Grittmann et al.
//! 2019, "Variance-aware multiple importance sampling"): each technique's count in the balance
//! heuristic is divided by its variance per sample, so a main-chain mutation counts as
//! `e = ρ·r_b/r_m` independent samples (`r_b`, `r_m` the samples and mutations made per unit of
//! work). Any split and any weights keep the combination unbiased; the pilot's images are not
//! part of the render's.
//!
//! A time budget gives each pilot render of the chains 4 % of it, at least 1 s (a chain's
//! error falls faster than one over the time at first, so a shorter pilot misjudges it), and
//! each of BDPT 1 %, at least 0.25 s, but never more than half of the budget in all (below 10 s
//! the pilot is shorter than it should be and its choice less sure); the render gets the rest,
//! and at least half of the budget where the pilot overran its share. A fixed budget gives each
//! pilot render of the chains 2 % of the mutations (at least one per pixel) and each of BDPT
//! an eighth of that in samples, and measures work in rays, so that the choice, and the
//! image, do not depend on the machine or the thread count. The chains' work leaves out their
//! bootstrap and preparation, which the render makes once whatever its length.

use super::{BdptIntegrator, Budget, Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::math::luminance;
use crate::scene::Scene;
use std::time::{Duration, Instant};

/// The share of a time budget each pilot render of the chains takes, its least length in
/// seconds (a chain's error falls faster than one over the time at first, so a shorter pilot
/// misjudges it) and its greatest share (a short budget keeps at least half for the render).
const CHAIN_TIME: (f64, f64, f64) = (0.04, 1.0, 0.2);
/// The same for each pilot render of BDPT, whose error falls as one over the time from the
/// start.
const BDPT_TIME: (f64, f64, f64) = (0.01, 0.25, 0.05);
/// The share of a fixed budget's mutations each pilot render of the chains makes.
const SAMPLE_SHARE: f64 = 0.02;
/// The bounds of the samples' share of the work in a combination.
const SHARE_RANGE: (f64, f64) = (0.05, 0.9);
/// Below this variance ratio BDPT renders alone; above the second, the chains.
const ALONE: (f64, f64) = (0.7, 1.5);

/// What the pilot chose (`--stats` writes it in depth 0's row as `hybrid_pilot`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct HybridChoice {
    /// BDPT's relative variance per unit of work over the chains' (`ρ`).
    pub variance_ratio: f64,
    /// The samples' share of the work (`s`): 1 where BDPT renders alone, 0 where the chains do.
    pub work_share: f64,
    /// BDPT samples per main-chain mutation that give the samples that share of the work in a
    /// combination (0 where one method renders alone).
    pub ratio: f64,
    /// BDPT samples per main-chain mutation made in the same work: under a fixed budget, BDPT
    /// alone draws this many samples per pixel for each mutation per pixel of the budget.
    #[serde(default)]
    pub samples_per_mutation: f64,
    /// What a main-chain mutation counts as in the combination's weights: BDPT's variance per
    /// sample over the chains' per mutation (`ρ` times BDPT's samples over the chains'
    /// mutations per unit of work), the variance-aware weights of Grittmann et al. 2019.
    pub efficiency: f64,
    /// The time the pilot took.
    pub seconds: f64,
}

impl HybridChoice {
    /// The split and weights for `variance_ratio` `ρ`, with `rates` the BDPT samples and the
    /// main-chain mutations made per unit of work.
    pub fn from_ratio(variance_ratio: f64, rates: (f64, f64), seconds: f64) -> Self {
        let rho =
            if variance_ratio.is_finite() && variance_ratio > 0.0 { variance_ratio.clamp(1e-3, 1e3) } else { 1.0 };
        let (samples, mutations) = rates;
        let per = if samples > 0.0 && mutations > 0.0 { samples / mutations } else { 0.1 };
        let (work_share, ratio) = if rho < ALONE.0 {
            (1.0, 0.0)
        } else if rho > ALONE.1 {
            (0.0, 0.0)
        } else {
            let s = (1.0 / (1.0 + rho.powi(4))).clamp(SHARE_RANGE.0, SHARE_RANGE.1);
            (s, (s / (1.0 - s) * per).clamp(1e-4, 100.0))
        };
        Self {
            variance_ratio: rho,
            work_share,
            ratio,
            samples_per_mutation: per,
            efficiency: (rho * per).clamp(1e-4, 100.0),
            seconds,
        }
    }

    /// Whether BDPT renders alone.
    pub fn bdpt_alone(&self) -> bool {
        self.work_share >= 1.0
    }

    /// Whether the chains render alone (with the integrator's own setup).
    pub fn chains_alone(&self) -> bool {
        self.work_share <= 0.0
    }
}

/// One method's pilot: its two images, the work each took and what it made per unit of work.
struct Pair {
    images: [RenderOutput; 2],
    work: f64,
}

impl Pair {
    fn run(
        method: &dyn Integrator,
        scene: &Scene,
        settings: RenderSettings,
        control: &RenderControl,
        by_time: bool,
    ) -> Result<Self, String> {
        let mut images = Vec::with_capacity(2);
        let mut work = 0.0;
        for i in 0..2u64 {
            let seed = crate::math::rng::hash(&[settings.seed, 0x9170_7e57, i]);
            let start = Instant::now();
            let out = method.render(scene, &RenderSettings { seed, ..settings }, control)?;
            // The chains' work without their bootstrap and preparation (tempered MMLT's ladder
            // tuning), which the render makes once whatever its length.
            let boot = out.chains.first().map_or((0.0, 0), |d| (d.setup_seconds, d.setup_rays));
            work += if by_time {
                (start.elapsed().as_secs_f64() - boot.0).max(1e-3)
            } else {
                out.stats.rays.saturating_sub(boot.1).max(1) as f64
            };
            images.push(out);
        }
        let images: [RenderOutput; 2] = images.try_into().map_err(|_| "pilot renders missing")?;
        Ok(Self { images, work: work / 2.0 })
    }

    /// Samples (or main-chain mutations) made per unit of work.
    fn rate(&self) -> f64 {
        let n: u64 = self.images.iter().map(|o| o.stats.pixel_samples).sum();
        if self.work > 0.0 { n as f64 / 2.0 / self.work } else { 0.0 }
    }

    /// Relative variance of one image times the work it took, against `reference`.
    fn variance(&self, reference: &[f32]) -> f64 {
        let [a, b] = &self.images;
        let sum: f64 = a
            .image
            .pixels
            .iter()
            .zip(&b.image.pixels)
            .zip(reference)
            .map(|((p, q), r)| {
                let d = f64::from(luminance(*p) - luminance(*q));
                let d = if d.is_finite() { d } else { 0.0 };
                d * d / 2.0 / (f64::from(*r).powi(2) + 0.01)
            })
            .sum();
        sum / reference.len().max(1) as f64 * self.work
    }
}

/// Runs the pilot for a render of `scene` under `settings` by `chains` (the render's own
/// chains, without samples) and BDPT to `max_depth`; returns the choice and the settings left
/// for the render itself.
pub fn choose(
    chains: &dyn Integrator,
    max_depth: u32,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
) -> Result<(HybridChoice, RenderSettings), String> {
    if control.cluster.is_distributed() {
        return Err("--hybrid auto is not supported across MPI ranks yet: give --hybrid a ratio".into());
    }
    let start = Instant::now();
    let quiet = |_: u64| {};
    let pilot_control = RenderControl { on_progress: &quiet, snapshots: &[], ..*control };
    let (chain_budget, bdpt_budget, by_time) = match settings.budget {
        Budget::Time(t) => {
            let t = t.as_secs_f64();
            let each = |(share, least, most): (f64, f64, f64)| {
                Budget::Time(Duration::from_secs_f64((t * share).max(least).min(t * most)))
            };
            (each(CHAIN_TIME), each(BDPT_TIME), true)
        }
        Budget::Samples(mpp) => {
            let m = ((f64::from(mpp) * SAMPLE_SHARE).round() as u32).max(1);
            (Budget::Samples(m), Budget::Samples((m / 8).max(1)), false)
        }
    };
    let bdpt = BdptIntegrator::new(max_depth);
    let samples =
        Pair::run(&bdpt, scene, RenderSettings { budget: bdpt_budget, ..*settings }, &pilot_control, by_time)?;
    let walks =
        Pair::run(chains, scene, RenderSettings { budget: chain_budget, ..*settings }, &pilot_control, by_time)?;
    // The reference: per pixel the median of the four images (a firefly in one of them would
    // otherwise enter its own denominator and hide), averaged over the pixel's 3×3 block.
    let (w, h) = (scene.film.width as usize, scene.film.height as usize);
    let median: Vec<f32> = (0..w * h)
        .map(|j| {
            let mut v: Vec<f32> = samples
                .images
                .iter()
                .chain(&walks.images)
                .map(|o| luminance(o.image.pixels[j]))
                .map(|y| if y.is_finite() { y } else { 0.0 })
                .collect();
            v.sort_by(f32::total_cmp);
            0.5 * (v[1] + v[2])
        })
        .collect();
    let reference =
        crate::mcmc::importance::neighbourhood(w, h, &median, 1, |v| v.iter().sum::<f32>() / v.len() as f32);
    let rho = samples.variance(&reference) / walks.variance(&reference);
    let seconds = start.elapsed().as_secs_f64();
    let choice = HybridChoice::from_ratio(rho, (samples.rate(), walks.rate()), seconds);
    // A pilot that overran its share (budgets of a second or less, where the chains' bootstrap
    // alone takes longer) leaves half.
    Ok((choice, RenderSettings { budget: settings.budget.after_pilot(start.elapsed()), ..*settings }))
}

/// Renders by the pilot's choice: the pilot by `chains`, then `main` with the choice, under
/// the rest of a time budget (its snapshots as many seconds earlier as the pilot took); the
/// statistics count the pilot's time and carry the choice in depth 0's row.
pub fn render(
    chains: &dyn Integrator,
    max_depth: u32,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
    main: impl FnOnce(&HybridChoice, &RenderSettings, &RenderControl) -> Result<RenderOutput, String>,
) -> Result<RenderOutput, String> {
    let (choice, rest) = choose(chains, max_depth, scene, settings, control)?;
    let pilot = Duration::from_secs_f64(choice.seconds);
    let snapshots = super::snapshots_after(control.snapshots, pilot);
    let control = RenderControl { snapshots: &snapshots, ..*control };
    let mut out = if choice.bdpt_alone() {
        let budget = match rest.budget {
            // The samples the budget's mutations would have cost in rays.
            Budget::Samples(mpp) => {
                Budget::Samples(((f64::from(mpp) * choice.samples_per_mutation).round() as u32).max(1))
            }
            time => time,
        };
        let mut out = BdptIntegrator::new(max_depth).render(scene, &RenderSettings { budget, ..rest }, &control)?;
        // BDPT has no chains: the choice gets a row of its own.
        out.chains = vec![crate::mcmc::DepthStats::default()];
        out
    } else {
        main(&choice, &rest, &control)?
    };
    out.stats.seconds += choice.seconds;
    if let Some(first) = out.chains.first_mut() {
        first.hybrid_choice = Some(choice);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// BDPT worse: little work and weight for the samples; better: most of both; the count ratio
    /// converts the split with the rates; far apart, one method renders alone.
    #[test]
    fn the_split_follows_the_variance_ratio() {
        let worse = HybridChoice::from_ratio(1.4, (1.0, 10.0), 0.0);
        let even = HybridChoice::from_ratio(1.0, (1.0, 10.0), 0.0);
        let better = HybridChoice::from_ratio(0.75, (1.0, 10.0), 0.0);
        assert!((worse.work_share - 1.0 / (1.0 + 1.4f64.powi(4))).abs() < 1e-12);
        assert!((even.work_share - 0.5).abs() < 1e-12);
        assert!(better.work_share > 0.75 && better.work_share < 0.9, "{}", better.work_share);
        // A mutation counts as ρ times the samples per mutation made per unit of work.
        assert!((worse.efficiency - 0.14).abs() < 1e-12 && (better.efficiency - 0.075).abs() < 1e-12);
        assert!((even.ratio - 0.1).abs() < 1e-12, "{}", even.ratio);
        // No measurement: an even split.
        assert_eq!(HybridChoice::from_ratio(f64::NAN, (1.0, 10.0), 0.0).work_share, 0.5);
        // Far apart: one method alone, and no samples beside the chains.
        let chains = HybridChoice::from_ratio(3.0, (1.0, 10.0), 0.0);
        let bdpt = HybridChoice::from_ratio(0.2, (1.0, 10.0), 0.0);
        assert!(chains.chains_alone() && !chains.bdpt_alone() && chains.ratio == 0.0);
        assert!(bdpt.bdpt_alone() && !bdpt.chains_alone() && bdpt.ratio == 0.0);
        assert!(!even.bdpt_alone() && !even.chains_alone());
        assert_eq!(bdpt.samples_per_mutation, 0.1);
    }
}
