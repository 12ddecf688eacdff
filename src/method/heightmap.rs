//! The height map of section 4.1: the scene seen from above in square cells. The paper
//! keeps the highest point of each cell; here a cell keeps the top of the lowest stack of
//! points standing on the floor, so that ceilings, table tops, shelves and upper bunks
//! (anything with a tall free gap beneath it) do not hide the seats and beds under them,
//! and each point counts in the cells within a point spacing of it, so that surfaces
//! sampled more sparsely than the cells (reconstructions read as vertices, subsampled
//! clouds) have no empty cells. Cells where nothing is
//! seen stay invalid.

use std::sync::atomic::{AtomicBool, Ordering};

use crate::cloud::{point_spacing, PointCloud, TileSpacing};
use crate::num::{index32, to_f32, to_isize, to_usize};
use nalgebra::Point3;
use rayon::prelude::*;

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

/// Side of the square tiles the height map stores, in cells: only tiles that some point
/// reaches are kept, so memory follows the points, not their bounding box (a 200 m floor
/// sampled every metre keeps a fifth of its tiles). 8 x 8 cells (0.4 m at 5 cm) are 1 KiB
/// of heights, and the index over all tiles is a 64th of the cells.
const TILE: usize = 8;
/// A tile that no point reaches: every cell of it is invalid and it is not stored.
const NO_TILE: usize = usize::MAX;
/// Points per piece of the map's per-point passes (reaches, tiles, cells), which run in
/// parallel pieces merged in the points' order: a piece is tens of microseconds of work,
/// well above a task's overhead on rayon's pool. The map does not depend on it.
const PIECE: usize = 8 * 1024;

/// The cloud's point spacing ([`point_spacing`]) for building a height map: measured by
/// the build, or given by a caller that measured it already (of the points the cloud was
/// cut from); `Given(None)` is a cloud too small to have one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Spacing {
    /// Measured by the build, beside the tiles' own spacings.
    Measure,
    /// Given.
    Given(Option<f64>),
}

/// A height map over the x-y plane (metres, z up): `nx` x `ny` square cells from the corner
/// `(x0, y0)`, stored in tiles of [`TILE`] x [`TILE`] cells of which only those holding a
/// point are kept.
#[derive(Debug, Clone)]
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
    /// Per tile (`ty * tiles_x + tx`, tile `(tx, ty)` holding cells `tx * TILE ..` along x
    /// and `ty * TILE ..` along y), its index among the stored tiles, or [`NO_TILE`].
    tiles: Vec<usize>,
    /// Tiles along x: `nx` over [`TILE`], rounded up.
    tiles_x: usize,
    /// Surface height per cell of the stored tiles, `TILE * TILE` per tile, row-major
    /// within a tile; `None` where the cell is invalid.
    heights: Vec<Option<f64>>,
    /// Per cell of the stored tiles (as `heights`), how far its stack reaches below its
    /// top, metres: the side face of a seat seen under its edge, or the floor under an
    /// open one; 0 where the cell is invalid or was filled without points.
    depths: Vec<f32>,
}

/// Read access to the cells of a height map: the map itself, or a copy of some of its
/// rows that answers as the map does for the rows it holds.
pub trait Cells {
    /// Height of cell `(ix, iy)`; `None` if invalid or outside the map.
    fn height(&self, ix: isize, iy: isize) -> Option<f64>;
    /// Cell edge length, metres.
    fn cell_size(&self) -> f64;
}

impl Cells for HeightMap {
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        self.get(ix, iy)
    }

    fn cell_size(&self) -> f64 {
        self.cell
    }
}

impl PartialEq for HeightMap {
    /// Same grid and the same height in every cell, however the tiles are stored.
    fn eq(&self, other: &Self) -> bool {
        (self.x0, self.y0, self.cell, self.nx, self.ny)
            == (other.x0, other.y0, other.cell, other.nx, other.ny)
            && (0..self.ny).all(|iy| {
                (0..self.nx).all(|ix| {
                    let (x, y) = (ix as isize, iy as isize);
                    self.get(x, y) == other.get(x, y)
                })
            })
    }
}

/// Index of the cell `(ix, iy)` within its tile.
fn in_tile(ix: usize, iy: usize) -> usize {
    (iy % TILE) * TILE + ix % TILE
}

impl HeightMap {
    /// A map of `nx` x `ny` cells of `cell` metres from `(x0, y0)` with the heights given
    /// row-major (`iy * nx + ix`; cells past the end of `heights` are invalid).
    pub fn from_dense(
        x0: f64,
        y0: f64,
        cell: f64,
        nx: usize,
        ny: usize,
        heights: &[Option<f64>],
    ) -> HeightMap {
        let mut map = HeightMap::empty(x0, y0, cell, nx, ny);
        map.tiles.fill(0);
        map.number_tiles();
        for iy in 0..ny {
            for ix in 0..nx {
                let i = map.index(ix, iy);
                map.heights[i] = heights.get(iy * nx + ix).copied().flatten();
            }
        }
        map
    }

