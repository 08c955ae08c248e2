//! The roughening ladder `a_0 = 0 < a_1 < … < a_{K−1}` of one depth and its tuning for a
//! target neighbour-swap acceptance `α*` (0.234; Šik & Křivánek 2016), in one of two ways.
//!
//! **From the bootstrap, before the first sweep** (the default). In an ensemble at
//! equilibrium replicas `i` and `j` hold independent states `x ~ π_i`, `y ~ π_j`, so the
//! expected acceptance of exchanging them is
//! `α_ij = ∫∫ min(f_i(x) f_j(y), f_i(y) f_j(x)) dx dy / (b_i b_j)`
//! (the Metropolis ratio times the two densities). The depth's bootstrap samples are uniform,
//! valued under every candidate temperature without rays (a state keeps its path), and the
//! double sum over pairs of samples estimates the integral by importance weighting. Sorted by
//! `r = f_j/f_i`, `min(f_i(x) f_j(y), f_i(y) f_j(x)) = f_i(x) f_i(y) min(r_x, r_y)`, so the sum
//! over all pairs costs `O(N log N)`. The rungs are then chosen one after the other on a grid
//! of temperatures: each the hottest whose acceptance with the previous rung stays at or above
//! `α*`, with gaps capped as below.
//!
//! **During a burn-in** of `sweeps` sweeps (the adaptation follows Atchadé, Roberts &
//! Rosenthal 2011), in which the depth's first [`TUNING_ENSEMBLES`] ensembles sweep in
//! lockstep (splats discarded), the gaps `a_j − a_{j−1}` follow a Robbins–Monro recursion on
//! their logarithm, `ln g_j += γ_n (ᾱ_j − α*)` with `γ_n = (1 + n/10)^−0.6`, where `ᾱ_j` is
//! the probability of exchanging replicas `j − 1` and `j` (whatever the swap strategy)
//! averaged over those ensembles. A shared ladder lets one calibration from the depth's
//! bootstrap serve all-replica reuse, and averages out the noise of single ensembles. Wider
//! gaps lower the acceptance, so the recursion settles where the neighbour acceptance
//! averages `α*`; the ladder is then frozen.
//!
//! Either way gaps are capped at `1/(K−1)` of the temperature range in the tuner's coordinate
//! ([`heat`]): with roughening only, beyond `a = 1` nothing changes, and on scenes whose
//! connections are mostly diffuse the acceptance stays above `α*` even at the cap.

use super::ensemble::Ensemble;
use crate::mcmc::Flattening;
use rayon::prelude::*;

/// Ensembles of a depth that tune its ladder in lockstep; the others take the result.
const TUNING_ENSEMBLES: usize = 8;

/// How a depth's ladder is tuned: from its bootstrap, or during a burn-in of that many
/// sweeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TuningMethod {
    Bootstrap,
    BurnIn(u64),
}

