//! The vehicle side every engine shares: each car its own Newmark stepper with the wheelsets as
//! contact ports, the wheels' static loads, contact patches and positions, and the moving
//! forces.

use crate::config::Config;
use crate::engine::integrator::{GW, Newmark, Numbering, PortBlock, accelerations};
use crate::error::{Result, VtbError};
use crate::linalg::sparse::{Assembler, CsrMatrix};
use crate::model::Model;
use crate::model::basis::Shape;
use crate::model::contact::{compression, patch_half_length};
use crate::model::vehicle::Vehicle;

/// A constant force moving with the common speed.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Mover {
    pub(crate) layer: usize,
    pub(crate) x0: f64,
    pub(crate) magnitude: f64,
}

impl Mover {
    /// The moving forces of a configuration.
    pub(crate) fn all(cfg: &Config) -> Vec<Mover> {
        cfg.forces
            .iter()
            .map(|f| Mover {
                layer: f
                    .layer
                    .as_ref()
                    .and_then(|l| cfg.layer_index(l))
                    .unwrap_or(0),
                x0: f.x0,
                magnitude: f.magnitude,
            })
            .collect()
    }
}

/// A car's own Newmark stepper (one lane per job); its contact ports are the wheelset DOFs.
pub(crate) struct CarRun<const W: usize> {
    pub(crate) car: Vehicle,
    pub(crate) nm: Newmark<W>,
    m: CsrMatrix,
    k: CsrMatrix,
    pub(crate) ports: PortBlock<W>,
    /// Wheelset compliance over one step for unit port forces (constant, the same in every
    /// lane).
    pub(crate) compliance: [[f64; GW]; GW],
    pub(crate) gravity: Vec<f64>,
    pub(crate) f_prev: Vec<f64>,
    /// The static state of each lane (`[dof·W + lane]`).
    pub(crate) z0: Vec<f64>,
}

impl<const W: usize> CarRun<W> {
    pub(crate) fn new(car: &Vehicle, dt: f64, g: f64) -> Result<Self> {
        let nd = car.n_dofs();
        let dense = |m: &[f64]| {
            let mut a = Assembler::new(nd);
            for i in 0..nd {
                for j in 0..nd {
                    a.add(i, j, m[i * nd + j]);
                }
            }
            a.finish()
        };
        let mut am = Assembler::new(nd);
        for i in 0..nd {
            am.add(i, i, car.mass[i]);
        }
        let (m, c, k) = (am.finish(), dense(&car.c), dense(&car.k));
        let mut nm = Newmark::<W>::new(&m, &c, &k, dt, &[], 1, Numbering::Search, &[])?;
        for i in 0..nd {
            nm.observe(&Shape {
                start: i,
                values: vec![1.0],
            });
        }
        let mut ports = PortBlock::new(nd);
        for (w, &d) in car.wheel_dofs.iter().enumerate() {
            ports.vecs[w] = nm.vector(&Shape {
                start: d,
                values: vec![1.0],
            });
        }
        nm.prepare_ports(&mut ports);
        let compliance = nm.port_compliance(&ports, &ports)[0];
        let gravity = nm.to_stepper(&car.gravity(g));
        Ok(Self {
            car: car.clone(),
            nm,
            m,
            k,
            ports,
            compliance,
            f_prev: gravity.clone(),
            gravity,
            z0: vec![0.0; nd * W],
        })
    }

    /// Lane `lane` at rest in static equilibrium on wheel contacts whose rail side (rail
    /// displacement plus irregularity, m) is `rail`, under the static wheel loads `loads` (N).
    pub(crate) fn set_static(
        &mut self,
        lane: usize,
        rail: &[f64],
        loads: &[f64],
        g: f64,
    ) -> Result<()> {
        let zw: Vec<f64> = (rail.iter().zip(loads))
            .map(|(r, &l)| r + compression(self.car.hertz_g, l))
            .collect();
        let (_, z) = self.car.static_state(g, &zw);
        let mut f = self.car.gravity(g);
        for (&d, l) in self.car.wheel_dofs.iter().zip(loads) {
            f[d] -= self.car.rails * l;
        }
        let av = accelerations(&self.m, &self.k, &z, &f)?;
        let nd = z.len();
        self.nm
            .set_state(lane, &z, &vec![0.0; nd], &av, &self.k, &self.m);
        for i in 0..nd {
            self.z0[i * W + lane] = z[i];
        }
        Ok(())
    }

