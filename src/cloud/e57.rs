//! E57 files (ASTM E2807: terrestrial laser scanners, Matterport exports), read with the
//! `e57` crate: every scan with its pose (rotation and translation into the file's
//! coordinate system), merged, or one scan. Spherical coordinates are converted to
//! Cartesian; points without a valid Cartesian coordinate (direction-only or invalid)
//! are left out.

use std::path::Path;

use nalgebra::Point3;

use super::source::select_error;
use super::{CloudError, LoadedCloud};

fn bad(path: &Path, at: String, what: impl std::fmt::Display) -> CloudError {
    CloudError::Body {
        path: path.to_path_buf(),
        at,
        what: what.to_string(),
    }
}

/// Reads the scans of an E57 file in the file's coordinate system (metres): scan `scan`
/// (counted from 1) or, for `None`, every scan one after the other.
pub(crate) fn read_e57(path: &Path, scan: Option<usize>) -> Result<LoadedCloud, CloudError> {
    let file = std::fs::File::open(path).map_err(|source| CloudError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let mut reader =
        ::e57::E57Reader::new(std::io::BufReader::new(file)).map_err(|e| CloudError::Header {
            path: path.to_path_buf(),
            at: "the E57 header and XML section".into(),
            what: e.to_string(),
        })?;
    let clouds = reader.pointclouds();
    let chosen: Vec<(usize, ::e57::PointCloud)> = match scan {
        None => clouds.into_iter().enumerate().collect(),
        Some(k) => match clouds.get(k.wrapping_sub(1)) {
            Some(c) if k > 0 => vec![(k - 1, c.clone())],
            _ => {
                return Err(select_error(
                    path,
                    format!(
                        "--scan {k}: the file has {} scans (counted from 1)",
                        clouds.len()
                    ),
                ))
            }
        },
    };
    let mut points = Vec::new();
    let mut dropped = 0usize;
    for (i, pc) in chosen {
        let at = |n: usize| format!("scan {} point {n}", i + 1);
        let mut it = reader
            .pointcloud_simple(&pc)
            .map_err(|e| bad(path, format!("scan {}", i + 1), e))?;
        it.apply_pose(true);
        it.spherical_to_cartesian(true);
        for (n, p) in it.enumerate() {
            let p = p.map_err(|e| bad(path, at(n), e))?;
            match p.cartesian {
                ::e57::CartesianCoordinate::Valid { x, y, z } => {
                    let q = Point3::new(x, y, z);
                    if q.coords.iter().all(|c| c.is_finite()) {
                        points.push(q);
                    } else {
                        dropped += 1;
                    }
                }
                _ => dropped += 1,
            }
        }
    }
    Ok(LoadedCloud {
        cloud: super::PointCloud::new(points),
        dropped_non_finite: dropped,
    })
}
