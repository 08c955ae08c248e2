//! Allotting a time budget's mutations to the groups (MMLT's path depths) by the error their
//! chains measure, instead of by `b_k` alone ([`super::ChainSettings::reallot_at`]).
//!
//! The groups' chains are independent, so the image's error is the sum of the groups'. Group
//! `k`'s error after `M_k` mutations is about `a_k/M_k`, and a mutation there costs `c_k`
//! seconds; over a budget `T = Σ c_k M_k` the sum `Σ a_k/M_k` is least at
//! `M_k ∝ sqrt(a_k/c_k)` (a Lagrange multiplier; the allocation of stratified sampling with
//! per-stratum costs, Cochran 1977 §5.5). MMLT's `M_k ∝ b_k` (Hachisuka et al. 2014 §5) is
//! that allocation where `a_k ∝ b_k²·c_k`, which holds for independent samples of a uniform
//! image; where a depth's chains mix slowly (a caustic seen through glass, whose chains stay on
//! a rare bright path for many mutations) its `a_k` is many times larger.
//!
//! `a_k` is measured, not modelled: after a share of the budget, each group's walkers of even
//! and odd index have splatted into buffers of their own ([`super::efficiency`]), and the
//! halves' difference estimates the variance of the group's image without any assumption on
//! how its chains mix. The error weighs each pixel by `1/(Ī_p² + φ²)` (relMSE's terms, `Ī` the
//! image so far averaged over 3×3 pixels, `φ` half its mean, as the importance map's floor:
//! [`super::importance::DEFAULT_FLOOR`]), and `c_k` is the group's chain seconds per mutation
//! so far. The rest of the budget then runs at the new shares; a group keeps at least
//! [`FLOOR`] of its planned share, so that a depth whose halves have not met its light yet is
//! not starved. Where the chains have made fewer than [`MIN_MUTATIONS_PER_PIXEL`] by then, the
//! halves are too noisy to act on and the plan stands. Any allotment leaves each group's image
//! unbiased (each is scaled by its own `b_k/M_k`).

use super::driver::{Group, Slot};
use super::efficiency::Halves;
use super::walker::Layers;
use crate::cluster::Cluster;
use crate::film::SharedSplats;
use crate::integrator::RenderOutput;
use crate::math::luminance;
use crate::texture::Image;

/// The least share of its planned share a group keeps.
pub const FLOOR: f64 = 0.25;

/// The main-chain mutations per pixel the chains must have made for their halves to be
/// measured: below, the render keeps the planned shares. Tempered MMLT's 10-s renders of the
/// twin caustics, re-allotted after a quarter of the budget (about 90 mutations per pixel),
/// measured 1.27× the error of the planned shares over 24 seeds, through a few seeds whose
/// early halves differed by one rare bright path; its 30-s ones (about 280) 1.04×, its 90-s
/// ones 0.82× (README, "Re-allotted by the measured error").
pub const MIN_MUTATIONS_PER_PIXEL: f64 = 160.0;

/// Per pixel of `image`, the weight `1/(Ī_p² + φ²)` of its error, `Ī` the luminance averaged
/// over the 3×3 pixels around it (fewer at the borders) and `φ = floor · mean`; `None` where
/// the image has no light.
pub fn weights(image: &Image, floor: f64) -> Option<Vec<f64>> {
    let y: Vec<f32> =
        image.pixels.iter().map(|&p| luminance(p)).map(|v| if v.is_finite() { v.max(0.0) } else { 0.0 }).collect();
    let mean = y.iter().map(|&v| f64::from(v)).sum::<f64>() / y.len().max(1) as f64;
    let phi2 = (floor * mean).powi(2);
    if !(phi2 > 0.0 && phi2.is_finite()) {
        return None;
    }
    let smooth =
        super::importance::neighbourhood(image.width, image.height, &y, 1, |v| v.iter().sum::<f32>() / v.len() as f32);
    Some(smooth.iter().map(|&s| 1.0 / (f64::from(s).powi(2) + phi2)).collect())
}

/// A group's measured error constant `a_k` (its image's weighted variance times its
/// mutations) from its halves, with normalisation `b` and pixel weights `weights`; `None`
/// where a half made no mutations.
pub fn error_constant(
    even: &SharedSplats,
    odd: &SharedSplats,
    mutations: (u64, u64),
    b: f64,
    weights: &[f64],
) -> Option<f64> {
    let halves = Halves { even, odd, mutations };
    let variance = halves.weighted_variance(b, weights)?;
    Some(variance * (mutations.0 + mutations.1) as f64)
}

