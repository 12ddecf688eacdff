//! The scene the agent is fitted into (section 4.2): the point cloud voxelised into a
//! parry3d `Voxels` shape for exact collision tests, a Euclidean distance field over the
//! same voxels that bounds how far a body part is from anything (so exact tests are only
//! made where contact is near), and the floor, the half-space z <= 0 (paper section 3.1:
//! agent and scene share the ground plane).
//!
//! Memory follows the points and the region the agent reaches, not the bounding box: the
//! occupied voxels are kept as sorted rows, and the distance field is computed exactly but
//! lazily, chunk by chunk, where a body part first asks for it.
//!
//! World frame: metres, z up. Parry works in f32 in a local frame re-centred on the cloud.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::OnceLock;

use parry3d::bounding_volume::Aabb;

use nalgebra::{Point3, Vector3};
use parry3d::math::{ivect_to_vect, vect_to_ivect, IVector, Pose, Rotation, Vector};
use parry3d::shape::{Cylinder as ParryCylinder, Voxels};

use crate::cloud::PointCloud;
use crate::model::agent::Cylinder;
use crate::num::{floor_i64, index_f32, index_f64, slice_index_f32, to_f32, to_i64, to_usize};

/// How the scene is built.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneConfig {
    /// Voxel edge length, metres.
    pub voxel_size: f64,
    /// Whether the floor z <= 0 is solid even where the cloud has no floor points.
    pub floor: bool,
    /// Free border around the voxels over which the distance field is kept, metres.
    pub field_margin: f64,
}

/// Voxelised scene with a distance field and an optional solid floor.
#[derive(Debug)]
pub struct Scene {
    voxel: f64,
    /// World position of the local origin used for f32 geometry.
    origin: Vector3<f64>,
    /// Voxel edge (all three axes) in parry's f32, local frame.
    size: Vector,
    /// What parry's `Voxels::local_aabb` gives for these voxels (local frame): the union of
    /// its 8^3-voxel chunks; `None` without voxels.
    parry_aabb: Option<Aabb>,
    /// The same voxels as a parry3d `Voxels` shape, built only when
    /// [`Scene::intersects_parry`] asks for it: [`Scene::intersects`] needs only the
    /// numbers above, and building the shape is most of the scene's cost on a large floor.
    voxels: OnceLock<Option<Voxels>>,
    field: Option<DistanceField>,
    floor: bool,
    /// World bounds of the occupied voxels (cube extents included).
    occupied: Option<(Point3<f64>, Point3<f64>)>,
    count: usize,
}

/// Bytes the distance field of a scene spanning `extent` (metres along x, y, z, the
/// occupied voxels' span) takes at most while a body moves within a cube of edge `reach`
/// metres: a box of at most [`DENSE_CELLS`] has its first two passes computed in strips of
/// columns and its last pass in tiles of columns where asked (at most two f32 grids); a
/// larger one takes one
/// chunk slot per chunk of its box and the chunks covering that cube (an upper bound, in
/// f64 so any extent gives a number). Chunks beyond the cube are
/// computed only where bodies elsewhere ask for them (at most [`KEPT_CHUNKS`] kept).
pub fn field_bytes(extent: [f64; 3], cfg: &SceneConfig, reach: f64) -> f64 {
    let v = cfg.voxel_size;
    let margin = 2.0 * (cfg.field_margin / v).ceil();
    let dims = extent.map(|e| (e / v).floor() + 2.0 + margin);
    let cells: f64 = dims.iter().product();
    if cells <= DENSE_CELLS as f64 {
        // The first two passes' strips, and the last pass's tiles: at most a grid each.
        return cells * 2.0 * std::mem::size_of::<f32>() as f64;
    }
    let chunks: f64 = dims.iter().map(|d| (d / CHUNK as f64).ceil()).product();
    let around = ((reach / v / CHUNK as f64).ceil() + 1.0).powi(3);
    let chunk_bytes = (CHUNK_CELLS * std::mem::size_of::<f32>()) as f64;
    chunks * std::mem::size_of::<OnceLock<Box<[f32]>>>() as f64 + around * chunk_bytes
}

impl Scene {
    /// Voxelises `cloud` (world frame, metres).
    pub fn new(cloud: &PointCloud, cfg: &SceneConfig) -> Scene {
        let origin = origin_of(cloud.bounds(), cfg.voxel_size);
        Scene::of_keys(occupied_keys(cloud, origin, cfg.voxel_size), origin, cfg)
    }

    /// The scene of `cloud` and the points `more` together (world frame, metres), from
    /// `self`, the scene of `cloud` alone under the same `cfg`: the same scene as
    /// [`Scene::new`] of all the points. Where `more` leaves the local origin where it was
    /// (points inside the cloud's bounds, as the holes and hidden seats filled), their
    /// voxels are merged into `self`'s rather than every point's voxel found and sorted
    /// again; else the scene is built anew.
    pub fn with_points(
        &self,
        cloud: &PointCloud,
        more: Vec<Point3<f64>>,
        cfg: &SceneConfig,
    ) -> Scene {
        let v = cfg.voxel_size;
        let more = PointCloud::new(more);
        let all = match (cloud.bounds(), more.bounds()) {
            (Some((a, b)), Some((c, d))) => Some((a.inf(&c), b.sup(&d))),
            (a, c) => a.or(c),
        };
        let origin = origin_of(all, v);
        if origin != self.origin || v != self.voxel {
            let mut points = Vec::with_capacity(cloud.len() + more.len());
            points.extend_from_slice(&cloud.points);
            points.extend_from_slice(&more.points);
            return Scene::new(&PointCloud::new(points), cfg);
        }
        let added = occupied_keys(&more, origin, v);
        Scene::of_keys(merge_keys(&self.keys(), &added), origin, cfg)
    }

    /// The scene of the occupied voxel `keys` (sorted by [`zyx`], each once) of edge
    /// `cfg.voxel_size` from `origin` (world, metres).
    fn of_keys(keys: Vec<[i64; 3]>, origin: Vector3<f64>, cfg: &SceneConfig) -> Scene {
        let v = cfg.voxel_size;
        if keys.is_empty() {
            return Scene {
                voxel: v,
                origin,
                size: Vector::splat(to_f32(v)),
                parry_aabb: None,
                voxels: OnceLock::new(),
                field: None,
                floor: cfg.floor,
                occupied: None,
                count: 0,
            };
        }
        let mut lo = keys[0];
        let mut hi = keys[0];
        for k in &keys {
            for a in 0..3 {
                lo[a] = lo[a].min(k[a]);
                hi[a] = hi[a].max(k[a]);
            }
        }
        let size = Vector::splat(to_f32(v));
        let margin = to_i64((cfg.field_margin / v).ceil());
        let fmin = [lo[0] - margin, lo[1] - margin, lo[2] - margin];
        let dims = [0, 1, 2].map(|a| offset(hi[a] - lo[a] + 1 + 2 * margin));
        let field = DistanceField::new(fmin, dims, &keys, v);
        let world =
            |k: [i64; 3]| Point3::new(k[0] as f64 * v, k[1] as f64 * v, k[2] as f64 * v) + origin;
        let occupied = Some((world(lo), world([hi[0] + 1, hi[1] + 1, hi[2] + 1])));
        Scene {
            voxel: v,
            origin,
            size,
            parry_aabb: Some(parry_chunks_aabb(lo, hi, size)),
            voxels: OnceLock::new(),
            field: Some(field),
            floor: cfg.floor,
            occupied,
            count: keys.len(),
        }
    }

    /// The occupied voxels' keys, sorted by [`zyx`]: read back from the distance field's
    /// rows, which hold them in that order.
    fn keys(&self) -> Vec<[i64; 3]> {
        let Some(field) = &self.field else {
            return Vec::new();
        };
        let ny = field.dims[1] as u64;
        let mut keys = Vec::with_capacity(self.count);
        for (r, &id) in field.rows.iter().enumerate() {
            // Row ids are `z * ny + y` of the box, so both fit i64.
            let (y, z) = ((id % ny) as i64, (id / ny) as i64);
            for &x in &field.xs[field.row_start[r]..field.row_start[r + 1]] {
                keys.push([
                    field.min[0] + i64::from(x),
                    field.min[1] + y,
                    field.min[2] + z,
                ]);
            }
        }
        keys
    }

    /// Number of occupied voxels.
    pub fn voxel_count(&self) -> usize {
        self.count
    }

    /// Voxel edge length, metres.
    pub fn voxel_size(&self) -> f64 {
        self.voxel
    }

    /// A lower bound on the distance (metres) from point `p` (world) to the surface of any
    /// occupied voxel; may be negative when `p` is close to or inside one.
    pub fn point_clearance(&self, p: &Point3<f64>) -> f64 {
        let (Some(field), Some((lo, hi))) = (&self.field, &self.occupied) else {
            return f64::INFINITY;
        };
        let v = self.voxel;
        let half_diag = v * 3f64.sqrt() / 2.0;
        let l = (p.coords - self.origin) / v;
        let k = cell_of(&l);
        match field.get(k) {
            // Quantising p to its cell centre costs half a diagonal; the voxel's extent another.
            Some(d) => d as f64 - 2.0 * half_diag,
            None => {
                let dx = (lo.x - p.x).max(p.x - hi.x).max(0.0);
                let dy = (lo.y - p.y).max(p.y - hi.y).max(0.0);
                let dz = (lo.z - p.z).max(p.z - hi.z).max(0.0);
                (dx * dx + dy * dy + dz * dz).sqrt()
            }
        }
    }

    /// A lower bound on the gap (metres) between the body part `c` and the scene (voxels and
    /// floor); positive means certainly free, zero or negative means contact is possible.
    pub fn clearance(&self, c: &Cylinder) -> f64 {
        self.clearance_and_centres(c, &mut Vec::new()).0
    }

    /// [`Self::clearance`], and a lower bound on the distance (metres) from the axis of
    /// `c` to the centre of any occupied voxel (`f64::NEG_INFINITY` when some sampled cell
    /// is outside the field's box): each read sample's distance less its own offset from
    /// its cell's centre, the samples skipped bounded from the sample that skipped them.
    ///
    /// `read` keeps, per sample, the cell last read for it and its distance (a cell's
    /// distance never changes): a part that moved less than a cell since reads most of its
    /// cells from there. Reset when the number of samples changes.
    fn clearance_and_centres(&self, c: &Cylinder, read: &mut ReadCells) -> (f64, f64) {
        let floor = if self.floor {
            floor_gap(c)
        } else {
            f64::INFINITY
        };
        let Some(field) = &self.field else {
            return (floor, f64::INFINITY);
        };
        let axis = c.b - c.a;
        let len = axis.norm();
        let n = to_usize((len / self.voxel).ceil().max(1.0));
        let nf = index_f64(n);
        let spacing = len / nf;
        let point = |i: usize| c.a + axis * (index_f64(i) / nf);
        let mut best = f64::INFINITY;
        let mut centres = f64::NEG_INFINITY;
        if self.samples_in_field(c) {
            let v = self.voxel;
            let half_diag = v * 3f64.sqrt() / 2.0;
            if read.len() != n + 1 {
                read.clear();
                read.resize(n + 1, None);
            }
            // `point_clearance` of sample `i`, and a lower bound on its distance to any
            // occupied voxel centre.
            let mut sample = |i: usize| {
                let p = point(i);
                let l = (p.coords - self.origin) / v;
                // The cell read last for this sample when the sample is still in it
                // (its corner `lo` at most `l` and `l` under `lo + 1` along every axis:
                // then `cell_of(&l)` is that cell), else the field's distance at the
                // sample's cell (kept for the next time).
                let got = match read.get_mut(i) {
                    Some(Some(r)) if r.holds(&l) => Some((r.lo, r.d)),
                    slot => {
                        let k = cell_of(&l);
                        field.get(k).map(|d| {
                            if let Some(slot) = slot {
                                *slot = Some(ReadCell::new(k, d));
                            }
                            (k.map(|k| k as f64), d)
                        })
                    }
                };
                match got {
                    Some((lo, d)) => {
                        let centre = Vector3::new(lo[0] + 0.5, lo[1] + 0.5, lo[2] + 0.5);
                        let d = d as f64;
                        (d - 2.0 * half_diag, d - (l - centre).norm() * v)
                    }
                    // Not reached (every sampled cell is in the box); the distance to
                    // the occupied box bounds both.
                    None => {
                        let b = self.point_clearance(&p);
                        (b, b)
                    }
                }
            };
            // Both ends first, then the samples between, skipping those the field's
            // Lipschitz bound shows to be no nearer than the least found: sample `k`
            // reads a cell within `|k - i| spacing` plus two half diagonals of sample
            // `i`'s, so its value is at least `i`'s less that. The least is the same.
            let ((b0, c0), (bn, cn)) = (sample(0), sample(n));
            best = b0.min(bn);
            let mut near = c0.min(cn);
            let mut i = 1;
            while i < n {
                let (here, centre) = sample(i);
                best = best.min(here);
                near = near.min(centre);
                let room = here
                    - best
                    - 2.0 * half_diag
                    - BOUND_SLACK * (1.0 + here.abs() + best.abs() + len);
                let skip = if room > 0.0 && spacing > 0.0 {
                    to_usize((room / spacing).floor()).min(n)
                } else {
                    0
                };
                if skip > 0 {
                    // Distances to centres are 1-Lipschitz along the axis.
                    near = near.min(centre - index_f64(skip) * spacing);
                }
                i += 1 + skip;
            }
            // Every axis point is within half a spacing of a sample.
            centres = near - spacing / 2.0 - BOUND_SLACK * (1.0 + near.abs() + len);
        } else {
            for i in 0..=n {
                best = best.min(self.point_clearance(&point(i)));
            }
        }
        ((best - spacing / 2.0 - c.radius).min(floor), centres)
    }

    /// Whether every cell [`Self::clearance`] samples along `c` is in the field's box.
    fn samples_in_field(&self, c: &Cylinder) -> bool {
        self.field.as_ref().is_some_and(|f| {
            let v = self.voxel;
            let cell = |p: &Point3<f64>| cell_of(&((p.coords - self.origin) / v));
            f.holds_segment(cell(&c.a), cell(&c.b))
        })
    }

    /// A lower bound on [`Self::clearance`]`(c)` from one read of the distance field, at
    /// the cell of the axis midpoint: every cell the clearance samples is within `R + h` of
    /// that cell's centre (`R` the farther axis end from it, `h` half a cell diagonal), and
    /// the field is 1-Lipschitz between cell centres, so each sampled distance is at least
    /// the midpoint's less `R + h`; the sample spacing is at most one voxel. `None` when
    /// some sampled cell may lie outside the field's box (there the clearance is the
    /// distance to the occupied box, which the field does not bound) or without a field.
    ///
    /// With `last`, the clearance `g` computed for the same part at another pose with
    /// every sampled cell in the box, and how far (metres) no point of it has moved since,
    /// the bound [`carried_bound`] gives is taken as well (the larger of the two), and
    /// alone, with no read, when it is positive.
    fn clearance_bound(&self, c: &Cylinder, last: Option<(f64, f64)>) -> Option<f64> {
        let field = self.field.as_ref()?;
        let v = self.voxel;
        let (la, lb) = (
            (c.a.coords - self.origin) / v,
            (c.b.coords - self.origin) / v,
        );
        if !field.holds_segment(cell_of(&la), cell_of(&lb)) {
            return None;
        }
        let carried = last.map(|(g, moved)| carried_bound(c, g, moved, v));
        if let Some(b) = carried.filter(|&b| b > 0.0) {
            return Some(b);
        }
        let km = cell_of(&((la + lb) / 2.0));
        let d = f64::from(field.get(km)?);
        let centre = Vector3::new(km[0] as f64 + 0.5, km[1] as f64 + 0.5, km[2] as f64 + 0.5);
        let reach = (la - centre)
            .norm_squared()
            .max((lb - centre).norm_squared())
            .sqrt()
            * v;
        let half_diag = v * 3f64.sqrt() / 2.0;
        // The sampled cell's centre is within half a diagonal of its sample (one), the
        // clearance takes two more off the field (quantising and the voxel's extent).
        let bound = d
            - reach
            - 3.0 * half_diag
            - v / 2.0
            - c.radius
            - BOUND_SLACK * (1.0 + d.abs() + reach);
        let floor = if self.floor {
            floor_gap(c)
        } else {
            f64::INFINITY
        };
        let read = bound.min(floor);
        // `max` takes the other when one is NaN.
        Some(carried.map_or(read, |b| read.max(b)))
    }

    /// Exact test: does the body part `c` intersect an occupied voxel or the floor?
    ///
    /// The answer is parry3d's `intersection_test` of a cylinder against the `Voxels`
    /// shape, which tests every occupied voxel in the cylinder's bounding box with GJK.
    /// The same voxels are visited here (found in the sorted rows of occupied cells), but
    /// voxels whose centre lies deep inside the cylinder, or
    /// whose bounding sphere is clear of the cylinder's capsule, are decided by
    /// geometry with a margin of [`DECIDE_MARGIN`]; only the voxels between are handed
    /// to parry's GJK, with the poses parry itself would use.
    pub fn intersects(&self, c: &Cylinder) -> bool {
        self.intersects_near(c, f64::NEG_INFINITY, None)
    }

