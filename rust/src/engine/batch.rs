//! The engines' entrance: one configuration, or many jobs grouped by the model they share
//! and run in lockstep groups on the engine each asks for (Newmark, or the synthesis on a
//! reduction).

use super::newmark::Simulation;
use super::synthesis::{self, Reduction};
use super::{Control, DEFAULT_LANES, Job, LaneSpec, MAX_LANES};
use crate::check;
use crate::config::{Config, Profile};
use crate::error::{Result, VtbError};
use crate::model::Model;
use crate::model::structure::Structure;
use crate::model::substructures::Substructured;
use crate::outputs::{Record, RunResult};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, OnceLock};

/// Validates, assembles and integrates one configuration.
pub fn simulate(cfg: &Config, profile: &Profile, cancel: Option<&Control>) -> Result<RunResult> {
    simulate_with(cfg, profile, None, cancel)
}

/// What a configuration's structure is reduced to before it runs, built once (by the Python
/// layer) and shared by every job on it.
#[derive(Clone, Copy, Debug)]
pub enum Reduced<'r> {
    /// Complex modes and the rail's residual (`discretisation.synthesis_cutoff`): the
    /// synthesis engine.
    Modes(&'r Reduction),
    /// Substructured coordinates (`discretisation.substructure_cutoff`): the Newmark engine
    /// on them.
    Substructures(&'r Arc<Substructured>),
}

/// `simulate` with the structure's reduction, which a configuration with
/// `discretisation.synthesis_cutoff` or `substructure_cutoff` needs.
pub fn simulate_with(
    cfg: &Config,
    profile: &Profile,
    reduced: Option<Reduced>,
    cancel: Option<&Control>,
) -> Result<RunResult> {
    let model = check::validated(cfg.clone(), profile.clone())?;
    match engine(cfg, reduced)? {
        Some(Reduced::Modes(red)) => synthesis::run(
            &model,
            &LaneSpec::of(cfg, profile),
            red,
            Record::Full,
            cancel,
        ),
        Some(Reduced::Substructures(sub)) => {
            let structure = model.structure.substructured(Arc::clone(sub))?;
            let model = Model::with_structure(model.cfg, model.profile, structure);
            Simulation::new(&model)?.run(cancel)
        }
        None => Simulation::new(&model)?.run(cancel),
    }
}

/// The reduction a configuration runs on (`None`: the Newmark engine on its own structure); a
/// cut-off without its reduction, or a reduction the configuration does not ask for, is
/// refused.
fn engine<'r>(cfg: &Config, reduced: Option<Reduced<'r>>) -> Result<Option<Reduced<'r>>> {
    let d = &cfg.discretisation;
    match (reduced, d.synthesis_cutoff, d.substructure_cutoff) {
        (None, None, None) => Ok(None),
        (Some(r @ Reduced::Modes(_)), Some(_), _)
        | (Some(r @ Reduced::Substructures(_)), None, Some(_)) => Ok(Some(r)),
        (None, Some(fc), _) => Err(VtbError::config(
            "discretisation.synthesis_cutoff",
            fc,
            "the synthesis needs the structure's reduction (vtb.synthesis.reduction(config))",
        )),
        (None, None, Some(fc)) => Err(VtbError::config(
            "discretisation.substructure_cutoff",
            fc,
            "the substructured engine needs the structure's substructures \
             (vtb.run.substructures.reduction(config))",
        )),
        (Some(r), ..) => Err(VtbError::config(
            match r {
                Reduced::Modes(_) => "discretisation.synthesis_cutoff",
                Reduced::Substructures(_) => "discretisation.substructure_cutoff",
            },
            "None",
            "a reduction was given for a configuration that does not ask for it",
        )),
    }
}

/// Jobs that may share one model: configurations equal up to the dampers' parameters.
pub fn model_key(cfg: &Config) -> String {
    let mut c = cfg.clone();
    for t in c.dampers.iter_mut() {
        (t.inertance, t.stiffness, t.damping) = (0.0, 0.0, 0.0);
    }
    serde_json::to_string(&c).expect("a config serialises")
}

