//! The pilot of a Markov-chain render whose targets are shaped per pixel
//! ([`crate::mcmc::importance`], `--importance-pilot N`): `N` samples per pixel of bidirectional
//! path tracing (a seed of their own, the render's depth), whose luminance gives the map; the
//! chains then render under the rest of a time budget (their snapshots as much earlier), or
//! under the whole of a fixed one. The pilot's samples are a fixed count, so the map, and the
//! image, are the same at any thread count. Its image is not part of the render's (unless the
//! render is interrupted before the chains begin: then it is the image there is); its time and
//! rays are counted in the render's statistics.

use super::{BdptIntegrator, Budget, Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::mcmc::importance::ImportanceMap;
use crate::scene::Scene;
use std::time::Instant;

/// Whether a render with a pilot of `spp` samples per pixel may also combine its chains with
/// BDPT (`hybrid`) or measure their efficiency: neither yet, because both weigh the chains'
/// states as the unshaped target would (the combination's weights, and the independent
/// samples' variance the efficiency is measured against).
pub fn check(spp: u32, hybrid: bool, measure_efficiency: bool) -> Result<(), String> {
    if spp > 0 && hybrid {
        return Err("--importance-pilot cannot be combined with --hybrid yet: the combination's weights are \
                    the unshaped target's"
            .into());
    }
    if spp > 0 && measure_efficiency {
        return Err("--importance-pilot cannot be combined with --measure-efficiency yet: the measurement \
                    assumes the unshaped target"
            .into());
    }
    Ok(())
}

/// Renders by `main` with the map of a pilot of `spp` samples per pixel (none where `spp` is 0)
/// and the floor `φ = floor` times the pilot image's mean.
pub fn render(
    (spp, floor): (u32, f64),
    max_depth: u32,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
    main: impl FnOnce(Option<&ImportanceMap>, &RenderSettings, &RenderControl) -> Result<RenderOutput, String>,
) -> Result<RenderOutput, String> {
    if spp == 0 {
        return main(None, settings, control);
    }
    if control.cluster.is_distributed() {
        return Err("--importance-pilot is not supported across MPI ranks yet".into());
    }
    let start = Instant::now();
    let quiet = |_: u64| {};
    let pilot_control = RenderControl { on_progress: &quiet, snapshots: &[], ..*control };
    let seed = crate::math::rng::hash(&[settings.seed, 0x1a9b_0f7e]);
    let pilot = BdptIntegrator::new(max_depth).render(
        scene,
        &RenderSettings { budget: Budget::Samples(spp), seed, ..*settings },
        &pilot_control,
    )?;
    if pilot.stats.cancelled {
        // Interrupted before the chains began: the pilot's image is the render's.
        return Ok(pilot);
    }
    let luminance: Vec<f32> = pilot.image.pixels.iter().map(|&p| crate::math::luminance(p)).collect();
    let map = ImportanceMap::from_pilot(pilot.image.width, pilot.image.height, &luminance, floor);
    let spent = start.elapsed();
    let snapshots = super::snapshots_after(control.snapshots, spent);
    let control = RenderControl { snapshots: &snapshots, ..*control };
    let rest = RenderSettings { budget: settings.budget.after_pilot(spent), ..*settings };
    let mut out = main(map.as_ref(), &rest, &control)?;
    out.stats.seconds += spent.as_secs_f64();
    out.stats.rays += pilot.stats.rays;
    Ok(out)
}
