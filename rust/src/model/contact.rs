//! Nonlinear Hertz wheel–rail contact (docs/model.md §4) and the per-step contact solve.
//!
//! P = (δ/G)^{3/2} for a compression δ > 0, P = 0 otherwise (loss of contact). Within a time
//! step the compressions are affine in the unknown forces, δ = δ_free − A·P, where A is the
//! compliance of wheels and rail over one step (vehicle part + rail part at the wheel
//! positions). The forces solve P = h(δ_free − A·P), found by Newton's method on the few
//! wheel unknowns, never by re-solving the structure.

use crate::error::{Result, VtbError};

/// Contact force (N) of a compression δ (m).
#[inline]
pub fn force(g: f64, delta: f64) -> f64 {
    if delta > 0.0 {
        (delta / g).powf(1.5)
    } else {
        0.0
    }
}

/// dP/dδ (N/m); k_H = 3·P^{1/3}/(2G) at a load P.
#[inline]
pub fn stiffness(g: f64, delta: f64) -> f64 {
    if delta > 0.0 {
        1.5 * delta.sqrt() / g.powf(1.5)
    } else {
        0.0
    }
}

/// Compression δ = G·P^{2/3} carrying a load P.
#[inline]
pub fn compression(g: f64, p: f64) -> f64 {
    g * p.max(0.0).powf(2.0 / 3.0)
}

/// Young's modulus (Pa) and Poisson's ratio of wheel and rail steel.
pub const STEEL_YOUNG: f64 = 2.1e11;
pub const STEEL_POISSON: f64 = 0.3;

/// The complete elliptic integral K(m) of parameter m = e² ∈ [0, 1) and σ(m) = 1 − E(m)/K(m),
/// by the arithmetic–geometric mean (σ = Σ 2^{n−1}·c_n², without the cancellation of K − E).
fn elliptic_k_sigma(m: f64) -> (f64, f64) {
    let (mut a, mut b) = (1.0f64, (1.0 - m).sqrt());
    let mut c2 = m;
    let mut sigma = 0.5 * m;
    let mut pow = 0.5;
    for _ in 0..64 {
        let a1 = 0.5 * (a + b);
        // c_{n+1} = (a_n − b_n)/2 = c_n²/(4·a_{n+1}).
        let c = c2 / (4.0 * a1);
        (a, b) = (a1, (a * b).sqrt());
        c2 = c * c;
        pow *= 2.0;
        sigma += pow * c2;
        if c2 < 1e-34 {
            break;
        }
    }
    (std::f64::consts::PI / (2.0 * a), sigma)
}

