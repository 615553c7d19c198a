//! Time integration, the contact iteration, and how a run starts and ends.

use super::fields::{MAX_STEPS, STEP_TOL, non_negative, positive};
use crate::error::{Result, VtbError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default)]
#[serde(rename_all = "snake_case")]
pub enum InitialState {
    /// Static equilibrium of the loaded system (contact included).
    #[default]
    Static,
    /// Structure at rest and undeformed (Frýba's zero initial conditions); vehicles still
    /// start in their own static equilibrium on the undeformed track.
    Rest,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SolverConfig {
    /// Newmark time step (s).
    #[serde(default = "default_dt")]
    pub dt: f64,
    /// End time (s). Default: when the leading wheel (or force) reaches L − `end_margin`, or
    /// `tail` after the last one has left the structure.
    #[serde(default)]
    pub t_end: Option<f64>,
    /// Free vibration (s) recorded after the last wheel or force has left the structure
    /// (passed x = L): the default end time becomes that moment plus `tail`. Wheels beyond
    /// x = L run on a rigid track and no longer load the structure; as they cross the rail's
    /// end, a tail needs `edge_ramp` (or `vtb.track_zones`) or `edge_step`.
    #[serde(default)]
    pub tail: Option<f64>,
    /// Length (m) at each end of the rail over which a wheel's force is handed between the
    /// rail and the rigid track beyond the structure: the rail carries a raised-cosine share
    /// of it, 0 at the rail's end and 1 at `edge_ramp` from it, so that wheels join and leave
    /// the structure without a step (docs/zones.md; `vtb.track_zones` sets 10 m). 0: no
    /// hand-over, and a wheel that would cross an end of the rail during the run is refused
    /// unless `edge_step` asks for the step it meets there. Finite-element or modal rails.
    #[serde(default = "default_edge_ramp")]
    pub edge_ramp: f64,
    /// true/false: with `edge_ramp` = 0, let wheels cross an end of the rail and meet the
    /// track's static deflection there as a step (an impact no real track has; the FE–SEA
    /// hybrid, which takes no ramp, needs it for wheels that leave the rail).
    #[serde(default)]
    pub edge_step: bool,
    /// Distance kept between the leading wheel and the end of the structure for the default
    /// end time (m).
    #[serde(default = "default_end_margin")]
    pub end_margin: f64,
    /// Gravitational acceleration (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity: f64,
    /// Contact iteration stops when every wheel's residual `|P − h(δ)|` (force against the Hertz
    /// law at its compression) is at most `contact_tol` (−) × (static wheel load).
    #[serde(default = "default_contact_tol")]
    pub contact_tol: f64,
    /// Newton iterations (count) of the contact per step before a `ConvergenceError`.
    #[serde(default = "default_contact_max_iter")]
    pub contact_max_iter: usize,
    /// `"static"`: the static equilibrium of the loaded system; `"rest"`: the structure
    /// undeformed and at rest (docs/model.md §7).
    #[serde(default)]
    pub initial_state: InitialState,
    /// Memory a run may allocate (bytes): a run whose matrices or histories are estimated to
    /// need more is refused up front (docs/limits.md).
    #[serde(default = "default_memory_budget")]
    pub memory_budget: f64,
    /// Distance (m) over which the irregularity under every wheel grows from zero to its full
    /// value, a raised cosine in the distance travelled since t = 0 (docs/model.md §4): the
    /// run starts in the static equilibrium of the smooth track, with the wheels' vertical
    /// velocity in step with the profile. 0 applies the profile in full from t = 0; the wheels
    /// then start at rest on a profile that moves under them at the running speed, a start-up
    /// impact that sets the car body's maximum acceleration.
    #[serde(default = "default_fade_in")]
    pub fade_in: f64,
}

fn default_dt() -> f64 {
    5e-5
}
fn default_edge_ramp() -> f64 {
    0.0
}
fn default_end_margin() -> f64 {
    1.0
}
fn default_gravity() -> f64 {
    9.81
}
fn default_contact_tol() -> f64 {
    1e-10
}
fn default_contact_max_iter() -> usize {
    50
}
fn default_fade_in() -> f64 {
    2.0
}

fn default_memory_budget() -> f64 {
    8e9
}

impl Default for SolverConfig {
    fn default() -> Self {
        Self {
            dt: default_dt(),
            t_end: None,
            tail: None,
            edge_ramp: default_edge_ramp(),
            edge_step: false,
            end_margin: default_end_margin(),
            fade_in: default_fade_in(),
            gravity: default_gravity(),
            contact_tol: default_contact_tol(),
            contact_max_iter: default_contact_max_iter(),
            initial_state: InitialState::Static,
            memory_budget: default_memory_budget(),
        }
    }
}

impl SolverConfig {
    pub fn validate(&self) -> Result<()> {
        let dt = positive("solver.dt", self.dt)?;
        non_negative("solver.end_margin", self.end_margin)?;
        non_negative("solver.edge_ramp", self.edge_ramp)?;
        if self.edge_step && self.edge_ramp > 0.0 {
            return Err(VtbError::config(
                "solver.edge_step",
                true,
                format!(
                    "asks for the step of a rail end without a hand-over, but edge_ramp = {} m hands the force over",
                    self.edge_ramp
                ),
            ));
        }
        non_negative("solver.gravity", self.gravity)?;
        positive("solver.contact_tol", self.contact_tol)?;
        if self.contact_max_iter == 0 {
            return Err(VtbError::config(
                "solver.contact_max_iter",
                0,
                "must be >= 1",
            ));
        }
        positive("solver.memory_budget", self.memory_budget)?;
        non_negative("solver.fade_in", self.fade_in)?;
        if let Some(t) = self.t_end {
            positive("solver.t_end", t)?;
            let steps = t / dt;
            if (steps - steps.round()).abs() > STEP_TOL && steps < MAX_STEPS as f64 {
                let (lo, hi) = (steps.floor().max(1.0) * dt, steps.ceil() * dt);
                return Err(VtbError::config(
                    "solver.t_end",
                    format!("{t:?}"),
                    format!(
                        "is not a whole number of time steps dt = {dt:?} (t_end/dt = {steps:.6}): \
                         the nearest valid end times are {lo:?} and {hi:?} s"
                    ),
                ));
            }
        }
        if let Some(tail) = self.tail {
            non_negative("solver.tail", tail)?;
            if self.t_end.is_some() {
                return Err(VtbError::config(
                    "solver.tail",
                    tail,
                    "give either solver.t_end or solver.tail, not both",
                ));
            }
        }
        Ok(())
    }
}
