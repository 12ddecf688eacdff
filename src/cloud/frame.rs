//! Bringing a cloud into the detector's world frame: metres, z up, floor at z = 0.
//!
//! [`to_world`] applies, in this order: the units scale ([`Units`]), an optional 4x4
//! transform (applied as given, to the scaled coordinates), a rotation taking the given up
//! axis to +z ([`Up`], or the camera shortcut: x right, y down, z forward), and, with
//! [`FloorMode::Auto`], a levelling that puts the dominant floor plane at z = 0 with its
//! normal along +z. What was done is returned as a [`FrameReport`] (one info line through
//! its `Display`). [`check_units`] warns about clouds that look like millimetres or
//! centimetres; [`parse_matrix`] reads the 4x4 transform from text.

use std::fmt;
use std::str::FromStr;

use nalgebra::{Matrix3, Matrix4, Point3, Rotation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::{spacing, PointCloud};
use crate::num::to_usize;

/// Largest angle (degrees) between a floor candidate's normal and the assumed up (+z after
/// the up rotation), for scans whose up axis is known: a levelled scanner or a model.
pub const FLOOR_MAX_TILT_DEG: f64 = 25.0;
/// Largest angle (degrees) between a floor candidate's normal and the camera's up (-y) in a
/// camera frame: depth cameras look 10-55 deg down at furniture (a camera 1.5 m high aimed
/// at a chair 2 m away looks ~30 deg down); 75 deg leaves room for roll. Walls and ceilings
/// are told apart by the camera's side of the plane, not by the angle (see [`to_world`]).
pub const FLOOR_MAX_TILT_CAMERA_DEG: f64 = 75.0;
/// Distance (metres) within which a point counts as on a floor candidate plane.
pub const FLOOR_INLIER_M: f64 = 0.02;
/// A point more than this (metres) under a plane counts as below it.
const BELOW_M: f64 = 0.05;
/// Points within this distance (metres) of an extracted plane are removed before the next.
const REMOVE_M: f64 = 0.06;
/// At most this many horizontal-ish planes are extracted.
const MAX_PLANES: usize = 6;
/// RANSAC samples per extracted plane.
const ITERATIONS: usize = 2500;
/// Planes are extracted from at most this many points (an even subsample of the cloud).
const WORK_POINTS: usize = 60_000;
/// RANSAC candidates are scored on at most this many of the remaining points.
const SCORE_POINTS: usize = 4000;
/// Seed of the RANSAC generator (the result depends only on the cloud).
const SEED: u64 = 0xF1_00_2D_5E_ED;

/// Which input axis points up (away from the floor). The cloud is turned so that it
/// becomes +z, by a fixed proper rotation (listed per variant; `(x, y, z)` are input
/// coordinates, the tuple is the output).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Up {
    /// +x is up: `(x, y, z) -> (-z, y, x)` (a -90° turn about y).
    X,
    /// +y is up (most 3D modelling tools): `(x, y, z) -> (x, -z, y)` (+90° about x).
    Y,
    /// +z is up already: nothing is turned.
    #[default]
    Z,
    /// -x is up: `(x, y, z) -> (z, y, -x)` (+90° about y).
    NegX,
    /// -y is up (a camera frame: x right, y down, z forward): `(x, y, z) -> (x, z, -y)`
    /// (-90° about x), so the camera looks along +y and x stays to the right.
    NegY,
    /// -z is up: `(x, y, z) -> (x, -y, -z)` (180° about x).
    NegZ,
}

impl Up {
    /// The rotation taking this axis to +z (see the variants for the exact map).
    pub fn rotation(self) -> Rotation3<f64> {
        #[rustfmt::skip]
        let m = match self {
            Up::Z => Matrix3::identity(),
            Up::X => Matrix3::new(0.0, 0.0, -1.0,
                                  0.0, 1.0, 0.0,
                                  1.0, 0.0, 0.0),
            Up::NegX => Matrix3::new(0.0, 0.0, 1.0,
                                     0.0, 1.0, 0.0,
                                     -1.0, 0.0, 0.0),
            Up::Y => Matrix3::new(1.0, 0.0, 0.0,
                                  0.0, 0.0, -1.0,
                                  0.0, 1.0, 0.0),
            Up::NegY => Matrix3::new(1.0, 0.0, 0.0,
                                     0.0, 0.0, 1.0,
                                     0.0, -1.0, 0.0),
            Up::NegZ => Matrix3::new(1.0, 0.0, 0.0,
                                     0.0, -1.0, 0.0,
                                     0.0, 0.0, -1.0),
        };
        Rotation3::from_matrix_unchecked(m)
    }

    /// The axis as text: `+x`, `-y`, ...
    pub fn name(self) -> &'static str {
        match self {
            Up::X => "+x",
            Up::Y => "+y",
            Up::Z => "+z",
            Up::NegX => "-x",
            Up::NegY => "-y",
            Up::NegZ => "-z",
        }
    }
}

impl fmt::Display for Up {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Up {
    type Err = String;

    /// Accepts `x`, `+x`, `-x`, ... (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s.trim().to_ascii_lowercase().as_str() {
            "x" | "+x" => Up::X,
            "y" | "+y" => Up::Y,
            "z" | "+z" => Up::Z,
            "-x" => Up::NegX,
            "-y" => Up::NegY,
            "-z" => Up::NegZ,
            other => {
                return Err(format!(
                    "unknown up axis '{other}' (expected x, y, z, -x, -y or -z)"
                ))
            }
        })
    }
}

/// The length unit of the input coordinates.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Units {
    /// Metres (nothing is scaled).
    #[default]
    Metres,
    /// Millimetres (scaled by 0.001).
    Millimetres,
    /// Centimetres (scaled by 0.01).
    Centimetres,
}

