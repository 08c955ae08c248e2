//! `tempera.render` and `tempera.experiment`: the work runs on its own threads with the GIL
//! released while the calling thread shows progress (a tqdm bar when tqdm is installed) and
//! watches for Ctrl-C, which stops the work cleanly: a render returns the image so far, an
//! experiment keeps its finished runs.

use crate::PyScene;
use crate::convert;
use crate::images;
use numpy::PyArray3;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::thread::ScopedJoinHandle;
use std::time::{Duration, Instant};
use tempera::integrator::{self, Budget, IntegratorKind, IntegratorSettings, RenderControl, RenderSettings, RunStats};
use tempera::texture::Image;

/// A finished (or interrupted) render.
#[pyclass(module = "tempera", frozen)]
pub struct RenderResult {
    pub image: Image,
    array: Py<PyArray3<f32>>,
    stats: serde_json::Value,
    interrupted: bool,
}

#[pymethods]
impl RenderResult {
    /// The image: float32 numpy array, height × width × 3, linear RGB.
    #[getter]
    fn image(&self, py: Python<'_>) -> Py<PyArray3<f32>> {
        self.array.clone_ref(py)
    }

    /// The render statistics, as `tempera render --stats` writes them (a dict).
    #[getter]
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        convert::to_python(py, &self.stats)
    }

    /// True when Ctrl-C stopped the render before its budget was spent.
    #[getter]
    fn interrupted(&self) -> bool {
        self.interrupted
    }

    /// Writes the image (.exr, .pfm or .png; `exposure` in stops for PNG).
    #[pyo3(signature = (path, exposure = 0.0))]
    fn save(&self, py: Python<'_>, path: PathBuf, exposure: f32) -> PyResult<()> {
        py.detach(|| tempera_image::write_image(&path, &self.image, &tempera_image::WriteOptions { exposure }))
            .map_err(|e| pyo3::exceptions::PyOSError::new_err(e.to_string()))
    }

    fn __repr__(&self) -> String {
        let name = self.stats.get("integrator").and_then(|v| v.as_str()).unwrap_or("?");
        let seconds = self.stats.get("seconds").and_then(serde_json::Value::as_f64).unwrap_or(0.0);
        let note = if self.interrupted { ", interrupted" } else { "" };
        format!("<tempera.RenderResult {name} {}x{} in {seconds:.2} s{note}>", self.image.width, self.image.height)
    }
}

/// A tqdm bar when tqdm is installed and `show` is set.
fn progress_bar<'py>(py: Python<'py>, show: bool, total: u64, unit: &str) -> Option<Bound<'py, PyAny>> {
    if !show {
        return None;
    }
    let tqdm = py.import("tqdm.auto").ok()?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("total", total).ok()?;
    kwargs.set_item("unit", unit).ok()?;
    kwargs.set_item("leave", false).ok()?;
    tqdm.getattr("tqdm").ok()?.call((), Some(&kwargs)).ok()
}

/// Runs `work` on a scoped thread with the GIL released; meanwhile polls every 50 ms: Ctrl-C
/// sets `cancel`, `progress()` (units done) advances the bar. Returns the work's value and
/// whether Ctrl-C was pressed.
fn run_watched<T: Send>(
    py: Python<'_>,
    bar: Option<&Bound<'_, PyAny>>,
    cancel: &AtomicBool,
    progress: &(dyn Fn() -> u64 + Sync),
    work: impl FnOnce() -> T + Send,
) -> PyResult<(T, bool)> {
    let bar = bar.map(|b| b.clone().unbind());
    let mut interrupted = false;
    let mut shown = 0u64;
    let value = py.detach(|| {
        std::thread::scope(|scope| {
            let handle: ScopedJoinHandle<T> = scope.spawn(work);
            while !handle.is_finished() {
                std::thread::sleep(Duration::from_millis(50));
                Python::attach(|py| {
                    if py.check_signals().is_err() {
                        interrupted = true;
                        cancel.store(true, Ordering::SeqCst);
                    }
                    if let Some(bar) = &bar {
                        let done = progress();
                        if done > shown {
                            let _ = bar.call_method1(py, "update", (done - shown,));
                            shown = done;
                        }
                    }
                });
            }
            handle.join()
        })
    });
    if let Some(bar) = &bar {
        let done = progress();
        if done > shown {
            let _ = bar.call_method1(py, "update", (done - shown,));
        }
        let _ = bar.call_method0(py, "close");
    }
    let value = value.map_err(|_| PyRuntimeError::new_err("the render panicked (a bug; please report it)"))?;
    Ok((value, interrupted))
}

