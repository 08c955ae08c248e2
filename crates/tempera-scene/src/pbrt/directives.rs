//! Dispatch of pbrt-v4 directives: transformations, attribute blocks, scene-wide settings
//! (camera, film, sampler, integrator, filter), includes and object instancing (media in
//! [`super::media`]).

use super::lexer::{Lexer, TokenKind, unescape};
use super::params::ParamSet;
use super::state::{self, MaterialSlot};
use super::{Block, Loader};
use crate::LoadError;
use crate::diagnostics::Loc;
use tempera::camera::CameraDesc;
use tempera::film::Filter;
use tempera::integrator::IntegratorKind;
use tempera::math::{Mat4, Vec3};
use tempera::medium::MediumInterface;
use tempera::scene::ChainDefaults;

/// Reads a quoted-string argument.
pub(super) fn string_arg(lx: &mut Lexer, what: &str) -> Result<(String, Loc), LoadError> {
    match lx.next_token()? {
        Some(t) => {
            let loc = lx.loc_of(&t);
            match t.kind {
                TokenKind::Str(s) => Ok((unescape(s), loc)),
                _ => Err(lx.error(loc, format!("expected a quoted {what}"))),
            }
        }
        None => Err(lx.error(lx.here(), format!("expected a quoted {what}, found end of file"))),
    }
}

/// Reads `n` numbers, bare or inside one pair of brackets.
fn numbers(lx: &mut Lexer, n: usize, directive: &str) -> Result<Vec<f32>, LoadError> {
    let bracketed = matches!(lx.peek()?, Some(t) if t.kind == TokenKind::Open);
    if bracketed {
        lx.next_token()?;
    }
    let mut out = Vec::with_capacity(n);
    while out.len() < n {
        let Some(t) = lx.next_token()? else {
            return Err(lx.error(lx.here(), format!("{directive} expects {n} numbers, found end of file")));
        };
        match t.kind {
            TokenKind::Number(v) => out.push(v as f32),
            _ => {
                let loc = lx.loc_of(&t);
                return Err(lx.error(loc, format!("{directive} expects {n} numbers, found {}", out.len())));
            }
        }
    }
    if bracketed {
        match lx.next_token()? {
            Some(t) if t.kind == TokenKind::Close => {}
            Some(t) => {
                return Err(lx.error(lx.loc_of(&t), format!("expected ']' after the {n} numbers of {directive}")));
            }
            None => return Err(lx.error(lx.here(), format!("expected ']' after the {n} numbers of {directive}"))),
        }
    }
    Ok(out)
}

/// Skips the arguments of an unknown directive: everything up to the next bare word.
fn skip_arguments(lx: &mut Lexer) -> Result<(), LoadError> {
    while let Some(t) = lx.peek()? {
        if matches!(t.kind, TokenKind::Ident(w) if w != "true" && w != "false") {
            break;
        }
        lx.next_token()?;
    }
    Ok(())
}

impl Loader {
    fn apply(&mut self, m: Mat4) {
        self.state.ctm *= m;
    }

    fn begin(&mut self, block: Block, loc: Loc) {
        self.stack.push((self.state.clone(), block, loc));
    }

    fn end(&mut self, block: Block, loc: &Loc) -> Result<(), LoadError> {
        let name = |b: Block| if b == Block::Attribute { "Attribute" } else { "Transform" };
        match self.stack.pop() {
            Some((saved, b, _)) if b == block => {
                if block == Block::Attribute {
                    self.state = saved;
                } else {
                    self.state.ctm = saved.ctm;
                }
                Ok(())
            }
            Some((_, b, open)) => Err(LoadError::Syntax {
                loc: loc.clone(),
                message: format!("{}End does not match {}Begin at line {}", name(block), name(b), open.line),
            }),
            None => Err(LoadError::Syntax {
                loc: loc.clone(),
                message: format!("{}End without {}Begin", name(block), name(block)),
            }),
        }
    }

