//! Shape functions of one beam layer and their exact integrals.
//!
//! Two discretisations share one representation: a layer is a list of *pieces* (intervals),
//! each carrying a few basis functions that are, on that piece, either a cubic polynomial or
//! a scaled sine. The modal basis (docs/model.md §2.1) is a single piece over [0, L] with the four
//! Hermite cubics and the mass-normalised sines s_n = sqrt(2/(ρAL))·sin(nπx/L); the FEM basis
//! (§2.2) is one piece per element with the four element Hermite cubics. Every mass, stiffness
//! and coupling integral is a product of two such functions and is evaluated in closed form,
//! so the sine–sine blocks come out diagonal to round-off.

use std::f64::consts::PI;
use std::sync::OnceLock;

/// One basis function restricted to a piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Func {
    /// c0 + c1·ξ + c2·ξ² + c3·ξ³ with ξ = x − origin.
    Poly { origin: f64, c: [f64; 4] },
    /// amp·sin(k·(x − origin) + phase).
    Sine {
        origin: f64,
        amp: f64,
        k: f64,
        phase: f64,
    },
}

impl Func {
    #[inline]
    pub fn eval(&self, x: f64) -> f64 {
        match *self {
            Func::Poly { origin, c } => {
                let s = x - origin;
                c[0] + s * (c[1] + s * (c[2] + s * c[3]))
            }
            Func::Sine {
                origin,
                amp,
                k,
                phase,
            } => amp * (k * (x - origin) + phase).sin(),
        }
    }

    /// First derivative.
    pub fn d1(&self) -> Func {
        match *self {
            Func::Poly { origin, c } => Func::Poly {
                origin,
                c: [c[1], 2.0 * c[2], 3.0 * c[3], 0.0],
            },
            Func::Sine {
                origin,
                amp,
                k,
                phase,
            } => Func::Sine {
                origin,
                amp: amp * k,
                k,
                phase: phase + 0.5 * PI,
            },
        }
    }

    /// Second derivative (exact, without a π phase shift for the sine).
    pub fn d2(&self) -> Func {
        match *self {
            Func::Poly { origin, c } => Func::Poly {
                origin,
                c: [2.0 * c[2], 6.0 * c[3], 0.0, 0.0],
            },
            Func::Sine {
                origin,
                amp,
                k,
                phase,
            } => Func::Sine {
                origin,
                amp: -amp * k * k,
                k,
                phase,
            },
        }
    }

    fn is_zero(&self) -> bool {
        match *self {
            Func::Poly { c, .. } => c == [0.0; 4],
            Func::Sine { amp, .. } => amp == 0.0,
        }
    }
}

/// Gauss–Legendre nodes and weights on [−1, 1] (n = 16, exact to degree 31).
fn gauss16() -> &'static ([f64; 16], [f64; 16]) {
    static GL: OnceLock<([f64; 16], [f64; 16])> = OnceLock::new();
    GL.get_or_init(gauss_legendre::<16>)
}

