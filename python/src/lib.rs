//! `afford._native`: the afford library as a Python extension module. The pure-Python
//! package `afford` (python/afford) wraps these functions; they take already-checked
//! arguments and return plain Python data (dicts, lists, numpy arrays), so that the
//! package's `Result` pickles and crosses process boundaries.
//!
//! Detection runs with the GIL released, in a local rayon pool when `threads` is given.
//! The outputs (`--json`, `--csv`, `--summary` documents) are written by the library's own
//! writers ([`afford::report`]) from reports rebuilt out of that plain data.

use std::ffi::OsString;
use std::path::Path;
use std::str::FromStr;

use afford::cloud::frame::{parse_matrix, FloorMode, FrameOptions, Units};
use afford::cloud::CloudError;
use afford::detect::{DetectConfig, Detection, Stats};
use afford::embed::{self, Detected};
use afford::input::{load_input, InputError, InputOptions};
use afford::model::set::Model;
use afford::model::set::ModelChoice;
use afford::model::ModelError;
use afford::report::{self, FileReport, RunStats};
use nalgebra::Point3;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyReadonlyArray2};
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// A file error as `OSError` (`FileNotFoundError` when it is missing), a bad argument or
/// content as `ValueError`; the message is the CLI's line without `error: `.
fn input_error(e: InputError) -> PyErr {
    match &e {
        InputError::Cloud(CloudError::Io { source, .. })
            if source.kind() == std::io::ErrorKind::NotFound =>
        {
            PyFileNotFoundError::new_err(e.to_string())
        }
        InputError::Cloud(_) => PyOSError::new_err(e.to_string()),
        InputError::Frame { .. } => PyValueError::new_err(e.to_string()),
    }
}

/// A detection error: an input error as [`input_error`]; a cloud the extent guard refuses
/// (coordinates beyond the grids, grids over the memory limit) as `ValueError`.
fn detect_error(e: embed::DetectError) -> PyErr {
    match e {
        embed::DetectError::Input(e) => input_error(e),
        embed::DetectError::Extent(e) => PyValueError::new_err(e.to_string()),
    }
}

