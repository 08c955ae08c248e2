//! Loading the scene a command names (or the embedded default scene), reporting the loader's
//! warnings and timing the load and the acceleration-structure build.

use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;
use tempera::accel::AccelKind;
use tempera::scene::Scene;
use tempera_scene::{LoadInfo, LoadOptions, Warning};

pub struct Loaded {
    pub scene: Scene,
    pub warnings: Vec<Warning>,
    pub info: Option<LoadInfo>,
    pub load_seconds: f64,
    pub build_seconds: f64,
}

/// Loads the scene at `path` (none: the embedded default scene) and builds it with `accel`.
pub fn load(path: Option<&Path>, strict: bool, accel: AccelKind) -> Result<Loaded> {
    let start = Instant::now();
    let (mut builder, warnings, info) = match path {
        Some(path) => {
            let loaded = tempera_scene::load(path, &LoadOptions { strict })?;
            (loaded.builder, loaded.warnings, Some(loaded.info))
        }
        None => (tempera::scenes::default_scene(), Vec::new(), None),
    };
    let load_seconds = start.elapsed().as_secs_f64();
    let start = Instant::now();
    builder.set_accel(accel);
    let scene = builder.build().context("invalid scene")?;
    Ok(Loaded { scene, warnings, info, load_seconds, build_seconds: start.elapsed().as_secs_f64() })
}

/// Prints warnings to stderr, at most `limit` of them.
pub fn print_warnings(warnings: &[Warning], limit: usize) {
    for w in warnings.iter().take(limit) {
        eprintln!("warning: {w}");
    }
    if warnings.len() > limit {
        eprintln!("warning: … and {} more (see `tempera info`)", warnings.len() - limit);
    }
}
