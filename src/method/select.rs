//! Selection and segmentation (section 4.5): the best pose per hypothesis is kept, weaker
//! poses within the agent radius of a stronger one are suppressed, and the points that
//! afford each detection are grown from it.

use nalgebra::Point3;

use crate::cellhash::CellMap;
use crate::cloud::PointCloud;
use crate::num::{floor_i64, index32, to_i64};

/// Parameters of the region growing (section 4.5).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SegmentConfig {
    /// Largest gap between neighbouring points of one segment, metres.
    pub grow_distance: f64,
    /// Points lower than this above the floor are ignored, metres.
    pub floor_height: f64,
    /// Seeds are the points within this distance of the detection's contact point, metres.
    pub seed_radius: f64,
    /// A segment stops growing at this many points (guards against a whole room).
    pub max_points: usize,
}

/// Indices (into `centres`, ordered by score) of the detections kept by non-maximum
/// suppression: a detection is dropped when a kept one lies within `radius` metres (x-y).
/// `order` must list candidates strongest first.
pub fn suppress(centres: &[Point3<f64>], order: &[usize], radius: f64) -> Vec<usize> {
    let mut kept: Vec<usize> = Vec::new();
    for &i in order {
        let c = centres[i];
        if kept
            .iter()
            .all(|&k| (centres[k].xy() - c.xy()).norm() > radius)
        {
            kept.push(i);
        }
    }
    kept
}

/// Region growing from each seed in turn: returns, per point, the index of the seed whose
/// segment took it (earlier seeds win), or `None`.
///
/// Points at least `floor_height` high are binned into cubic cells of edge
/// `grow_distance` (metres, the cloud's frame). A seed first takes, in cell order, the
/// points within `seed_radius` of it; then, last taken first (a stack), each taken point
/// takes the untaken points within `grow_distance` in the 27 cells around its own, until
/// the segment holds `max_points`.
///
/// The cells are one flat array of the points sorted by cell (a stable counting sort, so
/// each cell lists its points by index), and a point leaves its cell's list when it is
/// taken (the list compacted in order as it is scanned). A taken point is one no later
/// scan could take, so every scan finds the same untaken points in the same order as a
/// scan of all the cell's points that skips the taken ones (`segment_reference` in the
/// tests): the same points are taken in the same order.
pub fn segment(
    cloud: &PointCloud,
    seeds: &[Point3<f64>],
    cfg: &SegmentConfig,
) -> Vec<Option<usize>> {
    if seeds.is_empty() {
        return vec![None; cloud.len()];
    }
    segment_in(&SegmentGrid::new(cloud, cfg), cloud, seeds, cfg)
}

/// The cells of [`segment`] for one cloud and one configuration, built once and shared by
/// the segmentations of several sets of seeds (each hierarchy's detections): a
/// segmentation copies only the per-cell counts and the flat array it takes points from.
pub struct SegmentGrid {
    /// Cell edge, metres (`grow_distance`, at least 1e-6).
    cell: f64,
    /// The cells as built, before any point is taken.
    index: CellIndex,
}

impl SegmentGrid {
    /// The cells of the points of `cloud` (world frame, metres) at least
    /// `cfg.floor_height` high, of edge `cfg.grow_distance`.
    pub fn new(cloud: &PointCloud, cfg: &SegmentConfig) -> SegmentGrid {
        let cell = cfg.grow_distance.max(1e-6);
        let index = CellIndex::new(cloud, cfg.floor_height, &|p| cell_key(p, cell));
        SegmentGrid { cell, index }
    }
}

/// The cell (of edge `cell` metres) holding `p`.
fn cell_key(p: &Point3<f64>, cell: f64) -> (i64, i64, i64) {
    (
        floor_i64(p.x / cell),
        floor_i64(p.y / cell),
        floor_i64(p.z / cell),
    )
}

