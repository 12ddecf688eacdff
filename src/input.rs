//! Turning a user's file into the cloud the detector needs: points or a sampled mesh,
//! in metres, z up, with the floor at z = 0 (the environment P of section 3.1).

use std::path::{Path, PathBuf};

use crate::cloud::frame::{FrameError, FrameOptions, FrameReport};
use crate::cloud::{self, CloudError, LoadedCloud, PointCloud};

/// How input files are read and brought into the world frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct InputOptions {
    /// Units, transform, up axis, camera frame and floor levelling.
    pub frame: FrameOptions,
    /// Sample meshes (and PLY files with faces) at this many points per square metre;
    /// `None` reads PLY vertices as points and samples OBJ/OFF/STL at [`MESH_DENSITY`].
    pub sample: Option<f64>,
    /// Which clouds of bags, E57 files and depth images (topic, messages, scan, intrinsics).
    pub source: cloud::source::SourceOptions,
}

/// Default surface density for meshes, points per square metre: 1 cm apart, so that every
/// 2 cm voxel of a surface is hit.
pub const MESH_DENSITY: f64 = 10_000.0;
/// Seed of mesh sampling: the same mesh always gives the same points.
const MESH_SEED: u64 = 0;

/// A cloud ready for detection.
#[derive(Debug, Clone, PartialEq)]
pub struct Input {
    /// Which cloud of the file this is (`@<time>` of a bag message), `None` for the file's
    /// only cloud; see [`crate::cloud::source::part_label`].
    pub part: Option<String>,
    /// The points, world frame.
    pub cloud: PointCloud,
    /// Points dropped for a non-finite coordinate.
    pub dropped_non_finite: usize,
    /// What was done to bring it into the world frame, when anything was.
    pub frame: Option<FrameReport>,
    /// A warning about the units the extent suggests.
    pub units_warning: Option<String>,
    /// A warning that the floor seems not to be at z = 0 ([`cloud::frame::check_floor`]).
    pub floor_warning: Option<String>,
}

/// What went wrong turning a file into a world-frame cloud.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    /// The file could not be read.
    #[error(transparent)]
    Cloud(#[from] CloudError),
    /// The frame could not be established (no floor found, bad transform).
    #[error("{path}: {source}")]
    Frame {
        /// The file.
        path: PathBuf,
        /// The cause.
        #[source]
        source: FrameError,
    },
}

fn is_mesh(path: &Path) -> bool {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    matches!(ext.as_deref(), Some("obj" | "off" | "stl"))
}

/// Reads `path` (points, or a mesh sampled by area) and brings it into the world frame.
/// A file must give one cloud: a bag with several selected messages is an error (see
/// [`load_inputs`]).
pub fn load_input(path: &Path, opts: &InputOptions) -> Result<Input, InputError> {
    let mut first = None;
    let mut count = 0usize;
    let mut failed = None;
    load_inputs(path, opts, &mut |i| {
        count += 1;
        match i {
            Ok(i) if first.is_none() => first = Some(i),
            Err(e) if failed.is_none() => failed = Some(e),
            _ => {}
        }
    })?;
    if let Some(e) = failed {
        return Err(e);
    }
    match (first, count) {
        (Some(i), 1) => Ok(i),
        (_, n) => Err(InputError::Cloud(cloud::source::select_error(
            path,
            format!("{n} clouds selected where one is read; pick one with --at TIME"),
        ))),
    }
}

/// Reads every cloud of `path` that `opts.source` selects (one for most formats, the
/// selected messages of a bag), brings each into the world frame and hands it to `each`
/// as it is read: a long bag is never held in memory. Returns how many clouds were read;
/// an error of the file itself (unreadable, malformed) is returned, an error of one
/// cloud's frame (no floor found) is handed over in its place.
pub fn load_inputs(
    path: &Path,
    opts: &InputOptions,
    each: &mut dyn FnMut(Result<Input, InputError>),
) -> Result<usize, InputError> {
    let to_input = |part: cloud::source::Part| -> Result<Input, InputError> {
        let mut frame = opts.frame.clone();
        // Depth images are in the camera's optical frame, whatever the flags say.
        frame.camera |= part.camera;
        world(path, part.name, part.cloud, &frame)
    };
    if is_mesh(path) || opts.sample.is_some() {
        let mesh = cloud::mesh::read_mesh(path)?;
        // Density is per square metre of the final cloud; the mesh is in the file's units.
        let k = opts.frame.units.factor();
        let density = opts.sample.unwrap_or(MESH_DENSITY) * k * k;
        let loaded = cloud::keep_finite(cloud::mesh::sample_mesh(&mesh, density, MESH_SEED).points);
        each(to_input(cloud::source::Part {
            name: None,
            cloud: loaded,
            camera: false,
        }));
        return Ok(1);
    }
    Ok(cloud::source::read_parts(path, &opts.source, &mut |p| {
        each(to_input(p))
    })?)
}

