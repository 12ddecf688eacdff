//! The affordance hierarchy A of section 3.2: an initial pose H_A and a rooted tree of
//! fine-grained affordances F = (J_F, E_F), each edge carrying a true/false constraint,
//! plus the hypothesis rule (section 4.1) and the fitting and scoring parameters
//! (sections 4.2-4.4) that the paper leaves free.
//!
//! Angles in the file are degrees; lengths are metres unless the key says "fraction of H".

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use nalgebra::{Unit, Vector3};
use serde::Deserialize;

use crate::agent::{Agent, Posture};
use crate::fuzzy::{Availability, Low, Trapezoid};
use crate::model::{invalid, parse_toml, read_toml, ModelError};

/// How the agent's heading relates to the height-gradient descent (section 4.1).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Facing along the descent (sitting).
    Parallel,
    /// Lying across it (lying).
    Orthogonal,
}

/// The hypothesis rule of section 4.1 (Fig. 5).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HypothesisRule {
    /// Diameter of the circular torso template, fraction of H.
    pub template_diameter: f64,
    /// Radius of the neighbourhood whose plane fit gives the height gradient, fraction of H.
    pub gradient_radius: f64,
    /// Slope (m/m) below which the gradient gives no heading and every heading is tried.
    pub flat_gradient: f64,
    /// "Discontinuity is low": share of invalid cells under the template.
    pub discontinuity: Low,
    /// "Roughness is low": standard deviation of heights under the template, metres.
    pub roughness: Low,
    /// "Height is comfortable": mean height under the template, fractions of H;
    /// absent to switch the height membership off.
    #[serde(default)]
    pub height: Option<Trapezoid>,
    /// The availability sets used for defuzzification (Fig. 5d).
    pub available: Availability,
}

/// Parameters of the initial agent fitting (section 4.2).
#[derive(Debug, Clone, PartialEq)]
pub struct FitRule {
    /// Headings tried around the hypothesis heading, radians.
    pub yaw_offsets: Vec<f64>,
    /// Step of the all-round heading search used when no offset heading is free, radians.
    pub fallback_yaw_step: f64,
    /// Height of the pelvis bottom above the highest cell under the template at the start, metres.
    pub start_clearance: f64,
    /// Furthest the agent is lowered below the hypothesis height before it is given up, metres.
    pub max_drop: f64,
    /// sigma_d of Eq. 1, metres.
    pub sigma_d: f64,
    /// Stability (Eq. 1) below which a fit is discarded.
    pub min_stability: f64,
    /// Stabilities within this much of the best count as equal when the orientation is chosen.
    pub stability_band: f64,
    /// Spacing of the samples along each stability link (Eq. 1), metres.
    pub sample_spacing: f64,
    /// Links whose distances to the scene make the stability score (joint indices).
    pub stability_links: Vec<usize>,
    /// Links left out of the collision tests of the fitting, because a node unfolds them
    /// afterwards (joint indices).
    pub unchecked_links: Vec<usize>,
}

/// How the best pose of a hypothesis, and the strongest of neighbouring detections, are chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// By the accumulated score of Eq. 5 alone (the paper).
    Score,
    /// By the number of fine-grained affordances found, then by the score: Eq. 5 saturates
    /// near 1 once two nodes score well, so a further affordance barely moves it.
    MostSpecific,
}

/// Parameters of the scores (Eq. 3-5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScoreRule {
    /// sigma_theta of Eq. 3, radians.
    pub sigma_theta: f64,
    /// epsilon of Eq. 3: the local score of a link without contact.
    pub epsilon: f64,
    /// Cosine of the largest angle between a contact's normal and a node's `release`
    /// direction for the contact to count as support.
    pub support_cos: f64,
    /// How poses and detections are ranked.
    pub select: Selection,
    /// Local score (Eq. 3-4) below which a contact does not count as the affordance.
    pub min_local: f64,
}

/// One joint constraint (theta1, theta2, theta_d, axis, joint) of J_F.
#[derive(Debug, Clone, PartialEq)]
pub struct Sweep {
    /// Joint index in the agent.
    pub joint: usize,
    /// Start angle, radians.
    pub theta1: f64,
    /// End angle, radians (theta1 <= theta2).
    pub theta2: f64,
    /// Default (preferred) angle, radians.
    pub thetad: f64,
    /// Axis of the rotation (parent frame, unit).
    pub axis: Unit<Vector3<f64>>,
}

