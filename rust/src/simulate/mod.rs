//! Coupled runs (track + cars + contact): one at a time, or many jobs that share a model in
//! lockstep (`Simulation` with W lanes, grouped automatically by `run_batch`).

use crate::basis::Shape;
use crate::config::{Config, InitialState, Profile};
use crate::contact::{ContactSolver, compression, patch_half_length};
use crate::dampers::DamperParams;
use crate::error::{Result, VtbError};
use crate::fesea::FeSea;
use crate::integrator::{GW, Newmark, PortBlock};
use crate::linalg::sparse::{Assembler, CsrMatrix, Ldlt};
use crate::model::Model;
use crate::results::{ContactLoss, Record, RunResult};
use crate::synthesis::{self, Reduction};
use crate::vehicle::Vehicle;
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

mod step;

/// Validates, assembles and integrates one configuration.
pub fn simulate(cfg: &Config, profile: &Profile, cancel: Option<&Control>) -> Result<RunResult> {
    simulate_with(cfg, profile, None, cancel)
}

/// `simulate` with the structure's reduction, which a configuration with
/// `discretisation.synthesis_cutoff` needs.
pub fn simulate_with(
    cfg: &Config,
    profile: &Profile,
    reduction: Option<&Reduction>,
    cancel: Option<&Control>,
) -> Result<RunResult> {
    let model = Model::new(cfg.clone(), profile.clone())?;
    match engine(cfg, reduction)? {
        Some(red) => synthesis::run(
            &model,
            &LaneSpec::of(cfg, profile),
            red,
            Record::Full,
            cancel,
        ),
        None => Simulation::new(&model)?.run(cancel),
    }
}

/// The reduction a configuration runs on (`None`: the Newmark engine); a synthesis without
/// its reduction, or a reduction for a configuration without synthesis, is refused.
fn engine<'r>(cfg: &Config, reduction: Option<&'r Reduction>) -> Result<Option<&'r Reduction>> {
    match (cfg.discretisation.synthesis_cutoff, reduction) {
        (Some(_), Some(r)) => Ok(Some(r)),
        (None, None) => Ok(None),
        (Some(fc), None) => Err(VtbError::config(
            "discretisation.synthesis_cutoff",
            fc,
            "the synthesis needs the structure's reduction (vtb.synthesis.reduction(config))",
        )),
        (None, Some(_)) => Err(VtbError::config(
            "discretisation.synthesis_cutoff",
            "None",
            "a reduction was given for a configuration that does not ask for the synthesis",
        )),
    }
}

/// What the caller of a run sees and steers while it runs, from another thread: the cancel
/// flag, polled every [`CANCEL_POLL`] steps, and at each poll the steps done of the run's total
/// (for a progress bar).
#[derive(Debug, Default)]
pub struct Control {
    cancel: AtomicBool,
    done: AtomicUsize,
    total: AtomicUsize,
}

impl Control {
    pub fn new() -> Self {
        Self::default()
    }

    /// Asks the run to stop at its next poll (it ends with [`VtbError::Cancelled`]).
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    pub fn cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    /// (steps done, steps in all) at the last poll; (0, 0) before the first.
    pub fn progress(&self) -> (usize, usize) {
        (
            self.done.load(Ordering::Relaxed),
            self.total.load(Ordering::Relaxed),
        )
    }
}

/// A run's poll at `step` of `total`: notes its progress and says whether to stop.
pub(crate) fn poll(control: Option<&Control>, step: usize, total: usize) -> bool {
    control.is_some_and(|c| {
        c.done.store(step, Ordering::Relaxed);
        c.total.store(total, Ordering::Relaxed);
        c.cancelled()
    })
}

/// Steps between polls of the cancel flag (well under a second on every model).
pub(crate) const CANCEL_POLL: usize = 64;
/// Steps between checks that every state is finite.
pub(crate) const FINITE_POLL: usize = 1024;
/// The widest lockstep group the engine compiles.
pub const MAX_LANES: usize = 8;
/// The default widest group, chosen by measurement (`cargo bench --bench lockstep`, docs).
pub const DEFAULT_LANES: usize = 4;
/// The default widest group on a reduction: its lanes share the wheels' modal shapes, a
/// pass over a few rows of ψ per wheel and step (measured, docs/synthesis.md: 8 lanes on 2
/// cores run a TID sweep's cases 1.35× faster than 4).
pub const SYNTHESIS_LANES: usize = 8;

/// One job of a batch: a configuration and its (possibly shared) irregularity profile.
#[derive(Clone, Debug)]
pub struct Job {
    pub config: Config,
    pub profile: Arc<Profile>,
}

