//! Zhai's 10-DOF vertical car (docs/model.md §3).
//!
//! DOFs, z positive downward, pitch positive nose-up, front at larger x:
//! `[Z_c, β_c, Z_t1, β_t1, Z_t2, β_t2, Z_w1, Z_w2, Z_w3, Z_w4]`; bogie 1 and wheelset 1 lead.
//! Each suspension element is a spring–dashpot acting on a relative displacement dᵀz, so
//! K = Σ k·d·dᵀ and C = Σ c·d·dᵀ are symmetric by construction and reproduce the force
//! equations of docs/model.md §3 (e.g. F_s1 = K_s(Z_c − l_c·β_c − Z_t1)).

use crate::config::VehicleConfig;

pub const N_DOF: usize = 10;
pub const N_WHEELS: usize = 4;
/// Index of the first wheelset DOF.
pub const WHEEL0: usize = 6;

pub type Mat10 = [[f64; N_DOF]; N_DOF];

#[derive(Clone, Debug)]
pub struct Car {
    /// Diagonal mass matrix.
    pub mass: [f64; N_DOF],
    pub k: Mat10,
    pub c: Mat10,
    /// Hertz constant G (m/N^(2/3)).
    pub hertz_g: f64,
    /// Wheelset positions at t = 0, front to rear.
    pub wheel_x0: [f64; N_WHEELS],
    /// Rails sharing each axle load: a wheelset receives `rails`·P for a modelled contact
    /// force P.
    pub rails: f64,
}

fn add_element(m: &mut Mat10, d: &[(usize, f64)], w: f64) {
    for &(i, a) in d {
        for &(j, b) in d {
            m[i][j] += w * a * b;
        }
    }
}

impl Car {
    pub fn new(v: &VehicleConfig) -> Self {
        let mass = [
            v.m_c, v.j_c, v.m_t, v.j_t, v.m_t, v.j_t, v.m_w, v.m_w, v.m_w, v.m_w,
        ];
        let (mut k, mut c) = ([[0.0; N_DOF]; N_DOF], [[0.0; N_DOF]; N_DOF]);
        // Secondary: bogie i (DOF 2+2i) under the body point Z_c ∓ l_c·β_c.
        for (i, sign) in [(0, -1.0), (1, 1.0)] {
            let d = [(0, 1.0), (1, sign * v.l_c), (2 + 2 * i, -1.0)];
            add_element(&mut k, &d, v.k_s);
            add_element(&mut c, &d, v.c_s);
        }
        // Primary: wheelsets a (front, −l_t·β_t) and b (rear, +l_t·β_t) of each bogie.
        for bogie in 0..2 {
            let (zt, bt) = (2 + 2 * bogie, 3 + 2 * bogie);
            for (j, sign) in [(0, -1.0), (1, 1.0)] {
                let d = [
                    (zt, 1.0),
                    (bt, sign * v.l_t),
                    (WHEEL0 + 2 * bogie + j, -1.0),
                ];
                add_element(&mut k, &d, v.k_p);
                add_element(&mut c, &d, v.c_p);
            }
        }
        Self {
            mass,
            k,
            c,
            hertz_g: v.hertz_constant(),
            wheel_x0: v.wheel_offsets(),
            rails: v.rails as f64,
        }
    }

    /// Gravity load vector m·g on the translational DOFs.
    pub fn gravity(&self, g: f64) -> [f64; N_DOF] {
        let mut f = [0.0; N_DOF];
        for i in [0, 2, 4, 6, 7, 8, 9] {
            f[i] = self.mass[i] * g;
        }
        f
    }

    /// Static wheel loads (N) and the body/bogie displacements for given wheel displacements.
    ///
    /// The car is statically determinate (body on two bogies, each on two wheelsets), so the
    /// wheel loads follow from statics alone: fix the wheelsets, solve the body and bogies,
    /// read the reactions. The body and bogies then follow the wheels as z_f =
    /// K_ff⁻¹(F_f − K_fw·z_w).
    pub fn static_state(
        &self,
        g: f64,
        z_wheels: &[f64; N_WHEELS],
    ) -> ([f64; N_WHEELS], [f64; N_DOF]) {
        let f = self.gravity(g);
        let kff: Vec<f64> = (0..WHEEL0 * WHEEL0)
            .map(|q| self.k[q / WHEEL0][q % WHEEL0])
            .collect();
        let rhs: Vec<f64> = (0..WHEEL0)
            .map(|i| {
                f[i] - (0..N_WHEELS)
                    .map(|w| self.k[i][WHEEL0 + w] * z_wheels[w])
                    .sum::<f64>()
            })
            .collect();
        // K_ff (the suspensions with the wheelsets held) is positive definite for validated
        // springs; parameters of extreme magnitude give NaN, which the run reports.
        let zf = crate::linalg::dense::solve(&kff, &rhs).unwrap_or_else(|| vec![f64::NAN; WHEEL0]);
        let mut z = [0.0; N_DOF];
        z[..WHEEL0].copy_from_slice(&zf);
        z[WHEEL0..].copy_from_slice(z_wheels);
        let mut p = [0.0; N_WHEELS];
        for (w, pw) in p.iter_mut().enumerate() {
            let i = WHEEL0 + w;
            *pw = f[i] - (0..N_DOF).map(|j| self.k[i][j] * z[j]).sum::<f64>();
        }
        (p, z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub fn set_a_trailer() -> VehicleConfig {
        VehicleConfig {
            m_c: 4.4e4,
            j_c: 2.7e6,
            m_t: 2.4e3,
            j_t: 2.2e3,
            m_w: 2.4e3,
            k_s: 6.0e5,
            c_s: 8.0e4,
            k_p: 1.4e6,
            c_p: 8.0e4,
            l_c: 8.6875,
            l_t: 1.25,
            wheel_radius: 0.46,
            contact_constant: None,
            x_front: 30.0,
            rails: 2,
            contact_patch: false,
            rail_crown_radius: crate::config::default_rail_crown_radius(),
        }
    }

    #[test]
    fn stiffness_is_symmetric_and_forces_match_model_md() {
        let v = set_a_trailer();
        let car = Car::new(&v);
        for i in 0..N_DOF {
            for j in 0..N_DOF {
                assert_eq!(car.k[i][j], car.k[j][i]);
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
            let got: f64 = -(0..N_DOF).map(|j| car.k[i][j] * z[j]).sum::<f64>();
            assert!(
                (got - want[i]).abs() < 1e-6 * want[i].abs().max(1.0),
                "dof {i}: {got} vs {}",
                want[i]
            );
        }
    }

    #[test]
    fn static_wheel_loads_follow_from_statics() {
        let v = set_a_trailer();
        let car = Car::new(&v);
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
