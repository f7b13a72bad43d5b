//! `flatray._flatray`: the library crates wired to a Python module, as
//! the CLI wires them to flags. The `flatray` package (`python/flatray/`)
//! wraps it: NumPy arrays, the `Scene` built from plain values, batches on
//! Ray.
//!
//! What it is for: loading, parsing and validating scenes with the errors
//! of `flatray-io`, rendering them with `flatray-tracer` with the GIL
//! released and Ctrl-C heard, and reading and writing images.
//!
//! What it never does: decide physics, or hold an estimator of its own.
//! A render here is the library's render, bit for bit the CLI's for the
//! same scene and settings.

use std::panic::AssertUnwindSafe;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use flatray_io::format::{MAX_BOUNCES, MAX_SAMPLES};
use flatray_io::{Loaded, SceneError as IoSceneError, ToneMap};
use flatray_tracer::{Image, Integrator, RenderOptions, Window, image_size};
use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyBytes;

pyo3::create_exception!(
    _flatray,
    SceneError,
    PyValueError,
    "A scene that cannot be loaded: `file`, `line` and `column` say where \
     (None where they do not apply), `at` the path of a value given in \
     code, `message` what was expected."
);

/// The Python exception for a scene error, carrying where it points.
fn scene_error(py: Python<'_>, error: &IoSceneError) -> PyErr {
    let err = SceneError::new_err(error.to_string());
    let value = err.value(py);
    let (file, line, column, at, message) = match error {
        IoSceneError::Read { path, source } => {
            (Some(path.clone()), None, None, None, source.to_string())
        }
        IoSceneError::NotAScene { path, .. } => {
            (Some(path.clone()), None, None, None, error.to_string())
        }
        IoSceneError::Invalid {
            path,
            line,
            column,
            message,
        } => (
            Some(path.clone()),
            Some(*line),
            Some(*column),
            None,
            message.clone(),
        ),
        IoSceneError::Value { at, message, .. } => {
            (None, None, None, Some(at.clone()), message.clone())
        }
    };
    let file = file.map(|p| p.display().to_string());
    // Setting attributes on a fresh exception instance does not fail.
    let _ = value.setattr("file", file);
    let _ = value.setattr("line", line);
    let _ = value.setattr("column", column);
    let _ = value.setattr("at", at);
    let _ = value.setattr("message", message);
    err
}

/// A validated scene with the render settings it asks for.
#[pyclass(frozen, module = "flatray._flatray")]
struct LoadedScene {
    loaded: Loaded,
    /// The scene text, where the scene was read from text.
    text: Option<String>,
}

#[pymethods]
impl LoadedScene {
    /// The canvas's size in pixels at scale 1: (width, height).
    #[getter]
    fn canvas(&self) -> (u32, u32) {
        let c = self.loaded.scene.canvas();
        (c.width, c.height)
    }

    /// What the scene lists: walls, emitting walls, lights, glass bodies.
    #[getter]
    fn counts(&self) -> (usize, usize, usize, usize) {
        let c = self.loaded.counts;
        (c.walls, c.emitting_walls, c.lights, c.glass)
    }

    /// The warnings: (line, column, message) each.
    #[getter]
    fn warnings(&self) -> Vec<(usize, usize, String)> {
        self.loaded
            .warnings
            .iter()
            .map(|w| (w.line, w.column, w.message.clone()))
            .collect()
    }

    /// The scene text, where it was read from text (None for values).
    #[getter]
    fn text(&self) -> Option<String> {
        self.text.clone()
    }

    /// The render settings the scene asks for, by the names of `render`'s
    /// keywords.
    #[getter]
    fn settings(&self) -> (u32, u32, u32, u64, f64, &'static str, &'static str, bool) {
        let o = &self.loaded.options;
        (
            o.samples,
            o.bounces,
            o.specular,
            o.seed,
            o.exposure,
            o.integrator.name(),
            o.memo.mode(),
            o.caustics,
        )
    }