    /// A map with no tile stored yet (every cell invalid).
    fn empty(x0: f64, y0: f64, cell: f64, nx: usize, ny: usize) -> HeightMap {
        let tiles_x = nx.div_ceil(TILE);
        HeightMap {
            x0,
            y0,
            cell,
            nx,
            ny,
            tiles: vec![NO_TILE; tiles_x * ny.div_ceil(TILE)],
            tiles_x,
            heights: Vec::new(),
            depths: Vec::new(),
        }
    }

    /// Gives the tiles marked (any value but [`NO_TILE`]) their indices in tile order and
    /// room for their cells, all invalid.
    fn number_tiles(&mut self) {
        let mut n = 0;
        for s in &mut self.tiles {
            if *s != NO_TILE {
                *s = n;
                n += 1;
            }
        }
        self.heights = vec![None; n * TILE * TILE];
        self.depths = vec![0.0; n * TILE * TILE];
    }

    /// The tile of cell `(ix, iy)` (inside the map).
    fn tile_of(&self, ix: usize, iy: usize) -> usize {
        (iy / TILE) * self.tiles_x + ix / TILE
    }

    /// Index into `heights` of cell `(ix, iy)`, whose tile is stored.
    fn index(&self, ix: usize, iy: usize) -> usize {
        self.tiles[self.tile_of(ix, iy)] * TILE * TILE + in_tile(ix, iy)
    }

    /// Builds the height map of `cloud` (world frame, metres, floor at z = 0) with cells
    /// of `cfg.cell` metres: per cell, the top of the lowest stack of points, a stack
    /// ending under a gap of at least `cfg.overhang_gap`; a cell whose lowest point floats
    /// that far above the floor sees only a roof and is invalid. Each point counts in every
    /// cell whose centre is within `cfg.sample_reach` point spacings of it. An empty cloud gives an empty map.
    pub fn from_cloud(cloud: &PointCloud, cfg: &HeightMapConfig) -> HeightMap {
        HeightMap::build(cloud, cfg, true, PIECE, Spacing::Measure)
    }

    /// [`HeightMap::from_cloud`] with the cloud's point spacing given rather than measured:
    /// the same map when `spacing` is [`point_spacing`] of `cloud`; the detector passes the
    /// spacing of the points `cloud` was cut from (less its specks, the same but for the
    /// few queries that moved).
    pub fn from_cloud_spaced(
        cloud: &PointCloud,
        cfg: &HeightMapConfig,
        spacing: Option<f64>,
    ) -> HeightMap {
        HeightMap::build(cloud, cfg, true, PIECE, Spacing::Given(spacing))
    }

