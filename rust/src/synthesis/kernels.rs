//! The passes over the modes of one step, for W jobs in lockstep (W = 1: a single run).
//!
//! Per step a run reads every mode twice: the wheel pass (`wheel_pass`: the wheels' modal
//! shapes ψᵀs from a few rows of ψ, their step compliance and the free rail displacement
//! under them) and the update pass (`update`: the forces in, the modes stepped, every
//! observer and damper port read out, the next step's free state). Both go block by block
//! over the modes so that a block's intermediate values stay in the L1 cache and every array
//! is streamed once per pass: the run is bound by memory traffic, not arithmetic.
//!
//! Lane arrays hold W interleaved jobs (`[j·W + c]`); shared arrays (ψ, the coefficients) one
//! value per mode. Every lane does the same floating-point operations in the same order
//! whatever W (dot products in `P` partial sums by mode index mod P, blocks a multiple of P),
//! so a job gives the same bits alone and in a group. Called inside `wide!`, the loops
//! vectorise over the modes (W = 1) or over the lanes.

use super::Reduction;
use super::step::Coefficients;
use crate::basis::Shape;
use crate::simd::PARTIAL_SUMS as P;

/// Modes per block: a multiple of P; 256 modes of a few lane arrays fit the L1 cache.
const BLOCK: usize = 256;
/// The width of the single-vector kernels.
const ONE: usize = 1;

/// A complex vector (re, im), over the modes (shared) or over modes × lanes.
#[derive(Clone, Debug, Default)]
pub(super) struct CVec {
    pub re: Vec<f64>,
    pub im: Vec<f64>,
}

impl CVec {
    pub fn zeros(n: usize) -> Self {
        Self {
            re: vec![0.0; n],
            im: vec![0.0; n],
        }
    }

    /// self = c ⊙ o for per-mode complex constants c (shared vectors).
    pub fn set_mul(&mut self, c: [&[f64]; 2], o: &CVec) {
        for j in 0..self.re.len() {
            let (a, b) = (o.re[j], o.im[j]);
            self.re[j] = c[0][j] * a - c[1][j] * b;
            self.im[j] = c[0][j] * b + c[1][j] * a;
        }
    }
}

/// A complex vector of W lanes over the modes: `[j][c]` is mode j of lane c.
#[derive(Clone, Debug)]
pub(super) struct LVec<const W: usize> {
    pub re: Vec<[f64; W]>,
    pub im: Vec<[f64; W]>,
}

impl<const W: usize> LVec<W> {
    pub fn zeros(n: usize) -> Self {
        Self {
            re: vec![[0.0; W]; n],
            im: vec![[0.0; W]; n],
        }
    }

    /// Lane c as a shared vector.
    pub fn lane(&self, c: usize) -> CVec {
        CVec {
            re: self.re.iter().map(|x| x[c]).collect(),
            im: self.im.iter().map(|x| x[c]).collect(),
        }
    }

    pub fn lane_finite(&self, c: usize) -> bool {
        self.re.iter().chain(&self.im).all(|x| x[c].is_finite())
    }

    /// Sets lane c to v at mode j.
    pub fn set(&mut self, j: usize, c: usize, v: (f64, f64)) {
        (self.re[j][c], self.im[j][c]) = v;
    }

    pub fn clear_lane(&mut self, c: usize) {
        for x in self.re.iter_mut().chain(self.im.iter_mut()) {
            x[c] = 0.0;
        }
    }
}


/// Partial sums of W lane dot products, by mode index mod P.
#[derive(Clone, Copy, Debug)]
pub(super) struct Acc<const W: usize>([[f64; W]; P]);

impl<const W: usize> Acc<W> {
    pub const ZERO: Self = Self([[0.0; W]; P]);

    /// The dot products: partial sums added pairwise.
    pub fn sum(&self) -> [f64; W] {
        let a = &self.0;
        std::array::from_fn(|c| {
            ((a[0][c] + a[1][c]) + (a[2][c] + a[3][c]))
                + ((a[4][c] + a[5][c]) + (a[6][c] + a[7][c]))
        })
    }
}

