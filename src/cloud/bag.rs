//! ROS bags in MCAP (ROS 2's default bag format, and ROS 1 bags converted to MCAP):
//! every `sensor_msgs/PointCloud2` message of one topic is one cloud. Chunks compressed
//! with zstd or lz4 are read by the `mcap` crate; the messages are decoded by
//! [`super::pointcloud2`].

use std::collections::BTreeSet;
use std::path::Path;

use super::pointcloud2::{decode, Encoding};
use super::source::{select_error, time_name, Part, Pick, SourceOptions};
use super::{keep_finite, CloudError};

/// Largest MCAP record read, bytes (1 GiB: a PointCloud2 of 40 M points of 24 bytes). The
/// `mcap` crate allocates what a record's length field says; a forged length beyond this
/// is an error instead of an allocation failure (found by the `bag` fuzz target).
const MAX_RECORD: usize = 1 << 30;

/// The messages of the bag in `buf`, in file order, with [`MAX_RECORD`].
fn messages(buf: &[u8]) -> ::mcap::io::MessageReader<&[u8]> {
    ::mcap::io::MessageReader::new_with_options(
        buf,
        ::mcap::sans_io::LinearReaderOptions::default().with_record_length_limit(MAX_RECORD),
    )
}

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

/// The topics of PointCloud2 messages in the bag, and every topic with its schema, from
/// the summary section when there is one, otherwise from a pass over the messages.
fn topics(path: &Path, buf: &[u8]) -> Result<(BTreeSet<String>, Vec<String>), CloudError> {
    let mut clouds = BTreeSet::new();
    let mut all = BTreeSet::new();
    let mut add = |topic: &str, schema: Option<&str>| {
        all.insert(format!("{topic} ({})", schema.unwrap_or("no schema")));
        if is_cloud(schema) {
            clouds.insert(topic.to_string());
        }
    };
    match ::mcap::Summary::read(buf) {
        Ok(Some(s)) if !s.channels.is_empty() => {
            for c in s.channels.values() {
                add(&c.topic, c.schema.as_ref().map(|s| s.name.as_str()));
            }
        }
        _ => {
            for (i, m) in messages(buf).enumerate() {
                let m = m.map_err(|e| body(path, format!("record of message {}", i + 1), e))?;
                add(
                    &m.channel.topic,
                    m.channel.schema.as_ref().map(|s| s.name.as_str()),
                );
            }
        }
    }
    Ok((clouds, all.into_iter().collect()))
}

/// Reads the PointCloud2 messages of a bag that `opts` selects (topic, then every N-th or
/// the one nearest a time) and hands each to `each` as a part named by its log time
/// ([`time_name`]), in file order. The points are in the message's frame, as sent.
pub fn read_bag(
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
    let mut nearest: Option<(u64, usize, ::mcap::Message<'static>)> = None;
    let decode_one = |m: &::mcap::Message, n: usize| -> Result<Part, CloudError> {
        let at = format!("message {n} on {topic}");
        let enc = encoding(&m.channel.message_encoding).ok_or_else(|| {
            body(
                path,
                at.clone(),
                format!(
                    "message encoding '{}' (this reader decodes cdr and ros1)",
                    m.channel.message_encoding
                ),
            )
        })?;
        let d = decode(&m.data, enc).map_err(|e| body(path, at, e))?;
        Ok(Part {
            name: Some(time_name(m.log_time)),
            cloud: keep_finite(d.points),
            camera: false,
        })
    };
    for (i, m) in messages(&buf).enumerate() {
        let m = m.map_err(|e| body(path, format!("record of message {}", i + 1), e))?;
        if m.channel.topic != topic {
            continue;
        }
        let schema = m.channel.schema.as_ref().map(|s| s.name.as_str());
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
                each(decode_one(&m, seen)?);
                handed += 1;
            }
            Pick::Every(n) => {
                if (seen - 1).is_multiple_of(n.max(1)) {
                    each(decode_one(&m, seen)?);
                    handed += 1;
                }
            }
            Pick::At(t) => {
                let d = m.log_time.abs_diff(t);
                if nearest.as_ref().is_none_or(|(best, _, _)| d < *best) {
                    nearest = Some((d, seen, m));
                }
            }
        }
    }
    if let Some((_, n, m)) = nearest {
        each(decode_one(&m, n)?);
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
