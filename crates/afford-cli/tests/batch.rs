//! Batch runs as a script or a cluster runs them: lists, shards, per-file outputs with
//! resume, the JSON log line, exit codes, and `afford eval --from` merging shards.

use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

use crate::common::{s, text};

fn afford_in(dir: &Path, args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_afford"))
        .current_dir(dir)
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("runs");
    let mut input = child.stdin.take().unwrap();
    input
        .write_all(stdin.unwrap_or("").as_bytes())
        .expect("stdin");
    drop(input);
    child.wait_with_output().expect("runs")
}

fn afford(args: &[&str]) -> Output {
    afford_in(
        Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../..")),
        args,
        None,
    )
}

/// `n` tiny clouds (a few points: read and detected in no time) in `dir`, named `c00.xyz`...
fn tiny_clouds(dir: &Path, n: usize) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let f = dir.join(format!("c{i:02}.xyz"));
            std::fs::write(&f, format!("0 0 0\n0.{i} 0.5 0.4\n1 1 0.{i}\n")).unwrap();
            f
        })
        .collect()
}

/// A temporary folder holding a folder `name` of `n` tiny clouds.
fn folder_of_clouds(name: &str, n: usize) -> (tempfile::TempDir, PathBuf) {
    let d = tempfile::tempdir().unwrap();
    let data = d.path().join(name);
    std::fs::create_dir(&data).unwrap();
    tiny_clouds(&data, n);
    (d, data)
}

/// The `--log-json` lines of a run, parsed.
fn log_lines(o: &Output) -> Vec<serde_json::Value> {
    text(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect()
}

fn files_of(lines: &[serde_json::Value]) -> Vec<String> {
    lines
        .iter()
        .map(|l| l["file"].as_str().unwrap().to_string())
        .collect()
}

fn names_in(dir: &Path) -> BTreeSet<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect()
}

