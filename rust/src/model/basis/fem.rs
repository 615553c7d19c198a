//! The finite-element basis of a layer: a mesh of interdependent Timoshenko elements (uneven
//! nodes, joints), the elements' local flexibility under a point load, and the load-weighted
//! shape and flexibility of a Hertz patch.

use super::integrals::{Func, gauss16};
use super::{Piece, Shape};

/// A finite-element mesh of beam elements with two DOFs per node: node i has DOFs 2i
/// (displacement w, positive downward) and 2i+1 (rotation: w′ for Euler–Bernoulli, the
/// cross-section rotation ψ for Timoshenko). Nodes may be spaced unevenly (they are placed on
/// the coupling points of the layer, see `FemBasis::aligned`).
///
/// Each element interpolates w with the *interdependent* cubics of a Timoshenko element
/// (w cubic, ψ quadratic, their coefficients tied so that the shear strain γ = w′ − ψ is
/// constant and the homogeneous static equations hold exactly): free of shear locking, exact
/// nodal values for static point loads, and equal to the cubic Hermite functions when the
/// element's shear parameter φ = 12EI/(κGAℓ²) is 0 (Euler–Bernoulli).
#[derive(Clone, Debug)]
pub struct FemBasis {
    /// Node positions, increasing, from the layer's start to its end (0 and L unless the
    /// layer covers part of the structure).
    pub nodes: Vec<f64>,
    /// Shear parameter φ of each element (0 for Euler–Bernoulli).
    pub phi: Vec<f64>,
}

impl FemBasis {
    /// `n` equal elements over [start, end].
    pub fn uniform(start: f64, end: f64, n: usize) -> Self {
        let nodes = (0..=n)
            .map(|i| {
                if i == n {
                    end
                } else {
                    start + (end - start) * i as f64 / n as f64
                }
            })
            .collect();
        Self {
            nodes,
            phi: vec![0.0; n],
        }
    }

    /// Nodes on every breakpoint within (start, end) (coupling points; the ends are added)
    /// and each interval between breakpoints split into the fewest equal elements no longer
    /// than `max_len`. Breakpoints closer than 1e-9·end merge.
    pub fn aligned(start: f64, end: f64, max_len: f64, breakpoints: &[f64]) -> Self {
        let tol = 1e-9 * end.abs().max(end - start);
        let mut bp: Vec<f64> = breakpoints
            .iter()
            .copied()
            .filter(|&x| x > start + tol && x < end - tol)
            .collect();
        bp.sort_by(f64::total_cmp);
        let mut nodes = vec![start];
        for &x in bp.iter().chain(std::iter::once(&end)) {
            let a = *nodes.last().expect("starts with the start");
            if x - a <= tol {
                continue;
            }
            let n = ((x - a) / max_len * (1.0 - 1e-12)).ceil().max(1.0) as usize;
            nodes.extend((1..=n).map(|k| {
                if k == n {
                    x
                } else {
                    a + (x - a) * k as f64 / n as f64
                }
            }));
        }
        let n = nodes.len() - 1;
        Self {
            nodes,
            phi: vec![0.0; n],
        }
    }

    /// First node (m).
    pub fn start(&self) -> f64 {
        self.nodes[0]
    }

    /// Last node (m).
    pub fn end(&self) -> f64 {
        *self.nodes.last().expect("a mesh has nodes")
    }

    /// x lies on the mesh (its shape functions are zero elsewhere).
    #[inline]
    pub fn covers(&self, x: f64) -> bool {
        x >= self.start() && x <= self.end()
    }

    /// Cuts the mesh at each of `joints` (each a node, up to the breakpoints' merging
    /// tolerance): the node nearest to it is doubled, with a zero-length element between the
    /// two, so nothing passes from one side to the other. A point at a joint belongs to the
    /// element on its right.
    pub fn with_joints(mut self, joints: &[f64]) -> Self {
        for &x in joints {
            let i = (0..self.nodes.len())
                .min_by(|&a, &b| {
                    (self.nodes[a] - x)
                        .abs()
                        .total_cmp(&(self.nodes[b] - x).abs())
                })
                .expect("a mesh has nodes");
            self.nodes.insert(i, self.nodes[i]);
            self.phi.insert(i, 0.0);
        }
        self
    }

    /// Element e has no length (a joint).
    #[inline]
    fn is_joint(&self, e: usize) -> bool {
        self.nodes[e + 1] == self.nodes[e]
    }

    /// Makes the elements Timoshenko elements of a beam with bending stiffness `ei` and shear
    /// stiffness `kga` = κGA.
    pub fn with_shear(mut self, ei: f64, kga: f64) -> Self {
        for e in 0..self.n_elements() {
            let l = self.nodes[e + 1] - self.nodes[e];
            if l > 0.0 {
                self.phi[e] = 12.0 * ei / (kga * l * l);
            }
        }
        self
    }

