//! The pipeline on clouds built in the test: which fine-grained affordances each piece of
//! furniture gives, and that the answer does not depend on where the scene stands or on
//! the number of threads.

use std::path::Path;

use afford::cloud::PointCloud;
use afford::detect::{detect, DetectConfig, Outcome};
use afford::mesh::{Mesh, Part};
use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;
use afford_synth::camera;
use afford_synth::furniture::*;
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};

use crate::common::bar_stool;

fn models(height: f64) -> (Agent, Hierarchy) {
    let agent = Agent::load(Path::new("agents/human.toml"), height).unwrap();
    let h = Hierarchy::load(Path::new("affordances/sitting.toml"), &agent).unwrap();
    (agent, h)
}

/// A full model sampled at 4000 points/m^2 with 2 mm noise, on a floor patch.
fn cloud(meshes: &[Mesh]) -> PointCloud {
    scene_cloud(meshes, 4000.0, 0.002, 7, true)
}

fn run(c: &PointCloud, height: f64) -> Outcome {
    let (agent, h) = models(height);
    detect(c, &agent, &h, &DetectConfig::default())
}

/// The affordances of the scene: those of any detection, in hierarchy order.
fn affords(o: &Outcome) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    for id in ["sitting", "backrest", "armrest", "headrest"] {
        if o.detections
            .iter()
            .any(|d| d.affordances.iter().any(|a| a == id))
        {
            out.push(id.to_string());
        }
    }
    out
}

fn check(meshes: &[Mesh], expected: &[&str]) {
    for height in [1.65, 1.75, 1.85] {
        let o = run(&cloud(meshes), height);
        assert_eq!(
            affords(&o),
            expected,
            "at body height {height}: {:?}",
            o.stats
        );
    }
}

#[test]
fn a_stool_affords_sitting_only() {
    check(&[stool(&StoolParams::default())], &["sitting"]);
}

#[test]
fn a_chair_adds_a_backrest() {
    check(&[chair(&ChairParams::default())], &["sitting", "backrest"]);
}

#[test]
fn an_armchair_adds_armrests() {
    check(
        &[chair(&ChairParams::with_arms())],
        &["sitting", "backrest", "armrest"],
    );
}

#[test]
fn a_high_back_chair_adds_a_headrest() {
    check(
        &[chair(&ChairParams::high_back())],
        &["sitting", "backrest", "headrest"],
    );
}

#[test]
fn a_stool_against_a_wall_affords_a_backrest() {
    // The paper's own example: the stool's seat edge 5 cm from the wall behind it. The
    // wall reaches far above the seat, so by the headrest convention (docs/conventions.md) leaning the
    // head back against it counts as a headrest too; the wall beside the arms is no armrest.
    let s = StoolParams::default();
    let wall_x = -(s.seat_size / 2.0 + 0.05);
    check(
        &[stool(&s), wall(wall_x - 0.05, -1.0, 1.0, 2.2, 0.1)],
        &["sitting", "backrest", "headrest"],
    );
}

#[test]
fn a_sofa_affords_armrests_at_its_ends() {
    let o = run(&cloud(&[sofa(&SofaParams::default())]), 1.75);
    assert!(o.detections.len() >= 2, "{} detections", o.detections.len());
    let with_arms: Vec<f64> = o
        .detections
        .iter()
        .filter(|d| d.affordances.iter().any(|a| a == "armrest"))
        .map(|d| d.seat.y)
        .collect();
    assert!(!with_arms.is_empty());
    // Only the end seats reach an arm: the sofa is 3 x 0.55 m wide.
    assert!(
        with_arms.iter().all(|y| y.abs() > 0.3),
        "armrest detections at y = {with_arms:?}"
    );
}

