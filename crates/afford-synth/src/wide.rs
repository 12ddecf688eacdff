//! The wide synthetic world (`afford synth --mix wide`, issue 11): what real scans have and
//! the default mix lacks, deterministic per seed.
//!
//! * New furniture: wooden armchairs whose arm rails rest on the front posts
//!   ([`wooden_armchair`]), wingback chairs, tub chairs, toilets, night stands (alone and
//!   beside beds), bunk beds, dining tables with chairs pushed under their top, benches
//!   against a wall with a shelf over them.
//! * Beds are dressed: a wrinkled duvet and pillows on the mattress, a headboard rising
//!   0.40–0.80 m above it or none, night stands beside the head end.
//! * Things lie on seats: flat books on any seat, a bag at one end of a seat long enough to
//!   leave a place free ([`THINGS_ON_SEATS_P`]).
//! * Overhangs: table tops over chair seats, shelves over benches, the upper bunk over the
//!   lower one; rooms have a ceiling (views) or have one in most reconstructions.
//! * Samplings: `full` scenes and `scan` rooms are the vertices of a mesh remeshed on a
//!   3.5–5 cm grid ([`afford::mesh::sample_vertex_grid`]), like ScanNet's `_vh_clean_2`
//!   read as points; half of the depth views are subsampled to 20k–50k points.
//! * Cameras look [`PITCH_DEG`] down at the object (the default mix: mostly 10–25°).
//!
//! Labels follow docs/conventions.md, including the rules this world forced
//! (toilets, night stands, headboards, bunk beds, chairs under tables, things on seats);
//! the constants below carry them. World frame as everywhere in [`super`]: metres, z up,
//! floor at z = 0, seating furniture facing +x.

use nalgebra::{Point3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::camera::Camera;
use super::dataset::{
    build_chair, chance, footprint_radius, mix, object_on_floor, p3, render_with_visibility, u,
    Class, DatasetSpec, Labels, Object, Scene, SceneKind, CLASSES,
};
use super::furniture::{
    bed, bench, cabinet, scene_mesh, table, BedParams, BenchParams, CabinetParams, TableParams,
};
use afford::mesh::{sample_vertex_grid, Mesh, Part};

/// Every class of the wide mix: the default ones, then the new ones.
pub const WIDE_CLASSES: [Class; 25] = [
    CLASSES[0],
    CLASSES[1],
    CLASSES[2],
    CLASSES[3],
    CLASSES[4],
    CLASSES[5],
    CLASSES[6],
    CLASSES[7],
    CLASSES[8],
    CLASSES[9],
    CLASSES[10],
    CLASSES[11],
    CLASSES[12],
    CLASSES[13],
    CLASSES[14],
    CLASSES[15],
    CLASSES[16],
    Class::WoodenArmchair,
    Class::Wingback,
    Class::TubChair,
    Class::Toilet,
    Class::NightStand,
    Class::BunkBed,
    Class::TableWithChairs,
    Class::BenchUnderShelf,
];

/// Seat to crown of the 1.75 m adult sitting upright, metres (0.52 H): the headroom a
/// seat under an overhang (upper bunk, shelf) needs to afford sitting.
pub const SITTING_HEIGHT_M: f64 = 0.91;
/// Free depth between a chair's back and the edge of the table it is pushed under, metres:
/// the trunk of the 1.75 m adult (~0.25 m) and a little room; chairs are pushed in no
/// further, so they afford sitting as they stand (docs/conventions.md).
pub const TRUNK_CLEARANCE_M: f64 = 0.30;
/// Highest top above the seat of something beside the body that can be an armrest, metres
/// (the armrest band's top, docs/conventions.md): headboards of the wide mix rise above
/// it, so they are beside the elbow, never under the forearm.
pub const ARMREST_BAND_TOP_M: f64 = 0.35;
/// Highest night-stand top labelled `doubtful` (sittable by geometry, negative by
/// convention), metres: the highest seat the 1.75 m adult perches on with the feet on the
/// floor, 0.37 H (thighs sloping 20 degrees; docs/conventions.md).
pub const NIGHT_STAND_DOUBT_MAX_M: f64 = 0.64;
/// The `doubtful` text of night stands low enough to sit on.
pub const NIGHT_STAND_DOUBT: &str =
    "night stand top at seat height: sittable by geometry, negative by convention";
/// Chance that a seat gets something lying on it.
pub const THINGS_ON_SEATS_P: f64 = 0.35;
/// Shortest seat (along its width) that gets a bag at one end, metres: the bag (≤ 0.35 m)
/// and a free place for one person (0.55 m).
pub const BAG_MIN_SEAT_M: f64 = 0.9;
/// Highest stack of books left on a seat, metres: flat enough to sit on.
pub const FLAT_THING_MAX_M: f64 = 0.05;
/// Camera pitch below level towards the object, degrees (a camera 1.5 m high aimed at a
/// chair 2 m away looks ~30° down; hand-held scans look further down).
pub const PITCH_DEG: (f64, f64) = (10.0, 55.0);
/// Highest camera above the floor outside rooms, metres (held overhead).
pub const MAX_CAMERA_HEIGHT_M: f64 = 2.6;
/// Nearest camera to its target, metres (the depth camera sees from 0.5 m).
pub const MIN_CAMERA_DISTANCE_M: f64 = 0.7;
/// Chance that a depth view is subsampled.
pub const SUBSAMPLE_P: f64 = 0.5;
/// Points kept in a subsampled view (SUN RGB-D style loaders hand over 20k–50k).
pub const SUBSAMPLE_POINTS: (usize, usize) = (20_000, 50_000);
/// Vertex spacing of reconstructed meshes, metres (ScanNet `_vh_clean_2`: ~4 cm).
pub const VERTEX_SPACING_M: (f64, f64) = (0.035, 0.05);
/// Noise on reconstructed vertices, metres (all three axes).
pub const VERTEX_NOISE_M: f64 = 0.004;
/// Room half sizes, metres (rooms 3.6–5.6 m across).
pub const ROOM_HALF_M: (f64, f64) = (1.8, 2.8);
/// Ceiling heights, metres.
pub const CEILING_M: (f64, f64) = (2.4, 2.9);
/// Chance that a reconstructed room keeps its ceiling (S3DIS has them, many ScanNet scans
/// lose them).
pub const SCAN_CEILING_P: f64 = 0.7;

/// What a builder returns: mesh, focus height, labels, doubtful note.
type Built = (Mesh, f64, Labels, Option<String>);

fn seat_labels(back_h: f64, arm_h: Option<f64>) -> Labels {
    Labels {
        sitting: true,
        backrest: back_h >= 0.25,
        armrest: arm_h.is_some_and(|a| (0.12..=ARMREST_BAND_TOP_M).contains(&a)),
        headrest: back_h >= 0.70,
        ..Labels::default()
    }
}

// ---------------------------------------------------------------------------------------
// Wooden armchair
// ---------------------------------------------------------------------------------------

/// Parameters of [`wooden_armchair`]. Metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WoodenArmchairParams {
    /// Seat top above the floor.
    pub seat_height: f64,
    /// Seat depth (x).
    pub seat_depth: f64,
    /// Seat width (y), outer faces of the posts.
    pub seat_width: f64,
    /// Side of the square posts (legs).
    pub post: f64,
    /// Top of the arm rails above the seat.
    pub arm_height_above_seat: f64,
    /// Width (y) of the arm rails.
    pub rail_width: f64,
    /// Thickness (z) of the arm rails.
    pub rail_thickness: f64,
    /// How far the rails reach beyond the front posts (x).
    pub rail_overhang: f64,
    /// Top of the back above the seat.
    pub back_height_above_seat: f64,
    /// Vertical back slats.
    pub slats: usize,
}