    /// The elements with a length (all but the joints').
    pub fn elements(&self) -> impl Iterator<Item = usize> + '_ {
        (0..self.n_elements()).filter(|&e| !self.is_joint(e))
    }

    pub fn n_elements(&self) -> usize {
        self.nodes.len() - 1
    }

    pub fn n_dofs(&self) -> usize {
        2 * self.nodes.len()
    }

    /// Element containing x (an element owns its left node; the last one also owns x = L).
    #[inline]
    pub fn element_of(&self, x: f64) -> usize {
        let ne = self.n_elements();
        self.nodes
            .partition_point(|&n| n <= x)
            .saturating_sub(1)
            .min(ne - 1)
    }

    /// (w, ψ) interpolation of element e as polynomials in ξ = x − x_e: the displacement
    /// functions and the rotation functions of its four DOFs.
    pub fn element_funcs(&self, e: usize) -> ([Func; 4], [Func; 4]) {
        let (a, l) = (self.nodes[e], self.nodes[e + 1] - self.nodes[e]);
        let [w, psi] = interdependent(l, self.phi[e]);
        let f = |c: [f64; 4]| Func::Poly { origin: a, c };
        (w.map(f), psi.map(f))
    }

    /// Static deflection at x under a unit load at x with the nodes of x's element held fixed
    /// (m/N): the part of a point load's deflection that the element's interpolation cannot
    /// carry. `ei` = EI; the shear stiffness enters through the elements' φ. Zero on a node.
    ///
    /// It is the deflection of the element's span clamped at both ends: with a node at x the
    /// element splits into two whose end stiffnesses (closed form, exact for Timoshenko
    /// beams) condense onto x. Euler–Bernoulli: a³b³/(3EIℓ³).
    pub fn local_flexibility(&self, ei: f64, x: f64) -> f64 {
        if !self.covers(x) {
            return 0.0;
        }
        self.local_flexibility_in(self.element_of(x), ei, x)
    }

    /// `local_flexibility` at x in element e.
    fn local_flexibility_in(&self, e: usize, ei: f64, x: f64) -> f64 {
        let (a, b) = (x - self.nodes[e], self.nodes[e + 1] - x);
        let l = a + b;
        if a <= 1e-12 * l || b <= 1e-12 * l {
            return 0.0;
        }
        // φ scales as 1/ℓ²: the sub-elements' φ from the element's.
        let phi_l2 = self.phi[e] * l * l;
        let end = |h: f64, sign: f64| {
            let phi = phi_l2 / (h * h);
            let c = ei / ((1.0 + phi) * h * h * h);
            (12.0 * c, sign * 6.0 * h * c, (4.0 + phi) * h * h * c)
        };
        // Right end of [x_e, x] and left end of [x, x_e+1].
        let (ka, kb) = (end(a, -1.0), end(b, 1.0));
        let (k11, k12, k22) = (ka.0 + kb.0, ka.1 + kb.1, ka.2 + kb.2);
        k22 / (k11 * k22 - k12 * k12)
    }

    /// Pieces of the patch [x − a, x + a] cut at the nodes (and at the mesh's ends), each with
    /// its element, for integrals over a distributed contact.
    fn patch_pieces(&self, x: f64, a: f64) -> impl Iterator<Item = (usize, f64, f64)> + '_ {
        let (lo, hi) = ((x - a).max(self.start()), (x + a).min(self.end()));
        let (e0, e1) = (self.element_of(lo), self.element_of(hi));
        (e0..=e1).filter(move |_| hi > lo).filter_map(move |e| {
            let (p, q) = (lo.max(self.nodes[e]), hi.min(self.nodes[e + 1]));
            (q > p).then_some((e, p, q))
        })
    }

    /// Σ over the patch's Gauss points of w·q(s)·f(e, x + s), normalised by the share of the
    /// load on the structure: q(s) = 1 − s²/a² is the Hertz line load (the pressure of an
    /// elliptical contact integrated across the rail head) along the rail.
    fn patch_average(&self, x: f64, a: f64, mut f: impl FnMut(usize, f64, f64)) {
        let (nodes, weights) = gauss16();
        let mut total = 0.0;
        for (_, p, q) in self.patch_pieces(x, a) {
            let (m, h) = (0.5 * (p + q), 0.5 * (q - p));
            for (t, w) in nodes.iter().zip(weights) {
                let s = (m + h * t - x) / a;
                total += w * h * (1.0 - s * s);
            }
        }
        for (e, p, q) in self.patch_pieces(x, a) {
            let (m, h) = (0.5 * (p + q), 0.5 * (q - p));
            for (t, w) in nodes.iter().zip(weights) {
                let xs = m + h * t;
                let s = (xs - x) / a;
                f(e, xs, w * h * (1.0 - s * s) / total);
            }
        }
    }

    /// Displacement shape vector of a unit load spread over the Hertz patch of half-length `a`
    /// centred at x: ∫N(x + s)·q(s)ds/∫q(s)ds, exact (16 Gauss points per element piece for a
    /// quintic integrand). It covers the DOFs of every element the patch touches; `out.values`
    /// is resized to them (no allocation once it has the capacity).
    /// A patch wholly off the mesh has a zero shape.
    pub fn patch_into(&self, x: f64, a: f64, out: &mut Shape) {
        let (lo, hi) = ((x - a).max(self.start()), (x + a).min(self.end()));
        let (e0, e1) = (self.element_of(lo), self.element_of(hi.max(lo)));
        out.start = 2 * e0;
        out.values.clear();
        out.values.resize(2 * (e1 - e0 + 2), 0.0);
        let values = &mut out.values;
        // The element's coefficients once per piece, not per Gauss point.
        let mut element = (usize::MAX, [[0.0; 4]; 4]);
        self.patch_average(x, a, |e, xs, w| {
            if element.0 != e {
                element = (
                    e,
                    interdependent(self.nodes[e + 1] - self.nodes[e], self.phi[e])[0],
                );
            }
            let wf = &element.1;
            let xi = xs - self.nodes[e];
            for (j, c) in wf.iter().enumerate() {
                values[2 * (e - e0) + j] += w * (c[0] + xi * (c[1] + xi * (c[2] + xi * c[3])));
            }
        });
    }

    /// `local_flexibility` averaged over the Hertz patch with the weight of its line load
    /// (m/N). An upper bound of the patch's own local flexibility (the double average of the
    /// clamped element's Green's function), by at most the shear deflection of a patch
    /// length, about 1 % of the Hertz compliance for a 60 kg rail.
    pub fn patch_flexibility(&self, ei: f64, x: f64, a: f64) -> f64 {
        let mut f = 0.0;
        self.patch_average(x, a, |e, xs, w| {
            f += w * self.local_flexibility_in(e, ei, xs)
        });
        f
    }

    /// Most shape-vector entries of a patch of half-length `a` anywhere on the mesh.
    pub fn patch_len(&self, a: f64) -> usize {
        let shortest = self
            .elements()
            .map(|e| self.nodes[e + 1] - self.nodes[e])
            .fold(f64::INFINITY, f64::min);
        2 * ((2.0 * a / shortest).ceil() as usize + 2)
    }

    pub fn pieces(&self) -> Vec<Piece> {
        self.elements()
            .map(|e| Piece {
                a: self.nodes[e],
                b: self.nodes[e + 1],
                funcs: self
                    .element_funcs(e)
                    .0
                    .into_iter()
                    .enumerate()
                    .map(|(j, f)| (2 * e + j, f))
                    .collect(),
            })
            .collect()
    }
}

