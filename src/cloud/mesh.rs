//! Triangle-mesh readers (OBJ, OFF, STL, PLY with faces) and surface sampling, to turn
//! 3D models into point clouds.
//!
//! Coordinates are taken as they are in the file (whatever unit and up axis the model
//! uses); bring the sampled cloud into the world frame with [`super::frame::to_world`].
//! Every triangle is labelled [`Part::Other`]. Polygons are split into triangle fans.
//! Bad input gives one [`CloudError`] naming the file and the line or byte, never a
//! panic, and counts in headers are checked against the file size before anything is
//! allocated from them.

use std::path::Path;

use nalgebra::Point3;

use std::borrow::Cow;

use super::{CloudError, PointCloud};
use crate::mesh::ply::{parse_mesh_ply, MeshError};
use crate::mesh::{sample_surface, Mesh, Part};
use crate::num::{capacity, index32 as index};

/// [`sample_mesh`] never draws more than about this many points: a higher density is
/// lowered to fit.
pub const MAX_SAMPLES: f64 = 5e7;

/// Reads a triangle mesh, choosing the reader by extension: `.obj`, `.off`, `.stl`
/// (ascii or binary) or `.ply` (ascii or binary, with a face element). Coordinates are
/// kept as in the file.
pub fn read_mesh(path: &Path) -> Result<Mesh, CloudError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "obj" => read_obj(path),
        "off" => read_off(path),
        "stl" => read_stl(path),
        "ply" => read_ply_mesh(path),
        _ => Err(CloudError::Header {
            path: path.to_path_buf(),
            at: "file name".into(),
            what: format!("unknown mesh format '.{ext}' (expected .obj, .off, .stl or .ply)"),
        }),
    }
}

/// Reads a Wavefront OBJ file: `v x y z` vertices and `f` faces (`f 1 2 3`, `f 1/1 2/2
/// 3/3`, `f 1//1 ...`, `f 1/1/1 ...`; negative indices count back from the last vertex
/// read). Other statements (`vn`, `vt`, `o`, `g`, `usemtl`, ...) are ignored.
pub fn read_obj(path: &Path) -> Result<Mesh, CloudError> {
    parse_obj(&read_bytes(path)?, path)
}

/// Reads an ascii OFF file (`OFF`, also `COFF`, `NOFF`, `STOFF` ...; the counts may
/// follow on the same line; `#` comments). Binary OFF is refused.
pub fn read_off(path: &Path) -> Result<Mesh, CloudError> {
    parse_off(&read_bytes(path)?, path)
}

/// Reads an STL file, binary when its size is exactly `84 + 50 n` bytes for the `n` in
/// its header, ascii (`solid ... facet ... vertex ... endsolid`) otherwise.
pub fn read_stl(path: &Path) -> Result<Mesh, CloudError> {
    parse_stl(&read_bytes(path)?, path)
}

/// Reads a PLY mesh (the file once, within the mesh size limit) with
/// [`parse_mesh_ply`], which checks its element counts against the file size.
pub fn read_ply_mesh(path: &Path) -> Result<Mesh, CloudError> {
    let bytes = read_bytes(path)?;
    parse_mesh_ply(&bytes, path).map_err(|e| match e {
        MeshError::Io { path, source } => CloudError::Io { path, source },
        MeshError::Header(e) => e,
        MeshError::Format { path, what } => CloudError::Body {
            path,
            at: "PLY body".into(),
            what,
        },
    })
}

/// Samples points uniformly over the mesh surface, `points_per_m2` per square unit of the
/// mesh's coordinates (square metres for a mesh in metres; for a mesh in millimetres pass
/// the density times 1e-6), without noise: the same mesh, density and seed give the same
/// points. The expected count is `mesh.area() * points_per_m2`, capped at
/// [`MAX_SAMPLES`]. Coordinates are those of the mesh.
///
/// Triangles whose area is not finite (corners near 1e200 overflow the cross product)
/// are left out: with them the total area was NaN, the cap test false, and a cap-sized
/// mesh beside them was sampled without limit.
pub fn sample_mesh(mesh: &Mesh, points_per_m2: f64, seed: u64) -> PointCloud {
    let kept = finite_triangles(mesh);
    sample_surface(&kept, capped_density(&kept, points_per_m2), 0.0, seed).0
}

