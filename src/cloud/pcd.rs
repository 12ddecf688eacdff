//! PCD reader (Point Cloud Library format, header versions 0.6 and 0.7).
//!
//! Handles `DATA ascii`, `binary` (packed row-major records) and `binary_compressed`
//! (LZF-compressed, fields stored column by column), fields of any size, type and count in
//! any order, and the `VIEWPOINT` pose, which is applied to every point.

use std::fs::File;
use std::io::{self, BufReader, Read};
use std::path::Path;

use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

use super::ply::{
    body_err, header_err, io_err, next_header_line, read_line_capped, shorten, Line, MAX_PREALLOC,
};
use super::CloudError;
use crate::num::{capacity, to_f32};

/// Largest output one LZF input byte can produce (a 3-byte back reference yields 264 bytes).
const LZF_MAX_RATIO: u64 = 88;
/// Most bytes one point's record may take: one field of the largest COUNT (1048576) of
/// 8 bytes and as much again; real clouds take a few dozen bytes. The record buffer is
/// allocated before any point is read, so this bounds what a header alone can ask for.
const MAX_RECORD: usize = 16 << 20;

/// One field of a PCD record.
#[derive(Debug, Clone)]
struct Field {
    name: String,
    /// Bytes per value: 1, 2, 4 or 8.
    size: usize,
    /// `I` (signed), `U` (unsigned) or `F` (float).
    ty: u8,
    /// Values per point.
    count: usize,
}

impl Field {
    fn bytes(&self) -> usize {
        self.size * self.count
    }

    /// Whether the values are 4-byte floats (`F 4`, the common layout of x, y, z), which
    /// the readers decode with [`f32_le`] rather than [`Field::decode`].
    fn is_f32(&self) -> bool {
        self.ty == b'F' && self.size == 4
    }

    /// Decodes one little-endian value (`b` is exactly `self.size` bytes).
    fn decode(&self, b: &[u8]) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                <$t>::from_le_bytes(a)
            }};
        }
        match (self.ty, self.size) {
            (b'F', 4) => f32_le(b),
            (b'F', _) => num!(f64, 8),
            (b'I', 1) => f64::from(b[0] as i8),
            (b'I', 2) => f64::from(num!(i16, 2)),
            (b'I', 4) => f64::from(num!(i32, 4)),
            (b'I', _) => num!(i64, 8) as f64,
            (_, 1) => f64::from(b[0]),
            (_, 2) => f64::from(num!(u16, 2)),
            (_, 4) => f64::from(num!(u32, 4)),
            (_, _) => num!(u64, 8) as f64,
        }
    }
}

