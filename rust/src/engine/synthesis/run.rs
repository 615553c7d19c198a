//! The coupled step on a reduction: W jobs of one model in lockstep (W = 1: a single run).
//!
//! The jobs of a group share the structure, the speed and the vehicles, so the wheels'
//! positions, their modal shapes ψᵀs and step compliances are computed once per step for all
//! of them (`kernels::wheel_pass`); each job has its own modal state, irregularity, contact
//! forces and dampers' parameters (`kernels::update`). A step is a few named phases
//! ([`Run::step`]): loads, wheel pass, dampers, contact, forces, update, record.
//!
//! Within a step the displacements at the wheels and at the dampers' ports are affine in the
//! unknown forces through the step compliance Re Σ ψ_a·a1·ψ_b + R_ab·γ_b (γ_b the step gain of
//! load b's residual filter, `residual`; 1 for a damper's force), so the contact Newton
//! iterates on the wheel forces alone, as in the finite-element engine. Two loads farther
//! apart than the residual's reach (`Reduction::band` rail DOFs) have no step compliance:
//! within one step (50 µs) no wave carries a load that far (the rail's shear wave needs
//! 0.3 ms per metre), so the full model's value is nil and the truncated modes' remainder is
//! noise. Tuned inerter dampers are physical elements on fixed ports: the trapezoidal rule on
//! their internal node gives F = κ(d − d̃) in the relative port displacement d, which is
//! eliminated exactly.
//!
//! Accelerations are analytic, Q̈ = λ²Q + λw·g + w·ġ per mode: the kernel reads Re Σ λ²ψᵀs·Q;
//! the force's direct terms Re Σ ψᵀs·λw·g and Re Σ ψᵀs·w·g are sums over the ports of the
//! force times a gain (`Gains` over the rail's DOFs for the wheels, constants for the
//! dampers); `records` assembles them with the rail residual's acceleration.

use super::kernels::{self, Acc, CVec, RailStepCompliance, Scratch, Update, WheelPass};
use super::residual::{Filter, FilterStep};
use super::step::{C, Coefficients};
use super::{Gains, Reduction};
use crate::config::InitialState;
use crate::engine::coupled::{CarRun, Mover, finish, note_contact, static_wheel_loads};
use crate::engine::integrator::GW;
use crate::engine::{CANCEL_POLL, Control, FINITE_POLL, LaneSpec, poll};
use crate::error::{Result, VtbError};
use crate::model::Model;
use crate::model::basis::Shape;
use crate::model::contact::{ContactSolver, patch_half_length};
use crate::model::dampers::{Branch, BranchState};
use crate::outputs::{Record, RunResult};
use std::sync::Arc;

/// One run on a reduction.
pub fn run(
    model: &Model,
    spec: &LaneSpec,
    red: &Reduction,
    record: Record,
    cancel: Option<&Control>,
) -> Result<RunResult> {
    run_lanes::<1>(model, std::slice::from_ref(spec), red, record, cancel)?
        .pop()
        .expect("one lane")
}

/// W jobs of one model on a reduction: lane c runs on `specs[c]`'s irregularity and damper
/// parameters. The outer error is shared by all lanes (setup, cancellation); the inner ones
/// are each lane's own (a failing lane idles while the others go on).
pub fn run_lanes<const W: usize>(
    model: &Model,
    specs: &[LaneSpec],
    red: &Reduction,
    record: Record,
    cancel: Option<&Control>,
) -> Result<Vec<Result<RunResult>>> {
    let mut run = Run::<W>::new(model, specs, red, record)?;
    run.initial_state()?;
    for step in 0..run.n_steps {
        if step % CANCEL_POLL == 0 && poll(cancel, step, run.n_steps) {
            return Err(VtbError::Cancelled);
        }
        if step % FINITE_POLL == 0 {
            run.check_finite(step);
        }
        if run.lanes.iter().all(|l| l.error.is_some()) {
            break;
        }
        run.step(step);
    }
    Ok(run.finish())
}

/// A damper's shared data: its ports and its step compliance with rail DOFs near it.
struct DamperPort {
    upper: Shape,
    /// Re Σ_j a1_j·ψᵀ(s_up − s_low)_j·ψ_j at rail DOFs `gain_start..` (the residual's reach
    /// around the damper).
    gain_start: usize,
    gain: Vec<f64>,
}

/// A damper of one lane: its parameters and trapezoidal state.
#[derive(Clone, Debug, Default)]
struct DamperLane {
    /// 1/κ = Σ 1/z over the branches (`Branch::step_stiffness`).
    kappa: f64,
    /// Upper and lower branches, their trapezoidal states, and this step's offsets x̂
    /// (x₁ = F/z + x̂, so F = κ(d − Σx̂)).
    branches: [Branch; 2],
    states: [BranchState; 2],
    offsets: [f64; 2],
}

/// A lane's own data.
struct Lane<'a> {
    spec: &'a LaneSpec<'a>,
    contact: ContactSolver,
    dampers: Vec<DamperLane>,
    /// (I + diag(κ)·G_dd)⁻¹, row-major.
    s_inv: Vec<f64>,
    error: Option<VtbError>,
    loss_open: Vec<Option<f64>>,
    /// The observers' readouts per step, `[(step·no + j)·READOUTS + k]`, and the rail
    /// observers' residual displacement `[step·n_rail + j]`: the records are made of them once
    /// the run is over (`records`).
    readouts: Vec<f64>,
    residual: Vec<f64>,
}

/// An observation point of one layer.
struct Observer {
    /// ψᵀs and λ²ψᵀs (the kernel's readouts).
    psi: [CVec; 2],
    /// Its shape on the rail (for the residual).
    rail_shape: Option<Shape>,
    /// The force's direct terms per unit force at every rail DOF (the wheels).
    gains: Arc<Gains>,
    /// The same of each damper port: Re Σ ψᵀs·λw·ψ_d and Re Σ ψᵀs·w·ψ_d.
    damper_gains: Vec<[f64; 2]>,
    /// λw·ψᵀs and w·ψᵀs, for the moving forces' modal force (none without).
    mover_gains: Option<[CVec; 2]>,
}

