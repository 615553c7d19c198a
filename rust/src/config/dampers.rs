//! Damper groups: identical dampers of one kind between two layers (or a layer and the
//! ground), at explicit positions or on a pattern.

use super::GROUND;
use super::fields::{MAX_TIDS, finite, non_negative, positive, within};
use crate::error::{Result, VtbError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Which element sits in which branch of a damper (docs/dampers.md; the branches of each
/// kind are `DamperParams::branches`, crate::model::dampers).
#[derive(Debug, Clone, Copy, Serialize, Deserialize, JsonSchema, PartialEq, Eq, Default, Hash)]
#[serde(rename_all = "lowercase")]
pub enum DamperKind {
    /// Tuned inerter damper: spring ∥ dashpot from the upper layer to the node, inerter from
    /// the node to the lower layer (or the ground).
    #[default]
    Tid,
    /// Tuned viscous mass damper: spring from the upper layer to the node, inerter ∥ dashpot
    /// from the node to the lower layer (or the ground).
    Tvmd,
    /// Tuned mass damper: a mass (`inertance`) hung from the upper layer by spring ∥ dashpot;
    /// `lower` must be `"ground"`.
    Tmd,
}

impl DamperKind {
    /// The kind's name in configurations.
    pub fn name(self) -> &'static str {
        match self {
            Self::Tid => "tid",
            Self::Tvmd => "tvmd",
            Self::Tmd => "tmd",
        }
    }

    /// Whether the kind needs `lower = "ground"`.
    pub fn grounded(self) -> bool {
        matches!(self, Self::Tmd)
    }
}

/// The parameters of one damper: what may differ between the lanes of a batch.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DamperParams {
    pub kind: DamperKind,
    pub stiffness: f64,
    pub damping: f64,
    pub inertance: f64,
}

/// A group of identical dampers of one kind between `upper` and `lower` (docs/dampers.md), at
/// `positions` or at x0 + i·spacing, i < count.
#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DamperGroup {
    /// A name (no unit) by which field paths and studies address the group instead of its
    /// index (`tids.stiffness` for the group named `tids`); unique among the groups.
    #[serde(default)]
    pub name: Option<String>,
    /// `"tid"` (spring ∥ dashpot, then inerter), `"tvmd"` (spring, then inerter ∥ dashpot)
    /// or `"tmd"` (a mass `inertance` on spring ∥ dashpot; `lower` must be `"ground"`).
    #[serde(default)]
    pub kind: DamperKind,
    /// Inertance b (kg) of each damper (a TMD's mass), from its internal node to the lower layer.
    pub inertance: f64,
    /// Spring stiffness k (N/m) of each damper, from the upper layer to its internal node.
    pub stiffness: f64,
    /// Dashpot damping c (N·s/m) of each damper: parallel to the spring (TID, TMD) or to the
    /// inerter (TVMD).
    pub damping: f64,
    /// Number of dampers (count) of the pattern x0 + i·spacing; omitted with `positions`.
    #[serde(default)]
    pub count: Option<usize>,
    /// Position of the pattern's first damper (m).
    #[serde(default)]
    pub x0: Option<f64>,
    /// Distance between neighbouring dampers of the pattern (m); needed when count > 1.
    #[serde(default)]
    pub spacing: Option<f64>,
    /// Explicit positions of the dampers (m), instead of the pattern.
    #[serde(default)]
    pub positions: Option<Vec<f64>>,
    /// The layer the springs attach to (name, no unit).
    #[serde(default = "default_tid_upper")]
    pub upper: String,
    /// The layer the inerters attach to (name, no unit), or `"ground"`: an inerter to the
    /// fixed ground is a mass b on the internal node (a TID to the ground is a TMD).
    #[serde(default = "default_tid_lower")]
    pub lower: String,
}

impl DamperGroup {
    /// The group's field path: its name, or `dampers[i]` (`i` its index).
    pub fn path(&self, i: usize) -> String {
        self.name.clone().unwrap_or_else(|| format!("dampers[{i}]"))
    }

