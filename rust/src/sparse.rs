//! Sparse symmetric matrices: assembly, products, and an LDLᵀ factor with allocation-free,
//! multi-right-hand-side solves for the time-step loop.
//!
//! Assembly sums symmetric contributions and then drops off-diagonal entries below
//! `DROP_TOL`·sqrt(|a_ii·a_jj|): the closed-form integrals of orthogonal sines and the discrete
//! sums over uniform fastener grids leave round-off of order 1e-16 relative where the exact
//! value is zero, and keeping it would make the matrices dense. The dropped entries change
//! the solution by a relative amount of the same order as round-off itself.

use crate::error::{Result, VtbError};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

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
        Self { n, entries: Vec::new() }
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
        CsrMatrix { n, row_ptr, col_idx, values }
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
        Self { n, row_ptr: vec![0; n + 1], col_idx: Vec::new(), values: Vec::new() }
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
                let keep = if i == j { v != 0.0 } else { v.abs() > tol * (d[i] * d[j]).sqrt() };
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

/// Two symmetric matrices A, B on one sparsity pattern, applied to the same vector in one
/// pass. The few heavy rows (the boundary functions of a modal basis couple to every sine)
/// are kept as dense segments over their column span: by symmetry the same segment serves
/// as a contiguous dot product for the heavy row and as a contiguous axpy for the heavy
/// column. The remaining light–light entries form a small CSR.
#[derive(Clone, Debug)]
pub struct PairOperator {
    n: usize,
    row_ptr: Vec<u32>,
    col_idx: Vec<u32>,
    /// (a_ij, b_ij) of light–light entries.
    values: Vec<[f64; 2]>,
    heavy: Vec<HeavyLine>,
}

#[derive(Clone, Debug)]
struct HeavyLine {
    index: usize,
    /// Column span start; `a`, `b` hold the entries of row `index` at columns span..span+len.
    span: usize,
    a: Vec<f64>,
    b: Vec<f64>,
}

impl PairOperator {
    pub fn new(a: &CsrMatrix, b: &CsrMatrix) -> Self {
        let pattern = CsrMatrix::combine(&[(1.0, a), (1.0, b)]);
        let n = a.n;
        let deg: Vec<usize> = (0..n).map(|i| pattern.row_ptr[i + 1] - pattern.row_ptr[i]).collect();
        let mean = deg.iter().sum::<usize>() as f64 / n.max(1) as f64;
        let is_heavy: Vec<bool> = deg.iter().map(|&d| d as f64 > (4.0 * mean).max(48.0)).collect();
        let mut heavy = Vec::new();
        let (mut row_ptr, mut col_idx, mut values) = (vec![0u32; n + 1], Vec::new(), Vec::new());
        for i in 0..n {
            let r = pattern.row_ptr[i]..pattern.row_ptr[i + 1];
            if is_heavy[i] {
                let cols = &pattern.col_idx[r];
                let (lo, hi) = (cols[0], *cols.last().unwrap());
                heavy.push(HeavyLine {
                    index: i,
                    span: lo,
                    a: (lo..=hi).map(|j| a.get(i, j)).collect(),
                    b: (lo..=hi).map(|j| b.get(i, j)).collect(),
                });
            } else {
                let from = col_idx.len();
                for p in r {
                    let j = pattern.col_idx[p];
                    if !is_heavy[j] {
                        col_idx.push(j as u32);
                        values.push([a.get(i, j), b.get(i, j)]);
                    }
                }
                if let Some(&last) = col_idx[from..].last() {
                    while (col_idx.len() - from) % 4 != 0 {
                        col_idx.push(last);
                        values.push([0.0, 0.0]);
                    }
                }
            }
            row_ptr[i + 1] = col_idx.len() as u32;
        }
        Self { n, row_ptr, col_idx, values, heavy }
    }

    pub fn nnz(&self) -> usize {
        self.values.len() + self.heavy.iter().map(|h| 2 * h.a.len()).sum::<usize>()
    }

