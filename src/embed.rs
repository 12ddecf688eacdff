//! Detection for programs that hold the cloud in memory (the Python package): the same
//! path as `afford detect` on one input ([`crate::input::to_input`], then
//! [`crate::detect::detect_input`] and [`FileReport::new`]), with what a caller needs
//! besides the report: which input row each point came from, the points of every
//! detection's segment, and the map to the world frame.

use std::path::Path;

use nalgebra::{Matrix4, Point3};

use crate::cloud::frame::{FrameOptions, FrameReport};
use crate::cloud::keep_finite;
use crate::detect::{detect_input, DetectConfig};
use crate::input::{load_input, to_input, Input, InputError, InputOptions};
use crate::method::extent::ExtentError;
use crate::model::set::Model;
use crate::report::FileReport;

/// One input's detection, with the links back to the caller's rows.
#[derive(Debug, Clone)]
pub struct Detected {
    /// The report `afford detect` writes for this input (the `--json` entry).
    pub report: FileReport,
    /// For every point of the cloud detected in (the finite ones, in order), its row in
    /// the caller's input.
    pub rows: Vec<usize>,
    /// For every detection of `report`, the points of the segment grown from it, as
    /// indices into the cloud detected in (its own run's segment, so a point can belong to
    /// detections of several bodies or hierarchies; `report.labels` keeps the first).
    pub segments: Vec<Vec<usize>>,
    /// What was done to bring the input into the world frame, when anything was.
    pub frame: Option<FrameReport>,
    /// A warning about the units the extent suggests (names the input).
    pub units_warning: Option<String>,
    /// A warning that the floor seems not to be at z = 0 (names the input).
    pub floor_warning: Option<String>,
}

