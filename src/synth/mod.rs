//! Procedural furniture and scenes with known affordances, for tests and labelled data.
//!
//! [`mesh`] holds labelled triangle meshes (boxes, cylinders) and a deterministic surface
//! sampler that turns them into point clouds; [`furniture`] builds parametric chairs,
//! stools, sofas, benches, beds (positives) and tables, desks, shelves, cabinets, walls,
//! floors (negatives) from them; [`wide`] adds what real scans have (`--mix wide`).
//! World frame: metres, z up, floor at z = 0; seating furniture faces +x (the backrest is
//! on the -x side).

pub mod camera;
pub mod dataset;
pub mod furniture;
pub mod mesh;
pub mod meshio;
pub mod scenes;
pub mod wide;

pub use furniture::*;
pub use mesh::{sample_surface, Mesh, Part};
