//! The track–bridge beam stack: layers, their Rayleigh damping, and the couplings between
//! layers or to the ground.

use super::fields::{non_negative, positive};
use crate::error::{Result, VtbError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Name used in coupling definitions for the fixed ground below the lowest layer.
pub const GROUND: &str = "ground";

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StructureConfig {
    /// Common length L of all layers (m); x runs from 0 to L.
    pub length: f64,
    /// Beam layers from top (the layer the wheels run on) to bottom.
    pub layers: Vec<LayerConfig>,
    /// Spring–dashpot connections between layers, or between a layer and the ground.
    #[serde(default)]
    pub couplings: Vec<CouplingConfig>,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LayerConfig {
    /// Name (no unit) by which couplings, dampers, outputs and metrics refer to the layer.
    pub name: String,
    /// Density ρ (kg/m³).
    pub density: f64,
    /// Cross-section area A (m²).
    pub area: f64,
    /// Young's modulus E (Pa).
    pub youngs_modulus: f64,
    /// Second moment of area I (m⁴).
    pub inertia: f64,
    /// Number of sine modes (count) of the modal/hybrid basis (the 4 Hermite DOFs come on top).
    pub modes: usize,
    /// Extra sine modes (count) treated as local (FE–SEA) modes by the hybrid method.
    #[serde(default)]
    pub local_modes: usize,
    /// Shear modulus G (Pa). Given with `shear_coefficient`, the layer is a Timoshenko beam
    /// (shear deformation and rotary inertia ρI); finite-element method only.
    #[serde(default)]
    pub shear_modulus: Option<f64>,
    /// Shear coefficient κ (−) of the cross-section (a rail in vertical bending: ≈ 0.4).
    #[serde(default)]
    pub shear_coefficient: Option<f64>,
    /// Longest element (m) of this layer's finite-element mesh, whose nodes then fall on every
    /// discrete coupling point of the layer (fasteners, piers, damper attachments). `None`:
    /// the uniform mesh of `discretisation.fem_elements` elements.
    #[serde(default)]
    pub element_length: Option<f64>,
    /// Rayleigh damping of the layer: a ratio (−) at two frequencies (Hz), or α (1/s) and β (s).
    pub damping: RayleighConfig,
    /// Where the layer begins (m); 0 when absent. A layer over part of the structure (a
    /// bridge girder between approach embankments) needs finite elements; its ends are free
    /// unless couplings hold them.
    #[serde(default)]
    pub start: Option<f64>,
    /// Where the layer ends (m); `structure.length` when absent.
    #[serde(default)]
    pub end: Option<f64>,
    /// Positions (m) where the layer is cut: a joint between simply supported spans or slabs,
    /// across which no displacement, rotation, shear or moment passes (only the couplings on
    /// either side hold the two ends). Finite elements only; a point exactly at a joint
    /// belongs to the part on its right.
    #[serde(default)]
    pub joints: Vec<f64>,
}

/// Rayleigh damping C = αM + βK of one layer.
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RayleighConfig {
    /// Damping ratio `ratio` at the two frequencies `f1` < `f2` (Hz).
    Ratio { ratio: f64, f1: f64, f2: f64 },
    /// Explicit coefficients α (1/s) and β (s).
    Coefficients { alpha: f64, beta: f64 },
}

impl RayleighConfig {
    /// (α, β) of the layer.
    pub fn coefficients(&self) -> (f64, f64) {
        match *self {
            RayleighConfig::Coefficients { alpha, beta } => (alpha, beta),
            RayleighConfig::Ratio { ratio, f1, f2 } => {
                let (w1, w2) = (
                    2.0 * std::f64::consts::PI * f1,
                    2.0 * std::f64::consts::PI * f2,
                );
                (2.0 * ratio * w1 * w2 / (w1 + w2), 2.0 * ratio / (w1 + w2))
            }
        }
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum CouplingKind {
    /// Point springs at `positions` (stiffness N/m, damping N·s/m per point).
    Discrete,
    /// Distributed over the whole length (stiffness N/m², damping N·s/m² per unit length).
    Continuous,
}

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct CouplingConfig {
    /// The upper layer's name (no unit).
    pub upper: String,
    /// The lower layer's name, or `"ground"` (no unit).
    pub lower: String,
    /// `"discrete"` (point springs at `positions`) or `"continuous"` (along the whole length).
    pub kind: CouplingKind,
    /// Stiffness (N/m per point if discrete, N/m² per unit length if continuous).
    pub stiffness: f64,
    /// Viscous damping (N·s/m per point if discrete, N·s/m² per unit length if continuous).
    #[serde(default)]
    pub damping: f64,
    /// Point positions for discrete couplings (m).
    #[serde(default)]
    pub positions: Vec<f64>,
    /// Where a continuous coupling begins (m); the start of the part both layers cover (of the
    /// upper layer, for the ground) when absent. Finite-element layers only.
    #[serde(default)]
    pub start: Option<f64>,
    /// Where a continuous coupling ends (m); the end of the part both layers cover when absent.
    #[serde(default)]
    pub end: Option<f64>,
}

impl RayleighConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        match *self {
            RayleighConfig::Ratio { ratio, f1, f2 } => {
                let r = non_negative(&format!("{p}.ratio"), ratio)?;
                if r >= 1.0 {
                    return Err(VtbError::config(format!("{p}.ratio"), r, "must be < 1"));
                }
                positive(&format!("{p}.f1"), f1)?;
                positive(&format!("{p}.f2"), f2)?;
                if f2 <= f1 {
                    return Err(VtbError::config(
                        format!("{p}.f2"),
                        f2,
                        format!("must be > f1 = {f1}"),
                    ));
                }
            }
            RayleighConfig::Coefficients { alpha, beta } => {
                non_negative(&format!("{p}.alpha"), alpha)?;
                non_negative(&format!("{p}.beta"), beta)?;
            }
        }
        Ok(())
    }
}

impl LayerConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        if self.name.is_empty() || self.name == GROUND {
            return Err(VtbError::config(
                format!("{p}.name"),
                format!("{:?}", self.name),
                "must be a non-empty name other than \"ground\"",
            ));
        }
        positive(&format!("{p}.density"), self.density)?;
        positive(&format!("{p}.area"), self.area)?;
        positive(&format!("{p}.youngs_modulus"), self.youngs_modulus)?;
        positive(&format!("{p}.inertia"), self.inertia)?;
        self.damping.validate(&format!("{p}.damping"))
    }
}

impl CouplingConfig {
    pub fn validate(&self, p: &str) -> Result<()> {
        non_negative(&format!("{p}.stiffness"), self.stiffness)?;
        non_negative(&format!("{p}.damping"), self.damping)?;
        match self.kind {
            CouplingKind::Discrete => {
                if self.positions.is_empty() {
                    return Err(VtbError::config(
                        format!("{p}.positions"),
                        "[]",
                        "a discrete coupling needs at least one position",
                    ));
                }
                for (name, v) in [("start", self.start), ("end", self.end)] {
                    if let Some(v) = v {
                        return Err(VtbError::config(
                            format!("{p}.{name}"),
                            v,
                            "a discrete coupling acts at its positions; start and end are for continuous ones",
                        ));
                    }
                }
            }
            CouplingKind::Continuous => {
                if !self.positions.is_empty() {
                    return Err(VtbError::config(
                        format!("{p}.positions"),
                        format!("{:?}", self.positions),
                        "a continuous coupling takes no positions",
                    ));
                }
            }
        }
        Ok(())
    }
}
