//! Loading of the TOML model files (agents and affordance hierarchies), with errors
//! that name the file, the line and the key.
//!
//! A model is first deserialised (serde: syntax, unknown keys, missing keys and wrong types
//! are [`ModelError::Syntax`], located by the TOML parser), then checked as a whole
//! (unknown names, cycles, impossible values are [`ModelError::Invalid`]). For the second
//! kind the checking code names the offending value by a [`Key`], which records both how the
//! key is shown (`joint.knee_l.parent`) and where it is in the document (array elements by
//! position, so that of two joints with the same name the right one is found); the line is
//! then looked up in the document's spans.
//!
//! The models: the body ([`agent`]), the affordance hierarchies ([`hierarchy`]) and the
//! bodies at their heights with every hierarchy ([`set`]).

pub mod agent;
pub mod hierarchy;
pub mod set;

use std::collections::HashMap;
use std::ops::{Range, RangeInclusive};
use std::path::{Path, PathBuf};

use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue};

/// What went wrong loading a model file (agent or hierarchy). Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The TOML is malformed or a key is unknown, missing or of the wrong type.
    #[error("{}: {}{what}", at(.path, *.line), .key.as_ref().map_or(String::new(), |k| format!("{k}: ")))]
    Syntax {
        /// The file.
        path: PathBuf,
        /// 1-based line of the problem (0 when unknown).
        line: usize,
        /// The key at the problem (`joint.knee_l.colour`), when the TOML itself is well
        /// formed and the parser points at a key or value.
        key: Option<String>,
        /// What is wrong (the parser's message, which names the key).
        what: String,
    },
    /// A model named on the command line is neither a file, a folder nor a built-in one.
    #[error("{name}: {what}")]
    Unknown {
        /// The name as given.
        name: String,
        /// What is wrong.
        what: String,
    },
    /// The file parses but describes an impossible model.
    #[error("{}: {key}: {what}", at(.path, *.line))]
    Invalid {
        /// The file.
        path: PathBuf,
        /// 1-based line of the key (0 when the problem is not in the file, such as the
        /// body height, which comes from the command line).
        line: usize,
        /// The key (for example `joint.knee_l.parent`).
        key: String,
        /// What is wrong.
        what: String,
    },
}

/// `path:line`, or `path` alone when the line is unknown (0).
fn at(path: &Path, line: usize) -> String {
    if line == 0 {
        path.display().to_string()
    } else {
        format!("{}:{line}", path.display())
    }
}

/// The largest model file read, bytes: the built-in ones are under 20 KB, and a device or
/// a mistaken path (`/dev/zero`, a point cloud) must not be read into memory without end.
pub const MAX_MODEL_BYTES: u64 = 1 << 20;

/// Reads a model file as text (at most [`MAX_MODEL_BYTES`]).
pub fn read_text(path: &Path) -> Result<String, ModelError> {
    use std::io::Read;
    let io = |source| ModelError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .map_err(io)?
        .take(MAX_MODEL_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 > MAX_MODEL_BYTES {
        return Err(io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("more than {MAX_MODEL_BYTES} bytes: not a model file"),
        )));
    }
    String::from_utf8(bytes).map_err(|_| {
        io(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "not UTF-8 text: not a model file",
        ))
    })
}

/// Deserialises TOML text; `path` only names the source in errors.
pub fn parse_toml<T: DeserializeOwned>(text: &str, path: &Path) -> Result<T, ModelError> {
    toml::from_str(text).map_err(|e| ModelError::Syntax {
        path: path.to_path_buf(),
        line: e.span().map_or(0, |s| line_at(text, s.start)),
        key: e.span().and_then(|s| key_at(text, &s)),
        what: e.message().trim().to_string(),
    })
}

/// The key whose name or value lies most tightly around `span` (a parser error's place),
/// shown like a [`Key`]: elements of arrays by their `name`, `id`, `joint` or `link`, else
/// by `[position]`. `None` for an empty span or a document that does not parse.
fn key_at(text: &str, span: &Range<usize>) -> Option<String> {
    if span.is_empty() {
        return None;
    }
    let doc = DeTable::parse(text).ok()?;
    let mut best = None;
    for (k, v) in doc.get_ref().iter() {
        visit(v, k.get_ref(), Some(k.span()), span, &mut best);
    }
    best.map(|(_, shown)| shown)
}

