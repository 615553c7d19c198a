//! The assembled track–bridge structure: layer DOFs stacked top to bottom, with mass M,
//! stiffness K and damping C = Σ_layers(α_l·M_l + β_l·K_l) + couplings.

use crate::config::DamperParams;
use crate::config::fields::on_interval;
use crate::config::{Config, CouplingKind, GROUND, Method};
use crate::error::{Result, VtbError};
use crate::linalg::sparse::{Assembler, CsrMatrix};
use crate::model::basis::{LayerBasis, ModalBasis, Shape};
use crate::model::couplings::{add_continuous, add_discrete};
use crate::model::dampers::{Attachment, stamp};
use crate::model::fesea::FeSea;
use crate::model::layers::{Derivative, Layer, gram_blocks};
use crate::model::substructures::Substructured;
use std::cell::RefCell;
use std::sync::Arc;

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
    /// The dampers of every group (internal node DOFs after the layers'), included in `m`,
    /// `k`, `c`.
    pub dampers: Vec<Attachment>,
    /// `m`, `k`, `c` without the dampers, on the layers' DOFs: the time stepper factors these
    /// and takes the dampers as rank-one updates (`None`: no dampers, use `m`, `k`, `c`).
    pub base: Option<[CsrMatrix; 3]>,
    /// `solver.edge_ramp` (m): over how much of each end of the rail a wheel's force is
    /// handed to the rigid track beyond (`edge_share`).
    pub edge_ramp: f64,
    /// Substructured coordinates (`substructured`): the matrices and every shape vector are
    /// then in T's reduced DOFs; `layers` still evaluate the finite-element shapes T maps.
    pub reduced: Option<Arc<Substructured>>,
}

thread_local! {
    /// A layer shape on its way to substructured coordinates (no allocation per call).
    static LAYER_SHAPE: RefCell<Shape> = RefCell::new(Shape::default());
}

impl Structure {
    /// The configuration as `build` reads it: the run's duration, its moving forces and —
    /// but on a hybrid rail, whose correction is tuned to the speed — its speed cleared.
    /// Configurations with equal keys assemble equal structures (the speeds of a scan share
    /// one; `engine::batch`).
    pub fn key(cfg: &Config) -> String {
        let mut c = cfg.clone();
        c.solver.t_end = None;
        c.forces.clear();
        if c.discretisation.method != Method::Hybrid {
            c.speed = 0.0;
        }
        serde_json::to_string(&c).expect("a config serialises")
    }