/// A fine-grained affordance F = (J_F, E_F) and its edge to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Node {
    /// Affordance id (`sitting`, `backrest`, ...).
    pub id: String,
    /// Index of the parent node; `None` for the root.
    pub parent: Option<usize>,
    /// Constraint c on the edge from the parent: processed when the parent's contact state equals it.
    pub when: bool,
    /// E_F: the links (joint indices) checked for contact.
    pub links: Vec<usize>,
    /// For each link of `links`, the part checked, as fractions `[from, to]` of its length
    /// (an armrest carries the forearm near the elbow, not at the wrist).
    pub spans: Vec<[f64; 2]>,
    /// J_F: the joints swept.
    pub sweeps: Vec<Sweep>,
    /// Joints held at each of several angles in turn while J_F is swept (an extension of
    /// the paper: the arm looks for an armrest at several abductions); each kinematic
    /// branch keeps the setting that scores best.
    pub spreads: Vec<Spread>,
    /// Joints held within a range while this node is judged (an extension of the paper:
    /// a headrest is judged at a plausible trunk recline); kept when the node is found.
    pub clamps: Vec<Clamp>,
    /// When set, a contact counts only if the scene holds the touching links from the side
    /// opposite this direction (agent frame: x forward, z up): `[0, 0, 1]` means "from
    /// below", so an armrest counts and a wall beside the arm does not.
    pub release: Option<nalgebra::Vector3<f64>>,
    /// Whether a contact already at theta1 is refused: the links had no room to unfold
    /// (shanks that start in a mattress are not hanging from a seat).
    pub free_start: bool,
    /// Whether one touching kinematic branch suffices for the affordance, or all must touch.
    pub contact: ContactRule,
    /// Parts that must rest on the scene at a contact (an extension of the paper: lying
    /// needs the back of the head and the heels supported, not only the trunk): at the
    /// contact, some part of each branch's support links (joint index, span) must have the
    /// scene within `support_gap` straight below it. Empty: any contact counts.
    pub support: Vec<(usize, [f64; 2])>,
    /// See `support`, metres.
    pub support_gap: f64,
}

/// How many of a node's kinematic branches must touch for its affordance to be found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactRule {
    /// One branch (the paper: "either a collision occurred or not"); one armrest suffices.
    #[default]
    Any,
    /// Every branch (an extension: lying needs the head and both heels supported).
    All,
}

/// A joint held within `[lower, upper]` (radians) while a node is judged.
#[derive(Debug, Clone, PartialEq)]
pub struct Clamp {
    /// Joint index in the agent.
    pub joint: usize,
    /// Lowest angle, radians.
    pub lower: f64,
    /// Highest angle, radians.
    pub upper: f64,
}

/// A joint tried at several fixed angles (radians) during a node's sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct Spread {
    /// Joint index in the agent.
    pub joint: usize,
    /// Angles tried, radians, in order (the first is kept when nothing is touched).
    pub angles: Vec<f64>,
}

