//! The LDLᵀ factor of the stepping matrices and the layout of L it is stored in.
//!
//! - `mod.rs` (this file): [`Ldlt`] and its layout;
//! - `factor`: the factorisation in named steps (faer's symbolic analysis and numeric LDLᵀ,
//!   then the entries of L sorted into the layout);
//! - `ordering`: the elimination orders tried for time stepping and the cost that picks one;
//! - `solve`: the forward and backward substitutions, single and many right-hand sides.

mod factor;
mod ordering;
mod solve;

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

impl Ldlt {
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
}
