//! Back-projects a 16-bit depth PNG (Kinect / RealSense / TUM / Redwood style) into a point
//! cloud in the depth camera's frame (x right, y down, z forward, metres), written as binary
//! PLY; `afford convert OUT.ply LEVELLED.ply --camera --floor auto` then puts it in the
//! detector's frame. Used to rebuild the real-scan set (`tools/realset.py`).
//!
//! ```sh
//! cargo run --release --example depth_to_ply -- DEPTH.png OUT.ply \
//!     --intrinsics 535.4,539.2,320.1,247.6 --scale 5000 [--stride 1] [--max-depth 8] \
//!     [--preview DEPTH.preview.png]
//! ```
//!
//! `--scale` is depth units per metre (TUM 5000, most others 1000); pixels with depth 0 (no
//! reading) or beyond `--max-depth` metres (default 8) are skipped. `--preview` writes the
//! depth image shaded near-light / far-dark (no reading black) for labelling by eye.
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use nalgebra::Point3;

/// Pinhole intrinsics in pixels.
struct Intrinsics {
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

struct Args {
    depth: PathBuf,
    out: PathBuf,
    k: Intrinsics,
    /// Depth units per metre.
    scale: f64,
    /// Keep every `stride`-th pixel in each direction.
    stride: usize,
    /// Readings farther than this (metres) are dropped (Kinect v1 noise grows with z^2).
    max_depth: f64,
    preview: Option<PathBuf>,
}

fn parse(mut it: impl Iterator<Item = String>) -> Result<Args> {
    let usage = "usage: depth_to_ply DEPTH.png OUT.ply --intrinsics fx,fy,cx,cy --scale S \
                 [--stride N] [--max-depth M] [--preview P.png]";
    let mut pos = Vec::new();
    let (mut k, mut scale, mut stride, mut max_depth, mut preview) = (None, None, 1, 8.0, None);
    while let Some(a) = it.next() {
        let mut val = || {
            it.next()
                .with_context(|| format!("{a} needs a value; {usage}"))
        };
        match a.as_str() {
            "--intrinsics" => {
                let v: Vec<f64> = val()?
                    .split(',')
                    .map(|s| s.trim().parse::<f64>())
                    .collect::<Result<_, _>>()
                    .context("--intrinsics: four numbers fx,fy,cx,cy")?;
                if v.len() != 4 || v.iter().any(|x| !x.is_finite()) || v[0] <= 0.0 || v[1] <= 0.0 {
                    bail!("--intrinsics: four finite numbers fx,fy,cx,cy with fx, fy > 0");
                }
                k = Some(Intrinsics {
                    fx: v[0],
                    fy: v[1],
                    cx: v[2],
                    cy: v[3],
                });
            }
            "--scale" => scale = Some(val()?.parse::<f64>().context("--scale: a number")?),
            "--stride" => stride = val()?.parse::<usize>().context("--stride: an integer")?,
            "--max-depth" => max_depth = val()?.parse::<f64>().context("--max-depth: a number")?,
            "--preview" => preview = Some(PathBuf::from(val()?)),
            _ if a.starts_with("--") => bail!("unknown option {a}; {usage}"),
            _ => pos.push(PathBuf::from(a)),
        }
    }
    let [depth, out]: [PathBuf; 2] = pos.try_into().map_err(|_| anyhow::anyhow!("{usage}"))?;
    let scale = scale.with_context(|| format!("--scale is required; {usage}"))?;
    if !(scale.is_finite() && scale > 0.0 && max_depth > 0.0) || stride == 0 {
        bail!("--scale and --max-depth must be > 0, --stride >= 1");
    }
    Ok(Args {
        depth,
        out,
        k: k.with_context(|| format!("--intrinsics is required; {usage}"))?,
        scale,
        stride,
        max_depth,
        preview,
    })
}

/// Reads a single-channel 16-bit PNG as (width, height, row-major raw values).
fn read_depth(path: &Path) -> Result<(usize, usize, Vec<u16>)> {
    let file = std::fs::File::open(path).with_context(|| format!("{}", path.display()))?;
    let dec = png::Decoder::new(std::io::BufReader::new(file));
    let mut reader = dec
        .read_info()
        .with_context(|| format!("{}: not a PNG", path.display()))?;
    let info = reader.info();
    if info.color_type != png::ColorType::Grayscale || info.bit_depth != png::BitDepth::Sixteen {
        bail!(
            "{}: want a 16-bit grayscale depth PNG, found {:?} {:?}",
            path.display(),
            info.color_type,
            info.bit_depth
        );
    }
    let (w, h) = (info.width as usize, info.height as usize);
    let mut buf = vec![0u8; reader.output_buffer_size().context("image too large")?];
    reader
        .next_frame(&mut buf)
        .with_context(|| format!("{}: bad PNG data", path.display()))?;
    let vals = buf[..w * h * 2]
        .chunks_exact(2)
        .map(|b| u16::from_be_bytes([b[0], b[1]]))
        .collect();
    Ok((w, h, vals))
}

fn write_preview(path: &Path, w: usize, h: usize, z: &[f64]) -> Result<()> {
    let mut seen: Vec<f64> = z.iter().copied().filter(|&v| v > 0.0).collect();
    seen.sort_by(f64::total_cmp);
    let (lo, hi) = match seen.len() {
        0 => (0.0, 1.0),
        n => (seen[n / 50], seen[n - 1 - n / 50]),
    };
    let px: Vec<u8> = z
        .iter()
        .map(|&v| {
            if v > 0.0 {
                let t = ((v - lo) / (hi - lo).max(1e-6)).clamp(0.0, 1.0);
                // t is clamped to 0..=1: the grey is in 40..=255.
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                let grey = (40.0 + 215.0 * (1.0 - t)) as u8;
                grey
            } else {
                0
            }
        })
        .collect();
    let file = std::fs::File::create(path).with_context(|| format!("{}", path.display()))?;
    let (w, h) = (
        u32::try_from(w).context("image width")?,
        u32::try_from(h).context("image height")?,
    );
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(&px)?;
    Ok(())
}

fn run(a: &Args) -> Result<usize> {
    let (w, h, raw) = read_depth(&a.depth)?;
    let z: Vec<f64> = raw
        .iter()
        .map(|&d| {
            let m = d as f64 / a.scale;
            if d > 0 && m <= a.max_depth {
                m
            } else {
                0.0
            }
        })
        .collect();
    let mut pts = Vec::new();
    for v in (0..h).step_by(a.stride) {
        for u in (0..w).step_by(a.stride) {
            let d = z[v * w + u];
            if d > 0.0 {
                pts.push(Point3::new(
                    (u as f64 - a.k.cx) * d / a.k.fx,
                    (v as f64 - a.k.cy) * d / a.k.fy,
                    d,
                ));
            }
        }
    }
    if pts.is_empty() {
        bail!("{}: no valid depth pixel", a.depth.display());
    }
    afford::cloud::write_ply_points(&a.out, &pts, &[], true)
        .with_context(|| format!("{}", a.out.display()))?;
    if let Some(p) = &a.preview {
        write_preview(p, w, h, &z)?;
    }
    Ok(pts.len())
}

fn main() -> ExitCode {
    match parse(std::env::args().skip(1)).and_then(|a| run(&a).map(|n| (a, n))) {
        Ok((a, n)) => {
            println!("{}: {n} points", a.out.display());
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(2)
        }
    }
}