/// A whole affordance hierarchy resolved against an agent.
#[derive(Debug, Clone, PartialEq)]
pub struct Hierarchy {
    /// Name of the coarse affordance (`sitting`).
    pub name: String,
    /// Heading relative to the gradient descent.
    pub orientation: Orientation,
    /// Section 4.1.
    pub hypothesis: HypothesisRule,
    /// Section 4.2.
    pub fit: FitRule,
    /// Section 4.4.
    pub score: ScoreRule,
    /// Radius within which weaker detections are suppressed (section 4.5), fraction of H.
    pub suppression_radius: f64,
    /// H_A: the initial pose.
    pub initial: Posture,
    /// Nodes, parents before children; node 0 is the root.
    pub nodes: Vec<Node>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    name: String,
    orientation: Orientation,
    suppression_radius: f64,
    hypothesis: HypothesisRule,
    fit: FitFile,
    score: ScoreFile,
    initial_pose: BTreeMap<String, f64>,
    node: Vec<NodeFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FitFile {
    yaw_offsets: Vec<f64>,
    fallback_yaw_step: f64,
    start_clearance: f64,
    max_drop: f64,
    sigma_d: f64,
    min_stability: f64,
    stability_band: f64,
    sample_spacing: f64,
    stability_links: Vec<String>,
    #[serde(default)]
    unchecked_links: Vec<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ScoreFile {
    sigma_theta: f64,
    epsilon: f64,
    support_angle: f64,
    select: Selection,
    min_local: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct NodeFile {
    id: String,
    #[serde(default)]
    parent: Option<String>,
    #[serde(default = "yes")]
    when: bool,
    links: Vec<LinkRef>,
    sweep: Vec<SweepFile>,
    #[serde(default)]
    spread: Vec<SpreadFile>,
    #[serde(default)]
    clamp: Vec<ClampFile>,
    #[serde(default)]
    release: Option<[f64; 3]>,
    #[serde(default)]
    free_start: bool,
    #[serde(default)]
    contact: ContactRule,
    #[serde(default)]
    support: Vec<LinkRef>,
    #[serde(default)]
    support_gap: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ClampFile {
    joint: String,
    lower: f64,
    upper: f64,
}

/// A link of E_F: its name, or its name and the span checked.
#[derive(Deserialize)]
#[serde(untagged)]
enum LinkRef {
    Name(String),
    Span { link: String, span: [f64; 2] },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SpreadFile {
    joint: String,
    angles: Vec<f64>,
}

fn yes() -> bool {
    true
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SweepFile {
    joint: String,
    theta1: f64,
    theta2: f64,
    thetad: f64,
    #[serde(default)]
    axis: Option<[f64; 3]>,
}

impl Hierarchy {
    /// Loads a hierarchy file and resolves its joint and link names against `agent`.
    pub fn load(path: &Path, agent: &Agent) -> Result<Hierarchy, ModelError> {
        let file: File = read_toml(path)?;
        Self::resolve(file, path, agent)
    }

    /// Parses hierarchy TOML text (`path` only names the source in errors).
    pub fn from_toml(text: &str, path: &Path, agent: &Agent) -> Result<Hierarchy, ModelError> {
        let file: File = parse_toml(text, path)?;
        Self::resolve(file, path, agent)
    }

    fn resolve(file: File, path: &Path, agent: &Agent) -> Result<Hierarchy, ModelError> {
        let link = |key: String, name: &str| {
            agent.link_index(name).ok_or_else(|| {
                invalid(
                    path,
                    key,
                    format!("unknown link `{name}` (not in agent `{}`)", agent.name),
                )
            })
        };
        let joint = |key: String, name: &str| {
            agent.joint_index(name).ok_or_else(|| {
                invalid(
                    path,
                    key,
                    format!("unknown joint `{name}` (not in agent `{}`)", agent.name),
                )
            })
        };
        let h = &file.hypothesis;
        for (key, v) in [
            ("hypothesis.template_diameter", h.template_diameter),
            ("hypothesis.gradient_radius", h.gradient_radius),
            ("suppression_radius", file.suppression_radius),
            ("fit.sigma_d", file.fit.sigma_d),
            ("fit.sample_spacing", file.fit.sample_spacing),
            ("fit.fallback_yaw_step", file.fit.fallback_yaw_step),
            ("score.sigma_theta", file.score.sigma_theta),
            ("score.epsilon", file.score.epsilon),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(invalid(path, key, "must be positive"));
            }
        }
        let mut initial = agent.rest_posture();
        for (name, deg) in &file.initial_pose {
            let j = joint(format!("initial_pose.{name}"), name)?;
            initial.angles[j] = deg.to_radians();
        }
        let stability_links = file
            .fit
            .stability_links
            .iter()
            .map(|n| link("fit.stability_links".into(), n))
            .collect::<Result<Vec<_>, _>>()?;
        let unchecked_links = file
            .fit
            .unchecked_links
            .iter()
            .map(|n| link("fit.unchecked_links".into(), n))
            .collect::<Result<Vec<_>, _>>()?;
        // Nodes: resolve parents, then order parents before children.
        let ids: HashMap<&str, usize> = file
            .node
            .iter()
            .enumerate()
            .map(|(i, n)| (n.id.as_str(), i))
            .collect();
        if ids.len() != file.node.len() {
            return Err(invalid(path, "node.id", "duplicate node id"));
        }
        let roots: Vec<&NodeFile> = file.node.iter().filter(|n| n.parent.is_none()).collect();
        if roots.len() != 1 {
            return Err(invalid(
                path,
                "node",
                "exactly one node must have no parent (the root)",
            ));
        }
        for n in &file.node {
            if let Some(p) = &n.parent {
                if !ids.contains_key(p.as_str()) {
                    return Err(invalid(
                        path,
                        format!("node.{}.parent", n.id),
                        format!("depends on a missing node `{p}`"),
                    ));
                }
            }
        }
        let mut order: Vec<usize> = Vec::new();
        let mut placed = vec![false; file.node.len()];
        loop {
            let before = order.len();
            for (i, n) in file.node.iter().enumerate() {
                let ready = n.parent.as_ref().is_none_or(|p| placed[ids[p.as_str()]]);
                if !placed[i] && ready {
                    placed[i] = true;
                    order.push(i);
                }
            }
            if order.len() == file.node.len() {
                break;
            }
            if order.len() == before {
                let stuck = placed.iter().position(|p| !p).unwrap_or(0);
                return Err(invalid(
                    path,
                    format!("node.{}.parent", file.node[stuck].id),
                    "the nodes form a cycle",
                ));
            }
        }
        let new_index: HashMap<usize, usize> = order
            .iter()
            .enumerate()
            .map(|(new, &old)| (old, new))
            .collect();
        let mut nodes = Vec::with_capacity(order.len());
        for &i in &order {
            let n = &file.node[i];
            let key = |k: &str| format!("node.{}.{k}", n.id);
            let spanned = |field: &str, refs: &[LinkRef]| {
                let mut out = Vec::new();
                for l in refs {
                    let (name, span) = match l {
                        LinkRef::Name(name) => (name, [0.0, 1.0]),
                        LinkRef::Span { link, span } => (link, *span),
                    };
                    if !(0.0..=1.0).contains(&span[0])
                        || !(0.0..=1.0).contains(&span[1])
                        || span[0] >= span[1]
                    {
                        return Err(invalid(
                            path,
                            key(&format!("{field}.{name}.span")),
                            "needs 0 <= from < to <= 1",
                        ));
                    }
                    out.push((link(key(field), name)?, span));
                }
                Ok(out)
            };
            let (links, spans): (Vec<usize>, Vec<[f64; 2]>) =
                spanned("links", &n.links)?.into_iter().unzip();
            let support = spanned("support", &n.support)?;
            if !(n.support_gap.is_finite() && n.support_gap >= 0.0) {
                return Err(invalid(
                    path,
                    key("support_gap"),
                    "must be 0 or more metres",
                ));
            }
            if links.is_empty() {
                return Err(invalid(
                    path,
                    key("links"),
                    "a node needs at least one link to check",
                ));
            }
            let mut sweeps = Vec::new();
            for s in &n.sweep {
                let j = joint(key("sweep.joint"), &s.joint)?;
                if !(s.theta1.is_finite() && s.theta2.is_finite() && s.thetad.is_finite()) {
                    return Err(invalid(path, key("sweep"), "angles must be finite"));
                }
                if s.theta1 > s.theta2 {
                    return Err(invalid(
                        path,
                        key(&format!("sweep.{}.theta1", s.joint)),
                        format!("theta1 = {} exceeds theta2 = {}", s.theta1, s.theta2),
                    ));
                }
                let axis = match s.axis {
                    None => agent.joints[j].axis,
                    Some(a) => {
                        let v = Vector3::from(a);
                        if v.norm().is_nan() || v.norm() <= 1e-9 {
                            return Err(invalid(
                                path,
                                key(&format!("sweep.{}.axis", s.joint)),
                                "must be a non-zero vector",
                            ));
                        }
                        Unit::new_normalize(v)
                    }
                };
                sweeps.push(Sweep {
                    joint: j,
                    theta1: s.theta1.to_radians(),
                    theta2: s.theta2.to_radians(),
                    thetad: s.thetad.to_radians(),
                    axis,
                });
            }
            if sweeps.is_empty() {
                return Err(invalid(
                    path,
                    key("sweep"),
                    "a node needs at least one joint sweep",
                ));
            }
            let mut spreads = Vec::new();
            for sp in &n.spread {
                let j = joint(key("spread.joint"), &sp.joint)?;
                if sp.angles.is_empty() || sp.angles.iter().any(|a| !a.is_finite()) {
                    return Err(invalid(
                        path,
                        key(&format!("spread.{}.angles", sp.joint)),
                        "needs finite angles",
                    ));
                }
                if sweeps.iter().any(|s| s.joint == j) {
                    return Err(invalid(
                        path,
                        key(&format!("spread.{}", sp.joint)),
                        "a joint cannot be both swept and spread",
                    ));
                }
                spreads.push(Spread {
                    joint: j,
                    angles: sp.angles.iter().map(|a| a.to_radians()).collect(),
                });
            }
            let mut clamps = Vec::new();
            for c in &n.clamp {
                let j = joint(key("clamp.joint"), &c.joint)?;
                if !(c.lower.is_finite() && c.upper.is_finite()) || c.lower > c.upper {
                    return Err(invalid(
                        path,
                        key(&format!("clamp.{}", c.joint)),
                        "lower must not exceed upper",
                    ));
                }
                clamps.push(Clamp {
                    joint: j,
                    lower: c.lower.to_radians(),
                    upper: c.upper.to_radians(),
                });
            }
            nodes.push(Node {
                id: n.id.clone(),
                parent: n.parent.as_ref().map(|p| new_index[&ids[p.as_str()]]),
                when: n.when,
                links,
                spans,
                sweeps,
                spreads,
                clamps,
                release: match n.release.map(Vector3::from) {
                    Some(r) if r.norm().is_nan() || r.norm() <= 1e-9 => {
                        return Err(invalid(
                            path,
                            key("release"),
                            "must be a non-zero direction",
                        ))
                    }
                    r => r,
                },
                free_start: n.free_start,
                contact: n.contact,
                support,
                support_gap: n.support_gap,
            });
        }
        let f = &file.fit;
        Ok(Hierarchy {
            name: file.name,
            orientation: file.orientation,
            hypothesis: file.hypothesis,
            fit: FitRule {
                yaw_offsets: f.yaw_offsets.iter().map(|d| d.to_radians()).collect(),
                fallback_yaw_step: f.fallback_yaw_step.to_radians(),
                start_clearance: f.start_clearance,
                max_drop: f.max_drop,
                sigma_d: f.sigma_d,
                min_stability: f.min_stability,
                stability_band: f.stability_band,
                sample_spacing: f.sample_spacing,
                stability_links,
                unchecked_links,
            },
            score: ScoreRule {
                sigma_theta: file.score.sigma_theta.to_radians(),
                epsilon: file.score.epsilon,
                support_cos: file.score.support_angle.to_radians().cos(),
                select: file.score.select,
                min_local: file.score.min_local,
            },
            suppression_radius: file.suppression_radius,
            initial,
            nodes,
        })
    }

    /// The affordance ids, in node order (root first).
    pub fn ids(&self) -> Vec<&str> {
        self.nodes.iter().map(|n| n.id.as_str()).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::run::{BUILTIN_AGENT, BUILTIN_SITTING};

    fn agent() -> Agent {
        Agent::from_toml(BUILTIN_AGENT, Path::new("human.toml"), 1.75).unwrap()
    }

    fn load(text: &str) -> Result<Hierarchy, ModelError> {
        Hierarchy::from_toml(text, Path::new("h.toml"), &agent())
    }

    #[test]
    fn the_sitting_hierarchy_follows_fig_3() {
        let h = load(BUILTIN_SITTING).unwrap();
        let ids = h.ids();
        assert_eq!(ids[0], "sitting");
        let parent = |id: &str| {
            let n = &h.nodes[ids.iter().position(|i| *i == id).unwrap()];
            n.parent.map(|p| h.nodes[p].id.as_str())
        };
        assert_eq!(parent("backrest"), Some("sitting"));
        assert_eq!(parent("armrest"), Some("sitting"));
        assert_eq!(parent("headrest"), Some("backrest"));
        assert!(h.nodes.iter().all(|n| n.when));
        // Degrees in the file, radians here.
        let knee = &h.nodes[0].sweeps[0];
        assert!((knee.thetad - 85f64.to_radians()).abs() < 1e-12);
        assert!(
            (h.initial.angles[agent().joint_index("hip_l").unwrap()] - 90f64.to_radians()).abs()
                < 1e-12
        );
    }

    #[test]
    fn bad_hierarchies_name_the_key() {
        let swapped =
            BUILTIN_SITTING.replace("theta1 = 0.0, theta2 = 30.0", "theta1 = 30.0, theta2 = 0.0");
        let e = load(&swapped).unwrap_err().to_string();
        assert!(
            e.contains("node.headrest.sweep.neck.theta1") && e.contains("exceeds"),
            "{e}"
        );
        let orphan = BUILTIN_SITTING.replace("parent = \"backrest\"", "parent = \"back\"");
        let e = load(&orphan).unwrap_err().to_string();
        assert!(
            e.contains("node.headrest.parent") && e.contains("missing node `back`"),
            "{e}"
        );
        let unknown = BUILTIN_SITTING.replace("links = [\"torso\"]", "links = [\"trunk\"]");
        let e = load(&unknown).unwrap_err().to_string();
        assert!(
            e.contains("node.backrest.links") && e.contains("unknown link `trunk`"),
            "{e}"
        );
        let typo = BUILTIN_SITTING.replace("free_start = true", "free_starts = true");
        let e = load(&typo).unwrap_err().to_string();
        assert!(e.starts_with("h.toml:") && e.contains("free_starts"), "{e}");
    }
}
