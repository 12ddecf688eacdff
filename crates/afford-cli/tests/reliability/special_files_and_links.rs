//! Cause: the atomic writer always renamed a temporary file over the target, so as root
//! `--json /dev/null` replaced the device with a regular file, `--json /dev/full` "worked"
//! (exit 0), and a symbolic link given as output became a regular file while its target
//! kept the old content. `afford::report::atomic` now writes special files directly (reporting
//! every error, a full device included) and writes through links to their target.

use crate::common::*;

#[test]
fn a_device_is_written_directly_and_a_full_device_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let o = afford(&[
        "detect",
        &s(&x),
        "--json",
        "/dev/null",
        "--csv",
        "/dev/null",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let m = std::fs::metadata("/dev/null").unwrap();
    assert!(!m.is_file(), "/dev/null became a regular file");
    let o = afford(&["detect", &s(&x), "--json", "/dev/full"]);
    assert_eq!(o.status.code(), Some(2));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(errors[0].contains("/dev/full: cannot write"), "{errors:?}");
    assert!(!std::fs::metadata("/dev/full").unwrap().is_file());
}

#[test]
fn a_symbolic_link_is_written_through_to_its_target() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let target = d.path().join("real.json");
    std::fs::write(&target, "old").unwrap();
    let link = d.path().join("link.json");
    std::os::unix::fs::symlink("real.json", &link).unwrap();
    let o = afford(&["detect", &s(&x), "--json", &s(&link)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(std::fs::symlink_metadata(&link)
        .unwrap()
        .file_type()
        .is_symlink());
    let got = std::fs::read_to_string(&target).unwrap();
    assert!(got.starts_with("{"), "{got}");
}

#[test]
fn a_fifo_output_is_written_directly() {
    let d = tempfile::tempdir().unwrap();
    let fifo = d.path().join("pipe.csv");
    let made = std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap();
    assert!(made.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let o = afford(&["detect", &s(&x), "--csv", &s(&fifo)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(reader.join().unwrap().starts_with("file,detection"));
    assert!(!std::fs::metadata(&fifo).unwrap().is_file());
}
