//! Zhai's 10-DOF vertical car (docs/vehicles.md).
//!
//! DOFs, z positive downward, pitch positive nose-up, front at larger x:
//! `[Z_c, β_c, Z_t1, β_t1, Z_t2, β_t2, Z_w1, Z_w2, Z_w3, Z_w4]`; bogie 1 and wheelset 1 lead.
//! Each suspension element is a spring–dashpot acting on a relative displacement dᵀz
//! (e.g. F_s1 = K_s(Z_c − l_c·β_c − Z_t1)).

use super::{Dof, Element, VehicleModel};
use crate::config::CarConfig;

/// Index of the first wheelset DOF.
const WHEEL0: usize = 6;

const DOFS: &[Dof] = &[
    Dof {
        name: "Z_c",
        translational: true,
    },
    Dof {
        name: "beta_c",
        translational: false,
    },
    Dof {
        name: "Z_t1",
        translational: true,
    },
    Dof {
        name: "beta_t1",
        translational: false,
    },
    Dof {
        name: "Z_t2",
        translational: true,
    },
    Dof {
        name: "beta_t2",
        translational: false,
    },
    Dof {
        name: "Z_w1",
        translational: true,
    },
    Dof {
        name: "Z_w2",
        translational: true,
    },
    Dof {
        name: "Z_w3",
        translational: true,
    },
    Dof {
        name: "Z_w4",
        translational: true,
    },
];

/// The 10-DOF car of a vehicle configuration.
pub struct ZhaiCar<'a>(pub &'a CarConfig);

impl VehicleModel for ZhaiCar<'_> {
    fn dofs(&self) -> &'static [Dof] {
        DOFS
    }

    fn masses(&self) -> Vec<f64> {
        let v = self.0;
        vec![
            v.m_c, v.j_c, v.m_t, v.j_t, v.m_t, v.j_t, v.m_w, v.m_w, v.m_w, v.m_w,
        ]
    }

    fn elements(&self) -> Vec<Element> {
        let v = self.0;
        let mut out = Vec::with_capacity(6);
        // Secondary: bogie i (DOF 2+2i) under the body point Z_c ∓ l_c·β_c.
        for (i, sign) in [(0, -1.0), (1, 1.0)] {
            out.push(Element {
                d: vec![(0, 1.0), (1, sign * v.l_c), (2 + 2 * i, -1.0)],
                k: v.k_s,
                c: v.c_s,
            });
        }
        // Primary: wheelsets a (front, −l_t·β_t) and b (rear, +l_t·β_t) of each bogie.
        for bogie in 0..2 {
            let (zt, bt) = (2 + 2 * bogie, 3 + 2 * bogie);
            for (j, sign) in [(0, -1.0), (1, 1.0)] {
                out.push(Element {
                    d: vec![
                        (zt, 1.0),
                        (bt, sign * v.l_t),
                        (WHEEL0 + 2 * bogie + j, -1.0),
                    ],
                    k: v.k_p,
                    c: v.c_p,
                });
            }
        }
        out
    }

    fn wheel_dofs(&self) -> Vec<usize> {
        (WHEEL0..WHEEL0 + 4).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::VehicleConfig;
    use crate::model::vehicle::Vehicle;

    const N_DOF: usize = 10;

    pub fn set_a_trailer() -> VehicleConfig {
        let mut v = crate::library::presets::crh3(false, 30.0);
        v.wheels.contact_constant = None;
        v
    }

    fn params(v: &VehicleConfig) -> &CarConfig {
        match &v.model {
            crate::config::VehicleModel::Car(c) => c,
            _ => unreachable!("a car"),
        }
    }

    #[test]
    fn stiffness_is_symmetric_and_forces_match_model_md() {
        let cfg = set_a_trailer();
        let car = Vehicle::new(&cfg);
        let v = params(&cfg);
        for i in 0..N_DOF {
            for j in 0..N_DOF {
                assert_eq!(car.k[i * N_DOF + j], car.k[j * N_DOF + i]);
            }
        }
        // Generalised force −K·z must equal the right-hand sides of docs/model.md §3.
        let z = [
            1.0e-3, 2.0e-4, -3.0e-4, 1.0e-3, 5.0e-4, -2.0e-3, 1.0e-4, -1.0e-4, 2.0e-4, 0.0,
        ];
        let fs1 = v.k_s * (z[0] - v.l_c * z[1] - z[2]);
        let fs2 = v.k_s * (z[0] + v.l_c * z[1] - z[4]);
        let fp = |zt: f64, bt: f64, zw: f64, s: f64| v.k_p * (zt + s * v.l_t * bt - zw);
        let (fp1, fp2) = (fp(z[2], z[3], z[6], -1.0), fp(z[2], z[3], z[7], 1.0));
        let (fp3, fp4) = (fp(z[4], z[5], z[8], -1.0), fp(z[4], z[5], z[9], 1.0));
        let want = [
            -fs1 - fs2,
            v.l_c * (fs1 - fs2),
            fs1 - fp1 - fp2,
            v.l_t * (fp1 - fp2),
            fs2 - fp3 - fp4,
            v.l_t * (fp3 - fp4),
            fp1,
            fp2,
            fp3,
            fp4,
        ];
        for i in 0..N_DOF {
            let got: f64 = -(0..N_DOF).map(|j| car.k[i * N_DOF + j] * z[j]).sum::<f64>();
            assert!(
                (got - want[i]).abs() < 1e-6 * want[i].abs().max(1.0),
                "dof {i}: {got} vs {}",
                want[i]
            );
        }
    }

    #[test]
    fn static_wheel_loads_follow_from_statics() {
        let cfg = set_a_trailer();
        let car = Vehicle::new(&cfg);
        let v = params(&cfg);
        let g = 9.81;
        let (p, _) = car.static_state(g, &[1e-4, -2e-4, 3e-4, 0.0]);
        let want = v.m_w * g + 0.5 * v.m_t * g + 0.25 * v.m_c * g;
        for pw in p {
            assert!((pw - want).abs() < 1e-6 * want, "{pw} vs {want}");
        }
        // Axle load of the set A trailer: 143.2 kN.
        assert!((want / 1e3 - 143.2).abs() < 0.1);
    }
}
