//! Conductors: GGX microfacet reflection with complex Fresnel, perfectly specular when alpha is
//! (near) zero (pbrt-v4 §9.4, §9.6).

use super::{BsdfSample, Ggx, SampleInverse, fresnel, same_hemisphere};
use crate::math::{Rgb, Vec2, Vec3};

#[derive(Clone, Copy, Debug)]
pub struct Conductor {
    pub distribution: Ggx,
    pub eta: Rgb,
    pub k: Rgb,
    /// Multiplier of the reflectance (Mitsuba's `specularReflectance`; 1 for physical metals).
    pub tint: Rgb,
}

impl Conductor {
    #[inline]
    fn fresnel(&self, cos: f32) -> Rgb {
        fresnel::conductor_rgb(cos.abs(), self.eta, self.k) * self.tint
    }

    fn microfacet(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let (cos_o, cos_i) = (wo.z.abs(), wi.z.abs());
        if cos_o == 0.0 || cos_i == 0.0 {
            return Rgb::ZERO;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return Rgb::ZERO;
        }
        let wm = wm.normalize();
        let d = &self.distribution;
        self.fresnel(wo.dot(wm)) * (d.d(wm) * d.g(wo, wi) / (4.0 * cos_o * cos_i))
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if !same_hemisphere(wo, wi) || self.distribution.effectively_smooth() {
            return Rgb::ZERO;
        }
        self.microfacet(wo, wi)
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !same_hemisphere(wo, wi) || self.distribution.effectively_smooth() {
            return 0.0;
        }
        let wm = wo + wi;
        if wm.length_squared() == 0.0 {
            return 0.0;
        }
        let wm = wm.normalize();
        let wm = if wm.z < 0.0 { -wm } else { wm };
        self.distribution.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }

    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.distribution.effectively_smooth() {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample {
                f: self.fresnel(wi.z) / wi.z.abs(),
                wi,
                pdf: 1.0,
                delta: true,
                transmission: false,
                proportional: false,
            });
        }
        let wm = self.distribution.sample_wm(wo, u);
        let wi = crate::math::reflect(wo, wm);
        if !same_hemisphere(wo, wi) {
            return None;
        }
        let pdf = self.distribution.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
        Some(BsdfSample { f: self.microfacet(wo, wi), wi, pdf, delta: false, transmission: false, proportional: false })
    }

    /// The numbers with which [`Self::sample`] produces `wi` from `wo`: none matter for a
    /// smooth conductor (whose one direction the caller checks), the visible normal's sample
    /// for a rough one.
    pub fn sample_inverse(&self, wo: Vec3, wi: Vec3) -> Option<SampleInverse> {
        if wo.z == 0.0 || !same_hemisphere(wo, wi) {
            return None;
        }
        if self.distribution.effectively_smooth() {
            return Some(SampleInverse { uc: None, u: None });
        }
        let wm = (wo + wi).normalize();
        let wm = if wm.z < 0.0 { -wm } else { wm };
        let u = self.distribution.sample_wm_inverse(wo, wm)?;
        Some(SampleInverse { uc: None, u: Some(u) })
    }
}