    /// ya = A·x, yb = B·x (all of length n).
    pub fn mul(&self, x: &[f64], ya: &mut [f64], yb: &mut [f64]) {
        assert!(x.len() == self.n && ya.len() == self.n && yb.len() == self.n);
        for i in 0..self.n {
            let (r0, r1) = (self.row_ptr[i] as usize, self.row_ptr[i + 1] as usize);
            let (mut sa, mut sb) = ([0.0; 4], [0.0; 4]);
            let mut p = r0;
            while p < r1 {
                // SAFETY: rows hold whole chunks of 4 entries and column indices are < n.
                unsafe {
                    for q in 0..4 {
                        let xj = *x.get_unchecked(*self.col_idx.get_unchecked(p + q) as usize);
                        let v = self.values.get_unchecked(p + q);
                        sa[q] += v[0] * xj;
                        sb[q] += v[1] * xj;
                    }
                }
                p += 4;
            }
            ya[i] = (sa[0] + sa[1]) + (sa[2] + sa[3]);
            yb[i] = (sb[0] + sb[1]) + (sb[2] + sb[3]);
        }
        // Heavy columns (axpy), then heavy rows (dot) overwrite their own outputs.
        for h in &self.heavy {
            let xi = x[h.index];
            let len = h.a.len();
            for (y, v) in ya[h.span..h.span + len].iter_mut().zip(&h.a) {
                *y += v * xi;
            }
            for (y, w) in yb[h.span..h.span + len].iter_mut().zip(&h.b) {
                *y += w * xi;
            }
        }
        for h in &self.heavy {
            let xs = &x[h.span..h.span + h.a.len()];
            ya[h.index] = dot4(&h.a, xs);
            yb[h.index] = dot4(&h.b, xs);
        }
    }
}

