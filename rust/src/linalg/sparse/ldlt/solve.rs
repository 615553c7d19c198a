//! Substitutions with the factor: forward (L⁻¹) and diagonal-backward (D⁻¹ then L⁻ᵀ) kernels
//! for `W` interleaved right-hand sides, each lane with the operations of a single one, and
//! the solves built on them.

use super::{Ldlt, Unit};

impl Ldlt {
    /// z ← L⁻¹·z for `W` interleaved right-hand sides, skipping columns before `start`
    /// (the caller knows z is zero there). `z.len()` must be `W·n`. Every lane does the
    /// operations of a single right-hand side (`simd::dot_lanes`).
    #[inline]
    pub fn forward<const W: usize>(&self, z: &mut [f64], start: usize) {
        self.forward_until::<W>(z, start, self.n);
    }

    /// `forward` through the columns before `end` only: rows from `end` on are left partial
    /// (a caller that reads L⁻¹z only before `end`, where it has decayed, saves the rest).
    #[inline]
    pub fn forward_until<const W: usize>(&self, z: &mut [f64], start: usize, end: usize) {
        assert_eq!(z.len(), W * self.n);
        crate::wide!(<W> (this: &Ldlt = self, z: &mut [f64] = z, start: usize = start, end: usize = end) {
            this.forward_kernel::<W>(z, start, end)
        });
    }

    #[inline(always)]
    fn forward_kernel<const W: usize>(&self, z: &mut [f64], start: usize, end: usize) {
        for unit in &self.units {
            if unit.end() <= start || unit.start() >= end {
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
                    for k in from.max(start)..to.min(end) {
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
        // Border rows as dot products over their runs, then the dense border triangle (none
        // when the window ends before them: they would read rows it left partial).
        let (pb, nb) = (self.p, if end > self.p { self.n - self.p } else { 0 });
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
                Unit::Segment { .. } => self.backward_segment::<W>(zi, unit),
                Unit::Columns { from, to } => {
                    for k in (from..to).rev() {
                        self.backward_column::<W>(zi, k);
                    }
                }
            }
        }
    }

    /// The backward substitution's step over a segment: its columns' rows from the rows
    /// their entries reach (interior rows of `zi`, W lanes).
    #[inline(always)]
    fn backward_segment<const W: usize>(&self, zi: &mut [f64], unit: &Unit) {
        let Unit::Segment {
            k0,
            len,
            off,
            n_off,
            val,
        } = *unit
        else {
            return;
        };
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

    /// The backward substitution's step at interior column k: z_k −= Σ L_ik·z_i.
    #[inline(always)]
    fn backward_column<const W: usize>(&self, zi: &mut [f64], k: usize) {
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

    /// Column k of A⁻¹ (this factor's numbering) over the rows where it matters, for a factor
    /// whose L is banded along its order (finite elements numbered along the track): its
    /// entries decay away from row k, so the substitutions stop where they have. The forward
    /// one runs from row k until what it would carry past its end is below `drop` times the
    /// largest of L⁻¹e_k; the backward one from there down until every row the columns below
    /// still read is below `drop` times the largest entry found. The work is the window's,
    /// not the structure's. `z` must be zero (length n); the column is left in
    /// `z[lo..hi]` for the returned `(lo, hi)` and the rest of `z` zero. `None` (z zero again)
    /// when the window reaches the border rows (they may hold every column): solve in full.
    pub fn column_window(&self, k: usize, drop: f64, z: &mut [f64]) -> Option<(usize, usize)> {
        /// Rows added to the forward window at a time (before rounding up to a unit's end).
        const CHUNK: usize = 64;
        assert_eq!(z.len(), self.n);
        assert!(k < self.n, "column {k} of {}", self.n);
        if k >= self.p {
            return None;
        }
        // Row r, or the end of the segment holding row r − 1: no segment (applied whole) is
        // split between two calls.
        let unit_end = |r: usize| match self.units[self.units.partition_point(|u| u.end() < r)] {
            seg @ Unit::Segment { .. } => seg.end(),
            Unit::Columns { .. } => r,
        };
        z[k] = 1.0;
        let (mut start, mut end, mut ymax) = (k, k, 1.0f64);
        loop {
            if end == self.p {
                if self.p < self.n {
                    z[k..].fill(0.0);
                    return None;
                }
                break;
            }
            let next = unit_end((end + CHUNK).min(self.p));
            self.forward_until::<1>(z, start, next);
            ymax = z[end..next].iter().fold(ymax, |m, v| m.max(v.abs()));
            (start, end) = (next, next);
            let spill = self.spill(end);
            if self.border_reads(k, end) {
                z[k..spill].fill(0.0);
                return None;
            }
            if z[end..spill].iter().all(|v| v.abs() <= drop * ymax) {
                z[end..spill].fill(0.0);
                break;
            }
        }
        for (x, d) in z[k..end].iter_mut().zip(&self.d_inv[k..end]) {
            *x *= d;
        }
        const W: usize = 1; // one right-hand side, with the lanes' fused kernels
        let lo = crate::wide!(<W> (this: &Ldlt = self, z: &mut [f64] = z, k: usize = k, end: usize = end, drop: f64 = drop) -> usize {
            this.column_backward(z, k, end, drop)
        });
        Some((lo, end))
    }

    /// Whether a border row has entries in the columns `from..to`: a column of A⁻¹ whose
    /// window holds them reaches the border rows, and through them every column they hold.
    fn border_reads(&self, from: usize, to: usize) -> bool {
        self.brun.iter().any(|&(s, l, _)| s < to && s + l > from)
    }

    /// The backward half of `column_window` (z holds D⁻¹L⁻¹e_k on rows k..end, zero
    /// elsewhere): returns the first row computed.
    #[inline(always)]
    fn column_backward(&self, z: &mut [f64], k: usize, end: usize, drop: f64) -> usize {
        // Backward: stop below row k once the lowest row above the threshold lies past
        // every row the columns still to come read (`touch`).
        let touch = self.touch();
        let (mut xmax, mut lowest_big) = (0.0f64, end);
        let note = |x: f64, row: usize, xmax: &mut f64, lowest: &mut usize| {
            *xmax = xmax.max(x.abs());
            if x.abs() > drop * *xmax {
                *lowest = row;
            }
        };
        let last = self.units.partition_point(|u| u.end() < end);
        let mut lo = 0;
        'units: for unit in self.units[..=last].iter().rev() {
            match *unit {
                Unit::Segment { k0, len, .. } => {
                    if k0 + len <= k && lowest_big >= touch[k0 + len - 1] {
                        lo = k0 + len;
                        break 'units;
                    }
                    self.backward_segment::<1>(z, unit);
                    for r in (k0..k0 + len).rev() {
                        note(z[r], r, &mut xmax, &mut lowest_big);
                    }
                }
                Unit::Columns { from, to } => {
                    for c in (from..to.min(end)).rev() {
                        if c < k && lowest_big >= touch[c] {
                            lo = c + 1;
                            break 'units;
                        }
                        self.backward_column::<1>(z, c);
                        note(z[c], c, &mut xmax, &mut lowest_big);
                    }
                }
            }
        }
        lo
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
