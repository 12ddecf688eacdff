#![no_main]
//! PCD reader (ascii, binary, binary_compressed) on arbitrary bytes.

use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let path = common::temp_file("pcd", data);
    let _ = afford::cloud::read_pcd(&path);
});
