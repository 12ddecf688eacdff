//! Position hypotheses (section 4.1): the torso template slides over the height map, the
//! fuzzy rule rates each cell, and the height-gradient descent gives a heading.

use nalgebra::{Matrix3, Point3, Vector3};

use crate::method::fuzzy::{rule, Trapezoid};
use crate::method::heightmap::{Cells, HeightMap};
use crate::model::hierarchy::{FlatRule, HypothesisRule, Orientation, PerchRule};
use crate::num::{to_isize, to_usize};
use rayon::prelude::*;

/// A promising position for the agent.
#[derive(Debug, Clone, PartialEq)]
pub struct Hypothesis {
    /// Cell `(ix, iy)` of the height map.
    pub cell: (usize, usize),
    /// Cell centre in x-y and mean height under the template in z, metres (world).
    pub position: Point3<f64>,
    /// Highest height under the template, metres.
    pub top: f64,
    /// Crisp availability (first of maximum, Fig. 5d), the arrow length of Fig. 4c.
    pub availability: f64,
    /// Heading (radians about z, 0 = +x) from the gradient descent; `None` where the
    /// neighbourhood is flat and no heading is preferred.
    pub heading: Option<f64>,
    /// The heading facing away from the top of the tallest thing near the place (a chair's
    /// back rather than the table it stands at, whose larger top can turn the plane fit's
    /// descent round). Where the gradient gives no heading, the fitting tries its offsets
    /// round this one; where none of those is free, its all-round search starts here, so
    /// that the order, and with it the pose kept among equally stable ones, follows the
    /// scene and not the frame (section 4.2). `None` where nothing rises above the place.
    pub facing: Option<f64>,
    /// The three memberships: discontinuity low, roughness low, height comfortable.
    pub memberships: [f64; 3],
    /// Whether the rating set aside cells standing over the seat's edge (the rule's
    /// `rise_height`): such a place is a seat only where no plain one is near, and its
    /// detections rank after those of plain places.
    pub risen: bool,
    /// Whether the surface round the place was narrower in view than the `surface` rule's
    /// `min_width` and passed only because the scan runs on unseen across it (a bed cut
    /// lengthwise by the image edge): its width is unknown. Such a place may not also
    /// leave the legs over unseen space (the node's `unseen_sweeps`).
    pub unseen_width: bool,
    /// Where the hierarchy asks a flat rectangle round the place (its `flat` rule), the
    /// orientations (radians about z, in `[0, pi)`) along which one lies there: the body
    /// is laid along one of them ([`crate::method::fit`]). Empty: any heading.
    pub flat_axes: Vec<f64>,
}

/// Rates every valid cell of `map` with the rule of section 4.1 for an agent of body
/// height `body_height` (metres) and returns the available ones in row-major cell order.
pub fn hypotheses(
    map: &HeightMap,
    rule_: &HypothesisRule,
    orientation: Orientation,
    body_height: f64,
) -> Vec<Hypothesis> {
    hypotheses_in_pieces(map, rule_, orientation, body_height, BAND_ROWS)
}

/// [`hypotheses`], the rows rated in pieces of about `piece_rows` map rows side by side
/// (at least one row a piece), each piece with a band of its own, and the hypotheses
/// kept in row order: the same whatever the pieces (a cell's rating reads the map's
/// heights, whichever band holds them).
fn hypotheses_in_pieces(
    map: &HeightMap,
    rule_: &HypothesisRule,
    orientation: Orientation,
    body_height: f64,
    piece_rows: usize,
) -> Vec<Hypothesis> {
    let template = map.disc(rule_.template_diameter * body_height / 2.0);
    let neighbourhood = map.disc(rule_.gradient_radius * body_height);
    // The surface rule, the folds it crosses (metres above its level) and its disc.
    let surface_rule = rule_.surface.map(|sr| {
        let rise = sr.rise.unwrap_or(sr.tolerance);
        (sr, rise, map.disc(sr.radius * body_height))
    });
    // The flat rectangle's samples, the same at every place.
    let flat_grid = rule_
        .flat
        .as_ref()
        .zip(rule_.surface.as_ref())
        .map(|(f, sr)| FlatGrid::new(f, sr.min_width * body_height, body_height, map.cell));
    // The membership in fractions of H, or in metres as it is.
    let height = rule_
        .height
        .map(|t| t.scaled(body_height))
        .or(rule_.height_m);
    let perch = rule_.perch.map(|p| Perch::new(&p, map, body_height));
    let facing_tolerance = rule_.facing_tolerance.unwrap_or(0.0);
    // A direction across the surface (descent, facing) as the body's heading.
    let turn = |d: f64| match orientation {
        Orientation::Parallel => d,
        Orientation::Orthogonal => d + std::f64::consts::FRAC_PI_2,
    };
    // Only every `step`-th cell in x and y is tried (grid-aligned, so deterministic).
    let step = rule_
        .spacing
        .map_or(1, |s| to_usize((s * body_height / map.cell).round()).max(1));
    // Rows above and below a cell that its template and neighbourhood read.
    let reach = template
        .iter()
        .chain(&neighbourhood)
        .map(|&(_, dy)| dy.unsigned_abs())
        .max()
        .unwrap_or(0);
    // The hypotheses of row `iy`, rated from `band`, into `out`.
    let row = |band: &mut Band, iy: usize, out: &mut Vec<Hypothesis>| {
        if !band.holds(iy, reach) {
            band.fill(map, iy, reach);
        }
        // Tiles of the map that no point reaches hold no valid cell to rate.
        for ix in map.stored_columns(iy, step) {
            let Some(plain) = rate(&*band, ix, iy, &template, height.as_ref(), rule_) else {
                continue;
            };
            // A seat too high to sit on is perched on where its top is a stool's.
            let Rating {
                mean,
                top,
                memberships,
                risen,
            } = match &perch {
                Some(p) if !available(rule_, plain.memberships) => p
                    .rate(map, &*band, ix, iy, &template, height.as_ref(), rule_)
                    .unwrap_or(plain),
                _ => plain,
            };
            let verdict =
                rule_
                    .available
                    .defuzzify(rule(memberships[0], memberships[1], memberships[2]));
            if !verdict.available {
                continue;
            }
            // The surface reaches further than the band's rows: read from the map.
            let shape = surface_rule.as_ref().map(|(sr, rise, disc)| {
                (
                    sr,
                    *rise,
                    surface(map, ix, iy, disc, mean, sr.tolerance, *rise),
                )
            });
            // Too narrow where seen edges bound it. A long strip running on unseen out of
            // the scan across its axis (a bed cut lengthwise by the image edge) is of
            // unknown width, not too narrow; its axis is known where it is elongated and
            // at least as long as the surface's reach (half a body).
            let mut unseen_width = false;
            if let Some((sr, rise, shape)) = &shape {
                let reach = sr.radius * body_height;
                if shape.width < sr.min_width * body_height {
                    unseen_width = shape.length >= reach
                        && shape.along(sr.elongation).is_some()
                        && open_across(
                            map,
                            (ix, iy),
                            shape.axis,
                            reach / 2.0,
                            (mean, sr.tolerance, *rise),
                            sr.face,
                        );
                    if !unseen_width {
                        continue;
                    }
                }
            }
            // Where the gradient is flat, the direction across the surface's long axis
            // stands in for the descent (both point across a bed or a bench).
            let across =
                descent(&*band, ix, iy, &neighbourhood, rule_.flat_gradient).or_else(|| {
                    shape
                        .and_then(|(sr, _, shape)| shape.along(sr.elongation))
                        .map(|along| along + std::f64::consts::FRAC_PI_2)
                });
            let facing =
                away_from_highest(&*band, ix, iy, &neighbourhood, mean, facing_tolerance).map(turn);
            // A descent that climbs towards the tallest top was turned round by a larger,
            // lower surface beyond the seat (the table a chair is pushed in at).
            let heading = match (across.map(turn), facing) {
                (Some(d), Some(f)) if rule_.facing_overrules && (d - f).cos() < 0.0 => Some(f),
                (d, _) => d,
            };
            // A flat rectangle along the body: the orientations it lies along, or none.
            let mut flat_axes = Vec::new();
            if let (Some(grid), Some((sr, rise, _))) = (&flat_grid, &shape) {
                flat_axes = flat_rectangles(map, (ix, iy), (mean, sr.tolerance, *rise), grid);
                if flat_axes.is_empty() {
                    continue;
                }
            }
            let (x, y) = map.centre(ix, iy);
            out.push(Hypothesis {
                cell: (ix, iy),
                position: Point3::new(x, y, mean),
                top,
                availability: verdict.value,
                heading,
                facing,
                memberships,
                risen,
                unseen_width,
                flat_axes,
            });
        }
    };
    let rows: Vec<usize> = (0..map.ny).step_by(step).collect();
    let pieces: Vec<Vec<Hypothesis>> = rows
        .par_chunks((piece_rows / step).max(1))
        .map(|piece| {
            let mut band = Band::default();
            let mut out = Vec::new();
            for &iy in piece {
                row(&mut band, iy, &mut out);
            }
            out
        })
        .collect();
    pieces.concat()
}

