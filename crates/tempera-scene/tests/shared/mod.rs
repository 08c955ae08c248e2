//! Where the real scenes are, for the tests that use them.

use std::path::PathBuf;

/// `../shared/scenes` beside the project, or `None` (with a message saying why the test is
/// skipped) where it does not exist.
pub fn shared_scenes() -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes");
    if dir.is_dir() {
        Some(dir)
    } else {
        eprintln!("skipping: {} not found (the real scenes live beside the project)", dir.display());
        None
    }
}