/// Brings a cloud already read (finite points, as given) into the world frame with
/// `frame`, and checks its units; `path` names it in messages (a file, or a name given
/// to points held in memory). What [`load_inputs`] does after reading.
pub fn to_input(
    path: &Path,
    loaded: LoadedCloud,
    frame: &FrameOptions,
) -> Result<Input, InputError> {
    world(path, None, loaded, frame)
}

/// Brings one cloud of `path` into the world frame.
fn world(
    path: &Path,
    part: Option<String>,
    loaded: cloud::LoadedCloud,
    frame: &FrameOptions,
) -> Result<Input, InputError> {
    let untouched = *frame == FrameOptions::default();
    let label = cloud::source::part_label(path, part.as_deref());
    let (cloud, frame) = if untouched {
        (loaded.cloud, None)
    } else {
        let (c, r) =
            cloud::frame::to_world(loaded.cloud, frame).map_err(|source| InputError::Frame {
                path: PathBuf::from(&label),
                source,
            })?;
        (c, Some(r))
    };
    let extent = cloud::robust_extent(&cloud);
    let named = |w: String| format!("{label}: {w}");
    let units_warning = extent
        .as_ref()
        .and_then(|e| cloud::frame::units_warning(&cloud, e))
        .map(named);
    // A levelled cloud has its floor at z = 0 by construction.
    let levelled = frame.as_ref().is_some_and(|f| f.floor.is_some());
    let floor_warning = extent
        .as_ref()
        .filter(|_| !levelled)
        .and_then(cloud::frame::floor_warning)
        .map(named);
    Ok(Input {
        part,
        cloud,
        dropped_non_finite: loaded.dropped_non_finite,
        frame,
        units_warning,
        floor_warning,
    })
}

/// Extensions taken from a folder (clouds and meshes), lower case. Text clouds named
/// `.txt` or `.csv` are read when given by name, but not picked out of a folder, where
/// such files are usually labels and notes; PNG depth images likewise, as a folder of
/// PNGs is more often pictures.
pub const EXTENSIONS: [&str; 8] = ["ply", "pcd", "xyz", "obj", "off", "stl", "e57", "mcap"];

/// The files in folder `dir` (not recursive) whose extension is one of `extensions`
/// (lower case; compared without case), sorted by name.
pub fn files_in(dir: &Path, extensions: &[&str]) -> std::io::Result<Vec<PathBuf>> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|f| {
            f.is_file()
                && f.extension()
                    .and_then(|e| e.to_str())
                    .is_some_and(|e| extensions.contains(&e.to_ascii_lowercase().as_str()))
        })
        .collect();
    files.sort();
    Ok(files)
}

/// Expands the inputs of a run: a folder stands for the files in it with one of
/// [`EXTENSIONS`] (not recursive), sorted by name; files are kept as given.
pub fn expand_inputs(paths: &[PathBuf]) -> Result<Vec<PathBuf>, CloudError> {
    let mut out = Vec::new();
    for p in paths {
        if p.is_dir() {
            out.extend(files_in(p, &EXTENSIONS).map_err(|source| CloudError::Io {
                path: p.clone(),
                source,
            })?);
        } else {
            out.push(p.clone());
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_folder_expands_to_its_clouds_in_name_order() {
        let d = tempfile::tempdir().unwrap();
        for f in ["b.ply", "a.pcd", "notes.md", "c.STL"] {
            std::fs::write(d.path().join(f), b"x").unwrap();
        }
        std::fs::create_dir(d.path().join("sub.ply")).unwrap();
        let single = d.path().join("z.xyz");
        let got = expand_inputs(&[d.path().to_path_buf(), single.clone()]).unwrap();
        let names: Vec<String> = got
            .iter()
            .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
            .collect();
        assert_eq!(names, ["a.pcd", "b.ply", "c.STL", "z.xyz"]);
    }
}
