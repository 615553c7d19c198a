//! The frequency band each discretisation resolves (docs/resolution.md).
//!
//! A layer's response is resolved up to the lower of two limits, each the frequency at which
//! that part of the discretisation is [`TOLERANCE`] (1 %) off the continuous beam:
//! - **basis**: the free bending wave (Euler–Bernoulli, or Timoshenko's lower branch with
//!   rotary inertia) of the shortest wavelength the layer's basis holds to 1 %: the shortest sine
//!   of a modal basis (λ = 2L/N; a modal or hybrid basis holds nothing shorter), or for finite
//!   elements the wave whose Bloch (periodic-mesh) frequency on an element of the longest length
//!   the mesh allows is 1 % off;
//! - **time step**: Newmark's average-acceleration rule shifts a frequency f to
//!   2·atan(πfΔt)/(πfΔt)·f, 1 % low at 2πfΔt = 0.3496. The complex-modal synthesis steps its
//!   modes exactly; its Δt limit is where its piecewise-linear force's sinc²(πfΔt) loss, once
//!   equalised by the records' FIR (docs/synthesis.md), is 1 % off, at 2πfΔt = 0.974; its
//!   basis limit is `SYNTHESIS_BAND_SHARE` of the cut-off.
//!
//! Supports raise a layer's frequencies at a given wavelength, so the free beam's frequency is
//! the conservative end. These bounds are computed from the configuration alone (the mesh's
//! longest element is at most `element_length`, or L / `fem_elements`).

use crate::config::{Config, CouplingKind, LayerConfig, Method};
use crate::model::layers::Layer;
use std::f64::consts::PI;

/// Relative frequency error that bounds a resolved band.
pub const TOLERANCE: f64 = 0.01;

/// The band one layer resolves.
#[derive(Clone, Debug, PartialEq)]
pub struct LayerBand {
    pub layer: String,
    /// Upper end of the resolved band (Hz): the lower of the two limits.
    pub f_max: f64,
    /// Limit of the spatial basis (Hz) and the shortest bending wavelength it holds (m).
    pub basis_f_max: f64,
    pub shortest_wavelength: f64,
    /// Limit of the time step (Hz).
    pub time_f_max: f64,
}

/// ω² (rad²/s²) of the free continuous beam's bending wave of wavenumber k (rad/m): the lower
/// root of (κGA·k² − ρAω²)(EI·k² + κGA − ρIω²) = (κGA·k)² for a Timoshenko layer.
fn continuous_omega2(layer: &Layer, k: f64) -> f64 {
    let (ra, ei, k2) = (layer.rho_a, layer.ei, k * k);
    match layer.shear {
        None => ei * k2 * k2 / ra,
        Some(s) => {
            // ρA·ρI·ω⁴ − (ρA(EIk² + κGA) + ρI·κGA·k²)·ω² + EI·κGA·k⁴ = 0.
            let a = ra * s.rho_i;
            let b = ra * (ei * k2 + s.kga) + s.rho_i * s.kga * k2;
            let c = ei * s.kga * k2 * k2;
            // Lower root without cancellation: 2c/(b + √(b² − 4ac)).
            2.0 * c / (b + (b * b - 4.0 * a * c).max(0.0).sqrt())
        }
    }
}

/// Lowest ω² of the periodic (Bloch) problem of one element with phase θ = k·h between its
/// nodes: det(K(θ) − λM(θ)) = 0 with K(θ) = Tᴴ·K_e·T, T = [I; e^{iθ}I].
fn bloch_omega2(m: &[f64; 16], k: &[f64; 16], theta: f64) -> f64 {
    let (c, s) = (theta.cos(), theta.sin());
    // 2 × 2 Hermitian reduction: A11 + A22 + e^{iθ}A12 + e^{−iθ}A12ᵀ (blocks of the 4 × 4).
    let reduce = |a: &[f64; 16]| {
        let at = |i: usize, j: usize| a[4 * i + j];
        let diag = |p: usize| at(p, p) + at(p + 2, p + 2) + 2.0 * c * at(p, p + 2);
        // Off-diagonal (row w, column ψ): a01 + a23 + e^{iθ}·a03 + e^{−iθ}·a21.
        let re = at(0, 1) + at(2, 3) + c * (at(0, 3) + at(2, 1));
        let im = s * (at(0, 3) - at(2, 1));
        (diag(0), diag(1), re, im)
    };
    let (k11, k22, kr, ki) = reduce(k);
    let (m11, m22, mr, mi) = reduce(m);
    let qa = m11 * m22 - (mr * mr + mi * mi);
    let qb = -(k11 * m22 + k22 * m11 - 2.0 * (kr * mr + ki * mi));
    let qc = k11 * k22 - (kr * kr + ki * ki);
    let disc = (qb * qb - 4.0 * qa * qc).max(0.0).sqrt();
    // Lower root, written without cancellation.
    2.0 * qc / (-qb + disc)
}

