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
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholeskyRaw, SymmetricOrdering, factorize_symbolic_cholesky,
};
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

/// A diagonal segment of light entries: first row i, length, offset j − i, value offset.
type Segment = (usize, usize, usize, usize);
/// A heavy row: its index and its runs (first column, length, value offset).
type HeavyRow = (usize, Vec<(usize, usize, usize)>);
/// The order key of an unknown: (heavy, late, its component's size, its rank in the component,
/// the component).
type GroupKey = (bool, bool, usize, usize, usize);

/// Two symmetric sparse matrices A, B on the union of their patterns, prepared for the
/// repeated products y_a = A·x, y_b = B·x in one pass: the diagonals as vectors, the light
/// off-diagonal entries once each (i < j) grouped into diagonal segments (runs of consecutive
/// i at one offset j − i, as the per-mode chains of a modal basis give in slot-major order)
/// applied to both (i, j) and (j, i), and the few heavy rows (the boundary functions of a
/// modal basis couple to every sine) as runs of their nonzeros, where one pass serves the
/// heavy row (dot product) and, by symmetry, the heavy column (axpy). No per-row loops over
/// short rows.
#[derive(Clone, Debug)]
pub struct SymOperator {
    n: usize,
    diag: [Vec<f64>; 2],
    /// Light–light off-diagonal entries (i, i + d) as segments (first i, length, offset d,
    /// value offset).
    segs: Vec<Segment>,
    seg_vals: [Vec<f64>; 2],
    /// Heavy rows: index, runs (first column, length, value offset).
    heavy: Vec<HeavyRow>,
    heavy_vals: [Vec<f64>; 2],
}

impl SymOperator {
    /// Builds the operator for P·A·Pᵀ and P·B·Pᵀ, `perm[k]` being the original index of
    /// unknown k.
    pub fn new(mats: &[&CsrMatrix; 2], perm: &[usize]) -> Self {
        let pattern = CsrMatrix::combine(&[(1.0, mats[0]), (1.0, mats[1])]);
        let n = pattern.n;
        let mut inv = vec![0usize; n];
        for (k, &i) in perm.iter().enumerate() {
            inv[i] = k;
        }
        let deg: Vec<usize> = (0..n)
            .map(|i| pattern.row_ptr[perm[i] + 1] - pattern.row_ptr[perm[i]])
            .collect();
        let mean = deg.iter().sum::<usize>() as f64 / n.max(1) as f64;
        let is_heavy: Vec<bool> = deg
            .iter()
            .map(|&d| d as f64 > (4.0 * mean).max(48.0))
            .collect();
        let mut diag = [vec![0.0; n], vec![0.0; n]];
        let mut pairs: Vec<(usize, usize, [f64; 2])> = Vec::new();
        let (mut heavy, mut heavy_vals) = (Vec::new(), [Vec::new(), Vec::new()]);
        let mut row: Vec<(usize, [f64; 2])> = Vec::new();
        for k in 0..n {
            let i = perm[k];
            row.clear();
            row.extend((pattern.row_ptr[i]..pattern.row_ptr[i + 1]).map(|p| {
                let j = pattern.col_idx[p];
                (inv[j], [mats[0].get(i, j), mats[1].get(i, j)])
            }));
            row.sort_unstable_by_key(|e| e.0);
            if is_heavy[k] {
                // A heavy row owns every entry of its row; light rows skip heavy columns.
                let mut runs = Vec::new();
                let mut q = 0;
                while q < row.len() {
                    let mut e = q + 1;
                    while e < row.len() && row[e].0 == row[e - 1].0 + 1 {
                        e += 1;
                    }
                    runs.push((row[q].0, e - q, heavy_vals[0].len()));
                    for m in 0..2 {
                        heavy_vals[m].extend(row[q..e].iter().map(|x| x.1[m]));
                    }
                    q = e;
                }
                heavy.push((k, runs));
            } else {
                for &(j, v) in &row {
                    if j == k {
                        diag[0][k] = v[0];
                        diag[1][k] = v[1];
                    } else if j > k && !is_heavy[j] {
                        pairs.push((k, j - k, v));
                    }
                }
            }
        }
        pairs.sort_unstable_by_key(|&(i, d, _)| (d, i));
        let (mut segs, mut seg_vals) = (Vec::new(), [Vec::new(), Vec::new()]);
        let mut q = 0;
        while q < pairs.len() {
            let (i0, d, _) = pairs[q];
            let mut e = q + 1;
            while e < pairs.len() && pairs[e].1 == d && pairs[e].0 == pairs[e - 1].0 + 1 {
                e += 1;
            }
            segs.push((i0, e - q, d, seg_vals[0].len()));
            for m in 0..2 {
                seg_vals[m].extend(pairs[q..e].iter().map(|p| p.2[m]));
            }
            q = e;
        }
        Self {
            n,
            diag,
            segs,
            seg_vals,
            heavy,
            heavy_vals,
        }
    }