    /// [`Self::intersects`] given `centres`, a lower bound on the distance (metres) from
    /// the axis of `c` to any occupied voxel centre ([`Self::clearance_and_centres`]):
    /// when it exceeds the radius, half a voxel diagonal and [`DECIDE_MARGIN`], every
    /// voxel is one the walk would find clear (false at once); when it exceeds half a
    /// diagonal, no axis point lies in an occupied voxel (the look for one is skipped).
    /// Both with [`F32_SLACK`] for the `f32` geometry the walk classifies with. With
    /// `near`, the voxels are taken from it (filled anew when it does not cover the
    /// cylinder's voxel range): the same voxels, so the same answer.
    fn intersects_near(&self, c: &Cylinder, centres: f64, near: Option<&mut NearVoxels>) -> bool {
        if self.floor && floor_gap(c) < 0.0 {
            return true;
        }
        let (Some(local_aabb), Some(field)) = (&self.parry_aabb, &self.field) else {
            return false;
        };
        let axis = c.b - c.a;
        let len = axis.norm();
        let extent = (c.a.coords - self.origin)
            .amax()
            .max((c.b.coords - self.origin).amax());
        let half_diag = self.voxel * 3f64.sqrt() / 2.0 + F32_SLACK * (1.0 + extent + len);
        if centres > c.radius + half_diag + DECIDE_MARGIN {
            return false;
        }
        let Some((pose, shape)) = self.parry_cylinder(c) else {
            return false;
        };
        // Certainly touching: an axis point, away from the ends and the surface by the
        // margin, lies in an occupied voxel (the cylinder holds a ball around it).
        if centres <= half_diag && c.radius > DECIDE_MARGIN && len > 2.0 * DECIDE_MARGIN {
            let n = to_usize((len / self.voxel).ceil());
            let inner = len - 2.0 * DECIDE_MARGIN;
            for i in 0..=n {
                let p = c.a + axis * ((DECIDE_MARGIN + inner * i as f64 / n as f64) / len);
                if field.occupied(cell_of(&((p.coords - self.origin) / self.voxel))) {
                    return true;
                }
            }
        }
        use parry3d::query::QueryDispatcher;
        // As parry's `intersection_test` and `intersection_test_voxels_shape` compute them.
        let pos12 = Pose::IDENTITY.inv_mul(&pose);
        let Some(aabb) = local_aabb.intersection(&cylinder_aabb(&shape, &pos12)) else {
            return false;
        };
        // `Voxels::voxel_range_intersecting_local_aabb`.
        let mins = vect_to_ivect((aabb.mins / self.size).floor());
        let maxs = vect_to_ivect((aabb.maxs / self.size).ceil());
        let lo = [mins.x as i64, mins.y as i64, mins.z as i64];
        let hi = [maxs.x as i64, maxs.y as i64, maxs.z as i64];
        let t = pos12.translation;
        let u = pos12.rotation * Vector::Y;
        let (t, u) = (
            Vector3::new(t.x as f64, t.y as f64, t.z as f64),
            Vector3::new(u.x as f64, u.y as f64, u.z as f64),
        );
        let (hh, r) = (shape.half_height as f64, shape.radius as f64);
        let size = self.size;
        let half_diag = (size.x as f64).hypot(size.y as f64).hypot(size.z as f64) / 2.0;
        let centre = |k: [i64; 3]| voxel_centre(k, size);
        // Where the voxel centred at `p` stands against the cylinder.
        let clear2 = (r + half_diag + DECIDE_MARGIN).powi(2);
        let inside2 = (r - DECIDE_MARGIN).max(0.0).powi(2);
        let classify = |p: Vector| {
            let w = Vector3::new(p.x as f64, p.y as f64, p.z as f64) - t;
            let along = w.dot(&u);
            let perp2 = w.norm_squared() - along * along;
            let beyond = (along.abs() - hh).max(0.0);
            if perp2 + beyond * beyond > clear2 {
                Side::Clear
            } else if along.abs() < hh - DECIDE_MARGIN && perp2 < inside2 {
                Side::Inside
            } else {
                Side::Boundary
            }
        };
        let cuboid = parry3d::shape::Cuboid::new(size / 2.0);
        let touches = |p: Vector| match classify(p) {
            Side::Inside => true,
            Side::Clear => false,
            Side::Boundary => {
                let pose12 = Pose::from_translation(-p) * pos12;
                parry3d::query::DefaultQueryDispatcher
                    .intersection_test(&pose12, &cuboid, &shape)
                    .is_ok_and(|r| r.intersecting)
            }
        };
        match near {
            Some(near) => near.any(field, lo, hi, size, touches),
            None => field.any_occupied(lo, hi, |k| touches(centre(k))),
        }
    }

    /// Whether the body part `c` touches the scene: [`Self::clearance`] first (cheap, and
    /// positive for most parts), then the exact [`Self::intersects`].
    pub fn touches(&self, c: &Cylinder) -> bool {
        self.clearance(c) <= 0.0 && self.intersects(c)
    }

    /// The same test made by parry3d alone (`intersection_test` of the cylinder against
    /// the whole `Voxels` shape): the reference [`Scene::intersects`] must agree with.
    pub fn intersects_parry(&self, c: &Cylinder) -> bool {
        if self.floor && floor_gap(c) < 0.0 {
            return true;
        }
        let Some(voxels) = self.parry_voxels() else {
            return false;
        };
        let Some((pose, shape)) = self.parry_cylinder(c) else {
            return false;
        };
        parry3d::query::intersection_test(&Pose::IDENTITY, voxels, &pose, &shape)
            .map(|r| r.intersecting)
            .unwrap_or(false)
    }

    /// The occupied voxels as a parry3d `Voxels` shape (local frame), built on first use
    /// from the distance field's rows; `None` without voxels.
    fn parry_voxels(&self) -> Option<&Voxels> {
        self.voxels
            .get_or_init(|| {
                let field = self.field.as_ref()?;
                let mut keys = Vec::with_capacity(self.count);
                field.any_occupied(
                    field.min,
                    [0, 1, 2].map(|a| field.min[a] + field.dims[a] as i64),
                    |k| {
                        keys.push(ivector(k));
                        false
                    },
                );
                Some(Voxels::new(self.size, &keys))
            })
            .as_ref()
    }

    /// The body part as a parry cylinder and its pose in the local (f32) frame; `None` for
    /// a part of no length.
    fn parry_cylinder(&self, c: &Cylinder) -> Option<(Pose, ParryCylinder)> {
        let axis = c.b - c.a;
        let len = axis.norm();
        if len < 1e-9 {
            return None;
        }
        let mid = nalgebra::center(&c.a, &c.b).coords - self.origin;
        let dir = axis / len;
        let rot = Rotation::from_rotation_arc(
            Vector::Y,
            Vector::new(to_f32(dir.x), to_f32(dir.y), to_f32(dir.z)),
        );
        let pose = Pose::from_parts(
            Vector::new(to_f32(mid.x), to_f32(mid.y), to_f32(mid.z)),
            rot,
        );
        Some((
            pose,
            ParryCylinder::new(to_f32(len / 2.0), to_f32(c.radius)),
        ))
    }

    /// The direction (unit, world) in which the scene falls away from the body part `c` where
    /// it comes closest to it: the gradient of the distance field at the axis point nearest
    /// to an occupied voxel. For a forearm lying on an armrest it points up; for one
    /// touching a wall beside it, sideways. `None` with no voxels nearby (or only the floor,
    /// whose normal is +z).
    pub fn contact_normal(&self, c: &Cylinder) -> Option<Vector3<f64>> {
        self.contact(c).map(|(_, n)| n)
    }

    /// Where body part `c` comes closest to the scene and the direction in which the scene
    /// falls away from it there ([`Self::contact_normal`]): the axis point (world, at voxel
    /// steps along the axis) whose distance-field cell is nearest to an occupied voxel,
    /// with the field's gradient there; next to the floor, the part's lower end and +z.
    pub fn contact(&self, c: &Cylinder) -> Option<(Point3<f64>, Vector3<f64>)> {
        if self.floor && floor_gap(c) <= self.voxel {
            let low = if c.a.z <= c.b.z { c.a } else { c.b };
            return Some((low, Vector3::z()));
        }
        let field = self.field.as_ref()?;
        let v = self.voxel;
        let key = |p: &Point3<f64>| {
            let l = (p.coords - self.origin) / v;
            cell_of(&l)
        };
        let axis = c.b - c.a;
        let n = to_usize((axis.norm() / v).ceil()).max(1);
        let (mut best, mut at) = (f32::INFINITY, None);
        for i in 0..=n {
            let p = c.a + axis * (i as f64 / n as f64);
            if let Some(d) = field.get(key(&p)) {
                if d < best {
                    best = d;
                    at = Some((p, key(&p)));
                }
            }
        }
        let (p, k) = at?;
        let g = |a: usize| {
            let (mut lo, mut hi) = (k, k);
            lo[a] -= 2;
            hi[a] += 2;
            match (field.get(lo), field.get(hi)) {
                (Some(l), Some(h)) if l.is_finite() && h.is_finite() => (h - l) as f64,
                _ => 0.0,
            }
        };
        let grad = Vector3::new(g(0), g(1), g(2));
        (grad.norm() > 1e-9).then(|| (p, grad.normalize()))
    }

    /// How far (metres) the scene lies straight below `p`: the drop to the first occupied
    /// voxel or the floor, or `f64::INFINITY` when there is nothing below within `max`.
    pub fn drop_below(&self, p: &Point3<f64>, max: f64) -> f64 {
        let floor = if self.floor { p.z } else { f64::INFINITY };
        let mut q = *p;
        // March down by the clearance bound (never less than half a voxel).
        while p.z - q.z <= max.min(floor) {
            let clearance = self.point_clearance(&q);
            if clearance <= self.voxel / 2.0 {
                return p.z - q.z;
            }
            q.z -= clearance;
        }
        if floor <= max {
            floor
        } else {
            f64::INFINITY
        }
    }

    /// Whether the surface at the height of a seat goes on beyond what stands on it: a
    /// level walk from `from` along the unit direction `dir`, in steps of one voxel up to
    /// `limit` metres, looks down from each probe to the first surface within reach of
    /// `level - gap` ([`Self::drop_below`]). While that surface lies above `level` the walk
    /// is over what stands up (a back, an arm, a pillow, or `from` itself inside it). Past
    /// it, true once a surface has lain within `gap` below `level` under consecutive
    /// probes over `length` metres (the mattress beyond a pillow, the top of a night stand
    /// beyond its lamp); false at the first probe with nothing there where the scan saw
    /// something lower in its column (the floor far below a chair's back or a sofa's arm).
    /// A column seen nowhere (the shadow a pillow casts on a mattress, the space behind a
    /// wall) is stepped over: what the scan saw beyond it decides, and past a shadow a
    /// column counts as at the seat's level only where nothing seen in it stands above
    /// `level` ([`Self::top_at_most`]: a wall's foot seen under the shadow a chair's back
    /// casts on it is no seat). A stretch shorter than `length` (the seat seen through the
    /// gaps of a slatted back) ends where something stands up again, and the walk goes
    /// on. False when the walk meets nothing above `level`, or reaches `limit`. `level` is
    /// the seat's level `seat` raised by `rise` (metres): a mattress beyond a pillow that a
    /// duvet's lumps lift a little above the pelvis of a body sunk into it is at it; the
    /// band below reaches `gap` under `seat`.
    pub fn goes_on_beyond(
        &self,
        from: &Point3<f64>,
        dir: &Vector3<f64>,
        limit: f64,
        (seat, gap, rise): (f64, f64, f64),
        length: f64,
    ) -> bool {
        let bottom = seat - gap;
        // A surface up to `rise` above the seat's level is at it: a duvet's lumps round a
        // body sunk into a mattress.
        let level = seat + rise;
        let mut over = false;
        // Whether the walk has stepped over a shadow since it was over something.
        let mut shadowed = false;
        // Where the current stretch at the seat's level began, metres along the walk.
        let mut stretch: Option<f64> = None;
        let mut s = 0.0;
        while s <= limit {
            let q = from + dir * s;
            let depth = q.z - bottom;
            if depth <= 0.0 {
                return false;
            }
            let d = self.drop_below(&q, depth);
            // Past a shadow, a column with something seen above `level` (a wall whose
            // foot the scan saw) stands up too.
            let stands =
                q.z - d > level || (shadowed && d.is_finite() && !self.top_at_most(&q, level));
            if stands {
                over = true;
                stretch = None;
            } else if over {
                if d.is_finite() {
                    let start = *stretch.get_or_insert(s);
                    if s - start >= length {
                        return true;
                    }
                } else if self.sees_below(&Point3::new(q.x, q.y, bottom), self.voxel / 2.0) {
                    return false;
                } else {
                    shadowed = true;
                    stretch = None;
                }
            }
            s += self.voxel;
        }
        false
    }

    /// Whether a surface under a level walk ends: from `from` along the unit direction
    /// `dir`, in steps of one voxel up to `limit` metres, some probe has no scene within
    /// `gap` metres below it ([`Self::drop_below`]). Space the scan did not see ends it.
    /// The `narrow` rule of a node walks this way (what an arm stands on ends within an
    /// arm's width); `rear` steps over unseen space ([`Self::seat_ends`]).
    pub fn surface_ends(
        &self,
        from: &Point3<f64>,
        dir: &Vector3<f64>,
        limit: f64,
        gap: f64,
    ) -> bool {
        self.walk_ends(from, dir, limit, gap, false)
    }

    /// Whether the surface sat on ends under a level walk, as [`Self::surface_ends`], but
    /// stepping over space the scan did not see: a probe with no scene within `gap` below
    /// ends it only where the scan saw something lower in its column (the floor in front
    /// of a seat's edge, the side of a bed: [`Self::sees_below`] from the bottom of the
    /// band); a column seen nowhere (the shadow a pillow or a fold casts on a mattress
    /// from the camera's side) is stepped over. Where the walk's last probes are in such a
    /// shadow, it looks on past `limit`, over columns with something seen above the walk
    /// ([`Self::top_at_most`]: a bag on the mattress, a wall), to the first other column
    /// the scan saw something in: the surface goes on where that column holds it within
    /// `gap` (the mattress beyond the shadow of a pillow or a bag), and ends where it holds
    /// only something lower (the floor), or where the scene's box ends first. The `rear`
    /// rule of a node walks this way: a mattress goes on in front of a headboard through
    /// the shadows on it.
    pub fn seat_ends(&self, from: &Point3<f64>, dir: &Vector3<f64>, limit: f64, gap: f64) -> bool {
        self.walk_ends(from, dir, limit, gap, true)
    }

    /// The walk of [`Self::surface_ends`] (`over_unseen` false) and [`Self::seat_ends`]
    /// (true): true at the first probe with nothing within `gap` below, unless
    /// `over_unseen` and the scan saw nothing lower in its column either; at the end of
    /// the walk, false unless its last probe was such an unseen one, and then what the
    /// scan saw past it decides (see [`Self::seat_ends`]).
    fn walk_ends(
        &self,
        from: &Point3<f64>,
        dir: &Vector3<f64>,
        limit: f64,
        gap: f64,
        over_unseen: bool,
    ) -> bool {
        let step = self.voxel;
        let mut s = step;
        let mut unseen = false;
        while s <= limit {
            let q = from + dir * s;
            unseen = self.drop_below(&q, gap) > gap;
            if unseen
                && (!over_unseen || self.sees_below(&Point3::new(q.x, q.y, q.z - gap), step / 2.0))
            {
                return true;
            }
            s += step;
        }
        // Unseen at the end only with `over_unseen`: `surface_ends` returned at it.
        if !unseen {
            return false;
        }
        // The walk ends in a shadow: what the scan saw past it decides. The surface goes
        // on where a column with nothing seen above the walk holds it within `gap` (the
        // mattress beyond a pillow's shadow), and ends where such a column holds only
        // something lower (the floor) or nothing is seen before the scene's box ends. A
        // column with something seen above the walk (a bag on the mattress, a wall whose
        // foot was seen) says neither, and the look goes on past it.
        let Some((lo, hi)) = self.occupied else {
            return true;
        };
        loop {
            let q = from + dir * s;
            if q.x < lo.x || q.y < lo.y || q.x > hi.x || q.y > hi.y {
                return true;
            }
            if self.top_at_most(&q, q.z) {
                if self.drop_below(&q, gap) <= gap {
                    return false;
                }
                if self.sees_below(&Point3::new(q.x, q.y, q.z - gap), step / 2.0) {
                    return true;
                }
            }
            s += step;
        }
    }

    /// Whether nothing the scan saw in the vertical column through `p` lies above `level`
    /// metres: the column's top is a surface at or below `level`, or nothing was seen in
    /// it. A wall or the back of a chair standing in the column has its top above.
    pub fn top_at_most(&self, p: &Point3<f64>, level: f64) -> bool {
        let Some((_, hi)) = self.occupied else {
            return true;
        };
        let top = Point3::new(p.x, p.y, hi.z + self.voxel);
        top.z - self.drop_below(&top, top.z - level) <= level
    }

    /// Whether the scan saw anything in the column below `p`: some voxel within `reach`
    /// metres of the vertical line from `p` down to the lowest voxel of the scene. The
    /// floor plane the scene assumes does not count: it is not seen. Marches down by the
    /// clearance bound, at least half a voxel per step.
    pub fn sees_below(&self, p: &Point3<f64>, reach: f64) -> bool {
        let Some((lo, _)) = self.occupied else {
            return false;
        };
        let mut q = *p;
        while q.z >= lo.z - reach {
            let c = self.point_clearance(&q);
            if c <= reach {
                return true;
            }
            // Every point of the line within c - reach below q is further than `reach`
            // from any voxel.
            q.z -= (c - reach).max(self.voxel / 2.0);
        }
        false
    }