/// The number of points [`sample_mesh`] draws from `mesh` at `points_per_m2`, in
/// expectation: at most [`MAX_SAMPLES`], whatever the mesh.
pub fn expected_samples(mesh: &Mesh, points_per_m2: f64) -> f64 {
    let kept = finite_triangles(mesh);
    kept.area() * capped_density(&kept, points_per_m2)
}

/// `mesh` without its triangles of non-finite area (borrowed when it has none).
fn finite_triangles(mesh: &Mesh) -> Cow<'_, Mesh> {
    let finite = |i: &usize| mesh.triangle_area(*i).is_finite();
    if (0..mesh.triangles.len()).all(|i| finite(&i)) {
        return Cow::Borrowed(mesh);
    }
    let keep: Vec<usize> = (0..mesh.triangles.len()).filter(finite).collect();
    Cow::Owned(Mesh {
        vertices: mesh.vertices.clone(),
        triangles: keep.iter().map(|&i| mesh.triangles[i]).collect(),
        parts: keep.iter().map(|&i| mesh.parts[i]).collect(),
    })
}

/// `points_per_m2`, lowered so that the finite-area `mesh` gets at most [`MAX_SAMPLES`].
fn capped_density(mesh: &Mesh, points_per_m2: f64) -> f64 {
    let area = mesh.area();
    if area > 0.0 && area * points_per_m2 > MAX_SAMPLES {
        MAX_SAMPLES / area
    } else {
        points_per_m2
    }
}

/// Largest mesh file read, bytes: the readers hold the whole file, and 1 GiB is a binary
/// STL of 21 million triangles (sampled at the default density, far beyond the point cap).
pub const MAX_MESH_BYTES: u64 = 1 << 30;

/// Reads the whole file, refusing more than [`MAX_MESH_BYTES`] (also from endless
/// sources such as `/dev/zero`, which have no size to check first).
fn read_bytes(path: &Path) -> Result<Vec<u8>, CloudError> {
    use std::io::Read;
    let io = |source| CloudError::Io {
        path: path.to_path_buf(),
        source,
    };
    super::regular_file(path)?;
    let mut f = std::fs::File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let too_big = || {
        header_err(
            path,
            "file size".into(),
            format!("a mesh of more than {MAX_MESH_BYTES} bytes is not read (convert it to a cloud first)"),
        )
    };
    if len > MAX_MESH_BYTES {
        return Err(too_big());
    }
    let mut bytes = Vec::with_capacity(capacity(len, usize::MAX));
    f.by_ref()
        .take(MAX_MESH_BYTES)
        .read_to_end(&mut bytes)
        .map_err(io)?;
    if bytes.len() as u64 == MAX_MESH_BYTES && f.read(&mut [0u8; 1]).map_err(io)? > 0 {
        return Err(too_big());
    }
    Ok(bytes)
}

fn header_err(path: &Path, at: String, what: String) -> CloudError {
    CloudError::Header {
        path: path.to_path_buf(),
        at,
        what,
    }
}

fn body_err(path: &Path, at: String, what: String) -> CloudError {
    CloudError::Body {
        path: path.to_path_buf(),
        at,
        what,
    }
}

/// Parses one finite coordinate.
fn coord(tok: Option<&str>, path: &Path, line: usize) -> Result<f64, CloudError> {
    let tok = tok.ok_or_else(|| {
        body_err(
            path,
            format!("line {line}"),
            "a vertex needs three coordinates".into(),
        )
    })?;
    match tok.parse::<f64>() {
        Ok(v) if v.is_finite() => Ok(v),
        _ => Err(body_err(
            path,
            format!("line {line}"),
            format!("'{tok}' is not a finite number"),
        )),
    }
}

