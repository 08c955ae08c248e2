//! pbrt-v4 materials translated into core materials. `diffuse`, `diffusetransmission`,
//! `conductor`, `dielectric`, `mix` and the layered `coateddiffuse` and `coatedconductor` (with
//! every parameter pbrt-v4 reads for them) map exactly, and `displacement` bump-maps any of
//! them. Approximations (`thindielectric`, unsupported types) are reported once per material
//! type.

use super::Loader;
use super::params::ParamSet;
use super::state::MaterialSlot;
use super::textures::SpectrumUse;
use crate::LoadError;
use crate::diagnostics::Loc;
use tempera::material::{
    ConductorFresnel, ConductorMaterial, DielectricMaterial, DiffuseTransmissionMaterial, LayeredBaseMaterial,
    LayeredMaterial, Material, MixMaterial, Roughness,
};
use tempera::math::Rgb;
use tempera::texture::Texture;

impl Loader {
    fn roughness(&mut self, params: &ParamSet, prefix: &str) -> Result<Roughness, LoadError> {
        let name = |n: &str| format!("{prefix}{n}");
        let r = self.float_param(params, &name("roughness"), 0.0)?;
        let u = if params.params.iter().any(|p| p.name == name("uroughness")) {
            self.float_param(params, &name("uroughness"), 0.0)?
        } else {
            r.clone()
        };
        let v = if params.params.iter().any(|p| p.name == name("vroughness")) {
            self.float_param(params, &name("vroughness"), 0.0)?
        } else {
            r
        };
        let remap = params.bool("remaproughness", true)?;
        Ok(Roughness { u, v, remap })
    }

    /// A scalar index of refraction from a float or a (named) spectrum.
    fn eta(&mut self, params: &ParamSet, name: &str, default: f32, at: &Loc) -> Result<f32, LoadError> {
        let eta = match self.spectrum_param(params, name, Some(Rgb::splat(default)), SpectrumUse::Unitless)? {
            Some(Texture::Constant(c)) => c.y,
            _ => {
                return Err(LoadError::Syntax {
                    loc: at.clone(),
                    message: format!("textured \"{name}\" is not supported"),
                });
            }
        };
        if eta.is_nan() || eta <= 0.0 {
            return Err(LoadError::Syntax {
                loc: at.clone(),
                message: format!("index of refraction must be positive, got {eta}"),
            });
        }
        Ok(eta)
    }

    fn conductor(&mut self, params: &ParamSet, prefix: &str) -> Result<ConductorMaterial, LoadError> {
        let key = |n: &str| format!("{prefix}{n}");
        let fresnel = match self.spectrum_param(params, &key("reflectance"), None, SpectrumUse::Unitless)? {
            Some(r) => ConductorFresnel::Reflectance(r),
            None => {
                let eta = self.spectrum_param(
                    params,
                    &key("eta"),
                    crate::spectrum::named("metal-Cu-eta"),
                    SpectrumUse::Unitless,
                )?;
                let k = self.spectrum_param(
                    params,
                    &key("k"),
                    crate::spectrum::named("metal-Cu-k"),
                    SpectrumUse::Unitless,
                )?;
                ConductorFresnel::Ior { eta: eta.expect("default given"), k: k.expect("default given") }
            }
        };
        Ok(ConductorMaterial { fresnel, roughness: self.roughness(params, prefix)?, tint: 1.0.into() })
    }

    fn approximated(&mut self, ty: &str, at: &Loc, how: &str) -> Result<(), LoadError> {
        self.warn_once(&format!("material-{ty}"), Some(at), format!("material \"{ty}\" is approximated: {how}"))
    }

    /// The coat and slab of pbrt-v4's `coateddiffuse` and `coatedconductor` over `base`;
    /// `prefix` names the coat's roughness and index (`interface.` for `coatedconductor`).
    fn layered(
        &mut self,
        params: &ParamSet,
        at: &Loc,
        base: LayeredBaseMaterial,
        prefix: &str,
        eta: f32,
    ) -> Result<Material, LoadError> {
        let syntax = |message: String| LoadError::Syntax { loc: at.clone(), message };
        let max_depth = params.int("maxdepth", 10)?;
        let samples = params.int("nsamples", 1)?;
        if !(1..=10_000).contains(&max_depth) {
            return Err(syntax(format!("\"maxdepth\" must be between 1 and 10000, got {max_depth}")));
        }
        if !(1..=1_000).contains(&samples) {
            return Err(syntax(format!("\"nsamples\" must be between 1 and 1000, got {samples}")));
        }
        let albedo = self.spectrum_param(params, "albedo", Some(Rgb::ZERO), SpectrumUse::Unitless)?.expect("default");
        Ok(Material::Layered(LayeredMaterial {
            base,
            roughness: self.roughness(params, prefix)?,
            eta,
            thickness: self.float_param(params, "thickness", 0.01)?,
            albedo,
            g: self.float_param(params, "g", 0.0)?,
            max_depth: max_depth as u32,
            samples: samples as u32,
        }))
    }

