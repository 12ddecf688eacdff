//! Benchmarks of the pipeline stages and of the whole detection on the committed sample
//! (`data/sample/room.ply`, 90k points) and on a generated sofa: one hierarchy (sitting,
//! lying) and the default run (both, on one shared scene).

use std::path::Path;

use afford::cloud;
use afford::detect::{detect, detect_all, prepare, DetectConfig};
use afford::method::heightmap::HeightMap;
use afford::method::hypotheses::hypotheses;
use afford::method::scene::Scene;
use afford::model::set::load_models;
use afford_synth::furniture::{scene_cloud, sofa, SofaParams};
use criterion::{criterion_group, criterion_main, Criterion};

fn stages(c: &mut Criterion) {
    let sample = Path::new("data/sample/room.ply");
    let cloud = cloud::load(sample).unwrap().cloud;
    let (agent, h) = load_models(
        Path::new("agents/human.toml"),
        Path::new("affordances/sitting.toml"),
        1.75,
    )
    .unwrap();
    let (_, lying) = load_models(
        Path::new("agents/human.toml"),
        Path::new("affordances/lying.toml"),
        1.75,
    )
    .unwrap();
    let all = afford::model::set::ModelChoice::default().load().unwrap();
    let cfg = DetectConfig::default();
    let mut g = c.benchmark_group("room");
    g.sample_size(10);
    g.bench_function("load_ply", |b| b.iter(|| cloud::load(sample).unwrap()));
    g.bench_function("heightmap", |b| {
        b.iter(|| HeightMap::from_cloud(&cloud, &cfg.heightmap))
    });
    let prepared = prepare(&cloud, &cfg);
    g.bench_function("hypotheses", |b| {
        b.iter(|| hypotheses(&prepared.map, &h.hypothesis, h.orientation, agent.height))
    });
    g.bench_function("scene", |b| b.iter(|| Scene::new(&cloud, &cfg.scene)));
    g.bench_function("detect", |b| b.iter(|| detect(&cloud, &agent, &h, &cfg)));
    g.bench_function("detect_lying", |b| {
        b.iter(|| detect(&cloud, &agent, &lying, &cfg))
    });
    g.bench_function("detect_all", |b| b.iter(|| detect_all(&cloud, &all, &cfg)));
    g.finish();
    let sofa_cloud = scene_cloud(&[sofa(&SofaParams::default())], 4000.0, 0.002, 1, true);
    let mut g = c.benchmark_group("sofa");
    g.sample_size(10);
    g.bench_function("detect", |b| {
        b.iter(|| detect(&sofa_cloud, &agent, &h, &cfg))
    });
    g.bench_function("detect_lying", |b| {
        b.iter(|| detect(&sofa_cloud, &agent, &lying, &cfg))
    });
    g.finish();
}

/// The benchmark group.
#[allow(missing_docs)]
mod group {
    use super::*;
    criterion_group!(benches, stages);
}
use group::benches;
criterion_main!(benches);
