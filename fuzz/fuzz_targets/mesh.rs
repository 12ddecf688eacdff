#![no_main]
//! OBJ / OFF / STL readers: the first byte picks the extension, the rest is the file.

use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, body)) = data.split_first() else {
        return;
    };
    let ext = match sel % 3 {
        0 => "obj",
        1 => "off",
        _ => "stl",
    };
    let path = common::temp_file(ext, body);
    let _ = afford::cloud::mesh::read_mesh(&path);
});