    /// pbrt-v4's `coateddiffuse`: a dielectric coat over a Lambertian base.
    fn coated_diffuse(&mut self, params: &ParamSet, at: &Loc) -> Result<Material, LoadError> {
        let reflectance =
            self.spectrum_param(params, "reflectance", Some(Rgb::splat(0.5)), SpectrumUse::Unitless)?.expect("default");
        let eta = self.eta(params, "eta", 1.5, at)?;
        self.layered(params, at, LayeredBaseMaterial::Diffuse(reflectance), "", eta)
    }

    /// pbrt-v4's `coatedconductor`: a dielectric coat over a conductor given by `reflectance`
    /// or by `conductor.eta` and `conductor.k` (copper by default).
    fn coated_conductor(&mut self, params: &ParamSet, at: &Loc) -> Result<Material, LoadError> {
        let eta = self.eta(params, "interface.eta", 1.5, at)?;
        let mut conductor = self.conductor(params, "conductor.")?;
        if let Some(r) = self.spectrum_param(params, "reflectance", None, SpectrumUse::Unitless)? {
            if params.find("conductor.eta").is_some() || params.find("conductor.k").is_some() {
                return Err(LoadError::Syntax {
                    loc: at.clone(),
                    message: "coatedconductor takes \"reflectance\" or \"conductor.eta\"/\"conductor.k\", not both"
                        .into(),
                });
            }
            conductor.fresnel = ConductorFresnel::Reflectance(r);
        }
        self.layered(params, at, LayeredBaseMaterial::Conductor(conductor), "interface.", eta)
    }

    /// pbrt-v4's `mix` of two named materials.
    fn mix(&mut self, params: &ParamSet, at: &Loc) -> Result<Material, LoadError> {
        let syntax = |message: String| LoadError::Syntax { loc: at.clone(), message };
        let names = match params.find("materials").map(|p| &p.values) {
            Some(super::params::Values::Str(v)) if v.len() == 2 => v.clone(),
            _ => return Err(syntax("mix needs \"string materials\" with two names".into())),
        };
        let mut ids = [0u32; 2];
        for (slot, name) in ids.iter_mut().zip(&names) {
            let m = self
                .named
                .materials
                .get(name)
                .cloned()
                .ok_or_else(|| syntax(format!("mix refers to unknown material \"{name}\"")))?;
            *slot = self
                .material_id(&m)
                .ok_or_else(|| syntax("mix of an \"interface\" material is not supported".into()))?
                .0;
        }
        Ok(Material::Mix(MixMaterial { materials: ids, amount: self.float_param(params, "amount", 0.5)? }))
    }

    pub(super) fn make_material(&mut self, ty: &str, params: &ParamSet, at: &Loc) -> Result<MaterialSlot, LoadError> {
        let displacement = match params.params.iter().any(|p| p.name == "displacement") {
            true => Some(self.float_param(params, "displacement", 0.0)?),
            false => None,
        };
        if params.find("normalmap").is_some() {
            self.warn_once("normalmap", Some(at), "normal maps are not supported yet and are ignored")?;
        }
        let material = match ty {
            "diffuse" => Material::diffuse(
                self.spectrum_param(params, "reflectance", Some(Rgb::splat(0.5)), SpectrumUse::Unitless)?
                    .expect("default"),
            ),
            "conductor" => Material::Conductor(self.conductor(params, "")?),
            "dielectric" | "thindielectric" => {
                if ty == "thindielectric" {
                    self.approximated(ty, at, "rendered as a solid dielectric of the same index")?;
                }
                let eta = self.eta(params, "eta", 1.5, at)?;
                Material::Dielectric(DielectricMaterial { eta, roughness: self.roughness(params, "")? })
            }
            "coateddiffuse" => self.coated_diffuse(params, at)?,
            "coatedconductor" => self.coated_conductor(params, at)?,
            "diffusetransmission" => {
                let unitless = SpectrumUse::Unitless;
                Material::DiffuseTransmission(DiffuseTransmissionMaterial {
                    reflectance: self
                        .spectrum_param(params, "reflectance", Some(Rgb::splat(0.25)), unitless)?
                        .expect("default"),
                    transmittance: self
                        .spectrum_param(params, "transmittance", Some(Rgb::splat(0.25)), unitless)?
                        .expect("default"),
                    scale: params.float("scale", 1.0)? as f32,
                })
            }
            "mix" => self.mix(params, at)?,
            "interface" => return Ok(MaterialSlot::Interface),
            "measured" | "hair" | "subsurface" => {
                let names: Vec<String> = params.params.iter().map(|p| p.name.clone()).collect();
                let names: Vec<&str> = names.iter().map(String::as_str).collect();
                self.ignore(params, &names, "a grey diffuse material stands in for the unsupported material");
                self.approximated(ty, at, "a grey diffuse material stands in for it")?;
                Material::diffuse(Rgb::splat(0.5))
            }
            other => {
                return Err(LoadError::Syntax {
                    loc: at.clone(),
                    message: format!("unknown material type \"{other}\""),
                });
            }
        };
        *self.cx.info.materials.entry(ty.to_owned()).or_default() += 1;
        let id = self.cx.builder.add_material(material);
        if let Some(d) = displacement {
            self.cx.builder.set_displacement(id, d);
        }
        Ok(MaterialSlot::Id(id))
    }
}
