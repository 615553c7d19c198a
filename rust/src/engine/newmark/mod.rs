//! The structure stepped by Newmark (modal, hybrid FE–SEA or finite elements), coupled with
//! the cars through the contact; W jobs of one model in lockstep (`Simulation` with W lanes).

use super::coupled::{CarRun, Mover, static_wheel_loads};
use super::integrator::{GW, Newmark, PortBlock, accelerations};
use super::{Control, LaneSpec};
use crate::config::DamperParams;
use crate::config::{InitialState, Profile};
use crate::error::{Result, VtbError};
use crate::linalg::sparse::Ldlt;
use crate::model::Model;
use crate::model::basis::Shape;
use crate::model::contact::{ContactSolver, patch_half_length};
use crate::model::fesea::FeSea;
use crate::outputs::{Record, RunResult};

mod step;

/// The FE–SEA force terms of the hybrid model on the rail's cubic DOFs g1..g4 (docs/model.md §6):
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
    /// H_n, and H_{n+1} from the known loads of the step, per lane.
    g_prev: Vec<[f64; 4]>,
    g_next: Vec<[f64; 4]>,
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

/// A lane's own data: its irregularity, contact iteration, damper parameters, result, and
/// its failure once it failed (the lane then idles at zero while the others go on).
struct Lane<'a> {
    profile: &'a Profile,
    dampers: Vec<DamperParams>,
    contact: ContactSolver,
    error: Option<VtbError>,
    loss_open: Vec<Option<f64>>,
}

/// The state of W coupled runs on one model in lockstep (W = 1: a single run).
pub struct Simulation<'m, const W: usize = 1> {
    model: &'m Model,
    lanes: Vec<Lane<'m>>,
    record: Record,
    /// Observation points recorded (all, or the first only).
    points: Vec<f64>,
    track: Newmark<W>,
    f_prev: Vec<f64>,
    f_next: Vec<f64>,
    movers: Vec<Mover>,
    cars: Vec<CarRun<W>>,
    /// Wheels per car (one vehicle model per run): wheel `w` of car `ci` is `ci·wpc + w`.
    wpc: usize,
    /// Rail shape vectors at the wheels, one block per car.
    track_ports: Vec<PortBlock<W>>,
    /// Add the rail elements' local flexibility under the wheels (finite-element rails).
    element_flexibility: bool,
    /// Half-length (m) of each wheel's contact patch, 0 for a point contact.
    patch: Vec<f64>,
    /// A wheel's rail shape vector (point or patch).
    wheel_shape: Shape,
    /// Contact force of each wheel on the modelled rail (N), `[lane·n_wheels + wheel]`.
    p: Vec<f64>,
    shape: Shape,
    scratch: crate::engine::integrator::SVec,
    n_steps: usize,
    correction: Option<RailCorrection<'m>>,
    /// Each lane's free compressions δ_free and contact compliance A this step (`step.rs`).
    delta_free: Vec<f64>,
    amat: Vec<f64>,
}

impl<'m> Simulation<'m, 1> {
    /// A single run of the model's own configuration and irregularity, recording everything.
    pub fn new(model: &'m Model) -> Result<Self> {
        let lane = LaneSpec::of(&model.cfg, &model.profile);
        Self::lanes(model, &[lane], Record::Full)
    }

    /// Runs all steps; `cancel` is polled every `CANCEL_POLL` steps.
    pub fn run(self, cancel: Option<&Control>) -> Result<RunResult> {
        self.run_lanes(cancel)?.pop().expect("one lane")
    }
}

