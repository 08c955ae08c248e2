//! Typed integrator settings, one type for every front end: `tempera render`'s flags and an
//! experiment file's methods build the same [`IntegratorSettings`], which [`create`] checks and
//! turns into an integrator. Every setting is optional; an absent one keeps the integrator's
//! default (or, for `maxdepth`, the scene's).

mod create;

use crate::bidir::Heuristic;
use crate::integrator::sppm::PhotonSampler;
use crate::integrator::tempered::Permutation;
pub use crate::mcmc::Flattening;
pub use create::create;
use serde::{Deserialize, Serialize};

/// The light-transport algorithms.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum IntegratorKind {
    Path,
    Bdpt,
    Mmlt,
    Pssmlt,
    Tempered,
    Sppm,
}

impl IntegratorKind {
    pub const ALL: [IntegratorKind; 6] = [
        IntegratorKind::Path,
        IntegratorKind::Bdpt,
        IntegratorKind::Mmlt,
        IntegratorKind::Pssmlt,
        IntegratorKind::Tempered,
        IntegratorKind::Sppm,
    ];

    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Bdpt => "bdpt",
            IntegratorKind::Mmlt => "mmlt",
            IntegratorKind::Pssmlt => "pssmlt",
            IntegratorKind::Tempered => "tempered",
            IntegratorKind::Sppm => "sppm",
        }
    }

    /// The integrator called `name` (Tempera's names, as [`Self::name`] gives them).
    pub fn from_name(name: &str) -> Option<IntegratorKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Markov-chain integrators (budgets in mutations per pixel, per-depth statistics).
    pub fn is_chain(self) -> bool {
        matches!(self, IntegratorKind::Mmlt | IntegratorKind::Pssmlt | IntegratorKind::Tempered)
    }
}

impl std::fmt::Display for IntegratorKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Which swap strategy tempered ensembles use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Swap {
    #[default]
    Neighbor,
    EquiEnergy,
    Permutation,
    /// No swaps: one chain per ensemble whose target is the mixture `Σ_l f_l/ρ_l` of the
    /// replicas' normalised targets (serial tempering with the temperature summed out), at
    /// the cost of one chain ([`crate::integrator::tempered::mixture`]).
    Mixture,
}

/// Which densities the MIS weights inside tempered targets use.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum TemperedMis {
    /// The scene's own (untempered) densities.
    #[default]
    Original,
    /// The roughened densities.
    Roughened,
}

/// How many BDPT samples MMLT and tempered MMLT combine with their chains: a fixed ratio
/// per main-chain mutation, or the split a short pilot measures ([`super::hybrid_pilot`]).
/// Written as a number or `"auto"`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Hybrid {
    Ratio(f64),
    Auto(AutoWord),
}

/// The word `auto`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum AutoWord {
    Auto,
}

impl Hybrid {
    /// The fixed ratio (0 with `auto`, whose ratio the pilot chooses).
    pub fn ratio(self) -> f64 {
        match self {
            Hybrid::Ratio(r) => r,
            Hybrid::Auto(_) => 0.0,
        }
    }

    pub fn is_auto(self) -> bool {
        matches!(self, Hybrid::Auto(_))
    }
}

impl std::str::FromStr for Hybrid {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s.eq_ignore_ascii_case("auto") {
            return Ok(Hybrid::Auto(AutoWord::Auto));
        }
        s.parse()
            .map(Hybrid::Ratio)
            .map_err(|_| format!("expected a number of samples per mutation or `auto`, got `{s}`"))
    }
}

/// How MMLT and tempered MMLT allot mutations to path depths.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum Allocation {
    /// In proportion to each depth's normalisation `b_k` (Hachisuka et al. 2014).
    #[default]
    Normalisation,
    /// In proportion to `b_k` times the spread of the depth's non-zero bootstrap values.
    Spread,
    /// Tempered MMLT: by `b_k` times spread at the depths whose bootstrap holds fewer non-zero
    /// values than `ensembles_below` (the depths with ensembles, and depth 0 where it is as
    /// sparse), by `b_k` alone, as MMLT allots, at the others.
    Sparse,
}

