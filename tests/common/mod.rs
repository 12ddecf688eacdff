//! The F-score gate shared by the regression tests: detection on a committed labelled set
//! must not score below its committed baseline CSV for any affordance at any body height.

use std::collections::BTreeMap;
use std::path::Path;

use afford::detect::{DetectConfig, DEFAULT_VOXEL};
use afford::eval::evaluate;
use afford::mesh::{Mesh, Part};
use afford::model::set::ModelChoice;
use afford_synth::furniture::{stool, StoolParams};
use nalgebra::Point3;

/// `(height in mm, affordance) -> F` of the main (non-doubtful) rows of an eval CSV.
pub(crate) fn baseline(path: &Path) -> BTreeMap<(u32, String), f64> {
    let mut r = csv::Reader::from_path(path).expect("baseline CSV is committed");
    let header = r.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (h, set, id, f) = (col("height"), col("set"), col("affordance"), col("f"));
    let mut out = BTreeMap::new();
    for row in r.records() {
        let row = row.unwrap();
        if &row[set] != "main" || row[f].is_empty() {
            continue;
        }
        let height: f64 = row[h].parse().unwrap();
        out.insert(
            (millimetres(height), row[id].to_string()),
            row[f].parse().unwrap(),
        );
    }
    out
}

/// Runs `afford eval` on `labels` with the built-in adult and hierarchies at `heights` and
/// returns one line per (height, affordance) whose F fell below `base`, or has no F where
/// the baseline has a positive one. Panics when a labelled file could not be scored.
pub(crate) fn drops_below(
    labels: &Path,
    base: &BTreeMap<(u32, String), f64>,
    heights: &[f64],
) -> Vec<String> {
    let models = ModelChoice {
        heights: heights.to_vec(),
        ..Default::default()
    };
    let cfg = DetectConfig::for_voxel(DEFAULT_VOXEL);
    let ev = evaluate(labels, &models, &cfg, &Default::default(), false).unwrap();
    assert!(ev.failed.is_empty(), "{:?}", ev.failed);
    let mut drops = Vec::new();
    for hr in &ev.heights {
        for s in &hr.scores {
            let key = (millimetres(hr.height), s.id.clone());
            match (base.get(&key), s.f) {
                // Baseline values are printed to 4 decimals.
                (Some(&b), Some(f)) if f < b - 5e-5 => drops.push(format!(
                    "{} at {} m: F {f:.4} < baseline {b:.4}",
                    s.id, hr.height
                )),
                // An F of 0 that becomes undefined (nothing labelled, nothing found) is
                // not a drop.
                (Some(&b), None) if b > 0.0 => drops.push(format!(
                    "{} at {} m: no F (baseline {b:.4})",
                    s.id, hr.height
                )),
                _ => {}
            }
        }
    }
    drops
}

/// A body height (metres, 0.3 to 3.0) in whole millimetres, as a map key.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn millimetres(height: f64) -> u32 {
    // At most 3000: a u32 holds it.
    (height * 1000.0).round() as u32
}

// Furniture shared by the topics.

/// A footrest ring around a stool's pedestal: a tube of radius `tube` bent into a circle of
/// radius `radius` at height `z` (metres), from 32 straight pieces.
pub(crate) fn footrest_ring(radius: f64, z: f64, tube: f64) -> Mesh {
    let mut m = Mesh::new();
    let n = 32;
    let at = |k: usize| {
        let t = std::f64::consts::TAU * k as f64 / n as f64;
        Point3::new(radius * t.cos(), radius * t.sin(), z)
    };
    for k in 0..n {
        m.add_cylinder(at(k), at(k + 1), tube, 12, Part::Other);
    }
    m
}

/// A bar stool (seat 0.75 m, 0.36 m across, on a pedestal), with a footrest ring 0.40 m
/// below the seat (0.22 m radius, 25 mm tube, as on common bar stools) when `footrest`.
pub(crate) fn bar_stool(footrest: bool) -> Vec<Mesh> {
    let mut meshes = vec![stool(&StoolParams::bar())];
    if footrest {
        meshes.push(footrest_ring(0.22, 0.35, 0.0125));
    }
    meshes
}
