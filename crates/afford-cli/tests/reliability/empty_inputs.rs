//! Cause: an empty folder or an empty list expanded to no input and the run ended with
//! exit 0 and no message; an empty folder among other inputs silently dropped out of the
//! count. Both are now errors that say which.

use crate::common::*;

#[test]
fn an_empty_folder_or_list_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let empty = d.path().join("empty");
    std::fs::create_dir(&empty).unwrap();
    let o = afford(&["detect", &s(&empty)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("empty: no .ply"),
        "{}",
        text(&o.stderr)
    );
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let o = afford(&["detect", &s(&x), &s(&empty)]);
    assert_eq!(o.status.code(), Some(2));
    let list = d.path().join("list.txt");
    std::fs::write(&list, "# nothing yet\n").unwrap();
    let o = afford(&["detect", "--list", &s(&list)]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("no input files"),
        "{}",
        text(&o.stderr)
    );
}
