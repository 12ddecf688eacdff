//! Cause: the run-wide `--json`, `--csv` and `--summary` hold the reports of the inputs a
//! run processed; a second `--resume` run after completion skipped every input and
//! rewrote them empty (72 KB to 34 bytes). A run that skipped inputs now leaves them as
//! they are and says so in one note line per output.

use crate::common::*;

#[test]
fn a_second_resume_run_does_not_empty_the_run_wide_outputs() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let y = write_xyz(&d.path().join("y.xyz"), &small_scene(0.05));
    let out = d.path().join("out");
    let (json, csv, sum) = (
        d.path().join("a.json"),
        d.path().join("a.csv"),
        d.path().join("s.csv"),
    );
    let args = [
        "detect".to_string(),
        s(&x),
        s(&y),
        "--out-dir".into(),
        s(&out),
        "--resume".into(),
        "--json".into(),
        s(&json),
        "--csv".into(),
        s(&csv),
        "--summary".into(),
        s(&sum),
    ];
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let o = afford(&args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let first: Vec<Vec<u8>> = [&json, &csv, &sum]
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    assert!(first[0].len() > 100);
    let o = afford(&args);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let again: Vec<Vec<u8>> = [&json, &csv, &sum]
        .iter()
        .map(|p| std::fs::read(p).unwrap())
        .collect();
    assert_eq!(first, again);
    assert_eq!(
        text(&o.stderr).matches("note: ").count(),
        3,
        "{}",
        text(&o.stderr)
    );
}
