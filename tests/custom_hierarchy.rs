//! A new affordance added as data only: the hierarchy `perching` (sitting on a bar stool
//! with the feet on its footrest) exists only as the TOML text below, written to a
//! temporary file and loaded with `Hierarchy::load` against the built-in agent, as a
//! researcher following docs/models.md would. It must be found on a bar stool with a
//! footrest ring and not on the same stool without one, nor on a low chair.

use std::path::{Path, PathBuf};

use afford::detect::{detect, DetectConfig, Outcome};
use afford::mesh::Mesh;
use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;
use afford_synth::furniture::*;

use crate::common::bar_stool;

/// The hierarchy under test. Angles in degrees, lengths in metres unless "fraction of H".
const PERCHING: &str = r#"
name = "perching"
orientation = "parallel"
suppression_radius = 0.25      # fraction of H: one detection per stool

[hypothesis]
template_diameter = 0.17       # fraction of H: the loaded width of the buttocks (0.30 m)
gradient_radius = 0.25
flat_gradient = 0.05
discontinuity = [0.10, 0.40]
roughness = [0.015, 0.045]
# Bar stools are 0.65-0.80 m high: full from 0.37 H to 0.46 H (1.75 m: 0.65-0.80 m),
# nothing below 0.34 H (0.60 m; chairs are 0.40-0.50 m) or above 0.49 H (0.86 m).
height = [0.34, 0.37, 0.46, 0.49]
available = [0.3, 0.7]

[fit]
yaw_offsets = [0.0, -20.0, 20.0, -40.0, 40.0]
fallback_yaw_step = 30.0       # a round stool seat is flat: every 30 deg is tried
start_clearance = 0.04
max_drop = 0.20
sigma_d = 0.03
min_stability = 0.5
stability_band = 0.05
sample_spacing = 0.02
stability_links = ["pelvis"]
unchecked_links = ["shank_l", "shank_r", "foot_l", "foot_r"]  # unfolded by the node

[score]
sigma_theta = 20.0
epsilon = 0.1
min_local = 0.01
select = "most_specific"
support_angle = 50.0           # a footrest holds the feet from below, give or take 50 deg

[initial_pose]
hip_l = 90.0                   # thighs level on the seat
hip_r = 90.0
ankle_l = 20.0                 # toes a little down, onto a bar
ankle_r = 20.0
shoulder_l = -70.0             # arms forward, clear of the seat while the agent is lowered
shoulder_r = -70.0
elbow_l = 110.0
elbow_r = 110.0

# The shanks swing down and back, from 30 deg in front of vertical to 50 deg behind it,
# until a foot or shank rests on something that holds it from below; preferred with the
# shanks 25 deg behind vertical, heels drawn in towards the stool. From a bar-stool seat
# the feet cannot reach the floor (the soles stay ~0.3 m above it), so only a footrest
# can be found.
[[node]]
id = "perching"
links = ["shank_l", "shank_r", "foot_l", "foot_r"]
sweep = [
  { joint = "knee_l", theta1 = 60.0, theta2 = 140.0, thetad = 115.0 },
  { joint = "knee_r", theta1 = 60.0, theta2 = 140.0, thetad = 115.0 },
]
free_start = true              # feet that start in something are not resting on a footrest
release = [0.0, 0.0, 1.0]      # the footrest must hold the feet from below
"#;