impl Units {
    /// Metres per input unit.
    pub fn factor(self) -> f64 {
        match self {
            Units::Metres => 1.0,
            Units::Millimetres => 0.001,
            Units::Centimetres => 0.01,
        }
    }

    /// The unit's symbol: `m`, `mm` or `cm`.
    pub fn symbol(self) -> &'static str {
        match self {
            Units::Metres => "m",
            Units::Millimetres => "mm",
            Units::Centimetres => "cm",
        }
    }
}

impl FromStr for Units {
    type Err = String;

    /// Accepts `m`, `mm`, `cm` and the spelled-out names (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s.trim().to_ascii_lowercase().as_str() {
            "m" | "metre" | "metres" | "meter" | "meters" => Units::Metres,
            "mm" | "millimetre" | "millimetres" | "millimeter" | "millimeters" => {
                Units::Millimetres
            }
            "cm" | "centimetre" | "centimetres" | "centimeter" | "centimeters" => {
                Units::Centimetres
            }
            other => return Err(format!("unknown units '{other}' (expected m, cm or mm)")),
        })
    }
}

/// Whether to look for the floor.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FloorMode {
    /// Keep the cloud where the units, transform and up rotation put it.
    #[default]
    Keep,
    /// Find the floor plane (RANSAC) and move it to z = 0, normal +z.
    Auto,
}

impl FromStr for FloorMode {
    type Err = String;

    /// Accepts `keep` and `auto` (any case).
    fn from_str(s: &str) -> Result<Self, String> {
        Ok(match s.trim().to_ascii_lowercase().as_str() {
            "keep" | "none" => FloorMode::Keep,
            "auto" => FloorMode::Auto,
            other => {
                return Err(format!(
                    "unknown floor mode '{other}' (expected keep or auto)"
                ))
            }
        })
    }
}

/// How to bring a cloud into the world frame (metres, z up, floor at z = 0). The default
/// changes nothing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrameOptions {
    /// Which input axis points up (after the transform); ignored when `camera` is set.
    pub up: Up,
    /// A rigid or affine 4x4 map (last row `0 0 0 1`), applied as given to the points
    /// after the units scaling, i.e. its translation is in metres.
    pub transform: Option<Matrix4<f64>>,
    /// The unit of the input coordinates.
    pub units: Units,
    /// Whether to find the floor and put it at z = 0.
    pub floor: FloorMode,
    /// The input is a camera frame (x right, y down, z forward): the same as `up: NegY`.
    /// Giving another `up` than `Z` (the default) or `NegY` with it is an error.
    pub camera: bool,
}

/// The floor plane [`to_world`] found and levelled.
#[derive(Clone, Debug, PartialEq)]
pub struct FloorFit {
    /// Unit normal of the plane, pointing up, in the frame after the units scaling,
    /// transform and up rotation (before levelling).
    pub normal: Vector3<f64>,
    /// The plane is `normal · p = offset_m` (metres, same frame as `normal`): the signed
    /// height of the floor along its normal, e.g. -1.5 for a camera 1.5 m above it.
    pub offset_m: f64,
    /// Share (0..1) of all points within [`FLOOR_INLIER_M`] of the plane.
    pub inlier_share: f64,
    /// Share (0..1) of all points more than 5 cm below the plane (noise, reflections).
    pub below_share: f64,
    /// Angle (degrees) the cloud was turned by to make the normal +z.
    pub rotation_deg: f64,
    /// How many horizontal-ish planes were found and compared.
    pub planes: usize,
}

/// What [`to_world`] did; `Display` gives one line for the log.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameReport {
    /// Input units.
    pub units: Units,
    /// Whether a transform was applied.
    pub transformed: bool,
    /// The up axis that was turned to +z (`NegY` for a camera frame).
    pub up: Up,
    /// Whether the input was declared a camera frame.
    pub camera: bool,
    /// The floor found, with [`FloorMode::Auto`].
    pub floor: Option<FloorFit>,
    /// The whole map from input coordinates to the world frame (metres): scaling,
    /// transform, up rotation and levelling, as one affine 4x4.
    pub matrix: Matrix4<f64>,
}

impl fmt::Display for FrameReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts: Vec<String> = Vec::new();
        if self.units != Units::Metres {
            parts.push(format!(
                "{} to metres (x{})",
                self.units.symbol(),
                self.units.factor()
            ));
        }
        if self.transformed {
            parts.push("transform applied".into());
        }
        if self.camera {
            parts.push("camera frame (x right, y down, z forward), -y turned to +z".into());
        } else if self.up != Up::Z {
            parts.push(format!("{} turned to +z", self.up));
        }
        if let Some(fl) = &self.floor {
            let n = fl.normal;
            parts.push(format!(
                "floor plane normal ({:.3}, {:.3}, {:.3}) at {:.3} m, {:.1}% of points on it, \
                 levelled by {:.1} deg and moved to z = 0 ({} planes compared, {:.1}% of points below it)",
                n.x,
                n.y,
                n.z,
                fl.offset_m,
                100.0 * fl.inlier_share,
                fl.rotation_deg,
                fl.planes,
                100.0 * fl.below_share
            ));
        }
        if parts.is_empty() {
            f.write_str("frame: unchanged (metres, z up)")
        } else {
            write!(f, "frame: {}", parts.join("; "))
        }
    }
}

/// What went wrong bringing a cloud into the world frame.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum FrameError {
    /// The transform cannot be applied as it is.
    #[error("bad transform: {0}")]
    Transform(String),
    /// A camera frame fixes up = -y; another up axis was given too.
    #[error("a camera frame has up = -y, but up = {0} was given too")]
    Conflict(Up),
    /// No floor plane was found.
    #[error("no floor found: {0}")]
    NoFloor(String),
}

