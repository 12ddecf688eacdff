//! A virtual depth camera (Kinect v1 like) that ray-casts a labelled [`Mesh`].
//!
//! Every pixel (optionally every `stride`-th pixel in both directions) casts a ray from
//! the camera centre through the pixel centre of a pinhole image; the nearest triangle hit
//! is kept, so parts hidden behind others are not seen (self-occlusion). Depth values are
//! then degraded as a structured-light sensor would degrade them:
//!
//! * axial (depth) noise of standard deviation `0.0012 + 0.0019 (z - 0.4)²` metres at
//!   depth `z` (Nguyen, Izadi and Lovell 2012, for Kinect v1);
//! * disparity quantisation: depths are rounded to the nearest `1 / (k n)` for an integer
//!   `n`, which gives depth steps of about `k z²` metres (`k = 2.85e-3` per metre);
//! * dropouts at grazing angles: a hit whose ray makes more than `grazing_start_deg` with
//!   the surface normal is lost with a probability rising linearly to 1 at
//!   `grazing_end_deg`;
//! * a working range: depths outside `min_range..max_range` give no point;
//! * mixed pixels ("flying pixels", off for the default Kinect v1): where the depths of
//!   two neighbouring cast pixels differ by more than `mixed_jump`, the nearer pixel gives
//!   with probability `mixed_pixels` a second point on its ray at a depth drawn uniformly
//!   between the two, as a time-of-flight or stereo sensor that mixes the foreground's
//!   and the background's returns at a depth edge does. These draw from their own random
//!   stream, so a view without them is the same bytes as before they existed.
//!
//! "Depth" is the distance along the optical axis (as a depth image stores it), not
//! along the ray. Points are returned in the world frame (metres, z up). The result only
//! depends on the mesh, the camera and the seed.

use nalgebra::{Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use afford::cloud::PointCloud;
use afford::mesh::{Mesh, Part};

/// How the sensor degrades depth. All lengths in metres, angles in degrees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SensorNoise {
    /// Constant term of the axial noise standard deviation, metres (Kinect v1: 0.0012).
    pub axial_a: f64,
    /// Quadratic term of the axial noise standard deviation, per metre (Kinect v1: 0.0019).
    pub axial_b: f64,
    /// Depth at which the quadratic term vanishes, metres (Kinect v1: 0.4).
    pub axial_z0: f64,
    /// Depth quantisation factor `k` (step ≈ `k z²`), per metre (Kinect v1: 2.85e-3);
    /// 0 for no quantisation.
    pub quantisation: f64,
    /// Angle between ray and surface normal above which points start to drop out, degrees.
    pub grazing_start_deg: f64,
    /// Angle between ray and surface normal at which every point drops out, degrees.
    pub grazing_end_deg: f64,
    /// Probability that a pixel at a depth edge gives a mixed return (0: none).
    pub mixed_pixels: f64,
    /// Least depth difference between neighbouring cast pixels that makes an edge, metres.
    pub mixed_jump: f64,
}

impl Default for SensorNoise {
    /// Kinect v1 values (see the module documentation).
    fn default() -> Self {
        Self {
            axial_a: 0.0012,
            axial_b: 0.0019,
            axial_z0: 0.4,
            quantisation: 2.85e-3,
            grazing_start_deg: 75.0,
            grazing_end_deg: 85.0,
            // Structured light (Kinect v1) loses edge pixels rather than mixing them.
            mixed_pixels: 0.0,
            // 5 cm: a Kinect v2 smears returns across steps of a few centimetres and more.
            mixed_jump: 0.05,
        }
    }
}

impl SensorNoise {
    /// A perfect sensor: no noise, no quantisation, no grazing dropouts.
    pub fn none() -> Self {
        Self {
            axial_a: 0.0,
            axial_b: 0.0,
            axial_z0: 0.0,
            quantisation: 0.0,
            grazing_start_deg: 90.0,
            grazing_end_deg: 90.0,
            mixed_pixels: 0.0,
            mixed_jump: 0.05,
        }
    }

    /// Standard deviation of the axial noise at depth `z` metres, metres.
    pub fn axial_sigma(&self, z: f64) -> f64 {
        self.axial_a + self.axial_b * (z - self.axial_z0).powi(2)
    }
}

