//! The regression gate: detection on the committed labelled set `data/regression` must
//! not score below its committed baseline (`data/regression/baseline.csv`) for any
//! affordance at any body height. Regenerate the baseline after a deliberate change with
//! `afford eval data/regression/labels.csv --heights 1.65,1.75,1.85 --csv data/regression/baseline.csv`.

use crate::common;

use std::path::Path;

#[test]
fn no_f_score_drops_below_the_baseline() {
    let base = common::baseline(Path::new("data/regression/baseline.csv"));
    assert!(
        base.len() >= 12,
        "baseline covers 3 heights x 4 affordances: {base:?}"
    );
    let drops = common::drops_below(
        Path::new("data/regression/labels.csv"),
        &base,
        &[1.65, 1.75, 1.85],
    );
    assert!(drops.is_empty(), "{}", drops.join("\n"));
}
