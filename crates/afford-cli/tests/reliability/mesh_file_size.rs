//! Cause: the mesh readers read the whole file into memory with no limit (`/dev/zero`
//! named `.obj` grew to 4 GB). Mesh files over `MAX_MESH_BYTES` are refused before they
//! are read, and special files are refused as not files.

use std::io::{Seek, SeekFrom, Write};

#[test]
fn an_oversized_mesh_is_refused_before_reading() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("big.obj");
    // A sparse file one byte over the limit: no disk is used.
    let mut f = std::fs::File::create(&p).unwrap();
    f.seek(SeekFrom::Start(afford::cloud::mesh::MAX_MESH_BYTES))
        .unwrap();
    f.write_all(b"\n").unwrap();
    drop(f);
    let e = afford::cloud::mesh::read_mesh(&p).unwrap_err().to_string();
    assert!(e.contains("big.obj") && e.contains("more than"), "{e}");
}
