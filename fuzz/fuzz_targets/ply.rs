#![no_main]
//! PLY point and mesh readers on arbitrary bytes: must return Ok or Err, never panic.

use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let path = common::temp_file("ply", data);
    let _ = afford::cloud::read_ply(&path);
    let _ = afford::cloud::mesh::read_mesh(&path);
});
