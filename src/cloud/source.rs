//! Which cloud (or clouds) of a file to read, for the formats that hold several or need
//! more than the file: ROS bags (a topic, some of its messages), E57 (one scan or all),
//! depth images (the camera's intrinsics). [`read_parts`] hands each cloud of a file to
//! a callback, so that a long bag is never held in memory as clouds.

use std::path::{Path, PathBuf};
use std::str::FromStr;

use super::{CloudError, LoadedCloud};

/// Which clouds of a file to read, and what a depth image needs.
#[derive(Debug, Clone, PartialEq)]
pub struct SourceOptions {
    /// ROS bags: the topic of `sensor_msgs/PointCloud2` messages; `None` takes the only
    /// such topic of the bag.
    pub topic: Option<String>,
    /// ROS bags: which messages of the topic.
    pub pick: Pick,
    /// E57: the scan to read, counted from 1; `None` merges every scan, each with its pose.
    pub scan: Option<usize>,
    /// Depth images: the pinhole intrinsics, pixels.
    pub intrinsics: Option<Intrinsics>,
    /// Depth images: metres per unit of the 16-bit depth value.
    pub depth_scale: f64,
}

/// Metres per depth unit when none is given: millimetres, as Kinect, RealSense and
/// ScanNet depth PNGs store them.
pub const DEPTH_SCALE: f64 = 0.001;

impl Default for SourceOptions {
    fn default() -> Self {
        SourceOptions {
            topic: None,
            pick: Pick::All,
            scan: None,
            intrinsics: None,
            depth_scale: DEPTH_SCALE,
        }
    }
}

/// Which messages of a bag's topic become clouds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pick {
    /// Every message.
    All,
    /// Every N-th message, starting with the first (N >= 1).
    Every(usize),
    /// The one message whose log time is nearest this time, nanoseconds since the epoch
    /// (the earlier of two equally near).
    At(u64),
}

/// Pinhole intrinsics of a depth camera, pixels: focal lengths and principal point
/// (`fx,fy,cx,cy`; pixel (u, v) counts columns from the left and rows from the top, its
/// centre at integer coordinates, as OpenCV, ROS `camera_info` and ScanNet give them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along image columns, pixels.
    pub fx: f64,
    /// Focal length along image rows, pixels.
    pub fy: f64,
    /// Principal point column, pixels.
    pub cx: f64,
    /// Principal point row, pixels.
    pub cy: f64,
}

impl FromStr for Intrinsics {
    type Err = String;

    /// Parses `fx,fy,cx,cy`: four finite numbers, focal lengths positive.
    fn from_str(s: &str) -> Result<Self, String> {
        let v: Vec<f64> = s
            .split(',')
            .map(|t| {
                t.trim()
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| format!("'{}' is not a number", t.trim()))
            })
            .collect::<Result<_, _>>()?;
        let [fx, fy, cx, cy] = v[..] else {
            return Err(format!(
                "give four numbers fx,fy,cx,cy (pixels), found {}",
                v.len()
            ));
        };
        if fx <= 0.0 || fy <= 0.0 {
            return Err("the focal lengths fx and fy must be positive".into());
        }
        Ok(Intrinsics { fx, fy, cx, cy })
    }
}

/// Parses a time in seconds since the epoch, as printed in result names
/// (`1700000000.25`), to nanoseconds, exactly (no floating point).
pub fn parse_time(s: &str) -> Result<u64, String> {
    let t = s.trim().trim_start_matches('@');
    let (whole, frac) = t.split_once('.').unwrap_or((t, ""));
    let digits = |d: &str| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit());
    if !digits(whole) || !(frac.is_empty() || digits(frac)) || frac.len() > 9 {
        return Err(format!(
            "'{s}' is not a time in seconds (digits, up to 9 decimals, e.g. 1700000000.25)"
        ));
    }
    let secs: u64 = whole.parse().map_err(|_| format!("'{s}' is too large"))?;
    let nanos: u64 = format!("{frac:0<9}").parse().unwrap_or(0);
    secs.checked_mul(1_000_000_000)
        .and_then(|n| n.checked_add(nanos))
        .ok_or_else(|| format!("'{s}' is too large"))
}

