//! Shape functions of one beam layer and their exact integrals.
//!
//! Two discretisations share one representation: a layer is a list of *pieces* (intervals),
//! each carrying a few basis functions that are, on that piece, either a cubic polynomial or
//! a scaled sine. The modal basis (docs/model.md §2.1) is a single piece over [0, L] with the four
//! Hermite cubics and the mass-normalised sines s_n = sqrt(2/(ρAL))·sin(nπx/L); the FEM basis
//! (§2.2) is one piece per element with the four element Hermite cubics. Every mass, stiffness
//! and coupling integral is a product of two such functions and is evaluated in closed form,
//! so the sine–sine blocks come out diagonal to round-off.
//!
//! - `mod.rs` (this file): the shared representation — [`Piece`], [`Shape`], [`LayerBasis`];
//! - `integrals`: piece functions ([`Func`]), the Hermite cubics and their exact integrals;
//! - `modal`: the modal basis ([`ModalBasis`]) and its Gram blocks in closed form;
//! - `fem`: the finite-element mesh ([`FemBasis`]): interdependent Timoshenko elements, local
//!   flexibility, Hertz patches.

mod fem;
mod integrals;
mod modal;

pub use fem::FemBasis;
use fem::interdependent;
pub use integrals::{Func, hermite, integrate};
pub use modal::ModalBasis;

/// Basis functions of a layer on one interval: (local DOF, function) pairs.
#[derive(Clone, Debug)]
pub struct Piece {
    pub a: f64,
    pub b: f64,
    pub funcs: Vec<(usize, Func)>,
}

/// A shape vector: `values` of the contiguous layer DOFs `start..start + values.len()`.
#[derive(Clone, Debug, Default)]
pub struct Shape {
    pub start: usize,
    pub values: Vec<f64>,
}

/// The basis of one layer.
#[derive(Clone, Debug)]
pub enum LayerBasis {
    Modal(ModalBasis),
    Fem(FemBasis),
}

impl LayerBasis {
    pub fn n_dofs(&self) -> usize {
        match self {
            LayerBasis::Modal(b) => b.n_dofs(),
            LayerBasis::Fem(b) => b.n_dofs(),
        }
    }

    /// Integration pieces (FEM only; modal Gram blocks are computed analytically).
    pub fn pieces(&self) -> Vec<Piece> {
        match self {
            LayerBasis::Modal(_) => Vec::new(),
            LayerBasis::Fem(b) => b.pieces(),
        }
    }

    /// Largest number of nonzeros of a shape vector.
    pub fn shape_len(&self) -> usize {
        match self {
            LayerBasis::Modal(b) => b.n_dofs(),
            LayerBasis::Fem(_) => 4,
        }
    }

    /// Displacement shape vector N(x) (layer-local DOF numbering). `out.values` must have
    /// length `shape_len()`; it is overwritten without allocating.
    #[inline]
    pub fn eval(&self, x: f64, out: &mut Shape) {
        self.eval_derivative::<false>(x, out);
    }

    /// Curvature shape vector κ(x): w″ of the basis functions (ψ′ of a Timoshenko element,
    /// whose bending moment is EI·ψ′), laid out as `eval`'s and overwritten without
    /// allocating. At a node it is the element's on the right, as `eval`.
    #[inline]
    pub fn eval_curvature(&self, x: f64, out: &mut Shape) {
        self.eval_derivative::<true>(x, out);
    }

    /// Slope shape vector w′(x) of a finite-element layer (the derivative of `eval`'s, laid
    /// out as it and overwritten without allocating): how a load's shape changes as it moves.
    /// `false`, `out` untouched, on a modal layer (no moving load needs its slope).
    pub fn eval_slope(&self, x: f64, out: &mut Shape) -> bool {
        match self {
            LayerBasis::Modal(_) => false,
            LayerBasis::Fem(b) => {
                fem_eval::<SLOPE>(b, x, out);
                true
            }
        }
    }

    /// `eval` or, with `CURVATURE`, `eval_curvature` (one body, compiled once for each).
    #[inline]
    fn eval_derivative<const CURVATURE: bool>(&self, x: f64, out: &mut Shape) {
        match self {
            LayerBasis::Modal(b) => {
                out.start = 0;
                if !(0.0..=b.length).contains(&x) {
                    out.values.fill(0.0);
                } else if CURVATURE {
                    b.curvature_into(x, &mut out.values);
                } else {
                    b.eval_into(x, &mut out.values);
                }
            }
            LayerBasis::Fem(b) if CURVATURE => fem_eval::<CURVATURE_OF_ROTATION>(b, x, out),
            LayerBasis::Fem(b) => fem_eval::<VALUE>(b, x, out),
        }
    }

    pub fn shape(&self, x: f64) -> Shape {
        let mut s = Shape {
            start: 0,
            values: vec![0.0; self.shape_len()],
        };
        self.eval(x, &mut s);
        s
    }
}

/// What `fem_eval` evaluates: w, w′ (both from the displacement polynomials) or ψ′ (from the
/// rotation's: the Timoshenko element's curvature).
const VALUE: u8 = 0;
const SLOPE: u8 = 1;
const CURVATURE_OF_ROTATION: u8 = 2;

/// A finite-element shape vector at x (zero off the mesh): `WHAT` of the element's
/// interdependent polynomials.
#[inline]
fn fem_eval<const WHAT: u8>(b: &FemBasis, x: f64, out: &mut Shape) {
    if !b.covers(x) {
        out.start = 0;
        out.values.fill(0.0);
        return;
    }
    let e = b.element_of(x);
    let (a, l) = (b.nodes[e], b.nodes[e + 1] - b.nodes[e]);
    out.start = 2 * e;
    let xi = x - a;
    let coeffs = interdependent(l, b.phi[e]);
    let polys = &coeffs[usize::from(WHAT == CURVATURE_OF_ROTATION)];
    for (o, c) in out.values.iter_mut().zip(polys) {
        *o = if WHAT == VALUE {
            c[0] + xi * (c[1] + xi * (c[2] + xi * c[3]))
        } else {
            c[1] + xi * (2.0 * c[2] + xi * 3.0 * c[3])
        };
    }
}

#[cfg(test)]
mod tests;