/// Coefficients (in powers of ξ, 0 ≤ ξ ≤ ℓ) of the interdependent-interpolation element:
/// [w functions, ψ functions] of the DOFs (w₁, ψ₁, w₂, ψ₂), μ = 1/(1 + φ), s = ξ/ℓ:
///   w:  μ(2s³ − 3s² − φs + 1 + φ),  ℓμ(s³ − (2 + φ/2)s² + (1 + φ/2)s),
///       −μ(2s³ − 3s² − φs),          ℓμ(s³ − (1 − φ/2)s² − (φ/2)s);
///   ψ:  (6μ/ℓ)(s² − s),  μ(3s² − (4 + φ)s + 1 + φ),  −(6μ/ℓ)(s² − s),  μ(3s² − (2 − φ)s).
pub(super) fn interdependent(l: f64, phi: f64) -> [[[f64; 4]; 4]; 2] {
    let mu = 1.0 / (1.0 + phi);
    // Polynomials in s, then scaled to powers of ξ = ℓ·s.
    let ws = [
        [1.0 + phi, -phi, -3.0, 2.0].map(|c| mu * c),
        [0.0, 1.0 + 0.5 * phi, -(2.0 + 0.5 * phi), 1.0].map(|c| l * mu * c),
        [0.0, phi, 3.0, -2.0].map(|c| mu * c),
        [0.0, -0.5 * phi, -(1.0 - 0.5 * phi), 1.0].map(|c| l * mu * c),
    ];
    let ps = [
        [0.0, -1.0, 1.0, 0.0].map(|c| 6.0 * mu / l * c),
        [1.0 + phi, -(4.0 + phi), 3.0, 0.0].map(|c| mu * c),
        [0.0, 1.0, -1.0, 0.0].map(|c| 6.0 * mu / l * c),
        [0.0, -(2.0 - phi), 3.0, 0.0].map(|c| mu * c),
    ];
    let scale = |p: [f64; 4]| [p[0], p[1] / l, p[2] / (l * l), p[3] / (l * l * l)];
    [ws.map(scale), ps.map(scale)]
}
