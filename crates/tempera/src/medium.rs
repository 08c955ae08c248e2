//! Homogeneous participating media (pbrt-v4 §11.1 and §14.1, its `homogeneous` medium):
//! absorption `σa` and scattering `σs` per RGB channel, constant in space, with a
//! Henyey–Greenstein phase function of asymmetry `g`. Media fill the space between surfaces
//! that carry a [`MediumInterface`]; a ray knows the medium it travels in from the last such
//! surface it crossed (or the camera's).
//!
//! Free-flight distances are sampled in proportion to `σt·exp(−σt·t)` of one channel picked
//! uniformly, and weighted by the density averaged over the three channels (the one-sample
//! MIS estimator of chromatic media, after pbrt-v4's spectral MIS for distance sampling), so a
//! medium whose channels differ stays unbiased in every channel.

use crate::math::frame::Frame;
use crate::math::{Rgb, Vec2, Vec3};
use std::f32::consts::PI;

/// A homogeneous medium: coefficients per unit length.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Medium {
    pub sigma_a: Rgb,
    pub sigma_s: Rgb,
    /// Henyey–Greenstein asymmetry in `(−1, 1)`.
    pub g: f32,
}

/// The media on the two sides of a surface (`None`: vacuum). `inside` lies opposite the
/// surface normal, `outside` on its side.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct MediumInterface {
    pub inside: Option<u32>,
    pub outside: Option<u32>,
}

impl MediumInterface {
    /// The medium a ray leaving the surface along `w` enters (`n`: the surface normal).
    pub fn towards(&self, n: Vec3, w: Vec3) -> Option<u32> {
        if w.dot(n) > 0.0 { self.outside } else { self.inside }
    }
}

/// Where a sampled free flight ended and the weight to multiply the path's throughput by.
#[derive(Clone, Copy, Debug)]
pub enum Flight {
    /// Scattered at distance `t` inside the medium; `weight` = `σs·T(t)/p(t)`.
    Scatter { t: f32, weight: Rgb },
    /// Reached the surface (or infinity) at `t_max`; `weight` = `T(t_max)/P(t ≥ t_max)`.
    Through { weight: Rgb },
}

impl Medium {
    pub fn sigma_t(&self) -> Rgb {
        self.sigma_a + self.sigma_s
    }

    /// The transmittance over a distance `t` (zero in any absorbing channel at infinity).
    pub fn transmittance(&self, t: f32) -> Rgb {
        let s = self.sigma_t();
        let tr = |sigma: f32| if sigma <= 0.0 { 1.0 } else { (-sigma * t).exp() };
        Rgb::new(tr(s.x), tr(s.y), tr(s.z))
    }

    /// Samples a free flight along a ray whose next surface is at `t_max` (infinite when
    /// there is none); `channel` picks the channel whose density proposes the distance, `u`
    /// the distance.
    pub fn sample_flight(&self, channel: f32, u: f32, t_max: f32) -> Flight {
        let s = self.sigma_t();
        let c = ((channel * 3.0) as usize).min(2);
        let t = if s[c] > 0.0 { -(1.0 - u).max(f32::MIN_POSITIVE).ln() / s[c] } else { f32::INFINITY };
        if t < t_max {
            let tr = self.transmittance(t);
            let pdf = (s * tr).to_array().iter().sum::<f32>() / 3.0;
            let weight = if pdf > 0.0 { self.sigma_s * tr / pdf } else { Rgb::ZERO };
            Flight::Scatter { t, weight }
        } else {
            let tr = self.transmittance(t_max);
            let p = tr.to_array().iter().sum::<f32>() / 3.0;
            Flight::Through { weight: if p > 0.0 { tr / p } else { Rgb::ZERO } }
        }
    }

    /// The phase function's value (and density) for `wo`, `wi` both pointing away from the
    /// scattering point.
    pub fn phase(&self, wo: Vec3, wi: Vec3) -> f32 {
        hg(wo, wi, self.g)
    }

