//! The bridge estimate of a target's normalisation `b = ∫ f` from independent uniform samples
//! and the chains' own states together (Meng & Wong 1996, "Simulating ratios of normalizing
//! constants via a simple identity"; Gelman & Meng 1998). For any level `h > 0`,
//!
//! ```text
//! E_uniform[f/(f + h)] = ∫ f/(f + h),    E_{f/b}[1/(f + h)] = ∫ (f/b)/(f + h),
//! b = E_uniform[f/(f + h)] / E_{f/b}[1/(f + h)],
//! ```
//!
//! so the ratio of the uniform samples' mean of `f/(f + h)` (the bootstrap's values and the
//! chains' large-step proposals) to the chains' mean of `1/(f + h)` over their states
//! estimates `b`. Neither mean has a heavy tail: a rare bright path, which in the plain mean
//! of `f` over uniform samples moves `b` by its whole value, adds at most 1 to the first, and
//! the chains' states add at most `1/h` to the second. The share of the light in paths much
//! brighter than `h` is measured by how often the chains visit them, which is what a Markov
//! chain estimates well; the uniform samples only have to value the paths near and below `h`.
//! The level is the bootstrap's mean `b`; any fixed level keeps the estimate consistent.
//!
//! The same identity between two targets instead of a target and the uniform density gives
//! the ratio of two tempered replicas' normalisations from their states ([`LadderBridge`]);
//! down a ladder from a roughened target, whose uniform samples are far less heavy-tailed than
//! the scene's own, the product of the ratios is a second estimate of `b`.
//!
//! The chains' states are counted after every mutation in expectation over its outcome (the
//! proposal with its acceptance probability `a`, the current state with `1 − a`), as their
//! splats are; a chain's successive states are correlated, so the estimate's standard error
//! is taken over the group's chains, each an independent replication.

use super::Moments;
use super::stats::BridgeSums;

/// The default threshold of `b`'s reported relative error past which a depth may take its
/// bridge estimate ([`prefer`]; measured in the README, "Bridge only where `b` is uncertain").
pub const DEFAULT_ABOVE: f64 = 0.1;

/// The most of `b`'s reported relative error the bridge estimate may report where it replaces
/// `b` ([`prefer`]).
pub const PRECISION: f64 = 0.5;

/// Whether a depth's image takes its bridge estimate instead of `b` at the threshold `above`:
/// where it has one, `b` reports a relative error above `above` (a mean of uniform samples
/// moved by a few bright paths) and the bridge reports at most [`PRECISION`] times that (its
/// error is taken over the chains, which a rare path moves less). Where both are uncertain,
/// as at depths the chains have barely visited, `b` stays.
pub fn prefer(d: &super::DepthStats, above: f64) -> bool {
    d.b_bridge > 0.0 && d.b_rel_se > above && d.b_bridge_rel_se <= PRECISION * d.b_rel_se
}

/// The bridge estimate from the uniform values `uniform` (the bootstrap's, valued `f`) and the
/// group's chains' sums (`chains`, one per chain, at the level they carry); with its relative
/// standard error. `None` where the chains made no mutation or no value was positive.
pub fn estimate(uniform: &[f32], chains: &[BridgeSums]) -> Option<(f64, f64)> {
    let h = chains.iter().map(|c| c.level).find(|&h| h > 0.0)?;
    if !h.is_finite() {
        return None;
    }
    let mut u = Moments::default();
    for &v in uniform {
        let f = f64::from(v.max(0.0));
        u.push(f / (f + h));
    }
    let mut states = Moments::default();
    for c in chains {
        u.merge(&c.uniform);
        states.merge(&c.states);
    }
    if u.n == 0 || states.n == 0 || u.sum <= 0.0 || states.sum <= 0.0 {
        return None;
    }
    let (mu, rel_u) = u.mean_and_rel_se();
    let ms = states.sum / states.n as f64;
    // The states' mean over the chains, each chain's mean a replication weighted by its count.
    let n = states.n as f64;
    let var: f64 = chains
        .iter()
        .filter(|c| c.states.n > 0)
        .map(|c| {
            let w = c.states.n as f64 / n;
            let d = c.states.sum / c.states.n as f64 - ms;
            w * w * d * d
        })
        .sum();
    let replications = chains.iter().filter(|c| c.states.n > 0).count() as f64;
    let rel_s = if replications > 1.0 { (var * replications / (replications - 1.0)).sqrt() / ms } else { 0.0 };
    Some((mu / ms, (rel_u * rel_u + rel_s * rel_s).sqrt()))
}

