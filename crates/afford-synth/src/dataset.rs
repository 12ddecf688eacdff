//! Labelled synthetic datasets: varied furniture, rendered as full models or depth views,
//! written as PLY (binary, with a per-point `part` property) or PCD files plus a
//! `labels.csv` in the format of docs/formats.md:
//! `file,sitting,backrest,armrest,headrest,lying,kind,class,doubtful,points`, then the
//! fine-grained lying columns `elongated_body,raised_body,stretched_legs,raised_legs`
//! appended at the end so that readers of the older columns are unaffected.
//!
//! Labels follow from construction (see [`Labels`]):
//! * `sitting`: a seat 0.25–0.55 m high with the feet on the floor (chairs, stools,
//!   sofas, recliners, benches, beds), and bar stools (seat 0.65–0.80 m, 0.30–0.42 m
//!   across), perched on with the feet on their ring or the floor. Low tables at seat
//!   height are sittable by geometry but negative by convention: `sitting` 0 and a
//!   non-empty `doubtful` column, so that evaluation can report them apart;
//! * `backrest`: a back reaching at least 0.25 m above the seat, or (kind `wall`) a wall within
//!   0.15 m behind a backless seat (not a bed's: see [`wall_backs`]);
//! * `armrest`: arms 0.12–0.35 m above the seat, on the seat's sides;
//! * `headrest`: a back reaching at least 0.70 m above the seat, or (kind `wall`) the wall
//!   0-0.15 m behind the seat;
//! * `lying`: a bed: a flat surface that carries an adult (1.75 m) on the back from head
//!   to heels, at least [`LYING_MIN_LENGTH`] long and [`LYING_MIN_WIDTH`] wide (beds,
//!   daybeds: the wide benches of 0.70 m and more), or a recliner as wide whose back
//!   panel, seat and unfolded leg rest (0–40° above level) measure at least
//!   [`LYING_MIN_RECLINER_LENGTH`] along their surfaces with the back at most 70° above
//!   level. Sofas (seats 0.48–0.66 m deep), narrower benches and recliners are for
//!   sitting, as real furniture labelled by others counts them (docs/conventions.md); the
//!   sofa rule (at least [`LYING_MIN_SOFA_LENGTH`] between the arms) stays, with the same
//!   width asked of the seat, which no drawn sofa has;
//! * fine-grained lying (affordances/lying.toml; all 0 when `lying` is 0):
//!   `elongated_body` (trunk within 25° of level) or `raised_body` (25–70°), and
//!   `stretched_legs` (legs within 15° of level) or `raised_legs` (15–40°). Beds and
//!   daybeds: elongated body, stretched legs. Recliners: the trunk at the back panel's
//!   angle (30–50°: raised body), the legs at the leg rest's (0–25°: stretched up to 15°,
//!   raised above). A sofa that passed the rules would lie flat from 1.6 m between the
//!   arms and be left undecided (empty cells, not scored) below, where its arms under
//!   the head and ankles tilt the trunk and legs across the 25° and 15° borders.
//!
//! Per-point `part` codes ([`afford::mesh::part_code`]): 0 other (legs, frames, floor,
//! walls), 1 seat, 2 backrest, 3 armrest, 4 headrest, 5 lying surface.
//!
//! Scene kinds: `full` (whole model sampled over its surface with light noise, with a
//! floor patch), `view` (one depth view including the floor), `wall` (object with its back
//! against a wall 0–0.15 m behind it, one view), `room` (2–4 non-overlapping objects in a
//! 4 × 4 m room with walls, one view; labels are the OR over the objects in view, seat
//! seen or not (per object: a chair seen from behind is a seat; see
//! [`render_with_visibility`]); a fine-grained column is 1 if it is 1 for a counted object,
//! else empty if it is undecided for one, else 0). World frame: metres, z up, floor at z = 0.

use std::path::{Path, PathBuf};

use nalgebra::{Point3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use super::camera::{render_view_triangles, Camera, SensorNoise};
use super::furniture::{
    bed, bench, cabinet, desk, recliner, scene_mesh, shelf, sofa, table, BedParams, BenchParams,
    CabinetParams, DeskParams, ReclinerParams, ShelfParams, SofaParams, TableParams,
    CYLINDER_SEGMENTS,
};
use afford::cloud::{self, CloudError};
use afford::mesh::ply::{read_mesh_ply, MeshError};
use afford::mesh::{part_code, sample_surface, Mesh, Part};

/// What went wrong generating a dataset.
#[derive(Debug, thiserror::Error)]
pub enum SynthError {
    /// A directory or file could not be created or read.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A cloud could not be written.
    #[error(transparent)]
    Cloud(#[from] CloudError),
    /// A mesh could not be read.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// A labels file could not be read or written.
    #[error("{path}: {what}")]
    Labels {
        /// The labels file.
        path: PathBuf,
        /// What is wrong.
        what: String,
    },
}

/// The affordance labels of an object or scene (columns of `labels.csv`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct Labels {
    /// A seat 0.25–0.55 m high with the feet on the floor.
    pub sitting: bool,
    /// A back ≥ 0.25 m above the seat (or a wall close behind a backless seat).
    pub backrest: bool,
    /// Arms 0.12–0.35 m above the seat at its sides.
    pub armrest: bool,
    /// A back reaching ≥ 0.70 m above the seat.
    pub headrest: bool,
    /// A surface that carries an adult on the back from head to heels: see the
    /// `LYING_MIN_*` constants and the module documentation.
    pub lying: bool,
    /// Lying with the trunk within 25° of level (beds, long benches, long sofas, recliners
    /// with a back below 25°).
    pub elongated_body: bool,
    /// Lying with the trunk raised 25–70° (recliners).
    pub raised_body: bool,
    /// Lying with the legs within 15° of level.
    pub stretched_legs: bool,
    /// Lying with the legs raised 15–40° (recliners with a raised leg rest).
    pub raised_legs: bool,
    /// The four fine-grained lying labels are not decided: a `0` among them is written as
    /// an empty cell (not scored). Set for short sofas (the posture depends on how the
    /// head and ankles rest on the arms) and for lying models read without those columns.
    pub posture_unknown: bool,
}

impl Labels {
    /// Component-wise OR.
    pub fn or(self, o: Labels) -> Labels {
        Labels {
            sitting: self.sitting || o.sitting,
            backrest: self.backrest || o.backrest,
            armrest: self.armrest || o.armrest,
            headrest: self.headrest || o.headrest,
            lying: self.lying || o.lying,
            elongated_body: self.elongated_body || o.elongated_body,
            raised_body: self.raised_body || o.raised_body,
            stretched_legs: self.stretched_legs || o.stretched_legs,
            raised_legs: self.raised_legs || o.raised_legs,
            posture_unknown: self.posture_unknown || o.posture_unknown,
        }
    }

    /// Sets the fine-grained lying labels of a lying posture with the trunk `trunk_deg`
    /// and the legs `legs_deg` above level (see [`TRUNK_RAISED_DEG`], [`LEGS_RAISED_DEG`]).
    /// Postures outside those ranges get none.
    pub fn with_posture(mut self, trunk_deg: f64, legs_deg: f64) -> Labels {
        let (t0, t1) = TRUNK_RAISED_DEG;
        let (l0, l1) = LEGS_RAISED_DEG;
        self.elongated_body = trunk_deg.abs() < t0;
        self.raised_body = (t0..=t1).contains(&trunk_deg);
        self.stretched_legs = legs_deg.abs() <= l0;
        self.raised_legs = legs_deg > l0 && legs_deg <= l1;
        self
    }

    /// The fine-grained lying columns in header order, as written: `1`, `0`, or empty when
    /// not decided (see [`Labels::posture_unknown`]).
    pub fn posture_cells(&self) -> [&'static str; 4] {
        [
            self.elongated_body,
            self.raised_body,
            self.stretched_legs,
            self.raised_legs,
        ]
        .map(|x| match (x, self.posture_unknown) {
            (true, _) => "1",
            (false, true) => "",
            (false, false) => "0",
        })
    }
}

/// Trunk angles above level (degrees) of lying with a raised body: from here to there;
/// below the first it is an elongated body (affordances/lying.toml).
pub const TRUNK_RAISED_DEG: (f64, f64) = (25.0, 70.0);
/// Leg angles above level (degrees) of lying with raised legs: above the first up to the
/// second; within the first of level the legs are stretched (affordances/lying.toml).
pub const LEGS_RAISED_DEG: (f64, f64) = (15.0, 40.0);

/// Furniture classes of the generator (the `class` column).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Class {
    /// Backless stool, seat 0.42–0.50 m.
    Stool,
    /// Bar stool, seat 0.65–0.80 m, perched on (a seat, docs/conventions.md).
    BarStool,
    /// Chair with a back, without arms.
    Chair,
    /// Chair or upholstered armchair with arms.
    Armchair,
    /// Chair whose back reaches ≥ 0.70 m above the seat (headrest).
    HighBackChair,
    /// Sofa with two to four seats.
    Sofa,
    /// Recliner or chaise longue: back reclined 30–50°, leg rest raised 0–25° or folded.
    Recliner,
    /// Backless bench.
    Bench,
    /// Bench with a back.
    BenchWithBack,
    /// Bed.
    Bed,
    /// Dining table (rectangular or round), negative.
    DiningTable,
    /// Desk, negative.
    Desk,
    /// Dresser or cabinet (0.80–1.30 m high), negative.
    Dresser,
    /// Shelf or bookcase, negative.
    Shelf,
    /// Radiator, negative.
    Radiator,
    /// Floor lamp (pole and shade), negative.
    Lamp,
    /// Low (coffee) table at seat height: doubtful.
    LowTable,
    /// Wooden armchair whose arm rails rest on the front posts (`--mix wide`).
    WoodenArmchair,
    /// Upholstered wingback chair: high back with wings, arms (`--mix wide`).
    Wingback,
    /// Tub chair: a round seat in a curved shell whose back runs into the arms
    /// (`--mix wide`).
    TubChair,
    /// Toilet: seat ring, bowl, tank or raised lid behind (`--mix wide`).
    Toilet,
    /// Night stand, alone or beside a bed: negative (`--mix wide`).
    NightStand,
    /// Bunk bed: the upper bunk over the lower one (`--mix wide`).
    BunkBed,
    /// Dining table with chairs pushed under its top (`--mix wide`).
    TableWithChairs,
    /// Bench against a wall with a shelf over it (`--mix wide`).
    BenchUnderShelf,
}

/// Every class, in a fixed order.
pub const CLASSES: [Class; 17] = [
    Class::Stool,
    Class::BarStool,
    Class::Chair,
    Class::Armchair,
    Class::HighBackChair,
    Class::Sofa,
    Class::Bench,
    Class::BenchWithBack,
    Class::Bed,
    Class::DiningTable,
    Class::Desk,
    Class::Dresser,
    Class::Shelf,
    Class::Radiator,
    Class::Lamp,
    Class::LowTable,
    Class::Recliner,
];

/// The `doubtful` text written for low tables.
pub const LOW_TABLE_DOUBT: &str =
    "low surface at seat height: sittable by geometry, negative by convention";

impl Class {
    /// The name written in the `class` column.
    pub fn name(self) -> &'static str {
        match self {
            Class::Stool => "stool",
            Class::BarStool => "bar_stool",
            Class::Chair => "chair",
            Class::Armchair => "armchair",
            Class::HighBackChair => "high_back_chair",
            Class::Sofa => "sofa",
            Class::Recliner => "recliner",
            Class::Bench => "bench",
            Class::BenchWithBack => "bench_with_back",
            Class::Bed => "bed",
            Class::DiningTable => "dining_table",
            Class::Desk => "desk",
            Class::Dresser => "dresser",
            Class::Shelf => "shelf",
            Class::Radiator => "radiator",
            Class::Lamp => "lamp",
            Class::LowTable => "low_table",
            Class::WoodenArmchair => "wooden_armchair",
            Class::Wingback => "wingback",
            Class::TubChair => "tub_chair",
            Class::Toilet => "toilet",
            Class::NightStand => "night_stand",
            Class::BunkBed => "bunk_bed",
            Class::TableWithChairs => "table_chairs",
            Class::BenchUnderShelf => "bench_shelf",
        }
    }

    /// Relative frequency in generated datasets.
    pub(super) fn weight(self) -> usize {
        match self {
            Class::Chair
            | Class::Armchair
            | Class::Sofa
            | Class::WoodenArmchair
            | Class::TableWithChairs => 3,
            Class::Stool
            | Class::HighBackChair
            | Class::Bench
            | Class::BenchWithBack
            | Class::Bed
            | Class::Recliner
            | Class::BarStool
            | Class::DiningTable
            | Class::LowTable
            | Class::Wingback
            | Class::TubChair
            | Class::Toilet
            | Class::BunkBed
            | Class::BenchUnderShelf => 2,
            _ => 1,
        }
    }
}

