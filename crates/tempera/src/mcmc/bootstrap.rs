//! The bootstrap of a group of chains (MMLT: one path depth; Veach 1997 §11.3.1, pbrt-v4
//! §13.4.4): independent uniform samples of the group's target. Their mean is the
//! normalisation `b`, and chains start from them in proportion to their value, which removes
//! start-up bias. Sample `i` of group `k` always has the same seed, so whoever needs the same
//! samples again (tempering's calibration) evaluates them again; it is the same point of primary
//! sample space in every group, so groups whose targets value the same paths value it together.

use super::driver::ChainSettings;
use super::{EvalContext, GroupValue, Moments, NormaliserMoments, State, Target};
use crate::bidir::Paths;
use crate::math::distribution::Distribution1D;
use crate::math::rng::hash;
use crate::sampler::PssSampler;
use crate::sampler::pss::FILM_STEP_WIDTH;
use rayon::prelude::*;

/// Seed of the numbers of the chain that starts from bootstrap sample `i` of group `k`.
fn bootstrap_seed(seed: u64, k: usize, i: usize) -> u64 {
    hash(&[seed, 0xb007, k as u64, i as u64])
}

/// The sampler holding bootstrap sample `i` of group `k` (a chain started from it mutates it).
/// Sample `i` is the same primary-sample-space point in every group (a counter-based first
/// state seeded by `i` alone), so groups whose targets value the same paths (MMLT's depths)
/// can value it together ([`Target::value_groups`]); the numbers of the chain that mutates it
/// are the group's own.
pub fn sampler_for(seed: u64, k: usize, i: usize, settings: &ChainSettings) -> PssSampler {
    PssSampler::new(bootstrap_seed(seed, k, i), k as u64, settings.sigma, settings.large_step_probability)
        .with_first_state(hash(&[seed, 0xb007, i as u64]))
        .with_jumps(settings.jumps)
        .with_film_steps(settings.film_steps, FILM_STEP_WIDTH)
        .with_lens_steps(settings.lens_steps, FILM_STEP_WIDTH)
}

/// Per-thread storage for evaluating independent samples one after the other.
pub struct Scratch<S> {
    paths: Paths,
    state: S,
    /// The last sampler evaluated, whose storage the next one takes over.
    spare: Option<PssSampler>,
}

impl<S: State> Default for Scratch<S> {
    fn default() -> Self {
        Self { paths: Paths::default(), state: S::default(), spare: None }
    }
}

impl<S: State> Scratch<S> {
    /// Evaluates the state `sampler` holds under `target`; returns it and the rays traced.
    pub fn evaluate(&mut self, target: &impl Target<State = S>, sampler: PssSampler) -> (&mut S, u64) {
        let mut cx = self.lend(sampler);
        self.state = target.evaluate(&mut cx, std::mem::take(&mut self.state));
        let rays = self.take_back(cx);
        (&mut self.state, rays)
    }

    /// A context for evaluating the state `sampler` holds, with this scratch's storage.
    fn lend(&mut self, mut sampler: PssSampler) -> EvalContext {
        if let Some(spare) = self.spare.take() {
            sampler.reuse_storage(spare);
        }
        EvalContext { paths: std::mem::take(&mut self.paths), ..EvalContext::new(sampler) }
    }

    /// Keeps the storage of a context [`Self::lend`] gave; returns the rays it traced.
    fn take_back(&mut self, cx: EvalContext) -> u64 {
        self.paths = cx.paths;
        self.spare = Some(cx.sampler);
        cx.rays
    }
}

/// Samples of a target's own normaliser beside `bootstrap` bootstrap samples: a quarter as
/// many. Its estimates have far less variance than the target's values (that is its point),
/// and at depth `k` each costs about twice the rays of a bootstrap sample.
pub fn normaliser_samples(bootstrap: usize) -> usize {
    bootstrap.div_ceil(4)
}

