//! Vehicles and moving forces: what loads the structure.
//!
//! A vehicle is one model's own parameters ([`VehicleModel`]: Zhai's car, a quarter car) and
//! its wheels ([`Wheels`]: where they start and how they touch the rail). Its JSON (and TOML)
//! form is one flat table tagged by `model`, `"car"` when absent; a table carries only the
//! fields of its model (docs/vehicles.md). A new model is a variant here, its parameters, and
//! its file in `crate::model::vehicle`.

use super::fields::{finite, non_negative, positive};
use crate::error::{Result, VtbError};
use schemars::{JsonSchema, Schema, SchemaGenerator};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::{Map, Value};

/// Zhai's 10-DOF vertical car (docs/model.md §3). Suspension constants are per bogie (secondary)
/// and per wheelset (primary), both sides lumped.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct CarConfig {
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
}

/// A quarter car (moving sprung mass): a body `m_c` on the suspension `k_p` ∥ `c_p` over one
/// wheel of mass `m_w`.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct QuarterCarConfig {
    /// Sprung (body) mass (kg).
    pub m_c: f64,
    /// Wheel mass (kg).
    pub m_w: f64,
    /// Suspension stiffness (N/m).
    pub k_p: f64,
    /// Suspension damping (N·s/m).
    pub c_p: f64,
}

/// A vehicle's model and its own parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum VehicleModel {
    /// Zhai's 10-DOF car: body, two bogies and four wheelsets, bounce and pitch.
    Car(CarConfig),
    /// A quarter car: a sprung mass over one wheel.
    QuarterCar(QuarterCarConfig),
}

/// Which vehicle model a configuration describes (the `model` tag).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VehicleKind {
    Car,
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

    fn of(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

impl VehicleModel {
    pub fn kind(&self) -> VehicleKind {
        match self {
            VehicleModel::Car(_) => VehicleKind::Car,
            VehicleModel::QuarterCar(_) => VehicleKind::QuarterCar,
        }
    }

    /// The model's own parameters as a JSON table (its fields, no tag).
    fn fields(&self) -> Value {
        match self {
            VehicleModel::Car(c) => serde_json::to_value(c),
            VehicleModel::QuarterCar(q) => serde_json::to_value(q),
        }
        .expect("vehicle parameters serialise")
    }

    /// The model of `kind` read from a table of its fields.
    fn from_fields(kind: VehicleKind, fields: Value) -> std::result::Result<Self, String> {
        fn read<T: serde::de::DeserializeOwned>(v: Value) -> std::result::Result<T, String> {
            serde_path_to_error::deserialize(v).map_err(|e| at(&e.path().to_string(), e.inner()))
        }
        Ok(match kind {
            VehicleKind::Car => VehicleModel::Car(read(fields)?),
            VehicleKind::QuarterCar => VehicleModel::QuarterCar(read(fields)?),
        })
    }

    /// The model's parameter `name`, if it has one.
    pub fn field(&self, name: &str) -> Option<f64> {
        self.fields().get(name).and_then(Value::as_f64)
    }

    /// Checks the model's own fields; `p` is the vehicle's path.
    pub fn validate(&self, p: &str) -> Result<()> {
        match self {
            VehicleModel::Car(v) => {
                for (name, val) in [
                    ("m_c", v.m_c),
                    ("j_c", v.j_c),
                    ("m_t", v.m_t),
                    ("j_t", v.j_t),
                    ("m_w", v.m_w),
                    ("k_s", v.k_s),
                    ("k_p", v.k_p),
                    ("l_c", v.l_c),
                    ("l_t", v.l_t),
                ] {
                    positive(&format!("{p}.{name}"), val)?;
                }
                non_negative(&format!("{p}.c_s"), v.c_s)?;
                non_negative(&format!("{p}.c_p"), v.c_p)?;
                if v.l_t >= v.l_c {
                    return Err(VtbError::config(
                        format!("{p}.l_t"),
                        v.l_t,
                        format!("half wheelbase must be smaller than l_c = {}", v.l_c),
                    ));
                }
            }
            VehicleModel::QuarterCar(v) => {
                for (name, val) in [("m_c", v.m_c), ("m_w", v.m_w), ("k_p", v.k_p)] {
                    positive(&format!("{p}.{name}"), val)?;
                }
                non_negative(&format!("{p}.c_p"), v.c_p)?;
            }
        }
        Ok(())
    }
}

/// A serde error at a field inside a table read by hand: `Config::from_json` moves the path
/// into the error's field.
fn at(path: &str, e: impl std::fmt::Display) -> String {
    if path == "." || path.is_empty() {
        e.to_string()
    } else {
        format!("at `{path}`: {e}")
    }
}

/// A vehicle's wheels: where they start and how they touch the rail.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Wheels {
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
}

/// The wheels' fields, in the order of the flat form.
const WHEEL_FIELDS: [&str; 6] = [
    "wheel_radius",
    "contact_constant",
    "x_front",
    "rails",
    "contact_patch",
    "rail_crown_radius",
];

fn default_rails() -> usize {
    2
}

pub(crate) fn default_rail_crown_radius() -> f64 {
    0.3
}

/// A vehicle of the run: its model and its wheels. Every vehicle of a run is of the same model.
#[derive(Debug, Clone, PartialEq)]
pub struct VehicleConfig {
    pub model: VehicleModel,
    pub wheels: Wheels,
}

