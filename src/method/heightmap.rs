//! The height map of section 4.1: the scene seen from above in square cells. The paper
//! keeps the highest point of each cell; here a cell keeps the top of the lowest stack of
//! points standing on the floor, so that ceilings, table tops, shelves and upper bunks
//! (anything with a tall free gap beneath it) do not hide the seats and beds under them,
//! and each point counts in the cells within a point spacing of it, so that surfaces
//! sampled more sparsely than the cells (reconstructions read as vertices, subsampled
//! clouds) have no empty cells. Cells where nothing is
//! seen stay invalid.

use crate::cloud::{point_spacing, PointCloud, TileSpacing};
use crate::num::{to_isize, to_usize};
use nalgebra::Point3;

/// How the height map is built. Defaults carry their reasons.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeightMapConfig {
    /// Cell edge length, metres.
    pub cell: f64,
    /// A vertical gap at least this tall (metres) under a layer of points makes that layer
    /// a roof over what is below (a ceiling, an upper bunk, a high shelf), not part of the
    /// furniture the body uses; the floor, z = 0, counts as the lowest layer.
    pub overhang_gap: f64,
    /// Over a surface at seat height (`seat_band`), a gap this tall (metres) is enough to
    /// make what is above it a roof: a table top, a shelf or an arm rail over a seat, not
    /// the seat itself.
    pub thigh_gap: f64,
    /// Heights (metres) of the surfaces people sit or lie on: a gap of `thigh_gap` over a
    /// surface in this band ends the stack.
    pub seat_band: [f64; 2],
    /// Each point stands for the surface within this many point spacings (the cloud's
    /// median nearest-neighbour distance) of it: it counts in every cell whose centre lies
    /// that close, so a surface sampled more sparsely than the cells has no empty cells.
    pub sample_reach: f64,
    /// The most a point may stand for, metres, however sparse the cloud.
    pub max_reach: f64,
    /// Side of the cube tiles whose own point spacing a point's reach follows, metres.
    pub spacing_tile: f64,
    /// Points per tile whose neighbours measure its spacing, at most.
    pub spacing_queries: usize,
}

impl Default for HeightMapConfig {
    fn default() -> Self {
        HeightMapConfig {
            // Paper, section 4.1: 0.05 m balanced precision and time.
            cell: 0.05,
            // 0.85 m: the sitting height of a 1.65 m adult (0.52 H): under less free space
            // nobody sits upright, so what covers a surface that closely (a table top over a
            // seat, a bar stool's top over the floor) belongs to the furniture, as in the
            // paper's map; ceilings, upper bunks and shelves above head height do not.
            overhang_gap: 0.85,
            // 0.15 m: a seated adult's thigh thickness (thigh clearance 0.13-0.18 m, 5th-95th
            // percentile): desks and tables leave 0.22-0.30 m over a 0.45 m seat, arm rails
            // over a seat's edges ~0.19 m; cushions and backs rise from the seat without a gap.
            thigh_gap: 0.15,
            // Chair and bench seats pushed under tables (0.38-0.50 m) up to the highest
            // beds and stool seats reached without climbing (0.75 m); from 0.35 m, so that a
            // chair's leg stretchers (0.15-0.30 m) do not cut the seat above them.
            seat_band: [0.35, 0.75],
            // One spacing: every point of a surface sampled on a grid is within 0.71 spacings
            // of a sample, so a cell centre farther than a spacing from every sample is off
            // the surface or in a hole; edges grow by at most a spacing. Dense clouds
            // (spacing under half a cell, 2.5 cm) count each point in its own cell only.
            sample_reach: 1.0,
            // 0.10 m: 20k-50k-point room views sample their surfaces every 5-10 cm; points
            // farther apart than that do not describe a surface a body could rest on.
            max_reach: 0.10,
            // 0.25 m: each surface a body rests on is sampled at its own density (a depth
            // camera's falls with the square of the range, so a bed at 3.5 m has an eighth
            // of the floor's at 1.2 m; a decimated mesh keeps few vertices on flat parts),
            // so a point reaches by its tile's spacing, never less than the cloud's median (a
            // denser patch keeps the reach it had). Tiles are cubes smaller than the height
            // of a seat (0.4 m) so that a seat and the floor seen under it are apart, and
            // large enough to hold 25 samples of a surface sampled every 5 cm.
            spacing_tile: 0.25,
            // 16 points: the median of 16 neighbour distances is within ~15 % of a tile's.
            spacing_queries: 16,
        }
    }
}

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
    /// Surface height per cell, row-major (`iy * nx + ix`); `None` where the cell is invalid.
    pub heights: Vec<Option<f64>>,
}

