//! The dampers' Woodbury data and their parts of a step (the method: the module header): the
//! dampers' shape vectors gathered on one index set, Y = A₀⁻¹W, WᵀY and each lane's S⁻¹, built
//! at set-up; per step, v̄ corrected by Woodbury, the internal nodes' v̄_d and the dampers'
//! parts of M·v̄ and K·v̄.

use super::{Newmark, SVec};
use crate::config::DamperParams;
use crate::error::Result;
use crate::model::dampers::Attachment;

/// Shape vectors of all dampers' upper (or lower) points stored densely on the union of
/// their indices, so that a step gathers and scatters each stepper vector once and the
/// per-damper work is contiguous dots and axpys (the modal rail shapes of all dampers share
/// one index set).
#[derive(Clone, Debug, Default)]
pub(super) struct ShapeSet {
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
    pub(super) fn add_to<const W: usize>(&mut self, x: &mut [f64], w: &[f64]) {
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
pub(super) struct Attached {
    pub(super) upper: ShapeSet,
    pub(super) lower: ShapeSet,
    /// Stepper index of each internal node.
    pub(super) node: Vec<usize>,
    /// α_r and α_s, the upper and lower branches' parts of A; the upper branch's k and the
    /// lower branch's b (their parts of K and M: the upper branch has no inerter, the lower
    /// no spring).
    pub(super) alpha_r: Vec<f64>,
    pub(super) alpha_s: Vec<f64>,
    k: Vec<f64>,
    b: Vec<f64>,
    /// Y = A₀⁻¹·W by rows (`yt[k·N_t + i]` = (A₀⁻¹·w_i)_k), and for forward ports
    /// D⁻¹·L⁻¹·P·w_i.
    pub(super) yt: Vec<f64>,
    pub(super) lw: Vec<Vec<f64>>,
    /// WᵀA₀⁻¹W (row-major, N_t × N_t), and S⁻¹ = (K⁻¹ + WᵀA₀⁻¹W)⁻¹ of each lane at
    /// `[lane·N_t² + r·N_t + c]`.
    wty: Vec<f64>,
    pub(super) s_inv: Vec<f64>,
    /// S⁻¹·Wᵀ·A₀⁻¹·b of the step's known right-hand side, and scratch: Wᵀ·z, the upper and
    /// lower shapes' products with z, per-damper weights.
    pub(super) t_free: Vec<f64>,
    pub(super) wz: Vec<f64>,
    pu: Vec<f64>,
    pl: Vec<f64>,
    pub(super) wu: Vec<f64>,
    pub(super) wl: Vec<f64>,
}

impl Attached {
    pub(super) fn len(&self) -> usize {
        self.node.len()
    }

    /// wz = Wᵀ·x (W's columns: upper − lower shapes); also leaves the upper and lower
    /// products in pu, pl.
    pub(super) fn w_dots<const W: usize>(&mut self, x: &[f64]) {
        self.upper.dots::<W>(x, &mut self.pu);
        self.lower.dots::<W>(x, &mut self.pl);
        for ((w, u), l) in self.wz.iter_mut().zip(&self.pu).zip(&self.pl) {
            *w = u - l;
        }
    }

    /// out = S⁻¹·v per lane.
    pub(super) fn s_solve<const W: usize>(&self, v: &[f64], out: &mut [f64]) {
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

impl<const W: usize> Newmark<W> {
    /// Woodbury data of the dampers: Y = A₀⁻¹W (and L⁻¹W for forward ports), WᵀY, and every
    /// lane's S⁻¹ for the attachments' own parameters.
    pub(super) fn attach(&mut self, attachments: &[Attachment]) -> Result<()> {
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

    /// v̄ = A⁻¹b from z = A₀⁻¹b (Woodbury), then the damper nodes' v̄_d, then the dampers'
    /// parts of M·v̄ and K·v̄: b·(e_d − N_lower)(…)ᵀ and k·(N_upper − e_d)(…)ᵀ.
    pub(super) fn finish_dampers(&mut self) {
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
    pub(super) fn damper_products(&mut self) {
        let att = &mut self.att;
        if att.len() > 0 {
            att.lower.add_to::<W>(&mut self.y1, &att.wl);
            att.upper.add_to::<W>(&mut self.y2, &att.wu);
        }
    }
}
