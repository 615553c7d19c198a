//! The coupled loop every engine shares: W jobs of one model in lockstep (W = 1: a single
//! run), their vehicles, the wheel–rail contact, the records and the run's finish, over the
//! structure side each engine implements ([`StructureSide`]).
//!
//! A step, t_n → t_{n+1}: the structure begins its step (its known loads, the wheels'
//! positions, the rail's free displacement at every wheel and its step compliance there), the
//! cars begin theirs; the contact solves δ = δ_free − A·P for the wheel forces P of each lane
//! (Newton on the Hertz law), A the rail's compliance plus each car's own; both sides then
//! take P and finish the step, and the step is recorded. The vehicles see the structure only
//! through the rail's free displacement and compliance at the wheels (a wheel's port), as in
//! STEM's vehicle interface, so a new engine is a new structure side.

pub(crate) mod residual;
mod vehicles;

pub(crate) use vehicles::{Mover, Vehicles};

use super::{CANCEL_POLL, Control, FINITE_POLL, poll};
use crate::config::Profile;
use crate::error::{Result, VtbError};
use crate::model::Model;
use crate::model::contact::ContactSolver;
use crate::outputs::{ContactLoss, Record, RunResult};

/// What an engine does for the structure in the shared loop. Lanes are `0..W`; `p` holds the
/// contact force of every wheel on the modelled rail, `[lane·nw + wheel]` (N); `live[lane]` is
/// false once a lane failed (it then idles at zero).
pub(crate) trait StructureSide<const W: usize> {
    /// The state at t = 0 (static under the vehicles' static loads and the moving forces, or
    /// at rest) in every lane; a lane that cannot start gets its error in `failed`. Returns the
    /// rail's displacement at every wheel, `[lane·nw + wheel]` (m).
    fn start(&mut self, v: &Vehicles<W>, failed: &mut [Option<VtbError>]) -> Result<Vec<f64>>;

    /// The step to `t1` up to the contact: the known loads, the wheels' positions, the rail's
    /// free displacement and step compliance at them. An error fails every live lane.
    fn begin_step(
        &mut self,
        step: usize,
        t1: f64,
        v: &Vehicles<W>,
        p: &[f64],
        live: &[bool; W],
    ) -> Option<VtbError>;

    /// The rail's displacement at wheel `wheel` of lane `lane` at t1 under no new wheel force
    /// (m).
    fn free_rail(&self, lane: usize, wheel: usize) -> f64;

    /// Every lane's contact compliance `a[lane·nw² + wi·nw + vi]` (m/N): the rail's
    /// displacement at wheel wi per unit force of wheel vi over the step, plus the vehicles'
    /// own compliance `car(wi, vi)` (`None` between wheels of different cars), added in the
    /// side's own order.
    fn compliance(&self, v: &Vehicles<W>, a: &mut [f64], car: &dyn Fn(usize, usize) -> Option<f64>);

    /// The wheel forces `p` known: the structure takes them and finishes the step.
    fn end_step(&mut self, v: &Vehicles<W>, p: &[f64], live: &[bool; W]);

    /// The structure's records of every live lane at `step`.
    fn record(&mut self, res: &mut [RunResult], step: usize, p: &[f64], live: &[bool; W]);

    /// Lane `lane` failed: zero its state so that it idles finite.
    fn fail(&mut self, lane: usize);

    /// The structure's quantity that is not finite in lane `lane`, if any.
    fn non_finite(&self, lane: usize) -> Option<&'static str>;

    /// Lane `lane`'s records completed once the run is over.
    fn finish(&mut self, _lane: usize, _r: &mut RunResult) {}
}

/// A lane's own data in the loop: its irregularity, contact iteration, open contact-loss
/// periods and its failure once it failed.
struct Lane<'a> {
    profile: &'a Profile,
    contact: ContactSolver,
    error: Option<VtbError>,
    loss_open: Vec<Option<f64>>,
}

/// W coupled runs on one model.
struct Coupled<'a, S, const W: usize> {
    model: &'a Model,
    side: S,
    v: Vehicles<W>,
    lanes: Vec<Lane<'a>>,
    /// Contact forces `[lane·nw + wheel]` (N).
    p: Vec<f64>,
    /// Each lane's free compressions δ_free and contact compliance A this step.
    delta_free: Vec<f64>,
    amat: Vec<f64>,
    res: Vec<RunResult>,
    n_steps: usize,
}

