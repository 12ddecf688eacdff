//! Specks: small clusters of points detached from everything else, left out of the grids.
//!
//! A surface the body can rest on or touch is sampled densely and in one piece: a depth
//! camera's points lie millimetres to centimetres apart, a reconstruction's vertices a
//! few centimetres, and a chair's arm joins its back and seat. A point with nothing near
//! it, or a few points together with nothing near them, is none of these: sensor speckle,
//! returns from a window or a mirror, dust in a laser scan, a reconstruction's floating
//! fragment. Kept, each fills voxels the body collides with (a phantom obstacle over a
//! seat, a phantom armrest under a forearm) and can be the highest point of its
//! height-map cell. The guard ([`super::extent`]) drops whole regions far from the scene;
//! this stage drops specks inside it.
//!
//! The test is on a grid of cubes of edge `cell`: the occupied cubes are joined into
//! components through their faces, edges and corners (26-connected), and the points of a
//! component of at most `max_cubes` cubes are specks. With one cube allowed, a speck is a
//! point or a clump with no other point within `cell` of it.
//!
//! A surface seen at a grazing angle is sampled more sparsely than the cloud's spacing
//! says: a depth camera's rows land on it `1 / sin` of the angle further apart (3 spacings
//! at 20 degrees), so the top of a sofa's arm or back, a seat's side edge or a shelf's
//! board seen from a few metres away falls apart into pieces of a cube or two, each of
//! them as small as a speck, and with them the arm, the back or the seat's edge the later
//! stages look for (and a board a body then sits in between). What tells such
//! a piece from a stray is what lies beyond it: the samples of a surface go on through it,
//! on both sides, along a line, while nothing lies beyond a stray on its far side from the
//! surface it is near. So a cube of a small component is also joined to two occupied cubes
//! at opposite offsets of up to `line` cubes along each axis (a line of samples through
//! it). The components are a partition of the occupied cubes, which depends only on the
//! set of points, so the answer does not depend on their order or on the thread count.

use std::sync::atomic::{AtomicU32, Ordering};

use nalgebra::Point3;
use rayon::prelude::*;

use crate::cellhash::{component_roots, find, join, offset_key, CellMap, CellSet, CubeBox};
use crate::cloud::PointCloud;

/// For each point of `points`, whether it belongs to a speck: a component of at most
/// `max_cubes` occupied cubes of edge `cell` metres, 26-connected and joined along lines of
/// samples up to `line` cubes apart (see the module documentation). Cube indices saturate
/// at `i64`'s range (the guard refuses coordinates that far out before this stage runs).
pub fn specks(points: &[Point3<f64>], cell: f64, max_cubes: usize, line: usize) -> Vec<bool> {
    in_cubes(points, cell, &speck_cubes(points, cell, max_cubes, line))
}

/// The occupied cubes of edge `cell` metres of `points` that lie in components of at most
/// `max_cubes` cubes, joined along lines up to `line` cubes apart (see [`specks`]):
/// usually none, and a few where there are specks.
///
/// Where at least half the points (of a sample) start a run of points in one cube (a
/// scan's points, unlike a depth image's rows, do not come in runs) and the box of the occupied cubes
/// has at most [`DENSE_CUBES_PER_POINT`] cubes a point, the cubes are marked in a dense
/// grid over it ([`dense_speck_cubes`]), which costs no hashing per point; else they are
/// hashed, a run at a time ([`hashed_speck_cubes`]). The components, so the answer,
/// depend only on the set of occupied cubes.
fn speck_cubes(
    points: &[Point3<f64>],
    cell: f64,
    max_cubes: usize,
    line: usize,
) -> CellSet<[i64; 3]> {
    // Points in long runs (a depth image's rows) hash one cube a run, fewer than a dense
    // grid costs to fill and read; points mostly not in runs (a scan) go to the grid. A
    // point over a cube's edge from the one before is in another cube: counted on a
    // sample of the pairs of consecutive points.
    let (pairs, jumps) = (0..points.len().saturating_sub(1))
        .step_by(RUN_SAMPLE)
        .fold((0usize, 0usize), |(n, j), i| {
            let jump = (points[i + 1].coords - points[i].coords).amax() > cell;
            (n + 1, j + usize::from(jump))
        });
    if jumps.saturating_mul(2) < pairs {
        return hashed_speck_cubes(points, cell, max_cubes, line);
    }
    let small_box = |b: &CubeBox| {
        b.len().is_some_and(|n| {
            n <= points.len().saturating_mul(DENSE_CUBES_PER_POINT)
                && u32::try_from(n).is_ok_and(|n| n < u32::MAX)
        })
    };
    // Without a box that holds every cube (no points, non-finite coordinates), hashed.
    CubeBox::of(points, cell, PIECE)
        .filter(small_box)
        .and_then(|b| dense_speck_cubes(points, cell, max_cubes, line, b))
        .unwrap_or_else(|| hashed_speck_cubes(points, cell, max_cubes, line))
}

