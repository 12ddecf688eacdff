//! Cause: `--voxel 0.002` was accepted and the distance field over the committed sample
//! asked for 42.9 GB and aborted. The grid budget of the extent guard counts the voxel
//! size, so the file is refused with one line that names a coarser `--voxel`.

use crate::common::*;

#[test]
fn a_fine_voxel_on_the_sample_is_refused_by_the_budget() {
    let o = afford_limited(2 << 30, &["detect", SAMPLE, "--voxel", "0.002"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("room.ply") && errors[0].contains("--voxel"),
        "{errors:?}"
    );
}
