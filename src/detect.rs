//! The pipeline of section 4, stage after stage: height map, hypotheses, scene, fitting,
//! unfolding, selection and segmentation.

use std::path::Path;
use std::sync::OnceLock;

use nalgebra::Point3;
use rayon::prelude::*;

use crate::cloud::{point_spacing, PointCloud};
use crate::method::extent::{guard, ExtentConfig, ExtentError};
use crate::method::fit::{fit, ContactConfig, Fit};
use crate::method::heightmap::{HeightMap, HeightMapConfig, Spacing};
use crate::method::hidden::{hidden_seats, HiddenConfig};
use crate::method::holes::{fill, fill_points, holes, Hole, HoleConfig};
use crate::method::hypotheses::{hypotheses, Hypothesis};
use crate::method::scene::{Scene, SceneConfig};
use crate::method::select::{segment_in, suppress, SegmentConfig, SegmentGrid};
use crate::method::specks::without_specks;
use crate::method::unfold::{unfold, Unfolded};
use crate::model::agent::{Agent, Cylinder};
use crate::model::hierarchy::{Hierarchy, Selection};
use crate::model::set::Model;

/// The scene-level numbers of a run (not per hierarchy). Defaults carry their reasons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectConfig {
    /// The height map (section 4.1).
    pub heightmap: HeightMapConfig,
    /// The holes of a view filled before the grids ([`crate::method::holes`]).
    pub holes: HoleConfig,
    /// The seats hidden behind their backs and arms filled after them
    /// ([`crate::method::hidden`]).
    pub hidden: HiddenConfig,
    /// Voxelisation of the scene.
    pub scene: SceneConfig,
    /// Contact location.
    pub contact: ContactConfig,
    /// Region growing.
    pub segment: SegmentConfig,
    /// Specks ([`crate::method::specks`]): points in a component of at most
    /// `speck_cubes` occupied cubes, joined through faces, edges and corners, are left out
    /// of the height map and the scene. The cubes' edge is `speck_spacings` times the
    /// cloud's point spacing ([`crate::cloud::point_spacing`]), and at least
    /// `speck_min_cell` metres.
    pub speck_spacings: f64,
    /// See `speck_spacings`.
    pub speck_min_cell: f64,
    /// See `speck_spacings`.
    pub speck_cubes: usize,
    /// A cube of a component that small also joins the occupied cubes on both sides of
    /// it along a line, up to this many cubes away along each axis: the samples of a
    /// surface seen at a grazing angle go on through it, a stray's do not.
    pub speck_line: usize,
}

/// The default voxel edge, metres: at most 0.02 m, finer than the 3-4 cm radius of the
/// thinnest limb.
pub const DEFAULT_VOXEL: f64 = 0.02;
/// Contact resolution in voxels: a quarter voxel (5 mm at 2 cm), under 1 degree of trunk
/// recline at shoulder height.
pub const CONTACT_VOXELS: f64 = 0.25;
/// Region-growing distance in voxels: 1.5 voxels (3 cm at 2 cm) closes gaps of
/// depth-camera sampling at 1-2 m without jumping between objects.
pub const GROW_VOXELS: f64 = 1.5;

impl Default for DetectConfig {
    fn default() -> Self {
        Self::for_voxel(DEFAULT_VOXEL)
    }
}

