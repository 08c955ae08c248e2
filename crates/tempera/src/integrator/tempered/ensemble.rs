//! One ensemble of replicas of a path depth: sweeps of one mutation per replica, each followed
//! by a swap step. Replica 0 holds the scene's BSDFs and alone splats; its mutations are the
//! ensemble's mutations in budgets and statistics.

use super::{CrossValues, SwapStrategy};
use crate::film::SplatBuffer;
use crate::integrator::mmlt::Walker;
use crate::math::rng::Pcg32;
use crate::mcmc::{Chain, DepthStats, SwapStats, TemperedState, TemperedTarget};

pub struct Ensemble<'a> {
    pub replicas: Vec<Chain<TemperedState>>,
    pub targets: Vec<TemperedTarget<'a>>,
    pub strategy: Box<dyn SwapStrategy>,
    pub rng: Pcg32,
    pub swaps: SwapStats,
}

/// Lazily computed cross-evaluations `f_i(u_j)` of an ensemble.
struct Cross<'e, 'a> {
    ensemble: &'e mut Ensemble<'a>,
    cache: Vec<Option<f64>>,
}

impl CrossValues for Cross<'_, '_> {
    fn replicas(&self) -> usize {
        self.ensemble.replicas.len()
    }

    fn f(&mut self, i: usize, j: usize) -> f64 {
        let k = self.replicas();
        if let Some(v) = self.cache[i * k + j] {
            return v;
        }
        let e = &mut *self.ensemble;
        let v = if i == j {
            f64::from(e.replicas[j].state().value)
        } else {
            f64::from(e.targets[i].value_of(e.replicas[j].state_mut()))
        };
        self.cache[i * k + j] = Some(v);
        v
    }
}

/// Applies `sigma` in place: afterwards `items[i]` holds what `items[sigma[i]]` held.
pub fn apply_permutation<T>(items: &mut [T], sigma: &[usize], exchange: impl Fn(&mut [T], usize, usize)) {
    for i in 0..sigma.len() {
        let mut j = sigma[i];
        while j < i {
            j = sigma[j];
        }
        if j != i {
            exchange(items, i, j);
        }
    }
}

impl Ensemble<'_> {
    /// One swap step; replicas that receive another state re-value it under their target.
    fn swap(&mut self) {
        let k = self.replicas.len();
        if k < 2 {
            return;
        }
        let mut rng = self.rng.clone();
        let mut swaps = std::mem::take(&mut self.swaps);
        // The strategy is moved out while the cross-evaluations borrow the ensemble.
        let strategy = std::mem::replace(&mut self.strategy, Box::new(super::Neighbor));
        let sigma = {
            let mut cross = Cross { ensemble: self, cache: vec![None; k * k] };
            strategy.step(&mut cross, &mut rng, &mut swaps)
        };
        self.strategy = strategy;
        self.rng = rng;
        self.swaps = swaps;
        let Some(sigma) = sigma else { return };
        apply_permutation(&mut self.replicas, &sigma, |r, i, j| {
            let (lo, hi) = r.split_at_mut(j.max(i));
            lo[i.min(j)].exchange(&mut hi[0]);
        });
        for (i, &from) in sigma.iter().enumerate() {
            if from != i {
                let value = self.targets[i].value_of(self.replicas[i].state_mut());
                self.replicas[i].state_mut().value = value;
            }
        }
    }
}

impl Walker for Ensemble<'_> {
    fn run(&mut self, mutations: u64, splats: &mut SplatBuffer, stop: &dyn Fn() -> bool) -> u64 {
        if self.replicas.len() == 1 {
            return self.replicas[0].run(&self.targets[0], mutations, Some(splats), stop);
        }
        let never = || false;
        let mut done = 0;
        while done < mutations {
            if done % 256 == 0 && stop() {
                break;
            }
            for (j, (chain, target)) in self.replicas.iter_mut().zip(&self.targets).enumerate() {
                chain.run(target, 1, if j == 0 { Some(&mut *splats) } else { None }, &never);
            }
            self.swap();
            done += 1;
        }
        done
    }

    fn stats(&self) -> DepthStats {
        let mut stats = self.replicas[0].stats.clone();
        stats.ladder = self.targets.iter().map(|t| t.temper.a).collect();
        stats.swaps = (self.replicas.len() > 1).then(|| self.swaps.clone());
        stats
    }

    fn large(&self) -> (f64, f64, u64) {
        self.replicas[0].large
    }

    fn rays(&self) -> u64 {
        self.replicas.iter().map(|r| r.rays).sum()
    }
}
