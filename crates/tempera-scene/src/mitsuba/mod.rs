//! The Mitsuba 0.5/0.6 XML scene loader (Mitsuba 0.6 documentation, ch. 6 "Scene file format"
//! and ch. 8 "Plugin reference"): `<default>` and `$name` substitution, `<include>`, `id`/`<ref>`,
//! transforms, shapes, BSDFs, textures, emitters, the sensor with its film and sampler, and the
//! integrator, translated into the core's [`SceneBuilder`]. Positions come from `roxmltree`.

mod bsdfs;
mod emitters;
mod media;
mod props;
mod shapes;
mod sky;

use crate::context::LoadContext;
use crate::diagnostics::Loc;
use crate::{LoadError, LoadOptions, LoadedScene};
use bsdfs::BsdfDesc;
use props::Props;
use roxmltree::Node;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tempera::camera::{CameraDesc, FovAxis};
use tempera::film::{FilmDesc, Filter};
use tempera::integrator::IntegratorKind;
use tempera::math::{Mat4, Vec3};
use tempera::scene::PrototypeId;
use tempera::texture::Texture;

/// Per-file context: the file name (for locations) and the `<default>` values in effect.
pub(super) struct Ctx {
    file: Arc<PathBuf>,
    defaults: HashMap<String, String>,
}

impl Ctx {
    pub fn loc(&self, n: Node) -> Loc {
        let pos = n.document().text_pos_at(n.range().start);
        Loc::new(&self.file, pos.row, pos.col)
    }

    pub fn err(&self, loc: &Loc, message: impl Into<String>) -> LoadError {
        LoadError::Syntax { loc: loc.clone(), message: message.into() }
    }

    /// Replaces `$name` by the `<default>` of that name.
    pub fn subst(&self, value: &str, loc: &Loc) -> Result<String, LoadError> {
        if !value.contains('$') {
            return Ok(value.to_owned());
        }
        let mut out = String::with_capacity(value.len());
        let mut rest = value;
        while let Some(i) = rest.find('$') {
            out.push_str(&rest[..i]);
            let after = &rest[i + 1..];
            let len = after.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(after.len());
            let name = &after[..len];
            match self.defaults.get(name) {
                Some(v) => out.push_str(v),
                None => return Err(self.err(loc, format!("\"${name}\" has no <default> value"))),
            }
            rest = &after[len..];
        }
        out.push_str(rest);
        Ok(out)
    }

    pub fn resolve(&self, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() { p.to_owned() } else { self.file.parent().map_or_else(|| p.to_owned(), |d| d.join(p)) }
    }
}

struct Loader {
    cx: LoadContext,
    bsdfs: HashMap<String, BsdfDesc>,
    textures: HashMap<String, Texture>,
    groups: HashMap<String, Option<PrototypeId>>,
    /// Named media, by their index in the scene.
    media: HashMap<String, u32>,
}

impl Loader {
    fn warn(&mut self, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.cx.warn(loc, message)
    }

    fn warn_once(&mut self, key: &str, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.cx.warn_once(key, loc, message)
    }

    /// Marks the properties `names` of `props` as read and records, for those present, that
    /// they are deliberately ignored and why.
    fn ignore(&mut self, ctx: &Ctx, props: &Props, names: &[&str], why: &str) {
        for node in props.take(names) {
            let name = node.attribute("name").unwrap_or_default();
            self.cx.ignored(&ctx.loc(node), name, why);
        }
    }

    /// Warns about the properties of `props` that nothing read.
    fn report_unused(&mut self, ctx: &Ctx, props: &Props, what: &str) -> Result<(), LoadError> {
        for n in props.unused() {
            let name = n.attribute("name").map_or_else(|| format!("<{}>", n.tag_name().name()), |s| format!("\"{s}\""));
            self.warn(Some(&ctx.loc(n)), format!("unused property {name} in {what}"))?;
        }
        Ok(())
    }

    fn load_file(
        &mut self,
        path: &Path,
        from: Option<&Loc>,
        defaults: HashMap<String, String>,
    ) -> Result<(), LoadError> {
        let text = self.cx.enter_file(path, from)?;
        self.load_text(&text, path, defaults)?;
        self.cx.leave_file();
        Ok(())
    }

    fn load_text(&mut self, text: &str, path: &Path, defaults: HashMap<String, String>) -> Result<(), LoadError> {
        let file = Arc::new(path.to_owned());
        self.cx.info.files += 1;
        let doc = roxmltree::Document::parse(text).map_err(|e| {
            let pos = e.pos();
            LoadError::Syntax { loc: Loc::new(&file, pos.row, pos.col), message: format!("malformed XML: {e}") }
        })?;
        let mut ctx = Ctx { file, defaults };
        let root = doc.root_element();
        let loc = ctx.loc(root);
        if root.tag_name().name() != "scene" {
            return Err(ctx.err(&loc, format!("expected <scene>, found <{}>", root.tag_name().name())));
        }
        if let Some(v) = root.attribute("version")
            && v.starts_with('3')
        {
            return Err(
                ctx.err(&loc, format!("Mitsuba 3 scenes (version {v}) are not supported; use the Mitsuba 0.6 format"))
            );
        }
        for child in root.children().filter(Node::is_element) {
            self.scene_child(&mut ctx, child)?;
        }
        Ok(())
    }

