//! Parametric furniture as labelled meshes, built from boxes and cylinders.
//!
//! Conventions (world frame, metres, z up):
//! * every piece stands on the floor (lowest point at z = 0);
//! * seating furniture faces +x: a seated person looks towards +x and the backrest is on
//!   the -x side; the centre of the sitting (or lying) surface is at x = y = 0, so the
//!   expected place of the person is above the origin;
//! * other pieces (tables, desks, shelves, cabinets) have their footprint centred at the
//!   origin, with their front (the user's side, the open side) towards +x;
//! * labels: seat top = [`Part::Seat`], back = [`Part::Backrest`] (the part of a high back
//!   above the sitter's shoulders = [`Part::Headrest`]), arm tops = [`Part::Armrest`],
//!   mattress top = [`Part::LyingSurface`], everything else [`Part::Other`].
//!
//! Default dimensions follow common furniture standards and ergonomic guidance; they are
//! noted on each parameter struct. Angles are in degrees.

use nalgebra::{Point2, Point3, UnitQuaternion, Vector3};

use afford::cloud::PointCloud;
use afford::mesh::{sample_surface, Mesh, Part};

/// Number of side segments used for cylinders (legs, round seats, pedestals).
pub const CYLINDER_SEGMENTS: u32 = 24;

/// How far (metres) the floor patch of [`scene_mesh`] / [`scene_cloud`] extends beyond
/// the objects' footprint on every side.
pub const FLOOR_MARGIN_M: f64 = 0.5;

fn p(x: f64, y: f64, z: f64) -> Point3<f64> {
    Point3::new(x, y, z)
}

/// Adds a (possibly tilted) back panel rising from the rear edge of a seat.
///
/// The panel's front face passes through `(x_front, ·, z_bottom)` and leans back (towards
/// -x) by `tilt_deg` from vertical. It spans `width` in y (centred on y = 0), is
/// `thickness` thick and reaches `height_above_seat` vertically above `seat_top`.
/// The part of it higher than `headrest_from` above the seat (if any) is labelled
/// [`Part::Headrest`], the rest [`Part::Backrest`].
#[allow(clippy::too_many_arguments)]
fn add_back_panel(
    m: &mut Mesh,
    x_front: f64,
    z_bottom: f64,
    seat_top: f64,
    width: f64,
    height_above_seat: f64,
    thickness: f64,
    tilt_deg: f64,
    headrest_from: Option<f64>,
) {
    let theta = tilt_deg.clamp(0.0, 60.0).to_radians();
    let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -theta);
    let up = rot * Vector3::z(); // (-sin θ, 0, cos θ): along the panel, leaning back
    let front = rot * Vector3::x(); // (cos θ, 0, sin θ): the panel's front normal
    let origin = p(x_front, 0.0, z_bottom) - front * (thickness / 2.0);
    let top = seat_top + height_above_seat;
    let mut segment = |z0: f64, z1: f64, part: Part| {
        if z1 <= z0 {
            return;
        }
        let (s0, s1) = ((z0 - z_bottom) / theta.cos(), (z1 - z_bottom) / theta.cos());
        let centre = origin + up * ((s0 + s1) / 2.0);
        let half = Vector3::new(thickness / 2.0, width / 2.0, (s1 - s0) / 2.0);
        m.add_oriented_box(centre, half, rot, part);
    };
    match headrest_from {
        Some(h0) if height_above_seat > h0 => {
            let split = seat_top + h0.max(0.0);
            segment(z_bottom, split, Part::Backrest);
            segment(split, top, Part::Headrest);
        }
        _ => segment(z_bottom, top, Part::Backrest),
    }
}

/// Adds four square legs of side `size` from the floor to `z_top`, inset by `inset` from
/// the corners of the rectangle `x0..x1` × `y0..y1`.
#[allow(clippy::too_many_arguments)]
fn add_square_legs(
    m: &mut Mesh,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    inset: f64,
    size: f64,
    z_top: f64,
) {
    for (xa, xb) in [
        (x0 + inset, x0 + inset + size),
        (x1 - inset - size, x1 - inset),
    ] {
        for (ya, yb) in [
            (y0 + inset, y0 + inset + size),
            (y1 - inset - size, y1 - inset),
        ] {
            m.add_box(p(xa, ya, 0.0), p(xb, yb, z_top), Part::Other);
        }
    }
}

// ---------------------------------------------------------------------------------------
// Stool
// ---------------------------------------------------------------------------------------

/// What a stool stands on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum StoolBase {
    /// Four vertical round legs under the seat.
    FourLegs,
    /// One central column on a round foot plate.
    Pedestal,
}

/// Parameters of [`stool`]. Metres.
///
/// Default: a low stool, round seat 0.35 m across at 0.45 m (seat heights of 0.43–0.48 m
/// as for chairs, cf. ANSI/BIFMA X5.1 and EN 1335-1 ranges), on four legs.
/// [`StoolParams::bar`] gives a bar stool (seat 0.75 m; bar stools are 0.65–0.80 m high
/// for counters and bars of 0.90–1.10 m).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct StoolParams {
    /// Height of the seat top above the floor, metres (default 0.45).
    pub seat_height: f64,
    /// Seat diameter (round) or side (square), metres (default 0.35; usual 0.30–0.40).
    pub seat_size: f64,
    /// Seat thickness, metres (default 0.04).
    pub seat_thickness: f64,
    /// Round (true, default) or square seat.
    pub round: bool,
    /// Legs or pedestal (default four legs).
    pub base: StoolBase,
    /// Leg radius, metres (default 0.015; the pedestal column is twice as thick).
    pub leg_radius: f64,
}

impl Default for StoolParams {
    fn default() -> Self {
        Self {
            seat_height: 0.45,
            seat_size: 0.35,
            seat_thickness: 0.04,
            round: true,
            base: StoolBase::FourLegs,
            leg_radius: 0.015,
        }
    }
}

impl StoolParams {
    /// A bar stool: round seat 0.36 m at 0.75 m on a pedestal.
    pub fn bar() -> Self {
        Self {
            seat_height: 0.75,
            seat_size: 0.36,
            base: StoolBase::Pedestal,
            ..Self::default()
        }
    }
}

/// A stool: seat (top = [`Part::Seat`]) on four legs or a pedestal, seat centred at the
/// origin, standing on z = 0.
pub fn stool(params: &StoolParams) -> Mesh {
    let s = params;
    let mut m = Mesh::new();
    let top = s.seat_height;
    let bottom = top - s.seat_thickness;
    let r = s.seat_size / 2.0;
    if s.round {
        m.add_cylinder_with_top(
            p(0.0, 0.0, bottom),
            p(0.0, 0.0, top),
            r,
            CYLINDER_SEGMENTS * 2,
            Part::Seat,
            Part::Other,
        );
    } else {
        m.add_box_with_top(p(-r, -r, bottom), p(r, r, top), Part::Seat, Part::Other);
    }
    match s.base {
        StoolBase::FourLegs => {
            // Legs well inside the seat edge (on a round seat, inside the inscribed square).
            let a = r * if s.round { 0.6 } else { 0.8 };
            for (x, y) in [(a, a), (a, -a), (-a, a), (-a, -a)] {
                m.add_cylinder(
                    p(x, y, 0.0),
                    p(x, y, bottom),
                    s.leg_radius,
                    CYLINDER_SEGMENTS,
                    Part::Other,
                );
            }
        }
        StoolBase::Pedestal => {
            let plate = 0.02;
            m.add_cylinder(
                p(0.0, 0.0, 0.0),
                p(0.0, 0.0, plate),
                r * 1.1,
                CYLINDER_SEGMENTS * 2,
                Part::Other,
            );
            m.add_cylinder(
                p(0.0, 0.0, plate),
                p(0.0, 0.0, bottom),
                2.0 * s.leg_radius,
                CYLINDER_SEGMENTS,
                Part::Other,
            );
        }
    }
    m
}

// ---------------------------------------------------------------------------------------
// Chair
// ---------------------------------------------------------------------------------------

