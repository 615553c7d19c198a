//! Newmark average-acceleration integration (γ = ½, β = ¼) of the coupled system
//! (model.md §7), with the Hertz contact forces iterated within each step.
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

use crate::banded::{BlockLayout, BlockLdlt, BlockPair, BlockTri, PAD};
use crate::basis::Shape;
use crate::error::Result;
use crate::sparse::{CsrMatrix, Ldlt, SymOperator};

/// Port columns processed together (one car: four wheelsets).
pub const GW: usize = 4;
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
}

/// Up to GW contact ports of one subsystem (one car's wheels) and the data the engine derives
/// from them each step.
#[derive(Clone, Debug)]
pub struct PortBlock {
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
}

impl PortBlock {
    pub fn new(n: usize) -> Self {
        Self {
            vecs: Default::default(),
            force: None,
            cols: vec![0.0; n * GW],
            cols_f: Vec::new(),
            start: n,
            fstart: n,
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
#[derive(Clone, Debug)]
enum Engine {
    /// General sparse LDLᵀ (modal bases, cars).
    Sparse { factor: Ldlt, mk: SymOperator },
    /// Block tridiagonal (finite elements numbered node by node).
    Blocks { factor: BlockLdlt, mk: BlockPair },
}

impl Engine {
    /// z ← A⁻¹·z for a right-hand side that is zero before unknown `start`.
    fn solve_from(&self, z: &mut [f64], start: usize) {
        match self {
            Engine::Sparse { factor, .. } => {
                factor.forward::<1>(z, start);
                factor.diag_backward(z);
            }
            Engine::Blocks { factor, .. } => factor.solve_from(z, start / factor.block_size()),
        }
    }

    fn mul2(&self, x: &[f64], ym: &mut [f64], yk: &mut [f64]) {
        match self {
            Engine::Sparse { mk, .. } => mk.mul2(x, ym, yk),
            Engine::Blocks { mk, .. } => mk.mul2(x, ym, yk),
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

/// Newmark stepper of one linear subsystem M·ü + C·u̇ + K·u = F. Vectors, forces and
/// observations live in the stepper's numbering (the elimination order of the factor of A,
/// with padding slots for block factors).
#[derive(Clone, Debug)]
pub struct Newmark {
    /// Length of stepper vectors.
    pub n: usize,
    pub dt: f64,
    engine: Engine,
    /// Stepper → original index (`PAD` for padding) and original → stepper index.
    perm: Vec<usize>,
    inv: Vec<usize>,
    /// Displacements.
    pub u: Vec<f64>,
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

impl Newmark {
    /// `ports` lists the unknowns contact forces act on (eliminated late so that port vectors
    /// forward-substitute cheaply); `port_len` is the number of entries of a port vector.
    /// Short port vectors (finite elements, car wheelsets) use *column ports*: the columns of
    /// A⁻¹ at the few unknowns they touch are cached, so a step needs one full solve and a few
    /// axpys. Long ones (modal layers) are forward-substituted with the right-hand side.
    /// `blocks` optionally groups the unknowns by node: if the matrices are block tridiagonal
    /// in that grouping (finite elements), the block solver is used.
    pub fn new(
        m: &CsrMatrix,
        c: &CsrMatrix,
        k: &CsrMatrix,
        dt: f64,
        ports: &[usize],
        port_len: usize,
        blocks: Option<&[Vec<usize>]>,
    ) -> Result<Self> {
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
        let n = perm.len();
        let column_ports =
            port_len <= COLUMN_PORTS_MAX_LEN || matches!(engine, Engine::Blocks { .. });
        Ok(Self {
            n,
            dt,
            engine,
            perm,
            inv,
            u: vec![0.0; n],
            q: vec![0.0; n],
            s: vec![0.0; n],
            z: vec![0.0; n],
            columns: column_ports.then(std::collections::HashMap::new),
            units: Vec::new(),
            y1: vec![0.0; n],
            y2: vec![0.0; n],
            obs: Vec::new(),
            obs_v: Vec::new(),
            obs_a: Vec::new(),
        })
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

    /// A dense vector (original numbering) in the stepper's numbering.
    pub fn to_stepper(&self, x: &[f64]) -> Vec<f64> {
        self.perm
            .iter()
            .map(|&i| if i == PAD { 0.0 } else { x[i] })
            .collect()
    }

    /// Current displacements in the original numbering.
    pub fn displacements(&self) -> Vec<f64> {
        let mut x = vec![0.0; self.inv.len()];
        for (i, &k) in self.inv.iter().enumerate() {
            x[i] = self.u[k];
        }
        x
    }

    /// Registers an observation vector (original numbering); returns its index.
    pub fn observe(&mut self, shape: &Shape) -> usize {
        let v = self.vector(shape);
        self.obs.push(v);
        self.obs_v.push(0.0);
        self.obs_a.push(0.0);
        self.obs.len() - 1
    }

    /// Sets the state at t = 0 from displacements, velocities and accelerations (original
    /// numbering). The acceleration only seeds the observed Newmark acceleration recursion,
    /// which carries any error in a₀ forever, so it must satisfy the equation of motion.
    pub fn set_state(&mut self, u0: &[f64], v0: &[f64], a0: &[f64], k: &CsrMatrix, m: &CsrMatrix) {
        let n = self.inv.len();
        let (mut ku, mut mv) = (vec![0.0; n], vec![0.0; n]);
        k.mul(u0, &mut ku);
        m.mul(v0, &mut mv);
        let q: Vec<f64> = (0..n).map(|i| 2.0 * mv[i] - self.dt * ku[i]).collect();
        self.q = self.to_stepper(&q);
        self.s = self.to_stepper(&ku);
        self.u = self.to_stepper(u0);
        let (vt, at) = (self.to_stepper(v0), self.to_stepper(a0));
        for (j, o) in self.obs.iter().enumerate() {
            self.obs_v[j] = o.dot(&vt);
            self.obs_a[j] = o.dot(&at);
        }
    }

    /// Displacement, velocity and acceleration of observation `j`.
    pub fn observed(&self, j: usize) -> (f64, f64, f64) {
        (self.obs[j].dot(&self.u), self.obs_v[j], self.obs_a[j])
    }

    pub fn n_observed(&self) -> usize {
        self.obs.len()
    }

    /// Starts a step with the known forces F_n and F_{n+1} (stepper numbering).
    pub fn begin_step(&mut self, f_prev: &[f64], f_next: &[f64]) {
        let h = 0.5 * self.dt;
        for (((z, q), fp), fnx) in self.z.iter_mut().zip(&self.q).zip(f_prev).zip(f_next) {
            *z = q + h * (fp + fnx);
        }
        if self.columns.is_some() {
            self.engine.solve_from(&mut self.z, 0);
        } else {
            self.engine.sparse().forward::<1>(&mut self.z, 0);
        }
    }

    /// Prepares the port vectors set this step: forward substitution, or the cached columns
    /// of A⁻¹ they need.
    pub fn prepare_ports(&mut self, ports: &mut PortBlock) {
        if let Some(cache) = &mut self.columns {
            if cache.len() > COLUMN_CACHE {
                cache.retain(|k, _| ports.vecs.iter().any(|v| v.idx.contains(k)));
            }
            for v in ports.vecs.iter().chain(ports.force.iter().flatten()) {
                for &k in &v.idx {
                    cache.entry(k).or_insert_with(|| {
                        let mut e = vec![0.0; self.n];
                        e[k] = 1.0;
                        self.engine.solve_from(&mut e, k);
                        Column::new(&e)
                    });
                }
            }
            return;
        }
        let s = ports.start.min(self.n);
        ports.cols[s * GW..].fill(0.0);
        ports.start = self.n;
        for (c, v) in ports.vecs.iter().enumerate() {
            for (&i, &val) in v.idx.iter().zip(&v.val) {
                ports.cols[i * GW + c] = val;
                ports.start = ports.start.min(i);
            }
        }
        self.engine
            .sparse()
            .forward::<GW>(&mut ports.cols, ports.start);
        // L⁻¹·f = L⁻¹·n + Σ_k (f − n)_k·L⁻¹·e_k over the few entries where they differ.
        ports.fstart = self.n;
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
        let (fs, n) = (ports.fstart, self.n);
        if fs == n {
            return;
        }
        ports.cols_f.resize(n * GW, 0.0);
        ports.cols_f[fs * GW..].copy_from_slice(&ports.cols[fs * GW..]);
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

    /// Port displacements at t_{n+1} without the unknown port forces: n_cᵀ(u_n + Δt·A⁻¹·b).
    pub fn free_port_disp(&self, ports: &PortBlock) -> [f64; GW] {
        if self.columns.is_some() {
            return std::array::from_fn(|c| {
                ports.vecs[c].dot(&self.u) + self.dt * ports.vecs[c].dot(&self.z)
            });
        }
        let d = self.engine.sparse().d_inv();
        let mut acc = [0.0; GW];
        for k in ports.start..self.n {
            let w = d[k] * self.z[k];
            let r = &ports.cols[k * GW..k * GW + GW];
            for c in 0..GW {
                acc[c] += r[c] * w;
            }
        }
        std::array::from_fn(|c| ports.vecs[c].dot(&self.u) + self.dt * acc[c])
    }

    /// Port compliance (Δt²/2)·n_iᵀA⁻¹f_j between two port blocks (rows: `a`, cols: `b`):
    /// the displacement of port i per unit force of port j.
    pub fn port_compliance(&self, a: &PortBlock, b: &PortBlock) -> [[f64; GW]; GW] {
        let c2 = 0.5 * self.dt * self.dt;
        if let Some(cache) = &self.columns {
            // n_iᵀA⁻¹f_j = Σ_l f_j[l]·(n_iᵀ·col_l).
            return std::array::from_fn(|i| {
                std::array::from_fn(|j| {
                    let nj = b.force_vec(j);
                    c2 * nj
                        .idx
                        .iter()
                        .zip(&nj.val)
                        .map(|(l, v)| v * cache[l].dot(&a.vecs[i]))
                        .sum::<f64>()
                })
            });
        }
        let d = self.engine.sparse().d_inv();
        let mut g = [[0.0; GW]; GW];
        for k in a.start.max(b.start)..self.n {
            let (ra, rb) = (&a.cols[k * GW..k * GW + GW], b.force_row(k));
            for r in 0..GW {
                let ar = ra[r] * d[k];
                for c in 0..GW {
                    g[r][c] += ar * rb[c];
                }
            }
        }
        g.map(|row| row.map(|v| c2 * v))
    }

    /// Adds the port forces (Δt/2)·Σ_c w_c·f_c of the step.
    pub fn add_port_forces(&mut self, ports: &PortBlock, w: [f64; GW]) {
        let h = 0.5 * self.dt;
        if let Some(cache) = &self.columns {
            for (c, wc) in w.into_iter().enumerate() {
                let v = ports.force_vec(c);
                for (l, val) in v.idx.iter().zip(&v.val) {
                    let col = &cache[l];
                    crate::simd::axpy(&mut self.z[col.start..], &col.values, h * wc * val);
                }
            }
            return;
        }
        for k in ports.start..self.n {
            let r = ports.force_row(k);
            let mut s = 0.0;
            for c in 0..GW {
                s += r[c] * w[c];
            }
            self.z[k] += h * s;
        }
    }

    /// Finishes the step: back-substitution for v̄ and the state update.
    pub fn end_step(&mut self) {
        let dt = self.dt;
        if self.columns.is_none() {
            self.engine.sparse().diag_backward(&mut self.z);
        }
        self.engine.mul2(&self.z, &mut self.y1, &mut self.y2);
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
        for (o, (ov, oa)) in self
            .obs
            .iter()
            .zip(self.obs_v.iter_mut().zip(self.obs_a.iter_mut()))
        {
            let nv = o.dot(&self.z);
            *oa = 4.0 * (nv - *ov) / dt - *oa;
            *ov = 2.0 * nv - *ov;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sparse::Assembler;

    fn scalar(v: f64) -> CsrMatrix {
        let mut a = Assembler::new(1);
        a.add(0, 0, v);
        a.finish()
    }

    /// physics-data.md §5d: m = 1, k = 4π², u0 = 1, v0 = 0. Newmark average acceleration gives
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
            let mut nm = Newmark::new(&m, &c, &k, dt, &[], 1, None).unwrap();
            nm.observe(&Shape {
                start: 0,
                values: vec![1.0],
            });
            nm.set_state(&[1.0], &[0.0], &[-w * w], &k, &m);
            let wbar = 2.0 / dt * (w * dt / 2.0).atan();
            assert!((w / wbar - elong).abs() < 5e-6, "T̄/T = {}", w / wbar);
            let zero = [0.0];
            let mut peak: f64 = 0.0;
            for step in 1..=2000 {
                nm.begin_step(&zero, &zero);
                nm.end_step();
                let (u, _, a) = nm.observed(0);
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
}
