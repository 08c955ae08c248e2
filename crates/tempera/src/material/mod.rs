//! Materials: textured parameters that produce a [`Bsdf`] at a surface point (pbrt-v4 §10.5).

use crate::bsdf::plastic::PlasticCoat;
use crate::bsdf::{
    Bsdf, Conductor, Dielectric, Diffuse, DiffuseTransmission, Ggx, Layered, LayeredBase, Plastic, fresnel,
};
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

impl ConductorMaterial {
    pub fn bsdf(&self, uv: Vec2) -> Conductor {
        let (eta, k) = match &self.fresnel {
            ConductorFresnel::Ior { eta, k } => (eta.eval(uv), k.eval(uv)),
            ConductorFresnel::Reflectance(r) => fresnel::conductor_from_reflectance(r.eval(uv)),
        };
        Conductor { distribution: self.roughness.distribution(uv), eta, k, tint: self.tint.eval(uv).max(Rgb::ZERO) }
    }
}

#[derive(Clone, Debug)]
pub struct DielectricMaterial {
    pub eta: f32,
    pub roughness: Roughness,
}

/// Mitsuba's analytic `plastic` and `roughplastic` (a GGX dielectric coat over a Lambertian
/// base, Mitsuba's definition).
#[derive(Clone, Debug)]
pub struct PlasticMaterial {
    pub reflectance: Texture,
    pub roughness: Roughness,
    pub specular: f32,
    pub coat: PlasticCoat,
}

impl PlasticMaterial {
    pub fn new(reflectance: Texture, roughness: Roughness, eta: f32, nonlinear: bool) -> Self {
        Self { reflectance, roughness, specular: 1.0, coat: PlasticCoat::new(eta, nonlinear) }
    }
}

/// What lies under a layered material's coat.
#[derive(Clone, Debug)]
pub enum LayeredBaseMaterial {
    /// pbrt-v4's `coateddiffuse`: a Lambertian base of this reflectance.
    Diffuse(Texture),
    /// pbrt-v4's `coatedconductor`: a conductor, whose index of refraction is taken relative
    /// to the coat's (pbrt-v4 divides `eta` and `k` by the interface's `eta`).
    Conductor(ConductorMaterial),
}

/// pbrt-v4's `coateddiffuse` and `coatedconductor`: a dielectric coat of index `eta` over a
/// base, with a slab of `thickness` between them holding a medium of single-scattering
/// `albedo` and Henyey–Greenstein `g`, evaluated stochastically ([`Layered`]) with walks of at
/// most `max_depth` events, `samples` of them per estimate.
#[derive(Clone, Debug)]
pub struct LayeredMaterial {
    pub base: LayeredBaseMaterial,
    pub roughness: Roughness,
    pub eta: f32,
    pub thickness: Texture,
    pub albedo: Texture,
    pub g: Texture,
    pub max_depth: u32,
    pub samples: u32,
}

impl LayeredMaterial {
    fn bsdf(&self, uv: Vec2) -> Layered {
        let base = match &self.base {
            LayeredBaseMaterial::Diffuse(r) => {
                LayeredBase::Diffuse(Diffuse { reflectance: r.eval(uv).clamp(Rgb::ZERO, Rgb::ONE) })
            }
            LayeredBaseMaterial::Conductor(m) => {
                let mut c = m.bsdf(uv);
                c.eta /= self.eta;
                c.k /= self.eta;
                LayeredBase::Conductor(c)
            }
        };
        Layered {
            top: Dielectric { distribution: self.roughness.distribution(uv), eta: self.eta },
            base,
            thickness: self.thickness.eval_float(uv).max(f32::MIN_POSITIVE),
            albedo: self.albedo.eval(uv).clamp(Rgb::ZERO, Rgb::ONE),
            g: self.g.eval_float(uv).clamp(-0.99, 0.99),
            max_depth: self.max_depth,
            samples: self.samples.max(1),
        }
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
    Plastic(PlasticMaterial),
    Layered(LayeredMaterial),
    /// pbrt-v4's `interface`: a surface that only bounds participating media; rays pass
    /// through it (see `Scene::is_interface`).
    Interface,
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
            Material::Mix(_) | Material::Interface => Bsdf::Diffuse(Diffuse { reflectance: Rgb::ZERO }),
            Material::Diffuse(m) => {
                Bsdf::Diffuse(Diffuse { reflectance: m.reflectance.eval(uv).clamp(Rgb::ZERO, Rgb::ONE) })
            }
            Material::Conductor(m) => Bsdf::Conductor(m.bsdf(uv)),
            Material::Dielectric(m) => {
                Bsdf::Dielectric(Dielectric { distribution: m.roughness.distribution(uv), eta: m.eta })
            }
            Material::Layered(m) => Bsdf::Layered(m.bsdf(uv)),
            Material::Plastic(m) => {
                Bsdf::Plastic(Plastic::new(m.roughness.distribution(uv), &m.coat, m.reflectance.eval(uv), m.specular))
            }
        }
    }
}