/// The little-endian `f32` at the start of `b` (at least 4 bytes): what [`Field::decode`]
/// gives for an `F 4` field.
fn f32_le(b: &[u8]) -> f64 {
    let mut a = [0u8; 4];
    a.copy_from_slice(&b[..4]);
    f64::from(f32::from_le_bytes(a))
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Data {
    Ascii,
    Binary,
    Compressed,
}

/// A parsed PCD header.
struct Header {
    fields: Vec<Field>,
    points: u64,
    data: Data,
    /// Viewpoint rotation and translation, if not the identity.
    pose: Option<(UnitQuaternion<f64>, Vector3<f64>)>,
    /// Bytes taken by the header, up to and including the `DATA` line.
    len: u64,
    /// Lines taken by the header.
    lines: usize,
    /// Bytes per packed record.
    record: usize,
    /// For x, y, z: index of the field, byte offset of the field in a record, and the index of
    /// its first value among all values of a record (for ascii).
    xyz: [(usize, usize, usize); 3],
}

fn parse_header<R: io::BufRead>(path: &Path, r: &mut R) -> Result<Header, CloudError> {
    let mut names: Option<(Vec<String>, usize)> = None;
    let mut sizes: Option<(Vec<String>, usize)> = None;
    let mut types: Option<(Vec<String>, usize)> = None;
    let mut counts: Option<(Vec<String>, usize)> = None;
    let mut width: Option<u64> = None;
    let mut height: Option<u64> = None;
    let mut points: Option<(u64, usize)> = None;
    let mut pose = None;
    let mut len = 0u64;
    let mut lineno = 0usize;
    let data = loop {
        lineno += 1;
        let at = format!("line {lineno}");
        let text = next_header_line(
            path,
            r,
            lineno,
            &mut len,
            "the 'DATA' line",
            "header line is not text (not a PCD file?)",
        )?;
        let text = text.trim_start_matches('\u{feff}').trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let mut words = text.split_whitespace();
        let key = words.next().unwrap_or_default().to_ascii_uppercase();
        let rest: Vec<String> = words.map(str::to_string).collect();
        let one_int = |what: &str| -> Result<u64, CloudError> {
            match rest.as_slice() {
                [v] => v.parse::<u64>().map_err(|_| {
                    header_err(
                        path,
                        &at,
                        format!("{what} '{}' is not a non-negative integer", shorten(v)),
                    )
                }),
                _ => Err(header_err(path, &at, format!("expected '{what} <number>'"))),
            }
        };
        match key.as_str() {
            "VERSION" => {}
            "FIELDS" | "COLUMNS" => names = Some((rest, lineno)),
            "SIZE" => sizes = Some((rest, lineno)),
            "TYPE" => types = Some((rest, lineno)),
            "COUNT" => counts = Some((rest, lineno)),
            "WIDTH" => width = Some(one_int("WIDTH")?),
            "HEIGHT" => height = Some(one_int("HEIGHT")?),
            "POINTS" => points = Some((one_int("POINTS")?, lineno)),
            "VIEWPOINT" => {
                let v: Vec<f64> = rest.iter().filter_map(|s| s.parse().ok()).collect();
                if v.len() != 7 || rest.len() != 7 || v.iter().any(|x| !x.is_finite()) {
                    return Err(header_err(
                        path,
                        at,
                        "expected 'VIEWPOINT tx ty tz qw qx qy qz' (7 finite numbers)",
                    ));
                }
                let q = Quaternion::new(v[3], v[4], v[5], v[6]);
                if q.norm() < 1e-12 {
                    return Err(header_err(path, at, "VIEWPOINT quaternion is zero"));
                }
                let rot = UnitQuaternion::from_quaternion(q);
                let t = Vector3::new(v[0], v[1], v[2]);
                let identity = t == Vector3::zeros() && rot.angle() == 0.0;
                pose = (!identity).then_some((rot, t));
            }
            "DATA" => {
                break match rest.first().map(|s| s.to_ascii_lowercase()).as_deref() {
                    Some("ascii") => Data::Ascii,
                    Some("binary") => Data::Binary,
                    Some("binary_compressed") => Data::Compressed,
                    _ => {
                        return Err(header_err(
                            path,
                            at,
                            "expected 'DATA ascii', 'DATA binary' or 'DATA binary_compressed'",
                        ))
                    }
                };
            }
            _ => {
                let what = if lineno == 1 {
                    "not a PCD file (unknown first header line)".to_string()
                } else {
                    format!("unknown header keyword '{}'", shorten(&key))
                };
                return Err(header_err(path, at, what));
            }
        }
    };

    let data_at = format!("line {lineno}");
    let Some((names, names_line)) = names else {
        return Err(header_err(path, data_at, "no FIELDS line before DATA"));
    };
    let fl = format!("line {names_line}");
    let (Some((sizes, sizes_line)), Some((types, types_line))) = (sizes, types) else {
        return Err(header_err(
            path,
            data_at,
            "SIZE and TYPE lines are required",
        ));
    };
    let counts = counts.unwrap_or_else(|| (vec!["1".to_string(); names.len()], names_line));
    if names.is_empty() {
        return Err(header_err(path, fl, "FIELDS is empty"));
    }
    for (list, line, what) in [
        (&sizes, sizes_line, "SIZE"),
        (&types, types_line, "TYPE"),
        (&counts.0, counts.1, "COUNT"),
    ] {
        if list.len() != names.len() {
            return Err(header_err(
                path,
                format!("line {line}"),
                format!(
                    "{what} has {} entries but FIELDS has {}",
                    list.len(),
                    names.len()
                ),
            ));
        }
    }
    let mut fields = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        let size = match sizes[k].as_str() {
            "1" => 1,
            "2" => 2,
            "4" => 4,
            "8" => 8,
            s => {
                return Err(header_err(
                    path,
                    format!("line {sizes_line}"),
                    format!(
                        "SIZE of '{}' is '{}', expected 1, 2, 4 or 8",
                        shorten(name),
                        shorten(s)
                    ),
                ))
            }
        };
        let ty = match types[k].to_ascii_uppercase().as_str() {
            "I" => b'I',
            "U" => b'U',
            "F" if size >= 4 => b'F',
            t => {
                return Err(header_err(
                    path,
                    format!("line {types_line}"),
                    format!(
                        "TYPE of '{}' is '{}' with SIZE {size}, expected I, U, or F (SIZE 4 or 8)",
                        shorten(name),
                        shorten(t)
                    ),
                ))
            }
        };
        let count = match counts.0[k].parse::<usize>() {
            Ok(c) if (1..=1 << 20).contains(&c) => c,
            _ => {
                return Err(header_err(
                    path,
                    format!("line {}", counts.1),
                    format!(
                        "COUNT of '{}' is '{}', expected 1 to 1048576",
                        shorten(name),
                        shorten(&counts.0[k])
                    ),
                ))
            }
        };
        fields.push(Field {
            name: name.clone(),
            size,
            ty,
            count,
        });
    }
    // At most 64 KiB / 2 fields of at most 8 MiB each: cannot overflow.
    let record: usize = fields.iter().map(Field::bytes).sum();
    if record > MAX_RECORD {
        return Err(header_err(
            path,
            format!("line {}", counts.1),
            format!(
                "one point takes {record} bytes (SIZE x COUNT over all fields), more than the \
                 {MAX_RECORD} this reader accepts"
            ),
        ));
    }

    let mut xyz = [(0, 0, 0); 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let Some(fi) = fields.iter().position(|f| f.name == *name) else {
            return Err(header_err(path, fl, format!("no field '{name}'")));
        };
        let offset = fields[..fi].iter().map(Field::bytes).sum();
        let value = fields[..fi].iter().map(|f| f.count).sum();
        xyz[k] = (fi, offset, value);
    }

    let points = match (points, width, height) {
        (Some((p, line)), Some(w), h) => {
            let h = h.unwrap_or(1);
            if w.checked_mul(h) != Some(p) {
                return Err(header_err(
                    path,
                    format!("line {line}"),
                    format!("POINTS {p} is not WIDTH {w} x HEIGHT {h}"),
                ));
            }
            p
        }
        (Some((p, _)), None, _) => p,
        (None, Some(w), h) => w
            .checked_mul(h.unwrap_or(1))
            .ok_or_else(|| header_err(path, &data_at, "WIDTH x HEIGHT overflows"))?,
        (None, None, _) => return Err(header_err(path, data_at, "neither POINTS nor WIDTH given")),
    };

    Ok(Header {
        fields,
        points,
        data,
        pose,
        len,
        lines: lineno,
        record,
        xyz,
    })
}