#[test]
fn the_samples_chair_at_its_table_gets_no_armrest_from_the_table_edge() {
    // In the committed sample the chair stands in front of the table (seat at x = 1.35 m,
    // y = 0): the forearm came down onto the table edge in front of the seat, which runs
    // on across the lap (`beside` of the armrest node). The armchair (x = 0) keeps its arms.
    let c = afford::cloud::load(Path::new("data/sample/room.ply"))
        .unwrap()
        .cloud;
    let o = run(&c, 1.75);
    let near = |x: f64| {
        o.detections
            .iter()
            .find(|d| (d.position.x - x).abs() < 0.3 && d.position.y.abs() < 0.3)
            .map(|d| d.affordances.clone())
    };
    assert_eq!(near(1.35).unwrap(), ["sitting", "backrest"]);
    assert_eq!(near(0.0).unwrap(), ["sitting", "armrest", "backrest"]);
}

#[test]
fn a_table_a_shelf_and_an_empty_floor_afford_nothing() {
    for meshes in [
        vec![table(&TableParams::default())],
        vec![shelf(&ShelfParams::default())],
        vec![floor(-1.5, -1.5, 1.5, 1.5)],
    ] {
        let o = run(&cloud(&meshes), 1.75);
        assert!(o.detections.is_empty(), "{:?}", o.stats);
    }
}

#[test]
fn an_empty_cloud_gives_no_detection() {
    let o = run(&PointCloud::default(), 1.75);
    assert!(o.detections.is_empty());
    assert_eq!(o.stats.points, 0);
}

#[test]
fn the_agent_sits_on_the_seat_facing_away_from_the_back() {
    let o = run(&cloud(&[chair(&ChairParams::default())]), 1.75);
    let d = &o.detections[0];
    let p = ChairParams::default();
    assert!(
        d.seat.x.abs() < p.seat_depth / 2.0 && d.seat.y.abs() < p.seat_width / 2.0,
        "seat {:?}",
        d.seat
    );
    assert!(
        (d.seat.z - p.seat_height).abs() < 0.03,
        "seat height {}",
        d.seat.z
    );
    // Facing +x, within the tried offsets.
    let yaw = d.yaw.to_degrees();
    let off = yaw.min(360.0 - yaw);
    assert!(off < 45.0, "yaw {yaw}");
    assert!(
        d.segment_points > 1000,
        "segment of {} points",
        d.segment_points
    );
}

#[test]
fn moving_the_scene_does_not_change_the_affordances() {
    let meshes = [chair(&ChairParams::with_arms())];
    let base = affords(&run(&cloud(&meshes), 1.75));
    for (yaw_deg, dx, dy) in [(90.0, 3.0, -2.0), (37.0, -10.0, 25.0), (200.0, 0.5, 0.5)] {
        let iso = Isometry3::from_parts(
            Translation3::new(dx, dy, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), f64::to_radians(yaw_deg)),
        );
        let moved = PointCloud::new(cloud(&meshes).points.iter().map(|p| iso * p).collect());
        let o = run(&moved, 1.75);
        assert_eq!(
            affords(&o),
            base,
            "turned {yaw_deg} deg and moved by ({dx}, {dy})"
        );
        let d = &o.detections[0];
        let local = iso.inverse() * Point3::new(d.seat.x, d.seat.y, d.seat.z);
        assert!(
            local.x.abs() < 0.25 && local.y.abs() < 0.25,
            "seat {local:?} in the chair's frame"
        );
    }
}

#[test]
fn output_does_not_depend_on_the_thread_count() {
    let c = cloud(&[
        sofa(&SofaParams::default()),
        chair(&ChairParams::with_arms()).placed(1.5, 0.0, 180.0),
    ]);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| run(&c, 1.75));
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| run(&c, 1.75));
    assert!(!one.detections.is_empty());
    assert_eq!(one, two);
}