    pub(super) fn directive(&mut self, name: &str, lx: &mut Lexer, loc: Loc) -> Result<(), LoadError> {
        match name {
            "AttributeBegin" | "AttributeEnd" | "TransformBegin" | "TransformEnd" | "Identity" | "Translate"
            | "Scale" | "Rotate" | "LookAt" | "Transform" | "ConcatTransform" | "CoordinateSystem"
            | "CoordSysTransform" | "ReverseOrientation" => self.transform_directive(name, lx, loc)?,
            "WorldBegin" => {
                self.state.ctm = Mat4::IDENTITY;
                self.named.coord_systems.insert("world".into(), Mat4::IDENTITY);
                self.world_begun = true;
            }
            "WorldEnd" => {}
            "Option" => self.option(lx)?,
            "ColorSpace" => {
                let (space, at) = string_arg(lx, "colour space")?;
                if space != "srgb" {
                    self.warn(Some(&at), format!("colour space \"{space}\" is not supported; using sRGB"))?;
                }
            }
            "Camera" => self.camera(lx)?,
            "Film" => self.film(lx)?,
            "Sampler" => self.sampler(lx)?,
            "Integrator" => self.integrator(lx)?,
            "PixelFilter" => self.filter(lx)?,
            "Accelerator" => {
                string_arg(lx, "accelerator type")?;
                ParamSet::parse(lx)?;
            }
            "Texture" => self.texture_directive(lx)?,
            "Material" | "MakeNamedMaterial" | "NamedMaterial" => self.material_directive(name, lx)?,
            "LightSource" => self.light_source(lx)?,
            "AreaLightSource" => self.area_light_source(lx)?,
            "Shape" => self.shape_directive(lx)?,
            "ObjectBegin" | "ObjectEnd" | "ObjectInstance" => self.object_directive(name, lx, loc)?,
            "Include" | "Import" => {
                let (file, at) = string_arg(lx, "file name")?;
                let path = self.resolve(&at, &file);
                self.parse_file(&path, Some(&at))?;
            }
            "MakeNamedMedium" | "MediumInterface" => self.medium_directive(name, lx)?,
            "TransformTimes" | "ActiveTransform" | "AttributeState" => {
                skip_arguments(lx)?;
                self.warn_once(name, Some(&loc), format!("{name} (motion blur) is not supported and is ignored"))?;
            }
            _ => {
                skip_arguments(lx)?;
                self.warn(Some(&loc), format!("unknown directive '{name}' ignored"))?;
            }
        }
        Ok(())
    }

    /// The directives that change the transform or the attribute stack.
    fn transform_directive(&mut self, name: &str, lx: &mut Lexer, loc: Loc) -> Result<(), LoadError> {
        match name {
            "AttributeBegin" => self.begin(Block::Attribute, loc),
            "AttributeEnd" => self.end(Block::Attribute, &loc)?,
            "TransformBegin" => self.begin(Block::Transform, loc),
            "TransformEnd" => self.end(Block::Transform, &loc)?,
            "Identity" => self.state.ctm = Mat4::IDENTITY,
            "Translate" => {
                let v = numbers(lx, 3, name)?;
                self.apply(Mat4::from_translation(Vec3::new(v[0], v[1], v[2])));
            }
            "Scale" => {
                let v = numbers(lx, 3, name)?;
                self.apply(Mat4::from_scale(Vec3::new(v[0], v[1], v[2])));
            }
            "Rotate" => {
                let v = numbers(lx, 4, name)?;
                let r = state::rotation(v[0], Vec3::new(v[1], v[2], v[3])).ok_or_else(|| LoadError::Syntax {
                    loc: loc.clone(),
                    message: "Rotate about a zero axis".into(),
                })?;
                self.apply(r);
            }
            "LookAt" => {
                let v = numbers(lx, 9, name)?;
                let m = state::look_at(
                    Vec3::new(v[0], v[1], v[2]),
                    Vec3::new(v[3], v[4], v[5]),
                    Vec3::new(v[6], v[7], v[8]),
                )
                .ok_or_else(|| LoadError::Syntax {
                    loc: loc.clone(),
                    message: "degenerate LookAt (eye = target or up parallel to the view)".into(),
                })?;
                self.apply(m);
            }
            "Transform" | "ConcatTransform" => {
                let v = numbers(lx, 16, name)?;
                let m = Mat4::from_cols_slice(&v);
                if name == "Transform" {
                    self.state.ctm = m;
                } else {
                    self.apply(m);
                }
            }
            "CoordinateSystem" => {
                let (n, _) = string_arg(lx, "coordinate system name")?;
                self.named.coord_systems.insert(n, self.state.ctm);
            }
            "CoordSysTransform" => {
                let (n, at) = string_arg(lx, "coordinate system name")?;
                match self.named.coord_systems.get(&n) {
                    Some(m) => self.state.ctm = *m,
                    None => self.warn(Some(&at), format!("unknown coordinate system \"{n}\""))?,
                }
            }
            "ReverseOrientation" => self.state.reverse_orientation = !self.state.reverse_orientation,
            _ => unreachable!("transform directives only"),
        }
        Ok(())
    }

