//! Complex-modal synthesis of a finite-element structure (docs/synthesis.md).
//!
//! The structure is linear and shared by every job of a study; the wheels and the dampers
//! are not, and they touch it at a few points. A [`Reduction`] holds the structure's complex
//! modes, (λ²M + λC + K)ψ = 0 normalised to ψᵀ(2λM + C)ψ = 1 (one of each conjugate pair,
//! weight w = 2; real modes w = 1), and the static residual flexibility of the rail, R =
//! K⁻¹ − G_m (G_m = −Σ w·Re(ψψᵀ/λ)), as a band over the rail's DOFs. The displacement is
//!
//!   u = Re Σ_j ψ_j·Q_j + R·f,   Q̇_j = λ_j·Q_j + w_j·ψ_jᵀf,
//!
//! and each Q_j is stepped exactly under a force linear over the step,
//!
//!   Q_{n+1} = e^{z}Q_n + h·[(φ₁ − φ₂)(z)·g_n + φ₂(z)·g_{n+1}]·w,   z = λh,
//!
//! with φ₁(z) = (e^z − 1)/z, φ₂(z) = (e^z − 1 − z)/z²: no period error at any Δt. The linear
//! interpolation of the force samples filters the force's spectrum by sinc²(ωh/2) (−3 % at
//! 2 kHz, h = 5e-5 s). It is not equalised per mode: a mode's factor 1/sinc²(ω_j·h/2) also
//! scales its quasi-static response, which dominates the modes above the force's band, and
//! raised the rail's band-limited peak by 24 % at h = 5e-5 s (docs/synthesis.md).
//!
//! Within a step the displacements at the wheels and at the dampers' ports are affine in the
//! unknown forces through the step compliance Re Σ ψ_a·h·φ₂·w·ψ_b + R_ab, so the contact
//! Newton iterates on the wheel forces alone, as in the finite-element engine. Tuned inerter
//! dampers are physical elements on fixed ports: the trapezoidal rule on their internal node
//! gives F = κ(d − d̃) in the relative port displacement d, which is eliminated exactly.
//! Accelerations are analytic: ü = Re Σ ψ·λ·(λQ + w·g) + Re Σ ψ·w·ġ, the last term the
//! quasi-static share of the truncated modes (Σ over all modes of ψ·w·ψᵀ vanishes), with ġ
//! the rate of the piecewise-linear force over the step.

use crate::basis::Shape;
use crate::config::{InitialState, Profile};
use crate::contact::{ContactSolver, lu_solve_in_place, patch_half_length};
use crate::error::{Result, VtbError};
use crate::integrator::GW;
use crate::model::Model;
use crate::results::{Record, RunResult};
use crate::simulate::{
    CANCEL_POLL, CarRun, FINITE_POLL, LaneSpec, Mover, finish, note_contact, static_wheel_loads,
};
use crate::vehicle::N_WHEELS;
use std::sync::atomic::{AtomicBool, Ordering};

/// The reduction of one structure (see the module documentation).
#[derive(Clone, Debug)]
pub struct Reduction {
    n_dofs: usize,
    m: usize,
    lam_re: Vec<f64>,
    lam_im: Vec<f64>,
    weight: Vec<f64>,
    /// ψ_j at DOF i at `[i·m + j]`.
    psi_re: Vec<f64>,
    psi_im: Vec<f64>,
    rail_dofs: usize,
    band: usize,
    /// R between rail DOFs i and i + d at `[i·(band + 1) + d]`, 0 ≤ d ≤ band.
    residual: Vec<f64>,
}

fn refuse(field: &str, value: impl std::fmt::Display, why: &str) -> VtbError {
    VtbError::config(format!("reduction.{field}"), value, why.to_string())
}