/// A chair pushed in at a table: the table's top is larger than the chair's back within
/// the gradient's reach, so the plane fit descends towards the back and no heading round
/// it is free; the search of every heading then starts facing away from the back, whatever
/// the frame (it once started at the frame's +x, so the agent sat turned to the table's
/// edge in some frames and facing it in others).
#[test]
fn a_chair_pushed_in_at_a_table_faces_the_table_whatever_the_frame() {
    let meshes = [
        chair(&ChairParams::default()),
        table(&TableParams::default()).placed(0.55, 0.0, 90.0),
    ];
    for (yaw_deg, dx, dy) in [
        (0.0, 0.0, 0.0),
        (77.0, 2.0, -1.0),
        (160.0, -3.0, 4.0),
        (250.0, 0.5, 0.5),
    ] {
        let iso = Isometry3::from_parts(
            Translation3::new(dx, dy, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), f64::to_radians(yaw_deg)),
        );
        let moved = PointCloud::new(cloud(&meshes).points.iter().map(|p| iso * p).collect());
        let o = run(&moved, 1.75);
        let d = o
            .detections
            .iter()
            .find(|d| {
                let local = iso.inverse() * Point3::new(d.seat.x, d.seat.y, d.seat.z);
                local.x.abs() < 0.25 && local.y.abs() < 0.25
            })
            .unwrap_or_else(|| panic!("no seat on the chair turned {yaw_deg} deg: {:?}", o.stats));
        // The agent's heading in the chair's frame, where the table is at +x.
        let turn = (d.yaw.to_degrees() - yaw_deg).rem_euclid(360.0);
        let off = turn.min(360.0 - turn);
        assert!(
            off < 45.0,
            "turned {yaw_deg} deg: the agent faces {turn} deg in the chair's frame"
        );
    }
}

/// A wooden armchair whose arm rails rest on the front legs carried up as posts and run
/// back to the back posts right over the seat's side edges (issue 11: 12 of
/// 16 such chairs got no sitting: the rails flank the seat, the gradient heading is off by
/// 90 degrees, and the raised arms of the initial pose meet a rail at every heading).
fn wooden_armchair() -> Mesh {
    let (hx, hy, seat, leg) = (0.23, 0.27, 0.44, 0.04);
    let (rail_top, rail_w) = (seat + 0.22, 0.05);
    let mut m = Mesh::new();
    let p = Point3::new;
    m.add_box(p(-hx, -hy, seat - 0.04), p(hx, hy, seat), Part::Seat);
    for (x, y) in [
        (-hx, -hy),
        (-hx, hy - leg),
        (hx - leg, -hy),
        (hx - leg, hy - leg),
    ] {
        // Front legs rise to the rails; back legs rise into the back.
        let top = if x > 0.0 { rail_top } else { seat + 0.45 };
        m.add_box(p(x, y, 0.0), p(x + leg, y + leg, top), Part::Other);
    }
    for y0 in [-hy - 0.01, hy - rail_w + 0.01] {
        m.add_box(
            p(-hx, y0, rail_top - 0.03),
            p(hx + 0.02, y0 + rail_w, rail_top),
            Part::Armrest,
        );
    }
    // Back: slats between the back legs, leaning on nothing (upright).
    m.add_box(
        p(-hx, -hy, seat + 0.10),
        p(-hx + 0.03, hy, seat + 0.45),
        Part::Backrest,
    );
    m
}

#[test]
fn a_wooden_armchair_with_arm_rails_on_its_front_posts_gives_sitting_and_armrest() {
    check(&[wooden_armchair()], &["sitting", "backrest", "armrest"]);
    // Depth views from the front and the front corners, the camera 1.5 m high, 1.6 m away.
    let scene = scene_mesh(&[wooden_armchair()], true);
    for deg in [-40.0f64, 0.0, 40.0] {
        let (s, c) = deg.to_radians().sin_cos();
        let cam = camera::Camera::looking_at(
            Point3::new(1.6 * c, 1.6 * s, 1.5),
            Point3::new(0.0, 0.0, 0.45),
        );
        let view = camera::render_view(&scene, &cam, 3).0;
        let o = run(&view, 1.75);
        assert_eq!(
            affords(&o),
            ["sitting", "backrest", "armrest"],
            "view from {deg} deg: {:?}",
            o.stats
        );
    }
}

