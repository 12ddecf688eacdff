//! Cause: `--segments`/`--mesh` name each input's file after the input's stem
//! (`seg.chair.ply`), so `a/chair.ply`, `a/chair.pcd` and `b/chair.ply` all wrote
//! `seg.chair.ply`, the last one winning, exit 0. Such a run is now refused before
//! anything runs, naming both inputs.

use crate::common::*;

#[test]
fn inputs_sharing_a_stem_are_refused_for_per_input_outputs() {
    let d = tempfile::tempdir().unwrap();
    for sub in ["a", "b"] {
        std::fs::create_dir(d.path().join(sub)).unwrap();
    }
    let a = write_xyz(&d.path().join("a/chair.xyz"), &small_scene(0.1));
    let b = write_xyz(&d.path().join("b/chair.xyz"), &small_scene(0.1));
    let seg = d.path().join("seg.ply");
    let o = afford(&["detect", &s(&a), &s(&b), "--segments", &s(&seg)]);
    assert_eq!(o.status.code(), Some(2));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("a/chair.xyz") && errors[0].contains("b/chair.xyz"),
        "{errors:?}"
    );
    assert!(!d.path().join("seg.chair.ply").exists());
    // Distinct stems are fine.
    let c = write_xyz(&d.path().join("b/table.xyz"), &small_scene(0.1));
    let o = afford(&["detect", &s(&a), &s(&c), "--segments", &s(&seg)]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    assert!(d.path().join("seg.chair.ply").exists() && d.path().join("seg.table.ply").exists());
}
