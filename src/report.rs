//! Outputs (docs/formats.md): JSON per run, detections CSV,
//! summary CSV, segments PLY, and a short human-readable table. Every file is written to a
//! temporary file beside it and renamed into place, so nothing half-written is left.
//!
//! Numbers are printed with fixed decimals so that the same input gives the same bytes.
//! Beside the tables: pictures ([`render`]), the agents as meshes ([`agent_mesh`], [`glb`])
//! the atomic file writes every writer uses ([`atomic`]), and reading saved outputs back
//! ([`saved`]).

pub mod agent_mesh;
pub mod atomic;
pub mod glb;
pub mod render;
pub mod saved;

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::detect::{Detection, Outcome, Stats};
use crate::model::set::Model;

/// The result of one input file over every model of the run, as it goes into the outputs.
#[derive(Debug, Clone)]
pub struct FileReport {
    /// The file as named on the command line (or relative to a labels file).
    pub file: String,
    /// Points dropped for non-finite coordinates.
    pub dropped_non_finite: usize,
    /// Affordance ids of every hierarchy run, each once, in hierarchy and node order.
    pub ids: Vec<String>,
    /// What each model (a body with a hierarchy) produced, in the order of the set.
    pub runs: Vec<RunStats>,
    /// The detections of every run, run after run; their index here is their number.
    pub detections: Vec<Detection>,
    /// Per input point, the number of the first detection whose segment holds it.
    pub labels: Vec<Option<usize>>,
}

/// One model's run over a file: which body and hierarchy, and the counts of its stages.
#[derive(Debug, Clone)]
pub struct RunStats {
    /// Agent name.
    pub agent: String,
    /// Body height, metres.
    pub height: f64,
    /// Hierarchy name.
    pub hierarchy: String,
    /// Stage counts.
    pub stats: Stats,
}

impl FileReport {
    /// Gathers the outcomes of `models` (one each, in order) on one file.
    pub fn new(
        file: String,
        points: usize,
        dropped_non_finite: usize,
        models: &[Model],
        outcomes: Vec<Outcome>,
    ) -> FileReport {
        let mut detections = Vec::new();
        // `None` until the first outcome: every label `None`, one per point.
        let mut labels: Option<Vec<Option<usize>>> = None;
        let mut runs = Vec::new();
        for (m, o) in models.iter().zip(outcomes) {
            let offset = detections.len();
            if labels.is_none() && o.labels.len() == points {
                // The first outcome's labels, one per point, are the merged ones as they
                // stand (no detection before it, so no offset): kept, not copied.
                labels = Some(o.labels);
            } else {
                let merged = labels.get_or_insert_with(|| vec![None; points]);
                for (l, ol) in merged.iter_mut().zip(&o.labels) {
                    if l.is_none() {
                        *l = ol.map(|i| i + offset);
                    }
                }
            }
            runs.push(RunStats {
                agent: m.agent.name.clone(),
                height: m.agent.height,
                hierarchy: m.hierarchy.name.clone(),
                stats: o.stats,
            });
            detections.extend(o.detections);
        }
        FileReport {
            file,
            dropped_non_finite,
            ids: crate::model::set::ids(models),
            runs,
            detections,
            labels: labels.unwrap_or_else(|| vec![None; points]),
        }
    }

    /// The bodies of the run, `(agent, height)`, each once, in order.
    pub fn bodies(&self) -> Vec<(&str, f64)> {
        let mut out: Vec<(&str, f64)> = Vec::new();
        for r in &self.runs {
            if !out.iter().any(|b| b.0 == r.agent && b.1 == r.height) {
                out.push((&r.agent, r.height));
            }
        }
        out
    }

    /// Points of the cloud (one label each).
    pub fn points(&self) -> usize {
        self.labels.len()
    }

    /// Hypotheses over every run.
    pub fn hypotheses(&self) -> usize {
        self.runs.iter().map(|r| r.stats.hypotheses).sum()
    }
}

