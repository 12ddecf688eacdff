//! How densely a cloud samples its surfaces: the side of the patch of surface each point
//! stands for, measured as the median distance from a point to its fourth nearest
//! neighbour (a grid of step s gives s, its four edge neighbours; points strewn at random
//! with density rho give about 1.13 / sqrt(rho), where the nearest neighbour alone would
//! say 0.5 / sqrt(rho)). A depth camera at 1-2 m gives 2-5 mm, a reconstruction read as
//! mesh vertices ~4 cm, a 20k-point room view 5-10 cm; stages that look at cells of a few
//! centimetres use it to tell a hole in a surface from a gap between samples.

use nalgebra::Point3;
use rayon::prelude::*;

use super::PointCloud;
use crate::cellhash::{CellMap, CellSet};
use crate::num::{floor_i64, to_usize};

/// Points whose neighbours [`point_spacing`] measures: evenly spread over the cloud's order.
const QUERIES: usize = 256;
/// Which neighbour's distance is the spacing: the fourth, the edge neighbours of a grid.
const K: usize = 4;
/// Neighbour candidates scanned per query at most (a bound on time for piled-up points);
/// a grid cell keeps no more than this many points (a bound on memory).
const MAX_SCANNED: usize = 5000;
/// Most points (evenly chosen) whose coordinates are sorted for the robust extent: enough
/// for the 1 % and 99 % quantiles to be within a few per cent of the cloud's.
const EXTENT_SAMPLE: usize = 10_000;
/// A [`TileSpacing`] tile with fewer points than this also searches the tiles round it:
/// 64 samples of a surface crossing a tile leave few queries near its border.
const FEW_IN_TILE: usize = 64;
/// Share of the sample left out at each end of every axis: stray points do not size the grid.
const EXTENT_TRIM: f64 = 0.01;

/// The finite points of a cloud and their robust extent.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Extent {
    /// Number of finite points.
    pub n: usize,
    /// Per axis, the [`EXTENT_TRIM`] quantile of up to [`EXTENT_SAMPLE`] evenly chosen
    /// finite points.
    pub lo: Point3<f64>,
    /// Per axis, the 1 - [`EXTENT_TRIM`] quantile of the same points.
    pub hi: Point3<f64>,
}

/// The robust extent of `cloud`; `None` without finite points.
pub(crate) fn robust_extent(cloud: &PointCloud) -> Option<Extent> {
    let finite = |p: &&Point3<f64>| p.coords.iter().all(|c| c.is_finite());
    let n = cloud.points.iter().filter(finite).count();
    if n == 0 {
        return None;
    }
    let step = n.div_ceil(EXTENT_SAMPLE);
    let sample: Vec<&Point3<f64>> = cloud.points.iter().filter(finite).step_by(step).collect();
    let cut = to_usize(sample.len() as f64 * EXTENT_TRIM);
    let mut lo = Point3::origin();
    let mut hi = Point3::origin();
    for axis in 0..3 {
        let mut v: Vec<f64> = sample.iter().map(|p| p[axis]).collect();
        // The values at two ranks of the sorted order (`total_cmp` orders every f64, and
        // values it calls equal have the same bits): found by selection, not a sort.
        let top = v.len() - 1 - cut;
        lo[axis] = *v.select_nth_unstable_by(cut, f64::total_cmp).1;
        hi[axis] = *v.select_nth_unstable_by(top, f64::total_cmp).1;
    }
    Some(Extent { n, lo, hi })
}

/// Median distance (in the cloud's units) from up to [`QUERIES`] points, chosen evenly by
/// index, to their [`K`]-th nearest neighbour; `None` for fewer than two finite points.
pub fn point_spacing(cloud: &PointCloud) -> Option<f64> {
    neighbour_distance(cloud, &robust_extent(cloud)?, K, QUERIES)
}

