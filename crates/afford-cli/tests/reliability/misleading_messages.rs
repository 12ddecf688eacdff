//! Cause: several errors named the wrong problem: an ascii row missing a value failed the
//! whole-file size estimate first ("file too short"); a FIFO has no size ("only 0
//! bytes"); a missing `--transform` file was parsed as a matrix ("entry 1 is not a
//! number"); the unknown-format message left out the mesh formats; a list with one
//! non-UTF-8 line was refused without naming the line.

use std::path::Path;

use crate::common::*;

fn load_err(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    afford::cloud::load(&p).unwrap_err().to_string()
}

#[test]
fn a_missing_value_is_reported_on_its_line() {
    let d = tempfile::tempdir().unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 1\n2 2 2\n";
    let e = load_err(d.path(), "a.ply", ply.as_bytes());
    assert!(
        e.contains("line 9") && e.contains("no value for property 'z'"),
        "{e}"
    );
    let pcd = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\nPOINTS 3\nDATA ascii\n0 0 0\n1 1\n2 2 2\n";
    let e = load_err(d.path(), "a.pcd", pcd.as_bytes());
    assert!(e.contains("line 11") && e.contains("has 2 values"), "{e}");
}

#[test]
fn a_fifo_is_not_a_file() {
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("pipe.ply");
    assert!(std::process::Command::new("mkfifo")
        .arg(&f)
        .status()
        .unwrap()
        .success());
    let e = afford::cloud::load(&f).unwrap_err().to_string();
    assert!(e.contains("not a regular file (a FIFO)"), "{e}");
    let zero = d.path().join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let e = afford::cloud::mesh::read_mesh(&zero)
        .unwrap_err()
        .to_string();
    assert!(e.contains("a device"), "{e}");
}

#[test]
fn a_missing_transform_file_and_an_unknown_format_say_so() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let o = afford(&["detect", &s(&x), "--transform", "no_such_pose.txt"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("no such file"),
        "{}",
        text(&o.stderr)
    );
    let e = load_err(d.path(), "a.las", b"x");
    assert!(e.contains(".obj") && e.contains(".stl"), "{e}");
}

#[test]
fn a_list_with_a_non_utf8_line_names_the_line() {
    let d = tempfile::tempdir().unwrap();
    let list = d.path().join("list.txt");
    std::fs::write(&list, b"a.ply\nb.ply\nc\xff.ply\n").unwrap();
    let e = afford_cli::batch::read_list(&list).unwrap_err().to_string();
    assert!(e.ends_with("line 3: not UTF-8 text"), "{e}");
}