    /// The PNG tone map's white point (Reinhard), or None where the
    /// scene clamps.
    #[getter]
    fn white(&self) -> Option<f64> {
        match self.loaded.tonemap {
            ToneMap::Clamp => None,
            ToneMap::Reinhard { white } => Some(white.0),
        }
    }

    /// The image's size in pixels at `scale`: (width, height).
    fn image_size(&self, scale: f64) -> (u32, u32) {
        image_size(&self.loaded.scene, scale)
    }

    /// The plan of a render with the scene's settings: the effects, with
    /// whether each runs and why, one line each.
    fn plan(&self) -> String {
        flatray_tracer::Plan::new(&self.loaded.scene, &self.loaded.options).to_string()
    }
}

fn loaded(
    py: Python<'_>,
    result: Result<Loaded, IoSceneError>,
    text: Option<String>,
) -> PyResult<LoadedScene> {
    result
        .map(|loaded| LoadedScene { loaded, text })
        .map_err(|e| scene_error(py, &e))
}

/// Reads and validates the scene file at `path`.
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<LoadedScene> {
    // Both reads with the GIL released; the text is read again only once
    // `load` has found a regular file of a scene.
    let (result, text) = py.detach(|| {
        let result = flatray_io::load(&path);
        let text = result.as_ref().ok().and_then(|_| {
            flatray_io::read_within(&path, flatray_io::MAX_INPUT_BYTES)
                .ok()
                .and_then(|bytes| String::from_utf8(bytes).ok())
        });
        (result, text)
    });
    loaded(py, result, text)
}

/// Parses and validates scene `text`; `name` names it in messages and
/// relative paths resolve against `base`.
#[pyfunction]
#[pyo3(signature = (text, name = "<string>".to_string(), base = PathBuf::from(".")))]
fn parse(py: Python<'_>, text: String, name: String, base: PathBuf) -> PyResult<LoadedScene> {
    let result = flatray_io::parse(&text, Path::new(&name), &base);
    loaded(py, result, Some(text))
}

/// Validates a scene given as JSON text of the format's values.
#[pyfunction]
#[pyo3(signature = (json, name = "<values>".to_string(), base = PathBuf::from(".")))]
fn from_json(py: Python<'_>, json: String, name: String, base: PathBuf) -> PyResult<LoadedScene> {
    loaded(py, flatray_io::from_json(&json, &name, &base), None)
}

/// The scene text of a generated apartment.
#[pyfunction]
#[pyo3(signature = (rooms = 16, lamps = 1, mirrors = 0.3, seed = 1, sun = true))]
fn generate(rooms: u32, lamps: u32, mirrors: f64, seed: u64, sun: bool) -> PyResult<String> {
    if rooms == 0 || rooms > 10_000 {
        return Err(PyValueError::new_err(format!(
            "rooms: expected 1 to 10000, found {rooms}"
        )));
    }
    if lamps > 64 {
        return Err(PyValueError::new_err(format!(
            "lamps: expected 0 to 64 a room, found {lamps}"
        )));
    }
    if !(0.0..=1.0).contains(&mirrors) {
        return Err(PyValueError::new_err(format!(
            "mirrors: expected a share from 0 to 1, found {mirrors}"
        )));
    }
    let plan = flatray_io::generate::Apartment {
        rooms,
        lamps_per_room: lamps,
        mirrors,
        sun,
        seed,
    };
    Ok(plan.to_ron())
}

