//! The train library: consists of published cars (each a 10-DOF vehicle) with the distances
//! that place them one behind the other. The Python layer's `vtb.train` builds a run's
//! vehicles from here, so every number lives in one place.

use crate::config::{CarConfig, VehicleConfig, VehicleModel};
use crate::library::presets::crh3;
use serde::Serialize;

/// One car of a consist.
#[derive(Debug, Clone, Serialize)]
pub struct TrainCar {
    /// What the car is in its formation (no unit): "motor", "trailer", "end", "intermediate",
    /// "middle".
    pub role: &'static str,
    /// Its vehicle, leading wheelset at x = 0.
    pub vehicle: VehicleConfig,
    /// From the front of the car body to its leading wheelset (m).
    pub front_overhang: f64,
    /// From its trailing wheelset to the rear of the car body (m).
    pub rear_overhang: f64,
}

impl TrainCar {
    /// Length over the car body (m).
    pub fn length(&self) -> f64 {
        let c = car_of(&self.vehicle);
        self.front_overhang + 2.0 * (c.l_c + c.l_t) + self.rear_overhang
    }
}

/// A train of the library, in its standard formation.
#[derive(Debug, Clone, Serialize)]
pub struct TrainSpec {
    pub name: &'static str,
    pub title: &'static str,
    /// Where each number comes from.
    pub source: &'static str,
    pub cars: Vec<TrainCar>,
}

/// Distance (m) from a car-body end to the nearest bogie centre of the Velaro platform:
/// 3.70 m between cars, 4.76 m at a nose (Goicolea 2014, as in TTB-2D's Velaro E files).
const VELARO_INNER_END: f64 = 3.70;
const VELARO_NOSE_END: f64 = 4.76;

/// The car parameters of a library vehicle (every one of them is a car).
fn car_of(v: &VehicleConfig) -> &CarConfig {
    // A refutable pattern, not a match: a new vehicle model needs no arm here.
    let VehicleModel::Car(c) = &v.model else {
        unreachable!("the library holds cars")
    };
    c
}

fn car(role: &'static str, vehicle: VehicleConfig, front_end: f64, rear_end: f64) -> TrainCar {
    // The overhangs run from the body ends to the outer wheelsets, l_t inside the bogie centres.
    let l_t = car_of(&vehicle).l_t;
    TrainCar {
        front_overhang: front_end - l_t,
        rear_overhang: rear_end - l_t,
        role,
        vehicle,
    }
}

/// Ends (front, rear) of car `i` of `n`: a nose at each end of the formation.
fn ends(i: usize, n: usize) -> (f64, f64) {
    (
        if i == 0 {
            VELARO_NOSE_END
        } else {
            VELARO_INNER_END
        },
        if i + 1 == n {
            VELARO_NOSE_END
        } else {
            VELARO_INNER_END
        },
    )
}

/// CRH3 (Velaro CN), 8 cars, 4 motor + 4 trailer cars in the formation Tc–M–Tp–M–M–Tp–M–Tc;
/// the cars are parameter set A (the article's car as trailer).
pub fn crh3_train() -> TrainSpec {
    let motor = [false, true, false, true, true, false, true, false];
    TrainSpec {
        name: "crh3",
        title: "CRH3 (Siemens Velaro CN), 8 cars",
        source: "cars: Zeng et al., Shock and Vibration 2014, 304219, Table 1 (trailer and motor \
                 car); formation Tc-M-Tp-M-M-Tp-M-Tc of the CRH3C; bogie centres 17.375 m \
                 apart, body ends 3.70 m (4.76 m at the noses) beyond them, the Velaro \
                 platform's (Goicolea 2014), giving 24.775 m intermediate and 25.835 m end cars",
        cars: motor
            .iter()
            .enumerate()
            .map(|(i, &m)| {
                let (f, r) = ends(i, motor.len());
                car(if m { "motor" } else { "trailer" }, crh3(m, 0.0), f, r)
            })
            .collect(),
    }
}

/// A Velaro E (RENFE AVE S-103) car: `middle` for coaches 4 and 5, the others (1–3, 6–8)
/// otherwise. Suspension per side doubled to the model's lumped values; wheel radius 0.46 m
/// (920 mm wheels).
fn velaro_e_car(middle: bool) -> VehicleConfig {
    let (m_c, j_c, j_t) = if middle {
        (41_200.0, 1_687_552.0, 1_372.0)
    } else {
        (47_800.0, 1_957_888.0, 1_715.0)
    };
    let base = crh3(false, 0.0);
    VehicleConfig {
        model: VehicleModel::Car(CarConfig {
            m_c,
            j_c,
            m_t: 3_500.0,
            j_t,
            m_w: 1_800.0,
            k_s: 2.0 * 350e3,
            c_s: 2.0 * 20e3,
            k_p: 2.0 * 1.2e6,
            c_p: 2.0 * 10e3,
            ..car_of(&base).clone()
        }),
        ..base
    }
}

/// Velaro E (AVE S-103), 8 cars.
pub fn velaro_e_train() -> TrainSpec {
    let n = 8;
    TrainSpec {
        name: "velaro_e",
        title: "Siemens Velaro E (RENFE AVE S-103), 8 cars",
        source: "J. M. Goicolea (2014), Simplified mechanical description of the AVE S-103 \
                 (ICE3 / Velaro E) high-speed train, Universidad Politécnica de Madrid, \
                 oa.upm.es/43946, as tabulated in the TTB-2D files TrainProp_AVE_S103_* \
                 (Cantero, SoftwareX 2022): coaches 1-3 and 6-8 47.8 t, 4-5 41.2 t; \
                 bogie centres 17.375 m apart, wheelbase 2.5 m, body ends 3.70 m (4.76 m at \
                 the noses) beyond the bogie centres; 200.3 m over the 8 cars",
        cars: (0..n)
            .map(|i| {
                let middle = i == 3 || i == 4;
                let (f, r) = ends(i, n);
                let role = match i {
                    0 | 7 => "end",
                    3 | 4 => "middle",
                    _ => "intermediate",
                };
                car(role, velaro_e_car(middle), f, r)
            })
            .collect(),
    }
}

/// Every train of the library.
pub fn library() -> Vec<TrainSpec> {
    vec![crh3_train(), velaro_e_train()]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The consists' lengths are the published ones: Velaro E 200.3 m over its 8 cars
    /// (Goicolea 2014), CRH3C the same body (Velaro platform).
    #[test]
    fn consists_have_their_published_lengths() {
        for t in library() {
            let total: f64 = t.cars.iter().map(TrainCar::length).sum();
            assert!((total - 200.32).abs() < 0.01, "{}: {total}", t.name);
        }
    }

    /// Velaro E static axle load, coaches 1-3 and 6-8: (M_c + 2M_t + 4M_w)·g/4 = 152.1 kN
    /// (physics data for the Velaro, set B).
    #[test]
    fn velaro_axle_load() {
        let car = velaro_e_car(false);
        let v = car_of(&car);
        let axle = (v.m_c + 2.0 * v.m_t + 4.0 * v.m_w) * 9.81 / 4.0;
        assert!((axle - 152.1e3).abs() < 0.1e3, "{axle}");
    }
}
