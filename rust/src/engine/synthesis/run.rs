//! The synthesis engine's side of the coupled loop (`crate::engine::coupled`): W jobs of one
//! model on a reduction, in lockstep (W = 1: a single run).
//!
//! The jobs of a group share the structure, the speed and the vehicles, so the wheels'
//! positions, their modal shapes ψᵀs and step compliances are computed once per step for all
//! of them (`kernels::wheel_pass`); each job has its own modal state, irregularity, contact
//! forces and dampers' parameters (`kernels::update`). A step is a few named phases
//! (`passes`): loads, wheel pass, dampers, then the shared contact, then forces, update,
//! record.
//!
//! Within a step the displacements at the wheels and at the dampers' ports are affine in the
//! unknown forces through the step compliance Re Σ ψ_a·a1·ψ_b + R_ab·γ_b (γ_b the step gain of
//! load b's residual filter, `residual`; 1 for a damper's force), so the contact Newton
//! iterates on the wheel forces alone, as in the finite-element engine. The modes' share of
//! the step compliance reaches the step's reach (`Reduction::step_band` rail DOFs): within
//! one step (50 µs) no wave carries a load farther (the rail's shear wave needs 0.3 ms per
//! metre), so the full model's value is nil there and the modes' sum is noise. The
//! residual's share, quasi-static, reaches as far as the stored residual. Tuned inerter dampers are physical elements on fixed ports: the trapezoidal rule on
//! their internal node gives F = κ(d − d̃) in the relative port displacement d, which is
//! eliminated exactly.
//!
//! Accelerations are analytic, Q̈ = λ²Q + λw·g + w·ġ per mode: the kernel reads Re Σ λ²ψᵀs·Q;
//! the force's direct terms Re Σ ψᵀs·λw·g and Re Σ ψᵀs·w·g are sums over the ports of the
//! force times a gain (`Gains` over the rail's DOFs for the wheels, constants for the
//! dampers); `records` assembles them with the rail residual's acceleration.

use super::kernels::{self, Acc, CVec, RailStepCompliance, Scratch};
use super::step::Coefficients;
use super::{Gains, Reduction};
use crate::config::DamperParams;
use crate::engine::coupled::{self, Mover, Vehicles};
use crate::engine::{Control, LaneSpec};
use crate::error::{Result, VtbError};
use crate::model::Model;
use crate::model::basis::Shape;
use crate::model::dampers::{Branch, BranchState};
use crate::outputs::catalog::{Pad, pads_of};
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
    assert_eq!(specs.len(), W, "one lane spec per lane");
    let cfg = &model.cfg;
    let points = record.points(cfg);
    fits(model, specs, red)?;
    crate::check::budget::check_histories(cfg, record, W)?;
    let v = Vehicles::<W>::new(model, cfg.solver.dt)?;
    let side = SynthesisSide::<W>::new(model, specs, red, record, &points, &v);
    let profiles = std::array::from_fn(|j| specs[j].profile);
    coupled::run(model, side, v, profiles, (record, &points), cancel)
}

