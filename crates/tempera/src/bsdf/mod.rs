//! Scattering functions in the local shading frame (normal = +z; `wo` and `wi` both point away
//! from the surface), their sampling and densities (pbrt-v4 ch. 9), and the world-space wrapper
//! [`SurfaceBsdf`] that carries the shading frame.

pub mod conductor;
pub mod dielectric;
pub mod diffuse;
pub mod diffuse_transmission;
pub mod fresnel;
pub mod layered;
pub mod microfacet;
pub mod plastic;

#[cfg(test)]
mod tests;

pub use conductor::Conductor;
pub use dielectric::Dielectric;
pub use diffuse::Diffuse;
pub use diffuse_transmission::DiffuseTransmission;
pub use layered::{Base as LayeredBase, Layered};
pub use microfacet::Ggx;
pub use plastic::Plastic;

use crate::math::frame::Frame;
use crate::math::{Rgb, Vec2, Vec3};

/// Which quantity a path carries; transmission through a refractive boundary scales radiance by
/// `1/η²` but importance not (Veach 1997, §5.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TransportMode {
    Radiance,
    Importance,
}

/// A sampled direction with its BSDF value (without the cosine) and density.
#[derive(Clone, Copy, Debug)]
pub struct BsdfSample {
    pub f: Rgb,
    pub wi: Vec3,
    /// Solid-angle density; for delta lobes, the discrete probability of the lobe.
    pub pdf: f32,
    pub delta: bool,
    pub transmission: bool,
    /// `pdf` is only proportional to the density of the sampling procedure (a layered BSDF's
    /// random walk): `f·cos/pdf` is the sample's exact weight, but multiple importance
    /// sampling must use [`Bsdf::pdf`] for the density of `wi`.
    pub proportional: bool,
}

/// The numbers with which [`Bsdf::sample`] produces a given direction (the inverse mapping of
/// Bitterli et al. 2017): the interval of `uc` that chooses the direction's lobe, and the
/// direction sample `u`; `None` where any value does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleInverse {
    pub uc: Option<(f32, f32)>,
    pub u: Option<Vec2>,
}

#[inline]
pub(crate) fn same_hemisphere(a: Vec3, b: Vec3) -> bool {
    a.z * b.z > 0.0
}

/// A BSDF at one surface point, in its local frame.
#[derive(Clone, Copy, Debug)]
pub enum Bsdf {
    Diffuse(Diffuse),
    DiffuseTransmission(DiffuseTransmission),
    Conductor(Conductor),
    Dielectric(Dielectric),
    Plastic(Plastic),
    Layered(Layered),
}

