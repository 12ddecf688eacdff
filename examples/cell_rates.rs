//! Writes, for every valid cell of a cloud's height map, what the hypothesis rule of
//! section 4.1 sees there, as CSV on stdout (`x,y,height,mean,discontinuity,roughness,
//! comfortable`), for looking at why a place gets no hypothesis:
//! `cargo run --release --example cell_rates -- cloud.ply [sitting|lying|FILE.toml] [height]`.
//! The cloud must already be in the detector's frame (metres, z up, floor at z = 0). The
//! map rated is the one the detector rates: the specks left out, the scan's holes filled, and the hidden seats
//! where the hierarchy takes them.
use afford::detect::{prepare_guarded, DetectConfig};
use afford::method::hypotheses::rate;
use afford::model::set::{load_agent, load_hierarchy, Source, BUILTIN_AGENTS, BUILTIN_HIERARCHIES};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let Some(path) = args.get(1) else {
        eprintln!("usage: cell_rates CLOUD [sitting|lying|FILE.toml] [HEIGHT]");
        std::process::exit(2);
    };
    let name = args.get(2).map_or("sitting", String::as_str);
    let body: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1.75);
    let cloud = match afford::cloud::load(std::path::Path::new(path)) {
        Ok(c) => c.cloud,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let (an, at) = BUILTIN_AGENTS[0];
    let agent = load_agent(&Source::Builtin(an, at), body).expect("built-in agent");
    let source = match BUILTIN_HIERARCHIES.iter().find(|(n, _)| *n == name) {
        Some(&(n, t)) => Source::Builtin(n, t),
        None => Source::File(name.into()),
    };
    let h = match load_hierarchy(&source, &agent) {
        Ok(h) => h,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let prepared =
        match prepare_guarded(std::path::Path::new(path), &cloud, &DetectConfig::default()) {
            Ok(p) => p,
            Err(e) => {
                eprintln!("error: {e}");
                std::process::exit(2);
            }
        };
    let rule = &h.hypothesis;
    let map = prepared.map_for(rule.hidden_seats);
    let template = map.disc(rule.template_diameter * body / 2.0);
    let height = rule.height.map(|t| t.scaled(body)).or(rule.height_m);
    println!("x,y,height,mean,discontinuity,roughness,comfortable");
    for iy in 0..map.ny {
        for ix in 0..map.nx {
            if let Some(r) = rate(map, ix, iy, &template, height.as_ref(), rule) {
                let (x, y) = map.centre(ix, iy);
                let z = map.get(ix as isize, iy as isize).unwrap_or(f64::NAN);
                let [d, ro, c] = r.memberships;
                println!("{x:.3},{y:.3},{z:.3},{:.3},{d:.3},{ro:.3},{c:.3}", r.mean);
            }
        }
    }
}