/// Share of the synthesis cut-off f_c up to which its modes plus the static residual hold
/// the response (the modes reach twice the band; docs/synthesis.md, receptance check).
pub const SYNTHESIS_BAND_SHARE: f64 = 0.5;

/// Share of the substructure cut-off f_c up to which the substructured coordinates hold the
/// response: the interiors' modes reach twice the band, where the natural frequencies are
/// within 2e-3 of the structure's (docs/substructures.md, the convergence table).
pub const SUBSTRUCTURE_BAND_SHARE: f64 = 0.5;

/// The x in (1e-6, hi) where an error rising with x reaches `tol` (bisection).
fn crossing(err: impl Fn(f64) -> f64, tol: f64, hi: f64) -> f64 {
    let (mut lo, mut hi) = (1e-6, hi);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if err(mid) < tol {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// The error of the synthesis's force interpolation at 2πfΔt = x once equalised: the
/// piecewise-linear force's gain sinc²(x/2) times the records' FIR 1 + (1 − cos x)/6.
fn interpolation_error(x: f64) -> f64 {
    let h = 0.5 * x;
    (1.0 - (h.sin() / h).powi(2) * (1.0 + (1.0 - x.cos()) / 6.0)).abs()
}

/// The synthesis's 1 % frequency limit of the time step (`interpolation_error`).
fn interpolation_limit(dt: f64) -> f64 {
    crossing(interpolation_error, TOLERANCE, 2.0) / (2.0 * PI * dt)
}

/// Newmark's 1 % frequency limit 2πfΔt = x with 1 − 2·atan(x/2)/x = TOLERANCE.
fn newmark_limit(dt: f64) -> f64 {
    crossing(|x| 1.0 - 2.0 * (0.5 * x).atan() / x, TOLERANCE, 3.0) / (2.0 * PI * dt)
}

/// Largest wavenumber (rad/m) that a finite-element layer with elements of length `h` holds to
/// TOLERANCE: the first k·h at which the Bloch frequency leaves the continuous one, scanned to
/// the Brillouin zone's edge θ = π.
fn fem_wavenumber_limit(cfg: &LayerConfig, h: f64) -> f64 {
    let layer = element_layer(cfg, h);
    let (_, m, k) = &layer.element_matrices()[0];
    let ok = |theta: f64| {
        let fe = bloch_omega2(m, k, theta).sqrt();
        let exact = continuous_omega2(&layer, theta / h).sqrt();
        (fe / exact - 1.0).abs() <= TOLERANCE
    };
    let n = 2000;
    let first_bad = (1..=n).map(|i| PI * i as f64 / n as f64).find(|&t| !ok(t));
    let Some(bad) = first_bad else {
        return PI / h;
    };
    let (mut lo, mut hi) = (bad - PI / n as f64, bad);
    for _ in 0..60 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) { lo = mid } else { hi = mid }
    }
    lo / h
}

/// The layer of `cfg` as one finite element of length `h`: its section properties and the
/// matrices of an element of that length.
fn element_layer(cfg: &LayerConfig, h: f64) -> Layer {
    let mut one = cfg.clone();
    one.element_length = None;
    Layer::new(&one, h, (0.0, h), Method::Fem, 1, &[], 0)
}