/// Parameters of [`chair`]. Metres and degrees.
///
/// Defaults: a dining/side chair. Seat height 0.45 m (0.43–0.48 m typical for fixed
/// chairs; cf. ANSI/BIFMA X5.1 and the EN 1335-1 office chair range 0.42–0.51 m), seat
/// depth 0.42 m (0.40–0.45), seat width 0.46 m (0.40–0.50; EN 1335-1 asks ≥ 0.40 m),
/// seat slab 0.04 m (0.03–0.05), back 0.40 m above the seat (0.35–0.45) tilted 8° back
/// (seat–back angle ≈ 100°), no arms; arms when enabled 0.22 m above the seat
/// (0.18–0.25 m, EN 1335-1: 0.20–0.25 m). A back whose top is more than
/// `headrest_from_above_seat` (0.60 m, about sitting shoulder height) above the seat has
/// its upper part labelled [`Part::Headrest`]; see [`ChairParams::high_back`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ChairParams {
    /// Height of the seat top above the floor, metres (default 0.45).
    pub seat_height: f64,
    /// Seat width (y), metres (default 0.46).
    pub seat_width: f64,
    /// Seat depth (x), metres (default 0.42).
    pub seat_depth: f64,
    /// Seat slab thickness, metres (default 0.04).
    pub seat_thickness: f64,
    /// Side of the square legs, metres (default 0.035).
    pub leg_size: f64,
    /// Vertical height of the back's top above the seat top, metres (default 0.40;
    /// 0 for no back at all).
    pub back_height_above_seat: f64,
    /// Back panel thickness, metres (default 0.03).
    pub back_thickness: f64,
    /// Backward tilt of the back from vertical, degrees (default 8; clamped to 0–60).
    pub back_tilt_deg: f64,
    /// Whether the chair has armrests (default false).
    pub arms: bool,
    /// Height of the armrest tops above the seat top, metres (default 0.22).
    pub arm_height_above_seat: f64,
    /// Width (y) of each armrest bar, metres (default 0.05).
    pub arm_width: f64,
    /// Height above the seat from which the back counts as headrest, metres
    /// (default 0.60); backs lower than this have no headrest.
    pub headrest_from_above_seat: f64,
}

impl Default for ChairParams {
    fn default() -> Self {
        Self {
            seat_height: 0.45,
            seat_width: 0.46,
            seat_depth: 0.42,
            seat_thickness: 0.04,
            leg_size: 0.035,
            back_height_above_seat: 0.40,
            back_thickness: 0.03,
            back_tilt_deg: 8.0,
            arms: false,
            arm_height_above_seat: 0.22,
            arm_width: 0.05,
            headrest_from_above_seat: 0.60,
        }
    }
}

impl ChairParams {
    /// A high-back chair: the default chair with its back top 0.80 m above the seat
    /// (0.75–0.85 m typical), the top 0.20 m of which is [`Part::Headrest`].
    pub fn high_back() -> Self {
        Self {
            back_height_above_seat: 0.80,
            back_tilt_deg: 12.0,
            ..Self::default()
        }
    }

    /// An armchair-style chair: the default chair with armrests.
    pub fn with_arms() -> Self {
        Self {
            arms: true,
            ..Self::default()
        }
    }
}

/// A chair: four legs, seat slab (top = [`Part::Seat`]), back panel rising from the rear
/// (-x) edge of the seat (tilted back by `back_tilt_deg`), and optionally armrest bars
/// ([`Part::Armrest`]) on posts on both sides, outside the seat width. The seat centre is
/// at x = y = 0; the chair stands on z = 0 and faces +x.
pub fn chair(params: &ChairParams) -> Mesh {
    let c = params;
    let mut m = Mesh::new();
    let (hx, hy) = (c.seat_depth / 2.0, c.seat_width / 2.0);
    let top = c.seat_height;
    let bottom = top - c.seat_thickness;
    m.add_box_with_top(p(-hx, -hy, bottom), p(hx, hy, top), Part::Seat, Part::Other);
    add_square_legs(&mut m, -hx, hx, -hy, hy, 0.01, c.leg_size, bottom);
    if c.back_height_above_seat > 0.0 {
        add_back_panel(
            &mut m,
            -hx,
            bottom,
            top,
            c.seat_width,
            c.back_height_above_seat,
            c.back_thickness,
            c.back_tilt_deg,
            Some(c.headrest_from_above_seat),
        );
    }
    if c.arms {
        let bar = 0.03;
        let arm_top = top + c.arm_height_above_seat;
        let post = 0.03;
        for side in [-1.0, 1.0] {
            let (y0, y1) = if side > 0.0 {
                (hy, hy + c.arm_width)
            } else {
                (-hy - c.arm_width, -hy)
            };
            m.add_box(
                p(-hx, y0, arm_top - bar),
                p(hx - 0.02, y1, arm_top),
                Part::Armrest,
            );
            let yc = (y0 + y1) / 2.0;
            for x in [-hx + 0.01, hx - 0.06] {
                m.add_box(
                    p(x, yc - post / 2.0, bottom),
                    p(x + post, yc + post / 2.0, arm_top - bar),
                    Part::Other,
                );
            }
        }
    }
    m
}

// ---------------------------------------------------------------------------------------
// Sofa / armchair
// ---------------------------------------------------------------------------------------

/// Parameters of [`sofa`] and [`armchair`]. Metres.
///
/// Defaults: a three-seat sofa. Seat (cushion top) 0.43 m high (upholstered seating is
/// usually 0.40–0.45 m), seat depth 0.55 m (0.50–0.60), 0.55 m of width per seat
/// (0.50–0.60), cushions 0.13 m thick on a solid base, back 0.40 m above the seat and
/// 0.20 m thick, arms 0.18 m wide reaching 0.20 m above the seat (0.18–0.25).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SofaParams {
    /// Number of seats side by side (default 3; at least 1).
    pub seats: u32,
    /// Width (y) of each seat cushion, metres (default 0.55).
    pub seat_width_per_person: f64,
    /// Depth (x) of the seat cushions, metres (default 0.55).
    pub seat_depth: f64,
    /// Height of the cushion tops above the floor, metres (default 0.43).
    pub seat_height: f64,
    /// Cushion thickness, metres (default 0.13); the solid base fills the rest below.
    pub cushion_thickness: f64,
    /// Height of the back's top above the seat, metres (default 0.40).
    pub back_height_above_seat: f64,
    /// Back thickness (x), metres (default 0.20).
    pub back_thickness: f64,
    /// Width (y) of each side arm, metres (default 0.18).
    pub arm_width: f64,
    /// Height of the arm tops above the seat, metres (default 0.20).
    pub arm_height_above_seat: f64,
}

impl Default for SofaParams {
    fn default() -> Self {
        Self {
            seats: 3,
            seat_width_per_person: 0.55,
            seat_depth: 0.55,
            seat_height: 0.43,
            cushion_thickness: 0.13,
            back_height_above_seat: 0.40,
            back_thickness: 0.20,
            arm_width: 0.18,
            arm_height_above_seat: 0.20,
        }
    }
}