/// A wooden armchair: seat on four square posts; the front posts rise to the arm rails,
/// which run from the back posts to just beyond the front posts, centred on them (the
/// rail sits on the front post); a slatted back between the back posts. Rail tops are
/// [`Part::Armrest`], the seat top [`Part::Seat`], the back [`Part::Backrest`]. Seat centre
/// at x = y = 0, facing +x.
pub fn wooden_armchair(p: &WoodenArmchairParams) -> Mesh {
    let mut m = Mesh::new();
    let (hx, hy, ps) = (p.seat_depth / 2.0, p.seat_width / 2.0, p.post);
    let seat = p.seat_height;
    let rail_top = seat + p.arm_height_above_seat;
    let rail_bottom = rail_top - p.rail_thickness;
    let back_top = seat + p.back_height_above_seat;
    m.add_box_with_top(
        p3(-hx, -hy, seat - 0.03),
        p3(hx, hy, seat),
        Part::Seat,
        Part::Other,
    );
    for s in [-1.0, 1.0] {
        let (ya, yb) = if s > 0.0 {
            (hy - ps, hy)
        } else {
            (-hy, -hy + ps)
        };
        // Front post up to the rail; back post up to the back's top.
        m.add_box(p3(hx - ps, ya, 0.0), p3(hx, yb, rail_bottom), Part::Other);
        m.add_box(p3(-hx, ya, 0.0), p3(-hx + ps, yb, seat), Part::Other);
        m.add_box(
            p3(-hx, ya, seat),
            p3(-hx + ps, yb, back_top),
            Part::Backrest,
        );
        // Side stretcher.
        m.add_box(
            p3(-hx + ps, ya + ps * 0.25, 0.14),
            p3(hx - ps, yb - ps * 0.25, 0.14 + ps * 0.6),
            Part::Other,
        );
        let yc = s * (hy - ps / 2.0);
        m.add_box_with_top(
            p3(-hx, yc - p.rail_width / 2.0, rail_bottom),
            p3(hx + p.rail_overhang, yc + p.rail_width / 2.0, rail_top),
            Part::Armrest,
            Part::Other,
        );
    }
    // Top rail and slats of the back, between the back posts.
    let rail_h = 0.07_f64.min(p.back_height_above_seat / 3.0);
    m.add_box(
        p3(-hx, -hy + ps, back_top - rail_h),
        p3(-hx + 0.025, hy - ps, back_top),
        Part::Backrest,
    );
    let n = p.slats.max(1);
    let span = p.seat_width - 2.0 * ps;
    for k in 0..n {
        let y = -hy + ps + span * (k as f64 + 0.5) / n as f64;
        m.add_box(
            p3(-hx + 0.002, y - 0.02, seat + 0.06),
            p3(-hx + 0.022, y + 0.02, back_top - rail_h),
            Part::Backrest,
        );
    }
    m
}

/// A random [`wooden_armchair`] with its labels.
pub(super) fn wooden_armchair_object(rng: &mut ChaCha8Rng) -> Built {
    let p = wooden_armchair_params(rng);
    let labels = seat_labels(p.back_height_above_seat, Some(p.arm_height_above_seat));
    (wooden_armchair(&p), p.seat_height, labels, None)
}

/// Random parameters of a [`wooden_armchair`]: seat 0.42–0.48 m high, rails 0.18–0.26 m
/// above it, back 0.35–0.60 m.
fn wooden_armchair_params(rng: &mut ChaCha8Rng) -> WoodenArmchairParams {
    WoodenArmchairParams {
        seat_height: u(rng, 0.42, 0.48),
        seat_depth: u(rng, 0.44, 0.52),
        seat_width: u(rng, 0.54, 0.64),
        post: u(rng, 0.035, 0.05),
        arm_height_above_seat: u(rng, 0.18, 0.26),
        rail_width: u(rng, 0.045, 0.075),
        rail_thickness: u(rng, 0.02, 0.035),
        rail_overhang: u(rng, 0.0, 0.06),
        back_height_above_seat: u(rng, 0.35, 0.60),
        slats: rng.random_range(3..=5),
    }
}

// ---------------------------------------------------------------------------------------
// Wingback and tub chairs
// ---------------------------------------------------------------------------------------

/// A wingback chair: upholstered base and seat cushion, arms, a back reaching 0.75–0.95 m
/// above the seat (headrest above 0.60 m, as on other high backs) and wings: side panels on the
/// back above the arms reaching forward. Wings are [`Part::Other`].
pub(super) fn wingback_object(rng: &mut ChaCha8Rng) -> Built {
    let seat = u(rng, 0.40, 0.46);
    let (hx, hy) = (u(rng, 0.48, 0.58) / 2.0, u(rng, 0.48, 0.58) / 2.0);
    let cush = u(rng, 0.08, 0.14);
    let aw = u(rng, 0.10, 0.18);
    let ah = u(rng, 0.16, 0.24);
    let bh = u(rng, 0.75, 0.95);
    let bt = u(rng, 0.12, 0.20);
    let wd = u(rng, 0.18, 0.30);
    let wt = u(rng, 0.06, 0.10);
    let leg = u(rng, 0.05, 0.12);
    let mut m = Mesh::new();
    let (yo, xo) = (hy + aw, hx + 0.02);
    for (x, y) in [(xo, yo), (xo, -yo), (-hx - bt, yo), (-hx - bt, -yo)] {
        let (sx, sy) = (x.signum() * 0.04, y.signum() * 0.04);
        m.add_box(p3(x, y, 0.0), p3(x - sx, y - sy, leg), Part::Other);
    }
    m.add_box(p3(-hx, -hy, leg), p3(hx, hy, seat - cush), Part::Other);
    m.add_box_with_top(
        p3(-hx, -hy, seat - cush),
        p3(hx, hy, seat),
        Part::Seat,
        Part::Other,
    );
    for s in [-1.0, 1.0] {
        let (ya, yb) = if s > 0.0 { (hy, yo) } else { (-yo, -hy) };
        m.add_box_with_top(
            p3(-hx, ya, leg),
            p3(xo, yb, seat + ah),
            Part::Armrest,
            Part::Other,
        );
        let (wa, wb) = if s > 0.0 {
            (yo - wt, yo)
        } else {
            (-yo, -yo + wt)
        };
        m.add_box(
            p3(-hx, wa, seat + ah),
            p3(-hx + wd, wb, seat + bh - 0.05),
            Part::Other,
        );
    }
    let split = seat + 0.60;
    m.add_box(p3(-hx - bt, -yo, leg), p3(-hx, yo, split), Part::Backrest);
    m.add_box(
        p3(-hx - bt, -yo, split),
        p3(-hx, yo, seat + bh),
        Part::Headrest,
    );
    (m, seat, seat_labels(bh, Some(ah)), None)
}

/// A tub chair: a round seat cushion in a curved shell open at the front; the shell is
/// highest at the back and falls to the arms at the sides. Shell segments within 60° of
/// the back are [`Part::Backrest`], the others [`Part::Armrest`]. Labels: a backrest (the
/// back rises 0.28–0.40 m above the seat) and an armrest (the shell beside the hips,
/// 90° from the back, 0.16–0.26 m above the seat).
pub(super) fn tub_chair_object(rng: &mut ChaCha8Rng) -> Built {
    let seat = u(rng, 0.40, 0.46);
    let r = u(rng, 0.25, 0.32);
    let cush = u(rng, 0.06, 0.12);
    let t = u(rng, 0.07, 0.12);
    let back_h = u(rng, 0.28, 0.40);
    let side_h = u(rng, 0.16, 0.26);
    let span = u(rng, 125.0, 140.0);
    let base_z = if chance(rng, 0.5) {
        u(rng, 0.08, 0.15)
    } else {
        0.0
    };
    let mut m = Mesh::new();
    if base_z > 0.0 {
        for k in 0..4 {
            let a = std::f64::consts::FRAC_PI_4 + std::f64::consts::FRAC_PI_2 * k as f64;
            let (x, y) = (a.cos() * r * 0.8, a.sin() * r * 0.8);
            m.add_cylinder(p3(x, y, 0.0), p3(x, y, base_z), 0.015, 10, Part::Other);
        }
    }
    m.add_cylinder(
        p3(0.0, 0.0, base_z),
        p3(0.0, 0.0, seat - cush),
        r + t,
        32,
        Part::Other,
    );
    m.add_cylinder_with_top(
        p3(0.0, 0.0, seat - cush),
        p3(0.0, 0.0, seat),
        r,
        32,
        Part::Seat,
        Part::Other,
    );
    let n = 24;
    let rc = r + t / 2.0;
    let step = 2.0 * span / n as f64;
    for k in 0..n {
        // Angle from the back (-x), degrees.
        let off = -span + step * (k as f64 + 0.5);
        let a = (180.0 + off).to_radians();
        let d = off.abs();
        let h = if d <= 90.0 {
            back_h - (back_h - side_h) * d / 90.0
        } else {
            side_h - 0.03 * (d - 90.0) / (span - 90.0).max(1.0)
        };
        let len = rc * step.to_radians() * 1.05;
        let top = seat + h;
        m.add_oriented_box(
            p3(a.cos() * rc, a.sin() * rc, (base_z + top) / 2.0),
            Vector3::new(t / 2.0, len / 2.0, (top - base_z) / 2.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a),
            if d <= 60.0 {
                Part::Backrest
            } else {
                Part::Armrest
            },
        );
    }
    (m, seat, seat_labels(back_h, Some(side_h)), None)
}