/// Runs W jobs of `model` on the structure side `side` with the vehicles `v`: lane j on
/// `profiles[j]`, recording `points` as `record` asks. The outer error is shared by all lanes
/// (setup, or cancellation: `cancel` is polled every `CANCEL_POLL` steps); the inner ones are
/// each lane's own.
pub(crate) fn run<'a, S: StructureSide<W>, const W: usize>(
    model: &'a Model,
    side: S,
    v: Vehicles<W>,
    profiles: [&'a Profile; W],
    (record, points): (Record, &[f64]),
    cancel: Option<&Control>,
) -> Result<Vec<Result<RunResult>>> {
    let cfg = &model.cfg;
    let nw = v.n_wheels();
    let n_steps = cfg.n_steps();
    let lanes = profiles
        .into_iter()
        .map(|profile| Lane {
            profile,
            contact: ContactSolver::new(
                v.hertz.clone(),
                v.loads.clone(),
                cfg.solver.contact_tol,
                cfg.solver.contact_max_iter,
            )
            .with_block(v.wpc),
            error: None,
            loss_open: vec![None; nw],
        })
        .collect();
    let res = (0..W)
        .map(|_| {
            RunResult::new(
                cfg,
                &model.structure,
                n_steps,
                points,
                v.cars.len(),
                nw,
                record,
            )
        })
        .collect();
    let mut run = Coupled {
        model,
        side,
        lanes,
        p: v.loads.repeat(W),
        delta_free: vec![0.0; W * nw],
        amat: vec![0.0; W * nw * nw],
        res,
        n_steps,
        v,
    };
    run.start()?;
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
    run.check_finite(run.n_steps);
    Ok(run.finish())
}

impl<S: StructureSide<W>, const W: usize> Coupled<'_, S, W> {
    fn live(&self) -> [bool; W] {
        std::array::from_fn(|j| self.lanes[j].error.is_none())
    }

    /// t = 0: the structure's state, the cars' static equilibrium on it, the first record.
    fn start(&mut self) -> Result<()> {
        let cfg = &self.model.cfg;
        let (g, share) = (cfg.solver.gravity, cfg.irregularity_share(0.0));
        let nw = self.v.n_wheels();
        let mut failed: Vec<Option<VtbError>> = vec![None; W];
        let rail0 = self.side.start(&self.v, &mut failed)?;
        for (j, e) in failed.into_iter().enumerate() {
            if let Some(e) = e {
                self.fail(j, e);
            }
        }
        let wpc = self.v.wpc;
        for ci in 0..self.v.cars.len() {
            for j in 0..W {
                if self.lanes[j].error.is_some() {
                    continue;
                }
                let rail: Vec<f64> = (ci * wpc..(ci + 1) * wpc)
                    .map(|wi| {
                        rail0[j * nw + wi] + share * self.lanes[j].profile.under(wi, self.v.x0[wi])
                    })
                    .collect();
                let loads = &self.v.loads[ci * wpc..(ci + 1) * wpc];
                if let Err(e) = self.v.cars[ci].set_static(j, &rail, loads, g) {
                    self.fail(j, e);
                }
            }
            let pc = self.v.car_forces(ci, &self.v.loads.repeat(W));
            self.v.cars[ci].set_force(&pc);
        }
        self.record(0);
        Ok(())
    }

    /// One step, t_n → t_{n+1}.
    fn step(&mut self, step: usize) {
        let t1 = (step + 1) as f64 * self.model.cfg.solver.dt;
        let live = self.live();
        if let Some(e) = self.side.begin_step(step, t1, &self.v, &self.p, &live) {
            for j in (0..W).filter(|&j| live[j]) {
                self.fail(j, e.clone());
            }
        }
        for c in &mut self.v.cars {
            c.nm.begin_step(&c.f_prev, &c.gravity);
        }
        self.contact(step, t1);
        let live = self.live();
        self.side.end_step(&self.v, &self.p, &live);
        let nw = self.v.n_wheels();
        for ci in 0..self.v.cars.len() {
            let pc = self.v.car_forces(ci, &self.p);
            let c = &mut self.v.cars[ci];
            let wheel = pc.map(|pl| pl.map(|pw| -c.car.rails * pw));
            c.nm.add_port_forces(&c.ports, &wheel);
            c.nm.end_step();
            c.set_force(&pc);
        }
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            if lane.error.is_none() {
                note_contact(
                    &mut lane.loss_open,
                    &self.p[j * nw..(j + 1) * nw],
                    t1,
                    &mut self.res[j].contact_loss,
                );
            }
        }
        self.record(step + 1);
    }

    /// The contact: δ = δ_free − A·P per lane, solved by each lane's Newton.
    fn contact(&mut self, step: usize, t1: f64) {
        let cfg = &self.model.cfg;
        let (v, share) = (cfg.speed, cfg.irregularity_share(t1));
        let (nw, wpc) = (self.v.n_wheels(), self.v.wpc);
        for (ci, c) in self.v.cars.iter().enumerate() {
            let wheel = c.nm.free_port_disp(&c.ports);
            for (j, lane) in self.lanes.iter().enumerate() {
                for w in 0..wpc {
                    let wi = ci * wpc + w;
                    let x = self.v.x0[wi] + v * t1;
                    self.delta_free[j * nw + wi] = wheel[j][w]
                        - self.side.free_rail(j, wi)
                        - share * lane.profile.under(wi, x);
                }
            }
        }
        let cars = &self.v.cars;
        let own = |wi: usize, vi: usize| {
            let (ci, cj) = (wi / wpc, vi / wpc);
            (ci == cj).then(|| cars[ci].car.rails * cars[ci].compliance[wi % wpc][vi % wpc])
        };
        self.side.compliance(&self.v, &mut self.amat, &own);
        if nw == 0 {
            return;
        }
        for j in 0..W {
            let lane = &mut self.lanes[j];
            if lane.error.is_some() {
                continue;
            }
            let solved = lane.contact.solve(
                &mut self.p[j * nw..(j + 1) * nw],
                &self.delta_free[j * nw..(j + 1) * nw],
                &self.amat[j * nw * nw..(j + 1) * nw * nw],
                t1,
                step + 1,
            );
            if let Err(e) = solved {
                self.fail(j, e);
            }
        }
    }

    /// The records of every live lane at `step`: the structure's, the vehicles', the contact
    /// forces.
    fn record(&mut self, step: usize) {
        let live = self.live();
        self.side.record(&mut self.res, step, &self.p, &live);
        let nw = self.v.n_wheels();
        for (j, r) in self.res.iter_mut().enumerate() {
            if !live[j] {
                continue;
            }
            let (ncars, ndof) = (r.n_cars, r.vehicle_dofs);
            for (ci, c) in self.v.cars.iter().take(ncars).enumerate() {
                for i in 0..ndof {
                    let (z, _, a) = c.nm.observed(i, j);
                    r.vehicle_disp[(step * ncars + ci) * ndof + i] = z - c.z0[i * W + j];
                    r.vehicle_acc[(step * ncars + ci) * ndof + i] = a;
                }
            }
            r.contact_force[step * nw..(step + 1) * nw]
                .copy_from_slice(&self.p[j * nw..(j + 1) * nw]);
        }
    }

    /// Lane `j` failed: keep the error, zero its state so that it idles finite.
    fn fail(&mut self, j: usize, e: VtbError) {
        let nw = self.v.n_wheels();
        self.lanes[j].error = Some(e);
        self.side.fail(j);
        for c in &mut self.v.cars {
            c.nm.clear_lane(j);
        }
        self.p[j * nw..(j + 1) * nw].fill(0.0);
    }

    /// A non-finite state (overflow from extreme parameters) fails its lane, never gives a
    /// result.
    fn check_finite(&mut self, step: usize) {
        let nw = self.v.n_wheels();
        for j in 0..W {
            if self.lanes[j].error.is_some() {
                continue;
            }
            let quantity = if let Some(q) = self.side.non_finite(j) {
                Some(q.to_string())
            } else if !self.p[j * nw..(j + 1) * nw].iter().all(|v| v.is_finite()) {
                Some("the contact forces".to_string())
            } else {
                (0..self.v.cars.len())
                    .find(|&i| !self.v.cars[i].nm.lane_finite(j))
                    .map(|i| format!("the DOFs of vehicles[{i}]"))
            };
            if let Some(q) = quantity {
                let t = step as f64 * self.model.cfg.solver.dt;
                self.fail(
                    j,
                    VtbError::Solver(format!(
                        "{q} became non-finite by step {step} (t = {t:.6} s): an overflow, most \
                         likely from parameters of extreme magnitude (a mass or stiffness many \
                         orders from the others)"
                    )),
                );
            }
        }
    }

    /// Each lane's result, its records completed, or its error.
    fn finish(mut self) -> Vec<Result<RunResult>> {
        let res = std::mem::take(&mut self.res);
        self.lanes
            .iter()
            .zip(res)
            .enumerate()
            .map(|(j, (lane, mut r))| match &lane.error {
                Some(e) => Err(e.clone()),
                None => {
                    self.side.finish(j, &mut r);
                    finish(&lane.loss_open, r)
                }
            })
            .collect()
    }
}

