//! Labelled triangle meshes built from boxes and cylinders, and deterministic surface sampling.
//!
//! Units are metres, the frame is the world frame (z up, floor at z = 0). Every triangle
//! carries a [`Part`] label so that sampled points can be scored against ground truth.
//! Triangles are wound counter-clockwise seen from outside, so `(b - a) × (c - a)` points
//! outward. [`ply`] reads triangle-mesh PLY files into a [`Mesh`].

use nalgebra::{Isometry3, Point3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::cloud::PointCloud;
use crate::num::{index32, to_i64, to_usize};

pub mod ply;

/// What a piece of furniture surface is for, as seen by a sitting or lying person.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub enum Part {
    /// The upper surface one sits on (chair seat top, sofa cushion top, stool top).
    Seat,
    /// The surface the back leans against (chair back, sofa back).
    Backrest,
    /// The bar or block the forearms rest on.
    Armrest,
    /// The part of a (high) back that supports the head.
    Headrest,
    /// The upper surface one lies on (mattress top).
    LyingSurface,
    /// Everything else: legs, frames, sides, tables, shelves, walls, floor.
    Other,
}

/// The per-point `part` code of a labelled cloud file (the `part` property of PLY files;
/// `afford synth` writes it, `afford eval` scores segmentation against it): 0 other (legs,
/// frames, floor, walls), 1 seat, 2 backrest, 3 armrest, 4 headrest, 5 lying surface.
pub fn part_code(p: Part) -> f64 {
    match p {
        Part::Other => 0.0,
        Part::Seat => 1.0,
        Part::Backrest => 2.0,
        Part::Armrest => 3.0,
        Part::Headrest => 4.0,
        Part::LyingSurface => 5.0,
    }
}

/// Whether a per-point `part` code ([`part_code`]) is a surface a body uses (seat,
/// backrest, armrest, headrest or lying surface), not [`Part::Other`].
pub fn is_body_part_code(code: f64) -> bool {
    (1.0..=5.0).contains(&code)
}

/// A triangle mesh in metres (world frame, z up) with one [`Part`] label per triangle.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Vertex positions, metres.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// One label per triangle (`parts.len() == triangles.len()`).
    pub parts: Vec<Part>,
}

/// The six faces of a box, as quads of corner indices (corner `i` has x = max if bit 0,
/// y = max if bit 1, z = max if bit 2), counter-clockwise seen from outside.
/// Order: -x, +x, -y, +y, -z (bottom), +z (top).
const BOX_FACES: [[usize; 4]; 6] = [
    [0, 4, 6, 2],
    [1, 3, 7, 5],
    [0, 1, 5, 4],
    [2, 6, 7, 3],
    [0, 2, 3, 1],
    [4, 5, 7, 6],
];