/// Model errors: a missing model file or unknown name is `FileNotFoundError`, another
/// read failure `OSError`, a malformed or impossible model `ValueError`.
fn model_error(e: ModelError) -> PyErr {
    match &e {
        ModelError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(e.to_string())
        }
        ModelError::Unknown { .. } => PyFileNotFoundError::new_err(e.to_string()),
        ModelError::Io { .. } => PyOSError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// Parses one option with its `FromStr` (the CLI's parser), naming the argument.
fn parse<T: FromStr<Err = String>>(what: &str, s: &str) -> PyResult<T> {
    s.parse()
        .map_err(|e: String| PyValueError::new_err(format!("{what}: {e}")))
}

/// The frame options of the CLI's `--up --units --camera --floor --transform`; the
/// transform is the text of a 4x4 matrix (the Python side reads files and flattens arrays).
fn frame_options(
    up: &str,
    units: &str,
    camera: bool,
    floor: &str,
    transform: Option<&str>,
) -> PyResult<FrameOptions> {
    let transform = match transform {
        None => None,
        Some(t) => {
            Some(parse_matrix(t).map_err(|e| PyValueError::new_err(format!("transform: {e}")))?)
        }
    };
    Ok(FrameOptions {
        up: parse("up", up)?,
        transform,
        units: parse::<Units>("units", units)?,
        floor: parse::<FloorMode>("floor", floor)?,
        camera,
    })
}

/// The bodies and hierarchies, loaded (as the CLI's `--agent --affordances --height`).
fn models(
    heights: Vec<f64>,
    agents: Vec<String>,
    affordances: Vec<String>,
) -> PyResult<Vec<Model>> {
    ModelChoice {
        agents,
        hierarchies: affordances,
        heights,
    }
    .load()
    .map_err(model_error)
}

/// Runs `f` without the GIL: in the global rayon pool, or in a local one of `threads`.
fn detached<T, F>(py: Python<'_>, threads: Option<usize>, f: F) -> PyResult<T>
where
    T: Send,
    F: FnOnce() -> T + Send,
{
    let pool = match threads {
        None => None,
        Some(0) => return Err(PyValueError::new_err("threads: must be at least 1")),
        Some(n) => Some(
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .map_err(|e| PyOSError::new_err(format!("threads: {e}")))?,
        ),
    };
    Ok(py.detach(move || match pool {
        Some(p) => p.install(f),
        None => f(),
    }))
}

/// One detection as a dict (full precision; `yaw` in radians, `yaw_deg` in degrees).
fn detection_dict<'py>(
    py: Python<'py>,
    d: &Detection,
    segment: &[usize],
    rows: &[usize],
) -> PyResult<Bound<'py, PyDict>> {
    let o = PyDict::new(py);
    o.set_item("hierarchy", &d.hierarchy)?;
    o.set_item("agent", &d.agent)?;
    o.set_item("height", d.height)?;
    o.set_item("position", [d.position.x, d.position.y, d.position.z])?;
    o.set_item("yaw", d.yaw)?;
    o.set_item("yaw_deg", d.yaw.to_degrees())?;
    o.set_item("affordances", &d.affordances)?;
    o.set_item("local_scores", d.local_scores.clone())?;
    o.set_item("pose_deg", d.pose.clone())?;
    let joints: Vec<(String, [f64; 3])> = d
        .joints
        .iter()
        .map(|(n, p)| (n.clone(), [p.x, p.y, p.z]))
        .collect();
    o.set_item("joints", joints)?;
    o.set_item("score", d.score)?;
    o.set_item("stability", d.stability)?;
    o.set_item("availability", d.availability)?;
    o.set_item("segment_points", d.segment_points)?;
    let seg: Vec<i64> = segment.iter().map(|&i| rows[i] as i64).collect();
    o.set_item("segment", seg.into_pyarray(py))?;
    Ok(o)
}

/// The plain data of one input's detection; `n` is the number of input rows.
fn detected_dict<'py>(py: Python<'py>, d: &Detected, n: usize) -> PyResult<Bound<'py, PyDict>> {
    let r = &d.report;
    let o = PyDict::new(py);
    o.set_item("file", &r.file)?;
    o.set_item("points", r.points())?;
    o.set_item("dropped_non_finite", r.dropped_non_finite)?;
    o.set_item("ids", &r.ids)?;
    o.set_item("affordances", report::affords(r, None))?;
    let runs: Vec<(String, f64, String, usize, usize, usize)> = r
        .runs
        .iter()
        .map(|u| {
            (
                u.agent.clone(),
                u.height,
                u.hierarchy.clone(),
                u.stats.hypotheses,
                u.stats.fits,
                u.stats.candidates,
            )
        })
        .collect();
    o.set_item("runs", runs)?;
    let dets = PyList::empty(py);
    for (det, seg) in r.detections.iter().zip(&d.segments) {
        dets.append(detection_dict(py, det, seg, &d.rows)?)?;
    }
    o.set_item("detections", dets)?;
    let mut labels = vec![-1i32; n];
    for (i, l) in r.labels.iter().enumerate() {
        if let Some(l) = l {
            labels[d.rows[i]] = i32::try_from(*l).unwrap_or(i32::MAX);
        }
    }
    o.set_item("labels", labels.into_pyarray(py))?;
    let m = d.matrix();
    let flat: Vec<f64> = (0..16).map(|k| m[(k / 4, k % 4)]).collect();
    let matrix =
        Array2::from_shape_vec((4, 4), flat).map_err(|e| PyValueError::new_err(e.to_string()))?;
    o.set_item("transform", matrix.into_pyarray(py))?;
    o.set_item("frame", d.frame.as_ref().map(|f| f.to_string()))?;
    o.set_item("units_warning", d.units_warning.clone())?;
    o.set_item("floor_warning", d.floor_warning.clone())?;
    Ok(o)
}

