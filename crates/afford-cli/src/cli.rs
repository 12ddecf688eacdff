//! The `afford` command line: parses arguments and calls the library.
//!
//! [`main`] is the whole program; `src/main.rs` and the Python package's `afford`
//! script both call it, so one wheel installs the same command line.

use std::ffi::OsString;
use std::io::IsTerminal;
use std::io::Write;
use std::path::PathBuf;

use crate::batch::{BatchError, Shard};
use crate::run::{
    error_line, run_convert, run_detect, run_eval, run_inspect, run_synth, ConvertRequest,
    DetectRequest, EvalRequest, InspectRequest, Outcome, StdoutError, SynthRequest,
};
use crate::settings::Settings;
use afford::cloud::frame::{parse_matrix, FloorMode, FrameOptions, Units, Up};
use afford::input::InputOptions;
use afford::model::set::ModelChoice;
use anyhow::{bail, Context};
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
    /// Detect fine-grained affordances in point clouds (PLY, PCD, XYZ, E57, ROS bags, depth PNG).
    #[command(after_help = DETECT_AFTER_HELP)]
    Detect(DetectArgs),
    /// Draw the height map, the hypotheses and the posed agents of one cloud as a PNG.
    Inspect(InspectArgs),
    /// Write a labelled synthetic dataset (procedural furniture, virtual depth camera).
    Synth(SynthArgs),
    /// Score detection against a labels.csv: precision, recall and F per affordance.
    Eval(EvalArgs),
    /// Convert a cloud or mesh to PLY or PCD in the detector's frame (metres, z up, floor at 0).
    Convert(ConvertArgs),
}

#[derive(clap::Args)]
struct ConvertArgs {
    /// Input cloud or mesh (PLY, PCD, XYZ/CSV, OBJ, OFF, STL).
    input: PathBuf,
    /// Output file: .ply (binary unless --ascii) or .pcd (binary).
    output: PathBuf,
    /// Write ascii PLY.
    #[arg(long)]
    ascii: bool,
    #[command(flatten)]
    input_frame: InputArgs,
}

#[derive(clap::Args)]
#[command(group(clap::ArgGroup::new("given_meshes").args(["mesh", "models"])))]
struct SynthArgs {
    /// Output directory (created).
    #[arg(long)]
    out: PathBuf,
    /// Random seed: the same seed writes the same bytes.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Scenes of each kind: full models, single views, objects against a wall, rooms.
    #[arg(long, num_args = 4, value_names = ["FULL", "VIEW", "WALL", "ROOM"], value_parser = parse_count, conflicts_with_all = ["mesh", "models"])]
    count: Option<Vec<usize>>,
    /// Render depth views of these triangle-mesh PLY files instead of furniture.
    #[arg(long, num_args = 1..)]
    mesh: Vec<PathBuf>,
    /// Render depth views of every model of this labels.csv (real models), with labels.
    #[arg(long, conflicts_with = "mesh")]
    models: Option<PathBuf>,
    /// Views per mesh or model.
    #[arg(long, default_value_t = 3)]
    views: usize,
    /// Depth-camera pixel stride (1 = 640 x 480 rays, 2 = 320 x 240, ...), also for the
    /// views of --mesh and --models.
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=16))]
    stride: u32,
    /// Which world: `default` (the mix of the tables in docs/results.md, same bytes per seed) or `wide`
    /// (ceilings, overhangs, reconstructed and subsampled clouds, pitched cameras, dressed
    /// beds, new furniture; docs/formats.md "Synthetic data"). Not with --mesh or --models.
    #[arg(long, default_value = "default", value_parser = ["default", "wide"], conflicts_with_all = ["mesh", "models"])]
    mix: String,
    /// Frame of the written clouds: `world` (z up, floor at 0) or `camera` (each scene or
    /// view in its depth camera's frame; evaluate with --camera --floor auto).
    #[arg(long, default_value = "world", value_parser = ["world", "camera"])]
    frame: String,
    /// Probability (0 to 1) that a depth-camera pixel at a depth edge gives a mixed
    /// ("flying") point between the foreground and the background, as time-of-flight and
    /// stereo sensors do; 0, the Kinect v1 default, for none.
    #[arg(long, default_value_t = 0.0, value_parser = probability)]
    mixed_pixels: f64,
    /// Single views of seats from every side alike (by default 85% come from within 80
    /// degrees of the seat's front): as independently generated views and a robot walking
    /// round a room see them, seats seen from behind included. Not with --mesh or
    /// --models, whose views are taken from every side already.
    #[arg(long, conflicts_with_all = ["mesh", "models"])]
    all_round: bool,
    /// Lowest and highest the camera of the views of --mesh and --models is held, metres
    /// above the floor, as MIN,MAX (default 1.0,1.8: a person's hands or a tripod; a
    /// robot's camera is lower, 0.4-1.0 m). Only with --mesh or --models.
    #[arg(long, value_name = "MIN,MAX", value_parser = metre_range, requires = "given_meshes")]
    camera_height: Option<[f64; 2]>,
    /// Nearest and farthest the camera of the views of --mesh and --models stands from the
    /// model, metres, horizontally from the side of its bounding box it faces, as MIN,MAX
    /// (0 < MIN <= MAX <= 10; by default 1.5-3.0 m from the model's centre plus 0.8 of its
    /// half-diagonal beyond 0.5 m, which keeps most of a model in view; a person photographing
    /// a bed from its side stands 0.5-1.5 m from it). Only with --mesh or --models.
    #[arg(long, value_name = "MIN,MAX", value_parser = metre_range, requires = "given_meshes")]
    camera_distance: Option<[f64; 2]>,
}

