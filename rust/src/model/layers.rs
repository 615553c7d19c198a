//! Beam layers (rail, slab, base, girder …): Euler–Bernoulli or Timoshenko properties, the
//! basis of each layer, the exact Gram blocks ∫N·Nᵀ and ∫N″·N″ᵀ from which modal mass,
//! stiffness, Rayleigh damping and continuous couplings are built, and the element matrices
//! of finite-element layers.

use crate::config::{LayerConfig, Method};
use crate::model::basis::{FemBasis, Func, LayerBasis, ModalBasis, Piece, Shape, integrate};

#[derive(Clone, Debug)]
pub struct Layer {
    pub name: String,
    pub basis: LayerBasis,
    /// First DOF of this layer in the structure's numbering.
    pub offset: usize,
    /// ρA (kg/m) and EI (N·m²).
    pub rho_a: f64,
    pub ei: f64,
    /// Timoshenko layers: shear stiffness κGA (N) and rotary inertia ρI (kg·m); `None` for
    /// Euler–Bernoulli.
    pub shear: Option<Shear>,
    /// Rayleigh coefficients α (1/s), β (s).
    pub alpha: f64,
    pub beta: f64,
}

/// Shear properties of a Timoshenko layer.
#[derive(Clone, Copy, Debug)]
pub struct Shear {
    /// κGA (N).
    pub kga: f64,
    /// ρI (kg·m).
    pub rho_i: f64,
}

impl Layer {
    /// A layer of a validated config over `extent` = (start, end) of a structure of length
    /// `length`. Finite-element layers with an `element_length` get nodes on `breakpoints`
    /// (the layer's coupling points) and on its joints; the others a uniform mesh of `fem_elements` over the
    /// structure's length (in proportion, over part of it).
    pub fn new(
        cfg: &LayerConfig,
        length: f64,
        (start, end): (f64, f64),
        method: Method,
        fem_elements: usize,
        breakpoints: &[f64],
        offset: usize,
    ) -> Self {
        let rho_a = cfg.density * cfg.area;
        let ei = cfg.youngs_modulus * cfg.inertia;
        let shear = match (cfg.shear_modulus, cfg.shear_coefficient) {
            (Some(g), Some(k)) => Some(Shear {
                kga: k * g * cfg.area,
                rho_i: cfg.density * cfg.inertia,
            }),
            _ => None,
        };
        let basis = match method {
            Method::Fem => {
                let share = (end - start) / length;
                let n = ((fem_elements as f64 * share).round() as usize).max(1);
                let points = [breakpoints, &cfg.joints].concat();
                let mesh = match cfg.element_length {
                    Some(h) => FemBasis::aligned(start, end, h, &points),
                    // A uniform mesh with nodes on the joints: aligned at its element length.
                    None if !cfg.joints.is_empty() => {
                        FemBasis::aligned(start, end, (end - start) / n as f64, &points)
                    }
                    None => FemBasis::uniform(start, end, n),
                }
                .with_joints(&cfg.joints);
                LayerBasis::Fem(match shear {
                    Some(s) => mesh.with_shear(ei, s.kga),
                    None => mesh,
                })
            }
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
            ei,
            shear,
            alpha,
            beta,
        }
    }

