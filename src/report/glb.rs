//! The posed agents of detections (and optionally the cloud as coloured points) as binary
//! glTF 2.0 (`.glb`), the format browser viewers, Blender, rerun and Foxglove open.
//!
//! Every detection is one named node (`detection 3: sitting, backrest`) holding one
//! triangle mesh of its body parts ([`crate::report::agent_mesh::cylinder_mesh`]) with one
//! material in its affordance colour ([`crate::report::render::Legend`], the palette
//! of the pictures and of the PLY mesh); the node's `extras` carry the detection's
//! numbers. The scene's points, when asked for, are one more node of `POINTS` whose
//! `COLOR_0` is the colour of the detection whose segment holds each point (grey for none,
//! as in `--segments`). Vertices are in the world frame, metres, z up; a root node
//! rotates z up to glTF's y up, so viewers show the floor as the floor.

use std::path::Path;

use nalgebra::Point3;
use serde_json::{json, Value};

use crate::detect::Detection;
use crate::num::{index32, to_f32};
use crate::report::agent_mesh::{cylinder_mesh, SEGMENTS, UNLABELLED};
use crate::report::render::Legend;

/// Name of the root node, which turns the world frame (z up) into glTF's (y up).
pub const ROOT_NAME: &str = "afford (world frame, z up)";
/// Name of the node of the scene's points.
pub const POINTS_NAME: &str = "scene points";

/// glTF component types and targets used here.
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// The cloud the detections were found in (world frame, metres), and per point the
/// detection whose segment holds it.
pub type ScenePoints<'a> = (&'a [Point3<f64>], &'a [Option<usize>]);

/// The name of detection `i`'s node: its number and affordances.
pub fn node_name(i: usize, d: &Detection) -> String {
    format!("detection {i}: {}", d.affordances.join(", "))
}

/// An sRGB byte as the linear value glTF colour factors and `COLOR_0` hold.
pub fn srgb_to_linear(c: u8) -> f64 {
    let s = c as f64 / 255.0;
    let l = if s <= 0.04045 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    };
    (l * 1e6).round() / 1e6
}

/// The binary buffer and the accessors, buffer views of the document being built.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    /// Appends `bytes` as a buffer view; returns its index.
    fn view(&mut self, bytes: &[u8], target: u32) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        self.views.push(json!({
            "buffer": 0, "byteOffset": offset, "byteLength": bytes.len(), "target": target
        }));
        self.views.len() - 1
    }

    /// A VEC3 float accessor over `v` (with its bounds, as POSITION needs); its index.
    fn vec3(&mut self, v: &[[f32; 3]]) -> usize {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        let mut bytes = Vec::with_capacity(12 * v.len());
        for p in v {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
                bytes.extend(p[k].to_le_bytes());
            }
        }
        let view = self.view(&bytes, ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": view, "componentType": FLOAT, "count": v.len(), "type": "VEC3",
            "min": lo.map(f64::from), "max": hi.map(f64::from)
        }));
        self.accessors.len() - 1
    }

    /// A SCALAR unsigned int accessor of triangle indices; its index.
    fn indices(&mut self, t: &[[u32; 3]]) -> usize {
        let bytes: Vec<u8> = t.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, ELEMENT_ARRAY_BUFFER);
        self.accessors.push(json!({
            "bufferView": view, "componentType": UNSIGNED_INT, "count": 3 * t.len(),
            "type": "SCALAR"
        }));
        self.accessors.len() - 1
    }
}

