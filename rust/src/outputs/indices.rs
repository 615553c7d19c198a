//! Control indices of a response history (docs/model.md §8, article §4.2–4.4).

/// Amplitude max|a(t)|.
pub fn amplitude(a: &[f64]) -> f64 {
    a.iter().fold(0.0, |m: f64, v| m.max(v.abs()))
}

/// Root mean square over the whole record.
pub fn rms(a: &[f64]) -> f64 {
    if a.is_empty() {
        return 0.0;
    }
    (a.iter().map(|v| v * v).sum::<f64>() / a.len() as f64).sqrt()
}

/// Stabilisation time: the time of the last sample with |a| ≥ `fraction`·max|a|, after which
/// |a| stays below that level (samples at t = i·dt). Zero for an identically zero record.
pub fn settle_time(a: &[f64], dt: f64, fraction: f64) -> f64 {
    let peak = amplitude(a);
    if peak == 0.0 {
        return 0.0;
    }
    let level = fraction * peak;
    let last = a.iter().rposition(|v| v.abs() >= level).unwrap_or(0);
    last as f64 * dt
}

/// Reduction rate (X0 − X)/X0 of an index against its uncontrolled value.
pub fn reduction(x0: f64, x: f64) -> f64 {
    (x0 - x) / x0
}

/// Comprehensive rail control rate η_r = (η_arm + η_arRMS + η_arst)/3.
pub fn comprehensive_rate(amp: (f64, f64), rms: (f64, f64), settle: (f64, f64)) -> f64 {
    (reduction(amp.0, amp.1) + reduction(rms.0, rms.1) + reduction(settle.0, settle.1)) / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn indices_of_known_signals() {
        // Decaying burst: |a| = 10 at i = 0, then 10·0.9^i; 5 % of 10 is reached when
        // 0.9^i < 0.05 → i ≥ 29 (0.9^28 = 0.0523, 0.9^29 = 0.0471).
        let a: Vec<f64> = (0..100)
            .map(|i| 10.0 * 0.9f64.powi(i) * if i % 2 == 0 { 1.0 } else { -1.0 })
            .collect();
        assert_eq!(amplitude(&a), 10.0);
        assert!((settle_time(&a, 0.01, 0.05) - 0.28).abs() < 1e-12);
        // RMS of a full-period sine of amplitude 2 is √2.
        let s: Vec<f64> = (0..1000)
            .map(|i| 2.0 * (2.0 * std::f64::consts::PI * i as f64 / 1000.0).sin())
            .collect();
        assert!((rms(&s) - 2f64.sqrt()).abs() < 1e-12);
        assert!((reduction(1005.6, 841.0) - 0.16368).abs() < 1e-4);
        // Hand-computed: (0.164280 + 0.084706 + 0.028519)/3.
        let eta = comprehensive_rate((1005.6, 840.4), (68.0, 62.24), (1.080, 1.0492));
        assert!((eta - 0.092502).abs() < 1e-6, "{eta}");
        assert_eq!(settle_time(&[0.0; 5], 0.1, 0.05), 0.0);
    }
}
