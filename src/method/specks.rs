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
//! point or a clump with no other point within `cell` of it. The components are a
//! partition of the occupied cubes, which depends only on the set of points, so the
//! answer does not depend on their order or on the thread count.

use nalgebra::Point3;
use rayon::prelude::*;

use crate::cellhash::{CellMap, CellSet};
use crate::cloud::PointCloud;
use crate::num::floor_i64;

/// For each point of `points`, whether it belongs to a speck: a 26-connected component of
/// at most `max_cubes` occupied cubes of edge `cell` metres (see the module
/// documentation). Cube indices saturate at `i64`'s range (the guard refuses coordinates
/// that far out before this stage runs).
pub fn specks(points: &[Point3<f64>], cell: f64, max_cubes: usize) -> Vec<bool> {
    in_cubes(points, cell, &speck_cubes(points, cell, max_cubes))
}

/// The cube of edge `cell` metres holding `p`, as cube indices along x, y and z.
fn cube_of(p: &Point3<f64>, cell: f64) -> [i64; 3] {
    [p.x, p.y, p.z].map(|c| floor_i64(c / cell))
}

/// The occupied cubes of edge `cell` metres of `points` that lie in components of at most
/// `max_cubes` cubes (see [`specks`]): usually none, and a few where there are specks.
fn speck_cubes(points: &[Point3<f64>], cell: f64, max_cubes: usize) -> CellSet<[i64; 3]> {
    // The occupied cubes, numbered in the order first met. A depth image lists row
    // neighbours side by side: a run of points in one cube is looked up once.
    let mut ids: CellMap<[i64; 3], usize> = CellMap::default();
    let mut cubes: Vec<[i64; 3]> = Vec::new();
    let mut last: Option<[i64; 3]> = None;
    for p in points {
        let k = cube_of(p, cell);
        if last != Some(k) {
            ids.entry(k).or_insert_with(|| {
                cubes.push(k);
                cubes.len() - 1
            });
            last = Some(k);
        }
    }
    // Union-find over the cubes: each joined with its occupied neighbours on the 13 sides
    // after it in (x, y, z) order, which meets every one of the 26 adjacencies once. The
    // smaller root becomes the parent; the partition is the same in any order.
    let mut parent: Vec<usize> = (0..cubes.len()).collect();
    let root = |parent: &mut [usize], mut x: usize| {
        while parent[x] != x {
            parent[x] = parent[parent[x]];
            x = parent[x];
        }
        x
    };
    for (i, k) in cubes.iter().enumerate() {
        for (dx, dy, dz) in HALF_NEIGHBOURS {
            let n = [
                k[0].wrapping_add(dx),
                k[1].wrapping_add(dy),
                k[2].wrapping_add(dz),
            ];
            if let Some(&j) = ids.get(&n) {
                let (a, b) = (root(&mut parent, i), root(&mut parent, j));
                parent[a.max(b)] = a.min(b);
            }
        }
    }
    let roots: Vec<usize> = (0..cubes.len()).map(|i| root(&mut parent, i)).collect();
    let mut size = vec![0usize; cubes.len()];
    for &r in &roots {
        size[r] += 1;
    }
    cubes
        .iter()
        .zip(&roots)
        .filter(|(_, &r)| size[r] <= max_cubes)
        .map(|(k, _)| *k)
        .collect()
}

/// For each point of `points`, whether its cube of edge `cell` metres is one of `cubes`
/// (all `false` when there are none, without looking).
fn in_cubes(points: &[Point3<f64>], cell: f64, cubes: &CellSet<[i64; 3]>) -> Vec<bool> {
    if cubes.is_empty() {
        return vec![false; points.len()];
    }
    points
        .par_iter()
        .with_min_len(PIECE)
        .map(|p| cubes.contains(&cube_of(p, cell)))
        .collect()
}

/// The 13 neighbour offsets after `(0, 0, 0)` in lexicographic order: with their
/// opposites, the 26 cubes round a cube.
const HALF_NEIGHBOURS: [(i64, i64, i64); 13] = [
    (0, 0, 1),
    (0, 1, -1),
    (0, 1, 0),
    (0, 1, 1),
    (1, -1, -1),
    (1, -1, 0),
    (1, -1, 1),
    (1, 0, -1),
    (1, 0, 0),
    (1, 0, 1),
    (1, 1, -1),
    (1, 1, 0),
    (1, 1, 1),
];

