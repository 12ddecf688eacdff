//! Benchmarks at the sizes of issue 12, on seeded synthetic scenes built with the
//! library's own `synth` code (nothing is read from outside the repository):
//!
//! `chair_view` (one depth view of an armchair, 100k-300k points), `room_view` (one depth
//! view of a furnished room corner, 200k-300k points) and `room_scan` (the whole room
//! sampled from its surfaces, about 1M points); see `afford::synth::scenes`.
//!
//! Every stage alone (PLY read, height map, hypotheses, scene, fitting, unfolding,
//! segmentation) and the default run end to end (sitting and lying, one shared scene).
//! Run with `cargo bench --bench scale` (add a scene name to filter, e.g.
//! `cargo bench --bench scale -- room_view`).

use afford::cloud;
use afford::detect::{best_at, detect_all, prepare, DetectConfig};
use afford::fit::fit;
use afford::hypotheses::hypotheses;
use afford::model_set::Model;
use afford::run::ModelChoice;
use afford::scene::Scene;
use afford::select::segment;
use afford::synth::scenes::speed_scenes;
use afford::unfold::unfold;
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
            b.iter(|| afford::heightmap::HeightMap::from_cloud(&cloud, &cfg.heightmap))
        });
        g.bench_function("scene", |b| b.iter(|| Scene::new(&cloud, &cfg.scene)));
        let prepared = prepare(&cloud, &cfg);
        for m in &models {
            let (agent, h) = (&m.agent, &m.hierarchy);
            let hyps = hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height);
            g.bench_function(format!("hypotheses_{}", h.name), |b| {
                b.iter(|| hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height))
            });
            g.bench_function(format!("fit_{}", h.name), |b| {
                b.iter(|| {
                    hyps.iter()
                        .map(|hyp| fit(agent, h, &prepared.scene, hyp, &cfg.contact).len())
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

/// The benchmark group.
#[allow(missing_docs)]
mod group {
    use super::*;
    criterion_group!(benches, stages);
}
use group::benches;
criterion_main!(benches);
