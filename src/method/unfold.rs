//! Unfolding the agent model (section 4.3) and combining the evidence (section 4.4).
//!
//! The hierarchy is walked from its root. At each node F the joints J_F are set to
//! theta1 and turned towards theta2 while the links E_F are checked for contact; the joint
//! stops at the contact angle theta_c, or takes theta_d when nothing was touched (Eq. 2).
//! A node's children are visited when their edge constraint equals the node's outcome.
//!
//! J_F is split into kinematic branches, sets of sweeps that move the same links (the left
//! and right leg are two branches); each branch stops at its own contact, and each branch
//! is one "edge" of Eq. 3-4: its local score is exp(-(theta_d - theta_c)^2 / 2 sigma^2)
//! (the squared differences averaged over its joints) on contact, epsilon otherwise.

use std::cell::OnceCell;

use crate::method::fit::{ContactConfig, Fit};
use crate::method::scene::Scene;
use crate::model::agent::{Agent, Cylinder, FkCache, Placement, Posture};
use crate::model::hierarchy::{Behind, Fallback, Hierarchy, Node, Slide, Spread};
use crate::num::to_usize;
use nalgebra::{Point3, Rotation3, Vector3};

/// Least length of the horizontal part of a unit contact normal for the `rear` and
/// `beyond` rules to read a direction from it: sin 30 degrees; a normal within 30 degrees
/// of vertical (the top of a seat, a gentle slope) says nothing about what lies in front
/// of the body.
const REAR_MIN_HORIZONTAL: f64 = 0.5;

/// The outcome of one node.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeOutcome {
    /// Whether the node was processed (its edge constraint matched).
    pub visited: bool,
    /// Whether a contact occurred: the fine-grained affordance is present.
    pub found: bool,
    /// Local score (Eq. 3 combined by the T-norm of Eq. 4); 0 when not visited.
    pub local: f64,
    /// Whether the node was found only by leaving a branch untouched over space the scan
    /// never saw (`unseen_sweeps`).
    pub unseen: bool,
}

/// What unfolding one node gave ([`NodeContext::unfold`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NodeFound {
    /// Whether the node was found.
    pub found: bool,
    /// Its local score (Eq. 3 combined by the T-norm of Eq. 4).
    pub local: f64,
    /// Whether it was found only by leaving a branch untouched over space the scan never
    /// saw (`unseen_sweeps`).
    pub unseen: bool,
}

/// The agent after unfolding: the goal configuration H_g and what it found.
#[derive(Debug, Clone, PartialEq)]
pub struct Unfolded {
    /// Where the agent is: where the fit placed it, or where a node's `slide` moved it.
    pub placement: Placement,
    /// The goal posture H_g.
    pub posture: Posture,
    /// One outcome per hierarchy node, in node order.
    pub nodes: Vec<NodeOutcome>,
    /// Accumulated score (T-conorm of Eq. 5 over the found nodes' local scores).
    pub score: f64,
    /// Stability of the fit (Eq. 1).
    pub stability: f64,
    /// Whether the fit's heading came from the all-round search ([`Fit::turned`]).
    pub turned: bool,
}

/// A pose of four nodes at `position` (no joints), the first `found` of them found, for
/// tests of the ranking and the selection.
#[cfg(test)]
pub(crate) fn pose_at(
    position: nalgebra::Point3<f64>,
    turned: bool,
    found: usize,
    score: f64,
) -> Unfolded {
    Unfolded {
        placement: Placement { position, yaw: 0.0 },
        posture: Posture {
            angles: Vec::new(),
            axes: Vec::new(),
        },
        nodes: (0..4)
            .map(|i| NodeOutcome {
                visited: true,
                found: i < found,
                local: 1.0,
                unseen: false,
            })
            .collect(),
        score,
        stability: 1.0,
        turned,
    }
}

impl Unfolded {
    /// Number of fine-grained affordances found.
    pub fn found(&self) -> usize {
        self.nodes.iter().filter(|n| n.found).count()
    }

    /// Whether some node was found only by leaving a branch untouched over space the scan
    /// never saw (`unseen_sweeps`).
    pub fn unseen(&self) -> bool {
        self.nodes.iter().any(|n| n.unseen)
    }

    /// Whether `self` ranks above `other` under `select` (ties are not stronger).
    pub fn stronger_than(
        &self,
        other: &Unfolded,
        select: crate::model::hierarchy::Selection,
    ) -> bool {
        self.rank(other, select) == std::cmp::Ordering::Greater
    }

    /// Orders two poses under `select`.
    pub fn rank(
        &self,
        other: &Unfolded,
        select: crate::model::hierarchy::Selection,
    ) -> std::cmp::Ordering {
        use crate::model::hierarchy::Selection;
        match select {
            Selection::Score => self.score.total_cmp(&other.score),
            Selection::MostSpecific => (!self.turned)
                .cmp(&!other.turned)
                .then(self.found().cmp(&other.found()))
                .then(self.score.total_cmp(&other.score)),
        }
    }
}

/// The T-norm of Eq. 4.
pub fn t_norm(r: f64, q: f64) -> f64 {
    r * q
}

/// The T-conorm of Eq. 5.
pub fn t_conorm(r: f64, q: f64) -> f64 {
    r + q - r * q
}

/// The local score of Eq. 3 for one edge: `Some(squared angle error)` on contact.
pub fn local_score(sq_error: Option<f64>, sigma_theta: f64, epsilon: f64) -> f64 {
    match sq_error {
        Some(e2) => (-e2 / (2.0 * sigma_theta * sigma_theta)).exp(),
        None => epsilon,
    }
}

/// Unfolds the hierarchy from a fit (sections 4.3 and 4.4): each node visited in turn
/// sweeps its joints from the posture the nodes before it left; where a node with a
/// `slide` finds nothing, the body slides back (`slide_back`) and stays where the node
/// is found, for the nodes after it.
pub fn unfold(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    fit: &Fit,
    contact: &ContactConfig,
) -> Unfolded {
    let mut posture = fit.posture.clone();
    // Where the body stands: the fit's place, until a node slides it back (`slide`).
    let mut placement = fit.placement;
    let mut nodes: Vec<NodeOutcome> = Vec::with_capacity(h.nodes.len());
    let mut score = 0.0;
    for node in &h.nodes {
        let visited = match node.parent {
            None => true,
            Some(p) => nodes[p].visited && nodes[p].found == node.when,
        };
        if !visited {
            nodes.push(NodeOutcome {
                visited: false,
                found: false,
                local: 0.0,
                unseen: false,
            });
            continue;
        }
        // The posture the node starts from, for a slide to start from too.
        let start = node.slide.as_ref().map(|_| posture.clone());
        let unfold_at = |place: &Placement, posture: &mut Posture| {
            NodeContext {
                agent,
                h,
                scene,
                place,
                node,
                contact,
                unseen_width: fit.unseen_width,
                behind_here: OnceCell::new(),
            }
            .unfold(posture)
        };
        let mut got = unfold_at(&placement, &mut posture);
        if let (false, Some(slide), Some(start)) = (got.found, &node.slide, &start) {
            if let Some((moved, g, slid)) =
                slide_back(agent, scene, &placement, start, slide, unfold_at)
            {
                (got, posture, placement) = (g, slid, moved);
            }
        }
        if got.found {
            score = t_conorm(score, got.local);
        }
        nodes.push(NodeOutcome {
            visited: true,
            found: got.found,
            local: got.local,
            unseen: got.found && got.unseen,
        });
    }
    Unfolded {
        placement,
        posture,
        nodes,
        score,
        stability: fit.stability,
        turned: fit.turned,
    }
}

/// A node's `slide` (see [`Slide`]): the body in posture `start` moved back from `place`
/// along its heading by each of the slide's steps in turn, as long as it is clear of the
/// scene lifted by the slide's `lift`, and unfolded there by `unfold` (which returns
/// whether the node was found and its local score, and leaves the posture it ends in).
/// The first moved place where the node is found, with its local score and posture;
/// `None` when the body meets something before or the node is found at none.
fn slide_back(
    agent: &Agent,
    scene: &Scene,
    place: &Placement,
    start: &Posture,
    slide: &Slide,
    mut unfold: impl FnMut(&Placement, &mut Posture) -> NodeFound,
) -> Option<(Placement, NodeFound, Posture)> {
    let back = -Vector3::new(place.yaw.cos(), place.yaw.sin(), 0.0);
    let up = Vector3::new(0.0, 0.0, slide.lift);
    let (mut frames, mut parts) = (Vec::new(), Vec::new());
    for &d in &slide.steps {
        let moved = Placement {
            position: place.position + back * d,
            yaw: place.yaw,
        };
        agent.forward_kinematics(&moved, start, &mut frames);
        parts.clear();
        agent.cylinders_into(&frames, |_| true, &mut parts);
        let meets = parts.iter().any(|c| {
            scene.touches(&Cylinder {
                a: c.a + up,
                b: c.b + up,
                ..*c
            })
        });
        if meets {
            return None;
        }
        let mut posture = start.clone();
        let got = unfold(&moved, &mut posture);
        if got.found {
            return Some((moved, got, posture));
        }
    }
    None
}

