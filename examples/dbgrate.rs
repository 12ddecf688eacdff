//! Local debugging aid (not committed): ratings of cells above a height.
use afford::detect::{prepare, DetectConfig};
use afford::method::hypotheses::rate;
use afford::model::set::load_models;
use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let cloud = afford::cloud::load(Path::new(&args[1])).unwrap().cloud;
    let cfg = DetectConfig::default();
    let (agent, h) = load_models(
        Path::new("/work/main/agents/human.toml"),
        Path::new(&args[2]),
        1.75,
    )
    .unwrap();
    let zmin: f64 = args[3].parse().unwrap();
    let p = prepare(&cloud, &cfg);
    let m = &p.map;
    let rule_ = &h.hypothesis;
    let template = m.disc(rule_.template_diameter * agent.height / 2.0);
    let height = rule_.height.map(|t| t.scaled(agent.height));
    for iy in 0..m.ny {
        for ix in 0..m.nx {
            if m.get(ix as isize, iy as isize).is_some_and(|z| z > zmin) {
                if let Some(r) = rate(m, ix, iy, &template, height.as_ref(), rule_) {
                    let (x, y) = m.centre(ix, iy);
                    println!(
                        "{x:.2} {y:.2} mean {:.3} top {:.3} mem {:.2?}",
                        r.mean, r.top, r.memberships
                    );
                }
            }
        }
    }
}
