//! Beam layers (rail, slab, base, girder …): Euler–Bernoulli properties, the basis of each
//! layer, and the exact Gram blocks ∫N·Nᵀ and ∫N″·N″ᵀ from which mass, stiffness, Rayleigh
//! damping and continuous couplings are built.

use crate::basis::{FemBasis, Func, LayerBasis, ModalBasis, Piece, Shape, integrate};
use crate::config::{LayerConfig, Method};

#[derive(Clone, Debug)]
pub struct Layer {
    pub name: String,
    pub basis: LayerBasis,
    /// First DOF of this layer in the structure's numbering.
    pub offset: usize,
    /// ρA (kg/m) and EI (N·m²).
    pub rho_a: f64,
    pub ei: f64,
    /// Rayleigh coefficients α (1/s), β (s).
    pub alpha: f64,
    pub beta: f64,
}

impl Layer {
    pub fn new(
        cfg: &LayerConfig,
        length: f64,
        method: Method,
        fem_elements: usize,
        offset: usize,
    ) -> Self {
        let rho_a = cfg.density * cfg.area;
        let basis = match method {
            Method::Fem => LayerBasis::Fem(FemBasis {
                length,
                n_elements: fem_elements,
            }),
            Method::Modal | Method::Hybrid => {
                LayerBasis::Modal(ModalBasis::new(length, rho_a, cfg.modes))
            }
        };
        let (alpha, beta) = cfg.damping.coefficients();
        Self {
            name: cfg.name.clone(),
            basis,
            offset,
            rho_a,
            ei: cfg.youngs_modulus * cfg.inertia,
            alpha,
            beta,
        }
    }

    pub fn n_dofs(&self) -> usize {
        self.basis.n_dofs()
    }

    /// Shape vector at x in the structure's numbering.
    #[inline]
    pub fn shape_into(&self, x: f64, out: &mut Shape) {
        self.basis.eval(x, out);
        out.start += self.offset;
    }

    pub fn shape(&self, x: f64) -> Shape {
        let mut s = self.basis.shape(x);
        s.start += self.offset;
        s
    }
}

/// A dense block of integrals between two DOF lists (structure numbering).
#[derive(Clone, Debug)]
pub struct Block {
    pub rows: Vec<usize>,
    pub cols: Vec<usize>,
    /// Row-major, rows.len() × cols.len().
    pub data: Vec<f64>,
}

/// Which product a Gram block integrates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Derivative {
    /// ∫ f·g
    Value,
    /// ∫ f″·g″
    Curvature,
}

fn piece_funcs(p: &Piece, d: Derivative) -> Vec<(usize, Func)> {
    match d {
        Derivative::Value => p.funcs.clone(),
        Derivative::Curvature => p.funcs.iter().map(|(i, f)| (*i, f.d2())).collect(),
    }
}

