use std::time::Instant;
fn main() {
    let cfg = vtb::library::presets::paper();
    let t0 = Instant::now();
    let model = vtb::check::validated(cfg, vtb::Profile::flat()).unwrap();
    let t1 = Instant::now();
    let sim = vtb::engine::newmark::Simulation::new(&model).unwrap();
    let t2 = Instant::now();
    let res = sim.run(None).unwrap();
    let t3 = Instant::now();
    println!(
        "assemble {:?} setup {:?} run {:?}",
        t1 - t0,
        t2 - t1,
        t3 - t2
    );
    println!(
        "nnz M {} K {} C {}",
        model.structure.m.nnz(),
        model.structure.k.nnz(),
        model.structure.c.nnz()
    );
    for (k, v) in res.metrics() {
        println!("{k:24} {v:.6e}");
    }
}