    /// [`HeightMap::from_cloud`]; with `skip_dense` the tiles whose spacing gives a reach
    /// under half a cell are not measured exactly (the same map, bit for bit: see below).
    /// The per-point passes run in parallel pieces of `piece` points (at least 1), merged
    /// in the points' order: the same map whatever `piece` and the thread count. The
    /// cloud's spacing is `spacing` ([`Spacing`]).
    fn build(
        cloud: &PointCloud,
        cfg: &HeightMapConfig,
        skip_dense: bool,
        piece: usize,
        spacing: Spacing,
    ) -> HeightMap {
        let piece = piece.max(1);
        let cell = cfg.cell;
        let Some((lo, hi)) = cloud.bounds() else {
            return HeightMap::empty(0.0, 0.0, cell, 0, 0);
        };
        let nx = to_usize(((hi.x - lo.x) / cell).floor()) + 1;
        let ny = to_usize(((hi.y - lo.y) / cell).floor()) + 1;
        let reaches = reaches(cloud, lo, cfg, skip_dense, piece, spacing);
        // Every other cell's centre is at least half a cell from the point along x or y:
        // `jx + 0.5 - fx` is at least 0.5 in size (`ix <= fx < ix + 1`, or `fx` beyond the
        // last column, which has no right neighbour) and rounding keeps it so, so a
        // point whose squared reach is below this reaches its own cell only (the same
        // cells as testing each).
        let half2 = (0.5 * cell) * (0.5 * cell);
        let widest = reaches.iter().copied().fold(0.0, f64::max);
        // Cell offsets a point may reach beyond its own cell (none for dense clouds).
        let r = to_isize((widest / cell).ceil());
        // The cell holding a point (the last column or row for points on the far edge).
        let own = |p: &Point3<f64>| {
            let (fx, fy) = ((p.x - lo.x) / cell, (p.y - lo.y) / cell);
            (fx, fy, to_usize(fx).min(nx - 1), to_usize(fy).min(ny - 1))
        };
        let cells_of = |p: &Point3<f64>, reach: f64, out: &mut Vec<(usize, usize)>| {
            out.clear();
            let (fx, fy, ix, iy) = own(p);
            out.push((ix, iy));
            if reach * reach < half2 {
                return;
            }
            let (ix, iy) = (ix as isize, iy as isize);
            // A cell centre within `reach` is at most `reach / cell + 0.5` cells from the
            // point's cell, so cells beyond `ceil(reach / cell)` need no test.
            let rp = to_isize((reach / cell).ceil()).min(r);
            let reach2 = reach * reach;
            for dy in -rp..=rp {
                let jy = iy + dy;
                if jy < 0 || jy >= ny as isize {
                    continue;
                }
                let cy = (jy as f64 + 0.5 - fy) * cell;
                let cy2 = cy * cy;
                // No cell of a row whose centre line is out of reach is within it: the
                // rounded sum `cx * cx + cy2` is at least `cy2`, so the test below fails
                // for every column (the same cells as testing each).
                if cy2 > reach2 {
                    continue;
                }
                for dx in -rp..=rp {
                    let jx = ix + dx;
                    if (dx, dy) == (0, 0) || jx < 0 || jx >= nx as isize {
                        continue;
                    }
                    let cx = (jx as f64 + 0.5 - fx) * cell;
                    if cx * cx + cy2 <= reach2 {
                        out.push((jx as usize, jy as usize));
                    }
                }
            }
        };
        // The pieces of the cloud, each with its points' reaches.
        let pieces = || {
            cloud
                .points
                .par_chunks(piece)
                .zip(reaches.par_chunks(piece))
        };
        // The tiles that some point may reach are stored, numbered in tile order: those
        // of the cells within `ceil(reach / cell)` columns and rows of its own, the square
        // `cells_of` looks in. Marked by the pieces side by side (a tile is marked or not,
        // whichever piece marks it); a run of points marking one span of tiles (as a
        // depth image's rows give) marks it once.
        let mut map = HeightMap::empty(lo.x, lo.y, cell, nx, ny);
        let marked: Vec<AtomicBool> = map.tiles.iter().map(|_| AtomicBool::new(false)).collect();
        let tiles_x = map.tiles_x;
        pieces().for_each(|(points, reaches)| {
            let mut last = None;
            for (p, &reach) in points.iter().zip(reaches) {
                let (_, _, ix, iy) = own(p);
                let rp = to_usize((reach / cell).ceil()).min(r.unsigned_abs());
                let span = (
                    iy.saturating_sub(rp) / TILE,
                    (iy + rp).min(ny - 1) / TILE,
                    ix.saturating_sub(rp) / TILE,
                    (ix + rp).min(nx - 1) / TILE,
                );
                if last == Some(span) {
                    continue;
                }
                last = Some(span);
                for ty in span.0..=span.1 {
                    for tx in span.2..=span.3 {
                        marked[ty * tiles_x + tx].store(true, Ordering::Relaxed);
                    }
                }
            }
        });
        for (t, m) in map.tiles.iter_mut().zip(marked) {
            if m.into_inner() {
                *t = 0;
            }
        }
        map.number_tiles();
        // Each point's cells as (stored cell, point) pairs, found by the pieces side by
        // side and kept in the points' order. Both are `u32`: a cloud of 2^32 points
        // would take 96 GiB of coordinates, a map of 2^32 stored cells 64 GiB of heights.
        let stored = map.heights.len();
        let entries: Vec<Vec<(u32, u32)>> = pieces()
            .enumerate()
            .map_init(Vec::new, |cells, (n, (points, reaches))| {
                let mut out = Vec::with_capacity(points.len());
                for (k, (p, &reach)) in points.iter().zip(reaches).enumerate() {
                    cells_of(p, reach, cells);
                    let i = index32(n * piece + k);
                    out.extend(
                        cells
                            .iter()
                            .map(|&(jx, jy)| (index32(map.index(jx, jy)), i)),
                    );
                }
                out
            })
            .collect();
        // The points' heights grouped by stored cell (counting sort, in the points'
        // order), then sorted within a cell.
        let mut start = vec![0usize; stored + 1];
        for &(c, _) in entries.iter().flatten() {
            start[c as usize + 1] += 1;
        }
        for i in 0..stored {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut zs = vec![0.0f64; start[stored]];
        for &(c, i) in entries.iter().flatten() {
            let c = c as usize;
            zs[fill[c]] = cloud.points[i as usize].z;
            fill[c] += 1;
        }
        drop(entries);
        drop(fill);
        // Each cell's top from its own column: tile by tile in parallel (a tile's cells
        // and their columns are contiguous), the same values as cell by cell.
        let cells_per_tile = TILE * TILE;
        let mut jobs = Vec::with_capacity(map.heights.len() / cells_per_tile);
        let mut rest: &mut [f64] = &mut zs;
        for (t, (hs, ds)) in map
            .heights
            .chunks_mut(cells_per_tile)
            .zip(map.depths.chunks_mut(cells_per_tile))
            .enumerate()
        {
            let (from, to) = (
                start[t * cells_per_tile],
                start[t * cells_per_tile + hs.len()],
            );
            let (mine, after) = std::mem::take(&mut rest).split_at_mut(to - from);
            rest = after;
            jobs.push((t * cells_per_tile, hs, ds, mine));
        }
        jobs.into_par_iter().for_each(|(c0, hs, ds, column_zs)| {
            let base = start[c0];
            for (k, (h, d)) in hs.iter_mut().zip(ds.iter_mut()).enumerate() {
                let c = c0 + k;
                let column = &mut column_zs[start[c] - base..start[c + 1] - base];
                if let Some((top, bottom)) = column_top(column, cfg) {
                    *h = Some(top);
                    *d = to_f32(top - bottom);
                }
            }
        });
        map
    }

    /// Whether any cell of the tile holding cell `(ix, iy)` (inside the map) may be
    /// valid; `false` means every cell of it is invalid.
    pub fn tile_stored(&self, ix: usize, iy: usize) -> bool {
        ix < self.nx && iy < self.ny && self.tiles[self.tile_of(ix, iy)] != NO_TILE
    }

    /// The first column at or after `ix` in row `iy` whose tile is stored (`nx` if none):
    /// columns before it hold only invalid cells.
    pub fn next_stored(&self, ix: usize, iy: usize) -> usize {
        let mut x = ix;
        while x < self.nx && !self.tile_stored(x, iy) {
            x = (x / TILE + 1) * TILE;
        }
        x.min(self.nx)
    }

    /// The columns `0, step, 2 step, ..` of row `iy` whose tiles are stored, in order:
    /// the others hold only invalid cells. A `step` of 0 counts as 1.
    pub fn stored_columns(&self, iy: usize, step: usize) -> impl Iterator<Item = usize> + '_ {
        let step = step.max(1);
        let mut ix = 0;
        std::iter::from_fn(move || loop {
            if iy >= self.ny || ix >= self.nx {
                return None;
            }
            if self.tile_stored(ix, iy) {
                ix += step;
                return Some(ix - step);
            }
            ix = self.next_stored(ix, iy).div_ceil(step) * step;
        })
    }

