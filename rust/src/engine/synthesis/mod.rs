//! Complex-modal synthesis of a finite-element structure (docs/synthesis.md).
//!
//! The structure is linear and shared by every job of a study; the wheels and the dampers
//! are not, and they touch it at a few points. A [`Reduction`] holds the structure's complex
//! modes, (λ²M + λC + K)ψ = 0 normalised to ψᵀ(2λM + C)ψ = 1 (one of each conjugate pair,
//! weight w = 2; real modes w = 1), and the residual of the rail: the moments R_k of the
//! full model's receptance about s = 0 less the kept modes' (R₀ = K⁻¹ − G₀, G_k =
//! −Σ w·Re(ψψᵀ/λ^(k+1)); R₁, R₂ the same of −K⁻¹CK⁻¹ and K⁻¹CK⁻¹CK⁻¹ − K⁻¹MK⁻¹), as bands
//! over the rail's DOFs. The displacement is
//!
//!   u = Re Σ_j ψ_j·Q_j + R₀·g,   Q̇_j = λ_j·Q_j + w_j·ψ_jᵀf,
//!
//! each Q_j stepped exactly under a force linear over the step (`step`): no period error at
//! any Δt; g is each wheel's force through the filter that carries the residual's moments
//! (`engine::coupled::residual`). [`run_lanes`] couples the modes with the wheels (Hertz contact), the dampers
//! (physical elements on fixed ports) and the moving forces, W jobs in lockstep.
//!
//! - `reduction` (this file): the modes, the residual and their checks;
//! - `step`: complex arithmetic, the exact step's coefficients;
//! - `kernels`: the two passes over the modes per step (vectorised, lane-generic);
//! - `run`: the engine's side of the coupled loop, its set-up;
//! - `passes`: the step's phases on that side;
//! - `records`: the records made of the readouts, the dampers' port equations.

mod kernels;
mod passes;
mod records;
mod run;
mod step;

pub use run::{run, run_lanes};

use crate::error::{Result, VtbError};
use crate::model::basis::Shape;
use kernels::{CVec, RailStepCompliance};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use step::Coefficients;

/// Mode arrays are padded with inert modes (ψ = 0, λ = 0, w = 0) to a multiple of this, the
/// partial sums of every dot product over the modes.
pub(crate) const PAD: usize = crate::linalg::simd::PARTIAL_SUMS;

/// The reduction of one structure (see the module documentation).
#[derive(Clone, Debug)]
pub struct Reduction {
    n_dofs: usize,
    /// Modes, and the padded mode count (the row stride of ψ).
    m: usize,
    stride: usize,
    lam_re: Vec<f64>,
    lam_im: Vec<f64>,
    weight: Vec<f64>,
    /// ψ_j at DOF i at `[i·stride + j]`, zero for j ≥ m.
    psi_re: Vec<f64>,
    psi_im: Vec<f64>,
    rail_dofs: usize,
    band: usize,
    /// The reach, in rail DOFs, of the step compliance between loads (≤ `band`): within one
    /// step no wave carries a load farther (`run`).
    step_band: usize,
    /// R_k between rail DOFs i and i + d at `[(k·rail_dofs + i)·(band + 1) + d]`, 0 ≤ d ≤
    /// band, k = 0, 1, 2 (m/N, m·s/N, m·s²/N).
    residual: Vec<f64>,
    /// Each observer's force-feedthrough gains over the rail's DOFs (`gains`), by shape.
    gains: Arc<Mutex<HashMap<ShapeKey, Arc<Gains>>>>,
    /// The rail's step-compliance tables (`rail_step_compliance`), by step (bits) and span.
    step_tables: Arc<Mutex<StepTables>>,
}

/// The rail's step-compliance tables by (step bits, span).
type StepTables = HashMap<(u64, usize), Arc<RailStepCompliance>>;

/// A shape vector as a key (its start and the bits of its values).
type ShapeKey = (usize, Vec<u64>);