/// Lower median distance from up to `queries` finite points of `cloud` (of robust extent
/// `extent`), chosen evenly by index, to their `k`-th nearest neighbour; `None` for fewer
/// than two finite points.
///
/// The search grid is sized from the robust extent (so stray points do not matter) and
/// the point count (twice the spacing of the points spread evenly over the extent's
/// diagonal square), so it is scale-free; only the grid cells around the query points
/// are stored, each with at most [`MAX_SCANNED`] points, so memory follows the queries,
/// not the cloud. A neighbour not found in the query's 27 cells counts as one cell apart.
pub(crate) fn neighbour_distance(
    cloud: &PointCloud,
    extent: &Extent,
    k: usize,
    queries: usize,
) -> Option<f64> {
    let Extent { n, lo, hi } = *extent;
    if n < 2 || k == 0 {
        return None;
    }
    let cell = 2.0 * (hi - lo).norm() / (n as f64).sqrt();
    if !(cell.is_finite() && cell > 0.0) {
        // Every point at one place.
        return Some(0.0);
    }
    let key = |p: &Point3<f64>| -> Option<[i64; 3]> {
        let k = [
            (p.x - lo.x) / cell,
            (p.y - lo.y) / cell,
            (p.z - lo.z) / cell,
        ];
        // Cells of a finite box over a finite cell are bounded: 2 sqrt(n) per axis at most.
        k.iter()
            .all(|v| v.is_finite() && v.abs() < 1e15)
            .then(|| k.map(floor_i64))
    };
    let step = n.div_ceil(queries.max(1));
    let queries: Vec<(usize, Point3<f64>)> = cloud
        .points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.coords.iter().all(|c| c.is_finite()))
        .step_by(step)
        .map(|(i, p)| (i, *p))
        .collect();
    let mut wanted: CellSet<[i64; 3]> = CellSet::default();
    for (_, q) in &queries {
        let Some(c) = key(q) else { continue };
        for d in neighbourhood() {
            wanted.insert([c[0] + d[0], c[1] + d[1], c[2] + d[2]]);
        }
    }
    let mut grid: CellMap<[i64; 3], Vec<usize>> = CellMap::default();
    // Whether the last cell looked up is wanted: a run of points in one cell (as a depth
    // image's rows give) looks it up once.
    let mut last: Option<([i64; 3], bool)> = None;
    for (i, p) in cloud.points.iter().enumerate() {
        let Some(c) = key(p) else { continue };
        let want = match last {
            Some((lc, w)) if lc == c => w,
            _ => {
                let w = wanted.contains(&c);
                last = Some((c, w));
                w
            }
        };
        if want {
            let list = grid.entry(c).or_default();
            if list.len() <= MAX_SCANNED {
                list.push(i);
            }
        }
    }
    // The k smallest distances of a query so far, ascending.
    let mut best = vec![f64::INFINITY; k];
    let mut dists: Vec<f64> = queries
        .iter()
        .map(|(qi, q)| {
            let Some(c) = key(q) else { return cell };
            best.fill(f64::INFINITY);
            let mut scanned = 0usize;
            'cells: for d in neighbourhood() {
                let Some(list) = grid.get(&[c[0] + d[0], c[1] + d[1], c[2] + d[2]]) else {
                    continue;
                };
                for &j in list {
                    if j != *qi {
                        let d = (cloud.points[j] - q).norm();
                        if d < best[k - 1] {
                            best[k - 1] = d;
                            best.sort_by(f64::total_cmp);
                        }
                    }
                    scanned += 1;
                    if scanned > MAX_SCANNED {
                        break 'cells;
                    }
                }
            }
            best[k - 1].min(cell)
        })
        .collect();
    dists.sort_by(f64::total_cmp);
    Some(dists[(dists.len() - 1) / 2])
}

/// The point spacing of each cube tile of space (`tile` metres, from a corner): the
/// median distance to the [`K`]-th nearest neighbour over up to
/// `queries` points of the tile, chosen evenly by index. Surfaces of one cloud are sampled
/// at different densities (a depth camera's density falls with the square of the range; a
/// decimated mesh keeps few vertices on flat parts), so a stage that must tell a hole
/// from a gap between samples asks the spacing where it looks. Tiles are cubes, not
/// columns, so that a seat and the floor seen under it are measured apart. A tile with
/// fewer than K + 1 points has none.
#[derive(Debug, Clone, PartialEq)]
pub struct TileSpacing {
    lo: Point3<f64>,
    tile: f64,
    /// The spacing of each tile that has one, by tile key; tiles without points are not
    /// stored, so memory follows the points, not the cloud's box.
    values: CellMap<[i64; 3], f64>,
}