/// A camera beside a sofa's arm cannot see the seat behind the arm: the end seat, the one
/// place where the arm is used, was a hole in the height map with nothing in the scene
/// to sit on. The far end is out of view (the view is cut at y = 0.3 m).
#[test]
fn the_seat_a_sofa_arm_hides_from_the_camera_gives_the_armrest() {
    let two = SofaParams {
        seats: 2,
        ..SofaParams::default()
    };
    let scene = scene_mesh(&[sofa(&two)], true);
    for (x, y) in [(1.0, -2.2), (1.6, -2.0)] {
        let cam = camera::Camera::looking_at(Point3::new(x, y, 1.2), Point3::new(0.0, -0.3, 0.43));
        let mut view = camera::render_view(&scene, &cam, 3).0;
        view.points.retain(|p| p.y < 0.3);
        let o = run(&view, 1.75);
        assert!(
            affords(&o).iter().any(|a| a == "armrest"),
            "camera at ({x}, {y}): {:?} {:?}",
            affords(&o),
            o.stats
        );
        // The same outcome on one thread as on the pool.
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| run(&view, 1.75));
        assert_eq!(one, o, "camera at ({x}, {y})");
    }
}

/// An armchair and a two-seat sofa seen from behind and above, as by a person standing
/// behind them: the back hides the seat and, with the arms, the floor beyond, so the
/// height map has nothing between the arms. The seat is filled under the arms
/// (`afford::method::hidden`), and the body sits in it against the back with a forearm
/// on an arm; without that stage neither the back nor an arm is found.
#[test]
fn an_armchair_and_a_sofa_seen_from_behind_give_sitting_backrest_and_armrest() {
    let (agent, h) = models(1.75);
    let mut off = DetectConfig::default();
    off.hidden.wall_high = 0.0;
    for seats in [1, 2] {
        let params = SofaParams {
            seats,
            ..SofaParams::default()
        };
        let scene = scene_mesh(&[sofa(&params)], true);
        for (x, y, z) in [(-1.9, -0.9, 1.5), (-2.5, 0.6, 1.3)] {
            let cam = camera::Camera::looking_at(Point3::new(x, y, z), Point3::new(0.0, 0.0, 0.45));
            let view = camera::render_view(&scene, &cam, 3).0;
            let o = run(&view, 1.75);
            assert_eq!(
                affords(&o),
                ["sitting", "backrest", "armrest"],
                "{seats} seats, camera at ({x}, {y}, {z}): {:?}",
                o.stats
            );
            let without = affords(&detect(&view, &agent, &h, &off));
            assert!(
                !without.iter().any(|a| a == "backrest" || a == "armrest"),
                "{seats} seats, camera at ({x}, {y}, {z}): {without:?}"
            );
        }
    }
}

/// Height of a desk's top, metres (0.72-0.75 m: the top board 3 cm thick).
const DESK_TOP: f64 = 0.72;

/// A desk top 1.4 m wide (y -0.7 to 0.7) from x `x0` to `x1` on 3 cm square legs whose
/// corners nearest the origin stand at `legs` (x, y).
fn desk_top(x0: f64, x1: f64, legs: &[(f64, f64)]) -> Mesh {
    let mut desk = Mesh::new();
    desk.add_box(
        Point3::new(x0, -0.7, DESK_TOP),
        Point3::new(x1, 0.7, DESK_TOP + 0.03),
        Part::Other,
    );
    for &(x, y) in legs {
        desk.add_box(
            Point3::new(x, y, 0.0),
            Point3::new(x + 0.03, y + 0.03, DESK_TOP),
            Part::Other,
        );
    }
    desk
}