/// A pinhole depth camera in the world frame (metres, z up).
///
/// The image has `width` × `height` pixels spanning `hfov_deg` × `vfov_deg`; the optical
/// axis goes from `position` to `target`, and the image's up direction is the world z
/// axis projected onto the image plane (no roll).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Horizontal field of view, degrees.
    pub hfov_deg: f64,
    /// Vertical field of view, degrees.
    pub vfov_deg: f64,
    /// Optical centre, world frame, metres.
    pub position: Point3<f64>,
    /// A point on the optical axis, world frame, metres.
    pub target: Point3<f64>,
    /// Only every `stride`-th pixel column and row is cast (1 = all pixels; 0 counts as 1).
    pub stride: u32,
    /// Nearest depth measured, metres.
    pub min_range: f64,
    /// Farthest depth measured, metres.
    pub max_range: f64,
    /// How depth is degraded.
    pub noise: SensorNoise,
}

impl Default for Camera {
    /// A Kinect v1: 640 × 480 pixels, 57° × 43°, 0.5–4.0 m, Kinect noise, at 1.4 m height
    /// 2.5 m in front (+x) of the origin, looking at (0, 0, 0.4).
    fn default() -> Self {
        Self {
            width: 640,
            height: 480,
            hfov_deg: 57.0,
            vfov_deg: 43.0,
            position: Point3::new(2.5, 0.0, 1.4),
            target: Point3::new(0.0, 0.0, 0.4),
            stride: 1,
            min_range: 0.5,
            max_range: 4.0,
            noise: SensorNoise::default(),
        }
    }
}

impl Camera {
    /// The default (Kinect v1) camera at `position` looking at `target` (metres, world).
    pub fn looking_at(position: Point3<f64>, target: Point3<f64>) -> Self {
        Self {
            position,
            target,
            ..Self::default()
        }
    }

    /// Unit vectors (forward, right, up) of the camera frame in the world frame.
    pub fn basis(&self) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let forward = (self.target - self.position)
            .try_normalize(1e-12)
            .unwrap_or_else(Vector3::x);
        let helper = if forward.cross(&Vector3::z()).norm() < 1e-6 {
            Vector3::x()
        } else {
            Vector3::z()
        };
        let right = forward.cross(&helper).normalize();
        let up = right.cross(&forward);
        (forward, right, up)
    }

    /// Moves `points` (world frame) into this camera's frame: x right, y down, z forward,
    /// metres from its centre.
    pub fn into_own_frame(&self, points: &mut [Point3<f64>]) {
        let (forward, right, up) = self.basis();
        for p in points {
            let d = *p - self.position;
            *p = Point3::new(d.dot(&right), -d.dot(&up), d.dot(&forward));
        }
    }

    /// Unit ray direction (world frame) through the centre of pixel (`u`, `v`); `u` counts
    /// columns from the left, `v` rows from the top.
    pub fn ray(&self, u: u32, v: u32) -> Vector3<f64> {
        let (forward, right, up) = self.basis();
        let fx = (self.width as f64 / 2.0) / (self.hfov_deg.to_radians() / 2.0).tan();
        let fy = (self.height as f64 / 2.0) / (self.vfov_deg.to_radians() / 2.0).tan();
        let x = (u as f64 + 0.5 - self.width as f64 / 2.0) / fx;
        let y = (v as f64 + 0.5 - self.height as f64 / 2.0) / fy;
        (forward + right * x - up * y).normalize()
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug)]
struct Aabb {
    lo: Vector3<f64>,
    hi: Vector3<f64>,
}

impl Aabb {
    fn empty() -> Self {
        Self {
            lo: Vector3::repeat(f64::INFINITY),
            hi: Vector3::repeat(f64::NEG_INFINITY),
        }
    }

    fn grow(&mut self, p: &Vector3<f64>) {
        self.lo = self.lo.inf(p);
        self.hi = self.hi.sup(p);
    }

    fn merge(&mut self, o: &Aabb) {
        self.lo = self.lo.inf(&o.lo);
        self.hi = self.hi.sup(&o.hi);
    }