/// The sums of the bridge estimate (Meng & Wong 1996) of the ratio `b_j/b_{j+1}` of two
/// neighbouring replicas' normalisations from their own states: with `α = 1/(f_j + c·f_{j+1})`
/// for a fixed `c > 0` (the calibrated `b_j/b_{j+1}`),
/// `b_j/b_{j+1} = E_{j+1}[f_j·α] / E_j[f_{j+1}·α]`, each expectation over the states of the
/// replica whose target it is. Both terms are bounded (by 1 and by `1/c`), so a state on a
/// bright path one target sees and the other barely does cannot move the ratio by its value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LadderBridge {
    /// `Σ w·f_j·α` over replica `j + 1`'s states, each weighted as it splats (a proposal by
    /// its acceptance, the current state by the rest), and `Σ w`.
    pub upper: [f64; 2],
    /// `Σ w·f_{j+1}·α` over replica `j`'s states, and `Σ w`.
    pub lower: [f64; 2],
}

impl LadderBridge {
    /// Adds a state of the upper (`upper`) or lower replica with values `f_j`, `f_{j+1}`
    /// under the pair's targets and weight `w`, for the level `c`.
    pub fn add(&mut self, upper: bool, f: (f64, f64), w: f64, c: f64) {
        let d = f.0 + c * f.1;
        let side = if upper { &mut self.upper } else { &mut self.lower };
        // A state neither target sees adds its weight only.
        if d > 0.0 && d.is_finite() && w > 0.0 {
            side[0] += w * if upper { f.0 } else { f.1 } / d;
        }
        side[1] += w.max(0.0);
    }

    /// The ratio `b_j/b_{j+1}` (`None` where either side saw nothing).
    pub fn ratio(&self) -> Option<f64> {
        let (u, l) = (self.upper[0] / self.upper[1], self.lower[0] / self.lower[1]);
        (u > 0.0 && l > 0.0 && u.is_finite() && l.is_finite()).then(|| u / l)
    }

