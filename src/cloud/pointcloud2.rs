//! Decoding `sensor_msgs/PointCloud2` messages by hand: ROS 2 (CDR, either byte order)
//! and ROS 1 serialisation. The layout is small and fixed; only the `x`, `y`, `z` fields
//! are read, whatever their type, offset and order, organised clouds (height > 1, rows
//! possibly padded) or not, with the point data in either byte order (`is_bigendian`).

use crate::num::to_f32;
use nalgebra::Point3;

/// How a message was serialised.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Encoding {
    /// ROS 2: a 4-byte CDR encapsulation header (big or little endian), then CDR with
    /// every primitive aligned to its size.
    Cdr,
    /// ROS 1: little endian, packed, a `seq` in the header, strings without a NUL.
    Ros1,
}

/// A decoded cloud: the points in the message's frame (`frame_id`), as sent (metres in
/// ROS), and the header's stamp.
#[derive(Debug, Clone, PartialEq)]
pub struct Decoded {
    /// The header's `frame_id`.
    pub frame_id: String,
    /// The header's stamp, nanoseconds since the epoch of the publisher's clock.
    pub stamp_ns: i128,
    /// Every point of the message, row after row (NaN points kept; the caller drops them).
    pub points: Vec<Point3<f64>>,
}

/// Reads primitives with CDR or ROS 1 rules, remembering where it is for errors.
struct Cursor<'a> {
    buf: &'a [u8],
    pos: usize,
    /// Where alignment is counted from (after the CDR encapsulation header).
    origin: usize,
    little: bool,
    align: bool,
}

impl<'a> Cursor<'a> {
    /// A primitive of `n` bytes, aligned to `n` under CDR.
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if self.align && n > 1 {
            let rel = self.pos - self.origin;
            self.pos += (n - rel % n) % n;
        }
        self.bytes(n, what)
    }

    /// `n` bytes of a string or byte sequence (no alignment).
    fn bytes(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.pos.checked_add(n).filter(|&e| e <= self.buf.len());
        let Some(end) = end else {
            return Err(format!(
                "byte {}: the message ends inside {what} ({} bytes)",
                self.pos.min(self.buf.len()),
                self.buf.len()
            ));
        };
        let s = &self.buf[self.pos..end];
        self.pos = end;
        Ok(s)
    }

    fn u8(&mut self, what: &str) -> Result<u8, String> {
        Ok(self.take(1, what)?[0])
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b: [u8; 4] = self.take(4, what)?.try_into().unwrap_or_default();
        Ok(if self.little {
            u32::from_le_bytes(b)
        } else {
            u32::from_be_bytes(b)
        })
    }

    /// A string: its length (with the NUL in CDR), then the bytes.
    fn string(&mut self, what: &str) -> Result<String, String> {
        let at = self.pos;
        let n = self.u32(what)? as usize;
        if n > self.buf.len() {
            return Err(format!("byte {at}: {what} claims {n} bytes"));
        }
        let mut s = self.bytes(n, what)?;
        if let [head @ .., 0] = s {
            s = head;
        }
        Ok(String::from_utf8_lossy(s).into_owned())
    }
}

/// The PointField datatypes of ROS: size in bytes, by code (1 = INT8 ... 8 = FLOAT64).
fn type_size(code: u8) -> Option<usize> {
    match code {
        1 | 2 => Some(1),
        3 | 4 => Some(2),
        5..=7 => Some(4),
        8 => Some(8),
        _ => None,
    }
}

/// One value of PointField type `code` from `b` (exactly its size).
fn value(code: u8, b: &[u8], big: bool) -> f64 {
    macro_rules! num {
        ($t:ty) => {{
            let a = b.try_into().unwrap_or_default();
            (if big {
                <$t>::from_be_bytes(a)
            } else {
                <$t>::from_le_bytes(a)
            }) as f64
        }};
    }
    match code {
        1 => num!(i8),
        2 => num!(u8),
        3 => num!(i16),
        4 => num!(u16),
        5 => num!(i32),
        6 => num!(u32),
        7 => num!(f32),
        _ => num!(f64),
    }
}

