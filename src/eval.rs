//! Evaluation against a `labels.csv` (docs/formats.md, "Outputs"): runs
//! detection on every labelled file at one or more body heights and scores the scene-level
//! answers (a file affords F when any detection does) per affordance id, as in Table 1 of
//! the paper (F-score, precision, recall per affordance and body height).
//!
//! Scored ids are those that have a column in the labels and that the hierarchy knows.
//! A cell that is empty is not scored for that file. Rows whose `doubtful` column is
//! non-empty are left out of the main table and scored apart. Files that cannot be read
//! are counted and listed, not fatal.
//!
//! [`evaluate_saved`] scores saved `afford detect` outputs instead (for example those of
//! several shards of one dataset), with the same scores as running detection.
//!
//! Undefined ratios: precision is `None` when nothing was predicted positive
//! (`tp + fp = 0`), recall is `None` when there is no positive label (`tp + fn = 0`), and
//! the F-score `2 tp / (2 tp + fp + fn)` is `None` only when both are (no positive label,
//! no positive prediction: nothing to score). `None` prints as `n/a` in markdown, `null` in
//! JSON and an empty cell in CSV.
//!
//! Segmentation: for PLY files with a per-point `part` property (synthetic data), the
//! points labelled to a detection are compared with the points whose part is seat,
//! backrest, armrest, headrest or lying surface (codes 1–5); the IoU is averaged over
//! files whose `sitting` (or `lying`) label is 1 and that have such points.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Serialize;

use crate::cloud;
use crate::detect::{detect_input, DetectConfig};
use crate::input::InputOptions;
use crate::model::set::{ids as ids_of, load_set, Model, ModelChoice};
use crate::model::ModelError;
use crate::report::{self, FileReport};

/// What went wrong before any file could be scored.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// The labels file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The labels file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The labels file is malformed.
    #[error("{path}: {what}")]
    Labels {
        /// The labels file.
        path: PathBuf,
        /// What is wrong (with the line).
        what: String,
    },
    /// The agent or hierarchy could not be loaded.
    #[error(transparent)]
    Model(#[from] ModelError),
    /// Saved detect outputs (`--from`) could not be read.
    #[error(transparent)]
    Saved(#[from] crate::report::saved::SavedError),
}

/// One row of a labels file.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LabelRow {
    /// The `file` cell as written (relative to the CSV).
    pub file: String,
    /// The file resolved against the CSV's directory.
    pub path: PathBuf,
    /// Label per affordance column present and non-empty in this row.
    pub labels: BTreeMap<String, bool>,
    /// The `doubtful` cell if non-empty.
    pub doubtful: Option<String>,
}

/// Parses labels CSV text. `ids` are the affordance ids to read (columns of other names
/// are ignored; an id without a column is not scored). Cells must be `0` or `1` (or
/// empty: not scored for that row). `base` is the directory files are relative to.
/// Returns the rows and the ids that have a column, in `ids` order.
pub fn parse_labels(
    text: &str,
    ids: &[&str],
    base: &Path,
) -> Result<(Vec<LabelRow>, Vec<String>), String> {
    let mut rd = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    let headers = rd.headers().map_err(|e| e.to_string())?.clone();
    let col = |n: &str| headers.iter().position(|h| h.trim() == n);
    let fcol = col("file").ok_or("no 'file' column")?;
    let dcol = col("doubtful");
    let cols: Vec<(String, usize)> = ids
        .iter()
        .filter_map(|id| col(id).map(|c| (id.to_string(), c)))
        .collect();
    let mut rows = Vec::new();
    for (i, rec) in rd.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| format!("line {line}: {e}"))?;
        let file = rec.get(fcol).unwrap_or("").trim();
        if file.is_empty() {
            return Err(format!("line {line}: empty 'file'"));
        }
        let mut labels = BTreeMap::new();
        for (id, c) in &cols {
            match rec.get(*c).map(str::trim).unwrap_or("") {
                "" => {}
                "1" | "true" => {
                    labels.insert(id.clone(), true);
                }
                "0" | "false" => {
                    labels.insert(id.clone(), false);
                }
                v => return Err(format!("line {line}: column '{id}': '{v}' is not 0 or 1")),
            }
        }
        let doubtful = dcol
            .and_then(|c| rec.get(c))
            .map(str::trim)
            .filter(|s| !s.is_empty())
            .map(String::from);
        rows.push(LabelRow {
            file: file.to_string(),
            path: base.join(file),
            labels,
            doubtful,
        });
    }
    Ok((rows, cols.into_iter().map(|(id, _)| id).collect()))
}