impl HeightMap {
    /// Builds the height map of `cloud` (world frame, metres, floor at z = 0) with cells
    /// of `cfg.cell` metres: per cell, the top of the lowest stack of points, a stack
    /// ending under a gap of at least `cfg.overhang_gap`; a cell whose lowest point floats
    /// that far above the floor sees only a roof and is invalid. Each point counts in every
    /// cell whose centre is within `cfg.sample_reach` point spacings of it. An empty cloud gives an empty map.
    pub fn from_cloud(cloud: &PointCloud, cfg: &HeightMapConfig) -> HeightMap {
        let cell = cfg.cell;
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
        let nx = to_usize(((hi.x - lo.x) / cell).floor()) + 1;
        let ny = to_usize(((hi.y - lo.y) / cell).floor()) + 1;
        let global = point_spacing(cloud);
        let tiles = TileSpacing::new(cloud, lo, cfg.spacing_tile, cfg.spacing_queries);
        // How far each point reaches: its tile's spacing, at least the cloud's (looked up
        // once, for both passes below).
        let reaches: Vec<f64> = cloud
            .points
            .iter()
            .map(|p| {
                global.map_or(0.0, |g| {
                    let s = tiles.at(p).map_or(g, |t| t.max(g));
                    (cfg.sample_reach * s).min(cfg.max_reach)
                })
            })
            .collect();
        let widest = reaches.iter().copied().fold(0.0, f64::max);
        // Cell offsets a point may reach beyond its own cell (none for dense clouds).
        let r = to_isize((widest / cell).ceil());
        let cells_of = |p: &Point3<f64>, reach: f64, out: &mut Vec<usize>| {
            let (x, y) = (p.x, p.y);
            out.clear();
            let fx = (x - lo.x) / cell;
            let fy = (y - lo.y) / cell;
            let ix = to_usize(fx).min(nx - 1) as isize;
            let iy = to_usize(fy).min(ny - 1) as isize;
            out.push(iy as usize * nx + ix as usize);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (jx, jy) = (ix + dx, iy + dy);
                    if (dx, dy) == (0, 0)
                        || jx < 0
                        || jy < 0
                        || jx >= nx as isize
                        || jy >= ny as isize
                    {
                        continue;
                    }
                    let (cx, cy) = ((jx as f64 + 0.5 - fx) * cell, (jy as f64 + 0.5 - fy) * cell);
                    if cx * cx + cy * cy <= reach * reach {
                        out.push(jy as usize * nx + jx as usize);
                    }
                }
            }
        };
        // The points' heights grouped by cell (counting sort), then sorted within a cell.
        let mut start = vec![0usize; nx * ny + 1];
        let mut cells = Vec::new();
        for (p, &reach) in cloud.points.iter().zip(&reaches) {
            cells_of(p, reach, &mut cells);
            for &c in &cells {
                start[c + 1] += 1;
            }
        }
        for i in 0..nx * ny {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut zs = vec![0.0f64; start[nx * ny]];
        for (p, &reach) in cloud.points.iter().zip(&reaches) {
            cells_of(p, reach, &mut cells);
            for &c in &cells {
                zs[fill[c]] = p.z;
                fill[c] += 1;
            }
        }
        let heights: Vec<Option<f64>> = (0..nx * ny)
            .map(|c| {
                let column = &mut zs[start[c]..start[c + 1]];
                column.sort_unstable_by(f64::total_cmp);
                stack_top(column, cfg)
            })
            .collect();
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
        let r = to_isize((radius / self.cell).floor());
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

/// The top of the lowest stack of the sorted heights `column` standing on the floor
/// (z = 0): the stack ends below the first gap of at least `cfg.overhang_gap` metres, or
/// of `cfg.thigh_gap` over a top in `cfg.seat_band`. `None` for an empty column or one
/// whose lowest point is `cfg.overhang_gap` or more above the floor (only a roof was seen
/// there).
fn stack_top(column: &[f64], cfg: &HeightMapConfig) -> Option<f64> {
    let (&first, rest) = column.split_first()?;
    if first >= cfg.overhang_gap {
        return None;
    }
    let [seat_lo, seat_hi] = cfg.seat_band;
    let mut top = first;
    for &z in rest {
        let gap = z - top;
        if gap >= cfg.overhang_gap || (gap >= cfg.thigh_gap && (seat_lo..=seat_hi).contains(&top)) {
            break;
        }
        top = z;
    }
    Some(top)
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
        let m = HeightMap::from_cloud(&PointCloud::new(pts), &HeightMapConfig::default());
        assert_eq!((m.nx, m.ny), (4, 2));
        assert_eq!(m.get(0, 0), Some(0.45));
        assert_eq!(m.get(1, 1), Some(0.45));
        assert_eq!(m.get(3, 0), Some(0.0));
        assert_eq!(m.get(3, 1), None);
        assert_eq!(m.get(-1, 0), None);
        let (x, y) = m.centre(3, 1);
        assert!((x - 0.185).abs() < 1e-9 && (y - 0.085).abs() < 1e-9);
    }

    /// A square of points `step` apart over `[x0, x0 + side) x [y0, y0 + side)` at height `z`.
    fn square(x0: f64, y0: f64, side: f64, step: f64, z: f64) -> Vec<Point3<f64>> {
        let n = to_usize((side / step).round());
        let mut pts = Vec::new();
        for i in 0..n {
            for j in 0..n {
                pts.push(Point3::new(
                    x0 + (i as f64 + 0.5) * step,
                    y0 + (j as f64 + 0.5) * step,
                    z,
                ));
            }
        }
        pts
    }

    /// Issue 11: the highest point of every cell of a room scan is the ceiling, and a
    /// shelf or an upper bunk hides what is under it; the paper's map then shows no seat.
    #[test]
    fn roofs_do_not_hide_what_is_under_them() {
        let mut pts = square(0.0, 0.0, 2.0, 0.02, 0.0); // floor
        pts.extend(square(0.5, 0.5, 0.5, 0.02, 0.45)); // seat
        pts.extend(square(1.2, 0.5, 0.4, 0.02, 0.72)); // table top over floor
        pts.extend(square(0.0, 0.0, 2.0, 0.02, 2.5)); // ceiling
        pts.extend(square(1.0, 1.4, 0.3, 0.02, 1.6)); // floating shelf, nothing below but floor
        pts.extend(square(0.2, 1.0, 0.3, 0.02, 0.5)); // a bed top ...
        pts.extend(square(0.2, 1.0, 0.3, 0.02, 1.5)); // ... under an upper bunk
        let m = HeightMap::from_cloud(&PointCloud::new(pts.clone()), &HeightMapConfig::default());
        let at =
            |x: f64, y: f64| m.get(to_isize((x - m.x0) / m.cell), to_isize((y - m.y0) / m.cell));
        assert_eq!(at(0.72, 0.72), Some(0.45), "seat under the ceiling");
        assert_eq!(at(1.4, 0.7), Some(0.72), "no room to sit under a table top");
        assert_eq!(at(1.1, 1.5), Some(0.0), "shelf");
        assert_eq!(at(0.35, 1.15), Some(0.5), "bed under a bunk");
        assert_eq!(at(0.2, 1.8), Some(0.0), "floor under the ceiling");
        // A back rising from the seat is part of its stack: the cell shows its top.
        let mut back = pts;
        for k in 0..30 {
            back.push(Point3::new(0.52, 0.7, 0.45 + 0.02 * k as f64));
        }
        let m = HeightMap::from_cloud(&PointCloud::new(back), &HeightMapConfig::default());
        let top = m.get(
            to_isize((0.52 - m.x0) / m.cell),
            to_isize((0.7 - m.y0) / m.cell),
        );
        assert!((top.unwrap() - 1.03).abs() < 1e-9, "{top:?}");
        // A cell where only a roof was seen (the floor under it hidden) is invalid.
        let roof = square(0.0, 0.0, 0.5, 0.02, 1.2);
        let m = HeightMap::from_cloud(&PointCloud::new(roof), &HeightMapConfig::default());
        assert!(m.heights.iter().all(|h| h.is_none()));
    }

    /// Issue 11: a reconstruction read as mesh vertices samples a seat every ~4-8 cm, so
    /// many 5 cm cells are empty and the discontinuity of the seat looks like a hole's.
    #[test]
    fn sampling_gaps_close_and_real_holes_stay() {
        // A 1 m seat sampled on a 7 cm grid, with a 0.35 m hole in its middle.
        let pts: Vec<Point3<f64>> = square(0.0, 0.0, 1.05, 0.07, 0.45)
            .into_iter()
            .filter(|p| !((0.35..0.70).contains(&p.x) && (0.35..0.70).contains(&p.y)))
            .collect();
        let cfg = HeightMapConfig::default();
        let m = HeightMap::from_cloud(&PointCloud::new(pts.clone()), &cfg);
        let valid = |m: &HeightMap, x0: usize, x1: usize| {
            let mut n = 0;
            for iy in x0..x1 {
                for ix in x0..x1 {
                    n += usize::from(m.get(ix as isize, iy as isize).is_some());
                }
            }
            n
        };
        // The ring around the hole: every cell of the first 0.3 m (off the map's border)
        // is seen or closed.
        let ring = |m: &HeightMap| {
            let mut n = 0;
            for iy in 1..6 {
                for ix in 1..19 {
                    n += usize::from(m.get(ix, iy).is_some());
                }
            }
            n
        };
        let missing: Vec<(usize, usize)> = (1..6)
            .flat_map(|iy| (1..19).map(move |ix| (ix, iy)))
            .filter(|&(ix, iy)| m.get(ix as isize, iy as isize).is_none())
            .collect();
        assert_eq!(ring(&m), 90, "{missing:?} nx {}", m.nx);
        assert_eq!(valid(&m, 9, 12), 0, "the hole's middle stays a hole");
        // Without closing, the 7 cm samples leave cells of the ring empty.
        let none = HeightMapConfig {
            sample_reach: 0.0,
            ..cfg
        };
        let raw = HeightMap::from_cloud(&PointCloud::new(pts), &none);
        assert!(ring(&raw) < 80, "{}", ring(&raw));
    }

    /// A seat sampled every 7 cm above a floor sampled every 1 cm (a depth camera sees the
    /// near floor far more densely than furniture further away): the cloud's median
    /// spacing is the floor's, so the seat would fall apart into holes; its own tile's
    /// spacing closes them. Fails with one spacing for the whole cloud.
    #[test]
    fn a_sparse_seat_over_a_dense_floor_is_closed() {
        let mut pts = square(-0.5, -0.5, 2.0, 0.01, 0.0);
        pts.extend(square(0.0, 0.0, 1.05, 0.07, 0.45));
        let cloud = PointCloud::new(pts);
        let cfg = HeightMapConfig::default();
        let m = HeightMap::from_cloud(&cloud, &cfg);
        let seat: Vec<Option<f64>> = (12..28)
            .flat_map(|iy| (12..28).map(move |ix| (ix, iy)))
            .map(|(ix, iy)| m.get(ix, iy))
            .collect();
        let on_seat = seat.iter().filter(|h| h.is_some_and(|z| z > 0.4)).count();
        assert_eq!(on_seat, seat.len(), "{seat:?}");
        // With one spacing for the cloud (tiles as large as the cloud), the seat's cells
        // between its samples show the floor.
        let one = HeightMapConfig {
            spacing_tile: 100.0,
            ..cfg
        };
        let m = HeightMap::from_cloud(&cloud, &one);
        let on_seat = (12..28)
            .flat_map(|iy| (12..28).map(move |ix| (ix, iy)))
            .filter(|&(ix, iy)| m.get(ix, iy).is_some_and(|z| z > 0.4))
            .count();
        assert!(on_seat < seat.len() / 2, "{on_seat}");
    }

    #[test]
    fn stack_tops() {
        let c = HeightMapConfig::default();
        assert_eq!(stack_top(&[], &c), None);
        // A leg stretcher under a seat.
        assert_eq!(stack_top(&[0.0, 0.2, 0.45], &c), Some(0.45));
        // A back rising from a seat in steps under a thigh's thickness; a gap of 0.15 m
        // over the seat ends the stack.
        assert_eq!(
            stack_top(&[0.0, 0.45, 0.55, 0.65, 0.75, 0.85, 0.95], &c),
            Some(0.95)
        );
        assert_eq!(stack_top(&[0.0, 0.45, 0.62, 0.75], &c), Some(0.45));
        // A table top 0.25 m over a seat; a shelf 0.75 m over the floor.
        assert_eq!(stack_top(&[0.0, 0.45, 0.7, 0.72], &c), Some(0.45));
        assert_eq!(stack_top(&[0.0, 0.75], &c), Some(0.75));
        assert_eq!(stack_top(&[0.0, 0.45, 1.3, 2.5], &c), Some(0.45));
        assert_eq!(stack_top(&[0.9, 1.0], &c), None);
        assert_eq!(stack_top(&[0.75], &c), Some(0.75));
        assert_eq!(stack_top(&[-0.01, 0.9], &c), Some(-0.01));
    }

    #[test]
    fn empty_cloud_gives_empty_map() {
        let m = HeightMap::from_cloud(&PointCloud::default(), &HeightMapConfig::default());
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