/// Brings `cloud` into the world frame (metres, z up, floor at z = 0 with
/// [`FloorMode::Auto`]): units scale, then `opts.transform`, then the up rotation, then
/// the floor levelling (see the module documentation). Point order is kept.
///
/// The floor is the lowest large plane whose normal is within [`FLOOR_MAX_TILT_DEG`] of
/// the assumed up (in a camera frame: within [`FLOOR_MAX_TILT_CAMERA_DEG`] of the camera's
/// up, and with the camera above the plane: a camera sees the floor from above, while a
/// wall in front of a camera looking down, or a ceiling, has the camera on its other
/// side, so no pitch makes them floors): up to six such planes are extracted by RANSAC (seeded, so the result
/// depends only on the input), and among those with at least a tenth of the largest
/// one's points, the one with the fewest points under it wins, so a big table top or a
/// ceiling does not beat the floor. The plane is refined by least squares on the points
/// within [`FLOOR_INLIER_M`], then turned to normal +z (shortest rotation, so headings
/// are kept as far as possible) and moved to z = 0.
pub fn to_world(
    cloud: PointCloud,
    opts: &FrameOptions,
) -> Result<(PointCloud, FrameReport), FrameError> {
    let up = if opts.camera {
        if !matches!(opts.up, Up::Z | Up::NegY) {
            return Err(FrameError::Conflict(opts.up));
        }
        Up::NegY
    } else {
        opts.up
    };
    let mut total = Matrix4::identity() * opts.units.factor();
    total[(3, 3)] = 1.0;
    if let Some(m) = &opts.transform {
        check_affine(m)?;
        total = m * total;
    }
    total = up.rotation().to_homogeneous() * total;
    let mut points = cloud.points;
    apply(&total, &mut points);
    let mut floor = None;
    if opts.floor == FloorMode::Auto {
        // The sensor's position in the turned frame: the input origin, for a camera frame.
        let sensor = opts
            .camera
            .then(|| Point3::from_homogeneous(total * Point3::origin().to_homogeneous()))
            .flatten();
        let fit = find_floor(&points, sensor.as_ref())?;
        let q = UnitQuaternion::rotation_between(&fit.normal, &Vector3::z())
            .unwrap_or_else(UnitQuaternion::identity);
        let mut level = q.to_homogeneous();
        level[(2, 3)] = -fit.offset_m;
        apply(&level, &mut points);
        total = level * total;
        floor = Some(fit);
    }
    Ok((
        PointCloud::new(points),
        FrameReport {
            units: opts.units,
            transformed: opts.transform.is_some(),
            up,
            camera: opts.camera,
            floor,
            matrix: total,
        },
    ))
}

/// Checks that `m` is a finite, invertible affine map.
fn check_affine(m: &Matrix4<f64>) -> Result<(), FrameError> {
    if m.iter().any(|v| !v.is_finite()) {
        return Err(FrameError::Transform("it has a non-finite entry".into()));
    }
    let last = m.row(3);
    if last[0].abs() > 1e-9
        || last[1].abs() > 1e-9
        || last[2].abs() > 1e-9
        || (last[3] - 1.0).abs() > 1e-9
    {
        return Err(FrameError::Transform(format!(
            "the last row is {} {} {} {}, not 0 0 0 1 (projective maps are not supported)",
            last[0], last[1], last[2], last[3]
        )));
    }
    let det = m.fixed_view::<3, 3>(0, 0).determinant();
    if det.abs() < 1e-12 {
        return Err(FrameError::Transform(
            "its 3x3 part is singular (it would flatten the cloud)".into(),
        ));
    }
    Ok(())
}

/// Applies the affine map `m` to every point.
fn apply(m: &Matrix4<f64>, points: &mut [Point3<f64>]) {
    let r = m.fixed_view::<3, 3>(0, 0).into_owned();
    let t = Vector3::new(m[(0, 3)], m[(1, 3)], m[(2, 3)]);
    for p in points {
        *p = Point3::from(r * p.coords + t);
    }
}

/// A plane `n · p = d` with unit normal `n` (`n.z > 0`).
#[derive(Clone, Copy, Debug)]
struct Plane {
    n: Vector3<f64>,
    d: f64,
}

impl Plane {
    fn dist(&self, p: &Point3<f64>) -> f64 {
        self.n.dot(&p.coords) - self.d
    }

    /// The plane through three points, if they span one whose normal is within the
    /// allowed tilt of +z.
    fn through(a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>, min_cos: f64) -> Option<Plane> {
        let n = (b - a).cross(&(c - a)).try_normalize(1e-12)?;
        let n = if n.z < 0.0 { -n } else { n };
        (n.z >= min_cos).then(|| Plane {
            n,
            d: n.dot(&a.coords),
        })
    }
}

/// Least-squares plane through `points` (normal: smallest eigenvector of the covariance),
/// oriented with `n.z >= 0`.
fn fit_plane<'a>(points: impl Iterator<Item = &'a Point3<f64>> + Clone) -> Option<Plane> {
    let mut count = 0usize;
    let mut sum = Vector3::zeros();
    for p in points.clone() {
        count += 1;
        sum += p.coords;
    }
    if count < 3 {
        return None;
    }
    let c = sum / count as f64;
    let mut cov = Matrix3::zeros();
    for p in points {
        let v = p.coords - c;
        cov += v * v.transpose();
    }
    let eig = cov.symmetric_eigen();
    let k = eig.eigenvalues.imin();
    let n = eig
        .eigenvectors
        .column(k)
        .into_owned()
        .try_normalize(1e-12)?;
    let n = if n.z < 0.0 { -n } else { n };
    Some(Plane { n, d: n.dot(&c) })
}

/// Refines `plane` by least squares on the points of `set` within the inlier distance.
fn refine(plane: Plane, set: &[Point3<f64>]) -> Plane {
    let mut plane = plane;
    for _ in 0..3 {
        let near = set.iter().filter(|p| plane.dist(p).abs() <= FLOOR_INLIER_M);
        match fit_plane(near) {
            Some(p) => plane = p,
            None => break,
        }
    }
    plane
}

