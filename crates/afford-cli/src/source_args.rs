//! The command-line flags that choose among the clouds of a file (bag topic and
//! messages, E57 scan) and read depth images, shared by every command that reads clouds.

use afford::cloud::source::{parse_time, Intrinsics, Pick, SourceOptions, DEPTH_SCALE};

/// Bags, E57 files and depth images.
#[derive(clap::Args, Debug, Clone)]
pub(crate) struct SourceArgs {
    /// ROS bags (.mcap): the topic of sensor_msgs/PointCloud2 messages [default: the
    /// bag's only such topic].
    #[arg(long, value_name = "TOPIC")]
    topic: Option<String>,
    /// ROS bags: every N-th message of the topic, from the first [default: every one].
    #[arg(long, value_name = "N", conflicts_with = "at",
          value_parser = clap::value_parser!(u64).range(1..))]
    every: Option<u64>,
    /// ROS bags: the one message logged nearest TIME (seconds since the epoch, as in the
    /// result names `run.mcap@TIME`).
    #[arg(long, value_name = "TIME", value_parser = parse_time)]
    at: Option<u64>,
    /// E57: read scan K only (counted from 1) [default: every scan, each with its pose].
    #[arg(long, value_name = "K", value_parser = clap::value_parser!(u64).range(1..))]
    scan: Option<u64>,
    /// Depth images (16-bit .png): the camera's pinhole intrinsics in pixels. The cloud is
    /// in the camera frame (--camera is implied).
    #[arg(long, value_name = "FX,FY,CX,CY")]
    intrinsics: Option<Intrinsics>,
    /// Depth images: metres per depth unit (0.001: millimetres).
    #[arg(long, value_name = "M", default_value_t = DEPTH_SCALE, value_parser = parse_scale)]
    depth_scale: f64,
}

fn parse_scale(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        _ => Err(format!("'{s}' is not a positive number of metres per unit")),
    }
}

impl SourceArgs {
    /// The options these flags give.
    pub(crate) fn options(&self) -> SourceOptions {
        SourceOptions {
            topic: self.topic.clone(),
            pick: match (self.every, self.at) {
                (_, Some(t)) => Pick::At(t),
                (Some(n), None) => Pick::Every(usize::try_from(n).unwrap_or(usize::MAX)),
                (None, None) => Pick::All,
            },
            scan: self.scan.map(|k| usize::try_from(k).unwrap_or(usize::MAX)),
            intrinsics: self.intrinsics,
            depth_scale: self.depth_scale,
        }
    }
}