/// Reads the points of a PCD file (metres), with the header's `VIEWPOINT` applied
/// (`p_world = R * p + t`). Points with NaN coordinates (organised clouds) are kept.
pub fn read_pcd(path: &Path) -> Result<Vec<Point3<f64>>, CloudError> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let file_len = file.metadata().map_err(|e| io_err(path, e))?.len();
    let mut r = BufReader::with_capacity(1 << 16, file);
    let h = parse_header(path, &mut r)?;
    let body_len = file_len.saturating_sub(h.len);
    let mut pts = match h.data {
        Data::Ascii => read_ascii(path, &mut r, &h, body_len)?,
        Data::Binary => read_binary(path, &mut r, &h, body_len)?,
        Data::Compressed => read_compressed(path, &mut r, &h, body_len)?,
    };
    // A POINTS smaller than the data silently truncated the cloud.
    let more = match h.data {
        Data::Ascii => loop {
            match read_line_capped(&mut r, 1 << 24).map_err(|e| io_err(path, e))? {
                Line::Eof => break false,
                Line::Text(b, _) if b.iter().all(u8::is_ascii_whitespace) => continue,
                _ => break true,
            }
        },
        Data::Binary => body_len - h.points * h.record as u64 >= h.record as u64,
        Data::Compressed => false,
    };
    if more {
        return Err(body_err(
            path,
            "the end of the data",
            format!(
                "the data goes on after the {} points the header declares (is POINTS too small?)",
                h.points
            ),
        ));
    }
    if let Some((rot, t)) = h.pose {
        for p in &mut pts {
            *p = rot * *p + t;
        }
    }
    Ok(pts)
}

/// Fails unless `need` bytes (points x at least `per_point` bytes each) fit in the data.
fn too_big(path: &Path, h: &Header, per_point: u64, body_len: u64) -> Result<(), CloudError> {
    let need = h.points.checked_mul(per_point);
    match need {
        // An ascii file may lack its last newline.
        Some(n) if n <= body_len + u64::from(h.data == Data::Ascii) => Ok(()),
        _ => Err(body_err(
            path,
            format!("byte {}", h.len),
            format!(
                "file too short: header declares {} points of at least {per_point} bytes, but \
                 the data is only {body_len} bytes",
                h.points
            ),
        )),
    }
}

fn read_ascii<R: io::BufRead>(
    path: &Path,
    r: &mut R,
    h: &Header,
    body_len: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    let values: usize = h.fields.iter().map(|f| f.count).sum();
    // No size check: the body is read line by line to its end (preallocation is capped),
    // and a row missing a value is reported where it is, not as a short file.
    let _ = body_len;
    let mut out = Vec::with_capacity(capacity(h.points, MAX_PREALLOC));
    let mut lineno = h.lines;
    while (out.len() as u64) < h.points {
        lineno += 1;
        let at = format!("line {lineno}");
        let bytes = match read_line_capped(r, 1 << 24).map_err(|e| io_err(path, e))? {
            Line::Eof => {
                return Err(body_err(
                    path,
                    at,
                    format!("file ends after {} of {} points", out.len(), h.points),
                ))
            }
            Line::TooLong => return Err(body_err(path, at, "line too long")),
            Line::Text(b, _) => b,
        };
        let Ok(text) = std::str::from_utf8(&bytes) else {
            return Err(body_err(path, at, "line is not text"));
        };
        if text.trim().is_empty() {
            continue;
        }
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        if toks.len() != values {
            return Err(body_err(
                path,
                at,
                format!(
                    "point {} has {} values, the header declares {values}",
                    out.len(),
                    toks.len()
                ),
            ));
        }
        let mut c = [0f64; 3];
        for (k, &(_, _, vi)) in h.xyz.iter().enumerate() {
            c[k] = toks[vi].parse().map_err(|_| {
                body_err(
                    path,
                    &at,
                    format!(
                        "point {}: '{}' is not a number",
                        out.len(),
                        shorten(toks[vi])
                    ),
                )
            })?;
        }
        out.push(Point3::from(c));
    }
    Ok(out)
}

fn read_binary<R: Read>(
    path: &Path,
    r: &mut R,
    h: &Header,
    body_len: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    too_big(path, h, h.record as u64, body_len)?;
    let mut out = Vec::with_capacity(capacity(h.points, MAX_PREALLOC));
    // Whole blocks of records at a time; x, y and z all `F 4` (the common layout) are
    // read at fixed offsets, the others through `Field::decode` (the same values).
    let f32_at = h
        .xyz
        .iter()
        .all(|&(fi, _, _)| h.fields[fi].is_f32())
        .then(|| h.xyz.map(|(_, off, _)| off));
    let block_rows = (BLOCK_BYTES / h.record.max(1)).max(1);
    let mut block = vec![0u8; block_rows * h.record];
    let mut done: u64 = 0;
    while done < h.points {
        let rows = usize::try_from(h.points - done).map_or(block_rows, |n| n.min(block_rows));
        let want = &mut block[..rows * h.record];
        let got = fill(r, want).map_err(|e| io_err(path, e))?;
        if got < want.len() {
            let i = done + (got / h.record) as u64;
            return Err(body_err(
                path,
                format!("byte {}", h.len + i * h.record as u64),
                format!("file ends inside point {i} of {}", h.points),
            ));
        }
        let records = want.chunks_exact(h.record);
        if let Some(at) = f32_at {
            let get = |row: &[u8], off: usize| f32_le(&row[off..]);
            out.extend(
                records.map(|row| Point3::new(get(row, at[0]), get(row, at[1]), get(row, at[2]))),
            );
        } else {
            out.extend(records.map(|row| {
                let mut c = [0f64; 3];
                for (k, &(fi, off, _)) in h.xyz.iter().enumerate() {
                    let f = &h.fields[fi];
                    c[k] = f.decode(&row[off..off + f.size]);
                }
                Point3::from(c)
            }));
        }
        done += rows as u64;
    }
    Ok(out)
}