/// The first pinned–pinned frequency (Hz) of the top layer (the rail) between its discrete
/// supports: the continuous beam's frequency (`continuous_omega2`: Euler–Bernoulli, or
/// Timoshenko with rotary inertia) at k = π/d, d the spacing of the first two points of the
/// first discrete coupling under it. `None` without such a coupling.
/// An upper bound on the number of undamped modes below `f` (Hz) of a finite-element
/// structure: the sum over the layers' free pieces (each layer cut at its joints) of the free
/// continuous beam's count, k(f)·ℓ/π + 3 (two rigid-body modes and the half wave a free–free
/// beam's ends add), doubled for a Timoshenko layer above its second branch's cut-on
/// (ω² = κGA/ρI), and at most the piece's DOFs. A bound by Rayleigh's rules: the couplings only
/// add stiffness, which lowers every count, and the elements are stiffer than the continuous
/// beam. Measured 1.05–1.2 times the count (one span and one span with 50 m embankments).
pub fn mode_count_bound(cfg: &Config, f: f64) -> f64 {
    let w2 = (2.0 * PI * f).powi(2);
    let mut total = 0.0;
    for (i, lc) in cfg.structure.layers.iter().enumerate() {
        let (a, b) = cfg.extent(i);
        let layer = element_layer(lc, b - a);
        // The wavenumber of ω on the lower branch (it rises with k): doubling, then bisection.
        let mut hi = 1.0;
        while continuous_omega2(&layer, hi) < w2 && hi < 1e9 {
            hi *= 2.0;
        }
        let k = crossing(|k| continuous_omega2(&layer, k) / w2, 1.0, hi);
        let second = layer.shear.is_some_and(|sh| w2 > sh.kga / sh.rho_i);
        let h = lc
            .element_length
            .unwrap_or(cfg.structure.length / cfg.discretisation.fem_elements as f64);
        let mut cuts: Vec<f64> = lc.joints.clone();
        cuts.extend([a, b]);
        cuts.sort_by(f64::total_cmp);
        for piece in cuts.windows(2).map(|w| w[1] - w[0]) {
            let count = (k * piece / PI + 3.0) * if second { 2.0 } else { 1.0 };
            total += count.min(2.0 * ((piece / h).ceil() + 1.0));
        }
    }
    total
}

pub fn pinned_pinned_frequency(cfg: &Config) -> Option<f64> {
    let rail = cfg.structure.layers.first()?;
    let support = cfg
        .structure
        .couplings
        .iter()
        .find(|c| c.upper == rail.name && c.kind == CouplingKind::Discrete)?;
    let mut pos = support.positions.clone();
    pos.sort_by(f64::total_cmp);
    let d = *pos.get(1)? - pos[0];
    (d > 0.0).then(|| continuous_omega2(&element_layer(rail, d), PI / d).sqrt() / (2.0 * PI))
}

/// The resolved band of every layer of a (validated) configuration, top layer first.
pub fn resolved_bands(cfg: &Config) -> Vec<LayerBand> {
    let length = cfg.structure.length;
    let method = cfg.discretisation.method;
    let synthesis = cfg.discretisation.synthesis_cutoff;
    let time_f_max = match synthesis {
        Some(_) => interpolation_limit(cfg.solver.dt),
        None => newmark_limit(cfg.solver.dt),
    };
    cfg.structure
        .layers
        .iter()
        .map(|lc| {
            let layer = element_layer(lc, length);
            let k_max = match method {
                Method::Fem => {
                    let h = lc
                        .element_length
                        .unwrap_or(length / cfg.discretisation.fem_elements as f64)
                        .min(length);
                    fem_wavenumber_limit(lc, h)
                }
                Method::Modal | Method::Hybrid => PI * lc.modes.max(1) as f64 / length,
            };
            let mut basis_f_max = continuous_omega2(&layer, k_max).sqrt() / (2.0 * PI);
            if let Some(fc) = synthesis {
                basis_f_max = basis_f_max.min(SYNTHESIS_BAND_SHARE * fc);
            }
            if let Some(fc) = cfg.discretisation.substructure_cutoff {
                basis_f_max = basis_f_max.min(SUBSTRUCTURE_BAND_SHARE * fc);
            }
            LayerBand {
                layer: lc.name.clone(),
                f_max: basis_f_max.min(time_f_max),
                basis_f_max,
                shortest_wavelength: 2.0 * PI / k_max,
                time_f_max,
            }
        })
        .collect()
}

// The synthesis reduction's geometry (`engine::synthesis`), read from here by vtb.run.synthesis
// (which builds the reduction) and by the build's estimate (`check::budget`).

