//! Inputs found by the cargo-fuzz targets in `fuzz/` that once made a reader panic, kept
//! as regression tests: each must now give an `Err`, not a panic. Also checks that the
//! committed seed corpora (`fuzz/corpus/`) are valid files the readers accept.

use std::path::{Path, PathBuf};

use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;

/// Writes `bytes` to `name` in a fresh temporary directory.
fn file(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

fn builtin() -> Agent {
    Agent::from_toml(
        afford::model::set::BUILTIN_AGENT,
        Path::new("human.toml"),
        1.75,
    )
    .unwrap()
}

fn corpus(target: &str) -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fuzz/corpus")
        .join(target);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("seed_"))
        })
        .map(|p| {
            let name = p.file_name().unwrap().to_str().unwrap().to_string();
            (name, std::fs::read(&p).unwrap())
        })
        .collect();
    out.sort();
    assert!(!out.is_empty(), "no seeds in {}", dir.display());
    out
}

#[test]
fn seed_corpora_are_valid() {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in corpus("ply") {
        let p = file(&dir, "seed.ply", &bytes);
        let pts = afford::cloud::read_ply(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!pts.is_empty(), "{name}");
        if name.contains("mesh") {
            let m = afford::cloud::mesh::read_mesh(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(!m.triangles.is_empty(), "{name}");
        }
    }
    for (name, bytes) in corpus("pcd") {
        let p = file(&dir, "seed.pcd", &bytes);
        let pts = afford::cloud::read_pcd(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!pts.is_empty(), "{name}");
    }
    for (name, bytes) in corpus("mesh") {
        let ext = ["obj", "off", "stl"][usize::from(bytes[0] % 3)];
        let p = file(&dir, &format!("seed.{ext}"), &bytes[1..]);
        let m = afford::cloud::mesh::read_mesh(&p).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(!m.triangles.is_empty(), "{name}");
    }
    for (name, bytes) in corpus("bag") {
        if name.ends_with(".mcap") {
            // Each seed bag holds two PointCloud2 messages (plain, lz4 and zstd chunks).
            let p = file(&dir, "seed.mcap", &bytes);
            let opts = afford::cloud::source::SourceOptions::default();
            let n = afford::cloud::source::read_parts(&p, &opts, &mut |_| {})
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(n, 2, "{name}");
        }
    }
    let agent = builtin();
    for (name, bytes) in corpus("toml") {
        let text = String::from_utf8(bytes).unwrap();
        let loaded = if name.contains("human") || name.contains("child") {
            Agent::from_toml(&text, Path::new("f.toml"), 1.75).map(|_| ())
        } else {
            Hierarchy::from_toml(&text, Path::new("f.toml"), &agent).map(|_| ())
        };
        // The TOML seeds are copies of agents/*.toml and affordances/*.toml: when the
        // model format changes, copy them again.
        loaded.unwrap_or_else(|e| panic!("{name} (copy the current model file over it): {e}"));
    }
}
