//! A render's statistics as people and programs read them: what `tempera render --stats`
//! writes, what an experiment records per run and what its report reads back. The keys are
//! documented in the README.

use super::RenderOutput;
use crate::mcmc::{DepthStats, SwapStats};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// The statistics of one render.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct RunStats {
    pub integrator: String,
    pub seconds: f64,
    /// Pixel samples (per-pixel integrators) or main-chain mutations (Markov chains).
    pub samples: u64,
    pub rays: u64,
    pub rays_per_second: f64,
    pub invalid_samples: u64,
    pub cancelled: bool,
    pub mutations: u64,
    pub mutations_per_second: f64,
    /// Per path depth (or one row for all, PSSMLT): the Markov chains' statistics.
    pub depths: Vec<DepthRecord>,
    /// Processes (MPI ranks) the render was shared among; written only when more than one.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub ranks: usize,
    /// Per rank, the bytes it handed to the exchanges between ranks; empty for one process.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub bytes_sent: Vec<u64>,
}

fn one() -> usize {
    1
}

fn is_one(v: &usize) -> bool {
    *v == 1
}

/// Which depths a row covers: one, or all (PSSMLT's single set of chains), written `"all"`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Depth {
    At(usize),
    #[default]
    All,
}

impl std::fmt::Display for Depth {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Depth::At(k) => f.pad(&k.to_string()),
            Depth::All => f.pad("all"),
        }
    }
}

impl Serialize for Depth {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        match self {
            Depth::At(k) => s.serialize_u64(*k as u64),
            Depth::All => s.serialize_str("all"),
        }
    }
}

impl<'de> Deserialize<'de> for Depth {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            At(usize),
            Name(String),
        }
        match Raw::deserialize(d)? {
            Raw::At(k) => Ok(Depth::At(k)),
            Raw::Name(n) if n == "all" => Ok(Depth::All),
            Raw::Name(n) => Err(serde::de::Error::custom(format!("expected a depth or \"all\", got \"{n}\""))),
        }
    }
}

/// Acceptance rates of one depth's chains.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Acceptance {
    pub total: f64,
    pub large_step: f64,
    pub small_step: f64,
    /// Accepted proposals that changed the technique, per proposal.
    pub technique_change: f64,
    /// Reversible jumps between techniques (`--jumps`): accepted per jump proposed, and how
    /// many were proposed.
    #[serde(default)]
    pub jump: f64,
    #[serde(default)]
    pub jumps_proposed: u64,
    /// Film steps (`--film-steps`): accepted per film step proposed, and how many were
    /// proposed (among the small steps).
    #[serde(default)]
    pub film_step: f64,
    #[serde(default)]
    pub film_steps_proposed: u64,
    /// The acceptance of lens steps ([`crate::mcmc::lens`]) and how many were proposed (among
    /// the small steps; where a state has none, its step is a film step, counted as one).
    #[serde(default)]
    pub lens_step: f64,
    #[serde(default)]
    pub lens_steps_proposed: u64,
}