/// Records in `best` (span length, key) the tightest key or value of `v` (shown as
/// `shown`) around `span`; deeper keys win ties.
fn visit(
    v: &toml::Spanned<DeValue>,
    shown: &str,
    key_span: Option<Range<usize>>,
    span: &Range<usize>,
    best: &mut Option<(usize, String)>,
) {
    for s in key_span.into_iter().chain([v.span()]) {
        let tighter = best.as_ref().is_none_or(|(len, _)| s.len() <= *len);
        if s.start <= span.start && span.end <= s.end && tighter {
            *best = Some((s.len(), shown.to_string()));
        }
    }
    match v.get_ref() {
        DeValue::Table(t) => {
            for (k, w) in t.iter() {
                visit(
                    w,
                    &format!("{shown}.{}", k.get_ref()),
                    Some(k.span()),
                    span,
                    best,
                );
            }
        }
        DeValue::Array(a) => {
            for (i, w) in a.iter().enumerate() {
                let label = match w.get_ref() {
                    DeValue::Table(t) => ["name", "id", "joint", "link"].iter().find_map(|n| {
                        t.iter().find_map(|(k, v)| match v.get_ref() {
                            DeValue::String(s) if k.get_ref() == n => Some(format!(".{s}")),
                            _ => None,
                        })
                    }),
                    _ => None,
                };
                let shown = format!("{shown}{}", label.unwrap_or_else(|| format!("[{i}]")));
                visit(w, &shown, None, span, best);
            }
        }
        _ => {}
    }
}

/// 1-based line of byte `offset` of `text`.
fn line_at(text: &str, offset: usize) -> usize {
    text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

/// Orders the `n` items of a tree, parents before children, given each item's parent
/// (`None` for a root): passes over the items in file order take every item whose parent is
/// already placed, so the file order is kept wherever the tree allows it.
///
/// When items are left that can never be placed, returns `Err` with a cycle among them as
/// item indices, the first repeated at the end (`[a, b, a]`: the parent of `a` is `b`, the
/// parent of `b` is `a`).
fn topological(
    n: usize,
    parent: impl Fn(usize) -> Option<usize>,
) -> Result<Vec<usize>, Vec<usize>> {
    let mut order = Vec::with_capacity(n);
    let mut placed = vec![false; n];
    while order.len() < n {
        let before = order.len();
        for i in 0..n {
            if !placed[i] && parent(i).is_none_or(|p| placed[p]) {
                placed[i] = true;
                order.push(i);
            }
        }
        if order.len() == before {
            // Every unplaced item has an unplaced parent: following parents from one of
            // them must come back to an item already seen.
            let mut chain = vec![placed.iter().position(|p| !p).unwrap_or(0)];
            while let Some(p) = parent(chain[chain.len() - 1]) {
                if let Some(start) = chain.iter().position(|&c| c == p) {
                    chain.push(p);
                    return Err(chain.split_off(start));
                }
                chain.push(p);
            }
            return Err(chain);
        }
    }
    Ok(order)
}

/// What the items of a tree of a model file are called in errors.
pub(crate) struct TreeWords {
    /// One item (`joint`, `node`); also the top-level key of their array.
    pub item: &'static str,
    /// The key that names an item (`name`, `id`).
    pub name_key: &'static str,
}

/// Orders the `len` items of a tree of a model file (the joints of an agent, the nodes of a
/// hierarchy) parents first (see [`topological`]), checking that there is at least one,
/// that names are unique, that every parent exists, that exactly one item is the root and
/// that the parents form no cycle. `key`, `name` and `parent` give item `i`'s key, name and
/// parent's name. Returns, in order, each item's index in the file and its parent's place
/// in the order.
pub(crate) fn tree_order<'a>(
    src: Source,
    words: &TreeWords,
    len: usize,
    key: impl Fn(usize) -> Key,
    name: impl Fn(usize) -> &'a str,
    parent: impl Fn(usize) -> Option<&'a str>,
) -> Result<Vec<(usize, Option<usize>)>, ModelError> {
    let TreeWords { item, name_key } = *words;
    if len == 0 {
        return Err(src.invalid(&Key::top(item), format!("there is no {item}")));
    }
    let mut index: HashMap<&str, usize> = HashMap::new();
    for i in 0..len {
        if index.insert(name(i), i).is_some() {
            return Err(src.invalid(
                &key(i).key(name_key),
                format!("duplicate {item} {name_key} `{}`", name(i)),
            ));
        }
    }
    let mut parents = Vec::with_capacity(len);
    let mut root = None;
    for i in 0..len {
        parents.push(match (parent(i), root) {
            (Some(p), _) => Some(*index.get(p).ok_or_else(|| {
                src.invalid(
                    &key(i).key("parent"),
                    format!("depends on a missing {item} `{p}`"),
                )
            })?),
            (None, None) => {
                root = Some(i);
                None
            }
            (None, Some(r)) => {
                return Err(src.invalid(
                    &key(i).key(name_key),
                    format!(
                        "a second {item} without a parent: only the root (`{}`) has none",
                        name(r)
                    ),
                ))
            }
        });
    }
    let order = topological(len, |i| parents[i]).map_err(|cycle| {
        let names: Vec<&str> = cycle.iter().map(|&i| name(i)).collect();
        src.invalid(
            &key(cycle[0]).key("parent"),
            format!(
                "the {item}s form a cycle (each names the next as parent): {}",
                names.join(" -> ")
            ),
        )
    })?;
    let mut place = vec![0; len];
    for (new, &old) in order.iter().enumerate() {
        place[old] = new;
    }
    Ok(order
        .into_iter()
        .map(|i| (i, parents[i].map(|p| place[p])))
        .collect())
}

