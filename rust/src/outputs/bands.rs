//! Energy-true one-third-octave band levels of a record taken whole (docs/spectra.md), the
//! core's band-level indices (`output.band_levels`).
//!
//! The one-sided periodogram of the record — |X_k|²/N², doubled but for 0 Hz and an even
//! record's Nyquist bin, no window, no averaging — puts each frequency bin's power wholly in
//! the band [f_m·10^(−1/20), f_m·10^(1/20)) holding its frequency, so that the band powers and
//! the power outside the bands sum to the record's mean square (Parseval). A passage is a
//! transient: Welch's segment averaging would weight an event by where it falls.
//! Bands: exact base-10 midbands f_m = 1000·10^(x/10) Hz (IEC 61260-1), labelled by their
//! nominal frequency; levels 10·log10(power/ref²) dB re 1e−6 m/s².

use crate::error::{Result, VtbError};
use rustfft::{FftPlanner, num_complex::Complex};

/// Level reference of acceleration (m/s²).
pub const ACC_REFERENCE: f64 = 1e-6;
/// A band gets a level only when it spans at least this many frequency bins of 1/T.
pub const MIN_BINS_PER_BAND: usize = 4;

/// A nominal midband label (Hz) within 3 % of its exact base-10 midband, and that band's
/// index x.
fn band_index(nominal: f64) -> Option<i32> {
    let x = (10.0 * (nominal / 1000.0).log10()).round();
    let exact = 1000.0 * 10f64.powf(x / 10.0);
    ((exact / nominal - 1.0).abs() < 0.03).then_some(x as i32)
}

/// The exact edges [lower, upper) (Hz) of the band labelled `nominal`.
pub fn edges(nominal: f64) -> Option<(f64, f64)> {
    band_index(nominal).map(|x| {
        let fm = 1000.0 * 10f64.powf(f64::from(x) / 10.0);
        (fm * 10f64.powf(-0.05), fm * 10f64.powf(0.05))
    })
}

/// Checks a band label `nominal` at `field` for records of `n` samples every `dt` s: a
/// one-third-octave label, below the Nyquist frequency, at least `MIN_BINS_PER_BAND` bins wide.
pub fn check(field: &str, nominal: f64, dt: f64, n: usize) -> Result<()> {
    let Some((lo, hi)) = edges(nominal).filter(|_| nominal.is_finite() && nominal > 0.0) else {
        return Err(VtbError::config(
            field,
            nominal,
            "is not a one-third-octave midband (Hz; e.g. 31.5, 63, 125, 1000)",
        ));
    };
    let (nyquist, df) = (0.5 / dt, 1.0 / (n as f64 * dt));
    if hi > nyquist {
        return Err(VtbError::config(
            field,
            nominal,
            format!("the band reaches {hi:.4} Hz, above the Nyquist frequency {nyquist:.4} Hz"),
        ));
    }
    if hi - lo < MIN_BINS_PER_BAND as f64 * df {
        return Err(VtbError::config(
            field,
            nominal,
            format!(
                "the band is {:.4} Hz wide, under {MIN_BINS_PER_BAND} frequency bins of the {:.4} s \
                 record: use a longer record or a higher band",
                hi - lo,
                n as f64 * dt
            ),
        ));
    }
    Ok(())
}

/// One-sided periodogram of `x`: (bin width 1/T in Hz, power per bin in units²).
fn periodogram(x: &[f64], dt: f64) -> (f64, Vec<f64>) {
    let n = x.len();
    let mut buf: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let scale = 1.0 / (n as f64 * n as f64);
    let p = (0..=n / 2)
        .map(|k| {
            let twice = k > 0 && !(n % 2 == 0 && k == n / 2);
            buf[k].norm_sqr() * scale * if twice { 2.0 } else { 1.0 }
        })
        .collect();
    (1.0 / (n as f64 * dt), p)
}

/// Each band's power (units²) of the record `x` sampled every `dt` s, for the band labels
/// `nominal` (checked by [`check`]).
pub fn band_powers(x: &[f64], dt: f64, nominal: &[f64]) -> Vec<f64> {
    if x.is_empty() {
        return vec![0.0; nominal.len()];
    }
    let (df, p) = periodogram(x, dt);
    nominal
        .iter()
        .map(|&f| {
            let (lo, hi) = edges(f).expect("a checked band label");
            p.iter()
                .enumerate()
                .filter(|&(k, _)| (lo..hi).contains(&(k as f64 * df)))
                .map(|(_, v)| v)
                .sum()
        })
        .collect()
}

/// A power (units²) as a level in dB re `reference`.
pub fn level(power: f64, reference: f64) -> f64 {
    10.0 * (power / (reference * reference)).log10()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parseval: the powers of every band covering (0, Nyquist) plus the mean sum to the mean
    /// square; a sine's power lies in its band alone, A²/2.
    #[test]
    fn band_powers_sum_to_the_mean_square_and_a_sine_sits_in_its_band() {
        let dt = 1.0 / 8192.0;
        let x: Vec<f64> = (0..8192)
            .map(|i| {
                let t = i as f64 * dt;
                0.3 + 2.0 * (2.0 * std::f64::consts::PI * 1000.0 * t).sin()
                    + 0.5 * (2.0 * std::f64::consts::PI * 63.0 * t).cos()
            })
            .collect();
        let labels = [
            1.0, 1.25, 1.6, 2.0, 2.5, 3.15, 4.0, 5.0, 6.3, 8.0, 10.0, 12.5, 16.0, 20.0, 25.0, 31.5,
            40.0, 50.0, 63.0, 80.0, 100.0, 125.0, 160.0, 200.0, 250.0, 315.0, 400.0, 500.0, 630.0,
            800.0, 1000.0, 1250.0, 1600.0, 2000.0, 2500.0, 3150.0,
        ];
        let p = band_powers(&x, dt, &labels);
        let ms = x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64;
        let total: f64 = p.iter().sum::<f64>() + 0.3 * 0.3;
        assert!((total / ms - 1.0).abs() < 1e-12, "{total} vs {ms}");
        let at = |f: f64| p[labels.iter().position(|&l| l == f).unwrap()];
        assert!((at(1000.0) - 2.0).abs() < 1e-9);
        assert!((at(63.0) - 0.125).abs() < 1e-9);
    }

    #[test]
    fn labels_outside_the_series_and_narrow_bands_are_refused_by_name() {
        for bad in [1100.0, 0.0, -63.0, f64::NAN] {
            let e = check("output.band_levels[0]", bad, 1e-4, 10_000).unwrap_err();
            assert!(e.to_string().contains("output.band_levels[0]"), "{e}");
        }
        assert!(check("f", 6300.0, 1e-4, 10_000).is_err()); // above Nyquist 5 kHz
        assert!(check("f", 10.0, 1e-4, 1_000).is_err()); // 2.3 Hz wide, 0.1 s record
        assert!(check("f", 1000.0, 1e-4, 10_000).is_ok());
    }
}