/// Rounds to `d` decimals for output (stable bytes, no float noise).
fn round(x: f64, d: i32) -> f64 {
    let k = 10f64.powi(d);
    let r = (x * k).round() / k;
    if r == 0.0 {
        0.0
    } else {
        r
    }
}

/// The JSON document of `afford detect --json` (and of each `--out-dir` file): version
/// [`JSON_VERSION`], one entry per input cloud. [`to_json`] writes it and
/// [`saved::read_saved`] reads it, with these same types. Numbers are rounded as
/// written: positions, scores and joint positions to 4 decimals, heights to 3, angles to 2.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Document {
    /// [`JSON_VERSION`] when written; the reader takes 2 to [`JSON_VERSION`].
    pub version: u32,
    /// One entry per input cloud, in input order.
    pub files: Vec<DocumentFile>,
}

/// One input cloud in the [`Document`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DocumentFile {
    /// The input as named (a bag message as `file@time`).
    pub file: String,
    /// Points of the cloud.
    pub points: usize,
    /// Points dropped for non-finite coordinates.
    pub dropped_non_finite: usize,
    /// Affordance ids found by any detection, in hierarchy and node order.
    pub affordances: Vec<String>,
    /// Every model run on the file (a body with a hierarchy), in the order of the set.
    pub runs: Vec<DocumentRun>,
    /// Every detection of every run, run after run.
    pub detections: Vec<DocumentDetection>,
}

/// One model's run in the [`Document`]: which body and hierarchy, and its stage counts.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DocumentRun {
    /// Agent name.
    pub agent: String,
    /// Body height, metres.
    pub height: f64,
    /// Hierarchy name.
    pub hierarchy: String,
    /// Hypotheses of the height map (section 4.1).
    pub hypotheses: usize,
    /// Stable fits (section 4.2).
    pub fits: usize,
    /// Unfolded candidates before suppression.
    pub candidates: usize,
}

/// One detection in the [`Document`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DocumentDetection {
    /// Its number in the file (index into `detections`).
    pub detection: usize,
    /// Hierarchy name.
    pub hierarchy: String,
    /// Agent name.
    pub agent: String,
    /// Body height, metres.
    pub height: f64,
    /// The agent's root joint, world frame, metres.
    pub position: [f64; 3],
    /// Heading about world z, degrees; 0 faces +x.
    pub yaw_deg: f64,
    /// Affordance ids found, in node order.
    pub affordances: Vec<String>,
    /// Accumulated score (Eq. 5).
    pub score: f64,
    /// Stability of the fit (Eq. 1).
    pub stability: f64,
    /// Availability of the hypothesis (section 4.1).
    pub availability: f64,
    /// Local score of every visited node (Eq. 3-4), by id.
    pub local_scores: BTreeMap<String, f64>,
    /// The goal pose: every joint's angle, degrees, by joint name.
    pub pose_deg: BTreeMap<String, f64>,
    /// Every joint's origin in the goal pose, world frame, metres, by joint name (added in
    /// version 3; empty when reading version 2).
    #[serde(default)]
    pub joints: BTreeMap<String, [f64; 3]>,
    /// Points of the segment grown from the detection.
    pub segment_points: usize,
}

/// The document entry of one report.
fn document_file(r: &FileReport) -> DocumentFile {
    DocumentFile {
        file: r.file.clone(),
        points: r.points(),
        dropped_non_finite: r.dropped_non_finite,
        affordances: affords(r, None).into_iter().cloned().collect(),
        runs: r
            .runs
            .iter()
            .map(|u| DocumentRun {
                agent: u.agent.clone(),
                height: round(u.height, 3),
                hierarchy: u.hierarchy.clone(),
                hypotheses: u.stats.hypotheses,
                fits: u.stats.fits,
                candidates: u.stats.candidates,
            })
            .collect(),
        detections: r
            .detections
            .iter()
            .enumerate()
            .map(|(i, d)| document_detection(i, d))
            .collect(),
    }
}

