//! Dampers (docs/dampers.md): every kind is two branches in series through a massless
//! internal node, the upper branch from a point of the upper layer to the node, the lower
//! branch from the node to a point of the lower layer (or the fixed ground). A branch is a
//! spring k, a dashpot c and an inerter b in parallel. A kind is which element sits in which
//! branch (`DamperParams::branches`); everything else (the stamp into M, K, C, the elimination
//! of the node in each time step, the branch state of the modal synthesis) works on branches,
//! so a new kind is one arm of that match.
//!
//! Kinds: the tuned inerter damper (TID: spring ∥ dashpot, then inerter), the tuned viscous
//! mass damper (TVMD, Ikago et al. 2012: spring, then inerter ∥ dashpot) and the tuned mass
//! damper (TMD: the TID's branches with the inerter to the ground, which is a mass b).
//!
//! The time steppers need the node's products with M and K on one side each: the upper
//! branch carries no inerter and the lower branch no spring (checked by `branches`).

use crate::config::{DamperKind, DamperParams};
use crate::linalg::sparse::{Assembler, CsrMatrix};
use crate::model::basis::Shape;

/// A spring k (N/m), a dashpot c (N·s/m) and an inerter b (kg) in parallel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Branch {
    pub stiffness: f64,
    pub damping: f64,
    pub inertance: f64,
}

impl Branch {
    /// Force per unit extension increment over one trapezoidal (average-acceleration) step:
    /// z = k + 2c/Δt + 4b/Δt².
    #[inline]
    pub fn step_stiffness(&self, dt: f64) -> f64 {
        self.stiffness + 2.0 * self.damping / dt + 4.0 * self.inertance / (dt * dt)
    }

    /// The same in the velocity form of the stepper's A = 2M + Δt·C + (Δt²/2)·K:
    /// α = (Δt²/2)·z = 2b + Δt·c + (Δt²/2)·k.
    #[inline]
    pub fn step_impedance(&self, dt: f64) -> f64 {
        2.0 * self.inertance + dt * self.damping + 0.5 * dt * dt * self.stiffness
    }
}

impl DamperParams {
    /// [upper branch (upper layer → node), lower branch (node → lower layer or ground)].
    pub fn branches(&self) -> [Branch; 2] {
        let (k, c, b) = (self.stiffness, self.damping, self.inertance);
        let out = match self.kind {
            DamperKind::Tid | DamperKind::Tmd => [
                Branch {
                    stiffness: k,
                    damping: c,
                    inertance: 0.0,
                },
                Branch {
                    stiffness: 0.0,
                    damping: 0.0,
                    inertance: b,
                },
            ],
            DamperKind::Tvmd => [
                Branch {
                    stiffness: k,
                    damping: 0.0,
                    inertance: 0.0,
                },
                Branch {
                    stiffness: 0.0,
                    damping: c,
                    inertance: b,
                },
            ],
        };
        debug_assert!(out[0].inertance == 0.0 && out[1].stiffness == 0.0);
        out
    }
}

/// A damper of the assembled structure: its kind and parameters, the shape vectors of its
/// upper and lower points (empty for the ground) and its internal node's DOF.
#[derive(Clone, Debug)]
pub struct Attachment {
    pub upper: Shape,
    pub lower: Shape,
    pub node: usize,
    pub params: DamperParams,
}

/// Trapezoidal (average-acceleration) state of a branch: extension x, its rate v and
/// acceleration a (the acceleration matters only with an inerter).
#[derive(Clone, Copy, Debug, Default)]
pub struct BranchState {
    pub x: f64,
    pub v: f64,
    pub a: f64,
}

impl BranchState {
    /// x̂ with x₁ = F₁/z + x̂ for the force F₁ at the end of the step (z = `step_stiffness`).
    #[inline]
    pub fn offset(&self, br: &Branch, dt: f64) -> f64 {
        let history = br.inertance * (4.0 * self.x / (dt * dt) + 4.0 * self.v / dt + self.a)
            + br.damping * (2.0 * self.x / dt + self.v);
        history / br.step_stiffness(dt)
    }

