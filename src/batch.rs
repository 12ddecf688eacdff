//! Batch runs over many files: input lists, deterministic shards, per-file outputs that a
//! later run can resume from, the JSON log line per file, and reading saved outputs back
//! (so that `afford eval` can score the outputs of several shards together).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::report::{Document, JSON_VERSION};

/// What went wrong with a list, a shard, an output folder or a saved output.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A folder given as input could not be listed.
    #[error(transparent)]
    Input(#[from] crate::cloud::CloudError),
    /// A list file (or standard input) could not be read.
    #[error("{path}: cannot read the list: {source}")]
    List {
        /// The list file (`-` for standard input).
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A line of a list file is not text.
    #[error("{path}: line {line}: not UTF-8 text")]
    ListLine {
        /// The list file (`-` for standard input).
        path: PathBuf,
        /// The line, from 1.
        line: usize,
    },
    /// A folder given as input holds no cloud or mesh file.
    #[error("{path}: no .ply, .pcd, .xyz, .obj, .off or .stl file in this folder")]
    EmptyFolder {
        /// The folder.
        path: PathBuf,
    },
    /// The run has no input at all.
    #[error("no input files (give files, folders or --list)")]
    NoInputs,
    /// `--shard` is not `K/N` with `1 <= K <= N`.
    #[error("--shard {given}: {why}")]
    Shard {
        /// What was given.
        given: String,
        /// What is wrong.
        why: &'static str,
    },
    /// Two inputs would be saved under the same name in the output folder.
    #[error("--out-dir: {first} and {second} would both be saved as {name}")]
    NameClash {
        /// The file name in the output folder.
        name: String,
        /// The first input.
        first: PathBuf,
        /// The second input.
        second: PathBuf,
    },
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

/// Parses the text of an input list: one path per line, relative to `base` unless absolute;
/// surrounding blanks are trimmed; blank lines and lines starting with `#` are skipped.
pub fn parse_list(text: &str, base: &Path) -> Vec<PathBuf> {
    text.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
        .map(|l| base.join(l))
        .collect()
}

/// Reads an input list ([`parse_list`]); paths are relative to the list's folder. `-` reads
/// standard input, with paths relative to the working directory.
pub fn read_list(path: &Path) -> Result<Vec<PathBuf>, BatchError> {
    let err = |source| BatchError::List {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    let base = if path == Path::new("-") {
        std::io::stdin().read_to_end(&mut bytes).map_err(err)?;
        Path::new("")
    } else {
        bytes = std::fs::read(path).map_err(err)?;
        path.parent().unwrap_or(Path::new(""))
    };
    let text = String::from_utf8(bytes).map_err(|e| {
        let good = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        BatchError::ListLine {
            path: path.to_path_buf(),
            line: 1 + good.iter().filter(|&&b| b == b'\n').count(),
        }
    })?;
    Ok(parse_list(&text, base))
}

/// The inputs of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct Inputs {
    /// The files this run (or shard) processes, in order.
    pub files: Vec<PathBuf>,
    /// Files of the whole list, over every shard.
    pub total: usize,
}

/// Gathers the inputs of a run: `paths` (files and folders) then the entries of each of
/// `lists` ([`read_list`]), folders expanded ([`crate::input::expand_inputs`]); with a
/// `shard`, its part of them ([`Shard::select`]). With `saved` (`--out-dir`), two inputs
/// of the whole list may not share a file name ([`check_saved_names`]), so that every
/// shard refuses the same list.
pub fn gather(
    paths: &[PathBuf],
    lists: &[PathBuf],
    shard: Option<Shard>,
    saved: bool,
) -> Result<Inputs, BatchError> {
    let mut given = paths.to_vec();
    for l in lists {
        given.extend(read_list(l)?);
    }
    for g in &given {
        if g.is_dir() && crate::input::expand_inputs(std::slice::from_ref(g))?.is_empty() {
            return Err(BatchError::EmptyFolder { path: g.clone() });
        }
    }
    let all = crate::input::expand_inputs(&given)?;
    if all.is_empty() {
        return Err(BatchError::NoInputs);
    }
    if saved {
        check_saved_names(&all)?;
    }
    let total = all.len();
    let files = match shard {
        Some(s) => s.select(&all),
        None => all,
    };
    Ok(Inputs { files, total })
}

/// One of `count` shards of a run, `index` counted from 1 (`--shard 2/4`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, 1 to `count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

impl FromStr for Shard {
    type Err = BatchError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let bad = |why| BatchError::Shard {
            given: s.to_string(),
            why,
        };
        let (k, n) = s
            .split_once('/')
            .ok_or_else(|| bad("write K/N, e.g. 2/4 (the second of four shards)"))?;
        let k: usize = k
            .trim()
            .parse()
            .map_err(|_| bad("K is not a whole number"))?;
        let n: usize = n
            .trim()
            .parse()
            .map_err(|_| bad("N is not a whole number"))?;
        if n == 0 {
            return Err(bad("N must be at least 1"));
        }
        if k == 0 || k > n {
            return Err(bad("K must be 1 to N (shards are counted from 1)"));
        }
        Ok(Shard { index: k, count: n })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// This shard's part of `files`: sorted by path, then every `count`-th file starting
    /// at the `index`-th. The shards of one list are disjoint and together hold all of it,
    /// whatever order the list came in. A shard outside `1..=count` (which only a hand-made
    /// `Shard` can be) selects nothing.
    pub fn select(&self, files: &[PathBuf]) -> Vec<PathBuf> {
        let mut sorted = files.to_vec();
        sorted.sort();
        sorted
            .into_iter()
            .enumerate()
            .filter(|(i, _)| self.count > 0 && i % self.count + 1 == self.index)
            .map(|(_, f)| f)
            .collect()
    }
}

/// The name an input's results are saved under in `--out-dir`: its file name and `.json`
/// (`chair.ply` → `chair.ply.json`).
pub fn saved_name(input: &Path) -> String {
    let name = input
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| input.display().to_string());
    format!("{name}.json")
}

/// Checks that no two inputs would be saved under the same name ([`saved_name`]).
pub fn check_saved_names(files: &[PathBuf]) -> Result<(), BatchError> {
    let mut seen: BTreeMap<String, &PathBuf> = BTreeMap::new();
    for f in files {
        let name = saved_name(f);
        if let Some(first) = seen.get(&name) {
            return Err(BatchError::NameClash {
                name,
                first: first.to_path_buf(),
                second: f.clone(),
            });
        }
        seen.insert(name, f);
    }
    Ok(())
}

/// How one input of a run ended, for the log.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Status {
    /// Detection ran and every output of the file was written.
    Ok,
    /// The file could not be read, or one of its outputs not written.
    Error,
    /// `--resume`: its saved output exists; not run again.
    Skipped,
}

