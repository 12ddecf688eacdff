#![no_main]
//! ROS bags on arbitrary bytes: a first byte of 0 or 1 decodes the rest as one
//! PointCloud2 message (ROS 2 CDR or ROS 1); anything else reads the bytes as an MCAP
//! file, every message of its PointCloud2 topic.

use afford::cloud::pointcloud2::{decode, Encoding};
use afford::cloud::source::{read_parts, SourceOptions};
use libfuzzer_sys::fuzz_target;

mod common;

fuzz_target!(|data: &[u8]| {
    match data.split_first() {
        Some((0, rest)) => {
            let _ = decode(rest, Encoding::Cdr);
        }
        Some((1, rest)) => {
            let _ = decode(rest, Encoding::Ros1);
        }
        _ => {
            let path = common::temp_file("mcap", data);
            let _ = read_parts(&path, &SourceOptions::default(), &mut |_| {});
        }
    }
});