/// An office chair pushed in under a desk whose drawer hangs 0.13 m above the seat, over
/// its front half: the thighs of the seated body (0.14 m thick) meet the drawer's
/// underside at every heading, and turned away from the desk the body meets the chair's
/// back. The chair is pulled out to sit, so the seat is not given up (as in a TUM RGB-D
/// frame of an office, where both chairs at the desk were missed at 1.75 m). At 1.85 m
/// the seat's free rear, 0.33 m deep, is narrower than the body's torso template with the
/// back beside it; it has been found there too since `rise_height` and `shift_back`,
/// which `a_seat_half_under_a_desk_top_is_found_with_the_desk_set_aside` and the fit's
/// tests cover.
#[test]
fn a_chair_pushed_in_under_a_desk_drawer_is_still_a_seat() {
    let seat = ChairParams::default();
    let legs = [(0.12, -0.67), (0.12, 0.64), (0.87, -0.67), (0.87, 0.64)];
    let mut desk = desk_top(0.12, 0.9, &legs);
    desk.add_box(
        Point3::new(0.12, -0.35, seat.seat_height + 0.13),
        Point3::new(0.7, 0.35, DESK_TOP),
        Part::Other,
    );
    let c = cloud(&[chair(&seat), desk]);
    for height in [1.65, 1.75] {
        let o = run(&c, height);
        let on_the_chair = o
            .detections
            .iter()
            .filter(|d| d.seat.x.abs() < 0.25 && d.seat.y.abs() < 0.25)
            .count();
        assert!(on_the_chair > 0, "at {height}: {:?}", o.stats);
        assert!(affords(&o).iter().any(|a| a == "sitting"), "at {height}");
    }
}

/// Issue 11: in a room scan the highest point of every cell is the ceiling, which left
/// the paper's height map without a single seat.
#[test]
fn a_room_with_a_ceiling_still_gives_its_seats() {
    let furniture = [
        chair(&ChairParams::with_arms()),
        sofa(&SofaParams::default()).placed(2.0, 0.0, 180.0),
    ];
    let open = cloud(&furniture);
    let mut roofed = furniture.to_vec();
    let mut ceiling = Mesh::new();
    ceiling.add_box(
        Point3::new(-1.5, -2.5, 2.5),
        Point3::new(3.5, 2.5, 2.55),
        Part::Other,
    );
    roofed.push(ceiling);
    let o = run(&cloud(&roofed), 1.75);
    assert!(o.detections.len() >= 3, "{:?}", o.stats);
    assert_eq!(affords(&o), affords(&run(&open, 1.75)));
    assert_eq!(affords(&o), ["sitting", "backrest", "armrest"]);
}

/// Keeps one point per `step` metre voxel of `c` (the first in the cloud's order): the
/// sampling of a reconstruction read as mesh vertices (6 cm voxels leave neighbours 3-8 cm
/// apart, ~4 cm typical, like ScanNet's cleaned meshes).
fn vertex_grid(c: &PointCloud, step: f64) -> PointCloud {
    // A test scene of a few metres at centimetre steps: the cell is far inside i64.
    #[allow(clippy::cast_possible_truncation)]
    fn cell(v: f64) -> i64 {
        v.floor() as i64
    }
    let mut seen = std::collections::HashSet::new();
    PointCloud::new(
        c.points
            .iter()
            .filter(|p| seen.insert((p.coords / step).map(cell)))
            .copied()
            .collect(),
    )
}

/// Issue 11: a reconstruction read as points (vertices ~4 cm apart) broke the height map
/// tuned on dense clouds: chairs and beds in it got nothing.
#[test]
fn a_cloud_of_4_cm_vertices_gives_sitting_and_lying() {
    let c = vertex_grid(
        &cloud(&[
            chair(&ChairParams::default()),
            bed(&BedParams::single()).placed(0.0, 1.8, 0.0),
        ]),
        0.06,
    );
    let agent = Agent::load(Path::new("agents/human.toml"), 1.75).unwrap();
    let lying = Hierarchy::load(Path::new("affordances/lying.toml"), &agent).unwrap();
    assert!(!run(&c, 1.75).detections.is_empty(), "no sitting");
    let o = detect(&c, &agent, &lying, &DetectConfig::default());
    assert!(
        o.detections.iter().any(|d| d.position.y > 1.0),
        "no lying on the bed: {:?}",
        o.stats
    );
}

