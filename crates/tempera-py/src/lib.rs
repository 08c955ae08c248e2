//! Tempera from Python: the module `tempera`. It calls the core, loader and image crates
//! directly (no subprocess): load a scene file or the default scene, render it with any
//! integrator and the same typed settings as the command line, compare images, run
//! experiment files. Images are numpy arrays (height × width × 3, float32, linear RGB).

mod convert;
mod images;
mod render;

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::Mutex;
use tempera_scene::{LoadInfo, LoadOptions, Warning};

create_exception!(
    tempera,
    SceneError,
    PyException,
    "A scene file that could not be loaded (the message names file and line)."
);

/// A scene ready to render (built: geometry, acceleration structure, lights).
#[pyclass(name = "Scene", module = "tempera", frozen)]
pub struct PyScene {
    /// Renders at another resolution change the film for their duration.
    scene: Mutex<tempera::scene::Scene>,
    warnings: Vec<Warning>,
    info: Option<LoadInfo>,
    path: Option<PathBuf>,
}

#[pymethods]
impl PyScene {
    /// What the scene holds: resolution, primitives, lights, materials, the loader's
    /// warnings (with file:line) and the file's defaults.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let scene = self.scene.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let d = PyDict::new(py);
        d.set_item("path", self.path.as_ref().map(|p| p.display().to_string()))?;
        d.set_item("resolution", (scene.film.width, scene.film.height))?;
        d.set_item("spp", scene.defaults.spp)?;
        d.set_item("maxdepth", scene.defaults.max_depth)?;
        d.set_item("mpp", scene.defaults.chain.mpp)?;
        d.set_item("integrator", scene.defaults.integrator.map(|k| k.to_string()))?;
        d.set_item("primitives", scene.geometry.prims.len())?;
        d.set_item("emitters", scene.lights.len())?;
        if let Some(info) = &self.info {
            d.set_item("files", info.files)?;
            d.set_item("shapes", info.shapes)?;
            d.set_item("triangles", info.triangles)?;
            d.set_item("instances", info.instances)?;
            d.set_item("textures", info.textures)?;
            d.set_item("materials", info.materials.clone())?;
            d.set_item("lights", info.lights.clone())?;
            d.set_item("file_integrator", info.integrator.clone())?;
        }
        let warnings: Vec<String> = self.warnings.iter().map(ToString::to_string).collect();
        d.set_item("warnings", PyList::new(py, warnings)?)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let scene = self.scene.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
        let name = self.path.as_ref().map_or_else(|| "default scene".to_owned(), |p| p.display().to_string());
        format!("<tempera.Scene {name} {}x{}>", scene.film.width, scene.film.height)
    }
}

/// Loads a pbrt-v4 (`.pbrt`) or Mitsuba 0.5/0.6 (`.xml`) scene file. `strict`: warnings
/// (unknown directives, unused parameters) are errors. Raises `SceneError`.
#[pyfunction]
#[pyo3(signature = (path, strict = false))]
fn load(py: Python<'_>, path: PathBuf, strict: bool) -> PyResult<PyScene> {
    let loaded = py
        .detach(|| {
            let loaded = tempera_scene::load(&path, &LoadOptions { strict }).map_err(|e| e.to_string())?;
            let scene = loaded.builder.build().map_err(|e| format!("{}: invalid scene: {e}", path.display()))?;
            Ok::<_, String>((scene, loaded.warnings, loaded.info))
        })
        .map_err(SceneError::new_err)?;
    let (scene, warnings, info) = loaded;
    Ok(PyScene { scene: Mutex::new(scene), warnings, info: Some(info), path: Some(path) })
}

/// The embedded default scene (what `tempera render` renders without a file).
#[pyfunction]
fn default_scene(py: Python<'_>) -> PyResult<PyScene> {
    let scene =
        py.detach(|| tempera::scenes::default_scene().build()).map_err(|e| SceneError::new_err(e.to_string()))?;
    Ok(PyScene { scene: Mutex::new(scene), warnings: Vec::new(), info: None, path: None })
}

#[pymodule(name = "tempera")]
fn tempera_module(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyScene>()?;
    m.add_class::<render::RenderResult>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(default_scene, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(render::experiment, m)?)?;
    m.add_function(wrap_pyfunction!(images::compare, m)?)?;
    m.add_function(wrap_pyfunction!(images::error_map, m)?)?;
    m.add_function(wrap_pyfunction!(images::save, m)?)?;
    m.add_function(wrap_pyfunction!(images::read, m)?)?;
    Ok(())
}
