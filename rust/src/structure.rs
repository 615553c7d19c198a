//! The assembled track–bridge structure: layer DOFs stacked top to bottom, with mass M,
//! stiffness K and damping C = Σ_layers(α_l·M_l + β_l·K_l) + couplings.

use crate::basis::{LayerBasis, ModalBasis, Shape};
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
        let layers = stack(cfg, 0);
        let n: usize = layers.iter().map(Layer::n_dofs).sum();
        let fesea = match method {
            Method::Hybrid => Some(FeSea::new(cfg, &layers[0])?),
            _ => None,
        };
        let [am, ak, ac] = match &fesea {
            // g̃ = g + Σ_j t_j·s_j spans no local content: the global matrices are the exact
            // Galerkin projection of the model with the local sines as DOFs (symmetric and
            // as definite as that model), plus the condensation of the residual couplings.
            Some(fs) if !fs.shape_terms().is_empty() => {
                let n_local = s.layers[0].local_modes;
                let mut full = assemble(cfg, &stack(cfg, n_local)).map(|a| a.finish().to_dense());
                let mut out = [Assembler::new(n), Assembler::new(n), Assembler::new(n)];
                let rail_dofs = layers[0].n_dofs();
                let ext = |r: usize| if r < rail_dofs { r } else { r + n_local };
                // g3, g4 of a modal basis are h2, h4 minus their own sines' content, so the
                // global g̃3, g̃4 are multiples of the extended basis' g3, g4; g1, g2 are the
                // same functions in both and take the local terms.
                let ext_rail = &stack(cfg, n_local)[0];
                let gram = match (&layers[0].basis, &ext_rail.basis) {
                    (LayerBasis::Modal(a), LayerBasis::Modal(b)) => ModalBasis::gram(a, b, false),
                    _ => unreachable!("hybrid rails are modal"),
                };
                let width = ext_rail.n_dofs();
                let r: [f64; 2] =
                    std::array::from_fn(|p| layers[0].rho_a * gram[(p + 2) * width + p + 2]);
                for (a, asm) in full.iter_mut().zip(&mut out) {
                    project(a, fs, r);
                    for i in 0..n {
                        for j in 0..n {
                            let v = a[ext(i)][ext(j)];
                            if v != 0.0 {
                                asm.add(i, j, v);
                            }
                        }
                    }
                }
                for (k, asm) in out.iter_mut().enumerate() {
                    let total = [&fs.delta_m, &fs.delta_k, &fs.delta_c][k];
                    add_on_cubics(asm, fs, |p, q| total[p][q] - fs.exact[k][p][q]);
                }
                out
            }
            Some(fs) => {
                let mut out = assemble(cfg, &layers);
                for (asm, d) in out.iter_mut().zip([&fs.delta_m, &fs.delta_k, &fs.delta_c]) {
                    add_on_cubics(asm, fs, |p, q| d[p][q]);
                }
                out
            }
            None => assemble(cfg, &layers),
        };
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

/// The layers of a config stacked top to bottom, the rail with `extra` more sines.
fn stack(cfg: &Config, extra: usize) -> Vec<Layer> {
    let s = &cfg.structure;
    let mut offset = 0;
    s.layers
        .iter()
        .enumerate()
        .map(|(i, lc)| {
            let mut lc = lc.clone();
            if i == 0 {
                lc.modes += extra;
            }
            let layer = Layer::new(
                &lc,
                s.length,
                cfg.discretisation.method,
                cfg.discretisation.fem_elements,
                offset,
            );
            offset += layer.n_dofs();
            layer
        })
        .collect()
}

/// M, K and C of the layers and couplings.
fn assemble(cfg: &Config, layers: &[Layer]) -> [Assembler; 3] {
    let n = layers.iter().map(Layer::n_dofs).sum();
    let (mut am, mut ak, mut ac) = (Assembler::new(n), Assembler::new(n), Assembler::new(n));
    for l in layers {
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
    for c in &cfg.structure.couplings {
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
    [am, ak, ac]
}

/// A ← TᵀAT for the change of the rail's cubic functions (DOFs 0..4) to g̃: g̃1,2 = g1,2 +
/// Σ_j t_j·s_j (sine j being DOF 3 + j of the extended rail) and g̃3,4 = r·g3,4.
fn project(a: &mut [Vec<f64>], fs: &FeSea, r: [f64; 2]) {
    for &(j, t) in fs.shape_terms() {
        let row = a[3 + j].clone();
        for g in 0..2 {
            for (x, v) in a[g].iter_mut().zip(&row) {
                *x += t[g] * v;
            }
        }
    }
    for (g, rg) in r.iter().enumerate() {
        a[g + 2].iter_mut().for_each(|x| *x *= rg);
    }
    for row in a.iter_mut() {
        for &(j, t) in fs.shape_terms() {
            let v = row[3 + j];
            for g in 0..2 {
                row[g] += t[g] * v;
            }
        }
        for (g, rg) in r.iter().enumerate() {
            row[g + 2] *= rg;
        }
    }
}

fn add_on_cubics(asm: &mut Assembler, fs: &FeSea, d: impl Fn(usize, usize) -> f64) {
    for (p, &i) in fs.dofs.iter().enumerate() {
        for (q, &j) in fs.dofs.iter().enumerate() {
            asm.add(i, j, d(p, q));
        }
    }
}
