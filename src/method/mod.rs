//! The stages of the method (Seib et al., "Affordance Origami", section 4), in the order
//! a cloud goes through them: [`heightmap`] (4.1) with the [`fuzzy`] rules of the
//! [`hypotheses`] (4.1); the [`extent`] guard and the [`specks`] left out before
//! the grids; the [`holes`] of a view filled; the voxel [`scene`] (4.2);
//! the initial [`fit`] (4.2); [`unfold`] (4.3, 4.4); [`select`] (4.5).
//! [`crate::detect`] runs them in this order.

pub mod extent;
pub mod fit;
pub mod fuzzy;
pub mod heightmap;
pub mod hidden;
pub mod holes;
pub mod hypotheses;
pub mod scene;
pub mod select;
pub mod specks;
pub mod unfold;