/// The name of a bag message's results: `@` and its log time in seconds with 9 decimals
/// (`@1700000000.250000000`), appended to the file name.
pub fn time_name(ns: u64) -> String {
    format!("@{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000)
}

/// One cloud of a file.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// What tells it apart from the file's other clouds (`@<time>` of a bag message);
    /// `None` when the file gives one cloud.
    pub name: Option<String>,
    /// The points, in the file's frame and units.
    pub cloud: LoadedCloud,
    /// The points are in a camera's optical frame (x right, y down, z forward) by the
    /// nature of the format (depth images), whatever the user said.
    pub camera: bool,
}

fn lower_ext(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default()
}

/// Whether `path` names a format that may hold several clouds or needs [`SourceOptions`]
/// (`.mcap`, `.e57`, `.png`).
pub fn needs_source(path: &Path) -> bool {
    matches!(lower_ext(path).as_str(), "mcap" | "e57" | "png")
}

/// The source options of `opts` that no file of `paths` reads, as warning lines (without
/// `warning: `), in the order of the flags: a `--topic`, `--every` or `--at` where no file
/// is a ROS bag, a `--scan` where none is an E57 file, an `--intrinsics` or a
/// `--depth-scale` other than millimetres where none is a depth image. Such an option is
/// left unused, which is what a batch over mixed files wants; given for files it does not
/// apply to, it is most likely a mistake worth a line.
pub fn unused_options(opts: &SourceOptions, paths: &[PathBuf]) -> Vec<String> {
    let any = |ext: &str| paths.iter().any(|p| lower_ext(p) == ext);
    let mut out = Vec::new();
    let mut unused = |given: bool, flag: &str, ext: &str, what: &str| {
        if given && !any(ext) {
            out.push(format!(
                "{flag} applies to {what} (.{ext}); no input is one, so it is not used"
            ));
        }
    };
    unused(opts.topic.is_some(), "--topic", "mcap", "ROS bags");
    let (every, at) = match opts.pick {
        Pick::All => (false, false),
        Pick::Every(_) => (true, false),
        Pick::At(_) => (false, true),
    };
    unused(every, "--every", "mcap", "ROS bags");
    unused(at, "--at", "mcap", "ROS bags");
    unused(opts.scan.is_some(), "--scan", "e57", "E57 files");
    unused(
        opts.intrinsics.is_some(),
        "--intrinsics",
        "png",
        "depth images",
    );
    unused(
        opts.depth_scale != DEPTH_SCALE,
        "--depth-scale",
        "png",
        "depth images",
    );
    out
}

/// An error about the options for a file (a topic it lacks, a scan it does not have).
pub(crate) fn select_error(path: &Path, what: impl Into<String>) -> CloudError {
    CloudError::Select {
        path: path.to_path_buf(),
        what: what.into(),
    }
}

/// Reads the clouds of `path` that `opts` selects and hands each to `each`, in file
/// order; returns how many there were. Formats with one cloud give one part. A bag whose
/// selection is empty is an error (naming the topics it has); an error after some parts
/// were handed over is returned after them.
pub fn read_parts(
    path: &Path,
    opts: &SourceOptions,
    each: &mut dyn FnMut(Part),
) -> Result<usize, CloudError> {
    let one = |cloud: LoadedCloud, camera: bool, each: &mut dyn FnMut(Part)| {
        each(Part {
            name: None,
            cloud,
            camera,
        });
        Ok(1)
    };
    match lower_ext(path).as_str() {
        "mcap" => super::bag::read_bag(path, opts, each),
        "e57" => one(super::e57::read_e57(path, opts.scan)?, false, each),
        "png" => {
            let Some(k) = opts.intrinsics else {
                return Err(select_error(
                    path,
                    "a depth image needs the camera's --intrinsics fx,fy,cx,cy",
                ));
            };
            let pts = super::depth::read_depth_png(path, &k, opts.depth_scale)?;
            one(super::keep_finite(pts), true, each)
        }
        _ => one(super::load_single(path)?, false, each),
    }
}