/// The direct force terms of an observer's acceleration per unit force at each rail DOF k:
/// `lw[k]` = Re Σ_j ψ_j(s)·λ_j·w_j·ψ_j(k) and `w[k]` = Re Σ_j ψ_j(s)·w_j·ψ_j(k). Shared by every
/// run on the reduction that observes the same shape.
#[derive(Debug)]
struct Gains {
    pub lw: Vec<f64>,
    pub w: Vec<f64>,
}

fn refuse(field: &str, value: impl std::fmt::Display, why: &str) -> VtbError {
    VtbError::config(format!("reduction.{field}"), value, why.to_string())
}

impl Reduction {
    /// Checks every array's length and value: finite, Re λ < 0 (a stable structure), weights
    /// 1 (real λ) or 2 (a pair). `psi` is n_dofs × m complex, row-major, each entry its real
    /// then its imaginary part (numpy's complex128 layout), borrowed: the reduction's only
    /// copy of it is its own padded one. `residual` holds the three moments' bands one after
    /// the other; `step_band` (≤ `band`) is the step compliance's reach.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        n_dofs: usize,
        lam_re: Vec<f64>,
        lam_im: Vec<f64>,
        weight: Vec<f64>,
        psi: &[f64],
        rail_dofs: usize,
        band: usize,
        step_band: usize,
        residual: Vec<f64>,
    ) -> Result<Self> {
        let m = lam_re.len();
        if m == 0 {
            return Err(refuse("modes", 0, "holds no mode"));
        }
        for (name, len, want) in [
            ("lambda_im", lam_im.len(), m),
            ("weight", weight.len(), m),
            ("psi", psi.len(), 2 * n_dofs * m),
            ("residual", residual.len(), 3 * rail_dofs * (band + 1)),
        ] {
            if len != want {
                let what = if name == "psi" {
                    " (re and im of DOFs × modes)"
                } else {
                    ""
                };
                return Err(refuse(name, len, &format!("needs {want} entries{what}")));
            }
        }
        if rail_dofs > n_dofs {
            return Err(refuse("rail_dofs", rail_dofs, "exceeds the DOF count"));
        }
        if step_band > band {
            return Err(refuse(
                "step_band",
                step_band,
                &format!("exceeds the stored band ({band})"),
            ));
        }
        for j in 0..m {
            if !(lam_re[j] < 0.0 && lam_im[j].is_finite() && lam_im[j] >= 0.0) {
                return Err(refuse(
                    &format!("lambda[{j}]"),
                    format!("{} + {}i", lam_re[j], lam_im[j]),
                    "must have Re λ < 0 and Im λ ≥ 0, finite",
                ));
            }
            let want = if lam_im[j] == 0.0 { 1.0 } else { 2.0 };
            if weight[j] != want {
                return Err(refuse(
                    &format!("weight[{j}]"),
                    weight[j],
                    "must be 1 for a real λ, 2 for a pair",
                ));
            }
        }
        if let Some(k) = psi.iter().position(|x| !x.is_finite()) {
            let (i, j, part) = (k / (2 * m), (k / 2) % m, ["re", "im"][k % 2]);
            return Err(refuse(
                &format!("psi[{i}, {j}].{part}"),
                psi[k],
                "must be finite",
            ));
        }
        if let Some(i) = residual.iter().position(|x| !x.is_finite()) {
            return Err(refuse(
                &format!("residual[{i}]"),
                residual[i],
                "must be finite",
            ));
        }
        let stride = m.next_multiple_of(PAD);
        let (mut psi_re, mut psi_im) = (vec![0.0; n_dofs * stride], vec![0.0; n_dofs * stride]);
        for ((re, im), src) in psi_re
            .chunks_exact_mut(stride)
            .zip(psi_im.chunks_exact_mut(stride))
            .zip(psi.chunks_exact(2 * m))
        {
            for (j, z) in src.chunks_exact(2).enumerate() {
                (re[j], im[j]) = (z[0], z[1]);
            }
        }
        let pad = |mut a: Vec<f64>| {
            a.resize(stride, 0.0);
            a
        };
        Ok(Self {
            n_dofs,
            m,
            stride,
            lam_re: pad(lam_re),
            lam_im: pad(lam_im),
            weight: pad(weight),
            psi_re,
            psi_im,
            rail_dofs,
            band,
            step_band,
            residual,
            gains: Arc::default(),
            step_tables: Arc::default(),
        })
    }

    pub fn n_modes(&self) -> usize {
        self.m
    }

    pub fn n_dofs(&self) -> usize {
        self.n_dofs
    }

    /// Rows of ψ (the modes at those DOFs) as (re, im), `rows.len()` × modes, row-major: what
    /// a caller outside the engine reads of ψ (the rail's receptance), so that it need not keep
    /// a second copy of it.
    pub fn psi_rows(&self, rows: &[usize]) -> Result<(Vec<f64>, Vec<f64>)> {
        let mut re = Vec::with_capacity(rows.len() * self.m);
        let mut im = Vec::with_capacity(rows.len() * self.m);
        for &i in rows {
            if i >= self.n_dofs {
                return Err(refuse(
                    "psi_rows",
                    i,
                    &format!("is not a DOF (the reduction has {})", self.n_dofs),
                ));
            }
            let (r, m) = self.row(i);
            re.extend_from_slice(&r[..self.m]);
            im.extend_from_slice(&m[..self.m]);
        }
        Ok((re, im))
    }

    /// Memory held (bytes).
    pub fn bytes(&self) -> usize {
        8 * (self.lam_re.len() * 3 + self.psi_re.len() * 2 + self.residual.len())
    }

    /// The rail's step-compliance table for the step of `coef` (h) and shapes of up to `span`
    /// values: computed by the first run that needs it, then shared.
    fn rail_step_compliance(
        &self,
        coef: &Coefficients,
        h: f64,
        span: usize,
    ) -> Arc<RailStepCompliance> {
        let mut tables = self.step_tables.lock().unwrap_or_else(|e| e.into_inner());
        tables
            .entry((h.to_bits(), span))
            .or_insert_with(|| Arc::new(RailStepCompliance::new(self, coef, span)))
            .clone()
    }

    /// ψ at DOF i (re, im), padded.
    fn row(&self, i: usize) -> (&[f64], &[f64]) {
        let r = i * self.stride..(i + 1) * self.stride;
        (&self.psi_re[r.clone()], &self.psi_im[r])
    }

    /// The `Gains` of observers of shapes s whose ψᵀs are given: those not yet known computed
    /// in one pass over the rail's rows of ψ, then shared.
    fn gains(&self, observers: &[(&Shape, &CVec)]) -> Vec<Arc<Gains>> {
        let key =
            |s: &Shape| -> ShapeKey { (s.start, s.values.iter().map(|v| v.to_bits()).collect()) };
        let mut cache = self.gains.lock().unwrap_or_else(|e| e.into_inner());
        let zeros = vec![0.0; self.stride];
        let missing: Vec<(ShapeKey, CVec, CVec)> = observers
            .iter()
            .filter(|(s, _)| !cache.contains_key(&key(s)))
            .map(|(s, psi)| {
                let (mut pw, mut lw) = (CVec::zeros(self.stride), CVec::zeros(self.stride));
                pw.set_mul([&self.weight, &zeros], psi.parts());
                lw.set_mul([&self.lam_re, &self.lam_im], pw.parts());
                (key(s), lw, pw)
            })
            .collect();
        let mut out: Vec<Gains> = missing
            .iter()
            .map(|_| Gains {
                lw: vec![0.0; self.rail_dofs],
                w: vec![0.0; self.rail_dofs],
            })
            .collect();
        for k in 0..self.rail_dofs {
            let (rr, ri) = self.row(k);
            for ((_, lw, pw), g) in missing.iter().zip(out.iter_mut()) {
                g.lw[k] = kernels::dot(&lw.re, &lw.im, rr, ri);
                g.w[k] = kernels::dot(&pw.re, &pw.im, rr, ri);
            }
        }
        for ((k, _, _), g) in missing.into_iter().zip(out) {
            cache.insert(k, Arc::new(g));
        }
        observers
            .iter()
            .map(|(s, _)| cache[&key(s)].clone())
            .collect()
    }

    /// aᵀ·R₀·b for two shapes on the rail's DOFs (zero beyond the stored band).
    pub fn residual(&self, a: &Shape, b: &Shape) -> f64 {
        self.moment(0, a, b)
    }

    /// aᵀ·R₁·b (m·s/N): the truncated modes' damping term, which a load moving at speed v
    /// drives through its shape's rate v·s′ (`passes`, the moving forces).
    pub fn residual_rate(&self, a: &Shape, b: &Shape) -> f64 {
        self.moment(1, a, b)
    }

    /// sᵀR_k s, k = 0, 1, 2, of a rail shape.
    pub fn residual_moments(&self, s: &Shape) -> [f64; 3] {
        std::array::from_fn(|k| self.moment(k, s, s))
    }

    /// aᵀ·R_k·b.
    fn moment(&self, k: usize, a: &Shape, b: &Shape) -> f64 {
        let bw = self.band + 1;
        let r = &self.residual[k * self.rail_dofs * bw..(k + 1) * self.rail_dofs * bw];
        let mut sum = 0.0;
        for (ka, &va) in a.values.iter().enumerate() {
            let i = a.start + ka;
            if i >= self.rail_dofs || va == 0.0 {
                continue;
            }
            for (kb, &vb) in b.values.iter().enumerate() {
                let k = b.start + kb;
                if k >= self.rail_dofs {
                    continue;
                }
                let (lo, hi) = if i <= k { (i, k) } else { (k, i) };
                if hi - lo <= self.band {
                    sum += va * vb * r[lo * bw + hi - lo];
                }
            }
        }
        sum
    }

    /// The residual's moments under a load of rail shape s (`residual_moments`), checked: a
    /// negative r₀ (a static correction where the kept modes overshoot K⁻¹, residual.rs) is
    /// accepted when the load's whole static flexibility sᵀK⁻¹s (`static_flexibility`) is
    /// positive, else refused as a corrupt reduction (`at` names the load). Non-finite moments
    /// are the filter's to refuse (`Filter::from_moments`).
    pub fn load_moments(&self, s: &Shape, at: impl FnOnce() -> String) -> Result<[f64; 3]> {
        let r = self.residual_moments(s);
        if r[0] < 0.0 {
            let total = self.static_flexibility(s, s);
            if !(total > 0.0) {
                return Err(VtbError::Solver(format!(
                    "the rail residual under {} has moments {:e}, {:e}, {:e} and the load's \
                     static flexibility is {total:e} m/N: not a flexibility (the reduction is \
                     corrupt or not of a stable structure)",
                    at(),
                    r[0],
                    r[1],
                    r[2]
                )));
            }
        }
        Ok(r)
    }

    /// Static flexibility aᵀK⁻¹b of the reduction: −Σ w·Re(ψᵀa·ψᵀb/λ) + aᵀRb.
    pub fn static_flexibility(&self, a: &Shape, b: &Shape) -> f64 {
        let (mut pa, mut pb) = (CVec::zeros(self.stride), CVec::zeros(self.stride));
        kernels::project(self, a, &mut pa);
        kernels::project(self, b, &mut pb);
        let (ar, ai, br, bi) = (&pa.re, &pa.im, &pb.re, &pb.im);
        let mut modal = 0.0;
        for j in 0..self.m {
            let (pr, pi) = (ar[j] * br[j] - ai[j] * bi[j], ar[j] * bi[j] + ai[j] * br[j]);
            let d = self.lam_re[j] * self.lam_re[j] + self.lam_im[j] * self.lam_im[j];
            // Re(p/λ) = (p_r λ_r + p_i λ_i)/|λ|².
            modal -= self.weight[j] * (pr * self.lam_re[j] + pi * self.lam_im[j]) / d;
        }
        modal + self.residual(a, b)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_bad_reduction_names_its_field() {
        // One mode on two DOFs: (Re λ, weight, ψ's length in f64 halves) and the field refused.
        for (lam_re, weight, n_psi, field) in [
            (1.0, 2.0, 4, "reduction.lambda[0]"),
            (-1.0, 1.0, 4, "reduction.weight[0]"),
            (-1.0, 2.0, 3, "reduction.psi"),
        ] {
            let e = Reduction::new(
                2,
                vec![lam_re],
                vec![3.0],
                vec![weight],
                &vec![0.0; n_psi],
                2,
                0,
                0,
                vec![0.0; 6],
            )
            .unwrap_err();
            assert!(e.to_string().contains(field), "{e}");
        }
        // the step's reach cannot pass the stored band
        let e = Reduction::new(
            2,
            vec![-1.0],
            vec![3.0],
            vec![2.0],
            &[0.0; 4],
            2,
            0,
            1,
            vec![0.0; 6],
        )
        .unwrap_err();
        assert!(e.to_string().contains("reduction.step_band"), "{e}");
        // a non-finite entry is named by DOF, mode and part
        let mut psi = vec![0.0; 4];
        psi[3] = f64::NAN;
        let e = Reduction::new(
            2,
            vec![-1.0],
            vec![3.0],
            vec![2.0],
            &psi,
            2,
            0,
            0,
            vec![0.0; 6],
        )
        .unwrap_err();
        assert!(e.to_string().contains("reduction.psi[1, 0].im"), "{e}");
    }

    /// One real mode λ = −1 of ψ = (1, 0) on two rail DOFs (w = 1: static part ψψᵀ = 1 at
    /// DOF 0) and a residual R₀ with diagonal r at DOF 0.
    fn one_mode_with_residual(r: f64) -> Reduction {
        let mut residual = vec![0.0; 6];
        residual[0] = r;
        Reduction::new(
            2,
            vec![-1.0],
            vec![0.0],
            vec![1.0],
            &[1.0, 0.0, 0.0, 0.0],
            2,
            0,
            0,
            residual,
        )
        .unwrap()
    }

    #[test]
    fn a_negative_residual_is_a_static_correction_while_the_loads_flexibility_is_positive() {
        let s = Shape {
            start: 0,
            values: vec![1.0],
        };
        // r₀ = −0.25 under a modal flexibility of 1: the load's flexibility 0.75, accepted.
        let red = one_mode_with_residual(-0.25);
        assert_eq!(red.load_moments(&s, String::new).unwrap()[0], -0.25);
        assert!((red.static_flexibility(&s, &s) - 0.75).abs() < 1e-15);
        // r₀ = −1.5: the load's flexibility would be −0.5: refused, naming the load.
        let red = one_mode_with_residual(-1.5);
        let e = red
            .load_moments(&s, || "wheel 1 at x = 3 m".into())
            .unwrap_err();
        assert!(e.to_string().contains("wheel 1 at x = 3 m"), "{e}");
    }

    #[test]
    fn psi_rows_give_back_the_rows_handed_in() {
        // 3 modes (padded inside to the stride) on 4 DOFs, ψ_j(i) = 10 i + j (re), its negative (im).
        let (n, m) = (4, 3);
        let re: Vec<f64> = (0..n * m).map(|k| (10 * (k / m) + k % m) as f64).collect();
        let psi: Vec<f64> = re.iter().flat_map(|&x| [x, -x]).collect();
        let red = Reduction::new(
            n,
            vec![-1.0; m],
            vec![1.0; m],
            vec![2.0; m],
            &psi,
            n,
            0,
            0,
            vec![0.0; 3 * n],
        )
        .unwrap();
        let (r, i) = red.psi_rows(&[2, 0]).unwrap();
        assert_eq!(r, [20.0, 21.0, 22.0, 0.0, 1.0, 2.0]);
        assert_eq!(i, [-20.0, -21.0, -22.0, -0.0, -1.0, -2.0]);
        let e = red.psi_rows(&[1, 4]).unwrap_err();
        assert!(e.to_string().contains("reduction.psi_rows"), "{e}");
    }
}