/// [`segment`] over the cells `grid` built for `cloud` and `cfg` (the same labels as
/// [`segment`]: the grid is only read and copied).
pub fn segment_in(
    grid: &SegmentGrid,
    cloud: &PointCloud,
    seeds: &[Point3<f64>],
    cfg: &SegmentConfig,
) -> Vec<Option<usize>> {
    let mut label: Vec<Option<usize>> = vec![None; cloud.len()];
    if seeds.is_empty() {
        return label;
    }
    let cell = grid.cell;
    let key = |p: &Point3<f64>| cell_key(p, cell);
    let mut grid = CellGrid::new(&grid.index);
    let r2 = cfg.grow_distance * cfg.grow_distance;
    // Taken points not yet grown from, with their cells.
    let mut queue: Vec<(usize, u32)> = Vec::new();
    for (s, seed) in seeds.iter().enumerate() {
        queue.clear();
        let reach = to_i64((cfg.seed_radius / cell).ceil());
        let k = key(seed);
        for dz in -reach..=reach {
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    if let Some(&c) = grid.index.ids.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                        grid.take(c, &cloud.points, &mut label, s, &mut queue, |q| {
                            (q - seed).norm() <= cfg.seed_radius
                        });
                    }
                }
            }
        }
        let mut taken = queue.len();
        while let Some((i, c)) = queue.pop() {
            if taken >= cfg.max_points {
                break;
            }
            let p = cloud.points[i];
            // A neighbourhood found with no untaken point stays so (cells only lose
            // points), so its cells are not visited again; an empty cell takes nothing.
            let Some((slot, around)) = grid.neighbours(c, &cloud.points, &key) else {
                continue;
            };
            let before = queue.len();
            let mut left = false;
            for n in around {
                if n != NO_CELL && grid.live[n as usize] != 0 {
                    grid.take(n, &cloud.points, &mut label, s, &mut queue, |q| {
                        (q - p).norm_squared() <= r2
                    });
                    left |= grid.live[n as usize] != 0;
                }
            }
            if !left {
                grid.drained[slot] = true;
            }
            taken += queue.len() - before;
        }
    }
    label
}

/// No cell: a neighbour of a cell that holds no point.
const NO_CELL: u32 = u32::MAX;

/// The points of [`segment`] (those at least the floor height high) sorted by cubic cell,
/// each cell's points in one run of a flat array, by index, before any is taken.
struct CellIndex {
    /// Cell key (cell coordinates) to cell id, ids in order of the cells' first points.
    ids: CellMap<(i64, i64, i64), u32>,
    /// Each cell's first point (an index into the cloud), whose key is the cell's, by id.
    first: Vec<u32>,
    /// Each cell's first entry in `entries`, by id.
    start: Vec<u32>,
    /// Each cell's number of points, by id.
    count: Vec<u32>,
    /// Indices of the points in the cloud, by cell, in index order within a cell (`u32`,
    /// half the memory of `usize`; see [`CellIndex::new`]).
    entries: Vec<u32>,
}

impl CellIndex {
    /// The cells of the points of `cloud` at least `floor_height` high, by `key`.
    ///
    /// Cell ids and point indices are `u32`: a cloud has fewer cells than points, and 2^32
    /// points would take 96 GiB of coordinates.
    fn new(
        cloud: &PointCloud,
        floor_height: f64,
        key: &impl Fn(&Point3<f64>) -> (i64, i64, i64),
    ) -> Self {
        let mut ids: CellMap<(i64, i64, i64), u32> = CellMap::default();
        let mut first: Vec<u32> = Vec::new();
        let mut count: Vec<u32> = Vec::new();
        let mut cell_of: Vec<u32> = vec![NO_CELL; cloud.len()];
        // The last cell looked up and its id: a run of points in one cell (as a depth
        // image's rows give) looks it up once.
        let mut last: Option<((i64, i64, i64), u32)> = None;
        for (i, p) in cloud.points.iter().enumerate() {
            if p.z >= floor_height {
                let k = key(p);
                let c = match last {
                    Some((lk, c)) if lk == k => c,
                    _ => {
                        let c = *ids.entry(k).or_insert_with(|| {
                            first.push(index32(i));
                            count.push(0);
                            index32(first.len() - 1)
                        });
                        last = Some((k, c));
                        c
                    }
                };
                count[c as usize] += 1;
                cell_of[i] = c;
            }
        }
        let mut start = Vec::with_capacity(count.len());
        let mut next = 0u32;
        for &n in &count {
            start.push(next);
            next += n;
        }
        let mut fill = start.clone();
        let mut entries = vec![0u32; next as usize];
        for (i, &c) in cell_of.iter().enumerate() {
            if c != NO_CELL {
                let f = &mut fill[c as usize];
                entries[*f as usize] = index32(i);
                *f += 1;
            }
        }
        CellIndex {
            ids,
            first,
            start,
            count,
            entries,
        }
    }
}