impl Mesh {
    /// An empty mesh.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether the mesh has no triangle.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    fn push_vertex(&mut self, p: Point3<f64>) -> u32 {
        let i = u32::try_from(self.vertices.len()).expect("mesh has more than u32::MAX vertices");
        self.vertices.push(p);
        i
    }

    fn push_triangle(&mut self, t: [u32; 3], part: Part) {
        self.triangles.push(t);
        self.parts.push(part);
    }

    /// Adds a box from its 8 corners (indexed as in [`BOX_FACES`]), one label per face
    /// in the order -x, +x, -y, +y, -z, +z.
    fn push_box_corners(&mut self, corners: &[Point3<f64>; 8], face_parts: [Part; 6]) {
        let base = self.vertices.len();
        for c in corners {
            self.push_vertex(*c);
        }
        let idx = |k: usize| index32(base + k);
        for (face, part) in BOX_FACES.iter().zip(face_parts) {
            let [a, b, c, d] = face.map(idx);
            self.push_triangle([a, b, c], part);
            self.push_triangle([a, c, d], part);
        }
    }

    /// Adds an axis-aligned box spanning `min`..`max` (metres): 12 outward triangles, all
    /// labelled `part`. Corners are taken component-wise, so swapped bounds are fine.
    pub fn add_box(&mut self, min: Point3<f64>, max: Point3<f64>, part: Part) {
        self.add_box_with_top(min, max, part, part);
    }

    /// Adds an axis-aligned box like [`Mesh::add_box`], with its upper (+z) face labelled
    /// `top` and the five other faces labelled `rest` (e.g. a seat slab: `Seat` on top,
    /// `Other` around).
    pub fn add_box_with_top(&mut self, min: Point3<f64>, max: Point3<f64>, top: Part, rest: Part) {
        let (lo, hi) = (min.inf(&max), min.sup(&max));
        let corners = std::array::from_fn(|i| {
            Point3::new(
                if i & 1 != 0 { hi.x } else { lo.x },
                if i & 2 != 0 { hi.y } else { lo.y },
                if i & 4 != 0 { hi.z } else { lo.z },
            )
        });
        self.push_box_corners(&corners, [rest, rest, rest, rest, rest, top]);
    }

    /// Adds a box centred at `center` with half sizes `half_extents` (metres, along the
    /// box's own axes) turned by `rotation`: 12 outward triangles labelled `part`.
    pub fn add_oriented_box(
        &mut self,
        center: Point3<f64>,
        half_extents: Vector3<f64>,
        rotation: UnitQuaternion<f64>,
        part: Part,
    ) {
        let h = half_extents.abs();
        let corners = std::array::from_fn(|i| {
            let local = Vector3::new(
                if i & 1 != 0 { h.x } else { -h.x },
                if i & 2 != 0 { h.y } else { -h.y },
                if i & 4 != 0 { h.z } else { -h.z },
            );
            center + rotation * local
        });
        self.push_box_corners(&corners, [part; 6]);
    }

    /// Adds a closed cylinder (side and both caps) from `base_center` to `top_center`
    /// with `radius` (metres), approximated by `segments` side quads (at least 3),
    /// all labelled `part`. Does nothing if the axis or the radius is (near) zero.
    pub fn add_cylinder(
        &mut self,
        base_center: Point3<f64>,
        top_center: Point3<f64>,
        radius: f64,
        segments: u32,
        part: Part,
    ) {
        self.add_cylinder_with_top(base_center, top_center, radius, segments, part, part);
    }

    /// Adds a closed cylinder like [`Mesh::add_cylinder`], with the cap at `top_center`
    /// labelled `top` and the side and the other cap labelled `rest` (e.g. a round stool
    /// seat: `Seat` on top).
    pub fn add_cylinder_with_top(
        &mut self,
        base_center: Point3<f64>,
        top_center: Point3<f64>,
        radius: f64,
        segments: u32,
        top: Part,
        rest: Part,
    ) {
        let axis = top_center - base_center;
        let len = axis.norm();
        if len < 1e-12 || radius.is_nan() || radius.abs() < 1e-12 {
            return;
        }
        let radius = radius.abs();
        let n = segments.max(3) as usize;
        let a = axis / len;
        let helper = if a.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let u = (helper - a * a.dot(&helper)).normalize();
        let v = a.cross(&u); // (u, v, a) right-handed
        let base = index32(self.vertices.len());
        for k in 0..n {
            let theta = std::f64::consts::TAU * k as f64 / n as f64;
            let off = (u * theta.cos() + v * theta.sin()) * radius;
            self.push_vertex(base_center + off);
            self.push_vertex(top_center + off);
        }
        let cb = self.push_vertex(base_center);
        let ct = self.push_vertex(top_center);
        for k in 0..n {
            let k1 = (k + 1) % n;
            let (b0, t0) = (base + 2 * index32(k), base + 2 * index32(k) + 1);
            let (b1, t1) = (base + 2 * index32(k1), base + 2 * index32(k1) + 1);
            self.push_triangle([b0, b1, t1], rest);
            self.push_triangle([b0, t1, t0], rest);
            self.push_triangle([cb, b1, b0], rest);
            self.push_triangle([ct, t0, t1], top);
        }
    }

    /// Adds a flat rectangle (2 triangles) spanning `x0..x1`, `y0..y1` at height `z`
    /// (metres), facing up (+z), labelled `part`.
    pub fn add_horizontal_rect(&mut self, x0: f64, y0: f64, x1: f64, y1: f64, z: f64, part: Part) {
        let (xa, xb) = (x0.min(x1), x0.max(x1));
        let (ya, yb) = (y0.min(y1), y0.max(y1));
        let i0 = self.push_vertex(Point3::new(xa, ya, z));
        let i1 = self.push_vertex(Point3::new(xb, ya, z));
        let i2 = self.push_vertex(Point3::new(xb, yb, z));
        let i3 = self.push_vertex(Point3::new(xa, yb, z));
        self.push_triangle([i0, i1, i2], part);
        self.push_triangle([i0, i2, i3], part);
    }

    /// Adds a height field z = `f(x, y)` over `x0..x1` × `y0..y1` (metres) as a grid of
    /// `nx` × `ny` cells (at least 1 each), two triangles per cell facing up, labelled
    /// `part` (a duvet, a pillow top).
    #[allow(clippy::too_many_arguments)]
    pub fn add_height_field(
        &mut self,
        x0: f64,
        x1: f64,
        y0: f64,
        y1: f64,
        nx: usize,
        ny: usize,
        f: impl Fn(f64, f64) -> f64,
        part: Part,
    ) {
        let (nx, ny) = (nx.max(1), ny.max(1));
        let base = index32(self.vertices.len());
        for j in 0..=ny {
            for i in 0..=nx {
                let x = x0 + (x1 - x0) * i as f64 / nx as f64;
                let y = y0 + (y1 - y0) * j as f64 / ny as f64;
                self.push_vertex(Point3::new(x, y, f(x, y)));
            }
        }
        let at = |i: usize, j: usize| base + index32(j * (nx + 1) + i);
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                self.push_triangle([a, b, c], part);
                self.push_triangle([a, c, d], part);
            }
        }
    }

    /// Appends all triangles of `other` (with their labels) to this mesh.
    pub fn append(&mut self, other: &Mesh) {
        let base = index32(self.vertices.len());
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles
            .extend(other.triangles.iter().map(|t| t.map(|i| i + base)));
        self.parts.extend_from_slice(&other.parts);
    }

    /// A copy of this mesh moved by the rigid transform `iso` (rotation then translation).
    pub fn transformed(&self, iso: &Isometry3<f64>) -> Mesh {
        Mesh {
            vertices: self.vertices.iter().map(|p| iso * p).collect(),
            triangles: self.triangles.clone(),
            parts: self.parts.clone(),
        }
    }

    /// A copy of this mesh turned by `yaw_deg` degrees about the vertical (z) axis through
    /// the origin (counter-clockwise seen from above), then moved to `(x, y)` metres.
    /// Heights are unchanged, so furniture standing on the floor stays on it.
    pub fn placed(&self, x: f64, y: f64, yaw_deg: f64) -> Mesh {
        let iso = Isometry3::new(Vector3::new(x, y, 0.0), Vector3::z() * yaw_deg.to_radians());
        self.transformed(&iso)
    }

    /// The three corners of triangle `i`.
    pub fn triangle(&self, i: usize) -> [Point3<f64>; 3] {
        self.triangles[i].map(|k| self.vertices[k as usize])
    }

    /// Area of triangle `i`, square metres.
    pub fn triangle_area(&self, i: usize) -> f64 {
        let [a, b, c] = self.triangle(i);
        0.5 * (b - a).cross(&(c - a)).norm()
    }

    /// Unit outward normal of triangle `i` (zero vector for a degenerate triangle).
    pub fn triangle_normal(&self, i: usize) -> Vector3<f64> {
        let [a, b, c] = self.triangle(i);
        (b - a)
            .cross(&(c - a))
            .try_normalize(1e-300)
            .unwrap_or_else(Vector3::zeros)
    }

    /// Total surface area, square metres.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len())
            .map(|i| self.triangle_area(i))
            .sum()
    }

    /// Total area of the triangles labelled `part`, square metres.
    pub fn part_area(&self, part: Part) -> f64 {
        (0..self.triangles.len())
            .filter(|&i| self.parts[i] == part)
            .map(|i| self.triangle_area(i))
            .sum()
    }

    /// Axis-aligned bounds `(min, max)` of the vertices (metres), or `None` if there is none.
    pub fn bounds(&self) -> Option<(Point3<f64>, Point3<f64>)> {
        let first = *self.vertices.first()?;
        Some(
            self.vertices
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
        )
    }
}

