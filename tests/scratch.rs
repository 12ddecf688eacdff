//! Scratch driver (to be replaced by the integration tests).
use afford::agent::Agent;
use afford::detect::{detect, DetectConfig};
use afford::hierarchy::Hierarchy;
use afford::synth::*;
use std::path::Path;

#[test]
fn scratch() {
    let agent = Agent::load(Path::new("agents/human.toml"), 1.75).unwrap();
    let h = Hierarchy::load(Path::new("affordances/sitting.toml"), &agent).unwrap();
    let cfg = DetectConfig::default();
    let cases: Vec<(&str, Mesh)> = vec![
        ("stool", stool(&StoolParams::default())),
        ("chair", chair(&ChairParams::default())),
        ("armchair_chair", chair(&ChairParams::with_arms())),
        ("highback", chair(&ChairParams::high_back())),
        ("sofa", sofa(&SofaParams::default())),
        ("table", table(&TableParams::default())),
        ("shelf", shelf(&ShelfParams::default())),
    ];
    for (name, m) in cases {
        let cloud = scene_cloud(&[m], 4000.0, 0.002, 1, true);
        let t = std::time::Instant::now();
        let out = detect(&cloud, &agent, &h, &cfg);
        println!("{name}: {:?} in {:?}", out.stats, t.elapsed());
        for d in out.detections.iter().take(4) {
            println!(
                "   {:?} at ({:.2},{:.2},{:.2}) yaw {:.0} score {:.3} stab {:.2} seg {} local {:?}",
                d.affordances,
                d.position.x,
                d.position.y,
                d.position.z,
                d.yaw.to_degrees(),
                d.score,
                d.stability,
                d.segment_points,
                d.local_scores
            );
        }
    }
}