    fn scene_child(&mut self, ctx: &mut Ctx, n: Node) -> Result<(), LoadError> {
        let loc = ctx.loc(n);
        match n.tag_name().name() {
            "default" => {
                let (Some(name), Some(value)) = (n.attribute("name"), n.attribute("value")) else {
                    return Err(ctx.err(&loc, "<default> needs \"name\" and \"value\""));
                };
                ctx.defaults.entry(name.to_owned()).or_insert_with(|| value.to_owned());
            }
            "include" => {
                let file = n.attribute("filename").ok_or_else(|| ctx.err(&loc, "<include> needs \"filename\""))?;
                let path = ctx.resolve(&ctx.subst(file, &loc)?);
                self.load_file(&path, Some(&loc), ctx.defaults.clone())?;
            }
            "integrator" => self.integrator(ctx, n)?,
            "sensor" => self.sensor(ctx, n)?,
            "bsdf" => {
                let desc = self.bsdf(ctx, n)?;
                match n.attribute("id") {
                    Some(id) => {
                        self.bsdfs.insert(id.to_owned(), desc);
                    }
                    None => self.warn(Some(&loc), "a top-level <bsdf> without \"id\" cannot be used")?,
                }
            }
            "texture" => {
                let tex = self.texture(ctx, n)?;
                let id = n.attribute("id").ok_or_else(|| ctx.err(&loc, "a top-level <texture> needs an \"id\""))?;
                self.cx.info.textures += 1;
                self.textures.insert(id.to_owned(), tex);
            }
            "shape" => self.shape(ctx, n, None)?,
            "emitter" => self.emitter(ctx, n)?,
            "medium" => {
                if n.attribute("id").is_none() {
                    self.warn(Some(&loc), "a top-level <medium> without \"id\" cannot be used")?;
                }
                self.medium(ctx, n)?;
            }
            "phase" | "subsurface" => {
                return Err(ctx.err(
                    &loc,
                    format!("<{}> outside a medium (subsurface scattering) is not supported", n.tag_name().name()),
                ));
            }
            other => self.warn(Some(&loc), format!("unknown element <{other}> ignored"))?,
        }
        Ok(())
    }

    fn integrator(&mut self, ctx: &Ctx, n: Node) -> Result<(), LoadError> {
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        // Wrapper integrators (adaptive sampling, irradiance caching) hold the real one.
        if let Some(inner) = props.object("integrator") {
            self.warn(Some(&props.loc), format!("integrator \"{ty}\" wraps another; using the inner one"))?;
            return self.integrator(ctx, inner);
        }
        // Mitsuba counts path vertices after the camera (1 = emitters seen directly); pbrt and
        // Tempera count scattering events, one fewer.
        let depth = props.int(ctx, "maxDepth", -1)?;
        self.cx.defaults.max_depth = if depth < 0 { 1000 } else { (depth - 1).max(0) as u32 };
        self.cx.info.integrator = Some(ty.clone());
        self.cx.defaults.integrator = match ty.as_str() {
            "path" | "volpath" | "volpath_simple" | "direct" => Some(IntegratorKind::Path),
            "mlt" | "pssmlt" => Some(IntegratorKind::Pssmlt),
            other => IntegratorKind::from_name(other),
        };
        if props.bool(ctx, "hideEmitters", false)? {
            self.warn(Some(&props.loc), "hideEmitters is not supported: emitters stay visible")?;
        }
        if ty == "sppm" {
            self.sppm_settings(ctx, &props)?;
        }
        if matches!(ty.as_str(), "mlt" | "pssmlt") {
            self.chain_settings(ctx, &props, &ty)?;
        }
        self.ignore(ctx, &props, &["strictNormals"], "an option of Mitsuba's path tracers that Tempera does not offer");
        let quiet = [
            "rrDepth",
            "photonCount",
            "maxPasses",
            "initialRadius",
            "alpha",
            "granularity",
            "twoStage",
            "bidirectional",
            "directSamples",
            "lightImage",
            "sampleDirect",
        ];
        self.ignore(
            ctx,
            &props,
            &quiet,
            "a sampling parameter of Mitsuba's integrator; Tempera's integrators sample their own way",
        );
        self.report_unused(ctx, &props, &format!("integrator \"{ty}\""))
    }

