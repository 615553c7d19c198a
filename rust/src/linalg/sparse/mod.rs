//! Sparse symmetric matrices: assembly, products, and an LDLᵀ factor with allocation-free,
//! multi-right-hand-side solves for the time-step loop.
//!
//! Assembly sums symmetric contributions and then drops off-diagonal entries below
//! `DROP_TOL`·sqrt(|a_ii·a_jj|): the closed-form integrals of orthogonal sines and the discrete
//! sums over uniform fastener grids leave round-off of order 1e-16 relative where the exact
//! value is zero, and keeping it would make the matrices dense. The dropped entries change
//! the solution by a relative amount of the same order as round-off itself.
//!
//! - `mod.rs` (this file): assembly ([`Assembler`]) and the CSR matrix ([`CsrMatrix`]);
//! - `operator`: the products M·x, K·x of a time step in one pass ([`SymOperator`]);
//! - `ldlt`: the LDLᵀ factor ([`Ldlt`]): its factorisation, the elimination orders for time
//!   stepping and the solves.

mod ldlt;
mod operator;

pub use ldlt::Ldlt;
pub use operator::SymOperator;

/// Relative drop tolerance for exact-zero entries polluted by round-off.
pub const DROP_TOL: f64 = 1e-12;

/// Collects symmetric contributions as triplets.
#[derive(Clone, Debug)]
pub struct Assembler {
    n: usize,
    entries: Vec<(u32, u32, f64)>,
}

impl Assembler {
    pub fn new(n: usize) -> Self {
        Self {
            n,
            entries: Vec::new(),
        }
    }

    pub fn dim(&self) -> usize {
        self.n
    }

    /// Adds v at (i, j); the caller adds the symmetric partner itself.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        self.entries.push((i as u32, j as u32, v));
    }

    /// Adds `scale`·B for a dense square block B (row-major, dim = dofs.len()).
    pub fn add_block(&mut self, dofs: &[usize], block: &[f64], scale: f64) {
        let m = dofs.len();
        debug_assert_eq!(block.len(), m * m);
        if scale == 0.0 {
            return;
        }
        self.entries.reserve(m * m);
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                self.add(i, j, scale * block[a * m + b]);
            }
        }
    }

    /// Sums duplicates, applies the drop rule and returns the CSR matrix (both triangles).
    pub fn finish(self) -> CsrMatrix {
        self.finish_exact().dropped(DROP_TOL)
    }

    /// Sums duplicates without dropping anything.
    pub fn finish_exact(self) -> CsrMatrix {
        let n = self.n;
        let mut count = vec![0usize; n + 1];
        for &(i, _, _) in &self.entries {
            count[i as usize + 1] += 1;
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut next = count.clone();
        let mut cols = vec![0u32; self.entries.len()];
        let mut vals = vec![0.0; self.entries.len()];
        for &(i, j, v) in &self.entries {
            let p = &mut next[i as usize];
            cols[*p] = j;
            vals[*p] = v;
            *p += 1;
        }
        let mut row_ptr = vec![0usize; n + 1];
        let mut col_idx = Vec::with_capacity(self.entries.len() / 2);
        let mut values = Vec::with_capacity(self.entries.len() / 2);
        let mut order: Vec<usize> = Vec::new();
        for i in 0..n {
            let (a, b) = (count[i], count[i + 1]);
            order.clear();
            order.extend(a..b);
            order.sort_unstable_by_key(|&p| cols[p]);
            let mut last: Option<u32> = None;
            for &p in &order {
                if last == Some(cols[p]) {
                    *values.last_mut().unwrap() += vals[p];
                } else {
                    col_idx.push(cols[p] as usize);
                    values.push(vals[p]);
                    last = Some(cols[p]);
                }
            }
            row_ptr[i + 1] = col_idx.len();
        }
        CsrMatrix {
            n,
            row_ptr,
            col_idx,
            values,
        }
    }
}

/// Square sparse matrix in compressed sparse row form (symmetric matrices store both
/// triangles).
#[derive(Clone, Debug, PartialEq)]
pub struct CsrMatrix {
    pub n: usize,
    pub row_ptr: Vec<usize>,
    pub col_idx: Vec<usize>,
    pub values: Vec<f64>,
}

impl CsrMatrix {
    pub fn zeros(n: usize) -> Self {
        Self {
            n,
            row_ptr: vec![0; n + 1],
            col_idx: Vec::new(),
            values: Vec::new(),
        }
    }

    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    pub fn diagonal(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.get(i, i)).collect()
    }

    pub fn get(&self, i: usize, j: usize) -> f64 {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        match self.col_idx[r.clone()].binary_search(&j) {
            Ok(p) => self.values[r.start + p],
            Err(_) => 0.0,
        }
    }

    fn dropped(self, tol: f64) -> Self {
        let d: Vec<f64> = self.diagonal().iter().map(|v| v.abs()).collect();
        let mut out = CsrMatrix::zeros(self.n);
        for i in 0..self.n {
            for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                let (j, v) = (self.col_idx[p], self.values[p]);
                let keep = if i == j {
                    v != 0.0
                } else {
                    v.abs() > tol * (d[i] * d[j]).sqrt()
                };
                if keep {
                    out.col_idx.push(j);
                    out.values.push(v);
                }
            }
            out.row_ptr[i + 1] = out.col_idx.len();
        }
        out
    }

    /// y = A·x.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        for i in 0..self.n {
            let mut s = 0.0;
            for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                s += self.values[p] * x[self.col_idx[p]];
            }
            y[i] = s;
        }
    }

    pub fn to_dense(&self) -> Vec<Vec<f64>> {
        let mut d = vec![vec![0.0; self.n]; self.n];
        for i in 0..self.n {
            for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                d[i][self.col_idx[p]] = self.values[p];
            }
        }
        d
    }

    /// Σ_k w_k·A_k over matrices of the same dimension, on the union of their patterns.
    /// Nothing is dropped: the Newmark recursions rely on A = 2M + ΔtC + (Δt²/2)K and
    /// 4M − Δt²K being exactly consistent with M, C and K.
    pub fn combine(terms: &[(f64, &CsrMatrix)]) -> CsrMatrix {
        let n = terms[0].1.n;
        let mut asm = Assembler::new(n);
        for &(w, a) in terms {
            assert_eq!(a.n, n);
            for i in 0..n {
                for p in a.row_ptr[i]..a.row_ptr[i + 1] {
                    asm.add(i, a.col_idx[p], w * a.values[p]);
                }
            }
        }
        asm.finish_exact()
    }

    /// Largest |a_ij − a_ji| relative to the largest |a_ij|.
    pub fn asymmetry(&self) -> f64 {
        let mut worst: f64 = 0.0;
        let mut scale: f64 = 0.0;
        for i in 0..self.n {
            for p in self.row_ptr[i]..self.row_ptr[i + 1] {
                let j = self.col_idx[p];
                scale = scale.max(self.values[p].abs());
                worst = worst.max((self.values[p] - self.get(j, i)).abs());
            }
        }
        if scale == 0.0 { 0.0 } else { worst / scale }
    }
}

#[cfg(test)]
mod tests;
