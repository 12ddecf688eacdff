//! A multiplicative hasher for integer cell keys (the Fx hash of rustc), for the hash maps
//! keyed by grid cells (segmentation's cells, the point-spacing tiles and search cells,
//! the extent guard's coarse cubes). SipHash's protection against chosen keys is of no
//! use for cells of a point cloud, and its seeds are random: no result may depend on the
//! maps' order, only their look-ups (each user says why its results do not). Also the
//! connected components of occupied cubes that the extent guard and the specks stage
//! both find ([`component_roots`]), and the box of cubes both index densely ([`CubeBox`]).

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};
use std::ops::Range;

use nalgebra::Point3;
use rayon::prelude::*;

use crate::num::floor_i64;

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

/// The box of the cubes of edge `cell` metres (cube `k` holds the points whose
/// coordinates `c` have `floor(c / cell) = k` along each axis) that hold a set of points:
/// its least cube and its extent in cubes along x, y and z. A cube index is monotone in
/// its coordinate, so the box comes from the points' least and greatest coordinates.
/// Cubes inside it are indexed x-major: offset `(x, y, z)` at `(x * ny + y) * nz + z`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct CubeBox {
    /// The least cube.
    pub(crate) lo: [i64; 3],
    /// Cubes along x, y and z.
    pub(crate) dims: [usize; 3],
}

impl CubeBox {
    /// The box of the cubes of `points` (the bounds reduced in parallel pieces of at least
    /// `piece` points), or `None` without points, for a `cell` not positive, a coordinate
    /// not finite, or a span of more cubes than `usize` counts.
    pub(crate) fn of(points: &[Point3<f64>], cell: f64, piece: usize) -> Option<CubeBox> {
        let (lo, hi) = points
            .par_iter()
            .with_min_len(piece)
            .map(|p| (p.coords, p.coords))
            .reduce_with(|(lo, hi), (l, h)| (lo.inf(&l), hi.sup(&h)))?;
        if !(cell > 0.0 && lo.iter().chain(hi.iter()).all(|c| c.is_finite())) {
            return None;
        }
        let (lo, hi) = (
            Self::cube_of(&lo.into(), cell),
            Self::cube_of(&hi.into(), cell),
        );
        let mut dims = [0usize; 3];
        for a in 0..3 {
            dims[a] = usize::try_from(hi[a].checked_sub(lo[a])?)
                .ok()?
                .checked_add(1)?;
        }
        Some(CubeBox { lo, dims })
    }

    /// The cube of edge `cell` holding `p`.
    pub(crate) fn cube_of(p: &Point3<f64>, cell: f64) -> [i64; 3] {
        [p.x, p.y, p.z].map(|c| floor_i64(c / cell))
    }

    /// Cubes in the box, or `None` past `usize`.
    pub(crate) fn len(&self) -> Option<usize> {
        self.dims.iter().try_fold(1usize, |n, &d| n.checked_mul(d))
    }

    /// The offset of cube `k` in the box, if inside.
    pub(crate) fn offset(&self, k: [i64; 3]) -> Option<[usize; 3]> {
        let mut o = [0usize; 3];
        for a in 0..3 {
            o[a] = usize::try_from(k[a].checked_sub(self.lo[a])?).ok()?;
            if o[a] >= self.dims[a] {
                return None;
            }
        }
        Some(o)
    }

    /// The index of offset `o` (inside the box).
    pub(crate) fn index(&self, [x, y, z]: [usize; 3]) -> usize {
        (x * self.dims[1] + y) * self.dims[2] + z
    }

    /// The offset of index `i` (inside the box).
    pub(crate) fn offset_of_index(&self, i: usize) -> [usize; 3] {
        let [_, ny, nz] = self.dims;
        [i / (ny * nz), i / nz % ny, i % nz]
    }

    /// The offset one step `(dx, dy, dz)` from offset `o`, if inside the box.
    pub(crate) fn step(&self, o: [usize; 3], (dx, dy, dz): (i64, i64, i64)) -> Option<[usize; 3]> {
        let mut n = [0usize; 3];
        for (a, d) in [dx, dy, dz].into_iter().enumerate() {
            n[a] = o[a]
                .checked_add_signed(isize::try_from(d).ok()?)
                .filter(|&v| v < self.dims[a])?;
        }
        Some(n)
    }

