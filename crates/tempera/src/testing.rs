//! Statistical test helpers: a chi-square goodness-of-fit test of a direction sampler against
//! its claimed density, binned over the sphere (after Mitsuba's `chi2` test suite).

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

fn bin_of(w: Vec3) -> usize {
    let theta = f64::from(w.z.clamp(-1.0, 1.0)).acos();
    let mut phi = f64::from(w.y).atan2(f64::from(w.x));
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let t = ((theta / PI * THETA_BINS as f64) as usize).min(THETA_BINS - 1);
    let p = ((phi / (2.0 * PI) * PHI_BINS as f64) as usize).min(PHI_BINS - 1);
    t * PHI_BINS + p
}

/// Integrates `pdf` over every (θ, φ) bin with a midpoint rule.
fn bin_integrals(pdf: &dyn Fn(Vec3) -> f64) -> Vec<f64> {
    let (dt, dp) = (PI / THETA_BINS as f64, 2.0 * PI / PHI_BINS as f64);
    let mut out = vec![0.0; THETA_BINS * PHI_BINS];
    for t in 0..THETA_BINS {
        for p in 0..PHI_BINS {
            let mut sum = 0.0;
            for i in 0..SUB {
                let theta = (t as f64 + (i as f64 + 0.5) / SUB as f64) * dt;
                for j in 0..SUB {
                    let phi = (p as f64 + (j as f64 + 0.5) / SUB as f64) * dp;
                    let w = Vec3::new(
                        (theta.sin() * phi.cos()) as f32,
                        (theta.sin() * phi.sin()) as f32,
                        theta.cos() as f32,
                    );
                    sum += pdf(w) * theta.sin();
                }
            }
            out[t * PHI_BINS + p] = sum * dt * dp / (SUB * SUB) as f64;
        }
    }
    out
}

/// Draws `n` samples and tests their histogram against the integral of `pdf` per bin. The test
/// is conditional on the number of produced directions, so samplers that sometimes fail (or
/// produce delta lobes, which the caller filters out) are handled.
pub fn chi2_sphere(
    n: usize,
    seed: u64,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
) -> Chi2Result {
    let mut rng = Pcg32::new(seed, 0x5eed);
    let mut counts = vec![0u64; THETA_BINS * PHI_BINS];
    let mut produced = 0u64;
    for _ in 0..n {
        let u = Vec2::new(rng.next_f32(), rng.next_f32());
        let uc = rng.next_f32();
        if let Some(w) = sample(u, uc) {
            counts[bin_of(w)] += 1;
            produced += 1;
        }
    }
    let integrals = bin_integrals(&pdf);
    let total: f64 = integrals.iter().sum();
    let (mut chi2, mut dof) = (0.0, 0i64);
    let (mut pool_obs, mut pool_exp) = (0.0, 0.0);
    for (obs, integral) in counts.iter().zip(&integrals) {
        let exp = produced as f64 * integral / total;
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
        chi2 = f64::INFINITY;
    }
    let dist = ChiSquared::new((dof - 1).max(1) as f64).expect("valid degrees of freedom");
    let p_value = if chi2.is_finite() {
        1.0 - dist.cdf(chi2)
    } else {
        0.0
    };
    Chi2Result {
        p_value,
        pdf_integral: total,
        sampled_fraction: produced as f64 / n as f64,
    }
}
