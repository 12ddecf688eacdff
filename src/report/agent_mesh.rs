//! The posed agents of detections as a triangle mesh (binary PLY), and the cloud with its
//! segments (binary PLY, coloured the same way), to look at them together in MeshLab or
//! CloudCompare.

use std::path::Path;

use nalgebra::{Point3, Vector3};

use crate::cloud::{CloudError, Scalar};
use crate::detect::Detection;
use crate::model::agent::Cylinder;
use crate::num::{index32, to_f32};
use crate::report::render::Legend;

/// Segments around the circumference of every body part in [`agent_mesh_ply`].
pub const SEGMENTS: usize = 16;

/// A closed triangle mesh of the cylinder `c` (world frame, metres) with `segments`
/// (at least 3) vertices around each end: `2 * segments + 2` vertices (the ring at `a`,
/// the ring at `b`, then the centres of the caps at `a` and `b`) and `4 * segments`
/// triangles (side, then caps), wound counter-clockwise seen from outside.
/// A cylinder of zero length gets its axis along world z.
pub fn cylinder_mesh(c: &Cylinder, segments: usize) -> (Vec<Point3<f64>>, Vec<[u32; 3]>) {
    let n = segments.max(3);
    let axis = c.b - c.a;
    let d = if axis.norm() > 1e-12 {
        axis.normalize()
    } else {
        Vector3::z()
    };
    // Any unit vector across the axis, from the world axis least aligned with it.
    let helper = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = d.cross(&helper).normalize();
    let v = d.cross(&u);
    let mut verts = Vec::with_capacity(2 * n + 2);
    for end in [c.a, c.b] {
        for i in 0..n {
            let (s, co) = (std::f64::consts::TAU * i as f64 / n as f64).sin_cos();
            verts.push(end + (u * co + v * s) * c.radius);
        }
    }
    verts.push(c.a);
    verts.push(c.b);
    let n32 = index32(n);
    let (ca, cb) = (2 * n32, 2 * n32 + 1);
    let mut faces = Vec::with_capacity(4 * n);
    for i in 0..n32 {
        let j = (i + 1) % n32;
        faces.push([i, j, n32 + j]);
        faces.push([i, n32 + j, n32 + i]);
    }
    for i in 0..n32 {
        let j = (i + 1) % n32;
        faces.push([ca, j, i]);
        faces.push([cb, n32 + i, n32 + j]);
    }
    (verts, faces)
}

/// The PLY header of a mesh of `vertices` coloured vertices and `faces` triangles.
fn header(vertices: usize, faces: usize, detections: usize) -> String {
    format!(
        "ply\nformat binary_little_endian 1.0\n\
         comment afford: posed agents of {detections} detections, metres, z up\n\
         element vertex {vertices}\n\
         property float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\n\
         element face {faces}\n\
         property list uchar int vertex_indices\n\
         end_header\n"
    )
}

/// The bytes of the binary PLY written by [`agent_mesh_ply`].
pub fn agent_mesh_bytes(detections: &[Detection], legend: &Legend) -> Vec<u8> {
    let mut verts: Vec<(Point3<f64>, [u8; 3])> = Vec::new();
    let mut faces: Vec<[u32; 3]> = Vec::new();
    for d in detections {
        let colour = legend.colour(&d.affordances);
        for c in &d.parts {
            let (v, f) = cylinder_mesh(c, SEGMENTS);
            let base = index32(verts.len());
            faces.extend(f.iter().map(|t| t.map(|i| i + base)));
            verts.extend(v.into_iter().map(|p| (p, colour)));
        }
    }
    let mut out = header(verts.len(), faces.len(), detections.len()).into_bytes();
    out.reserve(15 * verts.len() + 13 * faces.len());
    for (p, c) in &verts {
        for k in 0..3 {
            out.extend_from_slice(&to_f32(p[k]).to_le_bytes());
        }
        out.extend_from_slice(c);
    }
    for f in &faces {
        out.push(3);
        for i in f {
            out.extend_from_slice(&(*i as i32).to_le_bytes());
        }
    }
    out
}

