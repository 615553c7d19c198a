//! Block-tridiagonal systems. A finite-element structure numbered node by node (the DOFs of
//! every layer at one node form a block) couples only neighbouring nodes, so its matrices are
//! block tridiagonal. The time-stepping matrix is factorised by block LDLᵀ and the products
//! with M and K are dense block rows. Blocks are padded to a multiple of four; the kernels work
//! on W interleaved right-hand sides (the jobs of a lockstep group, W = 1 for a single run),
//! every lane with the same operations, and vectorise across the block's rows and the lanes
//! (compiled for AVX2 where the CPU has it); the few padding zeros cost less than the index
//! arithmetic of a general sparse format.

use crate::error::{Result, VtbError};
use crate::linalg::sparse::CsrMatrix;

/// Padded block sizes (the lane kernels keep a block of up to 16 in fixed arrays).
const SIZES: [usize; 4] = [4, 8, 12, 16];

/// Internal index of a padding slot in `BlockLayout::perm`.
pub const PAD: usize = usize::MAX;

/// The node-by-node numbering: internal unknown b·s + r is the r-th unknown of block b.
#[derive(Clone, Debug)]
pub struct BlockLayout {
    /// Padded block size.
    pub s: usize,
    /// Number of blocks.
    pub nb: usize,
    /// Internal → original index (`PAD` for padding).
    pub perm: Vec<usize>,
    /// Original → internal index.
    pub inv: Vec<usize>,
}

impl BlockLayout {
    /// The layout of `groups` (disjoint, covering every unknown of `pattern`) if each nonzero
    /// of `pattern` couples unknowns of the same or of neighbouring groups and the groups fit
    /// a compiled block size; `None` otherwise.
    pub fn new(groups: &[Vec<usize>], pattern: &CsrMatrix) -> Option<Self> {
        let n = pattern.n;
        let largest = groups.iter().map(Vec::len).max()?;
        let s = *SIZES.iter().find(|&&s| s >= largest)?;
        let mut group = vec![PAD; n];
        let mut perm = vec![PAD; groups.len() * s];
        let mut inv = vec![0; n];
        for (b, g) in groups.iter().enumerate() {
            for (r, &i) in g.iter().enumerate() {
                if i >= n || group[i] != PAD {
                    return None;
                }
                group[i] = b;
                perm[b * s + r] = i;
                inv[i] = b * s + r;
            }
        }
        if group.contains(&PAD) {
            return None;
        }
        let tridiagonal = (0..n).all(|i| {
            (pattern.row_ptr[i]..pattern.row_ptr[i + 1])
                .all(|p| group[i].abs_diff(group[pattern.col_idx[p]]) <= 1)
        });
        tridiagonal.then_some(Self {
            s,
            nb: groups.len(),
            perm,
            inv,
        })
    }

    /// Length of internal vectors (padding included).
    pub fn len(&self) -> usize {
        self.nb * self.s
    }

    pub fn is_empty(&self) -> bool {
        self.nb == 0
    }
}

/// A symmetric block-tridiagonal matrix stored by block rows: row b holds
/// [A(b,b−1) A(b,b) A(b,b+1)] column-major (s × 3s), so that y_b = row_b·x[(b−1)s..(b+2)s]
/// is one dense product over contiguous memory. (Storing only the lower blocks and applying
/// their transposes in the same pass reads a third less but needs horizontal sums; measured
/// slower.) Padding rows and columns are zero.
#[derive(Clone, Debug)]
pub struct BlockTri {
    s: usize,
    nb: usize,
    vals: Vec<f64>,
}

impl BlockTri {
    pub fn new(a: &CsrMatrix, layout: &BlockLayout) -> Self {
        let s = layout.s;
        let w = 3 * s * s;
        let mut vals = vec![0.0; layout.nb * w];
        for i in 0..a.n {
            let (b, r) = (layout.inv[i] / s, layout.inv[i] % s);
            for p in a.row_ptr[i]..a.row_ptr[i + 1] {
                let jj = layout.inv[a.col_idx[p]];
                let (c, q) = (jj / s, jj % s);
                // BlockLayout::new checked |b − c| ≤ 1.
                vals[b * w + ((c + 1 - b) * s + q) * s + r] = a.values[p];
            }
        }
        Self {
            s,
            nb: layout.nb,
            vals,
        }
    }

