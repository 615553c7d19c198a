//! The assembled track–bridge structure: layer DOFs stacked top to bottom, with mass M,
//! stiffness K and damping C = Σ_layers(α_l·M_l + β_l·K_l) + couplings.

use crate::basis::{LayerBasis, Shape};
use crate::config::{Config, CouplingKind, GROUND, Method};
use crate::couplings::{add_continuous, add_discrete};
use crate::error::Result;
use crate::fesea::FeSea;
use crate::layers::{Derivative, Layer, gram_blocks};
use crate::sparse::{Assembler, CsrMatrix};

#[derive(Clone, Debug)]
pub struct Structure {
    pub length: f64,
    pub layers: Vec<Layer>,
    pub n_dofs: usize,
    pub m: CsrMatrix,
    pub k: CsrMatrix,
    pub c: CsrMatrix,
    /// The FE–SEA correction of the rail (hybrid method), already added to `m`, `k` and `c`.
    pub fesea: Option<FeSea>,
}

impl Structure {
    /// Assembles the structure of a validated config.
    pub fn build(cfg: &Config) -> Result<Self> {
        let s = &cfg.structure;
        let method = cfg.discretisation.method;
        let mut layers = Vec::with_capacity(s.layers.len());
        let mut offset = 0;
        for lc in &s.layers {
            let layer = Layer::new(
                lc,
                s.length,
                method,
                cfg.discretisation.fem_elements,
                offset,
            );
            offset += layer.n_dofs();
            layers.push(layer);
        }
        let n = offset;
        let (mut am, mut ak, mut ac) = (Assembler::new(n), Assembler::new(n), Assembler::new(n));
        for l in &layers {
            for (blocks, coef_m, coef_k) in [
                (gram_blocks(l, l, Derivative::Value), l.rho_a, 0.0),
                (gram_blocks(l, l, Derivative::Curvature), 0.0, l.ei),
            ] {
                for b in blocks {
                    debug_assert_eq!(b.rows, b.cols);
                    am.add_block(&b.rows, &b.data, coef_m);
                    ak.add_block(&b.rows, &b.data, coef_k);
                    ac.add_block(&b.rows, &b.data, l.alpha * coef_m + l.beta * coef_k);
                }
            }
        }
        for c in &s.couplings {
            let a = &layers[cfg.layer_index(&c.upper).expect("validated")];
            let b = if c.lower == GROUND {
                None
            } else {
                Some(&layers[cfg.layer_index(&c.lower).expect("validated")])
            };
            for (asm, w) in [(&mut ak, c.stiffness), (&mut ac, c.damping)] {
                match c.kind {
                    CouplingKind::Continuous => add_continuous(asm, a, b, w),
                    CouplingKind::Discrete => add_discrete(asm, a, b, &c.positions, w),
                }
            }
        }
        let fesea = match method {
            Method::Hybrid => Some(FeSea::new(cfg, &layers[0])?),
            _ => None,
        };
        if let Some(fs) = &fesea {
            for (p, &i) in fs.dofs.iter().enumerate() {
                for (q, &j) in fs.dofs.iter().enumerate() {
                    am.add(i, j, fs.delta_m[p][q]);
                    ak.add(i, j, fs.delta_k[p][q]);
                    ac.add(i, j, fs.delta_c[p][q]);
                }
            }
        }
        Ok(Self {
            length: s.length,
            layers,
            n_dofs: n,
            m: am.finish(),
            k: ak.finish(),
            c: ac.finish(),
            fesea,
        })
    }

    /// The unknowns grouped by mesh node (every layer's DOFs at node j) when all layers are
    /// finite-element meshes of the same size: the grouping in which the matrices are block
    /// tridiagonal.
    pub fn node_blocks(&self) -> Option<Vec<Vec<usize>>> {
        let meshes: Vec<usize> = self
            .layers
            .iter()
            .map(|l| match &l.basis {
                LayerBasis::Fem(f) => Some(f.n_elements),
                LayerBasis::Modal(_) => None,
            })
            .collect::<Option<_>>()?;
        let ne = *meshes.first()?;
        if meshes.iter().any(|&m| m != ne) {
            return None;
        }
        Some(
            (0..=ne)
                .map(|j| {
                    self.layers
                        .iter()
                        .flat_map(|l| [l.offset + 2 * j, l.offset + 2 * j + 1])
                        .collect()
                })
                .collect(),
        )
    }

    /// Shape vector of layer `layer` at x (structure numbering), without allocating.
    /// The rail (layer 0) of a hybrid model uses the FE–SEA-corrected cubic functions g̃.
    #[inline]
    pub fn shape_into(&self, layer: usize, x: f64, out: &mut Shape) {
        self.layers[layer].shape_into(x, out);
        if layer == 0
            && let Some(fs) = &self.fesea
        {
            fs.correct_shape(x, &mut out.values);
        }
    }

    pub fn shape(&self, layer: usize, x: f64) -> Shape {
        let mut s = self.layers[layer].shape(x);
        if layer == 0
            && let Some(fs) = &self.fesea
        {
            fs.correct_shape(x, &mut s.values);
        }
        s
    }

    /// Displacement u_layer(x) for a DOF vector.
    pub fn displacement(&self, layer: usize, x: f64, q: &[f64]) -> f64 {
        dot(&self.shape(layer, x), q)
    }
}

/// nᵀ·q for a shape vector n.
#[inline]
pub fn dot(n: &Shape, q: &[f64]) -> f64 {
    n.values
        .iter()
        .zip(&q[n.start..n.start + n.values.len()])
        .map(|(a, b)| a * b)
        .sum()
}
