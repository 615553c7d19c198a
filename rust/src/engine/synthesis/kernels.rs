//! The passes over the modes of one step, for W jobs in lockstep (W = 1: a single run).
//!
//! Per step a run reads every mode twice: the wheel pass (`wheel_pass`: the wheels' modal
//! shapes ψᵀs from a few rows of ψ, their step compliance and the free rail displacement
//! under them) and the update pass (`update`: the forces in, the modes stepped, every
//! observer and damper port read out, the next step's free state). Both go block by block
//! over the modes: a block of the shared arrays (ψ, the coefficients, the ports) is read from
//! memory once and used by every lane while it is in cache, and a block's intermediate values
//! never leave the L1 cache. The run is bound by memory traffic, not arithmetic.
//!
//! Each lane's state is a vector of its own, and every lane runs the same single-vector code
//! on its slice of a block (dot products in `P` partial sums by mode index mod P, blocks a
//! multiple of P): a job gives the same bits alone and in a group. Called inside `wide!`, the
//! loops vectorise over the modes.

use super::Reduction;
use super::step::Coefficients;
use crate::linalg::simd::PARTIAL_SUMS as P;
use crate::model::basis::Shape;

/// Modes per block: a multiple of P, small enough for a block of every shared array a lane
/// reads to stay in cache for the next lane.
const BLOCK: usize = 256;
/// The lane count of the single-vector kernels (`wide!` is generic over lanes).
const ONE: usize = 1;

/// A complex vector (re, im) over the (padded) modes.
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

    /// The (re, im) parts, as `set_mul` takes them.
    pub fn parts(&self) -> [&[f64]; 2] {
        [&self.re, &self.im]
    }

    /// self = c ⊙ o for per-mode complex constants c and a complex vector o given by its
    /// (re, im) parts (a `CVec`'s or a row of ψ).
    pub fn set_mul(&mut self, c: [&[f64]; 2], o: [&[f64]; 2]) {
        for j in 0..self.re.len() {
            let (a, b) = (o[0][j], o[1][j]);
            self.re[j] = c[0][j] * a - c[1][j] * b;
            self.im[j] = c[0][j] * b + c[1][j] * a;
        }
    }

    pub fn is_finite(&self) -> bool {
        self.re.iter().chain(&self.im).all(|x| x.is_finite())
    }

    pub fn clear(&mut self) {
        self.re.fill(0.0);
        self.im.fill(0.0);
    }
}

/// Partial sums of one dot product per lane, by mode index mod P.
#[derive(Clone, Copy, Debug)]
pub(super) struct Acc<const W: usize>([[f64; P]; W]);

impl<const W: usize> Acc<W> {
    pub const ZERO: Self = Self([[0.0; P]; W]);

    /// The dot products: partial sums added pairwise.
    pub fn sum(&self) -> [f64; W] {
        self.0
            .map(|a| ((a[0] + a[1]) + (a[2] + a[3])) + ((a[4] + a[5]) + (a[6] + a[7])))
    }
}

/// acc += Re Σ a·x over a block (a length that is a multiple of P).
#[inline(always)]
fn cdot(acc: &mut [f64; P], ar: &[f64], ai: &[f64], xr: &[f64], xi: &[f64]) {
    let a = ar.chunks_exact(P).zip(ai.chunks_exact(P));
    let x = xr.chunks_exact(P).zip(xi.chunks_exact(P));
    let mut s = *acc;
    for ((ar, ai), (xr, xi)) in a.zip(x) {
        for q in 0..P {
            s[q] = ar[q].mul_add(xr[q], (-ai[q]).mul_add(xi[q], s[q]));
        }
    }
    *acc = s;
}

/// y = Σ_k s_k·x_k (`ADD`: y += …) for N vectors in one pass over y.
#[inline(always)]
fn combine<const N: usize, const ADD: bool>(y: &mut [f64], x: [&[f64]; N], s: [f64; N]) {
    let n = y.len();
    let x = x.map(|x| &x[..n]);
    for (j, y) in y.iter_mut().enumerate() {
        let mut a = if ADD { *y } else { 0.0 };
        for k in 0..N {
            a = x[k][j].mul_add(s[k], a);
        }
        *y = a;
    }
}