    /// Entry distance of the ray into the box if it enters before `tmax`.
    fn hit(&self, o: &Vector3<f64>, inv: &Vector3<f64>, tmax: f64) -> Option<f64> {
        let mut t0 = 0.0f64;
        let mut t1 = tmax;
        for k in 0..3 {
            let a = (self.lo[k] - o[k]) * inv[k];
            let b = (self.hi[k] - o[k]) * inv[k];
            let (a, b) = if a <= b { (a, b) } else { (b, a) };
            // NaN (0 * inf) compares false and leaves the bound unchanged.
            if a > t0 {
                t0 = a;
            }
            if b < t1 {
                t1 = b;
            }
            if t0 > t1 {
                return None;
            }
        }
        Some(t0)
    }
}

/// A node of the bounding volume hierarchy: a leaf holds `count` triangles from `start`
/// of the permuted triangle list; an inner node (`count == 0`) has its children at
/// `start` and `start + 1`.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Aabb,
    start: u32,
    count: u32,
}

/// A bounding volume hierarchy over the triangles of a mesh, for ray casting.
pub struct Bvh<'a> {
    mesh: &'a Mesh,
    nodes: Vec<Node>,
    tris: Vec<u32>,
}

/// The nearest intersection of a ray with a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the (unit) ray, metres.
    pub t: f64,
    /// Index of the triangle hit.
    pub triangle: usize,
}

const LEAF_SIZE: usize = 4;

/// A triangle or node index as the hierarchy stores it (`u32`, half the memory),
/// saturating: a mesh has fewer than `u32::MAX` triangles (its vertex indices are `u32`
/// and a mesh file is at most 1 GiB), and the hierarchy has fewer than twice as many nodes.
fn tri32(i: usize) -> u32 {
    u32::try_from(i).unwrap_or(u32::MAX)
}

impl<'a> Bvh<'a> {
    /// Builds the hierarchy (median split along the longest axis of the centroids).
    pub fn new(mesh: &'a Mesh) -> Self {
        let n = mesh.triangles.len();
        let mut tris: Vec<u32> = (0..tri32(n)).collect();
        let boxes: Vec<Aabb> = (0..n)
            .map(|i| {
                let mut b = Aabb::empty();
                for p in mesh.triangle(i) {
                    b.grow(&p.coords);
                }
                b
            })
            .collect();
        let centroids: Vec<Vector3<f64>> = boxes.iter().map(|b| (b.lo + b.hi) / 2.0).collect();
        let mut nodes = vec![Node {
            bounds: Aabb::empty(),
            start: 0,
            count: 0,
        }];
        // Work list of (node index, triangle range).
        let mut work = vec![(0usize, 0usize, n)];
        while let Some((ni, s, e)) = work.pop() {
            let mut b = Aabb::empty();
            let mut c = Aabb::empty();
            for &t in &tris[s..e] {
                b.merge(&boxes[t as usize]);
                c.grow(&centroids[t as usize]);
            }
            nodes[ni].bounds = b;
            let ext = c.hi - c.lo;
            if e - s <= LEAF_SIZE || ext.max() <= 0.0 {
                nodes[ni].start = tri32(s);
                nodes[ni].count = tri32(e - s);
                continue;
            }
            let axis = ext.imax();
            let mid = (s + e) / 2;
            tris[s..e].select_nth_unstable_by(mid - s, |a, b| {
                centroids[*a as usize][axis].total_cmp(&centroids[*b as usize][axis])
            });
            let left = nodes.len();
            let empty = Node {
                bounds: Aabb::empty(),
                start: 0,
                count: 0,
            };
            nodes.push(empty);
            nodes.push(empty);
            nodes[ni].start = tri32(left);
            nodes[ni].count = 0;
            work.push((left, s, mid));
            work.push((left + 1, mid, e));
        }
        Self { mesh, nodes, tris }
    }

