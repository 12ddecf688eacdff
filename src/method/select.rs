//! Selection and segmentation (section 4.5): the best pose per hypothesis is kept, weaker
//! poses within the agent radius of a stronger one are suppressed, and the points that
//! afford each detection are grown from it.

use nalgebra::Point3;

use crate::cellhash::CellMap;
use crate::cloud::PointCloud;
use crate::num::to_i64;

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
pub fn segment(
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
                        if label[i].is_none() && (cloud.points[i] - seed).norm() <= cfg.seed_radius
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
                            if label[j].is_none() && (cloud.points[j] - p).norm_squared() <= r2 {
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

#[cfg(test)]
mod tests {
    use super::*;

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