/// acc += Re Σ a·x for a shared vector a and a lane vector x (n modes, a multiple of P).
#[inline(always)]
fn cdot<const W: usize>(acc: &mut Acc<W>, ar: &[f64], ai: &[f64], xr: &[[f64; W]], xi: &[[f64; W]]) {
    let a = ar.chunks_exact(P).zip(ai.chunks_exact(P));
    let x = xr.chunks_exact(P).zip(xi.chunks_exact(P));
    let mut s = acc.0;
    for ((ar, ai), (xr, xi)) in a.zip(x) {
        for q in 0..P {
            for c in 0..W {
                s[q][c] = ar[q].mul_add(xr[q][c], (-ai[q]).mul_add(xi[q][c], s[q][c]));
            }
        }
    }
    acc.0 = s;
}

/// y[j][c] += x[j]·s[c] (a shared real vector times lane scalars).
#[inline(always)]
fn lane_axpy<const W: usize>(y: &mut [[f64; W]], x: &[f64], s: &[f64; W]) {
    for (yv, xv) in y.iter_mut().zip(x) {
        for c in 0..W {
            yv[c] = xv.mul_add(s[c], yv[c]);
        }
    }
}

/// y[j][c] += Σ_k x_k[j]·s_k[c] for four shared vectors (one pass over y).
#[inline(always)]
fn lane_axpy4<const W: usize>(y: &mut [[f64; W]], x: [&[f64]; 4], s: [&[f64; W]; 4]) {
    let [x0, x1, x2, x3] = x;
    let n = y.len();
    let (x0, x1, x2, x3) = (&x0[..n], &x1[..n], &x2[..n], &x3[..n]);
    for ((yv, (a, b)), (c, d)) in y.iter_mut().zip(x0.iter().zip(x1)).zip(x2.iter().zip(x3)) {
        for l in 0..W {
            yv[l] = a.mul_add(s[0][l], b.mul_add(s[1][l], c.mul_add(s[2][l], d.mul_add(s[3][l], yv[l]))));
        }
    }
}

/// y[j][c] += x[j] (a shared real vector added to every lane).
#[inline(always)]
fn lane_add<const W: usize>(y: &mut [[f64; W]], x: &[f64]) {
    for (yv, xv) in y.iter_mut().zip(x) {
        for c in 0..W {
            yv[c] += xv;
        }
    }
}

/// out[b0..b1] = Σ_k s_k·ψ(start + k)[b0..b1] (re, im).
#[inline(always)]
fn project_block(red: &Reduction, s: &Shape, b0: usize, b1: usize, or: &mut [f64], oi: &mut [f64]) {
    let mut first = true;
    for (k, &v) in s.values.iter().enumerate() {
        if v == 0.0 {
            continue;
        }
        let (rr, ri) = red.row(s.start + k);
        let (rr, ri) = (&rr[b0..b1], &ri[b0..b1]);
        if first {
            for (o, x) in or.iter_mut().zip(rr) {
                *o = v * x;
            }
            for (o, x) in oi.iter_mut().zip(ri) {
                *o = v * x;
            }
            first = false;
        } else {
            for (o, x) in or.iter_mut().zip(rr) {
                *o = v.mul_add(*x, *o);
            }
            for (o, x) in oi.iter_mut().zip(ri) {
                *o = v.mul_add(*x, *o);
            }
        }
    }
    if first {
        or.fill(0.0);
        oi.fill(0.0);
    }
}

/// Re Σ a·x for two shared vectors (length a multiple of P).
pub(super) fn dot(ar: &[f64], ai: &[f64], xr: &[f64], xi: &[f64]) -> f64 {
    crate::wide!(<ONE> (ar: &[f64] = ar, ai: &[f64] = ai, xr: &[f64] = xr, xi: &[f64] = xi) -> f64 {
        let mut acc = Acc::<1>::ZERO;
        let (xr, xi): (&[[f64; 1]], &[[f64; 1]]) = (xr.as_chunks().0, xi.as_chunks().0);
        cdot::<1>(&mut acc, ar, ai, xr, xi);
        acc.sum()[0]
    })
}

/// out = ψᵀs (padded length).
pub(super) fn project(red: &Reduction, s: &Shape, out: &mut CVec) {
    crate::wide!(<ONE> (red: &Reduction = red, s: &Shape = s, or: &mut [f64] = &mut out.re, oi: &mut [f64] = &mut out.im) {
        let n = or.len();
        project_block(red, s, 0, n, or, &mut oi[..n]);
    })
}