    /// The cube at offset `o` (inside the box: the offsets fit `i64`, as its span did).
    pub(crate) fn cube(&self, o: [usize; 3]) -> [i64; 3] {
        [0, 1, 2].map(|a| self.lo[a] + i64::try_from(o[a]).unwrap_or(0))
    }
}

/// Items per piece of [`key_runs`]: a piece's keys cost tens of microseconds, well above
/// a task's overhead on rayon's pool. The runs do not depend on it.
const RUN_PIECE: usize = 16 * 1024;

/// The maximal runs of consecutive `items` with one key (`key` of `None`: in no run), in
/// order, each with its key and its items' index range: what a loop over the items that
/// looks a cell up once per run of points in it (as a depth image's rows give) sees. The
/// keys are computed in parallel pieces of [`RUN_PIECE`] items, and a run cut by a
/// piece's border is joined again, so the runs are the same whatever the thread count.
pub(crate) fn key_runs<T, K>(
    items: &[T],
    key: impl Fn(&T) -> Option<K> + Sync,
) -> Vec<(K, Range<usize>)>
where
    T: Sync,
    K: Copy + PartialEq + Send,
{
    let pieces: Vec<Vec<(K, Range<usize>)>> = items
        .par_chunks(RUN_PIECE)
        .enumerate()
        .map(|(n, piece)| {
            let base = n * RUN_PIECE;
            let mut runs: Vec<(K, Range<usize>)> = Vec::new();
            for (i, item) in piece.iter().enumerate() {
                let Some(k) = key(item) else { continue };
                match runs.last_mut() {
                    Some((lk, r)) if *lk == k && r.end == base + i => r.end += 1,
                    _ => runs.push((k, base + i..base + i + 1)),
                }
            }
            runs
        })
        .collect();
    let mut out: Vec<(K, Range<usize>)> = Vec::with_capacity(pieces.iter().map(Vec::len).sum());
    for piece in pieces {
        let mut rest = piece.into_iter().peekable();
        if let (Some((lk, last)), Some((k, first))) = (out.last_mut(), rest.peek()) {
            if lk == k && last.end == first.start {
                last.end = first.end;
                rest.next();
            }
        }
        out.extend(rest);
    }
    out
}

/// The 13 neighbour offsets after `(0, 0, 0)` in lexicographic order: with their
/// opposites, the 26 cubes round a cube (through faces, edges and corners).
pub(crate) const HALF_NEIGHBOURS: [(i64, i64, i64); 13] = [
    (0, 0, 1),
    (0, 1, -1),
    (0, 1, 0),
    (0, 1, 1),
    (1, -1, -1),
    (1, -1, 0),
    (1, -1, 1),
    (1, 0, -1),
    (1, 0, 0),
    (1, 0, 1),
    (1, 1, -1),
    (1, 1, 0),
    (1, 1, 1),
];

/// The key of the cube at offset `d` from cube `k` (wrapping at `i64`'s ends, where the
/// saturated keys of far coordinates lie: a wrong neighbour there joins nothing real).
pub(crate) fn offset_key(k: [i64; 3], (dx, dy, dz): (i64, i64, i64)) -> [i64; 3] {
    [
        k[0].wrapping_add(dx),
        k[1].wrapping_add(dy),
        k[2].wrapping_add(dz),
    ]
}

/// For each of `n` cubes, the least number of a cube in its 26-connected component, where
/// `neighbour(i, d)` is the number of the occupied cube at offset `d` from cube `i`, if
/// any (an empty cube has no neighbours and is its own component). Union-find: each cube
/// is joined with its neighbours on the 13 sides after it ([`HALF_NEIGHBOURS`]), which
/// meets every one of the 26 adjacencies once, the smaller root becoming the parent; the
/// roots are the components' least numbers whatever the order of the joins.
pub(crate) fn component_roots(
    n: usize,
    neighbour: impl Fn(usize, (i64, i64, i64)) -> Option<usize>,
) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    for i in 0..n {
        for d in HALF_NEIGHBOURS {
            if let Some(j) = neighbour(i, d) {
                join(&mut parent, i, j);
            }
        }
    }
    (0..n).map(|i| find(&mut parent, i)).collect()
}

/// The root of `x` in the union-find forest `parent`, halving the path on the way.
pub(crate) fn find(parent: &mut [usize], mut x: usize) -> usize {
    while parent[x] != x {
        parent[x] = parent[parent[x]];
        x = parent[x];
    }
    x
}