/// Finds the floor in `points` (already turned so that the assumed up is +z). With a
/// `sensor` position (a camera frame), the tilt allowed is [`FLOOR_MAX_TILT_CAMERA_DEG`]
/// and only planes with the sensor above them are floors.
fn find_floor(
    points: &[Point3<f64>],
    sensor: Option<&Point3<f64>>,
) -> Result<FloorFit, FrameError> {
    let max_tilt = if sensor.is_some() {
        FLOOR_MAX_TILT_CAMERA_DEG
    } else {
        FLOOR_MAX_TILT_DEG
    };
    let faces_sensor = |plane: &Plane| sensor.is_none_or(|s| plane.dist(s) > 0.0);
    let finite: Vec<Point3<f64>> = points
        .iter()
        .filter(|p| p.coords.iter().all(|c| c.is_finite()))
        .copied()
        .collect();
    if finite.len() < 3 {
        return Err(FrameError::NoFloor(format!(
            "the cloud has {} finite points",
            finite.len()
        )));
    }
    let stride = finite.len().div_ceil(WORK_POINTS);
    let work: Vec<Point3<f64>> = finite.iter().step_by(stride).copied().collect();
    let min_cos = max_tilt.to_radians().cos();
    let min_points = to_usize(work.len() as f64 * 0.02).max(10);
    let mut rng = ChaCha8Rng::seed_from_u64(SEED);
    let mut remaining: Vec<Point3<f64>> = work.clone();
    // (plane, inliers in `work`)
    let mut planes: Vec<(Plane, usize)> = Vec::new();
    while planes.len() < MAX_PLANES && remaining.len() >= min_points.max(3) {
        let score_stride = remaining.len().div_ceil(SCORE_POINTS);
        let score: Vec<Point3<f64>> = remaining.iter().step_by(score_stride).copied().collect();
        let mut best: Option<(Plane, usize)> = None;
        for _ in 0..ITERATIONS {
            let n = remaining.len();
            let (i, j, k) = (
                rng.random_range(0..n),
                rng.random_range(0..n),
                rng.random_range(0..n),
            );
            if i == j || j == k || i == k {
                continue;
            }
            let Some(plane) = Plane::through(&remaining[i], &remaining[j], &remaining[k], min_cos)
                .filter(|p| faces_sensor(p))
            else {
                continue;
            };
            let count = score
                .iter()
                .filter(|p| plane.dist(p).abs() <= FLOOR_INLIER_M)
                .count();
            if best.is_none_or(|(_, c)| count > c) {
                best = Some((plane, count));
            }
        }
        let Some((plane, _)) = best else { break };
        let plane = refine(plane, &remaining);
        if plane.n.z < min_cos || !faces_sensor(&plane) {
            break;
        }
        let inliers = work
            .iter()
            .filter(|p| plane.dist(p).abs() <= FLOOR_INLIER_M)
            .count();
        if inliers < min_points {
            break;
        }
        planes.push((plane, inliers));
        remaining.retain(|p| plane.dist(p).abs() > REMOVE_M);
    }
    let largest = planes.iter().map(|(_, c)| *c).max().unwrap_or(0);
    if largest == 0 {
        // A camera frame fixes the up axis; what is missing there is the floor itself (a
        // view of a bed or a desk top from close by shows none).
        let why = if sensor.is_some() {
            format!(
                "no plane within {max_tilt} deg of the camera's up (-y), below the camera, \
                 holds 2% of the points: is the floor in view? (a view without it cannot \
                 be levelled; give the transform to the world frame instead)"
            )
        } else {
            format!(
                "no plane within {max_tilt} deg of the assumed up holds 2% of the points \
                 (is the up axis right? is the floor in view?)"
            )
        };
        return Err(FrameError::NoFloor(why));
    }
    let below = |plane: &Plane| work.iter().filter(|p| plane.dist(p) < -BELOW_M).count();
    let large: Vec<(Plane, usize, usize)> = planes
        .iter()
        .filter(|(_, c)| *c * 10 >= largest)
        .map(|(p, c)| (*p, *c, below(p)))
        .collect();
    let fewest_below = large.iter().map(|(_, _, b)| *b).min().unwrap_or(0);
    let slack = work.len() / 100;
    let (plane, _, _) = large
        .iter()
        .filter(|(_, _, b)| *b <= fewest_below + slack)
        .max_by_key(|(_, c, _)| *c)
        .copied()
        .expect("the largest plane is large");
    let plane = refine(plane, &finite);
    let total = points.len() as f64;
    let on = finite
        .iter()
        .filter(|p| plane.dist(p).abs() <= FLOOR_INLIER_M)
        .count();
    let under = finite.iter().filter(|p| plane.dist(p) < -BELOW_M).count();
    Ok(FloorFit {
        normal: plane.n,
        offset_m: plane.d,
        inlier_share: on as f64 / total,
        below_share: under as f64 / total,
        rotation_deg: plane.n.z.clamp(-1.0, 1.0).acos().to_degrees(),
        planes: planes.len(),
    })
}

/// A warning when the cloud's extent and point spacing say it is not in metres
/// (millimetres: bounding-box diagonal over 100 units with points at least 1 unit apart;
/// centimetres: over 20 units with points at least 0.2 apart), or `None`.
///
/// The extent is the robust one of [`spacing::robust_extent`] (the central 98 % of an
/// even sample along each axis), so that a stray point does not make a room look like
/// millimetres; the spacing is the nearest-neighbour distance at up to [`UNITS_QUERIES`]
/// points ([`spacing::neighbour_distance`]), whose memory follows those points.
pub fn check_units(cloud: &PointCloud) -> Option<String> {
    units_warning(cloud, &spacing::robust_extent(cloud)?)
}