/// One generated piece of furniture, standing on z = 0, facing +x (its back at -x).
#[derive(Clone, Debug)]
pub struct Object {
    /// The labelled mesh.
    pub mesh: Mesh,
    /// Its class.
    pub class: Class,
    /// Its labels by construction.
    pub labels: Labels,
    /// Non-empty when the labels are a convention rather than geometry (low tables).
    pub doubtful: Option<String>,
    /// Seat (or lying surface, or top) height, metres: where cameras aim.
    pub focus_height: f64,
}

pub(super) fn u(rng: &mut ChaCha8Rng, a: f64, b: f64) -> f64 {
    a + (b - a) * rng.random::<f64>()
}

pub(super) fn chance(rng: &mut ChaCha8Rng, p: f64) -> bool {
    rng.random::<f64>() < p
}

pub(super) fn p3(x: f64, y: f64, z: f64) -> Point3<f64> {
    Point3::new(x, y, z)
}

/// A box leaning back (towards -x) by `tilt_deg` about the line x = `x_front`,
/// z = `z_base` (its front face passes through that line), spanning heights `z0..z1`
/// vertically, `y0..y1` across and `thick` deep.
#[allow(clippy::too_many_arguments)]
pub(super) fn tilted_box(
    m: &mut Mesh,
    x_front: f64,
    z_base: f64,
    z0: f64,
    z1: f64,
    y0: f64,
    y1: f64,
    thick: f64,
    tilt_deg: f64,
    part: Part,
) {
    if z1 <= z0 || y1 <= y0 {
        return;
    }
    let th = tilt_deg.to_radians();
    let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -th);
    let up = rot * Vector3::z();
    let front = rot * Vector3::x();
    let origin = p3(x_front, (y0 + y1) / 2.0, z_base) - front * (thick / 2.0);
    let (s0, s1) = ((z0 - z_base) / th.cos(), (z1 - z_base) / th.cos());
    let centre = origin + up * ((s0 + s1) / 2.0);
    let half = Vector3::new(thick / 2.0, (y1 - y0) / 2.0, (s1 - s0) / 2.0);
    m.add_oriented_box(centre, half, rot, part);
}

/// A back rising from `x_front` (the seat's rear edge) at the seat top `seat`, `h` above
/// it, `width` wide, solid or slatted; parts above 0.60 m over the seat are headrest
/// when `h >= 0.70`.
pub(super) fn add_back(
    m: &mut Mesh,
    rng: &mut ChaCha8Rng,
    x_front: f64,
    seat: f64,
    width: f64,
    h: f64,
) {
    let tilt = u(rng, 0.0, 18.0);
    let thick = u(rng, 0.02, 0.06);
    let split = if h >= 0.70 {
        seat + 0.60
    } else {
        f64::INFINITY
    };
    let top = seat + h;
    let hw = width / 2.0;
    let column = |m: &mut Mesh, y0: f64, y1: f64, z0: f64, z1: f64| {
        tilted_box(
            m,
            x_front,
            seat,
            z0,
            z1.min(split),
            y0,
            y1,
            thick,
            tilt,
            Part::Backrest,
        );
        tilted_box(
            m,
            x_front,
            seat,
            z0.max(split),
            z1,
            y0,
            y1,
            thick,
            tilt,
            Part::Headrest,
        );
    };
    if chance(rng, 0.4) && h < 0.70 {
        // Slatted: vertical slats under a top rail, plus two side posts.
        let rail = u(rng, 0.06, 0.12);
        let n = rng.random_range(3..=6);
        let slat = u(rng, 0.025, 0.06);
        let lo = seat + u(rng, 0.0, 0.08);
        for k in 0..n {
            let y = -hw + slat / 2.0 + (width - slat) * k as f64 / (n - 1) as f64;
            column(m, y - slat / 2.0, y + slat / 2.0, lo, top - rail);
        }
        column(m, -hw, hw, top - rail, top);
    } else {
        // Solid panel, sometimes starting a little above the seat (a gap).
        let lo = seat
            + if chance(rng, 0.3) {
                u(rng, 0.03, 0.12)
            } else {
                0.0
            };
        column(m, -hw, hw, lo, top);
        if lo > seat {
            for y in [-hw, hw - 0.03] {
                column(m, y, y + 0.03, seat, lo);
            }
        }
    }
}

/// What a seat stands on.
#[derive(Clone, Copy)]
pub(super) enum Base {
    Legs,
    Pedestal,
    Sled,
    Solid,
}

/// Seat slab (top at `seat`, `depth` × `width`, round when `round`) on a base.
#[allow(clippy::too_many_arguments)]
pub(super) fn add_seat(
    m: &mut Mesh,
    rng: &mut ChaCha8Rng,
    seat: f64,
    depth: f64,
    width: f64,
    round: bool,
    base: Base,
    cushion: bool,
) {
    let (hx, hy) = (depth / 2.0, width / 2.0);
    let slab = u(rng, 0.025, 0.05);
    let cush = if cushion { u(rng, 0.04, 0.09) } else { 0.0 };
    let bottom = seat - cush - slab;
    if round {
        m.add_cylinder_with_top(
            p3(0.0, 0.0, bottom),
            p3(0.0, 0.0, seat - cush),
            hx.min(hy),
            CYLINDER_SEGMENTS * 2,
            if cushion { Part::Other } else { Part::Seat },
            Part::Other,
        );
        if cushion {
            m.add_cylinder_with_top(
                p3(0.0, 0.0, seat - cush),
                p3(0.0, 0.0, seat),
                hx.min(hy) * 0.95,
                CYLINDER_SEGMENTS * 2,
                Part::Seat,
                Part::Other,
            );
        }
    } else {
        let top_part = if cushion { Part::Other } else { Part::Seat };
        m.add_box_with_top(
            p3(-hx, -hy, bottom),
            p3(hx, hy, seat - cush),
            top_part,
            Part::Other,
        );
        if cushion {
            m.add_box_with_top(
                p3(-hx + 0.01, -hy + 0.01, seat - cush),
                p3(hx - 0.01, hy - 0.01, seat),
                Part::Seat,
                Part::Other,
            );
        }
    }
    let (ax, ay) = if round {
        (hx.min(hy) * 0.6, hx.min(hy) * 0.6)
    } else {
        (hx * 0.85, hy * 0.85)
    };
    match base {
        Base::Legs => {
            let r = u(rng, 0.012, 0.025);
            let splay = if chance(rng, 0.3) {
                u(rng, 0.02, 0.06)
            } else {
                0.0
            };
            for (x, y) in [(ax, ay), (ax, -ay), (-ax, ay), (-ax, -ay)] {
                let f = 1.0 + splay / ax.max(0.05);
                m.add_cylinder(p3(x * f, y * f, 0.0), p3(x, y, bottom), r, 12, Part::Other);
            }
        }
        Base::Pedestal => {
            let r = u(rng, 0.18, 0.30);
            if chance(rng, 0.5) {
                m.add_cylinder(p3(0.0, 0.0, 0.0), p3(0.0, 0.0, 0.02), r, 32, Part::Other);
            } else {
                // Five-star base of office chairs.
                for k in 0..5 {
                    let a = std::f64::consts::TAU * k as f64 / 5.0;
                    let q = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a);
                    m.add_oriented_box(
                        p3(a.cos() * r / 2.0, a.sin() * r / 2.0, 0.06),
                        Vector3::new(r / 2.0, 0.025, 0.02),
                        q,
                        Part::Other,
                    );
                }
            }
            m.add_cylinder(
                p3(0.0, 0.0, 0.02),
                p3(0.0, 0.0, bottom),
                u(rng, 0.025, 0.045),
                16,
                Part::Other,
            );
        }
        Base::Sled => {
            for y in [-ay, ay] {
                m.add_cylinder(
                    p3(-ax - 0.03, y, 0.012),
                    p3(ax + 0.03, y, 0.012),
                    0.012,
                    10,
                    Part::Other,
                );
                for x in [-ax, ax] {
                    m.add_cylinder(p3(x, y, 0.012), p3(x, y, bottom), 0.012, 10, Part::Other);
                }
            }
        }
        Base::Solid => {
            let inset = u(rng, 0.0, 0.04);
            m.add_box(
                p3(-hx + inset, -hy + inset, 0.0),
                p3(hx - inset, hy - inset, bottom),
                Part::Other,
            );
        }
    }
}

pub(super) fn pick_base(rng: &mut ChaCha8Rng, weights: [f64; 4]) -> Base {
    let total: f64 = weights.iter().sum();
    let mut x = u(rng, 0.0, total);
    for (b, w) in [Base::Legs, Base::Pedestal, Base::Sled, Base::Solid]
        .into_iter()
        .zip(weights)
    {
        if x < w {
            return b;
        }
        x -= w;
    }
    Base::Legs
}

/// A chair with a back, optionally with arms; `back_h` above the seat.
pub(super) fn build_chair(rng: &mut ChaCha8Rng, back_h: f64, arms: bool) -> (Mesh, f64, Labels) {
    let seat = u(rng, 0.42, 0.50);
    let depth = u(rng, 0.38, 0.50);
    let width = u(rng, 0.40, 0.52);
    let mut m = Mesh::new();
    let base = pick_base(rng, [0.55, 0.2, 0.15, 0.1]);
    let cushion = chance(rng, 0.4);
    add_seat(&mut m, rng, seat, depth, width, false, base, cushion);
    add_back(&mut m, rng, -depth / 2.0, seat, width, back_h);
    let mut labels = Labels {
        sitting: true,
        backrest: back_h >= 0.25,
        headrest: back_h >= 0.70,
        ..Labels::default()
    };
    if arms {
        let ah = u(rng, 0.16, 0.28);
        let aw = u(rng, 0.04, 0.10);
        let hy = width / 2.0;
        let solid = chance(rng, 0.3);
        for (y0, y1) in [(-hy - aw, -hy), (hy, hy + aw)] {
            let x0 = -depth / 2.0;
            let x1 = depth / 2.0 - u(rng, 0.0, 0.06);
            m.add_box_with_top(
                p3(x0, y0, seat + ah - 0.03),
                p3(x1, y1, seat + ah),
                Part::Armrest,
                Part::Armrest,
            );
            if solid {
                m.add_box(p3(x0, y0, 0.0), p3(x1, y1, seat + ah - 0.03), Part::Other);
            } else {
                let yc = (y0 + y1) / 2.0;
                m.add_box(
                    p3(x1 - 0.04, yc - 0.015, seat - 0.05),
                    p3(x1 - 0.01, yc + 0.015, seat + ah - 0.03),
                    Part::Other,
                );
            }
        }
        labels.armrest = (0.12..=0.35).contains(&ah);
    }
    (m, seat, labels)
}

