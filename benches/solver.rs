//! Solver timing (`cargo bench`): one run of the article's case (vtb.paper_config(): 160 m,
//! one car, 80 m/s, Δt = 5e−5 s, ≈ 34 500 steps) on one core, with the irregularity sample
//! the Python preset generates (benches/data, written by benches/make_fixture.py): the FE–SEA
//! hybrid (the preset: 120 global + 100 local rail sines, ω_r = 2π·800 Hz), the uncorrected
//! modal model, the hybrid with the optimisation's 10 TIDs and the conventional finite-element
//! reference (251 elements per layer).

use criterion::{Criterion, criterion_group, criterion_main};
use std::path::Path;
use vtb::{Model, Profile, presets, simulate::Simulation};

fn paper_profile() -> Profile {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/data");
    let meta: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("paper_profile.json")).expect("fixture json"),
    )
    .expect("json");
    let bytes = std::fs::read(dir.join("paper_profile.f64")).expect("fixture data");
    let values = bytes
        .chunks_exact(8)
        .map(|b| f64::from_le_bytes(b.try_into().unwrap()))
        .collect();
    Profile {
        x0: meta["x0"].as_f64().unwrap(),
        dx: meta["dx"].as_f64().unwrap(),
        values,
    }
}

fn bench_paper(c: &mut Criterion) {
    let profile = paper_profile();
    let mut g = c.benchmark_group("paper_case");
    g.sample_size(10);
    let run = |cfg: &vtb::config::Config| {
        let model = Model::new(cfg.clone(), profile.clone()).unwrap();
        Simulation::new(&model).unwrap().run(None).unwrap()
    };
    let hybrid = presets::paper();
    g.bench_function("hybrid_full_run", |b| b.iter(|| run(&hybrid)));
    // The optimisation's evaluation: the hybrid with 10 rail–slab TIDs (vtb.tids_around).
    let mut tids = presets::paper();
    tids.tids = Some(vtb::config::TidConfig {
        inertance: 5.0,
        stiffness: 2e8,
        damping: 1e3,
        count: 10,
        x0: 77.12,
        spacing: 0.64,
        upper: "rail".into(),
        lower: "slab".into(),
    });
    g.bench_function("hybrid_10_tids_full_run", |b| b.iter(|| run(&tids)));
    let mut modal = presets::paper();
    modal.discretisation.method = vtb::config::Method::Modal;
    g.bench_function("modal_full_run", |b| b.iter(|| run(&modal)));
    let model = Model::new(modal.clone(), profile.clone()).unwrap();
    g.bench_function("modal_time_stepping_only", |b| {
        b.iter(|| Simulation::new(&model).unwrap().run(None).unwrap())
    });
    let mut fem = presets::paper();
    fem.discretisation.method = vtb::config::Method::Fem;
    fem.discretisation.fem_elements = 251;
    g.bench_function("fem251_full_run", |b| b.iter(|| run(&fem)));
    g.finish();
}

criterion_group!(benches, bench_paper);
criterion_main!(benches);