    /// Row `iy` of the map into `out[..nx]` (the cells of tiles not stored as invalid);
    /// nothing is written for a row outside the map.
    pub fn copy_row(&self, iy: usize, out: &mut [Option<f64>]) {
        if iy >= self.ny {
            return;
        }
        let base = (iy / TILE) * self.tiles_x;
        for (tx, &slot) in self.tiles[base..base + self.tiles_x].iter().enumerate() {
            let x0 = tx * TILE;
            let x1 = (x0 + TILE).min(self.nx).min(out.len());
            if x0 >= x1 {
                break;
            }
            if slot == NO_TILE {
                out[x0..x1].fill(None);
            } else {
                let from = slot * TILE * TILE + (iy % TILE) * TILE;
                out[x0..x1].copy_from_slice(&self.heights[from..from + (x1 - x0)]);
            }
        }
    }

    /// Sets cell `(ix, iy)` (inside the map) to `height`, storing its tile if no point
    /// reached it (the new tile's other cells invalid).
    pub fn set(&mut self, ix: usize, iy: usize, height: f64) {
        let t = self.tile_of(ix, iy);
        if self.tiles[t] == NO_TILE {
            self.tiles[t] = self.heights.len() / (TILE * TILE);
            self.heights.resize(self.heights.len() + TILE * TILE, None);
            self.depths.resize(self.heights.len(), 0.0);
        }
        let i = self.index(ix, iy);
        self.heights[i] = Some(height);
        self.depths[i] = 0.0;
    }

