//! The affordance hierarchy A of section 3.2: an initial pose H_A and a rooted tree of
//! fine-grained affordances F = (J_F, E_F), each edge carrying a true/false constraint,
//! plus the hypothesis rule (section 4.1) and the fitting and scoring parameters
//! (sections 4.2-4.4) that the paper leaves free.
//!
//! Angles in the file are degrees; lengths are metres unless the key says "fraction of H".

use std::collections::BTreeMap;
use std::path::Path;

use nalgebra::{Unit, Vector3};
use serde::Deserialize;

use crate::method::fuzzy::{Availability, Low, Trapezoid};
use crate::model::agent::{Agent, Posture};
use crate::model::{parse_toml, read_text, tree_order, Key, ModelError, Source, TreeWords};

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
    /// Where the gradient gives no heading, the search of every heading starts facing away
    /// from the top of the tallest thing near the place: the cells of the gradient
    /// neighbourhood within this height (metres) of its highest (an extension: the order
    /// then follows the scene, not the frame); absent: the highest cells only.
    #[serde(default)]
    pub facing_tolerance: Option<f64>,
    /// Where the plane fit's descent points more than 90 degrees from facing away from
    /// that top (it climbs towards it), the facing heading replaces it (an extension: a
    /// larger, lower surface beyond the seat, such as the table a chair is pushed in at,
    /// turns the fit round); absent: false, the descent is kept.
    #[serde(default)]
    pub facing_overrules: bool,
    /// "Discontinuity is low": share of invalid cells under the template.
    pub discontinuity: Low,
    /// "Roughness is low": standard deviation of heights under the template, metres.
    pub roughness: Low,
    /// Cells this far (metres) below the template's median height are gaps, counted as
    /// missing rather than as roughness, where the template is rougher than `roughness`
    /// fully allows (an extension: the floor seen through a slatted seat); absent: every
    /// valid cell counts towards the roughness, as in the paper.
    #[serde(default)]
    pub hole_depth: Option<f64>,
    /// Cells this far (metres) above the template's median height are something standing
    /// over the seat's edge (a back, an arm, a desk top over its front), counted as
    /// missing rather than as roughness, where the template is rougher than `roughness`
    /// fully allows (an extension); absent: they count towards the roughness.
    #[serde(default)]
    pub rise_height: Option<f64>,
    /// "Height is comfortable": mean height under the template, fractions of H;
    /// absent to switch the height membership off.
    #[serde(default)]
    pub height: Option<Trapezoid>,
    /// The same membership in metres, whatever the body's height (an extension, instead
    /// of `height`, never with it): for surfaces whose usable heights are the furniture's,
    /// not the body's (beds up to about 0.70 m, tables from 0.72 m).
    #[serde(default)]
    pub height_m: Option<Trapezoid>,
    /// The availability sets used for defuzzification (Fig. 5d).
    pub available: Availability,
    /// Distance between the cells tried, fraction of H (an extension: a lying body is
    /// 1.7 m long, so places 5 cm apart are the same place); absent: every cell.
    #[serde(default)]
    pub spacing: Option<f64>,
    /// The surface the body rests on, measured around the place (an extension): how wide
    /// it must be, and where the gradient is flat, the heading from its long axis; absent:
    /// no width asked and every heading tried where it is flat.
    #[serde(default)]
    pub surface: Option<SurfaceRule>,
    /// A flat rectangle of the surface's least width round the place (an extension, with
    /// `surface` only): the body's middle lies on a level surface as wide as a bed, not
    /// across a corner or a seat's front; absent: the width alone is asked.
    #[serde(default)]
    pub flat: Option<FlatRule>,
    /// A second height membership for small tops (an extension): where the top round the
    /// place is no longer than a stool's, a seat higher than `height` allows is perched on
    /// (a bar stool); absent: `height` alone.
    #[serde(default)]
    pub perch: Option<PerchRule>,
    /// Whether the places and the scene hold the seats hidden behind backs and arms
    /// ([`crate::method::hidden`]; an extension): a seat inferred from the walls that hid
    /// it, at their level less a drop, as wide as their hull. Absent: true. Without them
    /// the hierarchy sees the scan with its holes filled only.
    #[serde(default = "yes")]
    pub hidden_seats: bool,
}

/// Seats above the comfortable height that a person perches on, told from table tops by
/// the size of the top (an extension of section 4.1's height membership): a bar stool is
/// 0.30-0.45 m across, tables, counters and cabinets 0.6 m and more. Where the top round
/// a place (the cells within `tolerance` of the template's mean height, reached from the
/// place, as [`crate::method::hypotheses::surface`] measures it) is at most `max_length`
/// long and drops `rim_drop` round all but `max_walled` of its rim, the place is rated as
/// a small top (what lies below its level missing) with the larger of the rule's
/// `height` and this one's `height`.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PerchRule {
    /// "Height is comfortable to perch on": mean height under the template, fractions of H.
    pub height: Trapezoid,
    /// Radius of the neighbourhood measured, fraction of H: it must reach past the
    /// longest top that is still a perch.
    pub radius: f64,
    /// Cells within this height (metres) of the template's mean height are on the top.
    pub tolerance: f64,
    /// Longest top perched on, along its long axis, fraction of H (the extent of a
    /// rectangle with the same spread: `sqrt(12)` standard deviations of its cells).
    pub max_length: f64,
    /// Largest share of the cells bounding the top that may not drop `rim_drop` below it
    /// (a stool's back on one side), 0 to 1: a top made small by the things standing on
    /// it (a patch of a cluttered desk), or standing on something (a box on a desk), is no
    /// perch.
    pub max_walled: f64,
    /// Least drop (metres) from the top to a cell bounding it for the cell to be the top's
    /// rim, where the legs hang: the floor or a stool's ring.
    pub rim_drop: f64,
}

/// The flat surface round a place (an extension of section 4.1): the cells at the level of
/// the template's mean height, reached from the place without crossing an edge. Lying
/// needs a bed's width, which the template (the width of the back) cannot tell from a sofa
/// seat; and in the middle of a bed the gradient is flat and gives no heading, but the
/// mattress is longer than it is wide and a body lies along it.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceRule {
    /// Radius of the neighbourhood measured, fraction of H.
    pub radius: f64,
    /// Cells within this height (metres) of the template's mean height are on the surface.
    pub tolerance: f64,
    /// Cells up to this height (metres) above the template's mean height are folds lying
    /// on the surface (a duvet's), crossed, and counted where it goes on beyond them at
    /// its level or is not seen there. `None`: no folds, the cells within `tolerance` only.
    #[serde(default)]
    pub rise: Option<f64>,
    /// Least width of the surface across its long axis, fraction of H.
    pub min_width: f64,
    /// Least ratio of the surface's spread along its long axis to its spread across
    /// (standard deviations) for the axis to give a heading where the gradient is flat.
    pub elongation: f64,
    /// Where the scan runs on unseen across the surface, how far below its level (metres)
    /// something seen in the column of its last cell ends it there (a seat's front face,
    /// the floor under an open seat); a mattress cut by the image edge shows only its top.
    /// `None`: nothing ends it.
    #[serde(default)]
    pub face: Option<f64>,
}

/// A flat rectangle round a place (an extension of section 4.1, with [`SurfaceRule`]): the
/// surface's least width (`min_width`) across and `length` along, at the place's level
/// (its `tolerance` below, its `rise` above; unseen cells are no edge), in one of the
/// orientations `turn` apart, shifted across by up to `shift`. The width of the surface
/// round the place (the spread of its cells) passes where two seats meet at a corner; a
/// body lies on a rectangle, and is laid along one that is flat
/// ([`crate::method::hypotheses::flat_rectangles`]).
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FlatRule {
    /// Length of the rectangle along the body, centred on the place, fraction of H.
    pub length: f64,
    /// Half the length of the rectangle's middle, fraction of H: a rise there is off the
    /// level; beyond it, at an end, a rise is the surface going up (a reclined back, a
    /// raised leg rest) where it runs across the whole width.
    pub middle: f64,
    /// Largest angle, degrees, between such a rise and the rectangle's width.
    pub square: f64,
    /// Largest share of the rectangle's samples (one per cell) seen off its level.
    pub off: f64,
    /// Furthest the rectangle's centre line is shifted across from the place, metres.
    pub shift: f64,
    /// Step between the orientations tried, degrees (over half a turn); a body is laid
    /// within half of it of one that is flat.
    pub turn: f64,
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
    /// Where the initial pose touches the scene at `start_clearance`, the start tried
    /// instead, metres above the same cell (an extension: a table's underside over the
    /// thighs of a chair pushed in); `None`: that heading is given up.
    pub low_start: Option<f64>,
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
    /// Links a node unfolds afterwards that are checked while fitting, except when no
    /// heading fits with them: then the fit is tried again without them, so that arms
    /// raised for an armrest do not lose a seat whose arm rails they meet (joint indices).
    pub deferred_links: Vec<usize>,
    /// Links tested by their lower half only (a cylinder of half the radius along their
    /// underside) in a last try, when no heading fits even without `deferred_links`: a
    /// desk's underside or drawer over the thighs of a chair pushed in under it does not
    /// lose the seat (the chair is pulled out to sit), while what fills the space below
    /// their axis still stops them (joint indices; an extension of section 4.2).
    pub overhang_links: Vec<usize>,
    /// Where no earlier try fits (`deferred_links`, `overhang_links`), the place is tried again moved
    /// this far back along its own heading, nearest first, metres: the free rear of a seat
    /// pushed in under a desk lies behind the place the template found there (the chair is
    /// pulled out to sit); empty: no such try (an extension of section 4.2).
    pub shift_back: Vec<f64>,
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
    /// End angle, radians: above or below theta1 (a sweep may run either way).
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
    /// Joints set to each of several angles in turn, only for a kinematic branch that
    /// found nothing at its own setting (an extension of the paper: where the shanks hang
    /// free with the thighs level, the thighs slope down until the feet reach the floor);
    /// the first setting that touches is kept.
    pub fallbacks: Vec<Fallback>,
    /// Joints held within a range while this node is judged (an extension of the paper:
    /// a headrest is judged at a plausible trunk recline); kept when the node is found.
    pub clamps: Vec<Clamp>,
    /// When set, a contact counts only if the scene holds the touching links from the side
    /// opposite this direction (agent frame: x forward, z up): `[0, 0, 1]` means "from
    /// below", so an armrest counts and a wall beside the arm does not.
    pub release: Option<nalgebra::Vector3<f64>>,
    /// Cosine of the largest angle between a contact's normal and `release` for this
    /// node, where it is narrower or wider than the hierarchy's
    /// ([`ScoreRule::support_cos`]); `None` keeps the hierarchy's.
    pub release_cos: Option<f64>,
    /// Whether a contact already at theta1 is refused: the links had no room to unfold
    /// (shanks that start in a mattress are not hanging from a seat).
    pub free_start: bool,
    /// Whether one touching kinematic branch suffices for the affordance, or all must touch.
    pub contact: ContactRule,
    /// Parts that must rest on the scene at a contact (an extension of the paper: lying
    /// needs the back of the head and the heels supported, not only the trunk): at the
    /// contact, every support link (joint index, span) the branch moves must have the
    /// scene within `support_gap` straight below some sample of its span (with
    /// `support_share`, below that share of them). Empty: any contact counts.
    pub support: Vec<(usize, [f64; 2])>,
    /// See `support`, metres.
    pub support_gap: f64,
    /// Least share of each support entry's samples (along its span) that must have the
    /// scene within `support_gap` below (an extension: an armrest carries the forearm
    /// along its length, a chair back crossed at an angle only at one point). `None`:
    /// one sample suffices.
    pub support_share: Option<f64>,
    /// A support part over a column of space in which the scan saw nothing within this
    /// many metres (horizontally) of the vertical line below it is not refuted and counts
    /// as resting: a bed cut by the image edge, or whose far end the camera cannot see.
    /// `None`: only a surface counts.
    pub unseen_reach: Option<f64>,
    /// Joints (indices) among the node's sweeps whose branch may touch nothing over its
    /// whole sweep (nor anything a rule refused) where its support parts, at the preferred
    /// angles, then hang over space the scan never saw (`unseen_reach`): the legs of a body
    /// on a bed the image edge cuts across at the hips. Such a branch neither refutes
    /// `contact = "all"` nor changes the node's local score; at least one branch must still
    /// touch, and one rest on a surface the scan saw. Never where the place's width is
    /// unknown too ([`crate::method::hypotheses::Hypothesis::unseen_width`]). Empty: every
    /// branch must touch.
    pub unseen_sweeps: Vec<usize>,
    /// What the node finds lies beside the body, not across in front of it (`None`: no
    /// such test).
    pub beside: Option<Beside>,
    /// What the node finds stands at the rear of a seat, not at the head of a bed (`None`:
    /// no such test).
    pub rear: Option<Rear>,
    /// What the node finds is a rest of a seat, not of a bed's edge: the seat ends behind
    /// the body (`None`: no such test).
    pub behind: Option<Behind>,
    /// What the node finds stands at the edge of the surface the body sits on, not on it
    /// (`None`: no such test).
    pub beyond: Option<Beyond>,
    /// Fraction of H: what the node's parts rest on ends within this far outwards from
    /// them, away from the body's midplane, within `support_gap` below (an armrest is a
    /// rest for one arm, a table top beside the body goes on). `None`: no such test.
    pub narrow: Option<f64>,
    /// Where the node finds nothing at the fit's place, the body slides back on its seat
    /// and the node is tried again (`None`: no slide).
    pub slide: Option<Slide>,
}

