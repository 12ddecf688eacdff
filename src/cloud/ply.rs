//! PLY reader and writer (Stanford polygon format): vertices only, faces ignored.
//!
//! The reader is our own, streaming, and checks every size before allocating; it handles
//! `ascii`, `binary_little_endian` and `binary_big_endian`, vertex coordinates of any scalar
//! type, extra vertex properties in any order, and other elements (faces, ...) before or
//! after the vertices, including list properties.

use std::fs::File;
use std::io::{self, BufRead, BufReader, Read, Write};
use std::path::Path;

use nalgebra::Point3;

use super::CloudError;
use crate::num::{capacity, to_f32, to_u64};

/// Longest header line accepted, in bytes (longer means the file is not a PLY header).
pub(super) const MAX_HEADER_LINE: usize = 64 * 1024;
/// Most header lines accepted before `end_header` (PLY) or `DATA` (PCD).
pub(super) const MAX_HEADER_LINES: usize = 100_000;
/// Most points reserved up front; the vector grows beyond this only as data is really read.
pub(super) const MAX_PREALLOC: usize = 1 << 20;

/// One line read by [`read_line_capped`].
pub(super) enum Line {
    /// End of file, nothing read.
    Eof,
    /// A line (without its `\n`, and without a trailing `\r`), and the bytes it took in the file.
    Text(Vec<u8>, usize),
    /// The line is longer than the cap.
    TooLong,
}

/// Reads one `\n`-terminated line of at most `cap` bytes; never allocates more than `cap + 1`.
pub(super) fn read_line_capped<R: BufRead>(r: &mut R, cap: usize) -> io::Result<Line> {
    let mut buf = Vec::new();
    let n = r
        .by_ref()
        .take(cap as u64 + 1)
        .read_until(b'\n', &mut buf)?;
    if n == 0 {
        return Ok(Line::Eof);
    }
    if buf.last() == Some(&b'\n') {
        buf.pop();
    } else if n > cap {
        return Ok(Line::TooLong);
    }
    if buf.last() == Some(&b'\r') {
        buf.pop();
    }
    Ok(Line::Text(buf, n))
}

/// Builds a [`CloudError::Header`].
pub(super) fn header_err(
    path: &Path,
    at: impl Into<String>,
    what: impl Into<String>,
) -> CloudError {
    CloudError::Header {
        path: path.to_path_buf(),
        at: at.into(),
        what: what.into(),
    }
}

/// Builds a [`CloudError::Body`].
pub(super) fn body_err(path: &Path, at: impl Into<String>, what: impl Into<String>) -> CloudError {
    CloudError::Body {
        path: path.to_path_buf(),
        at: at.into(),
        what: what.into(),
    }
}

