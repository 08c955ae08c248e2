//! The replicas of one ensemble: one chain per rung of the ladder, each with its tempered
//! target, and the cross-evaluations `f_i(u_j)` the swap kernels need (computed on demand and
//! without rays, from the states' cached paths).

use super::CrossValues;
use crate::mcmc::{Chain, TemperedState, TemperedTarget};

pub struct Replicas<'a> {
    pub chains: Vec<Chain<TemperedState>>,
    /// Replica `j`'s target: the scene roughened by the ladder's `a_j` (`a_0 = 0`).
    pub targets: Vec<TemperedTarget<'a>>,
}

/// Lazily computed cross-evaluations `f_i(u_j)` of the replicas' current states.
pub struct Cross<'r, 'a> {
    replicas: &'r mut Replicas<'a>,
    cache: &'r mut Vec<Option<f64>>,
}

impl CrossValues for Cross<'_, '_> {
    fn replicas(&self) -> usize {
        self.replicas.len()
    }

    fn f(&mut self, i: usize, j: usize) -> f64 {
        let k = self.replicas();
        if let Some(v) = self.cache[i * k + j] {
            return v;
        }
        let r = &mut *self.replicas;
        let v = if i == j {
            f64::from(r.chains[j].state().value)
        } else {
            f64::from(r.chains[j].state_mut().value_under(i, &r.targets))
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

impl<'a> Replicas<'a> {
    pub fn len(&self) -> usize {
        self.chains.len()
    }

    pub fn is_empty(&self) -> bool {
        self.chains.is_empty()
    }

    /// The temperature of every replica, `τ_0 = 0` first.
    pub fn ladder(&self) -> Vec<f32> {
        self.targets.iter().map(TemperedTarget::temperature).collect()
    }

    /// Cross-evaluations of the current states, computed on demand, in `cache` (reused
    /// storage).
    pub fn cross<'r>(&'r mut self, cache: &'r mut Vec<Option<f64>>) -> Cross<'r, 'a> {
        let k = self.len();
        cache.clear();
        cache.resize(k * k, None);
        Cross { replicas: self, cache }
    }

    /// Gives replica `i` the state replica `sigma[i]` held; replicas that receive another state
    /// re-value it under their target.
    pub fn permute(&mut self, sigma: &[usize]) {
        apply_permutation(&mut self.chains, sigma, |r, i, j| {
            let (lo, hi) = r.split_at_mut(j.max(i));
            lo[i.min(j)].exchange(&mut hi[0]);
        });
        for (i, &from) in sigma.iter().enumerate() {
            if from != i {
                self.revalue(i);
            }
        }
    }

    /// Values replica `j`'s state afresh under its own target (after its state or its target
    /// changed).
    fn revalue(&mut self, j: usize) {
        let state = self.chains[j].state_mut();
        state.value = state.value_under(j, &self.targets);
    }

    /// One mutation per replica, splatting nothing.
    pub fn sweep_without_splats(&mut self) {
        for (chain, target) in self.chains.iter_mut().zip(&self.targets) {
            chain.mutate(target, None);
        }
    }

    /// Sets the temperatures of replicas `1 …` to `ladder` and re-values their states.
    pub fn set_ladder(&mut self, ladder: &[f32]) {
        // Values under the old temperatures are stale.
        for chain in &mut self.chains {
            chain.state_mut().cross.clear();
        }
        for (j, &tau) in ladder.iter().enumerate() {
            self.targets[j + 1].set_temperature(tau);
            self.revalue(j + 1);
        }
    }

    /// Keeps replica 0 alone: the ensemble becomes a plain MMLT chain (which keeps the count of
    /// the rays the others traced).
    pub fn collapse(&mut self) {
        let dropped: u64 = self.chains.iter().skip(1).map(Chain::rays).sum();
        self.chains.truncate(1);
        self.targets.truncate(1);
        if let Some(chain) = self.chains.first_mut() {
            chain.count_rays(dropped);
        }
    }
}
