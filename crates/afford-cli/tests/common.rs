//! Helpers shared by the command line's integration tests (`cli`, `batch`, `reliability`):
//! running the built binary, small clouds.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs `afford` with `args` in the crate folder.
pub(crate) fn afford(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_afford"))
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .args(args)
        .output()
        .expect("runs")
}

/// Runs `afford` under an address-space limit of `bytes` (the `prlimit` command; the crate
/// forbids the unsafe code a `pre_exec` setrlimit would need).
pub(crate) fn afford_limited(bytes: u64, args: &[&str]) -> Output {
    Command::new("prlimit")
        .arg(format!("--as={bytes}"))
        .arg(env!("CARGO_BIN_EXE_afford"))
        .current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .args(args)
        .output()
        .expect("prlimit runs")
}

/// Standard error (or output) as text.
pub(crate) fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A path as an argument.
pub(crate) fn s(p: &Path) -> String {
    p.display().to_string()
}

/// The committed sample room.
pub(crate) const SAMPLE: &str = "data/sample/room.ply";

/// A seat-sized scene in metres: a 2 m x 2 m floor and a 0.5 m x 0.5 m box top at 0.45 m,
/// sampled every `step` metres, as `x y z` rows.
// `step` is a positive literal of a test: the counts are a few hundred at most.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
pub(crate) fn small_scene(step: f64) -> Vec<[f64; 3]> {
    let mut pts = Vec::new();
    let n = (2.0 / step) as usize;
    for i in 0..n {
        for j in 0..n {
            pts.push([i as f64 * step, j as f64 * step, 0.0]);
        }
    }
    let m = (0.5 / step) as usize;
    for i in 0..m {
        for j in 0..m {
            pts.push([0.75 + i as f64 * step, 0.75 + j as f64 * step, 0.45]);
        }
    }
    pts
}

/// Writes points as an `.xyz` file.
pub(crate) fn write_xyz(path: &Path, pts: &[[f64; 3]]) -> PathBuf {
    let mut t = String::new();
    for p in pts {
        t.push_str(&format!("{} {} {}\n", p[0], p[1], p[2]));
    }
    std::fs::write(path, t).unwrap();
    path.to_path_buf()
}

/// The stderr lines starting with `error:`.
pub(crate) fn error_lines(o: &Output) -> Vec<String> {
    text(&o.stderr)
        .lines()
        .filter(|l| l.starts_with("error:"))
        .map(str::to_string)
        .collect()
}

/// A 125 KB PCD header: 7000 fields of SIZE 8 and COUNT 1048576, POINTS 0 (its record
/// would take 58.7 GB).
pub(crate) fn huge_record_pcd() -> Vec<u8> {
    let n = 7000;
    let names: Vec<String> = ["x", "y", "z"]
        .iter()
        .map(|s| s.to_string())
        .chain((3..n).map(|i| format!("f{i}")))
        .collect();
    let rep = |t: &str| vec![t; n].join(" ");
    format!(
        "# .PCD v0.7\nVERSION 0.7\nFIELDS {}\nSIZE {}\nTYPE {}\nCOUNT {}\nWIDTH 0\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS 0\nDATA binary\n",
        names.join(" "),
        rep("8"),
        rep("F"),
        rep("1048576")
    )
    .into_bytes()
}

/// A 55-byte OFF file whose face says it has 2^64 - 1 corners.
pub(crate) fn huge_corner_off() -> Vec<u8> {
    b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n18446744073709551615 0 1 2\n".to_vec()
}