impl Reduction {
    /// Checks every array's length and value: finite, Re λ < 0 (a stable structure), weights
    /// 1 (real λ) or 2 (a pair).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        n_dofs: usize,
        lam_re: Vec<f64>,
        lam_im: Vec<f64>,
        weight: Vec<f64>,
        psi_re: Vec<f64>,
        psi_im: Vec<f64>,
        rail_dofs: usize,
        band: usize,
        residual: Vec<f64>,
    ) -> Result<Self> {
        let m = lam_re.len();
        if m == 0 {
            return Err(refuse("modes", 0, "holds no mode"));
        }
        for (name, len, want) in [
            ("lambda_im", lam_im.len(), m),
            ("weight", weight.len(), m),
            ("psi_re", psi_re.len(), n_dofs * m),
            ("psi_im", psi_im.len(), n_dofs * m),
            ("residual", residual.len(), rail_dofs * (band + 1)),
        ] {
            if len != want {
                return Err(refuse(name, len, &format!("needs {want} entries")));
            }
        }
        if rail_dofs > n_dofs {
            return Err(refuse("rail_dofs", rail_dofs, "exceeds the DOF count"));
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
        for (name, v) in [
            ("psi_re", &psi_re),
            ("psi_im", &psi_im),
            ("residual", &residual),
        ] {
            if let Some(i) = v.iter().position(|x| !x.is_finite()) {
                return Err(refuse(&format!("{name}[{i}]"), v[i], "must be finite"));
            }
        }
        Ok(Self {
            n_dofs,
            m,
            lam_re,
            lam_im,
            weight,
            psi_re,
            psi_im,
            rail_dofs,
            band,
            residual,
        })
    }

    pub fn n_modes(&self) -> usize {
        self.m
    }

    pub fn n_dofs(&self) -> usize {
        self.n_dofs
    }

    /// Memory held (bytes).
    pub fn bytes(&self) -> usize {
        8 * (self.lam_re.len() * 3 + self.psi_re.len() * 2 + self.residual.len())
    }

    /// out = ψᵀs per mode (re, im).
    fn project(&self, s: &Shape, re: &mut [f64], im: &mut [f64]) {
        re.fill(0.0);
        im.fill(0.0);
        let m = self.m;
        for (k, &v) in s.values.iter().enumerate() {
            if v == 0.0 {
                continue;
            }
            let row = (s.start + k) * m..(s.start + k + 1) * m;
            axpy2(re, im, v, &self.psi_re[row.clone()], &self.psi_im[row]);
        }
    }

    /// aᵀ·R·b for two shapes on the rail's DOFs (zero beyond the stored band).
    pub fn residual(&self, a: &Shape, b: &Shape) -> f64 {
        let bw = self.band + 1;
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
                    sum += va * vb * self.residual[lo * bw + hi - lo];
                }
            }
        }
        sum
    }

    /// Static flexibility aᵀK⁻¹b of the reduction: −Σ w·Re(ψᵀa·ψᵀb/λ) + aᵀRb.
    pub fn static_flexibility(&self, a: &Shape, b: &Shape) -> f64 {
        let m = self.m;
        let (mut ar, mut ai, mut br, mut bi) =
            (vec![0.0; m], vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        self.project(a, &mut ar, &mut ai);
        self.project(b, &mut br, &mut bi);
        let mut modal = 0.0;
        for j in 0..m {
            let (pr, pi) = (ar[j] * br[j] - ai[j] * bi[j], ar[j] * bi[j] + ai[j] * br[j]);
            let d = self.lam_re[j] * self.lam_re[j] + self.lam_im[j] * self.lam_im[j];
            // Re(p/λ) = (p_r λ_r + p_i λ_i)/|λ|².
            modal -= self.weight[j] * (pr * self.lam_re[j] + pi * self.lam_im[j]) / d;
        }
        modal + self.residual(a, b)
    }
}

// ------------------------------------------------------------------ complex arithmetic
#[derive(Clone, Copy, Debug, PartialEq)]
struct C(f64, f64);

impl C {
    fn mul(self, o: C) -> C {
        C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
    }
    fn add(self, o: C) -> C {
        C(self.0 + o.0, self.1 + o.1)
    }
    fn scale(self, s: f64) -> C {
        C(self.0 * s, self.1 * s)
    }
    fn div(self, o: C) -> C {
        let d = o.0 * o.0 + o.1 * o.1;
        C(
            (self.0 * o.0 + self.1 * o.1) / d,
            (self.1 * o.0 - self.0 * o.1) / d,
        )
    }
    fn exp(self) -> C {
        let r = self.0.exp();
        C(r * self.1.cos(), r * self.1.sin())
    }
}

/// φ₁(z) = (e^z − 1)/z and φ₂(z) = (e^z − 1 − z)/z², by their Taylor series near 0 (where
/// the closed forms cancel) and in closed form elsewhere.
fn phi12(z: C) -> (C, C) {
    let r = (z.0 * z.0 + z.1 * z.1).sqrt();
    if r < 0.5 {
        // Σ z^k/(k+1)! and Σ z^k/(k+2)!; 0.5^24/24! is far below rounding.
        let (mut p1, mut p2) = (C(0.0, 0.0), C(0.0, 0.0));
        let mut term = C(1.0, 0.0); // z^k/k!
        for k in 0..24 {
            p1 = p1.add(term.scale(1.0 / (k + 1) as f64));
            p2 = p2.add(term.scale(1.0 / ((k + 1) * (k + 2)) as f64));
            term = term.mul(z).scale(1.0 / (k + 1) as f64);
        }
        (p1, p2)
    } else {
        let e1 = z.exp().add(C(-1.0, 0.0));
        let p1 = e1.div(z);
        (p1, e1.add(z.scale(-1.0)).div(z.mul(z)))
    }
}

/// Per-mode step coefficients: e^{λh}, and the weights of g_n and g_{n+1} (with w).
#[derive(Clone, Debug)]
struct Coefficients {
    e: Vec<C>,
    a0: Vec<C>,
    a1: Vec<C>,
}

