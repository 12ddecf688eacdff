//! Cause: the height map and the distance field are dense grids over the cloud's bounding
//! box, so one stray point 100 m away asked for 14.8 GB and aborted the whole batch. The
//! guard stage (`afford::method::extent`) bins points into coarse cubes with a hash map, keeps the
//! connected regions holding the bulk of the points, and refuses an extent whose grids
//! would exceed the budget, with one line naming the file.

use std::borrow::Cow;
use std::path::Path;

use afford::cloud::PointCloud;
use afford::detect::DetectConfig;
use afford::method::extent::{guard, ExtentConfig, ExtentError};
use nalgebra::Point3;

use crate::common::*;

fn cloud(pts: &[[f64; 3]]) -> PointCloud {
    PointCloud::new(pts.iter().map(|p| Point3::from(*p)).collect())
}

#[test]
fn a_stray_point_is_dropped_and_the_grids_follow_the_points() {
    let mut pts = small_scene(0.05);
    let n = pts.len();
    pts.push([100.0, 100.0, 0.0]);
    let c = cloud(&pts);
    let g = guard(
        Path::new("s.xyz"),
        &c,
        &DetectConfig::default(),
        &ExtentConfig::default(),
    )
    .unwrap();
    assert_eq!(g.dropped, 1);
    assert_eq!(g.cloud.len(), n);
    let (lo, hi) = g.cloud.bounds().unwrap();
    assert!((hi - lo).norm() < 3.0, "{lo} {hi}");
    // Without the stray point the cloud passes through as it is.
    let clean = cloud(&pts[..n]);
    let g = guard(
        Path::new("c.xyz"),
        &clean,
        &DetectConfig::default(),
        &ExtentConfig::default(),
    )
    .unwrap();
    assert!(matches!(g.cloud, Cow::Borrowed(_)));
}

#[test]
fn two_points_far_apart_are_refused_with_one_line_and_the_batch_goes_on() {
    // 3 km apart: a height map of 115 GB (100 m apart is processed now: the distance
    // field follows the points, and the height map of 100 m x 100 m is 128 MB).
    let d = tempfile::tempdir().unwrap();
    let two = write_xyz(
        &d.path().join("two.xyz"),
        &[[0.0; 3], [3000.0, 3000.0, 0.0]],
    );
    let mut stray = small_scene(0.05);
    stray.push([100.0, 100.0, 0.0]);
    let stray = write_xyz(&d.path().join("stray.xyz"), &stray);
    let good = write_xyz(&d.path().join("good.xyz"), &small_scene(0.05));
    let json = d.path().join("all.json");
    let o = afford_limited(
        2 << 30,
        &[
            "detect",
            &s(&two),
            &s(&stray),
            &s(&good),
            "--json",
            &s(&json),
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("two.xyz") && errors[0].contains("over the"),
        "{errors:?}"
    );
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let files: Vec<&str> = j["files"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["file"].as_str().unwrap())
        .collect();
    assert_eq!(files.len(), 2, "{files:?}");
    assert!(files[0].ends_with("stray.xyz") && files[1].ends_with("good.xyz"));
}

#[test]
fn a_large_floor_is_refused_by_the_budget_not_by_an_abort() {
    // 2 km x 2 km of floor every 20 m: a height map of 51 GB (a 200 m floor is processed
    // now: see large_connected_floor.rs).
    let pts: Vec<[f64; 3]> = (0..=100)
        .flat_map(|i| (0..=100).map(move |j| [i as f64 * 20.0, j as f64 * 20.0, 0.0]))
        .collect();
    let e = guard(
        Path::new("floor.xyz"),
        &cloud(&pts),
        &DetectConfig::default(),
        &ExtentConfig::default(),
    )
    .unwrap_err();
    assert!(matches!(e, ExtentError::TooLarge { .. }));
    let m = e.to_string();
    assert!(
        m.starts_with("floor.xyz: the cloud spans 2000.0 x 2000.0"),
        "{m}"
    );
}
