//! `afford`: finds where a person could sit or lie in a 3D point cloud, and how.
//!
//! The method is Seib et al., "Affordance Origami" (sections 3 and 4): a simulated
//! body is dropped into the scene at promising positions and its joints are unfolded
//! until they touch the scene; which joints touch, and where, tells the fine-grained
//! affordance (sitting with or without backrest, armrest, headrest; lying).
//!
//! Stages, each a function from one typed value to the next:
//! [`cloud::load`] → [`heightmap::HeightMap`] → [`hypotheses::hypotheses`] →
//! [`scene::Scene`] → [`fit::fit`] → [`unfold::unfold`] → [`select`] → [`report`].

pub mod agent;
pub mod agent_mesh;
pub mod atomic;
pub mod batch;
pub mod cli;
pub mod cloud;
pub mod detect;
pub mod embed;
pub mod eval;
pub mod extent;
pub mod fit;
pub mod fuzzy;
pub mod glb;
pub mod heightmap;
pub mod hierarchy;
pub mod hypotheses;
pub mod input;
pub mod model;
pub mod model_set;
pub mod render;
pub mod report;
pub mod run;
pub mod scene;
pub mod select;
pub mod settings;
mod source_args;
pub mod synth;
pub mod unfold;
