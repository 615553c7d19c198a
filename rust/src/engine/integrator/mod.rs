//! Newmark average-acceleration integration (γ = ½, β = ¼) of the coupled system
//! (docs/model.md §7), with the Hertz contact forces iterated within each step.
//!
//! Newmark's average acceleration is the trapezoidal rule. Written with the mean velocity of
//! the step v̄ = (v_n + v_{n+1})/2 it reads
//!
//!   A·v̄ = q_n + Δt·F̄,   A = 2M + Δt·C + (Δt²/2)·K,   F̄ = (F_n + F_{n+1})/2,
//!   u_{n+1} = u_n + Δt·v̄,   q_{n+1} = (4M − Δt²K)·v̄ − q_n − 2Δt·s_n,   s_{n+1} = s_n + Δt·K·v̄,
//!
//! with q_n = 2M·v_n − Δt·K·u_n and s_n = K·u_n carried from step to step. A is factorised
//! once; a step costs the products M·v̄ and K·v̄ and one solve with A. Accelerations are those of Newmark's scheme,
//! a_{n+1} = 4(v̄ − v_n)/Δt − a_n, evaluated at observation vectors only.
//!
//! Contact forces act through *ports*: a port of a subsystem has a force vector f (where the
//! force enters) and a displacement vector n (what the contact sees); for the rail both are
//! the shape vector at the wheel (f also carries the FE–SEA force correction in the hybrid
//! model), for a car both are the unit vector of a wheelset DOF. The port displacements at
//! t_{n+1} are affine in the unknown forces with the compliance (Δt²/2)·n_iᵀA⁻¹f_j, so the
//! contact Newton iterates on the wheel forces alone. With P·A·Pᵀ = L·D·Lᵀ that compliance is
//! (L⁻¹n_i)ᵀD⁻¹(L⁻¹f_j): long (modal) port vectors are forward-substituted together with the
//! right-hand side and one backward substitution of the combined right-hand side finishes the
//! step; short ones use cached columns of A⁻¹.
//!
//! A stepper advances W jobs of one model in lockstep (lanes; W = 1 for a single run): the
//! factor of A, the ports and the dampers' positions are shared, each lane has its own state,
//! forces and damper parameters, stored interleaved, and does exactly the operations of a
//! single run (docs/batches.md).
//!
//! Dampers (`Attachment`, crate::model::dampers) are not factorised with A: a damper's point shape
//! vectors would fill the sparse factor. Its internal node is eliminated within the step
//! (upper branch α_r in series with lower branch α_s, `Branch::step_impedance`), leaving the rank-one
//! term κ·w·wᵀ on A, w = N_upper − N_lower, κ = α_rα_s/(α_r + α_s), which the Woodbury identity
//! A⁻¹ = A₀⁻¹ − Y·S⁻¹·Yᵀ (Y = A₀⁻¹W, S = K⁻¹ + WᵀA₀⁻¹W) applies with precomputed Y.
//!
//! - `mod.rs` (this file): the stepper [`Newmark`], its set-up, state and step;
//! - `ports`: sparse vectors ([`SVec`]), the contact ports ([`PortBlock`]) and the stepper's
//!   port operations (free displacements, compliance, forces), cached columns of A⁻¹;
//! - `woodbury`: the dampers' Woodbury data and their parts of the step.

mod ports;
mod woodbury;

use crate::error::Result;
use crate::linalg::banded::{BlockLayout, BlockLdlt, BlockPair, BlockTri, PAD};
use crate::linalg::sparse::{CsrMatrix, Ldlt, SymOperator};
use crate::model::basis::Shape;
use crate::model::dampers::Attachment;
use ports::Columns;
pub use ports::{PortBlock, SVec};
use woodbury::Attached;

/// Port columns processed together: one vehicle's wheels, at most `vehicle::MAX_WHEELS`.
pub const GW: usize = crate::model::vehicle::MAX_WHEELS;
/// Port vectors with at most this many entries use cached columns of A⁻¹.
const COLUMN_PORTS_MAX_LEN: usize = 16;

