//! One coupled run (track + cars + contact), and many runs in parallel.

use crate::basis::Shape;
use crate::config::{Config, InitialState, Profile};
use crate::contact::{ContactSolver, compression};
use crate::error::{Result, VtbError};
use crate::fesea::FeSea;
use crate::integrator::{GW, Newmark, PortBlock};
use crate::model::Model;
use crate::results::{ContactLoss, RunResult};
use crate::sparse::{Assembler, CsrMatrix, Ldlt};
use crate::vehicle::{Car, N_DOF, N_WHEELS, WHEEL0};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Validates, assembles and integrates one configuration.
pub fn simulate(cfg: &Config, profile: &Profile, cancel: Option<&AtomicBool>) -> Result<RunResult> {
    let model = Model::new(cfg.clone(), profile.clone())?;
    Simulation::new(&model)?.run(cancel)
}

/// One job of a batch: a configuration and its (possibly shared) irregularity profile.
#[derive(Clone, Debug)]
pub struct Job {
    pub config: Config,
    pub profile: Arc<Profile>,
}

/// Runs the jobs in parallel on the current rayon pool and returns each job's metrics or its
/// error, in input order. `done` counts finished jobs (for progress reporting).
pub fn run_batch(
    jobs: &[Job],
    cancel: Option<&AtomicBool>,
    done: Option<&AtomicUsize>,
) -> Vec<Result<BTreeMap<String, f64>>> {
    jobs.par_iter()
        .map(|job| {
            let r = simulate(&job.config, &job.profile, cancel).map(|res| res.metrics());
            if let Some(d) = done {
                d.fetch_add(1, Ordering::Relaxed);
            }
            r
        })
        .collect()
}

/// A constant force moving with the common speed.
#[derive(Clone, Copy, Debug)]
struct Mover {
    layer: usize,
    x0: f64,
    magnitude: f64,
}

/// A car's own Newmark stepper; its contact ports are the wheelset DOFs.
struct CarRun {
    car: Car,
    nm: Newmark,
    m: CsrMatrix,
    k: CsrMatrix,
    ports: PortBlock,
    /// Wheelset compliance over one step for unit port forces (constant).
    compliance: [[f64; GW]; GW],
    gravity: Vec<f64>,
    f_prev: Vec<f64>,
    z0: Vec<f64>,
}

impl CarRun {
    fn new(car: &Car, dt: f64, g: f64) -> Result<Self> {
        let dense = |m: &[[f64; N_DOF]; N_DOF]| {
            let mut a = Assembler::new(N_DOF);
            for i in 0..N_DOF {
                for j in 0..N_DOF {
                    a.add(i, j, m[i][j]);
                }
            }
            a.finish()
        };
        let mut am = Assembler::new(N_DOF);
        for i in 0..N_DOF {
            am.add(i, i, car.mass[i]);
        }
        let (m, c, k) = (am.finish(), dense(&car.c), dense(&car.k));
        let mut nm = Newmark::new(&m, &c, &k, dt, &[], 1, None, &[])?;
        for i in 0..N_DOF {
            nm.observe(&Shape {
                start: i,
                values: vec![1.0],
            });
        }
        let mut ports = PortBlock::new(N_DOF);
        for w in 0..N_WHEELS {
            ports.vecs[w] = nm.vector(&Shape {
                start: WHEEL0 + w,
                values: vec![1.0],
            });
        }
        nm.prepare_ports(&mut ports);
        let compliance = nm.port_compliance(&ports, &ports);
        let gravity = nm.to_stepper(&car.gravity(g));
        Ok(Self {
            car: car.clone(),
            nm,
            m,
            k,
            ports,
            compliance,
            f_prev: gravity.clone(),
            gravity,
            z0: vec![0.0; N_DOF],
        })
    }

    /// Gravity minus rails·P on the wheelsets (stepper coordinates) into `f_prev`.
    fn set_force(&mut self, p: &[f64]) {
        self.f_prev.clone_from(&self.gravity);
        for w in 0..N_WHEELS {
            self.ports.vecs[w].add_to(&mut self.f_prev, -self.car.rails * p[w]);
        }
    }
}

