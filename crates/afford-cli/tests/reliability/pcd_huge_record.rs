//! Cause: the PCD header check bounded each field (COUNT up to 1048576, SIZE up to 8) but
//! not their sum, and with POINTS 0 the size-against-file check passed; the record buffer
//! (58.7 GB for 7000 such fields) was then allocated before any point was read. The
//! header now refuses a record over 16 MiB.

use crate::common::*;

#[test]
fn a_header_asking_for_a_huge_record_is_refused_at_the_header() {
    let d = tempfile::tempdir().unwrap();
    let f = d.path().join("fields.pcd");
    std::fs::write(&f, huge_record_pcd()).unwrap();
    let e = afford::cloud::load(&f).unwrap_err().to_string();
    assert!(
        e.contains("fields.pcd: bad header at line") && e.contains("bytes"),
        "{e}"
    );
    let o = afford_limited(2 << 30, &["detect", &s(&f)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(error_lines(&o).len(), 1, "{}", text(&o.stderr));
}
