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

use crate::agent::{Agent, Cylinder, Placement, Posture};
use crate::fit::{ContactConfig, Fit};
use crate::hierarchy::{Hierarchy, Node};
use crate::scene::Scene;

/// The outcome of one node.
#[derive(Debug, Clone, PartialEq)]
pub struct NodeOutcome {
    /// Whether the node was processed (its edge constraint matched).
    pub visited: bool,
    /// Whether a contact occurred: the fine-grained affordance is present.
    pub found: bool,
    /// Local score (Eq. 3 combined by the T-norm of Eq. 4); 0 when not visited.
    pub local: f64,
}

/// The agent after unfolding: the goal configuration H_g and what it found.
#[derive(Debug, Clone, PartialEq)]
pub struct Unfolded {
    /// Where the agent is.
    pub placement: Placement,
    /// The goal posture H_g.
    pub posture: Posture,
    /// One outcome per hierarchy node, in node order.
    pub nodes: Vec<NodeOutcome>,
    /// Accumulated score (T-conorm of Eq. 5 over the found nodes' local scores).
    pub score: f64,
    /// Stability of the fit (Eq. 1).
    pub stability: f64,
}

impl Unfolded {
    /// Number of fine-grained affordances found.
    pub fn found(&self) -> usize {
        self.nodes.iter().filter(|n| n.found).count()
    }

    /// Whether `self` ranks above `other` under `select` (ties are not stronger).
    pub fn stronger_than(&self, other: &Unfolded, select: crate::hierarchy::Selection) -> bool {
        self.rank(other, select) == std::cmp::Ordering::Greater
    }

    /// Orders two poses under `select`.
    pub fn rank(
        &self,
        other: &Unfolded,
        select: crate::hierarchy::Selection,
    ) -> std::cmp::Ordering {
        use crate::hierarchy::Selection;
        match select {
            Selection::Score => self.score.total_cmp(&other.score),
            Selection::MostSpecific => self
                .found()
                .cmp(&other.found())
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

/// Unfolds the hierarchy from a fit (sections 4.3 and 4.4).
pub fn unfold(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    fit: &Fit,
    contact: &ContactConfig,
) -> Unfolded {
    let mut posture = fit.posture.clone();
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
            });
            continue;
        }
        let (found, local) =
            unfold_node(agent, h, scene, &fit.placement, &mut posture, node, contact);
        if found {
            score = t_conorm(score, local);
        }
        nodes.push(NodeOutcome {
            visited: true,
            found,
            local,
        });
    }
    Unfolded {
        placement: fit.placement,
        posture,
        nodes,
        score,
        stability: fit.stability,
    }
}