// ---------------------------------------------------------------------------------------
// Toilet and night stand
// ---------------------------------------------------------------------------------------

/// Parameters of [`toilet`]. Metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ToiletParams {
    /// Top of the seat ring above the floor.
    pub seat_height: f64,
    /// Ring depth (x) and width (y).
    pub ring_depth: f64,
    /// Ring width (y).
    pub ring_width: f64,
    /// Tank depth (x); 0 for none (a wall-hung bowl with a hidden cistern).
    pub tank_depth: f64,
    /// Tank width (y).
    pub tank_width: f64,
    /// Tank top above the seat ring.
    pub tank_rise: f64,
    /// Gap between the ring's rear edge and the tank's front.
    pub tank_gap: f64,
    /// Whether the lid stands up behind the ring (against the tank).
    pub lid_up: bool,
}

/// Lid of a toilet standing up: its top above the seat ring, metres.
pub const TOILET_LID_RISE_M: f64 = 0.42;

impl ToiletParams {
    /// Whether the toilet has a backrest (docs/conventions.md): the tank or the raised
    /// lid rises at least 0.25 m above the seat ring within 0.15 m behind its rear edge
    /// (the lower back of the 1.75 m adult leaning back at most 35° meets it).
    pub fn backrest(&self) -> bool {
        self.lid_up || (self.tank_depth > 0.0 && self.tank_rise >= 0.25 && self.tank_gap <= 0.15)
    }
}

/// A toilet: a bowl (round) under a seat ring ([`Part::Seat`] on top, open in the middle,
/// water inside), a tank behind it and optionally the lid standing up against the tank.
/// The tank (and the lid) are [`Part::Backrest`] when [`ToiletParams::backrest`], else
/// [`Part::Other`]. Ring centre at x = y = 0, facing +x.
pub fn toilet(p: &ToiletParams) -> Mesh {
    let mut m = Mesh::new();
    let (hx, hy) = (p.ring_depth / 2.0, p.ring_width / 2.0);
    let s = p.seat_height;
    let rt = 0.025;
    let (ix, iy) = (hx - 0.08, hy - 0.07);
    m.add_cylinder(
        p3(0.0, 0.0, s - rt - 0.18),
        p3(0.0, 0.0, s - rt),
        hy.min(hx) * 0.98,
        24,
        Part::Other,
    );
    m.add_cylinder(
        p3(-0.03, 0.0, 0.0),
        p3(-0.03, 0.0, s - rt - 0.18),
        hy * 0.6,
        20,
        Part::Other,
    );
    m.add_horizontal_rect(-ix, -iy, ix, iy, s - 0.14, Part::Other);
    for (x0, y0, x1, y1) in [
        (ix, -hy, hx, hy),
        (-hx, -hy, -ix, hy),
        (-ix, -hy, ix, -iy),
        (-ix, iy, ix, hy),
    ] {
        m.add_box_with_top(p3(x0, y0, s - rt), p3(x1, y1, s), Part::Seat, Part::Other);
    }
    let back = if p.backrest() {
        Part::Backrest
    } else {
        Part::Other
    };
    if p.tank_depth > 0.0 {
        let xf = -hx - p.tank_gap;
        let ty = p.tank_width / 2.0;
        m.add_box(
            p3(xf - p.tank_depth, -ty, s - 0.12),
            p3(xf, ty, s + p.tank_rise),
            back,
        );
        m.add_box(
            p3(xf - p.tank_depth * 0.8, -ty * 0.5, 0.0),
            p3(xf - 0.02, ty * 0.5, s - 0.12),
            Part::Other,
        );
    }
    if p.lid_up {
        // Leaning back 8° from the ring's rear edge (against the tank, if any).
        let tilt = 8.0_f64.to_radians();
        let h = TOILET_LID_RISE_M / tilt.cos();
        let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -tilt);
        let c = p3(-hx - 0.01, 0.0, s) + rot * Vector3::new(-0.01, 0.0, h / 2.0);
        m.add_oriented_box(c, Vector3::new(0.01, hy * 0.95, h / 2.0), rot, back);
    }
    m
}

/// A random [`toilet`] with its labels: sitting; a backrest per
/// [`ToiletParams::backrest`]; never an armrest (nothing beside the body) nor a headrest
/// (tank and lid end below 0.70 m above the seat; a wall behind is the wall rule's).
pub(super) fn toilet_object(rng: &mut ChaCha8Rng) -> Built {
    let tank = chance(rng, 0.85);
    let p = ToiletParams {
        seat_height: u(rng, 0.38, 0.44),
        ring_depth: u(rng, 0.42, 0.48),
        ring_width: u(rng, 0.34, 0.38),
        tank_depth: if tank { u(rng, 0.15, 0.22) } else { 0.0 },
        tank_width: u(rng, 0.36, 0.50),
        tank_rise: u(rng, 0.15, 0.45),
        tank_gap: u(rng, 0.0, 0.06),
        lid_up: chance(rng, 0.35),
    };
    let labels = Labels {
        sitting: true,
        backrest: p.backrest(),
        ..Labels::default()
    };
    (toilet(&p), p.seat_height, labels, None)
}

/// A night stand: a small cabinet 0.45–0.70 m high, sometimes a lamp on it. Never
/// labelled sitting (docs/conventions.md); `doubtful` when its top is free and at most
/// [`NIGHT_STAND_DOUBT_MAX_M`] high.
fn night_stand(rng: &mut ChaCha8Rng) -> (Mesh, f64, Option<String>, f64, f64) {
    let p = CabinetParams {
        width: u(rng, 0.38, 0.55),
        depth: u(rng, 0.32, 0.45),
        height: u(rng, 0.45, 0.70),
        top_overhang: u(rng, 0.0, 0.02),
    };
    let mut m = cabinet(&p);
    let lamp = chance(rng, 0.4);
    if lamp {
        let h = p.height;
        m.add_cylinder(
            p3(0.0, 0.0, h),
            p3(0.0, 0.0, h + 0.03),
            0.08,
            16,
            Part::Other,
        );
        m.add_cylinder(
            p3(0.0, 0.0, h),
            p3(0.0, 0.0, h + 0.35),
            0.012,
            8,
            Part::Other,
        );
        m.add_cylinder(
            p3(0.0, 0.0, h + 0.25),
            p3(0.0, 0.0, h + 0.45),
            0.13,
            20,
            Part::Other,
        );
    }
    let doubt =
        (!lamp && p.height <= NIGHT_STAND_DOUBT_MAX_M).then(|| NIGHT_STAND_DOUBT.to_string());
    (m, p.height, doubt, p.width, p.depth)
}

pub(super) fn night_stand_object(rng: &mut ChaCha8Rng) -> Built {
    let (m, h, doubt, _, _) = night_stand(rng);
    (m, h, Labels::default(), doubt)
}

// ---------------------------------------------------------------------------------------
// Beds
// ---------------------------------------------------------------------------------------

