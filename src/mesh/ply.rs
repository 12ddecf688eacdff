//! A small reader of triangle-mesh PLY files (vertex `x`, `y`, `z` and a face list
//! `vertex_indices`), for rendering depth views of external models.
//!
//! Handles `ascii`, `binary_little_endian` and `binary_big_endian`, scalar properties of
//! every PLY type, other vertex properties and other elements (skipped). Polygons with
//! more than three corners are split into a triangle fan. Units are taken as they are
//! (the real models are metres, z up).

use crate::cloud::Scalar;
use std::path::{Path, PathBuf};

use nalgebra::Point3;

use super::{Mesh, Part};

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
    /// The file is not a mesh PLY this reader understands.
    #[error("{path}: {what}")]
    Format {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

struct Prop {
    name: String,
    /// `Some(count type)` for a list.
    list: Option<Scalar>,
    ty: Scalar,
}

struct Elem {
    name: String,
    count: usize,
    props: Vec<Prop>,
}

/// Reads a triangle mesh from a PLY file; every triangle is labelled [`Part::Other`].
pub fn read_mesh_ply(path: &Path) -> Result<Mesh, MeshError> {
    let bytes = std::fs::read(path).map_err(|source| MeshError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let err = |what: String| MeshError::Format {
        path: path.to_path_buf(),
        what,
    };
    let end = b"end_header";
    let hpos = bytes
        .windows(end.len())
        .position(|w| w == end)
        .ok_or_else(|| err("no end_header".into()))?;
    let mut body = hpos + end.len();
    while body < bytes.len() && bytes[body] != b'\n' {
        body += 1;
    }
    body += 1;
    let header = String::from_utf8_lossy(&bytes[..hpos]);
    let mut format = "";
    let mut elems: Vec<Elem> = Vec::new();
    for line in header.lines() {
        let t: Vec<&str> = line.split_ascii_whitespace().collect();
        match t.as_slice() {
            ["format", f, ..] => format = f,
            ["element", name, count] => elems.push(Elem {
                name: name.to_string(),
                count: count
                    .parse()
                    .map_err(|_| err(format!("bad element count '{count}'")))?,
                props: Vec::new(),
            }),
            ["property", "list", c, i, name] => {
                let (Some(c), Some(i)) = (Scalar::parse(c), Scalar::parse(i)) else {
                    return Err(err(format!("bad list property '{line}'")));
                };
                let e = elems
                    .last_mut()
                    .ok_or_else(|| err("property before element".into()))?;
                e.props.push(Prop {
                    name: name.to_string(),
                    list: Some(c),
                    ty: i,
                });
            }
            ["property", ty, name] => {
                let ty = Scalar::parse(ty).ok_or_else(|| err(format!("bad property '{line}'")))?;
                let e = elems
                    .last_mut()
                    .ok_or_else(|| err("property before element".into()))?;
                e.props.push(Prop {
                    name: name.to_string(),
                    list: None,
                    ty,
                });
            }
            _ => {}
        }
    }
    let data = &bytes[body.min(bytes.len())..];
    let mut mesh = Mesh::new();
    let mut vertices: Vec<Point3<f64>> = Vec::new();
    let mut faces: Vec<Vec<usize>> = Vec::new();
    let short = || err("file too short for its header".into());
    match format {
        "binary_little_endian" | "binary_big_endian" => {
            let big = format == "binary_big_endian";
            let mut pos = 0usize;
            let mut take = |n: usize| -> Result<&[u8], MeshError> {
                let s = data.get(pos..pos + n).ok_or_else(short)?;
                pos += n;
                Ok(s)
            };
            for e in &elems {
                for _ in 0..e.count {
                    let mut xyz = [0.0; 3];
                    let mut face = Vec::new();
                    for p in &e.props {
                        if let Some(ct) = p.list {
                            let n = ct.decode(take(ct.size())?, big);
                            if !(0.0..=1e6).contains(&n) {
                                return Err(err(format!("bad list length {n}")));
                            }
                            for _ in 0..n as usize {
                                let v = p.ty.decode(take(p.ty.size())?, big);
                                if e.name == "face" {
                                    face.push(v as usize);
                                }
                            }
                        } else {
                            let v = p.ty.decode(take(p.ty.size())?, big);
                            if let Some(k) = ["x", "y", "z"].iter().position(|n| *n == p.name) {
                                xyz[k] = v;
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
        }
        "ascii" => {
            let text = String::from_utf8_lossy(data);
            let mut toks = text.split_ascii_whitespace();
            let mut next = || -> Result<f64, MeshError> {
                let t = toks.next().ok_or_else(short)?;
                t.parse::<f64>()
                    .map_err(|_| err(format!("'{t}' is not a number")))
            };
            for e in &elems {
                for _ in 0..e.count {
                    let mut xyz = [0.0; 3];
                    let mut face = Vec::new();
                    for p in &e.props {
                        if p.list.is_some() {
                            let n = next()?;
                            if !(0.0..=1e6).contains(&n) {
                                return Err(err(format!("bad list length {n}")));
                            }
                            for _ in 0..n as usize {
                                let v = next()?;
                                if e.name == "face" {
                                    face.push(v as usize);
                                }
                            }
                        } else {
                            let v = next()?;
                            if let Some(k) = ["x", "y", "z"].iter().position(|n| *n == p.name) {
                                xyz[k] = v;
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
        }
        other => return Err(err(format!("unknown format '{other}'"))),
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
                .push([f[0] as u32, f[k] as u32, f[k + 1] as u32]);
            mesh.parts.push(Part::Other);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

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
}