/// What a lane of a lockstep group owns: its irregularity and its dampers' parameters.
#[derive(Clone, Debug)]
pub struct LaneSpec<'a> {
    pub profile: &'a Profile,
    /// One per damper of the model (empty without dampers).
    pub dampers: Vec<DamperParams>,
}

impl<'a> LaneSpec<'a> {
    pub fn of(config: &Config, profile: &'a Profile) -> Self {
        Self {
            profile,
            dampers: config.damper_params(),
        }
    }
}

/// Jobs that may share one model: configurations equal up to the dampers' parameters.
pub fn model_key(cfg: &Config) -> String {
    let mut c = cfg.clone();
    for t in c.tids.iter_mut().chain(c.dampers.iter_mut()) {
        (t.inertance, t.stiffness, t.damping) = (0.0, 0.0, 0.0);
    }
    serde_json::to_string(&c).expect("a config serialises")
}

/// Lockstep widths for `n` jobs of one model on `threads` threads: powers of two up to
/// `max_lanes`, as wide as possible while every thread gets a group.
fn lane_widths(n: usize, threads: usize, max_lanes: usize) -> Vec<usize> {
    let pow2_floor = |k: usize| 1usize << (usize::BITS - 1 - k.leading_zeros());
    let w = pow2_floor(
        n.div_ceil(threads.max(1))
            .clamp(1, max_lanes.clamp(1, MAX_LANES)),
    );
    let mut sizes = vec![w; n / w];
    let mut left = n % w;
    while left > 0 {
        let p = pow2_floor(left);
        sizes.push(p);
        left -= p;
    }
    sizes
}

/// How `run_batch` runs its jobs.
#[derive(Clone, Copy, Debug)]
pub struct BatchOptions {
    /// What each result keeps.
    pub record: Record,
    /// The widest lockstep group (1, 2, 4 or 8; 1 runs every job alone).
    pub max_lanes: usize,
}

impl Default for BatchOptions {
    fn default() -> Self {
        Self {
            record: Record::Metrics,
            max_lanes: DEFAULT_LANES,
        }
    }
}

/// Runs the jobs on the current rayon pool and returns each job's result or error, in input
/// order. Jobs whose configurations differ only in the dampers' parameters (the cases of a
/// sweep, the designs of a generation) or in their irregularity share one assembled model and
/// run in lockstep groups of up to `opts.max_lanes`; a job gives the same bits in a group as
/// alone, and a job that fails leaves its group running. `done` counts finished jobs.
pub fn run_batch(
    jobs: &[Job],
    opts: BatchOptions,
    cancel: Option<&Control>,
    done: Option<&AtomicUsize>,
) -> Vec<Result<RunResult>> {
    run_batch_with(jobs, opts, None, cancel, done)
}

/// `run_batch` with the structure's reduction for jobs that ask for the synthesis (shared by
/// all; its lockstep groups share the wheels' modal shapes as well).
pub fn run_batch_with(
    jobs: &[Job],
    opts: BatchOptions,
    reduction: Option<&Reduction>,
    cancel: Option<&Control>,
    done: Option<&AtomicUsize>,
) -> Vec<Result<RunResult>> {
    let out: Mutex<Vec<Option<Result<RunResult>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    run_batch_each(jobs, opts, reduction, cancel, &|finished| {
        if let Some(d) = done {
            d.fetch_add(finished.len(), Ordering::Relaxed);
        }
        let mut out = out.lock().unwrap_or_else(|e| e.into_inner());
        for (i, r) in finished {
            out[i] = Some(r);
        }
    });
    out.into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|r| r.expect("every job has a result"))
        .collect()
}

/// Receives results as they are known: (job index, result) pairs, a lockstep group's at once.
pub type Sink<'a> = &'a (dyn Fn(Vec<(usize, Result<RunResult>)>) + Sync);

