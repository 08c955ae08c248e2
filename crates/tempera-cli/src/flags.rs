//! Command-line flags that describe a render, and the parsers behind them. The integrator's
//! flags build the core's typed [`IntegratorSettings`], the same type an experiment file's
//! methods deserialise into, so both are checked by the same code.

use clap::Args;
use tempera::bidir::Heuristic;
use tempera::integrator::{
    Allocation, Flattening, IntegratorSettings, LadderTuning, PhotonSampler, ReplicaSplats, Swap, TemperedMis,
};

/// The flags of `tempera render` that set up the integrator. They are parsed as plain values;
/// their ranges and their agreement with each other and with the integrator are checked where
/// experiment files are checked too ([`IntegratorSettings::validate`]).
#[derive(Args, Debug, Default)]
pub struct IntegratorFlags {
    /// Maximum number of scattering events per path (pbrt's maxdepth; default: the scene's).
    #[arg(long)]
    pub maxdepth: Option<u32>,
    /// BDPT: multiple importance sampling heuristic (default: power).
    #[arg(long, value_enum)]
    pub mis: Option<Heuristic>,
    /// Markov-chain integrators: bootstrap samples (per path depth for MMLT).
    #[arg(long)]
    pub bootstrap: Option<usize>,
    /// Markov-chain integrators: independent chains (per path depth for MMLT).
    #[arg(long)]
    pub chains: Option<usize>,
    /// Markov-chain integrators: probability of a large step.
    #[arg(long)]
    pub large_step: Option<f32>,
    /// Markov-chain integrators: standard deviation of a small step in primary sample space
    /// (default 0.01, as pbrt-v4's MLT).
    #[arg(long)]
    pub sigma: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a chain proposes a reversible jump between
    /// the bidirectional techniques of its path (the path kept, its sampling inverted) instead
    /// of a mutation (MMLT's default 0: never; tempered MMLT's 0.05).
    #[arg(long)]
    pub jumps: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a small step is a film step, which moves
    /// the film position alone by 2 % of the film and keeps every other number of the state
    /// (MMLT's default 0: never; tempered MMLT's 0.3).
    #[arg(long)]
    pub film_steps: Option<f32>,
    /// MMLT and tempered MMLT: the probability that a small step is a lens step, which moves
    /// the film position as a film step does and re-aims the first camera vertex at the path's
    /// second, keeping the rest of the path (MMLT's default 0: never; tempered MMLT's 0.3, on
    /// top of its film steps' 0.3). Film and lens steps share the
    /// small steps: a lens step takes what the film steps leave of the probability.
    #[arg(long)]
    pub lens_steps: Option<f32>,
    /// MMLT and tempered MMLT: how mutations are allotted to path depths: in proportion to their
    /// normalisation b_k (MMLT's default), to b_k times the spread of their light over their
    /// paths, or (tempered MMLT only, its default) by b_k times spread at the depths with
    /// ensembles and by b_k elsewhere.
    #[arg(long, value_enum)]
    pub allocation: Option<Allocation>,
    /// MMLT and tempered MMLT: sample the depths whose bootstrap has fewer than N non-zero
    /// values independently (bidirectional path tracing restricted to the depth) instead of by
    /// chains that would all start from those few states (MMLT's default 0: never; tempered
    /// MMLT's 40)
    #[arg(long, value_name = "N")]
    pub independent_below: Option<usize>,
    /// MMLT and tempered MMLT: the share of the chains' rays spent on further samples of the
    /// depths' normalisers (every strategy of a path at once) as the render goes on, split
    /// evenly over the depths (default 0.1; 0: the bootstrap's samples alone)
    #[arg(long, value_name = "SHARE")]
    pub normaliser_share: Option<f64>,
    /// MMLT: clamp each depth's target at F times the mean of its bootstrap's non-zero values;
    /// a clamped state splats its whole contribution, so a rare very bright path weighs on its
    /// own pixels instead of on its depth's normalisation (default 0: never)
    #[arg(long, value_name = "F")]
    pub target_clamp: Option<f64>,
    /// MMLT and tempered MMLT: shape the chains' targets per pixel by a pilot of N samples per
    /// pixel of bidirectional path tracing, so that dim pixels get about as many mutations as
    /// bright ones and the image's relative error evens out, where the pilot predicts a large
    /// gain (--importance-below) (default: 0, MMLT's target, for MMLT; 16 for tempered MMLT)
    #[arg(long, value_name = "N")]
    pub importance_pilot: Option<u32>,
    /// MMLT and tempered MMLT with --importance-pilot: pixels darker than F times the pilot
    /// image's mean get fewer mutations, in proportion to their brightness (default 0.5)
    #[arg(long, value_name = "F")]
    pub importance_floor: Option<f64>,
    /// MMLT and tempered MMLT with --importance-pilot: the power of the shape, 1 for dim and
    /// bright pixels' getting about as many mutations, towards 0 MMLT's share by brightness
    /// (default 0.75)
    #[arg(long, value_name = "G")]
    pub importance_power: Option<f64>,
    /// MMLT and tempered MMLT under a time budget: after this share of it, re-allot the
    /// mutations to the path depths by the error their chains measured, instead of by b_k
    /// alone, where they have made 160 mutations per pixel by then (default: 0, never, for
    /// MMLT; 0.25 for tempered MMLT)
    #[arg(long, value_name = "S")]
    pub reallot_at: Option<f64>,
    /// MMLT and tempered MMLT with --importance-pilot under a time budget: the pilot stops
    /// before it takes more than this share of the time (default 0.05; at least one sample per
    /// pixel)
    #[arg(long, value_name = "S")]
    pub importance_share: Option<f64>,
    /// MMLT and tempered MMLT with --importance-pilot: shape the chains only where the pilot's
    /// map predicts a relMSE below R times that of MMLT's targets (default 0.665; any R above 1
    /// nearly always shapes)
    #[arg(long, value_name = "R")]
    pub importance_below: Option<f64>,
    /// MMLT and tempered MMLT: R samples of bidirectional path tracing per main-chain
    /// mutation, combined with the chains by multiple importance sampling: the samples carry
    /// the dim parts of the image, the chains the bright, hard-to-find paths (default 0: the
    /// chains alone); `auto`: a short pilot chooses BDPT alone, the chains alone or their
    /// combination, and its split and weights
    #[arg(long, value_name = "R|auto")]
    pub hybrid: Option<tempera::integrator::Hybrid>,
    /// MMLT and tempered MMLT with --hybrid: what a main-chain mutation counts as, in
    /// independent samples at the same density, in the combination's weights (default 0.01:
    /// a chain's successive states are correlated)
    #[arg(long, value_name = "E")]
    pub chain_efficiency: Option<f64>,
    /// MMLT and tempered MMLT with --hybrid: instead of --chain-efficiency, weights that give
    /// the BDPT samples the share S (between 0 and 1) of each depth's light
    #[arg(long, value_name = "S")]
    pub hybrid_share: Option<f64>,
    /// MMLT and tempered MMLT: measure what a mutation of each depth's chains is worth in
    /// independent samples, from two halves of the chains (reported by --stats as
    /// `measured_efficiency`; the depths' splat buffers take twice the memory)
    #[arg(long)]
    pub measure_efficiency: bool,
    /// MMLT and tempered MMLT: scale each depth's share of the image by the bridge estimate of
    /// its normalisation (`b_bridge` in --stats) instead of `b` where `b`'s reported relative
    /// error (`b_rel_se`) exceeds E and the bridge reports at most half of it (inf: never)
    #[arg(long, value_name = "E")]
    pub bridge_above: Option<f64>,
    /// Tempered MMLT: render by bidirectional path tracing alone where the bootstrap's
    /// independent acceptance (the large steps' acceptance at equilibrium over the depths
    /// k ≥ 1, weighted by b_k; `independent_acceptance` in --stats) exceeds A: the scene's
    /// light is found as well by independent samples, and BDPT wins (default 0.03; inf: never;
    /// never with --hybrid, --depth-images or --measure-efficiency, which are the chains' own)
    #[arg(long, value_name = "A")]
    pub bdpt_above: Option<f64>,
    /// Tempered MMLT: replicas per ensemble (default 2; 1 is plain MMLT).
    #[arg(long)]
    pub replicas: Option<usize>,
    /// Tempered MMLT: how replicas exchange states (default: neighbor).
    #[arg(long, value_enum)]
    pub swap: Option<Swap>,
    /// Tempered MMLT: fixed ladder of temperatures t1,t2,… of replicas 1 … K−1 (increasing,
    /// in [0, 1000]; up to 1 a roughening of the connection vertices, beyond a power 1/t of the
    /// fully roughened target; leading zeros, which may repeat, add cold replicas).
    #[arg(long, value_delimiter = ',')]
    pub ladder: Option<Vec<f32>>,
    /// Tempered MMLT: the highest temperature the ladder tuning may reach (1: roughening only).
    #[arg(long)]
    pub max_temperature: Option<f32>,
    /// Tempered MMLT: depths whose tuned ladder still swaps neighbours more often than this
    /// run plain MMLT chains.
    #[arg(long)]
    pub collapse_above: Option<f64>,
    /// Tempered MMLT: depths whose tuned ladder swaps neighbours less often than this run
    /// plain MMLT chains.
    #[arg(long)]
    pub collapse_below: Option<f64>,
    /// Tempered MMLT: sweeps of the pilot that decides, per depth, whether ensembles pay for
    /// their replicas: half the depth's walkers run as ensembles, as many as plain MMLT
    /// chains, and the depth keeps the kind with the lower error per ray (0: ensembles at
    /// every depth).
    #[arg(long)]
    pub pilot: Option<u64>,
    /// Tempered MMLT: ensembles only at the depths whose bootstrap holds fewer than N non-zero
    /// values (a few start states for all their chains); plain MMLT chains at the others (0:
    /// ensembles at every depth).
    #[arg(long, value_name = "N")]
    pub ensembles_below: Option<usize>,
    /// Tempered MMLT: how each depth's ladder is tuned (default: bootstrap, before the first
    /// mutation; ignored with --ladder).
    #[arg(long, value_enum)]
    pub tuning: Option<LadderTuning>,
    /// Tempered MMLT: sweeps of the burn-in that tunes each depth's ladder (implies
    /// --tuning burn-in; default 500).
    #[arg(long)]
    pub burn_in: Option<u64>,
    /// Tempered MMLT: neighbour-swap acceptance the ladder tuning aims at.
    #[arg(long)]
    pub swap_target: Option<f64>,
    /// Tempered MMLT: MIS weights of tempered replicas from the original (default) or the
    /// roughened densities.
    #[arg(long, value_enum)]
    pub tempered_mis: Option<TemperedMis>,
    /// Tempered MMLT: every replica contributes to the image, weighted by the balance heuristic
    /// over the replicas' normalised targets (the default).
    #[arg(long, overrides_with = "no_reuse_replicas")]
    pub reuse_replicas: bool,
    /// Tempered MMLT: replica 0 alone writes the image (as in Šik & Křivánek 2016).
    #[arg(long, overrides_with = "reuse_replicas")]
    pub no_reuse_replicas: bool,
    /// Tempered MMLT: with reuse, which states of each replica splat: every mutation's proposal
    /// and current state with their acceptance probabilities as weights (default: expected), or
    /// the current state after each swap step (states).
    #[arg(long, value_enum)]
    pub replica_splats: Option<ReplicaSplats>,
    /// Tempered MMLT: how the hot replicas' targets are flattened: the connection vertices'
    /// GGX lobes roughened (default: roughen), or the scene's value raised to the power
    /// `1 − τ` (power).
    #[arg(long, value_enum)]
    pub flattening: Option<Flattening>,
    /// Tempered MMLT: sweeps (one mutation per replica) between swap steps.
    #[arg(long)]
    pub swap_every: Option<u64>,
    /// Tempered MMLT: sweeps between mutations of the hotter replicas (replica 0 mutates every
    /// sweep).
    #[arg(long)]
    pub hot_every: Option<u64>,
    /// Tempered MMLT: the large-step probability of the hotter replicas (default: that of
    /// replica 0, --large-step).
    #[arg(long)]
    pub hot_large_step: Option<f32>,
    /// Tempered MMLT with --swap mixture: the weight of the hotter targets in the chains'
    /// mixture target (default 1: every target's share equal).
    #[arg(long)]
    pub hot_weight: Option<f64>,
    /// Tempered MMLT: the setup of Šik & Křivánek 2016 exactly (five replicas at every depth, a
    /// roughness-only ladder tuned for 0.234, replica 0 alone writes the image).
    #[arg(long)]
    pub paper: bool,
    /// SPPM: photons per iteration (default: the scene's photonsperiteration, else one per
    /// pixel); --spp counts iterations.
    #[arg(long)]
    pub photons: Option<u64>,
    /// SPPM: initial search radius in scene units (default: the scene's, else 1).
    #[arg(long)]
    pub radius: Option<f32>,
    /// SPPM: how photon paths are sampled: uniform (default, as pbrt-v4), or mcmc (Markov
    /// chains whose target is the photon path's visibility, exchanging states with uniform
    /// photons; Hachisuka & Jensen 2011).
    #[arg(long, value_enum)]
    pub photon_sampler: Option<PhotonSampler>,
}