/// A wrinkled duvet over the mattress top at `top` (`hx`, `hy` its half sizes) from
/// `x_head` to the foot end, hanging over the sides, and `pillows` at the head end.
/// Duvet and pillow tops are [`Part::LyingSurface`].
fn dress_bed(m: &mut Mesh, rng: &mut ChaCha8Rng, hx: f64, hy: f64, top: f64, x_head: f64) {
    let dt = u(rng, 0.03, 0.07);
    let waves: Vec<(f64, f64, f64, f64)> = (0..4)
        .map(|_| {
            let a = u(rng, 0.0, std::f64::consts::TAU);
            let k = std::f64::consts::TAU / u(rng, 0.2, 0.7);
            (
                k * a.cos(),
                k * a.sin(),
                u(rng, 0.0, 6.3),
                u(rng, 0.004, 0.015),
            )
        })
        .collect();
    let folds: Vec<(f64, f64, f64, f64, f64)> = (0..rng.random_range(1..=3))
        .map(|_| {
            let a = u(rng, 0.0, std::f64::consts::PI);
            (
                u(rng, x_head, hx),
                u(rng, -hy, hy),
                a,
                u(rng, 0.02, 0.05),
                u(rng, 0.05, 0.12),
            )
        })
        .collect();
    let wrinkle = move |x: f64, y: f64| {
        let w: f64 = waves
            .iter()
            .map(|(kx, ky, ph, amp)| amp * (kx * x + ky * y + ph).sin())
            .sum();
        let f: f64 = folds
            .iter()
            .map(|(fx, fy, a, amp, width)| {
                // Distance to the fold's line.
                let d = (x - fx) * a.sin() - (y - fy) * a.cos();
                amp * (-(d * d) / (2.0 * width * width)).exp()
            })
            .sum();
        // Never into the mattress, however the waves add up.
        (top + dt + w + f).max(top + 0.01)
    };
    let (x0, x1, y0, y1) = (x_head, hx + 0.03, -hy - 0.03, hy + 0.03);
    let nx = crate::count(((x1 - x0) / 0.04).ceil());
    let ny = crate::count(((y1 - y0) / 0.04).ceil());
    m.add_height_field(x0, x1, y0, y1, nx, ny, wrinkle, Part::LyingSurface);
    let drop = u(rng, 0.10, 0.25);
    for (a, b) in [
        (p3(x0, hy + 0.03, top - drop), p3(x1, hy + 0.04, top + dt)),
        (p3(x0, -hy - 0.04, top - drop), p3(x1, -hy - 0.03, top + dt)),
        (
            p3(x1, -hy - 0.04, top - drop),
            p3(x1 + 0.01, hy + 0.04, top + dt),
        ),
    ] {
        m.add_box(a, b, Part::Other);
    }
    let pillows = if 2.0 * hy >= 1.2 { 2 } else { 1 };
    for k in 0..pillows {
        let pw = (2.0 * hy / pillows as f64 - 0.06).min(u(rng, 0.5, 0.7));
        let pd = (x_head - (-hx) - 0.04).max(0.25);
        let ph = u(rng, 0.10, 0.18);
        let yc = -hy + 2.0 * hy * (k as f64 + 0.5) / pillows as f64;
        let xc = -hx + 0.02 + pd / 2.0;
        let dome = move |x: f64, y: f64| {
            let a = 1.0 - (2.0 * (x - xc) / pd).powi(4);
            let b = 1.0 - (2.0 * (y - yc) / pw).powi(4);
            top + 0.005 + ph * a.max(0.0) * b.max(0.0)
        };
        m.add_height_field(
            xc - pd / 2.0,
            xc + pd / 2.0,
            yc - pw / 2.0,
            yc + pw / 2.0,
            10,
            14,
            dome,
            Part::LyingSurface,
        );
    }
}

/// A dressed bed (wide mix): frame, mattress, duvet and pillows ([`dress_bed`]), a
/// headboard rising 0.40–0.80 m above the mattress (beside one sitting on the edge and
/// above the elbow: no backrest, armrest or headrest) or none, and up to two night stands
/// beside the head end. Labels as every bed: sitting and lying flat.
fn dressed_bed_object(rng: &mut ChaCha8Rng) -> Built {
    let length = u(rng, 1.9, 2.1);
    let width = [0.9, 1.2, 1.4, 1.6, 1.8][rng.random_range(0..5)];
    let top = u(rng, 0.40, 0.60);
    let thick = u(rng, 0.15, 0.28);
    let (hx, hy) = (length / 2.0, width / 2.0);
    let hb_t = u(rng, 0.03, 0.08);
    let headboard_height = if chance(rng, 0.8) {
        top + u(rng, ARMREST_BAND_TOP_M + 0.05, 0.80)
    } else {
        0.0
    };
    let mut m = bed(&BedParams {
        length,
        width,
        mattress_height: top,
        mattress_thickness: thick,
        headboard_height,
        headboard_thickness: hb_t,
    });
    let x_head = -hx + u(rng, 0.30, 0.45);
    dress_bed(&mut m, rng, hx, hy, top, x_head);
    for s in [-1.0, 1.0] {
        if chance(rng, 0.5) {
            let (ns, _, _, w, d) = night_stand(rng);
            let gap = u(rng, 0.05, 0.12);
            m.append(&ns.placed(-hx - hb_t + d / 2.0, s * (hy + gap + w / 2.0), 0.0));
        }
    }
    let labels = Labels {
        sitting: true,
        lying: true,
        ..Labels::default()
    }
    .with_posture(0.0, 0.0);
    (m, top, labels, None)
}

/// A bunk bed: the lower bunk's mattress 0.32–0.45 m high, the upper bunk's frame
/// [`SITTING_HEIGHT_M`] + 0.04–0.20 m above it (one sits upright on the lower bunk's
/// edge), corner posts, head panels and guard rails round the upper bunk. The upper
/// mattress (1.4–1.8 m high) is beyond the lying height band (docs/conventions.md) and
/// labelled [`Part::Other`]; labels: sitting and lying flat (the lower bunk).
pub(super) fn bunk_bed_object(rng: &mut ChaCha8Rng) -> Built {
    let (hx, hy) = (u(rng, 1.9, 2.0) / 2.0, u(rng, 0.9, 1.0) / 2.0);
    let lt = u(rng, 0.32, 0.45);
    let mt = u(rng, 0.12, 0.18);
    let clear = SITTING_HEIGHT_M + u(rng, 0.04, 0.20);
    let under = lt + clear;
    let ut = under + 0.05 + u(rng, 0.12, 0.18);
    let post = u(rng, 0.05, 0.07);
    let mut m = Mesh::new();
    m.add_box(
        p3(-hx, -hy, lt - mt - 0.05),
        p3(hx, hy, lt - mt),
        Part::Other,
    );
    m.add_box_with_top(
        p3(-hx, -hy, lt - mt),
        p3(hx, hy, lt),
        Part::LyingSurface,
        Part::Other,
    );
    m.add_box(p3(-hx, -hy, under), p3(hx, hy, under + 0.05), Part::Other);
    m.add_box(p3(-hx, -hy, under + 0.05), p3(hx, hy, ut), Part::Other);
    let rail_top = ut + 0.30;
    for x in [-hx - post, hx] {
        for y in [-hy - post, hy] {
            m.add_box(p3(x, y, 0.0), p3(x + post, y + post, rail_top), Part::Other);
        }
    }
    // Head panel of the lower bunk, head and foot panels of the upper one.
    m.add_box(
        p3(-hx - post, -hy, 0.15),
        p3(-hx, hy, lt + 0.45),
        Part::Other,
    );
    for x in [-hx - post, hx] {
        m.add_box(
            p3(x, -hy, ut - 0.1),
            p3(x + post, hy, rail_top),
            Part::Other,
        );
    }
    // Guard rails of the upper bunk: full length at the back, half at the front.
    m.add_box(
        p3(-hx, -hy - 0.03, ut + 0.12),
        p3(hx, -hy, rail_top),
        Part::Other,
    );
    m.add_box(
        p3(-hx, hy, ut + 0.12),
        p3(0.0, hy + 0.03, rail_top),
        Part::Other,
    );
    if chance(rng, 0.6) {
        let x_head = -hx + u(rng, 0.30, 0.45);
        dress_bed(&mut m, rng, hx, hy, lt, x_head);
    }
    let labels = Labels {
        sitting: true,
        lying: true,
        ..Labels::default()
    }
    .with_posture(0.0, 0.0);
    (m, lt, labels, None)
}

// ---------------------------------------------------------------------------------------
// Overhangs: chairs under a table, a shelf over a bench
// ---------------------------------------------------------------------------------------

