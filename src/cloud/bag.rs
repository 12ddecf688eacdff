//! ROS bags in MCAP (ROS 2's default bag format, and ROS 1 bags converted to MCAP):
//! every `sensor_msgs/PointCloud2` message of one topic is one cloud. The messages are
//! decoded by [`super::pointcloud2`].
//!
//! The records are read here, over the bytes of the whole file, with every length checked
//! against the bytes that are there before anything is allocated or subtracted: the `mcap`
//! crate's readers (0.26, the newest) allocate what a forged string length says (4 GB)
//! and subtract a forged record length from a chunk's size (an overflow panic where
//! overflow checks are on), both found by the `bag` fuzz target. Only the records this
//! reader needs are parsed (schema, channel, message, chunk, data end, footer); chunks
//! compressed with zstd or lz4 are inflated with the `zstd` and `lz4` crates (those the
//! `mcap` crate uses), into a buffer that grows with the bytes actually produced.

use std::collections::{BTreeSet, HashMap};
use std::io::Read;
use std::path::Path;

use super::pointcloud2::{decode, Encoding};
use super::source::{select_error, time_name, Part, Pick, SourceOptions};
use super::{keep_finite, CloudError};

/// Largest chunk inflated, bytes (1 GiB: a PointCloud2 of 40 M points of 24 bytes); a
/// chunk that says or turns out to be larger is an error.
const MAX_RECORD: u64 = 1 << 30;

/// The MCAP magic, at the start of the file and after the footer.
const MAGIC: &[u8] = ::mcap::MAGIC;

/// Record opcodes this reader acts on (MCAP specification).
use ::mcap::records::op;

/// Schema names of `sensor_msgs/PointCloud2` in ROS 2 and ROS 1.
const SCHEMAS: [&str; 2] = ["sensor_msgs/msg/PointCloud2", "sensor_msgs/PointCloud2"];

fn body(path: &Path, at: String, what: impl std::fmt::Display) -> CloudError {
    CloudError::Body {
        path: path.to_path_buf(),
        at,
        what: what.to_string(),
    }
}

fn is_cloud(schema: Option<&str>) -> bool {
    schema.is_some_and(|s| SCHEMAS.contains(&s))
}

/// The message encoding of a channel, when it is one this reader decodes.
fn encoding(message_encoding: &str) -> Option<Encoding> {
    match message_encoding {
        "cdr" => Some(Encoding::Cdr),
        "ros1" => Some(Encoding::Ros1),
        _ => None,
    }
}

/// The little-endian fields of a run of bytes, each read only when its bytes are there.
struct Fields<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl<'a> Fields<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        Fields { bytes, pos: 0 }
    }

    /// The next `n` bytes, or what is missing when fewer are left.
    fn take(&mut self, n: u64, what: &str) -> Result<&'a [u8], String> {
        let left = self.bytes.len() - self.pos;
        match usize::try_from(n) {
            Ok(n) if n <= left => {
                let s = &self.bytes[self.pos..self.pos + n];
                self.pos += n;
                Ok(s)
            }
            _ => Err(format!("{what} needs {n} bytes, {left} are left")),
        }
    }

    fn array<const N: usize>(&mut self, what: &str) -> Result<[u8; N], String> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.take(N as u64, what)?);
        Ok(a)
    }

    fn u16(&mut self, what: &str) -> Result<u16, String> {
        self.array(what).map(u16::from_le_bytes)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.array(what).map(u32::from_le_bytes)
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        self.array(what).map(u64::from_le_bytes)
    }

    /// A string: its length (u32), then that many bytes of UTF-8.
    fn string(&mut self, what: &str) -> Result<&'a str, String> {
        let n = self.u32(what)?;
        std::str::from_utf8(self.take(u64::from(n), what)?)
            .map_err(|_| format!("{what} is not UTF-8"))
    }

    /// Whatever follows the fields read so far.
    fn rest(self) -> &'a [u8] {
        &self.bytes[self.pos..]
    }

    /// The next record (opcode, length as u64, body), or `None` at the end of the bytes;
    /// an error says where the record starts and what is missing.
    fn record(&mut self) -> Result<Option<Record<'a>>, (usize, String)> {
        let at = self.pos;
        if at == self.bytes.len() {
            return Ok(None);
        }
        let read = |f: &mut Self| -> Result<Record<'a>, String> {
            let [opcode] = f.array::<1>("record opcode")?;
            let len = f.u64("record length")?;
            let body = f.take(len, &format!("record (opcode {opcode:#04x})"))?;
            Ok(Record { at, opcode, body })
        };
        read(self).map(Some).map_err(|e| (at, e))
    }
}

