//! A quarter car, or moving sprung mass (docs/vehicles.md): a sprung mass m_c on a
//! spring k_p ∥ dashpot c_p over one wheel of mass m_w. DOFs `[Z_c, Z_w]`, z positive
//! downward. The classical reduced vehicle of bridge dynamics (the sprung mass of Yang & Wu,
//! the one-wheel vehicle of Frýba's moving-oscillator problems).

use super::{Dof, Element, VehicleModel};
use crate::config::QuarterCarConfig;

const DOFS: &[Dof] = &[
    Dof {
        name: "Z_c",
        translational: true,
    },
    Dof {
        name: "Z_w",
        translational: true,
    },
];

/// The quarter car of a vehicle configuration.
pub struct QuarterCar<'a>(pub &'a QuarterCarConfig);

impl VehicleModel for QuarterCar<'_> {
    fn dofs(&self) -> &'static [Dof] {
        DOFS
    }

    fn masses(&self) -> Vec<f64> {
        vec![self.0.m_c, self.0.m_w]
    }

    fn elements(&self) -> Vec<Element> {
        vec![Element {
            d: vec![(0, 1.0), (1, -1.0)],
            k: self.0.k_p,
            c: self.0.c_p,
        }]
    }

    fn wheel_dofs(&self) -> Vec<usize> {
        vec![1]
    }
}

#[cfg(test)]
mod tests {
    use crate::config::{VehicleConfig, VehicleKind};
    use crate::model::vehicle::Vehicle;

    fn quarter() -> VehicleConfig {
        let mut v: VehicleConfig = serde_json::from_str(
            r#"{"m_c": 11000, "m_w": 1200, "k_p": 1.2e6, "c_p": 3e4, "wheel_radius": 0.46,
                "x_front": 3.0, "model": "quarter_car"}"#,
        )
        .unwrap();
        v.wheels.rails = 1;
        v
    }

    #[test]
    fn the_wheel_carries_both_masses_and_the_body_sits_on_its_spring() {
        let v = quarter();
        assert_eq!(v.model.kind(), VehicleKind::QuarterCar);
        let q = Vehicle::new(&v);
        let (p, z) = q.static_state(9.81, &[1e-4]);
        assert!((p[0] - (11000.0 + 1200.0) * 9.81).abs() < 1e-6);
        // Body deflection = wheel + m_c·g/k_p (z downward).
        assert!((z[0] - (1e-4 + 11000.0 * 9.81 / 1.2e6)).abs() < 1e-12);
        assert_eq!(q.wheel_x0, vec![3.0]);
    }

    /// A quarter car carries only its own fields: a car's is an unknown field, named.
    #[test]
    fn car_fields_are_not_a_quarter_cars() {
        let text = r#"{"structure": {"length": 10, "layers": []}, "speed": 1,
            "vehicles": [{"model": "quarter_car", "m_c": 1, "m_w": 1, "k_p": 1, "c_p": 0,
                          "l_c": 8, "wheel_radius": 0.46, "x_front": 0}]}"#;
        match crate::config::Config::from_json(text) {
            Err(crate::error::VtbError::Config { field, .. }) => {
                assert_eq!(field, "vehicles[0].l_c")
            }
            other => panic!("{other:?}"),
        }
    }
}