/// The reduction was built for the model's structure, and every lane has its dampers.
fn fits(model: &Model, specs: &[LaneSpec], red: &Reduction) -> Result<()> {
    let st = &model.structure;
    let layer_dofs = st.base.as_ref().map_or(st.n_dofs, |b| b[0].n);
    if red.n_dofs != layer_dofs || red.rail_dofs != st.layers[0].n_dofs() {
        return Err(VtbError::config(
            "discretisation.synthesis_cutoff",
            model.cfg.discretisation.synthesis_cutoff.unwrap_or(0.0),
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
    Ok(())
}

/// A damper's shared data: its ports and its step compliance with rail DOFs near it.
pub(super) struct DamperPort {
    pub(super) upper: Shape,
    /// Re Σ_j a1_j·ψᵀ(s_up − s_low)_j·ψ_j at rail DOFs `gain_start..` (the residual's reach
    /// around the damper).
    pub(super) gain_start: usize,
    pub(super) gain: Vec<f64>,
}

/// A damper of one lane: its parameters and trapezoidal state.
#[derive(Clone, Debug, Default)]
pub(super) struct DamperLane {
    /// 1/κ = Σ 1/z over the branches (`Branch::step_stiffness`).
    pub(super) kappa: f64,
    /// Upper and lower branches, their trapezoidal states, and this step's offsets x̂
    /// (x₁ = F/z + x̂, so F = κ(d − Σx̂)).
    pub(super) branches: [Branch; 2],
    pub(super) states: [BranchState; 2],
    pub(super) offsets: [f64; 2],
}

impl DamperLane {
    fn new(p: &DamperParams, dt: f64) -> Self {
        let branches = p.branches();
        Self {
            kappa: 1.0
                / branches
                    .iter()
                    .map(|b| 1.0 / b.step_stiffness(dt))
                    .sum::<f64>(),
            branches,
            ..Default::default()
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

/// A lane's own data on the structure side.
pub(super) struct Lane {
    pub(super) dampers: Vec<DamperLane>,
    /// (I + diag(κ)·G_dd)⁻¹, row-major.
    pub(super) s_inv: Vec<f64>,
    /// The error of a lane whose dampers' port equations are singular.
    pub(super) setup: Option<VtbError>,
    /// The observers' readouts per step, `[(step·no + j)·READOUTS + k]`, and the rail
    /// observers' residual displacement `[step·no + j]` (0 off the rail): the records are made
    /// of them once the run is over (`records`).
    pub(super) readouts: Vec<f64>,
    pub(super) residual: Vec<f64>,
}

/// An observation point of one layer.
pub(super) struct Observer {
    /// ψᵀs and λ²ψᵀs (the kernel's readouts).
    pub(super) psi: [CVec; 2],
    /// Its shape on the rail (for the residual).
    pub(super) rail_shape: Option<Shape>,
    /// The force's direct terms per unit force at every rail DOF (the wheels).
    pub(super) gains: Arc<Gains>,
    /// The same of each damper port: Re Σ ψᵀs·λw·ψ_d and Re Σ ψᵀs·w·ψ_d.
    pub(super) damper_gains: Vec<[f64; 2]>,
    /// λw·ψᵀs and w·ψᵀs, for the moving forces' modal force (none without).
    pub(super) mover_gains: Option<[CVec; 2]>,
}

/// Readouts per observer and step: d = Re Σ ψᵀs·Q, e = Re Σ λ²ψᵀs·Q, z = Re Σ ψᵀs·λw·g and
/// y = Re Σ ψᵀs·w·g.
pub(super) const READOUTS: usize = 4;

/// The rows `[lo, hi)` of rail DOFs within the step's reach of a shape.
pub(super) fn reach(red: &Reduction, s: &Shape) -> (usize, usize) {
    let lo = s.start.saturating_sub(red.step_band);
    let hi = (s.start + s.values.len() + red.step_band).min(red.rail_dofs);
    (lo.min(hi), hi)
}

/// Whether two rail shapes are within the step's reach of each other.
pub(super) fn near(red: &Reduction, a: &Shape, b: &Shape) -> bool {
    let (lo, hi) = reach(red, a);
    b.start < hi && b.start + b.values.len() > lo
}

/// Re Σ x·y over the modes of two shared vectors.
pub(super) fn dot(x: &CVec, y: &CVec) -> f64 {
    kernels::dot(&x.re, &x.im, &y.re, &y.im)
}

/// Re Σ c·x·y over the modes, c per-mode complex constants.
fn scaled_dot(c: [&[f64]; 2], x: &CVec, y: &CVec) -> f64 {
    let mut t = CVec::zeros(x.re.len());
    t.set_mul(c, x.parts());
    dot(&t, y)
}

/// Σ_k s_k·gain[k − start] over the entries of a rail shape within the gain's range.
pub(super) fn shape_gain(s: &Shape, start: usize, gain: &[f64]) -> f64 {
    s.values
        .iter()
        .enumerate()
        .filter_map(|(k, a)| {
            let i = (s.start + k).checked_sub(start)?;
            gain.get(i).map(|g| a * g)
        })
        .sum()
}

/// The structure side of W coupled runs on one reduction.
pub(super) struct SynthesisSide<'a, const W: usize> {
    pub(super) model: &'a Model,
    pub(super) red: &'a Reduction,
    pub(super) coef: Coefficients,
    pub(super) observers: Vec<Observer>,
    /// The observers' kernel vectors (`Observer::psi`).
    pub(super) observer_psi: Vec<[CVec; 2]>,
    /// The pads whose force the run records (their two ends are the last observers).
    pub(super) pads: Vec<Pad>,
    pub(super) lanes: Vec<Lane>,
    /// The wheels' rail shapes this step.
    pub(super) wheel_shapes: Vec<Shape>,
    /// Ports: the wheels' ψᵀs (refreshed every step), then the dampers' ψᵀ(s_up − s_low).
    pub(super) ports: Vec<CVec>,
    /// Ports that carry a force: every damper, and the wheels on the structure (a wheel off it
    /// has a zero shape and a zero port, which the passes skip).
    pub(super) active: Vec<bool>,
    // Dampers.
    pub(super) dampers: Vec<DamperPort>,
    // Moving forces: shapes, their slopes (on the rail) and modal force at t_{n+1} (now) and
    // t_{n+2} (ahead).
    pub(super) movers: Vec<Mover>,
    pub(super) shapes_now: Vec<Shape>,
    pub(super) shapes_ahead: Vec<Shape>,
    pub(super) slopes_now: Vec<Shape>,
    pub(super) slopes_ahead: Vec<Shape>,
    pub(super) gk_now: CVec,
    pub(super) gk_ahead: CVec,
    /// Each moving force's magnitude, in `movers` order (the kernel's input).
    pub(super) mover_magnitudes: Vec<f64>,
    /// Each lane's free modal state Q̃ for the coming step.
    pub(super) q_free: [CVec; W],
    // Per-step values and scratch (allocated once).
    /// Each wheel's step compliance this step (modes and residual); the modes' share from
    /// the rail DOFs' table.
    pub(super) diag: Vec<f64>,
    pub(super) rail_step: Arc<RailStepCompliance>,
    pub(super) rail_acc: Vec<Acc<W>>,
    pub(super) rail_free: Vec<[f64; W]>,
    pub(super) element_flex: Vec<f64>,
    /// sᵀR₀s of each wheel this step.
    pub(super) self_res: Vec<f64>,
    /// The wheels' residual filters: each lane's states (g, ġ) `[lane·nw + wheel]` at the
    /// step's start, their values at its end under no new force (`g_free`) and per unit new
    /// force (`g_gain`, shared), and the filtered forces g at its end (`g_now`).
    pub(super) g_state: Vec<[f64; 2]>,
    pub(super) g_free: Vec<[f64; 2]>,
    pub(super) g_gain: Vec<[f64; 2]>,
    pub(super) g_now: Vec<f64>,
    /// Wheel pairs `[wi·nw + vi]`, wi < vi: the modes' step compliance between near ones, R₀
    /// between any two.
    pub(super) near_pairs: Vec<f64>,
    pub(super) near_res: Vec<f64>,
    /// a1·ψ of a wheel (scratch of the near pairs' compliance).
    pub(super) scaled_port: CVec,
    /// Per observer and wheel this step: the rail gains at the wheel's shape (λw, w).
    pub(super) wheel_gains: Vec<[f64; 2]>,
    pub(super) mover_direct: Vec<[f64; 2]>,
    /// Damper e's port and wheel w `[e·nw + w]`: the modes' step compliance and R₀.
    pub(super) gdw: Vec<f64>,
    pub(super) gdw_res: Vec<f64>,
    pub(super) t_mat: Vec<f64>,
    pub(super) f0: Vec<f64>,
    pub(super) tmp: Vec<f64>,
    pub(super) forces: Vec<[f64; W]>,
    pub(super) observed: Vec<Acc<W>>,
    /// The kernel's readouts d, e per observer (`[2·o + k]`) of the last step.
    pub(super) de: Vec<[f64; W]>,
    pub(super) damper_acc: Vec<Acc<W>>,
    pub(super) damper_free: Vec<[f64; W]>,
    pub(super) scratch: Scratch,
}

impl<'a, const W: usize> SynthesisSide<'a, W> {
    fn new(
        model: &'a Model,
        specs: &[LaneSpec],
        red: &'a Reduction,
        record: Record,
        points: &[f64],
        v: &Vehicles<W>,
    ) -> Self {
        let (cfg, st) = (&model.cfg, &model.structure);
        let n = red.stride;
        let dt = cfg.solver.dt;
        let coef = Coefficients::new(red, dt);
        let nw = v.n_wheels();
        let wheel_shapes: Vec<Shape> = (0..nw)
            .map(|w| Shape {
                start: 0,
                values: Vec::with_capacity(st.wheel_shape_len(v.patch[w])),
            })
            .collect();
        let span = v
            .patch
            .iter()
            .map(|&a| st.wheel_shape_len(a))
            .max()
            .unwrap_or(1);
        let (dampers, ports, g_dd) = damper_ports(model, red, &coef, nw);
        let movers = Mover::all(cfg);
        let pads = pads_of(cfg);
        let shapes = observed_shapes(model, record, points, &pads);
        let observers = observers(red, &coef, shapes, &ports[nw..], !movers.is_empty());
        let no = observers.len();
        let observer_psi = observers.iter().map(|o| o.psi.clone()).collect();
        let n_steps = cfg.n_steps();
        let lanes = specs
            .iter()
            .map(|spec| {
                let dampers: Vec<DamperLane> = spec
                    .dampers
                    .iter()
                    .map(|p| DamperLane::new(p, dt))
                    .collect();
                let (s_inv, setup) = damper_inverse(&dampers, &g_dd);
                Lane {
                    dampers,
                    s_inv,
                    setup,
                    readouts: vec![0.0; (n_steps + 1) * no * READOUTS],
                    residual: vec![0.0; (n_steps + 1) * no],
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
        let nd = dampers.len();
        Self {
            model,
            red,
            observer_psi,
            pads,
            lanes,
            wheel_shapes,
            active: vec![true; ports.len()],
            ports,
            shapes_now: mover_shapes(),
            shapes_ahead: mover_shapes(),
            slopes_now: mover_shapes(),
            slopes_ahead: mover_shapes(),
            mover_magnitudes: movers.iter().map(|m| m.magnitude).collect(),
            movers,
            gk_now: CVec::zeros(n),
            gk_ahead: CVec::zeros(n),
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
            forces: vec![[0.0; W]; nw + nd],
            observed: vec![Acc::ZERO; 2 * no],
            de: vec![[0.0; W]; 2 * no],
            damper_acc: vec![Acc::ZERO; nd],
            damper_free: vec![[0.0; W]; nd],
            scratch: Scratch::new(),
            observers,
            dampers,
            coef,
        }
    }
}

/// ψᵀs of a shape into a new vector.
fn project(red: &Reduction, s: &Shape) -> CVec {
    let mut p = CVec::zeros(red.stride);
    kernels::project(red, s, &mut p);
    p
}

/// The dampers' ports (after `nw` wheel ports, zero here), their step compliance with the rail
/// near them, and G_dd = Re Σ a1·ψ_d·ψ_e + R(upper_d, upper_e), the same in every lane.
fn damper_ports(
    model: &Model,
    red: &Reduction,
    coef: &Coefficients,
    nw: usize,
) -> (Vec<DamperPort>, Vec<CVec>, Vec<f64>) {
    let (cfg, st) = (&model.cfg, &model.structure);
    let n = red.stride;
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
        let mut psi = project(red, &att.upper);
        let low = project(red, &att.lower);
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
    (dampers, ports, g_dd)
}

/// What each observer reads: the layers' records, layer by layer and point by point, then each
/// pad's upper and lower end, read for velocity, then the bottom layer's bending moment at
/// each point when the run records it: (layer, shape, velocity).
fn observed_shapes(
    model: &Model,
    record: Record,
    points: &[f64],
    pads: &[Pad],
) -> Vec<(usize, Shape, bool)> {
    let (cfg, st) = (&model.cfg, &model.structure);
    let layers = record
        .layers(cfg)
        .into_iter()
        .flat_map(|li| points.iter().map(move |&x| (li, x, false)));
    let ends = pads
        .iter()
        .flat_map(|p| [(0, p.x, true), (p.lower, p.x, true)]);
    let shapes = layers
        .chain(ends)
        .map(|(li, x, velocity)| (li, st.shape(li, x), velocity));
    let deck = st.layers.len().saturating_sub(1);
    let moments = points
        .iter()
        .filter(|_| record.moments(cfg))
        .map(|&x| (deck, st.layers[deck].moment_shape(x), false));
    shapes.chain(moments).collect()
}

/// The observers of `shapes` with their gains: each reads Re Σ ψᵀs·Q and Re Σ λ²ψᵀs·Q
/// (Re Σ λψᵀs·Q when read for velocity).
fn observers(
    red: &Reduction,
    coef: &Coefficients,
    shapes: Vec<(usize, Shape, bool)>,
    damper_ports: &[CVec],
    movers: bool,
) -> Vec<Observer> {
    let n = red.stride;
    let lam = [&coef.lam[0][..], &coef.lam[1][..]];
    let zeros = vec![0.0; n];
    let weight = [&coef.w[..], &zeros[..]];
    let psis: Vec<CVec> = shapes.iter().map(|(_, s, _)| project(red, s)).collect();
    let pairs: Vec<(&Shape, &CVec)> = shapes.iter().map(|(_, s, _)| s).zip(&psis).collect();
    let gains = red.gains(&pairs);
    let mut observers = Vec::with_capacity(shapes.len());
    for (((li, s, velocity), psi), gains) in shapes.into_iter().zip(psis).zip(gains) {
        let mut pw = CVec::zeros(n);
        pw.set_mul(weight, psi.parts());
        let mut plw = CVec::zeros(n);
        plw.set_mul(lam, pw.parts());
        let mut l2 = CVec::zeros(n);
        l2.set_mul(lam, psi.parts());
        if !velocity {
            let l2_copy = l2.clone();
            l2.set_mul(lam, l2_copy.parts());
        }
        observers.push(Observer {
            damper_gains: damper_ports
                .iter()
                .map(|d| [dot(&plw, d), dot(&pw, d)])
                .collect(),
            mover_gains: movers.then_some([plw, pw]),
            psi: [psi, l2],
            rail_shape: (li == 0).then_some(s),
            gains,
        });
    }
    observers
}
