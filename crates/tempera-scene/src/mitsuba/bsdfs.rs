//! Mitsuba BSDFs and textures. `diffuse`, `conductor`/`roughconductor`, `dielectric`/
//! `roughdielectric`, `plastic`/`roughplastic`, `twosided`, `bumpmap`, `mask` and `blendbsdf` map
//! onto Tempera's models; Beckmann and Phong distributions become GGX of the same alpha; other
//! plugins are approximated with a warning. Mitsuba BSDFs are one-sided (black from behind)
//! unless wrapped in `twosided`; dielectrics are two-sided by nature.

use super::props::{Props, color_of};
use super::{Ctx, Loader};
use crate::LoadError;
use roxmltree::Node;
use std::sync::Arc;
use tempera::material::{
    ConductorFresnel, ConductorMaterial, DielectricMaterial, Material, MixMaterial, PlasticMaterial, Roughness,
};
use tempera::math::Rgb;
use tempera::scene::MaterialId;
use tempera::texture::{Checkerboard, ImageTexture, Texture, UvMapping, WrapMode};
use tempera_image::ColorEncoding;

/// A BSDF as defined, before it is added to the scene.
#[derive(Clone, Debug)]
pub(super) struct BsdfDesc {
    /// `None` for Mitsuba's `null` BSDF: the surface is invisible.
    pub material: Option<Material>,
    pub one_sided: bool,
    pub displacement: Option<Texture>,
    pub opacity: Option<Texture>,
    /// The material id once added (reused by every shape referring to this BSDF).
    pub id: Option<MaterialId>,
}

impl BsdfDesc {
    fn new(material: Material, one_sided: bool) -> Self {
        Self { material: Some(material), one_sided, displacement: None, opacity: None, id: None }
    }
}

/// Refractive indices of the media Mitsuba names (Mitsuba 0.6 documentation, Table 3).
fn named_ior(name: &str) -> Option<f32> {
    Some(match name {
        "vacuum" => 1.0,
        "helium" => 1.000_036,
        "hydrogen" => 1.000_132,
        "air" => 1.000_277,
        "carbon dioxide" => 1.000_45,
        "water" => 1.333,
        "acetone" => 1.36,
        "ethanol" => 1.361,
        "carbon tetrachloride" => 1.461,
        "glycerol" => 1.4729,
        "benzene" => 1.501,
        "silicone oil" => 1.520_45,
        "bromine" => 1.661,
        "water ice" => 1.31,
        "fused quartz" => 1.458,
        "pyrex" => 1.470,
        "acrylic glass" => 1.49,
        "polypropylene" => 1.49,
        "bk7" => 1.5046,
        "sodium chloride" => 1.544,
        "amber" => 1.55,
        "pet" => 1.575,
        "diamond" => 2.419,
        _ => return None,
    })
}

/// RGB complex indices of Mitsuba's named conductors (reduced from their spectra at about
/// 650/550/450 nm).
fn named_conductor(name: &str) -> Option<(Rgb, Rgb)> {
    let c = |e: [f32; 3], k: [f32; 3]| Some((Rgb::from(e), Rgb::from(k)));
    match name {
        "Ag" => c([0.155, 0.117, 0.138], [4.828, 3.122, 2.147]),
        "Al" => c([1.657, 0.880, 0.521], [9.224, 6.270, 4.837]),
        "Au" => c([0.143, 0.374, 1.442], [3.983, 2.385, 1.603]),
        "Cu" => c([0.200, 0.924, 1.102], [3.912, 2.452, 2.142]),
        "CuZn" => c([0.444, 0.527, 1.094], [3.695, 2.765, 1.829]),
        "Cr" => c([3.107, 3.181, 2.323], [3.331, 3.329, 3.135]),
        "W" => c([4.371, 3.300, 2.998], [3.501, 2.605, 2.273]),
        "Ni_palik" => c([2.367, 1.666, 1.442], [4.447, 3.143, 2.577]),
        "TiN" => c([1.652, 1.145, 1.272], [3.200, 2.316, 1.585]),
        _ => None,
    }
}