/// The scene text of a plan (SVG, Tiled map, Universal VTT map, wall
/// mask), and the notes and warnings of what was not imported. With
/// `output`, the scene and its floor image are written there as `flatray
/// import -o` writes them; without, a map's image is not written and the
/// floor is plain.
#[pyfunction]
#[pyo3(signature = (path, scale = None, tolerance = None, doors = None, open_portals = None, lights = None, output = None, force = false))]
#[allow(clippy::too_many_arguments)]
fn import_plan(
    py: Python<'_>,
    path: PathBuf,
    scale: Option<f64>,
    tolerance: Option<f64>,
    doors: Option<&str>,
    open_portals: Option<&str>,
    lights: Option<&str>,
    output: Option<PathBuf>,
    force: bool,
) -> PyResult<(String, Vec<String>, Vec<String>)> {
    use flatray_io::import::{Doors, ImportOptions, ImportedFloor, OpenPortals};
    let mut options = ImportOptions {
        scale,
        ..ImportOptions::default()
    };
    if let Some(tolerance) = tolerance {
        options.tolerance = tolerance;
    }
    options.doors = match doors.unwrap_or("as-drawn") {
        "as-drawn" => Doors::AsDrawn,
        "open" => Doors::Open,
        "closed" => Doors::Closed,
        other => {
            return Err(PyValueError::new_err(format!(
                "doors: expected 'as-drawn', 'open' or 'closed', found {other:?}"
            )));
        }
    };
    options.open_portals = match open_portals.unwrap_or("windows") {
        "windows" => OpenPortals::Windows,
        "doors" => OpenPortals::Doors,
        other => {
            return Err(PyValueError::new_err(format!(
                "open_portals: expected 'windows' or 'doors', found {other:?}"
            )));
        }
    };
    options.lights = match lights.unwrap_or("keep") {
        "keep" => true,
        "none" => false,
        other => {
            return Err(PyValueError::new_err(format!(
                "lights: expected 'keep' or 'none', found {other:?}"
            )));
        }
    };
    let mut imported = py
        .detach(|| flatray_io::import::import(&path, &options))
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let mut notes: Vec<String> = imported
        .mapping
        .iter()
        .chain(&imported.notes)
        .cloned()
        .collect();
    match &output {
        Some(output) => {
            py.detach(|| imported.write(output, &path, force))
                .map_err(PyValueError::new_err)?;
        }
        None => {
            if imported.floor_file.take().is_some() {
                imported.floor = ImportedFloor::Color([0.5; 3]);
                notes.push(
                    "the map's image is not written without output=: the floor is plain grey"
                        .to_string(),
                );
            }
        }
    }
    Ok((imported.to_ron(), notes, imported.warnings.clone()))
}

/// Why a render stopped midway: Ctrl-C.
struct Interrupted;

/// The render settings: the scene's, with what the caller gave instead.
#[allow(clippy::too_many_arguments)]
fn options(
    loaded: &Loaded,
    spp: Option<u32>,
    bounces: Option<u32>,
    specular: Option<u32>,
    seed: Option<u64>,
    integrator: Option<&str>,
    cache: Option<&str>,
    (caustics, indirect): (Option<bool>, Option<&str>),
    exposure: Option<f64>,
    scale: f64,
    window: Option<(u32, u32, u32, u32)>,
) -> Result<RenderOptions, String> {
    let mut options = loaded.options;
    if let Some(spp) = spp {
        if !(1..=MAX_SAMPLES).contains(&spp) {
            return Err(format!("spp: expected 1 to {MAX_SAMPLES}, found {spp}"));
        }
        options.samples = spp;
    }
    if let Some(bounces) = bounces {
        if bounces > MAX_BOUNCES {
            return Err(format!(
                "bounces: expected 0 to {MAX_BOUNCES}, found {bounces}"
            ));
        }
        options.bounces = bounces;
    }
    if let Some(specular) = specular {
        if specular > MAX_BOUNCES {
            return Err(format!(
                "specular: expected 0 to {MAX_BOUNCES}, found {specular}"
            ));
        }
        options.specular = specular;
    }
    if let Some(seed) = seed {
        options.seed = seed;
    }
    if let Some(name) = integrator {
        options.integrator = match name {
            "path" => Integrator::Path,
            "original" => Integrator::Original,
            "light" => Integrator::Light,
            other => {
                return Err(format!(
                    "integrator: expected \"path\", \"original\" or \"light\", found {other:?}"
                ));
            }
        };
    }
    if let Some(name) = cache {
        (options.memo.enabled, options.memo.onward) = match name {
            "on" => (true, true),
            "off" => (false, true),
            "direct" => (true, false),
            other => {
                return Err(format!(
                    "cache: expected \"on\", \"off\" or \"direct\", found {other:?}"
                ));
            }
        };
    }
    if let Some(caustics) = caustics {
        options.caustics = caustics;
    }
    if let Some(name) = indirect {
        options.floor_lines = match name {
            "lines" => true,
            "samples" => false,
            other => {
                return Err(format!(
                    "indirect: expected \"lines\" or \"samples\", found {other:?}"
                ));
            }
        };
    }
    if let Some(exposure) = exposure {
        flatray_tracer::scene::checks::exposure(exposure).map_err(|m| format!("exposure: {m}"))?;
        options.exposure = exposure;
    }
    if !(scale.is_finite() && scale > 0.0) {
        return Err(format!("scale: expected a number > 0, found {scale}"));
    }
    options.scale = scale;
    let (width, height) = flatray_tracer::checked_image_size(&loaded.scene, scale)
        .map_err(|why| format!("scale {scale}: {why}"))?;
    if let Some((x0, y0, x1, y1)) = window {
        if !(x0 < x1 && y0 < y1 && x1 <= width && y1 <= height) {
            return Err(format!(
                "window: expected (x0, y0, x1, y1) with x0 < x1 <= {width} and y0 < y1 <= \
                 {height}, found ({x0}, {y0}, {x1}, {y1})"
            ));
        }
        options.window = Some(Window { x0, y0, x1, y1 });
    }
    Ok(options)
}