impl VehicleConfig {
    pub fn hertz_constant(&self) -> f64 {
        let w = &self.wheels;
        w.contact_constant
            .unwrap_or_else(|| 4.57e-8 * w.wheel_radius.powf(-0.149))
    }

    /// Wheel positions at t = 0 (m), front to rear: the model's wheel geometry from the
    /// leading wheel at `x_front`.
    pub fn wheel_offsets(&self) -> Vec<f64> {
        let x_front = self.wheels.x_front;
        match &self.model {
            VehicleModel::Car(c) => {
                let xc = x_front - c.l_c - c.l_t;
                vec![
                    xc + c.l_c + c.l_t,
                    xc + c.l_c - c.l_t,
                    xc - c.l_c + c.l_t,
                    xc - c.l_c - c.l_t,
                ]
            }
            VehicleModel::QuarterCar(_) => vec![x_front],
        }
    }

    /// Number of wheels of this vehicle's model.
    pub fn n_wheels(&self) -> usize {
        self.wheel_offsets().len()
    }

    /// Checks its model's fields and its wheels'; `p` is the vehicle's path.
    pub fn validate(&self, p: &str) -> Result<()> {
        self.model.validate(p)?;
        let w = &self.wheels;
        positive(&format!("{p}.wheel_radius"), w.wheel_radius)?;
        if w.rails == 0 {
            return Err(VtbError::config(format!("{p}.rails"), 0, "must be >= 1"));
        }
        if let Some(g) = w.contact_constant {
            positive(&format!("{p}.contact_constant"), g)?;
        }
        positive(&format!("{p}.rail_crown_radius"), w.rail_crown_radius)?;
        // Wheels may start before x = 0 and end beyond L: off the structure they run on a
        // rigid track (docs/zones.md).
        finite(&format!("{p}.x_front"), w.x_front)?;
        Ok(())
    }
}

impl Serialize for VehicleConfig {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        let mut table = Map::new();
        table.insert("model".into(), self.model.kind().name().into());
        for value in [
            self.model.fields(),
            serde_json::to_value(&self.wheels).expect("wheels serialise"),
        ] {
            if let Value::Object(m) = value {
                table.extend(m);
            }
        }
        table.serialize(s)
    }
}

impl<'de> Deserialize<'de> for VehicleConfig {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let mut table = Map::<String, Value>::deserialize(d)?;
        let kind = match table.remove("model") {
            None => VehicleKind::Car,
            Some(Value::String(name)) => VehicleKind::of(&name).ok_or_else(|| {
                D::Error::custom(at(
                    "model",
                    format!("unknown model {name:?}, expected \"car\" or \"quarter_car\""),
                ))
            })?,
            Some(other) => {
                return Err(D::Error::custom(at(
                    "model",
                    format!("expected a model name, found {other}"),
                )));
            }
        };
        let wheels: Map<String, Value> = WHEEL_FIELDS
            .iter()
            .filter_map(|&f| table.remove(f).map(|v| (f.to_string(), v)))
            .collect();
        // What is left is the model's: its struct names any field that is not one of them.
        let model =
            VehicleModel::from_fields(kind, Value::Object(table)).map_err(D::Error::custom)?;
        let wheels = serde_path_to_error::deserialize(Value::Object(wheels))
            .map_err(|e| D::Error::custom(at(&e.path().to_string(), e.inner())))?;
        Ok(Self { model, wheels })
    }
}

impl JsonSchema for VehicleConfig {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "VehicleConfig".into()
    }

    /// One flat table per model, tagged by `model`: the model's fields and the wheels'.
    fn json_schema(g: &mut SchemaGenerator) -> Schema {
        let wheels = Wheels::json_schema(g);
        let variants: Vec<Value> = [
            (VehicleKind::Car, CarConfig::json_schema(g)),
            (VehicleKind::QuarterCar, QuarterCarConfig::json_schema(g)),
        ]
        .into_iter()
        .map(|(kind, own)| {
            let mut props = Map::new();
            let mut tag = serde_json::json!({
                "type": "string",
                "enum": [kind.name()],
                "description": "The vehicle model's name (docs/vehicles.md): `\"car\"` or `\"quarter_car\"`.",
            });
            if kind == VehicleKind::Car {
                tag["default"] = kind.name().into(); // a table without `model` is a car
            }
            props.insert("model".into(), tag);
            let mut required: Vec<Value> = Vec::new();
            for part in [&own, &wheels] {
                let part = part.as_value();
                if let Some(Value::Object(p)) = part.get("properties") {
                    props.extend(p.clone());
                }
                if let Some(Value::Array(r)) = part.get("required") {
                    required.extend(r.iter().cloned());
                }
            }
            serde_json::json!({
                "type": "object",
                "title": kind.name(),
                "properties": props,
                "required": required,
                "additionalProperties": false,
            })
        })
        .collect();
        Schema::try_from(serde_json::json!({
            "description": "A vehicle: one model's own parameters (`model`: \"car\", the default, \
                            or \"quarter_car\") and its wheels, as one flat table.",
            "oneOf": variants,
        }))
        .expect("an object schema")
    }
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema, PartialEq)]
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

impl MovingForceConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        finite(&format!("{p}.magnitude"), self.magnitude)?;
        // Off its layer a force loads nothing.
        finite(&format!("{p}.x0"), self.x0)?;
        Ok(())
    }
}
