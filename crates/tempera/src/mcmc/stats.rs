//! Per-depth chain statistics, counted per chain and merged once (DESIGN §6.7).

/// What the chains of one path depth did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct DepthStats {
    pub depth: usize,
    /// The row covers every path depth (PSSMLT's single set of chains); `depth` is then 0.
    pub all_depths: bool,
    /// Normalisation `b_k` (mean target value) and its relative standard error.
    pub b: f64,
    pub b_rel_se: f64,
    pub bootstrap_samples: u64,
    pub large_step_samples: u64,
    pub mutations: u64,
    pub large_steps_proposed: u64,
    pub large_steps_accepted: u64,
    pub small_steps_proposed: u64,
    pub small_steps_accepted: u64,
    /// Accepted proposals that changed the technique `s`.
    pub technique_changes: u64,
    /// Proposals whose value was NaN, infinite or negative (counted as zero).
    pub invalid: u64,
    pub seconds: f64,
}

impl DepthStats {
    pub fn merge(&mut self, o: &DepthStats) {
        self.mutations += o.mutations;
        self.large_steps_proposed += o.large_steps_proposed;
        self.large_steps_accepted += o.large_steps_accepted;
        self.small_steps_proposed += o.small_steps_proposed;
        self.small_steps_accepted += o.small_steps_accepted;
        self.technique_changes += o.technique_changes;
        self.invalid += o.invalid;
        self.seconds += o.seconds;
    }

    pub fn acceptance(&self) -> f64 {
        let proposed = self.large_steps_proposed + self.small_steps_proposed;
        if proposed == 0 {
            0.0
        } else {
            (self.large_steps_accepted + self.small_steps_accepted) as f64 / proposed as f64
        }
    }
}