/// How a depth's ladder is tuned.
#[derive(Clone, Copy, Debug)]
pub struct Tuning {
    pub method: TuningMethod,
    /// Target neighbour acceptance.
    pub target: f64,
    /// The highest temperature the ladder may reach (1: roughening only).
    pub max_temperature: f32,
    /// How the temperatures flatten the target (which decides the candidates).
    pub flattening: Flattening,
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
pub fn tune_together(
    all: &mut [&mut Ensemble],
    sweeps: u64,
    tuning: Tuning,
    stop: &(dyn Fn() -> bool + Sync),
) -> Option<f64> {
    let (ensembles, rest) = all.split_at_mut(all.len().min(TUNING_ENSEMBLES));
    let mut ladder = Ladder::new(&ensembles[0].replicas.ladder(), tuning.target, tuning.max_temperature);
    let settled = sweeps - sweeps / 4;
    let (mut sum, mut n) = (0.0, 0u64);
    for sweep in 0..sweeps {
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

/// The temperatures a ladder tuned from the bootstrap chooses from: 0, then roughenings from
/// 0.004 growing by a quarter up to 1, then (up to `max_temperature`) powers spaced by an
/// eighth in the tuner's coordinate (`τ` growing by `e^{1/2}` each). With a power flattening
/// (`f^{1−τ}`) the exponents `β = 1 − τ` shrink by 15 % from one candidate to the next down
/// to 0.002, then 0 (`τ = 1`): the acceptance follows `β` geometrically, and a grid in `τ`
/// would leave `β` between 0.15 and 0 without a candidate.
pub fn candidate_temperatures(max_temperature: f32, flattening: Flattening) -> Vec<f32> {
    let mut grid = vec![0.0f32];
    if flattening == Flattening::Power {
        let mut beta = 0.85f32;
        while beta > 0.002 {
            grid.push(1.0 - beta);
            beta *= 0.85;
        }
        grid.push(1.0);
        return grid;
    }
    let mut a = 0.004f32;
    while a < 0.95 {
        grid.push(a);
        a *= 1.25;
    }
    grid.push(1.0);
    let top = heat(max_temperature);
    let mut h = 1.125;
    while h < top - 1e-6 {
        grid.push(temperature(h));
        h += 0.125;
    }
    if max_temperature > 1.0 {
        grid.push(max_temperature);
    }
    grid
}

/// The expected acceptance of exchanging the states of replicas with targets `f_i` and `f_j`
/// at equilibrium, estimated from the two targets' values over the same uniform samples
/// (`fi[n]`, `fj[n]`: sample `n`), pairs of distinct samples only; `None` when either target
/// is zero on every sample.
pub fn estimated_acceptance(fi: &[f32], fj: &[f32]) -> Option<f64> {
    let (sum_i, sum_j): (f64, f64) =
        fi.iter().zip(fj).fold((0.0, 0.0), |(a, b), (&x, &y)| (a + f64::from(x), b + f64::from(y)));
    let diagonal: f64 = fi.iter().zip(fj).map(|(&x, &y)| f64::from(x) * f64::from(y)).sum();
    let denominator = sum_i * sum_j - diagonal;
    if denominator.is_nan() || denominator <= 0.0 {
        return None;
    }
    // Only samples where both targets are positive contribute: the minimum is 0 otherwise.
    let mut both: Vec<(f64, f64, f64)> = fi
        .iter()
        .zip(fj)
        .filter(|&(&x, &y)| x > 0.0 && y > 0.0)
        .map(|(&x, &y)| (f64::from(y) / f64::from(x), f64::from(x), f64::from(y)))
        .collect();
    both.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Σ over ordered pairs x ≠ y of f_i(x) f_i(y) min(r_x, r_y): with r ascending, each pair
    // counts twice as f_j(x) f_i(y) for x before y.
    let mut after = both.iter().map(|b| b.1).sum::<f64>();
    let mut numerator = 0.0;
    for &(_, x_i, x_j) in &both {
        after -= x_i;
        numerator += 2.0 * x_j * after;
    }
    Some((numerator / denominator).clamp(0.0, 1.0))
}

/// A ladder of `replicas` rungs chosen from `grid` (temperatures, `grid[0] = 0`) given each
/// candidate's values over the bootstrap (`columns[g]`): rung after rung, the hottest
/// candidate whose estimated acceptance with the rung before is still at least `tuning.target`
/// (the next candidate when none is), gaps capped at `1/(K−1)` of the range in [`heat`].
/// Returns the rungs' grid indices and the mean estimated neighbour acceptance; `None` when
/// the depth's bootstrap saw no light or the grid has too few candidates.
pub fn ladder_from_bootstrap(
    columns: &[Vec<f32>],
    grid: &[f32],
    replicas: usize,
    tuning: Tuning,
) -> Option<(Vec<usize>, f64)> {
    let top = grid.len() - 1;
    let max_gap = heat(tuning.max_temperature) / (replicas - 1) as f64 + 1e-6;
    let mut rungs = vec![0usize];
    let mut acceptances = Vec::with_capacity(replicas - 1);
    for j in 1..replicas {
        let prev = rungs[j - 1];
        // Leave one candidate for each rung still to come.
        let last = (top + j + 1).saturating_sub(replicas);
        let reachable = (prev + 1..=last).take_while(|&g| heat(grid[g]) - heat(grid[prev]) <= max_gap);
        let mut chosen = None;
        for g in reachable {
            let alpha = estimated_acceptance(&columns[prev], &columns[g])?;
            if alpha < tuning.target && chosen.is_some() {
                break;
            }
            chosen = Some((g, alpha));
            if alpha < tuning.target {
                break;
            }
        }
        let (g, alpha) = match chosen {
            Some(c) => c,
            // No candidate within the gap cap (a coarse grid for many replicas): the next one,
            // if there is one.
            None if prev < top => (prev + 1, estimated_acceptance(&columns[prev], &columns[prev + 1])?),
            None => return None,
        };
        rungs.push(g);
        acceptances.push(alpha);
    }
    Some((rungs, acceptances.iter().sum::<f64>() / acceptances.len().max(1) as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    /// The sorted-sum estimate equals the plain double sum over pairs of distinct samples,
    /// with zeros in either target among the samples.
    #[test]
    fn estimated_acceptance_is_the_pairwise_sum() {
        let mut rng = Pcg32::new(3, 1);
        let mut draw = |zero: f32| -> Vec<f32> {
            (0..300).map(|_| if rng.next_f32() < zero { 0.0 } else { rng.next_f32().powi(3) * 10.0 }).collect()
        };
        for (zi, zj) in [(0.0, 0.0), (0.3, 0.1), (0.8, 0.5)] {
            let (fi, fj) = (draw(zi), draw(zj));
            let (mut num, mut den) = (0.0f64, 0.0f64);
            for x in 0..fi.len() {
                for y in 0..fi.len() {
                    if x != y {
                        let (a, b) = (f64::from(fi[x]) * f64::from(fj[y]), f64::from(fi[y]) * f64::from(fj[x]));
                        num += a.min(b);
                        den += a;
                    }
                }
            }
            let estimate = estimated_acceptance(&fi, &fj).unwrap();
            assert!((estimate - num / den).abs() < 1e-9, "{estimate} vs {}", num / den);
        }
        assert_eq!(estimated_acceptance(&[0.0, 0.0], &[1.0, 2.0]), None);
    }
}