/// What the chains of one depth did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct DepthRecord {
    pub depth: Depth,
    pub b: f64,
    pub b_rel_se: f64,
    /// `b` as the bridge estimate gives it from the bootstrap, the large steps and the
    /// chains' states, and its relative standard error (absent where not estimated).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub b_bridge: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub b_bridge_rel_se: f64,
    /// Tempered MMLT with all-replica reuse: `b` as the hottest replica's normalisation times
    /// the bridge ratios down the ladder (absent where not estimated).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub b_ladder: f64,
    /// Where a per-pixel map shapes the target: the unshaped normalisation from the
    /// normaliser's samples and its relative standard error, and the chains' mean splat
    /// weight (luminance per unit of target), whose product with `b` is the chains' estimate of
    /// the same (absent where not shaped).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub b_plain: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub b_plain_rel_se: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub splat_weight: f64,
    pub bootstrap_samples: u64,
    pub large_step_samples: u64,
    /// Non-zero values among the bootstrap samples.
    #[serde(default)]
    pub bootstrap_nonzero: u64,
    /// The large-step acceptance the bootstrap predicts for the depth's chains (compare with
    /// `acceptance.large_step`, the realised one).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub large_step_estimate: f64,
    /// The depth was sampled independently (bidirectional path tracing restricted to it)
    /// instead of by chains: its bootstrap had too few non-zero values to start them apart.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub independent: bool,
    /// Samples of bidirectional path tracing combined with the chains (`--hybrid`), each
    /// covering every depth; all are counted in depth 0's row.
    #[serde(default, skip_serializing_if = "is_zero_u64")]
    pub hybrid_samples: u64,
    /// What one main-chain mutation of the depth was worth in independent samples of the
    /// chains' own density, measured from two halves of its chains (`--measure-efficiency`;
    /// absent without it, or where the halves could not tell).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub measured_efficiency: f64,
    /// The depth's share of the mutations after `--reallot-at` re-allotted them by the
    /// measured error (absent where they were not).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub reallotted_share: f64,
    /// What the pilot of `--hybrid auto` measured and chose (depth 0's row only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hybrid_pilot: Option<super::hybrid_pilot::HybridChoice>,
    /// Tempered MMLT's bootstrap-weighted independent acceptance, by which it chose between
    /// its chains and BDPT alone (`--bdpt-above`; depth 0's row only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub independent_acceptance: Option<f64>,
    /// What the pilot of `--importance-pilot` drew and chose (depth 0's row only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub importance_pilot: Option<super::importance_pilot::PilotChoice>,
    /// How unevenly the depth's light is spread over its paths: `sqrt(E[f²]/E[f]²)` over the
    /// bootstrap's non-zero values, capped at 8 (mutations may be allotted by `b` times it).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub spread: f64,
    pub mutations: u64,
    pub acceptance: Acceptance,
    pub invalid: u64,
    pub seconds: f64,
    /// Time spent preparing the depth before its first mutation (tempered MMLT: burn-in and
    /// calibration); absent when nothing was prepared.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub prepare_seconds: f64,
    /// Tempered MMLT: the ladder of temperatures.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ladder: Vec<f64>,
    /// Tempered MMLT with reuse: the weights' ratios `ρ_l ≈ b_l/b_0`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub replica_b_ratios: Vec<f64>,
    /// Tempered MMLT with reuse: each replica's refined `b_l`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub replica_b: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub swaps: Option<SwapRecord>,
}

/// Attempts and acceptances of one replica pair.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PairRecord {
    pub pair: [usize; 2],
    pub attempts: u64,
    pub accepted: u64,
}

/// What the swap steps of one depth did.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SwapRecord {
    pub steps: u64,
    /// Neighbouring pairs always, other pairs when attempted.
    pub swap_pairs: Vec<PairRecord>,
    pub neighbor_acceptance: f64,
    /// Equi-energy steps without two replicas in a ring.
    pub no_pair_rate: f64,
    /// Permutation steps other than the identity, and that gave replica 0 a new state.
    pub non_identity_rate: f64,
    pub main_changed_rate: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_zero_u64(v: &u64) -> bool {
    *v == 0
}

fn rate(accepted: u64, proposed: u64) -> f64 {
    if proposed == 0 { 0.0 } else { accepted as f64 / proposed as f64 }
}

/// The shortest decimal form of each `f32` (0.02, not 0.019999999552965164).
fn shortest(values: &[f32]) -> Vec<f64> {
    values.iter().map(|a| a.to_string().parse().unwrap_or(f64::from(*a))).collect()
}