/// A sofa: solid base, one cushion per seat (top = [`Part::Seat`]), a thick back behind
/// them (above the seat: [`Part::Backrest`]) and a solid arm at each side (above the seat:
/// [`Part::Armrest`]). The centre of the row of cushions is at x = y = 0; the sofa stands
/// on z = 0 and faces +x. Total width = `seats · seat_width_per_person + 2 · arm_width`.
pub fn sofa(params: &SofaParams) -> Mesh {
    let s = params;
    let mut m = Mesh::new();
    let n = s.seats.max(1);
    let hx = s.seat_depth / 2.0;
    let hy = n as f64 * s.seat_width_per_person / 2.0;
    let top = s.seat_height;
    let base_top = (top - s.cushion_thickness).max(0.0);
    let x_back = -hx - s.back_thickness;
    // Base under the cushions.
    if base_top > 0.0 {
        m.add_box(p(-hx, -hy, 0.0), p(hx, hy, base_top), Part::Other);
    }
    // Cushions.
    for k in 0..n {
        let y0 = -hy + k as f64 * s.seat_width_per_person;
        m.add_box_with_top(
            p(-hx, y0, base_top),
            p(hx, y0 + s.seat_width_per_person, top),
            Part::Seat,
            Part::Other,
        );
    }
    // Back: below the seat it is frame, above it the backrest.
    m.add_box(p(x_back, -hy, 0.0), p(-hx, hy, top), Part::Other);
    m.add_box(
        p(x_back, -hy, top),
        p(-hx, hy, top + s.back_height_above_seat),
        Part::Backrest,
    );
    // Arms over the full depth, at both sides.
    let arm_top = top + s.arm_height_above_seat;
    for (y0, y1) in [(-hy - s.arm_width, -hy), (hy, hy + s.arm_width)] {
        m.add_box(p(x_back, y0, 0.0), p(hx, y1, top), Part::Other);
        m.add_box(p(x_back, y0, top), p(hx, y1, arm_top), Part::Armrest);
    }
    m
}

/// An armchair: a one-seat [`sofa`] (`seats` is ignored).
pub fn armchair(params: &SofaParams) -> Mesh {
    sofa(&SofaParams {
        seats: 1,
        ..*params
    })
}

// ---------------------------------------------------------------------------------------
// Bench
// ---------------------------------------------------------------------------------------

/// Parameters of [`bench()`]. Metres and degrees.
///
/// Defaults: a 1.20 m long bench, seat 0.38 m deep and 0.45 m high (as chairs, 0.43–0.48),
/// slab 0.05 m, no back; with `back` a panel 0.40 m above the seat tilted 10° back.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BenchParams {
    /// Length (y) of the bench, metres (default 1.20).
    pub length: f64,
    /// Seat depth (x), metres (default 0.38).
    pub seat_depth: f64,
    /// Height of the seat top above the floor, metres (default 0.45).
    pub seat_height: f64,
    /// Seat slab thickness, metres (default 0.05).
    pub seat_thickness: f64,
    /// Side of the square legs, metres (default 0.05).
    pub leg_size: f64,
    /// Whether the bench has a back (default false).
    pub back: bool,
    /// Height of the back's top above the seat, metres (default 0.40).
    pub back_height_above_seat: f64,
    /// Back thickness, metres (default 0.03).
    pub back_thickness: f64,
    /// Backward tilt of the back from vertical, degrees (default 10).
    pub back_tilt_deg: f64,
}

impl Default for BenchParams {
    fn default() -> Self {
        Self {
            length: 1.20,
            seat_depth: 0.38,
            seat_height: 0.45,
            seat_thickness: 0.05,
            leg_size: 0.05,
            back: false,
            back_height_above_seat: 0.40,
            back_thickness: 0.03,
            back_tilt_deg: 10.0,
        }
    }
}

/// A bench: long seat slab (top = [`Part::Seat`]) along y on four legs, optionally with a
/// back panel ([`Part::Backrest`]) along its -x edge. Seat centre at x = y = 0, standing on
/// z = 0, facing +x.
pub fn bench(params: &BenchParams) -> Mesh {
    let b = params;
    let mut m = Mesh::new();
    let (hx, hy) = (b.seat_depth / 2.0, b.length / 2.0);
    let top = b.seat_height;
    let bottom = top - b.seat_thickness;
    m.add_box_with_top(p(-hx, -hy, bottom), p(hx, hy, top), Part::Seat, Part::Other);
    add_square_legs(&mut m, -hx, hx, -hy, hy, 0.03, b.leg_size, bottom);
    if b.back {
        add_back_panel(
            &mut m,
            -hx,
            bottom,
            top,
            b.length,
            b.back_height_above_seat,
            b.back_thickness,
            b.back_tilt_deg,
            None,
        );
    }
    m
}

// ---------------------------------------------------------------------------------------
// Bed
// ---------------------------------------------------------------------------------------

/// Parameters of [`bed`]. Metres.
///
/// Defaults: a double bed, mattress 2.00 m × 1.40 m (beds are 1.90–2.00 m long; EN 1725
/// covers domestic beds; common widths 0.90 single, 1.35–1.40 double, 1.50–1.60 queen)
/// with its top 0.50 m above the floor (0.45–0.55 typical), mattress 0.22 m thick on a
/// solid frame, headboard 1.00 m high and 0.06 m thick.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct BedParams {
    /// Mattress length (x), metres (default 2.00).
    pub length: f64,
    /// Mattress width (y), metres (default 1.40).
    pub width: f64,
    /// Height of the mattress top above the floor, metres (default 0.50).
    pub mattress_height: f64,
    /// Mattress thickness, metres (default 0.22).
    pub mattress_thickness: f64,
    /// Height of the headboard top above the floor, metres (default 1.00; 0 for none).
    pub headboard_height: f64,
    /// Headboard thickness (x), metres (default 0.06).
    pub headboard_thickness: f64,
}

impl Default for BedParams {
    fn default() -> Self {
        Self {
            length: 2.00,
            width: 1.40,
            mattress_height: 0.50,
            mattress_thickness: 0.22,
            headboard_height: 1.00,
            headboard_thickness: 0.06,
        }
    }
}

impl BedParams {
    /// A single bed: 0.90 m × 1.90 m.
    pub fn single() -> Self {
        Self {
            length: 1.90,
            width: 0.90,
            ..Self::default()
        }
    }
}

/// A bed: solid frame, mattress (top = [`Part::LyingSurface`]) and a headboard
/// ([`Part::Other`]) at the -x end. Mattress centre at x = y = 0, standing on z = 0.
pub fn bed(params: &BedParams) -> Mesh {
    let b = params;
    let mut m = Mesh::new();
    let (hx, hy) = (b.length / 2.0, b.width / 2.0);
    let top = b.mattress_height;
    let frame_top = (top - b.mattress_thickness).max(0.0);
    if frame_top > 0.0 {
        m.add_box(p(-hx, -hy, 0.0), p(hx, hy, frame_top), Part::Other);
    }
    m.add_box_with_top(
        p(-hx, -hy, frame_top),
        p(hx, hy, top),
        Part::LyingSurface,
        Part::Other,
    );
    if b.headboard_height > 0.0 {
        m.add_box(
            p(-hx - b.headboard_thickness, -hy, 0.0),
            p(-hx, hy, b.headboard_height),
            Part::Other,
        );
    }
    m
}

// ---------------------------------------------------------------------------------------
// Recliner / chaise longue
// ---------------------------------------------------------------------------------------

/// Parameters of [`recliner`]. Metres and degrees.
///
/// Defaults: a reclined lounge chair with its leg rest out (a chaise longue): seat
/// (cushion top) 0.44 m high (0.40–0.48), 0.65 m wide (0.55–0.75) and 0.50 m deep, a back
/// panel 0.80 m long (0.7–0.9) reclined to 40° above level (30–50), a leg rest 0.60 m long
/// (0.5–0.8) raised 10° (0–25), panels 0.10 m thick, no arms; arms when enabled 0.22 m
/// above the seat and 0.10 m wide. With `leg_rest_folded` the leg rest hangs down in front
/// of the seat (an ordinary recliner chair with its foot rest stowed).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ReclinerParams {
    /// Height of the seat top above the floor, metres (default 0.44).
    pub seat_height: f64,
    /// Seat (and panel) width (y), metres (default 0.65).
    pub seat_width: f64,
    /// Seat depth (x), metres (default 0.50).
    pub seat_depth: f64,
    /// Seat cushion thickness, metres (default 0.12); a solid base fills the rest below.
    pub seat_thickness: f64,
    /// Length of the back panel along its surface, from the seat's rear edge, metres
    /// (default 0.80).
    pub back_length: f64,
    /// Angle of the back panel above level, degrees (default 40; 90 = upright).
    pub back_angle_deg: f64,
    /// Length of the leg rest along its surface, from the seat's front edge, metres
    /// (default 0.60).
    pub leg_rest_length: f64,
    /// Angle of the leg rest above level, degrees (default 10), when not folded.
    pub leg_rest_angle_deg: f64,
    /// Whether the leg rest is folded down (hangs in front of the seat; default false).
    pub leg_rest_folded: bool,
    /// Thickness of the back panel and the leg rest, metres (default 0.10).
    pub panel_thickness: f64,
    /// Whether the recliner has arms (default false).
    pub arms: bool,
    /// Height of the arm tops above the seat top, metres (default 0.22).
    pub arm_height_above_seat: f64,
    /// Width (y) of each arm, metres (default 0.10).
    pub arm_width: f64,
    /// Height above the seat from which the back counts as headrest, metres (default
    /// 0.60, as for chairs); used only when the back's top rises at least 0.70 m above the
    /// seat.
    pub headrest_from_above_seat: f64,
    /// Label the seat top and the (unfolded) leg rest [`Part::LyingSurface`] instead of
    /// [`Part::Seat`] and [`Part::Other`] (default false; set for recliners that afford
    /// lying).
    pub lying_surface: bool,
}