    /// Distance (metres, >= 0) from the surface of a body part of radius `radius` whose axis
    /// passes through `p` to the nearest voxel or the floor: the d_i of Eq. 1.
    pub fn surface_distance(&self, p: &Point3<f64>, radius: f64) -> f64 {
        let floor = if self.floor {
            p.z - radius
        } else {
            f64::INFINITY
        };
        // The field holds centre distances: take back the quantisation slack for a
        // central estimate, and the half voxel to reach the voxel's face.
        let d = match (&self.field, self.occupied) {
            (Some(f), Some(_)) => {
                let l = (p.coords - self.origin) / self.voxel;
                match f.get(cell_of(&l)) {
                    Some(d) => d as f64 - self.voxel / 2.0 - radius,
                    None => self.point_clearance(p) - radius,
                }
            }
            _ => f64::INFINITY,
        };
        d.min(floor).max(0.0)
    }
}

impl Scene {
    /// The first parameter `t` in [0, 1] at which a moving set of body parts touches the
    /// scene, or `None` if it stays free. `motion(t, out)` writes the posed parts at `t`,
    /// the same parts in the same order at every `t`; `speed` bounds how far (metres) any
    /// point of them moves per unit of `t`; contact is located to within `resolution`
    /// metres of motion.
    ///
    /// Free space is crossed in steps as long as the distance field's clearance allows
    /// (conservative advancement); exact parry3d tests are made only for parts whose
    /// clearance bound is not positive, and the contact is refined by bisection.
    pub fn first_contact(
        &self,
        motion: impl FnMut(f64, &mut Vec<Cylinder>),
        speed: f64,
        resolution: f64,
    ) -> Option<f64> {
        self.first_contact_turning(motion, speed, None, resolution)
    }

    /// [`Self::first_contact`] for a motion that, with `turn` = `(pivot, rate)`, turns
    /// every part about one axis through `pivot` (world frame, metres; fixed during the
    /// motion) by at most `rate` radians per unit of `t`, so that a point moves at most
    /// `rate` times its distance from `pivot` (and `speed` bounds the fastest). Where a
    /// part's clearance allows no step, each point along it then steps by its own
    /// clearance, or `resolution`, at its own speed ([`Self::turn_bound`]): a part that
    /// lies near a surface at its pivot end (a trunk lowered onto a mattress about the
    /// hip, a shank swinging down past a seat's front edge) is not held to steps of
    /// `resolution` at the speed of its far end. Every point still moves at most the larger
    /// of its clearance and `resolution` per step.
    pub fn first_contact_turning(
        &self,
        mut motion: impl FnMut(f64, &mut Vec<Cylinder>),
        speed: f64,
        turn: Option<(Point3<f64>, f64)>,
        resolution: f64,
    ) -> Option<f64> {
        let mut parts = Vec::new();
        // Each part's bound on its clearance, ascending, with its index.
        let mut order: Vec<(f64, usize)> = Vec::new();
        // Each part's voxels near it and the cells its clearance read, kept from step to
        // step.
        let mut near: Vec<NearVoxels> = Vec::new();
        let mut read: Vec<ReadCells> = Vec::new();
        // Per part, whether every cell its clearance samples is in the field's box at
        // this `t` (known when its bound was read), and the clearance last computed for
        // it while they were, with that `t`.
        let mut in_field: Vec<bool> = Vec::new();
        let mut last: Vec<Option<(f64, f64)>> = Vec::new();
        let mut touching = |t: f64, parts: &mut Vec<Cylinder>| -> (bool, f64) {
            motion(t, parts);
            near.resize_with(parts.len(), NearVoxels::default);
            read.resize_with(parts.len(), Vec::new);
            if last.len() != parts.len() {
                last.clear();
                last.resize(parts.len(), None);
            }
            in_field.clear();
            order.clear();
            // A lone part is visited whatever its bound: no read for it.
            let lone = parts.len() == 1;
            for (i, c) in parts.iter().enumerate() {
                // `speed` bounds the motion; its size, should a caller pass it negative.
                let moved = |(g, at): (f64, f64)| (g, (speed * (t - at)).abs());
                let b = (!lone)
                    .then(|| self.clearance_bound(c, last[i].map(moved)))
                    .flatten();
                in_field.push(b.is_some());
                let b = b.filter(|b| !b.is_nan());
                order.push((b.unwrap_or(f64::NEG_INFINITY), i));
            }
            order.sort_unstable_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)));
            let mut gap = f64::INFINITY;
            let mut hit = false;
            for &(bound, i) in order.iter() {
                // This part and all after it have a positive clearance, so none touches;
                // none lowers the gap if their bounds are no smaller than it, and when
                // the gap is at most `resolution` its value no longer matters (`advance`
                // steps by `resolution` for any gap up to it). So the answer is the same
                // as testing every part: whether any touches, else the least clearance
                // (or, like it, a gap of at most `resolution`).
                if bound > 0.0 && (bound >= gap || gap <= resolution) {
                    break;
                }
                let c = &parts[i];
                let (g, centres) = self.clearance_and_centres(c, &mut read[i]);
                if in_field[i] {
                    last[i] = Some((g, t));
                }
                let mut part_gap = g;
                if g <= 0.0 {
                    if self.intersects_near(c, centres, Some(&mut near[i])) {
                        // The gap is not used once a part touches: the rest need no test.
                        hit = true;
                        break;
                    }
                    // Free: how long it may turn, as the distance the fastest point
                    // covers in that time; worth it for a part whose near end turns at
                    // under half the fastest speed ([`TURN_LEVER`]).
                    if let Some((pivot, rate)) = &turn {
                        let near_end = (c.a - pivot).norm().min((c.b - pivot).norm()) + c.radius;
                        if rate * near_end < TURN_LEVER * speed {
                            let least = resolution / speed;
                            part_gap =
                                g.max(self.turn_bound(c, pivot, *rate, resolution, least) * speed);
                        }
                    }
                }
                gap = gap.min(part_gap);
            }
            (hit, gap)
        };
        advance(|t| touching(t, &mut parts), speed, resolution)
    }

    /// A lower bound on how long (in units of a motion's parameter) the body part `c` may
    /// turn about an axis through `pivot` (world frame) at `rate` radians per unit before
    /// some point of it has moved further than the larger of its own clearance and
    /// `resolution` (metres): over samples at most a voxel apart along the axis, each
    /// sample's clearance (the field's bound at it, and its height above the floor, less
    /// half the spacing and the radius), or `resolution` where that is larger, over the
    /// speed of the points near it (`rate` times its distance from `pivot` plus half the
    /// spacing and the radius). Every point of the part is within half a spacing and the
    /// radius of a sample. The samples are read from the end farther from `pivot`, and
    /// the reading stops once the bound is at most `enough` (the step the search takes
    /// anyway), which is then returned.
    fn turn_bound(
        &self,
        c: &Cylinder,
        pivot: &Point3<f64>,
        rate: f64,
        resolution: f64,
        enough: f64,
    ) -> f64 {
        let axis = c.b - c.a;
        let len = axis.norm();
        let n = to_usize((len / self.voxel).ceil().max(1.0));
        let nf = index_f64(n);
        let spacing = len / nf;
        let from_b = (c.b - pivot).norm() > (c.a - pivot).norm();
        let mut least = f64::INFINITY;
        for k in 0..=n {
            let i = if from_b { n - k } else { k };
            let q = c.a + axis * (index_f64(i) / nf);
            let mut clear = self.point_clearance(&q);
            if self.floor {
                clear = clear.min(q.z);
            }
            let clear = clear - spacing / 2.0 - c.radius;
            let clear = clear - BOUND_SLACK * (1.0 + clear.abs() + len);
            let lever = (q - pivot).norm() + spacing / 2.0 + c.radius;
            least = least.min(clear.max(resolution) / (rate * lever));
            if least <= enough {
                return enough;
            }
        }
        least
    }
}

/// Per sample along a body part's axis, the cell [`Scene::clearance`] last read for it,
/// if any.
type ReadCells = Vec<Option<ReadCell>>;

/// A cell of the distance field a clearance sample read: its low corner in voxel units
/// (local frame) and its distance (metres).
#[derive(Debug, Clone, Copy)]
struct ReadCell {
    /// The grid key as `f64` (exact, as `k as f64` is for keys under 2^52 in size); NaN
    /// for a larger key, so that [`Self::holds`] never answers for it.
    lo: [f64; 3],
    d: f32,
}

impl ReadCell {
    /// The cell of grid key `k`, whose distance is `d`.
    fn new(k: [i64; 3], d: f32) -> ReadCell {
        const EXACT: i64 = 1 << 52;
        ReadCell {
            lo: k.map(|k| {
                if (-EXACT..EXACT).contains(&k) {
                    k as f64
                } else {
                    f64::NAN
                }
            }),
            d,
        }
    }

    /// Whether the position `l` (voxel units, local frame) lies in this cell, so that
    /// `cell_of(l)` is its key: `lo <= l < lo + 1` along every axis, both bounds exact
    /// integers below 2^52 (a NaN corner or position holds nothing).
    fn holds(&self, l: &Vector3<f64>) -> bool {
        (0..3).all(|a| self.lo[a] <= l[a] && l[a] < self.lo[a] + 1.0)
    }
}

/// A lower bound on the clearance ([`Scene::clearance`]) of the body part `c` (voxel edge
/// `v` metres), given that the part's clearance was `g` at another pose from which no
/// point of it has moved more than `moved` metres, and that every sampled cell lies in
/// the field's box at both poses.
///
/// Each sample now lies within `moved` of the point of the axis at the same fraction
/// then, which lies within half a sample spacing of a sample then; distances to occupied
/// voxel centres are 1-Lipschitz, and a cell's stored distance is within half a cell
/// diagonal `h` of the distance at any point of the cell, so the least sampled distance
/// is at least the least then less `moved`, half the old spacing and `2 h`; the clearance
/// takes off half the new spacing (at most `v / 2`) where the old clearance took off half
/// the old one. The floor's gap is 1-Lipschitz in the motion. [`BOUND_SLACK`] covers the
/// `f32` rounding of the stored distances, as in [`Scene::clearance_bound`].
fn carried_bound(c: &Cylinder, g: f64, moved: f64, v: f64) -> f64 {
    let half_diag = v * 3f64.sqrt() / 2.0;
    let len = (c.b - c.a).norm();
    g - moved - 2.0 * half_diag - v / 2.0 - BOUND_SLACK * (1.0 + g.abs() + moved + len + c.radius)
}

