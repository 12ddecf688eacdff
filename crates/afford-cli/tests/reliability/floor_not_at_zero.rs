//! Cause: a cloud whose floor is not at z = 0 (a depth-camera frame with the camera at the
//! origin, a scan in building coordinates) ran without a word and found nothing: the seat
//! heights are measured from z = 0. Such a cloud now gets one warning naming the flag that
//! levels it; a levelled run does not.

use crate::common::*;

#[test]
fn a_floor_far_below_zero_is_warned_about_and_levelling_silences_it() {
    let d = tempfile::tempdir().unwrap();
    let low: Vec<[f64; 3]> = small_scene(0.05)
        .iter()
        .map(|p| [p[0], p[1], p[2] - 1.3])
        .collect();
    let f = write_xyz(&d.path().join("low.xyz"), &low);
    let o = afford(&["detect", &s(&f)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    assert!(
        warnings[0].contains("low.xyz") && warnings[0].contains("--floor auto"),
        "{err}"
    );
    let o = afford(&["detect", &s(&f), "--floor", "auto"]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(!text(&o.stderr).contains("warning:"), "{}", text(&o.stderr));
    // The same scene with its floor at zero: no warning.
    let f = write_xyz(&d.path().join("level.xyz"), &small_scene(0.05));
    let o = afford(&["detect", &s(&f)]);
    assert!(!text(&o.stderr).contains("warning:"), "{}", text(&o.stderr));
}