/// What the rules of one node's unfolding read: the body, its hierarchy (for the scores),
/// the scene, where the body stands, the node, and how finely contact is located. Each
/// rule of the node ([`clamp`](Self::clamp), [`spread`](Self::spread),
/// [`free_start`](Self::free_start), [`release`](Self::release),
/// [`support`](Self::support), [`rear`](Self::rear), [`narrow`](Self::narrow)) is one
/// method.
pub struct NodeContext<'a> {
    /// The body.
    pub agent: &'a Agent,
    /// The hierarchy the node belongs to.
    pub h: &'a Hierarchy,
    /// The scene.
    pub scene: &'a Scene,
    /// Where the body stands.
    pub place: &'a Placement,
    /// The node F unfolded.
    pub node: &'a Node,
    /// How finely contact is located.
    pub contact: &'a ContactConfig,
    /// Whether the width of the surface round the place is unknown
    /// ([`crate::method::hypotheses::Hypothesis::unseen_width`]): then no branch may stay
    /// untouched over unseen space (`unseen_sweeps`).
    pub unseen_width: bool,
    /// The `behind` rule's answer at `place`, once asked (it reads the place only, and
    /// every contact of the node's sweeps asks it).
    behind_here: OnceCell<bool>,
}

impl NodeContext<'_> {
    /// `clamp`: holds each clamped joint of the node within its range (radians).
    pub fn clamp(&self, posture: &mut Posture) {
        for c in &self.node.clamps {
            posture.angles[c.joint] = posture.angles[c.joint].clamp(c.lower, c.upper);
        }
    }

    /// Undoes [`clamp`](Self::clamp): the clamped joints take their angles in `before`.
    pub fn unclamp(&self, posture: &mut Posture, before: &Posture) {
        for c in &self.node.clamps {
            posture.angles[c.joint] = before.angles[c.joint];
        }
    }

    /// Sets every swept joint of the node to theta1, turning about its sweep's axis.
    pub fn start(&self, posture: &mut Posture) {
        for s in &self.node.sweeps {
            posture.angles[s.joint] = s.theta1;
            posture.axes[s.joint] = s.axis;
        }
    }

    /// `spread`: sets each joint of `spreads` to its `k`-th angle (its last when it has
    /// fewer than `k + 1`).
    pub fn spread(spreads: &[&Spread], k: usize, posture: &mut Posture) {
        for sp in spreads {
            posture.angles[sp.joint] = sp.angles[k.min(sp.angles.len() - 1)];
        }
    }

    /// Sets the sweeps of `branch` to sweep parameter `t` (0 at theta1, 1 at theta2).
    pub fn at(&self, branch: &[usize], t: f64, posture: &mut Posture) {
        for &s in branch {
            let sw = &self.node.sweeps[s];
            posture.angles[sw.joint] = sw.theta1 + t * (sw.theta2 - sw.theta1);
        }
    }

    /// `free_start`: whether a contact at sweep parameter `hit` is refused because the
    /// links were already touching at theta1 (they had no room to unfold).
    pub fn free_start(&self, hit: Option<f64>) -> bool {
        self.node.free_start && hit == Some(0.0)
    }

    /// `release`: whether the parts of `parts` that touch the scene are held from the side
    /// opposite the node's release direction (agent frame, turned by the heading), within
    /// the node's `release_angle`, else the hierarchy's support angle. True when the node
    /// has no release direction.
    pub fn release(&self, parts: &[Cylinder]) -> bool {
        let Some(release) = self.node.release else {
            return true;
        };
        let dir =
            (nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), self.place.yaw)
                * release)
                .normalize();
        parts.iter().filter(|c| self.scene.touches(c)).all(|c| {
            self.scene.contact_normal(c).is_some_and(|n| {
                n.dot(&dir) >= self.node.release_cos.unwrap_or(self.h.score.support_cos)
            })
        })
    }

    /// `rear`: whether every part of `parts` that touches the scene stands at the rear of
    /// the seat: from the root joint (the placement's position), along the horizontal part
    /// of the contact's normal ([`Scene::contact_normal`], pointing away from what was
    /// touched) and along the directions the rule's `fan` either side of it, the scene
    /// stops holding a surface within the rule's `gap` below the root joint before the
    /// rule's `reach` (fraction of H), stepping over space the scan did not see
    /// ([`Scene::seat_ends`]). A contact whose normal is nearly vertical has no such
    /// direction and passes. True when the node has no `rear` rule.
    pub fn rear(&self, parts: &[Cylinder]) -> bool {
        let Some(rule) = self.node.rear else {
            return true;
        };
        let reach = rule.reach * self.agent.height;
        parts.iter().filter(|c| self.scene.touches(c)).all(|c| {
            let Some(n) = self.scene.contact_normal(c) else {
                return true;
            };
            let flat = nalgebra::Vector3::new(n.x, n.y, 0.0);
            // Within 30 degrees of vertical, the normal says little about "in front".
            if flat.norm() < REAR_MIN_HORIZONTAL {
                return true;
            }
            let ahead = flat.normalize();
            [0.0, rule.fan, -rule.fan].iter().all(|&a| {
                let dir = Rotation3::from_axis_angle(&Vector3::z_axis(), a) * ahead;
                self.scene
                    .seat_ends(&self.place.position, &dir, reach, rule.gap)
            })
        })
    }

    /// `behind`: whether the seat the body sits on ends behind it: from the root joint
    /// against the body's heading, within the rule's `reach` (fraction of H), some
    /// column holds something between the rule's `rise` and `top` above the root joint
    /// (a back, a wall), or the surface ends as `rear`'s walk finds
    /// ([`Scene::seat_ends`]). It depends on the place only, not on what was touched.
    /// True when the node has no `behind` rule.
    pub fn behind(&self) -> bool {
        let Some(rule) = self.node.behind else {
            return true;
        };
        *self
            .behind_here
            .get_or_init(|| self.seat_ends_behind(&rule))
    }

    /// The walks of [`behind`](Self::behind) under `rule`.
    fn seat_ends_behind(&self, rule: &Behind) -> bool {
        let from = self.place.position;
        let back = Vector3::new(-self.place.yaw.cos(), -self.place.yaw.sin(), 0.0);
        let reach = rule.reach * self.agent.height;
        let step = self.scene.voxel_size();
        // Looking down from `top` above each probe: something within `top - rise` of it.
        let band = rule.top - rule.rise;
        let risen = (1..)
            .map(|k| f64::from(k) * step)
            .take_while(|&s| s <= reach)
            .any(|s| {
                let q = from + back * s;
                let high = Point3::new(q.x, q.y, q.z + rule.top);
                self.scene.drop_below(&high, band) <= band
            });
        risen || self.scene.seat_ends(&from, &back, reach, rule.gap)
    }

    /// `beyond`: whether every part of `parts` that touches the scene touches something at
    /// the edge of the surface the body sits on: from the part's axis point nearest to the
    /// scene ([`Scene::contact`]), raised by its radius (level with its top), walking away
    /// from the body (into what was touched, along the horizontal part of the contact's
    /// normal; outwards from the body's midplane where that normal is within 30 degrees of
    /// vertical), the surface at the root joint's level does not go on beyond what was
    /// touched ([`Scene::goes_on_beyond`]). True when the node has no `beyond` rule.
    pub fn beyond(&self, parts: &[Cylinder]) -> bool {
        let Some(rule) = self.node.beyond else {
            return true;
        };
        let reach = rule.reach * self.agent.height;
        let level = self.place.position.z;
        parts.iter().filter(|p| self.scene.touches(p)).all(|p| {
            let Some((near, n)) = self.scene.contact(p) else {
                return true;
            };
            let flat = Vector3::new(n.x, n.y, 0.0);
            let dir = if flat.norm() >= REAR_MIN_HORIZONTAL {
                -flat.normalize()
            } else {
                self.outwards(&near)
            };
            let from = Point3::new(near.x, near.y, near.z + p.radius);
            !self.scene.goes_on_beyond(
                &from,
                &dir,
                reach,
                (level, rule.gap, rule.rise),
                rule.length,
            )
        })
    }

    /// The level unit direction square to the heading, away from the body's midplane (the
    /// vertical plane through the root joint along the heading), on the side of `at`.
    fn outwards(&self, at: &Point3<f64>) -> Vector3<f64> {
        let (s, c) = self.place.yaw.sin_cos();
        let left = Vector3::new(-s, c, 0.0);
        if (at - self.place.position).dot(&left) >= 0.0 {
            left
        } else {
            -left
        }
    }

    /// `narrow`: whether every part of `parts` that touches the scene rests on something
    /// that ends beside the body: from the part's middle, at its underside, outwards (away
    /// from the body's midplane, level), the scene stops lying within the node's
    /// `support_gap` below before the rule's width (fraction of H). An armrest is a rest
    /// for one arm; a table top or a bed beside a body turned on its seat goes on.
    /// True when the node has no `narrow` rule.
    pub fn narrow(&self, parts: &[Cylinder]) -> bool {
        let Some(width) = self.node.narrow else {
            return true;
        };
        let width = width * self.agent.height;
        let gap = self.node.support_gap;
        // Half a voxel above the underside: what the part rests on (touching it, or up to
        // a voxel into it) is below the probe.
        let lift = self.scene.voxel_size() / 2.0;
        parts.iter().filter(|p| self.scene.touches(p)).all(|p| {
            let mid = nalgebra::center(&p.a, &p.b);
            let out = self.outwards(&mid);
            let from = nalgebra::Point3::new(mid.x, mid.y, p.a.z.min(p.b.z) - p.radius + lift);
            self.scene.surface_ends(&from, &out, width, gap)
        })
    }

    /// `beside`: whether every part of `parts` that touches the scene is beside the body,
    /// not on something that runs on across in front of it: along the node's `over` link
    /// in `posture` (the thigh: the lap), moved sideways onto the body's midplane (the
    /// vertical plane through the root joint along the heading) and raised to the part's
    /// axis height, no scene lies within the `beside` gap below the part's underside.
    /// True when the node has no `beside` rule.
    pub fn beside(&self, posture: &Posture, parts: &[Cylinder]) -> bool {
        let Some(rule) = self.node.beside else {
            return true;
        };
        let mut frames = Vec::new();
        self.agent
            .forward_kinematics(self.place, posture, &mut frames);
        let Some(over) = self
            .agent
            .cylinders(&frames, |j| j == rule.over)
            .into_iter()
            .next()
        else {
            return true;
        };
        let (s, c) = self.place.yaw.sin_cos();
        let side = nalgebra::Vector3::new(-s, c, 0.0);
        let onto = |p: nalgebra::Point3<f64>| p - side * (p - self.place.position).dot(&side);
        let (a, b) = (onto(over.a), onto(over.b));
        let step = self.scene.voxel_size();
        let n = to_usize(((b - a).norm() / step).ceil().max(1.0));
        parts.iter().filter(|p| self.scene.touches(p)).all(|p| {
            let z = nalgebra::center(&p.a, &p.b).z;
            (0..=n).all(|i| {
                let mut q = a + (b - a) * (i as f64 / n as f64);
                q.z = z;
                self.scene.drop_below(&q, p.radius + rule.gap) - p.radius > rule.gap
            })
        })
    }

    /// `support`: whether the branch's support parts (if the node has any that the branch
    /// moves) rest on the scene at sweep parameter `t`: each has the scene within
    /// `support_gap` below it, or (with `unseen_reach`) space the scan never saw.
    pub fn support(&self, posture: &Posture, branch: &[usize], t: f64) -> bool {
        let mut p = posture.clone();
        self.at(branch, t, &mut p);
        self.resting(&p, branch) != Rest::Free
    }

    /// How the branch's support parts rest in `posture` as posed. Each support entry
    /// (a link and a span of it) the branch moves is judged alone: on a seen surface when
    /// some sample of its span (with `support_share`, that share of them) has the scene
    /// within `support_gap` below it, else over a column where the scan saw nothing
    /// within `unseen_reach`, else free. The branch rests as its worst entry:
    /// [`Rest::Seen`] when every entry is seen, [`Rest::Free`] when any is free, else
    /// [`Rest::Unseen`].
    fn resting(&self, p: &Posture, branch: &[usize]) -> Rest {
        let (agent, node, scene) = (self.agent, self.node, self.scene);
        let mine: Vec<(usize, [f64; 2])> = node
            .support
            .iter()
            .copied()
            .filter(|(l, _)| {
                branch
                    .iter()
                    .any(|&s| agent.is_descendant(*l, node.sweeps[s].joint))
            })
            .collect();
        if mine.is_empty() {
            return Rest::NoParts;
        }
        let mut frames = Vec::new();
        agent.forward_kinematics(self.place, p, &mut frames);
        let step = scene.voxel_size();
        let gap = node.support_gap;
        let cylinders = agent.cylinders(&frames, |j| mine.iter().any(|(l, _)| *l == j));
        let mut worst = Rest::Seen;
        for (link, [s0, s1]) in &mine {
            let Some(c) = cylinders.iter().find(|c| c.joint == *link) else {
                continue;
            };
            let d = c.b - c.a;
            let n = to_usize(((d.norm() * (s1 - s0)) / step).ceil().max(1.0));
            let samples = (0..=n).map(|i| c.a + d * (s0 + (s1 - s0) * i as f64 / n as f64));
            let on =
                |q: &nalgebra::Point3<f64>| scene.drop_below(q, c.radius + gap) - c.radius <= gap;
            let seen = match node.support_share {
                None => samples.clone().any(|q| on(&q)),
                Some(share) => {
                    samples.clone().filter(|q| on(q)).count() as f64 >= share * (n + 1) as f64
                }
            };
            if seen {
                continue;
            }
            if node
                .unseen_reach
                .is_some_and(|reach| samples.clone().any(|q| !scene.sees_below(&q, reach)))
            {
                worst = Rest::Unseen;
            } else {
                return Rest::Free;
            }
        }
        worst
    }

    /// `unseen_sweeps`: whether `branch`, whose sweep touched nothing, is not refuted by
    /// that: every one of its sweeps is among the node's `unseen_sweeps`, it touched
    /// nothing at all (its joints rest at their preferred angles, where Eq. 2 leaves an
    /// untouched sweep; a contact a rule refused leaves them at its angle), and its support
    /// parts there hang over space the scan never saw ([`Rest::Unseen`]). The legs of a
    /// body on a bed the image edge cuts across at the hips are such a branch; a place of
    /// unknown width (a strip cut lengthwise) has used up what the scan may leave unseen.
    fn unseen(&self, posture: &Posture, branch: &[usize]) -> bool {
        let node = self.node;
        !self.unseen_width
            && !branch.is_empty()
            && branch.iter().all(|&s| {
                let sw = &node.sweeps[s];
                node.unseen_sweeps.contains(&sw.joint) && posture.angles[sw.joint] == sw.thetad
            })
            && self.resting(posture, branch) == Rest::Unseen
    }

    /// `fallback`: for a branch whose sweep found nothing, sets the node's fallback joints
    /// that move the branch's links to their `k`-th angles (k = 0, 1, ..., all together)
    /// and sweeps the branch again; a setting is tried only if the links those joints move
    /// and the branch's sweeps do not (the thigh under a knee sweep) are free of the scene
    /// over their `free` span. Returns the first setting that touches: its sweep
    /// parameter, local score (Eq. 3) and posture. `None` when the node has no fallback
    /// for this branch or no setting touched.
    pub fn fallback(
        &self,
        posture: &Posture,
        branch: &[usize],
        links: &[usize],
    ) -> Option<(f64, f64, Posture)> {
        let (agent, node) = (self.agent, self.node);
        let mine: Vec<&Fallback> = node
            .fallbacks
            .iter()
            .filter(|fb| links.iter().any(|&l| agent.is_descendant(l, fb.joint)))
            .collect();
        let settings = mine.iter().map(|fb| fb.angles.len()).max()?;
        let swept = |l: usize| {
            branch
                .iter()
                .any(|&s| agent.is_descendant(l, node.sweeps[s].joint))
        };
        let held = |l: usize| mine.iter().find(|fb| agent.is_descendant(l, fb.joint));
        let mut frames = Vec::new();
        for k in 0..settings {
            let mut trial = posture.clone();
            for fb in &mine {
                trial.angles[fb.joint] = fb.angles[k.min(fb.angles.len() - 1)];
            }
            agent.forward_kinematics(self.place, &trial, &mut frames);
            let blocked = agent
                .cylinders(&frames, |l| !swept(l) && held(l).is_some())
                .into_iter()
                .any(|c| {
                    self.scene
                        .touches(&c.span(held(c.joint).map_or([0.0, 1.0], |fb| fb.free)))
                });
            if blocked {
                continue;
            }
            let (hit, r) = self.sweep_branch(&mut trial, branch, links);
            if let Some(t) = hit {
                return Some((t, r, trial));
            }
        }
        None
    }

    /// Sweeps one kinematic branch of the node from theta1 towards theta2, stopping at the
    /// first contact of its links that the rules accept; writes Eq. 2's angles into
    /// `posture` and returns the contact parameter and the branch's local score (Eq. 3).
    pub fn sweep_branch(
        &self,
        posture: &mut Posture,
        branch: &[usize],
        links: &[usize],
    ) -> (Option<f64>, f64) {
        let (agent, node) = (self.agent, self.node);
        // The parts tested, each cut to its span as the motion poses it.
        let span = |l: usize| {
            node.links
                .iter()
                .position(|&x| x == l)
                .map_or([0.0, 1.0], |k| node.spans[k])
        };
        let parts: Vec<(usize, [f64; 2])> = links.iter().map(|&l| (l, span(l))).collect();
        // How far any point of the tested parts moves per unit of the sweep: only they
        // are tested, so the parts they carry (the hand beyond an armrest's forearm span)
        // do not shorten the steps.
        let speed: f64 = branch
            .iter()
            .map(|&s| {
                let sw = &node.sweeps[s];
                (sw.theta2 - sw.theta1).abs() * agent.reach_to(sw.joint, &parts)
            })
            .sum();
        // Only the branch's joints move; they are rewritten at every step.
        let mut p = posture.clone();
        let (mut frames, mut cache) = (Vec::new(), FkCache::default());
        // One joint turning: every tested point moves at most the turn's rate times its
        // distance from the joint's origin, which the turn does not move. Posed here as
        // the motion poses it at its start, whose first call then reuses these frames.
        self.at(branch, 0.0, &mut p);
        agent.forward_kinematics_cached(self.place, &p, &mut cache, &mut frames);
        let turn = match branch {
            [s] => {
                let sw = &node.sweeps[*s];
                frames.get(sw.joint).map(|f| {
                    (
                        Point3::from(f.translation.vector),
                        (sw.theta2 - sw.theta1).abs(),
                    )
                })
            }
            _ => None,
        };
        let mut motion = |t: f64, out: &mut Vec<Cylinder>| {
            self.at(branch, t, &mut p);
            agent.forward_kinematics_cached(self.place, &p, &mut cache, &mut frames);
            agent.cylinders_into(&frames, |j| links.contains(&j), out);
            for c in out.iter_mut() {
                if let Some(k) = node.links.iter().position(|&l| l == c.joint) {
                    *c = c.span(node.spans[k]);
                }
            }
        };
        let mut hit = self.scene.first_contact_turning(
            &mut motion,
            speed.max(1e-9),
            turn,
            self.contact.resolution,
        );
        let mut blocked = None;
        if self.free_start(hit) {
            blocked = hit.take();
        }
        // The rules that judge the touching parts, in turn, on the parts at the contact
        // (`beyond`, the dearest, last).
        let judged = node.release.is_some()
            || node.rear.is_some()
            || node.behind.is_some()
            || node.beyond.is_some()
            || node.narrow.is_some()
            || node.beside.is_some();
        if let (Some(t), true) = (hit, judged) {
            let mut parts = Vec::new();
            motion(t, &mut parts);
            if !(self.release(&parts)
                && self.rear(&parts)
                && self.behind()
                && self.narrow(&parts)
                && self.beside(&p, &parts)
                && self.beyond(&parts))
            {
                blocked = hit.take();
            }
        }
        if let Some(t) = hit {
            if !self.support(&p, branch, t) {
                blocked = hit.take();
            }
        }
        let mut sq = 0.0;
        for &s in branch {
            let sw = &node.sweeps[s];
            // Eq. 2: theta_c on contact, theta_d otherwise.
            let theta = match hit.or(blocked) {
                Some(t) => sw.theta1 + t * (sw.theta2 - sw.theta1),
                None => sw.thetad,
            };
            posture.angles[sw.joint] = theta;
            sq += (sw.thetad - theta).powi(2);
        }
        let sq = sq / branch.len() as f64;
        (
            hit,
            local_score(
                hit.map(|_| sq),
                self.h.score.sigma_theta,
                self.h.score.epsilon,
            ),
        )
    }

    /// Sweeps the node's joints, writing the resulting angles (Eq. 2) into `posture`;
    /// returns whether it touched, its local score, and whether it touched only by leaving
    /// a branch untouched over unseen space.
    pub fn unfold(&self, posture: &mut Posture) -> NodeFound {
        let (agent, node) = (self.agent, self.node);
        let before = posture.clone();
        self.clamp(posture);
        self.start(posture);
        let branches = branches(agent, node);
        // The links of E_F each branch moves.
        let branch_links: Vec<Vec<usize>> = branches
            .iter()
            .map(|branch| {
                node.links
                    .iter()
                    .copied()
                    .filter(|&l| {
                        branch
                            .iter()
                            .any(|&s| agent.is_descendant(l, node.sweeps[s].joint))
                    })
                    .collect()
            })
            .collect();
        // A spread joint that moves the links of several branches (the trunk leaning
        // sideways moves both arms) is one setting for the whole node: each of its angles
        // is tried with all branches, and the best outcome (found first, then local score)
        // is kept.
        let moves =
            |sp: &Spread, links: &[usize]| links.iter().any(|&l| agent.is_descendant(l, sp.joint));
        let shared: Vec<&Spread> = node
            .spreads
            .iter()
            .filter(|sp| branch_links.iter().filter(|ls| moves(sp, ls)).count() > 1)
            .collect();
        let shared_settings = shared.iter().map(|sp| sp.angles.len()).max().unwrap_or(1);
        let mut outcome: Option<(bool, f64, bool, Posture)> = None;
        for ks in 0..shared_settings {
            let mut node_posture = posture.clone();
            Self::spread(&shared, ks, &mut node_posture);
            let mut local = 1.0;
            let mut found = false;
            let mut all_found = true;
            let mut unseen_any = false;
            for (branch, links) in branches.iter().zip(&branch_links) {
                // The spread joints that move only this branch's links; each of their
                // angles is tried.
                let spreads: Vec<&Spread> = node
                    .spreads
                    .iter()
                    .filter(|sp| moves(sp, links) && !shared.iter().any(|s| s.joint == sp.joint))
                    .collect();
                let settings = spreads.iter().map(|sp| sp.angles.len()).max().unwrap_or(1);
                let mut best: Option<(Option<f64>, f64, Posture)> = None;
                for k in 0..settings {
                    let mut trial = node_posture.clone();
                    Self::spread(&spreads, k, &mut trial);
                    let (hit, r) = self.sweep_branch(&mut trial, branch, links);
                    let better = match &best {
                        None => true,
                        Some((bh, br, _)) => {
                            (hit.is_some() && bh.is_none())
                                || (hit.is_some() == bh.is_some() && r > *br)
                        }
                    };
                    if better {
                        best = Some((hit, r, trial));
                    }
                }
                if best.as_ref().is_none_or(|b| b.0.is_none()) {
                    if let Some((t, r, trial)) = self.fallback(&node_posture, branch, links) {
                        best = Some((Some(t), r, trial));
                    }
                }
                let unseen = best
                    .as_ref()
                    .is_some_and(|(hit, _, trial)| hit.is_none() && self.unseen(trial, branch));
                if let Some((hit, r, trial)) = best {
                    for &s in branch {
                        let j = node.sweeps[s].joint;
                        node_posture.angles[j] = trial.angles[j];
                    }
                    for fb in &node.fallbacks {
                        node_posture.angles[fb.joint] = trial.angles[fb.joint];
                    }
                    for sp in &spreads {
                        node_posture.angles[sp.joint] = trial.angles[sp.joint];
                    }
                    found |= hit.is_some();
                    all_found &= hit.is_some() || unseen;
                    unseen_any |= unseen;
                    if !unseen {
                        local = t_norm(local, r);
                    }
                }
            }
            if node.contact == crate::model::hierarchy::ContactRule::All {
                found &= all_found;
            }
            // Space the scan never saw may hold one end of the body, not every end: some
            // branch with support parts rests on a surface it saw.
            if found && node.unseen_reach.is_some() {
                let rests: Vec<Rest> = branches
                    .iter()
                    .map(|b| self.resting(&node_posture, b))
                    .collect();
                found = rests.contains(&Rest::Seen) || rests.iter().all(|r| *r == Rest::NoParts);
            }
            let better = match &outcome {
                None => true,
                Some((bf, bl, _, _)) => (found && !*bf) || (found == *bf && local > *bl),
            };
            if better {
                outcome = Some((found, local, unseen_any, node_posture));
            }
        }
        let (found, local, unseen, node_posture) = outcome.expect("at least one setting");
        *posture = node_posture;
        // A contact far from every preferred angle is no use of the affordance.
        let found = found && local >= self.h.score.min_local;
        if !found {
            self.unclamp(posture, &before);
        }
        NodeFound {
            found,
            local,
            unseen,
        }
    }
}

