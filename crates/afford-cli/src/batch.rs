//! Batch runs over many files: input lists, deterministic shards, per-file outputs that a
//! later run can resume from, and the JSON log line per file (reading saved outputs back
//! is [`afford::report::saved`]).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use serde::{Deserialize, Serialize};

/// What went wrong with a list, a shard or an output folder.
#[derive(Debug, thiserror::Error)]
pub enum BatchError {
    /// A folder given as input could not be listed.
    #[error(transparent)]
    Input(#[from] afford::cloud::CloudError),
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
/// `lists` ([`read_list`]), folders expanded ([`afford::input::expand_inputs`]); with a
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
        if g.is_dir() && afford::input::expand_inputs(std::slice::from_ref(g))?.is_empty() {
            return Err(BatchError::EmptyFolder { path: g.clone() });
        }
    }
    let all = afford::input::expand_inputs(&given)?;
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
}
