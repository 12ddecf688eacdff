//! The documentation stays inside the repository and its links resolve: every relative
//! link and image in README.md, CHANGELOG.md and docs/*.md names a file of the
//! repository (not outside it), every `#anchor` names a heading of its target page, and no
//! page points to things a reader of the repository cannot open (issue numbers, notes
//! kept elsewhere); docs/cli.md documents every flag of `afford <command> --help` and no
//! other.

use std::collections::HashSet;
use std::path::{Component, Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
}

/// README.md, CHANGELOG.md and every Markdown file in docs/.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![root().join("README.md"), root().join("CHANGELOG.md")];
    let mut docs: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .expect("docs/ exists")
        .map(|e| e.expect("docs/ is readable").path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        .collect();
    docs.sort();
    pages.extend(docs);
    pages
}

/// The page's lines outside fenced code blocks, with inline code spans blanked out (so
/// that `[a](b)` inside code is not a link), numbered from 1.
fn prose(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut fenced = false;
    for (i, line) in text.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut clean = String::with_capacity(line.len());
        let mut in_code = false;
        for c in line.chars() {
            if c == '`' {
                in_code = !in_code;
                clean.push(' ');
            } else {
                clean.push(if in_code { ' ' } else { c });
            }
        }
        out.push((i + 1, clean));
    }
    out
}

/// The targets of the inline links and images `[text](target)` of one line.
fn link_targets(line: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut rest = line;
    while let Some(at) = rest.find("](") {
        let after = &rest[at + 2..];
        match after.find(')') {
            Some(end) => {
                targets.push(after[..end].trim().to_string());
                rest = &after[end + 1..];
            }
            None => break,
        }
    }
    targets
}

/// GitHub's anchor of a heading: lower case, only letters, digits, spaces, `-` and `_`
/// kept (code spans keep their text), spaces turned into `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a page's headings, numbered as GitHub numbers repeated ones (`x`, `x-1`).
fn anchors(text: &str) -> HashSet<String> {
    let mut seen = HashSet::new();
    let mut fenced = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced || !line.starts_with('#') {
            continue;
        }
        let heading = line.trim_start_matches('#');
        if !heading.starts_with(' ') {
            continue;
        }
        let base = slug(heading);
        let mut anchor = base.clone();
        let mut n = 0;
        while seen.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        seen.insert(anchor);
    }
    seen
}

/// `path` with `.` and `..` resolved lexically; `None` when it climbs above the root.
fn normalise(path: &Path) -> Option<PathBuf> {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::ParentDir => {
                if !out.pop() {
                    return None;
                }
            }
            Component::CurDir => {}
            Component::Normal(p) => out.push(p),
            Component::RootDir | Component::Prefix(_) => return None,
        }
    }
    Some(out)
}