/// The FE–SEA force terms of the hybrid model on the rail's cubic DOFs g1..g4 (model.md §6):
/// a load w at x adds w·a(x) + d/dt(w·b(x)) (`FeSea::load_terms`). The derivative is the
/// backward difference over the step, F_{n+1} ∋ (H_{n+1} − H_n)/Δt with H = Σ_loads w·b(x), so
/// every force sample is single-valued (Newmark's acceleration recursion stays consistent)
/// and the step integral of the term is exact up to a half-step lag.
struct RailCorrection<'m> {
    fs: &'m FeSea,
    /// Stepper indices of g1..g4.
    idx: [usize; 4],
    /// 1/Δt.
    rate: f64,
    /// H_n, and H_{n+1} from the known loads of the step.
    g_prev: [f64; 4],
    g_next: [f64; 4],
    /// b(x) at each wheel this step.
    wheel_r: Vec<[f64; 4]>,
    /// Static flexibility of the local modes (mode-acceleration recovery): 1/k_j, and
    /// s_j(x_o)/k_j at each rail observation point.
    inv_k: Vec<f64>,
    obs: Vec<Vec<f64>>,
    /// s_j at each wheel, then at each moving force on the rail, this step (row-major).
    sines: Vec<f64>,
    /// (x0, magnitude) of the moving forces on the rail.
    movers: Vec<(f64, f64)>,
}

impl RailCorrection<'_> {
    /// The corrections of the g entries of F_{n+1} for a unit load at x: (a + b/Δt, b).
    fn unit_load(&self, x: f64) -> ([f64; 4], [f64; 4]) {
        self.with_rate(self.fs.load_terms(x))
    }

    fn with_rate(&self, (a, b): ([f64; 4], [f64; 4])) -> ([f64; 4], [f64; 4]) {
        (std::array::from_fn(|g| a[g] + self.rate * b[g]), b)
    }

    fn row(&self, r: usize) -> &[f64] {
        let nl = self.inv_k.len();
        &self.sines[r * nl..(r + 1) * nl]
    }

    /// Sine rows at time t: the wheels (x0 + v·t), then the rail's moving forces.
    fn set_rows(&mut self, wheel_x0: impl Iterator<Item = f64>, v: f64, t: f64) {
        let nl = self.inv_k.len();
        let Self {
            fs, sines, movers, ..
        } = self;
        for (r, x) in wheel_x0.chain(movers.iter().map(|m| m.0)).enumerate() {
            fs.local_sines_into(x + v * t, &mut sines[r * nl..(r + 1) * nl]);
        }
    }

    /// The local modes' static deflection at rail observation point `j` under the wheel
    /// forces `p` and the rail's moving forces (output only: in the contact this static
    /// flexibility would replace the local modes' mass-like behaviour at ω_r, docs/fesea.md).
    fn observed_deflection(&self, j: usize, p: &[f64]) -> f64 {
        let loads = p.iter().copied().chain(self.movers.iter().map(|m| m.1));
        loads
            .enumerate()
            .map(|(r, w)| w * dot(&self.obs[j], self.row(r)))
            .sum()
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The state of one coupled run.
pub struct Simulation<'m> {
    model: &'m Model,
    track: Newmark,
    f_prev: Vec<f64>,
    f_next: Vec<f64>,
    movers: Vec<Mover>,
    cars: Vec<CarRun>,
    /// Rail shape vectors at the wheels, one block per car.
    track_ports: Vec<PortBlock>,
    /// Add the rail elements' local flexibility under the wheels (finite-element rails).
    element_flexibility: bool,
    contact: ContactSolver,
    /// Contact force of each wheel on the modelled rail (N).
    p: Vec<f64>,
    shape: Shape,
    scratch: crate::integrator::SVec,
    n_steps: usize,
    correction: Option<RailCorrection<'m>>,
}

