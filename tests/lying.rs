//! The lying hierarchy (affordances/lying.toml) on furniture built in the test: which of
//! its fine-grained affordances a flat bed, an adjustable bed with the head or the feet
//! raised, a short bench and a chair give, at three body heights; and the child body on
//! the same scene as the adult in one pass.

use std::path::Path;

use afford::cloud::PointCloud;
use afford::detect::{detect, detect_all, prepare, DetectConfig, Outcome};
use afford::mesh::{Mesh, Part};
use afford::method::fit::fit;
use afford::method::hypotheses::Hypothesis;
use afford::method::unfold::unfold;
use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;
use afford::model::set::{load_set, Source};
use afford_synth::furniture::*;
use nalgebra::{Point3, UnitQuaternion, Vector3};

fn lying(height: f64) -> (Agent, Hierarchy) {
    let agent = Agent::load(Path::new("agents/human.toml"), height).unwrap();
    let h = Hierarchy::load(Path::new("affordances/lying.toml"), &agent).unwrap();
    (agent, h)
}

fn cloud(m: &Mesh) -> PointCloud {
    scene_cloud(std::slice::from_ref(m), 2500.0, 0.002, 7, true)
}

/// The lying affordances of the scene (any detection), in hierarchy order.
fn affords(o: &Outcome) -> Vec<String> {
    let ids = [
        "lying",
        "elongated_body",
        "raised_body",
        "stretched_legs",
        "raised_legs",
    ];
    ids.iter()
        .filter(|id| {
            o.detections
                .iter()
                .any(|d| d.affordances.iter().any(|a| a == *id))
        })
        .map(|s| s.to_string())
        .collect()
}

fn check(m: &Mesh, expected: &[&str]) {
    check_cloud(&cloud(m), expected);
}

/// [`check`] on a cloud already sampled.
fn check_cloud(c: &PointCloud, expected: &[&str]) {
    // The extremes of the heights the paper evaluates (1.75 m lies between them).
    for height in [1.65, 1.85] {
        let (agent, h) = lying(height);
        let o = detect(c, &agent, &h, &DetectConfig::default());
        assert_eq!(
            affords(&o),
            expected,
            "at body height {height}: {:?}",
            o.stats
        );
    }
}

/// A mattress from `x0` to `x1`, 1.4 m wide, with its top at `top` metres, down to the floor.
fn mattress(m: &mut Mesh, x0: f64, x1: f64, top: f64) {
    m.add_box(
        Point3::new(x0, -0.7, 0.0),
        Point3::new(x1, 0.7, top),
        Part::LyingSurface,
    );
}

/// A flat section of length `len` (m) hinged at `(x, top)` and raised by `deg` towards
/// -x (`dir` = -1) or +x (`dir` = 1), as in an adjustable bed, 0.12 m thick, 1.4 m wide.
fn raised_section(m: &mut Mesh, x: f64, top: f64, len: f64, deg: f64, dir: f64) {
    raised_panel(m, x, top, len, 0.7, deg, dir);
}

/// Like [`raised_section`], `2 * half_width` wide.
fn raised_panel(m: &mut Mesh, x: f64, top: f64, len: f64, half_width: f64, deg: f64, dir: f64) {
    let a = deg.to_radians();
    let centre = Point3::new(
        x + dir * (len / 2.0) * a.cos(),
        0.0,
        top + (len / 2.0) * a.sin() - 0.06 * a.cos(),
    );
    let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -dir * a);
    m.add_oriented_box(
        centre,
        Vector3::new(len / 2.0, half_width, 0.06),
        rot,
        Part::LyingSurface,
    );
}

#[test]
fn a_flat_bed_affords_lying_flat_with_stretched_legs() {
    let mut m = Mesh::new();
    mattress(&mut m, -1.0, 1.0, 0.5);
    check(&m, &["lying", "elongated_body", "stretched_legs"]);
}

/// The lying affordances of the agent fitted with its pelvis over `(x, 0)` and its feet
/// towards +x (heading 0), then unfolded: the hierarchy's answer for that one placement
/// (the whole detector may also find other ways to lie on the same bed).
fn unfolded_at(m: &Mesh, height: f64, x: f64) -> Vec<String> {
    unfolded_in(&cloud(m), height, x)
}