    /// A(b,b) (`lower` false) or A(b,b−1) (`lower` true), column-major.
    fn block(&self, b: usize, lower: bool) -> &[f64] {
        let ss = self.s * self.s;
        let at = (3 * b + if lower { 0 } else { 1 }) * ss;
        &self.vals[at..at + ss]
    }
}

/// Two block-tridiagonal matrices of one layout (M and K) interleaved column by column, so
/// that the products A·x and B·x stream one array.
#[derive(Clone, Debug)]
pub struct BlockPair {
    s: usize,
    vals: Vec<f64>,
}

impl BlockPair {
    pub fn new(a: &BlockTri, b: &BlockTri) -> Self {
        assert!(a.s == b.s && a.nb == b.nb, "block pair layouts");
        let s = a.s;
        let vals = a
            .vals
            .chunks_exact(s)
            .zip(b.vals.chunks_exact(s))
            .flat_map(|(ca, cb)| ca.iter().chain(cb).copied())
            .collect();
        Self { s, vals }
    }

    /// ya = A·x and yb = B·x for `W` interleaved vectors (each lane with the operations of a
    /// single vector).
    pub fn mul2<const W: usize>(&self, x: &[f64], ya: &mut [f64], yb: &mut [f64]) {
        let s = self.s;
        let nb = self.vals.len() / (6 * s * s);
        assert!(x.len() == nb * s * W && ya.len() == x.len() && yb.len() == x.len());
        crate::wide!(<W> (vals: &[f64] = &self.vals, s: usize = s, nb: usize = nb, x: &[f64] = x, ya: &mut [f64] = ya, yb: &mut [f64] = yb) {
            // Two partial sums per product (even and odd columns) halve the latency chains;
            // only the block's s·W entries of each are used (and cleared).
            let mut acc = [[[0.0; 16 * 8]; 2]; 2];
            for blk in 0..nb {
                for a in acc.iter_mut().flatten() {
                    a[..s * W].fill(0.0);
                }
                let lo = if blk == 0 { s } else { 0 };
                let hi = if blk + 1 == nb { 2 * s } else { 3 * s };
                let row = &vals[blk * 6 * s * s..(blk + 1) * 6 * s * s];
                let (ya, yb) = (
                    &mut ya[blk * s * W..(blk + 1) * s * W],
                    &mut yb[blk * s * W..(blk + 1) * s * W],
                );
                for k in lo..hi {
                    let xk = &x[(blk * s + k - s) * W..(blk * s + k - s + 1) * W];
                    let cols = &row[2 * k * s..(2 * k + 2) * s];
                    let [aa, ab] = &mut acc[k & 1];
                    for i in 0..s {
                        let (a, b) = (cols[i], cols[s + i]);
                        for c in 0..W {
                            aa[i * W + c] = a.mul_add(xk[c], aa[i * W + c]);
                            ab[i * W + c] = b.mul_add(xk[c], ab[i * W + c]);
                        }
                    }
                }
                for q in 0..s * W {
                    ya[q] = acc[0][0][q] + acc[1][0][q];
                    yb[q] = acc[0][1][q] + acc[1][1][q];
                }
            }
        });
    }
}