/// Decodes one serialised `sensor_msgs/PointCloud2`. Errors say which byte or field.
pub fn decode(buf: &[u8], encoding: Encoding) -> Result<Decoded, String> {
    let mut c = match encoding {
        Encoding::Cdr => {
            let little = match buf.get(..2) {
                Some([0, 1]) => true,
                Some([0, 0]) => false,
                Some(h) => {
                    return Err(format!(
                    "byte 0: CDR encapsulation {:#04x}{:02x} is not plain CDR (0x0000 or 0x0001)",
                    h[0], h[1]
                ))
                }
                None => return Err("byte 0: the message is shorter than its CDR header".into()),
            };
            if buf.len() < 4 {
                return Err("byte 0: the message is shorter than its CDR header".into());
            }
            Cursor {
                buf,
                pos: 4,
                origin: 4,
                little,
                align: true,
            }
        }
        Encoding::Ros1 => Cursor {
            buf,
            pos: 0,
            origin: 0,
            little: true,
            align: false,
        },
    };
    if encoding == Encoding::Ros1 {
        c.u32("header.seq")?;
    }
    let sec = c.u32("header.stamp")?;
    let nsec = c.u32("header.stamp")?;
    let sec = match encoding {
        Encoding::Cdr => sec as i32 as i128,
        Encoding::Ros1 => sec as i128,
    };
    let stamp_ns = sec * 1_000_000_000 + nsec as i128;
    let frame_id = c.string("header.frame_id")?;
    // Sizes in u128: products of two u32 fields cannot overflow.
    let height = c.u32("height")? as u128;
    let width = c.u32("width")? as u128;
    let nfields_at = c.pos;
    let nfields = c.u32("fields")? as usize;
    // Each field takes at least 13 bytes: a bound before allocating anything.
    if nfields > buf.len() / 13 {
        return Err(format!(
            "byte {nfields_at}: {nfields} fields cannot fit in {} bytes",
            buf.len()
        ));
    }
    let mut xyz: [Option<(usize, u8)>; 3] = [None; 3];
    let mut need = 0usize;
    for k in 0..nfields {
        let name = c.string("a field name")?;
        let offset = c.u32("a field offset")? as usize;
        let at = c.pos;
        let datatype = c.u8("a field datatype")?;
        let count = c.u32("a field count")?;
        let slot = match name.as_str() {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        if let Some(s) = slot {
            let size = type_size(datatype).ok_or_else(|| {
                format!("byte {at}: field {k} '{name}' has unknown datatype {datatype}")
            })?;
            if count == 0 {
                return Err(format!("field {k} '{name}' has count 0"));
            }
            xyz[s] = Some((offset, datatype));
            need = need.max(offset.saturating_add(size));
        }
    }
    let [Some(fx), Some(fy), Some(fz)] = xyz else {
        return Err("the message has no x, y and z fields".into());
    };
    let big = c.u8("is_bigendian")? != 0;
    let point_step = c.u32("point_step")? as u128;
    let row_step = c.u32("row_step")? as u128;
    let data_len = c.u32("data")? as usize;
    let data_at = c.pos;
    let data = c.bytes(data_len, "data")?;
    let points = width * height;
    if points == 0 {
        return Ok(Decoded {
            frame_id,
            stamp_ns,
            points: Vec::new(),
        });
    }
    if (need as u128) > point_step {
        return Err(format!(
            "point_step {point_step} is shorter than the x, y, z fields (they end at byte {need})"
        ));
    }
    let row = if height > 1 {
        if row_step < width * point_step {
            return Err(format!(
                "row_step {row_step} is shorter than width {width} x point_step {point_step}"
            ));
        }
        row_step
    } else {
        width * point_step
    };
    let last = (height - 1) * row + (width - 1) * point_step + need as u128;
    if last > data.len() as u128 {
        return Err(format!(
            "byte {data_at}: data holds {} bytes, {height} x {width} points of {point_step} bytes need {last}",
            data.len()
        ));
    }
    let read = |base: usize, (off, code): (usize, u8)| {
        let size = type_size(code).unwrap_or(1);
        value(code, &data[base + off..base + off + size], big)
    };
    let mut out = Vec::with_capacity(points as usize);
    for r in 0..height as usize {
        for col in 0..width as usize {
            let base = r * row as usize + col * point_step as usize;
            out.push(Point3::new(read(base, fx), read(base, fy), read(base, fz)));
        }
    }
    Ok(Decoded {
        frame_id,
        stamp_ns,
        points: out,
    })
}

/// A length as the message's 32-bit field.
///
/// # Panics
/// When it does not fit: a message of 4 GiB or more cannot be written.
fn len32(n: usize) -> u32 {
    u32::try_from(n).expect("a PointCloud2 message under 4 GiB (its lengths are 32-bit)")
}

/// Serialises a `sensor_msgs/PointCloud2` with float32 `x, y, z` (and `pad` float32 fields
/// before them, to exercise offsets) as ROS 2 CDR: the inverse of [`decode`], for tests,
/// fuzz seeds and examples. `height` rows of `points.len() / height` points; `row_pad`
/// bytes after each row; `little` picks the CDR byte order and `big_data` the data's.
///
/// # Panics
/// When the message would be 4 GiB or more (its lengths are 32-bit).
pub fn encode_cdr(
    points: &[Point3<f64>],
    height: u32,
    pad: usize,
    row_pad: usize,
    little: bool,
    big_data: bool,
) -> Vec<u8> {
    let mut w = Writer {
        out: vec![0, u8::from(little), 0, 0],
        little,
    };
    w.u32(12);
    w.u32(34);
    w.string("camera_depth_optical_frame");
    let height = height.max(1);
    let width = len32(points.len()) / height;
    w.u32(height);
    w.u32(width);
    let names: Vec<String> = (0..pad)
        .map(|i| format!("pad{i}"))
        .chain(["x", "y", "z"].map(String::from))
        .collect();
    w.u32(len32(names.len()));
    for (i, n) in names.iter().enumerate() {
        w.string(n);
        w.u32(len32(4 * i));
        w.out.push(7);
        w.u32(1);
    }
    w.out.push(u8::from(big_data));
    let point_step = 4 * names.len();
    let row_step = width as usize * point_step + row_pad;
    w.u32(len32(point_step));
    w.u32(len32(row_step));
    let mut data = Vec::new();
    for r in 0..height as usize {
        for p in &points[r * width as usize..(r + 1) * width as usize] {
            data.extend(std::iter::repeat_n(0u8, 4 * pad));
            for k in 0..3 {
                let v = to_f32(p[k]);
                data.extend(if big_data {
                    v.to_be_bytes()
                } else {
                    v.to_le_bytes()
                });
            }
        }
        data.extend(std::iter::repeat_n(0xAAu8, row_pad));
    }
    w.u32(len32(data.len()));
    w.out.extend(data);
    w.out.push(1);
    w.out
}

struct Writer {
    out: Vec<u8>,
    little: bool,
}

impl Writer {
    fn u32(&mut self, v: u32) {
        while !(self.out.len() - 4).is_multiple_of(4) {
            self.out.push(0);
        }
        self.out.extend(if self.little {
            v.to_le_bytes()
        } else {
            v.to_be_bytes()
        });
    }

    fn string(&mut self, s: &str) {
        self.u32(len32(s.len() + 1));
        self.out.extend(s.as_bytes());
        self.out.push(0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pts(n: usize) -> Vec<Point3<f64>> {
        (0..n)
            .map(|i| Point3::new(i as f64 * 0.5, -(i as f64) * 0.25, 1.0 + i as f64))
            .collect()
    }

    #[test]
    fn every_byte_order_padding_and_organisation_round_trips() {
        let p = pts(6);
        for little in [true, false] {
            for big_data in [true, false] {
                for (height, pad, row_pad) in [(1, 0, 0), (2, 1, 3), (3, 2, 8), (6, 0, 1)] {
                    let buf = encode_cdr(&p, height, pad, row_pad, little, big_data);
                    let d = decode(&buf, Encoding::Cdr).unwrap();
                    assert_eq!(d.points, p, "{little} {big_data} {height} {pad} {row_pad}");
                    assert_eq!(d.frame_id, "camera_depth_optical_frame");
                    assert_eq!(d.stamp_ns, 12_000_000_034);
                }
            }
        }
    }

    #[test]
    fn ros1_layout_with_double_and_int_fields() {
        let mut b = Vec::new();
        let u = |b: &mut Vec<u8>, v: u32| b.extend(v.to_le_bytes());
        u(&mut b, 7); // seq
        u(&mut b, 3); // sec
        u(&mut b, 5); // nsec
        u(&mut b, 3);
        b.extend(b"map");
        u(&mut b, 1); // height
        u(&mut b, 2); // width
        u(&mut b, 3); // fields: z (int16 at 0), x (float64 at 2), y (uint8 at 10)
        for (name, off, ty) in [("z", 0u32, 3u8), ("x", 2, 8), ("y", 10, 2)] {
            u(&mut b, 1);
            b.extend(name.as_bytes());
            u(&mut b, off);
            b.push(ty);
            u(&mut b, 1);
        }
        b.push(0);
        u(&mut b, 11);
        u(&mut b, 22);
        u(&mut b, 22);
        for (z, x, y) in [(-3i16, 1.5f64, 200u8), (4, -2.25, 0)] {
            b.extend(z.to_le_bytes());
            b.extend(x.to_le_bytes());
            b.push(y);
        }
        b.push(1);
        let d = decode(&b, Encoding::Ros1).unwrap();
        assert_eq!(d.frame_id, "map");
        assert_eq!(d.stamp_ns, 3_000_000_005);
        assert_eq!(
            d.points,
            [Point3::new(1.5, 200.0, -3.0), Point3::new(-2.25, 0.0, 4.0)]
        );
    }

    #[test]
    fn damaged_messages_are_errors_not_panics() {
        let buf = encode_cdr(&pts(4), 2, 1, 2, true, false);
        // Every cut before the trailing is_dense byte (not needed for the points) fails.
        for n in 0..buf.len() - 1 {
            assert!(decode(&buf[..n], Encoding::Cdr).is_err(), "cut at {n}");
        }
        let mut bad = buf.clone();
        bad[1] = 3;
        let e = decode(&bad, Encoding::Cdr).unwrap_err();
        assert!(e.contains("encapsulation"), "{e}");
        // A row_step below width x point_step is refused.
        let mut short = encode_cdr(&pts(4), 2, 0, 0, true, false);
        let d = decode(&short, Encoding::Cdr).unwrap();
        assert_eq!(d.points.len(), 4);
        let data_len_at = short.len() - 1 - 4 * 3 * 4 - 4;
        let row_step_at = data_len_at - 4;
        short[row_step_at..row_step_at + 4].copy_from_slice(&4u32.to_le_bytes());
        let e = decode(&short, Encoding::Cdr).unwrap_err();
        assert!(e.contains("row_step 4"), "{e}");
    }
}
