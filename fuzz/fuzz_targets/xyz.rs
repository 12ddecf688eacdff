#![no_main]
//! Text cloud reader (`.xyz`, `.txt`, `.csv`): the first byte picks the extension.

use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, body)) = data.split_first() else {
        return;
    };
    let ext = match sel % 3 {
        0 => "xyz",
        1 => "txt",
        _ => "csv",
    };
    let path = common::temp_file(ext, body);
    let _ = afford::cloud::load(&path);
});