    /// The dampers' positions (m), from `positions` or the pattern (validated configs).
    pub fn locations(&self) -> Vec<f64> {
        match &self.positions {
            Some(p) => p.clone(),
            None => {
                let (x0, h) = (self.x0.unwrap_or(0.0), self.spacing.unwrap_or(0.0));
                (0..self.count.unwrap_or(0))
                    .map(|i| x0 + i as f64 * h)
                    .collect()
            }
        }
    }

    /// The parameters of each of its dampers.
    pub fn params(&self) -> DamperParams {
        DamperParams {
            kind: self.kind,
            stiffness: self.stiffness,
            damping: self.damping,
            inertance: self.inertance,
        }
    }
}

fn default_tid_upper() -> String {
    "rail".into()
}
fn default_tid_lower() -> String {
    "slab".into()
}

impl DamperGroup {
    /// Parameters, kind and positions (on [0, length]; layers are checked by the config).
    pub fn validate(&self, path: &str, length: f64) -> Result<()> {
        let at = |f: &str| format!("{path}.{f}");
        positive(&at("inertance"), self.inertance)?;
        // Without a spring the internal node has no static position (the inerter carries no
        // static force): k → 0 is a limit, not a value.
        positive(&at("stiffness"), self.stiffness)?;
        non_negative(&at("damping"), self.damping)?;
        if self.kind.grounded() && self.lower != GROUND {
            return Err(VtbError::config(
                at("lower"),
                format!("{:?}", self.lower),
                format!(
                    "a {} hangs from one layer: lower must be \"ground\"",
                    self.kind.name()
                ),
            ));
        }
        match (&self.positions, self.count, self.x0, self.spacing) {
            (Some(p), None, None, None) => {
                if p.is_empty() {
                    return Err(VtbError::config(
                        at("positions"),
                        "[]",
                        "must hold at least one position (omit the group for no dampers)",
                    ));
                }
                if p.len() > MAX_TIDS {
                    return Err(VtbError::config(
                        at("positions"),
                        p.len(),
                        format!("must hold at most {MAX_TIDS} positions"),
                    ));
                }
                for (i, &x) in p.iter().enumerate() {
                    within(
                        &format!("{path}.positions[{i}]"),
                        x,
                        0.0,
                        length,
                        "the structure",
                    )?;
                }
                Ok(())
            }
            (None, Some(count), Some(x0), spacing) => {
                if count == 0 {
                    return Err(VtbError::config(
                        at("count"),
                        0,
                        "must be >= 1 (omit the group for no dampers)",
                    ));
                }
                if count > MAX_TIDS {
                    return Err(VtbError::config(
                        at("count"),
                        count,
                        format!(
                            "must be <= {MAX_TIDS}: the dampers' coupling is a dense count × count \
                             matrix inverted once per run and applied every step"
                        ),
                    ));
                }
                within(&at("x0"), x0, 0.0, length, "the structure")?;
                if count > 1 {
                    let h = spacing.ok_or_else(|| {
                        VtbError::config(at("spacing"), "None", "is needed when count > 1")
                    })?;
                    positive(&at("spacing"), h)?;
                    let last = x0 + h * (count - 1) as f64;
                    if last > length + 1e-9 {
                        return Err(VtbError::config(
                            at("count"),
                            count,
                            format!(
                                "the last damper would sit at x = {last:.4} m, beyond the structure length {length}"
                            ),
                        ));
                    }
                } else if let Some(h) = spacing {
                    finite(&at("spacing"), h)?;
                }
                Ok(())
            }
            (Some(_), ..) => Err(VtbError::config(
                at("positions"),
                "given",
                "give either positions or the pattern count, x0, spacing, not both",
            )),
            (None, None, ..) => Err(VtbError::config(
                at("count"),
                "None",
                "give the pattern count, x0 (and spacing), or positions",
            )),
            (None, Some(_), None, _) => {
                Err(VtbError::config(at("x0"), "None", "is needed with count"))
            }
        }
    }
}
