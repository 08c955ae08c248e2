//! The pilot of a Markov-chain render whose targets are shaped per pixel
//! ([`crate::mcmc::importance`], `--importance-pilot N`): up to `N` samples per pixel of
//! bidirectional path tracing (seeds of their own, the render's depth), whose luminance gives
//! the map; under a time budget it stops earlier, at a share of the budget
//! (`--importance-share`), so that where bidirectional path tracing is slow the pilot does not
//! eat the chains' time. The chains then render under the rest of a time budget (their
//! snapshots as much earlier), or under the whole of a fixed one. Under a fixed budget the
//! pilot's samples are a fixed count, so the map, and the image, are the same at any thread
//! count, and across MPI ranks (the pilot's passes are shared among them like any BDPT
//! render's, and rank 0's image gives every rank the map). Its image is not part of the
//! render's (unless the render is interrupted before the chains begin: then it is the image
//! there is); its time and rays are counted in the render's statistics.

use super::{BdptIntegrator, Budget, Integrator, RenderControl, RenderOutput, RenderSettings};
use crate::cluster::Cluster;
use crate::mcmc::importance::ImportanceMap;
use crate::scene::Scene;
use crate::texture::Image;
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

/// How a render shapes its chains' targets per pixel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shaping {
    /// Samples per pixel of the pilot, at most (0: no shaping).
    pub spp: u32,
    /// The floor `φ` over the pilot image's mean ([`ImportanceMap::from_pilot`]).
    pub floor: f64,
    /// The power `γ` of the shape ([`ImportanceMap::from_pilot`]).
    pub power: f64,
    /// The share of a time budget the pilot may take: it stops at `spp` samples per pixel or
    /// before a pass would take it past this share, whichever comes first (one pass at least).
    pub share: f64,
    /// The chains are shaped only where the map's [`ImportanceMap::predicted_ratio`] is below
    /// this; elsewhere they sample MMLT's targets.
    pub below: f64,
}

/// Passes after which the pilot stops where its map already predicts too little gain.
pub const DECIDE_AFTER: u32 = 2;

/// The share of a time budget a pilot takes at most unless the render says otherwise.
pub const DEFAULT_SHARE: f64 = 0.05;

/// The predicted ratio below which the chains are shaped unless the render says otherwise:
/// the chains measured gain less than the model predicts, so only a large predicted gain is
/// taken; with the softer shape ([`crate::mcmc::importance::DEFAULT_POWER`]) the shaping paid
/// on both scenes it was measured on, whose predictions lie below this, and the one scene
/// predicted above it was not measured shaped (README, "A softer shape").
pub const DEFAULT_BELOW: f64 = 0.665;

/// What the pilot drew and chose (`--stats` writes it in depth 0's row as `importance_pilot`).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PilotChoice {
    /// Samples per pixel the pilot drew.
    pub spp: u32,
    /// Its seconds.
    pub seconds: f64,
    /// The map's predicted relMSE ratio ([`ImportanceMap::predicted_ratio`]; 1 without a map).
    pub predicted_ratio: f64,
    /// Whether the chains were shaped.
    pub shaped: bool,
}