/// `run_batch_with`, each lockstep group's results handed to `sink` as soon as the group
/// finishes (jobs refused before running first, together), so that a caller can keep finished
/// work while the batch goes on. Every job's result reaches the sink exactly once.
pub fn run_batch_each(
    jobs: &[Job],
    opts: BatchOptions,
    reduction: Option<&Reduction>,
    cancel: Option<&Control>,
    sink: Sink,
) {
    let record = opts.record;
    let mut refused = Vec::new();
    let mut keys: BTreeMap<String, usize> = BTreeMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        if let Err(e) = job
            .config
            .validate(&job.profile)
            .and_then(|_| engine(&job.config, reduction).map(|_| ()))
        {
            refused.push((i, Err(e)));
            continue;
        }
        let g = *keys.entry(model_key(&job.config)).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(i);
    }
    if !refused.is_empty() {
        sink(refused);
    }
    let cancelled = || cancel.is_some_and(Control::cancelled);
    let threads = rayon::current_num_threads();
    groups.par_iter().for_each(|members| {
        let first = &jobs[members[0]];
        let model = if cancelled() {
            Err(VtbError::Cancelled)
        } else {
            Model::build(first.config.clone(), (*first.profile).clone())
        };
        let mut chunks = Vec::new();
        let mut at = 0;
        for w in lane_widths(members.len(), threads, opts.max_lanes) {
            chunks.push(&members[at..at + w]);
            at += w;
        }
        chunks.into_par_iter().for_each(|chunk| {
            let res = match &model {
                Err(e) => vec![Err(e.clone()); chunk.len()],
                Ok(_) if cancelled() => vec![Err(VtbError::Cancelled); chunk.len()],
                Ok(m) => run_lanes(m, jobs, chunk, record, reduction, cancel),
            };
            sink(chunk.iter().copied().zip(res).collect());
        });
    });
}

/// One lockstep group of `chunk.len()` ∈ {1, 2, 4, 8} jobs on a shared model (on its
/// reduction when the jobs ask for the synthesis).
fn run_lanes(
    model: &Model,
    jobs: &[Job],
    chunk: &[usize],
    record: Record,
    reduction: Option<&Reduction>,
    cancel: Option<&Control>,
) -> Vec<Result<RunResult>> {
    let lanes: Vec<LaneSpec> = chunk
        .iter()
        .map(|&i| LaneSpec::of(&jobs[i].config, &jobs[i].profile))
        .collect();
    fn go<const W: usize>(
        model: &Model,
        lanes: &[LaneSpec],
        record: Record,
        reduction: Option<&Reduction>,
        cancel: Option<&Control>,
    ) -> Vec<Result<RunResult>> {
        let out = match reduction {
            Some(red) => synthesis::run_lanes::<W>(model, lanes, red, record, cancel),
            None => Simulation::<W>::lanes(model, lanes, record).and_then(|s| s.run_lanes(cancel)),
        };
        out.unwrap_or_else(|e| vec![Err(e); W])
    }
    match lanes.len() {
        1 => go::<1>(model, &lanes, record, reduction, cancel),
        2 => go::<2>(model, &lanes, record, reduction, cancel),
        4 => go::<4>(model, &lanes, record, reduction, cancel),
        8 => go::<8>(model, &lanes, record, reduction, cancel),
        w => unreachable!("lane width {w}"),
    }
}

/// A constant force moving with the common speed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mover {
    pub(crate) layer: usize,
    pub(crate) x0: f64,
    pub(crate) magnitude: f64,
}

impl Mover {
    /// The moving forces of a configuration.
    pub(crate) fn all(cfg: &Config) -> Vec<Mover> {
        cfg.forces
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
            .collect()
    }
}

/// A car's own Newmark stepper (one lane per job); its contact ports are the wheelset DOFs.
pub(crate) struct CarRun<const W: usize> {
    pub(crate) car: Vehicle,
    pub(crate) nm: Newmark<W>,
    m: CsrMatrix,
    k: CsrMatrix,
    pub(crate) ports: PortBlock<W>,
    /// Wheelset compliance over one step for unit port forces (constant, the same in every
    /// lane).
    pub(crate) compliance: [[f64; GW]; GW],
    pub(crate) gravity: Vec<f64>,
    pub(crate) f_prev: Vec<f64>,
    /// The static state of each lane (`[dof·W + lane]`).
    pub(crate) z0: Vec<f64>,
}

