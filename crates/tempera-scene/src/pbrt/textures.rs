//! pbrt-v4 textures (`imagemap`, `checkerboard`, `scale`, `mix`, `constant`) and the lookup of
//! texture-or-value material parameters (`"rgb reflectance"` or `"texture reflectance"`).

use super::Loader;
use super::directives::string_arg;
use super::lexer::Lexer;
use super::params::{ParamSet, Values};
use crate::LoadError;
use crate::diagnostics::Loc;
use crate::spectrum;
use std::sync::Arc;
use tempera::math::Rgb;
use tempera::texture::{Checkerboard, Image, ImageTexture, Texture, UvMapping, WrapMode};
use tempera_image::ColorEncoding;

/// How an unbounded spectrum parameter is reduced to RGB.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum SpectrumUse {
    /// Reflectances and indices of refraction: white-balanced.
    Unitless,
    /// Emission: normalised to unit luminance (then scaled), as pbrt-v4 does for lights.
    Emission,
}

fn syntax(loc: &Loc, message: impl Into<String>) -> LoadError {
    LoadError::Syntax { loc: loc.clone(), message: message.into() }
}

impl Loader {
    /// A spectrum-valued parameter as a texture, or `default` when absent.
    pub(super) fn spectrum_param(
        &mut self,
        params: &ParamSet,
        name: &str,
        default: Option<Rgb>,
        usage: SpectrumUse,
    ) -> Result<Option<Texture>, LoadError> {
        let Some(p) = params.find(name) else { return Ok(default.map(Texture::Constant)) };
        let at = p.loc.clone();
        let rgb = match (p.ty.as_str(), &p.values) {
            ("texture", Values::Str(v)) => {
                return match self.named.spectrum_textures.get(&v[0]).or_else(|| self.named.float_textures.get(&v[0])) {
                    Some(t) => Ok(Some(t.clone())),
                    None => Err(syntax(&at, format!("unknown texture \"{}\"", v[0]))),
                };
            }
            ("rgb" | "color", Values::Num(v)) => Rgb::new(v[0] as f32, v[1] as f32, v[2] as f32),
            ("blackbody", Values::Num(v)) if !v.is_empty() => spectrum::blackbody(v[0]),
            ("spectrum", Values::Num(v)) => match usage {
                SpectrumUse::Emission => spectrum::sampled_emission(v),
                SpectrumUse::Unitless => spectrum::sampled_reflectance(v),
            },
            ("spectrum", Values::Str(v)) => match spectrum::named(&v[0]) {
                Some(c) => c,
                None => {
                    let pairs = self.spectrum_file(&v[0], &at)?;
                    match usage {
                        SpectrumUse::Emission => spectrum::sampled_emission(&pairs),
                        SpectrumUse::Unitless => spectrum::sampled_reflectance(&pairs),
                    }
                }
            },

            ("float", Values::Num(v)) if !v.is_empty() => Rgb::splat(v[0] as f32),
            (ty, _) => return Err(syntax(&at, format!("parameter \"{name}\" cannot be given as \"{ty}\""))),
        };
        if !rgb.is_finite() {
            return Err(syntax(&at, format!("parameter \"{name}\" is not finite")));
        }
        Ok(Some(Texture::Constant(rgb)))
    }