    /// Layout summary (diagnostics).
    pub fn describe(&self) -> String {
        format!(
            "{} segments over {} entries, {} heavy rows with {} runs over {} entries",
            self.segs.len(),
            self.seg_vals[0].len(),
            self.heavy.len(),
            self.heavy.iter().map(|h| h.1.len()).sum::<usize>(),
            self.heavy_vals[0].len()
        )
    }

    /// ya = A·x, yb = B·x for `W` interleaved vectors (each lane with the operations of a
    /// single vector).
    pub fn mul2<const W: usize>(&self, x: &[f64], ya: &mut [f64], yb: &mut [f64]) {
        assert!(x.len() == W * self.n && ya.len() == W * self.n && yb.len() == W * self.n);
        crate::wide!(<W> (this: &SymOperator = self, x: &[f64] = x, ya: &mut [f64] = ya, yb: &mut [f64] = yb) {
            this.mul2_kernel::<W>(x, ya, yb)
        });
    }

    #[inline(always)]
    fn mul2_kernel<const W: usize>(&self, x: &[f64], ya: &mut [f64], yb: &mut [f64]) {
        for ((((a, b), xv), da), db) in ya
            .chunks_exact_mut(W)
            .zip(yb.chunks_exact_mut(W))
            .zip(x.chunks_exact(W))
            .zip(&self.diag[0])
            .zip(&self.diag[1])
        {
            for c in 0..W {
                a[c] = da * xv[c];
                b[c] = db * xv[c];
            }
        }
        // Entry (i, i + d) updates rows i and i + d: disjoint lane blocks (d ≥ 1).
        let pair = |y: &mut [f64], lo: usize, hi: usize, v: f64| {
            let (a, b) = y.split_at_mut(hi * W);
            let (ylo, yhi) = (&mut a[lo * W..lo * W + W], &mut b[..W]);
            let (xlo, xhi) = (&x[lo * W..lo * W + W], &x[hi * W..hi * W + W]);
            for c in 0..W {
                ylo[c] = v.mul_add(xhi[c], ylo[c]);
                yhi[c] = v.mul_add(xlo[c], yhi[c]);
            }
        };
        for &(i0, len, d, o) in &self.segs {
            let (va, vb) = (&self.seg_vals[0][o..o + len], &self.seg_vals[1][o..o + len]);
            for q in 0..len {
                pair(ya, i0 + q, i0 + d + q, va[q]);
                pair(yb, i0 + q, i0 + d + q, vb[q]);
            }
        }
        // Heavy rows as in `mul2`: column axpys, then their own rows set from the dots.
        let mut own_fixed = [[[0.0; W]; 2]; 64];
        let mut own_heap = Vec::new();
        let own = if self.heavy.len() <= 64 {
            &mut own_fixed[..self.heavy.len()]
        } else {
            own_heap.resize(self.heavy.len(), [[0.0; W]; 2]);
            &mut own_heap[..]
        };
        for ((i, runs), o) in self.heavy.iter().zip(own.iter_mut()) {
            let xi: [f64; W] = std::array::from_fn(|c| x[i * W + c]);
            for &(s, l, off) in runs {
                let (va, vb) = (
                    &self.heavy_vals[0][off..off + l],
                    &self.heavy_vals[1][off..off + l],
                );
                // One pass: the column's axpys and the row's dots (partial sums by entry
                // index, as in `simd::dot_lanes`).
                const P: usize = crate::linalg::simd::PARTIAL_SUMS;
                let mut acc = [[[0.0; W]; P]; 2];
                let rows = ya[s * W..(s + l) * W]
                    .chunks_exact_mut(W)
                    .zip(yb[s * W..(s + l) * W].chunks_exact_mut(W))
                    .zip(x[s * W..(s + l) * W].chunks_exact(W));
                for (q, ((ra, rb), xv)) in rows.enumerate() {
                    let (a, b) = (va[q], vb[q]);
                    for c in 0..W {
                        ra[c] = a.mul_add(xi[c], ra[c]);
                        rb[c] = b.mul_add(xi[c], rb[c]);
                        acc[0][q % P][c] = a.mul_add(xv[c], acc[0][q % P][c]);
                        acc[1][q % P][c] = b.mul_add(xv[c], acc[1][q % P][c]);
                    }
                }
                for c in 0..W {
                    for m in 0..2 {
                        let a = &acc[m];
                        o[m][c] += ((a[0][c] + a[1][c]) + (a[2][c] + a[3][c]))
                            + ((a[4][c] + a[5][c]) + (a[6][c] + a[7][c]));
                    }
                }
            }
        }
        for ((i, _), o) in self.heavy.iter().zip(own.iter()) {
            for c in 0..W {
                ya[i * W + c] = o[0][c];
                yb[i * W + c] = o[1][c];
            }
        }
    }
}