/// Conservative advancement and bisection: the first `t` in [0, 1] at which `touching(t)`
/// (whether the motion touches at `t`, and otherwise a lower bound on its gap, metres)
/// says it touches, steps of `gap / speed` (at least `resolution / speed`) through free
/// space and bisection to `resolution / 4` of motion; `None` if it never touches.
fn advance(
    mut touching: impl FnMut(f64) -> (bool, f64),
    speed: f64,
    resolution: f64,
) -> Option<f64> {
    let min_step = if speed > 0.0 { resolution / speed } else { 1.0 };
    let (mut free, mut t) = (None::<f64>, 0.0f64);
    loop {
        let (hit, gap) = touching(t);
        if hit {
            let Some(mut lo) = free else {
                return Some(t);
            };
            let mut hi = t;
            while (hi - lo) * speed > resolution / 4.0 {
                let mid = 0.5 * (lo + hi);
                if touching(mid).0 {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
            return Some(hi);
        }
        free = Some(t);
        if t >= 1.0 {
            return None;
        }
        let step = if gap > 0.0 && speed > 0.0 {
            (gap / speed).max(min_step)
        } else {
            min_step
        };
        t = (t + step).min(1.0);
    }
}

/// Geometric margin (metres) by which a voxel must be inside a cylinder, or clear of it,
/// to be decided without GJK: a thousand times the f32 rounding of room-sized coordinates,
/// so only voxels that GJK itself would decide the same way are skipped.
const DECIDE_MARGIN: f64 = 1e-3;

/// Share of a turning motion's fastest speed under which a part's nearer end must move for
/// the contact search to bound its steps point by point ([`Scene::turn_bound`]): a trunk
/// or shank turning about its own end (near 0) gains steps several times longer; a
/// forearm turning about the shoulder (its elbow end at two thirds of the fastest speed)
/// gains too little for the samples read.
const TURN_LEVER: f64 = 0.5;

/// Relative slack (of the distances involved) taken off bounds derived from the field's
/// `f32` distances: eight times their rounding (2^-23 per operation), so a bound stays
/// below the value it bounds as computed.
const BOUND_SLACK: f64 = 1e-6;

/// Slack (metres per metre of local coordinates and length) between the `f64` geometry of
/// a body part and the `f32` cylinder and voxel centres [`Scene::intersects`] classifies:
/// over a hundred times their rounding (2^-24 per operation).
const F32_SLACK: f64 = 1e-5;

/// Voxels per edge of parry3d's `Voxels` chunks in 3D (`VoxelsChunk::VOXELS_PER_CHUNK_DIM`),
/// whose union is the shape's `local_aabb`.
const PARRY_CHUNK: i64 = 8;

/// Parry's `Voxels::local_aabb` for occupied keys spanning `lo ..= hi` (grid keys) with
/// voxel edge `size` (local frame, metres, f32): the union of the 8^3-voxel chunks that
/// hold them, computed as parry computes each chunk's box (the same f32 values).
fn parry_chunks_aabb(lo: [i64; 3], hi: [i64; 3], size: Vector) -> Aabb {
    let key = ivector;
    let mins = lo.map(|l| l.div_euclid(PARRY_CHUNK) * PARRY_CHUNK);
    let maxs = hi.map(|h| (h.div_euclid(PARRY_CHUNK) + 1) * PARRY_CHUNK);
    Aabb::new(
        ivect_to_vect(key(mins)) * size,
        ivect_to_vect(key(maxs)) * size,
    )
}

/// Parry's `Cylinder::compute_aabb(pose)` (its `support_map_aabb`: per axis, the
/// support points toward the axis and against it), from three support points instead
/// of six: the support point against an axis is the one toward it negated before the
/// translation, the same values up to the sign of zeros (parry's quaternion rotation and
/// the cylinder's support map are linear in the direction, and negation commutes with
/// every rounding), except where the local direction's component along the cylinder's
/// axis is zero (there the support map's `copysign` reads the sign of that zero, and
/// parry's own support point is taken). The sign of a zero bound does not change the
/// voxel range it gives (test `three_support_points_give_parrys_aabb`).
fn cylinder_aabb(shape: &ParryCylinder, pose: &Pose) -> Aabb {
    use parry3d::shape::SupportMap;
    let inv = pose.rotation.inverse();
    let (mut mins, mut maxs) = (Vector::ZERO, Vector::ZERO);
    for d in 0..3 {
        let mut basis = Vector::ZERO;
        basis[d] = 1.0;
        let local = inv * basis;
        let r = pose.rotation * shape.local_support_point(local);
        maxs[d] = (r + pose.translation)[d];
        mins[d] = if local.y != 0.0 {
            (-r + pose.translation)[d]
        } else {
            basis[d] = -1.0;
            shape.support_point(pose, basis)[d]
        };
    }
    Aabb::new(mins, maxs)
}

/// Where a voxel stands against a cylinder, by its centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Side {
    /// Its bounding sphere is clear of the cylinder's capsule by the margin.
    Clear,
    /// Its centre is inside the cylinder by the margin.
    Inside,
    /// Neither: GJK decides.
    Boundary,
}

/// The occupied voxels of a range of grid keys, with their centres, kept for one body
/// part between the steps of a contact search ([`Scene::first_contact`]): a part crossing
/// free space near a surface moves a quarter voxel per step, so its exact tests often ask
/// for the same range, or one inside it, again; they filter these instead of walking the
/// rows of the field. Filled anew from the field's rows when the range leaves it. (Ranges
/// grown by one to three voxels, or grown the way the part moves, cost more to filter than
/// the walks they save.)
#[derive(Debug, Default)]
struct NearVoxels {
    /// The range, half-open `lo..hi` (grid keys); empty until filled.
    lo: [i64; 3],
    hi: [i64; 3],
    /// Its occupied voxels' keys and centres (parry's `Voxels::voxel_center`, local frame).
    voxels: Vec<([i64; 3], Vector)>,
}

impl NearVoxels {
    /// Whether any occupied voxel of `field` (voxel edge `size`) in the range `lo..hi`
    /// passes `test`, from the voxels kept (gathered anew unless the range lies in the
    /// one kept). The voxels passed are the same as [`DistanceField::any_occupied`]'s,
    /// in another order, so the answer is the same.
    fn any(
        &mut self,
        field: &DistanceField,
        lo: [i64; 3],
        hi: [i64; 3],
        size: Vector,
        mut test: impl FnMut(Vector) -> bool,
    ) -> bool {
        let inside = (0..3).all(|a| self.lo[a] <= lo[a] && hi[a] <= self.hi[a]);
        if !inside {
            (self.lo, self.hi) = (lo, hi);
            self.voxels.clear();
            field.any_occupied(lo, hi, |k| {
                self.voxels.push((k, voxel_centre(k, size)));
                false
            });
        }
        if (self.lo, self.hi) == (lo, hi) {
            self.voxels.iter().any(|&(_, p)| test(p))
        } else {
            self.voxels
                .iter()
                .filter(|(k, _)| (0..3).all(|a| lo[a] <= k[a] && k[a] < hi[a]))
                .any(|&(_, p)| test(p))
        }
    }
}

/// Parry's `Voxels::voxel_center` of the voxel with grid key `k` (edge `size`, local frame).
fn voxel_centre(k: [i64; 3], size: Vector) -> Vector {
    (ivect_to_vect(ivector(k)) + Vector::splat(0.5)) * size
}

/// A grid key as parry3d's voxel index (`i32` per axis), saturating. Keys count voxels
/// from the cloud's centre, so they fit unless the extent is over 8,500 km at the finest
/// voxel (2 mm; the extent guard allows coordinates up to 1e7 m); such a key stays at the
/// grid's edge instead of wrapping to its other side.
fn ivector(k: [i64; 3]) -> IVector {
    let c = |v: i64| i32::try_from(v).unwrap_or(if v < 0 { i32::MIN } else { i32::MAX });
    IVector::new(c(k[0]), c(k[1]), c(k[2]))
}

/// The offset of a key from a lower corner it is known not to be below (the box's
/// minimum, or a difference clamped at 0): an index into the grid's arrays.
fn offset(i: i64) -> usize {
    usize::try_from(i).unwrap_or(0)
}

/// An x offset as the distance field stores it, `u32` (half the memory of `usize`),
/// saturating: a box wider than 2^32 voxels exceeds any grid budget, so it never does.
fn x32(x: usize) -> u32 {
    u32::try_from(x).unwrap_or(u32::MAX)
}

/// The grid cell of a position given in voxel units (local frame).
fn cell_of(l: &Vector3<f64>) -> [i64; 3] {
    [floor_i64(l.x), floor_i64(l.y), floor_i64(l.z)]
}

/// The local origin of a scene over points with `bounds` (world, metres): their box's
/// centre rounded to a multiple of the voxel edge `v` (the origin without points).
fn origin_of(bounds: Option<(Point3<f64>, Point3<f64>)>, v: f64) -> Vector3<f64> {
    bounds.map_or(Vector3::zeros(), |(lo, hi)| {
        ((lo.coords + hi.coords) / 2.0).map(|c| (c / v).round() * v)
    })
}

/// The keys of `a` and `b` (each sorted by [`zyx`], each key once) together, sorted by
/// [`zyx`], each once.
fn merge_keys(a: &[[i64; 3]], b: &[[i64; 3]]) -> Vec<[i64; 3]> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut j) = (0, 0);
    while i < a.len() && j < b.len() {
        match zyx(&a[i]).cmp(&zyx(&b[j])) {
            std::cmp::Ordering::Less => {
                out.push(a[i]);
                i += 1;
            }
            std::cmp::Ordering::Greater => {
                out.push(b[j]);
                j += 1;
            }
            std::cmp::Ordering::Equal => {
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out.extend_from_slice(&a[i..]);
    out.extend_from_slice(&b[j..]);
    out
}

/// The voxels holding a point of `cloud` (world frame, metres): the keys (cells of edge
/// `v` from `origin`, [`cell_of`]) sorted by [`zyx`] and each once. A point in the voxel
/// of the point before it (a run of points in one voxel, as a depth image's rows give)
/// adds no key, so fewer keys are sorted: the same keys as sorting every point's and
/// removing repeats (test `occupied_keys_are_the_sorted_distinct_keys`), in no more
/// memory. In that order the distance field's rows along x ([`DistanceField::new`]) come
/// sorted already.
fn occupied_keys(cloud: &PointCloud, origin: Vector3<f64>, v: f64) -> Vec<[i64; 3]> {
    // Room for every point's key, as before; only the pages written are resident.
    let mut keys: Vec<[i64; 3]> = Vec::with_capacity(cloud.len());
    for p in &cloud.points {
        let k = cell_of(&((p.coords - origin) / v));
        if keys.last() != Some(&k) {
            keys.push(k);
        }
    }
    sort_keys(&mut keys);
    keys.dedup();
    keys
}

/// Fewest keys [`sort_keys`] sorts by radix: below this the passes over the buckets cost
/// more than a comparison sort (2^11 buckets a pass).
const RADIX_MIN_KEYS: usize = 1 << 12;
/// Bits of a packed key sorted per radix pass: 2^11 counts (16 KiB) stay in the L1 cache.
const RADIX_BITS: u32 = 11;

/// The order voxel keys are sorted in: by z, then y, then x (the order of the distance
/// field's rows along x, `z * ny + y`, and of the cells within a row).
fn zyx(k: &[i64; 3]) -> [i64; 3] {
    [k[2], k[1], k[0]]
}

/// Sorts voxel keys by [`zyx`], as `sort_unstable_by_key(zyx)` does.
///
/// When the keys' spans along the three axes fit 64 bits together, each key is packed
/// into a `u64` (its offsets from the least key along each axis, z in the high bits, x in
/// the low bits), whose order is the keys' [`zyx`] order, and the packed keys are
/// sorted by a least-significant-digit radix sort ([`RADIX_BITS`] a pass, only as many
/// passes as the packed keys have bits) and unpacked in place; equal keys pack alike, so
/// the result is the same sequence as `sort_unstable_by_key`'s (test
/// `sort_keys_equals_sort_unstable`). Fewer than [`RADIX_MIN_KEYS`] keys, or spans over 64
/// bits, are sorted by `sort_unstable_by_key`.
fn sort_keys(keys: &mut [[i64; 3]]) {
    if keys.len() < RADIX_MIN_KEYS {
        keys.sort_unstable_by_key(zyx);
        return;
    }
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for k in keys.iter() {
        for a in 0..3 {
            lo[a] = lo[a].min(k[a]);
            hi[a] = hi[a].max(k[a]);
        }
    }
    // The span `hi - lo` is below 2^64, so the wrapping difference read as u64 is it.
    let offset = |k: &[i64; 3], a: usize| k[a].wrapping_sub(lo[a]).cast_unsigned();
    let bits = [0, 1, 2].map(|a| u64::BITS - offset(&hi, a).leading_zeros());
    let total = bits[0] + bits[1] + bits[2];
    if total > u64::BITS {
        keys.sort_unstable_by_key(zyx);
        return;
    }
    let (shift_z, shift_y) = (bits[1] + bits[0], bits[0]);
    // A shift of 64 only meets an offset of 0 bits, which is 0.
    let shl = |x: u64, s: u32| x.checked_shl(s).unwrap_or(0);
    let mut packed: Vec<u64> = keys
        .iter()
        .map(|k| shl(offset(k, 2), shift_z) | shl(offset(k, 1), shift_y) | offset(k, 0))
        .collect();
    radix_sort(&mut packed, total);
    let mask = |b: u32| shl(1, b).wrapping_sub(1);
    let (mx, my, mz) = (mask(bits[0]), mask(bits[1]), mask(bits[2]));
    let unshr = |x: u64, s: u32| x.checked_shr(s).unwrap_or(0);
    for (k, &p) in keys.iter_mut().zip(&packed) {
        *k = [
            lo[0].wrapping_add_unsigned(p & mx),
            lo[1].wrapping_add_unsigned(unshr(p, shift_y) & my),
            lo[2].wrapping_add_unsigned(unshr(p, shift_z) & mz),
        ];
    }
}

/// Sorts `values`, all below 2^`bits`, ascending: a stable least-significant-digit radix
/// sort, [`RADIX_BITS`] bits a pass, with one buffer as large as `values`.
fn radix_sort(values: &mut Vec<u64>, bits: u32) {
    let passes = bits.div_ceil(RADIX_BITS);
    if passes == 0 || values.len() < 2 {
        return;
    }
    let buckets = 1usize << RADIX_BITS;
    let mask = (buckets - 1) as u64;
    // A digit is below 2^RADIX_BITS, so it fits `usize` everywhere.
    let digit = |v: u64, pass: u32| usize::try_from(v >> (pass * RADIX_BITS) & mask).unwrap_or(0);
    // Every pass's counts from one read.
    let mut counts = vec![0usize; buckets * passes as usize];
    for &v in values.iter() {
        for pass in 0..passes {
            counts[pass as usize * buckets + digit(v, pass)] += 1;
        }
    }
    let mut from = std::mem::take(values);
    let mut to = vec![0u64; from.len()];
    for pass in 0..passes {
        let count = &mut counts[pass as usize * buckets..(pass as usize + 1) * buckets];
        if count.contains(&from.len()) {
            // Every value has this digit: the pass would not move one.
            continue;
        }
        let mut next = 0;
        for c in count.iter_mut() {
            let n = *c;
            *c = next;
            next += n;
        }
        for &v in &from {
            let d = digit(v, pass);
            to[count[d]] = v;
            count[d] += 1;
        }
        std::mem::swap(&mut from, &mut to);
    }
    *values = from;
}

/// Height of the lowest point of a cylinder above z = 0, metres (negative below the floor).
fn floor_gap(c: &Cylinder) -> f64 {
    let axis = c.b - c.a;
    let len = axis.norm();
    let sin = if len > 1e-12 {
        (1.0 - (axis.z / len).powi(2)).max(0.0).sqrt()
    } else {
        1.0
    };
    c.a.z.min(c.b.z) - c.radius * sin
}

/// Edge of a distance-field chunk, cells: the unit in which distances are computed and
/// kept. 32 cells (0.64 m at 2 cm) hold a seat or a limb's neighbourhood, so a fit reuses
/// a few chunks; a chunk is 128 KiB of `f32`.
const CHUNK: usize = 32;
/// Cells cut per chunk (`CHUNK`^3).
const CHUNK_CELLS: usize = CHUNK * CHUNK * CHUNK;
/// Border (cells) first read around a chunk when its distances are computed: a quarter
/// chunk, so cells within 0.18 m of a surface (where contacts are found) are decided in
/// one cheap pass; a chunk with farther cells is computed again with a border as wide as
/// the farthest distance found.
const FIRST_PAD: usize = CHUNK / 4;
/// Growth of the border when a pass finds no occupied cell for some cell.
const PAD_GROWTH: usize = 4;
/// Squared distance (cells) standing for "no occupied cell in reach" in the passes.
const FAR: f32 = 1e20;
/// Largest field box (cells) whose passes are computed densely, in strips and tiles of
/// whole columns where bodies ask (up to 4 bytes a cell for the first two passes' strips,
/// and up to 4 more for the last pass's tiles): 2^25 cells, 256 MiB, a 1M-point room scan
/// at 2 cm; there one pass over the box costs about a third of the instructions of
/// computing its chunks with their borders. Larger boxes are computed in chunks where
/// they are used.
const DENSE_CELLS: usize = 1 << 25;
/// Most chunks kept at once: 512 MiB of distances. A 1M-point room scan at 2 cm touches
/// about a fifth of that; past it, distances are computed cell by cell and not kept, so
/// memory stays bounded and only time grows (the values are the same).
const KEPT_CHUNKS: usize = (512 << 20) / (CHUNK_CELLS * std::mem::size_of::<f32>());

/// Most row ids (`ny * nz`) for which [`DistanceField`] keeps a table from row id to
/// row (4 bytes each): 2^23, 32 MiB, covers a 160 m x 160 m x 10 m box at 2 cm (a
/// 1M-point room scan needs about 250 000); a larger box falls back to binary searches
/// over the sorted rows, with the same answers.
const ROW_TABLE_ENTRIES: usize = 1 << 23;

/// For sorted row ids `rows` (each below `ids`), the table whose entry `id` (for `id` in
/// `0..=ids`) is the index of the first row with an id at least `id`; `None` when `ids`
/// exceeds [`ROW_TABLE_ENTRIES`] or the rows do not fit `u32` indices.
fn row_table(rows: &[u64], ids: usize) -> Option<Vec<u32>> {
    if ids > ROW_TABLE_ENTRIES || u32::try_from(rows.len()).is_err() {
        return None;
    }
    let mut table = Vec::with_capacity(ids + 1);
    let mut r = 0usize;
    for id in 0..=ids as u64 {
        while r < rows.len() && rows[r] < id {
            r += 1;
        }
        // `rows.len()` fits u32 (checked above), and r <= rows.len().
        table.push(u32::try_from(r).unwrap_or(u32::MAX));
    }
    Some(table)
}

/// Euclidean distances from cell centres to the nearest occupied voxel centre, over the
/// box `min .. min + dims` (grid keys), computed lazily in chunks of [`CHUNK`]^3 cells:
/// only the chunks queried are ever computed or stored, so memory follows the region the
/// agent reaches, not the box. Each value is exact (the same `f32` a dense exact
/// transform over the whole box gives: the square root of an integer squared distance in
/// cells, times the voxel size); the occupied cells are kept as sorted rows along x.
#[derive(Debug)]
struct DistanceField {
    /// Grid key of cell (0, 0, 0).
    min: [i64; 3],
    dims: [usize; 3],
    /// Voxel edge, metres, in the precision of the stored distances.
    voxel: f32,
    /// Ids (`z * ny + y`) of the rows along x holding occupied cells, ascending.
    rows: Vec<u64>,
    /// Start of each row's cells in `xs` (one more entry than `rows`).
    row_start: Vec<usize>,
    /// For every row id `z * ny + y` (and one past the last), the index in `rows` of the
    /// first row with that id or more: the row lookups without a binary search. `None`
    /// when the box has more than [`ROW_TABLE_ENTRIES`] rows (then `rows` is searched).
    row_table: Option<Vec<u32>>,
    /// x offsets of the occupied cells, ascending within each row.
    xs: Vec<u32>,
    /// Chunks per axis.
    chunk_dims: [usize; 3],
    /// Distances (metres), chunk by chunk (`(cz * cny + cy) * cnx + cx`), each laid out
    /// `(z * CHUNK + y) * CHUNK + x`; computed on first use.
    chunks: Vec<OnceLock<Box<[f32]>>>,
    /// Chunks computed and kept so far.
    kept: AtomicUsize,
    /// The distances of a box of at most [`DENSE_CELLS`]: its first two passes computed
    /// in strips of columns, the last one in tiles of columns, where asked; `None` for a
    /// larger box (then
    /// `chunks` holds them).
    dense: Option<dense::Columns>,
}

impl DistanceField {
    /// The field over the box `min .. min + dims` of the occupied voxel `keys` (all inside
    /// the box), voxel edge `v` metres. Nothing is computed yet.
    fn new(min: [i64; 3], dims: [usize; 3], keys: &[[i64; 3]], v: f64) -> DistanceField {
        Self::with_dense_limit(min, dims, keys, v, DENSE_CELLS)
    }

    /// [`Self::new`], computing the box at once when it has at most `dense_cells` cells.
    fn with_dense_limit(
        min: [i64; 3],
        dims: [usize; 3],
        keys: &[[i64; 3]],
        v: f64,
        dense_cells: usize,
    ) -> DistanceField {
        let cells = dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d));
        let dense = cells
            .is_some_and(|n| n <= dense_cells)
            .then(|| dense::Columns::new(min, dims, keys, v));
        let ny = dims[1] as u64;
        let mut cells: Vec<(u64, u32)> = keys
            .iter()
            .map(|k| {
                let o = [0, 1, 2].map(|a| offset(k[a] - min[a]));
                (o[2] as u64 * ny + o[1] as u64, x32(o[0]))
            })
            .collect();
        cells.sort_unstable();
        cells.dedup();
        let (mut rows, mut row_start, mut xs) = (Vec::new(), Vec::new(), Vec::new());
        for (i, &(row, x)) in cells.iter().enumerate() {
            if rows.last() != Some(&row) {
                rows.push(row);
                row_start.push(i);
            }
            xs.push(x);
        }
        row_start.push(xs.len());
        let row_table = row_table(&rows, dims[1] * dims[2]);
        let chunk_dims = dims.map(|d| d.div_ceil(CHUNK));
        let slots = if dense.is_some() {
            0
        } else {
            chunk_dims.iter().product()
        };
        let chunks = (0..slots).map(|_| OnceLock::new()).collect();
        DistanceField {
            min,
            dims,
            voxel: to_f32(v),
            rows,
            row_start,
            row_table,
            xs,
            chunk_dims,
            chunks,
            kept: AtomicUsize::new(0),
            dense,
        }
    }

    /// Whether every cell a point of the segment between the cells `ka` and `kb` falls
    /// in (each axis between theirs, one cell more each way for rounding) is in the box.
    fn holds_segment(&self, ka: [i64; 3], kb: [i64; 3]) -> bool {
        (0..3).all(|a| {
            let lo = ka[a]
                .min(kb[a])
                .saturating_sub(1)
                .saturating_sub(self.min[a]);
            let hi = ka[a]
                .max(kb[a])
                .saturating_add(1)
                .saturating_sub(self.min[a]);
            lo >= 0 && usize::try_from(hi).is_ok_and(|h| h < self.dims[a])
        })
    }

    /// Offsets of grid key `k` in the box, or `None` outside it.
    fn offsets(&self, k: [i64; 3]) -> Option<[usize; 3]> {
        let mut o = [0usize; 3];
        for a in 0..3 {
            o[a] = usize::try_from(k[a] - self.min[a])
                .ok()
                .filter(|&i| i < self.dims[a])?;
        }
        Some(o)
    }

    /// Distance (metres) from the centre of cell `k` to the nearest occupied cell centre;
    /// `None` outside the box.
    fn get(&self, k: [i64; 3]) -> Option<f32> {
        let o = self.offsets(k)?;
        if let Some(d) = &self.dense {
            return Some(d.get(self, o));
        }
        let c = o.map(|i| i / CHUNK);
        let [cnx, cny, _] = self.chunk_dims;
        let slot = &self.chunks[(c[2] * cny + c[1]) * cnx + c[0]];
        let l = o.map(|i| i % CHUNK);
        let at = (l[2] * CHUNK + l[1]) * CHUNK + l[0];
        if let Some(chunk) = slot.get() {
            return Some(chunk[at]);
        }
        if self.kept.load(Ordering::Relaxed) >= KEPT_CHUNKS {
            return Some(self.cell_distance(o));
        }
        let chunk = slot.get_or_init(|| {
            self.kept.fetch_add(1, Ordering::Relaxed);
            self.compute_chunk(c.map(|i| i * CHUNK))
        });
        Some(chunk[at])
    }

    /// The rows `(y, z)` with occupied cells for `y` in `y0..y1` at height `z`, as
    /// `(y, x offsets)`.
    fn rows_at(&self, z: usize, y0: usize, y1: usize) -> impl Iterator<Item = (usize, &[u32])> {
        let base = (z * self.dims[1]) as u64;
        let (r, end) = (
            self.first_row(base + y0 as u64),
            self.first_row(base + y1 as u64),
        );
        self.rows[r..end].iter().enumerate().map(move |(i, &id)| {
            let (a, b) = (self.row_start[r + i], self.row_start[r + i + 1]);
            // Below `y1`, a row of the box: fits usize.
            let y = usize::try_from(id - base).unwrap_or(usize::MAX);
            (y, &self.xs[a..b])
        })
    }

    /// The distance of the one cell at offsets `o`, computed alone (as [`Self::get`] gives
    /// it, for distances under 2^12 cells, where the squared distances are exact in f32):
    /// the nearest occupied cell of each row within a border that grows as in
    /// [`Self::compute_chunk`].
    fn cell_distance(&self, o: [usize; 3]) -> f32 {
        let [_, ny, nz] = self.dims;
        let mut pad = FIRST_PAD;
        loop {
            let (y0, y1) = (o[1].saturating_sub(pad), (o[1] + 1 + pad).min(ny));
            let (z0, z1) = (o[2].saturating_sub(pad), (o[2] + 1 + pad).min(nz));
            let mut best = u64::MAX;
            for z in z0..z1 {
                for (y, xs) in self.rows_at(z, y0, y1) {
                    let mut d = [0f32];
                    nearest_in_list(xs, o[0], &mut d);
                    let (dy, dz) = (y.abs_diff(o[1]) as u64, z.abs_diff(o[2]) as u64);
                    // A squared distance in whole cells within the box, exact in f32.
                    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                    let dx2 = d[0] as u64;
                    best = best.min(dx2 + dy * dy + dz * dz);
                }
            }
            let whole = y0 == 0 && y1 == ny && z0 == 0 && z1 == nz;
            if whole || best <= ((pad + 1) * (pad + 1)) as u64 {
                return if best == u64::MAX {
                    f32::INFINITY
                } else {
                    (best as f32).sqrt() * self.voxel
                };
            }
            pad = if best == u64::MAX {
                pad * PAD_GROWTH
            } else {
                to_usize((best as f64).sqrt().ceil()).max(pad + 1)
            };
        }
    }

    /// The occupied x offsets of row `(y, z)` (offsets in the box).
    fn row(&self, y: usize, z: usize) -> &[u32] {
        let id = (z * self.dims[1] + y) as u64;
        let r = self.first_row(id);
        match self.rows.get(r) {
            Some(&found) if found == id => &self.xs[self.row_start[r]..self.row_start[r + 1]],
            _ => &[],
        }
    }

    /// The index in `rows` of the first row whose id is at least `id` (`rows.len()` when
    /// none is): a look-up in the row table, or a binary search without one.
    fn first_row(&self, id: u64) -> usize {
        match &self.row_table {
            // An id past usize is past the table: no entry, as past its end.
            Some(t) => usize::try_from(id)
                .ok()
                .and_then(|i| t.get(i))
                .map_or(self.rows.len(), |&r| r as usize),
            None => self.rows.partition_point(|&r| r < id),
        }
    }

    /// Whether cell `k` is occupied.
    fn occupied(&self, k: [i64; 3]) -> bool {
        self.offsets(k)
            .is_some_and(|o| self.row(o[1], o[2]).binary_search(&x32(o[0])).is_ok())
    }

    /// Calls `visit` on the occupied cells with keys in the half-open box `lo..hi` until it
    /// returns true; returns whether it did.
    fn any_occupied(
        &self,
        lo: [i64; 3],
        hi: [i64; 3],
        mut visit: impl FnMut([i64; 3]) -> bool,
    ) -> bool {
        let lo = [0, 1, 2].map(|a| offset((lo[a] - self.min[a]).max(0)));
        let hi = [0, 1, 2].map(|a| offset((hi[a] - self.min[a]).clamp(0, self.dims[a] as i64)));
        if (0..3).any(|a| lo[a] >= hi[a]) {
            return false;
        }
        for z in lo[2]..hi[2] {
            for (y, xs) in self.rows_at(z, lo[1], hi[1]) {
                let from = xs.partition_point(|&x| (x as usize) < lo[0]);
                for &x in xs[from..].iter().take_while(|&&x| (x as usize) < hi[0]) {
                    let key = [
                        x as i64 + self.min[0],
                        y as i64 + self.min[1],
                        z as i64 + self.min[2],
                    ];
                    if visit(key) {
                        return true;
                    }
                }
            }
        }
        false
    }

    /// The distances of the chunk whose first cell has offsets `start`: the exact
    /// transform (Felzenszwalb and Huttenlocher, 2012) of the occupied cells in whole rows
    /// along x and within a border of `pad` cells along y and z. A cell whose distance
    /// found is at most `pad + 1` cells is exact (any occupied cell outside the border is
    /// farther); if some cell is not, the border grows and the chunk is computed again.
    fn compute_chunk(&self, start: [usize; 3]) -> Box<[f32]> {
        let [_, ny, nz] = self.dims;
        let end = [0, 1, 2].map(|a| (start[a] + CHUNK).min(self.dims[a]));
        let cx = end[0] - start[0];
        let (cy, cz) = (end[1] - start[1], end[2] - start[2]);
        let mut pad = FIRST_PAD;
        loop {
            let (y0, y1) = (start[1].saturating_sub(pad), (end[1] + pad).min(ny));
            let (z0, z1) = (start[2].saturating_sub(pad), (end[2] + pad).min(nz));
            let whole = y0 == 0 && y1 == ny && z0 == 0 && z1 == nz;
            let (py, pz) = (y1 - y0, z1 - z0);
            let longest = py.max(pz);
            // Along x, whole rows: the squared distance to the nearest occupied cell of the
            // row, laid out `(z * py + y) * cx + x`.
            let mut g = vec![FAR; cx * py * pz];
            for z in z0..z1 {
                for (y, xs) in self.rows_at(z, y0, y1) {
                    let line = &mut g[((z - z0) * py + (y - y0)) * cx..][..cx];
                    nearest_in_list(xs, start[0], line);
                }
            }
            let (mut f, mut out) = (vec![0f32; longest], vec![0f32; longest]);
            let (mut vs, mut zs) = (vec![0usize; longest], vec![0f32; longest + 1]);
            // Along y, kept only for the chunk's rows: `(z * cy + y) * cx + x`.
            let mut g2 = vec![FAR; cx * cy * pz];
            for z in 0..pz {
                for x in 0..cx {
                    for y in 0..py {
                        f[y] = g[(z * py + y) * cx + x];
                    }
                    if f[..py].iter().all(|&d| d == FAR) {
                        continue;
                    }
                    edt_1d_range(&f[..py], start[1] - y0, &mut out[..cy], &mut vs, &mut zs);
                    for y in 0..cy {
                        g2[(z * cy + y) * cx + x] = out[y];
                    }
                }
            }
            // Along z, kept only for the chunk's cells.
            let mut dist = vec![f32::INFINITY; CHUNK_CELLS].into_boxed_slice();
            let reach = ((pad + 1) * (pad + 1)) as f32;
            // The largest squared distance found that is not certain yet.
            let mut undecided = 0f32;
            for y in 0..cy {
                for x in 0..cx {
                    for z in 0..pz {
                        f[z] = g2[(z * cy + y) * cx + x];
                    }
                    if f[..pz].iter().all(|&d| d == FAR) {
                        undecided = FAR;
                        continue;
                    }
                    edt_1d_range(&f[..pz], start[2] - z0, &mut out[..cz], &mut vs, &mut zs);
                    for z in 0..cz {
                        let q = out[z];
                        if !whole && q > reach {
                            undecided = undecided.max(q);
                        }
                        dist[(z * CHUNK + y) * CHUNK + x] = if q >= FAR / 2.0 {
                            f32::INFINITY
                        } else {
                            q.sqrt() * self.voxel
                        };
                    }
                }
            }
            if whole || undecided == 0.0 {
                return dist;
            }
            // A border as wide as the farthest distance found holds every nearest
            // occupied cell (the distances can only shrink as it widens); with none found,
            // the border grows by a factor.
            pad = if undecided < FAR / 2.0 {
                to_usize(f64::from(undecided.sqrt().ceil())).max(pad + 1)
            } else {
                pad * PAD_GROWTH
            };
        }
    }
}

