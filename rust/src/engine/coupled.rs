//! What every engine shares: the vehicles (each its own Newmark stepper with the wheelsets as
//! contact ports), the moving forces, the contact-loss record and a run's finish.

use super::integrator::{GW, Newmark, PortBlock, accelerations};
use crate::config::Config;
use crate::error::{Result, VtbError};
use crate::linalg::sparse::{Assembler, CsrMatrix};
use crate::model::basis::Shape;
use crate::model::contact::compression;
use crate::model::vehicle::Vehicle;
use crate::outputs::{ContactLoss, RunResult};

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
        let mut nm = Newmark::<W>::new(&m, &c, &k, dt, &[], 1, None, &[])?;
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

/// Opens and closes the contact-loss periods of one run at t1 from its wheel forces `p`.
pub(crate) fn note_contact(
    loss_open: &mut [Option<f64>],
    p: &[f64],
    t1: f64,
    out: &mut Vec<ContactLoss>,
) {
    for (wi, open) in loss_open.iter_mut().enumerate() {
        match (p[wi] == 0.0, *open) {
            (true, None) => *open = Some(t1),
            (false, Some(t0)) => {
                out.push(ContactLoss {
                    wheel: wi,
                    t_start: t0,
                    t_end: Some(t1),
                });
                *open = None;
            }
            _ => {}
        }
    }
}

/// A finished run: its open contact-loss periods closed at the end, and refused when an
/// index overflowed.
pub(crate) fn finish(loss_open: &[Option<f64>], mut r: RunResult) -> Result<RunResult> {
    for (wi, open) in loss_open.iter().enumerate() {
        if let Some(t0) = open {
            r.contact_loss.push(ContactLoss {
                wheel: wi,
                t_start: *t0,
                t_end: None,
            });
        }
    }
    // A finite state can still give an overflowing index (an acceleration of 1e308 squared
    // in an r.m.s.): never return it as a result.
    if let Some((name, v)) = r.metrics().into_iter().find(|(_, v)| !v.is_finite()) {
        return Err(VtbError::Solver(format!(
            "the index {name} = {v} is not finite at the end of the run (step {}): an \
             overflow, most likely from parameters of extreme magnitude",
            r.n_steps
        )));
    }
    Ok(r)
}