    /// `Material`, `MakeNamedMaterial` and `NamedMaterial`.
    fn material_directive(&mut self, name: &str, lx: &mut Lexer) -> Result<(), LoadError> {
        match name {
            "Material" => {
                let (ty, at) = string_arg(lx, "material type")?;
                let params = ParamSet::parse(lx)?;
                let slot = self.make_material(&ty, &params, &at)?;
                self.report_unused(&params, &format!("Material \"{ty}\""))?;
                self.state.material = slot;
            }
            "MakeNamedMaterial" => {
                let (n, at) = string_arg(lx, "material name")?;
                let params = ParamSet::parse(lx)?;
                let ty = params.string("type")?.map(str::to_owned).ok_or_else(|| LoadError::Syntax {
                    loc: at.clone(),
                    message: format!("MakeNamedMaterial \"{n}\" needs a \"string type\" parameter"),
                })?;
                let slot = self.make_material(&ty, &params, &at)?;
                self.report_unused(&params, &format!("MakeNamedMaterial \"{n}\""))?;
                if self.named.materials.insert(n.clone(), slot).is_some() {
                    self.warn(Some(&at), format!("material \"{n}\" redefined"))?;
                }
            }
            "NamedMaterial" => {
                let (n, at) = string_arg(lx, "material name")?;
                self.state.material = self
                    .named
                    .materials
                    .get(&n)
                    .cloned()
                    .ok_or_else(|| LoadError::Syntax { loc: at, message: format!("unknown material \"{n}\"") })?;
            }
            _ => unreachable!("material directives only"),
        }
        Ok(())
    }

    /// Object instancing: `ObjectBegin`, `ObjectEnd` and `ObjectInstance`.
    fn object_directive(&mut self, name: &str, lx: &mut Lexer, loc: Loc) -> Result<(), LoadError> {
        match name {
            "ObjectBegin" => {
                let (n, at) = string_arg(lx, "object name")?;
                if self.object.is_some() {
                    return Err(LoadError::Syntax {
                        loc: at,
                        message: "ObjectBegin inside another ObjectBegin".into(),
                    });
                }
                self.begin(Block::Attribute, at.clone());
                self.object = Some((n, Vec::new(), at));
            }
            "ObjectEnd" => {
                let Some((n, shapes, _)) = self.object.take() else {
                    return Err(LoadError::Syntax { loc, message: "ObjectEnd without ObjectBegin".into() });
                };
                let prototype = self.make_prototype(shapes, &loc)?;
                self.named.objects.insert(n, prototype);
                self.end(Block::Attribute, &loc)?;
            }
            "ObjectInstance" => {
                let (n, at) = string_arg(lx, "object name")?;
                self.instance(&n, &at)?;
            }
            _ => unreachable!("object directives only"),
        }
        Ok(())
    }

    fn option(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let params = ParamSet::parse(lx)?;
        for p in &params.params {
            p.mark_used();
        }
        for p in &params.params {
            let loc = p.loc.clone();
            self.warn(Some(&loc), format!("Option \"{}\" is not supported and is ignored", p.name))?;
        }
        Ok(())
    }

