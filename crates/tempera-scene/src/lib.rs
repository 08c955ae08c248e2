//! Scene loading for Tempera. Loaders translate scene files into the core's
//! [`tempera::scene::SceneBuilder`]; the core itself knows no file format. The format is chosen
//! by extension: `.pbrt` (pbrt-v4) and `.xml` (Mitsuba 0.5/0.6 XML).

mod common;
mod context;
pub mod diagnostics;
mod mitsuba;
pub mod obj;
mod pbrt;
pub mod ply;
pub mod serialized;
mod spectrum;

pub use diagnostics::{Loc, Warning};

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use tempera::scene::SceneBuilder;

/// A scene file that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: unknown scene format (expected a .pbrt or .xml file)")]
    UnknownFormat { path: PathBuf },
    #[error("{loc}: {message}")]
    Syntax { loc: Loc, message: String },
    #[error("{message}")]
    Unsupported { message: String },
}

#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// Treat warnings (unknown directives, unused parameters, approximations) as errors.
    pub strict: bool,
}

/// What a loader found, for `tempera info` and the render summary.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadInfo {
    pub files: usize,
    pub shapes: usize,
    pub triangles: usize,
    pub instances: usize,
    pub textures: usize,
    pub materials: BTreeMap<String, usize>,
    pub lights: BTreeMap<String, usize>,
    /// The integrator named by the file, as written there.
    pub integrator: Option<String>,
    /// Parameters read and deliberately ignored: `file:line:col: "name": why`.
    pub ignored: Vec<String>,
}

/// A loaded scene, ready to build, with the loader's warnings.
#[derive(Debug)]
pub struct LoadedScene {
    pub builder: SceneBuilder,
    pub warnings: Vec<Warning>,
    pub info: LoadInfo,
}

/// Scene file formats recognised by extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneFormat {
    Pbrt,
    Mitsuba,
}

impl SceneFormat {
    pub fn from_path(path: &Path) -> Option<Self> {
        match path.extension()?.to_str()?.to_ascii_lowercase().as_str() {
            "pbrt" => Some(SceneFormat::Pbrt),
            "xml" => Some(SceneFormat::Mitsuba),
            _ => None,
        }
    }
}

/// Loads pbrt-v4 scene text as if read from `path`.
pub fn load_pbrt_str(text: &str, path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    pbrt::load_str(text, path, options)
}

/// Loads Mitsuba XML scene text as if read from `path`.
pub fn load_mitsuba_str(text: &str, path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    mitsuba::load_str(text, path, options)
}

/// Loads the scene at `path`.
pub fn load(path: &Path, options: &LoadOptions) -> Result<LoadedScene, LoadError> {
    std::fs::metadata(path).map_err(|source| LoadError::Io { path: path.to_owned(), source })?;
    match SceneFormat::from_path(path).ok_or_else(|| LoadError::UnknownFormat { path: path.to_owned() })? {
        SceneFormat::Pbrt => pbrt::load(path, options),
        SceneFormat::Mitsuba => mitsuba::load(path, options),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_and_unknown_files_are_clear_errors() {
        let err = load(Path::new("/no/such/scene.pbrt"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, LoadError::Io { .. }));
        assert!(err.to_string().starts_with("/no/such/scene.pbrt: "));
        let err = load(Path::new("Cargo.toml"), &LoadOptions::default()).unwrap_err();
        assert!(matches!(err, LoadError::UnknownFormat { .. }), "{err}");
    }
}
