//! The FE–SEA correction in the Newmark engine: its set-up on the stepper, force terms and
//! output recovery.

use crate::engine::coupled::Mover;
use crate::engine::integrator::Newmark;
use crate::model::basis::Shape;
use crate::model::fesea::FeSea;

/// The FE–SEA force terms of the hybrid model on the rail's cubic DOFs g1..g4 (docs/model.md §6):
/// a load w at x adds w·a(x) + d/dt(w·b(x)) (`FeSea::load_terms`). The derivative is the
/// backward difference over the step, F_{n+1} ∋ (H_{n+1} − H_n)/Δt with H = Σ_loads w·b(x), so
/// every force sample is single-valued (Newmark's acceleration recursion stays consistent)
/// and the step integral of the term is exact up to a half-step lag.
pub(super) struct RailCorrection<'m> {
    pub(super) fs: &'m FeSea,
    /// Stepper indices of g1..g4.
    pub(super) idx: [usize; 4],
    /// 1/Δt.
    pub(super) rate: f64,
    /// H_n, and H_{n+1} from the known loads of the step, per lane.
    pub(super) g_prev: Vec<[f64; 4]>,
    pub(super) g_next: Vec<[f64; 4]>,
    /// b(x) at each wheel this step.
    pub(super) wheel_r: Vec<[f64; 4]>,
    /// Static flexibility of the local modes (mode-acceleration recovery): 1/k_j, and
    /// s_j(x_o)/k_j at each rail observation point.
    pub(super) inv_k: Vec<f64>,
    pub(super) obs: Vec<Vec<f64>>,
    /// The same at each recorded pad (`output.pad_forces`).
    pub(super) pad_obs: Vec<Vec<f64>>,
    /// s_j at each wheel, then at each moving force on the rail, this step (row-major).
    pub(super) sines: Vec<f64>,
    /// (x0, magnitude) of the moving forces on the rail.
    pub(super) movers: Vec<(f64, f64)>,
}

impl<'m> RailCorrection<'m> {
    /// The correction `fs` of the rail stepped by `track` (time step `dt`), its buffers for
    /// W lanes; the local modes' deflection is recovered at the observation `points` when
    /// `local_deflection`, and the moving forces on the rail are those of `movers` on layer 0.
    /// The wheels' rows are sized once they are known (`NewmarkSide::with_wheels`).
    pub(super) fn new<const W: usize>(
        fs: &'m FeSea,
        track: &Newmark<W>,
        dt: f64,
        movers: &[Mover],
        (rail_points, pad_points): (&[f64], &[f64]),
    ) -> Self {
        let rail_movers: Vec<(f64, f64)> = movers
            .iter()
            .filter(|m: &&Mover| m.layer == 0)
            .map(|m| (m.x0, m.magnitude))
            .collect();
        let idx = fs.dofs.map(|d| {
            track
                .vector(&Shape {
                    start: d,
                    values: vec![1.0],
                })
                .idx[0]
        });
        RailCorrection {
            fs,
            idx,
            rate: 1.0 / dt,
            g_prev: vec![[0.0; 4]; W],
            g_next: vec![[0.0; 4]; W],
            wheel_r: Vec::new(),
            inv_k: fs.modes.iter().map(|m| 1.0 / m.stiffness).collect(),
            obs: rail_points.iter().map(|&x| static_sines(fs, x)).collect(),
            pad_obs: pad_points.iter().map(|&x| static_sines(fs, x)).collect(),
            sines: Vec::new(),
            movers: rail_movers,
        }
    }

    /// The corrections of the g entries of F_{n+1} for a unit load at x: (a + b/Δt, b).
    pub(super) fn unit_load(&self, x: f64) -> ([f64; 4], [f64; 4]) {
        self.with_rate(self.fs.load_terms(x))
    }

    pub(super) fn with_rate(&self, (a, b): ([f64; 4], [f64; 4])) -> ([f64; 4], [f64; 4]) {
        (std::array::from_fn(|g| a[g] + self.rate * b[g]), b)
    }

    pub(super) fn row(&self, r: usize) -> &[f64] {
        let nl = self.inv_k.len();
        &self.sines[r * nl..(r + 1) * nl]
    }

    /// Sine rows at time t: the wheels (x0 + v·t), then the rail's moving forces.
    pub(super) fn set_rows(&mut self, wheel_x0: impl Iterator<Item = f64>, v: f64, t: f64) {
        let nl = self.inv_k.len();
        let Self {
            fs, sines, movers, ..
        } = self;
        for (r, x) in wheel_x0.chain(movers.iter().map(|m| m.0)).enumerate() {
            fs.local_sines_into(x + v * t, &mut sines[r * nl..(r + 1) * nl]);
        }
    }

    /// The local modes' static deflection at rail observation point `j` under the wheel
    /// forces `p` and the rail's moving forces (output only: in the contact this static
    /// flexibility would replace the local modes' mass-like behaviour at ω_r, docs/fesea.md).
    pub(super) fn observed_deflection(&self, j: usize, p: &[f64]) -> f64 {
        self.deflection(&self.obs[j], p)
    }

    /// The same at recorded pad `j`.
    pub(super) fn pad_deflection(&self, j: usize, p: &[f64]) -> f64 {
        self.deflection(&self.pad_obs[j], p)
    }

    /// Σ over the loads of w·(s_j(x)/k_j)·s_j(x_load): the local modes' static deflection at
    /// the point whose `static_sines` are `at`.
    fn deflection(&self, at: &[f64], p: &[f64]) -> f64 {
        let loads = p.iter().copied().chain(self.movers.iter().map(|m| m.1));
        loads
            .enumerate()
            .map(|(r, w)| w * dot(at, self.row(r)))
            .sum()
    }
}

pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// s_j(x)/k_j of every local mode: the local modes' static flexibility at x per unit load at
/// a point with sines s_j (mode-acceleration recovery of their deflection).
fn static_sines(fs: &FeSea, x: f64) -> Vec<f64> {
    let mut s = vec![0.0; fs.modes.len()];
    fs.local_sines_into(x, &mut s);
    s.iter()
        .zip(&fs.modes)
        .map(|(s, m)| s / m.stiffness)
        .collect()
}