/// Lockstep widths for `n` jobs of one model on `threads` threads: powers of two up to
/// `max_lanes`, as wide as possible while every thread gets a group.
fn lane_widths(n: usize, threads: usize, max_lanes: usize) -> Vec<usize> {
    let pow2_floor = |k: usize| 1usize << (usize::BITS - 1 - k.leading_zeros());
    let w = pow2_floor(
        n.div_ceil(threads.max(1))
            .clamp(1, max_lanes.clamp(1, MAX_LANES)),
    );
    let mut sizes = vec![w; n / w];
    let mut left = n % w;
    while left > 0 {
        let p = pow2_floor(left);
        sizes.push(p);
        left -= p;
    }
    sizes
}

/// How `run_batch` runs its jobs.
#[derive(Clone, Copy, Debug)]
pub struct BatchOptions {
    /// What each result keeps.
    pub record: Record,
    /// The widest lockstep group (1, 2, 4 or 8; 1 runs every job alone).
    pub max_lanes: usize,
}

impl Default for BatchOptions {
    fn default() -> Self {
        Self {
            record: Record::Metrics,
            max_lanes: DEFAULT_LANES,
        }
    }
}

/// Runs the jobs on the current rayon pool and returns each job's result or error, in input
/// order. Jobs whose configurations differ only in the dampers' parameters (the cases of a
/// sweep, the designs of a generation) or in their irregularity share one assembled model and
/// run in lockstep groups of up to `opts.max_lanes`; a job gives the same bits in a group as
/// alone, and a job that fails leaves its group running. `done` counts finished jobs.
pub fn run_batch(
    jobs: &[Job],
    opts: BatchOptions,
    cancel: Option<&Control>,
    done: Option<&AtomicUsize>,
) -> Vec<Result<RunResult>> {
    run_batch_with(jobs, opts, None, cancel, done)
}

/// `run_batch` with the structure's reduction for jobs that ask for the synthesis (shared by
/// all; its lockstep groups share the wheels' modal shapes as well).
pub fn run_batch_with(
    jobs: &[Job],
    opts: BatchOptions,
    reduced: Option<Reduced>,
    cancel: Option<&Control>,
    done: Option<&AtomicUsize>,
) -> Vec<Result<RunResult>> {
    let out: Mutex<Vec<Option<Result<RunResult>>>> =
        Mutex::new((0..jobs.len()).map(|_| None).collect());
    run_batch_each(jobs, opts, reduced, cancel, &|finished| {
        if let Some(d) = done {
            d.fetch_add(finished.len(), Ordering::Relaxed);
        }
        let mut out = out.lock().unwrap_or_else(|e| e.into_inner());
        for (i, r) in finished {
            out[i] = Some(r);
        }
    });
    out.into_inner()
        .unwrap_or_else(|e| e.into_inner())
        .into_iter()
        .map(|r| r.expect("every job has a result"))
        .collect()
}

/// Receives results as they are known: (job index, result) pairs, a lockstep group's at once.
pub type Sink<'a> = &'a (dyn Fn(Vec<(usize, Result<RunResult>)>) + Sync);

