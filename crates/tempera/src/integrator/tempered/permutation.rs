//! Importance-sampled permutations: a Gibbs step over the assignment of the ensemble's states to
//! its replicas. Every permutation `σ` of `K` replicas is weighted by `W(σ) = Π_i f_i(u_σ(i))`
//! and one is drawn in proportion (computed in logs for range; `K!` grows fast, so `K` is kept
//! at most [`Permutation::MAX_REPLICAS`]).

use super::{CrossValues, SwapStats, SwapStrategy};
use crate::math::rng::Pcg32;

/// The strategy for ensembles of `K` replicas, with their `K!` permutations enumerated once.
#[derive(Clone, Debug)]
pub struct Permutation {
    perms: Vec<Vec<usize>>,
}

impl Permutation {
    pub const MAX_REPLICAS: usize = 8;

    /// For ensembles of `replicas` replicas (at most [`Self::MAX_REPLICAS`]).
    pub fn new(replicas: usize) -> Self {
        Self { perms: permutations(replicas.min(Self::MAX_REPLICAS)) }
    }
}

/// Every permutation of `0..k` in lexicographic order.
pub fn permutations(k: usize) -> Vec<Vec<usize>> {
    let mut out = Vec::new();
    let mut p: Vec<usize> = (0..k).collect();
    loop {
        out.push(p.clone());
        // Next permutation in lexicographic order.
        let Some(i) = (0..k.saturating_sub(1)).rev().find(|&i| p[i] < p[i + 1]) else { break };
        let j = (i + 1..k).rev().find(|&j| p[j] > p[i]).expect("a larger element exists");
        p.swap(i, j);
        p[i + 1..].reverse();
    }
    out
}

/// `ln W(σ)` for every permutation, `-∞` where a factor is zero.
pub fn log_weights(values: &mut dyn CrossValues, perms: &[Vec<usize>]) -> Vec<f64> {
    let k = values.replicas();
    let mut log_m = vec![f64::NEG_INFINITY; k * k];
    for i in 0..k {
        for j in 0..k {
            let f = values.f(i, j);
            if f > 0.0 && f.is_finite() {
                log_m[i * k + j] = f.ln();
            }
        }
    }
    perms.iter().map(|p| p.iter().enumerate().map(|(i, &j)| log_m[i * k + j]).sum()).collect()
}

impl SwapStrategy for Permutation {
    fn name(&self) -> &'static str {
        "permutation"
    }

    fn step(&self, values: &mut dyn CrossValues, rng: &mut Pcg32, stats: &mut SwapStats) -> Option<Vec<usize>> {
        let k = values.replicas();
        if !(2..=Self::MAX_REPLICAS).contains(&k) {
            return None;
        }
        stats.steps += 1;
        let rebuilt;
        let perms = if self.perms.first().is_some_and(|p| p.len() == k) {
            &self.perms
        } else {
            rebuilt = permutations(k);
            &rebuilt
        };
        let mut weights = log_weights(values, perms);
        let max = weights.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if max == f64::NEG_INFINITY {
            return None;
        }
        for w in &mut weights {
            *w = (*w - max).exp();
        }
        let total: f64 = weights.iter().sum();
        let mut u = rng.next_f64() * total;
        // Rounding may run past the end: fall back on the heaviest permutation.
        let mut chosen = weights.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)).map_or(0, |(i, _)| i);
        for (index, w) in weights.iter().enumerate() {
            if u < *w {
                chosen = index;
                break;
            }
            u -= w;
        }
        let sigma = perms[chosen].clone();
        let identity = sigma.iter().enumerate().all(|(i, &j)| i == j);
        stats.non_identity += u64::from(!identity);
        stats.main_changed += u64::from(sigma[0] != 0);
        (!identity).then_some(sigma)
    }
}
