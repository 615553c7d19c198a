//! The local modes and the correction against closed forms, the band-averaged exact
//! condensation, the rigid motions of the track, definiteness for any ω_r and the sine
//! recurrences against direct sums.

use super::*;
use crate::config::Method;
use crate::library::presets;
use crate::linalg::sparse::CsrMatrix;

fn paper_hybrid(coupling: FeSeaCoupling) -> (Config, Layer) {
    let mut cfg = presets::paper();
    cfg.discretisation.method = Method::Hybrid;
    cfg.discretisation.fesea_coupling = coupling;
    let lc = &cfg.structure.layers[0];
    let rail = Layer::new(
        lc,
        cfg.structure.length,
        (0.0, cfg.structure.length),
        cfg.discretisation.method,
        0,
        &[],
        0,
    );
    (cfg, rail)
}

/// Closed forms for mass-normalised sines on a fastener grid that divides L (spacing d,
/// first fastener at x = 0): Σ_f s_j(x_f)² = (L/d)/2·(2/(ρAL)) = 1/(ρA·d), so
/// k_j = EI(jπ/L)⁴/ρA + k_f/(ρA·d), c_j = α + β·EI(jπ/L)⁴/ρA + c_f/(ρA·d), m_j = 1,
/// η_j = c_j/ω_j.
#[test]
fn local_mode_properties_match_closed_forms() {
    let (cfg, rail) = paper_hybrid(FeSeaCoupling::Full);
    let fs = FeSea::new(&cfg, &rail).unwrap();
    let lc = &cfg.structure.layers[0];
    let fasteners = &cfg.structure.couplings[0];
    assert_eq!(fasteners.upper, lc.name);
    let d = fasteners.positions[1] - fasteners.positions[0];
    let rho_a = lc.density * lc.area;
    let ei = lc.youngs_modulus * lc.inertia;
    let (alpha, beta) = lc.damping.coefficients();
    assert_eq!(fs.modes.len(), lc.local_modes);
    for m in &fs.modes {
        let k = m.index as f64 * PI / cfg.structure.length;
        let bend = ei * k.powi(4) / rho_a;
        let kj = bend + fasteners.stiffness / (rho_a * d);
        let cj = alpha + beta * bend + fasteners.damping / (rho_a * d);
        assert!((m.mass - 1.0).abs() < 1e-15);
        assert!(
            (m.stiffness - kj).abs() < 1e-9 * kj,
            "k_{}: {} vs {kj}",
            m.index,
            m.stiffness
        );
        assert!((m.damping - cj).abs() < 1e-9 * cj);
        let w = kj.sqrt();
        assert!((m.omega - w).abs() < 1e-9 * w);
        assert!((m.loss_factor - cj / w).abs() < 1e-9 * cj / w);
    }
}

/// Closed forms of the couplings of the linear functions g1 = 1 − x/L, g2 = x/L:
/// mass ρA∫(1 − x/L)·s_j = ρA·c·L/(jπ), ρA∫(x/L)·s_j = −ρA·c·(−1)^j·L/(jπ) with
/// c = sqrt(2/(ρAL)); no bending coupling (g″ = 0); fasteners at x_f = f·L/N, f = 0..N:
/// Σ_f k_f·(1 − f/N)·c·sin(jπf/N) = k_f·c·½·cot(jπ/2N) (from
/// Σ_{f<N} (N − f)·sin fθ = N·sin θ/(2(1 − cos θ)) at θ = jπ/N), and −(−1)^j times that
/// for g2 (f → N − f).
#[test]
fn couplings_of_linear_functions_match_closed_forms() {
    let (cfg, rail) = paper_hybrid(FeSeaCoupling::Full);
    let l = cfg.structure.length;
    let c = (2.0 / (rail.rho_a * l)).sqrt();
    let fasteners = &cfg.structure.couplings[0];
    let n = (fasteners.positions.len() - 1) as f64;
    assert!((fasteners.positions.last().unwrap() - l).abs() < 1e-9);
    let (alpha, _) = cfg.structure.layers[0].damping.coefficients();
    for mc in local_modes(&cfg, &rail).unwrap() {
        let j = mc.mode.index as f64;
        let sign = if mc.mode.index % 2 == 0 { 1.0 } else { -1.0 };
        let per = [1.0, -sign];
        let cot = 1.0 / (j * PI / (2.0 * n)).tan();
        for g in 0..2 {
            let m = rail.rho_a * c * l / (j * PI) * per[g];
            assert!((mc.m[g] - m).abs() < 1e-12 * m.abs());
            let k = fasteners.stiffness * c * 0.5 * cot * per[g];
            assert!(
                (mc.k[g] - k).abs() < 1e-9 * k.abs(),
                "K_{}{}: {} vs {k}",
                g + 1,
                mc.mode.index,
                mc.k[g]
            );
            let d = fasteners.damping * c * 0.5 * cot * per[g];
            assert!((mc.c[g] - (alpha * m + d)).abs() < 1e-9 * d.abs());
        }
    }
}

