//! Fits and unfolds one hierarchy at a place and heading you give, and prints what each
//! fit and node found, for looking at why a place gets no detection, or the one it gets:
//! `cargo run --release --example probe_place -- CLOUD X Y [YAW_DEG] [sitting|lying|FILE.toml] [BODY_M]`.
//! The cloud must already be in the detector's frame (metres, z up, floor at z = 0). The
//! hypothesis nearest to (X, Y) gives the height and the memberships; the place is moved to
//! (X, Y) and, with YAW_DEG, its heading set; then section 4.2's fit (every heading it
//! tries) and section 4.4's unfolding run as `afford detect` runs them, for a body BODY_M
//! metres tall (default 1.75).
use std::path::Path;

use afford::detect::{prepare_guarded, DetectConfig};
use afford::method::fit::fit;
use afford::method::hypotheses::{hypotheses, Hypothesis};
use afford::method::unfold::unfold;
use afford::model::set::{load_agent, load_hierarchy, Source, BUILTIN_AGENTS, BUILTIN_HIERARCHIES};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let number = |i: usize| args.get(i).and_then(|s| s.parse::<f64>().ok());
    let (Some(path), Some(x), Some(y)) = (args.get(1), number(2), number(3)) else {
        eprintln!("usage: probe_place CLOUD X Y [YAW_DEG] [sitting|lying|FILE.toml] [BODY_M]");
        std::process::exit(2);
    };
    let yaw = number(4).map(f64::to_radians);
    let name = args.get(5).map_or("sitting", String::as_str);
    let body = number(6).unwrap_or(1.75);
    let fail = |what: String| -> ! {
        eprintln!("error: {what}");
        std::process::exit(2);
    };
    let cloud = afford::cloud::load(Path::new(path))
        .unwrap_or_else(|e| fail(e.to_string()))
        .cloud;
    let (an, at) = BUILTIN_AGENTS[0];
    let agent = load_agent(&Source::Builtin(an, at), body).unwrap_or_else(|e| fail(e.to_string()));
    let source = match BUILTIN_HIERARCHIES.iter().find(|(n, _)| *n == name) {
        Some(&(n, t)) => Source::Builtin(n, t),
        None => Source::File(name.into()),
    };
    let h = load_hierarchy(&source, &agent).unwrap_or_else(|e| fail(e.to_string()));
    let cfg = DetectConfig::default();
    let prepared =
        prepare_guarded(Path::new(path), &cloud, &cfg).unwrap_or_else(|e| fail(e.to_string()));
    let all = hypotheses(
        prepared.map_for(h.hypothesis.hidden_seats),
        &h.hypothesis,
        h.orientation,
        body,
    );
    let off = |p: &Hypothesis| (p.position.x - x).hypot(p.position.y - y);
    let Some(near) = all.iter().min_by(|p, q| off(p).total_cmp(&off(q))) else {
        fail(format!("{path}: no hypothesis of `{}`", h.name));
    };
    let deg = |r: Option<f64>| r.map_or("-".into(), |r| format!("{:.1}", r.to_degrees()));
    println!(
        "{} hypotheses; nearest {:.3} m away at ({:.3}, {:.3}), z {:.3}, top {:.3}, heading {}, facing {}, memberships {:.2?}",
        all.len(),
        off(near),
        near.position.x,
        near.position.y,
        near.position.z,
        near.top,
        deg(near.heading),
        deg(near.facing),
        near.memberships
    );
    let mut place = near.clone();
    place.position.x = x;
    place.position.y = y;
    if yaw.is_some() {
        place.heading = yaw;
    }
    let fits = fit(&agent, &h, &prepared.scene, &place, &cfg.contact);
    println!("{} stable fits", fits.len());
    for f in &fits {
        let u = unfold(&agent, &h, &prepared.scene, f, &cfg.contact);
        let p = u.placement.position;
        let nodes: Vec<String> = h
            .nodes
            .iter()
            .zip(&u.nodes)
            .map(|(n, o)| {
                let state = match (o.visited, o.found) {
                    (false, _) => "not visited",
                    (true, false) => "not found",
                    (true, true) => "found",
                };
                format!("{} {state} ({:.3})", n.id, o.local)
            })
            .collect();
        println!(
            "fit: yaw {:.1}, z {:.3}, stability {:.3}{} -> at ({:.3}, {:.3}), score {:.3}: {}",
            f.placement.yaw.to_degrees(),
            f.placement.position.z,
            f.stability,
            if f.turned { ", turned" } else { "" },
            p.x,
            p.y,
            u.score,
            nodes.join(", ")
        );
        let angles: Vec<String> = agent
            .joints
            .iter()
            .zip(&u.posture.angles)
            .filter(|(_, a)| a.abs() > 1e-9)
            .map(|(j, a)| format!("{} {:.1}", j.name, a.to_degrees()))
            .collect();
        println!("    {}", angles.join(", "));
    }
}