/// The memory [`Bootstrap::run_groups`] takes for `bootstrap` samples of `groups` groups at
/// its peak: every sample's values under every group, and one group's column of them.
pub fn shared_bootstrap_bytes(bootstrap: usize, groups: usize) -> u64 {
    let value = std::mem::size_of::<GroupValue>() as u64;
    let row = std::mem::size_of::<(Vec<GroupValue>, u64)>() as u64;
    (bootstrap as u64).saturating_mul((groups as u64 + 1).saturating_mul(value).saturating_add(row))
}

/// Folds of the cross-fitted normalisation ([`Bootstrap::normalisation`]).
pub const FOLDS: usize = 8;

/// The bootstrap of one group: its samples' target values and their moments.
pub struct Bootstrap {
    pub values: Vec<f32>,
    /// The mean of the values: the group's normalisation before the large steps refine it.
    pub mean: f64,
    pub sum2: f64,
    /// Samples whose value was NaN, infinite or negative.
    pub invalid: u64,
    /// The target's own lower-variance estimator of `b` ([`Target::normaliser`]) in
    /// [`FOLDS`] independent folds, combined with the values' ([`Self::normalisation`]).
    pub normaliser: Option<Vec<NormaliserMoments>>,
    /// The rays the values and the normaliser's samples traced.
    pub rays: u64,
    pub normaliser_rays: u64,
    /// The value the target is clamped at (infinite: none): `values` are clamped, the
    /// normaliser estimates the clamped mean, and the group's chains clamp their states.
    pub clamp: f32,
}

impl Bootstrap {
    /// Evaluates `settings.bootstrap` samples of group `k` in parallel; returns them with the
    /// rays traced.
    pub fn run<T: Target + Sync>(target: &T, settings: &ChainSettings, seed: u64, k: usize) -> (Self, u64) {
        let results: Vec<GroupValue> = (0..settings.bootstrap)
            .into_par_iter()
            .map_init(Scratch::default, |scratch, i| {
                let (state, rays) = scratch.evaluate(target, sampler_for(seed, k, i, settings));
                GroupValue { value: state.value(), invalid: state.invalid(), rays }
            })
            .collect();
        let (boot, rays) = Self::from_results(target, settings, seed, &results);
        (boot, rays + results.iter().map(|r| r.rays).sum::<u64>())
    }

    /// Evaluates `settings.bootstrap` samples of every group `k < groups` at once, where the
    /// groups' targets value them together ([`Target::values_groups_together`]): sample `i`
    /// is one point of primary sample space in every group ([`sampler_for`]), which one
    /// evaluation values under every group's target. Each group gets the bootstrap its own
    /// [`Self::run`] would give; returns them with the rays traced in all.
    pub fn run_groups<T: Target + Sync>(
        targets: &(impl Fn(usize) -> T + Sync),
        settings: &ChainSettings,
        seed: u64,
        groups: usize,
    ) -> (Vec<Self>, u64) {
        let target = targets(0);
        let per_sample: Vec<(Vec<GroupValue>, u64)> = (0..settings.bootstrap)
            .into_par_iter()
            .map_init(Scratch::<T::State>::default, |scratch, i| {
                let mut cx = scratch.lend(sampler_for(seed, 0, i, settings));
                let mut out = Vec::with_capacity(groups);
                let rays = target.value_groups(&mut cx, groups, &mut out);
                scratch.take_back(cx);
                (out, rays)
            })
            .collect();
        let mut rays: u64 = per_sample.iter().map(|p| p.1).sum();
        let boots = (0..groups)
            .map(|k| {
                let results: Vec<GroupValue> = per_sample.iter().map(|p| p.0[k]).collect();
                let (boot, r) = Self::from_results(&targets(k), settings, seed, &results);
                rays += r;
                boot
            })
            .collect();
        (boots, rays)
    }

