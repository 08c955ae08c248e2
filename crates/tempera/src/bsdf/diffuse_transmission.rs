//! Lambertian reflection plus Lambertian transmission (pbrt-v4 §9.2's `DiffuseTransmission`
//! BxDF): `r/π` on the side of `wo`, `t/π` on the other; lobes are chosen in proportion to the
//! larger channel of each.

use super::{BsdfSample, same_hemisphere};
use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::math::{Rgb, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct DiffuseTransmission {
    pub reflectance: Rgb,
    pub transmittance: Rgb,
}

impl DiffuseTransmission {
    fn reflect_probability(&self) -> f32 {
        let (r, t) = (self.reflectance.max_element(), self.transmittance.max_element());
        if r + t > 0.0 { r / (r + t) } else { 0.5 }
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        if same_hemisphere(wo, wi) { self.reflectance * FRAC_1_PI } else { self.transmittance * FRAC_1_PI }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let pr = self.reflect_probability();
        let p = if same_hemisphere(wo, wi) { pr } else { 1.0 - pr };
        p * cosine_hemisphere_pdf(wi.z.abs())
    }

    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let pr = self.reflect_probability();
        let mut wi = cosine_hemisphere(u);
        let reflect = uc < pr;
        // Reflection stays on wo's side, transmission crosses to the other.
        if (wo.z < 0.0) == reflect {
            wi.z = -wi.z;
        }
        let (f, p) = if reflect { (self.reflectance, pr) } else { (self.transmittance, 1.0 - pr) };
        Some(BsdfSample {
            f: f * FRAC_1_PI,
            wi,
            pdf: p * cosine_hemisphere_pdf(wi.z.abs()),
            delta: false,
            transmission: !reflect,
            proportional: false,
        })
    }
}
