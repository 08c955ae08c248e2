//! The roughening ladder `a_0 = 0 < a_1 < … < a_{K−1}` of one depth and its tuning (Šik &
//! Křivánek 2016; the adaptation follows Atchadé, Roberts & Rosenthal 2011): during a burn-in
//! of `sweeps` sweeps, in which the depth's first [`TUNING_ENSEMBLES`] ensembles sweep in
//! lockstep (splats discarded), the gaps `a_j − a_{j−1}` follow a Robbins–Monro recursion on
//! their logarithm, `ln g_j += γ_n (ᾱ_j − α*)` with `γ_n = (1 + n/10)^−0.6`, where `ᾱ_j` is
//! the probability of exchanging replicas `j − 1` and `j` (whatever the swap strategy)
//! averaged over those ensembles and `α*` the target (0.234). A shared ladder lets one
//! calibration from the depth's bootstrap serve all-replica reuse, and averages out the noise
//! of single ensembles. Wider gaps lower the acceptance, so the recursion settles where the
//! neighbour acceptance averages `α*`; the ladder is then frozen. Gaps are capped at
//! `1/(K−1)`: beyond `a = 1` roughening changes nothing, and on scenes whose connections are
//! mostly diffuse the acceptance stays above `α*` even at the cap.

use super::ensemble::Ensemble;
use rayon::prelude::*;

/// Ensembles of a depth that tune its ladder in lockstep; the others take the result.
const TUNING_ENSEMBLES: usize = 8;

/// How a depth's ladder is tuned.
#[derive(Clone, Copy, Debug)]
pub struct Tuning {
    /// Burn-in sweeps.
    pub sweeps: u64,
    /// Target neighbour acceptance.
    pub target: f64,
    /// The highest temperature the ladder may reach (1: roughening only).
    pub max_temperature: f32,
}

/// How far temperatures beyond 1 are spaced in the tuner's coordinate: a unit step there
/// multiplies `τ` (and divides the exponent `1/τ`) by `e⁴ ≈ 55`.
const DECADES_PER_HEAT: f64 = 4.0;

/// The tuner's coordinate of temperature `tau`: `τ` itself up to 1 (roughening), beyond it
/// logarithmic, so that the powers `f^{1/τ}` of hot replicas are spaced geometrically.
fn heat(tau: f32) -> f64 {
    if tau <= 1.0 { f64::from(tau) } else { 1.0 + f64::from(tau).ln() / DECADES_PER_HEAT }
}

/// The temperature at heat `h` (inverse of [`heat`]).
fn temperature(h: f64) -> f32 {
    if h <= 1.0 { h as f32 } else { (DECADES_PER_HEAT * (h - 1.0)).exp() as f32 }
}

/// The Robbins–Monro recursion on the log gaps of the ladder's heats.
pub struct Ladder {
    log_gaps: Vec<f64>,
    /// The largest log gap: `ln(1/(K−1))`.
    max_gap: f64,
    target: f64,
    /// Steps taken.
    n: u64,
}

impl Ladder {
    /// The recursion starting from `ladder` (`τ_0 = 0` first, at least two rungs), keeping
    /// the ladder within `(0, max_temperature]`.
    pub fn new(ladder: &[f32], target: f64, max_temperature: f32) -> Self {
        let k = ladder.len();
        // Rungs within the roughness range subtract in f32, as the ladder itself is stored.
        let gap = |j: usize| match ladder[j] <= 1.0 {
            true => f64::from(ladder[j] - ladder[j - 1]),
            false => heat(ladder[j]) - heat(ladder[j - 1]),
        };
        let log_gaps = (1..k).map(|j| gap(j).max(1e-6).ln()).collect();
        // Gaps stay below h_max/(K−1). With τ_max = 1 (roughening only) this is where
        // roughening saturates: a = 1 flattens every lobe completely.
        Self { log_gaps, max_gap: (heat(max_temperature) / (k - 1) as f64).ln(), target, n: 0 }
    }

    /// One step with the neighbour acceptances `alphas[e][j]` (pair `(j, j+1)` of tuning
    /// ensemble `e`); returns the new `a_1 … a_{K−1}`.
    pub fn step(&mut self, alphas: &[Vec<f64>]) -> Vec<f32> {
        let gamma = (1.0 + self.n as f64 / 10.0).powf(-0.6);
        for (j, g) in self.log_gaps.iter_mut().enumerate() {
            let mean = alphas.iter().map(|a| a[j]).sum::<f64>() / alphas.len() as f64;
            *g = (*g + gamma * (mean - self.target)).clamp(1e-5f64.ln(), self.max_gap);
        }
        self.n += 1;
        let mut h = 0.0f64;
        self.log_gaps
            .iter()
            .map(|g| {
                h += g.exp();
                temperature(h)
            })
            .collect()
    }
}

/// The burn-in of one depth: its first ensembles sweep in lockstep under one shared ladder,
/// which then is frozen and given to every ensemble. Returns the neighbour acceptance over the
/// last quarter of the burn-in (averaged over pairs and tuning ensembles), or `None` when
/// stopped early.
pub fn tune_together(all: &mut [Ensemble], tuning: Tuning, stop: &(dyn Fn() -> bool + Sync)) -> Option<f64> {
    let (ensembles, rest) = all.split_at_mut(all.len().min(TUNING_ENSEMBLES));
    let mut ladder = Ladder::new(&ensembles[0].replicas.ladder(), tuning.target, tuning.max_temperature);
    let settled = tuning.sweeps - tuning.sweeps / 4;
    let (mut sum, mut n) = (0.0, 0u64);
    for sweep in 0..tuning.sweeps {
        if stop() {
            return None;
        }
        // One sweep of every tuning ensemble, then one step of the recursion with their mean
        // acceptance (a step per batch of sweeps lags behind the target; see the README).
        let alphas: Vec<Vec<f64>> = ensembles
            .par_iter_mut()
            .map(|e| {
                let alphas = e.tuning_sweep();
                e.swap();
                alphas
            })
            .collect();
        if sweep >= settled {
            sum += alphas.iter().flatten().sum::<f64>();
            n += alphas.iter().map(Vec::len).sum::<usize>() as u64;
        }
        let values = ladder.step(&alphas);
        ensembles.par_iter_mut().for_each(|e| e.replicas.set_ladder(&values));
    }
    let values = ensembles[0].replicas.ladder()[1..].to_vec();
    rest.par_iter_mut().for_each(|e| e.replicas.set_ladder(&values));
    Some(if n > 0 { sum / n as f64 } else { 0.0 })
}
