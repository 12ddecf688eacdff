//! A small reader of triangle-mesh PLY files (vertex `x`, `y`, `z` and a face list
//! `vertex_indices`), for rendering depth views of external models.
//!
//! Handles `ascii`, `binary_little_endian` and `binary_big_endian`, scalar properties of
//! every PLY type, other vertex properties and other elements (skipped). Polygons with
//! more than three corners are split into a triangle fan. Units are taken as they are
//! (the real models are metres, z up).

use crate::cloud::{parse_header, CloudError, Encoding, Kind};
use std::path::{Path, PathBuf};

use nalgebra::Point3;

use super::{Mesh, Part};
use crate::num::{index32, to_usize};

/// What went wrong reading a mesh file.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    /// The file could not be read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The header is malformed (the PLY header parser of the point readers, which names
    /// the line).
    #[error(transparent)]
    Header(#[from] CloudError),
    /// The body is not a mesh this reader understands.
    #[error("{path}: {what}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

/// Reads a triangle mesh from a PLY file; every triangle is labelled [`Part::Other`].
/// The header is read by the same parser as point clouds' ([`crate::cloud::read_ply`]).
pub fn read_mesh_ply(path: &Path) -> Result<Mesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_mesh_ply(&bytes, path)
}

/// The mesh of the PLY file `bytes` (`path` only names it in errors), as
/// [`read_mesh_ply`]: element counts that cannot fit in the file are refused before
/// anything is allocated.
pub fn parse_mesh_ply(bytes: &[u8], path: &Path) -> Result<Mesh, MeshError> {
    let err = |what: String| MeshError::Format {
        path: path.to_path_buf(),
        what,
    };
    let mut r: &[u8] = bytes;
    let header = parse_header(path, &mut r)?;
    if let Some(e) = header
        .elements
        .iter()
        .find(|e| e.count > bytes.len() as u64)
    {
        return Err(MeshError::Header(CloudError::Header {
            path: path.to_path_buf(),
            at: format!("line {}", e.line),
            what: format!(
                "element '{}' count '{}' cannot fit in a file of {} bytes",
                e.name,
                e.count,
                bytes.len()
            ),
        }));
    }
    let data = r;
    let mut mesh = Mesh::new();
    let mut vertices: Vec<Point3<f64>> = Vec::new();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    let short = || err("file too short for its header".into());
    let ascii_text;
    let mut toks = None;
    let (mut pos, big) = (0usize, header.encoding == Encoding::BinaryBe);
    if header.encoding == Encoding::Ascii {
        ascii_text = String::from_utf8_lossy(data);
        toks = Some(ascii_text.split_ascii_whitespace());
    }
    // The next value of the body, as the scalar type `ty` (binary) or a number (ascii).
    let mut next = |ty: crate::cloud::Scalar| -> Result<f64, MeshError> {
        match toks.as_mut() {
            Some(t) => {
                let t = t.next().ok_or_else(short)?;
                t.parse::<f64>()
                    .map_err(|_| err(format!("'{t}' is not a number")))
            }
            None => {
                let s = data.get(pos..pos + ty.size()).ok_or_else(short)?;
                pos += ty.size();
                Ok(ty.decode(s, big))
            }
        }
    };
    for e in &header.elements {
        for _ in 0..e.count {
            let mut xyz = [0.0; 3];
            let mut face = Vec::new();
            for p in &e.props {
                match p.kind {
                    Kind::List(count, item) => {
                        let n = next(count)?;
                        if !(0.0..=1e6).contains(&n) {
                            return Err(err(format!("bad list length {n}")));
                        }
                        for _ in 0..to_usize(n) {
                            let v = next(item)?;
                            if e.name == "face" {
                                // An index is a whole number from 0: `as` would read -1 as 0.
                                if !(v >= 0.0 && v.fract() == 0.0) {
                                    return Err(err(format!("bad face index {v}")));
                                }
                                face.push(to_usize(v));
                            }
                        }
                    }
                    Kind::Scalar(ty) => {
                        let v = next(ty)?;
                        if let Some(k) = ["x", "y", "z"].iter().position(|n| *n == p.name) {
                            xyz[k] = v;
                        }
                    }
                }
            }
            match e.name.as_str() {
                "vertex" => vertices.push(Point3::from(xyz)),
                "face" => faces.push(face),
                _ => {}
            }
        }
    }
    if vertices.is_empty() || faces.is_empty() {
        return Err(err("no vertices or no faces".into()));
    }
    let nv = vertices.len();
    mesh.vertices = vertices;
    for f in faces {
        if f.iter().any(|&i| i >= nv) {
            return Err(err(format!("face index out of range (vertices: {nv})")));
        }
        for k in 1..f.len().saturating_sub(1) {
            mesh.triangles
                .push([index32(f[0]), index32(f[k]), index32(f[k + 1])]);
            mesh.parts.push(Part::Other);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_negative_or_fractional_face_index_is_an_error() {
        let dir = tempfile::tempdir().unwrap();
        for (bad, says) in [("-1", "bad face index -1"), ("1.5", "bad face index 1.5")] {
            let ascii = format!(
                "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                 property float y\nproperty float z\n\
                 element face 1\nproperty list uchar float vertex_indices\nend_header\n\
                 0 0 0\n1 0 0\n1 1 0\n3 {bad} 1 2\n"
            );
            let p = dir.path().join("a.ply");
            std::fs::write(&p, ascii).unwrap();
            let e = read_mesh_ply(&p).unwrap_err().to_string();
            assert!(e.contains(says), "{e}");
        }
    }

    #[test]
    fn reads_ascii_and_binary_quads_as_triangles() {
        let dir = tempfile::tempdir().unwrap();
        let ascii = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                     property float y\nproperty float z\nproperty uchar red\n\
                     element face 1\nproperty list uchar int vertex_indices\nend_header\n\
                     0 0 0 9\n1 0 0 9\n1 1 0 9\n0 1 0 9\n4 0 1 2 3\n";
        let p = dir.path().join("a.ply");
        std::fs::write(&p, ascii).unwrap();
        let m = read_mesh_ply(&p).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3]]);
        assert!((m.area() - 1.0).abs() < 1e-12);

        let mut b = b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n\
                      property double x\nproperty double y\nproperty double z\n\
                      element face 1\nproperty list uchar uint vertex_indices\nend_header\n"
            .to_vec();
        for v in [[0.0f64, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]] {
            for c in v {
                b.extend_from_slice(&c.to_le_bytes());
            }
        }
        b.push(3);
        for i in [0u32, 1, 2] {
            b.extend_from_slice(&i.to_le_bytes());
        }
        let p = dir.path().join("b.ply");
        std::fs::write(&p, &b).unwrap();
        let m = read_mesh_ply(&p).unwrap();
        assert_eq!(m.triangles, vec![[0, 1, 2]]);
        assert!((m.area() - 2.0).abs() < 1e-12);
        // Truncated: an error, not a panic.
        std::fs::write(&p, &b[..b.len() - 3]).unwrap();
        assert!(read_mesh_ply(&p).is_err());
    }

    #[test]
    fn the_header_is_read_by_the_point_readers_parser_which_names_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("bad.ply");
        let text = "ply\nformat ascii 1.0\nelement vertex 3\nproperty flot x\nend_header\n";
        std::fs::write(&p, text).unwrap();
        let e = read_mesh_ply(&p).unwrap_err();
        assert!(matches!(e, MeshError::Header(_)), "{e}");
        assert!(e.to_string().contains("line 4"), "{e}");
    }
}