/// [`unfolded_at`] in a cloud.
fn unfolded_in(c: &PointCloud, height: f64, x: f64) -> Vec<String> {
    let (agent, h) = lying(height);
    unfolded_with(c, &agent, &h, x, false)
}

/// [`unfolded_in`] with hierarchy `h`, at a place whose width the scan did or did not show
/// (`unseen_width`).
fn unfolded_with(
    c: &PointCloud,
    agent: &Agent,
    h: &Hierarchy,
    x: f64,
    unseen_width: bool,
) -> Vec<String> {
    let cfg = DetectConfig::default();
    let prepared = prepare(c, &cfg);
    let top = 0.5;
    let hyp = Hypothesis {
        cell: (0, 0),
        position: Point3::new(x, 0.0, top),
        top,
        availability: 1.0,
        heading: Some(0.0),
        facing: None,
        memberships: [1.0; 3],
        risen: false,
        unseen_width,
        flat_axes: Vec::new(),
    };
    let fits = fit(agent, h, &prepared.scene, &hyp, &cfg.contact);
    let f = fits
        .iter()
        .find(|f| f.placement.yaw.abs() < 1e-6)
        .expect("a stable fit with the feet towards +x");
    let u = unfold(agent, h, &prepared.scene, f, &cfg.contact);
    h.nodes
        .iter()
        .zip(&u.nodes)
        .filter(|(_, o)| o.found)
        .map(|(n, _)| n.id.clone())
        .collect()
}

#[test]
fn a_bed_with_the_head_raised_affords_lying_with_a_raised_body() {
    // Head section 0.8 m raised 45 deg at x < -0.3; flat from there to the foot end.
    let mut m = Mesh::new();
    mattress(&mut m, -0.3, 1.2, 0.5);
    raised_section(&mut m, -0.3, 0.5, 0.8, 45.0, -1.0);
    for height in [1.65, 1.85] {
        assert_eq!(
            unfolded_at(&m, height, -0.15),
            ["lying", "raised_body", "stretched_legs"],
            "at {height} m"
        );
    }
}

#[test]
fn a_bed_with_the_feet_raised_affords_lying_with_raised_legs() {
    // Foot section 0.9 m raised 25 deg at x > 0.35; flat towards the head end.
    let mut m = Mesh::new();
    mattress(&mut m, -1.4, 0.35, 0.5);
    raised_section(&mut m, 0.35, 0.5, 0.9, 25.0, 1.0);
    for height in [1.65, 1.85] {
        assert_eq!(
            unfolded_at(&m, height, 0.3),
            ["lying", "elongated_body", "raised_legs"],
            "at {height} m"
        );
    }
}

/// A recliner `width` metres wide: seat 0.5 m deep at 0.45 m, back 0.8 m reclined to
/// 40 deg above level, leg rest 0.6 m raised 10 deg.
fn recliner_of(width: f64) -> Mesh {
    let mut m = Mesh::new();
    let w = width / 2.0;
    m.add_box(
        Point3::new(-0.25, -w, 0.0),
        Point3::new(0.25, w, 0.45),
        Part::LyingSurface,
    );
    raised_panel(&mut m, -0.25, 0.45, 0.8, w, 40.0, -1.0);
    raised_panel(&mut m, 0.25, 0.45, 0.6, w, 10.0, 1.0);
    m
}

#[test]
fn a_recliner_as_wide_as_a_bed_affords_lying_with_a_raised_body() {
    // 0.8 m wide, the whole detector: lying with the trunk on the reclined back. A common
    // recliner 0.6 m wide is narrower than a bed (docs/conventions.md): a chair.
    let c = cloud(&recliner_of(0.8));
    let (agent, h) = lying(1.75);
    let o = detect(&c, &agent, &h, &DetectConfig::default());
    let found = affords(&o);
    assert!(
        found.contains(&"lying".to_string()) && found.contains(&"raised_body".to_string()),
        "{found:?} {:?}",
        o.stats
    );
    let narrow = detect(
        &cloud(&recliner_of(0.6)),
        &agent,
        &h,
        &DetectConfig::default(),
    );
    assert_eq!(affords(&narrow), Vec::<String>::new(), "{:?}", narrow.stats);
}