impl DetectConfig {
    /// The defaults for a scene of `voxel_size` metres: the numbers defined as fractions
    /// of the voxel ([`CONTACT_VOXELS`], [`GROW_VOXELS`]) follow it. The caller checks the
    /// size (the command line checks it against its voxel range).
    pub fn for_voxel(voxel_size: f64) -> Self {
        DetectConfig {
            heightmap: HeightMapConfig::default(),
            holes: HoleConfig::default(),
            hidden: HiddenConfig::default(),
            scene: SceneConfig {
                voxel_size,
                // Paper, section 3.1: agent and scene share the ground plane z = 0.
                floor: true,
                // The agent's limbs sweep up to ~0.3 m beyond a seat; further out the box bound suffices.
                field_margin: 0.3,
            },
            contact: ContactConfig {
                resolution: CONTACT_VOXELS * voxel_size,
            },
            segment: SegmentConfig {
                grow_distance: GROW_VOXELS * voxel_size,
                // Points within 5 cm of the floor are floor (noise of a Kinect-like sensor at 2 m is ~1-2 cm).
                floor_height: 0.05,
                // Seeds: the seat under the pelvis, within a hip-breadth radius.
                seed_radius: 0.15,
                // A chair has a few thousand points in a view; a room-sized segment means a leak.
                max_points: 200_000,
            },
            // 1.5: a surface's points have their four nearest neighbours about one
            // spacing away (the spacing is the median distance to the fourth), so the
            // cubes of a densely sampled surface join up.
            speck_spacings: 1.5,
            // 0.04 m: surfaces sampled more sparsely than the cloud's median (mesh
            // vertices 4 cm apart, the far wall of a room view) still join up.
            speck_min_cell: 0.04,
            // 8 cubes (0.04-0.16 m across): a clump of stray returns or a floating
            // fragment; anything a forearm or a body rests on spans more.
            speck_cubes: 8,
            // 2 cubes (3 spacings): a depth camera's rows land on a surface seen at
            // 20 degrees 3 spacings apart (1 / sin 20 deg), one empty cube between its
            // samples; a camera 1.75 m high sees a 0.6 m arm top 3 m away at 21 degrees.
            speck_line: 2,
        }
    }
}

/// One detected place and how it affords the hierarchy's action.
#[derive(Debug, Clone, PartialEq)]
pub struct Detection {
    /// Hierarchy name (`sitting`).
    pub hierarchy: String,
    /// The body: agent name (`human`).
    pub agent: String,
    /// The body: height, metres.
    pub height: f64,
    /// The agent's root joint (pelvis), world frame, metres.
    pub position: Point3<f64>,
    /// Heading about z, radians (0 faces +x).
    pub yaw: f64,
    /// The point of the seat under the agent, world frame, metres (segmentation seed).
    pub seat: Point3<f64>,
    /// Ids of the fine-grained affordances found, in hierarchy order.
    pub affordances: Vec<String>,
    /// Local score of every visited node, `(id, score)`.
    pub local_scores: Vec<(String, f64)>,
    /// The goal pose H_g: every joint's angle, degrees.
    pub pose: Vec<(String, f64)>,
    /// Accumulated score (Eq. 5).
    pub score: f64,
    /// Stability (Eq. 1).
    pub stability: f64,
    /// Availability of the hypothesis (Fig. 5d).
    pub availability: f64,
    /// Number of points in the segment grown from the detection.
    pub segment_points: usize,
    /// The posed body parts of the goal pose, world frame (for pictures and meshes).
    pub parts: Vec<Cylinder>,
    /// Every joint's origin in the goal pose H_g, world frame, metres, in the agent's
    /// joint order: the forward kinematics of `pose` at `position` and `yaw`.
    pub joints: Vec<(String, Point3<f64>)>,
}

/// Everything one run over one cloud produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    /// Detections after suppression, strongest first.
    pub detections: Vec<Detection>,
    /// Per input point, the index of the detection whose segment holds it.
    pub labels: Vec<Option<usize>>,
    /// Counts of the stages, for reports.
    pub stats: Stats,
}

/// How many items each stage produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Stats {
    /// Points of the cloud.
    pub points: usize,
    /// Occupied voxels.
    pub voxels: usize,
    /// Available hypotheses (section 4.1).
    pub hypotheses: usize,
    /// Stable fits (section 4.2).
    pub fits: usize,
    /// Hypotheses whose root affordance was found, before suppression.
    pub candidates: usize,
}

