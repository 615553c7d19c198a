//! Vehicle models (docs/vehicles.md). A model states its degrees of freedom, masses,
//! suspension elements and wheels ([`VehicleModel`]); the engines see only the assembled linear
//! system and its wheel ports ([`Vehicle`]). Adding a model is one file here implementing the
//! trait, one arm of [`model_of`] and one variant of `crate::config::VehicleKind`.

mod car;
mod quarter_car;

pub use car::ZhaiCar;
pub use quarter_car::QuarterCar;

use crate::config::{VehicleConfig, VehicleKind};

/// The model a vehicle configuration describes, built from its fields.
pub fn model_of(v: &VehicleConfig) -> Box<dyn VehicleModel + '_> {
    match &v.model {
        crate::config::VehicleModel::Car(c) => Box::new(ZhaiCar(c)),
        crate::config::VehicleModel::QuarterCar(q) => Box::new(QuarterCar(q)),
    }
}

/// The DOF names (state order) and the wheel count of a kind: they do not depend on the
/// values, so they are read off a model with every field 0.
pub fn layout(kind: VehicleKind) -> (Vec<&'static str>, usize) {
    let zeros = match kind {
        VehicleKind::Car => serde_json::json!({
            "m_c": 0, "j_c": 0, "m_t": 0, "j_t": 0, "m_w": 0, "k_s": 0, "c_s": 0, "k_p": 0,
            "c_p": 0, "l_c": 0, "l_t": 0,
        }),
        VehicleKind::QuarterCar => serde_json::json!({"m_c": 0, "m_w": 0, "k_p": 0, "c_p": 0}),
    };
    let mut table = zeros.as_object().expect("a table").clone();
    table.insert("model".into(), kind.name().into());
    table.insert("wheel_radius".into(), 0.into());
    table.insert("x_front".into(), 0.into());
    let v: VehicleConfig =
        serde_json::from_value(table.into()).expect("a vehicle with every field 0 deserialises");
    let m = model_of(&v);
    (
        m.dofs().iter().map(|d| d.name).collect(),
        m.wheel_dofs().len(),
    )
}

/// One degree of freedom of a vehicle model: z positive downward, rotations positive nose-up.
pub struct Dof {
    pub name: &'static str,
    /// Carries its mass's weight (a bounce DOF, not a pitch).
    pub translational: bool,
}

/// A spring ∥ dashpot acting on the relative displacement dᵀz, so that it adds k·d·dᵀ to the
/// stiffness and c·d·dᵀ to the damping: symmetric by construction.
pub struct Element {
    pub d: Vec<(usize, f64)>,
    pub k: f64,
    pub c: f64,
}

/// What a vehicle model states; everything else (matrices, statics, ports) follows from it.
pub trait VehicleModel {
    /// The DOFs, in the order of the model's state; the first is the body's bounce (the DOF the
    /// comfort indices read).
    fn dofs(&self) -> &'static [Dof];
    /// The diagonal mass matrix (kg, kg·m²).
    fn masses(&self) -> Vec<f64>;
    /// The suspension elements.
    fn elements(&self) -> Vec<Element>;
    /// The DOF of each wheel in contact, front to rear.
    fn wheel_dofs(&self) -> Vec<usize>;
}

/// The largest number of wheels of one vehicle: the engines' port block width
/// (`integrator::GW`), so a model with more wheels needs a wider block.
pub const MAX_WHEELS: usize = 4;

/// A vehicle model assembled for the engines.
#[derive(Clone, Debug)]
pub struct Vehicle {
    /// Diagonal mass matrix.
    pub mass: Vec<f64>,
    /// Stiffness and damping, row-major n×n.
    pub k: Vec<f64>,
    pub c: Vec<f64>,
    /// Weight-carrying DOFs.
    translational: Vec<bool>,
    /// The DOF of each wheel, front to rear.
    pub wheel_dofs: Vec<usize>,
    /// Hertz constant G (m/N^(2/3)).
    pub hertz_g: f64,
    /// Wheel positions at t = 0, front to rear.
    pub wheel_x0: Vec<f64>,
    /// Rails sharing each axle load: a wheel receives `rails`·P for a modelled contact force P.
    pub rails: f64,
}

impl Vehicle {
    pub fn new(v: &VehicleConfig) -> Self {
        let model = model_of(v);
        let mass = model.masses();
        let n = mass.len();
        let (mut k, mut c) = (vec![0.0; n * n], vec![0.0; n * n]);
        for e in model.elements() {
            for &(i, a) in &e.d {
                for &(j, b) in &e.d {
                    k[i * n + j] += e.k * a * b;
                    c[i * n + j] += e.c * a * b;
                }
            }
        }
        Self {
            mass,
            k,
            c,
            translational: model.dofs().iter().map(|d| d.translational).collect(),
            wheel_dofs: model.wheel_dofs(),
            hertz_g: v.hertz_constant(),
            wheel_x0: v.wheel_offsets(),
            rails: v.wheels.rails as f64,
        }
    }

    pub fn n_dofs(&self) -> usize {
        self.mass.len()
    }

    pub fn n_wheels(&self) -> usize {
        self.wheel_dofs.len()
    }

    /// Gravity load vector m·g on the translational DOFs.
    pub fn gravity(&self, g: f64) -> Vec<f64> {
        self.mass
            .iter()
            .zip(&self.translational)
            .map(|(m, &t)| if t { m * g } else { 0.0 })
            .collect()
    }

    /// Static wheel loads (N) and the whole static state for given wheel displacements `z_w`:
    /// the wheels held at `z_w`, the other DOFs solve K_ff·z_f = F_f − K_fw·z_w and the wheel
    /// loads are the reactions F_w − K_w·z. For a statically determinate vehicle (both models
    /// here) the loads do not depend on `z_w`.
    pub fn static_state(&self, g: f64, z_w: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let n = self.n_dofs();
        let f = self.gravity(g);
        let free: Vec<usize> = (0..n).filter(|i| !self.wheel_dofs.contains(i)).collect();
        let mut z = vec![0.0; n];
        for (&d, &zw) in self.wheel_dofs.iter().zip(z_w) {
            z[d] = zw;
        }
        let kff: Vec<f64> = free
            .iter()
            .flat_map(|&i| free.iter().map(move |&j| (i, j)))
            .map(|(i, j)| self.k[i * n + j])
            .collect();
        let rhs: Vec<f64> = free
            .iter()
            .map(|&i| f[i] - (0..n).map(|j| self.k[i * n + j] * z[j]).sum::<f64>())
            .collect();
        // K_ff (the suspensions with the wheels held) is positive definite for validated
        // springs; parameters of extreme magnitude give NaN, which the run reports.
        let zf =
            crate::linalg::dense::solve(&kff, &rhs).unwrap_or_else(|| vec![f64::NAN; free.len()]);
        for (&i, zi) in free.iter().zip(zf) {
            z[i] = zi;
        }
        let p = self
            .wheel_dofs
            .iter()
            .map(|&i| f[i] - (0..n).map(|j| self.k[i * n + j] * z[j]).sum::<f64>())
            .collect();
        (p, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every model fits the engines' port block, and its layout names its DOFs.
    #[test]
    fn every_model_fits_the_port_block() {
        for kind in VehicleKind::ALL {
            let (dofs, wheels) = layout(kind);
            assert!((1..=MAX_WHEELS).contains(&wheels), "{}", kind.name());
            assert_eq!(dofs[0], "Z_c", "the body's bounce comes first");
        }
    }
}