impl TileSpacing {
    /// Measures the spacing of every tile of `cloud` (world frame, metres) in cubes of
    /// `tile` metres from the corner `lo`.
    pub fn new(cloud: &PointCloud, lo: Point3<f64>, tile: f64, queries: usize) -> TileSpacing {
        let mut out = TileSpacing {
            lo,
            tile,
            values: CellMap::default(),
        };
        // Visited in the map's order, but each tile's value depends on its own points only.
        let mut members: CellMap<[i64; 3], Vec<usize>> = CellMap::default();
        // A run of points in one tile (as a depth image's rows give) is added at once, in
        // order: each tile lists its points by index, as adding them one by one does.
        let mut run: Option<([i64; 3], usize)> = None;
        for (i, p) in cloud.points.iter().enumerate() {
            let k = out.key(p);
            if matches!(run, Some((rk, _)) if k == Some(rk)) {
                continue;
            }
            if let Some((rk, from)) = run.take() {
                members.entry(rk).or_default().extend(from..i);
            }
            run = k.map(|k| (k, i));
        }
        if let Some((rk, from)) = run {
            members.entry(rk).or_default().extend(from..cloud.len());
        }
        // The K-th nearest neighbour of each query among its tile's points; a tile of few
        // points (a sparse patch, whose edge queries would find their neighbours farther
        // inside the tile than across its border) looks in the 26 tiles round it too.
        // Each tile's value depends on the points only, so the tiles are measured in
        // parallel and the values inserted in the map's order, as one by one.
        let tiles: Vec<(&[i64; 3], &Vec<usize>)> =
            members.iter().filter(|(_, m)| m.len() > K).collect();
        let values: Vec<f64> = tiles
            .par_iter()
            .map_init(Vec::new, |near: &mut Vec<Point3<f64>>, &(k, m)| {
                near.clear();
                // Where the tile's own points start in `near`.
                let mut own = 0;
                if m.len() < FEW_IN_TILE {
                    for o in neighbourhood() {
                        if let Some(n) = members.get(&[k[0] + o[0], k[1] + o[1], k[2] + o[2]]) {
                            if o == [0, 0, 0] {
                                own = near.len();
                            }
                            near.extend(n.iter().map(|&j| cloud.points[j]));
                        }
                    }
                } else {
                    near.extend(m.iter().map(|&j| cloud.points[j]));
                }
                let step = m.len().div_ceil(queries.max(1));
                let mut kth: Vec<f64> = (0..m.len())
                    .step_by(step)
                    .map(|q| kth_nearest_of(near, own + q))
                    .collect();
                kth.sort_by(f64::total_cmp);
                kth[(kth.len() - 1) / 2]
            })
            .collect();
        for (&(k, _), v) in tiles.iter().zip(values) {
            out.values.insert(*k, v);
        }
        out
    }

    /// The key of the tile holding `p`; `None` for a point that is not finite.
    fn key(&self, p: &Point3<f64>) -> Option<[i64; 3]> {
        let f = (p - self.lo) / self.tile;
        f.iter()
            .all(|v| v.is_finite())
            .then(|| [floor_i64(f.x), floor_i64(f.y), floor_i64(f.z)])
    }

    /// The largest spacing of any tile, if any had enough points.
    pub fn widest(&self) -> Option<f64> {
        self.values.values().copied().reduce(f64::max)
    }

    /// The spacing of the tile holding `p`, if it had enough points.
    pub fn at(&self, p: &Point3<f64>) -> Option<f64> {
        self.values.get(&self.key(p)?).copied()
    }

    /// [`TileSpacing::at`] of each of `points`, in order: a run of points in one tile (as
    /// a depth image's rows give) looks its tile up once.
    pub fn at_each<'a>(
        &'a self,
        points: &'a [Point3<f64>],
    ) -> impl Iterator<Item = Option<f64>> + 'a {
        let mut last: Option<([i64; 3], Option<f64>)> = None;
        points.iter().map(move |p| {
            let k = self.key(p)?;
            match last {
                Some((lk, v)) if lk == k => v,
                _ => {
                    let v = self.values.get(&k).copied();
                    last = Some((k, v));
                    v
                }
            }
        })
    }
}

