//! A multiplicative hasher for integer cell keys (the Fx hash of rustc), for the hash maps
//! keyed by grid cells (segmentation's cells, the point-spacing tiles and search cells,
//! the extent guard's coarse cubes). SipHash's protection against chosen keys is of no
//! use for cells of a point cloud, and its seeds are random: no result may depend on the
//! maps' order, only their look-ups (each user says why its results do not).

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// A hash map keyed by cells, hashed by [`CellHasher`].
pub(crate) type CellMap<K, V> = HashMap<K, V, BuildHasherDefault<CellHasher>>;
/// A hash set of cells, hashed by [`CellHasher`].
pub(crate) type CellSet<K> = HashSet<K, BuildHasherDefault<CellHasher>>;

/// The Fx hash: each word rotates the state, is xored in and multiplied by a constant.
#[derive(Default)]
pub(crate) struct CellHasher(u64);

impl Hasher for CellHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
    }

    fn write_i64(&mut self, i: i64) {
        self.write_u64(i as u64);
    }

    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }

    fn write_u64(&mut self, i: u64) {
        const K: u64 = 0x517c_c1b7_2722_0a95;
        self.0 = (self.0.rotate_left(5) ^ i).wrapping_mul(K);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cells near one another land in different buckets: the hashes of a 20^3 block of
    /// keys (tuples and arrays, as the users key) are all distinct.
    #[test]
    fn neighbouring_cells_hash_apart() {
        use std::hash::BuildHasher;
        let b = BuildHasherDefault::<CellHasher>::default();
        let mut seen = HashSet::new();
        let mut seen_arrays = HashSet::new();
        for x in -10i64..10 {
            for y in -10i64..10 {
                for z in -10i64..10 {
                    assert!(seen.insert(b.hash_one((x, y, z))));
                    assert!(seen_arrays.insert(b.hash_one([x, y, z])));
                }
            }
        }
    }
}