/// One step from a TOML table or array to one of its values.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    /// The value of a key of a table.
    Key(String),
    /// An element of an array (0-based).
    Index(usize),
}

/// A key of a model file, as shown in errors and as a path into the TOML document.
///
/// Elements of arrays (`[[joint]]`, `[[node]]`, `sweep = [...]`) are shown by their name and
/// found by their position.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Key {
    shown: String,
    steps: Vec<Step>,
}

impl Key {
    /// A top-level key.
    pub(crate) fn top(name: &str) -> Key {
        Key {
            shown: name.to_string(),
            steps: vec![Step::Key(name.to_string())],
        }
    }

    /// The key `name` of the table this key holds.
    pub(crate) fn key(&self, name: &str) -> Key {
        let mut k = self.clone();
        k.shown = format!("{}.{name}", self.shown);
        k.steps.push(Step::Key(name.to_string()));
        k
    }

    /// Element `index` of the array this key holds, shown by its `name`.
    pub(crate) fn item(&self, index: usize, name: &str) -> Key {
        let mut k = self.at(index);
        k.shown = format!("{}.{name}", self.shown);
        k
    }

    /// Element `index` of the array this key holds, shown as the array itself.
    pub(crate) fn at(&self, index: usize) -> Key {
        let mut k = self.clone();
        k.steps.push(Step::Index(index));
        k
    }

    /// The byte range in `text` of the deepest part of this key present in the document
    /// (the key itself for table keys, the element for array elements).
    fn span(&self, text: &str) -> Option<Range<usize>> {
        let doc = DeTable::parse(text).ok()?;
        let mut table: Option<&DeTable> = Some(doc.get_ref());
        let mut array: Option<&[toml::Spanned<DeValue>]> = None;
        let mut found = None;
        for step in &self.steps {
            let (span, value) = match step {
                Step::Key(name) => {
                    let Some((k, v)) = table.and_then(|t| {
                        t.iter()
                            .find(|(k, _)| k.get_ref().as_ref() == name.as_str())
                    }) else {
                        break;
                    };
                    (k.span(), v)
                }
                Step::Index(i) => {
                    let Some(v) = array.and_then(|a| a.get(*i)) else {
                        break;
                    };
                    (v.span(), v)
                }
            };
            found = Some(span);
            (table, array) = match value.get_ref() {
                DeValue::Table(t) => (Some(t), None),
                DeValue::Array(a) => (None, Some(&a[..])),
                _ => (None, None),
            };
        }
        found
    }
}

