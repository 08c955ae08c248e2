//! Images between Tempera and numpy, and the image functions: `compare`, `error_map`, `save`,
//! `read`. Any height × width × 3 array of numbers is accepted (converted to float32), as are
//! a `RenderResult` and an image file's path.

use crate::render::RenderResult;
use numpy::{PyArray3, PyArrayMethods, PyUntypedArrayMethods};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use std::path::PathBuf;
use tempera::math::Rgb;
use tempera::texture::Image;
use tempera_image::{ColorEncoding, WriteOptions, metrics};

/// An image as a float32 numpy array, height × width × 3.
pub fn to_numpy<'py>(py: Python<'py>, image: &Image) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let flat: Vec<f32> = image.pixels.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    numpy::PyArray1::from_vec(py, flat).reshape([image.height, image.width, 3])
}

/// An image from a numpy-like array (H × W × 3), a `RenderResult` or a file path.
pub fn from_python(value: &Bound<'_, PyAny>, what: &str) -> PyResult<Image> {
    if let Ok(result) = value.cast::<RenderResult>() {
        return Ok(result.get().image.clone());
    }
    if value.is_instance_of::<PyString>() || value.hasattr("__fspath__")? {
        let path: PathBuf = value.extract()?;
        return tempera_image::read_image(&path, ColorEncoding::Srgb).map_err(|e| PyOSError::new_err(e.to_string()));
    }
    let np = value.py().import("numpy")?;
    let array = np.call_method1("ascontiguousarray", (value, "float32"))?;
    let array = array
        .cast::<PyArray3<f32>>()
        .map_err(|_| PyValueError::new_err(format!("{what}: expected an array of shape (height, width, 3)")))?;
    let shape = array.shape().to_vec();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(PyValueError::new_err(format!("{what}: expected shape (height, width, 3), got {shape:?}")));
    }
    let data = array.readonly();
    let values = data.as_slice().map_err(|e| PyValueError::new_err(format!("{what}: {e}")))?;
    let pixels = values.chunks_exact(3).map(|c| Rgb::new(c[0], c[1], c[2])).collect();
    Ok(Image::new(shape[1], shape[0], pixels))
}

const METRICS: [&str; 6] = ["mse", "rmse", "relmse", "smape", "flip", "mean_ratio"];

/// Compares `image` with `reference` (arrays, results or paths of the same size). `metrics`:
/// any of "mse", "rmse", "relmse", "smape", "flip", "mean_ratio" (default: all). Returns a
/// dict of floats.
#[pyfunction]
#[pyo3(signature = (image, reference, metrics = None))]
pub fn compare<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    reference: &Bound<'py, PyAny>,
    metrics: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let wanted = metrics.unwrap_or_else(|| METRICS.iter().map(|s| (*s).to_owned()).collect());
    if let Some(bad) = wanted.iter().find(|m| !METRICS.contains(&m.as_str())) {
        return Err(PyValueError::new_err(format!("unknown metric {bad:?} (expected one of {METRICS:?})")));
    }
    let (image, reference) = (from_python(image, "image")?, from_python(reference, "reference")?);
    let c = py.detach(|| metrics::compare(&image, &reference)).map_err(PyValueError::new_err)?;
    let d = PyDict::new(py);
    for m in wanted {
        let v = match m.as_str() {
            "mse" => c.mse,
            "rmse" => c.rmse,
            "relmse" => c.relmse,
            "smape" => c.smape,
            "flip" => c.flip,
            _ => c.mean_ratio,
        };
        d.set_item(m, v)?;
    }
    Ok(d)
}

/// Per-pixel errors of `image` against `reference`, height × width float32: "relmse" (the
/// pixel's relMSE term, averaged over channels as `compare` does) or "flip" (the FLIP error,
/// 0 to 1). `colour=True` returns the false-colour picture `tempera experiment` writes
/// instead (height × width × 3 with a colour bar and labels beneath).
#[pyfunction]
#[pyo3(signature = (image, reference, metric = "relmse", colour = false))]
pub fn error_map<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    reference: &Bound<'py, PyAny>,
    metric: &str,
    colour: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let (image, reference) = (from_python(image, "image")?, from_python(reference, "reference")?);
    if !matches!(metric, "relmse" | "flip") {
        return Err(PyValueError::new_err(format!("unknown error map {metric:?} (expected relmse or flip)")));
    }
    tempera_image::check_sizes(&image, &reference).map_err(PyValueError::new_err)?;
    if colour {
        let map = match metric {
            "relmse" => py.detach(|| metrics::error_map(&image, &reference)),
            _ => py.detach(|| metrics::flip_error_map(&image, &reference)),
        }
        .map_err(PyValueError::new_err)?;
        return Ok(to_numpy(py, &map)?.into_any());
    }
    let values: Vec<f32> = match metric {
        "relmse" => image.pixels.iter().zip(&reference.pixels).map(|(&i, &r)| metrics::rel_se(i, r) as f32).collect(),
        _ => py.detach(|| tempera_image::flip::flip(&image, &reference)).map_err(PyValueError::new_err)?.1,
    };
    Ok(numpy::PyArray1::from_vec(py, values).reshape([image.height, image.width])?.into_any())
}

/// Writes `image` to `path`: .exr and .pfm linear float, .png sRGB 8-bit after `exposure`
/// stops. The file appears whole (written beside it, then renamed).
#[pyfunction]
#[pyo3(signature = (image, path, exposure = 0.0))]
pub fn save(py: Python<'_>, image: &Bound<'_, PyAny>, path: PathBuf, exposure: f32) -> PyResult<()> {
    let image = from_python(image, "image")?;
    py.detach(|| tempera_image::write_image(&path, &image, &WriteOptions { exposure }))
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

/// Reads an image file (.exr, .pfm, .png, .jpg, .tga) as linear RGB (8-bit files decoded from
/// sRGB).
#[pyfunction]
pub fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = py
        .detach(|| tempera_image::read_image(&path, ColorEncoding::Srgb))
        .map_err(|e| PyOSError::new_err(e.to_string()))?;
    to_numpy(py, &image)
}
