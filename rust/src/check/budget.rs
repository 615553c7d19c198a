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
    let points = record.points(cfg).len() as f64;
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
    let field = if record.points(cfg).len() > 1 {
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

/// What building a synthesis reduction of a configuration will cost (docs/synthesis.md, "Before
/// a build"), estimated from the configuration alone: the structure's DOFs, the undamped modes
/// of the Ritz basis (a bound, `mode_count_bound` at `BASIS_RATIO`·f_c), the dashpot
/// attachment vectors, the kept complex modes (the bound at f_c), the peak memory (bytes) and
/// the time (s, one core) of its three stages: the undamped modes, the projected quadratic
/// eigenproblem and the rail residual.
#[derive(Clone, Debug, PartialEq)]
pub struct SynthesisBuild {
    pub dofs: f64,
    pub basis_modes: f64,
    pub attachments: f64,
    pub modes: f64,
    pub bytes: f64,
    pub stages: [f64; 3],
}

impl SynthesisBuild {
    /// The whole build's estimated time (s).
    pub fn seconds(&self) -> f64 {
        self.stages.iter().sum()
    }
}

use crate::model::resolution::{BASIS_RATIO, RESIDUAL_REACH};
/// Seconds per unit of the build's three costs, fitted to builds of one span and of one span
/// between 50 m embankments at 300 Hz on the 2-core machine (one BLAS thread; 2026-12-05 at
/// load 6, where the figures were 2–2.5 times these, and idle, about half of them): the
/// spectrum slicing and projections (n·q), the dense companion eigenproblem ((2q)³) and the
/// rail residual's solves (n·rail DOFs).
const SECONDS_PER_NQ: f64 = 2.5e-6;
const SECONDS_PER_EIG: f64 = 3.0e-9;
const SECONDS_PER_RESIDUAL: f64 = 1.5e-7;

/// The estimate of a synthesis build, `None` without `discretisation.synthesis_cutoff` or for
/// a structure that is not finite elements.
pub fn synthesis_build(cfg: &Config) -> Option<SynthesisBuild> {
    let fc = cfg.discretisation.synthesis_cutoff?;
    if cfg.discretisation.method != Method::Fem {
        return None;
    }
    let mut dofs = 0.0;
    let mut rail = 0.0;
    for (i, l) in cfg.structure.layers.iter().enumerate() {
        let (a, b) = cfg.extent(i);
        let h = l
            .element_length
            .unwrap_or(cfg.structure.length / cfg.discretisation.fem_elements as f64);
        let n = 2.0 * ((b - a) / h).ceil() + 2.0 * (1.0 + l.joints.len() as f64);
        if i == 0 {
            rail = n;
        }
        dofs += n;
    }
    let attachments: f64 = cfg
        .structure
        .couplings
        .iter()
        .filter(|c| c.kind == crate::config::CouplingKind::Discrete && c.damping > 0.0)
        .map(|c| c.positions.len() as f64)
        .sum();
    let bound = |f| crate::model::resolution::mode_count_bound(cfg, f).min(dofs);
    let basis_modes = bound(BASIS_RATIO * fc);
    let modes = bound(fc);
    let (n, q) = (dofs, basis_modes + attachments);
    // The Ritz basis and its modes (2·n·q), the attachments with their solve and QR (3·n·a),
    // the projected matrices and the companion problem with its complex eigenvectors and
    // LAPACK's work (160·q² bytes), ψ with its two products (3·n·m complex), six blocks of 512
    // rail solves, the core's copy of ψ, and the residual's three bands over the rail (twice:
    // built, and the core's copy).
    let band = (RESIDUAL_REACH * rail / cfg.structure.length).ceil() + 1.0;
    let bytes = F64 * (2.0 * n * q + 3.0 * n * attachments + 6.0 * 512.0 * n)
        + 160.0 * q * q
        + 16.0 * 4.0 * n * modes
        + F64 * 2.0 * 3.0 * rail * band;
    let stages = [
        SECONDS_PER_NQ * n * q,
        SECONDS_PER_EIG * (2.0 * q).powi(3),
        SECONDS_PER_RESIDUAL * n * rail,
    ];
    Some(SynthesisBuild {
        dofs,
        basis_modes,
        attachments,
        modes,
        bytes,
        stages,
    })
}

/// Refuses a synthesis build that would not fit `solver.memory_budget`, before it starts.
pub fn check_synthesis_build(cfg: &Config) -> Result<()> {
    let Some(b) = synthesis_build(cfg) else {
        return Ok(());
    };
    let budget = cfg.solver.memory_budget;
    if b.bytes <= budget {
        return Ok(());
    }
    Err(VtbError::config(
        "solver.memory_budget",
        budget,
        format!(
            "building the synthesis reduction of this structure would need about {:.3} GB \
             (about {:.0} DOFs × {:.0} basis modes and {:.0} dashpot attachments, {:.0} kept \
             modes; about {:.0} s), beyond the budget of {:.3} GB: raise solver.memory_budget if \
             the machine has the memory, or lower discretisation.synthesis_cutoff = {} Hz or the \
             structure's length",
            b.bytes / 1e9,
            b.dofs,
            b.basis_modes,
            b.attachments,
            b.modes,
            b.seconds(),
            budget / 1e9,
            cfg.discretisation.synthesis_cutoff.unwrap_or(0.0)
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::library::presets::paper as paper_config;

    /// The fast preset (160 m at 4 kHz) needs a few GB to build; sixty spans at 300 Hz need tens
    /// of GB and are refused by the default budget, naming it, before anything is built.
    #[test]
    fn a_synthesis_build_beyond_the_budget_is_refused_before_it_starts() {
        let fast = crate::library::presets::paper_fast();
        let b = synthesis_build(&fast).unwrap();
        assert!(b.bytes > 1e9 && b.bytes < 1e10, "{b:?}");
        assert!(synthesis_build(&paper_config()).is_none());
        let mut long = fast.clone();
        long.discretisation.synthesis_cutoff = Some(300.0);
        long.structure.length = 60.0 * 32.0;
        for c in &mut long.structure.couplings {
            if c.positions.len() > 1 {
                let d = c.positions[1] - c.positions[0];
                c.positions = (0..)
                    .map(|i| c.positions[0] + d * i as f64)
                    .take_while(|&x| x <= long.structure.length)
                    .collect();
            }
        }
        let b = synthesis_build(&long).unwrap();
        assert!(b.bytes > 2e10, "{b:?}");
        match check_synthesis_build(&long) {
            Err(VtbError::Config { field, reason, .. }) => {
                assert_eq!(field, "solver.memory_budget");
                assert!(
                    reason.contains("GB") && reason.contains("synthesis"),
                    "{reason}"
                );
            }
            other => panic!("expected a refusal, got {other:?}"),
        }
    }

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
