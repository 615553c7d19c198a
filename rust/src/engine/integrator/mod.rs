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

use crate::config::DamperParams;
use crate::error::Result;
use crate::linalg::banded::{BlockLayout, BlockLdlt, BlockPair, BlockTri, PAD};
use crate::linalg::sparse::{CsrMatrix, Ldlt, SymOperator};
use crate::model::basis::Shape;
use crate::model::dampers::Attachment;

/// Port columns processed together: one vehicle's wheels, at most `vehicle::MAX_WHEELS`.
pub const GW: usize = crate::model::vehicle::MAX_WHEELS;
/// Port vectors with at most this many entries use cached columns of A⁻¹.
const COLUMN_PORTS_MAX_LEN: usize = 16;
/// Cached columns kept before unused ones are dropped.
const COLUMN_CACHE: usize = 256;
/// Entries of a cached column of A⁻¹ below this fraction of its largest are dropped: they lie
/// below the rounding of every sum they enter. A = 2M + Δt·C + (Δt²/2)·K is dominated by its
/// mass part, so its inverse decays geometrically away from the diagonal (finite elements:
/// about tenfold per node at Δt = 5e-5 s) and a column shrinks to a window of a few dozen nodes.
const COLUMN_DROP: f64 = 1.0 / (1u64 << 60) as f64;

/// A column of A⁻¹ restricted to the window `start..start + values.len()` outside which its
/// entries are negligible (`COLUMN_DROP`).
#[derive(Clone, Debug)]
struct Column {
    start: usize,
    values: Vec<f64>,
}

impl Column {
    fn new(full: &[f64]) -> Self {
        let big = full.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let keep = |v: &f64| v.abs() > COLUMN_DROP * big;
        let start = full.iter().position(keep).unwrap_or(0);
        let end = full.iter().rposition(keep).map_or(start, |e| e + 1);
        Self {
            start,
            values: full[start..end].to_vec(),
        }
    }

    /// vᵀ·column.
    fn dot(&self, v: &SVec) -> f64 {
        v.idx
            .iter()
            .zip(&v.val)
            .filter_map(|(&i, &x)| self.values.get(i.wrapping_sub(self.start)).map(|c| c * x))
            .sum()
    }
}

/// A sparse vector in a stepper's numbering.
#[derive(Clone, Debug, Default)]
pub struct SVec {
    pub idx: Vec<usize>,
    pub val: Vec<f64>,
    /// (start, length) of the shape vector it was built from: a shape on the same DOFs
    /// (a modal layer at any x) only needs new values.
    key: Option<(usize, usize)>,
}

impl SVec {
    /// selfᵀ·x.
    #[inline]
    pub fn dot(&self, x: &[f64]) -> f64 {
        self.idx
            .iter()
            .zip(&self.val)
            .map(|(&i, &v)| v * x[i])
            .sum()
    }

    /// Becomes a copy of `other`, reusing the index list when it covers the same DOFs.
    pub fn copy_from(&mut self, other: &SVec) {
        if self.key != other.key || self.key.is_none() {
            self.idx.clone_from(&other.idx);
            self.key = other.key;
        }
        self.val.clone_from(&other.val);
    }

    /// x += w·self.
    #[inline]
    pub fn add_to(&self, x: &mut [f64], w: f64) {
        for (&i, &v) in self.idx.iter().zip(&self.val) {
            x[i] += w * v;
        }
    }

    /// selfᵀ·x for lane `lane` of W interleaved vectors.
    #[inline]
    pub fn dot_lane<const W: usize>(&self, x: &[f64], lane: usize) -> f64 {
        self.idx
            .iter()
            .zip(&self.val)
            .map(|(&i, &v)| v * x[i * W + lane])
            .sum()
    }

    /// x += w·self in lane `lane` of W interleaved vectors.
    #[inline]
    pub fn add_to_lane<const W: usize>(&self, x: &mut [f64], lane: usize, w: f64) {
        for (&i, &v) in self.idx.iter().zip(&self.val) {
            x[i * W + lane] += w * v;
        }
    }
}

