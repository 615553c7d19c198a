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
    /// `touch[k]`: one past the last row any interior column ≤ k writes (`spill`), made on
    /// first use.
    touch: std::sync::OnceLock<Vec<usize>>,
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

    fn start(&self) -> usize {
        match *self {
            Unit::Segment { k0, .. } => k0,
            Unit::Columns { from, .. } => from,
        }
    }
}

impl Ldlt {
    /// One past the last row that `forward_until(_, _, end)` writes: its interior columns
    /// before `end` scatter into rows up to there, and a window into the border rows writes
    /// them all (partial sums a caller must clear).
    pub fn spill(&self, end: usize) -> usize {
        if end == 0 {
            return 0;
        }
        if end > self.p {
            return self.n; // the border rows too
        }
        self.touch()[end.min(self.n) - 1]
    }

    /// `touch[k]`: one past the last row any interior column ≤ k writes in the forward
    /// substitution (reads in the backward one).
    fn touch(&self) -> &[usize] {
        self.touch.get_or_init(|| {
            let mut last = vec![0usize; self.n];
            for unit in &self.units {
                match *unit {
                    Unit::Segment {
                        k0,
                        len,
                        off,
                        n_off,
                        ..
                    } => {
                        let o = self.seg_off[off..off + n_off]
                            .iter()
                            .copied()
                            .max()
                            .unwrap_or(0);
                        for j in 0..len {
                            last[k0 + j] = (k0 + j + o + 1).min(self.n);
                        }
                    }
                    Unit::Columns { from, to } => {
                        for k in from..to {
                            let (a, b) = (self.col_ptr[k] as usize, self.col_ptr[k + 1] as usize);
                            last[k] = self.row_idx[a..b]
                                .iter()
                                .map(|&r| r as usize + 1)
                                .max()
                                .unwrap_or(k + 1);
                        }
                    }
                }
            }
            let mut run = 0;
            for (k, v) in last.iter_mut().enumerate() {
                run = run.max(*v).max(k + 1);
                *v = run;
            }
            last
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
}