/// The wheel pass: for each wheel of shape `shapes[w]`, `outs[w]` = ψᵀs, its step compliance
/// Re Σ a1·(ψᵀs)² into `diag[w]` and, per lane, the free rail displacement under it
/// Re Σ (ψᵀs)·Q̃ into `rail[w]`. All wheels go through one block at a time, so that the
/// block of a1 and Q̃ is read once for all of them.
pub(super) struct WheelPass<'a, const W: usize> {
    pub shapes: &'a [Shape],
    pub outs: &'a mut [CVec],
    pub diag: &'a mut [Acc<1>],
    pub rail: &'a mut [Acc<W>],
}

pub(super) fn wheel_pass<const W: usize>(red: &Reduction, coef: &Coefficients, q_free: &LVec<W>, p: WheelPass<'_, W>) {
    crate::wide!(<W> (red: &Reduction = red, coef: &Coefficients = coef, qf: &LVec<W> = q_free, p: WheelPass<'_, W> = p) {
        let WheelPass { shapes, outs, diag, rail } = p;
        let n = red.stride;
        diag.fill(Acc::ZERO);
        rail.fill(Acc::ZERO);
        let mut b0 = 0;
        while b0 < n {
            let b1 = (b0 + BLOCK).min(n);
            let (a1r, a1i) = (&coef.a1[0][b0..b1], &coef.a1[1][b0..b1]);
            let (qr, qi) = (&qf.re[b0..b1], &qf.im[b0..b1]);
            for (((s, out), d), r) in shapes.iter().zip(outs.iter_mut()).zip(diag.iter_mut()).zip(rail.iter_mut()) {
                let (or, oi) = (&mut out.re[b0..b1], &mut out.im[b0..b1]);
                project_block(red, s, b0, b1, or, oi);
                let chunks = or.chunks_exact(P).zip(oi.chunks_exact(P)).zip(a1r.chunks_exact(P).zip(a1i.chunks_exact(P)));
                // Partial sums in registers over the block.
                let mut acc = d.0.map(|x| x[0]);
                for ((or, oi), (a1r, a1i)) in chunks {
                    for q in 0..P {
                        let tr = a1r[q] * or[q] - a1i[q] * oi[q];
                        let ti = a1r[q] * oi[q] + a1i[q] * or[q];
                        acc[q] = tr.mul_add(or[q], (-ti).mul_add(oi[q], acc[q]));
                    }
                }
                d.0 = acc.map(|x| [x]);
                cdot::<W>(r, or, oi, qr, qi);
            }
            b0 = b1;
        }
    })
}

/// Lane-block scratch of the update pass.
#[derive(Clone, Debug)]
pub(super) struct Scratch<const W: usize> {
    dg: LVec<W>,
    q: LVec<W>,
    qa: LVec<W>,
    wg: LVec<W>,
    z: LVec<W>,
}

impl<const W: usize> Scratch<W> {
    pub fn new() -> Self {
        Self {
            dg: LVec::zeros(BLOCK),
            q: LVec::zeros(BLOCK),
            qa: LVec::zeros(BLOCK),
            wg: LVec::zeros(BLOCK),
            z: LVec::zeros(BLOCK),
        }
    }
}

/// What the update pass reads and writes.
pub(super) struct Update<'a, const W: usize> {
    pub coef: &'a Coefficients,
    /// The port vectors ψᵀ(shape) — wheels, then dampers — and each one's force per lane
    /// this step (N; a damper's −F).
    pub ports: &'a [CVec],
    pub forces: &'a [[f64; W]],
    /// The moving forces' modal force at t_{n+1} and t_{n+2} (shared), if any.
    pub movers: Option<(&'a CVec, &'a CVec)>,
    /// The observers' ψᵀs; out, per observer: Re Σ ψᵀs·Q (displacement), Re Σ ψᵀs·λ(λQ + w·g)
    /// (acceleration without the force-rate term), Re Σ ψᵀs·λw·g and Re Σ ψᵀs·w·g (whose rate
    /// is that term): `run::records` makes the records of them.
    pub observers: &'a [CVec],
    pub observed: &'a mut [Acc<W>],
    /// Ports from `dampers_from` on: out, their free displacement Re Σ ψᵀs·Q̃_{n+2}.
    pub dampers_from: usize,
    pub damper_free: &'a mut [Acc<W>],
}

