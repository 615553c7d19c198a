//! The coupled time step of the finite-element / modal engine as named phases: loads, ports,
//! contact, update, record. `run_lanes` calls them in that order for every step; each phase
//! works on all lanes of the lockstep group.

use super::Simulation;
use crate::engine::coupled::{finish, note_contact};
use crate::engine::integrator::GW;
use crate::engine::{CANCEL_POLL, Control, FINITE_POLL, poll};
use crate::error::{Result, VtbError};
use crate::outputs::RunResult;

impl<'m, const W: usize> Simulation<'m, W> {
    /// Runs all steps of every lane. The outer error is shared by all lanes (setup, or
    /// cancellation: `cancel` is polled every `CANCEL_POLL` steps); the inner ones are each
    /// lane's own.
    pub fn run_lanes(mut self, cancel: Option<&Control>) -> Result<Vec<Result<RunResult>>> {
        self.initial_state()?;
        let (cfg, st) = (&self.model.cfg, &self.model.structure);
        let nw = self.p.len() / W;
        let mut res: Vec<RunResult> = (0..W)
            .map(|_| {
                RunResult::new(
                    cfg,
                    st,
                    self.n_steps,
                    &self.points,
                    self.cars.len(),
                    nw,
                    self.record,
                )
            })
            .collect();
        self.record_step(&mut res, 0);
        let dt = cfg.solver.dt;
        for step in 0..self.n_steps {
            if step % CANCEL_POLL == 0 && poll(cancel, step, self.n_steps) {
                return Err(VtbError::Cancelled);
            }
            if step % FINITE_POLL == 0 {
                self.check_finite(step);
            }
            if self.lanes.iter().all(|l| l.error.is_some()) {
                break;
            }
            let t1 = (step + 1) as f64 * dt;
            self.loads(t1);
            self.ports(t1);
            self.contact(step, t1);
            self.update();
            self.record(&mut res, step, t1);
        }
        self.check_finite(self.n_steps);
        Ok(self
            .lanes
            .into_iter()
            .zip(res)
            .map(|(lane, r)| match lane.error {
                Some(e) => Err(e),
                None => finish(&lane.loss_open, r),
            })
            .collect())
    }

    /// Loads: F_{n+1} of the moving forces and of the FE–SEA correction's rate terms.
    fn loads(&mut self, t1: f64) {
        let v = self.model.cfg.speed;
        self.f_next.fill(0.0);
        if let Some(rc) = self.correction.as_mut() {
            for lane in 0..W {
                rc.g_next[lane] = [0.0; 4];
                for g in 0..4 {
                    self.f_next[rc.idx[g] * W + lane] -= rc.rate * rc.g_prev[lane][g];
                }
            }
        }
        for mi in 0..self.movers.len() {
            let m = self.movers[mi];
            self.add_load(m.layer, m.x0 + v * t1, m.magnitude);
        }
    }