/// One record: where it starts (bytes into the file or chunk), its opcode and body.
struct Record<'a> {
    at: usize,
    opcode: u8,
    body: &'a [u8],
}

/// Takes each message of a bag: its channel, log time (ns) and data.
type OnMessage<'f> = dyn FnMut(&Channel, u64, &[u8]) -> Result<(), CloudError> + 'f;

/// A channel as the bag defines it.
#[derive(Debug, Clone, PartialEq)]
struct Channel {
    topic: String,
    /// The schema id (0: none) and the schema's name.
    schema: (u16, Option<String>),
    message_encoding: String,
}

/// The schemas (name, encoding, data) and channels defined so far, checked as the `mcap`
/// crate checks them: ids are unique (a repeated definition must be identical), schema
/// id 0 means none, a channel's schema and a message's channel are defined before use.
#[derive(Default)]
struct Table {
    schemas: HashMap<u16, (String, String, Vec<u8>)>,
    channels: HashMap<u16, Channel>,
}

impl Table {
    /// Adds the schema or channel record `body` (opcode `opcode`).
    fn add(&mut self, opcode: u8, body: &[u8]) -> Result<(), String> {
        let mut f = Fields::new(body);
        if opcode == op::SCHEMA {
            let id = f.u16("schema id")?;
            let name = f.string("schema name")?.to_string();
            let enc = f.string("schema encoding")?.to_string();
            let n = f.u32("schema data")?;
            let data = f.take(u64::from(n), "schema data")?.to_vec();
            if id == 0 {
                return Err("schema id 0 (reserved for none)".into());
            }
            define(&mut self.schemas, id, (name, enc, data), "schema")
        } else {
            let id = f.u16("channel id")?;
            let schema_id = f.u16("channel schema id")?;
            let topic = f.string("channel topic")?.to_string();
            let message_encoding = f.string("channel message encoding")?.to_string();
            let schema = match schema_id {
                0 => None,
                s => Some(
                    self.schemas
                        .get(&s)
                        .ok_or_else(|| {
                            format!("channel {topic} uses schema {s}, not defined before")
                        })?
                        .0
                        .clone(),
                ),
            };
            let new = Channel {
                topic,
                schema: (schema_id, schema),
                message_encoding,
            };
            define(&mut self.channels, id, new, "channel")
        }
    }

    /// The channel, log time (ns) and data of the message record `body`.
    fn message<'b>(&self, body: &'b [u8]) -> Result<(&Channel, u64, &'b [u8]), String> {
        let mut f = Fields::new(body);
        let id = f.u16("message channel id")?;
        f.u32("message sequence")?;
        let log_time = f.u64("message log time")?;
        f.u64("message publish time")?;
        let channel = self
            .channels
            .get(&id)
            .ok_or_else(|| format!("message on channel {id}, not defined before"))?;
        Ok((channel, log_time, f.rest()))
    }
}

/// Enters `new` under `id`; a repeated definition must be the same.
fn define<T: PartialEq>(
    map: &mut HashMap<u16, T>,
    id: u16,
    new: T,
    what: &str,
) -> Result<(), String> {
    match map.get(&id) {
        Some(old) if *old != new => Err(format!("{what} {id} defined twice, differently")),
        Some(_) => Ok(()),
        None => {
            map.insert(id, new);
            Ok(())
        }
    }
}

