//! ROS 2 bags: PointCloud2 messages written with the `mcap` crate.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;

use afford::cloud::pointcloud2::encode_cdr;
use afford::cloud::source::{read_parts, Pick, SourceOptions};
use mcap::{Channel, Message, Schema, WriteOptions};
use nalgebra::Point3;

use super::*;

const T0: u64 = 1_700_000_000_000_000_000;
const TOPIC: &str = "/camera/depth/points";

/// A bag with one PointCloud2 message per entry of `clouds` on [`TOPIC`], 0.1 s apart
/// from [`T0`], each encoded as `layouts` says (height, pad fields, row padding, CDR
/// little endian, data big endian), and a string message on `/chatter` between them.
fn write_bag(
    path: &Path,
    clouds: &[Vec<Point3<f64>>],
    layouts: &[(u32, usize, usize, bool, bool)],
    compression: Option<mcap::Compression>,
) {
    let f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    let mut w = WriteOptions::new()
        .compression(compression)
        .profile("ros2")
        .create(f)
        .unwrap();
    let schema = Arc::new(Schema {
        id: 1,
        name: "sensor_msgs/msg/PointCloud2".into(),
        encoding: "ros2msg".into(),
        data: Cow::Borrowed(b"# the schema text is not read"),
    });
    let channel = Arc::new(Channel {
        id: 1,
        topic: TOPIC.into(),
        schema: Some(schema),
        message_encoding: "cdr".into(),
        metadata: BTreeMap::new(),
    });
    let chatter = Arc::new(Channel {
        id: 2,
        topic: "/chatter".into(),
        schema: Some(Arc::new(Schema {
            id: 2,
            name: "std_msgs/msg/String".into(),
            encoding: "ros2msg".into(),
            data: Cow::Borrowed(b"string data"),
        })),
        message_encoding: "cdr".into(),
        metadata: BTreeMap::new(),
    });
    for (i, (c, l)) in clouds.iter().zip(layouts).enumerate() {
        let t = T0 + i as u64 * 100_000_000;
        w.write(&Message {
            channel: channel.clone(),
            sequence: u32::try_from(i).unwrap(),
            log_time: t,
            publish_time: t,
            data: Cow::Owned(encode_cdr(c, l.0, l.1, l.2, l.3, l.4)),
        })
        .unwrap();
        w.write(&Message {
            channel: chatter.clone(),
            sequence: u32::try_from(i).unwrap(),
            log_time: t + 1,
            publish_time: t + 1,
            data: Cow::Borrowed(&[0, 1, 0, 0, 3, 0, 0, 0, b'h', b'i', 0]),
        })
        .unwrap();
    }
    w.finish().unwrap();
}

fn names(path: &Path, opts: &SourceOptions) -> Vec<String> {
    let mut out = Vec::new();
    read_parts(path, opts, &mut |p| out.push(p.name.unwrap())).unwrap();
    out
}

#[test]
fn each_message_gives_the_detections_of_its_points_as_ply() {
    let d = tempfile::tempdir().unwrap();
    // Message 0: organised in 2 rows with padded rows and a field before x, big-endian
    // CDR and data; message 1: another chair pose, one row, little endian.
    let a = chair_scene(0.0, 1);
    let mut b = chair_scene(90.0, 2);
    b.truncate(b.len() / 2 * 2);
    let a_even: Vec<_> = a[..a.len() / 2 * 2].to_vec();
    let bag = d.path().join("run.mcap");
    write_bag(
        &bag,
        &[a_even.clone(), b.clone()],
        &[(2, 1, 6, false, true), (1, 0, 0, true, false)],
        Some(mcap::Compression::Zstd),
    );
    let got = detect_json(d.path(), &bag, &[]);
    let files = got["files"].as_array().unwrap();
    assert_eq!(files.len(), 2);
    let name = bag.display().to_string();
    assert_eq!(files[0]["file"], format!("{name}@1700000000.000000000"));
    assert_eq!(files[1]["file"], format!("{name}@1700000000.100000000"));
    for (i, pts) in [a_even, b].iter().enumerate() {
        let ply = d.path().join(format!("m{i}.ply"));
        write_ply_f64(&ply, pts);
        let want = detect_json(d.path(), &ply, &[]);
        assert_finds_a_seat(&want, 0);
        assert_eq!(detections(&got, i), detections(&want, 0), "message {i}");
    }
}