/// One standard normal variate by Box–Muller from two uniforms of `rng`.
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    // `random::<f64>()` is in [0, 1); 1 - u is in (0, 1], so the log is finite.
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Samples points uniformly over the surface of `mesh`, as a depth sensor would see a
/// fully visible object (no occlusion).
///
/// Each triangle of area `A` (m²) gets `floor(A · points_per_m2 + u)` points with `u`
/// uniform in [0, 1), so the expected total is exactly `area · points_per_m2`. Each point
/// is moved along its triangle's normal by Gaussian noise of standard deviation
/// `noise_sigma_m` metres (0 for none). Returns the cloud and each point's [`Part`].
/// The result depends only on the mesh, the parameters and `seed` (ChaCha8).
/// A non-positive or non-finite density gives an empty cloud.
pub fn sample_surface(
    mesh: &Mesh,
    points_per_m2: f64,
    noise_sigma_m: f64,
    seed: u64,
) -> (PointCloud, Vec<Part>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut points = Vec::new();
    let mut parts = Vec::new();
    if !(points_per_m2.is_finite() && points_per_m2 > 0.0) {
        return (PointCloud::new(points), parts);
    }
    let sigma = if noise_sigma_m.is_finite() {
        noise_sigma_m.abs()
    } else {
        0.0
    };
    let expected = mesh.area() * points_per_m2;
    points.reserve(to_usize(expected.ceil()) + mesh.len());
    parts.reserve(to_usize(expected.ceil()) + mesh.len());
    for i in 0..mesh.triangles.len() {
        let area = mesh.triangle_area(i);
        let count = to_usize((area * points_per_m2 + rng.random::<f64>()).floor());
        if count == 0 {
            continue;
        }
        let [a, b, c] = mesh.triangle(i);
        let normal = mesh.triangle_normal(i);
        for _ in 0..count {
            // Uniform on the triangle (Osada et al. 2002): sqrt of the first uniform.
            let s = rng.random::<f64>().sqrt();
            let r = rng.random::<f64>();
            let p = a.coords * (1.0 - s) + b.coords * (s * (1.0 - r)) + c.coords * (s * r);
            let p = if sigma > 0.0 {
                p + normal * (sigma * gaussian(&mut rng))
            } else {
                p
            };
            points.push(Point3::from(p));
            parts.push(mesh.parts[i]);
        }
    }
    (PointCloud::new(points), parts)
}

