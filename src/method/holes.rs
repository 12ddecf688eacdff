//! Holes in the scan: surfaces the camera did not see because something nearer hid them,
//! filled at the level of what surrounds them before the grids are built.
//!
//! A single view leaves a shadow behind every edge: the seat of a sofa behind its own arm,
//! the cushion behind a pillow, the desk top behind a monitor. The height map (section
//! 4.1) has no valid cell there, so no hypothesis, and the voxel scene has nothing for the
//! pelvis to rest on, so no fit: the place next to an armrest, where the body would use
//! it, is exactly the one an arm hides from a camera on its side. A hole is filled when
//! the scan closes round it at one level: a component of invalid height-map cells that
//! does not reach the map's border, at most `max_area`, whose rim (the valid cells
//! beside it) lies at two heights: its lowest part at one level, continued by the hidden
//! surface, and the rest well above it, the edges that hid it. Such a hole is a surface seen
//! through an occluder, not a gap between objects: between objects the floor shows, or
//! the hole opens onto the map's border. A shadow that opens onto space behind the
//! furniture (the seat of a chair seen from behind) is not filled, nor one whose rim is
//! the floor.
//!
//! The fill ([`fill`], [`fill_points`]) sets the hole's cells in the height map to the
//! middle of the rim cells at the level, and adds points on the scene's voxel grid over
//! them at that height to the cloud the scene is built from (not to the segmented points).
//! This is not in the paper.

use std::collections::HashMap;

use nalgebra::Point3;

use crate::method::heightmap::HeightMap;
use crate::num::to_usize;

/// When a hole is filled.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoleConfig {
    /// Largest hole filled, square metres (the whole height-map cells within it).
    pub max_area: f64,
    /// Smallest hole filled, square metres (rounded to whole cells): smaller ones are gaps in the sampling, which
    /// the height map's reach and the hypotheses' tolerance of invalid cells deal with.
    pub min_area: f64,
    /// The rim's level is this quantile of its cells' heights (0 the lowest).
    pub rim_quantile: f64,
    /// Rim cells within this many metres of the level are at it.
    pub rim_tolerance: f64,
    /// The share of the rim's cells at its level, at least, for the hole to be filled.
    pub rim_share: f64,
    /// What hides a surface rises at least this many metres above it (an arm, a back):
    /// rim cells above the level by more than `rim_tolerance` but at most this are the
    /// surface sloping or stepping into the hole, whose hidden part's shape is unknown.
    pub occluder_rise: f64,
    /// The share of the rim's cells, at most, in that band for the hole to be filled.
    pub slope_share: f64,
    /// Holes whose level is below this, metres above the floor, are left empty.
    pub min_level: f64,
}

impl Default for HoleConfig {
    fn default() -> Self {
        HoleConfig {
            // 0.6 m²: a sofa seat hidden behind its arm (0.6 x 0.7 m at most); larger
            // enclosed holes are floors behind furniture, not seats.
            max_area: 0.6,
            // 0.01 m² (four 5 cm cells): an arm 0.15 m above a seat seen from 30 degrees
            // above hides a band 0.25 m wide; sparse sampling leaves single cells.
            min_area: 0.01,
            // The lowest tenth of the rim may be noise or a peek at the floor through a
            // gap; above it, the lowest surface round the hole is the one it continues.
            rim_quantile: 0.1,
            // 0.05 m: cushions and seat edges vary 1-3 cm, a duvet's folds up to 5.
            rim_tolerance: 0.05,
            // 0.15: a hole behind an arm is closed by the seat on one or two sides and by
            // the arm and the back, higher, on the others; a seat seen from behind, hidden
            // by its own back, shows only its front edge beyond the hole, a fifth of the
            // rim (0.19 on an armchair of the default-mix views), the arms and the back
            // closing the rest.
            rim_share: 0.15,
            // 0.10 m: arms rise 0.12-0.35 m over a seat (the armrest band), backs more;
            // a reclined back or a cushion's slope climbs through the band.
            occluder_rise: 0.10,
            // 0.1: a tenth of the rim may be a cushion's rounded edge or noise.
            slope_share: 0.1,
            // 0.15 m: below the lowest seat (0.14 H = 0.25 m at 1.75 m) and above the
            // floor's noise: a hole in the floor is no seat.
            min_level: 0.15,
        }
    }
}

/// An enclosed hole of a height map that [`holes`] fills.
#[derive(Debug, Clone, PartialEq)]
pub struct Hole {
    /// Its cells `(ix, iy)`, row by row.
    pub cells: Vec<(usize, usize)>,
    /// The height it is filled at, metres (world z): the median of the rim cells at the
    /// rim's level.
    pub height: f64,
}

/// The four cells beside a cell, in a fixed order.
const SIDES: [(isize, isize); 4] = [(1, 0), (-1, 0), (0, 1), (0, -1)];

