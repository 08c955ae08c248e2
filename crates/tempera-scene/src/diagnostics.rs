//! Source locations and diagnostics shared by the scene loaders: every message names the file,
//! the line and (for syntax errors) the column.

use crate::LoadError;
use std::collections::HashSet;
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

/// The warnings a loader collects, or, in strict mode, the error the first one becomes.
#[derive(Debug, Default)]
pub(crate) struct Diagnostics {
    pub strict: bool,
    pub warnings: Vec<Warning>,
    warned_once: HashSet<String>,
}

impl Diagnostics {
    pub fn new(strict: bool) -> Self {
        Self { strict, ..Self::default() }
    }

    /// Records a warning, or fails in strict mode.
    pub fn warn(&mut self, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        let message = message.into();
        if self.strict {
            return Err(match loc {
                Some(loc) => LoadError::Syntax { loc: loc.clone(), message },
                None => LoadError::Unsupported { message },
            });
        }
        self.warnings.push(Warning { loc: loc.cloned(), message });
        Ok(())
    }

    /// Warns once per `key` (e.g. once per approximated material type).
    pub fn warn_once(&mut self, key: &str, loc: Option<&Loc>, message: impl Into<String>) -> Result<(), LoadError> {
        if self.warned_once.insert(key.to_owned()) { self.warn(loc, message) } else { Ok(()) }
    }
}
