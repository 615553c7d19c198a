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
//! once; a step costs one product with the pair (4M − Δt²K, K) on one sparsity pattern and
//! one triangular solve. Accelerations are those of Newmark's scheme,
//! a_{n+1} = 4(v̄ − v_n)/Δt − a_n, evaluated at observation vectors only.
//!
//! Contact forces act through *ports*: a port of a subsystem has a force vector f (where the
//! force enters) and a displacement vector n (what the contact sees); for the rail both are
//! the shape vector at the wheel, for a car both are the unit vector of a wheelset DOF. The
//! port displacements at t_{n+1} are affine in the unknown forces with the compliance
//! (Δt²/2)·n_iᵀA⁻¹f_j = (Δt²/2)·(L⁻¹n_i)ᵀD⁻¹(L⁻¹f_j) for P·A·Pᵀ = L·D·Lᵀ, so the port vectors
//! are forward-substituted together with the right-hand side, the contact Newton iterates on
//! the wheel forces alone, and one backward substitution of the combined right-hand side
//! finishes the step.

use crate::basis::Shape;
use crate::error::Result;
use crate::sparse::{CsrMatrix, Ldlt, SymOperator};

/// Port columns forward-substituted together (one car: four wheelsets).
pub const GW: usize = 4;

/// A vector expressed in a stepper's permuted numbering (only its nonzeros).
#[derive(Clone, Debug, Default)]
pub struct Gathered {
    pub idx: Vec<usize>,
    pub val: Vec<f64>,
}

impl Gathered {
    pub fn from_shape(s: &Shape, inv: &[usize]) -> Self {
        Self {
            idx: (0..s.values.len()).map(|k| inv[s.start + k]).collect(),
            val: s.values.clone(),
        }
    }

    #[inline]
    pub fn dot(&self, x: &[f64]) -> f64 {
        self.idx
            .iter()
            .zip(&self.val)
            .map(|(&i, &v)| v * x[i])
            .sum()
    }
}

/// Up to GW ports forward-substituted as interleaved columns.
#[derive(Clone, Debug)]
pub struct PortBlock {
    /// L⁻¹·P·f_c for column c, at `[k·GW + c]`.
    pub cols: Vec<f64>,
    /// First nonzero row (in elimination order).
    pub start: usize,
    /// The ports' displacement vectors (permuted numbering).
    pub shapes: [Gathered; GW],
}

impl PortBlock {
    pub fn new(n: usize) -> Self {
        Self {
            cols: vec![0.0; n * GW],
            start: n,
            shapes: Default::default(),
        }
    }

    /// Clears the columns (only the part a previous forward solve could have filled).
    pub fn clear(&mut self) {
        let s = self.start.min(self.cols.len() / GW);
        self.cols[s * GW..].fill(0.0);
        self.start = self.cols.len() / GW;
        for g in &mut self.shapes {
            g.idx.clear();
            g.val.clear();
        }
    }

    /// Sets column `c` to the gathered vector `g`.
    pub fn set(&mut self, c: usize, g: &Gathered) {
        for (&i, &v) in g.idx.iter().zip(&g.val) {
            self.cols[i * GW + c] = v;
            self.start = self.start.min(i);
        }
        self.shapes[c].idx.extend_from_slice(&g.idx);
        self.shapes[c].val.extend_from_slice(&g.val);
    }

    /// Sets column `c` to a layer shape vector, `map` taking layer DOFs to permuted indices.
    pub fn set_shape(&mut self, c: usize, shape: &Shape, map: &[usize]) {
        let g = &mut self.shapes[c];
        for (k, &v) in shape.values.iter().enumerate() {
            let i = map[shape.start + k];
            self.cols[i * GW + c] = v;
            self.start = self.start.min(i);
            g.idx.push(i);
            g.val.push(v);
        }
    }
}

/// Newmark stepper of one linear subsystem M·ü + C·u̇ + K·u = F.
#[derive(Clone, Debug)]
pub struct Newmark {
    pub n: usize,
    pub dt: f64,
    factor: Ldlt,
    /// M and K for the products M·v̄ and K·v̄ (solver numbering).
    m_op: SymOperator,
    k_op: SymOperator,
    /// Displacements, solver numbering.
    pub u: Vec<f64>,
    q: Vec<f64>,
    s: Vec<f64>,
    /// Right-hand side during a step (forward-substituted); v̄ after `end_step`.
    z: Vec<f64>,
    /// M·v̄ and K·v̄.
    y1: Vec<f64>,
    y2: Vec<f64>,
    obs: Vec<Gathered>,
    obs_v: Vec<f64>,
    obs_a: Vec<f64>,
}

impl Newmark {
    /// `ports` lists the unknowns contact forces act on (they are eliminated late so that
    /// port vectors forward-substitute cheaply).
    pub fn new(
        m: &CsrMatrix,
        c: &CsrMatrix,
        k: &CsrMatrix,
        dt: f64,
        ports: &[usize],
    ) -> Result<Self> {
        let n = m.n;
        let a = CsrMatrix::combine(&[(2.0, m), (dt, c), (0.5 * dt * dt, k)]);
        let factor = Ldlt::for_stepping(&a, ports)?;
        let (m_op, k_op) = (
            SymOperator::new(m, &factor.perm),
            SymOperator::new(k, &factor.perm),
        );
        Ok(Self {
            n,
            dt,
            factor,
            m_op,
            k_op,
            u: vec![0.0; n],
            q: vec![0.0; n],
            s: vec![0.0; n],
            z: vec![0.0; n],
            y1: vec![0.0; n],
            y2: vec![0.0; n],
            obs: Vec::new(),
            obs_v: Vec::new(),
            obs_a: Vec::new(),
        })
    }

