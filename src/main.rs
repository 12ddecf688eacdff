//! The `afford` command line: parses arguments and calls the library.

use std::path::PathBuf;
use std::process::ExitCode;

use afford::detect::DetectConfig;
use afford::run::{run_detect, DetectRequest};
use clap::{Parser, Subcommand};

/// Finds where a person could sit or lie in a 3D point cloud, and how.
#[derive(Parser)]
#[command(name = "afford", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Detect fine-grained affordances in point clouds (PLY, PCD, XYZ).
    Detect(DetectArgs),
}

#[derive(clap::Args)]
struct DetectArgs {
    /// Point cloud files (metres, z up, floor at z = 0).
    #[arg(required = true)]
    files: Vec<PathBuf>,
    /// Agent model.
    #[arg(long, default_value = "agents/human.toml")]
    agent: PathBuf,
    /// Affordance hierarchy.
    #[arg(long, default_value = "affordances/sitting.toml")]
    affordances: PathBuf,
    /// Body height of the agent, metres.
    #[arg(long, default_value_t = 1.75)]
    height: f64,
    /// Write detections as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write detections as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Write one 0/1 row per file (the shape of labels.csv).
    #[arg(long)]
    summary: Option<PathBuf>,
    /// Write the segmented points as PLY with a per-point detection index.
    #[arg(long)]
    segments: Option<PathBuf>,
    /// Worker threads (default: all cores); the output does not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Voxel edge length of the scene, metres.
    #[arg(long)]
    voxel: Option<f64>,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match cli.command {
        Command::Detect(a) => {
            let mut config = DetectConfig::default();
            if let Some(v) = a.voxel {
                if !(v.is_finite() && v > 0.001 && v <= 0.1) {
                    eprintln!("error: --voxel {v}: must be between 0.001 and 0.1 m");
                    return ExitCode::from(2);
                }
                config.scene.voxel_size = v;
            }
            if let Some(n) = a.threads {
                if let Err(e) = rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build_global()
                {
                    eprintln!("error: --threads {n}: {e}");
                    return ExitCode::from(2);
                }
            }
            let req = DetectRequest {
                files: a.files,
                agent: a.agent,
                affordances: a.affordances,
                height: a.height,
                json: a.json,
                csv: a.csv,
                summary: a.summary,
                segments: a.segments,
                config,
                quiet: a.quiet,
            };
            let code = run_detect(
                &req,
                &mut std::io::stdout().lock(),
                &mut std::io::stderr().lock(),
            );
            ExitCode::from(code as u8)
        }
    }
}