/// Reads the one cloud of `path` that `opts` selects; a selection of several clouds (a
/// bag with several messages on the topic) is an error saying how to pick one.
pub fn load_one(path: &Path, opts: &SourceOptions) -> Result<Part, CloudError> {
    let mut first: Option<Part> = None;
    let mut count = 0usize;
    read_parts(path, opts, &mut |p| {
        count += 1;
        if first.is_none() {
            first = Some(p);
        }
    })?;
    match (first, count) {
        (Some(p), 1) => Ok(p),
        (_, n) => Err(select_error(
            path,
            format!("{n} clouds selected where one is read; pick one with --at TIME"),
        )),
    }
}

/// The path of a part's results: the file as named, then the part's name.
pub fn part_label(path: &Path, part: Option<&str>) -> String {
    format!("{}{}", path.display(), part.unwrap_or(""))
}

/// `PathBuf` of a part for messages: the file with the part's name appended.
pub fn part_path(path: &Path, part: Option<&str>) -> PathBuf {
    PathBuf::from(part_label(path, part))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intrinsics_parse_and_refuse() {
        let k: Intrinsics = "525, 525.5,319.5,239.5".parse().unwrap();
        assert_eq!((k.fx, k.fy, k.cx, k.cy), (525.0, 525.5, 319.5, 239.5));
        for bad in [
            "525,525,319.5",
            "0,1,2,3",
            "a,1,2,3",
            "1,1,nan,3",
            "1,2,3,4,5",
        ] {
            assert!(bad.parse::<Intrinsics>().is_err(), "{bad}");
        }
    }

    #[test]
    fn times_parse_exactly_and_print_back() {
        assert_eq!(
            parse_time("1700000000.25").unwrap(),
            1_700_000_000_250_000_000
        );
        assert_eq!(parse_time("@3").unwrap(), 3_000_000_000);
        assert_eq!(parse_time("0.000000001").unwrap(), 1);
        let ns = 1_700_000_000_123_456_789;
        assert_eq!(time_name(ns), "@1700000000.123456789");
        assert_eq!(parse_time(&time_name(ns)).unwrap(), ns);
        for bad in [
            "",
            "-1",
            "1.2.3",
            "1e9",
            "1.0000000001",
            "99999999999999999999",
        ] {
            assert!(parse_time(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn source_options_for_no_input_of_their_kind_are_named() {
        let paths: Vec<PathBuf> = ["a.ply", "b.PCD", "c.e57"]
            .iter()
            .map(PathBuf::from)
            .collect();
        let opts = SourceOptions {
            topic: Some("/points".into()),
            pick: Pick::Every(3),
            scan: Some(2),
            intrinsics: Some(Intrinsics::from_str("500,500,320,240").unwrap()),
            depth_scale: 0.0002,
        };
        let lines = unused_options(&opts, &paths);
        let flags: Vec<&str> = lines.iter().filter_map(|l| l.split(' ').next()).collect();
        assert_eq!(
            flags,
            ["--topic", "--every", "--intrinsics", "--depth-scale"]
        );
        assert_eq!(
            lines[2],
            "--intrinsics applies to depth images (.png); no input is one, so it is not used"
        );
        let mut with_all = paths.clone();
        with_all.extend(["d.mcap", "e.png"].iter().map(PathBuf::from));
        assert!(unused_options(&opts, &with_all).is_empty());
        assert!(unused_options(&SourceOptions::default(), &paths).is_empty());
    }
}