/// A material of one sRGB colour, named.
fn material(name: &str, rgb: [u8; 3]) -> Value {
    let [r, g, b] = rgb.map(srgb_to_linear);
    json!({
        "name": name,
        "pbrMetallicRoughness": {
            "baseColorFactor": [r, g, b, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0
        }
    })
}

fn round(x: f64, d: i32) -> f64 {
    let k = 10f64.powi(d);
    (x * k).round() / k
}

/// The bytes of the `.glb` of `detections` found in `file`; with `points` (the cloud, and
/// per point the detection whose segment holds it), the cloud as coloured points too. An
/// error (`InvalidInput`) when they would be 4 GiB or more, which the container's 32-bit
/// lengths cannot say.
pub fn agents_glb(
    file: &str,
    detections: &[Detection],
    legend: &Legend,
    points: Option<ScenePoints>,
) -> std::io::Result<Vec<u8>> {
    let mut b = Builder::default();
    let mut materials: Vec<Value> = Vec::new();
    let mut material_of: Vec<[u8; 3]> = Vec::new();
    let mut meshes = Vec::new();
    let mut nodes = vec![Value::Null];
    for (i, d) in detections.iter().enumerate() {
        let colour = legend.colour(&d.affordances);
        let m = match material_of.iter().position(|c| *c == colour) {
            Some(m) => m,
            None => {
                materials.push(material(
                    legend.finest(&d.affordances).unwrap_or("none"),
                    colour,
                ));
                material_of.push(colour);
                material_of.len() - 1
            }
        };
        let mut verts: Vec<[f32; 3]> = Vec::new();
        let mut tris: Vec<[u32; 3]> = Vec::new();
        for c in &d.parts {
            let (v, f) = cylinder_mesh(c, SEGMENTS);
            let base = index32(verts.len());
            tris.extend(f.iter().map(|t| t.map(|k| k + base)));
            verts.extend(v.iter().map(|p| [to_f32(p.x), to_f32(p.y), to_f32(p.z)]));
        }
        let position = [0, 1, 2].map(|k| round(d.position[k], 4));
        let mut node = json!({
            "name": node_name(i, d),
            "extras": {
                "detection": i,
                "hierarchy": d.hierarchy,
                "agent": d.agent,
                "height": round(d.height, 3),
                "affordances": d.affordances,
                "score": round(d.score, 4),
                "position": position,
                "yaw_deg": round(d.yaw.to_degrees(), 2),
            }
        });
        if !tris.is_empty() {
            let pos = b.vec3(&verts);
            let idx = b.indices(&tris);
            meshes.push(json!({
                "name": node_name(i, d),
                "primitives": [{
                    "attributes": {"POSITION": pos}, "indices": idx, "material": m, "mode": 4
                }]
            }));
            node["mesh"] = json!(meshes.len() - 1);
        }
        nodes.push(node);
    }
    if let Some((pts, labels)) = points.filter(|(p, _)| !p.is_empty()) {
        let colours: Vec<[u8; 3]> = detections
            .iter()
            .map(|d| legend.colour(&d.affordances))
            .collect();
        let verts: Vec<[f32; 3]> = pts
            .iter()
            .map(|p| [to_f32(p.x), to_f32(p.y), to_f32(p.z)])
            .collect();
        let rgb: Vec<[f32; 3]> = (0..pts.len())
            .map(|k| {
                let c = labels
                    .get(k)
                    .copied()
                    .flatten()
                    .and_then(|i| colours.get(i).copied())
                    .unwrap_or(UNLABELLED);
                c.map(|v| to_f32(srgb_to_linear(v)))
            })
            .collect();
        let pos = b.vec3(&verts);
        let col = b.vec3(&rgb);
        materials.push(material(POINTS_NAME, [255, 255, 255]));
        meshes.push(json!({
            "name": POINTS_NAME,
            "primitives": [{
                "attributes": {"POSITION": pos, "COLOR_0": col},
                "material": materials.len() - 1, "mode": 0
            }]
        }));
        nodes.push(json!({"name": POINTS_NAME, "mesh": meshes.len() - 1}));
    }
    let children: Vec<usize> = (1..nodes.len()).collect();
    // -90 degrees about x: world z (up) becomes glTF y (up), world y becomes -z.
    let h = std::f64::consts::FRAC_1_SQRT_2;
    nodes[0] = json!({"name": ROOT_NAME, "rotation": [-h, 0.0, 0.0, h]});
    if !children.is_empty() {
        nodes[0]["children"] = json!(children);
    }
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": concat!("afford ", env!("CARGO_PKG_VERSION"))},
        "scene": 0,
        "scenes": [{"name": file, "nodes": [0]}],
        "nodes": nodes,
    });
    for (key, v) in [
        ("meshes", meshes),
        ("materials", materials),
        ("accessors", b.accessors),
        ("bufferViews", b.views),
    ] {
        if !v.is_empty() {
            doc[key] = Value::Array(v);
        }
    }
    if !b.bin.is_empty() {
        doc["buffers"] = json!([{"byteLength": b.bin.len()}]);
    }
    let mut text = serde_json::to_vec(&doc).unwrap_or_default();
    while !text.len().is_multiple_of(4) {
        text.push(b' ');
    }
    let mut bin = b.bin;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + text.len() + if bin.is_empty() { 0 } else { 8 + bin.len() };
    // Every length below is at most `total`.
    let len32 = |n: usize| {
        u32::try_from(n).map_err(|_| {
            std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!("{total} bytes: a glTF binary file holds less than 4 GiB"),
            )
        })
    };
    let total32 = len32(total)?;
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend(total32.to_le_bytes());
    out.extend(len32(text.len())?.to_le_bytes());
    out.extend(b"JSON");
    out.extend(text);
    if !bin.is_empty() {
        out.extend(len32(bin.len())?.to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(bin);
    }
    Ok(out)
}

/// Writes [`agents_glb`] to `path` through a temporary file and a rename.
pub fn write_agents_glb(
    path: &Path,
    file: &str,
    detections: &[Detection],
    legend: &Legend,
    points: Option<ScenePoints>,
) -> std::io::Result<()> {
    crate::report::atomic::write_bytes(path, &agents_glb(file, detections, legend, points)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_conversion_fixes_black_white_and_mid_grey() {
        assert_eq!(srgb_to_linear(0), 0.0);
        assert_eq!(srgb_to_linear(255), 1.0);
        assert!((srgb_to_linear(128) - 0.2158605).abs() < 1e-6);
    }

    #[test]
    fn empty_is_a_valid_header_and_json_chunk() {
        let g = agents_glb("x.ply", &[], &Legend::default(), None).unwrap();
        assert_eq!(&g[..4], b"glTF");
        assert_eq!(
            u32::from_le_bytes(g[8..12].try_into().unwrap()) as usize,
            g.len()
        );
        let n = u32::from_le_bytes(g[12..16].try_into().unwrap()) as usize;
        assert_eq!(20 + n, g.len());
        let doc: Value = serde_json::from_slice(&g[20..]).unwrap();
        assert_eq!(doc["nodes"][0]["name"], ROOT_NAME);
        assert!(doc.get("buffers").is_none());
    }
}
