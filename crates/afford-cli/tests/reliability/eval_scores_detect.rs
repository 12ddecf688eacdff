//! Cause: `afford eval` ran its own copy of the per-file path (`detect_all` on the whole
//! cloud), without the extent guard that `afford detect` runs before building its grids
//! (`afford::method::extent`): stray regions far from the bulk of the points were left in
//! eval's height map and scene, so eval found seats in them that detect never looks at (and
//! on the PCL room scans, whose height-map grid is anchored at the strays' corner, eval
//! found seats where detect found none). Both now call `afford::detect::detect_input`.

use crate::common::*;

/// Points of the plane `z` over `[x0, x1] x [y0, y1]`, every `step` metres.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)] // small positive counts of the test's own planes
fn plane(pts: &mut Vec<[f64; 3]>, x: [f64; 2], y: [f64; 2], z: f64, step: f64) {
    let (nx, ny) = (
        ((x[1] - x[0]) / step).round() as usize,
        ((y[1] - y[0]) / step).round() as usize,
    );
    for i in 0..=nx {
        for j in 0..=ny {
            pts.push([x[0] + i as f64 * step, y[0] + j as f64 * step, z]);
        }
    }
}

/// The affordance ids marked 1 in each row of a `--summary` CSV, with the row's height.
fn summary_found(text: &str) -> Vec<(String, Vec<String>)> {
    let mut rd = csv::Reader::from_reader(text.as_bytes());
    let h = rd.headers().unwrap().clone();
    rd.records()
        .map(|r| {
            let r = r.unwrap();
            let found = h
                .iter()
                .zip(r.iter())
                .filter(|(k, v)| !matches!(*k, "file" | "agent" | "height") && *v == "1")
                .map(|(k, _)| k.to_string())
                .collect();
            (r[h.len() - 1].to_string(), found)
        })
        .collect()
}

#[test]
fn eval_finds_in_a_file_what_detect_finds() {
    // A stool (a 0.5 m box top at 0.45 m) on a 2 m floor, dense; 5 m away, a chair with a
    // backrest on a patch of floor: under 1 % of the points, a stray region to the guard.
    let mut pts = small_scene(0.005);
    let bulk = pts.len();
    plane(&mut pts, [6.7, 7.8], [0.5, 1.5], 0.0, 0.05);
    plane(&mut pts, [7.0, 7.44], [0.78, 1.22], 0.45, 0.02);
    for j in 0..=22 {
        for k in 0..=24 {
            pts.push([7.0, 0.78 + j as f64 * 0.02, 0.47 + k as f64 * 0.02]);
        }
    }
    assert!((pts.len() - bulk) * 100 < pts.len(), "the chair is stray");
    let d = tempfile::tempdir().unwrap();
    let file = write_xyz(&d.path().join("stool.xyz"), &pts);
    let summary = d.path().join("summary.csv");
    let o = afford(&[
        "detect",
        &s(&file),
        "--heights",
        "1.65,1.85",
        "--summary",
        &s(&summary),
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let detected = summary_found(&std::fs::read_to_string(&summary).unwrap());
    // Eval lists what it found in a doubtful row as it is.
    let labels = d.path().join("labels.csv");
    std::fs::write(&labels, "file,sitting,doubtful\nstool.xyz,1,any\n").unwrap();
    let json = d.path().join("eval.json");
    let o = afford(&[
        "eval",
        &s(&labels),
        "--heights",
        "1.65,1.85",
        "--json",
        &s(&json),
        "--quiet",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", text(&o.stderr));
    let ev: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let evaluated: Vec<(String, Vec<String>)> = ev["heights"]
        .as_array()
        .unwrap()
        .iter()
        .map(|h| {
            let found = &h["doubtful_found"][0];
            assert_eq!(found[0], "stool.xyz");
            let ids = found[1].as_array().unwrap();
            (
                format!("{:.3}", h["height"].as_f64().unwrap()),
                ids.iter()
                    .map(|i| i.as_str().unwrap().to_string())
                    .collect(),
            )
        })
        .collect();
    assert_eq!(evaluated, detected);
    // The stool is found at both heights; the stray chair's backrest is not.
    for (_, found) in &detected {
        assert_eq!(found, &["sitting"], "{detected:?}");
    }
}