fn gauss_legendre<const N: usize>() -> ([f64; N], [f64; N]) {
    let mut x = [0.0; N];
    let mut w = [0.0; N];
    for i in 0..N {
        // Newton on P_N from the Chebyshev-like initial guess.
        let mut z = (PI * (i as f64 + 0.75) / (N as f64 + 0.5)).cos();
        let mut dp = 0.0;
        for _ in 0..100 {
            let (mut p0, mut p1) = (1.0, z);
            for n in 2..=N {
                let p2 = ((2 * n - 1) as f64 * z * p1 - (n - 1) as f64 * p0) / n as f64;
                p0 = p1;
                p1 = p2;
            }
            dp = N as f64 * (z * p1 - p0) / (z * z - 1.0);
            let dz = p1 / dp;
            z -= dz;
            if dz.abs() < 1e-16 {
                break;
            }
        }
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

fn gauss_integrate(f: &Func, g: &Func, a: f64, b: f64) -> f64 {
    let (xs, ws) = gauss16();
    let (m, h) = (0.5 * (a + b), 0.5 * (b - a));
    xs.iter()
        .zip(ws)
        .map(|(&t, &w)| w * f.eval(m + h * t) * g.eval(m + h * t))
        .sum::<f64>()
        * h
}

/// sin(z)/z, accurate near 0.
#[inline]
fn sinc(z: f64) -> f64 {
    if z.abs() < 1e-4 {
        1.0 - z * z / 6.0
    } else {
        z.sin() / z
    }
}

/// ∫_a^b cos(κx + ψ) dx, stable for κ → 0.
fn int_cos(kappa: f64, psi: f64, a: f64, b: f64) -> f64 {
    let h = b - a;
    h * (kappa * 0.5 * (a + b) + psi).cos() * sinc(0.5 * kappa * h)
}

/// Exact ∫_a^b f(x)·g(x) dx of two piece functions.
pub fn integrate(f: &Func, g: &Func, a: f64, b: f64) -> f64 {
    if b <= a || f.is_zero() || g.is_zero() {
        return 0.0;
    }
    match (*f, *g) {
        (Func::Poly { .. }, Func::Poly { .. }) => gauss_integrate(f, g, a, b),
        (Func::Poly { .. }, Func::Sine { .. }) => poly_sine(f, g, a, b),
        (Func::Sine { .. }, Func::Poly { .. }) => poly_sine(g, f, a, b),
        (
            Func::Sine {
                origin: o1,
                amp: a1,
                k: k1,
                phase: p1,
            },
            Func::Sine {
                origin: o2,
                amp: a2,
                k: k2,
                phase: p2,
            },
        ) => {
            // sin θ1 sin θ2 = ½[cos(θ1 − θ2) − cos(θ1 + θ2)], θ = kx + (phase − k·origin).
            let (c1, c2) = (p1 - k1 * o1, p2 - k2 * o2);
            0.5 * a1 * a2 * (int_cos(k1 - k2, c1 - c2, a, b) - int_cos(k1 + k2, c1 + c2, a, b))
        }
    }
}

/// ∫ p(x)·A sin(kx + φ) by parts (p cubic): [−p cos/k + p′ sin/k² + p″ cos/k³ − p‴ sin/k⁴].
fn poly_sine(p: &Func, s: &Func, a: f64, b: f64) -> f64 {
    let Func::Sine {
        origin,
        amp,
        k,
        phase,
    } = *s
    else {
        unreachable!()
    };
    if (k * (b - a)).abs() < 1.0 {
        return gauss_integrate(p, s, a, b);
    }
    let (p1, p2) = (p.d1(), p.d2());
    let p3 = p2.d1();
    let prim = |x: f64| {
        let th = k * (x - origin) + phase;
        let (sn, cs) = th.sin_cos();
        -p.eval(x) * cs / k + p1.eval(x) * sn / (k * k) + p2.eval(x) * cs / (k * k * k)
            - p3.eval(x) * sn / (k * k * k * k)
    };
    amp * (prim(b) - prim(a))
}

/// Basis functions of a layer on one interval: (local DOF, function) pairs.
#[derive(Clone, Debug)]
pub struct Piece {
    pub a: f64,
    pub b: f64,
    pub funcs: Vec<(usize, Func)>,
}

/// The four cubic Hermite functions on [0, ℓ] as polynomials in ξ = x − origin: end
/// displacement and rotation at ξ = 0 (h1, h2) and at ξ = ℓ (h3, h4).
pub fn hermite(origin: f64, l: f64) -> [Func; 4] {
    let (l2, l3) = (l * l, l * l * l);
    [
        Func::Poly {
            origin,
            c: [1.0, 0.0, -3.0 / l2, 2.0 / l3],
        },
        Func::Poly {
            origin,
            c: [0.0, 1.0, -2.0 / l, 1.0 / l2],
        },
        Func::Poly {
            origin,
            c: [0.0, 0.0, 3.0 / l2, -2.0 / l3],
        },
        Func::Poly {
            origin,
            c: [0.0, 0.0, -1.0 / l, 1.0 / l2],
        },
    ]
}

#[inline]
fn hermite_values(xi: f64, l: f64) -> [f64; 4] {
    let s = xi / l;
    let (s2, s3) = (s * s, s * s * s);
    [
        1.0 - 3.0 * s2 + 2.0 * s3,
        l * (s - 2.0 * s2 + s3),
        3.0 * s2 - 2.0 * s3,
        l * (s3 - s2),
    ]
}

/// A shape vector: `values` of the contiguous layer DOFs `start..start + values.len()`.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    pub start: usize,
    pub values: Vec<f64>,
}

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
fn tail_sum(p: f64, q: f64, s: i32, n: usize) -> f64 {
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
    proj: [Vec<f64>; 2],
    /// Norms making ρA∫g_k² = 1.
    mu: [f64; 2],
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
        let th = PI * x / l;
        let (s1, c1) = th.sin_cos();
        let two_c = 2.0 * c1;
        let (mut prev, mut cur) = (0.0, s1);
        let (mut p2, mut p4) = (0.0, 0.0);
        for (n, v) in out[4..4 + self.n_sines].iter_mut().enumerate() {
            *v = self.scale * cur;
            p2 += self.proj[0][n] * cur;
            p4 += self.proj[1][n] * cur;
            let next = two_c * cur - prev;
            prev = cur;
            cur = next;
        }
        out[0] = 1.0 - x / l;
        out[1] = x / l;
        out[2] = (h[1] - p2) / self.mu[0];
        out[3] = (h[3] - p4) / self.mu[1];
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

/// A finite-element mesh of beam elements with two DOFs per node: node i has DOFs 2i
/// (displacement w, positive downward) and 2i+1 (rotation: w′ for Euler–Bernoulli, the
/// cross-section rotation ψ for Timoshenko). Nodes may be spaced unevenly (they are placed on
/// the coupling points of the layer, see `FemBasis::aligned`).
///
/// Each element interpolates w with the *interdependent* cubics of a Timoshenko element
/// (w cubic, ψ quadratic, their coefficients tied so that the shear strain γ = w′ − ψ is
/// constant and the homogeneous static equations hold exactly): free of shear locking, exact
/// nodal values for static point loads, and equal to the cubic Hermite functions when the
/// element's shear parameter φ = 12EI/(κGAℓ²) is 0 (Euler–Bernoulli).
#[derive(Clone, Debug)]
pub struct FemBasis {
    /// Node positions, increasing, from the layer's start to its end (0 and L unless the
    /// layer covers part of the structure).
    pub nodes: Vec<f64>,
    /// Shear parameter φ of each element (0 for Euler–Bernoulli).
    pub phi: Vec<f64>,
}

impl FemBasis {
    /// `n` equal elements over [start, end].
    pub fn uniform(start: f64, end: f64, n: usize) -> Self {
        let nodes = (0..=n)
            .map(|i| {
                if i == n {
                    end
                } else {
                    start + (end - start) * i as f64 / n as f64
                }
            })
            .collect();
        Self {
            nodes,
            phi: vec![0.0; n],
        }
    }

    /// Nodes on every breakpoint within (start, end) (coupling points; the ends are added)
    /// and each interval between breakpoints split into the fewest equal elements no longer
    /// than `max_len`. Breakpoints closer than 1e-9·end merge.
    pub fn aligned(start: f64, end: f64, max_len: f64, breakpoints: &[f64]) -> Self {
        let tol = 1e-9 * end.abs().max(end - start);
        let mut bp: Vec<f64> = breakpoints
            .iter()
            .copied()
            .filter(|&x| x > start + tol && x < end - tol)
            .collect();
        bp.sort_by(f64::total_cmp);
        let mut nodes = vec![start];
        for &x in bp.iter().chain(std::iter::once(&end)) {
            let a = *nodes.last().expect("starts with the start");
            if x - a <= tol {
                continue;
            }
            let n = ((x - a) / max_len * (1.0 - 1e-12)).ceil().max(1.0) as usize;
            nodes.extend((1..=n).map(|k| {
                if k == n {
                    x
                } else {
                    a + (x - a) * k as f64 / n as f64
                }
            }));
        }
        let n = nodes.len() - 1;
        Self {
            nodes,
            phi: vec![0.0; n],
        }
    }

    /// First node (m).
    pub fn start(&self) -> f64 {
        self.nodes[0]
    }

    /// Last node (m).
    pub fn end(&self) -> f64 {
        *self.nodes.last().expect("a mesh has nodes")
    }

    /// x lies on the mesh (its shape functions are zero elsewhere).
    #[inline]
    pub fn covers(&self, x: f64) -> bool {
        x >= self.start() && x <= self.end()
    }

    /// Cuts the mesh at each of `joints` (each a node, up to the breakpoints' merging
    /// tolerance): the node nearest to it is doubled, with a zero-length element between the
    /// two, so nothing passes from one side to the other. A point at a joint belongs to the
    /// element on its right.
    pub fn with_joints(mut self, joints: &[f64]) -> Self {
        for &x in joints {
            let i = (0..self.nodes.len())
                .min_by(|&a, &b| {
                    (self.nodes[a] - x)
                        .abs()
                        .total_cmp(&(self.nodes[b] - x).abs())
                })
                .expect("a mesh has nodes");
            self.nodes.insert(i, self.nodes[i]);
            self.phi.insert(i, 0.0);
        }
        self
    }

    /// Element e has no length (a joint).
    #[inline]
    fn is_joint(&self, e: usize) -> bool {
        self.nodes[e + 1] == self.nodes[e]
    }

    /// Makes the elements Timoshenko elements of a beam with bending stiffness `ei` and shear
    /// stiffness `kga` = κGA.
    pub fn with_shear(mut self, ei: f64, kga: f64) -> Self {
        for e in 0..self.n_elements() {
            let l = self.nodes[e + 1] - self.nodes[e];
            if l > 0.0 {
                self.phi[e] = 12.0 * ei / (kga * l * l);
            }
        }
        self
    }

    /// The elements with a length (all but the joints').
    pub fn elements(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n_elements()).filter(|&e| !self.is_joint(e))
    }

    pub fn n_elements(&self) -> usize {
        self.nodes.len() - 1
    }

    pub fn n_dofs(&self) -> usize {
        2 * self.nodes.len()
    }

    /// Element containing x (an element owns its left node; the last one also owns x = L).
    #[inline]
    pub fn element_of(&self, x: f64) -> usize {
        let ne = self.n_elements();
        self.nodes
            .partition_point(|&n| n <= x)
            .saturating_sub(1)
            .min(ne - 1)
    }

    /// (w, ψ) interpolation of element e as polynomials in ξ = x − x_e: the displacement
    /// functions and the rotation functions of its four DOFs.
    pub fn element_funcs(&self, e: usize) -> ([Func; 4], [Func; 4]) {
        let (a, l) = (self.nodes[e], self.nodes[e + 1] - self.nodes[e]);
        let [w, psi] = interdependent(l, self.phi[e]);
        let f = |c: [f64; 4]| Func::Poly { origin: a, c };
        (w.map(f), psi.map(f))
    }

    /// Static deflection at x under a unit load at x with the nodes of x's element held fixed
    /// (m/N): the part of a point load's deflection that the element's interpolation cannot
    /// carry. `ei` = EI; the shear stiffness enters through the elements' φ. Zero on a node.
    ///
    /// It is the deflection of the element's span clamped at both ends: with a node at x the
    /// element splits into two whose end stiffnesses (closed form, exact for Timoshenko
    /// beams) condense onto x. Euler–Bernoulli: a³b³/(3EIℓ³).
    pub fn local_flexibility(&self, ei: f64, x: f64) -> f64 {
        if !self.covers(x) {
            return 0.0;
        }
        self.local_flexibility_in(self.element_of(x), ei, x)
    }

    /// `local_flexibility` at x in element e.
    fn local_flexibility_in(&self, e: usize, ei: f64, x: f64) -> f64 {
        let (a, b) = (x - self.nodes[e], self.nodes[e + 1] - x);
        let l = a + b;
        if a <= 1e-12 * l || b <= 1e-12 * l {
            return 0.0;
        }
        // φ scales as 1/ℓ²: the sub-elements' φ from the element's.
        let phi_l2 = self.phi[e] * l * l;
        let end = |h: f64, sign: f64| {
            let phi = phi_l2 / (h * h);
            let c = ei / ((1.0 + phi) * h * h * h);
            (12.0 * c, sign * 6.0 * h * c, (4.0 + phi) * h * h * c)
        };
        // Right end of [x_e, x] and left end of [x, x_e+1].
        let (ka, kb) = (end(a, -1.0), end(b, 1.0));
        let (k11, k12, k22) = (ka.0 + kb.0, ka.1 + kb.1, ka.2 + kb.2);
        k22 / (k11 * k22 - k12 * k12)
    }

    /// Pieces of the patch [x − a, x + a] cut at the nodes (and at the mesh's ends), each with
    /// its element, for integrals over a distributed contact.
    fn patch_pieces(&self, x: f64, a: f64) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let (lo, hi) = ((x - a).max(self.start()), (x + a).min(self.end()));
        let (e0, e1) = (self.element_of(lo), self.element_of(hi));
        (e0..=e1).filter(move |_| hi > lo).filter_map(move |e| {
            let (p, q) = (lo.max(self.nodes[e]), hi.min(self.nodes[e + 1]));
            (q > p).then_some((e, p, q))
        })
    }

    /// Σ over the patch's Gauss points of w·q(s)·f(e, x + s), normalised by the share of the
    /// load on the structure: q(s) = 1 − s²/a² is the Hertz line load (the pressure of an
    /// elliptical contact integrated across the rail head) along the rail.
    fn patch_average(&self, x: f64, a: f64, mut f: impl FnMut(usize, f64, f64)) {
        let (nodes, weights) = gauss16();
        let mut total = 0.0;
        for (_, p, q) in self.patch_pieces(x, a) {
            let (m, h) = (0.5 * (p + q), 0.5 * (q - p));
            for (t, w) in nodes.iter().zip(weights) {
                let s = (m + h * t - x) / a;
                total += w * h * (1.0 - s * s);
            }
        }
        for (e, p, q) in self.patch_pieces(x, a) {
            let (m, h) = (0.5 * (p + q), 0.5 * (q - p));
            for (t, w) in nodes.iter().zip(weights) {
                let xs = m + h * t;
                let s = (xs - x) / a;
                f(e, xs, w * h * (1.0 - s * s) / total);
            }
        }
    }

    /// Displacement shape vector of a unit load spread over the Hertz patch of half-length `a`
    /// centred at x: ∫N(x + s)·q(s)ds/∫q(s)ds, exact (16 Gauss points per element piece for a
    /// quintic integrand). It covers the DOFs of every element the patch touches; `out.values`
    /// is resized to them (no allocation once it has the capacity).
    /// A patch wholly off the mesh has a zero shape.
    pub fn patch_into(&self, x: f64, a: f64, out: &mut Shape) {
        let (lo, hi) = ((x - a).max(self.start()), (x + a).min(self.end()));
        let (e0, e1) = (self.element_of(lo), self.element_of(hi.max(lo)));
        out.start = 2 * e0;
        out.values.clear();
        out.values.resize(2 * (e1 - e0 + 2), 0.0);
        let values = &mut out.values;
        // The element's coefficients once per piece, not per Gauss point.
        let mut element = (usize::MAX, [[0.0; 4]; 4]);
        self.patch_average(x, a, |e, xs, w| {
            if element.0 != e {
                element = (
                    e,
                    interdependent(self.nodes[e + 1] - self.nodes[e], self.phi[e])[0],
                );
            }
            let wf = &element.1;
            let xi = xs - self.nodes[e];
            for (j, c) in wf.iter().enumerate() {
                values[2 * (e - e0) + j] += w * (c[0] + xi * (c[1] + xi * (c[2] + xi * c[3])));
            }
        });
    }

    /// `local_flexibility` averaged over the Hertz patch with the weight of its line load
    /// (m/N). An upper bound of the patch's own local flexibility (the double average of the
    /// clamped element's Green's function), by at most the shear deflection of a patch
    /// length, about 1 % of the Hertz compliance for a 60 kg rail.
    pub fn patch_flexibility(&self, ei: f64, x: f64, a: f64) -> f64 {
        let mut f = 0.0;
        self.patch_average(x, a, |e, xs, w| {
            f += w * self.local_flexibility_in(e, ei, xs)
        });
        f
    }

    /// Most shape-vector entries of a patch of half-length `a` anywhere on the mesh.
    pub fn patch_len(&self, a: f64) -> usize {
        let shortest = self
            .elements()
            .map(|e| self.nodes[e + 1] - self.nodes[e])
            .fold(f64::INFINITY, f64::min);
        2 * ((2.0 * a / shortest).ceil() as usize + 2)
    }

    pub fn pieces(&self) -> Vec<Piece> {
        self.elements()
            .map(|e| Piece {
                a: self.nodes[e],
                b: self.nodes[e + 1],
                funcs: self
                    .element_funcs(e)
                    .0
                    .into_iter()
                    .enumerate()
                    .map(|(j, f)| (2 * e + j, f))
                    .collect(),
            })
            .collect()
    }
}

