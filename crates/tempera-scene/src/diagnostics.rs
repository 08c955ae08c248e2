//! Source locations and diagnostics shared by the scene loaders: every message names the file,
//! the line and (for syntax errors) the column.

use std::fmt;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A position in a scene file (1-based line and column).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Loc {
    pub file: Arc<PathBuf>,
    pub line: u32,
    pub col: u32,
}

impl Loc {
    pub fn new(file: &Arc<PathBuf>, line: u32, col: u32) -> Self {
        Self { file: Arc::clone(file), line, col }
    }

    pub fn path(&self) -> &Path {
        &self.file
    }
}

impl fmt::Display for Loc {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}:{}", self.file.display(), self.line, self.col)
    }
}

/// A warning about something the loader ignored or approximated.
#[derive(Clone, Debug, PartialEq)]
pub struct Warning {
    pub loc: Option<Loc>,
    pub message: String,
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match &self.loc {
            Some(loc) => write!(f, "{loc}: {}", self.message),
            None => f.write_str(&self.message),
        }
    }
}
