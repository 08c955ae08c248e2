//! Developing the chain driver's image ([`super::driver`]): the walkers' reports gathered
//! from every rank, each group's normalisation refined with its large steps, and each layer's
//! splats scaled to its share of the image.

use super::driver::{Group, Slot};
use super::efficiency::{Halves, second_moment};
use super::hybrid::{Hybrid, HybridDepth, HybridFilm};
use super::independent::Independent;
use super::stats::BridgeSums;
use super::walker::{Layers, Walker};
use super::{Bootstrap, DepthStats, Moments};
use crate::cluster::{Cluster, Reader, Wire};
use crate::film::SharedSplats;
use crate::integrator::{RenderOutput, RenderStats};
use crate::texture::Image;

/// What developing the image needs of one walker.
#[derive(Clone, Debug, Default)]
pub(super) struct Report {
    stats: DepthStats,
    /// Per layer, the moments of its target over the walker's large steps.
    large: Vec<Moments>,
    rays: u64,
}

impl Report {
    fn of<W: Walker>(walker: &W, layers: usize) -> Self {
        Report { stats: walker.stats(), large: (0..layers).map(|l| walker.large(l)).collect(), rays: walker.rays() }
    }
}

/// This rank's walkers' reports, the independent walkers' after the others (defaults for
/// the walkers other ranks run).
pub(super) fn local_reports<W: Walker>(
    cluster: &dyn Cluster,
    (walkers, independents, hybrids): (&[W], &[Independent], &[Hybrid]),
    plan: &[Slot],
    groups: &[Option<Group<Option<W::Group>>>],
) -> Vec<Report> {
    let layers = |k: usize| groups[k].as_ref().map_or(1, |g| g.shared.valued());
    let chains = walkers.iter().zip(plan).map(|(walker, slot)| Report::of(walker, layers(slot.group)));
    let others = independents.iter().map(|walker| Report {
        stats: walker.stats.clone(),
        large: vec![Moments::default()],
        rays: walker.rays(),
    });
    let hybrid = hybrids.iter().map(|walker| Report {
        stats: DepthStats { hybrid_samples: walker.samples, ..DepthStats::default() },
        large: vec![Moments::default()],
        rays: walker.rays(),
    });
    chains
        .chain(others)
        .chain(hybrid)
        .enumerate()
        .map(|(i, r)| if cluster.owns(i) { r } else { Report::default() })
        .collect()
}

/// Every walker's report, at rank 0 (each from the rank that runs it); the other ranks get
/// their own walkers' reports and defaults elsewhere.
pub(super) fn gather_reports(cluster: &dyn Cluster, mut reports: Vec<Report>) -> Vec<Report> {
    if !cluster.is_distributed() {
        return reports;
    }
    let mut w = Wire::default();
    for (i, r) in reports.iter().enumerate().filter(|(i, _)| cluster.owns(*i)) {
        w.u64(i as u64).u64(r.rays).u64(r.large.len() as u64);
        for m in &r.large {
            w.f64(m.sum).f64(m.sum2).u64(m.n);
        }
        r.stats.encode(&mut w);
    }
    for bytes in cluster.gather(w.bytes).iter().skip(1) {
        let mut r = Reader::new(bytes);
        while !r.is_empty() {
            let (i, rays) = (r.u64() as usize, r.u64());
            let large = (0..r.u64()).map(|_| Moments { sum: r.f64(), sum2: r.f64(), n: r.u64() }).collect();
            reports[i] = Report { stats: DepthStats::decode(&mut r), large, rays };
        }
    }
    reports
}

/// Splat buffers summed over the ranks (integer sums, exact).
pub(super) fn sum_buffers<'a>(
    cluster: &dyn Cluster,
    buffers: impl IntoIterator<Item = &'a SharedSplats>,
) -> Vec<SharedSplats> {
    buffers
        .into_iter()
        .map(|b| {
            let mut values = b.values();
            cluster.sum(&mut values);
            SharedSplats::from_values(b.width, b.height, &values)
        })
        .collect()
}

/// The independent samples combined with the chains: the depths they cover and their film.
pub(super) type IndependentImage<'a> = (&'a [HybridDepth], &'a HybridFilm);

/// Every prepared group's splat buffers summed over the ranks (integer sums, exact).
pub(super) fn sum_splats<L>(cluster: &dyn Cluster, groups: &[Option<Group<L>>]) -> Vec<Vec<SharedSplats>> {
    groups
        .iter()
        .map(|g| {
            let Some(g) = g else { return Vec::new() };
            sum_buffers(cluster, g.splats.iter().chain(&g.odd))
        })
        .collect()
}

