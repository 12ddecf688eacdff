//! Writes data/sample/room.ply: an armchair, a chair at a table, a stool against a wall and
//! a three-seat sofa, sampled from their surfaces (the committed sample of README).
use afford_synth::furniture::*;
fn main() {
    let s = StoolParams::default();
    let meshes = vec![
        chair(&ChairParams::with_arms()).placed(0.0, 0.0, 0.0),
        table(&TableParams::default()).placed(2.2, 0.0, 0.0),
        chair(&ChairParams::default()).placed(1.35, 0.0, 0.0),
        stool(&s).placed(0.0, 1.6, 0.0),
        sofa(&SofaParams {
            seats: 3,
            ..SofaParams::default()
        })
        .placed(2.6, 2.1, 180.0),
        wall(-0.6, -1.0, 2.5, 2.2, 0.1),
    ];
    let cloud = scene_cloud(&meshes, 1500.0, 0.003, 42, true);
    std::fs::create_dir_all("data/sample").unwrap();
    afford::cloud::write_ply_points(
        std::path::Path::new("data/sample/room.ply"),
        &cloud.points,
        &[],
        true,
    )
    .unwrap();
    println!("{} points", cloud.len());
}
