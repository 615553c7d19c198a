//! The factorisation in named steps: the lower triangle of A, faer's symbolic analysis
//! (simplicial, in the given order or AMD) and numeric LDLᵀ, then the entries of L sorted
//! into the parts `Ldlt` stores (interior columns, border rows, the border–border triangle,
//! D⁻¹ with the pivot check) and laid out (segments and plain columns, border-row runs).

use super::{Ldlt, Unit};
use crate::error::{Result, VtbError};
use crate::linalg::sparse::CsrMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Par, Side};

/// Shortest run of equal-pattern columns stored as a segment.
const MIN_SEGMENT: usize = 8;

/// A row of L with more than this many entries (in a trailing block of such rows) is stored
/// as a border row.
const BORDER_ROW_MIN: usize = 32;

/// The entries of L sorted into the parts `Ldlt` stores them in, before their layout.
struct Parts {
    /// Interior columns (rows < p): (row, value) each.
    cols: Vec<Vec<(usize, f64)>>,
    /// Border rows over interior columns: (column, value) each.
    brows: Vec<Vec<(usize, f64)>>,
    /// Border–border part of L, dense (nb × nb, row-major).
    lbb: Vec<f64>,
    d_inv: Vec<f64>,
}

/// A run of a border row: first column, length, value offset.
type Run = (usize, usize, usize);

impl Ldlt {
    /// Factorises with an approximate-minimum-degree ordering.
    pub fn new(a: &CsrMatrix) -> Result<Self> {
        Self::with_ordering(a, None)
    }

    /// Factorises with a given elimination order (`order[k]` = original index eliminated
    /// k-th), or AMD when `None`.
    pub fn with_ordering(a: &CsrMatrix, order: Option<&[usize]>) -> Result<Self> {
        let n = a.n;
        if n == 0 {
            return Ok(Self::empty());
        }
        let (symbolic, l_val) = factorize(a, order)?;
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
        let pb = border_start(li, n);
        let parts = sort_entries(a, &perm, (lp, li, &l_val), pb)?;
        let (col_ptr, row_idx, l) = interior_columns(&parts.cols);
        let (units, seg_off, seg_val) = units(&parts.cols);
        let (brow_ptr, brun, bval) = border_runs(&parts.brows);
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
            lbb: parts.lbb,
            d_inv: parts.d_inv,
            nnz: li.len() - n,
            touch: Default::default(),
        })
    }

    /// The factor of a 0 × 0 matrix.
    fn empty() -> Self {
        Self {
            n: 0,
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
            touch: Default::default(),
        }
    }
}

/// Symbolic analysis and numeric LDLᵀ of `a` (n ≥ 1) by faer, simplicial: the symbolic
/// factor (order, pattern of L) and L's values with D on the diagonal.
fn factorize(
    a: &CsrMatrix,
    order: Option<&[usize]>,
) -> Result<(SymbolicCholesky<usize>, Vec<f64>)> {
    let n = a.n;
    let (col_ptr, row_idx, vals) = lower_triangle(a);
    let symbolic_a = SymbolicSparseColMatRef::new_checked(n, n, &col_ptr, None, &row_idx);
    let a_lower = SparseColMatRef::new(symbolic_a, &vals);
    let symbolic = analyse(symbolic_a, order)?;
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
    Ok((symbolic, l_val))
}

/// Lower triangle of `a` by columns (column pointers, row indices, values).
fn lower_triangle(a: &CsrMatrix) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
    let n = a.n;
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
    (col_ptr, row_idx, vals)
}

/// Symbolic analysis of the lower triangle's pattern: simplicial, in `order` or AMD.
fn analyse(
    symbolic_a: SymbolicSparseColMatRef<'_, usize>,
    order: Option<&[usize]>,
) -> Result<SymbolicCholesky<usize>> {
    let n = symbolic_a.nrows();
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
    factorize_symbolic_cholesky(symbolic_a, Side::Lower, ordering, params)
        .map_err(|e| VtbError::Solver(format!("symbolic factorisation failed: {e:?}")))
}

/// Border: the longest trailing block of rows of L that each have many entries; returns its
/// first row.
fn border_start(li: &[usize], n: usize) -> usize {
    let mut row_count = vec![0usize; n];
    for &i in li {
        row_count[i] += 1;
    }
    let mut pb = n;
    while pb > 0 && row_count[pb - 1] > BORDER_ROW_MIN {
        pb -= 1;
    }
    pb
}

/// Sorts the entries of the simplicial L (`lp`, `li`, `l_val`: by column, the diagonal
/// holding D) into interior columns, border rows (from row `pb` on), the border–border
/// triangle and D⁻¹, checking each pivot.
fn sort_entries(
    a: &CsrMatrix,
    perm: &[usize],
    (lp, li, l_val): (&[usize], &[usize], &[f64]),
    pb: usize,
) -> Result<Parts> {
    let n = a.n;
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
    Ok(Parts {
        cols,
        brows,
        lbb,
        d_inv,
    })
}

/// The interior columns in compressed form (column pointers, row indices, values).
fn interior_columns(cols: &[Vec<(usize, f64)>]) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
    let mut col_ptr = vec![0u32; cols.len() + 1];
    let (mut row_idx, mut l) = (Vec::new(), Vec::new());
    for (j, c) in cols.iter().enumerate() {
        row_idx.extend(c.iter().map(|e| e.0 as u32));
        l.extend(c.iter().map(|e| e.1));
        col_ptr[j + 1] = row_idx.len() as u32;
    }
    (col_ptr, row_idx, l)
}

/// The interior columns grouped into units: runs of at least `MIN_SEGMENT` columns with
/// entries at the same row offsets become segments (with their offsets and values), the
/// rest plain columns.
fn units(cols: &[Vec<(usize, f64)>]) -> (Vec<Unit>, Vec<usize>, Vec<f64>) {
    let pb = cols.len();
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
    (units, seg_off, seg_val)
}

/// The border rows as runs of consecutive columns: row pointers into the runs, the runs and
/// their values.
fn border_runs(brows: &[Vec<(usize, f64)>]) -> (Vec<usize>, Vec<Run>, Vec<f64>) {
    let (mut brow_ptr, mut brun, mut bval) = (vec![0usize], Vec::new(), Vec::new());
    for row in brows {
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
    (brow_ptr, brun, bval)
}