#[test]
fn shards_of_a_folder_are_disjoint_and_complete() {
    let d = tempfile::tempdir().unwrap();
    let clouds = tiny_clouds(d.path(), 7);
    let mut seen = Vec::new();
    for k in 1..=3 {
        let o = afford(&[
            "detect",
            &s(d.path()),
            "--shard",
            &format!("{k}/3"),
            "--log-json",
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let files = files_of(&log_lines(&o));
        assert!(!files.is_empty());
        assert!(
            text(&o.stderr).contains(&format!("shard {k}/3: {} of 7 files", files.len())),
            "{}",
            text(&o.stderr)
        );
        seen.extend(files);
    }
    seen.sort();
    let want: Vec<String> = clouds.iter().map(|c| s(c)).collect();
    assert_eq!(seen, want, "every file in exactly one shard");

    for bad in ["0/3", "4/3", "3", "1/0"] {
        let o = afford(&["detect", &s(d.path()), "--shard", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(text(&o.stderr).contains(bad), "{}", text(&o.stderr));
    }
}

#[test]
fn a_list_file_names_inputs_relative_to_itself_and_can_be_read_from_stdin() {
    let (d, sub) = folder_of_clouds("scans", 3);
    let list = d.path().join("list.txt");
    std::fs::write(
        &list,
        "# day one\nscans/c02.xyz\n\n  scans/c00.xyz  \n# scans/c01.xyz\n",
    )
    .unwrap();
    let o = afford(&["detect", "--list", &s(&list), "--log-json"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let want = [s(&sub.join("c02.xyz")), s(&sub.join("c00.xyz"))];
    assert_eq!(files_of(&log_lines(&o)), want);

    // `-`: standard input, relative to the working directory.
    let o = afford_in(
        d.path(),
        &["detect", "--list", "-", "--log-json"],
        Some("scans/c01.xyz\n# no\nscans\n"),
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(
        files_of(&log_lines(&o)),
        [
            "scans/c01.xyz",
            "scans/c00.xyz",
            "scans/c01.xyz",
            "scans/c02.xyz"
        ]
    );

    let o = afford(&["detect", "--list", &s(&d.path().join("nope.txt"))]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(text(&o.stderr).lines().count(), 1, "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("nope.txt"));
}

#[test]
fn resume_skips_inputs_whose_results_are_saved() {
    let (d, data) = folder_of_clouds("data", 3);
    let out = d.path().join("out");
    let run = |resume: bool| {
        let mut args = vec!["detect", data.to_str().unwrap(), "--log-json", "--out-dir"];
        args.push(out.to_str().unwrap());
        if resume {
            args.push("--resume");
        }
        let o = afford(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
        log_lines(&o)
    };
    let first = run(false);
    assert!(first.iter().all(|l| l["status"] == "ok"));
    assert_eq!(
        names_in(&out),
        ["c00.xyz.json", "c01.xyz.json", "c02.xyz.json"]
            .map(String::from)
            .into()
    );
    let saved: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("c01.xyz.json")).unwrap()).unwrap();
    assert_eq!(saved["version"], afford::report::JSON_VERSION);
    assert_eq!(saved["files"].as_array().unwrap().len(), 1);
    assert_eq!(saved["files"][0]["file"], s(&data.join("c01.xyz")));

    // Mark one saved result (a trailing blank: still the same JSON, made with the same
    // models) and remove another: resume keeps the first, redoes the second.
    let kept = std::fs::read_to_string(out.join("c00.xyz.json")).unwrap() + " ";
    std::fs::write(out.join("c00.xyz.json"), &kept).unwrap();
    std::fs::remove_file(out.join("c02.xyz.json")).unwrap();
    let again = run(true);
    let status: Vec<&str> = again
        .iter()
        .map(|l| l["status"].as_str().unwrap())
        .collect();
    assert_eq!(status, ["skipped", "skipped", "ok"]);
    assert_eq!(
        std::fs::read_to_string(out.join("c00.xyz.json")).unwrap(),
        kept
    );
    assert!(out.join("c02.xyz.json").exists());

    let o = afford(&["detect", data.to_str().unwrap(), "--resume"]);
    assert_eq!(o.status.code(), Some(2), "--resume without --out-dir");
}

#[test]
fn a_failing_file_is_logged_and_counted_and_the_others_are_saved() {
    let (d, data) = folder_of_clouds("data", 2);
    std::fs::write(
        data.join("b_bad.ply"),
        "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\nend_header\n1\n",
    )
    .unwrap();
    let out = d.path().join("out");
    let summary = d.path().join("summary.csv");
    let o = afford(&[
        "detect",
        &s(&data),
        "--out-dir",
        &s(&out),
        "--summary",
        &s(&summary),
        "--log-json",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let lines = log_lines(&o);
    assert_eq!(lines.len(), 3);
    let bad = &lines[0];
    assert_eq!(bad["status"], "error");
    assert!(
        bad["error"].as_str().unwrap().contains("b_bad.ply"),
        "{bad}"
    );
    assert!(bad["seconds"].as_f64().is_some());
    assert!(bad.get("detections").is_none());
    for ok in &lines[1..] {
        assert_eq!(ok["status"], "ok", "{ok}");
        assert_eq!(ok["points"], 3);
        assert_eq!(ok["detections"], 0);
        assert_eq!(ok["affordances"], serde_json::json!([]));
    }
    let err = text(&o.stderr);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(err.contains("3 files, 1 failed"), "{err}");
    assert_eq!(
        names_in(&out),
        ["c00.xyz.json", "c01.xyz.json"].map(String::from).into()
    );
    assert_eq!(
        std::fs::read_to_string(&summary).unwrap().lines().count(),
        3
    );
}

#[test]
fn each_table_is_written_as_its_file_ends() {
    use std::sync::{Arc, Mutex};
    /// Both streams of a run into one sequence, so their order shows.
    struct Tagged(&'static str, Arc<Mutex<Vec<String>>>);
    impl Write for Tagged {
        fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
            self.1
                .lock()
                .unwrap()
                .push(format!("{}{}", self.0, String::from_utf8_lossy(buf)));
            Ok(buf.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }
    let d = tempfile::tempdir().unwrap();
    let clouds = tiny_clouds(d.path(), 2);
    let req = afford_cli::run::DetectRequest {
        files: vec![
            clouds[0].clone(),
            d.path().join("missing.pcd"),
            clouds[1].clone(),
        ],
        lists: Vec::new(),
        shard: None,
        out_dir: None,
        resume: false,
        log_json: false,
        settings: Default::default(),
        json: None,
        csv: None,
        summary: None,
        segments: None,
        mesh: None,
        mesh_scene: false,
        progress: false,
    };
    let seq = Arc::new(Mutex::new(Vec::new()));
    let outcome = afford_cli::run::run_detect(
        &req,
        &mut Tagged("out: ", seq.clone()),
        &mut Tagged("err: ", seq.clone()),
    );
    assert_eq!(outcome.unwrap(), afford_cli::run::Outcome::Failed);
    let seq = seq.lock().unwrap().join("");
    let at = |what: &str| seq.find(what).unwrap_or_else(|| panic!("{what}: {seq}"));
    assert!(at("c00.xyz: 3 points") < at("missing.pcd"), "{seq}");
    assert!(at("missing.pcd") < at("c01.xyz: 3 points"), "{seq}");
}

/// The markdown of an evaluation without its segmentation part (saved outputs have none).
fn without_segmentation(md: &str) -> String {
    let mut out = String::new();
    let mut skip = false;
    for l in md.lines() {
        if l.starts_with("Segmentation") {
            skip = true;
        } else if skip && (l.is_empty() || l.starts_with("- ")) {
            continue;
        } else {
            skip = false;
        }
        if !skip {
            out.push_str(l);
            out.push('\n');
        }
    }
    out
}

#[test]
fn eval_of_two_merged_shards_scores_as_eval_run_directly() {
    let d = tempfile::tempdir().unwrap();
    let set = d.path().join("set");
    let o = afford(&[
        "synth",
        "--out",
        &s(&set),
        "--seed",
        "5",
        "--count",
        "1",
        "2",
        "1",
        "0",
        "--stride",
        "4",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let labels = s(&set.join("labels.csv"));
    // The sitting hierarchy alone keeps it quick; two heights check per-height scoring.
    let common = ["--affordances", "sitting"];
    let eval = |more: &[&str]| {
        let mut args = vec!["eval", &labels, "--heights", "1.65,1.75"];
        args.extend(common);
        args.extend(more);
        afford(&args)
    };
    let direct_csv = s(&d.path().join("direct.csv"));
    let direct = eval(&["--csv", &direct_csv]);
    assert!(direct.status.success(), "{}", text(&direct.stderr));

    // Shard 1 saves per-file JSON in a folder, shard 2 writes a run-wide JSON.
    let saved = d.path().join("saved");
    let whole = s(&d.path().join("shard2.json"));
    for (k, out) in [
        ("1/2", ["--out-dir", &s(&saved)]),
        ("2/2", ["--json", &whole]),
    ] {
        let mut args = vec!["detect", set.to_str().unwrap(), "--height", "1.65,1.75"];
        args.extend(["--shard", k]);
        args.extend(out);
        args.extend(common);
        let o = afford(&args);
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    assert_eq!(names_in(&saved).len(), 2);

    let merged_csv = s(&d.path().join("merged.csv"));
    let merged = eval(&[
        "--csv",
        &merged_csv,
        "--from",
        saved.to_str().unwrap(),
        &whole,
    ]);
    assert!(merged.status.success(), "{}", text(&merged.stderr));
    let (a, b) = (text(&direct.stdout), text(&merged.stdout));
    assert!(a.contains("4 files scored, 0 doubtful, 0 failed"), "{a}");
    assert_eq!(without_segmentation(&a), without_segmentation(&b));
    assert!(b.contains("Segmentation: not scored"), "{b}");
    assert_eq!(
        std::fs::read(&direct_csv).unwrap(),
        std::fs::read(&merged_csv).unwrap()
    );

    // A shard missing from the merge: its files count as failed, exit code 2.
    let part = eval(&["--from", saved.to_str().unwrap()]);
    assert_eq!(part.status.code(), Some(2));
    assert!(
        text(&part.stdout).contains("2 files scored, 0 doubtful, 2 failed"),
        "{}",
        text(&part.stdout)
    );
}