    /// Original index → position in elimination order.
    pub fn inv(&self) -> &[usize] {
        &self.factor.inv
    }

    /// Position in elimination order → original index.
    pub fn perm(&self) -> &[usize] {
        &self.factor.perm
    }

    pub fn factor(&self) -> &Ldlt {
        &self.factor
    }

    pub fn to_permuted(&self, x: &[f64]) -> Vec<f64> {
        self.factor.perm.iter().map(|&i| x[i]).collect()
    }

    pub fn to_original(&self, xp: &[f64]) -> Vec<f64> {
        let mut x = vec![0.0; self.n];
        for (k, &i) in self.factor.perm.iter().enumerate() {
            x[i] = xp[k];
        }
        x
    }

    /// Registers an observation vector (original numbering); returns its index.
    pub fn observe(&mut self, shape: &Shape) -> usize {
        self.obs.push(Gathered::from_shape(shape, &self.factor.inv));
        self.obs_v.push(0.0);
        self.obs_a.push(0.0);
        self.obs.len() - 1
    }

    /// Sets the state at t = 0 from displacements, velocities and accelerations (original
    /// numbering). The acceleration only seeds the observed Newmark acceleration recursion,
    /// which carries any error in a₀ forever, so it must satisfy the equation of motion.
    pub fn set_state(&mut self, u0: &[f64], v0: &[f64], a0: &[f64], k: &CsrMatrix, m: &CsrMatrix) {
        let n = self.n;
        let (mut ku, mut mv) = (vec![0.0; n], vec![0.0; n]);
        k.mul(u0, &mut ku);
        m.mul(v0, &mut mv);
        for (p, &i) in self.factor.perm.iter().enumerate() {
            self.u[p] = u0[i];
            self.s[p] = ku[i];
            self.q[p] = 2.0 * mv[i] - self.dt * ku[i];
        }
        let (vp, ap) = (self.to_permuted(v0), self.to_permuted(a0));
        for (j, o) in self.obs.iter().enumerate() {
            self.obs_v[j] = o.dot(&vp);
            self.obs_a[j] = o.dot(&ap);
        }
    }

    /// Displacement, velocity and acceleration of observation `j`.
    pub fn observed(&self, j: usize) -> (f64, f64, f64) {
        (self.obs[j].dot(&self.u), self.obs_v[j], self.obs_a[j])
    }

    pub fn n_observed(&self) -> usize {
        self.obs.len()
    }

    /// Starts a step: z = L⁻¹·P·(q + (Δt/2)(F_n + F_{n+1})) for the known forces (permuted).
    pub fn begin_step(&mut self, f_prev: &[f64], f_next: &[f64]) {
        let h = 0.5 * self.dt;
        for k in 0..self.n {
            self.z[k] = self.q[k] + h * (f_prev[k] + f_next[k]);
        }
        self.factor.forward::<1>(&mut self.z, 0);
    }

    /// Forward-substitutes a port block in place.
    pub fn forward_ports(&self, ports: &mut PortBlock) {
        self.factor.forward::<GW>(&mut ports.cols, ports.start);
    }

    /// Port displacements at t_{n+1} without the unknown port forces:
    /// n_cᵀ(u_n + Δt·A⁻¹·b).
    pub fn free_port_disp(&self, ports: &PortBlock) -> [f64; GW] {
        let d = self.factor.d_inv();
        let mut acc = [0.0; GW];
        for k in ports.start..self.n {
            let w = d[k] * self.z[k];
            let r = &ports.cols[k * GW..k * GW + GW];
            for c in 0..GW {
                acc[c] += r[c] * w;
            }
        }
        std::array::from_fn(|c| ports.shapes[c].dot(&self.u) + self.dt * acc[c])
    }

    /// Port compliance (Δt²/2)·n_iᵀA⁻¹f_j between two port blocks (rows: `a`, cols: `b`).
    pub fn port_compliance(&self, a: &PortBlock, b: &PortBlock) -> [[f64; GW]; GW] {
        let d = self.factor.d_inv();
        let mut g = [[0.0; GW]; GW];
        for k in a.start.max(b.start)..self.n {
            let (ra, rb) = (&a.cols[k * GW..k * GW + GW], &b.cols[k * GW..k * GW + GW]);
            for r in 0..GW {
                let ar = ra[r] * d[k];
                for c in 0..GW {
                    g[r][c] += ar * rb[c];
                }
            }
        }
        let c2 = 0.5 * self.dt * self.dt;
        g.map(|row| row.map(|v| c2 * v))
    }

    /// Adds the port forces (Δt/2)·Σ_c w_c·f_c of the step to the right-hand side.
    pub fn add_port_forces(&mut self, ports: &PortBlock, w: [f64; GW]) {
        let h = 0.5 * self.dt;
        for k in ports.start..self.n {
            let r = &ports.cols[k * GW..k * GW + GW];
            let mut s = 0.0;
            for c in 0..GW {
                s += r[c] * w[c];
            }
            self.z[k] += h * s;
        }
    }

    /// Finishes the step: back-substitution for v̄ and the state update.
    pub fn end_step(&mut self) {
        self.factor.diag_backward(&mut self.z);
        let dt = self.dt;
        self.m_op.mul(&self.z, &mut self.y1);
        self.k_op.mul(&self.z, &mut self.y2);
        for k in 0..self.n {
            self.u[k] += dt * self.z[k];
            self.q[k] = 4.0 * self.y1[k] - dt * dt * self.y2[k] - self.q[k] - 2.0 * dt * self.s[k];
            self.s[k] += dt * self.y2[k];
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
            let mut nm = Newmark::new(&m, &c, &k, dt, &[]).unwrap();
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