    pub fn merge(&mut self, o: &LadderBridge) {
        for (a, b) in self.upper.iter_mut().chain(&mut self.lower).zip(o.upper.iter().chain(&o.lower)) {
            *a += b;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    /// On a one-dimensional target with a rare bright spike (1 % of the domain holding 91 % of
    /// the light), exact samples of `f/b` and 50 uniform samples give `b` to within 10 % on
    /// average over seeds, where the plain mean of the same uniform samples is off by half of
    /// it or more.
    #[test]
    fn the_bridge_finds_the_light_the_uniform_samples_miss() {
        let f = |x: f64| if x < 0.01 { 100.0 } else { 0.1 };
        let b = 0.01 * 100.0 + 0.99 * 0.1;
        let (mut bridge_err, mut plain_err) = (0.0f64, 0.0f64);
        let seeds = 20u32;
        for seed in 0..u64::from(seeds) {
            let mut rng = Pcg32::new(seed, 3);
            let uniform: Vec<f32> = (0..50).map(|_| f(rng.next_f64()) as f32).collect();
            // Exact samples of f/b: the spike with probability 1/b, else the rest.
            let mut sums = vec![BridgeSums { level: 0.5, ..BridgeSums::default() }; 8];
            for c in &mut sums {
                for _ in 0..2000 {
                    let x = if rng.next_f64() < 1.0 / b { 0.005 } else { 0.5 };
                    c.states.push(1.0 / (f(x) + 0.5));
                }
            }
            let (est, rel) = estimate(&uniform, &sums).unwrap();
            assert!(rel > 0.0 && rel < 0.2, "{rel}");
            bridge_err += (est / b - 1.0).abs() / f64::from(seeds);
            let plain = uniform.iter().map(|&v| f64::from(v)).sum::<f64>() / uniform.len() as f64;
            plain_err += (plain / b - 1.0).abs() / f64::from(seeds);
        }
        assert!(bridge_err < 0.1, "bridge off by {bridge_err}");
        assert!(plain_err > 0.5, "plain off by {plain_err}");
    }

    /// Exact samples of two targets on `[0, 1)`, a spike holding 91 % of the first's light and
    /// the second a flattened version of it, give the ratio of their normalisations within
    /// 3 % from 20,000 samples each, at a level off by a factor 2.
    #[test]
    fn the_ladder_bridge_gives_the_ratio_of_two_replicas_normalisations() {
        let f0 = |x: f64| if x < 0.01 { 100.0 } else { 0.1 };
        let f1 = |x: f64| if x < 0.01 { 3.0 } else { 0.5 };
        let (b0, b1) = (0.01 * 100.0 + 0.99 * 0.1, 0.01 * 3.0 + 0.99 * 0.5);
        // Exact samples: the spike with its share of the target's light, else the rest.
        let draw = |rng: &mut Pcg32, spike: f64| {
            if rng.next_f64() < spike { 0.01 * rng.next_f64() } else { 0.01 + 0.99 * rng.next_f64() }
        };
        let mut rng = Pcg32::new(7, 1);
        let mut pair = LadderBridge::default();
        let c = 2.0 * b0 / b1;
        for _ in 0..20_000 {
            let x = draw(&mut rng, 1.0 / b0);
            pair.add(false, (f0(x), f1(x)), 1.0, c);
            let y = draw(&mut rng, 0.03 / b1);
            pair.add(true, (f0(y), f1(y)), 1.0, c);
        }
        let r = pair.ratio().unwrap();
        assert!((r / (b0 / b1) - 1.0).abs() < 0.03, "{r} against {}", b0 / b1);
        // Weights split a state's count, as a proposal and its current state share a mutation.
        let mut halves = LadderBridge::default();
        halves.add(true, (1.0, 1.0), 0.25, 1.0);
        halves.add(true, (0.0, 1.0), 0.75, 1.0);
        halves.add(false, (1.0, 1.0), 1.0, 1.0);
        assert!((halves.ratio().unwrap() - 0.25).abs() < 1e-12);
        assert_eq!(LadderBridge::default().ratio(), None);
    }

    /// No chain states, no light, or no level: no estimate; else one.
    #[test]
    fn without_states_or_light_there_is_no_estimate() {
        let sums = [BridgeSums { level: 1.0, ..BridgeSums::default() }];
        assert_eq!(estimate(&[1.0], &sums), None);
        let mut s = BridgeSums { level: 1.0, ..BridgeSums::default() };
        s.states.push(0.5);
        assert_eq!(estimate(&[0.0, 0.0], &[s]), None);
        assert_eq!(estimate(&[1.0], &[BridgeSums { level: 0.0, ..s }]), None);
        assert!(estimate(&[1.0], &[s]).is_some());
    }

    /// The bridge replaces `b` only where `b` is uncertain past the threshold and the bridge
    /// reports at most half of `b`'s error.
    #[test]
    fn prefer_takes_the_bridge_only_where_b_is_uncertain_and_the_bridge_is_not() {
        let d = |b_rel_se, b_bridge, b_bridge_rel_se| super::super::DepthStats {
            b: 1.0,
            b_rel_se,
            b_bridge,
            b_bridge_rel_se,
            ..Default::default()
        };
        assert!(prefer(&d(0.3, 0.8, 0.1), 0.1));
        assert!(prefer(&d(0.3, 0.8, 0.14), 0.1));
        assert!(!prefer(&d(0.3, 0.8, 0.16), 0.1), "the bridge as uncertain as b");
        assert!(!prefer(&d(0.08, 0.8, 0.01), 0.1), "b certain enough");
        assert!(!prefer(&d(0.3, 0.0, 0.0), 0.1), "no bridge estimate");
        assert!(prefer(&d(0.01, 0.8, 0.005), 0.0));
        assert!(!prefer(&d(0.3, 0.8, 0.1), f64::INFINITY), "an infinite threshold: never");
    }
}
