//! Ride comfort of a car body in the core: the ISO 2631-1:1997 Wk frequency weighting of
//! vertical acceleration and the weighted r.m.s. a_w (the index `car_comfort_aw`), so that
//! studies can name it and batches record only the car body's series.
//!
//! Wk is the product of the standard's analogue filters (its Annex A): a band limit (high pass
//! at f1 = 0.4 Hz, low pass at f2 = 100 Hz, Butterworth Q = 1/√2), the acceleration–velocity
//! transition (f3 = f4 = 12.5 Hz, Q4 = 0.63) and the upward step (f5 = 2.37 Hz, Q5 = 0.91,
//! f6 = 3.35 Hz, Q6 = 0.91). Each is mapped to a digital second-order section by the bilinear
//! transform s = 2fs·(z − 1)/(z + 1) (no pre-warping: the convention of `vtb.comfort`, whose
//! SciPy filter the tests hold it to) and the record is filtered once, forwards, from rest.
//! The warping keeps the digital gain within 1 % of Wk up to 100 Hz at fs ≥ 4 kHz.

use crate::outputs::filter::Section;
use std::f64::consts::{PI, SQRT_2};

/// (f1, f2, f3, f4, Q4, f5, Q5, f6, Q6) of Wk (Hz), ISO 2631-1 Annex A.
const WK: [f64; 9] = [0.4, 100.0, 12.5, 12.5, 0.63, 2.37, 0.91, 3.35, 0.91];
/// The lowest sampling rate (Hz) the weighting is computed at: four samples per period of f2.
pub const MIN_RATE: f64 = 400.0;

/// The analogue sections of Wk as (numerator, denominator) coefficients [s², s, 1].
fn analogue() -> [([f64; 3], [f64; 3]); 4] {
    let w = |f: f64| 2.0 * PI * f;
    let [f1, f2, f3, f4, q4, f5, q5, f6, q6] = WK;
    let (w1, w2, w3, w4, w5, w6) = (w(f1), w(f2), w(f3), w(f4), w(f5), w(f6));
    [
        ([1.0, 0.0, 0.0], [1.0, SQRT_2 * w1, w1 * w1]),
        ([0.0, 0.0, w2 * w2], [1.0, SQRT_2 * w2, w2 * w2]),
        ([0.0, w4 * w4 / w3, w4 * w4], [1.0, w4 / q4, w4 * w4]),
        ([1.0, w5 / q5, w5 * w5], [1.0, w6 / q6, w6 * w6]),
    ]
}

/// |Wk(f)|, the analogue weighting's magnitude at `f` (Hz).
pub fn wk(f: f64) -> f64 {
    let s2 = -(2.0 * PI * f).powi(2);
    let s = 2.0 * PI * f; // s = i·s
    analogue().iter().fold(1.0, |g, (n, d)| {
        let num = (n[0] * s2 + n[2]).hypot(n[1] * s);
        let den = (d[0] * s2 + d[2]).hypot(d[1] * s);
        g * num / den
    })
}

/// The digital sections of Wk at the sampling rate `fs` (Hz).
pub fn sections(fs: f64) -> [Section; 4] {
    let k = 2.0 * fs;
    let map = |c: &[f64; 3]| {
        let (a, b) = (c[0] * k * k, c[1] * k);
        [a + b + c[2], 2.0 * (c[2] - a), a - b + c[2]]
    };
    analogue().map(|(n, d)| {
        let (bn, ad) = (map(&n), map(&d));
        Section {
            b: bn.map(|v| v / ad[0]),
            a: ad.map(|v| v / ad[0]),
        }
    })
}

/// The Wk-weighted record of `a` (m/s²) sampled every `dt` (s), filtered from rest.
pub fn weight(a: &[f64], dt: f64) -> Vec<f64> {
    let mut x = a.to_vec();
    for s in sections(1.0 / dt) {
        let (mut z0, mut z1) = (0.0, 0.0);
        for v in x.iter_mut() {
            let xin = *v;
            let y = s.b[0] * xin + z0;
            z0 = s.b[1] * xin - s.a[1] * y + z1;
            z1 = s.b[2] * xin - s.a[2] * y;
            *v = y;
        }
    }
    x
}

/// ISO 2631-1's a_w: the r.m.s. of the Wk-weighted record (m/s²).
pub fn weighted_rms(a: &[f64], dt: f64) -> f64 {
    crate::outputs::indices::rms(&weight(a, dt))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The standard's tabulated Wk (its Table 3, factors to 3 figures at the one-third octave
    /// band centres 10^(n/10) Hz), against the closed form.
    #[test]
    fn the_analogue_weighting_matches_the_standards_table() {
        for (n, table) in [
            (0, 0.482),
            (6, 0.967),
            (9, 1.036),
            (12, 0.768),
            (15, 0.405),
            (18, 0.186),
        ] {
            let f = 10f64.powf(n as f64 / 10.0);
            assert!(
                (wk(f) / table - 1.0).abs() < 0.02,
                "f = {f}: {} vs {table}",
                wk(f)
            );
        }
    }

    /// A sine's steady gain through the digital filter is the analogue |Wk| within 1 % up to
    /// 100 Hz at 20 kHz.
    #[test]
    fn a_sine_is_weighted_by_wk() {
        let dt = 5e-5;
        for f in [0.8f64, 2.0, 5.0, 12.5, 40.0, 100.0] {
            let n = ((20.0 / f).max(2.0) / dt) as usize;
            let x: Vec<f64> = (0..n)
                .map(|i| (2.0 * PI * f * i as f64 * dt).sin())
                .collect();
            let y = weight(&x, dt);
            let tail = &y[n / 2..];
            let amp = (2.0f64 * tail.iter().map(|v| v * v).sum::<f64>() / tail.len() as f64).sqrt();
            assert!(
                (amp / wk(f) - 1.0).abs() < 0.01,
                "f = {f}: {amp} vs {}",
                wk(f)
            );
        }
    }
}