/// The image's floats as little-endian bytes, row-major, RGB.
fn image_bytes(image: &Image) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// The image of `bytes` (as [`image_bytes`] writes them).
fn image_of(bytes: &[u8], width: u32, height: u32) -> PyResult<Image> {
    let expected = width as usize * height as usize * 12;
    if bytes.len() != expected || width == 0 || height == 0 {
        return Err(PyValueError::new_err(format!(
            "expected {width} x {height} x 3 float32 values ({expected} bytes), found {} bytes",
            bytes.len()
        )));
    }
    let mut image = Image::new(width, height);
    for (pixel, chunk) in image.pixels.iter_mut().zip(bytes.chunks_exact(12)) {
        for (c, v) in pixel.iter_mut().zip(chunk.chunks_exact(4)) {
            *c = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
        }
    }
    Ok(image)
}

/// Renders `scene`; the keywords override its render settings. Returns
/// (image bytes, width, height, statistics as JSON, seconds). The GIL is
/// released while rendering; Ctrl-C stops the render within a tile and
/// raises KeyboardInterrupt. `progress`, where given, is called on this
/// thread about ten times a second with (work done, total work), and once
/// with both equal at the end; an exception it raises stops the render
/// and is raised here.
#[pyfunction]
#[pyo3(signature = (
    scene, *, spp = None, bounces = None, specular = None, seed = None, integrator = None,
    cache = None, caustics = None, indirect = None, exposure = None, scale = 1.0, window = None,
    threads = None,
    progress = None
))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Bound<'py, LoadedScene>,
    spp: Option<u32>,
    bounces: Option<u32>,
    specular: Option<u32>,
    seed: Option<u64>,
    integrator: Option<&str>,
    cache: Option<&str>,
    caustics: Option<bool>,
    indirect: Option<&str>,
    exposure: Option<f64>,
    scale: f64,
    window: Option<(u32, u32, u32, u32)>,
    threads: Option<usize>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyBytes>, u32, u32, String, f64)> {
    let loaded = &scene.get().loaded;
    let options = options(
        loaded,
        spp,
        bounces,
        specular,
        seed,
        integrator,
        cache,
        (caustics, indirect),
        exposure,
        scale,
        window,
    )
    .map_err(PyValueError::new_err)?;
    let pool = match threads {
        None => None,
        Some(0) => {
            return Err(PyValueError::new_err(
                "threads: expected at least 1, found 0",
            ));
        }
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyOSError::new_err(format!("cannot start {n} threads: {e}")))?,
        ),
    };
    let stop = AtomicBool::new(false);
    let done = AtomicU64::new(0);
    let total = work_total(loaded, &options);
    let progress = progress.map(Bound::unbind);
    let started = Instant::now();
    let mut interrupt: Option<PyErr> = None;
    // Says how far the render is: the work its progress callback counted,
    // short of the total until the render ends (the caustic pass's
    // photons count too, and may take it past the total).
    let report = |py: Python<'_>, callback: &Py<PyAny>, finished: bool| {
        let so_far = if finished {
            total
        } else {
            done.load(Ordering::Relaxed).min(total.saturating_sub(1))
        };
        callback.call1(py, (so_far, total)).map(drop)
    };
    let outcome = py.detach(|| {
        std::thread::scope(|s| {
            let worker = s.spawn(|| {
                // The library's render cannot be asked to stop: its progress
                // callback, called before each unit of work, unwinds out of
                // it with a private payload, caught here.
                let progress = |n: u64| {
                    if stop.load(Ordering::Relaxed) {
                        std::panic::resume_unwind(Box::new(Interrupted));
                    }
                    done.fetch_add(n, Ordering::Relaxed);
                };
                let work = || flatray_tracer::render(&loaded.scene, &options, &progress);
                std::panic::catch_unwind(AssertUnwindSafe(|| match &pool {
                    Some(pool) => pool.install(work),
                    None => work(),
                }))
            });
            let mut ticks = 0u32;
            while !worker.is_finished() {
                std::thread::sleep(Duration::from_millis(20));
                ticks += 1;
                if interrupt.is_some() {
                    continue;
                }
                let heard = Python::attach(|py| {
                    py.check_signals()?;
                    match &progress {
                        Some(callback) if ticks.is_multiple_of(5) => report(py, callback, false),
                        _ => Ok(()),
                    }
                });
                if let Err(e) = heard {
                    interrupt = Some(e);
                    stop.store(true, Ordering::Relaxed);
                }
            }
            worker.join()
        })
    });
    let seconds = started.elapsed().as_secs_f64();
    if let Some(e) = interrupt {
        return Err(e);
    }
    let rendered = match outcome {
        Ok(Ok(rendered)) => rendered,
        Ok(Err(payload)) | Err(payload) => std::panic::resume_unwind(payload),
    };
    if let Some(callback) = &progress {
        report(py, callback, true)?;
    }
    let stats = flatray_io::report::stats_json(&rendered.stats).to_string();
    let bytes = PyBytes::new(py, &image_bytes(&rendered.image));
    Ok((
        bytes,
        rendered.image.width,
        rendered.image.height,
        stats,
        seconds,
    ))
}