/// Up to GW contact ports of one subsystem (one car's wheels) and the data the engine derives
/// from them each step. Everything but `sfy` is shared by the W lanes of a batch: the ports
/// sit where the wheels are, which all jobs of a batch share.
#[derive(Clone, Debug)]
pub struct PortBlock<const W: usize = 1> {
    /// The displacement vectors n_c (stepper coordinates): what the contact sees.
    pub vecs: [SVec; GW],
    /// The force vectors f_c where they differ from n_c (FE–SEA correction of the rail): same
    /// indices as `vecs`, different values at a few of them.
    pub force: Option<[SVec; GW]>,
    /// L⁻¹·P·n_c at `[k·GW + c]`, and L⁻¹·P·f_c from row `fstart` on (forward ports).
    cols: Vec<f64>,
    cols_f: Vec<f64>,
    /// First nonzero row in elimination order of `cols` and of `cols_f − cols`.
    start: usize,
    fstart: usize,
    /// With dampers: n_c·y_a and f_c·y_a per damper a, and (S⁻¹·Yᵀ·f_c)_a per damper and lane
    /// (S depends on the lane's damper parameters).
    ny: Vec<[f64; GW]>,
    fy: Vec<[f64; GW]>,
    sfy: Vec<[[f64; GW]; W]>,
    /// Scratch per damper: n_c·y_a and (f_c − n_c)·y_a of one port.
    yn: Vec<f64>,
    yd: Vec<f64>,
}

impl<const W: usize> PortBlock<W> {
    pub fn new(n: usize) -> Self {
        Self {
            vecs: Default::default(),
            force: None,
            cols: vec![0.0; n * GW],
            cols_f: Vec::new(),
            start: n,
            fstart: n,
            ny: Vec::new(),
            fy: Vec::new(),
            sfy: Vec::new(),
            yn: Vec::new(),
            yd: Vec::new(),
        }
    }

    /// The force vector of port c.
    #[inline]
    pub fn force_vec(&self, c: usize) -> &SVec {
        self.force.as_ref().map_or(&self.vecs[c], |f| &f[c])
    }

    /// Row k of L⁻¹·P·f (forward ports).
    #[inline]
    fn force_row(&self, k: usize) -> &[f64] {
        if k >= self.fstart {
            &self.cols_f[k * GW..k * GW + GW]
        } else {
            &self.cols[k * GW..k * GW + GW]
        }
    }
}

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

/// Shape vectors of all dampers' upper (or lower) points stored densely on the union of
/// their indices, so that a step gathers and scatters each stepper vector once and the
/// per-damper work is contiguous dots and axpys (the modal rail shapes of all dampers share
/// one index set).
#[derive(Clone, Debug, Default)]
struct ShapeSet {
    idx: Vec<usize>,
    /// Column a (length `idx.len()`) holds damper a's shape values.
    cols: Vec<f64>,
    /// Gathered lanes, `[i·W + lane]`.
    buf: Vec<f64>,
}

impl ShapeSet {
    fn new(shapes: &[SVec], lanes: usize) -> Self {
        let mut idx: Vec<usize> = shapes.iter().flat_map(|v| v.idx.iter().copied()).collect();
        idx.sort_unstable();
        idx.dedup();
        let len = idx.len();
        let mut cols = vec![0.0; len * shapes.len()];
        for (a, v) in shapes.iter().enumerate() {
            for (&i, &x) in v.idx.iter().zip(&v.val) {
                cols[a * len + idx.binary_search(&i).expect("index in union")] += x;
            }
        }
        Self {
            idx,
            cols,
            buf: vec![0.0; len * lanes],
        }
    }

    /// out[a·W + lane] = shape_a·x (x: W interleaved lanes).
    fn dots<const W: usize>(&mut self, x: &[f64], out: &mut [f64]) {
        for (b, &i) in self.buf.chunks_exact_mut(W).zip(&self.idx) {
            b.copy_from_slice(&x[i * W..i * W + W]);
        }
        crate::wide!(<W> (cols: &[f64] = &self.cols, len: usize = self.idx.len(), buf: &[f64] = &self.buf, out: &mut [f64] = out) {
            for (a, o) in out.chunks_exact_mut(W).enumerate() {
                o.copy_from_slice(&crate::linalg::simd::dot_lanes::<W>(&cols[a * len..(a + 1) * len], buf));
            }
        });
    }

    /// x += Σ_a w[a·W + lane]·shape_a.
    fn add_to<const W: usize>(&mut self, x: &mut [f64], w: &[f64]) {
        let len = self.idx.len();
        self.buf.fill(0.0);
        crate::wide!(<W> (buf: &mut [f64] = &mut self.buf, cols: &[f64] = &self.cols, len: usize = len, w: &[f64] = w) {
            for (a, wa) in w.chunks_exact(W).enumerate() {
                let wa: &[f64; W] = wa.try_into().expect("W weights");
                crate::linalg::simd::axpy_lanes::<W>(buf, &cols[a * len..(a + 1) * len], wa);
            }
        });
        for (b, &i) in self.buf.chunks_exact(W).zip(&self.idx) {
            for c in 0..W {
                x[i * W + c] += b[c];
            }
        }
    }
}

