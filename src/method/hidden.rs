//! Seats hidden behind their backs and arms: the seat of an armchair or a sofa seen from
//! behind, filled under the walls that hide it before the grids are built.
//!
//! A camera behind an armchair, above its back, sees the back and the arms and nothing of
//! the seat between them: the back's shadow covers the seat and the floor beyond it. The
//! height map (section 4.1) has no valid cell there, so no hypothesis, and the scene
//! nothing to sit on; the hole stage ([`crate::method::holes`]) leaves the place empty,
//! since nothing at the seat's level closes round it. What the scan shows is the shape
//! that hides it: walls (a back and one or both arms) 0.5-1.0 m high and thin seen from
//! above, round a concave space the scan never saw. Such a space is filled: a place as
//! wide as a body's hips, inside the convex hull of one component of such walls, with
//! nothing seen within its radius, is filled somewhat below the walls' lowest part, where
//! a seat under such arms is.
//!
//! What decides is the shape of what hides the place, not one more threshold on the
//! hole: a convex thing (a cabinet or a box seen from its corner, a table top) has no
//! hidden space inside its hull; a thick one (a bed's mattress, a table, a counter) is a
//! surface, not walls; higher walls (room walls, shelves, desks with raised back panels)
//! are left out. The body then sits, leans and rests its arms against what the scan did
//! see, as everywhere else ([`crate::method::unfold`]).
//!
//! A chair without arms seen from behind shows less: its back, and beside one end of it
//! the seat's side edge, a strip at seat height running forward from the back, while
//! where the seat is the map holds the floor, seen from behind under the seat. Such strips
//! joined to the walls widen the hull the place is looked for in, and where one is joined
//! and the walls and strips span no more across than a seat, the floor inside counts as
//! unseen too: two walls of a room meeting at a corner span the room. Seen from behind
//! and a little from the side, part of such a seat shows beside its back, too near the
//! floor under the rest for a place clear of everything but the floor: then the places
//! may hold the seat seen (not at their centre), and the rest is filled at its height,
//! where the walls rise above it as a back does.
//!
//! An office chair pushed up to a desk and seen from behind has arms that end at the
//! desk's edge, often at the desk's height: in the map they join the desk's top, and
//! their component is as thick as the top. The surface is then taken out of the
//! component and what is left beside it, if as thin as a chair's rails, is looked at as
//! walls, with its hidden places outside the surface's hull (inside it, a place is a
//! shadow on the surface: a duvet's behind a lump). Such a seat goes on under the desk's
//! top, so a place may also hold cells seen a thigh's room above the seat that are not
//! the walls' own (not at its centre; they are not filled).
//!
//! Seen squarely from behind, a sofa, a bench or a chair shows its back alone: a straight
//! wall, no arm and no seat's edge running forward, with the floor seen up to it on the
//! camera's side and next to nothing on the other, where its seat is. Such a back, as
//! long as a seat is wide (not a room's wall), level, and joined to nothing higher than a
//! wall (not the rest of a room's wall whose top the image's edge cuts aslant, nor a
//! counter's top), hides places on its unseen side within a seat's depth, filled a
//! back's height below its top: a guess at the seat's height, since nothing of the seat
//! shows. Seen a little from above, the floor may show under the seat as well, between
//! its legs; then the back itself tells the seat's side: reclined over its seat, it shows
//! its lower rows beside its top edge on that side.
//!
//! The fill is as for holes ([`crate::method::holes::fill`],
//! [`crate::method::holes::fill_points`]): the cells set in the height map and points
//! added over them to the cloud the scene is built from (not to the segmented points).
//! This is not in the paper.

use std::cell::OnceCell;
use std::collections::HashMap;

use nalgebra::Point3;

use crate::method::heightmap::HeightMap;
use crate::method::holes::{beside, Bits, Hole};
use crate::num::{to_i64, to_isize, to_usize};

/// Which hidden places are filled, and at what height.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HiddenConfig {
    /// Lowest height of a cell that may be a seat's back or arm, metres above the floor.
    pub wall_low: f64,
    /// Highest height of such a cell, metres above the floor.
    pub wall_high: f64,
    /// Half the widest a back or an arm is seen from above, metres: the largest distance,
    /// in steps between side-by-side cells, from a cell of the walls to a cell that is not
    /// one of them, times the cell size.
    pub max_half_width: f64,
    /// Half the widest a back or an arm joined to a surface is seen from above, metres
    /// (as `max_half_width`): walls thicker than that are a surface where a square of
    /// twice `max_half_width` fits in them, and what is left of them beside it is a
    /// seat's walls only where it is this thin.
    pub beside_half_width: f64,
    /// Radius of a hidden place, metres: no cell of the map is seen within it.
    pub clear: f64,
    /// The walls' level is this quantile of their cells' heights (0 the lowest).
    pub level_quantile: f64,
    /// The hidden seat is filled this many metres below the walls' level.
    pub drop: f64,
    /// The highest point the scan saw over a cell of a hidden place, within this many
    /// metres of the walls' middle height (their median), makes the walls the edges of
    /// one surface seen sparsely, not walls round a hidden seat.
    pub surface_tolerance: f64,
    /// Lowest height of a cell that may be a seat's side edge, metres: cells from here
    /// up to `wall_low`, joined to the walls and as thin as they, widen their hull.
    pub edge_low: f64,
    /// Inside walls with a seat's edge joined, a cell whose top is lower than this,
    /// metres (the floor, seen under the seat from behind), counts as unseen.
    pub floor_top: f64,
    /// ... only where the walls and the edges span at most this across, metres (the
    /// shorter side of their box).
    pub max_span: f64,
    /// Where such walls hide no place clear of everything seen but the floor, a place
    /// whose disc also holds the seat's edges (a seat seen in part) is filled at their
    /// height, if the walls' highest tenth (the quantile `1 - level_quantile`, the mirror
    /// of their level) rises at least this many metres above it.
    pub back_rise: f64,
    /// A cell seen between these many metres above the hidden seat's height (inclusive),
    /// not one of the walls, may lie in a hidden place (not at its centre): a top over
    /// the seat. Beside a reclined lone back it may also lie on the seat's side, with
    /// the floor ([`lone_back`]).
    pub under_room: (f64, f64),
    /// A straight wall alone (no arm, no seat's edge running forward from it), between
    /// these many metres long, standing free over the floor seen beside it on one side,
    /// with little seen on the other, is a back seen from behind: its hidden places lie on
    /// the other side, within `lone_depth` metres of its middle line ([`lone_back`]).
    pub lone_length: (f64, f64),
    /// How far from a lone back's middle line its hidden places' centres lie at most,
    /// metres.
    pub lone_depth: f64,
    /// A lone back's seat is filled this many metres below the back's top (the walls'
    /// highest tenth, the quantile `1 - level_quantile`).
    pub lone_drop: f64,
    /// A lone back's top is level: the line fitted to its heights along it (least
    /// squares) rises at most this many metres from one end to the other.
    pub lone_level: f64,
    /// A lone back is at least this many times as long as it is thick (its line, seen
    /// from above).
    pub lone_aspect: f64,
    /// Beside a lone back, the camera's side has at least this share of its cells seen
    /// (all of them the floor) ...
    pub lone_seen: f64,
    /// ... and the seat's side at most this share, where the floor does not show under
    /// the seat.
    pub lone_unseen: f64,
    /// A lone back's top edge: its cells within this many metres of its top.
    pub lone_edge: f64,
    /// With the floor seen on both sides of a lone back, its seat lies on the side its
    /// cells' middle lies at least this many metres from its top edge's (a back reclined
    /// over its seat shows its lower rows there).
    pub lone_fall: f64,
}

