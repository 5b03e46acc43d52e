//! `mislab._native`: the Python package's native module, a thin layer over `mislab::api`. The pure-Python
//! `mislab` package around it adds numpy arrays, pandas tables, docstrings and type hints.
//!
//! One lab (device and compiled pipelines) per process, opened at the first render. The GIL is released while
//! the device works; between submissions the render takes the GIL back for a moment to run Python's signal
//! handlers, so a notebook's interrupt stops it and returns the partial image.

use mislab::api::{self, ApiError, Budget, Image, Job, Lab, Observer, SceneHandle};
use pyo3::create_exception;
use pyo3::exceptions::{PyFileNotFoundError, PyRuntimeError, PyStopIteration, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyByteArray, PyBytes};
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

create_exception!(mislab, SceneError, PyValueError, "A scene file that cannot be loaded (names file and line).");

/// Seconds a submission takes from Python: the interrupt is looked at between submissions.
const SUBMIT_SECONDS: f64 = 0.25;

fn py_err(e: ApiError) -> PyErr {
    let message = e.to_string();
    match e {
        ApiError::Settings(_) => PyValueError::new_err(message),
        ApiError::NotFound(_) => PyFileNotFoundError::new_err(message),
        ApiError::Scene(_) | ApiError::Upload(_) => SceneError::new_err(message),
        _ => PyRuntimeError::new_err(message),
    }
}

/// The process's lab, opened at first use.
fn lab() -> PyResult<Arc<Lab>> {
    static LAB: Mutex<Option<Arc<Lab>>> = Mutex::new(None);
    let mut slot = LAB.lock().unwrap_or_else(|p| p.into_inner());
    if let Some(lab) = slot.as_ref() {
        return Ok(lab.clone());
    }
    let lab = Arc::new(Lab::open().map_err(py_err)?);
    *slot = Some(lab.clone());
    Ok(lab)
}

/// Watches a render from Python: runs the signal handlers between submissions (a KeyboardInterrupt stops the
/// render, which returns what it has) and writes notes to Python's stderr (a notebook shows them).
struct PyObserver {
    interrupted: bool,
}

impl Observer for PyObserver {
    fn note(&mut self, line: &str) {
        Python::attach(|py| {
            if let Ok(sys) = py.import("sys") {
                let _ = sys.getattr("stderr").and_then(|e| e.call_method1("write", (format!("{line}\n"),)));
            }
        });
    }
    fn stop_requested(&mut self) -> bool {
        if !self.interrupted {
            self.interrupted = Python::attach(|py| py.check_signals().is_err());
        }
        self.interrupted
    }
}

/// A loaded scene.
#[pyclass(name = "Scene", module = "mislab._native", frozen)]
struct PyScene {
    inner: Arc<SceneHandle>,
}

#[pymethods]
impl PyScene {
    /// The scene as it was named (a built-in name or a path).
    #[getter]
    fn name(&self) -> String {
        self.inner.spec().scene.clone()
    }
    /// One line of statistics: primitives, materials, lights, BVH.
    fn summary(&self) -> String {
        self.inner.summary()
    }
    /// The image size the scene file asks for, if any.
    #[getter]
    fn film_size(&self) -> Option<(u32, u32)> {
        self.inner.film_size().map(|[w, h]| (w, h))
    }
    fn __repr__(&self) -> String {
        format!("<mislab.Scene {}>", self.inner.summary())
    }
}

/// A rendered image (the native half of `mislab.Image`).
#[pyclass(name = "NativeImage", module = "mislab._native", frozen)]
struct PyImage {
    inner: Image,
}

