//! The glTF output, read back by the `gltf` crate.

use afford::model::set::{load_set, sources, BUILTIN_AGENTS, BUILTIN_HIERARCHIES};
use afford::report::render::Legend;

use super::*;

/// A linear colour factor back to its sRGB byte.
fn to_srgb(l: f32) -> u8 {
    let l = l as f64;
    let s = if l <= 0.0031308 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    // `s` is in 0..=1: the channel is in 0..=255.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let c = (s * 255.0).round() as u8;
    c
}

/// The colour the built-in hierarchies' legends give a detection with `affordances`.
fn legend(affordances: &[String]) -> [u8; 3] {
    let agents = sources(&[], BUILTIN_AGENTS, &["human"]).unwrap();
    let hierarchies = sources(&[], BUILTIN_HIERARCHIES, &["sitting", "lying"]).unwrap();
    let models = load_set(&agents, &hierarchies, &[1.75]).unwrap();
    Legend::of(models.iter().map(|m| &m.hierarchy)).colour(affordances)
}

#[test]
fn the_glb_opens_with_a_named_node_per_detection_in_its_colour() {
    let d = tempfile::tempdir().unwrap();
    let mut pts = chair_scene(0.0, 4);
    pts.extend(
        chair_scene(180.0, 5)
            .iter()
            .map(|p| p + nalgebra::Vector3::new(2.5, 0.0, 0.0)),
    );
    let ply = d.path().join("two.ply");
    write_ply_f64(&ply, &pts);
    let glb = d.path().join("agents.glb");
    let doc = detect_json(
        d.path(),
        &ply,
        &[
            "--affordances",
            "sitting,lying",
            "--mesh",
            glb.to_str().unwrap(),
            "--mesh-scene",
        ],
    );
    let dets = doc["files"][0]["detections"].as_array().unwrap();
    assert!(dets.len() >= 2, "{}", dets.len());
    let bytes = std::fs::read(&glb).unwrap();
    let g = gltf::Gltf::from_slice(&bytes).expect("a valid glTF");
    let blob = g.blob.clone().unwrap();
    let scene = g.default_scene().unwrap();
    let root = scene.nodes().next().unwrap();
    // The root turns z up into y up.
    let (_, r, _) = root.transform().decomposed();
    assert!((r[0] + std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-6 && r[3] > 0.7);
    let children: Vec<_> = root.children().collect();
    assert_eq!(children.len(), dets.len() + 1);
    for (i, (node, det)) in children.iter().zip(dets).enumerate() {
        let affs: Vec<String> = det["affordances"]
            .as_array()
            .unwrap()
            .iter()
            .map(|a| a.as_str().unwrap().to_string())
            .collect();
        assert_eq!(
            node.name().unwrap(),
            format!("detection {i}: {}", affs.join(", "))
        );
        let prim = node.mesh().unwrap().primitives().next().unwrap();
        assert_eq!(prim.mode(), gltf::mesh::Mode::Triangles);
        let c = prim.material().pbr_metallic_roughness().base_color_factor();
        let rgb = [to_srgb(c[0]), to_srgb(c[1]), to_srgb(c[2])];
        assert_eq!(rgb, legend(&affs), "detection {i}");
        // The body stands where the detection is: its pelvis within the mesh's bounds.
        let reader = prim.reader(|_| Some(&blob));
        let verts: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        let pos = det["position"].as_array().unwrap();
        for k in 0..3 {
            // A position the file wrote from f32 values: exact in f32.
            #[allow(clippy::cast_possible_truncation)]
            let p = pos[k].as_f64().unwrap() as f32;
            let lo = verts.iter().map(|v| v[k]).fold(f32::INFINITY, f32::min);
            let hi = verts.iter().map(|v| v[k]).fold(f32::NEG_INFINITY, f32::max);
            assert!(lo <= p && p <= hi, "axis {k}: {p} not in {lo}..{hi}");
        }
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert!(idx.iter().all(|&k| (k as usize) < verts.len()));
        assert_eq!(
            node.extras()
                .as_ref()
                .map(|e| e.get().contains("\"score\"")),
            Some(true)
        );
    }
    // The scene's points: every point, coloured by segment (grey outside any).
    let points = children.last().unwrap();
    assert_eq!(points.name(), Some("scene points"));
    let prim = points.mesh().unwrap().primitives().next().unwrap();
    assert_eq!(prim.mode(), gltf::mesh::Mode::Points);
    let reader = prim.reader(|_| Some(&blob));
    assert_eq!(reader.read_positions().unwrap().count(), pts.len());
    let colours: Vec<[u8; 3]> = reader
        .read_colors(0)
        .unwrap()
        .into_rgb_f32()
        .map(|c| c.map(to_srgb))
        .collect();
    assert!(colours.contains(&[128, 128, 128]));
    assert!(colours.contains(&legend(&["sitting".to_string(), "backrest".to_string()])));
    // JSON: every joint's world position, the root joint at the detection's position.
    let det = &dets[0];
    let joints = det["joints"].as_object().unwrap();
    let pose = det["pose_deg"].as_object().unwrap();
    assert_eq!(
        joints.keys().collect::<Vec<_>>(),
        pose.keys().collect::<Vec<_>>()
    );
    assert_eq!(joints["pelvis"], det["position"]);
    let knee = joints["knee_l"].as_array().unwrap();
    let pelvis = joints["pelvis"].as_array().unwrap();
    let dist: f64 = (0..3)
        .map(|k| (knee[k].as_f64().unwrap() - pelvis[k].as_f64().unwrap()).powi(2))
        .sum::<f64>()
        .sqrt();
    // Thigh of a 1.75 m body: about 0.245 H = 0.43 m.
    assert!((0.3..0.55).contains(&dist), "{dist}");
}

#[test]
fn mesh_scene_without_a_glb_name_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let ply = d.path().join("p.ply");
    write_ply_f64(&ply, &[Point3::origin()]);
    let m = d.path().join("m.ply");
    let code = afford_cli::cli::main([
        "afford",
        "detect",
        ply.to_str().unwrap(),
        "--mesh",
        m.to_str().unwrap(),
        "--mesh-scene",
    ]);
    assert_eq!(code, 2);
    assert!(!m.exists());
}