impl<'m, const W: usize> Simulation<'m, W> {
    /// W jobs of one model: lane j runs on `lanes[j]`'s irregularity and damper parameters.
    pub fn lanes(model: &'m Model, lanes: &[LaneSpec<'m>], record: Record) -> Result<Self> {
        assert_eq!(lanes.len(), W, "one lane spec per lane");
        let cfg = &model.cfg;
        let st = &model.structure;
        let dt = cfg.solver.dt;
        let points = match record {
            Record::Full => cfg.observation_points(),
            Record::Metrics => cfg.observation_points()[..1].to_vec(),
        };
        let contact_dofs: Vec<usize> = if model.cars.is_empty() {
            vec![]
        } else {
            (0..st.layers[0].n_dofs())
                .map(|k| st.layers[0].offset + k)
                .collect()
        };
        crate::check::budget::check_histories(cfg, record, W)?;
        let (m, c, k) = st.stepping_matrices();
        let mut track = Newmark::<W>::new(
            m,
            c,
            k,
            dt,
            &contact_dofs,
            st.layers[0].basis.shape_len(),
            st.node_blocks().as_deref(),
            &st.dampers,
        )?;
        for lane in lanes {
            if lane.dampers.len() != st.dampers.len() {
                return Err(VtbError::config(
                    "dampers",
                    lane.dampers.len(),
                    format!(
                        "a lockstep group needs {} dampers in every job",
                        st.dampers.len()
                    ),
                ));
            }
        }
        // A lane whose dampers cannot be set up (e.g. parameters of extreme magnitude) fails
        // alone.
        let setup: Vec<Option<VtbError>> = lanes
            .iter()
            .enumerate()
            .map(|(j, l)| {
                (!l.dampers.is_empty())
                    .then(|| track.set_damper_params(j, &l.dampers).err())
                    .flatten()
            })
            .collect();
        let layers = record.layers(cfg);
        for &li in &layers {
            for &x in &points {
                track.observe(&st.shape(li, x));
            }
        }
        let movers = Mover::all(cfg);
        let cars = model
            .cars
            .iter()
            .map(|c| CarRun::new(c, dt, cfg.solver.gravity))
            .collect::<Result<Vec<_>>>()?;
        let wpc = cars.first().map_or(0, |c| c.car.n_wheels());
        let nw = cars.len() * wpc;
        let patch: Vec<f64> = static_wheel_loads(&cars, cfg.solver.gravity)
            .iter()
            .enumerate()
            .map(|(wi, &load)| {
                let v = &cfg.vehicles[wi / wpc];
                if v.contact_patch && load > 0.0 {
                    patch_half_length(load, v.wheel_radius, v.rail_crown_radius)
                } else {
                    0.0
                }
            })
            .collect();
        let wheel_shape_len = patch
            .iter()
            .map(|&a| st.wheel_shape_len(a))
            .max()
            .unwrap_or(0);
        let g: Vec<f64> = cars.iter().flat_map(|c| vec![c.car.hertz_g; wpc]).collect();
        let lanes = lanes
            .iter()
            .zip(setup)
            .map(|(l, error)| Lane {
                profile: l.profile,
                dampers: l.dampers.clone(),
                contact: ContactSolver::new(
                    g.clone(),
                    vec![1.0; nw],
                    cfg.solver.contact_tol,
                    cfg.solver.contact_max_iter,
                )
                .with_block(wpc),
                error,
                loss_open: vec![None; nw],
            })
            .collect();
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
                g_prev: vec![[0.0; 4]; W],
                g_next: vec![[0.0; 4]; W],
                wheel_r: vec![[0.0; 4]; nw],
                inv_k: fs.modes.iter().map(|m| 1.0 / m.stiffness).collect(),
                obs: points
                    .iter()
                    .filter(|_| cfg.discretisation.local_deflection && layers.first() == Some(&0))
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
        let mut track_ports: Vec<PortBlock<W>> =
            (0..cars.len()).map(|_| PortBlock::new(n)).collect();
        if correction.is_some() {
            for p in &mut track_ports {
                p.force = Some(Default::default());
            }
        }
        Ok(Self {
            model,
            lanes,
            record,
            points,
            correction,
            f_prev: vec![0.0; n * W],
            f_next: vec![0.0; n * W],
            movers,
            track_ports,
            element_flexibility: cfg.discretisation.element_flexibility,
            patch,
            wheel_shape: Shape {
                start: 0,
                values: Vec::with_capacity(wheel_shape_len),
            },
            cars,
            wpc,
            p: vec![0.0; nw * W],
            shape: Shape {
                start: 0,
                values: vec![0.0; shape_len],
            },
            scratch: Default::default(),
            n_steps: cfg.n_steps(),
            track,
            delta_free: vec![0.0; W * nw],
            amat: vec![0.0; W * nw * nw],
        })
    }

    /// F_{n+1} += w·N_layer(x) in every lane (stepper coordinates), with the FE–SEA terms of
    /// a rail load.
    fn add_load(&mut self, layer: usize, x: f64, w: f64) {
        self.model.structure.shape_into(layer, x, &mut self.shape);
        self.track.vector_into(&self.shape, &mut self.scratch);
        for lane in 0..W {
            self.scratch.add_to_lane::<W>(&mut self.f_next, lane, w);
        }
        if let Some(rc) = self.correction.as_mut().filter(|_| layer == 0) {
            let (f, r) = rc.unit_load(x);
            for lane in 0..W {
                for g in 0..4 {
                    self.f_next[rc.idx[g] * W + lane] += w * f[g];
                    rc.g_next[lane][g] += w * r[g];
                }
            }
        }
    }

    /// Static (or rest) initial state of track and cars in every lane.
    fn initial_state(&mut self) -> Result<()> {
        let model = self.model;
        let cfg = &model.cfg;
        let st = &model.structure;
        let g = cfg.solver.gravity;
        let loads = static_wheel_loads(&self.cars, g);
        if let Some((i, l)) = loads.iter().enumerate().find(|(_, l)| !(**l > 0.0)) {
            return Err(VtbError::config(
                format!("vehicles[{}]", i / self.wpc),
                l,
                format!("wheel {} carries no static load", i % self.wpc + 1),
            ));
        }
        let nw = loads.len();
        for (j, lane) in self.lanes.iter_mut().enumerate() {
            lane.contact.p_ref.clone_from(&loads);
            self.p[j * nw..(j + 1) * nw].copy_from_slice(&loads);
        }
        // Track load at t = 0 in the original numbering.
        let n = st.n_dofs;
        let mut f0 = vec![0.0; n];
        // With the FE–SEA correction the initial state is the equilibrium of the corrected
        // model under the corrected loads; H_{−1} = H_0 (no derivative term at the start).
        let mut g0 = [0.0; 4];
        let correction = self.correction.as_ref();
        let wheel_shape = &mut self.wheel_shape;
        let mut add = |layer: usize, x: f64, w: f64, patch: f64| {
            let s = if layer == 0 {
                st.wheel_shape_into(x, patch, wheel_shape);
                &*wheel_shape
            } else {
                &st.shape(layer, x)
            };
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
            add(m.layer, m.x0, m.magnitude, 0.0);
        }
        for (ci, c) in self.cars.iter().enumerate() {
            for (w, &x0) in c.car.wheel_x0.iter().enumerate() {
                let wi = ci * self.wpc + w;
                add(0, x0, loads[wi], self.patch[wi]);
            }
        }
        if let Some(rc) = self.correction.as_mut() {
            rc.g_prev = vec![g0; W];
            rc.set_rows(
                self.cars
                    .iter()
                    .flat_map(|c| c.car.wheel_x0.iter().copied()),
                0.0,
                0.0,
            );
        }
        self.f_prev = self.track.to_stepper(&f0);
        // Each lane's state from its own matrices (its dampers' parameters), as in a single
        // run; lanes with the model's own parameters share them.
        let own: Vec<DamperParams> = st.dampers.iter().map(|a| a.params).collect();
        let mut own_state: Option<(Vec<f64>, Vec<f64>)> = None;
        for j in 0..W {
            if self.lanes[j].error.is_some() {
                continue;
            }
            if let Err(e) = self.lane_initial_state(j, &f0, &loads, &own, &mut own_state) {
                self.fail(j, e);
            }
        }
        for (ci, c) in self.cars.iter_mut().enumerate() {
            let p: [f64; GW] = std::array::from_fn(|w| {
                if w < self.wpc {
                    loads[ci * self.wpc + w]
                } else {
                    0.0
                }
            });
            c.set_force(&[p; W]);
        }
        Ok(())
    }

    /// Lane `j`'s state at t = 0 from its own matrices (its dampers' parameters), as in a
    /// single run; lanes with the model's own parameters share one solve (`own_state`).
    fn lane_initial_state(
        &mut self,
        j: usize,
        f0: &[f64],
        loads: &[f64],
        own: &[DamperParams],
        own_state: &mut Option<(Vec<f64>, Vec<f64>)>,
    ) -> Result<()> {
        let model = self.model;
        let cfg = &model.cfg;
        let st = &model.structure;
        let g = cfg.solver.gravity;
        let n = st.n_dofs;
        let lane_mk;
        let (m_l, k_l) = if self.lanes[j].dampers == own {
            (&st.m, &st.k)
        } else {
            lane_mk = st.with_damper_params(&self.lanes[j].dampers);
            (&lane_mk.0, &lane_mk.1)
        };
        let state = match (&*own_state, self.lanes[j].dampers == own) {
            (Some(s), true) => s.clone(),
            _ => {
                let u0 = match cfg.solver.initial_state {
                    InitialState::Static => Ldlt::new(k_l)
                        .map_err(|e| VtbError::Solver(format!("static stiffness: {e}")))?
                        .solve(f0),
                    InitialState::Rest => vec![0.0; n],
                };
                let a0 = accelerations(m_l, k_l, &u0, f0)?;
                if self.lanes[j].dampers == own {
                    *own_state = Some((u0.clone(), a0.clone()));
                }
                (u0, a0)
            }
        };
        let (u0, a0) = state;
        self.track.set_state(j, &u0, &vec![0.0; n], &a0, k_l, m_l);
        let profile = self.lanes[j].profile;
        for (ci, c) in self.cars.iter_mut().enumerate() {
            let wpc = self.wpc;
            let mut rail = [0.0; GW];
            for (w, r) in rail.iter_mut().take(wpc).enumerate() {
                let x = c.car.wheel_x0[w];
                st.wheel_shape_into(x, self.patch[ci * wpc + w], &mut self.wheel_shape);
                *r = dot(&self.wheel_shape.values, &u0[self.wheel_shape.start..])
                    + cfg.irregularity_share(0.0) * profile.under(ci * wpc + w, x);
            }
            c.set_static(j, &rail[..wpc], &loads[ci * wpc..(ci + 1) * wpc], g)?;
        }
        Ok(())
    }

    /// The wheel forces of car `ci` per lane, padded to the port width.
    fn car_forces(&self, ci: usize) -> [[f64; GW]; W] {
        let nw = self.p.len() / W;
        std::array::from_fn(|lane| {
            std::array::from_fn(|w| {
                if w < self.wpc {
                    self.p[lane * nw + ci * self.wpc + w]
                } else {
                    0.0
                }
            })
        })
    }

    /// Lane `j` failed: keep the error, zero its state so that it idles finite.
    fn fail(&mut self, j: usize, e: VtbError) {
        let nw = self.p.len() / W;
        self.lanes[j].error = Some(e);
        self.track.clear_lane(j);
        for c in &mut self.cars {
            c.nm.clear_lane(j);
        }
        self.p[j * nw..(j + 1) * nw].fill(0.0);
        for x in self.f_prev.iter_mut().skip(j).step_by(W) {
            *x = 0.0;
        }
        if let Some(rc) = self.correction.as_mut() {
            rc.g_prev[j] = [0.0; 4];
        }
    }

    /// A non-finite state (overflow from extreme parameters) fails its lane, never gives a
    /// result.
    fn check_finite(&mut self, step: usize) {
        let nw = self.p.len() / W;
        for j in 0..W {
            if self.lanes[j].error.is_some() {
                continue;
            }
            let quantity = if !self.track.lane_finite(j) {
                Some("the structure's displacements".to_string())
            } else if !self.p[j * nw..(j + 1) * nw].iter().all(|v| v.is_finite()) {
                Some("the contact forces".to_string())
            } else {
                (0..self.cars.len())
                    .find(|&i| !self.cars[i].nm.lane_finite(j))
                    .map(|i| format!("the DOFs of vehicles[{i}]"))
            };
            if let Some(q) = quantity {
                self.fail(
                    j,
                    VtbError::Solver(format!(
                        "{q} became non-finite by step {step} (t = {:.6} s): an overflow, most \
                         likely from parameters of extreme magnitude (a mass or stiffness many \
                         orders from the others)",
                        step as f64 * self.model.cfg.solver.dt
                    )),
                );
            }
        }
    }

    fn record_step(&self, res: &mut [RunResult], step: usize) {
        let no = self.track.n_observed();
        let nw = self.p.len() / W;
        for (lane, r) in res.iter_mut().enumerate() {
            if self.lanes[lane].error.is_some() {
                continue;
            }
            for j in 0..no {
                let (u, _, a) = self.track.observed(j, lane);
                r.disp[step * no + j] = u;
                r.acc[step * no + j] = a;
            }
            let p = &self.p[lane * nw..(lane + 1) * nw];
            if let Some(rc) = &self.correction {
                // Rail points come first: add the local modes' static deflection.
                for j in 0..rc.obs.len() {
                    r.disp[step * no + j] += rc.observed_deflection(j, p);
                }
            }
            let (ncars, ndof) = (r.n_cars, r.vehicle_dofs);
            for (ci, c) in self.cars.iter().take(ncars).enumerate() {
                for i in 0..ndof {
                    let (z, _, a) = c.nm.observed(i, lane);
                    r.vehicle_disp[(step * ncars + ci) * ndof + i] = z - c.z0[i * W + lane];
                    r.vehicle_acc[(step * ncars + ci) * ndof + i] = a;
                }
            }
            r.contact_force[step * nw..(step + 1) * nw].copy_from_slice(p);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DamperKind;
    use crate::config::{Config, DamperGroup};
    use crate::engine::simulate;
    use crate::library::presets;

    fn short_with_dampers() -> Config {
        let mut cfg = presets::paper();
        cfg.solver.t_end = Some(0.05);
        cfg.tids = Some(DamperGroup {
            kind: DamperKind::Tid,
            inertance: 3.0,
            stiffness: 1e8,
            damping: 1e3,
            count: Some(3),
            x0: Some(30.0),
            spacing: Some(0.64),
            positions: None,
            upper: "rail".into(),
            lower: "slab".into(),
        });
        cfg
    }

    /// Four lanes on one model, one of them on an irregularity that is non-finite from 9 m on: that lane fails with a `Solver` error, the other three give exactly the bits
    /// of their single runs (different damper parameters and irregularities).
    #[test]
    fn a_failing_lane_leaves_its_group_unharmed() {
        let cfg = short_with_dampers();
        let smooth = Profile::flat();
        let wavy = Profile {
            x0: -1.0,
            dx: 0.01,
            values: (0..20_000).map(|i| 1e-4 * (i as f64 * 0.3).sin()).collect(),
            treads: Vec::new(),
        };
        let mut broken = wavy.clone();
        broken
            .values
            .iter_mut()
            .skip(1000)
            .for_each(|v| *v = f64::NAN);
        let model = crate::check::validated(cfg.clone(), smooth.clone()).unwrap();
        let param = |k: f64, b: f64| {
            vec![
                DamperParams {
                    kind: DamperKind::Tid,
                    stiffness: k,
                    damping: 1e3,
                    inertance: b,
                };
                3
            ]
        };
        let lanes = [
            LaneSpec {
                profile: &smooth,
                dampers: param(1e8, 3.0),
            },
            LaneSpec {
                profile: &wavy,
                dampers: param(7e8, 9.0),
            },
            LaneSpec {
                profile: &broken,
                dampers: param(2e7, 1.0),
            },
            LaneSpec {
                profile: &wavy,
                dampers: param(1e4, 5.0),
            },
        ];
        let out = Simulation::<4>::lanes(&model, &lanes, Record::Full)
            .unwrap()
            .run_lanes(None)
            .unwrap();
        assert!(
            matches!(out[2], Err(VtbError::Solver(_))),
            "{:?}",
            out[2].as_ref().err()
        );
        for j in [0, 1, 3] {
            let alone = Simulation::<1>::lanes(&model, &lanes[j..j + 1], Record::Full)
                .unwrap()
                .run_lanes(None)
                .unwrap()
                .pop()
                .unwrap()
                .unwrap();
            let got = out[j].as_ref().unwrap();
            for (a, b) in alone.acc.iter().zip(&got.acc) {
                assert_eq!(a.to_bits(), b.to_bits(), "lane {j}");
            }
            assert_eq!(alone.contact_force, got.contact_force);
            assert_eq!(alone.metrics(), got.metrics());
        }
    }

    /// A tread irregularity is the rail's seen by one wheel: the same samples as treads of
    /// every wheel over a smooth rail give the rail run's bits; on one wheel only, that wheel's
    /// contact force departs most from the smooth run's.
    #[test]
    fn treads_on_every_wheel_equal_the_rail_profile() {
        let cfg = short_with_dampers();
        let wheels = cfg.vehicles.len() * 4;
        let wavy: Vec<f64> = (0..20_000).map(|i| 1e-4 * (i as f64 * 0.3).sin()).collect();
        let grid = |values: Vec<f64>, treads: Vec<Vec<f64>>| Profile {
            x0: -1.0,
            dx: 0.01,
            values,
            treads,
        };
        let on_rail = grid(wavy.clone(), Vec::new());
        let on_wheels = grid(vec![0.0; wavy.len()], vec![wavy.clone(); wheels]);
        let mut one = vec![Vec::new(); wheels];
        one[0] = wavy.clone();
        let on_wheel_0 = grid(vec![0.0; wavy.len()], one);
        let a = simulate(&cfg, &on_rail, None).unwrap();
        let b = simulate(&cfg, &on_wheels, None).unwrap();
        assert_eq!(a.contact_force, b.contact_force);
        assert_eq!(a.metrics(), b.metrics());
        let c = simulate(&cfg, &on_wheel_0, None).unwrap();
        let a = simulate(&cfg, &grid(vec![0.0; wavy.len()], Vec::new()), None).unwrap();
        let change = |w: usize| {
            (0..=c.n_steps)
                .map(|k| (c.contact_force[k * wheels + w] - a.contact_force[k * wheels + w]).abs())
                .fold(0.0, f64::max)
        };
        // Wheel 0 rides its tread; the others feel it only through the car and the rail.
        for w in 1..wheels {
            assert!(
                change(w) < 0.5 * change(0),
                "wheel {w}: {} vs {}",
                change(w),
                change(0)
            );
        }
    }

    #[test]
    fn treads_need_one_row_per_wheel_on_the_rail_grid() {
        let cfg = short_with_dampers();
        let p = Profile {
            x0: -1.0,
            dx: 0.01,
            values: vec![0.0; 20_000],
            treads: vec![vec![0.0; 10]],
        };
        let e = crate::check::validate(&cfg, &p).unwrap_err().to_string();
        assert!(e.contains("irregularity.treads"), "{e}");
        let wheels = cfg.vehicles.len() * 4;
        let mut rows = vec![Vec::new(); wheels];
        rows[1] = vec![0.0; 10];
        let e = crate::check::validate(
            &cfg,
            &Profile {
                treads: rows,
                ..p.clone()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("irregularity.treads[1]"), "{e}");
        let mut rows = vec![Vec::new(); wheels];
        rows[0] = vec![0.0; 20_000];
        rows[0][7] = f64::INFINITY;
        let e = crate::check::validate(&cfg, &Profile { treads: rows, ..p })
            .unwrap_err()
            .to_string();
        assert!(e.contains("irregularity.treads[0][7]"), "{e}");
    }
}