/// Extent `(x0, x1, y0, y1, z_top)` of the triangles labelled `part`.
fn part_extent(m: &Mesh, parts: &[Part]) -> Option<(f64, f64, f64, f64, f64)> {
    let mut e: Option<(f64, f64, f64, f64, f64)> = None;
    for (i, p) in m.parts.iter().enumerate() {
        if !parts.contains(p) {
            continue;
        }
        for v in m.triangle(i) {
            e = Some(match e {
                None => (v.x, v.x, v.y, v.y, v.z),
                Some((a, b, c, d, z)) => {
                    (a.min(v.x), b.max(v.x), c.min(v.y), d.max(v.y), z.max(v.z))
                }
            });
        }
    }
    e
}

/// A dining table (1.2–2.0 m long) with one to three armless chairs on each long side
/// pushed under its top: each seat's front edge 0.03 m or more under the top, but at least
/// [`TRUNK_CLEARANCE_M`] left between the chair's back and the table edge. Labels: those
/// of the chairs (the table edge in front is not an armrest).
pub(super) fn table_with_chairs_object(rng: &mut ChaCha8Rng) -> Built {
    let tp = TableParams {
        length: u(rng, 1.2, 2.0),
        width: u(rng, 0.75, 1.0),
        height: u(rng, 0.72, 0.76),
        top_thickness: u(rng, 0.025, 0.05),
        leg_size: u(rng, 0.05, 0.08),
        leg_inset: u(rng, 0.02, 0.10),
    };
    let mut m = table(&tp);
    let usable = tp.length - 2.0 * (tp.leg_inset + tp.leg_size + 0.02);
    let per_side = crate::count((usable / 0.58).floor()).clamp(1, 3);
    let mut labels = Labels::default();
    let mut seat_h: f64 = 0.45;
    let mut placed = 0;
    for s in [-1.0, 1.0] {
        let n = rng.random_range(0..=per_side);
        let n = if s > 0.0 && placed == 0 { n.max(1) } else { n };
        for k in 0..n {
            let back_h = u(rng, 0.28, 0.55);
            let (chair, seat, l) = build_chair(rng, back_h, false);
            let Some((sx0, sx1, _, _, _)) = part_extent(&chair, &[Part::Seat]) else {
                continue;
            };
            let max_push = (sx1 - sx0 - TRUNK_CLEARANCE_M).max(0.03);
            let push = u(rng, 0.03, max_push);
            let yc = s * (tp.width / 2.0 - push + sx1);
            let xc = -usable / 2.0 + usable * (k as f64 + 0.5) / n as f64;
            m.append(&chair.placed(xc, yc, -90.0 * s));
            labels = labels.or(l);
            seat_h = seat;
            placed += 1;
        }
    }
    (m, seat_h, labels, None)
}

/// A backless bench with its back 0–0.10 m from a wall, and a shelf on the wall over it
/// at [`SITTING_HEIGHT_M`] + 0.05–0.45 m above the seat, 0.25–0.40 m deep (over most of
/// the seat). Labels: sitting, and by the wall rule a backrest and a headrest.
pub(super) fn bench_under_shelf_object(rng: &mut ChaCha8Rng) -> Built {
    let p = BenchParams {
        length: u(rng, 0.9, 1.5),
        seat_depth: u(rng, 0.30, 0.42),
        seat_height: u(rng, 0.40, 0.48),
        seat_thickness: u(rng, 0.03, 0.06),
        leg_size: u(rng, 0.04, 0.07),
        back: false,
        ..BenchParams::default()
    };
    let mut m = bench(&p);
    let hx = p.seat_depth / 2.0;
    let hy = p.length / 2.0 + u(rng, 0.1, 0.4);
    let wall_x = -hx - u(rng, 0.0, 0.10);
    let wall_h = u(rng, 1.9, CEILING_M.0 - 0.05);
    m.add_box(
        p3(wall_x - 0.1, -hy, 0.0),
        p3(wall_x, hy, wall_h),
        Part::Other,
    );
    let sh = p.seat_height + SITTING_HEIGHT_M + u(rng, 0.05, 0.45);
    let sd = u(rng, 0.25, 0.40);
    m.add_box(
        p3(wall_x, -hy, sh),
        p3(wall_x + sd, hy, sh + 0.025),
        Part::Other,
    );
    for y in [-hy + 0.1, hy - 0.1] {
        m.add_box(
            p3(wall_x, y - 0.01, sh - 0.15),
            p3(wall_x + sd * 0.6, y + 0.01, sh),
            Part::Other,
        );
    }
    let labels = Labels {
        sitting: true,
        backrest: true,
        headrest: true,
        ..Labels::default()
    };
    (m, p.seat_height, labels, None)
}

// ---------------------------------------------------------------------------------------
// Things on seats
// ---------------------------------------------------------------------------------------

/// Puts something on the seat (or lying surface) of `m`: a bag at one end when the seat
/// is at least [`BAG_MIN_SEAT_M`] long, else a flat stack of books (at most
/// [`FLAT_THING_MAX_M`] high). Either way a person still sits there (docs/conventions.md),
/// so labels do not change. Things are [`Part::Other`].
fn put_thing_on_seat(m: &mut Mesh, rng: &mut ChaCha8Rng) {
    let Some((x0, x1, y0, y1, ztop)) = part_extent(m, &[Part::Seat, Part::LyingSurface]) else {
        return;
    };
    // Height under a point: the highest seat vertex within 0.15 m, else the seat's top.
    let height_at = |m: &Mesh, x: f64, y: f64| {
        let mut best: Option<f64> = None;
        for (i, p) in m.parts.iter().enumerate() {
            if !matches!(p, Part::Seat | Part::LyingSurface) {
                continue;
            }
            for v in m.triangle(i) {
                if (v.x - x).hypot(v.y - y) < 0.15 {
                    best = Some(best.map_or(v.z, |b| b.max(v.z)));
                }
            }
        }
        best.unwrap_or(ztop)
    };
    let (lx, ly) = (x1 - x0, y1 - y0);
    let yaw = u(rng, -20.0, 20.0).to_radians();
    let rot = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw);
    if ly.max(lx) >= BAG_MIN_SEAT_M && chance(rng, 0.6) {
        let (w, d, h) = (u(rng, 0.25, 0.35), u(rng, 0.12, 0.20), u(rng, 0.20, 0.35));
        let (x, y) = if ly >= lx {
            let y = if chance(rng, 0.5) {
                y0 + w / 2.0 + 0.03
            } else {
                y1 - w / 2.0 - 0.03
            };
            ((x0 + x1) / 2.0 + u(rng, -0.1, 0.1) * lx, y)
        } else {
            let x = if chance(rng, 0.5) {
                x0 + w / 2.0 + 0.03
            } else {
                x1 - w / 2.0 - 0.03
            };
            (x, (y0 + y1) / 2.0 + u(rng, -0.1, 0.1) * ly)
        };
        let z = height_at(m, x, y);
        m.add_oriented_box(
            p3(x, y, z + h / 2.0),
            Vector3::new(d / 2.0, w / 2.0, h / 2.0),
            rot,
            Part::Other,
        );
    } else {
        let (bw, bd) = (u(rng, 0.15, 0.22), u(rng, 0.20, 0.28));
        if lx < bw + 0.02 || ly < bd + 0.02 {
            return;
        }
        let x = u(rng, x0 + bw / 2.0, x1 - bw / 2.0);
        let y = u(rng, y0 + bd / 2.0, y1 - bd / 2.0);
        let mut z = height_at(m, x, y);
        let books = rng.random_range(1..=2);
        for _ in 0..books {
            let t = u(rng, 0.015, FLAT_THING_MAX_M / 2.0);
            let r = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw + u(rng, -0.2, 0.2));
            m.add_oriented_box(
                p3(x, y, z + t / 2.0),
                Vector3::new(bw / 2.0, bd / 2.0, t / 2.0),
                r,
                Part::Other,
            );
            z += t;
        }
    }
}

/// One random object of `class` for the wide mix: new classes and dressed beds, and with
/// [`THINGS_ON_SEATS_P`] something lying on its seat.
pub fn make_wide_object(class: Class, rng: &mut ChaCha8Rng) -> Object {
    let mut o = if class == Class::Bed {
        let (mesh, focus_height, labels, doubtful) = dressed_bed_object(rng);
        Object {
            mesh,
            class,
            labels,
            doubtful,
            focus_height,
        }
    } else {
        super::dataset::make_object(class, rng)
    };
    // A bar stool's top holds one person and nothing beside them.
    if o.labels.sitting && o.class != Class::BarStool && chance(rng, THINGS_ON_SEATS_P) {
        put_thing_on_seat(&mut o.mesh, rng);
    }
    o
}