/// [`check_units`] for a cloud whose robust extent is `extent`.
pub(crate) fn units_warning(cloud: &PointCloud, extent: &spacing::Extent) -> Option<String> {
    if extent.n < 10 {
        return None;
    }
    let diag = (extent.hi - extent.lo).norm();
    // Both warnings need more than `CM_DIAGONAL` units across: a cloud within that is
    // metres whatever its spacing, so the spacing is not measured.
    if !diag.is_finite() || diag <= CM_DIAGONAL {
        return None;
    }
    let spacing = spacing::neighbour_distance(cloud, extent, 1, UNITS_QUERIES)?;
    if diag > 100.0 && spacing >= 1.0 {
        Some(format!(
            "the cloud is {diag:.0} units across with points about {spacing:.2} apart: it \
             looks like millimetres ({:.2} m across) or centimetres ({:.1} m), not metres \
             (give the units, e.g. --units mm)",
            diag * 0.001,
            diag * 0.01
        ))
    } else if spacing >= 0.2 {
        Some(format!(
            "the cloud is {diag:.0} units across with points about {spacing:.2} apart: it \
             looks like centimetres ({:.2} m across), not metres (give the units, e.g. --units cm)",
            diag * 0.01
        ))
    } else {
        None
    }
}

/// A warning when the cloud's lowest points lie more than [`FLOOR_OFF_M`] below or above
/// z = 0, where the detector takes the floor to be, or `None`.
///
/// "Lowest" is the 1 % quantile of z of an even sample ([`spacing::robust_extent`]), so a
/// few stray points under the floor do not count. A cloud whose floor is elsewhere (a
/// depth-camera frame, whose origin is the camera; a building's coordinates; a file whose
/// up axis is not z) gives no seat where one is, or one where none is; the warning names
/// the flags that fix it. Meant for clouds the floor finder did not level.
pub fn check_floor(cloud: &PointCloud) -> Option<String> {
    floor_warning(&spacing::robust_extent(cloud)?)
}

/// [`check_floor`] for a cloud whose robust extent is `extent`.
pub(crate) fn floor_warning(extent: &spacing::Extent) -> Option<String> {
    let low = extent.lo.z;
    if extent.n < 10 || !low.is_finite() || low.abs() <= FLOOR_OFF_M {
        return None;
    }
    let how = if low < 0.0 {
        "1% of the points lie below"
    } else {
        "the lowest points lie at"
    };
    Some(format!(
        "{how} z = {low:.2} m, but the detector takes the floor to be at z = 0 (z up): if \
         the floor is elsewhere, give --floor auto (--camera for a depth-camera frame, --up \
         for another up axis)"
    ))
}

/// Distance (metres) from z = 0 of a cloud's lowest points beyond which [`check_floor`]
/// warns: a floor 0.25 m off moves a 0.45 m seat to 0.20 or 0.70 m, out of the seat
/// heights sitting looks for at 1.75 m (0.25-0.70 m).
pub const FLOOR_OFF_M: f64 = 0.25;

/// Diagonal (in the file's units) above which [`check_units`] suspects centimetres: a
/// room read as metres is under 20 m across, in centimetres several hundred.
const CM_DIAGONAL: f64 = 20.0;

/// Points whose nearest-neighbour distance [`check_units`] measures.
const UNITS_QUERIES: usize = 200;

/// Parses a 4x4 matrix from 16 numbers, row-major, separated by whitespace, commas or
/// semicolons (brackets are ignored, `#` starts a comment to the end of the line): the
/// text given inline or the content of a file. Units are those of the cloud after the
/// units scaling (metres). A ScanNet `axisAlignment = ...` line, or a whole ScanNet meta
/// file, gives the matrix of that line ([`super::scannet::axis_alignment`]).
pub fn parse_matrix(text: &str) -> Result<Matrix4<f64>, String> {
    let text = super::scannet::axis_alignment(text).unwrap_or(text);
    let mut values: Vec<f64> = Vec::new();
    for line in text.lines() {
        let line = line.split('#').next().unwrap_or("");
        for tok in line
            .split(|c: char| c.is_whitespace() || matches!(c, ',' | ';' | '[' | ']'))
            .filter(|t| !t.is_empty())
        {
            let v: f64 = tok.parse().map_err(|_| {
                format!("matrix entry {} '{tok}' is not a number", values.len() + 1)
            })?;
            if !v.is_finite() {
                return Err(format!(
                    "matrix entry {} '{tok}' is not finite",
                    values.len() + 1
                ));
            }
            values.push(v);
        }
    }
    if values.len() != 16 {
        return Err(format!(
            "a 4x4 matrix needs 16 numbers (row-major), found {}",
            values.len()
        ));
    }
    Ok(Matrix4::from_row_slice(&values))
}

#[cfg(test)]
// Test data: small literals and lengths, written into the fields of a file by hand.
#[allow(clippy::cast_possible_truncation)]
mod tests {
    use super::*;

    fn close(a: Point3<f64>, b: Point3<f64>) -> bool {
        (a - b).norm() < 1e-12
    }