/// Every how many points [`speck_cubes`] looks at a pair of consecutive points to tell a
/// scan from a depth image: 64 (2 500 pairs of a 160k-point view, a few microseconds).
const RUN_SAMPLE: usize = 64;

/// Cubes of the dense grid of [`speck_cubes`] per point of the cloud, at most: 4 (16
/// bytes a point, less than its 24 bytes of coordinates). A depth view's or a room scan's
/// box at 4 cm has 0.3-3.5 cubes a point; a few far strays spread it past this.
const DENSE_CUBES_PER_POINT: usize = 4;

/// [`speck_cubes`] over a dense grid of the cubes of `boxed` (fewer than `u32::MAX`);
/// `None` if some point's cube is outside it. The points mark their cubes in parallel
/// pieces (marking twice is marking once), and the occupied cubes are numbered in grid
/// order.
fn dense_speck_cubes(
    points: &[Point3<f64>],
    cell: f64,
    max_cubes: usize,
    line: usize,
    boxed: CubeBox,
) -> Option<CellSet<[i64; 3]>> {
    // 0: empty; else the cube's number plus one once numbered (1 while only marked).
    let mut grid: Vec<AtomicU32> = (0..boxed.len()?).map(|_| AtomicU32::new(0)).collect();
    let inside = points.par_chunks(PIECE).all(|piece| {
        let mut last = None;
        for p in piece {
            let k = CubeBox::cube_of(p, cell);
            if last != Some(k) {
                let Some(o) = boxed.offset(k) else {
                    return false;
                };
                grid[boxed.index(o)].store(1, Ordering::Relaxed);
                last = Some(k);
            }
        }
        true
    });
    if !inside {
        return None;
    }
    // The occupied cubes' offsets in the box, in grid order.
    let mut cubes: Vec<[usize; 3]> = Vec::new();
    for (i, g) in grid.iter_mut().enumerate() {
        let g = g.get_mut();
        if *g != 0 {
            cubes.push(boxed.offset_of_index(i));
            *g = u32::try_from(cubes.len()).unwrap_or(u32::MAX);
        }
    }
    let small = small_components(cubes.len(), max_cubes, line, |i, d| {
        match grid[boxed.index(boxed.step(cubes[i], d)?)].load(Ordering::Relaxed) {
            0 => None,
            id => Some(id as usize - 1),
        }
    });
    let set = cubes
        .iter()
        .zip(small)
        .filter(|(_, s)| *s)
        .map(|(&o, _)| boxed.cube(o))
        .collect();
    Some(set)
}

