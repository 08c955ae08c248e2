//! pbrt-v4's participating media: `MakeNamedMedium "homogeneous"` (`sigma_a`, `sigma_s`,
//! `scale`, `g`) and `MediumInterface`; heterogeneous media are refused with a clear message.

use super::Loader;
use super::directives::string_arg;
use super::lexer::{Lexer, TokenKind};
use super::params::ParamSet;
use super::textures::SpectrumUse;
use crate::LoadError;
use crate::diagnostics::Loc;
use tempera::math::Rgb;
use tempera::medium::Medium;

impl Loader {
    /// Participating media: pbrt-v4's `homogeneous` medium (`sigma_a`, `sigma_s`, `scale`,
    /// `g`) and `MediumInterface`; heterogeneous media are refused with a clear message.
    pub(super) fn medium_directive(&mut self, name: &str, lx: &mut Lexer) -> Result<(), LoadError> {
        match name {
            "MakeNamedMedium" => {
                let (n, at) = string_arg(lx, "medium name")?;
                let params = ParamSet::parse(lx)?;
                let medium = self.homogeneous_medium(&n, &params, &at)?;
                let index = self.cx.builder.add_medium(medium);
                self.named.media.insert(n, index);
                *self.cx.info.materials.entry("medium homogeneous".to_owned()).or_default() += 1;
                self.report_unused(&params, "MakeNamedMedium")?;
            }
            "MediumInterface" => {
                let (inside, _) = string_arg(lx, "medium name")?;
                let outside = match lx.peek()? {
                    Some(t) if matches!(t.kind, TokenKind::Str(_)) => string_arg(lx, "medium name")?.0,
                    _ => inside.clone(),
                };
                self.state.media = (inside, outside);
            }
            _ => unreachable!("medium directives only"),
        }
        Ok(())
    }

    /// A `homogeneous` medium from its parameters; other medium types are errors.
    fn homogeneous_medium(&mut self, name: &str, params: &ParamSet, at: &Loc) -> Result<Medium, LoadError> {
        let syntax = |message: String| LoadError::Syntax { loc: at.clone(), message };
        let ty = params.string("type")?.unwrap_or("").to_owned();
        match ty.as_str() {
            "homogeneous" => {}
            "uniformgrid" | "nanovdb" | "cloud" | "rgbgrid" => {
                return Err(syntax(format!(
                    "heterogeneous medium \"{name}\" of type \"{ty}\" is not supported (only \"homogeneous\")"
                )));
            }
            "" => return Err(syntax(format!("medium \"{name}\" needs a \"string type\""))),
            other => return Err(syntax(format!("unknown medium type \"{other}\""))),
        }
        if let Some(preset) = params.string("preset")? {
            return Err(syntax(format!(
                "medium preset \"{preset}\" is not supported; give \"sigma_a\" and \"sigma_s\" instead"
            )));
        }
        let constant = |loader: &mut Self, key: &str, default: Rgb| -> Result<Rgb, LoadError> {
            match loader.spectrum_param(params, key, Some(default), SpectrumUse::Unitless)? {
                Some(tempera::texture::Texture::Constant(c)) => Ok(c),
                _ => Err(LoadError::Syntax { loc: at.clone(), message: format!("\"{key}\" must be a constant") }),
            }
        };
        // pbrt-v4's defaults (per millimetre, a skim-milk-like medium).
        let sigma_a = constant(self, "sigma_a", Rgb::new(0.0011, 0.0024, 0.014))?;
        let sigma_s = constant(self, "sigma_s", Rgb::new(2.55, 3.21, 3.77))?;
        let scale = params.float("scale", 1.0)? as f32;
        let g = params.float("g", 0.0)? as f32;
        let le = constant(self, "Le", Rgb::ZERO)?;
        params.float("Lescale", 1.0)?;
        if le.max_element() > 0.0 {
            self.warn(Some(at), format!("medium \"{name}\": emission (\"Le\") is not supported and is ignored"))?;
        }
        let medium = Medium { sigma_a: sigma_a * scale, sigma_s: sigma_s * scale, g };
        let valid = |c: Rgb| c.is_finite() && c.min_element() >= 0.0;
        if !valid(medium.sigma_a) || !valid(medium.sigma_s) || g.is_nan() || g.abs() >= 1.0 {
            return Err(syntax(format!(
                "medium \"{name}\": coefficients must be finite and non-negative and \"g\" strictly between -1 and 1"
            )));
        }
        Ok(medium)
    }

    /// The scene index of medium `name` ("" is vacuum).
    pub(super) fn medium_index(&self, name: &str, at: &Loc) -> Result<Option<u32>, LoadError> {
        if name.is_empty() {
            return Ok(None);
        }
        self.named
            .media
            .get(name)
            .copied()
            .map(Some)
            .ok_or_else(|| LoadError::Syntax { loc: at.clone(), message: format!("unknown medium \"{name}\"") })
    }
}
