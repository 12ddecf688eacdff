//! E57: two scans with their poses, written with the `e57` crate.

use std::path::Path;

use afford::cloud::source::{read_parts, SourceOptions};
use e57::{E57Writer, Quaternion, Record, RecordValue, Transform, Translation};
use nalgebra::Point3;

use super::*;

/// The pose of scan 2: a half turn about z and a shift (exact in floating point).
const SHIFT: [f64; 3] = [2.0, -1.5, 0.0];

/// Writes `scans` (points in each scan's own frame) with `poses` (half turn or not).
fn write_e57(path: &Path, scans: &[Vec<Point3<f64>>], half_turn: &[bool]) {
    let mut w = E57Writer::from_file(path, "file-guid").unwrap();
    for (i, (s, turn)) in scans.iter().zip(half_turn).enumerate() {
        let proto = vec![
            Record::CARTESIAN_X_F64,
            Record::CARTESIAN_Y_F64,
            Record::CARTESIAN_Z_F64,
        ];
        let mut pc = w.add_pointcloud(&format!("scan-{i}"), proto).unwrap();
        if *turn {
            pc.set_transform(Some(Transform {
                rotation: Quaternion {
                    w: 0.0,
                    x: 0.0,
                    y: 0.0,
                    z: 1.0,
                },
                translation: Translation {
                    x: SHIFT[0],
                    y: SHIFT[1],
                    z: SHIFT[2],
                },
            }));
        }
        for p in s {
            pc.add_point(vec![
                RecordValue::Double(p.x),
                RecordValue::Double(p.y),
                RecordValue::Double(p.z),
            ])
            .unwrap();
        }
        pc.finalize().unwrap();
    }
    w.finalize().unwrap();
}

#[test]
fn merged_scans_with_poses_give_the_detections_of_the_same_points_as_ply() {
    let d = tempfile::tempdir().unwrap();
    let world = chair_scene(30.0, 3);
    let (first, second) = world.split_at(world.len() / 2);
    // Scan 2 is stored in its own frame: the inverse of its pose (a half turn is its
    // own inverse), exact for these quantised coordinates.
    let local: Vec<Point3<f64>> = second
        .iter()
        .map(|p| Point3::new(-(p.x - SHIFT[0]), -(p.y - SHIFT[1]), p.z - SHIFT[2]))
        .collect();
    let e57 = d.path().join("site.e57");
    write_e57(&e57, &[first.to_vec(), local], &[false, true]);

    let ply = d.path().join("site.ply");
    write_ply_f64(&ply, &world);
    let want = detect_json(d.path(), &ply, &[]);
    assert_finds_a_seat(&want, 0);
    let got = detect_json(d.path(), &e57, &[]);
    assert_eq!(detections(&got, 0), detections(&want, 0));

    // --scan 2: the second scan alone, posed into the file's frame.
    let mut pts = Vec::new();
    let opts = SourceOptions {
        scan: Some(2),
        ..Default::default()
    };
    read_parts(&e57, &opts, &mut |p| pts = p.cloud.cloud.points).unwrap();
    assert_eq!(pts, second);
    let e = read_parts(
        &e57,
        &SourceOptions {
            scan: Some(3),
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("site.e57") && e.contains("2 scans"), "{e}");
}

#[test]
fn a_damaged_e57_is_one_line_naming_the_file() {
    let d = tempfile::tempdir().unwrap();
    let e57 = d.path().join("s.e57");
    let pts: Vec<Point3<f64>> = (0..50).map(|i| Point3::new(i as f64, 0.0, 1.0)).collect();
    write_e57(&e57, &[pts], &[false]);
    let bytes = std::fs::read(&e57).unwrap();
    let cut = d.path().join("cut.e57");
    for n in (0..bytes.len()).step_by(97) {
        std::fs::write(&cut, &bytes[..n]).unwrap();
        let e = read_parts(&cut, &SourceOptions::default(), &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&cut.display().to_string()) && !e.contains('\n'),
            "{e}"
        );
    }
}

/// Fuzz seed: two scans, one posed.
pub(crate) fn seed(path: &Path, pts: &[Point3<f64>]) {
    write_e57(path, &[pts.to_vec(), pts.to_vec()], &[false, true]);
}