/// y (+)= Σ_k s_k·x_k for up to four vectors (`combine` by count).
#[inline(always)]
fn combine_up_to_4<const ADD: bool>(y: &mut [f64], x: &[&[f64]], s: &[f64]) {
    match x.len() {
        1 => combine::<1, ADD>(y, [x[0]], [s[0]]),
        2 => combine::<2, ADD>(y, [x[0], x[1]], [s[0], s[1]]),
        3 => combine::<3, ADD>(y, [x[0], x[1], x[2]], [s[0], s[1], s[2]]),
        _ => combine::<4, ADD>(y, [x[0], x[1], x[2], x[3]], [s[0], s[1], s[2], s[3]]),
    }
}

/// out[b0..b1] = Σ_k s_k·ψ(start + k)[b0..b1] (re, im): the nonzero rows four at a time, so
/// the output is written once per four rows (the pass is bound by these loads and stores).
#[inline(always)]
fn project_block(red: &Reduction, s: &Shape, b0: usize, b1: usize, or: &mut [f64], oi: &mut [f64]) {
    let mut rows = s
        .values
        .iter()
        .enumerate()
        .filter(|(_, v)| **v != 0.0)
        .map(|(k, &v)| (red.row(s.start + k), v));
    let mut first = true;
    loop {
        let (mut re, mut im, mut v) = ([&[][..]; 4], [&[][..]; 4], [0.0; 4]);
        let mut k = 0;
        for ((rr, ri), x) in rows.by_ref().take(4) {
            (re[k], im[k], v[k]) = (&rr[b0..b1], &ri[b0..b1], x);
            k += 1;
        }
        match (k, first) {
            (0, true) => {
                or.fill(0.0);
                oi.fill(0.0);
            }
            (0, false) => {}
            (_, true) => {
                combine_up_to_4::<false>(or, &re[..k], &v[..k]);
                combine_up_to_4::<false>(oi, &im[..k], &v[..k]);
            }
            (_, false) => {
                combine_up_to_4::<true>(or, &re[..k], &v[..k]);
                combine_up_to_4::<true>(oi, &im[..k], &v[..k]);
            }
        }
        if k < 4 {
            break;
        }
        first = false;
    }
}

/// Re Σ a·x for two vectors (length a multiple of P).
pub(super) fn dot(ar: &[f64], ai: &[f64], xr: &[f64], xi: &[f64]) -> f64 {
    crate::wide!(<ONE> (ar: &[f64] = ar, ai: &[f64] = ai, xr: &[f64] = xr, xi: &[f64] = xi) -> f64 {
        let mut acc = [0.0; P];
        cdot(&mut acc, ar, ai, xr, xi);
        Acc::<1>([acc]).sum()[0]
    })
}

/// out = ψᵀs (padded length).
pub(super) fn project(red: &Reduction, s: &Shape, out: &mut CVec) {
    crate::wide!(<ONE> (red: &Reduction = red, s: &Shape = s, or: &mut [f64] = &mut out.re, oi: &mut [f64] = &mut out.im) {
        let n = or.len();
        project_block(red, s, 0, n, or, &mut oi[..n]);
    })
}

/// out = Σ_m P_m·ψᵀs_m: the moving forces' modal force in one pass over the modes, block by
/// block (each force's block of ψᵀs made in a stack buffer and added while in cache), the
/// forces off the structure (an all-zero shape) skipped. Each mode's value takes the same
/// operations in the same order as `project` then P·ψᵀs added force by force, so the result
/// is that sum's bits.
pub(super) fn load_movers(red: &Reduction, shapes: &[Shape], magnitudes: &[f64], out: &mut CVec) {
    crate::wide!(<ONE> (red: &Reduction = red, shapes: &[Shape] = shapes, p: &[f64] = magnitudes, or: &mut [f64] = &mut out.re, oi: &mut [f64] = &mut out.im) {
        or.fill(0.0);
        oi.fill(0.0);
        let (mut br, mut bi) = ([0.0; BLOCK], [0.0; BLOCK]);
        let on = |s: &&Shape| s.values.iter().any(|&v| v != 0.0);
        let n = or.len();
        for b0 in (0..n).step_by(BLOCK) {
            let b1 = (b0 + BLOCK).min(n);
            let (yr, yi) = (&mut or[b0..b1], &mut oi[b0..b1]);
            let (tr, ti) = (&mut br[..b1 - b0], &mut bi[..b1 - b0]);
            for (s, &pm) in shapes.iter().zip(p).filter(|(s, _)| on(s)) {
                project_block(red, s, b0, b1, tr, ti);
                for j in 0..yr.len() {
                    yr[j] = pm.mul_add(tr[j], yr[j]);
                    yi[j] = pm.mul_add(ti[j], yi[j]);
                }
            }
        }
    })
}

