//! Cause: the PLY and PCD readers stopped after the count the header declares, so a count
//! smaller than the body (`element vertex 5` over 13,121 vertices, `POINTS 5` over 100)
//! silently truncated the cloud. Data beyond the declared rows is now an error.

use std::path::Path;

fn load(dir: &Path, name: &str, bytes: &[u8]) -> String {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    afford::cloud::load(&p)
        .map(|c| format!("ok {}", c.cloud.len()))
        .unwrap_or_else(|e| e.to_string())
}

#[test]
fn a_body_longer_than_its_header_count_is_an_error() {
    let d = tempfile::tempdir().unwrap();
    let rows: String = (0..20).map(|i| format!("{i} 0 0\n")).collect();
    let ply = format!("ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n{rows}");
    assert!(load(d.path(), "a.ply", ply.as_bytes()).contains("goes on after the 5"));
    let exact = format!("ply\nformat ascii 1.0\nelement vertex 20\nproperty float x\nproperty float y\nproperty float z\nend_header\n{rows}\n");
    assert_eq!(load(d.path(), "b.ply", exact.as_bytes()), "ok 20");
    let mut bin = b"ply\nformat binary_little_endian 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\nend_header\n".to_vec();
    for i in 0..20 {
        for c in [i as f32, 0.0, 0.0] {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    assert!(load(d.path(), "c.ply", &bin).contains("goes on after the 5"));
    let head = |n: usize, data: &str| {
        format!("VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA {data}\n")
    };
    let pcd = head(5, "ascii") + &rows;
    assert!(load(d.path(), "d.pcd", pcd.as_bytes()).contains("POINTS too small"));
    let mut pcdb = head(5, "binary").into_bytes();
    pcdb.extend_from_slice(&bin[bin.len() - 20 * 12..]);
    assert!(load(d.path(), "e.pcd", &pcdb).contains("POINTS too small"));
    let ok = head(20, "ascii") + &rows;
    assert_eq!(load(d.path(), "f.pcd", ok.as_bytes()), "ok 20");
}