/// `MIN,MAX` camera heights or distances, metres: finite, 0 < MIN <= MAX <= 10.
fn metre_range(s: &str) -> Result<[f64; 2], String> {
    let bad = || format!("'{s}' is not MIN,MAX in metres (0 < MIN <= MAX <= 10)");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let (a, b): (f64, f64) = (
        a.trim().parse().map_err(|_| bad())?,
        b.trim().parse().map_err(|_| bad())?,
    );
    (a > 0.0 && a <= b && b <= 10.0)
        .then_some([a, b])
        .ok_or_else(bad)
}

#[derive(clap::Args)]
struct EvalArgs {
    /// A labels.csv: column `file` (relative to it), then one 0/1 column per affordance.
    labels: PathBuf,
    #[command(flatten)]
    models: ModelArgs,
    /// Write the scores as JSON.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Write the scores as CSV.
    #[arg(long)]
    csv: Option<PathBuf>,
    /// Score saved `afford detect` results instead of running detection: --json files,
    /// --summary CSV files, or --out-dir folders (their .json files), e.g. of several
    /// shards. They must hold the same --agent and --affordances at every --height.
    #[arg(long, value_name = "PATH", num_args = 1..)]
    from: Vec<PathBuf>,
    #[command(flatten)]
    input: InputArgs,
    /// No progress bar.
    #[arg(long, short)]
    quiet: bool,
}

#[derive(clap::Args)]
struct ModelArgs {
    /// Body model: a TOML file, or a built-in name (human, child); repeat for several
    /// [default: human].
    #[arg(long, value_name = "FILE|NAME")]
    agent: Vec<String>,
    /// Affordance hierarchies: TOML files, folders of them, or built-in names (sitting,
    /// lying), comma-separated or repeated [default: every built-in one].
    #[arg(long, value_name = "FILE|DIR|NAME", value_delimiter = ',')]
    affordances: Vec<String>,
    /// Body heights of the agents, metres (0.3 to 3.0), comma-separated [default: 1.75].
    #[arg(long, visible_alias = "heights", value_delimiter = ',', value_parser = parse_height)]
    height: Vec<f64>,
    /// Voxel edge length of the scene, metres (0.002 to 0.1) [default: 0.02]; the contact
    /// resolution (a quarter voxel) and the segment growing distance (1.5 voxels) follow it.
    #[arg(long, value_parser = parse_voxel)]
    voxel: Option<f64>,
}