#[test]
fn a_sofa_is_for_sitting_and_a_narrow_bed_for_lying() {
    // A three-seat sofa (seat 0.55 m deep between back and front) gives no place to lie;
    // a 0.9 m single bed, turned 25 deg off the axes, does.
    let sofa = sofa(&SofaParams {
        seats: 3,
        ..SofaParams::default()
    });
    check(&sofa, &[]);
    let bed = bed(&BedParams {
        width: 0.9,
        headboard_height: 0.0,
        ..BedParams::default()
    })
    .placed(0.0, 0.0, 25.0);
    check(&bed, &["lying", "elongated_body", "stretched_legs"]);
}

/// The points of `c` with x in `range` (the rest out of the camera's view).
fn seen(c: &PointCloud, range: std::ops::Range<f64>) -> PointCloud {
    seen_where(c, |p| range.contains(&p.x))
}

/// The points of `c` for which `inside` holds (the rest out of the camera's view).
fn seen_where(c: &PointCloud, inside: impl Fn(&Point3<f64>) -> bool) -> PointCloud {
    PointCloud::new(c.points.iter().filter(|p| inside(p)).copied().collect())
}

/// The points of `c` a camera looking down sees of a solid block standing on the floor
/// with its top at `top` over the footprint `x` x `y`: none inside the footprint below the
/// top (the floor under it, the surfaces inside it); its side faces stay.
fn solid(c: &PointCloud, x: std::ops::Range<f64>, y: std::ops::Range<f64>, top: f64) -> PointCloud {
    let inner = |r: &std::ops::Range<f64>, v: f64| v > r.start + 0.01 && v < r.end - 0.01;
    seen_where(c, |p| {
        !(inner(&x, p.x) && inner(&y, p.y) && p.z < top - 0.01)
    })
}

#[test]
fn a_bed_cut_lengthwise_by_the_image_edge_is_not_taken_for_a_sofa() {
    // A 0.9 m single bed along x of which the camera sees 0.6 m across (y below 0.15 m),
    // the floor in front of it: narrower in view than a bed (0.70 m at 1.75 m), but the
    // scan ends unseen beside it, so its width is unknown, not too small. A three-seat
    // sofa cut the same way (its front out of view, its back seen) gives no place to lie.
    let bed = bed(&BedParams {
        width: 0.9,
        headboard_height: 0.0,
        ..BedParams::default()
    });
    let sofa = sofa(&SofaParams {
        seats: 3,
        ..SofaParams::default()
    });
    // The floor under the bed and its frame's inside are hidden from a camera.
    let bed = solid(&cloud(&bed), -1.0..1.0, -0.45..0.45, 0.5);
    let sofa = cloud(&sofa);
    for height in [1.65, 1.85] {
        let (agent, h) = lying(height);
        let cut = |c: &PointCloud, inside: fn(&Point3<f64>) -> bool| {
            let c = seen_where(c, inside);
            affords(&detect(&c, &agent, &h, &DetectConfig::default()))
        };
        // The bed along x, seen up to y = 0.15 m; the sofa's seat along y, its front
        // (x from 0 to 0.28 m) out of view.
        assert_eq!(
            cut(&bed, |p| p.y < 0.15),
            ["lying", "elongated_body", "stretched_legs"],
            "at {height} m"
        );
        assert!(cut(&sofa, |p| p.x < 0.0).is_empty(), "at {height} m");
    }
}

#[test]
fn a_seat_seen_to_its_front_at_the_image_edge_is_not_a_bed() {
    // An upholstered bench 1.6 m long and 0.45 m deep, its seat a box down to 0.05 m: the
    // camera looks down at its front face (x = 0.225 m) and sees no floor in front of it
    // (nor under the seat), and the floor behind it. The scan ends beside the seat, but
    // where the front face is seen going down under the seat's edge the seat ends there:
    // too narrow for a bed.
    // The same bench cut through its seat 0.10 m behind the front (only its top at the
    // cut) is of unknown width, as a bed's cut lengthwise.
    let bench = bench(&BenchParams {
        length: 1.6,
        seat_depth: 0.45,
        seat_thickness: 0.40,
        ..BenchParams::default()
    });
    let c = solid(&cloud(&bench), -0.225..0.225, -0.8..0.8, 0.45);
    for height in [1.65, 1.85] {
        let (agent, h) = lying(height);
        let found = |front: f64| {
            affords(&detect(
                &seen(&c, -3.0..front),
                &agent,
                &h,
                &DetectConfig::default(),
            ))
        };
        assert!(found(0.235).is_empty(), "front seen, at {height} m");
        assert_eq!(
            found(0.125),
            ["lying", "elongated_body", "stretched_legs"],
            "cut through the seat, at {height} m"
        );
    }
}