    fn camera(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "camera type")?;
        let params = ParamSet::parse(lx)?;
        if ty != "perspective" {
            return Err(LoadError::Syntax {
                loc: at,
                message: format!("camera \"{ty}\" is not supported (only \"perspective\")"),
            });
        }
        let camera_to_world = self.state.ctm.inverse();
        if !camera_to_world.is_finite() {
            return Err(LoadError::Syntax { loc: at, message: "the camera transformation is not invertible".into() });
        }
        self.named.coord_systems.insert("camera".into(), camera_to_world);
        // pbrt-v4: the camera sits in the outside medium of the current `MediumInterface`,
        // which may be defined later in the file.
        self.named.camera_medium = Some((self.state.media.1.clone(), at.clone()));
        let screen_window = match params.floats("screenwindow")? {
            Some(w) if w.len() == 4 => Some([w[0] as f32, w[1] as f32, w[2] as f32, w[3] as f32]),
            Some(_) => return Err(LoadError::Syntax { loc: at, message: "\"screenwindow\" needs 4 values".into() }),
            None => None,
        };
        let fov = params.float("fov", 90.0)?;
        if !(fov > 0.0 && fov < 180.0) {
            return Err(LoadError::Syntax { loc: at, message: format!("fov {fov} is outside (0, 180)") });
        }
        self.cx.builder.set_camera(CameraDesc {
            camera_to_world,
            fov_degrees: fov as f32,
            fov_axis: tempera::camera::FovAxis::Shorter,
            lens_radius: params.float("lensradius", 0.0)? as f32,
            focal_distance: params.float("focaldistance", 1e6)? as f32,
            screen_window,
        });
        self.report_unused(&params, "Camera \"perspective\"")
    }

    fn film(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "film type")?;
        let params = ParamSet::parse(lx)?;
        if ty != "rgb" {
            self.warn(Some(&at), format!("film \"{ty}\" is treated as \"rgb\""))?;
        }
        let (w, h) = (params.int("xresolution", 1280)?, params.int("yresolution", 720)?);
        if !(1..=65_536).contains(&w) || !(1..=65_536).contains(&h) {
            return Err(LoadError::Syntax { loc: at, message: format!("film resolution {w}x{h} is out of range") });
        }
        self.cx.film.width = w as u32;
        self.cx.film.height = h as u32;
        if let Some(name) = params.string("filename")? {
            self.cx.defaults.output = Some(name.into());
        }
        self.report_unused(&params, &format!("Film \"{ty}\""))
    }

    fn sampler(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "sampler type")?;
        let params = ParamSet::parse(lx)?;
        let spp = params.int("pixelsamples", 16)?;
        if !(1..=1 << 24).contains(&spp) {
            return Err(LoadError::Syntax { loc: at, message: format!("pixelsamples {spp} is out of range") });
        }
        self.cx.defaults.spp = spp as u32;
        self.report_unused(&params, &format!("Sampler \"{ty}\""))
    }

    fn integrator(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "integrator type")?;
        let params = ParamSet::parse(lx)?;
        let depth = params.int("maxdepth", 5)?;
        if !(0..=100_000).contains(&depth) {
            return Err(LoadError::Syntax { loc: at, message: format!("maxdepth {depth} is out of range") });
        }
        self.cx.defaults.max_depth = depth as u32;
        self.cx.info.integrator = Some(ty.clone());
        self.cx.defaults.integrator = match ty.as_str() {
            "path" | "volpath" => Some(IntegratorKind::Path),
            "mlt" => Some(IntegratorKind::Mmlt),
            other => IntegratorKind::from_name(other),
        };
        if ty == "sppm" {
            // pbrt-v4's SPPM: photons per iteration (-1: one per pixel) and the initial radius;
            // its seed is the render's --seed here.
            let photons = params.int("photonsperiteration", -1)?;
            let radius = params.float("radius", 1.0)?;
            if !(radius.is_finite() && radius > 0.0) || photons == 0 || photons > 1_000_000_000 {
                return Err(LoadError::Syntax {
                    loc: at,
                    message: format!("sppm needs a positive radius and photonsperiteration (got {radius}, {photons})"),
                });
            }
            self.cx.defaults.photons = (photons > 0).then_some(photons as u64);
            self.cx.defaults.radius = Some(radius as f32);
            params.int("seed", 0)?;
        }
        if ty == "mlt" {
            self.mlt_parameters(&params, &at, depth)?;
        }
        self.report_unused(&params, &format!("Integrator \"{ty}\""))
    }

    /// pbrt-v4's `mlt` parameters for Tempera's Markov-chain integrators: mutations per pixel
    /// (pbrt-v4's default 100, whatever the sampler's samples per pixel), bootstrap samples
    /// per path depth (as pbrt-v4 counts them), the large-step probability and `sigma`. pbrt-v4
    /// counts `chains` over all depths, Tempera per depth: `chains` over the `maxdepth + 1`
    /// depths, rounded up. `regularize`, which Tempera does not have, is warned about.
    fn mlt_parameters(&mut self, params: &ParamSet, at: &Loc, depth: i64) -> Result<(), LoadError> {
        let int = |name: &str| params.ints(name).map(|v| v.and_then(|v| v.first().copied()));
        let float = |name: &str| params.floats(name).map(|v| v.and_then(|v| v.first().copied()));
        let out_of_range = |message: String| LoadError::Syntax { loc: at.clone(), message };
        let mpp = int("mutationsperpixel")?.unwrap_or(100);
        if !(1..=1 << 24).contains(&mpp) {
            return Err(out_of_range(format!("mutationsperpixel {mpp} is out of range [1, 16777216]")));
        }
        let count = |name: &str| -> Result<Option<usize>, LoadError> {
            match int(name)? {
                Some(n) if !(1..=100_000_000).contains(&n) => {
                    Err(out_of_range(format!("{name} {n} is out of range [1, 100000000]")))
                }
                n => Ok(n.map(|n| n as usize)),
            }
        };
        let (bootstrap, chains) = (count("bootstrapsamples")?, count("chains")?);
        let large_step = float("largestepprobability")?;
        if large_step.is_some_and(|p| !(p as f32 > 0.0 && p <= 1.0)) {
            return Err(out_of_range(format!("largestepprobability {} must lie in (0, 1]", large_step.unwrap())));
        }
        let sigma = float("sigma")?;
        if sigma.is_some_and(|s| !(s as f32 > 0.0 && s <= 1.0)) {
            return Err(out_of_range(format!("sigma {} must lie in (0, 1]", sigma.unwrap())));
        }
        let depths = depth as usize + 1;
        self.cx.defaults.chain = ChainDefaults {
            mpp: Some(mpp as u32),
            bootstrap,
            chains: chains.map(|n| n.div_ceil(depths)),
            large_step: large_step.map(|p| p as f32),
            sigma: sigma.map(|s| s as f32),
        };
        if params.bool("regularize", false)? {
            self.warn(Some(at), "Integrator \"mlt\": \"regularize\" is not supported; rendering without it")?;
        }
        Ok(())
    }

    fn filter(&mut self, lx: &mut Lexer) -> Result<(), LoadError> {
        let (ty, at) = string_arg(lx, "filter type")?;
        let params = ParamSet::parse(lx)?;
        let default_radius = match ty.as_str() {
            "box" => 0.5,
            "gaussian" => 1.5,
            "triangle" | "mitchell" => 2.0,
            "sinc" => 4.0,
            _ => return Err(LoadError::Syntax { loc: at, message: format!("unknown pixel filter \"{ty}\"") }),
        };
        let (rx, ry) = (params.float("xradius", default_radius)?, params.float("yradius", default_radius)?);
        if rx != ry {
            self.warn(Some(&at), format!("anisotropic filter radii ({rx}, {ry}) are not supported; using {rx}"))?;
        }
        let radius = rx.max(1e-3) as f32;
        self.cx.film.filter = match ty.as_str() {
            "box" => Filter::Box { radius },
            "triangle" => Filter::Triangle { radius },
            "gaussian" => Filter::Gaussian { radius, sigma: params.float("sigma", 0.5)? as f32 },
            _ => {
                self.warn(
                    Some(&at),
                    format!("pixel filter \"{ty}\" is approximated by a Gaussian of the same radius"),
                )?;
                Filter::Gaussian { radius, sigma: radius / 3.0 }
            }
        };
        self.report_unused(&params, &format!("PixelFilter \"{ty}\""))
    }

    /// Turns the shapes of an object definition into a prototype stored once.
    fn make_prototype(
        &mut self,
        shapes: Vec<super::state::ObjectShape>,
        loc: &Loc,
    ) -> Result<Option<tempera::scene::PrototypeId>, LoadError> {
        let mut parts = Vec::with_capacity(shapes.len());
        for s in shapes {
            if s.emission.is_some() {
                self.warn_once(
                    "instance-emission",
                    Some(loc),
                    "area lights inside object instances are not supported (pbrt-v4 refuses them too); their emission is dropped",
                )?;
            }
            let Some(material) = self.material_id(&s.material) else { continue };
            self.cx.info.shapes += 1;
            if let tempera::geometry::Shape::Mesh(m) = &s.shape {
                self.cx.info.triangles += m.indices.len();
            }
            parts.push((s.shape, material, s.alpha));
        }
        Ok((!parts.is_empty()).then(|| self.cx.builder.add_prototype(parts)))
    }

    fn instance(&mut self, name: &str, at: &Loc) -> Result<(), LoadError> {
        if self.object.is_some() {
            return Err(LoadError::Syntax {
                loc: at.clone(),
                message: "ObjectInstance inside ObjectBegin is not supported".into(),
            });
        }
        let Some(prototype) = self.named.objects.get(name).copied() else {
            return Err(LoadError::Syntax { loc: at.clone(), message: format!("unknown object \"{name}\"") });
        };
        self.cx.info.instances += 1;
        if let Some(prototype) = prototype {
            let m = self.state.ctm;
            if !m.is_finite() || m.determinant().abs() < 1e-20 {
                return Err(LoadError::Syntax {
                    loc: at.clone(),
                    message: "ObjectInstance with a singular transformation".into(),
                });
            }
            self.cx.builder.add_instance(prototype, m);
        }
        Ok(())
    }

    /// Adds a shape to the scene, or to the object being defined.
    pub(super) fn add_shape(
        &mut self,
        shape: tempera::geometry::Shape,
        material: &MaterialSlot,
        emission: Option<tempera::scene::AreaEmission>,
        alpha: Option<tempera::texture::Texture>,
        at: &Loc,
    ) -> Result<(), LoadError> {
        let bounds_media = !self.state.media.0.is_empty() || !self.state.media.1.is_empty();
        if let Some((_, shapes, _)) = &mut self.object {
            shapes.push(super::state::ObjectShape { shape, material: material.clone(), emission, alpha });
            if bounds_media {
                self.warn_once(
                    "instance-media",
                    None,
                    "media boundaries inside object instances are not supported; those shapes bound no medium",
                )?;
            }
            return Ok(());
        }
        let id = match (self.material_id(material), bounds_media) {
            (Some(id), _) => id,
            // pbrt's `interface` material: invisible, unless it bounds media.
            (None, false) => return Ok(()),
            (None, true) => *self
                .named
                .interface_material
                .get_or_insert_with(|| self.cx.builder.add_material(tempera::material::Material::Interface)),
        };
        self.cx.info.shapes += 1;
        if emission.is_some() {
            *self.cx.info.lights.entry("area (diffuse)".to_owned()).or_default() += 1;
        }
        if let tempera::geometry::Shape::Mesh(m) = &shape {
            self.cx.info.triangles += m.indices.len();
        }
        self.cx.builder.add_shape_with_alpha(shape, id, emission, alpha);
        if bounds_media {
            let (inside, outside) = self.state.media.clone();
            let interface =
                MediumInterface { inside: self.medium_index(&inside, at)?, outside: self.medium_index(&outside, at)? };
            self.cx.builder.set_shape_medium(self.cx.builder.shape_count() - 1, interface);
        }
        Ok(())
    }
}