impl<'m> Simulation<'m> {
    pub fn new(model: &'m Model) -> Result<Self> {
        let cfg = &model.cfg;
        let st = &model.structure;
        let dt = cfg.solver.dt;
        let contact_dofs: Vec<usize> = if model.cars.is_empty() {
            vec![]
        } else {
            (0..st.layers[0].n_dofs())
                .map(|k| st.layers[0].offset + k)
                .collect()
        };
        let (m, c, k) = st.stepping_matrices();
        let mut track = Newmark::new(
            m,
            c,
            k,
            dt,
            &contact_dofs,
            st.layers[0].basis.shape_len(),
            st.node_blocks().as_deref(),
            &st.tids,
        )?;
        for li in 0..st.layers.len() {
            for x in cfg.observation_points() {
                track.observe(&st.shape(li, x));
            }
        }
        let movers: Vec<Mover> = cfg
            .forces
            .iter()
            .map(|f| Mover {
                layer: f
                    .layer
                    .as_ref()
                    .and_then(|l| cfg.layer_index(l))
                    .unwrap_or(0),
                x0: f.x0,
                magnitude: f.magnitude,
            })
            .collect();
        let cars = model
            .cars
            .iter()
            .map(|c| CarRun::new(c, dt, cfg.solver.gravity))
            .collect::<Result<Vec<_>>>()?;
        let nw = cars.len() * N_WHEELS;
        let g: Vec<f64> = cars
            .iter()
            .flat_map(|c| [c.car.hertz_g; N_WHEELS])
            .collect();
        let contact = ContactSolver::new(
            g,
            vec![1.0; nw],
            cfg.solver.contact_tol,
            cfg.solver.contact_max_iter,
        );
        let n = track.n;
        let shape_len = st
            .layers
            .iter()
            .map(|l| l.basis.shape_len())
            .max()
            .unwrap_or(0);
        let rail_movers: Vec<(f64, f64)> = movers
            .iter()
            .filter(|m: &&Mover| m.layer == 0)
            .map(|m| (m.x0, m.magnitude))
            .collect();
        let correction = st.fesea.as_ref().map(|fs| {
            let idx = fs.dofs.map(|d| {
                track
                    .vector(&Shape {
                        start: d,
                        values: vec![1.0],
                    })
                    .idx[0]
            });
            RailCorrection {
                fs,
                idx,
                rate: 1.0 / dt,
                g_prev: [0.0; 4],
                g_next: [0.0; 4],
                wheel_r: vec![[0.0; 4]; nw],
                inv_k: fs.modes.iter().map(|m| 1.0 / m.stiffness).collect(),
                obs: cfg
                    .observation_points()
                    .into_iter()
                    .filter(|_| cfg.discretisation.local_deflection)
                    .collect::<Vec<_>>()
                    .iter()
                    .map(|&x| {
                        let mut s = vec![0.0; fs.modes.len()];
                        fs.local_sines_into(x, &mut s);
                        s.iter()
                            .zip(&fs.modes)
                            .map(|(s, m)| s / m.stiffness)
                            .collect()
                    })
                    .collect(),
                sines: vec![0.0; (nw + rail_movers.len()) * fs.modes.len()],
                movers: rail_movers,
            }
        });
        let mut track_ports: Vec<PortBlock> = (0..cars.len()).map(|_| PortBlock::new(n)).collect();
        if correction.is_some() {
            for p in &mut track_ports {
                p.force = Some(Default::default());
            }
        }
        Ok(Self {
            model,
            correction,
            f_prev: vec![0.0; n],
            f_next: vec![0.0; n],
            movers,
            track_ports,
            element_flexibility: cfg.discretisation.element_flexibility,
            cars,
            contact,
            p: vec![0.0; nw],
            shape: Shape {
                start: 0,
                values: vec![0.0; shape_len],
            },
            scratch: Default::default(),
            n_steps: cfg.n_steps(),
            track,
        })
    }

    /// F_{n+1} += w·N_layer(x) (stepper coordinates), with the FE–SEA terms of a rail load.
    fn add_load(&mut self, layer: usize, x: f64, w: f64) {
        self.model.structure.shape_into(layer, x, &mut self.shape);
        self.track.vector_into(&self.shape, &mut self.scratch);
        self.scratch.add_to(&mut self.f_next, w);
        if let Some(rc) = self.correction.as_mut().filter(|_| layer == 0) {
            let (f, r) = rc.unit_load(x);
            for g in 0..4 {
                self.f_next[rc.idx[g]] += w * f[g];
                rc.g_next[g] += w * r[g];
            }
        }
    }