/// Seats above knee height that a person still perches on with the feet on the floor: a
/// 0.55 m stool and the edge of a 0.60 m bed give sitting at 1.75 m (the thighs slope
/// down: the sitting node's `fallback`); a 0.72 m table top does not. Before the
/// fallback, nothing above ~0.50 m gave sitting at 1.75 m.
#[test]
fn a_stool_and_a_bed_above_knee_height_are_perched_on() {
    let high_stool = stool(&StoolParams {
        seat_height: 0.55,
        ..StoolParams::default()
    });
    let o = run(&cloud(&[high_stool]), 1.75);
    assert_eq!(affords(&o), ["sitting"], "0.55 m stool: {:?}", o.stats);
    let high_bed = bed(&BedParams {
        mattress_height: 0.60,
        // The frame's top (a face inside the bed) below seat height, as on a real bed,
        // where no scan sees it; at 0.38 m the height map takes the mattress for a roof.
        mattress_thickness: 0.30,
        headboard_height: 0.0,
        ..BedParams::default()
    });
    let o = run(&cloud(&[high_bed]), 1.75);
    assert_eq!(affords(&o), ["sitting"], "0.60 m bed: {:?}", o.stats);
    let table = stool(&StoolParams {
        seat_height: 0.72,
        seat_size: 0.8,
        round: false,
        ..StoolParams::default()
    });
    let o = run(&cloud(&[table]), 1.75);
    assert!(affords(&o).is_empty(), "0.72 m table top: {:?}", o.stats);
}

/// A bed's headboard is beside a body sitting on the bed's edge, not behind it
/// (docs/conventions.md, "Beds and headboards"): a double bed with a headboard 0.5 m above
/// the mattress, whole and against nothing, gives sitting and no backrest. Agents at the
/// head-end corner, turned onto the headboard, found one until the backrest node's `rear`
/// rule: in front of a headboard the mattress goes on for a body's length.
#[test]
fn a_headboard_is_no_backrest() {
    let double = bed(&BedParams::default());
    let o = run(&cloud(&[double]), 1.75);
    assert_eq!(
        affords(&o),
        ["sitting"],
        "bed with headboard: {:?}",
        o.stats
    );
}