impl<const W: usize> CarRun<W> {
    pub(crate) fn new(car: &Vehicle, dt: f64, g: f64) -> Result<Self> {
        let nd = car.n_dofs();
        let dense = |m: &[f64]| {
            let mut a = Assembler::new(nd);
            for i in 0..nd {
                for j in 0..nd {
                    a.add(i, j, m[i * nd + j]);
                }
            }
            a.finish()
        };
        let mut am = Assembler::new(nd);
        for i in 0..nd {
            am.add(i, i, car.mass[i]);
        }
        let (m, c, k) = (am.finish(), dense(&car.c), dense(&car.k));
        let mut nm = Newmark::<W>::new(&m, &c, &k, dt, &[], 1, None, &[])?;
        for i in 0..nd {
            nm.observe(&Shape {
                start: i,
                values: vec![1.0],
            });
        }
        let mut ports = PortBlock::new(nd);
        for (w, &d) in car.wheel_dofs.iter().enumerate() {
            ports.vecs[w] = nm.vector(&Shape {
                start: d,
                values: vec![1.0],
            });
        }
        nm.prepare_ports(&mut ports);
        let compliance = nm.port_compliance(&ports, &ports)[0];
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
            z0: vec![0.0; nd * W],
        })
    }

    /// Lane `lane` at rest in static equilibrium on wheel contacts whose rail side (rail
    /// displacement plus irregularity, m) is `rail`, under the static wheel loads `loads` (N).
    pub(crate) fn set_static(
        &mut self,
        lane: usize,
        rail: &[f64],
        loads: &[f64],
        g: f64,
    ) -> Result<()> {
        let zw: Vec<f64> = (rail.iter().zip(loads))
            .map(|(r, &l)| r + compression(self.car.hertz_g, l))
            .collect();
        let (_, z) = self.car.static_state(g, &zw);
        let mut f = self.car.gravity(g);
        for (&d, l) in self.car.wheel_dofs.iter().zip(loads) {
            f[d] -= self.car.rails * l;
        }
        let av = accelerations(&self.m, &self.k, &z, &f)?;
        let nd = z.len();
        self.nm
            .set_state(lane, &z, &vec![0.0; nd], &av, &self.k, &self.m);
        for i in 0..nd {
            self.z0[i * W + lane] = z[i];
        }
        Ok(())
    }

    /// Gravity minus rails·P on the wheelsets (stepper coordinates) into `f_prev`.
    pub(crate) fn set_force(&mut self, p: &[[f64; GW]; W]) {
        self.f_prev.clone_from(&self.gravity);
        for (lane, pl) in p.iter().enumerate() {
            for w in 0..self.car.n_wheels() {
                self.ports.vecs[w].add_to_lane::<W>(
                    &mut self.f_prev,
                    lane,
                    -self.car.rails * pl[w],
                );
            }
        }
    }
}

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

/// Static wheel loads on the modelled rail (N) of every car's wheelsets, from the statics of
/// each (statically determinate) car.
pub(crate) fn static_wheel_loads<const W: usize>(cars: &[CarRun<W>], g: f64) -> Vec<f64> {
    cars.iter()
        .flat_map(|c| {
            let (r, _) = c.car.static_state(g, &vec![0.0; c.car.n_wheels()]);
            r.into_iter().map(|ri| ri / c.car.rails).collect::<Vec<_>>()
        })
        .collect()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
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
    scratch: crate::integrator::SVec,
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
        crate::budget::check_histories(cfg, record, W)?;
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

/// a = M⁻¹(F − K·u) for a subsystem at rest.
pub(crate) fn accelerations(
    m: &CsrMatrix,
    k: &CsrMatrix,
    u: &[f64],
    f: &[f64],
) -> Result<Vec<f64>> {
    let mut ku = vec![0.0; u.len()];
    k.mul(u, &mut ku);
    let r: Vec<f64> = f.iter().zip(&ku).map(|(a, b)| a - b).collect();
    if r.iter().all(|v| *v == 0.0) {
        return Ok(vec![0.0; u.len()]);
    }
    Ok(Ldlt::new(m)?.solve(&r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::DamperGroup;
    use crate::dampers::DamperKind;
    use crate::presets;

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
        let model = Model::new(cfg.clone(), smooth.clone()).unwrap();
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
        let e = cfg.validate(&p).unwrap_err().to_string();
        assert!(e.contains("irregularity.treads"), "{e}");
        let wheels = cfg.vehicles.len() * 4;
        let mut rows = vec![Vec::new(); wheels];
        rows[1] = vec![0.0; 10];
        let e = cfg
            .validate(&Profile {
                treads: rows,
                ..p.clone()
            })
            .unwrap_err()
            .to_string();
        assert!(e.contains("irregularity.treads[1]"), "{e}");
        let mut rows = vec![Vec::new(); wheels];
        rows[0] = vec![0.0; 20_000];
        rows[0][7] = f64::INFINITY;
        let e = cfg
            .validate(&Profile { treads: rows, ..p })
            .unwrap_err()
            .to_string();
        assert!(e.contains("irregularity.treads[0][7]"), "{e}");
    }

    #[test]
    fn lane_widths_keep_every_thread_busy() {
        assert_eq!(lane_widths(16, 2, 4), vec![4, 4, 4, 4]);
        assert_eq!(lane_widths(8, 2, 8), vec![4, 4]);
        assert_eq!(lane_widths(7, 1, 8), vec![4, 2, 1]);
        assert_eq!(lane_widths(3, 2, 4), vec![2, 1]);
        assert_eq!(lane_widths(1, 8, 4), vec![1]);
        assert_eq!(lane_widths(21, 1, 8), vec![8, 8, 4, 1]);
    }
}