/// Adds a vertex, refusing more than `u32::MAX`.
fn push_vertex(mesh: &mut Mesh, p: Point3<f64>, path: &Path, at: &str) -> Result<(), CloudError> {
    if mesh.vertices.len() >= u32::MAX as usize {
        return Err(body_err(
            path,
            at.to_string(),
            "more than 4294967295 vertices".into(),
        ));
    }
    mesh.vertices.push(p);
    Ok(())
}

/// Adds the triangle fan of a polygon (indices already checked).
fn push_fan(mesh: &mut Mesh, poly: &[u32]) {
    for k in 1..poly.len().saturating_sub(1) {
        mesh.triangles.push([poly[0], poly[k], poly[k + 1]]);
        mesh.parts.push(Part::Other);
    }
}

fn parse_obj(bytes: &[u8], path: &Path) -> Result<Mesh, CloudError> {
    let text = String::from_utf8_lossy(bytes);
    let mut mesh = Mesh::new();
    // Faces with their line, checked once all vertices are read.
    let mut faces: Vec<(usize, Vec<i64>)> = Vec::new();
    let mut last_line = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last_line = line;
        let content = raw.split('#').next().unwrap_or("");
        let mut toks = content.split_ascii_whitespace();
        match toks.next() {
            Some("v") => {
                let x = coord(toks.next(), path, line)?;
                let y = coord(toks.next(), path, line)?;
                let z = coord(toks.next(), path, line)?;
                push_vertex(
                    &mut mesh,
                    Point3::new(x, y, z),
                    path,
                    &format!("line {line}"),
                )?;
            }
            Some("f") | Some("fo") => {
                let nv = mesh.vertices.len() as i64;
                let mut poly = Vec::new();
                for t in toks {
                    let first = t.split('/').next().unwrap_or("");
                    let idx: i64 = first.parse().map_err(|_| {
                        body_err(
                            path,
                            format!("line {line}"),
                            format!("'{t}' is not a vertex index"),
                        )
                    })?;
                    // Negative: relative to the vertices read so far (-1 is the last).
                    let abs = match idx {
                        0 => {
                            return Err(body_err(
                                path,
                                format!("line {line}"),
                                "vertex index 0 (OBJ indices start at 1)".into(),
                            ))
                        }
                        i if i < 0 => nv + i,
                        i => i - 1,
                    };
                    if abs < 0 {
                        return Err(body_err(
                            path,
                            format!("line {line}"),
                            format!("vertex index {idx} reaches before the first vertex"),
                        ));
                    }
                    poly.push(abs);
                }
                if poly.len() < 3 {
                    return Err(body_err(
                        path,
                        format!("line {line}"),
                        format!("a face needs at least 3 vertices, found {}", poly.len()),
                    ));
                }
                faces.push((line, poly));
            }
            _ => {}
        }
    }
    let nv = mesh.vertices.len() as i64;
    for (line, poly) in faces {
        if let Some(bad) = poly.iter().find(|&&i| i >= nv) {
            return Err(body_err(
                path,
                format!("line {line}"),
                format!(
                    "vertex index {} out of range (the file has {nv} vertices)",
                    bad + 1
                ),
            ));
        }
        let poly: Vec<u32> = poly.iter().map(|&i| index(i)).collect();
        push_fan(&mut mesh, &poly);
    }
    if mesh.triangles.is_empty() {
        return Err(body_err(
            path,
            format!("line {last_line}"),
            "no faces ('f' lines) in the file".into(),
        ));
    }
    Ok(mesh)
}