/// The modes' step compliance between rail DOFs, D(k, k + d) = Re Σ a1·ψ_k·ψ_{k+d} for
/// d < `span` (the longest wheel shape). A wheel's own step compliance Re Σ a1·(ψᵀs)² = sᵀDs
/// is then a sum over its few DOFs, not a pass over the modes every step; the table depends
/// on the step only, so the runs of a study share it (`Reduction::rail_step_compliance`).
#[derive(Debug)]
pub(super) struct RailStepCompliance {
    span: usize,
    table: Vec<f64>,
}

impl RailStepCompliance {
    pub fn new(red: &Reduction, coef: &Coefficients, span: usize) -> Self {
        let mut table = vec![0.0; red.rail_dofs * span];
        let mut scaled = CVec::zeros(red.stride);
        for (k, row) in table.chunks_exact_mut(span).enumerate() {
            let (rr, ri) = red.row(k);
            scaled.set_mul([&coef.a1[0], &coef.a1[1]], [rr, ri]);
            for (d, l) in (k..(k + span).min(red.rail_dofs)).enumerate() {
                let (xr, xi) = red.row(l);
                row[d] = dot(&scaled.re, &scaled.im, xr, xi);
            }
        }
        Self { span, table }
    }

    /// sᵀDs for a rail shape of at most `span` values.
    pub fn quadratic(&self, s: &Shape) -> f64 {
        debug_assert!(
            s.values.len() <= self.span,
            "a wheel shape longer than the span"
        );
        let mut out = 0.0;
        for (i, a) in s.values.iter().enumerate() {
            let row = &self.table[(s.start + i) * self.span..];
            out += a * a * row[0];
            for (d, b) in s.values[i + 1..].iter().enumerate() {
                out += 2.0 * a * b * row[d + 1];
            }
        }
        out
    }
}

/// What the wheel pass reads and writes: for each wheel of shape `shapes[w]`, `outs[w]` =
/// ψᵀs and, per lane, the free rail displacement under it Re Σ (ψᵀs)·Q̃ into `rail[w]`.
pub(super) struct WheelPass<'a, const W: usize> {
    pub shapes: &'a [Shape],
    /// Wheels on the structure; the others (a zero shape) are skipped, their `outs` already
    /// zero.
    pub active: &'a [bool],
    pub outs: &'a mut [CVec],
    pub rail: &'a mut [Acc<W>],
}

/// The wheel pass (see `WheelPass`), all wheels and lanes one block at a time.
pub(super) fn wheel_pass<const W: usize>(red: &Reduction, q_free: &[CVec; W], p: WheelPass<'_, W>) {
    crate::wide!(<W> (red: &Reduction = red, qf: &[CVec; W] = q_free, p: WheelPass<'_, W> = p) {
        let WheelPass { shapes, active, outs, rail } = p;
        let n = red.stride;
        rail.fill(Acc::ZERO);
        let mut b0 = 0;
        while b0 < n {
            let b1 = (b0 + BLOCK).min(n);
            for (((s, out), r), _) in shapes.iter().zip(outs.iter_mut()).zip(rail.iter_mut())
                .zip(active).filter(|(_, on)| **on)
            {
                let (or, oi) = (&mut out.re[b0..b1], &mut out.im[b0..b1]);
                project_block(red, s, b0, b1, or, oi);
                for (acc, q) in r.0.iter_mut().zip(qf) {
                    cdot(acc, or, oi, &q.re[b0..b1], &q.im[b0..b1]);
                }
            }
            b0 = b1;
        }
    })
}

/// One lane's block scratch of the update pass.
#[derive(Clone, Debug)]
pub(super) struct Scratch {
    dg: CVec,
    q: CVec,
}

impl Scratch {
    pub fn new() -> Self {
        Self {
            dg: CVec::zeros(BLOCK),
            q: CVec::zeros(BLOCK),
        }
    }
}