/// Band averages over B of the exact condensation −Σ_j D_gj·D_jgᵀ/D_jj of every local mode
/// (D_jj = k_j + iωc_j − ω²m_j) with D_gj = K_gj + iωC_gj − ω²M_gj (`full`) or −ω²M_gj,
/// and of the model's ΔK − ω²ΔM + iωΔC: [Re exact, Im exact, Re model, Im model].
fn band_averages(cfg: &Config, rail: &Layer, fs: &FeSea, full: bool) -> [[[f64; 4]; 4]; 4] {
    let locals = local_modes(cfg, rail).unwrap();
    let k = 4000;
    let mut out = [[[0.0; 4]; 4]; 4];
    for i in 0..k {
        let w = fs.band.0 + (fs.band.1 - fs.band.0) * (i as f64 + 0.5) / k as f64;
        for l in &locals {
            let md = &l.mode;
            let djj = (md.stiffness - w * w * md.mass, w * md.damping);
            let den = djj.0 * djj.0 + djj.1 * djj.1;
            let inv = (djj.0 / den, -djj.1 / den);
            let dg: [(f64, f64); 4] = std::array::from_fn(|g| {
                if full {
                    (l.k[g] - w * w * l.m[g], w * l.c[g])
                } else {
                    (-w * w * l.m[g], 0.0)
                }
            });
            for p in 0..4 {
                for q in 0..4 {
                    let pq = (
                        dg[p].0 * dg[q].0 - dg[p].1 * dg[q].1,
                        dg[p].0 * dg[q].1 + dg[p].1 * dg[q].0,
                    );
                    out[0][p][q] -= (pq.0 * inv.0 - pq.1 * inv.1) / k as f64;
                    out[1][p][q] -= (pq.0 * inv.1 + pq.1 * inv.0) / k as f64;
                }
            }
        }
        for p in 0..4 {
            for q in 0..4 {
                out[2][p][q] += (fs.delta_k[p][q] - w * w * fs.delta_m[p][q]) / k as f64;
                out[3][p][q] += w * fs.delta_c[p][q] / k as f64;
            }
        }
    }
    out
}

fn rel_err(model: &[[f64; 4]; 4], exact: &[[f64; 4]; 4]) -> f64 {
    let norm = |f: &dyn Fn(usize, usize) -> f64| {
        (0..16).map(|i| f(i / 4, i % 4).powi(2)).sum::<f64>().sqrt()
    };
    norm(&|p, q| model[p][q] - exact[p][q]) / norm(&|p, q| exact[p][q])
}