/// The work a render's progress callback counts: a sample for each pixel
/// of the tiles it renders.
fn work_total(loaded: &Loaded, options: &RenderOptions) -> u64 {
    let (width, height) = image_size(&loaded.scene, options.scale);
    let pixels = match options.window {
        Some(w) => {
            let tile = flatray_tracer::TILE;
            let x0 = w.x0 / tile * tile;
            let y0 = w.y0 / tile * tile;
            let x1 = w.x1.div_ceil(tile).saturating_mul(tile).min(width);
            let y1 = w.y1.div_ceil(tile).saturating_mul(tile).min(height);
            (x1 - x0) as u64 * (y1 - y0) as u64
        }
        None => width as u64 * height as u64,
    };
    (pixels * options.samples as u64).max(1)
}

/// Measures `scene`'s rooms (`flatray measure`): the figures as JSON, and
/// the grid as little-endian f64 rows of (x, y, room, E, se) with their
/// count. The GIL is released during each batch's render; Ctrl-C is
/// heard between batches.
#[pyfunction]
#[pyo3(signature = (scene, *, spp = None, batches = 8, scale = 1.0, door_width = None, target_error = None))]
fn measure<'py>(
    py: Python<'py>,
    scene: &Bound<'py, LoadedScene>,
    spp: Option<u32>,
    batches: u32,
    scale: f64,
    door_width: Option<f64>,
    target_error: Option<f64>,
) -> PyResult<(String, Bound<'py, PyBytes>, usize)> {
    let loaded = &scene.get().loaded;
    let request = flatray_io::measure::Request {
        spp,
        batches,
        scale,
        door_width,
        target_error,
    };
    let mut interrupt: Option<PyErr> = None;
    let result = flatray_io::measure::run(loaded, &request, |options| {
        if interrupt.is_none()
            && let Err(e) = py.check_signals()
        {
            interrupt = Some(e);
        }
        if interrupt.is_some() {
            // A blank batch: the measurement is thrown away below.
            let (w, h) = image_size(&loaded.scene, options.scale);
            return flatray_tracer::Image::new(w, h);
        }
        py.detach(|| flatray_tracer::render(&loaded.scene, options, &|_| {}).image)
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let (_, measured) = result.map_err(PyValueError::new_err)?;
    let mut grid = Vec::with_capacity(measured.points.len() * 5 * 8);
    for p in &measured.points {
        for v in [p.at.x, p.at.y, p.room as f64, p.e.value, p.e.se] {
            grid.extend_from_slice(&v.to_le_bytes());
        }
    }
    Ok((
        flatray_io::measure::json(&measured).to_string(),
        PyBytes::new(py, &grid),
        measured.points.len(),
    ))
}

/// The scene text of scene values given as JSON (as `from_json` takes
/// them): it loads back as the same scene.
#[pyfunction]
fn values_text(json: &str) -> PyResult<String> {
    flatray_io::values::to_text(json).map_err(PyValueError::new_err)
}

/// Reads a linear EXR image: (bytes, width, height). Only a regular file
/// within the input budget is read, with the GIL released.
#[pyfunction]
fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyBytes>, u32, u32)> {
    let image = py
        .detach(|| {
            let bytes = flatray_io::read_within(&path, flatray_io::MAX_INPUT_BYTES)
                .map_err(|e| format!("{}: {e}", path.display()))?;
            flatray_io::decode_exr(&bytes).map_err(|e| format!("{}: {e}", path.display()))
        })
        .map_err(PyOSError::new_err)?;
    Ok((
        PyBytes::new(py, &image_bytes(&image)),
        image.width,
        image.height,
    ))
}

/// Writes an image (as [`image_bytes`] writes them) to `path`, whole or
/// not at all: `.exr` linear, `.png` tone-mapped with `white` (Reinhard;
/// None clamps).
#[pyfunction]
#[pyo3(signature = (path, data, width, height, white = Some(4.0)))]
fn write_image(
    py: Python<'_>,
    path: PathBuf,
    data: &[u8],
    width: u32,
    height: u32,
    white: Option<f64>,
) -> PyResult<()> {
    let image = image_of(data, width, height)?;
    let tonemap = match white {
        None => ToneMap::Clamp,
        Some(w) => {
            flatray_tracer::scene::checks::positive(w)
                .map_err(|m| PyValueError::new_err(format!("white: {m}")))?;
            ToneMap::Reinhard {
                white: flatray_io::format::Positive(w),
            }
        }
    };
    py.detach(|| flatray_io::write_image(&image, tonemap, &path))
        .map_err(|e| PyOSError::new_err(e.to_string()))
}

#[pymodule]
fn _flatray(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("SceneError", m.py().get_type::<SceneError>())?;
    m.add_class::<LoadedScene>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(parse, m)?)?;
    m.add_function(wrap_pyfunction!(from_json, m)?)?;
    m.add_function(wrap_pyfunction!(values_text, m)?)?;
    m.add_function(wrap_pyfunction!(generate, m)?)?;
    m.add_function(wrap_pyfunction!(import_plan, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(measure, m)?)?;
    m.add_function(wrap_pyfunction!(read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(write_image, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