#[pymethods]
impl PyImage {
    #[getter]
    fn width(&self) -> u32 {
        self.inner.width()
    }
    #[getter]
    fn height(&self) -> u32 {
        self.inner.height()
    }
    #[getter]
    fn spp(&self) -> u32 {
        self.inner.spp()
    }
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.stats.seconds
    }
    #[getter]
    fn rays(&self) -> u64 {
        self.inner.stats.rays
    }
    #[getter]
    fn nonfinite(&self) -> u64 {
        self.inner.stats.nonfinite
    }
    #[getter]
    fn interrupted(&self) -> bool {
        self.inner.stats.interrupted
    }
    #[getter]
    fn extra_rows(&self) -> u32 {
        self.inner.stats.extra_rows
    }
    #[getter]
    fn sample_range(&self) -> (u32, u32) {
        self.inner.sample_range
    }
    #[getter]
    fn scene(&self) -> String {
        self.inner.scene.scene.clone()
    }
    /// The settings as JSON (the names and values of the CLI's flags, `-` as `_`).
    fn settings_json(&self) -> String {
        serde_json::to_string(&self.inner.settings).unwrap_or_default()
    }
    /// Mean radiance, float32 RGB, row-major from the top (one copy, into a buffer numpy wraps without another).
    fn mean_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyByteArray>> {
        floats(py, &self.inner.film.mean)
    }
    /// Per-pixel sample variance, float32 RGB.
    fn variance_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyByteArray>> {
        let v: Vec<[f32; 3]> = self.inner.variance().collect();
        floats(py, &v)
    }
    /// Finite samples per pixel, uint32.
    fn count_bytes<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyByteArray>> {
        let c = &self.inner.film.count;
        PyByteArray::new_with(py, c.len() * 4, |buf| {
            for (d, v) in buf.chunks_exact_mut(4).zip(c) {
                d.copy_from_slice(&v.to_ne_bytes());
            }
            Ok(())
        })
    }
    /// 8-bit sRGB after exposure (stops) and the tonemapper ("clamp" or "aces").
    fn tonemapped_bytes<'py>(&self, py: Python<'py>, exposure: f32, tonemap: &str) -> PyResult<Bound<'py, PyBytes>> {
        let op = tonemap_of(tonemap)?;
        Ok(PyBytes::new(py, self.inner.film.to_rgb8(exposure, op).as_raw()))
    }
    /// Writes PNG (tonemapped) or EXR (linear) by the extension, with the CLI's header metadata.
    fn save(&self, py: Python<'_>, path: PathBuf, tonemap: &str, force: bool) -> PyResult<()> {
        let op = tonemap_of(tonemap)?;
        py.detach(|| self.inner.save(&path, op, force)).map_err(py_err)
    }
}

fn floats<'py>(py: Python<'py>, v: &[[f32; 3]]) -> PyResult<Bound<'py, PyByteArray>> {
    PyByteArray::new_with(py, v.len() * 12, |buf| {
        for (d, px) in buf.chunks_exact_mut(12).zip(v) {
            for (c, x) in d.chunks_exact_mut(4).zip(px) {
                c.copy_from_slice(&x.to_ne_bytes());
            }
        }
        Ok(())
    })
}

fn tonemap_of(name: &str) -> PyResult<api::Tonemap> {
    <api::Tonemap as clap::ValueEnum>::from_str(name, true)
        .map_err(|_| PyValueError::new_err(format!("tonemap '{name}': expected 'clamp' or 'aces'")))
}

/// Loads a scene: a built-in name or a .gltf/.glb/.toml/.pbrt/.xml path, with the scene flags as pairs.
#[pyfunction]
fn load(py: Python<'_>, name: String, flags: Vec<(String, String)>) -> PyResult<PyScene> {
    let spec = api::scene_spec(&name, &flags).map_err(py_err)?;
    let handle = py.detach(|| SceneHandle::load(&spec)).map_err(py_err)?;
    Ok(PyScene { inner: Arc::new(handle) })
}

/// Renders with the CLI's flags as pairs; `reference` switches to the reference estimator (MIS, power, Sobol)
/// and checks that every pixel got every sample.
#[pyfunction]
#[pyo3(signature = (scene, flags, reference = false))]
fn render(py: Python<'_>, scene: &PyScene, flags: Vec<(String, String)>, reference: bool) -> PyResult<PyImage> {
    let mut job = job_of(&flags, reference)?;
    let lab = lab()?;
    let mut observer = PyObserver { interrupted: false };
    let image = py.detach(|| api::render(&lab, &scene.inner, &mut job, &mut observer)).map_err(py_err)?;
    Ok(PyImage { inner: image })
}