/// The one place where the flags `detect`, `inspect` and `eval` share become the library's
/// validated [`Settings`].
fn settings(models: &ModelArgs, input: &InputArgs) -> anyhow::Result<Settings> {
    let choice = ModelChoice {
        agents: models.agent.clone(),
        hierarchies: models.affordances.clone(),
        heights: models.height.clone(),
    };
    Ok(Settings::new(choice, models.voxel, input.options()?)?)
}

#[derive(clap::Args)]
struct InputArgs {
    /// The axis that points up in the file: x, y, z, -x, -y, -z.
    #[arg(long, default_value = "z", allow_hyphen_values = true)]
    up: Up,
    /// The file is a depth-camera frame (x right, y down, z forward); implies --up -y.
    #[arg(long)]
    camera: bool,
    /// A 4x4 matrix (16 numbers, row-major) or a file holding one, applied after --units.
    #[arg(long)]
    transform: Option<String>,
    /// Units of the file: m, cm or mm.
    #[arg(long, default_value = "m")]
    units: Units,
    /// `auto` finds the dominant floor plane (RANSAC) and moves it to z = 0; `keep` trusts the file.
    #[arg(long, default_value = "keep")]
    floor: FloorMode,
    /// Sample meshes (OBJ, OFF, STL, PLY with faces) at this many points per square metre.
    #[arg(long, value_parser = parse_density)]
    sample: Option<f64>,
    #[command(flatten)]
    source: crate::source_args::SourceArgs,
}

impl InputArgs {
    fn options(&self) -> anyhow::Result<InputOptions> {
        let transform = match &self.transform {
            None => None,
            Some(t) => {
                let path = std::path::Path::new(t);
                let text = if path.is_file() {
                    std::fs::read_to_string(path).with_context(|| format!("--transform {t}"))?
                } else {
                    t.clone()
                };
                match parse_matrix(&text) {
                    Ok(m) => Some(m),
                    Err(e) => {
                        // Not 16 numbers and no such file: most likely a mistyped file name.
                        let numeric = t.chars().any(|c| c.is_ascii_digit())
                            && t.split(|c: char| c.is_whitespace() || ",;[]".contains(c))
                                .filter(|w| !w.is_empty())
                                .count()
                                > 1;
                        if numeric {
                            bail!("--transform {t}: {e}");
                        }
                        bail!("--transform {t}: no such file, and not a matrix of 16 numbers");
                    }
                }
            }
        };
        Ok(InputOptions {
            frame: FrameOptions {
                up: self.up,
                transform,
                units: self.units,
                floor: self.floor,
                camera: self.camera,
            },
            sample: self.sample,
            source: self.source.options(),
        })
    }
}

#[derive(clap::Args)]
struct InspectArgs {
    /// Point cloud file (metres, z up, floor at z = 0).
    file: PathBuf,
    /// Where to write the picture.
    #[arg(long)]
    png: PathBuf,
    #[command(flatten)]
    models: ModelArgs,
    #[command(flatten)]
    input: InputArgs,
}