/// The records of the chunk record `body`, inflated when compressed (at most
/// [`MAX_RECORD`] bytes, the buffer growing with the bytes produced).
fn chunk_records(body: &[u8]) -> Result<std::borrow::Cow<'_, [u8]>, String> {
    let mut f = Fields::new(body);
    f.u64("chunk start time")?;
    f.u64("chunk end time")?;
    let size = f.u64("chunk uncompressed size")?;
    f.u32("chunk CRC")?;
    let compression = f.string("chunk compression")?;
    let n = f.u64("chunk records")?;
    let records = f.take(n, "chunk records")?;
    if compression.is_empty() {
        return Ok(records.into());
    }
    if size > MAX_RECORD {
        return Err(format!(
            "chunk of {size} bytes uncompressed exceeds limit of {MAX_RECORD}"
        ));
    }
    let mut out = Vec::new();
    let read = match compression {
        "zstd" => zstd::stream::read::Decoder::with_buffer(records)
            .and_then(|d| d.take(size + 1).read_to_end(&mut out)),
        "lz4" => lz4::Decoder::new(records).and_then(|d| d.take(size + 1).read_to_end(&mut out)),
        other => {
            return Err(format!(
                "chunk compression '{other}' (this reader inflates zstd and lz4)"
            ))
        }
    };
    read.map_err(|e| format!("{compression} chunk: {e}"))?;
    if out.len() as u64 != size {
        return Err(format!(
            "{compression} chunk inflates to {}{} bytes, its header says {size}",
            if out.len() as u64 > size {
                "more than "
            } else {
                ""
            },
            out.len().min(usize::try_from(size).unwrap_or(usize::MAX))
        ));
    }
    Ok(out.into())
}

/// One pass over the bag in `buf`, in file order: hands each message of the data section
/// to `each` with its channel and log time (ns); with `chunks` false, skips the chunks
/// (their messages and definitions). Returns the channels the summary section defines.
fn walk(
    path: &Path,
    buf: &[u8],
    chunks: bool,
    each: &mut OnMessage,
) -> Result<Vec<Channel>, CloudError> {
    if !buf.starts_with(MAGIC) {
        return Err(body(
            path,
            "byte 0".into(),
            "no MCAP magic (not an MCAP file)",
        ));
    }
    let mut file = Fields::new(buf);
    file.pos = MAGIC.len();
    let mut data = Table::default();
    let mut summary = Table::default();
    let mut past_end = false;
    loop {
        let Some(Record {
            at,
            opcode,
            body: record,
        }) = file
            .record()
            .map_err(|(at, e)| body(path, format!("byte {at}"), e))?
        else {
            return Err(body(
                path,
                format!("byte {}", buf.len()),
                "the file ends before the footer (cut short?)",
            ));
        };
        let here = |what: String| body(path, format!("byte {at}"), what);
        match opcode {
            op::FOOTER => {
                if buf.get(file.pos..file.pos + MAGIC.len()) != Some(MAGIC) {
                    return Err(here("no MCAP magic after the footer".into()));
                }
                return Ok(summary.channels.into_values().collect());
            }
            op::DATA_END => past_end = true,
            op::SCHEMA | op::CHANNEL if past_end => summary.add(opcode, record).map_err(here)?,
            _ if past_end => {}
            op::SCHEMA | op::CHANNEL => data.add(opcode, record).map_err(here)?,
            op::MESSAGE => {
                let (c, t, d) = data.message(record).map_err(here)?;
                each(c, t, d)?;
            }
            op::CHUNK if chunks => {
                let inner = chunk_records(record).map_err(here)?;
                let mut f = Fields::new(&inner);
                let within = |i: usize| format!("byte {i} of the chunk at byte {at}");
                while let Some(Record {
                    at: i,
                    opcode,
                    body: record,
                }) = f.record().map_err(|(i, e)| body(path, within(i), e))?
                {
                    let inside = |e: String| body(path, within(i), e);
                    match opcode {
                        op::SCHEMA | op::CHANNEL => data.add(opcode, record).map_err(inside)?,
                        op::MESSAGE => {
                            let (c, t, d) = data.message(record).map_err(inside)?;
                            each(c, t, d)?;
                        }
                        _ => {}
                    }
                }
            }
            _ => {}
        }
    }
}

