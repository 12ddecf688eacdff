//! Read speed of the cloud loaders on 1M-point files, against just reading the bytes.
//!
//! At start-up three files are generated in a temporary directory (nothing large is
//! committed): a binary little-endian PLY (`x y z` float, `red green blue` uchar), a
//! binary PCD (`x y z` float, written by [`cloud::write_pcd`]) and a binary_compressed
//! PCD (same points, compressed here with a small LZF compressor). Each group times
//! [`cloud::load`] and [`std::fs::read`] on the same file; throughput is in points.

// The fixtures write file fields by hand (a PLY of 1M points, an LZF compressor's
// tokens): every narrowing cast packs a value already in the field's range.
#![allow(clippy::cast_possible_truncation)]

use std::path::{Path, PathBuf};

use afford::cloud;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::Point3;

/// Points per generated file.
const N: usize = 1_000_000;

/// Deterministic points in a 5 m x 4 m x 2.5 m room, on a 1 mm grid (so the LZF
/// compressor finds some repeats, as in real scans).
fn points() -> Vec<Point3<f64>> {
    let mut s: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut next = |scale: f64| {
        s = s
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((s >> 33) as f64 / (1u64 << 31) as f64 * scale * 1000.0).round() / 1000.0
    };
    (0..N)
        .map(|_| Point3::new(next(5.0), next(4.0), next(2.5)))
        .collect()
}

fn write_ply(path: &Path, pts: &[Point3<f64>]) {
    let mut b = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {}\nproperty float x\n\
         property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
         property uchar blue\nend_header\n",
        pts.len()
    )
    .into_bytes();
    b.reserve(pts.len() * 15);
    for (i, p) in pts.iter().enumerate() {
        for c in p.coords.iter() {
            b.extend_from_slice(&(*c as f32).to_le_bytes());
        }
        b.extend_from_slice(&[i as u8, (i >> 8) as u8, (i >> 16) as u8]);
    }
    std::fs::write(path, b).unwrap();
}

/// LZF compression (the liblzf format PCL uses): literal runs of up to 32 bytes
/// (control byte `len - 1`) and back references found with a 3-byte hash (control
/// `len - 2` in the top 3 bits, with an extra length byte when that is 7, and a 13-bit
/// offset minus one).
fn lzf_compress(input: &[u8]) -> Vec<u8> {
    const HLOG: u32 = 16;
    let mut table = vec![usize::MAX; 1 << HLOG];
    let mut out = Vec::with_capacity(input.len() + input.len() / 32 + 8);
    let mut lit: Vec<u8> = Vec::with_capacity(32);
    let flush = |out: &mut Vec<u8>, lit: &mut Vec<u8>| {
        if !lit.is_empty() {
            out.push((lit.len() - 1) as u8);
            out.extend_from_slice(lit);
            lit.clear();
        }
    };
    let mut i = 0;
    while i < input.len() {
        if i + 3 <= input.len() {
            let v =
                u32::from(input[i]) << 16 | u32::from(input[i + 1]) << 8 | u32::from(input[i + 2]);
            let h = (v.wrapping_mul(2_654_435_761) >> (32 - HLOG)) as usize;
            let r = table[h];
            table[h] = i;
            if r != usize::MAX && i - r <= 8192 && input[r..r + 3] == input[i..i + 3] {
                let max = (input.len() - i).min(264);
                let mut len = 3;
                while len < max && input[r + len] == input[i + len] {
                    len += 1;
                }
                flush(&mut out, &mut lit);
                let off = i - r - 1;
                let l = len - 2;
                if l < 7 {
                    out.push(((l as u8) << 5) | (off >> 8) as u8);
                } else {
                    out.push((7 << 5) | (off >> 8) as u8);
                    out.push((l - 7) as u8);
                }
                out.push(off as u8);
                i += len;
                continue;
            }
        }
        lit.push(input[i]);
        if lit.len() == 32 {
            flush(&mut out, &mut lit);
        }
        i += 1;
    }
    flush(&mut out, &mut lit);
    out
}

fn write_pcd_compressed(path: &Path, pts: &[Point3<f64>]) {
    let mut raw = Vec::with_capacity(pts.len() * 12);
    for k in 0..3 {
        for p in pts {
            raw.extend_from_slice(&(p[k] as f32).to_le_bytes());
        }
    }
    let packed = lzf_compress(&raw);
    let mut b = format!(
        "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\n\
         WIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary_compressed\n",
        n = pts.len()
    )
    .into_bytes();
    b.extend_from_slice(&(packed.len() as u32).to_le_bytes());
    b.extend_from_slice(&(raw.len() as u32).to_le_bytes());
    b.extend_from_slice(&packed);
    std::fs::write(path, b).unwrap();
}

fn readers(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let pts = points();
    let files: Vec<(&str, PathBuf)> = vec![
        ("ply_binary_le", dir.path().join("cloud.ply")),
        ("pcd_binary", dir.path().join("cloud.pcd")),
        ("pcd_binary_compressed", dir.path().join("cloud_lzf.pcd")),
    ];
    write_ply(&files[0].1, &pts);
    cloud::write_pcd(&files[1].1, &pts).unwrap();
    write_pcd_compressed(&files[2].1, &pts);
    for (name, path) in &files {
        let loaded = cloud::load(path).unwrap();
        assert_eq!(loaded.cloud.len(), N, "{name}");
        assert_eq!(
            loaded.cloud.points[N - 1].x,
            f64::from(pts[N - 1].x as f32),
            "{name}"
        );
        let mut g = c.benchmark_group(*name);
        g.sample_size(10);
        g.throughput(Throughput::Elements(N as u64));
        g.bench_function("load", |b| b.iter(|| cloud::load(path).unwrap()));
        g.bench_function("fs_read", |b| b.iter(|| std::fs::read(path).unwrap()));
        g.finish();
        eprintln!(
            "{name}: {} bytes",
            std::fs::metadata(path).map(|m| m.len()).unwrap_or(0)
        );
    }
}

/// The benchmark group.
#[allow(missing_docs)]
mod group {
    use super::*;
    criterion_group!(benches, readers);
}
use group::benches;
criterion_main!(benches);
