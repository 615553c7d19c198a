//! Assembly, the drop rule and the LDLᵀ solves on small matrices.

use super::*;

fn laplacian(n: usize) -> CsrMatrix {
    let mut a = Assembler::new(n);
    for i in 0..n {
        a.add(i, i, 2.5);
        if i + 1 < n {
            a.add(i, i + 1, -1.0);
            a.add(i + 1, i, -1.0);
        }
    }
    a.add(0, n - 1, 0.3);
    a.add(n - 1, 0, 0.3);
    a.finish()
}

#[test]
fn ldlt_solves() {
    let a = laplacian(50);
    let f = Ldlt::new(&a).unwrap();
    let b: Vec<f64> = (0..50).map(|i| (i as f64 * 0.37).sin()).collect();
    let x = f.solve(&b);
    let mut r = vec![0.0; 50];
    a.mul(&x, &mut r);
    for i in 0..50 {
        assert!((r[i] - b[i]).abs() < 1e-12);
    }
}

#[test]
fn many_columns_solve_as_one_at_a_time() {
    // 19 columns: two full groups of eight lanes and a partial one, on 1 and 2 threads.
    let a = laplacian(50);
    let f = Ldlt::new(&a).unwrap();
    let m = 19;
    let b: Vec<f64> = (0..50 * m).map(|i| (i as f64 * 0.61).cos()).collect();
    for threads in [1, 2] {
        let mut x = b.clone();
        f.solve_columns(&mut x, m, threads);
        for j in 0..m {
            let col: Vec<f64> = (0..50).map(|i| b[i * m + j]).collect();
            let want = f.solve(&col);
            for i in 0..50 {
                assert_eq!(
                    x[i * m + j],
                    want[i],
                    "column {j}, row {i}, {threads} threads"
                );
            }
        }
    }
}

#[test]
fn singular_matrix_is_an_error() {
    let mut a = Assembler::new(2);
    a.add_block(&[0, 1], &[1.0, -1.0, -1.0, 1.0], 1.0);
    assert!(Ldlt::new(&a.finish()).is_err());
}

#[test]
fn duplicates_are_summed_and_roundoff_dropped() {
    let mut a = Assembler::new(2);
    a.add(0, 0, 1.0);
    a.add(0, 0, 1.0);
    a.add(1, 1, 4.0);
    a.add(0, 1, 1e-17);
    a.add(1, 0, 1e-17);
    let m = a.finish();
    assert_eq!(m.get(0, 0), 2.0);
    assert_eq!(m.nnz(), 2);
}