    /// Ports: the structure's and the cars' steps begun with the known forces, and the rail's
    /// shape vectors at the wheels (with the FE–SEA force terms) prepared.
    fn ports(&mut self, t1: f64) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        self.track.begin_step(&self.f_prev, &self.f_next);
        if let Some(rc) = self.correction.as_mut() {
            rc.set_rows(
                self.cars
                    .iter()
                    .flat_map(|c| c.car.wheel_x0.iter().copied()),
                v,
                t1,
            );
        }
        for (ci, c) in self.cars.iter_mut().enumerate() {
            let ports = &mut self.track_ports[ci];
            let wpc = self.wpc;
            // Padded to the port width with the last wheel (the padding is not read).
            let xs: [f64; GW] = std::array::from_fn(|w| c.car.wheel_x0[w.min(wpc - 1)] + v * t1);
            let terms = self.correction.as_ref().map(|rc| rc.fs.load_terms_at(xs));
            for w in 0..wpc {
                let a = self.patch[ci * wpc + w];
                st.wheel_shape_into(xs[w], a, &mut self.wheel_shape);
                self.track
                    .vector_into(&self.wheel_shape, &mut ports.vecs[w]);
                if let (Some(rc), Some(force), Some(t)) =
                    (self.correction.as_mut(), ports.force.as_mut(), terms)
                {
                    let (f, r) = rc.with_rate(t[w]);
                    let fv = &mut force[w];
                    fv.copy_from(&ports.vecs[w]);
                    // A modal rail's shape vector covers all its DOFs, g1..g4 first.
                    for g in 0..4 {
                        fv.val[rc.fs.dofs[g] - self.wheel_shape.start] += f[g];
                    }
                    rc.wheel_r[ci * wpc + w] = r;
                }
            }
            self.track.prepare_ports(ports);
            c.nm.begin_step(&c.f_prev, &c.gravity);
        }
    }

    /// Contact: δ = δ_free − A·P with A = rails·(car compliance) + (rail compliance), and each
    /// lane's Hertz forces P by Newton.
    fn contact(&mut self, step: usize, t1: f64) {
        let (st, cfg) = (&self.model.structure, &self.model.cfg);
        let v = cfg.speed;
        let share = cfg.irregularity_share(t1);
        let nw = self.p.len() / W;
        let (ncars, wpc) = (self.cars.len(), self.wpc);
        let (amat, delta_free) = (&mut self.amat, &mut self.delta_free);
        for ci in 0..ncars {
            let c = &self.cars[ci];
            let rail = self.track.free_port_disp(&self.track_ports[ci]);
            let wheel = c.nm.free_port_disp(&c.ports);
            for (lane, l) in self.lanes.iter().enumerate() {
                for w in 0..wpc {
                    let x = c.car.wheel_x0[w] + v * t1;
                    delta_free[lane * nw + ci * wpc + w] =
                        wheel[lane][w] - rail[lane][w] - share * l.profile.under(ci * wpc + w, x);
                }
            }
            for cj in 0..ncars {
                let g = self
                    .track
                    .port_compliance(&self.track_ports[ci], &self.track_ports[cj]);
                for (lane, gl) in g.iter().enumerate() {
                    let a = &mut amat[lane * nw * nw..(lane + 1) * nw * nw];
                    for r in 0..wpc {
                        for s in 0..wpc {
                            let own = if ci == cj {
                                c.car.rails * c.compliance[r][s]
                            } else {
                                0.0
                            };
                            a[(ci * wpc + r) * nw + cj * wpc + s] = gl[r][s] + own;
                        }
                    }
                }
            }
            if self.element_flexibility {
                // The wheel also deflects the rail within its element (nodes fixed): in
                // series with the contact, so the static wheel–rail stiffness does not
                // depend on where in an element the wheel is (no element-passing
                // excitation from it). Wheels are more than an element apart.
                for w in 0..wpc {
                    let wi = ci * wpc + w;
                    let f = st.wheel_flexibility(c.car.wheel_x0[w] + v * t1, self.patch[wi]);
                    for lane in 0..W {
                        amat[lane * nw * nw + wi * nw + wi] += f;
                    }
                }
            }
        }
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

    /// Update: the wheel forces applied to the structure and the cars, both steps finished,
    /// and F_{n+1} (moving forces plus wheel forces) kept as the next step's F_n.
    fn update(&mut self) {
        let nw = self.p.len() / W;
        for ci in 0..self.cars.len() {
            let p = self.car_forces(ci);
            let c = &mut self.cars[ci];
            self.track.add_port_forces(&self.track_ports[ci], &p);
            let wheel: [[f64; GW]; W] = p.map(|pl| pl.map(|pw| -c.car.rails * pw));
            c.nm.add_port_forces(&c.ports, &wheel);
            c.nm.end_step();
            c.set_force(&p);
        }
        self.track.end_step();
        std::mem::swap(&mut self.f_prev, &mut self.f_next);
        for (ci, ports) in self.track_ports.iter().enumerate() {
            for lane in 0..W {
                for w in 0..self.wpc {
                    ports.force_vec(w).add_to_lane::<W>(
                        &mut self.f_prev,
                        lane,
                        self.p[lane * nw + ci * self.wpc + w],
                    );
                }
            }
        }
        if let Some(rc) = self.correction.as_mut() {
            for lane in 0..W {
                rc.g_prev[lane] = rc.g_next[lane];
                for (wi, r) in rc.wheel_r.iter().enumerate() {
                    for g in 0..4 {
                        rc.g_prev[lane][g] += self.p[lane * nw + wi] * r[g];
                    }
                }
            }
        }
    }

    /// Record: contact-loss events and the step's outputs of every lane.
    fn record(&mut self, res: &mut [RunResult], step: usize, t1: f64) {
        let nw = self.p.len() / W;
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            if lane.error.is_none() {
                note_contact(
                    &mut lane.loss_open,
                    &self.p[j * nw..(j + 1) * nw],
                    t1,
                    &mut res[j].contact_loss,
                );
            }
        }
        self.record_step(res, step + 1);
    }
}
