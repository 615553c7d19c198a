//! The modal basis of a layer: the end functions, the two cubic residuals and the
//! mass-normalised sines, evaluated by recurrence, with their Gram blocks (mass and
//! curvature) in closed form from the sine coefficients and Euler–Maclaurin tail sums.

use super::integrals::{Func, hermite_values};
use std::f64::consts::PI;

/// Σ_{m>M} m^{−s} (s ≥ 2): explicit terms, then the Euler–Maclaurin remainder, which is
/// exact to round-off once the start is beyond a few hundred.
fn zeta_tail(s: i32, m: usize) -> f64 {
    let m0 = m.max(400) + 200;
    let mut sum: f64 = ((m + 1)..=m0).rev().map(|k| (k as f64).powi(-s)).sum();
    let (x, sf) = (m0 as f64, s as f64);
    sum += x.powi(1 - s) / (sf - 1.0) - 0.5 * x.powi(-s) + sf / 12.0 * x.powi(-s - 1)
        - sf * (sf + 1.0) * (sf + 2.0) / 720.0 * x.powi(-s - 3)
        + sf * (sf + 1.0) * (sf + 2.0) * (sf + 3.0) * (sf + 4.0) / 30240.0 * x.powi(-s - 5);
    sum
}

/// Σ_{n>N} (p + q·(−1)ⁿ)/nˢ.
pub(super) fn tail_sum(p: f64, q: f64, s: i32, n: usize) -> f64 {
    let all = zeta_tail(s, n);
    let even = 2f64.powi(-s) * zeta_tail(s, n / 2);
    p * all + q * (2.0 * even - all)
}

/// The modal basis of one layer (article §2.1): the cubic polynomials on [0, L] plus the
/// mass-normalised sines s_n = sqrt(2/(ρAL))·sin(nπx/L), n = 1..N.
///
/// The article spans the cubics with the four Hermite functions h1..h4. Two of them (h2, h4)
/// vanish at both ends, so N sines approximate them to O(N^−5/2) and that basis is nearly
/// singular: for N = 120 the mass matrix has a condition number near 1e11, every solve
/// leaves large errors along the near-null directions, and Newmark's neutral acceleration
/// recursion accumulates them into a growing Nyquist oscillation. vtb spans *the same space*
/// with a well-conditioned basis, DOF order [g1, g2, g3, g4, s_1, …, s_N]:
/// g1 = 1 − x/L and g2 = x/L (end displacements), and g3, g4 = h2, h4 minus their projection
/// on s_1..s_N, scaled to unit modal mass. g3 and g4 are then mass- and stiffness-orthogonal
/// to the layer's own sines, and every integral is exact, from the closed-form sine
/// coefficients ∫h·sin(kx) = (h″(L)(−1)ⁿ − h″(0))/k³ and Euler–Maclaurin tail sums.
#[derive(Clone, Debug)]
pub struct ModalBasis {
    pub length: f64,
    pub n_sines: usize,
    /// ρA (kg/m).
    pub rho_a: f64,
    /// sqrt(2/(ρAL)).
    pub scale: f64,
    /// (2/L)·∫h_k·sin(k_n x) for n ≤ N (projection coefficients of h2 and h4).
    pub(super) proj: [Vec<f64>; 2],
    /// Norms making ρA∫g_k² = 1.
    pub(super) mu: [f64; 2],
}

/// (h″(L), h″(0)) of h2 and h4: ∫h·sin(k_n x) = (a(−1)ⁿ + b)/k_n³ with a = h″(L), b = −h″(0).
fn residual_coeffs(l: f64) -> [(f64, f64); 2] {
    [(2.0 / l, 4.0 / l), (4.0 / l, 2.0 / l)]
}

impl ModalBasis {
    pub fn new(length: f64, rho_a: f64, n_sines: usize) -> Self {
        let l = length;
        let ab = residual_coeffs(l);
        let proj = ab.map(|(a, b)| {
            (1..=n_sines)
                .map(|n| {
                    let k = n as f64 * PI / l;
                    let sign = if n % 2 == 0 { 1.0 } else { -1.0 };
                    2.0 / l * (a * sign + b) / (k * k * k)
                })
                .collect::<Vec<f64>>()
        });
        let c6 = (l / PI).powi(6);
        let mu = ab.map(|(a, b)| {
            (rho_a * 2.0 / l * c6 * tail_sum(a * a + b * b, 2.0 * a * b, 6, n_sines)).sqrt()
        });
        Self {
            length,
            n_sines,
            rho_a,
            scale: (2.0 / (rho_a * length)).sqrt(),
            proj,
            mu,
        }
    }

