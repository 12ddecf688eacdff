//! Cause: the outputs were written wherever they were asked to go, so `--json x.ply`,
//! `--segments x.ply` or `--mesh x.ply` on input `x.ply` replaced the input and exited 0.
//! An output that is an input of the run is now refused before anything runs.

use crate::common::*;

#[test]
fn an_output_naming_an_input_is_refused_and_the_input_kept() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let before = std::fs::read(&x).unwrap();
    for flag in ["--json", "--csv", "--summary", "--segments", "--mesh"] {
        let o = afford(&["detect", &s(&x), flag, &s(&x)]);
        assert_eq!(o.status.code(), Some(2), "{flag}");
        let errors = error_lines(&o);
        assert_eq!(errors.len(), 1, "{flag}: {errors:?}");
        assert!(errors[0].contains("refusing to replace"), "{errors:?}");
        assert_eq!(
            std::fs::read(&x).unwrap(),
            before,
            "{flag} replaced the input"
        );
    }
    let o = afford(&["convert", &s(&x), &s(&x)]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&x).unwrap(), before);
}
