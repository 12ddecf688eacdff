//! Benchmarks of the pipeline stages (filled in below).
fn main() {}
