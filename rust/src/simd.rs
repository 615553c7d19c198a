//! Dense inner kernels with a runtime-dispatched AVX2+FMA path (x86-64) and a portable
//! fallback, so one binary is fast where the CPU allows and correct everywhere. Results of
//! the two paths differ only by rounding (fused multiply–add, summation order).

#[cfg(target_arch = "x86_64")]
use std::sync::OnceLock;

#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub(crate) fn has_avx2() -> bool {
    static HAS: OnceLock<bool> = OnceLock::new();
    *HAS.get_or_init(|| is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
}

/// Σ aᵢ·bᵢ over the common length.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2() && n >= 8 {
        // SAFETY: the CPU supports AVX2 and FMA (checked above); slices are length ≥ n.
        return unsafe { avx::dot(&a[..n], &b[..n]) };
    }
    let mut s = [0.0; 4];
    let (ac, bc) = (a[..n].chunks_exact(4), b[..n].chunks_exact(4));
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

/// y += v·a over the common length.
#[inline]
pub fn axpy(y: &mut [f64], a: &[f64], v: f64) {
    let n = y.len().min(a.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2() && n >= 8 {
        // SAFETY: as in `dot`.
        return unsafe { avx::axpy(&mut y[..n], &a[..n], v) };
    }
    for (yv, av) in y[..n].iter_mut().zip(&a[..n]) {
        *yv += av * v;
    }
}

/// y += v·a and returns a·x, in one pass over equal-length slices.
#[inline]
pub fn axpy_dot(y: &mut [f64], a: &[f64], x: &[f64], v: f64) -> f64 {
    let n = y.len().min(a.len()).min(x.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2() && n >= 8 {
        // SAFETY: as in `dot`.
        return unsafe { avx::axpy_dot(&mut y[..n], &a[..n], &x[..n], v) };
    }
    let mut s = [0.0; 4];
    for (j, ((yv, av), xv)) in y[..n].iter_mut().zip(&a[..n]).zip(&x[..n]).enumerate() {
        *yv += av * v;
        s[j & 3] += av * xv;
    }
    (s[0] + s[1]) + (s[2] + s[3])
}

/// y1 += v·a1, y2 += v·a2 and returns (a1·x, a2·x), in one pass over equal-length slices.
#[inline]
pub fn axpy_dot2(
    y1: &mut [f64],
    y2: &mut [f64],
    a1: &[f64],
    a2: &[f64],
    x: &[f64],
    v: f64,
) -> (f64, f64) {
    let n = y1
        .len()
        .min(y2.len())
        .min(a1.len())
        .min(a2.len())
        .min(x.len());
    #[cfg(target_arch = "x86_64")]
    if has_avx2() && n >= 4 {
        // SAFETY: as in `dot`.
        return unsafe {
            avx::axpy_dot2(&mut y1[..n], &mut y2[..n], &a1[..n], &a2[..n], &x[..n], v)
        };
    }
    let (mut s1, mut s2) = (0.0, 0.0);
    for j in 0..n {
        y1[j] += a1[j] * v;
        y2[j] += a2[j] * v;
        s1 += a1[j] * x[j];
        s2 += a2[j] * x[j];
    }
    (s1, s2)
}

/// Σ_i aᵢ·z[4i..4i+4] for four interleaved columns z.
#[inline]
pub fn dot4_cols(a: &[f64], z: &[f64]) -> [f64; 4] {
    let n = a.len().min(z.len() / 4);
    #[cfg(target_arch = "x86_64")]
    if has_avx2() {
        // SAFETY: as in `dot`; z has at least 4n entries.
        return unsafe { avx::dot4_cols(&a[..n], &z[..4 * n]) };
    }
    let mut acc = [[0.0; 4]; 2];
    for (i, (av, zc)) in a[..n].iter().zip(z.chunks_exact(4)).enumerate() {
        for c in 0..4 {
            acc[i & 1][c] += av * zc[c];
        }
    }
    std::array::from_fn(|c| acc[0][c] + acc[1][c])
}

#[cfg(target_arch = "x86_64")]
mod avx {
    use std::arch::x86_64::*;

    #[target_feature(enable = "avx2,fma")]
    unsafe fn hsum(v: __m256d) -> f64 {
        let mut b = [0.0; 4];
        unsafe { _mm256_storeu_pd(b.as_mut_ptr(), v) };
        (b[0] + b[1]) + (b[2] + b[3])
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn dot(a: &[f64], b: &[f64]) -> f64 {
        let n = a.len();
        let (pa, pb) = (a.as_ptr(), b.as_ptr());
        unsafe {
            let (mut s0, mut s1, mut s2, mut s3) = (
                _mm256_setzero_pd(),
                _mm256_setzero_pd(),
                _mm256_setzero_pd(),
                _mm256_setzero_pd(),
            );
            let mut i = 0;
            while i + 16 <= n {
                s0 = _mm256_fmadd_pd(_mm256_loadu_pd(pa.add(i)), _mm256_loadu_pd(pb.add(i)), s0);
                s1 = _mm256_fmadd_pd(
                    _mm256_loadu_pd(pa.add(i + 4)),
                    _mm256_loadu_pd(pb.add(i + 4)),
                    s1,
                );
                s2 = _mm256_fmadd_pd(
                    _mm256_loadu_pd(pa.add(i + 8)),
                    _mm256_loadu_pd(pb.add(i + 8)),
                    s2,
                );
                s3 = _mm256_fmadd_pd(
                    _mm256_loadu_pd(pa.add(i + 12)),
                    _mm256_loadu_pd(pb.add(i + 12)),
                    s3,
                );
                i += 16;
            }
            while i + 4 <= n {
                s0 = _mm256_fmadd_pd(_mm256_loadu_pd(pa.add(i)), _mm256_loadu_pd(pb.add(i)), s0);
                i += 4;
            }
            let mut t = hsum(_mm256_add_pd(_mm256_add_pd(s0, s1), _mm256_add_pd(s2, s3)));
            while i < n {
                t += *pa.add(i) * *pb.add(i);
                i += 1;
            }
            t
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn axpy(y: &mut [f64], a: &[f64], v: f64) {
        let n = y.len();
        let (py, pa) = (y.as_mut_ptr(), a.as_ptr());
        unsafe {
            let vv = _mm256_set1_pd(v);
            let mut i = 0;
            while i + 4 <= n {
                _mm256_storeu_pd(
                    py.add(i),
                    _mm256_fmadd_pd(_mm256_loadu_pd(pa.add(i)), vv, _mm256_loadu_pd(py.add(i))),
                );
                i += 4;
            }
            while i < n {
                *py.add(i) += *pa.add(i) * v;
                i += 1;
            }
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn axpy_dot(y: &mut [f64], a: &[f64], x: &[f64], v: f64) -> f64 {
        let n = y.len();
        let (py, pa, px) = (y.as_mut_ptr(), a.as_ptr(), x.as_ptr());
        unsafe {
            let vv = _mm256_set1_pd(v);
            let (mut s0, mut s1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            let mut i = 0;
            while i + 8 <= n {
                let (a0, a1) = (_mm256_loadu_pd(pa.add(i)), _mm256_loadu_pd(pa.add(i + 4)));
                _mm256_storeu_pd(
                    py.add(i),
                    _mm256_fmadd_pd(a0, vv, _mm256_loadu_pd(py.add(i))),
                );
                _mm256_storeu_pd(
                    py.add(i + 4),
                    _mm256_fmadd_pd(a1, vv, _mm256_loadu_pd(py.add(i + 4))),
                );
                s0 = _mm256_fmadd_pd(a0, _mm256_loadu_pd(px.add(i)), s0);
                s1 = _mm256_fmadd_pd(a1, _mm256_loadu_pd(px.add(i + 4)), s1);
                i += 8;
            }
            let mut t = hsum(_mm256_add_pd(s0, s1));
            while i < n {
                *py.add(i) += *pa.add(i) * v;
                t += *pa.add(i) * *px.add(i);
                i += 1;
            }
            t
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn axpy_dot2(
        y1: &mut [f64],
        y2: &mut [f64],
        a1: &[f64],
        a2: &[f64],
        x: &[f64],
        v: f64,
    ) -> (f64, f64) {
        let n = y1.len();
        let (p1, p2, q1, q2, px) = (
            y1.as_mut_ptr(),
            y2.as_mut_ptr(),
            a1.as_ptr(),
            a2.as_ptr(),
            x.as_ptr(),
        );
        unsafe {
            let vv = _mm256_set1_pd(v);
            let (mut s1, mut s2) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            let mut i = 0;
            while i + 4 <= n {
                let (b1, b2, xv) = (
                    _mm256_loadu_pd(q1.add(i)),
                    _mm256_loadu_pd(q2.add(i)),
                    _mm256_loadu_pd(px.add(i)),
                );
                _mm256_storeu_pd(
                    p1.add(i),
                    _mm256_fmadd_pd(b1, vv, _mm256_loadu_pd(p1.add(i))),
                );
                _mm256_storeu_pd(
                    p2.add(i),
                    _mm256_fmadd_pd(b2, vv, _mm256_loadu_pd(p2.add(i))),
                );
                s1 = _mm256_fmadd_pd(b1, xv, s1);
                s2 = _mm256_fmadd_pd(b2, xv, s2);
                i += 4;
            }
            let (mut t1, mut t2) = (hsum(s1), hsum(s2));
            while i < n {
                *p1.add(i) += *q1.add(i) * v;
                *p2.add(i) += *q2.add(i) * v;
                t1 += *q1.add(i) * *px.add(i);
                t2 += *q2.add(i) * *px.add(i);
                i += 1;
            }
            (t1, t2)
        }
    }

    #[target_feature(enable = "avx2,fma")]
    pub unsafe fn dot4_cols(a: &[f64], z: &[f64]) -> [f64; 4] {
        let n = a.len();
        let (pa, pz) = (a.as_ptr(), z.as_ptr());
        unsafe {
            let (mut s0, mut s1) = (_mm256_setzero_pd(), _mm256_setzero_pd());
            let mut i = 0;
            while i + 2 <= n {
                s0 = _mm256_fmadd_pd(
                    _mm256_set1_pd(*pa.add(i)),
                    _mm256_loadu_pd(pz.add(4 * i)),
                    s0,
                );
                s1 = _mm256_fmadd_pd(
                    _mm256_set1_pd(*pa.add(i + 1)),
                    _mm256_loadu_pd(pz.add(4 * i + 4)),
                    s1,
                );
                i += 2;
            }
            if i < n {
                s0 = _mm256_fmadd_pd(
                    _mm256_set1_pd(*pa.add(i)),
                    _mm256_loadu_pd(pz.add(4 * i)),
                    s0,
                );
            }
            let mut out = [0.0; 4];
            _mm256_storeu_pd(out.as_mut_ptr(), _mm256_add_pd(s0, s1));
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernels_match_plain_loops() {
        for n in [0usize, 3, 8, 13, 64, 413] {
            let a: Vec<f64> = (0..n).map(|i| (i as f64 * 0.7).sin()).collect();
            let x: Vec<f64> = (0..n).map(|i| (i as f64 * 0.3).cos()).collect();
            let want: f64 = a.iter().zip(&x).map(|(p, q)| p * q).sum();
            assert!((dot(&a, &x) - want).abs() < 1e-12 * (1.0 + want.abs()));
            let mut y = x.clone();
            axpy(&mut y, &a, 0.5);
            for i in 0..n {
                assert!((y[i] - (x[i] + 0.5 * a[i])).abs() < 1e-14);
            }
            let mut y2 = x.clone();
            let d = axpy_dot(&mut y2, &a, &x, -2.0);
            assert!((d - want).abs() < 1e-12 * (1.0 + want.abs()));
            assert!(
                (y2[n.saturating_sub(1).min(n)..]
                    .iter()
                    .zip(&x[n.saturating_sub(1)..])
                    .zip(&a[n.saturating_sub(1)..])
                    .map(|((p, q), r)| (p - (q - 2.0 * r)).abs())
                    .sum::<f64>())
                    < 1e-13
            );
            let z: Vec<f64> = (0..4 * n).map(|i| (i as f64 * 0.11).sin()).collect();
            let got = dot4_cols(&a, &z);
            for c in 0..4 {
                let w: f64 = (0..n).map(|i| a[i] * z[4 * i + c]).sum();
                assert!((got[c] - w).abs() < 1e-12 * (1.0 + w.abs()));
            }
        }
    }
}