    /// Assembles the structure of a validated config.
    pub fn build(cfg: &Config) -> Result<Self> {
        let s = &cfg.structure;
        let method = cfg.discretisation.method;
        let layers = stack(cfg, 0);
        let n_layers: usize = layers.iter().map(Layer::n_dofs).sum();
        let n = n_layers + cfg.damper_params().len();
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
                let mut out = [(); 3].map(|_| Assembler::new(n_layers));
                let rail_dofs = layers[0].n_dofs();
                let ext = |r: usize| if r < rail_dofs { r } else { r + n_local };
                // g3, g4 of a modal basis are h2, h4 minus their own sines' content, so the
                // global g̃3, g̃4 are multiples of the extended basis' g3, g4; g1, g2 (the end
                // displacements, whose sum is the rigid translation) are left unsplit.
                let ext_rail = &stack(cfg, n_local)[0];
                let gram = match (&layers[0].basis, &ext_rail.basis) {
                    (LayerBasis::Modal(a), LayerBasis::Modal(b)) => ModalBasis::gram(a, b, false),
                    _ => unreachable!("hybrid rails are modal"),
                };
                let width = ext_rail.n_dofs();
                let r: [f64; 2] =
                    std::array::from_fn(|p| layers[0].rho_a * gram[(p + 2) * width + p + 2]);
                for a in full.iter_mut() {
                    project(a, fs, r);
                }
                condense_above(&mut full[1], fs);
                for (a, asm) in full.iter().zip(&mut out) {
                    for i in 0..n_layers {
                        for j in 0..n_layers {
                            let v = a[ext(i)][ext(j)];
                            if v != 0.0 {
                                asm.add(i, j, v);
                            }
                        }
                    }
                }
                for (k, asm) in out.iter_mut().enumerate() {
                    let total = [&fs.delta_m, &fs.delta_k, &fs.delta_c][k];
                    add_on_cubics(asm, fs, |p, q| {
                        let above = if k == 1 { -fs.above_k[p][q] } else { 0.0 };
                        total[p][q] - fs.exact[k][p][q] + above
                    });
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
        let mut structure = Self {
            length: s.length,
            layers,
            n_dofs: n,
            m: CsrMatrix::zeros(0),
            k: CsrMatrix::zeros(0),
            c: CsrMatrix::zeros(0),
            fesea,
            dampers: Vec::new(),
            base: None,
            edge_ramp: cfg.solver.edge_ramp,
            reduced: None,
        };
        let [m, k, c] = [am, ak, ac].map(Assembler::finish);
        structure.dampers = structure.damper_attachments(cfg, n_layers);
        if !structure.dampers.is_empty() {
            let params: Vec<DamperParams> = structure.dampers.iter().map(|a| a.params).collect();
            [structure.m, structure.k, structure.c] =
                stamp([&m, &k, &c], n, &structure.dampers, &params);
            structure.base = Some([m, k, c]);
        } else {
            (structure.m, structure.k, structure.c) = (m, k, c);
        }
        Ok(structure)
    }

    /// (M, C, K) for the time stepper: without the dampers when there are any.
    pub fn stepping_matrices(&self) -> (&CsrMatrix, &CsrMatrix, &CsrMatrix) {
        match &self.base {
            Some([m, k, c]) => (m, c, k),
            None => (&self.m, &self.c, &self.k),
        }
    }

    /// This structure in the substructured coordinates of `sub` (built on its layers' DOFs):
    /// the reduced matrices, the dampers stamped on their reduced shapes (their nodes after the
    /// reduced DOFs), every later shape vector reduced. Refused when `sub` maps another number
    /// of DOFs, or the rail is hybrid (its correction acts on the modal DOFs).
    pub fn substructured(&self, sub: Arc<Substructured>) -> Result<Self> {
        let n_layers: usize = self.layers.iter().map(Layer::n_dofs).sum();
        if sub.layer_dofs() != n_layers {
            return Err(VtbError::config(
                "substructures",
                sub.layer_dofs(),
                format!("maps another structure: this one has {n_layers} layer DOFs"),
            ));
        }
        if self.fesea.is_some() {
            return Err(VtbError::config(
                "discretisation.method",
                "hybrid",
                "substructures reduce a finite-element structure (\"fem\")",
            ));
        }
        let reduce = |s: &Shape| {
            let mut out = Shape::default();
            sub.reduce_shape(s.start, &s.values, &mut out);
            out
        };
        let dampers: Vec<Attachment> = self
            .dampers
            .iter()
            .enumerate()
            .map(|(i, a)| Attachment {
                upper: reduce(&a.upper),
                lower: reduce(&a.lower),
                node: sub.n + i,
                params: a.params,
            })
            .collect();
        let n = sub.n + dampers.len();
        let (m, k, c, base) = if dampers.is_empty() {
            (sub.m.clone(), sub.k.clone(), sub.c.clone(), None)
        } else {
            let params: Vec<DamperParams> = dampers.iter().map(|a| a.params).collect();
            let [m, k, c] = stamp([&sub.m, &sub.k, &sub.c], n, &dampers, &params);
            (m, k, c, Some([sub.m.clone(), sub.k.clone(), sub.c.clone()]))
        };
        Ok(Self {
            length: self.length,
            layers: self.layers.clone(),
            n_dofs: n,
            m,
            k,
            c,
            fesea: None,
            dampers,
            base,
            edge_ramp: self.edge_ramp,
            reduced: Some(sub),
        })
    }

    /// `out` holds a layer shape: in substructured coordinates, replace it by its reduction.
    #[inline]
    fn to_reduced(&self, out: &mut Shape) {
        if let Some(sub) = &self.reduced {
            LAYER_SHAPE.with_borrow_mut(|layer| {
                std::mem::swap(layer, out);
                sub.reduce_shape(layer.start, &layer.values, out);
            });
        }
    }

    /// The DOFs a contact force may act on: the rail's, or every reduced DOF.
    pub fn contact_dofs(&self) -> Vec<usize> {
        match &self.reduced {
            Some(sub) => (0..sub.n).collect(),
            None => (0..self.layers[0].n_dofs())
                .map(|k| self.layers[0].offset + k)
                .collect(),
        }
    }

    /// Entries of the rail's shape vectors (the stepper's port length).
    pub fn port_len(&self) -> usize {
        match &self.reduced {
            Some(sub) => sub.widest,
            None => self.layers[0].basis.shape_len(),
        }
    }

    /// The bending-moment shape vector of layer `layer` at x (`Layer::moment_shape`).
    pub fn moment_shape(&self, layer: usize, x: f64) -> Shape {
        let mut s = self.layers[layer].moment_shape(x);
        self.to_reduced(&mut s);
        s
    }

    /// The dampers of every group (docs/dampers.md), in `Config::damper_groups` order: DOF
    /// `first + i` is damper i's internal node, its upper and lower points the layers' shape
    /// vectors there (g̃ on a hybrid rail; none for the ground, which does not move).
    fn damper_attachments(&self, cfg: &Config, first: usize) -> Vec<Attachment> {
        let mut out = Vec::new();
        for (_, g) in cfg.damper_groups() {
            let upper = cfg.layer_index(&g.upper).expect("validated");
            let lower = cfg.layer_index(&g.lower);
            for x in g.locations() {
                out.push(Attachment {
                    upper: self.shape(upper, x),
                    lower: lower.map_or_else(Shape::default, |l| self.shape(l, x)),
                    node: first + out.len(),
                    params: g.params(),
                });
            }
        }
        out
    }

    /// (M, K) with the dampers at these positions but other parameters (one per damper): the
    /// matrices of another job of a batch.
    pub fn with_damper_params(&self, params: &[DamperParams]) -> (CsrMatrix, CsrMatrix) {
        match &self.base {
            Some([m, k, c]) => {
                let [m, k, _] = stamp([m, k, c], self.m.n, &self.dampers, params);
                (m, k)
            }
            None => (self.m.clone(), self.k.clone()),
        }
    }

    /// The layers' unknowns ordered along the track when all layers are finite-element
    /// meshes: by their node's x, then layer (top first), then DOF. Every matrix entry
    /// couples nodes at most one element of some layer apart, so in this order the matrices
    /// are banded with a bandwidth set by the meshes' densities, not by the length: an LDLᵀ in
    /// it fills O(n), and the columns of A⁻¹ the contact needs are short windows (they decay
    /// along the track). `None` when a layer is modal (its DOFs span the whole length).
    pub fn length_order(&self) -> Option<Vec<usize>> {
        if let Some(sub) = &self.reduced {
            return Some((0..sub.n).collect()); // numbered along the track already
        }
        let mut keyed = Vec::with_capacity(self.n_dofs);
        for (li, l) in self.layers.iter().enumerate() {
            let LayerBasis::Fem(mesh) = &l.basis else {
                return None;
            };
            for (j, &x) in mesh.nodes.iter().enumerate() {
                for d in 0..2 {
                    keyed.push((x, li, l.offset + 2 * j + d));
                }
            }
        }
        keyed.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
        Some(keyed.into_iter().map(|k| k.2).collect())
    }

    /// The unknowns grouped by mesh node (every layer's DOFs at node j) when all layers are
    /// finite-element meshes with the same nodes: the grouping in which the matrices are block
    /// tridiagonal.
    pub fn node_blocks(&self) -> Option<Vec<Vec<usize>>> {
        if self.reduced.is_some() {
            return None;
        }
        let meshes: Vec<&[f64]> = self
            .layers
            .iter()
            .map(|l| match &l.basis {
                LayerBasis::Fem(f) => Some(f.nodes.as_slice()),
                LayerBasis::Modal(_) => None,
            })
            .collect::<Option<_>>()?;
        let first = *meshes.first()?;
        if meshes.iter().any(|&m| m != first) {
            return None;
        }
        let ne = first.len() - 1;
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
        self.layer_shape_into(layer, x, out);
        self.to_reduced(out);
    }

    /// `shape_into` in the layers' own DOFs (no substructured reduction).
    fn layer_shape_into(&self, layer: usize, x: f64, out: &mut Shape) {
        // `out` may hold another layer's shape: layers of a modal basis differ in length.
        out.values.resize(self.layers[layer].basis.shape_len(), 0.0);
        self.layers[layer].shape_into(x, out);
        if layer == 0
            && let Some(fs) = &self.fesea
        {
            fs.correct_shape(x, &mut out.values);
        }
    }

    /// Slope shape vector w′ of layer `layer` at x (structure numbering), without allocating,
    /// where the layer is a finite-element mesh (`LayerBasis::eval_slope`; no FE–SEA
    /// correction: the synthesis, its one user, runs finite elements); `false` on a modal layer.
    pub fn slope_into(&self, layer: usize, x: f64, out: &mut Shape) -> bool {
        let l = &self.layers[layer];
        out.values.resize(l.basis.shape_len(), 0.0);
        let done = l.basis.eval_slope(x, out);
        out.start += l.offset;
        self.to_reduced(out);
        done
    }

    pub fn shape(&self, layer: usize, x: f64) -> Shape {
        let mut s = self.layers[layer].shape(x);
        if layer == 0
            && let Some(fs) = &self.fesea
        {
            fs.correct_shape(x, &mut s.values);
        }
        self.to_reduced(&mut s);
        s
    }

    /// The static flexibility (m/N) at x of layer `layer` that its finite-element
    /// interpolation misses: the deflection under a unit load at x with the nodes of its
    /// element fixed (`FemBasis::local_flexibility`); 0 for modal layers.
    pub fn local_flexibility(&self, layer: usize, x: f64) -> f64 {
        let l = &self.layers[layer];
        match &l.basis {
            LayerBasis::Fem(mesh) => mesh.local_flexibility(l.ei, x),
            LayerBasis::Modal(_) => 0.0,
        }
    }

    /// Shape vector of a wheel's contact on the rail (layer 0) at x: the point shape for a
    /// point contact (`patch` = 0), else the load-weighted average over its Hertz patch of
    /// half-length `patch` (m; finite-element rails, which the configuration ensures).
    ///
    /// Off the rail the wheel runs on a rigid track; within `edge_ramp` of the rail's ends the
    /// shape is scaled by the share s(x) of the wheel's force the rail carries (`edge_share`),
    /// the rigid track beyond taking the rest, so that a wheel joins and leaves the structure
    /// without a step in the rail level under it (docs/zones.md).
    pub fn wheel_shape_into(&self, x: f64, patch: f64, out: &mut Shape) {
        let (a, b) = self.layers[0].extent();
        let x = on_interval(x, a, b).unwrap_or(x);
        self.wheel_shape_on_rail(x, patch, out);
        let s = self.edge_share(x);
        if s != 1.0 {
            out.values.iter_mut().for_each(|v| *v *= s);
        }
        self.to_reduced(out);
    }

    /// The share (0–1) of a wheel's force at x that the rail carries: 0 off the rail, rising
    /// as a raised cosine over the first `edge_ramp` metres of the rail and falling over the
    /// last, 1 in between (and everywhere when `edge_ramp` is 0).
    pub fn edge_share(&self, x: f64) -> f64 {
        let (a, b) = self.layers[0].extent();
        let Some(x) = on_interval(x, a, b) else {
            return 0.0;
        };
        let ramp = |d: f64| {
            if d >= self.edge_ramp {
                1.0
            } else {
                0.5 * (1.0 - (std::f64::consts::PI * d / self.edge_ramp).cos())
            }
        };
        ramp(x - a) * ramp(b - x)
    }

    fn wheel_shape_on_rail(&self, x: f64, patch: f64, out: &mut Shape) {
        match &self.layers[0].basis {
            LayerBasis::Fem(mesh) if patch > 0.0 => mesh.patch_into(x, patch, out),
            _ => self.layer_shape_into(0, x, out),
        }
    }

    /// `local_flexibility` of the rail under a wheel, averaged over its patch (m/N), times
    /// the square of the rail's share of the force (`edge_share`): the wheel carries s·P to
    /// the rail and sees s times its deflection.
    pub fn element_flexibility(&self, x: f64, patch: f64) -> f64 {
        let l = &self.layers[0];
        let (a, b) = l.extent();
        let x = on_interval(x, a, b).unwrap_or(x);
        let s = self.edge_share(x);
        let element = match &l.basis {
            LayerBasis::Fem(mesh) if patch > 0.0 => mesh.patch_flexibility(l.ei, x, patch),
            _ => self.local_flexibility(0, x),
        };
        s * s * element
    }

    /// Substructured: the moments r₀, r₁, r₂ (m/N, m·s/N, m·s²/N) of the receptance the
    /// interiors' truncated modes hold under a wheel, times the square of the rail's share
    /// (`element_flexibility`); zero otherwise. r₀ is their static flexibility; r₁ and r₂ give
    /// the wheel's residual filter (`engine::coupled::residual`).
    pub fn wheel_residual(&self, x: f64, patch: f64) -> [f64; 3] {
        let Some(sub) = &self.reduced else {
            return [0.0; 3];
        };
        let (a, b) = self.layers[0].extent();
        let x = on_interval(x, a, b).unwrap_or(x);
        let s = self.edge_share(x);
        let r = LAYER_SHAPE.with_borrow_mut(|shape| {
            self.wheel_shape_on_rail(x, patch, shape);
            sub.residual_moments(shape.start, &shape.values)
        });
        r.map(|r| s * s * r)
    }

    /// The rail's static flexibility under a wheel beyond the structure's DOFs: the element's
    /// (`element_flexibility`) and, substructured, what the truncated modes hold.
    pub fn wheel_flexibility(&self, x: f64, patch: f64) -> f64 {
        self.element_flexibility(x, patch) + self.wheel_residual(x, patch)[0]
    }

    /// Entries a wheel's shape vector may need (`wheel_shape_into`).
    pub fn wheel_shape_len(&self, patch: f64) -> usize {
        if let Some(sub) = &self.reduced {
            return sub.widest;
        }
        match &self.layers[0].basis {
            LayerBasis::Fem(mesh) if patch > 0.0 => mesh.patch_len(patch),
            b => b.shape_len(),
        }
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
                cfg.extent(i),
                cfg.discretisation.method,
                cfg.discretisation.fem_elements,
                &coupling_points(cfg, &lc.name),
                offset,
            );
            offset += layer.n_dofs();
            layer
        })
        .collect()
}