/// The rows of an (N, 3) array as points (any memory order).
fn points_of<T: numpy::Element + Copy + Into<f64>>(
    a: &PyReadonlyArray2<'_, T>,
) -> PyResult<Vec<Point3<f64>>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "points: expected an array of shape (N, 3), got ({}, {})",
            v.nrows(),
            v.ncols()
        )));
    }
    Ok(v.rows()
        .into_iter()
        .map(|r| Point3::new(r[0].into(), r[1].into(), r[2].into()))
        .collect())
}

/// Detects in an (N, 3) float32 or float64 array (see `afford.detect`).
#[pyfunction]
#[pyo3(signature = (points, name, heights, agents, affordances, up, units, camera, floor, transform, threads))]
#[allow(clippy::too_many_arguments)]
fn detect_array<'py>(
    py: Python<'py>,
    points: &Bound<'py, PyAny>,
    name: &str,
    heights: Vec<f64>,
    agents: Vec<String>,
    affordances: Vec<String>,
    up: &str,
    units: &str,
    camera: bool,
    floor: &str,
    transform: Option<&str>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let raw = if let Ok(a) = points.extract::<PyReadonlyArray2<'py, f64>>() {
        points_of(&a)?
    } else if let Ok(a) = points.extract::<PyReadonlyArray2<'py, f32>>() {
        points_of(&a)?
    } else {
        return Err(PyValueError::new_err(
            "points: expected a 2-D float32 or float64 numpy array of shape (N, 3)",
        ));
    };
    let n = raw.len();
    let frame = frame_options(up, units, camera, floor, transform)?;
    let models = models(heights, agents, affordances)?;
    let cfg = DetectConfig::default();
    let d = detached(py, threads, || {
        embed::detect_points(name, raw, &frame, &models, &cfg)
    })?
    .map_err(detect_error)?;
    detected_dict(py, &d, n)
}

/// Reads and detects in one file as `afford detect` does (see `afford.detect_file`).
#[pyfunction]
#[pyo3(signature = (path, heights, agents, affordances, up, units, camera, floor, transform, sample, threads))]
#[allow(clippy::too_many_arguments)]
fn detect_file<'py>(
    py: Python<'py>,
    path: &str,
    heights: Vec<f64>,
    agents: Vec<String>,
    affordances: Vec<String>,
    up: &str,
    units: &str,
    camera: bool,
    floor: &str,
    transform: Option<&str>,
    sample: Option<f64>,
    threads: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let opts = InputOptions {
        frame: frame_options(up, units, camera, floor, transform)?,
        sample,
        source: Default::default(),
    };
    let models = models(heights, agents, affordances)?;
    let cfg = DetectConfig::default();
    let d = detached(py, threads, || {
        embed::detect_path(Path::new(path), &opts, &models, &cfg)
    })?
    .map_err(detect_error)?;
    let n = d.rows.len();
    detected_dict(py, &d, n)
}

/// Reads a cloud or samples a mesh into the world frame: `(points (N, 3) float64,
/// dropped_non_finite)` (see `afford.read`).
#[pyfunction]
#[pyo3(signature = (path, up, units, camera, floor, transform, sample))]
#[allow(clippy::too_many_arguments)]
fn read<'py>(
    py: Python<'py>,
    path: &str,
    up: &str,
    units: &str,
    camera: bool,
    floor: &str,
    transform: Option<&str>,
    sample: Option<f64>,
) -> PyResult<(Bound<'py, PyAny>, usize)> {
    let opts = InputOptions {
        frame: frame_options(up, units, camera, floor, transform)?,
        sample,
        source: Default::default(),
    };
    let input = py
        .detach(|| load_input(Path::new(path), &opts))
        .map_err(input_error)?;
    let flat: Vec<f64> = input
        .cloud
        .points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .collect();
    let a = Array2::from_shape_vec((input.cloud.len(), 3), flat)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    Ok((a.into_pyarray(py).into_any(), input.dropped_non_finite))
}

