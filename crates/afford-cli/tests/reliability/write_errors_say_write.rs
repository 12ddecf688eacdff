//! Cause: the PLY and PCD writers mapped their I/O errors to the reader's `Io` variant,
//! so a failed write (and `convert` and `synth`, which use them) said "cannot read". They
//! now give `CloudError::Write`: "cannot write".

use crate::common::*;

#[test]
fn a_failed_write_says_cannot_write() {
    let d = tempfile::tempdir().unwrap();
    let pts = [nalgebra::Point3::new(0.0, 0.0, 0.0); 3];
    let missing = d.path().join("no/such/dir/a.ply");
    let e = afford::cloud::write_ply_points(&missing, &pts, &[], true)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("cannot write") && !e.contains("cannot read"),
        "{e}"
    );
    let e = afford::cloud::write_pcd(&d.path().join("no/a.pcd"), &pts)
        .unwrap_err()
        .to_string();
    assert!(e.contains("cannot write"), "{e}");
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let o = afford(&["convert", &s(&x), "/dev/full/x.ply"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o.stderr).contains("cannot write"),
        "{}",
        text(&o.stderr)
    );
}