/// Which states of each replica splat when every replica contributes to the image.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum ReplicaSplats {
    /// Every mutation's proposal and current state, with their acceptance probabilities as
    /// weights (expected-value splatting, as an MMLT chain splats).
    #[default]
    Expected,
    /// The current state after each swap step.
    States,
}

/// How tempered MMLT tunes each depth's ladder (without a fixed ladder).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "clap", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum LadderTuning {
    /// From the depth's bootstrap, valued under candidate temperatures, before the first sweep.
    #[default]
    Bootstrap,
    /// During a burn-in of `burn_in` sweeps.
    BurnIn,
    /// Not at all: the default ladder as it is.
    None,
}

/// The settings of any integrator (those another integrator has are refused by [`create`]).
/// Absent settings are left out when serialised, so that a record of the settings given (an
/// experiment's cache keys) stays the same when new settings appear.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IntegratorSettings {
    /// Maximum number of scattering events per path (pbrt's `maxdepth`; absent: the scene's).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub maxdepth: Option<u32>,
    /// BDPT: the MIS heuristic.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mis: Option<Heuristic>,
    /// BDPT: also produce one image per strategy (an output option, not a setting of files).
    #[serde(skip)]
    pub strategy_images: bool,
    /// MMLT and tempered MMLT: also produce one image per path depth (an output option).
    #[serde(skip)]
    pub depth_images: bool,
    /// Markov-chain integrators: bootstrap samples (per depth for MMLT).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bootstrap: Option<usize>,
    /// Markov-chain integrators: independent chains (per depth for MMLT).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chains: Option<usize>,
    /// Markov-chain integrators: the probability of a large step.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub large_step: Option<f32>,
    /// Markov-chain integrators: the standard deviation of a small step in primary sample space
    /// (pbrt-v4's `sigma`, default 0.01).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sigma: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a chain proposes a reversible jump between
    /// the techniques of its path instead of a mutation (0: never).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub jumps: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a small step moves the film position alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub film_steps: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a small step moves the film position and
    /// keeps the path's second camera vertex (a lens step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lens_steps: Option<f32>,
    /// MMLT and tempered MMLT: how mutations are allotted to path depths.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub allocation: Option<Allocation>,
    /// MMLT and tempered MMLT: depths whose bootstrap has fewer non-zero values than this are
    /// sampled independently instead of by chains (0: none).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub independent_below: Option<usize>,
    /// MMLT and tempered MMLT: the share of the chains' rays spent on further samples of the
    /// depths' normalisers as the render goes on (0: the bootstrap's alone).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub normaliser_share: Option<f64>,
    /// MMLT: clamp each depth's target at this many times the mean of its bootstrap's
    /// non-zero values (0: never).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_clamp: Option<f64>,
    /// MMLT and tempered MMLT: samples per pixel of the BDPT pilot whose image shapes the
    /// chains' targets per pixel (0: no shaping).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance_pilot: Option<u32>,
    /// MMLT and tempered MMLT with `importance_pilot`: the floor of the per-pixel shaping as a
    /// fraction of the pilot image's mean.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance_floor: Option<f64>,
    /// MMLT and tempered MMLT with `importance_pilot`: the power of the per-pixel shape (1: the
    /// full shape, towards 0: MMLT's target).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance_power: Option<f64>,
    /// MMLT and tempered MMLT with `importance_pilot`: the share of a time budget the pilot
    /// takes at most.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance_share: Option<f64>,
    /// MMLT and tempered MMLT with `importance_pilot`: the chains are shaped only where the
    /// pilot's map predicts a relMSE below this ratio to MMLT's targets'.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub importance_below: Option<f64>,
    /// MMLT and tempered MMLT under a time budget: re-allot the mutations to the depths by
    /// their measured error after this share of the budget (0: never).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reallot_at: Option<f64>,
    /// MMLT: samples of bidirectional path tracing per main-chain mutation, combined with the
    /// chains by multiple importance sampling (0: the chains alone).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hybrid: Option<Hybrid>,
    /// MMLT and tempered MMLT with `hybrid`: what a main-chain mutation counts as, in
    /// independent samples at the same density, in the weights of the combination.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub chain_efficiency: Option<f64>,
    /// MMLT and tempered MMLT with `hybrid`: instead of `chain_efficiency`, weights that give
    /// the BDPT samples this share (in `(0, 1)`) of each depth's light.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hybrid_share: Option<f64>,
    /// MMLT and tempered MMLT: measure each depth's chain efficiency (what a mutation is worth
    /// in independent samples) from two halves of its chains, for the statistics.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub measure_efficiency: Option<bool>,
    /// MMLT and tempered MMLT: scale each depth's image (replica 0's layer) by the bridge
    /// estimate of its normalisation (`b_bridge`) instead of `b` where `b`'s reported relative
    /// error (`b_rel_se`) exceeds this and the bridge reports at most half of it
    /// ([`crate::mcmc::bridge::prefer`]; infinity: never).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bridge_above: Option<f64>,
    /// Tempered MMLT: render by bidirectional path tracing alone where the bootstrap's
    /// independent acceptance ([`crate::mcmc::acceptance::independent_acceptance`]) exceeds this
    /// (default [`crate::integrator::tempered::DEFAULT_BDPT_ABOVE`]; infinity: never).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bdpt_above: Option<f64>,
    /// Tempered MMLT: replicas per ensemble (1 is plain MMLT).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replicas: Option<usize>,
    /// Tempered MMLT: how replicas exchange states.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swap: Option<Swap>,
    /// Tempered MMLT: a fixed ladder of temperatures `τ_1 … τ_{K−1}` (in `[0, 1000]`,
    /// increasing but for leading zeros, which may repeat and add cold replicas: further chains
    /// of the scene's own target; up to 1 a roughening, beyond a power `1/τ` of the fully
    /// roughened target).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ladder: Option<Vec<f32>>,
    /// Tempered MMLT: the highest temperature the ladder tuning may reach (1: roughening only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub max_temperature: Option<f32>,
    /// Tempered MMLT: depths whose tuned ladder still swaps neighbours more often than this run
    /// plain MMLT chains.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse_above: Option<f64>,
    /// Tempered MMLT: depths whose tuned ladder swaps neighbours less often than this run plain
    /// MMLT chains.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub collapse_below: Option<f64>,
    /// Tempered MMLT: which densities the tempered targets' MIS weights use.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tempered_mis: Option<TemperedMis>,
    /// Tempered MMLT: how each depth's ladder is tuned.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tuning: Option<LadderTuning>,
    /// Tempered MMLT: the sweeps of a burn-in that tunes each depth's ladder (implies
    /// `tuning = "burn-in"`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub burn_in: Option<u64>,
    /// Tempered MMLT: the neighbour-swap acceptance the tuning aims at.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swap_target: Option<f64>,
    /// Tempered MMLT: every replica contributes to the image.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reuse_replicas: Option<bool>,
    /// Tempered MMLT: sweeps of the pilot that decides per depth whether ensembles pay for
    /// their replicas (0: ensembles at every depth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub pilot: Option<u64>,
    /// Tempered MMLT: ensembles only at the depths whose bootstrap holds fewer than this many
    /// non-zero values, plain MMLT chains at the others (0: ensembles at every depth).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ensembles_below: Option<usize>,
    /// Tempered MMLT: with reuse, which of each replica's states splat.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub replica_splats: Option<ReplicaSplats>,
    /// Tempered MMLT: how the hot replicas' targets are flattened.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub flattening: Option<Flattening>,
    /// Tempered MMLT: sweeps between swap steps.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub swap_every: Option<u64>,
    /// Tempered MMLT: sweeps between mutations of the replicas above replica 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hot_every: Option<u64>,
    /// Tempered MMLT: the large-step probability of the replicas above replica 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hot_large_step: Option<f32>,
    /// Tempered MMLT with `swap = mixture`: the weight `w` of the hotter targets in the
    /// mixture `f_0 + w Σ_{l ≥ 1} f_l/ρ_l`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hot_weight: Option<f64>,
    /// Tempered MMLT: the setup of Šik & Křivánek 2016 exactly — five replicas at every depth,
    /// a roughness-only ladder tuned for a neighbour acceptance of 0.234, replica 0 alone
    /// writing the image (the swap strategy stays free).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub paper: Option<bool>,
    /// SPPM: photons per iteration (absent: the scene's, else one per pixel).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photons: Option<u64>,
    /// SPPM: the initial search radius in scene units (absent: the scene's, else 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub radius: Option<f32>,
    /// SPPM: how photon paths are sampled (uniformly, or by Markov chains on visibility).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub photon_sampler: Option<PhotonSampler>,
}