fn parse_off(bytes: &[u8], path: &Path) -> Result<Mesh, CloudError> {
    let text = String::from_utf8_lossy(bytes);
    // Content lines: (line number, tokens), comments and blank lines skipped.
    let mut lines = text.lines().enumerate().filter_map(|(i, raw)| {
        let toks: Vec<&str> = raw
            .split('#')
            .next()
            .unwrap_or("")
            .split_ascii_whitespace()
            .collect();
        (!toks.is_empty()).then_some((i + 1, toks))
    });
    let Some((hline, htoks)) = lines.next() else {
        return Err(header_err(path, "line 1".into(), "empty file".into()));
    };
    let kw = htoks[0];
    if !kw.ends_with("OFF")
        || !matches!(
            kw.trim_end_matches("OFF"),
            "" | "C" | "N" | "CN" | "NC" | "ST" | "STC" | "STN" | "STCN"
        )
    {
        return Err(header_err(
            path,
            format!("line {hline}"),
            format!("expected 'OFF', found '{kw}'"),
        ));
    }
    if htoks.get(1) == Some(&"BINARY") {
        return Err(header_err(
            path,
            format!("line {hline}"),
            "binary OFF is not supported (convert it to ascii)".into(),
        ));
    }
    let (cline, counts): (usize, Vec<&str>) = if htoks.len() > 1 {
        (hline, htoks[1..].to_vec())
    } else {
        lines.next().ok_or_else(|| {
            header_err(
                path,
                format!("line {hline}"),
                "no vertex and face counts".into(),
            )
        })?
    };
    let count = |k: usize, what: &str| -> Result<usize, CloudError> {
        counts
            .get(k)
            .and_then(|t| t.parse::<usize>().ok())
            .ok_or_else(|| {
                header_err(
                    path,
                    format!("line {cline}"),
                    format!(
                        "expected the {what} count, found '{}'",
                        counts.get(k).unwrap_or(&"")
                    ),
                )
            })
    };
    let nv = count(0, "vertex")?;
    let nf = count(1, "face")?;
    // A vertex takes at least 5 bytes ("0 0 0"), a face at least 7 ("3 0 1 2").
    let need = nv.saturating_mul(5).saturating_add(nf.saturating_mul(7));
    if need > bytes.len() || nv > u32::MAX as usize {
        return Err(header_err(
            path,
            format!("line {cline}"),
            format!(
                "{nv} vertices and {nf} faces cannot fit in a file of {} bytes",
                bytes.len()
            ),
        ));
    }
    let mut mesh = Mesh::new();
    mesh.vertices.reserve(nv);
    let mut last = cline;
    for k in 0..nv {
        let (line, toks) = lines.next().ok_or_else(|| {
            body_err(
                path,
                format!("line {last}"),
                format!("the file ends after {k} of {nv} vertices"),
            )
        })?;
        last = line;
        let mut it = toks.iter().copied();
        let x = coord(it.next(), path, line)?;
        let y = coord(it.next(), path, line)?;
        let z = coord(it.next(), path, line)?;
        mesh.vertices.push(Point3::new(x, y, z));
    }
    for k in 0..nf {
        let (line, toks) = lines.next().ok_or_else(|| {
            body_err(
                path,
                format!("line {last}"),
                format!("the file ends after {k} of {nf} faces"),
            )
        })?;
        last = line;
        let at = || format!("line {line}");
        let n: usize = toks[0]
            .parse()
            .map_err(|_| body_err(path, at(), format!("'{}' is not a corner count", toks[0])))?;
        // `n >= toks.len()`, not `toks.len() < n + 1`: a count of 2^64 - 1 must not overflow.
        if n < 3 || n >= toks.len() {
            return Err(body_err(
                path,
                at(),
                format!(
                    "a face needs at least 3 corners and as many indices as it says (says {n}, has {})",
                    toks.len() - 1
                ),
            ));
        }
        let mut poly = Vec::with_capacity(n);
        for t in &toks[1..=n] {
            match t.parse::<usize>() {
                Ok(i) if i < nv => poly.push(index(i)),
                _ => {
                    return Err(body_err(
                        path,
                        at(),
                        format!("vertex index '{t}' is not in 0..{nv}"),
                    ))
                }
            }
        }
        push_fan(&mut mesh, &poly);
    }
    if mesh.triangles.is_empty() {
        return Err(body_err(path, format!("line {last}"), "no faces".into()));
    }
    Ok(mesh)
}