/// The points where couplings attach to the layer `name` or begin and end on it: the nodes
/// of an aligned finite-element mesh. Dampers are left out: the mesh, and so a synthesis
/// reduction built on it, is the same with and without them (a damper between nodes acts
/// through the element's shape functions; the presets put theirs on nodes).
fn coupling_points(cfg: &Config, name: &str) -> Vec<f64> {
    cfg.structure
        .couplings
        .iter()
        .filter(|c| c.upper == name || c.lower == name)
        .flat_map(|c| match c.kind {
            CouplingKind::Discrete => c.positions.clone(),
            CouplingKind::Continuous => {
                let (a, b) = cfg.coupling_range(c);
                vec![a, b]
            }
        })
        .collect()
}

/// M, K and C of the layers and couplings.
fn assemble(cfg: &Config, layers: &[Layer]) -> [Assembler; 3] {
    let n = layers.iter().map(Layer::n_dofs).sum();
    let (mut am, mut ak, mut ac) = (Assembler::new(n), Assembler::new(n), Assembler::new(n));
    for l in layers
        .iter()
        .filter(|l| matches!(l.basis, LayerBasis::Fem(_)))
    {
        for (dofs, m, k) in l.element_matrices() {
            let c: [f64; 16] = std::array::from_fn(|i| l.alpha * m[i] + l.beta * k[i]);
            am.add_block(&dofs, &m, 1.0);
            ak.add_block(&dofs, &k, 1.0);
            ac.add_block(&dofs, &c, 1.0);
        }
    }
    for l in layers
        .iter()
        .filter(|l| matches!(l.basis, LayerBasis::Modal(_)))
    {
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
                CouplingKind::Continuous => add_continuous(asm, a, b, w, cfg.coupling_range(c)),
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

/// K ← K − K_·a·K_aa⁻¹·K_a· on the projected extended stiffness: the local modes above the
/// band condensed statically, together and with all their couplings (a Schur complement of a
/// positive semi-definite matrix, so it stays one).
fn condense_above(k: &mut [Vec<f64>], fs: &FeSea) {
    let idx: Vec<usize> = fs.above.iter().map(|j| 3 + j).collect();
    let (na, n) = (idx.len(), k.len());
    if na == 0 {
        return;
    }
    let mut l = vec![0.0; na * na];
    for i in 0..na {
        for j in 0..=i {
            let mut v = k[idx[i]][idx[j]];
            for p in 0..j {
                v -= l[i * na + p] * l[j * na + p];
            }
            l[i * na + j] = if i == j {
                v.max(f64::MIN_POSITIVE).sqrt()
            } else {
                v / l[j * na + j]
            };
        }
    }
    // X = L⁻¹·K_a· (na × n); the update is −XᵀX.
    let mut x = vec![vec![0.0; n]; na];
    for i in 0..na {
        for c in 0..n {
            let mut v = k[idx[i]][c];
            for p in 0..i {
                v -= l[i * na + p] * x[p][c];
            }
            x[i][c] = v / l[i * na + i];
        }
    }
    let cols: Vec<usize> = (0..n).filter(|&c| x.iter().any(|r| r[c] != 0.0)).collect();
    for &r in &cols {
        for &c in &cols {
            k[r][c] -= x.iter().map(|row| row[r] * row[c]).sum::<f64>();
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The converged preset's track and girder cut to `length` (m), its couplings kept on it.
    fn converged(length: f64) -> Structure {
        let mut cfg = crate::library::presets::paper_converged();
        cfg.structure.length = length;
        for cp in cfg.structure.couplings.iter_mut() {
            cp.positions.retain(|&x| x <= length + 1e-9);
        }
        Structure::build(&cfg).unwrap()
    }

    /// The speeds, durations and moving forces of a scan share one structure key, and the
    /// structures built from them are equal; on a hybrid rail the speed stays in the key.
    #[test]
    fn a_scan_shares_its_structure() {
        let mut a = crate::library::presets::paper_converged();
        a.structure.length = 32.0;
        for cp in a.structure.couplings.iter_mut() {
            cp.positions.retain(|&x| x <= 32.0 + 1e-9);
        }
        let mut b = a.clone();
        b.speed = 2.0 * a.speed + 1.0;
        b.solver.t_end = Some(0.7);
        b.forces.push(crate::config::MovingForceConfig {
            magnitude: 1e5,
            x0: 3.0,
            layer: None,
        });
        assert_eq!(Structure::key(&a), Structure::key(&b));
        let (sa, sb) = (Structure::build(&a).unwrap(), Structure::build(&b).unwrap());
        for (x, y) in [(&sa.m, &sb.m), (&sa.k, &sb.k), (&sa.c, &sb.c)] {
            assert_eq!(
                (&x.row_ptr, &x.col_idx, &x.values),
                (&y.row_ptr, &y.col_idx, &y.values)
            );
        }
        let hybrid = crate::library::presets::paper();
        let mut faster = hybrid.clone();
        faster.speed += 1.0;
        assert_ne!(Structure::key(&hybrid), Structure::key(&faster));
    }

    /// Half-bandwidth of M + K + C (with the layers' own meshes) in `order`.
    fn bandwidth(st: &Structure, order: &[usize]) -> usize {
        let mut inv = vec![usize::MAX; st.n_dofs];
        for (k, &i) in order.iter().enumerate() {
            inv[i] = k;
        }
        [&st.m, &st.k, &st.c]
            .iter()
            .flat_map(|a| {
                (0..a.n).flat_map(move |i| {
                    (a.row_ptr[i]..a.row_ptr[i + 1]).map(move |p| (i, a.col_idx[p]))
                })
            })
            .map(|(i, j)| inv[i].abs_diff(inv[j]))
            .max()
            .unwrap()
    }

    /// Ordered along the track, the converged model's matrices (rail 10 times finer than the
    /// lower layers, no shared nodes) have a bandwidth that does not grow with the length,
    /// while the layer-by-layer numbering's grows with it; the order is a permutation.
    #[test]
    fn length_order_has_a_bandwidth_independent_of_length() {
        let (short, long) = (converged(32.0), converged(96.0));
        assert!(short.node_blocks().is_none(), "meshes of their own");
        let mut widths = Vec::new();
        for st in [&short, &long] {
            let order = st.length_order().unwrap();
            let mut seen = order.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..st.n_dofs).collect::<Vec<_>>());
            let natural: Vec<usize> = (0..st.n_dofs).collect();
            widths.push((bandwidth(st, &order), bandwidth(st, &natural)));
        }
        // The factor in this order: its fill per unknown does not grow with the length, and
        // it solves as AMD's does (a second ordering of the same matrix).
        let fill: Vec<f64> = [&short, &long]
            .iter()
            .map(|st| {
                let a = CsrMatrix::combine(&[(2.0, &st.m), (1e-5, &st.c), (1e-10, &st.k)]);
                let f =
                    crate::linalg::sparse::Ldlt::with_ordering(&a, st.length_order().as_deref())
                        .unwrap();
                let b: Vec<f64> = (0..a.n).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
                let (x, y) = (
                    f.solve(&b),
                    crate::linalg::sparse::Ldlt::new(&a).unwrap().solve(&b),
                );
                let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                for (u, v) in x.iter().zip(&y) {
                    assert!((u - v).abs() <= 1e-10 * scale, "{u} vs {v}");
                }
                f.nnz_l() as f64 / a.n as f64
            })
            .collect();
        assert!(
            fill[1] <= 1.02 * fill[0],
            "L's entries per unknown: {fill:?}"
        );
        let ((short_w, short_nat), (long_w, long_nat)) = (widths[0], widths[1]);
        assert_eq!(short_w, long_w, "{widths:?}");
        assert!(short_w < 64, "{widths:?}");
        assert!(long_nat > 2 * short_nat, "{widths:?}");
        let mut modal = crate::library::presets::paper();
        modal.discretisation.method = Method::Modal;
        assert!(Structure::build(&modal).unwrap().length_order().is_none());
    }

    /// The rail's share of a wheel's force is 0 off the rail and at its ends, a raised cosine
    /// over `edge_ramp` (one half at half the ramp), 1 in between; the wheel's shape vector is
    /// the point shape times the share, zero off the rail.
    #[test]
    fn wheels_hand_their_force_over_at_the_rail_ends() {
        let mut cfg = crate::library::presets::paper();
        cfg.discretisation.method = Method::Modal;
        cfg.solver.edge_ramp = 8.0;
        let st = Structure::build(&cfg).unwrap();
        let l = st.length;
        for (x, want) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (4.0, 0.5),
            (8.0, 1.0),
            (80.0, 1.0),
            (l - 4.0, 0.5),
            (l, 0.0),
            (l + 3.0, 0.0),
        ] {
            assert!(
                (st.edge_share(x) - want).abs() < 1e-12,
                "x = {x}: {}",
                st.edge_share(x)
            );
        }
        let mut got = Shape::default();
        st.wheel_shape_into(4.0, 0.0, &mut got);
        let point = st.shape(0, 4.0);
        assert_eq!(got.start, point.start);
        for (g, p) in got.values.iter().zip(&point.values) {
            assert!((g - 0.5 * p).abs() <= 1e-15 * p.abs().max(1.0));
        }
        st.wheel_shape_into(-2.0, 0.0, &mut got);
        assert!(got.values.iter().all(|&v| v == 0.0));
        assert_eq!(st.wheel_flexibility(-2.0, 0.0), 0.0);
    }
}