/// How a branch's support parts rest ([`NodeContext::resting`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Rest {
    /// The branch moves none of the node's support parts.
    NoParts,
    /// Every entry has a surface the scan saw within `support_gap` below it.
    Seen,
    /// Every entry is seen or over space the scan never saw (`unseen_reach`), some the
    /// latter.
    Unseen,
    /// Some entry hangs over seen space with nothing below it.
    Free,
}

/// Groups a node's sweeps (by index) into kinematic branches: sweeps that move a common
/// link of E_F, transitively, belong to one branch. Ordered by first sweep.
pub fn branches(agent: &Agent, node: &Node) -> Vec<Vec<usize>> {
    let n = node.sweeps.len();
    let moves: Vec<Vec<usize>> = node
        .sweeps
        .iter()
        .map(|s| {
            node.links
                .iter()
                .copied()
                .filter(|&l| agent.is_descendant(l, s.joint))
                .collect()
        })
        .collect();
    let mut group: Vec<usize> = (0..n).collect();
    for i in 0..n {
        for j in 0..i {
            if moves[i].iter().any(|l| moves[j].contains(l)) {
                let (gi, gj) = (group[i], group[j]);
                for g in group.iter_mut() {
                    if *g == gi {
                        *g = gj;
                    }
                }
            }
        }
    }
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut keys: Vec<usize> = Vec::new();
    for (i, g) in group.iter().enumerate() {
        match keys.iter().position(|k| k == g) {
            Some(p) => out[p].push(i),
            None => {
                keys.push(*g);
                out.push(vec![i]);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cloud::PointCloud;
    use crate::detect::DetectConfig;
    use crate::model::agent::Agent;
    use crate::model::hierarchy::Clamp;
    use nalgebra::{Point3, Vector3};
    use std::path::Path;

    /// A body of 1 m: a pelvis and one leg of 0.5 m on a hip turning about +y (a negative
    /// angle swings the leg forwards, +x), radius 2 cm.
    const STICK: &str = r#"
name = "stick"
[[joint]]
name = "pelvis"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 0.0, 1.0]
limit = { lower = 0.0, upper = 0.0 }
link = { name = "pelvis", from = [0.0, -0.05, 0.0], to = [0.0, 0.05, 0.0], radius = 0.02 }
[[joint]]
name = "hip"
parent = "pelvis"
origin = [0.0, 0.0, 0.0]
axis = [0.0, 1.0, 0.0]
limit = { lower = -180.0, upper = 180.0 }
link = { name = "leg", from = [0.0, 0.0, 0.0], to = [0.0, 0.0, -0.5], radius = 0.02 }
"#;

    /// The stick, and the lying hierarchy's numbers with one node that lowers the leg from
    /// 60 deg above level (hip -150) to 60 deg below (hip -30), held from below.
    fn models() -> (Agent, Hierarchy) {
        let agent = Agent::from_toml(STICK, Path::new("stick.toml"), 1.0).unwrap();
        let lying = crate::model::set::BUILTIN_LYING;
        let head = &lying[..lying.find("[initial_pose]").unwrap()];
        // Without lying's legend (its ids are not this file's nodes).
        let (a, b) = (
            head.find("legend = [").unwrap(),
            head.find("]\n\n[").unwrap(),
        );
        let head = format!("{}{}", &head[..a], &head[b + 2..]);
        let text = format!(
            "{head}\n[initial_pose]\n\n[[node]]\nid = \"leg\"\nlinks = [\"leg\"]\n\
             sweep = [{{ joint = \"hip\", theta1 = -150.0, theta2 = -30.0, thetad = -90.0 }}]\n\
             release = [0.0, 0.0, 1.0]\n"
        );
        let h = Hierarchy::from_toml(&text, Path::new("leg.toml"), &agent).unwrap();
        (agent, h)
    }

    /// A box 0.5 m long (x 0.1 to 0.6), 0.6 m wide, its top at z = 0.45 and its front face
    /// at x = 0.6, as points 1 cm apart.
    fn box_scene() -> Scene {
        let mut pts = Vec::new();
        for i in 0..=50 {
            for j in 0..=60 {
                pts.push(Point3::new(
                    0.1 + i as f64 * 0.01,
                    -0.3 + j as f64 * 0.01,
                    0.45,
                ));
            }
        }
        for k in 0..=45 {
            for j in 0..=60 {
                pts.push(Point3::new(0.6, -0.3 + j as f64 * 0.01, k as f64 * 0.01));
            }
        }
        Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
    }

    const CONTACT: ContactConfig = ContactConfig { resolution: 0.005 };

    /// The pelvis at `z` above x = 0.15 (over the box), facing +x.
    fn place(z: f64) -> Placement {
        Placement {
            position: Point3::new(0.15, 0.0, z),
            yaw: 0.0,
        }
    }

    /// The pelvis 8 cm above a seat at 0.45 m, at `x` on the x axis, facing +x.
    fn seated(x: f64) -> Placement {
        Placement {
            position: Point3::new(x, 0.0, 0.53),
            yaw: 0.0,
        }
    }

    fn with<'a>(
        agent: &'a Agent,
        h: &'a Hierarchy,
        scene: &'a Scene,
        place: &'a Placement,
        node: &'a Node,
    ) -> NodeContext<'a> {
        NodeContext {
            agent,
            h,
            scene,
            place,
            node,
            contact: &CONTACT,
            unseen_width: false,
            behind_here: OnceCell::new(),
        }
    }

    #[test]
    fn a_turned_pose_ranks_below_one_at_the_places_heading() {
        use crate::model::hierarchy::Selection;
        let pose = |turned: bool, found: usize, score: f64| {
            pose_at(Point3::origin(), turned, found, score)
        };
        let (natural, turned) = (pose(false, 2, 0.9), pose(true, 3, 0.99));
        assert!(natural.stronger_than(&turned, Selection::MostSpecific));
        assert!(turned.stronger_than(&natural, Selection::Score));
        assert!(pose(false, 3, 0.5).stronger_than(&natural, Selection::MostSpecific));
    }

    #[test]
    fn clamp_holds_a_joint_in_its_range_and_unclamp_restores_it() {
        let (a, h) = models();
        let s = box_scene();
        let p = place(1.0);
        let mut node = h.nodes[0].clone();
        node.clamps = vec![Clamp {
            joint: 1,
            lower: -0.5,
            upper: 0.5,
        }];
        let c = with(&a, &h, &s, &p, &node);
        let mut posture = a.rest_posture();
        posture.angles[1] = 1.2;
        let before = posture.clone();
        c.clamp(&mut posture);
        assert_eq!(posture.angles[1], 0.5);
        c.unclamp(&mut posture, &before);
        assert_eq!(posture.angles[1], 1.2);
    }

    #[test]
    fn spread_takes_the_kth_angle_or_the_last() {
        let (a, _) = models();
        let sp = Spread {
            joint: 1,
            angles: vec![0.1, 0.2],
        };
        let mut posture = a.rest_posture();
        NodeContext::spread(&[&sp], 0, &mut posture);
        assert_eq!(posture.angles[1], 0.1);
        NodeContext::spread(&[&sp], 5, &mut posture);
        assert_eq!(posture.angles[1], 0.2);
    }

    #[test]
    fn free_start_refuses_only_a_contact_at_theta1() {
        let (a, h) = models();
        let s = box_scene();
        let p = place(1.0);
        let mut node = h.nodes[0].clone();
        assert!(!with(&a, &h, &s, &p, &node).free_start(Some(0.0)));
        node.free_start = true;
        let c = with(&a, &h, &s, &p, &node);
        assert!(c.free_start(Some(0.0)));
        assert!(!c.free_start(Some(0.3)));
        assert!(!c.free_start(None));
    }

    /// A back (the plane x = 0, 0.45-1.0 m high, 0.6 m wide) with a surface at 0.45 m in
    /// front of it running `length` cm along +x and, with `front`, a face from its front
    /// edge down to the floor; points 1 cm apart.
    fn seat_and_back(length: usize, front: bool) -> Vec<Point3<f64>> {
        let x = length as f64 * 0.01;
        let mut pts = Vec::new();
        for j in 0..=60 {
            let y = -0.3 + j as f64 * 0.01;
            for i in 0..=length {
                pts.push(Point3::new(i as f64 * 0.01, y, 0.45));
            }
            for k in 0..=100 {
                let z = k as f64 * 0.01;
                if k >= 45 {
                    pts.push(Point3::new(0.0, y, z));
                } else if front {
                    pts.push(Point3::new(x, y, z));
                }
            }
        }
        pts
    }

    /// The built-in body at 1.75 m, the built-in sitting hierarchy and its backrest node's
    /// index.
    fn built_in_sitting() -> (Agent, Hierarchy, usize) {
        use crate::model::set::{BUILTIN_AGENT, BUILTIN_SITTING};
        let agent = Agent::from_toml(BUILTIN_AGENT, Path::new("human.toml"), 1.75).unwrap();
        let h = Hierarchy::from_toml(BUILTIN_SITTING, Path::new("sitting.toml"), &agent).unwrap();
        let backrest = h.ids().iter().position(|i| *i == "backrest").unwrap();
        (agent, h, backrest)
    }

    #[test]
    fn a_body_slides_back_onto_a_back_it_does_not_reach_until_its_shanks_meet_the_seat() {
        let (agent, h, backrest) = built_in_sitting();
        let mut still = h.clone();
        still.nodes[backrest].slide = None;
        // A chair: seat and back, its seat's front face dropping to the floor.
        let chair = |cm: usize| {
            Scene::new(
                &PointCloud::new(seat_and_back(cm, true)),
                &DetectConfig::default().scene,
            )
        };
        // Seated 0.45 m in front of the back, facing +x: the trunk leaning 35 deg does
        // not reach it.
        let fit = Fit {
            placement: seated(0.45),
            posture: h.initial.clone(),
            stability: 1.0,
            turned: false,
            unseen_width: false,
        };
        let x = |u: &Unfolded| u.placement.position.x;
        let shallow = chair(55);
        let without = unfold(&agent, &still, &shallow, &fit, &CONTACT);
        assert!(without.nodes[0].found && !without.nodes[backrest].found);
        assert_eq!(x(&without), 0.45);
        let slid = unfold(&agent, &h, &shallow, &fit, &CONTACT);
        assert!(slid.nodes[0].found && slid.nodes[backrest].found);
        let moved = 0.45 - x(&slid);
        assert!(
            [0.05, 0.10, 0.15].iter().any(|d| (moved - d).abs() < 1e-9),
            "moved {moved}"
        );
        assert_eq!(slid.placement.position.y, 0.0);
        // A seat 0.25 m deeper: its front face stands 2.6 cm behind the hanging shanks
        // (the knee 0.43 m in front of the pelvis, the shank 5.3 cm thick), so the first
        // 5 cm back already meets it, and the body stays where it was.
        let deep = chair(80);
        let stopped = unfold(&agent, &h, &deep, &fit, &CONTACT);
        assert!(stopped.nodes[0].found && !stopped.nodes[backrest].found);
        assert_eq!(x(&stopped), 0.45);
    }

    /// A mattress top at 0.45 m from x = -1.0 to its front edge at x = 0.45, with a face
    /// from that edge down to the floor, 0.6 m wide; a pillow on it from x = -0.30 to
    /// -0.02 (top at 0.65 m, faces all round); with `headboard`, the mattress ends at a
    /// headboard right behind the pillow at x = -0.32, up to 1.1 m. Points 1 cm apart.
    fn mattress_and_pillow(headboard: bool) -> Vec<Point3<f64>> {
        let cm = |i: i32| f64::from(i) * 0.01;
        let mut pts = Vec::new();
        let back = if headboard { -32 } else { -100 };
        for j in -30..=30 {
            for i in back..=45 {
                pts.push(Point3::new(cm(i), cm(j), 0.45));
            }
            for k in 0..=45 {
                pts.push(Point3::new(0.45, cm(j), cm(k)));
            }
            if headboard {
                for k in 45..=110 {
                    pts.push(Point3::new(-0.32, cm(j), cm(k)));
                }
            }
        }
        for j in -25..=25 {
            for i in -30..=-2 {
                pts.push(Point3::new(cm(i), cm(j), 0.65));
            }
            for k in 45..=65 {
                pts.push(Point3::new(-0.02, cm(j), cm(k)));
                pts.push(Point3::new(-0.30, cm(j), cm(k)));
            }
        }
        for i in -30..=-2 {
            for k in 45..=65 {
                pts.push(Point3::new(cm(i), -0.25, cm(k)));
                pts.push(Point3::new(cm(i), 0.25, cm(k)));
            }
        }
        pts
    }

    #[test]
    fn a_pillow_on_a_mattress_is_no_backrest_a_chair_back_is() {
        let (agent, mut h, backrest) = built_in_sitting();
        assert!(h.nodes[backrest].beyond.is_some());
        // The whole trunk checked, so that the rule alone decides (a pillow this high also
        // touches the trunk above the span left out: see the next test); the mattress
        // going on behind the body (`behind`) is left out too.
        h.nodes[backrest].spans = vec![[0.0, 1.0]];
        h.nodes[backrest].behind = None;
        let mut blind = h.clone();
        blind.nodes[backrest].beyond = None;
        let scene = |pts| Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene);
        let fit = |x: f64| Fit {
            placement: seated(x),
            posture: h.initial.clone(),
            stability: 1.0,
            turned: false,
            unseen_width: false,
        };
        // On the mattress's edge, 0.12 m in front of the pillow, facing +x: the leaning
        // trunk meets the pillow's top edge; beyond the pillow the mattress goes on.
        let bed = scene(mattress_and_pillow(false));
        let leaning = unfold(&agent, &blind, &bed, &fit(0.10), &CONTACT);
        assert!(leaning.nodes[0].found && leaning.nodes[backrest].found);
        let ruled = unfold(&agent, &h, &bed, &fit(0.10), &CONTACT);
        assert!(ruled.nodes[0].found && !ruled.nodes[backrest].found);
        // A pillow against a headboard has the headboard beyond it: a back.
        let against = scene(mattress_and_pillow(true));
        let propped = unfold(&agent, &h, &against, &fit(0.10), &CONTACT);
        assert!(propped.nodes[backrest].found);
        // A chair's back, with the floor far below behind it.
        let chair = scene(seat_and_back(45, true));
        let sat = unfold(&agent, &h, &chair, &fit(0.15), &CONTACT);
        assert!(sat.nodes[0].found && sat.nodes[backrest].found);
    }

    #[test]
    fn a_back_below_the_lumbar_spine_is_no_backrest() {
        let (agent, h, backrest) = built_in_sitting();
        let mut whole = h.clone();
        whole.nodes[backrest].spans = vec![[0.0, 1.0]];
        // A seat at 0.45 m, its front face dropping to the floor at x = 0.45, and a back
        // (the plane x = 0) rising `cm` above it, with nothing behind.
        let chair = |cm: usize| {
            let mut pts = seat_and_back(45, true);
            pts.retain(|p| p.x > 0.0 || p.z <= 0.45 + cm as f64 * 0.01);
            Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
        };
        let fit = Fit {
            placement: seated(0.12),
            posture: h.initial.clone(),
            stability: 1.0,
            turned: false,
            unseen_width: false,
        };
        // A rim 0.15 m high (a pillow's height) touches the trunk only at its lowest part.
        let rim = chair(15);
        let all = unfold(&agent, &whole, &rim, &fit, &CONTACT);
        assert!(all.nodes[0].found && all.nodes[backrest].found);
        let lumbar = unfold(&agent, &h, &rim, &fit, &CONTACT);
        assert!(lumbar.nodes[0].found && !lumbar.nodes[backrest].found);
        // A back 0.30 m high holds the lumbar spine.
        let back = unfold(&agent, &h, &chair(30), &fit, &CONTACT);
        assert!(back.nodes[backrest].found);
    }

    /// A trunk stick of radius 5 cm, upright from 0.6 to 0.9 m, leaning 1 cm into the back
    /// of [`seat_and_back`] (the plane x = 0); and the same 0.5 m further in front, where it
    /// touches nothing.
    fn trunk_at_the_back() -> (Cylinder, Cylinder) {
        let r = 0.05;
        let trunk = Cylinder {
            joint: 1,
            a: Point3::new(r - 0.01, 0.0, 0.6),
            b: Point3::new(r - 0.01, 0.0, 0.9),
            radius: r,
        };
        let away = Cylinder {
            a: trunk.a + Vector3::new(0.5, 0.0, 0.0),
            b: trunk.b + Vector3::new(0.5, 0.0, 0.0),
            ..trunk
        };
        (trunk, away)
    }

    #[test]
    fn beyond_needs_the_seat_to_go_on_for_its_length() {
        use crate::model::hierarchy::Beyond;
        let (a, h) = models();
        // A seat at 0.45 m jutting 8 cm out behind its back (the plane x = 0, 0.45-1.0 m).
        let mut pts = seat_and_back(45, false);
        for j in 0..=60 {
            for i in 1..=8 {
                pts.push(Point3::new(
                    -0.01 * f64::from(i),
                    -0.3 + f64::from(j) * 0.01,
                    0.45,
                ));
            }
        }
        let chair = Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene);
        let p = seated(0.15);
        let (trunk, away) = trunk_at_the_back();
        assert!(chair.touches(&trunk));
        let mut node = h.nodes[0].clone();
        // The stick is 1 m tall: the walk looks 0.45 m on.
        let rule = |length| {
            Some(Beyond {
                reach: 0.45,
                gap: 0.2,
                length,
                rise: 0.0,
            })
        };
        node.beyond = rule(0.10);
        assert!(with(&a, &h, &chair, &p, &node).beyond(&[trunk]));
        node.beyond = rule(0.04);
        assert!(!with(&a, &h, &chair, &p, &node).beyond(&[trunk]));
        // A part that touches nothing, or a node without the rule, is not refused.
        assert!(with(&a, &h, &chair, &p, &node).beyond(&[away]));
        node.beyond = None;
        assert!(with(&a, &h, &chair, &p, &node).beyond(&[trunk]));
    }

    /// A body turned at a bed's head-end corner: straight out from the back the seat ends
    /// (the bed's side), but 30 degrees to one side the mattress goes on along the bed.
    #[test]
    fn rear_looks_across_the_width_of_the_thighs() {
        use crate::model::hierarchy::Rear;
        let (a, h) = models();
        // The chair's seat (0.45 m deep), and a strip of mattress going on from its front
        // edge along x at y = 0.10-0.30 m.
        let mut pts = seat_and_back(45, false);
        for i in 46..=200 {
            for j in 10..=30 {
                pts.push(Point3::new(i as f64 * 0.01, j as f64 * 0.01, 0.45));
            }
        }
        let corner = Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene);
        let p = seated(0.15);
        let (trunk, _) = trunk_at_the_back();
        assert!(corner.touches(&trunk));
        let mut node = h.nodes[0].clone();
        let rear = |fan: f64| Rear {
            reach: 0.45,
            gap: 0.2,
            fan: fan.to_radians(),
        };
        node.rear = Some(rear(0.0));
        assert!(with(&a, &h, &corner, &p, &node).rear(&[trunk]));
        node.rear = Some(rear(30.0));
        assert!(!with(&a, &h, &corner, &p, &node).rear(&[trunk]));
    }

    /// A body on a pillow against a headboard, facing the foot of the bed: in front of the
    /// pillow's edge the mattress lies 0.17 m lower and goes on for the bed's length. The
    /// shanks cannot hang from so low a step: it is no seat's front edge, and the headboard
    /// no backrest, under the built-in backrest's `rear` rule (a seat's edge drops 0.22 m
    /// and more below its top). A chair's seat with the floor in front keeps its back.
    #[test]
    fn a_pillows_edge_is_no_seats_front_edge() {
        let (a, h, backrest) = built_in_sitting();
        let node = &h.nodes[backrest];
        assert!(node.rear.is_some());
        // The pillow's top at 0.45 m (0.35 m deep, from the headboard at x = 0), the
        // mattress at 0.28 m from its edge on; the chair: a 0.45 m seat, the floor beyond.
        let mut pillow = seat_and_back(35, false);
        let mut chair = seat_and_back(45, false);
        for i in 36..=200 {
            for j in 0..=60 {
                let (x, y) = (f64::from(i) * 0.01, -0.3 + f64::from(j) * 0.01);
                pillow.push(Point3::new(x, y, 0.28));
                if i > 45 {
                    chair.push(Point3::new(x, y, 0.0));
                }
            }
        }
        let scene = |pts| Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene);
        let (pillow, chair) = (scene(pillow), scene(chair));
        let p = seated(0.15);
        let (trunk, _) = trunk_at_the_back();
        assert!(pillow.touches(&trunk) && chair.touches(&trunk));
        assert!(with(&a, &h, &chair, &p, node).rear(&[trunk]));
        assert!(!with(&a, &h, &pillow, &p, node).rear(&[trunk]));
    }

    #[test]
    fn rear_accepts_a_chair_back_and_refuses_a_headboard() {
        use crate::model::hierarchy::Rear;
        let (a, h) = models();
        let scene = |length: usize| {
            Scene::new(
                &PointCloud::new(seat_and_back(length, false)),
                &DetectConfig::default().scene,
            )
        };
        let (chair, bed) = (scene(45), scene(200));
        // The pelvis 0.15 m in front of the back; a trunk leaning 1 cm into the back.
        let p = seated(0.15);
        let (trunk, away) = trunk_at_the_back();
        assert!(chair.touches(&trunk) && bed.touches(&trunk));
        let mut node = h.nodes[0].clone();
        // The stick is 1 m tall: the seat may go on 0.45 m in front of the pelvis.
        node.rear = Some(Rear {
            reach: 0.45,
            gap: 0.2,
            fan: 0.0,
        });
        assert!(with(&a, &h, &chair, &p, &node).rear(&[trunk]));
        assert!(!with(&a, &h, &bed, &p, &node).rear(&[trunk]));
        // A pillow's shadow across the mattress in front of the pelvis (nothing seen at
        // x = 0.25-0.45): the mattress goes on beyond it, and the headboard stays refused;
        // with the floor seen through the gap, the seat ends there.
        let cut = |floor: bool| {
            let mut pts = seat_and_back(200, false);
            pts.retain(|q| (q.z - 0.45).abs() > 1e-9 || !(0.25..=0.45).contains(&q.x));
            if floor {
                for i in 25..=45 {
                    for j in -30..=30 {
                        pts.push(Point3::new(f64::from(i) * 0.01, f64::from(j) * 0.01, 0.0));
                    }
                }
            }
            Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
        };
        let (shadowed, gap) = (cut(false), cut(true));
        assert!(!with(&a, &h, &shadowed, &p, &node).rear(&[trunk]));
        assert!(with(&a, &h, &gap, &p, &node).rear(&[trunk]));
        // A part that touches nothing, or a node without the rule, is not refused.
        assert!(with(&a, &h, &bed, &p, &node).rear(&[away]));
        node.rear = None;
        assert!(with(&a, &h, &bed, &p, &node).rear(&[trunk]));
    }

    #[test]
    fn behind_accepts_a_seat_with_its_back_or_rear_edge_and_refuses_a_beds_edge() {
        let (a, h) = models();
        // A top at 0.45 m from x = `from` to 0.45 (its front edge), 0.6 m wide, points 1 cm
        // apart, with `more` points added; the body sits facing +x, its pelvis joint at x =
        // 0.15, 8 cm over the top.
        let scene = |from: i32, more: &dyn Fn(&mut Vec<Point3<f64>>)| {
            let mut pts = Vec::new();
            for i in from..=45 {
                for j in -30..=30 {
                    pts.push(Point3::new(f64::from(i) * 0.01, f64::from(j) * 0.01, 0.45));
                }
            }
            more(&mut pts);
            Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
        };
        // Points 1 cm apart over x in `xs` (cm), all y of the top, z in `zs` (cm).
        let block = |xs: std::ops::RangeInclusive<i32>, zs: std::ops::RangeInclusive<i32>| {
            move |pts: &mut Vec<Point3<f64>>| {
                for i in xs.clone() {
                    for j in -30..=30 {
                        for k in zs.clone() {
                            let (x, y) = (f64::from(i) * 0.01, f64::from(j) * 0.01);
                            pts.push(Point3::new(x, y, f64::from(k) * 0.01));
                        }
                    }
                }
            }
        };
        let p = seated(0.15);
        let mut node = h.nodes[0].clone();
        // The stick is 1 m tall: the seat may go on 0.35 m behind the pelvis.
        node.behind = Some(Behind {
            reach: 0.35,
            gap: 0.2,
            rise: 0.15,
            top: 0.6,
        });
        let behind = |s: &Scene, node: &Node| with(&a, &h, s, &p, node).behind();
        // A seat with its back 0.15 m behind the pelvis (a sofa, an armchair).
        let sofa = scene(0, &block(-5..=-1, 45..=100));
        assert!(behind(&sofa, &node));
        // A bench 0.45 m deep, the floor seen behind it: its rear edge.
        let bench = scene(0, &block(-60..=-5, 0..=0));
        assert!(behind(&bench, &node));
        // A bed 2 m wide: the mattress goes on behind the body, also past a pillow lying
        // flat on it (its top 2 cm over the pelvis joint) and under a shelf 0.8 m over it.
        let bed = scene(-160, &|_| {});
        assert!(!behind(&bed, &node));
        let pillow = scene(-160, &block(-30..=-10, 46..=55));
        assert!(!behind(&pillow, &node));
        let shelf = scene(-160, &block(-50..=0, 133..=135));
        assert!(!behind(&shelf, &node));
        // A wall 0.30 m behind the pelvis ends it (a sofa's back against a wall).
        let wall = scene(-160, &block(-15..=-14, 0..=120));
        assert!(behind(&wall, &node));
        // Without the rule, nothing is refused.
        node.behind = None;
        assert!(behind(&bed, &node));
    }

    #[test]
    fn narrow_accepts_an_arm_and_refuses_a_table_beside() {
        let (a, h) = models();
        // A top at 0.70 m on the body's left (`side` 1: +y) or right (-1) from |y| = 0.20 to
        // `to_cm` cm, x -0.2 to 0.4, as points 1 cm apart: an arm 0.10 m wide, or a table
        // 1 m wide.
        let scene = |to_cm: usize, side: f64| {
            let mut pts = Vec::new();
            for i in 0..=60 {
                for j in 20..=to_cm {
                    pts.push(Point3::new(
                        -0.2 + i as f64 * 0.01,
                        side * j as f64 * 0.01,
                        0.70,
                    ));
                }
            }
            Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
        };
        let (arm, table) = (scene(30, 1.0), scene(120, 1.0));
        let p = seated(0.0);
        // A forearm along x over y = 0.25, its underside 1 cm below the top.
        let r = 0.02;
        let forearm = Cylinder {
            joint: 1,
            a: Point3::new(0.0, 0.25, 0.69 + r),
            b: Point3::new(0.25, 0.25, 0.69 + r),
            radius: r,
        };
        assert!(arm.touches(&forearm) && table.touches(&forearm));
        let mut node = h.nodes[0].clone();
        node.support_gap = 0.06;
        // The stick is 1 m tall: what holds the arm ends within 0.25 m outwards.
        node.narrow = Some(0.25);
        assert!(with(&a, &h, &arm, &p, &node).narrow(&[forearm]));
        assert!(!with(&a, &h, &table, &p, &node).narrow(&[forearm]));
        // The same on the right side, mirrored, and without the rule.
        let mirror = |q: Point3<f64>| Point3::new(q.x, -q.y, q.z);
        let right = Cylinder {
            a: mirror(forearm.a),
            b: mirror(forearm.b),
            ..forearm
        };
        assert!(with(&a, &h, &scene(30, -1.0), &p, &node).narrow(&[right]));
        assert!(!with(&a, &h, &scene(120, -1.0), &p, &node).narrow(&[right]));
        node.narrow = None;
        assert!(with(&a, &h, &table, &p, &node).narrow(&[forearm]));
    }

    #[test]
    fn release_accepts_a_top_and_refuses_a_side() {
        let (a, h) = models();
        let s = box_scene();
        let p = place(1.0);
        let node = h.nodes[0].clone();
        let c = with(&a, &h, &s, &p, &node);
        let r = 0.02;
        // Lying on the top (the top's voxels reach about 0.46 m), 1 cm into it.
        let on_top = Cylinder {
            joint: 1,
            a: Point3::new(0.2, 0.0, 0.46 + r - 0.01),
            b: Point3::new(0.5, 0.0, 0.46 + r - 0.01),
            radius: r,
        };
        // Standing against the front face, 1 cm into it.
        let at_side = Cylinder {
            joint: 1,
            a: Point3::new(0.61 + r - 0.01, 0.0, 0.1),
            b: Point3::new(0.61 + r - 0.01, 0.0, 0.35),
            radius: r,
        };
        assert!(s.intersects(&on_top) && s.intersects(&at_side));
        assert!(c.release(&[on_top]));
        assert!(!c.release(&[at_side]));
        // Held from above instead: the top no longer holds.
        let mut down = node.clone();
        down.release = Some(Vector3::new(0.0, 0.0, -1.0));
        assert!(!with(&a, &h, &s, &p, &down).release(&[on_top]));
        // No release direction: any contact holds.
        let mut none = node.clone();
        none.release = None;
        assert!(with(&a, &h, &s, &p, &none).release(&[at_side]));
    }

    #[test]
    fn a_nodes_release_angle_overrides_the_hierarchys() {
        let (a, h) = models();
        let s = box_scene();
        let p = place(1.0);
        let r = 0.02;
        // Along the top's front edge, 1 cm into the corner: the scene's normal there leans
        // forward from up, between the top's and the side's.
        let on_edge = Cylinder {
            joint: 1,
            a: Point3::new(0.61 + r - 0.01, -0.15, 0.46 + r - 0.01),
            b: Point3::new(0.61 + r - 0.01, 0.15, 0.46 + r - 0.01),
            radius: r,
        };
        assert!(s.intersects(&on_edge));
        let n = s.contact_normal(&on_edge).expect("a normal at the edge");
        let tilt = n.z.clamp(-1.0, 1.0).acos();
        assert!(tilt > 10f64.to_radians() && tilt < 80f64.to_radians());
        let mut node = h.nodes[0].clone();
        node.release = Some(Vector3::z());
        let wide = (tilt + 5f64.to_radians()).cos();
        let narrow = (tilt - 5f64.to_radians()).cos();
        node.release_cos = Some(wide);
        assert!(with(&a, &h, &s, &p, &node).release(&[on_edge]));
        node.release_cos = Some(narrow);
        assert!(!with(&a, &h, &s, &p, &node).release(&[on_edge]));
        // Without one, the hierarchy's support angle decides.
        node.release_cos = None;
        let mut h2 = h.clone();
        h2.score.support_cos = narrow;
        assert!(!with(&a, &h2, &s, &p, &node).release(&[on_edge]));
        h2.score.support_cos = wide;
        assert!(with(&a, &h2, &s, &p, &node).release(&[on_edge]));
    }

    #[test]
    fn support_needs_the_scene_within_the_gap_below() {
        let (a, h) = models();
        let s = box_scene();
        let mut node = h.nodes[0].clone();
        node.support = vec![(1, [0.0, 1.0])];
        node.support_gap = 0.05;
        let mut posture = a.rest_posture();
        // Halfway through the sweep the leg is level (hip -90), pointing forwards over the box.
        for (gap, held) in [(0.03, true), (0.2, false)] {
            let p = place(0.46 + 0.02 + gap);
            let c = with(&a, &h, &s, &p, &node);
            c.start(&mut posture);
            assert_eq!(
                c.support(&posture, &[0], 0.5),
                held,
                "{gap} m above the top"
            );
        }
    }

    /// A bar 4 cm wide across the leg's way (x 0.30 to 0.34, along y), its top at
    /// z = 0.45, on a leg of its own; points 1 cm apart.
    fn bar_scene() -> Scene {
        let mut pts = Vec::new();
        for j in 0..=60 {
            let y = -0.3 + j as f64 * 0.01;
            for i in 0..=4 {
                pts.push(Point3::new(0.30 + i as f64 * 0.01, y, 0.45));
            }
            for k in 0..45 {
                pts.push(Point3::new(0.32, y, k as f64 * 0.01));
            }
        }
        Scene::new(&PointCloud::new(pts), &DetectConfig::default().scene)
    }

    #[test]
    fn a_support_share_asks_the_link_to_rest_along_its_span() {
        let (a, h) = models();
        let mut node = h.nodes[0].clone();
        // The leg's first 40 cm (x 0.15 to 0.55 when level), 3 cm above the top.
        node.support = vec![(1, [0.0, 0.8])];
        node.support_gap = 0.05;
        let p = place(0.46 + 0.02 + 0.03);
        for (scene, share, held) in [
            (box_scene(), None, true),
            (box_scene(), Some(0.5), true),
            // The bar holds 4 of the 40 cm: one sample is enough, half is not.
            (bar_scene(), None, true),
            (bar_scene(), Some(0.5), false),
            (bar_scene(), Some(0.05), true),
        ] {
            node.support_share = share;
            let c = with(&a, &h, &scene, &p, &node);
            let mut posture = a.rest_posture();
            c.start(&mut posture);
            assert_eq!(c.support(&posture, &[0], 0.5), held, "share {share:?}");
        }
    }

    #[test]
    fn a_branch_comes_down_onto_the_top_and_is_held_from_below_only() {
        let (a, h) = models();
        let s = box_scene();
        // The pelvis 10 cm above the top: the leg, lowered from above, touches the top
        // below level.
        let p = place(0.46 + 0.02 + 0.1);
        let node = h.nodes[0].clone();
        let c = with(&a, &h, &s, &p, &node);
        let mut posture = a.rest_posture();
        c.start(&mut posture);
        let (hit, local) = c.sweep_branch(&mut posture, &[0], &[1]);
        let hip = posture.angles[1].to_degrees();
        assert!(hit.is_some(), "the leg touches the top");
        assert!(
            (-90.0..-60.0).contains(&hip),
            "touches below level: hip {hip}"
        );
        assert!(local > h.score.epsilon, "{local}");
        // Held from above instead: the contact does not count, Eq. 2 keeps its angle.
        let mut down = node.clone();
        down.release = Some(Vector3::new(0.0, 0.0, -1.0));
        let c = with(&a, &h, &s, &p, &down);
        let mut posture = a.rest_posture();
        c.start(&mut posture);
        let (hit, local) = c.sweep_branch(&mut posture, &[0], &[1]);
        assert_eq!(hit, None);
        assert_eq!(local, h.score.epsilon);
        assert!((posture.angles[1].to_degrees() - hip).abs() < 1e-9);
    }

    #[test]
    fn norms_and_local_score() {
        assert_eq!(t_norm(0.5, 0.4), 0.2);
        assert!((t_conorm(0.5, 0.4) - 0.7).abs() < 1e-12);
        assert_eq!(t_conorm(0.0, 0.3), 0.3);
        let s = 20f64.to_radians();
        assert_eq!(local_score(Some(0.0), s, 0.1), 1.0);
        // One sigma off: exp(-1/2).
        assert!((local_score(Some(s * s), s, 0.1) - (-0.5f64).exp()).abs() < 1e-12);
        assert_eq!(local_score(None, s, 0.1), 0.1);
    }
}