/// The cell beside `(x, y)` one step `(dx, dy)` away, if it is inside `map`.
pub(super) fn beside(
    map: &HeightMap,
    (x, y): (usize, usize),
    (dx, dy): (isize, isize),
) -> Option<(usize, usize)> {
    let (x, y) = (x.checked_add_signed(dx)?, y.checked_add_signed(dy)?);
    (x < map.nx && y < map.ny).then_some((x, y))
}

/// One bit per cell of a height map.
pub(super) struct Bits {
    nx: usize,
    words: Vec<u64>,
}

impl Bits {
    pub(super) fn new(map: &HeightMap) -> Bits {
        Bits {
            nx: map.nx,
            words: vec![0; (map.nx * map.ny).div_ceil(64)],
        }
    }

    pub(super) fn get(&self, (x, y): (usize, usize)) -> bool {
        let i = y * self.nx + x;
        self.words[i / 64] >> (i % 64) & 1 == 1
    }

    pub(super) fn set(&mut self, (x, y): (usize, usize), on: bool) {
        let i = y * self.nx + x;
        if on {
            self.words[i / 64] |= 1 << (i % 64);
        } else {
            self.words[i / 64] &= !(1 << (i % 64));
        }
    }
}

/// The enclosed holes of `map` that `cfg` fills. Deterministic: holes are found from the
/// valid cells at least `cfg.min_level` high (every hole filled has such cells in its
/// rim), in the order of [`HeightMap::cells_at_least`] (which holes are found does not
/// depend on it). Each invalid cell is visited at most once: a search that
/// meets a cell an earlier one found open is open too. Memory: two bits per cell.
pub fn holes(map: &HeightMap, cfg: &HoleConfig) -> Vec<Hole> {
    // Areas in cells: at most the whole cells within `max_area`, at least `min_area`
    // rounded to whole cells.
    let cells = |area: f64| area / (map.cell * map.cell);
    let (min_cells, max_cells) = (
        to_usize(cells(cfg.min_area).round()),
        to_usize(cells(cfg.max_area).floor()),
    );
    let mut seen = Bits::new(map);
    let mut current = Bits::new(map);
    let mut out = Vec::new();
    for (ix, iy) in map.cells_at_least(cfg.min_level) {
        for side in SIDES {
            let Some(start) = beside(map, (ix, iy), side) else {
                continue;
            };
            if map.get(start.0 as isize, start.1 as isize).is_some() || seen.get(start) {
                continue;
            }
            let marks = (&mut seen, &mut current);
            if let Some(hole) = flood(map, start, (min_cells, max_cells), marks, cfg) {
                out.push(hole);
            }
        }
    }
    out
}

/// Grows the component of invalid cells from `start` (not yet `seen`), marks it `seen`,
/// and gives it with its level when it is enclosed, small enough and its rim level
/// enough. `current` is clear before and after.
fn flood(
    map: &HeightMap,
    start: (usize, usize),
    (min_cells, max_cells): (usize, usize),
    (seen, current): (&mut Bits, &mut Bits),
    cfg: &HoleConfig,
) -> Option<Hole> {
    let mut comp = vec![start];
    seen.set(start, true);
    current.set(start, true);
    // The valid cells beside the component, with their heights.
    let mut rim: HashMap<(usize, usize), f64> = HashMap::new();
    let mut open = false;
    let mut next = 0;
    'grow: while next < comp.len() {
        let (cx, cy) = comp[next];
        next += 1;
        for side in SIDES {
            let Some(c) = beside(map, (cx, cy), side) else {
                open = true;
                break 'grow;
            };
            if let Some(h) = map.get(c.0 as isize, c.1 as isize) {
                rim.insert(c, h);
            } else if current.get(c) {
                continue;
            } else if seen.get(c) {
                // Found by an earlier search, which gave it up: open.
                open = true;
                break 'grow;
            } else {
                seen.set(c, true);
                current.set(c, true);
                comp.push(c);
                if comp.len() > max_cells {
                    open = true;
                    break 'grow;
                }
            }
        }
    }
    for &c in &comp {
        current.set(c, false);
    }
    if open || rim.is_empty() || comp.len() < min_cells {
        return None;
    }
    let mut heights: Vec<f64> = rim.into_values().collect();
    heights.sort_by(f64::total_cmp);
    let q = to_usize((cfg.rim_quantile * (heights.len() - 1) as f64).round());
    let level = heights[q.min(heights.len() - 1)];
    let n = heights.len() as f64;
    let above = |h: f64| h - level;
    let at = heights
        .iter()
        .filter(|&&h| above(h).abs() <= cfg.rim_tolerance)
        .count();
    // Rim cells a little above the level: the surface climbs into the hole.
    let sloping = heights
        .iter()
        .filter(|&&h| above(h) > cfg.rim_tolerance && above(h) <= cfg.occluder_rise)
        .count();
    if level < cfg.min_level
        || (at as f64) < cfg.rim_share * n
        || sloping as f64 > cfg.slope_share * n
    {
        return None;
    }
    // Filled at the middle of the rim cells at the level (sorted, so the middle one),
    // not at its lower edge: a fill below the surface round it would be a dip in it.
    let first = heights.partition_point(|&h| above(h) < -cfg.rim_tolerance);
    let middle = heights[first + at / 2];
    comp.sort_unstable_by_key(|&(x, y)| (y, x));
    Some(Hole {
        cells: comp,
        height: middle,
    })
}