fn job_of(flags: &[(String, String)], reference: bool) -> PyResult<Job> {
    let mut job = Job::from_pairs(flags).map_err(py_err)?;
    job.submit_seconds = SUBMIT_SECONDS;
    if reference {
        job.settings =
            api::Settings { seed: job.settings.seed, ..mislab::lab::reference::reference_settings(&job.settings) };
        job.verify_complete = true;
    }
    Ok(job)
}

/// A render that yields its image as it converges (`mislab.render_progressive`).
#[pyclass(name = "Progressive", module = "mislab._native")]
struct PyProgressive {
    lab: Arc<Lab>,
    render: Option<api::Render>,
    total: u32,
    done: u32,
    submit_seconds: f64,
}

#[pymethods]
impl PyProgressive {
    #[new]
    fn new(py: Python<'_>, scene: &PyScene, flags: Vec<(String, String)>) -> PyResult<PyProgressive> {
        let mut job = job_of(&flags, false)?;
        let mut observer = PyObserver { interrupted: false };
        for note in job.resolve(&scene.inner) {
            observer.note(&format!("note: {note}"));
        }
        let total = match job.budget {
            Budget::Samples(n) => n,
            Budget::Time(_) => return Err(PyValueError::new_err("render_progressive takes spp=, not time=")),
        };
        if job.state_path().is_some() {
            return Err(PyValueError::new_err("render_progressive does not write state files: use render()"));
        }
        let lab = lab()?;
        let render = py.detach(|| api::Render::begin(&lab, &scene.inner, &mut job, &mut observer)).map_err(py_err)?;
        Ok(PyProgressive { lab, render: Some(render), total, done: 0, submit_seconds: job.submit_seconds })
    }

    fn __iter__(slf: PyRef<'_, Self>) -> PyRef<'_, Self> {
        slf
    }

    /// Renders on (doubling the sample count: 1, 2, 4, … up to spp) and returns the image so far.
    fn __next__(&mut self, py: Python<'_>) -> PyResult<PyImage> {
        let Some(render) = self.render.as_mut() else {
            return Err(PyStopIteration::new_err(()));
        };
        let target = (self.done * 2).clamp(1, self.total);
        let (budget, submit_seconds) = (Budget::Samples(target - self.done), self.submit_seconds);
        let lab = &self.lab;
        let mut observer = PyObserver { interrupted: false };
        let (stats, image) = py
            .detach(|| {
                let plan = api::Plan { budget, submit_seconds, checkpoint: None };
                let stats = render.advance(lab, plan, &mut observer)?;
                Ok::<_, ApiError>((stats.clone(), render.image(lab)?))
            })
            .map_err(py_err)?;
        self.done = stats.spp;
        if stats.interrupted || self.done >= self.total {
            self.render = None;
        }
        Ok(PyImage { inner: image })
    }
}

/// An image file (EXR, or a render state) as float32 RGB bytes, width, height.
#[pyfunction]
fn read_image<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyByteArray>, u32, u32)> {
    if path.symlink_metadata().is_err() {
        return Err(PyFileNotFoundError::new_err(format!("{}: no such file", path.display())));
    }
    let img = mislab::lab::compare::read(&path).map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((floats(py, &img.pixels)?, img.width, img.height))
}

fn pixels_of(bytes: &[u8], width: u32, height: u32) -> PyResult<mislab::lab::compare::Image> {
    if bytes.len() != width as usize * height as usize * 12 {
        return Err(PyValueError::new_err(format!(
            "{} bytes are not a {width}x{height} float32 RGB image",
            bytes.len()
        )));
    }
    let pixels = bytes
        .chunks_exact(12)
        .map(|p| std::array::from_fn(|c| f32::from_ne_bytes(p[4 * c..4 * c + 4].try_into().unwrap())))
        .collect();
    Ok(mislab::lab::compare::Image { width, height, pixels })
}