    /// Mitsuba's Markov-chain integrators (rendered by Tempera's PSSMLT, with the sampler's
    /// samples per pixel as mutations per pixel, as Mitsuba counts them): `luminanceSamples`,
    /// the samples that estimate the normalisation, as the bootstrap's; and `pssmlt`'s large-step
    /// probability `pLarge`.
    fn chain_settings(&mut self, ctx: &Ctx, props: &Props, ty: &str) -> Result<(), LoadError> {
        let samples = props.int(ctx, "luminanceSamples", 100_000)?;
        if !(1..=100_000_000).contains(&samples) {
            return Err(ctx.err(&props.loc, format!("luminanceSamples must lie in [1, 10^8], not {samples}")));
        }
        self.cx.defaults.chain.bootstrap = Some(samples as usize);
        if ty == "pssmlt" {
            let p = props.float(ctx, "pLarge", 0.3)?;
            if !(p as f32 > 0.0 && p <= 1.0) {
                return Err(ctx.err(&props.loc, format!("pLarge must lie in (0, 1], not {p}")));
            }
            self.cx.defaults.chain.large_step = Some(p as f32);
        }
        Ok(())
    }

    /// Mitsuba's `sppm`: `photonCount` photons per pass and `initialRadius` (0: Mitsuba's
    /// automatic choice, which Tempera does not make). Iterations are the samples per pixel, as
    /// for pbrt-v4 files (`maxPasses` is not read); `alpha` is Tempera's fixed 2/3 (the two
    /// differ only in how fast the radius shrinks).
    fn sppm_settings(&mut self, ctx: &Ctx, props: &Props) -> Result<(), LoadError> {
        let photons = props.int(ctx, "photonCount", 250_000)?;
        if !(1..=1_000_000_000).contains(&photons) {
            return Err(ctx.err(&props.loc, format!("photonCount must lie in [1, 10^9], not {photons}")));
        }
        self.cx.defaults.photons = Some(photons as u64);
        let radius = props.float(ctx, "initialRadius", 0.0)?;
        if radius > 0.0 && radius.is_finite() {
            self.cx.defaults.radius = Some(radius as f32);
        } else {
            self.warn(
                Some(&props.loc),
                "sppm's automatic initial radius is not supported: radius 1 unless --radius says otherwise",
            )?;
        }
        Ok(())
    }

    fn sensor(&mut self, ctx: &Ctx, n: Node) -> Result<(), LoadError> {
        let props = Props::new(ctx, n);
        let ty = props.ty(ctx)?;
        if !matches!(ty.as_str(), "perspective" | "thinlens") {
            return Err(ctx.err(&props.loc, format!("sensor \"{ty}\" is not supported (perspective or thinlens)")));
        }
        let to_world = props.transform(ctx, "toWorld")?.unwrap_or(Mat4::IDENTITY);
        // Mitsuba's camera space has +x towards the image's left; Tempera's (pbrt's) towards
        // the right.
        let camera_to_world = to_world * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
        let fov_axis = match props.string(ctx, "fovAxis")?.as_deref() {
            None | Some("x") => FovAxis::X,
            Some("y") => FovAxis::Y,
            Some("smaller") => FovAxis::Shorter,
            Some("larger") => FovAxis::Larger,
            Some("diagonal") => FovAxis::Diagonal,
            Some(other) => return Err(ctx.err(&props.loc, format!("unknown fovAxis \"{other}\""))),
        };
        let fov = match props.float(ctx, "fov", -1.0)? {
            f if f > 0.0 && f < 180.0 => f,
            f if f >= 180.0 => return Err(ctx.err(&props.loc, format!("fov {f} must be below 180"))),
            _ => {
                let focal = props.string(ctx, "focalLength")?.unwrap_or_else(|| "50mm".into());
                let mm: f64 = focal
                    .trim_end_matches("mm")
                    .trim()
                    .parse()
                    .map_err(|_| ctx.err(&props.loc, format!("bad focalLength \"{focal}\"")))?;
                2.0 * (36.0 / (2.0 * mm)).atan().to_degrees()
            }
        };
        let (lens_radius, focal_distance) = if ty == "thinlens" {
            (props.float(ctx, "apertureRadius", 0.0)?, props.float(ctx, "focusDistance", 0.0)?)
        } else {
            (0.0, 1.0)
        };
        let fov_axis = if props.string(ctx, "focalLength")?.is_some() { FovAxis::X } else { fov_axis };
        props.float(ctx, "nearClip", 0.0)?;
        props.float(ctx, "farClip", 0.0)?;
        self.cx.builder.set_camera(CameraDesc {
            camera_to_world,
            fov_degrees: fov as f32,
            fov_axis,
            lens_radius: lens_radius as f32,
            focal_distance: focal_distance as f32,
            screen_window: None,
        });
        if let Some(film) = props.object("film") {
            self.film(ctx, film)?;
        }
        if let Some(sampler) = props.object("sampler") {
            let sp = Props::new(ctx, sampler);
            let count = sp.int(ctx, "sampleCount", 4)?;
            if !(1..=1 << 24).contains(&count) {
                return Err(ctx.err(&sp.loc, format!("sampleCount {count} is out of range")));
            }
            self.cx.defaults.spp = count as u32;
            self.ignore(ctx, &sp, &["scramble", "dimension"], "Tempera's samplers are not low-discrepancy");
            self.report_unused(ctx, &sp, "sampler")?;
        }
        // The medium the sensor sits in: a nested <medium> or a <ref> to one.
        let medium = props.object("medium").or_else(|| {
            props.objects("ref").into_iter().find(|r| r.attribute("id").is_some_and(|id| self.media.contains_key(id)))
        });
        if let Some(m) = medium {
            let index = self.medium(ctx, m)?;
            self.cx.builder.set_camera_medium(Some(index));
        }
        self.report_unused(ctx, &props, &format!("sensor \"{ty}\""))
    }

