//! The height map of section 4.1: the scene seen from above in square cells, each holding
//! the height of its highest point; cells without points are invalid.

use crate::cloud::PointCloud;

/// A height map over the x-y plane (metres, z up).
#[derive(Debug, Clone, PartialEq)]
pub struct HeightMap {
    /// World x of the lower edge of column 0, metres.
    pub x0: f64,
    /// World y of the lower edge of row 0, metres.
    pub y0: f64,
    /// Cell edge length, metres.
    pub cell: f64,
    /// Number of columns (along x).
    pub nx: usize,
    /// Number of rows (along y).
    pub ny: usize,
    /// Highest z per cell, row-major (`iy * nx + ix`); `None` where the cell is invalid.
    pub heights: Vec<Option<f64>>,
}

impl HeightMap {
    /// Builds the height map of `cloud` with cells of `cell` metres (highest point per cell).
    /// An empty cloud gives an empty map.
    pub fn from_cloud(cloud: &PointCloud, cell: f64) -> HeightMap {
        let Some((lo, hi)) = cloud.bounds() else {
            return HeightMap {
                x0: 0.0,
                y0: 0.0,
                cell,
                nx: 0,
                ny: 0,
                heights: Vec::new(),
            };
        };
        let nx = ((hi.x - lo.x) / cell).floor() as usize + 1;
        let ny = ((hi.y - lo.y) / cell).floor() as usize + 1;
        let mut heights: Vec<Option<f64>> = vec![None; nx * ny];
        for p in &cloud.points {
            let ix = (((p.x - lo.x) / cell) as usize).min(nx - 1);
            let iy = (((p.y - lo.y) / cell) as usize).min(ny - 1);
            let h = &mut heights[iy * nx + ix];
            *h = Some(h.map_or(p.z, |z: f64| z.max(p.z)));
        }
        HeightMap {
            x0: lo.x,
            y0: lo.y,
            cell,
            nx,
            ny,
            heights,
        }
    }

    /// Height of cell `(ix, iy)`; `None` if invalid or outside the map.
    pub fn get(&self, ix: isize, iy: isize) -> Option<f64> {
        if ix < 0 || iy < 0 || ix as usize >= self.nx || iy as usize >= self.ny {
            return None;
        }
        self.heights[iy as usize * self.nx + ix as usize]
    }

    /// World (x, y) of the centre of cell `(ix, iy)`, metres.
    pub fn centre(&self, ix: usize, iy: usize) -> (f64, f64) {
        (
            self.x0 + (ix as f64 + 0.5) * self.cell,
            self.y0 + (iy as f64 + 0.5) * self.cell,
        )
    }

    /// Cell offsets `(dx, dy)` whose centres lie within `radius` metres of a cell's centre.
    pub fn disc(&self, radius: f64) -> Vec<(isize, isize)> {
        let r = (radius / self.cell).floor() as isize;
        let mut out = Vec::new();
        for dy in -r..=r {
            for dx in -r..=r {
                let d2 = ((dx * dx + dy * dy) as f64) * self.cell * self.cell;
                if d2 <= radius * radius + 1e-12 {
                    out.push((dx, dy));
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    #[test]
    fn a_box_top_and_an_empty_cell() {
        // Points of a 0.1 x 0.1 box top at z = 0.45 over cells (0..2, 0..2) of 0.05 m, a
        // floor point at (0.175, 0.025) and nothing at (0.175, 0.075).
        let mut pts = Vec::new();
        for i in 0..4 {
            for j in 0..4 {
                let (x, y) = (0.01 + 0.025 * i as f64, 0.01 + 0.025 * j as f64);
                pts.push(Point3::new(x, y, 0.45));
                pts.push(Point3::new(x, y, 0.0));
            }
        }
        pts.push(Point3::new(0.175, 0.025, 0.0));
        pts.push(Point3::new(0.01, 0.099, 0.2));
        let m = HeightMap::from_cloud(&PointCloud::new(pts), 0.05);
        assert_eq!((m.nx, m.ny), (4, 2));
        assert_eq!(m.get(0, 0), Some(0.45));
        assert_eq!(m.get(1, 1), Some(0.45));
        assert_eq!(m.get(3, 0), Some(0.0));
        assert_eq!(m.get(3, 1), None);
        assert_eq!(m.get(-1, 0), None);
        let (x, y) = m.centre(3, 1);
        assert!((x - 0.185).abs() < 1e-9 && (y - 0.085).abs() < 1e-9);
    }

    #[test]
    fn empty_cloud_gives_empty_map() {
        let m = HeightMap::from_cloud(&PointCloud::default(), 0.05);
        assert_eq!(m.heights.len(), 0);
        assert_eq!(m.get(0, 0), None);
    }

    #[test]
    fn disc_counts_cells_within_radius() {
        let m = HeightMap {
            x0: 0.0,
            y0: 0.0,
            cell: 0.05,
            nx: 0,
            ny: 0,
            heights: vec![],
        };
        assert_eq!(m.disc(0.0).len(), 1);
        assert_eq!(m.disc(0.05).len(), 5);
        assert_eq!(m.disc(0.075).len(), 9);
    }
}
