//! The commands as functions. Each returns its [`Outcome`] when it ran to its end, or the
//! error that ended it, which the edge ([`crate::cli::main`]) prints as one line with exit
//! code 2. Errors a command goes on after (one input of many, one output) are reported
//! here as they happen. `detect`: loads the models once, runs every input file
//! independently (one bad file does not stop the others), and writes the outputs.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context};

use crate::batch::{self, LogLine, Shard, Status};
use crate::settings::Settings;
use afford::cloud;
use afford::detect::{detect_input, prepare_guarded, DetectConfig};
use afford::input::{load_input, Input, InputOptions};
use afford::method::extent::ExtentError;
use afford::model::set::Model;
use afford::report::render::Legend;
use afford::report::{self, FileReport};

/// Everything `afford detect` was asked to do, validated.
#[derive(Debug, Clone)]
pub struct DetectRequest {
    /// Input clouds and folders of them.
    pub files: Vec<PathBuf>,
    /// Input lists (see [`crate::batch::read_list`]), read after `files`.
    pub lists: Vec<PathBuf>,
    /// Run only this shard of the inputs (see [`crate::batch::Shard::select`]).
    pub shard: Option<Shard>,
    /// Save each input's JSON in this folder (see [`crate::batch::saved_name`]).
    pub out_dir: Option<PathBuf>,
    /// Skip inputs whose JSON is already in `out_dir`.
    pub resume: bool,
    /// Write one JSON line per input on `out` ([`crate::batch::LogLine`]) instead of the table.
    pub log_json: bool,
    /// Models, scene-level numbers and how inputs are read.
    pub settings: Settings,
    /// JSON output.
    pub json: Option<PathBuf>,
    /// Detections CSV output.
    pub csv: Option<PathBuf>,
    /// Summary CSV output.
    pub summary: Option<PathBuf>,
    /// Segments PLY output (one per input; see [`per_input_path`]).
    pub segments: Option<PathBuf>,
    /// Posed-agent mesh output, PLY or (named `.glb`) binary glTF (one per input cloud;
    /// see [`per_input_path`]).
    pub mesh: Option<PathBuf>,
    /// Put the cloud, coloured by segment, into a `.glb` mesh output too.
    pub mesh_scene: bool,
    /// Show a progress bar on stderr when there are several inputs (the caller says
    /// whether stderr is a terminal and the user did not ask for quiet).
    pub progress: bool,
}

/// How a command that ran to its end ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Everything asked was done (or skipped by `--resume`), or the reader of standard
    /// output went away (a closed pipe ends a run quietly, as a filter does).
    Done,
    /// Some input or output failed; each was reported on standard error as it happened.
    Failed,
}

impl Outcome {
    /// [`Outcome::Failed`] when `failed`.
    fn of(failed: bool) -> Outcome {
        if failed {
            Outcome::Failed
        } else {
            Outcome::Done
        }
    }

    /// The process exit code: 0 done, 2 failed (as for an error that ends a command).
    pub fn code(self) -> u8 {
        match self {
            Outcome::Done => 0,
            Outcome::Failed => 2,
        }
    }
}

/// Standard output could not be written. The edge ([`crate::cli::main`]) ends quietly with
/// exit code 0 when the reader went away ([`StdoutError::reader_gone`]).
#[derive(Debug, thiserror::Error)]
#[error("standard output: cannot write: {0}")]
pub struct StdoutError(#[source] pub std::io::Error);

impl StdoutError {
    /// Whether the reader of the output went away (a closed pipe: `afford detect ... |
    /// head`): the run then stops without a message, as a filter does.
    pub fn reader_gone(&self) -> bool {
        reader_gone(&self.0)
    }
}

/// The one line that reports `e` on standard error, for an error that ends a command (at
/// the edge) or one it goes on after: `error: ` and the messages of `e`'s chain, outermost
/// first, joined by `: `, with control characters escaped ([`batch::printable`]). The
/// chain stops at an error whose message already ends with its cause's (the library's
/// errors say their cause), so no cause is said twice.
pub fn error_line(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let said = cause.to_string();
        if !text.is_empty() {
            if text.ends_with(&said) {
                break;
            }
            text.push_str(": ");
        }
        text.push_str(&said);
    }
    format!("error: {}\n", batch::printable(&text))
}

