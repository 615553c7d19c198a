//! Run configuration: the serde schema shared with the Python layer (which serialises its
//! dataclasses to this JSON shape), each part's checks of its own fields, and the quantities a
//! configuration determines by itself (its end time, the wheels' travel, the dampers). A leaf:
//! it imports nothing of the model; `crate::check` judges a configuration as a whole.
//!
//! Units are SI throughout (m, s, kg, N, Pa). Displacements are positive downward.

mod dampers;
mod discretisation;
pub mod fields;
mod output;
mod profile;
mod solver;
mod structure;
mod vehicle;

pub use dampers::{DamperGroup, DamperKind, DamperParams};
pub use discretisation::{DiscretisationConfig, FeSeaCoupling, Method};
pub use output::OutputConfig;
pub use profile::Profile;
pub use solver::{InitialState, SolverConfig};
pub use structure::{
    CouplingConfig, CouplingKind, GROUND, LayerConfig, RayleighConfig, StructureConfig,
};
pub(crate) use vehicle::default_rail_crown_radius;
pub use vehicle::{
    CarConfig, MovingForceConfig, QuarterCarConfig, VehicleConfig, VehicleKind, VehicleModel,
    Wheels,
};

use crate::error::{Result, VtbError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

#[derive(Debug, Clone, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Config {
    /// The track–bridge beam stack: its length, layers and couplings.
    pub structure: StructureConfig,
    /// How the layers are discretised (modal, hybrid FE–SEA or finite elements).
    #[serde(default)]
    pub discretisation: DiscretisationConfig,
    /// Cars of the train, all running at `speed`. Empty for the moving-load mode.
    #[serde(default)]
    pub vehicles: Vec<VehicleConfig>,
    /// Constant moving forces (moving-load mode, bridge checks); may be combined with vehicles.
    #[serde(default)]
    pub forces: Vec<MovingForceConfig>,
    /// Speed of all vehicles and forces (m/s), in the +x direction.
    pub speed: f64,
    /// Time integration, contact iteration, start and end of the run.
    #[serde(default)]
    pub solver: SolverConfig,
    /// Observation points and the metrics' analysis window.
    #[serde(default)]
    pub output: OutputConfig,
    /// The damper groups, each of its own kind, tuning and positions (none by default); their
    /// internal nodes follow in this order. A named group is addressed by its name (the
    /// article's tuned inerter dampers are the group `tids`: `tids.stiffness`); a table's
    /// legacy key `tids` loads as that group, first.
    #[serde(default)]
    pub dampers: Vec<DamperGroup>,
    /// Field paths (e.g. `"speed"`, `"structure.couplings[3].stiffness"`) whose values may lie
    /// outside their plausible range (docs/limits.md, `vtb.plausible_ranges()`); any other
    /// such value is refused as a likely unit mistake.
    #[serde(default)]
    pub accept_implausible: Vec<String>,
}

impl Config {
    /// Parses the JSON form; a field of the wrong type or range is reported with its dotted
    /// path (`tids.count`, `structure.layers[0].modes`) and the value found there.
    pub fn from_json(text: &str) -> Result<Config> {
        let mut tree: serde_json::Value = serde_json::from_str(text)
            .map_err(|e| VtbError::config("<json>", "(text)", e.to_string()))?;
        legacy_tids(&mut tree);
        serde_path_to_error::deserialize(&tree).map_err(|e| {
            let mut reason = e.inner().to_string();
            let mut path = e.path().to_string();
            let join = |path: &str, name: &str| {
                if path == "." {
                    name.to_string()
                } else {
                    format!("{path}.{name}")
                }
            };
            // A table read by hand (a vehicle) names the field inside it: `at `f`: …`.
            if let Some((inner, rest)) = reason
                .strip_prefix("at `")
                .and_then(|r| r.split_once("`: "))
            {
                (path, reason) = (join(&path, inner), rest.to_string());
            }
            // An unknown field is reported at its parent: name the field itself.
            if let Some(name) = reason
                .strip_prefix("unknown field `")
                .and_then(|r| r.split('`').next())
                .filter(|name| !path.ends_with(&format!(".{name}")))
            {
                path = join(&path, name);
            }
            let value =
                value_at(&tree, &path).map_or_else(|| "(missing)".to_string(), |v| v.to_string());
            let path = named_group_path(&tree, path);
            let field = if path == "." {
                "<config>".to_string()
            } else {
                path
            };
            VtbError::config(field, value, reason)
        })
    }

