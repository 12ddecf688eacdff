//! The real-scan regression gate: detection on the small real Kinect clouds committed in
//! `data/real` (crops and subsampled frames of PCL and TUM RGB-D scans, provenance and
//! licences in `data/real/README.md`) must not score below `data/real/baseline.csv` for
//! any affordance at any body height. Regenerate the baseline after a deliberate change with
//! `afford eval data/real/labels.csv --heights 1.65,1.75,1.85 --csv data/real/baseline.csv`.

mod common;

use std::path::Path;

#[test]
fn no_f_score_on_real_scans_drops_below_the_baseline() {
    let base = common::baseline(Path::new("data/real/baseline.csv"));
    for h in [1650, 1750, 1850] {
        for id in ["sitting", "backrest"] {
            assert!(
                base.contains_key(&(h, id.to_string())),
                "baseline has {id} at {h} mm: {base:?}"
            );
        }
    }
    let drops = common::drops_below(
        Path::new("data/real/labels.csv"),
        &base,
        &[1.65, 1.75, 1.85],
    );
    assert!(drops.is_empty(), "{}", drops.join("\n"));
}
