//! The pbrt-v4 scene loader: reads `.pbrt` files (with `Include`/`Import`), keeps pbrt's
//! graphics state and translates every directive into the core's [`SceneBuilder`] (pbrt-v4 file
//! format reference, <https://pbrt.org/fileformat-v4>). What Tempera cannot represent exactly is
//! approximated with a warning, or refused with a clear error.

mod directives;
mod lexer;
mod lights;
mod materials;
mod media;
mod params;
mod shapes;

mod state;
mod textures;

use crate::context::LoadContext;
use crate::diagnostics::Loc;
use crate::{LoadError, LoadOptions, LoadedScene};
use lexer::{Lexer, TokenKind};
use params::ParamSet;
use state::{GraphicsState, MaterialSlot, Named, ObjectShape};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tempera::film::{FilmDesc, Filter};
use tempera::scene::MaterialId;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Block {
    Attribute,
    Transform,
}

struct Loader {
    cx: LoadContext,
    state: GraphicsState,
    stack: Vec<(GraphicsState, Block, Loc)>,
    named: Named,
    default_material: Option<MaterialId>,
    object: Option<(String, Vec<ObjectShape>, Loc)>,
    world_begun: bool,
}

impl Loader {
    fn new(options: &LoadOptions) -> Self {
        // pbrt-v4's film when the file names none: 1280x720, Gaussian filter of radius 1.5.
        let film = FilmDesc { width: 1280, height: 720, filter: Filter::Gaussian { radius: 1.5, sigma: 0.5 } };
        Self {
            cx: LoadContext::new(options, film),
            state: GraphicsState::default(),
            stack: Vec::new(),
            named: Named::default(),
            default_material: None,
            object: None,
            world_begun: false,
        }
    }

    /// Records a warning, or fails in strict mode.
    fn warn(&mut self, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.cx.warn(loc, message)
    }

    /// Warns once per `key` (e.g. once per approximated material type).
    fn warn_once(&mut self, key: &str, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.cx.warn_once(key, loc, message)
    }

    /// Marks the parameters `names` of `params` as read and records, for those present, that
    /// they are deliberately ignored and why.
    fn ignore(&mut self, params: &ParamSet, names: &[&str], why: &str) {
        for name in names {
            if let Some(p) = params.find(name) {
                self.cx.ignored(&p.loc, name, why);
            }
        }
    }

    /// Warns about every parameter of `params` that no lookup used.
    fn report_unused(&mut self, params: &ParamSet, what: &str) -> Result<(), LoadError> {
        let unused: Vec<(Loc, String)> = params
            .unused()
            .map(|p| (p.loc.clone(), format!("unused parameter \"{} {}\" in {what}", p.ty, p.name)))
            .collect();
        for (loc, message) in unused {
            self.warn(Some(&loc), message)?;
        }
        Ok(())
    }

    fn resolve(&self, loc: &Loc, file: &str) -> PathBuf {
        let p = Path::new(file);
        if p.is_absolute() {
            return p.to_owned();
        }
        loc.path().parent().map_or_else(|| p.to_owned(), |dir| dir.join(p))
    }

    fn material_id(&mut self, slot: &MaterialSlot) -> Option<MaterialId> {
        match slot {
            MaterialSlot::Id(id) => Some(*id),
            MaterialSlot::Interface => None,
            MaterialSlot::Default => Some(*self.default_material.get_or_insert_with(|| {
                self.cx.builder.add_material(tempera::material::Material::diffuse(tempera::math::Rgb::splat(0.5)))
            })),
        }
    }

    fn parse_file(&mut self, path: &Path, from: Option<&Loc>) -> Result<(), LoadError> {
        let text = self.cx.enter_file(path, from)?;
        self.parse_source(&text, path)?;
        self.cx.leave_file();
        Ok(())
    }

    fn parse_source(&mut self, text: &str, path: &Path) -> Result<(), LoadError> {
        self.cx.info.files += 1;
        let mut lx = Lexer::new(text, Arc::new(path.to_owned()));
        while let Some(tok) = lx.next_token()? {
            let loc = lx.loc_of(&tok);
            match tok.kind {
                TokenKind::Ident(name) => self.directive(name, &mut lx, loc)?,
                other => {
                    let found = match other {
                        TokenKind::Str(s) => format!("string \"{s}\""),
                        TokenKind::Number(v) => format!("number {v}"),
                        TokenKind::Open => "'['".into(),
                        TokenKind::Close => "']'".into(),
                        TokenKind::Ident(_) => unreachable!(),
                    };
                    return Err(lx.error(loc, format!("expected a directive, found {found}")));
                }
            }
        }
        Ok(())
    }
}

/// Loads a pbrt-v4 scene file.
pub fn load(path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    let mut loader = Loader::new(options);
    loader.parse_file(path, None)?;
    finish(loader)
}

/// Loads pbrt-v4 scene text as if it were the file `path` (relative names resolve against its
/// folder).
pub fn load_str(text: &str, path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    let mut loader = Loader::new(options);
    loader.parse_source(text, path)?;
    finish(loader)
}

fn finish(mut loader: Loader) -> Result<LoadedScene, LoadError> {
    if let Some((name, at)) = loader.named.camera_medium.take() {
        let medium = loader.medium_index(&name, &at)?;
        loader.cx.builder.set_camera_medium(medium);
    }
    if let Some((name, _, loc)) = &loader.object {
        return Err(LoadError::Syntax {
            loc: loc.clone(),
            message: format!("ObjectBegin \"{name}\" without ObjectEnd"),
        });
    }
    if let Some((_, block, loc)) = loader.stack.last() {
        let what = if *block == Block::Attribute { "AttributeBegin" } else { "TransformBegin" };
        return Err(LoadError::Syntax { loc: loc.clone(), message: format!("{what} without a matching end") });
    }
    Ok(loader.cx.finish())
}