impl Loader {
    /// A colour-or-texture property.
    pub(super) fn color_or_texture(
        &mut self,
        ctx: &Ctx,
        props: &Props,
        name: &str,
        default: Option<Rgb>,
    ) -> Result<Option<Texture>, LoadError> {
        if let Some(n) = props.named_object(name) {
            return self.texture_ref(ctx, n).map(Some);
        }
        Ok(props.color(ctx, name, false)?.or(default).map(Texture::Constant))
    }

    fn texture_ref(&mut self, ctx: &Ctx, n: Node) -> Result<Texture, LoadError> {
        if n.tag_name().name() == "ref" {
            let loc = ctx.loc(n);
            let id = n.attribute("id").ok_or_else(|| ctx.err(&loc, "<ref> needs an \"id\""))?;
            return self.textures.get(id).cloned().ok_or_else(|| ctx.err(&loc, format!("unknown texture \"{id}\"")));
        }
        self.texture(ctx, n)
    }

    fn ior(&mut self, ctx: &Ctx, props: &Props, name: &str, default: f32) -> Result<f32, LoadError> {
        if props.tag_of(name) == Some("string")
            && let Some(s) = props.string(ctx, name)?
        {
            return named_ior(&s).ok_or_else(|| ctx.err(&props.loc, format!("unknown index of refraction \"{s}\"")));
        }
        let v = props.float(ctx, name, f64::from(default))? as f32;
        if v <= 0.0 {
            return Err(ctx.err(&props.loc, format!("\"{name}\" must be positive")));
        }
        Ok(v)
    }

    fn roughness(&mut self, ctx: &Ctx, props: &Props, ty: &str, rough: bool) -> Result<Roughness, LoadError> {
        if !rough {
            return Ok(Roughness::alpha(0.0));
        }
        match props.string(ctx, "distribution")?.as_deref() {
            None | Some("ggx") => {}
            Some(d @ ("beckmann" | "phong" | "as")) => {
                self.warn_once(
                    &format!("distribution-{d}"),
                    Some(&props.loc),
                    format!("the {d} microfacet distribution is approximated by GGX with the same alpha"),
                )?;
            }
            Some(other) => {
                return Err(ctx.err(&props.loc, format!("unknown microfacet distribution \"{other}\" in {ty}")));
            }
        }
        let alpha = |this: &mut Self, name: &str| -> Result<Option<Texture>, LoadError> {
            if let Some(n) = props.named_object(name) {
                return this.texture_ref(ctx, n).map(Some);
            }
            Ok(props.color(ctx, name, false)?.map(|c| Texture::Constant(Rgb::splat(c.x))))
        };
        let a = alpha(self, "alpha")?.unwrap_or(Texture::Constant(Rgb::splat(0.1)));
        let u = alpha(self, "alphaU")?.unwrap_or_else(|| a.clone());
        let v = alpha(self, "alphaV")?.unwrap_or_else(|| a.clone());
        Ok(Roughness { u, v, remap: false })
    }

    pub(super) fn bsdf(&mut self, ctx: &Ctx, n: Node) -> Result<BsdfDesc, LoadError> {
        if n.tag_name().name() == "ref" {
            let loc = ctx.loc(n);
            let id = n.attribute("id").ok_or_else(|| ctx.err(&loc, "<ref> needs an \"id\""))?;
            return self.bsdfs.get(id).cloned().ok_or_else(|| ctx.err(&loc, format!("unknown BSDF \"{id}\"")));
        }
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        let desc = self.make_bsdf(ctx, &props, &ty)?;
        if let Some(m) = &desc.material {
            let name = match m {
                Material::Diffuse(_) => "diffuse",
                Material::DiffuseTransmission(_) => "diffuse transmission",
                Material::Conductor(_) => "conductor",
                Material::Dielectric(_) => "dielectric",
                Material::Plastic(_) => "plastic",
                Material::Layered(_) => "layered",
                Material::Mix(_) => "blend",
                Material::Interface => "interface",
            };
            if !matches!(ty.as_str(), "twosided" | "bumpmap" | "mask") {
                *self.cx.info.materials.entry(name.to_owned()).or_default() += 1;
            }
        }
        self.report_unused(ctx, &props, &format!("bsdf \"{ty}\""))?;
        Ok(desc)
    }

