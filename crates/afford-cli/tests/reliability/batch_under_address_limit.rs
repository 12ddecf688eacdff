//! Cause: before the extent guard and the reader fixes, one bad file among many ended the
//! process (an abort on allocation or a panic), taking the batch and its run-wide outputs
//! with it. A batch of 20 files, five of them bad in each of the ways that aborted, must
//! process every other file, say one line per bad one, write the run-wide outputs and
//! exit 2, all under a 2 GB address-space limit.

use crate::common::*;

#[test]
fn twenty_files_five_bad_under_two_gigabytes() {
    let d = tempfile::tempdir().unwrap();
    let dir = d.path().join("in");
    std::fs::create_dir(&dir).unwrap();
    let mut bad = Vec::new();
    let mut stray = small_scene(0.1);
    stray.push([100.0, 100.0, 0.0]);
    stray.push([-100.0, 0.0, 30.0]);
    // A stray point is dropped, not refused: this one is processed.
    write_xyz(&dir.join("b00_stray.xyz"), &stray);
    let mm: Vec<[f64; 3]> = small_scene(0.05)
        .iter()
        .map(|p| p.map(|c| c * 1000.0))
        .collect();
    bad.push(write_xyz(&dir.join("b01_mm.xyz"), &mm));
    let far: Vec<[f64; 3]> = small_scene(0.1)
        .iter()
        .map(|p| p.map(|c| c * 1e30))
        .collect();
    bad.push(write_xyz(&dir.join("b02_e30.xyz"), &far));
    let pcd = dir.join("b03_header.pcd");
    std::fs::write(&pcd, huge_record_pcd()).unwrap();
    bad.push(pcd);
    let off = dir.join("b04_corners.off");
    std::fs::write(&off, huge_corner_off()).unwrap();
    bad.push(off);
    bad.push(write_xyz(
        &dir.join("b05_two.xyz"),
        &[[0.0; 3], [3000.0, 3000.0, 0.0]],
    ));
    for i in 0..14 {
        let pts: Vec<[f64; 3]> = small_scene(0.1)
            .iter()
            .map(|p| [p[0] + i as f64 * 0.01, p[1], p[2]])
            .collect();
        write_xyz(&dir.join(format!("g{i:02}.xyz")), &pts);
    }
    let (json, csv, summary) = (
        d.path().join("all.json"),
        d.path().join("all.csv"),
        d.path().join("summary.csv"),
    );
    let o = afford_limited(
        2_000_000_000,
        &[
            "detect",
            &s(&dir),
            "--json",
            &s(&json),
            "--csv",
            &s(&csv),
            "--summary",
            &s(&summary),
            "--threads",
            "2",
        ],
    );
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    let errors = error_lines(&o);
    assert_eq!(errors.len(), bad.len(), "{err}");
    for (e, b) in errors.iter().zip(&bad) {
        let name = b.file_name().unwrap().to_string_lossy().into_owned();
        assert!(e.contains(&name), "{e} should name {name}");
    }
    assert!(err.contains("20 files, 5 failed"), "{err}");
    let j: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(j["files"].as_array().unwrap().len(), 15);
    assert!(std::fs::read_to_string(&csv).unwrap().starts_with("file,"));
    let sum = std::fs::read_to_string(&summary).unwrap();
    assert_eq!(sum.lines().count(), 1 + 15, "{sum}");
}