/// Coefficients (in powers of ξ, 0 ≤ ξ ≤ ℓ) of the interdependent-interpolation element:
/// [w functions, ψ functions] of the DOFs (w₁, ψ₁, w₂, ψ₂), μ = 1/(1 + φ), s = ξ/ℓ:
///   w:  μ(2s³ − 3s² − φs + 1 + φ),  ℓμ(s³ − (2 + φ/2)s² + (1 + φ/2)s),
///       −μ(2s³ − 3s² − φs),          ℓμ(s³ − (1 − φ/2)s² − (φ/2)s);
///   ψ:  (6μ/ℓ)(s² − s),  μ(3s² − (4 + φ)s + 1 + φ),  −(6μ/ℓ)(s² − s),  μ(3s² − (2 − φ)s).
fn interdependent(l: f64, phi: f64) -> [[[f64; 4]; 4]; 2] {
    let mu = 1.0 / (1.0 + phi);
    // Polynomials in s, then scaled to powers of ξ = ℓ·s.
    let ws = [
        [1.0 + phi, -phi, -3.0, 2.0].map(|c| mu * c),
        [0.0, 1.0 + 0.5 * phi, -(2.0 + 0.5 * phi), 1.0].map(|c| l * mu * c),
        [0.0, phi, 3.0, -2.0].map(|c| mu * c),
        [0.0, -0.5 * phi, -(1.0 - 0.5 * phi), 1.0].map(|c| l * mu * c),
    ];
    let ps = [
        [0.0, -1.0, 1.0, 0.0].map(|c| 6.0 * mu / l * c),
        [1.0 + phi, -(4.0 + phi), 3.0, 0.0].map(|c| mu * c),
        [0.0, 1.0, -1.0, 0.0].map(|c| 6.0 * mu / l * c),
        [0.0, -(2.0 - phi), 3.0, 0.0].map(|c| mu * c),
    ];
    let scale = |p: [f64; 4]| [p[0], p[1] / l, p[2] / (l * l), p[3] / (l * l * l)];
    [ws.map(scale), ps.map(scale)]
}

