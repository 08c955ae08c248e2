//! A coated diffuse ("plastic") BSDF: a smooth or GGX-rough dielectric coat over a Lambertian
//! base, after Mitsuba 0.6's `plastic`/`roughplastic` (Jakob, Mitsuba documentation §8.2). The
//! base is attenuated by the coat's Fresnel transmittance on the way in and out and renormalised
//! for internal reflections with the diffuse Fresnel reflectance `Fdr` of the inner side.
//! Two-sided: the lower side mirrors the upper.

use super::{BsdfSample, Ggx, fresnel};
use crate::math::warp::{cosine_hemisphere, cosine_hemisphere_pdf};
use crate::math::{Rgb, Vec2, Vec3};
use std::f32::consts::FRAC_1_PI;

#[derive(Clone, Copy, Debug)]
pub struct Plastic {
    pub distribution: Ggx,
    /// Coat index of refraction (relative to the outside).
    pub eta: f32,
    /// Effective diffuse albedo after the internal-reflection renormalisation.
    pub diffuse: Rgb,
    pub specular: f32,
    /// Probability weight of the specular lobe before Fresnel (from the reflectance averages).
    pub specular_weight: f32,
}

/// Precomputed coat constants, shared by every BSDF built from one material.
#[derive(Clone, Copy, Debug)]
pub struct PlasticCoat {
    pub eta: f32,
    /// `Fdr` on the inner side of the coat.
    pub fdr_inner: f32,
    pub nonlinear: bool,
}

impl PlasticCoat {
    pub fn new(eta: f32, nonlinear: bool) -> Self {
        Self { eta, fdr_inner: fresnel::diffuse_reflectance(1.0 / eta), nonlinear }
    }
}

impl Plastic {
    pub fn new(distribution: Ggx, coat: &PlasticCoat, reflectance: Rgb, specular: f32) -> Self {
        let reflectance = reflectance.clamp(Rgb::ZERO, Rgb::ONE);
        let diffuse = if coat.nonlinear {
            reflectance / (Rgb::ONE - reflectance * coat.fdr_inner)
        } else {
            reflectance / (1.0 - coat.fdr_inner)
        } / (coat.eta * coat.eta);
        let d_avg = reflectance.element_sum() / 3.0;
        let s = specular.max(0.0);
        let specular_weight = if s + d_avg > 0.0 { s / (s + d_avg) } else { 1.0 };
        Self { distribution, eta: coat.eta, diffuse, specular: s, specular_weight }
    }

    #[inline]
    fn upper(wo: Vec3, wi: Vec3) -> Option<(Vec3, Vec3)> {
        let flip = |w: Vec3| {
            if wo.z < 0.0 { Vec3::new(w.x, w.y, -w.z) } else { w }
        };
        let (o, i) = (flip(wo), flip(wi));
        (o.z > 0.0 && i.z > 0.0).then_some((o, i))
    }

    #[inline]
    fn specular_probability(&self, cos_o: f32) -> f32 {
        let f = fresnel::dielectric(cos_o, self.eta) * self.specular_weight;
        let d = (1.0 - fresnel::dielectric(cos_o, self.eta)) * (1.0 - self.specular_weight);
        if f + d > 0.0 { f / (f + d) } else { 0.0 }
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3) -> Rgb {
        let Some((wo, wi)) = Self::upper(wo, wi) else {
            return Rgb::ZERO;
        };
        let fo = fresnel::dielectric(wo.z, self.eta);
        let fi = fresnel::dielectric(wi.z, self.eta);
        let mut f = self.diffuse * ((1.0 - fo) * (1.0 - fi) * FRAC_1_PI);
        if !self.distribution.effectively_smooth() {
            let wm = (wo + wi).normalize();
            let d = &self.distribution;
            let spec = d.d(wm) * d.g(wo, wi) * fresnel::dielectric(wo.dot(wm), self.eta) / (4.0 * wo.z * wi.z);
            f += Rgb::splat(self.specular * spec);
        }
        f
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((wo, wi)) = Self::upper(wo, wi) else {
            return 0.0;
        };
        let ps = self.specular_probability(wo.z);
        let mut pdf = (1.0 - ps) * cosine_hemisphere_pdf(wi.z);
        if !self.distribution.effectively_smooth() {
            let wm = (wo + wi).normalize();
            pdf += ps * self.distribution.pdf(wo, wm) / (4.0 * wo.dot(wm).abs());
        }
        pdf
    }

    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        let flip = |w: Vec3| {
            if wo.z < 0.0 { Vec3::new(w.x, w.y, -w.z) } else { w }
        };
        let wo_up = flip(wo);
        let ps = self.specular_probability(wo_up.z);
        let smooth = self.distribution.effectively_smooth();
        let wi_up = if uc < ps {
            if smooth {
                let wi = Vec3::new(-wo_up.x, -wo_up.y, wo_up.z);
                let f = self.specular * fresnel::dielectric(wo_up.z, self.eta) / wi.z;
                return Some(BsdfSample {
                    f: Rgb::splat(f),
                    wi: flip(wi),
                    pdf: ps,
                    delta: true,
                    transmission: false,
                    proportional: false,
                });
            }
            let wm = self.distribution.sample_wm(wo_up, u);
            crate::math::reflect(wo_up, wm)
        } else {
            cosine_hemisphere(u)
        };
        if wi_up.z <= 0.0 {
            return None;
        }
        let wi = flip(wi_up);
        Some(BsdfSample {
            f: self.eval(wo, wi),
            wi,
            pdf: self.pdf(wo, wi),
            delta: false,
            transmission: false,
            proportional: false,
        })
    }
}