/// The update pass of a step: with Δg = Σ_ports f·ψᵀs (the forces found this step),
///
///   g_{n+1} = g_known + Δg,  Q_{n+1} = Q̃_{n+1} + a1·Δg,
///   Q̈ = λ(λQ + w·g) + w·ġ,
///   Q̃_{n+2} = e·Q_{n+1} + a0·g_{n+1} + a1·g_known,n+2,
///
/// the observers read Re Σ ψᵀs·Q, Re Σ ψᵀs·λ(λQ + w·g), Re Σ ψᵀs·λw·g and Re Σ ψᵀs·w·g,
/// the dampers Re Σ ψᵀs·Q̃_{n+2}. `q_free` (Q̃) and `g` advance in place.
pub(super) fn update<const W: usize>(
    u: Update<'_, W>,
    q_free: &mut LVec<W>,
    g: &mut LVec<W>,
    scratch: &mut Scratch<W>,
) {
    crate::wide!(<W> (u: Update<'_, W> = u, qf: &mut LVec<W> = q_free, g: &mut LVec<W> = g, sc: &mut Scratch<W> = scratch) {
        let Update { coef, ports, forces, movers, observers, observed, dampers_from, damper_free } = u;
        let n = coef.w.len();
        for acc in observed.iter_mut().chain(damper_free.iter_mut()) {
            *acc = Acc::ZERO;
        }
        let zero = [0.0; BLOCK];
        let mut b0 = 0;
        while b0 < n {
            let b1 = (b0 + BLOCK).min(n);
            let nb = b1 - b0;
            let (dgr, dgi) = (&mut sc.dg.re[..nb], &mut sc.dg.im[..nb]);
            dgr.fill([0.0; W]);
            dgi.fill([0.0; W]);
            // Four ports at a time: one pass over the block's Δg per four.
            for (v, f) in ports.chunks(4).zip(forces.chunks(4)) {
                if let ([v0, v1, v2, v3], [f0, f1, f2, f3]) = (v, f) {
                    let f = [f0, f1, f2, f3];
                    lane_axpy4::<W>(dgr, [&v0.re[b0..b1], &v1.re[b0..b1], &v2.re[b0..b1], &v3.re[b0..b1]], f);
                    lane_axpy4::<W>(dgi, [&v0.im[b0..b1], &v1.im[b0..b1], &v2.im[b0..b1], &v3.im[b0..b1]], f);
                } else {
                    for (v, f) in v.iter().zip(f) {
                        lane_axpy::<W>(dgr, &v.re[b0..b1], f);
                        lane_axpy::<W>(dgi, &v.im[b0..b1], f);
                    }
                }
            }
            let (er, ei) = (&coef.e[0][b0..b1], &coef.e[1][b0..b1]);
            let (a0r, a0i) = (&coef.a0[0][b0..b1], &coef.a0[1][b0..b1]);
            let (a1r, a1i) = (&coef.a1[0][b0..b1], &coef.a1[1][b0..b1]);
            let (lr, li, w) = (&coef.lam[0][b0..b1], &coef.lam[1][b0..b1], &coef.w[b0..b1]);
            let (qfr, qfi) = (&mut qf.re[b0..b1], &mut qf.im[b0..b1]);
            let (gr, gi) = (&mut g.re[b0..b1], &mut g.im[b0..b1]);
            let (qr, qi) = (&mut sc.q.re[..nb], &mut sc.q.im[..nb]);
            let (qar, qai) = (&mut sc.qa.re[..nb], &mut sc.qa.im[..nb]);
            let (k0r, k0i, k1r, k1i) = match movers {
                Some((k0, k1)) => (&k0.re[b0..b1], &k0.im[b0..b1], &k1.re[b0..b1], &k1.im[b0..b1]),
                None => (&zero[..nb], &zero[..nb], &zero[..nb], &zero[..nb]),
            };
            // A few arrays per loop, so that each vectorises over the modes (W = 1) or the
            // lanes; the block's intermediate values stay in L1.
            // Q = Q̃ + a1·Δg, with Δg = g_{n+1} − g_known.
            for ((((yr, yi), (fr, fi)), (dr, di)), (a1r, a1i)) in qr.iter_mut().zip(qi.iter_mut())
                .zip(qfr.iter().zip(qfi.iter())).zip(dgr.iter().zip(dgi.iter()))
                .zip(a1r.iter().zip(a1i))
            {
                for c in 0..W {
                    yr[c] = a1r.mul_add(dr[c], (-a1i).mul_add(di[c], fr[c]));
                    yi[c] = a1r.mul_add(di[c], a1i.mul_add(dr[c], fi[c]));
                }
            }
            if movers.is_some() {
                lane_add::<W>(dgr, k0r);
                lane_add::<W>(dgi, k0i);
            }
            let (gnr, gni): (&[[f64; W]], &[[f64; W]]) = (dgr, dgi);
            // w·g, and Q̈ without the force-rate term: λ(λQ + w·g); λw·g; g advances.
            let (wgr, wgi) = (&mut sc.wg.re[..nb], &mut sc.wg.im[..nb]);
            let (zr, zi) = (&mut sc.z.re[..nb], &mut sc.z.im[..nb]);
            for ((((vr, vi), (yr, yi)), ((dr, di), (wr, wi))), ((lr, li), w)) in qar.iter_mut().zip(qai.iter_mut())
                .zip(qr.iter().zip(qi.iter())).zip(gnr.iter().zip(gni.iter()).zip(wgr.iter_mut().zip(wgi.iter_mut())))
                .zip(lr.iter().zip(li).zip(w))
            {
                for c in 0..W {
                    (wr[c], wi[c]) = (w * dr[c], w * di[c]);
                    vr[c] = lr.mul_add(yr[c], (-li).mul_add(yi[c], wr[c]));
                    vi[c] = lr.mul_add(yi[c], li.mul_add(yr[c], wi[c]));
                }
            }
            for ((((ar, ai), (gr, gi)), ((dr, di), (zr, zi))), ((lr, li), (wr, wi))) in qar.iter_mut().zip(qai.iter_mut())
                .zip(gr.iter_mut().zip(gi.iter_mut())).zip(gnr.iter().zip(gni.iter()).zip(zr.iter_mut().zip(zi.iter_mut())))
                .zip(lr.iter().zip(li).zip(wgr.iter().zip(wgi.iter())))
            {
                for c in 0..W {
                    let (vr, vi) = (ar[c], ai[c]);
                    ar[c] = lr.mul_add(vr, -li * vi);
                    ai[c] = lr.mul_add(vi, li * vr);
                    zr[c] = lr.mul_add(wr[c], -li * wi[c]);
                    zi[c] = lr.mul_add(wi[c], li * wr[c]);
                    gr[c] = dr[c];
                    gi[c] = di[c];
                }
            }
            // Q̃_{n+2} = e·Q + a0·g_{n+1} (+ a1·g_known,n+2).
            for ((((fr, fi), (yr, yi)), (dr, di)), ((er, ei), (a0r, a0i))) in qfr.iter_mut().zip(qfi.iter_mut())
                .zip(qr.iter().zip(qi.iter())).zip(gnr.iter().zip(gni.iter()))
                .zip(er.iter().zip(ei).zip(a0r.iter().zip(a0i)))
            {
                for c in 0..W {
                    fr[c] = er.mul_add(yr[c], (-ei).mul_add(yi[c], a0r.mul_add(dr[c], -a0i * di[c])));
                    fi[c] = er.mul_add(yi[c], ei.mul_add(yr[c], a0r.mul_add(di[c], a0i * dr[c])));
                }
            }
            if movers.is_some() {
                for (((fr, fi), (a1r, a1i)), (kr, ki)) in qfr.iter_mut().zip(qfi.iter_mut())
                    .zip(a1r.iter().zip(a1i)).zip(k1r.iter().zip(k1i))
                {
                    let (ar, ai) = (a1r.mul_add(*kr, -a1i * ki), a1r.mul_add(*ki, a1i * kr));
                    for c in 0..W {
                        fr[c] += ar;
                        fi[c] += ai;
                    }
                }
            }
            for (o, acc) in observers.iter().zip(observed.chunks_exact_mut(4)) {
                let (or, oi) = (&o.re[b0..b1], &o.im[b0..b1]);
                cdot::<W>(&mut acc[0], or, oi, qr, qi);
                cdot::<W>(&mut acc[1], or, oi, qar, qai);
                cdot::<W>(&mut acc[2], or, oi, zr, zi);
                cdot::<W>(&mut acc[3], or, oi, wgr, wgi);
            }
            for (d, acc) in ports[dampers_from..].iter().zip(damper_free.iter_mut()) {
                cdot::<W>(acc, &d.re[b0..b1], &d.im[b0..b1], qfr, qfi);
            }
            b0 = b1;
        }
    })
}
