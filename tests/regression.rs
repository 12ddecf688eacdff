//! The regression gate: detection on the committed labelled set `data/regression` must
//! not score below its committed baseline (`data/regression/baseline.csv`) for any
//! affordance at any body height. Regenerate the baseline after a deliberate change with
//! `afford eval data/regression/labels.csv --heights 1.65,1.75,1.85 --csv data/regression/baseline.csv`.

use std::collections::BTreeMap;
use std::path::Path;

use afford::eval::evaluate;
use afford::model_set::{Source, BUILTIN_AGENTS, BUILTIN_HIERARCHIES};

/// `(height in mm, affordance) -> F` of the main (non-doubtful) rows of an eval CSV.
fn baseline(path: &Path) -> BTreeMap<(u32, String), f64> {
    let mut r = csv::Reader::from_path(path).expect("baseline.csv is committed");
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
            ((height * 1000.0).round() as u32, row[id].to_string()),
            row[f].parse().unwrap(),
        );
    }
    out
}

#[test]
fn no_f_score_drops_below_the_baseline() {
    let base = baseline(Path::new("data/regression/baseline.csv"));
    assert!(
        base.len() >= 12,
        "baseline covers 3 heights x 4 affordances: {base:?}"
    );
    let heights = [1.65, 1.75, 1.85];
    let agent = Source::Builtin("human", BUILTIN_AGENTS[0].1);
    let hierarchies: Vec<Source> = BUILTIN_HIERARCHIES
        .iter()
        .map(|(n, t)| Source::Builtin(n, t))
        .collect();
    let ev = evaluate(
        Path::new("data/regression/labels.csv"),
        &heights,
        &agent,
        &hierarchies,
        &Default::default(),
        false,
    )
    .unwrap();
    assert!(ev.failed.is_empty(), "{:?}", ev.failed);
    let mut drops = Vec::new();
    for hr in &ev.heights {
        for s in &hr.scores {
            let key = ((hr.height * 1000.0).round() as u32, s.id.clone());
            if let (Some(&b), Some(f)) = (base.get(&key), s.f) {
                // Baseline values are printed to 4 decimals.
                if f < b - 5e-5 {
                    drops.push(format!(
                        "{} at {} m: F {f:.4} < baseline {b:.4}",
                        s.id, hr.height
                    ));
                }
            } else if base.contains_key(&key) {
                drops.push(format!(
                    "{} at {} m: no F (baseline {:?})",
                    s.id,
                    hr.height,
                    base.get(&key)
                ));
            }
        }
    }
    assert!(drops.is_empty(), "{}", drops.join("\n"));
}