/// Whether memberships `[discontinuity, roughness, height]` make a place available (the
/// rule and its defuzzification, Fig. 5).
fn available(rule_: &HypothesisRule, [d, r, h]: [f64; 3]) -> bool {
    rule_.available.defuzzify(rule(d, r, h)).available
}

/// A [`PerchRule`] for one body height: its membership scaled, the neighbourhood its top
/// is measured over, and its lengths in metres.
struct Perch {
    height: Trapezoid,
    disc: Vec<(isize, isize)>,
    tolerance: f64,
    longest: f64,
    max_walled: f64,
    rim_drop: f64,
}

impl Perch {
    fn new(p: &PerchRule, map: &HeightMap, body_height: f64) -> Self {
        Perch {
            height: p.height.scaled(body_height),
            disc: map.disc(p.radius * body_height),
            tolerance: p.tolerance,
            longest: p.max_length * body_height,
            max_walled: p.max_walled,
            rim_drop: p.rim_drop,
        }
    }

    /// The rating of cell `(ix, iy)` as a small top perched on, where it is one: its own
    /// cell at perching height, available as a small top ([`rate_top`]) with the larger
    /// of the two height memberships, and the top round it short and dropping round its
    /// rim ([`rimmed_surface`]). `band` holds the template's rows, `map` the rest.
    #[allow(clippy::too_many_arguments)]
    fn rate(
        &self,
        map: &HeightMap,
        band: &impl Cells,
        ix: usize,
        iy: usize,
        template: &[(isize, isize)],
        height: Option<&Trapezoid>,
        rule_: &HypothesisRule,
    ) -> Option<Rating> {
        let centre = band.height(ix as isize, iy as isize)?;
        if self.height.membership(centre) <= 0.0 {
            return None;
        }
        let mut r = rate_top(band, ix, iy, template, height, rule_, Some(self.tolerance))?;
        r.memberships[2] = r.memberships[2].max(self.height.membership(r.mean));
        if !available(rule_, r.memberships) {
            return None;
        }
        let top = rimmed_surface(
            map,
            ix,
            iy,
            &self.disc,
            r.mean,
            self.tolerance,
            self.tolerance,
            self.rim_drop,
            Some(self.longest),
        );
        (top.spread_along > 0.0 && top.length <= self.longest && top.walled <= self.max_walled)
            .then_some(r)
    }
}

/// Rows of a band of the map whose cells are rated from one copy: 64 rows and the 2 x 8
/// rows their neighbourhoods read (0.44 m at 5 cm) copy each row 1.25 times. Also the
/// rows of a piece rated on its own ([`hypotheses`]): a 3.2 m piece at 5 cm, so a room
/// view's map gives a few pieces to share out.
const BAND_ROWS: usize = 64;

/// [`BAND_ROWS`] rows of the height map and `reach` rows on either side, copied into one
/// dense row-major block: the template and neighbourhood of every cell in the band are
/// then read with a multiply each instead of a tile look-up (each cell is read about a
/// hundred times). Reads the same heights as [`HeightMap::get`] for rows it holds.
#[derive(Default)]
struct Band {
    /// Map row of the block's first row (may be negative).
    iy0: isize,
    /// Rows held.
    rows: usize,
    /// Columns per row: the map's `nx`.
    nx: usize,
    /// The map's cell edge, metres.
    cell: f64,
    /// Heights, row-major.
    heights: Vec<Option<f64>>,
}

impl Band {
    /// Whether rows `iy - reach ..= iy + reach` are all held.
    fn holds(&self, iy: usize, reach: usize) -> bool {
        let (lo, hi) = (iy as isize - reach as isize, iy + reach);
        self.rows > 0 && lo >= self.iy0 && (hi as isize) < self.iy0 + self.rows as isize
    }

    /// Holds rows `iy - reach .. iy + BAND_ROWS + reach` of `map` (invalid outside it).
    fn fill(&mut self, map: &HeightMap, iy: usize, reach: usize) {
        self.iy0 = iy as isize - reach as isize;
        self.rows = BAND_ROWS + 2 * reach;
        self.nx = map.nx;
        self.cell = map.cell;
        // Every cell is written below: rows of the map by `copy_row`, the others here.
        self.heights.resize(self.rows * self.nx, None);
        for (r, row) in self.heights.chunks_mut(self.nx.max(1)).enumerate() {
            match usize::try_from(self.iy0 + r as isize) {
                Ok(y) if y < map.ny => map.copy_row(y, row),
                _ => row.fill(None),
            }
        }
    }
}

impl Cells for Band {
    /// Height of map cell `(ix, iy)`; `None` if invalid, outside the map or not held.
    fn height(&self, ix: isize, iy: isize) -> Option<f64> {
        let r = iy - self.iy0;
        if ix < 0 || r < 0 || ix as usize >= self.nx || r as usize >= self.rows {
            return None;
        }
        self.heights[r as usize * self.nx + ix as usize]
    }

    fn cell_size(&self) -> f64 {
        self.cell
    }
}

/// What the fuzzy rule of section 4.1 sees at one cell: the template's statistics and the
/// three memberships.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rating {
    /// Mean height of the valid cells under the template, metres.
    pub mean: f64,
    /// Highest height under the template, metres.
    pub top: f64,
    /// Discontinuity low, roughness low, height comfortable.
    pub memberships: [f64; 3],
    /// Whether cells above the rule's `rise_height` were set aside.
    pub risen: bool,
}

/// Count, sum, sum of squares and highest of a set of heights, metres: their mean and
/// standard deviation (section 4.1's roughness).
#[derive(Debug, Clone, Copy)]
struct Moments {
    n: usize,
    sum: f64,
    sum2: f64,
    top: f64,
}

impl Default for Moments {
    fn default() -> Self {
        Moments {
            n: 0,
            sum: 0.0,
            sum2: 0.0,
            top: f64::MIN,
        }
    }
}

impl Moments {
    fn add(&mut self, h: f64) {
        self.n += 1;
        self.sum += h;
        self.sum2 += h * h;
        self.top = self.top.max(h);
    }

    fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }

    fn spread(&self) -> f64 {
        let mean = self.mean();
        (self.sum2 / self.n as f64 - mean * mean).max(0.0).sqrt()
    }
}

/// Rates cell `(ix, iy)` of `map` with the torso `template` (cell offsets) and the
/// `height` set already in metres; `None` if the cell is invalid.
///
/// With the rule's `hole_depth`, a template whose cells vary more than "roughness is low"
/// fully allows is looked at again: cells more than `hole_depth` below the template's
/// median height are gaps (the floor seen through a slatted or cut-out seat, or past its
/// edge) and count as missing, towards the discontinuity, instead of as roughness; the
/// mean and the roughness are then those of the other cells (an extension of section 4.1).
pub fn rate(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    template: &[(isize, isize)],
    height: Option<&Trapezoid>,
    rule_: &HypothesisRule,
) -> Option<Rating> {
    rate_top(map, ix, iy, template, height, rule_, None)
}

/// [`rate`], or with `small_top` (metres) the rating of a top smaller than the template (a
/// stool perched on, [`PerchRule`]): cells more than `small_top`
/// below the template's median height count as missing, whether the top's rim drops to
/// the floor or a ring all round or a stool's pedestal shows through a gap in the map;
/// cells above it count as roughness (leaves of a plant, things on a cabinet), or with
/// `rise_height` as a rise, as on any seat.
fn rate_top(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    template: &[(isize, isize)],
    height: Option<&Trapezoid>,
    rule_: &HypothesisRule,
    small_top: Option<f64>,
) -> Option<Rating> {
    let at = |dx: isize, dy: isize| map.height(ix as isize + dx, iy as isize + dy);
    let centre = at(0, 0)?;
    let mut all = Moments::default();
    for &(dx, dy) in template {
        if let Some(h) = at(dx, dy) {
            all.add(h);
        }
    }
    let mut kept = all;
    let mut risen = false;
    if small_top.is_some()
        || all.spread() > rule_.roughness.full
            && (rule_.hole_depth.is_some() || rule_.rise_height.is_some())
    {
        let mut hs: Vec<f64> = template.iter().filter_map(|&(dx, dy)| at(dx, dy)).collect();
        let mid = hs.len() / 2;
        let (_, median, _) = hs.select_nth_unstable_by(mid, f64::total_cmp);
        let median = *median;
        let depth = rule_.hole_depth.unwrap_or(f64::INFINITY);
        // A place on the rise itself (the top of an arm or a back) keeps its cells as
        // roughness.
        let ceiling = rule_
            .rise_height
            .map(|r| median + r)
            .filter(|&c| centre <= c)
            .unwrap_or(f64::INFINITY);
        let floor = median - depth;
        // One cell past the template's farthest offset.
        let reach = template
            .iter()
            .map(|&(dx, dy)| dx.abs().max(dy.abs()))
            .max()
            .unwrap_or(0)
            + 1;
        // A low cell is a gap when the surface goes on beyond it (a cell within `depth`
        // of the median), seen from the place; past the surface's edge it does not, and
        // the cell stays as roughness.
        let enclosed = |dx: isize, dy: isize| {
            (dx, dy) == (0, 0)
                || cells_beyond(dx, dy, reach)
                    .any(|(x, y)| at(x, y).is_some_and(|h| (h - median).abs() <= depth))
        };
        kept = Moments::default();
        for &(dx, dy) in template {
            match (at(dx, dy), small_top) {
                // Below a small top: its rim's drop, or what shows through it.
                (Some(h), Some(t)) if h < median - t => {}
                (Some(h), _) if h > ceiling => risen = true,
                // Above it (leaves, clutter): roughness, as on any seat.
                (Some(h), Some(_)) => kept.add(h),
                (Some(h), None) if h >= floor || !enclosed(dx, dy) => kept.add(h),
                _ => {}
            }
        }
    }
    let Moments { n, top, .. } = kept;
    let (mean, roughness) = (kept.mean(), kept.spread());
    let discontinuity = 1.0 - n as f64 / template.len() as f64;
    Some(Rating {
        risen,
        mean,
        top,
        memberships: [
            rule_.discontinuity.membership(discontinuity),
            rule_.roughness.membership(roughness),
            height.map_or(1.0, |t| t.membership(mean)),
        ],
    })
}

