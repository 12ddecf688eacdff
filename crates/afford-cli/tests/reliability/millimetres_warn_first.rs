//! Cause: `detect` buffered each file's warnings until after its detection, so a cloud in
//! millimetres read as metres asked for 56-154 GB of grids and aborted before its units
//! warning was printed. Warnings now go out before detection, and the extent guard refuses
//! the grid the units mistake asks for.

use crate::common::*;

#[test]
fn a_millimetre_cloud_warns_first_then_is_refused_with_one_line() {
    let d = tempfile::tempdir().unwrap();
    let mm: Vec<[f64; 3]> = small_scene(0.05)
        .iter()
        .map(|p| p.map(|c| c * 1000.0))
        .collect();
    let f = write_xyz(&d.path().join("mm.xyz"), &mm);
    let o = afford_limited(2 << 30, &["detect", &s(&f)]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    let warn = err.find("warning:").expect("a units warning");
    let refuse = err.find("error:").expect("a refusal");
    assert!(warn < refuse, "{err}");
    assert!(err.contains("--units mm"), "{err}");
    assert_eq!(error_lines(&o).len(), 1, "{err}");
}

#[test]
fn a_stray_point_does_not_make_a_room_look_like_millimetres() {
    let mut pts: Vec<nalgebra::Point3<f64>> = small_scene(0.05)
        .iter()
        .map(|p| nalgebra::Point3::from(*p))
        .collect();
    pts.push(nalgebra::Point3::new(150.0, 0.0, 0.0));
    let c = afford::cloud::PointCloud::new(pts);
    assert_eq!(afford::cloud::frame::check_units(&c), None);
}