/// A node's `slide`: where the node finds nothing at the place the fit found, the body, in
/// the posture the node starts from, is moved back along its heading by each of `steps`
/// in turn (metres, nearest first) while it stays clear of the scene when lifted by
/// `lift` metres, and the node is unfolded there; the first place where it is found is
/// kept, for the nodes below it and the reported pose. A person settles back into a seat
/// deeper than the place leaves behind the pelvis (the place stands at least the template's
/// radius in front of a back). Lifted, the parts resting on the seat and the feet on the
/// floor are clear of them, while a back, an arm or the seat's front edge against the
/// hanging shanks ends the slide (an extension of section 4.4: the root joint unfolds
/// too).
#[derive(Debug, Clone, PartialEq)]
pub struct Slide {
    /// Metres back along the heading, increasing.
    pub steps: Vec<f64>,
    /// Metres the body is lifted for the test that it is clear of the scene.
    pub lift: f64,
}

/// A node's `rear` rule: a contact counts only if, from the root joint along the
/// horizontal part of the contact's normal (away from what was touched: forwards, for a
/// back behind the trunk), the surface the body sits on ends within `reach`. A seat ends
/// a thigh's length or so in front of its back; in front of a bed's headboard, or a bunk
/// bed's post, the mattress goes on for a body's length, and sitting with the back
/// against it puts the legs on the mattress (the conventions' bed rule).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rear {
    /// Fraction of the body height H: how far in front of the root joint the seat may go on.
    pub reach: f64,
    /// Metres below the root joint within which the scene counts as the seat going on.
    pub gap: f64,
    /// Radians either side of the contact's normal along which the seat must end too: a
    /// seat ends in front of its back across the thighs' width, not along one line.
    pub fan: f64,
}

/// A node's `behind` rule: a contact counts only if the seat the body sits on ends behind
/// it: walking from the root joint against the body's heading, within `reach` something
/// rises over the walk, between `rise` and `top` metres above the root joint (a back, a
/// wall behind a backless seat), or the surface ends
/// ([`crate::method::scene::Scene::seat_ends`], over unseen space as for `rear`, within
/// `gap` below). A rest belongs to a seat with its back, or its rear edge, a seat's depth
/// behind the sitter; a body on a bed's side edge has the mattress going on behind it for
/// the bed's width, and a bed's end board beside it is no armrest, nor a bag behind it a
/// backrest (the conventions' bed rule; an extension).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Behind {
    /// Fraction of the body height H: how far behind the root joint the seat may go on.
    pub reach: f64,
    /// Metres below the root joint within which the scene counts as the seat going on.
    pub gap: f64,
    /// Metres above the root joint from which something in a column counts as rising
    /// over the seat (a duvet's lumps or a pillow lying flat stay below).
    pub rise: f64,
    /// Metres above the root joint up to which it is looked for (a shelf or an upper
    /// bunk higher over the seat is not its end).
    pub top: f64,
}

/// A node's `beyond` rule: a contact counts only if, walking on from where the part comes
/// closest to the scene, away from the body (into what was touched, along the horizontal
/// part of the contact's normal; outwards from the body's midplane where the normal is
/// near vertical, as for a forearm resting on something), level with the top of the part,
/// the surface the body sits on does not go on beyond what was touched within `reach`
/// ([`crate::method::scene::Scene::goes_on_beyond`], with the root joint's height as the
/// seat's level). A back or an arm stands at the edge of a seat, with the floor, a wall or
/// nothing the scan saw beyond it; a pillow, a fold of a duvet or a lamp lies on the
/// surface sat on, which goes on beyond it (an extension: the paper's nodes judge only the
/// angle of the contact).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beyond {
    /// Fraction of the body height H: how far the walk goes on from the part.
    pub reach: f64,
    /// Metres below the root joint within which a surface counts as the seat going on.
    pub gap: f64,
    /// Metres the seat must go on beyond what was touched, at least.
    pub length: f64,
    /// Metres above the root joint up to which a surface still counts as the seat going
    /// on (a duvet's lumps lift a mattress round a body sunk into it).
    pub rise: f64,
}

/// A node's `beside` rule: a contact counts only if, over the body's midplane along the
/// link `over` (moved sideways onto the midplane: the lap, for a thigh), nothing of the
/// scene lies within `gap` metres below the height of each touching part's underside. An
/// armrest carries the forearm at the body's side with the lap free between the arms; a
/// table edge touched by the forearm runs on across in front of the body.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Beside {
    /// Metres below the touching part's underside.
    pub gap: f64,
    /// The link whose axis, moved onto the midplane, is searched.
    pub over: usize,
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

/// A joint tried at further angles (radians), in order, for a kinematic branch whose sweep
/// found nothing: the links it moves and the branch's sweeps do not (the thigh, for a hip
/// under a knee sweep) must then be free of the scene over the span `free` of their length.
#[derive(Debug, Clone, PartialEq)]
pub struct Fallback {
    /// Joint index in the agent.
    pub joint: usize,
    /// Angles tried after the node's own setting, radians, in order.
    pub angles: Vec<f64>,
    /// The part of each link it moves that must be free, fractions `[from, to]` of its length.
    pub free: [f64; 2],
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
    /// How detections are drawn (pictures, meshes, segment files): affordance ids with
    /// their sRGB colours, coarsest first; a detection takes the colour of the last entry
    /// it affords. From the file's `legend`, or, without one, every node in node order
    /// with the colours of [`NODE_PALETTE`].
    pub legend: Vec<(String, [u8; 3])>,
}

/// Colours given to the nodes of a hierarchy file that has no `legend`, in node order
/// (cycled): distinct hues that read on white and on the height map's viridis.
pub const NODE_PALETTE: [[u8; 3]; 8] = [
    [255, 140, 0],
    [225, 35, 150],
    [40, 160, 255],
    [120, 230, 40],
    [140, 80, 220],
    [230, 200, 0],
    [0, 185, 185],
    [170, 110, 60],
];

/// A hierarchy file; `F` and `S` are its `[fit]` and `[score]` tables, complete
/// ([`FitFile`], [`ScoreFile`]) or, in a file that shares them, as written (`toml::Table`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File<F = FitFile, S = ScoreFile> {
    name: String,
    orientation: Orientation,
    suppression_radius: f64,
    /// A hierarchy (built-in name or file beside this one) whose `[fit]` and `[score]`
    /// values this file takes where it gives none.
    #[serde(default)]
    shares: Option<String>,
    hypothesis: HypothesisRule,
    fit: F,
    score: S,
    initial_pose: BTreeMap<String, f64>,
    node: Vec<NodeFile>,
    #[serde(default)]
    legend: Vec<LegendFile>,
}

