//! The command line's integration tests, one binary (`cargo test --release -p afford-cli
//! --test integration`): one module per topic, the shared helpers in `common`. Run one
//! topic with a module filter, e.g. `cargo test --release -p afford-cli --test integration
//! reliability::`.

mod common;

mod batch;
mod cli;
mod docs_links;
mod formats;
mod reliability;