/// The dampers of a stepper, in its numbering, with their Woodbury data. Shapes, Y and
/// WᵀY are shared by the lanes; the parameters (and so S⁻¹) are per lane, at `[a·W + lane]`.
#[derive(Clone, Debug, Default)]
struct Attached {
    upper: ShapeSet,
    lower: ShapeSet,
    /// Stepper index of each internal node.
    node: Vec<usize>,
    /// α_r and α_s, the upper and lower branches' parts of A; the upper branch's k and the
    /// lower branch's b (their parts of K and M: the upper branch has no inerter, the lower
    /// no spring).
    alpha_r: Vec<f64>,
    alpha_s: Vec<f64>,
    k: Vec<f64>,
    b: Vec<f64>,
    /// Y = A₀⁻¹·W by rows (`yt[k·N_t + i]` = (A₀⁻¹·w_i)_k), and for forward ports
    /// D⁻¹·L⁻¹·P·w_i.
    yt: Vec<f64>,
    lw: Vec<Vec<f64>>,
    /// WᵀA₀⁻¹W (row-major, N_t × N_t), and S⁻¹ = (K⁻¹ + WᵀA₀⁻¹W)⁻¹ of each lane at
    /// `[lane·N_t² + r·N_t + c]`.
    wty: Vec<f64>,
    s_inv: Vec<f64>,
    /// S⁻¹·Wᵀ·A₀⁻¹·b of the step's known right-hand side, and scratch: Wᵀ·z, the upper and
    /// lower shapes' products with z, per-damper weights.
    t_free: Vec<f64>,
    wz: Vec<f64>,
    pu: Vec<f64>,
    pl: Vec<f64>,
    wu: Vec<f64>,
    wl: Vec<f64>,
}

impl Attached {
    fn len(&self) -> usize {
        self.node.len()
    }

    /// wz = Wᵀ·x (W's columns: upper − lower shapes); also leaves the upper and lower
    /// products in pu, pl.
    fn w_dots<const W: usize>(&mut self, x: &[f64]) {
        self.upper.dots::<W>(x, &mut self.pu);
        self.lower.dots::<W>(x, &mut self.pl);
        for ((w, u), l) in self.wz.iter_mut().zip(&self.pu).zip(&self.pl) {
            *w = u - l;
        }
    }

    /// out = S⁻¹·v per lane.
    fn s_solve<const W: usize>(&self, v: &[f64], out: &mut [f64]) {
        let n = self.len();
        for lane in 0..W {
            let s = &self.s_inv[lane * n * n..(lane + 1) * n * n];
            for r in 0..n {
                out[r * W + lane] = (0..n).map(|c| s[r * n + c] * v[c * W + lane]).sum();
            }
        }
    }