/// The article's mass-coupled correction against the exact condensation of the same
/// (mass-coupled) model, averaged over B, on the paper's rail (fasteners, slab blocked):
/// * imaginary part (iω·ΔC): within 15 % — the Strasberg–Feit average is exact for a
///   uniform modal density and coupling across the band and many modes in it; here
///   15–25 rail modes lie in the band, those at its edges resonate partly outside it
///   and M_gj² varies as 1/j² across it (measured: 13 % at 600 Hz, 9 % at 800 Hz);
/// * real part (−ω²·ΔM of the below-band modes; the other classes neglected): the right
///   sign on every diagonal entry and within a factor of two — modes just below the band
///   respond more strongly than the ω ≫ ω_j limit assumes and the modes above subtract.
#[test]
fn mass_coupled_correction_matches_band_averaged_exact_condensation() {
    let (mut cfg, rail) = paper_hybrid(FeSeaCoupling::Mass);
    for omega_r in [2.0 * PI * 600.0, 2.0 * PI * 800.0] {
        cfg.discretisation.omega_r = Some(omega_r);
        let fs = FeSea::new(&cfg, &rail).unwrap();
        let resonant = fs
            .modes
            .iter()
            .filter(|m| m.class == ModeClass::Resonant)
            .count();
        assert!(resonant >= 10, "{resonant} resonant modes");
        let [re, im, model_re, model_im] = band_averages(&cfg, &rail, &fs, false);
        let err_im = rel_err(&model_im, &im);
        assert!(err_im < 0.15, "imaginary part off by {err_im}");
        for p in 0..4 {
            assert!(
                im[p][p] > 0.0 && fs.delta_c[p][p] > 0.0,
                "damping is added, never removed"
            );
            assert!(fs.delta_m[p][p] < 0.0 && re[p][p] > 0.0);
            let r = model_re[p][p] / re[p][p];
            assert!((0.5..2.0).contains(&r), "real part ratio {r} on g{}", p + 1);
        }
    }
}

/// The full-coupling correction against the exact condensation with the full coupling
/// D_gj = K_gj + iωC_gj − ω²M_gj, averaged over B (measured at 600 / 800 Hz), on the block
/// of the cubic residuals g3, g4, which the exact split carries (their stiffness and mass
/// couplings cancel at resonance): real part within 1 % (0.06 %, 0.10 %), imaginary within
/// 2 % (0.5 %). The end functions g1, g2 stay out of the split by design (docs/fesea.md):
/// their rows and columns of ΔM, ΔK, ΔC are zero.
#[test]
fn full_coupled_correction_matches_band_averaged_exact_condensation() {
    let (mut cfg, rail) = paper_hybrid(FeSeaCoupling::Full);
    for omega_r in [2.0 * PI * 600.0, 2.0 * PI * 800.0] {
        cfg.discretisation.omega_r = Some(omega_r);
        let fs = FeSea::new(&cfg, &rail).unwrap();
        let [re, im, model_re, model_im] = band_averages(&cfg, &rail, &fs, true);
        let block = |a: &[[f64; 4]; 4]| -> [[f64; 4]; 4] {
            std::array::from_fn(|p| {
                std::array::from_fn(|q| if p >= 2 && q >= 2 { a[p][q] } else { 0.0 })
            })
        };
        let (br, bi) = (
            rel_err(&block(&model_re), &block(&re)),
            rel_err(&block(&model_im), &block(&im)),
        );
        assert!(br < 0.01 && bi < 0.02, "g3/g4 block off by {br}, {bi}");
        for d in [&fs.delta_m, &fs.delta_k, &fs.delta_c] {
            for p in 0..4 {
                for q in 0..2 {
                    assert!(d[p][q] == 0.0 && d[q][p] == 0.0, "end function g{}", q + 1);
                }
            }
        }
    }
}