/// `run_batch_with`, each lockstep group's results handed to `sink` as soon as the group
/// finishes (jobs refused before running first, together), so that a caller can keep finished
/// work while the batch goes on. Every job's result reaches the sink exactly once.
pub fn run_batch_each(
    jobs: &[Job],
    opts: BatchOptions,
    reduced: Option<Reduced>,
    cancel: Option<&Control>,
    sink: Sink,
) {
    let record = opts.record;
    let mut refused = Vec::new();
    let mut keys: BTreeMap<String, usize> = BTreeMap::new();
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        if let Err(e) = check::validate(&job.config, &job.profile)
            .and_then(|_| engine(&job.config, reduced).map(|_| ()))
        {
            refused.push((i, Err(e)));
            continue;
        }
        let g = *keys.entry(model_key(&job.config)).or_insert_with(|| {
            groups.push(Vec::new());
            groups.len() - 1
        });
        groups[g].push(i);
    }
    if !refused.is_empty() {
        sink(refused);
    }
    let cancelled = || cancel.is_some_and(Control::cancelled);
    let threads = rayon::current_num_threads();
    // The groups' structures, each assembled once for the groups that share it (a scan's
    // speeds): its first group builds it, the others wait for it and take a copy.
    let mut shared: BTreeMap<String, usize> = BTreeMap::new();
    let structure_of: Vec<usize> = groups
        .iter()
        .map(|m| {
            let key = Structure::key(&jobs[m[0]].config);
            let next = shared.len();
            *shared.entry(key).or_insert(next)
        })
        .collect();
    let structures: Vec<OnceLock<Result<Structure>>> =
        (0..shared.len()).map(|_| OnceLock::new()).collect();
    groups
        .par_iter()
        .zip(&structure_of)
        .for_each(|(members, &s)| {
            let first = &jobs[members[0]];
            let model = if cancelled() {
                Err(VtbError::Cancelled)
            } else {
                let structure = structures[s].get_or_init(|| {
                    Structure::build(&first.config).and_then(|st| match reduced {
                        Some(Reduced::Substructures(sub)) => st.substructured(Arc::clone(sub)),
                        _ => Ok(st),
                    })
                });
                structure.clone().map(|st| {
                    Model::with_structure(first.config.clone(), (*first.profile).clone(), st)
                })
            };
            let mut chunks = Vec::new();
            let mut at = 0;
            for w in lane_widths(members.len(), threads, opts.max_lanes) {
                chunks.push(&members[at..at + w]);
                at += w;
            }
            chunks.into_par_iter().for_each(|chunk| {
                let res = match &model {
                    Err(e) => vec![Err(e.clone()); chunk.len()],
                    Ok(_) if cancelled() => vec![Err(VtbError::Cancelled); chunk.len()],
                    Ok(m) => run_lanes(m, jobs, chunk, record, reduced, cancel),
                };
                sink(chunk.iter().copied().zip(res).collect());
            });
        });
}

/// One lockstep group of `chunk.len()` ∈ {1, 2, 4, 8} jobs on a shared model (on its
/// reduction when the jobs ask for the synthesis).
fn run_lanes(
    model: &Model,
    jobs: &[Job],
    chunk: &[usize],
    record: Record,
    reduced: Option<Reduced>,
    cancel: Option<&Control>,
) -> Vec<Result<RunResult>> {
    let lanes: Vec<LaneSpec> = chunk
        .iter()
        .map(|&i| LaneSpec::of(&jobs[i].config, &jobs[i].profile))
        .collect();
    fn go<const W: usize>(
        model: &Model,
        lanes: &[LaneSpec],
        record: Record,
        reduced: Option<Reduced>,
        cancel: Option<&Control>,
    ) -> Vec<Result<RunResult>> {
        let out = match reduced {
            Some(Reduced::Modes(red)) => {
                synthesis::run_lanes::<W>(model, lanes, red, record, cancel)
            }
            _ => Simulation::<W>::lanes(model, lanes, record).and_then(|s| s.run_lanes(cancel)),
        };
        out.unwrap_or_else(|e| vec![Err(e); W])
    }
    match lanes.len() {
        1 => go::<1>(model, &lanes, record, reduced, cancel),
        2 => go::<2>(model, &lanes, record, reduced, cancel),
        4 => go::<4>(model, &lanes, record, reduced, cancel),
        8 => go::<8>(model, &lanes, record, reduced, cancel),
        w => unreachable!("lane width {w}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_widths_keep_every_thread_busy() {
        assert_eq!(lane_widths(16, 2, 4), vec![4, 4, 4, 4]);
        assert_eq!(lane_widths(8, 2, 8), vec![4, 4]);
        assert_eq!(lane_widths(7, 1, 8), vec![4, 2, 1]);
        assert_eq!(lane_widths(3, 2, 4), vec![2, 1]);
        assert_eq!(lane_widths(1, 8, 4), vec![1]);
        assert_eq!(lane_widths(21, 1, 8), vec![8, 8, 4, 1]);
    }
}