/// acc[k] += Re Σ a_k·x over a block for four vectors a_k (x read once).
#[inline(always)]
fn cdot4(acc: [&mut [f64; P]; 4], a: [(&[f64], &[f64]); 4], xr: &[f64], xi: &[f64]) {
    let mut s = acc.each_ref().map(|a| **a);
    let n = xr.len();
    let a = a.map(|(r, i)| (&r[..n], &i[..n]));
    for (c, (xr, xi)) in xr.chunks_exact(P).zip(xi.chunks_exact(P)).enumerate() {
        for (k, (ar, ai)) in a.iter().enumerate() {
            let (ar, ai) = (&ar[c * P..(c + 1) * P], &ai[c * P..(c + 1) * P]);
            for q in 0..P {
                s[k][q] = ar[q].mul_add(xr[q], (-ai[q]).mul_add(xi[q], s[k][q]));
            }
        }
    }
    for (a, s) in acc.into_iter().zip(s) {
        *a = s;
    }
}

/// What the update pass reads and writes.
pub(super) struct Update<'a, const W: usize> {
    pub coef: &'a Coefficients,
    /// The port vectors ψᵀ(shape) — wheels, then dampers — and each one's force per lane
    /// this step (N; a damper's −F).
    pub ports: &'a [CVec],
    pub forces: &'a [[f64; W]],
    /// Ports that carry a force (a wheel off the structure has a zero port and is skipped).
    pub active: &'a [bool],
    /// The moving forces' modal force at t_{n+1} and t_{n+2} (shared), if any.
    pub movers: Option<(&'a CVec, &'a CVec)>,
    /// The observers' ψᵀs and λ²ψᵀs; out, per observer: Re Σ ψᵀs·Q and Re Σ λ²ψᵀs·Q (the
    /// displacement, and the acceleration but for the force's direct terms).
    pub observers: &'a [[CVec; 2]],
    pub observed: &'a mut [Acc<W>],
    /// Ports from `dampers_from` on: out, their free displacement Re Σ ψᵀs·Q̃_{n+2}.
    pub dampers_from: usize,
    pub damper_free: &'a mut [Acc<W>],
}