/// Renders by `main` with the map of a pilot (none where `shaping.spp` is 0, or where the map
/// predicts too little gain: `shaping.below`). The pilot runs in passes of one sample per
/// pixel, each with its own seed: under a fixed budget all `shaping.spp` of them, so the map is
/// the same at any thread count; under a time budget as many as fit in its share.
pub fn render(
    shaping: Shaping,
    max_depth: u32,
    scene: &Scene,
    settings: &RenderSettings,
    control: &RenderControl,
    main: impl FnOnce(Option<&ImportanceMap>, &RenderSettings, &RenderControl) -> Result<RenderOutput, String>,
) -> Result<RenderOutput, String> {
    if shaping.spp == 0 {
        return main(None, settings, control);
    }
    let start = Instant::now();
    let cap = match settings.budget {
        Budget::Time(t) => Some(t.mul_f64(shaping.share.clamp(0.0, 1.0))),
        Budget::Samples(_) => None,
    };
    let quiet = |_: u64| {};
    let pilot_control = RenderControl { on_progress: &quiet, snapshots: &[], ..*control };
    let bdpt = BdptIntegrator::new(max_depth);
    let mut pilot: Option<RenderOutput> = None;
    let mut passes = 0u32;
    while passes < shaping.spp {
        // Stop before a pass of the mean length so far would overrun the share; rank 0
        // decides, so that every rank draws the same passes.
        let elapsed = start.elapsed();
        let over = passes > 0 && cap.is_some_and(|c| elapsed + elapsed / passes > c);
        if cap.is_some() && control.cluster.broadcast(over) {
            break;
        }
        let seed = crate::math::rng::hash(&[settings.seed, 0x1a9b_0f7e, u64::from(passes)]);
        let pass =
            bdpt.render(scene, &RenderSettings { budget: Budget::Samples(1), seed, ..*settings }, &pilot_control)?;
        if pass.stats.cancelled {
            // Interrupted before the chains began: the pilot's image is the render's (the
            // finished passes', or the unfinished one's where none finished).
            let mut out = pilot.unwrap_or(pass);
            mean_of_passes(&mut out.image, passes.max(1));
            out.stats.cancelled = true;
            return Ok(out);
        }
        match pilot.as_mut() {
            None => pilot = Some(pass),
            Some(sum) => {
                sum.image.pixels.iter_mut().zip(&pass.image.pixels).for_each(|(a, b)| *a += *b);
                sum.stats.rays += pass.stats.rays;
            }
        }
        passes += 1;
        // A map of a few passes looks more uneven than the image is (its noise), so it predicts
        // at least the gain a longer pilot would: where even it predicts too little, the rest
        // of the pilot would be spent for nothing.
        if passes == DECIDE_AFTER && passes < shaping.spp {
            let sum = pilot.as_ref().expect("a finished pass");
            if map_of(sum, passes, &shaping, control.cluster).1 >= shaping.below {
                break;
            }
        }
    }
    let pilot = pilot.expect("at least one pass");
    let (map, predicted_ratio) = map_of(&pilot, passes, &shaping, control.cluster);
    let map = map.filter(|_| predicted_ratio < shaping.below);
    let spent = start.elapsed();
    let snapshots = super::snapshots_after(control.snapshots, spent);
    let control = RenderControl { snapshots: &snapshots, ..*control };
    let rest = RenderSettings { budget: settings.budget.after_pilot(spent), ..*settings };
    let mut out = main(map.as_ref(), &rest, &control)?;
    out.stats.seconds += spent.as_secs_f64();
    out.stats.rays += pilot.stats.rays;
    let choice = PilotChoice { spp: passes, seconds: spent.as_secs_f64(), predicted_ratio, shaped: map.is_some() };
    if let Some(first) = out.chains.first_mut() {
        first.importance_pilot = Some(choice);
    }
    Ok(out)
}

/// The map of the mean of `passes` passes whose image sum is `sum`, and its predicted ratio (1
/// without a map).
fn map_of(sum: &RenderOutput, passes: u32, shaping: &Shaping, cluster: &dyn Cluster) -> (Option<ImportanceMap>, f64) {
    let mut mean = sum.image.clone();
    mean_of_passes(&mut mean, passes);
    let luminance = shared_luminance(&mean, cluster);
    let map = ImportanceMap::from_pilot(mean.width, mean.height, &luminance, passes, shaping.floor, shaping.power);
    let predicted = map.as_ref().map_or(1.0, ImportanceMap::predicted_ratio);
    (map, predicted)
}

/// The pilot image's luminance, rank 0's on every rank (the image is merged there alone): the
/// other ranks add zeros to its bits in an exact integer sum.
fn shared_luminance(image: &Image, cluster: &dyn Cluster) -> Vec<f32> {
    let luminance = image.pixels.iter().map(|&p| crate::math::luminance(p));
    if !cluster.is_distributed() {
        return luminance.collect();
    }
    let mut bits: Vec<i64> = if cluster.is_root() {
        luminance.map(|y| i64::from(y.to_bits())).collect()
    } else {
        vec![0; image.width * image.height]
    };
    cluster.sum(&mut bits);
    bits.iter().map(|&b| f32::from_bits(b as u32)).collect()
}

/// Divides the sum of `passes` passes' images by their count.
fn mean_of_passes(image: &mut Image, passes: u32) {
    let scale = 1.0 / passes as f32;
    image.pixels.iter_mut().for_each(|p| *p *= scale);
}
