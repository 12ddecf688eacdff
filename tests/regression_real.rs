//! The real-scan regression gate: detection on the small real Kinect clouds committed in
//! `data/real` (crops and subsampled frames of PCL and TUM RGB-D scans, provenance and
//! licences in `data/real/README.md`) must not score below `data/real/baseline.csv` for
//! any affordance at any body height. Regenerate the baseline after a deliberate change with
//! `afford eval data/real/labels.csv --heights 1.65,1.75,1.85 --csv data/real/baseline.csv`.

use crate::common;

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

/// Every committed real sample names its source (repository, path, 40-hex commit) and
/// licence, and stays small (under 1 MB each, 4 MB together) so the repository stays light.
#[test]
fn every_real_sample_has_provenance_and_is_small() {
    let dir = Path::new("data/real");
    let mut r = csv::Reader::from_path(dir.join("labels.csv")).unwrap();
    let header = r.headers().unwrap().clone();
    let col = |name: &str| header.iter().position(|h| h == name).unwrap();
    let (file, repo, path, commit, licence) = (
        col("file"),
        col("source_repo"),
        col("source_path"),
        col("commit"),
        col("licence"),
    );
    let (mut n, mut total) = (0, 0);
    for row in r.records() {
        let row = row.unwrap();
        let name = &row[file];
        assert!(row[repo].contains('/'), "{name}: source_repo owner/name");
        assert!(!row[path].is_empty(), "{name}: source_path");
        assert!(
            row[commit].len() == 40 && row[commit].chars().all(|c| c.is_ascii_hexdigit()),
            "{name}: commit is 40 hex digits"
        );
        assert!(!row[licence].is_empty(), "{name}: licence");
        let size = std::fs::metadata(dir.join(name)).unwrap().len();
        assert!(size < 1_000_000, "{name}: {size} bytes");
        total += size;
        n += 1;
    }
    assert!(n >= 4, "at least four samples, found {n}");
    assert!(total < 4_000_000, "samples total {total} bytes");
}