    pub fn n_dofs(&self) -> usize {
        4 + self.n_sines
    }

    /// Wavenumber of sine n (1-based).
    pub fn wavenumber(&self, n: usize) -> f64 {
        n as f64 * PI / self.length
    }

    /// Sine n (1-based) as a piece function.
    pub fn sine(&self, n: usize) -> Func {
        Func::Sine {
            origin: 0.0,
            amp: self.scale,
            k: self.wavenumber(n),
            phase: 0.0,
        }
    }

    /// Values of all basis functions at x into `out` (length n_dofs); the sines by the
    /// Chebyshev recurrence sin((n+1)θ) = 2cosθ·sin(nθ) − sin((n−1)θ).
    #[inline]
    pub fn eval_into(&self, x: f64, out: &mut [f64]) {
        let l = self.length;
        let h = hermite_values(x, l);
        let (p2, p4) = self.sines_into::<false>(x, out);
        out[0] = 1.0 - x / l;
        out[1] = x / l;
        out[2] = (h[1] - p2) / self.mu[0];
        out[3] = (h[3] - p4) / self.mu[1];
    }

    /// Second derivatives of all basis functions at x into `out` (length n_dofs): the end
    /// functions have none, the sines −k_n²·s_n, the residuals (h″ − Σ proj·(−k_n²)·sin)/μ.
    #[inline]
    pub fn curvature_into(&self, x: f64, out: &mut [f64]) {
        let l = self.length;
        let s = x / l;
        // h2″ and h4″ of `hermite_values` (h2 = L(s − 2s² + s³), h4 = L(s³ − s²)).
        let (h2, h4) = ((6.0 * s - 4.0) / l, (6.0 * s - 2.0) / l);
        let (p2, p4) = self.sines_into::<true>(x, out);
        out[0] = 0.0;
        out[1] = 0.0;
        out[2] = (h2 + p2) / self.mu[0];
        out[3] = (h4 + p4) / self.mu[1];
    }

    /// The sines (or with `CURVATURE` their second derivatives −k_n²·s_n) at x into
    /// `out[4..]`, by the Chebyshev recurrence, and the two residuals' projections on them
    /// (Σ proj·s_n, or Σ proj·k_n²·s_n).
    #[inline(always)]
    fn sines_into<const CURVATURE: bool>(&self, x: f64, out: &mut [f64]) -> (f64, f64) {
        let th = PI * x / self.length;
        let (s1, c1) = th.sin_cos();
        let two_c = 2.0 * c1;
        let (mut prev, mut cur) = (0.0, s1);
        let (mut p2, mut p4) = (0.0, 0.0);
        for (n, v) in out[4..4 + self.n_sines].iter_mut().enumerate() {
            if CURVATURE {
                let k2 = self.wavenumber(n + 1).powi(2);
                *v = -k2 * self.scale * cur;
                p2 += self.proj[0][n] * k2 * cur;
                p4 += self.proj[1][n] * k2 * cur;
            } else {
                *v = self.scale * cur;
                p2 += self.proj[0][n] * cur;
                p4 += self.proj[1][n] * cur;
            }
            let next = two_c * cur - prev;
            prev = cur;
            cur = next;
        }
        (p2, p4)
    }

