//! The guard stage before the grids: the height map (section 4.1) is dense over the
//! cloud's extent in x and y, and the voxel distance field (section 4.2) keeps one slot
//! per 32^3 cells of its box (its distances are computed only where a body asks for them),
//! so part of their memory follows the bounding box, not the points. This stage makes the
//! extent the detector sees follow the points:
//!
//! 1. every coordinate must be finite and within [`ExtentConfig::max_coordinate`] (beyond,
//!    f64 cannot resolve the 5 mm contact steps and grid indices overflow);
//! 2. stray points are removed by construction: the points are binned into coarse cubes
//!    (a hash map, so memory follows the points), cubes touching each other form connected
//!    regions, and the regions holding the bulk of the points are kept;
//! 3. the grid memory the remaining extent needs is checked against
//!    [`ExtentConfig::grid_budget`]; over it, the file is refused with one line, and a
//!    batch goes on with the next file.
//!
//! World frame: metres, z up. Nothing here changes a cloud that has no stray region.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

use nalgebra::Point3;

use rayon::prelude::*;

use crate::cellhash::{component_roots, key_runs, offset_key, CellMap, CubeBox};
use crate::cloud::PointCloud;
use crate::detect::DetectConfig;

/// Limits of the guard stage. Defaults carry their reasons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtentConfig {
    /// Edge of the coarse cubes that decide which points are connected, metres.
    pub cell: f64,
    /// A connected region with fewer than this share of the points is stray (the largest
    /// region is always kept).
    pub stray_share: f64,
    /// Largest accepted |coordinate|, metres.
    pub max_coordinate: f64,
    /// Most bytes the grids (height map, distance field) of one file may take.
    pub grid_budget: u64,
    /// Edge of the cube around a body whose distance-field chunks must fit the budget
    /// together, metres.
    pub reach: f64,
}

impl Default for ExtentConfig {
    fn default() -> Self {
        ExtentConfig {
            // 1 m: about the reach of a limb; a gap wider than this cannot be bridged by a body part.
            cell: 1.0,
            // 1 %: a stray point or sensor ghost is far below it; a chair in a room scan is above it.
            stray_share: 0.01,
            // 1e7 m (10,000 km, the range of UTM northings): f64 still resolves 2e-9 m there.
            max_coordinate: 1e7,
            // 2 GiB: a 25 m x 25 m x 3 m scene at 2 cm voxels fits; half of a small 4 GB machine.
            grid_budget: 2 << 30,
            // 2 m: a 1.85 m adult lying, or sitting with the legs stretched, fits in it.
            reach: 2.0,
        }
    }
}

/// Points per piece of the coordinate check: tens of microseconds of work, well above a
/// task's overhead on rayon's pool (the point found does not depend on it).
const CHECK_PIECE: usize = 16 * 1024;

/// Bytes in a GiB, for messages.
const GIB: f64 = (1u64 << 30) as f64;
/// Bytes per height-map cell: the `Option<f64>` height and the two `usize` column offsets
/// of the per-cell sort (`heightmap::HeightMap::from_cloud`).
const HEIGHTMAP_CELL_BYTES: f64 =
    (std::mem::size_of::<Option<f64>>() + 2 * std::mem::size_of::<usize>()) as f64;

/// Why a cloud is refused before the grids are built. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum ExtentError {
    /// A coordinate is not finite or too large to be indexed.
    #[error(
        "{path}: point {point}: coordinate {value:.3e} m is beyond the {limit:e} m the grids can \
         index (check --units and --transform)"
    )]
    Coordinate {
        /// The file.
        path: PathBuf,
        /// Index of the point in the cloud.
        point: usize,
        /// The offending coordinate, metres.
        value: f64,
        /// [`ExtentConfig::max_coordinate`].
        limit: f64,
    },
    /// The grids over the kept extent would take more than the budget.
    #[error(
        "{path}: the cloud spans {:.1} x {:.1} x {:.1} m ({dropped} stray points dropped); its \
         grids would take {:.1} GiB, over the {:.1} GiB limit (check --units, crop the cloud, \
         or use a coarser --voxel)",
        extent[0], extent[1], extent[2], *need as f64 / GIB, *budget as f64 / GIB
    )]
    TooLarge {
        /// The file.
        path: PathBuf,
        /// Extent of the kept points along x, y, z, metres.
        extent: [f64; 3],
        /// Stray points dropped before measuring it.
        dropped: usize,
        /// Bytes the grids would take.
        need: u64,
        /// [`ExtentConfig::grid_budget`].
        budget: u64,
    },
}