/// Reorders `order` so that, after the heavy unknowns are removed, the disjoint components
/// of the rest (per-mode chains of a modal basis) are laid out slot by slot: the first
/// unknown of every component, then the second, …, with the `late` ones after all others.
/// Each component keeps its internal order, so the fill of the factor is unchanged while the
/// heavy rows of L become a few long runs.
fn slot_major(a: &CsrMatrix, order: &[usize], heavy: &[bool], late: &[bool]) -> Vec<usize> {
    let n = a.n;
    let mut comp = vec![usize::MAX; n];
    let mut ncomp = 0;
    for s in 0..n {
        if heavy[s] || comp[s] != usize::MAX {
            continue;
        }
        let mut stack = vec![s];
        comp[s] = ncomp;
        while let Some(i) = stack.pop() {
            for p in a.row_ptr[i]..a.row_ptr[i + 1] {
                let j = a.col_idx[p];
                if !heavy[j] && comp[j] == usize::MAX {
                    comp[j] = ncomp;
                    stack.push(j);
                }
            }
        }
        ncomp += 1;
    }
    let mut size = vec![0usize; ncomp];
    for i in 0..n {
        if !heavy[i] {
            size[comp[i]] += 1;
        }
    }
    let mut rank_in = vec![0usize; ncomp];
    // Components of equal size share their offset pattern, so they are grouped.
    let mut keyed: Vec<(GroupKey, usize)> = order
        .iter()
        .map(|&i| {
            if heavy[i] {
                ((true, false, 0, 0, 0), i)
            } else {
                let c = comp[i];
                let r = rank_in[c];
                rank_in[c] += 1;
                ((false, late[i], size[c], r, c), i)
            }
        })
        .collect();
    // Stable: heavy unknowns keep their relative order at the end.
    keyed.sort_by_key(|e| e.0);
    keyed.into_iter().map(|e| e.1).collect()
}

