//! Solver timing (`cargo bench`): one run of the article's case (vtb.paper_config(): 160 m,
//! one car, 80 m/s, Δt = 5e−5 s, ≈ 34 500 steps) on one core, with the irregularity sample
//! the Python preset generates (benches/data, written by benches/make_fixture.py): the FE–SEA
//! hybrid (the preset: 120 global + 100 local rail sines, ω_r = 2π·800 Hz), the uncorrected
//! modal model, the hybrid with the optimisation's 10 TIDs, the conventional finite-element
//! model (251 elements per layer) and the converged preset (Timoshenko rail 20 elements per
//! bay with element flexibility, lower layers 0.32 m, Δt = 2.5e−5 s: ≈ 69 000 steps). Compare
//! `converged_full_run` with `hybrid_full_run` of the same bench run.

use criterion::{Criterion, criterion_group, criterion_main};
mod common;

use common::paper_profile;
use vtb::Profile;
use vtb::engine::newmark::Simulation;
use vtb::library::presets;

/// Unknowns, nonzeros of the stepping matrix A = 2M + ΔtC + Δt²K/2 and of its LDLᵀ factor,
/// and the half-bandwidth of A in the mesh's natural (by position) numbering.
fn print_factor_size(cfg: &vtb::config::Config) {
    let model = vtb::check::validated(cfg.clone(), Profile::flat()).unwrap();
    let st = &model.structure;
    let (m, c, k) = st.stepping_matrices();
    let dt = cfg.solver.dt;
    let a = vtb::linalg::sparse::CsrMatrix::combine(&[(2.0, m), (dt, c), (0.5 * dt * dt, k)]);
    let rail: Vec<usize> = (0..st.layers[0].n_dofs())
        .map(|i| st.layers[0].offset + i)
        .collect();
    let f = vtb::linalg::sparse::Ldlt::for_stepping(&a, &rail).unwrap();
    // Position of every unknown: its node's x (finite elements).
    let mut x = vec![0.0; a.n];
    for l in &st.layers {
        if let vtb::model::basis::LayerBasis::Fem(mesh) = &l.basis {
            for (i, &xn) in mesh.nodes.iter().enumerate() {
                x[l.offset + 2 * i] = xn;
                x[l.offset + 2 * i + 1] = xn;
            }
        }
    }
    let mut order: Vec<usize> = (0..a.n).collect();
    order.sort_by(|&i, &j| x[i].total_cmp(&x[j]));
    let mut pos = vec![0; a.n];
    for (p, &i) in order.iter().enumerate() {
        pos[i] = p;
    }
    let band = (0..a.n)
        .flat_map(|i| (a.row_ptr[i]..a.row_ptr[i + 1]).map(move |p| (i, p)))
        .map(|(i, p)| pos[i].abs_diff(pos[a.col_idx[p]]))
        .max()
        .unwrap_or(0);
    println!(
        "converged preset: {} unknowns, A has {} nonzeros, half-bandwidth {} by position; LDLᵀ factor {} nonzeros ({:.1} per unknown)",
        a.n,
        a.nnz(),
        band,
        f.nnz_l(),
        f.nnz_l() as f64 / a.n as f64
    );
}

fn bench_paper(c: &mut Criterion) {
    let profile = paper_profile();
    let mut g = c.benchmark_group("paper_case");
    g.sample_size(10);
    let run = |cfg: &vtb::config::Config| {
        let model = vtb::check::validated(cfg.clone(), profile.clone()).unwrap();
        Simulation::new(&model).unwrap().run(None).unwrap()
    };
    let hybrid = presets::paper();
    g.bench_function("hybrid_full_run", |b| b.iter(|| run(&hybrid)));
    // The optimisation's evaluation: the hybrid with 10 rail–slab TIDs (vtb.tids_around).
    let mut tids = presets::paper();
    tids.dampers = vec![vtb::config::DamperGroup {
        name: Some("tids".into()),
        inertance: 5.0,
        stiffness: 2e8,
        damping: 1e3,
        kind: vtb::config::DamperKind::Tid,
        count: Some(10),
        x0: Some(77.12),
        spacing: Some(0.64),
        positions: None,
        upper: "rail".into(),
        lower: "slab".into(),
    }];
    g.bench_function("hybrid_10_tids_full_run", |b| b.iter(|| run(&tids)));
    let mut modal = presets::paper();
    modal.discretisation.method = vtb::config::Method::Modal;
    g.bench_function("modal_full_run", |b| b.iter(|| run(&modal)));
    let model = vtb::check::validated(modal.clone(), profile.clone()).unwrap();
    g.bench_function("modal_time_stepping_only", |b| {
        b.iter(|| Simulation::new(&model).unwrap().run(None).unwrap())
    });
    let mut fem = presets::paper();
    fem.discretisation.method = vtb::config::Method::Fem;
    fem.discretisation.fem_elements = 251;
    g.bench_function("fem251_full_run", |b| b.iter(|| run(&fem)));
    let converged = presets::paper_converged();
    print_factor_size(&converged);
    g.bench_function("converged_full_run", |b| b.iter(|| run(&converged)));
    g.finish();
    println!("{}", common::machine_load());
}

criterion_group!(benches, bench_paper);
criterion_main!(benches);