/// The rigid motions of the whole track (every layer translating, or rotating about
/// x = 0) strain only the ground supports, so the hybrid must give them the modal model's
/// stiffness Σ_p k·t(x_p)² and mass. Checked on the paper's structure with its piers
/// softened to 1e6 N/m, where the supports barely resist them: before the end functions
/// were kept out of the split the hybrid added 2.8e8 N/m to the translation (the soft
/// supports give 6e6) and its displacements came out 27 % low.
#[test]
fn rigid_motions_of_the_track_keep_their_stiffness_and_mass() {
    for k_pier in [1e6, 1e15] {
        let (mut cfg, _) = paper_hybrid(FeSeaCoupling::Full);
        let piers = cfg.structure.couplings.last_mut().unwrap();
        assert_eq!(piers.lower, GROUND);
        piers.stiffness = k_pier;
        let piers = piers.clone();
        let hybrid = crate::model::structure::Structure::build(&cfg).unwrap();
        cfg.discretisation.method = Method::Modal;
        cfg.structure.layers[0].local_modes = 0;
        let modal = crate::model::structure::Structure::build(&cfg).unwrap();
        let l = cfg.structure.length;
        for (g, shape) in [
            ([1.0, 1.0], &(|_x: f64| 1.0) as &dyn Fn(f64) -> f64),
            ([0.0, 1.0], &|x| x / l),
        ] {
            let energy = |st: &crate::model::structure::Structure| {
                let mut t = vec![0.0; st.n_dofs];
                for layer in &st.layers {
                    t[layer.offset] = g[0];
                    t[layer.offset + 1] = g[1];
                }
                let quad = |a: &CsrMatrix| {
                    let mut y = vec![0.0; t.len()];
                    a.mul(&t, &mut y);
                    t.iter().zip(&y).map(|(a, b)| a * b).sum::<f64>()
                };
                (quad(&st.k), quad(&st.m))
            };
            let supports: f64 = piers
                .positions
                .iter()
                .map(|&x| k_pier * shape(x).powi(2))
                .sum();
            let ((kh, mh), (km, mm)) = (energy(&hybrid), energy(&modal));
            assert!(
                (km - supports).abs() < 1e-9 * supports,
                "modal {km} vs {supports}"
            );
            assert!(
                (kh - supports).abs() < 1e-6 * supports,
                "hybrid {kh} vs {supports}"
            );
            assert!((mh - mm).abs() < 1e-9 * mm, "mass {mh} vs {mm}");
        }
    }
}

/// Whatever ω_r, the corrected structure keeps M positive definite and K positive
/// semi-definite (its static factorisation succeeds), for both couplings.
#[test]
fn corrected_matrices_stay_definite_for_any_omega_r() {
    for coupling in [FeSeaCoupling::Full, FeSeaCoupling::Mass] {
        for f in [
            50.0, 200.0, 360.0, 400.0, 600.0, 800.0, 1000.0, 1100.0, 5000.0,
        ] {
            let (mut cfg, _) = paper_hybrid(coupling);
            cfg.discretisation.omega_r = Some(2.0 * PI * f);
            let st = crate::model::structure::Structure::build(&cfg).unwrap();
            assert!(st.fesea.is_some());
            crate::linalg::sparse::Ldlt::new(&st.k).unwrap_or_else(|e| panic!("K at {f} Hz: {e}"));
            crate::linalg::sparse::Ldlt::new(&st.m).unwrap_or_else(|e| panic!("M at {f} Hz: {e}"));
        }
    }
}

/// The sine recurrence of the load and shape terms against direct sines.
#[test]
fn load_and_shape_terms_match_direct_sums() {
    for coupling in [FeSeaCoupling::Full, FeSeaCoupling::Mass] {
        let (cfg, rail) = paper_hybrid(coupling);
        let fs = FeSea::new(&cfg, &rail).unwrap();
        let direct = |terms: &[(usize, [f64; 4])], x: f64| -> [f64; 4] {
            let mut out = [0.0; 4];
            for (n, v) in terms {
                let s = fs.scale * (*n as f64 * PI * x / fs.length).sin();
                for g in 0..4 {
                    out[g] += v[g] * s;
                }
            }
            out
        };
        let xs = [0.0, 3.7, 80.0, 159.99];
        let at = fs.load_terms_at(xs);
        for (k, &x) in xs.iter().enumerate() {
            let (a, b) = (direct(&fs.terms_a, x), direct(&fs.terms_b, x));
            let mut sh = [0.0; 4];
            fs.correct_shape(x, &mut sh);
            let s2 = direct(&fs.shape_terms, x);
            for g in 0..4 {
                assert!((at[k].0[g] - a[g]).abs() <= 1e-9 * (1.0 + a[g].abs()));
                assert!((at[k].1[g] - b[g]).abs() <= 1e-9 * (1.0 + b[g].abs()));
                assert!((sh[g] - s2[g]).abs() <= 1e-9 * (1.0 + s2[g].abs()));
            }
        }
    }
}