/// Σ a_i·b_i with four independent partial sums.
#[inline(always)]
fn dot4(a: &[f64], b: &[f64]) -> f64 {
    let mut s = [0.0; 4];
    let (ac, bc) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ar, br) = (ac.remainder(), bc.remainder());
    for (x, y) in ac.zip(bc) {
        for q in 0..4 {
            s[q] += x[q] * y[q];
        }
    }
    for (x, y) in ar.iter().zip(br) {
        s[0] += x * y;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// P·A·Pᵀ = L·D·Lᵀ of a symmetric positive definite matrix. Solves work in the permuted
/// numbering on caller-provided buffers, several right-hand sides interleaved row by row.
#[derive(Clone, Debug)]
pub struct Ldlt {
    pub n: usize,
    /// `perm[k]`: original index of the k-th eliminated unknown; `inv` its inverse.
    pub perm: Vec<usize>,
    pub inv: Vec<usize>,
    /// Strictly lower part of unit L, by column (row indices < n, checked at construction).
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    l: Vec<f64>,
    d_inv: Vec<f64>,
}

impl Ldlt {
    /// Factorises with an approximate-minimum-degree ordering.
    pub fn new(a: &CsrMatrix) -> Result<Self> {
        Self::with_ordering(a, None)
    }

    /// Factorises with the cheapest of a few orderings for time stepping: AMD, and AMD with
    /// the high-degree unknowns and then also `late` (the unknowns that contact forces act on)
    /// moved to the end. The cost estimate counts a forward and a backward substitution of
    /// one vector plus the forward substitution of vectors that start at the first `late`
    /// unknown. The trailing dense block is then sorted by original index, which leaves
    /// its fill unchanged and turns the entries there into long runs.
    pub fn for_stepping(a: &CsrMatrix, late: &[usize]) -> Result<Self> {
        let n = a.n;
        let amd = Self::new(a)?;
        let degree: Vec<usize> = (0..n).map(|i| a.row_ptr[i + 1] - a.row_ptr[i]).collect();
        let mean = degree.iter().sum::<usize>() as f64 / n.max(1) as f64;
        let heavy: Vec<bool> = degree.iter().map(|&d| d as f64 > (4.0 * mean).max(32.0)).collect();
        let mut is_late = vec![false; n];
        for &i in late {
            is_late[i] = true;
        }
        let moved = |keep_last: &dyn Fn(usize) -> bool| -> Vec<usize> {
            let mut o: Vec<usize> = amd.perm.iter().copied().filter(|&i| !keep_last(i)).collect();
            o.extend(amd.perm.iter().copied().filter(|&i| keep_last(i)));
            o
        };
        let mut best = amd.clone();
        let mut best_cost = best.stepping_cost(late);
        for cand in [moved(&|i| heavy[i]), moved(&|i| heavy[i] || is_late[i])] {
            if let Ok(f) = Self::with_ordering(a, Some(&cand)) {
                let c = f.stepping_cost(late);
                if c < best_cost {
                    best = f;
                    best_cost = c;
                }
            }
        }
        // Sort the dense trailing block.
        let p = best.dense_suffix(0.9);
        if p + 1 < n {
            let mut o = best.perm.clone();
            o[p..].sort_unstable();
            if let Ok(f) = Self::with_ordering(a, Some(&o)) {
                if f.stepping_cost(late) <= best_cost {
                    best = f;
                }
            }
        }
        Ok(best)
    }

    fn stepping_cost(&self, late: &[usize]) -> usize {
        let start = late.iter().map(|&i| self.inv[i]).min().unwrap_or(self.n);
        2 * self.nnz_l() + 2 * self.nnz_l_from(start)
    }

    /// First column p such that every column k ≥ p of L holds at least `frac` of the
    /// n − 1 − k entries it could hold.
    fn dense_suffix(&self, frac: f64) -> usize {
        let mut p = self.n;
        while p > 0 {
            let k = p - 1;
            let cnt = (self.col_ptr[k + 1] - self.col_ptr[k]) as usize;
            if (cnt as f64) < frac * (self.n - 1 - k) as f64 {
                break;
            }
            p = k;
        }
        p
    }

    /// Factorises with a given elimination order (`order[k]` = original index eliminated
    /// k-th), or AMD when `None`.
    pub fn with_ordering(a: &CsrMatrix, order: Option<&[usize]>) -> Result<Self> {
        let n = a.n;
        if n == 0 {
            return Ok(Self { n, perm: vec![], inv: vec![], col_ptr: vec![0], row_idx: vec![], l: vec![], d_inv: vec![] });
        }
        // Lower triangle by columns = upper-right part of each CSR row (symmetry).
        let mut col_ptr = vec![0usize; n + 1];
        let mut row_idx = Vec::new();
        let mut vals = Vec::new();
        for j in 0..n {
            for p in a.row_ptr[j]..a.row_ptr[j + 1] {
                if a.col_idx[p] >= j {
                    row_idx.push(a.col_idx[p]);
                    vals.push(a.values[p]);
                }
            }
            col_ptr[j + 1] = row_idx.len();
        }
        let symbolic_a = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
        let a_lower = SparseColMatRef::new(symbolic_a, &vals);
        let (fwd, inv_owned);
        let ordering = match order {
            None => SymmetricOrdering::Amd,
            Some(o) => {
                fwd = o.to_vec();
                let mut inv = vec![0usize; n];
                for (k, &i) in fwd.iter().enumerate() {
                    inv[i] = k;
                }
                inv_owned = inv;
                SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&fwd, &inv_owned, n))
            }
        };
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(symbolic_a, Side::Lower, ordering, params)
            .map_err(|e| VtbError::Solver(format!("symbolic factorisation failed: {e:?}")))?;
        let mut l_val = vec![0.0f64; symbolic.len_val()];
        let scratch = symbolic.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default());
        let mut mem = MemBuffer::try_new(scratch).map_err(|_| VtbError::Solver("out of memory".into()))?;
        symbolic
            .factorize_numeric_ldlt(&mut l_val, a_lower, Side::Lower, Default::default(), Par::Seq, MemStack::new(&mut mem), Default::default())
            .map_err(|e| VtbError::Solver(format!("LDLᵀ factorisation failed: {e:?}")))?;
        let (perm, inv) = match symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (f.to_vec(), i.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let SymbolicCholeskyRaw::Simplicial(s) = symbolic.raw() else {
            return Err(VtbError::Solver("expected a simplicial factorisation".into()));
        };
        let (lp, li) = (s.col_ptr(), s.row_idx());
        let mut out_ptr = vec![0u32; n + 1];
        let mut out_row = Vec::with_capacity(li.len());
        let mut out_l = Vec::with_capacity(li.len());
        let mut d_inv = vec![0.0; n];
        // Pivots are compared with the permuted diagonal of A to detect a numerically
        // singular (unsupported) system.
        let diag = a.diagonal();
        for j in 0..n {
            for p in lp[j]..lp[j + 1] {
                let i = li[p];
                if i == j {
                    let dj = l_val[p];
                    let ajj = diag[perm[j]].abs();
                    if !(dj > 1e-13 * ajj) || !dj.is_finite() {
                        return Err(VtbError::Solver(format!(
                            "matrix is not positive definite (pivot {dj:.3e} at unknown {}, diagonal {ajj:.3e}): \
                             is every layer supported?",
                            perm[j]
                        )));
                    }
                    d_inv[j] = 1.0 / dj;
                } else {
                    assert!(i > j && i < n, "L entries lie strictly below the diagonal");
                    out_row.push(i as u32);
                    out_l.push(l_val[p]);
                }
            }
            out_ptr[j + 1] = out_row.len() as u32;
        }
        Ok(Self { n, perm, inv, col_ptr: out_ptr, row_idx: out_row, l: out_l, d_inv })
    }

    /// Number of off-diagonal entries of L.
    pub fn nnz_l(&self) -> usize {
        self.l.len()
    }

    /// Entries of L in columns `start..n` (the work of a forward substitution
    /// of a vector whose first nonzero is at `start`).
    pub fn nnz_l_from(&self, start: usize) -> usize {
        self.nnz_l() - self.col_ptr[start.min(self.n)] as usize
    }

    /// z ← L⁻¹·z for `W` interleaved right-hand sides, skipping columns before `start`
    /// (the caller knows z is zero there). `z.len()` must be `W·n`.
    #[inline]
    pub fn forward<const W: usize>(&self, z: &mut [f64], start: usize) {
        assert_eq!(z.len(), W * self.n);
        for k in start..self.n {
            let (a, b) = (self.col_ptr[k] as usize, self.col_ptr[k + 1] as usize);
            let mut zk = [0.0; W];
            zk.copy_from_slice(&z[k * W..k * W + W]);
            for p in a..b {
                // SAFETY: p < nnz (col_ptr is monotone and ends at nnz) and every row index is
                // < n (asserted at construction), so i·W + c < W·n = z.len().
                unsafe {
                    let i = *self.row_idx.get_unchecked(p) as usize;
                    let l = *self.l.get_unchecked(p);
                    for c in 0..W {
                        *z.get_unchecked_mut(i * W + c) -= l * zk[c];
                    }
                }
            }
        }
    }

    /// z ← D⁻¹·z then z ← L⁻ᵀ·z for one right-hand side (`z.len()` = n).
    #[inline]
    pub fn diag_backward(&self, z: &mut [f64]) {
        assert_eq!(z.len(), self.n);
        for (v, d) in z.iter_mut().zip(&self.d_inv) {
            *v *= d;
        }
        for k in (0..self.n).rev() {
            let (a, b) = (self.col_ptr[k] as usize, self.col_ptr[k + 1] as usize);
            let mut s = [0.0; 2];
            let mut p = a;
            // SAFETY: as in `forward`.
            unsafe {
                while p + 1 < b {
                    s[0] += *self.l.get_unchecked(p) * *z.get_unchecked(*self.row_idx.get_unchecked(p) as usize);
                    s[1] += *self.l.get_unchecked(p + 1) * *z.get_unchecked(*self.row_idx.get_unchecked(p + 1) as usize);
                    p += 2;
                }
                if p < b {
                    s[0] += *self.l.get_unchecked(p) * *z.get_unchecked(*self.row_idx.get_unchecked(p) as usize);
                }
            }
            z[k] -= s[0] + s[1];
        }
    }

    /// D⁻¹ weights (for products of forward-solved vectors).
    pub fn d_inv(&self) -> &[f64] {
        &self.d_inv
    }

    /// x = A⁻¹·b in the original numbering (allocates; for setup and tests).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut z: Vec<f64> = self.perm.iter().map(|&i| b[i]).collect();
        self.forward::<1>(&mut z, 0);
        self.diag_backward(&mut z);
        let mut x = vec![0.0; self.n];
        for (k, &i) in self.perm.iter().enumerate() {
            x[i] = z[k];
        }
        x
    }
}

#[cfg(test)]
mod tests {
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
}