    /// The cells `(ix, iy)` whose height is at least `min` metres, tile by tile (tiles in
    /// row-major order, cells row-major within a tile): one pass over the stored cells.
    pub fn cells_at_least(&self, min: f64) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for (t, &slot) in self.tiles.iter().enumerate() {
            if slot == NO_TILE {
                continue;
            }
            let (x0, y0) = ((t % self.tiles_x) * TILE, (t / self.tiles_x) * TILE);
            let cells = &self.heights[slot * TILE * TILE..(slot + 1) * TILE * TILE];
            for (i, h) in cells.iter().enumerate() {
                let (ix, iy) = (x0 + i % TILE, y0 + i / TILE);
                if h.is_some_and(|h| h >= min) && ix < self.nx && iy < self.ny {
                    out.push((ix, iy));
                }
            }
        }
        out
    }

    /// The heights of the valid cells, in no particular order.
    pub fn valid_heights(&self) -> impl Iterator<Item = f64> + '_ {
        self.heights.iter().flatten().copied()
    }

    /// Whether cell `(ix, iy)` lies within the map's `nx` x `ny` cells (valid or not).
    pub fn contains(&self, ix: isize, iy: isize) -> bool {
        ix >= 0 && iy >= 0 && (ix as usize) < self.nx && (iy as usize) < self.ny
    }

    /// Height of cell `(ix, iy)`; `None` if invalid or outside the map.
    pub fn get(&self, ix: isize, iy: isize) -> Option<f64> {
        if !self.contains(ix, iy) {
            return None;
        }
        let (ix, iy) = (ix as usize, iy as usize);
        let slot = self.tiles[self.tile_of(ix, iy)];
        if slot == NO_TILE {
            return None;
        }
        self.heights[slot * TILE * TILE + in_tile(ix, iy)]
    }

    /// How far the stack of cell `(ix, iy)` reaches below its top, metres: from its top
    /// to the lowest point seen in its column (a seat's side face seen under its edge, or
    /// the floor seen under an open seat; a mattress cut by the image edge shows nothing
    /// below its top at the cut). `None` if the cell is invalid or outside the map, 0 for
    /// a cell filled without points of its own.
    pub fn depth(&self, ix: isize, iy: isize) -> Option<f64> {
        self.get(ix, iy)?;
        let (ix, iy) = (ix as usize, iy as usize);
        Some(f64::from(self.depths[self.index(ix, iy)]))
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

/// How far each point of `cloud` reaches (metres, the [`HeightMap::from_cloud`] rule:
/// `cfg.sample_reach` times its tile's spacing, at least the cloud's, at most
/// `cfg.max_reach`; 0 without a spacing), tiles from the corner `lo`; with `skip_dense`
/// the tiles whose spacing gives a reach under half a cell are not measured exactly and
/// their points get the reach of the cloud's spacing, which reaches the same cells and
/// marks the same tiles (see below). The cloud's spacing is `spacing` when given, else
/// measured ([`point_spacing`]).
fn reaches(
    cloud: &PointCloud,
    lo: Point3<f64>,
    cfg: &HeightMapConfig,
    skip_dense: bool,
    piece: usize,
    spacing: Spacing,
) -> Vec<f64> {
    let cell = cfg.cell;
    // Every other cell's centre is at least half a cell from the point along x or y:
    // `jx + 0.5 - fx` is at least 0.5 in size (`ix <= fx < ix + 1`, or `fx` beyond the
    // last column, which has no right neighbour) and rounding keeps it so, so a
    // point whose squared reach is below this reaches its own cell only (the same
    // cells as testing each).
    let half2 = (0.5 * cell) * (0.5 * cell);
    // The reach a spacing `s` gives (before the cloud's spacing is taken as its
    // least), and whether it stays in the point's own cell.
    let reach_of = |s: f64| (cfg.sample_reach * s).min(cfg.max_reach);
    let dense = |s: f64| {
        let r = reach_of(s);
        r * r < half2
    };
    // The reach is monotonic in the spacing (`min` of a multiple), so `dense` holds on
    // a down-set of spacings (those up to some length): a point whose tile's spacing
    // is dense reaches its own cell only, as the cloud's spacing does when that is
    // dense too, and marks the tiles one cell round its own (`ceil(reach / cell)`
    // is 1) when the cloud's spacing gives a positive reach; when the cloud's
    // spacing is not dense, it is longer than a dense tile's and is the point's
    // spacing. So the dense tiles are left out of `tiles` (looked up, they give the
    // cloud's spacing) and every point reaches the same cells and marks the same
    // tiles, unless the cloud's spacing is dense without a positive reach (every
    // point doubled): then the tiles are measured again, exactly.
    let measure = |skip: bool| {
        if skip {
            TileSpacing::above(cloud, lo, cfg.spacing_tile, cfg.spacing_queries, &dense)
        } else {
            TileSpacing::new(cloud, lo, cfg.spacing_tile, cfg.spacing_queries)
        }
    };
    // Independent measures of the same points, side by side.
    let (global, tiles) = match spacing {
        Spacing::Given(global) => (global, measure(skip_dense)),
        Spacing::Measure => rayon::join(|| point_spacing(cloud), || measure(skip_dense)),
    };
    let no_reach = |g: f64| dense(g) && to_isize((reach_of(g) / cell).ceil()) != 1;
    let tiles = if skip_dense && global.is_some_and(no_reach) {
        measure(false)
    } else {
        tiles
    };
    // Looked up once per point, for the passes of the map, in parallel pieces written
    // in place.
    let mut out = vec![0.0; cloud.len()];
    out.par_chunks_mut(piece)
        .zip(cloud.points.par_chunks(piece))
        .for_each(|(out, points)| {
            for (r, t) in out.iter_mut().zip(tiles.at_each(points)) {
                *r = global.map_or(0.0, |g| {
                    let s = t.map_or(g, |t| t.max(g));
                    (cfg.sample_reach * s).min(cfg.max_reach)
                });
            }
        });
    out
}

/// [`stack_top`] of the heights `column` in any order, with the lowest height (the
/// stack's bottom): `(top, bottom)`. A column whose heights span less than both gaps
/// (every seat-only or floor-only column) has no gap between sorted
/// neighbours that reaches either (each is at most the span, and the rounded difference
/// of two heights is monotone in them), so its stack is the whole column: its top is the
/// highest height (by `total_cmp`, the last one sorting gives) without sorting. Other
/// columns are sorted (`total_cmp`) and walked.
fn column_top(column: &mut [f64], cfg: &HeightMapConfig) -> Option<(f64, f64)> {
    let (&first, rest) = column.split_first()?;
    let (mut lo, mut hi) = (first, first);
    for &z in rest {
        if z.total_cmp(&lo).is_lt() {
            lo = z;
        }
        if z.total_cmp(&hi).is_gt() {
            hi = z;
        }
    }
    let span = hi - lo;
    if span < cfg.overhang_gap && span < cfg.thigh_gap {
        // `stack_top`'s test of the lowest height (the gaps are not NaN here).
        return (lo < cfg.overhang_gap).then_some((hi, lo));
    }
    column.sort_unstable_by(f64::total_cmp);
    stack_top(column, cfg).map(|top| (top, column[0]))
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
        assert_eq!(m.valid_heights().count(), 0);
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
        assert_eq!((m.nx, m.ny, m.valid_heights().count()), (0, 0, 0));
        assert_eq!(m.get(0, 0), None);
    }

    #[test]
    fn disc_counts_cells_within_radius() {
        let m = HeightMap::from_dense(0.0, 0.0, 0.05, 0, 0, &[]);
        assert_eq!(m.disc(0.0).len(), 1);
        assert_eq!(m.disc(0.05).len(), 5);
        assert_eq!(m.disc(0.075).len(), 9);
    }

    /// The map as the dense grid it replaced built it: every cell of the box over x-y,
    /// each point's z put in its own cell and the cells within its reach, then
    /// [`stack_top`] per cell (row-major heights).
    fn dense_reference(cloud: &PointCloud, cfg: &HeightMapConfig) -> Vec<Option<f64>> {
        let Some((lo, hi)) = cloud.bounds() else {
            return Vec::new();
        };
        let cell = cfg.cell;
        let nx = to_usize(((hi.x - lo.x) / cell).floor()) + 1;
        let ny = to_usize(((hi.y - lo.y) / cell).floor()) + 1;
        // Independent measures of the same points, side by side.
        let (global, tiles) = rayon::join(
            || point_spacing(cloud),
            || TileSpacing::new(cloud, lo, cfg.spacing_tile, cfg.spacing_queries),
        );
        let mut columns: Vec<Vec<f64>> = vec![Vec::new(); nx * ny];
        for p in &cloud.points {
            let reach = global.map_or(0.0, |g| {
                let s = tiles.at(p).map_or(g, |t| t.max(g));
                (cfg.sample_reach * s).min(cfg.max_reach)
            });
            let (fx, fy) = ((p.x - lo.x) / cell, (p.y - lo.y) / cell);
            let (ix, iy) = (to_usize(fx).min(nx - 1), to_usize(fy).min(ny - 1));
            columns[iy * nx + ix].push(p.z);
            // Every cell within the largest reach and a cell of slack.
            let w = to_usize((cfg.max_reach / cell).ceil()) + 1;
            for jy in iy.saturating_sub(w)..(iy + w + 1).min(ny) {
                for jx in ix.saturating_sub(w)..(ix + w + 1).min(nx) {
                    let (cx, cy) = ((jx as f64 + 0.5 - fx) * cell, (jy as f64 + 0.5 - fy) * cell);
                    if (jx, jy) != (ix, iy) && cx * cx + cy * cy <= reach * reach {
                        columns[jy * nx + jx].push(p.z);
                    }
                }
            }
        }
        columns
            .iter_mut()
            .map(|c| {
                c.sort_unstable_by(f64::total_cmp);
                stack_top(c, cfg)
            })
            .collect()
    }

    /// `column_top` against sorting and `stack_top` (and the lowest height), bit for bit,
    /// on seeded columns: short and long, spans round both gaps, a seat over the floor,
    /// signed zeros, and gaps set so that a column's span equals one exactly.
    #[test]
    fn column_tops_without_sorting_are_the_sorted_ones() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let base = HeightMapConfig::default();
        let (mut quick, mut sorted) = (0, 0);
        for round in 0..4000 {
            let n = rng.random_range(1..60);
            let z0: f64 = [0.0, -0.0, 0.02, 0.4, 0.9][rng.random_range(0..5)];
            let spread: f64 = [0.0, 0.01, 0.1, 0.149, 0.15, 0.3, 1.0][rng.random_range(0..7)];
            let mut column: Vec<f64> = (0..n)
                .map(|_| match rng.random_range(0..6) {
                    0 => z0,
                    1 => -z0,
                    _ => z0 + rng.random_range(0.0..=1.0) * spread,
                })
                .collect();
            let mut cfg = base;
            if round % 5 == 0 {
                // A gap exactly the column's span: sorted, as the span is not under it.
                let (lo, hi) = column
                    .iter()
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &z| {
                        (l.min(z), h.max(z))
                    });
                cfg.thigh_gap = hi - lo;
            }
            let mut reference = column.clone();
            reference.sort_unstable_by(f64::total_cmp);
            let want = stack_top(&reference, &cfg);
            let got = column_top(&mut column, &cfg);
            // The bottom is the lowest height, as sorting puts it first.
            assert_eq!(
                got.map(|(top, bottom)| (top.to_bits(), bottom.to_bits())),
                want.map(|top| (top.to_bits(), reference[0].to_bits())),
                "{reference:?}"
            );
            let span = reference[n - 1] - reference[0];
            if span < cfg.thigh_gap && span < cfg.overhang_gap {
                quick += 1;
            } else {
                sorted += 1;
            }
        }
        assert!(
            quick > 1000 && sorted > 1000,
            "{quick} quick, {sorted} sorted"
        );
        assert_eq!(column_top(&mut [], &base), None);
    }

    /// The tiled map against [`dense_reference`], bit for bit in every cell, on seeded
    /// clouds: patches of different spacings (so points reach several cells), far apart so
    /// that most tiles hold no point, heights across the stack rules' thresholds.
    #[test]
    fn tiles_hold_the_dense_maps_heights() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
        let (mut seen, mut sparse) = (0, 0);
        for round in 0..12 {
            let mut pts = Vec::new();
            for _ in 0..rng.random_range(1..5) {
                let (x0, y0) = (rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
                let step = [0.01, 0.04, 0.07, 0.2][rng.random_range(0..4)];
                let z = [0.0, 0.45, 0.6, 0.9, 1.5][rng.random_range(0..5)];
                for p in square(x0, y0, rng.random_range(0.1..0.6), step, z) {
                    let jitter = rng.random_range(-0.004..0.004);
                    pts.push(Point3::new(p.x + jitter, p.y - jitter, p.z + jitter.abs()));
                }
            }
            let cloud = PointCloud::new(pts);
            let cfg = HeightMapConfig::default();
            let m = HeightMap::from_cloud(&cloud, &cfg);
            let want = dense_reference(&cloud, &cfg);
            assert_eq!(want.len(), m.nx * m.ny);
            let mut valid = 0;
            for iy in 0..m.ny {
                for ix in 0..m.nx {
                    let (got, want) = (m.get(ix as isize, iy as isize), want[iy * m.nx + ix]);
                    assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits), "{round}");
                    valid += usize::from(want.is_some());
                }
            }
            assert_eq!(m.valid_heights().count(), valid);
            seen += valid;
            sparse += usize::from(m.tiles.contains(&NO_TILE));
            // Skipping the tiles no point reaches skips only invalid cells.
            for step in [1, 2, 3, 9] {
                for iy in 0..m.ny {
                    let all: Vec<usize> = (0..m.nx)
                        .step_by(step)
                        .filter(|&ix| m.tile_stored(ix, iy))
                        .collect();
                    let got: Vec<usize> = m.stored_columns(iy, step).collect();
                    assert_eq!(got, all);
                    assert!((0..m.nx)
                        .filter(|&ix| !m.tile_stored(ix, iy))
                        .all(|ix| m.get(ix as isize, iy as isize).is_none()));
                }
            }
            // Rows copied out are the map's rows.
            let mut row = vec![Some(-1.0); m.nx];
            for iy in 0..m.ny {
                m.copy_row(iy, &mut row);
                let want: Vec<Option<f64>> = (0..m.nx)
                    .map(|ix| m.get(ix as isize, iy as isize))
                    .collect();
                assert_eq!(row, want);
            }
            // The dense constructor and the comparison see the same map.
            assert_eq!(
                HeightMap::from_dense(m.x0, m.y0, m.cell, m.nx, m.ny, &want),
                m
            );
        }
        assert!(seen > 300 && sparse > 3, "{seen} {sparse}");
    }

    /// The map built in parallel pieces of points against the map of one piece (one loop
    /// over the points, in their order): the same stored tiles and the same heights, bit
    /// for bit, at 1 and 2 threads, for pieces of 1, 7 and 1000 points. Seeded clouds mix
    /// dense patches (points in their own cell), sparse ones (points reaching up to two
    /// cells round), stacked layers (columns of several heights) and a run of points
    /// stepping back and forth across a tile border (spans of tiles that change point by
    /// point).
    #[test]
    fn cells_at_least_are_the_valid_cells_that_high() {
        // 11 x 9 cells (tiles cut by the map's edge), heights varying, some invalid.
        let (nx, ny) = (11, 9);
        let h: Vec<Option<f64>> = (0..nx * ny)
            .map(|i| (i % 7 != 3).then_some((i % 5) as f64 * 0.1))
            .collect();
        let m = HeightMap::from_dense(0.0, 0.0, 0.05, nx, ny, &h);
        let mut got = m.cells_at_least(0.2);
        got.sort_unstable();
        let mut want: Vec<(usize, usize)> = (0..ny)
            .flat_map(|iy| (0..nx).map(move |ix| (ix, iy)))
            .filter(|&(ix, iy)| h[iy * nx + ix].is_some_and(|v| v >= 0.2))
            .collect();
        want.sort_unstable();
        assert!(!want.is_empty() && want.len() < nx * ny);
        assert_eq!(got, want);
    }

    #[test]
    fn pieces_build_the_map_of_one_loop() {
        use crate::cellhash::on_threads;
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(41);
        let cfg = HeightMapConfig::default();
        let bits = |m: &HeightMap| -> (Vec<usize>, Vec<Option<u64>>) {
            let h = m.heights.iter().map(|h| h.map(f64::to_bits)).collect();
            (m.tiles.clone(), h)
        };
        for round in 0..6 {
            // A dense floor (3600 points), then patches of every density.
            let mut pts = square(-1.2, -1.2, 0.6, 0.01, 0.0);
            for _ in 0..rng.random_range(2..5) {
                let (x0, y0) = (rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0));
                let step = [0.005, 0.01, 0.04, 0.09][rng.random_range(0..4)];
                let z = [0.0, 0.45, 0.6, 1.5][rng.random_range(0..4)];
                for p in square(x0, y0, rng.random_range(0.3..0.8), step, z) {
                    let jitter = rng.random_range(-0.002..0.002);
                    pts.push(Point3::new(p.x + jitter, p.y - jitter, p.z + jitter.abs()));
                }
            }
            for k in 0..500 {
                let x = 0.4 + if k % 2 == 0 { -0.01 } else { 0.01 };
                pts.push(Point3::new(x, 0.1 + k as f64 * 1e-4, 0.45));
            }
            let cloud = PointCloud::new(pts);
            let one = bits(&HeightMap::build(
                &cloud,
                &cfg,
                true,
                usize::MAX,
                Spacing::Measure,
            ));
            let valid = one.1.iter().flatten().count();
            assert!(
                valid > 50 && cloud.len() > 3000,
                "{round}: {valid}, {}",
                cloud.len()
            );
            for threads in [1, 2] {
                for piece in [1, 7, 1000] {
                    let m = on_threads(threads, || {
                        HeightMap::build(&cloud, &cfg, true, piece, Spacing::Measure)
                    });
                    assert!(
                        bits(&m) == one,
                        "round {round}, {threads} threads, piece {piece}"
                    );
                }
            }
        }
    }

    /// The map built with the dense tiles' spacings left out ([`HeightMap::from_cloud`])
    /// against the map built from every tile's exact spacing: the same grid, the same
    /// stored tiles and the same heights, bit for bit. Seeded clouds mix dense patches
    /// (reach under half a cell), sparse ones and, in some rounds, a doubled dense floor
    /// that makes the cloud's spacing 0 (the tiles measured again); the reach settings
    /// vary round the thresholds.
    #[test]
    fn skipping_dense_tiles_builds_the_same_map() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(23);
        let base = HeightMapConfig::default();
        let configs = [
            base,
            HeightMapConfig {
                sample_reach: 3.0,
                ..base
            },
            HeightMapConfig {
                sample_reach: 0.0,
                ..base
            },
            HeightMapConfig {
                max_reach: 0.02,
                ..base
            },
            HeightMapConfig {
                sample_reach: -1.0,
                ..base
            },
        ];
        for round in 0..16 {
            let mut pts = Vec::new();
            for _ in 0..rng.random_range(1..5) {
                let (x0, y0) = (rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
                let step = [0.004, 0.01, 0.02, 0.04, 0.07][rng.random_range(0..5)];
                let z = [0.0, 0.45, 0.9][rng.random_range(0..3)];
                for p in square(x0, y0, rng.random_range(0.1..0.5), step, z) {
                    let jitter = rng.random_range(-0.001..0.001);
                    pts.push(Point3::new(p.x + jitter, p.y - jitter, p.z + jitter.abs()));
                }
            }
            if round % 4 == 0 {
                // Each point and four copies: the fourth nearest neighbour is 0 away.
                let floor = square(3.0, 3.0, 1.0, 0.005, 0.0);
                for _ in 0..5 {
                    pts.extend(&floor);
                }
            }
            let cloud = PointCloud::new(pts);
            for cfg in &configs {
                let fast = HeightMap::build(&cloud, cfg, true, PIECE, Spacing::Measure);
                let exact = HeightMap::build(&cloud, cfg, false, PIECE, Spacing::Measure);
                assert_eq!(
                    (fast.x0, fast.y0, fast.nx, fast.ny, fast.tiles_x),
                    (exact.x0, exact.y0, exact.nx, exact.ny, exact.tiles_x)
                );
                assert_eq!(fast.tiles, exact.tiles, "{round} {cfg:?}");
                let bits = |m: &HeightMap| -> Vec<Option<u64>> {
                    m.heights.iter().map(|h| h.map(f64::to_bits)).collect()
                };
                assert_eq!(bits(&fast), bits(&exact), "{round} {cfg:?}");
            }
        }
    }
}