/// The shares of the mutations after measurement: the groups with a measurement
/// `(a_k, c_k)` (error constant, seconds per mutation) share what they were planned to share
/// in proportion to `sqrt(a_k/c_k)`, each at least [`FLOOR`] of its planned share; the others
/// keep theirs. Where no group has a usable measurement, the planned shares.
pub fn shares(planned: &[f64], measured: &[Option<(f64, f64)>]) -> Vec<f64> {
    let usable = |m: &Option<(f64, f64)>| m.filter(|&(a, c)| a >= 0.0 && c > 0.0 && a.is_finite() && c.is_finite());
    let raw: Vec<Option<f64>> = measured.iter().map(|m| usable(m).map(|(a, c)| (a / c).sqrt())).collect();
    let pool: f64 = planned.iter().zip(&raw).filter(|(_, r)| r.is_some()).map(|(p, _)| p).sum();
    let total: f64 = raw.iter().flatten().sum();
    if !(pool > 0.0 && total > 0.0) {
        return planned.to_vec();
    }
    let mut out: Vec<f64> =
        planned.iter().zip(&raw).map(|(&p, r)| r.map_or(p, |r| (r / total * pool).max(FLOOR * p))).collect();
    // The floors lift some groups: the others give it back in proportion to what they hold
    // above their floors, so the measured groups still share `pool`.
    let measured_sum: f64 = out.iter().zip(&raw).filter(|(_, r)| r.is_some()).map(|(s, _)| s).sum();
    let excess = measured_sum - pool;
    let above: f64 =
        out.iter().zip(planned).zip(&raw).filter(|(_, r)| r.is_some()).map(|((s, p), _)| s - FLOOR * p).sum();
    if excess > 0.0 && above > 0.0 {
        for ((s, p), r) in out.iter_mut().zip(planned).zip(&raw) {
            if r.is_some() {
                *s -= excess * (*s - FLOOR * p) / above;
            }
        }
    }
    out
}

/// The shares for the rest of the render, from the render so far (`out`, developed at rank 0
/// from every rank's walkers; `summed`: the groups' buffers summed over the ranks, where the
/// render is distributed), its groups, its walkers' `plan` and the shares it ran at: rank 0's
/// measurement, the same on every rank; `None` where the chains have made fewer than
/// [`MIN_MUTATIONS_PER_PIXEL`]. Groups splatted in halves with one layer are measured; the
/// others keep their share.
pub(super) fn reallot<L: Layers>(
    cluster: &dyn Cluster,
    out: &RenderOutput,
    groups: &[Option<Group<L>>],
    summed: Option<&[Vec<SharedSplats>]>,
    plan: &[Slot],
    planned: &[f64],
) -> Option<Vec<f64>> {
    let pixels = (out.image.width * out.image.height).max(1) as f64;
    let mutations: u64 = out.chains.iter().map(|d| d.mutations).sum();
    if !cluster.broadcast(mutations as f64 >= MIN_MUTATIONS_PER_PIXEL * pixels) {
        return None;
    }
    let floor = super::importance::DEFAULT_FLOOR;
    let measured: Vec<Option<(f64, f64)>> = match weights(&out.image, floor) {
        Some(weights) => (0..planned.len())
            .map(|k| {
                let group = groups.get(k)?.as_ref()?;
                let d = out.chains.get(k)?;
                let buffers = summed.map_or(group.splats.as_slice(), |s| &s[k][..group.splats.len()]);
                let odd = summed.map_or(group.odd.as_slice(), |s| &s[k][group.splats.len()..]);
                let ([even], [odd]) = (buffers, odd) else { return None };
                if group.shared.mixture() || d.mutations == 0 {
                    return None;
                }
                // Every walker of the group made the same mutations each round.
                let walkers = plan.iter().find(|s| s.group == k)?.walkers;
                let even_mutations = d.mutations * walkers.div_ceil(2) / walkers;
                let mutations = (even_mutations, d.mutations - even_mutations);
                let a = error_constant(even, odd, mutations, d.b, &weights)?;
                Some((a, d.seconds / d.mutations as f64))
            })
            .collect(),
        None => vec![None; planned.len()],
    };
    Some(from_root(cluster, &shares(planned, &measured)))
}