/// The image and per-group statistics of the walkers' `reports` so far: statistics merged in
/// walker order, each layer's normalisation `b_l` refined with the large-step proposals, each
/// layer's splats (`summed` over the ranks, else the groups' own) scaled to estimate its share
/// of the image per mutation. Rays count the walkers' rays only. With `group_images`, each
/// group's share of the image (its layers summed) is also returned, in group order. The
/// independent samples combined with the chains (`hybrid`: their depths and one buffer per
/// depth, summed over the ranks) add their share ([`super::hybrid`]). Groups whose walkers
/// splat in halves ([`Group::odd`]) get their chain efficiency measured, with the film's
/// filter energy `kappa` ([`super::efficiency`]). With `bridge_above` each group's main layer
/// is scaled by its bridge estimate ([`super::bridge`]) instead of `b` where
/// [`super::bridge::prefer`] says so.
#[allow(clippy::too_many_arguments)]
pub(super) fn develop<L: Layers>(
    boots: &[Bootstrap],
    reports: &[Report],
    plan: &[Slot],
    groups: &[Option<Group<L>>],
    (summed, hybrid): (Option<&[Vec<SharedSplats>]>, Option<IndependentImage>),
    (w, h): (u32, u32),
    (group_images, kappa, bridge_above): (bool, f64, Option<f64>),
) -> RenderOutput {
    let pixels = u64::from(w) * u64::from(h);
    let layers = |k: usize| groups[k].as_ref().map_or(1, |g| g.shared.valued());
    let mut stats: Vec<DepthStats> =
        (0..boots.len()).map(|k| DepthStats { depth: k, ..DepthStats::default() }).collect();
    let mut large: Vec<Vec<Moments>> = (0..boots.len()).map(|k| vec![Moments::default(); layers(k)]).collect();
    let mut rays = 0;
    // Per group, the mutations of its walkers of even and of odd index ([`Group::odd`]).
    let mut halves = vec![(0u64, 0u64); boots.len()];
    // Per group, each walker's sums of the bridge estimate ([`super::bridge`]).
    let mut bridges: Vec<Vec<BridgeSums>> = vec![Vec::new(); boots.len()];
    for (report, slot) in reports.iter().zip(plan) {
        let k = slot.group;
        bridges[k].push(report.stats.bridge);
        let half = if slot.index % 2 == 0 { &mut halves[k].0 } else { &mut halves[k].1 };
        *half += report.stats.mutations;
        stats[k].merge(&report.stats);
        for (sums, m) in large[k].iter_mut().zip(&report.large) {
            sums.merge(m);
        }
        rays += report.rays;
    }
    // The independently sampled depths share their walkers' samples.
    let independent_samples: u64 = stats.iter().filter(|d| d.independent).map(|d| d.mutations).sum();
    let mut image = Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO);
    let mut per_group: Vec<Image> = Vec::new();
    let mut invalid = 0;
    for (k, d) in stats.iter_mut().enumerate() {
        if group_images {
            per_group.push(Image::filled(w as usize, h as usize, crate::math::Rgb::ZERO));
        }
        let boot = &boots[k];
        // A target's mean over its bootstrap and large-step samples.
        let refine = |mut prior: Moments, large: &Moments| {
            prior.merge(large);
            prior.mean_and_rel_se()
        };
        (d.b, d.b_rel_se) = boot.normalisation(&large[k][0]);
        (d.b_plain, d.b_plain_rel_se) = boot.plain_normalisation().unwrap_or((0.0, 0.0));
        // A mixture chain's states follow the mixture of targets, not the group's own.
        let mixture = groups[k].as_ref().is_some_and(|g| g.shared.mixture());
        if !d.independent
            && !mixture
            && let Some((b, rel)) = super::bridge::estimate(&boot.values, &bridges[k])
        {
            (d.b_bridge, d.b_bridge_rel_se) = (b, rel);
        }
        d.bootstrap_samples = boot.values.len() as u64;
        d.spread = boot.spread();
        d.bootstrap_nonzero = boot.nonzero();
        d.large_step_estimate = boot.large_step_acceptance();
        d.large_step_samples = large[k][0].n;
        d.invalid += boot.invalid;
        let Some(group) = &groups[k] else {
            invalid += d.invalid;
            continue;
        };
        let buffers = summed.map_or(group.splats.as_slice(), |s| s[k].as_slice());
        // The odd walkers' splats where they went to buffers of their own ([`Group::odd`]).
        let (buffers, odd) =
            if summed.is_some() { buffers.split_at(group.splats.len()) } else { (buffers, group.odd.as_slice()) };
        invalid += d.invalid + buffers.iter().chain(odd).map(SharedSplats::invalid).sum::<u64>();
        d.replica_b_ratios = group.shared.ratios().iter().map(|&r| r as f32).collect();
        d.prepare_seconds = group.seconds;
        if d.mutations == 0 {
            continue;
        }
        // Layer l estimates its share of the group's image per mutation: N_pixels · b_l/ρ_l / M_k
        // (MMLT's N_pixels · b_k / M_k for one layer).
        let mut layer_b = Vec::with_capacity(group.splats.len());
        for (l, buffer) in buffers.iter().enumerate() {
            let (b, ratio) = match (l, group.shared.layer(l)) {
                // A mixture chain's layer: b_m = b_0 + Σ_{l ≥ 1} b_l/ρ_l.
                (0, _) if group.shared.mixture() => {
                    let hot = (1..group.shared.valued()).filter_map(|m| {
                        group.shared.layer(m).map(|(moments, ratio)| refine(moments, &large[k][m]).0 / ratio)
                    });
                    (d.b + hot.sum::<f64>(), 1.0)
                }
                (0, _) if bridge_above.is_some_and(|e| super::bridge::prefer(d, e)) => (d.b_bridge, 1.0),
                (0, _) => (d.b, 1.0),
                (_, Some((moments, ratio))) => (refine(moments, &large[k][l]).0, ratio),
                (_, None) => continue,
            };
            layer_b.push(b);
            if l + 1 == group.shared.valued() && l > 0 && !group.shared.mixture() {
                // The hottest replica's b times the bridge ratios down the ladder.
                d.b_ladder = d.ladder_bridge.iter().try_fold(b, |acc, p| p.ratio().map(|r| acc * r)).unwrap_or(0.0);
            }
            let scale = if d.independent {
                pixels as f64 / independent_samples as f64
            } else {
                b / ratio * pixels as f64 / d.mutations as f64
            };
            let mut layer = buffer.image(scale);
            if let Some(odd) = odd.get(l) {
                for (p, q) in layer.pixels.iter_mut().zip(&odd.image(scale).pixels) {
                    *p += *q;
                }
            }
            for (p, q) in image.pixels.iter_mut().zip(&layer.pixels) {
                *p += *q;
            }
            if let Some(own) = per_group.last_mut() {
                for (p, q) in own.pixels.iter_mut().zip(&layer.pixels) {
                    *p += *q;
                }
            }
        }
        if layer_b.len() > 1 {
            d.replica_b = layer_b;
        }
        // A single layer splatted in halves: the chains' efficiency, their splats weighted as
        // they were (MMLT's, or combined with independent samples at the depth's level).
        if let ([even], [odd]) = (buffers, odd)
            && !group.shared.mixture()
        {
            let level = hybrid
                .and_then(|(depths, _)| depths.iter().find(|x| x.k == k))
                .map_or(0.0, |x| if x.level.is_finite() { x.level } else { 0.0 });
            let g2 = second_moment(&boot.values, level);
            let mutations = halves[k];
            d.measured_efficiency = Halves { even, odd, mutations }.efficiency(d.b, g2, kappa).unwrap_or(0.0);
        }
    }
    // The independent samples' share: each depth's weighted splats over the samples drawn.
    let hybrid_samples: u64 = stats.iter().map(|d| d.hybrid_samples).sum();
    if let Some((depths, film)) = hybrid
        && hybrid_samples > 0
    {
        invalid += film.invalid();
        for l in 0..film.layers() {
            let layer = film.image(l, hybrid_samples);
            for (p, q) in image.pixels.iter_mut().zip(&layer.pixels) {
                *p += *q;
            }
            // With per-group images the film has one layer per depth it covers.
            if let Some(own) = depths.get(l).and_then(|d| per_group.get_mut(d.k)) {
                for (p, q) in own.pixels.iter_mut().zip(&layer.pixels) {
                    *p += *q;
                }
            }
        }
    }
    let mutations: u64 = stats.iter().map(|d| d.mutations).sum();
    let stats_total = RenderStats {
        spp_completed: (mutations / pixels.max(1)) as u32,
        pixel_samples: mutations,
        rays,
        invalid_samples: invalid,
        seconds: 0.0,
        cancelled: false,
    };
    RenderOutput { image, stats: stats_total, layers: per_group, chains: stats }
}
