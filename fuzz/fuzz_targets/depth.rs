#![no_main]
//! Depth PNG reader on arbitrary bytes.

use afford::cloud::source::{read_parts, SourceOptions};
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let path = common::temp_file("png", data);
    let opts = SourceOptions {
        intrinsics: Some(afford::cloud::source::Intrinsics {
            fx: 500.0,
            fy: 500.0,
            cx: 2.0,
            cy: 2.0,
        }),
        ..Default::default()
    };
    let _ = read_parts(&path, &opts, &mut |_| {});
});