impl Default for HiddenConfig {
    fn default() -> Self {
        HiddenConfig {
            // 0.50 m: arms rise to 0.55-0.70 m and backs to 0.70-1.00 m; the highest
            // seats (0.48 m) stay below, so a seat the scan saw is never a wall.
            wall_low: 0.50,
            // 1.00 m: dining chairs' and armchairs' backs end at 0.75-1.00 m; higher, the
            // band takes in desks with raised back panels, shelves and room walls (a
            // real-model desk 1.02 m high seen from behind was sat in with 1.05). High
            // backs and wingbacks (1.1-1.4 m) seen from behind are missed.
            wall_high: 1.00,
            // 0.20 m: a back or an arm seen from above is at most 0.40 m thick (upholstered
            // backs 0.15-0.30 m, 2-3 cells from their edge at 0.05 m); a bed's mattress
            // with its pillows, a table's top or a counter's reach 6-12 cells in.
            max_half_width: 0.20,
            // 0.10 m: an office chair pushed up to a desk, its arms joined to the desk's
            // top (their height) in the map: the back and the arms 0.03-0.10 m thick; a
            // bed's duvet seen between the shadows of its lumps leaves strips 0.2-0.4 m
            // wide beside the flat parts, and 0.20 m added false rests on 8 of 120
            // messy-bed views.
            beside_half_width: 0.10,
            // 0.15 m: about half an adult's hip width (0.30-0.35 m); an unseen gap
            // narrower than a body between walls is a gap, not a seat.
            clear: 0.15,
            // The lowest tenth of the walls: the arms where the back is higher, a few
            // lower cells aside (an arm's sloping front end, noise).
            level_quantile: 0.1,
            // 0.15 m: arms rise 0.15-0.25 m above a seat (the wide mix's wingbacks
            // 0.16-0.24 m, the real-model armchairs about 0.2 m), so the forearm then
            // finds the arm inside the armrest band (0.12-0.35 m above the seat).
            // Measured on the real-model views of seed 3 from 0.10 to 0.25 m: 0.15 gave
            // the most armrests, the same seats from 0.10 to 0.18 m.
            drop: 0.15,
            // 0.05 m: a top's height varies 1-3 cm, a duvet's folds up to 5 (as the holes'
            // rim tolerance); a seat's own points, seen through a gap, lie 0.15-0.25 m
            // below its arms and further below its back, and a back leaning over the seat
            // far above the arms.
            surface_tolerance: 0.05,
            // 0.30 m: seats are 0.35-0.50 m high (their side edge seen a little lower
            // where the cushion is rounded); below, a rail or a stretcher between the legs.
            edge_low: 0.30,
            // 0.10 m: the floor, a rug or a chair's star base seen under the seat; a seat
            // is 0.35 m high and more.
            floor_top: 0.10,
            // 1.00 m: a chair, an armchair or a sofa seen from behind spans 0.45-0.95 m
            // from its back to its seat's front edge; two walls of a room meeting at a
            // corner span the room (a wide-mix room scan was lain on along its walls with
            // no bound, and along a 0.6 m band with places kept within 0.6 m of the walls).
            max_span: 1.00,
            // 0.20 m: a back holds the trunk at the lumbar spine or above, 0.15-0.25 m over
            // the seat, and chairs' backs rise 0.30-0.55 m over it; a night stand's top
            // stands 0.05-0.10 m over its side seen at seat height (two wide-mix night
            // stands were sat in without this).
            back_rise: 0.20,
            // 0.20-0.40 m: a desk's or a table's top over a chair pushed up to it stands
            // 0.20-0.35 m above the seat (room for the thighs; the walls' own arms stand
            // `drop`, 0.15 m, above it and are walls anyway); a shelf's board higher over
            // the place is no top a seated body's thighs go under.
            under_room: (0.20, 0.40),
            // 0.35-2.50 m: a chair's back is 0.35-0.50 m wide, a three-seat sofa's
            // 2.0-2.5 m; a room's wall seen no higher than a back (the image's top edge
            // cutting it) runs on for metres.
            lone_length: (0.35, 2.50),
            // 0.40 m: a seat is 0.40-0.60 m deep from its back; the places' discs
            // (`clear`) reach 0.15 m further.
            lone_depth: 0.40,
            // 0.40 m: a back's top stands 0.35-0.50 m above its seat (dining chairs and
            // benches 0.35-0.45, sofas 0.40-0.50); nothing of the seat shows to say more.
            lone_drop: 0.40,
            // 0.10 m: a back's top is level, its rounded ends or arms lower at both ends
            // alike; a room's wall whose top the image's edge cuts aslant rises along it
            // through the walls' band (0.2-0.5 m over a sofa's length).
            lone_level: 0.10,
            // 2: a back's line is long and thin (a chair's 0.35-0.50 m long, 0.03-0.15 m
            // thick); a bar stool's seat or a post seen from above is as thick as long.
            lone_aspect: 2.0,
            // Half: the floor seen up to the back on the camera's side, bar the back's
            // own shadow and the image's edge.
            lone_seen: 0.5,
            // A quarter: the seat's side hidden by the back, bar a few cells of the
            // floor seen past its ends or through a gap.
            lone_unseen: 0.25,
            // 0.10 m: a back's top edge, seen from above; a back reclined 5-15 degrees
            // shows its rows 0.05 m nearer the seat 0.2-0.6 m lower.
            lone_edge: 0.10,
            // 0.05 m, one cell: a back reclined 5-15 degrees over 0.3-0.5 m of height
            // leans 0.03-0.13 m; a partition or a room's wall stands upright.
            lone_fall: 0.05,
        }
    }
}

/// The seats hidden inside walls of `map` that `cfg` fills: per component of wall cells
/// (cells between `wall_low` and `wall_high`, joined through sides and corners) that is
/// thin, the hidden places inside its convex hull (cells the scan did not see, with
/// none seen within `clear`, and over none of which the highest point of `seen` lies at
/// the walls' middle height, give or take `surface_tolerance`), each grown to the disc of
/// radius `clear` round it, at the walls' level less `drop`. With a seat's edges joined
/// and a span of at most `max_span`, the floor counts as unseen; and where that still
/// leaves no place, places may also hold the edges (not at their centre), their floor and
/// unseen cells filled at the edges' median height if the walls' highest tenth rises
/// `back_rise` above it (a seat seen in part beside its back). Walls that are one straight
/// back alone hide their places on the side the scan did not see, or, with the floor seen
/// on both sides (on the seat's side also a top over it, `under_room`), on the side the
/// back leans towards ([`lone_back`]), filled `lone_drop` below the walls' highest tenth.
/// `seen` is every point the scan saw, world frame: also the specks left out of the map,
/// so that a sparse top seen at a grazing angle, whose scattered points are specks, is
/// not taken for a space the scan never saw. Components are taken in the order of
/// [`HeightMap::cells_at_least`]; a cell two of them would fill goes to the first, so the
/// answer is deterministic. Run on the map with its holes filled.
pub fn hidden_seats(map: &HeightMap, seen: &[Point3<f64>], cfg: &HiddenConfig) -> Vec<Hole> {
    let is_wall = |h: f64| (cfg.wall_low..=cfg.wall_high).contains(&h);
    let radius = cells(map, cfg.clear);
    let deepest = to_usize((cfg.max_half_width / map.cell + 1e-9).floor());
    let mut walls = Bits::new(map);
    let mut scratch = Bits::new(map);
    let mut candidates: Vec<Candidate> = Vec::new();
    for start in map.cells_at_least(cfg.wall_low) {
        if walls.get(start) || !height(map, start).is_some_and(is_wall) {
            continue;
        }
        let comp = component(map, start, &is_wall, &mut walls);
        let (parts, surface) = thin_parts(comp, deepest, cells(map, cfg.beside_half_width));
        // A place inside the surface's hull is a shadow on it (a bed's duvet behind a
        // lump), not a seat beside it.
        let beside_surface = |c: &(usize, usize)| surface.as_ref().is_none_or(|h| !h.contains(*c));
        for comp in parts {
            candidates.extend(candidate(
                map,
                &comp,
                cfg,
                (radius, deepest),
                &beside_surface,
                &mut scratch,
            ));
        }
    }
    if candidates.is_empty() {
        return Vec::new();
    }
    // The highest point of `seen` over each cell of the candidates' discs.
    let mut near = Bits::new(map);
    for cand in &candidates {
        for &c in &cand.centres {
            for n in disc(map, c, radius) {
                near.set(n, true);
            }
        }
    }
    let mut top: HashMap<(usize, usize), f64> = HashMap::new();
    for p in seen {
        let ix = to_isize(((p.x - map.x0) / map.cell).floor());
        let iy = to_isize(((p.y - map.y0) / map.cell).floor());
        let (Ok(x), Ok(y)) = (usize::try_from(ix), usize::try_from(iy)) else {
            continue;
        };
        if x < map.nx && y < map.ny && near.get((x, y)) {
            let t = top.entry((x, y)).or_insert(p.z);
            *t = t.max(p.z);
        }
    }
    let mut taken = Bits::new(map);
    let mut out = Vec::new();
    for Candidate {
        centres,
        open,
        level,
        middle,
    } in candidates
    {
        // A point seen at the walls' middle height over a cell of a place makes the walls
        // the edges of one surface seen sparsely; not over a top (`over`), nor over a
        // cell where the map kept the seat at the place's level: the map keeps a lower
        // layer only under a gap a thigh fits in, so the point is a top over the seat (a
        // desk's top over a chair pushed under it).
        let seat = |n: (usize, usize)| {
            height(map, n).is_some_and(|h| (h - level).abs() <= cfg.surface_tolerance)
        };
        let surface = |n: (usize, usize)| {
            !open.is_over(map, n)
                && !seat(n)
                && top
                    .get(&n)
                    .is_some_and(|&z| (z - middle).abs() <= cfg.surface_tolerance)
        };
        let mut cells = Vec::new();
        for c in centres {
            if disc(map, c, radius).any(surface) {
                continue;
            }
            // The seat's edges the place holds were seen: they stay as they are.
            for n in disc(map, c, radius).filter(|&n| open.centre(map, n)) {
                if !taken.get(n) {
                    taken.set(n, true);
                    cells.push(n);
                }
            }
        }
        if !cells.is_empty() {
            cells.sort_unstable_by_key(|&(x, y)| (y, x));
            out.push(Hole {
                cells,
                height: level,
            });
        }
    }
    out
}

/// `len` metres in whole cells of `map`, rounded up; the small offset keeps 0.15 / 0.05 at
/// 3, not 4.
fn cells(map: &HeightMap, len: f64) -> usize {
    to_usize((len / map.cell - 1e-9).ceil())
}