/// The cloud the grids are built from, and how many stray points were left out of it.
#[derive(Debug, Clone)]
pub struct Guarded<'a> {
    /// The points kept (the input itself when nothing was dropped).
    pub cloud: Cow<'a, PointCloud>,
    /// Stray points left out.
    pub dropped: usize,
}

/// Runs the guard stage on `cloud` (world frame, metres) read from `path`: refuses
/// coordinates that cannot be indexed, drops stray regions, and refuses an extent whose
/// grids exceed the budget.
pub fn guard<'a>(
    path: &Path,
    cloud: &'a PointCloud,
    detect: &DetectConfig,
    cfg: &ExtentConfig,
) -> Result<Guarded<'a>, ExtentError> {
    // The first such point in the cloud's order, searched in parallel pieces (each
    // piece in order, the first piece that has one wins).
    let bad = |p: &Point3<f64>| {
        p.coords
            .iter()
            .find(|c| !c.is_finite() || c.abs() > cfg.max_coordinate)
            .copied()
    };
    if let Some((point, value)) = cloud
        .points
        .par_chunks(CHECK_PIECE)
        .enumerate()
        .find_map_first(|(n, piece)| {
            piece
                .iter()
                .enumerate()
                .find_map(|(i, p)| bad(p).map(|c| (n * CHECK_PIECE + i, c)))
        })
    {
        return Err(ExtentError::Coordinate {
            path: path.to_path_buf(),
            point,
            value,
            limit: cfg.max_coordinate,
        });
    }
    let keep = bulk(&cloud.points, cfg.cell, cfg.stray_share);
    let dropped = keep.iter().filter(|k| !**k).count();
    let kept: Cow<'a, PointCloud> = if dropped == 0 {
        Cow::Borrowed(cloud)
    } else {
        Cow::Owned(PointCloud::new(
            cloud
                .points
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(p, _)| *p)
                .collect(),
        ))
    };
    if let Some((lo, hi)) = kept.bounds() {
        let extent = [hi.x - lo.x, hi.y - lo.y, hi.z - lo.z];
        let need = grid_bytes(extent, detect, cfg.reach);
        if need > cfg.grid_budget as f64 {
            // Above the budget, so positive, and capped at u64::MAX: only the fraction goes.
            #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
            let need = need.min(u64::MAX as f64) as u64;
            return Err(ExtentError::TooLarge {
                path: path.to_path_buf(),
                extent,
                dropped,
                need,
                budget: cfg.grid_budget,
            });
        }
    }
    Ok(Guarded {
        cloud: kept,
        dropped,
    })
}

/// Bytes the height map and the distance field take over an extent (metres along x, y, z)
/// while a body moves within a cube of edge `reach` metres ([`crate::method::scene::field_bytes`]),
/// as an upper bound (computed in f64, so any extent gives a number).
pub fn grid_bytes(extent: [f64; 3], cfg: &DetectConfig, reach: f64) -> f64 {
    let hc = cfg.heightmap.cell;
    let map = (extent[0] / hc + 1.0).floor() * (extent[1] / hc + 1.0).floor();
    map * HEIGHTMAP_CELL_BYTES + crate::method::scene::field_bytes(extent, &cfg.scene, reach)
}

/// Per point, whether it lies in a connected region of coarse cubes (edge `cell`, touching
/// by face, edge or corner) that holds at least `share` of the points, or in the largest.
///
/// Where the box of the occupied cubes has at most [`DENSE_BULK_CUBES`] cubes and no more
/// than the points ([`dense_bulk`]: each point's cube an index into the box, no hashing
/// and no list of runs, which a scan whose points do not come in runs makes as long as
/// the cloud), else by the runs of points in one cube ([`hashed_bulk`]). The regions and
/// their counts depend only on the points' cubes, so both give the same answer.
fn bulk(points: &[Point3<f64>], cell: f64, share: f64) -> Vec<bool> {
    dense_bulk(points, cell, share).unwrap_or_else(|| hashed_bulk(points, cell, share))
}