/// Reads `mesh` as a surface reconstruction would hand it over: the vertices of a mesh
/// remeshed on a grid of `spacing` metres (like ScanNet's `_vh_clean_2.ply` read as
/// points, about 4 cm apart on flat surfaces), not points spread over the area.
///
/// The surface is sampled densely ([`VERTEX_GRID_OVERSAMPLING`] points per grid cell
/// face), the samples are binned into cubes of side `spacing` (the grid's origin shifted
/// by a seeded offset), and each occupied cube gives one vertex at the mean of its
/// samples, labelled with its most frequent [`Part`] (ties: the first in [`Part`] order);
/// thin slabs thus merge into one layer and corners round off, as in a TSDF mesh. Then
/// Gaussian noise of `noise_sigma_m` moves every vertex (all three axes). Vertices come in
/// the order of their cubes; the result depends only on the inputs. A non-positive or
/// non-finite `spacing` gives an empty cloud.
pub fn sample_vertex_grid(
    mesh: &Mesh,
    spacing: f64,
    noise_sigma_m: f64,
    seed: u64,
) -> (PointCloud, Vec<Part>) {
    if !(spacing.is_finite() && spacing > 0.0) {
        return (PointCloud::new(Vec::new()), Vec::new());
    }
    let density = VERTEX_GRID_OVERSAMPLING / (spacing * spacing);
    let (dense, parts) = sample_surface(mesh, density, 0.0, seed);
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x005E_ED0F_6A1D);
    let offset = Vector3::new(
        rng.random::<f64>(),
        rng.random::<f64>(),
        rng.random::<f64>(),
    ) * spacing;
    let key = |p: &Point3<f64>| {
        let q = (p.coords + offset) / spacing;
        (
            to_i64(q.x.floor()),
            to_i64(q.y.floor()),
            to_i64(q.z.floor()),
        )
    };
    let mut order: Vec<(i64, i64, i64, usize)> = dense
        .points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let (a, b, c) = key(p);
            (a, b, c, i)
        })
        .collect();
    order.sort_unstable();
    let sigma = if noise_sigma_m.is_finite() {
        noise_sigma_m.abs()
    } else {
        0.0
    };
    let mut points = Vec::new();
    let mut labels = Vec::new();
    let mut start = 0;
    while start < order.len() {
        let k = (order[start].0, order[start].1, order[start].2);
        let mut end = start;
        let mut sum = Vector3::zeros();
        let mut counts = [0usize; 6];
        while end < order.len() && (order[end].0, order[end].1, order[end].2) == k {
            let i = order[end].3;
            sum += dense.points[i].coords;
            counts[part_index(parts[i])] += 1;
            end += 1;
        }
        let mean = sum / (end - start) as f64;
        let best = (0..6).max_by_key(|&c| (counts[c], 6 - c)).unwrap_or(0);
        let jitter = if sigma > 0.0 {
            Vector3::new(gaussian(&mut rng), gaussian(&mut rng), gaussian(&mut rng)) * sigma
        } else {
            Vector3::zeros()
        };
        points.push(Point3::from(mean + jitter));
        labels.push(PART_ORDER[best]);
        start = end;
    }
    (PointCloud::new(points), labels)
}