/// One segmentation's view of a [`CellIndex`]: each cell's untaken points the first ones
/// of its run.
struct CellGrid<'a> {
    /// The cells before any point was taken.
    index: &'a CellIndex,
    /// How many of a cell's entries are untaken (the first ones of its run), by id.
    live: Vec<u32>,
    /// The index's entries, each cell's run compacted as its points are taken.
    entries: Vec<u32>,
    /// A cell's index in `table` once its neighbours were looked up, else [`NO_CELL`].
    slot: Vec<u32>,
    /// The 27 cells around a cell (offsets in z, then y, then x, each from −1 to 1), by
    /// slot; [`NO_CELL`] where no point is.
    table: Vec<[u32; 27]>,
    /// By slot, whether all 27 cells were found with no untaken point.
    drained: Vec<bool>,
}

impl<'a> CellGrid<'a> {
    /// The cells of `index` with no point taken.
    fn new(index: &'a CellIndex) -> Self {
        CellGrid {
            index,
            live: index.count.clone(),
            entries: index.entries.clone(),
            slot: vec![NO_CELL; index.first.len()],
            table: Vec::new(),
            drained: Vec::new(),
        }
    }

    /// The slot and the 27 cells around cell `c` (see `table`) of the grid of `points` by
    /// `key`, looked up once per cell; `None` once they are `drained`.
    fn neighbours(
        &mut self,
        c: u32,
        points: &[Point3<f64>],
        key: &impl Fn(&Point3<f64>) -> (i64, i64, i64),
    ) -> Option<(usize, [u32; 27])> {
        let c = c as usize;
        if self.slot[c] == NO_CELL {
            let k = key(&points[self.index.first[c] as usize]);
            let mut around = [NO_CELL; 27];
            let mut n = 0;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(&id) = self.index.ids.get(&(k.0 + dx, k.1 + dy, k.2 + dz)) {
                            around[n] = id;
                        }
                        n += 1;
                    }
                }
            }
            self.slot[c] = index32(self.table.len());
            self.table.push(around);
            self.drained.push(false);
        }
        let slot = self.slot[c] as usize;
        (!self.drained[slot]).then(|| (slot, self.table[slot]))
    }

    /// Takes for seed `s` the untaken points of cell `c` (of `points`) that pass `near`, in
    /// index order: labels them, pushes them with their cell on `queue` and drops them
    /// from the cell's run, keeping the order of the others.
    fn take(
        &mut self,
        c: u32,
        points: &[Point3<f64>],
        label: &mut [Option<usize>],
        s: usize,
        queue: &mut Vec<(usize, u32)>,
        near: impl Fn(Point3<f64>) -> bool,
    ) {
        let from = self.index.start[c as usize] as usize;
        let to = from + self.live[c as usize] as usize;
        let mut kept = from;
        for e in from..to {
            let j = self.entries[e];
            let i = j as usize;
            if near(points[i]) {
                label[i] = Some(s);
                queue.push((i, c));
            } else {
                self.entries[kept] = j;
                kept += 1;
            }
        }
        self.live[c as usize] = index32(kept - from);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// [`segment`] as it was before the sorted cells: a hashed `Vec` of point indices per
    /// cell, every point of the 27 cells scanned (taken ones skipped) for each point grown
    /// from.
    fn segment_reference(
        cloud: &PointCloud,
        seeds: &[Point3<f64>],
        cfg: &SegmentConfig,
    ) -> Vec<Option<usize>> {
        let mut label: Vec<Option<usize>> = vec![None; cloud.len()];
        let cell = cfg.grow_distance.max(1e-6);
        let key = |p: &Point3<f64>| {
            (
                to_i64((p.x / cell).floor()),
                to_i64((p.y / cell).floor()),
                to_i64((p.z / cell).floor()),
            )
        };
        let mut grid: CellMap<(i64, i64, i64), Vec<usize>> = CellMap::default();
        for (i, p) in cloud.points.iter().enumerate() {
            if p.z >= cfg.floor_height {
                grid.entry(key(p)).or_default().push(i);
            }
        }
        let r2 = cfg.grow_distance * cfg.grow_distance;
        for (s, seed) in seeds.iter().enumerate() {
            let mut queue: Vec<usize> = Vec::new();
            let reach = to_i64((cfg.seed_radius / cell).ceil());
            let k = key(seed);
            for dz in -reach..=reach {
                for dy in -reach..=reach {
                    for dx in -reach..=reach {
                        for &i in grid
                            .get(&(k.0 + dx, k.1 + dy, k.2 + dz))
                            .into_iter()
                            .flatten()
                        {
                            if label[i].is_none()
                                && (cloud.points[i] - seed).norm() <= cfg.seed_radius
                            {
                                label[i] = Some(s);
                                queue.push(i);
                            }
                        }
                    }
                }
            }
            let mut taken = queue.len();
            while let Some(i) = queue.pop() {
                if taken >= cfg.max_points {
                    break;
                }
                let p = cloud.points[i];
                let k = key(&p);
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            for &j in grid
                                .get(&(k.0 + dx, k.1 + dy, k.2 + dz))
                                .into_iter()
                                .flatten()
                            {
                                if label[j].is_none() && (cloud.points[j] - p).norm_squared() <= r2
                                {
                                    label[j] = Some(s);
                                    queue.push(j);
                                    taken += 1;
                                }
                            }
                        }
                    }
                }
            }
        }
        label
    }

    /// [`segment`] against [`segment_reference`], label for label, on seeded clouds:
    /// patches and rods of different spacings (around the growing distance, so segments
    /// both leak and stop), loose points, points under the floor height and points with a
    /// NaN coordinate; one to five seeds, some on the same patch, and caps from a few
    /// points (cut off mid-growth, where the order of taking decides) to none; and
    /// [`segment_in`] over one grid for two sets of seeds in turn.
    #[test]
    fn segment_equals_the_reference() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let (mut capped, mut taken_total) = (0, 0);
        for round in 0..300 {
            let grow = [0.01, 0.03, 0.05][rng.random_range(0..3)];
            let mut pts = Vec::new();
            for _ in 0..rng.random_range(1..6) {
                let o = Point3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-0.1..1.0),
                );
                let step = grow * [0.3, 0.7, 0.95, 1.2][rng.random_range(0..4)];
                let (nu, nv) = (rng.random_range(1..40), rng.random_range(1..40));
                let (u, v) = match rng.random_range(0..3) {
                    0 => (Vector3::x(), Vector3::y()),
                    1 => (Vector3::x(), Vector3::z()),
                    _ => (Vector3::new(0.6, 0.8, 0.0), Vector3::new(0.0, 0.6, 0.8)),
                };
                for a in 0..nu {
                    for b in 0..nv {
                        let jitter = Vector3::new(
                            rng.random_range(-0.3..0.3),
                            rng.random_range(-0.3..0.3),
                            rng.random_range(-0.3..0.3),
                        ) * step;
                        pts.push(o + (u * f64::from(a) + v * f64::from(b)) * step + jitter);
                    }
                }
            }
            for _ in 0..rng.random_range(0..50) {
                pts.push(Point3::new(
                    rng.random_range(-1.5..1.5),
                    rng.random_range(-1.5..1.5),
                    rng.random_range(-0.2..1.5),
                ));
            }
            if round % 10 == 0 {
                pts.push(Point3::new(f64::NAN, 0.0, 0.5));
                pts.push(Point3::new(0.0, f64::NAN, 0.5));
            }
            // Shuffled, so a cell's points are not in the order they were made.
            for i in (1..pts.len()).rev() {
                pts.swap(i, rng.random_range(0..=i));
            }
            let cloud = PointCloud::new(pts);
            let seeds: Vec<Point3<f64>> = (0..rng.random_range(1..6))
                .map(|_| {
                    let p = cloud.points[rng.random_range(0..cloud.len())];
                    p + Vector3::new(
                        rng.random_range(-0.05..0.05),
                        rng.random_range(-0.05..0.05),
                        rng.random_range(-0.05..0.05),
                    )
                })
                .collect();
            let cfg = SegmentConfig {
                grow_distance: grow,
                floor_height: [0.0, 0.05, 0.3][rng.random_range(0..3)],
                seed_radius: [0.0, 0.02, 0.15][rng.random_range(0..3)],
                max_points: [1, 5, 40, 200, 200_000][rng.random_range(0..5)],
            };
            let want = segment_reference(&cloud, &seeds, &cfg);
            assert_eq!(segment(&cloud, &seeds, &cfg), want, "round {round}");
            // One grid shared by two segmentations (as the hierarchies of a run share
            // it): each gives the labels of its own seeds, whichever ran first.
            let grid = SegmentGrid::new(&cloud, &cfg);
            let others: Vec<Point3<f64>> = seeds
                .iter()
                .rev()
                .map(|p| p + Vector3::x() * 0.01)
                .collect();
            assert_eq!(
                segment_in(&grid, &cloud, &others, &cfg),
                segment_reference(&cloud, &others, &cfg),
                "round {round}"
            );
            assert_eq!(
                segment_in(&grid, &cloud, &seeds, &cfg),
                want,
                "round {round}"
            );
            taken_total += want.iter().flatten().count();
            capped += (0..seeds.len())
                .filter(|&s| want.iter().filter(|&&l| l == Some(s)).count() >= cfg.max_points)
                .count();
        }
        assert!(
            capped > 50 && taken_total > 20_000,
            "{capped} {taken_total}"
        );
        assert!(segment(
            &PointCloud::new(Vec::new()),
            &[Point3::origin()],
            &SegmentConfig {
                grow_distance: 0.03,
                floor_height: 0.05,
                seed_radius: 0.15,
                max_points: 10,
            }
        )
        .is_empty());
    }

    #[test]
    fn suppression_keeps_the_strongest_of_neighbours() {
        let c = vec![
            Point3::new(0.0, 0.0, 0.4),
            Point3::new(0.1, 0.0, 0.4),
            Point3::new(1.0, 0.0, 0.4),
        ];
        assert_eq!(suppress(&c, &[1, 0, 2], 0.3), vec![1, 2]);
        assert_eq!(suppress(&c, &[0, 1, 2], 0.05), vec![0, 1, 2]);
    }

    #[test]
    fn growing_stops_at_gaps_and_ignores_the_floor() {
        // Two 0.3 m rows of points 1 cm apart at z = 0.45, 10 cm apart, and a floor row.
        let mut pts = Vec::new();
        for i in 0..30 {
            pts.push(Point3::new(i as f64 * 0.01, 0.0, 0.45));
            pts.push(Point3::new(i as f64 * 0.01, 0.1, 0.45));
            pts.push(Point3::new(i as f64 * 0.01, 0.0, 0.0));
        }
        let cloud = PointCloud::new(pts);
        let cfg = SegmentConfig {
            grow_distance: 0.02,
            floor_height: 0.05,
            seed_radius: 0.03,
            max_points: 1000,
        };
        let l = segment(&cloud, &[Point3::new(0.0, 0.0, 0.45)], &cfg);
        let taken: Vec<usize> = (0..cloud.len()).filter(|&i| l[i] == Some(0)).collect();
        assert_eq!(taken.len(), 30);
        assert!(taken
            .iter()
            .all(|&i| cloud.points[i].y == 0.0 && cloud.points[i].z == 0.45));
    }
}
