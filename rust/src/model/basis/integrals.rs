//! Piece functions — a cubic polynomial or a scaled sine on an interval — with their
//! derivatives, the Hermite cubics, and the exact integral of a product of two: Gauss–Legendre
//! for polynomials (exact to degree 31), closed forms where a sine enters.

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
pub(super) fn gauss16() -> &'static ([f64; 16], [f64; 16]) {
    static GL: OnceLock<([f64; 16], [f64; 16])> = OnceLock::new();
    GL.get_or_init(gauss_legendre::<16>)
}

pub(super) fn gauss_legendre<const N: usize>() -> ([f64; N], [f64; N]) {
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
pub(super) fn hermite_values(xi: f64, l: f64) -> [f64; 4] {
    let s = xi / l;
    let (s2, s3) = (s * s, s * s * s);
    [
        1.0 - 3.0 * s2 + 2.0 * s3,
        l * (s - 2.0 * s2 + s3),
        3.0 * s2 - 2.0 * s3,
        l * (s3 - s2),
    ]
}