/// The factorised time-stepping matrix A and the products M·v̄, K·v̄ in one pass.
// One engine per run, never in a collection: the size difference of the variants costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
enum Engine {
    /// General sparse LDLᵀ (modal bases, cars).
    Sparse { factor: Ldlt, mk: SymOperator },
    /// Block tridiagonal (finite elements numbered node by node).
    Blocks { factor: BlockLdlt, mk: BlockPair },
}

impl Engine {
    /// z ← A⁻¹·z for W interleaved right-hand sides that are zero before unknown `start`.
    fn solve_from<const W: usize>(&self, z: &mut [f64], start: usize) {
        match self {
            Engine::Sparse { factor, .. } => {
                factor.forward::<W>(z, start);
                factor.diag_backward::<W>(z);
            }
            Engine::Blocks { factor, .. } => factor.solve_from::<W>(z, start / factor.block_size()),
        }
    }

    fn mul2<const W: usize>(&self, x: &[f64], ym: &mut [f64], yk: &mut [f64]) {
        match self {
            Engine::Sparse { mk, .. } => mk.mul2::<W>(x, ym, yk),
            Engine::Blocks { mk, .. } => mk.mul2::<W>(x, ym, yk),
        }
    }

    /// The sparse factor, for forward-substituted ports (only chosen with it).
    fn sparse(&self) -> &Ldlt {
        match self {
            Engine::Sparse { factor, .. } => factor,
            Engine::Blocks { .. } => unreachable!("forward ports need the sparse factor"),
        }
    }
}