/// Builds a [`CloudError::Io`].
pub(super) fn io_err(path: &Path, source: io::Error) -> CloudError {
    CloudError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A PLY scalar type (shared with the mesh reader of `synth::meshio`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    pub(crate) fn parse(s: &str) -> Option<Scalar> {
        Some(match s {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The type's name in a PLY header (`uchar`, `int`, `float`, ...).
    pub(crate) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }

    /// Writes `v` as this type, little-endian (`as` casts: integers truncated and saturated).
    // The file's declared type decides: saturating is what it is asked for.
    #[allow(clippy::cast_possible_truncation)]
    fn write_le<W: Write + ?Sized>(self, w: &mut W, v: f64) -> io::Result<()> {
        match self {
            Scalar::I8 => w.write_all(&(v as i8).to_le_bytes()),
            Scalar::U8 => w.write_all(&(v as u8).to_le_bytes()),
            Scalar::I16 => w.write_all(&(v as i16).to_le_bytes()),
            Scalar::U16 => w.write_all(&(v as u16).to_le_bytes()),
            Scalar::I32 => w.write_all(&(v as i32).to_le_bytes()),
            Scalar::U32 => w.write_all(&(v as u32).to_le_bytes()),
            Scalar::F32 => w.write_all(&(v as f32).to_le_bytes()),
            Scalar::F64 => w.write_all(&v.to_le_bytes()),
        }
    }

    /// Writes `v` as this type in ascii, with the casts of [`Scalar::write_le`]; NaN as
    /// `nan`, as C's printf writes it, which most PLY tools read.
    fn write_ascii<W: Write + ?Sized>(self, w: &mut W, v: f64) -> io::Result<()> {
        let v = self.decode(&self.le_bytes(v), false);
        match self {
            _ if v.is_nan() => write!(w, "nan"),
            Scalar::F32 => write!(w, "{}", to_f32(v)),
            _ => write!(w, "{v}"),
        }
    }

    /// The little-endian bytes [`Scalar::write_le`] writes.
    fn le_bytes(self, v: f64) -> Vec<u8> {
        let mut b = Vec::with_capacity(8);
        let _ = self.write_le(&mut b, v);
        b
    }

    /// Decodes `b` (exactly `self.size()` bytes) as a number.
    #[inline]
    pub(crate) fn decode(self, b: &[u8], big: bool) -> f64 {
        macro_rules! num {
            ($t:ty, $n:expr) => {{
                let mut a = [0u8; $n];
                a.copy_from_slice(&b[..$n]);
                if big {
                    <$t>::from_be_bytes(a)
                } else {
                    <$t>::from_le_bytes(a)
                }
            }};
        }
        match self {
            Scalar::I8 => f64::from(b[0] as i8),
            Scalar::U8 => f64::from(b[0]),
            Scalar::I16 => f64::from(num!(i16, 2)),
            Scalar::U16 => f64::from(num!(u16, 2)),
            Scalar::I32 => f64::from(num!(i32, 4)),
            Scalar::U32 => f64::from(num!(u32, 4)),
            Scalar::F32 => f64::from(num!(f32, 4)),
            Scalar::F64 => num!(f64, 8),
        }
    }
}

/// A property of an element: a scalar, or a list (count type, item type).
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum Kind {
    Scalar(Scalar),
    List(Scalar, Scalar),
}

/// A property of a PLY element: its name and type.
#[derive(Debug, Clone)]
pub(crate) struct Prop {
    pub(crate) name: String,
    pub(crate) kind: Kind,
}

/// An element of a PLY header: its name, row count and properties.
#[derive(Debug, Clone)]
pub(crate) struct Element {
    pub(crate) name: String,
    pub(crate) count: u64,
    pub(crate) props: Vec<Prop>,
    /// Header line of the `element` keyword.
    pub(crate) line: usize,
}

impl Element {
    /// Fewest bytes one binary row can take.
    fn min_binary_row(&self) -> u64 {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size() as u64,
                Kind::List(c, _) => c.size() as u64,
            })
            .sum()
    }

    /// Fewest bytes one ascii row can take (one character and one separator per value).
    fn min_ascii_row(&self) -> u64 {
        2 * self.props.len() as u64
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Encoding {
    Ascii,
    BinaryLe,
    BinaryBe,
}

/// A parsed PLY header: the one parser of PLY headers, for point clouds
/// ([`read_ply`]) and meshes ([`crate::mesh::ply::read_mesh_ply`]).
pub(crate) struct Header {
    pub(crate) encoding: Encoding,
    pub(crate) elements: Vec<Element>,
    /// Bytes taken by the header, up to and including the `end_header` line.
    pub(crate) len: u64,
    /// Lines taken by the header.
    pub(crate) lines: usize,
}

/// Reads header line `lineno` (1-based) of a PLY or PCD file: at most [`MAX_HEADER_LINE`]
/// bytes, as text, counting the bytes taken into `len`. The errors name the line and say
/// the header has no `end` marker, or is `not_text`.
pub(super) fn next_header_line<R: BufRead>(
    path: &Path,
    r: &mut R,
    lineno: usize,
    len: &mut u64,
    end: &str,
    not_text: &str,
) -> Result<String, CloudError> {
    let at = format!("line {lineno}");
    if lineno > MAX_HEADER_LINES {
        return Err(header_err(path, at, format!("header too long (no {end})")));
    }
    let bytes = match read_line_capped(r, MAX_HEADER_LINE).map_err(|e| io_err(path, e))? {
        Line::Eof if lineno == 1 => return Err(header_err(path, at, "empty file")),
        Line::Eof => return Err(header_err(path, at, format!("file ends before {end}"))),
        Line::TooLong => return Err(header_err(path, at, "header line too long")),
        Line::Text(b, n) => {
            *len += n as u64;
            b
        }
    };
    String::from_utf8(bytes).map_err(|_| header_err(path, at, not_text))
}

/// Parses a PLY header from `r`, leaving `r` at the first byte of the body; errors name
/// the header line.
pub(crate) fn parse_header<R: BufRead>(path: &Path, r: &mut R) -> Result<Header, CloudError> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut len = 0u64;
    let mut lineno = 0usize;
    loop {
        lineno += 1;
        let at = format!("line {lineno}");
        let not_text = if lineno == 1 {
            "not a PLY file (first line is not 'ply')"
        } else {
            "header line is not text"
        };
        let text = next_header_line(path, r, lineno, &mut len, "'end_header'", not_text)?;
        let words: Vec<&str> = text.split_whitespace().collect();
        if lineno == 1 {
            if words != ["ply"] {
                return Err(header_err(
                    path,
                    at,
                    "not a PLY file (first line is not 'ply')",
                ));
            }
            continue;
        }
        match words.first().copied() {
            None => {}
            Some("comment") | Some("obj_info") => {}
            Some("format") => {
                if encoding.is_some() {
                    return Err(header_err(path, at, "second 'format' line"));
                }
                let e = match words.get(1).copied() {
                    Some("ascii") => Encoding::Ascii,
                    Some("binary_little_endian") => Encoding::BinaryLe,
                    Some("binary_big_endian") => Encoding::BinaryBe,
                    other => {
                        return Err(header_err(
                            path,
                            at,
                            format!("unknown format '{}'", other.unwrap_or("")),
                        ))
                    }
                };
                if words.len() != 3 {
                    return Err(header_err(path, at, "expected 'format <encoding> 1.0'"));
                }
                encoding = Some(e);
            }
            Some("element") => {
                let (Some(name), Some(count), 3) = (words.get(1), words.get(2), words.len()) else {
                    return Err(header_err(path, at, "expected 'element <name> <count>'"));
                };
                let Ok(count) = count.parse::<u64>() else {
                    return Err(header_err(
                        path,
                        at,
                        format!("element count '{count}' is not a non-negative integer"),
                    ));
                };
                elements.push(Element {
                    name: (*name).to_string(),
                    count,
                    props: Vec::new(),
                    line: lineno,
                });
            }
            Some("property") => {
                let Some(elem) = elements.last_mut() else {
                    return Err(header_err(path, at, "'property' before any 'element'"));
                };
                let bad_type = |t: &str| header_err(path, &at, format!("unknown type '{t}'"));
                let (kind, name) = match words.get(1).copied() {
                    Some("list") => {
                        if words.len() != 5 {
                            return Err(header_err(
                                path,
                                at,
                                "expected 'property list <count type> <item type> <name>'",
                            ));
                        }
                        let c = Scalar::parse(words[2]).ok_or_else(|| bad_type(words[2]))?;
                        let i = Scalar::parse(words[3]).ok_or_else(|| bad_type(words[3]))?;
                        if !c.is_int() {
                            return Err(header_err(path, at, "list count type must be an integer"));
                        }
                        (Kind::List(c, i), words[4])
                    }
                    Some(t) if words.len() == 3 => (
                        Kind::Scalar(Scalar::parse(t).ok_or_else(|| bad_type(t))?),
                        words[2],
                    ),
                    _ => return Err(header_err(path, at, "expected 'property <type> <name>'")),
                };
                elem.props.push(Prop {
                    name: name.to_string(),
                    kind,
                });
            }
            Some("end_header") => break,
            Some(other) => {
                return Err(header_err(
                    path,
                    at,
                    format!("unknown header keyword '{other}'"),
                ))
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(header_err(path, "line 2", "no 'format' line in header"));
    };
    Ok(Header {
        encoding,
        elements,
        len,
        lines: lineno,
    })
}

/// The index of the `vertex` element and of its x, y, z properties.
fn find_xyz(path: &Path, h: &Header) -> Result<(usize, [usize; 3]), CloudError> {
    let Some(vi) = h.elements.iter().position(|e| e.name == "vertex") else {
        return Err(header_err(path, "end_header", "no 'vertex' element"));
    };
    let v = &h.elements[vi];
    let mut idx = [0usize; 3];
    for (k, name) in ["x", "y", "z"].iter().enumerate() {
        let Some(pi) = v.props.iter().position(|p| p.name == *name) else {
            return Err(header_err(
                path,
                format!("line {}", v.line),
                format!("element 'vertex' has no property '{name}'"),
            ));
        };
        if !matches!(v.props[pi].kind, Kind::Scalar(_)) {
            return Err(header_err(
                path,
                format!("line {}", v.line),
                format!("vertex property '{name}' is a list, expected a number"),
            ));
        }
        idx[k] = pi;
    }
    Ok((vi, idx))
}

/// Reads the vertices of a PLY file as points (metres, file frame); faces and other elements
/// are ignored. Non-finite coordinates are kept as they are.
pub fn read_ply(path: &Path) -> Result<Vec<Point3<f64>>, CloudError> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let file_len = file.metadata().map_err(|e| io_err(path, e))?.len();
    let mut r = BufReader::with_capacity(1 << 16, file);
    let header = parse_header(path, &mut r)?;
    let (vi, xyz) = find_xyz(path, &header)?;
    let body_len = file_len.saturating_sub(header.len);

    // Every element up to the vertices must fit in the body, before anything is allocated.
    // Binary only: an ascii body is read line by line to its end, and a row missing a
    // value is reported where it is, not as a short file.
    let mut need = 0u64;
    let checked = match header.encoding {
        Encoding::Ascii => &header.elements[..0],
        _ => &header.elements[..=vi],
    };
    for e in checked {
        let row = match header.encoding {
            Encoding::Ascii => e.min_ascii_row(),
            _ => e.min_binary_row(),
        };
        need = e
            .count
            .checked_mul(row)
            .and_then(|b| b.checked_add(need))
            .unwrap_or(u64::MAX);
        // An ascii file may lack its last newline.
        let slack = u64::from(header.encoding == Encoding::Ascii);
        if need > body_len + slack {
            return Err(body_err(
                path,
                format!("byte {}", header.len),
                format!(
                    "file too short: header declares {} '{}' elements, needing at least \
                     {need} data bytes, but there are only {body_len}",
                    e.count, e.name
                ),
            ));
        }
    }

    let last = vi + 1 == header.elements.len();
    let v = &header.elements[vi];
    match header.encoding {
        Encoding::Ascii => {
            let pts = read_ascii_body(path, &mut r, &header, vi, xyz)?;
            if last {
                no_more_rows(path, &mut r, v)?;
            }
            Ok(pts)
        }
        enc => {
            let mut src = Src { r, pos: header.len };
            let pts =
                read_binary_body(path, &mut src, &header, vi, xyz, enc == Encoding::BinaryBe)?;
            let left = file_len.saturating_sub(src.pos);
            if last && left >= v.min_binary_row().max(1) {
                return Err(more_than_declared(path, v, format!("byte {}", src.pos)));
            }
            Ok(pts)
        }
    }
}

/// The error for a body holding more rows than its header's count (a count too small
/// silently truncated the cloud).
fn more_than_declared(path: &Path, e: &Element, at: String) -> CloudError {
    body_err(
        path,
        at,
        format!(
            "the data goes on after the {} '{}' elements the header declares (is the count too small?)",
            e.count, e.name
        ),
    )
}

/// Fails if a non-blank line follows the last declared row of an ascii body.
fn no_more_rows<R: BufRead>(path: &Path, r: &mut R, e: &Element) -> Result<(), CloudError> {
    loop {
        match read_line_capped(r, 1 << 20).map_err(|err| io_err(path, err))? {
            Line::Eof => return Ok(()),
            Line::Text(b, _) if b.iter().all(u8::is_ascii_whitespace) => continue,
            _ => return Err(more_than_declared(path, e, "the end of the data".into())),
        }
    }
}

/// A reader that knows its byte offset in the file.
struct Src<R> {
    r: R,
    pos: u64,
}

impl<R: Read> Src<R> {
    fn read_exact(&mut self, buf: &mut [u8]) -> io::Result<()> {
        self.r.read_exact(buf)?;
        self.pos += buf.len() as u64;
        Ok(())
    }

    fn skip(&mut self, n: u64) -> io::Result<()> {
        let got = io::copy(&mut self.r.by_ref().take(n), &mut io::sink())?;
        self.pos += got;
        if got < n {
            return Err(io::ErrorKind::UnexpectedEof.into());
        }
        Ok(())
    }
}

fn read_binary_body<R: BufRead>(
    path: &Path,
    src: &mut Src<R>,
    h: &Header,
    vi: usize,
    xyz: [usize; 3],
    big: bool,
) -> Result<Vec<Point3<f64>>, CloudError> {
    for e in &h.elements[..vi] {
        skip_binary_element(path, src, e, big)?;
    }
    let v = &h.elements[vi];
    let mut out = Vec::with_capacity(capacity(v.count, MAX_PREALLOC));
    let mut buf = [0u8; 8];
    let mut vals = [0f64; 3];
    // Rows of scalars only have one size: a row wholly in the reader's buffer is decoded
    // from it (the value of each of x, y, z at its byte offset), the others property by
    // property as any row. The same values (each property decoded from the same bytes,
    // and only the first of `xyz` naming a property set, as below), and the same errors,
    // since a row that could end the file early is read the general way.
    //
    // The rows wholly in the buffer are decoded together (up to the last row declared),
    // each the same way, so one look at the buffer serves them all.
    let row = fixed_row(v, xyz).filter(|(size, _)| *size > 0);
    // x, y and z all `float`: decoded at fixed offsets, without the dispatch per field.
    let f32_at = row.as_ref().and_then(|(_, fields)| f32_offsets(fields));
    let mut i = 0;
    while i < v.count {
        let start = src.pos;
        if let Some((size, fields)) = &row {
            if let Ok(b) = src.r.fill_buf() {
                let left = usize::try_from(v.count - i).unwrap_or(usize::MAX);
                let whole = (b.len() / size).min(left);
                if whole > 0 {
                    let bytes = whole * size;
                    let rows = b[..bytes].chunks_exact(*size);
                    if let Some(at) = f32_at {
                        let get = |b: &[u8], off: usize| Scalar::F32.decode(&b[off..], big);
                        out.extend(
                            rows.map(|b| Point3::new(get(b, at[0]), get(b, at[1]), get(b, at[2]))),
                        );
                    } else {
                        out.extend(rows.map(|b| {
                            for &(k, off, s) in fields {
                                vals[k] = s.decode(&b[off..], big);
                            }
                            Point3::new(vals[0], vals[1], vals[2])
                        }));
                    }
                    src.r.consume(bytes);
                    src.pos += bytes as u64;
                    i += whole as u64;
                    continue;
                }
            }
        }
        for (pi, p) in v.props.iter().enumerate() {
            let res = match p.kind {
                Kind::Scalar(s) => src.read_exact(&mut buf[..s.size()]).map(|()| {
                    if let Some(k) = xyz.iter().position(|&x| x == pi) {
                        vals[k] = s.decode(&buf, big);
                    }
                }),
                Kind::List(c, item) => skip_list(path, src, c, item, big, &mut buf)?,
            };
            res.map_err(|e| binary_read_err(path, e, src.pos, "vertex", i, start))?;
        }
        out.push(Point3::new(vals[0], vals[1], vals[2]));
        i += 1;
    }
    Ok(out)
}

/// One of x, y, z in a binary row of scalars: its index in `xyz`, its byte offset in the
/// row and its type.
type RowField = (usize, usize, Scalar);

/// The byte offsets of x, y and z in a row when `fields` sets each of them from a
/// `float` (the common layout, decoded without a per-field dispatch); `None` otherwise.
fn f32_offsets(fields: &[RowField]) -> Option<[usize; 3]> {
    let mut at = [None; 3];
    for &(k, off, s) in fields {
        if s != Scalar::F32 {
            return None;
        }
        *at.get_mut(k)? = Some(off);
    }
    Some([at[0]?, at[1]?, at[2]?])
}

/// For an element of scalar properties only: the size of a binary row (bytes), and the
/// [`RowField`] of each of x, y, z that [`read_binary_body`] sets (the first of `xyz`
/// naming a property). `None` if a property is a list.
fn fixed_row(v: &Element, xyz: [usize; 3]) -> Option<(usize, Vec<RowField>)> {
    let mut fields = Vec::new();
    let mut size = 0;
    for (pi, p) in v.props.iter().enumerate() {
        let Kind::Scalar(s) = p.kind else {
            return None;
        };
        if let Some(k) = xyz.iter().position(|&x| x == pi) {
            fields.push((k, size, s));
        }
        size += s.size();
    }
    Some((size, fields))
}

/// Reads a list count and skips the items; the outer result is a bad count, the inner one I/O.
fn skip_list<R: Read>(
    path: &Path,
    src: &mut Src<R>,
    c: Scalar,
    item: Scalar,
    big: bool,
    buf: &mut [u8; 8],
) -> Result<io::Result<()>, CloudError> {
    if let Err(e) = src.read_exact(&mut buf[..c.size()]) {
        return Ok(Err(e));
    }
    let n = c.decode(&buf[..], big);
    if n < 0.0 {
        return Err(body_err(
            path,
            format!("byte {}", src.pos - c.size() as u64),
            format!("negative list length {n}"),
        ));
    }
    // n is an integer of at most 32 bits, so the product cannot overflow.
    Ok(src.skip(to_u64(n) * item.size() as u64))
}

fn binary_read_err(
    path: &Path,
    e: io::Error,
    pos: u64,
    name: &str,
    i: u64,
    start: u64,
) -> CloudError {
    if e.kind() == io::ErrorKind::UnexpectedEof {
        body_err(
            path,
            format!("byte {pos}"),
            format!("file ends inside {name} {i} (which starts at byte {start})"),
        )
    } else {
        io_err(path, e)
    }
}

fn skip_binary_element<R: Read>(
    path: &Path,
    src: &mut Src<R>,
    e: &Element,
    big: bool,
) -> Result<(), CloudError> {
    let has_list = e.props.iter().any(|p| matches!(p.kind, Kind::List(..)));
    if !has_list {
        // Fixed rows: one skip (the size was checked against the file already).
        let start = src.pos;
        return src
            .skip(e.count.saturating_mul(e.min_binary_row()))
            .map_err(|err| binary_read_err(path, err, src.pos, &e.name, 0, start));
    }
    let mut buf = [0u8; 8];
    for i in 0..e.count {
        let start = src.pos;
        for p in &e.props {
            let res = match p.kind {
                Kind::Scalar(s) => src.skip(s.size() as u64),
                Kind::List(c, item) => skip_list(path, src, c, item, big, &mut buf)?,
            };
            res.map_err(|err| binary_read_err(path, err, src.pos, &e.name, i, start))?;
        }
    }
    Ok(())
}

fn read_ascii_body<R: BufRead>(
    path: &Path,
    r: &mut R,
    h: &Header,
    vi: usize,
    xyz: [usize; 3],
) -> Result<Vec<Point3<f64>>, CloudError> {
    let mut line_no = AsciiLines { lineno: h.lines };
    let v = &h.elements[vi];
    for e in &h.elements[..vi] {
        for i in 0..e.count {
            let (text, at) = line_no.next(path, r, &e.name, (i, e.count))?;
            check_ascii_row(path, &text, e, &at)?;
        }
    }
    let mut out = Vec::with_capacity(capacity(v.count, MAX_PREALLOC));
    for i in 0..v.count {
        let (text, at) = line_no.next(path, r, "vertex", (i, v.count))?;
        let toks: Vec<&str> = text.split_ascii_whitespace().collect();
        let starts = check_ascii_row(path, &text, v, &at)?;
        let mut vals = [0f64; 3];
        for (k, &pi) in xyz.iter().enumerate() {
            let t = toks[starts[pi]];
            let x = t.parse::<f64>().map_err(|_| {
                body_err(
                    path,
                    &at,
                    format!("vertex {i}: '{}' is not a number", shorten(t)),
                )
            })?;
            // A `float` property holds what a binary file would: the value rounded to f32.
            vals[k] = match v.props[pi].kind {
                Kind::Scalar(Scalar::F32) => f64::from(to_f32(x)),
                _ => x,
            };
        }
        out.push(Point3::new(vals[0], vals[1], vals[2]));
    }
    Ok(out)
}

/// Checks that an ascii row has the values its element declares (lists included), and
/// returns the index of the first token of each property.
fn check_ascii_row(
    path: &Path,
    text: &str,
    e: &Element,
    at: &str,
) -> Result<Vec<usize>, CloudError> {
    let mut toks = text.split_ascii_whitespace();
    let mut starts = Vec::with_capacity(e.props.len());
    let mut used = 0usize;
    for p in &e.props {
        starts.push(used);
        used += 1;
        let Some(t) = toks.next() else {
            return Err(body_err(
                path,
                at,
                format!("'{}' row has no value for property '{}'", e.name, p.name),
            ));
        };
        if let Kind::List(..) = p.kind {
            let n: u64 = t.parse().map_err(|_| {
                body_err(
                    path,
                    at,
                    format!("list length '{}' is not a non-negative integer", shorten(t)),
                )
            })?;
            for _ in 0..n {
                used += 1;
                if toks.next().is_none() {
                    return Err(body_err(
                        path,
                        at,
                        format!("list '{}' declares {n} items but the line ends", p.name),
                    ));
                }
            }
        }
    }
    if toks.next().is_some() {
        return Err(body_err(
            path,
            at,
            format!(
                "'{}' row has more values than the {} properties the header declares",
                e.name,
                e.props.len()
            ),
        ));
    }
    Ok(starts)
}

/// Walks the ascii body line by line, keeping the file line number.
struct AsciiLines {
    lineno: usize,
}

impl AsciiLines {
    fn next<R: BufRead>(
        &mut self,
        path: &Path,
        r: &mut R,
        name: &str,
        (i, of): (u64, u64),
    ) -> Result<(String, String), CloudError> {
        loop {
            self.lineno += 1;
            let at = format!("line {}", self.lineno);
            match read_line_capped(r, 1 << 20).map_err(|e| io_err(path, e))? {
                Line::Eof => {
                    return Err(body_err(
                        path,
                        at,
                        format!("file ends before {name} {i} of the {of} the header declares"),
                    ))
                }
                Line::TooLong => return Err(body_err(path, at, "line too long")),
                Line::Text(b, _) => {
                    let Ok(s) = String::from_utf8(b) else {
                        return Err(body_err(path, at, "line is not text"));
                    };
                    if s.trim().is_empty() {
                        continue;
                    }
                    return Ok((s, at));
                }
            }
        }
    }
}

/// At most 32 characters of `s`, for error messages.
pub(super) fn shorten(s: &str) -> String {
    let mut out: String = s.chars().take(32).collect();
    if out.len() < s.len() {
        out.push_str("...");
    }
    out
}

/// Writes points (metres) as a PLY file: vertex `x`, `y`, `z` as `float`, then one `float`
/// property per entry of `extra` (its name and one value per point, e.g. `detection`).
///
/// `binary` selects `binary_little_endian`, otherwise `ascii`. The file is written as
/// [`crate::report::atomic::write_with`] writes: through a temporary file renamed into place, so
/// readers never see a half-written file (the temporary file is removed on error).
pub fn write_ply_points(
    path: &Path,
    points: &[Point3<f64>],
    extra: &[(&str, Vec<f64>)],
    binary: bool,
) -> Result<(), CloudError> {
    let typed: Vec<_> = extra
        .iter()
        .map(|(n, v)| (*n, Scalar::F32, v.as_slice()))
        .collect();
    write_ply_typed(path, points, &typed, &[], binary)
}

/// [`write_ply_points`] with a PLY type per extra property (integers are written as `v as
/// i32`, `v as u8`, ...: truncated towards zero and saturated) and `comment` lines in the
/// header after `comment written by afford`.
pub(crate) fn write_ply_typed(
    path: &Path,
    points: &[Point3<f64>],
    extra: &[(&str, Scalar, &[f64])],
    comments: &[String],
    binary: bool,
) -> Result<(), CloudError> {
    for (name, _, values) in extra {
        let at = format!("property '{name}'");
        if name.is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(header_err(path, at, "property name must be one word"));
        }
        if ["x", "y", "z"].contains(name) || extra.iter().filter(|e| e.0 == *name).count() > 1 {
            return Err(header_err(path, at, "property name used twice"));
        }
        if values.len() != points.len() {
            return Err(header_err(
                path,
                at,
                format!("{} values for {} points", values.len(), points.len()),
            ));
        }
    }
    if let Some(c) = comments.iter().find(|c| c.contains(['\n', '\r'])) {
        return Err(header_err(
            path,
            "comment",
            format!("'{}' is not one line", shorten(c)),
        ));
    }
    crate::report::atomic::write_with(path, |w| write_body(w, points, extra, comments, binary))
        .map_err(|source| CloudError::Write {
            path: path.to_path_buf(),
            source,
        })
}

fn write_body(
    w: &mut dyn Write,
    points: &[Point3<f64>],
    extra: &[(&str, Scalar, &[f64])],
    comments: &[String],
    binary: bool,
) -> io::Result<()> {
    let format = if binary {
        "binary_little_endian"
    } else {
        "ascii"
    };
    writeln!(w, "ply\nformat {format} 1.0\ncomment written by afford")?;
    for c in comments {
        writeln!(w, "comment {c}")?;
    }
    writeln!(w, "element vertex {}", points.len())?;
    let xyz = ["x", "y", "z"].map(|n| (n, Scalar::F32));
    let props = xyz
        .iter()
        .copied()
        .chain(extra.iter().map(|(n, t, _)| (*n, *t)));
    for (name, ty) in props {
        writeln!(w, "property {} {name}", ty.name())?;
    }
    writeln!(w, "end_header")?;
    for (i, p) in points.iter().enumerate() {
        let values = (0..3)
            .map(|k| (Scalar::F32, p[k]))
            .chain(extra.iter().map(|(_, t, v)| (*t, v[i])));
        for (k, (ty, v)) in values.enumerate() {
            if binary {
                ty.write_le(w, v)?;
            } else {
                if k > 0 {
                    w.write_all(b" ")?;
                }
                ty.write_ascii(w, v)?;
            }
        }
        if !binary {
            writeln!(w)?;
        }
    }
    w.flush()
}

/// Reads one scalar vertex property `name` of a PLY file (e.g. the per-point `part` label
/// written by the synthetic data generator), one value per vertex in file order, or
/// `Ok(None)` if the vertex element has no scalar property of that name.
pub fn read_ply_property(path: &Path, name: &str) -> Result<Option<Vec<f64>>, CloudError> {
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let mut r = BufReader::with_capacity(1 << 16, file);
    let header = parse_header(path, &mut r)?;
    let Some(vi) = header.elements.iter().position(|e| e.name == "vertex") else {
        return Ok(None);
    };
    let Some(pi) = header.elements[vi]
        .props
        .iter()
        .position(|p| p.name == name && matches!(p.kind, Kind::Scalar(_)))
    else {
        return Ok(None);
    };
    // The point readers take three property indices; all three name the wanted one and
    // the value comes back as x.
    let pts = match header.encoding {
        Encoding::Ascii => read_ascii_body(path, &mut r, &header, vi, [pi; 3])?,
        enc => {
            let mut src = Src { r, pos: header.len };
            read_binary_body(
                path,
                &mut src,
                &header,
                vi,
                [pi; 3],
                enc == Encoding::BinaryBe,
            )?
        }
    };
    Ok(Some(pts.into_iter().map(|p| p.x).collect()))
}

#[cfg(test)]
// Test data: small literals and lengths, written into the fields of a file by hand.
#[allow(clippy::cast_possible_truncation)]
mod tests {
    use super::*;
    use ply_rs_bw::ply::{
        Addable, DefaultElement, ElementDef, Encoding as PlyEncoding, Ply, Property, PropertyDef,
        PropertyType, ScalarType,
    };
    use std::path::PathBuf;

    fn file(dir: &tempfile::TempDir, name: &str, bytes: &[u8]) -> PathBuf {
        let p = dir.path().join(name);
        std::fs::write(&p, bytes).unwrap();
        p
    }

    #[test]
    fn ascii_with_leading_element_odd_order_lists_and_faces() {
        let dir = tempfile::tempdir().unwrap();
        let text = "ply\r\nformat ascii 1.0\ncomment made by hand\nobj_info x\n\
            element camera 1\nproperty float view_px\nproperty list uchar int junk\n\
            element vertex 3\nproperty uchar red\nproperty float z\nproperty double nx\n\
            property float x\nproperty list uchar float extra\nproperty float y\n\
            element face 1\nproperty list uchar int vertex_indices\nend_header\n\
            1.5 2 7 8\n\
            255 3.25 0.1 1 0 -2\n\
            0 -1 0.2 4 2 9 9 5.5\n\n\
            7 nan 0 1e3 1 0 0.125\n\
            3 0 1 2\n";
        let p = file(&dir, "a.ply", text.as_bytes());
        let pts = read_ply(&p).unwrap();
        assert_eq!(pts.len(), 3);
        assert_eq!(pts[0], Point3::new(1.0, -2.0, 3.25));
        assert_eq!(pts[1], Point3::new(4.0, 5.5, -1.0));
        assert_eq!((pts[2].x, pts[2].y), (1000.0, 0.125));
        assert!(pts[2].z.is_nan());
    }

    /// A binary PLY: a `camera` element with a list before the vertices, vertices with an
    /// int and a double coordinate among other properties, then faces.
    fn binary_file(big: bool, pts: &[[f64; 3]]) -> Vec<u8> {
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut b = format!(
            "ply\nformat {fmt} 1.0\nelement camera 2\nproperty list uchar short ids\n\
             property float w\nelement vertex {}\nproperty double y\nproperty uchar red\n\
             property float x\nproperty short z\nproperty float detection\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n",
            pts.len()
        )
        .into_bytes();
        macro_rules! put {
            ($v:expr) => {
                if big {
                    b.extend_from_slice(&$v.to_be_bytes())
                } else {
                    b.extend_from_slice(&$v.to_le_bytes())
                }
            };
        }
        // camera 0: 2 ids; camera 1: none.
        put!(2u8);
        put!(7i16);
        put!(-7i16);
        put!(1.0f32);
        put!(0u8);
        put!(2.0f32);
        for p in pts {
            put!(p[1]);
            put!(200u8);
            put!(p[0] as f32);
            put!(p[2] as i16);
            put!(0.75f32);
        }
        put!(3u8);
        for i in 0..3i32 {
            put!(i);
        }
        b
    }

    #[test]
    fn binary_little_and_big_endian() {
        let dir = tempfile::tempdir().unwrap();
        let pts = [[0.5, 0.1, -3.0], [-1.25, 1e-9, 42.0], [7.0, -2.5, 0.0]];
        for big in [false, true] {
            let p = file(&dir, "b.ply", &binary_file(big, &pts));
            let got = read_ply(&p).unwrap();
            let want: Vec<_> = pts.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
            assert_eq!(got, want, "big endian: {big}");
        }
    }

    #[test]
    fn float_coordinates_in_any_order_among_other_properties() {
        // x, y, z all `float` (read at fixed offsets) in the order z, x, y with a `uchar`
        // and a `double` between them, 5 000 rows (batches and rows across the buffer).
        let dir = tempfile::tempdir().unwrap();
        let pts: Vec<[f32; 3]> = (0..5_000u16)
            .map(|i| {
                let i = f32::from(i);
                [i * 0.125 - 90.0, -i / 64.0, 1e-3 * i + 0.5]
            })
            .collect();
        for big in [false, true] {
            let mut b = format!(
                "ply\nformat binary_{}_endian 1.0\nelement vertex {}\nproperty float z\n\
                 property uchar flag\nproperty float x\nproperty double w\n\
                 property float y\nend_header\n",
                if big { "big" } else { "little" },
                pts.len()
            )
            .into_bytes();
            for p in &pts {
                let mut put = |v: &[u8]| b.extend_from_slice(v);
                let f = |x: f32| {
                    if big {
                        x.to_be_bytes()
                    } else {
                        x.to_le_bytes()
                    }
                };
                put(&f(p[2]));
                put(&[7]);
                put(&f(p[0]));
                put(&(if big {
                    2.5f64.to_be_bytes()
                } else {
                    2.5f64.to_le_bytes()
                }));
                put(&f(p[1]));
            }
            let got = read_ply(&file(&dir, "f.ply", &b)).unwrap();
            let want: Vec<_> = pts
                .iter()
                .map(|p| Point3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2])))
                .collect();
            assert_eq!(got, want, "big endian: {big}");
        }
    }

    #[test]
    fn rows_across_the_read_buffer_keep_their_values() {
        // 10 000 rows of 19 bytes after a 14-byte leading element: the 64 KiB buffer ends
        // inside rows again and again, so batches of whole rows alternate with rows read
        // property by property.
        let dir = tempfile::tempdir().unwrap();
        let pts: Vec<[f64; 3]> = (0..10_000)
            .map(|i| {
                let i = f64::from(i);
                [i / 8.0 - 300.0, i * 0.001 + 0.1, (i % 97.0) - 40.0]
            })
            .collect();
        for big in [false, true] {
            let p = file(&dir, "many.ply", &binary_file(big, &pts));
            let got = read_ply(&p).unwrap();
            let want: Vec<_> = pts.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
            assert_eq!(got, want, "big endian: {big}");
        }
    }

    /// Writes a PLY with ply-rs-bw (double x, float y, int z, a leading `quality` property and
    /// faces) and checks our reader sees the same points, in all three encodings.
    #[test]
    fn reads_what_ply_rs_bw_writes() {
        let dir = tempfile::tempdir().unwrap();
        let pts = [[1.0, 2.5, -3.0], [-0.1, 0.0, 12.0], [1e6, -7.75, 0.0]];
        for enc in [
            PlyEncoding::Ascii,
            PlyEncoding::BinaryLittleEndian,
            PlyEncoding::BinaryBigEndian,
        ] {
            let mut ply = Ply::<DefaultElement>::new();
            ply.header.encoding = enc;
            let mut v = ElementDef::new("vertex".to_string());
            for (n, t) in [
                ("quality", ScalarType::UChar),
                ("z", ScalarType::Int),
                ("x", ScalarType::Double),
                ("y", ScalarType::Float),
            ] {
                v.properties
                    .add(PropertyDef::new(n.to_string(), PropertyType::Scalar(t)));
            }
            ply.header.elements.add(v);
            let mut f = ElementDef::new("face".to_string());
            f.properties.add(PropertyDef::new(
                "vertex_indices".to_string(),
                PropertyType::List(ScalarType::UChar, ScalarType::Int),
            ));
            ply.header.elements.add(f);
            let verts = pts
                .iter()
                .map(|p| {
                    let mut e = DefaultElement::new();
                    e.insert("quality".to_string(), Property::UChar(9));
                    e.insert("z".to_string(), Property::Int(p[2] as i32));
                    e.insert("x".to_string(), Property::Double(p[0]));
                    e.insert("y".to_string(), Property::Float(p[1] as f32));
                    e
                })
                .collect();
            ply.payload.insert("vertex".to_string(), verts);
            let mut face = DefaultElement::new();
            face.insert(
                "vertex_indices".to_string(),
                Property::ListInt(vec![0, 1, 2]),
            );
            ply.payload.insert("face".to_string(), vec![face]);
            let mut buf = Vec::new();
            ply_rs_bw::writer::Writer::new()
                .write_ply(&mut buf, &mut ply)
                .unwrap();
            let p = file(&dir, "w.ply", &buf);
            let got = read_ply(&p).unwrap();
            let want: Vec<_> = pts
                .iter()
                .map(|p| Point3::new(p[0], f64::from(p[1] as f32), p[2]))
                .collect();
            assert_eq!(got, want, "{enc:?}");
        }
    }

    #[test]
    fn writer_round_trips_through_our_reader_and_ply_rs_bw() {
        let dir = tempfile::tempdir().unwrap();
        let pts = vec![
            Point3::new(0.5, -1.25, 3.0),
            Point3::new(1e-3, 2.0, -0.0),
            Point3::new(f64::NAN, 4.0, 5.0),
        ];
        let det = vec![1.0, 0.0, 2.0];
        let score = vec![0.25, -1.0, 0.5];
        for binary in [false, true] {
            let p = dir.path().join("out.ply");
            write_ply_points(
                &p,
                &pts,
                &[("detection", det.clone()), ("score", score.clone())],
                binary,
            )
            .unwrap();
            let got = read_ply(&p).unwrap();
            assert_eq!(got[0], pts[0]);
            assert_eq!(got[1], Point3::new(f64::from(1e-3f32), 2.0, 0.0));
            assert!(got[1].z.is_sign_negative());
            assert!(got[2].x.is_nan() && got[2].z == 5.0);

            if !binary {
                let text = std::fs::read_to_string(&p).unwrap();
                let body: Vec<_> = text.lines().skip_while(|l| *l != "end_header").collect();
                assert_eq!(
                    body,
                    [
                        "end_header",
                        "0.5 -1.25 3 1 0.25",
                        "0.001 2 -0 0 -1",
                        "nan 4 5 2 0.5"
                    ]
                );
                // ply-rs-bw does not read `nan` in ascii: cross-check binary files only.
                continue;
            }
            let mut f = File::open(&p).unwrap();
            let ply = ply_rs_bw::parser::Parser::<DefaultElement>::new()
                .read_ply(&mut f)
                .unwrap();
            let v = &ply.payload["vertex"];
            let d: Vec<_> = v.iter().map(|e| e["detection"].clone()).collect();
            assert_eq!(
                d,
                vec![
                    Property::Float(1.0),
                    Property::Float(0.0),
                    Property::Float(2.0)
                ]
            );
            assert_eq!(v[1]["score"], Property::Float(-1.0));
            let names: Vec<_> = ply.header.elements["vertex"].properties.keys().collect();
            assert_eq!(names, ["x", "y", "z", "detection", "score"]);
            let entries: Vec<_> = std::fs::read_dir(dir.path()).unwrap().collect();
            assert_eq!(entries.len(), 1, "temporary file left behind");
        }
    }

    #[test]
    fn typed_writer_writes_integers_and_comments() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("t.ply");
        let pts = [Point3::new(0.5, 1.0, 2.0), Point3::new(3.0, 4.0, 5.0)];
        let extra = [
            ("label", Scalar::I32, &[-1.0, 7.9][..]),
            ("red", Scalar::U8, &[300.0, 12.0][..]),
        ];
        let comments = ["affordance 1 sitting".to_string()];
        write_ply_typed(&p, &pts, &extra, &comments, false).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(text.contains("comment affordance 1 sitting\nelement vertex 2\n"));
        assert!(text.contains("property int label\nproperty uchar red\nend_header\n"));
        assert!(
            text.ends_with("end_header\n0.5 1 2 -1 255\n3 4 5 7 12\n"),
            "{text}"
        );
        write_ply_typed(&p, &pts, &extra, &comments, true).unwrap();
        assert_eq!(read_ply(&p).unwrap(), pts);
        assert_eq!(
            read_ply_property(&p, "red").unwrap(),
            Some(vec![255.0, 12.0])
        );
        let bad = ["two\nlines".to_string()];
        let e = write_ply_typed(&p, &pts, &extra, &bad, true).unwrap_err();
        assert!(matches!(e, CloudError::Header { .. }), "{e}");
    }

    #[test]
    fn writer_rejects_bad_extras_and_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("o.ply");
        let pts = [Point3::origin(), Point3::new(1.0, 1.0, 1.0)];
        let e = write_ply_points(&p, &pts, &[("d", vec![1.0])], true).unwrap_err();
        assert!(matches!(e, CloudError::Header { .. }), "{e}");
        let e = write_ply_points(&p, &pts, &[("x", vec![1.0, 2.0])], true).unwrap_err();
        assert!(matches!(e, CloudError::Header { .. }), "{e}");
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
        // A directory that does not exist: a write error, no panic.
        let e = write_ply_points(&dir.path().join("no/o.ply"), &pts, &[], false).unwrap_err();
        assert!(matches!(e, CloudError::Write { .. }), "{e}");
    }

    #[test]
    fn truncated_binary_is_a_body_error_naming_where() {
        let dir = tempfile::tempdir().unwrap();
        let full = binary_file(false, &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        let header_len = full.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        let faces = 1 + 3 * 4;
        // Cameras take 14 bytes (10 at least), vertices 2 x 19: cut 2 bytes into the
        // vertices' end. The size check (48 bytes at least) passes; the read itself fails.
        let cut = header_len + 14 + 38 - 2;
        assert_eq!(cut, full.len() - faces - 2);
        let p = file(&dir, "t.ply", &full[..cut]);
        let e = read_ply(&p).unwrap_err();
        match &e {
            CloudError::Body { at, what, .. } => {
                // The cut property (`detection`, 4 bytes) starts 15 bytes into the vertex.
                assert_eq!(at, &format!("byte {}", header_len + 14 + 19 + 15), "{e}");
                assert!(what.contains("inside vertex 1"), "{e}");
                assert!(
                    what.contains(&format!("starts at byte {}", header_len + 14 + 19)),
                    "{e}"
                );
            }
            _ => panic!("expected Body error, got {e}"),
        }
        // Cut deeper: the size check itself fails, before reading.
        let p = file(&dir, "u.ply", &full[..header_len + 30]);
        let e = read_ply(&p).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { what, .. } if what.contains("2 'vertex' elements")),
            "{e}"
        );
        // Truncated faces do not matter: the vertices are all there.
        let p = file(&dir, "f.ply", &full[..full.len() - 2]);
        assert_eq!(read_ply(&p).unwrap().len(), 2);
    }

    #[test]
    fn huge_claimed_count_fails_fast_without_allocating() {
        let dir = tempfile::tempdir().unwrap();
        for fmt in ["binary_little_endian", "ascii"] {
            let text = format!(
                "ply\nformat {fmt} 1.0\nelement vertex 18446744073709551615\n\
                 property float x\nproperty float y\nproperty float z\nend_header\n0 0 0\n"
            );
            let p = file(&dir, "h.ply", text.as_bytes());
            let e = read_ply(&p).unwrap_err();
            assert!(matches!(e, CloudError::Body { .. }), "{e}");
            assert!(e.to_string().contains("18446744073709551615"), "{e}");
        }
        // A huge face count after the vertices is never read.
        let text = "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\n\
                    property float y\nproperty float z\nelement face 4000000000\n\
                    property list uchar int vertex_indices\nend_header\n";
        let mut b = text.as_bytes().to_vec();
        for v in [1.0f32, 2.0, 3.0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        let p = file(&dir, "f.ply", &b);
        assert_eq!(read_ply(&p).unwrap(), vec![Point3::new(1.0, 2.0, 3.0)]);
    }

    #[test]
    fn header_errors_name_the_line() {
        let dir = tempfile::tempdir().unwrap();
        let cases: &[(&[u8], &str, &str)] = &[
            (b"", "line 1", "empty file"),
            (b"\x00\x01\x02\xff\xfe garbage\n\x13", "line 1", "not a PLY file"),
            (b"ply\nformat ascii 1.0\ncomment \xff\xfe\n", "line 3", "not text"),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float y\nproperty float z\nend_header\n1 2\n",
                "line 3",
                "no property 'x'",
            ),
            (
                b"ply\nformat ascii 1.0\nelement face 0\nend_header\n",
                "end_header",
                "no 'vertex' element",
            ),
            (b"ply\nformat ascii 1.0\nelement vertex 1\n", "line 4", "before 'end_header'"),
            (b"ply\nformat utf8 1.0\n", "line 2", "unknown format"),
            (b"ply\nformat ascii 1.0\nproperty float x\n", "line 3", "before any 'element'"),
            (
                b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n",
                "line 4",
                "unknown type",
            ),
            (b"ply\nelement vertex 0\nend_header\n", "line 2", "no 'format'"),
        ];
        for (bytes, at_want, what_want) in cases {
            let p = file(&dir, "e.ply", bytes);
            let e = read_ply(&p).unwrap_err();
            let msg = e.to_string();
            match &e {
                CloudError::Header { at, what, .. } => {
                    assert_eq!(at, at_want, "{msg}");
                    assert!(what.contains(what_want), "{msg}");
                }
                _ => panic!("expected Header error, got {msg}"),
            }
            assert!(!msg.contains('\n'), "{msg}");
            assert!(msg.starts_with(&p.display().to_string()), "{msg}");
        }
    }

    #[test]
    fn ascii_body_errors_name_the_file_line() {
        let dir = tempfile::tempdir().unwrap();
        let head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n\
                    property float y\nproperty float z\nend_header\n";
        for (body, what) in [
            ("1 2 3\n4 5          \n", "no value for property 'z'"),
            ("1 2 3\n4 5 6 7\n", "more values"),
            ("1 2 3\n4 abc 6\n", "'abc' is not a number"),
        ] {
            let p = file(&dir, "a.ply", format!("{head}{body}").as_bytes());
            let e = read_ply(&p).unwrap_err();
            assert!(
                matches!(&e, CloudError::Body { at, what: w, .. } if at == "line 9" && w.contains(what)),
                "{e}"
            );
        }
        // Fewer rows than declared, with room in the size check.
        let p = file(&dir, "s.ply", format!("{head}1 2 3      \n").as_bytes());
        let e = read_ply(&p).unwrap_err();
        assert!(
            matches!(&e, CloudError::Body { at, .. } if at == "line 9"),
            "{e}"
        );
    }

    #[test]
    fn random_garbage_never_panics() {
        let dir = tempfile::tempdir().unwrap();
        let good = binary_file(true, &[[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        for round in 0..300 {
            let mut b = good.clone();
            for _ in 0..1 + round % 6 {
                seed ^= seed << 13;
                seed ^= seed >> 7;
                seed ^= seed << 17;
                let i = (seed % b.len() as u64) as usize;
                b[i] = (seed >> 32) as u8;
            }
            b.truncate((seed >> 40) as usize % (b.len() + 1));
            let p = file(&dir, "g.ply", &b);
            let _ = read_ply(&p);
        }
    }

    #[test]
    fn read_ply_property_gets_one_extra_column() {
        let dir = tempfile::tempdir().unwrap();
        let pts = vec![Point3::new(0.0, 1.0, 2.0), Point3::new(3.0, 4.0, 5.0)];
        for binary in [true, false] {
            let path = dir.path().join(format!("p{binary}.ply"));
            write_ply_points(
                &path,
                &pts,
                &[("part", vec![1.0, 5.0]), ("other", vec![-1.0, 0.5])],
                binary,
            )
            .unwrap();
            assert_eq!(
                read_ply_property(&path, "part").unwrap(),
                Some(vec![1.0, 5.0])
            );
            assert_eq!(
                read_ply_property(&path, "other").unwrap(),
                Some(vec![-1.0, 0.5])
            );
            assert_eq!(read_ply_property(&path, "y").unwrap(), Some(vec![1.0, 4.0]));
            assert_eq!(read_ply_property(&path, "missing").unwrap(), None);
        }
    }
}
