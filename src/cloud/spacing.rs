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
/// Positions of a tile's point list round a query that [`TileSpacing::above`] searches
/// first for the `K` neighbours that make its spacing small: a depth image lists a
/// point's row neighbours next to it, and a scan's points come in runs along a surface.
const NEARBY: usize = 8;
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
    // Counted in parallel; when every point is finite (as every cloud read is), the
    // sample is every `step`-th point, without filtering them again.
    let n = cloud.points.par_iter().filter(finite).count();
    if n == 0 {
        return None;
    }
    let step = n.div_ceil(EXTENT_SAMPLE);
    let sample: Vec<&Point3<f64>> = if n == cloud.len() {
        cloud.points.iter().step_by(step).collect()
    } else {
        cloud.points.iter().filter(finite).step_by(step).collect()
    };
    let cut = to_usize(sample.len() as f64 * EXTENT_TRIM);
    // The axes side by side: per axis, the values at two ranks of the sorted order
    // (`total_cmp` orders every f64, and values it calls equal have the same bits),
    // found by selection, not a sort.
    let ranks: Vec<(f64, f64)> = (0..3)
        .into_par_iter()
        .map(|axis| {
            let mut v: Vec<f64> = sample.iter().map(|p| p[axis]).collect();
            let top = v.len() - 1 - cut;
            let lo = *v.select_nth_unstable_by(cut, f64::total_cmp).1;
            (lo, *v.select_nth_unstable_by(top, f64::total_cmp).1)
        })
        .collect();
    let lo = Point3::new(ranks[0].0, ranks[1].0, ranks[2].0);
    let hi = Point3::new(ranks[0].1, ranks[1].1, ranks[2].1);
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
        TileSpacing::measure(cloud, lo, tile, queries, None)
    }

    /// [`TileSpacing::new`] without the tiles whose spacing is `small`: [`TileSpacing::at`]
    /// answers `None` for them, as for a tile of too few points, and every other tile has
    /// the value [`TileSpacing::new`] gives it, bit for bit. `small` must hold on a
    /// down-set (if it holds for a length, it holds for every shorter one, down to 0):
    /// then a tile's median is small when more than half of its queries' `K`-th
    /// distances are, and a query's is small as soon as `K` of its neighbours are found
    /// at a small distance, so a densely sampled tile is decided from a few neighbours
    /// of each query (visited outwards from the query in the cloud's order, where a depth
    /// image's row neighbours are) instead of a scan of every point of the tile.
    pub fn above(
        cloud: &PointCloud,
        lo: Point3<f64>,
        tile: f64,
        queries: usize,
        small: &(dyn Fn(f64) -> bool + Sync),
    ) -> TileSpacing {
        TileSpacing::measure(cloud, lo, tile, queries, Some(small))
    }

    /// [`TileSpacing::new`] (`small` of `None`) or [`TileSpacing::above`].
    fn measure(
        cloud: &PointCloud,
        lo: Point3<f64>,
        tile: f64,
        queries: usize,
        small: Option<&(dyn Fn(f64) -> bool + Sync)>,
    ) -> TileSpacing {
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
        let values: Vec<Option<f64>> = tiles
            .par_iter()
            .map_init(Vec::new, |ids: &mut Vec<usize>, &(k, m)| {
                // The indices of the points searched: the tile's own, or those of the 27
                // tiles round it, the tile's own from `own` on.
                ids.clear();
                let mut own = 0;
                let near: &[usize] = if m.len() < FEW_IN_TILE {
                    for o in neighbourhood() {
                        if let Some(n) = members.get(&[k[0] + o[0], k[1] + o[1], k[2] + o[2]]) {
                            if o == [0, 0, 0] {
                                own = ids.len();
                            }
                            ids.extend_from_slice(n);
                        }
                    }
                    ids
                } else {
                    m
                };
                let step = m.len().div_ceil(queries.max(1));
                let at = (0..m.len()).step_by(step).map(|q| own + q);
                match small {
                    None => {
                        let near: Vec<Point3<f64>> =
                            near.iter().map(|&j| cloud.points[j]).collect();
                        let mut kth: Vec<f64> = at.map(|q| kth_nearest_of(&near, q)).collect();
                        kth.sort_by(f64::total_cmp);
                        Some(kth[(kth.len() - 1) / 2])
                    }
                    Some(small) => median_above(&cloud.points, near, at, small),
                }
            })
            .collect();
        for (&(k, _), v) in tiles.iter().zip(values) {
            if let Some(v) = v {
                out.values.insert(*k, v);
            }
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

/// Keeps `s` among the [`K`] smallest squared lengths so far, `best` (ascending), when it
/// is smaller than the largest of them; a value equal to it does not enter.
#[inline]
fn keep_smallest(best: &mut [f64; K], s: f64) {
    if s < best[K - 1] {
        let mut i = K - 1;
        while i > 0 && best[i - 1] > s {
            best[i] = best[i - 1];
            i -= 1;
        }
        best[i] = s;
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
        keep_smallest(&mut best, s);
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
        keep_smallest(&mut best, s);
    }
    best[K - 1].sqrt()
}

/// Among the points `near` (indices into `points`), the lower median of the
/// [`kth_nearest_of`] distances of the queries `at` (positions in `near`), or `None`
/// when it is `small` (a predicate true on a down-set): the same median as sorting them
/// all, bit for bit. Every small distance is shorter than every other, so the median is
/// small when more than half of the queries are, and is otherwise the one at its rank
/// among the others once the small ones are counted; a query found small among its
/// neighbours in `near` ([`small_nearby`]) needs no exact distance, the others are
/// measured by [`kth_nearest_of`] over a copy of the points.
fn median_above(
    points: &[Point3<f64>],
    near: &[usize],
    at: impl ExactSizeIterator<Item = usize>,
    small: &dyn Fn(f64) -> bool,
) -> Option<f64> {
    let rank = (at.len().max(1) - 1) / 2;
    let mut below = 0usize;
    let mut rest: Vec<f64> = Vec::new();
    // The points of `near`, copied when a query first needs the full search.
    let mut copy: Vec<Point3<f64>> = Vec::new();
    for q in at {
        // After a query that is not small, the tile is taken for a sparse one and the
        // search nearby is left out: it would seldom find a small query there.
        let try_nearby = rest.is_empty();
        let exact = if try_nearby && small_nearby(points, near, q, small) {
            None
        } else {
            if copy.is_empty() {
                copy.extend(near.iter().filter_map(|&j| points.get(j)));
            }
            let d = kth_nearest_of(&copy, q);
            (!small(d)).then_some(d)
        };
        match exact {
            None => {
                below += 1;
                if below > rank {
                    return None;
                }
            }
            Some(d) => rest.push(d),
        }
    }
    rest.sort_by(f64::total_cmp);
    rest.get(rank - below).copied()
}

/// Whether the [`kth_nearest_of`] distance of the point at position `at` of `near`
/// (indices into `points`) is `small` (a predicate true on a down-set), as found among
/// the [`NEARBY`] positions of `near` round it: `true` when it is small, `false` when
/// it is not or was not found so. The `K`-th smallest distance among some of the points
/// is at least that among all, so when it is small, the one among all is too; the
/// positions nearest `at` are where a depth image's row neighbours are.
fn small_nearby(
    points: &[Point3<f64>],
    near: &[usize],
    at: usize,
    small: &dyn Fn(f64) -> bool,
) -> bool {
    let Some(&qp) = near.get(at).and_then(|&i| points.get(i)) else {
        return false;
    };
    let mut best = [f64::INFINITY; K];
    let from = at.saturating_sub(NEARBY / 2);
    let to = (from + NEARBY + 1).min(near.len());
    for (j, &i) in near[from..to].iter().enumerate() {
        let Some(p) = points.get(i) else { continue };
        if from + j != at {
            keep_smallest(&mut best, (p - qp).norm_squared());
        }
    }
    small(best[K - 1].sqrt())
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

    /// The robust extent (points counted in parallel, axes side by side, the sample
    /// taken without a filter when every point is finite) against sorting each axis of
    /// the filtered sample, bit for bit, at 1 and 2 threads: 40k points (a sample of
    /// every fourth), with and without points that are not finite.
    #[test]
    fn robust_extent_is_the_sorted_samples_quantiles() {
        use crate::cellhash::on_threads;
        let mut c = grid(0.01, 200);
        for (i, p) in c.points.iter_mut().enumerate() {
            p.z += (i % 7) as f64 * 0.013 - (i % 11) as f64 * 0.007;
        }
        let mut nan = c.clone();
        for i in (0..nan.len()).step_by(997) {
            nan.points[i].y = if i % 2 == 0 { f64::NAN } else { f64::INFINITY };
        }
        for cloud in [&c, &nan] {
            let finite: Vec<&Point3<f64>> = cloud
                .points
                .iter()
                .filter(|p| p.coords.iter().all(|v| v.is_finite()))
                .collect();
            let sample: Vec<&Point3<f64>> = finite
                .iter()
                .copied()
                .step_by(finite.len().div_ceil(EXTENT_SAMPLE))
                .collect();
            let cut = to_usize(sample.len() as f64 * EXTENT_TRIM);
            let (mut lo, mut hi) = (Point3::origin(), Point3::origin());
            for axis in 0..3 {
                let mut v: Vec<f64> = sample.iter().map(|p| p[axis]).collect();
                v.sort_by(f64::total_cmp);
                lo[axis] = v[cut];
                hi[axis] = v[v.len() - 1 - cut];
            }
            let want = Extent {
                n: finite.len(),
                lo,
                hi,
            };
            for threads in [1, 2] {
                let got = on_threads(threads, || robust_extent(cloud)).unwrap();
                assert_eq!(got.n, want.n);
                assert_eq!(
                    got.lo.coords.map(f64::to_bits),
                    want.lo.coords.map(f64::to_bits)
                );
                assert_eq!(
                    got.hi.coords.map(f64::to_bits),
                    want.hi.coords.map(f64::to_bits)
                );
            }
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
            let offsets: Vec<nalgebra::Vector3<f64>> =
                random_points(&mut rng, n, lattice.then_some(20.0))
                    .into_iter()
                    .map(|p| p.coords)
                    .collect();
            let mut d: Vec<f64> = offsets.iter().map(|v| v.norm()).collect();
            let want = *d.select_nth_unstable_by(K - 1, f64::total_cmp).1;
            let got = kth_nearest(offsets.into_iter());
            assert_eq!(got.to_bits(), want.to_bits(), "round {round}");
        }
    }

    /// `n` seeded points in a 0.6 m cube centred on the origin, continuous or, with
    /// `lattice`, rounded to a lattice of that many steps per metre (ties, repeated
    /// points, equal x).
    fn random_points(
        rng: &mut rand_chacha::ChaCha8Rng,
        n: usize,
        lattice: Option<f64>,
    ) -> Vec<Point3<f64>> {
        use rand::RngExt;
        (0..n)
            .map(|_| {
                let mut c = || {
                    let v: f64 = rng.random_range(-0.3..0.3);
                    match lattice {
                        Some(per) => (v * per).round() * (1.0 / per),
                        None => v,
                    }
                };
                Point3::new(c(), c(), c())
            })
            .collect()
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
            let points: Vec<Point3<f64>> = random_points(&mut rng, n, lattice.then_some(10.0));
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

    /// `small_nearby` (small only when the full search says so) and `median_above`
    /// against `kth_nearest_of` and the sorted median, bit for bit, on seeded sets (continuous, on a lattice with ties and
    /// repeated points, in a shuffled and in a sorted order, with a subset as `near`)
    /// and thresholds below, inside and above their distances (`<` and `<=`).
    #[test]
    fn searches_that_stop_at_small_distances_agree_with_the_full_ones() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(17);
        let (mut small_seen, mut exact_seen, mut nearby_seen) = (0, 0, 0);
        for round in 0..600 {
            let n = rng.random_range(1..90);
            let lattice = round % 3 == 0;
            let mut points: Vec<Point3<f64>> = random_points(&mut rng, n, lattice.then_some(10.0));
            if round % 2 == 0 {
                points.sort_by(|a, b| a.x.total_cmp(&b.x));
            }
            let near: Vec<usize> = (0..n).filter(|j| round % 5 != 0 || j % 4 != 1).collect();
            let pts: Vec<Point3<f64>> = near.iter().map(|&j| points[j]).collect();
            let thr = [0.0, 0.02, 0.05, 0.1, 0.2, 1.0][round % 6];
            let lt = move |d: f64| d < thr;
            let le = move |d: f64| d <= thr;
            for small in [&lt as &dyn Fn(f64) -> bool, &le] {
                let mut all = Vec::new();
                for at in 0..near.len() {
                    let want = kth_nearest_of(&pts, at);
                    if small_nearby(&points, &near, at, small) {
                        assert!(small(want), "{round} {at}");
                        nearby_seen += 1;
                    }
                    if small(want) {
                        small_seen += 1;
                    } else {
                        exact_seen += 1;
                    }
                    all.push(want);
                }
                let step = rng.random_range(1..4);
                let at = (0..near.len()).step_by(step);
                let mut kth: Vec<f64> = at.clone().map(|q| all[q]).collect();
                if kth.is_empty() {
                    continue;
                }
                kth.sort_by(f64::total_cmp);
                let want = kth[(kth.len() - 1) / 2];
                let got = median_above(&points, &near, at, small);
                assert_eq!(
                    got.map(f64::to_bits),
                    (!small(want)).then_some(want.to_bits()),
                    "{round}"
                );
            }
        }
        assert!(
            small_seen > 1000 && exact_seen > 1000 && nearby_seen > 1000,
            "{small_seen} {exact_seen} {nearby_seen}"
        );
    }

    /// `TileSpacing::above` holds exactly the tiles of `TileSpacing::new` whose spacing is
    /// not small, with the same values, bit for bit: a depth-image-like cloud (rows of a
    /// dense floor and a sparse seat), a shuffled one, and few points per tile.
    #[test]
    fn tiles_above_a_threshold_keep_their_values() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(19);
        let mut left_out = 0;
        for round in 0..8 {
            let mut pts = grid([0.004, 0.01][round % 2], 120).points;
            for p in &mut pts {
                p.z = 0.0;
            }
            pts.extend(grid(0.05, 12).points);
            pts.extend(
                grid(0.03, 5)
                    .points
                    .iter()
                    .map(|p| p + nalgebra::Vector3::new(2.0, 0.0, 0.0)),
            );
            for p in &mut pts {
                let j = rng.random_range(-0.001..0.001);
                *p += nalgebra::Vector3::new(j, -j, 0.5 * j);
            }
            if round >= 4 {
                for i in (1..pts.len()).rev() {
                    pts.swap(i, rng.random_range(0..=i));
                }
            }
            let c = PointCloud::new(pts);
            let lo = Point3::new(-0.1, -0.1, -0.1);
            let all = TileSpacing::new(&c, lo, 0.25, 16);
            for thr in [0.0, 0.008, 0.012, 0.03, 0.06] {
                let small = move |d: f64| d < thr;
                let above = TileSpacing::above(&c, lo, 0.25, 16, &small);
                for (k, &v) in &all.values {
                    let want = (!small(v)).then_some(v.to_bits());
                    assert_eq!(
                        above.values.get(k).map(|v| v.to_bits()),
                        want,
                        "{round} {thr}"
                    );
                    left_out += usize::from(want.is_none());
                }
                assert!(above.values.keys().all(|k| all.values.contains_key(k)));
            }
        }
        assert!(left_out > 100, "{left_out}");
    }
}