    /// ∫ N_a·N_bᵀ (`Derivative::Value`) or ∫ N_a″·N_b″ᵀ (`Curvature`) of two modal bases on
    /// the same length, row-major n_dofs(a) × n_dofs(b).
    pub fn gram(a: &ModalBasis, b: &ModalBasis, curvature: bool) -> Vec<f64> {
        let l = a.length;
        debug_assert_eq!(l, b.length);
        let (na, nb) = (a.n_dofs(), b.n_dofs());
        let mut g = vec![0.0; na * nb];
        let ab = residual_coeffs(l);
        let k = |n: usize| n as f64 * PI / l;
        let sign = |n: usize| if n % 2 == 0 { 1.0 } else { -1.0 };
        // ∫h_j·sin(k_n x)
        let hs = |j: usize, n: usize| (ab[j].0 * sign(n) + ab[j].1) / k(n).powi(3);
        let mut set = |r: usize, c: usize, v: f64| g[r * nb + c] = v;
        if !curvature {
            // linear × linear
            let ll = [[l / 3.0, l / 6.0], [l / 6.0, l / 3.0]];
            for i in 0..2 {
                for j in 0..2 {
                    set(i, j, ll[i][j]);
                }
            }
            // linear × sine: ∫(1 − x/L)σ_n = 1/k, ∫(x/L)σ_n = −(−1)ⁿ/k
            let lin_sine = |i: usize, n: usize| if i == 0 { 1.0 / k(n) } else { -sign(n) / k(n) };
            for n in 1..=b.n_sines {
                for i in 0..2 {
                    set(i, 3 + n, b.scale * lin_sine(i, n));
                }
            }
            for n in 1..=a.n_sines {
                for i in 0..2 {
                    set(3 + n, i, a.scale * lin_sine(i, n));
                }
            }
            // linear × residual: (2/L)·Σ_{n>N} G_in·H_kn / μ (Parseval), with G_1n = 1/k,
            // G_2n = −(−1)ⁿ/k.
            let c4 = (l / PI).powi(4);
            let lin_res = |i: usize, j: usize, nmax: usize, mu: f64| {
                let (ga, gb) = if i == 0 { (0.0, 1.0) } else { (-1.0, 0.0) };
                let (ha, hb) = ab[j];
                2.0 / l * c4 * tail_sum(ga * ha + gb * hb, ga * hb + gb * ha, 4, nmax) / mu
            };
            for i in 0..2 {
                for j in 0..2 {
                    set(i, 2 + j, lin_res(i, j, b.n_sines, b.mu[j]));
                    set(2 + j, i, lin_res(i, j, a.n_sines, a.mu[j]));
                }
            }
            // sine × residual: nonzero only beyond the other basis' own sines.
            for m in (b.n_sines + 1)..=a.n_sines {
                for j in 0..2 {
                    set(3 + m, 2 + j, a.scale * hs(j, m) / b.mu[j]);
                }
            }
            for n in (a.n_sines + 1)..=b.n_sines {
                for j in 0..2 {
                    set(2 + j, 3 + n, b.scale * hs(j, n) / a.mu[j]);
                }
            }
            // residual × residual
            let c6 = (l / PI).powi(6);
            let nmax = a.n_sines.max(b.n_sines);
            for i in 0..2 {
                for j in 0..2 {
                    let (p, q) = (
                        ab[i].0 * ab[j].0 + ab[i].1 * ab[j].1,
                        ab[i].0 * ab[j].1 + ab[i].1 * ab[j].0,
                    );
                    set(
                        2 + i,
                        2 + j,
                        2.0 / l * c6 * tail_sum(p, q, 6, nmax) / (a.mu[i] * b.mu[j]),
                    );
                }
            }
            for n in 1..=a.n_sines.min(b.n_sines) {
                set(3 + n, 3 + n, a.scale * b.scale * l / 2.0);
            }
        } else {
            // Linear functions have no curvature. ∫r_j″·σ_n″ = k⁴·∫h_j·σ_n beyond the own sines.
            for n in (a.n_sines + 1)..=b.n_sines {
                for j in 0..2 {
                    set(2 + j, 3 + n, b.scale * k(n).powi(4) * hs(j, n) / a.mu[j]);
                }
            }
            for m in (b.n_sines + 1)..=a.n_sines {
                for j in 0..2 {
                    set(3 + m, 2 + j, a.scale * k(m).powi(4) * hs(j, m) / b.mu[j]);
                }
            }
            let c2 = (l / PI).powi(2);
            let nmax = a.n_sines.max(b.n_sines);
            for i in 0..2 {
                for j in 0..2 {
                    let (p, q) = (
                        ab[i].0 * ab[j].0 + ab[i].1 * ab[j].1,
                        ab[i].0 * ab[j].1 + ab[i].1 * ab[j].0,
                    );
                    set(
                        2 + i,
                        2 + j,
                        2.0 / l * c2 * tail_sum(p, q, 2, nmax) / (a.mu[i] * b.mu[j]),
                    );
                }
            }
            for n in 1..=a.n_sines.min(b.n_sines) {
                set(3 + n, 3 + n, a.scale * b.scale * k(n).powi(4) * l / 2.0);
            }
        }
        g
    }
}