#[test]
fn every_compression_gives_the_same_points_and_messages_are_picked() {
    let d = tempfile::tempdir().unwrap();
    let clouds: Vec<Vec<Point3<f64>>> = (0..5)
        .map(|i| {
            (0..12)
                .map(|k| Point3::new(k as f64 * 0.125, i as f64, 0.5))
                .collect()
        })
        .collect();
    let layouts = [
        (1, 0, 0, true, false),
        (3, 2, 4, false, false),
        (4, 0, 1, true, true),
        (2, 1, 0, false, true),
        (6, 0, 0, true, false),
    ];
    for (k, c) in [
        None,
        Some(mcap::Compression::Lz4),
        Some(mcap::Compression::Zstd),
    ]
    .into_iter()
    .enumerate()
    {
        let bag = d.path().join(format!("b{k}.mcap"));
        write_bag(&bag, &clouds, &layouts, c);
        let mut got = Vec::new();
        let n = read_parts(&bag, &SourceOptions::default(), &mut |p| {
            got.push(p.cloud.cloud.points)
        })
        .unwrap();
        assert_eq!(n, 5);
        assert_eq!(got, clouds, "compression {c:?}");
        let every = SourceOptions {
            pick: Pick::Every(2),
            ..Default::default()
        };
        let t = |s: &str| format!("@1700000000.{s}00000000");
        assert_eq!(names(&bag, &every), [t("0"), t("2"), t("4")]);
        let at = SourceOptions {
            pick: Pick::At(T0 + 260_000_000),
            topic: Some(TOPIC.into()),
            ..Default::default()
        };
        assert_eq!(names(&bag, &at), [t("3")]);
    }
}

#[test]
fn a_wrong_topic_or_a_damaged_bag_is_one_line_naming_the_file() {
    let d = tempfile::tempdir().unwrap();
    let bag = d.path().join("run.mcap");
    let c: Vec<Point3<f64>> = vec![Point3::new(1.0, 2.0, 3.0); 4];
    write_bag(&bag, &[c], &[(1, 0, 0, true, false)], None);
    let err = |path: &Path, opts: &SourceOptions| {
        read_parts(path, opts, &mut |_| {}).unwrap_err().to_string()
    };
    let e = err(
        &bag,
        &SourceOptions {
            topic: Some("/nope".into()),
            ..Default::default()
        },
    );
    assert!(
        e.contains("run.mcap") && e.contains("/nope") && e.contains(TOPIC),
        "{e}"
    );
    let e = err(
        &bag,
        &SourceOptions {
            topic: Some("/chatter".into()),
            ..Default::default()
        },
    );
    assert!(e.contains("std_msgs/msg/String"), "{e}");
    // Cut anywhere: an error naming the file (or, cut in the summary, the same points).
    let bytes = std::fs::read(&bag).unwrap();
    let cut = d.path().join("cut.mcap");
    for n in (0..bytes.len()).step_by(7) {
        std::fs::write(&cut, &bytes[..n]).unwrap();
        match read_parts(&cut, &SourceOptions::default(), &mut |_| {}) {
            Err(e) => {
                let e = e.to_string();
                assert!(
                    e.starts_with(&cut.display().to_string()) && !e.contains('\n'),
                    "{e}"
                );
            }
            Ok(k) => assert_eq!(k, 1, "cut at {n}"),
        }
    }
    // Two PointCloud2 topics and no --topic: the error lists both.
    let two = d.path().join("two.mcap");
    let f = std::io::BufWriter::new(std::fs::File::create(&two).unwrap());
    let mut w = WriteOptions::new().create(f).unwrap();
    for (id, topic) in [(1u16, "/a"), (2, "/b")] {
        let ch = Arc::new(Channel {
            id,
            topic: topic.into(),
            schema: Some(Arc::new(Schema {
                id: 1,
                name: "sensor_msgs/msg/PointCloud2".into(),
                encoding: "ros2msg".into(),
                data: Cow::Borrowed(b""),
            })),
            message_encoding: "cdr".into(),
            metadata: BTreeMap::new(),
        });
        w.write(&Message {
            channel: ch,
            sequence: 0,
            log_time: 5,
            publish_time: 5,
            data: Cow::Owned(encode_cdr(&[Point3::origin()], 1, 0, 0, true, false)),
        })
        .unwrap();
    }
    w.finish().unwrap();
    let e = err(&two, &SourceOptions::default());
    assert!(e.contains("--topic") && e.contains("/a, /b"), "{e}");
}

