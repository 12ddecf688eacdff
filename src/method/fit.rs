//! Initial agent fitting (section 4.2): at a hypothesis, try headings around the
//! hypothesis heading, discard those where the agent in its initial pose collides before
//! it is lowered, lower it until it touches the scene, and rate it by the stability
//! score of Eq. 1.

use nalgebra::Point3;

use crate::method::hypotheses::Hypothesis;
use crate::method::scene::Scene;
use crate::model::agent::{Agent, Cylinder, FkCache, Placement, Posture};
use crate::model::hierarchy::Hierarchy;
use crate::num::to_usize;

/// The agent resting at a hypothesis in its initial pose.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Where the agent's root joint ended up, and its heading.
    pub placement: Placement,
    /// The initial pose H_A.
    pub posture: Posture,
    /// Stability score s of Eq. 1, in (0, 1].
    pub stability: f64,
    /// Whether the heading came from the all-round search after none of the offsets round
    /// the place's own heading was free: such a pose is turned from where the place
    /// faces, and ranks below the others (`Unfolded::rank`).
    pub turned: bool,
    /// The hypothesis's [`Hypothesis::unseen_width`]: the width of the surface round the
    /// place is unknown, so the unfolding leaves no branch over unseen space untouched.
    pub unseen_width: bool,
}

/// Numbers of the fitting that are not the hierarchy's: how finely contact is located.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactConfig {
    /// Contact positions are located to within this much motion, metres.
    pub resolution: f64,
}

/// Headings (radians) to try at a hypothesis, in order: the offsets of the hierarchy
/// around the place's own heading (the gradient heading, else the heading facing away from
/// the tallest thing near it, [`Hypothesis::facing`]), or every `fallback_yaw_step` round
/// from world +x where it has neither (nothing rises round a flat place).
pub fn headings(h: &Hierarchy, hyp: &Hypothesis) -> Vec<f64> {
    match own_heading(hyp) {
        Some(yaw) => h.fit.yaw_offsets.iter().map(|o| yaw + o).collect(),
        None => all_round(0.0, h.fit.fallback_yaw_step),
    }
}

/// The heading a place suggests: its gradient heading, else the heading facing away from
/// the tallest thing near it; `None` where neither exists.
fn own_heading(hyp: &Hypothesis) -> Option<f64> {
    hyp.heading.or(hyp.facing)
}

/// Headings `step` apart all round, nearest to `from` first: `from`, then one step either
/// side (counter-clockwise first), two steps, and so on.
fn all_round(from: f64, step: f64) -> Vec<f64> {
    let n = to_usize((std::f64::consts::TAU / step).round().max(1.0));
    let unit = std::f64::consts::TAU / n as f64;
    (0..n)
        .map(|i| {
            let k = i.div_ceil(2) as f64;
            let side = if i % 2 == 1 { 1.0 } else { -1.0 };
            from + side * k * unit
        })
        .collect()
}

/// Fits the agent at `hyp` (section 4.2) and returns every stable fit, one per heading that
/// was free before lowering, touched the scene within the allowed drop, and is stable.
/// When no heading around the hypothesis heading is free, all round headings are tried
/// (a gradient off by 90 degrees must not lose the place). When still nothing fits, the
/// hierarchy's `deferred_links` (limbs a node unfolds later, such as arms raised for an
/// armrest) are left out of the collision tests and every heading is tried again: a limb
/// that will move must not lose the seat. When even then nothing fits, the
/// `overhang_links` are tested by their lower half only ([`lower_half`]) and every heading
/// is tried once more: a desk over the thighs of a chair pushed in under it must not lose
/// the seat either (the chair is pulled out to sit). When still nothing fits, the place is
/// moved back along its own heading by each of `shift_back` in turn (nearest first) and
/// tried so: where the chair is pushed in so far that the body meets the desk at the
/// place, the seat's free rear behind it still seats it. Those fits stand where the place
/// was moved to.
pub fn fit(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    hyp: &Hypothesis,
    contact: &ContactConfig,
) -> Vec<Fit> {
    let mut unchecked = h.fit.unchecked_links.clone();
    let fits = fit_checking(agent, h, scene, hyp, contact, &unchecked, &[]);
    if !fits.is_empty() {
        return fits;
    }
    if !h.fit.deferred_links.is_empty() {
        unchecked.extend(&h.fit.deferred_links);
        let fits = fit_checking(agent, h, scene, hyp, contact, &unchecked, &[]);
        if !fits.is_empty() {
            return fits;
        }
    }
    let halved = &h.fit.overhang_links;
    if !halved.is_empty() {
        let fits = fit_checking(agent, h, scene, hyp, contact, &unchecked, halved);
        if !fits.is_empty() {
            return fits;
        }
    }
    let Some(heading) = own_heading(hyp) else {
        return Vec::new();
    };
    let back = -nalgebra::Vector3::new(heading.cos(), heading.sin(), 0.0);
    for &d in &h.fit.shift_back {
        let moved = Hypothesis {
            position: hyp.position + back * d,
            ..hyp.clone()
        };
        let fits = fit_checking(agent, h, scene, &moved, contact, &unchecked, halved);
        if !fits.is_empty() {
            return fits;
        }
    }
    Vec::new()
}