fn value_error(e: impl ToString) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The integrator named `name` (the experiment file's and the CLI's names).
fn integrator_kind(name: &str) -> PyResult<IntegratorKind> {
    IntegratorKind::from_name(name).ok_or_else(|| {
        let names: Vec<&str> = IntegratorKind::ALL.iter().map(|k| k.name()).collect();
        value_error(format!("unknown integrator {name:?} (expected one of {})", names.join(", ")))
    })
}

/// The typed integrator settings from keyword arguments, checked like an experiment file's.
fn settings(maxdepth: Option<u32>, extra: Option<&Bound<'_, PyDict>>) -> PyResult<IntegratorSettings> {
    let mut object = serde_json::Map::new();
    if let Some(d) = maxdepth {
        object.insert("maxdepth".into(), d.into());
    }
    for (key, value) in extra.into_iter().flat_map(|d| d.iter()) {
        let key: String = key.extract()?;
        let value = convert::from_python(&value, &key)?;
        object.insert(key.replace('-', "_"), value);
    }
    serde_json::from_value(serde_json::Value::Object(object.clone())).map_err(|e| {
        // Name the argument when one alone does not parse (serde names only unknown ones).
        let culprit = object.iter().find(|(k, v)| {
            let one = serde_json::Map::from_iter([((*k).clone(), (*v).clone())]);
            serde_json::from_value::<IntegratorSettings>(serde_json::Value::Object(one)).is_err()
        });
        match culprit {
            Some((k, _)) => value_error(format!("integrator setting {k}: {e}")),
            None => value_error(format!("integrator settings: {e}")),
        }
    })
}