/// Fuzz seeds: bags in every compression, and bare messages (first byte 0: CDR).
pub(crate) fn seeds(dir: &Path, pts: &[Point3<f64>]) {
    let clouds = [pts.to_vec(), pts.to_vec()];
    let layouts = [(2, 1, 2, false, true), (1, 0, 0, true, false)];
    for (name, c) in [
        ("plain", None),
        ("lz4", Some(mcap::Compression::Lz4)),
        ("zstd", Some(mcap::Compression::Zstd)),
    ] {
        write_bag(&dir.join(format!("seed_{name}.mcap")), &clouds, &layouts, c);
    }
    let mut msg = vec![0u8];
    msg.extend(encode_cdr(pts, 2, 1, 2, false, true));
    std::fs::write(dir.join("seed_message.cdr"), msg).unwrap();
}

#[test]
fn convert_takes_one_message_by_time_and_refuses_a_choice_of_several() {
    let d = tempfile::tempdir().unwrap();
    let bag = d.path().join("run.mcap");
    let clouds: Vec<Vec<Point3<f64>>> = (0..3)
        .map(|i| vec![Point3::new(i as f64, 0.5, 0.25); 3])
        .collect();
    write_bag(&bag, &clouds, &[(1, 0, 0, true, false); 3], None);
    let out = d.path().join("one.ply");
    let (b, o) = (bag.to_str().unwrap(), out.to_str().unwrap());
    afford(&["convert", b, o, "--at", "1700000000.14"]);
    assert_eq!(afford::cloud::read_ply(&out).unwrap(), clouds[1]);
    std::fs::remove_file(&out).unwrap();
    assert_eq!(afford_cli::cli::main(["afford", "convert", b, o]), 2);
    assert!(!out.exists());
    let both = [
        "afford",
        "convert",
        b,
        o,
        "--every",
        "2",
        "--at",
        "1700000000.3",
    ];
    assert_eq!(afford_cli::cli::main(both), 2);
}

#[test]
fn a_forged_record_length_is_an_error_not_an_allocation_failure() {
    // Found by the `bag` fuzz target: a record inside a zstd chunk claims 434 PB, which
    // the `mcap` crate allocated (abort); every record must fit in the bytes it is in.
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("forged.mcap");
    std::fs::write(&p, include_bytes!("crash_record_length.mcap")).unwrap();
    let e = read_parts(&p, &SourceOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("forged.mcap") && e.contains("of the chunk at byte") && e.contains("needs"),
        "{e}"
    );
}

/// An MCAP file: the magic, `records` (opcode, body), a footer (no summary) and the magic.
fn mcap_file(records: &[(u8, Vec<u8>)]) -> Vec<u8> {
    let mut out = mcap::MAGIC.to_vec();
    let footer = (0x02, vec![0u8; 20]);
    for (op, body) in records.iter().chain([&footer]) {
        out.push(*op);
        out.extend((body.len() as u64).to_le_bytes());
        out.extend(body);
    }
    out.extend(mcap::MAGIC);
    out
}