fn parse_stl(bytes: &[u8], path: &Path) -> Result<Mesh, CloudError> {
    if bytes.len() >= 84 {
        let n = u32::from_le_bytes(bytes[80..84].try_into().expect("4 bytes")) as u64;
        let expected = 84 + 50 * n;
        if expected == bytes.len() as u64 {
            return parse_stl_binary(bytes, capacity(n, usize::MAX), path);
        }
        let ascii = bytes.trim_ascii_start().starts_with(b"solid")
            && !bytes[..bytes.len().min(4096)].contains(&0);
        if !ascii {
            return Err(header_err(
                path,
                "byte 80".into(),
                format!(
                    "binary STL header says {n} triangles ({expected} bytes), but the file has {} bytes",
                    bytes.len()
                ),
            ));
        }
    } else if !bytes.trim_ascii_start().starts_with(b"solid") {
        return Err(header_err(
            path,
            "byte 0".into(),
            format!(
                "neither ascii STL (no 'solid') nor binary STL ({} bytes, fewer than 84)",
                bytes.len()
            ),
        ));
    }
    parse_stl_ascii(bytes, path)
}

fn parse_stl_binary(bytes: &[u8], n: usize, path: &Path) -> Result<Mesh, CloudError> {
    if n == 0 {
        return Err(body_err(path, "byte 84".into(), "no triangles".into()));
    }
    if n.saturating_mul(3) > u32::MAX as usize {
        return Err(header_err(
            path,
            "byte 80".into(),
            format!("{n} triangles is too many"),
        ));
    }
    let mut mesh = Mesh::new();
    mesh.vertices.reserve(3 * n);
    mesh.triangles.reserve(n);
    mesh.parts.reserve(n);
    for t in 0..n {
        let base = 84 + 50 * t + 12;
        let mut corner = [0u32; 3];
        for (c, slot) in corner.iter_mut().enumerate() {
            let mut xyz = [0.0f64; 3];
            for (k, v) in xyz.iter_mut().enumerate() {
                let off = base + 12 * c + 4 * k;
                let f = f32::from_le_bytes(bytes[off..off + 4].try_into().expect("4 bytes"));
                if !f.is_finite() {
                    return Err(body_err(
                        path,
                        format!("byte {off}"),
                        format!("non-finite coordinate in triangle {t}"),
                    ));
                }
                *v = f as f64;
            }
            *slot = index(mesh.vertices.len());
            mesh.vertices.push(Point3::from(xyz));
        }
        mesh.triangles.push(corner);
        mesh.parts.push(Part::Other);
    }
    Ok(mesh)
}

fn parse_stl_ascii(bytes: &[u8], path: &Path) -> Result<Mesh, CloudError> {
    let text = String::from_utf8_lossy(bytes);
    let mut mesh = Mesh::new();
    let mut poly: Vec<u32> = Vec::new();
    let mut in_loop = false;
    let mut last = 0;
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        last = line;
        let mut toks = raw.split_ascii_whitespace();
        let Some(kw) = toks.next() else { continue };
        let at = || format!("line {line}");
        match kw {
            "solid" | "endsolid" | "facet" | "endfacet" => {}
            "outer" => {
                in_loop = true;
                poly.clear();
            }
            "vertex" => {
                if !in_loop {
                    return Err(body_err(path, at(), "'vertex' outside 'outer loop'".into()));
                }
                let x = coord(toks.next(), path, line)?;
                let y = coord(toks.next(), path, line)?;
                let z = coord(toks.next(), path, line)?;
                poly.push(index(mesh.vertices.len()));
                push_vertex(&mut mesh, Point3::new(x, y, z), path, &at())?;
            }
            "endloop" => {
                if poly.len() < 3 {
                    return Err(body_err(
                        path,
                        at(),
                        format!("a facet needs 3 vertices, found {}", poly.len()),
                    ));
                }
                push_fan(&mut mesh, &poly);
                poly.clear();
                in_loop = false;
            }
            other => {
                let shown: String = other.chars().take(20).collect();
                return Err(body_err(
                    path,
                    at(),
                    format!("unexpected '{shown}' in an ascii STL"),
                ));
            }
        }
    }
    if in_loop {
        return Err(body_err(
            path,
            format!("line {last}"),
            "the file ends inside a facet".into(),
        ));
    }
    if mesh.triangles.is_empty() {
        return Err(body_err(path, format!("line {last}"), "no facets".into()));
    }
    Ok(mesh)
}