/// An armchair scanned with stray returns: 1% of its points again, strewn uniformly over
/// its bounding box, and as much again in clumps of ten within 2 cm (a laser's dust and
/// glass returns, a depth camera's speckle, a reconstruction's floating fragments). Each
/// filled voxels the body collided with or rested a forearm on, and could top its
/// height-map cell; the per-file path leaves such specks out of the grids, so the
/// armchair gives what it gives clean, at every body height (without that stage it lost
/// sitting or armrest).
#[test]
fn stray_points_and_clumps_over_an_armchair_change_nothing() {
    let clean = cloud(&[chair(&ChairParams::with_arms())]);
    let (lo, hi) = clean.bounds().unwrap();
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut unit = move || {
        // xorshift64*: a fixed sequence, so the test sees the same strays every run.
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut pts = clean.points.clone();
    let n = clean.len() / 100;
    for i in 0..n + n / 10 {
        let c = Point3::new(
            lo.x + unit() * (hi.x - lo.x),
            lo.y + unit() * (hi.y - lo.y),
            lo.z + unit() * (hi.z - lo.z),
        );
        let clump = if i < n { 1 } else { 10 };
        for _ in 0..clump {
            pts.push(c + Vector3::new(unit(), unit(), unit()) * 0.02);
        }
    }
    let noisy = PointCloud::new(pts);
    for height in [1.65, 1.75, 1.85] {
        let (agent, hierarchy) = models(height);
        let m = [afford::model::set::Model { agent, hierarchy }];
        let o =
            afford::detect::detect_input(Path::new("noisy"), &noisy, &m, &DetectConfig::default())
                .unwrap()
                .remove(0);
        assert_eq!(
            affords(&o),
            ["sitting", "backrest", "armrest"],
            "at body height {height}: {:?}",
            o.stats
        );
    }
}

/// A chair pushed in under a desk whose top (0.72 m) reaches 0.10 m past the middle of the
/// seat, the part of the seat under it hidden from a camera above (as the yellow chair of a
/// TUM RGB-D office frame): at 1.85 m the torso template round the seat's free rear takes
/// in the desk's cells and is rough, and the paper's rule gives no place at all. Setting
/// aside what stands over the seat's edge (`rise_height`) gives the seat and its back at
/// every height. Without it, the hidden-seat stage also finds a place: the seat hidden
/// under the desk's top, between the chair's back and the top 0.20-0.40 m over it.
#[test]
fn a_seat_half_under_a_desk_top_is_found_with_the_desk_set_aside() {
    let desk = desk_top(0.10, 0.8, &[(0.77, -0.67), (0.77, 0.64)]);
    let full = cloud(&[chair(&ChairParams::default()), desk]);
    // The chair under the desk top is hidden from above.
    let seen = PointCloud::new(
        full.points
            .iter()
            .filter(|p| !(p.x > 0.10 && p.x < 0.6 && p.z > 0.05 && p.z < 0.70))
            .copied()
            .collect(),
    );
    for height in [1.65, 1.75, 1.85] {
        let o = run(&seen, height);
        assert_eq!(
            affords(&o),
            ["sitting", "backrest"],
            "at {height}: {:?}",
            o.stats
        );
    }
    let (agent, mut paper) = models(1.85);
    assert!(paper.hypothesis.rise_height.is_some());
    paper.hypothesis.rise_height = None;
    let o = detect(&seen, &agent, &paper, &DetectConfig::default());
    assert!(o.stats.hypotheses > 0, "{:?}", o.stats);
    paper.hypothesis.hidden_seats = false;
    let o = detect(&seen, &agent, &paper, &DetectConfig::default());
    assert_eq!(o.stats.hypotheses, 0, "{:?}", o.stats);
}

/// A bar stool (a round top 0.36 m across at 0.75 m, on a pedestal, with a footrest ring
/// 0.35 m high) is perched on: too high for the seat height membership, it is tried because
/// its top is a stool's (`perch` in affordances/sitting.toml), at every body height the
/// labels use, with the feet on the ring. A bistro table of the same height, a round top
/// 0.60 m across on the same pedestal and ring, is too long to perch on and gives nothing;
/// without the perch the bar stool gives no hypothesis.
#[test]
fn a_bar_stool_is_perched_on_and_a_bistro_table_is_not() {
    let bar = bar_stool(true);
    let mut bistro = bar.clone();
    bistro[0] = stool(&StoolParams {
        seat_size: 0.60,
        ..StoolParams::bar()
    });
    for height in [1.65, 1.75, 1.85] {
        let o = run(&cloud(&bar), height);
        assert_eq!(
            affords(&o),
            ["sitting"],
            "bar stool at {height}: {:?}",
            o.stats
        );
        let seat = o.detections[0].seat;
        assert!(seat.coords.xy().norm() < 0.18, "{seat:?}");
        let o = run(&cloud(&bistro), height);
        assert!(
            o.detections.is_empty(),
            "bistro table at {height}: {:?}",
            o.stats
        );
    }
    let (agent, mut h) = models(1.75);
    h.hypothesis.perch = None;
    let o = detect(&cloud(&bar), &agent, &h, &DetectConfig::default());
    assert_eq!(o.stats.hypotheses, 0, "{:?}", o.stats);
}