/// Sets the cells of `holes` in `map` to their heights.
pub fn fill(map: &mut HeightMap, holes: &[Hole]) {
    for hole in holes {
        for &(ix, iy) in &hole.cells {
            map.set(ix, iy, hole.height);
        }
    }
}

/// Points filling `holes` of `map`: per hole cell, a square grid of points at most
/// `step` metres apart (the scene's voxel edge) at the hole's height, world frame.
pub fn fill_points(map: &HeightMap, holes: &[Hole], step: f64) -> Vec<Point3<f64>> {
    let n = to_usize((map.cell / step).ceil()).max(1);
    let d = map.cell / n as f64;
    let mut out = Vec::new();
    for hole in holes {
        for &(ix, iy) in &hole.cells {
            let (x0, y0) = (map.x0 + ix as f64 * map.cell, map.y0 + iy as f64 * map.cell);
            for j in 0..n {
                for i in 0..n {
                    let (x, y) = (x0 + (i as f64 + 0.5) * d, y0 + (j as f64 + 0.5) * d);
                    out.push(Point3::new(x, y, hole.height));
                }
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 12 x 12 map of 0.05 m cells: a seat at 0.45 m with a 3 x 3 hole in it.
    fn seat_with_hole(rim: f64) -> Vec<Option<f64>> {
        let mut h = vec![Some(0.0); 144];
        for y in 2..10 {
            for x in 2..10 {
                h[y * 12 + x] = Some(rim);
            }
        }
        for y in 5..8 {
            for x in 5..8 {
                h[y * 12 + x] = None;
            }
        }
        h
    }

    #[test]
    fn a_hole_inside_a_seat_is_filled_at_its_level() {
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &seat_with_hole(0.45));
        let found = holes(&map, &HoleConfig::default());
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].cells.len(), 9);
        assert_eq!(found[0].height, 0.45);
        let pts = fill_points(&map, &found, 0.02);
        // 3 x 3 points per 0.05 m cell at a 0.02 m step.
        assert_eq!(pts.len(), 81);
        assert!(pts.iter().all(|p| p.z == 0.45 && p.x > 0.25 && p.x < 0.40));
        let mut filled = map.clone();
        fill(&mut filled, &found);
        assert_eq!(filled.get(6, 6), Some(0.45));
        assert_eq!(filled.get(0, 0), Some(0.0));
        assert!(holes(&filled, &HoleConfig::default()).is_empty());
    }

    #[test]
    fn holes_in_the_floor_open_ones_and_large_ones_stay_empty() {
        // At floor level.
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &seat_with_hole(0.05));
        assert!(holes(&map, &HoleConfig::default()).is_empty());
        // Open onto the map's border: the hole's row runs out of the map.
        let mut h = seat_with_hole(0.45);
        for x in 0..12 {
            h[6 * 12 + x] = None;
        }
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &h);
        assert!(holes(&map, &HoleConfig::default()).is_empty());
        // Larger than allowed.
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &seat_with_hole(0.45));
        let small = HoleConfig {
            max_area: 8.0 * 0.0025,
            ..HoleConfig::default()
        };
        assert!(holes(&map, &small).is_empty());
    }

    #[test]
    fn a_rim_of_mixed_heights_is_not_level() {
        // The hole's rim: the seat at 0.45 on one side, a back at 0.9 round the rest: a
        // quarter of the rim at the level, a seat seen from behind past its back. Filled
        // at 0.45; with a share of 0.3 asked (before 2026-11-26, night) it was not.
        let mut h = seat_with_hole(0.9);
        for x in 4..9 {
            h[4 * 12 + x] = Some(0.45);
        }
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &h);
        let found = holes(&map, &HoleConfig::default());
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].height, 0.45);
        let strict = HoleConfig {
            rim_share: 0.3,
            ..HoleConfig::default()
        };
        assert!(holes(&map, &strict).is_empty());
        // With the seat on two sides it is a seat behind an arm and a back: filled at 0.45.
        for y in 4..9 {
            h[y * 12 + 8] = Some(0.45);
        }
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &h);
        let found = holes(&map, &HoleConfig::default());
        assert_eq!(found.len(), 1);
        assert_eq!(found[0].height, 0.45);
        // A third side 7 cm above the seat: the surface climbs into the hole (a reclined
        // back), whose hidden shape is unknown: not filled.
        for x in 5..8 {
            h[8 * 12 + x] = Some(0.52);
        }
        let map = HeightMap::from_dense(0.0, 0.0, 0.05, 12, 12, &h);
        assert!(holes(&map, &HoleConfig::default()).is_empty());
    }
}