/// The hidden places of one thin wall component `comp` of `map` (see [`hidden_seats`]),
/// those that `beside` keeps, and the seat's height there; `None` where it hides none.
/// `radius` and `deepest` are `cfg.clear` and `cfg.max_half_width` in cells. `scratch` is
/// scratch space, all clear on entry and on return.
fn candidate(
    map: &HeightMap,
    comp: &[(usize, usize)],
    cfg: &HiddenConfig,
    (radius, deepest): (usize, usize),
    beside: &impl Fn(&(usize, usize)) -> bool,
    scratch: &mut Bits,
) -> Option<Candidate> {
    // A seat's side edges joined to the walls widen the place they hold; where they
    // show a seat no wider across than one, the floor under it counts as unseen.
    let edges = seat_edges(map, comp, cfg, deepest, scratch);
    // No edge joined, and no seat the scan saw (`None`).
    let no_edge = edges.as_ref().is_some_and(Vec::is_empty);
    let edges = edges.unwrap_or_default();
    let mut shape = comp.to_vec();
    shape.extend_from_slice(&edges);
    let outline = Bounds::of(&shape);
    // The walls' heights, sorted only where a quantile is asked.
    let heights = OnceCell::new();
    let quantile = |q: f64| {
        let h: &Vec<f64> = heights.get_or_init(|| sorted_heights(map, comp));
        h[to_usize((q * (h.len() - 1) as f64).round())]
    };
    // With no seat's edge seen, walls that are a back and an arm running forward
    // from it (the other arm hidden) show the seat between them: an L's hull is
    // completed to the parallelogram of its legs, and the floor seen there counts as
    // seen under the seat, as where a seat's edge shows it. A ring or a corner of
    // one height (a bin, a bath, two low walls) has no back rising over an arm;
    // beside a seat the scan saw, the walls hide no other.
    let arm = no_edge && {
        let back = quantile(cfg.level_quantile) - cfg.drop + cfg.back_rise;
        back_and_arm(map, comp, back, radius, scratch)
    };
    // Cells on one line have no hull: only a lone back (below) may hide a place then.
    let mut hull = Hull::of(&shape);
    if let Some(l) = hull
        .as_ref()
        .filter(|_| arm)
        .and_then(|h| h.completed(comp, deepest + 1))
    {
        hull = Some(l);
    }
    let across = (outline.x1 - outline.x0 + 1).min(outline.y1 - outline.y0 + 1);
    let floor_top = ((!edges.is_empty() || arm) && across as f64 * map.cell <= cfg.max_span + 1e-9)
        .then_some(cfg.floor_top);
    let mut level = quantile(cfg.level_quantile) - cfg.drop;
    // A top over a seat at `seat` metres hides it as the walls' shadow does.
    let over = |seat: f64| Some((seat + cfg.under_room.0, seat + cfg.under_room.1));
    let strict = Open {
        floor_top,
        edges: None,
        over: over(level),
    };
    for &c in comp {
        scratch.set(c, true);
    }
    let places = |open: Open, scratch: &Bits| {
        hull.as_ref().map_or_else(Vec::new, |h| {
            hidden_centres(map, &h.bounds(map), h, radius, open, scratch)
        })
    };
    let mut centres = places(strict, scratch);
    centres.retain(beside);
    let mut open = strict;
    // No such place, but the seat seen in part beside one: the places may hold the
    // seat's edges too (not at their centre), and the seat is at the edges' height.
    if centres.is_empty() && floor_top.is_some() && !edges.is_empty() {
        let seat = sorted_heights(map, &edges);
        let seat = seat[seat.len() / 2];
        if quantile(1.0 - cfg.level_quantile) - seat >= cfg.back_rise - 1e-9 {
            open.edges = Some((cfg.edge_low, cfg.wall_low));
            open.over = over(seat);
            centres = places(open, scratch);
            centres.retain(beside);
            level = seat;
        }
    }
    // No such place, and the walls are one straight back alone, the floor seen beside
    // it on one side only (the seat is on the other side, below the back), or on both
    // (the seat is on the side the back reclines towards).
    if centres.is_empty() && !arm {
        let top = quantile(1.0 - cfg.level_quantile);
        let seat = top - cfg.lone_drop;
        if let Some((lone, under)) = lone_back(
            map,
            &shape,
            hull.as_ref(),
            (top, over(seat)),
            cfg,
            (radius, deepest),
        ) {
            open = Open {
                floor_top: under.then_some(cfg.floor_top),
                edges: None,
                over: over(seat),
            };
            centres = hidden_centres(map, &lone.bounds(map), &lone, radius, open, scratch);
            centres.retain(beside);
            level = seat;
        }
    }
    for &c in comp {
        scratch.set(c, false);
    }
    if centres.is_empty() {
        return None;
    }
    Some(Candidate {
        centres,
        open,
        level,
        middle: quantile(0.5),
    })
}

/// The rectangle in which the walls `comp` of `map` (with any seat's edges joined) hide a
/// seat as a back alone, if they are one: cells all within `deepest + 1` of the segment
/// between the two farthest, that segment `cfg.lone_length` long and at least twice as
/// long as they are thick, the least-squares line of the walls' heights along it rising
/// at most `cfg.lone_level`, no cell higher than `cfg.wall_high` joined, and beside them
/// (out to `radius` cells from them, along the segment) the cells on one side at least
/// half seen, every seen one lower than `cfg.floor_top` (the floor behind a back, seen
/// from behind it), and on the other at most a quarter seen. Or, with the floor and
/// nothing else seen on both sides (at least half seen on one), the back leaning
/// towards the other, where a top over the seat may also be seen (between
/// `cfg.under_room` over the seat `cfg.lone_drop` below the back's top: a desk the chair
/// is pushed under): its cells at least `cfg.edge_low` high and more than
/// `cfg.lone_edge` below its top (the walls' highest tenth) lie on average at least
/// `cfg.lone_fall` nearer that side
/// than its top edge (the walls within `cfg.lone_edge` of the top), and the top stands at
/// least `cfg.lone_drop` over `cfg.edge_low`; then the segment may also be the top
/// edge's own, where the cells are too thick for a line (a reclined back seen from
/// above), and the floor in the rectangle counts as unseen (the second value). The
/// rectangle runs along the segment from its line to `cfg.lone_depth` on that other
/// side, and lies inside the map. `hull` is the cells' convex hull (`None` on a line),
/// `top` the walls' highest tenth (metres) and `over` the heights of a top over the seat
/// `lone_drop` below it (as the places allow, [`Open`]); `radius` and `deepest` are
/// `cfg.clear` and `cfg.max_half_width` in cells.
fn lone_back(
    map: &HeightMap,
    comp: &[(usize, usize)],
    hull: Option<&Hull>,
    (top, over): (f64, Option<(f64, f64)>),
    cfg: &HiddenConfig,
    (radius, deepest): (usize, usize),
) -> Option<(Hull, bool)> {
    let pts: Vec<(i64, i64)> = comp.iter().map(|&(x, y)| (x as i64, y as i64)).collect();
    // Its top edge, the walls within `lone_edge` of the top, and the cells below that
    // (its lower rows, or a seat's edges joined): seen from above, a back reclined over
    // its seat shows its lower rows beside its top edge, on the seat's side.
    let rows = |keep: &dyn Fn(f64) -> bool| -> Vec<(i64, i64)> {
        comp.iter()
            .filter(|&&c| height(map, c).is_some_and(|h| h >= cfg.edge_low && keep(h)))
            .map(|&(x, y)| (x as i64, y as i64))
            .collect()
    };
    let edge = rows(&|h| h >= top - cfg.lone_edge);
    let lower = rows(&|h| h < top - cfg.lone_edge);
    if edge.is_empty() {
        return None;
    }
    let thick = (deepest + 1) as f64;
    // A back is a line: every cell within `deepest + 1` cells of the segment between the
    // line's two farthest cells, `lone_length` long and at least twice as long as the
    // line is thick (not a stool's seat or a post seen from above). The line is all the
    // cells, or else the top edge alone: a reclined back, whose seat is then looked for
    // only on the side it leans towards (below).
    let fits = |l: &Line, cells: &[(i64, i64)]| {
        let (lo, hi) = cfg.lone_length;
        let (t0, t1) = l.across(&pts);
        let (e0, e1) = l.across(cells);
        (lo / map.cell - 1e-9..=hi / map.cell + 1e-9).contains(&l.length)
            && l.length >= 1.0
            && t1 - t0 <= 2.0 * thick + 1e-9
            && cfg.lone_aspect * (e1 - e0 + 1.0) <= l.length + 1e-9
    };
    let whole = Line::of(hull.map_or(&pts, |h| &h.0));
    let (line, straight) = if fits(&whole, &pts) {
        (whole, true)
    } else {
        let top_edge = Line::of(&edge);
        if !fits(&top_edge, &edge) {
            return None;
        }
        (top_edge, false)
    };
    let (a, b, length, n) = (line.a, line.b, line.length, line.n);
    // A back stands free: nothing higher than a wall joins it (the rest of a room's wall
    // whose top the image's edge cuts aslant, a counter's top).
    let higher = |c: &(usize, usize)| {
        (-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                beside(map, *c, (dx, dy))
                    .and_then(|n| height(map, n))
                    .is_some_and(|h| h > cfg.wall_high)
            })
        })
    };
    if comp.iter().any(higher) {
        return None;
    }
    // How far the walls reach from the line on either side.
    let (t0, t1) = line.across(&pts);
    // The top's rise from one end to the other: the least-squares line of the walls'
    // heights over their places along the back.
    let walls: Vec<(f64, f64)> = comp
        .iter()
        .filter_map(|&c| {
            height(map, c)
                .filter(|&h| h >= cfg.wall_low)
                .map(|h| (c, h))
        })
        .map(|((x, y), h)| (line.at((x as i64, y as i64)).0, h))
        .collect();
    let k = walls.len().max(1) as f64;
    let (ms, mh) = walls
        .iter()
        .fold((0.0, 0.0), |(a, b), &(s, h)| (a + s / k, b + h / k));
    let (sh, ss) = walls.iter().fold((0.0, 0.0), |(a, b), &(s, h)| {
        (a + (s - ms) * (h - mh), b + (s - ms) * (s - ms))
    });
    if ss <= 0.0 || (sh / ss).abs() * length > cfg.lone_level + 1e-9 {
        return None;
    }
    // A top over the seat (a desk the chair is pushed under), as the places allow it.
    let is_over = |h: f64| over.is_some_and(|(lo, hi)| (lo - 1e-9..=hi + 1e-9).contains(&h));
    // Beside the walls along their length: per side, cells looked at, seen, seen low,
    // seen as a top over the seat.
    let mut sides = [(0usize, 0usize, 0usize, 0usize); 2];
    let r = radius as f64;
    let span = to_i64((t1.max(-t0) + r).ceil()) + 1;
    let (x0, x1) = (a.0.min(b.0) - span, a.0.max(b.0) + span);
    let (y0, y1) = (a.1.min(b.1) - span, a.1.max(b.1) + span);
    for y in y0.max(0)..=y1.min(map.ny as i64 - 1) {
        for x in x0.max(0)..=x1.min(map.nx as i64 - 1) {
            let (s, t) = line.at((x, y));
            if !(0.0..=length).contains(&s)
                || !(t0 - r..=t1 + r).contains(&t)
                || (t0..=t1).contains(&t)
            {
                continue;
            }
            let side = &mut sides[usize::from(t > 0.0)];
            side.0 += 1;
            let (Ok(cx), Ok(cy)) = (usize::try_from(x), usize::try_from(y)) else {
                continue;
            };
            if let Some(h) = height(map, (cx, cy)) {
                side.1 += 1;
                side.2 += usize::from(h < cfg.floor_top);
                side.3 += usize::from(is_over(h));
            }
        }
    }
    // The camera's side: at least half seen, all of it the floor; the seat's: at most a
    // quarter seen. Or the floor seen on both sides (under the seat too, between its
    // legs; on the seat's side also a top over the seat), and the back reclined towards
    // the seat's side: its lower rows' middle lies at least `lone_fall` from its top
    // edge's, towards the seat.
    type Side = (usize, usize, usize, usize);
    let seen_low =
        |(all, seen, low, _): Side| seen as f64 >= cfg.lone_seen * all as f64 && low == seen;
    let unseen = |(all, seen, _, _): Side| all > 0 && seen as f64 <= cfg.lone_unseen * all as f64;
    let floor_or_over = |(_, seen, low, over): Side| low + over == seen;
    let middle = |cells: &[(i64, i64)]| {
        cells.iter().map(|&c| line.at(c).1).sum::<f64>() / cells.len().max(1) as f64
    };
    let fall = middle(&lower) - middle(&edge);
    let leans =
        fall.abs() * map.cell >= cfg.lone_fall - 1e-9 && top - cfg.lone_drop >= cfg.edge_low;
    let (sign, under) = match sides {
        [front, back] if straight && unseen(back) && seen_low(front) => (1.0, false),
        [front, back] if straight && unseen(front) && seen_low(back) => (-1.0, false),
        [front, back] if leans && floor_or_over(front) && floor_or_over(back) => {
            let sign = fall.signum();
            let camera = if sign > 0.0 { front } else { back };
            if !seen_low(camera) {
                return None;
            }
            (sign, true)
        }
        _ => return None,
    };
    let depth = sign * cfg.lone_depth / map.cell;
    let far = |p: (i64, i64)| {
        (
            to_i64((p.0 as f64 + depth * n.0).round()),
            to_i64((p.1 as f64 + depth * n.1).round()),
        )
    };
    // The seat lies inside what the scan covers (a shadow with the scan going on past
    // it), not beyond the map's border.
    let inside =
        |(x, y): (i64, i64)| (0..map.nx as i64).contains(&x) && (0..map.ny as i64).contains(&y);
    let (fa, fb) = (far(a), far(b));
    if !(inside(fa) && inside(fb)) {
        return None;
    }
    Hull::of_points(vec![a, b, fa, fb]).map(|h| (h, under))
}

