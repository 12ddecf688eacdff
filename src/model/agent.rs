//! The agent H of the paper (section 3.1): a directed rooted tree whose nodes are joints
//! rotating about one axis and whose edges are body parts approximated by cylinders.
//!
//! Frames: the agent frame has x forward (the way the agent faces), y to its left and
//! z up; every joint angle is 0 in the upright standing pose. Lengths in the model file
//! are fractions of body height H; [`Agent::load`] scales them to metres.

use std::collections::HashSet;
use std::path::Path;

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use serde::Deserialize;

use crate::model::{parse_toml, read_text, tree_order, Key, ModelError, Source, TreeWords};

/// Most joints a body model may have: a human skeleton has a few dozen; the kinematic
/// chain is walked joint by joint on a worker thread, whose stack a chain of 100,000
/// joints overflowed.
pub const MAX_JOINTS: usize = 256;
/// Furthest a joint origin or link end may be from its joint, fraction of H: ten body
/// heights is no body, and the scene grids and drop searches grow with the body's size.
pub const MAX_REACH: f64 = 10.0;
/// Body heights a model may be scaled to, metres: from a toddler (0.3 m) to beyond the
/// tallest person recorded (2.72 m); a value outside is a typo or centimetres.
pub const HEIGHT_RANGE: std::ops::RangeInclusive<f64> = 0.3..=3.0;

/// Checks a body height (metres) against [`HEIGHT_RANGE`]; the error says why, without
/// naming where the value came from (the caller adds the flag, file or key).
pub fn check_height(height: f64) -> Result<f64, String> {
    crate::model::check_range(height, &HEIGHT_RANGE, "body height")
}

/// One joint (a vertex of H) with its optional body part (the edge to its parent's frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Joint {
    /// Name used by hierarchy files.
    pub name: String,
    /// Index of the parent joint; `None` for the root (the pelvis).
    pub parent: Option<usize>,
    /// Position of this joint in its parent's frame, metres.
    pub origin: Vector3<f64>,
    /// Rotation axis in the parent's frame (unit); a positive angle turns by the right-hand rule.
    pub axis: Unit<Vector3<f64>>,
    /// Anatomical limits `(lower, upper)`, radians; `(0, 0)` for a fixed joint.
    pub limit: (f64, f64),
    /// Whether the joint turns.
    pub kind: JointKind,
    /// The body part carried by this joint, if any.
    pub link: Option<Link>,
}

/// How a joint moves (the file's `type`, as in URDF).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// Turns about its axis within its limits (degrees in the file).
    #[default]
    Revolute,
    /// Does not turn: no axis, no limit (the root, whose placement is the body's).
    Fixed,
}

/// A body part: a cylinder between two points of its joint's frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Link {
    /// Name used by hierarchy files (for example `thigh_l`).
    pub name: String,
    /// Start of the cylinder axis in the joint frame, metres.
    pub from: Point3<f64>,
    /// End of the cylinder axis in the joint frame, metres.
    pub to: Point3<f64>,
    /// Cylinder radius, metres.
    pub radius: f64,
}

/// A body part placed in the world: a cylinder from `a` to `b` (metres, world frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cylinder {
    /// Index of the joint that carries it (also the link's index).
    pub joint: usize,
    /// Start of the axis, world frame, metres.
    pub a: Point3<f64>,
    /// End of the axis, world frame, metres.
    pub b: Point3<f64>,
    /// Radius, metres.
    pub radius: f64,
}

impl Cylinder {
    /// The part of the cylinder between fractions `s0` and `s1` of its axis (0 at `a`, 1
    /// at `b`), same radius: the part of a link a node checks (`span`, `free`).
    pub fn span(&self, [s0, s1]: [f64; 2]) -> Cylinder {
        let d = self.b - self.a;
        Cylinder {
            a: self.a + d * s0,
            b: self.a + d * s1,
            ..*self
        }
    }
}

/// The whole agent scaled to one body height, joints in topological order (parents first).
#[derive(Debug, Clone, PartialEq)]
pub struct Agent {
    /// Model name.
    pub name: String,
    /// Body height H, metres.
    pub height: f64,
    /// Joints, parents before children.
    pub joints: Vec<Joint>,
}

/// Where the agent stands: its root joint (pelvis) in the world and its heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// The root joint's position, world frame, metres.
    pub position: Point3<f64>,
    /// Heading about world z, radians; 0 faces +x.
    pub yaw: f64,
}

/// What [`Agent::forward_kinematics_cached`] keeps between calls: the placement and the
/// base frame it gave, each joint's local transform with the axis and angle (as bits) it
/// was built from, and which frames the last call rebuilt. Belongs to one agent and one
/// `frames` vector.
#[derive(Debug, Clone, Default)]
pub struct FkCache {
    /// Bits of the last placement's x, y, z (metres) and yaw (radians).
    place: Option<[u64; 4]>,
    /// The root's parent frame for that placement (world).
    base: Isometry3<f64>,
    /// Per joint: bits of axis x, y, z and angle, and the local transform (parent frame).
    locals: Vec<Option<([u64; 4], Isometry3<f64>)>>,
    /// Per joint: whether the last call rebuilt its frame.
    changed: Vec<bool>,
}

