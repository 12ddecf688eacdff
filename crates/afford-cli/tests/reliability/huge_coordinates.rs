//! Cause: coordinates of 1e17 m or more (from the file, or a finite `--transform` scaling
//! by 1e300) went through a saturating float-to-integer cast in the height map and indexed
//! out of bounds. The extent guard refuses any coordinate beyond what the grids can index,
//! with one line naming the file and the point.

use crate::common::*;

#[test]
fn coordinates_beyond_the_indexable_range_are_refused() {
    let d = tempfile::tempdir().unwrap();
    let far: Vec<[f64; 3]> = small_scene(0.1)
        .iter()
        .map(|p| p.map(|c| c + 1e17))
        .collect();
    let f17 = write_xyz(&d.path().join("e17.xyz"), &far);
    let f30 = write_xyz(
        &d.path().join("e30.xyz"),
        &[[1e30, 0.0, 0.0], [1e30, 1.0, 0.0]],
    );
    let ok = write_xyz(&d.path().join("ok.xyz"), &small_scene(0.1));
    let o = afford(&["detect", &s(&f17), &s(&f30), &s(&ok), "--log-json"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 2, "{errors:?}");
    assert!(errors[0].contains("e17.xyz: point 0: coordinate 1.000e17 m is beyond"));
    assert!(errors[1].contains("e30.xyz: point 0"), "{errors:?}");
    assert!(text(&o.stdout).contains("\"status\":\"ok\""));
}

#[test]
fn a_transform_scaling_by_1e300_is_refused_not_a_panic() {
    let d = tempfile::tempdir().unwrap();
    let f = write_xyz(&d.path().join("room.xyz"), &small_scene(0.1));
    let o = afford(&[
        "detect",
        &s(&f),
        "--transform",
        "1e300 0 0 0  0 1e300 0 0  0 0 1e300 0  0 0 0 1",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(errors[0].contains("room.xyz"), "{errors:?}");
}