    /// Sets one lane's damper parameters and its S⁻¹.
    fn set_params(
        &mut self,
        lane: usize,
        lanes: usize,
        dt: f64,
        params: &[DamperParams],
    ) -> Result<()> {
        let nt = self.len();
        let mut sm = self.wty.clone();
        for (i, p) in params.iter().enumerate() {
            let [up, lo] = p.branches();
            let (ar, as_) = (up.step_impedance(dt), lo.step_impedance(dt));
            let q = i * lanes + lane;
            self.alpha_r[q] = ar;
            self.alpha_s[q] = as_;
            self.k[q] = up.stiffness;
            self.b[q] = lo.inertance;
            sm[i * nt + i] += 1.0 / (ar * as_ / (ar + as_));
        }
        let inv = crate::linalg::dense::inverse_spd(&sm, nt).ok_or_else(|| {
            crate::error::VtbError::Solver("damper coupling matrix is not positive definite".into())
        })?;
        self.s_inv[lane * nt * nt..(lane + 1) * nt * nt].copy_from_slice(&inv);
        Ok(())
    }
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
    columns: Option<std::collections::HashMap<usize, Column>>,
    /// Forward ports with force vectors: (k, L⁻¹·P·e_k from row k on) for the few unknowns k
    /// where force and displacement vectors differ.
    units: Vec<(usize, Vec<f64>)>,
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
    /// `blocks` optionally groups the unknowns by node: if the matrices are block tridiagonal
    /// in that grouping (finite elements), the block solver is used. `attachments` are dampers
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
        blocks: Option<&[Vec<usize>]>,
        attachments: &[Attachment],
    ) -> Result<Self> {
        const { assert!(W >= 1 && W <= 8, "1 to 8 lanes") };
        let a = CsrMatrix::combine(&[(2.0, m), (dt, c), (0.5 * dt * dt, k)]);
        let pattern = CsrMatrix::combine(&[(1.0, &a), (1.0, m), (1.0, k)]);
        let (engine, perm, inv) = match blocks.and_then(|g| BlockLayout::new(g, &pattern)) {
            Some(lay) => {
                let factor = BlockLdlt::new(&BlockTri::new(&a, &lay), &lay)?;
                let mk = BlockPair::new(&BlockTri::new(m, &lay), &BlockTri::new(k, &lay));
                (Engine::Blocks { factor, mk }, lay.perm, lay.inv)
            }
            None => {
                let factor = Ldlt::for_stepping(&a, ports)?;
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
            columns: column_ports.then(std::collections::HashMap::new),
            units: Vec::new(),
            y1: vec![0.0; n * W],
            y2: vec![0.0; n * W],
            obs: Vec::new(),
            obs_v: Vec::new(),
            obs_a: Vec::new(),
        };
        nm.attach(attachments)?;
        Ok(nm)
    }

    /// Woodbury data of the dampers: Y = A₀⁻¹W (and L⁻¹W for forward ports), WᵀY, and every
    /// lane's S⁻¹ for the attachments' own parameters.
    fn attach(&mut self, attachments: &[Attachment]) -> Result<()> {
        let (ns, nt) = (self.ns, attachments.len());
        let mut att = Attached::default();
        let (mut uppers, mut lowers) = (Vec::with_capacity(nt), Vec::with_capacity(nt));
        let mut y = Vec::with_capacity(nt);
        for (i, a) in attachments.iter().enumerate() {
            let (up, lo) = (self.vector(&a.upper), self.vector(&a.lower));
            let mut e = vec![0.0; ns];
            up.add_to(&mut e, 1.0);
            lo.add_to(&mut e, -1.0);
            if self.columns.is_some() {
                self.engine.solve_from::<1>(&mut e, 0);
            } else {
                let f = self.engine.sparse();
                f.forward::<1>(&mut e, 0);
                att.lw
                    .push(e.iter().zip(f.d_inv()).map(|(v, d)| v * d).collect());
                f.diag_backward::<1>(&mut e);
            }
            y.push(e);
            uppers.push(up);
            lowers.push(lo);
            att.node.push(ns + i);
        }
        // WᵀY: (N_upper,i − N_lower,i)·y_j.
        att.wty = (0..nt * nt)
            .map(|q| {
                let (i, j) = (q / nt, q % nt);
                uppers[i].dot(&y[j]) - lowers[i].dot(&y[j])
            })
            .collect();
        att.yt = (0..ns * nt).map(|q| y[q % nt][q / nt]).collect();
        att.upper = ShapeSet::new(&uppers, W);
        att.lower = ShapeSet::new(&lowers, W);
        for v in [
            &mut att.t_free,
            &mut att.wz,
            &mut att.pu,
            &mut att.pl,
            &mut att.wu,
            &mut att.wl,
            &mut att.alpha_r,
            &mut att.alpha_s,
            &mut att.k,
            &mut att.b,
        ] {
            *v = vec![0.0; nt * W];
        }
        att.s_inv = vec![0.0; nt * nt * W];
        let params: Vec<DamperParams> = attachments.iter().map(|a| a.params).collect();
        for lane in 0..W {
            att.set_params(lane, W, self.dt, &params)?;
        }
        self.att = att;
        Ok(())
    }

    /// Gives lane `lane` its own damper parameters (one per attachment, in order).
    pub fn set_damper_params(&mut self, lane: usize, params: &[DamperParams]) -> Result<()> {
        assert_eq!(params.len(), self.att.len(), "one parameter set per damper");
        self.att.set_params(lane, W, self.dt, params)
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
        // Columns are dropped between steps only: every port block of a step (one per car)
        // must find its columns until the step ends.
        if let Some(cache) = &mut self.columns
            && cache.len() > COLUMN_CACHE
        {
            cache.clear();
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

    /// n_c·y_a, f_c·y_a and each lane's S⁻¹·Yᵀ·f_c of a port block (dampers only).
    fn prepare_damper_ports(&self, ports: &mut PortBlock<W>) {
        let nt = self.att.len();
        if nt == 0 {
            return;
        }
        ports.ny.resize(nt, [0.0; GW]);
        ports.fy.resize(nt, [0.0; GW]);
        ports.sfy.resize(nt, [[0.0; GW]; W]);
        // Row-wise over the port entries: the inner loop runs over the dampers. Force and
        // displacement vectors differ at a few entries only (FE–SEA correction).
        let (mut yn, mut yd) = (std::mem::take(&mut ports.yn), std::mem::take(&mut ports.yd));
        yn.resize(nt, 0.0);
        yd.resize(nt, 0.0);
        for c in 0..GW {
            let n = &ports.vecs[c];
            let f = ports.force.as_ref().map_or(n, |f| &f[c]);
            yn.fill(0.0);
            yd.fill(0.0);
            for (q, &k) in n.idx.iter().enumerate() {
                let (vn, vf) = (n.val[q], f.val[q]);
                let row = &self.att.yt[k * nt..(k + 1) * nt];
                for (acc, y) in yn.iter_mut().zip(row) {
                    *acc += vn * y;
                }
                if vf != vn {
                    for (acc, y) in yd.iter_mut().zip(row) {
                        *acc += (vf - vn) * y;
                    }
                }
            }
            for a in 0..nt {
                ports.ny[a][c] = yn[a];
                ports.fy[a][c] = yn[a] + yd[a];
            }
        }
        (ports.yn, ports.yd) = (yn, yd);
        for lane in 0..W {
            let s = &self.att.s_inv[lane * nt * nt..(lane + 1) * nt * nt];
            for a in 0..nt {
                let row = &s[a * nt..(a + 1) * nt];
                ports.sfy[a][lane] =
                    std::array::from_fn(|c| (0..nt).map(|b| row[b] * ports.fy[b][c]).sum());
            }
        }
    }

    /// Prepares the port vectors set this step: forward substitution, or the cached columns
    /// of A⁻¹ they need. Shared by all lanes.
    pub fn prepare_ports(&mut self, ports: &mut PortBlock<W>) {
        self.prepare_damper_ports(ports);
        if let Some(cache) = &mut self.columns {
            for v in ports.vecs.iter().chain(ports.force.iter().flatten()) {
                for &k in &v.idx {
                    cache.entry(k).or_insert_with(|| {
                        let mut e = vec![0.0; self.ns];
                        e[k] = 1.0;
                        self.engine.solve_from::<1>(&mut e, k);
                        Column::new(&e)
                    });
                }
            }
            return;
        }
        let s = ports.start.min(self.ns);
        ports.cols[s * GW..].fill(0.0);
        ports.start = self.ns;
        for (c, v) in ports.vecs.iter().enumerate() {
            for (&i, &val) in v.idx.iter().zip(&v.val) {
                ports.cols[i * GW + c] = val;
                ports.start = ports.start.min(i);
            }
        }
        self.engine
            .sparse()
            .forward::<GW>(&mut ports.cols[..self.ns * GW], ports.start);
        // L⁻¹·f = L⁻¹·n + Σ_k (f − n)_k·L⁻¹·e_k over the few entries where they differ.
        ports.fstart = self.ns;
        let Some(force) = &ports.force else {
            return;
        };
        let mut diffs = [[(0usize, 0.0f64); 8]; GW];
        let mut nd = [0usize; GW];
        for c in 0..GW {
            let (n, f) = (&ports.vecs[c], &force[c]);
            for (q, (&k, (&nv, &fv))) in n.idx.iter().zip(n.val.iter().zip(&f.val)).enumerate() {
                debug_assert_eq!(f.idx[q], k);
                if nv != fv {
                    assert!(nd[c] < 8, "at most 8 corrected entries per port");
                    diffs[c][nd[c]] = (k, fv - nv);
                    nd[c] += 1;
                    ports.fstart = ports.fstart.min(k);
                }
            }
        }
        let (fs, n) = (ports.fstart, self.ns);
        if fs == n {
            return;
        }
        ports.cols_f.resize(n * GW, 0.0);
        ports.cols_f[fs * GW..].copy_from_slice(&ports.cols[fs * GW..n * GW]);
        let sparse = self.engine.sparse();
        for c in 0..GW {
            for &(k, d) in &diffs[c][..nd[c]] {
                let at = match self.units.iter().position(|u| u.0 == k) {
                    Some(at) => at,
                    None => {
                        let mut e = vec![0.0; n];
                        e[k] = 1.0;
                        sparse.forward::<1>(&mut e, k);
                        self.units.push((k, e.split_off(k)));
                        self.units.len() - 1
                    }
                };
                let unit = &self.units[at].1;
                for (r, u) in unit.iter().enumerate() {
                    ports.cols_f[(k + r) * GW + c] += d * u;
                }
            }
        }
    }

    /// Port displacements at t_{n+1} without the unknown port forces, per lane:
    /// n_cᵀ(u_n + Δt·A⁻¹·b).
    pub fn free_port_disp(&self, ports: &PortBlock<W>) -> [[f64; GW]; W] {
        // Dampers: −n_cᵀ·Y·S⁻¹·WᵀA₀⁻¹b.
        let corr: [[f64; GW]; W] = std::array::from_fn(|lane| {
            std::array::from_fn(|c| {
                (0..self.att.len())
                    .map(|a| ports.ny[a][c] * self.att.t_free[a * W + lane])
                    .sum()
            })
        });
        if self.columns.is_some() {
            return std::array::from_fn(|lane| {
                std::array::from_fn(|c| {
                    let v = &ports.vecs[c];
                    v.dot_lane::<W>(&self.u, lane)
                        + self.dt * (v.dot_lane::<W>(&self.z, lane) - corr[lane][c])
                })
            });
        }
        let d = self.engine.sparse().d_inv();
        let mut acc = [[0.0; GW]; W];
        for k in ports.start..self.ns {
            let r = &ports.cols[k * GW..k * GW + GW];
            for (lane, a) in acc.iter_mut().enumerate() {
                let w = d[k] * self.z[k * W + lane];
                for c in 0..GW {
                    a[c] += r[c] * w;
                }
            }
        }
        std::array::from_fn(|lane| {
            std::array::from_fn(|c| {
                ports.vecs[c].dot_lane::<W>(&self.u, lane)
                    + self.dt * (acc[lane][c] - corr[lane][c])
            })
        })
    }

    /// Port compliance (Δt²/2)·n_iᵀA⁻¹f_j between two port blocks (rows: `a`, cols: `b`) per
    /// lane: the displacement of port i per unit force of port j.
    pub fn port_compliance(&self, a: &PortBlock<W>, b: &PortBlock<W>) -> [[[f64; GW]; GW]; W] {
        let c2 = 0.5 * self.dt * self.dt;
        // Without the dampers the compliance is the same in every lane.
        let g: [[f64; GW]; GW] = if let Some(cache) = &self.columns {
            // n_iᵀA⁻¹f_j = Σ_l f_j[l]·(n_iᵀ·col_l).
            std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    let nj = b.force_vec(j);
                    nj.idx
                        .iter()
                        .zip(&nj.val)
                        .map(|(l, v)| v * cache[l].dot(&a.vecs[i]))
                        .sum::<f64>()
                })
            })
        } else {
            let d = self.engine.sparse().d_inv();
            let mut g = [[0.0; GW]; GW];
            for k in a.start.max(b.start)..self.ns {
                let (ra, rb) = (&a.cols[k * GW..k * GW + GW], b.force_row(k));
                for r in 0..GW {
                    let ar = ra[r] * d[k];
                    for c in 0..GW {
                        g[r][c] += ar * rb[c];
                    }
                }
            }
            g
        };
        // Dampers: −n_iᵀ·Y·S⁻¹·Yᵀ·f_j.
        std::array::from_fn(|lane| {
            std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    let corr: f64 = (0..self.att.len())
                        .map(|t| a.ny[t][i] * b.sfy[t][lane][j])
                        .sum();
                    c2 * (g[i][j] - corr)
                })
            })
        })
    }

    /// Adds the port forces (Δt/2)·Σ_c w_c·f_c of the step, per lane.
    pub fn add_port_forces(&mut self, ports: &PortBlock<W>, w: &[[f64; GW]; W]) {
        let h = 0.5 * self.dt;
        if let Some(cache) = &self.columns {
            for c in 0..GW {
                let v = ports.force_vec(c);
                for (l, val) in v.idx.iter().zip(&v.val) {
                    let col = &cache[l];
                    let coef: [f64; W] = std::array::from_fn(|lane| h * w[lane][c] * val);
                    crate::wide!(<W> (z: &mut [f64] = &mut self.z[col.start * W..], a: &[f64] = &col.values, v: &[f64; W] = &coef) {
                        crate::linalg::simd::axpy_lanes::<W>(z, a, v)
                    });
                }
            }
            return;
        }
        for k in ports.start..self.ns {
            let r = ports.force_row(k);
            for (lane, wl) in w.iter().enumerate() {
                let mut s = 0.0;
                for c in 0..GW {
                    s += r[c] * wl[c];
                }
                self.z[k * W + lane] += h * s;
            }
        }
    }

    /// v̄ = A⁻¹b from z = A₀⁻¹b (Woodbury), then the damper nodes' v̄_d, then the dampers'
    /// parts of M·v̄ and K·v̄: b·(e_d − N_lower)(…)ᵀ and k·(N_upper − e_d)(…)ᵀ.
    fn finish_dampers(&mut self) {
        let (nt, ns) = (self.att.len(), self.ns);
        if nt == 0 {
            return;
        }
        let att = &mut self.att;
        att.w_dots::<W>(&self.z);
        let mut t = std::mem::take(&mut att.t_free);
        att.s_solve::<W>(&att.wz, &mut t);
        // z[..ns] −= Y·t, row by row over the contiguous rows of Y.
        crate::wide!(<W> (z: &mut [f64] = &mut self.z[..ns * W], yt: &[f64] = &att.yt, t: &[f64] = &t, nt: usize = nt) {
            for (zk, row) in z.chunks_exact_mut(W).zip(yt.chunks_exact(nt)) {
                    let mut s = [0.0; W];
                    for (y, ti) in row.iter().zip(t.chunks_exact(W)) {
                        for c in 0..W {
                            s[c] = y.mul_add(ti[c], s[c]);
                        }
                    }
                    for c in 0..W {
                        zk[c] -= s[c];
                    }
                }
        });
        att.t_free = t;
        att.w_dots::<W>(&self.z);
        for i in 0..nt {
            for lane in 0..W {
                let (q, d) = (i * W + lane, att.node[i] * W + lane);
                let h = att.alpha_r[q] * att.pu[q] + att.alpha_s[q] * att.pl[q];
                let zd = (self.z[d] + h) / (att.alpha_r[q] + att.alpha_s[q]);
                self.z[d] = zd;
                let vm = att.b[q] * (zd - att.pl[q]);
                let vk = att.k[q] * (att.pu[q] - zd);
                self.y1[d] = vm;
                self.y2[d] = -vk;
                att.wl[q] = -vm;
                att.wu[q] = vk;
            }
        }
    }

    /// Adds the dampers' parts of M·v̄ and K·v̄ (weights left by `finish_dampers`) once the
    /// structure's products have been written.
    fn damper_products(&mut self) {
        let att = &mut self.att;
        if att.len() > 0 {
            att.lower.add_to::<W>(&mut self.y1, &att.wl);
            att.upper.add_to::<W>(&mut self.y2, &att.wu);
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
mod tests {
    use super::*;
    use crate::config::DamperKind;
    use crate::linalg::sparse::Assembler;

    fn scalar(v: f64) -> CsrMatrix {
        let mut a = Assembler::new(1);
        a.add(0, 0, v);
        a.finish()
    }

    /// A unit oscillator: m = 1, k = 4π², u0 = 1, v0 = 0. Newmark average acceleration gives
    /// u_n = cos(ω̄·n·Δt) with ω̄ = (2/Δt)·atan(ωΔt/2), i.e. T̄/T = (ωΔt/2)/atan(ωΔt/2)
    /// (1.00033, 1.00817, 1.03207, 1.12003 for Δt/T = 0.01, 0.05, 0.1, 0.2), with no
    /// amplitude decay.
    #[test]
    fn newmark_sdof_period_elongation_matches_exact_formula() {
        let w = 2.0 * std::f64::consts::PI;
        for (ratio, elong) in [
            (0.01, 1.00033),
            (0.05, 1.00817),
            (0.1, 1.03207),
            (0.2, 1.12003),
        ] {
            let dt = ratio;
            let (m, k, c) = (scalar(1.0), scalar(w * w), CsrMatrix::zeros(1));
            let mut nm: Newmark = Newmark::new(&m, &c, &k, dt, &[], 1, None, &[]).unwrap();
            nm.observe(&Shape {
                start: 0,
                values: vec![1.0],
            });
            nm.set_state(0, &[1.0], &[0.0], &[-w * w], &k, &m);
            let wbar = 2.0 / dt * (w * dt / 2.0).atan();
            assert!((w / wbar - elong).abs() < 5e-6, "T̄/T = {}", w / wbar);
            let zero = [0.0];
            let mut peak: f64 = 0.0;
            for step in 1..=2000 {
                nm.begin_step(&zero, &zero);
                nm.end_step();
                let (u, _, a) = nm.observed(0, 0);
                let t = step as f64 * dt;
                assert!(
                    (u - (wbar * t).cos()).abs() < 1e-9,
                    "Δt/T={ratio} step {step}: {u}"
                );
                // Newmark's acceleration of a free SDOF is −ω²u exactly.
                assert!((a + w * w * u).abs() < 1e-7 * w * w);
                peak = peak.max(u.abs());
            }
            assert!(peak <= 1.0 + 1e-12);
        }
    }

    /// The dampers' Woodbury path against the same system with the damper assembled into
    /// M, K, C (a second method), with a linear spring acting through a port, for forward and
    /// column ports and each kind.
    #[test]
    fn dampers_by_woodbury_match_assembled_matrices() {
        let n = 5;
        let (mut am, mut ak) = (Assembler::new(n), Assembler::new(n));
        for i in 0..n {
            am.add(i, i, 1.0 + i as f64);
            ak.add(i, i, 200.0);
            if i + 1 < n {
                for (r, c, v) in [(i, i + 1, -80.0), (i + 1, i, -80.0), (i + 1, i + 1, 80.0)] {
                    ak.add(r, c, v);
                }
                ak.add(i, i, 80.0);
            }
        }
        let (m0, k0) = (am.finish(), ak.finish());
        let c0 = CsrMatrix::combine(&[(0.3, &m0), (1e-3, &k0)]);
        for kind in [DamperKind::Tid, DamperKind::Tvmd] {
            let att = Attachment {
                upper: Shape {
                    start: 1,
                    values: vec![0.3, 0.7],
                },
                lower: Shape {
                    start: 4,
                    values: vec![1.0],
                },
                node: n,
                params: DamperParams {
                    kind,
                    stiffness: 50.0,
                    damping: 0.5,
                    inertance: 0.2,
                },
            };
            // Full matrices with the node as DOF n: the damper assembled as a finite element.
            let [mf, kf, cf] = crate::model::dampers::stamp(
                [&m0, &k0, &c0],
                n + 1,
                std::slice::from_ref(&att),
                &[att.params],
            );
            let port = Shape {
                start: 0,
                values: vec![1.0, 0.5],
            };
            let k_contact = 300.0;
            let run = |nm: &mut Newmark| -> Vec<f64> {
                nm.observe(&Shape {
                    start: 3,
                    values: vec![1.0],
                });
                let u0 = [0.01, -0.02, 0.0, 0.03, 0.0, 0.0];
                nm.set_state(0, &u0, &[0.0; 6], &[0.0; 6], &kf, &mf);
                let mut ports = PortBlock::new(nm.n);
                nm.vector_into(&port, &mut ports.vecs[0]);
                let f = vec![0.0; nm.n];
                let mut out = Vec::new();
                for _ in 0..300 {
                    nm.begin_step(&f, &f);
                    nm.prepare_ports(&mut ports);
                    let free = nm.free_port_disp(&ports)[0][0];
                    let g = nm.port_compliance(&ports, &ports)[0][0][0];
                    let p = -k_contact * free / (1.0 + k_contact * g);
                    nm.add_port_forces(&ports, &[[p, 0.0, 0.0, 0.0]]);
                    nm.end_step();
                    out.push(nm.observed(0, 0).0);
                    out.push(p);
                }
                out
            };
            for port_len in [2, 100] {
                let mut a: Newmark = Newmark::new(
                    &m0,
                    &c0,
                    &k0,
                    1e-2,
                    &[0, 1],
                    port_len,
                    None,
                    std::slice::from_ref(&att),
                )
                .unwrap();
                let mut b: Newmark =
                    Newmark::new(&mf, &cf, &kf, 1e-2, &[0, 1], port_len, None, &[]).unwrap();
                let (ra, rb) = (run(&mut a), run(&mut b));
                let scale = rb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (x, y) in ra.iter().zip(&rb) {
                    assert!(
                        (x - y).abs() < 1e-10 * scale,
                        "{kind:?}, port_len {port_len}: {x} vs {y}"
                    );
                }
            }
        }
    }
}
