//! Turns checked [`IntegratorSettings`] into an integrator, each absent setting keeping the
//! integrator's default (or the scene's).

use super::{Allocation, Hybrid, IntegratorKind, IntegratorSettings, TemperedMis};
use crate::integrator::{
    BdptIntegrator, Integrator, LadderTuning, MmltIntegrator, PathIntegrator, PssmltIntegrator, SppmIntegrator,
    TemperedIntegrator,
};
use crate::scene::RenderDefaults;

/// The integrator `kind` with `settings` (checked first); what they leave out comes from the
/// scene's `defaults` (paths of at most its `max_depth` scattering events, SPPM's photons and
/// radius, the Markov-chain integrators' bootstrap, chains, large-step probability and
/// sigma), else from the integrator's own defaults.
pub fn create(
    kind: IntegratorKind,
    settings: &IntegratorSettings,
    defaults: &RenderDefaults,
) -> Result<Box<dyn Integrator>, String> {
    settings.validate(kind)?;
    let s = settings;
    let d = s.maxdepth.unwrap_or(defaults.max_depth);
    // The scene's Markov-chain parameters, under the settings given here.
    let c = &defaults.chain;
    Ok(match kind {
        IntegratorKind::Path => Box::new(PathIntegrator::new(d)),
        IntegratorKind::Bdpt => Box::new(BdptIntegrator {
            strategy_images: s.strategy_images,
            heuristic: s.mis.unwrap_or_default(),
            ..BdptIntegrator::new(d)
        }),
        IntegratorKind::Mmlt => {
            let m = MmltIntegrator::new(d);
            Box::new(MmltIntegrator {
                bootstrap: s.bootstrap.or(c.bootstrap).unwrap_or(m.bootstrap),
                chains: s.chains.or(c.chains).unwrap_or(m.chains),
                large_step_probability: s.large_step.or(c.large_step).unwrap_or(m.large_step_probability),
                sigma: s.sigma.or(c.sigma).unwrap_or(m.sigma),
                jumps: s.jumps.unwrap_or(m.jumps),
                film_steps: s.film_steps.unwrap_or(m.film_steps),
                lens_steps: s.lens_steps.unwrap_or(m.lens_steps),
                spread_allocation: s.allocation.map_or(m.spread_allocation, |a| a == Allocation::Spread),
                independent_below: s.independent_below.unwrap_or(m.independent_below),
                normaliser_share: s.normaliser_share.unwrap_or(m.normaliser_share),
                target_clamp: s.target_clamp.unwrap_or(m.target_clamp),
                importance_pilot: s.importance_pilot.unwrap_or(m.importance_pilot),
                importance_floor: s.importance_floor.unwrap_or(m.importance_floor),
                importance_power: s.importance_power.unwrap_or(m.importance_power),
                reallot_at: s.reallot_at.unwrap_or(m.reallot_at),
                importance_share: s.importance_share.unwrap_or(m.importance_share),
                importance_below: s.importance_below.unwrap_or(m.importance_below),
                hybrid: s.hybrid.map_or(m.hybrid, Hybrid::ratio),
                hybrid_auto: s.hybrid.is_some_and(Hybrid::is_auto),
                chain_efficiency: s.chain_efficiency.unwrap_or(m.chain_efficiency),
                sample_share: s.hybrid_share.or(m.sample_share),
                measure_efficiency: s.measure_efficiency.unwrap_or(m.measure_efficiency),
                bridge_above: s.bridge_above.or(m.bridge_above),
                depth_images: s.depth_images,
                ..m
            })
        }
        IntegratorKind::Pssmlt => {
            let m = PssmltIntegrator::new(d);
            Box::new(PssmltIntegrator {
                bootstrap: s.bootstrap.or(c.bootstrap).unwrap_or(m.bootstrap),
                chains: s.chains.or(c.chains).unwrap_or(m.chains),
                large_step_probability: s.large_step.or(c.large_step).unwrap_or(m.large_step_probability),
                sigma: s.sigma.or(c.sigma).unwrap_or(m.sigma),
                ..m
            })
        }
        IntegratorKind::Tempered => {
            let m = if s.paper == Some(true) { TemperedIntegrator::paper(d) } else { TemperedIntegrator::new(d) };
            Box::new(TemperedIntegrator {
                bootstrap: s.bootstrap.or(c.bootstrap).unwrap_or(m.bootstrap),
                chains: s.chains.or(c.chains).unwrap_or(m.chains),
                large_step_probability: s.large_step.or(c.large_step).unwrap_or(m.large_step_probability),
                sigma: s.sigma.or(c.sigma).unwrap_or(m.sigma),
                jumps: s.jumps.unwrap_or(m.jumps),
                film_steps: s.film_steps.unwrap_or(m.film_steps),
                lens_steps: s.lens_steps.unwrap_or(m.lens_steps),
                spread_allocation: s.allocation.map_or(m.spread_allocation, |a| a != Allocation::Normalisation),
                spread_only_sparse: s.allocation.map_or(m.spread_only_sparse, |a| a == Allocation::Sparse),
                replicas: s.replica_count().unwrap_or(m.replicas),
                independent_below: s.independent_below.unwrap_or(m.independent_below),
                normaliser_share: s.normaliser_share.unwrap_or(m.normaliser_share),
                // The shaping is tempered MMLT's default, but it weighs states as the combination with
                // BDPT and the efficiency measurement cannot yet: those turn it off unless asked for.
                importance_pilot: s.importance_pilot.unwrap_or(
                    if s.hybrid.is_some_and(|h| h.is_auto() || h.ratio() > 0.0) || s.measure_efficiency == Some(true) {
                        0
                    } else {
                        m.importance_pilot
                    },
                ),
                importance_floor: s.importance_floor.unwrap_or(m.importance_floor),
                importance_power: s.importance_power.unwrap_or(m.importance_power),
                reallot_at: s.reallot_at.unwrap_or(m.reallot_at),
                importance_share: s.importance_share.unwrap_or(m.importance_share),
                importance_below: s.importance_below.unwrap_or(m.importance_below),
                swap: s.swap.unwrap_or(m.swap),
                ladder: s.ladder.clone().unwrap_or_default(),
                max_temperature: s.max_temperature.unwrap_or(m.max_temperature),
                collapse_above: s.collapse_above.or(m.collapse_above),
                collapse_below: s.collapse_below.or(m.collapse_below),
                pilot: s.pilot.unwrap_or(m.pilot),
                ensembles_below: s.ensembles_below.unwrap_or(m.ensembles_below),
                roughen_mis: s.tempered_mis.map_or(m.roughen_mis, |t| t == TemperedMis::Roughened),
                tuning: s.tuning.or(s.burn_in.map(|_| LadderTuning::BurnIn)).unwrap_or(m.tuning),
                burn_in: s.burn_in.unwrap_or(m.burn_in),
                swap_target: s.swap_target.unwrap_or(m.swap_target),
                reuse_replicas: s.reuse_replicas.unwrap_or(m.reuse_replicas),
                replica_splats: s.replica_splats.unwrap_or(m.replica_splats),
                flattening: s.flattening.unwrap_or(m.flattening),
                swap_every: s.swap_every.unwrap_or(m.swap_every),
                hot_every: s.hot_every.unwrap_or(m.hot_every),
                hot_large_step: s.hot_large_step.or(m.hot_large_step),
                hot_weight: s.hot_weight.unwrap_or(m.hot_weight),
                hybrid: s.hybrid.map_or(m.hybrid, Hybrid::ratio),
                hybrid_auto: s.hybrid.is_some_and(Hybrid::is_auto),
                chain_efficiency: s.chain_efficiency.unwrap_or(m.chain_efficiency),
                sample_share: s.hybrid_share.or(m.sample_share),
                measure_efficiency: s.measure_efficiency.unwrap_or(m.measure_efficiency),
                bridge_above: s.bridge_above.or(m.bridge_above),
                bdpt_above: s.bdpt_above.or(m.bdpt_above),
                depth_images: s.depth_images,
                ..m
            })
        }
        IntegratorKind::Sppm => {
            let m = SppmIntegrator::new(d);
            Box::new(SppmIntegrator {
                photons: s.photons.or(defaults.photons).unwrap_or(m.photons),
                radius: s.radius.or(defaults.radius).unwrap_or(m.radius),
                photon_sampler: s.photon_sampler.unwrap_or(m.photon_sampler),
                ..m
            })
        }
    })
}