/// P·A·Pᵀ = L·D·Lᵀ of a symmetric positive definite matrix. Solves work in the permuted
/// numbering on caller-provided buffers, several right-hand sides interleaved row by row.
///
/// L is stored in three parts suited to the structure of the time-stepping matrices:
/// * interior rows by column (short columns: the per-mode chains of a modal basis);
/// * *border rows* (the high-degree unknowns eliminated last) as runs of consecutive
///   columns, applied as dot products in the forward and axpys in the backward substitution,
///   which avoids long read–modify–write chains on the same entries;
/// * the dense border–border triangle.
#[derive(Clone, Debug)]
pub struct Ldlt {
    pub n: usize,
    /// `perm[k]`: original index of the k-th eliminated unknown; `inv` its inverse.
    pub perm: Vec<usize>,
    pub inv: Vec<usize>,
    /// Rows `p..n` are border rows.
    p: usize,
    /// Interior part of strictly lower L by column (rows < p; indices checked at
    /// construction).
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    l: Vec<f64>,
    /// The interior columns in order, grouped: runs of at least `MIN_SEGMENT` consecutive
    /// columns with entries at the same row offsets (the per-mode chains of a modal basis in
    /// slot-major order) are segments applied as whole-vector operations; the rest are
    /// plain columns of the arrays above.
    units: Vec<Unit>,
    /// Row offsets of the segments and their values (per segment offset-major, `len` each).
    seg_off: Vec<usize>,
    seg_val: Vec<f64>,
    /// Border rows over interior columns: row g owns runs `brow_ptr[g]..brow_ptr[g+1]`,
    /// each (first column, length, value offset into `bval`).
    brow_ptr: Vec<usize>,
    brun: Vec<(usize, usize, usize)>,
    bval: Vec<f64>,
    /// Border–border part of L, dense lower triangle (nb × nb, row-major).
    lbb: Vec<f64>,
    d_inv: Vec<f64>,
    nnz: usize,
}

/// A group of interior columns of L.
#[derive(Clone, Copy, Debug)]
enum Unit {
    /// Columns k0..k0+len with entries at rows k + seg_off[off..off + n_off] (each offset
    /// ≥ len, so the segment's own unknowns are final before it is applied); values at
    /// seg_val[val + q·len..].
    Segment {
        k0: usize,
        len: usize,
        off: usize,
        n_off: usize,
        val: usize,
    },
    /// Plain columns from..to.
    Columns { from: usize, to: usize },
}

impl Unit {
    fn end(&self) -> usize {
        match *self {
            Unit::Segment { k0, len, .. } => k0 + len,
            Unit::Columns { to, .. } => to,
        }
    }
}

/// Shortest run of equal-pattern columns stored as a segment.
const MIN_SEGMENT: usize = 8;

/// A row of L with more than this many entries (in a trailing block of such rows) is stored
/// as a border row.
const BORDER_ROW_MIN: usize = 32;

impl Ldlt {
    /// Factorises with an approximate-minimum-degree ordering.
    pub fn new(a: &CsrMatrix) -> Result<Self> {
        Self::with_ordering(a, None)
    }

    /// Factorises with the cheapest of a few orderings for time stepping: AMD; AMD with the
    /// high-degree unknowns moved to the end; the same with `late` (the unknowns contact
    /// forces act on) also moved late; and slot-major versions of these (see `slot_major`).
    /// The cost estimate (`stepping_cost`) is deterministic, so the choice is reproducible.
    pub fn for_stepping(a: &CsrMatrix, late: &[usize]) -> Result<Self> {
        let n = a.n;
        let amd = Self::new(a)?;
        let degree: Vec<usize> = (0..n).map(|i| a.row_ptr[i + 1] - a.row_ptr[i]).collect();
        let mut sorted = degree.clone();
        sorted.sort_unstable();
        let median = sorted[n / 2];
        let mut is_late = vec![false; n];
        for &i in late {
            is_late[i] = true;
        }
        let moved = |keep_last: &dyn Fn(usize) -> bool| -> Vec<usize> {
            let mut o: Vec<usize> = amd
                .perm
                .iter()
                .copied()
                .filter(|&i| !keep_last(i))
                .collect();
            o.extend(amd.perm.iter().copied().filter(|&i| keep_last(i)));
            o
        };
        let mut best = amd.clone();
        let mut best_cost = best.stepping_cost(late);
        // "Heavy" at two levels: only the very dense rows, or every row well above the median
        // (e.g. girder sines coupled to each other by the piers).
        for factor in [8, 2] {
            let heavy: Vec<bool> = degree
                .iter()
                .map(|&d| d > (factor * median).max(32))
                .collect();
            for cand in [moved(&|i| heavy[i]), moved(&|i| heavy[i] || is_late[i])] {
                for order in [cand.clone(), slot_major(a, &cand, &heavy, &is_late)] {
                    if let Ok(f) = Self::with_ordering(a, Some(&order)) {
                        let c = f.stepping_cost(late);
                        if c < best_cost {
                            best = f;
                            best_cost = c;
                        }
                    }
                }
            }
        }
        Ok(best)
    }

