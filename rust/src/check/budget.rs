//! The memory budget of a run: what a configuration will allocate, estimated from the
//! configuration alone before anything is built, so that a run too large for the machine is
//! refused with its size instead of aborting on a failed allocation (docs/limits.md).
//!
//! The estimates are upper bounds of the large allocations (matrices, dampers, histories);
//! small fixed costs are left out. The budget is `solver.memory_budget` (bytes).

use crate::config::{Config, Method};
use crate::error::{Result, VtbError};
use crate::outputs::Record;

const F64: f64 = 8.0;
/// Copies of the stepping matrices alive at once (M, C, K, their Newmark combination, its
/// factor and the condensed base), each bounded by the estimated nonzero count.
const MATRIX_COPIES: f64 = 6.0;
/// Bandwidth bound of a finite-element layer's rows (nodes couple to their neighbours and to
/// the nodes of the coupled layers).
const FEM_ROW: f64 = 48.0;

/// Estimated bytes of the structure and damper matrices of a configuration.
pub fn model_bytes(cfg: &Config) -> f64 {
    let length = cfg.structure.length;
    let mut modal = 0.0;
    let mut fem = 0.0;
    for l in &cfg.structure.layers {
        match cfg.discretisation.method {
            Method::Fem => {
                let elements = match l.element_length {
                    Some(h) => (length / h)
                        .ceil()
                        .max(cfg.discretisation.fem_elements as f64),
                    None => cfg.discretisation.fem_elements as f64,
                };
                fem += 2.0 * (elements + 1.0);
            }
            _ => modal += (4 + l.modes) as f64 + l.local_modes as f64,
        }
    }
    let n = modal + fem;
    let matrices = MATRIX_COPIES * (modal * modal + fem * FEM_ROW) * F64;
    let m = cfg.damper_params().len() as f64;
    // Y = A₀⁻¹W (n × m), WᵀY and the lanes' m × m damper matrices.
    let dampers = (n * m + (2.0 + crate::config::fields::MAX_LANES as f64) * m * m) * F64;
    matrices + dampers
}

/// Estimated bytes of the histories one job records.
pub fn history_bytes(cfg: &Config, record: Record) -> f64 {
    let steps = cfg.n_steps() as f64 + 1.0;
    let layers = record.layers(cfg).len() as f64;
    let points = match record {
        Record::Full => cfg.observation_points().len() as f64,
        Record::Metrics => 1.0,
    };
    let cars = cfg.vehicles.len() as f64;
    let vehicle = match record {
        Record::Full => cars * 10.0,
        Record::Metrics => cars.min(1.0),
    };
    let wheels = 4.0 * cars;
    // An observer's displacement and acceleration; a synthesis run also keeps its four
    // readouts and the rail residual per step until the records are made (synthesis::run).
    let per_observer = if cfg.discretisation.synthesis_cutoff.is_some() {
        7.0
    } else {
        2.0
    };
    // A pad's force, and on the synthesis its two ends' readouts and residuals.
    let pads = crate::outputs::catalog::pads_of(cfg).len() as f64;
    let per_pad = if cfg.discretisation.synthesis_cutoff.is_some() {
        11.0
    } else {
        1.0
    };
    steps * (per_observer * layers * points + 2.0 * vehicle + wheels + per_pad * pads) * F64
}

fn refuse(
    what: &str,
    field: &str,
    value: impl std::fmt::Display,
    bytes: f64,
    budget: f64,
) -> VtbError {
    VtbError::config(
        field,
        value,
        format!(
            "{what} would need about {:.3} GB, beyond solver.memory_budget = {:.3} GB (raise the \
             budget if the machine has the memory)",
            bytes / 1e9,
            budget / 1e9
        ),
    )
}

/// Refuses a configuration whose matrices do not fit the budget, naming the field that
/// drives their size.
pub fn check_model(cfg: &Config) -> Result<()> {
    let budget = cfg.solver.memory_budget;
    let bytes = model_bytes(cfg);
    if bytes <= budget {
        return Ok(());
    }
    let largest = cfg
        .damper_groups()
        .into_iter()
        .map(|(path, g)| (path, g.locations().len()))
        .max_by_key(|&(_, n)| n);
    let (field, value) = if let Some((path, n)) = largest.filter(|&(_, n)| n > 100) {
        (format!("{path}.count"), n.to_string())
    } else if cfg.discretisation.method == Method::Fem {
        (
            "discretisation.fem_elements".into(),
            cfg.discretisation.fem_elements.to_string(),
        )
    } else {
        let (i, l) = cfg
            .structure
            .layers
            .iter()
            .enumerate()
            .max_by_key(|(_, l)| l.modes + l.local_modes)
            .expect("validated: at least one layer");
        (
            format!("structure.layers[{i}].modes"),
            (l.modes + l.local_modes).to_string(),
        )
    };
    Err(refuse("the model's matrices", &field, value, bytes, budget))
}

/// Refuses `lanes` jobs whose recorded histories do not fit the budget beside the model.
pub fn check_histories(cfg: &Config, record: Record, lanes: usize) -> Result<()> {
    let budget = cfg.solver.memory_budget;
    let bytes = model_bytes(cfg) + lanes as f64 * history_bytes(cfg, record);
    if bytes <= budget {
        return Ok(());
    }
    let field = if record == Record::Full && cfg.output.points.len() > 1 {
        "output.points"
    } else {
        "solver.t_end"
    };
    Err(refuse(
        &format!("{} steps of histories", cfg.n_steps()),
        field,
        format!("{:?}", cfg.t_end()),
        bytes,
        budget,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::presets::paper as paper_config;

    /// A huge damper count, mode count or recorded length is refused with the field that
    /// drives it and the estimated size; the article case fits the default budget easily.
    #[test]
    fn oversized_runs_are_refused_with_their_size() {
        let cfg = paper_config();
        assert!(model_bytes(&cfg) + history_bytes(&cfg, Record::Full) < 0.1e9);
        check_model(&cfg).unwrap();

        let mut big = cfg.clone();
        big.structure.layers[1].modes = 20_000;
        match check_model(&big) {
            Err(VtbError::Config { field, reason, .. }) => {
                assert_eq!(field, "structure.layers[1].modes");
                assert!(reason.contains("GB"), "{reason}");
            }
            other => panic!("expected a refusal, got {other:?}"),
        }

        let mut long = cfg.clone();
        long.solver.memory_budget = 1e6;
        match check_histories(&long, Record::Full, 1) {
            Err(VtbError::Config { field, .. }) => {
                assert!(field == "solver.t_end" || field == "output.points")
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
    }
}
