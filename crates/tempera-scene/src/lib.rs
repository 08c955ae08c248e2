//! Scene loading for Tempera. Loaders translate scene files into the core's
//! [`tempera::scene::SceneBuilder`]; the core itself knows no file format. The format is chosen
//! by extension: `.pbrt` (pbrt-v4) and `.xml` (Mitsuba 0.5/0.6).

use std::path::{Path, PathBuf};
use tempera::scene::SceneBuilder;

/// A scene file that could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: unknown scene format (expected a .pbrt or .xml file)")]
    UnknownFormat { path: PathBuf },
    #[error("{path}: {format} scene files are not supported by this version of Tempera")]
    Unsupported { path: PathBuf, format: &'static str },
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

/// Loads the scene at `path` into a builder.
pub fn load(path: &Path) -> Result<SceneBuilder, LoadError> {
    std::fs::metadata(path).map_err(|source| LoadError::Io {
        path: path.to_owned(),
        source,
    })?;
    let format = SceneFormat::from_path(path).ok_or_else(|| LoadError::UnknownFormat {
        path: path.to_owned(),
    })?;
    let name = match format {
        SceneFormat::Pbrt => "pbrt-v4",
        SceneFormat::Mitsuba => "Mitsuba XML",
    };
    Err(LoadError::Unsupported {
        path: path.to_owned(),
        format: name,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn missing_and_unknown_files_are_clear_errors() {
        let err = load(Path::new("/no/such/scene.pbrt")).unwrap_err();
        assert!(matches!(err, LoadError::Io { .. }));
        assert!(err.to_string().starts_with("/no/such/scene.pbrt: "));
        let err = load(Path::new("Cargo.toml")).unwrap_err();
        assert!(matches!(err, LoadError::UnknownFormat { .. }), "{err}");
    }
}