    /// A group's bootstrap from its samples' values, invalid flags and rays, with the
    /// target's own normaliser drawn; returns it with the normaliser's rays.
    fn from_results<T: Target>(target: &T, settings: &ChainSettings, seed: u64, results: &[GroupValue]) -> (Self, u64) {
        let mut values: Vec<f32> = results.iter().map(|r| r.value).collect();
        let clamp = if settings.clamp > 0.0 && target.clampable() {
            clamp_threshold(&values, settings.clamp)
        } else {
            f32::INFINITY
        };
        if clamp.is_finite() {
            values.iter_mut().for_each(|v| *v = v.min(clamp));
        }
        let n = values.len().max(1) as f64;
        let mean = values.iter().map(|&v| f64::from(v)).sum::<f64>() / n;
        let sum2 = values.iter().map(|&v| f64::from(v).powi(2)).sum::<f64>();
        let invalid = results.iter().filter(|r| r.invalid).count() as u64;
        let rays = results.iter().map(|r| r.rays).sum();
        let per_fold = normaliser_samples(settings.bootstrap).div_ceil(FOLDS);
        let mut normaliser_rays = 0;
        let normaliser = (0..FOLDS)
            .map(|f| {
                target.normaliser(hash(&[seed, 0x4a1f, f as u64]), per_fold, clamp).map(|(m, r)| {
                    normaliser_rays += r;
                    m
                })
            })
            .collect();
        (Bootstrap { values, mean, sum2, invalid, normaliser, rays, normaliser_rays, clamp }, normaliser_rays)
    }

    /// The group's normalisation as far as the bootstrap knows it.
    pub fn b(&self) -> f64 {
        self.normalisation(&Moments::default()).0
    }

    /// The group's normalisation `b` and its relative standard error, from the bootstrap and
    /// the large steps' values (`large`), independent uniform samples of the target. Where the
    /// target has its own normaliser, the two independent estimates are combined with weights
    /// inversely proportional to their variances. Weights estimated from the very samples
    /// they weight bias the result low where the values are heavy-tailed: an estimate that
    /// missed its rare bright samples also reports a small variance and draws the weight to
    /// itself (glossy paths that every strategy samples poorly). So the weights are
    /// cross-fitted: the normaliser's samples fall into [`FOLDS`] independent folds; each
    /// fold's estimate is combined with the values' with weights measured on the other folds,
    /// and the folds' combinations are averaged. Every weight is then independent of what it
    /// weights, and the result is unbiased; the other folds hold most of the samples, so the
    /// weights are nearly those of all of them.
    ///
    /// Where the normaliser measures the target's own variance ([`NormaliserMoments`]), the
    /// values' weight comes from that measurement, so neither the bootstrap nor the large
    /// steps weight themselves, and every fold combines the mean of all of them. (The
    /// bootstrap alone, tens of thousands of one-strategy samples, can miss the bright paths
    /// one large step in a hundred thousand finds; weighted by the bootstrap's variance, such
    /// a step then decided the depth's normalisation.) Otherwise the bootstrap's values fall
    /// into folds too, each weighted with the variance of the other folds' values.
    ///
    /// The relative error reported is that of the combination as weighted, over all samples,
    /// with the values' variance the larger of the normaliser's measurement and the values' own
    /// spread. Where the normaliser's samples missed bright paths the bootstrap or the large
    /// steps found, its measurement is too small: the combination then follows the values and
    /// is as uncertain as their own spread says, which the inverse-variance error of the two
    /// weights would hide (a depth whose estimate is twice its true value reporting ± 3 %).
    pub fn normalisation(&self, large: &Moments) -> (f64, f64) {
        let mut plain = self.moments();
        plain.merge(large);
        let Some(folds) = &self.normaliser else { return plain.mean_and_rel_se() };
        let mut normaliser = NormaliserMoments { one_sample_sum2: Some(0.0), ..Default::default() };
        folds.iter().for_each(|m| normaliser.merge(m));
        let (a, rel_a) = normaliser.moments.mean_and_rel_se();
        let (b, rel_b) = plain.mean_and_rel_se();
        if a <= 0.0 {
            // The normaliser saw no light where the values did: theirs is the estimate.
            return (b, rel_b);
        } else if b <= 0.0 {
            return (a, rel_a);
        }
        let all_values = self.moments();
        let others = |all: &Moments, fold: &Moments| Moments {
            sum: all.sum - fold.sum,
            sum2: all.sum2 - fold.sum2,
            n: all.n - fold.n,
        };
        let mut mean = 0.0;
        for (f, norm) in folds.iter().enumerate() {
            let rest = NormaliserMoments {
                moments: others(&normaliser.moments, &norm.moments),
                one_sample_sum2: normaliser.one_sample_sum2.zip(norm.one_sample_sum2).map(|(all, f)| all - f),
                plain: None,
            };
            let ma = norm.moments.mean_and_rel_se().0;
            let wa = precision(&rest.moments, norm.moments.n);
            let (mb, wb) = match rest.target_variance() {
                Some(var) => (b, if var > 0.0 { plain.n as f64 / var } else { f64::INFINITY }),
                None => {
                    let values = self.fold_moments(f, folds.len());
                    let mut estimate = values;
                    estimate.merge(large);
                    (estimate.mean_and_rel_se().0, precision(&others(&all_values, &values), estimate.n))
                }
            };
            let combined = match (wa.is_infinite(), wb.is_infinite()) {
                (true, false) => ma,
                (false, true) => mb,
                (false, false) if wa + wb > 0.0 => (ma * wa + mb * wb) / (wa + wb),
                _ => 0.5 * (ma + mb),
            };
            mean += combined / folds.len() as f64;
        }
        let var_a = (a * rel_a).powi(2);
        let n = plain.n.max(1) as f64;
        // The values' variance as their weight took it, and as their own spread shows it.
        let weighed = normaliser.target_variance().unwrap_or_else(|| per_sample_variance(&all_values)) / n;
        let var_b = weighed.max(per_sample_variance(&plain) / n);
        (mean, if mean > 0.0 { combined_variance(var_a, weighed, var_b).sqrt() / mean } else { 0.0 })
    }