fn check_range<T: PartialOrd + std::fmt::Display>(
    name: &str,
    value: Option<T>,
    range: std::ops::RangeInclusive<T>,
) -> Result<(), String> {
    match value {
        Some(v) if !range.contains(&v) => {
            Err(format!("{name} must lie in [{}, {}], not {v}", range.start(), range.end()))
        }
        _ => Ok(()),
    }
}

fn check_probability(name: &str, value: Option<f64>) -> Result<(), String> {
    match value {
        Some(p) if !(p > 0.0 && p <= 1.0) => Err(format!("{name} must be a probability in (0, 1], not {p}")),
        _ => Ok(()),
    }
}

impl IntegratorSettings {
    /// The settings given that `kind` does not have, by name.
    fn foreign(&self, kind: IntegratorKind) -> Vec<&'static str> {
        use IntegratorKind::*;
        let chain = kind.is_chain();
        let tempered = kind == Tempered;
        let given = [
            ("mis", self.mis.is_some(), kind == Bdpt),
            ("strategy_images", self.strategy_images, kind == Bdpt),
            ("depth_images", self.depth_images, kind == Mmlt || tempered),
            ("bootstrap", self.bootstrap.is_some(), chain),
            ("chains", self.chains.is_some(), chain),
            ("large_step", self.large_step.is_some(), chain),
            ("sigma", self.sigma.is_some(), chain),
            ("jumps", self.jumps.is_some(), kind == Mmlt || tempered),
            ("film_steps", self.film_steps.is_some(), kind == Mmlt || tempered),
            ("lens_steps", self.lens_steps.is_some(), kind == Mmlt || tempered),
            ("allocation", self.allocation.is_some(), kind == Mmlt || tempered),
            ("independent_below", self.independent_below.is_some(), kind == Mmlt || tempered),
            ("normaliser_share", self.normaliser_share.is_some(), kind == Mmlt || tempered),
            ("target_clamp", self.target_clamp.is_some(), kind == Mmlt),
            ("importance_pilot", self.importance_pilot.is_some(), kind == Mmlt || tempered),
            ("importance_floor", self.importance_floor.is_some(), kind == Mmlt || tempered),
            ("importance_power", self.importance_power.is_some(), kind == Mmlt || tempered),
            ("importance_share", self.importance_share.is_some(), kind == Mmlt || tempered),
            ("importance_below", self.importance_below.is_some(), kind == Mmlt || tempered),
            ("reallot_at", self.reallot_at.is_some(), kind == Mmlt || tempered),
            ("hybrid", self.hybrid.is_some(), kind == Mmlt || tempered),
            ("chain_efficiency", self.chain_efficiency.is_some(), kind == Mmlt || tempered),
            ("hybrid_share", self.hybrid_share.is_some(), kind == Mmlt || tempered),
            ("measure_efficiency", self.measure_efficiency.is_some(), kind == Mmlt || tempered),
            ("bridge_above", self.bridge_above.is_some(), kind == Mmlt || tempered),
            ("bdpt_above", self.bdpt_above.is_some(), tempered),
            ("replicas", self.replicas.is_some(), tempered),
            ("swap", self.swap.is_some(), tempered),
            ("ladder", self.ladder.is_some(), tempered),
            ("max_temperature", self.max_temperature.is_some(), tempered),
            ("collapse_above", self.collapse_above.is_some(), tempered),
            ("collapse_below", self.collapse_below.is_some(), tempered),
            ("tempered_mis", self.tempered_mis.is_some(), tempered),
            ("tuning", self.tuning.is_some(), tempered),
            ("burn_in", self.burn_in.is_some(), tempered),
            ("swap_target", self.swap_target.is_some(), tempered),
            ("reuse_replicas", self.reuse_replicas.is_some(), tempered),
            ("pilot", self.pilot.is_some(), tempered),
            ("ensembles_below", self.ensembles_below.is_some(), tempered),
            ("replica_splats", self.replica_splats.is_some(), tempered),
            ("flattening", self.flattening.is_some(), tempered),
            ("swap_every", self.swap_every.is_some(), tempered),
            ("hot_every", self.hot_every.is_some(), tempered),
            ("hot_large_step", self.hot_large_step.is_some(), tempered),
            ("hot_weight", self.hot_weight.is_some(), tempered),
            ("paper", self.paper.is_some(), tempered),
            ("photons", self.photons.is_some(), kind == Sppm),
            ("radius", self.radius.is_some(), kind == Sppm),
            ("photon_sampler", self.photon_sampler.is_some(), kind == Sppm),
        ];
        given.iter().filter(|(_, set, applies)| *set && !applies).map(|(name, ..)| *name).collect()
    }

    /// Checks every setting's range and the settings' agreement with each other and with
    /// `kind`; the error names the setting.
    pub fn validate(&self, kind: IntegratorKind) -> Result<(), String> {
        if let Some(name) = self.foreign(kind).first() {
            return Err(format!("{name} is not a setting of the {kind} integrator"));
        }
        if self.paper == Some(true) {
            let fixed = [
                ("replicas", self.replicas.is_some()),
                ("ladder", self.ladder.is_some()),
                ("reuse_replicas", self.reuse_replicas.is_some()),
                ("allocation", self.allocation.is_some()),
                ("independent_below", self.independent_below.is_some()),
                ("normaliser_share", self.normaliser_share.is_some()),
                ("max_temperature", self.max_temperature.is_some()),
                ("flattening", self.flattening.is_some()),
                ("collapse_above", self.collapse_above.is_some()),
                ("collapse_below", self.collapse_below.is_some()),
                ("pilot", self.pilot.is_some()),
                ("ensembles_below", self.ensembles_below.is_some()),
                ("swap_target", self.swap_target.is_some()),
                ("bdpt_above", self.bdpt_above.is_some()),
                ("jumps", self.jumps.is_some()),
                ("film_steps", self.film_steps.is_some()),
                ("lens_steps", self.lens_steps.is_some()),
            ];
            if let Some((name, _)) = fixed.iter().find(|f| f.1) {
                return Err(format!("the paper's setup fixes {name}; give one or the other"));
            }
        }
        check_range("maxdepth", self.maxdepth, 0..=100_000)?;
        check_range("bootstrap", self.bootstrap, 1..=100_000_000)?;
        check_range("chains", self.chains, 1..=1_000_000)?;
        check_range("independent_below", self.independent_below, 0..=100_000_000)?;
        check_probability("large_step", self.large_step.map(f64::from))?;
        check_probability("hot_large_step", self.hot_large_step.map(f64::from))?;
        for (name, p) in [("jumps", self.jumps), ("film_steps", self.film_steps), ("lens_steps", self.lens_steps)] {
            if let Some(p) = p.filter(|p| !(0.0..=1.0).contains(p)) {
                return Err(format!("{name} must be a probability in [0, 1], not {p}"));
            }
        }
        if let Some(sigma) = self.sigma.filter(|s| !(*s > 0.0 && *s <= 1.0)) {
            return Err(format!("sigma must lie in (0, 1], not {sigma}"));
        }
        check_probability("hot_weight", self.hot_weight)?;
        check_range("replicas", self.replicas, 1..=32)?;
        check_range("burn_in", self.burn_in, 1..=10_000_000)?;
        if self.burn_in.is_some() && self.tuning.is_some_and(|t| t != LadderTuning::BurnIn) {
            return Err("burn_in is the length of the burn-in tuning; it needs tuning = burn-in".into());
        }
        check_probability("swap_target", self.swap_target)?;
        check_probability("collapse_above", self.collapse_above)?;
        check_probability("collapse_below", self.collapse_below)?;
        check_range("normaliser_share", self.normaliser_share, 0.0..=1.0)?;
        check_range("reallot_at", self.reallot_at, 0.0..=1.0)?;
        check_range("bridge_above", self.bridge_above, 0.0..=f64::INFINITY)?;
        check_range("bdpt_above", self.bdpt_above, 0.0..=f64::INFINITY)?;
        if self.hybrid.is_some_and(|r| !(0.0..=100.0).contains(&r.ratio())) {
            return Err("hybrid must be between 0 and 100 samples per mutation".into());
        }
        if self.hybrid_share.is_some_and(|s| !(s > 0.0 && s < 1.0)) {
            return Err("hybrid_share must be above 0 and below 1".into());
        }
        if self.chain_efficiency.is_some_and(|e| !(e > 0.0 && e <= 100.0)) {
            return Err("chain_efficiency must be above 0 and at most 100".into());
        }
        if self.target_clamp.is_some_and(|c| !(c == 0.0 || (1.0..=1e9).contains(&c))) {
            return Err("target_clamp must be 0 (never) or between 1 and 1e9".into());
        }
        check_range("importance_pilot", self.importance_pilot, 0..=1024)?;
        if self.importance_floor.is_some_and(|f| !(f > 0.0 && f <= 100.0)) {
            return Err("importance_floor must be above 0 and at most 100".into());
        }
        if self.importance_power.is_some_and(|g| !(g > 0.0 && g <= 2.0)) {
            return Err("importance_power must be above 0 and at most 2".into());
        }
        if self.importance_share.is_some_and(|f| !(f > 0.0 && f <= 0.5)) {
            return Err("importance_share must be above 0 and at most 0.5".into());
        }
        if self.importance_below.is_some_and(|f| !(f > 0.0 && f <= 1000.0)) {
            return Err("importance_below must be above 0 and at most 1000".into());
        }
        check_range("max_temperature", self.max_temperature, 1.0..=1000.0)?;
        if self.flattening == Some(Flattening::Power) && self.max_temperature.is_some_and(|t| t > 1.0) {
            return Err(
                "a power flattening reaches the uniform target at temperature 1; max_temperature must be 1".into()
            );
        }
        check_range("swap_every", self.swap_every, 1..=1_000_000)?;
        check_range("hot_every", self.hot_every, 1..=1_000_000)?;
        check_range("pilot", self.pilot, 0..=10_000_000)?;
        check_range("ensembles_below", self.ensembles_below, 0..=100_000_000)?;
        check_range("photons", self.photons, 1..=1_000_000_000)?;
        if let Some(r) = self.radius
            && !(r.is_finite() && r > 0.0)
        {
            return Err(format!("radius must be positive, not {r}"));
        }
        if let Some(ladder) = &self.ladder {
            if ladder.is_empty() || ladder.iter().any(|v| !v.is_finite() || *v < 0.0 || *v > 1000.0) {
                return Err(format!("ladder values must lie in [0, 1000], not {ladder:?}"));
            }
            // Equal temperatures are exact (a swap between them is always accepted); only
            // cold replicas (τ = 0) may repeat, hot rungs must increase.
            if ladder.windows(2).any(|w| w[1] < w[0] || (w[1] == w[0] && w[0] > 0.0)) {
                return Err(format!("ladder values must increase (only zeros may repeat), not {ladder:?}"));
            }
            // A ladder fixes the number of replicas; both given must agree.
            if let Some(r) = self.replicas
                && r != ladder.len() + 1
            {
                return Err(format!(
                    "the ladder gives {} values, so replicas must be {} (it is {r})",
                    ladder.len(),
                    ladder.len() + 1
                ));
            }
        }
        if self.swap == Some(Swap::Permutation) && self.replica_count() > Some(Permutation::MAX_REPLICAS) {
            return Err(format!(
                "the permutation swap enumerates all K! permutations: use at most {} replicas",
                Permutation::MAX_REPLICAS
            ));
        }
        if self.hot_weight.is_some() && self.swap != Some(Swap::Mixture) {
            return Err("hot_weight weighs the hotter targets of the mixture: it needs swap = mixture".into());
        }
        if self.swap == Some(Swap::Mixture) && self.reuse_replicas == Some(false) {
            return Err("the mixture target reuses every replica by construction: drop --no-reuse-replicas".into());
        }
        if self.allocation == Some(Allocation::Sparse) && kind != IntegratorKind::Tempered {
            return Err("allocation sparse follows tempered MMLT's ensembles_below: use normalisation or spread".into());
        }
        Ok(())
    }

    /// The replicas the settings ask for, if they say.
    fn replica_count(&self) -> Option<usize> {
        self.replicas.or(self.ladder.as_ref().map(|l| l.len() + 1))
    }
}