/// The cells past offset `(dx, dy)` (not the place itself) on the line from the place
/// through it, one a step: the offset scaled by `1 + k / |(dx, dy)|`, rounded, for `k`
/// from 1 to `steps` (so about a cell apart, outwards).
fn cells_beyond(dx: isize, dy: isize, steps: isize) -> impl Iterator<Item = (isize, isize)> {
    let len = ((dx * dx + dy * dy) as f64).sqrt();
    (1..=steps).map(move |k| {
        let t = 1.0 + k as f64 / len;
        (
            to_isize((dx as f64 * t).round()),
            to_isize((dy as f64 * t).round()),
        )
    })
}

/// Direction (radians about z) of steepest descent of the least-squares plane through the
/// valid cells of the neighbourhood; `None` if the slope is below `flat` (m/m).
pub fn descent(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    neighbourhood: &[(isize, isize)],
    flat: f64,
) -> Option<f64> {
    let cell = map.cell_size();
    // Normal equations of h = a + gx * dx + gy * dy, dx and dy in metres.
    let mut ata = Matrix3::<f64>::zeros();
    let mut atb = Vector3::<f64>::zeros();
    for &(dx, dy) in neighbourhood {
        if let Some(h) = map.height(ix as isize + dx, iy as isize + dy) {
            let row = Vector3::new(1.0, dx as f64 * cell, dy as f64 * cell);
            ata += row * row.transpose();
            atb += row * h;
        }
    }
    let sol = ata.try_inverse()? * atb;
    let (gx, gy) = (sol.y, sol.z);
    if (gx * gx + gy * gy).sqrt() < flat {
        return None;
    }
    Some((-gy).atan2(-gx))
}

/// Direction (radians about z) from the top of the tallest thing near cell `(ix, iy)`
/// towards the cell: from the centroid of the cells of the neighbourhood (cell offsets)
/// within `tolerance` metres of its highest valid cell. A flat top (a chair's back, a
/// headboard) is taken whole, so which of its cells the scan's noise made highest does not
/// turn the direction. `None` if no cell rises above `level` (metres) or the centroid is
/// the cell itself (a top all round it).
pub fn away_from_highest(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    neighbourhood: &[(isize, isize)],
    level: f64,
    tolerance: f64,
) -> Option<f64> {
    let at = |&(dx, dy): &(isize, isize)| map.height(ix as isize + dx, iy as isize + dy);
    let highest = neighbourhood
        .iter()
        .filter_map(at)
        .fold(f64::NEG_INFINITY, f64::max);
    if highest <= level {
        return None;
    }
    let (mut sx, mut sy) = (0isize, 0isize);
    for o in neighbourhood {
        if at(o).is_some_and(|h| h >= highest - tolerance) {
            sx += o.0;
            sy += o.1;
        }
    }
    (sx != 0 || sy != 0).then(|| (-sy as f64).atan2(-sx as f64))
}

/// The shape of the flat surface round a place: its long axis and its width across it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct SurfaceShape {
    /// Direction of the long axis, radians about z in `[0, pi)`.
    pub axis: f64,
    /// Spread (standard deviation) of the surface along the long axis, metres.
    pub spread_along: f64,
    /// Spread across it, metres.
    pub spread_across: f64,
    /// Width across the long axis, metres: that of a rectangle with the same spread
    /// (`sqrt(12)` standard deviations of the cell centres), less the half cell by which
    /// the edge cells overhang the edge on either side; 0 where the place is not on the
    /// surface.
    pub width: f64,
    /// Length along the long axis, metres, measured as `width` is.
    pub length: f64,
    /// Share of the cells bounding the surface (seen, off its level, within the
    /// neighbourhood) that do not drop far below it ([`surface`]: that stand above it): 0
    /// for a stool's top, most for a box on a desk or a patch of a desk between the things
    /// standing on it.
    pub walled: f64,
}

impl SurfaceShape {
    /// The long axis, if the surface is at least `elongation` times longer than wide
    /// (spreads); `None` for a square or round top, or a double bed seen over less than
    /// its width.
    pub fn along(&self, elongation: f64) -> Option<f64> {
        (self.spread_along > 0.0 && self.spread_along >= elongation * self.spread_across)
            .then_some(self.axis)
    }
}

/// The flat surface round cell `(ix, iy)` of `map`: the cells of `neighbourhood` (cell
/// offsets) within `tolerance` metres of `level`, and the folds lying on it (cells up to
/// `rise` metres above `level` beyond which the surface goes on at its level or is not
/// seen: a duvet's folds and lumps on a mattress), reached from the cell through such
/// cells or invalid ones (a hole in the scan is not an edge), 4-connected, taken as a 2-D
/// point set whose principal axes give its long axis and width. A cell lower than
/// `tolerance` below is an edge (a drop where the legs hang), and so is one higher than
/// `rise` above (something standing on the surface, or that it stands against). With
/// `rise` at most `tolerance`, the cells within `tolerance` of `level` only.
pub fn surface(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    neighbourhood: &[(isize, isize)],
    level: f64,
    tolerance: f64,
    rise: f64,
) -> SurfaceShape {
    rimmed_surface(
        map,
        ix,
        iy,
        neighbourhood,
        level,
        tolerance,
        rise,
        tolerance,
        None,
    )
}

/// Whether height `h` lies on a surface at `level` (metres): within `tolerance` below it,
/// or up to `rise` (at least `tolerance`) above it, a fold lying on it.
fn on_level(h: f64, level: f64, tolerance: f64, rise: f64) -> bool {
    (-tolerance..=rise.max(tolerance)).contains(&(h - level))
}

/// Whether the surface at `level` (metres) through cell `(ix, iy)` may reach further
/// across its long axis `axis` (radians about z, as [`SurfaceShape::axis`]) than the scan
/// shows, on one side. On the lines at right angles to `axis` from the cell and from the
/// points `reach` metres either way along the axis (all three inside `map`, or it is
/// not), every cell past the last one at the surface's level (within `-tolerance..=rise`
/// of it, as [`surface`] crosses) is unseen up to the map's edge: the cloud ends there
/// unseen (the image edge of a depth view cutting a bed lengthwise), so the surface's
/// width is unknown rather than too small. A drop or a rise seen anywhere past it on any
/// line bounds that side (the floor seen past the shadow of a bench's far edge, a wall);
/// so does a rise seen on the other side (a sofa's or a bench's back: a narrow seat in
/// front of a back is taken for what it shows). The three lines keep a seat cut across
/// by the image edge near the cell, where a single slanted line runs out along the cut.
/// With `face` (metres), a line's last cell at the level whose stack reaches `face` or
/// more below the level ([`HeightMap::depth`]) bounds it too: the side face of a seat's
/// front, or the floor under an open seat, is seen there, with the floor in front of it
/// out of view (below a camera looking down); a mattress cut by the image edge shows only
/// its top at the cut.
pub fn open_across(
    map: &HeightMap,
    (ix, iy): (usize, usize),
    axis: f64,
    reach: f64,
    (level, tolerance, rise): (f64, f64, f64),
    face: Option<f64>,
) -> bool {
    let crossed = |h: f64| on_level(h, level, tolerance, rise);
    let (ax, ay) = (axis.cos(), axis.sin());
    let (ux, uy) = (-ay, ax);
    let along = reach / map.cell;
    let starts = [0.0, -along, along].map(|s| (ix as f64 + s * ax, iy as f64 + s * ay));
    if !starts
        .iter()
        .all(|&(x, y)| map.contains(to_isize(x.round()), to_isize(y.round())))
    {
        return false;
    }
    // The height of the first cell seen off the surface on the line from `(x0, y0)` the
    // way `way`; `None` where the line runs out of the map first. Points seen `face` or
    // more below the level in the last surface cell before the map's edge end the surface
    // there as a drop would: the height given is that cell's bottom.
    let bound = |(x0, y0): (f64, f64), way: f64| {
        let start = (to_isize(x0.round()), to_isize(y0.round()));
        let mut last = map
            .get(start.0, start.1)
            .filter(|&h| crossed(h))
            .map(|_| start);
        for k in 1.. {
            let t = way * f64::from(k);
            let (x, y) = (
                to_isize((x0 + t * ux).round()),
                to_isize((y0 + t * uy).round()),
            );
            if !map.contains(x, y) {
                break;
            }
            match map.get(x, y) {
                Some(h) if !crossed(h) => return Some(h),
                Some(_) => last = Some((x, y)),
                None => {}
            }
        }
        let (x, y) = last?;
        let (h, d) = (map.get(x, y)?, map.depth(x, y)?);
        face.is_some_and(|f| level - (h - d) >= f).then_some(h - d)
    };
    [1.0, -1.0].into_iter().any(|way| {
        starts.iter().all(|&start| bound(start, way).is_none())
            && starts
                .iter()
                .all(|&start| bound(start, -way).is_none_or(|h| h < level))
    })
}