impl IntegratorFlags {
    /// The typed settings these flags give (the output options, per-strategy and per-depth
    /// images, off).
    pub fn settings(&self) -> IntegratorSettings {
        IntegratorSettings {
            maxdepth: self.maxdepth,
            mis: self.mis,
            strategy_images: false,
            depth_images: false,
            bootstrap: self.bootstrap,
            chains: self.chains,
            large_step: self.large_step,
            sigma: self.sigma,
            jumps: self.jumps,
            film_steps: self.film_steps,
            lens_steps: self.lens_steps,
            allocation: self.allocation,
            independent_below: self.independent_below,
            normaliser_share: self.normaliser_share,
            target_clamp: self.target_clamp,
            importance_pilot: self.importance_pilot,
            importance_floor: self.importance_floor,
            importance_power: self.importance_power,
            reallot_at: self.reallot_at,
            importance_share: self.importance_share,
            importance_below: self.importance_below,
            hybrid: self.hybrid,
            chain_efficiency: self.chain_efficiency,
            hybrid_share: self.hybrid_share,
            measure_efficiency: self.measure_efficiency.then_some(true),
            bridge_above: self.bridge_above,
            bdpt_above: self.bdpt_above,
            replicas: self.replicas,
            swap: self.swap,
            ladder: self.ladder.clone(),
            max_temperature: self.max_temperature,
            collapse_above: self.collapse_above,
            collapse_below: self.collapse_below,
            pilot: self.pilot,
            ensembles_below: self.ensembles_below,
            tempered_mis: self.tempered_mis,
            tuning: self.tuning,
            burn_in: self.burn_in,
            swap_target: self.swap_target,
            reuse_replicas: match (self.reuse_replicas, self.no_reuse_replicas) {
                (true, _) => Some(true),
                (_, true) => Some(false),
                _ => None,
            },
            replica_splats: self.replica_splats,
            flattening: self.flattening,
            swap_every: self.swap_every,
            hot_every: self.hot_every,
            hot_large_step: self.hot_large_step,
            hot_weight: self.hot_weight,
            paper: self.paper.then_some(true),
            photons: self.photons,
            radius: self.radius,
            photon_sampler: self.photon_sampler,
        }
    }
}

pub fn parse_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("expected a positive number of seconds, got '{s}'")),
    }
}

pub fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let err = || format!("expected WIDTHxHEIGHT such as 640x480, got '{s}'");
    let (w, h) = s.split_once(['x', 'X']).ok_or_else(err)?;
    let (w, h): (u32, u32) = (w.trim().parse().map_err(|_| err())?, h.trim().parse().map_err(|_| err())?);
    if w == 0 || h == 0 || w > 65_536 || h > 65_536 {
        return Err(format!("resolution must be between 1x1 and 65536x65536, got '{s}'"));
    }
    Ok((w, h))
}