/// The [`K`]-th smallest length of `offsets` (at least [`K`] of them; infinity with
/// fewer): the `K` smallest squared lengths are kept in order as they come, and the root
/// taken of the last. The same value as sorting the lengths (`norm`, the root of
/// `norm_squared`) and taking the `K`-th, since the root is monotonic, without holding
/// or partitioning a distance per offset. (The reference for [`kth_nearest_of`].)
#[cfg(test)]
fn kth_nearest(offsets: impl Iterator<Item = nalgebra::Vector3<f64>>) -> f64 {
    let mut best = [f64::INFINITY; K];
    for v in offsets {
        let s = v.norm_squared();
        if s < best[K - 1] {
            let mut i = K - 1;
            while i > 0 && best[i - 1] > s {
                best[i] = best[i - 1];
                i -= 1;
            }
            best[i] = s;
        }
    }
    best[K - 1].sqrt()
}

/// The [`K`]-th smallest distance from `points[at]` to the other `points` (infinity with
/// fewer than [`K`] others): [`kth_nearest`] of their offsets, bit for bit, without the
/// squared length of the points farther along x alone than the `K`-th smallest so far.
/// The squared length of an offset is the rounded sum of three non-negative squares, so at
/// least its x square: such a point would not enter the `K` smallest (a length equal to
/// the `K`-th does not either), and the `K` smallest of a set do not depend on the order
/// they come in.
fn kth_nearest_of(points: &[Point3<f64>], at: usize) -> f64 {
    let Some(&qp) = points.get(at) else {
        return f64::INFINITY;
    };
    let mut best = [f64::INFINITY; K];
    for (j, p) in points.iter().enumerate() {
        let dx = p.x - qp.x;
        if dx * dx >= best[K - 1] || j == at {
            continue;
        }
        let s = (p - qp).norm_squared();
        if s < best[K - 1] {
            let mut i = K - 1;
            while i > 0 && best[i - 1] > s {
                best[i] = best[i - 1];
                i -= 1;
            }
            best[i] = s;
        }
    }
    best[K - 1].sqrt()
}