/// The lower half of body part `c` in a pose whose axis is level (the thighs of the
/// initial sitting pose): a cylinder of half the radius along its underside, lowered by
/// that much, so that its bottom is the part's and its top the part's axis. It touches
/// what lies below the axis (a mattress round a pelvis sunk into it), not what lies over
/// the part (a desk's underside or drawer over the thighs).
pub fn lower_half(c: &Cylinder) -> Cylinder {
    let half = c.radius / 2.0;
    let down = nalgebra::Vector3::new(0.0, 0.0, half);
    Cylinder {
        joint: c.joint,
        a: c.a - down,
        b: c.b - down,
        radius: half,
    }
}

/// [`fit`] with the links `unchecked` left out of the collision tests and the links
/// `halved` tested by their [`lower_half`]: the headings of [`headings`], then, if none
/// of them was free, all round from [`Hypothesis::facing`] (else the place's own
/// heading), those fits marked [`Fit::turned`]. Either way only headings along the
/// place's flat rectangles ([`Hypothesis::flat_axes`]) where it has them.
fn fit_checking(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    hyp: &Hypothesis,
    contact: &ContactConfig,
    unchecked: &[usize],
    halved: &[usize],
) -> Vec<Fit> {
    let links = Links { unchecked, halved };
    let first: Vec<f64> = headings(h, hyp)
        .into_iter()
        .filter(|&y| along_flat(h, hyp, y))
        .collect();
    let (fits, any_free) = fit_headings(agent, h, scene, hyp, &first, contact, &links);
    let Some(own) = own_heading(hyp).filter(|_| !any_free) else {
        return fits;
    };
    let tried = first;
    let rest: Vec<f64> = all_round(hyp.facing.unwrap_or(own), h.fit.fallback_yaw_step)
        .into_iter()
        .filter(|y| tried.iter().all(|t| angle_between(*t, *y) > 1e-6))
        .filter(|&y| along_flat(h, hyp, y))
        .collect();
    let mut turned = fit_headings(agent, h, scene, hyp, &rest, contact, &links).0;
    for f in &mut turned {
        f.turned = true;
    }
    turned
}

/// Which links a fit leaves out of its collision tests, and which it tests by their
/// [`lower_half`] (joint indices).
struct Links<'a> {
    unchecked: &'a [usize],
    halved: &'a [usize],
}

impl Links<'_> {
    /// The body parts of `frames` the fit tests, into `out`.
    fn parts(&self, agent: &Agent, frames: &[nalgebra::Isometry3<f64>], out: &mut Vec<Cylinder>) {
        agent.cylinders_into(frames, |j| !self.unchecked.contains(&j), out);
        if self.halved.is_empty() {
            return;
        }
        for c in out.iter_mut() {
            if self.halved.contains(&c.joint) {
                *c = lower_half(c);
            }
        }
    }
}

