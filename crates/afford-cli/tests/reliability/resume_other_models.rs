//! Cause: `--resume` skipped any input whose JSON was in `--out-dir`, whatever bodies and
//! hierarchies had made it, so one folder could mix heights and hierarchies without a
//! word. A saved result made with other models is now an error for that input.

use crate::common::*;

#[test]
fn resume_refuses_a_saved_result_of_other_models() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    let out = d.path().join("out");
    let run = |extra: &[&str]| {
        let mut a = vec!["detect", "--out-dir"];
        let o = s(&out);
        let xs = s(&x);
        a.push(&o);
        a.push("--resume");
        a.push(&xs);
        a.extend_from_slice(extra);
        afford(&a)
    };
    assert_eq!(run(&["--height", "1.75"]).status.code(), Some(0));
    // The same models: skipped.
    let o = run(&[]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    // Another height: refused, naming both.
    let o = run(&["--height", "1.65"]);
    assert_eq!(o.status.code(), Some(2));
    let errors = error_lines(&o);
    assert_eq!(errors.len(), 1, "{errors:?}");
    assert!(
        errors[0].contains("other models")
            && errors[0].contains("1.650")
            && errors[0].contains("1.750"),
        "{errors:?}"
    );
    // Another hierarchy set: refused too.
    let o = run(&["--affordances", "sitting"]);
    assert_eq!(o.status.code(), Some(2));
}
