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
//! The chains' states are counted after every mutation in expectation over its outcome (the
//! proposal with its acceptance probability `a`, the current state with `1 − a`), as their
//! splats are; a chain's successive states are correlated, so the estimate's standard error
//! is taken over the group's chains, each an independent replication.

use super::Moments;
use super::stats::BridgeSums;

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
}