/// The samples of [`flat_rectangles`] for one rule, width and body: the rectangle's sizes
/// in cells and, per orientation, the cell offset of each sample, the same at every place
/// (so turned and rounded once per map, not once per place).
#[derive(Debug, Clone)]
pub struct FlatGrid {
    /// The orientations, radians about z, the rule's `turn` apart in `[0, pi)`.
    thetas: Vec<f64>,
    /// Samples either side of the centre along the rectangle and across it, and the
    /// furthest shift across, in cells.
    half_along: isize,
    half_across: isize,
    shifts: isize,
    /// The middle's half length along the rectangle, cells.
    middle: isize,
    /// Most samples off the level.
    most_off: isize,
    /// Largest spread along the rectangle of where an end's rise begins, cells.
    square: f64,
    /// Per orientation, the offset `(dx, dy)` in cells of sample `(i, j)` (`i` along,
    /// `j` across including the shifts), row `j` after row.
    offsets: Vec<Vec<(isize, isize)>>,
}

impl FlatGrid {
    /// The samples of `rule` for a rectangle `width` metres wide, for a body
    /// `body_height` metres tall, on a map of `cell`-metre cells. The samples span
    /// `width` and the length to the nearest cell.
    pub fn new(rule: &FlatRule, width: f64, body_height: f64, cell: f64) -> FlatGrid {
        let half_along = to_isize((rule.length * body_height / 2.0 / cell).round());
        let half_across = to_isize((width / 2.0 / cell).round());
        let shifts = to_isize((rule.shift / cell).floor());
        let samples = (2 * half_along + 1) * (2 * half_across + 1);
        let turns = to_isize((180.0 / rule.turn).round()).max(1);
        let thetas: Vec<f64> = (0..turns)
            .map(|k| (k as f64 * rule.turn).to_radians())
            .collect();
        let reach = half_across + shifts;
        let offsets = thetas
            .iter()
            .map(|theta| {
                let (ax, ay) = (theta.cos(), theta.sin());
                (-reach..=reach)
                    .flat_map(|j| {
                        (-half_along..=half_along).map(move |i| {
                            let (fx, fy) =
                                (i as f64 * ax - j as f64 * ay, i as f64 * ay + j as f64 * ax);
                            (to_isize(fx.round()), to_isize(fy.round()))
                        })
                    })
                    .collect()
            })
            .collect();
        FlatGrid {
            thetas,
            half_along,
            half_across,
            shifts,
            middle: to_isize((rule.middle * body_height / cell).floor()),
            most_off: to_isize((rule.off * samples as f64).floor()),
            square: width * rule.square.to_radians().tan() / cell,
            offsets,
        }
    }
}

/// The orientations (radians about z) of `grid` along which a flat rectangle lies round
/// cell `(ix, iy)` of `map` ([`FlatRule`], [`FlatGrid`]): centred on the cell along it and
/// shifted across by up to the rule's `shift`, with at most the rule's `off` share of its
/// samples (one per cell, on a grid turned with it) seen off `level` (metres): more than
/// `tolerance` below it, or more than `rise` (the folds of a duvet) above it. Beyond the
/// rule's `middle` from the cell along the rectangle, at either end, a rise is not off but
/// the surface going up (a reclined back, a raised leg rest), where it runs across the
/// whole width (every column seen at that end rises there) and square to it (where it
/// begins along the rectangle spreads over at most the rule's `square` degrees' worth of
/// its width); else the rectangle is not flat (a back along its side, or one running into
/// a corner). Unseen cells, and cells outside the map, are no edge (a hole in the scan, a
/// bed cut by the image edge).
pub fn flat_rectangles(
    map: &HeightMap,
    (ix, iy): (usize, usize),
    (level, tolerance, rise): (f64, f64, f64),
    grid: &FlatGrid,
) -> Vec<f64> {
    let rises = rise.max(tolerance);
    let (half_along, half_across, middle) = (grid.half_along, grid.half_across, grid.middle);
    let columns = 2 * half_along + 1;
    let reach = half_across + grid.shifts;
    grid.thetas
        .iter()
        .zip(&grid.offsets)
        .filter(|(_, offsets)| {
            (-grid.shifts..=grid.shifts).any(|s| {
                let mut off = 0;
                // Per end (towards -i, towards +i): the nearest rise's |i| beyond the
                // middle over the columns that have one (least, most), and how many
                // columns are seen there without one.
                let mut ends = [(isize::MAX, isize::MIN, 0usize); 2];
                for j in -half_across + s..=half_across + s {
                    let row = (j + reach) * columns;
                    let mut first = [None::<isize>; 2];
                    let mut seen_end = [false; 2];
                    for i in -half_along..=half_along {
                        let (dx, dy) = offsets[(row + i + half_along).unsigned_abs()];
                        let Some(h) = map.get(ix as isize + dx, iy as isize + dy) else {
                            continue;
                        };
                        let d = h - level;
                        let end = (i.abs() > middle).then_some(usize::from(i > 0));
                        if let Some(e) = end {
                            seen_end[e] = true;
                        }
                        match end {
                            Some(e) if d > rises => {
                                first[e] = Some(first[e].map_or(i.abs(), |f| f.min(i.abs())));
                            }
                            _ if d < -tolerance || d > rises => {
                                off += 1;
                                if off > grid.most_off {
                                    return false;
                                }
                            }
                            _ => {}
                        }
                    }
                    for e in 0..2 {
                        match first[e] {
                            Some(a) => ends[e] = (ends[e].0.min(a), ends[e].1.max(a), ends[e].2),
                            None if seen_end[e] => ends[e].2 += 1,
                            None => {}
                        }
                    }
                }
                // A rise at an end runs square across the whole width (a reclined back,
                // a raised leg rest), not along a side or into a corner.
                !ends
                    .iter()
                    .any(|&(lo, hi, open)| hi >= lo && (open > 0 || (hi - lo) as f64 > grid.square))
            })
        })
        .map(|(&theta, _)| theta)
        .collect()
}

