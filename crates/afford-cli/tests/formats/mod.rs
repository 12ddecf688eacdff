//! The formats robots and scanners write (ROS 2 bags, E57, depth images) give the same
//! detections as the same points given as PLY, and the glTF output opens in an
//! independent reader with its named nodes and affordance colours.

mod bag;
mod depth;
mod glb;
mod scans;

use std::path::{Path, PathBuf};

use afford_synth::furniture::{chair, scene_cloud, ChairParams};
use nalgebra::Point3;
use serde_json::Value;

/// Runs the command line; panics with the arguments when it fails.
fn afford(args: &[&str]) {
    let mut all = vec!["afford"];
    all.extend(args);
    assert_eq!(afford_cli::cli::main(all.clone()), 0, "{all:?}");
}

/// Rounds to a multiple of 2^-10 m (about 1 mm): such coordinates below 8 km are exact in
/// float32 and survive every conversion of these formats, so a difference in the
/// detections is the reader's, not rounding's.
fn quantise(p: &Point3<f64>) -> Point3<f64> {
    p.map(|c| (c * 1024.0).round() / 1024.0)
}

/// A chair on a floor patch, sampled, quantised: the small scene every format carries.
fn chair_scene(yaw_deg: f64, seed: u64) -> Vec<Point3<f64>> {
    let m = chair(&ChairParams::default()).placed(0.3, -0.2, yaw_deg);
    scene_cloud(&[m], 3000.0, 0.002, seed, true)
        .points
        .iter()
        .map(quantise)
        .collect()
}

/// Writes `points` as binary PLY with double coordinates (exact for any f64).
fn write_ply_f64(path: &Path, points: &[Point3<f64>]) {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\n\
         property double x\nproperty double y\nproperty double z\nend_header\n",
        points.len()
    )
    .into_bytes();
    for p in points {
        for k in 0..3 {
            b.extend(p[k].to_le_bytes());
        }
    }
    std::fs::write(path, b).unwrap();
}

/// `afford detect FILE --json` with `extra` flags; the JSON document.
fn detect_json(dir: &Path, input: &Path, extra: &[&str]) -> Value {
    let out: PathBuf = dir.join(format!(
        "{}.json",
        input.file_name().unwrap().to_string_lossy()
    ));
    let mut args = vec![
        "detect",
        input.to_str().unwrap(),
        "--affordances",
        "sitting",
        "--quiet",
        "--json",
        out.to_str().unwrap(),
    ];
    args.extend(extra);
    afford(&args);
    serde_json::from_slice(&std::fs::read(&out).unwrap()).unwrap()
}

/// The detections of file entry `i`, and its point count: all that must agree between
/// two encodings of the same points.
fn detections(doc: &Value, i: usize) -> (Value, Value) {
    let f = &doc["files"][i];
    (f["detections"].clone(), f["points"].clone())
}

/// The file entry's detections must find the chair: a check that the scene is not empty
/// of affordances, so that equal detections mean something.
fn assert_finds_a_seat(doc: &Value, i: usize) {
    let d = doc["files"][i]["detections"].as_array().unwrap();
    assert!(
        d.iter().any(|d| d["affordances"]
            .as_array()
            .unwrap()
            .iter()
            .any(|a| a == "backrest")),
        "no seat with a backrest in {}",
        doc["files"][i]["file"]
    );
}

/// Writes the seed files of the fuzz targets `bag`, `e57` and `depth` into
/// `fuzz/corpus/` (run by hand: `cargo test --release -p afford-cli --test integration --
/// --ignored formats::write_fuzz_seeds`).
#[test]
#[ignore]
fn write_fuzz_seeds() {
    let root = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")).join("fuzz/corpus");
    let pts: Vec<Point3<f64>> = (0..6)
        .map(|k| Point3::new(k as f64 * 0.25, 1.0, 0.5))
        .collect();
    for t in ["bag", "e57", "depth"] {
        std::fs::create_dir_all(root.join(t)).unwrap();
    }
    bag::seeds(&root.join("bag"), &pts);
    scans::seed(&root.join("e57/seed_scans.e57"), &pts);
    afford::cloud::depth::write_depth_png(
        &root.join("depth/seed_depth.png"),
        4,
        &[0, 1000, 2000, 65535, 5, 6, 7, 8],
    )
    .unwrap();
}
