//! The exact step of one complex mode, q̇ = λq + w·g(t), under a force linear over the step:
//!
//!   Q_{n+1} = e^{z}Q_n + h·[(φ₁ − φ₂)(z)·g_n + φ₂(z)·g_{n+1}]·w,   z = λh,
//!
//! with φ₁(z) = (e^z − 1)/z, φ₂(z) = (e^z − 1 − z)/z²: no period error at any Δt. The linear
//! interpolation of the force samples filters the force's spectrum by sinc²(ωh/2) (−3.3 % at
//! 2 kHz, h = 5e-5 s): a loss at the forcing frequency, not at the mode's, which the run's
//! records undo (`run::records`).

use super::Reduction;

/// A complex number (re, im).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct C(pub f64, pub f64);

impl C {
    pub fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    pub fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    pub fn scale(self, s: f64) -> C {
        C(self.0 * s, self.1 * s)
    }
    pub fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    pub fn exp(self) -> C {
        let r = self.0.exp();
        C(r * self.1.cos(), r * self.1.sin())
    }
}

/// φ₁(z) = (e^z − 1)/z and φ₂(z) = (e^z − 1 − z)/z², by their Taylor series near 0 (where
/// the closed forms cancel) and in closed form elsewhere.
pub(super) fn phi12(z: C) -> (C, C) {
    let r = (z.0 * z.0 + z.1 * z.1).sqrt();
    if r < 0.5 {
        // Σ z^k/(k+1)! and Σ z^k/(k+2)!; 0.5^24/24! is far below rounding.
        let (mut p1, mut p2) = (C(0.0, 0.0), C(0.0, 0.0));
        let mut term = C(1.0, 0.0); // z^k/k!
        for k in 0..24 {
            p1 = p1.add(term.scale(1.0 / (k + 1) as f64));
            p2 = p2.add(term.scale(1.0 / ((k + 1) * (k + 2)) as f64));
            term = term.mul(z).scale(1.0 / (k + 1) as f64);
        }
        (p1, p2)
    } else {
        let e1 = z.exp().add(C(-1.0, 0.0));
        let p1 = e1.div(z);
        (p1, e1.add(z.scale(-1.0)).div(z.mul(z)))
    }
}

/// Per-mode constants of a run, padded like the reduction (inert modes all zero): e^{λh},
/// the weights a0, a1 of g_n and g_{n+1} (with w), λ and w. Split into real and imaginary
/// arrays so that the passes over the modes vectorise.
#[derive(Clone, Debug)]
pub(super) struct Coefficients {
    pub e: [Vec<f64>; 2],
    pub a0: [Vec<f64>; 2],
    pub a1: [Vec<f64>; 2],
    pub lam: [Vec<f64>; 2],
    pub w: Vec<f64>,
}

impl Coefficients {
    pub fn new(red: &Reduction, h: f64) -> Self {
        let n = red.stride;
        let zeros = || [vec![0.0; n], vec![0.0; n]];
        let (mut e, mut a0, mut a1) = (zeros(), zeros(), zeros());
        for j in 0..red.m {
            let z = C(red.lam_re[j] * h, red.lam_im[j] * h);
            let (p1, p2) = phi12(z);
            let s = red.weight[j] * h;
            for (arr, v) in [
                (&mut e, z.exp()),
                (&mut a0, p1.add(p2.scale(-1.0)).scale(s)),
                (&mut a1, p2.scale(s)),
            ] {
                arr[0][j] = v.0;
                arr[1][j] = v.1;
            }
        }
        Self {
            e,
            a0,
            a1,
            lam: [red.lam_re.clone(), red.lam_im.clone()],
            w: red.weight.clone(),
        }
    }

    pub fn a1_at(&self, j: usize) -> C {
        C(self.a1[0][j], self.a1[1][j])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact step of q̇ = λq + g(t) under a force linear over the step against the
    /// closed-form integral, for a slow, a fast and an overdamped mode.
    #[test]
    fn exact_modal_step_matches_the_closed_form() {
        for (lr, li, h) in [
            (-3.0, 20.0, 1e-4),
            (-900.0, 12000.0, 5e-5),
            (-8000.0, 0.0, 5e-5),
        ] {
            let lam = C(lr, li);
            let z = lam.scale(h);
            let (p1, p2) = phi12(z);
            let (g0, g1, q0) = (C(0.7, -0.2), C(-1.3, 0.4), C(0.25, 0.5));
            let q1 = z
                .exp()
                .mul(q0)
                .add(p1.add(p2.scale(-1.0)).scale(h).mul(g0))
                .add(p2.scale(h).mul(g1));
            // Closed form: q(h) = e^{λh}q0 + ∫ e^{λ(h−τ)}(g0 + (g1 − g0)τ/h)dτ
            //   = e^{λh}q0 + g0(e^{λh} − 1)/λ + (g1 − g0)(e^{λh} − 1 − λh)/(λ²h).
            let e = lam.scale(h).exp();
            let one = C(1.0, 0.0);
            let dg = g1.add(g0.scale(-1.0));
            let want = e.mul(q0).add(g0.mul(e.add(one.scale(-1.0)).div(lam))).add(
                dg.mul(
                    e.add(one.scale(-1.0))
                        .add(lam.scale(-h))
                        .div(lam.mul(lam).scale(h)),
                ),
            );
            let err = ((q1.0 - want.0).powi(2) + (q1.1 - want.1).powi(2)).sqrt();
            let size = (want.0.powi(2) + want.1.powi(2)).sqrt();
            assert!(err <= 1e-10 * size, "λ = {lr} + {li}i: {q1:?} vs {want:?}");
        }
    }

    /// Near z = 0 the series and the closed forms of φ₁, φ₂ agree where both are accurate.
    #[test]
    fn phi_series_and_closed_form_agree_at_the_switch() {
        let z = C(-0.3, 0.399);
        let (s1, s2) = phi12(z);
        let e1 = z.exp().add(C(-1.0, 0.0));
        let c1 = e1.div(z);
        let c2 = e1.add(z.scale(-1.0)).div(z.mul(z));
        for (a, b) in [(s1, c1), (s2, c2)] {
            assert!(
                (a.0 - b.0).abs() < 1e-13 && (a.1 - b.1).abs() < 1e-13,
                "{a:?} {b:?}"
            );
        }
    }
}