    fn inner_bsdf(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<BsdfDesc, LoadError> {
        let inner = props.object("bsdf").or_else(|| props.object("ref"));
        let inner = inner.ok_or_else(|| ctx.err(&props.loc, format!("{ty} needs a nested <bsdf> or <ref>")))?;
        self.bsdf(ctx, inner)
    }

    /// Adds a BSDF's material to the scene (once) and returns its id.
    pub(super) fn register(&mut self, desc: &mut BsdfDesc) -> Option<MaterialId> {
        if let Some(id) = desc.id {
            return Some(id);
        }
        let material = desc.material.clone()?;
        let id = self.cx.builder.add_material(material);
        if desc.one_sided {
            self.cx.builder.set_one_sided(id);
        }
        if let Some(d) = &desc.displacement {
            self.cx.builder.set_displacement(id, d.clone());
        }
        desc.id = Some(id);
        Some(id)
    }

    /// `dielectric`, `roughdielectric` and (approximated) `thindielectric`.
    fn dielectric(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<BsdfDesc, LoadError> {
        let rough = ty.starts_with("rough");
        if ty == "thindielectric" {
            self.warn_once(
                "thindielectric",
                Some(&props.loc),
                "thindielectric is approximated by a solid dielectric of the same index",
            )?;
        }
        let eta = self.ior(ctx, props, "intIOR", 1.5046)? / self.ior(ctx, props, "extIOR", 1.000_277)?;
        for name in ["specularReflectance", "specularTransmittance"] {
            if props.color(ctx, name, false)?.is_some_and(|c| c != Rgb::ONE) {
                self.warn_once(
                    name,
                    Some(&props.loc),
                    format!("{name} other than 1 is not supported for dielectrics"),
                )?;
            }
        }
        let roughness = self.roughness(ctx, props, ty, rough)?;
        Ok(BsdfDesc::new(Material::Dielectric(DielectricMaterial { eta, roughness }), false))
    }

    /// `conductor` and `roughconductor`: a named material, or `eta` and `k` (copper's by
    /// default), relative to `extEta`.
    fn conductor(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<BsdfDesc, LoadError> {
        let rough = ty.starts_with("rough");
        let ext = props.float(ctx, "extEta", 1.0)? as f32;
        let fresnel = match props.string(ctx, "material")? {
            Some(name) if name == "none" => ConductorFresnel::Reflectance(Rgb::ONE.into()),
            Some(name) => {
                let (eta, k) = named_conductor(&name)
                    .ok_or_else(|| ctx.err(&props.loc, format!("unknown conductor material \"{name}\"")))?;
                ConductorFresnel::Ior { eta: (eta / ext).into(), k: (k / ext).into() }
            }
            None => {
                let (eta0, k0) = named_conductor("Cu").expect("copper is known");
                let eta = props.color(ctx, "eta", false)?.unwrap_or(eta0);
                let k = props.color(ctx, "k", false)?.unwrap_or(k0);
                ConductorFresnel::Ior { eta: (eta / ext).into(), k: (k / ext).into() }
            }
        };
        let roughness = self.roughness(ctx, props, ty, rough)?;
        let tint = self.color_or_texture(ctx, props, "specularReflectance", Some(Rgb::ONE))?.expect("default");
        Ok(BsdfDesc::new(Material::Conductor(ConductorMaterial { fresnel, roughness, tint }), true))
    }

    /// `blendbsdf`: two nested BSDFs mixed by a constant or textured `weight`.
    fn blend(&mut self, ctx: &Ctx, props: &Props) -> Result<BsdfDesc, LoadError> {
        let weight = match props.named_object("weight") {
            Some(n) => self.texture_ref(ctx, n)?,
            None => Texture::Constant(Rgb::splat(props.float(ctx, "weight", 0.5)? as f32)),
        };
        let parts: Vec<Node> = props.objects("bsdf").into_iter().chain(props.objects("ref")).collect();
        if parts.len() != 2 {
            return Err(ctx.err(&props.loc, "blendbsdf needs exactly two nested BSDFs"));
        }
        let mut ids = [0u32; 2];
        for (slot, n) in ids.iter_mut().zip(parts) {
            let mut d = self.bsdf(ctx, n)?;
            *slot = self
                .register(&mut d)
                .ok_or_else(|| ctx.err(&props.loc, "blendbsdf of a null BSDF is not supported"))?
                .0;
        }
        Ok(BsdfDesc::new(Material::Mix(MixMaterial { materials: ids, amount: weight }), false))
    }

    fn make_bsdf(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<BsdfDesc, LoadError> {
        let rough = ty.starts_with("rough");
        Ok(match ty {
            "diffuse" | "roughdiffuse" => {
                if ty == "roughdiffuse" {
                    self.warn_once(
                        "roughdiffuse",
                        Some(&props.loc),
                        "roughdiffuse (Oren–Nayar) is approximated by Lambertian diffuse",
                    )?;
                    self.ignore(ctx, props, &["alpha", "useFastApprox"], "Lambertian diffuse stands in for Oren–Nayar");
                }
                let r = self.color_or_texture(ctx, props, "reflectance", Some(Rgb::splat(0.5)))?.expect("default");
                BsdfDesc::new(Material::diffuse(r), true)
            }
            "conductor" | "roughconductor" => self.conductor(ctx, props, ty)?,
            "dielectric" | "roughdielectric" | "thindielectric" => self.dielectric(ctx, props, ty)?,
            "plastic" | "roughplastic" => {
                let eta = self.ior(ctx, props, "intIOR", 1.49)? / self.ior(ctx, props, "extIOR", 1.000_277)?;
                let diffuse =
                    self.color_or_texture(ctx, props, "diffuseReflectance", Some(Rgb::splat(0.5)))?.expect("default");
                let specular = props.color(ctx, "specularReflectance", false)?.unwrap_or(Rgb::ONE);
                let nonlinear = props.bool(ctx, "nonlinear", false)?;
                let roughness = self.roughness(ctx, props, ty, rough)?;
                let mut m = PlasticMaterial::new(diffuse, roughness, eta, nonlinear);
                m.specular = tempera::math::luminance(specular);
                BsdfDesc::new(Material::Plastic(m), true)
            }
            "twosided" => {
                let mut inner = self.inner_bsdf(ctx, props, ty)?;
                inner.one_sided = false;
                inner.id = None;
                inner
            }
            "bumpmap" => {
                let tex =
                    props.object("texture").ok_or_else(|| ctx.err(&props.loc, "bumpmap needs a nested <texture>"))?;
                let tex = self.texture(ctx, tex)?;
                let mut inner = self.inner_bsdf(ctx, props, ty)?;
                inner.displacement = Some(tex);
                inner.id = None;
                inner
            }
            "mask" => {
                let opacity = self.color_or_texture(ctx, props, "opacity", Some(Rgb::splat(0.5)))?.expect("default");
                let mut inner = self.inner_bsdf(ctx, props, ty)?;
                inner.opacity = Some(opacity);
                inner
            }
            "blendbsdf" => self.blend(ctx, props)?,
            "coating" | "roughcoating" => {
                self.warn_once(
                    "coating",
                    Some(&props.loc),
                    format!("{ty} is approximated by its base BSDF without the coating"),
                )?;
                let coating =
                    ["intIOR", "extIOR", "thickness", "sigmaA", "alpha", "distribution", "specularReflectance"];
                self.ignore(ctx, props, &coating, "the coating of an approximated coating BSDF");
                self.inner_bsdf(ctx, props, ty)?
            }
            "null" => BsdfDesc { material: None, one_sided: false, displacement: None, opacity: None, id: None },
            other @ ("phong" | "ward" | "irawan" | "hk" | "dipole" | "difftrans" | "sssbrdf" | "mixturebsdf") => {
                let unused = props.unused();
                let names: Vec<&str> = unused.iter().filter_map(|n| n.attribute("name")).collect();
                self.ignore(ctx, props, &names, "a grey diffuse stands in for the unsupported BSDF");
                self.warn_once(
                    &format!("bsdf-{other}"),
                    Some(&props.loc),
                    format!("bsdf \"{other}\" is not supported; a grey diffuse stands in for it"),
                )?;
                BsdfDesc::new(Material::diffuse(Rgb::splat(0.5)), true)
            }
            other => return Err(ctx.err(&props.loc, format!("unknown bsdf plugin \"{other}\""))),
        })
    }

    pub(super) fn image(
        &mut self,
        ctx: &Ctx,
        file: &str,
        encoding: ColorEncoding,
        at: &crate::Loc,
    ) -> Result<Arc<tempera::texture::Image>, LoadError> {
        self.cx.image(&ctx.resolve(file), encoding, false, at)
    }

    fn mapping(ctx: &Ctx, props: &Props, scale: f32) -> Result<UvMapping, LoadError> {
        Ok(UvMapping {
            su: props.float(ctx, "uscale", 1.0)? as f32 * scale,
            sv: props.float(ctx, "vscale", 1.0)? as f32 * scale,
            du: props.float(ctx, "uoffset", 0.0)? as f32 * scale,
            dv: props.float(ctx, "voffset", 0.0)? as f32 * scale,
        })
    }

    pub(super) fn texture(&mut self, ctx: &Ctx, n: Node) -> Result<Texture, LoadError> {
        if n.tag_name().name() == "ref" {
            return self.texture_ref(ctx, n);
        }
        if n.tag_name().name() != "texture" {
            return color_of(ctx, n, false).map(Texture::Constant);
        }
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        self.cx.info.textures += 1;
        let tex = match ty.as_str() {
            "bitmap" => {
                let file =
                    props.string(ctx, "filename")?.ok_or_else(|| ctx.err(&props.loc, "bitmap needs \"filename\""))?;
                let gamma = props.float(ctx, "gamma", -1.0)? as f32;
                let encoding = if gamma == -1.0 {
                    ColorEncoding::Srgb
                } else if gamma == 1.0 {
                    ColorEncoding::Linear
                } else {
                    ColorEncoding::Gamma(gamma)
                };
                let image = self.image(ctx, &file, encoding, &props.loc)?;
                let wrap = props.string(ctx, "wrapMode")?.or(props.string(ctx, "wrapModeU")?);
                props.string(ctx, "wrapModeV")?;
                let wrap = match wrap.as_deref() {
                    None | Some("repeat") => WrapMode::Repeat,
                    Some("clamp") => WrapMode::Clamp,
                    Some("zero" | "black") => WrapMode::Black,
                    Some(other) => {
                        self.warn(Some(&props.loc), format!("wrap mode \"{other}\" is treated as repeat"))?;
                        WrapMode::Repeat
                    }
                };
                let filtering = ["filterType", "maxAnisotropy", "cache", "channel"];
                self.ignore(ctx, &props, &filtering, "image textures are filtered bilinearly");
                let mut t = ImageTexture::new(image);
                t.wrap = wrap;
                t.mapping = Self::mapping(ctx, &props, 1.0)?;
                Texture::Image(t)
            }
            "checkerboard" => {
                let even = self.color_or_texture(ctx, &props, "color0", Some(Rgb::splat(0.4)))?.expect("default");
                let odd = self.color_or_texture(ctx, &props, "color1", Some(Rgb::splat(0.2)))?.expect("default");
                // Mitsuba draws two checks per unit of uv.
                let mapping = Self::mapping(ctx, &props, 2.0)?;
                Texture::Checkerboard(Box::new(Checkerboard { even, odd, mapping }))
            }
            "scale" => {
                let inner = props.object("texture").or_else(|| props.named_object("texture"));
                let inner = match inner {
                    Some(t) => self.texture(ctx, t)?,
                    None => return Err(ctx.err(&props.loc, "scale texture needs a nested <texture>")),
                };
                let s = props.float(ctx, "scale", 1.0)? as f32;
                Texture::Scale(Box::new((inner, s.into())))
            }
            other @ ("gridtexture" | "curvature" | "vertexcolors" | "wireframe") => {
                self.warn(
                    Some(&props.loc),
                    format!("texture \"{other}\" is not supported; a constant 0.5 stands in for it"),
                )?;
                let unused = props.unused();
                let names: Vec<&str> = unused.iter().filter_map(|n| n.attribute("name")).collect();
                self.ignore(ctx, &props, &names, "a constant 0.5 stands in for the unsupported texture");
                Texture::Constant(Rgb::splat(0.5))
            }
            other => return Err(ctx.err(&props.loc, format!("unknown texture plugin \"{other}\""))),
        };
        self.report_unused(ctx, &props, &format!("texture \"{ty}\""))?;
        Ok(tex)
    }
}
