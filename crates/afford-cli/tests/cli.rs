//! The `afford` command line as a user runs it: outputs, exit codes and one-line errors.

use std::path::{Path, PathBuf};

use crate::common::{afford, text, SAMPLE};

/// The repository root, where the binary runs and `SAMPLE` resolves.
const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

fn tmp() -> tempfile::TempDir {
    tempfile::tempdir().unwrap()
}

fn p(dir: &Path, name: &str) -> String {
    dir.join(name).display().to_string()
}

#[test]
fn the_sample_prints_a_table_of_detections() {
    let o = afford(&["detect", SAMPLE]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = text(&o.stdout);
    // Lying runs too, and finds no bed: a sofa seat is narrower than one
    // (docs/conventions.md).
    assert!(
        out.contains("detections; affords: sitting, armrest, backrest\n"),
        "{out}"
    );
    // Armchair, chair, stool and three sofa seats.
    assert_eq!(
        out.lines()
            .filter(|l| l.trim_start().starts_with('#'))
            .count(),
        6,
        "{out}"
    );
}

#[test]
fn outputs_follow_the_interfaces_and_do_not_depend_on_threads() {
    let d = tmp();
    let run = |threads: &str, tag: &str| {
        let o = afford(&[
            "detect",
            SAMPLE,
            "--threads",
            threads,
            "--json",
            &p(d.path(), &format!("{tag}.json")),
            "--csv",
            &p(d.path(), &format!("{tag}.csv")),
            "--summary",
            &p(d.path(), &format!("{tag}-summary.csv")),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
    };
    run("1", "one");
    run("2", "two");
    for f in ["json", "csv"] {
        let a = std::fs::read(d.path().join(format!("one.{f}"))).unwrap();
        let b = std::fs::read(d.path().join(format!("two.{f}"))).unwrap();
        assert_eq!(a, b, "{f} differs between 1 and 2 threads");
    }
    let csv = std::fs::read_to_string(d.path().join("one.csv")).unwrap();
    assert_eq!(
        csv.lines().next().unwrap(),
        "file,detection,hierarchy,x,y,z,yaw_deg,score,stability,affordances,segment_points,agent,height"
    );
    assert_eq!(csv.lines().count(), 7);
    assert!(csv.contains("sitting;armrest;backrest"), "{csv}");
    let summary = std::fs::read_to_string(d.path().join("one-summary.csv")).unwrap();
    assert_eq!(
        summary,
        format!(
            "file,sitting,armrest,backrest,headrest,lying,elongated_body,raised_body,\
             stretched_legs,raised_legs,agent,height\n{SAMPLE},1,1,1,0,0,0,0,0,0,human,1.750\n"
        )
    );
    let json: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.path().join("one.json")).unwrap()).unwrap();
    assert_eq!(json["version"], afford::report::JSON_VERSION);
    let det = &json["files"][0]["detections"][0];
    assert_eq!(det["agent"], "human");
    assert_eq!(det["height"], 1.75);
    assert!(det["pose_deg"]["knee_l"].as_f64().unwrap() > 50.0);
    assert!(det["segment_points"].as_u64().unwrap() > 500);
    // No temporary files are left behind.
    let names: Vec<String> = std::fs::read_dir(d.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.iter().all(|n| !n.contains("tmp-")), "{names:?}");
}

#[test]
fn segments_carry_a_detection_index_per_point() {
    let d = tmp();
    let seg = p(d.path(), "seg.ply");
    let o = afford(&[
        "detect",
        SAMPLE,
        "--segments",
        &seg,
        "--summary",
        &p(d.path(), "s.csv"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let bytes = std::fs::read(&seg).unwrap();
    let header = text(&bytes[..1000.min(bytes.len())]);
    assert!(header.contains("property int detection"), "{header}");
    assert!(
        header.contains("comment affordance 2 armrest\n"),
        "{header}"
    );
    let n = afford::cloud::read_ply(Path::new(&seg)).unwrap().len();
    let m = afford::cloud::read_ply(&Path::new(ROOT).join(SAMPLE))
        .unwrap()
        .len();
    assert_eq!(n, m);
    // The sample's armchair and chair (armrest, code 2) and stool (sitting, code 1).
    let code = afford::cloud::read_ply_property(Path::new(&seg), "affordance").unwrap();
    let code = code.unwrap();
    for c in [0.0, 1.0, 2.0] {
        assert!(code.contains(&c), "no point with affordance {c}");
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let f = dir.join(name);
    std::fs::write(&f, bytes).unwrap();
    f
}

#[test]
fn a_bad_file_gets_one_line_and_the_others_are_still_processed() {
    let d = tmp();
    let bad_header = write(
        d.path(),
        "bad.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 10\nproperty float x\nend_header\n",
    );
    let truncated = write(
        d.path(),
        "short.ply",
        b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0",
    );
    let missing = d.path().join("missing.pcd");
    let summary = p(d.path(), "summary.csv");
    let o = afford(&[
        "detect",
        "--quiet",
        &bad_header.display().to_string(),
        SAMPLE,
        &truncated.display().to_string(),
        &missing.display().to_string(),
        "--summary",
        &summary,
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    let errors: Vec<&str> = err.lines().filter(|l| l.starts_with("error:")).collect();
    assert_eq!(errors.len(), 3, "{err}");
    assert!(
        errors[0].contains("bad.ply") && errors[0].contains('y'),
        "{}",
        errors[0]
    );
    assert!(errors[1].contains("short.ply"), "{}", errors[1]);
    assert!(errors[2].contains("missing.pcd"), "{}", errors[2]);
    let s = std::fs::read_to_string(&summary).unwrap();
    assert_eq!(s.lines().count(), 2, "the good file is summarised: {s}");
    assert!(s.contains(SAMPLE));
}

#[test]
fn an_empty_cloud_and_non_finite_points() {
    let d = tmp();
    let empty = write(d.path(), "empty.ply", b"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n");
    let nan = write(
        d.path(),
        "nan.xyz",
        b"0 0 0\nnan 1 1\n1 inf 2\n0.5 0.5 0.5\n",
    );
    let o = afford(&[
        "detect",
        &empty.display().to_string(),
        &nan.display().to_string(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let err = text(&o.stderr);
    assert!(
        err.contains("nan.xyz: dropped 2 points with non-finite coordinates"),
        "{err}"
    );
    assert!(text(&o.stdout)
        .contains("empty.ply: 0 points, 0 hypotheses, 0 detections; affords: nothing"));
}

#[test]
fn a_malformed_model_names_the_file_and_the_key() {
    let d = tmp();
    let h = std::fs::read_to_string(Path::new(ROOT).join("affordances/sitting.toml"))
        .unwrap()
        .replace("sigma_theta", "sigma_teta");
    let bad = write(d.path(), "bad.toml", h.as_bytes());
    let o = afford(&[
        "detect",
        SAMPLE,
        "--affordances",
        &bad.display().to_string(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let err = text(&o.stderr);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("bad.toml:") && err.contains("sigma_teta"),
        "{err}"
    );
    let a = std::fs::read_to_string(Path::new(ROOT).join("agents/human.toml"))
        .unwrap()
        .replace("parent = \"hip_l\"", "parent = \"hipl\"");
    let bad = write(d.path(), "agent.toml", a.as_bytes());
    let o = afford(&["detect", SAMPLE, "--agent", &bad.display().to_string()]);
    let err = text(&o.stderr);
    assert!(
        err.contains("agent.toml") && err.contains("knee_l.parent") && err.contains("hipl"),
        "{err}"
    );
}

#[test]
fn body_heights_outside_reason_are_refused() {
    let o = afford(&["detect", SAMPLE, "--height", "17.5"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("17.5"));
}

/// A source option given where no input is of its kind is named in one warning line,
/// and the run goes on as without it.
#[test]
fn source_options_that_no_input_reads_are_warned_about() {
    let o = afford(&[
        "detect",
        SAMPLE,
        "--intrinsics",
        "500,500,320,240",
        "--scan",
        "2",
    ]);
    assert_eq!(o.status.code(), Some(0));
    let err = text(&o.stderr);
    assert!(
        err.contains(
            "warning: --scan applies to E57 files (.e57); no input is one, so it is not used\n"
        ),
        "{err}"
    );
    assert!(
        err.contains("warning: --intrinsics applies to depth images (.png)"),
        "{err}"
    );
    let plain = afford(&["detect", SAMPLE]);
    assert_eq!(o.stdout, plain.stdout);
    assert!(!text(&plain.stderr).contains("warning"));
}

/// `synth --mesh` and `--models` render given meshes from every side: the options that
/// choose generated furniture and how it is seen are refused with them, not ignored.
#[test]
fn synth_refuses_furniture_options_with_given_meshes() {
    let d = tmp();
    let out = p(d.path(), "out");
    for extra in [
        &["--mix", "wide"][..],
        &["--all-round"],
        &["--count", "1", "1", "1", "1"],
    ] {
        for given in ["--mesh", "--models"] {
            let mut args = vec!["synth", "--out", &out, given, "x.ply"];
            args.extend_from_slice(extra);
            let o = afford(&args);
            assert_eq!(o.status.code(), Some(2), "{args:?}");
            let err = text(&o.stderr);
            assert!(err.contains("cannot be used with"), "{args:?}: {err}");
        }
    }
    assert!(!d.path().join("out").exists());
}

/// `--camera-height` and `--camera-distance` set the camera of mesh and model views only:
/// with furniture they are refused, and a range that is not one is refused with what was
/// wrong.
#[test]
fn synth_takes_a_camera_height_and_distance_for_given_meshes_only() {
    let d = tmp();
    let out = p(d.path(), "out");
    for flag in ["--camera-height", "--camera-distance"] {
        let o = afford(&["synth", "--out", &out, flag, "0.5,0.9"]);
        assert_eq!(o.status.code(), Some(2), "{flag}");
        assert!(text(&o.stderr).contains("--mesh"), "{}", text(&o.stderr));
        for bad in ["0.9,0.5", "0,1", "-1,1", "1", "a,b", "0.5,11"] {
            let o = afford(&[
                "synth",
                "--out",
                &out,
                "--mesh",
                "x.ply",
                &format!("{flag}={bad}"),
            ]);
            assert_eq!(o.status.code(), Some(2), "{flag} {bad}");
            assert!(
                text(&o.stderr).contains("MIN,MAX"),
                "{flag} {bad}: {}",
                text(&o.stderr)
            );
        }
    }
    assert!(!d.path().join("out").exists());
}

#[test]
fn a_camera_frame_in_millimetres_with_auto_floor_gives_the_same_affordances() {
    use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
    let d = tmp();
    let world = afford::cloud::read_ply(&Path::new(ROOT).join(SAMPLE)).unwrap();
    // A camera 1.6 m up, 3 m in front of the room, looking at it pitched 25 deg down:
    // camera axes x right, y down, z forward.
    let look = UnitQuaternion::face_towards(&Vector3::new(-0.9, 0.2, -0.42), &Vector3::z());
    let cam_in_world = Isometry3::from_parts(Translation3::new(3.0, 0.3, 1.6), look);
    // face_towards maps +z to the view direction and +y to up; the camera's y is down.
    let flip = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), std::f64::consts::PI);
    let world_to_cam =
        (cam_in_world * Isometry3::from_parts(Translation3::identity(), flip)).inverse();
    let cam: Vec<Point3<f64>> = world
        .iter()
        .map(|p| Point3::from((world_to_cam * p).coords * 1000.0))
        .collect();
    let file = d.path().join("camera.ply");
    afford::cloud::write_ply_points(&file, &cam, &[], true).unwrap();
    let direct = afford(&["detect", SAMPLE, "--summary", &p(d.path(), "a.csv")]);
    assert!(direct.status.success());
    let framed = afford(&[
        "detect",
        &file.display().to_string(),
        "--camera",
        "--units",
        "mm",
        "--floor",
        "auto",
        "--summary",
        &p(d.path(), "b.csv"),
    ]);
    assert!(framed.status.success(), "{}", text(&framed.stderr));
    assert!(
        text(&framed.stderr).contains("frame:"),
        "{}",
        text(&framed.stderr)
    );
    let row = |f: &str| {
        std::fs::read_to_string(d.path().join(f))
            .unwrap()
            .lines()
            .nth(1)
            .unwrap()
            .split_once(',')
            .unwrap()
            .1
            .to_string()
    };
    assert_eq!(row("a.csv"), row("b.csv"));
}

#[test]
fn convert_round_trips_through_pcd_and_ascii_ply() {
    let d = tmp();
    let pcd = p(d.path(), "room.pcd");
    let ply = p(d.path(), "room.ply");
    assert!(afford(&["convert", SAMPLE, &pcd]).status.success());
    let o = afford(&["convert", &pcd, &ply, "--ascii"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let a = afford::cloud::read_ply(&Path::new(ROOT).join(SAMPLE)).unwrap();
    let b = afford::cloud::read_ply(Path::new(&ply)).unwrap();
    assert_eq!(a.len(), b.len());
    assert!(
        a.iter().zip(&b).all(|(x, y)| (x - y).norm() < 1e-6),
        "same points, f32 precision"
    );
    let bad = afford(&["convert", SAMPLE, &p(d.path(), "room.las")]);
    assert_eq!(bad.status.code(), Some(2));
    assert!(text(&bad.stderr).contains("room.las"));
}

/// Errors that end a command are printed at the edge (`afford_cli::cli::main`): standard
/// error is exactly one line, byte for byte, and the exit code 2. Control characters in a
/// name are escaped there too, so the error stays one line.
#[test]
fn an_error_that_ends_a_command_is_one_exact_line() {
    use crate::common::{s, small_scene, write_xyz};
    let d = tmp();
    let x = s(&write_xyz(&d.path().join("x.xyz"), &small_scene(0.1)));
    let file = p(d.path(), "x.xyz");
    std::fs::create_dir_all(d.path().join("a")).unwrap();
    std::fs::create_dir_all(d.path().join("b")).unwrap();
    let a = s(&write_xyz(&d.path().join("a/chair.xyz"), &small_scene(0.1)));
    let b = s(&write_xyz(&d.path().join("b/chair.xyz"), &small_scene(0.1)));
    let seg = p(d.path(), "seg.ply");
    let pcd = p(d.path(), "out.pcd");
    let newline = p(d.path(), "two\nlines.xyz");
    let escaped = p(d.path(), "two\\nlines.xyz");
    let not_dir = "Not a directory (os error 20)";
    let (under_file, png_under_file) = (format!("{file}/sub"), format!("{file}/x.png"));
    let cases: Vec<(Vec<&str>, String)> = vec![
        (
            vec!["detect", &x, "--mesh-scene", "--mesh", &seg],
            "--mesh-scene puts the cloud into a glTF mesh: give --mesh NAME.glb".into(),
        ),
        (
            vec!["detect", &x, "--out-dir", &under_file],
            format!("{file}/sub: cannot create: {not_dir}"),
        ),
        (
            vec!["detect", &a, &b, "--segments", &seg],
            format!(
                "--segments: {a} and {b} would both be written to {}",
                p(d.path(), "seg.chair.ply")
            ),
        ),
        (
            vec!["detect", &x, "--transform", "no_such_matrix"],
            "--transform no_such_matrix: no such file, and not a matrix of 16 numbers".into(),
        ),
        (
            vec!["inspect", &x, "--png", &png_under_file],
            format!("{file}/x.png: cannot write: {not_dir}"),
        ),
        (
            vec!["synth", "--out", &under_file, "--count", "0", "0", "0", "0"],
            format!("{file}/sub: cannot create: {not_dir}"),
        ),
        (
            vec!["convert", &x, &x],
            format!("{x}: is the input; refusing to replace it"),
        ),
        (
            vec!["convert", &x, &pcd, "--ascii"],
            format!("{pcd}: ascii output is written as PLY only"),
        ),
        (
            vec!["convert", &x, &newline],
            format!("{escaped}: write .ply or .pcd"),
        ),
    ];
    for (args, line) in cases {
        let o = afford(&args);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert_eq!(text(&o.stderr), format!("error: {line}\n"), "{args:?}");
        assert!(o.stdout.is_empty(), "{args:?}");
    }
}
