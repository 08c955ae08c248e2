//! Statistical test helpers: a chi-square goodness-of-fit test of a direction sampler against
//! its claimed density, binned over the sphere (after Mitsuba's `chi2` test suite).

use crate::math::frame::Frame;
use crate::math::rng::Pcg32;
use crate::math::{Vec2, Vec3};
use statrs::distribution::{ChiSquared, ContinuousCDF};
use std::f64::consts::PI;

const THETA_BINS: usize = 24;
const PHI_BINS: usize = 48;
const SUB: usize = 16;

/// Outcome of [`chi2_sphere`].
#[derive(Debug)]
pub struct Chi2Result {
    pub p_value: f64,
    /// Integral of the density over the sphere.
    pub pdf_integral: f64,
    /// Fraction of sampler calls that produced a (non-delta) direction.
    pub sampled_fraction: f64,
}

/// How directions are binned: the whole sphere (bins uniform in θ), or a spherical cap
/// `cos θ ≥ cos_min` around `frame.n` (bins uniform in cos θ, so a density that is discontinuous
/// only at the cap's rim, such as a sphere light's cone, is integrated exactly).
#[derive(Clone, Copy, Debug)]
pub enum Binning {
    Sphere,
    Cap { frame: Frame, cos_min: f64 },
}

impl Binning {
    /// Polar coordinate mapped to `[0, 1)` and azimuth in radians, or `None` outside a cap.
    fn coords(&self, w: Vec3) -> Option<(f64, f64)> {
        let (w, a) = match *self {
            Binning::Sphere => (w, f64::from(w.z.clamp(-1.0, 1.0)).acos() / PI),
            Binning::Cap { frame, cos_min } => {
                let l = frame.to_local(w);
                (l, (1.0 - f64::from(l.z)) / (1.0 - cos_min))
            }
        };
        let mut phi = f64::from(w.y).atan2(f64::from(w.x));
        if phi < 0.0 {
            phi += 2.0 * PI;
        }
        (a <= 1.0).then_some((a, phi))
    }

    /// Direction at polar coordinate `a ∈ [0,1]`, azimuth `phi`, and the solid angle per unit
    /// `(a, phi)`.
    fn direction(&self, a: f64, phi: f64) -> (Vec3, f64) {
        let (cos, jac) = match *self {
            Binning::Sphere => ((a * PI).cos(), (a * PI).sin() * PI),
            Binning::Cap { cos_min, .. } => (1.0 - a * (1.0 - cos_min), 1.0 - cos_min),
        };
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        let l = Vec3::new((sin * phi.cos()) as f32, (sin * phi.sin()) as f32, cos as f32);
        let w = match *self {
            Binning::Sphere => l,
            Binning::Cap { frame, .. } => frame.to_world(l),
        };
        (w, jac)
    }