/// Rank 0's `values` on every rank (the others add zeros to their bits in an exact integer
/// sum).
fn from_root(cluster: &dyn Cluster, values: &[f64]) -> Vec<f64> {
    if !cluster.is_distributed() {
        return values.to_vec();
    }
    let mut bits: Vec<i64> =
        if cluster.is_root() { values.iter().map(|v| v.to_bits() as i64).collect() } else { vec![0; values.len()] };
    cluster.sum(&mut bits);
    bits.iter().map(|&b| f64::from_bits(b as u64)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::math::rng::Pcg32;

    /// Shares follow `sqrt(a/c)` and keep the measured groups' total; a group without a
    /// measurement keeps its share.
    #[test]
    fn shares_follow_the_square_root_of_error_over_cost() {
        let planned = [0.1, 0.3, 0.6];
        // a/c = 1, 4, 16 → sqrt 1, 2, 4 of a pool 0.9 for the last two.
        let s = shares(&planned, &[None, Some((4.0, 1.0)), Some((32.0, 2.0))]);
        assert!((s[0] - 0.1).abs() < 1e-12);
        assert!((s[1] - 0.3).abs() < 1e-12 && (s[2] - 0.6).abs() < 1e-12, "{s:?}");
        let s = shares(&planned, &[Some((1.0, 1.0)), Some((4.0, 1.0)), Some((1.0, 1.0))]);
        let sum: f64 = s.iter().sum();
        assert!((sum - 1.0).abs() < 1e-12, "{s:?}");
        // 1 : 2 : 1 before the floor (0.25 : 0.5 : 0.25), all above their floors.
        assert!((s[0] - 0.25).abs() < 1e-12 && (s[1] - 0.5).abs() < 1e-12 && (s[2] - 0.25).abs() < 1e-12);
    }

    /// A group whose error measured zero keeps its floor, and the shares still sum to one.
    #[test]
    fn a_group_measured_without_error_keeps_its_floor() {
        let planned = [0.5, 0.5];
        let s = shares(&planned, &[Some((0.0, 1.0)), Some((1.0, 1.0))]);
        assert!((s[0] - FLOOR * 0.5).abs() < 1e-12, "{s:?}");
        assert!((s[0] + s[1] - 1.0).abs() < 1e-12, "{s:?}");
        // Nothing usable: the plan.
        assert_eq!(shares(&planned, &[None, Some((f64::NAN, 1.0))]), planned.to_vec());
    }

    /// Weights are `1/(Ī² + φ²)` with `Ī` the 3×3 mean: a uniform image gives every pixel
    /// `1/(y²(1 + floor²))`; a dark image has none.
    #[test]
    fn weights_of_a_uniform_image() {
        let image = Image::filled(4, 3, crate::math::Rgb::splat(2.0));
        let y = f64::from(luminance(crate::math::Rgb::splat(2.0)));
        let w = weights(&image, 0.5).expect("a lit image");
        assert!(w.iter().all(|&v| (v - 1.0 / (y * y * 1.25)).abs() < 1e-9), "{w:?}");
        assert!(weights(&Image::filled(4, 3, crate::math::Rgb::ZERO), 0.5).is_none());
    }

    /// Halves of independent uniform splats: the measured constant does not depend on how
    /// many mutations were made (the error falls as `1/M`), and splats twice as bright measure
    /// four times the constant.
    #[test]
    fn the_error_constant_is_per_mutation() {
        let (w, h) = (8u32, 8u32);
        let weights = vec![1.0; 64];
        let measure = |m: u64, value: f32, seed: u64| {
            let (even, odd) = (SharedSplats::new(w, h), SharedSplats::new(w, h));
            let mut rng = Pcg32::new(seed, 3);
            for i in 0..m {
                let buffer = if i % 2 == 0 { &even } else { &odd };
                let p = Vec2::new(rng.next_f64() as f32 * w as f32, rng.next_f64() as f32 * h as f32);
                buffer.add(p, crate::math::Rgb::splat(value));
            }
            error_constant(&even, &odd, (m / 2, m / 2), 1.0, &weights).expect("both halves")
        };
        let mean = |m: u64, value: f32| (0..32).map(|s| measure(m, value, s)).sum::<f64>() / 32.0;
        let (small, large, bright) = (mean(4_000, 1.0), mean(16_000, 1.0), mean(4_000, 2.0));
        assert!((large / small - 1.0).abs() < 0.15, "{small} {large}");
        assert!((bright / small - 4.0).abs() < 0.6, "{small} {bright}");
        assert!(small > 0.0);
    }
}