/// Builds one random object of `class` (deterministic for the RNG state).
pub fn make_object(class: Class, rng: &mut ChaCha8Rng) -> Object {
    let seat_obj = |mesh: Mesh, h: f64, labels: Labels| (mesh, h, labels, None);
    let (mesh, focus_height, labels, doubtful) = match class {
        Class::Stool | Class::BarStool => {
            let bar = class == Class::BarStool;
            let seat = if bar {
                u(rng, 0.65, 0.80)
            } else {
                u(rng, 0.42, 0.50)
            };
            let size = u(rng, 0.30, 0.42);
            let mut m = Mesh::new();
            let base = if bar {
                pick_base(rng, [0.6, 0.4, 0.0, 0.0])
            } else {
                pick_base(rng, [0.5, 0.15, 0.1, 0.25])
            };
            let round = chance(rng, 0.6);
            let cushion = chance(rng, 0.3);
            add_seat(&mut m, rng, seat, size, size, round, base, cushion);
            if bar && chance(rng, 0.6) {
                // Foot rest ring (square) at about 0.30 m.
                let a = size * 0.45;
                let z = u(rng, 0.25, 0.35);
                for (x0, y0, x1, y1) in [
                    (-a, -a, a, -a + 0.02),
                    (-a, a - 0.02, a, a),
                    (-a, -a, -a + 0.02, a),
                    (a - 0.02, -a, a, a),
                ] {
                    m.add_box(p3(x0, y0, z - 0.02), p3(x1, y1, z), Part::Other);
                }
            }
            let labels = Labels {
                sitting: true,
                ..Labels::default()
            };
            seat_obj(m, seat, labels)
        }
        Class::Chair => {
            let h = u(rng, 0.28, 0.55);
            let (m, s, l) = build_chair(rng, h, false);
            seat_obj(m, s, l)
        }
        Class::HighBackChair => {
            let h = u(rng, 0.72, 0.90);
            let arms = chance(rng, 0.4);
            let (m, s, l) = build_chair(rng, h, arms);
            seat_obj(m, s, l)
        }
        Class::Armchair if chance(rng, 0.5) => {
            let h = u(rng, 0.30, 0.60);
            let (m, s, l) = build_chair(rng, h, true);
            seat_obj(m, s, l)
        }
        Class::Armchair | Class::Sofa => {
            let seats = if class == Class::Armchair {
                1
            } else {
                rng.random_range(2..=4)
            };
            let p = SofaParams {
                seats,
                seat_width_per_person: u(rng, 0.50, 0.68),
                seat_depth: u(rng, 0.48, 0.66),
                seat_height: u(rng, 0.38, 0.47),
                cushion_thickness: u(rng, 0.10, 0.18),
                back_height_above_seat: u(rng, 0.30, 0.55),
                back_thickness: u(rng, 0.12, 0.25),
                arm_width: u(rng, 0.08, 0.25),
                arm_height_above_seat: u(rng, 0.14, 0.30),
            };
            let len = seats as f64 * p.seat_width_per_person;
            let labels = Labels {
                sitting: true,
                backrest: p.back_height_above_seat >= 0.25,
                armrest: (0.12..=0.35).contains(&p.arm_height_above_seat),
                headrest: p.back_height_above_seat >= 0.70,
                lying: len >= LYING_MIN_SOFA_LENGTH && p.seat_depth >= LYING_MIN_WIDTH,
                ..Labels::default()
            };
            let labels = match (labels.lying, len >= LYING_MIN_LENGTH) {
                // Long enough to lie flat on the cushions between the arms.
                (true, true) => labels.with_posture(0.0, 0.0),
                // Head and ankles on the arms: posture not decided.
                (true, false) => Labels {
                    posture_unknown: true,
                    ..labels
                },
                (false, _) => labels,
            };
            let mut m = sofa(&p);
            if labels.lying {
                relabel_lying(&mut m);
            }
            seat_obj(m, p.seat_height, labels)
        }
        Class::Bench | Class::BenchWithBack => {
            let back = class == Class::BenchWithBack;
            let wide = !back && chance(rng, 0.25);
            let p = BenchParams {
                length: if wide {
                    u(rng, 1.9, 2.2)
                } else {
                    u(rng, 0.9, 2.0)
                },
                // Wide benches reach daybeds (0.70 m and more: a place to lie).
                seat_depth: if wide {
                    u(rng, 0.6, 0.8)
                } else {
                    u(rng, 0.30, 0.45)
                },
                seat_height: u(rng, 0.40, 0.48),
                seat_thickness: u(rng, 0.03, 0.06),
                leg_size: u(rng, 0.04, 0.07),
                back,
                back_height_above_seat: u(rng, 0.30, 0.45),
                back_thickness: u(rng, 0.02, 0.05),
                back_tilt_deg: u(rng, 5.0, 15.0),
            };
            let labels = Labels {
                sitting: true,
                backrest: back,
                lying: p.length >= LYING_MIN_LENGTH && p.seat_depth >= LYING_MIN_WIDTH,
                ..Labels::default()
            };
            let labels = if labels.lying {
                labels.with_posture(0.0, 0.0)
            } else {
                labels
            };
            let mut m = bench(&p);
            if labels.lying {
                relabel_lying(&mut m);
            }
            seat_obj(m, p.seat_height, labels)
        }
        Class::Bed => {
            let p = BedParams {
                length: u(rng, 1.9, 2.1),
                width: *[0.9, 1.2, 1.4, 1.6, 1.8]
                    .get(rng.random_range(0..5))
                    .unwrap(),
                mattress_height: u(rng, 0.40, 0.60),
                mattress_thickness: u(rng, 0.15, 0.28),
                headboard_height: if chance(rng, 0.2) {
                    0.0
                } else {
                    u(rng, 0.75, 1.2)
                },
                headboard_thickness: u(rng, 0.03, 0.08),
            };
            let labels = Labels {
                sitting: true,
                lying: true,
                ..Labels::default()
            }
            .with_posture(0.0, 0.0);
            seat_obj(bed(&p), p.mattress_height, labels)
        }
        Class::Recliner => {
            let mut p = ReclinerParams {
                seat_height: u(rng, 0.40, 0.48),
                seat_width: u(rng, 0.55, 0.75),
                seat_depth: u(rng, 0.45, 0.55),
                seat_thickness: u(rng, 0.08, 0.16),
                back_length: u(rng, 0.70, 0.90),
                back_angle_deg: u(rng, 30.0, 50.0),
                leg_rest_length: u(rng, 0.50, 0.80),
                leg_rest_angle_deg: u(rng, 0.0, 25.0),
                leg_rest_folded: chance(rng, 0.35),
                panel_thickness: u(rng, 0.06, 0.14),
                arms: chance(rng, 0.5),
                arm_height_above_seat: u(rng, 0.10, 0.30),
                arm_width: u(rng, 0.06, 0.14),
                headrest_from_above_seat: 0.60,
                lying_surface: false,
            };
            let labels = recliner_labels(&p);
            p.lying_surface = labels.lying;
            seat_obj(recliner(&p), p.seat_height, labels)
        }
        Class::DiningTable => {
            let h = u(rng, 0.70, 0.78);
            let m = if chance(rng, 0.3) {
                let mut m = Mesh::new();
                let r = u(rng, 0.35, 0.55);
                m.add_cylinder(p3(0.0, 0.0, h - 0.03), p3(0.0, 0.0, h), r, 48, Part::Other);
                m.add_cylinder(
                    p3(0.0, 0.0, 0.0),
                    p3(0.0, 0.0, h - 0.03),
                    0.04,
                    16,
                    Part::Other,
                );
                m.add_cylinder(
                    p3(0.0, 0.0, 0.0),
                    p3(0.0, 0.0, 0.03),
                    r * 0.6,
                    32,
                    Part::Other,
                );
                m
            } else {
                table(&TableParams {
                    length: u(rng, 0.8, 1.8),
                    width: u(rng, 0.6, 1.0),
                    height: h,
                    top_thickness: u(rng, 0.02, 0.05),
                    leg_size: u(rng, 0.04, 0.08),
                    leg_inset: u(rng, 0.0, 0.1),
                })
            };
            (m, h, Labels::default(), None)
        }
        Class::Desk => {
            let p = DeskParams {
                width: u(rng, 1.0, 1.8),
                depth: u(rng, 0.6, 0.8),
                height: u(rng, 0.72, 0.76),
                top_thickness: u(rng, 0.02, 0.04),
                panel_thickness: u(rng, 0.02, 0.04),
                pedestal: chance(rng, 0.5),
                pedestal_width: u(rng, 0.35, 0.45),
            };
            (desk(&p), p.height, Labels::default(), None)
        }
        Class::Dresser => {
            let p = CabinetParams {
                width: u(rng, 0.6, 1.6),
                depth: u(rng, 0.4, 0.6),
                height: u(rng, 0.80, 1.30),
                top_overhang: u(rng, 0.0, 0.03),
            };
            (cabinet(&p), p.height * 0.7, Labels::default(), None)
        }
        Class::Shelf => {
            let p = ShelfParams {
                width: u(rng, 0.6, 1.2),
                depth: u(rng, 0.25, 0.40),
                height: u(rng, 0.9, 2.0),
                board_thickness: u(rng, 0.016, 0.025),
                compartments: rng.random_range(2..=6),
                back_panel: chance(rng, 0.7),
            };
            (shelf(&p), p.height * 0.5, Labels::default(), None)
        }
        Class::Radiator => {
            let mut m = Mesh::new();
            let w = u(rng, 0.6, 1.4);
            let h = u(rng, 0.4, 0.8);
            let d = u(rng, 0.06, 0.12);
            let z0 = u(rng, 0.08, 0.18);
            let fins = crate::count((w / 0.06).round());
            for k in 0..fins {
                let y = -w / 2.0 + w * (k as f64 + 0.5) / fins as f64;
                m.add_box(
                    p3(-d / 2.0, y - 0.02, z0),
                    p3(d / 2.0, y + 0.02, z0 + h),
                    Part::Other,
                );
            }
            for y in [-w / 2.0 + 0.05, w / 2.0 - 0.05] {
                m.add_box(
                    p3(-0.02, y - 0.02, 0.0),
                    p3(0.02, y + 0.02, z0),
                    Part::Other,
                );
            }
            (m, z0 + h / 2.0, Labels::default(), None)
        }
        Class::Lamp => {
            let mut m = Mesh::new();
            let h = u(rng, 1.3, 1.8);
            let r = u(rng, 0.12, 0.25);
            m.add_cylinder(
                p3(0.0, 0.0, 0.0),
                p3(0.0, 0.0, 0.03),
                u(rng, 0.12, 0.2),
                32,
                Part::Other,
            );
            m.add_cylinder(p3(0.0, 0.0, 0.03), p3(0.0, 0.0, h), 0.015, 12, Part::Other);
            m.add_cylinder(
                p3(0.0, 0.0, h - 0.1),
                p3(0.0, 0.0, h + u(rng, 0.15, 0.3)),
                r,
                32,
                Part::Other,
            );
            (m, h * 0.6, Labels::default(), None)
        }
        Class::WoodenArmchair => super::wide::wooden_armchair_object(rng),
        Class::Wingback => super::wide::wingback_object(rng),
        Class::TubChair => super::wide::tub_chair_object(rng),
        Class::Toilet => super::wide::toilet_object(rng),
        Class::NightStand => super::wide::night_stand_object(rng),
        Class::BunkBed => super::wide::bunk_bed_object(rng),
        Class::TableWithChairs => super::wide::table_with_chairs_object(rng),
        Class::BenchUnderShelf => super::wide::bench_under_shelf_object(rng),
        Class::LowTable => {
            let h = u(rng, 0.30, 0.50);
            let m = if chance(rng, 0.3) {
                let mut m = Mesh::new();
                let (l, w) = (u(rng, 0.8, 1.3), u(rng, 0.5, 0.8));
                m.add_box(
                    p3(-w / 2.0, -l / 2.0, 0.0),
                    p3(w / 2.0, l / 2.0, h),
                    Part::Other,
                );
                m
            } else {
                let l = u(rng, 0.8, 1.3);
                let w = u(rng, 0.5, 0.8);
                table(&TableParams {
                    length: w,
                    width: l,
                    height: h,
                    top_thickness: u(rng, 0.02, 0.06),
                    leg_size: u(rng, 0.04, 0.07),
                    leg_inset: u(rng, 0.0, 0.06),
                })
            };
            (m, h, Labels::default(), Some(LOW_TABLE_DOUBT.to_string()))
        }
    };
    Object {
        mesh,
        class,
        labels,
        doubtful,
        focus_height,
    }
}