/// The state of every joint: angle (radians) and axis (unit, parent frame).
#[derive(Debug, Clone, PartialEq)]
pub struct Posture {
    /// Angle of each joint, radians, indexed like [`Agent::joints`].
    pub angles: Vec<f64>,
    /// Axis of each joint (a hierarchy node may turn a joint about another axis).
    pub axes: Vec<Unit<Vector3<f64>>>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct AgentFile {
    name: String,
    joint: Vec<JointFile>,
}

/// An agent file that changes another body (`extends`): its joints name joints of that
/// body and give only the keys that differ.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DerivedFile {
    name: String,
    extends: String,
    #[serde(default)]
    joint: Vec<JointChange>,
}

/// The keys of one joint of the extended body that a derived file changes.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointChange {
    name: String,
    #[serde(default)]
    origin: Option<[f64; 3]>,
    #[serde(default)]
    axis: Option<[f64; 3]>,
    #[serde(default)]
    limit: Option<LimitFile>,
    #[serde(default)]
    link: Option<LinkFile>,
}

/// The file's `extends`, if it has one (the text need not be a valid agent otherwise).
fn extends_of(text: &str) -> Option<String> {
    let table: toml::Table = toml::from_str(text).ok()?;
    table.get("extends")?.as_str().map(String::from)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointFile {
    name: String,
    #[serde(default)]
    parent: Option<String>,
    #[serde(rename = "type", default)]
    kind: JointKind,
    origin: [f64; 3],
    #[serde(default)]
    axis: Option<[f64; 3]>,
    #[serde(default)]
    limit: Option<LimitFile>,
    #[serde(default)]
    link: Option<LinkFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LimitFile {
    lower: f64,
    upper: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LinkFile {
    name: String,
    from: [f64; 3],
    to: [f64; 3],
    radius: f64,
}

impl Agent {
    /// Loads an agent file and scales it to body height `height` (metres).
    pub fn load(path: &Path, height: f64) -> Result<Agent, ModelError> {
        Self::from_toml(&read_text(path)?, path, height)
    }

    /// Parses agent TOML text (`path` only names the source in errors).
    pub fn from_toml(text: &str, path: &Path, height: f64) -> Result<Agent, ModelError> {
        if extends_of(text).is_some() {
            return Self::derived(text, path, height);
        }
        let file: AgentFile = parse_toml(text, path)?;
        Self::from_file(file, Source { path, text }, height)
    }

    /// An agent file with `extends = "BODY"`: the body BODY (a built-in agent's name, or a
    /// file relative to this one) with the joints this file lists changed, key by key
    /// (`origin`, `axis`, `limit`, `link`): a child is the adult's tree with other lengths,
    /// without a copy of what stays. The body extended may not itself extend another.
    /// Problems of the file's own keys name their line; problems of the body that results
    /// name the file and the key.
    fn derived(text: &str, path: &Path, height: f64) -> Result<Agent, ModelError> {
        let src = Source { path, text };
        let file: DerivedFile = parse_toml(text, path)?;
        let extends = Key::top("extends");
        let (base_path, base_text) = src.referred(
            &extends,
            &file.extends,
            crate::model::set::BUILTIN_AGENTS,
            "agents",
            "agent",
        )?;
        if extends_of(&base_text).is_some() {
            return Err(src.invalid(
                &extends,
                format!("`{}` extends another body itself", file.extends),
            ));
        }
        let mut base: AgentFile = parse_toml(&base_text, &base_path)?;
        for (i, change) in file.joint.into_iter().enumerate() {
            let Some(j) = base.joint.iter_mut().find(|j| j.name == change.name) else {
                return Err(src.invalid(
                    &Key::top("joint").item(i, &change.name).key("name"),
                    format!("`{}` has no joint `{}`", file.extends, change.name),
                ));
            };
            if let Some(o) = change.origin {
                j.origin = o;
            }
            if change.axis.is_some() {
                j.axis = change.axis;
            }
            if change.limit.is_some() {
                j.limit = change.limit;
            }
            if change.link.is_some() {
                j.link = change.link;
            }
        }
        base.name = file.name;
        // The body is checked whole; its keys are not all in this file, so no line.
        Self::from_file(base, Source { path, text: "" }, height)
    }

    fn from_file(file: AgentFile, src: Source, height: f64) -> Result<Agent, ModelError> {
        if let Err(why) = check_height(height) {
            return Err(src.invalid_outside("height", why));
        }
        if file.joint.len() > MAX_JOINTS {
            return Err(src.invalid(
                &Key::top("joint").at(MAX_JOINTS),
                format!(
                    "{} joints, more than the {MAX_JOINTS} a body model may have",
                    file.joint.len()
                ),
            ));
        }
        let key = |i: usize| Key::top("joint").item(i, &file.joint[i].name);
        let order = tree_order(
            src,
            &TreeWords {
                item: "joint",
                name_key: "name",
            },
            file.joint.len(),
            key,
            |i| &file.joint[i].name,
            |i| file.joint[i].parent.as_deref(),
        )?;
        let mut link_names = HashSet::new();
        for (i, j) in file.joint.iter().enumerate() {
            if let Some(l) = &j.link {
                if !link_names.insert(l.name.as_str()) {
                    return Err(src.invalid(
                        &key(i).key("link").key("name"),
                        format!("duplicate link name `{}`", l.name),
                    ));
                }
            }
        }
        let joints = order
            .into_iter()
            .map(|(i, parent)| Self::joint(&file.joint[i], key(i), parent, src, height))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Agent {
            name: file.name,
            height,
            joints,
        })
    }

    fn joint(
        j: &JointFile,
        key: Key,
        parent: Option<usize>,
        src: Source,
        h: f64,
    ) -> Result<Joint, ModelError> {
        let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
        let near = |v: &[f64]| v.iter().all(|x| x.abs() <= MAX_REACH);
        if !finite(&j.origin) {
            return Err(src.invalid(&key.key("origin"), "must be finite"));
        }
        if !near(&j.origin) {
            return Err(src.invalid(
                &key.key("origin"),
                format!("must be within {MAX_REACH} H of the parent joint"),
            ));
        }
        let (axis, limit) = match (j.kind, j.axis, &j.limit) {
            (JointKind::Fixed, None, None) => (Vector3::z(), (0.0, 0.0)),
            (JointKind::Fixed, _, _) => {
                let k = if j.axis.is_some() { "axis" } else { "limit" };
                return Err(src.invalid(
                    &key.key(k),
                    "a fixed joint does not turn: it takes no axis and no limit",
                ));
            }
            (JointKind::Revolute, None, _) | (JointKind::Revolute, _, None) => {
                let k = if j.axis.is_none() { "axis" } else { "limit" };
                return Err(src.invalid(
                    &key.key(k),
                    format!("a revolute joint needs `{k}` (or `type = \"fixed\"`)"),
                ));
            }
            (JointKind::Revolute, Some(a), Some(l)) => {
                let axis = Vector3::from(a);
                if !finite(&a) || axis.norm() < 1e-9 {
                    return Err(src.invalid(&key.key("axis"), "must be a non-zero vector"));
                }
                if !(l.lower.is_finite() && l.upper.is_finite()) || l.lower > l.upper {
                    return Err(src.invalid(
                        &key.key("limit"),
                        format!("lower = {} must not exceed upper = {}", l.lower, l.upper),
                    ));
                }
                (axis, (l.lower.to_radians(), l.upper.to_radians()))
            }
        };
        let link = match &j.link {
            None => None,
            Some(l) => {
                let lk = key.key("link");
                for (name, v) in [("from", &l.from), ("to", &l.to)] {
                    if !finite(v) {
                        return Err(src.invalid(&lk.key(name), "must be finite"));
                    }
                    if !near(v) {
                        return Err(src.invalid(
                            &lk.key(name),
                            format!("must be within {MAX_REACH} H of its joint"),
                        ));
                    }
                }
                let (from, to) = (Point3::from(l.from) * h, Point3::from(l.to) * h);
                if (to - from).norm() < 1e-6 {
                    return Err(src.invalid(
                        &lk.key("to"),
                        format!("link `{}` has zero length (from == to)", l.name),
                    ));
                }
                if !(l.radius.is_finite() && l.radius > 0.0 && l.radius <= MAX_REACH) {
                    return Err(src.invalid(
                        &lk.key("radius"),
                        format!(
                            "must be positive and at most {MAX_REACH} H, not {}",
                            l.radius
                        ),
                    ));
                }
                Some(Link {
                    name: l.name.clone(),
                    from,
                    to,
                    radius: l.radius * h,
                })
            }
        };
        Ok(Joint {
            name: j.name.clone(),
            parent,
            origin: Vector3::from(j.origin) * h,
            axis: Unit::new_normalize(axis),
            limit,
            kind: j.kind,
            link,
        })
    }

    /// Index of the joint named `name`.
    pub fn joint_index(&self, name: &str) -> Option<usize> {
        self.joints.iter().position(|j| j.name == name)
    }

    /// Index of the joint carrying the link named `name`.
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.joints
            .iter()
            .position(|j| j.link.as_ref().is_some_and(|l| l.name == name))
    }

    /// The upright standing posture: every angle 0, every axis as in the model.
    pub fn rest_posture(&self) -> Posture {
        Posture {
            angles: vec![0.0; self.joints.len()],
            axes: self.joints.iter().map(|j| j.axis).collect(),
        }
    }

    /// Whether joint `j` lies in the subtree of joint `root` (itself included).
    pub fn is_descendant(&self, j: usize, root: usize) -> bool {
        let mut k = Some(j);
        while let Some(i) = k {
            if i == root {
                return true;
            }
            k = self.joints[i].parent;
        }
        false
    }

    /// Forward kinematics: the world frame of every joint for a placement and posture,
    /// written into `frames` (resized to the number of joints).
    pub fn forward_kinematics(
        &self,
        place: &Placement,
        posture: &Posture,
        frames: &mut Vec<Isometry3<f64>>,
    ) {
        frames.clear();
        let base = Isometry3::from_parts(
            Translation3::from(place.position.coords),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), place.yaw),
        );
        for (i, j) in self.joints.iter().enumerate() {
            let parent = j.parent.map_or(base, |p| frames[p]);
            let local = Isometry3::from_parts(
                Translation3::from(j.origin),
                UnitQuaternion::from_axis_angle(&posture.axes[i], posture.angles[i]),
            );
            frames.push(parent * local);
        }
    }

    /// [`Self::forward_kinematics`] for a motion that changes few inputs between calls
    /// (lowering the agent changes only the placement, a sweep only a branch's angles):
    /// the same frames, bit for bit, but a joint's rotation is rebuilt only when its axis
    /// or angle changed, and its frame only when that or its parent's frame changed.
    /// `cache` holds what the previous call computed; start with `FkCache::default()`.
    pub fn forward_kinematics_cached(
        &self,
        place: &Placement,
        posture: &Posture,
        cache: &mut FkCache,
        frames: &mut Vec<Isometry3<f64>>,
    ) {
        let n = self.joints.len();
        let place_key = [
            place.position.x.to_bits(),
            place.position.y.to_bits(),
            place.position.z.to_bits(),
            place.yaw.to_bits(),
        ];
        let base_changed = cache.place != Some(place_key) || frames.len() != n;
        if base_changed {
            cache.place = Some(place_key);
            cache.base = Isometry3::from_parts(
                Translation3::from(place.position.coords),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), place.yaw),
            );
        }
        if cache.locals.len() != n || frames.len() != n {
            cache.locals = vec![None; n];
            cache.changed = vec![true; n];
            frames.clear();
            frames.resize(n, Isometry3::identity());
        }
        for (i, j) in self.joints.iter().enumerate() {
            let axis = &posture.axes[i];
            let key = [
                axis.x.to_bits(),
                axis.y.to_bits(),
                axis.z.to_bits(),
                posture.angles[i].to_bits(),
            ];
            let local_changed = match &cache.locals[i] {
                Some((k, _)) => *k != key,
                None => true,
            };
            if local_changed {
                let local = Isometry3::from_parts(
                    Translation3::from(j.origin),
                    UnitQuaternion::from_axis_angle(axis, posture.angles[i]),
                );
                cache.locals[i] = Some((key, local));
            }
            let parent_changed = j.parent.map_or(base_changed, |p| cache.changed[p]);
            let changed = local_changed || parent_changed;
            cache.changed[i] = changed;
            if changed {
                let parent = j.parent.map_or(cache.base, |p| frames[p]);
                if let Some((_, local)) = &cache.locals[i] {
                    frames[i] = parent * local;
                }
            }
        }
    }

    /// The posed body parts (world frame) of the joints selected by `which`.
    pub fn cylinders(
        &self,
        frames: &[Isometry3<f64>],
        which: impl Fn(usize) -> bool,
    ) -> Vec<Cylinder> {
        let mut out = Vec::new();
        self.cylinders_into(frames, which, &mut out);
        out
    }

    /// [`Self::cylinders`] written into `out` (cleared first), reusing its memory: for
    /// the motions that pose the parts at every step.
    pub fn cylinders_into(
        &self,
        frames: &[Isometry3<f64>],
        which: impl Fn(usize) -> bool,
        out: &mut Vec<Cylinder>,
    ) {
        out.clear();
        out.extend(
            self.joints
                .iter()
                .enumerate()
                .filter(|(i, _)| which(*i))
                .filter_map(|(i, j)| {
                    j.link.as_ref().map(|l| Cylinder {
                        joint: i,
                        a: frames[i] * l.from,
                        b: frames[i] * l.to,
                        radius: l.radius,
                    })
                }),
        );
    }

    /// Largest distance (metres) from any point of the subtree of joint `j` to that joint's
    /// origin, in any posture: bounds how far a rotation of `j` by one radian moves its parts.
    pub fn reach(&self, j: usize) -> f64 {
        fn depth(agent: &Agent, j: usize) -> f64 {
            let own = agent.joints[j].link.as_ref().map_or(0.0, |l| {
                l.from.coords.norm().max(l.to.coords.norm()) + l.radius
            });
            let kids = agent
                .joints
                .iter()
                .enumerate()
                .filter(|(_, c)| c.parent == Some(j))
                .map(|(c, cj)| cj.origin.norm() + depth(agent, c))
                .fold(0.0, f64::max);
            own.max(kids)
        }
        depth(self, j)
    }

    /// Largest distance (metres) from the origin of joint `j` to any point of the body
    /// parts `parts` that `j` moves, in any posture: `(link, span)` pairs, each link by its
    /// joint's index cut to the fractions `span` of its axis (as [`Cylinder::span`]; the
    /// radius included). Bounds how far a rotation of `j` by one radian moves those parts
    /// (each is at most the chain of joint offsets from `j` down to its link, plus the
    /// farther end of its span); parts `j` does not move count nothing. At most
    /// [`Self::reach`]`(j)`.
    pub fn reach_to(&self, j: usize, parts: &[(usize, [f64; 2])]) -> f64 {
        parts
            .iter()
            .filter(|(l, _)| self.is_descendant(*l, j))
            .map(|&(l, [s0, s1])| {
                let own = self.joints[l].link.as_ref().map_or(0.0, |k| {
                    let at = |s: f64| (k.from.coords + (k.to.coords - k.from.coords) * s).norm();
                    at(s0).max(at(s1)) + k.radius
                });
                let mut chain = 0.0;
                let mut k = l;
                while k != j {
                    chain += self.joints[k].origin.norm();
                    match self.joints[k].parent {
                        Some(p) => k = p,
                        None => break,
                    }
                }
                chain + own
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::line_of;

    const TWO_LINKS: &str = r#"
name = "leg"
[[joint]]
name = "hip"
origin = [0.0, 0.0, 0.5]
axis = [0.0, -1.0, 0.0]
limit = { lower = -30.0, upper = 120.0 }
link = { name = "thigh", from = [0.0, 0.0, 0.0], to = [0.0, 0.0, -0.25], radius = 0.04 }
[[joint]]
name = "knee"
parent = "hip"
origin = [0.0, 0.0, -0.25]
axis = [0.0, 1.0, 0.0]
limit = { lower = 0.0, upper = 150.0 }
link = { name = "shank", from = [0.0, 0.0, 0.0], to = [0.0, 0.0, -0.25], radius = 0.03 }
"#;

    fn leg(h: f64) -> Agent {
        Agent::from_toml(TWO_LINKS, Path::new("leg.toml"), h).unwrap()
    }

    /// The built-in agent `name`'s text.
    fn builtin(name: &str) -> &'static str {
        crate::model::set::BUILTIN_AGENTS
            .iter()
            .find(|(n, _)| *n == name)
            .unwrap()
            .1
    }

    #[test]
    fn a_derived_body_is_the_extended_one_with_the_listed_keys_changed() {
        let adult = Agent::from_toml(builtin("human"), Path::new("human.toml"), 1.0).unwrap();
        let child = Agent::from_toml(builtin("child"), Path::new("child.toml"), 1.0).unwrap();
        assert_eq!(child.name, "child");
        assert_eq!(child.joints.len(), adult.joints.len());
        let forearm = |a: &Agent| {
            let j = &a.joints[a.joint_index("elbow_l").unwrap()];
            let l = j.link.as_ref().unwrap();
            (l.to - l.from).norm()
        };
        assert!((forearm(&child) - 0.140).abs() < 1e-12);
        assert!((forearm(&adult) - 0.146).abs() < 1e-12);
        // What the child file leaves out is the adult's: names, parents, axes, limits, the
        // feet and the pelvis.
        for (c, a) in child.joints.iter().zip(&adult.joints) {
            assert_eq!(
                (&c.name, c.parent, c.axis, c.kind),
                (&a.name, a.parent, a.axis, a.kind)
            );
            assert_eq!(c.limit, a.limit, "{}", c.name);
        }
        for name in ["pelvis", "ankle_l", "ankle_r"] {
            let (c, a) = (
                child.joint_index(name).unwrap(),
                adult.joint_index(name).unwrap(),
            );
            assert_eq!(child.joints[c].link, adult.joints[a].link, "{name}");
        }
    }

    #[test]
    fn a_derived_body_may_extend_a_file_beside_it() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("leg.toml"), TWO_LINKS).unwrap();
        let long = "name = \"long leg\"\nextends = \"leg.toml\"\n[[joint]]\nname = \"knee\"\n\
                    origin = [0.0, 0.0, -0.30]\n";
        let path = dir.path().join("long.toml");
        let a = Agent::from_toml(long, &path, 1.0).unwrap();
        assert_eq!(a.name, "long leg");
        assert_eq!(a.joints[1].origin, Vector3::new(0.0, 0.0, -0.30));
        assert_eq!(a.joints[1].link, leg(1.0).joints[1].link);
        // A body that is not there, a joint the body does not have, a key a change may not
        // touch, a chain of extensions: one line each, naming file, line and key.
        let err = |text: &str| Agent::from_toml(text, &path, 1.0).unwrap_err().to_string();
        let missing = long.replace("leg.toml", "nowhere.toml");
        let e = err(&missing);
        assert!(
            e.contains("long.toml:2: extends: `nowhere.toml` is neither"),
            "{e}"
        );
        let ankle = long.replace("name = \"knee\"", "name = \"ankle\"");
        let e = err(&ankle);
        assert!(
            e.contains("long.toml:4: joint.ankle.name: `leg.toml` has no joint `ankle`"),
            "{e}"
        );
        let parent = format!("{long}parent = \"hip\"\n");
        let e = err(&parent);
        assert!(e.contains("long.toml:6") && e.contains("parent"), "{e}");
        std::fs::write(dir.path().join("long.toml"), long).unwrap();
        let longer = long
            .replace("leg.toml", "long.toml")
            .replace("long leg", "longer");
        let e = Agent::from_toml(&longer, &dir.path().join("longer.toml"), 1.0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("extends another body itself"), "{e}");
        // The body that results is checked whole: a limit the initial pose breaks is named
        // by file and key.
        let bad = format!("{long}limit = {{ lower = 10.0, upper = -10.0 }}\n");
        let e = err(&bad);
        assert!(
            e.starts_with(&format!("{}: joint.knee", path.display())),
            "{e}"
        );
    }

    #[test]
    fn scales_lengths_by_height() {
        let a = leg(2.0);
        assert_eq!(a.joints[1].origin, Vector3::new(0.0, 0.0, -0.5));
        assert!((a.joints[0].link.as_ref().unwrap().radius - 0.08).abs() < 1e-12);
    }

    #[test]
    fn cached_forward_kinematics_equals_the_full_one_bit_for_bit() {
        let a = Agent::from_toml(builtin("human"), Path::new("human.toml"), 1.75).unwrap();
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut posture = a.rest_posture();
        let mut place = Placement {
            position: Point3::new(1.0, -2.0, 0.5),
            yaw: 0.3,
        };
        let (mut cache, mut cached, mut full) = (FkCache::default(), Vec::new(), Vec::new());
        for step in 0..400 {
            // Now the placement moves, now one joint turns, now a joint's axis changes,
            // now nothing changes: the motions the fit and the sweeps make.
            match step % 4 {
                0 => place.position.z -= rnd() * 0.01,
                1 => {
                    let j = crate::num::to_usize(rnd() * a.joints.len() as f64) % a.joints.len();
                    posture.angles[j] = rnd() * 3.0 - 1.5;
                }
                2 if rnd() < 0.3 => {
                    let j = crate::num::to_usize(rnd() * a.joints.len() as f64) % a.joints.len();
                    posture.axes[j] = Unit::new_normalize(Vector3::new(rnd(), rnd(), 0.5));
                }
                _ if rnd() < 0.2 => place.yaw = rnd() * 6.0,
                _ => {}
            }
            a.forward_kinematics(&place, &posture, &mut full);
            a.forward_kinematics_cached(&place, &posture, &mut cache, &mut cached);
            assert_eq!(cached.len(), full.len());
            for (c, f) in cached.iter().zip(&full) {
                let bits = |m: &Isometry3<f64>| m.to_homogeneous().map(f64::to_bits);
                assert_eq!(bits(c), bits(f), "step {step}");
            }
        }
    }

    #[test]
    fn forward_kinematics_of_a_seated_leg() {
        // H = 2 m: hip at z = 1.0; thigh 0.5 m, shank 0.5 m. Hip flexed 90 deg about -y
        // puts the thigh forward (+x); knee flexed 90 deg about +y brings the shank down.
        let a = leg(2.0);
        let mut p = a.rest_posture();
        p.angles = vec![90f64.to_radians(), 90f64.to_radians()];
        let mut f = Vec::new();
        let place = Placement {
            position: Point3::new(1.0, 2.0, 0.0),
            yaw: 0.0,
        };
        a.forward_kinematics(&place, &p, &mut f);
        let c = a.cylinders(&f, |_| true);
        assert!(
            (c[0].b - Point3::new(1.5, 2.0, 1.0)).norm() < 1e-9,
            "knee at {:?}",
            c[0].b
        );
        assert!(
            (c[1].b - Point3::new(1.5, 2.0, 0.5)).norm() < 1e-9,
            "ankle at {:?}",
            c[1].b
        );
        // Turning the agent by 90 deg about z makes it face +y.
        let place = Placement {
            yaw: 90f64.to_radians(),
            ..place
        };
        a.forward_kinematics(&place, &p, &mut f);
        let c = a.cylinders(&f, |_| true);
        assert!(
            (c[0].b - Point3::new(1.0, 2.5, 1.0)).norm() < 1e-9,
            "knee at {:?}",
            c[0].b
        );
    }

    #[test]
    fn reach_bounds_the_subtree() {
        let a = leg(1.0);
        // From the hip: 0.25 to the knee + 0.25 shank + 0.03 radius.
        assert!((a.reach(0) - 0.53).abs() < 1e-9);
        assert!((a.reach(1) - 0.28).abs() < 1e-9);
        // Every part whole: the whole subtree's reach.
        let whole = [(0, [0.0, 1.0]), (1, [0.0, 1.0])];
        assert!((a.reach_to(0, &whole) - a.reach(0)).abs() < 1e-9);
        assert!((a.reach_to(1, &whole) - a.reach(1)).abs() < 1e-9);
        // The near half of the shank: the thigh's joint offset, half the shank, its
        // radius; the thigh alone is not moved by the knee.
        assert!((a.reach_to(0, &[(1, [0.0, 0.5])]) - (0.25 + 0.125 + 0.03)).abs() < 1e-9);
        assert!(a.reach_to(1, &[(0, [0.0, 1.0])]) == 0.0);
    }

    #[test]
    fn a_turn_moves_the_parts_no_further_than_their_reach() {
        // In postures drawn across the limits, turning one joint by a small angle moves
        // the span ends of the parts it carries no further than `reach_to` times the
        // angle: the armrest's forearm span from the shoulder, a leg from the hip, the
        // head from the lumbar joint.
        let a = Agent::from_toml(builtin("human"), Path::new("human.toml"), 1.75).unwrap();
        let ix = |n: &str| a.joint_index(n).unwrap();
        let cases = [
            ("shoulder_l", vec![("forearm_l", [0.0, 0.6])]),
            (
                "hip_r",
                vec![
                    ("thigh_r", [0.0, 1.0]),
                    ("shank_r", [0.0, 1.0]),
                    ("foot_r", [0.0, 1.0]),
                ],
            ),
            ("lumbar", vec![("head", [0.3, 1.0])]),
        ];
        let place = Placement {
            position: Point3::new(0.3, -0.2, 0.5),
            yaw: 0.7,
        };
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut f0, mut f1) = (Vec::new(), Vec::new());
        for (joint, links) in &cases {
            let j = ix(joint);
            let parts: Vec<(usize, [f64; 2])> = links
                .iter()
                .map(|(l, s)| (a.link_index(l).unwrap(), *s))
                .collect();
            let reach = a.reach_to(j, &parts);
            assert!(
                reach > 0.0 && reach <= a.reach(j) + 1e-12,
                "{joint}: {reach}"
            );
            for _ in 0..200 {
                let mut p = a.rest_posture();
                for (k, jt) in a.joints.iter().enumerate() {
                    p.angles[k] = jt.limit.0 + rng.random::<f64>() * (jt.limit.1 - jt.limit.0);
                }
                let turn = 1e-3;
                let mut q = p.clone();
                q.angles[j] += turn;
                a.forward_kinematics(&place, &p, &mut f0);
                a.forward_kinematics(&place, &q, &mut f1);
                let tested = |l: usize| parts.iter().any(|&(t, _)| t == l);
                let (c0, c1) = (a.cylinders(&f0, tested), a.cylinders(&f1, tested));
                for (x, y) in c0.iter().zip(&c1) {
                    let span = parts.iter().find(|&&(t, _)| t == x.joint).unwrap().1;
                    let (x, y) = (x.span(span), y.span(span));
                    for moved in [(y.a - x.a).norm(), (y.b - x.b).norm()] {
                        assert!(moved <= reach * turn * (1.0 + 1e-6), "{joint}: {moved}");
                    }
                }
            }
        }
    }

    /// The error loading `text` as `x.toml`.
    fn error(text: &str) -> String {
        Agent::from_toml(text, Path::new("x.toml"), 1.75)
            .unwrap_err()
            .to_string()
    }

    /// Asserts that `e` starts with `x.toml:LINE: KEY: ` and mentions `what`.
    fn names(e: &str, line: usize, key: &str, what: &str) {
        assert!(
            e.starts_with(&format!("x.toml:{line}: {key}: ")) && e.contains(what),
            "{e}"
        );
    }

    #[test]
    fn an_unknown_parent_is_named() {
        let bad = TWO_LINKS.replace("parent = \"hip\"", "parent = \"hips\"");
        let line = line_of(&bad, "parent = \"hips\"", 0);
        names(
            &error(&bad),
            line,
            "joint.knee.parent",
            "depends on a missing joint `hips`",
        );
    }

    #[test]
    fn a_cycle_of_joints_is_named() {
        let bad = format!(
            "{TWO_LINKS}{}",
            r#"
[[joint]]
name = "toe"
parent = "heel"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
limit = { lower = 0.0, upper = 10.0 }
[[joint]]
name = "heel"
parent = "toe"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
limit = { lower = 0.0, upper = 10.0 }
"#
        );
        let line = line_of(&bad, "parent = \"heel\"", 0);
        names(&error(&bad), line, "joint.toe.parent", "cycle");
        assert!(error(&bad).contains("toe -> heel -> toe"));
    }

    #[test]
    fn a_zero_length_link_is_named() {
        let bad = TWO_LINKS.replace(
            "to = [0.0, 0.0, -0.25], radius = 0.03",
            "to = [0.0, 0.0, 0.0], radius = 0.03",
        );
        let line = line_of(&bad, "name = \"shank\"", 0);
        names(
            &error(&bad),
            line,
            "joint.knee.link.to",
            "`shank` has zero length",
        );
    }

    #[test]
    fn a_non_positive_radius_is_named() {
        for radius in ["0.0", "-0.03", "nan"] {
            let bad = TWO_LINKS.replace("radius = 0.03", &format!("radius = {radius}"));
            let line = line_of(&bad, "name = \"shank\"", 0);
            names(
                &error(&bad),
                line,
                "joint.knee.link.radius",
                "must be positive",
            );
        }
    }

    #[test]
    fn duplicate_names_are_named_where_repeated() {
        let bad = TWO_LINKS.replace("name = \"knee\"", "name = \"hip\"");
        let line = line_of(&bad, "name = \"hip\"", 1);
        names(
            &error(&bad),
            line,
            "joint.hip.name",
            "duplicate joint name `hip`",
        );
        let bad = TWO_LINKS.replace("name = \"shank\"", "name = \"thigh\"");
        let line = line_of(&bad, "name = \"thigh\"", 1);
        names(
            &error(&bad),
            line,
            "joint.knee.link.name",
            "duplicate link name `thigh`",
        );
    }

    #[test]
    fn a_second_root_is_named() {
        let bad = TWO_LINKS.replace("parent = \"hip\"\n", "");
        let line = line_of(&bad, "name = \"knee\"", 0);
        names(&error(&bad), line, "joint.knee.name", "root (`hip`)");
    }

    #[test]
    fn impossible_axes_and_limits_are_named() {
        let bad = TWO_LINKS.replace("axis = [0.0, 1.0, 0.0]", "axis = [0.0, 0.0, 0.0]");
        let line = line_of(&bad, "axis = [0.0, 0.0, 0.0]", 0);
        names(&error(&bad), line, "joint.knee.axis", "non-zero");
        let bad = TWO_LINKS.replace("lower = 0.0, upper = 150.0", "lower = 150.0, upper = 0.0");
        let line = line_of(&bad, "lower = 150.0", 0);
        names(&error(&bad), line, "joint.knee.limit", "must not exceed");
    }

    #[test]
    fn an_unknown_key_is_named_with_its_line() {
        let bad = TWO_LINKS.replace(
            "axis = [0.0, 1.0, 0.0]",
            "axis = [0.0, 1.0, 0.0]\ncolour = 3",
        );
        let line = line_of(&bad, "colour", 0);
        names(
            &error(&bad),
            line,
            "joint.knee.colour",
            "unknown field `colour`",
        );
    }

    #[test]
    fn a_fixed_joint_takes_no_axis_or_limit_and_a_revolute_one_needs_both() {
        let fixed = TWO_LINKS.replacen(
            "axis = [0.0, -1.0, 0.0]\nlimit = { lower = -30.0, upper = 120.0 }",
            "type = \"fixed\"",
            1,
        );
        let a = Agent::from_toml(&fixed, Path::new("x.toml"), 1.75).unwrap();
        assert_eq!(a.joints[0].kind, JointKind::Fixed);
        assert_eq!(a.joints[0].limit, (0.0, 0.0));
        assert_eq!(a.joints[1].kind, JointKind::Revolute);
        // A fixed joint with a limit: named.
        let bad = TWO_LINKS.replacen("axis = [0.0, -1.0, 0.0]\n", "type = \"fixed\"\n", 1);
        names(
            &error(&bad),
            7,
            "joint.hip.limit",
            "a fixed joint does not turn",
        );
        // A revolute joint without a limit: named.
        let bad = TWO_LINKS.replacen("limit = { lower = 0.0, upper = 150.0 }\n", "", 1);
        let e = error(&bad);
        assert!(
            e.contains(": joint.knee.limit: a revolute joint needs `limit`"),
            "{e}"
        );
    }

    #[test]
    fn a_height_out_of_range_names_no_line() {
        let e = Agent::from_toml(TWO_LINKS, Path::new("x.toml"), 17.5)
            .unwrap_err()
            .to_string();
        assert_eq!(e, "x.toml: height: body height 17.5 m is outside 0.3-3.0 m");
    }
}
