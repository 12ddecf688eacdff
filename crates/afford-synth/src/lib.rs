//! Procedural furniture and scenes with known affordances, for tests and labelled data.
//!
//! The labelled triangle meshes (boxes, cylinders) and the deterministic surface sampler
//! that turns them into point clouds are the library's [`afford::mesh`]; [`furniture`]
//! builds parametric chairs, stools, sofas, benches, beds (positives) and tables, desks,
//! shelves, cabinets, walls, floors (negatives) from them; [`wide`] adds what real scans have (`--mix wide`).
//! World frame: metres, z up, floor at z = 0; seating furniture faces +x (the backrest is
//! on the -x side).

pub mod camera;
pub mod dataset;
pub mod furniture;
pub mod scenes;
pub mod wide;

/// A count of parts or cells from a length the caller has rounded (`round`, `floor`,
/// `ceil`): furniture sizes are drawn from ranges of a metre or two, so the count is small
/// and the saturating `as` (NaN and negatives give 0) drops only the fraction.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
pub(crate) fn count(x: f64) -> usize {
    // Saturating by the definition of `as` (see the function's doc).
    x as usize
}