fn document_detection(i: usize, d: &Detection) -> DocumentDetection {
    let named = |v: &[(String, f64)], decimals: i32| {
        v.iter()
            .map(|(k, x)| (k.clone(), round(*x, decimals)))
            .collect()
    };
    DocumentDetection {
        detection: i,
        hierarchy: d.hierarchy.clone(),
        agent: d.agent.clone(),
        height: round(d.height, 3),
        position: [0, 1, 2].map(|k| round(d.position[k], 4)),
        yaw_deg: round(d.yaw.to_degrees(), 2),
        affordances: d.affordances.clone(),
        score: round(d.score, 4),
        stability: round(d.stability, 4),
        availability: round(d.availability, 4),
        local_scores: named(&d.local_scores, 4),
        pose_deg: named(&d.pose, 2),
        joints: d
            .joints
            .iter()
            .map(|(k, p)| (k.clone(), [0, 1, 2].map(|i| round(p[i], 4))))
            .collect(),
        segment_points: d.segment_points,
    }
}

/// The affordance ids a file affords: those of any of its detections, or of the
/// detections of one body `(agent, height)` only.
pub fn affords<'a>(r: &'a FileReport, body: Option<(&str, f64)>) -> Vec<&'a String> {
    r.ids
        .iter()
        .filter(|id| {
            r.detections.iter().any(|d| {
                body.is_none_or(|(a, h)| d.agent == a && d.height == h)
                    && d.affordances.contains(id)
            })
        })
        .collect()
}

/// The version of the JSON document: 4 gives every joint angle of `pose_deg` in its
/// agent joint's own sign (a lying hip flexed 88 deg is +88, was -88 in 3); 3 added every
/// joint's world position (`joints`) to each detection; 2 had several bodies per file.
pub const JSON_VERSION: u32 = 4;

/// The JSON document of a run: `{"version": 4, "files": [...]}` ([`JSON_VERSION`]) with one
/// entry per input file, each with its runs (body and hierarchy) and its detections (each
/// naming its body, with its goal pose as angles and as joint positions).
pub fn to_json(reports: &[FileReport]) -> String {
    let doc = Document {
        version: JSON_VERSION,
        files: reports.iter().map(document_file).collect(),
    };
    let mut s = serde_json::to_string_pretty(&doc).unwrap_or_default();
    s.push('\n');
    s
}

/// The detections CSV:
/// `file,detection,hierarchy,x,y,z,yaw_deg,score,stability,affordances,segment_points,agent,height`.
pub fn to_csv(reports: &[FileReport]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "file",
        "detection",
        "hierarchy",
        "x",
        "y",
        "z",
        "yaw_deg",
        "score",
        "stability",
        "affordances",
        "segment_points",
        "agent",
        "height",
    ])?;
    for r in reports {
        for (i, d) in r.detections.iter().enumerate() {
            w.write_record([
                r.file.clone(),
                i.to_string(),
                d.hierarchy.clone(),
                format!("{:.4}", d.position.x),
                format!("{:.4}", d.position.y),
                format!("{:.4}", d.position.z),
                format!("{:.2}", d.yaw.to_degrees()),
                format!("{:.4}", d.score),
                format!("{:.4}", d.stability),
                d.affordances.join(";"),
                d.segment_points.to_string(),
                d.agent.clone(),
                format!("{:.3}", d.height),
            ])?;
        }
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| e.into_error())?).unwrap_or_default())
}