    /// Static (or rest) initial state of track and cars.
    fn initial_state(&mut self) -> Result<()> {
        let model = self.model;
        let cfg = &model.cfg;
        let st = &model.structure;
        let g = cfg.solver.gravity;
        // Wheel loads from the statics of each (statically determinate) car, per modelled rail.
        let mut loads = Vec::with_capacity(self.p.len());
        for c in &self.cars {
            let (r, _) = c.car.static_state(g, &[0.0; N_WHEELS]);
            loads.extend(r.iter().map(|ri| ri / c.car.rails));
        }
        if let Some((i, l)) = loads.iter().enumerate().find(|(_, l)| !(**l > 0.0)) {
            return Err(VtbError::config(
                format!("vehicles[{}]", i / N_WHEELS),
                l,
                format!("wheelset {} carries no static load", i % N_WHEELS + 1),
            ));
        }
        self.contact.p_ref.clone_from(&loads);
        self.p.clone_from(&loads);
        // Track load at t = 0 in the original numbering.
        let n = st.n_dofs;
        let mut f0 = vec![0.0; n];
        // With the FE–SEA correction the initial state is the equilibrium of the corrected
        // model under the corrected loads; H_{−1} = H_0 (no derivative term at the start).
        let mut g0 = [0.0; 4];
        let correction = self.correction.as_ref();
        let mut add = |layer: usize, x: f64, w: f64| {
            let s = st.shape(layer, x);
            for (k, v) in s.values.iter().enumerate() {
                f0[s.start + k] += w * v;
            }
            if let Some(rc) = correction.filter(|_| layer == 0) {
                let (a, b) = rc.fs.load_terms(x);
                for g in 0..4 {
                    f0[rc.fs.dofs[g]] += w * a[g];
                    g0[g] += w * b[g];
                }
            }
        };
        for m in &self.movers {
            add(m.layer, m.x0, m.magnitude);
        }
        for (ci, c) in self.cars.iter().enumerate() {
            for w in 0..N_WHEELS {
                add(0, c.car.wheel_x0[w], loads[ci * N_WHEELS + w]);
            }
        }
        if let Some(rc) = self.correction.as_mut() {
            rc.g_prev = g0;
        }
        self.f_prev = self.track.to_stepper(&f0);
        let u0 = match cfg.solver.initial_state {
            InitialState::Static => Ldlt::new(&st.k)
                .map_err(|e| VtbError::Solver(format!("static stiffness: {e}")))?
                .solve(&f0),
            InitialState::Rest => vec![0.0; n],
        };
        let a0 = accelerations(&st.m, &st.k, &u0, &f0)?;
        self.track.set_state(&u0, &vec![0.0; n], &a0, &st.k, &st.m);
        if let Some(rc) = self.correction.as_mut() {
            rc.set_rows(self.cars.iter().flat_map(|c| c.car.wheel_x0), 0.0, 0.0);
        }
        for (ci, c) in self.cars.iter_mut().enumerate() {
            let mut zw = [0.0; N_WHEELS];
            for w in 0..N_WHEELS {
                let x = c.car.wheel_x0[w];
                let p0 = loads[ci * N_WHEELS + w];
                zw[w] = st.displacement(0, x, &u0)
                    + model.profile.at(x)
                    + compression(c.car.hertz_g, p0);
            }
            let (_, z) = c.car.static_state(g, &zw);
            let mut f = c.car.gravity(g);
            for w in 0..N_WHEELS {
                f[WHEEL0 + w] -= c.car.rails * loads[ci * N_WHEELS + w];
            }
            let av = accelerations(&c.m, &c.k, &z, &f)?;
            c.nm.set_state(&z, &[0.0; N_DOF], &av, &c.k, &c.m);
            c.z0 = z.to_vec();
            c.set_force(&loads[ci * N_WHEELS..(ci + 1) * N_WHEELS]);
        }
        Ok(())
    }

