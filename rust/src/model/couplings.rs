//! Spring–dashpot connections (docs/model.md §2, article Eq. 23–26): discrete (fasteners, piers,
//! bearings) and continuous (CA mortar, support layer, Winkler foundation), between two layers
//! or between a layer and the ground.
//!
//! A connection at x between layers a (upper) and b (lower) acts on the relative displacement
//! u_a(x) − u_b(x) = nᵀQ with n = [.., N_a(x), .., −N_b(x), ..], so it adds k·n·nᵀ to K (and
//! c·n·nᵀ to C); a continuous one adds ∫k·n·nᵀ dx.

use crate::linalg::sparse::Assembler;
use crate::model::basis::Shape;
use crate::model::layers::{Derivative, Layer, gram_blocks_over};

/// Adds `w`·∫ n·nᵀ dx over `range` of a continuous connection (b = None: to the ground).
pub fn add_continuous(
    asm: &mut Assembler,
    a: &Layer,
    b: Option<&Layer>,
    w: f64,
    range: (f64, f64),
) {
    if w == 0.0 {
        return;
    }
    let mut pairs: Vec<(&Layer, &Layer, f64)> = vec![(a, a, w)];
    if let Some(b) = b {
        pairs.push((b, b, w));
        pairs.push((a, b, -w));
    }
    for (p, q, s) in pairs {
        for blk in gram_blocks_over(p, q, Derivative::Value, range) {
            let nc = blk.cols.len();
            for (r, &i) in blk.rows.iter().enumerate() {
                for (c, &j) in blk.cols.iter().enumerate() {
                    let v = s * blk.data[r * nc + c];
                    asm.add(i, j, v);
                    if !std::ptr::eq(p, q) {
                        asm.add(j, i, v);
                    }
                }
            }
        }
    }
}

/// Accumulates rank-one point contributions k·n·nᵀ. Consecutive points whose shape vectors
/// cover the same DOFs (always the case for modal layers) are summed in one dense block, so a
/// fastener row of 250 points over 250 modal DOFs costs one block, not 250.
pub struct PointAccumulator {
    dofs: Vec<usize>,
    block: Vec<f64>,
    n: Vec<f64>,
}

impl Default for PointAccumulator {
    fn default() -> Self {
        Self::new()
    }
}

impl PointAccumulator {
    pub fn new() -> Self {
        Self {
            dofs: Vec::new(),
            block: Vec::new(),
            n: Vec::new(),
        }
    }

    /// Adds `w`·n·nᵀ for n = [N_a; −N_b] (shape vectors in structure numbering).
    pub fn add(&mut self, asm: &mut Assembler, na: &Shape, nb: Option<&Shape>, w: f64) {
        if w == 0.0 {
            return;
        }
        let same = self.dofs.len() == na.values.len() + nb.map_or(0, |s| s.values.len())
            && self.dofs.first() == Some(&na.start)
            && nb.is_none_or(|s| self.dofs.get(na.values.len()) == Some(&s.start));
        if !same {
            self.flush(asm);
            self.dofs.extend(na.start..na.start + na.values.len());
            if let Some(s) = nb {
                self.dofs.extend(s.start..s.start + s.values.len());
            }
            self.block.resize(self.dofs.len() * self.dofs.len(), 0.0);
        }
        self.n.clear();
        self.n.extend_from_slice(&na.values);
        if let Some(s) = nb {
            self.n.extend(s.values.iter().map(|v| -v));
        }
        let m = self.n.len();
        for (r, &nr) in self.n.iter().enumerate() {
            let row = &mut self.block[r * m..(r + 1) * m];
            let f = w * nr;
            for (b, &nc) in row.iter_mut().zip(&self.n) {
                *b += f * nc;
            }
        }
    }

    pub fn flush(&mut self, asm: &mut Assembler) {
        if !self.dofs.is_empty() {
            asm.add_block(&self.dofs, &self.block, 1.0);
        }
        self.dofs.clear();
        self.block.clear();
    }
}

/// Adds `w`·Σ_points n·nᵀ of a discrete connection (b = None: to the ground).
pub fn add_discrete(asm: &mut Assembler, a: &Layer, b: Option<&Layer>, positions: &[f64], w: f64) {
    let mut acc = PointAccumulator::new();
    for &x in positions {
        let na = a.shape(x);
        let nb = b.map(|l| l.shape(x));
        acc.add(asm, &na, nb.as_ref(), w);
    }
    acc.flush(asm);
}
