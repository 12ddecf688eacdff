//! Cause: every write to standard output was `let _ = ...`, so the table or `--log-json`
//! sent to a full device was lost with exit 0. The first such error is now reported as one
//! line at the end and the exit code is 2.

use std::process::{Command, Stdio};

use crate::common::*;

#[test]
fn a_table_to_a_full_device_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let x = write_xyz(&d.path().join("x.xyz"), &small_scene(0.1));
    for extra in [None, Some("--log-json")] {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let mut args = vec!["detect".to_string(), s(&x)];
        args.extend(extra.map(String::from));
        let o = Command::new(env!("CARGO_BIN_EXE_afford"))
            .args(&args)
            .stdout(Stdio::from(full))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "{extra:?}");
        let err = text(&o.stderr);
        assert!(
            err.contains("error: standard output: cannot write"),
            "{err}"
        );
    }
}