/// Gets `key` of a dict made by [`detected_dict`], naming it when it is missing.
fn get<'py, T: FromPyObjectOwned<'py>>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<T> {
    match d.get_item(key)? {
        Some(v) => v.extract::<T>().map_err(|e| {
            let e: PyErr = e.into();
            PyValueError::new_err(format!("result field {key}: {e}"))
        }),
        None => Err(PyValueError::new_err(format!(
            "result field {key} is missing"
        ))),
    }
}

/// Rebuilds the library's report from the plain data of [`detected_dict`]; the fields the
/// documents do not use (the seat, the posed parts, voxel counts) are left empty.
fn report_of(d: &Bound<'_, PyDict>) -> PyResult<FileReport> {
    let points: usize = get(d, "points")?;
    let runs: Vec<(String, f64, String, usize, usize, usize)> = get(d, "runs")?;
    let dets: Vec<Bound<'_, PyDict>> = get(d, "detections")?;
    let mut detections = Vec::new();
    for x in &dets {
        let p: [f64; 3] = get(x, "position")?;
        let position = Point3::new(p[0], p[1], p[2]);
        detections.push(Detection {
            hierarchy: get(x, "hierarchy")?,
            agent: get(x, "agent")?,
            height: get(x, "height")?,
            position,
            yaw: get(x, "yaw")?,
            seat: position,
            affordances: get(x, "affordances")?,
            local_scores: get(x, "local_scores")?,
            pose: get(x, "pose_deg")?,
            joints: get::<Vec<(String, [f64; 3])>>(x, "joints")?
                .into_iter()
                .map(|(n, [jx, jy, jz])| (n, Point3::new(jx, jy, jz)))
                .collect(),
            score: get(x, "score")?,
            stability: get(x, "stability")?,
            availability: get(x, "availability")?,
            segment_points: get(x, "segment_points")?,
            parts: Vec::new(),
        });
    }
    Ok(FileReport {
        file: get(d, "file")?,
        dropped_non_finite: get(d, "dropped_non_finite")?,
        ids: get(d, "ids")?,
        runs: runs
            .into_iter()
            .map(
                |(agent, height, hierarchy, hypotheses, fits, candidates)| RunStats {
                    agent,
                    height,
                    hierarchy,
                    stats: Stats {
                        points,
                        voxels: 0,
                        hypotheses,
                        fits,
                        candidates,
                    },
                },
            )
            .collect(),
        detections,
        labels: vec![None; points],
    })
}

/// The `--json`, `--csv` and `--summary` documents of several results, as the CLI writes
/// them for a run over their files in this order.
#[pyfunction]
fn documents(results: Vec<Bound<'_, PyDict>>) -> PyResult<(String, String, String)> {
    let reports = results
        .iter()
        .map(report_of)
        .collect::<PyResult<Vec<_>>>()?;
    let csv_err = |e: csv::Error| PyValueError::new_err(e.to_string());
    Ok((
        report::to_json(&reports),
        report::to_csv(&reports).map_err(csv_err)?,
        report::to_summary(&reports).map_err(csv_err)?,
    ))
}

/// Runs the `afford` command line on `argv` (program name first); returns its exit code.
#[pyfunction]
fn cli_main(py: Python<'_>, argv: Vec<OsString>) -> u8 {
    py.detach(move || afford_cli::cli::main(argv))
}

/// The native half of the `afford` package.
#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(detect_array, m)?)?;
    m.add_function(wrap_pyfunction!(detect_file, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(documents, m)?)?;
    m.add_function(wrap_pyfunction!(cli_main, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