    /// Estimated work of one step: a forward and a backward substitution of one vector plus
    /// the forward substitution of four port vectors from the first `late` unknown on:
    /// interior entries cost 2, interior columns 4, border runs 8 plus their entries.
    fn stepping_cost(&self, late: &[usize]) -> usize {
        let start = late.iter().map(|&i| self.inv[i]).min().unwrap_or(self.n);
        let seg_cost = |from: usize| -> usize {
            2 * (self.l.len() - self.col_ptr[from.min(self.p)] as usize)
                + 4 * (self.p - from.min(self.p))
        };
        let border: usize =
            self.brun.iter().map(|&(_, l, _)| l + 8).sum::<usize>() + (self.n - self.p).pow(2) / 2;
        let ports: usize = self
            .brun
            .iter()
            .filter(|r| r.0 + r.1 > start)
            .map(|&(s, l, _)| 8 + (s + l - s.max(start)))
            .sum();
        2 * (seg_cost(0) + border) + 4 * (seg_cost(start) + ports)
    }

    /// Factorises with a given elimination order (`order[k]` = original index eliminated
    /// k-th), or AMD when `None`.
    pub fn with_ordering(a: &CsrMatrix, order: Option<&[usize]>) -> Result<Self> {
        let n = a.n;
        if n == 0 {
            return Ok(Self {
                n,
                perm: vec![],
                inv: vec![],
                p: 0,
                col_ptr: vec![0],
                row_idx: vec![],
                l: vec![],
                units: vec![],
                seg_off: vec![],
                seg_val: vec![],
                brow_ptr: vec![0],
                brun: vec![],
                bval: vec![],
                lbb: vec![],
                d_inv: vec![],
                nnz: 0,
            });
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
        let mut mem =
            MemBuffer::try_new(scratch).map_err(|_| VtbError::Solver("out of memory".into()))?;
        symbolic
            .factorize_numeric_ldlt(
                &mut l_val,
                a_lower,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .map_err(|e| VtbError::Solver(format!("LDLᵀ factorisation failed: {e:?}")))?;
        let (perm, inv) = match symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (f.to_vec(), i.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let SymbolicCholeskyRaw::Simplicial(s) = symbolic.raw() else {
            return Err(VtbError::Solver(
                "expected a simplicial factorisation".into(),
            ));
        };
        let (lp, li) = (s.col_ptr(), s.row_idx());
        // Border: the longest trailing block of rows that each have many entries.
        let mut row_count = vec![0usize; n];
        for &i in li {
            row_count[i] += 1;
        }
        let mut pb = n;
        while pb > 0 && row_count[pb - 1] > BORDER_ROW_MIN {
            pb -= 1;
        }
        let nb = n - pb;
        let mut brows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); nb];
        let mut lbb = vec![0.0; nb * nb];
        let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); pb];
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
                } else if i < pb {
                    cols[j].push((i, l_val[p]));
                } else if j < pb {
                    brows[i - pb].push((j, l_val[p]));
                } else {
                    lbb[(i - pb) * nb + (j - pb)] = l_val[p];
                }
            }
        }
        let mut col_ptr = vec![0u32; pb + 1];
        let (mut row_idx, mut l) = (Vec::new(), Vec::new());
        for (j, c) in cols.iter().enumerate() {
            row_idx.extend(c.iter().map(|e| e.0 as u32));
            l.extend(c.iter().map(|e| e.1));
            col_ptr[j + 1] = row_idx.len() as u32;
        }
        let (mut units, mut seg_off, mut seg_val) = (Vec::new(), Vec::new(), Vec::new());
        let offsets = |k: usize| cols[k].iter().map(move |e| e.0 - k);
        let mut k = 0;
        while k < pb {
            let min_off = offsets(k).min().unwrap_or(usize::MAX);
            let mut len = 1;
            while k + len < pb && len < min_off && offsets(k + len).eq(offsets(k)) {
                len += 1;
            }
            if len >= MIN_SEGMENT && !cols[k].is_empty() {
                let (off, val) = (seg_off.len(), seg_val.len());
                seg_off.extend(offsets(k));
                for q in 0..cols[k].len() {
                    seg_val.extend((k..k + len).map(|c| cols[c][q].1));
                }
                units.push(Unit::Segment {
                    k0: k,
                    len,
                    off,
                    n_off: cols[k].len(),
                    val,
                });
            } else {
                match units.last_mut() {
                    Some(Unit::Columns { to, .. }) if *to == k => *to = k + len,
                    _ => units.push(Unit::Columns {
                        from: k,
                        to: k + len,
                    }),
                }
            }
            k += len;
        }
        let (mut brow_ptr, mut brun, mut bval) = (vec![0usize], Vec::new(), Vec::new());
        for row in &brows {
            let mut q = 0;
            while q < row.len() {
                let mut e = q + 1;
                while e < row.len() && row[e].0 == row[e - 1].0 + 1 {
                    e += 1;
                }
                brun.push((row[q].0, e - q, bval.len()));
                bval.extend(row[q..e].iter().map(|x| x.1));
                q = e;
            }
            brow_ptr.push(brun.len());
        }
        Ok(Self {
            n,
            perm,
            inv,
            p: pb,
            col_ptr,
            row_idx,
            l,
            units,
            seg_off,
            seg_val,
            brow_ptr,
            brun,
            bval,
            lbb,
            d_inv,
            nnz: li.len() - n,
        })
    }

    /// Number of off-diagonal entries of L.
    pub fn nnz_l(&self) -> usize {
        self.nnz
    }

    /// Number of border rows, border-row runs, interior segments and plain interior columns.
    pub fn layout(&self) -> (usize, usize, usize, usize) {
        let segs = self
            .units
            .iter()
            .filter(|u| matches!(u, Unit::Segment { .. }))
            .count();
        let plain = self
            .units
            .iter()
            .map(|u| {
                if let Unit::Columns { from, to } = u {
                    to - from
                } else {
                    0
                }
            })
            .sum();
        (self.n - self.p, self.brun.len(), segs, plain)
    }

    /// z ← L⁻¹·z for `W` interleaved right-hand sides, skipping columns before `start`
    /// (the caller knows z is zero there). `z.len()` must be `W·n`. Every lane does the
    /// operations of a single right-hand side (`simd::dot_lanes`).
    #[inline]
    pub fn forward<const W: usize>(&self, z: &mut [f64], start: usize) {
        assert_eq!(z.len(), W * self.n);
        crate::wide!(<W> (this: &Ldlt = self, z: &mut [f64] = z, start: usize = start) {
            this.forward_kernel::<W>(z, start)
        });
    }

    #[inline(always)]
    fn forward_kernel<const W: usize>(&self, z: &mut [f64], start: usize) {
        for unit in &self.units {
            if unit.end() <= start {
                continue;
            }
            match *unit {
                Unit::Segment {
                    k0,
                    len,
                    off,
                    n_off,
                    val,
                } => {
                    for q in 0..n_off {
                        let o = self.seg_off[off + q];
                        let vals = &self.seg_val[val + q * len..val + (q + 1) * len];
                        // Rows k0+o.. lie beyond the segment's own columns (o ≥ len).
                        let (src, dst) = z.split_at_mut((k0 + o) * W);
                        let (src, dst) = (&src[k0 * W..(k0 + len) * W], &mut dst[..len * W]);
                        for j in 0..len {
                            for c in 0..W {
                                dst[j * W + c] = (-vals[j]).mul_add(src[j * W + c], dst[j * W + c]);
                            }
                        }
                    }
                }
                Unit::Columns { from, to } => {
                    for k in from.max(start)..to {
                        let (a, b) = (self.col_ptr[k] as usize, self.col_ptr[k + 1] as usize);
                        let mut zk = [0.0; W];
                        zk.copy_from_slice(&z[k * W..k * W + W]);
                        for p in a..b {
                            // SAFETY: p < nnz (col_ptr is monotone and ends at nnz) and every
                            // row index is < n (asserted at construction), so i·W + c < W·n.
                            unsafe {
                                let i = *self.row_idx.get_unchecked(p) as usize;
                                let l = *self.l.get_unchecked(p);
                                for c in 0..W {
                                    let zi = z.get_unchecked_mut(i * W + c);
                                    *zi = (-l).mul_add(zk[c], *zi);
                                }
                            }
                        }
                    }
                }
            }
        }
        // Border rows as dot products over their runs, then the dense border triangle.
        let (pb, nb) = (self.p, self.n - self.p);
        for g in 0..nb {
            let mut acc = [0.0; W];
            for &(s, l, o) in &self.brun[self.brow_ptr[g]..self.brow_ptr[g + 1]] {
                if s + l <= start {
                    continue;
                }
                let skip = start.saturating_sub(s);
                let d = crate::linalg::simd::dot_lanes::<W>(
                    &self.bval[o + skip..o + l],
                    &z[(s + skip) * W..(s + l) * W],
                );
                for c in 0..W {
                    acc[c] += d[c];
                }
            }
            for (h, v) in self.lbb[g * nb..g * nb + g].iter().enumerate() {
                for c in 0..W {
                    acc[c] = v.mul_add(z[(pb + h) * W + c], acc[c]);
                }
            }
            for c in 0..W {
                z[(pb + g) * W + c] -= acc[c];
            }
        }
    }

    /// z ← D⁻¹·z then z ← L⁻ᵀ·z for `W` interleaved right-hand sides (`z.len()` = W·n), each
    /// lane with the operations of a single one.
    #[inline]
    pub fn diag_backward<const W: usize>(&self, z: &mut [f64]) {
        assert_eq!(z.len(), W * self.n);
        crate::wide!(<W> (this: &Ldlt = self, z: &mut [f64] = z) { this.diag_backward_kernel::<W>(z) });
    }

    #[inline(always)]
    fn diag_backward_kernel<const W: usize>(&self, z: &mut [f64]) {
        for (v, d) in z.chunks_exact_mut(W).zip(&self.d_inv) {
            for x in v {
                *x *= d;
            }
        }
        let (pb, nb) = (self.p, self.n - self.p);
        for g in (0..nb).rev() {
            let mut s = [0.0; W];
            for h in g + 1..nb {
                let l = self.lbb[h * nb + g];
                for c in 0..W {
                    s[c] = l.mul_add(z[(pb + h) * W + c], s[c]);
                }
            }
            for c in 0..W {
                z[(pb + g) * W + c] -= s[c];
            }
        }
        let (zi, zb) = z.split_at_mut(pb * W);
        for (g, v) in zb.chunks_exact(W).enumerate() {
            let minus: [f64; W] = std::array::from_fn(|c| -v[c]);
            for &(s, l, o) in &self.brun[self.brow_ptr[g]..self.brow_ptr[g + 1]] {
                crate::linalg::simd::axpy_lanes::<W>(
                    &mut zi[s * W..],
                    &self.bval[o..o + l],
                    &minus,
                );
            }
        }
        for unit in self.units.iter().rev() {
            match *unit {
                Unit::Segment {
                    k0,
                    len,
                    off,
                    n_off,
                    val,
                } => {
                    for q in 0..n_off {
                        let o = self.seg_off[off + q];
                        let vals = &self.seg_val[val + q * len..val + (q + 1) * len];
                        let (dst, src) = zi.split_at_mut((k0 + o) * W);
                        let (dst, src) = (&mut dst[k0 * W..(k0 + len) * W], &src[..len * W]);
                        for j in 0..len {
                            for c in 0..W {
                                dst[j * W + c] = (-vals[j]).mul_add(src[j * W + c], dst[j * W + c]);
                            }
                        }
                    }
                }
                Unit::Columns { from, to } => {
                    for k in (from..to).rev() {
                        let (a, b) = (self.col_ptr[k] as usize, self.col_ptr[k + 1] as usize);
                        // Two partial sums (even and odd entries) halve the latency chain.
                        let mut s = [[0.0; W]; 2];
                        for p in a..b {
                            // SAFETY: as in `forward`; interior row indices are < zi.len()/W.
                            unsafe {
                                let i = *self.row_idx.get_unchecked(p) as usize;
                                let l = *self.l.get_unchecked(p);
                                for c in 0..W {
                                    let q = &mut s[(p - a) & 1][c];
                                    *q = l.mul_add(*zi.get_unchecked(i * W + c), *q);
                                }
                            }
                        }
                        for c in 0..W {
                            zi[k * W + c] -= s[0][c] + s[1][c];
                        }
                    }
                }
            }
        }
    }

    /// D⁻¹ weights (for products of forward-solved vectors).
    pub fn d_inv(&self) -> &[f64] {
        &self.d_inv
    }

    /// B ← A⁻¹·B for the m columns of a row-major n × m block, eight columns at a time as
    /// interleaved lanes of the forward and backward passes, on `threads` threads (column
    /// groups split between them). For setup work with many right-hand sides (the synthesis's
    /// residual: a column per rail DOF).
    pub fn solve_columns(&self, b: &mut [f64], m: usize, threads: usize) {
        const W: usize = 8;
        let n = self.n;
        assert_eq!(b.len(), n * m, "an n × m block");
        let groups = m.div_ceil(W);
        let per = groups.div_ceil(threads.max(1)).max(1);
        // Each thread solves whole groups of columns into its own block, copied back after.
        let cols: Vec<(usize, usize)> = (0..groups)
            .step_by(per)
            .map(|g| (g * W, ((g + per) * W).min(m)))
            .collect();
        let results: Vec<Vec<f64>> = std::thread::scope(|s| {
            let handles: Vec<_> = cols
                .iter()
                .map(|&(c0, c1)| {
                    let b = &*b;
                    s.spawn(move || {
                        let mut out = vec![0.0; n * (c1 - c0)];
                        let mut z = vec![0.0; W * n];
                        for g0 in (c0..c1).step_by(W) {
                            let w = W.min(c1 - g0);
                            for (k, &i) in self.perm.iter().enumerate() {
                                for c in 0..W {
                                    z[k * W + c] = if c < w { b[i * m + g0 + c] } else { 0.0 };
                                }
                            }
                            self.forward::<W>(&mut z, 0);
                            self.diag_backward::<W>(&mut z);
                            for (k, &i) in self.perm.iter().enumerate() {
                                for c in 0..w {
                                    out[i * (c1 - c0) + g0 - c0 + c] = z[k * W + c];
                                }
                            }
                        }
                        out
                    })
                })
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("a solve thread"))
                .collect()
        });
        for (&(c0, c1), out) in cols.iter().zip(results) {
            for i in 0..n {
                b[i * m + c0..i * m + c1].copy_from_slice(&out[i * (c1 - c0)..(i + 1) * (c1 - c0)]);
            }
        }
    }

    /// x = A⁻¹·b in the original numbering (allocates; for setup and tests).
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let mut z: Vec<f64> = self.perm.iter().map(|&i| b[i]).collect();
        self.forward::<1>(&mut z, 0);
        self.diag_backward::<1>(&mut z);
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
}