/// The shared, hierarchy-independent representations of a scene.
pub struct Prepared {
    /// The height map (section 4.1).
    pub map: HeightMap,
    /// The voxelised scene.
    pub scene: Scene,
    /// The holes of the height map filled before hypotheses and fits
    /// ([`crate::method::holes`]), then the seats hidden behind backs and arms
    /// ([`crate::method::hidden`]); their cells are set in `map` and occupied in `scene`.
    pub filled: Vec<Hole>,
    /// The height map with the holes filled but not the hidden seats, for the hierarchies
    /// that take none ([`crate::model::hierarchy::HypothesisRule::hidden_seats`]): their
    /// places and the surfaces round them are looked for where the scan saw something,
    /// while their bodies meet the same scene; `None` where no hidden seat was filled, and
    /// then `map` serves them too.
    pub without_hidden: Option<HeightMap>,
}

impl Prepared {
    /// The height map a hierarchy's places are found on: with the hidden seats filled
    /// where `hidden_seats`
    /// ([`crate::model::hierarchy::HypothesisRule::hidden_seats`]), else without them.
    pub fn map_for(&self, hidden_seats: bool) -> &HeightMap {
        match &self.without_hidden {
            Some(map) if !hidden_seats => map,
            _ => &self.map,
        }
    }
}

/// Builds the height map and the voxelised scene once for a cloud. The two are
/// independent (each reads only `cloud` and its own config), so they are built side by
/// side on rayon's pool: the same grids whatever the thread count.
pub fn prepare(cloud: &PointCloud, cfg: &DetectConfig) -> Prepared {
    prepare_spaced(cloud, cloud, cfg, Spacing::Measure)
}

/// [`prepare`], with the cloud's point spacing given when already measured
/// ([`HeightMap::from_cloud_spaced`]), else measured by the height map. `seen` holds every
/// point the scan saw (`cloud` and the specks left out of it), which a hidden seat must be
/// clear of ([`hidden_seats`]).
fn prepare_spaced(
    cloud: &PointCloud,
    seen: &PointCloud,
    cfg: &DetectConfig,
    spacing: Spacing,
) -> Prepared {
    let (mut map, scene) = rayon::join(
        || match spacing {
            Spacing::Given(s) => HeightMap::from_cloud_spaced(cloud, &cfg.heightmap, s),
            Spacing::Measure => HeightMap::from_cloud(cloud, &cfg.heightmap),
        },
        || Scene::new(cloud, &cfg.scene),
    );
    // The holes the scan closes round are filled, then the seats hidden inside the backs
    // and arms that hid them: their cells valid in the map, their voxels occupied in a
    // scene built again with the fill. A hierarchy that takes no hidden seats looks for
    // its places on the map with the holes alone filled, kept aside where hidden seats
    // are filled.
    let mut found = holes(&map, &cfg.holes);
    fill(&mut map, &found);
    let hidden = hidden_seats(&map, &seen.points, &cfg.hidden);
    let without_hidden = (!hidden.is_empty()).then(|| map.clone());
    fill(&mut map, &hidden);
    found.extend(hidden);
    if found.is_empty() {
        return Prepared {
            map,
            scene,
            filled: found,
            without_hidden,
        };
    }
    let fill_at = fill_points(&map, &found, cfg.scene.voxel_size);
    let scene = scene.with_points(cloud, fill_at, &cfg.scene);
    Prepared {
        map,
        scene,
        filled: found,
        without_hidden,
    }
}

/// The best unfolded pose at one hypothesis whose root affordance is present, with the
/// number of stable fits tried: the first in the fits' order (section 4.2, below) that
/// leaves nothing over space the scan never saw, else the first at all.
pub fn best_at(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    hyp: &Hypothesis,
    cfg: &DetectConfig,
) -> (Option<Unfolded>, usize) {
    let fits = fit(agent, h, scene, hyp, &cfg.contact);
    let n = fits.len();
    // Section 4.2: the orientation with the best stability is kept. Stabilities within
    // the hierarchy's band count as equal, and then the heading tried first (the nearest
    // to the hypothesis heading) wins; if its root affordance is absent the next is tried.
    let top = fits.iter().map(|f| f.stability).fold(0.0, f64::max);
    let (equal, rest): (Vec<&Fit>, Vec<&Fit>) = fits
        .iter()
        .partition(|f| f.stability >= top - h.fit.stability_band);
    let found = equal
        .into_iter()
        .chain(rest)
        .map(|f| unfold(agent, h, scene, f, &cfg.contact))
        .filter(|u| u.nodes.first().is_some_and(|r| r.found));
    (first_seen(found), n)
}

