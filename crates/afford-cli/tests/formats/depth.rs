//! Depth images: a 16-bit PNG rendered from a known scene, with its intrinsics.

use afford::cloud::depth::write_depth_png;
use afford_synth::camera::{Bvh, Camera};
use afford_synth::furniture::{floor, scene_mesh};
use nalgebra::{Point3, Vector3};

use super::*;

const W: u32 = 320;
const H: u32 = 240;
/// fx, fy, cx, cy of a 320 x 240 camera with a 58 degree horizontal field of view.
const K: [f64; 4] = [285.0, 285.0, 159.5, 119.5];

#[test]
fn a_depth_png_gives_the_detections_of_its_points_as_ply() {
    let d = tempfile::tempdir().unwrap();
    let m = chair(&ChairParams::default()).placed(0.3, -0.2, 0.0);
    // A room-sized floor, so that --floor auto finds it in the view.
    let mesh = scene_mesh(&[m, floor(-2.0, -3.0, 4.0, 3.0)], false);
    let bvh = Bvh::new(&mesh);
    let cam = Camera::looking_at(Point3::new(2.4, -0.1, 1.0), Point3::new(0.3, -0.2, 0.45));
    let (forward, right, up) = cam.basis();
    // Render: depth along the optical axis (z), millimetres, 0 where nothing is hit.
    let mut depth = vec![0u16; (W * H) as usize];
    for v in 0..H {
        for u in 0..W {
            let c = Vector3::new((u as f64 - K[2]) / K[0], (v as f64 - K[3]) / K[1], 1.0);
            let world = right * c.x - up * c.y + forward * c.z;
            if let Some(hit) = bvh.cast(&cam.position, &world.normalize()) {
                let z = hit.t / c.norm();
                if z < 6.0 {
                    // Under 6 m: at most 6000 mm, a u16.
                    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                    let mm = (z * 1000.0).round() as u16;
                    depth[(v * W + u) as usize] = mm;
                }
            }
        }
    }
    let png = d.path().join("frame.png");
    write_depth_png(&png, W, &depth).unwrap();
    // The same points, back-projected here, in the camera frame, as PLY.
    let mut pts = Vec::new();
    for v in 0..H {
        for u in 0..W {
            let z = depth[(v * W + u) as usize] as f64 * 0.001;
            if z > 0.0 {
                pts.push(Point3::new(
                    (u as f64 - K[2]) * z / K[0],
                    (v as f64 - K[3]) * z / K[1],
                    z,
                ));
            }
        }
    }
    let ply = d.path().join("frame.ply");
    write_ply_f64(&ply, &pts);
    let want = detect_json(d.path(), &ply, &["--camera", "--floor", "auto"]);
    assert_finds_a_seat(&want, 0);
    let k = K.map(|x| x.to_string()).join(",");
    let got = detect_json(
        d.path(),
        &png,
        &[
            "--intrinsics",
            &k,
            "--depth-scale",
            "0.001",
            "--floor",
            "auto",
        ],
    );
    assert_eq!(detections(&got, 0), detections(&want, 0));
    // Read at twice the scale, the scene is twice as far and twice as large.
    let mut far = Vec::new();
    let k: afford::cloud::source::Intrinsics = k.parse().unwrap();
    let opts = afford::cloud::source::SourceOptions {
        intrinsics: Some(k),
        depth_scale: 0.002,
        ..Default::default()
    };
    afford::cloud::source::read_parts(&png, &opts, &mut |p| far = p.cloud.cloud.points).unwrap();
    assert_eq!(far.len(), pts.len());
    for (a, b) in far.iter().zip(&pts) {
        assert!((a.coords - b.coords * 2.0).norm() < 1e-12);
    }
}

#[test]
fn a_depth_png_without_intrinsics_or_damaged_is_one_line() {
    let d = tempfile::tempdir().unwrap();
    let png = d.path().join("d.png");
    write_depth_png(&png, 4, &[1000; 16]).unwrap();
    let e = afford::cloud::load(&png).unwrap_err().to_string();
    assert!(e.contains("d.png") && e.contains("--intrinsics"), "{e}");
    let bytes = std::fs::read(&png).unwrap();
    let opts = afford::cloud::source::SourceOptions {
        intrinsics: Some("1,1,0,0".parse().unwrap()),
        ..Default::default()
    };
    for n in 0..bytes.len() - 12 {
        let cut = d.path().join("cut.png");
        std::fs::write(&cut, &bytes[..n]).unwrap();
        let e = afford::cloud::source::read_parts(&cut, &opts, &mut |_| {})
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with(&cut.display().to_string()) && !e.contains('\n'),
            "{e}"
        );
    }
}
