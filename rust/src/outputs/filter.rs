//! Zero-phase low-pass filtering of a response record for band-limited indices
//! (docs/model.md §8, `output.band_limit`).
//!
//! The filter is an 8th-order Butterworth low-pass (bilinear transform with pre-warping, four
//! second-order sections) run forwards and then backwards, so its phase is zero and its gain is
//! |H(f)|² = 1/(1 + (f/f_c)¹⁶): 0.97 at 0.8 f_c, ½ (−6 dB) at f_c, 1.5e-5 at 2 f_c. The record
//! is extended at both ends by an odd reflection of 27 samples and each pass starts from the
//! sections' steady state for the first sample: the conventions of SciPy's `sosfiltfilt`
//! (padtype "odd"), against which the tests hold it.

use crate::error::{Result, VtbError};
use std::f64::consts::PI;

/// Butterworth order of one pass.
pub const ORDER: usize = 8;
const SECTIONS: usize = ORDER / 2;
/// Samples of odd reflection at each end: 3·(2·sections + 1).
const PAD: usize = 3 * (2 * SECTIONS + 1);

/// A second-order section b0 + b1 z⁻¹ + b2 z⁻², a0 = 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Section {
    pub b: [f64; 3],
    pub a: [f64; 3],
}

impl Section {
    /// Transposed direct-form II state of a unit step in steady state.
    fn step_state(&self) -> [f64; 2] {
        let [b0, b1, b2] = self.b;
        let [_, a1, a2] = self.a;
        let h = (b0 + b1 + b2) / (1.0 + a1 + a2);
        [b1 + b2 - (a1 + a2) * h, b2 - a2 * h]
    }
}

/// The sections of an 8th-order digital Butterworth low-pass with cut-off `fc` (Hz) at the
/// sampling rate `fs` (Hz), 0 < fc < fs/2; unit gain at DC.
pub fn butterworth(fc: f64, fs: f64) -> [Section; SECTIONS] {
    // Pre-warped analogue cut-off for the bilinear map s = 2fs·(z − 1)/(z + 1).
    let wa = 2.0 * fs * (PI * fc / fs).tan();
    let k = 2.0 * fs;
    std::array::from_fn(|i| {
        // Analogue pole in the upper half of the left half-plane.
        let theta = PI * (2 * i + 1 + ORDER) as f64 / (2 * ORDER) as f64;
        let (pr, pi) = (wa * theta.cos(), wa * theta.sin());
        // z = (k + p)/(k − p).
        let (nr, ni) = (k + pr, pi);
        let (dr, di) = (k - pr, -pi);
        let d2 = dr * dr + di * di;
        let (zr, zi) = ((nr * dr + ni * di) / d2, (ni * dr - nr * di) / d2);
        let a = [1.0, -2.0 * zr, zr * zr + zi * zi];
        // Zeros at z = −1, gain for unit DC gain.
        let g = (a[0] + a[1] + a[2]) / 4.0;
        Section {
            b: [g, 2.0 * g, g],
            a,
        }
    })
}

/// One pass of the cascade over `x` in place, started from the steady state of `x[0]`.
fn pass(sections: &[Section], x: &mut [f64]) {
    let x0 = x[0];
    let mut scale = 1.0;
    for s in sections {
        let [z0, z1] = s.step_state();
        let (mut z0, mut z1) = (z0 * scale * x0, z1 * scale * x0);
        scale *= (s.b[0] + s.b[1] + s.b[2]) / (s.a[0] + s.a[1] + s.a[2]);
        for v in x.iter_mut() {
            let xin = *v;
            let y = s.b[0] * xin + z0;
            z0 = s.b[1] * xin - s.a[1] * y + z1;
            z1 = s.b[2] * xin - s.a[2] * y;
            *v = y;
        }
    }
}