/// The labels of a recliner (see the module documentation): sitting on the seat, a
/// backrest (its back rises ≥ 0.25 m), arms 0.12–0.35 m above the seat, a headrest when the
/// back's top rises ≥ 0.70 m above the seat, and lying when back, seat and unfolded leg
/// rest carry the body from the back of the head to the ankles along their surfaces
/// ([`LYING_MIN_RECLINER_LENGTH`]) at least [`LYING_MIN_WIDTH`] wide (seat and leg rest
/// make one surface that long under the pelvis and thighs), with the back at most
/// 70° above level; then the posture is that of the back (trunk) and the leg rest (legs).
pub fn recliner_labels(p: &ReclinerParams) -> Labels {
    let lying = p.support_length() >= LYING_MIN_RECLINER_LENGTH
        && p.seat_width >= LYING_MIN_WIDTH
        && p.back_angle_deg <= TRUNK_RAISED_DEG.1;
    let labels = Labels {
        sitting: (0.25..=0.55).contains(&p.seat_height),
        // A back reclined further than BACKREST_MAX_RECLINE_DEG from upright is for lying,
        // not a backrest to sit against (docs/conventions.md).
        backrest: p.back_rise() >= 0.25 && 90.0 - p.back_angle_deg <= BACKREST_MAX_RECLINE_DEG,
        armrest: p.arms && (0.12..=0.35).contains(&p.arm_height_above_seat),
        headrest: p.back_rise() >= 0.70,
        lying,
        ..Labels::default()
    };
    if lying {
        labels.with_posture(p.back_angle_deg, p.leg_rest_angle_deg)
    } else {
        labels
    }
}

/// Marks the seat tops as a lying surface (long, wide benches and sofas).
pub(super) fn relabel_lying(m: &mut Mesh) {
    for p in &mut m.parts {
        if *p == Part::Seat {
            *p = Part::LyingSurface;
        }
    }
}

/// Scene kinds (the `kind` column).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SceneKind {
    /// The whole model sampled over its surface, with a floor patch.
    Full,
    /// One depth view of the object and the floor.
    View,
    /// One depth view of the object with its back against a wall.
    Wall,
    /// One depth view of 2–4 objects in a 4 × 4 m room with walls (`--mix wide`: 2–5
    /// objects in a 3.6–5.6 m room with a ceiling).
    Room,
    /// A whole room reconstructed as a mesh and read as its vertices (ScanNet-like), with
    /// or without a ceiling (`--mix wide` only).
    Scan,
}

impl SceneKind {
    /// The name written in the `kind` column.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Full => "full",
            SceneKind::View => "view",
            SceneKind::Wall => "wall",
            SceneKind::Room => "room",
            SceneKind::Scan => "scan",
        }
    }
}

/// What [`generate`] makes.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetSpec {
    /// Number of `full` scenes.
    pub full: usize,
    /// Number of `view` scenes.
    pub view: usize,
    /// Number of `wall` scenes.
    pub wall: usize,
    /// Number of `room` scenes.
    pub room: usize,
    /// Pixel stride of the depth camera (2 = 320 × 240 rays).
    pub stride: u32,
    /// Every `pcd_every`-th scene is written as binary PCD (without `part`); 0 = never.
    pub pcd_every: usize,
    /// Surface density of `full` scenes, points per square metre.
    pub full_density: f64,
    /// Gaussian noise of `full` scenes along the surface normal, metres.
    pub full_noise: f64,
    /// Which furniture, cameras and samplings to draw from.
    pub mix: Mix,
    /// The frame the clouds are written in.
    pub frame: OutFrame,
    /// Probability of a mixed ("flying") pixel at each depth edge of a depth view
    /// ([`SensorNoise::mixed_pixels`]); 0, the Kinect v1 default, for none.
    pub mixed_pixels: f64,
    /// Single views of seats from every side alike (`afford synth --all-round`): the
    /// camera's azimuth relative to a seat's front uniform over the full circle, as
    /// independently generated views and a robot walking round a room see them. By
    /// default 85% of seat views come from within 80 degrees of its front; views against
    /// a wall stay within 70 degrees of it either way. `false` writes the same bytes as
    /// before the option existed.
    pub all_round: bool,
}

/// Which world [`generate`] draws from (`afford synth --mix`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mix {
    /// The mix of the docs/results.md tables and the regression set: the same seed and counts
    /// write the same bytes as before the wide mix existed.
    #[default]
    Default,
    /// What real scans have as well (issue 11, see [`super::wide`]): ceilings, overhangs
    /// (chairs pushed under tables, shelves over benches, bunk beds), reconstructed-mesh
    /// vertex clouds, subsampled views, cameras pitched 10–55° down, dressed beds, things
    /// on seats and the new furniture classes. Every room job alternates between a pitched
    /// view (`room`) and a reconstruction (`scan`).
    Wide,
}

/// The frame [`generate`] writes clouds in (`afford synth --frame`, the `frame` column).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OutFrame {
    /// Metres, z up, floor at z = 0 (the detector's frame).
    #[default]
    World,
    /// The frame of the scene's depth camera (x right, y down, z forward, metres; for
    /// `full` and `scan` scenes a virtual camera placed as for a view): the floor is
    /// tilted and anywhere, so `afford eval` needs `--camera --floor auto`.
    Camera,
}

impl OutFrame {
    /// The name written in the `frame` column.
    pub fn name(self) -> &'static str {
        match self {
            OutFrame::World => "world",
            OutFrame::Camera => "camera",
        }
    }
}

impl Default for DatasetSpec {
    /// 100 scenes: 25 full, 35 view, 20 wall, 20 room; stride 2; one in five as PCD;
    /// full models at 2500 points/m² with 3 mm noise.
    fn default() -> Self {
        Self {
            full: 25,
            view: 35,
            wall: 20,
            room: 20,
            stride: 2,
            pcd_every: 5,
            full_density: 2500.0,
            full_noise: 0.003,
            mix: Mix::Default,
            frame: OutFrame::World,
            mixed_pixels: 0.0,
            all_round: false,
        }
    }
}

impl DatasetSpec {
    /// `cam` with this dataset's sensor: its mixed pixels ([`Self::mixed_pixels`]).
    pub fn seen_by(&self, cam: Camera) -> Camera {
        Camera {
            noise: SensorNoise {
                mixed_pixels: self.mixed_pixels,
                ..cam.noise
            },
            ..cam
        }
    }
}

/// One row of a generated `labels.csv`.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelRow {
    /// File name relative to the CSV.
    pub file: String,
    /// Affordance labels.
    pub labels: Labels,
    /// Scene kind name.
    pub kind: String,
    /// Class name (`+`-joined for rooms).
    pub class: String,
    /// Why the labels are a convention, if they are.
    pub doubtful: Option<String>,
    /// Points in the file.
    pub points: usize,
    /// The frame the cloud is written in (`world`, `camera`), for sets written with
    /// `--mix wide` or `--frame`; `None` (no column) for the default world-frame sets.
    pub frame: Option<String>,
}

/// What [`generate`] and [`views_of_labelled_models`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetSummary {
    /// The labels file.
    pub labels_csv: PathBuf,
    /// One row per file written.
    pub rows: Vec<LabelRow>,
}

/// splitmix64, to derive independent per-scene seeds.
pub(super) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// A large floor rectangle centred at the origin.
pub(super) fn big_floor() -> Mesh {
    let mut m = Mesh::new();
    m.add_horizontal_rect(-8.0, -8.0, 8.0, 8.0, 0.0, Part::Other);
    m
}

/// Bounding radius of a mesh's footprint about the z axis, metres.
pub(super) fn footprint_radius(m: &Mesh) -> f64 {
    m.vertices
        .iter()
        .map(|p| (p.x * p.x + p.y * p.y).sqrt())
        .fold(0.0, f64::max)
}

/// Lowest and highest a depth camera is held for single views, metres above the floor: a
/// person's hands or a tripod (1.0-1.8 m). Robots carry theirs lower (0.4-1.0 m on a
/// mobile base): `afford synth --camera-height` draws those views.
pub const CAMERA_HELD_M: [f64; 2] = [1.0, 1.8];

/// A camera at horizontal distance `dist` from `(cx, cy)` at azimuth `az` (radians,
/// 0 = +x), held between `held[0]` and `held[1]` metres high, looking at `(cx, cy,
/// focus)`.
#[allow(clippy::too_many_arguments)]
fn camera_at(
    rng: &mut ChaCha8Rng,
    cx: f64,
    cy: f64,
    az: f64,
    dist: f64,
    focus: f64,
    stride: u32,
    held: [f64; 2],
) -> Camera {
    let h = u(rng, held[0], held[1]);
    Camera {
        stride,
        ..Camera::looking_at(
            p3(cx + dist * az.cos(), cy + dist * az.sin(), h),
            p3(cx, cy, focus),
        )
    }
}

/// One rendered or sampled scene.
pub(super) struct Scene {
    pub(super) points: Vec<Point3<f64>>,
    pub(super) parts: Vec<Part>,
    pub(super) labels: Labels,
    pub(super) class: String,
    pub(super) doubtful: Option<String>,
    /// The depth camera that saw the scene (`None` for sampled models and scans).
    pub(super) camera: Option<Camera>,
}

/// Shortest flat surface labelled `lying`, metres: it must carry the 1.75 m adult from the
/// back of the head to the ankles (about 0.85 H = 1.5 m); the feet may overhang.
pub const LYING_MIN_LENGTH: f64 = 1.6;
/// Narrowest surface labelled `lying`, metres: a bed's. A body on its back with the arms
/// beside it and room to turn takes about 0.40 H (0.70 m for the 1.75 m adult; the lying
/// template's diameter in affordances/lying.toml). Sofa seats (0.48-0.66 m deep),
/// benches and recliner seats are narrower: people sit on them and lie on beds, which is
/// how real furniture labelled by others counts them (docs/conventions.md).
pub const LYING_MIN_WIDTH: f64 = 0.70;
/// Shortest sofa seat (between the arms) labelled `lying`, metres: two seats; the head
/// rests on one arm and the ankles on the other (a 1.0 m seat and two arms span the
/// ~1.5 m from the back of the head to the ankles). A one-seat armchair does not.
pub const LYING_MIN_SOFA_LENGTH: f64 = 1.0;
/// Shortest recliner support labelled `lying`, metres, measured along the surfaces of the
/// back panel, the seat and the unfolded leg rest: the ~1.5 m (0.85 H) from the back of the
/// head to the ankles of the 1.75 m adult; the feet may overhang. A recliner with its leg
/// rest folded (0.70–0.90 m back + 0.45–0.55 m seat) is a chair.
pub const LYING_MIN_RECLINER_LENGTH: f64 = 1.5;

/// Furthest a back may recline from upright (degrees) and still be a backrest for sitting:
/// the sitting hierarchy's backrest sweep ends there ("beyond 35 deg it is lying").
pub const BACKREST_MAX_RECLINE_DEG: f64 = 35.0;

/// Least number of an object's points seen in a view for its labels to count: the object
/// is in the picture (a person judging it would name it), not a few stray pixels of a leg
/// at the image edge. Whether its seat is seen does not matter: labels are per object, as
/// in the real furniture models' labels, so a chair seen from behind, its seat hidden by
/// its back, is still a seat (docs/conventions.md, "Hidden seats").
const MIN_IN_VIEW_POINTS: usize = 100;

/// Renders `scene` with `objects` given by triangle ranges; an object's labels (and its
/// `doubtful` note) count when at least [`MIN_IN_VIEW_POINTS`] of its points are seen.
pub(super) fn render_with_visibility(
    scene: &Mesh,
    ranges: &[(usize, usize, Labels, Option<String>)],
    cam: &Camera,
    seed: u64,
) -> (Vec<Point3<f64>>, Vec<Part>, Labels, Option<String>) {
    let (cloud, tris) = render_view_triangles(scene, cam, seed);
    let parts: Vec<Part> = tris.iter().map(|&t| scene.parts[t]).collect();
    let mut labels = Labels::default();
    let mut doubtful = None;
    for (s, e, l, d) in ranges {
        let seen = tris.iter().filter(|&&t| t >= *s && t < *e).count();
        if seen < MIN_IN_VIEW_POINTS {
            continue;
        }
        labels = labels.or(*l);
        if d.is_some() && doubtful.is_none() {
            doubtful.clone_from(d);
        }
    }
    (cloud.points, parts, labels, doubtful)
}

