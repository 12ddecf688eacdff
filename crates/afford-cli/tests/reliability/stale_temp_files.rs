//! Cause: `kill -9` during a write left `<name>.tmp-<pid>` files (8.5 MB of segments) that
//! no later run removed, and the PLY/PCD ones were not hidden like the JSON ones. All
//! writers now share `afford::report::atomic`: hidden `.<name>.afford-tmp-<pid>` names, and a
//! write to a target first removes the temporary files of that target whose process is
//! gone.

use afford::report::atomic::{temp_path, write_bytes};

#[test]
fn a_dead_process_temp_file_is_removed_by_the_next_write() {
    let d = tempfile::tempdir().unwrap();
    let target = d.path().join("seg.chair.ply");
    // A temporary file of a process that no longer runs (pid beyond the kernel's maximum).
    let stale = d.path().join(".seg.chair.ply.afford-tmp-4294967294");
    std::fs::write(&stale, vec![0u8; 1000]).unwrap();
    // One of a live process (this one) is left alone: it may be writing.
    let live = temp_path(&target);
    std::fs::write(&live, b"x").unwrap();
    let own = live.file_name().unwrap().to_string_lossy().into_owned();
    assert!(
        own.starts_with('.') && own.contains(".afford-tmp-"),
        "{own}"
    );
    std::fs::remove_file(&live).unwrap();
    write_bytes(&target, b"ply\n").unwrap();
    assert!(!stale.exists());
    let names: Vec<String> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(names, ["seg.chair.ply"]);
}

#[test]
fn ply_and_pcd_writers_leave_only_the_file() {
    let d = tempfile::tempdir().unwrap();
    let pts = [nalgebra::Point3::new(0.0, 0.0, 0.0); 3];
    afford::cloud::write_ply_points(&d.path().join("a.ply"), &pts, &[], true).unwrap();
    afford::cloud::write_pcd(&d.path().join("a.pcd"), &pts).unwrap();
    assert_eq!(std::fs::read_dir(d.path()).unwrap().count(), 2);
}
