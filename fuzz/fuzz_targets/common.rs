//! Shared by the fuzz targets: the readers take paths, so each input is written to a
//! file in a per-process temporary directory (overwritten on every run).

use std::path::PathBuf;

/// Writes `bytes` to `<tmp>/afford-fuzz-<pid>/input.<ext>` and returns the path.
pub fn temp_file(ext: &str, bytes: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("afford-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("create fuzz temp dir");
    let path = dir.join(format!("input.{ext}"));
    std::fs::write(&path, bytes).expect("write fuzz input");
    path
}
