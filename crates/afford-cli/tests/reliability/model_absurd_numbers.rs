//! Cause: the model loaders checked that numbers were finite and of the right sign, not
//! that they were sane, so `start_clearance = 1e300` (a bisection that never ends),
//! `template_diameter = 1000` (8.6 GB of template cells), `sample_spacing = 1e-12`, a link
//! or an origin 1e6 H away, or a 100,000-joint chain (here 1000 show the limit) (a worker's stack overflowed) hung or
//! aborted detection. They are now refused at load with `file:line: key: what`. Likewise
//! `--threads 100000` (72 s of thread start-up) and `synth --count 100000000` (a 12 GB
//! plan) are refused by the parser.

use std::path::Path;

use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;

use crate::common::*;

fn human() -> Agent {
    Agent::from_toml(
        afford::model::set::BUILTIN_AGENT,
        Path::new("human.toml"),
        1.75,
    )
    .unwrap()
}

/// The sitting hierarchy with the line starting `key =` given `value`; the error it gives.
fn sitting_with(key: &str, value: &str) -> String {
    let text: String = afford::model::set::BUILTIN_SITTING
        .lines()
        .map(|l| {
            if l.starts_with(&format!("{key} =")) {
                format!("{key} = {value}\n")
            } else {
                format!("{l}\n")
            }
        })
        .collect();
    assert_ne!(text, afford::model::set::BUILTIN_SITTING, "{key} not found");
    Hierarchy::from_toml(&text, Path::new("sit.toml"), &human())
        .map(|_| String::new())
        .unwrap_or_else(|e| e.to_string())
}

#[test]
fn absurd_hierarchy_numbers_are_refused_at_load_with_file_line_and_key() {
    for (key, value) in [
        ("start_clearance", "1e300"),
        ("template_diameter", "1000"),
        ("template_diameter", "1e6"),
        ("gradient_radius", "1e6"),
        ("sample_spacing", "1e-12"),
        ("fallback_yaw_step", "1e-9"),
        ("max_drop", "1e9"),
    ] {
        let e = sitting_with(key, value);
        assert!(
            e.starts_with("sit.toml:") && e.contains(&format!("{key}: ")),
            "{key} = {value}: {e}"
        );
    }
    // The committed values load.
    assert_eq!(sitting_with("start_clearance", "0.04"), "");
}

#[test]
fn absurd_agent_numbers_are_refused_at_load() {
    let base = afford::model::set::BUILTIN_AGENT;
    let far_origin = base.replacen("origin = [0.0, 0.0, 0.0]", "origin = [1e300, 0.0, 0.0]", 1);
    let long_link = base.replacen("to = [0.0, 0.07, 0.0]", "to = [0.0, 1e6, 0.0]", 1);
    for (what, text) in [("origin", far_origin), ("link", long_link)] {
        assert_ne!(text, base, "{what}");
        let e = Agent::from_toml(&text, Path::new("a.toml"), 1.75)
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.toml:") && e.contains("within"),
            "{what}: {e}"
        );
    }
    let mut chain = String::from("name = \"snake\"\n");
    for i in 0..1000 {
        chain.push_str(&format!(
            "[[joint]]\nname = \"j{i}\"\n{}origin = [0.0, 0.0, 0.001]\naxis = [1.0, 0.0, 0.0]\n\
             limit = {{ lower = 0.0, upper = 0.0 }}\n",
            if i > 0 {
                format!("parent = \"j{}\"\n", i - 1)
            } else {
                String::new()
            }
        ));
    }
    let e = Agent::from_toml(&chain, Path::new("snake.toml"), 1.75)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("snake.toml:") && e.contains("joints"), "{e}");
}

#[test]
fn absurd_thread_and_scene_counts_are_refused_by_the_parser() {
    let o = afford(&["detect", SAMPLE, "--threads", "100000"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("1 to 256"), "{}", text(&o.stderr));
    let d = tempfile::tempdir().unwrap();
    let o = afford(&[
        "synth",
        "--out",
        &s(d.path()),
        "--count",
        "100000000",
        "0",
        "0",
        "0",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("0 to 100000"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 0);
}