    #[test]
    fn each_up_axis_maps_to_plus_z() {
        let p = Point3::new(1.0, 2.0, 3.0);
        let cases = [
            (Up::Z, Point3::new(1.0, 2.0, 3.0)),
            (Up::X, Point3::new(-3.0, 2.0, 1.0)),
            (Up::NegX, Point3::new(3.0, 2.0, -1.0)),
            (Up::Y, Point3::new(1.0, -3.0, 2.0)),
            (Up::NegY, Point3::new(1.0, 3.0, -2.0)),
            (Up::NegZ, Point3::new(1.0, -2.0, -3.0)),
        ];
        let axis = |u: Up| match u {
            Up::X => Vector3::x(),
            Up::Y => Vector3::y(),
            Up::Z => Vector3::z(),
            Up::NegX => -Vector3::x(),
            Up::NegY => -Vector3::y(),
            Up::NegZ => -Vector3::z(),
        };
        for (up, want) in cases {
            let r = up.rotation();
            // A proper rotation taking the up axis to +z.
            assert!((r.matrix().determinant() - 1.0).abs() < 1e-12, "{up}");
            assert!((r * axis(up) - Vector3::z()).norm() < 1e-12, "{up}");
            let opts = FrameOptions {
                up,
                ..Default::default()
            };
            let (out, rep) = to_world(PointCloud::new(vec![p]), &opts).unwrap();
            assert!(close(out.points[0], want), "{up}: {:?}", out.points[0]);
            assert_eq!(rep.up, up);
            assert_eq!(up.name().parse::<Up>().unwrap(), up);
        }
        // Camera: x right, y down, z forward -> x right, y forward, z up.
        let opts = FrameOptions {
            camera: true,
            ..Default::default()
        };
        let (out, rep) =
            to_world(PointCloud::new(vec![Point3::new(0.5, 1.0, 4.0)]), &opts).unwrap();
        assert!(close(out.points[0], Point3::new(0.5, 4.0, -1.0)));
        assert_eq!(rep.up, Up::NegY);
        let bad = FrameOptions {
            camera: true,
            up: Up::X,
            ..Default::default()
        };
        assert_eq!(
            to_world(PointCloud::default(), &bad).unwrap_err(),
            FrameError::Conflict(Up::X)
        );
        assert!("w".parse::<Up>().is_err());
    }

    #[test]
    fn units_then_transform_then_up() {
        let p = Point3::new(1000.0, 2000.0, 3000.0);
        let opts = FrameOptions {
            units: Units::Millimetres,
            ..Default::default()
        };
        let (out, rep) = to_world(PointCloud::new(vec![p]), &opts).unwrap();
        assert!(close(out.points[0], Point3::new(1.0, 2.0, 3.0)));
        assert!(rep.to_string().contains("mm to metres"), "{rep}");
        let opts = FrameOptions {
            units: Units::Centimetres,
            ..Default::default()
        };
        let (out, _) = to_world(PointCloud::new(vec![p]), &opts).unwrap();
        assert!(close(out.points[0], Point3::new(10.0, 20.0, 30.0)));
        // Translation in metres after scaling, then y up turned to z up.
        let t = parse_matrix("1 0 0 1\n0 1 0 0\n0 0 1 0\n0 0 0 1").unwrap();
        let opts = FrameOptions {
            units: Units::Millimetres,
            transform: Some(t),
            up: Up::Y,
            ..Default::default()
        };
        let (out, rep) = to_world(PointCloud::new(vec![p]), &opts).unwrap();
        assert!(
            close(out.points[0], Point3::new(2.0, -3.0, 2.0)),
            "{:?}",
            out.points[0]
        );
        // The reported matrix is the whole map.
        let q = rep.matrix.transform_point(&p);
        assert!(close(q, out.points[0]));
        assert_eq!(Units::from_str("mm").unwrap(), Units::Millimetres);
        assert_eq!("auto".parse::<FloorMode>().unwrap(), FloorMode::Auto);
    }

    #[test]
    fn bad_transforms_are_refused() {
        let mut m = Matrix4::identity();
        m[(3, 0)] = 0.5;
        let opts = FrameOptions {
            transform: Some(m),
            ..Default::default()
        };
        assert!(matches!(
            to_world(PointCloud::default(), &opts),
            Err(FrameError::Transform(_))
        ));
        let mut m = Matrix4::identity();
        m[(2, 2)] = 0.0;
        let opts = FrameOptions {
            transform: Some(m),
            ..Default::default()
        };
        let e = to_world(PointCloud::default(), &opts).unwrap_err();
        assert!(e.to_string().contains("singular"), "{e}");
    }

    #[test]
    fn parse_matrix_good_and_bad() {
        let m =
            parse_matrix("1, 2, 3, 4,\n5 6 7 8 # comment\r\n9;10;11;12\n[13 14 15 16]\n").unwrap();
        assert_eq!(m[(0, 1)], 2.0);
        assert_eq!(m[(1, 0)], 5.0);
        assert_eq!(m[(3, 3)], 16.0);
        assert_eq!(m[(2, 3)], 12.0);
        let e = parse_matrix("1 2 3").unwrap_err();
        assert!(e.contains("found 3"), "{e}");
        let e = parse_matrix(&"1 ".repeat(17)).unwrap_err();
        assert!(e.contains("found 17"), "{e}");
        let e = parse_matrix("1 0 0 0 0 1 0 0 0 0 x 0 0 0 0 1").unwrap_err();
        assert!(e.contains("entry 11 'x'"), "{e}");
        assert!(parse_matrix("1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 NaN").is_err());
        assert!(parse_matrix("").is_err());
    }

    /// A grid of points on the rectangle `x0..x1`, `y0..y1` at height `z`, `step` apart.
    fn rect(x0: f64, x1: f64, y0: f64, y1: f64, z: f64, step: f64) -> Vec<Point3<f64>> {
        let mut v = Vec::new();
        let (nx, ny) = (((x1 - x0) / step) as usize, ((y1 - y0) / step) as usize);
        for i in 0..=nx {
            for j in 0..=ny {
                v.push(Point3::new(x0 + i as f64 * step, y0 + j as f64 * step, z));
            }
        }
        v
    }

    /// The five visible faces of a box `x0..x1` x `y0..y1` x `0..h` (no bottom).
    fn box_points(x0: f64, x1: f64, y0: f64, y1: f64, h: f64, step: f64) -> Vec<Point3<f64>> {
        let mut v = rect(x0, x1, y0, y1, h, step);
        let nz = (h / step) as usize;
        for k in 1..nz {
            let z = k as f64 * step;
            let nx = ((x1 - x0) / step) as usize;
            for i in 0..=nx {
                let x = x0 + i as f64 * step;
                v.push(Point3::new(x, y0, z));
                v.push(Point3::new(x, y1, z));
            }
            let ny = ((y1 - y0) / step) as usize;
            for j in 0..=ny {
                let y = y0 + j as f64 * step;
                v.push(Point3::new(x0, y, z));
                v.push(Point3::new(x1, y, z));
            }
        }
        v
    }