/// [`speck_cubes`] with the occupied cubes in a hash map, numbered in the order first
/// met. A depth image lists row neighbours side by side: a run of points in one cube is
/// looked up once.
fn hashed_speck_cubes(
    points: &[Point3<f64>],
    cell: f64,
    max_cubes: usize,
    line: usize,
) -> CellSet<[i64; 3]> {
    let mut ids: CellMap<[i64; 3], usize> = CellMap::default();
    let mut cubes: Vec<[i64; 3]> = Vec::new();
    let mut last: Option<[i64; 3]> = None;
    for p in points {
        let k = CubeBox::cube_of(p, cell);
        if last != Some(k) {
            ids.entry(k).or_insert_with(|| {
                cubes.push(k);
                cubes.len() - 1
            });
            last = Some(k);
        }
    }
    let small = small_components(cubes.len(), max_cubes, line, |i, d| {
        ids.get(&offset_key(cubes[i], d)).copied()
    });
    cubes
        .iter()
        .zip(small)
        .filter(|(_, s)| *s)
        .map(|(k, _)| *k)
        .collect()
}

/// For each of `n` occupied cubes, whether its component has at most `max_cubes` cubes:
/// 26-connected ([`component_roots`], with `neighbour` as there), then each cube of a
/// component that small also joined to the two occupied cubes at `d` and `-d` for every
/// offset `d` of up to `line` cubes along each axis that has both (a line of samples
/// through it; offsets within one cube join it already). Union-find, the smaller root
/// becoming the parent: the components, so the answer, depend only on the occupied cubes.
fn small_components(
    n: usize,
    max_cubes: usize,
    line: usize,
    neighbour: impl Fn(usize, (i64, i64, i64)) -> Option<usize>,
) -> Vec<bool> {
    let sizes = |roots: &[usize]| {
        let mut size = vec![0usize; n];
        for &r in roots {
            size[r] += 1;
        }
        size
    };
    let mut roots = component_roots(n, &neighbour);
    let size = sizes(&roots);
    let reach = i64::try_from(line).unwrap_or(i64::MAX).min(MAX_LINE);
    if reach >= 2 && roots.iter().any(|&r| size[r] <= max_cubes) {
        // The offsets beyond the 26 round a cube, one of each opposite pair.
        let offsets: Vec<(i64, i64, i64)> = (-reach..=reach)
            .flat_map(|x| {
                (-reach..=reach).flat_map(move |y| (-reach..=reach).map(move |z| (x, y, z)))
            })
            .filter(|&(x, y, z)| x.abs().max(y.abs()).max(z.abs()) >= 2 && (x, y, z) > (0, 0, 0))
            .collect();
        let mut parent = roots.clone();
        for i in 0..n {
            if size[roots[i]] > max_cubes {
                continue;
            }
            for &(x, y, z) in &offsets {
                if let (Some(j), Some(k)) = (neighbour(i, (x, y, z)), neighbour(i, (-x, -y, -z))) {
                    join(&mut parent, i, j);
                    join(&mut parent, i, k);
                }
            }
        }
        roots = (0..n).map(|i| find(&mut parent, i)).collect();
    }
    let size = sizes(&roots);
    roots.iter().map(|&r| size[r] <= max_cubes).collect()
}

/// The most cubes along each axis [`small_components`] looks for a line through a cube:
/// 4 (351 pairs of opposite offsets for each cube of a small component), a bound on time
/// for any `line`.
const MAX_LINE: i64 = 4;

/// For each point of `points`, whether its cube of edge `cell` metres is one of `cubes`
/// (all `false` when there are none, without looking).
fn in_cubes(points: &[Point3<f64>], cell: f64, cubes: &CellSet<[i64; 3]>) -> Vec<bool> {
    if cubes.is_empty() {
        return vec![false; points.len()];
    }
    points
        .par_iter()
        .with_min_len(PIECE)
        .map(|p| cubes.contains(&CubeBox::cube_of(p, cell)))
        .collect()
}

/// Points per parallel piece of the answer pass: the same answers whatever the split
/// (each point's is its own).
const PIECE: usize = 8192;