/// Readouts per observer and step: d = Re Σ ψᵀs·Q, e = Re Σ λ²ψᵀs·Q, z = Re Σ ψᵀs·λw·g and
/// y = Re Σ ψᵀs·w·g.
const READOUTS: usize = 4;

/// The rows `[lo, hi)` of rail DOFs within the residual's reach of a shape.
fn reach(red: &Reduction, s: &Shape) -> (usize, usize) {
    let lo = s.start.saturating_sub(red.band);
    let hi = (s.start + s.values.len() + red.band).min(red.rail_dofs);
    (lo.min(hi), hi)
}

/// Whether two rail shapes are within the residual's reach of each other.
fn near(red: &Reduction, a: &Shape, b: &Shape) -> bool {
    let (lo, hi) = reach(red, a);
    b.start < hi && b.start + b.values.len() > lo
}

/// Re Σ x·y over the modes of two shared vectors.
fn dot(x: &CVec, y: &CVec) -> f64 {
    kernels::dot(&x.re, &x.im, &y.re, &y.im)
}

/// Re Σ c·x·y over the modes, c per-mode complex constants.
fn scaled_dot(c: [&[f64]; 2], x: &CVec, y: &CVec) -> f64 {
    let mut t = CVec::zeros(x.re.len());
    t.set_mul(c, x.parts());
    dot(&t, y)
}

/// Σ_k s_k·gain[k − start] over the entries of a rail shape within the gain's range.
fn shape_gain(s: &Shape, start: usize, gain: &[f64]) -> f64 {
    s.values
        .iter()
        .enumerate()
        .filter_map(|(k, a)| {
            let i = (s.start + k).checked_sub(start)?;
            gain.get(i).map(|g| a * g)
        })
        .sum()
}

/// The state of W coupled runs on one reduction.
struct Run<'a, const W: usize> {
    model: &'a Model,
    red: &'a Reduction,
    coef: Coefficients,
    n_steps: usize,
    observers: Vec<Observer>,
    /// The observers' kernel vectors (`Observer::psi`).
    observer_psi: Vec<[CVec; 2]>,
    n_rail: usize,
    lanes: Vec<Lane<'a>>,
    // Vehicles and wheels.
    cars: Vec<CarRun<W>>,
    /// Wheels per car (one vehicle model per run): wheel `w` of car `ci` is `ci·wpc + w`.
    wpc: usize,
    loads: Vec<f64>,
    patch: Vec<f64>,
    wheel_x0: Vec<f64>,
    wheel_shapes: Vec<Shape>,
    /// Ports: the wheels' ψᵀs (refreshed every step), then the dampers' ψᵀ(s_up − s_low).
    ports: Vec<CVec>,
    /// Ports that carry a force: every damper, and the wheels on the structure (a wheel off it
    /// has a zero shape and a zero port, which the passes skip).
    active: Vec<bool>,
    /// Contact forces `[lane·nw + wheel]` (N).
    p: Vec<f64>,
    // Dampers.
    dampers: Vec<DamperPort>,
    // Moving forces: shapes and modal force at t_{n+1} (now) and t_{n+2} (ahead).
    movers: Vec<Mover>,
    shapes_now: Vec<Shape>,
    shapes_ahead: Vec<Shape>,
    gk_now: CVec,
    gk_ahead: CVec,
    mover_psi: CVec,
    /// Each lane's free modal state Q̃ for the coming step.
    q_free: [CVec; W],
    // Per-step values and scratch (allocated once).
    /// Each wheel's step compliance this step (modes and residual); the modes' share from
    /// the rail DOFs' table.
    diag: Vec<f64>,
    rail_step: Arc<RailStepCompliance>,
    rail_acc: Vec<Acc<W>>,
    rail_free: Vec<[f64; W]>,
    element_flex: Vec<f64>,
    /// The wheels' residual filters: each lane's states (g, ġ) `[lane·nw + wheel]` at the
    /// step's start, their values at its end under no new force (`g_free`) and per unit new
    /// force (`g_gain`, shared), and the filtered forces g at its end (`g_now`).
    /// sᵀR₀s of each wheel this step.
    self_res: Vec<f64>,
    g_state: Vec<[f64; 2]>,
    g_free: Vec<[f64; 2]>,
    g_gain: Vec<[f64; 2]>,
    g_now: Vec<f64>,
    /// Near wheel pairs `[wi·nw + vi]`, wi < vi: the modes' step compliance and R₀ between them.
    near_pairs: Vec<f64>,
    near_res: Vec<f64>,
    /// a1·ψ of a wheel (scratch of the near pairs' compliance).
    scaled_port: CVec,
    /// Per observer and wheel this step: the rail gains at the wheel's shape (λw, w).
    wheel_gains: Vec<[f64; 2]>,
    mover_direct: Vec<[f64; 2]>,
    /// Damper e's port and wheel w `[e·nw + w]`: the modes' step compliance and R₀.
    gdw: Vec<f64>,
    gdw_res: Vec<f64>,
    t_mat: Vec<f64>,
    f0: Vec<f64>,
    tmp: Vec<f64>,
    amat: Vec<f64>,
    delta_free: Vec<f64>,
    forces: Vec<[f64; W]>,
    observed: Vec<Acc<W>>,
    /// The kernel's readouts d, e per observer (`[2·o + k]`) of the last step.
    de: Vec<[f64; W]>,
    damper_acc: Vec<Acc<W>>,
    damper_free: Vec<[f64; W]>,
    scratch: Scratch,
    res: Vec<RunResult>,
}