/// The scene of a `view` or `wall` scene: `obj` turned by `yaw` degrees on a large floor,
/// with a wall 0–0.15 m behind it when `wall` (then a seat gets a backrest and a headrest
/// by the wall rule, see [`wall_backs`]). Returns the mesh, how many of its first
/// triangles are the object's, and the labels.
pub(super) fn object_on_floor(
    obj: &Object,
    wall: bool,
    yaw: f64,
    rng: &mut ChaCha8Rng,
) -> (Mesh, usize, Labels) {
    let mut m = obj.mesh.clone();
    let mut labels = obj.labels;
    if wall {
        let (lo, _) = m.bounds().unwrap_or((Point3::origin(), Point3::origin()));
        let gap = u(rng, 0.0, 0.15);
        m.append(&super::furniture::wall(
            lo.x - gap - 0.05,
            -2.5,
            2.5,
            2.5,
            0.1,
        ));
        // A seat against a wall: the wall reaches far above the seat within 0.15 m of its
        // back, so the head leaning back rests on it (headrest), and a backless seat gets
        // it as its backrest (docs/conventions.md).
        if labels.sitting && wall_backs(obj.class) {
            labels.backrest = true;
            labels.headrest = true;
        }
    }
    let n = m.len();
    let mut scene = m.placed(0.0, 0.0, yaw);
    scene.append(&big_floor());
    (scene, n, labels)
}

/// Whether a wall close behind an object of `class` is its backrest and headrest (the
/// wall rule of docs/conventions.md): not for beds, whose head end stands at the wall;
/// one sits on a bed's side edge, so the wall (like the headboard) is beside the body.
pub(super) fn wall_backs(class: Class) -> bool {
    !matches!(class, Class::Bed | Class::BunkBed)
}

pub(super) fn one_scene(kind: SceneKind, class: Class, seed: u64, spec: &DatasetSpec) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let obj = make_object(class, &mut rng);
    let yaw = u(&mut rng, -180.0, 180.0);
    let seating = obj.labels.sitting;
    // Azimuth of the camera relative to the object's front, degrees.
    let rel_az = |rng: &mut ChaCha8Rng, wall: bool| {
        if wall {
            u(rng, -70.0, 70.0)
        } else if seating && !spec.all_round && chance(rng, 0.85) {
            u(rng, -80.0, 80.0)
        } else {
            u(rng, -180.0, 180.0)
        }
    };
    match kind {
        SceneKind::Full => {
            let m = obj.mesh.placed(0.0, 0.0, yaw);
            let (c, parts) = sample_surface(
                &scene_mesh(&[m], true),
                spec.full_density,
                spec.full_noise,
                mix(seed ^ 1),
            );
            Scene {
                points: c.points,
                parts,
                labels: obj.labels,
                class: class.name().into(),
                doubtful: obj.doubtful,
                camera: None,
            }
        }
        SceneKind::View | SceneKind::Wall => {
            let wall = kind == SceneKind::Wall;
            let (scene, n, labels) = object_on_floor(&obj, wall, yaw, &mut rng);
            let r = footprint_radius(&obj.mesh);
            let az = (yaw + rel_az(&mut rng, wall)).to_radians();
            let dist = u(&mut rng, 1.5, 3.0) + (r - 0.5).max(0.0) * 0.8;
            let cam = spec.seen_by(camera_at(
                &mut rng,
                0.0,
                0.0,
                az,
                dist,
                obj.focus_height,
                spec.stride,
                CAMERA_HELD_M,
            ));
            let (points, parts, labels, doubtful) = render_with_visibility(
                &scene,
                &[(0, n, labels, obj.doubtful.clone())],
                &cam,
                mix(seed ^ 2),
            );
            Scene {
                points,
                parts,
                labels,
                class: class.name().into(),
                doubtful,
                camera: Some(cam),
            }
        }
        SceneKind::Room | SceneKind::Scan => {
            let mut scene = Mesh::new();
            let mut ranges = Vec::new();
            let mut placed: Vec<(f64, f64, f64, f64)> = Vec::new(); // x, y, r, focus
            let mut names = Vec::new();
            let want = rng.random_range(2..=4);
            let mut objs = vec![obj];
            for _ in 1..want {
                let c = CLASSES[rng.random_range(0..CLASSES.len())];
                objs.push(make_object(c, &mut rng));
            }
            for o in &objs {
                let r = footprint_radius(&o.mesh);
                let lim = 2.0 - r - 0.5;
                if lim < 0.0 {
                    continue;
                }
                for _ in 0..50 {
                    let (x, y) = (u(&mut rng, -lim, lim), u(&mut rng, -lim, lim));
                    if placed.iter().all(|(px, py, pr, _)| {
                        ((x - px).powi(2) + (y - py).powi(2)).sqrt() > r + pr + 0.4
                    }) {
                        let s = scene.len();
                        scene.append(&o.mesh.placed(x, y, u(&mut rng, -180.0, 180.0)));
                        ranges.push((s, scene.len(), o.labels, o.doubtful.clone()));
                        placed.push((x, y, r, o.focus_height));
                        names.push(o.class.name());
                        break;
                    }
                }
            }
            for (a, b) in [
                ((-2.0, -2.0), (2.0, -2.0)),
                ((2.0, -2.0), (2.0, 2.0)),
                ((2.0, 2.0), (-2.0, 2.0)),
                ((-2.0, 2.0), (-2.0, -2.0)),
            ] {
                scene.append(&super::furniture::wall_segment(
                    nalgebra::Point2::new(a.0, a.1),
                    nalgebra::Point2::new(b.0, b.1),
                    2.5,
                    0.1,
                ));
            }
            let mut floor = Mesh::new();
            floor.add_horizontal_rect(-2.0, -2.0, 2.0, 2.0, 0.0, Part::Other);
            scene.append(&floor);
            // Camera near the room's edge, looking at the first object placed.
            let (tx, ty, _, tf) = placed.first().copied().unwrap_or((0.0, 0.0, 0.0, 0.5));
            let mut cam = None;
            for _ in 0..20 {
                let a = u(&mut rng, -180.0, 180.0).to_radians();
                let (cx, cy) = (1.75 * a.cos(), 1.75 * a.sin());
                let d = ((cx - tx).powi(2) + (cy - ty).powi(2)).sqrt();
                if d >= 1.2 {
                    let az = (cy - ty).atan2(cx - tx);
                    cam = Some(camera_at(
                        &mut rng,
                        tx,
                        ty,
                        az,
                        d,
                        tf,
                        spec.stride,
                        CAMERA_HELD_M,
                    ));
                    break;
                }
            }
            let cam = spec.seen_by(cam.unwrap_or_else(|| {
                camera_at(&mut rng, tx, ty, 0.0, 1.2, tf, spec.stride, CAMERA_HELD_M)
            }));
            let (points, parts, labels, mut doubtful) =
                render_with_visibility(&scene, &ranges, &cam, mix(seed ^ 3));
            // A low table only matters when nothing else affords sitting.
            if labels.sitting {
                doubtful = None;
            }
            Scene {
                points,
                parts,
                labels,
                class: names.join("+"),
                doubtful,
                camera: Some(cam),
            }
        }
    }
}

pub(super) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> SynthError + '_ {
    move |source| SynthError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes a labels file with the docs/formats.md columns plus `kind,class,doubtful,points` and
/// the fine-grained lying columns (see the module documentation), then a `frame` column
/// (`world` or `camera`) when any row names its frame.
pub fn write_labels(path: &Path, rows: &[LabelRow]) -> Result<(), SynthError> {
    let lerr = |e: csv::Error| SynthError::Labels {
        path: path.to_path_buf(),
        what: e.to_string(),
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    let with_frame = rows.iter().any(|r| r.frame.is_some());
    w.write_record(
        [
            "file",
            "sitting",
            "backrest",
            "armrest",
            "headrest",
            "lying",
            "kind",
            "class",
            "doubtful",
            "points",
            "elongated_body",
            "raised_body",
            "stretched_legs",
            "raised_legs",
        ]
        .into_iter()
        .chain(with_frame.then_some("frame")),
    )
    .map_err(lerr)?;
    let b = |x: bool| if x { "1" } else { "0" };
    for r in rows {
        let l = r.labels;
        let [eb, rb, sl, rl] = l.posture_cells();
        w.write_record(
            [
                r.file.as_str(),
                b(l.sitting),
                b(l.backrest),
                b(l.armrest),
                b(l.headrest),
                b(l.lying),
                &r.kind,
                &r.class,
                r.doubtful.as_deref().unwrap_or(""),
                &r.points.to_string(),
                eb,
                rb,
                sl,
                rl,
            ]
            .into_iter()
            .chain(with_frame.then(|| r.frame.as_deref().unwrap_or("world"))),
        )
        .map_err(lerr)?;
    }
    let bytes = w.into_inner().map_err(|e| SynthError::Labels {
        path: path.to_path_buf(),
        what: e.to_string(),
    })?;
    afford::report::atomic::write_bytes(path, &bytes).map_err(io_err(path))
}

/// Generates a labelled dataset in `out_dir` (created if needed): `spec.full + spec.view +
/// spec.wall + spec.room` clouds named `NNNN_<kind>_<class>.ply` (binary little endian,
/// vertex `x y z part`) or `.pcd` (every `spec.pcd_every`-th; binary, `x y z` only), and
/// `labels.csv`. Classes cycle through a seeded shuffle of a weighted list so every class
/// appears. The same `seed` and `spec` give byte-identical files.
pub fn generate(
    out_dir: &Path,
    seed: u64,
    spec: &DatasetSpec,
) -> Result<DatasetSummary, SynthError> {
    std::fs::create_dir_all(out_dir).map_err(io_err(out_dir))?;
    let classes: &[Class] = match spec.mix {
        Mix::Default => &CLASSES,
        Mix::Wide => &super::wide::WIDE_CLASSES,
    };
    let mut pool: Vec<Class> = classes
        .iter()
        .flat_map(|&c| std::iter::repeat_n(c, c.weight()))
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // Fisher–Yates with our RNG (deterministic).
    for i in (1..pool.len()).rev() {
        let j = rng.random_range(0..=i);
        pool.swap(i, j);
    }
    let mut jobs = Vec::new();
    for (kind, n) in [
        (SceneKind::Full, spec.full),
        (SceneKind::View, spec.view),
        (SceneKind::Wall, spec.wall),
        (SceneKind::Room, spec.room),
    ] {
        let offset = rng.random_range(0..pool.len());
        for k in 0..n {
            // The wide mix alternates room views and reconstructed rooms.
            let kind = if spec.mix == Mix::Wide && kind == SceneKind::Room && k % 2 == 1 {
                SceneKind::Scan
            } else {
                kind
            };
            jobs.push((kind, pool[(offset + k) % pool.len()]));
        }
    }
    let rows: Vec<Result<LabelRow, SynthError>> = jobs
        .par_iter()
        .enumerate()
        .map(|(i, &(kind, class))| {
            let scene_seed = mix(seed.wrapping_mul(1_000_003) ^ i as u64);
            let mut s = match spec.mix {
                Mix::Default => one_scene(kind, class, scene_seed, spec),
                Mix::Wide => super::wide::one_scene_wide(kind, class, scene_seed, spec),
            };
            if spec.frame == OutFrame::Camera {
                super::wide::to_camera_frame(&mut s, mix(scene_seed ^ 5));
            }
            let pcd = spec.pcd_every > 0 && i % spec.pcd_every == spec.pcd_every - 1;
            let ext = if pcd { "pcd" } else { "ply" };
            let name = format!("{i:04}_{}_{}.{ext}", kind.name(), class.name());
            let path = out_dir.join(&name);
            if pcd {
                cloud::write_pcd(&path, &s.points)?;
            } else {
                let codes = s.parts.iter().map(|&p| part_code(p)).collect();
                cloud::write_ply_points(&path, &s.points, &[("part", codes)], true)?;
            }
            Ok(LabelRow {
                file: name,
                labels: s.labels,
                kind: kind.name().into(),
                class: s.class,
                doubtful: s.doubtful,
                points: s.points.len(),
                frame: (spec.mix != Mix::Default || spec.frame != OutFrame::World)
                    .then(|| spec.frame.name().to_string()),
            })
        })
        .collect();
    let rows = rows.into_iter().collect::<Result<Vec<_>, _>>()?;
    let labels_csv = out_dir.join("labels.csv");
    write_labels(&labels_csv, &rows)?;
    Ok(DatasetSummary { labels_csv, rows })
}

/// How the depth views of a mesh are taken ([`render_mesh_views`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshViews {
    /// Views per mesh.
    pub views: usize,
    /// Pixel stride of the depth camera (2 = 320 × 240 rays).
    pub stride: u32,
    /// Probability of a mixed ("flying") pixel at each depth edge.
    pub mixed_pixels: f64,
    /// The frame each view is written in: the world's (z up, floor at z = 0) or its
    /// camera's (x right, y down, z forward).
    pub frame: OutFrame,
    /// Lowest and highest the camera is held, metres above the floor (drawn uniformly).
    pub camera_height: [f64; 2],
    /// Nearest and farthest the camera stands from the model, metres, horizontally from
    /// the side of the model's bounding box it faces (drawn uniformly); `None` for 1.5-3.0
    /// m from the model's centre plus 0.8 of its half-diagonal beyond 0.5 m, which keeps
    /// most of the model in view.
    pub camera_distance: Option<[f64; 2]>,
}