    fn bin_of(&self, w: Vec3) -> Option<usize> {
        let (a, phi) = self.coords(w)?;
        let t = ((a * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
        let p = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
        Some(t * PHI_BINS + p)
    }

    /// Integrates `pdf` over every bin with a midpoint rule.
    fn integrals(&self, pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
        let (da, dp) = (1.0 / THETA_BINS as f64, 2.0 * PI / PHI_BINS as f64);
        let mut out = vec![0.0; THETA_BINS * PHI_BINS];
        for t in 0..THETA_BINS {
            for p in 0..PHI_BINS {
                let mut sum = 0.0;
                for i in 0..SUB {
                    let a = (t as f64 + (i as f64 + 0.5) / SUB as f64) * da;
                    for j in 0..SUB {
                        let phi = (p as f64 + (j as f64 + 0.5) / SUB as f64) * dp;
                        let (w, jac) = self.direction(a, phi);
                        sum += pdf(w) * jac;
                    }
                }
                out[t * PHI_BINS + p] = sum * da * dp / (SUB * SUB) as f64;
            }
        }
        out
    }
}

/// p-value of Pearson's chi-square test of observed counts against expected counts; bins
/// expecting fewer than five are pooled.
pub fn chi2_p_value(observed: &[u64], expected: &[f64]) -> f64 {
    let (mut chi2, mut dof) = (0.0, 0i64);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for (obs, &exp) in observed.iter().zip(expected) {
        if exp < 5.0 {
            pool_obs += *obs as f64;
            pool_exp += exp;
        } else {
            chi2 += (*obs as f64 - exp).powi(2) / exp;
            dof += 1;
        }
    }
    if pool_exp >= 5.0 {
        chi2 += (pool_obs - pool_exp).powi(2) / pool_exp;
        dof += 1;
    } else if pool_obs > 20.0 {
        // Many samples where the density claims (almost) nothing: a certain failure.
        return 0.0;
    }
    let dist = ChiSquared::new((dof - 1).max(1) as f64).expect("valid degrees of freedom");
    1.0 - dist.cdf(chi2)
}

/// Draws `n` samples and tests their histogram against the integral of `pdf` per bin. The test
/// is conditional on the number of produced directions, so samplers that sometimes fail (or
/// produce delta lobes, which the caller filters out) are handled.
pub fn chi2_sphere(
    n: usize,
    seed: u64,
    sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
) -> Chi2Result {
    chi2_directions(Binning::Sphere, n, seed, sample, pdf)
}

/// [`chi2_sphere`] with a chosen binning; samples outside a cap count as a failure.
pub fn chi2_directions(
    binning: Binning,
    n: usize,
    seed: u64,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
) -> Chi2Result {
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut counts = vec![0u64; THETA_BINS * PHI_BINS];
    let (mut produced, mut outside) = (0u64, 0u64);
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let uc = rng.next_f32();
        if let Some(w) = sample(u, uc) {
            match binning.bin_of(w) {
                Some(bin) => counts[bin] += 1,
                None => outside += 1,
            }
            produced += 1;
        }
    }
    let integrals = binning.integrals(&pdf);
    let total: f64 = integrals.iter().sum();
    let expected: Vec<f64> = integrals.iter().map(|i| produced as f64 * i / total).collect();
    let p_value = if outside > 0 { 0.0 } else { chi2_p_value(&counts, &expected) };
    Chi2Result { p_value, pdf_integral: total, sampled_fraction: produced as f64 / n as f64 }
}

/// The moments of MMLT's depth-`k` target over `n` independent primary-sample-space samples
/// (the bootstrap's samplers, seeded by `seed`): the plain estimate of `b_k` that lower-variance
/// normalisers are held to.
pub fn mmlt_target_moments(scene: &crate::scene::Scene, k: usize, seed: u64, n: usize) -> crate::mcmc::Moments {
    let mut moments = crate::mcmc::Moments::default();
    for v in mmlt_target_values(scene, k, seed, n) {
        moments.push(v);
    }
    moments
}

/// The values of MMLT's depth-`k` target at `n` independent uniform samples (the bootstrap's
/// samples of seed `seed`).
pub fn mmlt_target_values(scene: &crate::scene::Scene, k: usize, seed: u64, n: usize) -> Vec<f64> {
    shaped_target_values(scene, k, seed, n, None)
}

/// [`mmlt_target_values`] of the target shaped per pixel by `importance`
/// ([`crate::mcmc::importance`]; `None`: MMLT's own).
pub fn shaped_target_values(
    scene: &crate::scene::Scene,
    k: usize,
    seed: u64,
    n: usize,
    importance: Option<&crate::mcmc::importance::ImportanceMap>,
) -> Vec<f64> {
    use crate::mcmc::{ChainSettings, EvalContext, evaluate, sampler_for};
    use rayon::prelude::*;
    let settings = ChainSettings::new(0, 0, 0.01, 0.3);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let mut cx = EvalContext::new(sampler_for(seed, k, i, &settings));
            f64::from(evaluate(scene, k, &mut cx, importance).f)
        })
        .collect()
}

/// Asserts that two independent estimates of one mean agree within four combined standard
/// errors; returns their relative standard errors.
pub fn assert_same_mean(name: &str, a: &crate::mcmc::Moments, b: &crate::mcmc::Moments) -> (f64, f64) {
    let ((ma, ea), (mb, eb)) = (a.mean_and_rel_se(), b.mean_and_rel_se());
    let sigma = ((ma * ea).powi(2) + (mb * eb).powi(2)).sqrt();
    assert!((ma - mb).abs() < 4.0 * sigma, "{name}: {ma} ± {ea} vs {mb} ± {eb}");
    (ea, eb)
}

/// A Cornell box filled with a scattering, absorbing, chromatic medium: every surface has it
/// on both sides and the camera sits in it, so light subpaths start in it too.
pub fn foggy_cornell_box(size: u32) -> crate::scene::Scene {
    use crate::math::Rgb;
    use crate::medium::{Medium, MediumInterface};
    let mut b = crate::scenes::cornell_box(size, size);
    let m = b.add_medium(Medium { sigma_a: Rgb::splat(0.15), sigma_s: Rgb::new(0.6, 0.45, 0.3), g: 0.4 });
    for shape in 0..b.shape_count() {
        b.set_shape_medium(shape, MediumInterface { inside: Some(m), outside: Some(m) });
    }
    b.set_camera_medium(Some(m));
    b.build().unwrap()
}

/// A Cornell box of `size`² pixels seen through a thin lens of `lens_radius` focused at 1.5
/// (the boxes far out of focus; a pinhole at radius 0).
pub fn thin_lens_cornell_box(size: u32, lens_radius: f32) -> crate::scene::Scene {
    let mut b = crate::scenes::cornell_box(size, size);
    let mut camera =
        crate::camera::CameraDesc::look_at(Vec3::new(0.0, 1.0, 3.9), Vec3::new(0.0, 1.0, 0.0), Vec3::Y, 38.0);
    camera.lens_radius = lens_radius;
    camera.focal_distance = 1.5;
    b.set_camera(camera);
    b.build().unwrap()
}