/// Renders `scene`. `integrator`: "path", "bdpt", "pssmlt", "mmlt" or "tempered" (default:
/// the scene file's, else path). Budget: `spp` samples per pixel, `mpp` mutations per pixel
/// (Markov chains), or `time` seconds (default: the scene's spp, or for a Markov-chain
/// integrator the mutations per pixel the scene gives). Further keyword arguments are the
/// integrator's settings, named as in experiment files (`bootstrap`, `chains`,
/// `replicas`, `swap`, `ladder`, …). Same seed and sample budget: the pixels the command line
/// writes. Ctrl-C stops the render and returns the image so far (`interrupted` is set).
#[pyfunction]
#[pyo3(signature = (
    scene, integrator = None, *, spp = None, mpp = None, time = None, seed = 0, threads = 0,
    resolution = None, maxdepth = None, max_memory = None, progress = true, **settings_kwargs
))]
#[allow(clippy::too_many_arguments)]
pub fn render(
    py: Python<'_>,
    scene: &PyScene,
    integrator: Option<&str>,
    spp: Option<u32>,
    mpp: Option<u32>,
    time: Option<f64>,
    seed: u64,
    threads: usize,
    resolution: Option<(u32, u32)>,
    maxdepth: Option<u32>,
    max_memory: Option<f64>,
    progress: bool,
    settings_kwargs: Option<&Bound<'_, PyDict>>,
) -> PyResult<RenderResult> {
    let given = [spp.is_some(), mpp.is_some(), time.is_some()].iter().filter(|&&g| g).count();
    if given > 1 {
        return Err(value_error("give at most one of spp, mpp and time"));
    }
    if spp == Some(0) || mpp == Some(0) {
        return Err(value_error("spp and mpp must be at least 1"));
    }
    if let Some(t) = time.filter(|t| !t.is_finite() || *t <= 0.0) {
        return Err(value_error(format!("time must be a positive number of seconds, got {t}")));
    }
    if let Some((w, h)) = resolution.filter(|&(w, h)| w == 0 || h == 0 || w > 65_536 || h > 65_536) {
        return Err(value_error(format!("resolution must be between (1, 1) and (65536, 65536), got ({w}, {h})")));
    }
    let max_memory = match max_memory {
        Some(g) if !(g.is_finite() && g > 0.0) => {
            return Err(value_error("max_memory must be a positive number of GiB"));
        }
        Some(g) => Some((g * (1u64 << 30) as f64) as u64),
        None => None,
    };
    let settings = settings(maxdepth, settings_kwargs)?;
    let mut guard = scene.scene.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    let original = (guard.film.width, guard.film.height);
    let kind = match integrator {
        Some(name) => integrator_kind(name)?,
        None => guard.defaults.integrator.unwrap_or(IntegratorKind::Path),
    };
    let integrator =
        integrator::create(kind, &settings, &guard.defaults).map_err(|e| value_error(format!("{kind}: {e}")))?;
    if let Some((w, h)) = resolution {
        guard.set_resolution(w, h);
    }
    let film = (guard.film.width, guard.film.height);
    let budget = match time {
        Some(t) => Budget::Time(Duration::from_secs_f64(t)),
        None => Budget::Samples(mpp.or(spp).unwrap_or(guard.defaults.per_pixel(kind))),
    };
    let pixels = u64::from(film.0) * u64::from(film.1);
    let (total, unit) = match budget {
        Budget::Samples(n) => (pixels * u64::from(n), if kind.is_chain() { "mutation" } else { "sample" }),
        Budget::Time(d) => (d.as_millis() as u64, "ms"),
    };
    let bar = progress_bar(py, progress, total, unit);
    let cancel = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let start = Instant::now();
    let on_progress = |n: u64| {
        done.fetch_add(n, Ordering::Relaxed);
    };
    let shown = || match budget {
        Budget::Samples(_) => done.load(Ordering::Relaxed),
        Budget::Time(d) => (start.elapsed().as_millis() as u64).min(d.as_millis() as u64),
    };
    let render_settings = RenderSettings { budget, seed, threads };
    let scene_ref = &*guard;
    let integrator_ref = integrator.as_ref();
    let watched = run_watched(py, bar.as_ref(), &cancel, &shown, || {
        let control = RenderControl::new(&cancel, &on_progress).with_max_memory(max_memory);
        integrator_ref.render(scene_ref, &render_settings, &control)
    });
    // The scene gets its resolution back whatever became of the render.
    if resolution.is_some() {
        guard.set_resolution(original.0, original.1);
    }
    drop(guard);
    let (out, interrupted) = watched?;
    let out = out.map_err(value_error)?;
    let stats = serde_json::to_value(RunStats::new(integrator.name(), &out)).map_err(value_error)?;
    let array = images::to_numpy(py, &out.image)?.unbind();
    Ok(RenderResult { image: out.image, array, stats, interrupted })
}

/// Runs an experiment file (the same TOML as `tempera experiment`), writing the same output
/// folder and report; returns the results table: a pandas DataFrame when pandas is installed,
/// else a list of dicts (one per run and recorded time). Ctrl-C stops it; finished runs are
/// kept and a later call resumes.
#[pyfunction]
#[pyo3(signature = (config, quiet = true))]
pub fn experiment<'py>(py: Python<'py>, config: PathBuf, quiet: bool) -> PyResult<Bound<'py, PyAny>> {
    let loaded = tempera_cli::experiment::Config::load(&config).map_err(|e| value_error(format!("{e:#}")))?;
    tempera_cli::run::CANCEL.store(false, Ordering::SeqCst);
    let args = tempera_cli::experiment::ExperimentArgs {
        config: config.clone(),
        report_only: false,
        quiet,
        handle_interrupts: false,
    };
    let (result, _) = run_watched(py, None, &tempera_cli::run::CANCEL, &|| 0, || tempera_cli::experiment::run(args))?;
    result.map_err(|e| PyRuntimeError::new_err(format!("{e:#}")))?;
    let path = loaded.output.join("results.json");
    let text = std::fs::read_to_string(&path)
        .map_err(|e| pyo3::exceptions::PyOSError::new_err(format!("{}: {e}", path.display())))?;
    let rows: serde_json::Value = serde_json::from_str(&text).map_err(value_error)?;
    let rows = convert::to_python(py, &rows)?;
    match py.import("pandas") {
        Ok(pandas) => pandas.call_method1("DataFrame", (rows,)),
        Err(_) => Ok(rows.cast_into::<PyList>()?.into_any()),
    }
}
