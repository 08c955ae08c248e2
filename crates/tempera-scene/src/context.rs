//! What every loader keeps while it reads a scene, and does alike: the scene being built, the
//! diagnostics, what was found (for `tempera info`), the film and render defaults the file asks
//! for, the cache of image textures, and the nesting of included files.

use crate::diagnostics::{Diagnostics, Loc};
use crate::{LoadError, LoadInfo, LoadOptions, LoadedScene};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use tempera::film::FilmDesc;
use tempera::math::Rgb;
use tempera::scene::{RenderDefaults, SceneBuilder};
use tempera::texture::Image;
use tempera_image::ColorEncoding;

/// Nesting limit for included files (guards against include cycles).
const MAX_INCLUDE_DEPTH: usize = 32;

pub(crate) struct LoadContext {
    pub builder: SceneBuilder,
    pub diag: Diagnostics,
    pub info: LoadInfo,
    pub film: FilmDesc,
    pub defaults: RenderDefaults,
    /// Images by file and the way they were read.
    images: HashMap<(PathBuf, String), Arc<Image>>,
    /// Files being read, the outermost included.
    depth: usize,
}

impl LoadContext {
    /// A context for a format whose film is `film` unless the file says otherwise.
    pub fn new(options: &LoadOptions, film: FilmDesc) -> Self {
        Self {
            builder: SceneBuilder::new(),
            diag: Diagnostics::new(options.strict),
            info: LoadInfo::default(),
            film,
            defaults: RenderDefaults::default(),
            images: HashMap::new(),
            depth: 0,
        }
    }

    /// Records a warning, or fails in strict mode.
    pub fn warn(&mut self, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.diag.warn(loc, message)
    }

    /// Warns once per `key` (e.g. once per approximated material type).
    pub fn warn_once(&mut self, key: &str, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        self.diag.warn_once(key, loc, message)
    }

    /// Records that the parameter `name` at `loc` was read and deliberately ignored, and why
    /// (`tempera info` lists them).
    pub fn ignored(&mut self, loc: &Loc, name: &str, why: &str) {
        self.info.ignored.push(format!("{loc}: \"{name}\": {why}"));
    }

    /// Reads the text of a scene file, included from `from` (the top file: `None`); counts it and
    /// its nesting, which [`Self::leave_file`] undoes. Invalid UTF-8 is replaced.
    pub fn enter_file(&mut self, path: &Path, from: Option<&Loc>) -> Result<String, LoadError> {
        if self.depth >= MAX_INCLUDE_DEPTH {
            let message = format!("includes nested deeper than {MAX_INCLUDE_DEPTH} (a cycle?)");
            return Err(match from {
                Some(loc) => LoadError::Syntax { loc: loc.clone(), message },
                None => LoadError::Unsupported { message },
            });
        }
        let bytes = std::fs::read(path).map_err(|source| match from {
            Some(loc) => {
                LoadError::Syntax { loc: loc.clone(), message: format!("cannot read {}: {source}", path.display()) }
            }
            None => LoadError::Io { path: path.to_owned(), source },
        })?;
        self.depth += 1;
        Ok(String::from_utf8_lossy(&bytes).into_owned())
    }

    /// The end of a file [`Self::enter_file`] read.
    pub fn leave_file(&mut self) {
        self.depth -= 1;
    }

    /// Reads an image texture (cached per file, encoding and `grey`: the channel average, for
    /// float textures); a file that cannot be read is an error at `at`.
    pub fn image(
        &mut self,
        path: &Path,
        encoding: ColorEncoding,
        grey: bool,
        at: &Loc,
    ) -> Result<Arc<Image>, LoadError> {
        let key = (path.to_owned(), format!("{encoding:?}-{grey}"));
        if let Some(img) = self.images.get(&key) {
            return Ok(Arc::clone(img));
        }
        let mut img = tempera_image::read_image(path, encoding)
            .map_err(|e| LoadError::Syntax { loc: at.clone(), message: e.to_string() })?;
        if grey {
            for p in &mut img.pixels {
                *p = Rgb::splat(p.element_sum() / 3.0);
            }
        }
        let img = Arc::new(img);
        self.images.insert(key, Arc::clone(&img));
        Ok(img)
    }

    /// The loaded scene, with the film and defaults the file asked for.
    pub fn finish(self) -> LoadedScene {
        let mut builder = self.builder;
        builder.set_film(self.film);
        builder.set_defaults(self.defaults);
        LoadedScene { builder, warnings: self.diag.warnings, info: self.info }
    }
}