/// Whether heading `yaw` (radians) lies along one of the place's flat rectangles
/// ([`Hypothesis::flat_axes`], either way along it), within half the step between their
/// orientations (the hierarchy's `flat` rule); true where the place has none.
fn along_flat(h: &Hierarchy, hyp: &Hypothesis, yaw: f64) -> bool {
    let Some(flat) = h.hypothesis.flat.filter(|_| !hyp.flat_axes.is_empty()) else {
        return true;
    };
    let half_step = flat.turn.to_radians() / 2.0 + 1e-9;
    hyp.flat_axes.iter().any(|&a| {
        angle_between(a, yaw) <= half_step
            || angle_between(a + std::f64::consts::PI, yaw) <= half_step
    })
}

fn angle_between(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    d.min(std::f64::consts::TAU - d)
}

/// Fits at each heading, collision-testing the body parts of `links`; also says whether
/// any heading was free at the start.
fn fit_headings(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    hyp: &Hypothesis,
    yaws: &[f64],
    contact: &ContactConfig,
    links: &Links,
) -> (Vec<Fit>, bool) {
    let posture = &h.initial;
    let mut frames = Vec::new();
    // Height of the lowest point of the stability links below the root joint.
    let probe = Placement {
        position: Point3::origin(),
        yaw: 0.0,
    };
    agent.forward_kinematics(&probe, posture, &mut frames);
    let bottom = agent
        .cylinders(&frames, |j| h.fit.stability_links.contains(&j))
        .iter()
        .map(|c| c.a.z.min(c.b.z) - c.radius)
        .fold(f64::INFINITY, f64::min);
    let bottom = if bottom.is_finite() { bottom } else { 0.0 };
    let start_z = hyp.top + h.fit.start_clearance - bottom;
    let drop = (hyp.top - hyp.position.z) + h.fit.start_clearance + h.fit.max_drop;
    // How much lower the second start is, where the first touches.
    let lower = h.fit.low_start.map(|l| h.fit.start_clearance - l);
    let mut out = Vec::new();
    let mut any_free = false;
    for &yaw in yaws {
        let at = |z: f64| Placement {
            position: Point3::new(hyp.position.x, hyp.position.y, z),
            yaw,
        };
        let mut parts: Vec<Cylinder> = Vec::new();
        let (mut f, mut cache) = (Vec::new(), FkCache::default());
        // The start: `start_clearance` above the top, else `low_start` (a table's underside
        // over the thighs of a chair pushed in leaves less room than the full clearance).
        let free_at = |z: f64, parts: &mut Vec<Cylinder>, f: &mut Vec<_>| {
            parts.clear();
            agent.forward_kinematics(&at(z), posture, f);
            links.parts(agent, f, parts);
            !parts.iter().any(|c| scene.touches(c))
        };
        let (start_z, drop) = if free_at(start_z, &mut parts, &mut f) {
            (start_z, drop)
        } else if let Some(lower) = lower.filter(|&l| free_at(start_z - l, &mut parts, &mut f)) {
            (start_z - lower, drop - lower)
        } else {
            continue;
        };
        let mut pose = |t: f64, out: &mut Vec<Cylinder>| {
            agent.forward_kinematics_cached(&at(start_z - t * drop), posture, &mut cache, &mut f);
            links.parts(agent, &f, out);
        };
        any_free = true;
        let Some(t) = scene.first_contact(&mut pose, drop, contact.resolution) else {
            continue;
        };
        // Rest just above the contact found (the bisection returns the touching side).
        let z = start_z - (t * drop - contact.resolution).max(0.0);
        let placement = at(z);
        agent.forward_kinematics(&placement, posture, &mut frames);
        let s = stability(agent, h, scene, &frames);
        if s >= h.fit.min_stability {
            out.push(Fit {
                placement,
                posture: posture.clone(),
                stability: s,
                turned: false,
                unseen_width: hyp.unseen_width,
            });
        }
    }
    (out, any_free)
}