    /// Mass and stiffness matrices of every element of a finite-element layer (structure
    /// numbering, row-major 4 × 4 over the element's DOFs w₁, θ₁, w₂, θ₂):
    /// M = ρA∫N_w N_wᵀ (+ ρI∫N_ψ N_ψᵀ), K = EI∫N_ψ′ N_ψ′ᵀ (+ κGA∫γ γᵀ, γ = N_w′ − N_ψ), with
    /// N_ψ = N_w′ for Euler–Bernoulli. All integrands are polynomials, integrated exactly.
    pub fn element_matrices(&self) -> Vec<([usize; 4], [f64; 16], [f64; 16])> {
        let LayerBasis::Fem(mesh) = &self.basis else {
            return Vec::new();
        };
        mesh.elements()
            .map(|e| {
                let (a, b) = (mesh.nodes[e], mesh.nodes[e + 1]);
                let (w, psi) = mesh.element_funcs(e);
                let (mut m, mut k) = ([0.0; 16], [0.0; 16]);
                for i in 0..4 {
                    for j in i..4 {
                        let (mij, kij) = match self.shear {
                            None => (
                                self.rho_a * integrate(&w[i], &w[j], a, b),
                                self.ei * integrate(&w[i].d2(), &w[j].d2(), a, b),
                            ),
                            Some(s) => {
                                let gi = sub(w[i].d1(), psi[i]);
                                let gj = sub(w[j].d1(), psi[j]);
                                (
                                    self.rho_a * integrate(&w[i], &w[j], a, b)
                                        + s.rho_i * integrate(&psi[i], &psi[j], a, b),
                                    self.ei * integrate(&psi[i].d1(), &psi[j].d1(), a, b)
                                        + s.kga * integrate(&gi, &gj, a, b),
                                )
                            }
                        };
                        (m[4 * i + j], m[4 * j + i]) = (mij, mij);
                        (k[4 * i + j], k[4 * j + i]) = (kij, kij);
                    }
                }
                let d0 = self.offset + 2 * e;
                ([d0, d0 + 1, d0 + 2, d0 + 3], m, k)
            })
            .collect()
    }

    pub fn n_dofs(&self) -> usize {
        self.basis.n_dofs()
    }

    /// [start, end] the layer covers (m).
    pub fn extent(&self) -> (f64, f64) {
        match &self.basis {
            LayerBasis::Fem(mesh) => (mesh.start(), mesh.end()),
            LayerBasis::Modal(b) => (0.0, b.length),
        }
    }

    /// Shape vector at x in the structure's numbering.
    #[inline]
    pub fn shape_into(&self, x: f64, out: &mut Shape) {
        self.basis.eval(x, out);
        out.start += self.offset;
    }

    /// Bending-moment shape vector at x (N·m per unit DOF, sagging positive: M = −EI·w″ with
    /// w down positive; −EI·ψ′ for Timoshenko elements), structure numbering.
    pub fn moment_shape(&self, x: f64) -> Shape {
        let mut s = Shape {
            start: 0,
            values: vec![0.0; self.basis.shape_len()],
        };
        self.basis.eval_curvature(x, &mut s);
        s.values.iter_mut().for_each(|v| *v *= -self.ei);
        s.start += self.offset;
        s
    }

    pub fn shape(&self, x: f64) -> Shape {
        let mut s = self.basis.shape(x);
        s.start += self.offset;
        s
    }
}