/// Most cubes in the box of [`dense_bulk`]: 65 536 (a 40 m cube at 1 m, counted in
/// parallel pieces of 512 KiB each); a far stray spreads the box past it, and the cubes
/// are then hashed.
const DENSE_BULK_CUBES: usize = 1 << 16;

/// Points per piece of [`dense_bulk`]'s passes: each piece counts into its own array of
/// the box's cubes, so a piece is many times the largest box. The counts do not depend
/// on it.
const BULK_PIECE: usize = 64 * 1024;

/// [`bulk`] over the box of the points' cubes, or `None` where the box is larger than
/// [`DENSE_BULK_CUBES`] or than the number of points (or the coordinates are not finite):
/// each point's cube as an index into the box (x-major), the points per cube counted in
/// parallel pieces and summed, the occupied cubes joined through the box.
fn dense_bulk(points: &[Point3<f64>], cell: f64, share: f64) -> Option<Vec<bool>> {
    let cubes = CubeBox::of(points, cell, BULK_PIECE)?;
    let cells = cubes
        .len()
        .filter(|&n| n <= DENSE_BULK_CUBES && n <= points.len())?;
    // Inside the box by its monotony; `None` (then hashed) were it not.
    let index = |p: &Point3<f64>| -> Option<usize> {
        let o = cubes.offset(CubeBox::cube_of(p, cell))?;
        Some(cubes.index(o))
    };
    let of_point: Vec<u32> = points
        .par_iter()
        .with_min_len(BULK_PIECE)
        .map(|p| {
            index(p)
                .and_then(|c| u32::try_from(c).ok())
                .unwrap_or(u32::MAX)
        })
        .collect();
    let count: Vec<usize> = of_point
        .par_chunks(BULK_PIECE)
        .map(|piece| {
            let mut n = vec![0usize; cells];
            for &c in piece {
                if let Some(n) = n.get_mut(c as usize) {
                    *n += 1;
                }
            }
            n
        })
        .reduce_with(|mut a, b| {
            for (a, b) in a.iter_mut().zip(b) {
                *a += b;
            }
            a
        })?;
    if count.iter().sum::<usize>() != points.len() {
        return None;
    }
    // The regions: components of the occupied cubes, numbered by their place in the box.
    let roots = component_roots(cells, |i, d| {
        if count[i] == 0 {
            return None;
        }
        let j = cubes.index(cubes.step(cubes.offset_of_index(i), d)?);
        (count[j] != 0).then_some(j)
    });
    let mut region = vec![0usize; cells];
    for (&r, &n) in roots.iter().zip(&count) {
        region[r] += n;
    }
    let largest = region.iter().copied().max().unwrap_or(0);
    let least = share * points.len() as f64;
    let kept: Vec<bool> = roots
        .iter()
        .map(|&r| {
            let n = region[r];
            n == largest || n as f64 >= least
        })
        .collect();
    Some(
        of_point
            .par_iter()
            .with_min_len(BULK_PIECE)
            .map(|&c| kept[c as usize])
            .collect(),
    )
}

