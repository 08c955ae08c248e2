//! Markov-chain machinery shared by the MCMC integrators: chains in primary sample space and
//! their targets ([`chain`]), the MMLT target of one path depth ([`strategy`]) and PSSMLT's of
//! all depths ([`full`]), the tempered targets ([`tempered`]), the bootstrap that normalises
//! and seeds the chains ([`bootstrap`]), the driver that runs them under a budget
//! ([`driver`]), and their statistics.

pub mod acceptance;
pub mod adaptive;
pub mod all_strategies;
pub mod bootstrap;
pub mod bridge;
pub mod chain;
mod develop;
pub mod direct;
pub mod driver;
mod driver_settings;
pub mod efficiency;
pub mod full;
pub mod hybrid;
mod hybrid_plan;
pub mod importance;
pub mod independent;
pub mod jump;
pub mod lens;
pub mod normaliser;
pub mod stats;
pub mod strategy;
pub mod tempered;
pub mod walker;

pub use bootstrap::{Bootstrap, sampler_for, shared_bootstrap_bytes};
pub use bridge::LadderBridge;
pub use chain::{Chain, EvalContext, GroupValue, State, Target, target_value};
pub use driver::{Bootstraps, ChainSettings};
pub use full::{FullContribution, evaluate_full};
pub use stats::{DepthStats, Moments, NormaliserMoments, SwapStats};
pub use strategy::{Contribution, Evaluated, evaluate, evaluate_connection, evaluate_depths, valid_radiance};
pub use tempered::{Flattening, TemperedState, TemperedTarget};
pub use walker::{GroupContext, Layers, OneLayer, Single, StartContext, Walker};