/// `cloud` without its specks ([`specks`]), and how many points were left out; `None`
/// when there are none.
pub fn without_specks(
    cloud: &PointCloud,
    cell: f64,
    max_cubes: usize,
    line: usize,
) -> Option<(PointCloud, usize)> {
    let cubes = speck_cubes(&cloud.points, cell, max_cubes, line);
    if cubes.is_empty() {
        return None;
    }
    let flags = in_cubes(&cloud.points, cell, &cubes);
    let dropped = flags.iter().filter(|&&f| f).count();
    (dropped > 0).then(|| {
        let kept = cloud
            .points
            .iter()
            .zip(&flags)
            .filter(|(_, &f)| !f)
            .map(|(p, _)| *p)
            .collect();
        (PointCloud::new(kept), dropped)
    })
}

#[cfg(test)]
// Test data: small literals and counts.
#[allow(clippy::cast_possible_truncation)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A 1 m x 1 m plane at z = `z`, points `step` apart.
    fn plane(z: f64, step: f64) -> Vec<Point3<f64>> {
        let n = (1.0 / step).round() as i64;
        (0..n)
            .flat_map(|i| (0..n).map(move |j| Point3::new(i as f64 * step, j as f64 * step, z)))
            .collect()
    }

    #[test]
    fn a_lone_point_and_a_clump_over_a_surface_are_specks_and_the_surface_is_not() {
        let mut pts = plane(0.45, 0.01);
        let n = pts.len();
        // 0.25 m over the seat: a lone point, and a clump of five within 2 cm.
        pts.push(Point3::new(0.55, 0.55, 0.75));
        for i in 0..5 {
            pts.push(Point3::new(0.2 + i as f64 * 0.004, 0.3, 0.70));
        }
        let flags = specks(&pts, 0.04, 1, 2);
        assert!(flags[..n].iter().all(|f| !f), "the seat's points are kept");
        assert!(flags[n..].iter().all(|&f| f), "{:?}", &flags[n..]);
        // A rod 0.3 m long is more than a few cubes: not a speck.
        let mut rod = plane(0.45, 0.01);
        rod.extend((0..30).map(|i| Point3::new(0.5, 0.5, 0.8 + i as f64 * 0.01)));
        assert!(specks(&rod, 0.04, 4, 2).iter().all(|f| !f));
        // ...but a clump of two cubes is one when two are allowed.
        let mut pair = plane(0.45, 0.01);
        pair.push(Point3::new(0.5, 0.5, 0.80));
        pair.push(Point3::new(0.5, 0.5, 0.85));
        let flags = specks(&pair, 0.04, 2, 2);
        assert_eq!(flags.iter().filter(|&&f| f).count(), 2);
    }

    /// A seat's side edge seen at a grazing angle: a row of single samples 7 cm apart
    /// beside a seat (one empty 4 cm cube between most of them), each piece a speck by
    /// size alone, is kept; a stray 7 cm over the seat, with nothing beyond it, is not.
    /// Fails without the line join (`line` 1).
    #[test]
    fn a_row_of_sparse_samples_is_kept_and_a_stray_beside_a_surface_is_not() {
        let mut pts = plane(0.45, 0.01);
        let n = pts.len();
        pts.extend((0..13).map(|i| Point3::new(0.03 + i as f64 * 0.07, 1.1, 0.45)));
        let row = pts.len();
        pts.push(Point3::new(0.5, 0.5, 0.52));
        let flags = specks(&pts, 0.04, 8, 2);
        assert!(flags[..n].iter().all(|f| !f), "the seat's points are kept");
        assert!(flags[n..row].iter().all(|f| !f), "{:?}", &flags[n..row]);
        assert!(flags[row], "the stray over the seat is a speck");
        // Without the join every piece of the row is a speck.
        let flags = specks(&pts, 0.04, 8, 1);
        assert!(flags[n..row].iter().all(|&f| f), "{:?}", &flags[n..row]);
    }

    #[test]
    fn the_speck_cubes_are_the_cubes_of_the_specks_points() {
        let mut pts = plane(0.45, 0.01);
        assert!(speck_cubes(&pts, 0.04, 8, 2).is_empty());
        // A lone point, and a pair in two cubes side by side.
        pts.push(Point3::new(0.55, 0.55, 0.75));
        pts.push(Point3::new(0.21, 0.3, 0.70));
        pts.push(Point3::new(0.25, 0.3, 0.70));
        let cubes = speck_cubes(&pts, 0.04, 8, 2);
        let mut got: Vec<[i64; 3]> = cubes.iter().copied().collect();
        got.sort_unstable();
        assert_eq!(got, vec![[5, 7, 17], [6, 7, 17], [13, 13, 18]]);
        let flags = in_cubes(&pts, 0.04, &cubes);
        let n = pts.len();
        assert!(flags[..n - 3].iter().all(|f| !f));
        assert!(flags[n - 3..].iter().all(|&f| f));
        // With one cube allowed, the pair is not a speck.
        let one: Vec<[i64; 3]> = speck_cubes(&pts, 0.04, 1, 2).into_iter().collect();
        assert_eq!(one, vec![[13, 13, 18]]);
    }

    #[test]
    fn the_dense_grid_finds_the_hashed_cubes() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let sorted = |set: CellSet<[i64; 3]>| {
            let mut v: Vec<[i64; 3]> = set.into_iter().collect();
            v.sort_unstable();
            v
        };
        let mut found = 0;
        for round in 0..40 {
            // Planes, rods and clumps of random sizes, shuffled (no runs), and strays,
            // some on the box's faces and corners, some negative.
            let mut pts = plane(rng.random_range(-0.5..0.5), 0.02);
            for _ in 0..rng.random_range(0..30) {
                let at = Point3::new(
                    rng.random_range(-0.6..1.6),
                    rng.random_range(-0.6..1.6),
                    rng.random_range(-0.6..1.6),
                );
                for _ in 0..rng.random_range(1..12) {
                    pts.push(
                        at + Vector3::new(
                            rng.random_range(0.0..0.08),
                            rng.random_range(0.0..0.08),
                            rng.random_range(0.0..0.08),
                        ),
                    );
                }
            }
            for i in (1..pts.len()).rev() {
                pts.swap(i, rng.random_range(0..=i));
            }
            let cell = [0.04, 0.05, 0.1][round % 3];
            let max_cubes = [1, 2, 8][round % 3];
            let line = [1, 2, 3, 2][round % 4];
            let keys: Vec<[i64; 3]> = pts.iter().map(|p| CubeBox::cube_of(p, cell)).collect();
            let lo = [0, 1, 2].map(|a| keys.iter().map(|k| k[a]).min().unwrap());
            let hi = [0, 1, 2].map(|a| keys.iter().map(|k| k[a]).max().unwrap());
            let dims = [0, 1, 2].map(|a| usize::try_from(hi[a] - lo[a] + 1).unwrap());
            assert_eq!(CubeBox::of(&pts, cell, PIECE), Some(CubeBox { lo, dims }));
            let hashed = sorted(hashed_speck_cubes(&pts, cell, max_cubes, line));
            let boxed = CubeBox { lo, dims };
            let dense = sorted(dense_speck_cubes(&pts, cell, max_cubes, line, boxed).unwrap());
            assert_eq!(dense, hashed, "round {round}");
            assert_eq!(sorted(speck_cubes(&pts, cell, max_cubes, line)), hashed);
            found += hashed.len();
        }
        assert!(found > 100, "{found} speck cubes");
        // Shuffled (no runs) in a small box, with two strays: `speck_cubes` takes the
        // dense grid, with the hashed answer.
        let mut shuffled = plane(0.0, 0.01);
        shuffled.push(Point3::new(0.5, 0.5, 0.6));
        shuffled.push(Point3::new(0.9, 0.1, 0.3));
        for i in (1..shuffled.len()).rev() {
            shuffled.swap(i, rng.random_range(0..=i));
        }
        let want = sorted(hashed_speck_cubes(&shuffled, 0.1, 1, 2));
        assert_eq!(want, vec![[5, 5, 5], [9, 1, 2]]);
        assert_eq!(sorted(speck_cubes(&shuffled, 0.1, 1, 2)), want);
        // A non-finite coordinate puts a cube outside the box of the others: hashed.
        let mut odd = plane(0.0, 0.02);
        odd.push(Point3::new(f64::NAN, 3.0, 0.5));
        odd.push(Point3::new(0.5, f64::INFINITY, 0.5));
        assert_eq!(
            sorted(speck_cubes(&odd, 0.04, 8, 2)),
            sorted(hashed_speck_cubes(&odd, 0.04, 8, 2))
        );
    }

    #[test]
    fn sparse_surfaces_are_kept() {
        // Vertices 8 cm apart on 0.1 m cubes (a decimated reconstruction): every cube has
        // neighbours, so the surface is one component, whatever the points' order.
        let mut pts = plane(0.0, 0.08);
        assert!(specks(&pts, 0.10, 8, 2).iter().all(|f| !f));
        pts.reverse();
        assert!(specks(&pts, 0.10, 8, 2).iter().all(|f| !f));
    }

    #[test]
    fn the_answer_does_not_depend_on_the_order() {
        let mut pts = plane(0.45, 0.05);
        pts.extend([
            Point3::new(2.0, 2.0, 1.0),
            Point3::new(-1.0, 0.5, 0.3),
            Point3::new(0.5, 0.5, 0.7),
            Point3::new(0.5, 0.52, 0.7),
        ]);
        let forward = specks(&pts, 0.10, 1, 2);
        let mut rev = pts.clone();
        rev.reverse();
        let mut backward = specks(&rev, 0.10, 1, 2);
        backward.reverse();
        assert_eq!(forward, backward);
        assert_eq!(forward.iter().filter(|&&f| f).count(), 4);
    }

    #[test]
    fn pieces_and_threads_do_not_change_the_answer() {
        // 40 000 plane points (several pieces, the plane's cubes met in many of them) with
        // strays and clumps between them in the list.
        let mut pts = plane(0.45, 0.005);
        let mut strays = Vec::new();
        for i in 0..30 {
            let at = Point3::new(0.1 + 0.03 * i as f64, 0.5, 0.9);
            let clump = if i % 2 == 0 { 1 } else { 6 };
            for j in 0..clump {
                strays.push(pts.len() / 30 * i + j);
                pts.insert(
                    pts.len() / 30 * i + j,
                    at + Vector3::new(0.0, 0.0, 0.002 * j as f64),
                );
            }
        }
        let on = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| specks(&pts, 0.04, 8, 2))
        };
        let one = on(1);
        assert_eq!(one, on(2));
        assert_eq!(one, on(3));
        // The strays 0.03 m apart along x join up into one component of 23 cubes: kept.
        // Moved off the plane in groups of six 0.3 m apart, they are specks.
        assert!(one.iter().all(|f| !f));
        let mut apart = pts.clone();
        for (n, &i) in strays.iter().enumerate() {
            apart[i].x = 0.1 + 0.3 * (n / 6) as f64 + 0.001 * (n % 6) as f64;
            apart[i].y = 2.0;
        }
        let flags = specks(&apart, 0.04, 8, 2);
        let marked: Vec<usize> = (0..apart.len()).filter(|&i| flags[i]).collect();
        let mut expected = strays.clone();
        expected.sort_unstable();
        assert_eq!(marked, expected);
    }

    #[test]
    fn without_specks_keeps_the_rest_in_order() {
        let mut pts = plane(0.0, 0.02);
        let first = pts.len();
        pts.push(Point3::new(5.0, 5.0, 1.0));
        pts.extend(
            plane(0.45, 0.02)
                .iter()
                .map(|p| p + Vector3::new(3.0, 0.0, 0.0)),
        );
        let cloud = PointCloud::new(pts.clone());
        let (kept, dropped) = without_specks(&cloud, 0.10, 8, 2).expect("one dropped");
        assert_eq!(dropped, 1);
        let mut expected = pts.clone();
        expected.remove(first);
        assert_eq!(kept.points, expected);
        assert!(without_specks(&PointCloud::new(plane(0.0, 0.02)), 0.10, 8, 2).is_none());
    }
}