    /// Where a per-pixel map shapes the group's target: the unshaped normalisation (the
    /// depth's total luminance) as the normaliser's samples estimate it, with its relative
    /// standard error ([`NormaliserMoments::plain`]); `None` where the target is not shaped.
    pub fn plain_normalisation(&self) -> Option<(f64, f64)> {
        let mut all = Moments::default();
        for fold in self.normaliser.as_ref()? {
            all.merge(fold.plain.as_ref()?);
        }
        (all.n > 0).then(|| all.mean_and_rel_se())
    }

    /// The moments of the bootstrap values whose index is `f` modulo `folds`.
    fn fold_moments(&self, f: usize, folds: usize) -> Moments {
        let mut m = Moments::default();
        for &v in self.values.iter().skip(f).step_by(folds) {
            m.push(f64::from(v));
        }
        m
    }

    /// How unevenly the group's light is spread over the paths that carry it:
    /// `sqrt(E[f²] / E[f]²)` over the bootstrap's non-zero values, from 1 (all equal) up to a
    /// cap of 8. Zeros are left out: a target that is zero on most of primary sample space (a
    /// small light seen directly) is easy for a chain once found.
    pub fn spread(&self) -> f64 {
        let Moments { sum, sum2, n } = nonzero_moments(&self.values);
        if n == 0 || sum <= 0.0 {
            return 1.0;
        }
        (sum2 * n as f64 / (sum * sum)).sqrt().clamp(1.0, 8.0)
    }

    /// The acceptance a chain's large steps will have at equilibrium, estimated from the
    /// values ([`super::acceptance::large_step_acceptance`]).
    pub fn large_step_acceptance(&self) -> f64 {
        super::acceptance::large_step_acceptance(&self.values)
    }

    /// How many of the values are non-zero.
    pub fn nonzero(&self) -> u64 {
        count_nonzero(&self.values)
    }

    /// The moments of the values, to be refined with the large steps'.
    pub fn moments(&self) -> Moments {
        let n = self.values.len() as u64;
        Moments { sum: self.mean * n as f64, sum2: self.sum2, n }
    }

