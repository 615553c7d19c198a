//! The coupled step on a reduction: W jobs of one model in lockstep (W = 1: a single run).
//!
//! The jobs of a group share the structure, the speed and the vehicles, so the wheels'
//! positions, their modal shapes ψᵀs and step compliances are computed once per step for all
//! of them (`kernels::wheel_pass`); each job has its own modal state, irregularity, contact
//! forces and dampers' parameters (`kernels::update`).
//!
//! Within a step the displacements at the wheels and at the dampers' ports are affine in the
//! unknown forces through the step compliance Re Σ ψ_a·a1·ψ_b + R_ab, so the contact Newton
//! iterates on the wheel forces alone, as in the finite-element engine. Two loads farther
//! apart than the residual's reach (`Reduction::band` rail DOFs) have no step compliance:
//! within one step (40 µs) no wave carries a load that far (the rail's shear wave needs
//! 0.4 ms per metre), so the full model's value is nil and the truncated modes' remainder is
//! noise. Tuned inerter dampers are physical elements on fixed ports: the trapezoidal rule on
//! their internal node gives F = κ(d − d̃) in the relative port displacement d, which is
//! eliminated exactly. Accelerations are analytic (`kernels::update`) plus the rail
//! residual's second difference.

use super::Reduction;
use super::kernels::{self, Acc, CVec, LVec, Scratch, Update, WheelPass};
use super::step::{C, Coefficients};
use crate::basis::Shape;
use crate::config::InitialState;
use crate::contact::{ContactSolver, patch_half_length};
use crate::error::{Result, VtbError};
use crate::integrator::GW;
use crate::model::Model;
use crate::results::{Record, RunResult};
use crate::simulate::{
    CANCEL_POLL, CarRun, FINITE_POLL, LaneSpec, Mover, finish, note_contact, static_wheel_loads,
};
use crate::vehicle::N_WHEELS;
use std::sync::atomic::{AtomicBool, Ordering};

/// One run on a reduction.
pub fn run(
    model: &Model,
    spec: &LaneSpec,
    red: &Reduction,
    record: Record,
    cancel: Option<&AtomicBool>,
) -> Result<RunResult> {
    run_lanes::<1>(model, std::slice::from_ref(spec), red, record, cancel)?
        .pop()
        .expect("one lane")
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

/// A lane's own data.
struct Lane<'a> {
    spec: &'a LaneSpec<'a>,
    contact: ContactSolver,
    dampers: Vec<DamperLane>,
    /// (I + diag(κ)·G_dd)⁻¹, row-major.
    s_inv: Vec<f64>,
    error: Option<VtbError>,
    loss_open: Vec<Option<f64>>,
    /// The observers' readouts (`kernels::update`) per step, `[(step·no + j)·4 + k]`, and
    /// the rail observers' residual displacement `[step·n_rail + j]`: the records are made
    /// of them once the run is over (`records`).
    readouts: Vec<f64>,
    residual: Vec<f64>,
}

/// An observation point of one layer: ψᵀs, and its shape on the rail (for the residual).
struct Observer {
    psi: CVec,
    rail_shape: Option<Shape>,
}

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

/// Re Σ a1·x·y over the modes.
fn a1_dot(coef: &Coefficients, x: &CVec, y: &CVec) -> f64 {
    let mut t = CVec::zeros(x.re.len());
    t.set_mul([&coef.a1[0], &coef.a1[1]], x);
    dot(&t, y)
}