/// How `afford detect` runs over many files, shown after the options of `--help`.
const DETECT_AFTER_HELP: &str = "\
Batch runs:
  Inputs are the FILES (files and folders) and then every --list, in that order; a folder
  stands for the clouds and meshes in it (not recursive). A list file has one path per
  line, relative to the list's folder (or absolute); blank lines and lines starting with #
  are skipped; `--list -` reads the list from standard input (paths relative to the
  working directory).
  --shard K/N sorts all inputs by path and keeps every N-th starting at the K-th (K from
  1), so N runs given the same inputs share them without overlap. --out-dir DIR saves each
  input's results as DIR/<file name>.json (the --json format, one file), written when the
  input is done; with --resume, inputs whose JSON is already there are skipped. Merge the
  saved results of all shards with `afford eval labels.csv --from DIR`.
  As each input ends, its table goes to stdout (unless an output file is asked for), or
  with --log-json one JSON line: {\"file\", \"status\": \"ok\"|\"error\"|\"skipped\",
  \"error\", \"points\", \"detections\", \"affordances\", \"seconds\"} (fields that do not
  apply are left out; \"seconds\" is wall time, the only part that differs between runs).
  Exit code: 0 when every input was done or skipped, 2 when anything failed (an input
  could not be read, an output not written, or the arguments, models or lists are wrong).";

#[derive(clap::Args)]
struct DetectArgs {
    /// Point clouds or meshes (metres, z up, floor at z = 0, unless said otherwise below),
    /// or folders of them.
    #[arg(required_unless_present = "list")]
    files: Vec<PathBuf>,
    /// A file listing inputs, one path per line (relative to the list; `#` comments);
    /// `-` reads standard input. Repeat for several.
    #[arg(long, value_name = "FILE")]
    list: Vec<PathBuf>,
    /// Run only shard K of N (K from 1): every N-th input, starting at the K-th, after
    /// sorting all inputs by path.
    #[arg(long, value_name = "K/N", value_parser = parse_shard)]
    shard: Option<Shard>,
    /// Save each input's results as DIR/<file name>.json (the --json format), as it ends.
    #[arg(long, value_name = "DIR")]
    out_dir: Option<PathBuf>,
    /// Skip inputs whose results are already saved in --out-dir.
    #[arg(long, requires = "out_dir")]
    resume: bool,
    /// Write one JSON line per input on stdout as it ends, instead of the table.
    #[arg(long)]
    log_json: bool,
    #[command(flatten)]
    models: ModelArgs,
    #[command(flatten)]
    input: InputArgs,
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
    /// Write the posed agents as a coloured triangle mesh: PLY, or binary glTF for a .glb
    /// name (each detection a named node).
    #[arg(long)]
    mesh: Option<PathBuf>,
    /// With --mesh x.glb: the cloud as points too, coloured by segment.
    #[arg(long, requires = "mesh")]
    mesh_scene: bool,
    /// Worker threads, 1 to 256 (default: all cores); the output does not depend on it.
    #[arg(long, value_parser = parse_threads)]
    threads: Option<usize>,
    /// No progress bar (there is none either when stderr is not a terminal).
    #[arg(long, short)]
    quiet: bool,
}

fn parse_shard(s: &str) -> Result<Shard, String> {
    s.parse().map_err(|e| match e {
        BatchError::Shard { why, .. } => why.to_string(),
        e => e.to_string(),
    })
}

fn parse_height(s: &str) -> Result<f64, String> {
    let h: f64 = s.parse().map_err(|e| format!("{e}"))?;
    afford::model::agent::check_height(h).map_err(|e| format!("{e} (metres, not centimetres?)"))
}

fn parse_density(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(d) if d.is_finite() && d > 0.0 => Ok(d),
        _ => Err(format!(
            "'{s}' is not a positive density (points per square metre)"
        )),
    }
}

fn probability(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(p) if (0.0..=1.0).contains(&p) => Ok(p),
        _ => Err(format!("'{s}' is not a probability (0 to 1)")),
    }
}

/// Most worker threads: far more than the cores of any machine this runs on; more only
/// spends time starting threads (100,000 took 72 s before the first file).
pub const MAX_THREADS: usize = 256;

fn parse_threads(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if (1..=MAX_THREADS).contains(&n) => Ok(n),
        _ => Err(format!(
            "'{s}' is not a thread count from 1 to {MAX_THREADS}"
        )),
    }
}

/// Most synthetic scenes of one kind: a run of this many takes days; more is a typo, and
/// the scene plan is allocated up front (1e8 asked for 12 GB).
pub const MAX_SCENES: usize = 100_000;

