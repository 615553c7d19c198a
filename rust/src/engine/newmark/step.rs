//! The Newmark engine's step as named phases, its side of the coupled loop: loads, ports (the
//! rail's shape vectors at the wheels and their free displacement), the contact compliance,
//! the update with the wheel forces, and the records. Each phase works on all lanes.

use super::NewmarkSide;
use crate::engine::coupled::{StructureSide, Vehicles};
use crate::engine::integrator::GW;
use crate::error::{Result, VtbError};
use crate::outputs::RunResult;

impl<const W: usize> NewmarkSide<'_, W> {
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

    /// Ports: the structure's step begun with the known forces, and the rail's shape vectors
    /// at the wheels (with the FE–SEA force terms) prepared; the rail's free displacement at
    /// every wheel.
    fn ports(&mut self, t1: f64, veh: &Vehicles<W>) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        let (nw, wpc) = (veh.n_wheels(), veh.wpc);
        self.track.begin_step(&self.f_prev, &self.f_next);
        if let Some(rc) = self.correction.as_mut() {
            rc.set_rows(veh.x0.iter().copied(), v, t1);
        }
        for ci in 0..veh.cars.len() {
            let ports = &mut self.track_ports[ci];
            // Padded to the port width with the last wheel (the padding is not read).
            let xs: [f64; GW] = std::array::from_fn(|w| veh.x0[ci * wpc + w.min(wpc - 1)] + v * t1);
            let terms = self.correction.as_ref().map(|rc| rc.fs.load_terms_at(xs));
            for w in 0..wpc {
                let a = veh.patch[ci * wpc + w];
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
            let rail = self.track.free_port_disp(ports);
            for (lane, r) in rail.iter().enumerate() {
                for w in 0..wpc {
                    self.rail_free[lane * nw + ci * wpc + w] = r[w];
                }
            }
        }
    }
}

impl<const W: usize> NewmarkSide<'_, W> {
    /// Substructured: each wheel's residual filter at its position this step, and the
    /// filtered residual under no new force added to the rail's free displacement there.
    fn residual_filters(&mut self, t1: f64, veh: &Vehicles<W>, p: &[f64]) -> Result<()> {
        let Some(res) = self.residual.as_mut() else {
            return Ok(());
        };
        let (st, cfg) = (&self.model.structure, &self.model.cfg);
        let nw = veh.n_wheels();
        for w in 0..nw {
            let x = veh.x0[w] + cfg.speed * t1;
            let at = || veh.wheel_name(w, x);
            res.begin(w, st.wheel_residual(x, veh.patch[w]), cfg.solver.dt, p, at)?;
            for lane in 0..W {
                self.rail_free[lane * nw + w] += res.free(lane, w);
            }
        }
        Ok(())
    }
}