/// Dense samples per grid-cell face area that [`sample_vertex_grid`] draws before binning:
/// enough that every cube a surface crosses gets samples (a cube cut by a plane at a
/// corner holds little of it), few enough to stay fast on a whole room.
pub const VERTEX_GRID_OVERSAMPLING: f64 = 6.0;

/// [`Part`]s in a fixed order (ties of [`sample_vertex_grid`]).
const PART_ORDER: [Part; 6] = [
    Part::Seat,
    Part::Backrest,
    Part::Armrest,
    Part::Headrest,
    Part::LyingSurface,
    Part::Other,
];

fn part_index(p: Part) -> usize {
    PART_ORDER.iter().position(|&q| q == p).unwrap_or(5)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn only_the_surfaces_a_body_uses_have_body_part_codes() {
        for p in PART_ORDER {
            assert_eq!(is_body_part_code(part_code(p)), p != Part::Other, "{p:?}");
        }
        assert!(!is_body_part_code(6.0) && !is_body_part_code(f64::NAN));
    }

    fn approx(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol
    }

    #[test]
    fn box_has_12_triangles_and_area_2_ab_bc_ca() {
        let mut m = Mesh::new();
        m.add_box(
            Point3::new(1.0, -1.0, 0.0),
            Point3::new(1.5, 1.0, 3.0),
            Part::Seat,
        );
        let (a, b, c) = (0.5, 2.0, 3.0);
        assert_eq!(m.triangles.len(), 12);
        assert_eq!(m.parts.len(), 12);
        assert!(m.parts.iter().all(|&p| p == Part::Seat));
        assert!(approx(m.area(), 2.0 * (a * b + b * c + c * a), 1e-12));
        let (lo, hi) = m.bounds().unwrap();
        assert_eq!(lo, Point3::new(1.0, -1.0, 0.0));
        assert_eq!(hi, Point3::new(1.5, 1.0, 3.0));
    }

    #[test]
    fn box_normals_point_outward() {
        let mut m = Mesh::new();
        m.add_box(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 2.0, 3.0),
            Part::Other,
        );
        let centre = Point3::new(0.5, 1.0, 1.5);
        for i in 0..m.len() {
            let [a, b, c] = m.triangle(i);
            let mid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            assert!(
                m.triangle_normal(i).dot(&(mid - centre)) > 0.0,
                "triangle {i}"
            );
        }
    }

    #[test]
    fn box_with_top_labels_only_the_upper_face() {
        let mut m = Mesh::new();
        m.add_box_with_top(
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(2.0, 3.0, 1.0),
            Part::Seat,
            Part::Other,
        );
        assert!(approx(m.part_area(Part::Seat), 6.0, 1e-12));
        for i in 0..m.len() {
            if m.parts[i] == Part::Seat {
                assert!(approx(m.triangle_normal(i).z, 1.0, 1e-12));
                assert!(m.triangle(i).iter().all(|p| p.z == 1.0));
            }
        }
    }

    #[test]
    fn oriented_box_keeps_area_and_turns_outward() {
        let rot = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.1);
        let centre = Point3::new(0.2, 0.4, 1.0);
        let mut m = Mesh::new();
        m.add_oriented_box(centre, Vector3::new(0.1, 0.2, 0.3), rot, Part::Backrest);
        let (a, b, c) = (0.2, 0.4, 0.6);
        assert!(approx(m.area(), 2.0 * (a * b + b * c + c * a), 1e-12));
        for i in 0..m.len() {
            let [p, q, r] = m.triangle(i);
            let mid = Point3::from((p.coords + q.coords + r.coords) / 3.0);
            assert!(m.triangle_normal(i).dot(&(mid - centre)) > 0.0);
        }
        // Unrotated, it equals the axis-aligned box.
        let mut o = Mesh::new();
        o.add_oriented_box(
            centre,
            Vector3::new(0.1, 0.2, 0.3),
            UnitQuaternion::identity(),
            Part::Other,
        );
        let (lo, hi) = o.bounds().unwrap();
        assert!((lo - Point3::new(0.1, 0.2, 0.7)).norm() < 1e-12);
        assert!((hi - Point3::new(0.3, 0.6, 1.3)).norm() < 1e-12);
    }

    #[test]
    fn cylinder_area_approaches_2_pi_r_r_plus_h() {
        let (r, h) = (0.2, 0.7);
        let mut m = Mesh::new();
        m.add_cylinder(
            Point3::new(0.0, 0.0, 0.0),
            Point3::from(Vector3::new(1.0, 2.0, 2.0).normalize() * h),
            r,
            512,
            Part::Other,
        );
        let exact = 2.0 * PI * r * (r + h);
        assert!(
            (m.area() - exact).abs() / exact < 1e-4,
            "{} vs {exact}",
            m.area()
        );
        // Exact polygonal area for few segments: n·2r·sin(π/n)·h + n·r²·sin(2π/n).
        let n = 6.0;
        let mut hex = Mesh::new();
        hex.add_cylinder(
            Point3::new(1.0, 1.0, 1.0),
            Point3::new(1.0, 1.0 + h, 1.0),
            r,
            6,
            Part::Other,
        );
        let poly = n * 2.0 * r * (PI / n).sin() * h + n * r * r * (2.0 * PI / n).sin();
        assert!(approx(hex.area(), poly, 1e-12));
        assert_eq!(hex.len(), 24);
    }

    #[test]
    fn tilted_cylinder_normals_point_outward_and_top_is_labelled() {
        let base = Point3::new(0.1, -0.2, 0.3);
        let top = Point3::new(0.5, 0.4, 1.2);
        let mut m = Mesh::new();
        m.add_cylinder_with_top(base, top, 0.15, 16, Part::Seat, Part::Other);
        let centre = Point3::from((base.coords + top.coords) / 2.0);
        let axis = (top - base).normalize();
        for i in 0..m.len() {
            let [a, b, c] = m.triangle(i);
            let mid = Point3::from((a.coords + b.coords + c.coords) / 3.0);
            assert!(m.triangle_normal(i).dot(&(mid - centre)) > 0.0);
            if m.parts[i] == Part::Seat {
                assert!(approx(m.triangle_normal(i).dot(&axis), 1.0, 1e-9));
            }
        }
        assert_eq!(m.parts.iter().filter(|&&p| p == Part::Seat).count(), 16);
    }

    #[test]
    fn append_and_transform_keep_area_and_labels() {
        let mut a = Mesh::new();
        a.add_box(Point3::origin(), Point3::new(1.0, 1.0, 1.0), Part::Seat);
        let mut b = Mesh::new();
        b.add_cylinder(
            Point3::origin(),
            Point3::new(0.0, 0.0, 1.0),
            0.1,
            8,
            Part::Other,
        );
        let mut m = a.clone();
        m.append(&b);
        assert_eq!(m.len(), a.len() + b.len());
        assert!(approx(m.area(), a.area() + b.area(), 1e-12));
        assert_eq!(m.parts[..12], [Part::Seat; 12]);
        assert!(m
            .triangles
            .iter()
            .flatten()
            .all(|&i| (i as usize) < m.vertices.len()));
        let iso = Isometry3::new(Vector3::new(1.0, 2.0, 3.0), Vector3::new(0.2, 0.5, -0.3));
        let t = m.transformed(&iso);
        assert!(approx(t.area(), m.area(), 1e-12));
        assert_eq!(t.parts, m.parts);
        let p = m.placed(2.0, -1.0, 90.0);
        let (lo, hi) = p.bounds().unwrap();
        // The unit cube turned 90° about z lies in x ∈ [-1, 0] before moving by (2, -1).
        assert!((lo - Point3::new(1.0, -1.1, 0.0)).norm() < 1e-9, "{lo}");
        assert!((hi - Point3::new(2.1, 0.0, 1.0)).norm() < 1e-9, "{hi}");
    }

    fn test_mesh() -> Mesh {
        let mut m = Mesh::new();
        m.add_box(
            Point3::new(-0.5, -0.4, 0.0),
            Point3::new(0.5, 0.4, 0.3),
            Part::Other,
        );
        m.add_box_with_top(
            Point3::new(-0.2, -0.2, 0.3),
            Point3::new(0.2, 0.2, 0.45),
            Part::Seat,
            Part::Other,
        );
        m.add_cylinder(
            Point3::new(0.0, 0.0, 0.45),
            Point3::new(0.0, 0.0, 1.0),
            0.05,
            24,
            Part::Backrest,
        );
        m
    }

    #[test]
    fn sampling_count_matches_density_times_area() {
        let m = test_mesh();
        for density in [500.0, 2000.0, 10000.0] {
            let (cloud, parts) = sample_surface(&m, density, 0.0, 7);
            let expected = m.area() * density;
            let got = cloud.len() as f64;
            assert_eq!(parts.len(), cloud.len());
            assert!(
                (got - expected).abs() / expected < 0.03,
                "{got} vs {expected}"
            );
        }
        // Per part too.
        let (_, parts) = sample_surface(&m, 20000.0, 0.0, 3);
        let seats = parts.iter().filter(|&&p| p == Part::Seat).count() as f64;
        let want = m.part_area(Part::Seat) * 20000.0;
        assert!((seats - want).abs() / want < 0.05, "{seats} vs {want}");
    }

    #[test]
    fn sampling_is_deterministic_per_seed() {
        let m = test_mesh();
        let (a, pa) = sample_surface(&m, 3000.0, 0.005, 42);
        let (b, pb) = sample_surface(&m, 3000.0, 0.005, 42);
        let (c, _) = sample_surface(&m, 3000.0, 0.005, 43);
        assert_eq!(a, b);
        assert_eq!(pa, pb);
        assert_ne!(a, c);
    }

    #[test]
    fn sampled_points_lie_on_the_surface_within_noise() {
        let m = test_mesh();
        let (lo, hi) = m.bounds().unwrap();
        let (clean, parts) = sample_surface(&m, 5000.0, 0.0, 1);
        for p in &clean.points {
            assert!(p.x >= lo.x - 1e-9 && p.y >= lo.y - 1e-9 && p.z >= lo.z - 1e-9);
            assert!(p.x <= hi.x + 1e-9 && p.y <= hi.y + 1e-9 && p.z <= hi.z + 1e-9);
        }
        // Noise-free Seat points are exactly on the seat top.
        for (p, part) in clean.points.iter().zip(&parts) {
            if *part == Part::Seat {
                assert!(approx(p.z, 0.45, 1e-12));
            }
        }
        let sigma = 0.004;
        let (noisy, parts) = sample_surface(&m, 5000.0, sigma, 1);
        let margin = 6.0 * sigma;
        for p in &noisy.points {
            assert!(p.x >= lo.x - margin && p.y >= lo.y - margin && p.z >= lo.z - margin);
            assert!(p.x <= hi.x + margin && p.y <= hi.y + margin && p.z <= hi.z + margin);
        }
        // Noise on the seat top is along z with the requested spread.
        let dz: Vec<f64> = noisy
            .points
            .iter()
            .zip(&parts)
            .filter(|(_, &part)| part == Part::Seat)
            .map(|(p, _)| p.z - 0.45)
            .collect();
        let n = dz.len() as f64;
        let mean = dz.iter().sum::<f64>() / n;
        let sd = (dz.iter().map(|d| (d - mean).powi(2)).sum::<f64>() / n).sqrt();
        assert!(mean.abs() < 0.001, "mean {mean}");
        assert!((sd - sigma).abs() / sigma < 0.15, "sd {sd}");
    }

    #[test]
    fn parts_serialize_by_name() {
        assert_eq!(serde_json::to_string(&Part::Seat).unwrap(), "\"Seat\"");
        assert_eq!(
            serde_json::to_string(&[Part::LyingSurface, Part::Headrest]).unwrap(),
            "[\"LyingSurface\",\"Headrest\"]"
        );
    }

    #[test]
    fn sampling_with_no_density_is_empty() {
        let m = test_mesh();
        assert!(sample_surface(&m, 0.0, 0.0, 1).0.is_empty());
        assert!(sample_surface(&m, f64::NAN, 0.0, 1).0.is_empty());
        assert!(sample_surface(&Mesh::new(), 1000.0, 0.01, 1).0.is_empty());
    }
    #[test]
    fn vertex_grid_spacing_is_the_grid_not_the_area() {
        let mut m = Mesh::new();
        m.add_horizontal_rect(0.0, 0.0, 1.0, 1.0, 0.0, Part::Seat);
        let s = 0.04;
        let (c, parts) = sample_vertex_grid(&m, s, 0.0, 3);
        let n = c.points.len();
        // 25 x 25 cells, plus a partial row and column at the shifted grid's edges.
        assert!((625..=676).contains(&n), "{n}");
        assert!(parts.iter().all(|&p| p == Part::Seat));
        let nn: Vec<f64> = c
            .points
            .iter()
            .enumerate()
            .map(|(i, p)| {
                c.points
                    .iter()
                    .enumerate()
                    .filter(|&(j, _)| j != i)
                    .map(|(_, q)| (p - q).norm())
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let mut sorted = nn.clone();
        sorted.sort_by(f64::total_cmp);
        let median = sorted[n / 2];
        // Cell centres ~s apart, each mean moved a few mm by the samples it holds.
        assert!((0.75 * s..=1.1 * s).contains(&median), "{median}");
        // Area sampling at the same count puts many points much closer together.
        let close = nn.iter().filter(|&&d| d < s / 2.0).count();
        let (a, _) = sample_surface(&m, n as f64, 0.0, 3);
        let close_area = a
            .points
            .iter()
            .enumerate()
            .filter(|(i, p)| {
                a.points
                    .iter()
                    .enumerate()
                    .any(|(j, q)| j != *i && (*p - q).norm() < s / 2.0)
            })
            .count();
        assert!(
            close * 10 < n && close_area * 4 > a.points.len(),
            "{close} {close_area}"
        );
        // Every point lies on the surface; the same seed gives the same cloud.
        assert!(c.points.iter().all(|p| p.z.abs() < 1e-12));
        assert_eq!(sample_vertex_grid(&m, s, 0.0, 3).0.points, c.points);
        assert!(sample_vertex_grid(&m, 0.0, 0.0, 3).0.points.is_empty());
    }
}
