//! Vehicles and moving forces: what loads the structure.

use super::fields::{finite, positive};
use crate::error::{Result, VtbError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Zhai's 10-DOF vertical car (docs/model.md §3). Suspension constants are per bogie (secondary)
/// and per wheelset (primary), both sides lumped.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VehicleConfig {
    /// Car body mass (kg).
    pub m_c: f64,
    /// Car body pitch inertia (kg·m²).
    pub j_c: f64,
    /// Bogie mass (kg).
    pub m_t: f64,
    /// Bogie pitch inertia (kg·m²).
    pub j_t: f64,
    /// Wheelset mass (kg).
    pub m_w: f64,
    /// Secondary suspension stiffness per bogie (N/m).
    pub k_s: f64,
    /// Secondary suspension damping per bogie (N·s/m).
    pub c_s: f64,
    /// Primary suspension stiffness per wheelset (N/m).
    pub k_p: f64,
    /// Primary suspension damping per wheelset (N·s/m).
    pub c_p: f64,
    /// Half the distance between the bogie centres (m).
    pub l_c: f64,
    /// Half the bogie wheelbase (m).
    pub l_t: f64,
    /// Wheel radius (m); sets the Hertz constant G = 4.57·R^−0.149·1e−8 m/N^(2/3).
    pub wheel_radius: f64,
    /// Overrides the Hertz constant G (m/N^(2/3)).
    #[serde(default)]
    pub contact_constant: Option<f64>,
    /// Position of the leading wheelset at t = 0 (m).
    pub x_front: f64,
    /// Identical rails (count) sharing each wheelset's load. The modelled top layer is one of them
    /// and carries 1/`rails` of every axle load through its own Hertz spring (2: a full car
    /// on one of its two rails, which is what the article's 0.97 mm rail / 0.46 mm slab
    /// amplitudes imply).
    #[serde(default = "default_rails")]
    pub rails: usize,
    /// Distributed contact (true/false): each wheel's force is spread along the rail over its
    /// Hertz contact patch, the parabolic line load of an elliptical contact whose half-length
    /// (m) follows from Hertz theory for the static wheel load, `wheel_radius` and
    /// `rail_crown_radius` (steel on steel); the rail displacement the contact sees is the same
    /// load-weighted average. Needs a finite-element rail. `false`: a point contact.
    #[serde(default)]
    pub contact_patch: bool,
    /// Crown radius of the rail head (m) across the rail, for the contact patch.
    #[serde(default = "default_rail_crown_radius")]
    pub rail_crown_radius: f64,
    /// Vehicle model (docs/vehicles.md): `"car"` (Zhai's 10-DOF car) or `"quarter_car"` (a
    /// sprung mass `m_c` on `k_p` ∥ `c_p` over one wheel `m_w`; the bogie and pitch fields 0).
    /// Every vehicle of a run is of the same model.
    #[serde(default)]
    pub model: VehicleKind,
}

fn default_rails() -> usize {
    2
}

pub(crate) fn default_rail_crown_radius() -> f64 {
    0.3
}

impl VehicleConfig {
    pub fn hertz_constant(&self) -> f64 {
        self.contact_constant
            .unwrap_or_else(|| 4.57e-8 * self.wheel_radius.powf(-0.149))
    }

    /// Wheel positions at t = 0 (m), front to rear: the model's wheel geometry from the
    /// leading wheel at `x_front`.
    pub fn wheel_offsets(&self) -> Vec<f64> {
        match self.model {
            VehicleKind::Car => {
                let xc = self.x_front - self.l_c - self.l_t;
                vec![
                    xc + self.l_c + self.l_t,
                    xc + self.l_c - self.l_t,
                    xc - self.l_c + self.l_t,
                    xc - self.l_c - self.l_t,
                ]
            }
            VehicleKind::QuarterCar => vec![self.x_front],
        }
    }

    /// Number of wheels of this vehicle's model.
    pub fn n_wheels(&self) -> usize {
        self.wheel_offsets().len()
    }
}

/// Which vehicle model a `VehicleConfig` describes.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default, Hash)]
#[serde(rename_all = "snake_case")]
pub enum VehicleKind {
    /// Zhai's 10-DOF car: body, two bogies and four wheelsets, bounce and pitch.
    #[default]
    Car,
    /// A quarter car (moving sprung mass): `m_c` on the suspension `k_p`, `c_p` over one wheel
    /// of mass `m_w`. The bogie and pitch fields are not part of it and must be 0.
    QuarterCar,
}

impl VehicleKind {
    pub const ALL: [VehicleKind; 2] = [VehicleKind::Car, VehicleKind::QuarterCar];

    /// The name used in configurations.
    pub fn name(self) -> &'static str {
        match self {
            VehicleKind::Car => "car",
            VehicleKind::QuarterCar => "quarter_car",
        }
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MovingForceConfig {
    /// Force (N), positive downward.
    pub magnitude: f64,
    /// Position at t = 0 (m).
    pub x0: f64,
    /// Name of the layer the force acts on (no unit); the top layer when absent.
    #[serde(default)]
    pub layer: Option<String>,
}

impl VehicleConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        let v = self;
        positive(&format!("{p}.wheel_radius"), v.wheel_radius)?;
        if v.rails == 0 {
            return Err(VtbError::config(format!("{p}.rails"), 0, "must be >= 1"));
        }
        if let Some(g) = v.contact_constant {
            positive(&format!("{p}.contact_constant"), g)?;
        }
        positive(&format!("{p}.rail_crown_radius"), v.rail_crown_radius)?;
        // Wheels may start before x = 0 and end beyond L: off the structure they run on a
        // rigid track (docs/zones.md).
        finite(&format!("{p}.x_front"), v.x_front)?;
        Ok(())
    }
}

impl MovingForceConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        finite(&format!("{p}.magnitude"), self.magnitude)?;
        // Off its layer a force loads nothing.
        finite(&format!("{p}.x0"), self.x0)?;
        Ok(())
    }
}
