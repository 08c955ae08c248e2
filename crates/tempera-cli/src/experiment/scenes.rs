//! The scenes of an experiment, each loaded once with every method built for it.

use super::config::{Config, Method, SceneEntry};
use anyhow::{Context, Result, bail};
use tempera::integrator::Integrator;

/// A method ready to render.
pub struct PreparedMethod {
    pub method: Method,
    pub integrator: Box<dyn Integrator>,
}

/// A scene loaded once for all its runs.
pub struct PreparedScene {
    pub entry: SceneEntry,
    pub scene: tempera::scene::Scene,
    pub methods: Vec<PreparedMethod>,
}

/// Loads every scene (skipping optional ones whose file is missing) and builds every method
/// for it, so that a mistake in any of them stops the experiment before the first render.
pub fn prepare_scenes(config: &Config) -> Result<Vec<PreparedScene>> {
    let mut scenes = Vec::new();
    for entry in &config.scenes {
        if let Some(file) = &entry.file
            && !file.exists()
        {
            if entry.optional {
                eprintln!("scene '{}': {} does not exist; skipped (optional)", entry.name, file.display());
                continue;
            }
            bail!("scene '{}': {} does not exist", entry.name, file.display());
        }
        let loaded = crate::scene::load(entry.file.as_deref(), false, tempera::accel::AccelKind::Bvh)
            .with_context(|| format!("scene '{}'", entry.name))?;
        if !loaded.warnings.is_empty() {
            eprintln!("scene '{}': {} loader warnings (see `tempera info`)", entry.name, loaded.warnings.len());
        }
        let mut scene = loaded.scene;
        if let Some(r) = &entry.resolution {
            let (w, h) = crate::flags::parse_resolution(r).map_err(anyhow::Error::msg)?;
            scene.set_resolution(w, h);
        }
        if let Some(d) = entry.maxdepth {
            scene.defaults.max_depth = d;
        }
        let mut methods = Vec::new();
        for method in &config.methods {
            let integrator = tempera::integrator::create(method.integrator, &method.settings, &scene.defaults)
                .map_err(|e| anyhow::anyhow!("method '{}': {e}", method.name))?;
            methods.push(PreparedMethod { method: method.clone(), integrator });
        }
        scenes.push(PreparedScene { entry: entry.clone(), scene, methods });
    }
    Ok(scenes)
}