/// Points per parallel piece of the answer pass: the same answers whatever the split
/// (each point's is its own).
const PIECE: usize = 8192;

/// `cloud` without its specks ([`specks`]), and how many points were left out; `None`
/// when there are none.
pub fn without_specks(
    cloud: &PointCloud,
    cell: f64,
    max_cubes: usize,
) -> Option<(PointCloud, usize)> {
    let cubes = speck_cubes(&cloud.points, cell, max_cubes);
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
    fn the_offsets_and_their_opposites_are_the_26_neighbours() {
        let mut all: Vec<(i64, i64, i64)> = HALF_NEIGHBOURS
            .iter()
            .flat_map(|&(x, y, z)| [(x, y, z), (-x, -y, -z)])
            .collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 26);
        assert!(!all.contains(&(0, 0, 0)));
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
        let flags = specks(&pts, 0.04, 1);
        assert!(flags[..n].iter().all(|f| !f), "the seat's points are kept");
        assert!(flags[n..].iter().all(|&f| f), "{:?}", &flags[n..]);
        // A rod 0.3 m long is more than a few cubes: not a speck.
        let mut rod = plane(0.45, 0.01);
        rod.extend((0..30).map(|i| Point3::new(0.5, 0.5, 0.8 + i as f64 * 0.01)));
        assert!(specks(&rod, 0.04, 4).iter().all(|f| !f));
        // ...but a clump of two cubes is one when two are allowed.
        let mut pair = plane(0.45, 0.01);
        pair.push(Point3::new(0.5, 0.5, 0.80));
        pair.push(Point3::new(0.5, 0.5, 0.85));
        let flags = specks(&pair, 0.04, 2);
        assert_eq!(flags.iter().filter(|&&f| f).count(), 2);
    }

    #[test]
    fn the_speck_cubes_are_the_cubes_of_the_specks_points() {
        let mut pts = plane(0.45, 0.01);
        assert!(speck_cubes(&pts, 0.04, 8).is_empty());
        // A lone point, and a pair in two cubes side by side.
        pts.push(Point3::new(0.55, 0.55, 0.75));
        pts.push(Point3::new(0.21, 0.3, 0.70));
        pts.push(Point3::new(0.25, 0.3, 0.70));
        let cubes = speck_cubes(&pts, 0.04, 8);
        let mut got: Vec<[i64; 3]> = cubes.iter().copied().collect();
        got.sort_unstable();
        assert_eq!(got, vec![[5, 7, 17], [6, 7, 17], [13, 13, 18]]);
        let flags = in_cubes(&pts, 0.04, &cubes);
        let n = pts.len();
        assert!(flags[..n - 3].iter().all(|f| !f));
        assert!(flags[n - 3..].iter().all(|&f| f));
        // With one cube allowed, the pair is not a speck.
        let one: Vec<[i64; 3]> = speck_cubes(&pts, 0.04, 1).into_iter().collect();
        assert_eq!(one, vec![[13, 13, 18]]);
    }

    #[test]
    fn sparse_surfaces_are_kept() {
        // Vertices 8 cm apart on 0.1 m cubes (a decimated reconstruction): every cube has
        // neighbours, so the surface is one component, whatever the points' order.
        let mut pts = plane(0.0, 0.08);
        assert!(specks(&pts, 0.10, 8).iter().all(|f| !f));
        pts.reverse();
        assert!(specks(&pts, 0.10, 8).iter().all(|f| !f));
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
        let forward = specks(&pts, 0.10, 1);
        let mut rev = pts.clone();
        rev.reverse();
        let mut backward = specks(&rev, 0.10, 1);
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
                .install(|| specks(&pts, 0.04, 8))
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
        let flags = specks(&apart, 0.04, 8);
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
        let (kept, dropped) = without_specks(&cloud, 0.10, 8).expect("one dropped");
        assert_eq!(dropped, 1);
        let mut expected = pts.clone();
        expected.remove(first);
        assert_eq!(kept.points, expected);
        assert!(without_specks(&PointCloud::new(plane(0.0, 0.02)), 0.10, 8).is_none());
    }
}