/// Reports `e` on `err` ([`error_line`]) for a command that goes on after it.
fn report_error(err: &mut dyn Write, e: &anyhow::Error) {
    let _ = err.write_all(error_line(e).as_bytes());
}

/// Detects in one file (already in metres, z up, floor at z = 0) with every model.
pub fn detect_file(
    path: &Path,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<FileReport, FileError> {
    let loaded = cloud::load(path)?;
    Ok(report_of(
        path,
        &loaded.cloud,
        loaded.dropped_non_finite,
        models,
        cfg,
    )?)
}

/// Why one file gave no report.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// It could not be read.
    #[error(transparent)]
    Cloud(#[from] cloud::CloudError),
    /// Its extent or coordinates are refused before the grids ([`afford::method::extent`]).
    #[error(transparent)]
    Extent(#[from] ExtentError),
}

/// Detection on one cloud ([`afford::detect::detect_input`], the path `afford eval` scores):
/// the grids are built from the points [`afford::method::extent::guard`] keeps; the
/// segments and the report cover every point of `cloud`.
fn report_of(
    path: &Path,
    cloud: &cloud::PointCloud,
    dropped: usize,
    models: &[Model],
    cfg: &DetectConfig,
) -> Result<FileReport, ExtentError> {
    Ok(FileReport::new(
        path.display().to_string(),
        cloud.len(),
        dropped,
        models,
        detect_input(path, cloud, models, cfg)?,
    ))
}

/// Where a per-input output of `input` goes: `base` itself for a single input, otherwise
/// `base` with the input's stem inserted before the extension (`seg.chair.ply`).
pub fn per_input_path(base: &Path, input: &Path, several: bool) -> PathBuf {
    per_part_path(base, input, None, several)
}

/// Where the per-input output of one cloud of `input` goes: as [`per_input_path`], with
/// the cloud's `part` name (`@<time>` of a bag message) after the input's stem, or after
/// `base`'s stem for a single input (`agents@1700000000.100000000.glb`). The extension is
/// `base`'s (`.ply` when it has none).
pub fn per_part_path(base: &Path, input: &Path, part: Option<&str>, several: bool) -> PathBuf {
    if !several && part.is_none() {
        return base.to_path_buf();
    }
    let stem = base
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = base
        .extension()
        .map_or("ply".into(), |e| e.to_string_lossy().into_owned());
    let part = part.unwrap_or("");
    if !several {
        return base.with_file_name(format!("{stem}{part}.{ext}"));
    }
    let inp = input
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    base.with_file_name(format!("{stem}.{inp}{part}.{ext}"))
}

/// Runs `afford detect`: [`Outcome::Done`] when every input was done or skipped,
/// [`Outcome::Failed`] when any input or output failed; an error for wrong flags, models or
/// lists (before any input), or for standard output that could not be written (at the end).
/// Inputs run one after the other; as each ends, its table (when no output
/// file is asked for) or its `--log-json` line goes to `out`, and its diagnostics to `err`.
/// The run-wide outputs (`--json`, `--csv`, `--summary`) are written at the end.
pub fn run_detect(
    req: &DetectRequest,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    if req.mesh_scene
        && !req
            .mesh
            .as_ref()
            .and_then(|m| m.extension())
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"))
    {
        bail!("--mesh-scene puts the cloud into a glTF mesh: give --mesh NAME.glb");
    }
    if req.resume && req.out_dir.is_none() {
        bail!("--resume needs --out-dir (where the saved results are)");
    }
    let models = req.settings.models.load()?;
    let inputs = batch::gather(&req.files, &req.lists, req.shard, req.out_dir.is_some())?;
    if let Some(d) = &req.out_dir {
        std::fs::create_dir_all(d).with_context(|| format!("{}: cannot create", d.display()))?;
    }
    let files = &inputs.files;
    let several = inputs.total > 1;
    check_outputs(req, files, several)?;
    warn_unused(&req.settings.input, files, err);
    // The first error writing standard output: a closed pipe (`| head`) stops the run
    // quietly, any other (a full disk) is reported at the end.
    let mut out_error: Option<std::io::Error> = None;
    let bar = if req.progress && files.len() > 1 {
        let bar = indicatif::ProgressBar::new(files.len() as u64);
        if let Ok(style) =
            indicatif::ProgressStyle::with_template("{bar:40} {pos}/{len} {wide_msg}")
        {
            bar.set_style(style);
        }
        bar
    } else {
        indicatif::ProgressBar::hidden()
    };
    let table = !req.log_json
        && req.json.is_none()
        && req.csv.is_none()
        && req.summary.is_none()
        && req.out_dir.is_none();
    let mut reports = Vec::new();
    let (mut failed, mut skipped) = (0usize, 0usize);
    for path in files {
        bar.set_message(path.display().to_string());
        let saved = req
            .out_dir
            .as_ref()
            .map(|d| d.join(batch::saved_name(path)));
        let mut line = LogLine {
            file: path.display().to_string(),
            status: Status::Skipped,
            error: None,
            points: None,
            detections: None,
            affordances: None,
            seconds: None,
        };
        let resumed = saved.as_deref().filter(|s| req.resume && s.exists());
        let done = if let Some(s) = resumed {
            match check_saved_models(s, &models) {
                Ok(()) => {
                    skipped += 1;
                    None
                }
                Err(e) => Some(Done {
                    reports: Vec::new(),
                    errors: vec![batch::printable(&e)],
                }),
            }
        } else {
            let start = std::time::Instant::now();
            let done = detect_one(req, &models, path, several, saved.as_deref(), &mut |n| {
                // Warnings (units above all) go out before detection, which may take long.
                bar.suspend(|| {
                    let _ = err.write_all(n);
                })
            });
            line.seconds = Some((start.elapsed().as_secs_f64() * 1000.0).round() / 1000.0);
            Some(done)
        };
        bar.suspend(|| {
            let Some(done) = &done else { return };
            for e in &done.errors {
                let _ = writeln!(err, "error: {}", batch::printable(&e.to_string()));
            }
            if table {
                for r in &done.reports {
                    if let Err(e) = out.write_all(report::to_table(r).as_bytes()) {
                        out_error.get_or_insert(e);
                    }
                }
            }
        });
        // One log line per cloud (a bag gives several), or one for an input with none.
        let mut lines = Vec::new();
        if let Some(done) = done {
            line.status = if done.errors.is_empty() {
                Status::Ok
            } else {
                failed += 1;
                line.error = Some(done.errors.join("; "));
                Status::Error
            };
            for r in done.reports {
                let mut l = line.clone();
                l.file = r.file.clone();
                l.points = Some(r.points());
                l.detections = Some(r.detections.len());
                l.affordances = Some(report::affords(&r, None).into_iter().cloned().collect());
                lines.push(l);
                reports.push(r);
            }
        }
        if lines.is_empty() {
            lines.push(line);
        }
        if req.log_json {
            for l in &lines {
                if let Err(e) = bar.suspend(|| writeln!(out, "{}", l.to_json())) {
                    out_error.get_or_insert(e);
                }
            }
        }
        if let Err(e) = out.flush() {
            out_error.get_or_insert(e);
        }
        bar.inc(1);
        if out_error.as_ref().is_some_and(reader_gone) {
            bar.finish_and_clear();
            return Ok(Outcome::of(failed > 0));
        }
    }
    bar.finish_and_clear();
    let mut unwritten = 0usize;
    let mut write = |target: &Option<PathBuf>, text: Result<String, csv::Error>| {
        if let Some(p) = target {
            let done = text.map_err(|e| e.to_string()).and_then(|t| {
                afford::report::atomic::write_bytes(p, t.as_bytes()).map_err(|e| e.to_string())
            });
            if let Err(e) = done {
                report_error(
                    err,
                    &anyhow::anyhow!(e).context(format!("{}: cannot write", p.display())),
                );
                unwritten += 1;
            }
        }
    };
    if skipped > 0 {
        // The skipped inputs have no report in this run: writing the run-wide outputs
        // would replace a complete run's with a part of it (or with nothing).
        for (flag, target) in [
            ("--json", &req.json),
            ("--csv", &req.csv),
            ("--summary", &req.summary),
        ] {
            if let Some(p) = target {
                let _ = writeln!(
                    err,
                    "note: {flag} {}: not written, {skipped} inputs were skipped by --resume \
                     (their results are in --out-dir; `afford eval --from` reads them)",
                    p.display()
                );
            }
        }
    } else {
        write(&req.json, Ok(report::to_json(&reports)));
        write(&req.csv, report::to_csv(&reports));
        write(&req.summary, report::to_summary(&reports));
    }
    if several || req.shard.is_some() {
        let mut s = match req.shard {
            Some(k) => format!("shard {k}: {} of {} files", files.len(), inputs.total),
            None => format!("{} files", files.len()),
        };
        s.push_str(&format!(", {failed} failed"));
        if req.resume {
            s.push_str(&format!(", {skipped} skipped (saved before)"));
        }
        let _ = writeln!(err, "{s}");
    }
    if let Some(e) = out_error {
        return Err(StdoutError(e).into());
    }
    Ok(Outcome::of(failed + unwritten > 0))
}

/// Whether a write error means that the reader of the output went away (a closed pipe:
/// `afford detect ... | head`): the run then stops without a message, as a filter does.
pub fn reader_gone(e: &std::io::Error) -> bool {
    e.kind() == std::io::ErrorKind::BrokenPipe
}

/// Writes `text` to standard output (`out`), flushed.
fn print(out: &mut dyn Write, text: &str) -> Result<(), StdoutError> {
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(StdoutError)
}

/// Checks that the saved result `saved` (an `--out-dir` JSON) was made with the bodies and
/// hierarchies of this run, so that `--resume` does not mix models in one folder.
fn check_saved_models(saved: &Path, models: &[Model]) -> Result<(), String> {
    let key =
        |agent: &str, height: f64, hierarchy: &str| format!("{agent} {height:.3} m {hierarchy}");
    let mut want: Vec<String> = models
        .iter()
        .map(|m| key(&m.agent.name, m.agent.height, &m.hierarchy.name))
        .collect();
    let bad = |what: String| format!("{}: {what}", saved.display());
    let text = std::fs::read_to_string(saved).map_err(|e| bad(format!("cannot read: {e}")))?;
    let doc = afford::report::saved::read_document(&text, saved).map_err(|e| e.to_string())?;
    let file = doc
        .files
        .first()
        .ok_or_else(|| bad("not a saved result: no file".into()))?;
    let mut got: Vec<String> = file
        .runs
        .iter()
        .map(|r| key(&r.agent, r.height, &r.hierarchy))
        .collect();
    want.sort();
    got.sort();
    if got != want {
        return Err(bad(format!(
            "saved with other models ({}) than this run ({}); use another --out-dir or remove it",
            got.join(", "),
            want.join(", ")
        )));
    }
    Ok(())
}

/// Refuses outputs that would destroy an input or each other: an output (`--json`,
/// `--csv`, `--summary`, or the per-input `--segments`/`--mesh` file of any input) that is
/// one of the inputs, and two inputs whose per-input outputs share a name
/// ([`per_input_path`] uses the file stem: `a/chair.ply` and `b/chair.pcd` clash).
fn check_outputs(req: &DetectRequest, files: &[PathBuf], several: bool) -> anyhow::Result<()> {
    let mut targets: Vec<(&str, PathBuf)> = Vec::new();
    for (flag, p) in [
        ("--json", &req.json),
        ("--csv", &req.csv),
        ("--summary", &req.summary),
    ] {
        if let Some(p) = p {
            targets.push((flag, p.clone()));
        }
    }
    for (flag, base) in [("--segments", &req.segments), ("--mesh", &req.mesh)] {
        if let Some(base) = base {
            let mut seen: std::collections::BTreeMap<PathBuf, &Path> = Default::default();
            for f in files {
                let t = per_input_path(base, f, several);
                if let Some(first) = seen.insert(t.clone(), f) {
                    bail!(
                        "{flag}: {} and {} would both be written to {}",
                        first.display(),
                        f.display(),
                        t.display()
                    );
                }
                targets.push((flag, t));
            }
        }
    }
    let inputs: std::collections::HashMap<PathBuf, &PathBuf> = files
        .iter()
        .filter_map(|f| std::fs::canonicalize(f).ok().map(|c| (c, f)))
        .collect();
    for (flag, t) in &targets {
        if let Some(f) = std::fs::canonicalize(t).ok().and_then(|c| inputs.get(&c)) {
            bail!(
                "{flag} {}: is the input {}; refusing to replace it",
                t.display(),
                f.display()
            );
        }
    }
    Ok(())
}

/// What one input gave: its report (when it could be read), and the errors of reading it
/// or writing its per-file outputs.
struct Done {
    reports: Vec<FileReport>,
    errors: Vec<String>,
}

/// Reads one input, detects in each of its clouds, and writes their per-file outputs
/// (`--segments`, `--mesh`), then its JSON in `--out-dir` at `saved`, last, so that it
/// marks a finished input.
fn detect_one(
    req: &DetectRequest,
    models: &[Model],
    path: &Path,
    several: bool,
    saved: Option<&Path>,
    warn: &mut dyn FnMut(&[u8]),
) -> Done {
    let mut done = Done {
        reports: Vec::new(),
        errors: Vec::new(),
    };
    let read = afford::input::load_inputs(path, &req.settings.input, &mut |input| match input {
        Ok(input) => detect_cloud(req, models, path, several, &input, &mut done, warn),
        Err(e) => done.errors.push(batch::printable(&e.to_string())),
    });
    if let Err(e) = read {
        done.errors.push(batch::printable(&e.to_string()));
    }
    if let (Some(target), true) = (saved, done.errors.is_empty()) {
        let json = report::to_json(&done.reports);
        if let Err(e) = afford::report::atomic::write_bytes(target, json.as_bytes()) {
            done.errors.push(batch::printable(&format!(
                "{}: cannot write: {e}",
                target.display()
            )));
        }
    }
    done
}

/// Detects in one cloud of input `path` and writes its per-file outputs; its warnings go
/// to `warn` first, before detection, which may take long.
fn detect_cloud(
    req: &DetectRequest,
    models: &[Model],
    path: &Path,
    several: bool,
    input: &Input,
    done: &mut Done,
    warn: &mut dyn FnMut(&[u8]),
) {
    let name = cloud::source::part_label(path, input.part.as_deref());
    let mut notes_text = Vec::new();
    notes(input, Path::new(&name), &mut notes_text);
    let notes_text: String = String::from_utf8_lossy(&notes_text)
        .lines()
        .map(|l| batch::printable(l) + "\n")
        .collect();
    warn(notes_text.as_bytes());
    let r = match report_of(
        Path::new(&name),
        &input.cloud,
        input.dropped_non_finite,
        models,
        &req.settings.detect,
    ) {
        Ok(r) => r,
        Err(e) => {
            done.errors.push(batch::printable(&e.to_string()));
            return;
        }
    };
    let part = input.part.as_deref();
    let legend = Legend::of(models.iter().map(|m| &m.hierarchy));
    if let Some(base) = &req.segments {
        let target = per_part_path(base, path, part, several);
        if let Err(e) = write_segments(input, &target, &r, &legend) {
            done.errors.push(batch::printable(&e.to_string()));
        }
    }
    if let Some(base) = &req.mesh {
        let target = per_part_path(base, path, part, several);
        let glb = base
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("glb"));
        let written = if glb {
            let scene = req
                .mesh_scene
                .then_some((input.cloud.points.as_slice(), r.labels.as_slice()));
            afford::report::glb::write_agents_glb(&target, &name, &r.detections, &legend, scene)
        } else {
            afford::report::agent_mesh::agent_mesh_ply(&r.detections, &legend, &target)
        };
        if let Err(e) = written {
            done.errors.push(batch::printable(&format!(
                "{}: cannot write: {e}",
                target.display()
            )));
        }
    }
    done.reports.push(r);
}

/// Writes the input cloud (world frame) with its segments ([`afford::report::agent_mesh::segments_ply`]).
fn write_segments(
    input: &Input,
    target: &Path,
    r: &FileReport,
    legend: &Legend,
) -> Result<(), cloud::CloudError> {
    afford::report::agent_mesh::segments_ply(
        &input.cloud.points,
        &r.detections,
        &r.labels,
        &r.ids,
        legend,
        target,
    )
}

/// The warnings and frame notes of an input, one line each.
fn notes(input: &Input, path: &Path, err: &mut dyn Write) {
    if input.dropped_non_finite > 0 {
        let _ = writeln!(
            err,
            "warning: {}: dropped {} points with non-finite coordinates",
            path.display(),
            input.dropped_non_finite
        );
    }
    for w in [&input.units_warning, &input.floor_warning]
        .into_iter()
        .flatten()
    {
        let _ = writeln!(err, "warning: {w}");
    }
    if let Some(f) = &input.frame {
        let _ = writeln!(err, "{}: {f}", path.display());
    }
}

/// Everything `afford inspect` was asked to do.
#[derive(Debug, Clone)]
pub struct InspectRequest {
    /// The input cloud.
    pub file: PathBuf,
    /// Models (the arrows are the hypotheses of the first), scene-level numbers and how
    /// the input is read.
    pub settings: Settings,
    /// The picture to write.
    pub png: PathBuf,
}

/// Runs `afford inspect`: detection on one file and a picture of the height map with the
/// hypotheses of the first model and the detections of all (the paper's Fig. 4 b-d) beside
/// views of the posed agents.
pub fn run_inspect(
    req: &InspectRequest,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let models = req.settings.models.load()?;
    warn_unused(&req.settings.input, std::slice::from_ref(&req.file), err);
    let loaded = load_input(&req.file, &req.settings.input)?;
    notes(&loaded, &req.file, err);
    let prepared = prepare_guarded(&req.file, &loaded.cloud, &req.settings.detect)?;
    let hyps = models
        .first()
        .map(|m| {
            afford::method::hypotheses::hypotheses(
                prepared.map_for(m.hierarchy.hypothesis.hidden_seats),
                &m.hierarchy.hypothesis,
                m.hierarchy.orientation,
                m.agent.height,
            )
        })
        .unwrap_or_default();
    let outcomes = afford::detect::detect_all_prepared(
        &loaded.cloud,
        &prepared,
        &models,
        &req.settings.detect,
    );
    let stats = outcomes.first().map(|o| o.stats).unwrap_or_default();
    let r = FileReport::new(
        req.file.display().to_string(),
        loaded.cloud.len(),
        loaded.dropped_non_finite,
        &models,
        outcomes,
    );
    let drawn = afford::detect::Outcome {
        detections: r.detections.clone(),
        labels: r.labels.clone(),
        stats,
    };
    let legend = Legend::of(models.iter().map(|m| &m.hierarchy));
    afford::report::render::inspect_png(&loaded.cloud, &prepared, &hyps, &drawn, &legend, &req.png)
        .with_context(|| format!("{}: cannot write", req.png.display()))?;
    let text = format!(
        "{}{} hypotheses drawn in {}\n",
        report::to_table(&r),
        hyps.len(),
        req.png.display()
    );
    print(out, &text)?;
    Ok(Outcome::Done)
}

/// Everything `afford synth` was asked to do.
#[derive(Debug, Clone)]
pub struct SynthRequest {
    /// Output directory.
    pub out: PathBuf,
    /// Random seed.
    pub seed: u64,
    /// Scenes per kind (full, view, wall, room); `None` for the default spec.
    pub count: Option<Vec<usize>>,
    /// Meshes to render views of, instead of furniture.
    pub meshes: Vec<PathBuf>,
    /// A labels.csv of meshes to render views of, with their labels.
    pub models: Option<PathBuf>,
    /// Views per mesh or model.
    pub views: usize,
    /// Depth-camera pixel stride for generated scenes.
    pub stride: u32,
    /// Probability of a mixed ("flying") pixel at each depth edge of a depth view.
    pub mixed_pixels: f64,
    /// Single views of seats from every side alike (`--all-round`).
    pub all_round: bool,
    /// Draw from the wide mix (`--mix wide`).
    pub wide: bool,
    /// Write clouds in their camera's frame (`--frame camera`).
    pub camera_frame: bool,
    /// The range the camera of mesh and model views is held at, metres (`--camera-height`);
    /// `None` for [`afford_synth::dataset::CAMERA_HELD_M`].
    pub camera_height: Option<[f64; 2]>,
    /// How far from the model's bounding box the camera of mesh and model views stands,
    /// metres (`--camera-distance`); `None` for the default that keeps the model in view.
    pub camera_distance: Option<[f64; 2]>,
}

/// Runs `afford synth`: with `--mesh`, one mesh that cannot be read does not stop the
/// others.
pub fn run_synth(
    req: &SynthRequest,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    use afford_synth::dataset;
    std::fs::create_dir_all(&req.out)
        .with_context(|| format!("{}: cannot create", req.out.display()))?;
    let frame = if req.camera_frame {
        dataset::OutFrame::Camera
    } else {
        dataset::OutFrame::World
    };
    let views = dataset::MeshViews {
        views: req.views,
        stride: req.stride,
        mixed_pixels: req.mixed_pixels,
        frame,
        camera_height: req.camera_height.unwrap_or(dataset::CAMERA_HELD_M),
        camera_distance: req.camera_distance,
    };
    if let Some(labels) = &req.models {
        let s = dataset::views_of_labelled_models(labels, &req.out, req.seed, &views)?;
        let mut text = format!(
            "wrote {} views and {}\n",
            s.rows.len(),
            s.labels_csv.display()
        );
        if req.camera_frame {
            text.push_str(&camera_frame_hint(&s.labels_csv));
        }
        print(out, &text)?;
        return Ok(Outcome::Done);
    }
    if !req.meshes.is_empty() {
        let mut failed = false;
        for m in &req.meshes {
            match dataset::render_mesh_views(m, &req.out, req.seed, &views) {
                Ok(files) => {
                    let text: String = files.iter().map(|f| format!("{}\n", f.display())).collect();
                    if let Err(e) = print(out, &text) {
                        // A closed pipe after a failed mesh still ends as failed.
                        if failed && e.reader_gone() {
                            return Ok(Outcome::Failed);
                        }
                        return Err(e.into());
                    }
                }
                Err(e) => {
                    report_error(err, &e.into());
                    failed = true;
                }
            }
        }
        return Ok(Outcome::of(failed));
    }
    let mut spec = dataset::DatasetSpec {
        stride: req.stride,
        mix: if req.wide {
            dataset::Mix::Wide
        } else {
            dataset::Mix::Default
        },
        frame,
        mixed_pixels: req.mixed_pixels,
        all_round: req.all_round,
        ..Default::default()
    };
    if let Some(c) = &req.count {
        if let [full, view, wall, room] = c[..] {
            spec.full = full;
            spec.view = view;
            spec.wall = wall;
            spec.room = room;
        }
    }
    let s = dataset::generate(&req.out, req.seed, &spec)?;
    let mut text = format!(
        "wrote {} scenes and {}\n",
        s.rows.len(),
        s.labels_csv.display()
    );
    if req.camera_frame {
        text.push_str(&camera_frame_hint(&s.labels_csv));
    }
    print(out, &text)?;
    Ok(Outcome::Done)
}

/// The line `afford synth` prints after writing clouds in their cameras' frames: how to
/// evaluate them.
fn camera_frame_hint(labels_csv: &Path) -> String {
    format!(
        "clouds are in their cameras' frames: afford eval {} --camera --floor auto\n",
        labels_csv.display()
    )
}

/// Everything `afford eval` was asked to do.
#[derive(Debug, Clone)]
pub struct EvalRequest {
    /// The labels file.
    pub labels: PathBuf,
    /// Models (every body is scored), scene-level numbers and how the labelled files are
    /// read.
    pub settings: Settings,
    /// JSON output.
    pub json: Option<PathBuf>,
    /// CSV output.
    pub csv: Option<PathBuf>,
    /// Score these saved detect outputs instead of running detection
    /// ([`afford::eval::evaluate_saved`]); empty to run detection.
    pub from: Vec<PathBuf>,
    /// No progress bar.
    pub quiet: bool,
}

/// Runs `afford eval`: prints the markdown table and writes the outputs;
/// [`Outcome::Failed`] when a labelled file could not be read or an output not written.
pub fn run_eval(
    req: &EvalRequest,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    let ev = if req.from.is_empty() {
        afford::eval::evaluate(
            &req.labels,
            &req.settings.models,
            &req.settings.detect,
            &req.settings.input,
            !req.quiet,
        )
    } else {
        afford::eval::evaluate_saved(&req.labels, &req.settings.models, &req.from)
    };
    let ev = ev?;
    // The outputs are written and the unread files reported after standard output failed
    // too; a closed pipe is no failure.
    let mut failed = match print(out, &ev.markdown()) {
        Err(e) if !e.reader_gone() => {
            report_error(err, &e.into());
            true
        }
        _ => false,
    };
    for (target, text) in [(&req.json, ev.to_json()), (&req.csv, ev.to_csv())] {
        if let Some(p) = target {
            if let Err(e) = afford::report::atomic::write_bytes(p, text.as_bytes()) {
                report_error(
                    err,
                    &anyhow::Error::new(e).context(format!("{}: cannot write", p.display())),
                );
                failed = true;
            }
        }
    }
    for (file, why) in &ev.failed {
        report_error(err, &anyhow::anyhow!("{file}: {why}"));
    }
    Ok(Outcome::of(failed || !ev.failed.is_empty()))
}

/// Everything `afford convert` was asked to do.
#[derive(Debug, Clone)]
pub struct ConvertRequest {
    /// The input cloud or mesh.
    pub input: PathBuf,
    /// The output: `.ply` or `.pcd`.
    pub output: PathBuf,
    /// Write ascii PLY instead of binary.
    pub ascii: bool,
    /// How the input is read and brought into the world frame.
    pub options: InputOptions,
}

/// Writes a warning line to `err` for each source option that no file of `paths` reads
/// ([`afford::cloud::source::unused_options`]).
fn warn_unused(opts: &InputOptions, paths: &[PathBuf], err: &mut dyn Write) {
    for line in afford::cloud::source::unused_options(&opts.source, paths) {
        let _ = writeln!(err, "warning: {line}");
    }
}

/// Runs `afford convert`: reads any input the detector reads (with the same frame options)
/// and writes it as PLY (binary or ascii) or binary PCD, in metres, z up, floor at z = 0.
pub fn run_convert(
    req: &ConvertRequest,
    out: &mut dyn Write,
    err: &mut dyn Write,
) -> anyhow::Result<Outcome> {
    if afford::report::atomic::same_file(&req.input, &req.output) {
        bail!(
            "{}: is the input; refusing to replace it",
            req.output.display()
        );
    }
    warn_unused(&req.options, std::slice::from_ref(&req.input), err);
    let input = load_input(&req.input, &req.options)?;
    notes(&input, &req.input, err);
    let ext = req
        .output
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    // Both formats hold 32-bit floats: a finite coordinate beyond their range would be
    // written as infinity.
    let limit = f64::from(f32::MAX);
    if let Some((i, c)) = input
        .cloud
        .points
        .iter()
        .enumerate()
        .find_map(|(i, p)| p.coords.iter().find(|c| c.abs() > limit).map(|&c| (i, c)))
    {
        bail!(
            "{}: point {i}: coordinate {c:.3e} does not fit the 32-bit floats of {}",
            req.input.display(),
            req.output.display()
        );
    }
    match ext.as_deref() {
        Some("ply") => cloud::write_ply_points(&req.output, &input.cloud.points, &[], !req.ascii)?,
        Some("pcd") if !req.ascii => cloud::write_pcd(&req.output, &input.cloud.points)?,
        Some("pcd") => bail!(
            "{}: ascii output is written as PLY only",
            req.output.display()
        ),
        _ => bail!("{}: write .ply or .pcd", req.output.display()),
    }
    let text = format!("{}: {} points\n", req.output.display(), input.cloud.len());
    print(out, &text)?;
    Ok(Outcome::Done)
}