    /// The JSON schema of the configuration (fields, types, defaults, documentation): the
    /// one definition the Python layer derives its defaults from and is tested against.
    pub fn schema() -> String {
        serde_json::to_string(&schemars::schema_for!(Config)).expect("schema serialises")
    }

    pub fn to_json(&self) -> String {
        serde_json::to_string(self).expect("config serialises")
    }

    pub fn layer_index(&self, name: &str) -> Option<usize> {
        self.structure.layers.iter().position(|l| l.name == name)
    }

    /// Number of time steps and the step actually used (the end time is rounded to a whole
    /// number of steps).
    pub fn n_steps(&self) -> usize {
        let t_end = self.t_end();
        (t_end / self.solver.dt).round().max(1.0) as usize
    }

    /// End time of the run (s), where its last step lands: explicit (validated to be a whole
    /// number of steps), or the whole step nearest to the leading wheel/force reaching
    /// L − end_margin.
    pub fn t_end(&self) -> f64 {
        if let Some(t) = self.solver.t_end {
            return t;
        }
        let dt = self.solver.dt;
        let t = self.lead_time();
        if dt > 0.0 && t.is_finite() {
            (t / dt).round() * dt
        } else {
            t
        }
    }

    /// Time (s) at which the leading wheel/force reaches L − end_margin, or with
    /// `solver.tail` the last one has passed L plus the tail.
    fn lead_time(&self) -> f64 {
        let positions = || {
            self.vehicles
                .iter()
                .flat_map(|v| v.wheel_offsets())
                .chain(self.forces.iter().map(|f| f.x0))
        };
        let (lead, last) = (
            positions().fold(f64::NEG_INFINITY, f64::max),
            positions().fold(f64::INFINITY, f64::min),
        );
        if !(self.speed > 0.0 && lead.is_finite()) {
            return 0.0;
        }
        let l = self.structure.length;
        match self.solver.tail {
            Some(tail) => ((l - last) / self.speed).max(0.0) + tail,
            None => ((l - self.solver.end_margin - lead) / self.speed).max(0.0),
        }
    }

    /// The share of the irregularity under the wheels at time `t` (s): a raised cosine in the
    /// distance travelled, v·t, over `solver.fade_in`. A stationary run (speed 0) has nothing
    /// moving under its wheels and takes the profile in full from its static state.
    pub fn irregularity_share(&self, t: f64) -> f64 {
        let s = self.speed * t;
        if self.speed == 0.0 || s >= self.solver.fade_in {
            1.0
        } else {
            0.5 * (1.0 - (std::f64::consts::PI * s / self.solver.fade_in).cos())
        }
    }