/// `mislab compare` on two float32 RGB images: JSON of the comparison (mean ratio, block relMSE, …).
#[pyfunction]
#[allow(clippy::too_many_arguments)]
fn compare(
    image: &[u8],
    width: u32,
    height: u32,
    reference: &[u8],
    ref_width: u32,
    ref_height: u32,
    block: u32,
) -> PyResult<String> {
    let a = pixels_of(image, width, height)?;
    let b = pixels_of(reference, ref_width, ref_height)?;
    let c = mislab::lab::compare::compare(&a, &b, block).map_err(|e| PyValueError::new_err(e.to_string()))?;
    serde_json::to_string(&c).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// `mislab bench` of one group (JSON of its fields: strategies, samplers, spp, seeds, mode, width, …) on `scene`
/// against a float32 RGB reference: JSON rows with results.csv's columns.
#[pyfunction]
fn bench_group(
    py: Python<'_>,
    scene: &PyScene,
    group_json: &str,
    reference: &[u8],
    ref_width: u32,
    ref_height: u32,
) -> PyResult<String> {
    use mislab::lab::bench::BenchGroup;
    let mut g: BenchGroup =
        serde_json::from_str(group_json).map_err(|e| PyValueError::new_err(format!("bench: {e}")))?;
    let spec = scene.inner.spec();
    g.scene = spec.scene.clone();
    g.gltf_scene = spec.gltf_scene;
    g.env = spec.env.clone();
    g.env_scale = spec.env_scale;
    g.env_rotation = spec.env_rotation;
    if g.name.is_empty() {
        g.name = "python".into();
    }
    if (ref_width, ref_height) != (g.width, g.height) {
        return Err(PyValueError::new_err(format!(
            "the reference is {ref_width}x{ref_height}, the benchmark renders {}x{}",
            g.width, g.height
        )));
    }
    let reference = pixels_of(reference, ref_width, ref_height)?.pixels;
    let lab = lab()?;
    let scene = scene.inner.scene();
    let rows = py
        .detach(|| mislab::lab::bench::run_configurations(lab.gpu(), &g, scene, &reference))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    serde_json::to_string(&rows.0).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The columns of `mislab bench`'s results.csv, in order.
#[pyfunction]
fn bench_columns() -> Vec<&'static str> {
    mislab::lab::bench::CSV_COLUMNS.to_vec()
}

/// Merges part state files into one image, as `mislab merge` does; writes the merged state to `state` if given.
#[pyfunction]
#[pyo3(signature = (paths, state = None))]
fn merge(py: Python<'_>, paths: Vec<PathBuf>, state: Option<PathBuf>) -> PyResult<PyImage> {
    let image = py.detach(|| api::merge(&paths, state.as_deref())).map_err(py_err)?;
    Ok(PyImage { inner: image })
}

/// Every render flag: (name, help, default, choices).
#[pyfunction]
fn settings() -> Vec<(String, String, Option<String>, Vec<String>)> {
    api::RenderFlags::describe().into_iter().map(|f| (f.name, f.help, f.default, f.choices)).collect()
}

/// The device the renders run on.
#[pyfunction]
fn adapter() -> PyResult<String> {
    Ok(lab()?.adapter())
}

/// Render pipelines this process has compiled so far (every render reuses them: one with the same scene features
/// and settings compiles nothing).
#[pyfunction]
fn pipelines_compiled() -> PyResult<usize> {
    Ok(lab()?.pipelines_compiled())
}

/// The module: the functions above, the scene and image classes, `SceneError`, and `REFERENCE_SEED` (the seed
/// of references, distinct from the seeds 0, 1, … that benchmarks measure).
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add("REFERENCE_SEED", mislab::lab::reference::REFERENCE_SEED)?;
    m.add("VERSION", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyScene>()?;
    m.add_class::<PyImage>()?;
    m.add_class::<PyProgressive>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(read_image, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(bench_group, m)?)?;
    m.add_function(wrap_pyfunction!(bench_columns, m)?)?;
    m.add_function(wrap_pyfunction!(merge, m)?)?;
    m.add_function(wrap_pyfunction!(settings, m)?)?;
    m.add_function(wrap_pyfunction!(adapter, m)?)?;
    m.add_function(wrap_pyfunction!(pipelines_compiled, m)?)?;
    Ok(())
}
