//! A synthesis run's records made of its readouts, and the dampers' port equations.

use super::run::READOUTS;
use crate::outputs::RunResult;
use crate::outputs::catalog::Pad;

/// A record of n samples padded by two on each side: constant before t = 0 (the loads stood
/// still), linear past the end.
fn padded(n: usize, f: impl Fn(usize) -> f64) -> Vec<f64> {
    let mut x = vec![0.0; n + 4];
    for s in 0..n {
        x[s + 2] = f(s);
    }
    (x[0], x[1]) = (x[2], x[2]);
    let (last, before) = (x[n + 1], if n > 1 { x[n] } else { x[n + 1] });
    (x[n + 2], x[n + 3]) = (2.0 * last - before, 3.0 * last - 2.0 * before);
    x
}

/// The displacement and acceleration records of a finished run from its readouts and the rail
/// residual r (readouts and residual of the `no` observers at `[step·no + j]`, the first
/// `no_layer` of them into `r.disp`, `r.acc` at `[step·no_layer + j]`):
///
///   u = E(d) + r,   ü = E(e + D₂r) + z + D₁y.
///
/// The modes' response to the piecewise-linear force through the force samples is the true
/// response low-passed by sinc²(ωh/2) at every sample, and so is the second difference D₂ of
/// the residual's samples: the zero-phase FIR E = (−1, 14, −1)/12, whose gain
/// 1 + (1 − cos ωh)/6 is 1/sinc²(ωh/2) to O((ωh)⁴) (0.2 % at 2 kHz, h = 5e-5 s), equalises
/// them. The force samples themselves are exact (z), and the force-rate term w·ġ is the
/// fourth-order central difference D₁ of y.
///
/// The observers after those are the pads' two ends (`pads`), read for velocity (their second
/// readout is Re Σ λψᵀs·Q): u̇ = E(e′) + y + D₁r, and the pad's force from both ends'
/// displacement and velocity into `r.pad_force`.
pub(super) fn records(
    r: &mut RunResult,
    readouts: &[f64],
    residual: &[f64],
    (no, no_layer): (usize, usize),
    pads: &[Pad],
    dt: f64,
) {
    let n = readouts.len() / (no * READOUTS).max(1);
    let e = |x: &[f64], s: usize| (14.0 * x[s + 2] - x[s + 1] - x[s + 3]) / 12.0;
    let d1 =
        |y: &[f64], s: usize| (y[s] - 8.0 * y[s + 1] + 8.0 * y[s + 3] - y[s + 4]) / (12.0 * dt);
    let series = |j: usize, k: usize| padded(n, |s| readouts[(s * no + j) * READOUTS + k]);
    for j in 0..no_layer {
        let rd = |k: usize, s: usize| readouts[(s * no + j) * READOUTS + k];
        let rr = padded(n, |s| residual[s * no + j]);
        let (d, y) = (series(j, 0), series(j, 3));
        let inner = padded(n, |s| {
            rd(1, s) + (rr[s + 3] - 2.0 * rr[s + 2] + rr[s + 1]) / (dt * dt)
        });
        for s in 0..n {
            r.disp[s * no_layer + j] = e(&d, s) + rr[s + 2];
            r.acc[s * no_layer + j] = e(&inner, s) + rd(2, s) + d1(&y, s);
        }
    }
    let np = pads.len();
    // The bending moments, after the pads' ends: read as the displacements are.
    let nm = r.n_moments;
    for k in 0..nm {
        let j = no_layer + 2 * np + k;
        let (d, rr) = (series(j, 0), padded(n, |s| residual[s * no + j]));
        for s in 0..n {
            r.moment[s * nm + k] = e(&d, s) + rr[s + 2];
        }
    }
    for (p, pad) in pads.iter().enumerate() {
        // (u, u̇) of the pad's upper and lower end at every sample.
        let ends: Vec<Vec<(f64, f64)>> = (0..2)
            .map(|end| {
                let j = no_layer + 2 * p + end;
                let rr = padded(n, |s| residual[s * no + j]);
                let (d, v, y) = (series(j, 0), series(j, 1), series(j, 3));
                (0..n)
                    .map(|s| (e(&d, s) + rr[s + 2], e(&v, s) + y[s + 2] + d1(&rr, s)))
                    .collect()
            })
            .collect();
        for s in 0..n {
            let ((uu, vu), (ul, vl)) = (ends[0][s], ends[1][s]);
            r.pad_force[s * np + p] = pad.force(uu - ul, vu - vl);
        }
    }
}