    /// Gravity minus rails·P on the wheelsets (stepper coordinates) into `f_prev`.
    pub(crate) fn set_force(&mut self, p: &[[f64; GW]; W]) {
        self.f_prev.clone_from(&self.gravity);
        for (lane, pl) in p.iter().enumerate() {
            for w in 0..self.car.n_wheels() {
                self.ports.vecs[w].add_to_lane::<W>(
                    &mut self.f_prev,
                    lane,
                    -self.car.rails * pl[w],
                );
            }
        }
    }
}

/// Static wheel loads on the modelled rail (N) of every car's wheelsets, from the statics of
/// each (statically determinate) car.
pub(crate) fn static_wheel_loads<const W: usize>(cars: &[CarRun<W>], g: f64) -> Vec<f64> {
    cars.iter()
        .flat_map(|c| {
            let (r, _) = c.car.static_state(g, &vec![0.0; c.car.n_wheels()]);
            r.into_iter().map(|ri| ri / c.car.rails).collect::<Vec<_>>()
        })
        .collect()
}

/// The vehicles of a run: their steppers and what the contact needs of every wheel (wheel
/// `w` of car `ci` is `ci·wpc + w`; one vehicle model per run).
pub(crate) struct Vehicles<const W: usize> {
    pub(crate) cars: Vec<CarRun<W>>,
    /// Wheels per car.
    pub(crate) wpc: usize,
    /// Static load of each wheel on the modelled rail (N).
    pub(crate) loads: Vec<f64>,
    /// Half-length (m) of each wheel's contact patch, 0 for a point contact.
    pub(crate) patch: Vec<f64>,
    /// Hertz constant of each wheel (m/N^(2/3)).
    pub(crate) hertz: Vec<f64>,
    /// Position of each wheel at t = 0 (m).
    pub(crate) x0: Vec<f64>,
}

impl<const W: usize> Vehicles<W> {
    /// The model's vehicles stepped at `dt`; a wheel that carries no static load is refused.
    pub(crate) fn new(model: &Model, dt: f64) -> Result<Self> {
        let cfg = &model.cfg;
        let g = cfg.solver.gravity;
        let cars = model
            .cars
            .iter()
            .map(|c| CarRun::<W>::new(c, dt, g))
            .collect::<Result<Vec<_>>>()?;
        let wpc = cars.first().map_or(0, |c| c.car.n_wheels());
        let loads = static_wheel_loads(&cars, g);
        if let Some((i, l)) = loads.iter().enumerate().find(|(_, l)| !(**l > 0.0)) {
            return Err(VtbError::config(
                format!("vehicles[{}]", i / wpc),
                l,
                format!("wheel {} carries no static load", i % wpc + 1),
            ));
        }
        let patch = loads
            .iter()
            .enumerate()
            .map(|(wi, &load)| {
                let v = &cfg.vehicles[wi / wpc].wheels;
                if v.contact_patch {
                    patch_half_length(load, v.wheel_radius, v.rail_crown_radius)
                } else {
                    0.0
                }
            })
            .collect();
        Ok(Self {
            hertz: cars.iter().flat_map(|c| vec![c.car.hertz_g; wpc]).collect(),
            x0: cars.iter().flat_map(|c| c.car.wheel_x0.clone()).collect(),
            cars,
            wpc,
            loads,
            patch,
        })
    }

    /// Wheels of the run.
    pub(crate) fn n_wheels(&self) -> usize {
        self.loads.len()
    }

    /// Wheel w as an error names it, at x (m).
    pub(crate) fn wheel_name(&self, w: usize, x: f64) -> String {
        format!(
            "vehicles[{}] wheel {} at x = {x:.4} m",
            w / self.wpc,
            w % self.wpc + 1
        )
    }

    /// The wheel forces of car `ci` per lane from the contact forces `p` (`[lane·nw + wheel]`),
    /// padded to the port width.
    pub(crate) fn car_forces(&self, ci: usize, p: &[f64]) -> [[f64; GW]; W] {
        let (nw, wpc) = (self.n_wheels(), self.wpc);
        std::array::from_fn(|lane| {
            std::array::from_fn(|w| {
                if w < wpc {
                    p[lane * nw + ci * wpc + w]
                } else {
                    0.0
                }
            })
        })
    }
}