impl<'a, const W: usize> Run<'a, W> {
    fn new(
        model: &'a Model,
        specs: &'a [LaneSpec<'a>],
        red: &'a Reduction,
        record: Record,
    ) -> Result<Self> {
        assert_eq!(specs.len(), W, "one lane spec per lane");
        let cfg = &model.cfg;
        let st = &model.structure;
        let layer_dofs = st.base.as_ref().map_or(st.n_dofs, |b| b[0].n);
        if red.n_dofs != layer_dofs || red.rail_dofs != st.layers[0].n_dofs() {
            return Err(VtbError::config(
                "discretisation.synthesis_cutoff",
                cfg.discretisation.synthesis_cutoff.unwrap_or(0.0),
                format!(
                    "the reduction has {} DOFs ({} on the rail), the structure {} ({}): it \
                     was built for another structure",
                    red.n_dofs,
                    red.rail_dofs,
                    layer_dofs,
                    st.layers[0].n_dofs()
                ),
            ));
        }
        for spec in specs {
            if spec.dampers.len() != st.dampers.len() {
                return Err(VtbError::config(
                    "dampers",
                    spec.dampers.len(),
                    format!(
                        "a lockstep group needs {} dampers in every job",
                        st.dampers.len()
                    ),
                ));
            }
        }
        let n = red.stride;
        let dt = cfg.solver.dt;
        let g = cfg.solver.gravity;
        let coef = Coefficients::new(red, dt);
        let points = match record {
            Record::Full => cfg.observation_points(),
            Record::Metrics => cfg.observation_points()[..1].to_vec(),
        };
        crate::check::budget::check_histories(cfg, record, W)?;
        let project = |s: &Shape| {
            let mut p = CVec::zeros(n);
            kernels::project(red, s, &mut p);
            p
        };
        let lam = [&coef.lam[0][..], &coef.lam[1][..]];
        let zeros = vec![0.0; n];
        let weight = [&coef.w[..], &zeros[..]];

        // Vehicles and wheels.
        let cars = model
            .cars
            .iter()
            .map(|c| CarRun::<W>::new(c, dt, g))
            .collect::<Result<Vec<_>>>()?;
        let wpc = cars.first().map_or(0, |c| c.car.n_wheels());
        let nw = cars.len() * wpc;
        let loads = static_wheel_loads(&cars, g);
        if let Some((i, l)) = loads.iter().enumerate().find(|(_, l)| !(**l > 0.0)) {
            return Err(VtbError::config(
                format!("vehicles[{}]", i / wpc),
                l,
                format!("wheel {} carries no static load", i % wpc + 1),
            ));
        }
        let patch: Vec<f64> = loads
            .iter()
            .enumerate()
            .map(|(wi, &load)| {
                let veh = &cfg.vehicles[wi / wpc];
                if veh.contact_patch {
                    patch_half_length(load, veh.wheel_radius, veh.rail_crown_radius)
                } else {
                    0.0
                }
            })
            .collect();
        let hertz: Vec<f64> = cars.iter().flat_map(|c| vec![c.car.hertz_g; wpc]).collect();
        let wheel_x0: Vec<f64> = cars.iter().flat_map(|c| c.car.wheel_x0.clone()).collect();
        let wheel_shapes: Vec<Shape> = (0..nw)
            .map(|w| Shape {
                start: 0,
                values: Vec::with_capacity(st.wheel_shape_len(patch[w])),
            })
            .collect();
        let span = patch
            .iter()
            .map(|&a| st.wheel_shape_len(a))
            .max()
            .unwrap_or(1);

        // Dampers: ports, step compliance with the rail near them, and G_dd = Re Σ a1·ψ_d·ψ_e
        // + R(upper_d, upper_e), the same in every lane.
        let nd = st.dampers.len();
        let damper_x: Vec<f64> = cfg
            .damper_groups()
            .into_iter()
            .flat_map(|(_, g)| g.locations())
            .collect();
        let a1 = [&coef.a1[0][..], &coef.a1[1][..]];
        let mut ports: Vec<CVec> = (0..nw).map(|_| CVec::zeros(n)).collect();
        let mut dampers = Vec::with_capacity(nd);
        for (att, &x) in st.dampers.iter().zip(&damper_x) {
            let mut psi = project(&att.upper);
            let low = project(&att.lower);
            for j in 0..n {
                psi.re[j] -= low.re[j];
                psi.im[j] -= low.im[j];
            }
            let mut scaled = CVec::zeros(n);
            scaled.set_mul(a1, psi.parts());
            let (lo, hi) = reach(red, &st.shape(0, x));
            let gain = (lo..hi)
                .map(|i| {
                    let (rr, ri) = red.row(i);
                    kernels::dot(&scaled.re, &scaled.im, rr, ri)
                })
                .collect();
            dampers.push(DamperPort {
                upper: att.upper.clone(),
                gain_start: lo,
                gain,
            });
            ports.push(psi);
        }
        let mut g_dd = vec![0.0; nd * nd];
        for e in 0..nd {
            for f in 0..nd {
                g_dd[e * nd + f] = scaled_dot(a1, &ports[nw + e], &ports[nw + f])
                    + red.residual(&dampers[e].upper, &dampers[f].upper);
            }
        }

        // Observers: layer by layer, point by point.
        let movers = Mover::all(cfg);
        let shapes: Vec<(usize, Shape)> = record
            .layers(cfg)
            .into_iter()
            .flat_map(|li| points.iter().map(move |&x| (li, x)))
            .map(|(li, x)| (li, st.shape(li, x)))
            .collect();
        let psis: Vec<CVec> = shapes.iter().map(|(_, s)| project(s)).collect();
        let pairs: Vec<(&Shape, &CVec)> = shapes.iter().map(|(_, s)| s).zip(&psis).collect();
        let gains = red.gains(&pairs);
        let mut observers = Vec::with_capacity(shapes.len());
        for (((li, s), psi), gains) in shapes.into_iter().zip(psis).zip(gains) {
            let mut pw = CVec::zeros(n);
            pw.set_mul(weight, psi.parts());
            let mut plw = CVec::zeros(n);
            plw.set_mul(lam, pw.parts());
            let mut l2 = CVec::zeros(n);
            l2.set_mul(lam, psi.parts());
            let l2_copy = l2.clone();
            l2.set_mul(lam, l2_copy.parts());
            observers.push(Observer {
                damper_gains: ports[nw..]
                    .iter()
                    .map(|d| [dot(&plw, d), dot(&pw, d)])
                    .collect(),
                mover_gains: (!movers.is_empty()).then_some([plw, pw]),
                psi: [psi, l2],
                rail_shape: (li == 0).then_some(s),
                gains,
            });
        }
        let no = observers.len();
        let n_rail = observers.iter().filter(|o| o.rail_shape.is_some()).count();
        let observer_psi = observers.iter().map(|o| o.psi.clone()).collect();

        // Lanes.
        let n_steps = cfg.n_steps();
        let lanes = specs
            .iter()
            .map(|spec| {
                let dampers: Vec<DamperLane> = spec
                    .dampers
                    .iter()
                    .map(|p| {
                        let branches = p.branches();
                        DamperLane {
                            kappa: 1.0
                                / branches
                                    .iter()
                                    .map(|b| 1.0 / b.step_stiffness(dt))
                                    .sum::<f64>(),
                            branches,
                            ..Default::default()
                        }
                    })
                    .collect();
                let (s_inv, error) = damper_inverse(&dampers, &g_dd);
                Lane {
                    spec,
                    contact: ContactSolver::new(
                        hertz.clone(),
                        loads.clone(),
                        cfg.solver.contact_tol,
                        cfg.solver.contact_max_iter,
                    )
                    .with_block(wpc),
                    dampers,
                    s_inv,
                    error,
                    loss_open: vec![None; nw],
                    readouts: vec![0.0; (n_steps + 1) * no * READOUTS],
                    residual: vec![0.0; (n_steps + 1) * n_rail],
                }
            })
            .collect();
        let mover_shapes = || -> Vec<Shape> {
            movers
                .iter()
                .map(|mv| Shape {
                    start: 0,
                    values: vec![0.0; st.layers[mv.layer].basis.shape_len()],
                })
                .collect()
        };
        let res = (0..W)
            .map(|_| RunResult::new(cfg, st, n_steps, &points, cars.len(), nw, record))
            .collect();
        let mut p = vec![0.0; nw * W];
        for c in 0..W {
            p[c * nw..(c + 1) * nw].copy_from_slice(&loads);
        }
        Ok(Self {
            model,
            red,
            n_steps,
            observer_psi,
            n_rail,
            lanes,
            wpc,
            loads,
            patch,
            wheel_x0,
            wheel_shapes,
            active: vec![true; ports.len()],
            ports,
            p,
            shapes_now: mover_shapes(),
            shapes_ahead: mover_shapes(),
            movers,
            gk_now: CVec::zeros(n),
            gk_ahead: CVec::zeros(n),
            mover_psi: CVec::zeros(n),
            q_free: std::array::from_fn(|_| CVec::zeros(n)),
            diag: vec![0.0; nw],
            rail_step: red.rail_step_compliance(&coef, dt, span),
            rail_acc: vec![Acc::ZERO; nw],
            rail_free: vec![[0.0; W]; nw],
            element_flex: vec![0.0; nw],
            self_res: vec![0.0; nw],
            g_state: vec![[0.0; 2]; W * nw],
            g_free: vec![[0.0; 2]; W * nw],
            g_gain: vec![[0.0; 2]; nw],
            g_now: vec![0.0; W * nw],
            near_pairs: vec![0.0; nw * nw],
            near_res: vec![0.0; nw * nw],
            scaled_port: CVec::zeros(n),
            wheel_gains: vec![[0.0; 2]; no * nw],
            mover_direct: vec![[0.0; 2]; no],
            gdw: vec![0.0; nd * nw],
            gdw_res: vec![0.0; nd * nw],
            t_mat: vec![0.0; W * nd * nw],
            f0: vec![0.0; W * nd],
            tmp: vec![0.0; nd],
            amat: vec![0.0; W * nw * nw],
            delta_free: vec![0.0; W * nw],
            forces: vec![[0.0; W]; nw + nd],
            observed: vec![Acc::ZERO; 2 * no],
            de: vec![[0.0; W]; 2 * no],
            damper_acc: vec![Acc::ZERO; nd],
            damper_free: vec![[0.0; W]; nd],
            scratch: Scratch::new(),
            res,
            observers,
            dampers,
            cars,
            coef,
        })
    }

    fn dt(&self) -> f64 {
        self.model.cfg.solver.dt
    }

    fn nw(&self) -> usize {
        self.wheel_shapes.len()
    }

    /// The moving forces' shapes at t into `shapes` and their modal force Σ P·ψᵀs into `gk`.
    fn movers_at(&mut self, t: f64, ahead: bool) {
        let (st, red, v) = (&self.model.structure, self.red, self.model.cfg.speed);
        let (gk, shapes) = if ahead {
            (&mut self.gk_ahead, &mut self.shapes_ahead)
        } else {
            (&mut self.gk_now, &mut self.shapes_now)
        };
        gk.clear();
        for (mv, sh) in self.movers.iter().zip(shapes.iter_mut()) {
            st.shape_into(mv.layer, mv.x0 + v * t, sh);
            kernels::project(red, sh, &mut self.mover_psi);
            for j in 0..gk.re.len() {
                gk.re[j] = mv.magnitude.mul_add(self.mover_psi.re[j], gk.re[j]);
                gk.im[j] = mv.magnitude.mul_add(self.mover_psi.im[j], gk.im[j]);
            }
        }
    }

    /// The rail's residual displacement at s under the rail's moving forces (now).
    fn mover_residual(&self, s: &Shape) -> f64 {
        self.movers
            .iter()
            .zip(&self.shapes_now)
            .filter(|(mv, _)| mv.layer == 0)
            .map(|(mv, sm)| mv.magnitude * self.red.residual(s, sm))
            .sum()
    }

    /// The rail's residual displacement at s under the wheels' filtered forces g.
    fn wheel_residual(&self, s: &Shape, p: &[f64]) -> f64 {
        self.wheel_shapes
            .iter()
            .zip(p)
            .map(|(sw, pw)| pw * self.red.residual(s, sw))
            .sum()
    }

    /// The wheels' shapes at t, and the observers' rail gains at them; the moving forces'
    /// direct terms at the observers.
    fn place_loads(&mut self, t: f64) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        for (w, s) in self.wheel_shapes.iter_mut().enumerate() {
            st.wheel_shape_into(self.wheel_x0[w] + v * t, self.patch[w], s);
            let on = s.values.iter().any(|&x| x != 0.0);
            if self.active[w] && !on {
                self.ports[w].clear();
            }
            self.active[w] = on;
        }
        let nw = self.nw();
        for (o, obs) in self.observers.iter().enumerate() {
            for (w, s) in self.wheel_shapes.iter().enumerate() {
                self.wheel_gains[o * nw + w] = [
                    shape_gain(s, 0, &obs.gains.lw),
                    shape_gain(s, 0, &obs.gains.w),
                ];
            }
            if let Some([plw, pw]) = &obs.mover_gains {
                self.mover_direct[o] = [dot(plw, &self.gk_now), dot(pw, &self.gk_now)];
            }
        }
    }

    /// Static (or rest) initial state at t = 0: the modes, the dampers, the cars, the first
    /// free state and the first record.
    fn initial_state(&mut self) -> Result<()> {
        let cfg = &self.model.cfg;
        let (red, dt, g) = (self.red, cfg.solver.dt, cfg.solver.gravity);
        let n = red.stride;
        let nw = self.nw();
        let rest = cfg.solver.initial_state == InitialState::Rest;
        self.movers_at(0.0, false);
        self.place_loads(0.0);
        let mut g0 = self.gk_now.clone();
        for w in 0..nw {
            kernels::project(red, &self.wheel_shapes[w], &mut self.ports[w]);
            for j in 0..n {
                g0.re[j] = self.loads[w].mul_add(self.ports[w].re[j], g0.re[j]);
                g0.im[j] = self.loads[w].mul_add(self.ports[w].im[j], g0.im[j]);
            }
        }
        // Q₀: static (λQ + w·g = 0) or at rest; the same in every lane.
        let mut q0 = CVec::zeros(n);
        if !rest {
            for j in 0..red.m {
                let qj = C(g0.re[j], g0.im[j])
                    .scale(-red.weight[j])
                    .div(C(red.lam_re[j], red.lam_im[j]));
                (q0.re[j], q0.im[j]) = (qj.0, qj.1);
            }
        }
        let share = if rest { 0.0 } else { 1.0 };
        // The residual filters at rest under the loads (g = F) or, at rest, empty.
        for c in 0..W {
            for w in 0..nw {
                self.g_state[c * nw + w] = [share * self.loads[w], 0.0];
                self.g_now[c * nw + w] = share * self.loads[w];
            }
        }
        let static_residual =
            |s: &Shape| share * (self.wheel_residual(s, &self.loads) + self.mover_residual(s));
        let d0: Vec<f64> = (0..self.dampers.len())
            .map(|d| dot(&self.ports[nw + d], &q0) + static_residual(&self.dampers[d].upper))
            .collect();
        let rail0: Vec<f64> = (0..nw)
            .map(|w| dot(&self.ports[w], &q0) + static_residual(&self.wheel_shapes[w]))
            .collect();
        for lane in self.lanes.iter_mut() {
            // No static force passes a spring in series with an inerter: the lower branch
            // (which has no spring) takes the whole static extension.
            for (d, s) in lane.dampers.iter_mut().zip(&d0) {
                d.states[1].x = *s;
            }
        }
        let wpc = self.wpc;
        for (ci, c) in self.cars.iter_mut().enumerate() {
            let wheels = ci * wpc..(ci + 1) * wpc;
            for (lane, l) in self.lanes.iter().enumerate() {
                let rail: Vec<f64> = wheels
                    .clone()
                    .map(|wi| {
                        rail0[wi]
                            + cfg.irregularity_share(0.0)
                                * l.spec.profile.under(wi, self.wheel_x0[wi])
                    })
                    .collect();
                c.set_static(lane, &rail, &self.loads[wheels.clone()], g)?;
            }
            let pc: [f64; GW] = std::array::from_fn(|w| {
                if w < wpc {
                    self.loads[ci * wpc + w]
                } else {
                    0.0
                }
            });
            c.set_force(&[pc; W]);
        }
        // Q̃₁ = e·Q₀ + a0·g₀ + a1·g_known(t₁), the dampers' free displacement under it.
        self.movers_at(dt, true);
        let coef = &self.coef;
        for j in 0..n {
            let (q, gj, k1) = (
                C(q0.re[j], q0.im[j]),
                C(g0.re[j], g0.im[j]),
                C(self.gk_ahead.re[j], self.gk_ahead.im[j]),
            );
            let qf = C(coef.e[0][j], coef.e[1][j])
                .mul(q)
                .add(C(coef.a0[0][j], coef.a0[1][j]).mul(gj))
                .add(coef.a1_at(j).mul(k1));
            for c in 0..W {
                (self.q_free[c].re[j], self.q_free[c].im[j]) = (qf.0, qf.1);
            }
        }
        for d in 0..self.dampers.len() {
            self.damper_free[d] = [dot(&self.ports[nw + d], &self.q_free[0]); W];
        }
        // The first readouts: d, e of Q₀, the loads' direct terms.
        for (o, obs) in self.observers.iter().enumerate() {
            for k in 0..2 {
                self.de[2 * o + k] = [dot(&obs.psi[k], &q0); W];
            }
        }
        self.record(0);
        Ok(())
    }

    /// One step, t_n → t_{n+1}.
    fn step(&mut self, step: usize) {
        let dt = self.dt();
        let t1 = (step + 1) as f64 * dt;
        if !self.movers.is_empty() {
            std::mem::swap(&mut self.shapes_now, &mut self.shapes_ahead);
            std::mem::swap(&mut self.gk_now, &mut self.gk_ahead);
            self.movers_at(t1 + dt, true);
        }
        self.place_loads(t1);
        self.wheel_pass(t1);
        self.damper_terms();
        self.contact(step, t1);
        self.forces();
        self.update();
        self.end_cars(t1);
        self.record(step + 1);
    }

    /// The wheel pass (shared): ψᵀs, step compliances, free rail displacements, the wheels'
    /// element flexibility, and their step compliance with the dampers.
    fn wheel_pass(&mut self, t1: f64) {
        let (red, st, cfg) = (self.red, &self.model.structure, &self.model.cfg);
        let nw = self.nw();
        kernels::wheel_pass::<W>(
            red,
            &self.q_free,
            WheelPass {
                shapes: &self.wheel_shapes,
                active: &self.active,
                outs: &mut self.ports[..nw],
                rail: &mut self.rail_acc,
            },
        );
        let (dt, wpc) = (cfg.solver.dt, self.wpc);
        let mut failed = None;
        for w in 0..nw {
            let s = &self.wheel_shapes[w];
            let x = self.wheel_x0[w] + cfg.speed * t1;
            let (modal, moments) = if self.active[w] {
                (self.rail_step.quadratic(s), red.residual_moments(s))
            } else {
                (0.0, [0.0; 3])
            };
            self.self_res[w] = moments[0];
            let filter = Filter::from_moments(moments, || {
                format!(
                    "vehicles[{}] wheel {} at x = {x:.4} m",
                    w / wpc,
                    w % wpc + 1
                )
            });
            let step = match filter {
                Ok(Some(f)) => f.step(dt),
                Ok(None) => FilterStep::pass(dt),
                Err(e) => {
                    failed = Some(e);
                    FilterStep::pass(dt)
                }
            };
            self.g_gain[w] = step.advance([0.0; 2], 0.0, 1.0);
            for c in 0..W {
                let i = c * nw + w;
                self.g_free[i] = step.advance(self.g_state[i], self.p[i], 0.0);
            }
            self.diag[w] = modal + moments[0] * self.g_gain[w][0];
            self.rail_free[w] = self.rail_acc[w].sum();
            self.element_flex[w] = if cfg.discretisation.element_flexibility {
                st.wheel_flexibility(x, self.patch[w])
            } else {
                0.0
            };
        }
        // Wheels off the rail (inactive) have no compliance with any other.
        let a1 = [&self.coef.a1[0][..], &self.coef.a1[1][..]];
        for wi in 0..nw {
            let mut scaled = false;
            for vi in wi + 1..nw {
                let (a, b) = (&self.wheel_shapes[wi], &self.wheel_shapes[vi]);
                (self.near_pairs[wi * nw + vi], self.near_res[wi * nw + vi]) =
                    if self.active[wi] && self.active[vi] && near(red, a, b) {
                        if !scaled {
                            self.scaled_port.set_mul(a1, self.ports[wi].parts());
                            scaled = true;
                        }
                        (dot(&self.scaled_port, &self.ports[vi]), red.residual(a, b))
                    } else {
                        (0.0, 0.0)
                    };
            }
        }
        for (e, dp) in self.dampers.iter().enumerate() {
            for (w, sw) in self.wheel_shapes.iter().enumerate() {
                self.gdw[e * nw + w] = shape_gain(sw, dp.gain_start, &dp.gain);
                self.gdw_res[e * nw + w] = red.residual(&dp.upper, sw);
            }
        }
        if let Some(e) = failed {
            for c in 0..W {
                if self.lanes[c].error.is_none() {
                    self.fail(c, e.clone());
                }
            }
        }
    }

    /// R₀ between near wheels w ≠ v (zero when not near).
    fn near_residual(&self, w: usize, v: usize) -> f64 {
        let nw = self.nw();
        self.near_res[w.min(v) * nw + w.max(v)]
    }

    /// The rail's residual displacement at wheel w of lane c under the wheels' filtered forces
    /// at the step's end with no new force.
    fn wheel_residual_free(&self, w: usize, c: usize) -> f64 {
        let nw = self.nw();
        (0..nw)
            .map(|v| {
                let r = if v == w {
                    self.self_res[w]
                } else {
                    self.near_residual(w, v)
                };
                r * self.g_free[c * nw + v][0]
            })
            .sum()
    }

    /// Each lane's dampers this step: their force F = F0 + T·P in the wheel forces P.
    fn damper_terms(&mut self) {
        let dt = self.dt();
        let (nw, nd) = (self.nw(), self.dampers.len());
        if nd == 0 {
            return;
        }
        for c in 0..W {
            if self.lanes[c].error.is_some() {
                continue;
            }
            for e in 0..nd {
                let wheels: f64 = (0..nw)
                    .map(|w| self.gdw_res[e * nw + w] * self.g_free[c * nw + w][0])
                    .sum();
                let free =
                    self.damper_free[e][c] + self.mover_residual(&self.dampers[e].upper) + wheels;
                let d = &mut self.lanes[c].dampers[e];
                for i in 0..2 {
                    d.offsets[i] = d.states[i].offset(&d.branches[i], dt);
                }
                self.f0[c * nd + e] = d.kappa * (free - d.offsets[0] - d.offsets[1]);
                for w in 0..nw {
                    let g = self.gdw[e * nw + w] + self.gdw_res[e * nw + w] * self.g_gain[w][0];
                    self.t_mat[(c * nd + e) * nw + w] = d.kappa * g;
                }
            }
            // F0 ← S⁻¹·F0, T ← S⁻¹·T.
            let s_inv = &self.lanes[c].s_inv;
            let f0 = &mut self.f0[c * nd..(c + 1) * nd];
            self.tmp.copy_from_slice(f0);
            for e in 0..nd {
                f0[e] = (0..nd).map(|f| s_inv[e * nd + f] * self.tmp[f]).sum();
            }
            let t_mat = &mut self.t_mat[c * nd * nw..(c + 1) * nd * nw];
            for w in 0..nw {
                for e in 0..nd {
                    self.tmp[e] = t_mat[e * nw + w];
                }
                for e in 0..nd {
                    t_mat[e * nw + w] = (0..nd).map(|f| s_inv[e * nd + f] * self.tmp[f]).sum();
                }
            }
        }
    }

    /// The contact: δ = δ_free − A·P per lane, solved by each lane's Newton.
    fn contact(&mut self, step: usize, t1: f64) {
        let cfg = &self.model.cfg;
        let (v, share) = (cfg.speed, cfg.irregularity_share(t1));
        let (nw, nd) = (self.nw(), self.dampers.len());
        for ci in 0..self.cars.len() {
            let car = &mut self.cars[ci];
            car.nm.begin_step(&car.f_prev, &car.gravity);
            let wheel = car.nm.free_port_disp(&car.ports);
            for c in 0..W {
                for w in 0..self.wpc {
                    let wi = ci * self.wpc + w;
                    let mut rail = self.rail_free[wi][c]
                        + self.mover_residual(&self.wheel_shapes[wi])
                        + self.wheel_residual_free(wi, c);
                    // The dampers' forces reach the wheel through the static residual (they
                    // have no filter).
                    for e in 0..nd {
                        rail -= (self.gdw[e * nw + wi] + self.gdw_res[e * nw + wi])
                            * self.f0[c * nd + e];
                    }
                    let x = self.wheel_x0[wi] + v * t1;
                    self.delta_free[c * nw + wi] =
                        wheel[c][w] - rail - share * self.lanes[c].spec.profile.under(wi, x);
                }
            }
        }
        for c in 0..W {
            let a = &mut self.amat[c * nw * nw..(c + 1) * nw * nw];
            let t_mat = &self.t_mat[c * nd * nw..(c + 1) * nd * nw];
            // Row wi: the displacement at wheel wi per unit force of wheel vi, whose residual
            // share passes vi's filter (so A is not symmetric).
            for wi in 0..nw {
                for vi in 0..nw {
                    let mut x = if wi == vi {
                        self.diag[wi] + self.element_flex[wi]
                    } else {
                        let (lo, hi) = (wi.min(vi), wi.max(vi));
                        self.near_pairs[lo * nw + hi]
                            + self.near_res[lo * nw + hi] * self.g_gain[vi][0]
                    };
                    for e in 0..nd {
                        x -= (self.gdw[e * nw + wi] + self.gdw_res[e * nw + wi])
                            * t_mat[e * nw + vi];
                    }
                    let (ci, cj) = (wi / self.wpc, vi / self.wpc);
                    if ci == cj {
                        let car = &self.cars[ci];
                        x += car.car.rails * car.compliance[wi % self.wpc][vi % self.wpc];
                    }
                    a[wi * nw + vi] = x;
                }
            }
        }
        if nw == 0 {
            return;
        }
        for c in 0..W {
            if self.lanes[c].error.is_some() {
                continue;
            }
            let solved = self.lanes[c].contact.solve(
                &mut self.p[c * nw..(c + 1) * nw],
                &self.delta_free[c * nw..(c + 1) * nw],
                &self.amat[c * nw * nw..(c + 1) * nw * nw],
                t1,
                step + 1,
            );
            if let Err(e) = solved {
                self.fail(c, e);
            }
        }
    }

    /// The ports' forces of every lane once the wheels' are known, and the dampers' states.
    fn forces(&mut self) {
        let dt = self.dt();
        let (nw, nd) = (self.nw(), self.dampers.len());
        for c in 0..W {
            for w in 0..nw {
                let i = c * nw + w;
                self.forces[w][c] = self.p[i];
                let (free, gain) = (self.g_free[i], self.g_gain[w]);
                self.g_state[i] = [
                    gain[0].mul_add(self.p[i], free[0]),
                    gain[1].mul_add(self.p[i], free[1]),
                ];
                self.g_now[i] = self.g_state[i][0];
            }
            if self.lanes[c].error.is_some() {
                for e in 0..nd {
                    self.forces[nw + e][c] = 0.0;
                }
                continue;
            }
            for e in 0..nd {
                let f: f64 = self.f0[c * nd + e]
                    + (0..nw)
                        .map(|w| self.t_mat[(c * nd + e) * nw + w] * self.p[c * nw + w])
                        .sum::<f64>();
                self.forces[nw + e][c] = -f;
                let d = &mut self.lanes[c].dampers[e];
                for i in 0..2 {
                    d.states[i].advance(&d.branches[i], dt, f, d.offsets[i]);
                }
            }
        }
    }

    /// The update pass: the modes stepped, the observers and damper ports read.
    fn update(&mut self) {
        let nw = self.nw();
        kernels::update::<W>(
            Update {
                coef: &self.coef,
                ports: &self.ports,
                forces: &self.forces,
                active: &self.active,
                movers: (!self.movers.is_empty()).then_some((&self.gk_now, &self.gk_ahead)),
                observers: &self.observer_psi,
                observed: &mut self.observed,
                dampers_from: nw,
                damper_free: &mut self.damper_acc,
            },
            &mut self.q_free,
            &mut self.scratch,
        );
        for (d, acc) in self.damper_free.iter_mut().zip(&self.damper_acc) {
            *d = acc.sum();
        }
        for (x, acc) in self.de.iter_mut().zip(&self.observed) {
            *x = acc.sum();
        }
    }

    /// The cars take the wheel forces; contact-loss periods are noted.
    fn end_cars(&mut self, t1: f64) {
        let nw = self.nw();
        for (ci, car) in self.cars.iter_mut().enumerate() {
            let pc: [[f64; GW]; W] = std::array::from_fn(|c| {
                std::array::from_fn(|w| {
                    if w < self.wpc {
                        self.p[c * nw + ci * self.wpc + w]
                    } else {
                        0.0
                    }
                })
            });
            let wheel: [[f64; GW]; W] = pc.map(|pl| pl.map(|pw| -car.car.rails * pw));
            car.nm.add_port_forces(&car.ports, &wheel);
            car.nm.end_step();
            car.set_force(&pc);
        }
        for (c, lane) in self.lanes.iter_mut().enumerate() {
            if lane.error.is_none() {
                note_contact(
                    &mut lane.loss_open,
                    &self.p[c * nw..(c + 1) * nw],
                    t1,
                    &mut self.res[c].contact_loss,
                );
            }
        }
    }

    /// The readouts of every live lane at `step` (the force's direct terms from the ports'
    /// forces this step), the rail residual, the vehicles and the contact forces.
    fn record(&mut self, step: usize) {
        let (nw, no, n_rail) = (self.nw(), self.observers.len(), self.n_rail);
        for c in 0..W {
            if self.lanes[c].error.is_some() {
                continue;
            }
            let pl = &self.p[c * nw..(c + 1) * nw];
            let gl = &self.g_now[c * nw..(c + 1) * nw];
            for (o, obs) in self.observers.iter().enumerate() {
                // z = Re Σ ψᵀs·λw·g and y = Re Σ ψᵀs·w·g, g = Σ ports' forces·ψᵀ(port).
                let mut zy = self.mover_direct[o];
                for (w, pw) in pl.iter().enumerate() {
                    let gw = self.wheel_gains[o * nw + w];
                    zy = [pw.mul_add(gw[0], zy[0]), pw.mul_add(gw[1], zy[1])];
                }
                for (e, gd) in obs.damper_gains.iter().enumerate() {
                    let f = self.forces[nw + e][c];
                    zy = [f.mul_add(gd[0], zy[0]), f.mul_add(gd[1], zy[1])];
                }
                let at = (step * no + o) * READOUTS;
                self.lanes[c].readouts[at..at + READOUTS].copy_from_slice(&[
                    self.de[2 * o][c],
                    self.de[2 * o + 1][c],
                    zy[0],
                    zy[1],
                ]);
                if let Some(s) = &obs.rail_shape {
                    self.lanes[c].residual[step * n_rail + o] =
                        self.wheel_residual(s, gl) + self.mover_residual(s);
                }
            }
            let r = &mut self.res[c];
            let (ncars, ndof) = (r.n_cars, r.vehicle_dofs);
            for (ci, car) in self.cars.iter().take(ncars).enumerate() {
                for i in 0..ndof {
                    let (z, _, a) = car.nm.observed(i, c);
                    r.vehicle_disp[(step * ncars + ci) * ndof + i] = z - car.z0[i * W + c];
                    r.vehicle_acc[(step * ncars + ci) * ndof + i] = a;
                }
            }
            r.contact_force[step * nw..(step + 1) * nw].copy_from_slice(pl);
        }
    }

    /// A non-finite state (overflow from extreme parameters) fails its lane.
    fn check_finite(&mut self, step: usize) {
        for c in 0..W {
            if self.lanes[c].error.is_none() && !self.q_free[c].is_finite() {
                self.fail(
                    c,
                    VtbError::Solver(format!(
                        "the modal coordinates became non-finite by step {step}: an overflow, \
                         most likely from parameters of extreme magnitude"
                    )),
                );
            }
        }
    }

    /// Lane c failed: keep the error and zero its state so that it idles finite.
    fn fail(&mut self, c: usize, e: VtbError) {
        let nw = self.nw();
        self.lanes[c].error = Some(e);
        self.q_free[c].clear();
        self.p[c * nw..(c + 1) * nw].fill(0.0);
        self.g_state[c * nw..(c + 1) * nw].fill([0.0; 2]);
        self.g_now[c * nw..(c + 1) * nw].fill(0.0);
        for car in &mut self.cars {
            car.nm.clear_lane(c);
        }
    }

    /// Each lane's result: its records made of its readouts, or its error.
    fn finish(self) -> Vec<Result<RunResult>> {
        let (no, n_rail, dt) = (self.observers.len(), self.n_rail, self.dt());
        self.lanes
            .into_iter()
            .zip(self.res)
            .map(|(lane, mut r)| match lane.error {
                Some(e) => Err(e),
                None => {
                    records(&mut r, &lane.readouts, &lane.residual, no, n_rail, dt);
                    finish(&lane.loss_open, r)
                }
            })
            .collect()
    }
}

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
/// residual r (`[step·no + j]` in `r.disp`, `r.acc`):
///
///   u = E(d) + r,   ü = E(e + D₂r) + z + D₁y.
///
/// The modes' response to the piecewise-linear force through the force samples is the true
/// response low-passed by sinc²(ωh/2) at every sample, and so is the second difference D₂ of
/// the residual's samples: the zero-phase FIR E = (−1, 14, −1)/12, whose gain
/// 1 + (1 − cos ωh)/6 is 1/sinc²(ωh/2) to O((ωh)⁴) (0.2 % at 2 kHz, h = 5e-5 s), equalises
/// them. The force samples themselves are exact (z), and the force-rate term w·ġ is the
/// fourth-order central difference D₁ of y.
fn records(
    r: &mut RunResult,
    readouts: &[f64],
    residual: &[f64],
    no: usize,
    n_rail: usize,
    dt: f64,
) {
    let n = readouts.len() / (no * READOUTS).max(1);
    let e = |x: &[f64], s: usize| (14.0 * x[s + 2] - x[s + 1] - x[s + 3]) / 12.0;
    for j in 0..no {
        let rd = |k: usize, s: usize| readouts[(s * no + j) * READOUTS + k];
        let rr = padded(n, |s| {
            if j < n_rail {
                residual[s * n_rail + j]
            } else {
                0.0
            }
        });
        let (d, y) = (padded(n, |s| rd(0, s)), padded(n, |s| rd(3, s)));
        let inner = padded(n, |s| {
            rd(1, s) + (rr[s + 3] - 2.0 * rr[s + 2] + rr[s + 1]) / (dt * dt)
        });
        for s in 0..n {
            r.disp[s * no + j] = e(&d, s) + rr[s + 2];
            let d1 = (y[s] - 8.0 * y[s + 1] + 8.0 * y[s + 3] - y[s + 4]) / (12.0 * dt);
            r.acc[s * no + j] = e(&inner, s) + rd(2, s) + d1;
        }
    }
}

/// (I + diag(κ)·G_dd)⁻¹ of one lane's dampers (constant over the run: fixed ports), and the
/// lane's error when it is singular or not finite.
fn damper_inverse(dampers: &[DamperLane], g_dd: &[f64]) -> (Vec<f64>, Option<VtbError>) {
    let nd = dampers.len();
    if nd == 0 {
        return (Vec::new(), None);
    }
    let s = faer::Mat::<f64>::from_fn(nd, nd, |e, f| {
        f64::from(u8::from(e == f)) + dampers[e].kappa * g_dd[e * nd + f]
    });
    let inv = faer::linalg::solvers::DenseSolveCore::inverse(&s.partial_piv_lu());
    let out: Vec<f64> = (0..nd * nd).map(|i| inv[(i / nd, i % nd)]).collect();
    let error = (!out.iter().all(|x| x.is_finite())).then(|| {
        VtbError::Solver(
            "the dampers' port equations are singular or overflow: parameters of extreme \
             magnitude"
                .into(),
        )
    });
    (out, error)
}