/// The undamped modes of the Ritz basis reach this multiple of the cut-off.
pub const BASIS_RATIO: f64 = 1.5;
/// Reach of the stored rail residual (m) on either side of a DOF: the residual between rail
/// points farther apart is dropped. The kept modes' static flexibility carries a short-wave
/// ripple that only the residual cancels, and it decays slowly (±7 % of the point value at
/// 1.3 m): a load moving past an observer drives what is left of it as rail acceleration in
/// the band. At 1.3 m a moving force's rail acceleration (≤ 2 kHz) was 8–11 % off the finite
/// elements' in r.m.s.; at this reach, with the taper, 5.4 % (3.2 % with the moving forces'
/// rate term; docs/synthesis.md, "Moving loads").
pub const RESIDUAL_REACH: f64 = 5.2;
/// The residual is kept whole up to this distance (m), then faded to zero at the reach by a
/// raised cosine, so that no load's residual at a point jumps as it crosses the reach (a sharp
/// cut put a spike in the acceleration there).
pub const RESIDUAL_TAPER: f64 = 2.6;
/// Reach of the modes' step compliance between two loads (m): within one step no wave
/// carries a load farther (the rail's shear wave needs 0.3 ms per metre), so the full model's
/// value is nil there and the modes' sum is noise (`engine::synthesis`).
pub const STEP_REACH: f64 = 1.3;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::presets::{paper, paper_converged, paper_fast};

    #[test]
    fn the_fast_preset_resolves_its_band_limit() {
        // sinc²(x/2)·(1 + (1 − cos x)/6) = 1 − x⁴/90 + O(x⁶): 1 % off at x = 2πfΔt ≈ 1.0
        // (0.996 exactly), 3.17 kHz at Δt = 5e-5 s. The modes to 4 kHz hold 2 kHz, the band
        // limit.
        let cfg = paper_fast();
        let x = 2.0 * PI * interpolation_limit(5e-5) * 5e-5;
        assert!((interpolation_error(x) - 0.01).abs() < 1e-12, "{x}");
        assert!((x - 0.9958).abs() < 1e-3, "{x}");
        for y in [0.05, 0.1, 0.2] {
            let rel = interpolation_error(y) / (y.powi(4) / 90.0);
            assert!((rel - 1.0).abs() < 0.01, "the x⁴/90 series at {y}: {rel}");
        }
        let rail = &resolved_bands(&cfg)[0];
        assert_eq!(rail.f_max, 2000.0);
        assert!(rail.f_max >= cfg.output.band_limit.unwrap());
    }

    #[test]
    fn newmark_limit_is_where_the_period_error_is_one_percent() {
        // x = 0.34956: 2·atan(0.17478)/0.34956 = 0.99000 (to 5 digits).
        let f = newmark_limit(2.5e-5);
        let x = 2.0 * PI * f * 2.5e-5;
        assert!((x - 0.34956).abs() < 1e-4, "{x}");
        assert!((1.0 - 2.0 * (0.5 * x).atan() / x - 0.01).abs() < 1e-12);
    }

    #[test]
    fn bloch_frequencies_of_cubic_elements_converge_to_the_beam() {
        // Long waves on short elements: the Bloch frequency tends to the continuous beam's,
        // Euler–Bernoulli (the article's rail; errors fall 16-fold per halving, (kh)⁴) and
        // Timoshenko with rotary inertia (the converged preset's; 5- to 10-fold before the
        // asymptotic rate: shear governs the short waves).
        for cfg in [paper(), paper_converged()] {
            let h = 0.032;
            let layer = element_layer(&cfg.structure.layers[0], h);
            let (_, m, k) = &layer.element_matrices()[0];
            let mut last = f64::INFINITY;
            for theta in [0.8, 0.4, 0.2, 0.1, 0.05] {
                let w2 = continuous_omega2(&layer, theta / h);
                let e = (bloch_omega2(m, k, theta) / w2 - 1.0).abs();
                assert!(e < last / 4.5 || e < 1e-9, "θ={theta}: {e} after {last}");
                last = e;
            }
        }
    }

    #[test]
    fn the_article_hybrid_rail_holds_no_pinned_pinned_wave_and_the_converged_one_does() {
        let bay = 0.64;
        let hybrid = &resolved_bands(&paper())[0];
        // 120 sines on 160 m: nothing shorter than 2.67 m, twice the pinned–pinned wavelength.
        assert!((hybrid.shortest_wavelength - 2.0 * 160.0 / 120.0).abs() < 1e-9);
        assert!(hybrid.shortest_wavelength > 2.0 * bay);
        // The converged rail (Timoshenko, 32 mm elements) holds the pinned–pinned wave with
        // room to spare, and is limited by its time step (Δt = 2.5e-5 s: 2.23 kHz).
        let conv = &resolved_bands(&paper_converged())[0];
        assert!(conv.shortest_wavelength < 2.0 * bay / 3.0, "{conv:?}");
        assert!((conv.time_f_max - 2225.4).abs() < 0.5, "{conv:?}");
        assert_eq!(conv.f_max, conv.time_f_max);
    }
}