/// Confusion counts of one affordance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Counts {
    /// Labelled 1, found.
    pub tp: usize,
    /// Labelled 0, found.
    pub fp: usize,
    /// Labelled 1, not found.
    #[serde(rename = "fn")]
    pub fn_: usize,
    /// Labelled 0, not found.
    pub tn: usize,
}

impl Counts {
    /// Adds one scored file.
    pub fn add(&mut self, label: bool, found: bool) {
        match (label, found) {
            (true, true) => self.tp += 1,
            (false, true) => self.fp += 1,
            (true, false) => self.fn_ += 1,
            (false, false) => self.tn += 1,
        }
    }

    /// `tp / (tp + fp)`, `None` when nothing was predicted positive.
    pub fn precision(&self) -> Option<f64> {
        let d = self.tp + self.fp;
        (d > 0).then(|| self.tp as f64 / d as f64)
    }

    /// `tp / (tp + fn)`, `None` when there is no positive label.
    pub fn recall(&self) -> Option<f64> {
        let d = self.tp + self.fn_;
        (d > 0).then(|| self.tp as f64 / d as f64)
    }

    /// `2 tp / (2 tp + fp + fn)` (the harmonic mean of P and R where both exist; 0 when
    /// one is undefined and the other 0), `None` when there is nothing to score.
    pub fn f_score(&self) -> Option<f64> {
        let d = 2 * self.tp + self.fp + self.fn_;
        (d > 0).then(|| 2.0 * self.tp as f64 / d as f64)
    }
}

/// Scores of one affordance at one height.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Score {
    /// Affordance id.
    pub id: String,
    /// Confusion counts.
    pub counts: Counts,
    /// Precision (see the module documentation for `None`).
    pub precision: Option<f64>,
    /// Recall.
    pub recall: Option<f64>,
    /// F-score.
    pub f: Option<f64>,
}

impl Score {
    fn new(id: &str, counts: Counts) -> Self {
        Self {
            id: id.to_string(),
            precision: counts.precision(),
            recall: counts.recall(),
            f: counts.f_score(),
            counts,
        }
    }
}

/// A file whose answer differs from its labels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Mistake {
    /// The file as in the labels.
    pub file: String,
    /// Ids found but labelled 0.
    pub false_positives: Vec<String>,
    /// Ids labelled 1 but not found.
    pub false_negatives: Vec<String>,
}

/// Results of one body: an agent at one height.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct HeightResult {
    /// The agent's name (its file's `name`).
    pub agent: String,
    /// Body height, metres.
    pub height: f64,
    /// Scores over the non-doubtful rows, in id order.
    pub scores: Vec<Score>,
    /// Scores over the doubtful rows alone.
    pub doubtful_scores: Vec<Score>,
    /// Non-doubtful files with a wrong answer.
    pub mistakes: Vec<Mistake>,
    /// Doubtful files and what was found in them.
    pub doubtful_found: Vec<(String, Vec<String>)>,
    /// Mean IoU of the segmentation over positive files with a `part` property.
    pub mean_iou: Option<f64>,
    /// Number of files in `mean_iou`.
    pub iou_files: usize,
}