impl Bsdf {
    /// BSDF value `f(wo, wi)` of the non-delta lobes.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        match self {
            Bsdf::Diffuse(b) => b.eval(wo, wi),
            Bsdf::DiffuseTransmission(b) => b.eval(wo, wi),
            Bsdf::Conductor(b) => b.eval(wo, wi),
            Bsdf::Dielectric(b) => b.eval(wo, wi, mode),
            Bsdf::Plastic(b) => b.eval(wo, wi),
            Bsdf::Layered(b) => b.eval(wo, wi, mode),
        }
    }

    /// Solid-angle density with which [`Self::sample`] produces `wi` through non-delta lobes.
    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        match self {
            Bsdf::Diffuse(b) => b.pdf(wo, wi),
            Bsdf::DiffuseTransmission(b) => b.pdf(wo, wi),
            Bsdf::Conductor(b) => b.pdf(wo, wi),
            Bsdf::Dielectric(b) => b.pdf(wo, wi),
            Bsdf::Plastic(b) => b.pdf(wo, wi),
            Bsdf::Layered(b) => b.pdf(wo, wi),
        }
    }

    /// Samples `wi` given `wo`; `uc` selects a lobe, `u` the direction.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let s = match self {
            Bsdf::Diffuse(b) => b.sample(wo, u),
            Bsdf::DiffuseTransmission(b) => b.sample(wo, uc, u),
            Bsdf::Conductor(b) => b.sample(wo, u),
            Bsdf::Dielectric(b) => b.sample(wo, uc, u, mode),
            Bsdf::Plastic(b) => b.sample(wo, uc, u),
            Bsdf::Layered(b) => b.sample(wo, uc, u, mode),
        }?;
        (s.pdf > 0.0 && s.f.is_finite() && s.wi.z != 0.0).then_some(s)
    }

    /// Whether [`Self::sample_inverse`] inverts this BSDF's sampling: diffuse, conductor and
    /// dielectric BSDFs (a layered one samples by a random walk, which no numbers invert).
    pub fn invertible(&self) -> bool {
        matches!(self, Bsdf::Diffuse(_) | Bsdf::Conductor(_) | Bsdf::Dielectric(_))
    }

    /// The numbers with which [`Self::sample`] produces `wi` from `wo` ([`SampleInverse`]);
    /// `None` where no numbers do, or the BSDF is not [`Self::invertible`].
    pub fn sample_inverse(&self, wo: Vec3, wi: Vec3) -> Option<SampleInverse> {
        match self {
            Bsdf::Diffuse(b) => b.sample_inverse(wo, wi),
            Bsdf::Conductor(b) => b.sample_inverse(wo, wi),
            Bsdf::Dielectric(b) => b.sample_inverse(wo, wi),
            _ => None,
        }
    }

    /// The BSDF with its GGX lobes roughened by `a` ([`Ggx::roughened`]); diffuse lobes and
    /// smooth (delta) lobes are unchanged, so a connectible BSDF stays connectible and a delta one
    /// stays delta.
    pub fn roughened(&self, a: f32) -> Bsdf {
        let mut out = *self;
        match &mut out {
            Bsdf::Diffuse(_) | Bsdf::DiffuseTransmission(_) => {}
            Bsdf::Conductor(b) => b.distribution = b.distribution.roughened(a),
            Bsdf::Dielectric(b) => b.distribution = b.distribution.roughened(a),
            Bsdf::Plastic(b) => b.distribution = b.distribution.roughened(a),
            Bsdf::Layered(b) => *b = b.roughened(a),
        }
        out
    }

    /// True when every lobe is a Dirac delta: no connection can be made through this BSDF.
    #[inline]
    pub fn is_delta(&self) -> bool {
        match self {
            Bsdf::Diffuse(_) | Bsdf::DiffuseTransmission(_) | Bsdf::Plastic(_) => false,
            Bsdf::Conductor(b) => b.distribution.effectively_smooth(),
            Bsdf::Dielectric(b) => b.is_delta(),
            Bsdf::Layered(b) => b.is_delta(),
        }
    }
}

/// A BSDF placed at a surface point: local BSDF plus shading frame and geometric normal.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceBsdf {
    pub bsdf: Bsdf,
    pub frame: Frame,
    pub ng: Vec3,
}

impl SurfaceBsdf {
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> Rgb {
        self.bsdf.eval(self.frame.to_local(wo), self.frame.to_local(wi), mode)
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.bsdf.pdf(self.frame.to_local(wo), self.frame.to_local(wi))
    }

    /// Samples a world-space direction; `wi` in the result is in world space.
    #[inline]
    pub fn sample(&self, wo: Vec3, uc: f32, u: Vec2, mode: TransportMode) -> Option<BsdfSample> {
        let mut s = self.bsdf.sample(self.frame.to_local(wo), uc, u, mode)?;
        s.wi = self.frame.to_world(s.wi).normalize();
        Some(s)
    }

    #[inline]
    pub fn is_delta(&self) -> bool {
        self.bsdf.is_delta()
    }

    /// [`Bsdf::sample_inverse`] for world-space directions.
    pub fn sample_inverse(&self, wo: Vec3, wi: Vec3) -> Option<SampleInverse> {
        self.bsdf.sample_inverse(self.frame.to_local(wo), self.frame.to_local(wi))
    }
}