/// `s` safe to print as one line of a terminal: control characters (newlines, NUL, the
/// escape that starts ANSI sequences) are written as Rust escapes (`\n`, `\u{1b}`), so
/// a file's bytes or a file name cannot split a line or drive the terminal.
pub fn printable(s: &str) -> String {
    if !s.chars().any(char::is_control) {
        return s.to_string();
    }
    s.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// One line of `--log-json`: how one input ended. Fields that do not apply are left out.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogLine {
    /// The input as named (on the command line, in a list, or found in a folder).
    pub file: String,
    /// How it ended.
    pub status: Status,
    /// The error, one line (status `error`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<String>,
    /// Points of the cloud (when it was read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub points: Option<usize>,
    /// Detections over every model (when it was read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub detections: Option<usize>,
    /// Affordance ids found by any detection (when it was read).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub affordances: Option<Vec<String>>,
    /// Wall time spent on the file, seconds (not for `skipped`). The only number of a run
    /// that changes from one run to the next: this is a log, not an output file.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seconds: Option<f64>,
}

impl LogLine {
    /// The line as compact JSON, without the newline.
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_default()
    }
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
pub fn read_document(text: &str, path: &Path) -> Result<Document, BatchError> {
    #[derive(Deserialize)]
    struct Version {
        version: u32,
    }
    let bad = |what: String| BatchError::Saved {
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
fn saved_json(text: &str, path: &Path) -> Result<Vec<SavedFile>, BatchError> {
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
fn saved_summary(text: &str, path: &Path) -> Result<Vec<SavedFile>, BatchError> {
    let bad = |what: String| BatchError::Saved {
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
pub fn read_saved(paths: &[PathBuf]) -> Result<Vec<SavedFile>, BatchError> {
    let mut sources = Vec::new();
    for p in paths {
        if p.is_dir() {
            let found =
                crate::input::files_in(p, &["json"]).map_err(|source| BatchError::SavedIo {
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
        let text = std::fs::read_to_string(s).map_err(|source| BatchError::SavedIo {
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
                    return Err(BatchError::Saved {
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
    fn a_list_skips_comments_and_blanks_and_is_relative_to_its_folder() {
        let got = parse_list(
            "# scans of day 1\n a.ply \n\nsub/b.pcd\n  # indented comment\n/abs/c.xyz\n",
            Path::new("lists"),
        );
        assert_eq!(
            got,
            [
                PathBuf::from("lists/a.ply"),
                PathBuf::from("lists/sub/b.pcd"),
                PathBuf::from("/abs/c.xyz")
            ]
        );
    }

    #[test]
    fn shards_are_disjoint_complete_and_independent_of_the_order_given() {
        let files: Vec<PathBuf> = (0..23)
            .map(|i| PathBuf::from(format!("d/{:02}.ply", (i * 7) % 23)))
            .collect();
        let mut reversed = files.clone();
        reversed.reverse();
        for n in [1, 2, 3, 5, 30] {
            let mut all = Vec::new();
            for k in 1..=n {
                let s = Shard { index: k, count: n };
                let part = s.select(&files);
                assert_eq!(part, s.select(&reversed));
                all.extend(part);
            }
            all.sort();
            let mut want = files.clone();
            want.sort();
            assert_eq!(all, want, "{n} shards");
        }
    }

    #[test]
    fn shard_syntax_is_checked() {
        assert_eq!(
            "2/4".parse::<Shard>().unwrap(),
            Shard { index: 2, count: 4 }
        );
        for bad in ["0/4", "5/4", "1/0", "2", "a/4", "1/-2", ""] {
            let e = bad.parse::<Shard>().unwrap_err().to_string();
            assert!(e.starts_with(&format!("--shard {bad}:")), "{e}");
        }
    }

    #[test]
    fn saved_names_clash_when_two_inputs_share_a_file_name() {
        let ok = [PathBuf::from("a/chair.ply"), PathBuf::from("a/chair.pcd")];
        assert!(check_saved_names(&ok).is_ok());
        let clash = [PathBuf::from("a/chair.ply"), PathBuf::from("b/chair.ply")];
        let e = check_saved_names(&clash).unwrap_err().to_string();
        assert!(
            e.contains("a/chair.ply") && e.contains("chair.ply.json"),
            "{e}"
        );
    }

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
