//! Benchmarks at the sizes of issue 12, on seeded synthetic scenes built with the
//! library's own `synth` code (nothing is read from outside the repository):
//!
//! `chair_view` (one depth view of an armchair, 100k-300k points), `room_view` (one depth
//! view of a furnished room corner, 200k-300k points), `room_scan` (the whole room
//! sampled from its surfaces, about 1M points) and `big_floor` (one chair on a
//! 200 m x 200 m floor); see `afford_synth::scenes`.
//!
//! Every stage alone (PLY read, height map, the holes' search, hypotheses, scene, the distance field over
//! the whole occupied box, fitting, unfolding, segmentation) and the default run end to
//! end (sitting and lying, one shared scene). The scene stage voxelises and, for a box
//! of at most 2^25 cells, runs the field's passes along x and y; the pass along z (per
//! tile of columns) or, for a larger box, the field's chunks are computed where the fits
//! first ask for them, so `fit_*` includes them (each `fit_*` iteration builds its own
//! scene) and `field_all` measures them all.
//! Run with `nice -n 19 cargo bench --bench scale` (add a scene name to filter, e.g.
//! `cargo bench --bench scale -- room_view`).

use afford::cloud;
use afford::detect::{best_at, detect_all, prepare, DetectConfig};
use afford::method::fit::fit;
use afford::method::hypotheses::hypotheses;
use afford::method::scene::Scene;
use afford::method::select::segment;
use afford::method::unfold::unfold;
use afford::model::set::Model;
use afford::model::set::ModelChoice;
use afford_synth::scenes::speed_scenes;
use criterion::{criterion_group, criterion_main, Criterion};
use nalgebra::Point3;

fn stages(c: &mut Criterion) {
    let models: Vec<Model> = ModelChoice::default().load().unwrap();
    let cfg = DetectConfig::default();
    let dir = tempfile::tempdir().unwrap();
    for (name, cloud) in speed_scenes() {
        let mut g = c.benchmark_group(format!("{name}_{}k", cloud.len() / 1000));
        g.sample_size(10);
        let path = dir.path().join(format!("{name}.ply"));
        cloud::write_ply_points(&path, &cloud.points, &[], true).unwrap();
        g.bench_function("load_ply", |b| b.iter(|| cloud::load(&path).unwrap()));
        g.bench_function("heightmap", |b| {
            b.iter(|| afford::method::heightmap::HeightMap::from_cloud(&cloud, &cfg.heightmap))
        });
        let map = afford::method::heightmap::HeightMap::from_cloud(&cloud, &cfg.heightmap);
        g.bench_function("holes", |b| {
            b.iter(|| afford::method::holes::holes(&map, &cfg.holes).len())
        });
        g.bench_function("scene", |b| b.iter(|| Scene::new(&cloud, &cfg.scene)));
        if name != "big_floor" {
            // Every chunk of the field over the occupied box (the big floor's 4 x 10^9
            // cells are the case the lazy field avoids).
            g.bench_function("field_all", |b| {
                b.iter(|| {
                    let scene = Scene::new(&cloud, &cfg.scene);
                    field_lattice(&cloud, 0.32)
                        .map(|p| scene.surface_distance(&p, 0.0))
                        .sum::<f64>()
                })
            });
        }
        let prepared = prepare(&cloud, &cfg);
        for m in &models {
            let (agent, h) = (&m.agent, &m.hierarchy);
            let hyps = hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height);
            g.bench_function(format!("hypotheses_{}", h.name), |b| {
                b.iter(|| hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height))
            });
            g.bench_function(format!("fit_{}", h.name), |b| {
                b.iter(|| {
                    let scene = Scene::new(&cloud, &cfg.scene);
                    hyps.iter()
                        .map(|hyp| fit(agent, h, &scene, hyp, &cfg.contact).len())
                        .sum::<usize>()
                })
            });
            let fits: Vec<_> = hyps
                .iter()
                .flat_map(|hyp| fit(agent, h, &prepared.scene, hyp, &cfg.contact))
                .collect();
            g.bench_function(format!("unfold_{}", h.name), |b| {
                b.iter(|| {
                    fits.iter()
                        .map(|f| unfold(agent, h, &prepared.scene, f, &cfg.contact).score)
                        .sum::<f64>()
                })
            });
            g.bench_function(format!("fit_and_unfold_parallel_{}", h.name), |b| {
                use rayon::prelude::*;
                b.iter(|| {
                    hyps.par_iter()
                        .map(|hyp| best_at(agent, h, &prepared.scene, hyp, &cfg).1)
                        .sum::<usize>()
                })
            });
        }
        let outcomes = detect_all(&cloud, &models, &cfg);
        let seeds: Vec<Point3<f64>> = outcomes[0].detections.iter().map(|d| d.seat).collect();
        g.bench_function("segment", |b| {
            b.iter(|| segment(&cloud, &seeds, &cfg.segment))
        });
        g.bench_function("detect_all", |b| {
            b.iter(|| detect_all(&cloud, &models, &cfg))
        });
        g.bench_function("load_and_detect_all", |b| {
            b.iter(|| {
                let cloud = cloud::load(&path).unwrap().cloud;
                detect_all(&cloud, &models, &cfg)
            })
        });
        g.finish();
        eprintln!(
            "{name}: {} points, {} detections ({})",
            cloud.len(),
            outcomes.iter().map(|o| o.detections.len()).sum::<usize>(),
            outcomes
                .iter()
                .map(|o| format!("{} hypotheses", o.stats.hypotheses))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
}

/// Points every `step` metres over the bounding box of `cloud` (world frame).
// A lattice over a speed scene (tens of metres at centimetre steps): counts far inside usize.
#[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
fn field_lattice(
    cloud: &afford::cloud::PointCloud,
    step: f64,
) -> impl Iterator<Item = Point3<f64>> {
    let (lo, hi) = cloud.bounds().expect("a speed scene has points");
    let n = ((hi - lo) / step).map(|e| e.ceil() as usize + 1);
    (0..n.x * n.y * n.z).map(move |i| {
        let (x, y, z) = (i % n.x, i / n.x % n.y, i / (n.x * n.y));
        lo + nalgebra::Vector3::new(x as f64, y as f64, z as f64) * step
    })
}

/// The benchmark group.
#[allow(missing_docs)]
mod group {
    use super::*;
    criterion_group!(benches, stages);
}
use group::benches;
criterion_main!(benches);