/// A model file being checked: its name and text, to locate problems.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Source<'a> {
    /// The file (only names it in errors).
    pub path: &'a Path,
    /// Its text.
    pub text: &'a str,
}

impl Source<'_> {
    /// The file name and text of the model `name` this file refers to at `key` (an agent's
    /// `extends`, a hierarchy's `shares`): one of `builtins` (shown as in `folder`), or a
    /// file beside this one; an error at `key` naming the `kind` of model otherwise.
    pub(crate) fn referred(
        &self,
        key: &Key,
        name: &str,
        builtins: &'static [(&'static str, &'static str)],
        folder: &str,
        kind: &str,
    ) -> Result<(PathBuf, String), ModelError> {
        if let Some((n, t)) = builtins.iter().find(|(n, _)| *n == name) {
            return Ok((set::Source::Builtin(n, t).label(folder), t.to_string()));
        }
        let path = self.path.parent().unwrap_or(Path::new("")).join(name);
        let text = read_text(&path).map_err(|e| {
            self.invalid(
                key,
                format!("`{name}` is neither a built-in {kind} nor a readable file: {e}"),
            )
        })?;
        Ok((path, text))
    }

    /// A [`ModelError::Invalid`] at `key`, with its line.
    pub(crate) fn invalid(&self, key: &Key, what: impl Into<String>) -> ModelError {
        ModelError::Invalid {
            path: self.path.to_path_buf(),
            line: key
                .span(self.text)
                .map_or(0, |s| line_at(self.text, s.start)),
            key: key.shown.clone(),
            what: what.into(),
        }
    }

    /// A [`ModelError::Invalid`] about something not in the file (no line).
    pub(crate) fn invalid_outside(&self, key: &str, what: impl Into<String>) -> ModelError {
        ModelError::Invalid {
            path: self.path.to_path_buf(),
            line: 0,
            key: key.to_string(),
            what: what.into(),
        }
    }
}

