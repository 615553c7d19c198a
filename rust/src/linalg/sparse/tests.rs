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

/// A chain of nodes with two unknowns each, coupled to the next two nodes (a beam on a
/// foundation, mass-dominated as Newmark's A is), with a longer coupling every 7 nodes (the
/// columns' patterns differ: plain columns).
fn chain(nodes: usize) -> CsrMatrix {
    let n = 2 * nodes;
    let mut a = Assembler::new(n);
    for i in 0..n {
        a.add(i, i, 6.0 + (i % 3) as f64 * 0.1);
        for (d, v) in [(1, -0.9), (2, -0.6), (3, 0.2), (4, -0.3)] {
            if i + d < n {
                a.add(i, i + d, v);
                a.add(i + d, i, v);
            }
        }
        if i % 14 == 0 && i + 9 < n {
            a.add(i, i + 9, -0.05);
            a.add(i + 9, i, -0.05);
        }
    }
    a.finish()
}

/// Twelve chains numbered slot by slot, each coupled to its next two slots and weakly to its
/// neighbour's next slot (a modal basis' per-mode chains: runs of equal-pattern columns,
/// stored as segments).
fn interleaved(slots: usize) -> CsrMatrix {
    const M: usize = 12;
    let n = M * slots;
    let mut a = Assembler::new(n);
    for i in 0..n {
        a.add(i, i, 5.0);
        let mut couple = |j: usize, v: f64| {
            if j < n {
                a.add(i, j, v);
                a.add(j, i, v);
            }
        };
        couple(i + M, -0.9);
        couple(i + 2 * M, -0.4);
        if i % M + 1 < M {
            couple(i + M + 1, 0.1);
        }
    }
    a.finish()
}

#[test]
fn a_windowed_column_of_the_inverse_is_the_full_solves_where_it_matters() {
    let drop = 1.0 / (1u64 << 60) as f64;
    for (segmented, a) in [(false, chain(6000)), (true, interleaved(1000))] {
        let order: Vec<usize> = (0..a.n).collect();
        let f = Ldlt::with_ordering(&a, Some(&order)).unwrap();
        let (_, _, segments, _) = f.layout();
        assert_eq!(segments > 0, segmented, "{segments} segments");
        let mut z = vec![0.0; a.n];
        for k in [0, 1, 777, 6001, a.n - 2, a.n - 1] {
            let mut e = vec![0.0; a.n];
            e[k] = 1.0;
            let full = f.solve(&e); // natural order: the factor's numbering is the original
            let big = full.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let (lo, hi) = f.column_window(k, drop, &mut z).unwrap();
            assert!(lo <= k && k < hi);
            assert!(
                hi - lo < a.n / 8,
                "column {k}: window {lo}..{hi} of {}",
                a.n
            );
            for (i, want) in full.iter().enumerate() {
                let got = if (lo..hi).contains(&i) { z[i] } else { 0.0 };
                assert!(
                    (got - want).abs() <= 4.0 * drop * big + 1e-15 * want.abs(),
                    "column {k}, row {i}: {got:e} against {want:e}"
                );
            }
            z[lo..hi].fill(0.0);
            assert!(z.iter().all(|&v| v == 0.0), "column {k}: z left zero");
        }
    }
}

#[test]
fn a_column_reaching_the_border_rows_is_left_to_the_full_solve() {
    // One unknown coupled to all: the border, which every column reaches.
    let nodes = 300;
    let mut a = Assembler::new(2 * nodes + 1);
    let base = chain(nodes);
    for i in 0..base.n {
        for j in 0..base.n {
            let v = base.get(i, j);
            if v != 0.0 {
                a.add(i, j, v);
            }
        }
        a.add(i, base.n, 0.01);
        a.add(base.n, i, 0.01);
    }
    a.add(base.n, base.n, 50.0);
    let a = a.finish();
    let order: Vec<usize> = (0..a.n).collect();
    let f = Ldlt::with_ordering(&a, Some(&order)).unwrap();
    assert!(f.layout().0 > 0, "a border row");
    let mut z = vec![0.0; a.n];
    assert!(f.column_window(10, 1e-18, &mut z).is_none());
    assert!(z.iter().all(|&v| v == 0.0));
}
