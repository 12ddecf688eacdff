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
//!
//! # Example
//!
//! A stool, a 0.40 m x 0.40 m box 0.45 m high standing on a floor, sampled as points every
//! centimetre (world frame: metres, z up, floor at z = 0), affords sitting for the built-in
//! 1.75 m human, without a backrest:
//!
//! ```
//! use afford::cloud::PointCloud;
//! use afford::detect::{detect, DetectConfig};
//! use afford::model::agent::Agent;
//! use afford::model::hierarchy::Hierarchy;
//! use afford::model::set::{BUILTIN_AGENT, BUILTIN_SITTING};
//! use nalgebra::Point3;
//! use std::path::Path;
//!
//! let mut points = Vec::new();
//! let steps = |from: f64, to: f64| {
//!     let n = ((to - from) / 0.01).round() as i32;
//!     (0..=n).map(move |i| from + f64::from(i) * 0.01)
//! };
//! for x in steps(-1.0, 1.0) {
//!     for y in steps(-1.0, 1.0) {
//!         let on_stool = x.abs() <= 0.2 && y.abs() <= 0.2;
//!         points.push(Point3::new(x, y, if on_stool { 0.45 } else { 0.0 }));
//!     }
//! }
//! for z in steps(0.0, 0.45) {
//!     for t in steps(-0.2, 0.2) {
//!         for (x, y) in [(t, -0.2), (t, 0.2), (-0.2, t), (0.2, t)] {
//!             points.push(Point3::new(x, y, z));
//!         }
//!     }
//! }
//! let cloud = PointCloud::new(points);
//! let agent = Agent::from_toml(BUILTIN_AGENT, Path::new("human.toml"), 1.75)?;
//! let sitting = Hierarchy::from_toml(BUILTIN_SITTING, Path::new("sitting.toml"), &agent)?;
//! let outcome = detect(&cloud, &agent, &sitting, &DetectConfig::default());
//! let seat = &outcome.detections[0];
//! assert!(seat.affordances.iter().any(|a| a == "sitting"));
//! assert!(!seat.affordances.iter().any(|a| a == "backrest"));
//! assert!((seat.seat.z - 0.45).abs() < 0.03, "sat on the top: {}", seat.seat);
//! # Ok::<(), afford::model::ModelError>(())
//! ```

mod cellhash;
pub mod cloud;
pub mod detect;
pub mod embed;
pub mod eval;
pub mod input;
pub mod mesh;
pub mod method;
pub mod model;
mod num;
pub mod report;