impl Default for ReclinerParams {
    fn default() -> Self {
        Self {
            seat_height: 0.44,
            seat_width: 0.65,
            seat_depth: 0.50,
            seat_thickness: 0.12,
            back_length: 0.80,
            back_angle_deg: 40.0,
            leg_rest_length: 0.60,
            leg_rest_angle_deg: 10.0,
            leg_rest_folded: false,
            panel_thickness: 0.10,
            arms: false,
            arm_height_above_seat: 0.22,
            arm_width: 0.10,
            headrest_from_above_seat: 0.60,
            lying_surface: false,
        }
    }
}

impl ReclinerParams {
    /// How high the top of the back panel rises above the seat top, metres.
    pub fn back_rise(&self) -> f64 {
        self.back_length * self.back_angle_deg.to_radians().sin()
    }

    /// Length of the body support along the surfaces, metres: back panel + seat depth +
    /// leg rest (the leg rest counts only when unfolded and 0–40° above level, the range
    /// of the lying hierarchy's raised legs).
    pub fn support_length(&self) -> f64 {
        let legs = !self.leg_rest_folded && (0.0..=40.0).contains(&self.leg_rest_angle_deg);
        self.back_length + self.seat_depth + if legs { self.leg_rest_length } else { 0.0 }
    }
}

/// Adds a flat panel whose upper face is hinged at the line x = `x`, z = `z` and runs
/// from `s0` to `s1` (metres, along the face) towards `dir` · x (`dir` = ±1), rising
/// `deg` above level (negative: falling); `width` across (centred on y = 0), `thick`
/// thick below its upper face.
#[allow(clippy::too_many_arguments)]
fn add_hinged_panel(
    m: &mut Mesh,
    x: f64,
    z: f64,
    s0: f64,
    s1: f64,
    width: f64,
    thick: f64,
    deg: f64,
    dir: f64,
    part: Part,
) {
    if s1 <= s0 {
        return;
    }
    let a = deg.to_radians();
    let along = Vector3::new(dir * a.cos(), 0.0, a.sin());
    let normal = Vector3::new(-dir * a.sin(), 0.0, a.cos());
    let centre = p(x, 0.0, z) + along * ((s0 + s1) / 2.0) - normal * (thick / 2.0);
    let rot = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), -dir * a);
    m.add_oriented_box(
        centre,
        Vector3::new((s1 - s0) / 2.0, width / 2.0, thick / 2.0),
        rot,
        part,
    );
}

/// Adds two square posts of side `size` from the floor to `z_top` (if above it), centred
/// on x = `x`, inside the sides y = ±`hy`.
fn add_side_posts(m: &mut Mesh, x: f64, z_top: f64, hy: f64, size: f64) {
    if z_top <= 0.0 {
        return;
    }
    for y in [-hy, hy - size] {
        m.add_box(
            p(x - size / 2.0, y, 0.0),
            p(x + size / 2.0, y + size, z_top),
            Part::Other,
        );
    }
}

/// A recliner (lounge chair, chaise longue): solid base, seat cushion (top =
/// [`Part::Seat`]), a back panel hinged at the seat's rear (-x) edge and reclined to
/// `back_angle_deg` above level ([`Part::Backrest`]; the part higher than
/// `headrest_from_above_seat` above the seat is [`Part::Headrest`] when the top rises at
/// least 0.70 m above the seat), propped by two posts, and a leg rest hinged at the seat's
/// front (+x) edge, raised `leg_rest_angle_deg` on two posts ([`Part::Other`]), or folded
/// down in front of the base. Optional arms beside the seat ([`Part::Armrest`] above the
/// seat). With `lying_surface`, seat and unfolded leg rest are [`Part::LyingSurface`].
/// Seat centre at x = y = 0, standing on z = 0, facing +x.
pub fn recliner(params: &ReclinerParams) -> Mesh {
    let r = params;
    let mut m = Mesh::new();
    let (hx, hy) = (r.seat_depth / 2.0, r.seat_width / 2.0);
    let top = r.seat_height;
    let base_top = (top - r.seat_thickness).max(0.0);
    let seat_part = if r.lying_surface {
        Part::LyingSurface
    } else {
        Part::Seat
    };
    if base_top > 0.0 {
        m.add_box(p(-hx, -hy, 0.0), p(hx, hy, base_top), Part::Other);
    }
    m.add_box_with_top(
        p(-hx, -hy, base_top),
        p(hx, hy, top),
        seat_part,
        Part::Other,
    );
    // Back panel, split into backrest and headrest.
    let a = r.back_angle_deg.to_radians();
    let split = if r.back_rise() >= 0.70 && a.sin() > 1e-6 {
        (r.headrest_from_above_seat / a.sin()).min(r.back_length)
    } else {
        r.back_length
    };
    let t = r.panel_thickness;
    let (w, deg) = (r.seat_width, r.back_angle_deg);
    add_hinged_panel(
        &mut m,
        -hx,
        top,
        0.0,
        split,
        w,
        t,
        deg,
        -1.0,
        Part::Backrest,
    );
    let back_len = r.back_length;
    add_hinged_panel(
        &mut m,
        -hx,
        top,
        split,
        back_len,
        w,
        t,
        deg,
        -1.0,
        Part::Headrest,
    );
    // Posts under the middle of the back panel.
    let post = 0.04;
    let (mx, mz) = (
        -hx - 0.5 * r.back_length * a.cos(),
        top + 0.5 * r.back_length * a.sin() - t / a.cos().max(0.2),
    );
    add_side_posts(&mut m, mx, mz, hy, post);
    // Leg rest.
    if r.leg_rest_folded {
        // Hanging (80° below level) in front of the base, clear of the floor.
        let reach = ((top - 0.06) / 80f64.to_radians().sin()).clamp(0.0, r.leg_rest_length);
        add_hinged_panel(&mut m, hx, top, 0.0, reach, w, t, -80.0, 1.0, Part::Other);
    } else {
        let part = if r.lying_surface {
            Part::LyingSurface
        } else {
            Part::Other
        };
        let b = r.leg_rest_angle_deg.to_radians();
        let len = r.leg_rest_length;
        add_hinged_panel(
            &mut m,
            hx,
            top,
            0.0,
            len,
            w,
            t,
            r.leg_rest_angle_deg,
            1.0,
            part,
        );
        // Posts under its far end.
        let (ex, ez) = (
            hx + (len - 0.05) * b.cos(),
            top + (len - 0.05) * b.sin() - t / b.cos().max(0.2),
        );
        add_side_posts(&mut m, ex, ez, hy, post);
    }
    if r.arms {
        let arm_top = top + r.arm_height_above_seat;
        for (y0, y1) in [(-hy - r.arm_width, -hy), (hy, hy + r.arm_width)] {
            m.add_box(p(-hx, y0, 0.0), p(hx, y1, top), Part::Other);
            m.add_box(p(-hx, y0, top), p(hx, y1, arm_top), Part::Armrest);
        }
    }
    m
}