/// The basis of one layer.
#[derive(Clone, Debug)]
pub enum LayerBasis {
    Modal(ModalBasis),
    Fem(FemBasis),
}

impl LayerBasis {
    pub fn n_dofs(&self) -> usize {
        match self {
            LayerBasis::Modal(b) => b.n_dofs(),
            LayerBasis::Fem(b) => b.n_dofs(),
        }
    }

    /// Integration pieces (FEM only; modal Gram blocks are computed analytically).
    pub fn pieces(&self) -> Vec<Piece> {
        match self {
            LayerBasis::Modal(_) => Vec::new(),
            LayerBasis::Fem(b) => b.pieces(),
        }
    }

    /// Largest number of nonzeros of a shape vector.
    pub fn shape_len(&self) -> usize {
        match self {
            LayerBasis::Modal(b) => b.n_dofs(),
            LayerBasis::Fem(_) => 4,
        }
    }

    /// Displacement shape vector N(x) (layer-local DOF numbering). `out.values` must have
    /// length `shape_len()`; it is overwritten without allocating.
    #[inline]
    pub fn eval(&self, x: f64, out: &mut Shape) {
        match self {
            LayerBasis::Modal(b) => {
                out.start = 0;
                if (0.0..=b.length).contains(&x) {
                    b.eval_into(x, &mut out.values);
                } else {
                    out.values.fill(0.0);
                }
            }
            LayerBasis::Fem(b) if !b.covers(x) => {
                out.start = 0;
                out.values.fill(0.0);
            }
            LayerBasis::Fem(b) => {
                let e = b.element_of(x);
                let (a, l) = (b.nodes[e], b.nodes[e + 1] - b.nodes[e]);
                out.start = 2 * e;
                let xi = x - a;
                for (o, c) in out.values.iter_mut().zip(&interdependent(l, b.phi[e])[0]) {
                    *o = c[0] + xi * (c[1] + xi * (c[2] + xi * c[3]));
                }
            }
        }
    }