/// The topics of PointCloud2 messages in the bag, and every topic with its schema, from
/// the summary section when it defines channels, otherwise from a pass over the messages.
fn topics(path: &Path, buf: &[u8]) -> Result<(BTreeSet<String>, Vec<String>), CloudError> {
    let mut clouds = BTreeSet::new();
    let mut all = BTreeSet::new();
    let mut add = |c: &Channel| {
        let schema = c.schema.1.as_deref();
        all.insert(format!("{} ({})", c.topic, schema.unwrap_or("no schema")));
        if is_cloud(schema) {
            clouds.insert(c.topic.clone());
        }
    };
    let summary = walk(path, buf, false, &mut |_, _, _| Ok(()))?;
    if summary.is_empty() {
        walk(path, buf, true, &mut |c, _, _| {
            add(c);
            Ok(())
        })?;
    } else {
        summary.iter().for_each(&mut add);
    }
    Ok((clouds, all.into_iter().collect()))
}

/// Reads the PointCloud2 messages of a bag that `opts` selects (topic, then every N-th or
/// the one nearest a time) and hands each to `each` as a part named by its log time
/// ([`time_name`]), in file order. The points are in the message's frame, as sent.
pub(crate) fn read_bag(
    path: &Path,
    opts: &SourceOptions,
    each: &mut dyn FnMut(Part),
) -> Result<usize, CloudError> {
    let buf = std::fs::read(path).map_err(|source| CloudError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let topic = match &opts.topic {
        Some(t) => t.clone(),
        None => {
            let (clouds, all) = topics(path, &buf)?;
            match clouds.len() {
                1 => clouds.into_iter().next().unwrap_or_default(),
                0 => {
                    return Err(select_error(
                        path,
                        format!(
                            "no sensor_msgs/PointCloud2 topic in the bag (topics: {})",
                            list(&all)
                        ),
                    ))
                }
                _ => {
                    return Err(select_error(
                        path,
                        format!(
                            "several PointCloud2 topics, pick one with --topic: {}",
                            clouds.into_iter().collect::<Vec<_>>().join(", ")
                        ),
                    ))
                }
            }
        }
    };
    let mut seen = 0usize;
    let mut handed = 0usize;
    // The message nearest `--at` so far: distance (ns), number, log time, encoding, data.
    let mut nearest: Option<(u64, usize, u64, String, Vec<u8>)> = None;
    let decode_one =
        |enc: &str, log_time: u64, data: &[u8], n: usize| -> Result<Part, CloudError> {
            let at = format!("message {n} on {topic}");
            let enc = encoding(enc).ok_or_else(|| {
                body(
                    path,
                    at.clone(),
                    format!("message encoding '{enc}' (this reader decodes cdr and ros1)"),
                )
            })?;
            let d = decode(data, enc).map_err(|e| body(path, at, e))?;
            Ok(Part {
                name: Some(time_name(log_time)),
                cloud: keep_finite(d.points),
                camera: false,
            })
        };
    walk(path, &buf, true, &mut |c, log_time, data| {
        if c.topic != topic {
            return Ok(());
        }
        let schema = c.schema.1.as_deref();
        if !is_cloud(schema) {
            return Err(select_error(
                path,
                format!(
                    "topic {topic} carries {}, not sensor_msgs/msg/PointCloud2",
                    schema.unwrap_or("messages without a schema")
                ),
            ));
        }
        seen += 1;
        match opts.pick {
            Pick::All => {
                each(decode_one(&c.message_encoding, log_time, data, seen)?);
                handed += 1;
            }
            Pick::Every(n) => {
                if (seen - 1).is_multiple_of(n.max(1)) {
                    each(decode_one(&c.message_encoding, log_time, data, seen)?);
                    handed += 1;
                }
            }
            Pick::At(t) => {
                let d = log_time.abs_diff(t);
                if nearest.as_ref().is_none_or(|(best, ..)| d < *best) {
                    let enc = c.message_encoding.clone();
                    nearest = Some((d, seen, log_time, enc, data.to_vec()));
                }
            }
        }
        Ok(())
    })?;
    if let Some((_, n, log_time, enc, data)) = nearest {
        each(decode_one(&enc, log_time, &data, n)?);
        handed += 1;
    }
    if seen == 0 {
        let (_, all) = topics(path, &buf)?;
        return Err(select_error(
            path,
            format!("no message on topic {topic} (topics: {})", list(&all)),
        ));
    }
    Ok(handed)
}

fn list(all: &[String]) -> String {
    if all.is_empty() {
        "none".into()
    } else {
        all.join(", ")
    }
}