/// Refuses PLY headers whose element counts exceed the file size (each element item
/// takes at least one byte), so that a lying header cannot make the reader loop or
/// allocate for long.
#[cfg(test)]
// Test data: small literals and lengths, written into the fields of a file by hand.
#[allow(clippy::cast_possible_truncation)]
mod tests {
    use super::*;

    fn write(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> std::path::PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn close(a: f64, b: f64) -> bool {
        (a - b).abs() < 1e-9
    }

    const CUBE_OBJ: &str = "# unit cube\r\nmtllib x.mtl\r\no cube\r\n\
        v 0 0 0\r\nv 1 0 0\r\nv 1 1 0\r\nv 0 1 0\r\n\
        v 0 0 1\r\nv 1 0 1\r\nv 1 1 1\r\nv 0 1 1 # top\r\n\
        vt 0 0\r\nvn 0 0 1\r\n\r\n\
        f 1 4 3 2\r\n\
        f 5/1 6/1 7/1 8/1\r\n\
        f 1//1 2//1 6//1 5//1\r\n\
        f 2/1/1 3/1/1 7/1/1 6/1/1\r\n\
        f -5 -1 -2 -6\r\n\
        f 4 1 5 8\r\n";

    #[test]
    fn obj_quads_negative_indices_and_crlf() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(&dir, "cube.obj", CUBE_OBJ.as_bytes());
        let m = read_mesh(&p).unwrap();
        assert_eq!(m.vertices.len(), 8);
        assert_eq!(m.len(), 12);
        assert_eq!(m.parts.len(), 12);
        assert!(close(m.area(), 6.0), "{}", m.area());
        // -5 -1 -2 -6 with 8 vertices is 4 8 7 3 (1-based): the +y face.
        assert_eq!(m.triangles[8], [3, 7, 6]);
        // A pentagon is a fan of three triangles.
        let p = write(
            &dir,
            "pent.obj",
            b"v 0 0 0\nv 2 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\nf 1 2 3 4 5\n",
        );
        let m = read_obj(&p).unwrap();
        assert_eq!(m.len(), 3);
        assert!(close(m.area(), 3.0), "{}", m.area());
    }

    #[test]
    fn obj_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let cases: [(&[u8], &str); 6] = [
            (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", "line 4"),
            (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "line 4"),
            (b"v 0 0 0\nv 1 0 0\nf -3 1 2\n", "line 3"),
            (b"v 0 0 0\nv 1 zero 0\n", "line 2"),
            (b"v 0 0 0\nv 1 0 0\nf 1 2\n", "line 3"),
            (b"v 0 0 0\nv 1 0 0\nv 0 1 0\n", "no faces"),
        ];
        for (bytes, want) in cases {
            let p = write(&dir, "bad.obj", bytes);
            let e = read_mesh(&p).unwrap_err().to_string();
            assert!(e.contains("bad.obj") && e.contains(want), "{e}");
            assert!(!e.contains('\n'), "{e}");
        }
    }