/// [`bulk`] by the runs of points in one cube, the cubes hashed.
fn hashed_bulk(points: &[Point3<f64>], cell: f64, share: f64) -> Vec<bool> {
    // The cubes of runs of points in one cube (as a depth image's rows give), found in
    // parallel pieces: each cube is looked up once per run, as one loop over the points
    // that remembers the last cube does.
    let runs = key_runs(points, |p| Some(CubeBox::cube_of(p, cell)));
    // Cells numbered in the points' order and only looked up: the map's order is unused.
    let mut cells: CellMap<[i64; 3], usize> = CellMap::default();
    let mut keys: Vec<[i64; 3]> = Vec::new();
    let of_run: Vec<usize> = runs
        .iter()
        .map(|&(k, _)| {
            let n = cells.len();
            *cells.entry(k).or_insert_with(|| {
                keys.push(k);
                n
            })
        })
        .collect();
    // The regions: components of the occupied cells.
    let roots = component_roots(keys.len(), |i, d| {
        cells.get(&offset_key(keys[i], d)).copied()
    });
    let mut count = vec![0usize; keys.len()];
    for ((_, r), &c) in runs.iter().zip(&of_run) {
        count[roots[c]] += r.len();
    }
    let largest = count.iter().copied().max().unwrap_or(0);
    let least = share * points.len() as f64;
    let mut keep = vec![false; points.len()];
    for ((_, r), &c) in runs.iter().zip(&of_run) {
        let n = count[roots[c]];
        keep[r.clone()].fill(n == largest || n as f64 >= least);
    }
    keep
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cellhash::on_threads;

    fn room() -> Vec<Point3<f64>> {
        // A 4 m x 3 m floor sampled every 5 cm.
        let mut pts = Vec::new();
        for i in 0..80 {
            for j in 0..60 {
                pts.push(Point3::new(i as f64 * 0.05, j as f64 * 0.05, 0.0));
            }
        }
        pts
    }

    #[test]
    fn a_cloud_without_strays_is_passed_through_untouched() {
        let c = PointCloud::new(room());
        let g = guard(
            Path::new("r.ply"),
            &c,
            &DetectConfig::default(),
            &ExtentConfig::default(),
        )
        .unwrap();
        assert_eq!(g.dropped, 0);
        assert!(matches!(g.cloud, Cow::Borrowed(_)));
    }

    /// [`bulk`] as it was, one loop over the points: each point's cube numbered, then
    /// the regions counted point by point.
    fn bulk_one_by_one(points: &[Point3<f64>], cell: f64, share: f64) -> Vec<bool> {
        let mut cells: CellMap<[i64; 3], usize> = CellMap::default();
        let mut keys: Vec<[i64; 3]> = Vec::new();
        let of_point: Vec<usize> = points
            .iter()
            .map(|p| {
                let k = CubeBox::cube_of(p, cell);
                let n = cells.len();
                *cells.entry(k).or_insert_with(|| {
                    keys.push(k);
                    n
                })
            })
            .collect();
        // Regions by flooding the cells' neighbourhoods (a different method than the
        // union-find, for the same regions).
        let mut region = vec![usize::MAX; keys.len()];
        for s in 0..keys.len() {
            if region[s] != usize::MAX {
                continue;
            }
            region[s] = s;
            let mut stack = vec![s];
            while let Some(c) = stack.pop() {
                let k = keys[c];
                for d in 0..27i64 {
                    let n = [k[0] + d % 3 - 1, k[1] + d / 3 % 3 - 1, k[2] + d / 9 - 1];
                    if let Some(&j) = cells.get(&n) {
                        if region[j] == usize::MAX {
                            region[j] = s;
                            stack.push(j);
                        }
                    }
                }
            }
        }
        let mut count = vec![0usize; keys.len()];
        for &c in &of_point {
            count[region[c]] += 1;
        }
        let largest = count.iter().copied().max().unwrap_or(0);
        of_point
            .iter()
            .map(|&c| {
                let n = count[region[c]];
                n == largest || n as f64 >= share * points.len() as f64
            })
            .collect()
    }

    /// The regions found from runs of points in parallel pieces keep the points one loop
    /// keeps, at 1 and 2 threads: a floor scanned in rows (long runs across the pieces),
    /// a far region under the share, one above it, and stray points between the rows.
    #[test]
    fn bulk_in_pieces_keeps_what_one_loop_keeps() {
        let mut pts = Vec::new();
        for j in 0..200 {
            for i in 0..300 {
                pts.push(Point3::new(i as f64 * 0.02, j as f64 * 0.02, 0.0));
            }
            if j % 50 == 7 {
                // A stray point far off, alone in its region.
                pts.push(Point3::new(40.0 + j as f64, -30.0, 2.0));
            }
        }
        // 300 points 10 m away (0.5 %: dropped) and 1200 20 m away (2 %: kept).
        pts.extend((0..300).map(|i| Point3::new(10.0 + i as f64 * 0.001, 10.0, 1.0)));
        pts.extend((0..1200).map(|i| Point3::new(-20.0, i as f64 * 0.001, 0.5)));
        let want = bulk_one_by_one(&pts, 1.0, 0.01);
        assert_eq!(want.iter().filter(|k| !**k).count(), 304);
        for threads in [1, 2] {
            assert_eq!(
                on_threads(threads, || bulk(&pts, 1.0, 0.01)),
                want,
                "{threads} threads"
            );
            // Both ways: the box (260 x 41 x 3 cubes) is under the points and the limit.
            let dense = on_threads(threads, || dense_bulk(&pts, 1.0, 0.01));
            assert_eq!(dense.as_ref(), Some(&want), "{threads} threads");
            assert_eq!(on_threads(threads, || hashed_bulk(&pts, 1.0, 0.01)), want);
        }
        // Shuffled (no runs), by a fixed permutation: the same answer for each point.
        let order: Vec<usize> = (0..pts.len()).map(|i| i * 7919 % pts.len()).collect();
        let shuffled: Vec<Point3<f64>> = order.iter().map(|&i| pts[i]).collect();
        let moved: Vec<bool> = order.iter().map(|&i| want[i]).collect();
        assert_eq!(bulk_one_by_one(&shuffled, 1.0, 0.01), moved);
        assert_eq!(on_threads(2, || bulk(&shuffled, 1.0, 0.01)), moved);
        // A stray 100 km off spreads the box past the limit: hashed, the same answer.
        let mut far = pts.clone();
        far.push(Point3::new(1e5, 0.0, 0.0));
        assert!(dense_bulk(&far, 1.0, 0.01).is_none());
        assert_eq!(bulk(&far, 1.0, 0.01), bulk_one_by_one(&far, 1.0, 0.01));
    }

    /// The point refused is the first one in the cloud's order with a coordinate out of
    /// range, and its first such coordinate, at 1 and 2 threads: bad points in two
    /// pieces, the later piece's worse, and two bad coordinates in one point.
    #[test]
    fn the_first_bad_coordinate_is_refused() {
        let mut pts = room();
        pts.resize(CHECK_PIECE * 3, Point3::new(1.0, 1.0, 0.5));
        let first = CHECK_PIECE + 5;
        pts[first] = Point3::new(0.0, 2e7, f64::NAN);
        pts[first + 1] = Point3::new(f64::INFINITY, 0.0, 0.0);
        pts[2 * CHECK_PIECE + 1] = Point3::new(-3e7, 0.0, 0.0);
        let c = PointCloud::new(pts);
        for threads in [1, 2] {
            let got = on_threads(threads, || {
                guard(
                    Path::new("r.ply"),
                    &c,
                    &DetectConfig::default(),
                    &ExtentConfig::default(),
                )
            });
            match got {
                Err(ExtentError::Coordinate { point, value, .. }) => {
                    assert_eq!((point, value), (first, 2e7), "{threads} threads");
                }
                other => panic!("{threads} threads: {other:?}"),
            }
        }
    }

    #[test]
    fn grid_bytes_match_the_grids_built() {
        // 1 m x 1 m x 0 m: height map 21 x 21 cells (16 bytes of height and two 8-byte
        // column offsets each); field box (50 + 2 + 30)^2 x (0 + 2 + 30) cells, computed
        // at once (two f32 grids).
        let b = grid_bytes([1.0, 1.0, 0.0], &DetectConfig::default(), 2.0);
        assert_eq!(b, 21.0 * 21.0 * 32.0 + 82.0 * 82.0 * 32.0 * 8.0);
        // 40 m x 40 m x 0 m: field box 2032^2 x 32 cells, over the dense limit: 64^2
        // chunks of 32^3 cells (a 24-byte slot each); a 2 m cube around a body spans
        // (ceil(100 / 32) + 1)^3 = 5^3 chunks of 128 KiB.
        let b = grid_bytes([40.0, 40.0, 0.0], &DetectConfig::default(), 2.0);
        assert_eq!(b, 801.0 * 801.0 * 32.0 + 4096.0 * 24.0 + 125.0 * 131072.0);
        // A 200 m x 200 m floor no longer counts its whole box of voxels (4e9 cells).
        let floor = grid_bytes([200.0, 200.0, 1.0], &DetectConfig::default(), 2.0);
        assert!(floor < 0.6 * GIB, "{}", floor / GIB);
        // A 2 mm voxel makes the cube around one body alone 4 GiB.
        let mut fine = DetectConfig::default();
        fine.scene.voxel_size = 0.002;
        assert!(grid_bytes([1.0, 1.0, 0.0], &fine, 2.0) > 4.0 * GIB);
    }
}