/// Squared distances (in cells) from cells `start .. start + out.len()` of a row to the
/// nearest of its occupied cells `xs` (ascending), written to `out`; the same values as
/// the transform of the whole row.
fn nearest_in_list(xs: &[u32], start: usize, out: &mut [f32]) {
    let mut i = xs.partition_point(|&x| (x as usize) < start);
    for (j, d) in out.iter_mut().enumerate() {
        let x = start + j;
        while i < xs.len() && (xs[i] as usize) < x {
            i += 1;
        }
        let right = xs.get(i).map(|&r| r as usize - x);
        let left = i.checked_sub(1).map(|l| x - xs[l] as usize);
        if let Some(n) = match (left, right) {
            (Some(l), Some(r)) => Some(l.min(r)),
            (l, r) => l.or(r),
        } {
            *d = (n * n) as f32;
        }
    }
}

/// One-dimensional squared distance transform of sampled function `f` (lower envelope of parabolas).
fn edt_1d(f: &[f32], d: &mut [f32], v: &mut [usize], z: &mut [f32]) {
    edt_1d_range(f, 0, d, v, z);
}

/// [`edt_1d`] written only for the positions `from .. from + d.len()` of `f` (the same
/// values, bit for bit).
///
/// Entries equal to [`FAR`] (no occupied cell on that line of the earlier passes) are left
/// out of the lower envelope: the transform with them has the same value at every
/// position (a FAR parabola is never the lowest where a finite one exists, and the
/// finite ones meet each other where they did), and a line of FAR alone is FAR.
fn edt_1d_range(f: &[f32], from: usize, d: &mut [f32], v: &mut [usize], z: &mut [f32]) {
    let n = f.len();
    let Some(first) = f.iter().position(|&x| x != FAR) else {
        for dq in d.iter_mut().take(n - from.min(n)) {
            *dq = FAR;
        }
        return;
    };
    let mut k = 0usize;
    v[0] = first;
    z[0] = f32::NEG_INFINITY;
    // A parabola's terms in the intersection: `f[p] + p^2` and `2 p`, as f32.
    let terms = |p: usize| (f[p] + index_f32(p * p), 2.0 * slice_index_f32(p));
    // The terms of `v[k]`, the top of the envelope, kept as it changes: the same values
    // as computing them at each comparison.
    let (mut hp, mut tp) = terms(first);
    // The envelope is built reading `z[..=k]` only; the bound past its top, `z[k + 1]`,
    // is set once it is complete.
    for (q, &fq) in f.iter().enumerate().skip(first + 1) {
        if fq == FAR {
            continue;
        }
        // The new parabola's terms (`terms(q)`).
        let (hq, q2) = terms(q);
        loop {
            let s = (hq - hp) / (q2 - tp);
            if s <= z[k] {
                if k == 0 {
                    // The new parabola dominates from -inf: replace.
                    v[0] = q;
                    (hp, tp) = (hq, q2);
                    break;
                }
                k -= 1;
                (hp, tp) = terms(v[k]);
            } else {
                k += 1;
                v[k] = q;
                z[k] = s;
                (hp, tp) = (hq, q2);
                break;
            }
        }
    }
    z[k + 1] = f32::INFINITY;
    k = 0;
    // `v[k]` as f32 and its `f`, and `z[k + 1]`, kept as `k` changes.
    let (mut pf, mut fp, mut next) = (slice_index_f32(v[0]), f[v[0]], z[1]);
    for (q, dq) in d.iter_mut().enumerate().take(n - from.min(n)) {
        let qf = slice_index_f32(q + from);
        if next < qf {
            while z[k + 1] < qf {
                k += 1;
            }
            (pf, fp, next) = (slice_index_f32(v[k]), f[v[k]], z[k + 1]);
        }
        let diff = qf - pf;
        *dq = diff * diff + fp;
    }
}

mod dense {
    //! The dense exact transform, for boxes small enough to hold at once
    //! ([`DENSE_CELLS`]): the passes along x and y per strip of columns, the pass along z
    //! per tile of columns, each where first asked; faster than chunks there; the chunked
    //! field equals it bit for bit.
    use super::*;

    /// Edge of a tile of columns, cells: the unit in which the last pass (along z) is
    /// computed and kept, and the width (along x) of the strips the first two passes are
    /// computed in. 8 x 8 columns (0.16 m square at 2 cm) is finer than a limb, so
    /// little is computed that no body asks for, and coarse enough that the tiles' slots
    /// (one `OnceLock` each) cost nothing beside the grid.
    const TILE: usize = 8;

    /// The exact distance field of a box of at most [`DENSE_CELLS`]: the first two passes
    /// of the transform (along x, then y) per strip of [`TILE`] columns along x (every y
    /// and z), and the last one (along z, which reads only its own column) per tile of
    /// [`TILE`] x [`TILE`] columns, each on first use. A line along y reads only its own
    /// (x, z) and the rows along x it crosses, so a strip's values are those of the passes
    /// over the whole box. Every value equals [`dense_distances`] of the box, bit for bit.
    #[derive(Debug)]
    pub(super) struct Columns {
        /// Cells along x, y, z.
        dims: [usize; 3],
        /// Voxel edge, metres, in the precision of the stored distances.
        voxel: f32,
        /// Per z slab, whether it holds an occupied cell: a slab without one is [`FAR`]
        /// after the passes along x and y (the transform of a constant FAR line is FAR).
        slab_used: Vec<bool>,
        /// Tiles along x (and strips).
        tiles_x: usize,
        /// Squared distances (cells) after the passes along x and y per strip (`tx`),
        /// laid out `(z * ny + y) * TILE + x % TILE`; computed on first use.
        strips: Vec<OnceLock<Box<[f32]>>>,
        /// Distances (metres) per tile (`ty * tiles_x + tx`), laid out
        /// `(z * TILE + y) * TILE + x` within it; computed on first use.
        tiles: Vec<OnceLock<Box<[f32]>>>,
    }

    impl Columns {
        /// The slots of the box `min .. min + dims` of the occupied voxel `keys`, voxel
        /// edge `v` metres; nothing is computed yet.
        pub(super) fn new(min: [i64; 3], dims: [usize; 3], keys: &[[i64; 3]], v: f64) -> Columns {
            let tiles_x = dims[0].div_ceil(TILE);
            let tiles = (0..tiles_x * dims[1].div_ceil(TILE))
                .map(|_| OnceLock::new())
                .collect();
            let mut slab_used = vec![false; dims[2]];
            for k in keys {
                if let Some(u) = slab_used.get_mut(offset(k[2] - min[2])) {
                    *u = true;
                }
            }
            Columns {
                dims,
                voxel: to_f32(v),
                slab_used,
                tiles_x,
                strips: (0..tiles_x).map(|_| OnceLock::new()).collect(),
                tiles,
            }
        }

        /// The distance (metres) at offsets `o` (inside the box), the occupied rows read
        /// from `field` (the field this is part of). Inlined into the field's reads, the
        /// hot path of the contact search (left to itself, the compiler's choice follows
        /// how the crate is split into codegen units).
        #[inline]
        pub(super) fn get(&self, field: &DistanceField, o: [usize; 3]) -> f32 {
            let (tx, ty) = (o[0] / TILE, o[1] / TILE);
            let tile = self.tiles[ty * self.tiles_x + tx].get_or_init(|| self.tile(field, tx, ty));
            tile[(o[2] * TILE + o[1] % TILE) * TILE + o[0] % TILE]
        }

        /// The passes along x and y over the columns of strip `tx` (x from `tx * TILE`,
        /// every y and z): per used slab, each occupied row's nearest occupied cell for the
        /// strip's x ([`nearest_in_list`], the exact squared distances of the pass along
        /// x; rows without one stay [`FAR`]), then the transform of each line along y.
        fn strip(&self, field: &DistanceField, tx: usize) -> Box<[f32]> {
            let [nx, ny, nz] = self.dims;
            let x0 = tx * TILE;
            let w = TILE.min(nx - x0);
            let mut out = vec![FAR; nz * ny * TILE].into_boxed_slice();
            // The strip's lines along y of one slab, `xi * ny + y`.
            let mut lines = vec![FAR; TILE * ny];
            let mut near = [FAR; TILE];
            let (mut d, mut vs, mut zs) = (vec![0f32; ny], vec![0usize; ny], vec![0f32; ny + 1]);
            for z in 0..nz {
                if !self.slab_used[z] {
                    continue;
                }
                lines.fill(FAR);
                for (y, xs) in field.rows_at(z, 0, ny) {
                    near.fill(FAR);
                    nearest_in_list(xs, x0, &mut near[..w]);
                    for (xi, &q) in near[..w].iter().enumerate() {
                        lines[xi * ny + y] = q;
                    }
                }
                for xi in 0..w {
                    edt_1d(&lines[xi * ny..(xi + 1) * ny], &mut d, &mut vs, &mut zs);
                    for (y, &q) in d.iter().enumerate() {
                        out[(z * ny + y) * TILE + xi] = q;
                    }
                }
            }
            out
        }

