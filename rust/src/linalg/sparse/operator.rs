//! Two symmetric matrices (M and K of a time step) applied together in one pass, laid out
//! for the structure of the stepping matrices: diagonal segments of light entries, a few
//! heavy rows as runs.

use super::CsrMatrix;

/// A diagonal segment of light entries: first row i, length, offset j − i, value offset.
type Segment = (usize, usize, usize, usize);
/// A heavy row: its index and its runs (first column, length, value offset).
type HeavyRow = (usize, Vec<(usize, usize, usize)>);

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