/// The body of a chunk record: times 0, `size` bytes uncompressed, no CRC, `compression`,
/// then `records` (as stored).
fn chunk(size: u64, compression: &str, records: &[u8]) -> Vec<u8> {
    let mut c = vec![0u8; 16];
    c.extend(size.to_le_bytes());
    c.extend(0u32.to_le_bytes());
    c.extend(u32::try_from(compression.len()).unwrap().to_le_bytes());
    c.extend(compression.as_bytes());
    c.extend((records.len() as u64).to_le_bytes());
    c.extend(records);
    c
}

/// Reads `bytes` as `name` and returns the error, which must be one line naming the file.
fn bag_error(name: &str, bytes: &[u8]) -> String {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join(name);
    std::fs::write(&p, bytes).unwrap();
    let e = read_parts(&p, &SourceOptions::default(), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with(&p.display().to_string()) && !e.contains('\n'),
        "{e}"
    );
    e
}

#[test]
fn a_forged_string_length_is_an_error_not_a_4_gb_allocation() {
    // The defect the `bag` fuzz target found, rebuilt by hand: the `mcap` crate (0.26)
    // reserves what a string's length field says before reading it, here 4 GB for a
    // channel topic of 3 bytes, which aborts under an address-space limit. The reader
    // checks every length first.
    let mut channel = vec![1, 0, 0, 0];
    channel.extend(0xFFFF_FFF0u32.to_le_bytes());
    channel.extend(b"/pc");
    let e = bag_error("string.mcap", &mcap_file(&[(0x04, channel)]));
    assert!(
        e.contains("byte 8") && e.contains("channel topic needs 4294967280 bytes, 3 are left"),
        "{e}"
    );
}

#[test]
fn a_record_longer_than_its_uncompressed_chunk_is_an_error_not_an_overflow() {
    // The defect the `bag` fuzz target found, rebuilt by hand: in an uncompressed chunk
    // whose records field holds 9 bytes, a record claiming 20 bytes (the footer after the
    // chunk supplies them) made the `mcap` crate subtract 29 from the chunk's 9 remaining
    // bytes, a panic where overflow checks are on. The record must fit in the chunk.
    let mut record = vec![0x80];
    record.extend(20u64.to_le_bytes());
    let e = bag_error("chunk.mcap", &mcap_file(&[(0x06, chunk(9, "", &record))]));
    assert!(
        e.contains("byte 0 of the chunk at byte 8") && e.contains("needs 20 bytes, 0 are left"),
        "{e}"
    );
}

#[test]
fn a_compressed_chunk_that_inflates_to_another_size_is_an_error() {
    // The header's uncompressed size is checked against what the chunk inflates to, and
    // a size over the 1 GiB limit is refused before anything is inflated.
    let records = [0x80u8, 0, 0, 0, 0, 0, 0, 0, 0];
    let chunk = |size: u64, compressed: &[u8]| chunk(size, "zstd", compressed);
    let z = zstd::encode_all(&records[..], 3).unwrap();
    let e = bag_error("short.mcap", &mcap_file(&[(0x06, chunk(10, &z))]));
    assert!(e.contains("inflates to 9 bytes, its header says 10"), "{e}");
    let e = bag_error("long.mcap", &mcap_file(&[(0x06, chunk(8, &z))]));
    assert!(e.contains("inflates to more than 8 bytes"), "{e}");
    let e = bag_error("huge.mcap", &mcap_file(&[(0x06, chunk(1 << 40, &z))]));
    assert!(e.contains("exceeds limit"), "{e}");
    // The same chunk with its true size reads (no PointCloud2 topic: a selection error).
    let e = bag_error("fine.mcap", &mcap_file(&[(0x06, chunk(9, &z))]));
    assert!(e.contains("no sensor_msgs/PointCloud2 topic"), "{e}");
}