        /// The last pass over the columns of tile `(tx, ty)`, from its strip.
        fn tile(&self, field: &DistanceField, tx: usize, ty: usize) -> Box<[f32]> {
            let [nx, ny, nz] = self.dims;
            let strip = self.strips[tx].get_or_init(|| self.strip(field, tx));
            let mut out = vec![f32::INFINITY; nz * TILE * TILE].into_boxed_slice();
            let (y0, y1) = (ty * TILE, ((ty + 1) * TILE).min(ny));
            // The tile's columns, `((y - y0) * TILE + xi) * nz + z`: at each z the strip
            // holds the tile's cells side by side (`(z * ny + y) * TILE + xi`), so they
            // are gathered in one sweep along z.
            let mut columns = vec![0f32; (y1 - y0) * TILE * nz];
            for z in 0..nz {
                let cells = &strip[(z * ny + y0) * TILE..(z * ny + y1) * TILE];
                for (c, &q) in cells.iter().enumerate() {
                    columns[c * nz + z] = q;
                }
            }
            let mut d = vec![0f32; nz];
            let (mut vs, mut zs) = (vec![0usize; nz], vec![0f32; nz + 1]);
            for yi in 0..y1 - y0 {
                for xi in 0..TILE.min(nx - tx * TILE) {
                    let f = &columns[(yi * TILE + xi) * nz..][..nz];
                    edt_1d(f, &mut d, &mut vs, &mut zs);
                    for (z, &q) in d.iter().enumerate() {
                        out[(z * TILE + yi) * TILE + xi] = distance(q, self.voxel);
                    }
                }
            }
            out
        }
    }

    /// Metres from a squared distance in cells `q` (at least `FAR / 2`: none, infinite).
    fn distance(q: f32, voxel: f32) -> f32 {
        if q >= FAR / 2.0 {
            f32::INFINITY
        } else {
            q.sqrt() * voxel
        }
    }

    /// Exact Euclidean distance transform (Felzenszwalb and Huttenlocher, 2012) of the
    /// occupied voxel `keys`, in metres, all at once: the reference [`Columns`] equals.
    /// The result is stored y-major (`(y * nz + z) * nx + x`).
    #[cfg(test)]
    pub(super) fn dense_distances(
        min: [i64; 3],
        dims: [usize; 3],
        keys: &[[i64; 3]],
        v: f64,
    ) -> Vec<f32> {
        let [nx, ny, nz] = dims;
        let d = planes(min, dims, keys);
        // Along z, column by column: write one y-major plane per y.
        let (mut f, mut out) = (vec![0f32; nz], vec![0f32; nz]);
        let (mut vs, mut zs) = (vec![0usize; nz], vec![0f32; nz + 1]);
        let mut dist = vec![0f32; nx * ny * nz];
        for y in 0..ny {
            for x in 0..nx {
                for (z, fz) in f.iter_mut().enumerate() {
                    *fz = d[(z * ny + y) * nx + x];
                }
                edt_1d(&f, &mut out, &mut vs, &mut zs);
                for (z, &q) in out.iter().enumerate() {
                    dist[(y * nz + z) * nx + x] = distance(q, to_f32(v));
                }
            }
        }
        dist
    }

    /// The first two passes of the transform (along x, then y) of the occupied voxel
    /// `keys` over the box `min .. min + dims`: squared distances in cells, z-major
    /// (`(z * ny + y) * nx + x`), [`FAR`] where a slab has no occupied cell. The
    /// reference [`Columns`]' strips equal.
    #[cfg(test)]
    fn planes(min: [i64; 3], dims: [usize; 3], keys: &[[i64; 3]]) -> Vec<f32> {
        use rayon::prelude::*;
        let [nx, ny, nz] = dims;
        // Squared distances in cells, z-major (`(z * ny + y) * nx + x`) for the first passes.
        let mut d = vec![FAR; nx * ny * nz];
        for k in keys {
            let (x, y, z) = (
                offset(k[0] - min[0]),
                offset(k[1] - min[1]),
                offset(k[2] - min[2]),
            );
            d[(z * ny + y) * nx + x] = 0.0;
        }
        let longest = nx.max(ny).max(nz);
        let scratch = || {
            (
                vec![0f32; longest],
                vec![0f32; longest],
                vec![0usize; longest],
                vec![0f32; longest + 1],
            )
        };
        // Along x: rows are contiguous and hold only 0 (occupied) or FAR, so the nearest
        // occupied cell on either side gives the exact squared distance (the value
        // `edt_1d` computes, in a fraction of its time).
        d.par_chunks_mut(nx).for_each(nearest_in_row);
        // Along y: within each z slab. A slab without occupied cells is FAR after the
        // first pass and stays FAR (the transform of a constant FAR line is FAR).
        let mut slab_used = vec![false; nz];
        for k in keys {
            slab_used[offset(k[2] - min[2])] = true;
        }
        d.par_chunks_mut(nx * ny)
            .zip(slab_used.par_iter())
            .filter(|(_, used)| **used)
            .for_each_init(scratch, |(f, out, vs, zs), (slab, _)| {
                for x in 0..nx {
                    for y in 0..ny {
                        f[y] = slab[y * nx + x];
                    }
                    edt_1d(&f[..ny], &mut out[..ny], vs, zs);
                    for y in 0..ny {
                        slab[y * nx + x] = out[y];
                    }
                }
            });
        d
    }