/// Joins the sets of `a` and `b` in the union-find forest `parent`, the smaller root
/// becoming the parent (so each set's root is its least member).
pub(crate) fn join(parent: &mut [usize], a: usize, b: usize) {
    let (a, b) = (find(parent, a), find(parent, b));
    parent[a.max(b)] = a.min(b);
}

/// `f` run on a pool of `threads` threads, for tests that compare results across thread
/// counts.
#[cfg(test)]
pub(crate) fn on_threads<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("a test pool")
        .install(f)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cube_box_indexes_its_cubes_and_steps_inside_it() {
        let pts = [
            Point3::new(-0.25, 0.0, 0.31),
            Point3::new(0.29, -0.11, 0.0),
            Point3::new(0.05, 0.39, 0.12),
        ];
        let b = CubeBox::of(&pts, 0.1, 1).unwrap();
        assert_eq!(b.lo, [-3, -2, 0]);
        assert_eq!(b.dims, [6, 6, 4]);
        assert_eq!(b.len(), Some(144));
        for p in &pts {
            let k = CubeBox::cube_of(p, 0.1);
            let o = b.offset(k).unwrap();
            assert_eq!(b.offset_of_index(b.index(o)), o);
            assert_eq!(b.cube(o), k);
        }
        assert_eq!(b.offset([3, 0, 0]), None);
        assert_eq!(b.step([0, 0, 0], (0, 0, -1)), None);
        assert_eq!(b.step([0, 0, 0], (1, 1, 1)), Some([1, 1, 1]));
        assert_eq!(b.step([5, 5, 3], (1, 0, 0)), None);
        assert_eq!(CubeBox::of(&pts, 0.0, 1), None);
        assert_eq!(CubeBox::of(&[], 0.1, 1), None);
        assert_eq!(
            CubeBox::of(&[Point3::new(f64::NAN, 0.0, 0.0)], 0.1, 1),
            None
        );
    }

    #[test]
    fn the_offsets_and_their_opposites_are_the_26_neighbours() {
        let mut all: Vec<(i64, i64, i64)> = HALF_NEIGHBOURS
            .iter()
            .flat_map(|&(x, y, z)| [(x, y, z), (-x, -y, -z)])
            .collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 26);
        assert!(!all.contains(&(0, 0, 0)));
    }

    /// The runs one loop over the items finds, for [`key_runs`] to be compared with.
    fn runs_one_by_one(
        items: &[i64],
        key: impl Fn(&i64) -> Option<i64>,
    ) -> Vec<(i64, Range<usize>)> {
        let mut runs: Vec<(i64, Range<usize>)> = Vec::new();
        for (i, item) in items.iter().enumerate() {
            let Some(k) = key(item) else { continue };
            match runs.last_mut() {
                Some((lk, r)) if *lk == k && r.end == i => r.end += 1,
                _ => runs.push((k, i..i + 1)),
            }
        }
        runs
    }

    /// Runs across the pieces' borders (a run longer than a piece, one ending at a border,
    /// a gap of keyless items at one) are the runs of one loop, at 1 and 3 threads.
    #[test]
    fn runs_in_pieces_are_the_runs_of_one_loop() {
        let mut items: Vec<i64> = Vec::new();
        // A run of 2.5 pieces, then short runs, then keyless items round a border.
        items.extend(std::iter::repeat_n(7, RUN_PIECE * 5 / 2));
        items.extend((0..RUN_PIECE as i64 / 2).map(|i| i / 3));
        items.extend(std::iter::repeat_n(-1, 10));
        items.extend(std::iter::repeat_n(5, RUN_PIECE));
        // The same key on both sides of a border, once joined and once split by a gap.
        let border = items.len().next_multiple_of(RUN_PIECE);
        items.resize(border, 9);
        items.extend([9, 9, -1, 9, 4]);
        let key = |v: &i64| (*v >= 0).then_some(*v % 10);
        let want = runs_one_by_one(&items, key);
        for threads in [1, 3] {
            assert_eq!(
                on_threads(threads, || key_runs(&items, key)),
                want,
                "{threads} threads"
            );
        }
        // Without the join at the borders there would be more runs.
        let pieces: usize = items
            .chunks(RUN_PIECE)
            .map(|c| runs_one_by_one(c, key).len())
            .sum();
        assert!(pieces > want.len());
    }

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