#[test]
fn every_relative_link_of_the_docs_resolves_inside_the_repository() {
    let mut problems = Vec::new();
    let mut checked = 0;
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("page is readable");
        let rel_page = page.strip_prefix(root()).expect("page in the repository");
        let dir = rel_page.parent().unwrap_or(Path::new(""));
        for (n, line) in prose(&text) {
            for target in link_targets(&line) {
                let at = format!("{}:{n}: ({target})", rel_page.display());
                if target.contains("://") || target.starts_with("mailto:") {
                    problems.push(format!("{at}: points outside the repository"));
                    continue;
                }
                let (file, anchor) = match target.split_once('#') {
                    Some((f, a)) => (f, Some(a)),
                    None => (target.as_str(), None),
                };
                let resolved = if file.is_empty() {
                    Some(rel_page.to_path_buf())
                } else {
                    normalise(&dir.join(file))
                };
                let Some(resolved) = resolved else {
                    problems.push(format!("{at}: leaves the repository"));
                    continue;
                };
                let full = root().join(&resolved);
                if !full.exists() {
                    problems.push(format!("{at}: {} does not exist", resolved.display()));
                    continue;
                }
                if let Some(anchor) = anchor {
                    let is_md = full.extension().is_some_and(|e| e == "md");
                    let target_text = std::fs::read_to_string(&full).unwrap_or_default();
                    if !is_md || !anchors(&target_text).contains(anchor) {
                        problems.push(format!(
                            "{at}: no heading #{anchor} in {}",
                            resolved.display()
                        ));
                    }
                }
                checked += 1;
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    assert!(
        checked >= 50,
        "only {checked} links found: is the parser right?"
    );
}

#[test]
fn the_docs_name_nothing_outside_the_repository() {
    let mut problems = Vec::new();
    for page in pages() {
        let text = std::fs::read_to_string(&page).expect("page is readable");
        let rel_page = page.strip_prefix(root()).expect("page in the repository");
        let dir = rel_page.parent().unwrap_or(Path::new(""));
        for (i, line) in text.lines().enumerate() {
            // Relative paths in code spans must stay inside the repository, as links do.
            for (k, span) in line.split('`').enumerate() {
                let escapes = span.starts_with("../") || span.contains("/../");
                if k % 2 == 1 && escapes && normalise(&dir.join(span)).is_none() {
                    problems.push(format!("{}:{}: {span}", rel_page.display(), i + 1));
                }
            }
            let lower = line.to_lowercase();
            let mut rest = lower.as_str();
            while let Some(at) = rest.find("issue") {
                let after = rest[at + 5..].trim_start_matches([' ', '#']);
                if after.starts_with(|c: char| c.is_ascii_digit()) {
                    problems.push(format!(
                        "{}:{}: an issue number (the issues are not in the repository)",
                        rel_page.display(),
                        i + 1
                    ));
                }
                rest = &rest[at + 5..];
            }
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

#[test]
fn the_anchor_rule_matches_github() {
    assert_eq!(slug(" The detector's frame"), "the-detectors-frame");
    assert_eq!(
        slug(" Synthetic data (`afford synth`)"),
        "synthetic-data-afford-synth"
    );
    assert_eq!(slug(" labels.csv"), "labelscsv");
    let a = anchors("# A\n## B c\n```\n# not a heading\n```\n## B c\n#!shebang\n");
    let want: HashSet<String> = ["a", "b-c", "b-c-1"].map(String::from).into();
    assert_eq!(a, want);
    assert_eq!(
        link_targets("see [a](x.md#y) and ![p](../p.png)"),
        ["x.md#y", "../p.png"]
    );
    assert_eq!(
        normalise(Path::new("docs/../README.md")),
        Some("README.md".into())
    );
    assert_eq!(normalise(Path::new("../outside/x.md")), None);
}

/// The long flags `afford <command> --help` lists (`--help` itself left out).
fn help_flags(command: &str) -> Vec<String> {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_afford"))
        .args([command, "--help"])
        .output()
        .expect("afford runs");
    assert!(out.status.success(), "afford {command} --help failed");
    let text = String::from_utf8(out.stdout).expect("help is UTF-8");
    let mut flags = Vec::new();
    for line in text.lines() {
        let line = line.trim_start();
        let line = line
            .strip_prefix('-')
            .filter(|l| !l.starts_with('-'))
            .map_or(line, |l| l.get(3..).unwrap_or(""));
        if let Some(rest) = line.strip_prefix("--") {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            if !name.is_empty() && name != "help" {
                flags.push(format!("--{name}"));
            }
        }
    }
    flags
}

/// Whether `doc` names `flag` in code (`` `--scan`` but not `` `--scans``).
fn mentions(doc: &str, flag: &str) -> bool {
    let quoted = format!("`{flag}");
    doc.match_indices(&quoted).any(|(at, _)| {
        doc[at + quoted.len()..]
            .chars()
            .next()
            .is_none_or(|c| !(c.is_ascii_alphanumeric() || c == '-'))
    })
}

#[test]
fn docs_cli_md_lists_every_flag_and_invents_none() {
    let doc = std::fs::read_to_string(root().join("docs/cli.md")).expect("docs/cli.md");
    let commands = ["detect", "inspect", "synth", "eval", "convert"];
    let mut problems = Vec::new();
    let mut all = HashSet::new();
    for command in commands {
        let flags = help_flags(command);
        assert!(
            flags.len() >= 2,
            "no flags parsed from `afford {command} --help`"
        );
        for f in flags {
            if !mentions(&doc, &f) {
                problems.push(format!("afford {command} {f}: not in docs/cli.md"));
            }
            all.insert(f);
        }
    }
    // The first cell of every table row that documents a flag.
    for (n, line) in doc.lines().enumerate() {
        let Some(cell) = line.strip_prefix("| `--") else {
            continue;
        };
        let name: String = cell
            .chars()
            .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
            .collect();
        if !all.contains(&format!("--{name}")) {
            problems.push(format!(
                "docs/cli.md:{}: --{name} is no flag of any command",
                n + 1
            ));
        }
    }
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