/// One entry of the file's `legend`: an affordance id and its colour (sRGB, 0-255).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LegendFile {
    id: String,
    colour: [u8; 3],
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FitFile {
    yaw_offsets: Vec<f64>,
    fallback_yaw_step: f64,
    start_clearance: f64,
    #[serde(default)]
    low_start: Option<f64>,
    max_drop: f64,
    sigma_d: f64,
    min_stability: f64,
    stability_band: f64,
    sample_spacing: f64,
    stability_links: Vec<String>,
    #[serde(default)]
    unchecked_links: Vec<String>,
    #[serde(default)]
    deferred_links: Vec<String>,
    #[serde(default)]
    overhang_links: Vec<String>,
    #[serde(default)]
    shift_back: Vec<f64>,
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
    fallback: Vec<FallbackFile>,
    #[serde(default)]
    clamp: Vec<ClampFile>,
    #[serde(default)]
    release: Option<[f64; 3]>,
    #[serde(default)]
    release_angle: Option<f64>,
    #[serde(default)]
    free_start: bool,
    #[serde(default)]
    contact: ContactRule,
    #[serde(default)]
    support: Vec<LinkRef>,
    #[serde(default)]
    support_gap: f64,
    #[serde(default)]
    support_share: Option<f64>,
    #[serde(default)]
    unseen_reach: Option<f64>,
    #[serde(default)]
    unseen_sweeps: Vec<String>,
    #[serde(default)]
    beside: Option<BesideFile>,
    #[serde(default)]
    rear: Option<RearFile>,
    #[serde(default)]
    behind: Option<BehindFile>,
    #[serde(default)]
    beyond: Option<BeyondFile>,
    #[serde(default)]
    narrow: Option<f64>,
    #[serde(default)]
    slide: Option<SlideFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SlideFile {
    steps: Vec<f64>,
    lift: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BeyondFile {
    reach: f64,
    gap: f64,
    length: f64,
    #[serde(default)]
    rise: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BehindFile {
    reach: f64,
    gap: f64,
    rise: f64,
    top: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RearFile {
    reach: f64,
    gap: f64,
    #[serde(default)]
    fan: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BesideFile {
    gap: f64,
    over: String,
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

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FallbackFile {
    joint: String,
    angles: Vec<f64>,
    #[serde(default = "whole")]
    free: [f64; 2],
}

fn whole() -> [f64; 2] {
    [0.0, 1.0]
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
        Self::from_toml(&read_text(path)?, path, agent)
    }

    /// Parses hierarchy TOML text (`path` only names the source in errors).
    pub fn from_toml(text: &str, path: &Path, agent: &Agent) -> Result<Hierarchy, ModelError> {
        let src = Source { path, text };
        let raw: File<toml::Table, toml::Table> = parse_toml(text, path)?;
        let file: File = match &raw.shares {
            None => parse_toml(text, path)?,
            Some(other) => {
                let other = other.clone();
                shared(&other, raw, src)?
            }
        };
        Self::resolve(file, src, agent)
    }

    fn resolve(file: File, src: Source, agent: &Agent) -> Result<Hierarchy, ModelError> {
        check_numbers(&file, src)?;
        check_limits(&file, src)?;
        let names = Names { src, agent };
        let mut initial = agent.rest_posture();
        for (name, deg) in &file.initial_pose {
            let key = Key::top("initial_pose").key(name);
            let j = names.joint(&key, name)?;
            if !deg.is_finite() {
                return Err(src.invalid(&key, "must be a finite angle"));
            }
            names.within_limit(&key, j, &agent.joints[j].axis, *deg)?;
            initial.angles[j] = deg.to_radians();
        }
        let fit = Key::top("fit");
        let stability_links =
            names.links(&fit.key("stability_links"), &file.fit.stability_links)?;
        if stability_links.is_empty() {
            return Err(src.invalid(
                &fit.key("stability_links"),
                "needs at least one link (what rests on the seat)",
            ));
        }
        let unchecked_links =
            names.links(&fit.key("unchecked_links"), &file.fit.unchecked_links)?;
        let deferred_links = names.links(&fit.key("deferred_links"), &file.fit.deferred_links)?;
        let overhang_links = names.links(&fit.key("overhang_links"), &file.fit.overhang_links)?;
        let key = |i: usize| Key::top("node").item(i, &file.node[i].id);
        let order = tree_order(
            src,
            &TreeWords {
                item: "node",
                name_key: "id",
            },
            file.node.len(),
            key,
            |i| &file.node[i].id,
            |i| file.node[i].parent.as_deref(),
        )?;
        let nodes = order
            .into_iter()
            .map(|(i, parent)| resolve_node(&file.node[i], &key(i), parent, &names))
            .collect::<Result<Vec<_>, _>>()?;
        let legend = resolve_legend(&file, src, &nodes)?;
        let f = &file.fit;
        Ok(Hierarchy {
            name: file.name,
            orientation: file.orientation,
            hypothesis: file.hypothesis,
            fit: FitRule {
                yaw_offsets: f.yaw_offsets.iter().map(|d| d.to_radians()).collect(),
                fallback_yaw_step: f.fallback_yaw_step.to_radians(),
                start_clearance: f.start_clearance,
                low_start: f.low_start,
                max_drop: f.max_drop,
                sigma_d: f.sigma_d,
                min_stability: f.min_stability,
                stability_band: f.stability_band,
                sample_spacing: f.sample_spacing,
                stability_links,
                unchecked_links,
                deferred_links,
                overhang_links,
                shift_back: f.shift_back.clone(),
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
            legend,
        })
    }

    /// The affordance ids, in node order (root first).
    pub fn ids(&self) -> Vec<&str> {
        self.nodes.iter().map(|n| n.id.as_str()).collect()
    }
}

/// The file `raw`, whose `shares = "OTHER"`, with the `[fit]` and `[score]` values it
/// leaves out taken from the hierarchy OTHER (a built-in name, or a file beside it, which
/// may not share another's itself): values the hierarchies have in common (the scores'
/// widths, the fit's stability rule) stand in one file, with their reasons. Keys of `raw`
/// keep their lines in errors; a problem of the tables that result names the table.
fn shared(
    other: &str,
    raw: File<toml::Table, toml::Table>,
    src: Source,
) -> Result<File, ModelError> {
    let key = Key::top("shares");
    let (base_path, base_text) = src.referred(
        &key,
        other,
        crate::model::set::BUILTIN_HIERARCHIES,
        "affordances",
        "hierarchy",
    )?;
    let base: File<toml::Table, toml::Table> = parse_toml(&base_text, &base_path)?;
    if base.shares.is_some() {
        return Err(src.invalid(&key, format!("`{other}` shares another's values itself")));
    }
    fn merge<T: serde::de::DeserializeOwned>(
        table: &str,
        own: toml::Table,
        theirs: toml::Table,
        other: &str,
        src: Source,
    ) -> Result<T, ModelError> {
        let mut all = theirs;
        all.extend(own);
        toml::Value::Table(all)
            .try_into()
            .map_err(|e: toml::de::Error| {
                let what = format!("with `{other}`'s values: {}", e.message().trim());
                src.invalid(&Key::top(table), what)
            })
    }
    Ok(File {
        name: raw.name,
        orientation: raw.orientation,
        suppression_radius: raw.suppression_radius,
        shares: raw.shares,
        hypothesis: raw.hypothesis,
        fit: merge("fit", raw.fit, base.fit, other, src)?,
        score: merge("score", raw.score, base.score, other, src)?,
        initial_pose: raw.initial_pose,
        node: raw.node,
        legend: raw.legend,
    })
}

/// The hierarchy's legend: the file's `legend` (every id a node's, none twice), or every
/// node in node order with the colours of [`NODE_PALETTE`].
fn resolve_legend(
    file: &File,
    src: Source,
    nodes: &[Node],
) -> Result<Vec<(String, [u8; 3])>, ModelError> {
    if file.legend.is_empty() {
        return Ok(nodes
            .iter()
            .zip(NODE_PALETTE.iter().cycle())
            .map(|(n, c)| (n.id.clone(), *c))
            .collect());
    }
    let mut legend: Vec<(String, [u8; 3])> = Vec::with_capacity(file.legend.len());
    for (i, e) in file.legend.iter().enumerate() {
        let key = Key::top("legend").item(i, &e.id).key("id");
        if !nodes.iter().any(|n| n.id == e.id) {
            return Err(src.invalid(&key, format!("`{}` is not the id of a node", e.id)));
        }
        if legend.iter().any(|(id, _)| *id == e.id) {
            return Err(src.invalid(&key, format!("`{}` is listed twice", e.id)));
        }
        legend.push((e.id.clone(), e.colour));
    }
    Ok(legend)
}

/// What a number of the hierarchy file must be.
#[derive(Debug, Clone, Copy)]
enum Bound {
    /// Finite and above 0.
    Positive,
    /// Finite and at least 0.
    NonNegative,
    /// Between 0 and 1, both included.
    Fraction,
}

impl Bound {
    fn holds(self, v: f64) -> bool {
        match self {
            Bound::Positive => v.is_finite() && v > 0.0,
            Bound::NonNegative => v.is_finite() && v >= 0.0,
            Bound::Fraction => (0.0..=1.0).contains(&v),
        }
    }

    fn what(self, v: f64) -> String {
        match self {
            Bound::Positive => format!("must be positive, not {v}"),
            Bound::NonNegative => format!("must not be negative, not {v}"),
            Bound::Fraction => format!("must be between 0 and 1, not {v}"),
        }
    }
}

/// The largest (or smallest) values the hypothesis and fit numbers may take: beyond them
/// the work grows without bound (template cells with the square of the diameter, samples
/// with 1 / spacing, drop steps with the clearance) and no body is described any more.
/// Each entry: key, value, least, most, reason.
fn check_limits(file: &File, src: Source) -> Result<(), ModelError> {
    let (hyp, fit) = (Key::top("hypothesis"), Key::top("fit"));
    let (h, f) = (&file.hypothesis, &file.fit);
    for (key, v, lo, hi, why) in [
        (
            hyp.key("template_diameter"),
            h.template_diameter,
            0.0,
            2.0,
            "fraction of H: a template wider than two bodies holds no place a body rests on",
        ),
        (
            hyp.key("gradient_radius"),
            h.gradient_radius,
            0.0,
            2.0,
            "fraction of H: a neighbourhood beyond two bodies is no longer the seat's",
        ),
        (
            hyp.key("spacing"),
            h.spacing.unwrap_or(0.1),
            0.0,
            2.0,
            "fraction of H: places further apart than two bodies miss whole seats",
        ),
        (
            hyp.key("surface").key("radius"),
            h.surface.map_or(0.5, |a| a.radius),
            0.0,
            2.0,
            "fraction of H: beyond two bodies the surface measured is no longer the place's",
        ),
        (
            hyp.key("surface").key("min_width"),
            h.surface.map_or(0.4, |a| a.min_width),
            0.0,
            2.0,
            "fraction of H: a surface wider than two bodies is asked of no place a body rests on",
        ),
        (
            hyp.key("flat").key("length"),
            h.flat.map_or(0.6, |a| a.length),
            0.0,
            2.0,
            "fraction of H: a rectangle longer than two bodies is no longer the place's",
        ),
        (
            hyp.key("flat").key("middle"),
            h.flat.map_or(0.05, |a| a.middle),
            0.0,
            2.0,
            "fraction of H: beyond two bodies nothing is the rectangle's middle",
        ),
        (
            hyp.key("flat").key("shift"),
            h.flat.map_or(0.25, |a| a.shift),
            0.0,
            2.0,
            "metres: a rectangle shifted further than a body's length is no longer round the place",
        ),
        (
            hyp.key("perch").key("radius"),
            h.perch.map_or(0.3, |p| p.radius),
            0.0,
            2.0,
            "fraction of H: beyond two bodies the top measured is no longer the place's",
        ),
        (
            Key::top("suppression_radius"),
            file.suppression_radius,
            0.0,
            10.0,
            "fraction of H: beyond ten bodies one detection would hide a whole building",
        ),
        (
            fit.key("start_clearance"),
            f.start_clearance,
            0.0,
            2.0,
            "metres: the body starts just above the seat; the drop search grows with it",
        ),
        (
            fit.key("low_start"),
            f.low_start.unwrap_or(0.0),
            0.0,
            f.start_clearance,
            "metres: between the seat and `start_clearance`",
        ),
        (
            fit.key("max_drop"),
            f.max_drop,
            0.0,
            3.0,
            "metres: further below a seat than a room is high is no support",
        ),
        (
            fit.key("sample_spacing"),
            f.sample_spacing,
            0.001,
            1.0,
            "metres: under 1 mm (a fifth of the 5 mm contact step) adds samples, not accuracy",
        ),
        (
            fit.key("fallback_yaw_step"),
            f.fallback_yaw_step,
            0.5,
            360.0,
            "degrees: finer than half a degree (720 headings) only multiplies the fits",
        ),
    ] {
        if !(lo..=hi).contains(&v) {
            return Err(src.invalid(&key, format!("{v} is outside {lo}-{hi} ({why})")));
        }
    }
    let shifts = fit.key("shift_back");
    if f.shift_back.len() > MAX_SHIFTS {
        return Err(src.invalid(
            &shifts,
            format!(
                "{} entries, at most {MAX_SHIFTS} (each is a fit at every heading)",
                f.shift_back.len()
            ),
        ));
    }
    if let Some(v) = f.shift_back.iter().find(|v| !(0.0..=1.0).contains(*v)) {
        return Err(src.invalid(
            &shifts,
            format!(
                "{v} is outside 0-1 (metres: a place moved further than a metre is another place)"
            ),
        ));
    }
    Ok(())
}

/// Most entries of `[fit] shift_back` (each is a fit of the place at every heading) and of
/// a node's `slide.steps` (each unfolds the node again).
const MAX_SHIFTS: usize = 16;

/// Checks the numbers of the hypothesis, fit and score sections.
fn check_numbers(file: &File, src: Source) -> Result<(), ModelError> {
    let (hyp, fit, score) = (Key::top("hypothesis"), Key::top("fit"), Key::top("score"));
    let (h, f, s) = (&file.hypothesis, &file.fit, &file.score);
    use Bound::*;
    for (key, v, bound) in [
        (hyp.key("template_diameter"), h.template_diameter, Positive),
        (hyp.key("gradient_radius"), h.gradient_radius, Positive),
        (hyp.key("flat_gradient"), h.flat_gradient, NonNegative),
        (
            Key::top("suppression_radius"),
            file.suppression_radius,
            Positive,
        ),
        (fit.key("fallback_yaw_step"), f.fallback_yaw_step, Positive),
        (fit.key("start_clearance"), f.start_clearance, NonNegative),
        (fit.key("max_drop"), f.max_drop, NonNegative),
        (fit.key("sigma_d"), f.sigma_d, Positive),
        (fit.key("min_stability"), f.min_stability, Fraction),
        (fit.key("stability_band"), f.stability_band, NonNegative),
        (fit.key("sample_spacing"), f.sample_spacing, Positive),
        (score.key("sigma_theta"), s.sigma_theta, Positive),
        (score.key("epsilon"), s.epsilon, Positive),
        (score.key("epsilon"), s.epsilon, Fraction),
        (score.key("min_local"), s.min_local, Fraction),
    ] {
        if !bound.holds(v) {
            return Err(src.invalid(&key, bound.what(v)));
        }
    }
    if !(0.0..=180.0).contains(&s.support_angle) {
        return Err(src.invalid(
            &score.key("support_angle"),
            format!("must be 0-180 degrees, not {}", s.support_angle),
        ));
    }
    if let Some(v) = h.hole_depth {
        if !Positive.holds(v) {
            return Err(src.invalid(&hyp.key("hole_depth"), Positive.what(v)));
        }
    }
    if let Some(v) = h.rise_height {
        if !Positive.holds(v) {
            return Err(src.invalid(&hyp.key("rise_height"), Positive.what(v)));
        }
    }
    if let Some(v) = h.facing_tolerance {
        if !NonNegative.holds(v) {
            return Err(src.invalid(&hyp.key("facing_tolerance"), NonNegative.what(v)));
        }
    }
    if let Some(v) = h.spacing {
        if !Positive.holds(v) {
            return Err(src.invalid(&hyp.key("spacing"), Positive.what(v)));
        }
    }
    if let Some(a) = h.surface {
        let surface = hyp.key("surface");
        for (key, v) in [
            ("radius", a.radius),
            ("tolerance", a.tolerance),
            ("min_width", a.min_width),
        ] {
            if !Positive.holds(v) {
                return Err(src.invalid(&surface.key(key), Positive.what(v)));
            }
        }
        if let Some(v) = a.rise {
            if !NonNegative.holds(v) {
                return Err(src.invalid(&surface.key("rise"), NonNegative.what(v)));
            }
        }
        if let Some(v) = a.face {
            if !Positive.holds(v) {
                return Err(src.invalid(&surface.key("face"), Positive.what(v)));
            }
        }
        if !(a.elongation.is_finite() && a.elongation >= 1.0) {
            return Err(src.invalid(
                &surface.key("elongation"),
                format!(
                    "must be at least 1 (a ratio of spreads), not {}",
                    a.elongation
                ),
            ));
        }
    }
    if let Some(a) = h.flat {
        let flat = hyp.key("flat");
        if h.surface.is_none() {
            return Err(src.invalid(
                &flat,
                "needs the surface rule ([hypothesis] surface): the rectangle is as wide as its min_width",
            ));
        }
        for (key, v, bound) in [
            ("length", a.length, Positive),
            ("middle", a.middle, NonNegative),
            ("off", a.off, Fraction),
            ("shift", a.shift, NonNegative),
        ] {
            if !bound.holds(v) {
                return Err(src.invalid(&flat.key(key), bound.what(v)));
            }
        }
        if !(a.square.is_finite() && (0.0..90.0).contains(&a.square)) {
            return Err(src.invalid(
                &flat.key("square"),
                format!("must be 0 to 90 degrees (less than 90), not {}", a.square),
            ));
        }
        if !(a.turn.is_finite() && a.turn >= 1.0 && a.turn <= 90.0) {
            return Err(src.invalid(
                &flat.key("turn"),
                format!("must be 1 to 90 degrees, not {}", a.turn),
            ));
        }
    }
    if let Some(k) = f.yaw_offsets.iter().position(|y| !y.is_finite()) {
        return Err(src.invalid(&fit.key("yaw_offsets").at(k), "must be finite"));
    }
    // Fuzzy sets: their breakpoints in order.
    let mut sets = vec![
        (
            hyp.key("discontinuity"),
            vec![h.discontinuity.full, h.discontinuity.zero],
        ),
        (
            hyp.key("roughness"),
            vec![h.roughness.full, h.roughness.zero],
        ),
        (hyp.key("available"), h.available.rise.to_vec()),
    ];
    if h.height.is_some() && h.height_m.is_some() {
        return Err(src.invalid(
            &hyp.key("height_m"),
            "is `height` in metres: give one of the two, not both".to_string(),
        ));
    }
    if let Some(t) = h.height {
        sets.push((hyp.key("height"), vec![t.a, t.b, t.c, t.d]));
    }
    if let Some(t) = h.height_m {
        sets.push((hyp.key("height_m"), vec![t.a, t.b, t.c, t.d]));
    }
    if let Some(p) = h.perch {
        let perch = hyp.key("perch");
        for (key, v) in [
            ("radius", p.radius),
            ("tolerance", p.tolerance),
            ("max_length", p.max_length),
            ("rim_drop", p.rim_drop),
        ] {
            if !Positive.holds(v) {
                return Err(src.invalid(&perch.key(key), Positive.what(v)));
            }
        }
        if !(0.0..=1.0).contains(&p.max_walled) {
            return Err(src.invalid(
                &perch.key("max_walled"),
                format!("must be a share from 0 to 1, not {}", p.max_walled),
            ));
        }
        if p.max_length > 2.0 * p.radius {
            return Err(src.invalid(
                &perch.key("max_length"),
                format!(
                    "must be at most the neighbourhood's diameter (2 x radius = {}), not {}",
                    2.0 * p.radius,
                    p.max_length
                ),
            ));
        }
        let t = p.height;
        sets.push((perch.key("height"), vec![t.a, t.b, t.c, t.d]));
    }
    for (key, points) in sets {
        if points.iter().any(|v| !v.is_finite()) || points.windows(2).any(|w| w[0] > w[1]) {
            return Err(src.invalid(
                &key,
                format!("needs finite values in increasing order, not {points:?}"),
            ));
        }
    }
    Ok(())
}

/// Resolves joint and link names of a hierarchy file against the agent.
struct Names<'a> {
    src: Source<'a>,
    agent: &'a Agent,
}

impl Names<'_> {
    /// Checks that `deg` (degrees, about `axis`) is within the agent's limit of joint `j`.
    /// An angle about the joint's own axis is compared as it is, about the reversed axis
    /// with its sign turned; about any other axis there is no limit to compare with.
    fn within_limit(
        &self,
        key: &Key,
        j: usize,
        axis: &Unit<Vector3<f64>>,
        deg: f64,
    ) -> Result<(), ModelError> {
        let joint = &self.agent.joints[j];
        let along = joint.axis.dot(axis);
        let own = if along > 1.0 - 1e-9 {
            deg
        } else if along < -1.0 + 1e-9 {
            -deg
        } else {
            return Ok(());
        };
        let (lo, hi) = (joint.limit.0.to_degrees(), joint.limit.1.to_degrees());
        // A tolerance for the round trip of the limit through radians.
        if own < lo - 1e-9 || own > hi + 1e-9 {
            return Err(self.src.invalid(
                key,
                format!(
                    "joint `{}` at {own} deg is outside its limit {lo:.1} to {hi:.1} deg (agent `{}`)",
                    joint.name, self.agent.name
                ),
            ));
        }
        Ok(())
    }

    fn joint(&self, key: &Key, name: &str) -> Result<usize, ModelError> {
        self.agent.joint_index(name).ok_or_else(|| {
            self.src.invalid(
                key,
                format!(
                    "unknown joint `{name}` (not in agent `{}`)",
                    self.agent.name
                ),
            )
        })
    }

    fn link(&self, key: &Key, name: &str) -> Result<usize, ModelError> {
        self.agent.link_index(name).ok_or_else(|| {
            self.src.invalid(
                key,
                format!("unknown link `{name}` (not in agent `{}`)", self.agent.name),
            )
        })
    }

    /// The links named by the array at `key`, each named once.
    fn links(&self, key: &Key, names: &[String]) -> Result<Vec<usize>, ModelError> {
        let mut out = Vec::with_capacity(names.len());
        for (k, name) in names.iter().enumerate() {
            let l = self.link(&key.at(k), name)?;
            if out.contains(&l) {
                return Err(self
                    .src
                    .invalid(&key.at(k), format!("link `{name}` is listed twice")));
            }
            out.push(l);
        }
        Ok(out)
    }
}

/// Resolves one node (`key` locates it in the file; `parent` is its parent's index in
/// the ordered nodes).
fn resolve_node(
    n: &NodeFile,
    key: &Key,
    parent: Option<usize>,
    names: &Names,
) -> Result<Node, ModelError> {
    let (src, agent) = (names.src, names.agent);
    let (links, spans): (Vec<usize>, Vec<[f64; 2]>) =
        spanned_links(&n.links, &key.key("links"), names)?
            .into_iter()
            .unzip();
    let support = spanned_links(&n.support, &key.key("support"), names)?;
    if !(n.support_gap.is_finite() && n.support_gap >= 0.0) {
        return Err(src.invalid(&key.key("support_gap"), "must be 0 or more metres"));
    }
    let beside = match &n.beside {
        None => None,
        Some(b) => {
            // A gap of a metre or more below a forearm is no longer "across in front of it".
            Some(Beside {
                gap: gap_under_a_metre(src, &key.key("beside").key("gap"), b.gap)?,
                over: names.link(&key.key("beside").key("over"), &b.over)?,
            })
        }
    };
    // The walks of `rear`, `behind` and `beyond`: a reach in H and a gap below the pelvis
    // under a metre (a metre below the pelvis is the floor under any seat).
    let walk = |name: &str, reach: f64, gap: f64| -> Result<(f64, f64), ModelError> {
        let key = key.key(name);
        Ok((
            fraction_of_h(src, &key.key("reach"), reach)?,
            gap_under_a_metre(src, &key.key("gap"), gap)?,
        ))
    };
    // Another length of such a rule, in metres under a metre.
    let metres =
        |rule: &str, name: &str, m: f64| gap_under_a_metre(src, &key.key(rule).key(name), m);
    let rear = n
        .rear
        .as_ref()
        .map(|r| {
            let (reach, gap) = walk("rear", r.reach, r.gap)?;
            if !(r.fan.is_finite() && (0.0..90.0).contains(&r.fan)) {
                return Err(src.invalid(
                    &key.key("rear").key("fan"),
                    format!("must be 0 to under 90 degrees, not {}", r.fan),
                ));
            }
            Ok(Rear {
                reach,
                gap,
                fan: r.fan.to_radians(),
            })
        })
        .transpose()?;
    let behind = n
        .behind
        .as_ref()
        .map(|r| {
            let (reach, gap) = walk("behind", r.reach, r.gap)?;
            let top = metres("behind", "top", r.top)?;
            let rise = metres("behind", "rise", r.rise)?;
            if rise >= top {
                return Err(src.invalid(
                    &key.key("behind").key("rise"),
                    format!("must be under `top` ({top} m), not {rise}"),
                ));
            }
            Ok::<_, ModelError>(Behind {
                reach,
                gap,
                rise,
                top,
            })
        })
        .transpose()?;
    let beyond = n
        .beyond
        .as_ref()
        .map(|r| {
            let (reach, gap) = walk("beyond", r.reach, r.gap)?;
            let length = metres("beyond", "length", r.length)?;
            let rise = metres("beyond", "rise", r.rise)?;
            Ok::<_, ModelError>(Beyond {
                reach,
                gap,
                length,
                rise,
            })
        })
        .transpose()?;
    let narrow = n
        .narrow
        .map(|w| fraction_of_h(src, &key.key("narrow"), w))
        .transpose()?;
    let slide = match &n.slide {
        None => None,
        Some(sl) => {
            let steps = key.key("slide").key("steps");
            if sl.steps.is_empty() || sl.steps.len() > MAX_SHIFTS {
                return Err(src.invalid(
                    &steps,
                    format!(
                        "{} entries, at least 1 and at most {MAX_SHIFTS} (each unfolds the node again)",
                        sl.steps.len()
                    ),
                ));
            }
            // A body slid further than a metre sits on another seat.
            if let Some(v) = sl.steps.iter().find(|v| !(**v > 0.0 && **v <= 1.0)) {
                return Err(src.invalid(&steps, format!("{v} is outside 0-1 (metres, over 0)")));
            }
            if sl.steps.windows(2).any(|w| w[1] <= w[0]) {
                return Err(src.invalid(&steps, "must increase (nearest first)"));
            }
            // Lifted a metre, the body would pass over a chair's back.
            Some(Slide {
                steps: sl.steps.clone(),
                lift: gap_under_a_metre(src, &key.key("slide").key("lift"), sl.lift)?,
            })
        }
    };
    if let Some(v) = n.support_share {
        if !(v > 0.0 && v <= 1.0) {
            return Err(src.invalid(
                &key.key("support_share"),
                format!("must be more than 0 and at most 1, not {v}"),
            ));
        }
    }
    if let Some(r) = n.unseen_reach {
        // Beyond a body's width no gap in a scan is a place the body could rest on.
        if !(r > 0.0 && r <= 1.0) {
            return Err(src.invalid(
                &key.key("unseen_reach"),
                format!("must be more than 0 and at most 1 metre, not {r}"),
            ));
        }
    }
    if links.is_empty() {
        return Err(src.invalid(&key.key("links"), "a node needs at least one link to check"));
    }
    let mut sweeps: Vec<Sweep> = Vec::new();
    for (k, s) in n.sweep.iter().enumerate() {
        let sk = key.key("sweep").item(k, &s.joint);
        let j = names.joint(&sk.key("joint"), &s.joint)?;
        for (name, v) in [
            ("theta1", s.theta1),
            ("theta2", s.theta2),
            ("thetad", s.thetad),
        ] {
            if !v.is_finite() {
                return Err(src.invalid(&sk.key(name), "must be a finite angle"));
            }
        }
        if sweeps.iter().any(|o| o.joint == j) {
            return Err(src.invalid(
                &sk.key("joint"),
                format!("joint `{}` is swept twice", s.joint),
            ));
        }
        if !links.iter().any(|&l| agent.is_descendant(l, j)) {
            return Err(src.invalid(
                &sk.key("joint"),
                format!(
                    "joint `{}` moves none of the node's links, so its sweep can touch nothing",
                    s.joint
                ),
            ));
        }
        let axis = match s.axis {
            None => agent.joints[j].axis,
            Some(a) => {
                let v = Vector3::from(a);
                if !v.norm().is_finite() || v.norm() <= 1e-9 {
                    return Err(src.invalid(&sk.key("axis"), "must be a non-zero vector"));
                }
                Unit::new_normalize(v)
            }
        };
        for (name, v) in [
            ("theta1", s.theta1),
            ("theta2", s.theta2),
            ("thetad", s.thetad),
        ] {
            names.within_limit(&sk.key(name), j, &axis, v)?;
        }
        sweeps.push(Sweep {
            joint: j,
            theta1: s.theta1.to_radians(),
            theta2: s.theta2.to_radians(),
            thetad: s.thetad.to_radians(),
            axis,
        });
    }
    if sweeps.is_empty() {
        return Err(src.invalid(&key.key("sweep"), "a node needs at least one joint sweep"));
    }
    let mut unseen_sweeps = Vec::new();
    for (k, name) in n.unseen_sweeps.iter().enumerate() {
        let uk = key.key("unseen_sweeps").item(k, name);
        let j = names.joint(&uk, name)?;
        if !sweeps.iter().any(|s| s.joint == j) {
            return Err(src.invalid(
                &uk,
                format!("joint `{name}` is not one of the node's sweeps"),
            ));
        }
        if n.unseen_reach.is_none() {
            return Err(src.invalid(
                &uk,
                "needs `unseen_reach`: it says how far from a support part the scan saw nothing",
            ));
        }
        if !unseen_sweeps.contains(&j) {
            unseen_sweeps.push(j);
        }
    }
    let mut spreads: Vec<Spread> = Vec::new();
    for (k, sp) in n.spread.iter().enumerate() {
        let sk = key.key("spread").item(k, &sp.joint);
        let j = joint_with_angles(names, &sk, &sp.joint, &sp.angles)?;
        if sweeps.iter().any(|s| s.joint == j) {
            return Err(src.invalid(
                &sk.key("joint"),
                format!("joint `{}` cannot be both swept and spread", sp.joint),
            ));
        }
        if spreads.iter().any(|o| o.joint == j) {
            return Err(src.invalid(
                &sk.key("joint"),
                format!("joint `{}` is spread twice", sp.joint),
            ));
        }
        spreads.push(Spread {
            joint: j,
            angles: radians_within(names, &sk, j, &sp.angles)?,
        });
    }
    let mut fallbacks: Vec<Fallback> = Vec::new();
    for (k, fb) in n.fallback.iter().enumerate() {
        let fk = key.key("fallback").item(k, &fb.joint);
        let j = joint_with_angles(names, &fk, &fb.joint, &fb.angles)?;
        let [f0, f1] = fb.free;
        if !(0.0..=1.0).contains(&f0) || !(0.0..=1.0).contains(&f1) || f0 > f1 {
            return Err(src.invalid(
                &fk.key("free"),
                format!("[{f0}, {f1}] is not a span within [0, 1]"),
            ));
        }
        if sweeps.iter().any(|s| s.joint == j) || spreads.iter().any(|s| s.joint == j) {
            return Err(src.invalid(
                &fk.key("joint"),
                format!("joint `{}` is already swept or spread", fb.joint),
            ));
        }
        if fallbacks.iter().any(|o| o.joint == j) {
            return Err(src.invalid(
                &fk.key("joint"),
                format!("joint `{}` falls back twice", fb.joint),
            ));
        }
        if !links.iter().any(|&l| agent.is_descendant(l, j)) {
            return Err(src.invalid(
                &fk.key("joint"),
                format!("joint `{}` moves none of the node's links", fb.joint),
            ));
        }
        fallbacks.push(Fallback {
            joint: j,
            angles: radians_within(names, &fk, j, &fb.angles)?,
            free: fb.free,
        });
    }
    let mut clamps = Vec::new();
    for (k, c) in n.clamp.iter().enumerate() {
        let ck = key.key("clamp").item(k, &c.joint);
        let j = names.joint(&ck.key("joint"), &c.joint)?;
        if !(c.lower.is_finite() && c.upper.is_finite()) || c.lower > c.upper {
            return Err(src.invalid(
                &ck.key("lower"),
                format!("lower = {} must not exceed upper = {}", c.lower, c.upper),
            ));
        }
        for (name, v) in [("lower", c.lower), ("upper", c.upper)] {
            names.within_limit(&ck.key(name), j, &agent.joints[j].axis, v)?;
        }
        clamps.push(Clamp {
            joint: j,
            lower: c.lower.to_radians(),
            upper: c.upper.to_radians(),
        });
    }
    let release = match n.release.map(Vector3::from) {
        Some(r) if !r.norm().is_finite() || r.norm() <= 1e-9 => {
            return Err(src.invalid(&key.key("release"), "must be a non-zero direction"))
        }
        r => r,
    };
    let release_cos = match n.release_angle {
        Some(_) if release.is_none() => {
            return Err(src.invalid(
                &key.key("release_angle"),
                "needs `release`, the direction it is measured from",
            ))
        }
        Some(a) if !(0.0..=180.0).contains(&a) => {
            return Err(src.invalid(
                &key.key("release_angle"),
                format!("must be 0-180 degrees, not {a}"),
            ))
        }
        a => a.map(|a| a.to_radians().cos()),
    };
    Ok(Node {
        id: n.id.clone(),
        parent,
        when: n.when,
        links,
        spans,
        sweeps,
        spreads,
        fallbacks,
        clamps,
        release,
        release_cos,
        free_start: n.free_start,
        contact: n.contact,
        support,
        support_gap: n.support_gap,
        support_share: n.support_share,
        unseen_reach: n.unseen_reach,
        unseen_sweeps,
        beside,
        rear,
        behind,
        beyond,
        narrow,
        slide,
    })
}

/// A node rule's reach (`rear`, `narrow`), a fraction of H: over 0 and at most 1 (beyond a
/// body height the rule could never refuse a contact in a room), else an error at `key`.
fn fraction_of_h(src: Source, key: &Key, v: f64) -> Result<f64, ModelError> {
    if v > 0.0 && v <= 1.0 {
        Ok(v)
    } else {
        Err(src.invalid(
            key,
            format!("must be over 0 and at most 1 (a fraction of H), not {v}"),
        ))
    }
}

/// A node rule's gap (`beside`, `rear`, `slide.lift`), metres: 0 or more and under 1, else an error at `key`.
fn gap_under_a_metre(src: Source, key: &Key, gap: f64) -> Result<f64, ModelError> {
    if (0.0..1.0).contains(&gap) {
        Ok(gap)
    } else {
        Err(src.invalid(
            key,
            format!("must be 0 or more and under 1 metre, not {gap}"),
        ))
    }
}

/// Resolves the joint of a `spread` or `fallback` entry (`key` locates the entry) and
/// checks that it lists at least one angle, all finite.
fn joint_with_angles(
    names: &Names,
    key: &Key,
    joint: &str,
    angles: &[f64],
) -> Result<usize, ModelError> {
    let j = names.joint(&key.key("joint"), joint)?;
    if angles.is_empty() || angles.iter().any(|a| !a.is_finite()) {
        return Err(names.src.invalid(&key.key("angles"), "needs finite angles"));
    }
    Ok(j)
}

/// The `angles` (degrees in the file) of joint `j` in radians, each within the joint's
/// limit about its own axis (`key` locates the entry).
fn radians_within(
    names: &Names,
    key: &Key,
    j: usize,
    angles: &[f64],
) -> Result<Vec<f64>, ModelError> {
    for &a in angles {
        names.within_limit(&key.key("angles"), j, &names.agent.joints[j].axis, a)?;
    }
    Ok(angles.iter().map(|a| a.to_radians()).collect())
}

/// Resolves a list of links, each with the span of it that counts, checking each once.
fn spanned_links(
    refs: &[LinkRef],
    key: &Key,
    names: &Names,
) -> Result<Vec<(usize, [f64; 2])>, ModelError> {
    let mut out: Vec<(usize, [f64; 2])> = Vec::new();
    for (k, l) in refs.iter().enumerate() {
        let at = key.at(k);
        let (name, span) = match l {
            LinkRef::Name(name) => (name, [0.0, 1.0]),
            LinkRef::Span { link, span } => (link, *span),
        };
        let index = names.link(&at, name)?;
        if !(0.0..=1.0).contains(&span[0]) || !(0.0..=1.0).contains(&span[1]) || span[0] >= span[1]
        {
            return Err(names.src.invalid(
                &key.item(k, name).key("span"),
                format!("needs 0 <= from < to <= 1, not {span:?}"),
            ));
        }
        if out.iter().any(|(i, _)| *i == index) {
            return Err(names
                .src
                .invalid(&at, format!("link `{name}` is listed twice")));
        }
        out.push((index, span));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::line_of;
    use crate::model::set::{BUILTIN_AGENT, BUILTIN_SITTING};

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

    /// The error loading `text` as `h.toml`.
    fn error(text: &str) -> String {
        load(text).unwrap_err().to_string()
    }

    /// The error of the built-in hierarchy with `from` replaced by `to` (once, checked),
    /// and the line where `to` now stands.
    fn edited(from: &str, to: &str) -> (String, usize) {
        assert_eq!(
            BUILTIN_SITTING.matches(from).count(),
            1,
            "`{from}` is not unique"
        );
        let bad = BUILTIN_SITTING.replace(from, to);
        let line = line_of(&bad, to.lines().last().unwrap_or(to), 0);
        (error(&bad), line)
    }

    /// Asserts that `e` starts with `h.toml:LINE: KEY: ` and mentions `what`.
    fn names(e: &str, line: usize, key: &str, what: &str) {
        assert!(
            e.starts_with(&format!("h.toml:{line}: {key}: ")) && e.contains(what),
            "{e}"
        );
    }

    #[test]
    fn lying_shares_sittings_fit_and_score_values_it_leaves_out() {
        let sitting = load(BUILTIN_SITTING).unwrap();
        let lying = load(crate::model::set::BUILTIN_LYING).unwrap();
        let (f, g) = (&lying.fit, &sitting.fit);
        assert_eq!(
            (f.sigma_d, f.min_stability, f.stability_band, f.max_drop),
            (g.sigma_d, g.min_stability, g.stability_band, g.max_drop)
        );
        assert_eq!(lying.score.sigma_theta, sitting.score.sigma_theta);
        // Its own values stay its own, empty lists included.
        assert_ne!(lying.fit.yaw_offsets, sitting.fit.yaw_offsets);
        assert!((lying.score.support_cos - 60f64.to_radians().cos()).abs() < 1e-12);
        assert!(lying.fit.deferred_links.is_empty() && !sitting.fit.deferred_links.is_empty());
    }

    #[test]
    fn sharing_names_what_is_missing_or_wrong() {
        let dir = tempfile::tempdir().unwrap();
        let base = BUILTIN_SITTING.replace("sigma_d = 0.03", "");
        std::fs::write(dir.path().join("base.toml"), &base).unwrap();
        let own = BUILTIN_SITTING
            .replace("sigma_d = 0.03 ", "# sigma_d from nowhere ")
            .replace(
                "suppression_radius = 0.25 ",
                "shares = \"base.toml\"\nsuppression_radius = 0.25 ",
            );
        let path = dir.path().join("own.toml");
        let err = |text: &str| {
            Hierarchy::from_toml(text, &path, &agent())
                .unwrap_err()
                .to_string()
        };
        // Neither file gives sigma_d.
        let e = err(&own);
        assert!(
            e.contains(": fit: with `base.toml`'s values") && e.contains("sigma_d"),
            "{e}"
        );
        // Given here, it is found; a key of neither kind is refused.
        let given = own.replace("# sigma_d from nowhere ", "sigma_d = 0.03 ");
        assert!(Hierarchy::from_toml(&given, &path, &agent()).is_ok());
        let unknown = given.replace("sigma_d = 0.03 ", "sigma_dd = 0.03 ");
        assert!(err(&unknown).contains("sigma_dd"), "{}", err(&unknown));
        // No such hierarchy; one that shares another's itself.
        let line = line_of(&own, "shares", 0);
        let e = err(&own.replace("base.toml", "nowhere.toml"));
        assert!(
            e.contains(&format!(
                "own.toml:{line}: shares: `nowhere.toml` is neither"
            )),
            "{e}"
        );
        std::fs::write(dir.path().join("base.toml"), &given).unwrap();
        let e = err(&own.replace("# sigma_d from nowhere ", "sigma_d = 0.03 "));
        assert!(e.contains("shares another's values itself"), "{e}");
    }

    #[test]
    fn the_legend_comes_from_the_file_or_the_node_palette() {
        let h = load(BUILTIN_SITTING).unwrap();
        let ids: Vec<&str> = h.legend.iter().map(|(id, _)| id.as_str()).collect();
        // As listed in the file (armrest after backrest: drawn over it), not node order.
        assert_eq!(ids, ["sitting", "backrest", "armrest", "headrest"]);
        assert_eq!(h.legend[0].1, [255, 140, 0]);
        // Without a legend every node gets a palette colour, in node order.
        let start = BUILTIN_SITTING.find("legend = [").unwrap();
        let end = start + BUILTIN_SITTING[start..].find("]\n\n").unwrap() + 2;
        let bare = format!("{}{}", &BUILTIN_SITTING[..start], &BUILTIN_SITTING[end..]);
        let h = load(&bare).unwrap();
        let want: Vec<(String, [u8; 3])> = h
            .ids()
            .iter()
            .zip(NODE_PALETTE)
            .map(|(id, c)| (id.to_string(), c))
            .collect();
        assert_eq!(h.legend, want);
    }

    #[test]
    fn a_legend_entry_names_a_node_once_with_bytes() {
        let (e, line) = edited(
            r#"{ id = "headrest", colour = [120, 230, 40] }"#,
            r#"{ id = "footrest", colour = [120, 230, 40] }"#,
        );
        names(&e, line, "legend.footrest.id", "not the id of a node");
        let (e, line) = edited(
            r#"{ id = "headrest", colour = [120, 230, 40] }"#,
            r#"{ id = "sitting", colour = [120, 230, 40] }"#,
        );
        names(&e, line, "legend.sitting.id", "listed twice");
        let (e, _) = edited(
            r#"{ id = "headrest", colour = [120, 230, 40] }"#,
            r#"{ id = "headrest", colour = [120, 230, 400] }"#,
        );
        assert!(e.starts_with("h.toml:") && e.contains("legend"), "{e}");
    }

    #[test]
    fn every_built_in_sweep_turns_about_its_joints_own_axis() {
        // One sign convention: a hip flexed 90 deg is +90 in sitting and in lying alike.
        let a = agent();
        for (name, text) in crate::model::set::BUILTIN_HIERARCHIES {
            let h = Hierarchy::from_toml(text, Path::new(name), &a).unwrap();
            for n in &h.nodes {
                for s in &n.sweeps {
                    assert_eq!(s.axis, a.joints[s.joint].axis, "{name} {}", n.id);
                }
            }
        }
        let lying = crate::model::set::BUILTIN_HIERARCHIES[1].1;
        let h = Hierarchy::from_toml(lying, Path::new("lying.toml"), &a).unwrap();
        let hip = a.joint_index("hip_l").unwrap();
        let s = h.nodes[0].sweeps.iter().find(|s| s.joint == hip).unwrap();
        assert_eq!(s.thetad.to_degrees().round(), 90.0);
    }

    #[test]
    fn a_sweep_may_run_downwards() {
        let a = agent();
        let text =
            BUILTIN_SITTING.replace("theta1 = 0.0, theta2 = 30.0", "theta1 = 30.0, theta2 = 0.0");
        let h = Hierarchy::from_toml(&text, Path::new("h.toml"), &a).unwrap();
        let s = &h.nodes.iter().find(|n| n.id == "headrest").unwrap().sweeps[0];
        assert!(s.theta1 > s.theta2);
    }

    #[test]
    fn angles_beyond_a_joint_limit_are_named_with_value_and_limit() {
        // The neck extends to 60 deg (agents/human.toml).
        let (e, line) = edited("theta1 = 0.0, theta2 = 30.0", "theta1 = 0.0, theta2 = 90.0");
        names(
            &e,
            line,
            "node.headrest.sweep.neck.theta2",
            "joint `neck` at 90 deg is outside its limit -45.0 to 60.0 deg (agent `human`)",
        );
        // The knee flexes from 0 to 150 deg.
        let (e, line) = edited("knee_l = 90.0", "knee_l = -10.0");
        names(
            &e,
            line,
            "initial_pose.knee_l",
            "joint `knee_l` at -10 deg is outside its limit",
        );
    }

    #[test]
    fn fallbacks_are_resolved_and_checked() {
        let h = load(BUILTIN_SITTING).unwrap();
        let hip_l = agent().joint_index("hip_l").unwrap();
        let fb = &h.nodes[0].fallbacks[0];
        assert_eq!(fb.joint, hip_l);
        assert!((fb.angles[1] - 70f64.to_radians()).abs() < 1e-12);
        assert_eq!(fb.free, [0.5, 1.0]);
        // The hip flexes at most 130 deg; a free span must lie within the link.
        let (e, line) = edited(
            "{ joint = \"hip_l\", angles = [80.0, 70.0]",
            "{ joint = \"hip_l\", angles = [80.0, 140.0]",
        );
        names(
            &e,
            line,
            "node.sitting.fallback.hip_l.angles",
            "outside its limit",
        );
        let (e, line) = edited(
            "{ joint = \"hip_r\", angles = [80.0, 70.0], free = [0.5, 1.0]",
            "{ joint = \"hip_r\", angles = [80.0, 70.0], free = [0.5, 1.5]",
        );
        names(&e, line, "node.sitting.fallback.hip_r.free", "not a span");
        // A swept joint cannot fall back as well.
        let (e, line) = edited(
            "{ joint = \"hip_l\", angles = [80.0, 70.0]",
            "{ joint = \"knee_l\", angles = [80.0, 70.0]",
        );
        names(
            &e,
            line,
            "node.sitting.fallback.knee_l.joint",
            "already swept",
        );
    }

    #[test]
    fn a_missing_parent_node_is_named() {
        let (e, line) = edited("parent = \"backrest\"", "parent = \"back\"");
        names(&e, line, "node.headrest.parent", "missing node `back`");
    }

    #[test]
    fn a_cycle_of_nodes_is_named() {
        let (e, line) = edited(
            "id = \"backrest\"\nparent = \"sitting\"",
            "id = \"backrest\"\nparent = \"headrest\"",
        );
        names(&e, line, "node.backrest.parent", "cycle");
        assert!(e.contains("backrest -> headrest -> backrest"), "{e}");
    }

    #[test]
    fn a_duplicate_node_id_is_named_where_repeated() {
        // The node's line (at the start of a line), not the legend's entry.
        let bad = BUILTIN_SITTING.replace("\nid = \"armrest\"", "\nid = \"backrest\"");
        names(
            &error(&bad),
            // The legend's entry, the backrest node, then the repeat.
            line_of(&bad, "id = \"backrest\"", 2),
            "node.backrest.id",
            "duplicate node id",
        );
    }

    #[test]
    fn an_initial_pose_of_an_unknown_joint_is_named() {
        let (e, line) = edited("knee_r = 90.0", "kne_r = 90.0");
        names(&e, line, "initial_pose.kne_r", "unknown joint `kne_r`");
    }

    #[test]
    fn an_unknown_link_is_named() {
        let (e, line) = edited("links = [{ link = \"torso\"", "links = [{ link = \"trunk\"");
        names(&e, line, "node.backrest.links", "unknown link `trunk`");
        let (e, line) = edited(
            "stability_links = [\"pelvis\"]",
            "stability_links = [\"hips\"]",
        );
        names(&e, line, "fit.stability_links", "unknown link `hips`");
    }

    #[test]
    fn a_sweep_that_moves_no_checked_link_is_named() {
        let (e, line) = edited(
            "sweep = [{ joint = \"lumbar\", theta1",
            "sweep = [{ joint = \"neck\", theta1",
        );
        names(&e, line, "node.backrest.sweep.neck.joint", "moves none");
    }

    #[test]
    fn a_number_out_of_range_is_named() {
        let (e, line) = edited("sigma_d = 0.03", "sigma_d = -0.03");
        names(&e, line, "fit.sigma_d", "must be positive");
        let (e, line) = edited(
            "height = [0.14, 0.21, 0.34, 0.40]",
            "height = [0.14, 0.34, 0.21, 0.40]",
        );
        names(&e, line, "hypothesis.height", "increasing order");
    }

    #[test]
    fn a_height_membership_in_metres_is_taken_as_it_is_and_never_beside_one_in_h() {
        let lying = crate::model::set::BUILTIN_LYING;
        let m = "height_m = [0.09, 0.18, 0.665, 0.72]";
        assert_eq!(lying.matches(m).count(), 1);
        let h = load(lying).unwrap().hypothesis;
        assert_eq!((h.height, h.height_m.map(|t| t.d)), (None, Some(0.72)));
        let both = lying.replace(m, &format!("height = [0.05, 0.10, 0.36, 0.40]\n{m}"));
        names(
            &error(&both),
            line_of(&both, m, 0),
            "hypothesis.height_m",
            "not both",
        );
        let unordered = lying.replace(m, "height_m = [0.09, 0.665, 0.18, 0.72]");
        names(
            &error(&unordered),
            line_of(&unordered, "height_m = [0.09, 0.665", 0),
            "hypothesis.height_m",
            "increasing order",
        );
    }

    /// Each of `edits` (`from`, `to`, key, what the error says) made to the inline table
    /// `rule` of `[hypothesis]` in `text` is named by its line and `hypothesis.<table>.<key>`.
    fn each_edit_named(text: &str, rule: &str, table: &str, edits: &[(&str, &str, &str, &str)]) {
        for (from, to, key, what) in edits {
            let to = rule.replace(from, to);
            let bad = text.replace(rule, &to);
            let line = line_of(&bad, &to, 0);
            names(
                &error(&bad),
                line,
                &format!("hypothesis.{table}.{key}"),
                what,
            );
        }
    }

    #[test]
    fn a_bad_surface_rule_is_named() {
        let rule =
            "surface = { radius = 0.5, tolerance = 0.05, rise = 0.10, min_width = 0.40, elongation = 1.3, face = 0.20 }";
        let lying = crate::model::set::BUILTIN_LYING;
        assert_eq!(lying.matches(rule).count(), 1);
        assert!(load(lying).unwrap().hypothesis.surface.is_some());
        each_edit_named(
            lying,
            rule,
            "surface",
            &[
                (
                    "elongation = 1.3",
                    "elongation = 0.5",
                    "elongation",
                    "at least 1",
                ),
                (
                    "min_width = 0.40",
                    "min_width = 0.0",
                    "min_width",
                    "positive",
                ),
                ("radius = 0.5", "radius = 3.0", "radius", "outside"),
                ("rise = 0.10", "rise = -0.1", "rise", "not be negative"),
                ("face = 0.20", "face = 0.0", "face", "positive"),
            ],
        );
    }

    #[test]
    fn a_bad_flat_rule_is_named_and_needs_the_surface_rule() {
        let rule =
            "flat = { length = 0.6, middle = 0.05, square = 15.0, off = 0.05, shift = 0.25, turn = 15.0 }";
        // Off in the built-in lying hierarchy: its line there, commented out, switched on.
        let builtin = crate::model::set::BUILTIN_LYING;
        assert!(load(builtin).unwrap().hypothesis.flat.is_none());
        assert_eq!(builtin.matches(&format!("# {rule}")).count(), 1);
        let lying = &builtin.replace(&format!("# {rule}"), rule);
        assert!(load(lying).unwrap().hypothesis.flat.is_some());
        each_edit_named(
            lying,
            rule,
            "flat",
            &[
                ("length = 0.6", "length = 0.0", "length", "positive"),
                (
                    "middle = 0.05",
                    "middle = -0.1",
                    "middle",
                    "not be negative",
                ),
                ("square = 15.0", "square = 90.0", "square", "0 to 90"),
                ("off = 0.05", "off = 1.5", "off", "between 0 and 1"),
                ("shift = 0.25", "shift = -0.1", "shift", "not be negative"),
                ("length = 0.6", "length = 1e9", "length", "outside"),
                ("turn = 15.0", "turn = 0.0", "turn", "1 to 90"),
            ],
        );
        // Without the surface rule the rectangle has no width: named at `flat`.
        let surface = lying.lines().find(|l| l.starts_with("surface = ")).unwrap();
        let e = error(&lying.replace(surface, ""));
        assert!(
            e.contains("hypothesis.flat") && e.contains("surface"),
            "{e}"
        );
    }

    #[test]
    fn a_bad_hole_depth_is_named() {
        assert_eq!(
            load(BUILTIN_SITTING).unwrap().hypothesis.hole_depth,
            Some(0.25)
        );
        let (e, line) = edited("hole_depth = 0.25", "hole_depth = 0.0");
        names(&e, line, "hypothesis.hole_depth", "positive");
    }

    #[test]
    fn a_bad_slide_is_named() {
        let h = load(BUILTIN_SITTING).unwrap();
        let slides: Vec<(&str, Option<&Slide>)> = h
            .nodes
            .iter()
            .map(|n| (n.id.as_str(), n.slide.as_ref()))
            .collect();
        assert!(slides
            .iter()
            .all(|(id, s)| s.is_some() == (*id == "backrest")));
        let rule = "slide = { steps = [0.05, 0.10, 0.15], lift = 0.02 }";
        let (e, line) = edited(rule, "slide = { steps = [0.10, 0.05], lift = 0.02 }");
        names(&e, line, "node.backrest.slide.steps", "increase");
        let (e, line) = edited(rule, "slide = { steps = [0.0, 0.05], lift = 0.02 }");
        names(&e, line, "node.backrest.slide.steps", "outside 0-1");
        let (e, line) = edited(rule, "slide = { steps = [], lift = 0.02 }");
        names(&e, line, "node.backrest.slide.steps", "at least 1");
        let (e, line) = edited(rule, "slide = { steps = [0.05], lift = 1.0 }");
        names(&e, line, "node.backrest.slide.lift", "under 1 metre");
    }

    #[test]
    fn a_bad_perch_rule_is_named() {
        let perch = load(BUILTIN_SITTING).unwrap().hypothesis.perch.unwrap();
        assert!(perch.max_length <= 2.0 * perch.radius);
        assert!(load(crate::model::set::BUILTIN_LYING)
            .unwrap()
            .hypothesis
            .perch
            .is_none());
        let (e, line) = edited("tolerance = 0.05, max_length", "tolerance = 0, max_length");
        names(&e, line, "hypothesis.perch.tolerance", "positive");
        let (e, line) = edited("max_length = 0.25", "max_length = 0.7");
        names(&e, line, "hypothesis.perch.max_length", "diameter");
        let (e, line) = edited("0.34, 0.36, 0.48, 0.50", "0.34, 0.48, 0.36, 0.50");
        names(&e, line, "hypothesis.perch.height", "increasing order");
        let (e, line) = edited("radius = 0.30, tolerance", "radius = 3.0, tolerance");
        names(&e, line, "hypothesis.perch.radius", "two bodies");
        let (e, line) = edited("max_walled = 0.25", "max_walled = 1.5");
        names(&e, line, "hypothesis.perch.max_walled", "share");
        let (e, line) = edited("rim_drop = 0.20", "rim_drop = -0.2");
        names(&e, line, "hypothesis.perch.rim_drop", "positive");
    }

    #[test]
    fn a_bad_beyond_rule_is_named() {
        let sitting = load(BUILTIN_SITTING).unwrap();
        for id in ["armrest", "backrest"] {
            let node = sitting.nodes.iter().find(|n| n.id == id).unwrap();
            assert_eq!(
                node.beyond.map(|b| (b.reach, b.gap, b.length, b.rise)),
                Some((0.45, 0.2, 0.1, 0.06)),
                "{id}"
            );
        }
        let rule = "beyond = { reach = 0.45, gap = 0.20, length = 0.10, rise = 0.06 }  # length (m): the seat seen through";
        let (e, line) = edited(rule, &rule.replace("length = 0.10", "length = 1.5"));
        names(&e, line, "node.backrest.beyond.length", "under 1 metre");
        let (e, line) = edited(rule, &rule.replace("reach = 0.45", "reach = 0"));
        names(&e, line, "node.backrest.beyond.reach", "over 0");
        let (e, line) = edited(rule, &rule.replace(", length = 0.10", ""));
        names(&e, line, "node.backrest.beyond", "length");
        let (e, line) = edited(rule, &rule.replace("rise = 0.06", "rise = -0.06"));
        names(&e, line, "node.backrest.beyond.rise", "0 or more");
    }

    #[test]
    fn a_bad_unseen_sweeps_is_named() {
        let lying = crate::model::set::BUILTIN_LYING;
        let rule = "unseen_sweeps = [\"hip_l\", \"hip_r\"]";
        assert_eq!(lying.matches(rule).count(), 1);
        let h = load(lying).unwrap();
        let node = h.nodes.iter().find(|n| n.id == "lying").unwrap();
        let hips: Vec<usize> = node.sweeps[1..].iter().map(|s| s.joint).collect();
        assert_eq!(node.unseen_sweeps, hips);
        assert!(h
            .nodes
            .iter()
            .all(|n| n.id == "lying" || n.unseen_sweeps.is_empty()));
        for (to, joint, what) in [
            (
                "unseen_sweeps = [\"hip_l\", \"knee_r\"]",
                "knee_r",
                "not one of the node's sweeps",
            ),
            (
                "unseen_sweeps = [\"hip_l\", \"tail\"]",
                "tail",
                "unknown joint `tail`",
            ),
        ] {
            let bad = lying.replace(rule, to);
            let key = format!("node.lying.unseen_sweeps.{joint}");
            names(&error(&bad), line_of(&bad, to, 0), &key, what);
        }
        // Without `unseen_reach` nothing says how far the scan saw nothing.
        let reach = "unseen_reach = 0.10";
        assert_eq!(lying.matches(reach).count(), 1);
        let bad = lying.replace(reach, "");
        let key = "node.lying.unseen_sweeps.hip_l";
        names(
            &error(&bad),
            line_of(&bad, rule, 0),
            key,
            "needs `unseen_reach`",
        );
    }

    #[test]
    fn a_bad_rise_height_is_named() {
        assert_eq!(
            load(BUILTIN_SITTING).unwrap().hypothesis.rise_height,
            Some(0.10)
        );
        assert_eq!(
            load(crate::model::set::BUILTIN_LYING)
                .unwrap()
                .hypothesis
                .rise_height,
            None
        );
        let (e, line) = edited("rise_height = 0.10", "rise_height = -0.1");
        names(&e, line, "hypothesis.rise_height", "positive");
    }

    #[test]
    fn a_bad_shift_back_is_named() {
        let sitting = load(BUILTIN_SITTING).unwrap();
        assert_eq!(sitting.fit.shift_back, [0.05, 0.10, 0.15, 0.20]);
        let lying = load(crate::model::set::BUILTIN_LYING).unwrap();
        assert!(lying.fit.shift_back.is_empty());
        let from = "shift_back = [0.05, 0.10, 0.15, 0.20]";
        let (e, line) = edited(from, "shift_back = [0.05, 1.5]");
        names(&e, line, "fit.shift_back", "1.5 is outside 0-1");
        let many = format!("shift_back = [{}]", vec!["0.1"; 17].join(", "));
        let (e, line) = edited(from, &many);
        names(&e, line, "fit.shift_back", "17 entries, at most 16");
    }

    #[test]
    fn a_negative_facing_tolerance_is_named() {
        assert_eq!(
            load(BUILTIN_SITTING).unwrap().hypothesis.facing_tolerance,
            Some(0.05)
        );
        let (e, line) = edited("facing_tolerance = 0.05", "facing_tolerance = -0.05");
        names(&e, line, "hypothesis.facing_tolerance", "-0.05");
    }

    #[test]
    fn a_bad_behind_rule_is_named() {
        let sitting = load(BUILTIN_SITTING).unwrap();
        for n in &sitting.nodes {
            let rests = n.id == "armrest" || n.id == "backrest";
            let want = rests.then_some((0.35, 0.20, 0.15, 0.60));
            assert_eq!(
                n.behind.map(|b| (b.reach, b.gap, b.rise, b.top)),
                want,
                "{}",
                n.id
            );
        }
        // The armrest's line, told from the backrest's by the comment line above it.
        let at = "17 -> 10 of 120).\n";
        let rule = format!("{at}behind = {{ reach = 0.35, gap = 0.20, rise = 0.15, top = 0.60 }}");
        for (bad, key, what) in [
            (
                "reach = 0.0, gap = 0.20, rise = 0.15, top = 0.60",
                "reach",
                "over 0",
            ),
            (
                "reach = 0.35, gap = 1.5, rise = 0.15, top = 0.60",
                "gap",
                "under 1 metre",
            ),
            (
                "reach = 0.35, gap = 0.20, rise = 0.15, top = 1.60",
                "top",
                "under 1 metre",
            ),
            (
                "reach = 0.35, gap = 0.20, rise = 0.60, top = 0.60",
                "rise",
                "under `top`",
            ),
        ] {
            let (e, line) = edited(&rule, &format!("{at}behind = {{ {bad} }}"));
            names(&e, line, &format!("node.armrest.behind.{key}"), what);
        }
        let (e, line) = edited(
            &rule,
            &format!("{at}behind = {{ reach = 0.35, gap = 0.20, rise = 0.15 }}"),
        );
        assert!(
            e.contains("top") && e.starts_with(&format!("h.toml:{line}")),
            "{e}"
        );
    }

    #[test]
    fn a_bad_rear_rule_is_named() {
        let rule = "rear = { reach = 0.45, gap = 0.30, fan = 30.0 }";
        assert_eq!(BUILTIN_SITTING.matches(rule).count(), 1);
        let backrest = &load(BUILTIN_SITTING).unwrap().nodes[2];
        assert_eq!(backrest.id, "backrest");
        assert_eq!(
            backrest.rear.map(|r| (r.reach, r.gap, r.fan)),
            Some((0.45, 0.3, 30f64.to_radians()))
        );
        let (e, line) = edited(rule, "rear = { reach = 1.5, gap = 0.30, fan = 30.0 }");
        names(&e, line, "node.backrest.rear.reach", "at most 1");
        let (e, line) = edited(rule, "rear = { reach = 0.45, gap = -0.1, fan = 30.0 }");
        names(&e, line, "node.backrest.rear.gap", "under 1 metre");
        let (e, line) = edited(rule, "rear = { reach = 0.45, gap = 0.30, fan = 90.0 }");
        names(&e, line, "node.backrest.rear.fan", "under 90 degrees");
    }

    #[test]
    fn a_bad_narrow_rule_is_named() {
        let rule = "narrow = 0.25";
        assert_eq!(BUILTIN_SITTING.matches(rule).count(), 1);
        let armrest = &load(BUILTIN_SITTING).unwrap().nodes[1];
        assert_eq!(armrest.narrow, Some(0.25));
        let (e, line) = edited(rule, "narrow = 0.0");
        names(&e, line, "node.armrest.narrow", "over 0 and at most 1");
    }

    #[test]
    fn a_bad_beside_rule_is_named() {
        let rule = "beside = { gap = 0.05, over = \"thigh_l\" }";
        assert_eq!(BUILTIN_SITTING.matches(rule).count(), 1);
        let armrest = &load(BUILTIN_SITTING).unwrap().nodes[1];
        assert_eq!(armrest.id, "armrest");
        assert_eq!(armrest.beside.map(|b| b.gap), Some(0.05));
        let (e, line) = edited(rule, "beside = { gap = 0.05, over = \"lap\" }");
        names(&e, line, "node.armrest.beside.over", "unknown link `lap`");
        let (e, line) = edited(rule, "beside = { gap = 1.5, over = \"thigh_l\" }");
        names(&e, line, "node.armrest.beside.gap", "under 1 metre");
    }

    #[test]
    fn a_bad_release_angle_is_named() {
        let rule = "release_angle = 30.0";
        assert_eq!(BUILTIN_SITTING.matches(rule).count(), 1);
        let h = load(BUILTIN_SITTING).unwrap();
        let armrest = &h.nodes[1];
        assert_eq!(armrest.id, "armrest");
        let cos = armrest.release_cos.expect("the armrest's own angle");
        assert!((cos - 30f64.to_radians().cos()).abs() < 1e-12);
        // The other nodes keep the hierarchy's support angle.
        assert!(h.nodes[2..].iter().all(|n| n.release_cos.is_none()));
        let (e, line) = edited(rule, "release_angle = 200.0");
        names(&e, line, "node.armrest.release_angle", "0-180 degrees");
        let bad = BUILTIN_SITTING.replace(rule, "").replace(
            "free_start = true",
            "free_start = true\nrelease_angle = 20.0",
        );
        let line = line_of(&bad, "release_angle = 20.0", 0);
        names(
            &error(&bad),
            line,
            "node.sitting.release_angle",
            "needs `release`",
        );
    }

    #[test]
    fn a_bad_support_share_is_named() {
        let rule = "support_share = 0.5";
        assert_eq!(BUILTIN_SITTING.matches(rule).count(), 1);
        let armrest = &load(BUILTIN_SITTING).unwrap().nodes[1];
        assert_eq!(armrest.support_share, Some(0.5));
        assert_eq!(armrest.support.len(), 2, "both forearms");
        // Lying keeps one sample enough.
        assert!(load(crate::model::set::BUILTIN_LYING)
            .unwrap()
            .nodes
            .iter()
            .all(|n| n.support_share.is_none()));
        for bad in ["support_share = 0.0", "support_share = 1.5"] {
            let (e, line) = edited(rule, bad);
            names(&e, line, "node.armrest.support_share", "at most 1");
        }
    }

    #[test]
    fn an_unknown_key_is_named_with_its_line() {
        let (e, line) = edited("free_start = true", "free_starts = true");
        names(
            &e,
            line,
            "node.sitting.free_starts",
            "unknown field `free_starts`",
        );
    }
}