    /// The distribution chains draw their start states from: in proportion to the values.
    pub fn starts(&self) -> Distribution1D {
        Distribution1D::new(&self.values)
    }
}

/// The value a target whose bootstrap drew `values` is clamped at: `factor` times the mean of
/// the non-zero values (infinite where there are none). The mean of the non-zero values, not of
/// all: a target that is zero on most of primary sample space (a small light seen directly)
/// has large values wherever it is not, and those are its ordinary values, not its tail.
fn clamp_threshold(values: &[f32], factor: f64) -> f32 {
    let Moments { sum, n, .. } = nonzero_moments(values);
    if n == 0 { f32::INFINITY } else { (factor * sum / n as f64) as f32 }
}

/// How many of a group's bootstrap values are non-zero ([`Bootstrap::nonzero`]).
pub fn count_nonzero(values: &[f32]) -> u64 {
    values.iter().filter(|&&v| v > 0.0).count() as u64
}

/// The variance of the inverse-variance combination of two independent estimates weighted by
/// the variances `var_a` and `weighed`, where the second one's variance is in fact `var_b`: a
/// weight of zero variance takes its estimate alone.
fn combined_variance(var_a: f64, weighed: f64, var_b: f64) -> f64 {
    match (var_a > 0.0, weighed > 0.0) {
        (true, true) => {
            let (wa, wb) = (1.0 / var_a, 1.0 / weighed);
            (wa * wa * var_a + wb * wb * var_b) / ((wa + wb) * (wa + wb))
        }
        (false, true) => var_a,
        (true, false) => var_b,
        (false, false) => 0.25 * (var_a + var_b),
    }
}

/// The moments of the non-zero values among `values`.
fn nonzero_moments(values: &[f32]) -> Moments {
    let mut m = Moments::default();
    values.iter().filter(|&&v| v > 0.0).for_each(|&v| m.push(f64::from(v)));
    m
}

/// The precision (inverse variance) of a mean of `n` samples with the per-sample variance
/// measured on the samples `m` holds: infinite where they all had one non-zero value, zero
/// where they saw no light (nothing is known then).
fn precision(m: &Moments, n: u64) -> f64 {
    let var = per_sample_variance(m);
    if m.sum <= 0.0 {
        0.0
    } else if var == 0.0 {
        f64::INFINITY
    } else {
        n as f64 / var
    }
}