/// f − g of two polynomials on the same origin.
fn sub(f: Func, g: Func) -> Func {
    match (f, g) {
        (Func::Poly { origin, c: a }, Func::Poly { c: b, .. }) => Func::Poly {
            origin,
            c: std::array::from_fn(|i| a[i] - b[i]),
        },
        _ => unreachable!("element functions are polynomials"),
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
    gram_blocks_over(a, b, d, (f64::NEG_INFINITY, f64::INFINITY))
}

/// `gram_blocks` with the integrals over `range` only (finite-element layers; two modal
/// layers span the whole structure and take the analytic block).
pub fn gram_blocks_over(a: &Layer, b: &Layer, d: Derivative, range: (f64, f64)) -> Vec<Block> {
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
        let lo = pa[i].a.max(pb[j].a).max(range.0);
        let hi = pa[i].b.min(pb[j].b).min(range.1);
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

    /// The article's rail as a layer config.
    fn rail_config() -> LayerConfig {
        LayerConfig {
            name: "rail".into(),
            density: 7800.0,
            area: 7.745e-3,
            youngs_modulus: 2.1e11,
            inertia: 3.217e-5,
            modes: 0,
            local_modes: 0,
            shear_modulus: None,
            shear_coefficient: None,
            element_length: None,
            joints: Vec::new(),
            damping: RayleighConfig::Coefficients {
                alpha: 0.0,
                beta: 0.0,
            },
            start: None,
            end: None,
        }
    }

    fn layer(method: Method, modes: usize) -> Layer {
        let cfg = LayerConfig {
            modes,
            ..rail_config()
        };
        Layer::new(&cfg, 32.0, (0.0, 32.0), method, 40, &[], 0)
    }

    /// A Timoshenko rail of shear stiffness κG = `kg` (κ = 0.4) meshed at 0.08 m with nodes at
    /// 0.1 and 0.74 m.
    fn timoshenko(kg: f64) -> Layer {
        let cfg = LayerConfig {
            shear_modulus: Some(kg / 0.4),
            shear_coefficient: Some(0.4),
            element_length: Some(0.08),
            ..rail_config()
        };
        Layer::new(&cfg, 32.0, (0.0, 32.0), Method::Fem, 0, &[0.1, 0.74], 0)
    }

    /// The interdependent-interpolation element's stiffness equals the closed form of the
    /// exact Timoshenko beam element (Przemieniecki; Friedman & Kosmatka 1993):
    /// EI/((1+φ)ℓ³)·[12, 6ℓ, −12, 6ℓ; 6ℓ, (4+φ)ℓ², −6ℓ, (2−φ)ℓ²; …], φ = 12EI/(κGAℓ²).
    #[test]
    fn timoshenko_element_stiffness_matches_closed_form() {
        let l = timoshenko(8.1e10);
        let LayerBasis::Fem(mesh) = &l.basis else {
            unreachable!()
        };
        for (e, (dofs, _, k)) in l.element_matrices().into_iter().enumerate() {
            let le = mesh.nodes[e + 1] - mesh.nodes[e];
            let phi = 12.0 * l.ei / (l.shear.unwrap().kga * le * le);
            let c = l.ei / ((1.0 + phi) * le.powi(3));
            let (a, b, d) = (6.0 * le, (4.0 + phi) * le * le, (2.0 - phi) * le * le);
            let kk = [
                12.0, a, -12.0, a, a, b, -a, d, -12.0, -a, 12.0, -a, a, d, -a, b,
            ];
            assert_eq!(dofs[0], 2 * e);
            for i in 0..16 {
                assert!(
                    (k[i] - c * kk[i]).abs() < 1e-9 * c * 12.0,
                    "e={e} k[{i}] {} {}",
                    k[i],
                    c * kk[i]
                );
            }
        }
    }

    /// Nodes fall on the breakpoints and no element is longer than the element length.
    #[test]
    fn aligned_mesh_has_nodes_on_coupling_points() {
        let l = timoshenko(8.1e10);
        let LayerBasis::Fem(mesh) = &l.basis else {
            unreachable!()
        };
        for bp in [0.0, 0.1, 0.74, 32.0] {
            assert!(mesh.nodes.iter().any(|&n| (n - bp).abs() < 1e-12), "{bp}");
        }
        assert!(
            mesh.nodes
                .windows(2)
                .all(|w| w[1] > w[0] && w[1] - w[0] <= 0.08 + 1e-12)
        );
        // [0, 0.1] → 2 elements, [0.1, 0.74] → 8, [0.74, 32] → 391.
        assert_eq!(mesh.n_elements(), 2 + 8 + 391);
    }

    /// κG → ∞ recovers the Euler–Bernoulli element: stiffness to round-off, mass up to the
    /// rotary inertia ρI∫N_w′N_w′ᵀ.
    #[test]
    fn timoshenko_element_tends_to_euler_bernoulli() {
        let t = timoshenko(1e30);
        let mut eb = timoshenko(1.0);
        eb.shear = None;
        if let LayerBasis::Fem(m) = &mut eb.basis {
            m.phi.iter_mut().for_each(|p| *p = 0.0);
        }
        let rho_i = t.shear.unwrap().rho_i;
        let LayerBasis::Fem(mesh) = &t.basis else {
            unreachable!()
        };
        for (e, ((_, mt, kt), (_, me, ke))) in t
            .element_matrices()
            .into_iter()
            .zip(eb.element_matrices())
            .enumerate()
        {
            let (a, b) = (mesh.nodes[e], mesh.nodes[e + 1]);
            let h = crate::model::basis::hermite(a, b - a);
            for i in 0..4 {
                for j in 0..4 {
                    let kref = ke[4 * i + j];
                    assert!((kt[4 * i + j] - kref).abs() < 1e-9 * ke[0], "k {i}{j}");
                    let rot = rho_i * integrate(&h[i].d1(), &h[j].d1(), a, b);
                    let mref = me[4 * i + j] + rot;
                    assert!((mt[4 * i + j] - mref).abs() < 1e-9 * me[0], "m {i}{j}");
                }
            }
        }
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