    /// Ends the step with force F₁ through the branch (`offset` taken from this state).
    #[inline]
    pub fn advance(&mut self, br: &Branch, dt: f64, f1: f64, offset: f64) {
        let x1 = f1 / br.step_stiffness(dt) + offset;
        let v1 = 2.0 * (x1 - self.x) / dt - self.v;
        // From the branch's own equation F = b·a + c·v + k·x (no round-off recursion).
        let a1 = if br.inertance > 0.0 {
            (f1 - br.damping * v1 - br.stiffness * x1) / br.inertance
        } else {
            0.0
        };
        *self = Self {
            x: x1,
            v: v1,
            a: a1,
        };
    }
}

/// M, K, C of `base` (the layers' DOFs) plus the dampers with the given parameters, in
/// matrices of dimension `n`: each branch element w·(e_node − N)(e_node − N)ᵀ with N the shape
/// of its side's point (w = b into M, k into K, c into C).
pub fn stamp(
    base: [&CsrMatrix; 3],
    n: usize,
    dampers: &[Attachment],
    params: &[DamperParams],
) -> [CsrMatrix; 3] {
    let mut full = base.map(|a| {
        let mut asm = Assembler::new(n);
        for i in 0..a.n {
            for p in a.row_ptr[i]..a.row_ptr[i + 1] {
                asm.add(i, a.col_idx[p], a.values[p]);
            }
        }
        asm
    });
    for (a, p) in dampers.iter().zip(params) {
        for (br, s) in p.branches().iter().zip([&a.upper, &a.lower]) {
            let mut dofs: Vec<usize> = (s.start..s.start + s.values.len()).collect();
            dofs.push(a.node);
            let mut v: Vec<f64> = s.values.iter().map(|x| -x).collect();
            v.push(1.0);
            let block: Vec<f64> = v
                .iter()
                .flat_map(|p| v.iter().map(move |q| p * q))
                .collect();
            let [am, ak, ac] = &mut full;
            for (asm, w) in [(am, br.inertance), (ak, br.stiffness), (ac, br.damping)] {
                if w != 0.0 {
                    asm.add_block(&dofs, &block, w);
                }
            }
        }
    }
    full.map(Assembler::finish)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A branch carrying a known force F₀·sin ωt, started on the steady state
    /// x = Im(F₀e^{iωt}/(k − bω² + iωc)): the step's extension converges to it at second order.
    #[test]
    fn a_branch_step_converges_to_its_force_law_at_second_order() {
        let (f0, w) = (1e3, 50.0);
        for br in [
            Branch {
                stiffness: 3.0e5,
                damping: 4e3,
                inertance: 2.0,
            },
            Branch {
                stiffness: 3.0e5,
                damping: 4e3,
                inertance: 0.0,
            },
            Branch {
                stiffness: 0.0,
                damping: 4e3,
                inertance: 2.0,
            },
            Branch {
                stiffness: 0.0,
                damping: 0.0,
                inertance: 2.0,
            },
        ] {
            // X = F₀/(d_re + i·d_im); x = |X|·sin(ωt − φ).
            let (d_re, d_im) = (br.stiffness - br.inertance * w * w, w * br.damping);
            let (amp, phi) = (f0 / d_re.hypot(d_im), d_im.atan2(d_re));
            let exact = |t: f64| amp * (w * t - phi).sin();
            let error = |dt: f64| {
                let mut s = BranchState {
                    x: exact(0.0),
                    v: amp * w * (-phi).cos(),
                    a: -w * w * exact(0.0),
                };
                let mut worst: f64 = 0.0;
                for i in 1..=(0.2 / dt).round() as usize {
                    let t = i as f64 * dt;
                    let off = s.offset(&br, dt);
                    s.advance(&br, dt, f0 * (w * t).sin(), off);
                    worst = worst.max((s.x - exact(t)).abs());
                }
                worst / amp
            };
            let (coarse, fine) = (error(1e-3), error(5e-4));
            assert!(coarse < 1e-2, "{br:?}: {coarse}");
            let order = (coarse / fine).log2();
            assert!((order - 2.0).abs() < 0.2, "{br:?}: order {order}");
        }
    }

    #[test]
    fn each_kind_keeps_the_inerter_below_and_the_spring_above() {
        for kind in [DamperKind::Tid, DamperKind::Tvmd, DamperKind::Tmd] {
            let p = DamperParams {
                kind,
                stiffness: 1.0,
                damping: 2.0,
                inertance: 3.0,
            };
            let [up, lo] = p.branches();
            assert_eq!((up.stiffness, lo.inertance), (1.0, 3.0));
            assert_eq!(up.damping + lo.damping, 2.0);
        }
    }
}