#[test]
fn a_bed_cut_by_the_image_edge_affords_lying_on_what_is_in_view() {
    // A 2 m bed whose last 0.8 m, and the floor beyond, the camera does not see: the heels
    // over unseen space are not refuted (`unseen_reach`), the head rests on the mattress.
    let mut m = Mesh::new();
    mattress(&mut m, -1.0, 1.0, 0.5);
    let c = cloud(&m);
    for height in [1.65, 1.85] {
        let (agent, h) = lying(height);
        let o = detect(&seen(&c, -3.0..0.2), &agent, &h, &DetectConfig::default());
        assert_eq!(
            affords(&o),
            ["lying", "elongated_body", "stretched_legs"],
            "at {height} m: {:?}",
            o.stats
        );
    }
}

#[test]
fn one_end_of_the_body_must_rest_on_a_surface_in_view() {
    // Along the bed, the pelvis at its middle: the head and the heels are over the
    // mattress when all of it is seen, over unseen space at one end (found) or at both
    // (not found) when the camera sees only part of it.
    let mut m = Mesh::new();
    mattress(&mut m, -1.0, 1.0, 0.5);
    let c = cloud(&m);
    let lying_flat = ["lying", "elongated_body", "stretched_legs"];
    for height in [1.65, 1.85] {
        assert_eq!(
            unfolded_in(&c, height, 0.0),
            lying_flat,
            "all seen, {height} m"
        );
        let one = unfolded_in(&seen(&c, -3.0..0.45), height, 0.0);
        assert_eq!(one, lying_flat, "the foot end unseen, {height} m");
        let both = unfolded_in(&seen(&c, -0.45..0.45), height, 0.0);
        assert!(both.is_empty(), "both ends unseen, {height} m: {both:?}");
    }
}

#[test]
fn a_bed_cut_across_at_the_hips_affords_lying_with_the_legs_unseen() {
    // The head half of a 2 m bed, the camera seeing nothing past x = 0 (the hips of a body
    // lying with its pelvis there, feet towards +x): the legs touch nothing, their heels
    // hang over space the scan never saw. They do not refute lying (`unseen_sweeps`); with
    // the key removed they do; and on a strip whose width is unknown too (cut lengthwise
    // as well) they do.
    let mut m = Mesh::new();
    mattress(&mut m, -1.0, 1.0, 0.5);
    let c = seen(&cloud(&m), -3.0..0.0);
    for height in [1.65, 1.75, 1.85] {
        let (agent, h) = lying(height);
        let node = h.nodes.iter().position(|n| n.id == "lying").unwrap();
        assert!(!h.nodes[node].unseen_sweeps.is_empty());
        let mut without = h.clone();
        without.nodes[node].unseen_sweeps.clear();
        let found = unfolded_with(&c, &agent, &h, 0.0, false);
        assert_eq!(found, ["lying", "elongated_body"], "at {height} m");
        let refuted = unfolded_with(&c, &agent, &without, 0.0, false);
        assert!(
            refuted.is_empty(),
            "without the key, at {height} m: {refuted:?}"
        );
        let narrow = unfolded_with(&c, &agent, &h, 0.0, true);
        assert!(
            narrow.is_empty(),
            "width unknown, at {height} m: {narrow:?}"
        );
    }
}

#[test]
fn a_short_bench_and_a_chair_do_not_afford_lying() {
    let short = BenchParams {
        length: 1.2,
        seat_depth: 0.45,
        ..BenchParams::default()
    };
    check(&bench(&short), &[]);
    check(&chair(&ChairParams::default()), &[]);
}