/// Sweeps one node's joints, writing the resulting angles (Eq. 2) into `posture`;
/// returns whether it touched and its local score.
fn unfold_node(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    place: &Placement,
    posture: &mut Posture,
    node: &Node,
    contact: &ContactConfig,
) -> (bool, f64) {
    let before = posture.clone();
    for c in &node.clamps {
        posture.angles[c.joint] = posture.angles[c.joint].clamp(c.lower, c.upper);
    }
    for s in &node.sweeps {
        posture.angles[s.joint] = s.theta1;
        posture.axes[s.joint] = s.axis;
    }
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
    // A spread joint that moves the links of several branches (the trunk leaning sideways
    // moves both arms) is one setting for the whole node: each of its angles is tried with
    // all branches, and the best outcome (found first, then local score) is kept.
    let moves = |sp: &crate::hierarchy::Spread, links: &[usize]| {
        links.iter().any(|&l| agent.is_descendant(l, sp.joint))
    };
    let shared: Vec<&crate::hierarchy::Spread> = node
        .spreads
        .iter()
        .filter(|sp| branch_links.iter().filter(|ls| moves(sp, ls)).count() > 1)
        .collect();
    let shared_settings = shared.iter().map(|sp| sp.angles.len()).max().unwrap_or(1);
    let mut outcome: Option<(bool, f64, Posture)> = None;
    for ks in 0..shared_settings {
        let mut node_posture = posture.clone();
        for sp in &shared {
            node_posture.angles[sp.joint] = sp.angles[ks.min(sp.angles.len() - 1)];
        }
        let mut local = 1.0;
        let mut found = false;
        let mut all_found = true;
        for (branch, links) in branches.iter().zip(&branch_links) {
            // The spread joints that move only this branch's links; each of their angles is tried.
            let spreads: Vec<&crate::hierarchy::Spread> = node
                .spreads
                .iter()
                .filter(|sp| moves(sp, links) && !shared.iter().any(|s| s.joint == sp.joint))
                .collect();
            let settings = spreads.iter().map(|sp| sp.angles.len()).max().unwrap_or(1);
            let mut best: Option<(Option<f64>, f64, Posture)> = None;
            for k in 0..settings {
                let mut trial = node_posture.clone();
                for sp in &spreads {
                    trial.angles[sp.joint] = sp.angles[k.min(sp.angles.len() - 1)];
                }
                let (hit, r) = sweep_branch(
                    agent, h, scene, place, &mut trial, node, branch, links, contact,
                );
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
            if let Some((hit, r, trial)) = best {
                for &s in branch {
                    let j = node.sweeps[s].joint;
                    node_posture.angles[j] = trial.angles[j];
                }
                for sp in &spreads {
                    node_posture.angles[sp.joint] = trial.angles[sp.joint];
                }
                found |= hit.is_some();
                all_found &= hit.is_some();
                local = t_norm(local, r);
            }
        }
        if node.contact == crate::hierarchy::ContactRule::All {
            found &= all_found;
        }
        let better = match &outcome {
            None => true,
            Some((bf, bl, _)) => (found && !*bf) || (found == *bf && local > *bl),
        };
        if better {
            outcome = Some((found, local, node_posture));
        }
    }
    let (found, local, node_posture) = outcome.expect("at least one setting");
    *posture = node_posture;
    // A contact far from every preferred angle is no use of the affordance.
    let found = found && local >= h.score.min_local;
    if !found {
        for c in &node.clamps {
            posture.angles[c.joint] = before.angles[c.joint];
        }
    }
    (found, local)
}

/// Sweeps one kinematic branch of a node from theta1 towards theta2, stopping at the
/// first contact of its links; writes Eq. 2's angles into `posture` and returns the
/// contact parameter and the branch's local score (Eq. 3).
#[allow(clippy::too_many_arguments)]
fn sweep_branch(
    agent: &Agent,
    h: &Hierarchy,
    scene: &Scene,
    place: &Placement,
    posture: &mut Posture,
    node: &Node,
    branch: &[usize],
    links: &[usize],
    contact: &ContactConfig,
) -> (Option<f64>, f64) {
    let speed: f64 = branch
        .iter()
        .map(|&s| {
            let sw = &node.sweeps[s];
            (sw.theta2 - sw.theta1) * agent.reach(sw.joint)
        })
        .sum();
    // Only the branch's joints move; they are rewritten at every step.
    let mut p = posture.clone();
    let mut frames = Vec::new();
    let mut motion = |t: f64, out: &mut Vec<Cylinder>| {
        for &s in branch {
            let sw = &node.sweeps[s];
            p.angles[sw.joint] = sw.theta1 + t * (sw.theta2 - sw.theta1);
        }
        agent.forward_kinematics(place, &p, &mut frames);
        *out = agent.cylinders(&frames, |j| links.contains(&j));
        for c in out.iter_mut() {
            if let Some(k) = node.links.iter().position(|&l| l == c.joint) {
                let [s0, s1] = node.spans[k];
                let (a, d) = (c.a, c.b - c.a);
                c.a = a + d * s0;
                c.b = a + d * s1;
            }
        }
    };
    let mut hit = scene.first_contact(&mut motion, speed.max(1e-9), contact.resolution);
    let mut blocked = None;
    if node.free_start && hit == Some(0.0) {
        blocked = hit.take();
    }
    if let (Some(t), Some(release)) = (hit, node.release) {
        let mut parts = Vec::new();
        motion(t, &mut parts);
        let dir = (nalgebra::Rotation3::from_axis_angle(&nalgebra::Vector3::z_axis(), place.yaw)
            * release)
            .normalize();
        // The parts in contact must be held from the side opposite `release`.
        let supported = parts
            .iter()
            .filter(|c| scene.clearance(c) <= 0.0 && scene.intersects(c))
            .all(|c| {
                scene
                    .contact_normal(c)
                    .is_some_and(|n| n.dot(&dir) >= h.score.support_cos)
            });
        if !supported {
            blocked = hit.take();
        }
    }
    if let Some(t) = hit {
        if !supported(agent, scene, place, &p, node, branch, t) {
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
        local_score(hit.map(|_| sq), h.score.sigma_theta, h.score.epsilon),
    )
}

/// Whether the branch's support parts (if the node has any that the branch moves) rest on
/// the scene at sweep parameter `t`: some part has the scene within `support_gap` below it.
fn supported(
    agent: &Agent,
    scene: &Scene,
    place: &Placement,
    posture: &Posture,
    node: &Node,
    branch: &[usize],
    t: f64,
) -> bool {
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
        return true;
    }
    let mut p = posture.clone();
    for &s in branch {
        let sw = &node.sweeps[s];
        p.angles[sw.joint] = sw.theta1 + t * (sw.theta2 - sw.theta1);
    }
    let mut frames = Vec::new();
    agent.forward_kinematics(place, &p, &mut frames);
    let step = scene.voxel_size();
    agent
        .cylinders(&frames, |j| mine.iter().any(|(l, _)| *l == j))
        .iter()
        .any(|c| {
            let [s0, s1] = mine
                .iter()
                .find(|(l, _)| *l == c.joint)
                .map_or([0.0, 1.0], |m| m.1);
            let d = c.b - c.a;
            let n = ((d.norm() * (s1 - s0)) / step).ceil().max(1.0) as usize;
            (0..=n).any(|i| {
                let q = c.a + d * (s0 + (s1 - s0) * i as f64 / n as f64);
                scene.drop_below(&q, c.radius + node.support_gap) - c.radius <= node.support_gap
            })
        })
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