/// Block LDLᵀ of a symmetric positive definite block-tridiagonal matrix:
/// A = L̃·S·L̃ᵀ with L̃ unit block lower bidiagonal (sub-diagonal blocks L_b) and S block
/// diagonal, S_0 = A(0,0), L_b = A(b,b−1)·S_{b−1}⁻¹, S_b = A(b,b) − L_b·A(b,b−1)ᵀ.
/// The inverses S_b⁻¹ are stored, so a solve is a forward pass (z_b = x_b − L_b·z_{b−1},
/// w_b = S_b⁻¹·z_b) and a backward pass (x_b = w_b − L_{b+1}ᵀ·x_{b+1}) whose only serial
/// dependence is one small dense product per block.
#[derive(Clone, Debug)]
pub struct BlockLdlt {
    s: usize,
    nb: usize,
    /// L_b column-major at b·s² (b ≥ 1), and row-major (columns of L_bᵀ, for the backward
    /// pass as axpys rather than dot products).
    l: Vec<f64>,
    lt: Vec<f64>,
    /// S_b⁻¹ at b·s².
    s_inv: Vec<f64>,
}

impl BlockLdlt {
    /// Factorises; padding unknowns get a unit diagonal. Fails if A is not positive definite.
    pub fn new(a: &BlockTri, layout: &BlockLayout) -> Result<Self> {
        let (s, nb) = (a.s, a.nb);
        let ss = s * s;
        let mut l = vec![0.0; nb * ss];
        let mut s_inv = vec![0.0; nb * ss];
        let mut sb = vec![0.0; ss];
        for b in 0..nb {
            sb.copy_from_slice(a.block(b, false));
            for r in 0..s {
                if layout.perm[b * s + r] == PAD {
                    sb[r * s + r] = 1.0;
                }
            }
            if b > 0 {
                // L_b = B·S_{b−1}⁻¹ and S_b −= L_b·Bᵀ with B = A(b, b−1).
                let bm = a.block(b, true);
                let prev = &s_inv[(b - 1) * ss..b * ss];
                let lb = &mut l[b * ss..(b + 1) * ss];
                for j in 0..s {
                    for k in 0..s {
                        let v = prev[j * s + k];
                        for i in 0..s {
                            lb[j * s + i] += bm[k * s + i] * v;
                        }
                    }
                }
                for j in 0..s {
                    for k in 0..s {
                        let v = bm[k * s + j];
                        for i in 0..s {
                            sb[j * s + i] -= lb[k * s + i] * v;
                        }
                    }
                }
            }
            let first = layout.perm[b * s..(b + 1) * s]
                .iter()
                .find(|&&i| i != PAD)
                .copied()
                .unwrap_or(0);
            spd_inverse(&sb, s, &mut s_inv[b * ss..(b + 1) * ss]).map_err(|pivot| {
                VtbError::Solver(format!(
                    "the time-stepping matrix is not positive definite (pivot {pivot:.3e} in \
                     the block of unknown {first})"
                ))
            })?;
        }
        let mut lt = vec![0.0; nb * ss];
        for b in 0..nb {
            for j in 0..s {
                for i in 0..s {
                    lt[b * ss + i * s + j] = l[b * ss + j * s + i];
                }
            }
        }
        Ok(Self {
            s,
            nb,
            l,
            lt,
            s_inv,
        })
    }