    /// Tiny deterministic noise in -a..a.
    fn jitter(points: &mut [Point3<f64>], a: f64) {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for p in points {
            p.z += a * (2.0 * rng.random::<f64>() - 1.0);
        }
    }

    #[test]
    fn camera_view_of_a_floor_comes_back_level() {
        camera_view_comes_back_level(22.0);
    }

    /// Issue 11: a camera 1.5 m high aimed at furniture 2 m away looks ~30-40 deg down;
    /// a floor search limited to 25 deg of the camera's up found no floor there, and the
    /// wall in front of a camera looking down is as steep to it as the floor.
    #[test]
    fn pitched_camera_views_come_back_level() {
        for pitch in [35.0, 45.0, 55.0] {
            camera_view_comes_back_level(pitch);
        }
    }

    fn camera_view_comes_back_level(pitch_deg: f64) {
        // World: floor 5 m x 6 m, a box 0.5 x 0.4 x 0.45 m on it, a wall at y = 6.
        let mut floor = rect(-2.5, 2.5, 0.5, 6.0, 0.0, 0.04);
        jitter(&mut floor, 0.003);
        let nf = floor.len();
        let boxp = box_points(0.3, 0.8, 2.5, 2.9, 0.45, 0.02);
        let nb = boxp.len();
        let mut wall = Vec::new();
        for i in 0..=125 {
            for k in 0..=60 {
                wall.push(Point3::new(-2.5 + 0.04 * i as f64, 6.0, 0.04 * k as f64));
            }
        }
        let world: Vec<Point3<f64>> = floor.iter().chain(&boxp).chain(&wall).copied().collect();
        // Camera 1.5 m above the floor looking along +y, pitched `pitch_deg` down, rolled 4
        // deg, yawed 10 deg. Columns of r_wc: the camera's x (right), y (down), z (forward).
        let (pitch, roll, yaw) = (
            pitch_deg.to_radians(),
            4f64.to_radians(),
            10f64.to_radians(),
        );
        let level = Matrix3::new(1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0);
        let r_wc = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), -pitch)
            * Rotation3::from_matrix_unchecked(level)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), roll);
        // At zero angles the camera's z (forward) is world +y and its y (down) is -z.
        assert!(
            (Rotation3::from_matrix_unchecked(level) * Vector3::z() - Vector3::y()).norm() < 1e-12
        );
        let c = Point3::new(0.2, -0.5, 1.5);
        let cam: Vec<Point3<f64>> = world
            .iter()
            .map(|p| Point3::from(r_wc.inverse() * (p - c)))
            .collect();
        let opts = FrameOptions {
            camera: true,
            floor: FloorMode::Auto,
            ..Default::default()
        };
        let (out, rep) = to_world(PointCloud::new(cam), &opts).unwrap();
        let fl = rep.floor.as_ref().unwrap();
        assert!((fl.offset_m + 1.5).abs() < 0.01, "{rep}");
        assert!((fl.rotation_deg - pitch_deg).abs() < 6.0, "{rep}");
        let worst_floor = out.points[..nf]
            .iter()
            .map(|p| p.z.abs())
            .fold(0.0, f64::max);
        assert!(worst_floor < 0.01, "floor off by {worst_floor}: {rep}");
        let top = out.points[nf..nf + nb]
            .iter()
            .map(|p| p.z)
            .fold(f64::MIN, f64::max);
        assert!((top - 0.45).abs() < 0.02, "box top at {top}");
        // Distances are kept.
        let d_in = (world[0] - world[nf]).norm();
        let d_out = (out.points[0] - out.points[nf]).norm();
        assert!((d_in - d_out).abs() < 1e-9);
        assert!(rep.to_string().contains("camera frame"), "{rep}");
    }

    #[test]
    fn table_and_wall_do_not_beat_a_smaller_floor() {
        // A big table top (3 x 2 m at 0.75 m) and a wall, with less floor visible.
        let table = rect(-1.5, 1.5, -1.0, 1.0, 0.75, 0.02);
        let floor = rect(-2.0, 2.0, 1.2, 1.8, 0.0, 0.03);
        let nt = table.len();
        let nf = floor.len();
        assert!(nf * 2 < nt, "floor {nf} table {nt}");
        let mut wall = Vec::new();
        for i in 0..=200 {
            for k in 0..=120 {
                wall.push(Point3::new(-2.0 + 0.02 * i as f64, 2.0, 0.02 * k as f64));
            }
        }
        assert!(wall.len() > nt);
        // Tilt the whole scene by 8 deg and lift it by 0.3 m.
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), 8f64.to_radians());
        let pts: Vec<Point3<f64>> = table
            .iter()
            .chain(&floor)
            .chain(&wall)
            .map(|p| r * p + Vector3::new(0.0, 0.0, 0.3))
            .collect();
        let opts = FrameOptions {
            floor: FloorMode::Auto,
            ..Default::default()
        };
        let (out, rep) = to_world(PointCloud::new(pts), &opts).unwrap();
        for p in &out.points[nt..nt + nf] {
            assert!(p.z.abs() < 0.01, "floor point at {}: {rep}", p.z);
        }
        for p in &out.points[..nt] {
            assert!((p.z - 0.75).abs() < 0.01, "table point at {}: {rep}", p.z);
        }
    }

    #[test]
    fn no_floor_is_an_error() {
        // Only a vertical wall.
        let wall: Vec<Point3<f64>> = rect(0.0, 2.0, 0.0, 2.0, 0.0, 0.05)
            .into_iter()
            .map(|p| Point3::new(p.x, 0.0, p.y))
            .collect();
        let opts = FrameOptions {
            floor: FloorMode::Auto,
            ..Default::default()
        };
        let e = to_world(PointCloud::new(wall.clone()), &opts).unwrap_err();
        assert!(matches!(e, FrameError::NoFloor(_)), "{e}");
        assert!(e.to_string().contains("up axis right"), "{e}");
        assert!(to_world(PointCloud::default(), &opts).is_err());
        // In a camera frame the up axis is known: the floor is out of view. The wall
        // stands square in front of the camera (the plane z = 2 m, camera axes).
        let ahead: Vec<Point3<f64>> = wall
            .iter()
            .map(|p| Point3::new(p.x - 1.0, 1.0 - p.z, 2.0))
            .collect();
        let camera = FrameOptions {
            camera: true,
            ..opts
        };
        let e = to_world(PointCloud::new(ahead), &camera).unwrap_err();
        assert!(matches!(e, FrameError::NoFloor(_)), "{e}");
        assert!(e.to_string().contains("floor in view"), "{e}");
    }

    #[test]
    fn units_warnings() {
        // A 4 x 3 m room floor, 5 cm grid, plus a wall.
        let mut room = rect(0.0, 4.0, 0.0, 3.0, 0.0, 0.05);
        room.extend(
            rect(0.0, 4.0, 0.0, 2.5, 0.0, 0.05)
                .iter()
                .map(|p| Point3::new(p.x, 0.0, p.y)),
        );
        let metres = PointCloud::new(room.clone());
        assert_eq!(check_units(&metres), None);
        let mm = PointCloud::new(room.iter().map(|p| p * 1000.0).collect());
        let w = check_units(&mm).expect("mm warning");
        assert!(w.contains("millimetres"), "{w}");
        let cm = PointCloud::new(room.iter().map(|p| p * 100.0).collect());
        // 500 units across at 5-unit spacing reads as mm or cm: a warning either way.
        assert!(check_units(&cm).is_some());
        // A chair-sized object in cm: 1 m across, 1 cm spacing.
        let chair = PointCloud::new(
            rect(0.0, 0.5, 0.0, 0.8, 0.0, 0.01)
                .iter()
                .map(|p| p * 100.0)
                .collect(),
        );
        let w = check_units(&chair).expect("cm warning");
        assert!(w.contains("centimetres"), "{w}");
        // A large, dense outdoor scan in metres: no warning.
        let site = PointCloud::new(
            rect(0.0, 60.0, 0.0, 60.0, 0.0, 0.1)
                .iter()
                .map(|p| Point3::new(p.x, p.y, 0.0))
                .collect(),
        );
        assert_eq!(check_units(&site), None);
        // Under 20 units across is metres however sparse: a 10 m yard sampled every metre.
        let yard = PointCloud::new(rect(0.0, 10.0, 0.0, 5.0, 0.0, 1.0));
        assert_eq!(check_units(&yard), None);
    }

    #[test]
    fn a_floor_away_from_zero_is_named() {
        // A 3 x 3 m floor at 5 cm with a 0.45 m box on it, moved to height `dz`.
        let room = |dz: f64| {
            let mut v = rect(0.0, 3.0, 0.0, 3.0, 0.0, 0.05);
            v.extend(box_points(1.0, 1.5, 1.0, 1.5, 0.45, 0.05));
            PointCloud::new(v.iter().map(|p| p + Vector3::new(0.0, 0.0, dz)).collect())
        };
        assert_eq!(check_floor(&room(0.0)), None);
        // Within FLOOR_OFF_M either way: sensor noise, a floor fitted a little off.
        assert_eq!(check_floor(&room(-0.2)), None);
        assert_eq!(check_floor(&room(0.2)), None);
        // A camera frame's origin is the camera, ~1.3 m over the floor.
        let w = check_floor(&room(-1.3)).expect("a floor below zero");
        assert!(w.contains("z = -1.30") && w.contains("--floor auto"), "{w}");
        let w = check_floor(&room(0.8)).expect("a floor above zero");
        assert!(w.contains("z = 0.80") && w.contains("--floor auto"), "{w}");
        // A few stray points far below a floor at zero do not count.
        let mut strays = room(0.0).points;
        let n = strays.len() / 200;
        strays.extend((0..n).map(|i| Point3::new(i as f64 * 0.01, 0.0, -2.0)));
        assert_eq!(check_floor(&PointCloud::new(strays)), None);
    }
}