/// The first of `found` (poses in the order their fits are tried) that leaves nothing over
/// space the scan never saw, else the first at all: a pose that rests on what the scan saw
/// comes before one found only by leaving a part over unseen space (`unseen_sweeps`).
/// Stops at the first such pose, so the rest are not unfolded.
fn first_seen(found: impl IntoIterator<Item = Unfolded>) -> Option<Unfolded> {
    let mut first_unseen = None;
    for u in found {
        if !u.unseen() {
            return Some(u);
        }
        first_unseen.get_or_insert(u);
    }
    first_unseen
}

/// Runs the whole method on `cloud` for one agent and one hierarchy.
pub fn detect(cloud: &PointCloud, agent: &Agent, h: &Hierarchy, cfg: &DetectConfig) -> Outcome {
    let prepared = prepare(cloud, cfg);
    detect_prepared(cloud, &prepared, agent, h, cfg)
}

/// Runs the method on `cloud` for every model of a set (each body with each hierarchy),
/// building the height map and the voxelised scene once for all of them, from every point
/// (no extent guard: a file is detected in with [`detect_input`]).
pub fn detect_all(cloud: &PointCloud, models: &[Model], cfg: &DetectConfig) -> Vec<Outcome> {
    detect_all_prepared(cloud, &prepare(cloud, cfg), models, cfg)
}

/// The grids of `cloud` (world frame, metres; read from `path`, which names it in
/// messages) as every command builds them: from the points the extent guard
/// ([`crate::method::extent::guard`], default limits) keeps, less the specks
/// ([`crate::method::specks`]). Refuses what the guard refuses.
pub fn prepare_guarded(
    path: &Path,
    cloud: &PointCloud,
    cfg: &DetectConfig,
) -> Result<Prepared, ExtentError> {
    let kept = guard(path, cloud, cfg, &ExtentConfig::default())?;
    // The spacing is measured once, for the specks' cubes and the height map. Where it
    // gives cubes no larger than `speck_min_cell` (every densely sampled cloud), the
    // specks on those cubes are found beside it; else found again on the larger cubes.
    let at_min = || {
        without_specks(
            &kept.cloud,
            cfg.speck_min_cell,
            cfg.speck_cubes,
            cfg.speck_line,
        )
    };
    let (spacing, specks) = rayon::join(|| point_spacing(&kept.cloud), at_min);
    let cell = spacing
        .map_or(0.0, |s| cfg.speck_spacings * s)
        .max(cfg.speck_min_cell);
    let specks = if cell > cfg.speck_min_cell {
        without_specks(&kept.cloud, cell, cfg.speck_cubes, cfg.speck_line)
    } else {
        specks
    };
    Ok(match specks {
        Some((surface, _)) => prepare_spaced(&surface, &kept.cloud, cfg, Spacing::Given(spacing)),
        None => prepare_spaced(&kept.cloud, &kept.cloud, cfg, Spacing::Given(spacing)),
    })
}