/// The summary CSV: `file`, one 0/1 column per affordance id (the shape of `labels.csv`),
/// then `agent,height`: one row per file and body.
pub fn to_summary(reports: &[FileReport]) -> Result<String, csv::Error> {
    let mut ids: Vec<&String> = Vec::new();
    for r in reports {
        for id in &r.ids {
            if !ids.contains(&id) {
                ids.push(id);
            }
        }
    }
    let mut w = csv::Writer::from_writer(Vec::new());
    let mut header = vec!["file".to_string()];
    header.extend(ids.iter().map(|s| s.to_string()));
    header.extend(["agent".to_string(), "height".to_string()]);
    w.write_record(&header)?;
    for r in reports {
        for body in r.bodies() {
            let found = affords(r, Some(body));
            let mut row = vec![r.file.clone()];
            row.extend(
                ids.iter()
                    .map(|id| if found.contains(id) { "1" } else { "0" }.to_string()),
            );
            row.extend([body.0.to_string(), format!("{:.3}", body.1)]);
            w.write_record(&row)?;
        }
    }
    Ok(String::from_utf8(w.into_inner().map_err(|e| e.into_error())?).unwrap_or_default())
}

/// A short table of the detections for a terminal.
pub fn to_table(r: &FileReport) -> String {
    let several = r.bodies().len() > 1;
    let mut s = format!(
        "{}: {} points, {} hypotheses, {} detections; affords: {}\n",
        r.file,
        r.points(),
        r.hypotheses(),
        r.detections.len(),
        match affords(r, None) {
            a if a.is_empty() => "nothing".to_string(),
            a => a.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", "),
        }
    );
    for (i, d) in r.detections.iter().enumerate() {
        let body = if several {
            format!("  [{} {:.2} m]", d.agent, d.height)
        } else {
            String::new()
        };
        s.push_str(&format!(
            "  #{i:<3} x {:>7.3}  y {:>7.3}  z {:>6.3}  yaw {:>6.1}  score {:.3}  stability {:.3}  {}{body}\n",
            d.position.x,
            d.position.y,
            d.position.z,
            d.yaw.to_degrees(),
            d.score,
            d.stability,
            d.affordances.join(", ")
        ));
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::set::ModelChoice;
    use nalgebra::Point3;

    /// A detection with every field empty or zero (only its place in the list matters).
    fn blank() -> Detection {
        Detection {
            hierarchy: String::new(),
            agent: String::new(),
            height: 0.0,
            position: Point3::origin(),
            yaw: 0.0,
            seat: Point3::origin(),
            affordances: Vec::new(),
            local_scores: Vec::new(),
            pose: Vec::new(),
            score: 0.0,
            stability: 0.0,
            availability: 0.0,
            segment_points: 0,
            parts: Vec::new(),
            joints: Vec::new(),
        }
    }

    fn outcome(detections: usize, labels: Vec<Option<usize>>) -> Outcome {
        Outcome {
            detections: vec![blank(); detections],
            labels,
            stats: Stats::default(),
        }
    }

    #[test]
    fn labels_merge_first_run_first_and_number_the_detections_run_after_run() {
        let models = ModelChoice::default().load().unwrap();
        assert_eq!(models.len(), 2);
        let first = vec![Some(0), None, None, Some(0)];
        let second = vec![Some(1), Some(0), None, Some(1)];
        let merged = |points: usize, first: Vec<Option<usize>>| {
            let outcomes = vec![outcome(1, first), outcome(2, second.clone())];
            FileReport::new("f".into(), points, 0, &models, outcomes).labels
        };
        // The first run's labels as they are; the second's numbered after its one
        // detection, where the first left a point unlabelled.
        assert_eq!(
            merged(4, first.clone()),
            vec![Some(0), Some(1), None, Some(0)]
        );
        // Labels shorter than the cloud: the rest unlabelled.
        assert_eq!(
            merged(5, first.clone()),
            vec![Some(0), Some(1), None, Some(0), None]
        );
        assert_eq!(merged(3, first), vec![Some(0), Some(1), None]);
        let none = FileReport::new("f".into(), 3, 0, &models, Vec::new());
        assert_eq!(none.labels, vec![None; 3]);
    }
}
