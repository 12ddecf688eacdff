//! `afford`: finds where a person could sit or lie in a 3D point cloud, and how.
//!
//! The method is Seib et al., "Affordance Origami" (sections 3 and 4): a simulated
//! body is dropped into the scene at promising positions and its joints are unfolded
//! until they touch the scene; which joints touch, and where, tells the fine-grained
//! affordance (sitting with or without backrest, armrest, headrest; lying).

pub mod cloud;
pub mod synth;