/// The stability score of Eq. 1: exp(-(mean d_i)^2 / (2 sigma_d^2)) over samples d_i of
/// the distances from the stability links' surfaces to the scene (metres).
pub fn stability(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    frames: &[nalgebra::Isometry3<f64>],
) -> f64 {
    let mut sum = 0.0;
    let mut n = 0usize;
    for c in agent.cylinders(frames, |j| h.fit.stability_links.contains(&j)) {
        let len = (c.b - c.a).norm();
        let k = to_usize((len / h.fit.sample_spacing).ceil().max(1.0));
        for i in 0..=k {
            let p = c.a + (c.b - c.a) * (i as f64 / k as f64);
            sum += scene.surface_distance(&p, c.radius);
            n += 1;
        }
    }
    if n == 0 {
        return 0.0;
    }
    let mean = sum / n as f64;
    (-(mean * mean) / (2.0 * h.fit.sigma_d * h.fit.sigma_d)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::PointCloud;
    use crate::method::scene::SceneConfig;
    use crate::model::hierarchy::Hierarchy;
    use crate::model::set::{BUILTIN_AGENT, BUILTIN_SITTING};
    use std::path::Path;

    fn models() -> (Agent, Hierarchy) {
        let a = Agent::from_toml(BUILTIN_AGENT, Path::new("human.toml"), 1.75).unwrap();
        let h = Hierarchy::from_toml(BUILTIN_SITTING, Path::new("sitting.toml"), &a).unwrap();
        (a, h)
    }

    /// A 1 x 1 m seat top of points 1 cm apart at z = 0.45 (its voxels reach 0.44-0.46).
    fn seat() -> Scene {
        let mut pts = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                pts.push(Point3::new(
                    -0.5 + i as f64 * 0.01,
                    -0.5 + j as f64 * 0.01,
                    0.45,
                ));
            }
        }
        scene_of(pts)
    }

    /// The scene of `pts`: 2 cm voxels over a solid floor.
    fn scene_of(pts: Vec<Point3<f64>>) -> Scene {
        Scene::new(
            &PointCloud::new(pts),
            &SceneConfig {
                voxel_size: 0.02,
                floor: true,
                field_margin: 0.3,
            },
        )
    }

    /// A place over the middle of `seat()`, heading +x.
    fn over_the_seat() -> Hypothesis {
        Hypothesis {
            cell: (0, 0),
            position: Point3::new(0.0, 0.0, 0.45),
            top: 0.45,
            availability: 1.0,
            heading: Some(0.0),
            facing: None,
            memberships: [1.0; 3],
            risen: false,
            unseen_width: false,
            flat_axes: Vec::new(),
        }
    }

    /// The fits at [`over_the_seat`] in `s`, contact to 5 mm.
    fn fit_over_the_seat(a: &Agent, h: &Hierarchy, s: &Scene) -> Vec<Fit> {
        fit(
            a,
            h,
            s,
            &over_the_seat(),
            &ContactConfig { resolution: 0.005 },
        )
    }

    /// The height of the pelvis's lowest point in fit `f`, metres.
    fn pelvis_bottom(a: &Agent, f: &Fit) -> f64 {
        let mut frames = Vec::new();
        a.forward_kinematics(&f.placement, &f.posture, &mut frames);
        let pelvis = a.cylinders(&frames, |j| j == 0)[0];
        pelvis.a.z - pelvis.radius
    }

    /// Eq. 1 with the pelvis bottom `gap` metres above the seat's voxels.
    fn stability_at(gap: f64) -> f64 {
        let (a, h) = models();
        let s = seat();
        let pelvis_radius = a.joints[0].link.as_ref().unwrap().radius;
        let mut frames = Vec::new();
        let place = Placement {
            position: Point3::new(0.0, 0.0, 0.46 + gap + pelvis_radius),
            yaw: 0.0,
        };
        a.forward_kinematics(&place, &h.initial, &mut frames);
        stability(&a, &h, &s, &frames)
    }

    #[test]
    fn stability_follows_eq_1() {
        // sigma_d = 0.03 m: resting gives ~1, one sigma exp(-1/2) = 0.61, 10 cm ~0.
        assert!(stability_at(0.0) > 0.9, "{}", stability_at(0.0));
        let one_sigma = stability_at(0.03);
        assert!((one_sigma - (-0.5f64).exp()).abs() < 0.15, "{one_sigma}");
        assert!(stability_at(0.10) < 0.01, "{}", stability_at(0.10));
    }

    #[test]
    fn all_round_headings_start_at_the_given_one_nearest_first() {
        let deg: Vec<f64> = all_round(0.5, 30f64.to_radians())
            .iter()
            .map(|y| (y - 0.5).to_degrees().round())
            .collect();
        assert_eq!(
            deg,
            [0., 30., -30., 60., -60., 90., -90., 120., -120., 150., -150., 180.]
        );
        assert_eq!(all_round(1.0, 7.0), [1.0]);
    }

    #[test]
    fn a_table_top_over_the_thighs_lowers_the_start() {
        // The seat of `seat()` with a table top over its front (x 0.2 to 0.5) whose
        // voxels start at 0.62 m: the thighs of the initial pose, started 4 cm above the
        // seat, reach 0.639 m and touch it; started 2 cm above they clear it, and seated
        // (0.61 m) they do too. A chair pushed in at a table is sat on facing it.
        let (a, h) = models();
        assert_eq!((h.fit.start_clearance, h.fit.low_start), (0.04, Some(0.02)));
        let mut pts: Vec<Point3<f64>> = Vec::new();
        for i in 0..100 {
            for j in 0..100 {
                let (x, y) = (-0.5 + i as f64 * 0.01, -0.5 + j as f64 * 0.01);
                pts.push(Point3::new(x, y, 0.45));
                if x >= 0.2 {
                    pts.push(Point3::new(x, y, 0.635));
                }
            }
        }
        let s = scene_of(pts);
        let fits = fit_over_the_seat(&a, &h, &s);
        let facing = fits.iter().find(|f| f.placement.yaw.abs() < 1e-9);
        let f = facing.expect("a fit facing the table");
        assert!(!f.turned);
        let bottom = pelvis_bottom(&a, f);
        assert!(
            (0.455..=0.47).contains(&bottom),
            "pelvis bottom at {bottom}"
        );
    }

    #[test]
    fn the_lower_half_of_a_level_part_spans_its_bottom_to_its_axis() {
        let c = Cylinder {
            joint: 3,
            a: Point3::new(0.0, 0.0, 0.52),
            b: Point3::new(0.4, 0.1, 0.52),
            radius: 0.07,
        };
        let h = lower_half(&c);
        assert_eq!(h.joint, 3);
        assert!((h.radius - 0.035).abs() < 1e-12);
        assert!(
            (h.a.z - h.radius - (c.a.z - c.radius)).abs() < 1e-12,
            "same bottom"
        );
        assert!((h.b.z + h.radius - c.b.z).abs() < 1e-12, "top at the axis");
        assert_eq!((h.a.x, h.a.y, h.b.x, h.b.y), (0.0, 0.0, 0.4, 0.1));
    }

    /// Heights from `from` to `to` (metres) 1 cm apart.
    fn steps(from: f64, to: f64) -> impl Iterator<Item = f64> {
        let n = to_usize(((to - from) / 0.01).round());
        (0..=n).map(move |i| from + i as f64 * 0.01)
    }

    /// An armchair: the seat of `seat()` inside a back (x = -0.25) and two arms (y =
    /// +-0.28, to x = 0.3 and z = 0.8), with points at the heights `over(x, y)` over each
    /// point of the seat. Turned away from the front the thighs meet the back or an arm.
    fn armchair(over: impl Fn(f64, f64) -> Vec<f64>) -> Scene {
        let mut pts = Vec::new();
        for x in steps(-0.5, 0.5) {
            for y in steps(-0.5, 0.5) {
                pts.push(Point3::new(x, y, 0.45));
                pts.extend(over(x, y).into_iter().map(|z| Point3::new(x, y, z)));
            }
        }
        for z in steps(0.45, 1.2) {
            for y in steps(-0.3, 0.3) {
                pts.push(Point3::new(-0.25, y, z));
            }
            for x in steps(-0.25, 0.3).filter(|_| z <= 0.8) {
                pts.push(Point3::new(x, -0.28, z));
                pts.push(Point3::new(x, 0.28, z));
            }
        }
        scene_of(pts)
    }

    /// The [`armchair`] pushed in under a desk: over its front (x 0.1 to 0.5) the
    /// underside of a drawer `above` metres over the seat, or a block `above` metres high
    /// standing on it.
    fn armchair_under(above: f64, block: bool) -> Scene {
        armchair(|x, y| match (x >= 0.1 && y.abs() <= 0.3, block) {
            (false, _) => Vec::new(),
            (true, false) => vec![0.45 + above],
            (true, true) => steps(0.45, 0.45 + above).collect(),
        })
    }

    /// Asserts that every fit of `fits` faces the desk (+x, within the 20-degree offsets)
    /// with the pelvis resting on the seat's voxels (0.46 m, contact to 5 mm).
    fn seated_facing_the_desk(a: &Agent, fits: &[Fit]) {
        for f in fits {
            let yaw = f.placement.yaw.to_degrees();
            assert!(yaw.abs() <= 20.0 + 1e-9, "facing the desk: {yaw}");
            let bottom = pelvis_bottom(a, f);
            assert!(
                (0.455..=0.47).contains(&bottom),
                "pelvis bottom at {bottom}"
            );
        }
    }

    #[test]
    fn a_drawer_over_the_thighs_does_not_lose_the_seat_what_stands_under_them_does() {
        let (a, h) = models();
        assert!(!h.fit.overhang_links.is_empty());
        // Seated, the thighs reach 0.14 m above the seat; started 2-4 cm higher, 0.16-0.18.
        let fits = fit_over_the_seat(&a, &h, &armchair_under(0.13, false));
        assert!(!fits.is_empty(), "the drawer lost the seat");
        seated_facing_the_desk(&a, &fits);
        // Without the last try (no overhang links) nothing fits at any heading.
        let mut strict = h.clone();
        strict.fit.overhang_links.clear();
        assert!(fit_over_the_seat(&a, &strict, &armchair_under(0.13, false)).is_empty());
        // A block 5 cm high on the seat's front fills the space below the thighs' axis:
        // the lowered body rests on it, not on the seat, and is not stable.
        assert!(fit_over_the_seat(&a, &h, &armchair_under(0.05, true)).is_empty());
    }

    #[test]
    fn a_chair_pushed_in_too_far_is_sat_on_at_its_free_rear() {
        // The armchair of `armchair` with a desk top at 0.72 m reaching back to
        // x = 0.05, over the place: the upright trunk (0.11 m radius) meets the desk's edge
        // at every heading there. 0.10 m further back it clears the edge and the chair's
        // back (x = -0.25) still; 0.15 m back it meets the chair's back.
        let (a, h) = models();
        assert_eq!(h.fit.shift_back, [0.05, 0.10, 0.15, 0.20]);
        let s = armchair(|x, _| if x >= 0.05 { vec![0.72] } else { Vec::new() });
        let fits = fit_over_the_seat(&a, &h, &s);
        assert!(!fits.is_empty(), "the desk's edge lost the seat");
        seated_facing_the_desk(&a, &fits);
        for f in &fits {
            let p = f.placement.position;
            assert!(
                (p.x + 0.10).abs() < 1e-9 && p.y.abs() < 1e-9,
                "moved to {p:?}"
            );
        }
        let mut fixed = h.clone();
        fixed.fit.shift_back.clear();
        assert!(fit_over_the_seat(&a, &fixed, &s).is_empty());
    }

    #[test]
    fn the_agent_is_lowered_onto_the_seat() {
        let (a, h) = models();
        let s = seat();
        let fits = fit_over_the_seat(&a, &h, &s);
        assert_eq!(
            fits.len(),
            h.fit.yaw_offsets.len(),
            "every heading is free and stable on a flat seat"
        );
        let f = &fits[0];
        let bottom = pelvis_bottom(&a, f);
        // The seat's voxels end at 0.46 m; contact is located to 5 mm.
        assert!(
            (0.455..=0.47).contains(&bottom),
            "pelvis bottom at {bottom}"
        );
    }
}
