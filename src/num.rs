//! Float-to-integer and f64-to-f32 conversions, in one place with their reasons.
//!
//! Rust's `as` from a float to an integer drops the fraction and saturates: NaN gives 0,
//! a value below or above the type's range gives its bound. The helpers below are that
//! conversion, named for what their callers rely on, so each call site says which it is
//! and no `as` that may drop bits goes unexplained (`clippy::cast_possible_truncation`).

/// A count or an index from a float the caller has already rounded (`ceil`, `round`,
/// `floor`) and knows to be at least 0: a count of samples or steps along a length, or
/// a grid offset from the grid's low corner. Saturates: NaN and negatives give 0, beyond
/// `usize::MAX` gives `usize::MAX` (callers cap counts by model values checked at load,
/// and grids by the extent guard, `crate::method::extent`).
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
#[inline]
pub(crate) fn to_usize(x: f64) -> usize {
    // Saturating by the definition of `as` (see the function's doc).
    x as usize
}

/// [`to_usize`] for a count a file declares as a number (a PLY list length), already
/// checked to be a whole number of at most 32 bits.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
#[inline]
pub(crate) fn to_u64(x: f64) -> u64 {
    // Saturating by the definition of `as` (see the function's doc).
    x as u64
}

/// A count declared by a file (`u64`) as the size of a preallocation, capped at `cap`:
/// the memory follows what is read, not what a header says.
#[inline]
pub(crate) fn capacity(count: u64, cap: usize) -> usize {
    usize::try_from(count).map_or(cap, |n| n.min(cap))
}

/// A vertex index as a triangle holds it (`u32`), saturating. Every index is below its
/// mesh's vertex count, which the mesh readers keep under `u32::MAX` (a mesh file is at
/// most 1 GiB; `cloud::mesh` checks the count), and the meshes built in code (furniture,
/// posed agents) have thousands, so the saturation never happens.
#[inline]
pub(crate) fn index32<T: TryInto<u32>>(i: T) -> u32 {
    i.try_into().unwrap_or(u32::MAX)
}

/// A signed grid index or cell offset from a float the caller has rounded. Saturates as
/// [`to_usize`]: after the extent guard (|coordinate| at most 1e7 m, cells of at least
/// 2 mm) an index is below 2^33, far inside `i64`.
#[allow(clippy::cast_possible_truncation)]
#[inline]
pub(crate) fn to_i64(x: f64) -> i64 {
    // Saturating by the definition of `as` (see the function's doc).
    x as i64
}

/// `to_i64(v.floor())` without a call to libm's `floor` (x86-64 without SSE4.1 has no
/// rounding instruction, so `floor` is a function call): the same value for every `v`,
/// NaN and infinities included (saturating as `as` does; test
/// `floor_i64_is_to_i64_of_floor`). For the grid keys computed per point.
#[inline]
pub(crate) fn floor_i64(v: f64) -> i64 {
    let t = to_i64(v);
    // `t` is `v` rounded toward zero (saturated): as an f64 it exceeds `v` only for a
    // negative `v` with a fraction, or below i64's range (kept at i64::MIN).
    t.saturating_sub(i64::from((t as f64) > v))
}

/// [`to_i64`] for offsets that index slices (`isize`), e.g. a few cells around a point.
#[allow(clippy::cast_possible_truncation)]
#[inline]
pub(crate) fn to_isize(x: f64) -> isize {
    // Saturating by the definition of `as` (see the function's doc).
    x as isize
}

/// The nearest `f32`, for parry3d's geometry and the 32-bit fields of the file formats:
/// metres in a scene kept within 1e7 m by the extent guard lose only precision below
/// their f32 resolution, never range (beyond ±`f32::MAX` gives ±infinity).
#[allow(clippy::cast_possible_truncation)]
#[inline]
pub(crate) fn to_f32(x: f64) -> f32 {
    // Rounds to nearest by the definition of `as` (see the function's doc).
    x as f32
}

/// `i as f64` for an index or a count: the same value (the integer rounded to the nearest
/// `f64`), converted from `i64` where it fits, which x86-64 does in one instruction
/// (`usize` needs a sequence of several, `i64` being the widest signed conversion it has).
/// For the per-sample and per-cell arithmetic of the contact search and the distance
/// field.
#[inline]
pub(crate) fn index_f64(i: usize) -> f64 {
    match i64::try_from(i) {
        Ok(j) => j as f64,
        Err(_) => i as f64,
    }
}

/// `i as f32`, as [`index_f64`] for `f64` (the same value: the integer rounded to the
/// nearest `f32`).
#[inline]
pub(crate) fn index_f32(i: usize) -> f32 {
    match i64::try_from(i) {
        Ok(j) => j as f32,
        Err(_) => i as f32,
    }
}

/// `i as f32` for an index into a slice (or a slice's length), in one instruction on
/// x86-64: such an index is at most `isize::MAX` (Rust's limit on an allocation), so as
/// an `i64` it is the same number and converts to the same `f32`. For the positions of
/// the distance transform's lines.
#[inline]
pub(crate) fn slice_index_f32(i: usize) -> f32 {
    debug_assert!(isize::try_from(i).is_ok());
    // At most isize::MAX (see the function's doc): the same value as an i64.
    i as i64 as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`floor_i64`] against `to_i64(v.floor())` on values around integers (both signs,
    /// up to beyond 2^63), NaN, infinities, zeros, subnormals and seeded random bit
    /// patterns.
    #[test]
    fn floor_i64_is_to_i64_of_floor() {
        use rand::{RngExt, SeedableRng};
        let mut values = vec![
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
        ];
        for e in 0..70 {
            let b = 2f64.powi(e);
            for v in [b, b + 0.5, b - 0.5, b.next_up(), b.next_down()] {
                values.extend([v, -v]);
            }
        }
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for _ in 0..200_000 {
            values.push(f64::from_bits(rng.random::<u64>()));
            values.push(rng.random_range(-1e6..1e6));
        }
        for v in values {
            assert_eq!(floor_i64(v), to_i64(v.floor()), "{v:e}");
        }
    }

    /// [`index_f64`], [`index_f32`] and [`slice_index_f32`] (up to `isize::MAX`) against `as` on small and large values, powers of
    /// two and their neighbours (where rounding ties fall), past `i64::MAX`, and seeded
    /// random values.
    #[test]
    fn index_conversions_equal_as() {
        use rand::{RngExt, SeedableRng};
        let mut values: Vec<usize> = (0..10_000).collect();
        for e in 0..usize::BITS {
            let b = 1usize << e;
            values.extend([b, b - 1, b + 1, b | (b >> 1), (b | (b >> 1)) + 1]);
        }
        values.extend([
            usize::MAX,
            usize::MAX - 1,
            usize::MAX / 2,
            usize::MAX / 2 + 1,
        ]);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        for _ in 0..200_000 {
            values.push(usize::try_from(rng.random::<u64>()).unwrap_or(usize::MAX));
            values.push(rng.random_range(0..1usize << 30));
        }
        for i in values {
            assert_eq!(index_f64(i).to_bits(), (i as f64).to_bits(), "{i}");
            assert_eq!(index_f32(i).to_bits(), (i as f32).to_bits(), "{i}");
            if isize::try_from(i).is_ok() {
                assert_eq!(slice_index_f32(i).to_bits(), (i as f32).to_bits(), "{i}");
            }
        }
    }
}