/// Bytes of records [`read_binary`] reads at a time (rounded down to whole records).
const BLOCK_BYTES: usize = 1 << 16;

/// Reads into `buf` until it is full or the input ends; the number of bytes read.
fn fill<R: Read>(r: &mut R, buf: &mut [u8]) -> io::Result<usize> {
    let mut n = 0;
    while n < buf.len() {
        match r.read(&mut buf[n..]) {
            Ok(0) => break,
            Ok(k) => n += k,
            Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
            Err(e) => return Err(e),
        }
    }
    Ok(n)
}

fn read_compressed<R: Read>(
    path: &Path,
    r: &mut R,
    h: &Header,
    body_len: u64,
) -> Result<Vec<Point3<f64>>, CloudError> {
    let at = |off: u64| format!("byte {}", h.len + off);
    let mut sizes = [0u8; 8];
    r.read_exact(&mut sizes).map_err(|e| {
        if e.kind() == io::ErrorKind::UnexpectedEof {
            body_err(path, at(0), "file ends before the compressed sizes")
        } else {
            io_err(path, e)
        }
    })?;
    let compressed = u64::from(u32::from_le_bytes([sizes[0], sizes[1], sizes[2], sizes[3]]));
    let uncompressed = u64::from(u32::from_le_bytes([sizes[4], sizes[5], sizes[6], sizes[7]]));
    let expected = h.points.checked_mul(h.record as u64);
    if expected != Some(uncompressed) {
        return Err(body_err(
            path,
            at(4),
            format!(
                "uncompressed size {uncompressed} is not POINTS {} x record {} bytes",
                h.points, h.record
            ),
        ));
    }
    if compressed > body_len.saturating_sub(8) {
        return Err(body_err(
            path,
            at(0),
            format!(
                "compressed size {compressed} exceeds the {} bytes left in the file",
                body_len.saturating_sub(8)
            ),
        ));
    }
    if uncompressed > compressed.saturating_mul(LZF_MAX_RATIO) {
        return Err(body_err(
            path,
            at(4),
            format!(
                "uncompressed size {uncompressed} is impossible from {compressed} compressed bytes"
            ),
        ));
    }
    let mut input = vec![0u8; capacity(compressed, usize::MAX)];
    r.read_exact(&mut input).map_err(|e| io_err(path, e))?;
    let data = lzf_decompress(&input, capacity(uncompressed, usize::MAX))
        .map_err(|(off, what)| body_err(path, at(8 + off as u64), what))?;
    let n = capacity(h.points, usize::MAX);
    let mut out = Vec::with_capacity(n);
    // Column start of each field: all values of field 0, then of field 1, ...
    let col = |fi: usize| -> usize { h.fields[..fi].iter().map(|f| f.bytes() * n).sum() };
    let cols: Vec<(usize, &Field)> = h
        .xyz
        .iter()
        .map(|&(fi, _, _)| (col(fi), &h.fields[fi]))
        .collect();
    if cols.iter().all(|(_, f)| f.is_f32() && f.count == 1) {
        // x, y and z all `F 4` with one value each (the common layout): three columns of
        // floats read side by side.
        let column = |k: usize| data[cols[k].0..cols[k].0 + 4 * n].chunks_exact(4);
        out.extend(
            column(0)
                .zip(column(1))
                .zip(column(2))
                .map(|((x, y), z)| Point3::new(f32_le(x), f32_le(y), f32_le(z))),
        );
        return Ok(out);
    }
    for i in 0..n {
        let mut c = [0f64; 3];
        for (k, (start, f)) in cols.iter().enumerate() {
            let s = start + i * f.bytes();
            c[k] = f.decode(&data[s..s + f.size]);
        }
        out.push(Point3::from(c));
    }
    Ok(out)
}

/// Decompresses LZF (liblzf format) data that must expand to exactly `out_len` bytes.
/// On error returns the input offset and what is wrong.
fn lzf_decompress(input: &[u8], out_len: usize) -> Result<Vec<u8>, (usize, String)> {
    // Written through a cursor into the declared size: no growth check per token, and
    // most tokens are short (a float's shared exponent and high mantissa, 3-4 bytes), so
    // where there is room a whole 32-byte literal or 16-byte reference is moved at once
    // (a fixed size, without a call); the bytes past the token's end are written again by
    // the tokens after it, which continue from there to `out_len`.
    let mut out = vec![0u8; out_len];
    let mut o = 0;
    let mut i = 0;
    let overflow = |at: usize| {
        Err((
            at,
            format!("compressed data expands past the declared {out_len} bytes"),
        ))
    };
    while i < input.len() {
        let start = i;
        let ctrl = usize::from(input[i]);
        i += 1;
        if ctrl < 32 {
            let len = ctrl + 1;
            if input.len() - i < len {
                return Err((
                    start,
                    "literal run goes past the end of the compressed data".into(),
                ));
            }
            if out_len - o < len {
                return overflow(start);
            }
            if input.len() - i >= 32 && out_len - o >= 32 {
                out[o..o + 32].copy_from_slice(&input[i..i + 32]);
            } else {
                out[o..o + len].copy_from_slice(&input[i..i + len]);
            }
            o += len;
            i += len;
        } else {
            let mut len = ctrl >> 5;
            if len == 7 {
                let Some(&b) = input.get(i) else {
                    return Err((start, "back reference cut off".into()));
                };
                len += usize::from(b);
                i += 1;
            }
            let Some(&b) = input.get(i) else {
                return Err((start, "back reference cut off".into()));
            };
            i += 1;
            let back = ((ctrl & 0x1f) << 8) + usize::from(b) + 1;
            len += 2;
            if back > o {
                return Err((start, "back reference before the start of the data".into()));
            }
            if out_len - o < len {
                return overflow(start);
            }
            let from = o - back;
            let (done, rest) = out.split_at_mut(o);
            if back >= 16 && len <= 16 && rest.len() >= 16 {
                rest[..16].copy_from_slice(&done[from..from + 16]);
            } else if back >= len {
                rest[..len].copy_from_slice(&done[from..from + len]);
            } else {
                // Overlapping its own output: byte by byte it repeats the last `back`
                // bytes.
                for k in 0..len {
                    out[o + k] = out[from + k];
                }
            }
            o += len;
        }
    }
    if o != out_len {
        return Err((
            input.len(),
            format!("compressed data expands to {o} bytes, expected {out_len}"),
        ));
    }
    Ok(out)
}