/// The whole evaluation.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Evaluation {
    /// The labels file.
    pub labels: String,
    /// Scored affordance ids (label column present and known to the hierarchy).
    pub ids: Vec<String>,
    /// Rows scored in the main table.
    pub files: usize,
    /// Doubtful rows.
    pub doubtful_files: usize,
    /// Files that could not be read, with the error.
    pub failed: Vec<(String, String)>,
    /// One entry per body, in the order asked: each agent at every height.
    pub heights: Vec<HeightResult>,
    /// Scored from saved `afford detect` outputs ([`evaluate_saved`]) rather than by
    /// running detection; they hold no per-point labels, so there is no segmentation IoU.
    pub from_saved: bool,
}

fn fmt(x: Option<f64>) -> String {
    x.map_or_else(|| "n/a".to_string(), |v| format!("{v:.2}"))
}

impl Evaluation {
    /// Whether the bodies are of more than one agent.
    fn several_agents(&self) -> bool {
        self.heights
            .iter()
            .any(|h| h.agent != self.heights[0].agent)
    }

    /// How a body is named in the report: its height, with the agent's name before it
    /// when several agents were scored (`child 1.20 m`).
    fn body(&self, h: &HeightResult) -> String {
        if self.several_agents() {
            format!("{} {:.2} m", h.agent, h.height)
        } else {
            format!("{:.2} m", h.height)
        }
    }

    /// A markdown report: the main table in the shape of the paper's Table 1 (rows =
    /// affordance, column groups = body height with F, P, R), then the doubtful rows, the
    /// segmentation IoU and the failed files.
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        let table = |s: &mut String, pick: &dyn Fn(&HeightResult) -> &Vec<Score>| {
            s.push_str("| affordance |");
            for h in &self.heights {
                let b = self.body(h);
                s.push_str(&format!(" F {b} | P {b} | R {b} |"));
            }
            s.push_str("\n|---|");
            for _ in &self.heights {
                s.push_str("---:|---:|---:|");
            }
            s.push('\n');
            for (k, id) in self.ids.iter().enumerate() {
                s.push_str(&format!("| {id} |"));
                for h in &self.heights {
                    let sc = &pick(h)[k];
                    s.push_str(&format!(
                        " {} | {} | {} |",
                        fmt(sc.f),
                        fmt(sc.precision),
                        fmt(sc.recall)
                    ));
                }
                s.push('\n');
            }
        };
        s.push_str(&format!(
            "Evaluation of {}: {} files scored, {} doubtful, {} failed.\n\n",
            self.labels,
            self.files,
            self.doubtful_files,
            self.failed.len()
        ));
        table(&mut s, &|h| &h.scores);
        if self.doubtful_files > 0 {
            s.push_str("\nDoubtful rows (labels by convention), apart:\n\n");
            table(&mut s, &|h| &h.doubtful_scores);
        }
        if self.from_saved {
            s.push_str(
                "\nSegmentation: not scored (saved detections hold no per-point labels; \
                 run `afford eval` without --from for it).\n",
            );
        } else {
            s.push_str("\nSegmentation (mean IoU over positive files with a `part` property):\n\n");
        }
        for h in self.heights.iter().filter(|_| !self.from_saved) {
            s.push_str(&format!(
                "- {}: {} over {} files\n",
                self.body(h),
                fmt(h.mean_iou),
                h.iou_files
            ));
        }
        for h in &self.heights {
            if h.mistakes.is_empty() {
                continue;
            }
            s.push_str(&format!(
                "\nWrong files at {} (false positives / false negatives):\n\n",
                self.body(h)
            ));
            for m in &h.mistakes {
                let list = |v: &Vec<String>| {
                    if v.is_empty() {
                        "-".to_string()
                    } else {
                        v.join(", ")
                    }
                };
                s.push_str(&format!(
                    "- {}: FP {}; FN {}\n",
                    m.file,
                    list(&m.false_positives),
                    list(&m.false_negatives)
                ));
            }
        }
        for h in &self.heights {
            let found: Vec<String> = h
                .doubtful_found
                .iter()
                .filter(|(_, f)| !f.is_empty())
                .map(|(file, f)| format!("{file} ({})", f.join(", ")))
                .collect();
            if !found.is_empty() {
                s.push_str(&format!(
                    "\nDoubtful files with affordances found at {}: {}\n",
                    self.body(h),
                    found.join("; ")
                ));
            }
        }
        if !self.failed.is_empty() {
            s.push_str("\nFailed files:\n\n");
            for (f, e) in &self.failed {
                s.push_str(&format!("- {f}: {e}\n"));
            }
        }
        s
    }

    /// The evaluation as pretty JSON (every field, including the mistakes per file).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_else(|_| "{}".into())
    }

    /// One CSV row per body, set (`main` or `doubtful`) and affordance:
    /// `height,set,affordance,tp,fp,fn,tn,precision,recall,f` (empty cell = undefined),
    /// with a first column `agent` when several agents were scored.
    pub fn to_csv(&self) -> String {
        let o = |x: Option<f64>| x.map_or_else(String::new, |v| format!("{v:.4}"));
        let several = self.several_agents();
        let mut s = String::from(if several { "agent," } else { "" });
        s.push_str("height,set,affordance,tp,fp,fn,tn,precision,recall,f\n");
        for h in &self.heights {
            for (set, scores) in [("main", &h.scores), ("doubtful", &h.doubtful_scores)] {
                for sc in scores {
                    let c = sc.counts;
                    if several {
                        s.push_str(&h.agent);
                        s.push(',');
                    }
                    s.push_str(&format!(
                        "{:.3},{set},{},{},{},{},{},{},{},{}\n",
                        h.height,
                        sc.id,
                        c.tp,
                        c.fp,
                        c.fn_,
                        c.tn,
                        o(sc.precision),
                        o(sc.recall),
                        o(sc.f)
                    ));
                }
            }
        }
        s
    }
}

