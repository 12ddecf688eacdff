//! Cause: every write to standard output was `let _ = ...`, so the table or `--log-json`
//! sent to a full device was lost with exit 0, and after `afford detect ... | head` closed
//! the pipe the run went on through every input. A closed pipe now ends the run at once
//! without a message (exit 0, as a filter does); any other write error to standard output
//! is one line and exit 2, in every command.

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};

use crate::common::*;

/// Standard output going to `/dev/full` (every write fails: no space left).
fn full() -> Stdio {
    Stdio::from(
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap(),
    )
}

fn run_to_full(args: &[String]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_afford"))
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .args(args)
        .stdout(full())
        .output()
        .unwrap()
}

#[test]
fn a_table_to_a_full_device_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    for extra in [None, Some("--log-json")] {
        let mut args = vec!["detect".to_string(), s(&x)];
        args.extend(extra.map(String::from));
        let o = run_to_full(&args);
        assert_eq!(o.status.code(), Some(2), "{extra:?}");
        let err = text(&o.stderr);
        assert_eq!(
            error_lines(&o),
            vec!["error: standard output: cannot write: No space left on device (os error 28)"],
            "{err}"
        );
    }
}

#[test]
fn every_command_reports_a_full_device_in_one_line() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let labels = d.path().join("labels.csv");
    std::fs::write(&labels, "file,sitting\nx.xyz,1\n").unwrap();
    let runs = [
        vec!["convert".into(), s(&x), s(&d.path().join("x.ply"))],
        vec!["eval".into(), s(&labels)],
        vec![
            "inspect".into(),
            s(&x),
            "--png".into(),
            s(&d.path().join("x.png")),
        ],
    ];
    for args in runs {
        let o = run_to_full(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        let errors = error_lines(&o);
        assert_eq!(errors.len(), 1, "{args:?}: {errors:?}");
        assert!(
            errors[0].starts_with("error: standard output: cannot write"),
            "{args:?}: {errors:?}"
        );
    }
}

#[test]
fn a_closed_pipe_stops_the_run_quietly() {
    let d = tempfile::tempdir().unwrap();
    let inputs = d.path().join("in");
    std::fs::create_dir(&inputs).unwrap();
    let scene = small_scene(0.1);
    // Many inputs: were the run to go on after the pipe closed, it would save them all.
    let n = 200;
    for i in 0..n {
        write_xyz(&inputs.join(format!("{i:03}.xyz")), &scene);
    }
    let saved = d.path().join("saved");
    let mut child = Command::new(env!("CARGO_BIN_EXE_afford"))
        .args([
            "detect",
            &s(&inputs),
            "--log-json",
            "--out-dir",
            &s(&saved),
            "--quiet",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    out.read_line(&mut first).unwrap();
    assert!(first.contains("\"status\":\"ok\""), "{first}");
    // As `head -1` does: read one line, close the pipe.
    drop(out);
    let o = child.wait_with_output().unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert_eq!(
        text(&o.stderr),
        "",
        "no message, not even the run's summary"
    );
    let done = std::fs::read_dir(&saved).unwrap().count();
    assert!(
        done < n,
        "the run stopped early: {done} of {n} inputs saved"
    );
}