/// Writes points (metres) as a PCD v0.7 file with `DATA binary`: fields `x y z` as 4-byte
/// floats, an unorganised cloud (`HEIGHT 1`) and the identity `VIEWPOINT`, so that
/// [`read_pcd`] gives the same points back (rounded to f32). The file is written to a
/// temporary file beside `path` and renamed into place; the same points give the same bytes.
pub fn write_pcd(path: &Path, points: &[Point3<f64>]) -> Result<(), CloudError> {
    let mut bytes = format!(
        "# .PCD v0.7 - Point Cloud Data file format (written by afford)\nVERSION 0.7\n\
         FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH {n}\nHEIGHT 1\n\
         VIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\nDATA binary\n",
        n = points.len()
    )
    .into_bytes();
    bytes.reserve(points.len() * 12);
    for p in points {
        for c in p.coords.iter() {
            bytes.extend_from_slice(&to_f32(*c).to_le_bytes());
        }
    }
    crate::report::atomic::write_bytes(path, &bytes).map_err(|source| CloudError::Write {
        path: path.to_path_buf(),
        source,
    })
}

#[cfg(test)]
// Test data: small literals and lengths, written into the fields of a file by hand.
#[allow(clippy::cast_possible_truncation)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn file(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    fn close(a: Point3<f64>, b: Point3<f64>) -> bool {
        (a - b).norm() < 1e-9
    }

    /// A naive LZF compressor (greedy longest match), for building test files.
    fn lzf_compress(inp: &[u8]) -> Vec<u8> {
        fn flush(out: &mut Vec<u8>, lit: &mut Vec<u8>) {
            for chunk in lit.chunks(32) {
                out.push((chunk.len() - 1) as u8);
                out.extend_from_slice(chunk);
            }
            lit.clear();
        }
        let (mut out, mut lit, mut i) = (Vec::new(), Vec::new(), 0);
        while i < inp.len() {
            let mut best = (0, 0);
            for j in i.saturating_sub(8192)..i {
                let mut l = 0;
                while i + l < inp.len() && l < 264 && inp[j + l] == inp[i + l] {
                    l += 1;
                }
                if l > best.0 {
                    best = (l, i - j);
                }
            }
            if best.0 >= 3 {
                flush(&mut out, &mut lit);
                let (len, off) = (best.0 - 2, best.1 - 1);
                if len < 7 {
                    out.push(((len << 5) | (off >> 8)) as u8);
                } else {
                    out.push(((7 << 5) | (off >> 8)) as u8);
                    out.push((len - 7) as u8);
                }
                out.push((off & 0xff) as u8);
                i += best.0;
            } else {
                lit.push(inp[i]);
                i += 1;
            }
        }
        flush(&mut out, &mut lit);
        out
    }

    #[test]
    fn lzf_hand_made_block_and_errors() {
        // Literal "abc", then a back reference of length 5 at distance 3.
        let block = [2, b'a', b'b', b'c', 0x60, 2];
        assert_eq!(lzf_decompress(&block, 8).unwrap(), b"abcabcab");
        assert!(lzf_decompress(&block, 7)
            .unwrap_err()
            .1
            .contains("past the declared"));
        assert!(lzf_decompress(&block, 9)
            .unwrap_err()
            .1
            .contains("expands to 8"));
        assert_eq!(lzf_decompress(&[0x60, 9], 5).unwrap_err().0, 0);
        assert_eq!(lzf_decompress(&[5, 1, 2], 6).unwrap_err().0, 0);
        assert_eq!(lzf_decompress(&[0, 1, 0xe0], 100).unwrap_err().0, 2);
        assert_eq!(lzf_decompress(&[], 0).unwrap(), b"");
        // The test compressor really uses back references, and round-trips.
        let data: Vec<u8> = (0..3000u32).map(|i| (i % 7 + i / 500) as u8).collect();
        let c = lzf_compress(&data);
        assert!(c.len() < data.len() / 4, "{}", c.len());
        assert_eq!(lzf_decompress(&c, data.len()).unwrap(), data);
    }

    /// The LZF decoder as first written (a byte pushed at a time): the reference the
    /// decoder's results and errors must equal.
    fn lzf_reference(input: &[u8], out_len: usize) -> Result<Vec<u8>, (usize, String)> {
        let mut out = Vec::with_capacity(out_len);
        let mut i = 0;
        let overflow = |at: usize| {
            Err((
                at,
                format!("compressed data expands past the declared {out_len} bytes"),
            ))
        };
        while i < input.len() {
            let start = i;
            let ctrl = usize::from(input[i]);
            i += 1;
            if ctrl < 32 {
                let len = ctrl + 1;
                let Some(lit) = input.get(i..i + len) else {
                    return Err((
                        start,
                        "literal run goes past the end of the compressed data".into(),
                    ));
                };
                if out.len() + len > out_len {
                    return overflow(start);
                }
                out.extend_from_slice(lit);
                i += len;
            } else {
                let mut len = ctrl >> 5;
                if len == 7 {
                    let Some(&b) = input.get(i) else {
                        return Err((start, "back reference cut off".into()));
                    };
                    len += usize::from(b);
                    i += 1;
                }
                let Some(&b) = input.get(i) else {
                    return Err((start, "back reference cut off".into()));
                };
                i += 1;
                let back = ((ctrl & 0x1f) << 8) + usize::from(b) + 1;
                len += 2;
                if back > out.len() {
                    return Err((start, "back reference before the start of the data".into()));
                }
                if out.len() + len > out_len {
                    return overflow(start);
                }
                let from = out.len() - back;
                for k in 0..len {
                    let c = out[from + k];
                    out.push(c);
                }
            }
        }
        if out.len() != out_len {
            return Err((
                input.len(),
                format!(
                    "compressed data expands to {} bytes, expected {out_len}",
                    out.len()
                ),
            ));
        }
        Ok(out)
    }

    #[test]
    fn lzf_decoder_equals_the_byte_by_byte_reference() {
        let mut s: u64 = 0x2545_f491_4f6c_dd1d;
        let mut next = |n: u64| {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            s % n
        };
        let mut oks = 0;
        for case in 0..3000 {
            // Data with repeats of every length and distance (short and long runs, a byte
            // repeated, copies of far-back pieces), compressed by the test compressor.
            let n = 1 + next(3000) as usize;
            let mut data: Vec<u8> = Vec::with_capacity(n);
            while data.len() < n {
                match next(4) {
                    0 => data.push(next(256) as u8),
                    1 => {
                        let b = next(256) as u8;
                        data.extend(std::iter::repeat_n(b, next(40) as usize));
                    }
                    _ if data.len() > 4 => {
                        let from = next(data.len() as u64) as usize;
                        let len = (next(60) as usize).min(data.len() - from);
                        data.extend_from_within(from..from + len);
                    }
                    _ => data.push(0),
                }
            }
            data.truncate(n);
            let mut c = lzf_compress(&data);
            // Some streams damaged: a byte changed, cut short, or the size misdeclared.
            let mut len = data.len();
            match case % 4 {
                1 if !c.is_empty() => {
                    let at = next(c.len() as u64) as usize;
                    c[at] = next(256) as u8;
                }
                2 => c.truncate(next(c.len() as u64 + 1) as usize),
                3 => len = (len + next(64) as usize).saturating_sub(32),
                _ => {}
            }
            let want = lzf_reference(&c, len);
            oks += usize::from(want.is_ok());
            assert_eq!(lzf_decompress(&c, len), want, "case {case}");
        }
        // Most streams decode, and some of every kind of damage is caught.
        assert!(oks > 750 && oks < 2900, "{oks}");
    }

    #[test]
    fn ascii_crlf_comments_viewpoint_translation() {
        let dir = tempfile::tempdir().unwrap();
        let text = "# .PCD v0.7 - Point Cloud Data file format\r\n\
            VERSION 0.7\r\nFIELDS x y z rgb\r\n  SIZE 4 4 4 4 \r\nTYPE F F F U\r\n\
            COUNT 1 1 1 1\r\n# a comment\r\nWIDTH 3\r\nHEIGHT 1\r\n\
            VIEWPOINT 1 2 3 1 0 0 0\r\nPOINTS 3\r\nDATA ascii\r\n\
            0.5 -1 2 4278190080\r\n\r\n1e-2\t0  0 0\r\n-3 -2 -1 7\r\n";
        let p = file(&dir, "a.pcd", text.as_bytes());
        let pts = read_pcd(&p).unwrap();
        assert_eq!(
            pts,
            vec![
                Point3::new(1.5, 1.0, 5.0),
                Point3::new(1.01, 2.0, 3.0),
                Point3::new(-2.0, 0.0, 2.0)
            ]
        );
    }

    #[test]
    fn organised_ascii_with_nan_and_version_06_without_points() {
        let dir = tempfile::tempdir().unwrap();
        let text = "VERSION .6\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nHEIGHT 2\n\
            DATA ascii\nnan nan nan\n1 2 3\n4 5 6\nNaN 0 0\n";
        let pts = read_pcd(&file(&dir, "o.pcd", text.as_bytes())).unwrap();
        assert_eq!(pts.len(), 4);
        assert!(pts[0].x.is_nan() && pts[3].x.is_nan());
        assert_eq!(pts[1], Point3::new(1.0, 2.0, 3.0));
        assert_eq!(pts[2], Point3::new(4.0, 5.0, 6.0));
    }

    /// Fields in odd order, with COUNT > 1, `_` padding and 1-, 2- and 8-byte types.
    const ODD_FIELDS: &str = "FIELDS normal_x rgb _ y x z\nSIZE 4 4 1 8 4 2\n\
        TYPE F U U F F I\nCOUNT 3 1 3 1 1 1\n";

    fn odd_record(p: [f64; 3]) -> Vec<u8> {
        let mut r = Vec::new();
        for v in [0.1f32, 0.2, 0.3] {
            r.extend_from_slice(&v.to_le_bytes());
        }
        r.extend_from_slice(&0xff00_00ffu32.to_le_bytes());
        r.extend_from_slice(&[0xaa; 3]);
        r.extend_from_slice(&p[1].to_le_bytes());
        r.extend_from_slice(&(p[0] as f32).to_le_bytes());
        r.extend_from_slice(&(p[2] as i16).to_le_bytes());
        r
    }

    #[test]
    fn binary_odd_fields_and_rotated_viewpoint() {
        let dir = tempfile::tempdir().unwrap();
        let pts = [
            [1.0, 0.25, -4.0],
            [f64::NAN, 3.5, 2.0],
            [-0.5, -1e-3, 300.0],
        ];
        // 90 degrees about z, then translation (0, 0, 10).
        let h = (0.5f64).sqrt();
        let mut b = format!(
            "VERSION 0.7\n{ODD_FIELDS}WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 10 {h} 0 0 {h}\n\
             POINTS 3\nDATA binary\n"
        )
        .into_bytes();
        for p in pts {
            b.extend(odd_record(p));
        }
        let got = read_pcd(&file(&dir, "b.pcd", &b)).unwrap();
        assert!(close(got[0], Point3::new(-0.25, 1.0, 6.0)), "{:?}", got[0]);
        // A NaN coordinate stays invalid after the rotation mixes the axes.
        assert!(got[1].x.is_nan() && got[1].y.is_nan());
        assert!(
            close(got[2], Point3::new(1e-3, -0.5, 310.0)),
            "{:?}",
            got[2]
        );

        // Truncated inside the last record: Body error before anything is read.
        let header_len = b.len() - 3 * 33;
        let p = file(&dir, "t.pcd", &b[..b.len() - 1]);
        let e = read_pcd(&p).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { at, what, .. }
                if *at == format!("byte {header_len}") && what.contains("3 points of at least 33 bytes")
                    && what.contains("only 98 bytes")),
            "{e}"
        );
    }

    #[test]
    fn binary_float_coordinates_across_blocks() {
        // x, y, z all `F 4` (read at fixed offsets) after another float field and in the
        // order z, x, y; 10 000 records of 20 bytes cross several 64 KiB blocks.
        let dir = tempfile::tempdir().unwrap();
        let pts: Vec<[f32; 3]> = (0..10_000u16)
            .map(|i| {
                let i = f32::from(i);
                [i * 0.25 - 1000.0, -i / 128.0, 1e-3 * i]
            })
            .collect();
        let mut b = format!(
            "VERSION 0.7\nFIELDS intensity z x y rgb\nSIZE 4 4 4 4 4\nTYPE F F F F U\n\
             COUNT 1 1 1 1 1\nWIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary\n",
            n = pts.len()
        )
        .into_bytes();
        for p in &pts {
            for v in [9.5f32, p[2], p[0], p[1]] {
                b.extend_from_slice(&v.to_le_bytes());
            }
            b.extend_from_slice(&0x00ff_00ffu32.to_le_bytes());
        }
        let got = read_pcd(&file(&dir, "f.pcd", &b)).unwrap();
        let want: Vec<_> = pts
            .iter()
            .map(|p| Point3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])))
            .collect();
        assert_eq!(got, want);
    }

    #[test]
    fn binary_compressed_column_wise() {
        let dir = tempfile::tempdir().unwrap();
        let n = 40usize;
        let pts: Vec<[f64; 3]> = (0..n)
            .map(|i| {
                [
                    i as f64 * 0.5,
                    -(i as f64),
                    if i % 9 == 0 { f64::NAN } else { 1.0 },
                ]
            })
            .collect();
        // Column-wise: all normal_x triples, all rgb, all _, all y, all x, all z.
        let recs: Vec<Vec<u8>> = pts.iter().map(|p| odd_record(*p)).collect();
        let mut raw = Vec::new();
        for (start, len) in [(0, 12), (12, 4), (16, 3), (19, 8), (27, 4), (31, 2)] {
            for r in &recs {
                raw.extend_from_slice(&r[start..start + len]);
            }
        }
        assert_eq!(raw.len(), n * 33);
        let c = lzf_compress(&raw);
        let mut b = format!(
            "VERSION 0.7\n{ODD_FIELDS}WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary_compressed\n"
        )
        .into_bytes();
        let header_len = b.len();
        b.extend_from_slice(&(c.len() as u32).to_le_bytes());
        b.extend_from_slice(&(raw.len() as u32).to_le_bytes());
        b.extend_from_slice(&c);
        let got = read_pcd(&file(&dir, "c.pcd", &b)).unwrap();
        assert_eq!(got.len(), n);
        for (g, p) in got.iter().zip(&pts) {
            assert_eq!((g.x, g.y), (p[0], p[1]));
            // z is stored as a 2-byte integer: NaN became 0.
            assert_eq!(g.z, if p[2].is_nan() { 0.0 } else { 1.0 });
        }

        // Wrong uncompressed size, compressed size past the end, corrupt data: Body errors.
        let mut bad = b.clone();
        bad[header_len + 4] ^= 1;
        let e = read_pcd(&file(&dir, "d.pcd", &bad)).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { what, .. } if what.contains("uncompressed size")),
            "{e}"
        );
        let mut bad = b.clone();
        bad[header_len..header_len + 4].copy_from_slice(&(c.len() as u32 + 1).to_le_bytes());
        let e = read_pcd(&file(&dir, "d.pcd", &bad)).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { what, .. } if what.contains("exceeds")),
            "{e}"
        );
        let mut bad = b.clone();
        bad[header_len + 8] = 0xff; // A back reference before the start.
        let e = read_pcd(&file(&dir, "d.pcd", &bad)).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { at, .. } if *at == format!("byte {}", header_len + 8)),
            "{e}"
        );
        // Random corruption never panics.
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..300 {
            let mut m = b.clone();
            for _ in 0..3 {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                let i = (seed % m.len() as u64) as usize;
                m[i] = (seed >> 24) as u8;
            }
            let _ = read_pcd(&file(&dir, "r.pcd", &m));
        }
    }

    #[test]
    fn huge_point_counts_fail_before_allocating() {
        let dir = tempfile::tempdir().unwrap();
        for data in ["ascii", "binary", "binary_compressed"] {
            let text = format!(
                "FIELDS x y z\nSIZE 8 8 8\nTYPE F F F\nWIDTH 4000000000\nHEIGHT 1\n\
                 POINTS 4000000000\nDATA {data}\n\x10\0\0\0\0\0\0\x70\0\0\0\0\0\0\0\0"
            );
            let e = read_pcd(&file(&dir, "h.pcd", text.as_bytes())).unwrap_err();
            assert!(matches!(e, CloudError::Body { .. }), "{data}: {e}");
        }
        // A claimed uncompressed size that 8 compressed bytes cannot produce.
        let mut b = b"FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1000000\nHEIGHT 1\n\
            DATA binary_compressed\n"
            .to_vec();
        b.extend_from_slice(&8u32.to_le_bytes());
        b.extend_from_slice(&12_000_000u32.to_le_bytes());
        b.extend_from_slice(&[0xe0; 8]);
        let e = read_pcd(&file(&dir, "z.pcd", &b)).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { what, .. } if what.contains("impossible")),
            "{e}"
        );
    }

    #[test]
    fn header_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let ok = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 1\n";
        let cases: Vec<(Vec<u8>, &str, &str)> = vec![
            (b"".to_vec(), "line 1", "empty file"),
            (b"\x89PNG\r\n\x1a\n\0\0".to_vec(), "line 1", "not text"),
            (
                b"ply\nformat ascii 1.0\n".to_vec(),
                "line 1",
                "not a PCD file",
            ),
            (b"VERSION 0.7\n# \xff\xfe\n".to_vec(), "line 2", "not text"),
            (
                format!("{ok}POINTS 1\n").into_bytes(),
                "line 6",
                "before the 'DATA' line",
            ),
            (
                b"FIELDS x y\nSIZE 4 4\nTYPE F F\nWIDTH 1\nDATA ascii\n1 2\n".to_vec(),
                "line 1",
                "no field 'z'",
            ),
            (
                b"FIELDS x y z\nSIZE 4 4\nTYPE F F F\nWIDTH 1\nDATA ascii\n".to_vec(),
                "line 2",
                "SIZE has 2 entries",
            ),
            (
                b"FIELDS x y z\nSIZE 4 4 3\nTYPE F F F\nWIDTH 1\nDATA ascii\n".to_vec(),
                "line 2",
                "SIZE of 'z'",
            ),
            (
                b"FIELDS x y z\nSIZE 4 4 2\nTYPE F F F\nWIDTH 1\nDATA ascii\n".to_vec(),
                "line 3",
                "TYPE of 'z'",
            ),
            (
                format!("{ok}COUNT 1 0 1\nDATA ascii\n").into_bytes(),
                "line 5",
                "COUNT of 'y'",
            ),
            (
                format!("{ok}HEIGHT 2\nPOINTS 3\nDATA ascii\n").into_bytes(),
                "line 6",
                "not WIDTH 1 x HEIGHT 2",
            ),
            (
                format!("{ok}DATA zip\n").into_bytes(),
                "line 5",
                "expected 'DATA ascii'",
            ),
            (
                format!("{ok}VIEWPOINT 0 0 0 0 0 0 0\nDATA ascii\n").into_bytes(),
                "line 5",
                "quaternion is zero",
            ),
            (
                format!("{ok}WIDTH -1\n").into_bytes(),
                "line 5",
                "not a non-negative",
            ),
        ];
        for (bytes, at_want, what_want) in cases {
            let p = file(&dir, "e.pcd", &bytes);
            let e = read_pcd(&p).unwrap_err();
            let msg = e.to_string();
            match &e {
                CloudError::Header { at, what, .. } => {
                    assert_eq!(at, at_want, "{msg}");
                    assert!(what.contains(what_want), "{msg}");
                }
                _ => panic!("expected Header error, got {msg}"),
            }
            assert!(
                !msg.contains('\n') && msg.starts_with(&p.display().to_string()),
                "{msg}"
            );
        }
    }

    #[test]
    fn ascii_body_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let head = "FIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nWIDTH 2\nDATA ascii\n";
        for (body, what) in [
            (&b"1 2 3\n4 5          \n"[..], "has 2 values"),
            (b"1 2 3\n4 x 6\n", "'x' is not a number"),
            (b"1 2 3\n\xff 5 6\n", "not text"),
        ] {
            let p = file(&dir, "a.pcd", &[head.as_bytes(), body].concat());
            let e = read_pcd(&p).unwrap_err();
            assert!(
                matches!(&e, CloudError::Body { at, what: w, .. } if at == "line 7" && w.contains(what)),
                "{e}"
            );
        }
        let p = file(&dir, "s.pcd", format!("{head}1 2 3          \n").as_bytes());
        let e = read_pcd(&p).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { what, .. } if what.contains("after 1 of 2")),
            "{e}"
        );
    }

    #[test]
    fn write_pcd_reads_back_the_same_points() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("w.pcd");
        let pts = vec![
            Point3::new(0.5, -1.25, 2.0),
            Point3::new(1.0e-3, 3.5, -0.125),
            Point3::new(0.1, 0.2, 0.3),
        ];
        write_pcd(&path, &pts).unwrap();
        let back = read_pcd(&path).unwrap();
        assert_eq!(back.len(), 3);
        for (a, b) in pts.iter().zip(&back) {
            assert!((a - b).norm() < 1e-6, "{a} {b}");
        }
        let first = std::fs::read(&path).unwrap();
        write_pcd(&path, &pts).unwrap();
        assert_eq!(first, std::fs::read(&path).unwrap());
        write_pcd(&path, &[]).unwrap();
        assert!(read_pcd(&path).unwrap().is_empty());
    }
}