fn neighbourhood() -> impl Iterator<Item = [i64; 3]> {
    (-1..=1).flat_map(|x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| [x, y, z])))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(step: f64, n: usize) -> PointCloud {
        let mut pts = Vec::new();
        for i in 0..n {
            for j in 0..n {
                pts.push(Point3::new(i as f64 * step, j as f64 * step, 0.45));
            }
        }
        PointCloud::new(pts)
    }

    #[test]
    fn a_regular_grid_gives_its_step() {
        for step in [0.005, 0.04, 0.1] {
            let s = point_spacing(&grid(step, 60)).unwrap();
            assert!((s - step).abs() < 1e-9, "step {step}: {s}");
        }
    }

    #[test]
    fn scale_free_and_stray_points_do_not_matter() {
        let mut c = grid(0.04, 60);
        c.points.push(Point3::new(1e4, -3e4, 50.0));
        let s = point_spacing(&c).unwrap();
        assert!((s - 0.04).abs() < 1e-9, "{s}");
        let mm = PointCloud::new(c.points.iter().map(|p| p * 1000.0).collect());
        assert!((point_spacing(&mm).unwrap() - 40.0).abs() < 1e-6);
    }

    #[test]
    fn degenerate_clouds() {
        assert_eq!(point_spacing(&PointCloud::default()), None);
        let one = PointCloud::new(vec![Point3::new(1.0, 2.0, 3.0)]);
        assert_eq!(point_spacing(&one), None);
        let same = PointCloud::new(vec![Point3::new(1.0, 2.0, 3.0); 5]);
        assert_eq!(point_spacing(&same), Some(0.0));
        let nan = PointCloud::new(vec![
            Point3::new(f64::NAN, 0.0, 0.0),
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 0.0, 0.5),
        ]);
        // Fewer than K neighbours: the missing ones count as a grid cell (here the whole
        // extent, 0.5, doubled over sqrt(2) points) apart.
        let s = point_spacing(&nan).unwrap();
        assert!((s - 2.0 * 0.5 / 2f64.sqrt()).abs() < 1e-9, "{s}");
    }

    #[test]
    fn tiles_measure_each_surface_at_its_own_density() {
        // A floor sampled every 1 cm and a seat 0.45 m above it every 7 cm, over the same
        // x-y square: each 0.25 m tile says its own surface's step.
        let mut pts = grid(0.01, 100).points;
        for p in &mut pts {
            p.z = 0.0;
        }
        pts.extend(grid(0.07, 14).points);
        let c = PointCloud::new(pts);
        let t = TileSpacing::new(&c, Point3::new(0.0, 0.0, 0.0), 0.25, 16);
        let floor = t.at(&Point3::new(0.5, 0.5, 0.0)).unwrap();
        let seat = t.at(&Point3::new(0.5, 0.5, 0.45)).unwrap();
        assert!((floor - 0.01).abs() < 1e-9, "{floor}");
        assert!((seat - 0.07).abs() < 1e-9, "{seat}");
        // At the seat's corners the fourth neighbour is a diagonal one.
        let widest = t.widest().unwrap();
        assert!(
            widest >= seat && widest <= seat * 2f64.sqrt() + 1e-9,
            "{widest}"
        );
        // The cloud's median is the floor's.
        assert!((point_spacing(&c).unwrap() - 0.01).abs() < 1e-9);
        // Looked up per point, runs of one tile once: the same as `at` of each.
        let mut pts = c.points.clone();
        pts.push(Point3::new(f64::NAN, 0.0, 0.0));
        pts.extend(c.points.iter().rev().step_by(7));
        let each: Vec<Option<f64>> = pts.iter().map(|p| t.at(p)).collect();
        assert_eq!(t.at_each(&pts).collect::<Vec<_>>(), each);
    }

    #[test]
    fn random_samples_give_the_side_of_their_share_of_the_surface() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        // 10 000 points on a 4 x 4 m floor: 625 per m2, 4 cm squares each.
        let pts = (0..10_000)
            .map(|_| Point3::new(rng.random_range(0.0..4.0), rng.random_range(0.0..4.0), 0.0))
            .collect();
        let s = point_spacing(&PointCloud::new(pts)).unwrap();
        assert!((0.040..0.050).contains(&s), "{s}");
    }

    /// `kth_nearest` against the straightforward computation it replaced (every length
    /// with `norm`, then the `K`-th by `select_nth_unstable_by`), bit for bit, on seeded
    /// offsets: continuous ones and ones on a coarse lattice (many ties, zero lengths).
    #[test]
    fn kth_nearest_is_the_kth_smallest_length() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        for round in 0..2000 {
            let n = rng.random_range(K..60);
            let lattice = round % 2 == 0;
            let offsets: Vec<nalgebra::Vector3<f64>> = (0..n)
                .map(|_| {
                    let mut c = || {
                        let v: f64 = rng.random_range(-0.3..0.3);
                        if lattice {
                            (v * 20.0).round() * 0.05
                        } else {
                            v
                        }
                    };
                    nalgebra::Vector3::new(c(), c(), c())
                })
                .collect();
            let mut d: Vec<f64> = offsets.iter().map(|v| v.norm()).collect();
            let want = *d.select_nth_unstable_by(K - 1, f64::total_cmp).1;
            let got = kth_nearest(offsets.into_iter());
            assert_eq!(got.to_bits(), want.to_bits(), "round {round}");
        }
    }

    /// `kth_nearest_of` against `kth_nearest` of every other point's offset, bit for bit,
    /// on seeded sets: continuous ones, ones on a coarse lattice (ties, repeated points,
    /// equal x), and sets of fewer than `K + 1` points (infinity).
    #[test]
    fn kth_nearest_of_skips_no_nearer_point() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(13);
        for round in 0..3000 {
            let n = rng.random_range(1..80);
            let lattice = round % 2 == 0;
            let points: Vec<Point3<f64>> = (0..n)
                .map(|_| {
                    let mut c = || {
                        let v: f64 = rng.random_range(-0.3..0.3);
                        if lattice {
                            (v * 10.0).round() * 0.1
                        } else {
                            v
                        }
                    };
                    Point3::new(c(), c(), c())
                })
                .collect();
            for at in 0..n {
                let want = kth_nearest((0..n).filter(|&j| j != at).map(|j| points[j] - points[at]));
                assert_eq!(
                    kth_nearest_of(&points, at).to_bits(),
                    want.to_bits(),
                    "{round}"
                );
            }
        }
        assert_eq!(kth_nearest_of(&[], 0), f64::INFINITY);
    }
}