/// Half-length (m) along the rail of the Hertz contact ellipse of a wheel of rolling radius
/// `wheel_radius` on a rail head of crown radius `rail_radius` (m) under a load `p` (N), both
/// of steel (`STEEL_YOUNG`, `STEEL_POISSON`): the wheel's curvature acts along the rail, the
/// crown's across it (Johnson, *Contact Mechanics*, 1985, §4.2). With e² = 1 − b²/a² of the
/// semi-axes a ≥ b, B/A = (E(e)/(1 − e²) − K(e))/(K(e) − E(e)) fixes e and
/// a³ = 3P·(K − E)/(2π·A·E*·e²), A ≤ B the half curvature sums, E* = E/(2(1 − ν²)).
pub fn patch_half_length(p: f64, wheel_radius: f64, rail_radius: f64) -> f64 {
    let e_star = STEEL_YOUNG / (2.0 * (1.0 - STEEL_POISSON * STEEL_POISSON));
    let (along, across) = (0.5 / wheel_radius, 0.5 / rail_radius);
    let (a_c, b_c) = (along.min(across), along.max(across));
    // (E/(1 − m) − K)/(K − E) with E = K·(1 − σ).
    let ratio = |m: f64| {
        let (_, sigma) = elliptic_k_sigma(m);
        (m - sigma) / ((1.0 - m) * sigma)
    };
    // B/A grows from 1 at m = 0 without bound as m → 1: bisection on m.
    let (mut lo, mut hi) = (0.0f64, 1.0f64);
    let target = b_c / a_c;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid == lo || mid == hi {
            break;
        }
        if ratio(mid) < target {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let m = 0.5 * (lo + hi);
    let major = if m == 0.0 {
        // Circular contact: a³ = 3P/(8·A·E*), the limit of the expression below.
        (3.0 * p / (8.0 * a_c * e_star)).cbrt()
    } else {
        let (k, sigma) = elliptic_k_sigma(m);
        (3.0 * p * k * sigma / (2.0 * std::f64::consts::PI * a_c * e_star * m)).cbrt()
    };
    // The major axis lies along the smaller curvature sum.
    if along <= across {
        major
    } else {
        major * (1.0 - m).sqrt()
    }
}

/// Newton solver for P = h(δ_free − A·P) with preallocated work space.
///
/// Converged when every wheel satisfies |P_i − h(δ_i)| ≤ `tol`·P_ref,i, P_ref being the static
/// wheel load. A backtracking line search keeps the iteration monotone across the kink of
/// the loss-of-contact law.
///
/// With `block` = b < n (`with_block`: the wheels of a car) the Newton matrix keeps only the
/// b × b diagonal blocks of J: wheels of different cars couple through the track far more
/// weakly than within a car, so the iteration converges to the same tolerance at a fraction
/// of the dense factorisation's cost; a step the line search cannot accept falls back to the
/// full J. The residual always uses the full A, so the solution is that of the full system.
#[derive(Clone, Debug)]
pub struct ContactSolver {
    n: usize,
    /// Hertz constant of each wheel.
    pub g: Vec<f64>,
    /// Force scale of the convergence test (static wheel loads).
    pub p_ref: Vec<f64>,
    pub tol: f64,
    pub max_iter: usize,
    block: usize,
    jac: Vec<f64>,
    res: Vec<f64>,
    dp: Vec<f64>,
    delta: Vec<f64>,
    trial: Vec<f64>,
}

/// Residual R = P − h(δ_free − A·P) into `res` (and δ into `delta`); returns max |R_i|/P_ref,i.
fn residual(
    p: &[f64],
    delta_free: &[f64],
    a: &[f64],
    g: &[f64],
    p_ref: &[f64],
    delta: &mut [f64],
    res: &mut [f64],
) -> f64 {
    let n = p.len();
    let mut worst: f64 = 0.0;
    for i in 0..n {
        let mut d = delta_free[i];
        for j in 0..n {
            d -= a[i * n + j] * p[j];
        }
        delta[i] = d;
        res[i] = p[i] - force(g[i], d);
        worst = worst.max(res[i].abs() / p_ref[i]);
    }
    worst
}

impl ContactSolver {
    pub fn new(g: Vec<f64>, p_ref: Vec<f64>, tol: f64, max_iter: usize) -> Self {
        let n = g.len();
        Self {
            n,
            g,
            p_ref,
            tol,
            max_iter,
            block: n.max(1),
            jac: vec![0.0; n * n],
            res: vec![0.0; n],
            dp: vec![0.0; n],
            delta: vec![0.0; n],
            trial: vec![0.0; n],
        }
    }

    /// Newton matrices of `block` × `block` diagonal blocks (a divisor of the wheel count).
    pub fn with_block(mut self, block: usize) -> Self {
        if block > 0 && self.n % block == 0 {
            self.block = block;
        }
        self
    }

    /// Solves for the forces `p` (initial guess in, solution out); `a` is row-major n×n.
    /// Returns the number of Newton iterations taken.
    pub fn solve(
        &mut self,
        p: &mut [f64],
        delta_free: &[f64],
        a: &[f64],
        time: f64,
        step: usize,
    ) -> Result<usize> {
        let n = self.n;
        let mut rnorm = residual(
            p,
            delta_free,
            a,
            &self.g,
            &self.p_ref,
            &mut self.delta,
            &mut self.res,
        );
        if rnorm <= self.tol {
            return Ok(0);
        }
        let mut iterations = 0;
        let mut block = self.block;
        for it in 1..=self.max_iter {
            iterations = it;
            // J = I + diag(h′(δ))·A, by diagonal blocks of `block` wheels.
            for i in 0..n {
                self.dp[i] = -self.res[i];
            }
            for b0 in (0..n).step_by(block) {
                let jac = &mut self.jac[..block * block];
                for i in 0..block {
                    let kh = stiffness(self.g[b0 + i], self.delta[b0 + i]);
                    for j in 0..block {
                        jac[i * block + j] =
                            kh * a[(b0 + i) * n + b0 + j] + if i == j { 1.0 } else { 0.0 };
                    }
                }
                crate::linalg::dense::lu_solve_in_place(jac, &mut self.dp[b0..b0 + block], block);
            }
            let mut lambda = 1.0;
            let mut accepted = false;
            for _ in 0..40 {
                for i in 0..n {
                    self.trial[i] = p[i] + lambda * self.dp[i];
                }
                let r_new = residual(
                    &self.trial,
                    delta_free,
                    a,
                    &self.g,
                    &self.p_ref,
                    &mut self.delta,
                    &mut self.res,
                );
                if r_new < rnorm || r_new <= self.tol {
                    p.copy_from_slice(&self.trial);
                    rnorm = r_new;
                    accepted = true;
                    break;
                }
                lambda *= 0.5;
            }
            if !accepted {
                if block == n {
                    break;
                }
                // The blocks' step failed: retry from here with the full J.
                block = n;
                let _ = residual(
                    p,
                    delta_free,
                    a,
                    &self.g,
                    &self.p_ref,
                    &mut self.delta,
                    &mut self.res,
                );
                continue;
            }
            if rnorm <= self.tol {
                return Ok(it);
            }
        }
        let residual = (0..n)
            .map(|i| (self.res[i] / self.p_ref[i]).abs() * self.p_ref[i])
            .fold(0.0, f64::max);
        Err(VtbError::ContactNotConverged {
            time,
            step,
            residual,
            iterations,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Hertz constant G = 4.57·R^−0.149·1e−8; R = 0.46 m → δ0 = 87.1 µm and
    /// k_H = 1.21e9 N/m at 70 kN; R = 0.43 m → 88.0 µm, 1.19e9 N/m.
    #[test]
    fn hertz_static_compression_and_linearised_stiffness() {
        for (r, g_want, d_want, k_want) in [
            (0.46, 5.131e-8, 87.1e-6, 1.21e9),
            (0.43, 5.182e-8, 88.0e-6, 1.19e9),
        ] {
            let g = 4.57e-8 * f64::powf(r, -0.149);
            assert!((g - g_want).abs() < 0.001 * g_want, "G({r}) = {g}");
            let d0 = compression(g, 70e3);
            assert!((d0 - d_want).abs() < 0.002 * d_want, "δ0 = {d0}");
            assert!((force(g, d0) - 70e3).abs() < 1e-6);
            let kh = stiffness(g, d0);
            assert!((kh - k_want).abs() < 0.01 * k_want, "k_H = {kh}");
            // k_H = 3·P^{1/3}/(2G)
            assert!((kh - 1.5 * f64::powf(70e3, 1.0 / 3.0) / g).abs() < 1e-6 * kh);
        }
    }

    #[test]
    fn newton_solves_coupled_wheels_and_loss_of_contact() {
        let g = vec![5.13e-8; 2];
        let mut s = ContactSolver::new(g.clone(), vec![7e4; 2], 1e-12, 50);
        let a = [2e-10, 5e-11, 5e-11, 3e-10];
        // Wheel 1 pressed, wheel 2 lifted (negative free compression).
        let dfree = [1e-4, -2e-5];
        let mut p = [0.0, 1e4];
        s.solve(&mut p, &dfree, &a, 0.0, 0).unwrap();
        assert_eq!(p[1], 0.0);
        let d0 = dfree[0] - a[0] * p[0];
        assert!((p[0] - force(g[0], d0)).abs() < 1e-6);
        assert!(p[0] > 0.0);
    }

    /// Two cars of four wheels, coupled within a car and (weakly, 5 %) across: the Newton
    /// iteration on the cars' blocks reaches the full iteration's forces, also with a wheel
    /// out of contact.
    #[test]
    fn block_newton_reaches_the_full_solution() {
        let n = 8;
        let a: Vec<f64> = (0..n * n)
            .map(|q| {
                let (i, j) = (q / n, q % n);
                let base = 2e-10 / (1.0 + (i as f64 - j as f64).abs());
                if i / 4 == j / 4 { base } else { 0.05 * base }
            })
            .collect();
        let dfree: Vec<f64> = (0..n)
            .map(|i| {
                if i == 5 {
                    -3e-5
                } else {
                    8e-5 + 1e-6 * i as f64
                }
            })
            .collect();
        let solve = |block: usize| {
            let mut s =
                ContactSolver::new(vec![5.13e-8; n], vec![7e4; n], 1e-12, 50).with_block(block);
            let mut p = vec![7e4; n];
            let it = s.solve(&mut p, &dfree, &a, 0.0, 0).unwrap();
            (p, it)
        };
        let ((full, it_full), (blocks, it_blocks)) = (solve(n), solve(4));
        assert_eq!(blocks[5], 0.0);
        for (x, y) in full.iter().zip(&blocks) {
            assert!((x - y).abs() < 1e-9 * 7e4, "{x} vs {y}");
        }
        assert!(it_blocks <= it_full + 3, "{it_blocks} vs {it_full}");
    }

    #[test]
    fn elliptic_integrals_against_tabulated_values() {
        // Abramowitz & Stegun Table 17.1: K(½) = 1.854074677301372, E(½) = 1.350643881047675.
        let (k, sigma) = elliptic_k_sigma(0.5);
        let e = k * (1.0 - sigma);
        assert!((k - 1.854074677301372).abs() < 1e-14, "{k}");
        assert!((e - 1.350643881047675).abs() < 1e-14, "{e}");
        let (k0, s0) = elliptic_k_sigma(0.0);
        assert!((k0 - std::f64::consts::FRAC_PI_2).abs() < 1e-15 && s0 == 0.0);
    }

    #[test]
    fn hertz_patch_against_the_circular_closed_form_and_the_wheel_rail_case() {
        // Equal radii: a circle, a³ = 3P·R_e/(4E*), R_e = 1/(A + B) = R for crossed cylinders.
        let e_star = STEEL_YOUNG / (2.0 * (1.0 - STEEL_POISSON * STEEL_POISSON));
        let circle = (3.0 * 70e3 * 0.5 / (4.0 * e_star)).cbrt();
        assert!((patch_half_length(70e3, 0.5, 0.5) - circle).abs() < 1e-12 * circle);
        // Nearly equal radii leave the closed form continuously (ellipse branch).
        let near = patch_half_length(70e3, 0.5, 0.4999);
        assert!((near - circle).abs() < 1e-3 * circle, "{near} vs {circle}");
        // Wheel 0.46 m on a 0.3 m crown at 72 kN: a 12.84 mm long patch (SciPy's ellipk/ellipe
        // with brentq on the same equations give a = 6.41887 mm; about 13 mm is the usual
        // figure for such a contact).
        let a = patch_half_length(72e3, 0.46, 0.3);
        assert!((a - 6.41887e-3).abs() < 1e-8, "{a}");
        // a ∝ P^{1/3}.
        let a2 = patch_half_length(8.0 * 72e3, 0.46, 0.3);
        assert!((a2 / a - 2.0).abs() < 1e-12);
        // Swapped radii: the patch along the rail is the minor axis b = a·√(1 − e²).
        let b = patch_half_length(72e3, 0.3, 0.46);
        assert!((b - 4.82842e-3).abs() < 1e-8, "{b}");
    }
}
