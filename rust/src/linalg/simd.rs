//! Lane kernels over W interleaved vectors (the jobs of a lockstep group; W = 1 for a single
//! run). Every lane does the same floating-point operations in the same order whatever W, so
//! a job gives identical bits alone and in a group; `wide` compiles the callers for AVX2+FMA
//! where the CPU has them (x86-64), which vectorises across the lanes and across the partial
//! sums of a dot product without changing any lane's arithmetic. The kernels use fused
//! multiply–adds (`mul_add`): one instruction with FMA hardware (x86-64 with AVX2, aarch64),
//! a slow but exact library call on older x86 CPUs.

#[cfg(target_arch = "x86_64")]
use std::sync::OnceLock;

#[cfg(target_arch = "x86_64")]
#[inline(always)]
pub fn has_avx2() -> bool {
    static HAS: OnceLock<bool> = OnceLock::new();
    *HAS.get_or_init(|| is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"))
}

/// `wide!(<W> (name: Type = value, …) -> Ret { body })` runs `body` on the named arguments in
/// a function compiled for AVX2+FMA where the CPU has them (x86-64; elsewhere as written).
/// The lane kernels it calls are `#[inline(always)]`, so they are compiled into that function
/// and vectorise across jobs with 256-bit registers and fused multiply–adds. The body is a
/// plain function: it captures nothing and cannot name `Self`.
#[macro_export]
macro_rules! wide {
    (<$w:ident> ($($arg:ident : $ty:ty = $val:expr),* $(,)?) $(-> $ret:ty)? $body:block) => {{
        #[inline(always)]
        fn kernel<const $w: usize>($($arg: $ty),*) $(-> $ret)? $body
        #[cfg(target_arch = "x86_64")]
        #[target_feature(enable = "avx2,fma")]
        unsafe fn fast<const $w: usize>($($arg: $ty),*) $(-> $ret)? {
            kernel::<$w>($($arg),*)
        }
        #[cfg(target_arch = "x86_64")]
        let r = if $crate::linalg::simd::has_avx2() {
            // SAFETY: the CPU supports AVX2 and FMA.
            unsafe { fast::<$w>($($val),*) }
        } else {
            kernel::<$w>($($val),*)
        };
        #[cfg(not(target_arch = "x86_64"))]
        let r = kernel::<$w>($($val),*);
        r
    }};
}

/// Partial sums of a lane dot product: enough independent chains to hide the latency of a
/// fused multiply–add for one lane, few enough to stay in registers for 8 lanes.
pub const PARTIAL_SUMS: usize = 8;

/// Σ_i a[i]·x[i·W + c] for each of W interleaved lanes c, in `PARTIAL_SUMS` partial sums by
/// i mod 8 (fused multiply–adds) added pairwise: every lane does the same operations whatever
/// W, so a job run alone (W = 1) and in a lockstep group give identical bits. Call inside
/// `wide`.
#[inline(always)]
pub fn dot_lanes<const W: usize>(a: &[f64], x: &[f64]) -> [f64; W] {
    const P: usize = PARTIAL_SUMS;
    let n = a.len();
    let mut acc = [[0.0; W]; P];
    let (ac, xc) = (a.chunks_exact(P), x[..n * W].chunks_exact(P * W));
    let (ra, rx) = (ac.remainder(), xc.remainder());
    for (av, xv) in ac.zip(xc) {
        for q in 0..P {
            for c in 0..W {
                acc[q][c] = av[q].mul_add(xv[q * W + c], acc[q][c]);
            }
        }
    }
    for (q, av) in ra.iter().enumerate() {
        for c in 0..W {
            acc[q][c] = av.mul_add(rx[q * W + c], acc[q][c]);
        }
    }
    std::array::from_fn(|c| {
        ((acc[0][c] + acc[1][c]) + (acc[2][c] + acc[3][c]))
            + ((acc[4][c] + acc[5][c]) + (acc[6][c] + acc[7][c]))
    })
}

/// y[i·W + c] += a[i]·v[c] over W interleaved lanes (fused; call inside `wide`).
#[inline(always)]
pub fn axpy_lanes<const W: usize>(y: &mut [f64], a: &[f64], v: &[f64; W]) {
    for (yv, av) in y[..a.len() * W].chunks_exact_mut(W).zip(a) {
        for c in 0..W {
            yv[c] = av.mul_add(v[c], yv[c]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dot_w<const W: usize>(a: &[f64], x: &[f64]) -> [f64; W] {
        crate::wide!(<W> (a: &[f64] = a, x: &[f64] = x) -> [f64; W] { dot_lanes::<W>(a, x) })
    }

    fn axpy_w<const W: usize>(y: &mut [f64], a: &[f64], v: &[f64; W]) {
        crate::wide!(<W> (y: &mut [f64] = y, a: &[f64] = a, v: &[f64; W] = v) { axpy_lanes::<W>(y, a, v) })
    }

    /// A lane of a W-wide call gives the bits of the same vector alone, and the dot product
    /// agrees with a plain sum to rounding.
    #[test]
    fn lanes_are_independent_of_width() {
        let n = 37;
        let a: Vec<f64> = (0..n)
            .map(|i| ((i * 7919) % 101) as f64 / 17.0 - 2.5)
            .collect();
        let cols: Vec<Vec<f64>> = (0..4)
            .map(|c| {
                (0..n)
                    .map(|i| ((i * 31 + c * 17) % 23) as f64 / 7.0 - 1.3)
                    .collect()
            })
            .collect();
        let mut x4 = vec![0.0; 4 * n];
        for i in 0..n {
            for c in 0..4 {
                x4[i * 4 + c] = cols[c][i];
            }
        }
        let d4 = dot_w::<4>(&a, &x4);
        for c in 0..4 {
            let d1 = dot_w::<1>(&a, &cols[c])[0];
            assert_eq!(d1.to_bits(), d4[c].to_bits());
            let plain: f64 = a.iter().zip(&cols[c]).map(|(p, q)| p * q).sum();
            assert!((d1 - plain).abs() < 1e-12 * plain.abs().max(1.0));
        }
        let v = [0.5, -1.25, 2.0, 3.5];
        let mut y4 = x4.clone();
        axpy_w::<4>(&mut y4, &a, &v);
        for c in 0..4 {
            let mut y1 = cols[c].clone();
            axpy_w::<1>(&mut y1, &a, &[v[c]]);
            for i in 0..n {
                assert_eq!(y1[i].to_bits(), y4[i * 4 + c].to_bits());
            }
        }
    }
}