/// Writes the posed body parts of every detection as one binary little-endian PLY
/// triangle mesh (vertex `x, y, z` float in metres, world frame, and `red, green, blue`
/// uchar; face `list uchar int vertex_indices`): each part a capped cylinder of
/// [`SEGMENTS`] sides ([`cylinder_mesh`]), coloured by its detection's finest
/// affordance ([`Legend::colour`], the legend of the pictures). The file is written
/// to a temporary file in the same directory and renamed into place.
pub fn agent_mesh_ply(
    detections: &[Detection],
    legend: &Legend,
    path: &Path,
) -> std::io::Result<()> {
    crate::report::atomic::write_bytes(path, &agent_mesh_bytes(detections, legend))
}

/// Colour of the points in no detection's segment in [`segments_ply`].
pub const UNLABELLED: [u8; 3] = [128, 128, 128];

/// The `affordance` code of a detection in [`segments_ply`]: 1 + the index in `ids` (the
/// hierarchy's affordance ids, in node order) of its finest affordance
/// ([`Legend::finest`], the one its colour shows); 0 for none.
pub fn affordance_code(d: &Detection, ids: &[String], legend: &Legend) -> usize {
    legend
        .finest(&d.affordances)
        .and_then(|f| ids.iter().position(|id| id == f))
        .map_or(0, |i| i + 1)
}