    #[test]
    fn off_reads_comments_quads_and_inline_counts() {
        let dir = tempfile::tempdir().unwrap();
        let off = "OFF\r\n# a square and a triangle\r\n\r\n5 2 0\r\n\
                   0 0 0\r\n2 0 0\r\n2 2 0\r\n0 2 0\r\n0 0 3\r\n\
                   4 0 1 2 3\r\n3 0 1 4 255 0 0\r\n";
        let p = write(&dir, "a.off", off.as_bytes());
        let m = read_mesh(&p).unwrap();
        assert_eq!(m.vertices.len(), 5);
        assert_eq!(m.len(), 3);
        assert!(close(m.area(), 4.0 + 3.0), "{}", m.area());
        let p = write(
            &dir,
            "b.off",
            b"COFF 3 1 0\n0 0 0 1 1 1\n1 0 0 1 1 1\n0 1 0 1 1 1\n3 0 1 2\n",
        );
        let m = read_off(&p).unwrap();
        assert_eq!(m.len(), 1);
        assert!(close(m.area(), 0.5));
    }

    #[test]
    fn off_errors() {
        let dir = tempfile::tempdir().unwrap();
        let cases: [(&[u8], &str); 6] = [
            // A lying header: refused before anything is allocated.
            (b"OFF\n4000000000 4000000000 0\n0 0 0\n", "cannot fit"),
            (b"OFF\n3 1 0\n0 0 0\n1 0 0\n", "ends after 2 of 3 vertices"),
            (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "line 6"),
            (b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n4 0 1 2\n", "line 6"),
            (b"PLY\n3 1 0\n", "expected 'OFF'"),
            (b"OFF BINARY\n", "binary OFF"),
        ];
        for (bytes, want) in cases {
            let p = write(&dir, "bad.off", bytes);
            let e = read_mesh(&p).unwrap_err().to_string();
            assert!(e.contains("bad.off") && e.contains(want), "{e}");
        }
    }

    fn binary_stl(header: &[u8; 80], tris: &[[[f32; 3]; 3]]) -> Vec<u8> {
        let mut b = header.to_vec();
        b.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend_from_slice(&[0u8; 12]);
            for v in t {
                for c in v {
                    b.extend_from_slice(&c.to_le_bytes());
                }
            }
            b.extend_from_slice(&[0u8; 2]);
        }
        b
    }