/// ∫ N_a·N_bᵀ (or of curvatures): one analytic block for two modal layers, else one block per
/// overlap of the pieces of two FEM layers.
pub fn gram_blocks(a: &Layer, b: &Layer, d: Derivative) -> Vec<Block> {
    if let (LayerBasis::Modal(ma), LayerBasis::Modal(mb)) = (&a.basis, &b.basis) {
        return vec![Block {
            rows: (0..ma.n_dofs()).map(|k| a.offset + k).collect(),
            cols: (0..mb.n_dofs()).map(|k| b.offset + k).collect(),
            data: ModalBasis::gram(ma, mb, d == Derivative::Curvature),
        }];
    }
    let (pa, pb) = (a.basis.pieces(), b.basis.pieces());
    let same = std::ptr::eq(a, b);
    let mut out = Vec::new();
    let (mut i, mut j) = (0, 0);
    while i < pa.len() && j < pb.len() {
        let (lo, hi) = (pa[i].a.max(pb[j].a), pa[i].b.min(pb[j].b));
        if hi > lo {
            let fa = piece_funcs(&pa[i], d);
            let fb = if same && i == j {
                fa.clone()
            } else {
                piece_funcs(&pb[j], d)
            };
            let mut data = vec![0.0; fa.len() * fb.len()];
            for (r, (_, f)) in fa.iter().enumerate() {
                for (c, (_, g)) in fb.iter().enumerate() {
                    // Gram blocks of a piece with itself are symmetric: fill both halves once.
                    if same && i == j && c < r {
                        data[r * fb.len() + c] = data[c * fb.len() + r];
                    } else {
                        data[r * fb.len() + c] = integrate(f, g, lo, hi);
                    }
                }
            }
            out.push(Block {
                rows: fa.iter().map(|(k, _)| a.offset + k).collect(),
                cols: fb.iter().map(|(k, _)| b.offset + k).collect(),
                data,
            });
        }
        if pa[i].b <= pb[j].b { i += 1 } else { j += 1 }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::RayleighConfig;

    fn layer(method: Method, modes: usize) -> Layer {
        let cfg = LayerConfig {
            name: "rail".into(),
            density: 7800.0,
            area: 7.745e-3,
            youngs_modulus: 2.1e11,
            inertia: 3.217e-5,
            modes,
            local_modes: 0,
            damping: RayleighConfig::Coefficients {
                alpha: 0.0,
                beta: 0.0,
            },
        };
        Layer::new(&cfg, 32.0, method, 40, 0)
    }

    #[test]
    fn modal_sine_blocks_are_identity_and_omega_squared() {
        let l = layer(Method::Modal, 30);
        let m = &gram_blocks(&l, &l, Derivative::Value)[0];
        let k = &gram_blocks(&l, &l, Derivative::Curvature)[0];
        let n = m.rows.len();
        let LayerBasis::Modal(b) = &l.basis else {
            unreachable!()
        };
        for p in 4..n {
            for q in 4..n {
                let mv = l.rho_a * m.data[p * n + q];
                let kv = l.ei * k.data[p * n + q];
                if p == q {
                    let kn = b.wavenumber(p - 3);
                    assert!((mv - 1.0).abs() < 1e-12);
                    let w2 = l.ei / l.rho_a * kn.powi(4);
                    assert!((kv - w2).abs() < 1e-9 * w2, "p={p} {kv} {w2}");
                } else {
                    assert!(mv.abs() < 1e-12 && kv.abs() < 1e-6, "p={p} q={q} {mv} {kv}");
                }
            }
        }
    }

    #[test]
    fn fem_element_blocks_match_textbook_matrices() {
        let l = layer(Method::Fem, 0);
        let m = &gram_blocks(&l, &l, Derivative::Value)[3];
        let k = &gram_blocks(&l, &l, Derivative::Curvature)[3];
        let le = 32.0 / 40.0;
        let mm = [
            156.0,
            22.0 * le,
            54.0,
            -13.0 * le,
            22.0 * le,
            4.0 * le * le,
            13.0 * le,
            -3.0 * le * le,
            54.0,
            13.0 * le,
            156.0,
            -22.0 * le,
            -13.0 * le,
            -3.0 * le * le,
            -22.0 * le,
            4.0 * le * le,
        ];
        let kk = [
            12.0,
            6.0 * le,
            -12.0,
            6.0 * le,
            6.0 * le,
            4.0 * le * le,
            -6.0 * le,
            2.0 * le * le,
            -12.0,
            -6.0 * le,
            12.0,
            -6.0 * le,
            6.0 * le,
            2.0 * le * le,
            -6.0 * le,
            4.0 * le * le,
        ];
        for i in 0..16 {
            assert!((m.data[i] - mm[i] * le / 420.0).abs() < 1e-13, "m[{i}]");
            assert!((k.data[i] - kk[i] / le.powi(3)).abs() < 1e-10, "k[{i}]");
        }
        assert_eq!(m.rows, vec![6, 7, 8, 9]);
    }
}
