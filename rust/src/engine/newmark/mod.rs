//! The structure stepped by Newmark (modal, hybrid FE–SEA or finite elements): the structure
//! side of the coupled loop (`crate::engine::coupled`). [`Simulation`] runs W jobs of one
//! model in lockstep (W = 1: a single run).
//!
//! - `mod.rs` (this file): the set-up and the state at t = 0;
//! - `step`: the step's phases — loads, ports, the contact's compliance, the update, records;
//! - `correction`: the FE–SEA correction's set-up, force terms and output recovery (hybrid
//!   rails).

mod correction;
mod step;

use super::coupled::residual::WheelFilters;
use super::coupled::{self, Mover, Vehicles};
use super::integrator::{Newmark, Numbering, PortBlock, SVec, accelerations};
use super::{Control, LaneSpec};
use crate::config::{DamperParams, InitialState, Profile};
use crate::error::{Result, VtbError};
use crate::linalg::sparse::Ldlt;
use crate::model::Model;
use crate::model::basis::Shape;
use crate::model::structure::Structure;
use crate::outputs::catalog::{Pad, pads_of};
use crate::outputs::{Record, RunResult};
use correction::{RailCorrection, dot};

/// The Newmark engine's side of W coupled runs on one model.
pub(super) struct NewmarkSide<'m, const W: usize> {
    model: &'m Model,
    track: Newmark<W>,
    f_prev: Vec<f64>,
    f_next: Vec<f64>,
    movers: Vec<Mover>,
    /// Each lane's damper parameters, and the error of a lane whose dampers could not be set
    /// up.
    dampers: Vec<Vec<DamperParams>>,
    setup: Vec<Option<VtbError>>,
    /// Rail shape vectors at the wheels, one block per car.
    track_ports: Vec<PortBlock<W>>,
    /// Add the rail elements' local flexibility under the wheels (finite-element rails).
    element_flexibility: bool,
    /// A wheel's rail shape vector (point or patch).
    wheel_shape: Shape,
    shape: Shape,
    scratch: SVec,
    correction: Option<RailCorrection<'m>>,
    /// The rail's free displacement at every wheel this step, `[lane·nw + wheel]`.
    rail_free: Vec<f64>,
    /// Substructured: each wheel's filter of the residual the interiors' truncated modes hold
    /// (their static flexibility, damping and inertia, in series with the contact).
    residual: Option<WheelFilters<W>>,
    /// The end of the step under way (s).
    t1: f64,
    /// Observers of the layers' records (the first ones), then of each pad's two ends, then
    /// of the bottom layer's bending moment at each of `n_moments` points.
    n_layer_obs: usize,
    pads: Vec<Pad>,
    n_moments: usize,
}

/// How many substructures' columns past a wheel's own the substructured engine keeps of its
/// port's forward substitution (`Newmark::set_port_reach`): L⁻¹n has decayed by then
/// (docs/substructures.md measures the truncation).
const PORT_REACH_PIECES: usize = 3;

/// W coupled runs of one model on the Newmark engine.
pub struct Simulation<'m, const W: usize = 1> {
    model: &'m Model,
    side: NewmarkSide<'m, W>,
    vehicles: Vehicles<W>,
    profiles: [&'m Profile; W],
    record: Record,
    /// Observation points recorded (all, or the first only).
    points: Vec<f64>,
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
        let points = record.points(cfg);
        let side = NewmarkSide::new(model, lanes, record, &points)?;
        let vehicles = Vehicles::new(model, cfg.solver.dt)?;
        Ok(Self {
            side: side.with_wheels(&vehicles),
            vehicles,
            profiles: std::array::from_fn(|j| lanes[j].profile),
            model,
            record,
            points,
        })
    }

    /// Runs all steps of every lane. The outer error is shared by all lanes (setup, or
    /// cancellation: `cancel` is polled every `CANCEL_POLL` steps); the inner ones are each
    /// lane's own.
    pub fn run_lanes(self, cancel: Option<&Control>) -> Result<Vec<Result<RunResult>>> {
        coupled::run(
            self.model,
            self.side,
            self.vehicles,
            self.profiles,
            (self.record, &self.points),
            cancel,
        )
    }
}

