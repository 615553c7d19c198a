//! The rail's residual under a load, as a filter (docs/synthesis.md, "The dynamic residual"):
//! the synthesis engine's, of the structure's truncated complex modes, and the substructured
//! engine's, of the interiors' truncated fixed-interface modes (docs/substructures.md).
//!
//! The truncated modes' part of the receptance at a load of shape s, expanded about s = 0, is
//! r₀ + r₁s + r₂s² (r_k = sᵀR_k s, the reduction's moments). The static residual keeps r₀
//! alone, which leaves the point receptance over a fastener 1.5 % low at 2 kHz (4 kHz cut-off):
//! the truncated modes there are the rail's local modes, damped by the fastener dashpots, and
//! their damping (r₁) and inertia (r₂) show well below their frequencies. The filter
//!
//!   h(s) = 1/(1 + αs + βs²),   α = −r₁/r₀,   β = α² − r₂/r₀,
//!
//! matches all three moments: the residual displacement is r₀·g with β·g̈ + α·ġ + g = F, a
//! damped oscillator (about 6–7 kHz, damping ratio 0.06–0.1, on the converged preset),
//! stepped exactly under the force linear over the step like the modes (`step`). A force held
//! constant passes unchanged (g = F).
//!
//! The filter must be passive (α, β > 0). Where the truncated modes are not well above the
//! band, as at a low cut-off that leaves heavily damped rail-on-pad modes and overdamped ones
//! out, or where a wheel's shape is ramped in at a rail end, the moments need not allow it: the
//! filter is then the highest-order passive one of the ladder 1/(1 + αs + βs²), 1/(1 + αs)
//! (α = −r₁/r₀ > 0, matching r₀ and r₁), 1 (the static residual).
//!
//! A residual r₀ < 0 is no flexibility of its own but a static correction: the complex modes of
//! a non-proportionally damped structure need not sum to less than K⁻¹, and near a free rail end
//! over a soft embankment the kept modes overshoot it (R₀'s diagonal measured down to −1.1e-9
//! m/N against 1.8e-9 m/N along the rail, 3-span viaduct between 50 m embankments at a 300 Hz
//! cut-off). It passes unfiltered, so the load's static flexibility stays exact; the load is
//! refused only when that whole flexibility, modes and residual, is not positive
//! (`Reduction::load_moments`).

use crate::error::{Result, VtbError};

/// The filter of one load (see the module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Filter {
    /// α (s) and β (s²).
    pub alpha: f64,
    pub beta: f64,
}

impl Filter {
    /// The filter of a load with residual moments r = (r₀, r₁, r₂), the highest-order passive
    /// one of the ladder (module documentation): `None` for the static residual (also when
    /// r₀ ≤ 0: a load beyond the rail, none, or a static correction, whose load the caller
    /// checks with `Reduction::load_moments`); β = 0 for the first-order filter. An error when
    /// the moments are not finite (`at` names the load in it).
    pub fn from_moments(r: [f64; 3], at: impl FnOnce() -> String) -> Result<Option<Self>> {
        if !r.iter().all(|x| x.is_finite()) {
            return Err(VtbError::Solver(format!(
                "the rail residual under {} has moments {:e}, {:e}, {:e}: not a residual \
                 flexibility (the reduction is corrupt or not of a stable structure)",
                at(),
                r[0],
                r[1],
                r[2]
            )));
        }
        if r[0] <= 0.0 {
            return Ok(None);
        }
        let alpha = -r[1] / r[0];
        let beta = alpha * alpha - r[2] / r[0];
        Ok(if !(alpha > 0.0 && alpha.is_finite()) {
            None
        } else if beta > 0.0 && beta.is_finite() {
            Some(Self { alpha, beta })
        } else {
            Some(Self { alpha, beta: 0.0 })
        })
    }