fn parse_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(n) if n <= MAX_SCENES => Ok(n),
        _ => Err(format!("'{s}' is not a scene count from 0 to {MAX_SCENES}")),
    }
}

fn parse_voxel(s: &str) -> Result<f64, String> {
    let v: f64 = s.parse().map_err(|e| format!("{e}"))?;
    crate::settings::check_voxel(v)
}

/// Runs the command line on `args` (the program name first, as `std::env::args_os`
/// gives them) and returns the process exit code: 0 when everything was done, 2 when
/// anything failed (docs/batch.md).
///
/// This is the edge where errors become exit codes: an error that ends a command is
/// printed here as one line ([`error_line`]), exit code 2, except that standard output
/// whose reader went away (`afford detect ... | head`) ends quietly with 0. The commands
/// below return typed errors with context ([`anyhow`]); the libraries keep typed errors.
pub fn main<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<OsString> + Clone,
{
    let cli = match Cli::try_parse_from(args) {
        Ok(cli) => cli,
        Err(e) => {
            // clap prints help and version to stdout (exit 0) and errors to stderr (exit 2).
            let _ = e.print();
            return u8::try_from(e.exit_code()).unwrap_or(2);
        }
    };
    // Standard error carries the diagnostics: when it cannot be written, the exit code is
    // all that is left, so its write errors are not reported further.
    let (mut out, mut err) = (std::io::stdout().lock(), std::io::stderr().lock());
    match run(cli.command, &mut out, &mut err) {
        Ok(outcome) => outcome.code(),
        Err(e)
            if e.downcast_ref::<StdoutError>()
                .is_some_and(StdoutError::reader_gone) =>
        {
            0
        }
        Err(e) => {
            let _ = err.write_all(error_line(&e).as_bytes());
            2
        }
    }
}

/// Turns the flags of one command into its validated request and runs it.
fn run(command: Command, out: &mut dyn Write, err: &mut dyn Write) -> anyhow::Result<Outcome> {
    match command {
        Command::Detect(a) => {
            let settings = settings(&a.models, &a.input)?;
            if let Some(n) = a.threads {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build_global()
                    .with_context(|| format!("--threads {n}"))?;
            }
            let req = DetectRequest {
                files: a.files,
                lists: a.list,
                shard: a.shard,
                out_dir: a.out_dir,
                resume: a.resume,
                log_json: a.log_json,
                settings,
                json: a.json,
                csv: a.csv,
                summary: a.summary,
                segments: a.segments,
                mesh: a.mesh,
                mesh_scene: a.mesh_scene,
                progress: !a.quiet && std::io::stderr().is_terminal(),
            };
            run_detect(&req, out, err)
        }
        Command::Synth(a) => run_synth(
            &SynthRequest {
                out: a.out,
                seed: a.seed,
                count: a.count,
                meshes: a.mesh,
                models: a.models,
                views: a.views,
                stride: a.stride,
                mixed_pixels: a.mixed_pixels,
                all_round: a.all_round,
                wide: a.mix == "wide",
                camera_frame: a.frame == "camera",
                camera_height: a.camera_height,
                camera_distance: a.camera_distance,
            },
            out,
            err,
        ),
        Command::Eval(a) => {
            let settings = settings(&a.models, &a.input)?;
            let req = EvalRequest {
                labels: a.labels,
                settings,
                json: a.json,
                csv: a.csv,
                from: a.from,
                quiet: a.quiet || !std::io::stderr().is_terminal(),
            };
            run_eval(&req, out, err)
        }
        Command::Convert(a) => {
            let req = ConvertRequest {
                input: a.input,
                output: a.output,
                ascii: a.ascii,
                options: a.input_frame.options()?,
            };
            run_convert(&req, out, err)
        }
        Command::Inspect(a) => {
            let req = InspectRequest {
                settings: settings(&a.models, &a.input)?,
                file: a.file,
                png: a.png,
            };
            run_inspect(&req, out, err)
        }
    }
}