// ---------------------------------------------------------------------------------------
// Negatives: table, desk, shelf, cabinet, wall, floor
// ---------------------------------------------------------------------------------------

/// Parameters of [`table`]. Metres.
///
/// Defaults: a dining table 1.20 m (x) × 0.80 m (y), top surface 0.74 m high (dining and
/// work tables are 0.72–0.76 m; EN 527-1 fixes 0.74 m for non-adjustable desks), top
/// 0.03 m thick, square legs 0.05 m, inset 0.05 m.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TableParams {
    /// Length (x), metres (default 1.20).
    pub length: f64,
    /// Width (y), metres (default 0.80).
    pub width: f64,
    /// Height of the top surface above the floor, metres (default 0.74).
    pub height: f64,
    /// Table top thickness, metres (default 0.03).
    pub top_thickness: f64,
    /// Side of the square legs, metres (default 0.05).
    pub leg_size: f64,
    /// Distance of the legs from the top's corners, metres (default 0.05).
    pub leg_inset: f64,
}

impl Default for TableParams {
    fn default() -> Self {
        Self {
            length: 1.20,
            width: 0.80,
            height: 0.74,
            top_thickness: 0.03,
            leg_size: 0.05,
            leg_inset: 0.05,
        }
    }
}

/// A table: top slab on four legs, all [`Part::Other`], centred at the origin on z = 0.
pub fn table(params: &TableParams) -> Mesh {
    let t = params;
    let mut m = Mesh::new();
    let (hx, hy) = (t.length / 2.0, t.width / 2.0);
    let bottom = t.height - t.top_thickness;
    m.add_box(p(-hx, -hy, bottom), p(hx, hy, t.height), Part::Other);
    add_square_legs(&mut m, -hx, hx, -hy, hy, t.leg_inset, t.leg_size, bottom);
    m
}

/// Parameters of [`desk`]. Metres.
///
/// Defaults: a 1.40 m wide (y), 0.70 m deep (x) desk, top 0.74 m high (EN 527-1), top
/// 0.03 m, side panels 0.03 m, a 0.40 m wide drawer pedestal on the +y side, modesty panel
/// at the back.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct DeskParams {
    /// Width (y), metres (default 1.40).
    pub width: f64,
    /// Depth (x), metres (default 0.70).
    pub depth: f64,
    /// Height of the top surface above the floor, metres (default 0.74).
    pub height: f64,
    /// Top thickness, metres (default 0.03).
    pub top_thickness: f64,
    /// Side panel thickness, metres (default 0.03).
    pub panel_thickness: f64,
    /// Whether the +y side is a solid drawer pedestal instead of a panel (default true).
    pub pedestal: bool,
    /// Pedestal width (y), metres (default 0.40).
    pub pedestal_width: f64,
}

impl Default for DeskParams {
    fn default() -> Self {
        Self {
            width: 1.40,
            depth: 0.70,
            height: 0.74,
            top_thickness: 0.03,
            panel_thickness: 0.03,
            pedestal: true,
            pedestal_width: 0.40,
        }
    }
}

/// A desk: top slab on two side panels (or a panel and a solid drawer pedestal), with a
/// modesty panel on the -x side; the user sits at +x. All [`Part::Other`], centred at the
/// origin on z = 0.
pub fn desk(params: &DeskParams) -> Mesh {
    let d = params;
    let mut m = Mesh::new();
    let (hx, hy) = (d.depth / 2.0, d.width / 2.0);
    let bottom = d.height - d.top_thickness;
    let t = d.panel_thickness;
    m.add_box(p(-hx, -hy, bottom), p(hx, hy, d.height), Part::Other);
    m.add_box(p(-hx, -hy, 0.0), p(hx, -hy + t, bottom), Part::Other);
    if d.pedestal {
        m.add_box(
            p(-hx, hy - d.pedestal_width, 0.0),
            p(hx, hy, bottom),
            Part::Other,
        );
    } else {
        m.add_box(p(-hx, hy - t, 0.0), p(hx, hy, bottom), Part::Other);
    }
    let modesty = 0.35_f64.min(bottom);
    m.add_box(
        p(-hx + 0.02, -hy + t, bottom - modesty),
        p(-hx + 0.02 + t / 2.0, hy, bottom),
        Part::Other,
    );
    m
}

/// Parameters of [`shelf`]. Metres.
///
/// Defaults: a bookcase 1.80 m high, 0.80 m wide (y), 0.35 m deep (x), 18 mm boards, five
/// compartments (six horizontal boards including bottom and top), with a back panel.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ShelfParams {
    /// Width (y), metres (default 0.80).
    pub width: f64,
    /// Depth (x), metres (default 0.35).
    pub depth: f64,
    /// Height, metres (default 1.80).
    pub height: f64,
    /// Board thickness, metres (default 0.018).
    pub board_thickness: f64,
    /// Number of compartments stacked vertically (default 5; at least 1).
    pub compartments: u32,
    /// Whether there is a thin back panel at -x (default true).
    pub back_panel: bool,
}

impl Default for ShelfParams {
    fn default() -> Self {
        Self {
            width: 0.80,
            depth: 0.35,
            height: 1.80,
            board_thickness: 0.018,
            compartments: 5,
            back_panel: true,
        }
    }
}

/// A shelf / bookcase: two side boards, evenly spaced horizontal boards (bottom and top
/// included), optional back panel; open towards +x. All [`Part::Other`], centred at the
/// origin on z = 0.
pub fn shelf(params: &ShelfParams) -> Mesh {
    let s = params;
    let mut m = Mesh::new();
    let (hx, hy) = (s.depth / 2.0, s.width / 2.0);
    let t = s.board_thickness;
    let n = s.compartments.max(1);
    m.add_box(p(-hx, -hy, 0.0), p(hx, -hy + t, s.height), Part::Other);
    m.add_box(p(-hx, hy - t, 0.0), p(hx, hy, s.height), Part::Other);
    let step = (s.height - t) / n as f64;
    for k in 0..=n {
        let z = k as f64 * step;
        m.add_box(p(-hx, -hy + t, z), p(hx, hy - t, z + t), Part::Other);
    }
    if s.back_panel {
        m.add_box(
            p(-hx, -hy + t, t),
            p(-hx + 0.006, hy - t, s.height - t),
            Part::Other,
        );
    }
    m
}

/// Parameters of [`cabinet`]. Metres.
///
/// Defaults: a sideboard cabinet 1.00 m wide (y), 0.50 m deep (x), 0.90 m high (cabinets
/// and dressers are 0.80–1.20 m high, above any sitting height); see
/// [`CabinetParams::dresser`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct CabinetParams {
    /// Width (y), metres (default 1.00).
    pub width: f64,
    /// Depth (x), metres (default 0.50).
    pub depth: f64,
    /// Height, metres (default 0.90).
    pub height: f64,
    /// Overhang of a 0.02 m top slab on every side, metres (default 0: a plain box).
    pub top_overhang: f64,
}

impl Default for CabinetParams {
    fn default() -> Self {
        Self {
            width: 1.00,
            depth: 0.50,
            height: 0.90,
            top_overhang: 0.0,
        }
    }
}

impl CabinetParams {
    /// A dresser / chest of drawers: 1.20 m wide, 0.50 m deep, 1.10 m high, top slab
    /// overhanging by 0.02 m.
    pub fn dresser() -> Self {
        Self {
            width: 1.20,
            depth: 0.50,
            height: 1.10,
            top_overhang: 0.02,
        }
    }
}

/// A cabinet or dresser: a solid box (with an optional overhanging top slab), all
/// [`Part::Other`], centred at the origin on z = 0; total height `height`.
pub fn cabinet(params: &CabinetParams) -> Mesh {
    let c = params;
    let mut m = Mesh::new();
    let (hx, hy) = (c.depth / 2.0, c.width / 2.0);
    if c.top_overhang > 0.0 {
        let slab = 0.02_f64.min(c.height);
        let o = c.top_overhang;
        m.add_box(p(-hx, -hy, 0.0), p(hx, hy, c.height - slab), Part::Other);
        m.add_box(
            p(-hx - o, -hy - o, c.height - slab),
            p(hx + o, hy + o, c.height),
            Part::Other,
        );
    } else {
        m.add_box(p(-hx, -hy, 0.0), p(hx, hy, c.height), Part::Other);
    }
    m
}

