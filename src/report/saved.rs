//! Reading saved detect outputs back (JSON documents, summary CSV files, folders of them),
//! so that `afford eval` can score the outputs of several shards together.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::report::{Document, JSON_VERSION};

/// What went wrong reading a saved output.
#[derive(Debug, thiserror::Error)]
pub enum SavedError {
    /// A saved output could not be read.
    #[error("{path}: cannot read: {source}")]
    SavedIo {
        /// The saved output.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A saved output is not a detect JSON (version 2 to 4) or summary CSV.
    #[error("{path}: {what}")]
    Saved {
        /// The saved output.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

/// What a saved output says of one body on one file.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedBody {
    /// Agent name.
    pub agent: String,
    /// Body height, metres (as saved: three decimals).
    pub height: f64,
    /// Affordance ids found by a detection of this body.
    pub found: Vec<String>,
}

/// What saved outputs say of one input file.
#[derive(Debug, Clone, PartialEq)]
pub struct SavedFile {
    /// The input as named in the run that saved it.
    pub file: String,
    /// The saved output it was read from.
    pub source: PathBuf,
    /// Each body run on the file, in the saved order.
    pub bodies: Vec<SavedBody>,
}

impl SavedFile {
    /// The body `agent` at `height` (compared at the three decimals of the outputs).
    pub fn body(&self, agent: &str, height: f64) -> Option<&SavedBody> {
        let h = format!("{height:.3}");
        self.bodies
            .iter()
            .find(|b| b.agent == agent && format!("{:.3}", b.height) == h)
    }
}

/// Reads a detect JSON document (`--json` or one file of `--out-dir`, version 2 to
/// [`JSON_VERSION`]): the version first, so that another version is named as such rather
/// than as a missing field.
pub fn read_document(text: &str, path: &Path) -> Result<Document, SavedError> {
    #[derive(Deserialize)]
    struct Version {
        version: u32,
    }
    let bad = |what: String| SavedError::Saved {
        path: path.to_path_buf(),
        what,
    };
    let not_ours = |e: serde_json::Error| bad(format!("not an `afford detect` JSON output: {e}"));
    let v: Version = serde_json::from_str(text).map_err(not_ours)?;
    // Version 3 only added joint positions, which version 2 documents read as empty; 4
    // only turned the sign of lying hip angles, which are not read here.
    if !(2..=JSON_VERSION).contains(&v.version) {
        return Err(bad(format!(
            "JSON version {} (this afford reads versions 2 to {JSON_VERSION})",
            v.version
        )));
    }
    serde_json::from_str(text).map_err(not_ours)
}

/// Reads a detect JSON (`--json` or one file of `--out-dir`, version 2 to 4).
fn saved_json(text: &str, path: &Path) -> Result<Vec<SavedFile>, SavedError> {
    let doc = read_document(text, path)?;
    Ok(doc
        .files
        .into_iter()
        .map(|f| {
            let mut bodies: Vec<SavedBody> = Vec::new();
            for r in &f.runs {
                if !bodies
                    .iter()
                    .any(|b| b.agent == r.agent && b.height == r.height)
                {
                    bodies.push(SavedBody {
                        agent: r.agent.clone(),
                        height: r.height,
                        found: Vec::new(),
                    });
                }
            }
            for d in &f.detections {
                let body = bodies
                    .iter_mut()
                    .find(|b| b.agent == d.agent && b.height == d.height);
                if let Some(b) = body {
                    for id in &d.affordances {
                        if !b.found.contains(id) {
                            b.found.push(id.clone());
                        }
                    }
                }
            }
            SavedFile {
                file: f.file,
                source: path.to_path_buf(),
                bodies,
            }
        })
        .collect())
}

/// Reads a summary CSV (`--summary`): `file`, one 0/1 column per id, `agent`, `height`.
fn saved_summary(text: &str, path: &Path) -> Result<Vec<SavedFile>, SavedError> {
    let bad = |what: String| SavedError::Saved {
        path: path.to_path_buf(),
        what,
    };
    let mut rd = csv::Reader::from_reader(text.as_bytes());
    let headers = rd.headers().map_err(|e| bad(e.to_string()))?.clone();
    let col = |n: &str| headers.iter().position(|h| h == n);
    let (Some(fcol), Some(acol), Some(hcol)) = (col("file"), col("agent"), col("height")) else {
        return Err(bad(
            "not an `afford detect --summary` CSV (needs columns file, agent, height)".into(),
        ));
    };
    let mut out: Vec<SavedFile> = Vec::new();
    for (i, rec) in rd.records().enumerate() {
        let line = i + 2;
        let rec = rec.map_err(|e| bad(format!("line {line}: {e}")))?;
        let cell = |c: usize| rec.get(c).unwrap_or("");
        let height: f64 = cell(hcol)
            .parse()
            .map_err(|_| bad(format!("line {line}: height '{}'", cell(hcol))))?;
        let mut found = Vec::new();
        for (c, id) in headers.iter().enumerate() {
            if c == fcol || c == acol || c == hcol {
                continue;
            }
            match cell(c) {
                "1" => found.push(id.to_string()),
                "0" => {}
                v => {
                    return Err(bad(format!(
                        "line {line}: column '{id}': '{v}' is not 0 or 1"
                    )))
                }
            }
        }
        let body = SavedBody {
            agent: cell(acol).to_string(),
            height,
            found,
        };
        match out.iter_mut().find(|f| f.file == cell(fcol)) {
            Some(f) => f.bodies.push(body),
            None => out.push(SavedFile {
                file: cell(fcol).to_string(),
                source: path.to_path_buf(),
                bodies: vec![body],
            }),
        }
    }
    Ok(out)
}

/// Reads saved detect outputs: JSON files (`--json`, or the files of `--out-dir`), summary
/// CSV files (`--summary`, by the `.csv` extension), and folders, which stand for the
/// `.json` files in them (not recursive). A file saved in several of them is kept once
/// if they agree, and refused if they do not.
pub fn read_saved(paths: &[PathBuf]) -> Result<Vec<SavedFile>, SavedError> {
    let mut sources = Vec::new();
    for p in paths {
        if p.is_dir() {
            let found =
                crate::input::files_in(p, &["json"]).map_err(|source| SavedError::SavedIo {
                    path: p.clone(),
                    source,
                })?;
            sources.extend(found);
        } else {
            sources.push(p.clone());
        }
    }
    let mut out: Vec<SavedFile> = Vec::new();
    for s in &sources {
        let text = std::fs::read_to_string(s).map_err(|source| SavedError::SavedIo {
            path: s.clone(),
            source,
        })?;
        let csv = s.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"));
        let files = if csv {
            saved_summary(&text, s)?
        } else {
            saved_json(&text, s)?
        };
        for f in files {
            match out.iter().find(|o| o.file == f.file) {
                Some(o) if o.bodies == f.bodies => {}
                Some(o) => {
                    return Err(SavedError::Saved {
                        path: s.clone(),
                        what: format!(
                            "{} is also in {}, with other detections",
                            f.file,
                            o.source.display()
                        ),
                    })
                }
                None => out.push(f),
            }
        }
    }
    Ok(out)
}

/// The saved file that is the labelled file `file` (as written in a labels CSV) at
/// `path` (resolved against the CSV): the one whose path ends with the components of
/// `file`; among several, the one that is the same file on disk. `Err` says why none.
pub fn find_saved<'a>(
    saved: &'a [SavedFile],
    file: &str,
    path: &Path,
) -> Result<&'a SavedFile, String> {
    let hits: Vec<&SavedFile> = saved
        .iter()
        .filter(|s| Path::new(&s.file).ends_with(file))
        .collect();
    match hits[..] {
        [] => Err("not in the saved outputs".to_string()),
        [one] => Ok(one),
        _ => {
            let same = |s: &&SavedFile| {
                let a = std::fs::canonicalize(&s.file);
                a.is_ok() && a.ok() == std::fs::canonicalize(path).ok()
            };
            let exact: Vec<&SavedFile> = hits.iter().copied().filter(same).collect();
            match exact[..] {
                [one] => Ok(one),
                _ => Err(format!(
                    "saved under several names: {}",
                    hits.iter()
                        .map(|s| s.file.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_summary_and_a_json_of_the_same_run_read_alike() {
        // A version 2 document: no `joints`.
        let json = r#"{"version": 2, "files": [{"file": "d/a.ply", "points": 3,
            "dropped_non_finite": 0, "affordances": ["sitting"],
            "runs": [{"agent": "human", "height": 1.65, "hierarchy": "sitting",
                      "hypotheses": 1, "fits": 0, "candidates": 0},
                     {"agent": "human", "height": 1.75, "hierarchy": "sitting",
                      "hypotheses": 1, "fits": 1, "candidates": 1}],
            "detections": [{"detection": 0, "hierarchy": "sitting", "agent": "human",
                            "height": 1.75, "position": [0, 0, 0.5], "yaw_deg": 0,
                            "affordances": ["sitting", "backrest"], "score": 1,
                            "stability": 1, "availability": 1, "local_scores": {},
                            "pose_deg": {}, "segment_points": 3}]}]}"#;
        let summary = "file,sitting,backrest,agent,height\n\
                       d/a.ply,0,0,human,1.650\nd/a.ply,1,1,human,1.750\n";
        let a = saved_json(json, Path::new("x.json")).unwrap();
        let b = saved_summary(summary, Path::new("x.csv")).unwrap();
        assert_eq!(a[0].bodies, b[0].bodies);
        assert_eq!(a[0].body("human", 1.75).unwrap().found.len(), 2);
        assert!(a[0].body("human", 1.85).is_none());
        assert!(
            saved_json(r#"{"version": 1, "files": []}"#, Path::new("x.json"))
                .unwrap_err()
                .to_string()
                .contains("version 1")
        );
    }

    #[test]
    fn the_reader_reads_what_the_writer_writes() {
        let text = crate::report::to_json(&[]);
        let doc = read_document(&text, Path::new("x.json")).unwrap();
        assert_eq!(doc.version, JSON_VERSION);
        // A written document with one detection reads back equal, joints included.
        let json = r#"{"version": 3, "files": [{"file": "a.ply", "points": 1,
            "dropped_non_finite": 0, "affordances": ["sitting"],
            "runs": [{"agent": "human", "height": 1.75, "hierarchy": "sitting",
                      "hypotheses": 1, "fits": 1, "candidates": 1}],
            "detections": [{"detection": 0, "hierarchy": "sitting", "agent": "human",
                            "height": 1.75, "position": [0, 0, 0.5], "yaw_deg": 90,
                            "affordances": ["sitting"], "score": 1, "stability": 1,
                            "availability": 1, "local_scores": {"sitting": 1},
                            "pose_deg": {"hip_l": 90}, "joints": {"pelvis": [0, 0, 0.5]},
                            "segment_points": 1}]}]}"#;
        let doc = read_document(json, Path::new("x.json")).unwrap();
        let again = serde_json::to_string(&doc).unwrap();
        assert_eq!(read_document(&again, Path::new("y.json")).unwrap(), doc);
        assert_eq!(doc.files[0].detections[0].joints["pelvis"], [0.0, 0.0, 0.5]);
        // A document of another version is named by its version, not a missing field.
        let e = read_document(r#"{"version": 5}"#, Path::new("z.json")).unwrap_err();
        assert!(e.to_string().contains("JSON version 5"), "{e}");
    }

    #[test]
    fn a_labelled_file_is_found_by_its_trailing_components() {
        let s = |f: &str| SavedFile {
            file: f.to_string(),
            source: PathBuf::from("s.json"),
            bodies: Vec::new(),
        };
        let saved = [s("/scratch/set/views/a.ply"), s("/scratch/set/a.ply")];
        let p = Path::new("x");
        assert_eq!(
            find_saved(&saved, "views/a.ply", p).unwrap().file,
            "/scratch/set/views/a.ply"
        );
        assert!(find_saved(&saved, "a.ply", p)
            .unwrap_err()
            .contains("several"));
        assert!(find_saved(&saved, "b.ply", p).is_err());
    }
}