    pub fn shape(&self, x: f64) -> Shape {
        let mut s = Shape {
            start: 0,
            values: vec![0.0; self.shape_len()],
        };
        self.eval(x, &mut s);
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * (1.0 + a.abs().max(b.abs()))
    }

    #[test]
    fn gauss_legendre_is_exact_for_polynomials() {
        let f = Func::Poly {
            origin: 0.0,
            c: [1.0, 2.0, 3.0, 4.0],
        };
        let g = Func::Poly {
            origin: 1.0,
            c: [0.5, -1.0, 0.0, 2.0],
        };
        // Reference by expanding into monomials and integrating exactly on [0, 2].
        let n = 2000;
        let h = 2.0 / n as f64;
        // Simpson with many points as an independent check.
        let mut s = 0.0;
        for i in 0..=n {
            let x = i as f64 * h;
            let w = if i == 0 || i == n {
                1.0
            } else if i % 2 == 1 {
                4.0
            } else {
                2.0
            };
            s += w * f.eval(x) * g.eval(x);
        }
        s *= h / 3.0;
        assert!(close(integrate(&f, &g, 0.0, 2.0), s, 1e-10));
    }

    #[test]
    fn sine_products_match_closed_forms() {
        let l = 160.0;
        let b = ModalBasis::new(l, 2.0 / l, 10); // scale = 1
        for m in 1..=10 {
            for n in 1..=10 {
                let v = integrate(&b.sine(m), &b.sine(n), 0.0, l);
                let want = if m == n { l / 2.0 } else { 0.0 };
                assert!((v - want).abs() < 1e-10, "m={m} n={n} v={v}");
            }
        }
    }