/// Intersection over union of two point sets given as masks; `None` if both are empty.
pub fn iou(a: &[bool], b: &[bool]) -> Option<f64> {
    let (mut i, mut u) = (0usize, 0usize);
    for (&x, &y) in a.iter().zip(b) {
        i += usize::from(x && y);
        u += usize::from(x || y);
    }
    (u > 0).then(|| i as f64 / u as f64)
}

/// What one file gave at every height: found ids and segmentation IoU.
type FileOutcome = Result<Vec<(Vec<String>, Option<f64>)>, String>;

/// What an evaluation scores against: the models (one set per body, each agent at every
/// height), the label rows, the ids of the hierarchies and the scored ids (those with a
/// label column).
struct Setup {
    models: Vec<Vec<Model>>,
    rows: Vec<LabelRow>,
    hier_ids: Vec<String>,
    ids: Vec<String>,
}

impl Setup {
    /// The bodies, `(agent name, height)`, one per model set.
    fn bodies(&self) -> Vec<(String, f64)> {
        self.models
            .iter()
            .filter_map(|set| set.first())
            .map(|m| (m.agent.name.clone(), m.agent.height))
            .collect()
    }
}

/// Loads the models of every body and reads the labels.
fn setup(labels_csv: &Path, choice: &ModelChoice) -> Result<Setup, EvalError> {
    let (agents, hierarchies) = choice.sources()?;
    let heights = choice.heights();
    let models = agents
        .iter()
        .flat_map(|a| heights.iter().map(move |&h| (a, h)))
        .map(|(a, h)| load_set(std::slice::from_ref(a), &hierarchies, &[h]))
        .collect::<Result<Vec<_>, _>>()?;
    let text = std::fs::read_to_string(labels_csv).map_err(|source| EvalError::Io {
        path: labels_csv.to_path_buf(),
        source,
    })?;
    let hier_ids: Vec<String> = models.first().map(|m| ids_of(m)).unwrap_or_default();
    let id_refs: Vec<&str> = hier_ids.iter().map(String::as_str).collect();
    let base = labels_csv.parent().unwrap_or(Path::new("."));
    let (rows, ids) = parse_labels(&text, &id_refs, base).map_err(|what| EvalError::Labels {
        path: labels_csv.to_path_buf(),
        what,
    })?;
    Ok(Setup {
        models,
        rows,
        hier_ids,
        ids,
    })
}