impl Coefficients {
    fn new(red: &Reduction, h: f64) -> Self {
        let m = red.m;
        let (mut e, mut a0, mut a1) = (
            Vec::with_capacity(m),
            Vec::with_capacity(m),
            Vec::with_capacity(m),
        );
        for j in 0..m {
            let z = C(red.lam_re[j] * h, red.lam_im[j] * h);
            let (p1, p2) = phi12(z);
            let s = red.weight[j] * h;
            e.push(z.exp());
            a0.push(p1.add(p2.scale(-1.0)).scale(s));
            a1.push(p2.scale(s));
        }
        Self { e, a0, a1 }
    }
}

/// A complex vector over the modes, stored as two real arrays (vectorisable loops).
#[derive(Clone, Debug, Default)]
struct MVec {
    re: Vec<f64>,
    im: Vec<f64>,
}

impl MVec {
    fn zeros(m: usize) -> Self {
        Self {
            re: vec![0.0; m],
            im: vec![0.0; m],
        }
    }

    /// Re Σ self·o.
    #[inline]
    fn re_dot(&self, o: &MVec) -> f64 {
        re_dot(&self.re, &self.im, &o.re, &o.im)
    }

    /// self += w·o.
    #[inline]
    fn axpy(&mut self, w: f64, o: &MVec) {
        axpy2(&mut self.re, &mut self.im, w, &o.re, &o.im);
    }

    /// self = c ⊙ o.
    fn set_mul(&mut self, c: &[C], o: &MVec) {
        for j in 0..self.re.len() {
            let (a, b) = (o.re[j], o.im[j]);
            self.re[j] = c[j].0 * a - c[j].1 * b;
            self.im[j] = c[j].0 * b + c[j].1 * a;
        }
    }
}

/// The one width the synthesis kernels are compiled for (`wide!` is generic over lanes).
const ONE: usize = 1;

/// Re Σ (ar + i·ai)(br + i·bi) in eight partial sums (fused multiply–adds, AVX2 where the CPU
/// has it).
#[inline]
fn re_dot(ar: &[f64], ai: &[f64], br: &[f64], bi: &[f64]) -> f64 {
    crate::wide!(<ONE> (ar: &[f64] = ar, ai: &[f64] = ai, br: &[f64] = br, bi: &[f64] = bi) -> f64 {
        const P: usize = 8;
        let n = ar.len().min(ai.len()).min(br.len()).min(bi.len());
        let (ar, ai, br, bi) = (&ar[..n], &ai[..n], &br[..n], &bi[..n]);
        let mut acc = [0.0; P];
        let full = n - n % P;
        for c in (0..full).step_by(P) {
            for q in 0..P {
                let j = c + q;
                acc[q] = ar[j].mul_add(br[j], (-ai[j]).mul_add(bi[j], acc[q]));
            }
        }
        for j in full..n {
            acc[j - full] = ar[j].mul_add(br[j], (-ai[j]).mul_add(bi[j], acc[j - full]));
        }
        ((acc[0] + acc[1]) + (acc[2] + acc[3])) + ((acc[4] + acc[5]) + (acc[6] + acc[7]))
    })
}

/// (yr, yi) += w·(xr, xi) (fused, AVX2 where the CPU has it).
#[inline]
fn axpy2(yr: &mut [f64], yi: &mut [f64], w: f64, xr: &[f64], xi: &[f64]) {
    crate::wide!(<ONE> (yr: &mut [f64] = yr, yi: &mut [f64] = yi, w: f64 = w, xr: &[f64] = xr, xi: &[f64] = xi) {
        let n = yr.len().min(yi.len()).min(xr.len()).min(xi.len());
        let (yr, yi, xr, xi) = (&mut yr[..n], &mut yi[..n], &xr[..n], &xi[..n]);
        for j in 0..n {
            yr[j] = w.mul_add(xr[j], yr[j]);
            yi[j] = w.mul_add(xi[j], yi[j]);
        }
    })
}

/// A tuned inerter damper on two fixed ports (docs/model.md §5) with its trapezoidal state.
struct Damper {
    upper: Shape,
    /// ψᵀ(s_up − s_low), and h·φ₂·w ⊙ it.
    psi: MVec,
    psi_a1: MVec,
    /// Re Σ_j (h·φ₂·w·ψᵀ(s_up − s_low))_j·ψ_j at every rail DOF: the step compliance between
    /// the damper and a wheel is its dot with the wheel's shape (a few entries, not a sum over
    /// the modes).
    rail_gain: Vec<f64>,
    kappa: f64,
    k: f64,
    c: f64,
    b: f64,
    /// Spring extension and rate; inerter relative displacement, velocity, acceleration.
    r: f64,
    rd: f64,
    s: f64,
    sd: f64,
    sdd: f64,
    /// This step: r̂ and s̃ (F = κ(d − r̂ − s̃)).
    r_hat: f64,
    s_tilde: f64,
}