    /// Solves A·x = rhs in place for `W` interleaved right-hand sides (each lane with the
    /// operations of a single one); entries before block `first` of the right-hand side must
    /// be zero (they are skipped in the forward pass).
    pub fn solve_from<const W: usize>(&self, x: &mut [f64], first: usize) {
        let (s, nb) = (self.s, self.nb);
        assert_eq!(x.len(), nb * s * W, "block solve dimension");
        assert!(W <= 8, "at most 8 lanes");
        let first = first.min(nb);
        if nb == 0 {
            return;
        }
        crate::wide!(<W> (l: &[f64] = &self.l, lt: &[f64] = &self.lt, s_inv: &[f64] = &self.s_inv, s: usize = s, nb: usize = nb, first: usize = first, x: &mut [f64] = x) {
            let ss = s * s;
            // Forward: z_b = x_b − L_b·z_{b−1} (kept in zp), x_b = S_b⁻¹·z_b.
            let mut zp = [0.0; 16 * 8];
            let mut w = [0.0; 16 * 8];
            let mut z2 = [0.0; 16 * 8];
            for b in first..nb {
                let xb = &mut x[b * s * W..(b + 1) * s * W];
                if b > first {
                    // Two partial sums (even and odd k) halve the serial chain.
                    let lb = &l[b * ss..(b + 1) * ss];
                    z2[..s * W].fill(0.0);
                    for k in 0..s {
                        let acc = if k & 1 == 0 { &mut *xb } else { &mut z2[..s * W] };
                        for i in 0..s {
                            let l = lb[k * s + i];
                            for c in 0..W {
                                acc[i * W + c] = (-l).mul_add(zp[k * W + c], acc[i * W + c]);
                            }
                        }
                    }
                    for q in 0..s * W {
                        xb[q] += z2[q];
                    }
                }
                zp[..s * W].copy_from_slice(xb);
                let sb = &s_inv[b * ss..(b + 1) * ss];
                w[..s * W].fill(0.0);
                for k in 0..s {
                    for i in 0..s {
                        let v = sb[k * s + i];
                        for c in 0..W {
                            w[i * W + c] = v.mul_add(zp[k * W + c], w[i * W + c]);
                        }
                    }
                }
                xb.copy_from_slice(&w[..s * W]);
            }
            // Backward: x_{b−1} −= L_bᵀ·x_b.
            for b in (1..nb).rev() {
                let lb = &lt[b * ss..(b + 1) * ss];
                let (head, tail) = x.split_at_mut(b * s * W);
                let (prev, xb) = (&mut head[(b - 1) * s * W..], &tail[..s * W]);
                for k in 0..s {
                    for m in 0..s {
                        let l = lb[k * s + m];
                        for c in 0..W {
                            prev[m * W + c] = (-l).mul_add(xb[k * W + c], prev[m * W + c]);
                        }
                    }
                }
            }
        });
    }

    pub fn block_size(&self) -> usize {
        self.s
    }
}