/// Runs detection on every file of `labels_csv` (paths relative to it) with every body of
/// `models` (each agent at each height, with every hierarchy), reading the files as
/// `input` says and building the scene as `cfg` says, and scores the answers (see the module
/// documentation). Each file goes through the per-file path of `afford detect`
/// ([`crate::input::load_input`], then [`detect_input`] with every body at once), so a file
/// affords here what `afford detect` finds in it with the same flags; a file the extent
/// guard refuses counts as failed. Files run in parallel (rayon); `progress` shows a
/// progress bar on stderr.
pub fn evaluate(
    labels_csv: &Path,
    models: &ModelChoice,
    cfg: &DetectConfig,
    input: &InputOptions,
    progress: bool,
) -> Result<Evaluation, EvalError> {
    let setup = setup(labels_csv, models)?;
    let bodies = setup.bodies();
    let Setup {
        models, rows, ids, ..
    } = setup;
    let all: Vec<Model> = models.iter().flatten().cloned().collect();
    let bar = if progress {
        indicatif::ProgressBar::new(rows.len() as u64)
    } else {
        indicatif::ProgressBar::hidden()
    };
    let outcomes: Vec<FileOutcome> = rows
        .par_iter()
        .map(|row| {
            let loaded = crate::input::load_input(&row.path, input).map_err(|e| e.to_string());
            let parts = if row
                .path
                .extension()
                .is_some_and(|e| e.eq_ignore_ascii_case("ply"))
            {
                cloud::read_ply_property(&row.path, "part").ok().flatten()
            } else {
                None
            };
            let out = loaded.and_then(|loaded| {
                // Part labels only line up with the points if nothing was dropped.
                let target: Option<Vec<bool>> =
                    parts.filter(|p| p.len() == loaded.cloud.len()).map(|p| {
                        p.iter()
                            .map(|&c| crate::mesh::is_body_part_code(c))
                            .collect()
                    });
                // The path of `afford detect` on this file with every body at once; the
                // outcomes come back in model order, one set (body) after the other.
                let mut outcomes = detect_input(&row.path, &loaded.cloud, &all, cfg)
                    .map_err(|e| e.to_string())?
                    .into_iter();
                Ok(models
                    .iter()
                    .map(|set| {
                        let outcomes = outcomes.by_ref().take(set.len()).collect();
                        let r = FileReport::new(
                            row.file.clone(),
                            loaded.cloud.len(),
                            loaded.dropped_non_finite,
                            set,
                            outcomes,
                        );
                        let found: Vec<String> =
                            report::affords(&r, None).into_iter().cloned().collect();
                        let positive = ["sitting", "lying"]
                            .iter()
                            .any(|id| row.labels.get(*id) == Some(&true));
                        let seg = target
                            .as_ref()
                            .filter(|t| positive && t.contains(&true))
                            .and_then(|t| {
                                let s: Vec<bool> = r.labels.iter().map(Option::is_some).collect();
                                iou(&s, t)
                            });
                        (found, seg)
                    })
                    .collect())
            });
            bar.inc(1);
            out
        })
        .collect();
    bar.finish_and_clear();
    Ok(score(labels_csv, &bodies, &ids, &rows, &outcomes))
}