/// Writes `text` as `perching.toml` in `dir` and returns its path.
fn write(dir: &tempfile::TempDir, text: &str) -> PathBuf {
    let path = dir.path().join("perching.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The built-in agent at body height `height` and the perching hierarchy loaded from a file.
fn models(height: f64) -> (Agent, Hierarchy) {
    let agent = Agent::from_toml(
        afford::model::set::BUILTIN_AGENT,
        Path::new("human.toml"),
        height,
    )
    .expect("the built-in agent loads");
    let dir = tempfile::tempdir().unwrap();
    let h = Hierarchy::load(&write(&dir, PERCHING), &agent).unwrap_or_else(|e| panic!("{e}"));
    (agent, h)
}

fn run(meshes: &[Mesh], height: f64) -> (Outcome, Agent) {
    let (agent, h) = models(height);
    let cloud = scene_cloud(meshes, 4000.0, 0.002, 7, true);
    (detect(&cloud, &agent, &h, &DetectConfig::default()), agent)
}

fn perches(o: &Outcome) -> bool {
    o.detections
        .iter()
        .any(|d| d.affordances.iter().any(|a| a == "perching"))
}

#[test]
fn perching_is_found_on_a_bar_stool_with_a_footrest() {
    for height in [1.65, 1.75, 1.85] {
        let (o, agent) = run(&bar_stool(true), height);
        assert!(perches(&o), "at body height {height}: {:?}", o.stats);
        let d = &o.detections[0];
        assert_eq!(d.hierarchy, "perching");
        // On the seat, with the knees bent past a right angle: the feet drawn back onto
        // the ring, not hanging straight down.
        assert!(d.seat.coords.xy().norm() < 0.18, "{:?}", d.seat);
        assert!((d.seat.z - 0.75).abs() < 0.03, "{:?}", d.seat);
        for knee in ["knee_l", "knee_r"] {
            let angle = d.pose[agent.joint_index(knee).unwrap()].1;
            assert!((95.0..140.0).contains(&angle), "{knee} at {angle} deg");
        }
    }
}

#[test]
fn perching_needs_the_footrest() {
    for height in [1.65, 1.75, 1.85] {
        let (o, _) = run(&bar_stool(false), height);
        // The seat is at perching height and the agent sits on it; only the feet find nothing.
        assert!(o.stats.fits > 0, "at body height {height}: {:?}", o.stats);
        assert!(!perches(&o), "at body height {height}: {:?}", o.detections);
    }
}

#[test]
fn a_low_chair_is_no_perch() {
    let (o, _) = run(&[chair(&ChairParams::default())], 1.75);
    // The height membership rules a 0.45 m seat out before any fitting.
    assert_eq!(o.stats.hypotheses, 0, "{:?}", o.stats);
    assert!(!perches(&o));
}

#[test]
fn a_broken_custom_hierarchy_is_refused_with_file_line_and_key() {
    let agent = Agent::from_toml(
        afford::model::set::BUILTIN_AGENT,
        Path::new("human.toml"),
        1.75,
    )
    .unwrap();
    let dir = tempfile::tempdir().unwrap();
    let bad = PERCHING.replace(
        "theta1 = 60.0, theta2 = 140.0",
        "theta1 = 60.0, theta2 = 170.0",
    );
    let path = write(&dir, &bad);
    let e = Hierarchy::load(&path, &agent).unwrap_err().to_string();
    let line = bad
        .lines()
        .position(|l| l.contains("theta2 = 170.0"))
        .unwrap()
        + 1;
    assert!(
        e.starts_with(&format!(
            "{}:{line}: node.perching.sweep.knee_l.theta2: joint `knee_l` at 170 deg is outside its limit 0.0 to 150.0 deg",
            path.display()
        )),
        "{e}"
    );
}

#[test]
fn the_examples_of_docs_models_md_load() {
    let doc = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/models.md"))
        .unwrap();
    let agent = Agent::from_toml(
        afford::model::set::BUILTIN_AGENT,
        Path::new("human.toml"),
        1.75,
    )
    .unwrap();
    let blocks: Vec<&str> = doc
        .split("```toml\n")
        .skip(1)
        .map(|b| b.split("```").next().unwrap_or(""))
        .collect();
    let mut kinds = Vec::new();
    for block in blocks {
        let at = Path::new("docs/models.md");
        if block.contains("[[joint]]") {
            Agent::from_toml(block, at, 1.75).unwrap_or_else(|e| panic!("{e}"));
            kinds.push("agent");
        } else {
            let h = Hierarchy::from_toml(block, at, &agent).unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(h.ids(), ["perching", "backrest"]);
            kinds.push("hierarchy");
        }
    }
    assert_eq!(kinds, ["agent", "agent", "hierarchy"]);
}

/// The colour of the first vertex of the posed-agent mesh of `o`'s detections, drawn with
/// the legend of `h`.
fn mesh_colour(o: &Outcome, h: &Hierarchy) -> [u8; 3] {
    let legend = afford::report::render::Legend::of([h]);
    let bytes = afford::report::agent_mesh::agent_mesh_bytes(&o.detections, &legend);
    let body = bytes
        .windows(11)
        .position(|w| w == b"end_header\n")
        .unwrap()
        + 11;
    bytes[body + 12..body + 15].try_into().unwrap()
}

#[test]
fn a_new_hierarchy_draws_in_its_own_colours() {
    let (o, _) = run(&bar_stool(true), 1.75);
    assert!(perches(&o));
    // Without a legend: the first colour of the node palette, not the grey of the unknown.
    let (_, h) = models(1.75);
    assert_eq!(
        mesh_colour(&o, &h),
        afford::model::hierarchy::NODE_PALETTE[0]
    );
    assert_ne!(
        mesh_colour(&o, &h),
        afford::report::render::OTHER_AFFORDANCE
    );
    // With one: the file's colour.
    let text = PERCHING.replace(
        "suppression_radius = 0.25",
        "legend = [{ id = \"perching\", colour = [10, 20, 30] }]\nsuppression_radius = 0.25",
    );
    let (agent, _) = models(1.75);
    let dir = tempfile::tempdir().unwrap();
    let h = Hierarchy::load(&write(&dir, &text), &agent).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(mesh_colour(&o, &h), [10, 20, 30]);
}
