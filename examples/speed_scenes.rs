//! Writes the seeded scenes of issue 12 (`afford_synth::scenes`) as binary PLY files into
//! the directory given (default `target/speed`), for timed runs of `afford detect`:
//! `cargo run --release --example speed_scenes -- target/speed`.
fn main() {
    let dir = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "target/speed".to_string());
    let dir = std::path::Path::new(&dir);
    std::fs::create_dir_all(dir).expect("output directory");
    for (name, cloud) in afford_synth::scenes::speed_scenes() {
        let path = dir.join(format!("{name}.ply"));
        afford::cloud::write_ply_points(&path, &cloud.points, &[], true).expect("write PLY");
        println!("{}: {} points", path.display(), cloud.len());
    }
}