    /// Samples the phase function around `wo`: `wi` and its density.
    pub fn sample_phase(&self, wo: Vec3, u: Vec2) -> (Vec3, f32) {
        sample_hg(wo, self.g, u)
    }
}

/// The Henyey–Greenstein phase function for directions `wo`, `wi` both pointing away from
/// the scattering point (`g > 0` scatters forward, towards `−wo`).
pub(crate) fn hg(wo: Vec3, wi: Vec3, g: f32) -> f32 {
    let denom = 1.0 + g * g + 2.0 * g * wo.dot(wi);
    (1.0 - g * g) / (4.0 * PI * denom * denom.max(0.0).sqrt())
}

/// Samples the Henyey–Greenstein phase function around `wo`; returns `wi` and its density
/// (the phase function's value).
pub(crate) fn sample_hg(wo: Vec3, g: f32, u: Vec2) -> (Vec3, f32) {
    // Cosine of the angle to the forward direction −wo, inverted from the HG distribution.
    let cos = if g.abs() < 1e-3 {
        1.0 - 2.0 * u.x
    } else {
        let s = (1.0 - g * g) / (1.0 - g + 2.0 * g * u.x);
        ((1.0 + g * g - s * s) / (2.0 * g)).clamp(-1.0, 1.0)
    };
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * u.y;
    let frame = Frame::from_z(-wo);
    let wi = frame.to_world(Vec3::new(sin * phi.cos(), sin * phi.sin(), cos)).normalize();
    (wi, hg(wo, wi, g))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    /// Free flights through a chromatic slab: the mean weight of the flights that get
    /// through is the transmittance in every channel, and the scattering weights sum to the
    /// single-scattering albedo times the interaction probability.
    #[test]
    fn free_flights_are_unbiased_in_every_channel() {
        let m = Medium { sigma_a: Rgb::new(0.1, 0.5, 2.0), sigma_s: Rgb::new(0.9, 0.5, 0.2), g: 0.0 };
        let d = 0.8;
        let mut rng = Pcg32::new(5, 1);
        let n = 400_000;
        let (mut through, mut scatter) = (Rgb::ZERO, Rgb::ZERO);
        for _ in 0..n {
            match m.sample_flight(rng.next_f32(), rng.next_f32(), d) {
                Flight::Through { weight } => through += weight,
                Flight::Scatter { weight, .. } => scatter += weight,
            }
        }
        let (through, scatter) = (through / n as f32, scatter / n as f32);
        let t = m.transmittance(d);
        let albedo = m.sigma_s / m.sigma_t();
        for c in 0..3 {
            assert!((through[c] - t[c]).abs() < 0.01, "channel {c}: {} vs {}", through[c], t[c]);
            let expected = albedo[c] * (1.0 - t[c]);
            assert!((scatter[c] - expected).abs() < 0.01, "channel {c}: {} vs {expected}", scatter[c]);
        }
    }

    /// The phase function integrates to one and its samples follow it (mean cosine `g`).
    #[test]
    fn henyey_greenstein_is_normalised_and_sampled_exactly() {
        let mut rng = Pcg32::new(9, 2);
        let wo = Vec3::new(0.3, -0.2, 0.9).normalize();
        for g in [-0.6f32, 0.0, 0.4, 0.9] {
            let n = 200_000;
            let (mut integral, mut mean_cos) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let u = Vec2::new(rng.next_f32(), rng.next_f32());
                let w = crate::math::warp::uniform_sphere(u);
                integral += f64::from(hg(wo, w, g)) * 4.0 * std::f64::consts::PI;
                let (wi, p) = sample_hg(wo, g, Vec2::new(rng.next_f32(), rng.next_f32()));
                assert!((p - hg(wo, wi, g)).abs() <= 1e-4 * p.max(1.0));
                mean_cos += f64::from((-wo).dot(wi));
            }
            let (integral, mean_cos) = (integral / n as f64, mean_cos / n as f64);
            assert!((integral - 1.0).abs() < 0.03, "g {g}: integral {integral}");
            assert!((mean_cos - f64::from(g)).abs() < 0.01, "g {g}: mean cosine {mean_cos}");
        }
    }
}