/// Why an input gave no detection.
#[derive(Debug, thiserror::Error)]
pub enum DetectError {
    /// It could not be read or brought into the world frame.
    #[error(transparent)]
    Input(#[from] InputError),
    /// Its coordinates or extent are refused before the grids ([`crate::method::extent`]).
    #[error(transparent)]
    Extent(#[from] ExtentError),
}

impl Detected {
    /// The affine map from input coordinates to the detector's world frame (metres, z up,
    /// floor at z = 0): the identity when the input was used as given.
    pub fn matrix(&self) -> Matrix4<f64> {
        self.frame
            .as_ref()
            .map_or_else(Matrix4::identity, |f| f.matrix)
    }
}

/// Detects in points held in memory, in input units and frame: rows with a non-finite
/// coordinate are dropped (and counted in the report), the rest brought into the world
/// frame with `frame` as `afford detect` does with a file. `name` stands for the file in
/// the report and in messages. The report equals the CLI's for a file holding the same
/// points (same coordinates after the reader's conversion to `f64`).
pub fn detect_points(
    name: &str,
    raw: Vec<Point3<f64>>,
    frame: &FrameOptions,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<Detected, DetectError> {
    let rows: Vec<usize> = raw
        .iter()
        .enumerate()
        .filter(|(_, p)| p.coords.iter().all(|c| c.is_finite()))
        .map(|(i, _)| i)
        .collect();
    let input = to_input(Path::new(name), keep_finite(raw), frame)?;
    detect_in(name, input, rows, models, cfg)
}

/// Reads and detects in one file exactly as `afford detect` does with `opts` (the
/// report's `file` is `path` as given); `rows` are the points' order in the file's cloud
/// after non-finite points are dropped, i.e. `0..points`.
pub fn detect_path(
    path: &Path,
    opts: &InputOptions,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<Detected, DetectError> {
    let input = load_input(path, opts)?;
    let rows = (0..input.cloud.len()).collect();
    detect_in(&path.display().to_string(), input, rows, models, cfg)
}

fn detect_in(
    name: &str,
    input: Input,
    rows: Vec<usize>,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<Detected, DetectError> {
    let outcomes = detect_input(Path::new(name), &input.cloud, models, cfg)?;
    let mut segments = Vec::new();
    for o in &outcomes {
        let mut own = vec![Vec::new(); o.detections.len()];
        for (i, l) in o.labels.iter().enumerate() {
            if let Some(d) = l {
                own[*d].push(i);
            }
        }
        segments.extend(own);
    }
    let report = FileReport::new(
        name.to_string(),
        input.cloud.len(),
        input.dropped_non_finite,
        models,
        outcomes,
    );
    Ok(Detected {
        report,
        rows,
        segments,
        frame: input.frame,
        units_warning: input.units_warning,
        floor_warning: input.floor_warning,
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::model::set::ModelChoice;

    /// A seat-height box top (0.45 m) on a floor, 1 cm apart: something to sit on.
    pub(crate) fn stool() -> Vec<Point3<f64>> {
        let mut pts = Vec::new();
        for i in 0..200 {
            for j in 0..200 {
                pts.push(Point3::new(i as f64 * 0.01, j as f64 * 0.01, 0.0));
            }
        }
        for i in 0..40 {
            for j in 0..40 {
                pts.push(Point3::new(
                    0.8 + i as f64 * 0.01,
                    0.8 + j as f64 * 0.01,
                    0.45,
                ));
            }
        }
        pts
    }

    /// The built-in human at 1.75 m with the sitting hierarchy.
    fn sitting() -> Vec<Model> {
        ModelChoice {
            hierarchies: vec!["sitting".into()],
            ..Default::default()
        }
        .load()
        .unwrap()
    }

    #[test]
    fn non_finite_rows_are_dropped_and_the_rest_keep_their_rows() {
        let models = sitting();
        let clean = stool();
        let mut holed = clean.clone();
        holed.insert(0, Point3::new(f64::NAN, 0.0, 0.0));
        holed.insert(500, Point3::new(0.0, f64::INFINITY, 0.0));
        let cfg = DetectConfig::default();
        let a = detect_points("a", clean, &FrameOptions::default(), &models, &cfg).unwrap();
        let b = detect_points("a", holed, &FrameOptions::default(), &models, &cfg).unwrap();
        assert_eq!(b.report.dropped_non_finite, 2);
        assert_eq!(b.rows.len(), a.rows.len());
        assert_eq!(b.rows[0], 1, "row 0 was dropped");
        assert_eq!(b.rows[498], 499);
        assert_eq!(b.rows[499], 501, "row 500 was dropped");
        assert_eq!(a.report.detections, b.report.detections);
        assert!(!a.report.detections.is_empty(), "the stool is found");
        assert_eq!(a.segments.len(), a.report.detections.len());
        for (s, d) in a.segments.iter().zip(&a.report.detections) {
            assert_eq!(s.len(), d.segment_points);
        }
        assert_eq!(a.matrix(), Matrix4::identity());
    }

    #[test]
    fn the_extent_guard_runs_as_in_afford_detect() {
        let models = sitting();
        let cfg = DetectConfig::default();
        // A point 1e8 m away (a grid over that box would not fit any memory): refused
        // with detect's line.
        let mut far = stool();
        far.push(Point3::new(1e8, 0.0, 0.0));
        let Err(e) = detect_points("far", far, &FrameOptions::default(), &models, &cfg) else {
            panic!("detected over a box of 1e8 m");
        };
        assert!(matches!(
            e,
            DetectError::Extent(ExtentError::Coordinate { .. })
        ));
        assert!(
            e.to_string().starts_with("far: point 41600: coordinate"),
            "{e}"
        );
        // A stray point is left out of the grids: the stool is found as without it.
        let mut stray = stool();
        stray.push(Point3::new(100.0, 100.0, 0.0));
        let a = detect_points("a", stool(), &FrameOptions::default(), &models, &cfg).unwrap();
        let b = detect_points("a", stray, &FrameOptions::default(), &models, &cfg).unwrap();
        assert!(!a.report.detections.is_empty(), "the stool is found");
        assert_eq!(a.report.detections, b.report.detections);
        assert_eq!(b.report.labels.len(), a.report.labels.len() + 1);
    }
}