impl SwapRecord {
    pub fn new(s: &SwapStats) -> Self {
        let k = s.replicas;
        let mut swap_pairs = Vec::new();
        for i in 0..k {
            for j in i + 1..k {
                let (attempts, accepted) = (s.attempts[i * k + j], s.accepted[i * k + j]);
                if attempts > 0 || j == i + 1 {
                    swap_pairs.push(PairRecord { pair: [i, j], attempts, accepted });
                }
            }
        }
        Self {
            steps: s.steps,
            swap_pairs,
            neighbor_acceptance: s.neighbor_acceptance(),
            no_pair_rate: rate(s.no_pair, s.steps),
            non_identity_rate: rate(s.non_identity, s.steps),
            main_changed_rate: rate(s.main_changed, s.steps),
        }
    }
}

impl DepthRecord {
    pub fn new(d: &DepthStats) -> Self {
        let proposed = d.large_steps_proposed + d.small_steps_proposed;
        Self {
            depth: if d.all_depths { Depth::All } else { Depth::At(d.depth) },
            b: d.b,
            b_rel_se: d.b_rel_se,
            b_bridge: d.b_bridge,
            b_bridge_rel_se: d.b_bridge_rel_se,
            b_ladder: d.b_ladder,
            b_plain: d.b_plain,
            b_plain_rel_se: d.b_plain_rel_se,
            splat_weight: if d.b_plain > 0.0 && d.mutations > 0 { d.splat_weight / d.mutations as f64 } else { 0.0 },
            bootstrap_samples: d.bootstrap_samples,
            large_step_samples: d.large_step_samples,
            bootstrap_nonzero: d.bootstrap_nonzero,
            large_step_estimate: d.large_step_estimate,
            independent: d.independent,
            hybrid_samples: d.hybrid_samples,
            measured_efficiency: d.measured_efficiency,
            reallotted_share: d.reallotted_share,
            hybrid_pilot: d.hybrid_choice,
            independent_acceptance: d.independent_acceptance,
            importance_pilot: d.importance_pilot,
            spread: d.spread,
            mutations: d.mutations,
            acceptance: Acceptance {
                total: d.acceptance(),
                large_step: rate(d.large_steps_accepted, d.large_steps_proposed),
                small_step: rate(d.small_steps_accepted, d.small_steps_proposed),
                technique_change: rate(d.technique_changes, proposed),
                jump: rate(d.jumps_accepted, d.jumps_proposed),
                jumps_proposed: d.jumps_proposed,
                film_step: rate(d.film_steps_accepted, d.film_steps_proposed),
                film_steps_proposed: d.film_steps_proposed,
                lens_step: rate(d.lens_steps_accepted, d.lens_steps_proposed),
                lens_steps_proposed: d.lens_steps_proposed,
            },
            invalid: d.invalid,
            seconds: d.seconds,
            prepare_seconds: d.prepare_seconds,
            ladder: shortest(&d.ladder),
            replica_b_ratios: shortest(&d.replica_b_ratios),
            replica_b: d.replica_b.clone(),
            swaps: d.swaps.as_ref().map(SwapRecord::new),
        }
    }
}

impl RunStats {
    /// The statistics of `out`, rendered by `integrator`.
    pub fn new(integrator: &str, out: &RenderOutput) -> Self {
        let s = &out.stats;
        let mutations: u64 = out.chains.iter().map(|d| d.mutations).sum();
        Self {
            integrator: integrator.to_owned(),
            seconds: s.seconds,
            samples: s.pixel_samples,
            rays: s.rays,
            rays_per_second: s.rays as f64 / s.seconds.max(1e-9),
            invalid_samples: s.invalid_samples,
            cancelled: s.cancelled,
            mutations,
            mutations_per_second: mutations as f64 / s.seconds.max(1e-9),
            depths: out.chains.iter().map(DepthRecord::new).collect(),
            ranks: 1,
            bytes_sent: Vec::new(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn depth_labels_round_trip() {
        for d in [Depth::At(3), Depth::All] {
            let text = serde_json::to_string(&d).unwrap();
            assert_eq!(serde_json::from_str::<Depth>(&text).unwrap(), d);
        }
        assert_eq!(serde_json::to_string(&Depth::All).unwrap(), "\"all\"");
        assert!(serde_json::from_str::<Depth>("\"some\"").is_err());
    }
}