    /// The nearest hit of the ray `origin + t dir` (t > 1e-9, `dir` unit) with the mesh,
    /// both faces of every triangle counting.
    pub fn cast(&self, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<Hit> {
        if self.tris.is_empty() {
            return None;
        }
        let o = origin.coords;
        let inv = dir.map(|d| 1.0 / d);
        let mut best: Option<Hit> = None;
        let mut tmax = f64::INFINITY;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let node = &self.nodes[ni as usize];
            if node.bounds.hit(&o, &inv, tmax).is_none() {
                continue;
            }
            if node.count > 0 {
                let s = node.start as usize;
                for &ti in &self.tris[s..s + node.count as usize] {
                    let [a, b, c] = self.mesh.triangle(ti as usize);
                    if let Some(t) = intersect(origin, dir, &a, &b, &c) {
                        if t < tmax {
                            tmax = t;
                            best = Some(Hit {
                                t,
                                triangle: ti as usize,
                            });
                        }
                    }
                }
            } else {
                let (l, r) = (node.start, node.start + 1);
                let tl = self.nodes[l as usize].bounds.hit(&o, &inv, tmax);
                let tr = self.nodes[r as usize].bounds.hit(&o, &inv, tmax);
                // Push the farther child first so the nearer one is searched first.
                match (tl, tr) {
                    (Some(a), Some(b)) if a <= b => {
                        stack.push(r);
                        stack.push(l);
                    }
                    (Some(_), Some(_)) => {
                        stack.push(l);
                        stack.push(r);
                    }
                    (Some(_), None) => stack.push(l),
                    (None, Some(_)) => stack.push(r),
                    (None, None) => {}
                }
            }
        }
        best
    }
}

/// Möller–Trumbore ray–triangle intersection, two-sided; the ray parameter if t > 1e-9.
fn intersect(
    o: &Point3<f64>,
    d: &Vector3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let pv = d.cross(&e2);
    let det = e1.dot(&pv);
    if det.abs() < 1e-15 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = o - a;
    let u = tv.dot(&pv) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qv = tv.cross(&e1);
    let v = d.dot(&qv) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    let t = e2.dot(&qv) * inv;
    (t > 1e-9).then_some(t)
}