    /// Wavelength–value pairs from a spectrum file (whitespace-separated numbers, `#` comments).
    fn spectrum_file(&self, name: &str, at: &Loc) -> Result<Vec<f64>, LoadError> {
        let path = self.resolve(at, name);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            syntax(at, format!("\"{name}\" is neither a named spectrum nor a readable spectrum file: {e}"))
        })?;
        let mut values = Vec::new();
        for (i, line) in text.lines().enumerate() {
            let line = line.split('#').next().unwrap_or("");
            for word in line.split_whitespace() {
                let v: f64 = word.parse().map_err(|_| {
                    syntax(at, format!("{}:{}: expected a number, found '{word}'", path.display(), i + 1))
                })?;
                values.push(v);
            }
        }
        if values.len() < 2 || values.len() % 2 != 0 || values.iter().any(|v| !v.is_finite()) {
            return Err(syntax(at, format!("{}: expected wavelength–value pairs", path.display())));
        }
        Ok(values)
    }

    /// A float-valued parameter as a texture.
    pub(super) fn float_param(&mut self, params: &ParamSet, name: &str, default: f32) -> Result<Texture, LoadError> {
        let Some(p) = params.find(name) else { return Ok(default.into()) };
        let at = p.loc.clone();
        match (p.ty.as_str(), &p.values) {
            ("float" | "integer", Values::Num(v)) if !v.is_empty() => Ok((v[0] as f32).into()),
            ("texture", Values::Str(v)) => {
                match self.named.float_textures.get(&v[0]).or_else(|| self.named.spectrum_textures.get(&v[0])) {
                    Some(t) => Ok(t.clone()),
                    None => Err(syntax(&at, format!("unknown texture \"{}\"", v[0]))),
                }
            }
            (ty, _) => {
                Err(syntax(&at, format!("parameter \"{name}\" must be \"float\" or \"texture\", found \"{ty}\"")))
            }
        }
    }

    fn mapping(&mut self, params: &ParamSet, at: &Loc) -> Result<UvMapping, LoadError> {
        if let Some(m) = params.string("mapping")?
            && m != "uv"
        {
            let m = m.to_owned();
            self.warn(Some(at), format!("texture mapping \"{m}\" is not supported; using \"uv\""))?;
        }
        Ok(UvMapping {
            su: params.float("uscale", 1.0)? as f32,
            sv: params.float("vscale", 1.0)? as f32,
            du: params.float("udelta", 0.0)? as f32,
            dv: params.float("vdelta", 0.0)? as f32,
        })
    }

    /// Loads an image (cached per file and encoding); float textures read its channel average.
    pub(super) fn image(
        &mut self,
        file: &str,
        encoding: ColorEncoding,
        grey: bool,
        at: &Loc,
    ) -> Result<Arc<Image>, LoadError> {
        let path = self.resolve(at, file);
        self.cx.image(&path, encoding, grey, at)
    }

    fn encoding(&mut self, params: &ParamSet, at: &Loc) -> Result<ColorEncoding, LoadError> {
        Ok(match params.string("encoding")? {
            None | Some("sRGB") => ColorEncoding::Srgb,
            Some("linear") => ColorEncoding::Linear,
            Some(g) if g.starts_with("gamma ") => match g[6..].trim().parse::<f32>() {
                Ok(v) if v > 0.0 => ColorEncoding::Gamma(v),
                _ => return Err(syntax(at, format!("invalid encoding \"{g}\""))),
            },
            Some(other) => {
                return Err(syntax(at, format!("unknown encoding \"{other}\" (sRGB, linear or \"gamma G\")")));
            }
        })
    }

    fn make_texture(&mut self, class: &str, float: bool, params: &ParamSet, at: &Loc) -> Result<Texture, LoadError> {
        let value = |this: &mut Self, name: &str, default: f32| -> Result<Texture, LoadError> {
            if float {
                this.float_param(params, name, default)
            } else {
                Ok(this
                    .spectrum_param(params, name, Some(Rgb::splat(default)), SpectrumUse::Unitless)?
                    .expect("default given"))
            }
        };
        Ok(match class {
            "constant" => value(self, "value", 1.0)?,
            "scale" => {
                let tex = value(self, "tex", 1.0)?;
                let scale = self.float_param(params, "scale", 1.0)?;
                Texture::Scale(Box::new((tex, scale)))
            }
            "mix" => {
                let a = value(self, "tex1", 0.0)?;
                let b = value(self, "tex2", 1.0)?;
                let amount = self.float_param(params, "amount", 0.5)?;
                Texture::Mix(Box::new((a, b, amount)))
            }
            "checkerboard" => {
                let dim = params.int("dimension", 2)?;
                if dim != 2 {
                    self.warn(Some(at), "3D checkerboards are not supported; using the 2D (uv) pattern")?;
                }
                let even = value(self, "tex1", 1.0)?;
                let odd = value(self, "tex2", 0.0)?;
                let mapping = self.mapping(params, at)?;
                Texture::Checkerboard(Box::new(Checkerboard { even, odd, mapping }))
            }
            "imagemap" => {
                let file = params
                    .string("filename")?
                    .ok_or_else(|| syntax(at, "imagemap needs \"string filename\""))?
                    .to_owned();
                let encoding = self.encoding(params, at)?;
                let image = self.image(&file, encoding, float, at)?;
                let wrap = match params.string("wrap")? {
                    None | Some("repeat") => WrapMode::Repeat,
                    Some("clamp") => WrapMode::Clamp,
                    Some("black") => WrapMode::Black,
                    Some(other) => return Err(syntax(at, format!("unknown wrap mode \"{other}\""))),
                };
                params.find("filter");
                params.find("maxanisotropy");
                let mut t = ImageTexture::new(image);
                t.wrap = wrap;
                t.mapping = self.mapping(params, at)?;
                t.scale = params.float("scale", 1.0)? as f32;
                t.invert = params.bool("invert", false)?;
                Texture::Image(t)
            }
            other => {
                for p in &params.params {
                    p.mark_used();
                }
                self.warn(Some(at), format!("texture \"{other}\" is not supported; using a constant 0.5"))?;
                Texture::Constant(Rgb::splat(0.5))
            }
        })
    }

    pub(super) fn texture_directive(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (name, at) = string_arg(lx, "texture name")?;
        let (kind, kind_at) = string_arg(lx, "texture type (\"float\" or \"spectrum\")")?;
        let (class, _) = string_arg(lx, "texture class")?;
        let params = ParamSet::parse(lx)?;
        let float = match kind.as_str() {
            "float" => true,
            "spectrum" | "color" | "rgb" => false,
            other => {
                return Err(syntax(
                    &kind_at,
                    format!("texture type must be \"float\" or \"spectrum\", found \"{other}\""),
                ));
            }
        };
        let tex = self.make_texture(&class, float, &params, &at)?;
        self.report_unused(&params, &format!("Texture \"{name}\""))?;
        self.cx.info.textures += 1;
        let map = if float { &mut self.named.float_textures } else { &mut self.named.spectrum_textures };
        if map.insert(name.clone(), tex).is_some() {
            self.warn(Some(&at), format!("texture \"{name}\" redefined"))?;
        }
        Ok(())
    }
}
