//! Neighbour swapping: exchange the states of replicas `i` and `i + 1`, `i` uniform.

use super::{CrossValues, SwapStats, SwapStrategy, try_exchange};
use crate::math::rng::Pcg32;

#[derive(Clone, Copy, Debug, Default)]
pub struct Neighbor;

impl SwapStrategy for Neighbor {
    fn name(&self) -> &'static str {
        "neighbor"
    }

    fn step(&self, values: &mut dyn CrossValues, rng: &mut Pcg32, stats: &mut SwapStats) -> Option<Vec<usize>> {
        let k = values.replicas();
        if k < 2 {
            return None;
        }
        stats.steps += 1;
        let i = ((rng.next_f64() * (k - 1) as f64) as usize).min(k - 2);
        try_exchange(values, i, i + 1, rng, stats)
    }
}