    /// Its exact step over `dt`.
    pub fn step(&self, dt: f64) -> FilterStep {
        let (a, b) = (self.alpha, self.beta);
        if b == 0.0 {
            // α·ġ + g = F: the rest decays by e^{−h/α}, and ġ = Ḟ − (g − g_p)/α.
            let e = (-dt / a).exp();
            return FilterStep {
                e: [[e, 0.0], [-e / a, 0.0]],
                alpha: a,
                dt,
                pass: false,
            };
        }
        // x = (g, ġ), ẋ = A·x + (0, F/β), A = [[0, 1], [−1/β, −α/β]]: eigenvalues μ ± δ and
        // e^{Ah} = e^{μh}·(cosh(δh)·I + sinh(δh)/δ·(A − μI)) (Cayley–Hamilton).
        let mu = -a / (2.0 * b);
        let d2 = mu * mu - 1.0 / b;
        let x = d2 * dt * dt;
        let emu = (mu * dt).exp();
        let (ch, sh) = if x.abs() < 1e-4 {
            // The series of cosh(√x) and sinh(√x)/√x, where the closed forms lose digits.
            (
                emu * (1.0 + x / 2.0 + x * x / 24.0 + x * x * x / 720.0),
                emu * dt * (1.0 + x / 6.0 + x * x / 120.0 + x * x * x / 5040.0),
            )
        } else if x > 0.0 {
            // Over-damped: both exponents μ ± δ are negative (δ < |μ|), so no overflow.
            let d = d2.sqrt();
            let (ep, em) = (((mu + d) * dt).exp(), ((mu - d) * dt).exp());
            ((ep + em) / 2.0, (ep - em) / (2.0 * d))
        } else {
            let w = (-d2).sqrt();
            (emu * (w * dt).cos(), emu * (w * dt).sin() / w)
        };
        FilterStep {
            e: [[ch - mu * sh, sh], [-sh / b, ch + mu * sh]],
            alpha: a,
            dt,
            pass: false,
        }
    }
}

/// One exact step of a filter (or of none: the force passes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterStep {
    e: [[f64; 2]; 2],
    alpha: f64,
    dt: f64,
    pass: bool,
}

impl FilterStep {
    /// The step of a load without a filter: g = F.
    pub fn pass(dt: f64) -> Self {
        Self {
            e: [[0.0; 2]; 2],
            alpha: 0.0,
            dt,
            pass: true,
        }
    }

    /// The state (g, ġ) at the end of the step from `x0`, the force going linearly from f0
    /// to f1. With the particular solution g_p = F(t) − α·Ḟ, ġ_p = Ḟ of the linear force, the
    /// rest decays by e^{Ah}.
    pub fn advance(&self, x0: [f64; 2], f0: f64, f1: f64) -> [f64; 2] {
        let rate = (f1 - f0) / self.dt;
        if self.pass {
            return [f1, rate];
        }
        let h = [x0[0] - f0 + self.alpha * rate, x0[1] - rate];
        let e = &self.e;
        [
            f1 - self.alpha * rate + e[0][0] * h[0] + e[0][1] * h[1],
            rate + e[1][0] * h[0] + e[1][1] * h[1],
        ]
    }
}

/// The residual filters of a set of wheels in W lanes, for an engine that adds the filtered
/// residual to a wheel's port (the substructured engine): each step, the wheel's filter from
/// its moments at its position (`begin`), the residual displacement there under no new force
/// (`free`) and per unit new force (`gain`), then the states under the solved forces (`end`).
#[derive(Clone, Debug)]
pub(crate) struct WheelFilters<const W: usize> {
    nw: usize,
    /// (g, ġ) of wheel w in lane c at the step's start, `[c·nw + w]`.
    state: Vec<[f64; 2]>,
    /// Their values at the step's end under no new force.
    free: Vec<[f64; 2]>,
    /// Per wheel: (g, ġ) at the step's end per unit new force, and r₀.
    gain: Vec<[f64; 2]>,
    r0: Vec<f64>,
}

impl<const W: usize> WheelFilters<W> {
    pub fn new(nw: usize) -> Self {
        Self {
            nw,
            state: vec![[0.0; 2]; W * nw],
            free: vec![[0.0; 2]; W * nw],
            gain: vec![[0.0; 2]; nw],
            r0: vec![0.0; nw],
        }
    }

    /// Wheel w's filter over the step `dt` from its moments r; `p` the forces at the step's
    /// start, `[c·nw + w]`. An error when the moments are not finite (`at` names the wheel).
    pub fn begin(
        &mut self,
        w: usize,
        r: [f64; 3],
        dt: f64,
        p: &[f64],
        at: impl FnOnce() -> String,
    ) -> Result<()> {
        let step = match Filter::from_moments(r, at)? {
            Some(f) => f.step(dt),
            None => FilterStep::pass(dt),
        };
        self.r0[w] = r[0];
        self.gain[w] = step.advance([0.0; 2], 0.0, 1.0);
        for c in 0..W {
            let i = c * self.nw + w;
            self.free[i] = step.advance(self.state[i], p[i], 0.0);
        }
        Ok(())
    }