/// The segment between the two farthest of some cells, as a frame: along it from `a`
/// (`u`) and across it (`n`), in cells.
#[derive(Debug, Clone, Copy)]
struct Line {
    a: (i64, i64),
    b: (i64, i64),
    length: f64,
    u: (f64, f64),
    n: (f64, f64),
}

impl Line {
    /// The line of `pts` (not empty).
    fn of(pts: &[(i64, i64)]) -> Line {
        let (d2, (a, b)) = farthest_pair(pts);
        let length = (d2 as f64).sqrt();
        let u = if length > 0.0 {
            ((b.0 - a.0) as f64 / length, (b.1 - a.1) as f64 / length)
        } else {
            (1.0, 0.0)
        };
        Line {
            a,
            b,
            length,
            u,
            n: (-u.1, u.0),
        }
    }

    /// Where cell `c` lies along the line from `a` and across it, cells.
    fn at(&self, c: (i64, i64)) -> (f64, f64) {
        let (ex, ey) = ((c.0 - self.a.0) as f64, (c.1 - self.a.1) as f64);
        (ex * self.u.0 + ey * self.u.1, ex * self.n.0 + ey * self.n.1)
    }

    /// The least and the most of `cells` across the line, cells.
    fn across(&self, cells: &[(i64, i64)]) -> (f64, f64) {
        cells.iter().fold((0.0f64, 0.0f64), |(t0, t1), &c| {
            let t = self.at(c).1;
            (t0.min(t), t1.max(t))
        })
    }
}

/// The hidden places of one thin wall component, before the points seen in them are
/// looked at.
struct Candidate {
    /// The places' centres, row by row.
    centres: Vec<(usize, usize)>,
    /// Which seen cells the places may hold.
    open: Open,
    /// The seat's height, metres: the walls' level less `drop`, or the height of the
    /// seat's edges the places hold.
    level: f64,
    /// The walls' middle height (their median), metres.
    middle: f64,
}

/// The cells of `map` within `radius` cells of `c` (centre to centre), row by row.
fn disc(
    map: &HeightMap,
    c: (usize, usize),
    radius: usize,
) -> impl Iterator<Item = (usize, usize)> + '_ {
    let r = radius as isize;
    (-r..=r)
        .flat_map(move |dy| (-r..=r).map(move |dx| (dx, dy)))
        .filter(move |&(dx, dy)| dx * dx + dy * dy <= r * r)
        .filter_map(move |d| beside(map, c, d))
}

/// The heights of the seen cells among `cells`, ascending (not empty for the cells of a
/// component, which are seen).
fn sorted_heights(map: &HeightMap, cells: &[(usize, usize)]) -> Vec<f64> {
    let mut h: Vec<f64> = cells.iter().filter_map(|&c| height(map, c)).collect();
    h.sort_by(f64::total_cmp);
    h
}

/// Which cells of the map a hidden place may hold.
#[derive(Debug, Clone, Copy)]
struct Open {
    /// Cells whose top is lower than this, metres (the floor seen under a seat), count as
    /// unseen.
    floor_top: Option<f64>,
    /// Cells between these heights, metres (low inclusive; a seat's edges, seen), may lie
    /// in a place, though not at its centre.
    edges: Option<(f64, f64)>,
    /// Cells seen between these heights, metres, other than the walls' own, may lie in a
    /// place, though not at its centre: a top over the seat (a desk's a chair is pushed
    /// up to) hides it as the walls' shadow does.
    over: Option<(f64, f64)>,
}

impl Open {
    /// Whether cell `c` counts as unseen: a place may be centred on it, and is filled there.
    fn centre(&self, map: &HeightMap, c: (usize, usize)) -> bool {
        match (height(map, c), self.floor_top) {
            (None, _) => true,
            (Some(h), Some(top)) => h < top,
            (Some(_), None) => false,
        }
    }

    /// Whether cell `c` may lie in a place; `walls` marks the walls' own cells.
    fn held(&self, map: &HeightMap, c: (usize, usize), walls: &Bits) -> bool {
        self.centre(map, c)
            || self
                .edges
                .is_some_and(|(lo, hi)| height(map, c).is_some_and(|h| (lo..hi).contains(&h)))
            || self.is_over(map, c) && !walls.get(c)
    }

    /// Whether cell `c` is seen between the heights of `over` (inclusive).
    fn is_over(&self, map: &HeightMap, c: (usize, usize)) -> bool {
        self.over.is_some_and(|(lo, hi)| {
            height(map, c).is_some_and(|h| (lo - 1e-9..=hi + 1e-9).contains(&h))
        })
    }
}

/// The height of cell `(x, y)`, if the scan saw it.
fn height(map: &HeightMap, (x, y): (usize, usize)) -> Option<f64> {
    map.get(x as isize, y as isize)
}

/// The cells of `map` between `cfg.edge_low` and `cfg.wall_low` joined to the wall
/// component `comp` through sides and corners (seat edges, and what joins them at their
/// height), if they are no thicker than `deepest` cells from their edge (see
/// [`half_width`]); `None` where they are thicker (a seat the scan saw, a low table).
/// `marks` is scratch space, all clear on entry and on return.
fn seat_edges(
    map: &HeightMap,
    comp: &[(usize, usize)],
    cfg: &HiddenConfig,
    deepest: usize,
    marks: &mut Bits,
) -> Option<Vec<(usize, usize)>> {
    let is_edge = |h: f64| (cfg.edge_low..cfg.wall_low).contains(&h);
    let mut edges = Vec::new();
    for &c in comp {
        for n in (-1..=1).flat_map(|dy| (-1..=1).filter_map(move |dx| beside(map, c, (dx, dy)))) {
            if !marks.get(n) && height(map, n).is_some_and(is_edge) {
                edges.extend(component(map, n, &is_edge, marks));
            }
        }
    }
    for &e in &edges {
        marks.set(e, false);
    }
    if !edges.is_empty() && half_width(&edges, &Bounds::of(&edges)) > deepest {
        return None;
    }
    Some(edges)
}

/// Whether the wall component `comp` is a back and an arm: some of its cells rise to
/// `back` metres or more (the back), and some lower cell (the arm) lies at least twice
/// `radius` cells (a place's width, a seat's least depth) from every one of them: an arm
/// running forward from the back, not a rail along it. Each lower cell looks only at the
/// disc of that radius round it (work in proportion to the component's size); `marks` is
/// scratch space, all clear on entry and on return.
fn back_and_arm(
    map: &HeightMap,
    comp: &[(usize, usize)],
    back: f64,
    radius: usize,
    marks: &mut Bits,
) -> bool {
    let high: Vec<(usize, usize)> = comp
        .iter()
        .copied()
        .filter(|&c| height(map, c).is_some_and(|h| h >= back - 1e-9))
        .collect();
    if high.is_empty() {
        return false;
    }
    for &c in &high {
        marks.set(c, true);
    }
    let reach = 2 * radius as isize;
    let near_back = |c: (usize, usize)| {
        (-reach..=reach).any(|dy| {
            (-reach..=reach).any(|dx| {
                dx * dx + dy * dy < reach * reach
                    && beside(map, c, (dx, dy)).is_some_and(|n| marks.get(n))
            })
        })
    };
    let arm = comp.iter().any(|&c| !marks.get(c) && !near_back(c));
    for &c in &high {
        marks.set(c, false);
    }
    arm
}

