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
}

/// The Robbins–Monro recursion on the ladder's log gaps.
pub struct Ladder {
    log_gaps: Vec<f64>,
    /// The largest log gap: `ln(1/(K−1))`.
    max_gap: f64,
    target: f64,
    /// Steps taken.
    n: u64,
}

impl Ladder {
    /// The recursion starting from `ladder` (`a_0 = 0` first, at least two rungs).
    pub fn new(ladder: &[f32], target: f64) -> Self {
        let k = ladder.len();
        let log_gaps = (1..k).map(|j| f64::from(ladder[j] - ladder[j - 1]).max(1e-6).ln()).collect();
        // Roughening saturates at α = 1 (a = 1 flattens every lobe completely), so gaps stay
        // below 1/(K−1) and the ladder within (0, 1].
        Self { log_gaps, max_gap: (1.0 / (k - 1) as f64).ln(), target, n: 0 }
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
        let mut a = 0.0f64;
        self.log_gaps
            .iter()
            .map(|g| {
                a += g.exp();
                a as f32
            })
            .collect()
    }
}

/// The burn-in of one depth: its first ensembles sweep in lockstep under one shared ladder,
/// which then is frozen and given to every ensemble. Returns false when stopped early.
pub fn tune_together(all: &mut [Ensemble], tuning: Tuning, stop: &(dyn Fn() -> bool + Sync)) -> bool {
    let (ensembles, rest) = all.split_at_mut(all.len().min(TUNING_ENSEMBLES));
    let mut ladder = Ladder::new(&ensembles[0].replicas.ladder(), tuning.target);
    let mut finished = true;
    for _ in 0..tuning.sweeps {
        if stop() {
            finished = false;
            break;
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
        let values = ladder.step(&alphas);
        ensembles.par_iter_mut().for_each(|e| e.replicas.set_ladder(&values));
    }
    let values = ensembles[0].replicas.ladder()[1..].to_vec();
    rest.par_iter_mut().for_each(|e| e.replicas.set_ladder(&values));
    finished
}
