//! The library's integration tests, one binary (`cargo test --release -p afford --test
//! integration`): one module per topic, the shared fixtures in `common`. Run one topic with
//! a module filter, e.g. `cargo test --release -p afford --test integration lying::`.

mod common;

mod custom_hierarchy;
mod fuzz_regressions;
mod lying;
mod pipeline;
mod regression;
mod regression_real;
mod render_demo;