/// Checks a band limit `fc` (Hz) for records sampled every `dt` (s): finite, positive and
/// below the Nyquist frequency 1/(2dt). `field` names it in the error.
pub fn check(field: &str, fc: f64, dt: f64) -> Result<()> {
    let nyquist = 0.5 / dt;
    // Below this fraction of the sampling rate the sections' poles sit within rounding of
    // z = 1 and the filtered record is no longer finite.
    let lowest = MIN_CUTOFF_RATIO / dt;
    if fc.is_finite() && fc >= lowest && fc < nyquist {
        Ok(())
    } else {
        Err(VtbError::config(
            field,
            format!("{fc:?}"),
            format!(
                "must lie in [{lowest:?}, {nyquist:?}) Hz: below the Nyquist frequency \
                 1/(2·dt) and at least {MIN_CUTOFF_RATIO:e}/dt, the lowest cut-off the \
                 filter resolves in double precision"
            ),
        ))
    }
}

/// The lowest cut-off (as a fraction of the sampling rate 1/dt) the filter takes: it breaks
/// down near 5e-10 and is exact to rounding at 5e-9.
pub const MIN_CUTOFF_RATIO: f64 = 1e-6;

/// `x` low-passed at `fc` (Hz), zero phase, sampled every `dt` (s); `fc` must lie below the
/// Nyquist frequency 1/(2dt) (the configuration checks it). Records shorter than the padding
/// are reflected as far as they reach.
pub fn low_pass(x: &[f64], fc: f64, dt: f64) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return x.to_vec();
    }
    let sections = butterworth(fc, 1.0 / dt);
    let pad = PAD.min(n - 1);
    let mut ext = Vec::with_capacity(n + 2 * pad);
    ext.extend((1..=pad).rev().map(|i| 2.0 * x[0] - x[i]));
    ext.extend_from_slice(x);
    ext.extend((1..=pad).map(|i| 2.0 * x[n - 1] - x[n - 1 - i]));
    pass(&sections, &mut ext);
    ext.reverse();
    pass(&sections, &mut ext);
    ext.reverse();
    ext[pad..pad + n].to_vec()
}

/// Gain |H(f)|² of the forward–backward filter (closed form of the Butterworth magnitude with
/// the bilinear frequency warping): 1/(1 + (tan(πf/fs)/tan(πf_c/fs))^{2·ORDER}).
pub fn gain(f: f64, fc: f64, dt: f64) -> f64 {
    let r = (PI * f * dt).tan() / (PI * fc * dt).tan();
    1.0 / (1.0 + r.powi(2 * ORDER as i32))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Steady-state gain of a sine through the zero-phase filter against the closed form.
    #[test]
    fn a_sine_is_scaled_by_the_squared_butterworth_magnitude() {
        let dt = 2.5e-5;
        let fc = 2000.0;
        for &f in &[200.0, 1000.0, 1600.0, 2000.0, 2400.0, 3000.0] {
            let n = 40_000;
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * PI * f * i as f64 * dt).sin())
                .collect();
            let y = low_pass(&x, fc, dt);
            // Amplitude over the middle half (edge transients excluded), against the gain.
            let amp = y[n / 4..3 * n / 4]
                .iter()
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let g = gain(f, fc, dt);
            assert!((amp - g).abs() < 2e-3 * g.max(1e-3), "f={f}: {amp} vs {g}");
        }
        assert!((gain(2000.0, 2000.0, 2.5e-5) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn constants_pass_unchanged_and_lines_away_from_the_ends() {
        // Unit DC gain and a steady-state start: a constant is reproduced everywhere.
        let c = low_pass(&[2.5; 300], 100.0, 1e-3);
        assert!(c.iter().all(|v| (v - 2.5).abs() < 1e-12));
        // A symmetric kernel of unit sum keeps a line once the start transient has decayed.
        let x: Vec<f64> = (0..500).map(|i| 3.0 - 0.01 * i as f64).collect();
        let y = low_pass(&x, 100.0, 1e-3);
        for (a, b) in x.iter().zip(&y).skip(150).take(200) {
            assert!((a - b).abs() < 1e-8, "{a} {b}");
        }
    }
}