/// One standard normal variate (Box–Muller).
fn gaussian(rng: &mut ChaCha8Rng) -> f64 {
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Renders one depth view of `mesh` and returns the measured points (world frame, metres)
/// with the triangle index each came from. See [`render_view`].
pub fn render_view_triangles(mesh: &Mesh, cam: &Camera, seed: u64) -> (PointCloud, Vec<usize>) {
    let bvh = Bvh::new(mesh);
    let stride = cam.stride.max(1);
    let (forward, _, _) = cam.basis();
    let cols: Vec<u32> = (0..cam.width).step_by(stride as usize).collect();
    let rows: Vec<u32> = (0..cam.height).step_by(stride as usize).collect();
    // Cast in parallel (pure), then degrade sequentially with one RNG (deterministic).
    let hits: Vec<(Vector3<f64>, Option<Hit>)> = rows
        .par_iter()
        .flat_map_iter(|&v| {
            let bvh = &bvh;
            cols.iter().map(move |&u| {
                let dir = cam.ray(u, v);
                (dir, bvh.cast(&cam.position, &dir))
            })
        })
        .collect();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let nz = &cam.noise;
    let mut points = Vec::new();
    let mut tris = Vec::new();
    // Each cast pixel's measured range along its ray and triangle, for the mixed pixels.
    let mixing = nz.mixed_pixels > 0.0;
    let mut measured: Vec<Option<(f64, usize)>> = Vec::new();
    for (dir, hit) in &hits {
        if mixing {
            measured.push(None);
        }
        let Some(hit) = hit else { continue };
        // Draw the same number of variates per hit, so one pixel does not shift the rest.
        let g = gaussian(&mut rng);
        let drop_u = rng.random::<f64>();
        let cos_axis = dir.dot(&forward);
        let z = hit.t * cos_axis;
        let normal = mesh.triangle_normal(hit.triangle);
        let cos_inc = dir.dot(&normal).abs().clamp(0.0, 1.0);
        let angle = cos_inc.acos().to_degrees();
        if angle > nz.grazing_start_deg {
            let span = (nz.grazing_end_deg - nz.grazing_start_deg).max(1e-9);
            let p_drop = ((angle - nz.grazing_start_deg) / span).clamp(0.0, 1.0);
            if drop_u < p_drop {
                continue;
            }
        }
        let mut zm = z + nz.axial_sigma(z) * g;
        if nz.quantisation > 0.0 && zm > 0.0 {
            let n = (1.0 / (nz.quantisation * zm)).round().max(1.0);
            zm = 1.0 / (nz.quantisation * n);
        }
        if !(cam.min_range..=cam.max_range).contains(&zm) {
            continue;
        }
        points.push(cam.position + dir * (zm / cos_axis));
        tris.push(hit.triangle);
        if let Some(m) = measured.last_mut() {
            *m = Some((zm / cos_axis, hit.triangle));
        }
    }
    if mixing {
        mix_edges(
            cam,
            &hits,
            &measured,
            cols.len(),
            seed,
            &mut points,
            &mut tris,
        );
    }
    (PointCloud::new(points), tris)
}

/// Random stream of the mixed pixels, apart from the per-pixel one.
const MIXED_STREAM: u64 = 0x6d69_7865_645f_7078;

/// Appends the mixed pixels of one view (see the module documentation): for each pair of
/// neighbouring cast pixels (right and below, row-major over `cols` columns) whose
/// `measured` ranges differ by more than the camera's `mixed_jump`, with probability
/// `mixed_pixels`, a point on the nearer pixel's ray (its direction in `hits`) at a range
/// drawn uniformly between the two, on the nearer pixel's triangle.
fn mix_edges(
    cam: &Camera,
    hits: &[(Vector3<f64>, Option<Hit>)],
    measured: &[Option<(f64, usize)>],
    cols: usize,
    seed: u64,
    points: &mut Vec<Point3<f64>>,
    tris: &mut Vec<usize>,
) {
    let nz = &cam.noise;
    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ MIXED_STREAM);
    for (i, here) in measured.iter().enumerate() {
        let Some((ri, ti)) = *here else { continue };
        let right = (cols > 0 && (i + 1) % cols != 0).then_some(i + 1);
        for j in [right, Some(i + cols)].into_iter().flatten() {
            let Some(&Some((rj, tj))) = measured.get(j) else {
                continue;
            };
            if (ri - rj).abs() <= nz.mixed_jump {
                continue;
            }
            // The same two draws for every edge pair.
            let (keep, at) = (rng.random::<f64>(), rng.random::<f64>());
            if keep >= nz.mixed_pixels {
                continue;
            }
            let (near, far, dir, tri) = if ri < rj {
                (ri, rj, hits[i].0, ti)
            } else {
                (rj, ri, hits[j].0, tj)
            };
            points.push(cam.position + dir * (near + at * (far - near)));
            tris.push(tri);
        }
    }
}