/// W jobs of one model on a reduction: lane c runs on `specs[c]`'s irregularity and damper
/// parameters. The outer error is shared by all lanes (setup, cancellation); the inner ones
/// are each lane's own (a failing lane idles while the others go on).
pub fn run_lanes<const W: usize>(
    model: &Model,
    specs: &[LaneSpec],
    red: &Reduction,
    record: Record,
    cancel: Option<&AtomicBool>,
) -> Result<Vec<Result<RunResult>>> {
    assert_eq!(specs.len(), W, "one lane spec per lane");
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
    for spec in specs {
        if spec.dampers.len() != st.tids.len() {
            return Err(VtbError::config(
                "tids.count",
                spec.dampers.len(),
                format!(
                    "a lockstep group needs {} dampers in every job",
                    st.tids.len()
                ),
            ));
        }
    }
    let n = red.stride;
    let dt = cfg.solver.dt;
    let g = cfg.solver.gravity;
    let v = cfg.speed;
    let coef = Coefficients::new(red, dt);
    let points = match record {
        Record::Full => cfg.observation_points(),
        Record::Metrics => cfg.observation_points()[..1].to_vec(),
    };
    crate::budget::check_histories(cfg, record, W)?;
    let project = |s: &Shape| {
        let mut p = CVec::zeros(n);
        kernels::project(red, s, &mut p);
        p
    };
    let observers: Vec<Observer> = (0..st.layers.len())
        .flat_map(|li| points.iter().map(move |&x| (li, x)))
        .map(|(li, x)| {
            let s = st.shape(li, x);
            Observer {
                psi: project(&s),
                rail_shape: (li == 0).then_some(s),
            }
        })
        .collect();
    let no = observers.len();
    let observer_psi: Vec<CVec> = observers.iter().map(|o| o.psi.clone()).collect();

    // ------------------------------------------------------------------ vehicles, contact
    let movers = Mover::all(cfg);
    let mut cars = model
        .cars
        .iter()
        .map(|c| CarRun::<W>::new(c, dt, g))
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
    let wheel_x0: Vec<f64> = cars.iter().flat_map(|c| c.car.wheel_x0).collect();

    // ------------------------------------------------------------------ dampers
    let nd = st.tids.len();
    let damper_x: Vec<f64> = cfg.tids.as_ref().map_or_else(Vec::new, |t| {
        (0..t.count).map(|i| t.x0 + i as f64 * t.spacing).collect()
    });
    // Ports: the wheels' ψᵀs (refreshed every step), then the dampers' ψᵀ(s_up − s_low).
    let mut ports: Vec<CVec> = (0..nw).map(|_| CVec::zeros(n)).collect();
    let mut damper_ports = Vec::with_capacity(nd);
    for (a, &x) in st.tids.iter().zip(&damper_x) {
        let mut psi = project(&a.upper);
        let low = project(&a.lower);
        for j in 0..n {
            psi.re[j] -= low.re[j];
            psi.im[j] -= low.im[j];
        }
        let mut scaled = CVec::zeros(n);
        scaled.set_mul([&coef.a1[0], &coef.a1[1]], &psi);
        let (lo, hi) = reach(red, &st.shape(0, x));
        let gain = (lo..hi)
            .map(|i| {
                let (rr, ri) = red.row(i);
                kernels::dot(&scaled.re, &scaled.im, rr, ri)
            })
            .collect();
        damper_ports.push(DamperPort {
            upper: a.upper.clone(),
            gain_start: lo,
            gain,
        });
        ports.push(psi);
    }
    // G_dd = Re Σ a1·ψ_d·ψ_e + R(upper_d, upper_e), the same in every lane.
    let mut g_dd = vec![0.0; nd * nd];
    for e in 0..nd {
        for f in 0..nd {
            g_dd[e * nd + f] = a1_dot(&coef, &ports[nw + e], &ports[nw + f])
                + red.residual(&damper_ports[e].upper, &damper_ports[f].upper);
        }
    }
    let n_steps = cfg.n_steps();
    let n_rail = observers.iter().filter(|o| o.rail_shape.is_some()).count();
    let mut lanes: Vec<Lane> = specs
        .iter()
        .map(|spec| {
            let dampers: Vec<DamperLane> = spec
                .dampers
                .iter()
                .map(|p| {
                    let (k, c, b) = (p.stiffness, p.damping, p.inertance);
                    DamperLane {
                        kappa: 1.0 / (1.0 / (k + 2.0 * c / dt) + dt * dt / (4.0 * b)),
                        k,
                        c,
                        b,
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
                ),
                dampers,
                s_inv,
                error,
                loss_open: vec![None; nw],
                readouts: vec![0.0; (n_steps + 1) * no * READOUTS],
                residual: vec![0.0; (n_steps + 1) * n_rail],
            }
        })
        .collect();

    // ------------------------------------------------------------------ loads
    let mut wheel_shapes: Vec<Shape> = (0..nw)
        .map(|w| Shape {
            start: 0,
            values: Vec::with_capacity(st.wheel_shape_len(patch[w])),
        })
        .collect();
    let set_wheel_shapes = |t: f64, shapes: &mut [Shape]| {
        for (w, s) in shapes.iter_mut().enumerate() {
            st.wheel_shape_into(wheel_x0[w] + v * t, patch[w], s);
        }
    };
    let new_mover_shapes = || -> Vec<Shape> {
        movers
            .iter()
            .map(|mv| Shape {
                start: 0,
                values: vec![0.0; st.layers[mv.layer].basis.shape_len()],
            })
            .collect()
    };
    // The moving forces' shapes at t and their modal force Σ P·ψᵀs into `gk`.
    let mut mover_psi = CVec::zeros(n);
    let mut movers_at = |t: f64, gk: &mut CVec, shapes: &mut [Shape]| {
        gk.re.fill(0.0);
        gk.im.fill(0.0);
        for (mv, sh) in movers.iter().zip(shapes.iter_mut()) {
            st.shape_into(mv.layer, mv.x0 + v * t, sh);
            kernels::project(red, sh, &mut mover_psi);
            for j in 0..n {
                gk.re[j] = mv.magnitude.mul_add(mover_psi.re[j], gk.re[j]);
                gk.im[j] = mv.magnitude.mul_add(mover_psi.im[j], gk.im[j]);
            }
        }
    };
    // The rail's residual displacement at s under the rail's moving forces.
    let mover_residual = |s: &Shape, shapes: &[Shape]| -> f64 {
        movers
            .iter()
            .zip(shapes)
            .filter(|(mv, _)| mv.layer == 0)
            .map(|(mv, sm)| mv.magnitude * red.residual(s, sm))
            .sum()
    };
    let wheel_residual = |s: &Shape, shapes: &[Shape], p: &[f64]| -> f64 {
        shapes
            .iter()
            .zip(p)
            .map(|(sw, pw)| pw * red.residual(s, sw))
            .sum()
    };

    // ------------------------------------------------------------------ t = 0
    let rest = cfg.solver.initial_state == InitialState::Rest;
    let mut shapes_now = new_mover_shapes();
    let mut shapes_ahead = new_mover_shapes();
    let mut gk_now = CVec::zeros(n);
    let mut gk_ahead = CVec::zeros(n);
    movers_at(0.0, &mut gk_now, &mut shapes_now);
    set_wheel_shapes(0.0, &mut wheel_shapes);
    let mut g0 = gk_now.clone();
    for (w, s) in wheel_shapes.iter().enumerate() {
        kernels::project(red, s, &mut ports[w]);
        for j in 0..n {
            g0.re[j] = loads[w].mul_add(ports[w].re[j], g0.re[j]);
            g0.im[j] = loads[w].mul_add(ports[w].im[j], g0.im[j]);
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
    let static_share = |u: f64| if rest { 0.0 } else { u };
    let p0 = loads.clone();
    let static_residual = |s: &Shape| {
        static_share(wheel_residual(s, &wheel_shapes, &p0) + mover_residual(s, &shapes_now))
    };
    let d0: Vec<f64> = (0..nd)
        .map(|d| {
            dot(&ports[nw + d], &q0) + static_residual(&damper_ports[d].upper)
        })
        .collect();
    let rail0: Vec<f64> = (0..nw)
        .map(|w| dot(&ports[w], &q0) + static_residual(&wheel_shapes[w]))
        .collect();
    for lane in lanes.iter_mut() {
        for (d, s) in lane.dampers.iter_mut().zip(&d0) {
            d.s = *s;
        }
    }
    for (ci, c) in cars.iter_mut().enumerate() {
        for (lane, l) in lanes.iter().enumerate() {
            let rail: [f64; N_WHEELS] = std::array::from_fn(|w| {
                let wi = ci * N_WHEELS + w;
                rail0[wi] + cfg.irregularity_share(0.0) * l.spec.profile.at(wheel_x0[wi])
            });
            c.set_static(lane, rail, &loads[ci * N_WHEELS..(ci + 1) * N_WHEELS], g)?;
        }
        let pc: [f64; GW] =
            std::array::from_fn(|w| if w < N_WHEELS { loads[ci * N_WHEELS + w] } else { 0.0 });
        c.set_force(&[pc; W]);
    }
    // The lanes' state: Q̃₁ = e·Q₀ + a0·g₀ + a1·g_known(t₁), and g₀.
    movers_at(dt, &mut gk_ahead, &mut shapes_ahead);
    let mut q_free = LVec::<W>::zeros(n);
    let mut g_lanes = LVec::<W>::zeros(n);
    let mut qa0 = CVec::zeros(n);
    for j in 0..n {
        let (q, gj, k1) = (
            C(q0.re[j], q0.im[j]),
            C(g0.re[j], g0.im[j]),
            C(gk_ahead.re[j], gk_ahead.im[j]),
        );
        let lam = C(coef.lam[0][j], coef.lam[1][j]);
        let qf = C(coef.e[0][j], coef.e[1][j])
            .mul(q)
            .add(C(coef.a0[0][j], coef.a0[1][j]).mul(gj))
            .add(coef.a1_at(j).mul(k1));
        let qa = lam.mul(lam.mul(q).add(gj.scale(coef.w[j])));
        // (The force-rate term w·ġ of Q̈ is zero: the loads stood still before t = 0.)
        (qa0.re[j], qa0.im[j]) = (qa.0, qa.1);
        for c in 0..W {
            q_free.set(j, c, (qf.0, qf.1));
            g_lanes.set(j, c, (gj.0, gj.1));
        }
    }
    let d_free0: Vec<f64> = (0..nd)
        .map(|d| dot(&ports[nw + d], &q_free.lane(0)))
        .collect();
    let mut damper_free = vec![Acc::<W>::ZERO; nd];
    let mut damper_free_now: Vec<[f64; W]> = d_free0.iter().map(|&x| [x; W]).collect();

    let mut res: Vec<RunResult> = (0..W)
        .map(|_| RunResult::new(cfg, st, n_steps, &points, cars.len(), nw, record))
        .collect();
    let mut wg0 = g0.clone();
    wg0.set_mul([&coef.w, &vec![0.0; n]], &g0);
    let mut lwg0 = wg0.clone();
    lwg0.set_mul([&coef.lam[0], &coef.lam[1]], &wg0);
    let mut observed_now: Vec<[f64; W]> = observers
        .iter()
        .flat_map(|o| [&q0, &qa0, &lwg0, &wg0].map(|x| [dot(&o.psi, x); W]))
        .collect();
    let mut p = vec![0.0; nw * W];
    for c in 0..W {
        p[c * nw..(c + 1) * nw].copy_from_slice(&loads);
    }
    // Observers, vehicles and contact forces of every live lane at `step`.
    let record_step = |res: &mut [RunResult],
                       lanes: &mut [Lane],
                       step: usize,
                       observed: &[[f64; W]],
                       shapes: &[Shape],
                       movers_now: &[Shape],
                       p: &[f64],
                       cars: &[CarRun<W>]| {
        for (c, (r, lane)) in res.iter_mut().zip(lanes.iter_mut()).enumerate() {
            if lane.error.is_some() {
                continue;
            }
            let pl = &p[c * nw..(c + 1) * nw];
            let at = step * no * READOUTS;
            for (k, x) in lane.readouts[at..at + no * READOUTS].iter_mut().enumerate() {
                *x = observed[k][c];
            }
            for (j, o) in observers.iter().enumerate() {
                if let Some(s) = &o.rail_shape {
                    lane.residual[step * n_rail + j] =
                        wheel_residual(s, shapes, pl) + mover_residual(s, movers_now);
                }
            }
            let (ncars, ndof) = (r.n_cars, r.vehicle_dofs);
            for (ci, car) in cars.iter().take(ncars).enumerate() {
                for i in 0..ndof {
                    let (z, _, a) = car.nm.observed(i, c);
                    r.vehicle_disp[(step * ncars + ci) * ndof + i] = z - car.z0[i * W + c];
                    r.vehicle_acc[(step * ncars + ci) * ndof + i] = a;
                }
            }
            r.contact_force[step * nw..(step + 1) * nw].copy_from_slice(pl);
        }
    };
    record_step(
        &mut res,
        &mut lanes,
        0,
        &observed_now,
        &wheel_shapes,
        &shapes_now,
        &p,
        &cars,
    );

    // ------------------------------------------------------------------ the steps
    let mut scratch = Scratch::<W>::new();
    let mut observed = vec![Acc::<W>::ZERO; READOUTS * no];
    let mut forces = vec![[0.0; W]; nw + nd];
    let mut diag = vec![0.0; nw];
    let mut diag_acc = vec![Acc::<1>::ZERO; nw];
    let mut rail_acc = vec![Acc::<W>::ZERO; nw];
    let mut near_pairs = vec![0.0; nw * nw];
    let mut rail_free = vec![[0.0; W]; nw];
    let mut element_flex = vec![0.0; nw];
    let mut gdw = vec![0.0; nd * nw];
    let mut t_mat = vec![0.0; W * nd * nw];
    let mut f0 = vec![0.0; W * nd];
    let mut tmp = vec![0.0; nd];
    let mut amat = vec![0.0; W * nw * nw];
    let mut delta_free = vec![0.0; W * nw];
    for step in 0..n_steps {
        if step % CANCEL_POLL == 0 && cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
            return Err(VtbError::Cancelled);
        }
        if step % FINITE_POLL == 0 {
            for (c, lane) in lanes.iter_mut().enumerate() {
                if lane.error.is_none() && !q_free.lane_finite(c) {
                    fail(
                        lane,
                        c,
                        &mut q_free,
                        &mut g_lanes,
                        &mut p,
                        &mut cars,
                        VtbError::Solver(format!(
                            "the modal coordinates became non-finite by step {step}: an \
                             overflow, most likely from parameters of extreme magnitude"
                        )),
                    );
                }
            }
        }
        if lanes.iter().all(|l| l.error.is_some()) {
            break;
        }
        let t1 = (step + 1) as f64 * dt;
        let share = cfg.irregularity_share(t1);
        if !movers.is_empty() {
            std::mem::swap(&mut shapes_now, &mut shapes_ahead);
            std::mem::swap(&mut gk_now, &mut gk_ahead);
            movers_at(t1 + dt, &mut gk_ahead, &mut shapes_ahead);
        }
        // The wheel pass (shared): ψᵀs, step compliances, free rail displacements.
        set_wheel_shapes(t1, &mut wheel_shapes);
        kernels::wheel_pass::<W>(
            red,
            &coef,
            &q_free,
            WheelPass {
                shapes: &wheel_shapes,
                outs: &mut ports[..nw],
                diag: &mut diag_acc,
                rail: &mut rail_acc,
            },
        );
        for w in 0..nw {
            diag[w] = diag_acc[w].sum()[0] + red.residual(&wheel_shapes[w], &wheel_shapes[w]);
            rail_free[w] = rail_acc[w].sum();
            element_flex[w] = if cfg.discretisation.element_flexibility {
                st.wheel_flexibility(wheel_x0[w] + v * t1, patch[w])
            } else {
                0.0
            };
        }
        for wi in 0..nw {
            for vi in wi + 1..nw {
                let a = if near(red, &wheel_shapes[wi], &wheel_shapes[vi]) {
                    a1_dot(&coef, &ports[wi], &ports[vi])
                        + red.residual(&wheel_shapes[wi], &wheel_shapes[vi])
                } else {
                    0.0
                };
                near_pairs[wi * nw + vi] = a;
            }
        }
        for (e, dp) in damper_ports.iter().enumerate() {
            for (w, sw) in wheel_shapes.iter().enumerate() {
                let modal: f64 = sw
                    .values
                    .iter()
                    .enumerate()
                    .filter_map(|(k, a)| {
                        let i = (sw.start + k).checked_sub(dp.gain_start)?;
                        dp.gain.get(i).map(|g| a * g)
                    })
                    .sum();
                gdw[e * nw + w] = modal + red.residual(&dp.upper, sw);
            }
        }
        // The dampers of each lane: F = F0 + T·P.
        for (c, lane) in lanes.iter_mut().enumerate() {
            if lane.error.is_some() || nd == 0 {
                continue;
            }
            let (f0, t_mat) = (
                &mut f0[c * nd..(c + 1) * nd],
                &mut t_mat[c * nd * nw..(c + 1) * nd * nw],
            );
            for (e, d) in lane.dampers.iter_mut().enumerate() {
                d.r_hat = d.c * (2.0 * d.r / dt + d.rd) / (d.k + 2.0 * d.c / dt);
                d.s_tilde = d.s + dt * d.sd + 0.25 * dt * dt * d.sdd;
                let free = damper_free_now[e][c] + mover_residual(&damper_ports[e].upper, &shapes_now);
                f0[e] = d.kappa * (free - d.r_hat - d.s_tilde);
                for w in 0..nw {
                    t_mat[e * nw + w] = d.kappa * gdw[e * nw + w];
                }
            }
            // F0 ← S⁻¹·F0, T ← S⁻¹·T.
            let s_inv = &lane.s_inv;
            tmp.copy_from_slice(f0);
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
        }
        // The wheels: δ = δ_free − A·P.
        for (ci, car) in cars.iter_mut().enumerate() {
            car.nm.begin_step(&car.f_prev, &car.gravity);
            let wheel = car.nm.free_port_disp(&car.ports);
            for (c, lane) in lanes.iter().enumerate() {
                for w in 0..N_WHEELS {
                    let wi = ci * N_WHEELS + w;
                    let mut rail = rail_free[wi][c]
                        + mover_residual(&wheel_shapes[wi], &shapes_now);
                    for e in 0..nd {
                        rail -= gdw[e * nw + wi] * f0[c * nd + e];
                    }
                    delta_free[c * nw + wi] =
                        wheel[c][w] - rail - share * lane.spec.profile.at(wheel_x0[wi] + v * t1);
                }
            }
        }
        for c in 0..W {
            let a = &mut amat[c * nw * nw..(c + 1) * nw * nw];
            let t_mat = &t_mat[c * nd * nw..(c + 1) * nd * nw];
            for wi in 0..nw {
                for vi in wi..nw {
                    let mut x = if wi == vi {
                        diag[wi] + element_flex[wi]
                    } else {
                        near_pairs[wi * nw + vi]
                    };
                    for e in 0..nd {
                        x -= gdw[e * nw + wi] * t_mat[e * nw + vi];
                    }
                    let (ci, cj) = (wi / N_WHEELS, vi / N_WHEELS);
                    if ci == cj {
                        x += cars[ci].car.rails * cars[ci].compliance[wi % N_WHEELS][vi % N_WHEELS];
                    }
                    a[wi * nw + vi] = x;
                    a[vi * nw + wi] = x;
                }
            }
        }
        for (c, lane) in lanes.iter_mut().enumerate() {
            if lane.error.is_some() || nw == 0 {
                continue;
            }
            let solved = lane.contact.solve(
                &mut p[c * nw..(c + 1) * nw],
                &delta_free[c * nw..(c + 1) * nw],
                &amat[c * nw * nw..(c + 1) * nw * nw],
                t1,
                step + 1,
            );
            if let Err(e) = solved {
                fail(lane, c, &mut q_free, &mut g_lanes, &mut p, &mut cars, e);
            }
        }
        // Forces known: the dampers' forces and states.
        for (c, lane) in lanes.iter_mut().enumerate() {
            for w in 0..nw {
                forces[w][c] = p[c * nw + w];
            }
            if lane.error.is_some() {
                for e in 0..nd {
                    forces[nw + e][c] = 0.0;
                }
                continue;
            }
            for (e, d) in lane.dampers.iter_mut().enumerate() {
                let f: f64 = f0[c * nd + e]
                    + (0..nw)
                        .map(|w| t_mat[c * nd * nw + e * nw + w] * p[c * nw + w])
                        .sum::<f64>();
                forces[nw + e][c] = -f;
                let r1 = f / (d.k + 2.0 * d.c / dt) + d.r_hat;
                d.rd = 2.0 * (r1 - d.r) / dt - d.rd;
                d.r = r1;
                let sdd1 = f / d.b;
                let sd1 = d.sd + 0.5 * dt * (d.sdd + sdd1);
                d.s += 0.5 * dt * (d.sd + sd1);
                d.sd = sd1;
                d.sdd = sdd1;
            }
        }
        // The update pass: the modes stepped, observers and damper ports read.
        kernels::update::<W>(
            Update {
                coef: &coef,
                ports: &ports,
                forces: &forces,
                movers: (!movers.is_empty()).then_some((&gk_now, &gk_ahead)),
                observers: &observer_psi,
                observed: &mut observed,
                dampers_from: nw,
                damper_free: &mut damper_free,
            },
            &mut q_free,
            &mut g_lanes,
            &mut scratch,
        );
        for (o, acc) in observed_now.iter_mut().zip(&observed) {
            *o = acc.sum();
        }
        for (d, acc) in damper_free_now.iter_mut().zip(&damper_free) {
            *d = acc.sum();
        }
        for (ci, car) in cars.iter_mut().enumerate() {
            let pc: [[f64; GW]; W] = std::array::from_fn(|c| {
                std::array::from_fn(|w| {
                    if w < N_WHEELS {
                        p[c * nw + ci * N_WHEELS + w]
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
        for (c, lane) in lanes.iter_mut().enumerate() {
            if lane.error.is_none() {
                note_contact(
                    &mut lane.loss_open,
                    &p[c * nw..(c + 1) * nw],
                    t1,
                    &mut res[c].contact_loss,
                );
            }
        }
        record_step(
            &mut res,
            &mut lanes,
            step + 1,
            &observed_now,
            &wheel_shapes,
            &shapes_now,
            &p,
            &cars,
        );
    }
    Ok(lanes
        .into_iter()
        .zip(res)
        .map(|(lane, mut r)| match lane.error {
            Some(e) => Err(e),
            None => {
                records(&mut r, &lane.readouts, &lane.residual, no, n_rail, dt);
                finish(&lane.loss_open, r)
            }
        })
        .collect())
}

/// Readouts per observer and step (`kernels::update`): d = Re Σ ψᵀs·Q, a = Re Σ ψᵀs·λ(λQ +
/// w·g), z = Re Σ ψᵀs·λw·g, y = Re Σ ψᵀs·w·g.
const READOUTS: usize = 4;

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
///   u = E(d) + r,   ü = E(a − z + D₂r) + z + D₁y.
///
/// The modes' response to the piecewise-linear force through the force samples is the true
/// response low-passed by sinc²(ωh/2) at every sample, and so is the second difference D₂ of
/// the exact quasi-static residual: the zero-phase FIR E = (−1, 14, −1)/12, whose gain
/// 1 + (1 − cos ωh)/6 is 1/sinc²(ωh/2) to O((ωh)⁴) (0.2 % at 2 kHz, h = 5e-5 s), equalises
/// them. The force samples themselves are exact (z), and the force-rate term w·ġ is the
/// fourth-order central difference D₁ of y.
fn records(r: &mut RunResult, readouts: &[f64], residual: &[f64], no: usize, n_rail: usize, dt: f64) {
    let n = readouts.len() / (no * READOUTS).max(1);
    let e = |x: &[f64], s: usize| (14.0 * x[s + 2] - x[s + 1] - x[s + 3]) / 12.0;
    for j in 0..no {
        let rd = |k: usize, s: usize| readouts[(s * no + j) * READOUTS + k];
        let rr = padded(n, |s| if j < n_rail { residual[s * n_rail + j] } else { 0.0 });
        let (d, z, y) = (padded(n, |s| rd(0, s)), padded(n, |s| rd(2, s)), padded(n, |s| rd(3, s)));
        let inner = padded(n, |s| {
            rd(1, s) - z[s + 2] + (rr[s + 3] - 2.0 * rr[s + 2] + rr[s + 1]) / (dt * dt)
        });
        for s in 0..n {
            r.disp[s * no + j] = e(&d, s) + rr[s + 2];
            let d1 = (y[s] - 8.0 * y[s + 1] + 8.0 * y[s + 3] - y[s + 4]) / (12.0 * dt);
            r.acc[s * no + j] = e(&inner, s) + z[s + 2] + d1;
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

/// Lane c failed: keep the error and zero its state so that it idles finite.
fn fail<const W: usize>(
    lane: &mut Lane,
    c: usize,
    q_free: &mut LVec<W>,
    g: &mut LVec<W>,
    p: &mut [f64],
    cars: &mut [CarRun<W>],
    e: VtbError,
) {
    lane.error = Some(e);
    q_free.clear_lane(c);
    g.clear_lane(c);
    let nw = p.len() / W;
    p[c * nw..(c + 1) * nw].fill(0.0);
    for car in cars {
        car.nm.clear_lane(c);
    }
}
