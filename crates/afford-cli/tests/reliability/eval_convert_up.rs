//! Cause: three small gaps: `eval` listed unreadable labelled files only in its table on
//! stdout; `convert` wrote finite doubles beyond the f32 range as `inf` without a word;
//! clap read `--up -y` as an unknown flag. `eval` now also gives one stderr line per
//! failed file, `convert` refuses such coordinates, and `--up` takes hyphenated values.

use crate::common::*;

#[test]
fn eval_names_unreadable_files_on_stderr() {
    let d = tempfile::tempdir().unwrap();
    let labels = d.path().join("labels.csv");
    std::fs::write(&labels, "file,sitting,lying\nmissing.ply,1,0\n").unwrap();
    let o = afford(&["eval", &s(&labels), "--quiet"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{}", text(&o.stderr));
    assert!(errors[0].contains("missing.ply"), "{errors:?}");
}

#[test]
fn convert_refuses_coordinates_beyond_f32() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(
        &d.path().join("x.xyz"),
        &[[0.0; 3], [1e39, 0.0, 0.0], [1.0, 1.0, 1.0]],
    );
    let out = d.path().join("o.ply");
    let o = afford(&["convert", &s(&x), &s(&out)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("point 1"), "{}", text(&o.stderr));
    assert!(!out.exists());
}

#[test]
fn up_takes_a_negative_axis() {
    let d = tempfile::tempdir().unwrap();
    let pts: Vec<[f64; 3]> = small_scene(0.1)
        .iter()
        .map(|p| [p[0], -p[2], p[1]])
        .collect();
    let x = write_xyz(&d.path().join("x.xyz"), &pts);
    let out = d.path().join("o.ply");
    let o = afford(&["convert", &s(&x), &s(&out), "--up", "-y"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
}
