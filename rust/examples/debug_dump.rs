use vtb::sparse::{CsrMatrix, Ldlt, PairOperator};
use std::time::Instant;
fn main() {
    let cfg = vtb::presets::paper();
    let model = vtb::Model::new(cfg, vtb::Profile::flat()).unwrap();
    let st = &model.structure;
    let dt = 5e-5;
    let a = CsrMatrix::combine(&[(2.0, &st.m), (dt, &st.c), (0.5 * dt * dt, &st.k)]);
    let n = a.n;
    let rail: Vec<usize> = (0..124).collect();
    let f = Ldlt::for_stepping(&a, &rail).unwrap();
    let reps = 34531;
    let mut z = vec![1.0; n];
    let z0: Vec<f64> = (0..n).map(|i| ((i as f64)*0.37).sin()).collect();
    let t = Instant::now(); for _ in 0..reps { z.copy_from_slice(&z0); f.forward::<1>(&mut z, 0); } println!("forward {:?}", t.elapsed());
    let t = Instant::now(); for _ in 0..reps { z.copy_from_slice(&z0); f.diag_backward(&mut z); } println!("backward {:?}", t.elapsed());
    let pair = PairOperator::new(&CsrMatrix::combine(&[(4.0, &st.m), (-dt * dt, &st.k)]), &st.k);
    let (mut y1, mut y2) = (vec![0.0; n], vec![0.0; n]);
    let t = Instant::now(); for _ in 0..reps { pair.mul(&z0, &mut y1, &mut y2); } println!("pair {:?} nnz {}", t.elapsed(), pair.nnz());
    println!("{}", z[3]);
}