    /// The residual displacement at wheel w of lane c at the step's end under no new force.
    pub fn free(&self, c: usize, w: usize) -> f64 {
        self.r0[w] * self.free[c * self.nw + w][0]
    }

    /// The residual displacement at wheel w per unit new force on it (its step compliance).
    pub fn gain(&self, w: usize) -> f64 {
        self.r0[w] * self.gain[w][0]
    }

    /// The states at the step's end under the solved forces `p`.
    pub fn end(&mut self, p: &[f64]) {
        for (i, (x, f)) in self.state.iter_mut().zip(&self.free).enumerate() {
            let g = self.gain[i % self.nw];
            *x = [g[0].mul_add(p[i], f[0]), g[1].mul_add(p[i], f[1])];
        }
    }

    pub fn wheels(&self) -> usize {
        self.nw
    }

    /// Lane c's filters holding the forces `p` at rest (g = F, ġ = 0).
    pub fn hold(&mut self, c: usize, p: &[f64]) {
        for (x, &f) in self.state[c * self.nw..(c + 1) * self.nw].iter_mut().zip(p) {
            *x = [f, 0.0];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// β·g̈ + α·ġ + g = F(t) by classical Runge–Kutta on a fine grid: an independent solution.
    fn rk4(f: &Filter, x0: [f64; 2], force: impl Fn(f64) -> f64, t_end: f64, n: usize) -> [f64; 2] {
        let h = t_end / n as f64;
        let rhs = |t: f64, x: [f64; 2]| [x[1], (force(t) - x[0] - f.alpha * x[1]) / f.beta];
        let mut x = x0;
        for i in 0..n {
            let t = i as f64 * h;
            let k1 = rhs(t, x);
            let k2 = rhs(
                t + h / 2.0,
                [x[0] + h / 2.0 * k1[0], x[1] + h / 2.0 * k1[1]],
            );
            let k3 = rhs(
                t + h / 2.0,
                [x[0] + h / 2.0 * k2[0], x[1] + h / 2.0 * k2[1]],
            );
            let k4 = rhs(t + h, [x[0] + h * k3[0], x[1] + h * k3[1]]);
            for j in 0..2 {
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
        }
        x
    }

    #[test]
    fn the_exact_step_matches_a_fine_integration() {
        // Under-damped (the preset's range), near-critical (the series) and over-damped.
        let dt = 5e-5;
        for (alpha, beta) in [
            (4.2e-6, 5.2e-10),
            (2.0 * 5.2e-10f64.sqrt() * (1.0 + 1e-7), 5.2e-10),
            (2e-4, 5.2e-10),
        ] {
            let f = Filter { alpha, beta };
            let step = f.step(dt);
            let x0 = [3.0, -2e4];
            let got = step.advance(x0, 7.0, -5.0);
            let want = rk4(&f, x0, |t| 7.0 - 12.0 * t / dt, dt, 20_000);
            for j in 0..2 {
                let scale = want[j].abs().max(if j == 0 { 1.0 } else { 1e4 });
                assert!(
                    (got[j] - want[j]).abs() < 1e-9 * scale,
                    "α {alpha:e}, β {beta:e}: {got:?} against {want:?}"
                );
            }
        }
    }

    #[test]
    fn the_first_order_step_matches_the_closed_form() {
        // α·ġ + g = F with F linear from 7 to −5 over the step, g(0) = 3: by hand,
        // g(t) = F(t) − αḞ + (g(0) − F(0) + αḞ)·e^{−t/α}.
        let (alpha, dt) = (2e-5, 5e-5);
        let step = Filter { alpha, beta: 0.0 }.step(dt);
        let rate = -12.0 / dt;
        let rest = (3.0 - 7.0 + alpha * rate) * (-dt / alpha).exp();
        let want = [-5.0 - alpha * rate + rest, rate - rest / alpha];
        let got = step.advance([3.0, 123.0], 7.0, -5.0);
        for j in 0..2 {
            assert!(
                (got[j] - want[j]).abs() < 1e-12 * want[j].abs().max(1.0),
                "{got:?} {want:?}"
            );
        }
    }

    #[test]
    fn the_ladder_keeps_the_highest_passive_order() {
        let f = |r| Filter::from_moments(r, String::new).unwrap();
        // The preset's range: second order.
        assert_eq!(
            f([1e-10, -4.2e-16, -5.2e-20]).map(|f| f.beta > 0.0),
            Some(true)
        );
        // r₂ too large for a positive β: first order.
        let first = f([1e-10, -4.2e-16, 1e-20]).unwrap();
        assert!(
            first.beta == 0.0 && (first.alpha - 4.2e-6).abs() < 1e-18,
            "{first:?}"
        );
        // r₁ ≥ 0: the static residual.
        assert_eq!(f([1e-10, 4e-16, -5e-20]), None);
        assert_eq!(f([0.0; 3]), None);
    }

    #[test]
    fn a_steady_force_passes_and_the_step_gain_is_positive() {
        let f = Filter {
            alpha: 4.2e-6,
            beta: 5.2e-10,
        };
        for dt in [1e-6, 1e-5, 5e-5, 1e-3] {
            let step = f.step(dt);
            let x = step.advance([7.0, 0.0], 7.0, 7.0);
            assert!(
                (x[0] - 7.0).abs() < 1e-12 && x[1].abs() < 1e-9,
                "{dt}: {x:?}"
            );
            // The step response to a ramp: never negative (the contact's compliance stays
            // positive).
            assert!(step.advance([0.0; 2], 0.0, 1.0)[0] > 0.0, "{dt}");
        }
    }

    #[test]
    fn moments_that_are_no_residual_are_refused() {
        for r in [[1e-10, f64::NAN, 0.0], [f64::INFINITY, 0.0, 0.0]] {
            let e = Filter::from_moments(r, || "wheel 1 at x = 3 m".into()).unwrap_err();
            assert!(e.to_string().contains("wheel 1 at x = 3 m"), "{e}");
        }
        // A negative r₀ is a static correction: no filter (its load is checked by the
        // reduction, `load_moments`).
        let f = Filter::from_moments([-1e-10, 4e-16, 0.0], String::new).unwrap();
        assert_eq!(f, None);
    }

    #[test]
    fn wheel_filters_in_lanes_follow_a_fine_integration_of_their_forces() {
        // Two wheels (one filtered, one without a filter), two lanes with their own forces,
        // the forces set after each step as the contact would: lane c's wheel 0 displacement
        // r₀·g against Runge–Kutta on the piecewise-linear force.
        let (r0, alpha, beta, dt) = (2e-10, 4.2e-6, 5.2e-10, 5e-5);
        let moments = [r0, -alpha * r0, (alpha * alpha - beta) * r0];
        let force = |c: usize, n: usize| 1e4 * (1.0 + c as f64) * (1.0 + (n as f64 * 0.7).sin());
        let mut wf = WheelFilters::<2>::new(2);
        let mut p = vec![force(0, 0), 5.0, force(1, 0), 6.0];
        wf.hold(0, &p[..2]);
        wf.hold(1, &p[2..]);
        for n in 1..=6 {
            wf.begin(0, moments, dt, &p, String::new).unwrap();
            wf.begin(1, [r0, 0.0, 0.0], dt, &p, String::new).unwrap();
            for c in 0..2 {
                let f1 = force(c, n);
                let got = wf.free(c, 0) + wf.gain(0) * f1;
                let filter = Filter { alpha, beta };
                let f0 = force(c, n - 1);
                let mut x = [force(c, 0), 0.0];
                for k in 1..n {
                    let (a, b) = (force(c, k - 1), force(c, k));
                    x = rk4(&filter, x, |t| a + (b - a) * t / dt, dt, 2_000);
                }
                let want = r0 * rk4(&filter, x, |t| f0 + (f1 - f0) * t / dt, dt, 2_000)[0];
                assert!(
                    (got - want).abs() < 1e-9 * want.abs(),
                    "lane {c}, step {n}: {got:e} {want:e}"
                );
                // No filter: the static residual of the new force.
                let p1 = 5.0 + c as f64;
                assert!((wf.free(c, 1) + wf.gain(1) * p1 - r0 * p1).abs() < 1e-24);
            }
            for c in 0..2 {
                p[2 * c] = force(c, n);
            }
            wf.end(&p);
        }
    }
}
