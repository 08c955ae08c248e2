//! pbrt-v4 light sources: `point`, `spot`, `distant`, `infinite` (constant or equal-area image)
//! and diffuse area lights. RGB emission is used as given (pbrt-v4 normalises its RGB
//! illuminants so that `"rgb L" [1 1 1]` renders as (1, 1, 1)); blackbody and sampled emission
//! spectra have unit luminance before `scale`.

use super::Loader;
use super::directives::string_arg;
use super::lexer::Lexer;
use super::params::ParamSet;
use super::textures::SpectrumUse;
use crate::LoadError;
use crate::diagnostics::Loc;
use tempera::light::{DistantLight, EnvironmentMap, InfiniteLight, Light, PointLight, SpotLight};
use tempera::math::{Mat3, Rgb, Vec3, luminance};
use tempera::scene::AreaEmission;
use tempera::texture::{ImageTexture, Texture};
use tempera_image::ColorEncoding;

fn syntax(loc: &Loc, message: impl Into<String>) -> LoadError {
    LoadError::Syntax { loc: loc.clone(), message: message.into() }
}

impl Loader {
    fn emission(&mut self, params: &ParamSet, name: &str, at: &Loc) -> Result<Rgb, LoadError> {
        match self.spectrum_param(params, name, Some(Rgb::ONE), SpectrumUse::Emission)? {
            Some(Texture::Constant(c)) => Ok(c),
            _ => Err(syntax(at, format!("\"{name}\" of a light cannot be a texture"))),
        }
    }

    fn point3(params: &ParamSet, name: &str, default: Vec3) -> Result<Vec3, LoadError> {
        Ok(params
            .points(name, 3)?
            .and_then(|v| v.first().cloned())
            .map_or(default, |p| Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)))
    }

    fn unsupported_power(&mut self, params: &ParamSet, at: &Loc) -> Result<(), LoadError> {
        if params.find("power").is_some() {
            self.warn(Some(at), "the \"power\" parameter of lights is not supported and is ignored")?;
        }
        Ok(())
    }

    pub(super) fn light_source(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "light type")?;
        let params = ParamSet::parse(lx)?;
        let scale = params.float("scale", 1.0)? as f32;
        let ctm = self.state.ctm;
        self.unsupported_power(&params, &at)?;
        let light = match ty.as_str() {
            "point" => {
                let i = self.emission(&params, "I", &at)? * scale;
                Light::Point(PointLight {
                    position: ctm.transform_point3(Self::point3(&params, "from", Vec3::ZERO)?),
                    intensity: i,
                })
            }
            "spot" => {
                let i = self.emission(&params, "I", &at)? * scale;
                let from = ctm.transform_point3(Self::point3(&params, "from", Vec3::ZERO)?);
                let to = ctm.transform_point3(Self::point3(&params, "to", Vec3::Z)?);
                if (to - from).length_squared() == 0.0 {
                    return Err(syntax(&at, "spot light \"from\" and \"to\" coincide"));
                }
                let (angle, delta) = (params.float("coneangle", 30.0)? as f32, params.float("conedelta", 5.0)? as f32);
                Light::Spot(SpotLight::new(from, to, i, angle, delta))
            }
            "distant" => {
                let mut l = self.emission(&params, "L", &at)? * scale;
                let e = params.float("illuminance", -1.0)? as f32;
                if e > 0.0 && luminance(l) > 0.0 {
                    l *= e / luminance(l);
                }
                let dir = ctm.transform_vector3(
                    Self::point3(&params, "from", Vec3::ZERO)? - Self::point3(&params, "to", Vec3::Z)?,
                );
                let to_light =
                    dir.try_normalize().ok_or_else(|| syntax(&at, "distant light \"from\" and \"to\" coincide"))?;
                Light::Distant(DistantLight { to_light, radiance: l })
            }
            "infinite" => self.infinite(&params, scale, &at)?,
            "goniometric" | "projection" => {
                return Err(syntax(&at, format!("\"{ty}\" lights are not supported")));
            }
            other => return Err(syntax(&at, format!("unknown light type \"{other}\""))),
        };
        self.report_unused(&params, &format!("LightSource \"{ty}\""))?;
        *self.cx.info.lights.entry(ty).or_default() += 1;
        // pbrt-v4: a light sits in the current `MediumInterface`'s outside medium.
        let medium = self.medium_index(&self.state.media.1.clone(), &at)?;
        self.cx.builder.add_light_in(light, medium);
        Ok(())
    }

    fn infinite(&mut self, params: &ParamSet, scale: f32, at: &Loc) -> Result<Light, LoadError> {
        if params.find("portal").is_some() {
            self.warn(Some(at), "portals of infinite lights are ignored")?;
        }
        if params.find("illuminance").is_some() {
            self.warn(Some(at), "\"illuminance\" of infinite lights is not supported and is ignored")?;
        }
        let c = self.state.ctm;
        let rotation = Mat3::from_cols(
            c.x_axis.truncate().normalize_or_zero(),
            c.y_axis.truncate().normalize_or_zero(),
            c.z_axis.truncate().normalize_or_zero(),
        );
        let Some(file) = params.string("filename")?.map(str::to_owned) else {
            let l = self.emission(params, "L", at)?;
            return Ok(Light::Infinite(InfiniteLight::uniform(l * scale)));
        };
        if params.params.iter().any(|p| p.name == "L") {
            return Err(syntax(at, "infinite light: give either \"L\" or \"filename\", not both"));
        }
        let image = self.image(&file, ColorEncoding::Srgb, false, at)?;
        let map = if image.width == image.height {
            EnvironmentMap::EqualArea
        } else {
            self.warn(
                Some(at),
                format!("{file} is not square, so not an equal-area map; reading it as latitude-longitude"),
            )?;
            EnvironmentMap::LatLong
        };
        Ok(Light::Infinite(InfiniteLight::image(image, map, rotation, Rgb::splat(scale))))
    }

    pub(super) fn area_light_source(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "area light type")?;
        let params = ParamSet::parse(lx)?;
        if ty != "diffuse" {
            return Err(syntax(&at, format!("area light \"{ty}\" is not supported (only \"diffuse\")")));
        }
        self.unsupported_power(&params, &at)?;
        let scale = params.float("scale", 1.0)? as f32;
        let two_sided = params.bool("twosided", false)?;
        let radiance = match params.string("filename")?.map(str::to_owned) {
            Some(file) => {
                let image = self.image(&file, ColorEncoding::Srgb, false, &at)?;
                Texture::Image(ImageTexture::new(image))
            }
            None => Texture::Constant(self.emission(&params, "L", &at)?),
        };
        self.report_unused(&params, "AreaLightSource \"diffuse\"")?;
        self.state.area_light = Some(AreaEmission { radiance, scale, two_sided });
        Ok(())
    }
}