    /// Squared distances (in cells) along a row of 0 (occupied) and FAR cells to its nearest
    /// occupied cell, in place; a row without one stays FAR. Equal, bit for bit, to
    /// [`edt_1d`] of the row (both are exact: squared distances are small integers in f32).
    #[cfg(test)]
    pub(super) fn nearest_in_row(row: &mut [f32]) {
        let mut last = None;
        for (x, d) in row.iter_mut().enumerate() {
            if *d == 0.0 {
                last = Some(x);
            } else if let Some(p) = last {
                *d = ((x - p) * (x - p)) as f32;
            }
        }
        let mut next = None;
        for (x, d) in row.iter_mut().enumerate().rev() {
            if *d == 0.0 {
                next = Some(x);
            } else if let Some(p) = next {
                *d = d.min(((p - x) * (p - x)) as f32);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `occupied_keys` against every point's key sorted with repeats removed, on seeded
    /// clouds: runs of points in one voxel, voxels revisited later, points on voxel
    /// faces, NaN and infinite coordinates.
    #[test]
    fn occupied_keys_are_the_sorted_distinct_keys() {
        let mut state = 5u64;
        for round in 0..200 {
            let v = [0.02, 0.05, 0.1][round % 3];
            let n = 1 + to_usize(uniform(&mut state) * 3000.0);
            let mut pts = Vec::with_capacity(n);
            let mut p = Point3::new(0.0, 0.0, 0.0);
            for i in 0..n {
                if uniform(&mut state) < 0.3 {
                    p = Point3::new(
                        uniform(&mut state) * 2.0 - 1.0,
                        uniform(&mut state) * 2.0 - 1.0,
                        uniform(&mut state) * 1.5,
                    );
                } else {
                    p.x += (uniform(&mut state) - 0.5) * v;
                }
                if i % 97 == 0 {
                    p.y = (p.y / v).round() * v;
                }
                pts.push(p);
            }
            if round % 7 == 0 {
                pts.push(Point3::new(f64::NAN, 0.0, 0.1));
                pts.push(Point3::new(0.0, f64::INFINITY, 0.1));
                pts.push(Point3::new(0.0, 0.0, f64::NEG_INFINITY));
            }
            let cloud = PointCloud::new(pts);
            let origin = Vector3::new(0.01, -0.02, 0.0);
            let mut want: Vec<[i64; 3]> = cloud
                .points
                .iter()
                .map(|p| cell_of(&((p.coords - origin) / v)))
                .collect();
            want.sort_unstable_by_key(zyx);
            want.dedup();
            assert_eq!(occupied_keys(&cloud, origin, v), want, "{round}");
        }
    }
    /// `sort_keys` against `sort_unstable_by_key(zyx)` on seeded key sets: small and large
    /// sets, narrow and wide spans (up to exactly 64 bits together, and past them),
    /// negative keys, repeats, and keys at the ends of `i64`.
    #[test]
    fn sort_keys_equals_sort_unstable() {
        let mut state = 11u64;
        let next = |state: &mut u64| {
            *state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *state >> 11
        };
        for round in 0..120 {
            let n = [10, 5000, 20_000][round % 3];
            // Bits of span per axis: narrow, room-sized, 64 together, over 64.
            let bits: [u32; 3] = match round % 6 {
                0 => [3, 4, 2],
                1 => [9, 9, 8],
                2 => [22, 21, 21],
                3 => [30, 20, 14],
                4 => [40, 20, 10],
                _ => [63, 63, 63],
            };
            let base = [
                i64::try_from(next(&mut state) % 1000).unwrap_or(0) - 500,
                -7,
                if round % 5 == 0 { i64::MIN } else { 3 },
            ];
            let mut keys: Vec<[i64; 3]> = (0..n)
                .map(|_| {
                    [0, 1, 2].map(|a| {
                        let span = 1u64 << bits[a].min(62);
                        base[a].wrapping_add_unsigned(next(&mut state) % span)
                    })
                })
                .collect();
            for i in 0..n / 10 {
                let j = usize::try_from(next(&mut state)).unwrap_or(0) % n;
                keys[i] = keys[j];
            }
            if round % 4 == 0 {
                keys.push([i64::MAX, 0, 0]);
            }
            let mut want = keys.clone();
            want.sort_unstable_by_key(zyx);
            sort_keys(&mut keys);
            assert_eq!(keys, want, "{round}");
        }
        // Spans that fill 64 bits exactly, with keys at both ends of every axis.
        let mut keys: Vec<[i64; 3]> = (0..RADIX_MIN_KEYS as i64 * 2)
            .map(|i| [(i * 7919) % 1_000_000, -(i % 65_536), (i * 31) % 1_000_003])
            .collect();
        keys.push([0, -65_535, 0]);
        keys.push([(1 << 23) - 1, 0, (1 << 25) - 1]);
        let mut want = keys.clone();
        want.sort_unstable_by_key(zyx);
        sort_keys(&mut keys);
        assert_eq!(keys, want);
        let mut values: Vec<u64> = (0..10_000u64)
            .map(|i| i.wrapping_mul(0x9E37_79B9_7F4A_7C15))
            .collect();
        let mut want = values.clone();
        want.sort_unstable();
        radix_sort(&mut values, 64);
        assert_eq!(values, want);
    }

    use dense::*;

    fn cfg(floor: bool) -> SceneConfig {
        SceneConfig {
            voxel_size: 0.02,
            floor,
            field_margin: 0.2,
        }
    }

    fn slab(z: f64) -> PointCloud {
        // A 0.6 x 0.6 m horizontal slab of points at height z, 1 cm apart.
        let mut pts = Vec::new();
        for i in 0..60 {
            for j in 0..60 {
                pts.push(Point3::new(i as f64 * 0.01, j as f64 * 0.01, z));
            }
        }
        PointCloud::new(pts)
    }

    #[test]
    fn the_scan_sees_below_a_slab_and_not_beside_it() {
        // A slab 0.6 m square at 0.45 m, a floor patch 0.3 m square at 0 beside it, and
        // the assumed floor plane (which is not seen).
        let mut cloud = slab(0.45);
        for i in 0..30 {
            for j in 0..30 {
                cloud
                    .points
                    .push(Point3::new(1.0 + i as f64 * 0.01, j as f64 * 0.01, 0.0));
            }
        }
        let s = Scene::new(&cloud, &cfg(true));
        let at = |x: f64, y: f64| s.sees_below(&Point3::new(x, y, 0.8), 0.1);
        assert!(at(0.3, 0.3), "over the slab");
        assert!(at(1.1, 0.1), "over the floor patch");
        assert!(at(0.65, 0.3), "within the reach of the slab's edge");
        assert!(!at(0.8, 0.3), "between them: nothing seen below");
        assert!(!at(0.3, 2.0), "beyond everything");
    }

    #[test]
    fn a_seat_goes_on_through_a_shadow_and_ends_at_a_seen_drop() {
        // A mattress at 0.5 m from x = 0 to 2 m with a strip 0.2 m wide missing at x =
        // 0.4-0.6 (a pillow's shadow); with `floor`, the floor seen under the strip.
        let bed = |floor: bool| {
            let mut pts = Vec::new();
            for i in 0..=200 {
                let x = f64::from(i) * 0.01;
                for j in 0..=40 {
                    let y = f64::from(j) * 0.01;
                    if !(0.4..=0.6).contains(&x) {
                        pts.push(Point3::new(x, y, 0.5));
                    } else if floor {
                        pts.push(Point3::new(x, y, 0.0));
                    }
                }
            }
            Scene::new(&PointCloud::new(pts), &cfg(true))
        };
        let from = Point3::new(0.1, 0.2, 0.6);
        let along = Vector3::x();
        let (shadow, gap) = (bed(false), bed(true));
        // The walk of `surface_ends` stops at the strip either way.
        assert!(shadow.surface_ends(&from, &along, 1.0, 0.2));
        assert!(gap.surface_ends(&from, &along, 1.0, 0.2));
        // Stepping over what was not seen, the mattress goes on past the shadow ...
        assert!(!shadow.seat_ends(&from, &along, 1.0, 0.2));
        // ... but not past a seen drop.
        assert!(gap.seat_ends(&from, &along, 1.0, 0.2));
        // A walk ending in the shadow looks on past it: the mattress is seen beyond.
        assert!(!shadow.seat_ends(&from, &along, 0.45, 0.2));
        // Off the mattress's far edge nothing is seen: the walk ends there, unseen.
        assert!(shadow.seat_ends(&from, &along, 2.5, 0.2));
    }

    /// Points 1 cm apart over x in `xs` and z in `zs` (metres, each from its start while
    /// below its end), y from 0 to 0.4 m: a level strip for a one-step `zs`, an upright
    /// sheet for a one-step `xs`.
    fn sheet(xs: std::ops::Range<f64>, zs: std::ops::Range<f64>, pts: &mut Vec<Point3<f64>>) {
        let mut x = xs.start;
        while x < xs.end {
            let mut z = zs.start;
            while z < zs.end {
                for j in 0..=40 {
                    pts.push(Point3::new(x, f64::from(j) * 0.01, z));
                }
                z += 0.01;
            }
            x += 0.01;
        }
    }

    /// [`sheet`] level at height `z`.
    fn strip(xs: std::ops::Range<f64>, z: f64, pts: &mut Vec<Point3<f64>>) {
        sheet(xs, z..z + 0.005, pts);
    }

    /// [`sheet`] upright on the plane x = `x`.
    fn upright(x: f64, zs: std::ops::Range<f64>, pts: &mut Vec<Point3<f64>>) {
        sheet(x..x + 0.005, zs, pts);
    }

    /// The scene (with the floor) of the points `build` writes.
    fn scene_of(build: impl Fn(&mut Vec<Point3<f64>>)) -> Scene {
        let mut pts = Vec::new();
        build(&mut pts);
        Scene::new(&PointCloud::new(pts), &cfg(true))
    }

    #[test]
    fn past_a_shadow_only_a_surface_with_nothing_over_it_goes_on() {
        // A seat at 0.5 m from x = 0 to 0.4, then nothing seen to x = 0.7 (a shadow);
        // a walk from the pelvis (0.6 m high) to 0.5 m ends in the shadow and looks on.
        let scene = |beyond: &dyn Fn(&mut Vec<Point3<f64>>)| {
            scene_of(|p| {
                strip(0.0..0.4, 0.5, p);
                beyond(p);
            })
        };
        let mattress = scene(&|p| strip(0.7..1.6, 0.45, p));
        let floor = scene(&|p| strip(0.7..1.6, 0.0, p));
        // A wall whose middle the shadow hides: its foot is seen at the seat's level.
        let wall = scene(&|p| {
            upright(0.8, 0.0..0.45, p);
            upright(0.8, 0.9..1.4, p);
        });
        let from = Point3::new(0.1, 0.2, 0.6);
        let along = Vector3::x();
        assert!(!mattress.seat_ends(&from, &along, 0.5, 0.2));
        assert!(floor.seat_ends(&from, &along, 0.5, 0.2));
        assert!(wall.seat_ends(&from, &along, 0.5, 0.2));
        // The wall's top is above the walk; the mattress's is not.
        assert!(!wall.top_at_most(&Point3::new(0.8, 0.2, 0.6), 0.6));
        assert!(mattress.top_at_most(&Point3::new(1.0, 0.2, 0.6), 0.6));
        assert!(
            wall.top_at_most(&Point3::new(1.2, 0.2, 0.6), 0.6),
            "nothing seen"
        );
    }

    #[test]
    fn a_mattress_goes_on_beyond_a_pillows_shadow() {
        // A mattress at 0.5 m from x = 0 to 0.3, a pillow from 0.3 to 0.5 (top 0.65 m),
        // then its shadow to x = 0.8, then whatever `beyond` puts there.
        let scene = |beyond: &dyn Fn(&mut Vec<Point3<f64>>)| {
            scene_of(|p| {
                strip(0.0..0.3, 0.5, p);
                strip(0.3..0.5, 0.65, p);
                upright(0.3, 0.5..0.65, p);
                beyond(p);
            })
        };
        let mattress = scene(&|p| strip(0.8..2.0, 0.5, p));
        let floor = scene(&|p| strip(0.8..2.0, 0.0, p));
        // A wall seen at its foot and its top, the shadow over its middle, crossed at a
        // slant (0.15 m of it along the walk).
        let wall = scene(&|p| {
            for k in 0..15 {
                let x = 0.9 + f64::from(k) * 0.01;
                upright(x, 0.0..0.45, p);
                upright(x, 0.9..1.4, p);
            }
        });
        // From the forearm's top over the pillow, level with the pelvis at 0.6 m.
        let from = Point3::new(0.4, 0.2, 0.7);
        let along = Vector3::x();
        let goes_on = |s: &Scene| s.goes_on_beyond(&from, &along, 0.8, (0.6, 0.2, 0.0), 0.1);
        assert!(goes_on(&mattress), "the mattress is seen beyond the shadow");
        assert!(!goes_on(&floor), "the floor is seen beyond it");
        assert!(!goes_on(&wall), "a wall's foot is no seat");
        // A taller pillow (top 0.75 m) and the mattress beyond it lifted 3 cm above the
        // pelvis by a duvet's lump (its voxels' tops 4 cm): at the seat's level only where
        // a rise is allowed.
        let lumpy = scene_of(|p| {
            strip(0.0..0.3, 0.5, p);
            strip(0.3..0.5, 0.75, p);
            upright(0.3, 0.5..0.75, p);
            strip(0.8..2.0, 0.63, p);
        });
        let from = Point3::new(0.4, 0.2, 0.8);
        let lumps = |rise: f64| lumpy.goes_on_beyond(&from, &along, 0.8, (0.6, 0.2, rise), 0.1);
        assert!(!lumps(0.0), "above the pelvis, without a rise");
        assert!(lumps(0.06), "within a rise of 6 cm");
    }

    fn vertical(x: f64, y: f64, bottom: f64, top: f64, r: f64) -> Cylinder {
        Cylinder {
            joint: 0,
            a: Point3::new(x, y, bottom),
            b: Point3::new(x, y, top),
            radius: r,
        }
    }

    /// Occupied keys of a seeded scene in a box: a slab, a wall, a post, and `strays` lone
    /// cells scattered far apart (so chunks far from everything grow their border).
    fn random_keys(seed: u64, dims: [usize; 3], strays: usize) -> Vec<[i64; 3]> {
        let mut state = seed;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as usize) % n.max(1)
        };
        let mut keys = Vec::new();
        let h = next(dims[2]);
        for x in 3..dims[0] / 2 {
            for y in 5..dims[1] / 3 {
                keys.push([x as i64, y as i64, h as i64]);
            }
        }
        let wx = next(dims[0]);
        for y in 0..dims[1] {
            for z in 0..dims[2] / 2 {
                keys.push([wx as i64, y as i64, z as i64]);
            }
        }
        let (px, py) = (next(dims[0]), next(dims[1]));
        for z in 0..dims[2] {
            keys.push([px as i64, py as i64, z as i64]);
        }
        for _ in 0..strays {
            keys.push([next(dims[0]), next(dims[1]), next(dims[2])].map(|c| c as i64));
        }
        keys.sort_unstable();
        keys.dedup();
        keys
    }

    #[test]
    fn chunked_field_equals_the_dense_transform_bit_for_bit() {
        // Boxes smaller and larger than a chunk, not multiples of it, offset from the
        // origin; sparse scenes (only strays) make chunks grow their border to the box.
        for (seed, dims, strays) in [
            (1u64, [7usize, 5, 3], 0usize),
            (2, [70, 41, 33], 5),
            (3, [150, 97, 40], 0),
            (4, [200, 180, 30], 3),
        ] {
            let mut keys = random_keys(seed, dims, strays);
            if seed == 4 {
                // Only the strays: most cells are far from everything.
                keys.truncate(0);
                keys.extend([[3, 170, 2], [190, 4, 27], [100, 90, 15]]);
            }
            let min = [-13, 7, -2];
            let keys: Vec<[i64; 3]> = keys
                .iter()
                .map(|k| [k[0] + min[0], k[1] + min[1], k[2] + min[2]])
                .collect();
            let want = dense_distances(min, dims, &keys, 0.02);
            let field = DistanceField::with_dense_limit(min, dims, &keys, 0.02, 0);
            assert!(field.dense.is_none());
            let whole = DistanceField::new(min, dims, &keys, 0.02);
            let [nx, ny, nz] = dims;
            let columns = whole.dense.as_ref().unwrap();
            let columns = |o: [usize; 3]| columns.get(&whole, o);
            for y in 0..ny {
                for z in 0..nz {
                    for x in 0..nx {
                        let w = want[(y * nz + z) * nx + x];
                        assert_eq!(columns([x, y, z]).to_bits(), w.to_bits(), "seed {seed}");
                    }
                }
            }
            for y in 0..ny {
                for z in 0..nz {
                    for x in 0..nx {
                        let k = [x as i64 + min[0], y as i64 + min[1], z as i64 + min[2]];
                        let got = field.get(k).unwrap();
                        let w = want[(y * nz + z) * nx + x];
                        assert_eq!(got.to_bits(), w.to_bits(), "seed {seed} at {k:?}");
                        assert_eq!(field.occupied(k), w == 0.0, "seed {seed} at {k:?}");
                        if (x + 3 * y + 7 * z) % 11 == 0 {
                            let alone = field.cell_distance([x, y, z]);
                            assert_eq!(alone.to_bits(), w.to_bits(), "seed {seed} at {k:?}");
                        }
                    }
                }
            }
            assert_eq!(field.get([min[0] - 1, min[1], min[2]]), None);
            // The occupied cells of sub-boxes are the keys inside them.
            for (lo, hi) in [
                ([-20, 0, -5], [100, 300, 100]),
                ([0, 10, 0], [5, 30, 3]),
                ([-13, 7, -2], [-12, 8, -1]),
            ] {
                let mut seen = Vec::new();
                field.any_occupied(lo, hi, |k| {
                    seen.push(k);
                    false
                });
                seen.sort_unstable();
                let inside: Vec<[i64; 3]> = keys
                    .iter()
                    .filter(|k| (0..3).all(|a| k[a] >= lo[a] && k[a] < hi[a]))
                    .copied()
                    .collect();
                assert_eq!(seen, inside, "seed {seed}");
            }
        }
    }

    #[test]
    fn row_table_equals_the_binary_search() {
        for (seed, dims, strays) in [(5u64, [40usize, 33, 21], 4usize), (6, [9, 50, 7], 0)] {
            let keys = random_keys(seed, dims, strays);
            let field = DistanceField::new([0, 0, 0], dims, &keys, 0.02);
            assert!(field.row_table.is_some());
            let ids = (dims[1] * dims[2]) as u64;
            for id in 0..=ids + 2 {
                let want = field.rows.partition_point(|&r| r < id);
                assert_eq!(field.first_row(id), want, "seed {seed} id {id}");
            }
            let searched = DistanceField {
                row_table: None,
                ..DistanceField::new([0, 0, 0], dims, &keys, 0.02)
            };
            for z in 0..dims[2] {
                for y in 0..dims[1] {
                    assert_eq!(field.row(y, z), searched.row(y, z));
                }
                let a: Vec<_> = field.rows_at(z, 3, dims[1] - 2).collect();
                let b: Vec<_> = searched.rows_at(z, 3, dims[1] - 2).collect();
                assert_eq!(a, b, "seed {seed} z {z}");
            }
        }
        assert!(row_table(&[0, 5], ROW_TABLE_ENTRIES + 1).is_none());
        assert_eq!(row_table(&[1, 3], 4), Some(vec![0, 0, 1, 1, 2]));
    }

    /// The transform by brute force: at each position the least of every entry's parabola
    /// (FAR ones included), in the same f32 arithmetic; exact, as the squared distances
    /// are small integers.
    fn edt_1d_brute(f: &[f32], from: usize, d: &mut [f32]) {
        for (q, dq) in d.iter_mut().enumerate() {
            let q = (q + from) as f32;
            *dq = f
                .iter()
                .enumerate()
                .map(|(p, fp)| (q - p as f32) * (q - p as f32) + fp)
                .fold(f32::INFINITY, f32::min);
        }
    }

    #[test]
    fn leaving_far_entries_out_changes_no_bit() {
        let mut state = 99u64;
        let mut next = |n: usize| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 33) as usize) % n.max(1)
        };
        for case in 0..3000 {
            let n = 1 + next(if case % 10 == 0 { 600 } else { 90 });
            // Runs of FAR (empty rows) between squared distances, as the earlier passes leave.
            let far_share = next(10);
            let f: Vec<f32> = (0..n)
                .map(|_| {
                    if next(10) < far_share {
                        FAR
                    } else {
                        let r = next(if case % 3 == 0 { 4 } else { 400 });
                        (r * r) as f32
                    }
                })
                .collect();
            let from = next(n);
            let len = next(n - from + 1);
            let (mut want, mut got) = (vec![-1f32; len], vec![-1f32; len]);
            edt_1d_brute(&f, from, &mut want);
            let (mut v, mut z) = (vec![0usize; n], vec![0f32; n + 1]);
            edt_1d_range(&f, from, &mut got, &mut v, &mut z);
            let bits = |x: &[f32]| x.iter().map(|d| d.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&want), "case {case}: {f:?} from {from}");
        }
    }

    #[test]
    fn one_dimensional_transform_matches_brute_force() {
        let f: Vec<f32> = vec![1e20, 0.0, 1e20, 1e20, 1e20, 4.0, 1e20, 0.0, 1e20];
        let mut d = vec![0.0; f.len()];
        let (mut v, mut z) = (vec![0; f.len()], vec![0.0; f.len() + 1]);
        edt_1d(&f, &mut d, &mut v, &mut z);
        for (q, dq) in d.iter().enumerate() {
            let brute = f
                .iter()
                .enumerate()
                .map(|(p, fp)| (q as f32 - p as f32).powi(2) + fp)
                .fold(f32::INFINITY, f32::min);
            assert_eq!(*dq, brute, "at {q}");
        }
    }

    #[test]
    fn row_shortcut_equals_the_transform_bit_for_bit() {
        const FAR: f32 = 1e20;
        let mut state = 99u64;
        for n in [1usize, 2, 7, 64, 301] {
            for density in [0.0, 0.01, 0.1, 0.5] {
                let mut row: Vec<f32> = (0..n)
                    .map(|_| {
                        state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                        if ((state >> 33) as f64 / (1u64 << 31) as f64) < density {
                            0.0
                        } else {
                            FAR
                        }
                    })
                    .collect();
                let mut want = vec![0.0; n];
                let (mut v, mut z) = (vec![0; n], vec![0.0; n + 1]);
                edt_1d(&row, &mut want, &mut v, &mut z);
                nearest_in_row(&mut row);
                let (got, want): (Vec<u32>, Vec<u32>) = (
                    row.iter().map(|d| d.to_bits()).collect(),
                    want.iter().map(|d| d.to_bits()).collect(),
                );
                assert_eq!(got, want, "n {n}, density {density}");
            }
        }
        // A constant FAR line stays FAR (empty slabs are skipped on that ground).
        let f = vec![FAR; 50];
        let mut d = vec![0.0; 50];
        edt_1d(&f, &mut d, &mut vec![0; 50], &mut vec![0.0; 51]);
        assert!(d.iter().all(|&x| x == FAR));
    }

    #[test]
    fn clearance_is_a_lower_bound_and_tight_far_away() {
        let s = Scene::new(&slab(0.45), &cfg(false));
        // A ball-like short cylinder 0.2 m above the slab: the true gap is about 0.2 - r.
        let c = vertical(0.3, 0.3, 0.65, 0.66, 0.05);
        let gap = s.clearance(&c);
        assert!(gap <= 0.15 + 1e-9, "lower bound: {gap}");
        assert!(gap > 0.15 - 0.06, "not too loose: {gap}");
        assert!(!s.intersects(&c));
    }

    #[test]
    fn exact_test_finds_contact_with_the_slab_and_the_floor() {
        let s = Scene::new(&slab(0.45), &cfg(true));
        // The slab's voxels span z in [0.44, 0.46]: a cylinder reaching down to 0.455 touches.
        assert!(s.intersects(&vertical(0.3, 0.3, 0.455, 0.7, 0.05)));
        assert!(!s.intersects(&vertical(0.3, 0.3, 0.47, 0.7, 0.05)));
        // Off the slab, only the floor: a leg ending 1 cm above it is free, 1 cm below is not.
        assert!(!s.intersects(&vertical(1.5, 1.5, 0.01, 0.4, 0.03)));
        assert!(s.intersects(&vertical(1.5, 1.5, -0.01, 0.4, 0.03)));
        let lying = Cylinder {
            joint: 0,
            a: Point3::new(2.0, 2.0, 0.04),
            b: Point3::new(2.5, 2.0, 0.04),
            radius: 0.05,
        };
        assert!(s.intersects(&lying));
        assert!((s.clearance(&lying) + 0.01).abs() < 1e-9);
    }

    #[test]
    fn chunk_box_equals_parrys_local_aabb() {
        // Key sets on both sides of zero, on and off chunk boundaries, at several voxel sizes.
        for (seed, dims, strays) in [(7u64, [20usize, 9, 17], 3usize), (8, [3, 3, 3], 0)] {
            for (shift, v) in [
                ([-8i64, 0, 5], 0.02f32),
                ([-13, -21, -1], 0.05),
                ([16, 7, -9], 0.003),
            ] {
                let keys: Vec<[i64; 3]> = random_keys(seed, dims, strays)
                    .iter()
                    .map(|k| [0, 1, 2].map(|a| k[a] + shift[a]))
                    .collect();
                let ivs: Vec<IVector> = keys.iter().map(|&k| ivector(k)).collect();
                let want = Voxels::new(Vector::splat(v), &ivs).local_aabb();
                let lo = [0, 1, 2].map(|a| keys.iter().map(|k| k[a]).min().unwrap());
                let hi = [0, 1, 2].map(|a| keys.iter().map(|k| k[a]).max().unwrap());
                let got = parry_chunks_aabb(lo, hi, Vector::splat(v));
                assert_eq!(got.mins.to_array(), want.mins.to_array(), "seed {seed}");
                assert_eq!(got.maxs.to_array(), want.maxs.to_array(), "seed {seed}");
            }
        }
    }

    #[test]
    fn a_read_cell_holds_exactly_the_positions_of_its_key() {
        // Positions on and beside cell faces (both signs, near 0 and far out), keys the
        // positions fall in and keys beside them, huge keys (never held) and NaN: a
        // read cell holds a position exactly when `cell_of` gives its key.
        let mut state = 99u64;
        let mut next = || uniform(&mut state);
        let mut positions = vec![f64::NAN, f64::INFINITY, -0.0, 0.0];
        for _ in 0..30_000 {
            let whole = ((next() - 0.5) * 2e6).round();
            let x = match to_usize(next() * 4.0) {
                0 => whole,
                1 => whole.next_up(),
                2 => whole.next_down(),
                _ => whole + next(),
            };
            positions.push(x);
        }
        for (i, &x) in positions.iter().enumerate() {
            let y = positions[(i * 7 + 3) % positions.len()];
            let z = positions[(i * 13 + 5) % positions.len()];
            let l = Vector3::new(x, y, z);
            let own = cell_of(&l);
            for k in [
                own,
                [own[0] + 1, own[1], own[2]],
                [own[0], own[1] - 1, own[2]],
                [own[0], own[1], own[2] + 1],
                [1 << 52, own[1], own[2]],
                [own[0], -(1 << 53) - 1, own[2]],
            ] {
                let small = k.iter().all(|k| k.abs() < 1 << 52);
                let want = small && l.iter().all(|v| v.is_finite()) && cell_of(&l) == k;
                assert_eq!(ReadCell::new(k, 1.0).holds(&l), want, "{l:?} {k:?}");
            }
        }
    }

    #[test]
    fn three_support_points_give_parrys_aabb() {
        // Cylinders of every orientation, along the grid axes and in the grid planes
        // (where a local direction's component along the axis is zero), at poses as
        // `parry_cylinder` builds them: the box equals parry's (`==`, so up to the sign
        // of zeros) and gives the same voxel range.
        use parry3d::shape::Shape;
        let s = furnished(false);
        let mut state = 777u64;
        let mut next = || uniform(&mut state);
        let size = s.size;
        let range = |b: &Aabb| {
            (
                vect_to_ivect((b.mins / size).floor()),
                vect_to_ivect((b.maxs / size).ceil()),
            )
        };
        let mut zero_component = 0;
        for i in 0..20_000 {
            let a = Point3::new(next() * 2.0 - 1.0, next() * 2.0 - 1.0, next() * 1.5);
            let mut d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * next();
            match i % 5 {
                0 => d = Vector3::ith(i / 5 % 3, d[i / 5 % 3]),
                1 => d[i / 5 % 3] = 0.0,
                _ => {}
            }
            let c = Cylinder {
                joint: 0,
                a,
                b: a + d,
                radius: 0.01 + next() * 0.08,
            };
            let Some((pose, shape)) = s.parry_cylinder(&c) else {
                continue;
            };
            let want = shape.compute_aabb(&pose);
            let got = cylinder_aabb(&shape, &pose);
            assert!(got.mins == want.mins && got.maxs == want.maxs, "{c:?}");
            assert_eq!(range(&got), range(&want), "{c:?}");
            let inv = pose.rotation.inverse();
            zero_component += (0..3)
                .filter(|&k| {
                    let mut e = Vector::ZERO;
                    e[k] = 1.0;
                    (inv * e).y == 0.0
                })
                .count();
        }
        // The fallback to parry's own support point is exercised.
        assert!(zero_component > 0);
    }

    #[test]
    fn field_guided_test_agrees_with_parry_alone() {
        // A slab, a post and a wall; cylinders of every orientation (and along the grid
        // axes), length and radius around them, many grazing: both tests must give the same
        // answer for each.
        let mut pts = slab(0.45).points;
        for k in 0..80 {
            pts.push(Point3::new(0.9, 0.2, k as f64 * 0.01));
            for j in 0..60 {
                pts.push(Point3::new(-0.3, j as f64 * 0.01, k as f64 * 0.01));
            }
        }
        let s = Scene::new(&PointCloud::new(pts), &cfg(false));
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let (mut hits, mut misses) = (0, 0);
        let mut near = NearVoxels::default();
        for i in 0..4000 {
            let a = Point3::new(next() * 1.6 - 0.5, next() * 1.0 - 0.2, next() * 0.9);
            let mut d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * next();
            if i % 4 == 0 {
                // Every fourth along a grid axis (legs hang straight down).
                let k = i / 4 % 3;
                d = Vector3::ith(k, d[k]);
            }
            let c = Cylinder {
                joint: 0,
                a,
                b: a + d,
                radius: 0.01 + next() * 0.08,
            };
            let want = s.intersects_parry(&c);
            assert_eq!(s.intersects(&c), want, "{c:?}");
            let centres = s.clearance_and_centres(&c, &mut Vec::new()).1;
            assert_eq!(s.intersects_near(&c, centres, None), want, "{c:?}");
            // From the voxels kept near the cylinder before, and near one nudged a few
            // millimetres (within the kept box, or filling it anew).
            assert_eq!(
                s.intersects_near(&c, centres, Some(&mut near)),
                want,
                "{c:?}"
            );
            let shift = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.01;
            let moved = Cylinder {
                a: c.a + shift,
                b: c.b + shift,
                ..c
            };
            let moved_want = s.intersects_parry(&moved);
            let centres = s.clearance_and_centres(&moved, &mut Vec::new()).1;
            assert_eq!(
                s.intersects_near(&moved, centres, Some(&mut near)),
                moved_want,
                "{moved:?}"
            );
            if want {
                hits += 1;
            } else {
                misses += 1;
            }
        }
        assert!(hits > 500 && misses > 500, "{hits} hits, {misses} misses");
    }

    #[test]
    fn empty_scene_is_free_but_for_the_floor() {
        let s = Scene::new(&PointCloud::default(), &cfg(true));
        assert!(!s.intersects(&vertical(0.0, 0.0, 0.1, 0.5, 0.05)));
        assert!((s.clearance(&vertical(0.0, 0.0, 0.1, 0.5, 0.05)) - 0.1).abs() < 1e-9);
        assert!((s.surface_distance(&Point3::new(0.0, 0.0, 0.3), 0.1) - 0.2).abs() < 1e-9);
    }

    /// A slab, a post and a wall (as in `field_guided_test_agrees_with_parry_alone`).
    fn furnished(floor: bool) -> Scene {
        let mut pts = slab(0.45).points;
        for k in 0..80 {
            pts.push(Point3::new(0.9, 0.2, k as f64 * 0.01));
            for j in 0..60 {
                pts.push(Point3::new(-0.3, j as f64 * 0.01, k as f64 * 0.01));
            }
        }
        Scene::new(&PointCloud::new(pts), &cfg(floor))
    }

    /// What two scenes hold, for comparing them: the local origin, the voxel count and
    /// bounds, parry's box and the distance field's occupied rows.
    fn contents(s: &Scene) -> String {
        let field = s
            .field
            .as_ref()
            .map(|f| (f.min, f.dims, &f.rows, &f.row_start, &f.xs));
        format!(
            "{:?} {} {:?} {:?} {:?} {}",
            s.origin, s.count, s.occupied, s.parry_aabb, field, s.floor
        )
    }

    /// Points added to a scene give the scene of all the points built at once: inside the
    /// cloud's bounds (merged), beyond them (built anew), on voxels already occupied, and
    /// to a scene without points.
    #[test]
    fn a_scene_with_points_added_is_the_scene_of_all_the_points() {
        let mut state = 3u64;
        for round in 0..40 {
            let n = [0, 1, 500, 4000, 9000][round % 5];
            let cloud: Vec<Point3<f64>> = (0..n)
                .map(|_| {
                    Point3::new(
                        uniform(&mut state) * 2.0 - 1.0,
                        uniform(&mut state) * 1.5,
                        uniform(&mut state) * 0.9,
                    )
                })
                .collect();
            // Inside the bounds (most rounds), some on the cloud's own points, and past
            // them every fourth round.
            let reach = if round % 4 == 3 { 1.6 } else { 0.9 };
            let mut more: Vec<Point3<f64>> = (0..1 + round * 30)
                .map(|_| {
                    Point3::new(
                        (uniform(&mut state) * 2.0 - 1.0) * reach,
                        0.1 + uniform(&mut state) * 1.2,
                        0.05 + uniform(&mut state) * 0.7,
                    )
                })
                .collect();
            more.extend(cloud.iter().step_by(7).copied());
            let mut all = cloud.clone();
            all.extend_from_slice(&more);
            let cloud = PointCloud::new(cloud);
            let c = cfg(round % 2 == 0);
            let added = Scene::new(&cloud, &c).with_points(&cloud, more, &c);
            let at_once = Scene::new(&PointCloud::new(all), &c);
            assert_eq!(contents(&added), contents(&at_once), "{round}");
        }
    }

    /// A seeded uniform number in [0, 1).
    fn uniform(state: &mut u64) -> f64 {
        *state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// [`Scene::clearance`] reading every sample, as before the Lipschitz skips.
    fn clearance_reference(s: &Scene, c: &Cylinder) -> f64 {
        let floor = if s.floor { floor_gap(c) } else { f64::INFINITY };
        if s.field.is_none() {
            return floor;
        }
        let axis = c.b - c.a;
        let len = axis.norm();
        let n = to_usize((len / s.voxel).ceil().max(1.0));
        let best = (0..=n)
            .map(|i| s.point_clearance(&(c.a + axis * (i as f64 / n as f64))))
            .fold(f64::INFINITY, f64::min);
        (best - len / n as f64 / 2.0 - c.radius).min(floor)
    }

    #[test]
    fn clearance_skips_no_nearest_sample_and_its_bound_stays_below() {
        for floor in [false, true] {
            let s = furnished(floor);
            let mut state = 99u64;
            let mut next = || uniform(&mut state);
            let (mut bounded, mut near) = (0, 0);
            let (mut carried, mut tight) = (0, 0);
            for _ in 0..20000 {
                // Around and beyond the field's box (0.2 m past the voxels).
                let a = Point3::new(next() * 2.4 - 0.8, next() * 1.4 - 0.4, next() * 1.4 - 0.2);
                let c = random_cylinder(&mut next, a);
                let g = s.clearance(&c);
                assert_eq!(g.to_bits(), clearance_reference(&s, &c).to_bits(), "{c:?}");
                if let Some(b) = s.clearance_bound(&c, None) {
                    assert!(b <= g, "bound {b} over clearance {g}: {c:?}");
                    bounded += 1;
                    near += usize::from(g - b < 0.1);
                } else {
                    continue;
                }
                // The part turned about a point near it and shifted, by up to a few
                // centimetres: its clearance there against the bound carried from here.
                let pivot = a + Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.6;
                let axis = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5);
                // Half of them by under 2 mm (crossing a cell face moves the sampled
                // cells' distances most for the least motion).
                let scale = if next() < 0.5 { 0.05 } else { 1.0 };
                let angle = next() * next() * 0.1 * scale;
                let shift =
                    Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * next() * 0.04 * scale;
                let turn = nalgebra::Rotation3::from_axis_angle(
                    &nalgebra::Unit::new_normalize(axis),
                    angle,
                );
                let pose = |p: Point3<f64>| pivot + turn * (p - pivot) + shift;
                let moved_part = Cylinder {
                    a: pose(c.a),
                    b: pose(c.b),
                    ..c
                };
                // Every point of the part moves at most the shift plus the angle times
                // its distance from the pivot (an arc is longer than its chord).
                let lever = (c.a - pivot).norm().max((c.b - pivot).norm()) + c.radius;
                let moved = shift.norm() + angle * lever;
                let Some(b) = s.clearance_bound(&moved_part, Some((g, moved))) else {
                    continue;
                };
                let g2 = s.clearance(&moved_part);
                // The same bits with the cells read for the part before it moved.
                let mut read = Vec::new();
                s.clearance_and_centres(&c, &mut read);
                let (fresh, kept) = (
                    s.clearance_and_centres(&moved_part, &mut Vec::new()),
                    s.clearance_and_centres(&moved_part, &mut read),
                );
                assert_eq!(
                    (kept.0.to_bits(), kept.1.to_bits()),
                    (fresh.0.to_bits(), fresh.1.to_bits())
                );
                assert!(b <= g2, "carried {b} over clearance {g2}: {moved_part:?}");
                assert!(
                    carried_bound(&moved_part, g, moved, s.voxel) <= g2,
                    "{moved_part:?}"
                );
                carried += 1;
                tight += usize::from(g2 - carried_bound(&moved_part, g, moved, s.voxel) < 0.06);
            }
            assert!(
                bounded > 5000 && near > 1000,
                "{bounded} bounded, {near} near"
            );
            assert!(
                carried > 4000 && tight > 100,
                "{carried} carried, {tight} tight"
            );
        }
    }

    /// [`Scene::first_contact`] as it was before the clearance bounds: every part's
    /// clearance in order, the exact test where it is not positive.
    fn first_contact_reference(
        s: &Scene,
        mut motion: impl FnMut(f64, &mut Vec<Cylinder>),
        speed: f64,
        resolution: f64,
    ) -> Option<f64> {
        let mut parts = Vec::new();
        let touching = |t: f64| -> (bool, f64) {
            motion(t, &mut parts);
            let mut gap = f64::INFINITY;
            for c in parts.iter() {
                let g = s.clearance(c);
                gap = gap.min(g);
                if g <= 0.0 && s.intersects(c) {
                    return (true, gap);
                }
            }
            (false, gap)
        };
        advance(touching, speed, resolution)
    }

    /// A cylinder from `a` of seeded direction, length (under 0.87 m) and radius.
    fn random_cylinder(next: &mut impl FnMut() -> f64, a: Point3<f64>) -> Cylinder {
        let d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * next();
        Cylinder {
            joint: 0,
            a,
            b: a + d,
            radius: 0.01 + next() * 0.08,
        }
    }

    /// Distance (metres, world) from the segment `a`-`b` to point `p`.
    fn segment_distance(a: Point3<f64>, b: Point3<f64>, p: Point3<f64>) -> f64 {
        let d = b - a;
        let t = if d.norm_squared() > 0.0 {
            ((p - a).dot(&d) / d.norm_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (p - (a + d * t)).norm()
    }

    /// The centres (world frame) of every occupied voxel of `s`.
    fn voxel_centres(s: &Scene) -> Vec<Point3<f64>> {
        let field = s.field.as_ref().unwrap();
        let mut centres = Vec::new();
        let hi = [0, 1, 2].map(|a| field.min[a] + field.dims[a] as i64);
        field.any_occupied(field.min, hi, |k| {
            let l = Vector3::new(k[0] as f64 + 0.5, k[1] as f64 + 0.5, k[2] as f64 + 0.5);
            centres.push(Point3::from(l * s.voxel + s.origin));
            false
        });
        centres
    }

    #[test]
    fn a_turn_within_its_bound_moves_no_point_past_its_clearance() {
        // Over random parts, pivots and rates, a turn of `turn_bound` moves every point of
        // the part (sampled through its volume) by at most the larger of its true
        // distance to every occupied voxel and the resolution.
        let s = furnished(false);
        let centres = voxel_centres(&s);
        let half = s.voxel / 2.0;
        let clearance = |p: Point3<f64>| {
            centres
                .iter()
                .map(|c| (p - c).map(|d| (d.abs() - half).max(0.0)).norm())
                .fold(f64::INFINITY, f64::min)
        };
        let mut state = 17u64;
        let mut next = || uniform(&mut state);
        let resolution = 0.005;
        let mut stepped = 0;
        for _ in 0..400 {
            let a = Point3::new(next() * 1.6 - 0.5, next() * 1.0 - 0.2, next() * 0.9);
            let c = random_cylinder(&mut next, a);
            let pivot = c.a + Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.3;
            let rate = 0.2 + next() * 2.0;
            let time = s.turn_bound(&c, &pivot, rate, resolution, 0.0);
            assert!(time > 0.0, "{c:?}");
            let axis = c.b - c.a;
            // Two directions across the axis.
            let u = axis.cross(&Vector3::new(0.3, 0.5, 0.8)).normalize();
            let w = axis.normalize().cross(&u);
            for _ in 0..40 {
                let (angle, r) = (next() * std::f64::consts::TAU, c.radius * next().sqrt());
                let p = c.a + axis * next() + (u * angle.cos() + w * angle.sin()) * r;
                let moved = rate * time * (p - pivot).norm();
                let room = clearance(p).max(resolution);
                assert!(moved <= room + 1e-9, "{c:?}: {moved} > {room}");
                if moved > resolution {
                    stepped += 1;
                }
            }
        }
        // Most points may move further than the resolution.
        assert!(stepped > 4000, "{stepped}");
    }

    #[test]
    fn centre_bound_is_below_the_nearest_voxel_centre() {
        let s = furnished(false);
        let centres = voxel_centres(&s);
        let mut state = 5u64;
        let mut next = || uniform(&mut state);
        let (mut bounded, mut decided) = (0, 0);
        for _ in 0..3000 {
            let a = Point3::new(next() * 1.6 - 0.5, next() * 1.0 - 0.2, next() * 0.9);
            let c = random_cylinder(&mut next, a);
            let bound = s.clearance_and_centres(&c, &mut Vec::new()).1;
            if bound == f64::NEG_INFINITY {
                continue;
            }
            let want = centres
                .iter()
                .map(|&p| segment_distance(c.a, c.b, p))
                .fold(f64::INFINITY, f64::min);
            assert!(bound <= want, "bound {bound} over {want}: {c:?}");
            bounded += 1;
            decided += usize::from(want - bound < 0.03);
        }
        assert!(
            bounded > 1000 && decided > 300,
            "{bounded} bounded, {decided} tight"
        );
    }

    #[test]
    fn first_contact_equals_testing_every_part_bit_for_bit() {
        for floor in [false, true] {
            let s = furnished(floor);
            let mut state = 7u64;
            let mut next = || uniform(&mut state);
            let (mut hits, mut misses) = (0, 0);
            for case in 0..300 {
                // A body of 2 to 8 parts moved along a straight line from above the scene,
                // every other one turning about a point near it as well.
                let n = 2 + to_usize(next() * 7.0);
                let base = Point3::new(next() * 1.6 - 0.5, next() * 1.0 - 0.2, 0.5 + next());
                let parts: Vec<Cylinder> = (0..n)
                    .map(|j| {
                        let a = base + Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.6;
                        let d = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.6;
                        Cylinder {
                            joint: j,
                            a,
                            b: a + d,
                            radius: 0.02 + next() * 0.08,
                        }
                    })
                    .collect();
                let dir = Vector3::new(next() - 0.5, next() - 0.5, -next() * 2.0);
                let pivot = base + Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5) * 0.4;
                let axis = nalgebra::Unit::new_normalize(Vector3::new(
                    next() - 0.5,
                    next() - 0.5,
                    next() - 0.5,
                ));
                let angle = if case % 2 == 1 {
                    (next() - 0.5) * 3.0
                } else {
                    0.0
                };
                let motion = |t: f64, out: &mut Vec<Cylinder>| {
                    let turn = nalgebra::Rotation3::from_axis_angle(&axis, angle * t);
                    let pose = |p: Point3<f64>| pivot + turn * (p - pivot) + dir * t;
                    out.clear();
                    out.extend(parts.iter().map(|c| Cylinder {
                        a: pose(c.a),
                        b: pose(c.b),
                        ..*c
                    }));
                };
                // The shift, and the turn times the farthest point from the pivot.
                let lever = parts
                    .iter()
                    .map(|c| (c.a - pivot).norm().max((c.b - pivot).norm()) + c.radius)
                    .fold(0.0, f64::max);
                let speed = dir.norm() + angle.abs() * lever;
                let want = first_contact_reference(&s, motion, speed, 0.005);
                let got = s.first_contact(motion, speed, 0.005);
                assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
                if want.is_some() {
                    hits += 1;
                } else {
                    misses += 1;
                }
            }
            assert!(hits > 50 && misses > 20, "{hits} hits, {misses} misses");
        }
    }
}