/// Scores saved `afford detect` outputs (`--json` files, `--summary` CSV files, `--out-dir`
/// folders: see [`crate::report::saved::read_saved`]) against `labels_csv`, as [`evaluate`] would
/// score running detection with the same models, without the segmentation IoU. A labelled
/// file is matched to the saved file whose path ends with its `file` cell; a labelled file
/// not saved, or saved without a run of one of the bodies of `models`, counts as failed.
pub fn evaluate_saved(
    labels_csv: &Path,
    models: &ModelChoice,
    saved: &[PathBuf],
) -> Result<Evaluation, EvalError> {
    let setup = setup(labels_csv, models)?;
    let bodies = setup.bodies();
    let Setup {
        rows,
        hier_ids,
        ids,
        ..
    } = setup;
    let saved = crate::report::saved::read_saved(saved)?;
    let outcomes: Vec<FileOutcome> = rows
        .iter()
        .map(|row| {
            let s = crate::report::saved::find_saved(&saved, &row.file, &row.path)?;
            bodies
                .iter()
                .map(|(agent, h)| {
                    let body = s.body(agent, *h).ok_or_else(|| {
                        format!(
                            "{}: no saved run of {agent} at {h:.3} m",
                            s.source.display()
                        )
                    })?;
                    // In hierarchy order, as detection reports them.
                    let found = hier_ids
                        .iter()
                        .filter(|id| body.found.contains(id))
                        .cloned()
                        .collect();
                    Ok((found, None))
                })
                .collect()
        })
        .collect();
    let mut ev = score(labels_csv, &bodies, &ids, &rows, &outcomes);
    ev.from_saved = true;
    Ok(ev)
}

