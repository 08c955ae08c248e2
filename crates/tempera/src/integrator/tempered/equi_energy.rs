//! Equi-energy moves (Baragatti, Grimaud & Pommeret 2012): the main target's value `f_0(u)` of
//! each replica's state puts it into a ring: ring 0 holds zero values, rings `1 … R` split
//! `[lo, hi]` evenly in `log f_0` (values outside are clamped into the end rings). A ring with at
//! least two replicas is chosen uniformly, two of its replicas uniformly, and they exchange
//! states with the usual swap acceptance. The bounds come from quantiles of the bootstrap.

use super::{CrossValues, SwapStats, SwapStrategy, try_exchange};
use crate::math::rng::Pcg32;

#[derive(Clone, Copy, Debug)]
pub struct EquiEnergy {
    pub lo: f64,
    pub hi: f64,
    /// Rings of positive values.
    pub rings: usize,
}

impl EquiEnergy {
    /// Rings spanning `[lo, hi]` (both positive; `hi > lo` is enforced).
    pub fn new(lo: f64, hi: f64, rings: usize) -> Self {
        let lo = if lo > 0.0 && lo.is_finite() { lo } else { 1e-12 };
        let hi = if hi > lo && hi.is_finite() { hi } else { lo * 10.0 };
        Self { lo, hi, rings: rings.max(1) }
    }

    /// Bounds from the 5th and 95th percentiles of the positive values of a bootstrap.
    pub fn from_samples(values: &[f32], rings: usize) -> Self {
        let mut positive: Vec<f64> = values.iter().filter(|&&v| v > 0.0).map(|&v| f64::from(v)).collect();
        positive.sort_by(f64::total_cmp);
        if positive.is_empty() {
            return Self::new(1e-12, 1.0, rings);
        }
        let at = |q: f64| positive[((positive.len() - 1) as f64 * q).round() as usize];
        Self::new(at(0.05), at(0.95), rings)
    }

    /// The ring of a state whose main-target value is `f0`.
    pub fn ring(&self, f0: f64) -> usize {
        if f0.is_nan() || f0 <= 0.0 {
            return 0;
        }
        let x = (f0 / self.lo).ln() / (self.hi / self.lo).ln();
        1 + ((x * self.rings as f64).floor().max(0.0) as usize).min(self.rings - 1)
    }
}

impl SwapStrategy for EquiEnergy {
    fn name(&self) -> &'static str {
        "equi-energy"
    }

    fn step(&self, values: &mut dyn CrossValues, rng: &mut Pcg32, stats: &mut SwapStats) -> Option<Vec<usize>> {
        let k = values.replicas();
        if k < 2 {
            return None;
        }
        stats.steps += 1;
        let rings: Vec<usize> = (0..k).map(|j| self.ring(values.f(0, j))).collect();
        let mut members = vec![Vec::new(); self.rings + 1];
        for (j, &r) in rings.iter().enumerate() {
            members[r].push(j);
        }
        let candidates: Vec<&Vec<usize>> = members.iter().filter(|m| m.len() >= 2).collect();
        if candidates.is_empty() {
            stats.no_pair += 1;
            return None;
        }
        let pick = |n: usize, rng: &mut Pcg32| ((rng.next_f64() * n as f64) as usize).min(n - 1);
        let ring = candidates[pick(candidates.len(), rng)];
        let a = pick(ring.len(), rng);
        let mut b = pick(ring.len() - 1, rng);
        if b >= a {
            b += 1;
        }
        try_exchange(values, ring[a], ring[b], rng, stats)
    }
}