#[test]
fn a_child_and_an_adult_run_in_one_pass_over_one_scene() {
    // A 1.2 m seat of 0.45 m: too short for an adult to lie on, long enough for a child of
    // 1.20 m (back of the head to ankles ~1.0 m); both bodies see the same voxelised scene.
    // The floor of the room round it is seen (where the scan saw nothing, an adult's head
    // could hang over the edge: `unseen_reach`).
    let mut m = floor(-2.0, -2.0, 2.0, 2.0);
    m.add_box(
        Point3::new(-0.6, -0.35, 0.0),
        Point3::new(0.6, 0.35, 0.40),
        Part::LyingSurface,
    );
    let agents = [
        Source::File("agents/human.toml".into()),
        Source::File("agents/child.toml".into()),
    ];
    let hs = [Source::File("affordances/lying.toml".into())];
    let adult = load_set(&agents[..1], &hs, &[1.75]).unwrap();
    let child = load_set(&agents[1..], &hs, &[1.20]).unwrap();
    let both: Vec<_> = adult.iter().chain(&child).cloned().collect();
    let c = cloud(&m);
    let out = detect_all(&c, &both, &DetectConfig::default());
    assert_eq!(out.len(), 2);
    assert!(affords(&out[0]).is_empty(), "adult: {:?}", affords(&out[0]));
    assert!(
        affords(&out[1]).contains(&"lying".to_string()),
        "child: {:?}",
        out[1].stats
    );
    assert!(out[1].detections.iter().all(|d| d.agent == "child"));
}

#[test]
fn a_seat_hidden_behind_its_back_is_for_hierarchies_that_take_hidden_seats() {
    // A three-seat sofa seen from behind and above: its back, the tops of its arms and the
    // floor behind and beside it; the seat never seen, nor anything in front of it (the
    // image ends there). The seat hidden inside the back and the arms is filled for
    // sitting; lying takes no hidden seat (a bed is a surface the scan saw), and a
    // hierarchy switched the same way finds no seat here.
    let mut m = floor(-2.0, -2.0, 2.5, 2.0);
    m.append(&sofa(&SofaParams::default()));
    let c = seen_where(&cloud(&m), |p| {
        let arm_top = p.y.abs() > 0.825 && p.z > 0.62;
        let floor_beside = p.z < 0.01 && p.x < 0.3 && p.y.abs() > 1.2;
        p.x < -0.27 || arm_top || floor_beside
    });
    let cfg = DetectConfig::default();
    let prepared = prepare(&c, &cfg);
    // The map's cell at the seat's middle, (0, 0).
    let cell = |map: &afford::method::heightmap::HeightMap| {
        let (ix, iy) = (0..map.ny)
            .flat_map(|iy| (0..map.nx).map(move |ix| (ix, iy)))
            .find(|&(ix, iy)| {
                let (x, y) = map.centre(ix, iy);
                x.abs() <= map.cell / 2.0 && y.abs() <= map.cell / 2.0
            })
            .expect("the seat's middle in the map");
        map.get(ix as isize, iy as isize)
    };
    let filled = cell(prepared.map_for(true)).expect("the hidden seat filled");
    assert!((0.40..0.55).contains(&filled), "filled at {filled}");
    assert_eq!(cell(prepared.map_for(false)), None);
    let agent = Agent::load(Path::new("agents/human.toml"), 1.75).unwrap();
    let mut sitting = Hierarchy::load(Path::new("affordances/sitting.toml"), &agent).unwrap();
    assert!(sitting.hypothesis.hidden_seats);
    // Seats between the arms (the arms' tops, 0.63 m high, are perched on either way).
    let on_seat = |o: &Outcome| {
        o.detections
            .iter()
            .filter(|d| d.seat.y.abs() < 0.8 && d.seat.z < 0.55)
            .count()
    };
    let sat = detect(&c, &agent, &sitting, &cfg);
    assert!(on_seat(&sat) > 0, "{:?}", sat.detections);
    sitting.hypothesis.hidden_seats = false;
    let unseen = detect(&c, &agent, &sitting, &cfg);
    assert_eq!(on_seat(&unseen), 0, "{:?}", unseen.detections);
    let (agent, h) = lying(1.75);
    assert!(!h.hypothesis.hidden_seats);
    assert!(affords(&detect(&c, &agent, &h, &cfg)).is_empty());
}