/// Renders one depth view of `mesh` seen by `cam`: the measured points in the world frame
/// (metres, z up) and the [`Part`] of the triangle each point was measured on.
///
/// Every cast pixel keeps its nearest hit (occlusion); depth noise, disparity
/// quantisation, grazing-angle dropouts and range limits follow [`Camera::noise`],
/// `min_range` and `max_range` (see the module documentation). Deterministic for `seed`.
pub fn render_view(mesh: &Mesh, cam: &Camera, seed: u64) -> (PointCloud, Vec<Part>) {
    let (cloud, tris) = render_view_triangles(mesh, cam, seed);
    let parts = tris.iter().map(|&t| mesh.parts[t]).collect();
    (cloud, parts)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A box whose front face (facing -x) is the plane x = 2, spanning y, z ∈ [-2, 2].
    fn wall_at_2() -> Mesh {
        let mut m = Mesh::new();
        m.add_box(
            Point3::new(2.0, -2.0, -2.0),
            Point3::new(2.5, 2.0, 2.0),
            Part::Other,
        );
        m
    }

    fn origin_cam() -> Camera {
        Camera {
            stride: 4,
            ..Camera::looking_at(Point3::origin(), Point3::new(1.0, 0.0, 0.0))
        }
    }

    #[test]
    fn ray_through_centre_is_the_axis_and_corners_span_the_fov() {
        let cam = Camera {
            width: 2,
            height: 2,
            hfov_deg: 90.0,
            vfov_deg: 90.0,
            ..origin_cam()
        };
        // Pixel (0, 0) is top left: direction (1, +y left, +z up) with |y| = |z| = 0.5.
        let d = cam.ray(0, 0);
        let e = Vector3::new(1.0, 0.5, 0.5).normalize();
        assert!((d - e).norm() < 1e-12, "{d}");
        let d = cam.ray(1, 1);
        let e = Vector3::new(1.0, -0.5, -0.5).normalize();
        assert!((d - e).norm() < 1e-12, "{d}");
    }

    #[test]
    fn camera_facing_a_wall_2_m_away_sees_x_near_2() {
        let cam = origin_cam();
        let (cloud, parts) = render_view(&wall_at_2(), &cam, 1);
        // 160 x 120 rays, all hitting the wall well inside the grazing limit.
        assert_eq!(cloud.len(), 160 * 120);
        assert_eq!(parts.len(), cloud.len());
        // σ(2 m) = 0.0012 + 0.0019·1.6² ≈ 6.1 mm, quantisation step ≈ 11 mm.
        let mean = cloud.points.iter().map(|p| p.x).sum::<f64>() / cloud.len() as f64;
        assert!((mean - 2.0).abs() < 0.003, "mean x {mean}");
        for p in &cloud.points {
            assert!((p.x - 2.0).abs() < 0.05, "{p}");
        }
        // Without noise every point is exactly on the plane.
        let clean = Camera {
            noise: SensorNoise::none(),
            ..cam
        };
        let (cloud, _) = render_view(&wall_at_2(), &clean, 1);
        assert!(cloud.points.iter().all(|p| (p.x - 2.0).abs() < 1e-9));
        // The view spans the field of view: y ∈ ±2·tan(28.5°) ≈ ±1.086.
        let ymax = cloud.points.iter().map(|p| p.y).fold(f64::MIN, f64::max);
        assert!(
            (ymax - 2.0 * 28.5f64.to_radians().tan()).abs() < 0.02,
            "{ymax}"
        );
    }

    #[test]
    fn mixed_pixels_lie_on_rays_between_an_edge_and_what_is_behind_it() {
        // A 0.4 m box 1.5 m in front of the wall at x = 2 fills the middle of the view.
        let mut m = wall_at_2();
        m.add_box(
            Point3::new(0.5, -0.2, -0.2),
            Point3::new(0.9, 0.2, 0.2),
            Part::Seat,
        );
        let clean = Camera {
            noise: SensorNoise::none(),
            ..origin_cam()
        };
        let mixing = Camera {
            noise: SensorNoise {
                mixed_pixels: 1.0,
                ..clean.noise
            },
            ..clean
        };
        let (plain, _) = render_view(&m, &clean, 3);
        let (mixed, parts) = render_view(&m, &mixing, 3);
        // The measured points come first and are unchanged; the mixed ones follow.
        assert_eq!(&mixed.points[..plain.len()], &plain.points[..]);
        let extra = &mixed.points[plain.len()..];
        assert!(!extra.is_empty(), "the box's outline is a depth edge");
        for p in extra {
            // Between the box's front face and the wall, on a ray through the front face
            // (the nearer pixel of the edge pair): |y| and |z| at most 0.2 / 0.5 of x. The
            // far end is the neighbour's range, taken along the nearer ray: the wall's
            // depth give or take the one pixel between the two rays.
            assert!(p.x > 0.5 - 1e-9 && p.x < 2.0 + 0.01, "{p}");
            assert!(p.y.abs().max(p.z.abs()) <= 0.4 * p.x + 1e-9, "{p}");
        }
        // Every edge pixel of the box's outline mixes with probability 1: about one per
        // outline pixel (a 0.4 m square at 0.5 m fills ~90 x 90 of the 160 x 120 rays).
        assert!((150..=800).contains(&extra.len()), "{}", extra.len());
        assert_eq!(parts.len(), mixed.len());
        // Seeded: the same view twice is the same points.
        assert_eq!(render_view(&m, &mixing, 3).0.points, mixed.points);
        // A plain wall has no edge: nothing is added.
        let (wall, _) = render_view(&wall_at_2(), &mixing, 3);
        assert_eq!(wall.len(), 160 * 120);
    }

    #[test]
    fn quantised_depths_lie_on_disparity_steps() {
        let cam = Camera {
            noise: SensorNoise {
                axial_a: 0.0,
                axial_b: 0.0,
                ..SensorNoise::default()
            },
            ..origin_cam()
        };
        let (cloud, _) = render_view(&wall_at_2(), &cam, 1);
        // z = 2 m: 1/(2.85e-3 · 2) = 175.4 → n = 175 → z = 2.00501 m.
        let want = 1.0 / (2.85e-3 * 175.0);
        assert!(cloud.points.iter().all(|p| (p.x - want).abs() < 1e-9));
    }

    #[test]
    fn a_box_behind_another_is_not_seen() {
        let mut m = Mesh::new();
        m.add_box(
            Point3::new(1.5, -0.2, -0.2),
            Point3::new(1.7, 0.2, 0.2),
            Part::Seat,
        );
        m.add_box(
            Point3::new(2.5, -0.1, -0.1),
            Point3::new(2.7, 0.1, 0.1),
            Part::Backrest,
        );
        let cam = Camera {
            noise: SensorNoise::none(),
            ..origin_cam()
        };
        let (cloud, parts) = render_view(&m, &cam, 3);
        assert!(!cloud.is_empty());
        assert!(parts.iter().all(|&p| p == Part::Seat));
        assert!(cloud.points.iter().all(|p| (p.x - 1.5).abs() < 1e-9));
        // Move the camera aside so it sees the far box too.
        let side = Camera {
            position: Point3::new(0.0, 2.0, 0.0),
            target: Point3::new(2.6, 0.0, 0.0),
            ..cam
        };
        let (_, parts) = render_view(&m, &side, 3);
        assert!(parts.contains(&Part::Backrest));
    }

    #[test]
    fn range_limits_and_grazing_dropouts() {
        // A floor seen from 0.3 m high far ahead: grazing everywhere beyond a few metres.
        let mut m = Mesh::new();
        m.add_horizontal_rect(-10.0, -10.0, 10.0, 10.0, 0.0, Part::Other);
        let cam = Camera {
            stride: 4,
            ..Camera::looking_at(Point3::new(0.0, 0.0, 0.3), Point3::new(5.0, 0.0, 0.0))
        };
        let (cloud, _) = render_view(&m, &cam, 5);
        assert!(!cloud.is_empty());
        let fwd = cam.basis().0;
        for p in &cloud.points {
            let z = (p - cam.position).dot(&fwd);
            assert!((0.5..=4.0).contains(&z), "{z}");
            // Angle to the normal > 85° means a ray slope < tan(5°) ≈ 0.087: beyond 3.4 m.
            let d = (p - cam.position).normalize();
            assert!(d.z.abs() > 5f64.to_radians().sin() - 0.01, "{p}");
        }
    }

    #[test]
    fn rendering_is_deterministic_per_seed() {
        let cam = origin_cam();
        let a = render_view(&wall_at_2(), &cam, 7);
        let b = render_view(&wall_at_2(), &cam, 7);
        let c = render_view(&wall_at_2(), &cam, 8);
        assert_eq!(a, b);
        assert_ne!(a.0, c.0);
    }

    #[test]
    fn bvh_matches_brute_force() {
        let mut m = Mesh::new();
        for i in 0..20 {
            let x = 1.0 + 0.1 * i as f64;
            let y = ((i * 7) % 11) as f64 * 0.1 - 0.5;
            m.add_cylinder(
                Point3::new(x, y, -0.5),
                Point3::new(x, y, 0.5),
                0.04,
                12,
                Part::Other,
            );
        }
        let bvh = Bvh::new(&m);
        let o = Point3::new(0.0, 0.1, 0.05);
        for k in 0..200 {
            let a = (k as f64 / 200.0 - 0.5) * 1.2;
            let dir = Vector3::new(a.cos(), a.sin(), 0.05).normalize();
            let brute = (0..m.len())
                .filter_map(|i| {
                    let [p, q, r] = m.triangle(i);
                    intersect(&o, &dir, &p, &q, &r)
                })
                .fold(f64::INFINITY, f64::min);
            let got = bvh.cast(&o, &dir).map_or(f64::INFINITY, |h| h.t);
            assert_eq!(got, brute, "ray {k}");
        }
    }
}