/// A straight wall parallel to the y-z plane: a slab centred on the plane `x` (metres),
/// spanning `y0..y1`, from the floor up to `height`, `thickness` thick. [`Part::Other`].
pub fn wall(x: f64, y0: f64, y1: f64, height: f64, thickness: f64) -> Mesh {
    let mut m = Mesh::new();
    let h = thickness.abs() / 2.0;
    m.add_box(p(x - h, y0, 0.0), p(x + h, y1, height), Part::Other);
    m
}

/// A straight wall between two floor points `start` and `end` (metres, x-y), from the
/// floor up to `height`, `thickness` thick, centred on the segment. [`Part::Other`].
pub fn wall_segment(start: Point2<f64>, end: Point2<f64>, height: f64, thickness: f64) -> Mesh {
    let mut m = Mesh::new();
    let d = end - start;
    let len = d.norm();
    if len < 1e-12 {
        return m;
    }
    let yaw = d.y.atan2(d.x);
    let mid = Point2::from((start.coords + end.coords) / 2.0);
    m.add_oriented_box(
        p(mid.x, mid.y, height / 2.0),
        Vector3::new(len / 2.0, thickness.abs() / 2.0, height / 2.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw),
        Part::Other,
    );
    m
}

/// A floor patch: an upward-facing rectangle at z = 0 spanning `x0..x1` × `y0..y1`
/// (metres), [`Part::Other`]. Being a single plane, it is sampled on its top only.
pub fn floor(x0: f64, y0: f64, x1: f64, y1: f64) -> Mesh {
    let mut m = Mesh::new();
    m.add_horizontal_rect(x0, y0, x1, y1, 0.0, Part::Other);
    m
}

// ---------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------

/// Merges `meshes` into one; with `with_floor`, adds a [`floor`] patch covering their
/// footprint plus [`FLOOR_MARGIN_M`] on every side. Labels are kept.
pub fn scene_mesh(meshes: &[Mesh], with_floor: bool) -> Mesh {
    let mut scene = Mesh::new();
    for m in meshes {
        scene.append(m);
    }
    if with_floor {
        if let Some((lo, hi)) = scene.bounds() {
            let e = FLOOR_MARGIN_M;
            scene.append(&floor(lo.x - e, lo.y - e, hi.x + e, hi.y + e));
        }
    }
    scene
}

/// Samples the merged `meshes` (see [`scene_mesh`], floor patch if `with_floor`) into a
/// cloud of about `points_per_m2` points per square metre of surface with Gaussian noise
/// of `noise` metres along the surface normals, deterministically for `seed`
/// (see [`sample_surface`], which also gives the per-point labels).
pub fn scene_cloud(
    meshes: &[Mesh],
    points_per_m2: f64,
    noise: f64,
    seed: u64,
    with_floor: bool,
) -> PointCloud {
    sample_surface(&scene_mesh(meshes, with_floor), points_per_m2, noise, seed).0
}

#[cfg(test)]
mod tests {
    use super::*;

    const DENSITY: f64 = 20_000.0;

    fn labelled(m: &Mesh, part: Part) -> Vec<Point3<f64>> {
        let (cloud, parts) = sample_surface(m, DENSITY, 0.0, 11);
        cloud
            .points
            .into_iter()
            .zip(parts)
            .filter(|(_, q)| *q == part)
            .map(|(p, _)| p)
            .collect()
    }

    fn max_z(pts: &[Point3<f64>]) -> f64 {
        pts.iter().map(|p| p.z).fold(f64::NEG_INFINITY, f64::max)
    }

    fn min_z(pts: &[Point3<f64>]) -> f64 {
        pts.iter().map(|p| p.z).fold(f64::INFINITY, f64::min)
    }

