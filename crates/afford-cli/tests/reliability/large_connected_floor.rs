//! Cause: the distance field was a dense grid over the bounding box of the voxels (8 bytes
//! per 2 cm cell), so a large connected scene, a 200 m x 200 m floor with one chair on it,
//! needed 56 GiB of grids and was refused by the extent guard (before the guard, it
//! aborted). The field now keeps its occupied cells as sorted rows and computes distances
//! in 32^3-cell chunks only where a body part asks for them, so the scene is processed,
//! with its detections, under a 2 GB address-space limit.

use afford_synth::scenes::big_floor;

use crate::common::*;

#[test]
fn a_200_m_floor_with_one_chair_is_processed_under_two_gigabytes() {
    let d = tempfile::tempdir().unwrap();
    // A chair in the middle, on a patch of densely sampled floor; the rest of the floor
    // sampled every metre: one connected region.
    let pts = big_floor().points;
    let ply = d.path().join("floor.ply");
    afford::cloud::write_ply_points(&ply, &pts, &[], true).unwrap();
    let json = d.path().join("floor.json");
    let o = afford_limited(
        2_000_000_000,
        &["detect", &s(&ply), "--json", &s(&json), "--threads", "2"],
    );
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(error_lines(&o).is_empty(), "{err}");
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let file = &j["files"][0];
    assert_eq!(file["points"].as_u64(), Some(pts.len() as u64), "{file}");
    let dets = file["detections"].as_array().unwrap();
    assert!(!dets.is_empty(), "{file}");
    // Every detection is on the chair, 200 m from the floor's far corners.
    for det in dets {
        let p = &det["position"];
        let (x, y) = (p[0].as_f64().unwrap(), p[1].as_f64().unwrap());
        assert!((x - 100.0).abs() < 1.5 && (y - 100.0).abs() < 1.5, "{det}");
    }
}