/// [`surface`] (folds up to `rise` above `level` crossed), with the share of its bounding
/// cells that do not drop at least `rim` metres below `level` as [`SurfaceShape::walled`]:
/// a stool's top drops to the floor or its ring all round, a box on a desk to the desk. With `longest` (metres), a surface
/// with too many cells to be at most that long is given up early, as of infinite length.
#[allow(clippy::too_many_arguments)]
fn rimmed_surface(
    map: &impl Cells,
    ix: usize,
    iy: usize,
    neighbourhood: &[(isize, isize)],
    level: f64,
    tolerance: f64,
    rise: f64,
    rim: f64,
    longest: Option<f64>,
) -> SurfaceShape {
    let at = |dx: isize, dy: isize| map.height(ix as isize + dx, iy as isize + dy);
    // Cells within `tolerance` of the level, or up to `rise` above it (a fold lying on
    // the surface): the others bound it.
    let crossed = |h: f64| on_level(h, level, tolerance, rise);
    let raised = |h: f64| h - level > tolerance && crossed(h);
    if !at(0, 0).is_some_and(|h| (h - level).abs() <= tolerance) {
        return SurfaceShape::default();
    }
    // Offsets as indices of a (2r + 1)^2 square: which are in the neighbourhood, which
    // were reached.
    let r = neighbourhood
        .iter()
        .map(|&(dx, dy)| dx.abs().max(dy.abs()))
        .max()
        .unwrap_or(0);
    // Whether a reached cell is part of the surface: one within `tolerance` of the level
    // is; a raised one is a fold lying on it when, along the line from the place, the
    // first cell seen beyond the raised ones is level with the place again (the surface
    // goes on under the fold) or none is seen (the fold's shadow); not when that cell is
    // higher (a reclined back rising on) or lower (the fold is the surface's edge, a leg
    // rest sloping off its side).
    let counts = |dx: isize, dy: isize| match at(dx, dy) {
        Some(h) if raised(h) => cells_beyond(dx, dy, 2 * r)
            .take_while(|&(x, y)| x.abs() <= r && y.abs() <= r)
            .find_map(|(x, y)| at(x, y).filter(|&h| !raised(h)))
            .is_none_or(|h| (h - level).abs() <= tolerance),
        Some(h) => (h - level).abs() <= tolerance,
        None => false,
    };
    let side = 2 * r + 1;
    let index = |dx: isize, dy: isize| ((dy + r) * side + dx + r).unsigned_abs();
    let mut inside = vec![false; index(r, r) + 1];
    for &(dx, dy) in neighbourhood {
        inside[index(dx, dy)] = true;
    }
    let mut seen = vec![false; inside.len()];
    seen[index(0, 0)] = true;
    let mut stack = vec![(0isize, 0isize)];
    let (mut n, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    // Cells bounding the surface, and those of them that do not drop `rim` below it.
    let (mut edges, mut walls) = (0.0, 0.0);
    // n cells of side c spread at least as a disc of their area does: the spreads'
    // squares sum to at least n c^2 / (2 pi) - c^2 / 6 (each cell's own spread), so the
    // long axis's length is at least c sqrt(3 n / pi - 1) - c; more cells than this
    // cannot be `longest` long (one cell of margin for rounding).
    let most = longest.map(|l| {
        let c = l / map.cell_size() + 1.0;
        std::f64::consts::FRAC_PI_3 * (c * c + 1.0) + 1.0
    });
    while let Some((dx, dy)) = stack.pop() {
        if counts(dx, dy) {
            let (x, y) = (dx as f64 * map.cell_size(), dy as f64 * map.cell_size());
            n += 1.0;
            if most.is_some_and(|m| n > m) {
                return SurfaceShape {
                    length: f64::INFINITY,
                    ..SurfaceShape::default()
                };
            }
            sx += x;
            sy += y;
            sxx += x * x;
            syy += y * y;
            sxy += x * y;
        }
        for (nx, ny) in [(dx + 1, dy), (dx - 1, dy), (dx, dy + 1), (dx, dy - 1)] {
            if nx.abs() > r || ny.abs() > r {
                continue;
            }
            let k = index(nx, ny);
            if !inside[k] || seen[k] {
                continue;
            }
            seen[k] = true;
            match at(nx, ny) {
                Some(h) if !crossed(h) => {
                    // An edge of the surface: a drop where legs hang, or a step to
                    // something it stands on or that stands on it.
                    edges += 1.0;
                    if h > level - rim {
                        walls += 1.0;
                    }
                }
                _ => stack.push((nx, ny)),
            }
        }
    }
    let (mx, my) = (sx / n, sy / n);
    let (cxx, cyy, cxy) = (sxx / n - mx * mx, syy / n - my * my, sxy / n - mx * my);
    // Eigenvalues of the 2 x 2 covariance: the variances along and across the long axis.
    let half_gap = ((cxx - cyy) * (cxx - cyy) / 4.0 + cxy * cxy).sqrt();
    let along = ((cxx + cyy) / 2.0 + half_gap).max(0.0);
    let across = ((cxx + cyy) / 2.0 - half_gap).max(0.0);
    SurfaceShape {
        axis: (0.5 * (2.0 * cxy).atan2(cxx - cyy)).rem_euclid(std::f64::consts::PI),
        spread_along: along.sqrt(),
        spread_across: across.sqrt(),
        // A cell at the edge holds the surface over half its width on average: one cell
        // less than the cells' own spread.
        width: ((12.0 * across).sqrt() - map.cell_size()).max(0.0),
        length: ((12.0 * along).sqrt() - map.cell_size()).max(0.0),
        walled: if edges > 0.0 { walls / edges } else { 0.0 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::method::fuzzy::{Availability, Low, Trapezoid};
    use std::f64::consts::PI;

    fn rule_() -> HypothesisRule {
        HypothesisRule {
            template_diameter: 0.1,
            gradient_radius: 0.1,
            flat_gradient: 0.05,
            facing_tolerance: None,
            facing_overrules: false,
            hole_depth: None,
            rise_height: None,
            discontinuity: Low {
                full: 0.1,
                zero: 0.4,
            },
            roughness: Low {
                full: 0.01,
                zero: 0.04,
            },
            height: Some(Trapezoid {
                a: 0.2,
                b: 0.3,
                c: 0.5,
                d: 0.6,
            }),
            height_m: None,
            available: Availability { rise: [0.3, 0.7] },
            spacing: None,
            surface: None,
            flat: None,
            perch: None,
            hidden_seats: true,
        }
    }

    fn map(f: impl Fn(usize, usize) -> Option<f64>) -> HeightMap {
        map_of(20, f)
    }

    /// An `n` x `n` map of 5 cm cells with heights `f(ix, iy)`.
    fn map_of(n: usize, f: impl Fn(usize, usize) -> Option<f64>) -> HeightMap {
        let heights: Vec<Option<f64>> = (0..n * n).map(|i| f(i % n, i / n)).collect();
        HeightMap::from_dense(0.0, 0.0, 0.05, n, n, &heights)
    }

    /// The flat rectangle of `affordances/lying.toml` (commented out there), and its width
    /// at 1.75 m (0.70 m).
    fn flat_rule() -> (FlatRule, f64) {
        let rule = FlatRule {
            length: 0.6,
            middle: 0.05,
            square: 15.0,
            off: 0.05,
            shift: 0.25,
            turn: 15.0,
        };
        (rule, 0.40 * 1.75)
    }

    /// The orientations (degrees) of the flat rectangles round the centre of a 60 x 60
    /// map of 5 cm cells (3 m square) with heights `f(x, y)` in metres from its centre.
    fn flat_axes_of(f: impl Fn(f64, f64) -> Option<f64>) -> Vec<isize> {
        let m = map_of(60, |ix, iy| {
            f(ix as f64 * 0.05 - 1.5, iy as f64 * 0.05 - 1.5)
        });
        let (rule, width) = flat_rule();
        let grid = FlatGrid::new(&rule, width, 1.75, 0.05);
        flat_rectangles(&m, (30, 30), (0.45, 0.05, 0.10), &grid)
            .into_iter()
            .map(|a| to_isize(a.to_degrees().round()))
            .collect()
    }

    #[test]
    fn a_body_lies_on_a_flat_rectangle_along_a_bed_and_not_into_a_seats_corner() {
        let floor = Some(0.0);
        // A bed 2 m x 0.9 m along x, its top at 0.45 m: flat along it (0 deg), not
        // across it.
        let bed = flat_axes_of(|x, y| {
            Some(if x.abs() < 1.0 && y.abs() < 0.45 {
                0.45
            } else {
                0.0
            })
        });
        assert!(bed.contains(&0) && !bed.contains(&90), "{bed:?}");
        // The same with the floor unseen round it (a depth view's shadow): the same.
        let shadowed = flat_axes_of(|x, y| (x.abs() < 1.0 && y.abs() < 0.45).then_some(0.45));
        assert!(shadowed.contains(&0), "{shadowed:?}");
        // An L sofa's corner: seats 0.6 m deep along -x and -y from the corner, backs
        // 0.85 m high behind them; the place near the corner (the centre). Its seat
        // spreads wider than a bed across the diagonal, but no rectangle is flat.
        let l_sofa = |x: f64, y: f64| {
            let seat = x < 0.15 && y < 0.15 && (x > -0.45 || y > -0.45);
            let back =
                ((0.15..0.35).contains(&y) && x < 0.35) || ((0.15..0.35).contains(&x) && y < 0.35);
            Some(if back {
                0.85
            } else if seat {
                0.45
            } else {
                0.0
            })
        };
        assert_eq!(flat_axes_of(l_sofa), Vec::<isize>::new());
        // A wide recliner along x: a 0.8 m wide seat with its back rising square across
        // it 0.15 m behind the place: flat along x, the rise at the end.
        let recliner = |x: f64, y: f64| {
            if y.abs() >= 0.4 || x.abs() >= 1.0 {
                return floor;
            }
            Some(if x < -0.15 {
                0.45 + (-0.15 - x) * 0.8
            } else {
                0.45
            })
        };
        assert!(flat_axes_of(recliner).contains(&0));
        // The same rise running along one side of the end instead (a sofa's back beside
        // the legs): not flat along x.
        let side = |x: f64, y: f64| {
            if y.abs() >= 0.4 || x.abs() >= 1.0 {
                return floor;
            }
            Some(if x < -0.15 && y > 0.1 { 0.85 } else { 0.45 })
        };
        assert!(!flat_axes_of(side).contains(&0), "{:?}", flat_axes_of(side));
    }

    #[test]
    fn a_seat_high_plateau_is_available_and_the_floor_is_not() {
        // Body height 1.0: template radius 0.05 m (5 cells), seat of 8 x 8 cells at 0.45 m.
        let m = map(|x, y| {
            Some(if (6..14).contains(&x) && (6..14).contains(&y) {
                0.45
            } else {
                0.0
            })
        });
        let h = hypotheses(&m, &rule_(), Orientation::Parallel, 1.0);
        assert!(h.iter().any(|h| h.cell == (10, 10)));
        assert!(
            h.iter()
                .all(|h| (7..13).contains(&h.cell.0) && (7..13).contains(&h.cell.1)),
            "only seat interior"
        );
        let c = h.iter().find(|h| h.cell == (10, 10)).unwrap();
        assert!((c.position.z - 0.45).abs() < 1e-12);
        assert_eq!(c.memberships, [1.0, 1.0, 1.0]);
        // The seat is flat: no preferred heading.
        assert_eq!(c.heading, None);
    }

    #[test]
    fn floor_seen_through_a_seat_is_a_gap_and_past_its_edge_stays_rough() {
        // A 12 x 12 cell seat at 0.45 m over the floor, with two cells of floor showing
        // through it at (10, 10) and (11, 10); a template of radius 3 cells.
        let m = map(|x, y| {
            let seat = (4..16).contains(&x) && (4..16).contains(&y);
            let hole = y == 10 && (x == 10 || x == 11);
            Some(if seat && !hole { 0.45 } else { 0.0 })
        });
        let paper = HypothesisRule {
            template_diameter: 0.3,
            ..rule_()
        };
        let gaps = HypothesisRule {
            hole_depth: Some(0.25),
            ..paper.clone()
        };
        let template = m.disc(0.15);
        let rated = |rule: &HypothesisRule, x: usize, y: usize| {
            rate(&m, x, y, &template, None, rule).unwrap()
        };
        // Beside the holes: rough in the paper's rule, a smooth seat with two cells
        // missing with the gaps.
        assert_eq!(rated(&paper, 10, 11).memberships[1], 0.0);
        let r = rated(&gaps, 10, 11);
        assert_eq!(r.memberships, [1.0, 1.0, 1.0]);
        assert!((r.mean - 0.45).abs() < 1e-12 && r.top == 0.45);
        // At the seat's edge the floor beyond does not end: still rough either way.
        assert_eq!(rated(&paper, 5, 10).memberships[1], 0.0);
        assert_eq!(rated(&gaps, 5, 10).memberships[1], 0.0);
        // A smooth place is rated the same by both.
        assert_eq!(rated(&paper, 7, 6), rated(&gaps, 7, 6));
    }

    #[test]
    fn a_stool_top_above_seat_height_is_perched_on_and_a_table_top_is_not() {
        // Body height 1.0 m, 5 cm cells, a template of radius 3 cells: a bar stool's round
        // top 0.28 m across at 0.75 m, its middle cell showing its pedestal at 0.55 m
        // through a gap in the map; and a table top 0.90 m square at the same height.
        let stool = |x: usize, y: usize| {
            let (dx, dy) = (x as isize - 10, y as isize - 10);
            match dx * dx + dy * dy {
                0 => Some(0.55),
                1..=8 => Some(0.75),
                _ => Some(0.0),
            }
        };
        let table = |x: usize, y: usize| {
            Some(if (6..24).contains(&x) && (6..24).contains(&y) {
                0.75
            } else {
                0.0
            })
        };
        let seat = HypothesisRule {
            template_diameter: 0.3,
            hole_depth: Some(0.25),
            ..rule_()
        };
        let perching = HypothesisRule {
            perch: Some(crate::model::hierarchy::PerchRule {
                height: Trapezoid {
                    a: 0.6,
                    b: 0.65,
                    c: 0.85,
                    d: 0.9,
                },
                radius: 0.4,
                tolerance: 0.05,
                max_length: 0.45,
                max_walled: 0.25,
                rim_drop: 0.2,
            }),
            ..seat.clone()
        };
        let found = |f: &dyn Fn(usize, usize) -> Option<f64>, rule: &HypothesisRule| {
            hypotheses(&map_of(30, f), rule, Orientation::Parallel, 1.0)
        };
        // Too high to sit on: nothing without the perch.
        assert!(found(&stool, &seat).is_empty());
        let h = found(&stool, &perching);
        assert!(!h.is_empty());
        for p in &h {
            // On the top, at its height (the pedestal's cell is not the top).
            let (dx, dy) = (p.cell.0 as f64 - 10.0, p.cell.1 as f64 - 10.0);
            assert!((1.0..=8.0).contains(&(dx * dx + dy * dy)), "{p:?}");
            assert!((p.position.z - 0.75).abs() < 1e-12, "{p:?}");
            assert_eq!(p.memberships[1], 1.0, "{p:?}");
        }
        // A table top at the same height is too long to perch on, and a box as small as
        // the stool's top standing on it drops to the table, not the floor, round its rim.
        assert!(found(&table, &perching).is_empty());
        let boxed = |x: usize, y: usize| {
            let on_box = (8..13).contains(&x) && (8..13).contains(&y);
            table(x, y).map(|h| if on_box { 0.80 } else { h - 0.1 })
        };
        assert!(found(&boxed, &perching).is_empty());
        let alone = |x: usize, y: usize| boxed(x, y).map(|h| if h < 0.75 { 0.0 } else { h });
        assert!(!found(&alone, &perching).is_empty());
        // The same top at seat height is a seat by the first membership, perch or not.
        let low = |x, y| table(x, y).map(|h| h * 0.6);
        assert_eq!(found(&low, &seat), found(&low, &perching));
        assert!(!found(&low, &seat).is_empty());
    }

    #[test]
    fn a_top_given_up_early_is_longer_than_asked() {
        // Discs and rectangles of every size up to the neighbourhood's: wherever the
        // flood gives up early, the whole top is longer than asked; elsewhere it is the
        // same shape.
        let disc = map_of(1, |_, _| None).disc(0.5);
        let mut given_up = 0;
        for size in 1..=18 {
            let half = size as f64 / 2.0;
            let round = |x: usize, y: usize| {
                let (dx, dy) = (x as f64 - 20.0, y as f64 - 20.0);
                Some(if dx * dx + dy * dy <= half * half {
                    0.7
                } else {
                    0.0
                })
            };
            let oblong = |x: usize, y: usize| {
                let (dx, dy) = ((x as f64 - 20.0).abs(), (y as f64 - 20.0).abs());
                Some(if dx <= half && dy <= half / 2.0 {
                    0.7
                } else {
                    0.0
                })
            };
            for m in [map_of(41, round), map_of(41, oblong)] {
                let whole = rimmed_surface(&m, 20, 20, &disc, 0.7, 0.05, 0.05, 0.2, None);
                for k in 1..=18 {
                    let longest = 0.05 * k as f64;
                    let early =
                        rimmed_surface(&m, 20, 20, &disc, 0.7, 0.05, 0.05, 0.2, Some(longest));
                    if early.length.is_infinite() {
                        assert!(whole.length > longest, "{size}, {longest}: {whole:?}");
                        given_up += 1;
                    } else {
                        assert_eq!(early, whole, "{size}, {longest}");
                    }
                }
            }
        }
        assert!(given_up > 100, "{given_up}");
    }

    #[test]
    fn what_stands_over_a_seats_edge_is_set_aside_and_marked() {
        // A 12 x 12 cell seat at 0.45 m whose front rows (y >= 13) lie under a desk top
        // at 0.72 m (the seat under it hidden), on the floor; a template of radius 3 cells.
        let m = map(|x, y| {
            Some(match ((4..16).contains(&x), y) {
                (true, 13..=15) => 0.72,
                (true, 4..=12) => 0.45,
                _ => 0.0,
            })
        });
        let paper = HypothesisRule {
            template_diameter: 0.3,
            hole_depth: Some(0.25),
            ..rule_()
        };
        let risen = HypothesisRule {
            rise_height: Some(0.10),
            ..paper.clone()
        };
        let template = m.disc(0.15);
        let rated = |rule: &HypothesisRule, x: usize, y: usize| {
            rate(&m, x, y, &template, None, rule).unwrap()
        };
        // Two rows from the desk: rough in the paper's rule; with the rise set aside, a
        // smooth seat with the desk's cells missing, at the seat's height, marked.
        let p = rated(&paper, 10, 11);
        assert_eq!(p.memberships[1], 0.0);
        assert!(!p.risen);
        let r = rated(&risen, 10, 11);
        assert_eq!(r.memberships[1], 1.0);
        assert!(r.memberships[0] > 0.0 && r.memberships[0] < 1.0, "{r:?}");
        assert!((r.mean - 0.45).abs() < 1e-12 && r.top == 0.45 && r.risen);
        // On the desk itself the rating stays rough.
        let d = rated(&risen, 10, 13);
        assert_eq!(d.memberships[1], 0.0);
        assert!(!d.risen);
        // Away from the desk both rules agree and nothing is marked.
        assert_eq!(rated(&paper, 8, 6), rated(&risen, 8, 6));
    }

    #[test]
    fn spacing_tries_every_nth_cell_of_the_grid() {
        let m = map(|x, y| {
            Some(if (6..14).contains(&x) && (6..14).contains(&y) {
                0.45
            } else {
                0.0
            })
        });
        let all = hypotheses(&m, &rule_(), Orientation::Parallel, 1.0);
        // 0.1 H at H = 1 m over 0.05 m cells: every second cell.
        let sparse = HypothesisRule {
            spacing: Some(0.1),
            ..rule_()
        };
        let some = hypotheses(&m, &sparse, Orientation::Parallel, 1.0);
        assert!(some.iter().all(|h| h.cell.0 % 2 == 0 && h.cell.1 % 2 == 0));
        let even: Vec<_> = all
            .iter()
            .filter(|h| h.cell.0 % 2 == 0 && h.cell.1 % 2 == 0)
            .collect();
        assert_eq!(some.len(), even.len());
        assert!(!some.is_empty() && some.len() < all.len());
    }

    #[test]
    fn pieces_of_rows_give_the_hypotheses_of_one_pass() {
        // Seats of several heights and a slope over 150 rows: hypotheses in many rows.
        let m = map_of(150, |x, y| {
            Some(match (x / 30 + y / 25) % 4 {
                0 => 0.45,
                1 => 0.0,
                2 => 0.3 + 0.002 * (x % 30) as f64,
                _ => 0.55,
            })
        });
        for spacing in [None, Some(0.1), Some(0.15)] {
            let rule = HypothesisRule { spacing, ..rule_() };
            let one = hypotheses_in_pieces(&m, &rule, Orientation::Parallel, 1.0, usize::MAX);
            assert!(one.len() > 50, "{} hypotheses", one.len());
            let rows: std::collections::BTreeSet<usize> = one.iter().map(|h| h.cell.1).collect();
            assert!(rows.len() > 20, "{} rows", rows.len());
            for (piece, threads) in [(1, 2), (7, 2), (64, 3), (64, 1)] {
                let got = rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| hypotheses_in_pieces(&m, &rule, Orientation::Parallel, 1.0, piece));
                assert_eq!(got, one, "pieces of {piece} rows, {threads} threads");
            }
        }
    }

    #[test]
    fn holes_make_a_place_unavailable() {
        let m = map(|x, y| if (x + y) % 2 == 0 { Some(0.45) } else { None });
        assert!(hypotheses(&m, &rule_(), Orientation::Parallel, 1.0).is_empty());
    }

    #[test]
    fn heading_faces_down_the_slope() {
        // Height rises towards -x (a backrest on the -x side): the descent faces +x.
        let m = map(|x, _| Some(1.0 - 0.01 * x as f64));
        let d = descent(&m, 10, 10, &m.disc(0.2), 0.05).unwrap();
        assert!(d.abs() < 1e-9, "heading {d}");
        let m = map(|_, y| Some(0.01 * y as f64));
        let d = descent(&m, 10, 10, &m.disc(0.2), 0.05).unwrap();
        assert!(
            (d + std::f64::consts::FRAC_PI_2).abs() < 1e-9,
            "heading {d}"
        );
    }

    #[test]
    fn facing_turns_away_from_the_tallest_top_not_the_largest() {
        // A seat at 0.45 m round cell (10, 10); a chair back one cell deep at x = 5 and
        // 0.85 m, with noise of 1 cm that makes one of its end cells the highest; a table
        // top at 0.73 m over x >= 13, far larger within the neighbourhood (8 cells).
        let m = map(|x, y| {
            Some(match x {
                5 if y == 7 => 0.86,
                5 => 0.85,
                13.. => 0.73,
                _ => 0.45,
            })
        });
        let disc = m.disc(0.4);
        // The plane fit's descent faces the back (the table outweighs it) ...
        let d = descent(&m, 10, 10, &disc, 0.05).unwrap();
        assert!(d.cos() < -0.9, "descent {}", d.to_degrees());
        // ... the top of the back, taken whole, faces the table (+x).
        let f = away_from_highest(&m, 10, 10, &disc, 0.45, 0.05).unwrap();
        assert!(f.abs() < 0.05, "facing {}", f.to_degrees());
        // The highest cell alone would turn it by the noise.
        let f0 = away_from_highest(&m, 10, 10, &disc, 0.45, 0.0).unwrap();
        assert!(f0.abs() > 0.3, "facing {}", f0.to_degrees());
        // Nothing above the place: no facing.
        let flat = map(|_, _| Some(0.45));
        assert_eq!(away_from_highest(&flat, 10, 10, &disc, 0.45, 0.05), None);
        // The hypothesis at the seat's middle: the descent's heading, unless the facing
        // overrules it.
        let at = |overrules: bool| {
            let rule = HypothesisRule {
                gradient_radius: 0.4,
                facing_tolerance: Some(0.05),
                facing_overrules: overrules,
                ..rule_()
            };
            let hyps = hypotheses(&m, &rule, Orientation::Parallel, 1.0);
            let h = hyps.iter().find(|h| h.cell == (10, 10)).unwrap().clone();
            (h.heading.unwrap(), h.facing.unwrap())
        };
        let (kept, facing) = at(false);
        assert!((kept - d).abs() < 1e-12 && (facing - f).abs() < 1e-12);
        let (turned, _) = at(true);
        assert!(
            (turned - f).abs() < 1e-12,
            "heading {}",
            turned.to_degrees()
        );
    }

    /// A band of rows answers as the map for every cell its template and neighbourhood
    /// read: `rate` and `descent` on the band against the same on the map, bit for bit,
    /// for every cell, on seeded maps (a dense one with holes and slopes, a tiled one
    /// built from far-apart patches of points), bands filled as `hypotheses` fills them.
    #[test]
    fn bands_rate_as_the_map_does() {
        use crate::cloud::PointCloud;
        use crate::method::heightmap::HeightMapConfig;
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let (nx, ny) = (23, 2 * BAND_ROWS + 9);
        let dense: Vec<Option<f64>> = (0..nx * ny)
            .map(|i| {
                let slope = 0.45 + 0.01 * (i % nx) as f64 - 0.004 * (i / nx) as f64;
                (rng.random_range(0.0..1.0) < 0.8).then(|| slope + rng.random_range(0.0..0.01))
            })
            .collect();
        let mut pts = Vec::new();
        for _ in 0..6 {
            let (x0, y0) = (rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0));
            let z = rng.random_range(0.3..0.6);
            for k in 0..400 {
                let (u, v) = ((k % 20) as f64 * 0.02, (k / 20) as f64 * 0.02);
                pts.push(Point3::new(x0 + u, y0 + v, z + 0.1 * u));
            }
        }
        let maps = [
            HeightMap::from_dense(0.0, 0.0, 0.05, nx, ny, &dense),
            HeightMap::from_cloud(&PointCloud::new(pts), &HeightMapConfig::default()),
        ];
        let r = rule_();
        let height = r.height.map(|t| t.scaled(1.0));
        let mut compared = 0;
        for map in &maps {
            for radius in [0.1, 0.2] {
                let template = map.disc(radius);
                let reach = template
                    .iter()
                    .map(|&(_, dy)| dy.unsigned_abs())
                    .max()
                    .unwrap();
                let mut band = Band::default();
                for iy in 0..map.ny {
                    if !band.holds(iy, reach) {
                        band.fill(map, iy, reach);
                    }
                    for ix in 0..map.nx {
                        let want = rate(map, ix, iy, &template, height.as_ref(), &r);
                        let got = rate(&band, ix, iy, &template, height.as_ref(), &r);
                        assert_eq!(format!("{got:?}"), format!("{want:?}"), "{ix} {iy}");
                        let want = descent(map, ix, iy, &template, 1e-3);
                        let got = descent(&band, ix, iy, &template, 1e-3);
                        assert_eq!(got.map(f64::to_bits), want.map(f64::to_bits));
                        compared += usize::from(want.is_some());
                    }
                }
            }
        }
        assert!(compared > 1000, "{compared}");
    }
    /// A strip `width` cells wide along the direction `deg` (degrees about z) through the
    /// centre of a 40 x 40 map at 0.45 m over a floor at 0; `hole(x, y)` cells invalid.
    fn strip(width: f64, deg: f64, hole: impl Fn(usize, usize) -> bool) -> HeightMap {
        let (s, c) = deg.to_radians().sin_cos();
        map_of(40, |x, y| {
            let (dx, dy) = (x as f64 - 20.0, y as f64 - 20.0);
            let across = (-s * dx + c * dy).abs();
            (!hole(x, y)).then_some(if across <= width / 2.0 { 0.45 } else { 0.0 })
        })
    }

    /// [`surface`] at a seat's level (0.45 m) within 5 cm, no folds crossed.
    fn seat_level(m: &HeightMap, ix: usize, iy: usize, disc: &[(isize, isize)]) -> SurfaceShape {
        surface(m, ix, iy, disc, 0.45, 0.05, 0.05)
    }

    #[test]
    fn the_surface_of_a_strip_has_its_width_and_its_direction() {
        // Half a 1.75 m body round the place (0.875 m, 17 cells).
        let m = strip(18.0, 0.0, |_, _| false);
        let disc = m.disc(0.875);
        let narrow = strip(12.0, 0.0, |_, _| false);
        // A 0.95 m (19 cells) bed: about 0.9 m measured; a 0.65 m sofa seat less than 0.7.
        let bed = seat_level(&m, 20, 20, &disc);
        let seat = seat_level(&narrow, 20, 20, &disc);
        assert!((bed.width - 0.9).abs() < 0.06, "{bed:?}");
        assert!(seat.width < 0.66 && seat.width > 0.55, "{seat:?}");
        // Along x, elongated enough for a heading; off the surface, nothing.
        assert!(bed
            .along(1.3)
            .is_some_and(|a| a.abs() < 1e-9 || (a - PI).abs() < 1e-9));
        assert_eq!(seat_level(&m, 0, 0, &disc).width, 0.0);
        // Turned 30 degrees, the axis turns with it.
        let turned = seat_level(&strip(18.0, 30.0, |_, _| false), 20, 20, &disc);
        let a = turned.along(1.3).expect("a long axis");
        assert!((a - 30f64.to_radians()).abs() < 0.05, "{}", a.to_degrees());
    }

    #[test]
    fn a_duvets_folds_do_not_cut_the_surface_and_a_back_does() {
        let disc = strip(18.0, 0.0, |_, _| false).disc(0.875);
        // A 0.95 m bed (rows 11-29) along x with two folds along it, 0.08 m high, four
        // rows either side of the place.
        let folded = |back: bool| {
            let bed = strip(18.0, 0.0, |_, _| false);
            map_of(40, move |x, y| {
                let h = bed.get(x as isize, y as isize)?;
                Some(match y {
                    16 | 24 if h > 0.0 => h + 0.08,
                    // A sofa's back, 0.35 m above its seat, from row 25 on.
                    25.. if back && h > 0.0 => h + 0.35,
                    _ => h,
                })
            })
        };
        // Level within 5 cm both ways: the folds cut the bed down to the 7 rows between.
        let cut = seat_level(&folded(false), 20, 20, &disc);
        assert!(cut.width < 0.4, "{cut:?}");
        // Folds up to 0.10 m above the level are on the surface: the bed's whole width.
        let whole = surface(&folded(false), 20, 20, &disc, 0.45, 0.05, 0.10);
        assert!((whole.width - 0.9).abs() < 0.06, "{whole:?}");
        // The last fold at the surface's edge: counted where its shadow hides what lies
        // beyond (rows 25-29 unseen), not where the floor is seen beyond it.
        let edged = |beyond: Option<f64>| {
            let m = folded(false);
            map_of(40, move |x, y| match y {
                25..=29 => beyond,
                _ => m.get(x as isize, y as isize),
            })
        };
        let shadowed = surface(&edged(None), 20, 20, &disc, 0.45, 0.05, 0.10);
        let dropped = surface(&edged(Some(0.0)), 20, 20, &disc, 0.45, 0.05, 0.10);
        assert!(
            shadowed.width > dropped.width + 0.02,
            "{shadowed:?} {dropped:?}"
        );
        // A back 0.35 m high still ends it (rows 11-23 are left, but for the fold).
        let backed = surface(&folded(true), 20, 20, &disc, 0.45, 0.05, 0.10);
        assert!(backed.width < 0.7 && backed.width > 0.5, "{backed:?}");
        // A seat 0.65 m deep (rows 14-26) whose back reclines from row 27 on, rising
        // 3.5 cm a row: its rows 28 and 29 (7 and 10.5 cm up) are crossed, but no seat lies
        // beyond them, so the seat is as wide as with the folds not crossed.
        let seat = strip(12.0, 0.0, |_, _| false);
        let reclined = map_of(40, |x, y| {
            let h = seat.get(x as isize, y as isize)?;
            Some(if y >= 27 {
                0.45 + 0.035 * (y - 26) as f64
            } else {
                h
            })
        });
        let crossing = surface(&reclined, 20, 20, &disc, 0.45, 0.05, 0.10);
        let level = seat_level(&reclined, 20, 20, &disc);
        assert!(
            (crossing.width - level.width).abs() < 1e-9,
            "{crossing:?} {level:?}"
        );
        assert!(crossing.width < 0.7, "{crossing:?}");
    }

    #[test]
    fn holes_do_not_end_the_surface_and_edges_do() {
        let disc = strip(18.0, 0.0, |_, _| false).disc(0.875);
        let whole = seat_level(&strip(18.0, 0.0, |_, _| false), 20, 20, &disc);
        // Every third row of the bed missing (a sparse scan): the same width.
        let holed = strip(18.0, 0.0, |x, y| {
            y % 3 == 0 && x != 20 && (12..29).contains(&y)
        });
        let holed = seat_level(&holed, 20, 20, &disc);
        assert!(
            (holed.width - whole.width).abs() < 0.05,
            "{holed:?} {whole:?}"
        );
        // A square top gives no axis.
        let square = map_of(40, |x, y| {
            Some(if (12..29).contains(&x) && (12..29).contains(&y) {
                0.45
            } else {
                0.0
            })
        });
        assert_eq!(seat_level(&square, 20, 20, &disc).along(1.3), None);
    }

    /// [`rule_`] asking a bed's surface: within half a body, 0.40 H (0.70 m at 1.75 m)
    /// wide, elongated 1.3 times for a heading.
    fn bed_rule() -> HypothesisRule {
        HypothesisRule {
            surface: Some(crate::model::hierarchy::SurfaceRule {
                radius: 0.5,
                tolerance: 0.05,
                rise: None,
                min_width: 0.4,
                elongation: 1.3,
                face: None,
            }),
            ..rule_()
        }
    }

    #[test]
    fn a_narrow_strip_running_out_of_the_scan_is_of_unknown_width() {
        let r = bed_rule();
        // Strips along x (2 m long) at 0.45 m, 0.65 m wide (13 rows): too narrow for the
        // 0.70 m asked at 1.75 m where seen edges bound them. Rows by height.
        let found = |row: fn(usize) -> Option<f64>| {
            hypotheses(
                &map_of(40, |_, y| row(y)),
                &r,
                Orientation::Orthogonal,
                1.75,
            )
            .len()
        };
        // Cut lengthwise by the scan's edge (rows 27-39), the floor seen in front: the
        // width is unknown, as a bed's cut by the image edge.
        assert!(found(|y| Some(if y < 27 { 0.0 } else { 0.45 })) > 0);
        // Rows 21-33, the floor seen past the shadow of its far edge: too narrow.
        assert_eq!(
            found(|y| match y {
                21..=33 => Some(0.45),
                34..=36 => None,
                _ => Some(0.0),
            }),
            0
        );
        // Cut by the scan's edge with a back rising before it (rows 21-26, a sofa's seat
        // with its front cut off): too narrow.
        assert_eq!(
            found(|y| Some(match y {
                27.. => 0.45,
                21.. => 0.85,
                _ => 0.0,
            })),
            0
        );
    }

    /// A seat cut lengthwise by the image edge shows its top only at the cut; one whose
    /// front edge is seen, with the floor in front of it out of view, shows its front face
    /// going down under its last cells, and ends there.
    #[test]
    fn a_face_seen_under_the_last_cells_ends_the_surface() {
        use crate::cloud::PointCloud;
        use crate::method::heightmap::HeightMapConfig;
        // Four points per 5 cm cell along x and y (2 m x 2 m, 40 x 40 cells from a point
        // at the origin): rows 0-26 floor, rows 27-39 a 0.65 m strip at 0.45 m running to
        // the cloud's edge; with `face`, the strip's last row also shows a side face down
        // to 0.20 m, sampled every 2.5 cm.
        let cloud = |face: bool| {
            let mut pts = vec![Point3::origin()];
            for i in 0..160 {
                for j in 0..160 {
                    let (x, y) = (0.00625 + 0.0125 * i as f64, 0.00625 + 0.0125 * j as f64);
                    let z = if j < 27 * 4 { 0.0 } else { 0.45 };
                    pts.push(Point3::new(x, y, z));
                    if face && j >= 39 * 4 {
                        pts.extend((1..=10).map(|k| Point3::new(x, y, 0.45 - 0.025 * k as f64)));
                    }
                }
            }
            HeightMap::from_cloud(&PointCloud::new(pts), &HeightMapConfig::default())
        };
        let rule = |face: Option<f64>| {
            let mut r = bed_rule();
            if let Some(sr) = r.surface.as_mut() {
                sr.face = face;
            }
            r
        };
        let found = |map: &HeightMap, r: &HypothesisRule| {
            hypotheses(map, r, Orientation::Orthogonal, 1.75).len()
        };
        let (top_only, faced) = (cloud(false), cloud(true));
        assert_eq!(top_only.depth(20, 39), Some(0.0));
        assert!((faced.depth(20, 39).unwrap() - 0.25).abs() < 1e-6);
        assert!(
            found(&top_only, &rule(Some(0.2))) > 0,
            "cut by the image edge"
        );
        assert_eq!(found(&faced, &rule(Some(0.2))), 0, "its front seen");
        assert!(found(&faced, &rule(None)) > 0, "no face asked");
        assert!(
            found(&faced, &rule(Some(0.3))) > 0,
            "a face shallower than asked"
        );
    }

    #[test]
    fn a_surface_narrower_than_the_rule_gives_no_hypothesis() {
        let r = bed_rule();
        // Body height 1.75: 0.70 m asked; a 0.95 m strip passes, a 0.65 m one does not.
        let wide = hypotheses(
            &strip(19.0, 0.0, |_, _| false),
            &r,
            Orientation::Orthogonal,
            1.75,
        );
        let narrow = hypotheses(
            &strip(13.0, 0.0, |_, _| false),
            &r,
            Orientation::Orthogonal,
            1.75,
        );
        assert!(!wide.is_empty());
        assert!(narrow.is_empty());
        // The middle of the wide strip is flat: the heading is along the strip.
        let mid = wide
            .iter()
            .find(|h| h.cell == (20, 20))
            .expect("a hypothesis in the middle");
        let yaw = mid
            .heading
            .expect("a heading from the long axis")
            .rem_euclid(PI);
        assert!(yaw.abs() < 1e-6 || (yaw - PI).abs() < 1e-6, "{yaw}");
    }
}