    #[test]
    fn stl_ascii_and_binary() {
        let dir = tempfile::tempdir().unwrap();
        let ascii = "solid sq\r\n  facet normal 0 0 1\r\n    outer loop\r\n\
                     vertex 0 0 0\r\n vertex 3 0 0\r\n vertex 3 2 0\r\n    endloop\r\n  endfacet\r\n\
                     facet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 3 2 0\nvertex 0 2 0\n\
                     endloop\nendfacet\nendsolid sq\n";
        let p = write(&dir, "a.stl", ascii.as_bytes());
        let m = read_mesh(&p).unwrap();
        assert_eq!(m.len(), 2);
        assert!(close(m.area(), 6.0));
        // Binary, with a header that starts with "solid" as many exporters write.
        let mut h = [b' '; 80];
        h[..11].copy_from_slice(b"solid model");
        let tris = [
            [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
            [[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [0.0, 2.0, 1.0]],
            [[0.0, 0.0, 0.0], [0.0, 4.0, 0.0], [0.0, 0.0, 1.0]],
        ];
        let b = binary_stl(&h, &tris);
        assert_eq!(b.len(), 84 + 50 * 3);
        let p = write(&dir, "b.STL", &b);
        let m = read_mesh(&p).unwrap();
        assert_eq!(m.len(), 3);
        assert!(close(m.area(), 0.5 + 2.0 + 2.0), "{}", m.area());
        // Truncated binary: the size no longer matches the count.
        let p = write(&dir, "t.stl", &b[..b.len() - 7]);
        let e = read_mesh(&p).unwrap_err().to_string();
        assert!(e.contains("t.stl") && e.contains("3 triangles"), "{e}");
        // Binary with a lying count and no "solid".
        let mut lie = binary_stl(&[0; 80], &tris);
        lie[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        let p = write(&dir, "l.stl", &lie);
        assert!(read_mesh(&p).unwrap_err().to_string().contains("byte 80"));
        // Non-finite coordinate.
        let bad = binary_stl(
            &[0; 80],
            &[[[f32::NAN, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]],
        );
        let p = write(&dir, "n.stl", &bad);
        assert!(read_mesh(&p).unwrap_err().to_string().contains("byte 96"));
        // Ascii cut inside a facet, and a bad keyword.
        let p = write(&dir, "c.stl", &ascii.as_bytes()[..60]);
        assert!(read_mesh(&p).is_err());
        let p = write(
            &dir,
            "k.stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertx 0 0 0\n",
        );
        let e = read_mesh(&p).unwrap_err().to_string();
        assert!(e.contains("line 4") && e.contains("vertx"), "{e}");
    }

    #[test]
    fn ply_meshes_and_lying_headers() {
        let dir = tempfile::tempdir().unwrap();
        let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                   property float y\nproperty float z\nelement face 1\n\
                   property list uchar int vertex_indices\nend_header\n\
                   0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";
        let p = write(&dir, "q.ply", ply.as_bytes());
        let m = read_mesh(&p).unwrap();
        assert_eq!(m.len(), 2);
        assert!(close(m.area(), 1.0));
        let lie = ply.replace("element vertex 4", "element vertex 99999999999");
        let p = write(&dir, "lie.ply", lie.as_bytes());
        let e = read_mesh(&p).unwrap_err().to_string();
        assert!(e.contains("lie.ply") && e.contains("line 3"), "{e}");
        let p = write(&dir, "cut.ply", &ply.as_bytes()[..ply.len() - 6]);
        assert!(read_mesh(&p).is_err());
    }

    #[test]
    fn garbage_and_empty_files_are_errors_not_panics() {
        let dir = tempfile::tempdir().unwrap();
        // Deterministic garbage of several sizes, including 84 + 50 n.
        let mut x: u32 = 12345;
        let mut garbage = Vec::new();
        for _ in 0..5000 {
            x = x.wrapping_mul(1664525).wrapping_add(1013904223);
            garbage.push((x >> 24) as u8);
        }
        for ext in ["obj", "off", "stl", "ply"] {
            for len in [0, 1, 10, 83, 84, 134, 999, 5000] {
                let p = write(&dir, &format!("g.{ext}"), &garbage[..len]);
                // 134 = 84 + 50: random bytes are a (possibly valid) binary STL triangle.
                match read_mesh(&p) {
                    Ok(m) => assert!(ext == "stl" && len == 134 && m.len() == 1, "{ext} {len}"),
                    Err(e) => assert!(!e.to_string().contains('\n')),
                }
            }
        }
        let p = write(&dir, "x.dae", b"");
        assert!(read_mesh(&p)
            .unwrap_err()
            .to_string()
            .contains("unknown mesh format"));
        let missing = dir.path().join("missing.obj");
        assert!(matches!(read_mesh(&missing), Err(CloudError::Io { .. })));
    }

    #[test]
    fn sampling_is_deterministic_and_follows_the_density() {
        let dir = tempfile::tempdir().unwrap();
        let p = write(&dir, "cube.obj", CUBE_OBJ.as_bytes());
        let m = read_mesh(&p).unwrap();
        let a = sample_mesh(&m, 2000.0, 7);
        let b = sample_mesh(&m, 2000.0, 7);
        assert_eq!(a, b);
        let want = 2000.0 * 6.0;
        assert!(((a.len() as f64) - want).abs() < 0.02 * want, "{}", a.len());
        // Every point lies on the cube's surface.
        for q in &a.points {
            let on_face = [q.x, q.y, q.z]
                .iter()
                .any(|c| c.abs() < 1e-9 || (c - 1.0).abs() < 1e-9);
            assert!(on_face, "{q:?}");
            assert!(q.coords.iter().all(|c| (-1e-9..=1.0 + 1e-9).contains(c)));
        }
        let c = sample_mesh(&m, 2000.0, 8);
        assert_ne!(a, c);
        assert!(sample_mesh(&m, 0.0, 7).is_empty());
    }
}