/// The update pass of a step: with Δg = Σ_ports f·ψᵀs (the forces found this step),
///
///   g_{n+1} = g_known + Δg,  Q_{n+1} = Q̃_{n+1} + a1·Δg,
///   Q̃_{n+2} = e·Q_{n+1} + a0·g_{n+1} + a1·g_known,n+2,
///
/// the observers read Re Σ ψᵀs·Q and Re Σ λ²ψᵀs·Q (of Q̈ = λ²Q + λw·g + w·ġ; the force's
/// terms are the caller's, `run`), the dampers Re Σ ψᵀs·Q̃_{n+2}. `q_free` (Q̃) advances in place.
pub(super) fn update<const W: usize>(
    u: Update<'_, W>,
    q_free: &mut [CVec; W],
    scratch: &mut Scratch,
) {
    crate::wide!(<W> (u: Update<'_, W> = u, qf: &mut [CVec; W] = q_free, sc: &mut Scratch = scratch) {
        let Update { coef, ports, forces, active, movers, observers, observed, dampers_from, damper_free } = u;
        let n = coef.w.len();
        for acc in observed.iter_mut().chain(damper_free.iter_mut()) {
            *acc = Acc::ZERO;
        }
        let mut b0 = 0;
        while b0 < n {
            let b1 = (b0 + BLOCK).min(n);
            let nb = b1 - b0;
            let (er, ei) = (&coef.e[0][b0..b1], &coef.e[1][b0..b1]);
            let (a0r, a0i) = (&coef.a0[0][b0..b1], &coef.a0[1][b0..b1]);
            let (a1r, a1i) = (&coef.a1[0][b0..b1], &coef.a1[1][b0..b1]);
            for c in 0..W {
                let (dgr, dgi) = (&mut sc.dg.re[..nb], &mut sc.dg.im[..nb]);
                dgr.fill(0.0);
                dgi.fill(0.0);
                // Four active ports at a time: one pass over the block's Δg per four.
                let (mut re, mut im, mut s) = ([&[][..]; 4], [&[][..]; 4], [0.0; 4]);
                let mut k = 0;
                let mut on = ports.iter().zip(forces).zip(active).filter(|(_, on)| **on).peekable();
                while let Some(((v, f), _)) = on.next() {
                    (re[k], im[k], s[k]) = (&v.re[b0..b1], &v.im[b0..b1], f[c]);
                    k += 1;
                    if k == 4 || on.peek().is_none() {
                        combine_up_to_4::<true>(dgr, &re[..k], &s[..k]);
                        combine_up_to_4::<true>(dgi, &im[..k], &s[..k]);
                        k = 0;
                    }
                }
                let (qfr, qfi) = (&mut qf[c].re[b0..b1], &mut qf[c].im[b0..b1]);
                let (qr, qi) = (&mut sc.q.re[..nb], &mut sc.q.im[..nb]);
                // Q = Q̃ + a1·Δg.
                for (((yr, yi), (fr, fi)), ((dr, di), (a1r, a1i))) in qr.iter_mut().zip(qi.iter_mut())
                    .zip(qfr.iter().zip(qfi.iter())).zip(dgr.iter().zip(dgi.iter()).zip(a1r.iter().zip(a1i)))
                {
                    *yr = a1r.mul_add(*dr, (-a1i).mul_add(*di, *fr));
                    *yi = a1r.mul_add(*di, a1i.mul_add(*dr, *fi));
                }
                // g_{n+1} = Δg + g_known.
                if let Some((k0, _)) = movers {
                    for (d, k) in dgr.iter_mut().zip(&k0.re[b0..b1]) {
                        *d += k;
                    }
                    for (d, k) in dgi.iter_mut().zip(&k0.im[b0..b1]) {
                        *d += k;
                    }
                }
                let (gnr, gni): (&[f64], &[f64]) = (dgr, dgi);
                // Q̃_{n+2} = e·Q + a0·g_{n+1} (+ a1·g_known,n+2).
                for ((((fr, fi), (yr, yi)), (dr, di)), ((er, ei), (a0r, a0i))) in qfr.iter_mut().zip(qfi.iter_mut())
                    .zip(qr.iter().zip(qi.iter())).zip(gnr.iter().zip(gni.iter()))
                    .zip(er.iter().zip(ei).zip(a0r.iter().zip(a0i)))
                {
                    *fr = er.mul_add(*yr, (-ei).mul_add(*yi, a0r.mul_add(*dr, -a0i * di)));
                    *fi = er.mul_add(*yi, ei.mul_add(*yr, a0r.mul_add(*di, a0i * dr)));
                }
                if let Some((_, k1)) = movers {
                    for (((fr, fi), (a1r, a1i)), (kr, ki)) in qfr.iter_mut().zip(qfi.iter_mut())
                        .zip(a1r.iter().zip(a1i)).zip(k1.re[b0..b1].iter().zip(&k1.im[b0..b1]))
                    {
                        *fr += a1r.mul_add(*kr, -a1i * ki);
                        *fi += a1r.mul_add(*ki, a1i * kr);
                    }
                }
                for ([o, l2], acc) in observers.iter().zip(observed.chunks_exact_mut(2)) {
                    let [a0, a1] = acc else { unreachable!() };
                    let (or, oi, lr, li) = (&o.re[b0..b1], &o.im[b0..b1], &l2.re[b0..b1], &l2.im[b0..b1]);
                    cdot(&mut a0.0[c], or, oi, qr, qi);
                    cdot(&mut a1.0[c], lr, li, qr, qi);
                }
                // Four dampers at a time: Q̃ read once per four.
                let dampers = &ports[dampers_from..];
                for (d, acc) in dampers.chunks(4).zip(damper_free.chunks_mut(4)) {
                    match (d, acc) {
                        ([d0, d1, d2, d3], [f0, f1, f2, f3]) => {
                            let v = [d0, d1, d2, d3].map(|d| (&d.re[b0..b1], &d.im[b0..b1]));
                            let accs = [&mut f0.0[c], &mut f1.0[c], &mut f2.0[c], &mut f3.0[c]];
                            cdot4(accs, v, qfr, qfi);
                        }
                        (d, acc) => {
                            for (d, acc) in d.iter().zip(acc) {
                                cdot(&mut acc.0[c], &d.re[b0..b1], &d.im[b0..b1], qfr, qfi);
                            }
                        }
                    }
                }
            }
            b0 = b1;
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reduction of `m` arbitrary stable modes on `n` DOFs, all rail, from a fixed sequence.
    fn reduction(m: usize, n: usize) -> Reduction {
        let mut seed = 0x9e37_79b9_u64;
        let mut next = move || {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        let lam_re = (0..m).map(|_| -1.0 - next().abs()).collect();
        let lam_im = (0..m).map(|j| 100.0 * (j + 1) as f64).collect();
        let psi: Vec<f64> = (0..2 * n * m).map(|_| next()).collect();
        Reduction::new(
            n,
            lam_re,
            lam_im,
            vec![2.0; m],
            &psi,
            n,
            0,
            0,
            vec![0.0; 3 * n],
        )
        .expect("a valid reduction")
    }

    /// ψᵀs by the definition, one mode at a time.
    fn naive_projection(red: &Reduction, s: &Shape) -> CVec {
        let mut out = CVec::zeros(red.stride);
        for (k, v) in s.values.iter().enumerate() {
            let (rr, ri) = red.row(s.start + k);
            for j in 0..red.stride {
                out.re[j] += v * rr[j];
                out.im[j] += v * ri[j];
            }
        }
        out
    }

    /// The moving forces' modal force against its definition Σ_m P_m·Σ_k s_mk·ψ_k, with
    /// forces off the structure (zero shapes) among them and more modes than one block.
    #[test]
    fn moving_loads_match_their_definition() {
        let red = reduction(40, 2 * BLOCK + 24);
        let shapes: Vec<Shape> = (0..7)
            .map(|m| Shape {
                start: 3 * m,
                values: if m % 3 == 2 {
                    vec![0.0; 4]
                } else {
                    (0..4).map(|k| 0.2 + (m + k) as f64).collect()
                },
            })
            .collect();
        let p: Vec<f64> = (0..7).map(|m| -8e4 + 3e4 * m as f64).collect();
        let mut got = CVec::zeros(red.stride);
        load_movers(&red, &shapes, &p, &mut got);
        let mut want = CVec::zeros(red.stride);
        for (s, pm) in shapes.iter().zip(&p) {
            let psi = naive_projection(&red, s);
            for j in 0..red.stride {
                want.re[j] += pm * psi.re[j];
                want.im[j] += pm * psi.im[j];
            }
        }
        let scale = want
            .re
            .iter()
            .chain(&want.im)
            .fold(0.0_f64, |a, x| a.max(x.abs()));
        for j in 0..red.stride {
            assert!((got.re[j] - want.re[j]).abs() <= 1e-12 * scale);
            assert!((got.im[j] - want.im[j]).abs() <= 1e-12 * scale);
        }
    }

    /// The projection (rows four at a time, zeros skipped) against the definition, for shapes
    /// of 1 to 9 values with zeros among them.
    #[test]
    fn projection_matches_its_definition() {
        let red = reduction(21, 16);
        for len in 1..=9 {
            let values = (0..len)
                .map(|k| if k % 3 == 1 { 0.0 } else { 0.3 + k as f64 })
                .collect();
            let s = Shape { start: 5, values };
            let mut got = CVec::zeros(red.stride);
            project(&red, &s, &mut got);
            let want = naive_projection(&red, &s);
            for j in 0..red.stride {
                assert!((got.re[j] - want.re[j]).abs() <= 1e-13 * (1.0 + want.re[j].abs()));
                assert!((got.im[j] - want.im[j]).abs() <= 1e-13 * (1.0 + want.im[j].abs()));
            }
        }
    }

    /// The table's sᵀDs against Re Σ a1·(ψᵀs)² over the modes, at every start of the rail
    /// (the last rows, whose band runs off the rail, included).
    #[test]
    fn the_step_compliance_table_matches_the_modal_sum() {
        let red = reduction(13, 12);
        let coef = Coefficients::new(&red, 5e-5);
        let span = 4;
        let table = RailStepCompliance::new(&red, &coef, span);
        for start in 0..red.rail_dofs {
            let len = span.min(red.rail_dofs - start);
            let values = (0..len).map(|k| 1.0 - 0.4 * k as f64).collect();
            let s = Shape { start, values };
            let p = naive_projection(&red, &s);
            let want: f64 = (0..red.stride)
                .map(|j| {
                    let (ar, ai) = (coef.a1[0][j], coef.a1[1][j]);
                    let (tr, ti) = (ar * p.re[j] - ai * p.im[j], ar * p.im[j] + ai * p.re[j]);
                    tr * p.re[j] - ti * p.im[j]
                })
                .sum();
            let got = table.quadratic(&s);
            assert!(
                (got - want).abs() <= 1e-12 * want.abs().max(1e-30),
                "start {start}: {got} vs {want}"
            );
        }
    }
}
