//! `afford`: finds where a person could sit or lie in a 3D point cloud, and how.
//!
//! The method is Seib et al., "Affordance Origami" (sections 3 and 4): a simulated
//! body is dropped into the scene at promising positions and its joints are unfolded
//! until they touch the scene; which joints touch, and where, tells the fine-grained
//! affordance (sitting with or without backrest, armrest, headrest; lying).
//!
//! Stages, each a function from one typed value to the next:
//! [`cloud::load`] → [`method::heightmap::HeightMap`] → [`method::hypotheses::hypotheses`] →
//! [`method::scene::Scene`] → [`method::fit::fit`] → [`method::unfold::unfold`] →
//! [`method::select`] → [`report`].

pub mod cloud;
pub mod detect;
pub mod embed;
pub mod eval;
pub mod input;
pub mod mesh;
pub mod method;
pub mod model;
pub mod report;