#[test]
fn a_tall_bed_is_lain_on_by_every_body_and_a_table_by_none() {
    // A bed whose mattress top stands 0.67 m high (a box-spring bed with its duvet; the
    // lying height membership is in metres, half at 0.69 m) affords lying for the 1.65 m
    // body as for the 1.85 m one; a table top 0.74 m high, as long and wide as a bed,
    // for neither. The bed as a camera sees it, a solid block: the full model's inner
    // faces put the frame's top 0.22 m under the mattress's, a gap the height map takes
    // for the room under a roof.
    let tall = bed(&BedParams {
        mattress_height: 0.67,
        headboard_height: 0.0,
        ..BedParams::default()
    });
    let seen = solid(&cloud(&tall), -1.0..1.0, -0.7..0.7, 0.67);
    check_cloud(&seen, &["lying", "elongated_body", "stretched_legs"]);
    let table = table(&TableParams {
        length: 2.0,
        width: 1.0,
        ..TableParams::default()
    });
    check(&table, &[]);
}

/// The lying hierarchy with its `flat` rule switched on: the line that stands commented
/// out in affordances/lying.toml.
fn lying_with_flat(height: f64) -> (Agent, Hierarchy) {
    let agent = Agent::load(Path::new("agents/human.toml"), height).unwrap();
    let path = Path::new("affordances/lying.toml");
    let text = std::fs::read_to_string(path).unwrap();
    assert_eq!(text.matches("\n# flat = ").count(), 1);
    let text = text.replacen("\n# flat = ", "\nflat = ", 1);
    let h = Hierarchy::from_toml(&text, path, &agent).unwrap();
    assert!(h.hypothesis.flat.is_some());
    (agent, h)
}

/// An L sofa: two seats 0.6 m deep at 0.45 m meeting at a corner square, 2 m long each
/// from the corner's outer side, with backs 0.85 m high and 0.2 m thick behind them.
fn l_sofa() -> Mesh {
    let mut m = Mesh::new();
    let seat = |m: &mut Mesh, a: Point3<f64>, b: Point3<f64>| m.add_box(a, b, Part::Seat);
    seat(
        &mut m,
        Point3::new(-2.0, 0.0, 0.0),
        Point3::new(0.6, 0.6, 0.45),
    );
    seat(
        &mut m,
        Point3::new(0.0, -2.0, 0.0),
        Point3::new(0.6, 0.0, 0.45),
    );
    m.add_box(
        Point3::new(-2.0, 0.6, 0.0),
        Point3::new(0.8, 0.8, 0.85),
        Part::Backrest,
    );
    m.add_box(
        Point3::new(0.6, -2.0, 0.0),
        Point3::new(0.8, 0.6, 0.85),
        Part::Backrest,
    );
    m
}

#[test]
fn a_flat_rectangle_keeps_bodies_off_an_l_sofas_corner_and_on_a_bed() {
    let sofa = cloud(&l_sofa());
    let bed = cloud(
        &bed(&BedParams {
            width: 0.9,
            headboard_height: 0.0,
            ..BedParams::default()
        })
        .placed(0.0, 0.0, 25.0),
    );
    for height in [1.65, 1.85] {
        // The seats' spread at the corner is a bed's width across the diagonal: without the
        // rule a body is laid there.
        let (agent, plain) = lying(height);
        let o = detect(&sofa, &agent, &plain, &DetectConfig::default());
        assert!(
            affords(&o).contains(&"lying".to_string()),
            "{height}: {:?}",
            o.stats
        );
        // With it, no flat rectangle 0.4 H wide lies there; on a bed one does.
        let (agent, flat) = lying_with_flat(height);
        let o = detect(&sofa, &agent, &flat, &DetectConfig::default());
        assert_eq!(
            affords(&o),
            Vec::<String>::new(),
            "{height}: {:?} {:?}",
            o.stats,
            o.detections
                .iter()
                .map(|d| (d.position, d.yaw))
                .collect::<Vec<_>>()
        );
        let o = detect(&bed, &agent, &flat, &DetectConfig::default());
        assert_eq!(
            affords(&o),
            ["lying", "elongated_body", "stretched_legs"],
            "{height}: {:?}",
            o.stats
        );
    }
}