    /// The stretch (m) the wheels roll over during the run, from the rearmost wheel's start
    /// to the leading wheel's end; `None` without vehicles or with a non-finite end time.
    pub fn wheel_travel(&self) -> Option<(f64, f64)> {
        let travel = self.speed * self.n_steps() as f64 * self.solver.dt;
        let offsets = self.vehicles.iter().flat_map(|v| v.wheel_offsets());
        let lo = offsets.clone().fold(f64::INFINITY, f64::min);
        let hi = offsets.fold(f64::NEG_INFINITY, f64::max) + travel;
        (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
    }

    /// [start, end] of layer `i` (m).
    pub fn extent(&self, i: usize) -> (f64, f64) {
        let l = &self.structure.layers[i];
        (
            l.start.unwrap_or(0.0),
            l.end.unwrap_or(self.structure.length),
        )
    }

    /// [start, end] (m) over which a continuous coupling of validated layers acts.
    pub fn coupling_range(&self, c: &CouplingConfig) -> (f64, f64) {
        let (a0, a1) = self.extent(self.layer_index(&c.upper).expect("validated"));
        let (b0, b1) = self
            .layer_index(&c.lower)
            .map_or((a0, a1), |l| self.extent(l));
        (c.start.unwrap_or(a0.max(b0)), c.end.unwrap_or(a1.min(b1)))
    }

    /// Observation points, defaulting to mid-length.
    pub fn observation_points(&self) -> Vec<f64> {
        if self.output.points.is_empty() {
            vec![0.5 * self.structure.length]
        } else {
            self.output.points.clone()
        }
    }

    /// The damper groups with their field paths: a named group's name, else `dampers[i]`.
    pub fn damper_groups(&self) -> Vec<(String, &DamperGroup)> {
        self.dampers
            .iter()
            .enumerate()
            .map(|(i, g)| (g.path(i), g))
            .collect()
    }

    /// The damper group named `name`, if there is one.
    pub fn damper_group(&self, name: &str) -> Option<&DamperGroup> {
        self.dampers
            .iter()
            .find(|g| g.name.as_deref() == Some(name))
    }

    /// Every damper of every group, in node order.
    pub fn damper_params(&self) -> Vec<DamperParams> {
        self.damper_groups()
            .into_iter()
            .flat_map(|(_, g)| vec![g.params(); g.locations().len()])
            .collect()
    }
}

/// The legacy key `tids` (one damper group beside `dampers`) as the first damper group,
/// named `tids`.
fn legacy_tids(tree: &mut serde_json::Value) {
    let Some(root) = tree.as_object_mut() else {
        return;
    };
    let Some(tids) = root.remove("tids") else {
        return;
    };
    if tids.is_null() {
        return;
    }
    let mut group = tids;
    if let Some(g) = group.as_object_mut() {
        g.entry("name").or_insert_with(|| "tids".into());
    }
    match root.get_mut("dampers") {
        Some(serde_json::Value::Array(list)) => list.insert(0, group),
        _ => {
            root.insert("dampers".into(), serde_json::Value::Array(vec![group]));
        }
    }
}

/// A path into `dampers[i]` of a named group by the group's name (`dampers[0].count` →
/// `tids.count`), as the checks name it.
fn named_group_path(tree: &serde_json::Value, path: String) -> String {
    let Some(rest) = path.strip_prefix("dampers[") else {
        return path;
    };
    let Some((i, tail)) = rest.split_once(']') else {
        return path;
    };
    let name = i
        .parse::<usize>()
        .ok()
        .and_then(|i| tree.get("dampers")?.get(i)?.get("name")?.as_str());
    match name {
        Some(name) => format!("{name}{tail}"),
        None => path,
    }
}

/// The value at a dotted path (`a.b[2].c`) of a JSON tree.
fn value_at<'v>(tree: &'v serde_json::Value, path: &str) -> Option<&'v serde_json::Value> {
    let mut v = tree;
    for part in path.split('.').filter(|p| !p.is_empty()) {
        let (name, indices) = part.split_once('[').map_or((part, ""), |(n, r)| (n, r));
        if !name.is_empty() {
            v = v.get(name)?;
        }
        for idx in indices.split('[').filter(|s| !s.is_empty()) {
            v = v.get(idx.trim_end_matches(']').parse::<usize>().ok()?)?;
        }
    }
    Some(v)
}

#[cfg(test)]
mod tests {

    #[test]
    fn irregularity_share_is_a_smooth_ramp_over_the_fade_distance() {
        let mut cfg = crate::library::presets::paper();
        cfg.speed = 80.0;
        cfg.solver.fade_in = 2.0;
        let t_full = 2.0 / 80.0;
        assert_eq!(cfg.irregularity_share(0.0), 0.0);
        assert!((cfg.irregularity_share(t_full / 2.0) - 0.5).abs() < 1e-15);
        assert_eq!(cfg.irregularity_share(t_full), 1.0);
        assert_eq!(cfg.irregularity_share(1.0), 1.0);
        // C¹: the slope vanishes at both ends of the ramp
        let h = 1e-7 * t_full;
        assert!(cfg.irregularity_share(h) < 1e-12);
        assert!(1.0 - cfg.irregularity_share(t_full - h) < 1e-12);
        cfg.solver.fade_in = 0.0;
        assert_eq!(cfg.irregularity_share(0.0), 1.0);
        cfg.solver.fade_in = 2.0;
        cfg.speed = 0.0;
        assert_eq!(cfg.irregularity_share(0.0), 1.0);
    }
}