/// The unbiased per-sample variance of the samples `m` holds (0 for fewer than two).
fn per_sample_variance(m: &Moments) -> f64 {
    let (mean, rel) = m.mean_and_rel_se();
    (mean * rel).powi(2) * m.n as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    /// `n` values uniform on `[0.8·base, 1.2·base]` plus a rare spike: mean `base + spike·p`.
    fn draw(rng: &mut Pcg32, n: usize, base: f64, spike: f64, p: f64) -> Vec<f64> {
        (0..n).map(|_| base * (0.8 + 0.4 * rng.next_f64()) + if rng.next_f64() < p { spike } else { 0.0 }).collect()
    }

    /// A bootstrap of `values` beside the normaliser folds `normaliser`.
    fn bootstrap(values: Vec<f32>, normaliser: Vec<NormaliserMoments>) -> Bootstrap {
        let all = moments(&values.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
        let (mean, sum2) = (all.sum / all.n as f64, all.sum2);
        Bootstrap {
            mean,
            sum2,
            values,
            invalid: 0,
            rays: 0,
            normaliser_rays: 0,
            normaliser: Some(normaliser),
            clamp: f32::INFINITY,
        }
    }

    fn moments(values: &[f64]) -> Moments {
        let mut m = Moments::default();
        values.iter().for_each(|&v| m.push(v));
        m
    }

    /// Values that carry much of their mean in rare spikes (mean 1 for both estimators): over
    /// 4000 independent bootstraps the cross-fitted normalisation averages to 1 within four
    /// standard errors, while weights measured on the samples they weight (the combination it
    /// replaces, computed alongside) come out low by more than ten; so the test can tell.
    #[test]
    fn cross_fitted_normalisation_is_unbiased_on_heavy_tails() {
        let mut rng = Pcg32::new(17, 3);
        let (runs, n_values, n_normaliser) = (4000, 400, 96);
        let (mut cross, mut naive) = (Moments::default(), Moments::default());
        for _ in 0..runs {
            let values: Vec<f32> = draw(&mut rng, n_values, 0.5, 50.0, 0.01).iter().map(|&v| v as f32).collect();
            let norm = draw(&mut rng, n_normaliser, 0.8, 20.0, 0.01);
            let all = moments(&values.iter().map(|&v| f64::from(v)).collect::<Vec<_>>());
            let folds = norm.chunks(n_normaliser / FOLDS).map(|c| NormaliserMoments {
                moments: moments(c),
                one_sample_sum2: None,
                plain: None,
            });
            let boot = bootstrap(values, folds.collect());
            cross.push(boot.normalisation(&Moments::default()).0);
            let (a, rel_a) = moments(&norm).mean_and_rel_se();
            let (b, rel_b) = all.mean_and_rel_se();
            let (va, vb) = ((a * rel_a).powi(2), (b * rel_b).powi(2));
            naive.push((a * vb + b * va) / (va + vb));
        }
        let (mean, rel) = cross.mean_and_rel_se();
        assert!((mean - 1.0).abs() < 4.0 * mean * rel, "cross-fitted: {mean} ± {}", mean * rel);
        let (mean, rel) = naive.mean_and_rel_se();
        assert!(1.0 - mean > 10.0 * mean * rel, "self-weighted: {mean} ± {}", mean * rel);
    }

    /// `n` strategies' MIS-weighted values `Y_s` of one path: most paths share the light
    /// evenly, a rare one (probability `p`) carries a spike in one strategy. Returns the
    /// normaliser's estimate `Σ Y_s`, its `n Σ Y_s²`, and the one-strategy value `n·Y_S` of a
    /// strategy `S` picked uniformly (the target's own sample).
    fn path(rng: &mut Pcg32, n: usize, p: f64, spike: f64) -> PathSample {
        let spiky = (rng.next_f64() < p).then(|| (rng.next_f64() * n as f64) as usize);
        let y: Vec<f64> =
            (0..n).map(|s| if spiky == Some(s) { spike } else { (0.8 + 0.4 * rng.next_f64()) / n as f64 }).collect();
        let pick = ((rng.next_f64() * n as f64) as usize).min(n - 1);
        (y.iter().sum(), n as f64 * y.iter().map(|v| v * v).sum::<f64>(), n as f64 * y[pick])
    }

    /// A normaliser sample as [`path`] returns it.
    type PathSample = (f64, f64, f64);

    /// The heavy-tailed model of the tests below: a spike of `SPIKE` that every thousandth path
    /// carries in one of `STRATEGIES` strategies.
    const STRATEGIES: usize = 4;
    const SPIKE_PROBABILITY: f64 = 0.001;
    const SPIKE: f64 = 200.0;
    /// The normalisation the heavy-tailed samples estimate.
    const HEAVY_TAILED_TRUTH: f64 = 1.0 + SPIKE_PROBABILITY * (SPIKE - 1.0 / STRATEGIES as f64);
    /// The bootstrap values per heavy-tailed bootstrap.
    const HEAVY_TAILED_VALUES: usize = 400;

    /// One bootstrap's worth of heavy-tailed samples: [`HEAVY_TAILED_VALUES`] values, the
    /// moments of 1600 large steps, and 96 normaliser samples as [`path`] returns them.
    fn heavy_tailed(rng: &mut Pcg32) -> (Vec<f32>, Moments, Vec<PathSample>) {
        let mut draw = || path(rng, STRATEGIES, SPIKE_PROBABILITY, SPIKE);
        let values = (0..HEAVY_TAILED_VALUES).map(|_| draw().2 as f32).collect();
        let large = moments(&(0..1600).map(|_| draw().2).collect::<Vec<_>>());
        let norm = (0..96).map(|_| draw()).collect();
        (values, large, norm)
    }

    /// The normaliser samples `norm` in [`FOLDS`] folds, with the target's variance measured
    /// where `with_variance` is set.
    fn folds(norm: &[PathSample], with_variance: bool) -> Vec<NormaliserMoments> {
        norm.chunks(norm.len() / FOLDS)
            .map(|c| NormaliserMoments {
                moments: moments(&c.iter().map(|v| v.0).collect::<Vec<_>>()),
                one_sample_sum2: with_variance.then(|| c.iter().map(|v| v.1).sum()),
                plain: None,
            })
            .collect()
    }

    /// Heavy-tailed one-strategy values (a spike that every thousandth path carries in one of
    /// four strategies): with the target's variance measured on the normaliser's samples the
    /// normalisation stays unbiased over 4000 independent bootstraps and has less than 0.8 of
    /// the mean squared error (0.67 here) of the weights from the bootstrap's own variance,
    /// which a spike among the large steps escapes.
    #[test]
    fn the_normalisers_measure_of_the_targets_variance_lowers_the_error() {
        let mut rng = Pcg32::new(23, 5);
        let (mut measured, mut own) = (Moments::default(), Moments::default());
        let (mut se_measured, mut se_own, truth) = (0.0, 0.0, HEAVY_TAILED_TRUTH);
        for _ in 0..4000 {
            let (values, large, norm) = heavy_tailed(&mut rng);
            let mut boot = bootstrap(values, folds(&norm, true));
            let b = boot.normalisation(&large).0;
            measured.push(b);
            se_measured += (b - truth).powi(2);
            boot.normaliser = Some(folds(&norm, false));
            let b = boot.normalisation(&large).0;
            own.push(b);
            se_own += (b - truth).powi(2);
        }
        let (mean, rel) = measured.mean_and_rel_se();
        assert!((mean - truth).abs() < 4.0 * mean * rel, "measured variance: {mean} ± {} vs {truth}", mean * rel);
        assert!(se_measured < 0.8 * se_own, "squared errors: {se_measured} (measured) vs {se_own} (own)");
    }

    /// The reported error is honest where the values caught a spike the normaliser missed: on
    /// the heavy-tailed values above, among 4000 independent bootstraps, the estimates above the
    /// truth by more than 10 % (the values caught a spike) lie within two reported standard
    /// errors of it in at least 90 % of runs. The inverse-variance error of the two weights
    /// (the formula this replaced, computed alongside) covers under half of them: it takes the
    /// values' variance from the normaliser, which saw no spike.
    #[test]
    fn the_reported_error_covers_estimates_the_values_spike_drove_up() {
        let mut rng = Pcg32::new(29, 7);
        let (mut high, mut covered, mut covered_before) = (0, 0, 0);
        let truth = HEAVY_TAILED_TRUTH;
        for _ in 0..4000 {
            let (values, large, norm) = heavy_tailed(&mut rng);
            let measured = folds(&norm, true);
            let mut all = NormaliserMoments { one_sample_sum2: Some(0.0), ..Default::default() };
            measured.iter().for_each(|f| all.merge(f));
            let boot = bootstrap(values, measured);
            let (b, rel) = boot.normalisation(&large);
            if b <= 1.1 * truth {
                continue;
            }
            high += 1;
            covered += usize::from((b - truth).abs() <= 2.0 * b * rel);
            let (a, rel_a) = all.moments.mean_and_rel_se();
            let var_a = (a * rel_a).powi(2);
            let var_b = all.target_variance().unwrap() / (large.n + HEAVY_TAILED_VALUES as u64) as f64;
            let before = (var_a * var_b / (var_a + var_b)).sqrt();
            covered_before += usize::from((b - truth).abs() <= 2.0 * before);
        }
        assert!(high > 400, "{high} runs above the truth");
        let share = |c: usize| c as f64 / high as f64;
        assert!(share(covered) >= 0.9, "covered {covered} of {high}");
        assert!(share(covered_before) < 0.5, "before: covered {covered_before} of {high}");
    }
}