// ---------------------------------------------------------------------------------------
// Cameras, samplings, frames
// ---------------------------------------------------------------------------------------

/// A camera looking [`PITCH_DEG`] down at `(cx, cy, focus)` from azimuth `az` (radians):
/// held 1.0–2.2 m high, moved along its line of sight to between
/// [`MIN_CAMERA_DISTANCE_M`] and 3.5 m away (both plus 0.8 of the object's footprint
/// radius beyond 0.5 m), and lowered along it when above `max_height`. The pitch is kept.
#[allow(clippy::too_many_arguments)]
pub fn pitched_camera(
    rng: &mut ChaCha8Rng,
    cx: f64,
    cy: f64,
    az: f64,
    focus: f64,
    radius: f64,
    stride: u32,
    max_height: f64,
) -> Camera {
    let pitch = u(rng, PITCH_DEG.0, PITCH_DEG.1).to_radians();
    let held = u(rng, 1.0, 2.2);
    let extra = (radius - 0.5).max(0.0) * 0.8;
    let mut d =
        ((held - focus).max(0.1) / pitch.tan()).clamp(MIN_CAMERA_DISTANCE_M + extra, 3.5 + extra);
    let mut h = focus + d * pitch.tan();
    if h > max_height {
        h = max_height.max(focus + MIN_CAMERA_DISTANCE_M * pitch.tan());
        d = (h - focus) / pitch.tan();
    }
    Camera {
        stride,
        ..Camera::looking_at(
            p3(cx + d * az.cos(), cy + d * az.sin(), h),
            p3(cx, cy, focus),
        )
    }
}

/// Pitch of a camera's optical axis below level, degrees.
pub fn pitch_deg(cam: &Camera) -> f64 {
    let d = cam.target - cam.position;
    (-d.z).atan2(d.xy().norm()).to_degrees()
}

/// With [`SUBSAMPLE_P`], keeps a random [`SUBSAMPLE_POINTS`] of the points (in their
/// order); the same number of draws either way.
fn maybe_subsample(points: &mut Vec<Point3<f64>>, parts: &mut Vec<Part>, rng: &mut ChaCha8Rng) {
    let on = chance(rng, SUBSAMPLE_P);
    let n = rng.random_range(SUBSAMPLE_POINTS.0..=SUBSAMPLE_POINTS.1);
    let seed = rng.random::<u64>();
    if on && points.len() > n {
        let keep = subsample_indices(points.len(), n, seed);
        *points = keep.iter().map(|&i| points[i]).collect();
        *parts = keep.iter().map(|&i| parts[i]).collect();
    }
}

/// `n` distinct indices below `len` (all if `n >= len`), drawn with `seed`, ascending.
pub fn subsample_indices(len: usize, n: usize, seed: u64) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..len).collect();
    let n = n.min(len);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    for i in 0..n {
        let j = rng.random_range(i..len);
        idx.swap(i, j);
    }
    idx.truncate(n);
    idx.sort_unstable();
    idx
}