/// Scores the outcomes of `rows` (one entry per row, one element per body).
fn score(
    labels_csv: &Path,
    bodies: &[(String, f64)],
    ids: &[String],
    rows: &[LabelRow],
    outcomes: &[FileOutcome],
) -> Evaluation {
    let mut failed = Vec::new();
    for (row, o) in rows.iter().zip(outcomes) {
        if let Err(e) = o {
            failed.push((row.file.clone(), e.clone()));
        }
    }
    let ok = |o: &FileOutcome| o.is_ok();
    let files = rows
        .iter()
        .zip(outcomes)
        .filter(|(r, o)| r.doubtful.is_none() && ok(o))
        .count();
    let doubtful_files = rows
        .iter()
        .zip(outcomes)
        .filter(|(r, o)| r.doubtful.is_some() && ok(o))
        .count();
    let heights = bodies
        .iter()
        .enumerate()
        .map(|(k, (agent, height))| {
            let mut main = vec![Counts::default(); ids.len()];
            let mut doubt = vec![Counts::default(); ids.len()];
            let mut mistakes = Vec::new();
            let mut doubtful_found = Vec::new();
            let mut ious = Vec::new();
            for (row, o) in rows.iter().zip(outcomes) {
                let Ok(per_height) = o else { continue };
                let (found, seg) = &per_height[k];
                let counts = if row.doubtful.is_some() {
                    doubtful_found.push((row.file.clone(), found.clone()));
                    &mut doubt
                } else {
                    &mut main
                };
                let mut m = Mistake {
                    file: row.file.clone(),
                    false_positives: Vec::new(),
                    false_negatives: Vec::new(),
                };
                for (i, id) in ids.iter().enumerate() {
                    let Some(&label) = row.labels.get(id) else {
                        continue;
                    };
                    let got = found.contains(id);
                    counts[i].add(label, got);
                    if got && !label {
                        m.false_positives.push(id.clone());
                    } else if label && !got {
                        m.false_negatives.push(id.clone());
                    }
                }
                if row.doubtful.is_none()
                    && !(m.false_positives.is_empty() && m.false_negatives.is_empty())
                {
                    mistakes.push(m);
                }
                if let Some(v) = seg {
                    ious.push(*v);
                }
            }
            HeightResult {
                agent: agent.clone(),
                height: *height,
                scores: ids
                    .iter()
                    .zip(main)
                    .map(|(id, c)| Score::new(id, c))
                    .collect(),
                doubtful_scores: ids
                    .iter()
                    .zip(doubt)
                    .map(|(id, c)| Score::new(id, c))
                    .collect(),
                mistakes,
                doubtful_found,
                mean_iou: (!ious.is_empty()).then(|| ious.iter().sum::<f64>() / ious.len() as f64),
                iou_files: ious.len(),
            }
        })
        .collect();
    Evaluation {
        labels: labels_csv.display().to_string(),
        ids: ids.to_vec(),
        files,
        doubtful_files,
        failed,
        heights,
        from_saved: false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn c(tp: usize, fp: usize, fn_: usize, tn: usize) -> Counts {
        Counts { tp, fp, fn_, tn }
    }

    #[test]
    fn precision_recall_f_by_hand() {
        // 8 tp, 2 fp, 4 fn: P = 0.8, R = 8/12, F = 16/22.
        let k = c(8, 2, 4, 5);
        assert_eq!(k.precision(), Some(0.8));
        assert!((k.recall().unwrap() - 2.0 / 3.0).abs() < 1e-12);
        assert!((k.f_score().unwrap() - 16.0 / 22.0).abs() < 1e-12);
        // F is the harmonic mean of P and R.
        let (p, r) = (k.precision().unwrap(), k.recall().unwrap());
        assert!((k.f_score().unwrap() - 2.0 * p * r / (p + r)).abs() < 1e-12);
        // Perfect.
        assert_eq!(c(3, 0, 0, 7).f_score(), Some(1.0));
    }

    #[test]
    fn zero_over_zero_cases() {
        // Nothing predicted, positives missed: P undefined, R = 0, F = 0.
        let k = c(0, 0, 5, 3);
        assert_eq!(
            (k.precision(), k.recall(), k.f_score()),
            (None, Some(0.0), Some(0.0))
        );
        // No positive label, false alarms: P = 0, R undefined, F = 0.
        let k = c(0, 2, 0, 3);
        assert_eq!(
            (k.precision(), k.recall(), k.f_score()),
            (Some(0.0), None, Some(0.0))
        );
        // Only true negatives: nothing to score.
        let k = c(0, 0, 0, 9);
        assert_eq!((k.precision(), k.recall(), k.f_score()), (None, None, None));
        assert_eq!(Counts::default().f_score(), None);
    }

    #[test]
    fn counts_add_all_four_cells() {
        let mut k = Counts::default();
        for (l, f) in [
            (true, true),
            (true, false),
            (false, true),
            (false, false),
            (true, true),
        ] {
            k.add(l, f);
        }
        assert_eq!(k, c(2, 1, 1, 1));
    }

    #[test]
    fn labels_parsing_ignores_extra_columns_and_skips_missing_ones() {
        let text = "file,class,sitting,backrest,width_m,doubtful\n\
                    a.ply,chair,1,1,0.4,\n\
                    sub/b.pcd,table,0,,1.2,\"low, by convention\"\n";
        let ids = ["sitting", "backrest", "armrest", "headrest"];
        let (rows, cols) = parse_labels(text, &ids, Path::new("/d")).unwrap();
        assert_eq!(cols, vec!["sitting", "backrest"]);
        assert_eq!(rows.len(), 2);
        assert_eq!(rows[0].path, Path::new("/d/a.ply"));
        assert_eq!(rows[0].labels.get("sitting"), Some(&true));
        assert_eq!(rows[0].labels.get("backrest"), Some(&true));
        assert_eq!(rows[0].labels.get("armrest"), None);
        assert_eq!(rows[0].doubtful, None);
        assert_eq!(rows[1].file, "sub/b.pcd");
        assert_eq!(rows[1].labels.get("sitting"), Some(&false));
        assert_eq!(rows[1].labels.get("backrest"), None); // empty cell: not scored
        assert_eq!(rows[1].doubtful.as_deref(), Some("low, by convention"));
        assert!(
            parse_labels("file,sitting\nx.ply,2\n", &ids, Path::new("."))
                .unwrap_err()
                .contains("line 2")
        );
        assert!(parse_labels("name,sitting\nx.ply,1\n", &ids, Path::new(".")).is_err());
    }

    #[test]
    fn scoring_separates_doubtful_rows_and_lists_mistakes() {
        let text = "file,sitting,backrest,doubtful\n\
                    a.ply,1,1,\nb.ply,0,0,\nc.ply,1,0,\nd.ply,0,0,low table\ne.ply,1,1,\n";
        let ids = ["sitting", "backrest"];
        let (rows, cols) = parse_labels(text, &ids, Path::new(".")).unwrap();
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        let outcomes: Vec<FileOutcome> = vec![
            Ok(vec![(s(&["sitting", "backrest"]), Some(0.5))]),
            Ok(vec![(s(&["sitting"]), None)]),
            Ok(vec![(s(&["sitting", "backrest"]), Some(1.0))]),
            Ok(vec![(s(&["sitting"]), None)]),
            Err("cannot read".into()),
        ];
        let e = score(
            Path::new("l.csv"),
            &[("human".into(), 1.75)],
            &cols,
            &rows,
            &outcomes,
        );
        assert_eq!((e.files, e.doubtful_files, e.failed.len()), (3, 1, 1));
        let h = &e.heights[0];
        assert_eq!(h.scores[0].counts, c(2, 1, 0, 0));
        assert_eq!(h.scores[1].counts, c(1, 1, 0, 1));
        assert_eq!(h.doubtful_scores[0].counts, c(0, 1, 0, 0));
        assert_eq!(h.mean_iou, Some(0.75));
        assert_eq!(h.mistakes.len(), 2);
        assert_eq!(h.mistakes[0].file, "b.ply");
        assert_eq!(h.mistakes[1].false_positives, vec!["backrest"]);
        let md = e.markdown();
        assert!(md.contains("| sitting | 0.80 | 0.67 | 1.00 |"), "{md}");
        assert!(e
            .to_csv()
            .contains("1.750,main,backrest,1,1,0,1,0.5000,1.0000,0.6667"));
        assert!(e.to_json().contains("\"fn\": 0"));
        assert!(md.contains(" F 1.75 m |"), "{md}");
    }

    #[test]
    fn several_agents_are_scored_and_named_apart() {
        let text = "file,sitting\na.ply,1\nb.ply,0\n";
        let (rows, cols) = parse_labels(text, &["sitting"], Path::new(".")).unwrap();
        let s = |v: &[&str]| v.iter().map(|x| x.to_string()).collect::<Vec<_>>();
        // The adult finds sitting on both files, the child on neither.
        let outcomes: Vec<FileOutcome> = vec![
            Ok(vec![(s(&["sitting"]), None), (s(&[]), None)]),
            Ok(vec![(s(&["sitting"]), None), (s(&[]), None)]),
        ];
        let bodies = [("human".to_string(), 1.75), ("child".to_string(), 1.2)];
        let e = score(Path::new("l.csv"), &bodies, &cols, &rows, &outcomes);
        assert_eq!(e.heights[0].scores[0].counts, c(1, 1, 0, 0));
        assert_eq!(e.heights[1].scores[0].counts, c(0, 0, 1, 1));
        assert_eq!(e.heights[1].agent, "child");
        let md = e.markdown();
        assert!(md.contains(" F child 1.20 m |"), "{md}");
        let csv = e.to_csv();
        assert!(csv.starts_with("agent,height,set,"), "{csv}");
        assert!(csv.contains("\nchild,1.200,main,sitting,0,0,1,1,"), "{csv}");
    }

    #[test]
    fn iou_of_masks() {
        assert_eq!(
            iou(&[true, true, false, false], &[true, false, true, false]),
            Some(1.0 / 3.0)
        );
        assert_eq!(iou(&[false, false], &[false, false]), None);
    }
}