/// Detection on one input cloud, the one per-file path of `afford detect`, `afford eval`,
/// `afford inspect` and the Python package: the grids from [`prepare_guarded`], every model
/// of the set on them, and the segments over every point of `cloud` (stray points
/// included), so that the outcomes' labels line up with `cloud`.
pub fn detect_input(
    path: &Path,
    cloud: &PointCloud,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<Vec<Outcome>, ExtentError> {
    let prepared = prepare_guarded(path, cloud, cfg)?;
    Ok(detect_all_prepared(cloud, &prepared, models, cfg))
}

/// [`detect_all`] on a scene already prepared (the caller also draws its height map).
pub fn detect_all_prepared(
    cloud: &PointCloud,
    prepared: &Prepared,
    models: &[Model],
    cfg: &DetectConfig,
) -> Vec<Outcome> {
    // The segmentation's cells depend on the cloud and `cfg.segment` only: built once,
    // beside the first search with hypotheses to try.
    let grid = OnceLock::new();
    // Each model's segmentation (serial) runs beside the next model's search: each reads
    // only the prepared scene, the cloud and the cells, so each gives the same whatever
    // runs beside it, and the outcomes are kept in the models' order. A model without
    // detections has nothing to grow: its outcome (every label `None`) is made right
    // after its search, still beside the segmentation before it.
    let mut outcomes = Vec::with_capacity(models.len());
    let mut last: Option<Found> = None;
    for m in models {
        let (found, done) = rayon::join(
            || {
                let f = find(cloud, prepared, &m.agent, &m.hierarchy, cfg, &grid);
                if f.detections.is_empty() {
                    Err(label(cloud, f, cfg, &grid))
                } else {
                    Ok(f)
                }
            },
            || last.take().map(|f| label(cloud, f, cfg, &grid)),
        );
        outcomes.extend(done);
        match found {
            Ok(f) => last = Some(f),
            Err(labelled) => outcomes.push(labelled),
        }
    }
    outcomes.extend(last.map(|f| label(cloud, f, cfg, &grid)));
    outcomes
}

/// Runs the method on a prepared scene (shared between hierarchies and bodies).
pub fn detect_prepared(
    cloud: &PointCloud,
    prepared: &Prepared,
    agent: &Agent,
    h: &Hierarchy,
    cfg: &DetectConfig,
) -> Outcome {
    let grid = OnceLock::new();
    label(
        cloud,
        find(cloud, prepared, agent, h, cfg, &grid),
        cfg,
        &grid,
    )
}

/// One model's detections on a prepared scene, strongest first, before segmentation
/// (`segment_points` 0), with the counts of its stages.
struct Found {
    /// The detections after suppression.
    detections: Vec<Detection>,
    /// Counts of the stages.
    stats: Stats,
}

/// The search of [`detect_prepared`]: hypotheses, fits, unfolding, selection. The
/// cells in `grid` are built beside the search when there are hypotheses to try.
fn find(
    cloud: &PointCloud,
    prepared: &Prepared,
    agent: &Agent,
    h: &Hierarchy,
    cfg: &DetectConfig,
    grid: &OnceLock<SegmentGrid>,
) -> Found {
    let map = prepared.map_for(h.hypothesis.hidden_seats);
    let hyps = hypotheses(map, &h.hypothesis, h.orientation, agent.height);
    let radius = h.suppression_radius * agent.height;
    // The best pose at each hypothesis of `at` (indices into `hyps`), as candidates
    // (hypothesis, pose), with the number of fits tried.
    let search = |at: &[usize]| -> (Vec<(usize, Unfolded)>, usize) {
        let results: Vec<(Option<Unfolded>, usize)> = at
            .par_iter()
            .map(|&i| best_at(agent, h, &prepared.scene, &hyps[i], cfg))
            .collect();
        let fits = results.iter().map(|r| r.1).sum();
        let found = at
            .iter()
            .zip(results)
            .filter_map(|(&i, (u, _))| u.map(|u| (i, u)))
            .collect();
        (found, fits)
    };
    let (plain, risen): (Vec<usize>, Vec<usize>) = (0..hyps.len()).partition(|&i| !hyps[i].risen);
    // With hypotheses to try, a detection (and so the segmentation's cells) is likely:
    // the cells are built beside the search rather than after it. They depend on `cloud`
    // and `cfg.segment` only, so they are the same whenever they are built.
    let (mut candidates, mut fits) = if hyps.is_empty() {
        (Vec::new(), 0)
    } else {
        rayon::join(
            || search(&plain),
            || {
                grid.get_or_init(|| SegmentGrid::new(cloud, &cfg.segment));
            },
        )
        .0
    };
    // Places found only with a rise set aside rank after every plain one
    // ([`strongest_first`]), so the plain places kept are those kept among the plain
    // candidates alone, and a risen place within the radius of one of them would be
    // suppressed: only the others are tried (the same detections as trying all, but
    // where the fit's last resort, `shift_back`, would have moved a place out of it).
    let kept_plain: Vec<Point3<f64>> = kept(&candidates, |_| false, h.score.select, radius)
        .into_iter()
        .map(|k| candidates[k].1.placement.position)
        .collect();
    let apart: Vec<usize> = risen
        .into_iter()
        .filter(|&i| {
            let p = hyps[i].position;
            kept_plain.iter().all(|c| (c.xy() - p.xy()).norm() > radius)
        })
        .collect();
    if !apart.is_empty() {
        let (more, more_fits) = search(&apart);
        candidates.extend(more);
        candidates.sort_by_key(|(i, _)| *i);
        fits += more_fits;
    }
    let kept = kept(&candidates, |i| hyps[i].risen, h.score.select, radius);
    let detections: Vec<Detection> = kept
        .iter()
        .map(|&k| {
            let (hi, u) = &candidates[k];
            to_detection(agent, h, &hyps[*hi], u)
        })
        .collect();
    Found {
        detections,
        stats: Stats {
            points: cloud.len(),
            voxels: prepared.scene.voxel_count(),
            hypotheses: hyps.len(),
            fits,
            candidates: candidates.len(),
        },
    }
}

/// The candidates (hypothesis index, pose) that suppression keeps, strongest first
/// ([`strongest_first`], with `risen` telling which hypotheses' places were found only by
/// setting a rise aside; [`suppress`] within `radius` metres): indices into `candidates`.
fn kept(
    candidates: &[(usize, Unfolded)],
    risen: impl Fn(usize) -> bool,
    select: Selection,
    radius: f64,
) -> Vec<usize> {
    let ranked: Vec<(bool, &Unfolded)> = candidates.iter().map(|(i, u)| (risen(*i), u)).collect();
    let centres: Vec<Point3<f64>> = candidates
        .iter()
        .map(|(_, u)| u.placement.position)
        .collect();
    suppress(&centres, &strongest_first(&ranked, select), radius)
}

/// The order in which candidates are kept by suppression: indices into `candidates`
/// (each with whether its place was found only by setting aside what stands over a seat's
/// edge, [`Hypothesis::risen`]), plain places before such ones, each strongest first under
/// `select`, ties by index (hypothesis order), so the result is independent of threads.
/// A place found only with the rise set aside is thus kept only where no plain place is
/// near: it adds seats, it does not move them.
fn strongest_first(candidates: &[(bool, &Unfolded)], select: Selection) -> Vec<usize> {
    let mut order: Vec<usize> = (0..candidates.len()).collect();
    order.sort_by(|&a, &b| {
        let ((ra, ua), (rb, ub)) = (candidates[a], candidates[b]);
        ra.cmp(&rb).then(ub.rank(ua, select)).then(a.cmp(&b))
    });
    order
}

/// The segmentation of [`detect_prepared`]: the points of `cloud` grown from each
/// detection of `found` in turn (over the cells in `grid`, built if not yet there), and
/// each detection's count of them.
fn label(
    cloud: &PointCloud,
    found: Found,
    cfg: &DetectConfig,
    grid: &OnceLock<SegmentGrid>,
) -> Outcome {
    let Found {
        mut detections,
        stats,
    } = found;
    let seeds: Vec<Point3<f64>> = detections.iter().map(|d| d.seat).collect();
    let labels = if seeds.is_empty() {
        vec![None; cloud.len()]
    } else {
        let grid = grid.get_or_init(|| SegmentGrid::new(cloud, &cfg.segment));
        segment_in(grid, cloud, &seeds, &cfg.segment)
    };
    for l in labels.iter().flatten() {
        detections[*l].segment_points += 1;
    }
    Outcome {
        detections,
        labels,
        stats,
    }
}

fn to_detection(agent: &Agent, h: &Hierarchy, hyp: &Hypothesis, u: &Unfolded) -> Detection {
    let mut frames = Vec::new();
    agent.forward_kinematics(&u.placement, &u.posture, &mut frames);
    let bottom = agent
        .cylinders(&frames, |j| h.fit.stability_links.contains(&j))
        .iter()
        .map(|c| c.a.z.min(c.b.z) - c.radius)
        .fold(f64::INFINITY, f64::min);
    let p = u.placement.position;
    let seat = Point3::new(p.x, p.y, if bottom.is_finite() { bottom } else { p.z });
    Detection {
        hierarchy: h.name.clone(),
        agent: agent.name.clone(),
        height: agent.height,
        position: p,
        yaw: u.placement.yaw.rem_euclid(std::f64::consts::TAU),
        seat,
        affordances: h
            .nodes
            .iter()
            .zip(&u.nodes)
            .filter(|(_, o)| o.found)
            .map(|(n, _)| n.id.clone())
            .collect(),
        local_scores: h
            .nodes
            .iter()
            .zip(&u.nodes)
            .filter(|(_, o)| o.visited)
            .map(|(n, o)| (n.id.clone(), o.local))
            .collect(),
        pose: agent
            .joints
            .iter()
            .zip(&u.posture.angles)
            .map(|(j, a)| (j.name.clone(), a.to_degrees()))
            .collect(),
        score: u.score,
        stability: u.stability,
        availability: hyp.availability,
        segment_points: 0,
        parts: agent.cylinders(&frames, |_| true),
        joints: agent
            .joints
            .iter()
            .zip(&frames)
            .map(|(j, f)| (j.name.clone(), Point3::from(f.translation.vector)))
            .collect(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::set::ModelChoice;

    /// Points on a grid of `step` metres over the box `lo`-`hi` (x, y) at height `z`.
    fn patch(lo: (f64, f64), hi: (f64, f64), z: f64, step: f64, out: &mut Vec<Point3<f64>>) {
        let n = |a: f64, b: f64| crate::num::to_usize(((b - a) / step).round());
        for j in 0..=n(lo.1, hi.1) {
            for i in 0..=n(lo.0, hi.0) {
                out.push(Point3::new(
                    lo.0 + i as f64 * step,
                    lo.1 + j as f64 * step,
                    z,
                ));
            }
        }
    }

    #[test]
    fn a_pose_on_what_the_scan_saw_comes_before_one_over_unseen_space() {
        use crate::method::unfold::pose_at;
        // Poses at x = 0, 1, 2 in the order their fits are tried; `unseen` marks those
        // found only by leaving the legs over unseen space.
        let poses = |unseen: [bool; 3]| {
            (0..3).map(move |i| {
                let mut u = pose_at(Point3::new(i as f64, 0.0, 0.5), false, 2, 0.9);
                u.nodes[0].unseen = unseen[i];
                u
            })
        };
        let x = |u: Option<Unfolded>| u.map(|u| u.placement.position.x);
        assert_eq!(x(first_seen(poses([true, false, false]))), Some(1.0));
        assert_eq!(x(first_seen(poses([false, true, false]))), Some(0.0));
        assert_eq!(x(first_seen(poses([true, true, false]))), Some(2.0));
        assert_eq!(x(first_seen(poses([true, true, true]))), Some(0.0));
        assert_eq!(x(first_seen(std::iter::empty())), None);
    }

    #[test]
    fn a_place_found_by_setting_a_rise_aside_never_suppresses_a_plain_one() {
        let pose = |x: f64, found: usize| {
            crate::method::unfold::pose_at(Point3::new(x, 0.0, 0.5), false, found, 0.9)
        };
        // A plain seat, a place 0.2 m from it found only with its arm set aside (it finds
        // the arm: more affordances), and such a place alone 2 m away.
        let (plain, beside, alone) = (pose(0.0, 2), pose(0.2, 3), pose(2.0, 3));
        let risen_too = [(false, &plain), (true, &beside), (true, &alone)];
        let order = strongest_first(&risen_too, Selection::MostSpecific);
        assert_eq!(order, [0, 1, 2]);
        let centres = [0.0, 0.2, 2.0].map(|x| Point3::new(x, 0.0, 0.5));
        assert_eq!(suppress(&centres, &order, 0.5), [0, 2]);
        // Were the places all plain, the one beside would win the seat.
        let all_plain = [(false, &plain), (false, &beside), (false, &alone)];
        let order = strongest_first(&all_plain, Selection::MostSpecific);
        assert_eq!(suppress(&centres, &order, 0.5), [1, 2]);
    }

    /// The height map's cell at world `(x, y)`.
    fn map_at(m: &HeightMap, x: f64, y: f64) -> Option<f64> {
        let ix = crate::num::to_isize(((x - m.x0) / m.cell).floor());
        let iy = crate::num::to_isize(((y - m.y0) / m.cell).floor());
        m.get(ix, iy)
    }

    #[test]
    fn a_seat_hidden_behind_its_arm_is_filled_a_gap_to_the_floor_is_not() {
        // A sofa's seat (x 0-1.2 m, y 0-0.6 m, 0.45 m high) with its back along y = 0.6-0.7
        // and an arm along x = -0.1-0 (both 0.65-0.8 m high, solid), and the floor round
        // it; the seat's corner next to the arm (x 0-0.4, y 0.1-0.5) unseen, as from a
        // camera on the arm's side.
        let mut pts = Vec::new();
        patch((-1.0, -1.0), (2.0, -0.05), 0.0, 0.02, &mut pts);
        patch((-1.0, 0.75), (2.0, 1.5), 0.0, 0.02, &mut pts);
        for z in [0.65, 0.7, 0.75, 0.8] {
            patch((-0.1, 0.6), (1.2, 0.7), z, 0.02, &mut pts);
            patch((-0.1, 0.0), (0.0, 0.7), z, 0.02, &mut pts);
        }
        let seat_len = pts.len();
        patch((0.0, 0.0), (1.2, 0.6), 0.45, 0.02, &mut pts);
        let hidden = |p: &Point3<f64>| p.x > 0.01 && p.x < 0.4 && p.y > 0.1 && p.y < 0.5;
        let mut seen: Vec<Point3<f64>> = pts[..seat_len].to_vec();
        seen.extend(pts[seat_len..].iter().filter(|p| !hidden(p)));
        let cfg = DetectConfig::default();
        let p = prepare(&PointCloud::new(seen.clone()), &cfg);
        assert_eq!(map_at(&p.map, 0.2, 0.3), Some(0.45));
        assert!(p.scene.point_clearance(&Point3::new(0.2, 0.3, 0.47)) < 0.03);
        // Without the fill the corner is invalid and the scene free there.
        let none = DetectConfig {
            holes: HoleConfig {
                max_area: 0.0,
                ..HoleConfig::default()
            },
            ..cfg
        };
        let q = prepare(&PointCloud::new(seen.clone()), &none);
        assert_eq!(map_at(&q.map, 0.2, 0.3), None);
        assert!(q.scene.point_clearance(&Point3::new(0.2, 0.3, 0.47)) > 0.03);
        // A cut through the seat to its front edge, where the floor shows: not filled.
        seen.retain(|p| !(p.z > 0.4 && p.z < 0.5 && p.x > 0.01 && p.x < 0.4 && p.y < 0.5));
        let p = prepare(&PointCloud::new(seen), &cfg);
        assert_eq!(map_at(&p.map, 0.2, 0.3), None);
    }

    #[test]
    fn every_model_at_once_gives_each_model_alone_whatever_the_threads() {
        // Two bodies with both hierarchies: four models, the segmentation of each beside
        // the search of the next.
        let models = ModelChoice {
            heights: vec![1.65, 1.85],
            ..Default::default()
        }
        .load()
        .unwrap();
        assert_eq!(models.len(), 4);
        let cloud = PointCloud::new(crate::embed::tests::stool());
        let cfg = DetectConfig::default();
        let alone: Vec<Outcome> = models
            .iter()
            .map(|m| detect(&cloud, &m.agent, &m.hierarchy, &cfg))
            .collect();
        let found = alone.iter().filter(|o| !o.detections.is_empty()).count();
        assert!(found >= 2, "{found} models detect");
        for threads in [1, 2] {
            let all = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| detect_all(&cloud, &models, &cfg));
            assert_eq!(all, alone, "{threads} threads");
        }
    }
}