/// How a stepper numbers the unknowns it factorises.
#[derive(Clone, Copy, Debug)]
pub enum Numbering<'a> {
    /// The cheapest of a few general orderings by an estimate of one step's work
    /// (`Ldlt::for_stepping`): modal bases, cars.
    Search,
    /// The unknowns grouped by node: the block solver if the matrices are block tridiagonal
    /// in that grouping (finite elements on one mesh), else `Search`.
    Blocks(&'a [Vec<usize>]),
    /// This elimination order (finite elements on meshes of their own, ordered along the
    /// track), or AMD where it fills less and no contact asks for columns of A⁻¹: both
    /// factors cost O(length), so the general search's costly trials are skipped.
    Order(&'a [usize]),
    /// This elimination order, along the track (substructured coordinates): a port vector's
    /// forward substitution then decays along it, which `Newmark::set_port_reach` uses.
    Along(&'a [usize]),
}

/// Newmark stepper of one linear subsystem M·ü + C·u̇ + K·u = F for W jobs in lockstep
/// (lanes). The lanes share the matrices, the factor of A, the dampers' positions and the
/// ports; their states, forces and damper parameters are their own, stored interleaved
/// (`[i·W + lane]`) so that each matrix entry is loaded once for all lanes. Every lane does
/// the operations of a single run (W = 1 uses the single-vector kernels). Vectors, forces and
/// observations live in the stepper's numbering (the elimination order of the factor of A,
/// with padding slots for block factors).
#[derive(Clone, Debug)]
pub struct Newmark<const W: usize = 1> {
    /// Length of one lane's stepper vectors: the factorised unknowns (`ns`), then the
    /// damper nodes.
    pub n: usize,
    ns: usize,
    pub dt: f64,
    engine: Engine,
    att: Attached,
    /// Stepper → original index (`PAD` for padding) and original → stepper index.
    perm: Vec<usize>,
    inv: Vec<usize>,
    /// Displacements (all lanes).
    u: Vec<f64>,
    q: Vec<f64>,
    s: Vec<f64>,
    /// During a step the forward-substituted right-hand side (forward ports) or the free mean
    /// velocity A⁻¹·b (column ports); v̄ after `end_step`.
    z: Vec<f64>,
    /// Column ports: columns of A⁻¹ at the unknowns port vectors touch (stepper numbering),
    /// computed on first use.
    columns: Option<Columns>,
    /// Forward ports with force vectors: (k, L⁻¹·P·e_k from row k on) for the few unknowns k
    /// where force and displacement vectors differ.
    units: Vec<(usize, Vec<f64>)>,
    /// Rows past a forward port's last entry that its forward substitution keeps
    /// (`set_port_reach`; unbounded by default).
    port_reach: usize,
    y1: Vec<f64>,
    y2: Vec<f64>,
    obs: Vec<SVec>,
    obs_v: Vec<f64>,
    obs_a: Vec<f64>,
}

impl<const W: usize> Newmark<W> {
    /// `ports` lists the unknowns contact forces act on (eliminated late so that port vectors
    /// forward-substitute cheaply); `port_len` is the number of entries of a port vector.
    /// Short port vectors (finite elements, car wheelsets) use *column ports*: the columns of
    /// A⁻¹ at the few unknowns they touch are cached, so a step needs one full solve and a few
    /// axpys. Long ones (modal layers) are forward-substituted with the right-hand side.
    /// `numbering` says how the unknowns are ordered for the factor (`Numbering`). `attachments` are dampers
    /// whose nodes are the DOFs after those of m, c, k (which exclude the dampers); every lane
    /// starts with their parameters (`set_damper_params` changes a lane's).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        m: &CsrMatrix,
        c: &CsrMatrix,
        k: &CsrMatrix,
        dt: f64,
        ports: &[usize],
        port_len: usize,
        numbering: Numbering<'_>,
        attachments: &[Attachment],
    ) -> Result<Self> {
        const { assert!(W >= 1 && W <= 8, "1 to 8 lanes") };
        let a = CsrMatrix::combine(&[(2.0, m), (dt, c), (0.5 * dt * dt, k)]);
        let layout = match numbering {
            Numbering::Blocks(g) => {
                BlockLayout::new(g, &CsrMatrix::combine(&[(1.0, &a), (1.0, m), (1.0, k)]))
            }
            _ => None,
        };
        let (engine, perm, inv) = match layout {
            Some(lay) => {
                let factor = BlockLdlt::new(&BlockTri::new(&a, &lay), &lay)?;
                let mk = BlockPair::new(&BlockTri::new(m, &lay), &BlockTri::new(k, &lay));
                (Engine::Blocks { factor, mk }, lay.perm, lay.inv)
            }
            None => {
                let factor = match numbering {
                    // Wheels crossing a short-port structure keep asking for new columns of
                    // A⁻¹: along the track each is a window (`Ldlt::column_window`), with AMD
                    // the whole structure. Without them AMD, linear too on a track, wins
                    // where it fills less (a solve's work is L's entries).
                    Numbering::Order(order)
                        if !ports.is_empty() && port_len <= COLUMN_PORTS_MAX_LEN =>
                    {
                        Ldlt::with_ordering(&a, Some(order))?
                    }
                    Numbering::Order(order) => {
                        let (along, amd) = (Ldlt::with_ordering(&a, Some(order))?, Ldlt::new(&a)?);
                        if amd.nnz_l() < along.nnz_l() {
                            amd
                        } else {
                            along
                        }
                    }
                    Numbering::Along(order) => Ldlt::with_ordering(&a, Some(order))?,
                    _ => Ldlt::for_stepping(&a, ports)?,
                };
                let mk = SymOperator::new(&[m, k], &factor.perm);
                let (perm, inv) = (factor.perm.clone(), factor.inv.clone());
                (Engine::Sparse { factor, mk }, perm, inv)
            }
        };
        let ns = perm.len();
        let (mut perm, mut inv) = (perm, inv);
        for (i, a) in attachments.iter().enumerate() {
            debug_assert_eq!(
                a.node,
                m.n + i,
                "damper nodes follow the factorised unknowns"
            );
            perm.push(a.node);
            inv.push(ns + i);
        }
        let n = perm.len();
        let column_ports =
            port_len <= COLUMN_PORTS_MAX_LEN || matches!(engine, Engine::Blocks { .. });
        let mut nm = Self {
            n,
            ns,
            dt,
            engine,
            att: Attached::default(),
            perm,
            inv,
            u: vec![0.0; n * W],
            q: vec![0.0; n * W],
            s: vec![0.0; n * W],
            z: vec![0.0; n * W],
            columns: column_ports.then(Columns::default),
            units: Vec::new(),
            port_reach: usize::MAX,
            y1: vec![0.0; n * W],
            y2: vec![0.0; n * W],
            obs: Vec::new(),
            obs_v: Vec::new(),
            obs_a: Vec::new(),
        };
        nm.attach(attachments)?;
        Ok(nm)
    }

    /// A shape vector (original numbering) in the stepper's numbering, into `out`.
    #[inline]
    pub fn vector_into(&self, shape: &Shape, out: &mut SVec) {
        let key = (shape.start, shape.values.len());
        if out.key != Some(key) {
            out.idx.clear();
            out.idx
                .extend((0..key.1).map(|k| self.inv[shape.start + k]));
            out.val.resize(key.1, 0.0);
            out.key = Some(key);
        }
        out.val.copy_from_slice(&shape.values);
    }

    pub fn vector(&self, shape: &Shape) -> SVec {
        let mut v = SVec::default();
        self.vector_into(shape, &mut v);
        v
    }

    /// A dense vector (original numbering) in the stepper's numbering, the same in every lane.
    pub fn to_stepper(&self, x: &[f64]) -> Vec<f64> {
        self.perm
            .iter()
            .flat_map(|&i| [if i == PAD { 0.0 } else { x[i] }; W])
            .collect()
    }

    /// Registers an observation vector (original numbering); returns its index.
    /// Keeps a forward port's L⁻¹n only over `reach` unknowns past its last entry: where the
    /// numbering runs along the track (`Numbering::Along`), L⁻¹n decays along it, so the rows
    /// beyond hold nothing a step needs (the substructured engine: a few substructures on).
    pub fn set_port_reach(&mut self, reach: usize) {
        self.port_reach = reach;
    }

    pub fn observe(&mut self, shape: &Shape) -> usize {
        let v = self.vector(shape);
        self.obs.push(v);
        self.obs_v.extend([0.0; W]);
        self.obs_a.extend([0.0; W]);
        self.obs.len() - 1
    }

    /// Sets lane `lane`'s state at t = 0 from displacements, velocities and accelerations
    /// (original numbering) and that lane's K and M. The acceleration only seeds the observed
    /// Newmark acceleration recursion, which carries any error in a₀ forever, so it must
    /// satisfy the equation of motion.
    #[allow(clippy::too_many_arguments)]
    pub fn set_state(
        &mut self,
        lane: usize,
        u0: &[f64],
        v0: &[f64],
        a0: &[f64],
        k: &CsrMatrix,
        m: &CsrMatrix,
    ) {
        let n = self.inv.len();
        let (mut ku, mut mv) = (vec![0.0; n], vec![0.0; n]);
        k.mul(u0, &mut ku);
        m.mul(v0, &mut mv);
        let put = |dst: &mut [f64], x: &dyn Fn(usize) -> f64| {
            for (slot, &i) in self.perm.iter().enumerate() {
                dst[slot * W + lane] = if i == PAD { 0.0 } else { x(i) };
            }
        };
        put(&mut self.q, &|i| 2.0 * mv[i] - self.dt * ku[i]);
        put(&mut self.s, &|i| ku[i]);
        put(&mut self.u, &|i| u0[i]);
        for (j, o) in self.obs.iter().enumerate() {
            let at = |x: &[f64]| -> f64 {
                o.idx
                    .iter()
                    .zip(&o.val)
                    .map(|(&k, v)| {
                        let i = self.perm[k];
                        if i == PAD { 0.0 } else { v * x[i] }
                    })
                    .sum()
            };
            self.obs_v[j * W + lane] = at(v0);
            self.obs_a[j * W + lane] = at(a0);
        }
    }

    /// Zeroes a lane's state (a failed job: its lane then stays finite and idle).
    pub fn clear_lane(&mut self, lane: usize) {
        for v in [&mut self.u, &mut self.q, &mut self.s, &mut self.z] {
            for x in v.iter_mut().skip(lane).step_by(W) {
                *x = 0.0;
            }
        }
        for v in [&mut self.obs_v, &mut self.obs_a] {
            for x in v.iter_mut().skip(lane).step_by(W) {
                *x = 0.0;
            }
        }
    }

    /// Whether a lane's displacements and observations are all finite.
    pub fn lane_finite(&self, lane: usize) -> bool {
        self.u.iter().skip(lane).step_by(W).all(|v| v.is_finite())
            && (0..self.obs.len()).all(|j| self.observed(j, lane).2.is_finite())
    }

    /// Displacement, velocity and acceleration of observation `j` in lane `lane`.
    pub fn observed(&self, j: usize, lane: usize) -> (f64, f64, f64) {
        (
            self.obs[j].dot_lane::<W>(&self.u, lane),
            self.obs_v[j * W + lane],
            self.obs_a[j * W + lane],
        )
    }

    pub fn n_observed(&self) -> usize {
        self.obs.len()
    }

    /// Starts a step with the known forces F_n and F_{n+1} (stepper numbering, all lanes).
    pub fn begin_step(&mut self, f_prev: &[f64], f_next: &[f64]) {
        if let Some(cache) = &mut self.columns {
            cache.begin_step();
        }
        let h = 0.5 * self.dt;
        for (((z, q), fp), fnx) in self.z.iter_mut().zip(&self.q).zip(f_prev).zip(f_next) {
            *z = q + h * (fp + fnx);
        }
        // Damper nodes: a_d·v̄_d = b_d + (α_r·N_upper + α_s·N_lower)ᵀv̄, eliminated.
        let att = &mut self.att;
        let nt = att.len();
        if nt > 0 {
            for i in 0..nt {
                for lane in 0..W {
                    let q = i * W + lane;
                    let g = self.z[att.node[i] * W + lane] / (att.alpha_r[q] + att.alpha_s[q]);
                    att.wu[q] = att.alpha_r[q] * g;
                    att.wl[q] = att.alpha_s[q] * g;
                }
            }
            att.upper.add_to::<W>(&mut self.z, &att.wu);
            att.lower.add_to::<W>(&mut self.z, &att.wl);
        }
        let ns = self.ns;
        if self.columns.is_some() {
            self.engine.solve_from::<W>(&mut self.z[..ns * W], 0);
        } else {
            self.engine.sparse().forward::<W>(&mut self.z[..ns * W], 0);
        }
        if nt > 0 {
            if self.columns.is_some() {
                self.att.w_dots::<W>(&self.z);
            } else {
                crate::wide!(<W> (wz: &mut [f64] = &mut self.att.wz, lw: &[Vec<f64>] = &self.att.lw, z: &[f64] = &self.z[..ns * W]) {
                    for (w, l) in wz.chunks_exact_mut(W).zip(lw) {
                        w.copy_from_slice(&crate::linalg::simd::dot_lanes::<W>(l, z));
                    }
                });
            }
            let mut t = std::mem::take(&mut self.att.t_free);
            self.att.s_solve::<W>(&self.att.wz, &mut t);
            self.att.t_free = t;
        }
    }

    /// Finishes the step: back-substitution for v̄ and the state update.
    pub fn end_step(&mut self) {
        let (dt, ns) = (self.dt, self.ns);
        if self.columns.is_none() {
            self.engine
                .sparse()
                .diag_backward::<W>(&mut self.z[..ns * W]);
        }
        self.finish_dampers();
        self.engine.mul2::<W>(
            &self.z[..ns * W],
            &mut self.y1[..ns * W],
            &mut self.y2[..ns * W],
        );
        self.damper_products();
        let (u, q, sv, z, y1, y2) = (
            &mut self.u[..],
            &mut self.q[..],
            &mut self.s[..],
            &self.z[..],
            &self.y1[..],
            &self.y2[..],
        );
        for (((((uk, qk), sk), zk), mk), kk) in u
            .iter_mut()
            .zip(q.iter_mut())
            .zip(sv.iter_mut())
            .zip(z)
            .zip(y1)
            .zip(y2)
        {
            *uk += dt * zk;
            *qk = 4.0 * mk - dt * dt * kk - *qk - 2.0 * dt * *sk;
            *sk += dt * kk;
        }
        for (j, o) in self.obs.iter().enumerate() {
            for lane in 0..W {
                let nv = o.dot_lane::<W>(&self.z, lane);
                let (ov, oa) = (&mut self.obs_v[j * W + lane], &mut self.obs_a[j * W + lane]);
                *oa = 4.0 * (nv - *ov) / dt - *oa;
                *ov = 2.0 * nv - *ov;
            }
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
mod tests;
