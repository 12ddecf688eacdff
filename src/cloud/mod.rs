//! Point clouds: the environment P of the paper (section 3.1), and the readers that load it.
//!
//! Every cloud handed to the detector is in metres, z up, with the floor at z = 0.

use std::path::{Path, PathBuf};

use nalgebra::Point3;

mod bag;
pub mod depth;
mod e57;
pub mod frame;
pub mod mesh;
mod pcd;
mod ply;
pub mod pointcloud2;
mod scannet;
pub mod source;
mod spacing;
mod xyz;

// One path per public item: the readers of single formats and the sample spacing are
// here; frames (`frame`), mesh sampling (`mesh`), multi-cloud sources (`source`), depth
// images (`depth`) and ROS messages (`pointcloud2`) are under their module's name.
pub use pcd::{read_pcd, write_pcd};
pub(crate) use ply::{parse_header, write_ply_typed, Encoding, Kind, Scalar};
pub use ply::{read_ply, read_ply_property, write_ply_points};
pub(crate) use spacing::robust_extent;
pub use spacing::{point_spacing, TileSpacing};
pub use xyz::read_xyz;

/// A point cloud in metres, z up (the environment P, section 3.1).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// The points, in metres, in the world frame (z up, floor at z = 0).
    pub points: Vec<Point3<f64>>,
}

/// A cloud as read from a file, with what the reader had to drop.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LoadedCloud {
    /// The finite points of the file.
    pub cloud: PointCloud,
    /// How many points had a NaN or infinite coordinate and were dropped.
    pub dropped_non_finite: usize,
}

/// What went wrong reading a cloud file. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum CloudError {
    /// The file could not be opened or read.
    #[error("{path}: cannot read: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The file could not be written.
    #[error("{path}: cannot write: {source}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// The path is not a regular file (a FIFO, a device, a socket): the readers check
    /// every count against the file's size, which such files do not have.
    #[error("{path}: not a regular file ({what}); give a file")]
    NotAFile {
        /// The file.
        path: PathBuf,
        /// What it is.
        what: &'static str,
    },
    /// The header is malformed; `at` says where (line or byte).
    #[error("{path}: bad header at {at}: {what}")]
    Header {
        /// The file.
        path: PathBuf,
        /// Where: "line N" or "byte N".
        at: String,
        /// What is wrong.
        what: String,
    },
    /// The body does not match the header; `at` says where (line or byte).
    #[error("{path}: bad data at {at}: {what}")]
    Body {
        /// The file.
        path: PathBuf,
        /// Where: "line N", "byte N" or "point N".
        at: String,
        /// What is wrong.
        what: String,
    },
    /// The options do not fit the file (a topic or scan it lacks, a depth image without
    /// intrinsics, several clouds where one is read).
    #[error("{path}: {what}")]
    Select {
        /// The file.
        path: PathBuf,
        /// What is wrong and how to fix it.
        what: String,
    },
    /// The file's extension names no format this tool reads.
    #[error(
        "{path}: unknown point cloud format (expected .ply, .pcd, .xyz, .txt, .csv, .e57, .mcap \
         or a depth .png, or a mesh: .obj, .off or .stl)"
    )]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Reads a point cloud file, choosing the reader by extension (`.ply`, `.pcd`,
/// `.xyz`/`.txt`/`.csv`; `.e57` merges every scan; a `.mcap` bag must hold one
/// PointCloud2 message; see [`source::read_parts`] to choose among several clouds).
///
/// Points with a non-finite coordinate are dropped and counted in [`LoadedCloud::dropped_non_finite`].
pub fn load(path: &Path) -> Result<LoadedCloud, CloudError> {
    regular_file(path)?;
    if source::needs_source(path) {
        return Ok(source::load_one(path, &source::SourceOptions::default())?.cloud);
    }
    load_single(path)
}

/// The readers of formats with one cloud and no options (PLY, PCD, text).
fn load_single(path: &Path) -> Result<LoadedCloud, CloudError> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    let raw = match ext.as_str() {
        "ply" => read_ply(path)?,
        "pcd" => read_pcd(path)?,
        "xyz" | "txt" | "csv" => read_xyz(path)?,
        _ => {
            return Err(CloudError::UnknownFormat {
                path: path.to_path_buf(),
            })
        }
    };
    Ok(keep_finite(raw))
}

/// Fails unless `path` is a regular file (after links). A missing file passes: opening it
/// gives the error that says so.
pub fn regular_file(path: &Path) -> Result<(), CloudError> {
    use std::os::unix::fs::FileTypeExt;
    let Ok(m) = std::fs::metadata(path) else {
        return Ok(());
    };
    let t = m.file_type();
    let what = if t.is_file() {
        return Ok(());
    } else if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    };
    Err(CloudError::NotAFile {
        path: path.to_path_buf(),
        what,
    })
}

/// Splits raw points into the finite ones and a count of the rest.
pub fn keep_finite(raw: Vec<Point3<f64>>) -> LoadedCloud {
    let total = raw.len();
    let points: Vec<Point3<f64>> = raw
        .into_iter()
        .filter(|p| p.coords.iter().all(|c| c.is_finite()))
        .collect();
    LoadedCloud {
        dropped_non_finite: total - points.len(),
        cloud: PointCloud { points },
    }
}

impl PointCloud {
    /// Builds a cloud from points in metres (world frame).
    pub fn new(points: Vec<Point3<f64>>) -> Self {
        Self { points }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the cloud has no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Axis-aligned bounds `(min, max)` in metres, or `None` for an empty cloud.
    pub fn bounds(&self) -> Option<(Point3<f64>, Point3<f64>)> {
        let first = *self.points.first()?;
        Some(
            self.points
                .iter()
                .fold((first, first), |(lo, hi), p| (lo.inf(p), hi.sup(p))),
        )
    }
}
