//! Lambertian reflection with cosine-weighted sampling (pbrt-v4 §9.2).

use super::{BsdfSample, SampleInverse, same_hemisphere};
use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_inverse, cosine_hemisphere_pdf};
use crate::math::{Rgb, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct Diffuse {
    pub reflectance: Rgb,
}

impl Diffuse {
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if same_hemisphere(wo, wi) { self.reflectance * FRAC_1_PI } else { Rgb::ZERO }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if same_hemisphere(wo, wi) { cosine_hemisphere_pdf(wi.z.abs()) } else { 0.0 }
    }

    pub fn sample(&self, wo: Vec3, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let mut wi = cosine_hemisphere(u);
        if wo.z < 0.0 {
            wi.z = -wi.z;
        }
        Some(BsdfSample {
            f: self.reflectance * FRAC_1_PI,
            wi,
            pdf: cosine_hemisphere_pdf(wi.z.abs()),
            delta: false,
            transmission: false,
            proportional: false,
        })
    }

    /// The numbers with which [`Self::sample`] produces `wi` from `wo`.
    pub fn sample_inverse(&self, wo: Vec3, wi: Vec3) -> Option<SampleInverse> {
        if wo.z == 0.0 || !same_hemisphere(wo, wi) {
            return None;
        }
        let u = cosine_hemisphere_inverse(Vec3::new(wi.x, wi.y, wi.z.abs()));
        Some(SampleInverse { uc: None, u: Some(u) })
    }
}