/// Expresses the scene's points in the frame of its camera (x right, y down, z forward,
/// metres); scenes without one (sampled models, scans) get a virtual camera placed as a
/// view's would be, looking [`PITCH_DEG`] down at the middle of the cloud.
pub(super) fn to_camera_frame(s: &mut Scene, seed: u64) {
    let cam = s.camera.unwrap_or_else(|| {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let (lo, hi) = s.points.iter().fold(
            (
                Point3::<f64>::from([f64::INFINITY; 3]),
                Point3::<f64>::from([f64::NEG_INFINITY; 3]),
            ),
            |(lo, hi), p| (lo.inf(p), hi.sup(p)),
        );
        let (cx, cy) = ((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0);
        let r = ((hi.x - lo.x).hypot(hi.y - lo.y) / 2.0).min(3.0);
        let az = u(&mut rng, -180.0, 180.0).to_radians();
        pitched_camera(&mut rng, cx, cy, az, 0.5, r, 1, MAX_CAMERA_HEIGHT_M)
    });
    cam.into_own_frame(&mut s.points);
    s.camera = Some(cam);
}

/// The room of a wide `room` or `scan` scene: walls `2 hx` × `2 hy` and `height` high, a
/// floor, and a ceiling slab when `ceiling`.
fn room_shell(hx: f64, hy: f64, height: f64, ceiling: bool) -> Mesh {
    let mut m = Mesh::new();
    for (a, b) in [
        ((-hx, -hy), (hx, -hy)),
        ((hx, -hy), (hx, hy)),
        ((hx, hy), (-hx, hy)),
        ((-hx, hy), (-hx, -hy)),
    ] {
        m.append(&super::furniture::wall_segment(
            nalgebra::Point2::new(a.0, a.1),
            nalgebra::Point2::new(b.0, b.1),
            height,
            0.1,
        ));
    }
    m.add_horizontal_rect(-hx, -hy, hx, hy, 0.0, Part::Other);
    if ceiling {
        m.add_box(p3(-hx, -hy, height), p3(hx, hy, height + 0.05), Part::Other);
    }
    m
}

/// One scene of the wide mix (see the module documentation); the same inputs give the
/// same scene.
pub(super) fn one_scene_wide(
    kind: SceneKind,
    class: Class,
    seed: u64,
    spec: &DatasetSpec,
) -> Scene {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let obj = make_wide_object(class, &mut rng);
    let yaw = u(&mut rng, -180.0, 180.0);
    let spacing = u(&mut rng, VERTEX_SPACING_M.0, VERTEX_SPACING_M.1);
    match kind {
        SceneKind::Full => {
            let m = obj.mesh.placed(0.0, 0.0, yaw);
            let (c, parts) = sample_vertex_grid(
                &scene_mesh(&[m], true),
                spacing,
                VERTEX_NOISE_M,
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
            let rel = if wall {
                u(&mut rng, -70.0, 70.0)
            } else if obj.labels.sitting
                && obj.class != Class::BarStool
                && !spec.all_round
                && chance(&mut rng, 0.85)
            {
                // Seen mostly from the front; a bar stool has no front.
                u(&mut rng, -80.0, 80.0)
            } else {
                u(&mut rng, -180.0, 180.0)
            };
            let az = (yaw + rel).to_radians();
            let cam = spec.seen_by(pitched_camera(
                &mut rng,
                0.0,
                0.0,
                az,
                obj.focus_height,
                r,
                spec.stride,
                MAX_CAMERA_HEIGHT_M,
            ));
            let (mut points, mut parts, labels, doubtful) = render_with_visibility(
                &scene,
                &[(0, n, labels, obj.doubtful.clone())],
                &cam,
                mix(seed ^ 2),
            );
            maybe_subsample(&mut points, &mut parts, &mut rng);
            Scene {
                points,
                parts,
                labels,
                class: class.name().into(),
                doubtful,
                camera: Some(cam),
            }
        }
        SceneKind::Room | SceneKind::Scan => wide_room(kind, obj, seed, spec, rng, spacing),
    }
}

/// A wide `room` (one pitched view under a ceiling) or `scan` (the whole room as mesh
/// vertices, most with a ceiling) of 2–5 objects, the first being `first`.
fn wide_room(
    kind: SceneKind,
    first: Object,
    seed: u64,
    spec: &DatasetSpec,
    mut rng: ChaCha8Rng,
    spacing: f64,
) -> Scene {
    let (hx, hy) = (
        u(&mut rng, ROOM_HALF_M.0, ROOM_HALF_M.1),
        u(&mut rng, ROOM_HALF_M.0, ROOM_HALF_M.1),
    );
    let height = u(&mut rng, CEILING_M.0, CEILING_M.1);
    let ceiling = kind == SceneKind::Room || chance(&mut rng, SCAN_CEILING_P);
    let want = rng.random_range(2..=5);
    let mut objs = vec![first];
    for _ in 1..want {
        let c = WIDE_CLASSES[rng.random_range(0..WIDE_CLASSES.len())];
        objs.push(make_wide_object(c, &mut rng));
    }
    let mut scene = Mesh::new();
    let mut ranges = Vec::new();
    let mut placed: Vec<(f64, f64, f64, f64)> = Vec::new();
    let mut names = Vec::new();
    for o in &objs {
        let r = footprint_radius(&o.mesh);
        let (lx, ly) = (hx - r - 0.3, hy - r - 0.3);
        if lx < 0.0 || ly < 0.0 {
            continue;
        }
        for _ in 0..50 {
            let (x, y) = (u(&mut rng, -lx, lx), u(&mut rng, -ly, ly));
            if placed
                .iter()
                .all(|(px, py, pr, _)| (x - px).hypot(y - py) > r + pr + 0.3)
            {
                let s = scene.len();
                scene.append(&o.mesh.placed(x, y, u(&mut rng, -180.0, 180.0)));
                ranges.push((s, scene.len(), o.labels, o.doubtful.clone()));
                placed.push((x, y, r, o.focus_height));
                names.push(o.class.name());
                break;
            }
        }
    }
    scene.append(&room_shell(hx, hy, height, ceiling));
    let (points, parts, labels, mut doubtful, camera) = if kind == SceneKind::Scan {
        let (c, parts) = sample_vertex_grid(&scene, spacing, VERTEX_NOISE_M, mix(seed ^ 3));
        let mut labels = Labels::default();
        let mut doubtful = None;
        for (_, _, l, d) in &ranges {
            labels = labels.or(*l);
            if doubtful.is_none() {
                doubtful.clone_from(d);
            }
        }
        (c.points, parts, labels, doubtful, None)
    } else {
        let (tx, ty, _, tf) = placed.first().copied().unwrap_or((0.0, 0.0, 0.0, 0.5));
        let hmax = height - 0.25;
        let mut cam = None;
        for _ in 0..30 {
            let az = u(&mut rng, -180.0, 180.0).to_radians();
            let c = pitched_camera(&mut rng, tx, ty, az, tf, 0.5, spec.stride, hmax);
            if c.position.x.abs() < hx - 0.15 && c.position.y.abs() < hy - 0.15 {
                cam = Some(c);
                break;
            }
        }
        let cam = cam.unwrap_or_else(|| {
            // Towards the middle of the room from the target, close.
            let az = (-ty).atan2(-tx);
            let pitch = u(&mut rng, PITCH_DEG.0, PITCH_DEG.1).to_radians();
            let d = MIN_CAMERA_DISTANCE_M + 0.1;
            let h = (tf + d * pitch.tan()).min(hmax);
            Camera {
                stride: spec.stride,
                ..Camera::looking_at(p3(tx + d * az.cos(), ty + d * az.sin(), h), p3(tx, ty, tf))
            }
        });
        let cam = spec.seen_by(cam);
        let (mut points, mut parts, labels, doubtful) =
            render_with_visibility(&scene, &ranges, &cam, mix(seed ^ 3));
        maybe_subsample(&mut points, &mut parts, &mut rng);
        (points, parts, labels, doubtful, Some(cam))
    };
    if labels.sitting {
        doubtful = None;
    }
    Scene {
        points,
        parts,
        labels,
        class: names.join("+"),
        doubtful,
        camera,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Bvh;
    use afford::mesh::sample_surface;

    fn rng(seed: u64) -> ChaCha8Rng {
        ChaCha8Rng::seed_from_u64(seed)
    }

    fn zs(m: &Mesh, part: Part) -> Vec<f64> {
        (0..m.len())
            .filter(|&i| m.parts[i] == part)
            .flat_map(|i| m.triangle(i))
            .map(|p| p.z)
            .collect()
    }

    fn max(v: &[f64]) -> f64 {
        v.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    }

    fn min(v: &[f64]) -> f64 {
        v.iter().copied().fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn arm_rails_sit_on_the_front_posts_at_armrest_height() {
        for seed in 0..20 {
            let p = wooden_armchair_params(&mut rng(seed));
            let m = wooden_armchair(&p);
            let seat = max(&zs(&m, Part::Seat));
            let rail = max(&zs(&m, Part::Armrest));
            assert!(
                (0.12..=0.35).contains(&(rail - seat)),
                "{seed}: {}",
                rail - seat
            );
            let (cloud, _) = sample_surface(&m, 40_000.0, 0.0, seed);
            let (hx, hy, ps) = (p.seat_depth / 2.0, p.seat_width / 2.0, p.post);
            for s in [-1.0, 1.0] {
                // The column of the front post: surface from the floor up to the rail's
                // top without a gap of 5 cm.
                let yc = s * (hy - ps / 2.0);
                let col: Vec<f64> = cloud
                    .points
                    .iter()
                    .filter(|q| (q.x - (hx - ps / 2.0)).abs() <= ps / 2.0)
                    .filter(|q| (q.y - yc).abs() <= ps / 2.0)
                    .map(|q| q.z)
                    .collect();
                assert!(
                    (max(&col) - rail).abs() < 1e-9,
                    "{seed}: the rail tops the post"
                );
                let bins = crate::count((rail / 0.05).floor());
                for b in 0..bins {
                    let (z0, z1) = (b as f64 * 0.05, (b + 1) as f64 * 0.05);
                    assert!(
                        col.iter().any(|&z| z >= z0 && z < z1),
                        "{seed}: gap in the front post at {z0:.2} m"
                    );
                }
                // The rail covers the post and reaches at least to its front face.
                let rail_pts: Vec<_> = (0..m.len())
                    .filter(|&i| m.parts[i] == Part::Armrest)
                    .flat_map(|i| m.triangle(i))
                    .filter(|q| q.y * s > 0.0)
                    .collect();
                let x_front = rail_pts.iter().map(|q| q.x).fold(f64::MIN, f64::max);
                let (y0, y1) = rail_pts
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(a, b), q| (a.min(q.y), b.max(q.y)));
                assert!(x_front >= hx - 1e-9);
                assert!(y0 <= yc && yc <= y1);
            }
            let (_, _, l, _) = wooden_armchair_object(&mut rng(seed));
            assert!(l.sitting && l.armrest && l.backrest && !l.headrest);
        }
    }

    #[test]
    fn the_ceiling_is_above_everything() {
        for class in WIDE_CLASSES {
            for seed in 0..12 {
                let o = make_wide_object(class, &mut rng(seed));
                let (lo, hi) = o.mesh.bounds().unwrap();
                // Splayed legs' end caps dip a few mm.
                assert!(lo.z > -0.01, "{class:?} {seed}: nothing below the floor");
                assert!(
                    hi.z < CEILING_M.0 - 0.02,
                    "{class:?} {seed}: {} reaches the ceiling",
                    hi.z
                );
            }
        }
        let shell = room_shell(2.0, 2.5, 2.6, true);
        let (lo, hi) = shell.bounds().unwrap();
        assert!((hi.z - 2.65).abs() < 1e-9 && lo.z.abs() < 1e-9);
        // A reconstructed room with its ceiling: the highest points are the ceiling, over
        // the whole room.
        let spec = DatasetSpec::default();
        let mut with_ceiling = 0;
        for seed in 0..6 {
            let s = one_scene_wide(SceneKind::Scan, Class::Sofa, seed, &spec);
            let top = s.points.iter().map(|p| p.z).fold(f64::MIN, f64::max);
            let high = s.points.iter().filter(|p| p.z > CEILING_M.0 - 0.05).count();
            if top > CEILING_M.0 {
                with_ceiling += 1;
                assert!(high > 1000, "{seed}: {high} ceiling points");
            }
            assert!(s.camera.is_none());
        }
        assert!(with_ceiling >= 2);
    }

    #[test]
    fn views_look_10_to_55_degrees_down() {
        let spec = DatasetSpec {
            stride: 16,
            ..DatasetSpec::default()
        };
        let mut lo: f64 = 90.0;
        let mut hi: f64 = 0.0;
        for (k, kind) in [SceneKind::View, SceneKind::Wall, SceneKind::Room]
            .into_iter()
            .enumerate()
        {
            for seed in 0..15 {
                let class =
                    WIDE_CLASSES[(usize::try_from(seed).unwrap() * 7 + k) % WIDE_CLASSES.len()];
                let s = one_scene_wide(kind, class, seed, &spec);
                let p = pitch_deg(&s.camera.unwrap());
                assert!(
                    (PITCH_DEG.0 - 1e-6..=PITCH_DEG.1 + 1e-6).contains(&p),
                    "{kind:?} {seed}: pitch {p}"
                );
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
        // The range is used, not just allowed.
        assert!(lo < 20.0 && hi > 45.0, "{lo} {hi}");
    }

    #[test]
    fn camera_frame_puts_the_scene_in_front_of_the_camera() {
        let spec = DatasetSpec {
            stride: 8,
            ..DatasetSpec::default()
        };
        for (kind, class) in [
            (SceneKind::View, Class::Chair),
            (SceneKind::Full, Class::Toilet),
        ] {
            let world = one_scene_wide(kind, class, 3, &spec);
            let mut cam = one_scene_wide(kind, class, 3, &spec);
            to_camera_frame(&mut cam, 17);
            let c = cam.camera.unwrap();
            let (f, r, u) = c.basis();
            assert_eq!(world.points.len(), cam.points.len());
            for (w, q) in world.points.iter().zip(&cam.points) {
                // Depth along the optical axis is positive; the inverse map gives the
                // world point back.
                assert!(q.z > 0.0, "{kind:?}: behind the camera");
                let back = c.position + r * q.x - u * q.y + f * q.z;
                assert!((back - w).norm() < 1e-9);
            }
            // The floor is no longer at z = 0 in any axis: the camera is above it.
            let floor_y = cam
                .points
                .iter()
                .zip(&world.points)
                .filter(|(_, w)| w.z.abs() < 0.02)
                .map(|(q, _)| q.y)
                .fold(f64::MIN, f64::max);
            assert!(floor_y > 0.3, "{kind:?}: floor below the camera: {floor_y}");
        }
    }

    #[test]
    fn toilets_follow_the_convention() {
        let mut backed = [0, 0];
        for seed in 0..40 {
            let mut r = rng(seed);
            let (m, seat, l, d) = toilet_object(&mut r);
            assert!(d.is_none() && l.sitting && !l.armrest && !l.headrest && !l.lying);
            assert!((max(&zs(&m, Part::Seat)) - seat).abs() < 1e-9);
            let back = zs(&m, Part::Backrest);
            assert_eq!(l.backrest, !back.is_empty(), "{seed}");
            if l.backrest {
                assert!(max(&back) - seat >= 0.25 - 1e-9, "{seed}");
            }
            assert!(m
                .parts
                .iter()
                .all(|p| !matches!(p, Part::Armrest | Part::Headrest)));
            // The seat is a ring: nothing labelled seat at its centre.
            let centre_seat = (0..m.len())
                .filter(|&i| m.parts[i] == Part::Seat)
                .flat_map(|i| m.triangle(i))
                .any(|q| q.x.abs() < 0.05 && q.y.abs() < 0.05);
            assert!(!centre_seat);
            backed[usize::from(l.backrest)] += 1;
        }
        assert!(backed[0] > 0 && backed[1] > 0, "{backed:?}");
    }

    #[test]
    fn night_stands_are_never_seats() {
        let mut doubtful = 0;
        for seed in 0..30 {
            let (m, h, l, d) = night_stand_object(&mut rng(seed));
            assert_eq!(l, Labels::default());
            assert!(m.parts.iter().all(|&p| p == Part::Other));
            if let Some(d) = d {
                assert_eq!(d, NIGHT_STAND_DOUBT);
                assert!(h <= NIGHT_STAND_DOUBT_MAX_M);
                doubtful += 1;
            }
        }
        assert!(doubtful > 0);
    }

    #[test]
    fn beds_are_dressed_and_headboards_clear_the_armrest_band() {
        for seed in 0..20 {
            let (m, top, l, _) = dressed_bed_object(&mut rng(seed));
            assert!(l.lying && l.sitting && !l.backrest && !l.armrest && !l.headrest);
            let lying = zs(&m, Part::LyingSurface);
            assert!((min(&lying) - top).abs() < 1e-9);
            // Wrinkled duvet and pillows: the soft top is raised and uneven.
            let above: Vec<f64> = lying.iter().copied().filter(|&z| z > top + 1e-6).collect();
            let mean = above.iter().sum::<f64>() / above.len() as f64;
            let sd =
                (above.iter().map(|z| (z - mean).powi(2)).sum::<f64>() / above.len() as f64).sqrt();
            assert!(sd > 0.005 && max(&above) - top > 0.08, "{seed}: sd {sd}");
            // Down onto the head end: a headboard rises beyond the armrest band, else
            // the first thing met is a pillow or the mattress.
            let (lo, _) = m.bounds().unwrap();
            if let Some(hit) = Bvh::new(&m).cast(&p3(lo.x + 0.01, 0.0, 3.0), &-Vector3::z()) {
                let rise = 3.0 - hit.t - top;
                assert!(
                    rise >= ARMREST_BAND_TOP_M + 0.05 - 1e-9 || rise <= 0.2,
                    "{seed}: {rise}"
                );
            }
        }
    }

    #[test]
    fn the_lower_bunk_has_headroom_to_sit() {
        for seed in 0..20 {
            let (m, lt, l, _) = bunk_bed_object(&mut rng(seed));
            assert!(l.sitting && l.lying);
            let lying = zs(&m, Part::LyingSurface);
            assert!((min(&lying) - lt).abs() < 1e-9);
            let (lo, hi) = m.bounds().unwrap();
            let bvh = Bvh::new(&m);
            // Straight up from anywhere over the lower mattress (above duvet and pillows),
            // the first thing hit is the upper bunk, with room to sit upright below it.
            for i in 1..10 {
                for j in 1..5 {
                    let x = lo.x + (hi.x - lo.x) * i as f64 / 10.0;
                    let y = lo.y + (hi.y - lo.y) * j as f64 / 5.0;
                    let from = p3(x, y, lt + 0.3);
                    let hit = bvh.cast(&from, &Vector3::z()).expect("an upper bunk");
                    assert!(hit.t + 0.3 >= SITTING_HEIGHT_M, "{seed}: {}", hit.t + 0.3);
                    assert!(hit.t + 0.3 <= SITTING_HEIGHT_M + 0.21, "{seed}");
                }
            }
        }
    }

    #[test]
    fn chairs_go_under_the_table_top() {
        for seed in 0..20 {
            let (m, _, l, _) = table_with_chairs_object(&mut rng(seed));
            assert!(l.sitting && !l.armrest);
            // The table top is the largest triangle; some seat lies under it.
            let big = (0..m.len())
                .max_by(|&a, &b| m.triangle_area(a).total_cmp(&m.triangle_area(b)))
                .unwrap();
            let top = m.triangle(big);
            let ymax = top.iter().map(|q| q.y.abs()).fold(0.0, f64::max);
            let under = (0..m.len())
                .filter(|&i| m.parts[i] == Part::Seat)
                .flat_map(|i| m.triangle(i))
                .any(|q| q.y.abs() < ymax - 0.02 && q.z < top[0].z);
            assert!(under, "{seed}");
        }
    }

    #[test]
    fn things_on_a_chair_are_flat() {
        for seed in 0..30 {
            let mut r = rng(seed);
            let o = crate::dataset::make_object(Class::Chair, &mut r);
            let mut m = o.mesh.clone();
            put_thing_on_seat(&mut m, &mut r);
            let added = &m.vertices[o.mesh.vertices.len()..];
            if added.is_empty() {
                continue;
            }
            let top = added.iter().map(|q| q.z).fold(f64::MIN, f64::max);
            assert!(top - o.focus_height <= FLAT_THING_MAX_M + 1e-9, "{seed}");
            assert!(top > o.focus_height, "{seed}: on the seat");
        }
    }

    #[test]
    fn subsampling_keeps_distinct_points_in_order() {
        let k = subsample_indices(1000, 300, 4);
        assert_eq!(k.len(), 300);
        assert!(k.windows(2).all(|w| w[0] < w[1]));
        assert!(k.iter().all(|&i| i < 1000));
        assert_eq!(subsample_indices(10, 20, 4), (0..10).collect::<Vec<_>>());
        assert_ne!(k, subsample_indices(1000, 300, 5));
    }
}
