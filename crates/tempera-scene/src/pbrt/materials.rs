//! pbrt-v4 materials translated into core materials. `diffuse`, `diffusetransmission`,
//! `conductor`, `dielectric` and `mix` map exactly, and `displacement` bump-maps any of them.
//! pbrt-v4's stochastic layered `coateddiffuse` is approximated by the analytic
//! coated-diffuse (plastic) model with the same coat index and roughness, and `coatedconductor`
//! by its base conductor; these and other approximations are reported once per material type.

use super::Loader;
use super::params::ParamSet;
use super::state::MaterialSlot;
use super::textures::SpectrumUse;
use crate::LoadError;
use crate::diagnostics::Loc;
use tempera::material::{
    CoatedDiffuseMaterial, ConductorFresnel, ConductorMaterial, DielectricMaterial, DiffuseTransmissionMaterial,
    Material, MixMaterial, Roughness,
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

    /// pbrt-v4's `coateddiffuse`, approximated analytically.
    fn coated_diffuse(&mut self, params: &ParamSet, at: &Loc) -> Result<Material, LoadError> {
        self.approximated("coateddiffuse", at, "analytic coated diffuse (GGX dielectric coat over Lambertian, no coat absorption or interreflection sampling)")?;
        let layer = ["thickness", "albedo", "g", "maxdepth", "nsamples"];
        self.ignore(params, &layer, "the analytic coated diffuse has no medium between its layers");
        let reflectance =
            self.spectrum_param(params, "reflectance", Some(Rgb::splat(0.5)), SpectrumUse::Unitless)?.expect("default");
        let eta = self.eta(params, "eta", 1.5, at)?;
        Ok(Material::CoatedDiffuse(CoatedDiffuseMaterial::new(reflectance, self.roughness(params, "")?, eta, false)))
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
            "coatedconductor" => {
                self.approximated(ty, at, "its base conductor without the dielectric coat")?;
                let coat = [
                    "interface.roughness",
                    "interface.uroughness",
                    "interface.vroughness",
                    "interface.eta",
                    "thickness",
                    "albedo",
                    "g",
                    "maxdepth",
                    "nsamples",
                ];
                self.ignore(params, &coat, "the coat of an approximated coatedconductor");
                Material::Conductor(self.conductor(params, "conductor.")?)
            }
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
