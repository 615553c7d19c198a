//! A quarter car, or moving sprung mass (docs/vehicles.md): a sprung mass m_c on a
//! spring k_p ∥ dashpot c_p over one wheel of mass m_w. DOFs `[Z_c, Z_w]`, z positive
//! downward. The classical reduced vehicle of bridge dynamics (the sprung mass of Yang & Wu,
//! the one-wheel vehicle of Frýba's moving-oscillator problems).

use super::{Dof, Element, VehicleModel};
use crate::config::VehicleConfig;
use crate::config::fields::{non_negative, positive};
use crate::error::{Result, VtbError};

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
pub struct QuarterCar<'a>(pub &'a VehicleConfig);

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

    fn validate(&self, p: &str) -> Result<()> {
        let v = self.0;
        for (name, val) in [("m_c", v.m_c), ("m_w", v.m_w), ("k_p", v.k_p)] {
            positive(&format!("{p}.{name}"), val)?;
        }
        non_negative(&format!("{p}.c_p"), v.c_p)?;
        // The car's other fields have no meaning here; a value would be silently unused.
        for (name, val) in [
            ("j_c", v.j_c),
            ("m_t", v.m_t),
            ("j_t", v.j_t),
            ("k_s", v.k_s),
            ("c_s", v.c_s),
            ("l_c", v.l_c),
            ("l_t", v.l_t),
        ] {
            if val != 0.0 {
                return Err(VtbError::config(
                    format!("{p}.{name}"),
                    val,
                    "a quarter car (model = \"quarter_car\") has no bogie or pitch: leave it 0",
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::VehicleKind;
    use crate::model::vehicle::Vehicle;

    fn quarter() -> VehicleConfig {
        let mut v: VehicleConfig = serde_json::from_str(
            r#"{"m_c": 11000, "j_c": 0, "m_t": 0, "j_t": 0, "m_w": 1200, "k_s": 0, "c_s": 0,
                "k_p": 1.2e6, "c_p": 3e4, "l_c": 0, "l_t": 0, "wheel_radius": 0.46,
                "x_front": 3.0, "model": "quarter_car"}"#,
        )
        .unwrap();
        v.rails = 1;
        v
    }

    #[test]
    fn the_wheel_carries_both_masses_and_the_body_sits_on_its_spring() {
        let v = quarter();
        assert_eq!(v.model, VehicleKind::QuarterCar);
        let q = Vehicle::new(&v);
        let (p, z) = q.static_state(9.81, &[1e-4]);
        assert!((p[0] - (11000.0 + 1200.0) * 9.81).abs() < 1e-6);
        // Body deflection = wheel + m_c·g/k_p (z downward).
        assert!((z[0] - (1e-4 + 11000.0 * 9.81 / 1.2e6)).abs() < 1e-12);
        assert_eq!(q.wheel_x0, vec![3.0]);
    }

    #[test]
    fn car_fields_left_set_are_refused_by_name() {
        let mut v = quarter();
        v.l_c = 8.0;
        let e = super::super::model_of(&v)
            .validate("vehicles[0]")
            .unwrap_err();
        assert!(e.to_string().contains("vehicles[0].l_c"), "{e}");
    }
}
