//! Small dense systems, row-major, through faer; and the one hand-written kernel of the time
//! step (`lu_solve_in_place`), whose systems are a car's 4 × 4 contact Jacobian blocks, solved
//! every Newton iteration of every step without allocating.

use faer::Mat;
use faer::linalg::solvers::{DenseSolveCore, Solve};

fn to_mat(a: &[f64], n: usize) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| a[i * n + j])
}

fn to_rows(m: &Mat<f64>) -> Vec<f64> {
    let (r, c) = (m.nrows(), m.ncols());
    (0..r * c).map(|q| m[(q / c, q % c)]).collect()
}

/// Inverse of a symmetric positive definite n × n matrix (Cholesky); `None` when it is not
/// positive definite or the inverse is not finite.
pub fn inverse_spd(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let inv = to_rows(&to_mat(a, n).llt(faer::Side::Lower).ok()?.inverse());
    inv.iter().all(|x| x.is_finite()).then_some(inv)
}

/// Inverse of an n × n matrix (LU with partial pivoting); `None` when it is singular (the
/// inverse not finite).
pub fn inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let inv = to_rows(&to_mat(a, n).partial_piv_lu().inverse());
    inv.iter().all(|x| x.is_finite()).then_some(inv)
}

/// Solves A·x = b (LU with partial pivoting); `None` when A is singular.
pub fn solve(a: &[f64], b: &[f64]) -> Option<Vec<f64>> {
    let n = b.len();
    let rhs = Mat::from_fn(n, 1, |i, _| b[i]);
    let x = to_mat(a, n).partial_piv_lu().solve(&rhs);
    let x: Vec<f64> = (0..n).map(|i| x[(i, 0)]).collect();
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Solves J·x = b in place (row-major n × n, partial pivoting), overwriting J: the contact
/// Newton's per-car blocks, every iteration of every step, with no allocation.
pub fn lu_solve_in_place(j: &mut [f64], b: &mut [f64], n: usize) {
    for col in 0..n {
        let mut piv = col;
        for r in col + 1..n {
            if j[r * n + col].abs() > j[piv * n + col].abs() {
                piv = r;
            }
        }
        if piv != col {
            for c in 0..n {
                j.swap(col * n + c, piv * n + c);
            }
            b.swap(col, piv);
        }
        let d = j[col * n + col];
        for r in col + 1..n {
            let f = j[r * n + col] / d;
            if f != 0.0 {
                for c in col..n {
                    j[r * n + c] -= f * j[col * n + c];
                }
                b[r] -= f * b[col];
            }
        }
    }
    for r in (0..n).rev() {
        let mut s = b[r];
        for c in r + 1..n {
            s -= j[r * n + c] * b[c];
        }
        b[r] = s / j[r * n + r];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A known system: A = [[4, 1, 0], [1, 3, 1], [0, 1, 2]], x = (1, −2, 3).
    #[test]
    fn small_systems_against_a_known_solution() {
        let a = [4.0, 1.0, 0.0, 1.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        let x = [1.0, -2.0, 3.0];
        let b: Vec<f64> = (0..3)
            .map(|i| (0..3).map(|k| a[i * 3 + k] * x[k]).sum())
            .collect();
        let got = solve(&a, &b).unwrap();
        let mut j = a;
        let mut inplace = b.clone();
        lu_solve_in_place(&mut j, &mut inplace, 3);
        for inv in [inverse_spd(&a, 3).unwrap(), inverse(&a, 3).unwrap()] {
            for i in 0..3 {
                let xi: f64 = (0..3).map(|k| inv[i * 3 + k] * b[k]).sum();
                assert!((xi - x[i]).abs() < 1e-12);
            }
        }
        for i in 0..3 {
            assert!((got[i] - x[i]).abs() < 1e-12 && (inplace[i] - x[i]).abs() < 1e-12);
        }
        assert!(
            inverse_spd(&[1.0, 2.0, 2.0, 1.0], 2).is_none(),
            "indefinite"
        );
        assert!(inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none(), "singular");
    }
}
