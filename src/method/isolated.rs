//! Isolated points: points that no surface holds, left out of the grids.
//!
//! A surface the body can rest on or touch is sampled densely: a depth camera's points
//! lie millimetres to centimetres apart, a reconstruction's vertices a few centimetres,
//! and the height map bridges gaps of at most 0.10 m. A point with no other point near it
//! is none of these: sensor speckle, a return from a window or a mirror, a dust particle
//! in a laser scan. Kept, each one fills a voxel the body collides with (a phantom
//! obstacle over a seat, a phantom armrest under a forearm) and can be the highest point
//! of its height-map cell. The guard ([`super::extent`]) drops whole regions far from the
//! scene; this stage drops single points inside it.
//!
//! The test is on a grid of cubes of edge `cell`: a point is isolated when it is the only
//! point in its cube and the 26 cubes round it hold none, that is, when no other point
//! lies within `cell` of it (and none within up to `3 cell` in the directions of its
//! cube's neighbours). It reads only the points, so its answer does not depend on their
//! order or on the thread count.

use nalgebra::Point3;

use rayon::prelude::*;

use crate::cellhash::CellMap;
use crate::cloud::PointCloud;
use crate::num::floor_i64;

/// For each point of `points`, whether it is isolated on the grid of cubes of edge
/// `cell` metres (see the module documentation). Cube indices saturate at `i64`'s range
/// (the guard refuses coordinates that far out before this stage runs).
pub fn isolated(points: &[Point3<f64>], cell: f64) -> Vec<bool> {
    let keys: Vec<[i64; 3]> = points
        .par_iter()
        .with_min_len(PIECE)
        .map(|p| [p.x, p.y, p.z].map(|c| floor_i64(c / cell)))
        .collect();
    // Points per cube, counted up to 2 (one or more than one is all that matters). A
    // depth image lists row neighbours side by side: a run of points in one cube is
    // counted with one look-up. The counts do not depend on the order of the points.
    let mut counts: CellMap<[i64; 3], u8> = CellMap::default();
    let mut i = 0;
    while i < keys.len() {
        let k = keys[i];
        let mut j = i + 1;
        while j < keys.len() && j - i < 2 && keys[j] == k {
            j += 1;
        }
        let run = if j - i >= 2 { 2 } else { 1 };
        let c = counts.entry(k).or_insert(0);
        *c = (*c + run).min(2);
        while j < keys.len() && keys[j] == k {
            j += 1;
        }
        i = j;
    }
    let occupied = |k: &[i64; 3]| counts.contains_key(k);
    keys.par_iter()
        .with_min_len(PIECE)
        .map(|k| {
            if counts.get(k) != Some(&1) {
                return false;
            }
            let mut n = *k;
            for dx in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dz in -1i64..=1 {
                        if (dx, dy, dz) == (0, 0, 0) {
                            continue;
                        }
                        n[0] = k[0].wrapping_add(dx);
                        n[1] = k[1].wrapping_add(dy);
                        n[2] = k[2].wrapping_add(dz);
                        if occupied(&n) {
                            return false;
                        }
                    }
                }
            }
            true
        })
        .collect()
}

/// Points per parallel piece of the key and neighbour passes: the same keys and answers
/// whatever the split (each point's is its own).
const PIECE: usize = 8192;

/// `cloud` without its isolated points ([`isolated`] on cubes of edge `cell` metres), and
/// how many were left out; `None` when there are none.
pub fn without_isolated(cloud: &PointCloud, cell: f64) -> Option<(PointCloud, usize)> {
    let flags = isolated(&cloud.points, cell);
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

    /// A 1 m x 1 m plane at z = `z`, points `step` apart.
    fn plane(z: f64, step: f64) -> Vec<Point3<f64>> {
        let n = (1.0 / step).round() as i64;
        (0..n)
            .flat_map(|i| (0..n).map(move |j| Point3::new(i as f64 * step, j as f64 * step, z)))
            .collect()
    }

    #[test]
    fn a_lone_point_over_a_surface_is_isolated_and_the_surface_is_not() {
        let mut pts = plane(0.45, 0.01);
        let n = pts.len();
        // 0.25 m over the seat: no point within 0.10 m, nor in the cubes round its own.
        pts.push(Point3::new(0.55, 0.55, 0.75));
        // A pair of points 3 cm apart: each has a neighbour, neither is isolated.
        pts.push(Point3::new(0.30, 0.30, 1.20));
        pts.push(Point3::new(0.33, 0.30, 1.20));
        let flags = isolated(&pts, 0.10);
        assert!(flags[..n].iter().all(|f| !f), "the seat's points are kept");
        assert_eq!(&flags[n..], &[true, false, false]);
    }

    #[test]
    fn sparse_surfaces_are_kept() {
        // Vertices 8 cm apart (a decimated reconstruction): each has neighbours in the
        // cubes round its own, so none is dropped, whatever the points' order.
        let mut pts = plane(0.0, 0.08);
        assert!(isolated(&pts, 0.10).iter().all(|f| !f));
        pts.reverse();
        assert!(isolated(&pts, 0.10).iter().all(|f| !f));
    }

    #[test]
    fn the_answer_does_not_depend_on_the_order() {
        let mut pts = plane(0.45, 0.05);
        pts.extend([
            Point3::new(2.0, 2.0, 1.0),
            Point3::new(-1.0, 0.5, 0.3),
            Point3::new(0.5, 0.5, 0.7),
        ]);
        let forward = isolated(&pts, 0.10);
        let mut rev = pts.clone();
        rev.reverse();
        let mut backward = isolated(&rev, 0.10);
        backward.reverse();
        assert_eq!(forward, backward);
        assert_eq!(forward.iter().filter(|&&f| f).count(), 3);
    }

    #[test]
    fn without_isolated_keeps_the_rest_in_order() {
        let mut pts = plane(0.0, 0.02);
        let first = pts.len();
        pts.push(Point3::new(5.0, 5.0, 1.0));
        pts.extend(
            plane(0.45, 0.02)
                .iter()
                .map(|p| p + nalgebra::Vector3::new(3.0, 0.0, 0.0)),
        );
        let cloud = PointCloud::new(pts.clone());
        let (kept, dropped) = without_isolated(&cloud, 0.10).expect("one dropped");
        assert_eq!(dropped, 1);
        let mut expected = pts.clone();
        expected.remove(first);
        assert_eq!(kept.points, expected);
        assert!(without_isolated(&PointCloud::new(plane(0.0, 0.02)), 0.10).is_none());
    }
}