/// Writes `points` (the cloud the detections were found in, in its order; `labels` gives
/// each point's detection) as a binary
/// little-endian PLY with, per vertex, `x, y, z` float (metres), `detection` int (index of
/// the detection whose segment holds the point, -1 for none), `affordance` int
/// ([`affordance_code`] of that detection, 0 for none) and `red, green, blue` uchar (the
/// detection's colour in the mesh of [`agent_mesh_ply`] and the pictures, [`UNLABELLED`]
/// grey for none). The header lists the codes: `comment affordance 0 none`,
/// `comment affordance 1 sitting`, ... Written atomically, like every output.
pub fn segments_ply(
    points: &[Point3<f64>],
    detections: &[Detection],
    labels: &[Option<usize>],
    ids: &[String],
    legend: &Legend,
    path: &Path,
) -> Result<(), CloudError> {
    let per_detection: Vec<(f64, [u8; 3])> = detections
        .iter()
        .map(|d| {
            (
                affordance_code(d, ids, legend) as f64,
                legend.colour(&d.affordances),
            )
        })
        .collect();
    let mut cols: [Vec<f64>; 5] = Default::default();
    for label in labels {
        let (det, (code, rgb)) = label
            .and_then(|i| Some((i as f64, *per_detection.get(i)?)))
            .unwrap_or((-1.0, (0.0, UNLABELLED)));
        let row = [det, code, rgb[0].into(), rgb[1].into(), rgb[2].into()];
        for (col, v) in cols.iter_mut().zip(row) {
            col.push(v);
        }
    }
    let names = ["detection", "affordance", "red", "green", "blue"];
    let types = [Scalar::I32, Scalar::I32, Scalar::U8, Scalar::U8, Scalar::U8];
    let extra: Vec<_> = (0..5)
        .map(|k| (names[k], types[k], cols[k].as_slice()))
        .collect();
    let comments: Vec<String> = std::iter::once("affordance 0 none".to_string())
        .chain(
            ids.iter()
                .enumerate()
                .map(|(i, id)| format!("affordance {} {id}", i + 1)),
        )
        .collect();
    crate::cloud::write_ply_typed(path, points, &extra, &comments, true)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cyl(a: [f64; 3], b: [f64; 3], r: f64) -> Cylinder {
        Cylinder {
            joint: 0,
            a: Point3::from(a),
            b: Point3::from(b),
            radius: r,
        }
    }

    fn detection(affordances: &[&str], parts: Vec<Cylinder>) -> Detection {
        Detection {
            agent: "human".into(),
            height: 1.75,
            hierarchy: "sitting".into(),
            position: Point3::origin(),
            yaw: 0.0,
            seat: Point3::origin(),
            affordances: affordances.iter().map(|s| s.to_string()).collect(),
            local_scores: vec![],
            pose: vec![],
            score: 1.0,
            stability: 1.0,
            availability: 1.0,
            segment_points: 0,
            parts,
            joints: vec![],
        }
    }

    #[test]
    fn cylinder_vertices_lie_on_its_surface_and_faces_point_outwards() {
        for c in [
            cyl([0.1, 0.2, 0.3], [0.4, -0.2, 0.9], 0.05),
            cyl([0.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.02),
            cyl([0.0, 0.0, 1.0], [0.0, 0.0, 0.0], 0.1),
        ] {
            let (v, f) = cylinder_mesh(&c, 16);
            assert_eq!((v.len(), f.len()), (34, 64));
            let axis = (c.b - c.a).normalize();
            for p in &v[..32] {
                let w = p - c.a;
                let radial = (w - axis * w.dot(&axis)).norm();
                assert!((radial - c.radius).abs() < 1e-9, "{radial}");
            }
            assert_eq!((v[32], v[33]), (c.a, c.b));
            let centre = nalgebra::center(&c.a, &c.b);
            for t in &f {
                let [p, q, r] = t.map(|i| v[i as usize]);
                let n = (q - p).cross(&(r - p));
                let mid = Point3::from((p.coords + q.coords + r.coords) / 3.0);
                assert!(n.dot(&(mid - centre)) > 0.0, "face {t:?} points inwards");
                assert!(t.iter().all(|&i| (i as usize) < v.len()));
            }
        }
    }

    #[test]
    fn ply_header_counts_and_length() {
        let ds = [
            detection(
                &["sitting", "backrest"],
                vec![
                    cyl([0.0; 3], [0.0, 0.0, 0.3], 0.05),
                    cyl([0.0; 3], [0.3, 0.0, 0.0], 0.04),
                ],
            ),
            detection(
                &["sitting"],
                vec![cyl([1.0, 0.0, 0.0], [1.0, 0.0, 0.3], 0.05)],
            ),
        ];
        let legend = crate::report::render::builtin_legend();
        let colour = |id: &str| legend.entries().iter().find(|(e, _)| e == id).unwrap().1;
        let bytes = agent_mesh_bytes(&ds, &legend);
        let text_end = bytes
            .windows(11)
            .position(|w| w == b"end_header\n")
            .unwrap()
            + 11;
        let head = std::str::from_utf8(&bytes[..text_end]).unwrap();
        let (nv, nf) = (3 * (2 * SEGMENTS + 2), 3 * 4 * SEGMENTS);
        assert!(head.starts_with("ply\nformat binary_little_endian 1.0\n"));
        assert!(head.contains(&format!("element vertex {nv}\n")), "{head}");
        assert!(head.contains(&format!("element face {nf}\n")), "{head}");
        assert_eq!(bytes.len(), text_end + 15 * nv + 13 * nf);
        // First vertex: on the first part, coloured by "backrest".
        let body = &bytes[text_end..];
        let z = f32::from_le_bytes(body[8..12].try_into().unwrap());
        assert!(z.abs() < 1e-6);
        assert_eq!(body[12..15], colour("backrest"));
        // Last vertex belongs to the second detection: "sitting" colour.
        let last = &body[15 * (nv - 1)..15 * nv];
        assert_eq!(last[12..15], colour("sitting"));
        // Faces: count byte 3 and indices inside the vertex range.
        let faces = &body[15 * nv..];
        for f in faces.chunks(13) {
            assert_eq!(f[0], 3);
            for k in 0..3 {
                let i = i32::from_le_bytes(f[1 + 4 * k..5 + 4 * k].try_into().unwrap());
                assert!(i >= 0 && (i as usize) < nv);
            }
        }
    }

    #[test]
    fn segments_open_in_both_readers_with_codes_and_palette_colours() {
        use crate::detect::Outcome;
        use ply_rs_bw::ply::{DefaultElement, Property, PropertyType, ScalarType};
        let ids: Vec<String> = ["sitting", "armrest", "backrest", "headrest"]
            .map(String::from)
            .to_vec();
        let outcome = Outcome {
            detections: vec![
                detection(&["sitting", "armrest", "backrest"], vec![]),
                detection(&["sitting", "backrest", "headrest"], vec![]),
                detection(&["sitting"], vec![]),
            ],
            labels: vec![Some(1), None, Some(0), Some(2), Some(7)],
            stats: Default::default(),
        };
        let points: Vec<_> = (0..5).map(|i| Point3::new(i as f64, 0.5, -0.25)).collect();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("seg.ply");
        let palette = crate::report::render::builtin_legend();
        segments_ply(
            &points,
            &outcome.detections,
            &outcome.labels,
            &ids,
            &palette,
            &path,
        )
        .unwrap();

        // Our own reader: the points, and every field by name.
        let got = crate::cloud::read_ply(&path).unwrap();
        assert_eq!(got, points);
        let field = |n| crate::cloud::read_ply_property(&path, n).unwrap().unwrap();
        assert_eq!(field("detection"), [1.0, -1.0, 0.0, 2.0, -1.0]);
        // headrest 4, armrest 2 (the colour's affordance), sitting 1; none 0.
        assert_eq!(field("affordance"), [4.0, 0.0, 2.0, 1.0, 0.0]);

        // ply-rs-bw: names, types, the code table and the colours.
        let mut f = std::fs::File::open(&path).unwrap();
        let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
            .read_ply(&mut f)
            .unwrap();
        let props = &ply.header.elements["vertex"].properties;
        let types: Vec<_> = props
            .values()
            .map(|p| (p.name.as_str(), p.data_type.clone()))
            .collect();
        let s = |t| PropertyType::Scalar(t);
        assert_eq!(
            types,
            [
                ("x", s(ScalarType::Float)),
                ("y", s(ScalarType::Float)),
                ("z", s(ScalarType::Float)),
                ("detection", s(ScalarType::Int)),
                ("affordance", s(ScalarType::Int)),
                ("red", s(ScalarType::UChar)),
                ("green", s(ScalarType::UChar)),
                ("blue", s(ScalarType::UChar)),
            ]
        );
        assert!(ply.header.comments.iter().any(|c| c == "affordance 0 none"));
        for (i, id) in ids.iter().enumerate() {
            let line = format!("affordance {} {id}", i + 1);
            assert!(ply.header.comments.contains(&line), "{line}");
        }
        let v = &ply.payload["vertex"];
        let rgb = |e: &DefaultElement| {
            ["red", "green", "blue"].map(|k| match e[k] {
                Property::UChar(c) => c,
                ref p => panic!("{k}: {p:?}"),
            })
        };
        let legend = |id: &str| palette.entries().iter().find(|(l, _)| l == id).unwrap().1;
        let want = [
            legend("headrest"),
            UNLABELLED,
            legend("armrest"),
            legend("sitting"),
            UNLABELLED,
        ];
        assert_eq!(v.iter().map(rgb).collect::<Vec<_>>(), want);
        assert_eq!(v[0]["detection"], Property::Int(1));
        assert_eq!(v[1]["detection"], Property::Int(-1));
        assert_eq!(v[0]["affordance"], Property::Int(4));
        // The mesh of the same detections carries the same colours.
        let mesh = agent_mesh_bytes(
            &[detection(
                &["sitting", "armrest", "backrest"],
                vec![cyl([0.0; 3], [0.0, 0.0, 0.3], 0.05)],
            )],
            &palette,
        );
        let body = mesh.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        assert_eq!(mesh[body + 12..body + 15], legend("armrest"));
    }

    #[test]
    fn writes_atomically_and_empty_is_valid() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("agents.ply");
        agent_mesh_ply(&[], &Legend::default(), &path).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let head = String::from_utf8(bytes.clone()).unwrap();
        assert!(head.contains("element vertex 0\n") && head.contains("element face 0\n"));
        assert!(head.ends_with("end_header\n"));
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        assert!(agent_mesh_ply(
            &[],
            &Legend::default(),
            &dir.path().join("missing/agents.ply")
        )
        .is_err());
        // The project's own PLY reader accepts the mesh and finds its vertices.
        let d = detection(&["sitting"], vec![cyl([0.0; 3], [0.0, 0.0, 0.5], 0.1)]);
        agent_mesh_ply(&[d], &Legend::default(), &path).unwrap();
        let pts = crate::cloud::read_ply(&path).unwrap();
        assert_eq!(pts.len(), 2 * SEGMENTS + 2);
        assert!(pts.iter().all(|p| p.z >= -1e-6 && p.z <= 0.5 + 1e-6));
    }
}