/// Inverse of a small symmetric positive definite matrix (column-major) by Cholesky;
/// `Err(pivot)` if a pivot is not positive and finite.
fn spd_inverse(a: &[f64], s: usize, out: &mut [f64]) -> std::result::Result<(), f64> {
    let mut r = a.to_vec();
    // Lower Cholesky factor in place: a = R·Rᵀ.
    for j in 0..s {
        let mut d = r[j * s + j];
        for k in 0..j {
            d -= r[k * s + j] * r[k * s + j];
        }
        let scale = a[j * s + j].abs().max(f64::MIN_POSITIVE);
        if !(d > 1e-14 * scale) || !d.is_finite() {
            return Err(d);
        }
        let d = d.sqrt();
        r[j * s + j] = d;
        for i in j + 1..s {
            let mut v = r[j * s + i];
            for k in 0..j {
                v -= r[k * s + i] * r[k * s + j];
            }
            r[j * s + i] = v / d;
        }
    }
    // Columns of a⁻¹ = R⁻ᵀR⁻¹·e_c.
    for c in 0..s {
        let col = &mut out[c * s..(c + 1) * s];
        col.fill(0.0);
        col[c] = 1.0;
        for i in 0..s {
            let mut v = col[i];
            for k in 0..i {
                v -= r[k * s + i] * col[k];
            }
            col[i] = v / r[i * s + i];
        }
        for i in (0..s).rev() {
            let mut v = col[i];
            for k in i + 1..s {
                v -= r[i * s + k] * col[k];
            }
            col[i] = v / r[i * s + i];
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::sparse::{Assembler, Ldlt};

    /// A random SPD block-tridiagonal matrix: chains of 2-DOF nodes in `layers` layers,
    /// coupled within a node and to the next node.
    fn chain(nodes: usize, layers: usize, seed: u64) -> (CsrMatrix, Vec<Vec<usize>>) {
        let n = nodes * layers * 2;
        let mut rng = seed;
        let mut next = || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((rng >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let idx = |node: usize, layer: usize, d: usize| layer * 2 * nodes + 2 * node + d;
        let mut a = Assembler::new(n);
        for node in 0..nodes {
            for layer in 0..layers {
                for d in 0..2 {
                    let i = idx(node, layer, d);
                    a.add(i, i, 20.0);
                    for (nn, ll) in [(node + 1, layer), (node, layer + 1), (node + 1, layer + 1)] {
                        if nn < nodes && ll < layers {
                            for e in 0..2 {
                                let v = next();
                                a.add(i, idx(nn, ll, e), v);
                                a.add(idx(nn, ll, e), i, v);
                            }
                        }
                    }
                }
            }
        }
        let groups = (0..nodes)
            .map(|node| {
                (0..layers)
                    .flat_map(|l| [idx(node, l, 0), idx(node, l, 1)])
                    .collect()
            })
            .collect();
        (a.finish(), groups)
    }

    #[test]
    fn block_solve_and_products_match_sparse_reference() {
        for layers in [1, 2, 3, 4, 5] {
            let (a, groups) = chain(9, layers, layers as u64);
            let lay = BlockLayout::new(&groups, &a).expect("block tridiagonal");
            let rows = BlockTri::new(&a, &lay);
            let f = BlockLdlt::new(&rows, &lay).unwrap();
            let n = a.n;
            let rhs: Vec<f64> = (0..n).map(|i| ((i * 7) as f64).sin()).collect();
            let want = Ldlt::new(&a).unwrap().solve(&rhs);
            let mut x = vec![0.0; lay.len()];
            for i in 0..n {
                x[lay.inv[i]] = rhs[i];
            }
            f.solve_from::<1>(&mut x, 0);
            for i in 0..n {
                assert!(
                    (x[lay.inv[i]] - want[i]).abs() < 1e-12,
                    "layers {layers} unknown {i}"
                );
            }
            for (k, &i) in lay.perm.iter().enumerate() {
                if i == PAD {
                    assert_eq!(x[k], 0.0);
                }
            }
            // A·x reproduces the right-hand side; a second matrix (2A) in the same pass.
            let twice = CsrMatrix::combine(&[(2.0, &a)]);
            let rows2 = BlockTri::new(&twice, &lay);
            let (mut y1, mut y2) = (vec![0.0; lay.len()], vec![0.0; lay.len()]);
            BlockPair::new(&rows, &rows2).mul2::<1>(&x, &mut y1, &mut y2);
            for i in 0..n {
                let k = lay.inv[i];
                assert!((y1[k] - rhs[i]).abs() < 1e-12 && (y2[k] - 2.0 * rhs[i]).abs() < 1e-12);
            }
            // A right-hand side that starts at a later block.
            let mut e = vec![0.0; lay.len()];
            let k0 = lay.inv[groups[5][1]];
            e[k0] = 1.0;
            f.solve_from::<1>(&mut e, k0 / lay.s);
            let mut unit = vec![0.0; n];
            unit[groups[5][1]] = 1.0;
            let col = Ldlt::new(&a).unwrap().solve(&unit);
            for i in 0..n {
                assert!((e[lay.inv[i]] - col[i]).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn layout_rejects_couplings_beyond_neighbours_and_bad_groups() {
        let (a, groups) = chain(6, 2, 1);
        let mut skip = groups.clone();
        skip.swap(1, 3);
        assert!(BlockLayout::new(&skip, &a).is_none());
        let mut missing = groups.clone();
        missing[2].pop();
        assert!(BlockLayout::new(&missing, &a).is_none());
        let mut twice = groups.clone();
        twice[2].push(groups[1][0]);
        assert!(BlockLayout::new(&twice, &a).is_none());
    }

    #[test]
    fn indefinite_matrix_is_an_error() {
        let (a, groups) = chain(5, 2, 3);
        let neg = CsrMatrix::combine(&[(-1.0, &a)]);
        let lay = BlockLayout::new(&groups, &neg).unwrap();
        let err = BlockLdlt::new(&BlockTri::new(&neg, &lay), &lay).unwrap_err();
        assert!(matches!(err, VtbError::Solver(m) if m.contains("positive definite")));
    }
}
