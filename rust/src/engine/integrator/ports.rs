//! Sparse vectors in a stepper's numbering and the contact ports (the method: the module
//! header): a port block's data (forward-substituted vectors, the dampers' products with
//! them) and the stepper's port operations of a step — preparation (forward substitution or
//! cached columns of A⁻¹), free displacements, compliance and forces.

use super::{Engine, GW, Newmark};

/// Entries of a cached column of A⁻¹ below this fraction of its largest are dropped: they lie
/// below the rounding of every sum they enter. A = 2M + Δt·C + (Δt²/2)·K is dominated by its
/// mass part, so its inverse decays geometrically away from the diagonal (finite elements:
/// about tenfold per node at Δt = 5e-5 s) and a column shrinks to a window of a few dozen nodes.
const COLUMN_DROP: f64 = 1.0 / (1u64 << 60) as f64;

/// Entries the cached columns hold before the longest unused are dropped (32 MB). A train's
/// wheels follow each other over the same nodes, so a column computed for the first wheel
/// serves every wheel behind it while it stays: the budget holds a few thousand columns, a
/// train's length of rail.
const COLUMN_CACHE_VALUES: usize = 1 << 22;

/// A column of A⁻¹ restricted to the window `start..start + values.len()` outside which its
/// entries are negligible (`COLUMN_DROP`).
#[derive(Clone, Debug)]
pub(super) struct Column {
    start: usize,
    values: Vec<f64>,
    /// The last step that used it.
    used: u64,
}

impl Column {
    /// The column from its entries `window` at rows `offset..`, trimmed to `COLUMN_DROP`.
    fn new(window: &[f64], offset: usize, used: u64) -> Self {
        let big = window.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let keep = |v: &f64| v.abs() > COLUMN_DROP * big;
        let start = window.iter().position(keep).unwrap_or(0);
        let end = window.iter().rposition(keep).map_or(start, |e| e + 1);
        Self {
            start: offset + start,
            values: window[start..end].to_vec(),
            used,
        }
    }

    /// Column k of A⁻¹ (stepper numbering): windowed where the factor runs along the track
    /// (`Ldlt::column_window`: the work of the window, not of the structure), else a full
    /// solve. `scratch` is zero, and left so.
    fn solve(engine: &Engine, ns: usize, k: usize, scratch: &mut Vec<f64>, used: u64) -> Self {
        if let Engine::Sparse { factor, .. } = engine {
            scratch.resize(ns, 0.0);
            if let Some((lo, hi)) = factor.column_window(k, COLUMN_DROP, scratch) {
                let column = Self::new(&scratch[lo..hi], lo, used);
                scratch[lo..hi].fill(0.0);
                return column;
            }
        }
        let mut e = vec![0.0; ns];
        e[k] = 1.0;
        engine.solve_from::<1>(&mut e, k);
        Self::new(&e, 0, used)
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

/// The cached columns of A⁻¹ (column ports), by unknown (stepper numbering).
#[derive(Clone, Debug, Default)]
pub(super) struct Columns {
    map: std::collections::HashMap<usize, Column>,
    /// Entries held by all columns.
    values: usize,
    /// Steps begun.
    step: u64,
    /// Zeros, the length of the factorised unknowns (a windowed column's work space).
    scratch: Vec<f64>,
}

impl Columns {
    /// Starts a step. Beyond `COLUMN_CACHE_VALUES` the columns unused longest are dropped
    /// down to half of it, never one the last step used (its ports' unknowns, which the
    /// wheels have not left yet). Dropping only between steps: every port block of a step (one
    /// per car) finds its columns until the step ends.
    pub(super) fn begin_step(&mut self) {
        self.step += 1;
        if self.values <= COLUMN_CACHE_VALUES {
            return;
        }
        let mut stale: Vec<(u64, usize)> = self
            .map
            .iter()
            .filter(|(_, c)| c.used + 1 < self.step)
            .map(|(&k, c)| (c.used, k))
            .collect();
        stale.sort_unstable();
        for (_, k) in stale {
            if self.values <= COLUMN_CACHE_VALUES / 2 {
                break;
            }
            if let Some(c) = self.map.remove(&k) {
                self.values -= c.values.len();
            }
        }
    }

    /// Column k, solved on first use; marks it used.
    fn touch(&mut self, k: usize, engine: &Engine, ns: usize) {
        let step = self.step;
        if let Some(c) = self.map.get_mut(&k) {
            c.used = step;
            return;
        }
        let c = Column::solve(engine, ns, k, &mut self.scratch, step);
        self.values += c.values.len();
        self.map.insert(k, c);
    }
}

impl std::ops::Index<&usize> for Columns {
    type Output = Column;
    fn index(&self, k: &usize) -> &Column {
        &self.map[k]
    }
}

/// A sparse vector in a stepper's numbering.
#[derive(Clone, Debug, Default)]
pub struct SVec {
    pub idx: Vec<usize>,
    pub val: Vec<f64>,
    /// (start, length) of the shape vector it was built from: a shape on the same DOFs
    /// (a modal layer at any x) only needs new values.
    pub(super) key: Option<(usize, usize)>,
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
    /// First nonzero row in elimination order of `cols` and of `cols_f − cols`, and the end
    /// of the rows kept of `cols` (`Newmark::set_port_reach`; the unknowns' count otherwise).
    start: usize,
    fstart: usize,
    end: usize,
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
            end: n,
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

impl<const W: usize> Newmark<W> {
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
                    cache.touch(k, &self.engine, self.ns);
                }
            }
            return;
        }
        let s = ports.start.min(self.ns);
        // The last step's window and the partial sums it spilled past its end.
        let spill = self.engine.sparse().spill(ports.end).max(s);
        ports.cols[s * GW..spill * GW].fill(0.0);
        ports.start = self.ns;
        let mut last = 0;
        for (c, v) in ports.vecs.iter().enumerate() {
            for (&i, &val) in v.idx.iter().zip(&v.val) {
                ports.cols[i * GW + c] = val;
                ports.start = ports.start.min(i);
                last = last.max(i + 1);
            }
        }
        ports.end = self.ns.min(last.saturating_add(self.port_reach));
        self.engine.sparse().forward_until::<GW>(
            &mut ports.cols[..self.ns * GW],
            ports.start,
            ports.end,
        );
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
        for k in ports.start..ports.end {
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
            for k in a.start.max(b.start)..a.end.min(b.end) {
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
        for k in ports.start..ports.end {
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
}
