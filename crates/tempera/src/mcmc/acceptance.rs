//! What a chain's large steps (independent uniform proposals in primary sample space) would
//! be accepted at, estimated from a group's bootstrap values, and what that says of a whole
//! render: whether its light is found as well by independent samples as by chains.

use super::Bootstrap;

/// The equilibrium acceptance of independent proposals drawn uniformly in primary sample
/// space (a chain's large steps) for a target whose values at uniform samples are `values`:
/// with `x` distributed as the target and `y` uniform, `E[min(1, f(y)/f(x))]`, which is
/// `E[min(f(x), f(y))] / E[f]` with both `x` and `y` uniform. Estimated by the U-statistic over
/// all pairs of distinct samples (`Σ_{i<j} min(f_i, f_j)` is `Σ_r f_(r) (n − 1 − r)` over the
/// values sorted in ascending order); 0 where no value is positive.
pub fn large_step_acceptance(values: &[f32]) -> f64 {
    let mut sorted: Vec<f64> = values.iter().filter(|&&v| v > 0.0).map(|&v| f64::from(v)).collect();
    let n = values.len() as f64;
    let sum: f64 = sorted.iter().sum();
    if sum <= 0.0 || values.len() < 2 {
        return 0.0;
    }
    sorted.sort_by(f64::total_cmp);
    // The zeros sort first and add nothing; the r-th smallest positive value is the smaller
    // of its pairs with every value above it.
    let above = |r: usize| (sorted.len() - 1 - r) as f64;
    let pairs: f64 = sorted.iter().enumerate().map(|(r, &v)| v * above(r)).sum();
    let mean_min = 2.0 * pairs / (n * (n - 1.0));
    (mean_min / (sum / n)).min(1.0)
}

/// How well independent samples would do where MMLT's chains run: over the path depths
/// `k ≥ 1` (`boots[k]`, one per depth from 0), each depth's [`Bootstrap::large_step_acceptance`]
/// weighted by its normalisation `b_k`, so the acceptance a chain's large steps would have at
/// equilibrium, averaged over the light the chains carry. Depth 0 (emitters seen directly) is
/// left out: a chain finds its light as easily as a camera ray does. An acceptance near one
/// says uniform samples land about as often on the light as the chains' states do, so the
/// chains' local moves have little to find that independent samples miss (Kelemen et al.
/// 2002 read the large steps' acceptance so); an acceptance near zero says the light lies in
/// small regions of primary sample space that only chains keep finding. 0 where no depth
/// `k ≥ 1` has light.
pub fn independent_acceptance(boots: &[Bootstrap]) -> f64 {
    let (mut weighted, mut total) = (0.0, 0.0);
    for boot in boots.iter().skip(1) {
        let b = boot.b();
        if b.is_finite() && b > 0.0 {
            weighted += b * boot.large_step_acceptance();
            total += b;
        }
    }
    if total > 0.0 { weighted / total } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;
    use crate::mcmc::Moments;

    /// The estimated large-step acceptance matches closed forms: a target that is 1 on a
    /// fraction `p` of the space and 0 elsewhere accepts a proposal exactly when it lands in
    /// that fraction (`p`); one uniform on `[0, 1]` accepts `E[min(X, Y)] / E[X] = 2/3`; and a
    /// constant target accepts every proposal.
    #[test]
    fn large_step_acceptance_matches_closed_forms() {
        let n = 20_000;
        let indicator: Vec<f32> = (0..n).map(|i| if i % 50 < 3 { 2.5 } else { 0.0 }).collect();
        assert!((large_step_acceptance(&indicator) - 0.06).abs() < 1e-4, "{}", large_step_acceptance(&indicator));
        let mut rng = Pcg32::new(7, 1);
        let uniform: Vec<f32> = (0..n).map(|_| rng.next_f64() as f32).collect();
        let a = large_step_acceptance(&uniform);
        assert!((a - 2.0 / 3.0).abs() < 0.01, "{a}");
        assert!((large_step_acceptance(&[0.3; 100]) - 1.0).abs() < 1e-12);
        assert_eq!(large_step_acceptance(&[0.0; 100]), 0.0);
        // A rare bright value lowers it: most proposals fall from the bright state.
        let mut spiked = uniform.clone();
        spiked[0] = 1e6;
        assert!(large_step_acceptance(&spiked) < 0.05, "{}", large_step_acceptance(&spiked));
    }

    /// Depths `k ≥ 1` count by their `b_k`, depth 0 not at all: a depth of equal values
    /// (acceptance 1, `b` = 1) beside one whose light is a single value of a thousand
    /// (acceptance 0, `b` = 1, then 3), with a depth 0 of equal values and a large `b`.
    #[test]
    fn independent_acceptance_weighs_the_depths_by_b() {
        let plain = |values: Vec<f32>| {
            let mut all = Moments::default();
            values.iter().for_each(|&v| all.push(f64::from(v)));
            Bootstrap {
                mean: all.sum / all.n as f64,
                sum2: all.sum2,
                values,
                invalid: 0,
                rays: 0,
                normaliser_rays: 0,
                normaliser: None,
                clamp: f32::INFINITY,
            }
        };
        let spike = |v: f32| {
            let mut values = vec![0.0; 1000];
            values[500] = v;
            plain(values)
        };
        let seen_directly = || plain(vec![50.0; 1000]);
        let flat = || plain(vec![1.0; 1000]);
        let a = independent_acceptance(&[seen_directly(), flat(), spike(1000.0)]);
        assert!((a - 0.5).abs() < 1e-9, "{a}");
        let a = independent_acceptance(&[seen_directly(), flat(), spike(3000.0)]);
        assert!((a - 0.25).abs() < 1e-9, "{a}");
        assert_eq!(independent_acceptance(&[seen_directly(), plain(vec![0.0; 1000])]), 0.0);
    }
}