    fn check_well_formed(m: &Mesh) {
        assert!(!m.is_empty());
        assert_eq!(m.parts.len(), m.triangles.len());
        assert!(m
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < m.vertices.len()));
        let (lo, _) = m.bounds().unwrap();
        assert!(lo.z.abs() < 1e-9, "stands on the floor: min z = {}", lo.z);
    }

    fn has(m: &Mesh, part: Part) -> bool {
        m.parts.contains(&part)
    }

    #[test]
    fn default_chair_seat_back_and_floor() {
        let c = ChairParams::default();
        let m = chair(&c);
        check_well_formed(&m);
        let seat = labelled(&m, Part::Seat);
        assert!(!seat.is_empty());
        let top = max_z(&seat);
        assert!(
            (top - c.seat_height).abs() <= c.seat_thickness,
            "seat top {top}"
        );
        assert!((top - c.seat_height).abs() < 1e-9);
        // Seat points cover the seat footprint around the origin.
        assert!(seat
            .iter()
            .all(|p| p.x.abs() <= c.seat_depth / 2.0 + 1e-9
                && p.y.abs() <= c.seat_width / 2.0 + 1e-9));
        let area = m.part_area(Part::Seat);
        assert!((area - c.seat_depth * c.seat_width).abs() < 1e-9);
        // Backrest behind the seat centre, rising to the back height.
        let back = labelled(&m, Part::Backrest);
        assert!(!back.is_empty());
        assert!(back
            .iter()
            .all(|p| p.x < 0.0 && p.x <= -c.seat_depth / 2.0 + 1e-9));
        let back_top = max_z(&back);
        assert!(
            (back_top - (c.seat_height + c.back_height_above_seat)).abs() < 0.01,
            "back top {back_top}"
        );
        // On the floor.
        let (cloud, _) = sample_surface(&m, DENSITY, 0.0, 5);
        assert!(min_z(&cloud.points).abs() < 1e-9);
        assert!(!has(&m, Part::Headrest));
        assert!(!has(&m, Part::Armrest));
        assert!(!has(&m, Part::LyingSurface));
    }

    #[test]
    fn chair_back_tilt_leans_backwards() {
        let upright = chair(&ChairParams {
            back_tilt_deg: 0.0,
            ..ChairParams::default()
        });
        let tilted = chair(&ChairParams {
            back_tilt_deg: 20.0,
            ..ChairParams::default()
        });
        let min_x = |m: &Mesh| {
            labelled(m, Part::Backrest)
                .iter()
                .map(|p| p.x)
                .fold(f64::INFINITY, f64::min)
        };
        let c = ChairParams::default();
        // Upright: back panel from -d/2 - t to -d/2.
        assert!((min_x(&upright) - (-c.seat_depth / 2.0 - c.back_thickness)).abs() < 0.005);
        // 20° tilt moves the top back by about (h + seat thickness)·tan 20° ≈ 0.16 m.
        let shift = min_x(&upright) - min_x(&tilted);
        let want = (c.back_height_above_seat + c.seat_thickness) * 20f64.to_radians().tan();
        assert!((shift - want).abs() < 0.02, "shift {shift} vs {want}");
        // The vertical height of the back top is unchanged.
        assert!((max_z(&labelled(&tilted, Part::Backrest)) - 0.85).abs() < 0.015);
    }

    #[test]
    fn chair_arms_are_at_arm_height_beside_the_seat() {
        let c = ChairParams::with_arms();
        let m = chair(&c);
        check_well_formed(&m);
        let arms = labelled(&m, Part::Armrest);
        assert!(!arms.is_empty());
        let top = max_z(&arms);
        assert!((top - (c.seat_height + c.arm_height_above_seat)).abs() < 1e-9);
        assert!(arms.iter().all(|p| p.y.abs() >= c.seat_width / 2.0 - 1e-9));
        assert!(arms.iter().any(|p| p.y > 0.0) && arms.iter().any(|p| p.y < 0.0));
        assert!(!has(&m, Part::Headrest));
    }

    #[test]
    fn headrest_only_on_high_back_chairs() {
        let c = ChairParams::high_back();
        let m = chair(&c);
        check_well_formed(&m);
        let head = labelled(&m, Part::Headrest);
        assert!(!head.is_empty());
        let seat = c.seat_height;
        assert!(min_z(&head) >= seat + c.headrest_from_above_seat - 0.01);
        assert!((max_z(&head) - (seat + 0.80)).abs() < 0.015);
        // The backrest stays below the headrest.
        assert!(max_z(&labelled(&m, Part::Backrest)) <= seat + c.headrest_from_above_seat + 0.01);
        assert!(head.iter().all(|p| p.x < 0.0));
        assert!(!has(&chair(&ChairParams::default()), Part::Headrest));
        assert!(!has(&chair(&ChairParams::with_arms()), Part::Headrest));
        assert!(!has(&sofa(&SofaParams::default()), Part::Headrest));
        assert!(!has(
            &bench(&BenchParams {
                back: true,
                ..Default::default()
            }),
            Part::Headrest
        ));
    }

    #[test]
    fn chair_without_back_has_no_backrest() {
        let m = chair(&ChairParams {
            back_height_above_seat: 0.0,
            ..ChairParams::default()
        });
        assert!(!has(&m, Part::Backrest));
        assert!(has(&m, Part::Seat));
    }

    #[test]
    fn stools_low_and_bar() {
        for params in [
            StoolParams::default(),
            StoolParams {
                round: false,
                base: StoolBase::Pedestal,
                ..StoolParams::default()
            },
            StoolParams::bar(),
        ] {
            let m = stool(&params);
            check_well_formed(&m);
            let seat = labelled(&m, Part::Seat);
            assert!((max_z(&seat) - params.seat_height).abs() < 1e-9);
            assert!((min_z(&seat) - params.seat_height).abs() < 1e-9);
            let r = params.seat_size / 2.0;
            let want = if params.round {
                std::f64::consts::PI * r * r
            } else {
                4.0 * r * r
            };
            assert!((m.part_area(Part::Seat) - want).abs() / want < 0.01);
            assert!(!has(&m, Part::Backrest));
        }
        let bar = StoolParams::bar();
        assert!((0.65..=0.80).contains(&bar.seat_height));
    }

    #[test]
    fn sofa_width_seats_arms_and_back() {
        let s = SofaParams::default();
        let m = sofa(&s);
        check_well_formed(&m);
        let (lo, hi) = m.bounds().unwrap();
        let width = 3.0 * s.seat_width_per_person + 2.0 * s.arm_width;
        assert!((hi.y - lo.y - width).abs() < 1e-9);
        assert!((hi.z - (s.seat_height + s.back_height_above_seat)).abs() < 1e-9);
        let want = 3.0 * s.seat_width_per_person * s.seat_depth;
        assert!((m.part_area(Part::Seat) - want).abs() < 1e-9);
        let seat = labelled(&m, Part::Seat);
        assert!((max_z(&seat) - s.seat_height).abs() < 1e-9);
        let back = labelled(&m, Part::Backrest);
        assert!(back.iter().all(|p| p.x <= -s.seat_depth / 2.0 + 1e-9));
        assert!(min_z(&back) >= s.seat_height - 1e-9);
        let arms = labelled(&m, Part::Armrest);
        assert!((max_z(&arms) - (s.seat_height + s.arm_height_above_seat)).abs() < 1e-9);
        assert!(min_z(&arms) >= s.seat_height - 1e-9);
        // Armchair: one seat, narrower.
        let a = armchair(&s);
        check_well_formed(&a);
        let (lo, hi) = a.bounds().unwrap();
        assert!((hi.y - lo.y - (s.seat_width_per_person + 2.0 * s.arm_width)).abs() < 1e-9);
        assert!((a.part_area(Part::Seat) - s.seat_width_per_person * s.seat_depth).abs() < 1e-9);
    }

    #[test]
    fn bench_with_and_without_back() {
        let b = BenchParams::default();
        let plain = bench(&b);
        check_well_formed(&plain);
        assert!(!has(&plain, Part::Backrest));
        assert!((max_z(&labelled(&plain, Part::Seat)) - b.seat_height).abs() < 1e-9);
        assert!((plain.part_area(Part::Seat) - b.length * b.seat_depth).abs() < 1e-9);
        let backed = bench(&BenchParams { back: true, ..b });
        check_well_formed(&backed);
        let back = labelled(&backed, Part::Backrest);
        assert!(back.iter().all(|p| p.x < 0.0));
        assert!((max_z(&back) - (b.seat_height + b.back_height_above_seat)).abs() < 0.01);
    }

    #[test]
    fn bed_mattress_is_the_lying_surface() {
        let b = BedParams::default();
        let m = bed(&b);
        check_well_formed(&m);
        let lying = labelled(&m, Part::LyingSurface);
        assert!((max_z(&lying) - b.mattress_height).abs() < 1e-9);
        assert!((min_z(&lying) - b.mattress_height).abs() < 1e-9);
        assert!((m.part_area(Part::LyingSurface) - b.length * b.width).abs() < 1e-9);
        assert!((1.9..=2.0).contains(&b.length) && (0.45..=0.55).contains(&b.mattress_height));
        let (lo, hi) = m.bounds().unwrap();
        assert!((hi.z - b.headboard_height).abs() < 1e-9);
        assert!((lo.x - (-b.length / 2.0 - b.headboard_thickness)).abs() < 1e-9);
        assert!(!has(&m, Part::Seat));
        let single = bed(&BedParams::single());
        assert!((single.part_area(Part::LyingSurface) - 0.9 * 1.9).abs() < 1e-9);
    }

    /// The direction (degrees above level) of the principal axis of `pts` in the x-z
    /// plane, measured away from `dir` · x.
    fn slope_deg(pts: &[Point3<f64>], dir: f64) -> f64 {
        let n = pts.len() as f64;
        let (mx, mz) = (
            pts.iter().map(|p| p.x).sum::<f64>() / n,
            pts.iter().map(|p| p.z).sum::<f64>() / n,
        );
        let (mut sxx, mut sxz) = (0.0, 0.0);
        for p in pts {
            sxx += (p.x - mx) * (p.x - mx);
            sxz += (p.x - mx) * (p.z - mz);
        }
        (dir * sxz / sxx).atan().to_degrees()
    }

    /// The highest vertex of the triangles labelled `part`.
    fn part_top(m: &Mesh, part: Part) -> f64 {
        (0..m.len())
            .filter(|&i| m.parts[i] == part)
            .flat_map(|i| m.triangle(i))
            .map(|p| p.z)
            .fold(f64::NEG_INFINITY, f64::max)
    }

    #[test]
    fn recliner_seat_reclined_back_and_leg_rest() {
        let r = ReclinerParams::default();
        let m = recliner(&r);
        check_well_formed(&m);
        let seat = labelled(&m, Part::Seat);
        assert!((max_z(&seat) - r.seat_height).abs() < 1e-9);
        assert!((min_z(&seat) - r.seat_height).abs() < 1e-9);
        assert!((m.part_area(Part::Seat) - r.seat_depth * r.seat_width).abs() < 1e-9);
        // The back rises behind the seat at its angle, to back_rise() above the seat.
        let back = labelled(&m, Part::Backrest);
        assert!(back.iter().all(|p| p.x <= -r.seat_depth / 2.0 + 1e-9));
        assert!((part_top(&m, Part::Backrest) - (r.seat_height + r.back_rise())).abs() < 1e-9);
        // The upper face of the back panel (the highest points at each x) slopes at 40°.
        let upper: Vec<_> = back
            .iter()
            .copied()
            .filter(|p| {
                let want = r.seat_height + (-r.seat_depth / 2.0 - p.x) * 40f64.to_radians().tan();
                (p.z - want).abs() < 0.005
            })
            .collect();
        assert!(upper.len() > 500, "{}", upper.len());
        let a = slope_deg(&upper, -1.0);
        assert!((a - r.back_angle_deg).abs() < 1.0, "{a}");
        // Back rise 0.51 m < 0.70 m: no headrest; no arms; no lying surface.
        assert!(!has(&m, Part::Headrest));
        assert!(!has(&m, Part::Armrest));
        assert!(!has(&m, Part::LyingSurface));
        // The leg rest reaches len · cos 10° in front of the seat, up to len · sin 10°.
        let (lo, hi) = m.bounds().unwrap();
        let b = r.leg_rest_angle_deg.to_radians();
        assert!((hi.x - (r.seat_depth / 2.0 + r.leg_rest_length * b.cos())).abs() < 0.02);
        assert!(lo.x < -r.seat_depth / 2.0 - r.back_length * 40f64.to_radians().cos() + 0.01);
        assert!((r.support_length() - 1.9).abs() < 1e-9);

        // As a lying surface: seat and leg rest, whose top is the highest at its far end.
        let l = recliner(&ReclinerParams {
            lying_surface: true,
            ..r
        });
        assert!(!has(&l, Part::Seat));
        let lying = labelled(&l, Part::LyingSurface);
        let rest: Vec<_> = lying
            .iter()
            .copied()
            .filter(|p| p.x > r.seat_depth / 2.0 + 0.02)
            .collect();
        let top = r.seat_height + r.leg_rest_length * b.sin();
        assert!((max_z(&rest) - top).abs() < 0.01);
        assert!((part_top(&l, Part::LyingSurface) - top).abs() < 1e-9);
        let upper: Vec<_> = rest
            .iter()
            .copied()
            .filter(|p| {
                (p.z - (r.seat_height + (p.x - r.seat_depth / 2.0) * b.tan())).abs() < 0.003
            })
            .collect();
        let a = slope_deg(&upper, 1.0);
        assert!((a - r.leg_rest_angle_deg).abs() < 1.0, "{a}");
    }

    #[test]
    fn recliner_folded_arms_and_headrest() {
        let r = ReclinerParams {
            leg_rest_folded: true,
            arms: true,
            back_length: 0.9,
            back_angle_deg: 60.0,
            lying_surface: true,
            ..ReclinerParams::default()
        };
        let m = recliner(&r);
        check_well_formed(&m);
        // Folded: nothing in front of the seat higher than its front edge, nothing far out.
        let (_, hi) = m.bounds().unwrap();
        assert!(hi.x < r.seat_depth / 2.0 + 0.2, "{}", hi.x);
        assert!((r.support_length() - 1.4).abs() < 1e-9);
        // Only the seat top is a lying surface when folded.
        assert!((m.part_area(Part::LyingSurface) - r.seat_depth * r.seat_width).abs() < 1e-9);
        // Arms beside the seat at their height.
        let arms = labelled(&m, Part::Armrest);
        assert!((max_z(&arms) - (r.seat_height + r.arm_height_above_seat)).abs() < 1e-9);
        assert!(arms.iter().all(|p| p.y.abs() >= r.seat_width / 2.0 - 1e-9));
        // 0.9 · sin 60° = 0.78 m ≥ 0.70: the part above 0.60 m is headrest.
        assert!(r.back_rise() >= 0.70);
        let head = labelled(&m, Part::Headrest);
        assert!(min_z(&head) >= r.seat_height + 0.60 - 0.1);
        assert!((part_top(&m, Part::Headrest) - (r.seat_height + r.back_rise())).abs() < 1e-9);
        assert!(part_top(&m, Part::Backrest) <= r.seat_height + 0.60 + 1e-9);
    }

    #[test]
    fn table_top_at_its_height_and_unlabelled() {
        let t = TableParams::default();
        let m = table(&t);
        check_well_formed(&m);
        assert!(m.parts.iter().all(|&p| p == Part::Other));
        let (cloud, _) = sample_surface(&m, DENSITY, 0.0, 2);
        assert!((max_z(&cloud.points) - t.height).abs() < 1e-9);
        assert!((0.72..=0.76).contains(&t.height));
        // Points on the top surface.
        let top = cloud
            .points
            .iter()
            .filter(|p| (p.z - t.height).abs() < 1e-9)
            .count() as f64;
        let want = t.length * t.width * DENSITY;
        assert!((top - want).abs() / want < 0.05, "{top} vs {want}");
        let (lo, hi) = m.bounds().unwrap();
        assert!((lo.x + hi.x).abs() < 1e-9 && (lo.y + hi.y).abs() < 1e-9);
    }

    #[test]
    fn negatives_have_only_other_and_plausible_sizes() {
        let d = desk(&DeskParams::default());
        let s = shelf(&ShelfParams::default());
        let c = cabinet(&CabinetParams::default());
        let r = cabinet(&CabinetParams::dresser());
        for (m, h) in [(&d, 0.74), (&s, 1.80), (&c, 0.90), (&r, 1.10)] {
            check_well_formed(m);
            assert!(m.parts.iter().all(|&p| p == Part::Other));
            let (lo, hi) = m.bounds().unwrap();
            assert!((hi.z - h).abs() < 1e-9, "height {} vs {h}", hi.z);
            assert!((lo.x + hi.x).abs() < 0.05 && (lo.y + hi.y).abs() < 1e-9);
        }
        // Shelf: 2 sides + 6 boards + back panel = 9 boxes.
        assert_eq!(s.len(), 9 * 12);
        // Cabinet is a solid box: area of a 1.0 × 0.5 × 0.9 box.
        assert!((c.area() - 2.0 * (0.5 + 0.45 + 0.9)).abs() < 1e-9);
    }

    #[test]
    fn walls_and_floor() {
        let w = wall(2.0, -1.0, 3.0, 2.5, 0.1);
        check_well_formed(&w);
        let (lo, hi) = w.bounds().unwrap();
        assert!((lo - Point3::new(1.95, -1.0, 0.0)).norm() < 1e-12);
        assert!((hi - Point3::new(2.05, 3.0, 2.5)).norm() < 1e-12);
        let s = wall_segment(Point2::new(0.0, 0.0), Point2::new(3.0, 4.0), 2.5, 0.1);
        check_well_formed(&s);
        let (a, b, c) = (5.0, 0.1, 2.5);
        assert!((s.area() - 2.0 * (a * b + b * c + c * a)).abs() < 1e-9);
        let f = floor(-1.0, -2.0, 3.0, 2.0);
        assert_eq!(f.len(), 2);
        assert!((f.area() - 16.0).abs() < 1e-12);
        assert!((0..2).all(|i| (f.triangle_normal(i).z - 1.0).abs() < 1e-12));
    }

    #[test]
    fn scene_cloud_with_and_without_floor() {
        let meshes = [
            chair(&ChairParams::default()),
            table(&TableParams::default()).placed(1.0, 0.0, 0.0),
        ];
        let bare = scene_cloud(&meshes, 2000.0, 0.002, 9, false);
        let floored = scene_cloud(&meshes, 2000.0, 0.002, 9, true);
        let area: f64 = meshes.iter().map(Mesh::area).sum();
        assert!((bare.len() as f64 - 2000.0 * area).abs() / (2000.0 * area) < 0.03);
        let scene = scene_mesh(&meshes, true);
        let (lo, hi) = scene.bounds().unwrap();
        let floor_area = (hi.x - lo.x) * (hi.y - lo.y);
        let (olo, ohi) = scene_mesh(&meshes, false).bounds().unwrap();
        assert!((lo.x - (olo.x - FLOOR_MARGIN_M)).abs() < 1e-9);
        assert!((hi.y - (ohi.y + FLOOR_MARGIN_M)).abs() < 1e-9);
        let want = 2000.0 * (area + floor_area);
        assert!((floored.len() as f64 - want).abs() / want < 0.03);
        assert_eq!(floored, scene_cloud(&meshes, 2000.0, 0.002, 9, true));
        assert_ne!(floored, scene_cloud(&meshes, 2000.0, 0.002, 10, true));
        assert!(scene_cloud(&[], 2000.0, 0.0, 1, true).is_empty());
    }
}
