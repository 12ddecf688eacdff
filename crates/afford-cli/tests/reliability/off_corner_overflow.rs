//! Cause: the OFF reader checked a face with `toks.len() < n + 1`; a corner count of
//! 2^64 - 1 overflowed `n + 1` (a panic in debug builds, a wrapped test in release that
//! let `Vec::with_capacity(n)` panic). The check is now `n >= toks.len()`.

use crate::common::*;

#[test]
fn a_face_with_2_pow_64_corners_is_a_body_error() {
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("corners.off");
    std::fs::write(&f, huge_corner_off()).unwrap();
    let e = afford::cloud::mesh::read_mesh(&f).unwrap_err().to_string();
    assert!(e.contains("corners.off: bad data at line 6"), "{e}");
}