    #[test]
    fn poly_sine_matches_quadrature() {
        let l = 3.0;
        let p = Func::Poly {
            origin: 0.5,
            c: [0.3, -1.0, 0.7, 0.2],
        };
        for &(k, ph) in &[(0.1, 0.3), (2.0, 0.0), (25.0, 1.1)] {
            let s = Func::Sine {
                origin: 0.2,
                amp: 1.7,
                k,
                phase: ph,
            };
            let n = 20000;
            let h = l / n as f64;
            let mut q = 0.0;
            for i in 0..=n {
                let x = i as f64 * h;
                let w = if i == 0 || i == n {
                    1.0
                } else if i % 2 == 1 {
                    4.0
                } else {
                    2.0
                };
                q += w * p.eval(x) * s.eval(x);
            }
            q *= h / 3.0;
            assert!(close(integrate(&p, &s, 0.0, l), q, 1e-9), "k={k}");
        }
    }

    /// Gauss–Legendre reference integrals of the modal basis: the analytic Gram blocks must
    /// match them, and the basis must span the Hermite cubics (h2 is reproduced exactly).
    #[test]
    fn modal_gram_matches_quadrature_and_spans_the_cubics() {
        let (l, rho_a) = (40.0, 3.0);
        let a = ModalBasis::new(l, rho_a, 12);
        let b = ModalBasis::new(l, 5.0, 17);
        let (xs, ws) = gauss_legendre::<16>();
        let n_int = 400;
        let pts: Vec<(f64, f64)> = (0..n_int)
            .flat_map(|e| {
                let (x0, h) = (e as f64 * l / n_int as f64, l / n_int as f64);
                xs.iter()
                    .zip(ws)
                    .map(move |(&t, w)| (x0 + 0.5 * h * (t + 1.0), 0.5 * h * w))
                    .collect::<Vec<_>>()
            })
            .collect();
        let d2 = |bs: &ModalBasis, x: f64| {
            let hh = 1e-3;
            let (mut p, mut m, mut c) = (
                vec![0.0; bs.n_dofs()],
                vec![0.0; bs.n_dofs()],
                vec![0.0; bs.n_dofs()],
            );
            bs.eval_into(x + hh, &mut p);
            bs.eval_into(x - hh, &mut m);
            bs.eval_into(x, &mut c);
            (0..bs.n_dofs())
                .map(|i| (p[i] - 2.0 * c[i] + m[i]) / (hh * hh))
                .collect::<Vec<_>>()
        };
        for curvature in [false, true] {
            let g = ModalBasis::gram(&a, &b, curvature);
            let (mut va, mut vb) = (vec![0.0; a.n_dofs()], vec![0.0; b.n_dofs()]);
            let mut q = vec![0.0; g.len()];
            for &(x, w) in &pts {
                if curvature {
                    va = d2(&a, x);
                    vb = d2(&b, x);
                } else {
                    a.eval_into(x, &mut va);
                    b.eval_into(x, &mut vb);
                }
                for i in 0..a.n_dofs() {
                    for j in 0..b.n_dofs() {
                        q[i * b.n_dofs() + j] += w * va[i] * vb[j];
                    }
                }
            }
            let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, (x, y)) in g.iter().zip(&q).enumerate() {
                let tol = if curvature { 2e-5 } else { 1e-9 };
                assert!(
                    (x - y).abs() < tol * scale,
                    "curv={curvature} entry {i}: {x} vs {y}"
                );
            }
        }
        // Unit modal mass of g3, g4 and of the sines.
        let m = ModalBasis::gram(&a, &a, false);
        let n = a.n_dofs();
        for i in 2..n {
            assert!((rho_a * m[i * n + i] - 1.0).abs() < 1e-12, "dof {i}");
        }
        // h2 = μ·g3 + projection: reconstruct at a few points.
        let mut v = vec![0.0; n];
        for &x in &[0.3, 7.0, 20.0, 39.9] {
            a.eval_into(x, &mut v);
            let proj: f64 = (0..a.n_sines)
                .map(|k| a.proj[0][k] * v[4 + k] / a.scale)
                .sum();
            let h2 = hermite_values(x, l)[1];
            assert!((a.mu[0] * v[2] + proj - h2).abs() < 1e-11 * l);
        }
    }

    #[test]
    fn recurrence_matches_direct_sines() {
        let b = ModalBasis::new(160.0, 60.0, 220);
        let mut out = vec![0.0; b.n_dofs()];
        for &x in &[0.0, 0.37, 80.0, 123.456, 160.0] {
            b.eval_into(x, &mut out);
            for n in 1..=220 {
                let want = b.sine(n).eval(x);
                assert!((out[3 + n] - want).abs() < 1e-12 * b.scale, "x={x} n={n}");
            }
        }
    }

    #[test]
    fn tail_sums_match_direct_summation() {
        for s in [2, 4, 6] {
            for n in [1usize, 7, 120, 1000] {
                let direct: f64 = ((n + 1)..4_000_000)
                    .rev()
                    .map(|k| (1.0 + 0.5 * if k % 2 == 0 { 1.0 } else { -1.0 }) / (k as f64).powi(s))
                    .sum();
                let rest = if s == 2 { 1.0 / 4.0e6 } else { 0.0 };
                let t = tail_sum(1.0, 0.5, s, n);
                assert!(
                    (t - direct - rest).abs() < 1e-7 * t,
                    "s={s} n={n}: {t} vs {direct}"
                );
            }
        }
    }

    #[test]
    fn hermite_end_conditions() {
        let l = 2.5;
        let h = hermite(1.0, l);
        let want = [
            [1.0, 0.0, 0.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
            [0.0, 0.0, 0.0, 1.0],
        ];
        for (j, f) in h.iter().enumerate() {
            let d = f.d1();
            let got = [f.eval(1.0), d.eval(1.0), f.eval(1.0 + l), d.eval(1.0 + l)];
            for i in 0..4 {
                assert!((got[i] - want[j][i]).abs() < 1e-12, "h{} cond {i}", j + 1);
            }
        }
    }

    /// A rail mesh like the converged preset's: Timoshenko elements of 32 mm with a node on
    /// every fastener, one shorter element to exercise uneven nodes.
    fn rail_mesh() -> FemBasis {
        let mut nodes = FemBasis::uniform(0.0, 1.28, 40).nodes;
        nodes.insert(21, 0.6545);
        FemBasis {
            phi: vec![0.0; nodes.len() - 1],
            nodes,
        }
        .with_shear(6.625e6, 2.5e8)
    }

    /// Brute force: the midpoint rule over the patch on 200 000 points of the point shape
    /// (a second quadrature that never splits at the nodes).
    fn brute_patch(mesh: &FemBasis, x: f64, a: f64, mut f: impl FnMut(f64, f64)) {
        let n = 200_000;
        let h = 2.0 * a / n as f64;
        let w: Vec<f64> = (0..n)
            .map(|i| {
                let s = (-a + (i as f64 + 0.5) * h) / a;
                let xs = x + s * a;
                if mesh.covers(xs) { 1.0 - s * s } else { 0.0 }
            })
            .collect();
        let total: f64 = w.iter().sum();
        for (i, wi) in w.iter().enumerate() {
            f(x - a + (i as f64 + 0.5) * h, wi / total);
        }
    }

    #[test]
    fn patch_shape_is_the_load_weighted_average_of_the_point_shape() {
        let mesh = rail_mesh();
        let basis = LayerBasis::Fem(mesh.clone());
        let a = 6.4e-3;
        // Inside one element, across a node, across the uneven node, at the end.
        for &x in &[0.101, 0.128, 0.6545 + 0.002, 0.64, 1.277] {
            let mut got = Shape::default();
            mesh.patch_into(x, a, &mut got);
            assert!(got.values.len() <= mesh.patch_len(a));
            let mut want = vec![0.0; mesh.n_dofs()];
            brute_patch(&mesh, x, a, |xs, w| {
                let s = basis.shape(xs.min(mesh.end()));
                for (k, v) in s.values.iter().enumerate() {
                    want[s.start + k] += w * v;
                }
            });
            for (k, w) in want.iter().enumerate() {
                let g = k
                    .checked_sub(got.start)
                    .and_then(|j| got.values.get(j))
                    .copied()
                    .unwrap_or(0.0);
                assert!((g - w).abs() < 1e-6, "x={x} dof {k}: {g} vs {w}");
            }
        }
    }

    #[test]
    fn a_patch_sees_a_linear_field_at_its_centre() {
        // Nodal values of w = 2 + 3x (ψ = 3): the interdependent element interpolates it
        // exactly, and a symmetric load averages it to its value at the centre.
        let mesh = rail_mesh();
        let u: Vec<f64> = mesh
            .nodes
            .iter()
            .flat_map(|&x| [2.0 + 3.0 * x, 3.0])
            .collect();
        for &x in &[0.3, 0.64, 0.655] {
            let mut s = Shape::default();
            mesh.patch_into(x, 6.4e-3, &mut s);
            let w: f64 = s.values.iter().zip(&u[s.start..]).map(|(a, b)| a * b).sum();
            assert!((w - (2.0 + 3.0 * x)).abs() < 1e-12, "{w}");
        }
    }

    #[test]
    fn patch_flexibility_is_the_weighted_average_of_the_local_flexibility() {
        let mesh = rail_mesh();
        for &x in &[0.101, 0.128, 0.6545 + 0.002] {
            let got = mesh.patch_flexibility(6.625e6, x, 6.4e-3);
            let mut want = 0.0;
            brute_patch(&mesh, x, 6.4e-3, |xs, w| {
                want += w * mesh.local_flexibility(6.625e6, xs)
            });
            assert!((got - want).abs() < 1e-6 * want, "x={x}: {got} vs {want}");
        }
    }
}