/// The wall cells joined to `start` through sides and corners, marked in `walls`.
fn component(
    map: &HeightMap,
    start: (usize, usize),
    is_wall: &impl Fn(f64) -> bool,
    walls: &mut Bits,
) -> Vec<(usize, usize)> {
    let mut comp = vec![start];
    walls.set(start, true);
    let mut next = 0;
    while next < comp.len() {
        let c = comp[next];
        next += 1;
        for dy in -1..=1 {
            for dx in -1..=1 {
                let Some(n) = beside(map, c, (dx, dy)) else {
                    continue;
                };
                if !walls.get(n) && height(map, n).is_some_and(is_wall) {
                    walls.set(n, true);
                    comp.push(n);
                }
            }
        }
    }
    comp
}

/// The cells' bounding box, inclusive.
struct Bounds {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

impl Bounds {
    /// The bounding box of `cells` (not empty).
    fn of(cells: &[(usize, usize)]) -> Bounds {
        let mut b = Bounds {
            x0: usize::MAX,
            x1: 0,
            y0: usize::MAX,
            y1: 0,
        };
        for &(x, y) in cells {
            (b.x0, b.x1, b.y0, b.y1) = (b.x0.min(x), b.x1.max(x), b.y0.min(y), b.y1.max(y));
        }
        b
    }
}

/// The largest distance, in steps between side-by-side cells, from a cell of `comp` to a
/// cell not in it (1 at its edge): half the width of the widest part, in cells. Two
/// passes of the city-block distance transform over the component's box with a border.
fn half_width(comp: &[(usize, usize)], b: &Bounds) -> usize {
    let (inside, w) = box_grid(comp, b);
    distance_transform(&inside, w, false)
        .into_iter()
        .max()
        .unwrap_or(0)
}

/// The thin parts of the wall component `comp`, and the hull of the surface they were
/// joined to. Where `comp` is thin (at most `deepest` cells from its edge, see
/// [`half_width`]) it is its one part, with no surface. Else the surface is every square
/// of `2 deepest + 1` cells that fits inside it (a desk's top an office chair's arms are
/// joined to, a bed's mattress, a table), and the parts what is left, joined through
/// sides and corners, in the order of `comp`, those at most `thin` cells from their edge.
/// A rectangular surface leaves nothing, a round or ragged one slivers of its edge.
fn thin_parts(
    comp: Vec<(usize, usize)>,
    deepest: usize,
    thin: usize,
) -> (Vec<Vec<(usize, usize)>>, Option<Hull>) {
    let b = Bounds::of(&comp);
    let (inside, w) = box_grid(&comp, &b);
    if distance_transform(&inside, w, false)
        .into_iter()
        .max()
        .unwrap_or(0)
        <= deepest
    {
        return (vec![comp], None);
    }
    let at = |(x, y): (usize, usize)| (y - b.y0 + 1) * w + (x - b.x0 + 1);
    let round = |k: usize| {
        [
            k - w - 1,
            k - w,
            k - w + 1,
            k - 1,
            k + 1,
            k + w - 1,
            k + w,
            k + w + 1,
        ]
    };
    // Steps through sides and corners from the nearest cell a square's centre fits on
    // (its chessboard distance to the outside over `deepest`), up to `deepest`.
    let squares = distance_transform(&inside, w, true);
    let mut from_centre = vec![usize::MAX; inside.len()];
    let mut queue: Vec<usize> = Vec::new();
    for &c in &comp {
        if squares[at(c)] > deepest {
            from_centre[at(c)] = 0;
            queue.push(at(c));
        }
    }
    let mut next = 0;
    while next < queue.len() {
        let k = queue[next];
        next += 1;
        if from_centre[k] == deepest {
            continue;
        }
        for n in round(k) {
            if inside[n] && from_centre[n] == usize::MAX {
                from_centre[n] = from_centre[k] + 1;
                queue.push(n);
            }
        }
    }
    let mut left: Vec<bool> = inside
        .iter()
        .zip(&from_centre)
        .map(|(&i, &f)| i && f == usize::MAX)
        .collect();
    let surface: Vec<(usize, usize)> = comp.iter().copied().filter(|&c| !left[at(c)]).collect();
    let mut parts = Vec::new();
    for &c in &comp {
        if !left[at(c)] {
            continue;
        }
        left[at(c)] = false;
        let mut part = vec![at(c)];
        let mut next = 0;
        while next < part.len() {
            for n in round(part[next]) {
                if left[n] {
                    left[n] = false;
                    part.push(n);
                }
            }
            next += 1;
        }
        let part: Vec<(usize, usize)> = part
            .into_iter()
            .map(|k| (k % w + b.x0 - 1, k / w + b.y0 - 1))
            .collect();
        if half_width(&part, &Bounds::of(&part)) <= thin {
            parts.push(part);
        }
    }
    if parts.is_empty() {
        return (parts, None);
    }
    (parts, Hull::of(&surface))
}

/// `cells` set in their box `b` with a border of one clear cell, row by row, and the row
/// length.
fn box_grid(cells: &[(usize, usize)], b: &Bounds) -> (Vec<bool>, usize) {
    let w = b.x1 - b.x0 + 3;
    let mut inside = vec![false; w * (b.y1 - b.y0 + 3)];
    for &(x, y) in cells {
        inside[(y - b.y0 + 1) * w + (x - b.x0 + 1)] = true;
    }
    (inside, w)
}

/// The distance transform of the cells set in `inside` (rows of `w` cells whose border
/// row and column are clear): steps to the nearest clear cell through sides (city block)
/// or, with `corners`, through sides and corners (chessboard); 0 on clear cells, 1 at
/// the edge. Two passes.
fn distance_transform(inside: &[bool], w: usize, corners: bool) -> Vec<usize> {
    let h = inside.len() / w;
    let mut d: Vec<usize> = inside
        .iter()
        .map(|&i| if i { usize::MAX / 2 } else { 0 })
        .collect();
    for j in 1..h - 1 {
        for i in 1..w - 1 {
            let k = j * w + i;
            if d[k] > 0 {
                let mut m = d[k - 1].min(d[k - w]);
                if corners {
                    m = m.min(d[k - w - 1]).min(d[k - w + 1]);
                }
                d[k] = d[k].min(m + 1);
            }
        }
    }
    for j in (1..h - 1).rev() {
        for i in (1..w - 1).rev() {
            let k = j * w + i;
            if d[k] > 0 {
                let mut m = d[k + 1].min(d[k + w]);
                if corners {
                    m = m.min(d[k + w + 1]).min(d[k + w - 1]);
                }
                d[k] = d[k].min(m + 1);
            }
        }
    }
    d
}

/// The convex hull of cell centres, counter-clockwise, in cell units.
struct Hull(Vec<(i64, i64)>);

/// A cell's centre, in cell units.
type Point = (i64, i64);

/// The two points of `v` (not empty) farthest apart, the first such pair in order, and
/// their squared distance.
fn farthest_pair(v: &[Point]) -> (i64, (Point, Point)) {
    let mut best = (-1, (v[0], v[0]));
    for (i, &a) in v.iter().enumerate() {
        for &b in &v[i + 1..] {
            let d = (a.0 - b.0).pow(2) + (a.1 - b.1).pow(2);
            if d > best.0 {
                best = (d, (a, b));
            }
        }
    }
    best
}

/// Twice the signed area of the triangle `o a b`: positive when `b` is left of `o -> a`.
fn cross(o: (i64, i64), a: (i64, i64), b: (i64, i64)) -> i64 {
    (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
}

impl Hull {
    /// The hull of `cells` (Andrew's monotone chain), or `None` when they lie on a line.
    fn of(cells: &[(usize, usize)]) -> Option<Hull> {
        Hull::of_points(cells.iter().map(|&(x, y)| (x as i64, y as i64)).collect())
    }

    /// The hull of `pts` (Andrew's monotone chain), or `None` when they lie on a line.
    fn of_points(mut pts: Vec<(i64, i64)>) -> Option<Hull> {
        pts.sort_unstable();
        pts.dedup();
        // The lower chain left to right and the upper chain right to left, each with its
        // own stack, then joined (each without its last point, the other's first).
        let chain = |pts: &mut dyn Iterator<Item = (i64, i64)>| {
            let mut c: Vec<(i64, i64)> = Vec::new();
            for p in pts {
                while c.len() >= 2 && cross(c[c.len() - 2], c[c.len() - 1], p) <= 0 {
                    c.pop();
                }
                c.push(p);
            }
            c.pop();
            c
        };
        let mut hull = chain(&mut pts.iter().copied());
        hull.extend(chain(&mut pts.iter().rev().copied()));
        (hull.len() >= 3).then_some(Hull(hull))
    }

    /// This hull, of the wall cells `cells` (at most `thick` cells from their middle
    /// line), completed to the parallelogram of an L: with every vertex also mirrored
    /// through the middle of the hull's widest chord (its two farthest vertices, the ends
    /// of an L's legs), so that an L's corner finds its opposite. `None` unless every cell
    /// lies along the two legs from the corner (the vertex farthest from the chord) to
    /// the chord's ends: a U, a ring or a blob (a plant's leaves) is no L.
    fn completed(&self, cells: &[(usize, usize)], thick: usize) -> Option<Hull> {
        let v = &self.0;
        let (_, (a, b)) = farthest_pair(v);
        // The corner: the vertex farthest from the chord; every cell within `thick` of
        // one of the two legs from it to the chord's ends.
        let corner = *v.iter().max_by_key(|&&p| cross(a, b, p).abs())?;
        let near = |p: (i64, i64), q: (i64, i64), c: (i64, i64)| {
            let (dx, dy) = ((q.0 - p.0) as f64, (q.1 - p.1) as f64);
            let (ex, ey) = ((c.0 - p.0) as f64, (c.1 - p.1) as f64);
            let t = ((ex * dx + ey * dy) / (dx * dx + dy * dy).max(1.0)).clamp(0.0, 1.0);
            (ex - t * dx).hypot(ey - t * dy) <= thick as f64 + 1e-9
        };
        let on_legs = cells.iter().all(|&(x, y)| {
            let c = (x as i64, y as i64);
            near(corner, a, c) || near(corner, b, c)
        });
        if !on_legs {
            return None;
        }
        let mut pts: Vec<(i64, i64)> = v.clone();
        pts.extend(v.iter().map(|&p| (a.0 + b.0 - p.0, a.1 + b.1 - p.1)));
        Hull::of_points(pts)
    }

    /// The box of the cells of `map` whose centres may lie inside (a hull of cells of the
    /// map, completed beyond them or not, is clipped to it).
    fn bounds(&self, map: &HeightMap) -> Bounds {
        let (mut x0, mut x1, mut y0, mut y1) = (i64::MAX, i64::MIN, i64::MAX, i64::MIN);
        for &(x, y) in &self.0 {
            (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
        }
        let clip = |v: i64, n: usize| usize::try_from(v.clamp(0, n as i64 - 1)).unwrap_or(0);
        Bounds {
            x0: clip(x0, map.nx),
            x1: clip(x1, map.nx),
            y0: clip(y0, map.ny),
            y1: clip(y1, map.ny),
        }
    }

    /// Whether the centre of cell `(x, y)` lies strictly inside.
    fn contains(&self, (x, y): (usize, usize)) -> bool {
        let p = (x as i64, y as i64);
        let n = self.0.len();
        (0..n).all(|i| cross(self.0[i], self.0[(i + 1) % n], p) > 0)
    }
}

/// The centres of the hidden places inside `hull` (within `b`): the cells counting as
/// unseen under `open` with nothing within `radius` cells but cells `open` lets a place
/// hold (the map's border counts as unseen; `walls` marks the walls' own cells), row by
/// row.
fn hidden_centres(
    map: &HeightMap,
    b: &Bounds,
    hull: &Hull,
    radius: usize,
    open: Open,
    walls: &Bits,
) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    for y in b.y0..=b.y1 {
        for x in b.x0..=b.x1 {
            let c = (x, y);
            if open.centre(map, c)
                && hull.contains(c)
                && disc(map, c, radius).all(|n| open.held(map, n, walls))
            {
                out.push(c);
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 30 x 30 map of 0.05 m cells, all unseen but a floor band along its low rows
    /// (y 0-3, at 0) and the `walls` given as `(x0, x1, y0, y1, height)` cell ranges,
    /// inclusive.
    fn map_with(walls: &[(usize, usize, usize, usize, f64)]) -> HeightMap {
        painted(|_, y| (y < 4).then_some(0.0), walls)
    }

    /// A 30 x 30 map of 0.05 m cells, `(x, y)` at `base(x, y)`, with the `walls` given as
    /// `(x0, x1, y0, y1, height)` cell ranges, inclusive, painted over it.
    fn painted(
        base: impl Fn(usize, usize) -> Option<f64>,
        walls: &[(usize, usize, usize, usize, f64)],
    ) -> HeightMap {
        let n = 30;
        let mut h: Vec<Option<f64>> = (0..n * n).map(|i| base(i % n, i / n)).collect();
        for &(x0, x1, y0, y1, z) in walls {
            for y in y0..=y1 {
                for x in x0..=x1 {
                    h[y * n + x] = Some(z);
                }
            }
        }
        HeightMap::from_dense(0.0, 0.0, 0.05, n, n, &h)
    }

    /// An armchair seen from behind: its back (0.85 m) along y 20-22, its arms (0.62 m)
    /// along x 8-9 and 20-21 from y 10 to the back, 0.10 m thick; the seat between them
    /// and the floor in front unseen.
    const ARMCHAIR: [(usize, usize, usize, usize, f64); 3] = [
        (8, 21, 20, 22, 0.85),
        (8, 9, 10, 19, 0.62),
        (20, 21, 10, 19, 0.62),
    ];

    #[test]
    fn the_seat_between_an_armchairs_back_and_arms_is_filled_below_its_arms() {
        let map = map_with(&ARMCHAIR);
        let found = hidden_seats(&map, &[], &HiddenConfig::default());
        assert_eq!(found.len(), 1);
        // The lowest tenth of the walls is the arms' 0.62 m; the seat 0.15 m below.
        assert!((found[0].height - 0.47).abs() < 1e-9);
        let cells = &found[0].cells;
        // The middle of the seat is filled, the walls and the floor are not.
        assert!(cells.contains(&(15, 15)));
        assert!(cells.iter().all(|&c| height(&map, c).is_none()));
        assert!(cells
            .iter()
            .all(|&(x, y)| (10..=19).contains(&x) && (8..=19).contains(&y)));
        // One arm and the back (an L, the other arm hidden) still hold it.
        let map = map_with(&ARMCHAIR[..2]);
        let found = hidden_seats(&map, &[], &HiddenConfig::default());
        assert_eq!(found.len(), 1);
        assert!(found[0].cells.contains(&(13, 15)));
    }

    #[test]
    fn a_box_thick_walls_high_walls_and_a_straight_back_hide_no_seat() {
        // A small cabinet's top (0.75 m, 0.35 x 0.45 m) seen from its corner, its shadow
        // unseen round it: convex, nothing hidden inside its hull.
        let map = map_with(&[(8, 14, 10, 18, 0.75)]);
        assert!(hidden_seats(&map, &[], &HiddenConfig::default()).is_empty());
        // The armchair's walls 0.5 m thick (a mattress with its pillows, a table).
        let map = map_with(&[
            (4, 25, 20, 29, 0.85),
            (4, 8, 10, 19, 0.62),
            (21, 25, 10, 19, 0.62),
        ]);
        assert!(hidden_seats(&map, &[], &HiddenConfig::default()).is_empty());
        // The same shape 1.2 m high (a shelf's sides, a desk's raised panels).
        let high: Vec<_> = ARMCHAIR
            .iter()
            .map(|&(a, b, c, d, _)| (a, b, c, d, 1.2))
            .collect();
        assert!(hidden_seats(&map_with(&high), &[], &HiddenConfig::default()).is_empty());
        // A chair's back alone (no arms): nothing inside its hull but itself; turned 45
        // degrees, its box holds unseen cells either side, outside the hull.
        assert!(hidden_seats(&map_with(&ARMCHAIR[..1]), &[], &HiddenConfig::default()).is_empty());
        let turned: Vec<_> = (8..24).map(|x| (x, x + 1, x - 2, x - 2, 0.85)).collect();
        assert!(hidden_seats(&map_with(&turned), &[], &HiddenConfig::default()).is_empty());
        // Arms 0.20 m apart: no place as wide as the hips between them.
        let narrow = [
            (8, 15, 20, 22, 0.85),
            (8, 9, 10, 19, 0.62),
            (14, 15, 10, 19, 0.62),
        ];
        assert!(hidden_seats(&map_with(&narrow), &[], &HiddenConfig::default()).is_empty());
    }

    #[test]
    fn a_back_alone_hides_its_seat_on_the_side_the_scan_did_not_see() {
        // A sofa's back (0.85 m, 0.70 m long, 0.15 m thick) seen from behind: the floor
        // seen up to it on the camera's side (y below 12), nothing beyond it.
        let back = [(8, 21, 12, 14, 0.85)];
        let floor_to = |last: usize| move |_: usize, y: usize| (y <= last).then_some(0.0);
        let cfg = HiddenConfig::default();
        let found = hidden_seats(&painted(floor_to(11), &back), &[], &cfg);
        assert_eq!(found.len(), 1);
        // The seat is `lone_drop` below the back's top, on the unseen side, within
        // `lone_depth` and a place's radius of the back's line and its ends.
        assert!((found[0].height - 0.45).abs() < 1e-9);
        assert!(found[0].cells.contains(&(15, 18)));
        assert!(found[0]
            .cells
            .iter()
            .all(|&(x, y)| (15..=25).contains(&y) && (5..=24).contains(&x)));
        // Turned to face the other way (the floor seen beyond it, nothing before it).
        let turned = painted(|_, y| (y >= 15).then_some(0.0), &back);
        let found = hidden_seats(&turned, &[], &cfg);
        assert_eq!(found.len(), 1);
        assert!(found[0].cells.iter().all(|&(_, y)| y < 12));
        // The floor seen on both sides (a low partition), or on neither: which side the
        // seat is on, if any, is not shown.
        let both = painted(|_, y| (!(12..=14).contains(&y)).then_some(0.0), &back);
        assert!(hidden_seats(&both, &[], &cfg).is_empty());
        // The floor seen right behind it as well (under an open back), unseen further on.
        let open = painted(|_, y| (y < 12 || y == 15 || y == 16).then_some(0.0), &back);
        assert!(hidden_seats(&open, &[], &cfg).is_empty());
        assert!(hidden_seats(&painted(|_, _| None, &back), &[], &cfg).is_empty());
        // Something higher than the floor right beside it on the camera's side (a low
        // cabinet's top, 0.48 m): not a back standing free over the floor.
        let cabinet = [back[0], (8, 21, 9, 10, 0.48)];
        assert!(hidden_seats(&painted(floor_to(11), &cabinet), &[], &cfg).is_empty());
        // Longer than `lone_length` allows (a room's wall cut by the image's edge).
        let short = HiddenConfig {
            lone_length: (0.35, 0.60),
            ..cfg
        };
        assert!(hidden_seats(&painted(floor_to(11), &back), &[], &short).is_empty());
        // Joined to something higher than a wall at its end (a room's wall whose top
        // the image's edge cuts aslant, rising past `wall_high`): not standing free.
        let cut = [back[0], (22, 27, 12, 14, 1.3)];
        assert!(hidden_seats(&painted(floor_to(11), &cut), &[], &cfg).is_empty());
        // Its top rising along it (0.60 to 0.86 m: a room's wall whose top the image's
        // edge cuts aslant), or as thick as it is long (a bar stool's seat, 0.80 m):
        // not a back.
        let aslant: Vec<_> = (8..=21)
            .map(|x| (x, x, 12, 14, 0.60 + 0.02 * (x - 8) as f64))
            .collect();
        assert!(hidden_seats(&painted(floor_to(11), &aslant), &[], &cfg).is_empty());
        let stool = [(12, 18, 12, 18, 0.80)];
        assert!(hidden_seats(&painted(floor_to(11), &stool), &[], &cfg).is_empty());
        // Narrower than a place: no seat behind a post.
        let post = [(14, 16, 12, 14, 0.85)];
        assert!(hidden_seats(&painted(floor_to(11), &post), &[], &cfg).is_empty());
        // At the map's edge, the seat's side past the border: nothing the scan covers.
        let edge = [(8, 21, 20, 22, 0.85)];
        assert!(hidden_seats(&painted(floor_to(19), &edge), &[], &cfg).is_empty());
    }

    #[test]
    fn a_reclined_back_hides_its_seat_where_the_floor_shows_under_it() {
        // A chair's back (0.45 m long) seen from behind, reclined over its seat: its top
        // edge (0.90 m) along y = 12 and its lower rows (0.80-0.50 m) along y 13-16, on
        // the seat's side; the floor seen on both sides, under the seat too (between its
        // legs, the seat's top hidden by the back). Seen from above it is about as thick
        // as it is long; its top edge is a line.
        let back = [
            (8, 16, 12, 12, 0.90),
            (8, 16, 13, 13, 0.80),
            (8, 16, 14, 14, 0.70),
            (8, 16, 15, 15, 0.60),
            (8, 16, 16, 16, 0.50),
        ];
        let floor = |_: usize, y: usize| (!(12..=16).contains(&y)).then_some(0.0);
        let cfg = HiddenConfig::default();
        let found = hidden_seats(&painted(floor, &back), &[], &cfg);
        assert_eq!(found.len(), 1);
        // On the side it leans towards, `lone_drop` below its top.
        assert!((found[0].height - 0.50).abs() < 1e-9);
        assert!(found[0].cells.iter().all(|&(_, y)| y > 12));
        assert!(found[0].cells.contains(&(12, 20)));
        // Mirrored: the lower rows along y 8-11, the top edge along y = 12.
        let mirrored: Vec<_> = back
            .iter()
            .map(|&(x0, x1, y, _, h)| (x0, x1, 24 - y, 24 - y, h))
            .collect();
        let floor_m = |_: usize, y: usize| (!(8..=12).contains(&y)).then_some(0.0);
        let found = hidden_seats(&painted(floor_m, &mirrored), &[], &cfg);
        assert_eq!(found.len(), 1);
        assert!(found[0].cells.iter().all(|&(_, y)| y < 12));
        // Upright (every row at its top): which side the seat is on is not shown.
        let upright: Vec<_> = back
            .iter()
            .map(|&(x0, x1, y0, y1, _)| (x0, x1, y0, y1, 0.90))
            .collect();
        assert!(hidden_seats(&painted(floor, &upright), &[], &cfg).is_empty());
        // Something other than the floor beside it on the seat's side (a footrest's
        // top, 0.20 m): not the floor seen under a seat.
        let mut cabinet = back.to_vec();
        cabinet.push((8, 9, 17, 18, 0.20));
        assert!(hidden_seats(&painted(floor, &cabinet), &[], &cfg).is_empty());
        // A desk's top over the seat's side, 0.25 m over the seat, beside its corner
        // (the chair pushed in under it): room for the thighs, the seat hidden under it
        // as beside it.
        let mut pushed_in = back.to_vec();
        pushed_in.push((0, 10, 19, 26, 0.75));
        let found = hidden_seats(&painted(floor, &pushed_in), &[], &cfg);
        assert_eq!(found.len(), 1);
        assert!((found[0].height - 0.50).abs() < 1e-9);
        assert!(found[0].cells.iter().all(|&(_, y)| y > 12));
        // The same top 0.10 m over the seat: no room for the thighs under it.
        pushed_in.pop();
        pushed_in.push((0, 10, 19, 26, 0.60));
        assert!(hidden_seats(&painted(floor, &pushed_in), &[], &cfg).is_empty());
        // The floor seen on the seat's side only, the camera's side unseen: no side
        // the scan saw the back from.
        let far = painted(|_, y| (y > 16).then_some(0.0), &back);
        assert!(hidden_seats(&far, &[], &cfg).is_empty());
        // Leaning less than `lone_fall`: not shown either.
        let steep = HiddenConfig {
            lone_fall: 0.15,
            ..cfg
        };
        assert!(hidden_seats(&painted(floor, &back), &[], &steep).is_empty());
        // Too low for a back over a seat (its top 0.68 m: the seat would be 0.28 m high).
        let low = [
            (8, 16, 12, 12, 0.68),
            (8, 16, 13, 13, 0.62),
            (8, 16, 14, 14, 0.56),
            (8, 16, 15, 15, 0.52),
            (8, 16, 16, 16, 0.50),
        ];
        assert!(hidden_seats(&painted(floor, &low), &[], &cfg).is_empty());
    }

    #[test]
    fn a_chair_whose_arms_meet_a_desk_in_the_map_still_hides_its_seat() {
        // An office chair pushed up to a desk, seen from behind: the desk's top (0.75 m,
        // 0.60 m deep) along y 2-13, the chair's arms at the top's height running from
        // it to the back (0.90 m) along y 21-22; the seat between them unseen. The top
        // joins the arms in the map and is too thick for a wall.
        let desk = (4, 25, 2, 13, 0.75);
        let chair = [
            desk,
            (8, 9, 14, 20, 0.75),
            (20, 21, 14, 20, 0.75),
            (8, 21, 21, 22, 0.90),
        ];
        let cfg = HiddenConfig::default();
        let found = hidden_seats(&map_with(&chair), &[], &cfg);
        assert_eq!(found.len(), 1);
        assert!(found[0].cells.contains(&(15, 17)));
        // Below the arms' level, as for walls standing alone; nothing on the desk.
        assert!((found[0].height - 0.60).abs() < 1e-9);
        assert!(found[0].cells.iter().all(|&(_, y)| y > 13));
        // The same with arms 0.25 m wide (a sofa's, or the strips a bed's duvet leaves
        // between its lumps' shadows beside its flat part): not a chair's walls.
        let wide = [
            desk,
            (5, 9, 14, 20, 0.75),
            (20, 24, 14, 20, 0.75),
            (5, 24, 21, 22, 0.90),
        ];
        assert!(hidden_seats(&map_with(&wide), &[], &cfg).is_empty());
        let at_most = HiddenConfig {
            beside_half_width: 0.20,
            ..cfg
        };
        assert_eq!(hidden_seats(&map_with(&wide), &[], &at_most).len(), 1);
    }

    #[test]
    fn a_shadow_inside_a_surface_is_no_seat_beside_it() {
        // A bed's duvet (0.60 m) seen either side of a lump's shadow, flat parts 0.45 m
        // wide, and across the shadow's near end a pillow's edge (0.70 m) from one to the
        // other with two thin folds (0.62 m) running into it: a U of walls round an
        // unseen place 0.40 m wide, as a chair's, but between the parts of the surface.
        let bed = [
            (0, 8, 0, 29, 0.60),
            (21, 29, 0, 29, 0.60),
            (9, 20, 24, 25, 0.70),
            (10, 10, 5, 23, 0.62),
            (19, 19, 5, 23, 0.62),
        ];
        assert!(hidden_seats(&map_with(&bed), &[], &HiddenConfig::default()).is_empty());
        // The same walls with the duvet's flat parts seen lower (not walls): a seat.
        let low: Vec<_> = bed
            .iter()
            .map(|&(a, b, c, d, z)| (a, b, c, d, if z == 0.60 { 0.40 } else { z }))
            .collect();
        assert_eq!(
            hidden_seats(&map_with(&low), &[], &HiddenConfig::default()).len(),
            1
        );
    }

    /// A 30 x 30 map of 0.05 m cells, the floor (0.0) seen everywhere but under `walls`.
    fn floor_map_with(walls: &[(usize, usize, usize, usize, f64)]) -> HeightMap {
        painted(|_, _| Some(0.0), walls)
    }

    /// The back of a chair without arms seen from behind: 0.5 m wide, its top at 0.85 m
    /// and its lower rail at 0.55 m.
    const ARMLESS_BACK: [(usize, usize, usize, usize, f64); 2] =
        [(10, 19, 10, 10, 0.85), (10, 19, 11, 11, 0.55)];

    #[test]
    fn an_armless_chair_seen_from_behind_is_filled_over_the_floor_under_its_seat() {
        // A chair without arms seen from behind: its back, the seat's side edge (0.45 m)
        // running 0.4 m forward from one end of it, and the floor seen everywhere else,
        // under the seat too.
        let chair = [ARMLESS_BACK[0], ARMLESS_BACK[1], (19, 19, 12, 19, 0.45)];
        let cfg = HiddenConfig::default();
        let holes = hidden_seats(&floor_map_with(&chair), &[], &cfg);
        assert_eq!(holes.len(), 1);
        assert!(holes[0].cells.contains(&(15, 15)));
        // Under the walls' lowest tenth (the back's rail), as for arms.
        assert!((holes[0].height - 0.40).abs() < 1e-9);
        // The floor counts only as far as the seat's edge shows a seat: with the floor
        // not counted, or without the edge, or the walls and the edge spanning more than
        // a seat (two 1.3 m walls of a room meeting at a corner, a bench along one),
        // nothing is filled.
        let no_floor = HiddenConfig {
            floor_top: 0.0,
            ..cfg
        };
        assert!(hidden_seats(&floor_map_with(&chair), &[], &no_floor).is_empty());
        let no_edge = [chair[0], chair[1], (19, 19, 12, 19, 0.85)];
        assert!(hidden_seats(&floor_map_with(&no_edge), &[], &cfg).is_empty());
        let corner = [
            (2, 27, 2, 2, 0.85),
            (2, 2, 3, 27, 0.85),
            (3, 27, 3, 3, 0.45),
        ];
        assert!(hidden_seats(&floor_map_with(&corner), &[], &cfg).is_empty());
        let wide = HiddenConfig {
            max_span: 1.5,
            ..cfg
        };
        assert!(!hidden_seats(&floor_map_with(&corner), &[], &wide).is_empty());
    }

    #[test]
    fn a_seat_pushed_under_a_desk_is_filled_beside_the_desks_top() {
        // A chair without arms pushed up to a desk, seen from behind: its back, the seat's
        // side edge running from it to the desk's top (0.75 m, from y 17 on), the floor
        // seen elsewhere. Between the back's rail and the desk there are 0.25 m, less than
        // a place's width: the seat goes on under the top.
        let chair = [
            ARMLESS_BACK[0],
            ARMLESS_BACK[1],
            (19, 19, 12, 16, 0.45),
            (5, 24, 17, 28, 0.75),
        ];
        let cfg = HiddenConfig::default();
        let holes = hidden_seats(&floor_map_with(&chair), &[], &cfg);
        assert_eq!(holes.len(), 1);
        assert!(holes[0].cells.contains(&(15, 15)));
        // Only what the scan did not see (the floor under the seat) is filled, at the
        // height of the seat's edge (the walls' hull, a thin triangle, holds no place:
        // the seat is seen in part beside them); the top stays as it is.
        assert!((holes[0].height - 0.45).abs() < 1e-9);
        assert!(holes[0].cells.iter().all(|&(_, y)| (12..17).contains(&y)));
        // A top that leaves no room for the thighs over the seat does not hide it.
        let no_room = HiddenConfig {
            under_room: (0.35, 0.60),
            ..cfg
        };
        assert!(hidden_seats(&floor_map_with(&chair), &[], &no_room).is_empty());
    }

    #[test]
    fn a_seat_seen_in_part_beside_its_back_is_filled_at_its_height_over_the_floor() {
        // A chair without arms seen from behind and a little from the side: its back, the
        // seat seen as a strip 0.20 m wide along its far side (0.45 m), and the floor seen
        // under the rest of it. No place 0.15 m clear of everything but the floor fits
        // between the rail and the strip.
        let chair = [ARMLESS_BACK[0], ARMLESS_BACK[1], (16, 19, 12, 19, 0.45)];
        let cfg = HiddenConfig::default();
        let map = floor_map_with(&chair);
        let holes = hidden_seats(&map, &[], &cfg);
        assert_eq!(holes.len(), 1);
        // At the height of the seat seen, over the floor beside it; the seat seen and the
        // walls are left as they are.
        assert!((holes[0].height - 0.45).abs() < 1e-9);
        assert!(holes[0].cells.contains(&(14, 15)));
        assert!(holes[0]
            .cells
            .iter()
            .all(|&c| height(&map, c).is_some_and(|h| h < cfg.floor_top)));
        // Walls hardly higher than the seat (a night stand's top, 0.55 m, over its side
        // seen at 0.45 m) are no back: nothing is filled, unless the rise asked is lower.
        let stand = [(10, 19, 10, 11, 0.55), (16, 19, 12, 19, 0.45)];
        let map = floor_map_with(&stand);
        assert!(hidden_seats(&map, &[], &cfg).is_empty());
        let low_rise = HiddenConfig {
            back_rise: 0.05,
            ..cfg
        };
        assert!(!hidden_seats(&map, &[], &low_rise).is_empty());
    }

    #[test]
    fn a_back_and_one_arm_hold_the_seat_between_them_over_the_floor_seen_under_it() {
        // An armchair with solid arm panels seen from its side: its back (0.88 m) along x
        // 19-20, its near arm (0.62 m) running 0.45 m forward from it along y 10-11, the
        // seat hidden behind the arm and the floor seen under it; the far arm unseen.
        let chair = [(19, 20, 10, 19, 0.88), (10, 18, 10, 11, 0.62)];
        let cfg = HiddenConfig::default();
        let map = floor_map_with(&chair);
        let holes = hidden_seats(&map, &[], &cfg);
        assert_eq!(holes.len(), 1);
        // Under the arm, as for an armchair seen from behind.
        assert!((holes[0].height - 0.47).abs() < 1e-9);
        // The far corner of the seat, (11, 17), is 0.15 m or less from no cell inside
        // the L's own hull (a triangle), only from cells of its parallelogram.
        assert!(holes[0].cells.contains(&(11, 17)));
        // The walls are left as they are: the fill is over the floor beside them.
        assert!(holes[0]
            .cells
            .iter()
            .all(|&c| height(&map, c).is_some_and(|h| h < cfg.floor_top)));
        // A corner of one height (two low walls, a bin's side) has no back over an arm;
        // an arm shorter than a seat is deep is a rail along the back; walls spanning
        // more than a seat are a room's: nothing is filled over the floor.
        // Beside a seat the scan saw (0.42 m, joined to the arm's front end and wider
        // than a seat's edge: a sofa's next seat), the walls hide no other.
        let beside_seen = [chair[0], chair[1], (0, 9, 8, 19, 0.42)];
        assert!(hidden_seats(&floor_map_with(&beside_seen), &[], &cfg).is_empty());
        let corner = [(19, 20, 10, 19, 0.62), (10, 18, 10, 11, 0.62)];
        assert!(hidden_seats(&floor_map_with(&corner), &[], &cfg).is_empty());
        let rail = [(19, 20, 10, 19, 0.88), (15, 18, 10, 11, 0.62)];
        assert!(hidden_seats(&floor_map_with(&rail), &[], &cfg).is_empty());
        let room = [(27, 28, 2, 27, 0.88), (2, 26, 2, 3, 0.62)];
        assert!(hidden_seats(&floor_map_with(&room), &[], &cfg).is_empty());
        let wide = HiddenConfig {
            max_span: 1.5,
            ..cfg
        };
        assert!(!hidden_seats(&floor_map_with(&room), &[], &wide).is_empty());
    }

    #[test]
    fn the_hull_of_an_l_holds_the_space_between_its_legs() {
        // A row and, at its right end, a column: the column's cells lie in line with the
        // lower chain's last edge, and must not fold the upper chain back onto the row.
        let mut cells: Vec<(usize, usize)> = (10..=19).map(|x| (x, 10)).collect();
        cells.extend((11..=19).map(|y| (19, y)));
        let hull = Hull::of(&cells).expect("not in line");
        assert!(hull.contains((17, 13)));
        assert!(!hull.contains((12, 17)));
        assert!(!hull.contains((19, 15)));
    }

    #[test]
    fn a_seat_the_scan_saw_is_not_filled_again() {
        // The seat seen at 0.45 m between the arms: nothing hidden there.
        let mut walls = ARMCHAIR.to_vec();
        walls.push((10, 19, 10, 19, 0.45));
        assert!(hidden_seats(&map_with(&walls), &[], &HiddenConfig::default()).is_empty());
        // Points over the seat the map left out (specks: a sparse top seen at a grazing
        // angle), one every 0.15 m at the walls' middle height (the back's 0.85 m, the
        // most of their cells): the walls are the edges of one surface.
        let map = map_with(&ARMCHAIR);
        let over = |z: f64| -> Vec<Point3<f64>> {
            (0..5)
                .flat_map(|i| (0..5).map(move |j| (i, j)))
                .map(|(i, j)| Point3::new(0.5 + 0.15 * f64::from(i), 0.5 + 0.15 * f64::from(j), z))
                .collect()
        };
        assert!(hidden_seats(&map, &over(0.85), &HiddenConfig::default()).is_empty());
        // At the seat's height (its cushion glimpsed through a gap), below it (the floor
        // seen between its legs) or well above the walls (a back leaning over the seat)
        // they change nothing.
        let found = hidden_seats(&map, &[], &HiddenConfig::default());
        assert_eq!(found.len(), 1);
        for z in [0.0, 0.5, 1.0] {
            assert_eq!(
                hidden_seats(&map, &over(z), &HiddenConfig::default()),
                found
            );
        }
    }

    #[test]
    fn a_top_over_a_seat_the_map_kept_is_no_surface_of_the_walls() {
        // The armchair seen from behind, its seat seen across it in a band (y 12-13, at
        // 0.47 m, the place's level) under a desk's top (points at 0.85 m, the walls'
        // middle height, over the band): the chair pushed in under the desk, the map
        // keeping the seat under it.
        let mut walls = ARMCHAIR.to_vec();
        walls.push((10, 19, 12, 13, 0.47));
        let map = map_with(&walls);
        let cfg = HiddenConfig::default();
        let plain = hidden_seats(&map, &[], &cfg);
        assert_eq!(plain.len(), 1);
        let desk = |z: f64| -> Vec<Point3<f64>> {
            (10..20)
                .flat_map(|x| (12..14).map(move |y| (x, y)))
                .map(|(x, y)| {
                    Point3::new(0.05 * f64::from(x) + 0.025, 0.05 * f64::from(y) + 0.025, z)
                })
                .collect()
        };
        assert_eq!(hidden_seats(&map, &desk(0.85), &cfg), plain);
        // The same points over the floor the map kept there (a desk's top over the floor,
        // no seat under it): the walls' surface seen sparsely, as before.
        let mut floor = ARMCHAIR.to_vec();
        floor.push((10, 19, 12, 13, 0.0));
        let map = map_with(&floor);
        let filled = |holes: &[Hole]| holes.iter().map(|h| h.cells.len()).sum::<usize>();
        let plain = filled(&hidden_seats(&map, &[], &cfg));
        assert!(filled(&hidden_seats(&map, &desk(0.85), &cfg)) < plain);
    }

    #[test]
    fn the_half_width_of_a_strip_is_half_its_cells() {
        for (width, half) in [(1, 1), (2, 1), (3, 2), (8, 4), (9, 5)] {
            let comp: Vec<(usize, usize)> = (0..width)
                .flat_map(|x| (0..20).map(move |y| (x + 5, y + 5)))
                .collect();
            assert_eq!(half_width(&comp, &Bounds::of(&comp)), half, "width {width}");
        }
    }
}