/// 1-based number of the `nth` (from 0) line of `text` that contains `needle`, for tests
/// that check the line an error names.
/// Checks a length `value` (metres) against `range`; the error says `what` is outside it.
pub fn check_range(value: f64, range: &RangeInclusive<f64>, what: &str) -> Result<f64, String> {
    if value.is_finite() && range.contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "{what} {value} m is outside {:?}-{:?} m",
            range.start(),
            range.end()
        ))
    }
}
#[cfg(test)]
pub(crate) fn line_of(text: &str, needle: &str, nth: usize) -> usize {
    text.lines()
        .enumerate()
        .filter(|(_, l)| l.contains(needle))
        .nth(nth)
        .map(|(i, _)| i + 1)
        .unwrap_or_else(|| panic!("no line {nth} with `{needle}`"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_model_file_is_read_up_to_a_size_and_as_text() {
        let dir = tempfile::tempdir().unwrap();
        let big = dir.path().join("big.toml");
        std::fs::write(
            &big,
            vec![b'#'; usize::try_from(MAX_MODEL_BYTES).unwrap() + 1],
        )
        .unwrap();
        let e = read_text(&big).unwrap_err().to_string();
        assert!(e.contains("big.toml: cannot read: more than"), "{e}");
        let bin = dir.path().join("bin.toml");
        std::fs::write(&bin, [0xff, 0xfe, 0x00]).unwrap();
        assert!(read_text(&bin)
            .unwrap_err()
            .to_string()
            .contains("not UTF-8"));
        std::fs::write(&bin, "name = \"x\"\n").unwrap();
        assert_eq!(read_text(&bin).unwrap(), "name = \"x\"\n");
        // A device that never ends is refused, not read without end.
        if Path::new("/dev/zero").exists() {
            assert!(read_text(Path::new("/dev/zero")).is_err());
        }
    }

    #[test]
    fn topological_order_keeps_file_order_and_finds_cycles() {
        // 0 <- 2 <- 1: 1 waits for 2.
        let parents = [None, Some(2), Some(0)];
        assert_eq!(topological(3, |i| parents[i]), Ok(vec![0, 2, 1]));
        // 0 is the root; 1 -> 3 -> 2 -> 1 is a cycle, 4 hangs from it.
        let parents = [None, Some(3), Some(1), Some(2), Some(2)];
        assert_eq!(topological(5, |i| parents[i]), Err(vec![1, 3, 2, 1]));
        let parents = [None, Some(1)];
        assert_eq!(topological(2, |i| parents[i]), Err(vec![1, 1]));
    }

    const DOC: &str = "name = \"x\"\n\n[[joint]]\nname = \"a\"\nlink = { name = \"l\", \
                       radius = 0.1 }\n\n[[joint]]\nname = \"a\"\nsweep = [\n  { joint = \"k\" },\n  \
                       { joint = \"m\", theta1 = 3.0 },\n]\n";

    fn line(key: &Key) -> usize {
        let e = Source {
            path: Path::new("d.toml"),
            text: DOC,
        }
        .invalid(key, "bad");
        match e {
            ModelError::Invalid { line, .. } => line,
            _ => unreachable!(),
        }
    }

    #[test]
    fn keys_are_found_by_position_and_shown_by_name() {
        let joint = |i: usize| Key::top("joint").item(i, "a");
        assert_eq!(line(&Key::top("name")), 1);
        assert_eq!(line(&joint(0).key("name")), 4);
        assert_eq!(
            line(&joint(1).key("name")),
            8,
            "the second of two equal names"
        );
        assert_eq!(line(&joint(0).key("link").key("radius")), 5);
        let theta1 = joint(1).key("sweep").item(1, "m").key("theta1");
        assert_eq!(line(&theta1), 11);
        assert_eq!(theta1.shown, "joint.a.sweep.m.theta1");
        // A key the document lacks is located at its deepest present part.
        assert_eq!(line(&joint(1).key("sweep").at(0).key("theta2")), 10);
        assert_eq!(line(&Key::top("missing")), 0);
    }

    #[test]
    fn parser_errors_name_the_key_at_their_place() {
        #[derive(Debug, serde::Deserialize)]
        #[serde(deny_unknown_fields)]
        #[allow(dead_code)]
        struct Doc {
            name: String,
            joint: Vec<toml::Value>,
        }
        let e = parse_toml::<Doc>(
            &DOC.replace("name = \"x\"", "nam = \"x\""),
            Path::new("d.toml"),
        )
        .unwrap_err()
        .to_string();
        assert!(e.starts_with("d.toml:1: nam: unknown field `nam`"), "{e}");
        let bad = DOC.replace("theta1 = 3.0", "theta1 = 3.0, colour = 1");
        let e = key_at(
            &bad,
            &(bad.find("colour").unwrap()..bad.find("colour").unwrap() + 6),
        );
        assert_eq!(e.as_deref(), Some("joint.a.sweep.m.colour"));
        let e = key_at(
            &bad,
            &(bad.find("{ joint = \"k\"").unwrap()..bad.find("{ joint").unwrap() + 3),
        );
        assert_eq!(e.as_deref(), Some("joint.a.sweep.k"));
        assert_eq!(key_at(&bad, &(0..0)), None);
        assert_eq!(key_at("a = [", &(0..1)), None);
    }

    #[test]
    fn errors_name_file_line_and_key() {
        let src = Source {
            path: Path::new("d.toml"),
            text: DOC,
        };
        let e = src.invalid(&Key::top("joint").item(1, "a").key("name"), "duplicate");
        assert_eq!(e.to_string(), "d.toml:8: joint.a.name: duplicate");
        let e = src.invalid_outside("height", "too tall");
        assert_eq!(e.to_string(), "d.toml: height: too tall");
    }
}