impl<const W: usize> StructureSide<W> for NewmarkSide<'_, W> {
    fn start(&mut self, v: &Vehicles<W>, failed: &mut [Option<VtbError>]) -> Result<Vec<f64>> {
        let f0 = self.initial_load(v);
        self.f_prev = self.track.to_stepper(&f0);
        // Each lane's state from its own matrices (its dampers' parameters), as in a single
        // run; lanes with the model's own parameters share them.
        let nw = v.n_wheels();
        let mut rail = vec![0.0; W * nw];
        let mut own_state = None;
        for j in 0..W {
            if let Some(e) = self.setup[j].take() {
                failed[j] = Some(e);
                continue;
            }
            match self.lane_state(j, &f0, v, &mut own_state) {
                Ok(r) => rail[j * nw..(j + 1) * nw].copy_from_slice(&r),
                Err(e) => failed[j] = Some(e),
            }
        }
        Ok(rail)
    }

    fn begin_step(
        &mut self,
        _step: usize,
        t1: f64,
        v: &Vehicles<W>,
        p: &[f64],
        _live: &[bool; W],
    ) -> Option<VtbError> {
        self.t1 = t1;
        self.loads(t1);
        self.ports(t1, v);
        self.residual_filters(t1, v, p).err()
    }

    fn free_rail(&self, lane: usize, wheel: usize) -> f64 {
        self.rail_free[lane * (self.rail_free.len() / W) + wheel]
    }

    /// A = the rail's port compliance plus the cars' own, each wheel's element flexibility
    /// and, substructured, its residual filter's step compliance.
    fn compliance(
        &self,
        veh: &Vehicles<W>,
        amat: &mut [f64],
        car: &dyn Fn(usize, usize) -> Option<f64>,
    ) {
        let (st, v) = (&self.model.structure, self.model.cfg.speed);
        let (ncars, wpc, nw) = (veh.cars.len(), veh.wpc, veh.n_wheels());
        let t1 = self.t1;
        for ci in 0..ncars {
            for cj in 0..ncars {
                let g = self
                    .track
                    .port_compliance(&self.track_ports[ci], &self.track_ports[cj]);
                for (lane, gl) in g.iter().enumerate() {
                    let a = &mut amat[lane * nw * nw..(lane + 1) * nw * nw];
                    for r in 0..wpc {
                        for s in 0..wpc {
                            let (wi, vi) = (ci * wpc + r, cj * wpc + s);
                            a[wi * nw + vi] = gl[r][s] + car(wi, vi).unwrap_or(0.0);
                        }
                    }
                }
            }
            // The wheel also deflects the rail within its element (nodes fixed): in series
            // with the contact, so the static wheel–rail stiffness does not depend on where in
            // an element the wheel is (no element-passing excitation from it). Wheels are
            // more than an element apart (and, substructured, the residual between two
            // wheels is left out).
            for w in 0..wpc {
                let wi = ci * wpc + w;
                let mut f = match self.element_flexibility {
                    true => st.element_flexibility(veh.x0[wi] + v * t1, veh.patch[wi]),
                    false => 0.0,
                };
                if let Some(res) = &self.residual {
                    f += res.gain(wi);
                }
                for lane in 0..W {
                    amat[lane * nw * nw + wi * nw + wi] += f;
                }
            }
        }
    }

    /// Update: the wheel forces applied to the structure, its step finished, and F_{n+1}
    /// (moving forces plus wheel forces) kept as the next step's F_n.
    fn end_step(&mut self, v: &Vehicles<W>, p: &[f64], _live: &[bool; W]) {
        let (nw, wpc) = (v.n_wheels(), v.wpc);
        for ci in 0..v.cars.len() {
            self.track
                .add_port_forces(&self.track_ports[ci], &v.car_forces(ci, p));
        }
        self.track.end_step();
        if let Some(res) = self.residual.as_mut() {
            res.end(p);
        }
        std::mem::swap(&mut self.f_prev, &mut self.f_next);
        for (ci, ports) in self.track_ports.iter().enumerate() {
            for lane in 0..W {
                for w in 0..wpc {
                    ports.force_vec(w).add_to_lane::<W>(
                        &mut self.f_prev,
                        lane,
                        p[lane * nw + ci * wpc + w],
                    );
                }
            }
        }
        if let Some(rc) = self.correction.as_mut() {
            for lane in 0..W {
                rc.g_prev[lane] = rc.g_next[lane];
                for (wi, r) in rc.wheel_r.iter().enumerate() {
                    for g in 0..4 {
                        rc.g_prev[lane][g] += p[lane * nw + wi] * r[g];
                    }
                }
            }
        }
    }

    fn record(&mut self, res: &mut [RunResult], step: usize, p: &[f64], live: &[bool; W]) {
        let no = self.n_layer_obs;
        let nw = self.rail_free.len() / W;
        for (lane, r) in res.iter_mut().enumerate() {
            if !live[lane] {
                continue;
            }
            for j in 0..no {
                let (u, _, a) = self.track.observed(j, lane);
                r.disp[step * no + j] = u;
                r.acc[step * no + j] = a;
            }
            if let Some(rc) = &self.correction {
                // Rail points come first: add the local modes' static deflection.
                let pl = &p[lane * nw..(lane + 1) * nw];
                for j in 0..rc.obs.len() {
                    r.disp[step * no + j] += rc.observed_deflection(j, pl);
                }
            }
            let np = self.pads.len();
            for (j, pad) in self.pads.iter().enumerate() {
                let (mut uu, vu, _) = self.track.observed(no + 2 * j, lane);
                let (ul, vl, _) = self.track.observed(no + 2 * j + 1, lane);
                if let Some(rc) = self.correction.as_ref().filter(|rc| !rc.pad_obs.is_empty()) {
                    uu += rc.pad_deflection(j, &p[lane * nw..(lane + 1) * nw]);
                }
                r.pad_force[step * np + j] = pad.force(uu - ul, vu - vl);
            }
            let (nm, first) = (self.n_moments, no + 2 * np);
            for j in 0..nm {
                r.moment[step * nm + j] = self.track.observed(first + j, lane).0;
            }
        }
    }

    fn fail(&mut self, j: usize) {
        self.track.clear_lane(j);
        for x in self.f_prev.iter_mut().skip(j).step_by(W) {
            *x = 0.0;
        }
        if let Some(rc) = self.correction.as_mut() {
            rc.g_prev[j] = [0.0; 4];
        }
        if let Some(res) = self.residual.as_mut() {
            res.hold(j, &vec![0.0; res.wheels()]);
        }
    }

    fn non_finite(&self, lane: usize) -> Option<&'static str> {
        (!self.track.lane_finite(lane)).then_some("the structure's displacements")
    }
}