impl Default for MeshViews {
    /// Three views, stride 2, no mixed pixels, in the world frame, the camera held at
    /// [`CAMERA_HELD_M`].
    fn default() -> Self {
        MeshViews {
            views: 3,
            stride: 2,
            mixed_pixels: 0.0,
            frame: OutFrame::World,
            camera_height: CAMERA_HELD_M,
            camera_distance: None,
        }
    }
}

/// Reads a triangle-mesh PLY (metres, z up, standing on z = 0; e.g.
/// `real-models/meshes/*.ply`) and writes `how.views` depth views of it standing on a
/// floor, seen by the default Kinect-v1 camera (pixel stride `how.stride`) from random
/// azimuths all around (the model's front is unknown), held between `how.camera_height`
/// metres high, at a distance that fits the model in view (or `how.camera_distance` from its
/// box), each in the frame `how.frame`. Files are
/// `<out_dir>/<stem>_vNN.ply` (binary, x y z); returns their paths. Deterministic for
/// `seed`; the frame changes where a view's points are written, not which they are.
pub fn render_mesh_views(
    mesh_path: &Path,
    out_dir: &Path,
    seed: u64,
    how: &MeshViews,
) -> Result<Vec<PathBuf>, SynthError> {
    std::fs::create_dir_all(out_dir).map_err(io_err(out_dir))?;
    let model = read_mesh_ply(mesh_path)?;
    let (lo, hi) = model
        .bounds()
        .unwrap_or((Point3::origin(), Point3::origin()));
    let (cx, cy) = ((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0);
    let r = ((hi.x - lo.x).powi(2) + (hi.y - lo.y).powi(2)).sqrt() / 2.0;
    let mut scene = model;
    scene.append(&big_floor());
    let stem = mesh_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    let mut out = Vec::new();
    for k in 0..how.views {
        let mut rng = ChaCha8Rng::seed_from_u64(mix(seed ^ mix(k as u64)));
        let az = u(&mut rng, -180.0, 180.0).to_radians();
        let dist = match how.camera_distance {
            None => u(&mut rng, 1.5, 3.0) + (r - 0.5).max(0.0) * 0.8,
            Some([near, far]) => {
                // From the centre to the box's side along the azimuth, then beyond it.
                let (hx, hy) = ((hi.x - lo.x) / 2.0, (hi.y - lo.y) / 2.0);
                let (c, s) = (az.cos().abs(), az.sin().abs());
                let to_side = (hx / c.max(1e-9)).min(hy / s.max(1e-9));
                to_side + u(&mut rng, near, far)
            }
        };
        let focus = (hi.z * 0.5).min(0.6);
        let mut cam = camera_at(
            &mut rng,
            cx,
            cy,
            az,
            dist,
            focus,
            how.stride,
            how.camera_height,
        );
        cam.noise.mixed_pixels = how.mixed_pixels;
        let (mut cloud, _) = render_view_triangles(&scene, &cam, mix(seed ^ k as u64 ^ 7));
        if how.frame == OutFrame::Camera {
            cam.into_own_frame(&mut cloud.points);
        }
        let path = out_dir.join(format!("{stem}_v{k:02}.ply"));
        cloud::write_ply_points(&path, &cloud.points, &[], true)?;
        out.push(path);
    }
    Ok(out)
}

/// The labels of the CSV row `rec` under `headers`. Affordance columns other than `1` are 0. The fine-grained lying columns: an
/// empty cell, or a missing column on a lying row, leaves them undecided
/// ([`Labels::posture_unknown`]); a missing column on a row that is not lying is 0.
fn labels_of(headers: &csv::StringRecord, rec: &csv::StringRecord) -> Labels {
    let cell = |n: &str| {
        headers
            .iter()
            .position(|h| h.trim() == n)
            .map(|c| rec.get(c).map(str::trim).unwrap_or(""))
    };
    let flag = |n: &str| cell(n) == Some("1");
    let lying = flag("lying");
    let fine = [
        "elongated_body",
        "raised_body",
        "stretched_legs",
        "raised_legs",
    ];
    let posture_unknown = fine.iter().any(|n| match cell(n) {
        Some(c) => c.is_empty(),
        None => lying,
    });
    Labels {
        sitting: flag("sitting"),
        backrest: flag("backrest"),
        armrest: flag("armrest"),
        headrest: flag("headrest"),
        lying,
        elongated_body: flag("elongated_body"),
        raised_body: flag("raised_body"),
        stretched_legs: flag("stretched_legs"),
        raised_legs: flag("raised_legs"),
        posture_unknown,
    }
}

/// The header and the records of a CSV file.
fn read_csv(path: &Path) -> Result<(csv::StringRecord, Vec<csv::StringRecord>), SynthError> {
    let lerr = |e: csv::Error| SynthError::Labels {
        path: path.to_path_buf(),
        what: e.to_string(),
    };
    let text = std::fs::read_to_string(path).map_err(io_err(path))?;
    let mut rd = csv::Reader::from_reader(text.as_bytes());
    let headers = rd.headers().map_err(lerr)?.clone();
    let records = rd.records().collect::<Result<Vec<_>, _>>().map_err(lerr)?;
    Ok((headers, records))
}

/// Reads a `labels.csv` written by [`write_labels`] (columns found by name, so older files
/// without the fine-grained lying columns read too, see [`labels_of`]).
pub fn read_labels(path: &Path) -> Result<Vec<LabelRow>, SynthError> {
    let lerr = |what: String| SynthError::Labels {
        path: path.to_path_buf(),
        what,
    };
    let (headers, records) = read_csv(path)?;
    let col = |n: &str| headers.iter().position(|h| h.trim() == n);
    let mut rows = Vec::new();
    for rec in records {
        let get = |n: &str| col(n).and_then(|c| rec.get(c)).map(str::trim);
        let text = |n: &str| get(n).unwrap_or("").to_string();
        rows.push(LabelRow {
            file: text("file"),
            labels: labels_of(&headers, &rec),
            kind: text("kind"),
            class: text("class"),
            doubtful: Some(text("doubtful")).filter(|s| !s.is_empty()),
            points: text("points")
                .parse()
                .map_err(|_| lerr(format!("bad 'points' cell for {}", text("file"))))?,
            frame: get("frame").map(String::from),
        });
    }
    Ok(rows)
}

/// Turns a labels file of meshes (like `real-models/labels.csv`: `file` relative to the
/// CSV, affordance columns, `class`, `doubtful`) into a dataset of depth views in
/// `out_dir`: `how.views` views per mesh (see [`render_mesh_views`]) and a
/// `labels.csv` carrying over the affordance columns (missing ones as 0), `class` and
/// `doubtful`, with `kind` = `view` (and `frame` = `camera` where the views are in their
/// cameras' frames). Deterministic for `seed`.
pub fn views_of_labelled_models(
    labels_csv: &Path,
    out_dir: &Path,
    seed: u64,
    how: &MeshViews,
) -> Result<DatasetSummary, SynthError> {
    let lerr = |what: String| SynthError::Labels {
        path: labels_csv.to_path_buf(),
        what,
    };
    let (headers, records) = read_csv(labels_csv)?;
    let col = |n: &str| headers.iter().position(|h| h.trim() == n);
    let fcol = col("file").ok_or_else(|| lerr("no 'file' column".into()))?;
    let base = labels_csv.parent().unwrap_or(Path::new("."));
    let mut rows = Vec::new();
    for (i, rec) in records.iter().enumerate() {
        let get = |n: &str| col(n).and_then(|c| rec.get(c)).map(str::trim).unwrap_or("");
        let labels = labels_of(&headers, rec);
        let file = rec.get(fcol).unwrap_or("").trim();
        let paths = render_mesh_views(&base.join(file), out_dir, mix(seed ^ i as u64), how)?;
        for p in paths {
            let points = cloud::read_ply(&p)?.len();
            rows.push(LabelRow {
                file: p
                    .file_name()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default(),
                labels,
                kind: "view".into(),
                class: get("class").to_string(),
                doubtful: Some(get("doubtful").to_string()).filter(|s| !s.is_empty()),
                points,
                frame: (how.frame == OutFrame::Camera).then(|| how.frame.name().to_string()),
            });
        }
    }
    let out = out_dir.join("labels.csv");
    write_labels(&out, &rows)?;
    Ok(DatasetSummary {
        labels_csv: out,
        rows,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obj(class: Class, seed: u64) -> Object {
        make_object(class, &mut ChaCha8Rng::seed_from_u64(seed))
    }

    fn top_of(m: &Mesh, part: Part) -> Option<f64> {
        (0..m.len())
            .filter(|&i| m.parts[i] == part)
            .flat_map(|i| m.triangle(i))
            .map(|p| p.z)
            .reduce(f64::max)
    }

    #[test]
    fn labels_follow_construction() {
        for seed in 0..20 {
            let s = obj(Class::Stool, seed);
            assert_eq!(
                s.labels,
                Labels {
                    sitting: true,
                    ..Labels::default()
                }
            );
            let seat = top_of(&s.mesh, Part::Seat).unwrap();
            assert!((0.42..=0.50 + 1e-9).contains(&seat), "{seat}");

            let b = obj(Class::BarStool, seed);
            let perched = Labels {
                sitting: true,
                ..Labels::default()
            };
            assert_eq!(b.labels, perched);
            assert!(top_of(&b.mesh, Part::Seat).unwrap() >= 0.65 - 1e-9);

            let c = obj(Class::Chair, seed);
            assert!(c.labels.sitting && c.labels.backrest && !c.labels.headrest);
            let seat = top_of(&c.mesh, Part::Seat).unwrap();
            let back = top_of(&c.mesh, Part::Backrest).unwrap();
            assert!(back - seat >= 0.25, "{back} {seat}");
            assert!(top_of(&c.mesh, Part::Headrest).is_none());

            let h = obj(Class::HighBackChair, seed);
            assert!(h.labels.headrest && h.labels.backrest);
            let seat = top_of(&h.mesh, Part::Seat).unwrap();
            assert!(top_of(&h.mesh, Part::Headrest).unwrap() - seat >= 0.70 - 1e-9);

            let a = obj(Class::Armchair, seed);
            assert!(a.labels.armrest && a.labels.sitting);
            let seat = top_of(&a.mesh, Part::Seat).unwrap();
            let arm = top_of(&a.mesh, Part::Armrest).unwrap() - seat;
            assert!((0.12..=0.35).contains(&arm), "{arm}");

            let bed = obj(Class::Bed, seed);
            assert!(bed.labels.lying && bed.labels.sitting && !bed.labels.backrest);

            let lt = obj(Class::LowTable, seed);
            assert_eq!(lt.labels, Labels::default());
            assert_eq!(lt.doubtful.as_deref(), Some(LOW_TABLE_DOUBT));
            for neg in [
                Class::DiningTable,
                Class::Desk,
                Class::Shelf,
                Class::Lamp,
                Class::Radiator,
            ] {
                let n = obj(neg, seed);
                assert_eq!(n.labels, Labels::default());
                assert!(n.doubtful.is_none());
                assert!(n.mesh.parts.iter().all(|&p| p == Part::Other));
            }
        }
    }

    #[test]
    fn lying_needs_a_long_wide_surface() {
        for seed in 0..40 {
            for class in [Class::Sofa, Class::Bench] {
                let o = obj(class, seed);
                let lying_area = o.mesh.part_area(Part::LyingSurface);
                assert_eq!(o.labels.lying, lying_area > 0.0, "{class:?} {seed}");
                if o.labels.lying {
                    assert!(
                        lying_area >= LYING_MIN_SOFA_LENGTH * LYING_MIN_WIDTH * 0.95,
                        "{lying_area}"
                    );
                }
            }
        }
    }

    #[test]
    fn recliners_follow_the_rules() {
        let (mut lying, mut chairs, mut raised_legs, mut arms, mut unfolded) = (0, 0, 0, 0, 0);
        for seed in 0..80 {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let o = make_object(Class::Recliner, &mut rng);
            // The same seed gives the same recliner.
            let again = obj(Class::Recliner, seed);
            assert_eq!(o.mesh.vertices, again.mesh.vertices);
            assert_eq!(o.labels, again.labels);
            let l = o.labels;
            // Backs at 30-50 deg above level recline 40-60 deg from upright: lying, not a
            // backrest to sit against.
            assert!(
                l.sitting && !l.backrest && !l.headrest && !l.posture_unknown,
                "{l:?}"
            );
            // The seat top (over the origin) at the focus height.
            let seat = o.focus_height;
            assert!((0.40..=0.48 + 1e-9).contains(&seat), "{seat}");
            let over_origin = |part: Part| {
                (0..o.mesh.len())
                    .filter(|&i| o.mesh.parts[i] == part)
                    .flat_map(|i| o.mesh.triangle(i))
                    .any(|p| (p.z - seat).abs() < 1e-9 && p.x.abs() < 0.3)
            };
            assert!(over_origin(if l.lying {
                Part::LyingSurface
            } else {
                Part::Seat
            }));
            // The back top rises 0.7–0.9 m · sin 30–50° above the seat.
            let rise = top_of(&o.mesh, Part::Backrest).unwrap() - seat;
            assert!((0.35 - 1e-9..=0.69).contains(&rise), "{rise}");
            if let Some(arm) = top_of(&o.mesh, Part::Armrest) {
                arms += 1;
                assert_eq!(l.armrest, (0.12..=0.35).contains(&(arm - seat)), "{seed}");
            } else {
                assert!(!l.armrest);
            }
            // Lying only with the leg rest out (then it is a lying surface in front of the
            // seat, and seat + back + leg rest ≥ 1.5 m) and a bed's width
            // (LYING_MIN_WIDTH); the body is raised, the legs stretched or raised by the
            // leg rest's angle.
            let front = o.mesh.bounds().unwrap().1.x;
            assert!(!l.lying || front > 0.5, "{seed}: {front}");
            if front > 0.5 {
                unfolded += 1;
            }
            if l.lying {
                lying += 1;
                assert!(!o.mesh.parts.contains(&Part::Seat));
                assert!(l.raised_body && !l.elongated_body);
                assert!(l.stretched_legs != l.raised_legs);
                // The leg rest's far end is higher than the seat by len · sin(angle).
                let top = top_of(&o.mesh, Part::LyingSurface).unwrap() - seat;
                let len = front - 0.275; // at most: half a 0.55 m seat
                let sin = (top / len).clamp(-1.0, 1.0);
                if l.stretched_legs {
                    assert!(
                        top <= 0.8 * 15f64.to_radians().sin() + 1e-9,
                        "{seed}: {top}"
                    );
                } else {
                    raised_legs += 1;
                    assert!(sin >= 15f64.to_radians().sin() * 0.9, "{seed}: {top} {len}");
                }
            } else {
                chairs += 1;
                assert!(o.mesh.parts.contains(&Part::Seat));
                assert!(!o.mesh.parts.contains(&Part::LyingSurface));
                assert!(!(l.elongated_body || l.raised_body || l.stretched_legs || l.raised_legs));
            }
        }
        // Both kinds, leg rests out and folded, and arms occur.
        assert!(lying >= 5 && raised_legs >= 3 && chairs >= 30 && unfolded >= 30 && arms >= 20);
    }

    #[test]
    fn recliner_rule_is_the_length_along_the_surfaces() {
        // A recliner as wide as a bed (0.75 m, more than LYING_MIN_WIDTH).
        let p = ReclinerParams {
            back_length: 0.7,
            seat_depth: 0.45,
            seat_width: 0.75,
            leg_rest_length: 0.5,
            back_angle_deg: 30.0,
            leg_rest_angle_deg: 20.0,
            ..ReclinerParams::default()
        };
        let l = recliner_labels(&p);
        assert!(l.lying && l.raised_body && l.raised_legs && !l.stretched_legs);
        // Folded, or too short: a chair.
        for q in [
            ReclinerParams {
                leg_rest_folded: true,
                ..p
            },
            ReclinerParams {
                leg_rest_length: 0.3,
                ..p
            },
            ReclinerParams {
                back_angle_deg: 75.0,
                ..p
            },
            // A chair's width: narrower than a bed.
            ReclinerParams {
                seat_width: 0.6,
                ..p
            },
        ] {
            let l = recliner_labels(&q);
            assert!(
                l.sitting && !l.lying && !l.raised_body && !l.raised_legs,
                "{q:?}"
            );
        }
        // A back below 25° is an elongated body; a level leg rest stretched legs.
        let l = recliner_labels(&ReclinerParams {
            back_angle_deg: 20.0,
            leg_rest_angle_deg: 0.0,
            ..p
        });
        assert!(l.elongated_body && !l.raised_body && l.stretched_legs && !l.raised_legs);
        // Headrest and arms by height.
        let l = recliner_labels(&ReclinerParams {
            back_length: 0.9,
            back_angle_deg: 60.0,
            arms: true,
            arm_height_above_seat: 0.36,
            ..p
        });
        assert!(l.headrest && !l.armrest && l.raised_body);
    }

    #[test]
    fn fine_lying_labels_of_beds_benches_and_sofas() {
        for seed in 0..40 {
            let b = obj(Class::Bed, seed).labels;
            assert!(b.elongated_body && b.stretched_legs && !b.raised_body && !b.raised_legs);
            assert!(!b.posture_unknown);
            for class in [
                Class::Sofa,
                Class::Bench,
                Class::BenchWithBack,
                Class::Armchair,
            ] {
                let l = obj(class, seed).labels;
                let any = l.elongated_body || l.raised_body || l.stretched_legs || l.raised_legs;
                if !l.lying {
                    assert!(!any && !l.posture_unknown, "{class:?} {seed}");
                } else if l.posture_unknown {
                    assert_eq!(class, Class::Sofa);
                    assert!(!any);
                    assert_eq!(l.posture_cells(), [""; 4]);
                } else {
                    assert!(l.elongated_body && l.stretched_legs && !l.raised_body);
                    assert_eq!(l.posture_cells(), ["1", "0", "1", "0"]);
                }
            }
        }
        // Sofas are never beds (their seats are narrower than LYING_MIN_WIDTH); wide
        // benches of LYING_MIN_WIDTH and more are daybeds.
        let (mut sofas, mut daybeds) = (0, 0);
        for seed in 0..200 {
            sofas += usize::from(obj(Class::Sofa, seed).labels.lying);
            daybeds += usize::from(obj(Class::Bench, seed).labels.lying);
        }
        assert!(sofas == 0 && daybeds > 5, "{sofas} {daybeds}");
    }

    #[test]
    fn fine_lying_labels_or_over_a_room() {
        let bed = Labels {
            sitting: true,
            lying: true,
            ..Labels::default()
        }
        .with_posture(0.0, 0.0);
        let short_sofa = Labels {
            sitting: true,
            lying: true,
            posture_unknown: true,
            ..Labels::default()
        };
        let recl = Labels {
            lying: true,
            ..Labels::default()
        }
        .with_posture(40.0, 20.0);
        assert_eq!(bed.or(short_sofa).posture_cells(), ["1", "", "1", ""]);
        assert_eq!(bed.or(recl).posture_cells(), ["1", "1", "1", "1"]);
        assert_eq!(
            Labels::default().or(recl).posture_cells(),
            ["0", "1", "0", "1"]
        );
        assert_eq!(Labels::default().posture_cells(), ["0"; 4]);
    }

    #[test]
    fn labels_read_back_with_and_without_fine_columns() {
        let d = tempfile::tempdir().unwrap();
        let row = |file: &str, labels: Labels| LabelRow {
            file: file.into(),
            labels,
            kind: "room".into(),
            class: "bed+sofa".into(),
            doubtful: None,
            points: 7,
            frame: None,
        };
        let rows = vec![
            row(
                "a.ply",
                Labels {
                    lying: true,
                    posture_unknown: true,
                    ..Labels::default()
                }
                .or(Labels {
                    lying: true,
                    ..Labels::default()
                }
                .with_posture(0.0, 20.0)),
            ),
            row("b.ply", Labels::default()),
        ];
        let path = d.path().join("labels.csv");
        write_labels(&path, &rows).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(
            text.contains("a.ply,0,0,0,0,1,room,bed+sofa,,7,1,,,1\n"),
            "{text}"
        );
        assert!(
            text.contains("b.ply,0,0,0,0,0,room,bed+sofa,,7,0,0,0,0\n"),
            "{text}"
        );
        assert_eq!(read_labels(&path).unwrap(), rows);
        // An older file without the fine columns: undecided where lying, 0 elsewhere.
        std::fs::write(
            &path,
            "file,sitting,backrest,armrest,headrest,lying,kind,class,doubtful,points\n\
             a.ply,1,0,0,0,1,full,bed,,5\nb.ply,1,1,0,0,0,full,chair,,6\n",
        )
        .unwrap();
        let back = read_labels(&path).unwrap();
        assert_eq!(back[0].labels.posture_cells(), [""; 4]);
        assert!(back[0].labels.lying && back[0].labels.sitting);
        assert_eq!(back[1].labels.posture_cells(), ["0"; 4]);
        assert_eq!(back[1].points, 6);
    }

    #[test]
    fn a_chair_seen_from_behind_is_a_seat_though_its_seat_is_hidden() {
        use crate::furniture::{chair, ChairParams};
        let mut scene = chair(&ChairParams::default());
        let n = scene.triangles.len();
        scene.append(&big_floor());
        let labels = Labels {
            sitting: true,
            backrest: true,
            ..Labels::default()
        };
        let ranges = [(0, n, labels, None)];
        // The chair faces +x; a camera 2.5 m behind it at 1.2 m looks over its back.
        let behind = Camera::looking_at(p3(-2.5, 0.0, 1.2), p3(0.0, 0.0, 0.45));
        let (_, parts, seen, _) = render_with_visibility(&scene, &ranges, &behind, 1);
        assert!(!parts.contains(&Part::Seat), "the back hides the seat");
        assert!(parts.contains(&Part::Backrest));
        assert_eq!(seen, labels);
        // Looking away from the chair, nothing of it is in view: no labels.
        let away = Camera::looking_at(p3(-2.5, 0.0, 1.2), p3(-5.0, 0.0, 0.45));
        let (_, _, none, _) = render_with_visibility(&scene, &ranges, &away, 1);
        assert_eq!(none, Labels::default());
    }

    /// Views of chairs seen from behind, of 60 seeds: the camera on the side of the
    /// chair's back (its horizontal direction from the chair's middle within 80 degrees of
    /// the back's). By default few are (15% of views are drawn all round, under half of
    /// those from behind: 6 of 60 when written); with `all_round` about half (36).
    fn chair_views_from_behind(all_round: bool) -> usize {
        let spec = DatasetSpec {
            all_round,
            ..DatasetSpec::default()
        };
        let flat = |p: Point3<f64>| nalgebra::Vector2::new(p.x, p.y);
        let centroid = |pts: Vec<Point3<f64>>| {
            let n = pts.len() as f64;
            pts.iter()
                .fold(nalgebra::Vector2::zeros(), |a, &p| a + flat(p))
                / n
        };
        (0..60)
            .filter(|&seed| {
                let s = one_scene(SceneKind::View, Class::Chair, seed, &spec);
                let object: Vec<_> = s
                    .points
                    .iter()
                    .zip(&s.parts)
                    .filter(|(p, _)| p.z > 0.05)
                    .map(|(p, _)| *p)
                    .collect();
                let back: Vec<_> = s
                    .points
                    .iter()
                    .zip(&s.parts)
                    .filter(|(_, &q)| q == Part::Backrest)
                    .map(|(p, _)| *p)
                    .collect();
                let (Some(cam), false) = (s.camera, back.is_empty()) else {
                    return false;
                };
                let middle = centroid(object);
                let to_back = centroid(back) - middle;
                let to_cam = flat(cam.position) - middle;
                to_back.angle(&to_cam) < 80f64.to_radians()
            })
            .count()
    }

    #[test]
    fn all_round_views_see_chairs_from_behind_far_more_often() {
        let (front, round) = (
            chair_views_from_behind(false),
            chair_views_from_behind(true),
        );
        assert!(front <= 9, "default: {front} of 60 from behind");
        assert!(round >= 24, "all round: {round} of 60 from behind");
    }

    #[test]
    fn a_stool_against_a_wall_gets_a_backrest_and_is_seen() {
        let spec = DatasetSpec::default();
        let s = one_scene(SceneKind::Wall, Class::Stool, 5, &spec);
        assert!(s.labels.sitting && s.labels.backrest && s.labels.headrest);
        assert!(s.parts.contains(&Part::Seat));
        let v = one_scene(SceneKind::View, Class::Stool, 5, &spec);
        assert!(v.labels.sitting && !v.labels.backrest);
        // Everything seen is within range of a camera 1.5–3 m away, on or above the floor.
        assert!(v.points.iter().all(|p| p.z > -0.05 && p.x.abs() < 8.0));
        // A bar stool is perched on, and leant back against the wall behind it.
        let b = one_scene(SceneKind::Wall, Class::BarStool, 5, &spec);
        assert!(b.labels.sitting && b.labels.backrest && b.labels.headrest);
        assert!(!b.labels.armrest && !b.labels.lying);
    }

    #[test]
    fn generate_is_deterministic_and_writes_labels() {
        let spec = DatasetSpec {
            full: 2,
            view: 2,
            wall: 1,
            room: 1,
            stride: 8,
            pcd_every: 3,
            full_density: 300.0,
            ..DatasetSpec::default()
        };
        let d1 = tempfile::tempdir().unwrap();
        let d2 = tempfile::tempdir().unwrap();
        let a = generate(d1.path(), 9, &spec).unwrap();
        let b = generate(d2.path(), 9, &spec).unwrap();
        assert_eq!(a.rows, b.rows);
        assert_eq!(a.rows.len(), 6);
        for r in &a.rows {
            let x = std::fs::read(d1.path().join(&r.file)).unwrap();
            let y = std::fs::read(d2.path().join(&r.file)).unwrap();
            assert_eq!(x, y, "{}", r.file);
            let n = cloud::load(&d1.path().join(&r.file)).unwrap().cloud.len();
            assert_eq!(n, r.points);
        }
        assert_eq!(
            a.rows.iter().filter(|r| r.file.ends_with(".pcd")).count(),
            2
        );
        let ply = a.rows.iter().find(|r| r.file.ends_with(".ply")).unwrap();
        let part = cloud::read_ply_property(&d1.path().join(&ply.file), "part").unwrap();
        assert_eq!(part.unwrap().len(), ply.points);
        let text = std::fs::read_to_string(&a.labels_csv).unwrap();
        assert!(
            text.starts_with("file,sitting,backrest,armrest,headrest,lying,kind,class,doubtful")
        );
        assert_eq!(
            text.lines().next().unwrap(),
            "file,sitting,backrest,armrest,headrest,lying,kind,class,doubtful,points,\
             elongated_body,raised_body,stretched_legs,raised_legs"
        );
        assert_eq!(read_labels(&a.labels_csv).unwrap(), a.rows);
        assert_eq!(text.lines().count(), 7);
        assert_eq!(text, std::fs::read_to_string(&b.labels_csv).unwrap());
    }
    #[test]
    fn wide_sets_name_their_frame_and_differ_from_the_default() {
        let spec = DatasetSpec {
            full: 1,
            view: 1,
            wall: 0,
            room: 2,
            stride: 16,
            pcd_every: 0,
            mix: Mix::Wide,
            ..DatasetSpec::default()
        };
        let d = tempfile::tempdir().unwrap();
        let a = generate(d.path(), 4, &spec).unwrap();
        let kinds: Vec<&str> = a.rows.iter().map(|r| r.kind.as_str()).collect();
        assert_eq!(kinds, ["full", "view", "room", "scan"]);
        assert!(a.rows.iter().all(|r| r.frame.as_deref() == Some("world")));
        let text = std::fs::read_to_string(&a.labels_csv).unwrap();
        assert!(text.lines().next().unwrap().ends_with(",raised_legs,frame"));
        assert_eq!(read_labels(&a.labels_csv).unwrap(), a.rows);
        let cam = DatasetSpec {
            frame: OutFrame::Camera,
            ..spec.clone()
        };
        let c = generate(&d.path().join("cam"), 4, &cam).unwrap();
        assert!(c.rows.iter().all(|r| r.frame.as_deref() == Some("camera")));
        // The same scenes, other coordinates.
        for (x, y) in a.rows.iter().zip(&c.rows) {
            assert_eq!((x.points, x.labels), (y.points, y.labels));
            let pa = cloud::load(&d.path().join(&x.file)).unwrap().cloud;
            let pc = cloud::load(&d.path().join("cam").join(&y.file))
                .unwrap()
                .cloud;
            assert_ne!(pa.points, pc.points);
        }
        // A default set writes no frame column.
        let def = generate(
            &d.path().join("def"),
            4,
            &DatasetSpec {
                mix: Mix::Default,
                ..spec
            },
        )
        .unwrap();
        assert!(def.rows.iter().all(|r| r.frame.is_none()));
    }

    #[test]
    fn a_bed_against_a_wall_gets_no_backrest() {
        let spec = DatasetSpec::default();
        for seed in 0..5 {
            let s = one_scene(SceneKind::Wall, Class::Bed, seed, &spec);
            assert!(!s.labels.backrest && !s.labels.headrest && !s.labels.armrest);
        }
        assert!(wall_backs(Class::Toilet) && !wall_backs(Class::BunkBed));
    }

    /// A 0.5 m cube standing on the floor at the origin, as an ascii PLY mesh.
    fn cube_ply(path: &Path) {
        let mut m = Mesh::new();
        m.add_box(p3(-0.25, -0.25, 0.0), p3(0.25, 0.25, 0.5), Part::Other);
        let mut t = format!(
            "ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar int vertex_indices\nend_header\n",
            m.vertices.len(),
            m.triangles.len()
        );
        for v in &m.vertices {
            t += &format!("{} {} {}\n", v.x, v.y, v.z);
        }
        for [a, b, c] in &m.triangles {
            t += &format!("3 {a} {b} {c}\n");
        }
        std::fs::write(path, t).unwrap();
    }

    /// The views of a mesh take the pixel stride and the frame asked: a coarser stride
    /// gives fewer points of the same scene; the camera frame moves every point rigidly
    /// (the distances between them stay) to depths in front of the camera, where the world
    /// frame has the floor at z = 0.
    #[test]
    fn mesh_views_take_the_stride_and_the_frame_asked() {
        let d = tempfile::tempdir().unwrap();
        let mesh = d.path().join("cube.ply");
        cube_ply(&mesh);
        let view = |name: &str, how: MeshViews| {
            let out = d.path().join(name);
            let files = render_mesh_views(&mesh, &out, 4, &how).unwrap();
            assert_eq!(files.len(), how.views);
            cloud::read_ply(&files[0]).unwrap()
        };
        let one = MeshViews {
            views: 1,
            ..MeshViews::default()
        };
        let world = view("world", one);
        let camera = view(
            "camera",
            MeshViews {
                frame: OutFrame::Camera,
                ..one
            },
        );
        let sparse = view("sparse", MeshViews { stride: 4, ..one });
        assert!(world.len() > 1000);
        assert_eq!(camera.len(), world.len());
        assert!(sparse.len() * 3 < world.len() && sparse.len() * 5 > world.len());
        let lowest = world.iter().map(|p| p.z).fold(f64::INFINITY, f64::min);
        assert!(lowest.abs() < 0.05, "{lowest}");
        assert!(camera.iter().all(|p| p.z > 0.3));
        for k in [1, world.len() / 2, world.len() - 1] {
            let (dw, dc) = ((world[k] - world[0]).norm(), (camera[k] - camera[0]).norm());
            assert!((dw - dc).abs() < 1e-3, "{dw} {dc}");
        }
        assert!((camera[0] - world[0]).norm() > 0.1);
    }

    /// Renders `how`'s views of `mesh` into `out` (seed 4) and counts, per view, the
    /// points `keep` takes.
    fn points_per_view(
        mesh: &Path,
        out: &Path,
        how: &MeshViews,
        keep: impl Fn(&Point3<f64>) -> bool,
    ) -> Vec<usize> {
        let files = render_mesh_views(mesh, out, 4, how).unwrap();
        files
            .iter()
            .map(|f| {
                cloud::read_ply(f)
                    .unwrap()
                    .iter()
                    .filter(|p| keep(p))
                    .count()
            })
            .collect()
    }

    /// `camera_height` sets how high the camera is held: above the 0.5 m cube it sees the
    /// cube's top, held below the top it sees none of it (at most its edges), as a robot's
    /// camera sees a desk or a cabinet.
    #[test]
    fn mesh_views_are_seen_from_the_camera_height_asked() {
        let d = tempfile::tempdir().unwrap();
        let mesh = d.path().join("cube.ply");
        cube_ply(&mesh);
        let on_top = |name: &str, camera_height: [f64; 2]| {
            let how = MeshViews {
                views: 2,
                camera_height,
                ..MeshViews::default()
            };
            let top = |p: &Point3<f64>| (p.z - 0.5).abs() < 0.01 && p.x.abs().max(p.y.abs()) < 0.2;
            let counts = points_per_view(&mesh, &d.path().join(name), &how, top);
            counts.into_iter().min().unwrap()
        };
        assert!(on_top("high", [1.5, 1.8]) > 100);
        assert_eq!(on_top("low", [0.3, 0.4]), 0);
    }

    /// `camera_distance` sets how far from the model's side the camera stands: seen from
    /// 0.5-0.7 m the 0.5 m cube fills many more pixels than from 3.0-3.5 m, and in every
    /// view some of it is seen.
    #[test]
    fn mesh_views_stand_at_the_camera_distance_asked() {
        let d = tempfile::tempdir().unwrap();
        let mesh = d.path().join("cube.ply");
        cube_ply(&mesh);
        let cube_points = |name: &str, near: f64, far: f64| {
            let how = MeshViews {
                views: 3,
                camera_distance: Some([near, far]),
                ..MeshViews::default()
            };
            let cube = |p: &Point3<f64>| p.z > 0.05 && p.x.abs().max(p.y.abs()) < 0.26;
            points_per_view(&mesh, &d.path().join(name), &how, cube)
        };
        let (close, far) = (cube_points("close", 0.5, 0.7), cube_points("far", 3.0, 3.5));
        assert!(far.iter().all(|&n| n > 20), "{far:?}");
        let (least_close, most_far) = (close.iter().min().unwrap(), far.iter().max().unwrap());
        assert!(*least_close > 4 * most_far, "{close:?} {far:?}");
    }
}