    /// Runs all steps; `cancel` is polled every 1024 steps.
    pub fn run(mut self, cancel: Option<&AtomicBool>) -> Result<RunResult> {
        self.initial_state()?;
        let model = self.model;
        let cfg = &model.cfg;
        let st = &model.structure;
        let n_points = cfg.observation_points().len();
        let nw = self.p.len();
        let ncars = self.cars.len();
        let mut res = RunResult::new(cfg, st, self.n_steps, n_points, ncars, nw);
        self.record(&mut res, 0);
        let dt = cfg.solver.dt;
        let v = cfg.speed;
        let mut amat = vec![0.0; nw * nw];
        let mut delta_free = vec![0.0; nw];
        let mut loss_open: Vec<Option<f64>> = vec![None; nw];

        for step in 0..self.n_steps {
            if step % 1024 == 0 {
                if cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                    return Err(VtbError::Cancelled);
                }
                self.check_finite(step)?;
            }
            let t1 = (step + 1) as f64 * dt;
            self.f_next.fill(0.0);
            if let Some(rc) = self.correction.as_mut() {
                rc.g_next = [0.0; 4];
                for g in 0..4 {
                    self.f_next[rc.idx[g]] -= rc.rate * rc.g_prev[g];
                }
            }
            for mi in 0..self.movers.len() {
                let m = self.movers[mi];
                self.add_load(m.layer, m.x0 + v * t1, m.magnitude);
            }
            self.track.begin_step(&self.f_prev, &self.f_next);
            if let Some(rc) = self.correction.as_mut() {
                rc.set_rows(self.cars.iter().flat_map(|c| c.car.wheel_x0), v, t1);
            }
            for (ci, c) in self.cars.iter_mut().enumerate() {
                let ports = &mut self.track_ports[ci];
                let xs: [f64; N_WHEELS] = std::array::from_fn(|w| c.car.wheel_x0[w] + v * t1);
                let terms = self.correction.as_ref().map(|rc| rc.fs.load_terms_at(xs));
                for w in 0..N_WHEELS {
                    st.shape_into(0, xs[w], &mut self.shape);
                    self.track.vector_into(&self.shape, &mut ports.vecs[w]);
                    if let (Some(rc), Some(force), Some(t)) =
                        (self.correction.as_mut(), ports.force.as_mut(), terms)
                    {
                        let (f, r) = rc.with_rate(t[w]);
                        let fv = &mut force[w];
                        fv.copy_from(&ports.vecs[w]);
                        // A modal rail's shape vector covers all its DOFs, g1..g4 first.
                        for g in 0..4 {
                            fv.val[rc.fs.dofs[g] - self.shape.start] += f[g];
                        }
                        rc.wheel_r[ci * N_WHEELS + w] = r;
                    }
                }
                self.track.prepare_ports(ports);
                c.nm.begin_step(&c.f_prev, &c.gravity);
            }
            // δ = δ_free − A·P with A = rails·(car compliance) + (rail compliance).
            for ci in 0..ncars {
                let c = &self.cars[ci];
                let rail = self.track.free_port_disp(&self.track_ports[ci]);
                let wheel = c.nm.free_port_disp(&c.ports);
                for w in 0..N_WHEELS {
                    let wi = ci * N_WHEELS + w;
                    let x = c.car.wheel_x0[w] + v * t1;
                    delta_free[wi] = wheel[w] - rail[w] - model.profile.at(x);
                }
                for cj in 0..ncars {
                    let g = self
                        .track
                        .port_compliance(&self.track_ports[ci], &self.track_ports[cj]);
                    for r in 0..N_WHEELS {
                        for s in 0..N_WHEELS {
                            let own = if ci == cj {
                                c.car.rails * c.compliance[r][s]
                            } else {
                                0.0
                            };
                            amat[(ci * N_WHEELS + r) * nw + cj * N_WHEELS + s] = g[r][s] + own;
                        }
                    }
                }
                if self.element_flexibility {
                    // The wheel also deflects the rail within its element (nodes fixed): in
                    // series with the contact, so the static wheel–rail stiffness does not
                    // depend on where in an element the wheel is (no element-passing
                    // excitation from it). Wheels are more than an element apart.
                    for w in 0..N_WHEELS {
                        let wi = ci * N_WHEELS + w;
                        amat[wi * nw + wi] += st.local_flexibility(0, c.car.wheel_x0[w] + v * t1);
                    }
                }
            }
            if nw > 0 {
                self.contact
                    .solve(&mut self.p, &delta_free, &amat, t1, step + 1)?;
            }
            for (ci, c) in self.cars.iter_mut().enumerate() {
                let p: [f64; GW] = std::array::from_fn(|w| {
                    if w < N_WHEELS {
                        self.p[ci * N_WHEELS + w]
                    } else {
                        0.0
                    }
                });
                self.track.add_port_forces(&self.track_ports[ci], p);
                c.nm.add_port_forces(&c.ports, p.map(|pw| -c.car.rails * pw));
                c.nm.end_step();
                c.set_force(&p[..N_WHEELS]);
            }
            self.track.end_step();
            // F_{n+1} becomes F_n: moving forces plus the converged wheel forces.
            std::mem::swap(&mut self.f_prev, &mut self.f_next);
            for (ci, ports) in self.track_ports.iter().enumerate() {
                for w in 0..N_WHEELS {
                    ports
                        .force_vec(w)
                        .add_to(&mut self.f_prev, self.p[ci * N_WHEELS + w]);
                }
            }
            if let Some(rc) = self.correction.as_mut() {
                rc.g_prev = rc.g_next;
                for (wi, r) in rc.wheel_r.iter().enumerate() {
                    for g in 0..4 {
                        rc.g_prev[g] += self.p[wi] * r[g];
                    }
                }
            }
            for wi in 0..nw {
                match (self.p[wi] == 0.0, loss_open[wi]) {
                    (true, None) => loss_open[wi] = Some(t1),
                    (false, Some(t0)) => {
                        res.contact_loss.push(ContactLoss {
                            wheel: wi,
                            t_start: t0,
                            t_end: Some(t1),
                        });
                        loss_open[wi] = None;
                    }
                    _ => {}
                }
            }
            self.record(&mut res, step + 1);
        }
        self.check_finite(self.n_steps)?;
        for (wi, open) in loss_open.iter().enumerate() {
            if let Some(t0) = open {
                res.contact_loss.push(ContactLoss {
                    wheel: wi,
                    t_start: *t0,
                    t_end: None,
                });
            }
        }
        Ok(res)
    }

    /// A non-finite state (overflow from extreme parameters) is an error, never a result.
    fn check_finite(&self, step: usize) -> Result<()> {
        let ok = self.track.u.iter().all(|v| v.is_finite())
            && self.p.iter().all(|v| v.is_finite())
            && (0..self.track.n_observed()).all(|j| self.track.observed(j).2.is_finite())
            && self
                .cars
                .iter()
                .all(|c| (0..N_DOF).all(|i| c.nm.observed(i).2.is_finite()));
        if ok {
            Ok(())
        } else {
            Err(VtbError::Solver(format!(
                "the state became non-finite by step {step}: parameters of extreme magnitude?"
            )))
        }
    }

    fn record(&self, res: &mut RunResult, step: usize) {
        let no = self.track.n_observed();
        for j in 0..no {
            let (u, _, a) = self.track.observed(j);
            res.disp[step * no + j] = u;
            res.acc[step * no + j] = a;
        }
        if let Some(rc) = &self.correction {
            // Rail points come first: add the local modes' static deflection.
            for j in 0..rc.obs.len() {
                res.disp[step * no + j] += rc.observed_deflection(j, &self.p);
            }
        }
        let ncars = self.cars.len();
        for (ci, c) in self.cars.iter().enumerate() {
            for i in 0..N_DOF {
                let (z, _, a) = c.nm.observed(i);
                res.vehicle_disp[(step * ncars + ci) * N_DOF + i] = z - c.z0[i];
                res.vehicle_acc[(step * ncars + ci) * N_DOF + i] = a;
            }
        }
        let nw = self.p.len();
        res.contact_force[step * nw..(step + 1) * nw].copy_from_slice(&self.p);
    }
}

/// a = M⁻¹(F − K·u) for a subsystem at rest.
fn accelerations(m: &CsrMatrix, k: &CsrMatrix, u: &[f64], f: &[f64]) -> Result<Vec<f64>> {
    let mut ku = vec![0.0; u.len()];
    k.mul(u, &mut ku);
    let r: Vec<f64> = f.iter().zip(&ku).map(|(a, b)| a - b).collect();
    if r.iter().all(|v| *v == 0.0) {
        return Ok(vec![0.0; u.len()]);
    }
    Ok(Ldlt::new(m)?.solve(&r))
}