    fn film(&mut self, ctx: &Ctx, n: Node) -> Result<(), LoadError> {
        let props = Props::new(ctx, n);
        let (w, h) = (props.int(ctx, "width", 768)?, props.int(ctx, "height", 576)?);
        if !(1..=65_536).contains(&w) || !(1..=65_536).contains(&h) {
            return Err(ctx.err(&props.loc, format!("film size {w}x{h} is out of range")));
        }
        self.cx.film.width = w as u32;
        self.cx.film.height = h as u32;
        // Output-format options do not change the rendered radiance.
        for name in [
            "fileFormat",
            "pixelFormat",
            "componentFormat",
            "tonemapMethod",
            "banner",
            "highQualityEdges",
            "attachLog",
            "gamma",
            "exposure",
            "key",
            "burn",
        ] {
            let _ = (props.string(ctx, name), props.bool(ctx, name, false), props.float(ctx, name, 0.0));
        }
        if props.find_crop() {
            self.warn(Some(&props.loc), "film crop windows are ignored")?;
        }
        self.cx.film.filter = match props.object("rfilter") {
            None => Filter::Gaussian { radius: 2.0, sigma: 0.5 },
            Some(f) => {
                let fp = Props::new(ctx, f);
                let ty = fp.ty(ctx)?;
                let filter = match ty.as_str() {
                    "box" => Filter::Box { radius: fp.float(ctx, "radius", 0.5)? as f32 },
                    "tent" => Filter::Triangle { radius: fp.float(ctx, "radius", 1.0)? as f32 },
                    "gaussian" => {
                        let s = fp.float(ctx, "stddev", 0.5)? as f32;
                        Filter::Gaussian { radius: 4.0 * s, sigma: s }
                    }
                    other => {
                        self.warn(
                            Some(&fp.loc),
                            format!("reconstruction filter \"{other}\" is approximated by a Gaussian"),
                        )?;
                        self.ignore(ctx, &fp, &["B", "C", "lobes"], "the filter is approximated by a Gaussian");
                        Filter::Gaussian { radius: 2.0, sigma: 0.5 }
                    }
                };
                self.report_unused(ctx, &fp, &format!("rfilter \"{ty}\""))?;
                filter
            }
        };
        self.report_unused(ctx, &props, "film")
    }
}

impl Props<'_, '_> {
    /// Marks crop-window properties as read; true when any was present.
    fn find_crop(&self) -> bool {
        let names = ["cropOffsetX", "cropOffsetY", "cropWidth", "cropHeight"];
        names.iter().filter(|n| self.named_value_present(n)).count() > 0
    }
}

/// Loads a Mitsuba XML scene file.
pub fn load(path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    let mut loader = new_loader(options);
    loader.load_file(path, None, HashMap::new())?;
    Ok(finish(loader))
}

/// Loads Mitsuba XML text as if read from `path`.
pub fn load_str(text: &str, path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    let mut loader = new_loader(options);
    loader.load_text(text, path, HashMap::new())?;
    Ok(finish(loader))
}

fn new_loader(options: &LoadOptions) -> Loader {
    // Mitsuba 0.6's film when the file names none: 768x576 (its Gaussian filter's stddev 0.5).
    let film = FilmDesc { width: 768, height: 576, filter: Filter::Gaussian { radius: 2.0, sigma: 0.5 } };
    Loader {
        cx: LoadContext::new(options, film),
        bsdfs: HashMap::new(),
        textures: HashMap::new(),
        groups: HashMap::new(),
        media: HashMap::new(),
    }
}

fn finish(loader: Loader) -> LoadedScene {
    loader.cx.finish()
}
