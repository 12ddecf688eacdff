//! Writes, for a visual check, the pictures of an armchair and of a chair against a wall
//! to `/tmp/render-*.png`:
//! `cargo test --release -p afford --test integration -- --ignored render_demo::`.

use std::path::Path;

use afford::detect::{detect_prepared, prepare, DetectConfig};
use afford::method::hypotheses::hypotheses;
use afford::model::set::load_models;
use afford::report::render::*;
use afford_synth::furniture::{self as synth, ChairParams};

#[test]
#[ignore = "writes pictures to /tmp for a person to look at"]
fn pictures() {
    let (agent, h) = load_models(
        Path::new("agents/human.toml"),
        Path::new("affordances/sitting.toml"),
        1.75,
    )
    .unwrap();
    let legend = Legend::of([&h]);
    let cfg = DetectConfig::default();
    let scenes = [
        ("armchair", vec![synth::chair(&ChairParams::with_arms())]),
        (
            "wall",
            vec![
                synth::chair(&ChairParams::default()).placed(0.0, 0.0, 0.0),
                synth::wall(-0.45, -1.0, 1.0, 1.5, 0.1),
            ],
        ),
        ("highback", vec![synth::chair(&ChairParams::high_back())]),
        ("sofa", vec![synth::sofa(&synth::SofaParams::default())]),
    ];
    for (name, meshes) in scenes {
        let cloud = synth::scene_cloud(&meshes, 4000.0, 0.002, 1, true);
        let prepared = prepare(&cloud, &cfg);
        let hyps = hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height);
        let out = detect_prepared(&cloud, &prepared, &agent, &h, &cfg);
        for d in &out.detections {
            eprintln!(
                "{name}: at {:.2} {:.2} {:.2} seat z {:.2} yaw {:.0} deg {:?} score {:.2}",
                d.position.x,
                d.position.y,
                d.position.z,
                d.seat.z,
                d.yaw.to_degrees(),
                d.affordances,
                d.score
            );
        }
        for d in &out.detections {
            eprintln!(
                "  pose {:?}",
                d.pose
                    .iter()
                    .map(|(n, a)| format!("{n} {a:.0}"))
                    .collect::<Vec<_>>()
            );
            for c in &d.parts {
                let gap = cloud
                    .points
                    .iter()
                    .map(|p| {
                        let ab = c.b - c.a;
                        let t = ((p - c.a).dot(&ab) / ab.norm_squared().max(1e-12)).clamp(0.0, 1.0);
                        (p - (c.a + ab * t)).norm()
                    })
                    .fold(f64::INFINITY, f64::min)
                    - c.radius;
                let name = agent.joints[c.joint]
                    .link
                    .as_ref()
                    .map_or("?", |l| l.name.as_str());
                eprintln!(
                    "    {name:12} a ({:.2} {:.2} {:.2}) b ({:.2} {:.2} {:.2}) gap {:.3}",
                    c.a.x, c.a.y, c.a.z, c.b.x, c.b.y, c.b.z, gap
                );
            }
        }
        eprintln!("  {} hypotheses, stats {:?}", hyps.len(), out.stats);
        for hy in &hyps {
            let (u, n) = afford::detect::best_at(&agent, &h, &prepared.scene, hy, &cfg);
            if let Some(u) = u {
                let found: Vec<&str> = h
                    .nodes
                    .iter()
                    .zip(&u.nodes)
                    .filter(|(_, o)| o.found)
                    .map(|(n, _)| n.id.as_str())
                    .collect();
                eprintln!(
                    "    hyp {:?} head {:?} avail {:.2}: {n} fits, best yaw {:.0} score {:.3} {:?}",
                    hy.cell,
                    hy.heading.map(f64::to_degrees),
                    hy.availability,
                    u.placement.yaw.to_degrees(),
                    u.score,
                    found
                );
            }
        }
        inspect_png(
            &cloud,
            &prepared,
            &hyps,
            &out,
            &legend,
            Path::new(&format!("/tmp/render-{name}.png")),
        )
        .unwrap();
        let front = scene_image(&cloud, &out.detections, &legend, View::Front, 500, 500);
        let top = scene_image(&cloud, &out.detections, &legend, View::Top, 500, 500);
        panel(&[front, top])
            .save_png(Path::new(&format!("/tmp/render-{name}-ft.png")))
            .unwrap();
    }
}
