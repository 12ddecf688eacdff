#![no_main]
//! E57 reader (every scan, with its pose) on arbitrary bytes.

use afford::cloud::source::{read_parts, SourceOptions};
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let path = common::temp_file("e57", data);
    let _ = read_parts(&path, &SourceOptions::default(), &mut |_| {});
});