/// Opens and closes the contact-loss periods of one run at t1 from its wheel forces `p`.
pub(crate) fn note_contact(
    loss_open: &mut [Option<f64>],
    p: &[f64],
    t1: f64,
    out: &mut Vec<ContactLoss>,
) {
    for (wi, open) in loss_open.iter_mut().enumerate() {
        match (p[wi] == 0.0, *open) {
            (true, None) => *open = Some(t1),
            (false, Some(t0)) => {
                out.push(ContactLoss {
                    wheel: wi,
                    t_start: t0,
                    t_end: Some(t1),
                });
                *open = None;
            }
            _ => {}
        }
    }
}

/// A finished run: its open contact-loss periods closed at the end, and refused when an
/// index overflowed.
pub(crate) fn finish(loss_open: &[Option<f64>], mut r: RunResult) -> Result<RunResult> {
    for (wi, open) in loss_open.iter().enumerate() {
        if let Some(t0) = open {
            r.contact_loss.push(ContactLoss {
                wheel: wi,
                t_start: *t0,
                t_end: None,
            });
        }
    }
    // A finite state can still give an overflowing index (an acceleration of 1e308 squared
    // in an r.m.s.): never return it as a result.
    if let Some((name, v)) = r.metrics().into_iter().find(|(_, v)| !v.is_finite()) {
        return Err(VtbError::Solver(format!(
            "the index {name} = {v} is not finite at the end of the run (step {}): an \
             overflow, most likely from parameters of extreme magnitude",
            r.n_steps
        )));
    }
    Ok(r)
}
