//! Materials: textured parameters that produce a [`Bsdf`] at a surface point (pbrt-v4 §10.5).

use crate::bsdf::plastic::PlasticCoat;
use crate::bsdf::{Bsdf, Conductor, Dielectric, Diffuse, DiffuseTransmission, Ggx, Plastic, fresnel};
use crate::math::Vec3;
use crate::math::rng::{hash, mix64};
use crate::math::{Rgb, Vec2};
use crate::texture::Texture;

/// GGX roughness, possibly anisotropic and textured. With `remap`, values are pbrt's perceptual
/// roughness and alpha = sqrt(roughness); otherwise they are alpha directly.
#[derive(Clone, Debug)]
pub struct Roughness {
    pub u: Texture,
    pub v: Texture,
    pub remap: bool,
}

impl Roughness {
    pub fn alpha(alpha: f32) -> Self {
        Self { u: alpha.into(), v: alpha.into(), remap: false }
    }

    pub fn anisotropic(alpha_u: f32, alpha_v: f32) -> Self {
        Self { u: alpha_u.into(), v: alpha_v.into(), remap: false }
    }

    #[inline]
    pub fn distribution(&self, uv: Vec2) -> Ggx {
        let (mut u, mut v) = (self.u.eval_float(uv), self.v.eval_float(uv));
        if self.remap {
            u = Ggx::roughness_to_alpha(u);
            v = Ggx::roughness_to_alpha(v);
        }
        Ggx::new(u, v)
    }
}

/// How a conductor's Fresnel term is specified.
#[derive(Clone, Debug)]
pub enum ConductorFresnel {
    /// Complex index of refraction per RGB channel.
    Ior { eta: Texture, k: Texture },
    /// pbrt-v4's artist-friendly normal-incidence reflectance.
    Reflectance(Texture),
}

#[derive(Clone, Debug)]
pub struct DiffuseMaterial {
    pub reflectance: Texture,
}

#[derive(Clone, Debug)]
pub struct ConductorMaterial {
    pub fresnel: ConductorFresnel,
    pub roughness: Roughness,
    /// Reflectance multiplier (Mitsuba's `specularReflectance`).
    pub tint: Texture,
}

#[derive(Clone, Debug)]
pub struct DielectricMaterial {
    pub eta: f32,
    pub roughness: Roughness,
}

#[derive(Clone, Debug)]
pub struct CoatedDiffuseMaterial {
    pub reflectance: Texture,
    pub roughness: Roughness,
    pub specular: f32,
    pub coat: PlasticCoat,
}

impl CoatedDiffuseMaterial {
    pub fn new(reflectance: Texture, roughness: Roughness, eta: f32, nonlinear: bool) -> Self {
        Self { reflectance, roughness, specular: 1.0, coat: PlasticCoat::new(eta, nonlinear) }
    }
}

#[derive(Clone, Debug)]
pub struct DiffuseTransmissionMaterial {
    pub reflectance: Texture,
    pub transmittance: Texture,
    pub scale: f32,
}

/// pbrt-v4's `mix`: at each shading point one of two materials is chosen, the second with
/// probability `amount`, by a hash of the point and direction (so a given path is deterministic).
#[derive(Clone, Debug)]
pub struct MixMaterial {
    pub materials: [u32; 2],
    pub amount: Texture,
}

impl MixMaterial {
    /// The material index used at `p` seen from `wo`.
    pub fn choose(&self, uv: Vec2, p: Vec3, wo: Vec3) -> u32 {
        let amount = self.amount.eval_float(uv);
        if amount <= 0.0 {
            return self.materials[0];
        }
        if amount >= 1.0 {
            return self.materials[1];
        }
        let bits =
            |v: Vec3| (u64::from(v.x.to_bits()) << 32) ^ (u64::from(v.y.to_bits()) << 16) ^ u64::from(v.z.to_bits());
        let u = (mix64(hash(&[bits(p), bits(wo), u64::from(self.materials[0]), u64::from(self.materials[1])])) >> 40)
            as f32
            / (1u64 << 24) as f32;
        if u < amount { self.materials[1] } else { self.materials[0] }
    }
}

#[derive(Clone, Debug)]
pub enum Material {
    Diffuse(DiffuseMaterial),
    DiffuseTransmission(DiffuseTransmissionMaterial),
    Conductor(ConductorMaterial),
    Dielectric(DielectricMaterial),
    CoatedDiffuse(CoatedDiffuseMaterial),
    /// Resolved by the scene, which knows the other materials (see `Scene::bsdf`).
    Mix(MixMaterial),
}

impl Material {
    pub fn diffuse(reflectance: impl Into<Texture>) -> Self {
        Material::Diffuse(DiffuseMaterial { reflectance: reflectance.into() })
    }

    /// The BSDF at texture coordinates `uv`. A `Mix` must be resolved to one of its materials
    /// first; unresolved it is black.
    pub fn bsdf(&self, uv: Vec2) -> Bsdf {
        match self {
            Material::DiffuseTransmission(m) => Bsdf::DiffuseTransmission(DiffuseTransmission {
                reflectance: (m.reflectance.eval(uv) * m.scale).clamp(Rgb::ZERO, Rgb::ONE),
                transmittance: (m.transmittance.eval(uv) * m.scale).clamp(Rgb::ZERO, Rgb::ONE),
            }),
            Material::Mix(_) => Bsdf::Diffuse(Diffuse { reflectance: Rgb::ZERO }),
            Material::Diffuse(m) => {
                Bsdf::Diffuse(Diffuse { reflectance: m.reflectance.eval(uv).clamp(Rgb::ZERO, Rgb::ONE) })
            }
            Material::Conductor(m) => {
                let (eta, k) = match &m.fresnel {
                    ConductorFresnel::Ior { eta, k } => (eta.eval(uv), k.eval(uv)),
                    ConductorFresnel::Reflectance(r) => fresnel::conductor_from_reflectance(r.eval(uv)),
                };
                Bsdf::Conductor(Conductor {
                    distribution: m.roughness.distribution(uv),
                    eta,
                    k,
                    tint: m.tint.eval(uv).max(Rgb::ZERO),
                })
            }
            Material::Dielectric(m) => {
                Bsdf::Dielectric(Dielectric { distribution: m.roughness.distribution(uv), eta: m.eta })
            }
            Material::CoatedDiffuse(m) => {
                Bsdf::Plastic(Plastic::new(m.roughness.distribution(uv), &m.coat, m.reflectance.eval(uv), m.specular))
            }
        }
    }
}
