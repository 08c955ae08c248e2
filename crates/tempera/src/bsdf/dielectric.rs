//! Dielectric interfaces: perfectly smooth or GGX-rough reflection and refraction with the
//! generalised half vector (Walter et al. 2007, "Microfacet Models for Refraction through Rough
//! Surfaces"; pbrt-v4 §9.5, §9.7). `eta` is the inside index over the outside index; the
//! outside is the +z side. Radiance crossing the interface is scaled by `1/η'²`.

use super::{BsdfSample, Ggx, SampleInverse, TransportMode, fresnel, same_hemisphere};
use crate::math::{Rgb, Vec2, Vec3};

/// Which lobes of a dielectric interface to sample or value (layered BSDFs ask for one).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Lobes {
    pub reflection: bool,
    pub transmission: bool,
}

impl Lobes {
    pub const ALL: Lobes = Lobes { reflection: true, transmission: true };
    pub const REFLECTION: Lobes = Lobes { reflection: true, transmission: false };
    pub const TRANSMISSION: Lobes = Lobes { reflection: false, transmission: true };

    /// The probabilities of choosing reflection and transmission, given the Fresnel terms,
    /// with the lobes not asked for at zero.
    fn weights(self, r: f32, t: f32) -> (f32, f32) {
        (if self.reflection { r } else { 0.0 }, if self.transmission { t } else { 0.0 })
    }
}

#[derive(Clone, Copy, Debug)]
pub struct Dielectric {
    pub distribution: Ggx,
    pub eta: f32,
}

impl Dielectric {
    pub fn is_delta(&self) -> bool {
        self.eta == 1.0 || self.distribution.effectively_smooth()
    }