impl<'m, const W: usize> NewmarkSide<'m, W> {
    fn new(
        model: &'m Model,
        lanes: &[LaneSpec<'m>],
        record: Record,
        points: &[f64],
    ) -> Result<Self> {
        let cfg = &model.cfg;
        let st = &model.structure;
        let dt = cfg.solver.dt;
        let contact_dofs: Vec<usize> = if model.cars.is_empty() {
            vec![]
        } else {
            st.contact_dofs()
        };
        crate::check::budget::check_histories(cfg, record, W)?;
        let (m, c, k) = st.stepping_matrices();
        // Finite elements: one mesh → block tridiagonal; meshes of their own → ordered along
        // the track, linear in length (the general search's trial factors cost far more).
        let (blocks, order) = (st.node_blocks(), st.length_order());
        let numbering = match (&blocks, &order) {
            (Some(b), _) => Numbering::Blocks(b),
            (None, Some(o)) if st.reduced.is_some() => Numbering::Along(o),
            (None, Some(o)) => Numbering::Order(o),
            (None, None) => Numbering::Search,
        };
        let mut track = Newmark::<W>::new(
            m,
            c,
            k,
            dt,
            &contact_dofs,
            st.port_len(),
            numbering,
            &st.dampers,
        )?;
        if let Some(sub) = &st.reduced {
            track.set_port_reach(PORT_REACH_PIECES * sub.widest);
        }
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
            for &x in points {
                track.observe(&st.shape(li, x));
            }
        }
        let n_layer_obs = track.n_observed();
        let pads = pads_of(cfg);
        for pad in &pads {
            track.observe(&st.shape(0, pad.x));
            track.observe(&st.shape(pad.lower, pad.x));
        }
        let n_moments = observe_moments(&mut track, st, record.moments(cfg), points);
        let movers = Mover::all(cfg);
        let n = track.n;
        let shape_len = st
            .layers
            .iter()
            .map(|l| l.basis.shape_len())
            .max()
            .unwrap_or(0);
        // The local modes' deflection is added to the rail's records and the pads' rail ends.
        let local = cfg.discretisation.local_deflection;
        let rail_points = if local && layers.first() == Some(&0) {
            points.to_vec()
        } else {
            Vec::new()
        };
        let pad_points: Vec<f64> = pads.iter().filter(|_| local).map(|p| p.x).collect();
        let correction = st
            .fesea
            .as_ref()
            .map(|fs| RailCorrection::new(fs, &track, dt, &movers, (&rail_points, &pad_points)));
        Ok(Self {
            model,
            dampers: lanes.iter().map(|l| l.dampers.clone()).collect(),
            setup,
            correction,
            f_prev: vec![0.0; n * W],
            f_next: vec![0.0; n * W],
            movers,
            track_ports: Vec::new(),
            element_flexibility: cfg.discretisation.element_flexibility,
            wheel_shape: Shape::default(),
            shape: Shape {
                start: 0,
                values: vec![0.0; shape_len],
            },
            scratch: Default::default(),
            rail_free: Vec::new(),
            residual: None,
            t1: 0.0,
            n_layer_obs,
            pads,
            n_moments,
            track,
        })
    }

