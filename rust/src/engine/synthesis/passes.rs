//! The synthesis engine's step as named phases, its side of the coupled loop: the moving
//! forces ahead, the wheels placed, the wheel pass (shared by the lanes), the dampers' terms,
//! then — after the shared contact — the ports' forces, the update pass and the readouts.

use super::kernels::{self, Update, WheelPass};
use super::records::records;
use super::run::{READOUTS, SynthesisSide, dot, near, shape_gain};
use super::step::C;
use crate::config::InitialState;
use crate::engine::coupled::residual::{Filter, FilterStep};
use crate::engine::coupled::{StructureSide, Vehicles};
use crate::error::{Result, VtbError};
use crate::model::basis::Shape;
use crate::outputs::RunResult;

impl<const W: usize> SynthesisSide<'_, W> {
    fn dt(&self) -> f64 {
        self.model.cfg.solver.dt
    }

    fn nw(&self) -> usize {
        self.wheel_shapes.len()
    }

    /// The moving forces' shapes (and on the rail their slopes) at t into `shapes` and their
    /// modal force Σ P·ψᵀs into `gk`.
    fn movers_at(&mut self, t: f64, ahead: bool) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        let (gk, shapes, slopes) = if ahead {
            (
                &mut self.gk_ahead,
                &mut self.shapes_ahead,
                &mut self.slopes_ahead,
            )
        } else {
            (&mut self.gk_now, &mut self.shapes_now, &mut self.slopes_now)
        };
        for ((mv, sh), sl) in self
            .movers
            .iter()
            .zip(shapes.iter_mut())
            .zip(slopes.iter_mut())
        {
            let x = mv.x0 + v * t;
            st.shape_into(mv.layer, x, sh);
            if mv.layer == 0 {
                st.slope_into(0, x, sl);
            }
        }
        kernels::load_movers(self.red, shapes, &self.mover_magnitudes, gk);
    }

    /// The rail's residual displacement at s under the rail's moving forces (now). A force
    /// of shape s_m(x(t)) moving at v loads the truncated modes with g = P·s_m, whose rate
    /// ġ = P·v·s_m′ drives their damping term R₁ (docs/synthesis.md, "Moving loads"):
    /// P·(R₀s_m + v·R₁s_m′). The next term, R₂·g̈, changed the rail's acceleration by under
    /// 0.03 % of its r.m.s. on the converged track (measured; docs/synthesis.md), and is left out.
    fn mover_residual(&self, s: &Shape) -> f64 {
        let v = self.model.cfg.speed;
        self.movers
            .iter()
            .zip(self.shapes_now.iter().zip(&self.slopes_now))
            .filter(|(mv, _)| mv.layer == 0)
            .map(|(mv, (sm, sl))| {
                mv.magnitude * (self.red.residual(s, sm) + v * self.red.residual_rate(s, sl))
            })
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
    fn place_loads(&mut self, t: f64, veh: &Vehicles<W>) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        for (w, s) in self.wheel_shapes.iter_mut().enumerate() {
            st.wheel_shape_into(veh.x0[w] + v * t, veh.patch[w], s);
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

    /// Q̃₁ = e·Q₀ + a0·g₀ + a1·g_known(t₁) in every lane, and the dampers' free displacement
    /// under it.
    fn first_free_state(&mut self, q0: &super::kernels::CVec, g0: &super::kernels::CVec) {
        let nw = self.nw();
        self.movers_at(self.dt(), true);
        let coef = &self.coef;
        for j in 0..self.red.stride {
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
    }

    /// The wheel pass (shared): ψᵀs, step compliances, free rail displacements, the wheels'
    /// element flexibility, and their step compliance with the dampers. A wheel whose residual
    /// has no stable filter fails every lane.
    fn wheel_pass(&mut self, t1: f64, veh: &Vehicles<W>, p: &[f64]) -> Option<VtbError> {
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
        let dt = cfg.solver.dt;
        let mut failed = None;
        for w in 0..nw {
            let s = &self.wheel_shapes[w];
            let x = veh.x0[w] + cfg.speed * t1;
            let at = || veh.wheel_name(w, x);
            let (modal, moments) = if self.active[w] {
                match red.load_moments(s, at) {
                    Ok(r) => (self.rail_step.quadratic(s), r),
                    Err(e) => {
                        failed = Some(e);
                        (self.rail_step.quadratic(s), [0.0; 3])
                    }
                }
            } else {
                (0.0, [0.0; 3])
            };
            self.self_res[w] = moments[0];
            let filter = Filter::from_moments(moments, at);
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
                self.g_free[i] = step.advance(self.g_state[i], p[i], 0.0);
            }
            self.diag[w] = modal + moments[0] * self.g_gain[w][0];
            self.rail_free[w] = self.rail_acc[w].sum();
            self.element_flex[w] = if cfg.discretisation.element_flexibility {
                st.element_flexibility(x, veh.patch[w])
            } else {
                0.0
            };
        }
        // Wheels off the rail (inactive) have no compliance with any other. The modes' step
        // compliance reaches the near wheels; the residual, static, every wheel within its
        // stored reach (as at the dampers and the observers).
        let a1 = [&self.coef.a1[0][..], &self.coef.a1[1][..]];
        for wi in 0..nw {
            let mut scaled = false;
            for vi in wi + 1..nw {
                let (a, b) = (&self.wheel_shapes[wi], &self.wheel_shapes[vi]);
                let both = self.active[wi] && self.active[vi];
                self.near_pairs[wi * nw + vi] = if both && near(red, a, b) {
                    if !scaled {
                        self.scaled_port.set_mul(a1, self.ports[wi].parts());
                        scaled = true;
                    }
                    dot(&self.scaled_port, &self.ports[vi])
                } else {
                    0.0
                };
                self.near_res[wi * nw + vi] = if both { red.residual(a, b) } else { 0.0 };
            }
        }
        for (e, dp) in self.dampers.iter().enumerate() {
            for (w, sw) in self.wheel_shapes.iter().enumerate() {
                self.gdw[e * nw + w] = shape_gain(sw, dp.gain_start, &dp.gain);
                self.gdw_res[e * nw + w] = red.residual(&dp.upper, sw);
            }
        }
        failed
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

    /// Each live lane's dampers this step: their force F = F0 + T·P in the wheel forces P.
    fn damper_terms(&mut self, live: &[bool; W]) {
        let dt = self.dt();
        let (nw, nd) = (self.nw(), self.dampers.len());
        if nd == 0 {
            return;
        }
        for c in (0..W).filter(|&c| live[c]) {
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

    /// The ports' forces of every lane once the wheels' are known, and the dampers' states.
    fn forces(&mut self, p: &[f64], live: &[bool; W]) {
        let dt = self.dt();
        let (nw, nd) = (self.nw(), self.dampers.len());
        for c in 0..W {
            for w in 0..nw {
                let i = c * nw + w;
                self.forces[w][c] = p[i];
                let (free, gain) = (self.g_free[i], self.g_gain[w]);
                self.g_state[i] = [
                    gain[0].mul_add(p[i], free[0]),
                    gain[1].mul_add(p[i], free[1]),
                ];
                self.g_now[i] = self.g_state[i][0];
            }
            if !live[c] {
                for e in 0..nd {
                    self.forces[nw + e][c] = 0.0;
                }
                continue;
            }
            for e in 0..nd {
                let f: f64 = self.f0[c * nd + e]
                    + (0..nw)
                        .map(|w| self.t_mat[(c * nd + e) * nw + w] * p[c * nw + w])
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
}

impl<const W: usize> StructureSide<W> for SynthesisSide<'_, W> {
    /// Static (or rest) state at t = 0: the modes, the residual filters, the dampers, the
    /// first free state and readouts.
    fn start(&mut self, v: &Vehicles<W>, failed: &mut [Option<VtbError>]) -> Result<Vec<f64>> {
        let cfg = &self.model.cfg;
        let red = self.red;
        let n = red.stride;
        let nw = self.nw();
        for (c, lane) in self.lanes.iter_mut().enumerate() {
            failed[c] = lane.setup.take();
        }
        let rest = cfg.solver.initial_state == InitialState::Rest;
        self.movers_at(0.0, false);
        self.place_loads(0.0, v);
        let mut g0 = self.gk_now.clone();
        for w in 0..nw {
            kernels::project(red, &self.wheel_shapes[w], &mut self.ports[w]);
            for j in 0..n {
                g0.re[j] = v.loads[w].mul_add(self.ports[w].re[j], g0.re[j]);
                g0.im[j] = v.loads[w].mul_add(self.ports[w].im[j], g0.im[j]);
            }
        }
        // Q₀: static (λQ + w·g = 0) or at rest; the same in every lane.
        let mut q0 = super::kernels::CVec::zeros(n);
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
                self.g_state[c * nw + w] = [share * v.loads[w], 0.0];
                self.g_now[c * nw + w] = share * v.loads[w];
            }
        }
        let static_residual =
            |s: &Shape| share * (self.wheel_residual(s, &v.loads) + self.mover_residual(s));
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
        self.first_free_state(&q0, &g0);
        // The first readouts: d, e of Q₀, the loads' direct terms.
        for (o, obs) in self.observers.iter().enumerate() {
            for k in 0..2 {
                self.de[2 * o + k] = [dot(&obs.psi[k], &q0); W];
            }
        }
        Ok(rail0.repeat(W))
    }

    fn begin_step(
        &mut self,
        _step: usize,
        t1: f64,
        v: &Vehicles<W>,
        p: &[f64],
        live: &[bool; W],
    ) -> Option<VtbError> {
        let dt = self.dt();
        if !self.movers.is_empty() {
            std::mem::swap(&mut self.shapes_now, &mut self.shapes_ahead);
            std::mem::swap(&mut self.slopes_now, &mut self.slopes_ahead);
            std::mem::swap(&mut self.gk_now, &mut self.gk_ahead);
            self.movers_at(t1 + dt, true);
        }
        self.place_loads(t1, v);
        let failed = self.wheel_pass(t1, v, p);
        self.damper_terms(live);
        failed
    }

    /// The rail at the wheel: the modes' free displacement, the residual under the moving
    /// forces and the wheels' filtered forces, less the dampers' forces through the static
    /// residual (they have no filter).
    fn free_rail(&self, c: usize, wi: usize) -> f64 {
        let (nw, nd) = (self.nw(), self.dampers.len());
        let mut rail = self.rail_free[wi][c]
            + self.mover_residual(&self.wheel_shapes[wi])
            + self.wheel_residual_free(wi, c);
        for e in 0..nd {
            rail -= (self.gdw[e * nw + wi] + self.gdw_res[e * nw + wi]) * self.f0[c * nd + e];
        }
        rail
    }

    /// Row wi: the displacement at wheel wi per unit force of wheel vi, whose residual share
    /// passes vi's filter (so A is not symmetric), less the dampers' response to it.
    fn compliance(
        &self,
        _v: &Vehicles<W>,
        amat: &mut [f64],
        car: &dyn Fn(usize, usize) -> Option<f64>,
    ) {
        let (nw, nd) = (self.nw(), self.dampers.len());
        for c in 0..W {
            let a = &mut amat[c * nw * nw..(c + 1) * nw * nw];
            let t_mat = &self.t_mat[c * nd * nw..(c + 1) * nd * nw];
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
                    if let Some(own) = car(wi, vi) {
                        x += own;
                    }
                    a[wi * nw + vi] = x;
                }
            }
        }
    }

    fn end_step(&mut self, _v: &Vehicles<W>, p: &[f64], live: &[bool; W]) {
        self.forces(p, live);
        self.update();
    }

    /// The readouts of every live lane at `step` (the force's direct terms from the ports'
    /// forces this step) and the rail residual.
    fn record(&mut self, _res: &mut [RunResult], step: usize, p: &[f64], live: &[bool; W]) {
        let (nw, no) = (self.nw(), self.observers.len());
        for c in (0..W).filter(|&c| live[c]) {
            let pl = &p[c * nw..(c + 1) * nw];
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
                    self.lanes[c].residual[step * no + o] =
                        self.wheel_residual(s, gl) + self.mover_residual(s);
                }
            }
        }
    }

    fn fail(&mut self, c: usize) {
        let nw = self.nw();
        self.q_free[c].clear();
        self.g_state[c * nw..(c + 1) * nw].fill([0.0; 2]);
        self.g_now[c * nw..(c + 1) * nw].fill(0.0);
    }

    fn non_finite(&self, c: usize) -> Option<&'static str> {
        (!self.q_free[c].is_finite()).then_some("the modal coordinates")
    }

    /// The lane's records made of its readouts.
    fn finish(&mut self, c: usize, r: &mut RunResult) {
        let (no, dt) = (self.observers.len(), self.dt());
        let lane = &self.lanes[c];
        let observers = (no, no - 2 * self.pads.len() - r.n_moments);
        records(r, &lane.readouts, &lane.residual, observers, &self.pads, dt);
    }
}