#[cfg(test)]
mod sample_tests {
    use super::*;
    use std::path::Path;

    /// The committed sample room, seen through a tilted camera 1.6 m above the floor in
    /// millimetres, comes back with its floor at z = 0 and its heights kept.
    #[test]
    fn committed_sample_round_trips_through_a_camera_frame() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/sample/room.ply");
        let world = crate::cloud::load(&path).unwrap().cloud.points;
        let r_wc = Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), -18f64.to_radians())
            * Rotation3::from_matrix_unchecked(Matrix3::new(
                1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, -1.0, 0.0,
            ));
        let c = Point3::new(-1.0, -2.5, 1.6);
        let cam: Vec<Point3<f64>> = world
            .iter()
            .map(|p| Point3::from((r_wc.inverse() * (p - c)) * 1000.0))
            .collect();
        let opts = FrameOptions {
            camera: true,
            units: Units::Millimetres,
            floor: FloorMode::Auto,
            ..Default::default()
        };
        let cam = PointCloud::new(cam);
        assert!(check_units(&cam).unwrap().contains("millimetres"));
        assert_eq!(check_units(&PointCloud::new(world.clone())), None);
        let (out, rep) = to_world(cam, &opts).unwrap();
        let worst = world
            .iter()
            .zip(&out.points)
            .map(|(a, b)| (a.z - b.z).abs())
            .fold(0.0, f64::max);
        assert!(worst < 0.01, "heights off by {worst} m: {rep}");
    }
}
