#![no_main]
//! The model loaders over extreme numbers: the input is a list of (key, f64) edits applied
//! to the numeric lines of the built-in agent and sitting hierarchy (each 9 bytes: a key
//! selector and the little-endian bits of the value, so 1e300, 1e-300, subnormals, NaN
//! and infinities all occur). Whatever loads is then run on a small scene: a model the
//! loader accepts must not hang, abort or panic detection (libFuzzer's -timeout catches
//! hangs).

use std::path::Path;
use std::sync::OnceLock;

use afford::cloud::PointCloud;
use afford::detect::{detect, DetectConfig};
use afford::model::agent::Agent;
use afford::model::hierarchy::Hierarchy;
use libfuzzer_sys::fuzz_target;
use nalgebra::Point3;

/// A 1 m x 1 m floor and a 0.4 m seat box top at 0.45 m, 5 cm apart.
fn scene() -> &'static PointCloud {
    static SCENE: OnceLock<PointCloud> = OnceLock::new();
    SCENE.get_or_init(|| {
        let mut pts = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (x, y) = (i as f64 * 0.05, j as f64 * 0.05);
                pts.push(Point3::new(x, y, 0.0));
                if (0.3..0.7).contains(&x) && (0.3..0.7).contains(&y) {
                    pts.push(Point3::new(x, y, 0.45));
                }
            }
        }
        PointCloud::new(pts)
    })
}

/// Replaces the `n`-th number (counting every number on `key = ...` lines) with `v`.
fn edit(text: &str, n: usize, v: f64) -> String {
    let mut seen = 0usize;
    let mut out = String::with_capacity(text.len() + 32);
    for line in text.lines() {
        let code = line.split('#').next().unwrap_or("");
        let mut done = line.to_string();
        if code.contains('=') && !code.trim_start().starts_with('[') {
            let (head, _) = code.split_once('=').unwrap_or((code, ""));
            let rest = &code[head.len()..];
            // The first plain number after `=` on this line.
            let mut chars = rest.char_indices().peekable();
            while let Some((i, c)) = chars.next() {
                if c.is_ascii_digit() || c == '-' {
                    let end = rest[i..]
                        .find(|c: char| !(c.is_ascii_digit() || "-+.eE".contains(c)))
                        .map_or(rest.len(), |e| i + e);
                    if rest[i..end].parse::<f64>().is_ok() {
                        if seen == n {
                            let lit = if v.is_nan() {
                                "nan".to_string()
                            } else if v.is_infinite() {
                                if v > 0.0 { "inf" } else { "-inf" }.to_string()
                            } else {
                                format!("{v:e}")
                            };
                            done = format!("{head}{}{lit}{}", &rest[..i], &rest[end..]);
                        }
                        seen += 1;
                    }
                    break;
                }
            }
        }
        out.push_str(&done);
        out.push('\n');
    }
    out
}

fuzz_target!(|data: &[u8]| {
    let mut agent_text = afford::model::set::BUILTIN_AGENT.to_string();
    let mut sit_text = afford::model::set::BUILTIN_SITTING.to_string();
    for chunk in data.chunks_exact(9).take(4) {
        let v = f64::from_le_bytes(chunk[1..9].try_into().unwrap());
        let which = chunk[0] as usize;
        if which % 2 == 0 {
            agent_text = edit(&agent_text, which / 2, v);
        } else {
            sit_text = edit(&sit_text, which / 2, v);
        }
    }
    let Ok(agent) = Agent::from_toml(&agent_text, Path::new("a.toml"), 1.75) else {
        return;
    };
    let Ok(h) = Hierarchy::from_toml(&sit_text, Path::new("s.toml"), &agent) else {
        return;
    };
    let _ = detect(scene(), &agent, &h, &DetectConfig::default());
});