    /// The generalised half vector (upper hemisphere) and the relative eta of the pair, or
    /// `None` for configurations no microfacet can produce.
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        let reflect = cos_o * cos_i > 0.0;
        let etap = if reflect {
            1.0
        } else if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let wm = wi * etap + wo;
        if cos_i == 0.0 || cos_o == 0.0 || wm.length_squared() == 0.0 {
            return None;
        }
        let wm = wm.normalize();
        let wm = if wm.z < 0.0 { -wm } else { wm };
        if wm.dot(wi) * cos_i < 0.0 || wm.dot(wo) * cos_o < 0.0 {
            return None;
        }
        Some((wm, etap, reflect))
    }

    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        if self.is_delta() {
            return Rgb::ZERO;
        }
        let Some((wm, etap, reflect)) = self.half_vector(wo, wi) else {
            return Rgb::ZERO;
        };
        let d = &self.distribution;
        let f = fresnel::dielectric(wo.dot(wm), self.eta);
        let v = if reflect {
            d.d(wm) * d.g(wo, wi) * f / (4.0 * wi.z * wo.z).abs()
        } else {
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2) * wi.z * wo.z;
            let mut ft = d.d(wm) * (1.0 - f) * d.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / denom).abs();
            if mode == TransportMode::Radiance {
                ft /= etap * etap;
            }
            ft
        };
        if v.is_finite() { Rgb::splat(v) } else { Rgb::ZERO }
    }

    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.pdf_lobes(wo, wi, Lobes::ALL)
    }

    /// The density of [`Self::sample_lobes`] with `lobes`.
    pub fn pdf_lobes(&self, wo: Vec3, wi: Vec3, lobes: Lobes) -> f32 {
        if self.is_delta() {
            return 0.0;
        }
        let Some((wm, etap, reflect)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let r = fresnel::dielectric(wo.dot(wm), self.eta);
        let (pr, pt) = lobes.weights(r, 1.0 - r);
        if pr + pt == 0.0 {
            return 0.0;
        }
        let pdf = if reflect {
            self.distribution.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt)
        } else {
            let dwm_dwi = wi.dot(wm).abs() / (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            self.distribution.pdf(wo, wm) * dwm_dwi * pt / (pr + pt)
        };
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        self.sample_lobes(wo, uc, u, mode, Lobes::ALL)
    }

    /// Samples reflection or transmission (with probabilities in proportion to the Fresnel
    /// terms of the lobes asked for).
    pub fn sample_lobes(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode, lobes: Lobes) -> Option<BsdfSample> {
        if wo.z == 0.0 {
            return None;
        }
        if self.is_delta() {
            return self.sample_smooth(wo, uc, mode, lobes);
        }
        let wm = self.distribution.sample_wm(wo, u);
        let r = fresnel::dielectric(wo.dot(wm), self.eta);
        let t = 1.0 - r;
        let (pr, pt) = lobes.weights(r, t);
        if pr + pt == 0.0 {
            return None;
        }
        if uc < pr / (pr + pt) {
            let wi = crate::math::reflect(wo, wm);
            if !same_hemisphere(wo, wi) {
                return None;
            }
            let d = &self.distribution;
            let pdf = d.pdf(wo, wm) / (4.0 * wo.dot(wm).abs()) * pr / (pr + pt);
            let f = d.d(wm) * d.g(wo, wi) * r / (4.0 * wi.z * wo.z).abs();
            Some(BsdfSample { f: Rgb::splat(f), wi, pdf, delta: false, transmission: false, proportional: false })
        } else {
            let (wi, etap) = fresnel::refract(wo, wm, self.eta)?;
            if same_hemisphere(wo, wi) || wi.z == 0.0 {
                return None;
            }
            let d = &self.distribution;
            let denom = (wi.dot(wm) + wo.dot(wm) / etap).powi(2);
            let dwm_dwi = wi.dot(wm).abs() / denom;
            let pdf = d.pdf(wo, wm) * dwm_dwi * pt / (pr + pt);
            let mut ft = t * d.d(wm) * d.g(wo, wi) * (wi.dot(wm) * wo.dot(wm) / (wi.z * wo.z * denom)).abs();
            if mode == TransportMode::Radiance {
                ft /= etap * etap;
            }
            Some(BsdfSample { f: Rgb::splat(ft), wi, pdf, delta: false, transmission: true, proportional: false })
        }
    }

    /// The numbers with which [`Self::sample`] produces `wi` from `wo`: the interval of the
    /// lobe-choosing number that picks reflection or transmission (by the Fresnel term, as
    /// sampling does) and, for a rough interface, the visible normal's sample.
    pub fn sample_inverse(&self, wo: Vec3, wi: Vec3) -> Option<SampleInverse> {
        if wo.z == 0.0 || wi.z == 0.0 {
            return None;
        }
        let reflect = same_hemisphere(wo, wi);
        let (r, u) = if self.is_delta() {
            (fresnel::dielectric(wo.z, self.eta), None)
        } else {
            let (wm, _, _) = self.half_vector(wo, wi)?;
            (fresnel::dielectric(wo.dot(wm), self.eta), Some(self.distribution.sample_wm_inverse(wo, wm)?))
        };
        let uc = if reflect { (0.0, r) } else { (r, 1.0) };
        (uc.1 > uc.0).then_some(SampleInverse { uc: Some(uc), u })
    }

    fn sample_smooth(&self, wo: Vec3, uc: f32, mode: TransportMode, lobes: Lobes) -> Option<BsdfSample> {
        let r = fresnel::dielectric(wo.z, self.eta);
        let t = 1.0 - r;
        let (pr, pt) = lobes.weights(r, t);
        if pr + pt == 0.0 {
            return None;
        }
        if uc < pr / (pr + pt) {
            let wi = Vec3::new(-wo.x, -wo.y, wo.z);
            return Some(BsdfSample {
                f: Rgb::splat(r / wi.z.abs()),
                wi,
                pdf: pr / (pr + pt),
                delta: true,
                transmission: false,
                proportional: false,
            });
        }
        let (wi, etap) = fresnel::refract(wo, Vec3::Z, self.eta)?;
        let mut ft = t / wi.z.abs();
        if mode == TransportMode::Radiance {
            ft /= etap * etap;
        }
        Some(BsdfSample {
            f: Rgb::splat(ft),
            wi,
            pdf: pt / (pr + pt),
            delta: true,
            transmission: true,
            proportional: false,
        })
    }
}