    /// The buffers sized for the vehicles' wheels: one port block per car, the FE–SEA rows.
    fn with_wheels(mut self, v: &Vehicles<W>) -> Self {
        let (st, nw) = (&self.model.structure, v.n_wheels());
        let wheel_shape_len = v
            .patch
            .iter()
            .map(|&a| st.wheel_shape_len(a))
            .max()
            .unwrap_or(0);
        self.wheel_shape = Shape {
            start: 0,
            values: Vec::with_capacity(wheel_shape_len),
        };
        self.track_ports = (0..v.cars.len())
            .map(|_| PortBlock::new(self.track.n))
            .collect();
        if let Some(rc) = self.correction.as_mut() {
            for p in &mut self.track_ports {
                p.force = Some(Default::default());
            }
            rc.wheel_r = vec![[0.0; 4]; nw];
            rc.sines = vec![0.0; (nw + rc.movers.len()) * rc.fs.modes.len()];
        }
        self.rail_free = vec![0.0; W * nw];
        self.residual = st.reduced.as_ref().map(|_| WheelFilters::new(nw));
        self
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

    /// The track's load at t = 0 (original numbering): the moving forces and the wheels' static
    /// loads, with the FE–SEA terms; the correction's H_{−1} = H_0 (no derivative term at the
    /// start: the initial state is the corrected model's equilibrium under the corrected loads).
    fn initial_load(&mut self, v: &Vehicles<W>) -> Vec<f64> {
        let st = &self.model.structure;
        let mut f0 = vec![0.0; st.n_dofs];
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
        for wi in 0..v.n_wheels() {
            add(0, v.x0[wi], v.loads[wi], v.patch[wi]);
        }
        if let Some(rc) = self.correction.as_mut() {
            rc.g_prev = vec![g0; W];
            rc.set_rows(v.x0.iter().copied(), 0.0, 0.0);
        }
        f0
    }

    /// Lane `j`'s state at t = 0 from its own matrices (its dampers' parameters), as in a
    /// single run; lanes with the model's own parameters share one solve (`own_state`).
    /// Returns the rail's displacement at each wheel.
    fn lane_state(
        &mut self,
        j: usize,
        f0: &[f64],
        v: &Vehicles<W>,
        own_state: &mut Option<(Vec<f64>, Vec<f64>)>,
    ) -> Result<Vec<f64>> {
        let cfg = &self.model.cfg;
        let st = &self.model.structure;
        let n = st.n_dofs;
        let own = st
            .dampers
            .iter()
            .map(|a| a.params)
            .eq(self.dampers[j].iter().copied());
        let lane_mk;
        let (m_l, k_l) = if own {
            (&st.m, &st.k)
        } else {
            lane_mk = st.with_damper_params(&self.dampers[j]);
            (&lane_mk.0, &lane_mk.1)
        };
        let (u0, a0) = match (&*own_state, own) {
            (Some(s), true) => s.clone(),
            _ => {
                let u0 = match cfg.solver.initial_state {
                    InitialState::Static => Ldlt::new(k_l)
                        .map_err(|e| VtbError::Solver(format!("static stiffness: {e}")))?
                        .solve(f0),
                    InitialState::Rest => vec![0.0; n],
                };
                let a0 = accelerations(m_l, k_l, &u0, f0)?;
                if own {
                    *own_state = Some((u0.clone(), a0.clone()));
                }
                (u0, a0)
            }
        };
        self.track.set_state(j, &u0, &vec![0.0; n], &a0, k_l, m_l);
        // Substructured: the wheel also stands on its static flexibility in series with its
        // contact (the truncated interior modes' share is not small), so that it starts at
        // rest, and the residual filters hold the loads.
        let held: Vec<f64> = match cfg.solver.initial_state {
            InitialState::Static => v.loads.clone(),
            InitialState::Rest => vec![0.0; v.n_wheels()],
        };
        let series = |x: f64, patch: f64| {
            let element = if self.element_flexibility && st.reduced.is_some() {
                st.element_flexibility(x, patch)
            } else {
                0.0
            };
            element + st.wheel_residual(x, patch)[0]
        };
        let rail = (0..v.n_wheels())
            .map(|wi| {
                let under = series(v.x0[wi], v.patch[wi]) * held[wi];
                st.wheel_shape_into(v.x0[wi], v.patch[wi], &mut self.wheel_shape);
                dot(&self.wheel_shape.values, &u0[self.wheel_shape.start..]) + under
            })
            .collect();
        if let Some(r) = self.residual.as_mut() {
            r.hold(j, &held);
        }
        Ok(rail)
    }
}

#[cfg(test)]
mod tests;

/// Observers of the bottom layer's bending moment at `points` when `wanted`; their count.
fn observe_moments<const W: usize>(
    track: &mut Newmark<W>,
    st: &Structure,
    wanted: bool,
    points: &[f64],
) -> usize {
    if !wanted || st.layers.is_empty() {
        return 0;
    }
    for &x in points {
        track.observe(&st.moment_shape(st.layers.len() - 1, x));
    }
    points.len()
}