/// An observation point of one layer: ψᵀs for the displacement, ψᵀs·λ², ψᵀs·λ·w and ψᵀs·w
/// for the acceleration, and its shape for the rail's residual.
struct Observer {
    psi: MVec,
    psi_l2: MVec,
    psi_lw: MVec,
    psi_w: MVec,
    shape: Option<Shape>,
}

/// One run on a reduction.
pub fn run(
    model: &Model,
    spec: &LaneSpec,
    red: &Reduction,
    record: Record,
    cancel: Option<&AtomicBool>,
) -> Result<RunResult> {
    let cfg = &model.cfg;
    let st = &model.structure;
    let layer_dofs = st.base.as_ref().map_or(st.n_dofs, |b| b[0].n);
    if red.n_dofs != layer_dofs || red.rail_dofs != st.layers[0].n_dofs() {
        return Err(VtbError::config(
            "discretisation.synthesis_cutoff",
            cfg.discretisation.synthesis_cutoff.unwrap_or(0.0),
            format!(
                "the reduction has {} DOFs ({} on the rail), the structure {} ({}): it was \
                 built for another structure",
                red.n_dofs,
                red.rail_dofs,
                layer_dofs,
                st.layers[0].n_dofs()
            ),
        ));
    }
    let m = red.m;
    let dt = cfg.solver.dt;
    let g = cfg.solver.gravity;
    let v = cfg.speed;
    let coef = Coefficients::new(red, dt);
    let points = match record {
        Record::Full => cfg.observation_points(),
        Record::Metrics => cfg.observation_points()[..1].to_vec(),
    };
    crate::budget::check_histories(cfg, record, 1)?;
    let project = |s: &Shape| {
        let mut p = MVec::zeros(m);
        red.project(s, &mut p.re, &mut p.im);
        p
    };
    let lam: Vec<C> = (0..m).map(|j| C(red.lam_re[j], red.lam_im[j])).collect();
    let mut observers = Vec::new();
    for li in 0..st.layers.len() {
        for &x in &points {
            let s = st.shape(li, x);
            let psi = project(&s);
            let mut psi_l2 = MVec::zeros(m);
            let mut psi_lw = MVec::zeros(m);
            let mut psi_w = MVec::zeros(m);
            let l2: Vec<C> = lam.iter().map(|l| l.mul(*l)).collect();
            let lw: Vec<C> = (0..m).map(|j| lam[j].scale(red.weight[j])).collect();
            let w: Vec<C> = red.weight.iter().map(|&w| C(w, 0.0)).collect();
            psi_l2.set_mul(&l2, &psi);
            psi_lw.set_mul(&lw, &psi);
            psi_w.set_mul(&w, &psi);
            observers.push(Observer {
                psi,
                psi_l2,
                psi_lw,
                psi_w,
                shape: (li == 0).then_some(s),
            });
        }
    }
    let mut dampers: Vec<Damper> = st
        .tids
        .iter()
        .zip(&spec.dampers)
        .map(|(a, p)| {
            let mut psi = project(&a.upper);
            let low = project(&a.lower);
            psi.axpy(-1.0, &low);
            let mut psi_a1 = MVec::zeros(m);
            psi_a1.set_mul(&coef.a1, &psi);
            let rail_gain = (0..red.rail_dofs)
                .map(|i| {
                    let row = i * m..(i + 1) * m;
                    re_dot(
                        &psi_a1.re,
                        &psi_a1.im,
                        &red.psi_re[row.clone()],
                        &red.psi_im[row],
                    )
                })
                .collect();
            let (k, c, b) = (p.stiffness, p.damping, p.inertance);
            Damper {
                upper: a.upper.clone(),
                psi,
                psi_a1,
                rail_gain,
                kappa: 1.0 / (1.0 / (k + 2.0 * c / dt) + dt * dt / (4.0 * b)),
                k,
                c,
                b,
                r: 0.0,
                rd: 0.0,
                s: 0.0,
                sd: 0.0,
                sdd: 0.0,
                r_hat: 0.0,
                s_tilde: 0.0,
            }
        })
        .collect();
    let nd = dampers.len();
    // S = I + diag(κ)·G_dd is constant over the run (fixed ports): its inverse once.
    let mut s_inv = vec![0.0; nd * nd];
    if nd > 0 {
        let mut s_mat = vec![0.0; nd * nd];
        for e in 0..nd {
            for f in 0..nd {
                let gdd = dampers[e].psi_a1.re_dot(&dampers[f].psi)
                    + red.residual(&dampers[e].upper, &dampers[f].upper);
                s_mat[e * nd + f] = f64::from(u8::from(e == f)) + dampers[e].kappa * gdd;
            }
        }
        for f in 0..nd {
            let mut col: Vec<f64> = (0..nd).map(|e| f64::from(u8::from(e == f))).collect();
            lu_solve_in_place(&mut s_mat.clone(), &mut col, nd);
            for e in 0..nd {
                s_inv[e * nd + f] = col[e];
            }
        }
    }

    let movers = Mover::all(cfg);
    let mut cars = model
        .cars
        .iter()
        .map(|c| CarRun::<1>::new(c, dt, g))
        .collect::<Result<Vec<_>>>()?;
    let nw = cars.len() * N_WHEELS;
    let loads = static_wheel_loads(&cars, g);
    if let Some((i, l)) = loads.iter().enumerate().find(|(_, l)| !(**l > 0.0)) {
        return Err(VtbError::config(
            format!("vehicles[{}]", i / N_WHEELS),
            l,
            format!("wheelset {} carries no static load", i % N_WHEELS + 1),
        ));
    }
    let patch: Vec<f64> = loads
        .iter()
        .enumerate()
        .map(|(wi, &load)| {
            let veh = &cfg.vehicles[wi / N_WHEELS];
            if veh.contact_patch {
                patch_half_length(load, veh.wheel_radius, veh.rail_crown_radius)
            } else {
                0.0
            }
        })
        .collect();
    let hertz: Vec<f64> = cars
        .iter()
        .flat_map(|c| [c.car.hertz_g; N_WHEELS])
        .collect();
    let mut contact = ContactSolver::new(
        hertz,
        loads.clone(),
        cfg.solver.contact_tol,
        cfg.solver.contact_max_iter,
    );
    let wheel_x0: Vec<f64> = cars.iter().flat_map(|c| c.car.wheel_x0).collect();

    // Loads on the structure at a time t: wheel shapes and ψᵀs; movers likewise.
    let mut wheel_shapes: Vec<Shape> = (0..nw)
        .map(|w| Shape {
            start: 0,
            values: Vec::with_capacity(st.wheel_shape_len(patch[w])),
        })
        .collect();
    let mut psi_w: Vec<MVec> = (0..nw).map(|_| MVec::zeros(m)).collect();
    let mut psi_w_a1: Vec<MVec> = (0..nw).map(|_| MVec::zeros(m)).collect();
    let mut mover_shapes: Vec<Shape> = movers
        .iter()
        .map(|mv| Shape {
            start: 0,
            values: vec![0.0; st.layers[mv.layer].basis.shape_len()],
        })
        .collect();
    let mut mover_psi = MVec::zeros(m);
    let set_wheels = |t: f64, shapes: &mut [Shape], psi: &mut [MVec]| {
        for w in 0..nw {
            st.wheel_shape_into(wheel_x0[w] + v * t, patch[w], &mut shapes[w]);
            red.project(&shapes[w], &mut psi[w].re, &mut psi[w].im);
        }
    };
    // Modal forces (unweighted ψᵀf) of the movers at t into `gk`, their shapes into `shapes`.
    let movers_at = |t: f64, gk: &mut MVec, shapes: &mut [Shape], psi: &mut MVec| {
        gk.re.fill(0.0);
        gk.im.fill(0.0);
        for (mv, sh) in movers.iter().zip(shapes.iter_mut()) {
            st.shape_into(mv.layer, mv.x0 + v * t, sh);
            red.project(sh, &mut psi.re, &mut psi.im);
            gk.axpy(mv.magnitude, psi);
        }
    };
    let rest = cfg.solver.initial_state == InitialState::Rest;
    // The rail's residual displacement at shape s under the wheels' forces p and the rail's
    // moving forces.
    let residual_at = |s: &Shape, wheels: &[Shape], p: &[f64], movers_now: &[Shape]| {
        let mut u = 0.0;
        for (sw, pw) in wheels.iter().zip(p) {
            u += pw * red.residual(s, sw);
        }
        for (mv, sm) in movers.iter().zip(movers_now) {
            if mv.layer == 0 {
                u += mv.magnitude * red.residual(s, sm);
            }
        }
        u
    };

    // ------------------------------------------------------------- initial state (t = 0)
    let mut q = MVec::zeros(m);
    let mut g_prev = MVec::zeros(m);
    movers_at(0.0, &mut g_prev, &mut mover_shapes, &mut mover_psi);
    set_wheels(0.0, &mut wheel_shapes, &mut psi_w);
    let mut p = loads.clone();
    for w in 0..nw {
        g_prev.axpy(p[w], &psi_w[w]);
    }
    if !rest {
        for j in 0..m {
            // λQ + w·g = 0.
            let qj = C(g_prev.re[j], g_prev.im[j])
                .scale(-red.weight[j])
                .div(lam[j]);
            q.re[j] = qj.0;
            q.im[j] = qj.1;
        }
    }
    let static_residual = |s: &Shape, wheels: &[Shape], p: &[f64], movers_now: &[Shape]| {
        if rest {
            0.0
        } else {
            residual_at(s, wheels, p, movers_now)
        }
    };
    for d in dampers.iter_mut() {
        d.s = d.psi.re_dot(&q) + static_residual(&d.upper, &wheel_shapes, &p, &mover_shapes);
    }
    let profile: &Profile = spec.profile;
    for (ci, c) in cars.iter_mut().enumerate() {
        let rail: [f64; N_WHEELS] = std::array::from_fn(|w| {
            let wi = ci * N_WHEELS + w;
            psi_w[wi].re_dot(&q)
                + static_residual(&wheel_shapes[wi], &wheel_shapes, &p, &mover_shapes)
                + cfg.irregularity_share(0.0) * profile.at(wheel_x0[wi])
        });
        c.set_static(0, rail, &loads[ci * N_WHEELS..(ci + 1) * N_WHEELS], g)?;
        let pc: [f64; GW] = std::array::from_fn(|w| {
            if w < N_WHEELS {
                p[ci * N_WHEELS + w]
            } else {
                0.0
            }
        });
        c.set_force(&[pc]);
    }

    let n_steps = cfg.n_steps();
    let mut res = RunResult::new(cfg, st, n_steps, &points, cars.len(), nw, record);
    let no = observers.len();
    let record_step = |res: &mut RunResult,
                       step: usize,
                       q: &MVec,
                       g: &MVec,
                       g_rate: &MVec,
                       shapes: &[Shape],
                       p: &[f64],
                       movers_now: &[Shape],
                       cars: &[CarRun<1>],
                       ur: &mut [[f64; 2]]| {
        for (j, o) in observers.iter().enumerate() {
            let mut u = o.psi.re_dot(q);
            res.acc[step * no + j] =
                o.psi_l2.re_dot(q) + o.psi_lw.re_dot(g) + o.psi_w.re_dot(g_rate);
            if let Some(s) = &o.shape {
                // The residual's displacement moves with the loads; its acceleration is the
                // central second difference, added to the previous step once this one is known
                // (before t = 0 the loads stood still).
                let r = residual_at(s, shapes, p, movers_now);
                u += r;
                let [before, last] = if step == 0 { [r, r] } else { ur[j] };
                if step > 0 {
                    let before = if step == 1 { last } else { before };
                    res.acc[(step - 1) * no + j] += (r - 2.0 * last + before) / (dt * dt);
                }
                ur[j] = [last, r];
            }
            res.disp[step * no + j] = u;
        }
        let (ncars, ndof) = (res.n_cars, res.vehicle_dofs);
        for (ci, c) in cars.iter().take(ncars).enumerate() {
            for i in 0..ndof {
                let (z, _, a) = c.nm.observed(i, 0);
                res.vehicle_disp[(step * ncars + ci) * ndof + i] = z - c.z0[i];
                res.vehicle_acc[(step * ncars + ci) * ndof + i] = a;
            }
        }
        res.contact_force[step * nw..(step + 1) * nw].copy_from_slice(p);
    };
    let mut g_rate = MVec::zeros(m);
    let mut ur = vec![[0.0; 2]; no];
    record_step(
        &mut res,
        0,
        &q,
        &g_prev,
        &g_rate,
        &wheel_shapes,
        &p,
        &mover_shapes,
        &cars,
        &mut ur,
    );

    // ------------------------------------------------------------- the steps
    let mut g_known = MVec::zeros(m);
    let mut g_next = MVec::zeros(m);
    let mut q_free = MVec::zeros(m);
    let mut tmp = vec![0.0; nd];
    let mut amat = vec![0.0; nw * nw];
    let mut delta_free = vec![0.0; nw];
    let mut gdw = vec![0.0; nd * nw];
    let mut t_mat = vec![0.0; nd * nw];
    let mut f0 = vec![0.0; nd];
    let mut loss_open = vec![None; nw];
    for step in 0..n_steps {
        if step % CANCEL_POLL == 0 && cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(VtbError::Cancelled);
        }
        if step % FINITE_POLL == 0 && !(q.re.iter().chain(&q.im).all(|x| x.is_finite())) {
            return Err(VtbError::Solver(format!(
                "the modal coordinates became non-finite by step {step}: an overflow, most likely \
                 from parameters of extreme magnitude"
            )));
        }
        let t1 = (step + 1) as f64 * dt;
        let share = cfg.irregularity_share(t1);
        movers_at(t1, &mut g_known, &mut mover_shapes, &mut mover_psi);
        // Q̃ = e·Q + a0·g_n + a1·g_known.
        for j in 0..m {
            let (qr, qi) = (q.re[j], q.im[j]);
            let (e, a0, a1) = (coef.e[j], coef.a0[j], coef.a1[j]);
            q_free.re[j] = e.0 * qr - e.1 * qi + a0.0 * g_prev.re[j] - a0.1 * g_prev.im[j]
                + a1.0 * g_known.re[j]
                - a1.1 * g_known.im[j];
            q_free.im[j] = e.0 * qi
                + e.1 * qr
                + a0.0 * g_prev.im[j]
                + a0.1 * g_prev.re[j]
                + a1.0 * g_known.im[j]
                + a1.1 * g_known.re[j];
        }
        set_wheels(t1, &mut wheel_shapes, &mut psi_w);
        for w in 0..nw {
            psi_w_a1[w].set_mul(&coef.a1, &psi_w[w]);
        }
        // The dampers: F = F0 + T·P.
        for (e, d) in dampers.iter_mut().enumerate() {
            d.r_hat = d.c * (2.0 * d.r / dt + d.rd) / (d.k + 2.0 * d.c / dt);
            d.s_tilde = d.s + dt * d.sd + 0.25 * dt * dt * d.sdd;
            let free = d.psi.re_dot(&q_free) + residual_at(&d.upper, &[], &[], &mover_shapes);
            f0[e] = d.kappa * (free - d.r_hat - d.s_tilde);
            for w in 0..nw {
                let sw = &wheel_shapes[w];
                let gain = &d.rail_gain[sw.start..sw.start + sw.values.len()];
                let modal: f64 = sw.values.iter().zip(gain).map(|(a, b)| a * b).sum();
                let gv = modal + red.residual(&d.upper, sw);
                gdw[e * nw + w] = gv;
                t_mat[e * nw + w] = d.kappa * gv;
            }
        }
        // F0 ← S⁻¹·F0, T ← S⁻¹·T.
        tmp.copy_from_slice(&f0);
        for e in 0..nd {
            f0[e] = (0..nd).map(|f| s_inv[e * nd + f] * tmp[f]).sum();
        }
        for w in 0..nw {
            for e in 0..nd {
                tmp[e] = t_mat[e * nw + w];
            }
            for e in 0..nd {
                t_mat[e * nw + w] = (0..nd).map(|f| s_inv[e * nd + f] * tmp[f]).sum();
            }
        }
        // The wheels: δ = δ_free − A·P.
        for (ci, c) in cars.iter_mut().enumerate() {
            c.nm.begin_step(&c.f_prev, &c.gravity);
            let wheel = c.nm.free_port_disp(&c.ports)[0];
            for w in 0..N_WHEELS {
                let wi = ci * N_WHEELS + w;
                let mut rail = psi_w[wi].re_dot(&q_free)
                    + residual_at(&wheel_shapes[wi], &[], &[], &mover_shapes);
                for e in 0..nd {
                    rail -= gdw[e * nw + wi] * f0[e];
                }
                delta_free[wi] = wheel[w] - rail - share * profile.at(wheel_x0[wi] + v * t1);
            }
        }
        for wi in 0..nw {
            for vi in wi..nw {
                let mut a = psi_w_a1[wi].re_dot(&psi_w[vi])
                    + red.residual(&wheel_shapes[wi], &wheel_shapes[vi]);
                for e in 0..nd {
                    a -= gdw[e * nw + wi] * t_mat[e * nw + vi];
                }
                let (ci, cj) = (wi / N_WHEELS, vi / N_WHEELS);
                if ci == cj {
                    a += cars[ci].car.rails * cars[ci].compliance[wi % N_WHEELS][vi % N_WHEELS];
                }
                if wi == vi && cfg.discretisation.element_flexibility {
                    a += st.wheel_flexibility(wheel_x0[wi] + v * t1, patch[wi]);
                }
                amat[wi * nw + vi] = a;
                amat[vi * nw + wi] = a;
            }
        }
        if nw > 0 {
            contact.solve(&mut p, &delta_free, &amat, t1, step + 1)?;
        }
        // Forces known: the dampers' forces, their states, and the modes.
        g_next.re.copy_from_slice(&g_known.re);
        g_next.im.copy_from_slice(&g_known.im);
        for w in 0..nw {
            g_next.axpy(p[w], &psi_w[w]);
        }
        for (e, d) in dampers.iter_mut().enumerate() {
            let f: f64 = f0[e] + (0..nw).map(|w| t_mat[e * nw + w] * p[w]).sum::<f64>();
            g_next.axpy(-f, &d.psi);
            let r1 = f / (d.k + 2.0 * d.c / dt) + d.r_hat;
            d.rd = 2.0 * (r1 - d.r) / dt - d.rd;
            d.r = r1;
            let sdd1 = f / d.b;
            let sd1 = d.sd + 0.5 * dt * (d.sdd + sdd1);
            d.s += 0.5 * dt * (d.sd + sd1);
            d.sd = sd1;
            d.sdd = sdd1;
        }
        // Q = Q̃ + a1·(g_next − g_known).
        for j in 0..m {
            let (dr, di) = (g_next.re[j] - g_known.re[j], g_next.im[j] - g_known.im[j]);
            let a1 = coef.a1[j];
            q.re[j] = q_free.re[j] + a1.0 * dr - a1.1 * di;
            q.im[j] = q_free.im[j] + a1.0 * di + a1.1 * dr;
        }
        for j in 0..m {
            g_rate.re[j] = (g_next.re[j] - g_prev.re[j]) / dt;
            g_rate.im[j] = (g_next.im[j] - g_prev.im[j]) / dt;
        }
        std::mem::swap(&mut g_prev, &mut g_next);
        for (ci, c) in cars.iter_mut().enumerate() {
            let pc: [f64; GW] = std::array::from_fn(|w| {
                if w < N_WHEELS {
                    p[ci * N_WHEELS + w]
                } else {
                    0.0
                }
            });
            let wheel = [pc.map(|pw| -c.car.rails * pw)];
            c.nm.add_port_forces(&c.ports, &wheel);
            c.nm.end_step();
            c.set_force(&[pc]);
        }
        note_contact(&mut loss_open, &p, t1, &mut res.contact_loss);
        record_step(
            &mut res,
            step + 1,
            &q,
            &g_prev,
            &g_rate,
            &wheel_shapes,
            &p,
            &mover_shapes,
            &cars,
            &mut ur,
        );
    }
    finish(&loss_open, res)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact step of q̇ = λq + g(t) under a force linear over the step against the
    /// closed-form integral, for a slow, a fast and an overdamped mode.
    #[test]
    fn exact_modal_step_matches_the_closed_form() {
        for (lr, li, h) in [
            (-3.0, 20.0, 1e-4),
            (-900.0, 12000.0, 5e-5),
            (-8000.0, 0.0, 5e-5),
        ] {
            let lam = C(lr, li);
            let z = lam.scale(h);
            let (p1, p2) = phi12(z);
            let (g0, g1, q0) = (C(0.7, -0.2), C(-1.3, 0.4), C(0.25, 0.5));
            let q1 = z
                .exp()
                .mul(q0)
                .add(p1.add(p2.scale(-1.0)).scale(h).mul(g0))
                .add(p2.scale(h).mul(g1));
            // Closed form: q(h) = e^{λh}q0 + ∫ e^{λ(h−τ)}(g0 + (g1 − g0)τ/h)dτ
            //   = e^{λh}q0 + g0(e^{λh} − 1)/λ + (g1 − g0)(e^{λh} − 1 − λh)/(λ²h).
            let e = lam.scale(h).exp();
            let one = C(1.0, 0.0);
            let dg = g1.add(g0.scale(-1.0));
            let want = e.mul(q0).add(g0.mul(e.add(one.scale(-1.0)).div(lam))).add(
                dg.mul(
                    e.add(one.scale(-1.0))
                        .add(lam.scale(-h))
                        .div(lam.mul(lam).scale(h)),
                ),
            );
            let err = ((q1.0 - want.0).powi(2) + (q1.1 - want.1).powi(2)).sqrt();
            let size = (want.0.powi(2) + want.1.powi(2)).sqrt();
            assert!(err <= 1e-10 * size, "λ = {lr} + {li}i: {q1:?} vs {want:?}");
        }
    }

    /// Near z = 0 the series and the closed forms of φ₁, φ₂ agree where both are accurate.
    #[test]
    fn phi_series_and_closed_form_agree_at_the_switch() {
        let z = C(-0.3, 0.399);
        let (s1, s2) = phi12(z);
        let e1 = z.exp().add(C(-1.0, 0.0));
        let c1 = e1.div(z);
        let c2 = e1.add(z.scale(-1.0)).div(z.mul(z));
        for (a, b) in [(s1, c1), (s2, c2)] {
            assert!(
                (a.0 - b.0).abs() < 1e-13 && (a.1 - b.1).abs() < 1e-13,
                "{a:?} {b:?}"
            );
        }
    }

    #[test]
    fn a_bad_reduction_names_its_field() {
        // One mode on two DOFs: (Re λ, weight, psi_re length) and the field refused.
        for (lam_re, weight, n_psi, field) in [
            (1.0, 2.0, 2, "reduction.lambda[0]"),
            (-1.0, 1.0, 2, "reduction.weight[0]"),
            (-1.0, 2.0, 3, "reduction.psi_re"),
        ] {
            let e = Reduction::new(
                2,
                vec![lam_re],
                vec![3.0],
                vec![weight],
                vec![0.0; n_psi],
                vec![0.0; 2],
                2,
                0,
                vec![0.0; 2],
            )
            .unwrap_err();
            assert!(e.to_string().contains(field), "{e}");
        }
    }
}
